/*
 * test_kd_walk.c — the traversal's copy of the nodes (src/accel/kd_walk.h):
 * the built tree node for node, pairs at even indices, a flag on exactly the
 * children that are empty leaves; the checker refuses a copy that differs;
 * and the traversal that skips empty near children still visits every
 * non-empty leaf a ray passes through (counted against a brute force over
 * every leaf's box).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "accel/kd_walk.h"
#include "harness.h"
#include "kd_test_util.h"

typedef struct mirror {
    const kd_tree *t;
    size_t bad, flagged, interior;
    uint8_t *met; /* walk nodes reached */
} mirror;

/* Compares tree node TI with walk node WI and their subtrees, recursively. */
static void mirror_node(mirror *m, uint32_t ti, uint32_t wi)
{
    const kd_node *n = &m->t->nodes[ti], *w = &m->t->walk[wi];
    m->met[wi]++;
    if (kd_is_leaf(n)) {
        m->bad += memcmp(n, w, sizeof *n) != 0;
        return;
    }
    m->interior++;
    float sn, sw;
    memcpy(&sn, &n->u, sizeof sn);
    memcpy(&sw, &w->u, sizeof sw);
    uint32_t c = (w->bits >> 4) << 1; /* the pair's index: bits over 16, times 2 */
    const kd_node *kids = &m->t->nodes[kd_child(n)];
    int le = kd_is_leaf(&kids[0]) && kd_count(&kids[0]) == 0;
    int re = kd_is_leaf(&kids[1]) && kd_count(&kids[1]) == 0;
    if (kd_is_leaf(w) || (w->bits & 3u) != kd_axis(n) || memcmp(&sn, &sw, sizeof sn) != 0 ||
        !!(w->bits & 4u) != le || !!(w->bits & 8u) != re || c < 2 || c + 1 >= m->t->nwalk) {
        m->bad++;
        return;
    }
    m->flagged += (size_t)(le + re);
    mirror_node(m, kd_child(n), c);
    mirror_node(m, kd_child(n) + 1, c + 1);
}

/* Every scene kind with both rules: the walk is the tree again, node for
 * node, every walk node but the spare met once, the spare an empty leaf,
 * and the flags where this test finds empty children. */
static void mirror_tree(const bsp_scene *s, const bsp_accel *a, const char *spec, size_t scene,
                        size_t kind, void *ctx)
{
    (void)s, (void)scene, (void)kind, (void)ctx;
    const kd_tree *t = a->impl;
    REQUIRE(t->walk && t->nwalk == t->nnodes + 1);
    mirror m = {t, 0, 0, 0, calloc(t->nwalk, 1)};
    REQUIRE(m.met);
    mirror_node(&m, 0, 0);
    size_t once = 0;
    for (uint32_t i = 0; i < t->nwalk; i++)
        once += m.met[i] == 1;
    CHECK_MSG(m.bad == 0, "%s: %zu walk nodes differ", spec, m.bad);
    CHECK_MSG(once == t->nwalk - 1 && m.met[KD_WALK_SPARE] == 0,
              "%s: %zu of %u walk nodes met once", spec, once, t->nwalk);
    CHECK(kd_is_leaf(&t->walk[KD_WALK_SPARE]) && kd_count(&t->walk[KD_WALK_SPARE]) == 0);
    /* SAH trees cut off empty space; Kaplan's have empty octants */
    CHECK_MSG(m.flagged > 0, "%s: no empty child among %zu interior nodes", spec, m.interior);
    CHECK_MSG(kd_test_accepted(a), "%s: the checker refuses the tree", spec);
    free(m.met);
}

TEST(kd_walk_mirrors_the_tree_with_empty_child_flags)
{
    const char *specs[] = {"spd:mount:2", "spd:gears:2", "spd:rings:2", "spd:sample"};
    kd_test_each_tree(specs, sizeof specs / sizeof *specs, mirror_tree, NULL);
}

/* A flag cleared, a flag set on a child that is not an empty leaf, a split
 * one ulp off, a pair moved to an odd index, a spare leaf that lists
 * something: each is refused, and accepted again once restored. */
TEST(kd_walk_check_refuses_a_wrong_walk)
{
    bsp_scene *s = kd_test_load("spd:mount:2");
    bsp_accel *a = kd_test_build(s, BSP_ACCEL_SAH);
    kd_tree *t = a->impl;
    REQUIRE(kd_test_accepted(a));
    uint32_t flagged = UINT32_MAX, plain = UINT32_MAX;
    for (uint32_t i = 0; i < t->nwalk; i++) {
        const kd_node *w = &t->walk[i];
        if (kd_is_leaf(w))
            continue;
        if ((w->bits & 12u) && flagged == UINT32_MAX)
            flagged = i;
        if (!(w->bits & 12u) && plain == UINT32_MAX)
            plain = i;
    }
    REQUIRE(flagged != UINT32_MAX && plain != UINT32_MAX);

    kd_node keep = t->walk[flagged];
    t->walk[flagged].bits &= ~12u;
    CHECK(!kd_test_accepted(a));
    t->walk[flagged] = keep;
    CHECK(kd_test_accepted(a));

    keep = t->walk[plain];
    t->walk[plain].bits |= 4u;
    CHECK(!kd_test_accepted(a));
    t->walk[plain] = keep;
    CHECK(kd_test_accepted(a));

    t->walk[plain].u.first ^= 1; /* the split's lowest bit */
    CHECK(!kd_test_accepted(a));
    t->walk[plain] = keep;
    CHECK(kd_test_accepted(a));

    /* the pair of PLAIN's children copied one node up into the spare's
     * place and the next (an odd index); PLAIN names it */
    uint32_t c = (keep.bits >> 4) << 1;
    if (c == 2) {
        kd_node save[3] = {t->walk[1], t->walk[2], t->walk[3]};
        t->walk[1] = save[1];
        t->walk[2] = save[2];
        t->walk[plain].bits = (keep.bits & 15u) | (1u << KD_INDEX_SHIFT);
        CHECK(!kd_test_accepted(a));
        t->walk[1] = save[0];
        t->walk[2] = save[1];
        t->walk[3] = save[2];
        t->walk[plain] = keep;
        CHECK(kd_test_accepted(a));
    }

    keep = t->walk[KD_WALK_SPARE];
    t->walk[KD_WALK_SPARE].bits = kd_pack(1, KD_LEAF_TAG);
    CHECK(!kd_test_accepted(a));
    t->walk[KD_WALK_SPARE] = keep;
    CHECK(kd_test_accepted(a));

    bsp_accel_destroy(a);
    bsp_scene_destroy(s);
}

/* --- every non-empty leaf on the ray is visited ----------------------------- */

typedef struct leaf_count {
    const kd_tree *t;
    const bsp_ray *ray;
    size_t nonempty, empty;
} leaf_count;

/* The length in t of the ray's segment [tmin, tmax] inside BOX (negative:
 * they do not meet). */
static double segment_in_box(const bsp_ray *ray, bsp_box box)
{
    double a = ray->tmin, b = ray->tmax;
    for (int k = 0; k < 3; k++) {
        double o = ray->org.v[k], d = ray->dir.v[k];
        double ta = (box.lo.v[k] - o) / d, tb = (box.hi.v[k] - o) / d;
        if (ta > tb) {
            double x = ta;
            ta = tb;
            tb = x;
        }
        a = ta > a ? ta : a;
        b = tb < b ? tb : b;
    }
    return b - a;
}

/* Counts the leaves under node I (cell BOX) whose box the ray's segment
 * crosses over a positive length (well over rounding: the rays are random,
 * so none grazes a cell's edge). */
static void count_leaves(leaf_count *c, uint32_t i, bsp_box box)
{
    const kd_node *n = &c->t->nodes[i];
    double len = segment_in_box(c->ray, box);
    if (len < 0.0)
        return;
    if (!kd_is_leaf(n)) {
        unsigned ax = kd_axis(n);
        bsp_box l = box, r = box;
        l.hi.v[ax] = n->u.split;
        r.lo.v[ax] = n->u.split;
        count_leaves(c, kd_child(n), l);
        count_leaves(c, kd_child(n) + 1, r);
        return;
    }
    if (len > 1e-9) {
        if (kd_count(n))
            c->nonempty++;
        else
            c->empty++;
    }
}

static double uniform(uint64_t *state)
{
    *state = *state * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(*state >> 11) * (1.0 / 9007199254740992.0);
}

/* Rays that hit nothing pass through every cell of their segment (half of
 * them the whole line, half a twentieth of the scene): the traversal's
 * counts of non-empty and of empty leaves must be exactly the brute force's,
 * the empty near children it skips without a visit included (cells
 * traversed, as Havran counts them). Random origins in and around the scene
 * box, random directions with no zero component, so no segment runs along a
 * plane. */
static void visit_check(const bsp_scene *s, const bsp_accel *a, const char *spec, size_t scene,
                        size_t kind, void *ctx)
{
    (void)s;
    size_t *empties = ctx;
    const kd_tree *t = a->impl;
    bsp_query *q = bsp_query_create(a);
    REQUIRE(q);
    bsp_vec3 lo = t->box.lo, hi = t->box.hi;
    double diag = sqrt((hi.x - lo.x) * (hi.x - lo.x) + (hi.y - lo.y) * (hi.y - lo.y) +
                       (hi.z - lo.z) * (hi.z - lo.z));
    uint64_t rng = 12345 + scene;
    size_t misses = 0, bad = 0;
    for (int i = 0; i < 4000; i++) {
        bsp_ray ray;
        for (int k = 0; k < 3; k++) {
            double ext = hi.v[k] - lo.v[k];
            ray.org.v[k] = lo.v[k] - 0.2 * ext + 1.4 * ext * uniform(&rng);
            double d = 2.0 * uniform(&rng) - 1.0;
            ray.dir.v[k] = fabs(d) < 1e-3 ? 0.5 : d;
        }
        ray.tmin = 0.0;
        ray.tmax = (i & 1) ? INFINITY : 0.05 * diag; /* half: short segments */
        bsp_hit h;
        bsp_query_reset_counters(q);
        if (bsp_intersect(a, q, &ray, &h))
            continue;
        const bsp_query_counters *qc = bsp_query_get_counters(q);
        leaf_count c = {t, &ray, 0, 0};
        count_leaves(&c, 0, t->box);
        if (qc->leaves_visited == 0 && c.nonempty + c.empty == 0)
            continue; /* misses the box */
        misses++;
        uint64_t nonempty = qc->leaves_visited - qc->empty_leaves;
        bad += nonempty != c.nonempty || qc->empty_leaves != c.empty;
        empties[kind] += c.empty;
    }
    CHECK_MSG(misses > 1000, "%s: %zu rays through the box hit nothing", spec, misses);
    CHECK_MSG(bad == 0, "%s (%s): %zu of %zu rays visit other leaves than the brute force", spec,
              kind ? "kaplan" : "sah", bad, misses);
    bsp_query_destroy(q);
}

TEST(kd_traversal_counts_every_leaf_on_the_ray)
{
    const char *specs[] = {"spd:mount:1", "spd:rings:1", "spd:balls:2", "spd:tetra:2"};
    size_t empties[2] = {0, 0};
    kd_test_each_tree(specs, sizeof specs / sizeof *specs, visit_check, empties);
    CHECK_MSG(empties[0] > 1000 && empties[1] > 1000, "empty leaves met: sah %zu, kaplan %zu",
              empties[0], empties[1]);
}
