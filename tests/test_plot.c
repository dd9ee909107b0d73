/*
 * test_plot.c — the benchmarks' charts (src/render/plot.c): axis mapping,
 * ticks, labels and ranges against hand-computed values; the pixels of drawn
 * markers and bars where the layout puts them; bad data and sizes.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bspray/bspray.h"
#include "harness.h"
#include "render/plot.h"

TEST(plot_axis_maps_linear_and_log_values)
{
    plot_axis lin = {NULL, 0, 0.0, 10.0};
    CHECK_NEAR(plot_axis_pos(&lin, 2.5, 100.0, 500.0), 200.0, 1e-12);
    CHECK_NEAR(plot_axis_pos(&lin, 0.0, 100.0, 500.0), 100.0, 1e-12);
    CHECK_NEAR(plot_axis_pos(&lin, 10.0, 500.0, 100.0), 100.0, 1e-12); /* reversed (y down) */
    CHECK_NEAR(plot_axis_pos(&lin, -5.0, 100.0, 500.0), -100.0, 1e-12); /* outside: outside */
    CHECK(isnan(plot_axis_pos(&lin, NAN, 0.0, 1.0)));
    CHECK(isnan(plot_axis_pos(&lin, INFINITY, 0.0, 1.0)));
    plot_axis lg = {NULL, 1, 10.0, 1e4};
    /* log10 100 = 2 is a third of the way from 1 to 4 */
    CHECK_NEAR(plot_axis_pos(&lg, 100.0, 0.0, 300.0), 100.0, 1e-9);
    CHECK_NEAR(plot_axis_pos(&lg, 1e4, 0.0, 300.0), 300.0, 1e-9);
    CHECK(isnan(plot_axis_pos(&lg, 0.0, 0.0, 300.0)));
    CHECK(isnan(plot_axis_pos(&lg, -3.0, 0.0, 300.0)));
    plot_axis bad = {NULL, 0, 1.0, 1.0}; /* an empty range shows nothing */
    CHECK(isnan(plot_axis_pos(&bad, 1.0, 0.0, 1.0)));
}

TEST(plot_ticks_are_round_values)
{
    double t[32];
    /* [0, 3.5]: a sixth is 0.58, so steps of 0.5 */
    plot_axis a = {NULL, 0, 0.0, 3.5};
    size_t n = plot_ticks(&a, t, 32);
    CHECK_EQ_INT(n, 8);
    for (size_t i = 0; i < n; i++)
        CHECK_NEAR(t[i], 0.5 * (double)i, 1e-12);
    /* [-20, 100]: a sixth is 20: steps of 20, zero exactly */
    plot_axis b = {NULL, 0, -20.0, 100.0};
    n = plot_ticks(&b, t, 32);
    CHECK_EQ_INT(n, 7);
    CHECK_NEAR(t[0], -20.0, 1e-12);
    CHECK(t[1] == 0.0);
    CHECK_NEAR(t[6], 100.0, 1e-12);
    /* log over three decades: the powers of ten */
    plot_axis c = {NULL, 1, 10.0, 1e4};
    n = plot_ticks(&c, t, 32);
    CHECK_EQ_INT(n, 4);
    CHECK_NEAR(t[0], 10.0, 1e-9);
    CHECK_NEAR(t[3], 1e4, 1e-6);
    /* log under two decades: 1, 2, 5 per decade */
    plot_axis d = {NULL, 1, 1.0, 50.0};
    n = plot_ticks(&d, t, 32);
    const double want[] = {1, 2, 5, 10, 20, 50};
    CHECK_EQ_INT(n, 6);
    for (size_t i = 0; i < n && i < 6; i++)
        CHECK_NEAR(t[i], want[i], 1e-9);
    /* MAX bounds the count; a broken axis has none */
    CHECK_EQ_INT(plot_ticks(&a, t, 3), 3);
    plot_axis e = {NULL, 1, -1.0, 10.0};
    CHECK_EQ_INT(plot_ticks(&e, t, 32), 0);
    plot_axis f = {NULL, 0, 5.0, 5.0};
    CHECK_EQ_INT(plot_ticks(&f, t, 32), 0);
}

TEST(plot_tick_labels_are_short)
{
    char buf[32];
    plot_tick_label(100000.0, buf, sizeof buf);
    CHECK(!strcmp(buf, "100K"));
    plot_tick_label(2e6, buf, sizeof buf);
    CHECK(!strcmp(buf, "2M"));
    plot_tick_label(1500.0, buf, sizeof buf); /* not a whole thousand */
    CHECK(!strcmp(buf, "1500"));
    plot_tick_label(0.5, buf, sizeof buf);
    CHECK(!strcmp(buf, "0.5"));
    plot_tick_label(0.0, buf, sizeof buf);
    CHECK(!strcmp(buf, "0"));
}

TEST(plot_fit_axes_from_the_data)
{
    /* the scaling chart: N on a log axis, us per primitive from 0 */
    const double x[] = {92, 828, 7382}, y[] = {0.68, 0.70, 2.04};
    plot_series s = {"A", x, y, 3, 0, 0};
    plot_chart c = {NULL, {NULL, 1, 0, 0}, {NULL, 0, 0, 0}, &s, 1, NULL, 0};
    plot_fit_axes(&c);
    /* 92 lies in [50, 100), 7382 in (5000, 10000] */
    CHECK_NEAR(c.x.lo, 50.0, 1e-9);
    CHECK_NEAR(c.x.hi, 1e4, 1e-6);
    /* 2.04 plus 8 % is 2.2032; a sixth of that is 0.37: steps of 0.5, up to 2.5 */
    CHECK(c.y.lo == 0.0);
    CHECK_NEAR(c.y.hi, 2.5, 1e-12);
    /* a bar chart on a log axis: 1, 2, 5 steps around the bars; NaN and 0 are no bars */
    const double t[] = {0.013, NAN, 4.2, 0.0};
    plot_series b = {"B", NULL, t, 4, 0, 0};
    const char *cats[] = {"a", "b", "c", "d"};
    plot_chart d = {NULL, {NULL, 0, 0, 0}, {NULL, 1, 0, 0}, &b, 1, cats, 4};
    plot_fit_axes(&d);
    CHECK_NEAR(d.y.lo, 0.01, 1e-12);
    CHECK_NEAR(d.y.hi, 5.0, 1e-9);
    /* exact round values are their own bounds; one value: a decade from it */
    const double one[] = {200.0};
    plot_series o = {"O", one, one, 1, 0, 0};
    plot_chart g = {NULL, {NULL, 1, 0, 0}, {NULL, 1, 0, 0}, &o, 1, NULL, 0};
    plot_fit_axes(&g);
    CHECK_NEAR(g.x.lo, 200.0, 1e-9);
    CHECK_NEAR(g.x.hi, 2000.0, 1e-9);
    /* no showable value at all: a default range, never NaN */
    const double none[] = {NAN, -1.0};
    plot_series z = {"Z", none, none, 2, 0, 0};
    plot_chart e = {NULL, {NULL, 1, 0, 0}, {NULL, 1, 0, 0}, &z, 1, NULL, 0};
    plot_fit_axes(&e);
    CHECK(e.x.lo == 1.0 && e.x.hi == 10.0 && e.y.lo == 1.0 && e.y.hi == 10.0);
}

static const float *pixel(const bsp_image *img, double x, double y)
{
    int i = (int)floor(x), j = (int)floor(y);
    if (i < 0 || j < 0 || i >= img->width || j >= img->height)
        return NULL;
    return img->rgb + 3 * ((size_t)j * (size_t)img->width + (size_t)i);
}

static int is_color(const float *px, const float rgb[3])
{
    return px && fabsf(px[0] - rgb[0]) < 1e-6f && fabsf(px[1] - rgb[1]) < 1e-6f &&
           fabsf(px[2] - rgb[2]) < 1e-6f;
}

TEST(plot_markers_lie_where_the_layout_maps_them)
{
    const double x[] = {100, 1000, 10000}, y[] = {1.0, 3.0, 2.0};
    plot_series s = {"SERIES", x, y, 3, 0, 2};
    plot_chart c = {"TITLE", {"N", 1, 10.0, 1e5}, {"VALUE", 0, 0.0, 4.0}, &s, 1, NULL, 0};
    bsp_image *img = plot_draw(&c, 640, 480);
    REQUIRE(img);
    CHECK_EQ_INT(img->width, 640);
    CHECK_EQ_INT(img->height, 480);
    plot_rect r;
    CHECK(plot_layout(&c, 640, 480, &r));
    CHECK(r.x0 > 0 && r.x1 < 640 && r.y0 > 0 && r.y1 < 480);
    float rgb[3];
    plot_color(2, rgb);
    for (int i = 0; i < 3; i++) {
        /* by hand: log10 x in [1, 5] and y in [0, 4] over the plot area */
        double px = r.x0 + (log10(x[i]) - 1.0) / 4.0 * (r.x1 - r.x0);
        double py = r.y1 - y[i] / 4.0 * (r.y1 - r.y0);
        CHECK_MSG(is_color(pixel(img, px, py), rgb), "marker %d not at (%.1f, %.1f)", i, px, py);
    }
    /* nothing of the series' colour far from its line: the top-right corner */
    CHECK(!is_color(pixel(img, r.x1 - 3, r.y0 + 3), rgb));
    /* the background is white, the frame dark */
    const float white[3] = {1, 1, 1};
    CHECK(is_color(pixel(img, 1, 1), white));
    CHECK(pixel(img, r.x0, (r.y0 + r.y1) / 2)[0] < 0.5f);
    bsp_image_destroy(img);
}

TEST(plot_bars_have_heights_of_their_values)
{
    /* one category, two series on a log axis [1, 1000]: log10 100 = 2 and
     * log10 10 = 1, so the first bar is twice as tall as the second */
    const double a[] = {100.0}, b[] = {10.0};
    plot_series s[2] = {{"A", NULL, a, 1, 0, 0}, {"B", NULL, b, 1, 0, 1}};
    const char *cats[] = {"ONE"};
    plot_chart c = {"BARS", {"SCENE", 0, 0, 0}, {"SECONDS", 1, 1.0, 1000.0}, s, 2, cats, 1};
    bsp_image *img = plot_draw(&c, 480, 360);
    REQUIRE(img);
    plot_rect r;
    REQUIRE(plot_layout(&c, 480, 360, &r));
    const double w = r.x1 - r.x0;
    int height[2] = {0, 0};
    for (int k = 0; k < 2; k++) {
        float rgb[3];
        plot_color(k, rgb);
        double mid = r.x0 + (0.1 + 0.8 * (k + 0.5) / 2.0) * w; /* the bar's centre column */
        for (int y = 0; y < img->height; y++)
            height[k] += is_color(pixel(img, mid, y + 0.5), rgb);
        /* the bar stands on the axis: its foot is the plot area's bottom */
        CHECK(is_color(pixel(img, mid, r.y1 - 1.5), rgb));
    }
    const double ph = r.y1 - r.y0;
    CHECK_NEAR(height[0], 2.0 / 3.0 * ph, 2.5);
    CHECK_NEAR(height[1], 1.0 / 3.0 * ph, 2.5);
    bsp_image_destroy(img);
}

TEST(plot_survives_bad_data_and_sizes)
{
    const double x[] = {NAN, -1.0, 0.0, INFINITY, 1e300, 5.0};
    const double y[] = {INFINITY, NAN, -1e300, 2.0, 3.0, -0.0};
    plot_series s[2] = {{"X", x, y, 6, 0, 0}, {"Y", x, y, 6, 1, 1}};
    plot_chart c = {"BAD", {"X", 1, 0, 0}, {"Y", 0, 0, 0}, s, 2, NULL, 0};
    plot_fit_axes(&c);
    CHECK(isfinite(c.x.lo) && isfinite(c.x.hi) && c.x.lo < c.x.hi);
    CHECK(isfinite(c.y.lo) && isfinite(c.y.hi) && c.y.lo < c.y.hi);
    bsp_image *img = plot_draw(&c, 300, 200);
    REQUIRE(img);
    bsp_image_destroy(img);
    /* the smallest size: the data and the frame, no text */
    plot_rect r;
    CHECK(!plot_layout(&c, 240, 160, &r) || (r.x1 - r.x0 >= 40 && r.y1 - r.y0 >= 40));
    img = plot_draw(&c, 240, 160);
    REQUIRE(img);
    bsp_image_destroy(img);
    CHECK(plot_draw(&c, 100, 100) == NULL);
    CHECK(plot_draw(&c, 9000, 300) == NULL);
    bsp_error err;
    char path[512];
    snprintf(path, sizeof path, "%s/no/such/dir/chart.png", harness_tmpdir());
    CHECK(plot_write_png(&c, 320, 240, path, &err) != BSP_OK);
    CHECK_STR_CONTAINS(err.message, "chart.png");
    /* and a good one reads back as the size asked for */
    snprintf(path, sizeof path, "%s/chart.png", harness_tmpdir());
    REQUIRE(plot_write_png(&c, 320, 240, path, &err) == BSP_OK);
    bsp_image *back = NULL;
    REQUIRE(bsp_image_read_png(path, &back, &err) == BSP_OK);
    CHECK_EQ_INT(back->width, 320);
    CHECK_EQ_INT(back->height, 240);
    bsp_image_destroy(back);
}
