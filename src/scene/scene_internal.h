/*
 * scene_internal.h — the storage behind the opaque bsp_scene.
 *
 * Layout: one small record per primitive index (kind, shape, slot, material)
 * and one packed array per shape, so that an intersection loop touches only
 * the data of the shape it tests. Polygons and patches with three vertices
 * are stored as triangles (their own fast test); larger ones keep their
 * vertices in a shared pool and are tested by an exact even-odd crossing test,
 * so concave polygons (SPD gears) are correct.
 *
 * Invariant: once a loader returns, the scene is never written again.
 */
#ifndef BSPRAY_SCENE_INTERNAL_H
#define BSPRAY_SCENE_INTERNAL_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>

#include "bspray/error.h"
#include "bspray/geom.h"
#include "bspray/scene.h"
#include "geom/isect.h"
#include "geom/shapes.h"

#define HIDDEN __attribute__((visibility("hidden")))

/* How a primitive is stored and intersected (not the same as its NFF kind:
 * a p or pp with three vertices is a triangle). */
typedef enum shape_kind {
    SHAPE_SPHERE = 0,
    SHAPE_TRIANGLE,
    SHAPE_POLYGON,
    SHAPE_CONE,
    SHAPE_NONE /* dropped primitive */
} shape_kind;

/* Refusal limits, checked before anything is allocated. */
#define SCENE_MAX_PRIMS ((size_t)1 << 28)      /* 268 million primitives */
#define SCENE_MAX_POLY_VERTS ((size_t)1 << 20) /* vertices of one polygon */
#define SCENE_MAX_TOTAL_VERTS ((size_t)1 << 30)
#define SCENE_MAX_LIGHTS ((size_t)1 << 16)
#define SCENE_MAX_MATERIALS ((size_t)1 << 26)
#define SCENE_MAX_WARNINGS 64

typedef struct prim_record {
    uint8_t kind;      /* bsp_prim_kind */
    uint8_t shape;     /* shape_kind */
    uint32_t slot;     /* index into the array of its shape */
    uint32_t material; /* index into materials */
} prim_record;

struct bsp_scene {
    /* per primitive, in input order */
    prim_record *prims;
    size_t nprims, cap_prims;

    /* per shape */
    sphere_shape *spheres;
    size_t nspheres, cap_spheres;
    triangle_shape *triangles;
    size_t ntriangles, cap_triangles;
    polygon_shape *polygons;
    size_t npolygons, cap_polygons;
    cone_shape *cones;
    size_t ncones, cap_cones;

    /* vertex pool of polygons with more than three vertices, and the vertex
     * normals of patches (triangles and polygons), indexed by the shapes */
    bsp_vec3 *verts;
    size_t nverts, cap_verts;
    bsp_vec3 *plane_verts; /* verts[i] of a polygon moved onto its mean plane
                              (polygon_plane_vertex): the outline of its hits,
                              which the kd-tree builders clip */
    size_t cap_plane_verts;
    bsp_vec3 *normals;
    size_t nnormals, cap_normals;
    /* the slabs of the polygons with many vertices (polygon_slabs.c) */
    polygon_slab_pool slabs;

    size_t kind_count[BSP_PRIM_KIND_COUNT];

    bsp_material *materials;
    size_t nmaterials, cap_materials;
    size_t current_material;
    int material_explicit; /* set_material was called at least once */

    bsp_light *lights;
    size_t nlights, cap_lights;

    bsp_camera camera;
    int has_camera;
    int camera_is_default; /* framed by bsp_scene_set_default_view */
    double background[3];

    bsp_box bounds; /* of the live primitives */
    /* from scene_scale, kept with bounds (scene_update_scale): */
    double far_origin; /* RAY_FAR_ORIGIN_REL scales: the precision domain */
    double hit_tol;    /* ISECT_HIT_TOL_REL scales: the kernels' hit check */
    triangle_reach tri_reach; /* the live triangles' (isect_ray.tri_bound): from the
                                 bounds and 2^tri_edge_exp_max */
    int tri_edge_exp_max; /* the largest triangle_edge_exp of a triangle added
                             (TRIANGLE_EDGE_EXP_NONE: none) */

    char *warnings[SCENE_MAX_WARNINGS];
    size_t nwarnings;
    /* degenerate input per original kind: how many, and where first met */
    size_t dropped_by_kind[BSP_PRIM_KIND_COUNT];
    size_t dropped_first_line[BSP_PRIM_KIND_COUNT]; /* 0: no line (binary input, API) */
    size_t dropped_first_prim[BSP_PRIM_KIND_COUNT]; /* its primitive index */
    int finished; /* scene_finish has run */

    /* the location loaders report in messages: file name and current line
     * (line 0: no location) */
    const char *src_name;
    size_t src_line;
};

/* Formats "NAME:LINE: message" (or just the message without a location)
 * into ERR (when not NULL), with the scene's current source as the location. */
HIDDEN void scene_fail_record(const bsp_scene *s, bsp_error *err, bsp_status status,
                              const char *fmt, ...) __attribute__((format(printf, 4, 5)));

/* Same, with an explicit location (NAME may be NULL). */
HIDDEN void error_record(bsp_error *err, bsp_status status, const char *name, size_t line,
                         const char *fmt, ...) __attribute__((format(printf, 5, 6)));

/* Runs RECORD, a call that records an error, and yields STATUS, for
 * `return error_set(...)`. The error helpers are macros over this so that
 * the failing status a caller returns is visible where it is returned: a
 * static analyser that does not follow a call into another file, or into a
 * variadic function, otherwise assumes it may return BSP_OK and follows
 * paths no input can take. STATUS is evaluated twice; every caller passes a
 * constant or a plain variable. A GNU statement expression (gcc and clang),
 * so that a call whose status is not used does not warn. */
#define FAIL_WITH(status, record)                                                              \
    __extension__({                                                                            \
        record;                                                                                \
        (bsp_status)(status);                                                                  \
    })
#define scene_fail(s, err, status, ...)                                                        \
    FAIL_WITH(status, scene_fail_record((s), (err), (status), __VA_ARGS__))
#define error_set(err, status, ...) FAIL_WITH(status, error_record((err), (status), __VA_ARGS__))

/* Adds a warning string (copied) unless the list is full. */
HIDDEN void scene_warn(bsp_scene *s, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));

/* Emits the one-warning-per-kind summary of dropped primitives; loaders call
 * it once at the end. Idempotent. */
HIDDEN void scene_finish(bsp_scene *s);

/* Sets where the next primitives come from, for messages (NAME borrowed). */
HIDDEN void scene_set_source(bsp_scene *s, const char *name, size_t line);

/* The scene's scale: the largest absolute coordinate of its bounds, at least
 * 1. Offsets for secondary rays and kd-tree padding are relative to it. */
HIDDEN double scene_scale(const bsp_scene *s);
/* Sets far_origin and hit_tol from the scale (after bounds change). */
HIDDEN void scene_update_scale(bsp_scene *s);

/* The precision domain of exact queries. Exactness of the kd-trees
 * (kd_tree.h) needs the rounding error of the points they compute, about
 * 1e-16 (|o| + |d t|), far below their padding. The points lie in the root
 * box, so |d t| <= |o| + the box, and an origin within RAY_FAR_ORIGIN_REL
 * scene scales (the sum of its absolute coordinates) keeps the error near
 * 1e-9 scales, 1/100 of the padding; dot(d, d) within [RAY_DIR_DOT_MIN,
 * RAY_DIR_DOT_MAX] keeps the kernels' products of d with scene coordinates
 * (at most 1e30) clear of overflow and underflow. Rays outside (an origin
 * 1e7 scene sizes away, a direction of length 1e-300, NaN) are answered by
 * the naive loop without the kernels' hit check, whose distance would be
 * below their rounding error there. */
#define RAY_FAR_ORIGIN_REL 1e6
#define RAY_DIR_DOT_MIN 1e-200
#define RAY_DIR_DOT_MAX 1e200

/* 1 when the ray from O with dot(d, d) = DD lies in S's precision domain:
 * the sum of O's absolute coordinates (one compare for three; a bound of
 * the largest) at most far_origin, DD within [RAY_DIR_DOT_MIN,
 * RAY_DIR_DOT_MAX]. NaN propagates into the sum and fails every comparison,
 * so it is outside too. */
static inline int scene_ray_in_domain(const bsp_scene *s, const double o[3], double dd)
{
    double o1 = fabs(o[0]) + fabs(o[1]) + fabs(o[2]);
    return o1 <= s->far_origin && dd >= RAY_DIR_DOT_MIN && dd <= RAY_DIR_DOT_MAX;
}

/* The kernels' view of RAY for queries on S: with the hit check in the
 * precision domain, without it outside. */
static inline void scene_isect_ray_init(const bsp_scene *s, isect_ray *r, const bsp_ray *ray)
{
    isect_ray_init(r, ray, INFINITY, &s->tri_reach);
    if (scene_ray_in_domain(s, ray->org.v, r->dd))
        r->tol = s->hit_tol;
}

/* Reads an NFF file (plain or gzip): bsp_scene_load without the dispatch. */
HIDDEN bsp_status nff_load_file(const char *path, bsp_scene **out, bsp_error *err);
HIDDEN bsp_status obj_load_file(const char *path, bsp_scene **out, bsp_error *err);
HIDDEN bsp_status ply_load_file(const char *path, bsp_scene **out, bsp_error *err);

/* Whether BUF[0..LEN) starts as gzip data does (magic bytes 1f 8b). */
HIDDEN int scene_is_gzip(const char *buf, size_t len);
/* Inflates the gzip (or zlib) data IN[0..INLEN), concatenated members
 * included, into a new buffer *OUT of *OUTLEN bytes (free with free());
 * BSP_ERR_LIMIT when it inflates to more than LIMIT bytes, BSP_ERR_PARSE
 * for corrupt or truncated data. Errors are "NAME: ...". (gunzip.c) */
HIDDEN bsp_status scene_gunzip(const char *in, size_t inlen, const char *name, size_t limit,
                               char **out, size_t *outlen, bsp_error *err);
/* A reader's parser: BUF[0..LEN) named NAME (a path or "<memory>") into a
 * new scene *OUT. */
typedef bsp_status (*scene_parse_fn)(const char *buf, size_t len, const char *name,
                                     bsp_scene **out, bsp_error *err);
/* PARSE on BUF[0..LEN), inflated first (scene_gunzip, under LIMIT) when it
 * is gzip data or GZIP is set. */
HIDDEN bsp_status scene_parse_maybe_gzip(scene_parse_fn parse, const char *buf, size_t len,
                                         const char *name, size_t limit, int gzip,
                                         bsp_scene **out, bsp_error *err);

/* A hit of one primitive as the intersection loops keep it: t, and for
 * triangles the unnormalised barycentrics and determinant (u = bu / det,
 * v = bv / det, divided out once for the final hit by scene_hit_finish);
 * other shapes have bu = bv = 0, det = 1. */
typedef struct scene_isect_hit {
    double t, bu, bv, det;
} scene_isect_hit;

/* triangle_isect_near_edge (geom/isect.h) on primitive PRIM's vertices in S,
 * for a triangle the direct test found near an edge. Not inlined, and
 * taking S and PRIM rather than the vertices: the lookup kept inline cost
 * the loops it sits in 1.5 % more instructions (dragon res3). Rays come
 * here on purpose (none in the default renders of the dragon, teapot,
 * tetra or gears). */
static __attribute__((noinline, unused)) int
scene_triangle_near_edge(const bsp_scene *s, uint32_t prim, const triangle_edges *tr,
                         const isect_ray *ray, double tmax, scene_isect_hit *h)
{
    return triangle_isect_near_edge(tr, &s->triangles[s->prims[prim].slot].verts, ray, tmax,
                                    &h->t, &h->bu, &h->bv, &h->det);
}

/* The kernel of a shape of kind SHAPE whose data is at DATA (its
 * triangle_edges, sphere_shape, polygon_shape or cone_shape, in the scene
 * or a copy of it: the kd-tree's, accel/kd_local.h), inline with the
 * kernels of geom/isect.h; polygons read S's vertex and slab pools, and a
 * triangle near an edge its vertices there (primitive PRIM; EDGE_EXP its
 * triangle_edge_exp). The t computed never depends on ray->tmin / TMAX,
 * which only filter. Writes *H only on a hit. */
static inline __attribute__((always_inline)) int
shape_isect(const bsp_scene *s, unsigned shape, const void *data, uint32_t prim, int edge_exp,
            const isect_ray *ray, double tmax, scene_isect_hit *h)
{
    /* triangles first: the switch's compare tree costs them 2-3 more
     * instructions per test (tetra, teapot and nurbtst are all triangles) */
    if (__builtin_expect(shape == SHAPE_TRIANGLE, 1)) {
        int r = triangle_isect(data, triangle_edge_norm(edge_exp), ray, tmax, &h->t, &h->bu,
                               &h->bv, &h->det);
        if (__builtin_expect(r == TRIANGLE_NEAR_EDGE, 0))
            r = scene_triangle_near_edge(s, prim, data, ray, tmax, h);
        return r;
    }
    switch ((shape_kind)shape) {
    case SHAPE_SPHERE:
        if (!sphere_isect(data, ray, tmax, &h->t))
            return 0;
        break;
    case SHAPE_POLYGON:
        if (!polygon_isect(data, s->verts, &s->slabs, ray, tmax, &h->t))
            return 0;
        break;
    case SHAPE_CONE:
        if (!cone_isect(data, ray, tmax, &h->t))
            return 0;
        break;
    default:
        return 0;
    }
    h->bu = 0.0;
    h->bv = 0.0;
    h->det = 1.0;
    return 1;
}

/* Intersection of primitive PRIM of S (shape_isect on the scene's data), as
 * the naive method tests it. A triangle's edges are made here from its
 * vertices, as every copy makes them (triangle_edges_of). */
static inline __attribute__((always_inline)) int
scene_isect(const bsp_scene *s, uint32_t prim, const isect_ray *ray, double tmax,
            scene_isect_hit *h)
{
    const prim_record *p = &s->prims[prim];
    const void *data;
    switch ((shape_kind)p->shape) {
    case SHAPE_TRIANGLE: {
        const triangle_shape *tr = &s->triangles[p->slot];
        const triangle_edges e = triangle_edges_of(&tr->verts);
        return shape_isect(s, SHAPE_TRIANGLE, &e, prim, tr->edge_exp, ray, tmax, h);
    }
    case SHAPE_SPHERE:
        data = &s->spheres[p->slot];
        break;
    case SHAPE_POLYGON:
        data = &s->polygons[p->slot];
        break;
    case SHAPE_CONE:
        data = &s->cones[p->slot];
        break;
    default:
        return 0;
    }
    return shape_isect(s, p->shape, data, prim, 0, ray, tmax, h);
}

/* The public hit record of H on primitive PRIM. */
static inline void scene_hit_finish(const scene_isect_hit *h, uint32_t prim, bsp_hit *hit)
{
    hit->t = h->t;
    hit->prim = prim;
    triangle_uv(h->bu, h->bv, h->det, &hit->u, &hit->v); /* 0 / 1 = 0 for the others */
}

/* One primitive against a public ray (bsp_scene_intersect_prim, tools). */
static inline int scene_intersect(const bsp_scene *s, uint32_t prim, const bsp_ray *ray,
                                  bsp_hit *hit)
{
    isect_ray r;
    scene_isect_ray_init(s, &r, ray);
    scene_isect_hit h;
    if (!scene_isect(s, prim, &r, ray->tmax, &h))
        return 0;
    scene_hit_finish(&h, prim, hit);
    return 1;
}

#endif /* BSPRAY_SCENE_INTERNAL_H */
