/*
 * naive_blocks.h — the naive method's copy of the primitives in blocks of
 * four of one shape, tested four at a time (naive_blocks.c).
 *
 * Why: the naive method is the reference every test compares with, and its
 * O(N) scans were over half of the test suite's time. Almost every test of
 * a scan is a miss, and most misses are decided by the kernel's first test
 * alone: the sphere's and cone's discriminant below zero, the triangle's
 * barycentric range, the polygon's plane behind the ray or beyond the best
 * hit (the polygon's inside test comes after). A block computes that first test
 * for four primitives at once, by the very expressions of geom/isect.h in
 * the same order, and only the primitives that pass it go through the
 * kernel itself (scene_isect). IEEE arithmetic gives each lane the bits the
 * scalar expression gives, so a block rejects exactly the primitives whose
 * kernel returns at that test: the answers, t bit for bit included, are the
 * scalar loop's (naive.c), whatever the order of the blocks.
 *
 * Order: the blocks go by shape, not by index. The closest hit is the least
 * (t, index) pair, which no order changes (a kernel's t does not depend on
 * tmax, and a lowered tmax only drops roots beyond the best hit); the
 * any-hit answer is whether any primitive hits, which no order changes
 * either. Only the any-hit scan's count of tests (where it stops) differs.
 */
#ifndef BSPRAY_ACCEL_NAIVE_BLOCKS_H
#define BSPRAY_ACCEL_NAIVE_BLOCKS_H

#include "accel/accel_internal.h"

#define NAIVE_LANES 4

/* Lanes past a shape's last primitive hold NaN data (their first test fails)
 * and prim BSP_NO_PRIM (never passed to the kernel). */
typedef struct naive_sphere_block {
    double cx[NAIVE_LANES], cy[NAIVE_LANES], cz[NAIVE_LANES], r2[NAIVE_LANES];
    uint32_t prim[NAIVE_LANES];
} naive_sphere_block;

typedef struct naive_cone_block {
    double bx[NAIVE_LANES], by[NAIVE_LANES], bz[NAIVE_LANES]; /* base */
    double ax[NAIVE_LANES], ay[NAIVE_LANES], az[NAIVE_LANES]; /* unit axis */
    double mx[NAIVE_LANES], my[NAIVE_LANES], mz[NAIVE_LANES]; /* middle of the axis,
                                                                  as cone_isect computes it */
    double base_radius[NAIVE_LANES], slope[NAIVE_LANES], far2[NAIVE_LANES];
    uint32_t prim[NAIVE_LANES];
} naive_cone_block;

typedef struct naive_triangle_block {
    double vx[NAIVE_LANES], vy[NAIVE_LANES], vz[NAIVE_LANES];       /* v0 */
    double e1x[NAIVE_LANES], e1y[NAIVE_LANES], e1z[NAIVE_LANES];    /* v1 - v0 */
    double e2x[NAIVE_LANES], e2y[NAIVE_LANES], e2z[NAIVE_LANES];    /* v2 - v0 */
    uint32_t prim[NAIVE_LANES];
} naive_triangle_block;

typedef struct naive_polygon_block {
    double nx[NAIVE_LANES], ny[NAIVE_LANES], nz[NAIVE_LANES]; /* unit normal */
    double d[NAIVE_LANES];                                    /* the plane's distance */
    uint32_t prim[NAIVE_LANES];
} naive_polygon_block;

typedef struct naive_blocks {
    naive_sphere_block *spheres;
    naive_cone_block *cones;
    naive_triangle_block *triangles;
    naive_polygon_block *polygons;
    size_t nsphere_blocks, ncone_blocks, ntriangle_blocks, npolygon_blocks;
    size_t nspheres, ncones, ntriangles, npolygons; /* primitives in the blocks */
    /* per scene primitive: its position in the scan (spheres, cones,
     * triangles, polygons, each in index order); dropped ones SIZE_MAX */
    size_t *rank;
    size_t nprims;
} naive_blocks;

/* Makes the blocks of S's live primitives: BSP_OK, or BSP_ERR_NOMEM. */
HIDDEN bsp_status naive_blocks_build(const bsp_scene *s, naive_blocks **out, bsp_error *err);
HIDDEN void naive_blocks_destroy(void *blocks);
/* The bytes naive_blocks_build would take for S (the memory limit's check). */
HIDDEN size_t naive_blocks_bytes(const bsp_scene *s);

/* naive_scene_intersect and naive_scene_occluded, the same answers, by blocks
 * B made of S. */
HIDDEN int naive_blocks_intersect(const naive_blocks *b, const bsp_scene *s, bsp_query *q,
                                  const bsp_ray *ray, uint32_t from, bsp_hit *hit);
HIDDEN int naive_blocks_occluded(const naive_blocks *b, const bsp_scene *s, bsp_query *q,
                                 const bsp_ray *ray, uint32_t from);

#endif /* BSPRAY_ACCEL_NAIVE_BLOCKS_H */
