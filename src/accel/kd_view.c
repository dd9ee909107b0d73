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
 * area instead (build_node in kd_split_sah.c), because the secondary and
 * shadow rays still need a good tree there (docs/modified-sah.md).
 */
#include <math.h>
#include <string.h>

#include "accel/kd_cost.h"
#include "accel/kd_view.h"
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
 * into Q; returns Q's vertex count. */
static int clip_half(const pt2 *p, int n, int axis, double s, double lim, pt2 *q)
{
    int m = 0;
    for (int i = 0; i < n; i++) {
        pt2 a = p[i], b = p[(i + 1) % n];
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

static double polygon_area(const pt2 *p, int n)
{
    double a = 0.0;
    for (int i = 0; i < n; i++) {
        const pt2 *u = &p[i], *w = &p[(i + 1) % n];
        a += u->x * w->y - w->x * u->y;
    }
    return 0.5 * fabs(a);
}

/* The 12 edges of a box by corner index (bit k of a corner: hi on axis k). */
static const unsigned char box_edges[12][2] = {{0, 1}, {2, 3}, {4, 5}, {6, 7}, {0, 2}, {1, 3},
                                               {4, 6}, {5, 7}, {0, 4}, {1, 5}, {2, 6}, {3, 7}};

/* The area of polygon P[0..N) clipped to the viewport of V (P and the
 * scratch Q have room for N + 4 vertices; P is overwritten). */
static double clipped_area(const kd_view *v, pt2 *p, int n, pt2 *q)
{
    n = clip_half(p, n, 0, 1.0, v->hx, q);
    n = clip_half(q, n, 0, -1.0, v->hx, p);
    n = clip_half(p, n, 1, 1.0, v->hy, q);
    n = clip_half(q, n, 1, -1.0, v->hy, p);
    return n >= 3 ? polygon_area(p, n) : 0.0;
}

/* Corner indices of the face of axis K on side S (0 lo, 1 hi), in cyclic order. */
static void face_corners(int k, int side, int c[4])
{
    int j1 = (k + 1) % 3, j2 = (k + 2) % 3, base = side << k;
    c[0] = base;
    c[1] = base | 1 << j1;
    c[2] = base | 1 << j1 | 1 << j2;
    c[3] = base | 1 << j2;
}

double kd_view_area(const bsp_box *box, const void *ctx)
{
    const kd_view *v = ctx;
    const double vp_area = 4.0 * v->hx * v->hy;
    if (!v->ortho && v->eye.x >= box->lo.x && v->eye.x <= box->hi.x && v->eye.y >= box->lo.y &&
        v->eye.y <= box->hi.y && v->eye.z >= box->lo.z && v->eye.z <= box->hi.z)
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
        for (int c = 0; c < 8; c++) {
            cx[c] = bx + (c & 1 ? ex[0] : 0.0) + (c & 2 ? ex[1] : 0.0) + (c & 4 ? ex[2] : 0.0);
            cy[c] = by + (c & 1 ? ey[0] : 0.0) + (c & 2 ? ey[1] : 0.0) + (c & 4 ? ey[2] : 0.0);
            cz[c] = bz + (c & 1 ? ez[0] : 0.0) + (c & 2 ? ez[1] : 0.0) + (c & 4 ? ez[2] : 0.0);
        }
    }
    /* near: PAR rays start on the window's plane; PER projects from the eye,
     * so the polytope is cut a hair in front of it (relative to the box's
     * size, so that the projected coordinates stay finite) */
    double near = 0.0;
    if (!v->ortho) {
        double ext = fmax(box->hi.x - box->lo.x, fmax(box->hi.y - box->lo.y, box->hi.z - box->lo.z));
        near = 1e-9 * ext;
    }
    pt2 pts[8 + 12], hull[2 * (8 + 12)], tmp[2 * (8 + 12) + 8];
    int front = 0;
    for (int c = 0; c < 8; c++)
        front += cz[c] >= near;
    if (front == 0)
        return 0.0; /* wholly behind */

    if (front == 8) {
        /* wholly in front: the projections of the faces turned towards the
         * rays tile the silhouette, so the area is their sum (no hull) */
        pt2 proj[8];
        int inside = 1;
        for (int c = 0; c < 8; c++) {
            proj[c] = v->ortho ? (pt2){cx[c], cy[c]} : (pt2){cx[c] / cz[c], cy[c] / cz[c]};
            inside &= fabs(proj[c].x) <= v->hx && fabs(proj[c].y) <= v->hy;
        }
        double a = 0.0;
        for (int k = 0; k < 3; k++) {
            for (int side = 0; side < 2; side++) {
                /* PER: the face is seen when the eye is outside its plane;
                 * PAR: when the rays run against its outward normal */
                int seen = v->ortho ? (side ? v->fwd.v[k] < 0.0 : v->fwd.v[k] > 0.0)
                                    : (side ? v->eye.v[k] > box->hi.v[k]
                                            : v->eye.v[k] < box->lo.v[k]);
                if (!seen)
                    continue;
                int fc[4];
                face_corners(k, side, fc);
                pt2 quad[4 + 4];
                for (int i = 0; i < 4; i++)
                    quad[i] = proj[fc[i]];
                a += inside ? polygon_area(quad, 4) : clipped_area(v, quad, 4, tmp);
            }
        }
        return a < vp_area ? a : vp_area;
    }

    /* straddling the start plane: the hull of the part in front */
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
    double a = clipped_area(v, hull, h, tmp);
    return a < vp_area ? a : vp_area;
}

/* --- the mixed measure ------------------------------------------------------------------------ */

/* sah-mixed: the expected share of all the render's rays that cross a box,
 * w * A_view(B) / A_viewport + (1 - w) * SA(B) / SA(root), w the share of
 * primary rays: primary rays are counted by the projected area, every other
 * ray (shadow, reflected, refracted) as a uniformly distributed line. */
typedef struct mixed_measure {
    kd_view view;
    double w_view; /* w / A_viewport */
    double w_surf; /* (1 - w) / SA(root) */
} mixed_measure;

static double mixed_area(const bsp_box *box, const void *ctx)
{
    const mixed_measure *m = ctx;
    return m->w_view * kd_view_area(box, &m->view) + m->w_surf * kd_surface_area(box);
}

/* The camera of a view, for the renderer's pre-pass. */
static bsp_camera view_camera(const bsp_scene *scene, const bsp_build_options *o, int res)
{
    bsp_camera cam;
    if (!o->view.explicit_view) {
        cam = *bsp_scene_camera(scene);
    } else {
        memset(&cam, 0, sizeof cam);
        cam.from = o->view.eye;
        cam.at = v3_add(o->view.eye, o->view.dir);
        cam.up = o->view.up;
        cam.angle_deg = o->view.fov_deg;
    }
    cam.res_x = cam.res_y = res - 1; /* SPD protocol: res rays across */
    return cam;
}

/* Side of the sah-mixed pre-pass image, in rays. */
#define MIXED_PREPASS_RES 65

bsp_status kd_build_view(kd_tree *t, const bsp_scene *scene, const bsp_build_options *o,
                         bsp_error *err)
{
    int ortho = o->kind == BSP_ACCEL_SAH_PAR;
    kd_view v;
    bsp_status st = kd_view_resolve(scene, o, ortho, &v, err);
    if (st != BSP_OK)
        return st;
    if (o->kind != BSP_ACCEL_SAH_MIXED)
        return kd_build_sah_measure(t, scene, o, kd_view_area, &v, err);

    double share = o->mixed_primary_share;
    if (share == 0.0) {
        bsp_camera cam = view_camera(scene, o, MIXED_PREPASS_RES);
        st = bsp_measure_primary_share(scene, &cam, 0, &share, err);
        if (st != BSP_OK)
            return st;
    }
    if (!(share > 0.0 && share <= 1.0))
        return error_set(err, BSP_ERR_INVALID, NULL, 0,
                         "sah-mixed: the share of primary rays %g is outside (0, 1]", share);
    mixed_measure m;
    m.view = v;
    m.w_view = share / (4.0 * v.hx * v.hy);
    double root_sa = kd_surface_area(&t->box);
    m.w_surf = root_sa > 0.0 ? (1.0 - share) / root_sa : 0.0;
    return kd_build_sah_measure(t, scene, o, mixed_area, &m, err);
}
