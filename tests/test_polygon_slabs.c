/*
 * test_polygon_slabs.c — the slabs of polygons with many vertices
 * (src/geom/polygon_slabs.c) against the walk of every edge, which stays the
 * reference: the same inside/outside answer and the same hit t, bit for bit,
 * on random concave, self-intersecting and grid polygons, at points on
 * vertices, on edges, on the slabs' bounds and outside; the budget that
 * keeps zigzags on the walk; and the test units of the cost model, worked
 * out by hand.
 */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>

#include "geom/isect.h"
#include "geom/shapes.h"
#include "geom/vec.h"
#include "harness.h"

static unsigned long long rng_state = 0x9e3779b97f4a7c15ULL;

static double urand(void)
{
    return harness_rnd(&rng_state);
}

static uint32_t irand(uint32_t n)
{
    return (uint32_t)(urand() * n) % n;
}

/* The vertices of one random polygon of N vertices in the plane z = 0 (or,
 * when TILT, a plane whose dominant axis is x or y), by SHAPE: 0 star
 * (concave, sorted angles), 1 random points (self-intersecting), 2 points on
 * an integer grid (shared v values, horizontal and vertical edges), 3 a gear
 * of rectangular teeth. */
static void random_polygon(bsp_vec3 *v, uint32_t n, int shape, int tilt)
{
    for (uint32_t i = 0; i < n; i++) {
        double a = 0.0, b = 0.0;
        switch (shape) {
        case 0: {
            double ang = 2.0 * 3.14159265358979 * (i + 0.5 * urand()) / n, r = 0.3 + urand();
            a = r * cos(ang);
            b = r * sin(ang);
            break;
        }
        case 1:
            a = urand() * 2.0 - 1.0;
            b = urand() * 2.0 - 1.0;
            break;
        case 2:
            a = (double)irand(7);
            b = (double)irand(7);
            break;
        default: { /* teeth: (inner, outer) radius pairs at the same angle */
            double ang = 2.0 * 3.14159265358979 * (double)(i / 2) / (double)((n + 1) / 2);
            double r = ((i / 2) % 2 == 0) == (i % 2 == 0) ? 1.0 : 1.25;
            a = r * cos(ang);
            b = r * sin(ang);
            break;
        }
        }
        v[i] = tilt == 0   ? bsp_v3(a, b, 0.0)
               : tilt == 1 ? bsp_v3(0.01 * a, a, b)
                           : bsp_v3(a, 0.02 * b, b);
    }
}

/* Query points of polygon P: on and between its vertices' coordinates, on
 * edge midpoints, at random, and beyond its extent. */
static void query_point(const bsp_vec3 *vs, uint32_t n, int au, int av, uint32_t q, double *px,
                        double *py)
{
    const bsp_vec3 a = vs[irand(n)], b = vs[irand(n)];
    switch (q % 6) {
    case 0: /* a vertex */
        *px = a.v[au];
        *py = a.v[av];
        break;
    case 1: /* one vertex's v, another's u */
        *px = b.v[au];
        *py = a.v[av];
        break;
    case 2: { /* an edge's midpoint */
        uint32_t i = irand(n);
        const bsp_vec3 c = vs[i], d = vs[(i + 1) % n];
        *px = 0.5 * (c.v[au] + d.v[au]);
        *py = 0.5 * (c.v[av] + d.v[av]);
        break;
    }
    case 3: /* a vertex's v, random u */
        *px = a.v[au] + (urand() - 0.5);
        *py = a.v[av];
        break;
    case 4: /* beyond the extent (on some axis) */
        *px = a.v[au] + 5.0 * (urand() - 0.5);
        *py = (urand() < 0.5 ? -1.0 : 1.0) * (9.0 + urand());
        break;
    default:
        *px = a.v[au] + (urand() - 0.5);
        *py = a.v[av] + (urand() - 0.5);
        break;
    }
}

TEST(polygon_slabs_match_the_walk_of_every_edge)
{
    enum { POLYGONS = 2000, QUERIES = 200, MAXN = 160 };
    static bsp_vec3 v[MAXN];
    size_t with_slabs = 0, without = 0, inside = 0, outside = 0, hits = 0, mismatches = 0;
    size_t near = 0;
    for (int pi = 0; pi < POLYGONS; pi++) {
        polygon_slab_pool pool = {0};
        int shape = pi % 4, tilt = (pi / 4) % 3;
        uint32_t n = POLYGON_SLAB_MIN + irand(shape == 1 ? 40 : MAXN - POLYGON_SLAB_MIN + 1);
        random_polygon(v, n, shape, tilt);
        polygon_shape p;
        if (!polygon_setup(&p, v, 0, n, SHAPE_NO_NORMALS))
            continue; /* a degenerate grid polygon */
        /* other polygons before it in the pool: indices must be absolute */
        polygon_shape q0 = p;
        REQUIRE(polygon_slabs_build(&q0, v, &pool));
        REQUIRE(polygon_slabs_build(&p, v, &pool));
        if (p.nslabs == 0) {
            without++;
        } else {
            with_slabs++;
            REQUIRE(p.slab_first == q0.nslabs);
        }
        const int au = p.axis_u, av = p.axis_v, aw = 3 - au - av;
        for (uint32_t qi = 0; qi < QUERIES; qi++) {
            double px, py;
            query_point(v, n, au, av, qi, &px, &py);
            /* with a margin, also the "near" bit (POLYGON_NEAR) */
            const double delta = qi % 3 == 0 ? 0.0 : qi % 3 == 1 ? 1e-9 : 0.01 * (qi % 7);
            int walk = polygon_contains_2d(v, n, au, av, px, py, delta);
            near += (walk & POLYGON_NEAR) != 0;
            if (p.nslabs) {
                int slab = polygon_contains_slabs(&p, &pool, px, py, delta);
                if (slab != walk && mismatches++ < 5)
                    CHECK_MSG(
                        0, "polygon %d (shape %d, n %u), point (%.17g, %.17g): slabs %d, walk %d",
                        pi, shape, n, px, py, slab, walk);
            }
            walk &= POLYGON_INSIDE;
            inside += walk != 0;
            outside += walk == 0;
            /* and through the ray test: a ray along the dropped axis */
            bsp_ray r;
            r.org = bsp_v3(0, 0, 0);
            r.org.v[au] = px;
            r.org.v[av] = py;
            r.org.v[aw] = 3.0;
            r.dir = bsp_v3(0, 0, 0);
            r.dir.v[aw] = -1.0;
            r.dir.v[au] = 0.001 * (urand() - 0.5);
            r.tmin = 0.0;
            r.tmax = INFINITY;
            double ta = -1.0, tb = -2.0;
            int ha = polygon_intersect(&p, v, &pool, &r, &ta),
                hb = polygon_intersect(&p, v, NULL, &r, &tb);
            hits += ha != 0;
            if ((ha != hb || (ha && ta != tb)) && mismatches++ < 5)
                CHECK_MSG(0, "polygon %d ray %u: with slabs %d (t %.17g), without %d (t %.17g)", pi,
                          qi, ha, ta, hb, tb);
        }
        polygon_slab_pool_free(&pool);
    }
    CHECK_MSG(mismatches == 0, "%zu mismatches", mismatches);
    /* not vacuous: most polygons have slabs, and both answers occur often */
    CHECK_MSG(with_slabs > POLYGONS / 2, "%zu polygons with slabs, %zu without", with_slabs,
              without);
    CHECK_MSG(inside > 50000 && outside > 50000 && hits > 50000,
              "inside %zu, outside %zu, hits %zu", inside, outside, hits);
    CHECK_MSG(near > 20000, "near %zu", near);
}

/* A zigzag whose every edge spans most slabs: more than POLYGON_SLAB_BUDGET
 * entries per vertex, so it keeps the walk, and still answers. */
TEST(polygon_slabs_budget_keeps_zigzags_on_the_walk)
{
    enum { N = 200 };
    static bsp_vec3 v[N];
    /* vertex i at height +-i: edge (i-1, i) spans about 2i slabs, N^2 in all */
    for (uint32_t i = 0; i < N; i++)
        v[i] = bsp_v3((double)i, (i % 2 ? 1.0 : -1.0) * (double)i, 0.0);
    polygon_shape p;
    REQUIRE(polygon_setup(&p, v, 0, N, SHAPE_NO_NORMALS));
    polygon_slab_pool pool = {0};
    REQUIRE(polygon_slabs_build(&p, v, &pool));
    CHECK_EQ_INT(p.nslabs, 0);
    CHECK_EQ_INT(pool.nentry, 0);
    CHECK_EQ_INT(polygon_test_units(&p, &pool), N);
    /* a smaller zigzag fits the budget */
    polygon_shape s;
    REQUIRE(polygon_setup(&s, v, 0, 16, SHAPE_NO_NORMALS));
    REQUIRE(polygon_slabs_build(&s, v, &pool));
    CHECK(s.nslabs > 0);
    polygon_slab_pool_free(&pool);
    /* fewer than POLYGON_SLAB_MIN vertices: none */
    polygon_shape t;
    REQUIRE(polygon_setup(&t, v, 0, POLYGON_SLAB_MIN - 1, SHAPE_NO_NORMALS));
    REQUIRE(polygon_slabs_build(&t, v, &pool));
    CHECK_EQ_INT(t.nslabs, 0);
    polygon_slab_pool_free(&pool);
}

/* The octagon (+-1, +-2), (+-2, +-1), with a ninth vertex (0, -2) on its
 * bottom edge (POLYGON_SLAB_MIN vertices): distinct v -2, -1, 1, 2 (k = 4,
 * three slabs), every slab crossed by exactly two edges (convex), so 6
 * entries; the three horizontal edges never cross. The lists, the units
 * (ceil(log2 3) = 2 search steps + 2 entries = 4) and point answers by
 * hand (the half-open rule: left and bottom edges inside, right and top
 * edges outside). */
TEST(polygon_slabs_octagon_by_hand)
{
    _Static_assert(POLYGON_SLAB_MIN <= 9, "the polygon below has slabs");
    bsp_vec3 v[9] = {bsp_v3(1, -2, 0),  bsp_v3(2, -1, 0),  bsp_v3(2, 1, 0),
                     bsp_v3(1, 2, 0),   bsp_v3(-1, 2, 0),  bsp_v3(-2, 1, 0),
                     bsp_v3(-2, -1, 0), bsp_v3(-1, -2, 0), bsp_v3(0, -2, 0)};
    polygon_shape p;
    REQUIRE(polygon_setup(&p, v, 0, 9, SHAPE_NO_NORMALS));
    REQUIRE(p.axis_u == 0 && p.axis_v == 1);
    polygon_slab_pool pool = {0};
    REQUIRE(polygon_slabs_build(&p, v, &pool));
    REQUIRE(p.nslabs == 4);
    CHECK(pool.y[0] == -2.0 && pool.y[1] == -1.0 && pool.y[2] == 1.0 && pool.y[3] == 2.0);
    CHECK_EQ_INT(pool.off[0], 0);
    CHECK_EQ_INT(pool.off[1], 2);
    CHECK_EQ_INT(pool.off[2], 4);
    CHECK_EQ_INT(pool.off[3], 6);
    CHECK_EQ_INT(pool.nedge, 6); /* not the three horizontal edges */
    CHECK_EQ_INT(polygon_test_units(&p, &pool), 4);
    struct {
        double x, y;
        int in;
    } c[] = {{0, 0, 1},      {1.9, 0, 1},    {2, 0, 0},   {-2, 0, 1},   {0, -2, 1},    {0, 2, 0},
             {1.4, -1.5, 1}, {1.5, -1.5, 0}, {0, 2.5, 0}, {0, -2.5, 0}, {-1.5, 1.4, 1}};
    for (size_t i = 0; i < sizeof c / sizeof c[0]; i++)
        CHECK_MSG(polygon_contains_slabs(&p, &pool, c[i].x, c[i].y, 0.0) == c[i].in,
                  "(%g, %g) should be %s", c[i].x, c[i].y, c[i].in ? "inside" : "outside");
    polygon_slab_pool_free(&pool);
}
