/*
 * test_render.c — the Whitted renderer: camera geometry of both sampling
 * conventions, shadows, determinism across thread counts, and ray statistics
 * on scenes whose counts can be worked out by hand.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bspray/bspray.h"
#include "geom/vec.h"
#include "harness.h"
#include "render/camera.h"

static bsp_camera make_camera(bsp_vec3 from, bsp_vec3 at, bsp_vec3 up, double angle, int res)
{
    bsp_camera c;
    memset(&c, 0, sizeof c);
    c.from = from;
    c.at = at;
    c.up = up;
    c.angle_deg = angle;
    c.hither = 1;
    c.res_x = c.res_y = res;
    return c;
}

static double angle_between(bsp_vec3 a, bsp_vec3 b)
{
    return acos(v3_dot(v3_normalize(a), v3_normalize(b))) * 180.0 / BSP_PI;
}

TEST(camera_spd_corner_rays_span_the_angle)
{
    bsp_camera c = make_camera(bsp_v3(0, 0, 10), bsp_v3(0, 0, 0), bsp_v3(0, 1, 0), 45, 512);
    int w, h;
    camera_default_size(&c, BSP_SAMPLING_SPD, &w, &h);
    CHECK_EQ_INT(w, 513);
    CHECK_EQ_INT(h, 513);
    camera_rays cr;
    camera_rays_init(&cr, &c, w, h, BSP_SAMPLING_SPD, 0.0);
    /* first and last ray of the middle row are 45 degrees apart */
    bsp_ray left = camera_ray(&cr, 0, 256), right = camera_ray(&cr, 512, 256);
    CHECK_NEAR(angle_between(left.dir, right.dir), 45.0, 1e-9);
    /* the centre ray looks at 'at'; row 0 is up (+y), column 0 is left (-x) */
    bsp_ray mid = camera_ray(&cr, 256, 256);
    CHECK_NEAR(mid.dir.x, 0, 1e-15);
    CHECK_NEAR(mid.dir.y, 0, 1e-15);
    CHECK_NEAR(mid.dir.z, -1, 1e-15);
    CHECK(camera_ray(&cr, 256, 0).dir.y > 0);
    CHECK(camera_ray(&cr, 0, 256).dir.x < 0);
    CHECK_NEAR(camera_ray(&cr, 0, 0).dir.x, -camera_ray(&cr, 512, 512).dir.x, 1e-15);
}

TEST(camera_pixel_centres_span_the_outer_edges)
{
    bsp_camera c = make_camera(bsp_v3(0, 0, 10), bsp_v3(0, 0, 0), bsp_v3(0, 1, 0), 90, 512);
    int w, h;
    camera_default_size(&c, BSP_SAMPLING_CENTRES, &w, &h);
    CHECK_EQ_INT(w, 512);
    camera_rays cr;
    camera_rays_init(&cr, &c, 4, 4, BSP_SAMPLING_CENTRES, 0.0);
    /* 4 pixels over tan(45) = 1 on each side: centres at -0.75, -0.25, 0.25, 0.75 */
    bsp_ray r = camera_ray(&cr, 0, 0);
    CHECK_NEAR(r.dir.x / -r.dir.z, -0.75, 1e-15);
    CHECK_NEAR(r.dir.y / -r.dir.z, 0.75, 1e-15);
    r = camera_ray(&cr, 2, 3);
    CHECK_NEAR(r.dir.x / -r.dir.z, 0.25, 1e-15);
    CHECK_NEAR(r.dir.y / -r.dir.z, -0.75, 1e-15);
}

TEST(camera_up_need_not_be_perpendicular)
{
    /* lattice-like: up (0.2, 1, 0) is not perpendicular to the view */
    bsp_camera c = make_camera(bsp_v3(0, 1, 1), bsp_v3(0, -1, -1), bsp_v3(0.2, 1, 0), 60, 8);
    camera_rays cr;
    camera_rays_init(&cr, &c, 9, 9, BSP_SAMPLING_SPD, 0.0);
    CHECK_NEAR(v3_dot(cr.forward, cr.right), 0, 1e-15);
    CHECK_NEAR(v3_dot(cr.forward, cr.up), 0, 1e-15);
    CHECK_NEAR(v3_dot(cr.right, cr.up), 0, 1e-15);
    CHECK_NEAR(v3_length(cr.up), 1, 1e-15);
    CHECK(v3_dot(cr.up, c.up) > 0);
}

/* A floor square at z = 0, a sphere above it, one light overhead, the camera
 * looking down. */
/* A new scene seen from (0, 0, 10) looking down at the origin (60 degrees,
 * 33 x 33 rays), with one white light at LIGHT. */
static bsp_scene *scene_from_above(bsp_vec3 light)
{
    bsp_scene *s = bsp_scene_create();
    REQUIRE(s);
    bsp_error err;
    bsp_camera c = make_camera(bsp_v3(0, 0, 10), bsp_v3(0, 0, 0), bsp_v3(0, 1, 0), 60, 32);
    REQUIRE(bsp_scene_set_camera(s, &c, &err) == BSP_OK);
    bsp_light l = {light, {1, 1, 1}, 0};
    REQUIRE(bsp_scene_add_light(s, &l, &err) == BSP_OK);
    return s;
}

static bsp_scene *shadow_scene(double floor_ks)
{
    bsp_scene *s = scene_from_above(bsp_v3(0, 0, 8));
    bsp_error err;
    bsp_material m = {{1, 1, 1}, 0.8, floor_ks, 10, 0, 1, 0};
    REQUIRE(bsp_scene_set_material(s, &m, &err) == BSP_OK);
    bsp_vec3 q[4] = {bsp_v3(-50, -50, 0), bsp_v3(50, -50, 0), bsp_v3(50, 50, 0),
                     bsp_v3(-50, 50, 0)};
    REQUIRE(bsp_scene_add_polygon(s, q, 4, &err) == BSP_OK);
    bsp_material m2 = {{1, 0, 0}, 0.8, 0, 10, 0, 1, 0};
    REQUIRE(bsp_scene_set_material(s, &m2, &err) == BSP_OK);
    REQUIRE(bsp_scene_add_sphere(s, bsp_v3(2.5, 0, 4), 1.0, &err) == BSP_OK);
    return s;
}

static bsp_image *render(const bsp_scene *s, int threads, int depth, bsp_render_stats *st)
{
    bsp_accel *a = NULL;
    bsp_error err;
    REQUIRE(bsp_accel_build(s, NULL, &a, &err) == BSP_OK);
    CHECK_MSG(bsp_accel_check(a, &err) == BSP_OK, "%s", err.message);
    bsp_render_options o;
    bsp_render_options_defaults(&o);
    o.threads = threads;
    o.max_depth = depth;
    bsp_image *img = NULL;
    REQUIRE(bsp_render(a, &o, &img, st, &err) == BSP_OK);
    bsp_accel_destroy(a);
    return img;
}

static double luminance(const bsp_image *img, int x, int y)
{
    const float *p = img->rgb + 3 * ((size_t)y * (size_t)img->width + (size_t)x);
    return p[0] + p[1] + p[2];
}

TEST(render_shadowed_pixel_is_darker_than_lit_neighbour)
{
    bsp_scene *s = shadow_scene(0);
    bsp_render_stats st;
    bsp_image *img = render(s, 1, 4, &st);
    CHECK_EQ_INT(img->width, 33);
    /* The sphere at x = 2.5, z = 4 under a light at z = 8 shadows the floor
     * around x = 2.5 * 8 / 4 = 5. With the view half-width tan(30) * 10 =
     * 5.77 over 16 ray steps, x = 5 is column 16 + 5 / (5.77/16) = 29.9. */
    double step = tan(30.0 * BSP_PI / 180.0) * 10.0 / 16.0;
    int shadow_col = 16 + (int)lround(5.0 / step);
    int lit_col = 16 - (int)lround(5.0 / step); /* mirror image: lit floor */
    double dark = luminance(img, shadow_col, 16), lit = luminance(img, lit_col, 16);
    CHECK_MSG(dark < 0.5 * lit, "shadow %g vs lit %g", dark, lit);
    /* the ray counts: every primary ray hits (floor or sphere), each hit
     * casts one shadow ray (the light is on the visible side everywhere) */
    CHECK_EQ_INT(st.cls[BSP_RAY_PRIMARY].rays, 33 * 33);
    CHECK_EQ_INT(st.cls[BSP_RAY_PRIMARY].hits, 33 * 33);
    CHECK_EQ_INT(st.cls[BSP_RAY_SHADOW].rays, 33 * 33);
    CHECK(st.cls[BSP_RAY_SHADOW].hits > 0);
    CHECK_EQ_INT(st.cls[BSP_RAY_SECONDARY].rays, 0);
    bsp_image_destroy(img);
    bsp_scene_destroy(s);
}

TEST(render_reflection_counts_by_hand)
{
    /* Floor with Ks > 0: every floor hit spawns one reflected ray; reflected
     * rays go up and hit the sphere or nothing; the sphere has Ks = 0. */
    bsp_scene *s = shadow_scene(0.5);
    bsp_render_stats st1, st2;
    bsp_image *d1 = render(s, 1, 0, &st1);
    CHECK_EQ_INT(st1.cls[BSP_RAY_SECONDARY].rays, 0); /* depth 0: primary rays only */
    bsp_image *d2 = render(s, 1, 1, &st2);
    uint64_t sphere_pixels = 0;
    /* primary hits on the sphere are the rays whose reflected count is 0 */
    CHECK_EQ_INT(st2.cls[BSP_RAY_PRIMARY].hits, 33 * 33);
    sphere_pixels = 33 * 33 - st2.reflected_rays;
    CHECK(sphere_pixels > 0 && sphere_pixels < 200);
    CHECK_EQ_INT(st2.cls[BSP_RAY_SECONDARY].rays, st2.reflected_rays);
    CHECK_EQ_INT(st2.refracted_rays, 0);
    /* reflected rays go up from the floor and mostly hit the sphere's
     * underside, which faces away from the overhead light: the SPD rule casts
     * a shadow ray only from hits whose visible side faces the light, so
     * depth 1 adds at most one shadow ray per secondary hit, and far fewer */
    uint64_t sec_hits = st2.cls[BSP_RAY_SECONDARY].hits;
    uint64_t extra = st2.cls[BSP_RAY_SHADOW].rays - st1.cls[BSP_RAY_SHADOW].rays;
    CHECK(sec_hits > 0);
    CHECK(st2.cls[BSP_RAY_SHADOW].rays >= st1.cls[BSP_RAY_SHADOW].rays);
    CHECK_MSG(extra * 4 < sec_hits, "%llu extra shadow rays for %llu secondary hits",
              (unsigned long long)extra, (unsigned long long)sec_hits);
    bsp_image_destroy(d1);
    bsp_image_destroy(d2);
    bsp_scene_destroy(s);
}

TEST(render_identical_with_one_and_two_threads)
{
    bsp_scene *s = shadow_scene(0.5);
    bsp_render_stats a, b;
    bsp_image *i1 = render(s, 1, 4, &a), *i2 = render(s, 2, 4, &b);
    REQUIRE(i1->width == i2->width && i1->height == i2->height);
    CHECK(memcmp(i1->rgb, i2->rgb, sizeof(float) * 3 * (size_t)i1->width * (size_t)i1->height) ==
          0);
    for (int c = 0; c < BSP_RAY_CLASS_COUNT; c++) {
        CHECK_EQ_INT(a.cls[c].rays, b.cls[c].rays);
        CHECK_EQ_INT(a.cls[c].hits, b.cls[c].hits);
        CHECK_EQ_INT(a.cls[c].isect_tests, b.cls[c].isect_tests);
    }
    CHECK_EQ_INT(b.threads, 2);
    bsp_image_destroy(i1);
    bsp_image_destroy(i2);
    bsp_scene_destroy(s);
}

TEST(render_refraction_through_glass_sphere)
{
    /* A glass sphere (T > 0) in front of the camera, nothing else: the
     * central ray enters, leaves through the back and misses; every ray that
     * hits spawns a refracted ray, and with Ks > 0 a reflected one. */
    bsp_scene *s = bsp_scene_create();
    bsp_error err;
    bsp_camera c = make_camera(bsp_v3(0, 0, 10), bsp_v3(0, 0, 0), bsp_v3(0, 1, 0), 20, 8);
    REQUIRE(bsp_scene_set_camera(s, &c, &err) == BSP_OK);
    bsp_material glass = {{1, 1, 1}, 0.1, 0.1, 30, 0.9, 1.5, 0};
    REQUIRE(bsp_scene_set_material(s, &glass, &err) == BSP_OK);
    REQUIRE(bsp_scene_add_sphere(s, bsp_v3(0, 0, 0), 1.0, &err) == BSP_OK);
    bsp_render_stats st;
    bsp_image *img = render(s, 1, 1, &st);
    uint64_t hits = st.cls[BSP_RAY_PRIMARY].hits;
    CHECK(hits > 0 && hits < 81);
    /* depth 1: each primary hit spawns one reflected and one refracted ray
     * (no total internal reflection when entering) */
    CHECK_EQ_INT(st.reflected_rays, hits);
    CHECK_EQ_INT(st.refracted_rays, hits);
    /* reflected rays leave the convex sphere and miss; refracted rays hit
     * its far side from inside */
    CHECK_EQ_INT(st.cls[BSP_RAY_SECONDARY].hits, hits);
    bsp_image_destroy(img);
    bsp_scene_destroy(s);
}

/* Renders S at 37 x 23 rays (tiles of 16 x 16 leave partial tiles on both
 * edges) in ORDER on THREADS threads, with the per-pixel costs in COSTS. */
static bsp_image *render_in(const bsp_accel *a, bsp_pixel_order order, int threads,
                            bsp_render_stats *st, bsp_query_counters *costs)
{
    bsp_render_options o;
    bsp_render_options_defaults(&o);
    o.width = 37;
    o.height = 23;
    o.threads = threads;
    o.pixel_order = order;
    o.pixel_costs = costs;
    o.pixel_costs_count = 37 * 23;
    bsp_image *img = NULL;
    bsp_error err;
    REQUIRE(bsp_render(a, &o, &img, st, &err) == BSP_OK);
    return img;
}

TEST(render_tiles_and_rows_give_the_same_image_and_counts)
{
    bsp_scene *s = shadow_scene(0.5);
    bsp_accel *a = NULL;
    bsp_error err;
    REQUIRE(bsp_accel_build(s, NULL, &a, &err) == BSP_OK);
    static bsp_query_counters rows_costs[37 * 23], costs[37 * 23];
    bsp_render_stats ref, st;
    bsp_image *rows = render_in(a, BSP_PIXELS_ROWS, 1, &ref, rows_costs);
    CHECK(ref.cls[BSP_RAY_SECONDARY].rays > 0); /* the floor reflects */
    for (int threads = 1; threads <= 2; threads++) {
        bsp_image *img = render_in(a, BSP_PIXELS_TILES, threads, &st, costs);
        CHECK(memcmp(img->rgb, rows->rgb, sizeof(float) * 3 * 37 * 23) == 0);
        for (int c = 0; c < BSP_RAY_CLASS_COUNT; c++) {
            CHECK_EQ_INT(st.cls[c].rays, ref.cls[c].rays);
            CHECK_EQ_INT(st.cls[c].hits, ref.cls[c].hits);
            CHECK_EQ_INT(st.cls[c].isect_tests, ref.cls[c].isect_tests);
            CHECK_EQ_INT(st.cls[c].traversal_steps, ref.cls[c].traversal_steps);
        }
        int same = 0;
        for (int i = 0; i < 37 * 23; i++)
            same += costs[i].rays == rows_costs[i].rays &&
                    costs[i].isect_tests == rows_costs[i].isect_tests &&
                    costs[i].traversal_steps == rows_costs[i].traversal_steps;
        CHECK_EQ_INT(same, 37 * 23);
        bsp_image_destroy(img);
    }
    bsp_image_destroy(rows);
    bsp_accel_destroy(a);
    bsp_scene_destroy(s);
}

typedef struct primary_log {
    bsp_ray rays[37 * 23 + 1];
    int n;
} primary_log;

static void log_primary_ray(bsp_ray_class cls, const bsp_ray *ray, uint32_t from, void *ctx)
{
    (void)from;
    primary_log *l = ctx;
    if (cls == BSP_RAY_PRIMARY && l->n <= 37 * 23)
        l->rays[l->n++] = *ray;
}

static int same_ray(const bsp_ray *a, const bsp_ray *b)
{
    return memcmp(&a->org, &b->org, sizeof a->org) == 0 &&
           memcmp(&a->dir, &b->dir, sizeof a->dir) == 0;
}

/* One thread: tiles row by row, rows in scanline order; an unknown order is refused. */
TEST(render_pixel_orders_trace_in_their_documented_sequence)
{
    bsp_scene *s = shadow_scene(0);
    bsp_accel *a = NULL;
    bsp_error err;
    REQUIRE(bsp_accel_build(s, NULL, &a, &err) == BSP_OK);
    camera_rays cr;
    camera_rays_init(&cr, bsp_scene_camera(s), 37, 23, BSP_SAMPLING_SPD, 0.0);
    static primary_log log;
    for (int order = 0; order < 2; order++) {
        bsp_render_options o;
        bsp_render_options_defaults(&o);
        o.width = 37;
        o.height = 23;
        o.threads = 1;
        o.max_depth = 0;
        o.pixel_order = order ? BSP_PIXELS_ROWS : BSP_PIXELS_TILES;
        o.ray_log = log_primary_ray;
        o.ray_log_ctx = &log;
        log.n = 0;
        bsp_image *img = NULL;
        REQUIRE(bsp_render(a, &o, &img, NULL, &err) == BSP_OK);
        bsp_image_destroy(img);
        CHECK_EQ_INT(log.n, 37 * 23);
        /* the expected order, by hand: tiles of 16 x 16 in rows of tiles
         * (widths 16, 16, 5; heights 16, 7), each row by row */
        int k = 0, in_order = 0, tile = order ? 37 : BSP_RENDER_TILE, tile_h = order ? 1 : tile;
        for (int ty = 0; ty < 23; ty += tile_h)
            for (int tx = 0; tx < 37; tx += tile)
                for (int y = ty; y < ty + tile_h && y < 23; y++)
                    for (int x = tx; x < tx + tile && x < 37; x++) {
                        bsp_ray want = camera_ray(&cr, x, y);
                        in_order += k < log.n && same_ray(&log.rays[k], &want);
                        k++;
                    }
        CHECK_EQ_INT(k, 37 * 23);
        CHECK_EQ_INT(in_order, 37 * 23);
    }
    /* and an order that is neither is refused */
    bsp_render_options o;
    bsp_render_options_defaults(&o);
    o.pixel_order = (bsp_pixel_order)7;
    bsp_image *img = NULL;
    CHECK(bsp_render(a, &o, &img, NULL, &err) == BSP_ERR_INVALID);
    CHECK(img == NULL);
    CHECK(strstr(err.message, "pixel order 7") != NULL);
    bsp_accel_destroy(a);
    bsp_scene_destroy(s);
}

/* Two 4 x 6 squares on z = 0 left and right of the axis, seen from above
 * with the light at the eye: the left one wound to face the eye, the right
 * one wound away from it, each the other's mirror image. */
static const bsp_vec3 facing_square[4] = {{{-5, -3, 0}}, {{-1, -3, 0}}, {{-1, 3, 0}}, {{-5, 3, 0}}};
static const bsp_vec3 turned_square[4] = {{{1, -3, 0}}, {{1, 3, 0}}, {{5, 3, 0}}, {{5, -3, 0}}};

/* Renders S (33 x 33 rays from (0, 0, 10), 60 degrees) and checks what its
 * material's two_sided flag promises: the mirrored pixels of the two squares
 * equally bright and a shadow ray for every hit when two-sided, the away
 * square darker and shadow rays only from the facing one when not. */
static void check_two_squares(const bsp_scene *s, int two_sided)
{
    bsp_render_stats st;
    bsp_image *img = render(s, 1, 0, &st);
    REQUIRE(img->width == 33);
    /* columns 16 -/+ 8: x = -/+ 8 * tan(30 deg) * 10 / 16 = -/+ 2.89, inside both */
    double left = luminance(img, 8, 16), right = luminance(img, 24, 16);
    uint64_t hits = st.cls[BSP_RAY_PRIMARY].hits;
    CHECK(hits > 0 && hits % 2 == 0); /* the squares are mirror images */
    CHECK_EQ_INT(st.cls[BSP_RAY_SHADOW].hits, 0); /* nothing between a square and the eye */
    if (two_sided) {
        CHECK_NEAR(left, right, 1e-6);
        CHECK_EQ_INT(st.cls[BSP_RAY_SHADOW].rays, hits);
    } else {
        /* the away square gets the ambient term alone, the facing one also
         * Lambert's (about its cosine 0.9 here times Kd 0.8, per channel) */
        CHECK_MSG(right + 0.5 < left, "away square %g, facing square %g", right, left);
        CHECK_EQ_INT(st.cls[BSP_RAY_SHADOW].rays, hits / 2);
    }
    bsp_image_destroy(img);
}

TEST(render_two_sided_material_lights_faces_wound_away)
{
    for (int two_sided = 0; two_sided <= 1; two_sided++) {
        bsp_scene *s = scene_from_above(bsp_v3(0, 0, 10)); /* the light at the eye */
        bsp_error err;
        bsp_material m = {{1, 1, 1}, 0.8, 0, 10, 0, 1, two_sided};
        REQUIRE(bsp_scene_set_material(s, &m, &err) == BSP_OK);
        REQUIRE(bsp_scene_add_polygon(s, facing_square, 4, &err) == BSP_OK);
        REQUIRE(bsp_scene_add_polygon(s, turned_square, 4, &err) == BSP_OK);
        check_two_squares(s, two_sided);
        bsp_scene_destroy(s);
    }
    /* a flag other than 0 or 1 is refused, naming the field */
    bsp_scene *s = bsp_scene_create();
    REQUIRE(s);
    bsp_error err;
    bsp_material bad = {{1, 1, 1}, 0.8, 0, 10, 0, 1, 2};
    CHECK_EQ_INT(bsp_scene_set_material(s, &bad, &err), BSP_ERR_INVALID);
    CHECK_STR_CONTAINS(err.message, "two_sided");
    bsp_scene_destroy(s);
}

TEST(render_mesh_default_material_is_two_sided)
{
    /* the same squares as an OBJ file: the mesh's default material lights
     * the square wound away like the facing one */
    char path[512];
    harness_tmp_path(path, sizeof path, "two_squares.obj");
    FILE *f = fopen(path, "w");
    REQUIRE(f);
    for (int k = 0; k < 4; k++)
        fprintf(f, "v %g %g %g\n", facing_square[k].x, facing_square[k].y, facing_square[k].z);
    for (int k = 0; k < 4; k++)
        fprintf(f, "v %g %g %g\n", turned_square[k].x, turned_square[k].y, turned_square[k].z);
    fprintf(f, "f 1 2 3 4\nf 5 6 7 8\n");
    fclose(f);
    bsp_scene *s = NULL;
    bsp_error err;
    REQUIRE_MSG(bsp_scene_load(path, &s, &err) == BSP_OK, "%s", err.message);
    REQUIRE(bsp_scene_material_count(s) == 1);
    CHECK_EQ_INT(bsp_scene_material(s, 0)->two_sided, 1);
    /* the view of the test above; the mesh's light moves with its eye */
    bsp_vec3 eye = bsp_v3(0, 0, 10), at = bsp_v3(0, 0, 0), up = bsp_v3(0, 1, 0);
    REQUIRE(bsp_scene_set_default_view(s, &eye, &at, &up, 60, &err) == BSP_OK);
    bsp_camera c = *bsp_scene_camera(s);
    c.res_x = c.res_y = 32;
    REQUIRE(bsp_scene_set_camera(s, &c, &err) == BSP_OK);
    REQUIRE(bsp_scene_light_count(s) == 1);
    CHECK(bsp_scene_light(s, 0)->pos.z == 10);
    check_two_squares(s, 1);
    bsp_scene_destroy(s);
}
