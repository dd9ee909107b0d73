/*
 * bvh.h — a bounding volume hierarchy (binary, object partitioning, binned
 * SAH), the structure most ray tracers use today, built here to compare the
 * kd-trees with on the same kernels, rays and counters (`--accel bvh`).
 *
 * Layout: a node is its box, in floats rounded outward, an index and a
 * count (bvh_node). The root is node 0 and kept apart; every other node lies
 * beside its sibling in a 64-byte pair (bvh_pair: left then right, node ids
 * 2 + 2p and 3 + 2p for pair p, so id 1 is unused), its boxes stored axis by
 * axis with the two siblings' bounds side by side, so that one line holds
 * both boxes a traversal tests together and two-wide vector code loads each
 * bound of both with one convert. An interior node's `index` is its pair's
 * first id. Leaves are runs of the primitives' records (kd_local.h: the
 * kernels' data, copied bit for bit) in the order the leaves list them, so a
 * leaf is `count` records from `index`. Every live primitive is in exactly
 * one leaf: no mailbox is needed, and none is used.
 *
 * Wide (`--accel bvh4`, width 4; `--accel bvh8`, width 8): the same binary
 * build, then each node takes up to W descendants as its children (the
 * interior child of the largest surface area opened first, Embree's
 * collapse) in a wide node of 32 W bytes (bvh_wide_*: the W boxes axis by
 * axis, lo on axis k at floats kW..kW+W-1, hi at (3+k)W.., then W indices
 * and W metas), whose boxes a ray tests four at a time in SSE's float
 * lanes. The root is kept apart as before; child c of wide node q is node
 * id 1 + Wq + c, an interior node's `index` is its wide node, and the
 * lanes a node does not use hold index BVH_NONE, meta 0 and the box
 * +inf..-inf on every axis (its entry is +inf and its exit -inf for every
 * ray: no 0 x inf or inf - inf arises with a finite origin).
 *
 * Exactness invariant: a node's box contains the bounds of every primitive
 * below it grown by `pad` (KD_PAD_REL times the scene scale: four times the
 * distance from its shape within which the kernels accept a hit), so every
 * accepted hit's point lies at least 3/4 pad inside the box of every node
 * above its primitive. The traversal's slab test (bvh_traverse.c) errs by
 * about 1e-16 of |o| + |box| in the precision domain (scene_internal.h), far
 * below that margin; so it never rejects a node whose primitives hold a hit
 * in [tmin, best t], ties included, and testing every such node's leaves
 * with tmax = best t and the lower index winning at equal t gives the naive
 * method's answer. Rays outside the domain take the naive loop.
 *
 * The wide trees' tests run in float (bvh_wide_traverse.c), whose rounding
 * is far coarser, so their pad is larger, BVH_WIDE_PAD_REL M (M the largest
 * |coordinate| of the scene's bounds; the kd-trees' pad if that is more),
 * and its float tests serve the origins with every |o_k| <= 2^19 pad - M
 * (`float_origin`; other rays of the domain take the same walk with double
 * tests): there a computed slab t is the exact t of a face moved by at most
 * 2^-22 (|face| + |o_k|) (1 + 2^-20) <= 2^-22 2^19 pad (1 + 2^-20), about
 * pad / 8, far inside the 3/4 pad by which hits clear the box.
 */
#ifndef BSPRAY_ACCEL_BVH_H
#define BSPRAY_ACCEL_BVH_H

#include <float.h>
#include <stdint.h>
#include <string.h>

#include "accel/kd_local.h"

/* The deepest a node may lie (the traversal's stack holds one entry per
 * level); a node at this depth becomes a leaf whatever its size. */
#define BVH_MAX_DEPTH 60
/* Leaves hold at most this many primitives by default (max_leaf_prims),
 * unless their centroids cannot be told apart or the depth limit is met. */
#define BVH_LEAF_MAX 8
/* The BVH's C_trav in kd-tree traversal steps (sah_costs.traversal, default
 * 1): a step tests a pair of boxes. Against 1, primary rays +1 to +5 %
 * (balls, sample, teapot:12, the dragon), the other SPD scenes within
 * +-0.6 % (docs/bvh.md). */
#define BVH_TRAVERSAL_COST 2.0
/* Centroid bins per axis of the binned SAH. */
#define BVH_BINS 16
/* The wide trees' bounds padding: 2^-14 M, M the largest |coordinate| of
 * the scene's bounds (at least the kd-trees' pad), and the largest |o_k|
 * their float slab tests take: 2^19 pads less M (see above). */
#define BVH_WIDE_PAD_REL (1.0 / 16384.0)
#define BVH_WIDE_FLOAT_ORIGIN_PADS 524288.0
/* A wide node's unused lane. */
#define BVH_NONE UINT32_MAX
/* The widest node (bvh8), and a wide node's bytes. */
#define BVH_WIDEST 8u
#define BVH_WIDE_BYTES(w) (32u * (w))

typedef struct bvh_node {
    float lo[3], hi[3]; /* the box, rounded outward from the padded doubles */
    uint32_t index;     /* interior: its children's pair (first id); leaf: the first record */
    uint32_t meta;      /* count << 2 | axis; count 0: interior, split on axis */
} bvh_node;

/* Two siblings: child c's box is lo[k][c]..hi[k][c] on axis k. */
typedef struct bvh_pair {
    float lo[3][2], hi[3][2];
    uint32_t index[2], meta[2]; /* as bvh_node's */
} bvh_pair;

_Static_assert(sizeof(bvh_pair) == 64, "a BVH pair is one 64-byte line");

#define BVH_COUNT(n) ((n)->meta >> 2)
#define BVH_AXIS(n) ((n)->meta & 3u)
/* The most primitives one leaf may count (meta's 30 bits). */
#define BVH_MAX_PRIMS ((uint32_t)1 << 30)

typedef struct bvh {
    bvh_node root;
    unsigned width;  /* 2: the nodes lie in pairs; 4 or 8: in wide nodes */
    bvh_pair *pairs; /* width 2: 64-byte aligned, inside nodes_block */
    unsigned char *wide; /* width 4 or 8: likewise, BVH_WIDE_BYTES(width) each */
    void *nodes_block;
    /* node ids in use + 1: 0, no live primitive; else 2 + 2 x pairs (id 1
     * unused), or 1 + W x wide nodes (their unused lanes included) */
    uint32_t nnodes;
    kd_local *rec;  /* nrec records in leaf order */
    uint32_t nrec;
    double pad;     /* the bounds padding (KD_PAD_REL or BVH_WIDE_PAD_REL x scene scale) */
    double float_origin; /* width 4, 8: the float tests take |o_k| up to this (< 0: none) */
    bsp_sah_costs costs; /* the build's cost model: C_trav (traversal) and T_i by kind */
} bvh;

/* Wide node Q of T (width 4 or 8), and its lane C's parts (memcpy: the
 * bytes hold floats and integers side by side). */
static inline unsigned char *bvh_wide_node(const bvh *t, uint32_t q)
{
    return t->wide + (size_t)q * BVH_WIDE_BYTES(t->width);
}
static inline float bvh_wide_lo(const unsigned char *n, unsigned w, unsigned k, unsigned c)
{
    float f;
    memcpy(&f, n + 4 * (k * w + c), sizeof f);
    return f;
}
static inline float bvh_wide_hi(const unsigned char *n, unsigned w, unsigned k, unsigned c)
{
    return bvh_wide_lo(n, w, 3 + k, c);
}
static inline uint32_t bvh_wide_index(const unsigned char *n, unsigned w, unsigned c)
{
    uint32_t u;
    memcpy(&u, n + 4 * (6 * w + c), sizeof u);
    return u;
}
static inline uint32_t bvh_wide_meta(const unsigned char *n, unsigned w, unsigned c)
{
    return bvh_wide_index(n, w, w + c); /* the metas follow the W indices */
}
/* Lane C of wide node N (width W) as a node, and set from X. */
static inline bvh_node bvh_wide_get(const unsigned char *n, unsigned w, unsigned c)
{
    bvh_node x;
    for (unsigned k = 0; k < 3; k++) {
        x.lo[k] = bvh_wide_lo(n, w, k, c);
        x.hi[k] = bvh_wide_hi(n, w, k, c);
    }
    x.index = bvh_wide_index(n, w, c);
    x.meta = bvh_wide_meta(n, w, c);
    return x;
}
static inline void bvh_wide_set(unsigned char *n, unsigned w, unsigned c, const bvh_node *x)
{
    for (unsigned k = 0; k < 3; k++) {
        memcpy(n + 4 * (k * w + c), &x->lo[k], sizeof(float));
        memcpy(n + 4 * ((3 + k) * w + c), &x->hi[k], sizeof(float));
    }
    memcpy(n + 4 * (6 * w + c), &x->index, sizeof(uint32_t));
    memcpy(n + 4 * (7 * w + c), &x->meta, sizeof(uint32_t));
}

/* Node ID of T (0 the root; width 2: 2 + 2p + c child c of pair p; width
 * 4 or 8: 1 + Wq + c child c of wide node q). */
static inline bvh_node bvh_get(const bvh *t, uint32_t id)
{
    if (id == 0)
        return t->root;
    if (t->width != 2)
        return bvh_wide_get(bvh_wide_node(t, (id - 1) / t->width), t->width, (id - 1) % t->width);
    bvh_node n;
    const bvh_pair *p = &t->pairs[(id - 2) >> 1];
    unsigned c = id & 1u;
    for (unsigned k = 0; k < 3; k++) {
        n.lo[k] = p->lo[k][c];
        n.hi[k] = p->hi[k][c];
    }
    n.index = p->index[c];
    n.meta = p->meta[c];
    return n;
}

/* The float after / before F (F finite; at +-FLT_MAX, +-inf). Inline:
 * libm's nextafterf is a call, and the wide walks round after every
 * leaf that hits. */
static inline float bvh_float_step(float f, int up)
{
    if (f == 0.0f)
        return up ? FLT_TRUE_MIN : -FLT_TRUE_MIN;
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    u += (f > 0.0f) == (up != 0) ? 1u : (uint32_t)-1; /* away from / towards 0 */
    memcpy(&f, &u, sizeof f);
    return f;
}

/* X rounded to a float towards -inf / +inf: a node's float box contains
 * its double one; the walk's float interval contains the double one. */
static inline float bvh_float_down(double x)
{
    float f = (float)x;
    return (double)f > x ? bvh_float_step(f, 0) : f;
}
static inline float bvh_float_up(double x)
{
    float f = (float)x;
    return (double)f < x ? bvh_float_step(f, 1) : f;
}

/* The ids of interior node N's children in IDS (left to right), and how
 * many it has: 2, or (width 4, 8) the lanes of its wide node in use. */
static inline unsigned bvh_children(const bvh *t, const bvh_node *n, uint32_t ids[BVH_WIDEST])
{
    if (t->width == 2) {
        ids[0] = n->index;
        ids[1] = n->index + 1;
        return 2;
    }
    const unsigned char *w = bvh_wide_node(t, n->index);
    unsigned c = 0;
    while (c < t->width && bvh_wide_index(w, t->width, c) != BVH_NONE) {
        ids[c] = 1 + t->width * n->index + c;
        c++;
    }
    return c;
}

/* Builds A's BVH over A->scene (options A->opts): sets A's ops and impl.
 * BSP_ERR_NOMEM or BSP_ERR_LIMIT (more than bsp_build_options.max_tree_bytes
 * or BVH_MAX_PRIMS) with a message in ERR. */
HIDDEN bsp_status bvh_build(bsp_accel *a, bsp_error *err);

/* Havran's figures of the BVH (bsp_tree_stats; empty_leaves 0, references the
 * live primitives, expected_cost and model_cost by surface area over the
 * root's box, interior nodes at C_trav). */
HIDDEN void bvh_stats(const bvh *b, const bsp_scene *scene, bsp_tree_stats *st);

/* The invariants: child indices in range and depth within BVH_MAX_DEPTH,
 * every live primitive in exactly one leaf with its record the scene's data
 * bit for bit, and its padded bounds inside the box of its leaf and of
 * every node above it. BSP_OK or BSP_ERR_INVALID with the first violation. */
HIDDEN bsp_status bvh_check(const bvh *b, const bsp_scene *scene, bsp_error *err);

/* bsp_accel_visit_cells for a BVH: each node's box, depth first; an interior
 * node's axis is the one its primitives were partitioned on and its "split"
 * the low face of its right child's box on that axis (the boxes may overlap). */
HIDDEN bsp_status bvh_visit(const bvh *b, int max_depth,
                            int (*visit)(const bsp_cell_info *cell, void *ctx), void *ctx);

/* The queries (bvh_traverse.c; width 4 and 8: bvh_wide_traverse.c). */
HIDDEN int bvh_intersect(const bsp_accel *a, bsp_query *q, const bsp_ray *ray, uint32_t from,
                         bsp_hit *hit);
HIDDEN int bvh_occluded(const bsp_accel *a, bsp_query *q, const bsp_ray *ray, uint32_t from);
HIDDEN int bvh_wide_intersect(const bsp_accel *a, bsp_query *q, const bsp_ray *ray,
                              uint32_t from, bsp_hit *hit);
HIDDEN int bvh_wide_occluded(const bsp_accel *a, bsp_query *q, const bsp_ray *ray, uint32_t from);

HIDDEN void bvh_destroy(void *impl);

#endif /* BSPRAY_ACCEL_BVH_H */
