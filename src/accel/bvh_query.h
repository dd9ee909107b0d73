/*
 * bvh_query.h — what the BVH's two traversals (bvh_traverse.c, two-wide;
 * bvh4_traverse.c, four-wide) share: the precision domain's test and the
 * leaf step, which tests a leaf's records with the exact kernels.
 */
#ifndef BSPRAY_ACCEL_BVH_QUERY_H
#define BSPRAY_ACCEL_BVH_QUERY_H

#include <math.h>

#include "accel/bvh.h"

/* 1 when RAY lies in S's precision domain (scene_internal.h). */
static inline int bvh_in_domain(const bsp_scene *s, const bsp_ray *ray)
{
    const double *d = ray->dir.v;
    return scene_ray_in_domain(s, ray->org.v, d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
}

/* A query's state, for its leaf steps. */
typedef struct query_state {
    const bsp_scene *s;
    const kd_local *rec;
    isect_ray r;
    uint32_t from, best_p;
    double tmax; /* closest hit: follows the best hit; t never depends on it */
    scene_isect_hit best;
    uint64_t leaves, refs, tests;
} query_state;

/* Tests the CNT records from FIRST for the query C, closest hit or ANY hit;
 * 1 when an any-hit query found one. */
static inline __attribute__((always_inline)) int leaf_records(query_state *c, uint32_t first,
                                                              uint32_t cnt, int any)
{
    scene_isect_hit h;
    c->leaves++;
    c->refs += cnt;
    for (const kd_local *L = c->rec + first, *end = L + cnt; L != end; L++) {
        if (L->prim == c->from)
            continue;
        c->tests++;
        if (!kd_local_isect(c->s, L, &c->r, c->tmax, &h))
            continue;
        if (any)
            return 1;
        /* every hit found is at most tmax: better when its t is smaller or,
         * at equal t, its index lower (the naive order) */
        if (h.t < c->best.t || L->prim < c->best_p) {
            c->best = h;
            c->best_p = L->prim;
            c->tmax = h.t;
        }
    }
    return 0;
}

/* Whether the query of RAY on A (closest hit into HIT, or occlusion when
 * HIT is NULL) is answered without a walk, in *OUT: outside the precision
 * domain by the naive method, in an empty tree by no hit. */
static inline int query_without_walk(const bsp_accel *a, bsp_query *q, const bsp_ray *ray,
                                     uint32_t from, bsp_hit *hit, int *out)
{
    const bvh *t = a->impl;
    if (hit)
        hit->prim = BSP_NO_PRIM;
    if (__builtin_expect(!bvh_in_domain(a->scene, ray), 0))
        *out = hit ? naive_scene_intersect(a->scene, q, ray, from, hit)
                   : naive_scene_occluded(a->scene, q, ray, from);
    else if (!t->nnodes)
        *out = 0;
    else
        return 0;
    return 1;
}

/* Starts the query C of RAY (in the domain) on T, FROM left out. */
static inline void query_start(query_state *c, const bsp_scene *s, const bvh *t,
                               const bsp_ray *ray, uint32_t from)
{
    *c = (query_state){.s = s, .rec = t->rec, .from = from, .best_p = BSP_NO_PRIM,
                       .tmax = ray->tmax};
    c->best = (scene_isect_hit){INFINITY, 0.0, 0.0, 1.0};
    isect_ray_init(&c->r, ray, s->hit_tol, &s->tri_reach);
}

/* Ends the query C, which tested BOXES node boxes: its counters into Q
 * (N_TS the boxes; interior: all but the leaves entered; no empty leaves,
 * no skips; mailbox hits = refs - tests = the left-out primitive) and, for
 * a closest hit (HIT not NULL), its answer; 1 when it hit. */
static inline int query_finish(bsp_query *q, const query_state *c, uint64_t boxes, bsp_hit *hit)
{
    query_count(q, boxes - c->leaves, c->leaves, 0, c->leaves, c->refs, c->tests);
    if (!hit || c->best_p == BSP_NO_PRIM)
        return 0;
    scene_hit_finish(&c->best, c->best_p, hit);
    return 1;
}

#endif /* BSPRAY_ACCEL_BVH_QUERY_H */
