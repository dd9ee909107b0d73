/*
 * kd_clip.c — split-clipped bounds of a primitive against a box (contract in
 * kd_clip.h): Sutherland–Hodgman for triangles and polygons, the ball ∩ box
 * for spheres, the axis range and cross-section circles for cones.
 *
 * Rounding: a clipped vertex gets the plane's coordinate exactly and its
 * other coordinates by interpolation, each within a few ulps of the true
 * point; the final padding (PAD, about 1e-7 of the scene scale) swallows
 * that, and the result is clamped to the exact unclipped bounds and to the
 * clipping box, which both contain the true part. A concave polygon may leave
 * zero-width "bridges" along a clipping plane; their vertices lie inside the
 * bounds of the part already clipped, so the result can only be larger than
 * the true bounds, never smaller.
 */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "accel/kd_clip.h"
#include "geom/vec.h"
#include "util/grow.h"

/* NaN-free minimum and maximum (no libm call) */
static inline double dmin(double a, double b)
{
    return a < b ? a : b;
}
static inline double dmax(double a, double b)
{
    return a > b ? a : b;
}

void kd_clip_scratch_free(kd_clip_scratch *scr)
{
    if (!scr)
        return;
    for (int i = 0; i < 2; i++) {
        free(scr->buf[i]);
        scr->buf[i] = NULL;
        scr->cap[i] = 0;
    }
}

/* Clips the closed polygon IN[0..N) to x[k] >= c (ABOVE) or x[k] <= c;
 * writes at most 2N vertices to OUT and returns their count. Coordinates are
 * kept in locals and written whole (writing one component of a vertex just
 * copied through memory stalls the next read of it). Inlined with K and
 * ABOVE constant (clip_plane): the plane's coordinate is then a fixed
 * register, not a selection per vertex. */
static inline __attribute__((always_inline)) size_t
clip_plane_k(const bsp_vec3 *in, size_t n, bsp_vec3 *out, const int k, double c, const int above)
{
    size_t m = 0;
    const double sgn = above ? 1.0 : -1.0; /* c - x = -(x - c) exactly */
    double ax = in[n - 1].x, ay = in[n - 1].y, az = in[n - 1].z;
    double da = sgn * (in[n - 1].v[k] - c);
    for (size_t i = 0; i < n; i++) {
        double bx = in[i].x, by = in[i].y, bz = in[i].z;
        double db = sgn * (in[i].v[k] - c);
        if ((da > 0.0 && db < 0.0) || (da < 0.0 && db > 0.0)) {
            double t = da / (da - db); /* in [0, 1] up to rounding */
            double px = ax + (bx - ax) * t, py = ay + (by - ay) * t, pz = az + (bz - az) * t;
            px = k == 0 ? c : px;
            py = k == 1 ? c : py;
            pz = k == 2 ? c : pz;
            out[m++] = bsp_v3(px, py, pz);
        }
        if (db >= 0.0)
            out[m++] = bsp_v3(bx, by, bz);
        ax = bx;
        ay = by;
        az = bz;
        da = db;
    }
    return m;
}

static size_t clip_plane(const bsp_vec3 *in, size_t n, bsp_vec3 *out, int k, double c, int above)
{
    switch (k * 2 + !!above) {
    case 0: return clip_plane_k(in, n, out, 0, c, 0);
    case 1: return clip_plane_k(in, n, out, 0, c, 1);
    case 2: return clip_plane_k(in, n, out, 1, c, 0);
    case 3: return clip_plane_k(in, n, out, 1, c, 1);
    case 4: return clip_plane_k(in, n, out, 2, c, 0);
    default: return clip_plane_k(in, n, out, 2, c, 1);
    }
}

/* Adds the point (X, Y, Z) to the bounds LO, HI, as box_add_point does
 * (the same comparisons, so the same bits, zeros' signs included). */
static inline __attribute__((always_inline)) void add_point(double lo[3], double hi[3], double x,
                                                            double y, double z)
{
    lo[0] = lo[0] < x ? lo[0] : x;
    lo[1] = lo[1] < y ? lo[1] : y;
    lo[2] = lo[2] < z ? lo[2] : z;
    hi[0] = hi[0] > x ? hi[0] : x;
    hi[1] = hi[1] > y ? hi[1] : y;
    hi[2] = hi[2] > z ? hi[2] : z;
}

/* The bounds of the points V[0..N) into LO and HI (add_point, in order: the
 * comparisons of box_add_point, so the same bits wherever they are taken). */
static inline __attribute__((always_inline)) void points_bounds(const bsp_vec3 *v, size_t n,
                                                            double lo[3], double hi[3])
{
    lo[0] = lo[1] = lo[2] = INFINITY;
    hi[0] = hi[1] = hi[2] = -INFINITY;
    for (size_t i = 0; i < n; i++)
        add_point(lo, hi, v[i].x, v[i].y, v[i].z);
}

/* The same bounds as a box. */
static bsp_box points_box(const bsp_vec3 *v, size_t n)
{
    double lo[3], hi[3];
    points_bounds(v, n, lo, hi);
    return (bsp_box){bsp_v3(lo[0], lo[1], lo[2]), bsp_v3(hi[0], hi[1], hi[2])};
}

/* One edge A-B of clip_plane_k's loop for one side (DA, DB: the signed
 * distances of A and B, kept side >= 0), as bounds: adds the crossing with
 * the plane x[K] = C and B when kept; returns how many points it added. */
static inline __attribute__((always_inline)) size_t
side_points(double lo[3], double hi[3], double da, double db, double ax, double ay, double az,
            double bx, double by, double bz, const int k, double c)
{
    size_t m = 0;
    if ((da > 0.0 && db < 0.0) || (da < 0.0 && db > 0.0)) {
        double t = da / (da - db);
        double px = ax + (bx - ax) * t, py = ay + (by - ay) * t, pz = az + (bz - az) * t;
        add_point(lo, hi, k == 0 ? c : px, k == 1 ? c : py, k == 2 ? c : pz);
        m++;
    }
    if (db >= 0.0) {
        add_point(lo, hi, bx, by, bz);
        m++;
    }
    return m;
}

/* The bounds of polygon IN[0..N) clipped to x[k] <= CL (side 0) and to
 * x[k] >= CR (side 1), in one pass and without writing a vertex: each side
 * sees the points clip_plane(IN, N, ., K, C, ABOVE) would output, in its
 * order and by the same arithmetic (its sign -1 is a negation, exact), so
 * its bounds are box_add_point's over that output bit for bit. M[c]: the
 * count of those points (0: the side is empty). */
static inline __attribute__((always_inline)) void
split_bounds_k(const bsp_vec3 *in, size_t n, const int k, double cl, double cr, bsp_box out[2],
               size_t m[2])
{
    double lo[2][3], hi[2][3];
    for (int c = 0; c < 2; c++)
        for (int j = 0; j < 3; j++) {
            lo[c][j] = INFINITY;
            hi[c][j] = -INFINITY;
        }
    size_t ml = 0, mr = 0;
    double ax = in[n - 1].x, ay = in[n - 1].y, az = in[n - 1].z;
    double dal = -(in[n - 1].v[k] - cl), dar = in[n - 1].v[k] - cr;
    for (size_t i = 0; i < n; i++) {
        const double bx = in[i].x, by = in[i].y, bz = in[i].z;
        const double dbl = -(in[i].v[k] - cl), dbr = in[i].v[k] - cr;
        ml += side_points(lo[0], hi[0], dal, dbl, ax, ay, az, bx, by, bz, k, cl);
        mr += side_points(lo[1], hi[1], dar, dbr, ax, ay, az, bx, by, bz, k, cr);
        ax = bx;
        ay = by;
        az = bz;
        dal = dbl;
        dar = dbr;
    }
    for (int c = 0; c < 2; c++)
        out[c] = (bsp_box){bsp_v3(lo[c][0], lo[c][1], lo[c][2]),
                           bsp_v3(hi[c][0], hi[c][1], hi[c][2])};
    m[0] = ml;
    m[1] = mr;
}

static void split_bounds(const bsp_vec3 *in, size_t n, unsigned k, double cl, double cr,
                         bsp_box out[2], size_t m[2])
{
    switch (k) {
    case 0: split_bounds_k(in, n, 0, cl, cr, out, m); break;
    case 1: split_bounds_k(in, n, 1, cl, cr, out, m); break;
    default: split_bounds_k(in, n, 2, cl, cr, out, m); break;
    }
}

#define STACK_VERTS 32

/* Clips polygon VS[0..N) (bounds PB) to G, ping-ponging between BUF[0]
 * and BUF[1] (capacities CAP; grown in SCR when too small): *OUT is the part
 * (VS itself when no plane of G cuts PB), *NOUT its vertex count (0: nothing
 * left) and *CB its bounds; -1 when out of memory. The planes of G are taken
 * in the order of the share of the current bounds they cut away, largest
 * first, and skipped once the current polygon lies on their kept side, so a
 * large polygon in a small cell shrinks at the first plane. Each plane at
 * most doubles the vertex count (an output vertex is an input vertex or a
 * crossing edge), so the output buffer is grown to 2N first; it never holds
 * the current polygon, which lives in the other one. */
static int clip_polygon_in(const bsp_vec3 *vs, size_t n, bsp_box pb, const bsp_box *g,
                           bsp_vec3 *buf[2], size_t cap[2], kd_clip_scratch *s,
                           const bsp_vec3 **out, size_t *nout, bsp_box *cb_out)
{
    const bsp_vec3 *cur = vs;
    bsp_box cb = pb; /* bounds of the current polygon */
    int o = 0, done = 0;
    while (n > 0) {
        int plane = -1;
        double most = 0.0;
        for (int pl = 0; pl < 6; pl++) {
            int k = pl >> 1, above = !(pl & 1);
            double c = above ? g->lo.v[k] : g->hi.v[k], ext = cb.hi.v[k] - cb.lo.v[k];
            double cut = above ? c - cb.lo.v[k] : cb.hi.v[k] - c;
            if ((done >> pl) & 1 || !(cut > 0.0))
                continue;
            double share = ext > 0.0 ? cut / ext : 1.0;
            if (plane < 0 || share > most) {
                plane = pl;
                most = share;
            }
        }
        if (plane < 0)
            break; /* on the kept side of every remaining plane */
        done |= 1 << plane;
        int k = plane >> 1, above = !(plane & 1);
        if (2 * n > cap[o]) {
            if (!GROW_ARRAY(s->buf[o], s->cap[o], 2 * n))
                return -1;
            buf[o] = s->buf[o];
            cap[o] = s->cap[o];
        }
        n = clip_plane(cur, n, buf[o], k, above ? g->lo.v[k] : g->hi.v[k], above);
        cur = buf[o];
        o ^= 1;
        cb = points_box(cur, n);
    }
    *out = cur;
    *nout = n;
    *cb_out = cb;
    return 1;
}

/* Bounds of polygon VS[0..N) ∩ G into *B (PB: its unclipped bounds), in
 * buffers on the stack while they suffice. */
static int clip_polygon(const bsp_vec3 *vs, size_t n, bsp_box pb, const bsp_box *g,
                        kd_clip_scratch *scr, bsp_box *b)
{
    bsp_vec3 stk[2][STACK_VERTS];
    bsp_vec3 *buf[2] = {stk[0], stk[1]};
    size_t cap[2] = {STACK_VERTS, STACK_VERTS};
    kd_clip_scratch local = {{NULL, NULL}, {0, 0}};
    const bsp_vec3 *part;
    size_t m;
    bsp_box cb;
    int result = clip_polygon_in(vs, n, pb, g, buf, cap, scr ? scr : &local, &part, &m, &cb);
    if (result == 1) {
        if (m == 0)
            result = 0;
        else
            *b = cb;
    }
    if (!scr)
        kd_clip_scratch_free(&local);
    return result;
}

/* One plane of clip_triangle_into (K, ABOVE constant): clips *CUR[0..*N) to
 * x[K] >= C (ABOVE) or x[K] <= C when PB crosses it, ping-ponging between
 * OUT and BUF; 0 when nothing is left. */
static inline __attribute__((always_inline)) int
triangle_plane(const bsp_vec3 **cur, size_t *n, bsp_vec3 *out, bsp_vec3 *buf, const bsp_box *pb,
               const bsp_box *g, const int k, const int above, int *clipped)
{
    const double c = above ? g->lo.v[k] : g->hi.v[k];
    if (above ? !(pb->lo.v[k] < c) : !(pb->hi.v[k] > c))
        return 1;
    bsp_vec3 *dst = (*cur == out) ? buf : out;
    *n = clip_plane_k(*cur, *n, dst, k, c, above);
    *cur = dst;
    *clipped = 1;
    return *n != 0;
}

/* Vertices a triangle clipped by six planes can have as computed. Exactly a
 * triangle ∩ box has at most 9; rounded, vertices within rounding of a plane
 * can lie on alternating sides, and a plane then turns n vertices into at
 * most 1.5 n (k kept, at most 2 min(k, n - k) crossings): 3, 4, 6, 9, 13,
 * 19, 28. */
#define TRI_CLIP_MAX 28

/* Clips triangle V (bounds PB) to G into OUT[0..*N) (at most TRI_CLIP_MAX):
 * returns 1 when it clipped, 0 with *N = 0 when nothing is left, 0 with
 * *N = 3 when no plane of G crosses PB (V itself is the part). The planes
 * in the order x lo, x hi, y lo, y hi, z lo, z hi, each inlined. */
static int clip_triangle_into(const bsp_vec3 v[3], bsp_box pb, const bsp_box *g,
                              bsp_vec3 out[TRI_CLIP_MAX], size_t *np)
{
    bsp_vec3 buf[TRI_CLIP_MAX];
    const bsp_vec3 *cur = v;
    size_t n = 3;
    int clipped = 0;
    if (!triangle_plane(&cur, &n, out, buf, &pb, g, 0, 1, &clipped) ||
        !triangle_plane(&cur, &n, out, buf, &pb, g, 0, 0, &clipped) ||
        !triangle_plane(&cur, &n, out, buf, &pb, g, 1, 1, &clipped) ||
        !triangle_plane(&cur, &n, out, buf, &pb, g, 1, 0, &clipped) ||
        !triangle_plane(&cur, &n, out, buf, &pb, g, 2, 1, &clipped) ||
        !triangle_plane(&cur, &n, out, buf, &pb, g, 2, 0, &clipped)) {
        *np = 0;
        return 0;
    }
    if (clipped && cur != out)
        for (size_t i = 0; i < n; i++)
            out[i] = cur[i];
    *np = n;
    return clipped;
}

/* Bounds of triangle V ∩ G into *B (PB: its unclipped bounds): the convex
 * case, in fixed buffers. */
static int clip_triangle(const bsp_vec3 v[3], bsp_box pb, const bsp_box *g, bsp_box *b)
{
    bsp_vec3 part[TRI_CLIP_MAX];
    size_t n;
    int clipped = clip_triangle_into(v, pb, g, part, &n);
    if (n == 0)
        return 0;
    const bsp_vec3 *cur = clipped ? part : v;
    *b = points_box(cur, n);
    return 1;
}

/* Clamps the bounds B of a clipped part to the unclipped bounds PB and to G
 * (both contain the true part), pads them by PAD into *OUT; 0 when the
 * clamp leaves nothing. */
static int finish(const double blo[3], const double bhi[3], const bsp_box *pb, const bsp_box *g,
                  double pad, bsp_box *out)
{
    /* in scalars, written once: a box stored a double at a time and then
     * copied whole stalled on store forwarding (session 31) */
    double lo[3], hi[3];
    for (int k = 0; k < 3; k++) {
        lo[k] = dmax(dmax(blo[k], pb->lo.v[k]), g->lo.v[k]);
        hi[k] = dmin(dmin(bhi[k], pb->hi.v[k]), g->hi.v[k]);
        if (lo[k] > hi[k])
            return 0;
    }
    for (int k = 0; k < 3; k++) {
        out->lo.v[k] = lo[k] - pad;
        out->hi.v[k] = hi[k] + pad;
    }
    return 1;
}

/* Relative slack of the round-shape tests below: far above their rounding. */
#define ROUND_SLACK (16.0 * DBL_EPSILON)

/* The distance from C to [LO, HI] (0 inside) and to its farther end. */
static inline void gap_and_far(double c, double lo, double hi, double *gap, double *far)
{
    *gap = c < lo ? lo - c : (c > hi ? c - hi : 0.0);
    *far = dmax(fabs(c - lo), fabs(hi - c));
}

/* How far from the centre, along one axis, a point of a circle or sphere of
 * radius R (R2 = R^2) can lie when it is at least sqrt(D2O) from the centre
 * across the other axes: sqrt(R2 - D2O), never below the truth. */
static inline double reach(double r2, double r, double d2o)
{
    return dmin(sqrt(dmax(r2 - d2o, 0.0) + ROUND_SLACK * (r2 + d2o)), r);
}

/* clip_sphere given the distances GAP and FAR of the centre to G on each
 * axis (gap_and_far). EXT_AXIS (0..2, or -1: none) names an axis whose
 * extent *EXT_CACHE holds, or NAN until computed here: the extent on an
 * axis depends only on the gaps of the other two, so the two children of a
 * split on that axis share it (clip_sphere_split). */
static int sphere_part(const sphere_shape *s, const bsp_box *g, const double gap[3],
                       const double far[3], int ext_axis, double *ext_cache, bsp_box *b)
{
    double r2 = s->radius2, d2min = 0.0, d2max = 0.0;
    for (int k = 0; k < 3; k++) {
        d2min += gap[k] * gap[k];
        d2max += far[k] * far[k];
    }
    if (d2min > r2 * (1.0 + ROUND_SLACK))
        return 0; /* the ball misses G */
    if (d2max < r2 * (1.0 - ROUND_SLACK))
        return 0; /* G lies inside the ball: the surface misses it */
    const double q[3] = {gap[0] * gap[0], gap[1] * gap[1], gap[2] * gap[2]};
    /* squared distance to G across the other two axes, summed in axis order */
    const double d2o_of[3] = {q[1] + q[2], q[0] + q[2], q[0] + q[1]};
    for (int k = 0; k < 3; k++) {
        double c = s->center.v[k];
        double ext;
        if (k == ext_axis) {
            if (isnan(*ext_cache))
                *ext_cache = reach(r2, s->radius, d2o_of[k]);
            ext = *ext_cache;
        } else {
            ext = reach(r2, s->radius, d2o_of[k]);
        }
        b->lo.v[k] = dmax(c - ext, g->lo.v[k]);
        b->hi.v[k] = dmin(c + ext, g->hi.v[k]);
        if (b->lo.v[k] > b->hi.v[k]) {
            b->lo.v[k] = dmax(c - s->radius, g->lo.v[k]);
            b->hi.v[k] = dmin(c + s->radius, g->hi.v[k]);
        }
    }
    return 1;
}

/* Bounds of the sphere's surface ∩ G (through the ball ∩ G, exact per
 * axis); 0 when the ball misses G or G lies inside the sphere. */
static int clip_sphere(const sphere_shape *s, const bsp_box *g, bsp_box *b)
{
    double gap[3], far[3];
    for (int k = 0; k < 3; k++)
        gap_and_far(s->center.v[k], g->lo.v[k], g->hi.v[k], &gap[k], &far[k]);
    return sphere_part(s, g, gap, far, -1, NULL, b);
}

/* The parameters [*H0, *H1] (within [0, length]) of the cone's axis at which
 * the box of its cross-section circle can meet G: on each axis k that box is
 * [lo_k(h), hi_k(h)], both linear in h, and lo_k(h) <= G.hi_k, hi_k(h) >= G.lo_k
 * are linear inequalities a h <= b. Each b gets a tolerance of 1e-12 of the
 * magnitudes involved (far below the padding, far above rounding), so the
 * interval only widens; 0 when it is empty (the cone misses G). */
static int cone_axis_range(const cone_shape *c, const bsp_box *g, const double s[3], double *h0,
                           double *h1)
{
    const double r0 = c->base_radius, sl = c->slope, len = c->length;
    const double rmax = dmax(r0, c->apex_radius);
    double lo = 0.0, hi = len;
    for (int k = 0; k < 3; k++) {
        double bk = c->base.v[k], ak = c->axis.v[k];
        double tol = 1e-12 * (fabs(g->lo.v[k]) + fabs(g->hi.v[k]) + fabs(bk) + rmax + len);
        /* lo_k(h) = bk - r0 s + (ak - sl s) h <= G.hi_k;
         * hi_k(h) = bk + r0 s + (ak + sl s) h >= G.lo_k */
        double alpha[2] = {ak - sl * s[k], -(ak + sl * s[k])};
        double beta[2] = {g->hi.v[k] - bk + r0 * s[k] + tol, bk + r0 * s[k] - g->lo.v[k] + tol};
        for (int i = 0; i < 2; i++) {
            if (alpha[i] > 0.0)
                hi = dmin(hi, beta[i] / alpha[i]);
            else if (alpha[i] < 0.0)
                lo = dmax(lo, beta[i] / alpha[i]);
            else if (beta[i] < 0.0)
                return 0;
        }
    }
    if (!(lo <= hi))
        return 0;
    *h0 = lo;
    *h1 = hi;
    return 1;
}

/* Bounds of the cone's surface ∩ G. The surface between the axis parameters
 * h0 and h1 lies in the convex hull of its two circles there, so the part in
 * G lies in the box of the circles at the ends of cone_axis_range — for a
 * cone not parallel to a coordinate axis far tighter than its bounds ∩ G.
 * A cone along a coordinate axis has circular cross-sections in the other
 * two: their radii between h0 and h1 lie in [rlo, rhi], and, as for the
 * sphere, the circles miss the rectangle of G when it lies outside the disc
 * of radius rhi or inside that of radius rlo; on each cross axis the part
 * reaches at most sqrt(rhi^2 - gap^2) from the axis, gap being G's distance
 * from the axis on the other. */
static int clip_cone(const cone_shape *c, const bsp_box *g, bsp_box *b)
{
    /* a unit circle's half-width on each axis, sqrt(1 - a_k^2) */
    const bsp_box unit = cone_disc_bounds(bsp_v3(0.0, 0.0, 0.0), 1.0, c->axis);
    const double *s = unit.hi.v;
    double h[2];
    if (!cone_axis_range(c, g, s, &h[0], &h[1]))
        return 0;
    double r[2];
    for (int e = 0; e < 2; e++)
        r[e] = dmax(c->base_radius + c->slope * h[e], 0.0);
    *b = box_union(cone_disc_bounds(v3_madd(c->base, c->axis, h[0]), r[0], c->axis),
                   cone_disc_bounds(v3_madd(c->base, c->axis, h[1]), r[1], c->axis));
    int along = -1; /* the coordinate axis the cone's axis is parallel to */
    for (int k = 0; k < 3; k++)
        if (c->axis.v[(k + 1) % 3] == 0.0 && c->axis.v[(k + 2) % 3] == 0.0)
            along = k;
    if (along < 0)
        return 1;
    const double rlo = dmin(r[0], r[1]), rhi = dmax(r[0], r[1]);
    const int j[2] = {(along + 1) % 3, (along + 2) % 3};
    double gap[2], far[2];
    for (int i = 0; i < 2; i++)
        gap_and_far(c->base.v[j[i]], g->lo.v[j[i]], g->hi.v[j[i]], &gap[i], &far[i]);
    double r2 = rhi * rhi;
    if (gap[0] * gap[0] + gap[1] * gap[1] > r2 * (1.0 + ROUND_SLACK))
        return 0; /* outside the largest circle */
    if (far[0] * far[0] + far[1] * far[1] < rlo * rlo * (1.0 - ROUND_SLACK))
        return 0; /* inside the smallest circle */
    for (int i = 0; i < 2; i++) {
        double ext = reach(r2, rhi, gap[1 - i] * gap[1 - i]);
        double cc = c->base.v[j[i]];
        b->lo.v[j[i]] = dmax(b->lo.v[j[i]], cc - ext);
        b->hi.v[j[i]] = dmin(b->hi.v[j[i]], cc + ext);
    }
    return 1;
}

/* Whether A lies inside G (both by pointer: a box passed by value is copied
 * whole, and one just stored a double at a time stalls on store forwarding). */
static int box_inside(const bsp_box *a, const bsp_box *g)
{
    for (int k = 0; k < 3; k++)
        if (!(a->lo.v[k] >= g->lo.v[k] && a->hi.v[k] <= g->hi.v[k]))
            return 0;
    return 1;
}

static int box_meets(const bsp_box *a, const bsp_box *g)
{
    for (int k = 0; k < 3; k++)
        if (a->lo.v[k] > g->hi.v[k] || a->hi.v[k] < g->lo.v[k])
            return 0;
    return 1;
}

int kd_clip_prim(const bsp_scene *scene, uint32_t prim, const bsp_box *box, double pad,
                 kd_clip_scratch *scr, bsp_box *out)
{
    return kd_clip_prim_bounded(scene, prim, bsp_scene_prim_bounds(scene, prim), box, pad, scr,
                                out);
}

int kd_clip_prim_bounded(const bsp_scene *scene, uint32_t prim, bsp_box pb, const bsp_box *box,
                         double pad, kd_clip_scratch *scr, bsp_box *out)
{
    const prim_record *p = &scene->prims[prim];
    bsp_box g = box_grow(*box, pad), b;
    if (box_is_empty(pb) || !box_meets(&pb, &g))
        return 0;
    int r = 1;
    if (box_inside(&pb, &g)) {
        b = pb;
    } else {
        switch ((shape_kind)p->shape) {
        case SHAPE_SPHERE:
            r = clip_sphere(&scene->spheres[p->slot], &g, &b);
            break;
        case SHAPE_TRIANGLE: {
            const triangle_shape *tr = &scene->triangles[p->slot];
            bsp_vec3 vs[3] = {tr->v0, tr->v1, tr->v2};
            r = clip_triangle(vs, pb, &g, &b);
            break;
        }
        case SHAPE_POLYGON: {
            /* its hits: its vertices moved onto its plane (polygon_plane_vertex) */
            const polygon_shape *pg = &scene->polygons[p->slot];
            r = clip_polygon(scene->plane_verts + pg->first, pg->count, pb, &g, scr, &b);
            break;
        }
        case SHAPE_CONE:
            r = clip_cone(&scene->cones[p->slot], &g, &b);
            break;
        default:
            return 0;
        }
        if (r != 1)
            return r;
        return finish(b.lo.v, b.hi.v, &pb, &g, pad, out);
    }
    *out = box_grow(b, pad);
    return 1;
}

/* The bounds of the part of triangle V (bounds PB) in each child of CELL
 * split at S on AXIS: the triangle is clipped once to the parent's G, and
 * that polygon once more by each child's side — the same sets as clipping
 * to each child's G, about half the work. */
static int clip_triangle_split(const bsp_vec3 v[3], bsp_box pb, const bsp_box *g, unsigned axis,
                               double s, double pad, bsp_box out[2])
{
    bsp_vec3 par[TRI_CLIP_MAX];
    bsp_box pc;
    size_t n = 3;
    const bsp_vec3 *cur = v;
    if (clip_triangle_into(v, pb, g, par, &n)) {
        cur = par;
        pc = points_box(cur, n);
    } else if (n == 0) {
        return 0;
    } else {
        pc = pb; /* not clipped: inside G */
    }
    /* the children's boxes differ from G only on AXIS: hi s + pad on the left, lo s - pad on
     * the right */
    const double cl = s + pad, cr = s - pad;
    bsp_box sb[2];
    size_t sm[2];
    int split_done = 0;
    int got = 0;
    for (int c = 0; c < 2; c++) {
        bsp_box gc = *g;
        if (c == 0)
            gc.hi.v[axis] = cl;
        else
            gc.lo.v[axis] = cr;
        if (box_inside(&pb, &gc)) {
            out[c] = box_grow(pb, pad);
            got |= 1 << c;
            continue;
        }
        bsp_box b;
        if (c == 0 ? pc.hi.v[axis] <= cl : pc.lo.v[axis] >= cr) {
            b = pc; /* the clipped part lies on this side */
        } else {
            if (!split_done) {
                split_bounds(cur, n, axis, cl, cr, sb, sm);
                split_done = 1;
            }
            if (sm[c] == 0)
                continue;
            b = sb[c];
        }
        if (finish(b.lo.v, b.hi.v, &pb, &gc, pad, &out[c]) == 1)
            got |= 1 << c;
    }
    return got;
}

/* kd_clip_prim_split for a sphere: both children at once, as two calls of
 * kd_clip_prim_bounded would clip it (the same arithmetic, so the same
 * bits), sharing what does not depend on the side: the distances to the cell
 * on the other two axes and the extent along AXIS. Nested spheres straddle
 * most splits (shells), and their clipping was the largest part of such a
 * build. */
static int clip_sphere_split(const sphere_shape *sp, const bsp_box *pb, const bsp_box *cell,
                             unsigned axis, double s, double pad, bsp_box out[2])
{
    if (box_is_empty(*pb))
        return 0;
    double gap[3], far[3], ext_cache = NAN;
    int shared = 0, got = 0;
    for (int c = 0; c < 2; c++) {
        /* made a double at a time, never copied whole: a box stored by parts
         * and read back at once stalls on store forwarding */
        bsp_box gc;
        for (int k = 0; k < 3; k++) {
            gc.lo.v[k] = (unsigned)k == axis && c == 1 ? s - pad : cell->lo.v[k] - pad;
            gc.hi.v[k] = (unsigned)k == axis && c == 0 ? s + pad : cell->hi.v[k] + pad;
        }
        if (!box_meets(pb, &gc))
            continue;
        if (box_inside(pb, &gc)) {
            out[c] = box_grow(*pb, pad);
            got |= 1 << c;
            continue;
        }
        if (!shared) {
            for (unsigned k = 0; k < 3; k++)
                if (k != axis)
                    gap_and_far(sp->center.v[k], gc.lo.v[k], gc.hi.v[k], &gap[k], &far[k]);
            shared = 1;
        }
        gap_and_far(sp->center.v[axis], gc.lo.v[axis], gc.hi.v[axis], &gap[axis], &far[axis]);
        bsp_box b;
        if (sphere_part(sp, &gc, gap, far, (int)axis, &ext_cache, &b) &&
            finish(b.lo.v, b.hi.v, pb, &gc, pad, &out[c]) == 1)
            got |= 1 << c;
    }
    return got;
}

int kd_clip_prim_split(const bsp_scene *scene, uint32_t prim, bsp_box pb, const bsp_box *cell,
                       unsigned axis, double s, double pad, kd_clip_scratch *scr, bsp_box out[2])
{
    const prim_record *p = &scene->prims[prim];
    if ((shape_kind)p->shape == SHAPE_SPHERE)
        return clip_sphere_split(&scene->spheres[p->slot], &pb, cell, axis, s, pad, out);
    if ((shape_kind)p->shape == SHAPE_TRIANGLE) {
        bsp_box g = box_grow(*cell, pad);
        if (box_is_empty(pb) || !box_meets(&pb, &g))
            return 0;
        const triangle_shape *tr = &scene->triangles[p->slot];
        bsp_vec3 vs[3] = {tr->v0, tr->v1, tr->v2};
        return clip_triangle_split(vs, pb, &g, axis, s, pad, out);
    }
    int got = 0;
    for (int c = 0; c < 2; c++) {
        bsp_box child = *cell;
        if (c == 0)
            child.hi.v[axis] = s;
        else
            child.lo.v[axis] = s;
        int r = kd_clip_prim_bounded(scene, prim, pb, &child, pad, scr, &out[c]);
        if (r < 0)
            return -1;
        got |= r << c;
    }
    return got;
}

/* --- triangles' and polygons' parts along a build path -------------------------------------- */

void kd_clip_path_free(kd_clip_path *path)
{
    free(path->of);
    free(path->v);
    memset(path, 0, sizeof *path);
}

/* Room for MORE vertices above the path's top; 0 when out of memory. */
static int path_reserve(kd_clip_path *path, size_t more)
{
    return GROW_ARRAY(path->v, path->cap, path->top + more);
}

/* The handle of the part whose M vertices lie at the path's top + 2, with
 * its bounds B stored in the two slots before them (0 and nothing kept:
 * more than KD_PART_MAX_VERTS; the child clips the primitive afresh). */
static uint64_t path_keep(kd_clip_path *path, size_t m, const double lo[3], const double hi[3])
{
    if (m > KD_PART_MAX_VERTS)
        return 0;
    path->v[path->top] = bsp_v3(lo[0], lo[1], lo[2]);
    path->v[path->top + 1] = bsp_v3(hi[0], hi[1], hi[2]);
    uint64_t h = ((uint64_t)path->top << KD_PART_COUNT_BITS) | m;
    path->top += m + 2;
    return h;
}

/* The part of triangle or polygon PRIM (bounds PB) in G, clipped afresh as
 * kd_clip_prim_split does: *CUR its vertices (the primitive's own when no
 * plane of G cuts PB; VS holds a triangle's), *N their count, *PC their
 * bounds, *PART its handle when it was clipped and kept on PATH (else 0),
 * with room left on PATH for both sides of a split of it. 0: nothing of it
 * is in G; -1: out of memory. */
static int part_afresh(const bsp_scene *scene, uint32_t prim, bsp_box pb, const bsp_box *g,
                       kd_clip_path *path, kd_clip_scratch *scr, bsp_vec3 vs[3],
                       const bsp_vec3 **cur, size_t *n, bsp_box *pc, uint64_t *part)
{
    const prim_record *p = &scene->prims[prim];
    const bsp_vec3 *got;
    int clipped;
    if ((shape_kind)p->shape == SHAPE_TRIANGLE) {
        const triangle_shape *tr = &scene->triangles[p->slot];
        vs[0] = tr->v0;
        vs[1] = tr->v1;
        vs[2] = tr->v2;
        /* the part and both sides of it: a plane at most doubles a polygon */
        if (!path_reserve(path, 5 * TRI_CLIP_MAX + 6))
            return -1;
        bsp_vec3 *dst = path->v + path->top + 2;
        clipped = clip_triangle_into(vs, pb, g, dst, n);
        if (!clipped && *n == 0)
            return 0;
        got = clipped ? dst : vs;
        *pc = clipped ? points_box(got, *n) : pb;
    } else {
        /* its hits: its vertices moved onto its plane (polygon_plane_vertex) */
        const polygon_shape *pg = &scene->polygons[p->slot];
        const bsp_vec3 *vp = scene->plane_verts + pg->first;
        bsp_vec3 *buf[2] = {scr->buf[0], scr->buf[1]};
        size_t cap[2] = {scr->cap[0], scr->cap[1]};
        if (clip_polygon_in(vp, pg->count, pb, g, buf, cap, scr, &got, n, pc) < 0)
            return -1;
        if (*n == 0)
            return 0;
        clipped = got != vp;
        if (!path_reserve(path, 5 * *n + 6))
            return -1;
        if (clipped)
            memcpy(path->v + path->top + 2, got, *n * sizeof *got);
    }
    *part = 0;
    *cur = got;
    if (clipped) { /* kept for the children */
        *cur = path->v + path->top + 2;
        *part = path_keep(path, *n, pc->lo.v, pc->hi.v);
    }
    return 1;
}

int kd_clip_split_part(const bsp_scene *scene, uint32_t prim, bsp_box pb, const bsp_box *cell,
                       unsigned axis, double s, double pad, kd_clip_path *path,
                       kd_clip_scratch *scr, uint64_t part, bsp_box out[2], uint64_t parts[2])
{
    parts[0] = parts[1] = 0;
    /* G and each child's GC made a double at a time and never copied whole
     * (box_grow, a copy: a box stored by parts and read back at once stalls
     * on store forwarding) */
    bsp_box g;
    for (int k = 0; k < 3; k++) {
        g.lo.v[k] = cell->lo.v[k] - pad;
        g.hi.v[k] = cell->hi.v[k] + pad;
    }
    if (box_is_empty(pb) || !box_meets(&pb, &g))
        return 0;
    size_t n;
    const bsp_vec3 *cur;
    bsp_vec3 vs[3];
    bsp_box pc;
    if (part) {
        n = part & KD_PART_COUNT_MASK;
        /* room for both sides with their bounds: a plane at most doubles a
         * polygon's vertices */
        if (!path_reserve(path, 4 * n + 4))
            return -1;
        const bsp_vec3 *at = path->v + (part >> KD_PART_COUNT_BITS);
        pc = (bsp_box){at[0], at[1]};
        cur = at + 2;
    } else {
        int r = part_afresh(scene, prim, pb, &g, path, scr, vs, &cur, &n, &pc, &part);
        if (r <= 0)
            return r;
    }
    const double cl = s + pad, cr = s - pad;
    int got = 0;
    for (int c = 0; c < 2; c++) {
        bsp_box gc;
        for (int k = 0; k < 3; k++) {
            gc.lo.v[k] = cell->lo.v[k] - pad;
            gc.hi.v[k] = cell->hi.v[k] + pad;
        }
        if (c == 0)
            gc.hi.v[axis] = cl;
        else
            gc.lo.v[axis] = cr;
        if (box_inside(&pb, &gc)) {
            out[c] = box_grow(pb, pad); /* the primitive lies inside the child: no part */
            got |= 1 << c;
            continue;
        }
        double blo[3], bhi[3];
        if (c == 0 ? pc.hi.v[axis] <= cl : pc.lo.v[axis] >= cr) {
            for (int k = 0; k < 3; k++) { /* the part lies on this side: the child keeps it */
                blo[k] = pc.lo.v[k];
                bhi[k] = pc.hi.v[k];
            }
            parts[c] = part;
        } else {
            bsp_vec3 *dst = path->v + path->top + 2;
            size_t m = clip_plane(cur, n, dst, (int)axis, c == 0 ? cl : cr, c == 1);
            if (m == 0)
                continue;
            points_bounds(dst, m, blo, bhi);
            parts[c] = path_keep(path, m, blo, bhi);
        }
        if (finish(blo, bhi, &pb, &gc, pad, &out[c]) == 1)
            got |= 1 << c;
        else
            parts[c] = 0;
    }
    return got;
}

/* Whether the segment A-B meets the closed box G (slab clipping of its
 * parameter range [0, 1]). */
static int segment_meets_box(bsp_vec3 a, bsp_vec3 b, const bsp_box *g)
{
    double t0 = 0.0, t1 = 1.0;
    for (int k = 0; k < 3; k++) {
        double d = b.v[k] - a.v[k];
        if (d == 0.0) {
            if (a.v[k] < g->lo.v[k] || a.v[k] > g->hi.v[k])
                return 0;
            continue;
        }
        double ta = (g->lo.v[k] - a.v[k]) / d, tb = (g->hi.v[k] - a.v[k]) / d;
        t0 = dmax(t0, dmin(ta, tb));
        t1 = dmin(t1, dmax(ta, tb));
        if (t0 > t1)
            return 0;
    }
    return 1;
}

/* The polygon's hits meet G either along its outline (an edge meets G) or,
 * when no edge does, with all of G's cross-section by the plane (a convex
 * set the outline does not cross lies wholly inside or wholly outside):
 * then one point of that cross-section — the mean of the points where G's
 * edges meet the plane — decides, by the even-odd test of the hits. */
int kd_polygon_meets_box(const bsp_scene *scene, uint32_t prim, const bsp_box *g)
{
    const polygon_shape *p = &scene->polygons[scene->prims[prim].slot];
    const bsp_vec3 *v = scene->plane_verts + p->first;
    for (uint32_t i = 0; i < p->count; i++)
        if (segment_meets_box(v[i], v[i + 1 < p->count ? i + 1 : 0], g))
            return 1;
    bsp_vec3 sum = bsp_v3(0.0, 0.0, 0.0);
    int n = 0;
    for (int e = 0; e < 12; e++) { /* the 4 edges of G along each axis k */
        int k = e / 4, j = (k + 1) % 3, l = (k + 2) % 3;
        bsp_vec3 a, b;
        a.v[j] = b.v[j] = e & 1 ? g->hi.v[j] : g->lo.v[j];
        a.v[l] = b.v[l] = e & 2 ? g->hi.v[l] : g->lo.v[l];
        a.v[k] = g->lo.v[k];
        b.v[k] = g->hi.v[k];
        double fa = v3_dot(p->normal, a) - p->d, fb = v3_dot(p->normal, b) - p->d;
        if (fa == 0.0 || fb == 0.0 || (fa < 0.0) != (fb < 0.0)) {
            double t = fa == fb ? 0.0 : fa / (fa - fb);
            sum = v3_add(sum, v3_madd(a, v3_sub(b, a), t));
            n++;
        }
    }
    if (n == 0)
        return 0; /* the plane misses G */
    bsp_vec3 c = v3_scale(sum, 1.0 / n);
    return polygon_contains_2d(v, p->count, p->axis_u, p->axis_v, c.v[p->axis_u], c.v[p->axis_v],
                               0.0);
}
