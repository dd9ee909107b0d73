/*
 * kd_local.c — the traversal's copy of the primitives in leaf order
 * (contract and reasons in kd_local.h).
 */
#include <stdlib.h>
#include <string.h>

#include "accel/kd_local.h"
#include "util/bigmem.h"

void kd_local_fill(kd_local *L, const bsp_scene *s, uint32_t p)
{
    const prim_record *r = &s->prims[p];
    memset(L, 0, sizeof *L);
    L->prim = p;
    L->shape = r->shape;
    switch ((shape_kind)r->shape) {
    case SHAPE_TRIANGLE:
        L->u.triangle = triangle_edges_of(&s->triangles[r->slot].verts);
        L->edge_exp = s->triangles[r->slot].edge_exp;
        break;
    case SHAPE_SPHERE:
        L->u.sphere = s->spheres[r->slot];
        break;
    case SHAPE_POLYGON:
        L->u.polygon = s->polygons[r->slot];
        break;
    case SHAPE_CONE:
        L->u.cone = &s->cones[r->slot];
        break;
    default: /* dropped primitives are in no leaf */
        break;
    }
}

int kd_local_build(kd_tree *t, const bsp_scene *scene)
{
    free(t->lref);
    free(t->loc);
    free(t->local_of);
    t->lref = NULL;
    t->loc = NULL;
    t->local_of = NULL;
    t->nloc = 0;
    t->nlocal_of = 0;
    size_t np = scene->nprims;
    /* number[p]: p's local number + 1, 0 while unlisted (kept: local_of). Every listed
     * primitive is live, so at most np records; the ones filled are written
     * in order, and the pages of the rest are never touched. */
    uint32_t *number = calloc(np ? np : 1, sizeof *number);
    uint32_t *lref = bigmem_malloc((t->nprims ? t->nprims : 1) * sizeof *lref);
    kd_local *loc = bigmem_malloc((np ? np : 1) * sizeof *loc);
    if (!number || !lref || !loc) {
        free(number);
        free(lref);
        free(loc);
        return 0;
    }
    /* leaves in node order: the depth-first order of the tree */
    uint32_t nloc = 0;
    for (uint32_t i = 0; i < t->nnodes; i++) {
        const kd_node *n = &t->nodes[i];
        if (!kd_is_leaf(n))
            continue;
        for (uint32_t j = n->u.first, end = j + kd_count(n); j < end; j++) {
            uint32_t p = t->prims[j];
            if (!number[p]) {
                kd_local_fill(&loc[nloc], scene, p);
                number[p] = ++nloc;
            }
            lref[j] = number[p] - 1;
        }
    }
    t->lref = lref;
    t->loc = loc;
    t->nloc = nloc;
    t->local_of = number;
    t->nlocal_of = np;
    return 1;
}

/* Whether record L holds primitive L->prim's data bit for bit (members
 * compared, not padding). */
static int local_matches(const kd_local *L, const bsp_scene *s)
{
    const prim_record *r = &s->prims[L->prim];
    if (L->shape != r->shape)
        return 0;
    switch ((shape_kind)r->shape) {
    case SHAPE_TRIANGLE: { /* nine doubles, no padding */
        const triangle_shape *tr = &s->triangles[r->slot];
        const triangle_edges e = triangle_edges_of(&tr->verts);
        return memcmp(&L->u.triangle, &e, sizeof e) == 0 && L->edge_exp == tr->edge_exp;
    }
    case SHAPE_SPHERE: {
        const sphere_shape *a = &L->u.sphere, *b = &s->spheres[r->slot];
        return memcmp(&a->center, &b->center, sizeof a->center) == 0 &&
               memcmp(&a->radius, &b->radius, sizeof a->radius) == 0 &&
               memcmp(&a->radius2, &b->radius2, sizeof a->radius2) == 0 &&
               a->inside_only == b->inside_only;
    }
    case SHAPE_POLYGON: {
        const polygon_shape *a = &L->u.polygon, *b = &s->polygons[r->slot];
        return memcmp(&a->normal, &b->normal, sizeof a->normal) == 0 &&
               memcmp(&a->d, &b->d, sizeof a->d) == 0 && a->first == b->first &&
               a->count == b->count && a->normals == b->normals && a->axis_u == b->axis_u &&
               a->axis_v == b->axis_v && a->slab_first == b->slab_first &&
               a->nslabs == b->nslabs && memcmp(&a->wt_base, &b->wt_base, sizeof a->wt_base) == 0;
    }
    case SHAPE_CONE:
        return L->u.cone == &s->cones[r->slot];
    default: /* a dropped primitive has no record */
        return 0;
    }
}

bsp_status kd_local_check(const kd_tree *t, const bsp_scene *scene, bsp_error *err)
{
    if (!t->lref || !t->loc)
        return error_set(err, BSP_ERR_INVALID, NULL, 0, "kd-tree: no local copy of the primitives");
    if (!t->local_of || t->nlocal_of != scene->nprims)
        return error_set(err, BSP_ERR_INVALID, NULL, 0,
                         "kd-tree: no local number for each of the %zu primitives", scene->nprims);
    if (t->nloc > scene->nprims)
        return error_set(err, BSP_ERR_INVALID, NULL, 0, "kd-tree: %u local records for %zu primitives",
                         t->nloc, scene->nprims);
    /* the next record a walk of the leaves in node order must meet first */
    uint32_t next = 0;
    for (uint32_t i = 0; i < t->nnodes; i++) {
        const kd_node *n = &t->nodes[i];
        if (!kd_is_leaf(n))
            continue;
        for (uint32_t j = n->u.first, end = j + kd_count(n); j < end; j++) {
            uint32_t l = t->lref[j];
            if (l >= t->nloc)
                return error_set(err, BSP_ERR_INVALID, NULL, 0,
                                 "kd-tree: leaf %u lists local record %u of %u", i, l, t->nloc);
            if (l > next)
                return error_set(err, BSP_ERR_INVALID, NULL, 0,
                                 "kd-tree: leaf %u lists local record %u before record %u", i, l,
                                 next);
            if (t->loc[l].prim != t->prims[j])
                return error_set(err, BSP_ERR_INVALID, NULL, 0,
                                 "kd-tree: leaf %u: local record %u is primitive %u, not %u", i, l,
                                 t->loc[l].prim, t->prims[j]);
            if (l == next)
                next++;
        }
    }
    if (next != t->nloc)
        return error_set(err, BSP_ERR_INVALID, NULL, 0,
                         "kd-tree: %u local records, %u of them listed", t->nloc, next);
    /* one record per primitive: two would give it two mailbox stamps, and
     * a ray could test it twice */
    uint8_t *seen = calloc(scene->nprims ? scene->nprims : 1, 1);
    if (!seen)
        return error_set(err, BSP_ERR_NOMEM, NULL, 0, "out of memory");
    bsp_status st = BSP_OK;
    for (uint32_t l = 0; l < t->nloc && st == BSP_OK; l++) {
        uint32_t p = t->loc[l].prim;
        if (p >= scene->nprims)
            st = error_set(err, BSP_ERR_INVALID, NULL, 0,
                           "kd-tree: local record %u names primitive %u of %zu", l, p,
                           scene->nprims);
        else if (seen[p])
            st = error_set(err, BSP_ERR_INVALID, NULL, 0,
                           "kd-tree: primitive %u has a second local record, %u", p, l);
        else if (!local_matches(&t->loc[l], scene))
            st = error_set(err, BSP_ERR_INVALID, NULL, 0,
                           "kd-tree: local record %u differs from primitive %u's data", l, p);
        else if (t->local_of[p] != l + 1)
            st = error_set(err, BSP_ERR_INVALID, NULL, 0,
                           "kd-tree: primitive %u's local number is not its record's, %u", p, l);
        else
            seen[p] = 1;
    }
    /* and a primitive no leaf lists has no local number */
    for (size_t p = 0; p < scene->nprims && st == BSP_OK; p++)
        if (!seen[p] && t->local_of[p] != 0)
            st = error_set(err, BSP_ERR_INVALID, NULL, 0,
                           "kd-tree: primitive %zu is in no leaf but has local number %u", p,
                           t->local_of[p] - 1);
    free(seen);
    return st;
}
