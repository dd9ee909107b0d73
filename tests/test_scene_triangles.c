/*
 * test_scene_triangles.c — bsp_scene_add_triangles (an indexed triangle
 * mesh in one call) against the same triangles added one by one with
 * bsp_scene_add_polygon / _add_patch: the same primitives bit for bit, the
 * same kd-tree (digest), the same closest hits; and its refusals (an index
 * out of range, a bad vertex, NULL arrays, too many triangles), each naming
 * what is wrong and leaving the scene as it was.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bspray/bspray.h"
#include "harness.h"
#include "same_util.h"

/* A height field of (G+1)^2 shared vertices and 2 G^2 triangles over
 * [0, 1]^2, with coordinates that are not exactly representable, one
 * degenerate triangle (a repeated index) appended, and one vertex no
 * triangle uses. */
enum { G = 12, NV = (G + 1) * (G + 1) + 1, NT = 2 * G * G + 1 };

static void height_field(bsp_vec3 *v, bsp_vec3 *n, uint32_t *ix)
{
    for (int j = 0; j <= G; j++)
        for (int i = 0; i <= G; i++) {
            double x = i / (double)G, y = j / (double)G;
            v[j * (G + 1) + i] = bsp_v3(x, y, 0.3 * sin(7.1 * x) * cos(5.3 * y));
            n[j * (G + 1) + i] = bsp_v3(0.1 * x, -0.2 * y, 1.0);
        }
    v[NV - 1] = bsp_v3(100, 100, 100); /* unused */
    n[NV - 1] = bsp_v3(0, 0, 1);
    size_t t = 0;
    for (int j = 0; j < G; j++)
        for (int i = 0; i < G; i++) {
            uint32_t a = (uint32_t)(j * (G + 1) + i), b = a + 1, c = a + G + 1, d = c + 1;
            /* alternate diagonals, so both windings occur */
            if ((i + j) & 1) {
                ix[3 * t] = a, ix[3 * t + 1] = b, ix[3 * t + 2] = d, t++;
                ix[3 * t] = a, ix[3 * t + 1] = d, ix[3 * t + 2] = c, t++;
            } else {
                ix[3 * t] = a, ix[3 * t + 1] = b, ix[3 * t + 2] = c, t++;
                ix[3 * t] = b, ix[3 * t + 1] = d, ix[3 * t + 2] = c, t++;
            }
        }
    ix[3 * t] = 5, ix[3 * t + 1] = 5, ix[3 * t + 2] = 9; /* degenerate: dropped */
}

/* The scene: a sphere, then the mesh, by one call (BULK) or triangle by
 * triangle; with or without normals. */
static bsp_scene *mesh_scene(int bulk, int with_normals)
{
    static bsp_vec3 v[NV], n[NV];
    static uint32_t ix[3 * NT];
    height_field(v, n, ix);
    bsp_scene *s = bsp_scene_create();
    REQUIRE(s);
    bsp_error err;
    REQUIRE(bsp_scene_add_sphere(s, bsp_v3(0.5, 0.5, 0.6), 0.2, &err) == BSP_OK);
    if (bulk) {
        REQUIRE(bsp_scene_add_triangles(s, v, NV, with_normals ? n : NULL, ix, NT, &err) ==
                BSP_OK);
    } else {
        for (size_t t = 0; t < NT; t++) {
            const bsp_vec3 tv[3] = {v[ix[3 * t]], v[ix[3 * t + 1]], v[ix[3 * t + 2]]};
            const bsp_vec3 tn[3] = {n[ix[3 * t]], n[ix[3 * t + 1]], n[ix[3 * t + 2]]};
            REQUIRE((with_normals ? bsp_scene_add_patch(s, tv, tn, 3, &err)
                                  : bsp_scene_add_polygon(s, tv, 3, &err)) == BSP_OK);
        }
    }
    return s;
}

static int same_box(bsp_box a, bsp_box b)
{
    return same_vec(a.lo, b.lo) && same_vec(a.hi, b.hi);
}

TEST(scene_add_triangles_makes_the_polygons_one_by_one)
{
    for (int with_normals = 0; with_normals < 2; with_normals++) {
        bsp_scene *a = mesh_scene(1, with_normals), *b = mesh_scene(0, with_normals);
        REQUIRE(bsp_scene_prim_count(a) == 1 + NT);
        REQUIRE(bsp_scene_prim_count(b) == 1 + NT);
        CHECK(bsp_scene_kind_count(a, BSP_PRIM_DROPPED) == 1);
        CHECK(bsp_scene_kind_count(a, with_normals ? BSP_PRIM_PATCH : BSP_PRIM_POLYGON) ==
              NT - 1);
        CHECK(same_box(bsp_scene_bounds(a), bsp_scene_bounds(b)));
        int same = 1;
        for (size_t p = 0; p < bsp_scene_prim_count(a); p++) {
            same &= bsp_scene_prim_kind(a, p) == bsp_scene_prim_kind(b, p);
            same &= same_box(bsp_scene_prim_bounds(a, p), bsp_scene_prim_bounds(b, p));
            if (p == 0 || bsp_scene_prim_kind(a, p) == BSP_PRIM_DROPPED)
                continue;
            for (size_t i = 0; i < 3; i++) {
                bsp_vec3 va, vb;
                same &= bsp_scene_prim_vertex(a, p, i, &va) == BSP_OK &&
                        bsp_scene_prim_vertex(b, p, i, &vb) == BSP_OK && same_vec(va, vb);
                if (with_normals)
                    same &= bsp_scene_prim_vertex_normal(a, p, i, &va) == BSP_OK &&
                            bsp_scene_prim_vertex_normal(b, p, i, &vb) == BSP_OK &&
                            same_vec(va, vb);
            }
        }
        CHECK_MSG(same, "with normals %d: a primitive differs", with_normals);

        /* the same tree, and the same closest hits as the naive method on
         * the one-by-one scene, for rays through the field */
        bsp_error err;
        bsp_accel *ka, *kb, *nb;
        REQUIRE(bsp_accel_build(a, NULL, &ka, &err) == BSP_OK);
        REQUIRE(bsp_accel_build(b, NULL, &kb, &err) == BSP_OK);
        bsp_build_options no;
        bsp_build_options_defaults(&no);
        no.kind = BSP_ACCEL_NAIVE;
        REQUIRE(bsp_accel_build(b, &no, &nb, &err) == BSP_OK);
        bsp_tree_stats ta, tb;
        bsp_accel_tree_stats(ka, &ta);
        bsp_accel_tree_stats(kb, &tb);
        CHECK(ta.digest == tb.digest);
        bsp_query *qa = bsp_query_create(ka), *qn = bsp_query_create(nb);
        REQUIRE(qa && qn);
        unsigned long long rng = 0x51ce5eedull;
        int hits = 0, agree = 1;
        for (int r = 0; r < 4000; r++) {
            bsp_ray ray;
            ray.org = bsp_v3(harness_rnd(&rng) * 1.2 - 0.1, harness_rnd(&rng) * 1.2 - 0.1, 2.0);
            ray.dir = bsp_v3(0.3 * (harness_rnd(&rng) - 0.5), 0.3 * (harness_rnd(&rng) - 0.5), -1.0);
            if (r % 7 == 0)
                ray.dir = bsp_v3(0, 0, -1); /* two zero components */
            ray.tmin = 0.0;
            ray.tmax = INFINITY;
            bsp_hit ha, hn;
            int ia = bsp_intersect(ka, qa, &ray, &ha), in = bsp_intersect(nb, qn, &ray, &hn);
            hits += in;
            agree &= same_hit(ia, &ha, in, &hn);
        }
        CHECK_MSG(agree, "with normals %d: a closest hit differs from the naive method's",
                  with_normals);
        CHECK_MSG(hits > 2000, "%d hits", hits); /* the rays do meet the field */
        bsp_query_destroy(qa);
        bsp_query_destroy(qn);
        bsp_accel_destroy(ka);
        bsp_accel_destroy(kb);
        bsp_accel_destroy(nb);
        bsp_scene_destroy(a);
        bsp_scene_destroy(b);
    }
}

TEST(scene_add_triangles_refuses_bad_meshes_whole)
{
    bsp_vec3 v[5] = {{{0, 0, 0}}, {{1, 0, 0}}, {{0, 1, 0}}, {{1, 1, 0}}, {{2, 2, 2}}};
    uint32_t ix[9] = {0, 1, 2, 1, 3, 2, 2, 3, 4};
    bsp_scene *s = bsp_scene_create();
    REQUIRE(s);
    bsp_error err;
    REQUIRE(bsp_scene_add_sphere(s, bsp_v3(5, 5, 5), 1.0, &err) == BSP_OK);

    /* an index out of range in the last triangle: nothing added, the
     * triangle and the index named */
    ix[7] = 5;
    CHECK(bsp_scene_add_triangles(s, v, 5, NULL, ix, 3, &err) == BSP_ERR_INVALID);
    CHECK_STR_CONTAINS(err.message, "triangle 2");
    CHECK_STR_CONTAINS(err.message, "index 5");
    CHECK(bsp_scene_prim_count(s) == 1);
    ix[7] = 3;

    /* a non-finite coordinate in a vertex no triangle of the call uses */
    v[4].y = NAN;
    CHECK(bsp_scene_add_triangles(s, v, 5, NULL, ix, 2, &err) == BSP_ERR_INVALID);
    CHECK_STR_CONTAINS(err.message, "vertex 4");
    CHECK(bsp_scene_prim_count(s) == 1);
    v[4].y = 2;

    /* a coordinate beyond BSP_SCENE_MAX_COORD, a non-finite normal */
    v[1].z = -1e31;
    CHECK(bsp_scene_add_triangles(s, v, 5, NULL, ix, 3, &err) == BSP_ERR_INVALID);
    CHECK_STR_CONTAINS(err.message, "vertex 1");
    CHECK_STR_CONTAINS(err.message, "out of range");
    v[1].z = 0;
    bsp_vec3 n[5] = {{{0, 0, 1}}, {{0, 0, 1}}, {{0, 0, 1}}, {{0, 0, INFINITY}}, {{0, 0, 1}}};
    CHECK(bsp_scene_add_triangles(s, v, 5, n, ix, 3, &err) == BSP_ERR_INVALID);
    CHECK_STR_CONTAINS(err.message, "vertex 3");
    CHECK(bsp_scene_prim_count(s) == 1);

    /* NULL arrays; an absurd count is refused before any index is read */
    CHECK(bsp_scene_add_triangles(s, v, 5, NULL, NULL, 3, &err) == BSP_ERR_INVALID);
    CHECK(bsp_scene_add_triangles(s, NULL, 5, NULL, ix, 3, &err) == BSP_ERR_INVALID);
    CHECK(bsp_scene_add_triangles(s, v, 5, NULL, ix, (size_t)1 << 40, &err) == BSP_ERR_LIMIT);
    CHECK(bsp_scene_prim_count(s) == 1);

    /* nothing to add is fine, even with no arrays */
    CHECK(bsp_scene_add_triangles(s, NULL, 0, NULL, NULL, 0, &err) == BSP_OK);
    CHECK(bsp_scene_prim_count(s) == 1);

    /* and the mesh itself goes in after the refusals, numbered after the
     * sphere */
    CHECK(bsp_scene_add_triangles(s, v, 5, NULL, ix, 3, &err) == BSP_OK);
    REQUIRE(bsp_scene_prim_count(s) == 4);
    bsp_vec3 got;
    CHECK(bsp_scene_prim_vertex(s, 3, 2, &got) == BSP_OK && same_vec(got, v[4]));
    bsp_scene_destroy(s);
}
