/*
 * kd_prepass.c — sah-mixed's pre-pass: a small Whitted render through the
 * tree's view that tells the build how the render's rays divide into
 * classes and where the non-primary ones run.
 *
 * The render runs on a `sah` tree capped at depth log2 N (the rays and their
 * hits do not depend on the structure; a tree for a few ten thousand rays
 * need not be deep, and a shallow one is cheap to build) on one
 * thread, so the rays are logged in one fixed order and the sampled measure
 * — sums of floating-point runs — is the same on every run: the tree does
 * not depend on the thread count.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "accel/kd_prepass.h"
#include "bspray/render.h"

#include "geom/vec.h"

bsp_camera kd_prepass_camera(const bsp_scene *scene, const bsp_build_options *o, int res)
{
    bsp_camera cam;
    if (!o->view.explicit_view) {
        cam = *bsp_scene_camera(scene);
    } else {
        memset(&cam, 0, sizeof cam);
        cam.from = o->view.eye;
        cam.at = v3_add(o->view.eye, o->view.dir);
        cam.up = o->view.up;
        cam.angle_deg = o->view.fov_deg;
    }
    cam.res_x = cam.res_y = res - 1; /* SPD protocol: res rays across */
    return cam;
}

typedef struct ray_log {
    uint64_t count[BSP_RAY_CLASS_COUNT];
    bsp_ray *rays;  /* the rays kept */
    uint32_t *from; /* the primitive each one's query leaves out */
    uint8_t *cls;   /* their classes, when kept too */
    size_t n, cap;
    int keep, keep_primary, nomem;
} ray_log;

static void log_ray(bsp_ray_class cls, const bsp_ray *ray, uint32_t from, void *ctx)
{
    ray_log *l = ctx;
    if ((unsigned)cls < BSP_RAY_CLASS_COUNT)
        l->count[cls]++;
    if (!l->keep || (cls == BSP_RAY_PRIMARY && !l->keep_primary) || l->nomem)
        return;
    if (l->n == l->cap) {
        size_t ncap = l->cap ? 2 * l->cap : 4096;
        bsp_ray *nr = realloc(l->rays, ncap * sizeof *nr);
        if (nr)
            l->rays = nr;
        uint32_t *nf = nr ? realloc(l->from, ncap * sizeof *nf) : NULL;
        if (nf)
            l->from = nf;
        uint8_t *nc = nf && l->keep_primary ? realloc(l->cls, ncap) : NULL;
        if (nc)
            l->cls = nc;
        if (!nr || !nf || (l->keep_primary && !nc)) {
            l->nomem = 1;
            return;
        }
        l->cap = ncap;
    }
    if (l->keep_primary)
        l->cls[l->n] = (uint8_t)cls;
    l->from[l->n] = from;
    l->rays[l->n++] = *ray;
}

/* Renders through A with camera CAM on one thread (one order of the logged
 * rays), logging into LOG. */
static bsp_status render_logged(const bsp_accel *a, const bsp_camera *cam, int max_depth,
                                ray_log *log, bsp_error *err)
{
    bsp_render_options ro;
    bsp_render_options_defaults(&ro);
    ro.camera = cam;
    if (max_depth > 0)
        ro.max_depth = max_depth;
    ro.threads = 1;
    ro.ray_log = log_ray;
    ro.ray_log_ctx = log;
    bsp_image *img = NULL;
    bsp_status st = bsp_render(a, &ro, &img, NULL, err);
    bsp_image_destroy(img);
    if (st == BSP_OK && log->nomem)
        st = error_set(err, BSP_ERR_NOMEM, NULL, 0, "out of memory");
    return st;
}

bsp_status kd_render_rays(const bsp_accel *accel, const bsp_camera *cam, int max_depth,
                          bsp_ray **rays, uint8_t **cls, uint32_t **from, size_t *n,
                          bsp_error *err)
{
    ray_log log;
    memset(&log, 0, sizeof log);
    log.keep = log.keep_primary = 1;
    bsp_status st = render_logged(accel, cam, max_depth, &log, err);
    if (st != BSP_OK) {
        free(log.rays);
        free(log.cls);
        free(log.from);
        return st;
    }
    *rays = log.rays;
    *cls = log.cls;
    *from = log.from;
    *n = log.n;
    return BSP_OK;
}

bsp_status kd_mixed_prepass(const bsp_scene *scene, const bsp_camera *cam, int max_depth,
                            int build_threads, double *share, kd_flux_segment **seg, size_t *nseg,
                            bsp_error *err)
{
    bsp_build_options bo;
    bsp_build_options_defaults(&bo);
    bo.kind = BSP_ACCEL_SAH;
    bo.threads = build_threads;
    /* depth at most ceil(log2 N) (about one primitive per leaf), below the
     * everyday 8 + 1.3 log2 N: the whole sah-mixed build 2.6-3.6x faster on
     * gears and shells. The rays and where they stop are exact, so the
     * pre-pass's figures (share, segments) do not depend on the tree. */
    size_t n = bsp_scene_prim_count(scene);
    int depth = (int)ceil(log2((double)n + 1.0));
    bo.max_depth = depth < 4 ? 4 : depth < BSP_KD_MAX_DEPTH_LIMIT ? depth : BSP_KD_MAX_DEPTH_LIMIT;
    bsp_accel *a = NULL;
    bsp_status st = bsp_accel_build(scene, &bo, &a, err);
    if (st != BSP_OK)
        return st;
    ray_log log;
    memset(&log, 0, sizeof log);
    log.keep = seg != NULL;
    st = render_logged(a, cam, max_depth, &log, err); /* one order: see the top of the file */
    kd_flux_segment *out = NULL;
    if (st == BSP_OK && seg) {
        out = malloc((log.n ? log.n : 1) * sizeof *out);
        bsp_query *q = out ? bsp_query_create(a) : NULL;
        if (!q) {
            st = error_set(err, BSP_ERR_NOMEM, NULL, 0, "out of memory");
        } else {
            /* a segment ends where its ray stops: the closest hit (a shadow ray
             * stops at its first occluder, the nearest it meets), or tmax */
            for (size_t i = 0; i < log.n; i++) {
                const bsp_ray *r = &log.rays[i];
                bsp_hit h;
                double end = bsp_intersect_from(a, q, r, log.from[i], &h) ? h.t : r->tmax;
                out[i] = (kd_flux_segment){r->org, r->dir, r->tmin, end};
            }
            bsp_query_destroy(q);
        }
    }
    free(log.rays);
    free(log.from);
    bsp_accel_destroy(a);
    if (st != BSP_OK) {
        free(out);
        return st;
    }
    uint64_t all = 0;
    for (int c = 0; c < BSP_RAY_CLASS_COUNT; c++)
        all += log.count[c];
    *share = all ? (double)log.count[BSP_RAY_PRIMARY] / (double)all : 1.0;
    if (seg) {
        *seg = out;
        *nseg = log.n;
    }
    return BSP_OK;
}

/* render.h: the pre-pass without the segments */
bsp_status bsp_measure_primary_share(const bsp_scene *scene, const bsp_camera *camera,
                                     int max_depth, double *share, bsp_error *err)
{
    return kd_mixed_prepass(scene, camera, max_depth, 0, share, NULL, NULL, err);
}
