/*
 * test_kd_raycount.c — sah-mixed's counted model (src/accel/kd_raycount.c)
 * and its check against sah (src/accel/kd_mixed_check.c): counts of the
 * segments meeting boxes against counts made by hand and against a brute
 * force written here, on a random descent of nested cells; the counted
 * tree the same for any thread count; the check keeping the tree it
 * measured cheaper, with the cost recomputed here from a render's rays.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "accel/accel_internal.h"
#include "accel/kd_cost.h"
#include "accel/kd_raycount.h"
#include "accel/kd_tree.h"
#include "bspray/bspray.h"
#include "geom/vec.h"
#include "harness.h"

static bsp_box box(double x0, double y0, double z0, double x1, double y1, double z1)
{
    bsp_box b = {{{x0, y0, z0}}, {{x1, y1, z1}}};
    return b;
}

static kd_flux_segment seg(double ox, double oy, double oz, double dx, double dy, double dz,
                           double t0, double t1)
{
    kd_flux_segment s = {{{ox, oy, oz}}, {{dx, dy, dz}}, t0, t1};
    return s;
}

TEST(raycount_counts_segments_by_hand)
{
    bsp_box root = box(0, 0, 0, 4, 4, 4);
    kd_flux_segment s[] = {
        seg(-1, 1.5, 2.5, 1, 0, 0, 0, 6),       /* a: along x, through the whole box */
        seg(2.5, 0.5, 0.5, 1, 0, 0, 0, 1),      /* b: inside, x from 2.5 to 3.5 */
        seg(-1, -1, -1, 1, 1, 1, 0, 10),        /* c: the diagonal x = y = z */
        seg(5, 5, 5, 1, 1, 1, 0, 1),            /* outside: not counted */
        seg(4, 2, 2, 1, 0, 0, 0, 1),            /* e: starts on the face x = 4 */
        seg(NAN, 0, 0, 1, 0, 0, 0, 1),          /* not finite: not counted */
        seg(1, 1, 1, 0, 0, 1, 0, INFINITY),     /* g: up from (1, 1, 1), unbounded */
    };
    kd_raycount rc;
    bsp_error err;
    REQUIRE(kd_raycount_init(&rc, &root, s, sizeof s / sizeof s[0], &err) == BSP_OK);
    CHECK_EQ_INT(rc.nseg, 5);
    kd_raycount_cursor c;
    kd_raycount_cursor_init(&c, &rc);
    REQUIRE(kd_raycount_enter(&c, &root));
    CHECK_EQ_INT(c.top, 0); /* the root itself: nothing new kept */
    bsp_box all = root, left = box(0, 0, 0, 2, 4, 4), right = box(2, 0, 0, 4, 4, 4),
            low = box(0, 0, 0, 4, 1, 4);
    CHECK_NEAR(kd_raycount_measure(&c, &all), 5.0, 0.0);
    CHECK_NEAR(kd_raycount_measure(&c, &left), 3.0, 0.0);  /* a, c, g */
    CHECK_NEAR(kd_raycount_measure(&c, &right), 4.0, 0.0); /* a, b, c, e */
    CHECK_NEAR(kd_raycount_measure(&c, &low), 3.0, 0.0);   /* b, c, g (g starts at y = 1) */

    /* inside the right half the diagonal runs at z >= 2 */
    REQUIRE(kd_raycount_enter(&c, &right));
    CHECK_EQ_INT(c.top, 1);
    CHECK_EQ_INT(c.cells[0].n, 4);
    bsp_box bottom = box(2, 0, 0, 4, 4, 1), top = box(2, 0, 3, 4, 4, 4);
    CHECK_NEAR(kd_raycount_measure(&c, &bottom), 1.0, 0.0); /* b */
    CHECK_NEAR(kd_raycount_measure(&c, &top), 1.0, 0.0);    /* c */
    /* two faces moved: counted part by part */
    bsp_box corner = box(2, 0, 0, 3, 1, 4);
    CHECK_NEAR(kd_raycount_measure(&c, &corner), 1.0, 0.0); /* b */
    /* a box outside the kept cell is counted from the root */
    bsp_box column = box(0.5, 0.5, 3, 1.5, 1.5, 4);
    CHECK_NEAR(kd_raycount_measure(&c, &column), 1.0, 0.0); /* g */
    /* entering the left half drops the right one */
    REQUIRE(kd_raycount_enter(&c, &left));
    CHECK_EQ_INT(c.top, 1);
    CHECK_EQ_INT(c.cells[0].n, 3);
    kd_raycount_reset(&c);
    CHECK_EQ_INT(c.top, 0);
    CHECK_NEAR(kd_raycount_measure(&c, &right), 4.0, 0.0);
    kd_raycount_cursor_free(&c);
    kd_raycount_free(&rc);
}

static uint64_t rng;
static double urand(void)
{
    return harness_xorshift_unit(&rng);
}

/* Whether the segment S meets box B: an independent brute force, by
 * bisection-free interval arithmetic on each axis in turn — the t-interval
 * where the point's coordinate lies in [lo, hi], written with comparisons of
 * coordinates at the interval's ends. */
static int brute_meets(const kd_flux_segment *s, const bsp_box *b)
{
    double a = s->t0, e = s->t1;
    const double o[3] = {s->org.x, s->org.y, s->org.z}, d[3] = {s->dir.x, s->dir.y, s->dir.z};
    for (int k = 0; k < 3 && a <= e; k++) {
        if (d[k] == 0.0) {
            if (o[k] < b->lo.v[k] || o[k] > b->hi.v[k])
                return 0;
            continue;
        }
        double enter = ((d[k] > 0 ? b->lo.v[k] : b->hi.v[k]) - o[k]) / d[k];
        double leave = ((d[k] > 0 ? b->hi.v[k] : b->lo.v[k]) - o[k]) / d[k];
        a = fmax(a, enter);
        e = fmin(e, leave);
    }
    return a <= e;
}

static double brute_count(const kd_flux_segment *s, size_t n, const bsp_box *b)
{
    size_t c = 0;
    for (size_t i = 0; i < n; i++)
        c += (size_t)brute_meets(&s[i], b);
    return (double)c;
}

/* Random segments (a third axis-aligned, some with one zero component, some
 * starting inside), a random descent of nested cells, and at every level
 * the counts of the two children of random planes on every axis. */
TEST(raycount_matches_a_brute_force_down_random_descents)
{
    enum { NSEG = 3000 };
    kd_flux_segment *s = malloc(NSEG * sizeof *s);
    REQUIRE(s);
    rng = 0x5eedULL;
    bsp_box root = box(-2, -1, 0, 6, 3, 2);
    for (int i = 0; i < NSEG; i++) {
        bsp_vec3 o = bsp_v3(-4 + 12 * urand(), -3 + 8 * urand(), -2 + 6 * urand());
        bsp_vec3 d = bsp_v3(urand() - 0.5, urand() - 0.5, urand() - 0.5);
        if (i % 3 == 0) { /* axis-aligned */
            int k = i % 9 / 3;
            d = bsp_v3(0, 0, 0);
            d.v[k] = urand() < 0.5 ? -1 : 1;
        } else if (i % 5 == 0) {
            d.v[i % 3] = 0.0;
        }
        double t0 = i % 7 == 0 ? 0.3 : 0.0, t1 = i % 11 == 0 ? INFINITY : 4 + 20 * urand();
        s[i] = (kd_flux_segment){o, d, t0, t1};
    }
    kd_raycount rc;
    bsp_error err;
    REQUIRE(kd_raycount_init(&rc, &root, s, NSEG, &err) == BSP_OK);
    CHECK_NEAR((double)rc.nseg, brute_count(s, NSEG, &root), 0.0);
    kd_raycount_cursor c;
    kd_raycount_cursor_init(&c, &rc);
    int bad = 0;
    for (int descent = 0; descent < 20 && !bad; descent++) {
        bsp_box cell = root;
        for (int level = 0; level < 12 && !bad; level++) {
            REQUIRE(kd_raycount_enter(&c, &cell));
            double nv = kd_raycount_measure(&c, &cell);
            bad += nv != brute_count(s, NSEG, &cell);
            for (int k = 0; k < 3; k++) {
                double p = cell.lo.v[k] + (cell.hi.v[k] - cell.lo.v[k]) * urand();
                bsp_box l = cell, r = cell;
                l.hi.v[k] = p;
                r.lo.v[k] = p;
                double nl = kd_raycount_measure(&c, &l), nr = kd_raycount_measure(&c, &r);
                double bl = brute_count(s, NSEG, &l), br = brute_count(s, NSEG, &r);
                CHECK_MSG(nl == bl && nr == br,
                          "descent %d level %d axis %d: counted %g, %g; brute force %g, %g",
                          descent, level, k, nl, nr, bl, br);
                bad += nl != bl || nr != br;
                CHECK(nl + nr >= nv && nl <= nv && nr <= nv); /* covering, monotone */
            }
            /* a box with two faces moved, counted part by part */
            bsp_box q = cell;
            q.lo.v[0] += 0.25 * (cell.hi.v[0] - cell.lo.v[0]);
            q.hi.v[1] -= 0.25 * (cell.hi.v[1] - cell.lo.v[1]);
            bad += kd_raycount_measure(&c, &q) != brute_count(s, NSEG, &q);
            /* down into a random child */
            int k = (int)(3 * urand()) % 3;
            double p = cell.lo.v[k] + (cell.hi.v[k] - cell.lo.v[k]) * (0.2 + 0.6 * urand());
            if (urand() < 0.5)
                cell.hi.v[k] = p;
            else
                cell.lo.v[k] = p;
        }
    }
    CHECK_EQ_INT(bad, 0);
    kd_raycount_cursor_free(&c);
    kd_raycount_free(&rc);
    free(s);
}

static bsp_accel *build_mixed(const bsp_scene *s, bsp_mixed_model model, int check, int threads)
{
    bsp_build_options o;
    bsp_build_options_defaults(&o);
    o.kind = BSP_ACCEL_SAH_MIXED;
    o.mixed_model = model;
    o.mixed_check = check;
    o.threads = threads;
    bsp_accel *a = NULL;
    bsp_error err;
    if (bsp_accel_build(s, &o, &a, &err) != BSP_OK)
        return NULL;
    return a;
}

static int same_tree(const bsp_accel *a, const bsp_accel *b)
{
    const kd_tree *ta = a->impl, *tb = b->impl;
    return ta->nnodes == tb->nnodes && ta->nprims == tb->nprims &&
           memcmp(ta->nodes, tb->nodes, ta->nnodes * sizeof *ta->nodes) == 0 &&
           memcmp(ta->prims, tb->prims, ta->nprims * sizeof *ta->prims) == 0;
}

/* The counted tree: the same node array for any number of build threads
 * (each parallel task starts from the root's parts), and not the surface
 * model's; it passes the tree invariants. */
TEST(raycount_mixed_tree_is_deterministic)
{
    bsp_scene *s = NULL;
    bsp_error err;
    REQUIRE(bsp_scene_load("spd:balls:3", &s, &err) == BSP_OK);
    bsp_accel *a = build_mixed(s, BSP_MIXED_COUNTED, 0, 1), *b = build_mixed(s, BSP_MIXED_COUNTED, 0, 3),
              *c = build_mixed(s, BSP_MIXED_SURFACE, 0, 1);
    REQUIRE(a && b && c);
    CHECK(same_tree(a, b));
    CHECK(!same_tree(a, c));
    CHECK(bsp_accel_check(a, &err) == BSP_OK);
    bsp_mixed_check chk;
    bsp_accel_mixed_check(a, &chk);
    CHECK_EQ_INT(chk.ran, 0); /* the check was off */
    bsp_accel_destroy(a);
    bsp_accel_destroy(b);
    bsp_accel_destroy(c);
    bsp_scene_destroy(s);
}

typedef struct logged {
    bsp_ray *rays;
    int *cls;
    uint32_t *from;
    size_t n, cap;
} logged;

static void log_ray(bsp_ray_class cls, const bsp_ray *ray, uint32_t from, void *ctx)
{
    logged *l = ctx;
    if (l->n == l->cap) {
        l->cap = l->cap ? 2 * l->cap : 1024;
        l->rays = realloc(l->rays, l->cap * sizeof *l->rays);
        l->cls = realloc(l->cls, l->cap * sizeof *l->cls);
        l->from = realloc(l->from, l->cap * sizeof *l->from);
    }
    l->rays[l->n] = *ray;
    l->from[l->n] = from;
    l->cls[l->n++] = (int)cls;
}

/* What sah-mixed's check should find for the tree A built with options O:
 * the cost per ray, C_trav steps + mean T_i tests + T_mb mailbox hits, of
 * the rays of a 64 x 64 render of the scene's camera, recomputed here from
 * the render's logged rays (RAYS: how many the check shot). */
static double check_cost(const bsp_scene *s, const bsp_accel *a, const bsp_build_options *o,
                         uint64_t rays)
{
    logged l = {0};
    bsp_camera cam = *bsp_scene_camera(s);
    cam.res_x = cam.res_y = 63;
    bsp_render_options ro;
    bsp_render_options_defaults(&ro);
    ro.camera = &cam;
    ro.threads = 1;
    ro.ray_log = log_ray;
    ro.ray_log_ctx = &l;
    bsp_image *img = NULL;
    bsp_error err;
    REQUIRE(bsp_render(a, &ro, &img, NULL, &err) == BSP_OK);
    bsp_image_destroy(img);
    CHECK_EQ_INT(rays, l.n);
    bsp_query *q = bsp_query_create(a);
    for (size_t i = 0; i < l.n; i++) {
        bsp_hit h;
        if (l.cls[i] == BSP_RAY_SHADOW)
            bsp_occluded_from(a, q, &l.rays[i], l.from[i]);
        else
            bsp_intersect_from(a, q, &l.rays[i], l.from[i], &h);
    }
    const bsp_query_counters *qc = bsp_query_get_counters(q);
    double tsum = 0.0;
    size_t live = 0;
    for (uint32_t p = 0; p < bsp_scene_prim_count(s); p++)
        if (s->prims[p].shape != SHAPE_NONE) {
            tsum += kd_prim_cost(s, p, &o->sah_costs);
            live++;
        }
    double steps = (double)qc->traversal_steps * o->sah_costs.traversal;
    double cost = (steps + tsum / (double)live * (double)qc->isect_tests +
                   KD_MAILBOX_HIT_COST * o->sah_costs.traversal * (double)qc->mailbox_hits) /
                  (double)l.n;
    bsp_query_destroy(q);
    free(l.rays);
    free(l.cls);
    free(l.from);
    return cost;
}

/* The check keeps the tree it measured cheaper: that tree's node array is
 * the plain sah build's or the unchecked sah-mixed build's, and the sah
 * tree's cost is what a 64 x 64 render of the scene's camera costs on it,
 * recomputed here from the render's logged rays. */
TEST(mixed_check_keeps_the_tree_it_measured_cheaper)
{
    const char *scenes[] = {"spd:tree:3", "spd:balls:2"};
    const bsp_mixed_model models[] = {BSP_MIXED_SURFACE, BSP_MIXED_COUNTED};
    for (size_t si = 0; si < 2; si++) {
        bsp_scene *s = NULL;
        bsp_error err;
        REQUIRE(bsp_scene_load(scenes[si], &s, &err) == BSP_OK);
        for (size_t mi = 0; mi < 2; mi++) {
            bsp_accel *checked = build_mixed(s, models[mi], 1, 0),
                      *mixed = build_mixed(s, models[mi], 0, 0);
            bsp_build_options so;
            bsp_build_options_defaults(&so);
            bsp_accel *sah = NULL;
            REQUIRE(checked && mixed && bsp_accel_build(s, &so, &sah, &err) == BSP_OK);
            bsp_mixed_check chk;
            bsp_accel_mixed_check(checked, &chk);
            CHECK(chk.ran);
            CHECK_EQ_INT(chk.kept_sah, chk.cost_sah < chk.cost_mixed);
            CHECK_MSG(same_tree(checked, chk.kept_sah ? sah : mixed), "%s: kept %s", scenes[si],
                      chk.kept_sah ? "sah" : "sah-mixed");

            CHECK_NEAR(chk.cost_sah, check_cost(s, sah, &so, chk.rays), 1e-9 * chk.cost_sah);
            bsp_accel_destroy(checked);
            bsp_accel_destroy(mixed);
            bsp_accel_destroy(sah);
        }
        bsp_scene_destroy(s);
    }
}

/* The check charges the mailbox hits of a tree built by the plain model
 * (--straddle twice) too: the traversal looks them up whatever charge the
 * builder made (it used to leave them out with the model's term). */
TEST(mixed_check_charges_mailbox_hits_with_the_plain_model)
{
    bsp_scene *s = NULL;
    bsp_error err;
    REQUIRE(bsp_scene_load("spd:balls:2", &s, &err) == BSP_OK);
    bsp_build_options o;
    bsp_build_options_defaults(&o);
    o.kind = BSP_ACCEL_SAH_MIXED;
    o.sah_straddle_twice = 1;
    bsp_accel *checked = NULL, *sah = NULL;
    REQUIRE(bsp_accel_build(s, &o, &checked, &err) == BSP_OK);
    bsp_build_options so = o;
    so.kind = BSP_ACCEL_SAH;
    REQUIRE(bsp_accel_build(s, &so, &sah, &err) == BSP_OK);
    bsp_mixed_check chk;
    bsp_accel_mixed_check(checked, &chk);
    CHECK(chk.ran);
    double want = check_cost(s, sah, &so, chk.rays);
    CHECK_NEAR(chk.cost_sah, want, 1e-9 * want);
    bsp_accel_destroy(checked);
    bsp_accel_destroy(sah);
    bsp_scene_destroy(s);
}
