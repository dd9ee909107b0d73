/*
 * kd_view.c — the modified SAH of Havran, Bittner & Kopal (section 4): the
 * projected-area measures of PER and PAR, the mixed measure, and the builds.
 *
 * Projected area of a box. The rays of a view that cross a box B start in
 * front of the plane through the eye (PER) or on the plane of the window
 * (PAR), so only B+ = B ∩ {depth >= near} counts (depth along the view
 * direction; near = 0 for PAR, a tiny distance for PER so that the central
 * projection stays finite). B+ is a convex polytope whose vertices are B's
 * corners in front of the plane and the points where B's edges cross it; the
 * projection of a convex polytope is the convex hull of its projected
 * vertices. So: project at most 8 + 6 points, take their hull (monotone
 * chain), clip it to the viewport rectangle (Sutherland–Hodgman) and take
 * the area (shoelace). Rays are spread uniformly over the image plane (SPD
 * sampling: a regular grid on it), so this area over the viewport's is the
 * share of the view's rays that cross B.
 *
 * A box that contains the eye (closed box) is crossed by every ray of a PER
 * view: its measure is the whole viewport. A box behind the eye plane or
 * outside the viewport gets 0; the builder then measures it by its surface
 * area instead (kd_sah_build_node in kd_sah_node.c), because the secondary and
 * shadow rays still need a good tree there (docs/modified-sah.md).
 */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "accel/kd_cost.h"
#include "accel/kd_prepass.h"
#include "accel/kd_view.h"
#include "accel/kd_view_faces.h"
#include "bspray/render.h"
#include "geom/vec.h"

/* --- views -------------------------------------------------------------------------------- */

static int finite3(bsp_vec3 v)
{
    return isfinite(v.x) && isfinite(v.y) && isfinite(v.z);
}

bsp_status kd_view_resolve(const bsp_scene *scene, const bsp_build_options *o, int ortho,
                           kd_view *v, bsp_error *err)
{
    const char *rule = bsp_accel_kind_name(o->kind);
    bsp_vec3 eye, dir, up;
    double fov;
    int w, h;
    if (o->view.explicit_view) {
        eye = o->view.eye;
        dir = o->view.dir;
        up = o->view.up;
        fov = o->view.fov_deg;
        w = o->view.width > 0 ? o->view.width : 513;
        h = o->view.height > 0 ? o->view.height : w;
    } else {
        const bsp_camera *cam = bsp_scene_camera(scene);
        if (!cam)
            return error_set(err, BSP_ERR_INVALID, NULL, 0,
                             "%s builds for a view, but the scene has no camera: give one "
                             "(--eye/--at or an NFF 'v' block)",
                             rule);
        eye = cam->from;
        dir = v3_sub(cam->at, cam->from);
        up = cam->up;
        fov = cam->angle_deg;
        w = cam->res_x + 1; /* the SPD protocol: res + 1 rays, the angle spans them */
        h = cam->res_y + 1;
    }
    double dlen = v3_length(dir);
    if (!finite3(eye) || !finite3(dir) || !finite3(up) || !(dlen > 0.0))
        return error_set(err, BSP_ERR_INVALID, NULL, 0,
                         "%s: the view's eye, direction and up must be finite and the "
                         "direction non-zero",
                         rule);
    if (!(fov > 0.0 && fov < 180.0))
        return error_set(err, BSP_ERR_INVALID, NULL, 0,
                         "%s: the view's angle %g is outside (0, 180) degrees", rule, fov);
    memset(v, 0, sizeof *v);
    v->ortho = ortho;
    v->eye = eye;
    v->fwd = v3_scale(dir, 1.0 / dlen);
    bsp_vec3 right = v3_cross(v->fwd, up);
    double rlen = v3_length(right);
    if (!(rlen > 1e-12 * v3_length(up)))
        return error_set(err, BSP_ERR_INVALID, NULL, 0,
                         "%s: the view's up vector is zero or parallel to its direction", rule);
    v->right = v3_scale(right, 1.0 / rlen);
    v->up = v3_cross(v->right, v->fwd);
    /* the window spans the first to the last ray, as the renderer's SPD sampling */
    double half = tan(fov * (BSP_PI / 360.0));
    double aspect = w > 1 && h > 1 ? (double)(h - 1) / (double)(w - 1) : 1.0;
    if (ortho) {
        double width = o->view.ortho_width > 0.0 ? o->view.ortho_width : 2.0 * half * dlen;
        if (!isfinite(width))
            return error_set(err, BSP_ERR_INVALID, NULL, 0,
                             "%s: the orthographic window width is not finite", rule);
        v->hx = 0.5 * width;
    } else {
        v->hx = half;
    }
    v->hy = v->hx * aspect;
    return BSP_OK;
}

/* --- projected area ----------------------------------------------------------------------- */

typedef struct pt2 {
    double x, y;
} pt2;

static double cross2(pt2 o, pt2 a, pt2 b)
{
    return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x);
}

static void sort_pts(pt2 *p, int n)
{
    for (int i = 1; i < n; i++) {
        pt2 x = p[i];
        int j = i;
        for (; j > 0 && (p[j - 1].x > x.x || (p[j - 1].x == x.x && p[j - 1].y > x.y)); j--)
            p[j] = p[j - 1];
        p[j] = x;
    }
}

/* The convex hull of P[0..N) (sorted in place) into H, counter-clockwise;
 * returns its vertex count (H has room for 2N). */
static int convex_hull(pt2 *p, int n, pt2 *h)
{
    sort_pts(p, n);
    int k = 0;
    for (int i = 0; i < n; i++) {
        while (k >= 2 && cross2(h[k - 2], h[k - 1], p[i]) <= 0.0)
            k--;
        h[k++] = p[i];
    }
    for (int i = n - 2, lo = k + 1; i >= 0; i--) {
        while (k >= lo && cross2(h[k - 2], h[k - 1], p[i]) <= 0.0)
            k--;
        h[k++] = p[i];
    }
    return k > 1 ? k - 1 : k;
}

/* Clips the convex polygon P[0..N) to the half-plane s * coord(axis) <= lim
 * into Q; returns Q's vertex count. AXIS and S are constants after inlining
 * (s * x is x or -x, exact). */
static inline __attribute__((always_inline)) int clip_half(const pt2 *p, int n, const int axis,
                                                           const double s, double lim, pt2 *q)
{
    int m = 0;
    for (int i = 0; i < n; i++) {
        pt2 a = p[i], b = i + 1 < n ? p[i + 1] : p[0];
        double da = s * (axis ? a.y : a.x) - lim, db = s * (axis ? b.y : b.x) - lim;
        if (da <= 0.0)
            q[m++] = a;
        if ((da < 0.0 && db > 0.0) || (da > 0.0 && db < 0.0)) {
            double u = da / (da - db);
            q[m++] = (pt2){a.x + u * (b.x - a.x), a.y + u * (b.y - a.y)};
        }
    }
    return m;
}

/* Whether every vertex of P[0..N) is in the half-plane s * coord(axis) <=
 * lim (with the comparison of clip_half): clipping would copy P unchanged. */
static inline __attribute__((always_inline)) int in_half(const pt2 *p, int n, const int axis,
                                                         const double s, double lim)
{
    int all = 1;
    for (int i = 0; i < n; i++)
        all &= s * (axis ? p[i].y : p[i].x) - lim <= 0.0;
    return all;
}

static double polygon_area(const pt2 *p, int n)
{
    double a = 0.0;
    for (int i = 0; i + 1 < n; i++)
        a += p[i].x * p[i + 1].y - p[i + 1].x * p[i].y;
    if (n > 0)
        a += p[n - 1].x * p[0].y - p[0].x * p[n - 1].y;
    return 0.5 * fabs(a);
}

/* The 12 edges of a box by corner index (bit k of a corner: hi on axis k). */
static const unsigned char box_edges[12][2] = {{0, 1}, {2, 3}, {4, 5}, {6, 7}, {0, 2}, {1, 3},
                                               {4, 6}, {5, 7}, {0, 4}, {1, 5}, {2, 6}, {3, 7}};

/* The area of polygon P[0..N) clipped to the viewport of V (P and the
 * scratch Q have room for N + 4 vertices; P may be overwritten). A clip that
 * would leave the polygon as it is is skipped: the same vertices, the same
 * area. */
static double clipped_area(const kd_view *v, pt2 *p, int n, pt2 *q)
{
    for (int h = 0; h < 4; h++) { /* x <= hx, x >= -hx, y <= hy, y >= -hy */
        int axis = h >> 1;
        double sign = (h & 1) ? -1.0 : 1.0, lim = axis ? v->hy : v->hx;
        if (!in_half(p, n, axis, sign, lim)) {
            n = clip_half(p, n, axis, sign, lim, q);
            pt2 *t = p;
            p = q;
            q = t;
        }
    }
    return n >= 3 ? polygon_area(p, n) : 0.0;
}

/* B + E0 + E1 + E2 for the 8 corners (bit k of C: E_k added, else 0.0),
 * summed left to right as written, sharing the partial sums. */
static inline __attribute__((always_inline)) void corner_sums(double base, const double e[3],
                                                              double out[8])
{
    double s0 = base + 0.0, s1 = base + e[0];
    double s00 = s0 + 0.0, s10 = s1 + 0.0, s01 = s0 + e[1], s11 = s1 + e[1];
    out[0] = s00 + 0.0;
    out[1] = s10 + 0.0;
    out[2] = s01 + 0.0;
    out[3] = s11 + 0.0;
    out[4] = s00 + e[2];
    out[5] = s10 + e[2];
    out[6] = s01 + e[2];
    out[7] = s11 + e[2];
}

/* The part in front of the start plane of a box straddling it: the hull of
 * its corners in front and of the points where its edges cross the plane
 * (depth NEAR), projected, clipped to the viewport. */
static double straddling_area(const kd_view *v, const double *cx, const double *cy,
                              const double *cz, double near)
{
    pt2 pts[8 + 12], hull[2 * (8 + 12)], tmp[2 * (8 + 12) + 8];
    int n = 0;
    for (int c = 0; c < 8; c++) {
        if (!(cz[c] >= near))
            continue;
        pts[n++] = v->ortho ? (pt2){cx[c], cy[c]} : (pt2){cx[c] / cz[c], cy[c] / cz[c]};
    }
    for (int e = 0; e < 12; e++) {
        int ia = box_edges[e][0], ib = box_edges[e][1];
        double za = cz[ia] - near, zb = cz[ib] - near;
        if ((za < 0.0) == (zb < 0.0))
            continue;
        double u = za / (za - zb);
        double x = cx[ia] + u * (cx[ib] - cx[ia]), y = cy[ia] + u * (cy[ib] - cy[ia]);
        double z = v->ortho ? 1.0 : near;
        pts[n++] = (pt2){x / z, y / z};
    }
    int h = convex_hull(pts, n, hull);
    if (h < 3)
        return 0.0;
    return clipped_area(v, hull, h, tmp);
}

double kd_view_area(const bsp_box *box, const void *ctx)
{
    const kd_view *v = ctx;
    const double vp_area = 4.0 * v->hx * v->hy;
    const int ortho = v->ortho;
    if (!ortho && kd_view_eye_in(v, box))
        return vp_area; /* seen from inside: every ray crosses it */

    /* corners in the view frame: (across, up, depth); corner c has bit k
     * set when it is on the hi side of axis k */
    double cx[8], cy[8], cz[8];
    {
        bsp_vec3 d0 = v3_sub(box->lo, v->eye);
        double bx = v3_dot(d0, v->right), by = v3_dot(d0, v->up), bz = v3_dot(d0, v->fwd);
        double ex[3], ey[3], ez[3];
        for (int k = 0; k < 3; k++) {
            double w = box->hi.v[k] - box->lo.v[k];
            ex[k] = w * v->right.v[k];
            ey[k] = w * v->up.v[k];
            ez[k] = w * v->fwd.v[k];
        }
        corner_sums(bx, ex, cx);
        corner_sums(by, ey, cy);
        corner_sums(bz, ez, cz);
    }
    /* near: PAR rays start on the window's plane; PER projects from the eye,
     * so the polytope is cut a hair in front of it (relative to the box's
     * size, so that the projected coordinates stay finite) */
    double near = 0.0;
    if (!ortho) {
        /* the largest extent (extents are >= +0, never NaN for a valid box) */
        double wx = box->hi.x - box->lo.x, wy = box->hi.y - box->lo.y, wz = box->hi.z - box->lo.z;
        double wyz = wy > wz ? wy : wz;
        double ext = wx > wyz ? wx : wyz;
        near = 1e-9 * ext;
    }
    int front = 0;
    for (int c = 0; c < 8; c++)
        front += cz[c] >= near;
    if (front == 0)
        return 0.0; /* wholly behind */
    if (front < 8) {
        /* straddling the start plane: the hull of the part in front */
        double a = straddling_area(v, cx, cy, cz, near);
        return a < vp_area ? a : vp_area;
    }

    /* wholly in front: the projections of the faces turned towards the
     * rays tile the silhouette, so the area is their sum (no hull) */
    double px[8], py[8];
    if (ortho) {
        for (int c = 0; c < 8; c++)
            px[c] = cx[c], py[c] = cy[c];
    } else {
        for (int c = 0; c < 8; c++)
            px[c] = cx[c] / cz[c], py[c] = cy[c] / cz[c];
    }
    int inside = 1;
    for (int c = 0; c < 8; c++)
        inside &= (fabs(px[c]) <= v->hx) & (fabs(py[c]) <= v->hy);
    double a = 0.0;
    for (int k = 0; k < 3; k++) {
        /* the faces turned towards the rays (at most one per axis) */
        int side = kd_view_face_seen(v, (unsigned)k, box->lo.v[k], box->hi.v[k]);
        if (side < 0)
            continue;
        const unsigned char *fc = kd_face_corners[k][side];
        if (inside) {
            a += kd_quad_area(px, py, fc);
        } else {
            pt2 quad[4 + 4], tmp[4 + 4];
            for (int i = 0; i < 4; i++)
                quad[i] = (pt2){px[fc[i]], py[fc[i]]};
            a += clipped_area(v, quad, 4, tmp);
        }
    }
    return a < vp_area ? a : vp_area;
}

/* --- the mixed measure ------------------------------------------------------------------------ */

/* sah-mixed's measure (kd_view.h). */
double kd_mixed_area(const bsp_box *box, const void *ctx)
{
    const kd_mixed_measure *m = ctx;
    return kd_mixed_area_of_view(m, box, kd_view_area(box, &m->view));
}

double kd_mixed_area_of_view(const kd_mixed_measure *m, const bsp_box *box, double view_area)
{
    double a = m->w_view * view_area + m->w_surf * kd_surface_area(box);
    if (m->w_count > 0.0)
        a += m->w_count * kd_raycount_measure(m->count, box);
    return m->w_flux > 0.0 ? a + m->w_flux * kd_flux_measure(m->flux, box) : a;
}

/* The counted model's per-thread context: a copy of the shared measure with
 * a cursor of its own (kd_descent). */
typedef struct mixed_thread_ctx {
    kd_mixed_measure m; /* first: the context kd_mixed_area sees */
    kd_raycount_cursor cursor;
} mixed_thread_ctx;

static void *mixed_thread_ctx_new(const void *shared)
{
    const kd_mixed_measure *sm = shared;
    mixed_thread_ctx *c = malloc(sizeof *c);
    if (!c)
        return NULL;
    c->m = *sm;
    kd_raycount_cursor_init(&c->cursor, sm->count->rc);
    c->m.count = &c->cursor;
    return c;
}

static void mixed_thread_ctx_free(void *ctx)
{
    mixed_thread_ctx *c = ctx;
    kd_raycount_cursor_free(&c->cursor);
    free(c);
}

static int mixed_enter(void *ctx, const bsp_box *cell)
{
    return kd_raycount_enter(&((mixed_thread_ctx *)ctx)->cursor, cell);
}

static void mixed_reset(void *ctx)
{
    kd_raycount_reset(&((mixed_thread_ctx *)ctx)->cursor);
}

static const kd_descent mixed_counted_descent = {mixed_thread_ctx_new, mixed_thread_ctx_free,
                                                 mixed_enter, mixed_reset};

/* --- rounding of the measures ------------------------------------------------------------ */

/*
 * How far kd_view_area of a box inside CELL may be from the exact projected
 * area, for the pruned sweep (kd_sweep_measure.c), which relies on the exact
 * measures being monotone under inclusion and covering (al + ar >= A).
 *
 * The corners in the view frame are sums of terms up to R (the farthest
 * corner from the eye), so they carry absolute errors of a few eps R. PAR
 * projects them as they are: coordinates off by ~eps R, clipped to a window
 * of half sizes hx, hy and summed over at most 3 faces of perimeter
 * <= 4 (hx + hy) in the window, so the area is off by ~eps (hx + hy)
 * (R + hx + hy) times a small constant. PER divides by the depth, at least
 * D (the nearest corner of the cell, or the cut `near` of a box straddling
 * the eye plane, >= 1e-9 of the cell's middle extent, which every box of a
 * sweep exceeds): the projected coordinates then carry relative errors of
 * ~eps R / D, and within the viewport (clipping keeps what is summed inside
 * it) the area is off by ~eps (1 + R / D) (hx + hy)^2 times a constant.
 * NOISE_K covers the constants many times over (the worst case seen on the
 * SPD builds and on random boxes is below 1 % of this bound).
 *
 * Exact monotonicity itself fails next to the eye: a box cut at its own
 * `near` (1e-9 of its size) keeps points at depths up to a larger box's
 * `near`, which the larger box cuts off, and these points can project into
 * the viewport only if they lie within ~1e-9 size * max(hx, hy) of the eye
 * aside. So the children (the inner boxes of the sweep's comparisons; the
 * covering holds exactly, as children cut nearer) are safe when they are
 * farther than RHO = 1e-7 size (1 + 1.5 max(hx, hy)) from the eye (100 times
 * that reach), or contain it (the whole viewport, the most). For the split
 * axis that leaves: the children at positions within RHO of the eye, when
 * the eye is inside the cell (ZONE: the sweep evaluates them all); no bound
 * (INFINITY: every candidate evaluated) when the eye is within RHO of the
 * cell but outside it on another axis, or just below or above it on the
 * split axis.
 */
#define NOISE_K 256.0

static double view_noise(const kd_view *v, const bsp_box *cell, unsigned axis, double zone[2])
{
    double e0 = cell->hi.x - cell->lo.x, e1 = cell->hi.y - cell->lo.y,
           e2 = cell->hi.z - cell->lo.z;
    double e01 = e0 > e1 ? e0 : e1, f01 = e0 < e1 ? e0 : e1;
    double emax = e01 > e2 ? e01 : e2, emin = f01 < e2 ? f01 : e2;
    double emid = e0 + e1 + e2 - emax - emin;
    /* the farthest corner and the nearest depth, axis by axis */
    double r2 = 0.0, dmin = 0.0;
    for (int k = 0; k < 3; k++) {
        double dl = cell->lo.v[k] - v->eye.v[k], dh = cell->hi.v[k] - v->eye.v[k];
        double ml = dl * dl, mh = dh * dh, fl = dl * v->fwd.v[k], fh = dh * v->fwd.v[k];
        r2 += ml > mh ? ml : mh;
        dmin += fl < fh ? fl : fh;
    }
    double R = sqrt(r2), s = v->hx + v->hy;
    if (!(isfinite(R) && isfinite(s) && isfinite(emax)))
        return INFINITY;
    if (v->ortho)
        return NOISE_K * DBL_EPSILON * s * (R + s);
    /* the children next to the eye */
    double rho = 1e-7 * emax * (1.0 + 1.5 * (v->hx > v->hy ? v->hx : v->hy));
    double dj2 = 0.0; /* the eye's squared distance to the cell on the other axes */
    for (unsigned k = 0; k < 3; k++) {
        if (k == axis)
            continue;
        double x = v->eye.v[k], lo = cell->lo.v[k], hi = cell->hi.v[k];
        double d = x < lo ? lo - x : x > hi ? x - hi : 0.0;
        dj2 += d * d;
    }
    if (dj2 < rho * rho) {
        double x = v->eye.v[axis], lo = cell->lo.v[axis], hi = cell->hi.v[axis];
        if (dj2 > 0.0 || (x < lo && lo - x < rho) || (x > hi && x - hi < rho))
            return INFINITY;
        if (x >= lo && x <= hi) {
            zone[0] = x - rho;
            zone[1] = x + rho;
        }
    }
    double D = dmin > 1e-9 * emid ? dmin : 1e-9 * emid;
    if (!(D > 0.0))
        return INFINITY;
    return NOISE_K * DBL_EPSILON * s * s * (1.0 + R / D);
}

double kd_view_measure_noise(kd_area_fn measure, const void *ctx, const bsp_box *cell,
                             unsigned axis, double zone[2])
{
    zone[0] = INFINITY;
    zone[1] = -INFINITY;
    if (measure == kd_view_area)
        return view_noise(ctx, cell, axis, zone);
    if (measure == kd_mixed_area) {
        const kd_mixed_measure *m = ctx;
        if (m->w_flux > 0.0)
            return INFINITY; /* the sampled term is not monotone (kd_flux.h) */
        double dv = view_noise(&m->view, cell, axis, zone);
        double noise = m->w_view * dv + m->w_surf * NOISE_K * DBL_EPSILON * kd_surface_area(cell);
        /* the counted term: integer counts, exactly monotone and covering
         * (kd_raycount.h), scaled by one rounded product: CTX is the build
         * thread's context, whose cursor has entered CELL */
        if (m->w_count > 0.0)
            noise += m->w_count * NOISE_K * DBL_EPSILON * kd_raycount_measure(m->count, cell);
        return noise;
    }
    return INFINITY;
}

/* Side of the sah-mixed pre-pass image, in rays. */
#define MIXED_PREPASS_RES 65
/* The sampled model: voxels of its density grid, and the weight b of the
 * uniform lines under it (docs/modified-sah.md). */
#define MIXED_FLUX_CELLS 16384
#define MIXED_FLUX_FLOOR 0.1

bsp_status kd_build_view(kd_tree *t, const bsp_scene *scene, const bsp_build_options *o,
                         bsp_error *err)
{
    int ortho = o->kind == BSP_ACCEL_SAH_PAR;
    kd_view v;
    bsp_status st = kd_view_resolve(scene, o, ortho, &v, err);
    if (st != BSP_OK)
        return st;
    if (o->kind != BSP_ACCEL_SAH_MIXED)
        return kd_build_sah_measure(t, scene, o, kd_view_area, &v, NULL, err);

    int counted = o->mixed_model == BSP_MIXED_COUNTED;
    int sampled = o->mixed_model == BSP_MIXED_SAMPLED || counted; /* both sample the rays */
    if (!sampled && o->mixed_model != BSP_MIXED_SURFACE)
        return error_set(err, BSP_ERR_INVALID, NULL, 0, "sah-mixed: unknown model %d",
                         (int)o->mixed_model);
    double share = o->mixed_primary_share;
    if (share != 0.0 && !(share > 0.0 && share <= 1.0))
        return error_set(err, BSP_ERR_INVALID, NULL, 0,
                         "sah-mixed: the share of primary rays %g is outside (0, 1]", share);
    double root_sa = kd_surface_area(&t->box);
    if (!(root_sa > 0.0 && isfinite(root_sa)))
        sampled = 0; /* an empty (or point-like) scene box: nothing to sample */
    kd_flux_segment *seg = NULL;
    size_t nseg = 0;
    if (share == 0.0 || sampled) {
        bsp_camera cam = kd_prepass_camera(scene, o, MIXED_PREPASS_RES);
        double measured;
        st = kd_mixed_prepass(scene, &cam, 0, o->threads, &measured, sampled ? &seg : NULL, &nseg,
                              err);
        if (st != BSP_OK)
            return st;
        if (share == 0.0)
            share = measured;
    }
    kd_mixed_measure m;
    memset(&m, 0, sizeof m);
    m.view = v;
    m.w_view = share / (4.0 * v.hx * v.hy);
    double floor_share = 1.0;
    kd_flux flux;
    memset(&flux, 0, sizeof flux);
    kd_raycount rc;
    memset(&rc, 0, sizeof rc);
    kd_raycount_cursor root_only; /* the shared context's cursor: the root cell only */
    kd_raycount_cursor_init(&root_only, &rc);
    if (counted) {
        st = kd_raycount_init(&rc, &t->box, seg, nseg, err);
        free(seg);
        if (st != BSP_OK)
            return st;
        if (rc.nseg > 0) {
            floor_share = MIXED_FLUX_FLOOR;
            m.w_count = (1.0 - share) * (1.0 - floor_share) / (double)rc.nseg;
            m.count = &root_only;
        }
    } else if (sampled) {
        st = kd_flux_build(&flux, &t->box, seg, nseg, MIXED_FLUX_CELLS, err);
        free(seg);
        if (st != BSP_OK)
            return st;
        if (flux.total > 0.0 && isfinite(flux.total)) {
            floor_share = MIXED_FLUX_FLOOR;
            m.w_flux = (1.0 - share) * (1.0 - floor_share) / flux.total;
            m.flux = &flux;
        }
    }
    m.w_surf = root_sa > 0.0 ? (1.0 - share) * floor_share / root_sa : 0.0;
    st = kd_build_sah_measure(t, scene, o, kd_mixed_area, &m,
                              m.w_count > 0.0 ? &mixed_counted_descent : NULL, err);
    kd_flux_free(&flux);
    kd_raycount_free(&rc);
    return st;
}
