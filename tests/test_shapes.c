/*
 * test_shapes.c — unit tests of the ray–shape routines in src/geom: setup and
 * degeneracy, exact bounds, intersection (plain, miss, grazing, inside,
 * on-surface origins, parallel rays, interval filtering, unnormalised
 * directions, concave polygons) and normals. Expected values are worked out
 * by hand in the comments; the few randomised tests check properties only.
 */
#include <math.h>
#include <stdint.h>

#include "geom/shapes.h"
#include "geom/vec.h"
#include "harness.h"

#define EPS 1e-12

static bsp_ray mkray(bsp_vec3 org, bsp_vec3 dir, double tmin, double tmax)
{
    bsp_ray r;
    r.org = org;
    r.dir = dir;
    r.tmin = tmin;
    r.tmax = tmax;
    return r;
}

static bsp_ray ray0(double ox, double oy, double oz, double dx, double dy, double dz)
{
    return mkray(bsp_v3(ox, oy, oz), bsp_v3(dx, dy, dz), 0.0, INFINITY);
}

static int vec_near(bsp_vec3 a, bsp_vec3 b, double tol)
{
    return fabs(a.x - b.x) <= tol && fabs(a.y - b.y) <= tol && fabs(a.z - b.z) <= tol;
}

static int vec_eq(bsp_vec3 a, bsp_vec3 b)
{
    return a.x == b.x && a.y == b.y && a.z == b.z;
}

/* A small deterministic generator for the property tests: rnd draws from
 * one shared stream; a test that must not shift the other tests' draws uses
 * a stream of its own with rnd_from. */
static double rnd_from(uint64_t *state, double lo, double hi)
{
    *state = *state * 6364136223846793005u + 1442695040888963407u;
    return lo + (hi - lo) * (double)(*state >> 11) * (1.0 / 9007199254740992.0);
}
static uint64_t rng_state = 0x9E3779B97F4A7C15u;
static double rnd(double lo, double hi)
{
    return rnd_from(&rng_state, lo, hi);
}

/* ======================================================================== */
/* sphere                                                                   */
/* ======================================================================== */

static sphere_shape unit_sphere(void)
{
    sphere_shape s;
    REQUIRE(sphere_setup(&s, bsp_v3(0, 0, 0), 1.0));
    return s;
}

TEST(sphere_setup_and_degenerate)
{
    sphere_shape s;
    CHECK(sphere_setup(&s, bsp_v3(1, 2, 3), 2.0));
    CHECK(s.radius == 2.0 && s.radius2 == 4.0 && s.inside_only == 0);
    CHECK(sphere_setup(&s, bsp_v3(1, 2, 3), -0.5));
    CHECK(s.radius == 0.5 && s.radius2 == 0.25 && s.inside_only == 1);
    CHECK_EQ_INT(sphere_setup(&s, bsp_v3(1, 2, 3), 0.0), 0);
    CHECK_EQ_INT(sphere_setup(&s, bsp_v3(1, 2, 3), -0.0), 0);
}

TEST(sphere_plain_hit_and_miss)
{
    sphere_shape s;
    REQUIRE(sphere_setup(&s, bsp_v3(1, 2, 3), 2.0));
    double t = -1.0;
    /* from (1,2,-5) along +z: front at z = 1, t = 6 */
    bsp_ray r = ray0(1, 2, -5, 0, 0, 1);
    CHECK(sphere_intersect(&s, &r, &t));
    CHECK(t == 6.0);
    /* off by more than the radius */
    r = ray0(3.5, 2, -5, 0, 0, 1);
    CHECK_EQ_INT(sphere_intersect(&s, &r, &t), 0);
    /* pointing away */
    r = ray0(1, 2, -5, 0, 0, -1);
    CHECK_EQ_INT(sphere_intersect(&s, &r, &t), 0);
    /* diagonal ray through the centre: |dir| = sqrt(3), hits at distance
     * |(-5,-5,-5)| - 2 = 5 sqrt(3) - 2, i.e. t = 5 - 2/sqrt(3) */
    r = ray0(-4, -3, -2, 1, 1, 1);
    CHECK(sphere_intersect(&s, &r, &t));
    CHECK_NEAR(t, 5.0 - 2.0 / sqrt(3.0), EPS);
}

TEST(sphere_grazing_tangent)
{
    sphere_shape s = unit_sphere();
    double t = -1.0;
    /* y = 1 touches the unit sphere at (0,1,0): disc is exactly 0, t = 5 */
    bsp_ray r = ray0(-5, 1, 0, 1, 0, 0);
    CHECK(sphere_intersect(&s, &r, &t));
    CHECK(t == 5.0);
    /* the same ray run twice gives the same answer */
    double t2 = -1.0;
    CHECK(sphere_intersect(&s, &r, &t2));
    CHECK(t2 == t);
    /* a hair outside misses */
    r = ray0(-5, 1.0 + 1e-12, 0, 1, 0, 0);
    CHECK_EQ_INT(sphere_intersect(&s, &r, &t), 0);
    /* nearly tangent (one ulp inside): either answer is fine, never NaN */
    r = ray0(-5, nextafter(1.0, 0.0), 0, 1, 0, 0);
    t = 0.0;
    if (sphere_intersect(&s, &r, &t))
        CHECK(isfinite(t) && fabs(t - 5.0) < 1e-6);
}

TEST(sphere_origin_inside_and_on_surface)
{
    sphere_shape s = unit_sphere();
    double t = -1.0;
    /* from the centre: the only root in [0, inf) is the far one, t = 1 */
    bsp_ray r = ray0(0, 0, 0, 0, 0, 1);
    CHECK(sphere_intersect(&s, &r, &t));
    CHECK(t == 1.0);
    /* from (0,0,0.5) towards -z: exit at z = -1, t = 1.5 */
    r = ray0(0, 0, 0.5, 0, 0, -1);
    CHECK(sphere_intersect(&s, &r, &t));
    CHECK(t == 1.5);
    /* origin on the surface heading in: t = 0 with tmin = 0 ... */
    r = ray0(1, 0, 0, -1, 0, 0);
    CHECK(sphere_intersect(&s, &r, &t));
    CHECK(t == 0.0);
    /* ... and the far side t = 2 once 0 is excluded */
    r.tmin = 1e-9;
    CHECK(sphere_intersect(&s, &r, &t));
    CHECK(t == 2.0);
    /* on the surface heading out: only t = 0 */
    r = ray0(1, 0, 0, 1, 0, 0);
    CHECK(sphere_intersect(&s, &r, &t));
    CHECK(t == 0.0);
    r.tmin = 1e-9;
    CHECK_EQ_INT(sphere_intersect(&s, &r, &t), 0);
    /* on the surface, tangent: q == 0, double root at 0 */
    r = ray0(1, 0, 0, 0, 1, 0);
    CHECK(sphere_intersect(&s, &r, &t));
    CHECK(t == 0.0);
}

TEST(sphere_interval_filter_bit_identical)
{
    sphere_shape s;
    REQUIRE(sphere_setup(&s, bsp_v3(0.3, -0.7, 0.1), 0.9));
    bsp_ray r = ray0(-3.1, 2.3, 1.7, 1.3, -1.1, -0.6);
    double t_full = -1.0, t = -1.0;
    REQUIRE(sphere_intersect(&s, &r, &t_full));
    r.tmax = t_full; /* inclusive */
    CHECK(sphere_intersect(&s, &r, &t));
    CHECK(t == t_full);
    r.tmax = nextafter(t_full, 0.0); /* excludes the near root */
    CHECK_EQ_INT(sphere_intersect(&s, &r, &t), 0);
    r.tmin = 0.5 * t_full;
    r.tmax = 1e6;
    CHECK(sphere_intersect(&s, &r, &t));
    CHECK(t == t_full);
    /* tmin just past the near root gives the far one */
    r.tmin = nextafter(t_full, INFINITY);
    CHECK(sphere_intersect(&s, &r, &t));
    CHECK(t > t_full);
    /* a hit beyond tmax is excluded */
    r = ray0(0.3, -0.7, -10, 0, 0, 1); /* near root t = 10.1 - 0.9 = 9.2 */
    r.tmax = 9.0;
    CHECK_EQ_INT(sphere_intersect(&s, &r, &t), 0);
    r.tmax = 9.5;
    CHECK(sphere_intersect(&s, &r, &t));
    CHECK_NEAR(t, 9.2, EPS);
}

TEST(sphere_unnormalised_and_zero_direction)
{
    sphere_shape s = unit_sphere();
    double t1 = -1.0, t2 = -1.0, t3 = -1.0;
    /* t halves when dir doubles (exactly: scaling by 2 is exact) */
    bsp_ray r = ray0(-3.7, 0.2, 0.1, 1.1, -0.05, -0.02);
    bsp_ray r2 = ray0(-3.7, 0.2, 0.1, 2.2, -0.1, -0.04);
    REQUIRE(sphere_intersect(&s, &r, &t1));
    REQUIRE(sphere_intersect(&s, &r2, &t2));
    CHECK(t2 == 0.5 * t1);
    /* a direction of length 4 along -y from (0,5,0): t = 4 / 4 = 1 */
    r = ray0(0, 5, 0, 0, -4, 0);
    CHECK(sphere_intersect(&s, &r, &t3));
    CHECK(t3 == 1.0);
    /* zero direction: no hit, no NaN */
    r = ray0(0, 0, 0, 0, 0, 0);
    CHECK_EQ_INT(sphere_intersect(&s, &r, &t3), 0);
    r = ray0(5, 5, 5, 0, 0, 0);
    CHECK_EQ_INT(sphere_intersect(&s, &r, &t3), 0);
}

TEST(sphere_far_origin_accuracy)
{
    /* origin 1e8 away: the root must still be accurate to ~1e-8 relative */
    sphere_shape s;
    REQUIRE(sphere_setup(&s, bsp_v3(0, 0, 0), 1e-3));
    bsp_ray r = ray0(-1e8, 0.5e-3, 0, 1, 0, 0);
    double t = -1.0;
    REQUIRE(sphere_intersect(&s, &r, &t));
    /* x = -sqrt(1e-6 - 0.25e-6) = -sqrt(0.75) * 1e-3 */
    CHECK_NEAR(t, 1e8 - sqrt(0.75) * 1e-3, 1e-7);
}

TEST(sphere_bounds_exact)
{
    sphere_shape s;
    REQUIRE(sphere_setup(&s, bsp_v3(1, 2, 3), 0.5));
    bsp_box b = sphere_bounds(&s);
    CHECK(vec_eq(b.lo, bsp_v3(0.5, 1.5, 2.5)));
    CHECK(vec_eq(b.hi, bsp_v3(1.5, 2.5, 3.5)));
}

TEST(sphere_normal_unit_outward)
{
    sphere_shape s;
    REQUIRE(sphere_setup(&s, bsp_v3(1, 2, 3), 2.0));
    CHECK(vec_near(sphere_normal(&s, bsp_v3(1, 2, 5)), bsp_v3(0, 0, 1), EPS));
    CHECK(vec_near(sphere_normal(&s, bsp_v3(-1, 2, 3)), bsp_v3(-1, 0, 0), EPS));
    bsp_vec3 p = bsp_v3(1 + 2 / sqrt(3.0), 2 + 2 / sqrt(3.0), 3 + 2 / sqrt(3.0));
    bsp_vec3 n = sphere_normal(&s, p);
    CHECK_NEAR(v3_length(n), 1.0, EPS);
    CHECK(vec_near(n, bsp_v3(1 / sqrt(3.0), 1 / sqrt(3.0), 1 / sqrt(3.0)), EPS));
}

TEST(sphere_random_roots_on_surface)
{
    sphere_shape s;
    REQUIRE(sphere_setup(&s, bsp_v3(0.5, -0.25, 2), 1.5));
    int hits = 0;
    for (int i = 0; i < 2000; i++) {
        bsp_ray r = ray0(rnd(-5, 5), rnd(-5, 5), rnd(-5, 5), rnd(-1, 1), rnd(-1, 1), rnd(-1, 1));
        double t = -1.0, t2 = -1.0;
        if (!sphere_intersect(&s, &r, &t))
            continue;
        hits++;
        CHECK(t >= 0.0 && isfinite(t));
        double dist = v3_length(v3_sub(ray_at(&r, t), s.center));
        CHECK_NEAR(dist, 1.5, 1e-9);
        r.tmax = t;
        CHECK(sphere_intersect(&s, &r, &t2) && t2 == t);
    }
    CHECK(hits > 100);
}

/* ======================================================================== */
/* triangle                                                                 */
/* ======================================================================== */

/* (0,0,0), (1,0,0), (0,1,0): normal +z */
static triangle_shape unit_triangle(void)
{
    triangle_shape tr;
    REQUIRE(triangle_setup(&tr, bsp_v3(0, 0, 0), bsp_v3(1, 0, 0), bsp_v3(0, 1, 0),
                           SHAPE_NO_NORMALS));
    return tr;
}

TEST(triangle_setup_and_degenerate)
{
    triangle_shape tr = unit_triangle();
    CHECK(vec_eq(tr.normal, bsp_v3(0, 0, 1)));
    CHECK(vec_eq(tr.v0, bsp_v3(0, 0, 0)) && vec_eq(tr.v1, bsp_v3(1, 0, 0)) &&
          vec_eq(tr.v2, bsp_v3(0, 1, 0)));
    /* |e1|_1 + |e2|_1 = 2: the least power of two above it is 4 */
    CHECK_EQ_INT(tr.edge_exp, 2);
    CHECK(triangle_edge_norm(tr.edge_exp) == 4.0);
    CHECK(tr.normals == SHAPE_NO_NORMALS);
    /* reversed winding flips the normal */
    REQUIRE(triangle_setup(&tr, bsp_v3(0, 0, 0), bsp_v3(0, 1, 0), bsp_v3(1, 0, 0), 7));
    CHECK(vec_eq(tr.normal, bsp_v3(0, 0, -1)));
    CHECK(tr.normals == 7);
    /* collinear and coincident vertices */
    CHECK_EQ_INT(triangle_setup(&tr, bsp_v3(0, 0, 0), bsp_v3(1, 1, 1), bsp_v3(2, 2, 2), 0), 0);
    CHECK_EQ_INT(triangle_setup(&tr, bsp_v3(1, 2, 3), bsp_v3(1, 2, 3), bsp_v3(4, 5, 7), 0), 0);
    CHECK_EQ_INT(triangle_setup(&tr, bsp_v3(1, 2, 3), bsp_v3(1, 2, 3), bsp_v3(1, 2, 3), 0), 0);
}

TEST(triangle_plain_hit_and_miss)
{
    triangle_shape tr = unit_triangle();
    double t = -1, u = -1, v = -1;
    /* straight down onto (0.25, 0.5): t = 3, u = 0.25, v = 0.5 */
    bsp_ray r = ray0(0.25, 0.5, 3, 0, 0, -1);
    CHECK(triangle_intersect(&tr, &r, &t, &u, &v));
    CHECK(t == 3.0 && u == 0.25 && v == 0.5);
    /* from below: both sides are hit */
    r = ray0(0.25, 0.5, -2, 0, 0, 1);
    CHECK(triangle_intersect(&tr, &r, &t, &u, &v));
    CHECK(t == 2.0 && u == 0.25 && v == 0.5);
    /* outside the hypotenuse, outside each leg, pointing away */
    r = ray0(0.75, 0.5, 3, 0, 0, -1);
    CHECK_EQ_INT(triangle_intersect(&tr, &r, &t, &u, &v), 0);
    r = ray0(-0.25, 0.5, 3, 0, 0, -1);
    CHECK_EQ_INT(triangle_intersect(&tr, &r, &t, &u, &v), 0);
    r = ray0(0.5, -0.25, 3, 0, 0, -1);
    CHECK_EQ_INT(triangle_intersect(&tr, &r, &t, &u, &v), 0);
    r = ray0(0.25, 0.25, 3, 0, 0, 1);
    CHECK_EQ_INT(triangle_intersect(&tr, &r, &t, &u, &v), 0);
    /* an oblique ray onto a tilted triangle (2,0,0),(0,2,0),(0,0,2), plane
     * x + y + z = 2: from the origin along (1,1,1), hit at (2/3,2/3,2/3),
     * t = 2/3, barycentrics 1/3 each */
    triangle_shape t2;
    REQUIRE(triangle_setup(&t2, bsp_v3(2, 0, 0), bsp_v3(0, 2, 0), bsp_v3(0, 0, 2),
                           SHAPE_NO_NORMALS));
    r = ray0(0, 0, 0, 1, 1, 1);
    CHECK(triangle_intersect(&t2, &r, &t, &u, &v));
    CHECK_NEAR(t, 2.0 / 3.0, EPS);
    CHECK_NEAR(u, 1.0 / 3.0, EPS);
    CHECK_NEAR(v, 1.0 / 3.0, EPS);
}

TEST(triangle_edges_and_vertices)
{
    triangle_shape tr = unit_triangle();
    double t = -1, u = -1, v = -1;
    /* on the hypotenuse: u + v == 1 counts as inside */
    bsp_ray r = ray0(0.5, 0.5, 1, 0, 0, -1);
    CHECK(triangle_intersect(&tr, &r, &t, &u, &v));
    CHECK(t == 1.0 && u == 0.5 && v == 0.5);
    /* on the leg y = 0 (v == 0) and x = 0 (u == 0) */
    r = ray0(0.5, 0, 1, 0, 0, -1);
    CHECK(triangle_intersect(&tr, &r, &t, &u, &v));
    CHECK(u == 0.5 && v == 0.0);
    r = ray0(0, 0.5, 1, 0, 0, -1);
    CHECK(triangle_intersect(&tr, &r, &t, &u, &v));
    CHECK(u == 0.0 && v == 0.5);
    /* exactly at each vertex */
    r = ray0(0, 0, 1, 0, 0, -1);
    CHECK(triangle_intersect(&tr, &r, &t, &u, &v));
    CHECK(t == 1.0 && u == 0.0 && v == 0.0);
    r = ray0(1, 0, 1, 0, 0, -1);
    CHECK(triangle_intersect(&tr, &r, &t, &u, &v));
    CHECK(t == 1.0 && u == 1.0 && v == 0.0);
    r = ray0(0, 1, 1, 0, 0, -1);
    CHECK(triangle_intersect(&tr, &r, &t, &u, &v));
    CHECK(t == 1.0 && u == 0.0 && v == 1.0);
    /* just past a vertex */
    r = ray0(1.0 + 1e-15, 0, 1, 0, 0, -1);
    CHECK_EQ_INT(triangle_intersect(&tr, &r, &t, &u, &v), 0);
    /* a ray running along an edge, in the plane: parallel, so a miss */
    r = ray0(-1, 0, 0, 1, 0, 0);
    CHECK_EQ_INT(triangle_intersect(&tr, &r, &t, &u, &v), 0);
    r = ray0(1.5, -0.5, 0, -1, 1, 0); /* along the hypotenuse's line */
    CHECK_EQ_INT(triangle_intersect(&tr, &r, &t, &u, &v), 0);
    /* parallel above the plane */
    r = ray0(0.2, 0.2, 1, 1, 0, 0);
    CHECK_EQ_INT(triangle_intersect(&tr, &r, &t, &u, &v), 0);
    /* an oblique ray through the vertex (1,0,0) from (0,-1,1) */
    r = ray0(0, -1, 1, 1, 1, -1);
    CHECK(triangle_intersect(&tr, &r, &t, &u, &v));
    CHECK(t == 1.0 && u == 1.0 && v == 0.0);
}

TEST(triangle_origin_on_surface)
{
    triangle_shape tr = unit_triangle();
    double t = -1, u = -1, v = -1;
    bsp_ray r = ray0(0.25, 0.25, 0, 0, 0, 1);
    CHECK(triangle_intersect(&tr, &r, &t, &u, &v));
    CHECK(t == 0.0 && u == 0.25 && v == 0.25);
    r.tmin = 1e-9;
    CHECK_EQ_INT(triangle_intersect(&tr, &r, &t, &u, &v), 0);
}

TEST(triangle_interval_unnormalised_zero_components)
{
    triangle_shape tr;
    REQUIRE(triangle_setup(&tr, bsp_v3(0.1, 0.2, 0.3), bsp_v3(1.7, -0.4, 0.9),
                           bsp_v3(-0.3, 1.3, 0.5), SHAPE_NO_NORMALS));
    double t = -1, u = -1, v = -1, t2 = -1, u2 = -1, v2 = -1;
    bsp_ray r = ray0(0.4, 0.3, 5, 0.05, 0.02, -1);
    REQUIRE(triangle_intersect(&tr, &r, &t, &u, &v));
    /* bit-identical when the interval changes */
    r.tmax = t;
    CHECK(triangle_intersect(&tr, &r, &t2, &u2, &v2));
    CHECK(t2 == t && u2 == u && v2 == v);
    r.tmin = t;
    r.tmax = 1e300;
    CHECK(triangle_intersect(&tr, &r, &t2, &u2, &v2));
    CHECK(t2 == t);
    r.tmin = 0.0;
    r.tmax = nextafter(t, 0.0);
    CHECK_EQ_INT(triangle_intersect(&tr, &r, &t2, &u2, &v2), 0);
    /* doubling the direction halves t, same barycentrics */
    r = ray0(0.4, 0.3, 5, 0.1, 0.04, -2);
    CHECK(triangle_intersect(&tr, &r, &t2, &u2, &v2));
    CHECK(t2 == 0.5 * t && u2 == u && v2 == v);
    /* two zero components: straight down onto the unit triangle with |dir| = 4 */
    triangle_shape ut = unit_triangle();
    r = ray0(0.5, 0.25, 2, 0, 0, -4);
    CHECK(triangle_intersect(&ut, &r, &t, &u, &v));
    CHECK(t == 0.5 && u == 0.5 && v == 0.25);
    /* one zero component, oblique: from (0,0.25,1) along (0.5,0,-1), hit at
     * (0.5, 0.25, 0), t = 1 */
    r = ray0(0, 0.25, 1, 0.5, 0, -1);
    CHECK(triangle_intersect(&ut, &r, &t, &u, &v));
    CHECK(t == 1.0 && u == 0.5 && v == 0.25);
    /* zero direction */
    r = ray0(0.2, 0.2, 0, 0, 0, 0);
    CHECK_EQ_INT(triangle_intersect(&ut, &r, &t, &u, &v), 0);
}

TEST(triangle_bounds_exact)
{
    triangle_shape tr;
    REQUIRE(triangle_setup(&tr, bsp_v3(1, -2, 3), bsp_v3(4, 0.5, -1), bsp_v3(-0.5, 2, 2),
                           SHAPE_NO_NORMALS));
    bsp_box b = triangle_bounds(&tr);
    CHECK(vec_eq(b.lo, bsp_v3(-0.5, -2, -1)));
    CHECK(vec_eq(b.hi, bsp_v3(4, 2, 3)));
    /* inexact edges: e1 = fl((1e17, -1e17) - (0.1, -0.1)) = (1e17, -1e17), so
     * the vertex intersected, v0 + e1 = (1e17 + 0.1, -1e17 - 0.1), lies one
     * rounding beyond the stored coordinates: the box is one ulp wider there,
     * and not where the sums are exact (z) */
    REQUIRE(triangle_setup(&tr, bsp_v3(0.1, -0.1, 0), bsp_v3(1e17, -1e17, 0.25),
                           bsp_v3(0.25, 0.5, 0.75), SHAPE_NO_NORMALS));
    b = triangle_bounds(&tr);
    CHECK(b.hi.x == nextafter(1e17, INFINITY));
    CHECK(b.lo.y == nextafter(-1e17, -INFINITY));
    CHECK(b.lo.x == 0.1 && b.lo.z == 0.0 && b.hi.z == 0.75);
}

TEST(triangle_shading_normal_interpolates)
{
    bsp_vec3 pool[4] = {bsp_v3(9, 9, 9), bsp_v3(0, 0, 2), bsp_v3(1, 0, 0), bsp_v3(0, 1, 0)};
    triangle_shape tr;
    REQUIRE(triangle_setup(&tr, bsp_v3(0, 0, 0), bsp_v3(1, 0, 0), bsp_v3(0, 1, 0), 1));
    CHECK(vec_near(triangle_shading_normal(&tr, pool, 0, 0), bsp_v3(0, 0, 1), EPS));
    CHECK(vec_near(triangle_shading_normal(&tr, pool, 1, 0), bsp_v3(1, 0, 0), EPS));
    CHECK(vec_near(triangle_shading_normal(&tr, pool, 0, 1), bsp_v3(0, 1, 0), EPS));
    /* centroid: (1/3)(0,0,2) + (1/3)(1,0,0) + (1/3)(0,1,0) -> (1,1,2)/sqrt(6) */
    bsp_vec3 n = triangle_shading_normal(&tr, pool, 1.0 / 3.0, 1.0 / 3.0);
    CHECK(vec_near(n, bsp_v3(1 / sqrt(6.0), 1 / sqrt(6.0), 2 / sqrt(6.0)), EPS));
    /* no vertex normals: the face normal */
    triangle_shape plain = unit_triangle();
    CHECK(vec_eq(triangle_shading_normal(&plain, pool, 0.2, 0.3), bsp_v3(0, 0, 1)));
    /* opposite vertex normals cancelling at the midpoint: the face normal */
    bsp_vec3 opp[3] = {bsp_v3(0, 0, 1), bsp_v3(0, 0, -1), bsp_v3(0, 0, 1)};
    REQUIRE(triangle_setup(&tr, bsp_v3(0, 0, 0), bsp_v3(1, 0, 0), bsp_v3(0, 1, 0), 0));
    CHECK(vec_eq(triangle_shading_normal(&tr, opp, 0.5, 0), bsp_v3(0, 0, 1)));
}

TEST(triangle_random_consistency)
{
    triangle_shape tr;
    bsp_vec3 a = bsp_v3(-1, -0.5, 0.3), b = bsp_v3(1.2, -0.2, -0.4), c = bsp_v3(0.1, 1.3, 0.6);
    REQUIRE(triangle_setup(&tr, a, b, c, SHAPE_NO_NORMALS));
    int hits = 0;
    for (int i = 0; i < 2000; i++) {
        bsp_ray r = ray0(rnd(-2, 2), rnd(-2, 2), rnd(2, 4), rnd(-0.5, 0.5), rnd(-0.5, 0.5), -1);
        double t, u, v;
        if (!triangle_intersect(&tr, &r, &t, &u, &v))
            continue;
        hits++;
        bsp_vec3 p = ray_at(&r, t);
        bsp_vec3 q = v3_add(v3_scale(a, 1 - u - v), v3_add(v3_scale(b, u), v3_scale(c, v)));
        CHECK(vec_near(p, q, 1e-12));
        CHECK(u >= 0 && v >= 0 && u + v <= 1 + 1e-15);
    }
    CHECK(hits > 100);
}

/* ======================================================================== */
/* polygon                                                                  */
/* ======================================================================== */

/* The L-shape (CCW in the plane z = 1):
 *
 *   (0,2) +---+ (1,2)
 *         |   |
 *         |   +-----+ (2,1)      the concavity is the square [1,2] x [1,2]
 *         |   (1,1) |
 *   (0,0) +---------+ (2,0)
 *
 * listed from (2,1) so that a fan from vertex 0 is wrong:
 * (2,1) (1,1) (1,2) (0,2) (0,0) (2,0). */
static const bsp_vec3 *l_shape(void)
{
    static bsp_vec3 v[8];
    v[0] = bsp_v3(7, 7, 7); /* padding: the polygon starts at index 1 */
    v[1] = bsp_v3(2, 1, 1);
    v[2] = bsp_v3(1, 1, 1);
    v[3] = bsp_v3(1, 2, 1);
    v[4] = bsp_v3(0, 2, 1);
    v[5] = bsp_v3(0, 0, 1);
    v[6] = bsp_v3(2, 0, 1);
    v[7] = bsp_v3(7, 7, 7);
    return v;
}

static const bsp_vec3 square_verts[4] = {{{0, 0, 0}}, {{2, 0, 0}}, {{2, 2, 0}}, {{0, 2, 0}}};

TEST(polygon_setup_plane_and_axes)
{
    polygon_shape p;
    const bsp_vec3 *v = l_shape();
    REQUIRE(polygon_setup(&p, v, 1, 6, SHAPE_NO_NORMALS));
    CHECK(vec_eq(p.normal, bsp_v3(0, 0, 1)));
    CHECK(p.d == 1.0);
    CHECK(p.first == 1 && p.count == 6 && p.normals == SHAPE_NO_NORMALS);
    CHECK(p.axis_u == 0 && p.axis_v == 1);
    /* a tilted square in the plane x + z = 2 (normal (1,0,1)/sqrt2, winding CCW
     * seen from +x+z): dominant axis x (tie with z broken towards x) */
    bsp_vec3 tv[4] = {bsp_v3(2, 0, 0), bsp_v3(2, 1, 0), bsp_v3(1, 1, 1), bsp_v3(1, 0, 1)};
    REQUIRE(polygon_setup(&p, tv, 0, 4, 3));
    CHECK(vec_near(p.normal, bsp_v3(1 / sqrt(2.0), 0, 1 / sqrt(2.0)), EPS));
    CHECK_NEAR(p.d, sqrt(2.0), EPS);
    CHECK(p.axis_u == 1 && p.axis_v == 2);
    CHECK(p.normals == 3);
    /* a square in y = -3 wound CW seen from +y: normal -y, axes z, x */
    bsp_vec3 yv[4] = {bsp_v3(0, -3, 0), bsp_v3(1, -3, 0), bsp_v3(1, -3, 1), bsp_v3(0, -3, 1)};
    REQUIRE(polygon_setup(&p, yv, 0, 4, SHAPE_NO_NORMALS));
    CHECK(vec_eq(p.normal, bsp_v3(0, -1, 0)));
    CHECK(p.d == 3.0);
    CHECK(p.axis_u == 2 && p.axis_v == 0);
}

TEST(polygon_degenerate)
{
    polygon_shape p;
    /* all vertices collinear */
    bsp_vec3 line[4] = {bsp_v3(0, 0, 0), bsp_v3(1, 1, 0), bsp_v3(2, 2, 0), bsp_v3(3, 3, 0)};
    CHECK_EQ_INT(polygon_setup(&p, line, 0, 4, SHAPE_NO_NORMALS), 0);
    /* all vertices equal */
    bsp_vec3 dot[4] = {bsp_v3(1, 2, 3), bsp_v3(1, 2, 3), bsp_v3(1, 2, 3), bsp_v3(1, 2, 3)};
    CHECK_EQ_INT(polygon_setup(&p, dot, 0, 4, SHAPE_NO_NORMALS), 0);
    /* a symmetric bow tie: the two lobes cancel, zero Newell area */
    bsp_vec3 bow[4] = {bsp_v3(0, 0, 0), bsp_v3(1, 1, 0), bsp_v3(1, 0, 0), bsp_v3(0, 1, 0)};
    CHECK_EQ_INT(polygon_setup(&p, bow, 0, 4, SHAPE_NO_NORMALS), 0);
}

TEST(polygon_plain_hit_and_miss)
{
    polygon_shape p;
    REQUIRE(polygon_setup(&p, square_verts, 0, 4, SHAPE_NO_NORMALS));
    double t = -1;
    bsp_ray r = ray0(0.5, 1.5, 4, 0, 0, -1);
    CHECK(polygon_intersect(&p, square_verts, NULL, &r, &t));
    CHECK(t == 4.0);
    r = ray0(0.5, 1.5, -4, 0, 0, 2); /* from below, |dir| = 2 */
    CHECK(polygon_intersect(&p, square_verts, NULL, &r, &t));
    CHECK(t == 2.0);
    r = ray0(2.5, 1.5, 4, 0, 0, -1);
    CHECK_EQ_INT(polygon_intersect(&p, square_verts, NULL, &r, &t), 0);
    r = ray0(0.5, 1.5, 4, 0, 0, 1);
    CHECK_EQ_INT(polygon_intersect(&p, square_verts, NULL, &r, &t), 0);
    /* oblique with one zero component: from (-1,1,2) along (1,0,-1): (1,1,0), t = 2 */
    r = ray0(-1, 1, 2, 1, 0, -1);
    CHECK(polygon_intersect(&p, square_verts, NULL, &r, &t));
    CHECK(t == 2.0);
    /* oblique, unnormalised (3,0,-1.5) from (-1.5,1,1): hit (0.5,1,0) at t = 2/3 */
    r = ray0(-1.5, 1, 1, 3, 0, -1.5);
    CHECK(polygon_intersect(&p, square_verts, NULL, &r, &t));
    CHECK_NEAR(t, 2.0 / 3.0, EPS);
    /* tilted square x + z = 2, y in [0,1]: from (0,0.5,0.5) along +x the
     * plane is met at x = 1.5, t = 1.5; at y = 1.5 the point is outside */
    bsp_vec3 tv[4] = {bsp_v3(2, 0, 0), bsp_v3(2, 1, 0), bsp_v3(1, 1, 1), bsp_v3(1, 0, 1)};
    REQUIRE(polygon_setup(&p, tv, 0, 4, SHAPE_NO_NORMALS));
    r = ray0(0, 0.5, 0.5, 1, 0, 0);
    CHECK(polygon_intersect(&p, tv, NULL, &r, &t));
    CHECK_NEAR(t, 1.5, EPS);
    r = ray0(0, 1.5, 0.5, 1, 0, 0);
    CHECK_EQ_INT(polygon_intersect(&p, tv, NULL, &r, &t), 0);
}

TEST(polygon_parallel_rays_miss)
{
    polygon_shape p;
    REQUIRE(polygon_setup(&p, square_verts, 0, 4, SHAPE_NO_NORMALS));
    double t = -1;
    bsp_ray r = ray0(-1, 1, 1, 1, 0, 0); /* above the plane */
    CHECK_EQ_INT(polygon_intersect(&p, square_verts, NULL, &r, &t), 0);
    r = ray0(-1, 1, 0, 1, 0, 0); /* lying in the plane, crossing the square */
    CHECK_EQ_INT(polygon_intersect(&p, square_verts, NULL, &r, &t), 0);
    r = ray0(1, 1, 0, 1, 1, 0); /* in the plane, starting inside */
    CHECK_EQ_INT(polygon_intersect(&p, square_verts, NULL, &r, &t), 0);
    r = ray0(1, 1, 0, 0, 0, 0); /* zero direction */
    CHECK_EQ_INT(polygon_intersect(&p, square_verts, NULL, &r, &t), 0);
    CHECK(t == -1);
}

TEST(polygon_origin_on_surface_interval_unnormalised)
{
    polygon_shape p;
    REQUIRE(polygon_setup(&p, square_verts, 0, 4, SHAPE_NO_NORMALS));
    double t = -1, t2 = -1;
    bsp_ray r = ray0(1, 1, 0, 0.3, 0.1, 1);
    CHECK(polygon_intersect(&p, square_verts, NULL, &r, &t));
    CHECK(t == 0.0);
    r.tmin = 1e-9;
    CHECK_EQ_INT(polygon_intersect(&p, square_verts, NULL, &r, &t), 0);

    r = ray0(0.3, 0.7, 3.3, 0.11, 0.13, -1.7);
    REQUIRE(polygon_intersect(&p, square_verts, NULL, &r, &t));
    r.tmax = t;
    CHECK(polygon_intersect(&p, square_verts, NULL, &r, &t2) && t2 == t);
    r.tmax = nextafter(t, 0);
    CHECK_EQ_INT(polygon_intersect(&p, square_verts, NULL, &r, &t2), 0);
    r.tmin = 0.5;
    r.tmax = 1e9;
    CHECK(polygon_intersect(&p, square_verts, NULL, &r, &t2) && t2 == t);
    r = ray0(0.3, 0.7, 3.3, 0.22, 0.26, -3.4);
    CHECK(polygon_intersect(&p, square_verts, NULL, &r, &t2));
    CHECK(t2 == 0.5 * t);
    /* a hit at t = 3 is excluded by tmax = 2.5 */
    r = ray0(1, 1, 3, 0, 0, -1);
    r.tmax = 2.5;
    CHECK_EQ_INT(polygon_intersect(&p, square_verts, NULL, &r, &t2), 0);
}

/* The fan triangle (v0, v1, v2) of the L-shape covers the concavity point. */
TEST(polygon_concave_l_shape)
{
    polygon_shape p;
    const bsp_vec3 *v = l_shape();
    REQUIRE(polygon_setup(&p, v, 1, 6, SHAPE_NO_NORMALS));
    double t = -1;
    /* inside the three squares of the L */
    const double in[][2] = {{0.5, 0.5}, {1.5, 0.5}, {0.5, 1.5}, {1.25, 0.75}, {0.75, 1.25}};
    for (size_t i = 0; i < sizeof in / sizeof in[0]; i++) {
        bsp_ray r = ray0(in[i][0], in[i][1], 3, 0, 0, -1);
        CHECK_MSG(polygon_intersect(&p, v, NULL, &r, &t) && t == 2.0, "L inside point %zu", i);
    }
    /* in the concavity and outside the hull */
    const double out[][2] = {{1.25, 1.25}, {1.5, 1.5}, {1.9, 1.1}, {-0.5, 1}, {2.5, 0.5}};
    for (size_t i = 0; i < sizeof out / sizeof out[0]; i++) {
        bsp_ray r = ray0(out[i][0], out[i][1], 3, 0, 0, -1);
        CHECK_MSG(!polygon_intersect(&p, v, NULL, &r, &t), "L outside point %zu", i);
    }
    /* a fan from vertex 0, (2,1) (1,1) (1,2), claims (1.25, 1.25): a fan
     * triangulation would report a hit where the polygon has none */
    triangle_shape fan;
    REQUIRE(triangle_setup(&fan, v[1], v[2], v[3], SHAPE_NO_NORMALS));
    double u, w;
    bsp_ray r = ray0(1.25, 1.25, 3, 0, 0, -1);
    CHECK(triangle_intersect(&fan, &r, &t, &u, &w));
    CHECK_EQ_INT(polygon_intersect(&p, v, NULL, &r, &t), 0);
}

/* A 24-vertex star (a gear-like concave face), tips at radius 2, notches at
 * radius 1: between the teeth at radius 1.5 is outside, along a tooth inside. */
TEST(polygon_concave_star)
{
    enum { TEETH = 12 };
    bsp_vec3 v[2 * TEETH];
    const double pi = 3.14159265358979323846;
    for (int i = 0; i < 2 * TEETH; i++) {
        double ang = pi * i / TEETH, rad = i % 2 ? 1.0 : 2.0;
        v[i] = bsp_v3(rad * cos(ang), 0.5, rad * sin(ang)); /* plane y = 0.5 */
    }
    polygon_shape p;
    REQUIRE(polygon_setup(&p, v, 0, 2 * TEETH, SHAPE_NO_NORMALS));
    CHECK(vec_near(p.normal, bsp_v3(0, -1, 0), EPS)); /* x->z is CW seen from +y */
    for (int i = 0; i < 2 * TEETH; i++) {
        double ang = pi * i / TEETH;
        bsp_ray r = ray0(1.5 * cos(ang), 3, 1.5 * sin(ang), 0, -1, 0);
        double t = -1;
        int hit = polygon_intersect(&p, v, NULL, &r, &t);
        CHECK_MSG(hit == (i % 2 == 0), "star direction %d: hit %d", i, hit);
        if (hit)
            CHECK(t == 2.5);
        r.org = bsp_v3(0.5 * cos(ang), 3, 0.5 * sin(ang)); /* the hub */
        CHECK(polygon_intersect(&p, v, NULL, &r, &t));
    }
}

/* The half-open rule partitions a shared edge: exactly one of two adjacent
 * squares claims each point of it, whichever way each square is wound. */
TEST(polygon_shared_edge_counted_once)
{
    bsp_vec3 v[8] = {bsp_v3(0, 0, 0), bsp_v3(1, 0, 0), bsp_v3(1, 1, 0), bsp_v3(0, 1, 0),
                     bsp_v3(1, 0, 0), bsp_v3(1, 1, 0), bsp_v3(2, 1, 0), bsp_v3(2, 0, 0)};
    polygon_shape a, b;
    REQUIRE(polygon_setup(&a, v, 0, 4, SHAPE_NO_NORMALS));
    REQUIRE(polygon_setup(&b, v, 4, 4, SHAPE_NO_NORMALS)); /* wound the other way */
    const double ys[] = {0.0, 0.25, 0.5, 0.75, 0.1, 1.0 / 3.0};
    for (size_t i = 0; i < sizeof ys / sizeof ys[0]; i++) {
        bsp_ray r = ray0(1, ys[i], 1, 0, 0, -1);
        double t;
        int ha = polygon_intersect(&a, v, NULL, &r, &t);
        int hb = polygon_intersect(&b, v, NULL, &r, &t);
        CHECK_MSG(ha + hb == 1, "y = %g: %d + %d", ys[i], ha, hb);
    }
    /* a slanted shared edge from (0,0) to (1,3) between two quads */
    bsp_vec3 s[8] = {bsp_v3(-1, 0, 0), bsp_v3(0, 0, 0), bsp_v3(1, 3, 0), bsp_v3(-1, 3, 0),
                     bsp_v3(2, 0, 0), bsp_v3(2, 3, 0), bsp_v3(1, 3, 0), bsp_v3(0, 0, 0)};
    REQUIRE(polygon_setup(&a, s, 0, 4, SHAPE_NO_NORMALS));
    REQUIRE(polygon_setup(&b, s, 4, 4, SHAPE_NO_NORMALS));
    for (int i = 1; i < 30; i++) {
        double y = 0.1 * i, x = y / 3.0;
        bsp_ray r = ray0(x, y, 1, 0, 0, -1);
        double t;
        int ha = polygon_intersect(&a, s, NULL, &r, &t);
        int hb = polygon_intersect(&b, s, NULL, &r, &t);
        CHECK_MSG(ha + hb == 1, "slanted y = %g: %d + %d", y, ha, hb);
    }
}

TEST(polygon_edge_rule)
{
    /* the square [0,2]^2: left and bottom edges belong, right and top don't */
    polygon_shape p;
    REQUIRE(polygon_setup(&p, square_verts, 0, 4, SHAPE_NO_NORMALS));
    double t;
    struct {
        double x, y;
        int hit;
    } cases[] = {{0, 1, 1}, {1, 0, 1}, {2, 1, 0}, {1, 2, 0}, {0, 0, 1}, {2, 2, 0}};
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        bsp_ray r = ray0(cases[i].x, cases[i].y, 1, 0, 0, -1);
        CHECK_MSG(polygon_intersect(&p, square_verts, NULL, &r, &t) == cases[i].hit,
                  "edge point (%g, %g)", cases[i].x, cases[i].y);
    }
}

/* The crossing test against an exact reference: random polygons (often
 * self-intersecting, with horizontal edges and shared vertex heights) on an
 * integer grid in the plane z = 0, probed on a quarter grid, so points lie on
 * vertices, on edges and on the lines through vertices. The reference counts
 * the crossings of the same half-open rule in integer arithmetic (x < x_cross
 * as a cross-multiplied comparison, no division); on these inputs every
 * abscissa the kernel computes is exact, so the two must agree point for
 * point. */
TEST(polygon_crossing_rule_matches_exact_reference)
{
    enum { MAXV = 12 };
    uint64_t rng = 12345; /* its own stream: the shared one stays as the other tests expect */
    int tested = 0;
    for (int poly = 0; poly < 400; poly++) {
        int n = 4 + poly % (MAXV - 3);
        long xs[MAXV], ys[MAXV];
        bsp_vec3 v[MAXV];
        for (int i = 0; i < n; i++) {
            xs[i] = (long)floor(rnd_from(&rng, 0, 9)); /* 0..8 */
            ys[i] = (long)floor(rnd_from(&rng, 0, 9));
            v[i] = bsp_v3((double)xs[i], (double)ys[i], 0.0);
        }
        polygon_shape p;
        if (!polygon_setup(&p, v, 0, (uint32_t)n, SHAPE_NO_NORMALS) || p.axis_u != 0 ||
            p.axis_v != 1)
            continue; /* no area (or not dropped along z): nothing to probe */
        tested++;
        for (int qy = -1; qy <= 33; qy++) {
            for (int qx = -1; qx <= 33; qx++) {
                /* the probe (qx/4, qy/4); the reference works on 4x coordinates */
                int inside = 0;
                for (int i = 0, j = n - 1; i < n; j = i++) {
                    long ay = 4 * ys[i], by = 4 * ys[j];
                    if ((ay > qy) == (by > qy))
                        continue;
                    int lo = ay < by ? i : j, hi = lo == i ? j : i;
                    long dy = 4 * (ys[hi] - ys[lo]), dx = 4 * (xs[hi] - xs[lo]);
                    if ((qx - 4 * xs[lo]) * dy < (qy - 4 * ys[lo]) * dx)
                        inside ^= 1;
                }
                bsp_ray r = ray0(qx / 4.0, qy / 4.0, 1, 0, 0, -1);
                double t = -1;
                int hit = polygon_intersect(&p, v, NULL, &r, &t);
                CHECK_MSG(hit == inside, "polygon %d point (%g, %g): kernel %d, exact %d", poly,
                          qx / 4.0, qy / 4.0, hit, inside);
                if (hit)
                    CHECK(t == 1.0);
            }
        }
    }
    CHECK(tested > 300);

    /* Off the grid the abscissa rounds; within rounding of an edge the
     * watertight test decides (isect.h). Either way a point of an edge two
     * polygons share belongs to exactly one of them: a convex polygon of
     * random vertices on a circle, cut by the chord from vertex 0 to vertex
     * m into two, probed on and one ulp either side of points of the chord,
     * by rays along -z and oblique ones. */
    int near_edges = 0;
    for (int poly = 0; poly < 200; poly++) {
        int n = 6 + poly % (MAXV - 5), m = n / 2;
        bsp_vec3 v[MAXV + 1];
        for (int i = 0; i < n; i++) {
            double a = 6.283185307179586 * (i + rnd_from(&rng, 0.1, 0.9)) / n;
            v[i] = bsp_v3(3 * cos(a), 3 * sin(a), 0.0);
        }
        v[n] = v[0];
        polygon_shape pa, pb;
        REQUIRE(polygon_setup(&pa, v, 0, (uint32_t)m + 1, SHAPE_NO_NORMALS));
        REQUIRE(polygon_setup(&pb, v, (uint32_t)m, (uint32_t)(n - m + 1), SHAPE_NO_NORMALS));
        const bsp_vec3 *a = &v[0], *b = &v[m];
        for (int k = 0; k < 10; k++) {
            double py = a->y + (b->y - a->y) * rnd_from(&rng, 0.05, 0.95);
            const bsp_vec3 *lo = a->y < b->y ? a : b, *hi = lo == a ? b : a;
            double xe = lo->x + (py - lo->y) * (hi->x - lo->x) / (hi->y - lo->y);
            const double probes[] = {xe, nextafter(xe, -INFINITY), nextafter(xe, INFINITY)};
            for (int q = 0; q < 3; q++) {
                double sx = k & 1 ? rnd_from(&rng, -0.7, 0.7) : 0.0;
                double sy = k & 2 ? rnd_from(&rng, -0.7, 0.7) : 0.0;
                bsp_ray r = ray0(probes[q] - sx, py - sy, 1, sx, sy, -1);
                double t;
                int ha = polygon_intersect(&pa, v, NULL, &r, &t);
                int hb = polygon_intersect(&pb, v, NULL, &r, &t);
                CHECK_MSG(ha + hb == 1, "polygon %d probe %d.%d: inside %d and %d of the halves",
                          poly, k, q, ha, hb);
                near_edges++;
            }
        }
    }
    CHECK(near_edges == 6000);
}

TEST(polygon_bounds_exact)
{
    polygon_shape p;
    const bsp_vec3 *v = l_shape();
    REQUIRE(polygon_setup(&p, v, 1, 6, SHAPE_NO_NORMALS));
    bsp_box b = polygon_bounds(&p, v);
    CHECK(vec_eq(b.lo, bsp_v3(0, 0, 1)));
    CHECK(vec_eq(b.hi, bsp_v3(2, 2, 1)));
    bsp_vec3 tv[4] = {bsp_v3(2, 0, 0), bsp_v3(2, 1, 0), bsp_v3(1, 1, 1), bsp_v3(1, 0, 1)};
    REQUIRE(polygon_setup(&p, tv, 0, 4, SHAPE_NO_NORMALS));
    b = polygon_bounds(&p, tv);
    CHECK(vec_eq(b.lo, bsp_v3(1, 0, 0)));
    CHECK(vec_eq(b.hi, bsp_v3(2, 1, 1)));
}

TEST(polygon_shading_normal_mean_value)
{
    bsp_vec3 pool[5] = {bsp_v3(5, 5, 5), bsp_v3(0, 0, 1), bsp_v3(1, 0, 1), bsp_v3(0, 1, 1),
                        bsp_v3(-1, -1, 2)};
    polygon_shape p;
    REQUIRE(polygon_setup(&p, square_verts, 0, 4, 1));
    /* at each vertex: that vertex's normal, normalised */
    for (int i = 0; i < 4; i++) {
        bsp_vec3 n = polygon_shading_normal(&p, square_verts, pool, square_verts[i]);
        CHECK_MSG(vec_near(n, v3_normalize(pool[1 + i]), EPS), "vertex %d", i);
    }
    /* at the centre of the square all weights are equal: the normalised mean
     * (0,0,5)/4 -> (0,0,1) */
    bsp_vec3 n = polygon_shading_normal(&p, square_verts, pool, bsp_v3(1, 1, 0));
    CHECK(vec_near(n, bsp_v3(0, 0, 1), EPS));
    /* mid-edge between vertices 0 and 1: mean of (0,0,1) and (1,0,1) */
    n = polygon_shading_normal(&p, square_verts, pool, bsp_v3(1, 0, 0));
    CHECK(vec_near(n, v3_normalize(bsp_v3(0.5, 0, 1)), EPS));
    /* a quarter along edge 1 -> 2 (from (2,0) to (2,2)): 3/4 n1 + 1/4 n2 */
    n = polygon_shading_normal(&p, square_verts, pool, bsp_v3(2, 0.5, 0));
    CHECK(vec_near(n, v3_normalize(bsp_v3(0.75, 0.25, 1)), EPS));
    /* any interior point: unit, finite, on the +z side of these normals */
    for (int i = 0; i < 200; i++) {
        bsp_vec3 q = bsp_v3(rnd(0.01, 1.99), rnd(0.01, 1.99), 0);
        n = polygon_shading_normal(&p, square_verts, pool, q);
        CHECK(v3_is_finite(n));
        CHECK_NEAR(v3_length(n), 1.0, EPS);
        CHECK(n.z > 0);
    }
    /* no vertex normals: the face normal */
    REQUIRE(polygon_setup(&p, square_verts, 0, 4, SHAPE_NO_NORMALS));
    CHECK(vec_eq(polygon_shading_normal(&p, square_verts, pool, bsp_v3(0.3, 0.4, 0)),
                 bsp_v3(0, 0, 1)));
}

TEST(polygon_shading_normal_continuous_at_edges)
{
    /* Within rounding of an edge the coordinates' weights blow up; the
     * normal must still be the edge's linear blend of its ends' normals, not
     * the flat face normal (which r nr + dot cancelling to 0 used to give
     * within about 5e-9 of an edge of this square). */
    bsp_vec3 pool[5] = {bsp_v3(5, 5, 5), bsp_v3(0, 0, 1), bsp_v3(1, 0, 1), bsp_v3(0, 1, 1),
                        bsp_v3(-1, -1, 2)};
    polygon_shape p;
    REQUIRE(polygon_setup(&p, square_verts, 0, 4, 1));
    const double gaps[] = {1e-6, 1e-9, 1e-12, 1e-15, 1e-300, 0.0};
    int checked = 0;
    for (int e = 0; e < 4; e++) {
        bsp_vec3 a = square_verts[e], b = square_verts[(e + 1) % 4];
        bsp_vec3 inward = bsp_v3(1.0 - 0.5 * (a.x + b.x), 1.0 - 0.5 * (a.y + b.y), 0.0);
        for (int k = 1; k < 64; k++) {
            double s = k / 64.0;
            bsp_vec3 on = v3_add(v3_scale(a, 1.0 - s), v3_scale(b, s)); /* exact: 1/64ths */
            bsp_vec3 want = v3_normalize(v3_add(v3_scale(pool[1 + e], 1.0 - s),
                                                v3_scale(pool[1 + (e + 1) % 4], s)));
            for (size_t g = 0; g < sizeof gaps / sizeof gaps[0]; g++) {
                bsp_vec3 q = v3_madd(on, inward, gaps[g]);
                if (gaps[g] == 0.0) { /* the next double inside */
                    q.x = nextafter(on.x, on.x + inward.x);
                    q.y = nextafter(on.y, on.y + inward.y);
                }
                bsp_vec3 n = polygon_shading_normal(&p, square_verts, pool, q);
                CHECK_MSG(vec_near(n, want, 1e-5), "edge %d at %g, %g inside: (%g, %g, %g)", e,
                          s, gaps[g], n.x, n.y, n.z);
                checked++;
            }
        }
    }
    CHECK_EQ_INT(checked, 4 * 63 * 6);
}

TEST(polygon_shading_normal_concave_and_linear)
{
    /* mean value coordinates reproduce linear functions: vertex normals that
     * are a linear function of position, N(x, y) = (x, y, 4), interpolate to
     * exactly that function, also inside the concave L */
    const bsp_vec3 *v = l_shape();
    bsp_vec3 pool[8];
    for (int i = 0; i < 8; i++)
        pool[i] = bsp_v3(v[i].x, v[i].y, 4);
    polygon_shape p;
    REQUIRE(polygon_setup(&p, v, 1, 6, 1));
    const double pts[][2] = {{0.5, 0.5}, {1.5, 0.5}, {0.5, 1.5}, {0.9, 0.9}, {0.1, 1.9}};
    for (size_t i = 0; i < sizeof pts / sizeof pts[0]; i++) {
        bsp_vec3 n = polygon_shading_normal(&p, v, pool, bsp_v3(pts[i][0], pts[i][1], 1));
        bsp_vec3 want = v3_normalize(bsp_v3(pts[i][0], pts[i][1], 4));
        CHECK_MSG(vec_near(n, want, 1e-12), "L point %zu", i);
    }
    /* at the reflex vertex (1,1): its own normal */
    bsp_vec3 n = polygon_shading_normal(&p, v, pool, bsp_v3(1, 1, 1));
    CHECK(vec_near(n, v3_normalize(bsp_v3(1, 1, 4)), EPS));
}

/* ======================================================================== */
/* cone / cylinder                                                          */
/* ======================================================================== */

/* radius 1 along +z from z = 0 to z = 2 */
static cone_shape z_cylinder(void)
{
    cone_shape c;
    REQUIRE(cone_setup(&c, bsp_v3(0, 0, 0), 1.0, bsp_v3(0, 0, 2), 1.0));
    return c;
}

/* base radius 1 at z = 0, apex radius 0 at z = 2: slope -1/2 */
static cone_shape z_cone(void)
{
    cone_shape c;
    REQUIRE(cone_setup(&c, bsp_v3(0, 0, 0), 1.0, bsp_v3(0, 0, 2), 0.0));
    return c;
}

TEST(cone_setup_and_degenerate)
{
    cone_shape c = z_cone();
    CHECK(vec_eq(c.axis, bsp_v3(0, 0, 1)));
    CHECK(c.length == 2.0 && c.base_radius == 1.0 && c.apex_radius == 0.0);
    CHECK(c.slope == -0.5 && c.inside_only == 0);
    REQUIRE(cone_setup(&c, bsp_v3(1, 1, 1), -0.5, bsp_v3(1, 4, 5), -1.5));
    CHECK(c.inside_only == 1 && c.base_radius == 0.5 && c.apex_radius == 1.5);
    CHECK(c.length == 5.0 && vec_near(c.axis, bsp_v3(0, 0.6, 0.8), 1e-16) && c.slope == 0.2);
    REQUIRE(cone_setup(&c, bsp_v3(1, 1, 1), 0.0, bsp_v3(1, 4, 5), -1.5));
    CHECK(c.inside_only == 1 && c.base_radius == 0.0);
    CHECK_EQ_INT(cone_setup(&c, bsp_v3(1, 2, 3), 1.0, bsp_v3(1, 2, 3), 2.0), 0);
    CHECK_EQ_INT(cone_setup(&c, bsp_v3(1, 2, 3), 0.0, bsp_v3(1, 2, 4), 0.0), 0);
    CHECK_EQ_INT(cone_setup(&c, bsp_v3(1, 2, 3), 0.0, bsp_v3(1, 2, 3), 0.0), 0);
}

TEST(cylinder_hits)
{
    cone_shape c = z_cylinder();
    double t = -1;
    /* from (-3,0,1) along +x: enters at x = -1, t = 2 */
    bsp_ray r = ray0(-3, 0, 1, 1, 0, 0);
    CHECK(cone_intersect(&c, &r, &t));
    CHECK(t == 2.0);
    /* unnormalised: |dir| = 4 gives t = 2 / 4 */
    r = ray0(-3, 0, 1, 4, 0, 0);
    CHECK(cone_intersect(&c, &r, &t));
    CHECK(t == 0.5);
    /* misses: beside, above the top rim, below the base */
    r = ray0(-3, 1.5, 1, 1, 0, 0);
    CHECK_EQ_INT(cone_intersect(&c, &r, &t), 0);
    r = ray0(-3, 0, 2.5, 1, 0, 0);
    CHECK_EQ_INT(cone_intersect(&c, &r, &t), 0);
    r = ray0(-3, 0, -0.5, 1, 0, 0);
    CHECK_EQ_INT(cone_intersect(&c, &r, &t), 0);
    /* an oblique ray through the open top: from (0,0,3) along (1,0,-1): the
     * wall x = 1 at z = 2 (the rim), t = 1 */
    r = ray0(0, 0, 3, 1, 0, -1);
    CHECK(cone_intersect(&c, &r, &t));
    CHECK(t == 1.0);
    /* from (0,0,4) along (1,0,-1): the wall's line x = 1 is met at z = 3,
     * above the top rim, and x = -1 only behind the origin: a miss */
    r = ray0(0, 0, 4, 1, 0, -1);
    CHECK_EQ_INT(cone_intersect(&c, &r, &t), 0);
    /* tangent line x = 1: a double root at the tangent point, t = 3 */
    r = ray0(1, -3, 1, 0, 1, 0);
    CHECK(cone_intersect(&c, &r, &t));
    CHECK(t == 3.0);
}

TEST(cylinder_inside_on_surface_parallel)
{
    cone_shape c = z_cylinder();
    double t = -1;
    /* origin on the axis: far side only, t = 1 */
    bsp_ray r = ray0(0, 0, 1, 1, 0, 0);
    CHECK(cone_intersect(&c, &r, &t));
    CHECK(t == 1.0);
    r = ray0(0.5, 0, 1, -1, 0, 0);
    CHECK(cone_intersect(&c, &r, &t));
    CHECK(t == 1.5);
    /* origin on the wall heading in: t = 0, then the far wall at t = 2 */
    r = ray0(1, 0, 1, -1, 0, 0);
    CHECK(cone_intersect(&c, &r, &t));
    CHECK(t == 0.0);
    r.tmin = 1e-9;
    CHECK(cone_intersect(&c, &r, &t));
    CHECK(t == 2.0);
    /* parallel to the axis, inside, outside and lying on the wall: miss */
    r = ray0(0.5, 0, -1, 0, 0, 1);
    CHECK_EQ_INT(cone_intersect(&c, &r, &t), 0);
    r = ray0(3, 0, -1, 0, 0, 1);
    CHECK_EQ_INT(cone_intersect(&c, &r, &t), 0);
    r = ray0(1, 0, -1, 0, 0, 1);
    CHECK_EQ_INT(cone_intersect(&c, &r, &t), 0);
    /* zero direction */
    r = ray0(0.5, 0, 1, 0, 0, 0);
    CHECK_EQ_INT(cone_intersect(&c, &r, &t), 0);
    CHECK(t == 2.0);
}

TEST(cone_hits_parallel_and_generator)
{
    cone_shape c = z_cone();
    double t = -1;
    /* from (-3,0,1) along +x: radius 0.5 at z = 1, enters at x = -0.5, t = 2.5 */
    bsp_ray r = ray0(-3, 0, 1, 1, 0, 0);
    CHECK(cone_intersect(&c, &r, &t));
    CHECK(t == 2.5);
    /* parallel to the axis inside the base: hits once, where r(z) = 0.5,
     * z = 1, t = 2 (the other root, z = 3, is on the mirrored nappe) */
    r = ray0(0.5, 0, -1, 0, 0, 1);
    CHECK(cone_intersect(&c, &r, &t));
    CHECK(t == 2.0);
    r.tmin = 2.5;
    CHECK_EQ_INT(cone_intersect(&c, &r, &t), 0);
    /* the same from inside the cone (origin at z = 0.25, r = 0.875) */
    r = ray0(0.5, 0, 0.25, 0, 0, 1);
    CHECK(cone_intersect(&c, &r, &t));
    CHECK(t == 0.75);
    /* and going down from above the apex: the mirrored nappe above the apex
     * (z = 3) must not count; the cone is met at z = 1, t = 4 */
    r = ray0(0.5, 0, 5, 0, 0, -1);
    CHECK(cone_intersect(&c, &r, &t));
    CHECK(t == 4.0);
    /* parallel to the axis outside the base radius: miss */
    r = ray0(1.5, 0, -1, 0, 0, 1);
    CHECK_EQ_INT(cone_intersect(&c, &r, &t), 0);
    /* parallel to a generator (direction (1,0,2), slope -1/2) leaves a
     * linear equation: x = -1 + s, z = -1 + 2s, r(z) = 1.5 - s; x < 0 needs
     * 1 - s = 1.5 - s (never), x > 0 needs s - 1 = 1.5 - s: s = 1.25 */
    r = ray0(-1, 0, -1, 1, 0, 2);
    CHECK(cone_intersect(&c, &r, &t));
    CHECK(t == 1.25);
    /* a ray lying on the cone's surface (along a generator): miss */
    r = ray0(1, 0, 0, -1, 0, 2);
    CHECK_EQ_INT(cone_intersect(&c, &r, &t), 0);
    /* through the apex along the axis: the apex point (r = 0) hits at t = 1 */
    r = ray0(0, 0, 3, 0, 0, -1);
    CHECK(cone_intersect(&c, &r, &t));
    CHECK(t == 1.0);
}

TEST(cone_inverted_and_truncated)
{
    /* apex below the base: base radius 0.5 at z = 4, apex radius 1.5 at z = 2
     * (slope +1/2 going down); from (-5,0,3) along +x: r(z=3) = 1, t = 4 */
    cone_shape c;
    REQUIRE(cone_setup(&c, bsp_v3(0, 0, 4), 0.5, bsp_v3(0, 0, 2), 1.5));
    double t = -1;
    bsp_ray r = ray0(-5, 0, 3, 1, 0, 0);
    CHECK(cone_intersect(&c, &r, &t));
    CHECK(t == 4.0);
    r.tmin = 4.5; /* far wall at x = 1, t = 6 */
    CHECK(cone_intersect(&c, &r, &t));
    CHECK(t == 6.0);
    /* outside the truncation: z = 1 is past the apex end */
    r = ray0(-5, 0, 1, 1, 0, 0);
    CHECK_EQ_INT(cone_intersect(&c, &r, &t), 0);
}

TEST(cone_tilted_and_interval)
{
    /* a cylinder of radius 1 along (1,1,0) from the origin to (2,2,0): the
     * vertical line through (1,1) meets it at z = +1 and -1; from (1,1,5) down, t = 4 */
    cone_shape c;
    REQUIRE(cone_setup(&c, bsp_v3(0, 0, 0), 1.0, bsp_v3(2, 2, 0), 1.0));
    double t = -1, t2 = -1;
    bsp_ray r = ray0(1, 1, 5, 0, 0, -1);
    CHECK(cone_intersect(&c, &r, &t));
    CHECK_NEAR(t, 4.0, EPS);
    r.tmin = 5.0;
    CHECK(cone_intersect(&c, &r, &t2));
    CHECK_NEAR(t2, 6.0, EPS);
    /* bit-identical under interval changes */
    r = ray0(-1.3, 2.9, 0.7, 0.8, -1.1, -0.15);
    REQUIRE(cone_intersect(&c, &r, &t));
    r.tmax = t;
    CHECK(cone_intersect(&c, &r, &t2) && t2 == t);
    r.tmax = nextafter(t, 0);
    CHECK_EQ_INT(cone_intersect(&c, &r, &t2), 0);
    r.tmax = INFINITY;
    r.tmin = 0.25 * t;
    CHECK(cone_intersect(&c, &r, &t2) && t2 == t);
    /* doubling the direction halves t */
    r = ray0(-1.3, 2.9, 0.7, 1.6, -2.2, -0.3);
    CHECK(cone_intersect(&c, &r, &t2));
    CHECK(t2 == 0.5 * t);
    /* excluded beyond tmax */
    r = ray0(1, 1, 5, 0, 0, -1);
    r.tmax = 3.9;
    CHECK_EQ_INT(cone_intersect(&c, &r, &t2), 0);
}

/* An orthonormal pair perpendicular to the unit vector A. */
static void perp_basis(bsp_vec3 a, bsp_vec3 *u, bsp_vec3 *w)
{
    bsp_vec3 h = fabs(a.x) < 0.6 ? bsp_v3(1, 0, 0) : bsp_v3(0, 1, 0);
    *u = v3_normalize(v3_cross(a, h));
    *w = v3_cross(a, *u);
}

TEST(cone_bounds_tilted_vs_sampling)
{
    cone_shape c;
    bsp_vec3 base = bsp_v3(1, 2, 3), apex = bsp_v3(2, 4, 7);
    REQUIRE(cone_setup(&c, base, 1.0, apex, 0.5));
    bsp_box b = cone_bounds(&c);
    bsp_vec3 u, w;
    perp_basis(c.axis, &u, &w);
    bsp_box s = box_empty();
    const int n = 100000;
    for (int i = 0; i < n; i++) {
        double ang = 2.0 * 3.14159265358979323846 * i / n;
        bsp_vec3 dir = v3_add(v3_scale(u, cos(ang)), v3_scale(w, sin(ang)));
        s = box_add_point(s, v3_madd(base, dir, 1.0));
        s = box_add_point(s, v3_madd(apex, dir, 0.5));
    }
    for (int k = 0; k < 3; k++) {
        CHECK_MSG(b.lo.v[k] <= s.lo.v[k] + 1e-12 && b.lo.v[k] >= s.lo.v[k] - 1e-8,
                  "lo[%d] %.17g vs sampled %.17g", k, b.lo.v[k], s.lo.v[k]);
        CHECK_MSG(b.hi.v[k] >= s.hi.v[k] - 1e-12 && b.hi.v[k] <= s.hi.v[k] + 1e-8,
                  "hi[%d] %.17g vs sampled %.17g", k, b.hi.v[k], s.hi.v[k]);
    }
    /* axis-aligned: exact */
    cone_shape z = z_cone();
    b = cone_bounds(&z);
    CHECK(vec_eq(b.lo, bsp_v3(-1, -1, 0)) && vec_eq(b.hi, bsp_v3(1, 1, 2)));
    /* along x with a zero base radius: the apex disc alone sets y and z */
    REQUIRE(cone_setup(&c, bsp_v3(-1, 0, 0), 0.0, bsp_v3(3, 0, 0), 2.0));
    b = cone_bounds(&c);
    CHECK(vec_eq(b.lo, bsp_v3(-1, -2, -2)) && vec_eq(b.hi, bsp_v3(3, 2, 2)));
}

TEST(cone_normals_unit_outward)
{
    cone_shape cyl = z_cylinder();
    CHECK(vec_near(cone_normal(&cyl, bsp_v3(1, 0, 1)), bsp_v3(1, 0, 0), EPS));
    CHECK(vec_near(cone_normal(&cyl, bsp_v3(0, -1, 0.5)), bsp_v3(0, -1, 0), EPS));
    /* the 45-degree cone r = 1 - z: at (0.5, 0, 0.5) the normal is (1,0,1)/sqrt2 */
    cone_shape c;
    REQUIRE(cone_setup(&c, bsp_v3(0, 0, 0), 1.0, bsp_v3(0, 0, 1), 0.0));
    CHECK(vec_near(cone_normal(&c, bsp_v3(0.5, 0, 0.5)),
                   bsp_v3(1 / sqrt(2.0), 0, 1 / sqrt(2.0)), EPS));
    CHECK(vec_near(cone_normal(&c, bsp_v3(0, -0.25, 0.75)),
                   bsp_v3(0, -1 / sqrt(2.0), 1 / sqrt(2.0)), EPS));
    /* a widening cone (slope +1): the normal tilts towards the base */
    REQUIRE(cone_setup(&c, bsp_v3(0, 0, 0), 0.0, bsp_v3(0, 0, 1), 1.0));
    CHECK(vec_near(cone_normal(&c, bsp_v3(0, 0.5, 0.5)),
                   bsp_v3(0, 1 / sqrt(2.0), -1 / sqrt(2.0)), EPS));
    /* random hit points on a tilted cone: unit, perpendicular to the surface
     * (the generator through the point) and pointing away from the axis */
    REQUIRE(cone_setup(&c, bsp_v3(1, 2, 3), 1.0, bsp_v3(2, 4, 7), 0.5));
    bsp_vec3 apex = bsp_v3(2, 4, 7);
    int hits = 0;
    for (int i = 0; i < 500; i++) {
        bsp_ray r = ray0(rnd(-3, 6), rnd(-2, 8), rnd(-1, 10), rnd(-1, 1), rnd(-1, 1), rnd(-1, 1));
        r.dir = v3_sub(v3_add(bsp_v3(1.5, 3, 5), bsp_v3(rnd(-1, 1), rnd(-1, 1), rnd(-1, 1))),
                       r.org);
        double t;
        if (!cone_intersect(&c, &r, &t))
            continue;
        hits++;
        bsp_vec3 p = ray_at(&r, t);
        bsp_vec3 n = cone_normal(&c, p);
        CHECK_NEAR(v3_length(n), 1.0, EPS);
        double h = v3_dot(v3_sub(p, c.base), c.axis);
        bsp_vec3 radial = v3_sub(v3_sub(p, c.base), v3_scale(c.axis, h));
        CHECK_NEAR(v3_length(radial), 1.0 - 0.5 * h / c.length, 1e-9);
        CHECK(v3_dot(n, radial) > 0);
        /* the rim point on the base disc in the same radial direction, and
         * the apex rim point: the generator through p joins them */
        bsp_vec3 ru = v3_normalize(radial);
        bsp_vec3 gen = v3_sub(v3_madd(apex, ru, 0.5), v3_madd(c.base, ru, 1.0));
        CHECK_NEAR(v3_dot(n, v3_normalize(gen)), 0.0, 1e-9);
    }
    CHECK(hits > 50);
}
