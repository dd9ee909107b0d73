/*
 * kd_view_faces.h — a box's faces by corner, and the projected area of a
 * face: shared by the PER/PAR measure of a box (kd_view.c) and of the
 * children of a cell's splits (kd_view_split.c).
 *
 * Corner c of a box has bit k set when it lies on the hi side of axis k.
 */
#ifndef BSPRAY_ACCEL_KD_VIEW_FACES_H
#define BSPRAY_ACCEL_KD_VIEW_FACES_H

#include <math.h>

#include "accel/kd_view.h"

/* Corner indices of the face of axis K on side S (0 lo, 1 hi), in cyclic
 * order: c[0] = S << K, then with the bit of axis K+1, of both, of K+2. */
static const unsigned char kd_face_corners[3][2][4] = {
    {{0, 2, 6, 4}, {1, 3, 7, 5}}, /* x: then y, z */
    {{0, 4, 5, 1}, {2, 6, 7, 3}}, /* y: then z, x */
    {{0, 1, 3, 2}, {4, 5, 7, 6}}, /* z: then x, y */
};

/* The shoelace area of the quadrilateral of corners FC (projected to X, Y),
 * summed as a polygon's area is (kd_view.c). */
static inline double kd_quad_area(const double *x, const double *y, const unsigned char fc[4])
{
    double x0 = x[fc[0]], y0 = y[fc[0]], x1 = x[fc[1]], y1 = y[fc[1]];
    double x2 = x[fc[2]], y2 = y[fc[2]], x3 = x[fc[3]], y3 = y[fc[3]];
    double a = 0.0;
    a += x0 * y1 - x1 * y0;
    a += x1 * y2 - x2 * y1;
    a += x2 * y3 - x3 * y2;
    a += x3 * y0 - x0 * y3;
    return 0.5 * fabs(a);
}

/* Whether the eye of the PER view V lies in the closed BOX (every ray of
 * the view then crosses it). */
static inline int kd_view_eye_in(const kd_view *v, const bsp_box *box)
{
    return v->eye.x >= box->lo.x && v->eye.x <= box->hi.x && v->eye.y >= box->lo.y &&
           v->eye.y <= box->hi.y && v->eye.z >= box->lo.z && v->eye.z <= box->hi.z;
}

/* The face of axis K that the rays of V see on a box spanning [LO, HI] on
 * that axis: 0 the lo face, 1 the hi face, -1 none. PER: the face whose
 * plane has the eye outside it; PAR: the face the rays run against. */
static inline int kd_view_face_seen(const kd_view *v, unsigned k, double lo, double hi)
{
    if (v->ortho)
        return v->fwd.v[k] > 0.0 ? 0 : v->fwd.v[k] < 0.0 ? 1 : -1;
    return v->eye.v[k] < lo ? 0 : v->eye.v[k] > hi ? 1 : -1;
}

#endif /* BSPRAY_ACCEL_KD_VIEW_FACES_H */
