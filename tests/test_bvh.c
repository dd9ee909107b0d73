/*
 * test_bvh.c — the BVHs (`--accel bvh`, `bvh4`, `bvh8`) beyond the exactness tests
 * they share with the kd-trees (test_kdtree.c, test_kd_sah.c): their leaf
 * and depth limits, their figures against a hand computation, their visit,
 * the wide trees' collapse and their float and double paths, the threaded
 * build, and what they refuse.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "accel/bvh.h"
#include "bspray/bspray.h"
#include "harness.h"
#include "same_util.h"

static bsp_accel *bvh_kind_of(const bsp_scene *s, bsp_accel_kind kind, int leaf_size,
                              int max_depth)
{
    bsp_build_options o;
    bsp_build_options_defaults(&o);
    o.kind = kind;
    o.max_leaf_prims = leaf_size;
    o.max_depth = max_depth;
    bsp_accel *a = NULL;
    bsp_error err;
    REQUIRE_MSG(bsp_accel_build(s, &o, &a, &err) == BSP_OK, "%s", err.message);
    CHECK_MSG(bsp_accel_check(a, &err) == BSP_OK, "%s", err.message);
    return a;
}

/* The three BVHs, and the wide ones' widths. */
static const bsp_accel_kind bvh_kinds[] = {BSP_ACCEL_BVH, BSP_ACCEL_BVH4, BSP_ACCEL_BVH8};
static const struct {
    bsp_accel_kind kind;
    unsigned width;
} wide_kinds[] = {{BSP_ACCEL_BVH4, 4}, {BSP_ACCEL_BVH8, 8}};

static bsp_accel *bvh_of(const bsp_scene *s, int leaf_size, int max_depth)
{
    return bvh_kind_of(s, BSP_ACCEL_BVH, leaf_size, max_depth);
}

/* What a visit of every node sees. */
typedef struct visit_tally {
    uint64_t nodes, leaves, refs, largest_leaf;
    int deepest;
    int bad_box; /* a child's box not inside its parent's */
    bsp_box path[64];
} visit_tally;

static int tally(const bsp_cell_info *c, void *ctx)
{
    visit_tally *t = ctx;
    t->nodes++;
    if (c->depth > t->deepest)
        t->deepest = c->depth;
    if (c->depth > 0 && c->depth < 64) {
        const bsp_box *p = &t->path[c->depth - 1];
        for (int k = 0; k < 3; k++)
            if (c->box.lo.v[k] < p->lo.v[k] || c->box.hi.v[k] > p->hi.v[k])
                t->bad_box = 1;
    }
    if (c->depth < 64)
        t->path[c->depth] = c->box;
    if (c->is_leaf) {
        t->leaves++;
        t->refs += c->refs;
        if (c->refs > t->largest_leaf)
            t->largest_leaf = c->refs;
    }
    return 1;
}

/* spd:teapot, and its live primitives in *N. */
static bsp_scene *teapot(uint64_t *n)
{
    bsp_scene *s = NULL;
    bsp_error err;
    REQUIRE_MSG(bsp_scene_load("spd:teapot", &s, &err) == BSP_OK, "%s", err.message);
    *n = bsp_scene_prim_count(s) - bsp_scene_kind_count(s, BSP_PRIM_DROPPED);
    return s;
}

/* --leaf-size and --max-depth bound the leaves: at most L primitives each
 * (teapot's triangles have distinct centroids), no leaf deeper than the
 * limit; every primitive in exactly one leaf; the options report the
 * limits the build used. */
TEST(bvh_leaves_respect_the_limits)
{
    bsp_error err;
    uint64_t n;
    bsp_scene *s = teapot(&n);
    static const struct {
        int leaf, depth;
    } cases[] = {{0, 0}, {1, 0}, {2, 0}, {4, 0}, {0, 4}, {1, 7}};
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        bsp_accel *a = bvh_of(s, cases[i].leaf, cases[i].depth);
        bsp_build_options got;
        bsp_accel_get_options(a, &got);
        int want_leaf = cases[i].leaf ? cases[i].leaf : 8;
        int want_depth = cases[i].depth ? cases[i].depth : 60;
        CHECK_EQ_INT(got.max_leaf_prims, want_leaf);
        CHECK_EQ_INT(got.max_depth, want_depth);
        visit_tally t;
        memset(&t, 0, sizeof t);
        REQUIRE(bsp_accel_visit_cells(a, -1, tally, &t, &err) == BSP_OK);
        bsp_tree_stats st;
        bsp_accel_tree_stats(a, &st);
        CHECK_MSG(t.refs == n && st.references == n, "leaf %d depth %d: %llu / %llu refs of %llu",
                  cases[i].leaf, cases[i].depth, (unsigned long long)t.refs,
                  (unsigned long long)st.references, (unsigned long long)n);
        CHECK(t.leaves == st.leaves && t.nodes == st.leaves + st.interior_nodes);
        CHECK(st.leaves == st.interior_nodes + 1); /* a binary tree */
        CHECK(st.empty_leaves == 0);
        CHECK(t.deepest <= want_depth && st.max_leaf_depth == t.deepest);
        CHECK(!t.bad_box);
        if (!cases[i].depth) /* no depth limit met: every leaf within the size */
            CHECK_MSG(t.largest_leaf <= (uint64_t)want_leaf, "leaf size %d: a leaf of %llu",
                      want_leaf, (unsigned long long)t.largest_leaf);
        else /* the depth limit holds 2^d leaves at most */
            CHECK(st.leaves <= (1u << want_depth));
        bsp_accel_destroy(a);
    }
    bsp_scene_destroy(s);
}

/* Two unit spheres 10 apart, a leaf each: the expected cost is the root's
 * step plus each leaf's surface area over the root's (one test each),
 * 1 + 2 x 24 / 104, to the padding (1e-7 of the scene scale, 11). */
TEST(bvh_expected_cost_matches_hand_computation)
{
    bsp_scene *s = bsp_scene_create();
    bsp_error err;
    REQUIRE(bsp_scene_add_sphere(s, bsp_v3(0, 0, 0), 1.0, &err) == BSP_OK);
    REQUIRE(bsp_scene_add_sphere(s, bsp_v3(10, 0, 0), 1.0, &err) == BSP_OK);
    bsp_accel *a = bvh_of(s, 1, 0);
    bsp_tree_stats st;
    bsp_accel_tree_stats(a, &st);
    CHECK_EQ_INT((int)st.interior_nodes, 1);
    CHECK_EQ_INT((int)st.leaves, 2);
    CHECK_NEAR(st.expected_cost, 1.0 + 2.0 * 24.0 / 104.0, 1e-5);
    CHECK(st.bytes == 32 + 64); /* the root, one pair */
    /* a ray between the spheres meets no leaf; one through both hits the
     * first at t = 4 */
    bsp_query *q = bsp_query_create(a);
    bsp_ray r = {bsp_v3(5, -5, 0), bsp_v3(0, 1, 0), 0.0, INFINITY};
    bsp_hit h;
    CHECK(!bsp_intersect(a, q, &r, &h));
    r = (bsp_ray){bsp_v3(-5, 0, 0), bsp_v3(1, 0, 0), 0.0, INFINITY};
    REQUIRE(bsp_intersect(a, q, &r, &h));
    CHECK_EQ_INT((int)h.prim, 0);
    CHECK_NEAR(h.t, 4.0, 1e-12);
    bsp_query_destroy(q);
    bsp_accel_destroy(a);
    bsp_scene_destroy(s);
}

/* An empty scene builds an empty BVH that answers "no hit"; a BVH is not
 * saved (bspray build refuses with a message). */
TEST(bvh_empty_scene_and_no_save)
{
    bsp_scene *s = bsp_scene_create();
    for (size_t i = 0; i < sizeof bvh_kinds / sizeof bvh_kinds[0]; i++) {
    bsp_accel *a = bvh_kind_of(s, bvh_kinds[i], 0, 0);
    bsp_query *q = bsp_query_create(a);
    bsp_ray r = {bsp_v3(0, 0, -5), bsp_v3(0, 0, 1), 0.0, INFINITY};
    bsp_hit h;
    CHECK(!bsp_intersect(a, q, &r, &h));
    CHECK(!bsp_occluded(a, q, &r));
    bsp_tree_stats st;
    bsp_accel_tree_stats(a, &st);
    CHECK(st.leaves == 0 && st.bytes == 0);
    char path[1024];
    harness_tmp_path(path, sizeof path, "bvh.tree");
    bsp_error err;
    CHECK(bsp_accel_save(a, path, &err) == BSP_ERR_INVALID);
    CHECK_STR_CONTAINS(err.message, bsp_accel_kind_name(bvh_kinds[i]));
    bsp_query_destroy(q);
    bsp_accel_destroy(a);
    }
    bsp_scene_destroy(s);
}

/* The wide trees are the binary one collapsed: on teapot, every interior
 * node of width W has two to W children, more than W / 2 on average, the
 * leaves list every primitive once, children's boxes lie in their
 * parents', and the limits hold as in the binary tree (a wide node's levels
 * count as its depth). */
TEST(bvh_wide_collapse_keeps_leaves_and_limits)
{
    bsp_error err;
    uint64_t n;
    bsp_scene *s = teapot(&n);
    static const struct {
        int leaf, depth;
    } cases[] = {{0, 0}, {1, 0}, {4, 0}, {1, 5}};
    for (size_t wk = 0; wk < sizeof wide_kinds / sizeof wide_kinds[0]; wk++) {
        const uint64_t w = wide_kinds[wk].width;
        for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
            bsp_accel *a = bvh_kind_of(s, wide_kinds[wk].kind, cases[i].leaf, cases[i].depth);
            int want_leaf = cases[i].leaf ? cases[i].leaf : 8;
            int want_depth = cases[i].depth ? cases[i].depth : 60;
            visit_tally t;
            memset(&t, 0, sizeof t);
            REQUIRE(bsp_accel_visit_cells(a, -1, tally, &t, &err) == BSP_OK);
            bsp_tree_stats st;
            bsp_accel_tree_stats(a, &st);
            CHECK(t.refs == n && st.references == n);
            CHECK(t.leaves == st.leaves && t.nodes == st.leaves + st.interior_nodes);
            /* children: every node but the root is one */
            uint64_t children = t.nodes - 1;
            CHECK_MSG(children >= 2 * st.interior_nodes && children <= w * st.interior_nodes &&
                          2 * children > w * st.interior_nodes,
                      "width %u, case %zu: %llu children of %llu interior nodes", (unsigned)w,
                      i, (unsigned long long)children, (unsigned long long)st.interior_nodes);
            CHECK(st.bytes == 32 + 32 * w * st.interior_nodes);
            CHECK(!t.bad_box);
            CHECK(t.deepest <= want_depth);
            if (!cases[i].depth)
                CHECK(t.largest_leaf <= (uint64_t)want_leaf);
            bsp_accel_destroy(a);
        }
    }
    bsp_scene_destroy(s);
}

/* Three unit spheres far apart, a leaf each: the binary tree's two interior
 * nodes become one wide node of three children (its other lanes unused),
 * and a ray hits the nearest sphere. The checker refuses the node once its
 * last unused lane is given a box. */
TEST(bvh_wide_one_node_and_its_unused_lanes)
{
    bsp_scene *s = bsp_scene_create();
    bsp_error err;
    for (int i = 0; i < 3; i++)
        REQUIRE(bsp_scene_add_sphere(s, bsp_v3(10.0 * i, 0, 0), 1.0, &err) == BSP_OK);
    for (size_t wk = 0; wk < sizeof wide_kinds / sizeof wide_kinds[0]; wk++) {
        const unsigned w = wide_kinds[wk].width;
        bsp_accel *a = bvh_kind_of(s, wide_kinds[wk].kind, 1, 0);
        bsp_tree_stats st;
        bsp_accel_tree_stats(a, &st);
        CHECK_EQ_INT((int)st.interior_nodes, 1);
        CHECK_EQ_INT((int)st.leaves, 3);
        CHECK(st.bytes == 32 + 32 * w);
        bsp_query *q = bsp_query_create(a);
        bsp_ray r = {bsp_v3(25, 0, 0), bsp_v3(-1, 0, 0), 0.0, INFINITY};
        bsp_hit h;
        REQUIRE(bsp_intersect(a, q, &r, &h));
        CHECK_EQ_INT((int)h.prim, 2);
        CHECK_NEAR(h.t, 4.0, 1e-12);
        r.org = bsp_v3(5, -5, 0); /* between the spheres, across the row */
        r.dir = bsp_v3(0, 1, 0);
        CHECK(!bsp_intersect(a, q, &r, &h));
        bsp_query_destroy(q);
        bvh *b = a->impl;
        unsigned char *node = bvh_wide_node(b, 0);
        REQUIRE(b->width == w && bvh_wide_index(node, w, 2) != BVH_NONE);
        for (unsigned c = 3; c < w; c++)
            CHECK(bvh_wide_index(node, w, c) == BVH_NONE && bvh_wide_meta(node, w, c) == 0);
        bvh_node lane = bvh_wide_get(node, w, w - 1);
        lane.lo[1] = 0.0f;
        bvh_wide_set(node, w, w - 1, &lane);
        CHECK(bsp_accel_check(a, &err) == BSP_ERR_INVALID);
        CHECK_STR_CONTAINS(err.message, "wide node");
        bsp_accel_destroy(a);
    }
    bsp_scene_destroy(s);
}

/* A uniform number in [0, 1) from the generator *RNG. */
static double next_u(uint64_t *rng)
{
    *rng = *rng * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(*rng >> 11) / 9007199254740992.0;
}

/* The four-wide tree's two paths answer as the naive method: origins just
 * inside and just outside the float tests' range (float_origin) on each
 * axis, on its bound, and near the scene; directions of lengths 1e-90, 1 and
 * 1e90 (the float path scales them by a power of two), some with a zero
 * component; the rays aimed at the vertices of small triangles, which make
 * the faces of the boxes (where a slab test's error would lose a hit), at
 * points on their edges, and inside them; occlusion queries too. */
TEST(bvh_wide_float_and_double_paths_match_naive)
{
    for (size_t wk = 0; wk < sizeof wide_kinds / sizeof wide_kinds[0]; wk++) {
    bsp_scene *s = bsp_scene_create();
    bsp_error err;
    enum { NTRI = 1500 };
    static bsp_vec3 v[3 * NTRI];
    uint64_t rng = 12345;
    for (int i = 0; i < NTRI; i++) {
        double c[3], e[3];
        for (int k = 0; k < 3; k++)
            c[k] = 2 * next_u(&rng) - 1;
        for (int j = 0; j < 3; j++) {
            for (int k = 0; k < 3; k++)
                e[k] = c[k] + 0.02 * next_u(&rng);
            v[3 * i + j] = bsp_v3(e[0], e[1], e[2]);
        }
        REQUIRE(bsp_scene_add_polygon(s, &v[3 * i], 3, &err) == BSP_OK);
    }
    bsp_accel *a = bvh_kind_of(s, wide_kinds[wk].kind, 0, 0);
    bsp_build_options o;
    bsp_build_options_defaults(&o);
    o.kind = BSP_ACCEL_NAIVE;
    bsp_accel *nv = NULL;
    REQUIRE(bsp_accel_build(s, &o, &nv, &err) == BSP_OK);
    const bvh *b = a->impl;
    REQUIRE(b->float_origin > 0.0);
    bsp_query *qa = bsp_query_create(a), *qn = bsp_query_create(nv);
    int rays = 0, hits = 0, bad = 0;
    for (int i = 0; i < 12000 && bad < 5; i++) {
        /* the target: a vertex, a point on an edge, or inside a triangle */
        const bsp_vec3 *t = &v[3 * (int)(next_u(&rng) * NTRI)];
        double w1 = next_u(&rng), w2 = next_u(&rng);
        int where = i % 3;
        if (where == 0)
            w1 = w2 = 0.0;
        else if (where == 1)
            w2 = 0.0;
        else if (w1 + w2 > 1.0)
            w1 = 1.0 - w1, w2 = 1.0 - w2;
        double p[3], org[3];
        for (int k = 0; k < 3; k++) {
            p[k] = t[0].v[k] + w1 * (t[1].v[k] - t[0].v[k]) + w2 * (t[2].v[k] - t[0].v[k]);
            org[k] = p[k];
        }
        int axis = (i / 3) % 3, kase = (i / 9) % 4;
        double side = (i / 36) % 2 ? 1.0 : -1.0;
        if (kase == 0) /* just inside the float range */
            org[axis] = side * nextafter(b->float_origin, 0.0);
        else if (kase == 1) /* just outside: the double tests */
            org[axis] = side * nextafter(b->float_origin, INFINITY);
        else if (kase == 2) /* exactly on its bound */
            org[axis] = side * b->float_origin;
        else /* near the scene, beside the target */
            org[axis] += side * 0.5;
        /* off the axis a little, so that the rays cross the boxes' faces */
        org[(axis + 1) % 3] += (next_u(&rng) - 0.5) * (kase == 3 ? 0.5 : b->float_origin);
        double d[3] = {p[0] - org[0], p[1] - org[1], p[2] - org[2]};
        if ((i / 72) % 3 == 1) /* one zero component (the ray misses or grazes) */
            d[(axis + 2) % 3] = 0.0;
        double len = (i / 216) % 3 == 0 ? 1e-90 : (i / 216) % 3 == 1 ? 1.0 : 1e90;
        double norm = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        if (!(norm > 0.0))
            continue;
        bsp_ray r = {bsp_v3(org[0], org[1], org[2]),
                     bsp_v3(d[0] / norm * len, d[1] / norm * len, d[2] / norm * len), 0.0,
                     INFINITY};
        bsp_hit ha, hn;
        int xa = bsp_intersect(a, qa, &r, &ha), xn = bsp_intersect(nv, qn, &r, &hn);
        rays++;
        hits += xn;
        if (!same_hit(xa, &ha, xn, &hn) ||
            bsp_occluded(a, qa, &r) != bsp_occluded(nv, qn, &r)) {
            bad++;
            CHECK_MSG(0, "ray %d (case %d, length %g): width %u %d prim %u t %.17g, naive %d prim %u t %.17g",
                      i, kase, len, wide_kinds[wk].width, xa, ha.prim, ha.t, xn, hn.prim, hn.t);
        }
    }
    CHECK(bad == 0);
    CHECK_MSG(hits > rays / 2, "%d hits of %d rays: the rays should mostly hit", hits, rays);
    bsp_query_destroy(qa);
    bsp_query_destroy(qn);
    bsp_accel_destroy(nv);
    bsp_accel_destroy(a);
    bsp_scene_destroy(s);
    }
}

/* The threaded build (bvh_build.c: subtrees deferred as tasks) gives the
 * same bytes on 1 and 3 threads — the root, every pair or quad, the
 * records' order — and those trees answer as the naive method. The scenes
 * have more than 2 BVH_TASK_FLOOR primitives, so most of their tree is
 * built in tasks. */
TEST(bvh_build_is_deterministic)
{
    const char *specs[] = {"spd:tetra:7", "spd:balls:5"};
    const size_t nspecs = getenv("BSPRAY_TEST_QUICK") ? 1 : 2;
    for (size_t i = 0; i < nspecs; i++) {
        bsp_scene *s = NULL;
        bsp_error err;
        REQUIRE_MSG(bsp_scene_load(specs[i], &s, &err) == BSP_OK, "%s", err.message);
        REQUIRE(bsp_scene_prim_count(s) >= 2 * 4096);
        for (size_t kind = 0; kind < sizeof bvh_kinds / sizeof bvh_kinds[0]; kind++) {
            const char *name = bsp_accel_kind_name(bvh_kinds[kind]);
            bsp_accel *acc[2];
            for (int v = 0; v < 2; v++) {
                bsp_build_options o;
                bsp_build_options_defaults(&o);
                o.kind = bvh_kinds[kind];
                o.threads = v ? 3 : 1;
                REQUIRE_MSG(bsp_accel_build(s, &o, &acc[v], &err) == BSP_OK, "%s", err.message);
                CHECK_MSG(bsp_accel_check(acc[v], &err) == BSP_OK, "%s", err.message);
            }
            const bvh *a = acc[0]->impl, *b = acc[1]->impl;
            REQUIRE(a->nnodes == b->nnodes && a->nrec == b->nrec && a->width == b->width);
            CHECK(memcmp(&a->root, &b->root, sizeof a->root) == 0);
            const int wide = a->width != 2;
            const size_t node_bytes = wide ? (a->nnodes - 1) / a->width * BVH_WIDE_BYTES(a->width)
                                           : (a->nnodes - 2) / 2 * sizeof(bvh_pair);
            const void *na = wide ? (const void *)a->wide : (const void *)a->pairs;
            const void *nb = wide ? (const void *)b->wide : (const void *)b->pairs;
            CHECK_MSG(memcmp(na, nb, node_bytes) == 0, "%s %s: node arrays differ", specs[i],
                      name);
            uint32_t differ = 0;
            for (uint32_t r = 0; r < a->nrec; r++)
                differ += a->rec[r].prim != b->rec[r].prim;
            CHECK_MSG(differ == 0, "%s: %u records in another order", specs[i], differ);
            /* the threaded tree against the naive method on random rays */
            bsp_build_options o;
            bsp_build_options_defaults(&o);
            o.kind = BSP_ACCEL_NAIVE;
            bsp_accel *nv = NULL;
            REQUIRE(bsp_accel_build(s, &o, &nv, &err) == BSP_OK);
            bsp_query *qa = bsp_query_create(acc[1]), *qn = bsp_query_create(nv);
            REQUIRE(qa && qn);
            const bsp_box box = bsp_scene_bounds(s);
            uint64_t rng = 99 + i;
            int bad = 0, hits = 0;
            for (int j = 0; j < 3000; j++) {
                double org[3], d[3];
                for (int k = 0; k < 3; k++) {
                    double ext = box.hi.v[k] - box.lo.v[k];
                    org[k] = box.lo.v[k] - 0.2 * ext + 1.4 * ext * next_u(&rng);
                    d[k] = 2 * next_u(&rng) - 1;
                }
                if (j % 5 == 0)
                    d[j % 3] = 0.0; /* a zero component */
                bsp_ray r = {bsp_v3(org[0], org[1], org[2]), bsp_v3(d[0], d[1], d[2]), 0.0,
                             INFINITY};
                bsp_hit ha, hn;
                int xa = bsp_intersect(acc[1], qa, &r, &ha), xn = bsp_intersect(nv, qn, &r, &hn);
                hits += xn;
                bad += !same_hit(xa, &ha, xn, &hn) ||
                       bsp_occluded(acc[1], qa, &r) != bsp_occluded(nv, qn, &r);
            }
            CHECK_MSG(bad == 0, "%s %s: %d of 3000 rays differ from naive", specs[i], name,
                      bad);
            CHECK_MSG(hits > 300, "%s: only %d rays hit", specs[i], hits);
            bsp_query_destroy(qa);
            bsp_query_destroy(qn);
            bsp_accel_destroy(nv);
            bsp_accel_destroy(acc[0]);
            bsp_accel_destroy(acc[1]);
        }
        bsp_scene_destroy(s);
    }
}
