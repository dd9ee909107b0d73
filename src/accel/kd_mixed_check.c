/*
 * kd_mixed_check.c — sah-mixed's check against plain sah.
 *
 * A sah-mixed tree is built from a model of the render's rays: a 65 x 65
 * pre-pass measures their mix and, for the sampled and counted models, where
 * the non-primary ones run. The model's expected cost ranks trees well on
 * average but not on every scene: where it is off (on SPD tree the surface
 * term spreads the shadow rays over empty ground; a few per cent either way
 * on balls and tetra) the sah-mixed tree renders slower than plain sah's.
 * So the check measures instead of predicting: it builds the sah tree of the
 * same options, renders the view once more at 64 x 64 — rays the models were
 * not fitted to, since the pre-pass shot 65 x 65 other ones — shoots every
 * ray of that render through both trees (closest hit, or any hit for shadow
 * rays, as the renderer does) and keeps the tree of the lower cost per ray:
 *
 *     C_trav steps + T tests + T_mb mailbox hits,
 *
 * the SAH's own units, T the mean T_i of the scene's primitives (the
 * counters do not split tests by kind). The rays and their hits are the same
 * for every exact tree, so both trees see exactly the same work; the counts
 * are integers, so the choice is deterministic. A tie keeps the sah-mixed
 * tree. Cost: one sah build, a 64 x 64 render and two passes of its rays.
 */
#include <stdlib.h>
#include <string.h>

#include "accel/kd_cost.h"
#include "accel/kd_mixed_check.h"
#include "accel/kd_prepass.h"

/* Side of the check's render, in rays: not the pre-pass's (kd_view.c). */
#define CHECK_RES 64

/* The cost per ray of shooting RAYS[0..N) (classes CLS) through A. -1 when
 * out of memory. */
static double rays_cost(const bsp_accel *a, const bsp_ray *rays, const uint8_t *cls,
                        const uint32_t *from, size_t n, const kd_cost_model *cm, double t_mean)
{
    bsp_query *q = bsp_query_create(a);
    if (!q)
        return -1.0;
    for (size_t i = 0; i < n; i++) {
        bsp_hit h;
        if (cls[i] == BSP_RAY_SHADOW)
            (void)bsp_occluded_from(a, q, &rays[i], from[i]);
        else
            (void)bsp_intersect_from(a, q, &rays[i], from[i], &h);
    }
    const bsp_query_counters *c = bsp_query_get_counters(q);
    /* every entry not tested costs its look-up (a stamp, or a compare without
     * mailboxes), whatever model built the tree: --straddle twice changes the
     * builder's charge, not the traversal's work */
    double cost = cm->c.traversal * (double)c->traversal_steps + t_mean * (double)c->isect_tests +
                  cm->mailbox_hit * (double)c->mailbox_hits;
    bsp_query_destroy(q);
    return n ? cost / (double)n : 0.0;
}

/* The mean T_i of SCENE's live primitives under CM. */
static double mean_prim_cost(const bsp_scene *scene, const kd_cost_model *cm)
{
    double sum = 0.0;
    size_t live = 0, np = bsp_scene_prim_count(scene);
    for (uint32_t p = 0; p < np; p++)
        if (scene->prims[p].shape != SHAPE_NONE) {
            sum += kd_prim_cost(scene, p, &cm->c);
            live++;
        }
    return live ? sum / (double)live : 0.0;
}

bsp_status kd_mixed_check(bsp_accel *a, bsp_error *err)
{
    bsp_build_options so = a->opts; /* its limits are resolved: the same in both trees */
    so.kind = BSP_ACCEL_SAH;
    bsp_accel *s = NULL;
    bsp_status st = bsp_accel_build(a->scene, &so, &s, err);
    if (st != BSP_OK)
        return st;
    bsp_camera cam = kd_prepass_camera(a->scene, &a->opts, CHECK_RES);
    bsp_ray *rays = NULL;
    uint8_t *cls = NULL;
    uint32_t *from = NULL;
    size_t n = 0;
    st = kd_render_rays(s, &cam, 0, &rays, &cls, &from, &n, err);
    if (st == BSP_OK) {
        kd_cost_model cm;
        kd_cost_resolve(&a->opts, &cm);
        double t_mean = mean_prim_cost(a->scene, &cm);
        double cm_mixed = rays_cost(a, rays, cls, from, n, &cm, t_mean);
        double cm_sah = rays_cost(s, rays, cls, from, n, &cm, t_mean);
        if (cm_mixed < 0.0 || cm_sah < 0.0) {
            st = error_set(err, BSP_ERR_NOMEM, NULL, 0, "out of memory");
        } else {
            a->check.ran = 1;
            a->check.rays = n;
            a->check.cost_mixed = cm_mixed;
            a->check.cost_sah = cm_sah;
            a->check.kept_sah = cm_sah < cm_mixed;
            if (a->check.kept_sah) { /* the two trees swap owners */
                void *impl = a->impl;
                a->impl = s->impl;
                s->impl = impl;
            }
        }
    }
    free(rays);
    free(cls);
    free(from);
    bsp_accel_destroy(s);
    return st;
}

void bsp_accel_mixed_check(const bsp_accel *a, bsp_mixed_check *out)
{
    *out = a->check;
}
