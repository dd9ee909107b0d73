/*
 * kd_tree.h — the compact kd-tree (axis-aligned BSP tree) shared by every
 * construction rule, and the interface between the builders and the rest.
 *
 * Node layout (Havran's cache-sensitive representation, as pbrt and Mitsuba
 * also use it): 8 bytes per node in one array; the two children of an
 * interior node are adjacent (left at `child`, right at `child + 1`), and
 * the array is in depth-first order from the root at index 0 — for SAH
 * trees, the top of the tree and then each subtree built in parallel
 * (kd_sah_tasks.c), each in depth-first order. A leaf's primitives are a
 * run in one shared index array.
 *
 * Conservative assignment invariant (what exactness rests on): a primitive
 * is listed in every leaf whose box overlaps the interior of its bounds
 * padded by `pad` (lo < cell.hi and hi > cell.lo on every axis) — for SAH
 * trees, of the bounds of its part inside the cell (perfect splits: the
 * primitive clipped to the padded cell, then padded; kd_clip.c). A primitive
 * lies at least `pad` inside its padded bounds, so it is listed in every
 * leaf whose closed box it touches — in both children when it lies in a
 * splitting plane — and the padding (KD_PAD_REL times the scene scale) is
 * four times the distance from its primitive within which every accepted hit
 * lies (the kernels' hit check, geom/isect.h), and far larger than the
 * rounding error of the points the traversal computes. So a
 * traversal that tests the primitives of every leaf the ray's segment passes
 * through, and stops only once the closest hit lies inside the current cell,
 * returns what the naive method returns, ties included.
 */
#ifndef BSPRAY_ACCEL_KD_TREE_H
#define BSPRAY_ACCEL_KD_TREE_H

#include <stdint.h>

#include "accel/accel_internal.h"

/* Bounds padding relative to the scene scale (see the invariant above):
 * 1e-7, four times the kernels' hit check distance (geom/isect.h), which
 * keeps every hit within a quarter of the padding of its shape; the
 * traversal's points err by about 1e-9 scales in the precision domain
 * (scene_internal.h), far less than the rest. (4 x 2.5e-8 rounds to the
 * double nearest 1e-7: scaling by 4 is exact.) */
#define KD_PAD_REL (4.0 * ISECT_HIT_TOL_REL)

#define KD_LEAF_TAG 3u

typedef struct kd_node {
    uint32_t bits; /* low 2 bits: axis 0..2, or KD_LEAF_TAG; bit 2: 0; upper
                      29 bits (bits >> KD_INDEX_SHIFT): interior: index of
                      the left child (right = left + 1); leaf: primitive
                      count. So bits & ~7 of an interior node is the byte
                      offset of its left child in the node array. (The
                      traversal reads kd_walk.h's copy, whose bits 2 and 3
                      flag empty children: there the offset is bits & ~15,
                      one AND away from the load.) */
    union {
        float split;    /* interior: the plane's coordinate on `axis` */
        uint32_t first; /* leaf: first entry in kd_tree.prims */
    } u;
} kd_node;

_Static_assert(sizeof(kd_node) == 8, "kd-tree nodes are 8 bytes");

#define KD_INDEX_SHIFT 3
#define KD_MAX_NODES ((uint32_t)1 << (32 - KD_INDEX_SHIFT))
/* The most primitives one leaf can list. */
#define KD_MAX_LEAF_COUNT ((size_t)1 << (32 - KD_INDEX_SHIFT))

/* The bits of a node: index or count I (below 2^29) over the low tag LOW
 * (an axis or KD_LEAF_TAG). */
static inline uint32_t kd_pack(uint32_t i, unsigned low)
{
    return (i << KD_INDEX_SHIFT) | low;
}

static inline int kd_is_leaf(const kd_node *n)
{
    return (n->bits & 3u) == KD_LEAF_TAG;
}
static inline unsigned kd_axis(const kd_node *n)
{
    return n->bits & 3u;
}
static inline uint32_t kd_child(const kd_node *n)
{
    return n->bits >> KD_INDEX_SHIFT;
}
static inline uint32_t kd_count(const kd_node *n)
{
    return n->bits >> KD_INDEX_SHIFT;
}

typedef struct kd_tree {
    kd_node *nodes;
    uint32_t nnodes, cap_nodes;
    uint32_t *prims; /* leaf index lists */
    size_t nprims, cap_prims;
    /* The traversal's copy (kd_local.h), made once the tree is built: the
     * leaf lists again in local numbers (nprims entries, parallel to prims),
     * and nloc records; NULL until then. */
    uint32_t *lref;
    struct kd_local *loc;
    uint32_t nloc;
    /* local_of[p]: primitive p's local number + 1, 0 when no leaf lists p
     * (the scene's nprims entries): how a query finds the record of the
     * primitive it leaves out (bsp_intersect_from). */
    uint32_t *local_of;
    size_t nlocal_of;
    /* ... and the nodes again with empty-child flags (kd_walk.h), nwalk of
     * them; NULL until then. The traversal reads these, the rest nodes. */
    kd_node *walk;
    uint32_t nwalk;
    bsp_box box;    /* root cell: the scene bounds grown by pad */
    double pad;     /* bounds padding used for assignment */
    int max_depth;  /* the enforced limit (sizes the traversal stack) */
    int max_leaf_prims;
    int box_empty; /* traversal: box is empty (no live primitive), every ray misses;
                      set by kd_accel_build once the tree is built */
    size_t max_bytes; /* the most bytes nodes and references may take (0: no limit) */
    int over_limit;   /* an allocation failed for max_bytes or KD_MAX_NODES, not for
                         want of memory: kd_build_failed says which */
    double *saving;   /* per node (cap_nodes entries) while a build records them
                         (kd_tree_record_savings): an interior node's saving per ray of
                         the root, by which a leaf budget ranks splits (kd_prune.h);
                         NULL: not recorded */
    double budget_cut;  /* after an SAH build with a leaf budget: the least saving the
                           budget's estimate let the build cut at (-inf: none) */
    int budget_rebuilt; /* ... and 1 when the estimate proved too high and the tree
                           was built again without it */
    double budget_probe_cut; /* ... and the least saving the estimate's probes were
                                built with, from its scouts' (-inf: none; not
                                kept in a tree file) */
    double budget_scout_cut; /* ... and its scouts', from its pilots' (the same) */
    int octree;         /* 1: an octree in binary form (kd_build_octree); its figures
                           count octree nodes (interior nodes and depths in octree
                           levels: three binary levels each) */
} kd_tree;

/* Makes the traversal's copies of a finished tree over SCENE (kd_local.h,
 * kd_walk.h), replacing earlier ones; 0 when out of memory. */
HIDDEN int kd_trace_build(kd_tree *t, const bsp_scene *scene);

/* --- used by builders ------------------------------------------------------ */

/* Room for NODES nodes in all (and their savings, when recorded); 0 when
 * out of memory or past KD_MAX_NODES or max_bytes. */
HIDDEN int kd_reserve_nodes(kd_tree *t, size_t nodes);
/* Makes T (built or not) its root alone again, an empty leaf, keeping its
 * limits and its memory (a builder that starts over). */
HIDDEN void kd_tree_reset(kd_tree *t);
/* Starts recording every node's saving (t->saving); 0 when out of memory. */
HIDDEN int kd_tree_record_savings(kd_tree *t);
/* Appends two adjacent nodes and returns the index of the first, or
 * UINT32_MAX when out of memory or past KD_MAX_NODES or max_bytes. */
HIDDEN uint32_t kd_alloc_pair(kd_tree *t);
/* Room for MORE entries in the leaf index array; 0 when out of memory or
 * past 2^32 entries or max_bytes. */
HIDDEN int kd_reserve_prims(kd_tree *t, size_t more);
/* 1 when T may hold NODES nodes and PRIMS references; else sets over_limit. */
HIDDEN int kd_tree_fits(kd_tree *t, size_t nodes, size_t prims);
/* The error of a build that could not grow T: its size limit when over_limit,
 * else out of memory. */
HIDDEN bsp_status kd_build_failed(const kd_tree *t, bsp_error *err);
/* Sorts the primitive indices A[0..N) ascending. */
HIDDEN void kd_sort_prims(uint32_t *a, size_t n);
/* Sorts A[0..N) and keeps each index once, at A[0..the count returned). */
HIDDEN size_t kd_sort_unique_prims(uint32_t *a, size_t n);
/* Makes node I a leaf listing PRIMS[0..N). Returns 0 when out of memory. */
HIDDEN int kd_make_leaf(kd_tree *t, uint32_t i, const uint32_t *prims, size_t n);
/* Makes node I interior with children at CHILD, CHILD + 1. */
HIDDEN void kd_make_interior(kd_tree *t, uint32_t i, unsigned axis, float split, uint32_t child);

/* Sets up an empty tree over SCENE: root box, padding, limits. Returns 0 when
 * out of memory. */
HIDDEN int kd_tree_init(kd_tree *t, const bsp_scene *scene, int max_depth, int max_leaf_prims);
HIDDEN void kd_tree_free(kd_tree *t);

/* The padded bounds of primitive PRIM. */
HIDDEN bsp_box kd_prim_box(const kd_tree *t, const bsp_scene *scene, uint32_t prim);

/* Kaplan's rule: spatial median, axes in turn. Fills T (already set up). */
HIDDEN bsp_status kd_build_median(kd_tree *t, const bsp_scene *scene, bsp_error *err);
/* The octree as a kd-tree: three levels (x, y, z at the node's planes: its
 * centre, or with BSP_OCTREE_COST the planes of the cost estimate) per octree
 * node, the limits decided at every third level (T->max_depth is then three
 * times the octree's depth). Sets T->octree. */
HIDDEN bsp_status kd_build_octree(kd_tree *t, const bsp_scene *scene, bsp_octree_split split,
                                  bsp_error *err);
/* The octree's default depth for N primitives (docs/octree.md). */
HIDDEN int kd_octree_default_depth(size_t n);
/* Surface area heuristic, exact O(N log N) event build with perfect splits
 * (kd_split_sah.c, kd_sah_node.c). Fills T (already set up) with the costs of O. */
HIDDEN bsp_status kd_build_sah(kd_tree *t, const bsp_scene *scene, const bsp_build_options *o,
                               bsp_error *err);
/* Replaces 0 limits of O by the SAH defaults for SCENE: max_depth
 * round(8 + 1.3 log2 N) (at most BSP_KD_MAX_DEPTH_LIMIT), max_leaf_prims 1. */
HIDDEN void kd_sah_default_limits(bsp_build_options *o, const bsp_scene *scene);

/* --- used by the accel front end --------------------------------------------- */

HIDDEN bsp_status kd_accel_build(bsp_accel *a, bsp_error *err);
/* Makes the built (or loaded) tree T the structure of A: its traversal
 * copies made, A's queries pointed at it; A owns T from then on, also when
 * this fails (out of memory: T is freed). */
HIDDEN bsp_status kd_accel_adopt(bsp_accel *a, kd_tree *t, bsp_error *err);
HIDDEN int kd_intersect(const bsp_accel *a, bsp_query *q, const bsp_ray *ray, uint32_t from,
                        bsp_hit *hit);
HIDDEN int kd_occluded(const bsp_accel *a, bsp_query *q, const bsp_ray *ray, uint32_t from);
/* The figures of T; the model cost under COSTS (every field > 0) with
 * SCENE's primitives. */
HIDDEN void kd_tree_stats(const kd_tree *t, const bsp_scene *scene, const bsp_sah_costs *costs,
                          bsp_tree_stats *st);
HIDDEN bsp_status kd_tree_visit(const kd_tree *t, int max_depth,
                                int (*visit)(const bsp_cell_info *cell, void *ctx), void *ctx,
                                bsp_error *err);
HIDDEN bsp_status kd_tree_check(const kd_tree *t, const bsp_scene *scene, bsp_error *err);

#endif /* BSPRAY_ACCEL_KD_TREE_H */
