/*
 * havran_test_util.h — helpers shared by the tests that compare bspray's
 * structures with Havran's 1999 statistics (test_grid.c, test_octree.c):
 * the SPD database generated in code, a render's figures per ray of every
 * class, and the fields of a bench CSV line. Computed here from the
 * library's own counters, apart from the bench tool's code they check.
 */
#ifndef BSPRAY_TESTS_HAVRAN_TEST_UTIL_H
#define BSPRAY_TESTS_HAVRAN_TEST_UTIL_H

#include <string.h>

#include "bspray/bspray.h"
#include "harness.h"

/* The scene SPEC ("spd:NAME"); ends the test when it does not load. The SPD
 * databases generated in code are bit for bit the files Havran measured
 * (test_spd.c checks that), so these tests need no ../shared. */
static inline bsp_scene *havran_test_scene(const char *spec)
{
    bsp_scene *s = NULL;
    bsp_error err;
    REQUIRE_MSG(bsp_scene_load(spec, &s, &err) == BSP_OK, "%s", err.message);
    return s;
}

/* A render's counts summed over the ray classes (divide by rays: per ray). */
typedef struct havran_test_totals {
    double rays, it, ts, ets, eets;
} havran_test_totals;

static inline havran_test_totals havran_test_sum(const bsp_render_stats *st)
{
    havran_test_totals t = {0, 0, 0, 0, 0};
    for (int c = 0; c < BSP_RAY_CLASS_COUNT; c++) {
        t.rays += (double)st->cls[c].rays;
        t.it += (double)st->cls[c].isect_tests;
        t.ts += (double)st->cls[c].traversal_steps;
        t.ets += (double)st->cls[c].leaves_visited;
        t.eets += (double)st->cls[c].empty_leaves;
    }
    return t;
}

/* Why quick mode (the sanitizer run) skips a test of his figures: they are
 * of 513 x 513 renders and the same in every build of the library (make
 * test checks them); the structures and the renderer run under the
 * sanitizers in the exactness and render tests. */
#define HAVRAN_FIGURES_FULL_ONLY \
    "Havran's figures (of 513 x 513 renders, the same in every build) are make test's check"

/* Renders A as his tables were (the renderer's defaults: 513 x 513 rays of
 * ray depth 4) and returns the counts summed over the ray classes; ends the
 * test when the render fails or shoots too few rays for his figures. */
static inline havran_test_totals havran_test_render(const bsp_accel *a)
{
    bsp_render_options o;
    bsp_render_options_defaults(&o);
    bsp_image *img = NULL;
    bsp_render_stats st;
    bsp_error err;
    REQUIRE_MSG(bsp_render(a, &o, &img, &st, &err) == BSP_OK, "%s", err.message);
    bsp_image_destroy(img);
    havran_test_totals t = havran_test_sum(&st);
    REQUIRE(t.rays > 1e6);
    return t;
}

/* Splits LINE at its commas, in place, into FIELDS[0..MAX); returns how
 * many. */
static inline int havran_test_csv_fields(char *line, char **fields, int max)
{
    int n = 0;
    for (char *p = strtok(line, ","); p && n < max; p = strtok(NULL, ","))
        fields[n++] = p;
    return n;
}

#endif /* BSPRAY_TESTS_HAVRAN_TEST_UTIL_H */
