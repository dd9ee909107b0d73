/*
 * plot.h — line and bar charts as images, for the benchmarks' figures
 * (`bspray bench --plot`, `bspray bench --scaling --plot`): axes on a linear
 * or a log10 scale with round tick values, a grid, a title, axis labels, a
 * legend, and either lines through points (with markers; dashed lines for
 * reference curves, without) or groups of bars, one group per category.
 *
 * Text uses draw.h's 5 x 7 font, which has upper case only: labels are shown
 * in upper case. Values that cannot be shown (NaN, infinities, values <= 0
 * on a log axis) are left out: a line breaks there, a bar is not drawn.
 * Nothing is written outside the image, whatever the data.
 */
#ifndef BSPRAY_RENDER_PLOT_H
#define BSPRAY_RENDER_PLOT_H

#include <stddef.h>

#include "bspray/error.h"
#include "bspray/render.h"

#define PLOT_HIDDEN __attribute__((visibility("hidden")))

typedef struct plot_axis {
    const char *label;
    int log;       /* log10 scale: only values > 0 are shown */
    double lo, hi; /* the range shown, lo < hi (plot_fit_axes sets it from the data) */
} plot_axis;

typedef struct plot_series {
    const char *name; /* in the legend (NULL: not listed) */
    const double *x;  /* line charts: the points (x[i], y[i]), drawn in this order */
    const double *y;  /* bar charts: y[c] is this series' bar in category c */
    size_t n;         /* points; bar charts: the number of categories */
    int dashed;       /* a reference curve: dashed, no markers */
    int color;        /* index into plot_color's palette */
} plot_series;

typedef struct plot_chart {
    const char *title;
    plot_axis x, y; /* a bar chart's x axis is its categories: only its label is used */
    const plot_series *series;
    size_t nseries;
    const char *const *categories; /* a bar chart when ncategories > 0 */
    size_t ncategories;
} plot_chart;

/* Colour I of the palette (any I >= 0; it repeats after 8), sRGB in [0, 1]. */
PLOT_HIDDEN void plot_color(int i, float rgb[3]);

/* Where V lies on axis A mapped linearly (log axes: in log10 V) onto
 * [P0, P1], P0 at A->lo and P1 at A->hi; NaN for a value the axis cannot
 * show. Values outside [lo, hi] map outside [P0, P1]. */
PLOT_HIDDEN double plot_axis_pos(const plot_axis *a, double v, double p0, double p1);

/* The tick values of A in increasing order, at most MAX, into T; returns
 * how many. Linear: multiples of 1, 2 or 5 times a power of ten, about 4 to
 * 8 of them. Log: the powers of ten in range, and 2 and 5 times them when
 * the range spans fewer than two decades. */
PLOT_HIDDEN size_t plot_ticks(const plot_axis *a, double *t, size_t max);

/* A tick label for V: plain digits for moderate values, a K or M suffix
 * for large round ones (100000 -> "100K", 2000000 -> "2M"). */
PLOT_HIDDEN void plot_tick_label(double v, char *buf, size_t size);

/* Sets both axes' ranges from the data shown: a linear axis from 0 (or
 * below, for negative data) up to its largest value plus a margin, rounded
 * to a tick; a log axis from the largest 1, 2 or 5 times a power of ten at
 * or below the smallest positive value to the smallest one at or above the
 * largest (a decade if they are equal).
 * A bar chart's value axis always includes the bars' base. Axes with no
 * showable value get [0, 1] (log: [1, 10]). */
PLOT_HIDDEN void plot_fit_axes(plot_chart *c);

/* The plot area of C on a WIDTH x HEIGHT image, in continuous pixel
 * coordinates (x0 < x1 left to right, y0 < y1 top to bottom): where the axes'
 * ranges map (x: lo at x0; y: lo at y1). A value V of series S lies at
 * plot_axis_pos(&c->x, x, x0, x1), plot_axis_pos(&c->y, y, y1, y0); the bar
 * of series S in category K spans [x0 + (K + 0.1 + 0.8 S / nseries) W,
 * ... + 0.8 W / nseries) with W = (x1 - x0) / ncategories. Returns 0 when
 * the image is too small for the text, and the area is then the whole image
 * but for a margin (plot_draw then draws the data and the frame only). */
typedef struct plot_rect {
    double x0, y0, x1, y1;
} plot_rect;
PLOT_HIDDEN int plot_layout(const plot_chart *c, int width, int height, plot_rect *r);

/* The chart drawn on a new WIDTH x HEIGHT white image (at least 240 x 160);
 * NULL when out of memory or the size is outside that range or above
 * 8192 x 8192. */
PLOT_HIDDEN bsp_image *plot_draw(const plot_chart *c, int width, int height);

/* The chart written as a PNG file at PATH (errors name the file). */
PLOT_HIDDEN bsp_status plot_write_png(const plot_chart *c, int width, int height,
                                      const char *path, bsp_error *err);

#endif /* BSPRAY_RENDER_PLOT_H */
