/*
 * draw.c — raster drawing for the kd-tree pictures of `bspray viz`
 * (see draw.h for the pixel convention and the promise never to write
 * outside an image).
 *
 * Lines are clipped to the image rectangle in continuous coordinates
 * (Liang–Barsky) before they are turned into integers, so huge or far
 * off-screen coordinates cost nothing and cannot overflow; Bresenham's
 * integer walk then visits each pixel of the line once. 3D segments are
 * clipped against the camera's near plane before projection, so a segment
 * passing behind the eye is drawn only where it is in front.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "geom/vec.h"
#include "render/draw.h"

/* --- 2D raster helpers -------------------------------------------------------------- */

void draw_blend(bsp_image *img, int x, int y, const float rgb[3], float alpha)
{
    if (x < 0 || y < 0 || x >= img->width || y >= img->height)
        return;
    float *px = img->rgb + 3 * ((size_t)y * (size_t)img->width + (size_t)x);
    for (int c = 0; c < 3; c++)
        px[c] += alpha * (rgb[c] - px[c]);
}

/* Liang–Barsky: shrinks [*T0, *T1] to where P * t <= Q; 0 when empty. */
static int clip_edge(double p, double q, double *t0, double *t1)
{
    if (p == 0)
        return q >= 0;
    double r = q / p;
    if (p < 0) {
        if (r > *t1)
            return 0;
        if (r > *t0)
            *t0 = r;
    } else {
        if (r < *t0)
            return 0;
        if (r < *t1)
            *t1 = r;
    }
    return 1;
}

static int clamp_int(double v, int lo, int hi)
{
    if (!(v >= lo)) /* also NaN */
        return lo;
    if (v > hi)
        return hi;
    return (int)v;
}

void draw_line(bsp_image *img, double x0, double y0, double x1, double y1, const float rgb[3],
               float alpha)
{
    double dx = x1 - x0, dy = y1 - y0;
    if (!isfinite(x0) || !isfinite(y0) || !isfinite(dx) || !isfinite(dy))
        return;
    double t0 = 0, t1 = 1, w = img->width, h = img->height;
    if (!clip_edge(-dx, x0, &t0, &t1) || !clip_edge(dx, w - x0, &t0, &t1) ||
        !clip_edge(-dy, y0, &t0, &t1) || !clip_edge(dy, h - y0, &t0, &t1) || t0 > t1)
        return;
    int ax = clamp_int(floor(x0 + t0 * dx), 0, img->width - 1);
    int ay = clamp_int(floor(y0 + t0 * dy), 0, img->height - 1);
    int bx = clamp_int(floor(x0 + t1 * dx), 0, img->width - 1);
    int by = clamp_int(floor(y0 + t1 * dy), 0, img->height - 1);
    /* Bresenham over the integer endpoints */
    int sx = ax < bx ? 1 : -1, sy = ay < by ? 1 : -1;
    int ex = abs(bx - ax), ey = -abs(by - ay), e = ex + ey;
    for (;;) {
        draw_blend(img, ax, ay, rgb, alpha);
        if (ax == bx && ay == by)
            break;
        int e2 = 2 * e;
        if (e2 >= ey) {
            e += ey;
            ax += sx;
        }
        if (e2 <= ex) {
            e += ex;
            ay += sy;
        }
    }
}

/* The pixel indices [*LO, *HI) whose centres lie in [A, B), within [0, N). */
static void centre_span(double a, double b, int n, int *lo, int *hi)
{
    *lo = clamp_int(ceil(a - 0.5), 0, n);
    *hi = clamp_int(ceil(b - 0.5), 0, n);
}

void draw_fill_rect(bsp_image *img, double x0, double y0, double x1, double y1, const float rgb[3],
                    float alpha)
{
    int xa, xb, ya, yb;
    centre_span(x0, x1, img->width, &xa, &xb);
    centre_span(y0, y1, img->height, &ya, &yb);
    for (int y = ya; y < yb; y++)
        for (int x = xa; x < xb; x++)
            draw_blend(img, x, y, rgb, alpha);
}

void draw_frame(bsp_image *img, int x0, int y0, int x1, int y1, const float rgb[3], float alpha)
{
    for (int x = x0; x <= x1; x++) {
        draw_blend(img, x, y0, rgb, alpha);
        if (y1 != y0)
            draw_blend(img, x, y1, rgb, alpha);
    }
    for (int y = y0 + 1; y < y1; y++) {
        draw_blend(img, x0, y, rgb, alpha);
        if (x1 != x0)
            draw_blend(img, x1, y, rgb, alpha);
    }
}

void draw_paste(bsp_image *dst, const bsp_image *src, int dx, int dy)
{
    for (int y = 0; y < src->height; y++) {
        int ty = y + dy;
        if (ty < 0 || ty >= dst->height)
            continue;
        for (int x = 0; x < src->width; x++) {
            int tx = x + dx;
            if (tx < 0 || tx >= dst->width)
                continue;
            memcpy(dst->rgb + 3 * ((size_t)ty * (size_t)dst->width + (size_t)tx),
                   src->rgb + 3 * ((size_t)y * (size_t)src->width + (size_t)x), 3 * sizeof(float));
        }
    }
}

void draw_fade(bsp_image *img)
{
    size_t n = (size_t)img->width * (size_t)img->height;
    for (size_t i = 0; i < n; i++) {
        float *p = img->rgb + 3 * i;
        float r = fminf(fmaxf(p[0], 0.f), 1.f), g = fminf(fmaxf(p[1], 0.f), 1.f),
              b = fminf(fmaxf(p[2], 0.f), 1.f);
        /* 32 grey levels: a quieter background, and smaller PNG files */
        float lum = floorf((0.2126f * r + 0.7152f * g + 0.0722f * b) * 31.f + 0.5f) / 31.f;
        p[0] = 0.07f + 0.38f * (0.85f * lum + 0.15f * r);
        p[1] = 0.07f + 0.38f * (0.85f * lum + 0.15f * g);
        p[2] = 0.07f + 0.38f * (0.85f * lum + 0.15f * b);
    }
}

void draw_ramp(const float (*stops)[3], int nstops, double t, float rgb[3])
{
    const int last = nstops - 1;
    if (!(t > 0))
        t = 0;
    if (t > 1)
        t = 1;
    double f = t * last;
    int i = (int)f;
    if (i >= last)
        i = last - 1;
    float u = (float)(f - i);
    for (int c = 0; c < 3; c++)
        rgb[c] = stops[i][c] + u * (stops[i + 1][c] - stops[i][c]);
}

void draw_colormap(double t, float rgb[3])
{
    /* shallow to deep: pale yellow, orange, red, magenta, violet, blue */
    static const float stops[][3] = {
        {1.00f, 0.97f, 0.55f}, {1.00f, 0.70f, 0.15f}, {0.95f, 0.30f, 0.20f},
        {0.85f, 0.20f, 0.60f}, {0.55f, 0.30f, 0.95f}, {0.20f, 0.55f, 1.00f},
    };
    draw_ramp(stops, (int)(sizeof stops / sizeof stops[0]), t, rgb);
}

/* --- text ------------------------------------------------------------------------- */

/* 5 x 7 glyphs, one byte per row, bit 4 the leftmost dot. */
typedef struct glyph {
    char ch;
    unsigned char row[7];
} glyph;

static const glyph font[] = {
    {' ', {0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00}},
    {'A', {0x0E, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11}},
    {'B', {0x1E, 0x11, 0x11, 0x1E, 0x11, 0x11, 0x1E}},
    {'C', {0x0E, 0x11, 0x10, 0x10, 0x10, 0x11, 0x0E}},
    {'D', {0x1E, 0x11, 0x11, 0x11, 0x11, 0x11, 0x1E}},
    {'E', {0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x1F}},
    {'F', {0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x10}},
    {'G', {0x0E, 0x11, 0x10, 0x17, 0x11, 0x11, 0x0F}},
    {'H', {0x11, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11}},
    {'I', {0x0E, 0x04, 0x04, 0x04, 0x04, 0x04, 0x0E}},
    {'J', {0x07, 0x02, 0x02, 0x02, 0x02, 0x12, 0x0C}},
    {'K', {0x11, 0x12, 0x14, 0x18, 0x14, 0x12, 0x11}},
    {'L', {0x10, 0x10, 0x10, 0x10, 0x10, 0x10, 0x1F}},
    {'M', {0x11, 0x1B, 0x15, 0x15, 0x11, 0x11, 0x11}},
    {'N', {0x11, 0x11, 0x19, 0x15, 0x13, 0x11, 0x11}},
    {'O', {0x0E, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E}},
    {'P', {0x1E, 0x11, 0x11, 0x1E, 0x10, 0x10, 0x10}},
    {'Q', {0x0E, 0x11, 0x11, 0x11, 0x15, 0x12, 0x0D}},
    {'R', {0x1E, 0x11, 0x11, 0x1E, 0x14, 0x12, 0x11}},
    {'S', {0x0F, 0x10, 0x10, 0x0E, 0x01, 0x01, 0x1E}},
    {'T', {0x1F, 0x04, 0x04, 0x04, 0x04, 0x04, 0x04}},
    {'U', {0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E}},
    {'V', {0x11, 0x11, 0x11, 0x11, 0x11, 0x0A, 0x04}},
    {'W', {0x11, 0x11, 0x11, 0x15, 0x15, 0x15, 0x0A}},
    {'X', {0x11, 0x11, 0x0A, 0x04, 0x0A, 0x11, 0x11}},
    {'Y', {0x11, 0x11, 0x0A, 0x04, 0x04, 0x04, 0x04}},
    {'Z', {0x1F, 0x01, 0x02, 0x04, 0x08, 0x10, 0x1F}},
    {'0', {0x0E, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0E}},
    {'1', {0x04, 0x0C, 0x04, 0x04, 0x04, 0x04, 0x0E}},
    {'2', {0x0E, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1F}},
    {'3', {0x1F, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0E}},
    {'4', {0x02, 0x06, 0x0A, 0x12, 0x1F, 0x02, 0x02}},
    {'5', {0x1F, 0x10, 0x1E, 0x01, 0x01, 0x11, 0x0E}},
    {'6', {0x06, 0x08, 0x10, 0x1E, 0x11, 0x11, 0x0E}},
    {'7', {0x1F, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08}},
    {'8', {0x0E, 0x11, 0x11, 0x0E, 0x11, 0x11, 0x0E}},
    {'9', {0x0E, 0x11, 0x11, 0x0F, 0x01, 0x02, 0x0C}},
    {'-', {0x00, 0x00, 0x00, 0x1F, 0x00, 0x00, 0x00}},
    {'+', {0x00, 0x04, 0x04, 0x1F, 0x04, 0x04, 0x00}},
    {'=', {0x00, 0x00, 0x1F, 0x00, 0x1F, 0x00, 0x00}},
    {'.', {0x00, 0x00, 0x00, 0x00, 0x00, 0x0C, 0x0C}},
    {',', {0x00, 0x00, 0x00, 0x00, 0x0C, 0x04, 0x08}},
    {':', {0x00, 0x0C, 0x0C, 0x00, 0x0C, 0x0C, 0x00}},
    {'(', {0x02, 0x04, 0x08, 0x08, 0x08, 0x04, 0x02}},
    {')', {0x08, 0x04, 0x02, 0x02, 0x02, 0x04, 0x08}},
    {'/', {0x01, 0x01, 0x02, 0x04, 0x08, 0x10, 0x10}},
    {'<', {0x02, 0x04, 0x08, 0x10, 0x08, 0x04, 0x02}},
    {'>', {0x08, 0x04, 0x02, 0x01, 0x02, 0x04, 0x08}},
    {'_', {0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x1F}},
    {'?', {0x0E, 0x11, 0x01, 0x02, 0x04, 0x00, 0x04}},
};

static const glyph *find_glyph(char ch)
{
    if (ch >= 'a' && ch <= 'z')
        ch = (char)(ch - 'a' + 'A');
    const glyph *unknown = NULL;
    for (size_t i = 0; i < sizeof font / sizeof font[0]; i++) {
        if (font[i].ch == ch)
            return &font[i];
        if (font[i].ch == '?')
            unknown = &font[i];
    }
    return unknown;
}

int draw_text_width(const char *text, int scale)
{
    size_t n = strlen(text);
    return n ? (int)(6 * n - 1) * scale : 0;
}

int draw_text(bsp_image *img, int x, int y, int scale, const char *text, const float rgb[3])
{
    for (const char *c = text; *c; c++) {
        const glyph *g = find_glyph(*c);
        int gx = x + (int)(c - text) * 6 * scale;
        for (int r = 0; r < 7; r++)
            for (int col = 0; col < 5; col++)
                if (g->row[r] & (0x10 >> col))
                    for (int dy = 0; dy < scale; dy++)
                        for (int dx = 0; dx < scale; dx++)
                            draw_blend(img, gx + col * scale + dx, y + r * scale + dy, rgb, 1.f);
    }
    return draw_text_width(text, scale);
}

int draw_label(bsp_image *img, int x, int y, int scale, const char *text)
{
    static const float black[3] = {0, 0, 0}, white[3] = {1, 1, 1};
    int w = draw_text_width(text, scale) + 2 * scale, h = 7 * scale + 2 * scale;
    draw_fill_rect(img, x, y, x + w, y + h, black, 0.65f);
    draw_text(img, x + scale, y + scale, scale, text, white);
    return h;
}

/* --- projections -------------------------------------------------------------------- */

void draw_pinhole_init(draw_pinhole *p, const bsp_camera *cam, int width, int height, double near)
{
    /* the renderer's basis (src/render/camera.c) */
    p->eye = cam->from;
    p->forward = v3_normalize(v3_sub(cam->at, cam->from));
    p->right = v3_normalize(v3_cross(p->forward, cam->up));
    p->up = v3_cross(p->right, p->forward);
    /* pixel centres: rays 2 tan(angle/2) / width apart on the plane at distance 1 */
    p->focal = (double)width / (2.0 * tan(cam->angle_deg * (BSP_PI / 360.0)));
    p->cx = 0.5 * width;
    p->cy = 0.5 * height;
    p->near = near;
}

/* Camera coordinates of Q: right, up, forward. */
static bsp_vec3 to_camera(const draw_pinhole *p, bsp_vec3 q)
{
    bsp_vec3 d = v3_sub(q, p->eye);
    return bsp_v3(v3_dot(d, p->right), v3_dot(d, p->up), v3_dot(d, p->forward));
}

static void project_camera(const draw_pinhole *p, bsp_vec3 c, double *px, double *py)
{
    *px = p->cx + p->focal * c.x / c.z;
    *py = p->cy - p->focal * c.y / c.z;
}

int draw_pinhole_project(const draw_pinhole *p, bsp_vec3 q, double *px, double *py)
{
    bsp_vec3 c = to_camera(p, q);
    if (!(c.z >= p->near))
        return 0;
    project_camera(p, c, px, py);
    return 1;
}

void draw_segment_3d(bsp_image *img, const draw_pinhole *p, bsp_vec3 a, bsp_vec3 b,
                     const float rgb[3], float alpha)
{
    bsp_vec3 ca = to_camera(p, a), cb = to_camera(p, b);
    int ina = ca.z >= p->near, inb = cb.z >= p->near;
    if (!ina && !inb)
        return;
    if (!ina || !inb) {
        /* move the point behind the plane onto it */
        double t = (p->near - ca.z) / (cb.z - ca.z);
        bsp_vec3 m = v3_add(ca, v3_scale(v3_sub(cb, ca), t));
        m.z = p->near;
        if (!ina)
            ca = m;
        else
            cb = m;
    }
    double x0, y0, x1, y1;
    project_camera(p, ca, &x0, &y0);
    project_camera(p, cb, &x1, &y1);
    draw_line(img, x0, y0, x1, y1, rgb, alpha);
}

void draw_topview_init(draw_topview *tv, const bsp_camera *cam, bsp_box region, int width,
                       int height, int margin)
{
    bsp_vec3 up = cam->up;
    int ua = 0;
    for (int i = 1; i < 3; i++)
        if (fabs(up.v[i]) > fabs(up.v[ua]))
            ua = i;
    double up_sign = up.v[ua] < 0 ? -1.0 : 1.0;
    bsp_vec3 fwd = v3_normalize(v3_sub(cam->at, cam->from));
    bsp_vec3 right = v3_cross(fwd, up);
    int a1 = (ua + 1) % 3, a2 = (ua + 2) % 3;
    int ha = fabs(right.v[a2]) > fabs(right.v[a1]) ? a2 : a1;
    int va = ha == a1 ? a2 : a1;
    tv->up_axis = ua;
    tv->h_axis = ha;
    tv->v_axis = va;
    tv->h_sign = right.v[ha] < 0 ? -1.0 : 1.0;
    /* not mirrored: (h_sign e_h) x (v_sign e_v) points along up; e_h x e_v
     * is +e_up when (h, v, up) is a cyclic order of (x, y, z) */
    double cyclic = (ha + 1) % 3 == va ? 1.0 : -1.0;
    tv->v_sign = up_sign * cyclic * tv->h_sign;
    double hw = region.hi.v[ha] - region.lo.v[ha], vw = region.hi.v[va] - region.lo.v[va];
    double aw = width - 2.0 * margin, ah = height - 2.0 * margin;
    if (aw < 1)
        aw = 1;
    if (ah < 1)
        ah = 1;
    double sh = hw > 0 ? aw / hw : INFINITY, sv = vw > 0 ? ah / vw : INFINITY;
    tv->scale = sh < sv ? sh : sv;
    if (!isfinite(tv->scale))
        tv->scale = 1.0;
    tv->hc = 0.5 * (region.lo.v[ha] + region.hi.v[ha]);
    tv->vc = 0.5 * (region.lo.v[va] + region.hi.v[va]);
    tv->cx = 0.5 * width;
    tv->cy = 0.5 * height;
}

void draw_topview_project(const draw_topview *tv, bsp_vec3 q, double *px, double *py)
{
    *px = tv->cx + tv->h_sign * (q.v[tv->h_axis] - tv->hc) * tv->scale;
    *py = tv->cy - tv->v_sign * (q.v[tv->v_axis] - tv->vc) * tv->scale;
}

/* --- kd-tree cells ------------------------------------------------------------------- */

static int collect_cell(const bsp_cell_info *cell, void *ctx)
{
    draw_cells *c = ctx;
    if (c->count == c->cap) {
        size_t ncap = c->cap ? 2 * c->cap : 256;
        bsp_cell_info *n = realloc(c->cell, ncap * sizeof *n);
        if (!n) {
            c->cap = 0; /* marks the failure */
            return 0;
        }
        c->cell = n;
        c->cap = ncap;
    }
    c->cell[c->count++] = *cell;
    if (cell->depth > c->max_depth)
        c->max_depth = cell->depth;
    if (cell->is_leaf) {
        c->leaves++;
        c->empty += cell->refs == 0;
        if (cell->refs > c->max_refs)
            c->max_refs = cell->refs;
    }
    return 1;
}

bsp_status draw_cells_collect(const bsp_accel *accel, draw_cells *cells, bsp_error *err)
{
    memset(cells, 0, sizeof *cells);
    bsp_status st = bsp_accel_visit_cells(accel, -1, collect_cell, cells, err);
    if (st == BSP_OK && cells->count > 0 && cells->cap == 0)
        st = BSP_ERR_NOMEM;
    if (st == BSP_ERR_NOMEM && err) {
        err->status = st;
        snprintf(err->message, sizeof err->message, "out of memory while collecting tree cells");
    }
    if (st != BSP_OK)
        draw_cells_free(cells);
    return st;
}

void draw_cells_free(draw_cells *cells)
{
    free(cells->cell);
    memset(cells, 0, sizeof *cells);
}

void draw_cell_color(draw_color_mode mode, double value, double scale, float rgb[3])
{
    if (mode == DRAW_COLOR_DEPTH) {
        draw_colormap(scale > 0 ? value / scale : 0.0, rgb);
        return;
    }
    if (!(value > 0)) {
        rgb[0] = rgb[1] = rgb[2] = 0.22f;
        return;
    }
    double t = scale > 0 ? log1p(value) / log1p(scale) : 1.0;
    draw_colormap(1.0 - t, rgb);
}

/* The 8 corners of B: bit 0 x, bit 1 y, bit 2 z (0 lo, 1 hi). */
static bsp_vec3 box_corner(bsp_box b, int k)
{
    return bsp_v3(k & 1 ? b.hi.x : b.lo.x, k & 2 ? b.hi.y : b.lo.y, k & 4 ? b.hi.z : b.lo.z);
}

/* The colour and opacity of the lines of depth D on a scale ending at
 * DEPTH_SCALE: the many deep ones fainter. */
static float depth_style(int d, int depth_scale, float rgb[3])
{
    double t = depth_scale > 0 ? (double)d / depth_scale : 0.0;
    draw_colormap(t, rgb);
    return (float)(0.95 - 0.35 * (t < 1 ? t : 1));
}

void draw_panel_planes(bsp_image *img, const draw_pinhole *p, const draw_cells *cells,
                       int depth_scale)
{
    for (int d = cells->max_depth; d >= 0; d--) {
        float rgb[3];
        float alpha = depth_style(d, depth_scale, rgb);
        for (size_t i = 0; i < cells->count; i++) {
            const bsp_cell_info *c = &cells->cell[i];
            if (c->is_leaf || c->depth != d)
                continue;
            /* the plane clipped to the cell: a rectangle spanned by the other two axes */
            unsigned a = c->axis, b = (a + 1) % 3, e = (a + 2) % 3;
            bsp_vec3 q[4];
            for (int k = 0; k < 4; k++) {
                q[k].v[a] = c->split;
                q[k].v[b] = (k == 1 || k == 2) ? c->box.hi.v[b] : c->box.lo.v[b];
                q[k].v[e] = k >= 2 ? c->box.hi.v[e] : c->box.lo.v[e];
            }
            for (int k = 0; k < 4; k++)
                draw_segment_3d(img, p, q[k], q[(k + 1) % 4], rgb, alpha);
        }
    }
}

/* The twelve edges of B, projected by P. */
static void draw_box_edges(bsp_image *img, const draw_pinhole *p, bsp_box b, const float rgb[3],
                           float alpha)
{
    for (int k = 0; k < 8; k++)
        for (int bit = 1; bit < 8; bit <<= 1)
            if (!(k & bit))
                draw_segment_3d(img, p, box_corner(b, k), box_corner(b, k | bit), rgb, alpha);
}

void draw_panel_boxes(bsp_image *img, const draw_pinhole *p, const draw_cells *cells,
                      int depth_scale)
{
    for (int d = cells->max_depth; d >= 1; d--) {
        float rgb[3];
        float alpha = depth_style(d, depth_scale, rgb);
        for (size_t i = 0; i < cells->count; i++)
            if (cells->cell[i].depth == d)
                draw_box_edges(img, p, cells->cell[i].box, rgb, alpha);
    }
}

void draw_panel_root(bsp_image *img, const draw_pinhole *p, const draw_cells *cells)
{
    if (cells->count == 0)
        return;
    static const float white[3] = {1, 1, 1};
    draw_box_edges(img, p, cells->cell[0].box, white, 0.7f);
}

/* The frustum's two horizontal edges and the eye, seen from above. */
static void draw_frustum_top(bsp_image *img, const draw_topview *tv, const bsp_camera *cam)
{
    static const float white[3] = {1, 1, 1};
    double ex, ey;
    draw_topview_project(tv, cam->from, &ex, &ey);
    bsp_vec3 fwd = v3_normalize(v3_sub(cam->at, cam->from));
    bsp_vec3 right = v3_normalize(v3_cross(fwd, cam->up));
    double half = tan(cam->angle_deg * (BSP_PI / 360.0));
    double reach = 4.0 * (img->width + img->height);
    for (int s = -1; s <= 1; s += 2) {
        bsp_vec3 d = v3_add(fwd, v3_scale(right, s * half));
        double dx = tv->h_sign * d.v[tv->h_axis], dy = -tv->v_sign * d.v[tv->v_axis];
        double len = sqrt(dx * dx + dy * dy);
        if (!(len > 1e-9))
            continue; /* looking straight down: the edge has no horizontal extent */
        draw_line(img, ex, ey, ex + reach * dx / len, ey + reach * dy / len, white, 0.9f);
    }
    draw_fill_rect(img, ex - 2.5, ey - 2.5, ex + 2.5, ey + 2.5, white, 1.f);
}

bsp_status draw_panel_top(bsp_image *img, const draw_topview *tv, const draw_cells *cells,
                          draw_color_mode mode, double scale, const bsp_camera *cam, bsp_error *err)
{
    int w = img->width, h = img->height;
    float *best = malloc((size_t)w * (size_t)h * sizeof *best);
    if (!best) {
        if (err) {
            err->status = BSP_ERR_NOMEM;
            snprintf(err->message, sizeof err->message, "out of memory for the top view");
        }
        return BSP_ERR_NOMEM;
    }
    for (size_t i = 0; i < (size_t)w * (size_t)h; i++)
        best[i] = -1.f;
    /* per pixel, the largest value over the leaves covering its centre */
    for (size_t i = 0; i < cells->count; i++) {
        const bsp_cell_info *c = &cells->cell[i];
        if (!c->is_leaf)
            continue;
        double ax, ay, bx, by;
        draw_topview_project(tv, c->box.lo, &ax, &ay);
        draw_topview_project(tv, c->box.hi, &bx, &by);
        int x0, x1, y0, y1;
        centre_span(fmin(ax, bx), fmax(ax, bx), w, &x0, &x1);
        centre_span(fmin(ay, by), fmax(ay, by), h, &y0, &y1);
        float v = mode == DRAW_COLOR_DEPTH ? (float)c->depth : (float)c->refs;
        for (int y = y0; y < y1; y++)
            for (int x = x0; x < x1; x++)
                if (v > best[(size_t)y * w + x])
                    best[(size_t)y * w + x] = v;
    }
    for (size_t i = 0; i < (size_t)w * (size_t)h; i++) {
        float *px = img->rgb + 3 * i;
        if (best[i] < 0)
            px[0] = px[1] = px[2] = 0.06f;
        else
            draw_cell_color(mode, best[i], scale, px);
    }
    free(best);
    /* outlines; shared edges darken where many leaves are stacked */
    static const float black[3] = {0, 0, 0};
    for (size_t i = 0; i < cells->count; i++) {
        const bsp_cell_info *c = &cells->cell[i];
        if (!c->is_leaf)
            continue;
        double ax, ay, bx, by;
        draw_topview_project(tv, c->box.lo, &ax, &ay);
        draw_topview_project(tv, c->box.hi, &bx, &by);
        draw_line(img, ax, ay, bx, ay, black, 0.45f);
        draw_line(img, bx, ay, bx, by, black, 0.45f);
        draw_line(img, bx, by, ax, by, black, 0.45f);
        draw_line(img, ax, by, ax, ay, black, 0.45f);
    }
    if (cam)
        draw_frustum_top(img, tv, cam);
    return BSP_OK;
}
