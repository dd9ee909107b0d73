/*
 * test_watertight.c — no ray passes between two triangles that share an
 * edge (geom/isect.h: Möller–Trumbore, with Woop, Benthin and Wald's
 * watertight test deciding within the margin of an edge).
 *
 * 1. A closed UV sphere of triangles, rays aimed at points on its edges from
 *    outside, near and inside: none may pass through the edge to a surface
 *    beyond it, and none whose line enters the solid may miss it (naive
 *    method and SAH tree alike), also with the triangles' windings mixed.
 *    Möller–Trumbore alone let 12.6 % of such rays through (session 53,
 *    docs/precision.md).
 * 2. The margin: on rays aimed within rounding of triangles' edges and
 *    vertices, from near and far, the kernel's answer is the watertight
 *    test's (wherever Möller–Trumbore decides alone, the two must agree).
 */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "bspray/bspray.h"
#include "geom/isect.h"
#include "geom/shapes.h"
#include "harness.h"
#include "scene/scene_internal.h"

/* A closed mesh: vertices and faces of 3 or 4 vertices (a face of 3 has
 * idx[3] unused). */
typedef struct mesh {
    bsp_vec3 *v;
    size_t nv;
    uint32_t (*face)[4];
    int *count;
    size_t nf;
} mesh;

/* A UV sphere of radius 1 about the origin: NLAT rings of NLON faces, fans
 * of triangles at the poles; between them quads (QUADS) or each quad cut
 * into two triangles. MIXED reverses the winding of every other face. */
static mesh uv_sphere(int nlat, int nlon, int quads, int mixed)
{
    const double pi = 3.14159265358979323846;
    mesh m;
    m.nv = (size_t)(nlat - 1) * (size_t)nlon + 2;
    m.v = malloc(m.nv * sizeof *m.v);
    m.nf = 2 * (size_t)nlon * (size_t)(nlat - 1);
    m.face = malloc(m.nf * sizeof *m.face);
    m.count = malloc(m.nf * sizeof *m.count);
    REQUIRE(m.v && m.face && m.count);
    m.v[0] = bsp_v3(0, 0, 1);
    m.v[1] = bsp_v3(0, 0, -1);
    for (int i = 1; i < nlat; i++)
        for (int j = 0; j < nlon; j++) {
            double th = pi * i / nlat, ph = 2 * pi * j / nlon;
            m.v[2 + (size_t)(i - 1) * nlon + j] =
                bsp_v3(sin(th) * cos(ph), sin(th) * sin(ph), cos(th));
        }
    size_t k = 0;
#define RING(i, j) ((uint32_t)(2 + (size_t)((i) - 1) * nlon + (size_t)(((j) + nlon) % nlon)))
    /* face k with the N vertices of F, reversed on every other face if MIXED */
#define FACE(N, ...)                                                                               do {                                                                                               const uint32_t f_[4] = {__VA_ARGS__};                                                          for (int q_ = 0; q_ < (N); q_++)                                                                   m.face[k][q_] = mixed && (k & 1) ? f_[(N) - 1 - q_] : f_[q_];                              m.count[k++] = (N);                                                                        } while (0)
    for (int j = 0; j < nlon; j++) {
        FACE(3, 0, RING(1, j), RING(1, j + 1));
        FACE(3, 1, RING(nlat - 1, j + 1), RING(nlat - 1, j));
        for (int i = 1; i < nlat - 1; i++) {
            if (quads) {
                FACE(4, RING(i, j), RING(i + 1, j), RING(i + 1, j + 1), RING(i, j + 1));
            } else {
                FACE(3, RING(i, j), RING(i + 1, j), RING(i + 1, j + 1));
                FACE(3, RING(i, j), RING(i + 1, j + 1), RING(i, j + 1));
            }
        }
    }
#undef FACE
#undef RING
    m.nf = k;
    return m;
}

static void mesh_free(mesh *m)
{
    free(m->v);
    free(m->face);
    free(m->count);
}

/* The scene of mesh M: its faces as polygons (3 vertices: triangles). */
static bsp_scene *mesh_scene(const mesh *m)
{
    bsp_error err;
    bsp_scene *s = bsp_scene_create();
    REQUIRE(s);
    for (size_t f = 0; f < m->nf; f++) {
        bsp_vec3 vs[4];
        for (int q = 0; q < m->count[f]; q++)
            vs[q] = m->v[m->face[f][q]];
        REQUIRE(bsp_scene_add_polygon(s, vs, (size_t)m->count[f], &err) == BSP_OK);
    }
    REQUIRE(bsp_scene_kind_count(s, BSP_PRIM_DROPPED) == 0);
    return s;
}

/* Rays from 4 origins (far, near, and two inside) aimed at 4 points of
 * every edge of the unit sphere M: none may pass through the edge to a
 * surface beyond it, nor miss when its line enters the solid; naive method
 * and SAH tree. */
static void check_closed(const mesh *m, const char *what)
{
    const bsp_vec3 origins[] = {
        {{0.3, -0.2, 40.0}},   /* far: ~ 300 edge lengths */
        {{1.7, 0.9, -1.3}},    /* near */
        {{0.01, -0.02, 0.03}}, /* inside */
        {{0.0, 0.0, 0.5}},     /* inside, on the axis of the poles */
    };
    const double fracs[] = {0.25, 0.5, 0.75, 1.0 / 3.0};
    bsp_scene *s = mesh_scene(m);
    bsp_error err;
    bsp_build_options opt;
    bsp_build_options_defaults(&opt);
    bsp_accel *acc[2];
    opt.kind = BSP_ACCEL_NAIVE;
    REQUIRE(bsp_accel_build(s, &opt, &acc[0], &err) == BSP_OK);
    opt.kind = BSP_ACCEL_SAH;
    REQUIRE(bsp_accel_build(s, &opt, &acc[1], &err) == BSP_OK);
    for (int a = 0; a < 2; a++) {
        bsp_query *q = bsp_query_create(acc[a]);
        REQUIRE(q);
        size_t rays = 0, through = 0, grazing = 0, edges = 0;
        for (size_t o = 0; o < sizeof origins / sizeof origins[0]; o++)
            for (size_t f = 0; f < m->nf; f++)
                for (int e = 0; e < m->count[f]; e++) {
                    edges += o == 0;
                    bsp_vec3 p0 = m->v[m->face[f][e]];
                    bsp_vec3 p1 = m->v[m->face[f][(e + 1) % m->count[f]]];
                    for (size_t k = 0; k < sizeof fracs / sizeof fracs[0]; k++) {
                        /* a point of the edge, to rounding; the ray reaches it at t = 1 */
                        bsp_vec3 p = v3_madd(p0, v3_sub(p1, p0), fracs[k]);
                        bsp_ray r = {origins[o], v3_sub(p, origins[o]), 0.0, INFINITY};
                        bsp_hit h;
                        int hit = bsp_intersect(acc[a], q, &r, &h);
                        rays++;
                        /* A line that passes within 0.98 of the centre
                         * crosses the solid (its faces lie 0.989 and more
                         * from the centre); one that only grazes the
                         * silhouette, nearly in the plane of a face there,
                         * may miss: the hit check refuses such hits
                         * (geom/isect.h), and the ray does not enter. */
                        bsp_vec3 d = v3_normalize(r.dir);
                        bsp_vec3 near = v3_madd(r.org, d, -v3_dot(r.org, d));
                        int enters = v3_length(near) < 0.98;
                        grazing += !hit && !enters;
                        if ((hit && h.t > 1.0 + 1e-9) || (!hit && enters)) {
                            if (through++ < 5)
                                harness_fail(__FILE__, __LINE__,
                                             "%s, %s: ray from origin %zu to edge %d of face "
                                             "%zu at %g: %s",
                                             what, a ? "sah" : "naive", o, e, f, fracs[k],
                                             hit ? "hit beyond the edge" : "missed");
                        }
                    }
                }
        CHECK(rays == 4 * 4 * edges);
        printf("  %s, %s: %zu rays, %zu missed grazing the silhouette\n", what,
               a ? "sah" : "naive", rays, grazing);
        if (through)
            harness_fail(__FILE__, __LINE__, "%s: %zu of %zu rays passed through an edge", what,
                         through, rays);
        bsp_query_destroy(q);
    }
    bsp_accel_destroy(acc[0]);
    bsp_accel_destroy(acc[1]);
    bsp_scene_destroy(s);
}

/* Quick mode (the sanitizer run): a sphere of a quarter of the faces. */
static int sphere_rings(void)
{
    return harness_quick() ? 12 : 24;
}

TEST(watertight_closed_mesh_lets_no_ray_through)
{
    for (int mixed = 0; mixed < 2; mixed++) {
        mesh m = uv_sphere(sphere_rings(), 2 * sphere_rings(), 0, mixed);
        check_closed(&m, mixed ? "triangles, mixed windings" : "triangles");
        mesh_free(&m);
    }
}

TEST(watertight_closed_mesh_of_quads_lets_no_ray_through)
{
    for (int mixed = 0; mixed < 2; mixed++) {
        mesh m = uv_sphere(sphere_rings(), 2 * sphere_rings(), 1, mixed);
        check_closed(&m, mixed ? "quads, mixed windings" : "quads");
        mesh_free(&m);
    }
}

/* A uniform double in [lo, hi). */
static double uniform(unsigned long long *s, double lo, double hi)
{
    return lo + (hi - lo) * harness_rnd(s);
}

static bsp_vec3 random_unit(unsigned long long *s)
{
    for (;;) {
        bsp_vec3 p = bsp_v3(uniform(s, -1, 1), uniform(s, -1, 1), uniform(s, -1, 1));
        double l = v3_length(p);
        if (l > 0.1 && l <= 1.0)
            return v3_scale(p, 1.0 / l);
    }
}

/* X moved by K units in the last place (K may be negative). */
static double ulps(double x, int k)
{
    for (; k > 0; k--)
        x = nextafter(x, INFINITY);
    for (; k < 0; k++)
        x = nextafter(x, -INFINITY);
    return x;
}

/* Ray K of a boundary probe of the face VS (N vertices, size ~SIZE): aimed
 * at a point of an edge or a vertex moved by a few ulps per axis, from an
 * origin 0.5 to 10^4 sizes away (*DIST), every 11th with a zero direction
 * component; the interval is the whole line. */
static bsp_ray ray_near_boundary(unsigned long long *rng, const bsp_vec3 *vs, uint32_t n,
                                 double size, int k, double *dist)
{
    uint32_t e = (uint32_t)(harness_rnd(rng) * n);
    double f = k % 7 == 0 ? 0.0 : harness_rnd(rng);
    bsp_vec3 p = v3_madd(vs[e], v3_sub(vs[(e + 1) % n], vs[e]), f);
    for (int ax = 0; ax < 3; ax++)
        p.v[ax] = ulps(p.v[ax], (int)(harness_rnd(rng) * 9) - 4);
    *dist = size * pow(10.0, uniform(rng, -0.3, 4));
    bsp_vec3 o = v3_madd(p, random_unit(rng), *dist);
    if (k % 11 == 0)
        o.v[k % 3] = p.v[k % 3];
    bsp_ray r = {o, v3_sub(p, o), -INFINITY, INFINITY};
    return r;
}

/* The counts of a margin test. */
typedef struct tally {
    size_t rays, hits, differs_from_plain;
} tally;

/* Counts one ray: the kernel said GOT, the watertight test WANT, the test
 * without the margin PLAIN. 0 (a failure reported) when GOT != WANT. */
static int count_ray(tally *c, int got, int want, int plain, int trial, int k, uint32_t n,
                     double size, double dist)
{
    c->rays++;
    c->hits += (size_t)want;
    c->differs_from_plain += (size_t)(plain != want);
    if (got == want)
        return 1;
    harness_fail(__FILE__, __LINE__,
                 "trial %d ray %d: the kernel says %s, the watertight test %s "
                 "(%u vertices, size %g, origin %g sizes away)",
                 trial, k, got ? "hit" : "miss", want ? "hit" : "miss", n, size, dist / size);
    return 0;
}

/* The triangle kernel as the traversals run it, with the ray's bound of the
 * margin made for REACH (isect_ray.tri_bound); *T the hit's t. */
static int kernel_with_reach(const triangle_shape *tr, const bsp_ray *r,
                             const triangle_reach *reach, double *t)
{
    isect_ray ir;
    isect_ray_init(&ir, r, INFINITY, reach);
    double bu, bv, det;
    return triangle_isect_verts(&tr->verts, tr->edge_exp, &ir, r->tmax, t, &bu, &bv, &det);
}

/* Whether the ray's bound made for REACH covers the triangle's margin. */
static int bound_covers_margin(const triangle_shape *tr, const bsp_ray *r,
                               const triangle_reach *reach)
{
    isect_ray ir;
    isect_ray_init(&ir, r, INFINITY, reach);
    const bsp_vec3 tv = v3_sub(r->org, tr->v0);
    return triangle_margin(tv.x, tv.y, tv.z, triangle_edge_norm(tr->edge_exp), ir.edge_scale) <=
           ir.tri_bound;
}

TEST(watertight_margin_gives_the_watertight_answer)
{
    unsigned long long rng = 0x5eed5eed1234ULL;
    tally count = {0, 0, 0};
    for (int trial = 0; trial < 400; trial++) {
        /* a triangle of size ~SIZE at OFFSET, sometimes thin */
        double size = pow(10.0, uniform(&rng, -3, 3));
        bsp_vec3 off = v3_scale(random_unit(&rng), trial % 4 == 0 ? 1e4 * size : size);
        bsp_vec3 a = v3_madd(off, random_unit(&rng), size);
        bsp_vec3 b = v3_madd(a, random_unit(&rng), size * uniform(&rng, 0.2, 1.0));
        bsp_vec3 c = v3_madd(a, random_unit(&rng), size * (trial % 5 == 0 ? 1e-3 : 1.0));
        triangle_shape tr;
        if (!triangle_setup(&tr, a, b, c, SHAPE_NO_NORMALS))
            continue;
        const bsp_vec3 vs[3] = {a, b, c};
        /* the reach of a scene of this triangle alone (scene_update_scale),
         * and a far looser one: the ray's bound only chooses where the
         * margin is computed, so both must give the margin's answer */
        triangle_reach tight = {0.0, triangle_edge_norm(tr.edge_exp)};
        const bsp_box tb = triangle_bounds(&tr);
        for (int ax = 0; ax < 3; ax++)
            tight.radius += fmax(fabs(tb.lo.v[ax]), fabs(tb.hi.v[ax]));
        const triangle_reach loose = {1e3 * tight.radius, 0x1p10 * tight.enorm};
        for (int k = 0; k < 300; k++) {
            double dist;
            bsp_ray r = ray_near_boundary(&rng, vs, 3, size, k, &dist);
            const bsp_vec3 o = r.org;
            double t = 0.0, u, v;
            int got = triangle_intersect(&tr, &r, &t, &u, &v);
            double t_tight = 0.0, t_loose = 0.0;
            int got_tight = kernel_with_reach(&tr, &r, &tight, &t_tight);
            int got_loose = kernel_with_reach(&tr, &r, &loose, &t_loose);
            if (!bound_covers_margin(&tr, &r, &tight) || got_tight != got || got_loose != got ||
                (got && (memcmp(&t_tight, &t, sizeof t) || memcmp(&t_loose, &t, sizeof t)))) {
                harness_fail(__FILE__, __LINE__,
                             "trial %d ray %d: the ray's bound of the margin changed the answer "
                             "(%d, tight %d, loose %d; t %.17g %.17g %.17g)",
                             trial, k, got, got_tight, got_loose, t, t_tight, t_loose);
                return;
            }

            isect_ray ir;
            isect_ray_init(&ir, &r, INFINITY, NULL);
            const bsp_vec3 tv = v3_sub(o, tr.v0), e1 = v3_sub(tr.v1, tr.v0),
                           e2 = v3_sub(tr.v2, tr.v0);
            double det, bu, bv, qx, qy, qz;
            triangle_bary(r.dir.x, r.dir.y, r.dir.z, tv.x, tv.y, tv.z, e1.x, e1.y, e1.z, e2.x,
                          e2.y, e2.z, &det, &bu, &bv, &qx, &qy, &qz);
            int neg;
            const int plain = triangle_range(&det, &bu, &bv, 0.0, &neg);
            const int want = det != 0.0 && triangle_watertight(&tr.verts, &ir);
            if (!count_ray(&count, got, want, plain, trial, k, 3, size, dist))
                return;
        }
    }
    /* the rays reach the margin: Möller–Trumbore alone would have answered
     * otherwise on some of them */
    printf("  %zu rays, %zu hits, %zu where Möller–Trumbore alone differs\n", count.rays, count.hits,
           count.differs_from_plain);
    CHECK(count.rays > 100000);
    CHECK(count.hits > count.rays / 10 && count.hits < count.rays - count.rays / 10);
    CHECK(count.differs_from_plain > 100);
}

/* The scene's reach (scene_update_scale) and the ray's bound made from it:
 * for every ray of the precision domain and every triangle of the scene,
 * the bound is at least the triangle's margin, so the traversals, which
 * compute the margin only within the bound, answer as the margin does. On
 * the SPD tetrahedron and teapot (triangles beside polygons), and on a mesh
 * of triangles of mixed sizes far from the origin, its largest triangle
 * added last. */
TEST(watertight_scene_bound_covers_every_margin)
{
    bsp_scene *scenes[3] = {NULL, NULL, NULL};
    bsp_error err;
    REQUIRE(bsp_scene_load("spd:tetra", &scenes[0], &err) == BSP_OK);
    REQUIRE(bsp_scene_load("spd:teapot", &scenes[1], &err) == BSP_OK);
    unsigned long long rng = 0xb0b0cafe11ULL;
    scenes[2] = bsp_scene_create();
    REQUIRE(scenes[2]);
    const bsp_vec3 far = {{3e5, -2e5, 7e4}};
    for (int i = 0; i < 200; i++) {
        double size = i == 199 ? 50.0 : pow(10.0, uniform(&rng, -3, 0));
        bsp_vec3 a = v3_madd(far, random_unit(&rng), uniform(&rng, 0.0, 20.0));
        bsp_vec3 tri[3] = {a, v3_madd(a, random_unit(&rng), size),
                           v3_madd(a, random_unit(&rng), size)};
        REQUIRE(bsp_scene_add_polygon(scenes[2], tri, 3, &err) == BSP_OK);
    }
    for (int sc = 0; sc < 3; sc++) {
        const bsp_scene *s = scenes[sc];
        const bsp_box box = bsp_scene_bounds(s);
        const bsp_vec3 mid = v3_scale(v3_add(box.lo, box.hi), 0.5);
        const double ext = v3_length(v3_sub(box.hi, box.lo));
        size_t tested = 0;
        int bad = 0;
        for (int k = 0; k < 300 && !bad; k++) {
            /* origins inside, near and far (up to 10^5 scene sizes) */
            double reach = ext * pow(10.0, uniform(&rng, -2, 5));
            bsp_ray r = {v3_madd(mid, random_unit(&rng), reach), random_unit(&rng), 0.0, INFINITY};
            r.dir = v3_scale(r.dir, pow(10.0, uniform(&rng, -3, 3)));
            const double o[3] = {r.org.x, r.org.y, r.org.z};
            if (!scene_ray_in_domain(s, o, v3_dot(r.dir, r.dir)))
                continue;
            for (size_t t = 0; t < s->ntriangles && !bad; t++, tested++)
                if (!bound_covers_margin(&s->triangles[t], &r, &s->tri_reach)) {
                    bad = 1;
                    harness_fail(__FILE__, __LINE__,
                                 "scene %d, ray %d: the bound is below triangle %zu's margin", sc,
                                 k, t);
                }
        }
        CHECK(tested > 10000);
    }
    for (int sc = 0; sc < 3; sc++)
        bsp_scene_destroy(scenes[sc]);
}

/* The polygon's margin (polygon_isect): on rays aimed within a few ulps of
 * the edges and vertices of planar polygons (4 to 14 vertices, convex and
 * star-shaped, in random planes, from near and far), the kernel gives the
 * answer of the crossing test on the ray's shear, the watertight test. */
TEST(watertight_polygon_margin_gives_the_watertight_answer)
{
    unsigned long long rng = 0xfacade5eedULL;
    tally count = {0, 0, 0};
    size_t polygons = 0;
    for (int trial = 0; trial < 300; trial++) {
        const uint32_t n = 4 + (uint32_t)(trial % 11);
        const int star = trial % 3 == 0 && n >= 6;
        double size = pow(10.0, uniform(&rng, -3, 3));
        bsp_vec3 c = v3_scale(random_unit(&rng), trial % 4 == 0 ? 1e4 * size : size);
        bsp_vec3 ax = random_unit(&rng), w = random_unit(&rng);
        bsp_vec3 ay = v3_normalize(v3_cross(ax, w));
        ax = v3_normalize(v3_cross(ay, w));
        bsp_vec3 vs[14];
        for (uint32_t i = 0; i < n; i++) {
            const double pi = 3.14159265358979323846;
            double a = 2 * pi * i / n, r = size * (star && (i & 1) ? 0.4 : 1.0);
            vs[i] = v3_madd(v3_madd(c, ax, r * cos(a)), ay, r * sin(a));
        }
        polygon_shape pg;
        if (!polygon_setup(&pg, vs, 0, n, SHAPE_NO_NORMALS))
            continue;
        REQUIRE(pg.wt_base >= 0.0); /* planar to rounding */
        polygons++;
        for (int k = 0; k < 300; k++) {
            double dist;
            bsp_ray r = ray_near_boundary(&rng, vs, n, size, k, &dist);
            const bsp_vec3 o = r.org;
            double t;
            int got = polygon_intersect(&pg, vs, NULL, &r, &t);

            isect_ray ir;
            isect_ray_init(&ir, &r, INFINITY, NULL);
            double denom;
            double tt = polygon_plane(pg.normal.x, pg.normal.y, pg.normal.z, pg.d, o.x, o.y, o.z,
                                      r.dir.x, r.dir.y, r.dir.z, &denom);
            const int au = pg.axis_u, av = pg.axis_v;
            const int plain = denom != 0.0 &&
                              (polygon_contains_2d(vs, n, au, av, o.v[au] + r.dir.v[au] * tt,
                                                   o.v[av] + r.dir.v[av] * tt, 0.0) &
                               POLYGON_INSIDE);
            const int want = denom != 0.0 && polygon_watertight(vs, n, &ir);
            if (!count_ray(&count, got, want, plain, trial, k, n, size, dist))
                return;
        }
    }
    printf("  %zu polygons, %zu rays, %zu hits, %zu where the projected crossing test alone "
           "differs\n",
           polygons, count.rays, count.hits, count.differs_from_plain);
    CHECK(count.rays > 80000);
    CHECK(count.hits > count.rays / 10 && count.hits < count.rays - count.rays / 10);
    CHECK(count.differs_from_plain > 100);
}
