/*
 * test_scene_access.c — the public geometry accessors of bspray/scene.h
 * (bsp_scene_prim_sphere, _cone, _vertex, _vertex_normal) on scenes built by
 * hand: what goes in comes back (bit for bit where the header promises it,
 * within a few ulps for a triangle's edges and a cone's apex), and every
 * accessor refuses the wrong kind, a dropped primitive and an index out of
 * range without writing its outputs. Also: every destroy function takes NULL.
 */
#include <math.h>

#include "bspray/bspray.h"
#include "harness.h"

static int vec_eq(bsp_vec3 a, bsp_vec3 b)
{
    return a.x == b.x && a.y == b.y && a.z == b.z;
}

static int vec_near(bsp_vec3 a, bsp_vec3 b, double tol)
{
    return fabs(a.x - b.x) <= tol && fabs(a.y - b.y) <= tol && fabs(a.z - b.z) <= tol;
}

/* A marker value the accessors must leave alone on failure. */
static const double UNTOUCHED = 12345.0;

static bsp_vec3 untouched_vec(void)
{
    return bsp_v3(UNTOUCHED, UNTOUCHED, UNTOUCHED);
}

/* Primitive indices of the scene built by mixed_scene(). */
enum { P_SPHERE, P_INSIDE_SPHERE, P_TRI, P_QUAD, P_CONCAVE, P_PATCH3, P_PATCH4, P_CONE,
       P_INSIDE_CONE, P_DROPPED, P_COUNT };

static const bsp_vec3 quad_v[4] = {{{0, 0, 1}}, {{2, 0, 1}}, {{2, 3, 1}}, {{0, 3, 1}}};
/* an L shape: concave at (1, 1) */
static const bsp_vec3 ell_v[6] = {{{0, 0, 0}}, {{2, 0, 0}}, {{2, 1, 0}},
                                  {{1, 1, 0}}, {{1, 2, 0}}, {{0, 2, 0}}};
/* not exactly representable coordinates: v0 + (v1 - v0) may round */
static const bsp_vec3 tri_v[3] = {{{0.1, 0.2, 0.3}}, {{1.7, -0.3, 0.9}}, {{0.4, 2.3, -1.1}}};
static const bsp_vec3 patch_n[4] = {{{0, 0, 2}}, {{0, 3, 0}}, {{4, 0, 0}}, {{0, 0, -1}}};

/* One primitive of every kind, in the order of the enum above. */
static bsp_scene *mixed_scene(void)
{
    bsp_scene *s = bsp_scene_create();
    REQUIRE(s);
    bsp_error err;
    REQUIRE(bsp_scene_add_sphere(s, bsp_v3(1, 2, 3), 0.5, &err) == BSP_OK);
    REQUIRE(bsp_scene_add_sphere(s, bsp_v3(-1, 0, 0.25), -4.0, &err) == BSP_OK);
    REQUIRE(bsp_scene_add_polygon(s, tri_v, 3, &err) == BSP_OK);
    REQUIRE(bsp_scene_add_polygon(s, quad_v, 4, &err) == BSP_OK);
    REQUIRE(bsp_scene_add_polygon(s, ell_v, 6, &err) == BSP_OK);
    REQUIRE(bsp_scene_add_patch(s, quad_v, patch_n, 3, &err) == BSP_OK);
    REQUIRE(bsp_scene_add_patch(s, quad_v, patch_n, 4, &err) == BSP_OK);
    /* an axis-parallel cone: its apex is base + 1 * 4, exact */
    REQUIRE(bsp_scene_add_cone(s, bsp_v3(1, 2, 3), 1.5, bsp_v3(1, 2, 7), 0.5, &err) == BSP_OK);
    REQUIRE(bsp_scene_add_cone(s, bsp_v3(0, 0, 0), -2.0, bsp_v3(3, 0, 0), -2.0, &err) ==
            BSP_OK);
    REQUIRE(bsp_scene_add_sphere(s, bsp_v3(0, 0, 0), 0.0, &err) == BSP_OK); /* dropped */
    REQUIRE(bsp_scene_prim_count(s) == P_COUNT);
    REQUIRE(bsp_scene_prim_kind(s, P_DROPPED) == BSP_PRIM_DROPPED);
    return s;
}

TEST(scene_access_sphere)
{
    bsp_scene *s = mixed_scene();
    bsp_vec3 c;
    double r;
    CHECK(bsp_scene_prim_sphere(s, P_SPHERE, &c, &r) == BSP_OK);
    CHECK(vec_eq(c, bsp_v3(1, 2, 3)) && r == 0.5);
    CHECK(bsp_scene_prim_sphere(s, P_INSIDE_SPHERE, &c, &r) == BSP_OK);
    CHECK(vec_eq(c, bsp_v3(-1, 0, 0.25)) && r == -4.0); /* the sign comes back */
    CHECK(bsp_scene_prim_sphere(s, P_SPHERE, NULL, NULL) == BSP_OK);
    bsp_scene_destroy(s);
}

TEST(scene_access_cone)
{
    bsp_scene *s = mixed_scene();
    bsp_vec3 b, a;
    double rb, ra;
    CHECK(bsp_scene_prim_cone(s, P_CONE, &b, &rb, &a, &ra) == BSP_OK);
    CHECK(vec_eq(b, bsp_v3(1, 2, 3)) && vec_eq(a, bsp_v3(1, 2, 7)));
    CHECK(rb == 1.5 && ra == 0.5);
    CHECK(bsp_scene_prim_cone(s, P_INSIDE_CONE, &b, &rb, &a, &ra) == BSP_OK);
    CHECK(vec_eq(b, bsp_v3(0, 0, 0)) && vec_eq(a, bsp_v3(3, 0, 0)));
    CHECK(rb == -2.0 && ra == -2.0);
    CHECK(bsp_scene_prim_cone(s, P_CONE, NULL, NULL, NULL, NULL) == BSP_OK);
    bsp_scene_destroy(s);
}

/* A slanted cone's apex is rebuilt from the unit axis and the length. */
TEST(scene_access_cone_slanted_apex_within_ulps)
{
    bsp_scene *s = bsp_scene_create();
    REQUIRE(s);
    bsp_error err;
    bsp_vec3 base = bsp_v3(0.3, -1.7, 2.9), apex = bsp_v3(4.1, 0.6, -3.3);
    REQUIRE(bsp_scene_add_cone(s, base, 0.7, apex, 0.0, &err) == BSP_OK);
    bsp_vec3 b, a;
    double rb, ra;
    CHECK(bsp_scene_prim_cone(s, 0, &b, &rb, &a, &ra) == BSP_OK);
    CHECK(vec_eq(b, base) && rb == 0.7 && ra == 0.0);
    CHECK(vec_near(a, apex, 1e-14));
    bsp_scene_destroy(s);
}

TEST(scene_access_polygon_vertices)
{
    bsp_scene *s = mixed_scene();
    CHECK_EQ_INT(bsp_scene_prim_vertex_count(s, P_QUAD), 4);
    CHECK_EQ_INT(bsp_scene_prim_vertex_count(s, P_CONCAVE), 6);
    bsp_vec3 v;
    for (size_t i = 0; i < 4; i++) {
        CHECK(bsp_scene_prim_vertex(s, P_QUAD, i, &v) == BSP_OK);
        CHECK(vec_eq(v, quad_v[i])); /* the pool keeps the input */
    }
    for (size_t i = 0; i < 6; i++) {
        CHECK(bsp_scene_prim_vertex(s, P_CONCAVE, i, &v) == BSP_OK);
        CHECK(vec_eq(v, ell_v[i]));
    }
    bsp_scene_destroy(s);
}

TEST(scene_access_triangle_vertices)
{
    bsp_scene *s = mixed_scene();
    CHECK_EQ_INT(bsp_scene_prim_vertex_count(s, P_TRI), 3);
    bsp_vec3 v;
    CHECK(bsp_scene_prim_vertex(s, P_TRI, 0, &v) == BSP_OK);
    CHECK(vec_eq(v, tri_v[0])); /* v0 is stored as given */
    for (size_t i = 1; i < 3; i++) {
        CHECK(bsp_scene_prim_vertex(s, P_TRI, i, &v) == BSP_OK);
        CHECK(vec_near(v, tri_v[i], 4e-15)); /* v0 + (vi - v0): one rounding each way */
    }
    /* small integers: the sums are exact */
    for (size_t i = 0; i < 3; i++) {
        CHECK(bsp_scene_prim_vertex(s, P_PATCH3, i, &v) == BSP_OK);
        CHECK(vec_eq(v, quad_v[i]));
    }
    bsp_scene_destroy(s);
}

TEST(scene_access_patch_normals)
{
    bsp_scene *s = mixed_scene();
    bsp_vec3 n;
    /* the stored normals are the input ones made unit */
    const bsp_vec3 unit[4] = {{{0, 0, 1}}, {{0, 1, 0}}, {{1, 0, 0}}, {{0, 0, -1}}};
    for (size_t i = 0; i < 3; i++) {
        CHECK(bsp_scene_prim_vertex_normal(s, P_PATCH3, i, &n) == BSP_OK);
        CHECK(vec_eq(n, unit[i]));
    }
    for (size_t i = 0; i < 4; i++) {
        CHECK(bsp_scene_prim_vertex_normal(s, P_PATCH4, i, &n) == BSP_OK);
        CHECK(vec_eq(n, unit[i]));
    }
    bsp_scene_destroy(s);
}

/* Every accessor on every primitive of another kind. */
TEST(scene_access_wrong_kind)
{
    bsp_scene *s = mixed_scene();
    for (size_t p = 0; p < P_COUNT; p++) {
        bsp_prim_kind k = bsp_scene_prim_kind(s, p);
        int sphere_ok = k == BSP_PRIM_SPHERE, cone_ok = k == BSP_PRIM_CONE;
        int vert_ok = k == BSP_PRIM_POLYGON || k == BSP_PRIM_PATCH;
        int normal_ok = k == BSP_PRIM_PATCH;
        CHECK_MSG((bsp_scene_prim_sphere(s, p, NULL, NULL) == BSP_OK) == sphere_ok, "prim %zu", p);
        CHECK_MSG((bsp_scene_prim_cone(s, p, NULL, NULL, NULL, NULL) == BSP_OK) == cone_ok,
                  "prim %zu", p);
        CHECK_MSG((bsp_scene_prim_vertex(s, p, 0, NULL) == BSP_OK) == vert_ok, "prim %zu", p);
        CHECK_MSG((bsp_scene_prim_vertex_normal(s, p, 0, NULL) == BSP_OK) == normal_ok,
                  "prim %zu", p);
    }
    bsp_scene_destroy(s);
}

/* Failures return BSP_ERR_INVALID and leave every output as it was. */
TEST(scene_access_errors_write_nothing)
{
    bsp_scene *s = mixed_scene();
    bsp_vec3 c = untouched_vec(), a = untouched_vec();
    double r = UNTOUCHED, ra = UNTOUCHED;
    CHECK(bsp_scene_prim_sphere(s, P_CONE, &c, &r) == BSP_ERR_INVALID);
    CHECK(bsp_scene_prim_sphere(s, P_DROPPED, &c, &r) == BSP_ERR_INVALID);
    CHECK(bsp_scene_prim_sphere(s, P_COUNT, &c, &r) == BSP_ERR_INVALID);
    CHECK(bsp_scene_prim_sphere(s, (size_t)-1, &c, &r) == BSP_ERR_INVALID);
    CHECK(bsp_scene_prim_cone(s, P_SPHERE, &c, &r, &a, &ra) == BSP_ERR_INVALID);
    CHECK(bsp_scene_prim_cone(s, P_COUNT, &c, &r, &a, &ra) == BSP_ERR_INVALID);
    CHECK(vec_eq(c, untouched_vec()) && vec_eq(a, untouched_vec()));
    CHECK(r == UNTOUCHED && ra == UNTOUCHED);
    bsp_scene_destroy(s);
}

TEST(scene_access_vertex_index_out_of_range)
{
    bsp_scene *s = mixed_scene();
    bsp_vec3 v = untouched_vec();
    CHECK(bsp_scene_prim_vertex(s, P_TRI, 3, &v) == BSP_ERR_INVALID);
    CHECK(bsp_scene_prim_vertex(s, P_QUAD, 4, &v) == BSP_ERR_INVALID);
    CHECK(bsp_scene_prim_vertex(s, P_CONCAVE, 6, &v) == BSP_ERR_INVALID);
    CHECK(bsp_scene_prim_vertex(s, P_QUAD, (size_t)-1, &v) == BSP_ERR_INVALID);
    CHECK(bsp_scene_prim_vertex(s, P_COUNT, 0, &v) == BSP_ERR_INVALID);
    CHECK(bsp_scene_prim_vertex_normal(s, P_PATCH3, 3, &v) == BSP_ERR_INVALID);
    CHECK(bsp_scene_prim_vertex_normal(s, P_PATCH4, 4, &v) == BSP_ERR_INVALID);
    CHECK(bsp_scene_prim_vertex_normal(s, P_QUAD, 0, &v) == BSP_ERR_INVALID);
    CHECK(vec_eq(v, untouched_vec()));
    bsp_scene_destroy(s);
}

/* A patch given without normals has none to read. */
TEST(scene_access_patch_without_normals)
{
    bsp_scene *s = bsp_scene_create();
    REQUIRE(s);
    bsp_error err;
    REQUIRE(bsp_scene_add_patch(s, quad_v, NULL, 4, &err) == BSP_OK);
    REQUIRE(bsp_scene_add_patch(s, quad_v, NULL, 3, &err) == BSP_OK);
    bsp_vec3 n = untouched_vec(), v;
    CHECK(bsp_scene_prim_vertex_normal(s, 0, 0, &n) == BSP_ERR_INVALID);
    CHECK(bsp_scene_prim_vertex_normal(s, 1, 2, &n) == BSP_ERR_INVALID);
    CHECK(vec_eq(n, untouched_vec()));
    CHECK(bsp_scene_prim_vertex(s, 0, 3, &v) == BSP_OK && vec_eq(v, quad_v[3]));
    bsp_scene_destroy(s);
}

/* An empty scene: every index is out of range. */
TEST(scene_access_empty_scene)
{
    bsp_scene *s = bsp_scene_create();
    REQUIRE(s);
    CHECK(bsp_scene_prim_sphere(s, 0, NULL, NULL) == BSP_ERR_INVALID);
    CHECK(bsp_scene_prim_cone(s, 0, NULL, NULL, NULL, NULL) == BSP_ERR_INVALID);
    CHECK(bsp_scene_prim_vertex(s, 0, 0, NULL) == BSP_ERR_INVALID);
    CHECK(bsp_scene_prim_vertex_normal(s, 0, 0, NULL) == BSP_ERR_INVALID);
    bsp_scene_destroy(s);
}

/* Every destroy function takes NULL and does nothing (DESIGN: destroy(NULL)
 * is a no-op), so error paths can free what they have without tests. */
TEST(api_destroy_null_is_a_no_op)
{
    bsp_scene_destroy(NULL);
    bsp_accel_destroy(NULL);
    bsp_query_destroy(NULL);
    bsp_image_destroy(NULL);
    /* and the objects they free still work after such calls */
    bsp_scene *s = bsp_scene_create();
    REQUIRE(s);
    bsp_error err;
    REQUIRE(bsp_scene_add_sphere(s, bsp_v3(0, 0, 0), 1.0, &err) == BSP_OK);
    bsp_accel *a = NULL;
    REQUIRE(bsp_accel_build(s, NULL, &a, &err) == BSP_OK);
    bsp_query *q = bsp_query_create(a);
    REQUIRE(q);
    bsp_ray r = {bsp_v3(0, 0, -5), bsp_v3(0, 0, 1), 0.0, INFINITY};
    bsp_hit h;
    CHECK(bsp_intersect(a, q, &r, &h) && h.prim == 0 && h.t == 4.0);
    bsp_query_destroy(q);
    bsp_accel_destroy(a);
    bsp_scene_destroy(s);
}
