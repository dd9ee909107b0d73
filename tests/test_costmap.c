/*
 * test_costmap.c — per-pixel costs of a render (bsp_render_options.
 * pixel_costs) and their picture (src/render/costmap.c, `render
 * --cost-map`): the pixels' counts sum to the render's statistics, do not
 * depend on the thread count, sit at the right pixels (a background pixel of
 * a depth-0 render cast one ray, a pixel on an object one plus a shadow ray
 * per light), and the naive method tests every primitive (but the one a ray
 * leaves) for every ray; the picture's colours are the map's values.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bspray/bspray.h"
#include "harness.h"
#include "kd_test_util.h"
#include "render/costmap.h"

/* A render of ACCEL at W x H with depth DEPTH on THREADS threads, its pixel
 * costs in a new array (free()); the image and statistics in *IMG, *ST. */
static bsp_query_counters *render_costs(const bsp_accel *accel, int w, int h, int depth,
                                        int threads, bsp_image **img, bsp_render_stats *st)
{
    bsp_render_options o;
    bsp_render_options_defaults(&o);
    o.width = w;
    o.height = h;
    o.max_depth = depth;
    o.threads = threads;
    o.pixel_costs = calloc((size_t)w * (size_t)h, sizeof *o.pixel_costs);
    o.pixel_costs_count = (size_t)w * (size_t)h;
    REQUIRE(o.pixel_costs);
    bsp_error err;
    bsp_status s = bsp_render(accel, &o, img, st, &err);
    CHECK_MSG(s == BSP_OK, "render: %s", err.message);
    if (s != BSP_OK)
        harness_abort_test();
    return o.pixel_costs;
}

TEST(render_pixel_costs_sum_to_the_statistics_on_any_thread_count)
{
    static const char *const scenes[] = {"spd:balls", "spd:rings"};
    enum { W = 40, H = 30 };
    for (size_t sc = 0; sc < 2; sc++) {
        bsp_scene *s = kd_test_load(scenes[sc]);
        const size_t np = bsp_scene_prim_count(s);
        for (int naive = 0; naive < 2; naive++) {
            bsp_accel *a = kd_test_build(s, naive ? BSP_ACCEL_NAIVE : BSP_ACCEL_SAH);
            bsp_image *img1, *img2;
            bsp_render_stats st1, st2;
            bsp_query_counters *c1 = render_costs(a, W, H, 4, 1, &img1, &st1);
            bsp_query_counters *c2 = render_costs(a, W, H, 4, 2, &img2, &st2);
            CHECK_MSG(!memcmp(c1, c2, W * H * sizeof *c1), "%s: the costs depend on threads",
                      scenes[sc]);
            bsp_query_counters sum = {0};
            int naive_ok = 1;
            for (size_t i = 0; i < W * H; i++) {
                sum.rays += c1[i].rays;
                sum.isect_tests += c1[i].isect_tests;
                sum.traversal_steps += c1[i].traversal_steps;
                sum.leaves_visited += c1[i].leaves_visited;
                sum.empty_leaves += c1[i].empty_leaves;
                sum.mailbox_hits += c1[i].mailbox_hits;
                /* at most every primitive for every ray; the primary ray at
                 * least every one but the one it may leave */
                if (naive && !(c1[i].isect_tests <= c1[i].rays * np && c1[i].isect_tests >= np - 1))
                    naive_ok = 0;
            }
            CHECK(naive_ok);
            bsp_ray_class_stats all = {0};
            for (int k = 0; k < BSP_RAY_CLASS_COUNT; k++) {
                all.rays += st1.cls[k].rays;
                all.isect_tests += st1.cls[k].isect_tests;
                all.traversal_steps += st1.cls[k].traversal_steps;
                all.leaves_visited += st1.cls[k].leaves_visited;
                all.empty_leaves += st1.cls[k].empty_leaves;
                all.mailbox_hits += st1.cls[k].mailbox_hits;
            }
            CHECK_EQ_INT(sum.rays, all.rays);
            CHECK_EQ_INT(sum.isect_tests, all.isect_tests);
            CHECK_EQ_INT(sum.traversal_steps, all.traversal_steps);
            CHECK_EQ_INT(sum.leaves_visited, all.leaves_visited);
            CHECK_EQ_INT(sum.empty_leaves, all.empty_leaves);
            CHECK_EQ_INT(sum.mailbox_hits, all.mailbox_hits);
            CHECK(naive ? sum.traversal_steps == 0 : sum.traversal_steps > sum.rays);
            free(c1);
            free(c2);
            bsp_image_destroy(img1);
            bsp_image_destroy(img2);
            bsp_accel_destroy(a);
        }
        bsp_scene_destroy(s);
    }
}

TEST(render_pixel_costs_sit_at_their_pixels)
{
    /* depth 0, one sphere off the centre and the light at the eye: a pixel
     * whose ray misses shows the background and cast one ray; one whose ray
     * hits faces the light and cast a shadow ray too */
    char path[600];
    snprintf(path, sizeof path, "%s/costmap_sphere.nff", harness_tmpdir());
    FILE *f = fopen(path, "w");
    REQUIRE(f);
    fputs("v\nfrom 0 0 10\nat 0 0 0\nup 0 1 0\nangle 40\nhither 1\nresolution 8 8\n"
          "b 0.1 0.2 0.3\nl 0 0 10\nf 1 0 0 1 0 0 0 0\ns 1.2 0.6 0 1.5\n",
          f);
    fclose(f);
    bsp_scene *s = kd_test_load(path);
    bsp_accel *a = kd_test_build(s, BSP_ACCEL_SAH);
    enum { W = 37, H = 23 };
    bsp_image *img;
    bsp_render_stats st;
    bsp_query_counters *c = render_costs(a, W, H, 0, 2, &img, &st);
    double bg[3];
    bsp_scene_background(s, bg);
    const uint64_t lights = bsp_scene_light_count(s);
    size_t misses = 0, wrong = 0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            const float *p = img->rgb + ((size_t)y * W + (size_t)x) * 3;
            int background = p[0] == (float)bg[0] && p[1] == (float)bg[1] && p[2] == (float)bg[2];
            misses += (size_t)background;
            uint64_t r = c[(size_t)y * W + (size_t)x].rays;
            wrong += background ? r != 1 : r != 1 + lights;
        }
    CHECK_MSG(wrong == 0, "%zu pixels with another count of rays", wrong);
    CHECK_MSG(misses > 20 && misses < W * H - 20, "%zu background pixels", misses);
    free(c);
    bsp_image_destroy(img);

    /* the size: bsp_render_size's, and too little room is refused */
    bsp_render_options o;
    bsp_render_options_defaults(&o);
    int w = 0, h = 0;
    bsp_error err;
    REQUIRE(bsp_render_size(s, &o, &w, &h, &err) == BSP_OK);
    CHECK_EQ_INT(w, 9); /* 'resolution 8 8': the SPD protocol's 9 rays across */
    CHECK_EQ_INT(h, 9);
    o.width = 10;
    o.height = 4;
    REQUIRE(bsp_render_size(s, &o, &w, &h, &err) == BSP_OK);
    CHECK_EQ_INT(w, 10);
    CHECK_EQ_INT(h, 4);
    bsp_query_counters few[39];
    o.pixel_costs = few;
    o.pixel_costs_count = 39;
    CHECK_EQ_INT(bsp_render(a, &o, &img, NULL, &err), BSP_ERR_INVALID);
    CHECK_STR_CONTAINS(err.message, "10 x 4 pixels");
    o.width = -1;
    CHECK_EQ_INT(bsp_render_size(s, &o, &w, &h, &err), BSP_ERR_INVALID);
    bsp_accel_destroy(a);
    bsp_scene_destroy(s);
}

static int same_rgb(const float *p, const float want[3])
{
    return fabsf(p[0] - want[0]) < 1e-6f && fabsf(p[1] - want[1]) < 1e-6f &&
           fabsf(p[2] - want[2]) < 1e-6f;
}

TEST(costmap_colours_each_pixel_by_its_share_of_the_most)
{
    /* 3 x 2 pixels of steps 0, 10, 20 / 40, 30, 5: scaled up 8x, each block
     * the colour of steps / 40 */
    bsp_query_counters c[6];
    memset(c, 0, sizeof c);
    const uint64_t steps[6] = {0, 10, 20, 40, 30, 5};
    for (int i = 0; i < 6; i++) {
        c[i].traversal_steps = steps[i];
        c[i].isect_tests = 7; /* the same everywhere: every pixel the brightest */
    }
    const int s = costmap_scale(3, 2);
    CHECK_EQ_INT(s, 8);
    bsp_image *img = costmap_draw(c, 3, 2, COSTMAP_STEPS);
    REQUIRE(img);
    CHECK(img->width > 3 * s + 20 && img->height >= 2 * s);
    for (int i = 0; i < 6; i++) {
        float want[3];
        costmap_color((double)steps[i] / 40.0, want);
        int bx = (i % 3) * s, by = (i / 3) * s;
        for (int k = 0; k < 4; k++) { /* corners of the block */
            int x = bx + (k & 1) * (s - 1), y = by + (k >> 1) * (s - 1);
            CHECK_MSG(same_rgb(img->rgb + ((size_t)y * img->width + x) * 3, want),
                      "pixel %d at (%d, %d)", i, x, y);
        }
    }
    /* the colours grow brighter with the value */
    float lo[3], mid[3], hi[3];
    costmap_color(0.0, lo);
    costmap_color(0.5, mid);
    costmap_color(1.0, hi);
    CHECK(lo[0] + lo[1] + lo[2] < mid[0] + mid[1] + mid[2]);
    CHECK(mid[0] + mid[1] + mid[2] < hi[0] + hi[1] + hi[2]);
    bsp_image_destroy(img);
    img = costmap_draw(c, 3, 2, COSTMAP_TESTS);
    REQUIRE(img);
    CHECK(same_rgb(img->rgb, hi));
    bsp_image_destroy(img);
    CHECK(costmap_draw(c, 0, 2, COSTMAP_STEPS) == NULL);
    costmap_measure m;
    CHECK(costmap_measure_parse("leaves", &m) && m == COSTMAP_LEAVES);
    CHECK(!costmap_measure_parse("cycles", &m));
}

TEST(cli_render_cost_map)
{
    char path[600], cmd[2048];
    snprintf(path, sizeof path, "%s/cost.png", harness_tmpdir());
    snprintf(cmd, sizeof cmd,
             "%s render spd:tree --res 64 --cost-map %s --cost-measure tests -o %s/c.png "
             "--quiet 2>&1",
             harness_cli(), path, harness_tmpdir());
    int status;
    char *out = harness_run(cmd, &status);
    REQUIRE(out);
    CHECK_MSG(status == 0, "%s", out);
    free(out);
    bsp_image *img;
    bsp_error err;
    REQUIRE(bsp_image_read_png(path, &img, &err) == BSP_OK);
    const int s = costmap_scale(64, 64);
    CHECK_EQ_INT(img->height, 64 * s);
    CHECK(img->width > 64 * s);
    bsp_image_destroy(img);
    static const struct {
        const char *args, *msg;
        int status;
    } bad[] = {
        {"--cost-map %s/x.png --cost-measure cycles", "steps, tests, leaves or rays", 2},
        {"--cost-map /nonexistent/dir/x.png", "/nonexistent/dir/x.png", 1},
    };
    for (size_t i = 0; i < 2; i++) {
        char args[700];
        snprintf(args, sizeof args, bad[i].args, harness_tmpdir());
        snprintf(cmd, sizeof cmd, "%s render spd:balls --res 8 %s -o %s/c.png 2>&1", harness_cli(),
                 args, harness_tmpdir());
        out = harness_run(cmd, &status);
        REQUIRE(out);
        CHECK_EQ_INT(status, bad[i].status);
        CHECK_STR_CONTAINS(out, bad[i].msg);
        free(out);
    }
}
