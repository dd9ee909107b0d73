/*
 * kd_flux.c — the sampled-ray measure of kd_flux.h: a voxel grid of
 * crossing densities filled by walking the sample's segments through it
 * (Amanatides & Woo), and face integrals from per-slab 2D prefix sums.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "accel/kd_flux.h"

#define FLUX_MAX_PER_AXIS 128

/* Voxels per axis for about CELLS cubic voxels over extents E (an axis of
 * no extent gets one voxel). */
static void grid_shape(const double e[3], size_t cells, int n[3])
{
    double vol = 1.0;
    int dims = 0;
    for (int k = 0; k < 3; k++)
        if (e[k] > 0.0) {
            vol *= e[k];
            dims++;
        }
    double side = dims ? pow(vol / (double)cells, 1.0 / dims) : 1.0;
    for (int k = 0; k < 3; k++) {
        double c = e[k] > 0.0 && side > 0.0 ? floor(e[k] / side + 0.5) : 1.0;
        n[k] = c < 1.0 ? 1 : c > FLUX_MAX_PER_AXIS ? FLUX_MAX_PER_AXIS : (int)c;
    }
}

static int clampi(double x, int n)
{
    return !(x >= 0.0) ? 0 : x >= (double)n ? n - 1 : (int)x; /* NaN: 0 */
}

static size_t voxel_index(const kd_flux *f, const int idx[3])
{
    return ((size_t)idx[0] * (size_t)f->n[1] + (size_t)idx[1]) * (size_t)f->n[2] + (size_t)idx[2];
}

/* Adds segment S's runs through the voxels to ACC (3 sums per voxel:
 * run length in t times |d_k|, for k = 0, 1, 2) and its end points inside
 * the grid's box to ENDS (a count per voxel). */
static void walk_segment(const kd_flux *f, const kd_flux_segment *s, double *acc, double *ends)
{
    double t0 = s->t0, t1 = s->t1;
    const double o[3] = {s->org.x, s->org.y, s->org.z}, d[3] = {s->dir.x, s->dir.y, s->dir.z};
    for (int k = 0; k < 3; k++)
        if (!isfinite(o[k]) || !isfinite(d[k]))
            return;
    if (!line_clip_box(o, d, &f->box, &t0, &t1) || !(t0 < t1) || !isfinite(t1))
        return;
    /* an end point lies inside the box when clipping left its t alone */
    const int start_inside = t0 == s->t0, end_inside = t1 == s->t1;
    const double ad[3] = {fabs(d[0]), fabs(d[1]), fabs(d[2])};
    int idx[3], step[3];
    /* the start voxel: where the clipped segment begins (rounded into a
     * neighbour, the walk leaves it at once with a run of 0) */
    for (int k = 0; k < 3; k++) {
        double p = d[k] == 0.0 ? o[k] : o[k] + t0 * d[k];
        idx[k] = clampi((p - f->box.lo.v[k]) / f->cs[k], f->n[k]);
        step[k] = d[k] > 0.0 ? 1 : d[k] < 0.0 ? -1 : 0;
    }
    if (start_inside)
        ends[voxel_index(f, idx)] += 1.0;
    if (end_inside) {
        int e[3];
        for (int k = 0; k < 3; k++) {
            double p = d[k] == 0.0 ? o[k] : o[k] + t1 * d[k];
            e[k] = clampi((p - f->box.lo.v[k]) / f->cs[k], f->n[k]);
        }
        ends[voxel_index(f, e)] += 1.0;
    }
    double t = t0;
    /* each step leaves a voxel through one face: at most the sum of the
     * counts (plus slack for rounding at the start) */
    for (int guard = f->n[0] + f->n[1] + f->n[2] + 4; guard > 0; guard--) {
        double tn[3];
        for (int k = 0; k < 3; k++) {
            if (!step[k]) {
                tn[k] = INFINITY;
                continue;
            }
            double plane = f->box.lo.v[k] + (double)(idx[k] + (step[k] > 0)) * f->cs[k];
            tn[k] = (plane - o[k]) / d[k];
        }
        int k = tn[0] <= tn[1] ? (tn[0] <= tn[2] ? 0 : 2) : (tn[1] <= tn[2] ? 1 : 2);
        double te = tn[k] < t1 ? tn[k] : t1;
        if (te > t) {
            double *a = acc + 3 * voxel_index(f, idx);
            double dt = te - t;
            a[0] += dt * ad[0];
            a[1] += dt * ad[1];
            a[2] += dt * ad[2];
            t = te;
        }
        if (t >= t1)
            break;
        idx[k] += step[k];
        if (idx[k] < 0 || idx[k] >= f->n[k])
            break;
    }
}

bsp_status kd_flux_build(kd_flux *f, const bsp_box *box, const kd_flux_segment *seg, size_t n,
                         size_t cells, bsp_error *err)
{
    memset(f, 0, sizeof *f);
    f->box = *box;
    double e[3];
    for (int k = 0; k < 3; k++) {
        e[k] = box->hi.v[k] - box->lo.v[k];
        if (!(e[k] >= 0.0) || !isfinite(e[k]))
            e[k] = 0.0;
    }
    grid_shape(e, cells ? cells : 1, f->n);
    for (int k = 0; k < 3; k++)
        f->cs[k] = e[k] > 0.0 ? e[k] / f->n[k] : 1.0; /* a flat axis: any positive size */
    size_t nvox = (size_t)f->n[0] * (size_t)f->n[1] * (size_t)f->n[2];
    const size_t n0 = (size_t)f->n[0], n1 = (size_t)f->n[1], n2 = (size_t)f->n[2];
    double *acc = calloc(4 * nvox, sizeof *acc);
    f->ends = calloc((n0 + 1) * (n1 + 1) * (n2 + 1), sizeof *f->ends);
    if (!acc || !f->ends) {
        free(acc);
        kd_flux_free(f);
        return error_set(err, BSP_ERR_NOMEM, NULL, 0, "out of memory");
    }
    double *ends = acc + 3 * nvox; /* after the NULL test: no arithmetic on NULL */
    for (size_t i = 0; i < n; i++)
        walk_segment(f, &seg[i], acc, ends);
    /* 3D prefix sums of the end points: Q[i][j][l] = the points in the
     * voxels below i, j, l */
    for (size_t i = 0; i < n0; i++)
        for (size_t j = 0; j < n1; j++)
            for (size_t l = 0; l < n2; l++) {
#define Q(a, b, c) f->ends[((a) * (n1 + 1) + (b)) * (n2 + 1) + (c)]
                Q(i + 1, j + 1, l + 1) = ends[(i * n1 + j) * n2 + l] + Q(i, j + 1, l + 1) +
                                         Q(i + 1, j, l + 1) + Q(i + 1, j + 1, l) -
                                         Q(i, j, l + 1) - Q(i, j + 1, l) - Q(i + 1, j, l) +
                                         Q(i, j, l);
#undef Q
            }

    /* phi_k times a k-face's voxel area = run * |d_k| / (V / (cs_u cs_v)) =
     * run * |d_k| / cs_k; then 2D prefix sums per slab */
    for (int k = 0; k < 3; k++) {
        int u = (k + 1) % 3, v = (k + 2) % 3;
        size_t nu = (size_t)f->n[u], nv = (size_t)f->n[v], nk = (size_t)f->n[k];
        double *p = calloc(nk * (nu + 1) * (nv + 1), sizeof *p);
        if (!p) {
            free(acc);
            kd_flux_free(f);
            return error_set(err, BSP_ERR_NOMEM, NULL, 0, "out of memory");
        }
        f->pre[k] = p;
        for (size_t i = 0; i < nk; i++) {
            double *slab = p + i * (nu + 1) * (nv + 1);
            for (size_t a = 0; a < nu; a++)
                for (size_t b = 0; b < nv; b++) {
                    size_t c[3];
                    c[k] = i, c[u] = a, c[v] = b;
                    size_t vox = (c[0] * (size_t)f->n[1] + c[1]) * (size_t)f->n[2] + c[2];
                    double x = acc[3 * vox + (size_t)k] / f->cs[k];
                    slab[(a + 1) * (nv + 1) + b + 1] = x + slab[a * (nv + 1) + b + 1] +
                                                       slab[(a + 1) * (nv + 1) + b] -
                                                       slab[a * (nv + 1) + b];
                }
        }
    }
    free(acc);
    f->total = kd_flux_measure(f, box);
    return BSP_OK;
}

/* Where X lies on axis K of the grid: voxel *I and fraction *W in it. */
static inline void locate(const kd_flux *f, int k, double x, int *i, double *w)
{
    double g = (x - f->box.lo.v[k]) / f->cs[k];
    int n = f->n[k];
    if (!(g > 0.0)) { /* also NaN */
        *i = 0;
        *w = 0.0;
    } else if (g >= (double)n) {
        *i = n - 1;
        *w = 1.0;
    } else {
        *i = (int)g;
        *w = g - (double)*i;
    }
}

/* The integral of slab P's density up to the point at voxels A, B with
 * fractions WA, WB: bilinear in the prefix sums of the voxel's corners. */
static inline double prefix_at(const double *p, size_t nv1, int a, double wa, int b, double wb)
{
    const double *r0 = p + (size_t)a * nv1 + (size_t)b, *r1 = r0 + nv1;
    return (1.0 - wa) * ((1.0 - wb) * r0[0] + wb * r0[1]) + wa * ((1.0 - wb) * r1[0] + wb * r1[1]);
}

/* The end points inside the box whose bounds lie in voxels AT[k][0] (low)
 * and AT[k][1] (high) at fractions W[k][.]: the prefix sums are trilinear
 * within a voxel, and inclusion-exclusion over the box's corners makes,
 * per axis, four (index, coefficient) pairs; the sum runs over their
 * 4 x 4 x 4 products, the inner axis contiguous in memory. */
static double ends_inside(const kd_flux *f, const int at[3][2], const double w[3][2])
{
    const size_t s1 = (size_t)f->n[2] + 1, s0 = ((size_t)f->n[1] + 1) * s1;
    size_t ix[3][4];
    double cf[3][4];
    for (int k = 0; k < 3; k++) {
        const size_t stride = k == 0 ? s0 : k == 1 ? s1 : 1;
        ix[k][0] = (size_t)at[k][0] * stride;
        ix[k][1] = ix[k][0] + stride;
        ix[k][2] = (size_t)at[k][1] * stride;
        ix[k][3] = ix[k][2] + stride;
        cf[k][0] = -(1.0 - w[k][0]);
        cf[k][1] = -w[k][0];
        cf[k][2] = 1.0 - w[k][1];
        cf[k][3] = w[k][1];
    }
    double sum = 0.0;
    for (int a = 0; a < 4; a++)
        for (int b = 0; b < 4; b++) {
            const double *q = f->ends + ix[0][a] + ix[1][b];
            double row = cf[2][0] * q[ix[2][0]] + cf[2][1] * q[ix[2][1]] +
                         cf[2][2] * q[ix[2][2]] + cf[2][3] * q[ix[2][3]];
            sum += cf[0][a] * cf[1][b] * row;
        }
    return sum;
}

double kd_flux_measure(const kd_flux *f, const bsp_box *b)
{
    /* each bound located once: as a face's slab (its voxel) and as a corner
     * of the faces of the other two axes */
    int at[3][2];
    double w[3][2];
    for (int k = 0; k < 3; k++) {
        locate(f, k, b->lo.v[k], &at[k][0], &w[k][0]);
        locate(f, k, b->hi.v[k], &at[k][1], &w[k][1]);
    }
    double sum = 0.0;
    for (int k = 0; k < 3; k++) {
        int u = (k + 1) % 3, v = (k + 2) % 3;
        size_t nv1 = (size_t)f->n[v] + 1, slab = ((size_t)f->n[u] + 1) * nv1;
        for (int side = 0; side < 2; side++) {
            const double *p = f->pre[k] + (size_t)at[k][side] * slab;
            double face = prefix_at(p, nv1, at[u][1], w[u][1], at[v][1], w[v][1]) -
                          prefix_at(p, nv1, at[u][0], w[u][0], at[v][1], w[v][1]) -
                          prefix_at(p, nv1, at[u][1], w[u][1], at[v][0], w[v][0]) +
                          prefix_at(p, nv1, at[u][0], w[u][0], at[v][0], w[v][0]);
            sum += face > 0.0 ? face : 0.0;
        }
    }
    const double pts = ends_inside(f, at, w);
    return 0.5 * (sum + (pts > 0.0 ? pts : 0.0));
}

void kd_flux_free(kd_flux *f)
{
    free(f->ends);
    f->ends = NULL;
    for (int k = 0; k < 3; k++) {
        free(f->pre[k]);
        f->pre[k] = NULL;
    }
}
