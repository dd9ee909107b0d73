/*
 * test_kd_view.c — the probability measures of the modified SAH (sah-per,
 * sah-par; src/accel/kd_view.c) against areas computed by hand, the view
 * resolution from a scene camera and from explicit options, and the
 * orthographic camera of the renderer.
 *
 * Conventions of the hand computations: the eye at the origin looks along
 * +z with up +y, so the view frame is right = fwd x up = (-1, 0, 0)... which
 * mirrors x; the areas below are symmetric in x, or stated for the mirrored
 * coordinate where it matters.
 */
#include <math.h>
#include <string.h>

#include "accel/kd_view.h"
#include "geom/vec.h"
#include "bspray/bspray.h"
#include "harness.h"

static bsp_box box(double x0, double y0, double z0, double x1, double y1, double z1)
{
    bsp_box b = {{{x0, y0, z0}}, {{x1, y1, z1}}};
    return b;
}

/* A view from EYE along +z, up +y, with the viewport [-h, h] x [-h, h]. */
static kd_view view_z(int ortho, double h)
{
    kd_view v;
    memset(&v, 0, sizeof v);
    v.ortho = ortho;
    v.fwd = (bsp_vec3){{0, 0, 1}};
    v.up = (bsp_vec3){{0, 1, 0}};
    v.right = (bsp_vec3){{-1, 0, 0}}; /* fwd x up */
    v.hx = v.hy = h;
    return v;
}

TEST(view_per_head_on_box)
{
    /* the near face z = 2 of a unit box projects to [-1/4, 1/4]^2, the far
     * face inside it: area 1/4 */
    kd_view v = view_z(0, 1.0);
    bsp_box b = box(-0.5, -0.5, 2, 0.5, 0.5, 3);
    CHECK_NEAR(kd_view_area(&b, &v), 0.25, 1e-12);
    /* the same box partly outside a narrow viewport [-0.1, 0.1]^2: 0.04 */
    kd_view narrow = view_z(0, 0.1);
    CHECK_NEAR(kd_view_area(&b, &narrow), 0.04, 1e-12);
}

TEST(view_per_box_off_axis)
{
    /* box x in [1, 2] (image u = -x / z after the mirror), y in [-1/2, 1/2],
     * z in [1, 2]: near face u in [-2, -1], |v| <= 1/2; far face u in
     * [-1, -1/2], |v| <= 1/4. Hull: the 1 x 1 square plus a trapezoid of
     * width 1/2 and heights 1 and 1/2: 1.375. In the viewport [-1, 1]^2
     * only the trapezoid remains: 0.375. */
    bsp_box b = box(1, -0.5, 1, 2, 0.5, 2);
    kd_view wide = view_z(0, 10.0);
    CHECK_NEAR(kd_view_area(&b, &wide), 1.375, 1e-12);
    kd_view v = view_z(0, 1.0);
    CHECK_NEAR(kd_view_area(&b, &v), 0.375, 1e-12);
}

TEST(view_per_from_a_corner)
{
    /* seen along the diagonal from far away a unit cube's projection is a
     * regular hexagon of area sqrt(3) / d^2 at distance d (the cube's
     * projected area along (1,1,1)/sqrt(3) is sqrt(3), and at distance d
     * the central projection scales by 1/d up to O(1/d^3)) */
    double d = 1e4;
    kd_view v;
    memset(&v, 0, sizeof v);
    double s = 1.0 / sqrt(3.0);
    v.eye = (bsp_vec3){{0.5 - d * s, 0.5 - d * s, 0.5 - d * s}};
    v.fwd = (bsp_vec3){{s, s, s}};
    bsp_vec3 up = {{0, 0, 1}};
    /* right = fwd x up, then up = right x fwd */
    bsp_vec3 r = {{v.fwd.y * up.z - v.fwd.z * up.y, v.fwd.z * up.x - v.fwd.x * up.z,
                   v.fwd.x * up.y - v.fwd.y * up.x}};
    double rl = sqrt(r.x * r.x + r.y * r.y + r.z * r.z);
    v.right = (bsp_vec3){{r.x / rl, r.y / rl, r.z / rl}};
    v.up = (bsp_vec3){{v.right.y * v.fwd.z - v.right.z * v.fwd.y,
                       v.right.z * v.fwd.x - v.right.x * v.fwd.z,
                       v.right.x * v.fwd.y - v.right.y * v.fwd.x}};
    v.hx = v.hy = 1.0;
    bsp_box b = box(0, 0, 0, 1, 1, 1);
    double a = kd_view_area(&b, &v) * d * d;
    CHECK_NEAR(a, sqrt(3.0), 1e-3);
}

TEST(view_per_eye_inside_and_behind)
{
    kd_view v = view_z(0, 0.5);
    bsp_box around = box(-1, -1, -1, 1, 1, 1);
    CHECK_NEAR(kd_view_area(&around, &v), 1.0, 1e-15); /* the whole viewport 4 hx hy */
    bsp_box on_face = box(0, -1, -1, 1, 1, 1);         /* the eye on its boundary */
    CHECK_NEAR(kd_view_area(&on_face, &v), 1.0, 1e-15);
    bsp_box behind = box(-1, -1, -3, 1, 1, -1);
    CHECK(kd_view_area(&behind, &v) == 0.0);
    bsp_box aside = box(5, 5, 1, 6, 6, 2); /* in front, outside the frustum */
    CHECK(kd_view_area(&aside, &v) == 0.0);
}

TEST(view_per_box_straddling_eye_plane)
{
    /* x in [1/2, 3/2], |y| <= 1/2, z in [-1, 1]: the part in front of the
     * eye reaches image points with u >= 1/2 (mirrored) and |v| <= u; in the
     * viewport [-1, 1]^2 that is the integral of 2u over [1/2, 1] = 3/4 */
    kd_view v = view_z(0, 1.0);
    bsp_box b = box(0.5, -0.5, -1, 1.5, 0.5, 1);
    CHECK_NEAR(kd_view_area(&b, &v), 0.75, 1e-6);
}

TEST(view_par_along_axes_and_diagonal)
{
    /* parallel rays along +z starting on z = 0: a unit box in front is its
     * unit xy face; behind the start plane it is 0; straddling it, the same */
    kd_view v = view_z(1, 10.0);
    bsp_box b = box(0, 0, 1, 1, 1, 2);
    CHECK_NEAR(kd_view_area(&b, &v), 1.0, 1e-12);
    bsp_box behind = box(0, 0, -3, 1, 1, -2);
    CHECK(kd_view_area(&behind, &v) == 0.0);
    bsp_box straddle = box(0, 0, -1, 2, 1, 1);
    CHECK_NEAR(kd_view_area(&straddle, &v), 2.0, 1e-12);
    /* a window [-1/2, 1/2]^2 keeps a quarter of the box [0, 1]^2 */
    kd_view small = view_z(1, 0.5);
    CHECK_NEAR(kd_view_area(&b, &small), 0.25, 1e-12);
    /* along the x axis: the box's yz face, 2 x 3 */
    kd_view vx = v;
    vx.fwd = (bsp_vec3){{1, 0, 0}};
    vx.up = (bsp_vec3){{0, 1, 0}};
    vx.right = (bsp_vec3){{0, 0, 1}};
    vx.eye = (bsp_vec3){{-5, 0, 0}};
    bsp_box c = box(0, -1, -1.5, 7, 1, 1.5);
    CHECK_NEAR(kd_view_area(&c, &vx), 6.0, 1e-12);
    /* along the diagonal (1,1,1)/sqrt(3): a box's projected area is
     * |dx| A_yz + |dy| A_xz + |dz| A_xy = (2 + 6 + 3) / sqrt(3) for 1 x 2 x 3 */
    kd_view vd;
    memset(&vd, 0, sizeof vd);
    vd.ortho = 1;
    double s = 1.0 / sqrt(3.0);
    vd.fwd = (bsp_vec3){{s, s, s}};
    vd.right = (bsp_vec3){{1.0 / sqrt(2.0), -1.0 / sqrt(2.0), 0}};
    vd.up = (bsp_vec3){{vd.right.y * vd.fwd.z - vd.right.z * vd.fwd.y,
                        vd.right.z * vd.fwd.x - vd.right.x * vd.fwd.z,
                        vd.right.x * vd.fwd.y - vd.right.y * vd.fwd.x}};
    vd.eye = (bsp_vec3){{-10, -10, -10}};
    vd.hx = vd.hy = 100.0;
    bsp_box d = box(0, 0, 0, 1, 2, 3);
    CHECK_NEAR(kd_view_area(&d, &vd), (2.0 * 3 + 1.0 * 3 + 1.0 * 2) * s, 1e-12);
}

/* An SPD-like scene: one sphere and a camera from (0, 0, -5) at the origin,
 * up +y, 90 degrees, 512 x 256 pixels (513 x 257 rays). */
static bsp_scene *camera_scene(void)
{
    bsp_scene *s = bsp_scene_create();
    REQUIRE(s != NULL);
    bsp_error err;
    bsp_camera c;
    memset(&c, 0, sizeof c);
    c.from = (bsp_vec3){{0, 0, -5}};
    c.at = (bsp_vec3){{0, 0, 0}};
    c.up = (bsp_vec3){{0, 1, 0}};
    c.angle_deg = 90.0;
    c.res_x = 512;
    c.res_y = 256;
    REQUIRE(bsp_scene_set_camera(s, &c, &err) == BSP_OK);
    bsp_vec3 centre = {{0, 0, 0}};
    REQUIRE(bsp_scene_add_sphere(s, centre, 1.0, &err) == BSP_OK);
    return s;
}

TEST(view_resolve_from_camera_and_options)
{
    bsp_scene *s = camera_scene();
    bsp_build_options o;
    bsp_build_options_defaults(&o);
    o.kind = BSP_ACCEL_SAH_PER;
    kd_view v;
    bsp_error err;
    REQUIRE(kd_view_resolve(s, &o, 0, &v, &err) == BSP_OK);
    CHECK_NEAR(v.hx, 1.0, 1e-12);      /* tan 45 */
    CHECK_NEAR(v.hy, 0.5, 1e-12);      /* 256 / 512 of it */
    CHECK_NEAR(v.fwd.z, 1.0, 1e-15);
    CHECK_NEAR(v.up.y, 1.0, 1e-15);
    /* PAR: the default window is the perspective width at the look-at
     * point, 2 tan 45 * 5 = 10 */
    REQUIRE(kd_view_resolve(s, &o, 1, &v, &err) == BSP_OK);
    CHECK_NEAR(v.hx, 5.0, 1e-12);
    CHECK_NEAR(v.hy, 2.5, 1e-12);
    o.view.ortho_width = 3.0;
    REQUIRE(kd_view_resolve(s, &o, 1, &v, &err) == BSP_OK);
    CHECK_NEAR(v.hx, 1.5, 1e-12);
    /* explicit views, and their errors */
    o.view.explicit_view = 1;
    o.view.eye = (bsp_vec3){{1, 2, 3}};
    o.view.dir = (bsp_vec3){{0, 0, -2}};
    o.view.up = (bsp_vec3){{0, 1, 0}};
    o.view.fov_deg = 60.0;
    REQUIRE(kd_view_resolve(s, &o, 0, &v, &err) == BSP_OK);
    CHECK_NEAR(v.hx, tan(30.0 * BSP_PI / 180.0), 1e-12);
    CHECK_NEAR(v.fwd.z, -1.0, 1e-15);
    o.view.up = (bsp_vec3){{0, 0, 1}};
    CHECK(kd_view_resolve(s, &o, 0, &v, &err) == BSP_ERR_INVALID);
    CHECK_STR_CONTAINS(err.message, "parallel");
    o.view.up = (bsp_vec3){{0, 1, 0}};
    o.view.fov_deg = 180.0;
    CHECK(kd_view_resolve(s, &o, 0, &v, &err) == BSP_ERR_INVALID);
    o.view.fov_deg = 60.0;
    o.view.dir = (bsp_vec3){{0, NAN, 0}};
    CHECK(kd_view_resolve(s, &o, 0, &v, &err) == BSP_ERR_INVALID);
    bsp_scene_destroy(s);

    /* a scene without a camera cannot resolve its own view */
    bsp_scene *nc = bsp_scene_create();
    bsp_build_options d;
    bsp_build_options_defaults(&d);
    d.kind = BSP_ACCEL_SAH_PAR;
    CHECK(kd_view_resolve(nc, &d, 1, &v, &err) == BSP_ERR_INVALID);
    CHECK_STR_CONTAINS(err.message, "no camera");
    bsp_scene_destroy(nc);
}

TEST(view_orthographic_render_rays)
{
    /* the orthographic camera: every primary ray runs along the view
     * direction; with a window 2.2 wide around the sphere of radius 1 the
     * 65 x 65 SPD grid covers [-1.1, 1.1]^2, so the hits are the grid points
     * inside the unit disc (none lies on its rim: 1.21 (a^2 + b^2) = 1024
     * has no integer solution) — counted here */
    bsp_scene *s = camera_scene();
    bsp_build_options bo;
    bsp_build_options_defaults(&bo);
    bo.kind = BSP_ACCEL_NAIVE;
    bsp_accel *a = NULL;
    bsp_error err;
    REQUIRE(bsp_accel_build(s, &bo, &a, &err) == BSP_OK);
    bsp_render_options ro;
    bsp_render_options_defaults(&ro);
    ro.width = ro.height = 65;
    ro.max_depth = 0;
    ro.threads = 1;
    ro.orthographic = 1;
    ro.ortho_width = 2.2;
    bsp_image *img = NULL;
    bsp_render_stats st;
    REQUIRE(bsp_render(a, &ro, &img, &st, &err) == BSP_OK);
    uint64_t inside = 0;
    for (int y = 0; y < 65; y++)
        for (int x = 0; x < 65; x++) {
            double u = 1.1 * (x - 32) / 32.0, w = 1.1 * (32 - y) / 32.0;
            inside += u * u + w * w < 1.0;
        }
    CHECK_EQ_INT(st.cls[BSP_RAY_PRIMARY].rays, 65 * 65);
    CHECK_EQ_INT(st.cls[BSP_RAY_PRIMARY].hits, inside);
    bsp_image_destroy(img);
    bsp_accel_destroy(a);
    bsp_scene_destroy(s);
}

/* The sah-mixed pre-pass: its share of primary rays is the share in an
 * ordinary render (naive method) through the same camera. */
TEST(view_mixed_prepass_share)
{
    bsp_scene *s = NULL;
    bsp_error err;
    REQUIRE(bsp_scene_load("spd:balls:1", &s, &err) == BSP_OK);
    bsp_camera cam = *bsp_scene_camera(s);
    cam.res_x = cam.res_y = 32; /* 33 x 33 rays */
    double share = 0.0;
    REQUIRE(bsp_measure_primary_share(s, &cam, 4, &share, &err) == BSP_OK);

    bsp_build_options bo;
    bsp_build_options_defaults(&bo);
    bo.kind = BSP_ACCEL_NAIVE;
    bsp_accel *a = NULL;
    REQUIRE(bsp_accel_build(s, &bo, &a, &err) == BSP_OK);
    bsp_render_options ro;
    bsp_render_options_defaults(&ro);
    ro.camera = &cam;
    ro.threads = 1;
    bsp_image *img = NULL;
    bsp_render_stats st;
    REQUIRE(bsp_render(a, &ro, &img, &st, &err) == BSP_OK);
    uint64_t all = 0;
    for (int c = 0; c < BSP_RAY_CLASS_COUNT; c++)
        all += st.cls[c].rays;
    CHECK_EQ_INT(st.cls[BSP_RAY_PRIMARY].rays, 33 * 33);
    CHECK(all > st.cls[BSP_RAY_PRIMARY].rays); /* balls has shadows and reflections */
    CHECK_NEAR(share, (double)st.cls[BSP_RAY_PRIMARY].rays / (double)all, 1e-15);
    bsp_image_destroy(img);
    bsp_accel_destroy(a);

    /* a mixed build with the share given and one measuring it: both exact
     * trees; an invalid share is an error */
    bsp_build_options mo;
    bsp_build_options_defaults(&mo);
    mo.kind = BSP_ACCEL_SAH_MIXED;
    mo.mixed_primary_share = 1.5;
    CHECK(bsp_accel_build(s, &mo, &a, &err) == BSP_ERR_INVALID);
    CHECK_STR_CONTAINS(err.message, "share");
    bsp_scene_destroy(s);
}
