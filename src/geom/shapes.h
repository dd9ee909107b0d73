/*
 * shapes.h — the four intersectable shapes: their precomputed records, setup
 * (validation + precomputation), exact bounds, ray intersection and normals.
 *
 * The *_intersect functions are out-of-line wrappers of the inline kernels in
 * geom/isect.h, which the intersection loops of every method use directly;
 * both compute the same t, bit for bit. The wrappers skip the kernels' hit
 * check (isect.h), whose distance is relative to the scene's scale; a
 * scene's queries (scene_isect) apply it.
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

#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "bspray/geom.h"

#define SHAPES_HIDDEN __attribute__((visibility("hidden")))

/* Index marker: "no vertex normals". */
#define SHAPE_NO_NORMALS UINT32_MAX

/* Polygons of at least this many vertices get slabs (polygon_slabs.c), as
 * long as their slabs hold at most POLYGON_SLAB_BUDGET entries per vertex
 * (a polygon whose edges each span many slabs keeps the walk of its edges:
 * slabs are O(n^2) at worst). Timed on random rays against random star
 * polygons, slabs over the walk: n = 4: 1.24, 8: 1.03, 9: 0.94, 16: 0.78,
 * 40: 0.50 (docs/kdtree.md). */
#define POLYGON_SLAB_MIN 9
#define POLYGON_SLAB_BUDGET 32

typedef struct sphere_shape {
    bsp_vec3 center;
    double radius;  /* > 0 */
    double radius2; /* radius * radius */
    int inside_only; /* NFF negative radius: only the inside is visible */
} sphere_shape;

/* A triangle's vertices: what the scene keeps, and what the watertight
 * decision (geom/isect.h) reads, since it needs each vertex as every
 * triangle sharing it has it (v0 + (v1 - v0) does not give v1 back in
 * floating point). */
typedef struct triangle_verts {
    bsp_vec3 v0, v1, v2;
} triangle_verts;

/* What Möller–Trumbore reads (geom/isect.h): the first vertex and the edges
 * e1 = v1 - v0, e2 = v2 - v0, always made by triangle_edges_of, so always
 * the same bits. The kd-tree's leaf-ordered copy of the primitives
 * (accel/kd_local.h) holds this. */
typedef struct triangle_edges {
    bsp_vec3 v0, e1, e2;
} triangle_edges;

typedef struct triangle_shape {
    union { /* the vertices, also by name: tr->v0 is tr->verts.v0 */
        triangle_verts verts;
        struct {
            bsp_vec3 v0, v1, v2;
        };
    };
    bsp_vec3 normal;  /* unit normal of e1 x e2 (the vertex winding) */
    uint32_t normals; /* first of 3 vertex normals in the pool, or SHAPE_NO_NORMALS */
    int8_t edge_exp;  /* triangle_edge_exp of its edges */
} triangle_shape;

static inline triangle_edges triangle_edges_of(const triangle_verts *t)
{
    triangle_edges e;
    e.v0 = t->v0;
    e.e1 = bsp_v3(t->v1.x - t->v0.x, t->v1.y - t->v0.y, t->v1.z - t->v0.z);
    e.e2 = bsp_v3(t->v2.x - t->v0.x, t->v2.y - t->v0.y, t->v2.z - t->v0.z);
    return e;
}

/* The edges' size for the watertight margin (isect_first.h, triangle_margin)
 * as a power of two: the least k >= -127 with 2^k > |e1|_1 + |e2|_1 (a
 * byte, so that it fits the kd-tree's 80-byte records; at most 2^104 for
 * coordinates within 1e30). */
static inline int triangle_edge_exp(const triangle_edges *e)
{
    double n = (fabs(e->e1.x) + fabs(e->e1.y) + fabs(e->e1.z)) +
               (fabs(e->e2.x) + fabs(e->e2.y) + fabs(e->e2.z));
    int k = -127;
    if (n >= 0x1p-127) {
        int ex;
        (void)frexp(n, &ex); /* n < 2^ex */
        k = ex;
    }
    return k > 127 ? 127 : k;
}

/* Below every triangle_edge_exp: no triangle (bsp_scene.tri_edge_exp_max). */
#define TRIANGLE_EDGE_EXP_NONE (-128)

/* 2^K for -127 <= K <= 127, made from its bits (no libm call in the hot
 * loop). */
static inline double triangle_edge_norm(int k)
{
    uint64_t bits = (uint64_t)(k + 1023) << 52;
    double x;
    memcpy(&x, &bits, sizeof x);
    return x;
}

typedef struct polygon_shape {
    bsp_vec3 normal;  /* unit normal (Newell's method: the winding's orientation) */
    double d;         /* plane: dot(normal, p) == d (mean over the vertices) */
    uint32_t first;   /* first vertex in the pool */
    uint32_t count;   /* vertex count, >= 4 */
    uint32_t normals; /* first vertex normal in the pool, or SHAPE_NO_NORMALS */
    uint8_t axis_u, axis_v; /* the two axes of the projection plane: the
                               dominant axis of the normal is dropped */
    uint32_t slab_first; /* with nslabs > 0: its slabs in a polygon_slab_pool */
    uint32_t nslabs;     /* distinct vertex v values of its slabs; 0: none (the
                            crossing test walks every edge) */
    double wt_base; /* the polygon's part of the watertight margin
                       (polygon_margin, geom/isect.h); < 0: not planar to
                       rounding, no watertight decision */
} polygon_shape;

/* An edge of a polygon as the crossing test uses it: its lower endpoint
 * (lower v) and the differences to the upper one. */
typedef struct polygon_edge {
    double lo_u, lo_v, du, dv;
} polygon_edge;

/* Slabs of the polygons with many vertices (polygon_slabs.c), for all the
 * polygons of a scene: a polygon's k distinct vertex v values, ascending, at
 * y[slab_first ..], and for the slab between y[j] and y[j + 1] the edges
 * that cross it, edge[entry[off[j]] .. entry[off[j + 1]]). */
typedef struct polygon_slab_pool {
    double *y;
    uint32_t *off; /* parallel to y */
    size_t ny, cap_y, cap_off;
    uint32_t *entry;
    size_t nentry, cap_entry;
    polygon_edge *edge;
    size_t nedge, cap_edge;
} polygon_slab_pool;

typedef struct cone_shape {
    bsp_vec3 base;      /* centre of the base disc */
    bsp_vec3 axis;      /* unit vector from base to apex */
    double length;      /* distance base -> apex, > 0 */
    double base_radius; /* |radius| at the base, >= 0 */
    double apex_radius; /* |radius| at the apex, >= 0; not both 0 */
    double slope;       /* (apex_radius - base_radius) / length */
    double far2;        /* squared distance from the base beyond which an origin is moved
                           along the ray before solving (cone_isect) */
    int inside_only;    /* NFF negative radii: only the inside is visible */
} cone_shape;

/* --- setup ---------------------------------------------------------------- */

SHAPES_HIDDEN int sphere_setup(sphere_shape *s, bsp_vec3 center, double radius);
SHAPES_HIDDEN int triangle_setup(triangle_shape *tr, bsp_vec3 a, bsp_vec3 b, bsp_vec3 c,
                                 uint32_t normals);
/* VERTS is the pool; the polygon's vertices are VERTS[first .. first+count). */
SHAPES_HIDDEN int polygon_setup(polygon_shape *p, const bsp_vec3 *verts, uint32_t first,
                                uint32_t count, uint32_t normals);
/* Builds the slabs of polygon P (set up; vertices VERTS[p->first ..]) into
 * POOL when it has at least POLYGON_SLAB_MIN vertices and its slabs hold at
 * most POLYGON_SLAB_BUDGET entries per vertex; otherwise P keeps none.
 * Returns 0 only when out of memory (P then has none). */
SHAPES_HIDDEN int polygon_slabs_build(polygon_shape *p, const bsp_vec3 *verts,
                                      polygon_slab_pool *pool);
SHAPES_HIDDEN void polygon_slab_pool_free(polygon_slab_pool *pool);
/* The work of P's crossing test in edges visited, for the cost model: its
 * vertex count when it has no slabs (POOL may then be NULL), else the steps
 * of the binary search plus the mean entries of a slab, each rounded up. */
SHAPES_HIDDEN uint32_t polygon_test_units(const polygon_shape *p, const polygon_slab_pool *pool);
/* Radii may be negative (inside only); both radii must then be <= 0. */
SHAPES_HIDDEN int cone_setup(cone_shape *c, bsp_vec3 base, double base_radius, bsp_vec3 apex,
                             double apex_radius);

/* --- exact bounds ------------------------------------------------------- */

SHAPES_HIDDEN bsp_box sphere_bounds(const sphere_shape *s);
SHAPES_HIDDEN bsp_box triangle_bounds(const triangle_shape *tr);
SHAPES_HIDDEN bsp_box polygon_bounds(const polygon_shape *p, const bsp_vec3 *verts);
/* Vertex V of polygon P moved along the dropped axis onto P's mean plane. A
 * polygon's hits lie on that plane inside the projection of its vertices,
 * so they are exactly the planar polygon of its vertices moved so: what
 * bounds and clipping must cover, rather than the vertices as read, which
 * lie off the plane by ~1e-6 of their size (%g precision) or, in a
 * non-planar input polygon, by far more. */
static inline bsp_vec3 polygon_plane_vertex(const polygon_shape *p, bsp_vec3 v)
{
    const int au = p->axis_u, av = p->axis_v, aw = 3 - au - av;
    v.v[aw] = (p->d - p->normal.v[au] * v.v[au] - p->normal.v[av] * v.v[av]) / p->normal.v[aw];
    return v;
}
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
/* SLABS: the pool of P's slabs, or NULL to walk every edge (the same answer,
 * bit for bit). */
SHAPES_HIDDEN int polygon_intersect(const polygon_shape *p, const bsp_vec3 *verts,
                                    const polygon_slab_pool *slabs, const bsp_ray *ray,
                                    double *t);
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
