/*
 * accel_internal.h — what every acceleration method plugs into: a small table
 * of operations behind the opaque bsp_accel, and the per-thread bsp_query.
 */
#ifndef BSPRAY_ACCEL_INTERNAL_H
#define BSPRAY_ACCEL_INTERNAL_H

#include "bspray/accel.h"
#include "scene/scene_internal.h"

typedef struct accel_ops {
    /* FROM: the primitive left out (bsp_intersect_from), or BSP_NO_PRIM */
    int (*intersect)(const bsp_accel *a, bsp_query *q, const bsp_ray *ray, uint32_t from,
                     bsp_hit *hit);
    int (*occluded)(const bsp_accel *a, bsp_query *q, const bsp_ray *ray, uint32_t from);
    void (*destroy)(void *impl);
} accel_ops;

struct bsp_accel {
    const bsp_scene *scene; /* borrowed */
    bsp_build_options opts;
    const accel_ops *ops;
    void *impl; /* method-specific, owned */
    double build_seconds;
    bsp_mixed_check check; /* sah-mixed's check against sah (kd_mixed_check.c) */
};

struct bsp_query {
    const bsp_accel *accel; /* borrowed */
    bsp_query_counters counters;
    /* Mailbox: stamp[i] == ray_id means primitive i was already tested with
     * the current ray, i in the structure's numbering (a kd-tree's local
     * numbers, kd_local.h; fewer than the scene's primitives). Lives here,
     * never in the shared structure. */
    uint32_t *stamp;
    uint32_t ray_id;
};

/* Starts a new ray in Q's mailbox (NPRIMS stamps): returns its stamp (0
 * without a mailbox). */
static inline uint32_t query_mailbox_next(bsp_query *q, size_t nprims)
{
    if (!q->stamp)
        return 0;
    if (++q->ray_id == 0) { /* wrapped: forget every old stamp */
        for (size_t i = 0; i < nprims; i++)
            q->stamp[i] = 0;
        q->ray_id = 1;
    }
    return q->ray_id;
}

/* Adds one query's counts to Q: INTERIOR nodes and LEAVES (cells) visited,
 * NONEMPTY of them with entries, SKIPPED empty leaves the ray passed through
 * without visiting them (a kd traversal's empty near children: cells
 * traversed, N_ETS and N_EETS, but no step, N_TS), REFS entries met (tested
 * or skipped by the mailbox), TESTS intersection tests. */
static inline void query_count(bsp_query *q, uint64_t interior, uint64_t leaves,
                               uint64_t skipped, uint64_t nonempty, uint64_t refs,
                               uint64_t tests)
{
    q->counters.traversal_steps += interior + leaves;
    q->counters.isect_tests += tests;
    q->counters.leaves_visited += leaves + skipped;
    q->counters.empty_leaves += leaves + skipped - nonempty;
    q->counters.mailbox_hits += refs - tests;
}

/* Builds the naive method (no structure; tests every live primitive). */
HIDDEN bsp_status naive_build(bsp_accel *a, bsp_error *err);
/* The naive method's queries on SCENE: the reference answers, also taken by
 * the kd traversal for rays outside its precision domain (kd_traverse.c). */
HIDDEN int naive_scene_intersect(const bsp_scene *s, bsp_query *q, const bsp_ray *ray,
                                 uint32_t from, bsp_hit *hit);
HIDDEN int naive_scene_occluded(const bsp_scene *s, bsp_query *q, const bsp_ray *ray,
                                uint32_t from);

/* The most bytes a structure's nodes (cells) and lists may take under O:
 * max_tree_bytes, or by default half the machine's physical memory; 0: no
 * limit (the system does not say). */
HIDDEN size_t accel_max_bytes(const bsp_build_options *o);

/* Seconds on a monotonic clock. */
HIDDEN double accel_now(void);

/* Whether KIND is one of the BVHs (bvh.h): binary, four- or eight-wide. */
static inline int accel_is_bvh(bsp_accel_kind kind)
{
    return kind == BSP_ACCEL_BVH || kind == BSP_ACCEL_BVH4 || kind == BSP_ACCEL_BVH8;
}

#endif /* BSPRAY_ACCEL_INTERNAL_H */
