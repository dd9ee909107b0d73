/*
 * shapes.h — the four intersectable shapes: their precomputed records, setup
 * (validation + precomputation), exact bounds, ray intersection and normals.
 *
 * The *_intersect functions are out-of-line wrappers of the inline kernels in
 * geom/isect.h, which the intersection loops of every method use directly;
 * both compute the same t, bit for bit.
 *
 * Contract shared by every *_intersect:
 *   - returns 1 and writes *t when the shape is hit at some t with
 *     ray->tmin <= t <= ray->tmax; returns 0 otherwise;
 *   - when several t qualify, the smallest one is returned;
 *   - the value of t is computed without reference to tmin/tmax (they only
 *     filter), so two callers with different intervals get bit-identical t;
 *   - both sides of every surface are hit (sidedness is a shading matter);
 *   - never divides by zero into a result: parallel rays simply miss;
 *   - no allocation, no failure.
 * Every *_setup returns 1 on success and 0 when the shape is degenerate
 * (zero radius, zero area, zero length); inputs are finite (the caller
 * checked).
 */
#ifndef BSPRAY_GEOM_SHAPES_H
#define BSPRAY_GEOM_SHAPES_H

#include <stddef.h>
#include <stdint.h>

#include "bspray/geom.h"

#define SHAPES_HIDDEN __attribute__((visibility("hidden")))

/* Index marker: "no vertex normals". */
#define SHAPE_NO_NORMALS UINT32_MAX

typedef struct sphere_shape {
    bsp_vec3 center;
    double radius;  /* > 0 */
    double radius2; /* radius * radius */
    int inside_only; /* NFF negative radius: only the inside is visible */
} sphere_shape;

typedef struct triangle_shape {
    bsp_vec3 v0;       /* first vertex */
    bsp_vec3 e1, e2;   /* v1 - v0, v2 - v0 */
    bsp_vec3 normal;   /* unit normal of e1 x e2 (the vertex winding) */
    uint32_t normals;  /* first of 3 vertex normals in the pool, or SHAPE_NO_NORMALS */
} triangle_shape;

typedef struct polygon_shape {
    bsp_vec3 normal;  /* unit normal (Newell's method: the winding's orientation) */
    double d;         /* plane: dot(normal, p) == d (mean over the vertices) */
    uint32_t first;   /* first vertex in the pool */
    uint32_t count;   /* vertex count, >= 4 */
    uint32_t normals; /* first vertex normal in the pool, or SHAPE_NO_NORMALS */
    uint8_t axis_u, axis_v; /* the two axes of the projection plane: the
                               dominant axis of the normal is dropped */
} polygon_shape;

typedef struct cone_shape {
    bsp_vec3 base;      /* centre of the base disc */
    bsp_vec3 axis;      /* unit vector from base to apex */
    double length;      /* distance base -> apex, > 0 */
    double base_radius; /* |radius| at the base, >= 0 */
    double apex_radius; /* |radius| at the apex, >= 0; not both 0 */
    double slope;       /* (apex_radius - base_radius) / length */
    int inside_only;    /* NFF negative radii: only the inside is visible */
} cone_shape;

/* --- setup ---------------------------------------------------------------- */

SHAPES_HIDDEN int sphere_setup(sphere_shape *s, bsp_vec3 center, double radius);
SHAPES_HIDDEN int triangle_setup(triangle_shape *tr, bsp_vec3 a, bsp_vec3 b, bsp_vec3 c,
                                 uint32_t normals);
/* VERTS is the pool; the polygon's vertices are VERTS[first .. first+count). */
SHAPES_HIDDEN int polygon_setup(polygon_shape *p, const bsp_vec3 *verts, uint32_t first,
                                uint32_t count, uint32_t normals);
/* Radii may be negative (inside only); both radii must then be <= 0. */
SHAPES_HIDDEN int cone_setup(cone_shape *c, bsp_vec3 base, double base_radius, bsp_vec3 apex,
                             double apex_radius);

/* --- exact bounds ------------------------------------------------------- */

SHAPES_HIDDEN bsp_box sphere_bounds(const sphere_shape *s);
SHAPES_HIDDEN bsp_box triangle_bounds(const triangle_shape *tr);
SHAPES_HIDDEN bsp_box polygon_bounds(const polygon_shape *p, const bsp_vec3 *verts);
SHAPES_HIDDEN bsp_box cone_bounds(const cone_shape *c);
/* The box of the circle of radius R centred at CENTER in the plane with unit
 * normal A (a cross-section of a cone; cone_bounds is the union of its two
 * end circles'). */
SHAPES_HIDDEN bsp_box cone_disc_bounds(bsp_vec3 center, double r, bsp_vec3 a);

/* --- intersection --------------------------------------------------------- */

SHAPES_HIDDEN int sphere_intersect(const sphere_shape *s, const bsp_ray *ray, double *t);
/* *u, *v: barycentric weights of v1 and v2 at the hit. */
SHAPES_HIDDEN int triangle_intersect(const triangle_shape *tr, const bsp_ray *ray, double *t,
                                     double *u, double *v);
SHAPES_HIDDEN int polygon_intersect(const polygon_shape *p, const bsp_vec3 *verts,
                                    const bsp_ray *ray, double *t);
SHAPES_HIDDEN int cone_intersect(const cone_shape *c, const bsp_ray *ray, double *t);

/* --- normals at a point on the surface (unit, outward / winding side) ---- */

SHAPES_HIDDEN bsp_vec3 sphere_normal(const sphere_shape *s, bsp_vec3 p);
SHAPES_HIDDEN bsp_vec3 cone_normal(const cone_shape *c, bsp_vec3 p);
/* Interpolated shading normal of a patch triangle at barycentrics (u, v). */
SHAPES_HIDDEN bsp_vec3 triangle_shading_normal(const triangle_shape *tr,
                                               const bsp_vec3 *normal_pool, double u,
                                               double v);
/* Interpolated shading normal of a patch polygon at point P (mean value
 * coordinates in the projection plane, so concave polygons work too). */
SHAPES_HIDDEN bsp_vec3 polygon_shading_normal(const polygon_shape *p, const bsp_vec3 *verts,
                                              const bsp_vec3 *normal_pool, bsp_vec3 p_hit);

#endif /* BSPRAY_GEOM_SHAPES_H */
