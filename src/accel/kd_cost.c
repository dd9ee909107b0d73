/*
 * kd_cost.c — the cost model of the SAH builders (MacDonald & Booth 1990):
 * default per-kind intersection costs T_i relative to one traversal step
 * C_trav, their resolution from build options, the surface-area measure, and
 * bsp_calibrate_costs, which measures the costs on the running machine
 * (after Mitsuba's findCosts, which fits them to timings of random rays).
 *
 * Calibration: the shapes of each kind are set up directly (the code of
 * src/geom, as the traversal calls it) at random in the unit cube, and 512
 * rays from random points of [-1, 2]^3 aimed at random points of the unit
 * cube are tested against every one of them; the best of several rounds,
 * timed in thread CPU time, gives ns per test. Polygons are regular n-gons for several n, fitted
 * by least squares to base + vertex * n. A traversal step is measured in
 * place: the same rays through Kaplan trees of several depths over tiny
 * spheres, the time per ray fitted by least squares to
 * a + steps * C_trav + tests * C_sphere; the in-tree sphere cost over the
 * isolated one (cold caches) then scales every kind.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "accel/kd_cost.h"
#include "geom/vec.h"

/*
 * Defaults, in units of one traversal step (C_trav = 1). Measured with
 * bsp_calibrate_costs (`bspray calibrate`) on the development machine (a
 * 2-core Intel Xeon VM shared with other jobs, gcc -O2) on 2026-11-22 when
 * the SAH builder was written: the median over 12 runs of each cost's ratio
 * to the traversal step. Median absolute figures: traversal step 13 ns,
 * sphere 9 ns, triangle 34 ns (Moeller-Trumbore's sign tests mispredict on
 * incoherent rays), polygon 22 + 2.5 n ns, cone 23 ns; single runs varied
 * by up to +-50 % under the machine's load, the ratios by less.
 *
 * Except the triangle's: calibrated 2.57, set to 1.2 from render timings
 * (session 10). Trees of the six triangle scenes built with 0.8-2.2 were
 * timed against the 2.57 trees on the same rays of a 513 x 513 depth-4
 * render, in alternating slices in one process (docs/kdtree.md): at 1.2,
 * +3 to +7 % rays per second on mount, teapot, tetra, sample and nurbtst,
 * sombrero unchanged, and 14-61 % fewer leaves. In a render a triangle test
 * is independent arithmetic that overlaps the descent, whose steps wait on
 * each other's loads; the isolated tests of the calibration cannot show it.
 * Spheres and cones measured no better either way (shells gains from dearer
 * spheres, balls and rings lose).
 */
#define T_SPHERE 0.67
#define T_TRIANGLE 1.2
#define T_POLYGON_BASE 1.58
#define T_POLYGON_VERTEX 0.185
#define T_CONE 2.0

void kd_cost_defaults(bsp_sah_costs *c)
{
    c->traversal = 1.0;
    c->sphere = T_SPHERE;
    c->triangle = T_TRIANGLE;
    c->polygon_base = T_POLYGON_BASE;
    c->polygon_vertex = T_POLYGON_VERTEX;
    c->cone = T_CONE;
}

/* V, or D when V is not a positive finite number; clamped to the range the
 * sums of the cost model stay exact in. */
static double or_default(double v, double d)
{
    double x = v > 0.0 && isfinite(v) ? v : d;
    return x < BSP_SAH_COST_MIN ? BSP_SAH_COST_MIN : x > BSP_SAH_COST_MAX ? BSP_SAH_COST_MAX : x;
}

void kd_cost_resolve(const bsp_build_options *o, kd_cost_model *m)
{
    bsp_sah_costs d;
    kd_cost_defaults(&d);
    const bsp_sah_costs *c = &o->sah_costs;
    m->c.traversal = or_default(c->traversal, d.traversal);
    m->c.sphere = or_default(c->sphere, d.sphere);
    m->c.triangle = or_default(c->triangle, d.triangle);
    m->c.polygon_base = or_default(c->polygon_base, d.polygon_base);
    m->c.polygon_vertex = or_default(c->polygon_vertex, d.polygon_vertex);
    m->c.cone = or_default(c->cone, d.cone);
    double b = o->sah_empty_bonus;
    if (b == 0.0 || !isfinite(b))
        b = KD_DEFAULT_EMPTY_BONUS;
    else if (b < 0.0)
        b = 0.0;
    else if (b > 0.99)
        b = 0.99;
    m->empty_bonus = b;
    double ms = o->sah_min_saving;
    if (ms == 0.0 || !isfinite(ms))
        ms = KD_DEFAULT_MIN_SAVING;
    else if (ms < 0.0)
        ms = 0.0;
    m->min_saving = ms;
    double lb = o->sah_leaf_budget;
    if (lb == 0.0 || !isfinite(lb))
        lb = KD_DEFAULT_LEAF_BUDGET;
    m->leaf_budget = lb > 0.0 ? lb : 0.0;
    m->leaf_budget_min =
        o->sah_leaf_budget_min ? o->sah_leaf_budget_min : KD_DEFAULT_LEAF_BUDGET_MIN;
    double bc = o->sah_budget_cut;
    if (bc == 0.0 || isnan(bc))
        bc = KD_DEFAULT_BUDGET_CUT;
    m->budget_cut = bc > 0.0 ? fmin(bc, 1e6) : 0.0;
    /* not O->mailbox: the mailbox term's trees are faster without mailboxes
     * too (shells 2.6x; docs/kdtree-log.md, "Session 25") */
    m->mailbox_term = !o->sah_straddle_twice;
    m->mailbox_hit = KD_MAILBOX_HIT_COST * m->c.traversal;
}

double kd_prim_cost(const bsp_scene *scene, uint32_t prim, const bsp_sah_costs *c)
{
    const prim_record *p = &scene->prims[prim];
    switch ((shape_kind)p->shape) {
    case SHAPE_SPHERE:
        return c->sphere;
    case SHAPE_TRIANGLE:
        return c->triangle;
    case SHAPE_POLYGON:
        return c->polygon_base +
               c->polygon_vertex *
                   (double)polygon_test_units(&scene->polygons[p->slot], &scene->slabs);
    case SHAPE_CONE:
        return c->cone;
    case SHAPE_NONE:
        break;
    }
    return 0.0;
}

double kd_area_surface(const bsp_box *box, const void *ctx)
{
    (void)ctx;
    return kd_surface_area(box);
}

/* --- calibration ------------------------------------------------------------------ */

#define CAL_RAYS 512
#define CAL_SHAPES 256
#define CAL_ROUNDS 5
#define CAL_MIN_SECONDS 0.02

static double urand(uint64_t *s)
{
    *s ^= *s >> 12;
    *s ^= *s << 25;
    *s ^= *s >> 27;
    return (double)((*s * 2685821657736338717ULL) >> 11) * (1.0 / 9007199254740992.0);
}

static bsp_vec3 vrand(uint64_t *s, double lo, double hi)
{
    double x = lo + (hi - lo) * urand(s), y = lo + (hi - lo) * urand(s);
    return bsp_v3(x, y, lo + (hi - lo) * urand(s));
}

typedef struct cal_set {
    shape_kind kind;
    size_t n;
    const sphere_shape *spheres;
    const triangle_shape *triangles;
    const polygon_shape *polygons;
    const bsp_vec3 *verts;
    const cone_shape *cones;
} cal_set;

/* One pass of every ray against every shape; returns the number of hits. */
static size_t cal_pass(const cal_set *cs, const bsp_ray *rays)
{
    size_t hits = 0;
    double t, u, v;
    for (size_t r = 0; r < CAL_RAYS; r++) {
        const bsp_ray *ray = &rays[r];
        switch (cs->kind) {
        case SHAPE_SPHERE:
            for (size_t i = 0; i < cs->n; i++)
                hits += (size_t)sphere_intersect(&cs->spheres[i], ray, &t);
            break;
        case SHAPE_TRIANGLE:
            for (size_t i = 0; i < cs->n; i++)
                hits += (size_t)triangle_intersect(&cs->triangles[i], ray, &t, &u, &v);
            break;
        case SHAPE_POLYGON:
            for (size_t i = 0; i < cs->n; i++)
                hits += (size_t)polygon_intersect(&cs->polygons[i], cs->verts, NULL, ray, &t);
            break;
        case SHAPE_CONE:
            for (size_t i = 0; i < cs->n; i++)
                hits += (size_t)cone_intersect(&cs->cones[i], ray, &t);
            break;
        case SHAPE_NONE:
            break;
        }
    }
    return hits;
}

/* where the timed loops' results go, so that they are not optimised away; one
 * per thread, since calibrations may run on several threads at once */
static _Thread_local volatile size_t cal_sink;

/* Seconds of CPU time of this thread: unlike wall time, not inflated while
 * other processes run. */
static double cpu_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* ns per ray-shape test: the best of CAL_ROUNDS rounds of at least
 * CAL_MIN_SECONDS each. */
static double cal_time(const cal_set *cs, const bsp_ray *rays)
{
    double best = INFINITY;
    for (int round = 0; round < CAL_ROUNDS; round++) {
        size_t passes = 0, hits = 0;
        double t0 = cpu_now(), el;
        do {
            hits += cal_pass(cs, rays);
            passes++;
            el = cpu_now() - t0;
        } while (el < CAL_MIN_SECONDS);
        cal_sink += hits;
        double ns = el * 1e9 / ((double)passes * CAL_RAYS * (double)cs->n);
        if (ns < best)
            best = ns;
    }
    return best;
}

/* A random unit vector and two unit vectors perpendicular to it. */
static void frame(uint64_t *s, bsp_vec3 *n, bsp_vec3 *a, bsp_vec3 *b)
{
    bsp_vec3 d;
    do
        d = vrand(s, -1, 1);
    while (v3_dot(d, d) < 0.01 || v3_dot(d, d) > 1);
    *n = v3_normalize(d);
    bsp_vec3 h = fabs(n->x) < 0.9 ? bsp_v3(1, 0, 0) : bsp_v3(0, 1, 0);
    *a = v3_normalize(v3_cross(*n, h));
    *b = v3_cross(*n, *a);
}

/* Solves the 3 x 3 system M x = V (Cramer); 0 when singular. */
static int solve3(double m[3][3], const double v[3], double x[3])
{
    double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
                 m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                 m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    if (!(fabs(det) > 0.0))
        return 0;
    for (int c = 0; c < 3; c++) {
        double t[3][3];
        memcpy(t, m, sizeof t);
        for (int r = 0; r < 3; r++)
            t[r][c] = v[r];
        x[c] = (t[0][0] * (t[1][1] * t[2][2] - t[1][2] * t[2][1]) -
                t[0][1] * (t[1][0] * t[2][2] - t[1][2] * t[2][0]) +
                t[0][2] * (t[1][0] * t[2][1] - t[1][1] * t[2][0])) /
               det;
    }
    return 1;
}

/* The traversal step and the sphere test as they cost inside the
 * traversal (cache misses included): Kaplan trees of several depths over
 * tiny spheres, the same rays through each, and a least-squares fit of the
 * time per ray to a + steps * C_trav + tests * C_sphere. */
static bsp_status cal_traversal(double *ns_trav, double *ns_sphere, bsp_error *err)
{
    enum { NRAYS = 4096, NCONF = 6 };
    static const int depth[NCONF] = {4, 7, 10, 13, 16, 20};
    bsp_scene *sc = bsp_scene_create();
    bsp_ray *rays = malloc(NRAYS * sizeof *rays);
    if (!sc || !rays) {
        bsp_scene_destroy(sc);
        free(rays);
        return error_set(err, BSP_ERR_NOMEM, NULL, 0, "out of memory");
    }
    uint64_t s = 0x5eed5eedULL;
    bsp_status st = BSP_OK;
    for (int i = 0; i < 4000 && st == BSP_OK; i++)
        st = bsp_scene_add_sphere(sc, vrand(&s, 0, 1), 0.004, err);
    for (int r = 0; r < NRAYS; r++) {
        rays[r].org = vrand(&s, -1, 2);
        rays[r].dir = v3_sub(vrand(&s, 0, 1), rays[r].org);
        rays[r].tmin = 0;
        rays[r].tmax = INFINITY;
    }
    double m[3][3] = {{0}}, v[3] = {0};
    for (int c = 0; c < NCONF && st == BSP_OK; c++) {
        bsp_accel *a = NULL;
        bsp_build_options o;
        bsp_build_options_defaults(&o);
        o.kind = BSP_ACCEL_KAPLAN;
        o.max_depth = depth[c];
        o.max_leaf_prims = 1;
        st = bsp_accel_build(sc, &o, &a, err);
        bsp_query *q = a ? bsp_query_create(a) : NULL;
        if (st == BSP_OK && !q)
            st = error_set(err, BSP_ERR_NOMEM, NULL, 0, "out of memory");
        if (st == BSP_OK) {
            double best = INFINITY, steps = 0, tests = 0;
            for (int round = 0; round < CAL_ROUNDS; round++) {
                size_t passes = 0, hits = 0;
                double t0 = cpu_now(), el;
                do {
                    bsp_query_reset_counters(q);
                    for (int r = 0; r < NRAYS; r++) {
                        bsp_hit h;
                        hits += (size_t)bsp_intersect(a, q, &rays[r], &h);
                    }
                    passes++;
                    el = cpu_now() - t0;
                } while (el < CAL_MIN_SECONDS);
                cal_sink += hits;
                const bsp_query_counters *qc = bsp_query_get_counters(q);
                steps = (double)qc->traversal_steps / NRAYS;
                tests = (double)qc->isect_tests / NRAYS;
                double ns = el * 1e9 / ((double)passes * NRAYS);
                best = ns < best ? ns : best;
            }
            double x[3] = {1.0, steps, tests};
            for (int i = 0; i < 3; i++) {
                for (int j = 0; j < 3; j++)
                    m[i][j] += x[i] * x[j];
                v[i] += x[i] * best;
            }
        }
        bsp_query_destroy(q);
        bsp_accel_destroy(a);
    }
    double x[3];
    if (st == BSP_OK) {
        if (!solve3(m, v, x) || !(x[1] > 0.0) || !(x[2] > 0.0))
            st = error_set(err, BSP_ERR_INVALID, NULL, 0,
                           "calibration: the timings did not fit (a busy machine?)");
        else {
            *ns_trav = x[1];
            *ns_sphere = x[2];
        }
    }
    bsp_scene_destroy(sc);
    free(rays);
    return st;
}

bsp_status bsp_calibrate_costs(bsp_sah_costs *ns, bsp_error *err)
{
    enum { NPOLY = 5 };
    static const uint32_t poly_n[NPOLY] = {4, 8, 16, 32, 64};
    bsp_ray *rays = malloc(CAL_RAYS * sizeof *rays);
    sphere_shape *sp = malloc(CAL_SHAPES * sizeof *sp);
    triangle_shape *tr = malloc(CAL_SHAPES * sizeof *tr);
    cone_shape *co = malloc(CAL_SHAPES * sizeof *co);
    polygon_shape *pg = malloc(CAL_SHAPES * sizeof *pg);
    bsp_vec3 *verts = malloc((size_t)CAL_SHAPES * 64 * sizeof *verts);
    bsp_status st = BSP_OK;
    if (!rays || !sp || !tr || !co || !pg || !verts) {
        st = error_set(err, BSP_ERR_NOMEM, NULL, 0, "out of memory");
        goto done;
    }
    uint64_t s = 0xca1b7a7eULL;
    for (int r = 0; r < CAL_RAYS; r++) {
        rays[r].org = vrand(&s, -1, 2);
        rays[r].dir = v3_sub(vrand(&s, 0, 1), rays[r].org);
        rays[r].tmin = 0;
        rays[r].tmax = INFINITY;
    }
    size_t n = 0;
    while (n < CAL_SHAPES)
        n += (size_t)sphere_setup(&sp[n], vrand(&s, 0, 1), 0.02 + 0.08 * urand(&s));
    for (n = 0; n < CAL_SHAPES;) {
        bsp_vec3 c = vrand(&s, 0, 1);
        n += (size_t)triangle_setup(&tr[n], v3_add(c, vrand(&s, -.1, .1)),
                                    v3_add(c, vrand(&s, -.1, .1)), v3_add(c, vrand(&s, -.1, .1)),
                                    SHAPE_NO_NORMALS);
    }
    for (n = 0; n < CAL_SHAPES;) {
        bsp_vec3 b = vrand(&s, 0, 1);
        n += (size_t)cone_setup(&co[n], b, 0.02 + 0.05 * urand(&s),
                                v3_add(b, vrand(&s, -.15, .15)), 0.05 * urand(&s));
    }
    cal_set cs = {SHAPE_SPHERE, CAL_SHAPES, sp, tr, pg, verts, co};
    memset(ns, 0, sizeof *ns);
    ns->sphere = cal_time(&cs, rays);
    cs.kind = SHAPE_TRIANGLE;
    ns->triangle = cal_time(&cs, rays);
    cs.kind = SHAPE_CONE;
    ns->cone = cal_time(&cs, rays);

    /* polygons: regular n-gons in random planes; least squares t = a + b n */
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    cs.kind = SHAPE_POLYGON;
    for (int j = 0; j < NPOLY; j++) {
        uint32_t nv = poly_n[j];
        for (n = 0; n < CAL_SHAPES;) {
            bsp_vec3 c = vrand(&s, 0, 1), nn, ea, eb;
            frame(&s, &nn, &ea, &eb);
            double rad = 0.05 + 0.05 * urand(&s);
            uint32_t first = (uint32_t)(n * 64);
            for (uint32_t i = 0; i < nv; i++) {
                double ang = 2 * BSP_PI * i / nv;
                verts[first + i] = v3_madd(v3_madd(c, ea, rad * cos(ang)), eb, rad * sin(ang));
            }
            n += (size_t)polygon_setup(&pg[n], verts, first, nv, SHAPE_NO_NORMALS);
        }
        double y = cal_time(&cs, rays);
        sx += nv;
        sy += y;
        sxx += (double)nv * nv;
        sxy += nv * y;
    }
    double slope = (NPOLY * sxy - sx * sy) / (NPOLY * sxx - sx * sx);
    ns->polygon_vertex = slope > 0.01 ? slope : 0.01;
    ns->polygon_base = (sy - slope * sx) / NPOLY;
    if (!(ns->polygon_base > 0.01))
        ns->polygon_base = 0.01;
    /* in the traversal a test also fetches its primitive from a cold cache:
     * scale every kind by the in-traversal / isolated ratio of the sphere */
    double sphere_in_tree = 0.0;
    /* the fit can fail on a busy machine: try again a few times */
    for (int attempt = 0; attempt < 3; attempt++) {
        st = cal_traversal(&ns->traversal, &sphere_in_tree, err);
        if (st != BSP_ERR_INVALID)
            break;
    }
    if (st == BSP_OK) {
        double f = sphere_in_tree / ns->sphere;
        f = f > 1.0 ? f : 1.0;
        ns->sphere *= f;
        ns->triangle *= f;
        ns->polygon_base *= f;
        ns->polygon_vertex *= f;
        ns->cone *= f;
    }
done:
    free(rays);
    free(sp);
    free(tr);
    free(co);
    free(pg);
    free(verts);
    return st;
}
