/*
 * render.c — the Whitted ray tracer of the SPD, with ray statistics.
 *
 * Shading rules — the ones that reproduce the ray counts of Havran's SPD
 * tables and of the SPD Readme (docs/renderer.md has the comparison):
 *   - every surface is hit from both sides;
 *   - a shadow ray goes to every point light on the surface's own front side:
 *     dot(N, L) > 0 with N the outward normal (spheres, cones) or the winding
 *     normal (polygons, patches), not turned toward the viewer. A ray that
 *     hits a glass sphere from inside therefore casts shadow rays only to
 *     lights outside that wall. A two-sided material (a mesh's default:
 *     bsp_material.two_sided) takes its lights on the side the viewer sees
 *     instead, so that a face wound the other way round is lit like its
 *     neighbours;
 *   - a surface with Ks > 0 or T > 0 spawns a reflected ray (the SPD Readme:
 *     every transmitter also reflects), one with T > 0 a refracted ray, none
 *     on total internal reflection;
 *   - ray depth counts generations: primary rays have depth 0 and a hit
 *     spawns secondary rays while its depth is below the maximum (default 4:
 *     the paper's and Havran's "maximal ray-recursion depth 4", the SPD
 *     Readme's "maximum depth 5" counting the eye ray as 1);
 *   - every primitive blocks shadow rays, transmitters too;
 *   - colour: ambient + Lambert + Phong highlight per unshadowed light,
 *     with normals turned to face the viewer, plus Ks * reflected +
 *     T * refracted (a transmitter with Ks = 0 weights its reflection 0);
 *     a miss returns the background.
 *
 * Epsilon policy: secondary and shadow rays start exactly at the hit point
 * with tmin = RAY_EPS_REL * (scene scale), directions of unit length; shadow
 * rays end RAY_EPS_REL * scale before the light (docs/precision.md). A ray
 * that cannot meet the primitive it leaves again is cast without it
 * (bsp_intersect_from, origin_prim below).
 *
 * Threads take tiles (or rows: bsp_pixel_order) from a shared counter;
 * every pixel depends only on its own rays, so the image is identical for
 * any thread count and either order. Counters live in per-thread state and
 * are summed at the end.
 */
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "accel/accel_internal.h"
#include "geom/vec.h"
#include "render/camera.h"

/* Relative offset of secondary-ray origins (times the scene scale). */
#define RAY_EPS_REL 1e-9

void bsp_render_options_defaults(bsp_render_options *o)
{
    memset(o, 0, sizeof *o);
    o->max_depth = 4;
    o->sampling = BSP_SAMPLING_SPD;
}

typedef struct render_job {
    const bsp_accel *accel;
    const bsp_scene *scene;
    const bsp_render_options *opts;
    camera_rays cam;
    bsp_image *img;
    double eps;             /* absolute offset of secondary rays */
    double light_intensity; /* per light, and ambient */
    int tile_w, tile_h;     /* the pieces handed out: tiles, or rows (width x 1) */
    int tiles_x, ntiles;    /* pieces across, and in all */
    atomic_int next_tile;
    atomic_int tiles_done;
} render_job;

typedef struct worker {
    render_job *job;
    bsp_query *query;
    bsp_render_stats stats;
    int is_main; /* reports progress */
} worker;

/* Adds the query counters spent since BEFORE to class CLS. */
static void account(worker *w, bsp_ray_class cls, const bsp_query_counters *before)
{
    const bsp_query_counters *now = &w->query->counters;
    bsp_ray_class_stats *c = &w->stats.cls[cls];
    c->isect_tests += now->isect_tests - before->isect_tests;
    c->traversal_steps += now->traversal_steps - before->traversal_steps;
    c->leaves_visited += now->leaves_visited - before->leaves_visited;
    c->empty_leaves += now->empty_leaves - before->empty_leaves;
    c->mailbox_hits += now->mailbox_hits - before->mailbox_hits;
}

/* The primitive to leave out of the query of a ray from a point of PRIM in
 * direction D (bsp_intersect_from), or BSP_NO_PRIM. A ray that starts on a
 * planar primitive (a triangle, or a polygon, whose hits lie on its mean
 * plane) and leaves its plane cannot meet it again; nor can a ray that leaves
 * a sphere or cone through the outer side of its surface, both solids being
 * convex (FRONT: the primitive's normal at the point, by
 * bsp_scene_hit_normals: outward, or inward for an NFF negative radius; a
 * cone's apex, where that normal falls back to the axis, is left to the
 * test). A ray into a sphere or cone keeps it: it meets the far side. */
static uint32_t origin_prim(const bsp_scene *s, uint32_t prim, bsp_vec3 front, bsp_vec3 d)
{
    const prim_record *r = &s->prims[prim];
    double dn = v3_dot(front, d);
    switch ((shape_kind)r->shape) {
    case SHAPE_TRIANGLE:
    case SHAPE_POLYGON:
        return dn != 0.0 ? prim : BSP_NO_PRIM;
    case SHAPE_SPHERE:
        return (s->spheres[r->slot].inside_only ? dn < 0.0 : dn > 0.0) ? prim : BSP_NO_PRIM;
    case SHAPE_CONE: {
        const cone_shape *c = &s->cones[r->slot];
        bsp_vec3 ax = c->inside_only ? v3_neg(c->axis) : c->axis;
        int at_apex = front.x == ax.x && front.y == ax.y && front.z == ax.z;
        return (c->inside_only ? dn < 0.0 : dn > 0.0) && !at_apex ? prim : BSP_NO_PRIM;
    }
    default:
        return BSP_NO_PRIM;
    }
}

/* Whether the segment from P (on primitive FROM, BSP_NO_PRIM: on none) to
 * LIGHT is blocked. */
static int shadowed(worker *w, bsp_vec3 p, uint32_t from, bsp_vec3 light)
{
    bsp_vec3 to = v3_sub(light, p);
    double dist = v3_length(to);
    bsp_ray r;
    r.org = p;
    r.dir = v3_scale(to, 1.0 / dist);
    r.tmin = w->job->eps;
    r.tmax = dist - w->job->eps;
    if (!(r.tmax > r.tmin))
        return 0; /* the light sits on the surface */
    if (w->job->opts->ray_log)
        w->job->opts->ray_log(BSP_RAY_SHADOW, &r, from, w->job->opts->ray_log_ctx);
    bsp_query_counters before = w->query->counters;
    int blocked = bsp_occluded_from(w->job->accel, w->query, &r, from);
    account(w, BSP_RAY_SHADOW, &before);
    w->stats.cls[BSP_RAY_SHADOW].rays++;
    w->stats.cls[BSP_RAY_SHADOW].hits += (uint64_t)blocked;
    return blocked;
}

static void trace(worker *w, const bsp_ray *ray, uint32_t from, int depth, bsp_ray_class cls,
                  double out[3]);

static void shade(worker *w, const bsp_ray *ray, const bsp_hit *hit, int depth, double out[3])
{
    const render_job *job = w->job;
    const bsp_scene *s = job->scene;
    const bsp_material *m = bsp_scene_material(s, bsp_scene_prim_material(s, hit->prim));
    bsp_vec3 ng, ns;
    bsp_scene_hit_normals(s, ray, hit, &ng, &ns);
    bsp_vec3 p = ray_at(ray, hit->t);
    bsp_vec3 d = ray->dir;

    /* ng is the surface's own front; shading uses normals turned to the viewer */
    bsp_vec3 front = ng;
    int entering = v3_dot(ng, d) < 0.0;
    if (!entering) {
        ng = v3_neg(ng);
        ns = v3_neg(ns);
    }
    if (v3_dot(ns, d) > 0.0) /* interpolated normal facing away: use the true one */
        ns = ng;
    /* the side whose lights count: the front (the SPD rule), or for a
     * two-sided material the side the viewer sees */
    const bsp_vec3 lit_side = m->two_sided ? ng : front;

    double I = job->light_intensity;
    for (int c = 0; c < 3; c++)
        out[c] = I * m->kd * m->color[c];

    bsp_vec3 view = v3_neg(d);
    for (size_t l = 0; l < bsp_scene_light_count(s); l++) {
        const bsp_light *light = bsp_scene_light(s, l);
        bsp_vec3 L = v3_sub(light->pos, p);
        if (v3_dot(lit_side, L) <= 0.0)
            continue; /* light behind the lit side: no shadow ray (SPD rule) */
        if (shadowed(w, p, origin_prim(s, hit->prim, front, L), light->pos))
            continue;
        L = v3_normalize(L);
        double diff = v3_dot(ns, L);
        if (diff < 0.0)
            diff = 0.0;
        double spec = 0.0;
        if (m->ks > 0.0) {
            bsp_vec3 h = v3_sub(v3_scale(ns, 2.0 * v3_dot(ns, L)), L); /* mirror of L */
            double rv = v3_dot(h, view);
            if (rv > 0.0)
                spec = m->ks * pow(rv, m->shine);
        }
        for (int c = 0; c < 3; c++)
            out[c] += I * light->color[c] * (m->kd * m->color[c] * diff + spec);
    }

    if (depth >= job->opts->max_depth)
        return;
    double cosi = -v3_dot(d, ns);
    if (m->ks > 0.0 || m->t > 0.0) {
        bsp_ray r;
        r.org = p;
        r.dir = v3_normalize(v3_madd(d, ns, 2.0 * cosi));
        r.tmin = job->eps;
        r.tmax = INFINITY;
        double c[3];
        w->stats.reflected_rays++;
        trace(w, &r, origin_prim(s, hit->prim, front, r.dir), depth + 1, BSP_RAY_SECONDARY, c);
        for (int k = 0; k < 3; k++)
            out[k] += m->ks * c[k];
    }
    if (m->t > 0.0) {
        double eta = entering ? 1.0 / m->ior : m->ior;
        double k = 1.0 - eta * eta * (1.0 - cosi * cosi);
        if (k >= 0.0) {
            bsp_ray r;
            r.org = p;
            r.dir = v3_normalize(v3_add(v3_scale(d, eta), v3_scale(ns, eta * cosi - sqrt(k))));
            r.tmin = job->eps;
            r.tmax = INFINITY;
            double c[3];
            w->stats.refracted_rays++;
            trace(w, &r, origin_prim(s, hit->prim, front, r.dir), depth + 1, BSP_RAY_SECONDARY,
                  c);
            for (int q = 0; q < 3; q++)
                out[q] += m->t * c[q];
        }
    }
}

/* Traces RAY (leaving primitive FROM, BSP_NO_PRIM: none) into OUT. */
static void trace(worker *w, const bsp_ray *ray, uint32_t from, int depth, bsp_ray_class cls,
                  double out[3])
{
    bsp_hit hit;
    if (w->job->opts->ray_log)
        w->job->opts->ray_log(cls, ray, from, w->job->opts->ray_log_ctx);
    bsp_query_counters before = w->query->counters;
    int found = bsp_intersect_from(w->job->accel, w->query, ray, from, &hit);
    account(w, cls, &before);
    w->stats.cls[cls].rays++;
    if (!found) {
        bsp_scene_background(w->job->scene, out);
        return;
    }
    w->stats.cls[cls].hits++;
    shade(w, ray, &hit, depth, out);
}

/* *TO = the counters of NOW less those of BEFORE. */
static void counters_since(bsp_query_counters *to, const bsp_query_counters *now,
                           const bsp_query_counters *before)
{
    to->rays = now->rays - before->rays;
    to->isect_tests = now->isect_tests - before->isect_tests;
    to->traversal_steps = now->traversal_steps - before->traversal_steps;
    to->leaves_visited = now->leaves_visited - before->leaves_visited;
    to->empty_leaves = now->empty_leaves - before->empty_leaves;
    to->mailbox_hits = now->mailbox_hits - before->mailbox_hits;
}

/* Traces the pixels of [X0, X1) x [Y0, Y1) row by row. */
static void render_piece(worker *w, int x0, int x1, int y0, int y1)
{
    render_job *job = w->job;
    int width = job->img->width;
    bsp_query_counters *costs = job->opts->pixel_costs;
    for (int y = y0; y < y1; y++) {
        float *row = job->img->rgb + (size_t)y * (size_t)width * 3;
        for (int x = x0; x < x1; x++) {
            bsp_ray r = camera_ray(&job->cam, x, y);
            double c[3];
            if (costs) {
                const bsp_query_counters before = w->query->counters;
                trace(w, &r, BSP_NO_PRIM, 0, BSP_RAY_PRIMARY, c);
                counters_since(&costs[(size_t)y * (size_t)width + (size_t)x],
                               &w->query->counters, &before);
            } else {
                trace(w, &r, BSP_NO_PRIM, 0, BSP_RAY_PRIMARY, c);
            }
            for (int k = 0; k < 3; k++)
                row[3 * x + k] = (float)c[k];
        }
    }
}

/* Takes pieces (tiles or rows) from the job's counter until none is left. */
static void render_pieces(worker *w)
{
    render_job *job = w->job;
    int width = job->img->width, height = job->img->height;
    for (;;) {
        int i = atomic_fetch_add(&job->next_tile, 1);
        if (i >= job->ntiles)
            break;
        int x0 = (i % job->tiles_x) * job->tile_w, y0 = (i / job->tiles_x) * job->tile_h;
        int x1 = x0 + job->tile_w < width ? x0 + job->tile_w : width;
        int y1 = y0 + job->tile_h < height ? y0 + job->tile_h : height;
        render_piece(w, x0, x1, y0, y1);
        int done = atomic_fetch_add(&job->tiles_done, 1) + 1;
        if (w->is_main && job->opts->progress)
            job->opts->progress((double)done / (double)job->ntiles, job->opts->progress_ctx);
    }
}

static void *worker_main(void *arg)
{
    render_pieces(arg);
    return NULL;
}

static void add_stats(bsp_render_stats *to, const bsp_render_stats *from)
{
    for (int c = 0; c < BSP_RAY_CLASS_COUNT; c++) {
        bsp_ray_class_stats *a = &to->cls[c];
        const bsp_ray_class_stats *b = &from->cls[c];
        a->rays += b->rays;
        a->hits += b->hits;
        a->isect_tests += b->isect_tests;
        a->traversal_steps += b->traversal_steps;
        a->leaves_visited += b->leaves_visited;
        a->empty_leaves += b->empty_leaves;
        a->mailbox_hits += b->mailbox_hits;
    }
    to->reflected_rays += from->reflected_rays;
    to->refracted_rays += from->refracted_rays;
}

#define RENDER_MAX_THREADS 256

bsp_status bsp_render_size(const bsp_scene *scene, const bsp_render_options *opts_in,
                           int *width, int *height, bsp_error *err)
{
    bsp_render_options opts;
    if (opts_in)
        opts = *opts_in;
    else
        bsp_render_options_defaults(&opts);
    const bsp_camera *cam = opts.camera ? opts.camera : bsp_scene_camera(scene);
    if (!cam)
        return error_set(err, BSP_ERR_INVALID, NULL, 0,
                         "the scene has no camera (no 'v' block)");
    if (opts.width < 0 || opts.height < 0)
        return error_set(err, BSP_ERR_INVALID, NULL, 0, "negative image size");
    *width = opts.width;
    *height = opts.height;
    if (*width == 0 || *height == 0)
        camera_default_size(cam, opts.sampling, width, height);
    return BSP_OK;
}

bsp_status bsp_render(const bsp_accel *accel, const bsp_render_options *opts_in,
                      bsp_image **out, bsp_render_stats *stats, bsp_error *err)
{
    *out = NULL;
    bsp_render_options opts;
    if (opts_in)
        opts = *opts_in;
    else
        bsp_render_options_defaults(&opts);
    const bsp_scene *s = bsp_accel_scene(accel);
    const bsp_camera *cam = opts.camera ? opts.camera : bsp_scene_camera(s);
    if (!cam)
        return error_set(err, BSP_ERR_INVALID, NULL, 0,
                         "the scene has no camera (no 'v' block)");
    double ortho_width = 0.0;
    if (opts.orthographic) {
        ortho_width = opts.ortho_width > 0.0 ? opts.ortho_width : camera_default_ortho_width(cam);
        if (!(ortho_width > 0.0 && isfinite(ortho_width)))
            return error_set(err, BSP_ERR_INVALID, NULL, 0,
                             "the orthographic window width must be positive and finite");
    }
    if (opts.pixel_order != BSP_PIXELS_TILES && opts.pixel_order != BSP_PIXELS_ROWS)
        return error_set(err, BSP_ERR_INVALID, NULL, 0, "pixel order %d is not one of %d, %d",
                         (int)opts.pixel_order, BSP_PIXELS_TILES, BSP_PIXELS_ROWS);
    if (opts.max_depth < 0 || opts.max_depth > 64)
        return error_set(err, BSP_ERR_INVALID, NULL, 0, "ray depth %d is outside 0..64",
                         opts.max_depth);
    int width, height;
    bsp_status sz = bsp_render_size(s, &opts, &width, &height, err);
    if (sz != BSP_OK)
        return sz;
    if (opts.pixel_costs && opts.pixel_costs_count < (size_t)width * (size_t)height)
        return error_set(err, BSP_ERR_INVALID, NULL, 0,
                         "room for %zu pixel costs, the render has %d x %d pixels",
                         opts.pixel_costs_count, width, height);
    int threads = opts.threads;
    if (threads <= 0) {
        long n = sysconf(_SC_NPROCESSORS_ONLN);
        threads = n > 0 ? (int)n : 1;
    }
    if (threads > RENDER_MAX_THREADS)
        threads = RENDER_MAX_THREADS;

    render_job job;
    memset(&job, 0, sizeof job);
    job.accel = accel;
    job.scene = s;
    job.opts = &opts;
    if (width < 1 || height < 1)
        return error_set(err, BSP_ERR_INVALID, NULL, 0, "image size %d x %d", width, height);
    if ((long long)width > BSP_IMAGE_MAX_PIXELS / height)
        return error_set(err, BSP_ERR_LIMIT, NULL, 0,
                         "a %d x %d image has more than %lld pixels", width, height,
                         BSP_IMAGE_MAX_PIXELS);
    job.img = bsp_image_create(width, height);
    if (!job.img)
        return error_set(err, BSP_ERR_NOMEM, NULL, 0, "out of memory for a %d x %d image",
                         width, height);
    camera_rays_init(&job.cam, cam, width, height, opts.sampling, ortho_width);
    job.eps = RAY_EPS_REL * scene_scale(s);
    size_t nl = bsp_scene_light_count(s);
    job.light_intensity = nl ? 1.0 / (2.0 * sqrt((double)nl)) : 0.5;
    if (opts.pixel_order == BSP_PIXELS_ROWS) {
        job.tile_w = width;
        job.tile_h = 1;
    } else {
        job.tile_w = job.tile_h = BSP_RENDER_TILE;
    }
    job.tiles_x = (width + job.tile_w - 1) / job.tile_w;
    job.ntiles = job.tiles_x * ((height + job.tile_h - 1) / job.tile_h);
    atomic_init(&job.next_tile, 0);
    atomic_init(&job.tiles_done, 0);

    worker *workers = calloc((size_t)threads, sizeof *workers);
    pthread_t *tids = calloc((size_t)threads, sizeof *tids);
    bsp_status st = BSP_OK;
    if (!workers || !tids)
        st = error_set(err, BSP_ERR_NOMEM, NULL, 0, "out of memory");
    for (int i = 0; st == BSP_OK && i < threads; i++) {
        workers[i].job = &job;
        workers[i].is_main = i == 0;
        workers[i].query = bsp_query_create(accel);
        if (!workers[i].query)
            st = error_set(err, BSP_ERR_NOMEM, NULL, 0, "out of memory");
    }
    double t0 = accel_now();
    int started = 1;
    if (st == BSP_OK) {
        for (; started < threads; started++)
            if (pthread_create(&tids[started], NULL, worker_main, &workers[started]) != 0)
                break; /* fewer threads is still a correct render */
        render_pieces(&workers[0]);
        for (int i = 1; i < started; i++)
            pthread_join(tids[i], NULL);
    }
    double t1 = accel_now();

    if (st == BSP_OK && stats) {
        memset(stats, 0, sizeof *stats);
        for (int i = 0; i < started; i++)
            add_stats(stats, &workers[i].stats);
        stats->width = width;
        stats->height = height;
        stats->max_depth = opts.max_depth;
        stats->threads = started;
        stats->build_seconds = bsp_accel_build_seconds(accel);
        stats->render_seconds = t1 - t0;
    }
    if (workers)
        for (int i = 0; i < threads; i++)
            bsp_query_destroy(workers[i].query);
    free(workers);
    free(tids);
    if (st != BSP_OK) {
        bsp_image_destroy(job.img);
        return st;
    }
    *out = job.img;
    return BSP_OK;
}
