/*
 * kd_split_median.c — Kaplan's BSP: every node is cut at the spatial median
 * of its box, the axes taken in turn x, y, z by depth; a node becomes a leaf
 * at the depth limit or with at most max_leaf_prims primitives (the paper:
 * 18 and 2). And the octree of centre subdivision (Glassner 1984, as Havran's
 * 1999 octree statistics built it), which is the same tree decided only every
 * third level: an octree node that is not a leaf is cut in x, both halves in
 * y and the four quarters in z, so its eight octants are all made (empty ones
 * as empty leaves), and each octant is an octree node one level down.
 *
 * Primitive lists live in one growable scratch stack: a node's list is at
 * [base, base + n), its children's lists are written at the first free index
 * above it, and the left subtree works above both, so the right list
 * survives until its turn. Everything is addressed by index, so growing the stack is safe.
 */
#include <stdlib.h>

#include "accel/kd_tree.h"
#include "util/grow.h"

typedef struct median_build {
    kd_tree *t;
    bsp_box *pbox; /* padded bounds per primitive */
    uint32_t *scratch;
    size_t cap;
    int group; /* levels per decision: 1 Kaplan, 3 the octree */
    bsp_error *err;
} median_build;

static int reserve(median_build *b, size_t need)
{
    return GROW_ARRAY(b->scratch, b->cap, need);
}

static bsp_status oom(median_build *b)
{
    return kd_build_failed(b->t, b->err);
}

/* The node's list is scratch[base, base + n); scratch[top, ...) is free. */
static bsp_status build_node(median_build *b, uint32_t node, bsp_box box, size_t base, size_t n,
                             size_t top, int depth)
{
    kd_tree *t = b->t;
    unsigned axis = (unsigned)(depth % 3);
    double lo = box.lo.v[axis], hi = box.hi.v[axis];
    float split = (float)(0.5 * (lo + hi));
    double s = (double)split;
    /* a leaf by the limits (decided at a node of the group's first level), or
     * when the box is too thin for a float plane */
    int decides = depth % b->group == 0;
    if ((decides && (n <= (size_t)t->max_leaf_prims || depth >= t->max_depth)) ||
        !(s > lo && s < hi))
        return kd_make_leaf(t, node, b->scratch + base, n) ? BSP_OK : oom(b);

    if (!reserve(b, top + 2 * n))
        return oom(b);
    size_t left = top, nl = 0;
    for (size_t k = 0; k < n; k++) {
        uint32_t p = b->scratch[base + k];
        if (b->pbox[p].lo.v[axis] < s)
            b->scratch[left + nl++] = p;
    }
    size_t right = left + nl, nr = 0;
    for (size_t k = 0; k < n; k++) {
        uint32_t p = b->scratch[base + k];
        if (b->pbox[p].hi.v[axis] > s)
            b->scratch[right + nr++] = p;
    }
    uint32_t child = kd_alloc_pair(t);
    if (child == UINT32_MAX)
        return oom(b);
    kd_make_interior(t, node, axis, split, child);
    bsp_box lb = box, rb = box;
    lb.hi.v[axis] = rb.lo.v[axis] = s;
    /* the left subtree works above both lists; then the right one may reuse it */
    bsp_status st = build_node(b, child, lb, left, nl, right + nr, depth + 1);
    if (st == BSP_OK)
        st = build_node(b, child + 1, rb, right, nr, right + nr, depth + 1);
    return st;
}

static bsp_status build_median(kd_tree *t, const bsp_scene *scene, int group, bsp_error *err)
{
    size_t np = bsp_scene_prim_count(scene);
    median_build b = {t, NULL, NULL, 0, group, err};
    b.pbox = malloc((np ? np : 1) * sizeof *b.pbox);
    b.cap = 4 * np + 64;
    b.scratch = malloc(b.cap * sizeof *b.scratch);
    bsp_status st = BSP_OK;
    if (!b.pbox || !b.scratch) {
        st = oom(&b);
    } else {
        size_t n = 0;
        for (uint32_t p = 0; p < np; p++) {
            if (bsp_scene_prim_kind(scene, p) == BSP_PRIM_DROPPED)
                continue;
            b.pbox[p] = kd_prim_box(t, scene, p);
            b.scratch[n++] = p;
        }
        if (n > 0)
            st = build_node(&b, 0, t->box, 0, n, n, 0);
    }
    free(b.pbox);
    free(b.scratch);
    return st;
}

bsp_status kd_build_median(kd_tree *t, const bsp_scene *scene, bsp_error *err)
{
    return build_median(t, scene, 1, err);
}

bsp_status kd_build_octree(kd_tree *t, const bsp_scene *scene, bsp_error *err)
{
    t->octree = 1;
    return build_median(t, scene, 3, err);
}

int kd_octree_default_depth(size_t n)
{
    /* the least d with 8^d >= 8 N: about eight finest cells per primitive. On
     * the SPD scenes (N 4,096 to 9,345) that is 5 or 6, within 20 % of each
     * scene's fastest depth but tree's (docs/octree.md) */
    int d = 1;
    for (double cells = 8.0; cells < 8.0 * (double)n && d < BSP_OCTREE_MAX_DEPTH; cells *= 8.0)
        d++;
    return d;
}
