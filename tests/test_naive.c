/*
 * test_naive.c — the naive method's block scans (accel/naive_blocks.h)
 * against its scalar loops (naive_scene_intersect / naive_scene_occluded,
 * the definition): for every ray the same primitive, t, u and v bit for bit,
 * the same occlusion answer, and the closest-hit scan's count of tests.
 */
#include <math.h>
#include <string.h>

#include "accel/accel_internal.h"
#include "accel/naive_blocks.h"
#include "harness.h"
#include "kd_test_util.h"
#include "same_util.h"

/* The bits of X and Y are the same. */
static int same_bits(double x, double y)
{
    return memcmp(&x, &y, sizeof x) == 0;
}

typedef struct naive_pair {
    bsp_accel *blocks; /* the naive method: its blocks */
    bsp_query *qb, *qs;
    const bsp_scene *s;
    const char *name;
    uint64_t rays, hits, occluded, surface_rays, bad;
} naive_pair;

/* RAY (leaving out FROM) both ways; on a hit of the scalar loop, also
 * returns it in *HIT. */
static int compare_ray(naive_pair *p, const bsp_ray *ray, uint32_t from, bsp_hit *hit)
{
    bsp_hit hb, hs;
    uint64_t tb0 = bsp_query_get_counters(p->qb)->isect_tests;
    uint64_t ts0 = bsp_query_get_counters(p->qs)->isect_tests;
    int fb = bsp_intersect_from(p->blocks, p->qb, ray, from, &hb);
    int fs = naive_scene_intersect(p->s, p->qs, ray, from, &hs);
    uint64_t tb = bsp_query_get_counters(p->qb)->isect_tests - tb0;
    uint64_t ts = bsp_query_get_counters(p->qs)->isect_tests - ts0;
    int ok = fb == fs && (!fs || (hb.prim == hs.prim && same_bits(hb.t, hs.t) &&
                                  same_bits(hb.u, hs.u) && same_bits(hb.v, hs.v)));
    p->bad += (uint64_t)!ok;
    if (!ok && p->bad <= 5)
        harness_fail(__FILE__, __LINE__,
                     "%s: ray (%.17g %.17g %.17g) dir (%.17g %.17g %.17g) [%.17g, %.17g] from %u: "
                     "blocks %d prim %u t %.17g, scalar %d prim %u t %.17g",
                     p->name, ray->org.x, ray->org.y, ray->org.z, ray->dir.x, ray->dir.y,
                     ray->dir.z, ray->tmin, ray->tmax, from, fb, fb ? hb.prim : 0u,
                     fb ? hb.t : 0.0, fs, fs ? hs.prim : 0u, fs ? hs.t : 0.0);
    p->bad += (uint64_t)(tb != ts);
    CHECK_MSG(tb == ts, "%s: %llu tests by blocks, %llu by the scalar loop", p->name,
              (unsigned long long)tb, (unsigned long long)ts);
    int ob = bsp_occluded_from(p->blocks, p->qb, ray, from);
    int os = naive_scene_occluded(p->s, p->qs, ray, from);
    p->bad += (uint64_t)!(ob == os && ob == fs);
    CHECK_MSG(ob == os && ob == fs, "%s: occluded: blocks %d, scalar %d, closest hit %d",
              p->name, ob, os, fs);
    p->rays++;
    p->hits += (uint64_t)fs;
    p->occluded += (uint64_t)os;
    if (fs)
        *hit = hs;
    return fs;
}

/* A point on the boundary of primitive P (where the kernels' first tests
 * are decided by rounding): a triangle's vertex or edge point, a sphere's
 * silhouette seen from O, a point of a cone's rim, a polygon's vertex. */
static bsp_vec3 boundary_point(const bsp_scene *s, uint32_t p, bsp_vec3 o, unsigned long long *rng)
{
    const prim_record *r = &s->prims[p];
    double x = harness_rnd(rng);
    switch ((shape_kind)r->shape) {
    case SHAPE_TRIANGLE: {
        const triangle_edges t = triangle_edges_of(&s->triangles[r->slot].verts);
        static const double ab[7][2] = {{0, 0}, {1, 0}, {0, 1}, {0.5, 0}, {0, 0.5}, {0.5, 0.5},
                                        {0.25, 0.75}};
        const double *w = ab[(int)(x * 7)];
        return v3_add(t.v0, v3_add(v3_scale(t.e1, w[0]), v3_scale(t.e2, w[1])));
    }
    case SHAPE_SPHERE: {
        const sphere_shape *sp = &s->spheres[r->slot];
        bsp_vec3 w = v3_sub(sp->center, o);
        bsp_vec3 u = v3_normalize(v3_cross(w, bsp_v3(x - 0.5, harness_rnd(rng) - 0.5, 0.3)));
        return v3_madd(sp->center, u, sp->radius);
    }
    case SHAPE_CONE: {
        const cone_shape *c = &s->cones[r->slot];
        bsp_vec3 u = v3_normalize(v3_cross(c->axis, bsp_v3(x - 0.5, harness_rnd(rng) - 0.5, 0.3)));
        return x < 0.5 ? v3_madd(c->base, u, c->base_radius)
                       : v3_madd(v3_madd(c->base, c->axis, c->length), u, c->apex_radius);
    }
    case SHAPE_POLYGON: {
        const polygon_shape *pg = &s->polygons[r->slot];
        return s->verts[pg->first + (uint32_t)(x * pg->count)];
    }
    default:
        return o;
    }
}

/* N random rays about the scene box (kd_test_rays: axis-aligned ones, zero
 * components, finite intervals, left-out primitives; a quarter of them aimed
 * at a primitive's boundary instead), and from each hit a
 * ray starting on the surface in a random direction, once leaving the
 * primitive out and once not (its own hit at t near 0 in play), a shadow
 * ray from there to a random point, and the first ray again with its
 * interval ending at the hit's t exactly. */
static void compare_scene(const bsp_scene *s, const char *name, size_t n, unsigned long long seed)
{
    bsp_build_options o;
    bsp_build_options_defaults(&o);
    o.kind = BSP_ACCEL_NAIVE;
    naive_pair p = {0};
    bsp_error err;
    REQUIRE(bsp_accel_build(s, &o, &p.blocks, &err) == BSP_OK);
    REQUIRE(p.blocks->impl != NULL); /* the blocks, not the scalar fallback */
    p.qb = bsp_query_create(p.blocks);
    p.qs = bsp_query_create(p.blocks);
    REQUIRE(p.qb && p.qs);
    p.s = s;
    p.name = name;
    bsp_ray *rays = malloc(n * sizeof *rays);
    uint32_t *from = malloc(n * sizeof *from);
    REQUIRE(rays && from);
    unsigned long long rng = seed;
    bsp_box box = bsp_scene_bounds(s);
    size_t np = bsp_scene_prim_count(s);
    kd_test_rays(&rng, box, n, np, rays, from);
    /* every fourth ray aimed at a primitive's boundary, every eighth from
     * 10^5 times as far away (where cones are solved from a moved origin
     * and thin triangles by the careful path) */
    for (size_t i = 0; i < n; i += 4) {
        uint32_t prim = (uint32_t)(harness_rnd(&rng) * (double)np);
        bsp_vec3 to = boundary_point(s, prim, rays[i].org, &rng);
        rays[i].dir = v3_sub(to, rays[i].org);
        if (i % 8 == 0)
            rays[i].org = v3_madd(to, rays[i].dir, -1e5);
        rays[i].tmax = INFINITY;
    }
    for (size_t i = 0; i < n; i++) {
        bsp_hit h;
        if (!compare_ray(&p, &rays[i], from[i], &h))
            continue;
        /* the interval closed at the hit: the same hit, and occluded */
        bsp_ray upto = rays[i];
        upto.tmax = h.t;
        bsp_hit same;
        CHECK(compare_ray(&p, &upto, from[i], &same) && same.prim == h.prim);
        bsp_vec3 at = v3_madd(rays[i].org, rays[i].dir, h.t);
        bsp_vec3 d = bsp_v3(2.0 * harness_rnd(&rng) - 1.0, 2.0 * harness_rnd(&rng) - 1.0,
                            2.0 * harness_rnd(&rng) - 1.0);
        bsp_ray on = {at, d, 0.0, INFINITY};
        bsp_hit ignored;
        compare_ray(&p, &on, h.prim, &ignored);
        compare_ray(&p, &on, BSP_NO_PRIM, &ignored);
        bsp_vec3 to = bsp_v3(box.lo.x + (box.hi.x - box.lo.x) * harness_rnd(&rng),
                             box.lo.y + (box.hi.y - box.lo.y) * harness_rnd(&rng),
                             box.lo.z + (box.hi.z - box.lo.z) * harness_rnd(&rng));
        bsp_ray shadow = {at, v3_sub(to, at), 0.0, 1.0};
        compare_ray(&p, &shadow, h.prim, &ignored);
        p.surface_rays += 4;
    }
    /* the rays met the scene: many hits and many misses */
    CHECK_MSG(p.hits > p.rays / 20 && p.hits < p.rays - p.rays / 20,
              "%s: %llu hits of %llu rays", name, (unsigned long long)p.hits,
              (unsigned long long)p.rays);
    CHECK_MSG(p.bad == 0, "%s: %llu differences", name, (unsigned long long)p.bad);
    fprintf(stderr, "    %s: %llu rays (%llu of them made from hits), %llu hits, %llu differences\n",
            name, (unsigned long long)p.rays, (unsigned long long)p.surface_rays,
            (unsigned long long)p.hits, (unsigned long long)p.bad);
    free(rays);
    free(from);
    bsp_query_destroy(p.qb);
    bsp_query_destroy(p.qs);
    bsp_accel_destroy(p.blocks);
}

static void compare_spec(const char *spec, size_t n, unsigned long long seed)
{
    bsp_scene *s = kd_test_load(spec);
    compare_scene(s, spec, harness_quick() ? n / 4 : n, seed);
    bsp_scene_destroy(s);
}

/* Spheres (balls), cones and spheres (tree, rings), triangles (tetra,
 * teapot), polygons (gears), all four (mount: triangles and spheres). */
TEST(naive_blocks_match_the_scalar_loop_on_spd_scenes)
{
    compare_spec("spd:balls", 1600, 11);
    compare_spec("spd:tree", 1600, 12);
    compare_spec("spd:rings", 1600, 13);
    compare_spec("spd:tetra", 1600, 14);
    compare_spec("spd:teapot", 1600, 15);
    compare_spec("spd:gears", 600, 16);
    compare_spec("spd:mount", 1000, 17);
}

/* Shapes that take the kernels' other paths: cones seen from far away
 * (their origin moved along the ray), cylinders and discs-like cones (qa ==
 * 0 along the axis), thin triangles seen from far away (the careful path),
 * degenerate primitives (dropped), exact duplicates (ties at equal t, lowest
 * index), spheres of an NFF inside-only radius, coordinates far from the
 * origin. */
TEST(naive_blocks_match_the_scalar_loop_on_stress_shapes)
{
    bsp_scene *s = bsp_scene_create();
    REQUIRE(s);
    bsp_error err;
    unsigned long long rng = 99;
    for (int i = 0; i < 120; i++) {
        bsp_vec3 c = bsp_v3(20 * harness_rnd(&rng) - 10, 20 * harness_rnd(&rng) - 10,
                            20 * harness_rnd(&rng) - 10);
        double r = 0.05 + harness_rnd(&rng);
        REQUIRE(bsp_scene_add_sphere(s, c, r, &err) == BSP_OK);
        REQUIRE(bsp_scene_add_sphere(s, c, r, &err) == BSP_OK); /* its duplicate */
        bsp_vec3 a = v3_add(c, bsp_v3(2 * harness_rnd(&rng) - 1, 2 * harness_rnd(&rng) - 1,
                                      2 * harness_rnd(&rng) - 1));
        /* a cone, a cylinder along an axis, a cone to a point */
        REQUIRE(bsp_scene_add_cone(s, c, 0.3 * r, a, 0.1 * r, &err) == BSP_OK);
        bsp_vec3 up = v3_add(c, bsp_v3(0, 0, 3 * r));
        REQUIRE(bsp_scene_add_cone(s, c, 0.2, up, 0.2, &err) == BSP_OK);
        REQUIRE(bsp_scene_add_cone(s, a, 0.25, c, 0.0, &err) == BSP_OK);
        /* a thin triangle and an ordinary one */
        bsp_vec3 thin[3] = {c, v3_add(c, bsp_v3(8, 0.001, 0)), v3_add(c, bsp_v3(8, 0, 0.001))};
        REQUIRE(bsp_scene_add_polygon(s, thin, 3, &err) == BSP_OK);
        bsp_vec3 tri[3] = {a, c, up};
        REQUIRE(bsp_scene_add_polygon(s, tri, 3, &err) == BSP_OK);
        REQUIRE(bsp_scene_add_polygon(s, tri, 3, &err) == BSP_OK); /* its duplicate */
        /* degenerate: collinear points, dropped */
        bsp_vec3 line[3] = {c, a, v3_add(a, v3_sub(a, c))};
        REQUIRE(bsp_scene_add_polygon(s, line, 3, &err) == BSP_OK);
        /* a quadrilateral */
        bsp_vec3 quad[4] = {c, v3_add(c, bsp_v3(1, 0, 0)), v3_add(c, bsp_v3(1, 1, 0)),
                            v3_add(c, bsp_v3(0, 1, 0))};
        REQUIRE(bsp_scene_add_polygon(s, quad, 4, &err) == BSP_OK);
    }
    REQUIRE(bsp_scene_kind_count(s, BSP_PRIM_DROPPED) > 0);
    compare_scene(s, "stress shapes", harness_quick() ? 5000 : 20000, 21);
    bsp_scene_destroy(s);

    /* the same kinds a million units away, rays from far outside */
    s = bsp_scene_create();
    REQUIRE(s);
    bsp_vec3 off = bsp_v3(1e6, -2e6, 3e6);
    for (int i = 0; i < 200; i++) {
        bsp_vec3 c = v3_add(off, bsp_v3(20 * harness_rnd(&rng) - 10, 20 * harness_rnd(&rng) - 10,
                                        20 * harness_rnd(&rng) - 10));
        REQUIRE(bsp_scene_add_sphere(s, c, 0.05 + harness_rnd(&rng), &err) == BSP_OK);
        bsp_vec3 a = v3_add(c, bsp_v3(2 * harness_rnd(&rng) - 1, 2 * harness_rnd(&rng) - 1,
                                      2 * harness_rnd(&rng) - 1));
        REQUIRE(bsp_scene_add_cone(s, c, 0.2, a, 0.1, &err) == BSP_OK);
        bsp_vec3 tri[3] = {c, a, v3_add(c, bsp_v3(0, 1, 0))};
        REQUIRE(bsp_scene_add_polygon(s, tri, 3, &err) == BSP_OK);
    }
    compare_scene(s, "far from the origin", harness_quick() ? 5000 : 20000, 22);
    bsp_scene_destroy(s);
}

/* Under a memory limit too small for the blocks the method scans by the
 * scalar loop (no blocks built), with the same answers as the blocks. */
TEST(naive_under_a_tiny_memory_limit_scans_without_blocks)
{
    bsp_scene *s = kd_test_load("spd:balls:1");
    bsp_build_options o;
    bsp_build_options_defaults(&o);
    o.kind = BSP_ACCEL_NAIVE;
    bsp_accel *blocks = NULL, *plain = NULL;
    bsp_error err;
    REQUIRE(bsp_accel_build(s, &o, &blocks, &err) == BSP_OK);
    o.max_tree_bytes = 64;
    REQUIRE(bsp_accel_build(s, &o, &plain, &err) == BSP_OK);
    CHECK(blocks->impl != NULL && plain->impl == NULL);
    bsp_query *qb = bsp_query_create(blocks), *qp = bsp_query_create(plain);
    REQUIRE(qb && qp);
    enum { N = 2000 };
    static bsp_ray rays[N];
    static uint32_t from[N];
    unsigned long long rng = 5;
    kd_test_rays(&rng, bsp_scene_bounds(s), N, bsp_scene_prim_count(s), rays, from);
    int hits = 0, same = 0;
    for (int i = 0; i < N; i++) {
        bsp_hit hb, hp;
        int fb = bsp_intersect_from(blocks, qb, &rays[i], from[i], &hb);
        int fp = bsp_intersect_from(plain, qp, &rays[i], from[i], &hp);
        hits += fp;
        same += same_hit(fb, &hb, fp, &hp) &&
                bsp_occluded_from(blocks, qb, &rays[i], from[i]) ==
                    bsp_occluded_from(plain, qp, &rays[i], from[i]);
    }
    CHECK_EQ_INT(same, N);
    CHECK(hits > N / 20);
    bsp_query_destroy(qb);
    bsp_query_destroy(qp);
    bsp_accel_destroy(blocks);
    bsp_accel_destroy(plain);
    bsp_scene_destroy(s);
}
