/*
 * naive_blocks.c — the naive method's scans four primitives at a time
 * (naive_blocks.h says why, and why the answers are the scalar loop's).
 *
 * The first tests are the kernels' own text (geom/isect_first.h),
 * instantiated here for vectors of two doubles (GCC/Clang vector extensions:
 * SSE2 on x86-64, NEON on AArch64), two per block of four; a vector
 * operation rounds each lane as the scalar one does. Floating-point
 * contraction is off in the build (-ffp-contract=off), so no compiler fuses
 * a multiply-add in one instance and not in the other. What is this file's
 * own is small: the blocks' layout, the broadcast ray, the select that
 * takes the moved cone origin where it applies, and the bookkeeping of the
 * scan. test_naive.c compares every scan with the scalar loop.
 */
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "accel/naive_blocks.h"

typedef double nv2 __attribute__((vector_size(16)));
typedef __typeof__((nv2){0.0, 0.0} < (nv2){0.0, 0.0}) nm2; /* a comparison's lanes: 0 or -1 */

/* Lanes H * 2 and H * 2 + 1 of the block array FIELD. */
static inline nv2 lanes(const double *field, int h)
{
    nv2 v;
    memcpy(&v, field + 2 * h, sizeof v);
    return v;
}

static inline nv2 splat(double x)
{
    return (nv2){x, x};
}

/* Bits 0 and 1: the lanes of M that are set. */
static inline unsigned mask_bits(nm2 m)
{
    return (unsigned)(m[0] & 1) | (unsigned)(m[1] & 2);
}

/* A where M is set, B elsewhere. */
static inline nv2 select2(nm2 m, nv2 a, nv2 b)
{
    nm2 ia, ib;
    memcpy(&ia, &a, sizeof ia);
    memcpy(&ib, &b, sizeof ib);
    nm2 r = (ia & m) | (ib & ~m);
    nv2 out;
    memcpy(&out, &r, sizeof out);
    return out;
}

/* -X where M is set, X elsewhere: the sign bit flipped, as unary minus does. */
static inline nv2 negate_where(nm2 m, nv2 x)
{
    return select2(m, -x, x);
}

/* |X|: the sign bit cleared, as fabs does. */
static inline nv2 abs2(nv2 x)
{
    typedef int64_t bits2 __attribute__((vector_size(16)));
    bits2 bits;
    memcpy(&bits, &x, sizeof bits);
    bits &= (bits2){INT64_MAX, INT64_MAX};
    nv2 out;
    memcpy(&out, &bits, sizeof out);
    return out;
}

/* The kernels' first tests (geom/isect_first.h) on two lanes at a time. */
#define ISECT_T nv2
#define ISECT_MASK nm2
#define ISECT_FIRST(name) name##_v2
#define ISECT_NEG_WHERE(m, x) negate_where((m), (x))
#define ISECT_ZERO splat(0.0)
#define ISECT_ABS(x) abs2(x)
#include "geom/isect_first.h"
#undef ISECT_T
#undef ISECT_MASK
#undef ISECT_FIRST
#undef ISECT_NEG_WHERE
#undef ISECT_ZERO
#undef ISECT_ABS

/* One scan's state: the closest hit so far (ANY: the first hit found). */
typedef struct scan {
    const bsp_scene *s;
    const isect_ray *r;
    uint32_t from;
    double tmax;
    scene_isect_hit best;
    uint32_t best_p;
} scan;

/* The ray, broadcast. */
typedef struct ray2 {
    nv2 ox, oy, oz, dx, dy, dz, dd, tri_bound;
} ray2;

/* sphere_isect's first test on lanes H * 2 and H * 2 + 1. */
static inline unsigned sphere_pass(const naive_sphere_block *b, int h, const ray2 *r,
                                   const scan *sc)
{
    (void)sc;
    nv2 ocx = r->ox - lanes(b->cx, h), ocy = r->oy - lanes(b->cy, h),
        ocz = r->oz - lanes(b->cz, h), bb;
    nv2 disc = sphere_disc_v2(ocx, ocy, ocz, r->dx, r->dy, r->dz, r->dd, lanes(b->r2, h), &bb);
    return mask_bits(disc >= splat(0.0));
}

/* cone_isect's first test, from the origin it solves from (moved along the
 * ray when far from the base): passes when qa == 0 (the kernel's linear
 * case, left to it) or the discriminant is >= 0. */
static inline unsigned cone_pass(const naive_cone_block *b, int h, const ray2 *r,
                                 const scan *sc)
{
    (void)sc;
    nv2 bx = lanes(b->bx, h), by = lanes(b->by, h), bz = lanes(b->bz, h);
    nv2 ocx = r->ox - bx, ocy = r->oy - by, ocz = r->oz - bz;
    nm2 far = cone_origin_far_v2(ocx, ocy, ocz, lanes(b->far2, h));
    if (mask_bits(far)) {
        nv2 mx, my, mz;
        cone_moved_origin_v2(r->ox, r->oy, r->oz, r->dx, r->dy, r->dz, r->dd, lanes(b->mx, h),
                             lanes(b->my, h), lanes(b->mz, h), bx, by, bz, &mx, &my, &mz);
        ocx = select2(far, mx, ocx);
        ocy = select2(far, my, ocy);
        ocz = select2(far, mz, ocz);
    }
    nv2 h0, hd, qa, qb, qc;
    nv2 disc = cone_quadratic_v2(ocx, ocy, ocz, r->dx, r->dy, r->dz, lanes(b->ax, h),
                                 lanes(b->ay, h), lanes(b->az, h), lanes(b->base_radius, h),
                                 lanes(b->slope, h), &h0, &hd, &qa, &qb, &qc);
    return mask_bits((qa == splat(0.0)) | (disc >= splat(0.0)));
}

/* triangle_solve's first test (the direct solution): the barycentric range
 * widened by the ray's bound of the margin (isect_ray.tri_bound), as the
 * kernel's first test widens it. A miss there is the kernel's miss (its
 * careful path runs only after a direct hit fails the hit check). */
static inline unsigned triangle_pass(const naive_triangle_block *b, int h, const ray2 *r,
                                     const scan *sc)
{
    (void)sc;
    const nv2 tx = r->ox - lanes(b->vx, h), ty = r->oy - lanes(b->vy, h),
              tz = r->oz - lanes(b->vz, h);
    const nv2 e1x = lanes(b->e1x, h), e1y = lanes(b->e1y, h), e1z = lanes(b->e1z, h);
    const nv2 e2x = lanes(b->e2x, h), e2y = lanes(b->e2y, h), e2z = lanes(b->e2z, h);
    nv2 det, bu, bv, qx, qy, qz;
    triangle_bary_v2(r->dx, r->dy, r->dz, tx, ty, tz, e1x, e1y, e1z, e2x, e2y, e2z, &det, &bu, &bv,
                     &qx, &qy, &qz);
    nm2 neg;
    return mask_bits(triangle_range_v2(&det, &bu, &bv, r->tri_bound, &neg));
}

/* polygon_isect's first test: the plane met at t in [tmin, tmax], tmax the
 * best hit's t so far. */
static inline unsigned polygon_pass(const naive_polygon_block *b, int h, const ray2 *r,
                                    const scan *sc)
{
    const nv2 tmin = splat(sc->r->tmin), tmax = splat(sc->tmax);
    nv2 denom;
    nv2 tt = polygon_plane_v2(lanes(b->nx, h), lanes(b->ny, h), lanes(b->nz, h), lanes(b->d, h),
                              r->ox, r->oy, r->oz, r->dx, r->dy, r->dz, &denom);
    return mask_bits((denom != splat(0.0)) & (tt >= tmin) & (tt <= tmax));
}

/* The kernel on the lanes of PRIM that PASS marks; for an any-hit scan
 * returns 1 at the first hit. A closest hit replaces the best one when it is
 * the lesser (t, index) pair: the scalar loop's winner, met in another order. */
static inline __attribute__((always_inline)) int scan_lanes(scan *sc, const uint32_t *prim,
                                                            unsigned pass, const int any)
{
    for (; pass; pass &= pass - 1) {
        uint32_t p = prim[__builtin_ctz(pass)];
        if (p == sc->from || p == BSP_NO_PRIM)
            continue;
        scene_isect_hit h;
        if (!scene_isect(sc->s, p, sc->r, sc->tmax, &h))
            continue;
        if (any)
            return 1;
        if (sc->best_p == BSP_NO_PRIM || h.t < sc->best.t ||
            (h.t == sc->best.t && p < sc->best_p)) {
            sc->best = h;
            sc->best_p = p;
            sc->tmax = h.t;
        }
    }
    return 0;
}

/* The primitives scanned when block K (counted from 0) of a shape with N
 * primitives is done: its padding lanes are no primitives. */
static inline size_t scanned(size_t k, size_t n)
{
    size_t upto = (k + 1) * NAIVE_LANES;
    return upto < n ? upto : n;
}

/* The blocks BLOCKS[0 .. NBLOCKS) of a shape with N primitives, tested by
 * PASS two lanes at a time: scan_all's loop, once per shape. */
#define SCAN_SHAPE(BLOCKS, NBLOCKS, N, PASS)                                                   \
    for (size_t k = 0; k < (NBLOCKS); k++) {                                                   \
        unsigned pass = PASS(&(BLOCKS)[k], 0, &rv, sc) | PASS(&(BLOCKS)[k], 1, &rv, sc) << 2;  \
        if (pass && scan_lanes(sc, (BLOCKS)[k].prim, pass, any)) {                             \
            *done = base + scanned(k, (N));                                                    \
            return 1;                                                                          \
        }                                                                                      \
    }                                                                                          \
    base += (N)

/* Scans every block; ANY: stops at the first hit, returning 1. *DONE: the
 * primitives scanned (all of them, or those up to the block of the hit),
 * numbered by their position in the scan as rank[] numbers them. */
static inline __attribute__((always_inline)) int scan_all(const naive_blocks *b, scan *sc,
                                                          const int any, size_t *done)
{
    const isect_ray *r = sc->r;
    const ray2 rv = {splat(r->org.x), splat(r->org.y), splat(r->org.z), splat(r->dir.x),
                     splat(r->dir.y), splat(r->dir.z), splat(r->dd), splat(r->tri_bound)};
    size_t base = 0;
    SCAN_SHAPE(b->spheres, b->nsphere_blocks, b->nspheres, sphere_pass);
    SCAN_SHAPE(b->cones, b->ncone_blocks, b->ncones, cone_pass);
    SCAN_SHAPE(b->triangles, b->ntriangle_blocks, b->ntriangles, triangle_pass);
    SCAN_SHAPE(b->polygons, b->npolygon_blocks, b->npolygons, polygon_pass);
    *done = base;
    return 0;
}

#undef SCAN_SHAPE

/* Whether FROM is a primitive B scans within its first DONE (then it is left
 * out, untested). */
static int from_scanned(const naive_blocks *b, uint32_t from, size_t done)
{
    return from < b->nprims && b->rank[from] < done;
}

int naive_blocks_intersect(const naive_blocks *b, const bsp_scene *s, bsp_query *q,
                           const bsp_ray *ray, uint32_t from, bsp_hit *hit)
{
    isect_ray r;
    scene_isect_ray_init(s, &r, ray);
    scan sc = {s, &r, from, ray->tmax, {INFINITY, 0.0, 0.0, 1.0}, BSP_NO_PRIM};
    size_t done;
    scan_all(b, &sc, 0, &done);
    q->counters.isect_tests += done - (size_t)from_scanned(b, from, done);
    hit->prim = BSP_NO_PRIM;
    if (sc.best_p == BSP_NO_PRIM)
        return 0;
    scene_hit_finish(&sc.best, sc.best_p, hit);
    return 1;
}

int naive_blocks_occluded(const naive_blocks *b, const bsp_scene *s, bsp_query *q,
                          const bsp_ray *ray, uint32_t from)
{
    isect_ray r;
    scene_isect_ray_init(s, &r, ray);
    scan sc = {s, &r, from, ray->tmax, {INFINITY, 0.0, 0.0, 1.0}, BSP_NO_PRIM};
    size_t done;
    int hit = scan_all(b, &sc, 1, &done);
    q->counters.isect_tests += done - (size_t)from_scanned(b, from, done);
    return hit;
}

static size_t blocks_of(size_t n)
{
    return (n + NAIVE_LANES - 1) / NAIVE_LANES;
}

/* The shapes in the order the scan takes them (scan_all's SCAN_SHAPE lines). */
static const shape_kind scan_order[4] = {SHAPE_SPHERE, SHAPE_CONE, SHAPE_TRIANGLE, SHAPE_POLYGON};

/* N[shape]: how many live primitives of S have each shape (one pass). */
static void count_shapes(const bsp_scene *s, size_t n[SHAPE_NONE])
{
    memset(n, 0, SHAPE_NONE * sizeof *n);
    for (size_t i = 0; i < s->nprims; i++)
        if (s->prims[i].shape < SHAPE_NONE)
            n[s->prims[i].shape]++;
}

size_t naive_blocks_bytes(const bsp_scene *s)
{
    size_t n[SHAPE_NONE];
    count_shapes(s, n);
    return sizeof(naive_blocks) + s->nprims * sizeof(size_t) +
           blocks_of(n[SHAPE_SPHERE]) * sizeof(naive_sphere_block) +
           blocks_of(n[SHAPE_CONE]) * sizeof(naive_cone_block) +
           blocks_of(n[SHAPE_TRIANGLE]) * sizeof(naive_triangle_block) +
           blocks_of(n[SHAPE_POLYGON]) * sizeof(naive_polygon_block);
}

void naive_blocks_destroy(void *blocks)
{
    naive_blocks *b = blocks;
    if (!b)
        return;
    free(b->spheres);
    free(b->cones);
    free(b->triangles);
    free(b->polygons);
    free(b->rank);
    free(b);
}

/* Fills every lane of the N blocks of SIZE bytes at BLOCKS with NaN data and
 * BSP_NO_PRIM, the padding's values; the primitives then overwrite theirs.
 * Every block type is doubles followed by its NAIVE_LANES primitive indices,
 * with no padding (asserted below). */
#define NAIVE_BLOCK_LAYOUT(T)                                                                  \
    _Static_assert(offsetof(T, prim) % sizeof(double) == 0 &&                                  \
                       offsetof(T, prim) + sizeof(((T *)0)->prim) == sizeof(T),                \
                   #T ": doubles, then the primitive indices")
NAIVE_BLOCK_LAYOUT(naive_sphere_block);
NAIVE_BLOCK_LAYOUT(naive_cone_block);
NAIVE_BLOCK_LAYOUT(naive_triangle_block);
NAIVE_BLOCK_LAYOUT(naive_polygon_block);
#undef NAIVE_BLOCK_LAYOUT
static void pad_blocks(void *blocks, size_t n, size_t size)
{
    const size_t ndoubles = (size - NAIVE_LANES * sizeof(uint32_t)) / sizeof(double);
    for (size_t k = 0; k < n; k++) {
        char *blk = (char *)blocks + k * size;
        for (size_t j = 0; j < ndoubles; j++) {
            const double nan = NAN;
            memcpy(blk + j * sizeof(double), &nan, sizeof nan);
        }
        for (size_t j = 0; j < NAIVE_LANES; j++) {
            const uint32_t none = BSP_NO_PRIM;
            memcpy(blk + ndoubles * sizeof(double) + j * sizeof(uint32_t), &none, sizeof none);
        }
    }
}

/* Lane L of the block arrays X, Y and Z: the components of V. */
static void put3(double *x, double *y, double *z, size_t l, bsp_vec3 v)
{
    x[l] = v.x;
    y[l] = v.y;
    z[l] = v.z;
}

bsp_status naive_blocks_build(const bsp_scene *s, naive_blocks **out, bsp_error *err)
{
    *out = NULL;
    naive_blocks *b = calloc(1, sizeof *b);
    if (!b)
        return error_set(err, BSP_ERR_NOMEM, NULL, 0, "out of memory (naive method's blocks)");
    size_t n[SHAPE_NONE];
    count_shapes(s, n);
    b->nspheres = n[SHAPE_SPHERE];
    b->ncones = n[SHAPE_CONE];
    b->ntriangles = n[SHAPE_TRIANGLE];
    b->npolygons = n[SHAPE_POLYGON];
    b->nsphere_blocks = blocks_of(b->nspheres);
    b->ncone_blocks = blocks_of(b->ncones);
    b->ntriangle_blocks = blocks_of(b->ntriangles);
    b->npolygon_blocks = blocks_of(b->npolygons);
    b->nprims = s->nprims;
    /* malloc(0) may return NULL: every array gets at least one element */
    b->spheres = malloc((b->nsphere_blocks + 1) * sizeof *b->spheres);
    b->cones = malloc((b->ncone_blocks + 1) * sizeof *b->cones);
    b->triangles = malloc((b->ntriangle_blocks + 1) * sizeof *b->triangles);
    b->polygons = malloc((b->npolygon_blocks + 1) * sizeof *b->polygons);
    b->rank = malloc((s->nprims + 1) * sizeof *b->rank);
    if (!b->spheres || !b->cones || !b->triangles || !b->polygons || !b->rank) {
        naive_blocks_destroy(b);
        return error_set(err, BSP_ERR_NOMEM, NULL, 0, "out of memory (naive method's blocks)");
    }
    pad_blocks(b->spheres, b->nsphere_blocks, sizeof *b->spheres);
    pad_blocks(b->cones, b->ncone_blocks, sizeof *b->cones);
    pad_blocks(b->triangles, b->ntriangle_blocks, sizeof *b->triangles);
    pad_blocks(b->polygons, b->npolygon_blocks, sizeof *b->polygons);
    /* next[shape]: the scan position of the shape's next primitive; its
     * position among its shape's is that less first[shape] */
    size_t first[SHAPE_NONE], next[SHAPE_NONE], at = 0;
    for (size_t k = 0; k < sizeof scan_order / sizeof *scan_order; k++) {
        first[scan_order[k]] = next[scan_order[k]] = at;
        at += n[scan_order[k]];
    }
    for (size_t i = 0; i < s->nprims; i++) {
        const prim_record *p = &s->prims[i];
        if (p->shape >= SHAPE_NONE) {
            b->rank[i] = SIZE_MAX;
            continue;
        }
        b->rank[i] = next[p->shape];
        size_t j = next[p->shape]++ - first[p->shape], l = j % NAIVE_LANES;
        switch ((shape_kind)p->shape) {
        case SHAPE_SPHERE: {
            const sphere_shape *sp = &s->spheres[p->slot];
            naive_sphere_block *blk = &b->spheres[j / NAIVE_LANES];
            put3(blk->cx, blk->cy, blk->cz, l, sp->center);
            blk->r2[l] = sp->radius2;
            blk->prim[l] = (uint32_t)i;
            break;
        }
        case SHAPE_CONE: {
            const cone_shape *c = &s->cones[p->slot];
            naive_cone_block *blk = &b->cones[j / NAIVE_LANES];
            put3(blk->bx, blk->by, blk->bz, l, c->base);
            put3(blk->ax, blk->ay, blk->az, l, c->axis);
            put3(blk->mx, blk->my, blk->mz, l, cone_axis_middle(c));
            blk->base_radius[l] = c->base_radius;
            blk->slope[l] = c->slope;
            blk->far2[l] = c->far2;
            blk->prim[l] = (uint32_t)i;
            break;
        }
        case SHAPE_TRIANGLE: {
            const triangle_shape *tr = &s->triangles[p->slot];
            const triangle_edges t = triangle_edges_of(&tr->verts);
            naive_triangle_block *blk = &b->triangles[j / NAIVE_LANES];
            put3(blk->vx, blk->vy, blk->vz, l, t.v0);
            put3(blk->e1x, blk->e1y, blk->e1z, l, t.e1);
            put3(blk->e2x, blk->e2y, blk->e2z, l, t.e2);
            blk->prim[l] = (uint32_t)i;
            break;
        }
        case SHAPE_POLYGON: {
            const polygon_shape *pg = &s->polygons[p->slot];
            naive_polygon_block *blk = &b->polygons[j / NAIVE_LANES];
            put3(blk->nx, blk->ny, blk->nz, l, pg->normal);
            blk->d[l] = pg->d;
            blk->prim[l] = (uint32_t)i;
            break;
        }
        default:
            break;
        }
    }
    *out = b;
    return BSP_OK;
}
