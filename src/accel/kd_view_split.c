/*
 * kd_view_split.c — the PER and PAR measures of the children of a cell's
 * splits, for the SAH sweep (kd_sweep_measure.c).
 *
 * The sweep measures both children of each candidate plane p of a cell,
 * [lo, p] and [p, hi] on the split axis. When the cell lies wholly in front
 * of the rays' start plane, inside the viewport, and (PER) does not contain
 * the eye, so does every child: a child is a convex part of the cell, and
 * the projection of a convex body in front of the eye lies inside the
 * projection of any body that contains it. A child's measure is then the sum
 * of the projected areas of its faces turned towards the rays, with no hull
 * and no clipping (as in kd_view_area). A child's 8 corners are 4 of the
 * cell's and the 4 corners of the plane p, which both children share: so the
 * cell's corners are projected once for the sweeps of its three axes, and
 * each plane's corners once for both of its children, where kd_view_area
 * projects 16 corners per candidate (and tests each against the start plane
 * and the viewport).
 *
 * A corner's coordinates in the view frame are sums of the terms
 * (x_j - eye_j) f_j of the three axes (f: right, up, fwd), summed here in
 * another order than kd_view_area sums them, so the two differ by a few
 * rounding errors of terms up to R (the farthest corner's distance): within
 * the error bound kd_view_measure_noise gives the pruned sweep
 * (tests/test_kd_view.c checks the bound on these measures and their
 * agreement with kd_view_area).
 */
#include <math.h>
#include <string.h>

#include "accel/kd_view.h"
#include "accel/kd_view_faces.h"

/* A cell this close to the rays' start plane (relative to its largest
 * extent) is left to kd_view_area, whose cut at the plane matters there. */
#define SPLIT_MIN_DEPTH 1e-6

/* The corners of a child's face of axis J (not the split axis K) seen from
 * side S, in the cycle of kd_face_corners[J][S], for the child whose corners
 * on side H of axis K are the cell's: FACE_SRC[K][J][S][H] names each as an
 * index of the split's corners, 0-7 the cell's corner c, 8 + q the plane's
 * corner q (bit 0: the side of axis K + 1, bit 1: of axis K + 2). Derived
 * from kd_face_corners: corner c is the cell's when its bit K is H, else
 * the plane's with c's sides on the other two axes (tests/test_kd_view.c
 * checks every child's measure against kd_view_area). */
static const unsigned char face_src[3][3][2][2][4] = {
    {{{{0, 2, 6, 4}, {8, 9, 11, 10}}, {{8, 9, 11, 10}, {1, 3, 7, 5}}}, {{{0, 4, 10, 8}, {8, 10, 5, 1}}, {{2, 6, 11, 9}, {9, 11, 7, 3}}}, {{{0, 8, 9, 2}, {8, 1, 3, 9}}, {{4, 10, 11, 6}, {10, 5, 7, 11}}}},
    {{{{0, 8, 9, 4}, {8, 2, 6, 9}}, {{1, 10, 11, 5}, {10, 3, 7, 11}}}, {{{0, 4, 5, 1}, {8, 9, 11, 10}}, {{8, 9, 11, 10}, {2, 6, 7, 3}}}, {{{0, 1, 10, 8}, {8, 10, 3, 2}}, {{4, 5, 11, 9}, {9, 11, 7, 6}}}},
    {{{{0, 2, 10, 8}, {8, 10, 6, 4}}, {{1, 3, 11, 9}, {9, 11, 7, 5}}}, {{{0, 8, 9, 1}, {8, 4, 5, 9}}, {{2, 10, 11, 3}, {10, 6, 7, 11}}}, {{{0, 1, 3, 2}, {8, 9, 11, 10}}, {{8, 9, 11, 10}, {4, 5, 7, 6}}}},
};

/* Twice the area of the quadrilateral A B C D (in cyclic order) from its
 * diagonals: |(C - A) x (D - B)|. */
static inline double quad2(double ax, double ay, double bx, double by, double cx, double cy,
                           double dx, double dy)
{
    return fabs((cx - ax) * (dy - by) - (dx - bx) * (cy - ay));
}

void kd_view_split_begin(kd_view_split *s, kd_view_cell *vc, const kd_view *view,
                         const bsp_box *cell, unsigned k)
{
    if (vc->view != view || memcmp(&vc->box, cell, sizeof *cell) != 0) {
        vc->view = view;
        vc->box = *cell;
        vc->state = 0;
    }
    s->vc = vc;
    s->k = k;
    s->ready = 0;
}

/* The cell's corners in the view frame, projected; whether it is accepted. */
static int prepare_cell(kd_view_cell *vc)
{
    const kd_view *v = vc->view;
    const bsp_box *b = &vc->box;
    const int ortho = v->ortho;
    if (!ortho && kd_view_eye_in(v, b))
        return 0; /* the eye inside: the whole viewport */
    const bsp_vec3 *f[3] = {&v->right, &v->up, &v->fwd};
    double ext = 0.0;
    for (unsigned j = 0; j < 3; j++) {
        double dl = b->lo.v[j] - v->eye.v[j], dh = b->hi.v[j] - v->eye.v[j];
        for (unsigned a = 0; a < 3; a++) {
            vc->rl[a][j] = dl * f[a]->v[j];
            vc->rh[a][j] = dh * f[a]->v[j];
        }
        double w = b->hi.v[j] - b->lo.v[j];
        ext = w > ext ? w : ext;
        vc->side[j] = (signed char)kd_view_face_seen(v, j, b->lo.v[j], b->hi.v[j]);
    }
    const double min_depth = ortho ? 0.0 : SPLIT_MIN_DEPTH * ext;
    int ok = 1;
    double f3[3][8]; /* the corners in the view frame: x, y and z terms summed */
    for (unsigned a = 0; a < 3; a++) {
        const double *lo = vc->rl[a], *hi = vc->rh[a];
        const double s00 = lo[0] + lo[1], s10 = hi[0] + lo[1], s01 = lo[0] + hi[1],
                     s11 = hi[0] + hi[1];
        f3[a][0] = s00 + lo[2];
        f3[a][1] = s10 + lo[2];
        f3[a][2] = s01 + lo[2];
        f3[a][3] = s11 + lo[2];
        f3[a][4] = s00 + hi[2];
        f3[a][5] = s10 + hi[2];
        f3[a][6] = s01 + hi[2];
        f3[a][7] = s11 + hi[2];
    }
    for (unsigned c = 0; c < 8; c++) {
        double t[3] = {f3[0][c], f3[1][c], f3[2][c]};
        ok &= t[2] > min_depth;
        if (!ortho) {
            t[0] /= t[2];
            t[1] /= t[2];
        }
        ok &= (fabs(t[0]) <= v->hx) & (fabs(t[1]) <= v->hy);
        vc->cx[c] = t[0];
        vc->cy[c] = t[1];
    }
    return ok;
}

/* The split axis's terms; 0 when the cell is refused. */
static int prepare(kd_view_split *s)
{
    kd_view_cell *vc = s->vc;
    if (vc->state == 0)
        vc->state = prepare_cell(vc) ? 1 : -1;
    if (vc->state < 0)
        return 0;
    const kd_view *v = vc->view;
    const unsigned k = s->k, j1 = k == 2 ? 0 : k + 1, j2 = k == 0 ? 2 : k - 1;
    s->eye_k = v->eye.v[k];
    s->lo_k = vc->box.lo.v[k];
    s->hi_k = vc->box.hi.v[k];
    s->rk = v->right.v[k];
    s->uk = v->up.v[k];
    s->fk = v->fwd.v[k];
    double *out[3] = {s->sx, s->sy, s->sz};
    for (unsigned a = 0; a < 3; a++)
        for (unsigned q = 0; q < 4; q++)
            out[a][q] = ((q & 1) ? vc->rh[a][j1] : vc->rl[a][j1]) +
                        ((q & 2) ? vc->rh[a][j2] : vc->rl[a][j2]);
    /* the faces of the other two axes the rays see, and the cell's own
     * faces of the split axis (twice their areas) */
    s->nside = 0;
    for (unsigned j = 0; j < 3; j++)
        if (j != k && vc->side[j] >= 0)
            s->side_src[s->nside++] = face_src[k][j][vc->side[j]];
    for (unsigned c = 0; c < 8; c++) {
        s->px[c] = vc->cx[c];
        s->py[c] = vc->cy[c];
    }
    for (unsigned h = 0; h < 2; h++) {
        const unsigned char *fc = kd_face_corners[k][h];
        s->cell_face2[h] = quad2(vc->cx[fc[0]], vc->cy[fc[0]], vc->cx[fc[1]], vc->cy[fc[1]],
                                 vc->cx[fc[2]], vc->cy[fc[2]], vc->cx[fc[3]], vc->cy[fc[3]]);
    }
    s->vp_area = 4.0 * v->hx * v->hy;
    s->p = NAN;
    s->plane_ok = 0;
    s->ready = 1;
    return 1;
}

/* The corners of the plane at P, projected, unless they are already. */
static void plane_corners(kd_view_split *s, double p)
{
    if (p == s->p)
        return;
    const double dk = p - s->eye_k, ax = dk * s->rk, ay = dk * s->uk, az = dk * s->fk;
    const int ortho = s->vc->view->ortho;
    int ok = 1;
    for (unsigned q = 0; q < 4; q++) {
        double x = ax + s->sx[q], y = ay + s->sy[q], z = az + s->sz[q];
        if (ortho) {
            ok &= z >= 0.0;
        } else {
            ok &= z > 0.0;
            x /= z;
            y /= z;
        }
        s->px[8 + q] = x;
        s->py[8 + q] = y;
    }
    /* the plane's own face, a cycle of plane corners 0, 1, 3, 2 */
    const double *px = s->px + 8, *py = s->py + 8;
    s->plane_face2 = quad2(px[0], py[0], px[1], py[1], px[3], py[3], px[2], py[2]);
    s->p = p;
    s->plane_ok = ok;
}

/* The measure of the child whose corners on side HI (1: hi, 0: lo) of the
 * split axis are the cell's and whose others are the plane's; SIDE_K: the
 * face it shows on the split axis (-1: none). A face of another axis has
 * two corners of each kind, and each of its diagonals joins a cell corner
 * to a plane corner. */
static double child_area(const kd_view_split *s, unsigned hi, int side_k)
{
    const double *x = s->px, *y = s->py;
    double a2 = 0.0;
    for (unsigned f = 0; f < s->nside; f++) {
        const unsigned char *i = s->side_src[f][hi];
        a2 += quad2(x[i[0]], y[i[0]], x[i[1]], y[i[1]], x[i[2]], y[i[2]], x[i[3]], y[i[3]]);
    }
    if (side_k >= 0)
        a2 += (unsigned)side_k == hi ? s->cell_face2[hi] : s->plane_face2;
    const double a = 0.5 * a2;
    return a < s->vp_area ? a : s->vp_area;
}

/* The measure of CHILD, the child of the plane at P on side HI (1: above). */
static double child_measure(kd_view_split *s, const bsp_box *child, double p, unsigned hi)
{
    if (!s->ready && !prepare(s))
        return kd_view_area(child, s->vc->view);
    plane_corners(s, p);
    if (!s->plane_ok)
        return kd_view_area(child, s->vc->view);
    const kd_view *v = s->vc->view;
    return child_area(s, hi, hi ? kd_view_face_seen(v, s->k, p, s->hi_k)
                                : kd_view_face_seen(v, s->k, s->lo_k, p));
}

double kd_view_split_left(kd_view_split *s, const bsp_box *child, double p)
{
    return child_measure(s, child, p, 0);
}

double kd_view_split_right(kd_view_split *s, const bsp_box *child, double p)
{
    return child_measure(s, child, p, 1);
}
