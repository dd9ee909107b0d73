/*
 * bspray/geom.h — transparent value types shared by every part of the API:
 * 3-vectors, rays with a parametric interval, hit records and boxes.
 *
 * Precision: all geometry is double. The reasons are written down in
 * docs/precision.md: SPD files carry only 6 significant digits, scenes mix
 * 100-unit ground planes with millimetre branches, and kd-tree exactness
 * checks compare t values bit for bit, which is easiest to reason about when
 * every routine works in one precision with a 53-bit mantissa.
 */
#ifndef BSPRAY_GEOM_H
#define BSPRAY_GEOM_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Anonymous structs are standard C11 but an extension in C++, which g++ and
 * clang++ accept; __extension__ keeps their -pedantic quiet about it. */
#if defined(__cplusplus) && defined(__GNUC__)
#define BSP_ANONYMOUS_STRUCT __extension__ struct
#else
#define BSP_ANONYMOUS_STRUCT struct
#endif

/* A 3-vector. Components are reachable by name (p.x) or by axis (p.v[1]);
 * the union makes axis indexing legal without pointer tricks. */
typedef union bsp_vec3 {
    BSP_ANONYMOUS_STRUCT {
        double x, y, z;
    };
    double v[3];
} bsp_vec3;

/* A ray r(t) = org + t * dir, valid for tmin <= t <= tmax (both inclusive).
 * dir need not be unit length: t is measured in units of dir. */
typedef struct bsp_ray {
    bsp_vec3 org;
    bsp_vec3 dir;
    double tmin;
    double tmax;
} bsp_ray;

/* "No primitive" marker in bsp_hit.prim. */
#define BSP_NO_PRIM UINT32_MAX

/* The result of a closest-hit query. */
typedef struct bsp_hit {
    double t;      /* ray parameter of the hit */
    uint32_t prim; /* 0-based primitive index in file order, or BSP_NO_PRIM */
    double u, v;   /* barycentric coordinates (triangles and patches), else 0 */
} bsp_hit;

/* An axis-aligned box; empty when lo > hi on any axis. */
typedef struct bsp_box {
    bsp_vec3 lo;
    bsp_vec3 hi;
} bsp_box;

static inline bsp_vec3 bsp_v3(double x, double y, double z)
{
    bsp_vec3 r;
    r.x = x;
    r.y = y;
    r.z = z;
    return r;
}

#ifdef __cplusplus
}
#endif

#endif /* BSPRAY_GEOM_H */
