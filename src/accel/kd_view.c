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

double kd_view_area(const bsp_box *box, const void *ctx)
{
    const kd_view *v = ctx;
    const double vp_area = 4.0 * v->hx * v->hy;
    if (!v->ortho && v->eye.x >= box->lo.x && v->eye.x <= box->hi.x && v->eye.y >= box->lo.y &&
        v->eye.y <= box->hi.y && v->eye.z >= box->lo.z && v->eye.z <= box->hi.z)
        return vp_area; /* seen from inside: every ray crosses it */

    /* corners in the view frame: (across, up, depth) */
    double cx[8], cy[8], cz[8];
    for (int c = 0; c < 8; c++) {
        bsp_vec3 p = {{c & 1 ? box->hi.x : box->lo.x, c & 2 ? box->hi.y : box->lo.y,
                       c & 4 ? box->hi.z : box->lo.z}};
        bsp_vec3 d = v3_sub(p, v->eye);
        cx[c] = v3_dot(d, v->right);
        cy[c] = v3_dot(d, v->up);
        cz[c] = v3_dot(d, v->fwd);
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
    int n = 0;
    for (int c = 0; c < 8; c++) {
        if (!(cz[c] >= near))
            continue;
        pts[n++] = v->ortho ? (pt2){cx[c], cy[c]} : (pt2){cx[c] / cz[c], cy[c] / cz[c]};
    }
    if (n == 0)
        return 0.0; /* wholly behind */
    if (n < 8) {
        for (int e = 0; e < 12; e++) {
            int a = box_edges[e][0], b = box_edges[e][1];
            double za = cz[a] - near, zb = cz[b] - near;
            if ((za < 0.0) == (zb < 0.0))
                continue;
            double u = za / (za - zb);
            double x = cx[a] + u * (cx[b] - cx[a]), y = cy[a] + u * (cy[b] - cy[a]);
            double z = v->ortho ? 1.0 : near;
            pts[n++] = (pt2){x / z, y / z};
        }
    }
    int h = convex_hull(pts, n, hull);
    if (h < 3)
        return 0.0;
    /* clip to [-hx, hx] x [-hy, hy] */
    h = clip_half(hull, h, 0, 1.0, v->hx, tmp);
    h = clip_half(tmp, h, 0, -1.0, v->hx, hull);
    h = clip_half(hull, h, 1, 1.0, v->hy, tmp);
    h = clip_half(tmp, h, 1, -1.0, v->hy, hull);
    if (h < 3)
        return 0.0;
    double a = polygon_area(hull, h);
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
