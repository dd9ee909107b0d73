/*
 * costmap.c — the per-pixel cost picture (costmap.h).
 */
#include "render/costmap.h"

#include <stdio.h>
#include <string.h>

#include "render/draw.h"
#include "render/plot.h"

/* The map is scaled up until it is at least this tall (at most 8x). */
#define COSTMAP_MIN_HEIGHT 256
/* The colour bar's column: its margin, bar width and room for the labels. */
#define BAR_MARGIN 16
#define BAR_WIDTH 20
#define BAR_LABELS 64
#define LEGEND_WIDTH (BAR_MARGIN + BAR_WIDTH + 8 + BAR_LABELS)

static const char *const measure_names[COSTMAP_MEASURE_COUNT] = {"steps", "tests", "leaves",
                                                                 "rays"};

int costmap_measure_parse(const char *name, costmap_measure *m)
{
    for (int i = 0; i < COSTMAP_MEASURE_COUNT; i++)
        if (!strcmp(name, measure_names[i])) {
            *m = (costmap_measure)i;
            return 1;
        }
    return 0;
}

const char *costmap_measure_name(costmap_measure m)
{
    return (unsigned)m < COSTMAP_MEASURE_COUNT ? measure_names[m] : "?";
}

uint64_t costmap_value(const bsp_query_counters *c, costmap_measure m)
{
    switch (m) {
    case COSTMAP_STEPS:
        return c->traversal_steps;
    case COSTMAP_TESTS:
        return c->isect_tests;
    case COSTMAP_LEAVES:
        return c->leaves_visited;
    default:
        return c->rays;
    }
}

void costmap_color(double t, float rgb[3])
{
    static const float stops[][3] = {
        {0.00f, 0.00f, 0.02f}, {0.34f, 0.06f, 0.43f}, {0.73f, 0.21f, 0.33f},
        {0.97f, 0.55f, 0.04f}, {0.99f, 1.00f, 0.64f},
    };
    draw_ramp(stops, (int)(sizeof stops / sizeof stops[0]), t, rgb);
}

int costmap_scale(int width, int height)
{
    int s = 1;
    while (s < 8 && height * s < COSTMAP_MIN_HEIGHT && width * (s + 1) <= 4096)
        s++;
    return s;
}

bsp_image *costmap_draw(const bsp_query_counters *costs, int width, int height, costmap_measure m)
{
    if (width < 1 || height < 1)
        return NULL;
    const int s = costmap_scale(width, height);
    const int mw = width * s, mh = height * s;
    const int top = DRAW_TEXT_HEIGHT(1) + 8; /* the measure's name above the bar */
    const int ih = mh > top + 64 ? mh : top + 64;
    bsp_image *img = bsp_image_create(mw + LEGEND_WIDTH, ih);
    if (!img)
        return NULL;
    uint64_t most = 0;
    for (size_t i = 0; i < (size_t)width * (size_t)height; i++) {
        uint64_t v = costmap_value(&costs[i], m);
        most = v > most ? v : most;
    }
    const float white[3] = {1, 1, 1};
    for (int y = 0; y < mh; y++)
        for (int x = 0; x < mw; x++) {
            uint64_t v =
                costmap_value(&costs[(size_t)(y / s) * (size_t)width + (size_t)(x / s)], m);
            float rgb[3];
            costmap_color(most ? (double)v / (double)most : 0.0, rgb);
            memcpy(img->rgb + ((size_t)y * (size_t)img->width + (size_t)x) * 3, rgb, sizeof rgb);
        }
    /* the bar: bright at the top (the largest value), dark at the bottom (0) */
    const int bx = mw + BAR_MARGIN, by0 = top, by1 = ih - 8;
    draw_text(img, bx, 2, 1, costmap_measure_name(m), white);
    for (int y = by0; y <= by1; y++) {
        float rgb[3];
        costmap_color((double)(by1 - y) / (double)(by1 - by0), rgb);
        draw_fill_rect(img, bx, y, bx + BAR_WIDTH, y + 1, rgb, 1.0f);
    }
    plot_axis a = {NULL, 0, 0.0, most > 0 ? (double)most : 1.0};
    double t[16];
    size_t nt = plot_ticks(&a, t, 16);
    for (size_t i = 0; i < nt; i++) {
        int y = by1 - (int)((t[i] / a.hi) * (by1 - by0) + 0.5);
        char label[32];
        plot_tick_label(t[i], label, sizeof label);
        draw_fill_rect(img, bx + BAR_WIDTH, y, bx + BAR_WIDTH + 4, y + 1, white, 1.0f);
        draw_text(img, bx + BAR_WIDTH + 8, y - DRAW_TEXT_HEIGHT(1) / 2, 1, label, white);
    }
    return img;
}
