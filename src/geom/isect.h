/*
 * isect.h — the ray–shape intersection kernels, static inline so that the
 * intersection loops of every method (naive, kd-tree leaves) inline them.
 * The out-of-line *_intersect functions of shapes.h are thin wrappers.
 *
 * A kernel sees the ray as an isect_ray: origin, direction, dot(dir, dir)
 * (computed once per ray: the same expression, so the same bits, as a
 * per-test computation would give) and the interval. It writes *t only on a
 * hit, and computes t without reference to tmin/tmax (they only filter), so
 * every caller, whatever its interval, gets the same t bit for bit. The
 * contract of shapes.h holds for each kernel.
 *
 * Hit check: the triangle, sphere and cone kernels accept a root only when
 * the ray's point at that t lies within ray->tol of the shape. Without it a
 * ray in a triangle's plane "hit" the triangle at t = 0, a triangle-width
 * outside it, a line that misses a cone "hit" it, and a tangent from a
 * sphere's surface "hit" the sphere three radii out: phantoms that no
 * kd-tree lists where they lie (kd_tree.h needs every hit within its padding
 * of the shape). The test is part of the kernel, so every method applies it
 * alike. Where a real hit's point can err by more than tol (a thin triangle
 * or a cone seen from far away), the kernel solves from a point of the ray
 * near the shape instead (triangle_isect_near, cone_isect), decided by the
 * ray and the shape alone, never by tmin/tmax. Polygons need no check: the
 * inside test runs on the computed point (near an edge, the distance from
 * the edges is checked where the watertight test decides: polygon_isect).
 *
 * Watertight: where a ray passes within rounding of a triangle's or a
 * polygon's edge, inside or outside is decided on the ray's own shear from
 * the vertices themselves (triangle_watertight, polygon_watertight), so two
 * faces that share an edge see it as the same line and a closed mesh lets
 * no ray through (docs/precision.md).
 */
#ifndef BSPRAY_GEOM_ISECT_H
#define BSPRAY_GEOM_ISECT_H

#include <math.h>

#include "geom/shapes.h"
#include "geom/vec.h"

/* The kernels are small enough to inline into every loop that calls them. */
#define ISECT_INLINE static inline __attribute__((always_inline))

/* The ray as the kernels see it; the upper end of the interval is a separate
 * argument TMAX, since the closest-hit loops lower it to the best hit. */
typedef struct isect_ray {
    bsp_vec3 org, dir;
    double dd;   /* dot(dir, dir) */
    double tmin; /* accepted t: tmin <= t <= tmax (closed) */
    double tol;  /* the hit check's distance (above); INFINITY: no check */
    double edge_scale; /* 2^-40 |dir|_1: the triangle's margin (triangle_margin) */
    double tri_bound;  /* at least the triangle_margin of every triangle within the
                          triangle_reach the ray was made with (INFINITY: none given) */
    double org_norm, dir_norm; /* |org|_1, |dir|_1: the polygon's margin (polygon_margin) */
} isect_ray;

/* Where a scene's triangles lie, for isect_ray.tri_bound: every vertex v has
 * |v|_1 <= radius, and every triangle's triangle_edge_norm is at most enorm
 * (0: no triangles). */
typedef struct triangle_reach {
    double radius, enorm;
} triangle_reach;

/* The hit check's distance relative to the scene scale (scene_internal.h):
 * a quarter of the kd-tree's padding (kd_tree.h defines the padding as four
 * times this), leaving room for the traversal's rounding. Far above the rounding
 * of a well-conditioned hit (about 1e-9 scales at the far end of the
 * precision domain), so no real hit fails it. */
#define ISECT_HIT_TOL_REL 2.5e-8

/* RAY for the kernels, with the hit check's distance TOL; REACH: where the
 * triangles it may be tested against lie, or NULL (not known). tri_bound is
 * twice the margin triangle_margin gives a triangle of size REACH->enorm
 * with |o - v0|_1 = |o|_1 + REACH->radius, at least the true |o - v0|_1;
 * the factor 2 covers the rounding of both expressions. A few operations
 * per ray (a bound from the distance to the scene's centre took 14, most of
 * what it saved), and none of the margin's per test. */
static inline void isect_ray_init(isect_ray *r, const bsp_ray *ray, double tol,
                                  const triangle_reach *reach)
{
    r->org = ray->org;
    r->dir = ray->dir;
    r->dd = v3_dot(ray->dir, ray->dir);
    r->tmin = ray->tmin;
    r->tol = tol;
    r->dir_norm = (fabs(ray->dir.x) + fabs(ray->dir.y)) + fabs(ray->dir.z);
    r->org_norm = (fabs(ray->org.x) + fabs(ray->org.y)) + fabs(ray->org.z);
    r->edge_scale = 0x1p-40 * r->dir_norm;
    r->tri_bound = INFINITY;
    if (reach && reach->enorm > 0.0) {
        const double tn = r->org_norm + reach->radius;
        const double b = 2.0 * (r->edge_scale * ((tn + reach->enorm) * reach->enorm));
        /* none for NaN (an origin of NaN or inf), nor near the subnormals (a
         * direction far outside the precision domain: there a product's
         * rounding is no longer relative, and the bound might fall below a
         * margin; in the domain the bound exceeds 2^-700) */
        if (b >= 0x1p-960)
            r->tri_bound = b;
    }
}

/* The first tests of the sphere, cone, triangle and polygon kernels, for doubles
 * (isect_first.h: one text for these kernels and the naive method's blocks). */
#define ISECT_T double
#define ISECT_MASK int
#define ISECT_FIRST(name) name
#define ISECT_NEG_WHERE(m, x) ((m) ? -(x) : (x))
#define ISECT_ZERO 0.0
#define ISECT_ABS(x) fabs(x)
#include "geom/isect_first.h"
#undef ISECT_T
#undef ISECT_MASK
#undef ISECT_FIRST
#undef ISECT_NEG_WHERE
#undef ISECT_ZERO
#undef ISECT_ABS

/* The roots t0 <= t1 of a t^2 + 2 b t + c = 0 given disc = b^2 - a c >= 0
 * (a != 0), by the stable formula: q = -(b + sign(b) sqrt(disc)), the roots
 * q / a and c / q. */
static inline void quadratic_roots(double a, double b, double c, double disc, double *t0,
                                   double *t1)
{
    double q = -(b + copysign(sqrt(disc), b));
    double r0 = 0.0, r1 = 0.0; /* q == 0: b == 0 and c == 0, a double root at 0 */
    if (q != 0.0) {
        r0 = q / a;
        r1 = c / q;
    }
    *t0 = r0 > r1 ? r1 : r0;
    *t1 = r0 > r1 ? r0 : r1;
}

/* Whether a point at squared distance RHO2 from a centre (or an axis) lies
 * within E of the sphere (or circle) of radius R: |rho - r| <= e by
 * squares, without a square root on the hit's dependency chain. */
static inline int isect_near_radius(double rho2, double r, double e)
{
    double lo = r - e, hi = r + e;
    return rho2 <= hi * hi && (lo <= 0.0 || rho2 >= lo * lo);
}

/* --- sphere (see sphere.c for the numerics) ------------------------------ */

/* The hit check for a sphere: the ray's point at T (OC = org - centre) lies
 * within ray->tol of the surface. A ray starting on the surface along a
 * tangent has b and c both rounding noise, and the root c / q anywhere on
 * the tangent line. */
ISECT_INLINE int sphere_near_surface(const sphere_shape *s, const isect_ray *ray, bsp_vec3 oc,
                                     double t)
{
    if (!(ray->tol < INFINITY))
        return 1;
    bsp_vec3 p = v3_madd(oc, ray->dir, t);
    return isect_near_radius(v3_dot(p, p), s->radius, ray->tol);
}

ISECT_INLINE int sphere_isect(const sphere_shape *s, const isect_ray *ray, double tmax, double *t)
{
    double a = ray->dd;
    if (!(a > 0.0))
        return 0;
    bsp_vec3 d = ray->dir;
    bsp_vec3 oc = v3_sub(ray->org, s->center);
    double b;
    double disc = sphere_disc(oc.x, oc.y, oc.z, d.x, d.y, d.z, a, s->radius2, &b);
    if (!(disc >= 0.0))
        return 0;
    double c = v3_dot(oc, oc) - s->radius2;

    double t0, t1;
    quadratic_roots(a, b, c, disc, &t0, &t1);
    if (t0 >= ray->tmin && t0 <= tmax && sphere_near_surface(s, ray, oc, t0)) {
        *t = t0;
        return 1;
    }
    if (t1 >= ray->tmin && t1 <= tmax && sphere_near_surface(s, ray, oc, t1)) {
        *t = t1;
        return 1;
    }
    return 0;
}

/* --- triangle (Möller–Trumbore, watertight near edges; see triangle.c) ---- */

/* The side of the 2-D point Q from the line through the origin and P, as the
 * sign of px qy - py qx, exactly. The rounded difference of the two rounded
 * products has the exact sign or is 0 (rounding is monotonic: px qy > py qx
 * gives fl(px qy) >= fl(py qx)); at 0, Kahan's form with fused multiply-adds
 * decides (the exact value, rounded once). Swapping P and Q negates the
 * result bit for bit. */
static inline double edge_side(double px, double py, double qx, double qy)
{
    double r = px * qy - py * qx;
    if (r != 0.0)
        return r;
    double w = py * qx;
    double err = fma(-py, qx, w); /* w - py qx, exactly */
    return fma(px, qy, -w) + err;
}

/* The ray's frame of the watertight tests: the axis of the direction's
 * largest component (kz) and the shear that takes the direction onto it. */
typedef struct ray_shear {
    int kx, ky, kz;
    double sx, sy;
} ray_shear;

static inline ray_shear ray_shear_of(const isect_ray *ray)
{
    const double *d = ray->dir.v;
    const double ax = fabs(d[0]), ay = fabs(d[1]), az = fabs(d[2]);
    ray_shear sh;
    sh.kz = ax >= ay ? (ax >= az ? 0 : 2) : (ay >= az ? 1 : 2);
    sh.kx = sh.kz == 2 ? 0 : sh.kz + 1;
    sh.ky = sh.kx == 2 ? 0 : sh.kx + 1;
    sh.sx = d[sh.kx] / d[sh.kz];
    sh.sy = d[sh.ky] / d[sh.kz];
    return sh;
}

/* Vertex V in the ray's frame: the origin subtracted, then sheared along the
 * direction onto the plane across kz (the ray becomes the point (0, 0)).
 * A function of the vertex and the ray alone, so every face sharing the
 * vertex gets the same (*X, *Y). */
static inline void ray_shear_point(const ray_shear *sh, const isect_ray *ray, const bsp_vec3 *v,
                                   double *x, double *y)
{
    const double *o = ray->org.v;
    double h = v->v[sh->kz] - o[sh->kz];
    *x = (v->v[sh->kx] - o[sh->kx]) - sh->sx * h;
    *y = (v->v[sh->ky] - o[sh->ky]) - sh->sy * h;
}

/* Woop, Benthin and Wald's watertight test ("Watertight ray/triangle
 * intersection", JCGT 2013): whether the ray's line passes through the
 * triangle, decided on its vertices in the ray's frame (ray_shear_point).
 * Each edge's side is edge_side of its two ends, so the triangle on the
 * other side of a shared edge computes the same value negated, and the
 * signs are exact: of two triangles sharing an edge, any line through it
 * passes inside at least one, whatever their windings. Both faces count:
 * inside when the three sides agree in sign (zeros agreeing with either);
 * all three 0, a line in the triangle's plane, misses. Not inlined: taken
 * only near an edge (triangle_solve). */
static __attribute__((noinline, unused)) int triangle_watertight(const triangle_verts *tr,
                                                                 const isect_ray *ray)
{
    const ray_shear sh = ray_shear_of(ray);
    double x[3], y[3];
    ray_shear_point(&sh, ray, &tr->v0, &x[0], &y[0]);
    ray_shear_point(&sh, ray, &tr->v1, &x[1], &y[1]);
    ray_shear_point(&sh, ray, &tr->v2, &x[2], &y[2]);
    const double s0 = edge_side(x[1], y[1], x[2], y[2]); /* the edge v1 v2 */
    const double s1 = edge_side(x[2], y[2], x[0], y[0]); /* v2 v0 */
    const double s2 = edge_side(x[0], y[0], x[1], y[1]); /* v0 v1 */
    const int pos = s0 >= 0.0 && s1 >= 0.0 && s2 >= 0.0;
    const int neg = s0 <= 0.0 && s1 <= 0.0 && s2 <= 0.0;
    return (pos || neg) && !(s0 == 0.0 && s1 == 0.0 && s2 == 0.0);
}

/* What triangle_isect returns when the watertight test must decide. */
#define TRIANGLE_NEAR_EDGE 2

/* Whether the unnormalised barycentrics BU, BV and DET - (BU + BV) are all
 * at least X (triangle_solve's tests against its margins). */
static inline int triangle_all_at_least(double bu, double bv, double det, double x)
{
    return bu >= x && bv >= x && det - (bu + bv) >= x;
}

/* How triangle_solve decides inside or outside: by the margin, returning
 * TRIANGLE_NEAR_EDGE within it (DIRECT); or not at all, the caller having
 * decided (DECIDED: the ray's origin; SHIFTED: a point of the ray TS
 * further on, the careful path). */
enum { TRIANGLE_DIRECT, TRIANGLE_DECIDED, TRIANGLE_SHIFTED };

/* Möller–Trumbore for the ray from ORG to the triangle, as triangle_isect
 * describes; returns 1 on a hit, 0 on a miss, TRIANGLE_NEAR_EDGE (DIRECT
 * only), and -1 when a hit fails only the hit check.
 *
 * Inside or outside: where the unnormalised barycentrics bu, bv and
 * det - (bu + bv) are all past the margin (triangle_margin) inside, a hit;
 * any one past it outside, a miss; otherwise (the ray passes within
 * rounding of an edge) the watertight test decides, so that a closed mesh
 * lets no ray through between its faces. The margin is far above either
 * test's rounding, so both agree wherever Möller–Trumbore decides alone,
 * and the answer is the watertight test's on every ray. t is
 * Möller–Trumbore's either way.
 *
 * Branch-free up to the test of the margin: u, v and the unnormalised t are
 * always computed, the determinant's sign folded in by selects, and the
 * range conditions combined with & into one branch. Whether a ray passes a
 * triangle's u or v edge is the kind of branch no predictor can learn;
 * testing u first saved a cross product on a miss but cost a misprediction
 * on about every other test. Same values, so the same bits: primary rays
 * per second +15 % on the Stanford dragon (202,520 triangles), +0-10 % on
 * teapot:60 (docs/kdtree-log.md, "Session 22"). */
ISECT_INLINE int triangle_solve(const triangle_edges *tr, double enorm, const isect_ray *ray,
                                bsp_vec3 org, double ts, const int mode, double tmax, double *t,
                                double *bu_out, double *bv_out, double *det_out)
{
    const bsp_vec3 d = ray->dir, tvec = v3_sub(org, tr->v0), e1 = tr->e1, e2 = tr->e2;
    bsp_vec3 qvec;
    double det, bu, bv;
    triangle_bary(d.x, d.y, d.z, tvec.x, tvec.y, tvec.z, e1.x, e1.y, e1.z, e2.x, e2.y, e2.z, &det,
                  &bu, &bv, &qvec.x, &qvec.y, &qvec.z);
    double bt = v3_dot(e2, qvec);
    /* First against the ray's bound of the margin (isect_ray.tri_bound,
     * M >= m): a value below -M is below -m, all at least M are at least m,
     * so the answer is the margin's; the margin itself is computed only for
     * a ray within M of an edge (dragon res3's traversal: 1.1 % fewer
     * instructions). Decided already: no margin, only det != 0. */
    const double mb = mode != TRIANGLE_DIRECT ? INFINITY : ray->tri_bound;
    int neg;
    const int maybe = triangle_range(&det, &bu, &bv, mb, &neg);
    bt = neg ? -bt : bt;
    if (!maybe)
        return 0;
    if (mode == TRIANGLE_DIRECT && !triangle_all_at_least(bu, bv, det, mb)) {
        const double m = triangle_margin(tvec.x, tvec.y, tvec.z, enorm, ray->edge_scale);
        if (!triangle_all_at_least(bu, bv, det, -m))
            return 0;
        if (!triangle_all_at_least(bu, bv, det, m))
            return TRIANGLE_NEAR_EDGE;
    }
    /* The hit check, before the interval: whether the careful path runs
     * must not depend on tmin/tmax, or a closest-hit loop (whose tmax
     * follows the best hit) would see another t than a loop with another
     * tmax. Cramer's rule makes det tvec + bt dir - bu e1 - bv e2 vanish
     * (org + (bt / det) d = v0 + u e1 + v e2); its residual over det is the
     * distance, per axis, between the ray's point and the point of the
     * triangle at (u, v). Rounding adds about 1e-16 (|tvec| + |t d| + |e1| +
     * |e2|) to that; a ray almost in the plane leaves det as rounding noise
     * and a large residual. (NaN, outside the domain, passes: those queries
     * take no check.) The edges are read from *TR here, not from the
     * copies above: a loop indexing those kept them on the stack, stored
     * and reloaded on every test (dragon res3's traversal: 1.4 % more
     * instructions). */
    const double lim = det * ray->tol;
    for (int k = 0; k < 3; k++) {
        double res = det * tvec.v[k] + bt * ray->dir.v[k] - bu * tr->e1.v[k] - bv * tr->e2.v[k];
        if (fabs(res) > lim)
            return -1;
    }
    double tt = mode == TRIANGLE_SHIFTED ? ts + bt / det : bt / det;
    if (!(tt >= ray->tmin && tt <= tmax))
        return 0;
    *t = tt;
    *bu_out = bu;
    *bv_out = bv;
    *det_out = det;
    return 1;
}

/* The careful path, for a hit of the direct solution that failed the hit
 * check: the ray's origin moved along it to the point nearest v0, so that
 * tvec is about the triangle's size rather than the origin's distance. From
 * far away (10^3 scene scales and more) the direct solution's point errs by
 * 1e-16 |o - v0| / sine (the sine of the angle at v0) and a thin triangle's
 * real hit fails the check; from the near point it passes. A phantom fails
 * here too: its determinant is noise whatever the origin. Inside or outside
 * was decided on the direct solution. Not inlined: taken only after a
 * failed check. */
static __attribute__((noinline, unused)) int triangle_isect_near(const triangle_edges *tr,
                                                                 const isect_ray *ray, double tmax,
                                                                 double *t, double *bu_out,
                                                                 double *bv_out, double *det_out)
{
    double ts = v3_dot(v3_sub(tr->v0, ray->org), ray->dir) / ray->dd;
    bsp_vec3 org = v3_madd(ray->org, ray->dir, ts);
    return triangle_solve(tr, 0.0, ray, org, ts, TRIANGLE_SHIFTED, tmax, t, bu_out, bv_out,
                          det_out) == 1;
}

/* The triangle with the edges' size ENORM (triangle_edge_norm): 1 on a hit,
 * 0 on a miss, and TRIANGLE_NEAR_EDGE when the ray passes within the margin
 * of an edge: then the caller finishes with triangle_isect_near_edge on the
 * triangle's vertices.
 * On a hit also writes the unnormalised barycentrics and the (positive)
 * determinant: u = *bu / *det, v = *bv / *det, computed only for the final
 * hit by triangle_uv. */
ISECT_INLINE int triangle_isect(const triangle_edges *tr, double enorm, const isect_ray *ray,
                                double tmax, double *t, double *bu_out, double *bv_out,
                                double *det_out)
{
    int r = triangle_solve(tr, enorm, ray, ray->org, 0.0, TRIANGLE_DIRECT, tmax, t, bu_out,
                           bv_out, det_out);
    if (__builtin_expect(r < 0, 0))
        return triangle_isect_near(tr, ray, tmax, t, bu_out, bv_out, det_out);
    return r;
}

/* triangle_isect's answer for a ray it found near an edge
 * (TRIANGLE_NEAR_EDGE): inside or outside by triangle_watertight on the
 * triangle's vertices V, then the hit finished on its edges TR. Not
 * inlined: taken only near an edge. */
static __attribute__((noinline, unused)) int
triangle_isect_near_edge(const triangle_edges *tr, const triangle_verts *v, const isect_ray *ray,
                         double tmax, double *t, double *bu_out, double *bv_out, double *det_out)
{
    if (!triangle_watertight(v, ray))
        return 0;
    int r = triangle_solve(tr, 0.0, ray, ray->org, 0.0, TRIANGLE_DECIDED, tmax, t, bu_out,
                           bv_out, det_out);
    if (r < 0)
        return triangle_isect_near(tr, ray, tmax, t, bu_out, bv_out, det_out);
    return r;
}

/* The whole triangle kernel for a triangle whose vertices V are at hand
 * (EDGE_EXP its triangle_edge_exp): triangle_isect on its edges, finished
 * near an edge by triangle_isect_near_edge, as shape_isect finishes it on
 * the scene's vertices. */
static inline int triangle_isect_verts(const triangle_verts *v, int edge_exp,
                                       const isect_ray *ray, double tmax, double *t,
                                       double *bu_out, double *bv_out, double *det_out)
{
    const triangle_edges e = triangle_edges_of(v);
    int hit = triangle_isect(&e, triangle_edge_norm(edge_exp), ray, tmax, t, bu_out, bv_out,
                             det_out);
    if (hit == TRIANGLE_NEAR_EDGE)
        hit = triangle_isect_near_edge(&e, v, ray, tmax, t, bu_out, bv_out, det_out);
    return hit;
}

ISECT_INLINE void triangle_uv(double bu, double bv, double det, double *u, double *v)
{
    *u = bu / det;
    *v = bv / det;
}

/* --- polygon (even-odd crossing test, watertight near edges; polygon.c) -- */

/* The crossing test's answer: bit 0 inside, bit 1 "near": the point lies
 * within the margin of the boundary, and the watertight test decides. */
#define POLYGON_INSIDE 1
#define POLYGON_NEAR 2

/* Even-odd test of (px, py) against the polygon projected on axes (au, av).
 * An edge crosses the line v = py when exactly one endpoint lies above it
 * (v > py); that endpoint has the larger v, so the other one is the lower
 * endpoint the abscissa is computed from — the operands a comparison of the
 * two v values picks, so the same bits. Each vertex is compared with py once.
 * Near (POLYGON_NEAR) when a vertex lies within DELTA of the line or a
 * crossing edge within DELTA of the point (its distance |px - x| dv / len
 * against DELTA, len bounded by |du| + dv): an edge within DELTA of the point
 * either crosses the line or has an end within DELTA of it. DELTA = 0: never
 * near. Not inlined: inlined, this loop's registers made the kd-tree descent
 * it is inlined into spill (spd:tree: +17 instructions per primary ray; out
 * of line: -19); `unused`: a file that includes this header without testing
 * polygons gets no warning. */
static __attribute__((noinline, unused)) int
polygon_contains_2d(const bsp_vec3 *vs, uint32_t count, int au, int av, double px, double py,
                    double delta)
{
    int inside = 0, near = 0;
    const double *prev = vs[count - 1].v;
    int prev_above = prev[av] > py;
    for (uint32_t i = 0; i < count; i++) {
        const double *cur = vs[i].v;
        int cur_above = cur[av] > py;
        near |= fabs(cur[av] - py) < delta;
        if (cur_above != prev_above) {
            const double *lo = cur_above ? prev : cur, *hi = cur_above ? cur : prev;
            double du = hi[au] - lo[au], dv = hi[av] - lo[av];
            double x = lo[au] + (py - lo[av]) * du / dv;
            inside ^= px < x;
            near |= fabs(px - x) * dv < delta * (fabs(du) + dv);
        }
        prev = cur;
        prev_above = cur_above;
    }
    return inside | near << 1;
}

/* The last index j < HI with Y[j] <= V, for the ascending Y[0..HI] with
 * Y[0] <= V (V < Y[HI] when HI is past the end: the slab of V). */
static inline uint32_t polygon_slab_of(const double *y, uint32_t hi, double v)
{
    uint32_t lo = 0; /* y[lo] <= v, and v < y[hi] or hi is the end */
    while (hi - lo > 1) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (y[mid] <= v)
            lo = mid;
        else
            hi = mid;
    }
    return lo;
}

/* The same answer as polygon_contains_2d, bit for bit, from P's slabs
 * (polygon_slabs.c): an edge crosses the line v = py exactly when one
 * endpoint lies above py and the other at or below it, that is when its
 * lower endpoint's v is at most y[j] and its upper one's at least y[j + 1],
 * y[j] <= py < y[j + 1] being py's slab among the vertices' distinct v; the
 * slab lists those edges, and each abscissa is computed from the same
 * operands as there (the lower endpoint and the two differences). The
 * vertices nearest the line are the slab's bounds (outside every slab: the
 * first or the last). Outside every slab (or py NaN) no edge crosses:
 * outside. Not inlined, as above. */
static __attribute__((noinline, unused)) int
polygon_contains_slabs(const polygon_shape *p, const polygon_slab_pool *sp, double px, double py,
                       double delta)
{
    const double *y = sp->y + p->slab_first;
    const uint32_t k = p->nslabs;
    if (!(py >= y[0] && py < y[k - 1]))
        return (fabs(y[0] - py) < delta || fabs(y[k - 1] - py) < delta) << 1;
    const uint32_t lo = polygon_slab_of(y, k - 1, py);
    const uint32_t *off = sp->off + p->slab_first;
    int inside = 0, near = fabs(y[lo] - py) < delta || fabs(y[lo + 1] - py) < delta;
    for (uint32_t i = off[lo]; i < off[lo + 1]; i++) {
        const polygon_edge *e = &sp->edge[sp->entry[i]];
        double x = e->lo_u + (py - e->lo_v) * e->du / e->dv;
        inside ^= px < x;
        near |= fabs(px - x) * e->dv < delta * (fabs(e->du) + e->dv);
    }
    return inside | near << 1;
}

/* The even-odd test on the ray's own shear: whether the ray's line passes
 * inside the polygon of the vertices VS (COUNT) themselves, counting the
 * edges that cross the half-line x > 0, y = 0 of the ray's frame
 * (ray_shear_point). An edge crosses when exactly one end lies above the
 * line (y > 0) and the line meets it at x > 0, whose sign is that of
 * edge_side(lower end, upper end): exact, and the same value in every
 * polygon and triangle sharing the edge. So, around any edge or vertex, the
 * faces' parities add up to the parity of their union's boundary: a line
 * through the union passes inside at least one face. Not inlined: taken
 * only near an edge (polygon_isect). */
static __attribute__((noinline, unused)) int polygon_watertight(const bsp_vec3 *vs, uint32_t count,
                                                                const isect_ray *ray)
{
    const ray_shear sh = ray_shear_of(ray);
    double px, py;
    ray_shear_point(&sh, ray, &vs[count - 1], &px, &py);
    int inside = 0;
    for (uint32_t i = 0; i < count; i++) {
        double cx, cy;
        ray_shear_point(&sh, ray, &vs[i], &cx, &cy);
        if ((cy > 0.0) != (py > 0.0)) {
            int c_up = cy > 0.0;
            double s = c_up ? edge_side(px, py, cx, cy) : edge_side(cx, cy, px, py);
            inside ^= s > 0.0;
        }
        px = cx;
        py = cy;
    }
    return inside;
}

/* The margin of the crossing test at the point of the plane at TT (DENOM =
 * n . d): how far, in the projection, the rounding of the point, of the
 * crossings and of the watertight test's sheared vertices, and the
 * vertices' distance from the plane (polygon_shape.wt_base), can move the
 * boundary, 2^12 times over; the ray's obliquity 1 + |d|_1 / |n . d|
 * magnifies each. 0 for a polygon not planar to rounding. */
static inline double polygon_margin(const polygon_shape *p, const isect_ray *ray, double tt,
                                    double denom)
{
    if (!(p->wt_base >= 0.0))
        return 0.0;
    return (0x1p-41 * (ray->org_norm + fabs(tt) * ray->dir_norm) + p->wt_base) *
           (1.0 + ray->dir_norm / fabs(denom));
}

/* The distance in the projection on (au, av) from (px, py) to the nearest
 * edge of the polygon VS (COUNT). Not inlined: taken only near an edge. */
static __attribute__((noinline, unused)) double
polygon_edge_distance(const bsp_vec3 *vs, uint32_t count, int au, int av, double px, double py)
{
    double best = INFINITY;
    const double *a = vs[count - 1].v;
    for (uint32_t i = 0; i < count; i++) {
        const double *b = vs[i].v;
        double ex = b[au] - a[au], ey = b[av] - a[av], wx = px - a[au], wy = py - a[av];
        double ee = ex * ex + ey * ey, s = ee > 0.0 ? (wx * ex + wy * ey) / ee : 0.0;
        s = s < 0.0 ? 0.0 : s > 1.0 ? 1.0 : s;
        best = fmin(best, hypot(wx - s * ex, wy - s * ey));
        a = b;
    }
    return best;
}

/* Whether the ray's point on P's plane at TT (DENOM = n . d) lies inside P,
 * SLABS and the near-edge cases as polygon_isect describes. Not inlined:
 * it holds the one call to a crossing test the kernel made before, so the
 * loops the kernel is inlined into keep their registers. */
static __attribute__((noinline, unused)) int
polygon_inside(const polygon_shape *p, const bsp_vec3 *verts, const polygon_slab_pool *slabs,
               const isect_ray *ray, double tt, double denom)
{
    int au = p->axis_u, av = p->axis_v;
    double px = ray->org.v[au] + ray->dir.v[au] * tt;
    double py = ray->org.v[av] + ray->dir.v[av] * tt;
    const bsp_vec3 *vs = verts + p->first;
    const double delta = polygon_margin(p, ray, tt, denom);
    int r = slabs && p->nslabs ? polygon_contains_slabs(p, slabs, px, py, delta)
                               : polygon_contains_2d(vs, p->count, au, av, px, py, delta);
    if (__builtin_expect(r & POLYGON_NEAR, 0)) {
        int in = polygon_watertight(vs, p->count, ray);
        if (in && !(r & POLYGON_INSIDE) && delta > ray->tol &&
            !(polygon_edge_distance(vs, p->count, au, av, px, py) <= ray->tol))
            in = 0;
        r = in;
    }
    return r & POLYGON_INSIDE;
}

/* SLABS: the pool of P's slabs, or NULL: walk every edge (the same answer).
 * Near an edge the watertight test decides. A hit must lie within the hit
 * check's distance (ray->tol) of the polygon, as every hit must
 * (kd_tree.h): where the margin exceeds it (a ray nearly in the plane,
 * whose point the plane's equation places poorly) and the point is not
 * inside, the point's distance from the edges is checked. */
ISECT_INLINE int polygon_isect(const polygon_shape *p, const bsp_vec3 *verts,
                               const polygon_slab_pool *slabs, const isect_ray *ray, double tmax,
                               double *t)
{
    const bsp_vec3 n = p->normal, o = ray->org, d = ray->dir;
    double denom;
    double tt = polygon_plane(n.x, n.y, n.z, p->d, o.x, o.y, o.z, d.x, d.y, d.z, &denom);
    if (denom == 0.0 || !(tt >= ray->tmin && tt <= tmax))
        return 0;
    if (!polygon_inside(p, verts, slabs, ray, tt, denom))
        return 0;
    *t = tt;
    return 1;
}

/* --- cone (see cone.c) ------------------------------------------------------ */

/* The hit check for a cone: the ray's point at T (OC = org - base) lies
 * within ray->tol of the lateral surface — the distance along the axis past
 * an end plus the radial distance from the circle at its height (past an
 * end: that end's). A line that misses the cone by a hair can leave a
 * discriminant of rounding noise and a root anywhere along it. */
ISECT_INLINE int cone_near_surface(const cone_shape *c, const isect_ray *ray, bsp_vec3 oc, double t)
{
    if (!(ray->tol < INFINITY))
        return 1;
    bsp_vec3 p = v3_madd(oc, ray->dir, t);
    double h = v3_dot(p, c->axis);
    double hc = h < 0.0 ? 0.0 : h > c->length ? c->length : h;
    double e = ray->tol - fabs(h - hc); /* what is left for the radial distance */
    if (!(e >= 0.0))
        return 0;
    bsp_vec3 perp = v3_madd(p, c->axis, -h);
    return isect_near_radius(v3_dot(perp, perp), c->base_radius + c->slope * hc, e);
}

/* Root T of the cone's quadratic (for the origin OC = org - base, TS along
 * the ray): whether it is a hit in [tmin, TMAX] (the final t, TS + T, in
 * *OUT). */
ISECT_INLINE int cone_root(const cone_shape *c, const isect_ray *ray, double tmax, bsp_vec3 oc,
                           double h0, double hd, double ts, double t, double *out)
{
    double h = h0 + t * hd;
    double tt = ts + t;
    if (!(h >= 0.0 && h <= c->length && c->base_radius + c->slope * h >= 0.0 && tt >= ray->tmin &&
          tt <= tmax && cone_near_surface(c, ray, oc, t)))
        return 0;
    *out = tt;
    return 1;
}

/* An origin farther from the cone's base than this many times its size
 * (length and largest radius; cone_shape.far2) is moved along the ray first
 * (below). */
#define CONE_NEAR_SIZES 8.0

/* The middle of C's axis, the point a far origin is moved toward. */
static inline bsp_vec3 cone_axis_middle(const cone_shape *c)
{
    return v3_madd(c->base, c->axis, 0.5 * c->length);
}

/* From an origin far from the cone (over CONE_NEAR_SIZES sizes from its
 * base) the quadratic is solved from the point of the ray nearest the
 * cone's middle (TS along it): from 10^4 scene scales away its constant
 * term |po|^2 - ro^2 would lose 1e-16 |o|^2 to rounding and a real hit's
 * root err by far more than the hit check allows; from the near point the
 * terms are about the cone's size. Which origin is used depends on the ray
 * and the cone alone, never on tmin/tmax. */
ISECT_INLINE int cone_isect(const cone_shape *c, const isect_ray *ray, double tmax, double *t)
{
    const bsp_vec3 o = ray->org, d = ray->dir, ax = c->axis;
    bsp_vec3 oc = v3_sub(o, c->base);
    double ts = 0.0;
    if (__builtin_expect(cone_origin_far(oc.x, oc.y, oc.z, c->far2), 0)) {
        bsp_vec3 mid = cone_axis_middle(c);
        ts = cone_moved_origin(o.x, o.y, o.z, d.x, d.y, d.z, ray->dd, mid.x, mid.y, mid.z,
                               c->base.x, c->base.y, c->base.z, &oc.x, &oc.y, &oc.z);
    }
    double h0, hd, qa, qb, qc;
    double disc = cone_quadratic(oc.x, oc.y, oc.z, d.x, d.y, d.z, ax.x, ax.y, ax.z,
                                 c->base_radius, c->slope, &h0, &hd, &qa, &qb, &qc);

    double t0, t1;
    if (qa == 0.0) {
        if (qb == 0.0)
            return 0;
        t0 = t1 = -qc / (2.0 * qb);
    } else {
        if (!(disc >= 0.0))
            return 0;
        quadratic_roots(qa, qb, qc, disc, &t0, &t1);
    }
    return cone_root(c, ray, tmax, oc, h0, hd, ts, t0, t) ||
           cone_root(c, ray, tmax, oc, h0, hd, ts, t1, t);
}

#endif /* BSPRAY_GEOM_ISECT_H */
