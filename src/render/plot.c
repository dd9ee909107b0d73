/*
 * plot.c — line and bar charts (plot.h), drawn with draw.h's lines,
 * rectangles and bitmap font.
 *
 * Layout, from the top: the title, the value axis's label, the plot area
 * (grid, data, frame), the tick labels of the horizontal axis, its label,
 * and the legend in rows below it, so that no legend ever hides data.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "render/draw.h"
#include "render/plot.h"
#include "scene/scene_internal.h"

#define TEXT_SCALE 2 /* font dots per pixel for titles, labels and the legend */
#define PAD 14       /* pixels between the blocks of the layout */
#define MAX_TICKS 32
#define MAX_SIDE 8192

static const float ink[3] = {0.10f, 0.10f, 0.12f};
static const float grid_grey[3] = {0.86f, 0.86f, 0.88f};

void plot_color(int i, float rgb[3])
{
    /* distinguishable on white, and in grey print by lightness */
    static const float palette[8][3] = {
        {0.12f, 0.38f, 0.72f}, {0.85f, 0.37f, 0.05f}, {0.17f, 0.59f, 0.23f},
        {0.75f, 0.15f, 0.20f}, {0.50f, 0.32f, 0.67f}, {0.55f, 0.35f, 0.25f},
        {0.85f, 0.40f, 0.70f}, {0.45f, 0.45f, 0.45f},
    };
    const float *p = palette[(i < 0 ? -i : i) % 8];
    rgb[0] = p[0];
    rgb[1] = p[1];
    rgb[2] = p[2];
}

/* --- axes -------------------------------------------------------------------------- */

static int showable(const plot_axis *a, double v)
{
    return isfinite(v) && (!a->log || v > 0.0);
}

double plot_axis_pos(const plot_axis *a, double v, double p0, double p1)
{
    if (!showable(a, v) || !(a->hi > a->lo) || (a->log && !(a->lo > 0.0)))
        return NAN;
    double f = a->log ? (log10(v) - log10(a->lo)) / (log10(a->hi) - log10(a->lo))
                      : (v - a->lo) / (a->hi - a->lo);
    return p0 + f * (p1 - p0);
}

/* The linear tick step for [LO, HI]: 1, 2 or 5 times a power of ten, about
 * a sixth of the range. */
static double linear_step(double lo, double hi)
{
    double raw = (hi - lo) / 6.0;
    if (!(raw > 0.0) || !isfinite(raw))
        return 1.0;
    double mag = pow(10.0, floor(log10(raw)));
    double f = raw / mag;
    return (f < 1.5 ? 1.0 : f < 3.5 ? 2.0 : f < 7.5 ? 5.0 : 10.0) * mag;
}

size_t plot_ticks(const plot_axis *a, double *t, size_t max)
{
    size_t n = 0;
    if (!(a->hi > a->lo) || !isfinite(a->lo) || !isfinite(a->hi))
        return 0;
    if (!a->log) {
        double step = linear_step(a->lo, a->hi);
        double first = ceil(a->lo / step - 1e-9);
        for (double i = first; n < max; i += 1.0) {
            double v = i * step; /* a multiple, not a running sum: no drift */
            if (v > a->hi + step * 1e-9)
                break;
            t[n++] = fabs(v) < step * 1e-9 ? 0.0 : v;
        }
        return n;
    }
    if (!(a->lo > 0.0))
        return 0;
    const double l0 = log10(a->lo), l1 = log10(a->hi);
    const int fine = l1 - l0 < 2.0; /* under two decades: 1, 2, 5 per decade */
    const int e0 = (int)floor(l0 + 1e-9), e1 = (int)floor(l1 + 1e-9);
    const int every = fine ? 1 : 1 + (e1 - e0) / 10; /* at most about 10 powers */
    static const double mant[3] = {1.0, 2.0, 5.0};
    for (int e = e0; e <= e1 && n < max; e++) {
        if (!fine && (e - e0) % every != 0)
            continue;
        for (int k = 0; k < (fine ? 3 : 1) && n < max; k++) {
            double v = mant[k] * pow(10.0, e);
            if (v >= a->lo * (1.0 - 1e-9) && v <= a->hi * (1.0 + 1e-9))
                t[n++] = v;
        }
    }
    return n;
}

void plot_tick_label(double v, char *buf, size_t size)
{
    double av = fabs(v);
    if (av >= 1e6 && fabs(v / 1e6 - nearbyint(v / 1e6)) < 1e-9)
        snprintf(buf, size, "%gM", v / 1e6);
    else if (av >= 1e3 && fabs(v / 1e3 - nearbyint(v / 1e3)) < 1e-9)
        snprintf(buf, size, "%gK", v / 1e3);
    else
        snprintf(buf, size, "%g", v);
}

/* The smallest and largest showable values of the chart on axis A: the x
 * values (WHICH 0) or the y values (1). 0 when there is none. */
static int data_range(const plot_chart *c, const plot_axis *a, int which, double *mn,
                      double *mx)
{
    int any = 0;
    for (size_t s = 0; s < c->nseries; s++) {
        const plot_series *sr = &c->series[s];
        const double *v = which ? sr->y : sr->x;
        if (!v)
            continue;
        for (size_t i = 0; i < sr->n; i++) {
            if (!showable(a, v[i]))
                continue;
            if (!any || v[i] < *mn)
                *mn = v[i];
            if (!any || v[i] > *mx)
                *mx = v[i];
            any = 1;
        }
    }
    return any;
}

/* The largest of 1, 2, 5 times a power of ten at or below V > 0 (UP: the
 * smallest at or above it). */
static double round_125(double v, int up)
{
    const double m[3] = {1.0, 2.0, 5.0};
    double p = pow(10.0, floor(log10(v)));
    if (!up) {
        double best = p;
        for (int k = 1; k < 3; k++)
            if (m[k] * p <= v * (1.0 + 1e-12))
                best = m[k] * p;
        return best;
    }
    for (int k = 0; k < 3; k++)
        if (m[k] * p >= v * (1.0 - 1e-12))
            return m[k] * p;
    return 10.0 * p;
}

static void fit_axis(const plot_chart *c, plot_axis *a, int which, int from_zero)
{
    double mn = 0.0, mx = 0.0;
    if (!data_range(c, a, which, &mn, &mx)) {
        a->lo = a->log ? 1.0 : 0.0;
        a->hi = a->log ? 10.0 : 1.0;
        return;
    }
    if (a->log) {
        a->lo = round_125(mn, 0);
        a->hi = round_125(mx, 1);
        if (!(a->hi > a->lo))
            a->hi = a->lo * 10.0;
        return;
    }
    if (from_zero && mn > 0.0)
        mn = 0.0;
    if (from_zero && mx < 0.0)
        mx = 0.0;
    if (!(mx > mn))
        mx = mn + (mn != 0.0 ? fabs(mn) : 1.0);
    double hi = mx + 0.08 * (mx - mn);
    double step = linear_step(mn, hi);
    a->hi = ceil(hi / step - 1e-9) * step;
    a->lo = mn < 0.0 ? floor(mn / step + 1e-9) * step : mn;
}

void plot_fit_axes(plot_chart *c)
{
    if (c->ncategories == 0)
        fit_axis(c, &c->x, 0, 1);
    fit_axis(c, &c->y, 1, 1);
}

/* --- drawing helpers -------------------------------------------------------------------- */

typedef plot_rect rect;

/* Liang-Barsky clip of the segment to R; 0 when nothing is left. */
static int clip_to(const rect *r, double *ax, double *ay, double *bx, double *by)
{
    double t0 = 0.0, t1 = 1.0, dx = *bx - *ax, dy = *by - *ay;
    const double p[4] = {-dx, dx, -dy, dy};
    const double q[4] = {*ax - r->x0, r->x1 - *ax, *ay - r->y0, r->y1 - *ay};
    for (int i = 0; i < 4; i++) {
        if (p[i] == 0.0) {
            if (q[i] < 0.0)
                return 0;
            continue;
        }
        double u = q[i] / p[i];
        if (p[i] < 0.0) {
            if (u > t1)
                return 0;
            if (u > t0)
                t0 = u;
        } else {
            if (u < t0)
                return 0;
            if (u < t1)
                t1 = u;
        }
    }
    double x0 = *ax + t0 * dx, y0 = *ay + t0 * dy;
    *bx = *ax + t1 * dx;
    *by = *ay + t1 * dy;
    *ax = x0;
    *ay = y0;
    return 1;
}

/* A line two pixels wide. */
static void thick_line(bsp_image *img, double ax, double ay, double bx, double by,
                       const float rgb[3])
{
    int steep = fabs(by - ay) > fabs(bx - ax);
    for (int o = 0; o < 2; o++)
        draw_line(img, ax + (steep ? o : 0), ay + (steep ? 0 : o), bx + (steep ? o : 0),
                  by + (steep ? 0 : o), rgb, 1.0f);
}

/* A dashed line (9 pixels on, 6 off), the pattern continued from *PHASE
 * (pixels along the pattern) across a polyline's segments. */
static void dashed_line(bsp_image *img, double ax, double ay, double bx, double by,
                        const float rgb[3], double *phase)
{
    const double on = 9.0, period = 15.0;
    double len = hypot(bx - ax, by - ay);
    if (!(len > 0.0) || !isfinite(len))
        return;
    double at = 0.0;
    while (at < len) {
        double p = fmod(*phase + at, period);
        double run = p < on ? on - p : period - p; /* to the pattern's next change */
        double end = at + run < len ? at + run : len;
        if (p < on)
            thick_line(img, ax + (bx - ax) * at / len, ay + (by - ay) * at / len,
                       ax + (bx - ax) * end / len, ay + (by - ay) * end / len, rgb);
        at = end;
    }
    *phase = fmod(*phase + len, period);
}

/* TEXT in upper case (the font's) centred on X, top at Y. */
static void text_centred(bsp_image *img, double x, int y, int scale, const char *text)
{
    draw_text(img, (int)lround(x - draw_text_width(text, scale) / 2.0), y, scale, text, ink);
}

/* --- the legend ---------------------------------------------------------------------------- */

#define SWATCH 28

static int legend_entry_width(const plot_series *s)
{
    return SWATCH + 8 + draw_text_width(s->name, TEXT_SCALE) + 26;
}

/* Lays the legend out in rows within WIDTH - 2 PAD; draws it with its top at
 * Y when IMG is given. Returns its height (0: no named series). */
static int legend(bsp_image *img, const plot_chart *c, int width, int y, int bars)
{
    const int row_h = DRAW_TEXT_HEIGHT(TEXT_SCALE) + 8;
    int x = PAD, rows = 0;
    for (size_t s = 0; s < c->nseries; s++) {
        const plot_series *sr = &c->series[s];
        if (!sr->name)
            continue;
        int w = legend_entry_width(sr);
        if (rows == 0 || (x + w > width - PAD && x > PAD)) {
            rows++;
            x = PAD;
        }
        if (img) {
            float rgb[3];
            plot_color(sr->color, rgb);
            int top = y + (rows - 1) * row_h, mid = top + DRAW_TEXT_HEIGHT(TEXT_SCALE) / 2 - 1;
            if (bars) {
                draw_fill_rect(img, x, top, x + SWATCH, top + DRAW_TEXT_HEIGHT(TEXT_SCALE) - 2,
                               rgb, 1.0f);
            } else if (sr->dashed) {
                double phase = 0.0;
                dashed_line(img, x, mid, x + SWATCH, mid, rgb, &phase);
            } else {
                thick_line(img, x, mid, x + SWATCH, mid, rgb);
                draw_fill_rect(img, x + SWATCH / 2 - 3, mid - 3, x + SWATCH / 2 + 4, mid + 4, rgb,
                               1.0f);
            }
            draw_text(img, x + SWATCH + 8, top, TEXT_SCALE, sr->name, ink);
        }
        x += w;
    }
    return rows * row_h;
}

/* --- the chart ------------------------------------------------------------------------------ */

static void draw_lines(bsp_image *img, const plot_chart *c, const rect *r)
{
    for (size_t s = 0; s < c->nseries; s++) {
        const plot_series *sr = &c->series[s];
        if (!sr->x || !sr->y)
            continue;
        float rgb[3];
        plot_color(sr->color, rgb);
        double phase = 0.0, px = NAN, py = NAN;
        for (size_t i = 0; i < sr->n; i++) {
            double x = plot_axis_pos(&c->x, sr->x[i], r->x0, r->x1);
            double y = plot_axis_pos(&c->y, sr->y[i], r->y1, r->y0);
            if (isnan(x) || isnan(y)) {
                px = py = NAN; /* the line breaks */
                continue;
            }
            double ax = px, ay = py, bx = x, by = y;
            if (!isnan(px) && clip_to(r, &ax, &ay, &bx, &by)) {
                if (sr->dashed)
                    dashed_line(img, ax, ay, bx, by, rgb, &phase);
                else
                    thick_line(img, ax, ay, bx, by, rgb);
            }
            px = x;
            py = y;
        }
        if (sr->dashed)
            continue;
        for (size_t i = 0; i < sr->n; i++) { /* markers on top of the lines */
            double x = plot_axis_pos(&c->x, sr->x[i], r->x0, r->x1);
            double y = plot_axis_pos(&c->y, sr->y[i], r->y1, r->y0);
            if (isnan(x) || isnan(y) || x < r->x0 || x > r->x1 || y < r->y0 || y > r->y1)
                continue;
            draw_fill_rect(img, x - 4, y - 4, x + 5, y + 5, ink, 1.0f);
            draw_fill_rect(img, x - 3, y - 3, x + 4, y + 4, rgb, 1.0f);
        }
    }
}

/* The width of a category's group of bars. */
static double group_width(const plot_chart *c, const rect *r)
{
    return (r->x1 - r->x0) / (double)c->ncategories;
}

static void draw_bars(bsp_image *img, const plot_chart *c, const rect *r)
{
    const double gw = group_width(c, r), inner = 0.8 * gw;
    const double bw = c->nseries ? inner / (double)c->nseries : inner;
    /* the bars' base: the axis's low end, or 0 on a linear axis that shows it */
    double base = r->y1;
    if (!c->y.log) {
        double z = plot_axis_pos(&c->y, 0.0, r->y1, r->y0);
        base = z < r->y0 ? r->y0 : z > r->y1 ? r->y1 : z;
    }
    for (size_t s = 0; s < c->nseries; s++) {
        const plot_series *sr = &c->series[s];
        if (!sr->y)
            continue;
        float rgb[3];
        plot_color(sr->color, rgb);
        for (size_t k = 0; k < sr->n && k < c->ncategories; k++) {
            double y = plot_axis_pos(&c->y, sr->y[k], r->y1, r->y0);
            if (isnan(y))
                continue;
            y = y < r->y0 ? r->y0 : y > r->y1 ? r->y1 : y;
            double x0 = r->x0 + (double)k * gw + 0.1 * gw + (double)s * bw;
            double top = y < base ? y : base, bottom = y < base ? base : y;
            draw_fill_rect(img, x0, top, x0 + bw - 1.0, bottom, rgb, 1.0f);
        }
    }
}

/* The categories' names under their groups: at the text scale when every one
 * fits its group, else at scale 1, cut to fit. */
static void draw_categories(bsp_image *img, const plot_chart *c, const rect *r, int y)
{
    const double gw = group_width(c, r);
    int scale = TEXT_SCALE;
    for (size_t k = 0; k < c->ncategories; k++)
        if (c->categories[k] && draw_text_width(c->categories[k], TEXT_SCALE) > gw - 4)
            scale = 1;
    for (size_t k = 0; k < c->ncategories; k++) {
        if (!c->categories[k])
            continue;
        char name[128];
        snprintf(name, sizeof name, "%s", c->categories[k]);
        size_t len = strlen(name);
        while (len > 1 && draw_text_width(name, scale) > gw - 2)
            name[--len] = 0;
        text_centred(img, r->x0 + ((double)k + 0.5) * gw, y, scale, name);
    }
}

/* The widest tick label of axis A. */
static int widest_tick_label(const plot_axis *a)
{
    double t[MAX_TICKS];
    size_t n = plot_ticks(a, t, MAX_TICKS);
    int w = 0;
    char buf[64];
    for (size_t i = 0; i < n; i++) {
        plot_tick_label(t[i], buf, sizeof buf);
        int tw = draw_text_width(buf, TEXT_SCALE);
        w = tw > w ? tw : w;
    }
    return w;
}

int plot_layout(const plot_chart *c, int width, int height, plot_rect *r)
{
    const int th = DRAW_TEXT_HEIGHT(TEXT_SCALE);
    const int legend_h = legend(NULL, c, width, 0, c->ncategories > 0);
    r->x0 = PAD + widest_tick_label(&c->y) + 10;
    r->x1 = width - 2 * PAD;
    r->y0 = PAD + (c->title ? th + PAD : 0) + (c->y.label ? th + 8 : 0);
    r->y1 = height - (PAD + th + (c->x.label ? 8 + th : 0) + (legend_h ? PAD + legend_h : 0) + PAD);
    if (r->x1 - r->x0 >= 40.0 && r->y1 - r->y0 >= 40.0)
        return 1;
    *r = (plot_rect){PAD, PAD, width - PAD, height - PAD};
    return 0;
}

bsp_image *plot_draw(const plot_chart *c, int width, int height)
{
    if (width < 240 || height < 160 || width > MAX_SIDE || height > MAX_SIDE)
        return NULL;
    bsp_image *img = bsp_image_create(width, height);
    if (!img)
        return NULL;
    for (size_t i = 0; i < (size_t)width * (size_t)height * 3; i++)
        img->rgb[i] = 1.0f;
    const int bars = c->ncategories > 0;
    const int th = DRAW_TEXT_HEIGHT(TEXT_SCALE);
    rect r;
    const int text = plot_layout(c, width, height, &r); /* 0: no room for text */
    double yt[MAX_TICKS], xt[MAX_TICKS];
    const size_t nyt = text ? plot_ticks(&c->y, yt, MAX_TICKS) : 0;
    const size_t nxt = text && !bars ? plot_ticks(&c->x, xt, MAX_TICKS) : 0;
    char buf[64];

    /* grid and tick labels */
    for (size_t i = 0; i < nyt; i++) {
        double y = lround(plot_axis_pos(&c->y, yt[i], r.y1, r.y0));
        draw_line(img, r.x0, y, r.x1, y, grid_grey, 1.0f);
        plot_tick_label(yt[i], buf, sizeof buf);
        draw_text(img, (int)r.x0 - 10 - draw_text_width(buf, TEXT_SCALE), (int)y - th / 2 + 1,
                  TEXT_SCALE, buf, ink);
    }
    for (size_t i = 0; i < nxt; i++) {
        double x = lround(plot_axis_pos(&c->x, xt[i], r.x0, r.x1));
        draw_line(img, x, r.y0, x, r.y1, grid_grey, 1.0f);
        plot_tick_label(xt[i], buf, sizeof buf);
        text_centred(img, x, (int)r.y1 + 8, TEXT_SCALE, buf);
    }
    if (bars && text)
        draw_categories(img, c, &r, (int)r.y1 + 8);

    if (bars)
        draw_bars(img, c, &r);
    else
        draw_lines(img, c, &r);
    draw_frame(img, (int)r.x0, (int)r.y0, (int)r.x1, (int)r.y1, ink, 1.0f);

    /* the text around the plot area (none when it had no room) */
    if (text) {
        int y = PAD;
        if (c->title) {
            text_centred(img, width / 2.0, y, TEXT_SCALE, c->title);
            y += th + PAD;
        }
        if (c->y.label)
            draw_text(img, (int)r.x0, y, TEXT_SCALE, c->y.label, ink);
        int below = (int)r.y1 + 8 + th + 8;
        if (c->x.label) {
            text_centred(img, (r.x0 + r.x1) / 2.0, below, TEXT_SCALE, c->x.label);
            below += th;
        }
        legend(img, c, width, below + PAD, bars);
    }
    return img;
}

bsp_status plot_write_png(const plot_chart *c, int width, int height, const char *path,
                          bsp_error *err)
{
    bsp_image *img = plot_draw(c, width, height);
    if (!img)
        return error_set(err, BSP_ERR_NOMEM, path, 0,
                         "cannot draw a %d x %d chart (out of memory, or not between 240 x 160 "
                         "and %d x %d)",
                         width, height, MAX_SIDE, MAX_SIDE);
    bsp_status st = bsp_image_write_png(img, path, err);
    bsp_image_destroy(img);
    return st;
}
