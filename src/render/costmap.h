/*
 * costmap.h — a picture of where a render's work went: one counter of every
 * pixel (bsp_render_options.pixel_costs) as a colour from dark (none) to
 * bright (the most), beside a colour bar with its scale (`bspray render
 * --cost-map`). The classic figure of acceleration-structure papers: the
 * traversal steps or intersection tests each pixel's rays cost.
 */
#ifndef BSPRAY_RENDER_COSTMAP_H
#define BSPRAY_RENDER_COSTMAP_H

#include "bspray/render.h"

#define COSTMAP_HIDDEN __attribute__((visibility("hidden")))

typedef enum costmap_measure {
    COSTMAP_STEPS = 0, /* traversal steps (nodes visited: N_TS's numerator) */
    COSTMAP_TESTS,     /* ray-primitive intersection tests (N_IT's) */
    COSTMAP_LEAVES,    /* leaves visited (N_ETS's) */
    COSTMAP_RAYS,      /* queries (the primary ray and all it spawned) */
    COSTMAP_MEASURE_COUNT
} costmap_measure;

/* The measure called NAME ("steps", "tests", "leaves", "rays"); 0 when there
 * is none. */
COSTMAP_HIDDEN int costmap_measure_parse(const char *name, costmap_measure *m);
COSTMAP_HIDDEN const char *costmap_measure_name(costmap_measure m);
/* Measure M of one pixel's counters. */
COSTMAP_HIDDEN uint64_t costmap_value(const bsp_query_counters *c, costmap_measure m);
/* The colour of T in [0, 1] (clamped): black, violet, red, orange, pale
 * yellow; its luminance grows with T. */
COSTMAP_HIDDEN void costmap_color(double t, float rgb[3]);

/* The picture of measure M of COSTS[y * WIDTH + x]: pixel (x, y) of the map
 * (scaled up by a whole factor when the render is small) coloured by
 * value / the largest value, and a colour bar on its right with ticks from 0
 * to that largest value and the measure's name. NULL when out of memory. */
COSTMAP_HIDDEN bsp_image *costmap_draw(const bsp_query_counters *costs, int width, int height,
                                       costmap_measure m);
/* The factor costmap_draw scales a WIDTH x HEIGHT render up by. */
COSTMAP_HIDDEN int costmap_scale(int width, int height);

#endif /* BSPRAY_RENDER_COSTMAP_H */
