/*
 * test_bvh.c — the BVH (`--accel bvh`) beyond the exactness tests it shares
 * with the kd-trees (test_kdtree.c, test_kd_sah.c): its leaf and depth
 * limits, its figures against a hand computation, its visit, and what it
 * refuses.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "bspray/bspray.h"
#include "harness.h"

static bsp_accel *bvh_of(const bsp_scene *s, int leaf_size, int max_depth)
{
    bsp_build_options o;
    bsp_build_options_defaults(&o);
    o.kind = BSP_ACCEL_BVH;
    o.max_leaf_prims = leaf_size;
    o.max_depth = max_depth;
    bsp_accel *a = NULL;
    bsp_error err;
    REQUIRE_MSG(bsp_accel_build(s, &o, &a, &err) == BSP_OK, "%s", err.message);
    CHECK_MSG(bsp_accel_check(a, &err) == BSP_OK, "%s", err.message);
    return a;
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

/* --leaf-size and --max-depth bound the leaves: at most L primitives each
 * (teapot's triangles have distinct centroids), no leaf deeper than the
 * limit; every primitive in exactly one leaf; the options report the
 * limits the build used. */
TEST(bvh_leaves_respect_the_limits)
{
    bsp_scene *s = NULL;
    bsp_error err;
    REQUIRE_MSG(bsp_scene_load("spd:teapot", &s, &err) == BSP_OK, "%s", err.message);
    const uint64_t n = bsp_scene_prim_count(s) - bsp_scene_kind_count(s, BSP_PRIM_DROPPED);
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
    bsp_accel *a = bvh_of(s, 0, 0);
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
    CHECK_STR_CONTAINS(err.message, "bvh");
    bsp_query_destroy(q);
    bsp_accel_destroy(a);
    bsp_scene_destroy(s);
}
