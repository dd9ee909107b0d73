/*
 * test_kd_local.c — the traversal's leaf-ordered copy of the primitives
 * (src/accel/kd_local.h): numbered by first appearance in a walk of the
 * leaves in node order, each record the scene's data bit for bit, the leaf
 * lists the same primitives in that numbering; and the checker
 * (bsp_accel_check) refuses a copy that differs in any of those ways.
 */
#include <stdlib.h>
#include <string.h>

#include "accel/kd_local.h"
#include "harness.h"
#include "kd_test_util.h"

/* The scene's data of primitive P as the record must hold it. */
static int same_as_scene(const bsp_scene *s, const kd_local *L, uint32_t p)
{
    const prim_record *r = &s->prims[p];
    if (L->prim != p || L->shape != r->shape)
        return 0;
    switch ((shape_kind)r->shape) {
    case SHAPE_TRIANGLE: {
        const triangle_shape *tr = &s->triangles[r->slot];
        const bsp_vec3 e1 = v3_sub(tr->v1, tr->v0), e2 = v3_sub(tr->v2, tr->v0);
        return memcmp(&L->u.triangle.v0, &tr->v0, sizeof tr->v0) == 0 &&
               memcmp(&L->u.triangle.e1, &e1, sizeof e1) == 0 &&
               memcmp(&L->u.triangle.e2, &e2, sizeof e2) == 0 && L->edge_exp == tr->edge_exp;
    }
    case SHAPE_SPHERE: {
        const sphere_shape *sp = &s->spheres[r->slot];
        return memcmp(&L->u.sphere.center, &sp->center, sizeof sp->center) == 0 &&
               L->u.sphere.radius == sp->radius && L->u.sphere.radius2 == sp->radius2 &&
               L->u.sphere.inside_only == sp->inside_only;
    }
    case SHAPE_POLYGON: {
        const polygon_shape *pg = &s->polygons[r->slot];
        return L->u.polygon.first == pg->first && L->u.polygon.count == pg->count &&
               L->u.polygon.d == pg->d && L->u.polygon.nslabs == pg->nslabs &&
               L->u.polygon.axis_u == pg->axis_u && L->u.polygon.axis_v == pg->axis_v &&
               L->u.polygon.wt_base == pg->wt_base;
    }
    case SHAPE_CONE:
        return L->u.cone == &s->cones[r->slot];
    default:
        return 0;
    }
}

/* On scenes of every shape (mount: triangles and spheres; gears: quads and
 * 144-gons with slabs; rings: spheres and cones; sample: a bit of each),
 * with both rules: the numbering is recomputed here from the leaf lists
 * alone and must be the copy's, record for record. */
static void numbering_check(const bsp_scene *s, const bsp_accel *a, const char *spec, size_t scene,
                            size_t kind, void *ctx)
{
    (void)kind, (void)ctx;
    const kd_tree *t = a->impl;
    uint32_t *number = malloc(s->nprims * sizeof *number);
    REQUIRE(number);
    for (size_t p = 0; p < s->nprims; p++)
        number[p] = UINT32_MAX;
    uint32_t next = 0;
    size_t bad = 0, shapes[SHAPE_CONE + 1] = {0};
    for (uint32_t i = 0; i < t->nnodes; i++) {
        const kd_node *n = &t->nodes[i];
        if (!kd_is_leaf(n))
            continue;
        for (uint32_t j = n->u.first; j < n->u.first + kd_count(n); j++) {
            uint32_t p = t->prims[j];
            if (number[p] == UINT32_MAX) {
                number[p] = next++;
                if (s->prims[p].shape <= SHAPE_CONE)
                    shapes[s->prims[p].shape]++;
            }
            bad += t->lref[j] != number[p];
        }
    }
    CHECK_MSG(bad == 0, "%s: %zu leaf entries in another numbering", spec, bad);
    CHECK_MSG(t->nloc == next, "%s: %u records for %u listed primitives", spec,
              t->nloc, next);
    for (size_t p = 0; p < s->nprims; p++)
        if (number[p] != UINT32_MAX && number[p] < t->nloc)
            bad += !same_as_scene(s, &t->loc[number[p]], (uint32_t)p);
    CHECK_MSG(bad == 0, "%s: %zu records differ from the scene", spec, bad);
    /* the inverse numbering of bsp_intersect_from: number + 1, 0 unlisted */
    REQUIRE(t->local_of && t->nlocal_of == s->nprims);
    for (size_t p = 0; p < s->nprims; p++)
        bad += t->local_of[p] != number[p] + 1; /* UINT32_MAX + 1 == 0 */
    CHECK_MSG(bad == 0, "%s: %zu primitives with another local number", spec, bad);
    CHECK_MSG(kd_test_accepted(a), "%s: the checker refuses the tree", spec);
    bsp_tree_stats st;
    bsp_accel_tree_stats(a, &st);
    CHECK(st.trace_bytes == (uint64_t)t->nloc * sizeof(kd_local) +
                                (uint64_t)t->nprims * sizeof(uint32_t) +
                                (uint64_t)s->nprims * sizeof(uint32_t) +
                                ((uint64_t)t->nnodes + 1) * sizeof(kd_node));
    /* the scenes give the copy the shapes it must cover */
    if (scene == 0)
        CHECK(shapes[SHAPE_TRIANGLE] > 0 && shapes[SHAPE_SPHERE] > 0);
    if (scene == 1)
        CHECK(shapes[SHAPE_POLYGON] > 0);
    if (scene == 2)
        CHECK(shapes[SHAPE_CONE] > 0 && shapes[SHAPE_SPHERE] > 0);
    free(number);
}

TEST(kd_local_copies_every_listed_primitive_in_leaf_order)
{
    const char *specs[] = {"spd:mount:2", "spd:gears:2", "spd:rings:2", "spd:sample"};
    kd_test_each_tree(specs, sizeof specs / sizeof *specs, numbering_check, NULL);
}

/* A copy that no longer matches — one bit of a triangle, a sphere's radius,
 * a leaf entry naming another record, two records swapped with their
 * entries (the same primitives, out of first-appearance order), a second
 * record of one primitive, one record fewer than the leaves name — is refused, and accepted again once restored. */
TEST(kd_local_check_refuses_a_stale_copy)
{
    bsp_scene *s = NULL;
    bsp_error err;
    REQUIRE(bsp_scene_load("spd:mount:2", &s, &err) == BSP_OK);
    bsp_accel *a = kd_test_build(s, BSP_ACCEL_SAH);
    kd_tree *t = a->impl;
    REQUIRE(kd_test_accepted(a));
    REQUIRE(t->nloc >= 2 && t->nprims >= 2);

    uint32_t tri = UINT32_MAX, sph = UINT32_MAX;
    for (uint32_t l = 0; l < t->nloc; l++) {
        if (t->loc[l].shape == SHAPE_TRIANGLE && tri == UINT32_MAX)
            tri = l;
        if (t->loc[l].shape == SHAPE_SPHERE && sph == UINT32_MAX)
            sph = l;
    }
    REQUIRE(tri != UINT32_MAX && sph != UINT32_MAX);

    kd_local keep = t->loc[tri];
    uint64_t bits;
    memcpy(&bits, &t->loc[tri].u.triangle.e1.x, sizeof bits);
    bits ^= 1; /* one ulp */
    memcpy(&t->loc[tri].u.triangle.e1.x, &bits, sizeof bits);
    CHECK(!kd_test_accepted(a));
    t->loc[tri] = keep;
    CHECK(kd_test_accepted(a));

    keep = t->loc[sph];
    t->loc[sph].u.sphere.radius *= 1.5;
    CHECK(!kd_test_accepted(a));
    t->loc[sph] = keep;
    CHECK(kd_test_accepted(a));

    /* a primitive's local number off by one, and a local number for a
     * primitive no leaf lists (a new one, past the listed ones) */
    uint32_t lp = t->loc[tri].prim, keep_num = t->local_of[lp];
    t->local_of[lp] = keep_num + 1;
    CHECK(!kd_test_accepted(a));
    t->local_of[lp] = keep_num;
    CHECK(kd_test_accepted(a));
    {
        size_t unlisted = SIZE_MAX;
        for (size_t p = 0; p < s->nprims && unlisted == SIZE_MAX; p++)
            if (t->local_of[p] == 0)
                unlisted = p;
        if (unlisted != SIZE_MAX) {
            t->local_of[unlisted] = 1;
            CHECK(kd_local_check(t, s, &err) != BSP_OK);
            CHECK_STR_CONTAINS(err.message, "in no leaf");
            t->local_of[unlisted] = 0;
            CHECK(kd_test_accepted(a));
        }
    }

    /* an entry naming another record (the last entry's, where it differs) */
    size_t j = 0;
    while (j + 1 < t->nprims && t->lref[j] == t->lref[t->nprims - 1])
        j++;
    uint32_t e = t->lref[j];
    t->lref[j] = t->lref[t->nprims - 1];
    CHECK(!kd_test_accepted(a));
    t->lref[j] = e;
    CHECK(kd_test_accepted(a));

    /* records 0 and 1 swapped, with every entry: each entry still names its
     * primitive's record, but record 1 comes first */
    kd_local r0 = t->loc[0];
    t->loc[0] = t->loc[1];
    t->loc[1] = r0;
    for (size_t k = 0; k < t->nprims; k++)
        if (t->lref[k] < 2)
            t->lref[k] ^= 1;
    CHECK(!kd_test_accepted(a));
    r0 = t->loc[0];
    t->loc[0] = t->loc[1];
    t->loc[1] = r0;
    for (size_t k = 0; k < t->nprims; k++)
        if (t->lref[k] < 2)
            t->lref[k] ^= 1;
    CHECK(kd_test_accepted(a));

    /* record 1 a second record of record 0's primitive, the lists changed to
     * match (the tree's own check would refuse those lists, so the copy's
     * check is asked alone) */
    {
        uint32_t p0 = t->loc[0].prim, p1 = t->loc[1].prim;
        kd_local r1 = t->loc[1];
        t->loc[1] = t->loc[0];
        for (size_t k = 0; k < t->nprims; k++)
            if (t->lref[k] == 1)
                t->prims[k] = p0;
        CHECK(kd_local_check(t, s, &err) != BSP_OK);
        CHECK_STR_CONTAINS(err.message, "second local record");
        t->loc[1] = r1;
        for (size_t k = 0; k < t->nprims; k++)
            if (t->lref[k] == 1)
                t->prims[k] = p1;
        CHECK(kd_local_check(t, s, &err) == BSP_OK);
        CHECK(kd_test_accepted(a));
    }

    /* one record fewer than the leaves name */
    t->nloc--;
    CHECK(!kd_test_accepted(a));
    t->nloc++;
    CHECK(kd_test_accepted(a));

    bsp_accel_destroy(a);
    bsp_scene_destroy(s);
}
