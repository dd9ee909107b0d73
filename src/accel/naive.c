/*
 * naive.c — the O(N) reference method: every live primitive is tested, in
 * index order. It is what every other method is checked against.
 *
 * Ties: a primitive replaces the current closest hit only when its t is
 * strictly smaller, so at equal t the lowest index wins.
 */
#include "accel/accel_internal.h"

static int naive_intersect(const bsp_accel *a, bsp_query *q, const bsp_ray *ray, bsp_hit *hit)
{
    const bsp_scene *s = a->scene;
    bsp_ray r = *ray; /* r.tmax shrinks to the closest hit so far; t never depends on it */
    bsp_hit h;
    int found = 0;
    hit->prim = BSP_NO_PRIM;
    uint64_t tests = 0;
    for (uint32_t i = 0; i < (uint32_t)s->nprims; i++) {
        if (s->prims[i].shape == SHAPE_NONE)
            continue;
        tests++;
        if (scene_intersect(s, i, &r, &h) && (!found || h.t < hit->t)) {
            *hit = h;
            r.tmax = h.t;
            found = 1;
        }
    }
    q->counters.isect_tests += tests;
    return found;
}

static int naive_occluded(const bsp_accel *a, bsp_query *q, const bsp_ray *ray)
{
    const bsp_scene *s = a->scene;
    bsp_hit h;
    for (uint32_t i = 0; i < (uint32_t)s->nprims; i++) {
        if (s->prims[i].shape == SHAPE_NONE)
            continue;
        q->counters.isect_tests++;
        if (scene_intersect(s, i, ray, &h))
            return 1;
    }
    return 0;
}

static const accel_ops naive_ops = {naive_intersect, naive_occluded, NULL};

bsp_status naive_build(bsp_accel *a, bsp_error *err)
{
    (void)err;
    a->ops = &naive_ops;
    a->impl = NULL;
    return BSP_OK;
}
