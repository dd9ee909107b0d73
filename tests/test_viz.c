/*
 * test_viz.c — the tree pictures of `bspray viz`: the pinhole projection
 * against hand-computed pixels and against the renderer's own primary rays,
 * the first split plane of a hand-made scene at the column computed by hand,
 * near-plane clipping (the visible part only, never a write out of bounds),
 * the top view's orientation, and the command end to end.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bspray/bspray.h"
#include "harness.h"
#include "render/draw.h"

/* --- helpers ------------------------------------------------------------------ */

static bsp_camera make_camera(bsp_vec3 from, bsp_vec3 at, bsp_vec3 up, double angle, int res)
{
    bsp_camera c;
    memset(&c, 0, sizeof c);
    c.from = from;
    c.at = at;
    c.up = up;
    c.angle_deg = angle;
    c.hither = 0.01;
    c.res_x = c.res_y = res;
    return c;
}

static const float *pixel(const bsp_image *img, int x, int y)
{
    return img->rgb + 3 * ((size_t)y * (size_t)img->width + (size_t)x);
}

static int is_black(const bsp_image *img, int x, int y)
{
    const float *p = pixel(img, x, y);
    return p[0] == 0 && p[1] == 0 && p[2] == 0;
}

/* Runs CMD, discarding its output; returns the exit status. */
static int run_status(const char *cmd)
{
    int st;
    free(harness_run(cmd, &st));
    return st;
}

/* --- projection ------------------------------------------------------------------ */

TEST(viz_pinhole_hand_computed_pixel)
{
    /* eye (1,2,3) looking down -z, up +y, 90 degrees over 100 pixels: right is
     * +x, and the image plane at distance 1 spans [-1, 1], 50 pixels a unit */
    bsp_camera cam = make_camera(bsp_v3(1, 2, 3), bsp_v3(1, 2, -7), bsp_v3(0, 1, 0), 90, 100);
    draw_pinhole p;
    draw_pinhole_init(&p, &cam, 100, 100, 1e-3);
    double x, y;
    /* (2, 2.5, -1) is (1, 0.5) right/up at depth 4: x = 50 + 50 * 1/4, y = 50 - 50 * 0.5/4 */
    REQUIRE(draw_pinhole_project(&p, bsp_v3(2, 2.5, -1), &x, &y));
    CHECK_NEAR(x, 62.5, 1e-9);
    CHECK_NEAR(y, 43.75, 1e-9);
    /* the view axis lands on the image centre */
    REQUIRE(draw_pinhole_project(&p, bsp_v3(1, 2, -100), &x, &y));
    CHECK_NEAR(x, 50.0, 1e-9);
    CHECK_NEAR(y, 50.0, 1e-9);
    /* behind the eye, and in front of it but closer than the near plane */
    CHECK(!draw_pinhole_project(&p, bsp_v3(1, 2, 4), &x, &y));
    CHECK(!draw_pinhole_project(&p, bsp_v3(1.5, 2, 3 - 1e-4), &x, &y));
}

typedef struct ray_check {
    draw_pinhole p;
    int seen[16][16];
    int rays, off_centre;
} ray_check;

static void log_primary(bsp_ray_class cls, const bsp_ray *ray, uint32_t from, void *ctx)
{
    (void)from;
    ray_check *rc = ctx;
    if (cls != BSP_RAY_PRIMARY)
        return;
    rc->rays++;
    bsp_vec3 q = bsp_v3(ray->org.x + 7 * ray->dir.x, ray->org.y + 7 * ray->dir.y,
                        ray->org.z + 7 * ray->dir.z);
    double x, y;
    if (!draw_pinhole_project(&rc->p, q, &x, &y)) {
        rc->off_centre++;
        return;
    }
    int i = (int)floor(x), j = (int)floor(y);
    /* every primary ray passes through a pixel centre */
    if (fabs(x - i - 0.5) > 1e-6 || fabs(y - j - 0.5) > 1e-6 || i < 0 || j < 0 || i >= 16 ||
        j >= 16)
        rc->off_centre++;
    else
        rc->seen[j][i]++;
}

TEST(viz_pinhole_matches_renderer_rays)
{
    /* an independent check: the renderer's own primary rays (pixel-centre
     * sampling) must project to the centres of their pixels, each once */
    bsp_error err;
    bsp_scene *s = bsp_scene_create();
    REQUIRE(s);
    REQUIRE(bsp_scene_add_sphere(s, bsp_v3(0, 0, 0), 1, &err) == BSP_OK);
    bsp_camera cam = make_camera(bsp_v3(3, -4, 2), bsp_v3(0.2, 0.1, 0), bsp_v3(0, 0, 1), 50, 16);
    REQUIRE(bsp_scene_set_camera(s, &cam, &err) == BSP_OK);
    bsp_accel *a = NULL;
    REQUIRE(bsp_accel_build(s, NULL, &a, &err) == BSP_OK);
    ray_check rc;
    memset(&rc, 0, sizeof rc);
    draw_pinhole_init(&rc.p, &cam, 16, 16, 1e-6);
    bsp_render_options ro;
    bsp_render_options_defaults(&ro);
    ro.width = ro.height = 16;
    ro.sampling = BSP_SAMPLING_CENTRES;
    ro.max_depth = 0;
    ro.threads = 1;
    ro.ray_log = log_primary;
    ro.ray_log_ctx = &rc;
    bsp_image *img = NULL;
    REQUIRE(bsp_render(a, &ro, &img, NULL, &err) == BSP_OK);
    CHECK_EQ_INT(rc.rays, 256);
    CHECK_EQ_INT(rc.off_centre, 0);
    int once = 0;
    for (int j = 0; j < 16; j++)
        for (int i = 0; i < 16; i++)
            once += rc.seen[j][i] == 1;
    CHECK_EQ_INT(once, 256);
    bsp_image_destroy(img);
    bsp_accel_destroy(a);
    bsp_scene_destroy(s);
}

/* --- the first split plane ---------------------------------------------------------- */

/* Two unit spheres at x = -5 and x = +5: Kaplan's root cut is the plane x = 0. */
static bsp_scene *two_spheres(void)
{
    bsp_error err;
    bsp_scene *s = bsp_scene_create();
    if (!s || bsp_scene_add_sphere(s, bsp_v3(-5, 0, 0), 1, &err) != BSP_OK ||
        bsp_scene_add_sphere(s, bsp_v3(5, 0, 0), 1, &err) != BSP_OK) {
        bsp_scene_destroy(s);
        return NULL;
    }
    return s;
}

TEST(viz_first_split_plane_at_hand_computed_column)
{
    bsp_error err;
    bsp_scene *s = two_spheres();
    REQUIRE(s);
    bsp_build_options o;
    bsp_build_options_defaults(&o);
    o.kind = BSP_ACCEL_KAPLAN;
    o.max_depth = 1;
    o.max_leaf_prims = 1; /* Kaplan's default of 2 would keep the root a leaf */
    bsp_accel *a = NULL;
    REQUIRE(bsp_accel_build(s, &o, &a, &err) == BSP_OK);
    draw_cells cells;
    REQUIRE(draw_cells_collect(a, &cells, &err) == BSP_OK);
    REQUIRE(cells.count == 3);
    CHECK(!cells.cell[0].is_leaf);
    CHECK_EQ_INT(cells.cell[0].axis, 0);
    CHECK(cells.cell[0].split == 0.0);
    CHECK_EQ_INT(cells.leaves, 2);
    CHECK_EQ_INT(cells.max_depth, 1);

    /* eye (0.5, 0, 20) looking down -z, 90 degrees over 64 pixels: 32 pixels
     * per unit at distance 1. The plane x = 0 clipped to the cell spans
     * y, z in [-1, 1] (plus a padding far below a pixel): its corners project
     * to x = 32 - 32 * 0.5 / (20 -+ 1), 31.158 and 31.238 — all in column 31
     * — and y = 32 -+ 32 / 19 or 32 -+ 32 / 21: rows 30 to 33. */
    bsp_camera cam = make_camera(bsp_v3(0.5, 0, 20), bsp_v3(0.5, 0, 0), bsp_v3(0, 1, 0), 90, 64);
    draw_pinhole p;
    draw_pinhole_init(&p, &cam, 64, 64, 1e-3);
    bsp_image *img = bsp_image_create(64, 64);
    REQUIRE(img);
    draw_panel_planes(img, &p, &cells, 1);
    int painted = 0;
    for (int y = 0; y < 64; y++)
        for (int x = 0; x < 64; x++)
            if (!is_black(img, x, y)) {
                painted++;
                CHECK_MSG(x == 31 && y >= 30 && y <= 33, "pixel (%d, %d) painted", x, y);
            }
    CHECK_EQ_INT(painted, 4);
    /* the root plane has depth 0: the warm end of the colour map */
    float warm[3];
    draw_colormap(0, warm);
    CHECK(pixel(img, 31, 31)[0] > pixel(img, 31, 31)[2]);
    CHECK(warm[0] > warm[2]);

    /* the top view (down +y, the camera's up) puts the cut x = 0 at the
     * centre column: the root cell spans x in [-6, 6] over the 64 pixels */
    draw_topview tv;
    draw_topview_init(&tv, &cam, cells.cell[0].box, 64, 64, 0);
    CHECK_EQ_INT(tv.up_axis, 1);
    CHECK_EQ_INT(tv.h_axis, 0);
    double x, y;
    draw_topview_project(&tv, bsp_v3(0, 0, 0), &x, &y);
    CHECK_NEAR(x, 32.0, 1e-9);
    draw_topview_project(&tv, bsp_v3(3, 0, 0), &x, &y);
    CHECK_NEAR(x, 32.0 + 3 * 64.0 / 12.0, 1e-3); /* right stays right (less the padding) */
    /* the camera looks down -z, so -z points up the image: the eye (z = 20)
     * is below the centre */
    draw_topview_project(&tv, cam.from, &x, &y);
    CHECK(y > 32.0);
    CHECK_EQ_INT(draw_panel_top(img, &tv, &cells, DRAW_COLOR_DEPTH, 1, &cam, &err), BSP_OK);
    /* both leaves have depth 1; the outline of the cut runs down column 32 */
    float deep[3];
    draw_colormap(1, deep);
    /* rows 27..36 hold the cell's z in [-1, 1] (5.33 pixels a unit, around row 32) */
    const float *left = pixel(img, 16, 32), *right = pixel(img, 48, 32);
    CHECK_NEAR(left[2], deep[2], 1e-6);
    CHECK_NEAR(right[2], deep[2], 1e-6);
    CHECK(pixel(img, 32, 32)[2] < deep[2] - 0.1); /* darkened by the outline */
    CHECK(pixel(img, 16, 10)[2] < 0.1f);          /* outside the root cell: dark */

    bsp_image_destroy(img);
    draw_cells_free(&cells);
    bsp_accel_destroy(a);
    bsp_scene_destroy(s);
}

/* A BVH's camera view draws its node boxes below the root: two spheres at
 * x = -5 and 5 (radius 1), a leaf each, seen from (0, 0, 20) down -z at 32
 * pixels per unit at distance 1. The right leaf's box [4, 6] x [-1, 1]^2
 * projects to columns 32 + 32 x / (20 - z): 38.1 to 42.1 over z = -1..1,
 * rows 32 -+ 32 / 19 or 21: 30.3 to 33.7; the left one mirrored. */
TEST(viz_bvh_boxes_at_hand_computed_pixels)
{
    bsp_error err;
    bsp_scene *s = two_spheres();
    REQUIRE(s);
    bsp_build_options o;
    bsp_build_options_defaults(&o);
    o.kind = BSP_ACCEL_BVH;
    o.max_leaf_prims = 1;
    bsp_accel *a = NULL;
    REQUIRE(bsp_accel_build(s, &o, &a, &err) == BSP_OK);
    draw_cells cells;
    REQUIRE(draw_cells_collect(a, &cells, &err) == BSP_OK);
    REQUIRE(cells.count == 3);
    CHECK_EQ_INT(cells.leaves, 2);
    bsp_camera cam = make_camera(bsp_v3(0, 0, 20), bsp_v3(0, 0, 0), bsp_v3(0, 1, 0), 90, 64);
    draw_pinhole p;
    draw_pinhole_init(&p, &cam, 64, 64, 1e-3);
    bsp_image *img = bsp_image_create(64, 64);
    REQUIRE(img);
    draw_panel_boxes(img, &p, &cells, 1);
    int left = 0, right = 0;
    for (int y = 0; y < 64; y++)
        for (int x = 0; x < 64; x++)
            if (!is_black(img, x, y)) {
                int in_right = x >= 38 && x <= 42, in_left = x >= 21 && x <= 25;
                CHECK_MSG((in_left || in_right) && y >= 30 && y <= 33, "pixel (%d, %d) painted",
                          x, y);
                left += in_left;
                right += in_right;
            }
    CHECK(left > 4 && right > 4);
    bsp_image_destroy(img);
    draw_cells_free(&cells);
    bsp_accel_destroy(a);
    bsp_scene_destroy(s);
}

/* --- clipping --------------------------------------------------------------------------- */

TEST(viz_near_plane_clipping_draws_the_visible_part)
{
    /* eye at the origin looking down -z, 90 degrees, 64 pixels; a segment from
     * behind the eye at the left, A = (-1, 0, 3), to B = (0.5, 0, -2) in front:
     * B projects to x = 32 + 32 * 0.25 = 40 on row 32, and the part in front
     * runs from B leftwards off the image. Projecting A without clipping would
     * land it at x = 32 + 32 * (-1) / (-3) = 42.7, on the wrong side. */
    bsp_camera cam = make_camera(bsp_v3(0, 0, 0), bsp_v3(0, 0, -1), bsp_v3(0, 1, 0), 90, 64);
    draw_pinhole p;
    draw_pinhole_init(&p, &cam, 64, 64, 1e-3);
    bsp_image *img = bsp_image_create(64, 64);
    REQUIRE(img);
    const float white[3] = {1, 1, 1};
    draw_segment_3d(img, &p, bsp_v3(-1, 0, 3), bsp_v3(0.5, 0, -2), white, 1.f);
    for (int x = 0; x <= 40; x++)
        CHECK_MSG(!is_black(img, x, 32), "column %d of row 32 not drawn", x);
    for (int x = 41; x < 64; x++)
        CHECK_MSG(is_black(img, x, 32), "column %d of row 32 drawn", x);
    /* wholly behind the eye: nothing */
    bsp_image *none = bsp_image_create(64, 64);
    REQUIRE(none);
    draw_segment_3d(none, &p, bsp_v3(-1, 0, 3), bsp_v3(2, 1, 0.5), white, 1.f);
    int drawn = 0;
    for (int y = 0; y < 64; y++)
        for (int x = 0; x < 64; x++)
            drawn += !is_black(none, x, y);
    CHECK_EQ_INT(drawn, 0);
    bsp_image_destroy(none);
    bsp_image_destroy(img);
}

TEST(viz_drawing_never_writes_out_of_bounds)
{
    enum { W = 37, H = 23, GUARD = 4096 };
    static float buf[GUARD + W * H * 3 + GUARD];
    for (size_t i = 0; i < sizeof buf / sizeof buf[0]; i++)
        buf[i] = 7.0f;
    bsp_image img = {W, H, buf + GUARD};
    for (int i = 0; i < W * H * 3; i++)
        img.rgb[i] = 0;
    const float c[3] = {1, 0.5f, 0.25f};
    bsp_camera cam = make_camera(bsp_v3(0.3, -0.2, 0.1), bsp_v3(1, 2, -3), bsp_v3(0, 1, 0), 70, W);
    draw_pinhole p;
    draw_pinhole_init(&p, &cam, W, H, 1e-4);
    /* random segments around the eye, many crossing the near plane or
     * passing behind it, some enormous (fixed seed) */
    unsigned long long seed = 12345;
    for (int k = 0; k < 20000; k++) {
        double v[6];
        for (int j = 0; j < 6; j++) {
            seed = seed * 6364136223846793005ULL + 1442695040888963407ULL;
            double u = (double)(seed >> 11) / 9007199254740992.0 * 2 - 1;
            v[j] = u * (k % 4 == 0 ? 1e9 : k % 4 == 1 ? 1e-3 : 5);
        }
        draw_segment_3d(&img, &p, bsp_v3(v[0], v[1], v[2]), bsp_v3(v[3], v[4], v[5]), c, 0.5f);
        draw_line(&img, v[0] * 10, v[1] * 10, v[3] * 10, v[4] * 10, c, 0.5f);
    }
    /* degenerate and non-finite input */
    draw_line(&img, NAN, 0, 5, 5, c, 1);
    draw_line(&img, -INFINITY, 3, INFINITY, 3, c, 1);
    draw_line(&img, 1e308, -1e308, -1e308, 1e308, c, 1);
    draw_line(&img, W, H, W, H, c, 1);
    draw_line(&img, -0.5, -0.5, -0.5, -0.5, c, 1);
    draw_fill_rect(&img, -1e300, -1e300, 1e300, 1e300, c, 0.1f);
    draw_fill_rect(&img, NAN, 0, 3, 3, c, 1);
    draw_frame(&img, -5, -5, W + 5, H + 5, c, 1);
    draw_text(&img, W - 3, H - 3, 3, "OVERFLOW?", c);
    draw_text(&img, -100, -100, 2, "x", c);
    draw_label(&img, -4, H - 2, 2, "LABEL 123");
    int guard_ok = 1;
    for (int i = 0; i < GUARD; i++)
        guard_ok &= buf[i] == 7.0f && buf[GUARD + W * H * 3 + i] == 7.0f;
    CHECK(guard_ok);
    int finite = 1;
    for (int i = 0; i < W * H * 3; i++)
        finite &= isfinite(img.rgb[i]) && img.rgb[i] >= 0 && img.rgb[i] <= 1.0f;
    CHECK(finite);
}

TEST(viz_colormap_and_font)
{
    float a[3], b[3];
    draw_colormap(0, a);
    draw_colormap(1, b);
    CHECK(a[0] > a[2]); /* shallow: warm */
    CHECK(b[2] > b[0]); /* deep: cool */
    draw_colormap(-3, b);
    CHECK(a[0] == b[0] && a[1] == b[1] && a[2] == b[2]);
    /* refs: an empty leaf grey, the fullest warm */
    draw_cell_color(DRAW_COLOR_REFS, 0, 100, a);
    CHECK(a[0] == a[1] && a[1] == a[2]);
    draw_cell_color(DRAW_COLOR_REFS, 100, 100, a);
    CHECK(a[0] > a[2]);
    /* "1" is 5 x 7 dots at scale 1, 6 pixels a character */
    CHECK_EQ_INT(draw_text_width("SAH 10", 1), 35);
    bsp_image *img = bsp_image_create(8, 8);
    REQUIRE(img);
    const float w[3] = {1, 1, 1};
    draw_text(img, 0, 0, 1, "1", w);
    /* the stem of '1' is the middle column, rows 0..6, with a foot of
     * columns 1..3 on row 6 */
    for (int y = 0; y < 7; y++)
        CHECK(!is_black(img, 2, y));
    CHECK(!is_black(img, 1, 6) && !is_black(img, 3, 6));
    CHECK(is_black(img, 0, 6) && is_black(img, 4, 6));
    CHECK(is_black(img, 0, 0) && is_black(img, 4, 0) && is_black(img, 5, 3));
    bsp_image_destroy(img);
}

/* --- the command ------------------------------------------------------------------------ */

TEST(viz_cli_writes_panels_and_rejects_bad_input)
{
    char out[512], cmd[2048];
    snprintf(out, sizeof out, "%s/viz.png", harness_tmpdir());
    snprintf(cmd, sizeof cmd,
             "%s viz spd:balls:1 --accel kaplan,sah --size 48 --threads 1 --quiet -o %s",
             harness_cli(), out);
    CHECK_EQ_INT(run_status(cmd), 0);
    bsp_image *img = NULL;
    bsp_error err;
    REQUIRE(bsp_image_read_png(out, &img, &err) == BSP_OK);
    CHECK_EQ_INT(img->width, 2 * 48);  /* camera view + top view */
    CHECK_EQ_INT(img->height, 2 * 48); /* one row per method */
    bsp_image_destroy(img);

    /* one method, colour by references, a summary line per method */
    snprintf(cmd, sizeof cmd,
             "%s viz spd:balls:1 --color refs --size 40 --threads 1 --max-depth 4 -o %s 2>&1",
             harness_cli(), out);
    int st;
    char *text = harness_run(cmd, &st);
    REQUIRE(text);
    CHECK_EQ_INT(st, 0);
    CHECK_STR_CONTAINS(text, "sah");
    CHECK_STR_CONTAINS(text, "leaves");
    free(text);
    img = NULL;
    REQUIRE(bsp_image_read_png(out, &img, &err) == BSP_OK);
    CHECK_EQ_INT(img->width, 80);
    CHECK_EQ_INT(img->height, 40);
    bsp_image_destroy(img);

    snprintf(cmd, sizeof cmd, "%s viz spd:balls:1 --bogus -o %s 2>/dev/null", harness_cli(), out);
    CHECK_EQ_INT(run_status(cmd), 2);
    snprintf(cmd, sizeof cmd, "%s viz spd:balls:1 --accel sah,quadtree -o %s 2>/dev/null",
             harness_cli(), out);
    CHECK_EQ_INT(run_status(cmd), 2);
    snprintf(cmd, sizeof cmd, "%s viz spd:balls:1 --size 0 -o %s 2>/dev/null", harness_cli(), out);
    CHECK_EQ_INT(run_status(cmd), 2);
    snprintf(cmd, sizeof cmd, "%s viz spd:balls:1 2>/dev/null", harness_cli());
    CHECK_EQ_INT(run_status(cmd), 2); /* no -o */

    snprintf(cmd, sizeof cmd, "%s viz spd:balls:1 --accel naive -o %s 2>&1", harness_cli(), out);
    text = harness_run(cmd, &st);
    REQUIRE(text);
    CHECK_EQ_INT(st, 1);
    CHECK_STR_CONTAINS(text, "naive");
    free(text);
    snprintf(cmd, sizeof cmd, "%s viz %s/no-such-scene.nff -o %s 2>&1", harness_cli(),
             harness_tmpdir(), out);
    text = harness_run(cmd, &st);
    REQUIRE(text);
    CHECK_EQ_INT(st, 1);
    CHECK_STR_CONTAINS(text, "no-such-scene.nff");
    free(text);

    snprintf(cmd, sizeof cmd, "%s viz --help", harness_cli());
    text = harness_run(cmd, &st);
    REQUIRE(text);
    CHECK_EQ_INT(st, 0);
    CHECK_STR_CONTAINS(text, "usage: bspray viz");
    free(text);
}
