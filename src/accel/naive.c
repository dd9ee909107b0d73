/*
 * naive.c — the O(N) reference method: every live primitive is tested, in
 * index order. It is what every other method is checked against. The
 * method's queries scan its blocks (naive_blocks.h: four primitives at a
 * time, the same answers); the scalar loops here are the definition, taken
 * by the structures for rays they leave to it and when the blocks would
 * exceed the memory limit.
 *
 * Ties: a primitive replaces the current closest hit only when its t is
 * strictly smaller, so at equal t the lowest index wins. FROM (the ray's
 * origin primitive, bsp_intersect_from) is skipped and not counted as a test.
 */
#include <math.h>

#include "accel/accel_internal.h"
#include "accel/naive_blocks.h"

int naive_scene_intersect(const bsp_scene *s, bsp_query *q, const bsp_ray *ray, uint32_t from,
                          bsp_hit *hit)
{
    isect_ray r;
    scene_isect_ray_init(s, &r, ray);
    double tmax = ray->tmax; /* shrinks to the closest hit so far; t never depends on it */
    scene_isect_hit best = {INFINITY, 0.0, 0.0, 1.0}, h;
    uint32_t best_p = BSP_NO_PRIM;
    hit->prim = BSP_NO_PRIM;
    uint64_t tests = 0;
    for (uint32_t i = 0; i < (uint32_t)s->nprims; i++) {
        if (s->prims[i].shape == SHAPE_NONE || i == from)
            continue;
        tests++;
        if (scene_isect(s, i, &r, tmax, &h) && (best_p == BSP_NO_PRIM || h.t < best.t)) {
            best = h;
            best_p = i;
            tmax = h.t;
        }
    }
    q->counters.isect_tests += tests;
    if (best_p == BSP_NO_PRIM)
        return 0;
    scene_hit_finish(&best, best_p, hit);
    return 1;
}

int naive_scene_occluded(const bsp_scene *s, bsp_query *q, const bsp_ray *ray, uint32_t from)
{
    isect_ray r;
    scene_isect_ray_init(s, &r, ray);
    scene_isect_hit h;
    for (uint32_t i = 0; i < (uint32_t)s->nprims; i++) {
        if (s->prims[i].shape == SHAPE_NONE || i == from)
            continue;
        q->counters.isect_tests++;
        if (scene_isect(s, i, &r, ray->tmax, &h))
            return 1;
    }
    return 0;
}

static int naive_intersect(const bsp_accel *a, bsp_query *q, const bsp_ray *ray, uint32_t from,
                           bsp_hit *hit)
{
    if (a->impl)
        return naive_blocks_intersect(a->impl, a->scene, q, ray, from, hit);
    return naive_scene_intersect(a->scene, q, ray, from, hit);
}

static int naive_occluded(const bsp_accel *a, bsp_query *q, const bsp_ray *ray, uint32_t from)
{
    if (a->impl)
        return naive_blocks_occluded(a->impl, a->scene, q, ray, from);
    return naive_scene_occluded(a->scene, q, ray, from);
}

static const accel_ops naive_ops = {naive_intersect, naive_occluded, naive_blocks_destroy};

/* The blocks, unless they would exceed the memory limit (max_tree_bytes, or
 * half the machine's memory): then the scalar loops, which need none. */
bsp_status naive_build(bsp_accel *a, bsp_error *err)
{
    a->ops = &naive_ops;
    a->impl = NULL;
    size_t limit = accel_max_bytes(&a->opts);
    if (limit && naive_blocks_bytes(a->scene) > limit)
        return BSP_OK;
    naive_blocks *b = NULL;
    bsp_status st = naive_blocks_build(a->scene, &b, err);
    a->impl = b;
    return st;
}
