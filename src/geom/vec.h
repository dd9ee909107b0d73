/*
 * vec.h — static inline vector and box arithmetic on bsp_vec3 / bsp_box.
 * Header-only so that hot loops inline it.
 */
#ifndef BSPRAY_GEOM_VEC_H
#define BSPRAY_GEOM_VEC_H

#include <math.h>

#include "bspray/geom.h"

#define BSP_PI 3.14159265358979323846

static inline bsp_vec3 v3_add(bsp_vec3 a, bsp_vec3 b)
{
    return bsp_v3(a.x + b.x, a.y + b.y, a.z + b.z);
}
static inline bsp_vec3 v3_sub(bsp_vec3 a, bsp_vec3 b)
{
    return bsp_v3(a.x - b.x, a.y - b.y, a.z - b.z);
}
static inline bsp_vec3 v3_scale(bsp_vec3 a, double s)
{
    return bsp_v3(a.x * s, a.y * s, a.z * s);
}
static inline bsp_vec3 v3_mul(bsp_vec3 a, bsp_vec3 b)
{
    return bsp_v3(a.x * b.x, a.y * b.y, a.z * b.z);
}
static inline bsp_vec3 v3_neg(bsp_vec3 a)
{
    return bsp_v3(-a.x, -a.y, -a.z);
}
static inline double v3_dot(bsp_vec3 a, bsp_vec3 b)
{
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
static inline bsp_vec3 v3_cross(bsp_vec3 a, bsp_vec3 b)
{
    return bsp_v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
static inline double v3_length(bsp_vec3 a)
{
    return sqrt(v3_dot(a, a));
}
/* Unit vector along A; the zero vector stays zero. */
static inline bsp_vec3 v3_normalize(bsp_vec3 a)
{
    double len = v3_length(a);
    return len > 0.0 ? v3_scale(a, 1.0 / len) : a;
}
/* A + s * B */
static inline bsp_vec3 v3_madd(bsp_vec3 a, bsp_vec3 b, double s)
{
    return bsp_v3(a.x + b.x * s, a.y + b.y * s, a.z + b.z * s);
}
static inline bsp_vec3 v3_min(bsp_vec3 a, bsp_vec3 b)
{
    return bsp_v3(a.x < b.x ? a.x : b.x, a.y < b.y ? a.y : b.y, a.z < b.z ? a.z : b.z);
}
static inline bsp_vec3 v3_max(bsp_vec3 a, bsp_vec3 b)
{
    return bsp_v3(a.x > b.x ? a.x : b.x, a.y > b.y ? a.y : b.y, a.z > b.z ? a.z : b.z);
}
static inline int v3_is_finite(bsp_vec3 a)
{
    return isfinite(a.x) && isfinite(a.y) && isfinite(a.z);
}
/* The point of RAY at parameter T. */
static inline bsp_vec3 ray_at(const bsp_ray *ray, double t)
{
    return v3_madd(ray->org, ray->dir, t);
}

/* The empty box (lo = +inf, hi = -inf): the identity of box_union. */
static inline bsp_box box_empty(void)
{
    bsp_box b;
    b.lo = bsp_v3(INFINITY, INFINITY, INFINITY);
    b.hi = bsp_v3(-INFINITY, -INFINITY, -INFINITY);
    return b;
}
static inline int box_is_empty(bsp_box b)
{
    return b.lo.x > b.hi.x || b.lo.y > b.hi.y || b.lo.z > b.hi.z;
}
static inline bsp_box box_union(bsp_box a, bsp_box b)
{
    bsp_box r;
    r.lo = v3_min(a.lo, b.lo);
    r.hi = v3_max(a.hi, b.hi);
    return r;
}
/* B grown by D on every side (D >= 0; the padding of the kd-trees). */
static inline bsp_box box_grow(bsp_box b, double d)
{
    for (int k = 0; k < 3; k++) {
        b.lo.v[k] -= d;
        b.hi.v[k] += d;
    }
    return b;
}
/* Clips the parameter interval [*T0, *T1] of the line O + t D to box B
 * (slab by slab; max and min do not round, and the slab parameters of
 * nested boxes are nested, so clipping in steps gives what clipping at once
 * gives). 0 when a zero component of D leaves the line outside B's slab;
 * otherwise 1 (the interval may have become empty: *T0 > *T1). */
static inline int line_clip_box(const double o[3], const double d[3], const bsp_box *b,
                                double *t0, double *t1)
{
    for (int k = 0; k < 3; k++) {
        double lo = b->lo.v[k], hi = b->hi.v[k];
        if (d[k] == 0.0) {
            if (o[k] < lo || o[k] > hi)
                return 0;
            continue;
        }
        double ta = (lo - o[k]) / d[k], tb = (hi - o[k]) / d[k];
        if (ta > tb) {
            double x = ta;
            ta = tb;
            tb = x;
        }
        *t0 = ta > *t0 ? ta : *t0;
        *t1 = tb < *t1 ? tb : *t1;
    }
    return 1;
}

static inline bsp_box box_add_point(bsp_box a, bsp_vec3 p)
{
    bsp_box r;
    r.lo = v3_min(a.lo, p);
    r.hi = v3_max(a.hi, p);
    return r;
}

#endif /* BSPRAY_GEOM_VEC_H */
