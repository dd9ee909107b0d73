/*
 * test_kd_flux.c — sah-mixed's sampled model (src/accel/kd_flux.c,
 * src/accel/kd_prepass.c): the measure of boxes by a sample of ray
 * segments against counts made by hand, against the surface area for
 * uniformly distributed lines (Cauchy), its robustness to bad segments, and
 * the sampled sah-mixed tree: built from the pre-pass's rays, the same for
 * any thread count.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "accel/kd_cost.h"
#include "accel/kd_flux.h"
#include "accel/kd_prepass.h"
#include "accel/kd_tree.h"
#include "bspray/bspray.h"
#include "geom/vec.h"
#include "harness.h"

static bsp_box box(double x0, double y0, double z0, double x1, double y1, double z1)
{
    bsp_box b = {{{x0, y0, z0}}, {{x1, y1, z1}}};
    return b;
}

/* One segment along x through [0,4]^3 (4 x 4 x 4 unit voxels): every box
 * it runs through, voxel-aligned, is crossed once; boxes beside it never. */
TEST(flux_measure_counts_one_segment_by_hand)
{
    bsp_box root = box(0, 0, 0, 4, 4, 4);
    kd_flux_segment s = {{{-1, 1.5, 2.5}}, {{1, 0, 0}}, 0.0, 6.0};
    kd_flux f;
    bsp_error err;
    REQUIRE(kd_flux_build(&f, &root, &s, 1, 64, &err) == BSP_OK);
    CHECK_EQ_INT(f.n[0], 4);
    CHECK_EQ_INT(f.n[1], 4);
    CHECK_EQ_INT(f.n[2], 4);
    CHECK_NEAR(f.total, 1.0, 1e-12);
    bsp_box on = box(1, 1, 2, 2, 2, 3), slab = box(0, 1, 2, 4, 2, 3), tall = box(2, 0, 0, 3, 4, 4);
    CHECK_NEAR(kd_flux_measure(&f, &on), 1.0, 1e-12);
    CHECK_NEAR(kd_flux_measure(&f, &slab), 1.0, 1e-12);
    CHECK_NEAR(kd_flux_measure(&f, &tall), 1.0, 1e-12);
    bsp_box beside = box(1, 0, 0, 2, 1, 1), above = box(0, 2, 2, 4, 4, 4);
    CHECK_NEAR(kd_flux_measure(&f, &beside), 0.0, 1e-12);
    CHECK_NEAR(kd_flux_measure(&f, &above), 0.0, 1e-12);

    /* the same segment backwards, stopping half-way through voxel 2 on x: a
     * run of 0.5 there, so a face in that voxel sees half a crossing. A face
     * on a voxel boundary takes the density of the voxel above it (so the
     * two children of a split see the same density on their common face):
     * [3,4] has faces in voxel 3 (1, 1), [2,3] in voxels 2 and 3 (0.5, 1)
     * and the segment's end point (1),
     * [1,2] in voxels 1 and 2 (0, 0.5) */
    kd_flux_free(&f);
    kd_flux_segment back = {{{5, 1.5, 2.5}}, {{-2, 0, 0}}, 0.0, 1.25}; /* x from 5 to 2.5 */
    REQUIRE(kd_flux_build(&f, &root, &back, 1, 64, &err) == BSP_OK);
    bsp_box v3 = box(3, 1, 2, 4, 2, 3), v2 = box(2, 1, 2, 3, 2, 3), v1 = box(1, 1, 2, 2, 2, 3);
    CHECK_NEAR(kd_flux_measure(&f, &v3), 1.0, 1e-12);
    CHECK_NEAR(kd_flux_measure(&f, &v2), 1.25, 1e-12);
    CHECK_NEAR(kd_flux_measure(&f, &v1), 0.25, 1e-12);
    kd_flux_free(&f);
}

/* End points count: a segment meeting a box crosses its surface twice, or
 * once with one end inside, or has both ends inside — always one segment.
 * Boxes whose faces lie in voxels the segment does not reach measure that
 * exactly (crossings alone would give 1/2 and 0). */
TEST(flux_measure_counts_segments_that_start_or_end_inside)
{
    bsp_box root = box(0, 0, 0, 4, 4, 4);
    kd_flux f;
    bsp_error err;
    /* from the middle of voxel (2, 1, 2) along +x out of the grid */
    kd_flux_segment out = {{{2.5, 1.5, 2.5}}, {{1, 0, 0}}, 0.0, 10.0};
    REQUIRE(kd_flux_build(&f, &root, &out, 1, 64, &err) == BSP_OK);
    CHECK_NEAR(kd_flux_measure(&f, &(bsp_box){{{1, 1, 2}}, {{4, 2, 3}}}), 1.0, 1e-12);
    CHECK_NEAR(kd_flux_measure(&f, &(bsp_box){{{1, 0, 1}}, {{4, 3, 4}}}), 1.0, 1e-12);
    CHECK_NEAR(kd_flux_measure(&f, &(bsp_box){{{0, 1, 2}}, {{1, 2, 3}}}), 0.0, 1e-12);
    kd_flux_free(&f);
    /* wholly inside: from voxel (1, 1, 1) to voxel (2, 1, 1) */
    kd_flux_segment in = {{{1.5, 1.5, 1.5}}, {{1, 0, 0}}, 0.0, 1.0};
    REQUIRE(kd_flux_build(&f, &root, &in, 1, 64, &err) == BSP_OK);
    CHECK_NEAR(f.total, 1.0, 1e-12);
    CHECK_NEAR(kd_flux_measure(&f, &(bsp_box){{{0, 1, 1}}, {{4, 2, 2}}}), 1.0, 1e-12);
    CHECK_NEAR(kd_flux_measure(&f, &(bsp_box){{{0, 2, 1}}, {{4, 3, 2}}}), 0.0, 1e-12);
    kd_flux_free(&f);
}


/* Isotropic uniformly distributed lines (direction uniform on the sphere,
 * offset uniform on a disc around the box) hit a convex body in proportion
 * to its surface area (Cauchy): so does F, on boxes of the grid and off it. */
TEST(flux_measure_of_uniform_lines_is_the_surface_area)
{
    bsp_box root = box(-1, -2, 0, 3, 2, 2); /* 4 x 4 x 2 */
    enum { N = 200000 };
    static kd_flux_segment seg[N];
    uint64_t rng = 0x9e3779b97f4a7c15u;
    bsp_vec3 c = bsp_v3(1, 0, 1);
    double R = 3.1; /* > the half diagonal, 3 */
    for (int i = 0; i < N; i++) {
        double z = 2.0 * harness_xorshift_unit(&rng) - 1.0, phi = 2.0 * BSP_PI * harness_xorshift_unit(&rng);
        double rxy = sqrt(1.0 - z * z);
        bsp_vec3 d = bsp_v3(rxy * cos(phi), rxy * sin(phi), z);
        bsp_vec3 a = fabs(d.x) < 0.9 ? bsp_v3(1, 0, 0) : bsp_v3(0, 1, 0);
        bsp_vec3 u = v3_normalize(v3_cross(d, a)), v = v3_cross(d, u);
        double r = R * sqrt(harness_xorshift_unit(&rng)), th = 2.0 * BSP_PI * harness_xorshift_unit(&rng);
        bsp_vec3 p = v3_add(c, v3_add(v3_scale(u, r * cos(th)), v3_scale(v, r * sin(th))));
        seg[i] = (kd_flux_segment){v3_sub(p, v3_scale(d, 10.0)), d, 0.0, 20.0};
    }
    kd_flux f;
    bsp_error err;
    REQUIRE(kd_flux_build(&f, &root, seg, N, 4096, &err) == BSP_OK);
    const bsp_box boxes[] = {box(-1, -2, 0, 1, 2, 2), box(0, -1, 0.5, 2, 1, 1.5),
                             box(-1, -2, 0, 0.2, 0.3, 0.7), box(1.1, 0.4, 0.9, 2.6, 1.7, 1.3)};
    double sa_root = kd_surface_area(&root);
    for (size_t i = 0; i < sizeof boxes / sizeof boxes[0]; i++) {
        double want = kd_surface_area(&boxes[i]) / sa_root;
        double got = kd_flux_measure(&f, &boxes[i]) / f.total;
        CHECK_MSG(fabs(got - want) < 0.05 * want, "box %zu: F share %.4f, SA share %.4f", i, got,
                  want);
    }
    kd_flux_free(&f);
}

/* Segments that are not finite, miss the box or have no length add nothing;
 * an empty sample measures 0 everywhere. */
TEST(flux_ignores_bad_segments)
{
    bsp_box root = box(0, 0, 0, 1, 1, 1);
    kd_flux_segment bad[] = {
        {{{NAN, 0.5, 0.5}}, {{1, 0, 0}}, 0.0, 2.0},
        {{{-1, 0.5, 0.5}}, {{INFINITY, 0, 0}}, 0.0, 2.0},
        {{{-1, 0.5, 0.5}}, {{0, 0, 0}}, 0.0, 2.0},   /* no direction */
        {{{-1, 5.0, 0.5}}, {{1, 0, 0}}, 0.0, 2.0},   /* beside the box */
        {{{-1, 0.5, 0.5}}, {{1, 0, 0}}, 0.0, 0.5},   /* stops before it */
        {{{-1, 0.5, 0.5}}, {{1, 0, 0}}, 3.0, 2.0},   /* empty interval */
        {{{-1, 0.5, 0.5}}, {{1, 0, 0}}, NAN, 2.0},
    };
    kd_flux f;
    bsp_error err;
    REQUIRE(kd_flux_build(&f, &root, bad, sizeof bad / sizeof bad[0], 1000, &err) == BSP_OK);
    CHECK(f.total == 0.0);
    kd_flux_free(&f);
    /* a flat box (no extent on z) still gets a grid */
    bsp_box flat = box(0, 0, 1, 2, 2, 1);
    kd_flux_segment down = {{{0.5, 0.5, 2}}, {{0, 0, -1}}, 0.0, 5.0};
    REQUIRE(kd_flux_build(&f, &flat, &down, 1, 100, &err) == BSP_OK);
    CHECK_EQ_INT(f.n[2], 1);
    CHECK(isfinite(f.total));
    kd_flux_free(&f);
}

/* The pre-pass keeps one segment per non-primary ray of the render, each
 * ending at its ray's closest hit or tmax. */
TEST(flux_prepass_segments_are_the_renders_other_rays)
{
    bsp_scene *s = NULL;
    bsp_error err;
    REQUIRE(bsp_scene_load("spd:balls:1", &s, &err) == BSP_OK);
    bsp_camera cam = *bsp_scene_camera(s);
    cam.res_x = cam.res_y = 16;
    double share = 0.0;
    kd_flux_segment *seg = NULL;
    size_t n = 0;
    REQUIRE(kd_mixed_prepass(s, &cam, 4, 1, &share, &seg, &n, &err) == BSP_OK);
    /* share = 17^2 / all, so all - 17^2 other rays */
    double all = 17.0 * 17.0 / share;
    CHECK_NEAR((double)n, all - 17.0 * 17.0, 1e-6 * all);
    bsp_accel *naive = NULL;
    bsp_build_options bo;
    bsp_build_options_defaults(&bo);
    bo.kind = BSP_ACCEL_NAIVE;
    REQUIRE(bsp_accel_build(s, &bo, &naive, &err) == BSP_OK);
    bsp_query *q = bsp_query_create(naive);
    size_t wrong = 0;
    for (size_t i = 0; i < n; i += 7) {
        bsp_ray r = {seg[i].org, seg[i].dir, seg[i].t0, seg[i].t1};
        bsp_hit h;
        /* nothing closer than the segment's end, and the end is a hit or
         * the ray's own limit (shadow rays: the light; others: infinity) */
        r.tmax = nextafter(seg[i].t1, 0.0);
        wrong += bsp_intersect(naive, q, &r, &h) != 0;
    }
    CHECK_EQ_INT(wrong, 0);
    bsp_query_destroy(q);
    bsp_accel_destroy(naive);
    free(seg);
    bsp_scene_destroy(s);
}

/* The sampled sah-mixed tree: the pre-pass renders on one thread, so the
 * tree is the same for any number of build threads; it differs from the
 * surface model's. */
TEST(flux_sampled_mixed_tree_is_deterministic)
{
    bsp_scene *s = NULL;
    bsp_error err;
    REQUIRE(bsp_scene_load("spd:tree:3", &s, &err) == BSP_OK);
    bsp_build_options o;
    bsp_build_options_defaults(&o);
    o.kind = BSP_ACCEL_SAH_MIXED;
    o.mixed_model = BSP_MIXED_SAMPLED;
    o.mixed_check = 0; /* the sampled tree itself, whatever the check would keep */
    o.threads = 1;
    bsp_accel *a = NULL, *b = NULL, *c = NULL;
    REQUIRE(bsp_accel_build(s, &o, &a, &err) == BSP_OK);
    o.threads = 3;
    REQUIRE(bsp_accel_build(s, &o, &b, &err) == BSP_OK);
    o.mixed_model = BSP_MIXED_SURFACE;
    REQUIRE(bsp_accel_build(s, &o, &c, &err) == BSP_OK);
    const kd_tree *ta = a->impl, *tb = b->impl, *tc = c->impl;
    CHECK_EQ_INT(ta->nnodes, tb->nnodes);
    if (ta->nnodes == tb->nnodes)
        CHECK(memcmp(ta->nodes, tb->nodes, ta->nnodes * sizeof *ta->nodes) == 0);
    CHECK(ta->nnodes != tc->nnodes ||
          memcmp(ta->nodes, tc->nodes, ta->nnodes * sizeof *ta->nodes) != 0);
    CHECK(bsp_accel_check(a, &err) == BSP_OK);
    o.mixed_model = (bsp_mixed_model)7;
    bsp_accel *bad = NULL;
    CHECK(bsp_accel_build(s, &o, &bad, &err) == BSP_ERR_INVALID);
    CHECK_STR_CONTAINS(err.message, "model");
    bsp_accel_destroy(a);
    bsp_accel_destroy(b);
    bsp_accel_destroy(c);
    bsp_scene_destroy(s);
}
