/*
 * test_kd_prune.c — the leaf budget's pruning (src/accel/kd_prune.c) on
 * random trees made by hand, against brute force:
 * - the threshold is the least one that meets the budget: the tree pruned
 *   at it has at most the budget's leaves, the tree pruned at the next
 *   smaller saving has more (leaves counted by a plain recursive walk);
 * - the pruned tree keeps exactly the splits that it and its ancestors make
 *   with a saving at or above the threshold, with their planes, and every
 *   collapsed subtree becomes one leaf listing the sorted union of its
 *   leaves' primitives; a tree within the budget is left untouched.
 * (The builds with a budget, their exactness and their determinism are in
 * test_kd_sah.c.)
 */
#include <stdint.h>
#include <stdlib.h>
#include <math.h>
#include <string.h>

#include "accel/kd_prune.h"
#include "harness.h"

static unsigned long long rng;
static uint32_t next_u32(void)
{
    return harness_rnd_u32(&rng);
}

enum { PRIMS = 40 };

/* A random tree: children allocated after their parent, depth-first as
 * the builder does; leaves list 0-4 distinct primitives, sorted; savings
 * drawn from few values (ties) or many. */
typedef struct gen {
    kd_tree t;
    size_t cap_prims;
    int max_depth;
} gen;

static void gen_node(gen *g, uint32_t v, int depth)
{
    kd_tree *t = &g->t;
    if (depth >= g->max_depth || (depth > 1 && next_u32() % 10 < 3)) {
        int present[PRIMS] = {0};
        uint32_t n = next_u32() % 5;
        for (uint32_t i = 0; i < n; i++)
            present[next_u32() % PRIMS] = 1;
        t->nodes[v].u.first = (uint32_t)t->nprims;
        uint32_t c = 0;
        for (uint32_t p = 0; p < PRIMS; p++)
            if (present[p]) {
                t->prims[t->nprims++] = p;
                c++;
            }
        t->nodes[v].bits = kd_pack(c, KD_LEAF_TAG);
        t->saving[v] = -1.0; /* unused at a leaf */
        return;
    }
    uint32_t child = t->nnodes;
    t->nnodes += 2;
    t->nodes[v].u.split = (float)(next_u32() % 1000);
    t->nodes[v].bits = kd_pack(child, next_u32() % 3);
    t->saving[v] = next_u32() % 2 ? (double)(next_u32() % 6) : (double)next_u32() * 1e-6;
    gen_node(g, child, depth + 1);
    gen_node(g, child + 1, depth + 1);
}

static void random_tree(gen *g, uint64_t seed, int max_depth)
{
    memset(g, 0, sizeof *g);
    rng = seed;
    g->max_depth = max_depth;
    size_t most = (size_t)2 << max_depth; /* nodes of a full tree of that depth */
    g->t.nodes = malloc(most * sizeof *g->t.nodes);
    g->t.saving = malloc(most * sizeof *g->t.saving);
    g->t.prims = malloc(most * 4 * sizeof *g->t.prims);
    REQUIRE(g->t.nodes && g->t.saving && g->t.prims);
    g->t.cap_nodes = (uint32_t)most;
    g->t.cap_prims = most * 4;
    g->t.nnodes = 1;
    gen_node(g, 0, 0);
}

/* Leaves of T pruned at THETA, by recursion. */
static size_t leaves_at(const kd_tree *t, uint32_t v, double theta)
{
    const kd_node *x = &t->nodes[v];
    if (kd_is_leaf(x) || !(t->saving[v] >= theta))
        return 1;
    return leaves_at(t, kd_child(x), theta) + leaves_at(t, kd_child(x) + 1, theta);
}

/* Marks the primitives of the leaves under old node V in IN. */
static void mark_prims(const kd_tree *t, uint32_t v, int *in)
{
    const kd_node *x = &t->nodes[v];
    if (!kd_is_leaf(x)) {
        mark_prims(t, kd_child(x), in);
        mark_prims(t, kd_child(x) + 1, in);
        return;
    }
    for (uint32_t i = 0; i < kd_count(x); i++)
        in[t->prims[x->u.first + i]] = 1;
}

/* Whether new node W of P is old node V of T pruned at THETA. */
static int same_pruned(const kd_tree *t, uint32_t v, const kd_tree *p, uint32_t w, double theta)
{
    const kd_node *x = &t->nodes[v], *y = &p->nodes[w];
    if (!kd_is_leaf(x) && t->saving[v] >= theta) {
        return !kd_is_leaf(y) && kd_axis(x) == kd_axis(y) && x->u.split == y->u.split &&
               same_pruned(t, kd_child(x), p, kd_child(y), theta) &&
               same_pruned(t, kd_child(x) + 1, p, kd_child(y) + 1, theta);
    }
    if (!kd_is_leaf(y))
        return 0;
    int in[PRIMS] = {0};
    mark_prims(t, v, in);
    uint32_t c = 0;
    for (uint32_t p_ = 0; p_ < PRIMS; p_++) {
        if (!in[p_])
            continue;
        if (c >= kd_count(y) || p->prims[y->u.first + c] != p_)
            return 0;
        c++;
    }
    return c == kd_count(y);
}

TEST(prune_threshold_is_the_least_that_meets_the_budget)
{
    for (uint64_t seed = 1; seed <= 60; seed++) {
        gen g;
        random_tree(&g, seed * 7919, 3 + (int)(seed % 8));
        kd_tree *t = &g.t;
        size_t all = leaves_at(t, 0, -INFINITY);
        REQUIRE(all == (t->nnodes + 1) / 2);
        size_t budget = 1 + next_u32() % (all + 2);
        double *m = malloc(t->nnodes * sizeof *m), *scratch = malloc(t->nnodes * sizeof *m);
        double *vals = malloc(t->nnodes * sizeof *vals);
        REQUIRE(m && scratch && vals);
        double theta = kd_prune_threshold(t, budget, m, scratch);
        if (budget >= all) {
            CHECK_MSG(theta == -INFINITY, "seed %llu: a tree within the budget has theta %g",
                      (unsigned long long)seed, theta);
        } else {
            size_t kept = leaves_at(t, 0, theta);
            CHECK_MSG(kept <= budget, "seed %llu: %zu leaves at theta %g, budget %zu",
                      (unsigned long long)seed, kept, theta, budget);
            /* every smaller saving of the tree keeps too many leaves, or the
             * same tree (a saving hidden below a smaller one changes nothing) */
            size_t nv = 0;
            for (uint32_t v = 0; v < t->nnodes; v++)
                if (!kd_is_leaf(&t->nodes[v]) && t->saving[v] < theta)
                    vals[nv++] = t->saving[v];
            for (size_t i = 0; i < nv; i++) {
                size_t more = leaves_at(t, 0, vals[i]);
                CHECK_MSG(more > budget || more == kept,
                          "seed %llu: theta %g is not the least: %g keeps %zu <= %zu leaves",
                          (unsigned long long)seed, theta, vals[i], more, budget);
            }
            /* m[v] is the least saving of v's strict ancestors */
            for (uint32_t v = 0; v < t->nnodes; v++) {
                const kd_node *x = &t->nodes[v];
                if (kd_is_leaf(x))
                    continue;
                double want = t->saving[v] < m[v] ? t->saving[v] : m[v];
                CHECK(m[kd_child(x)] == want && m[kd_child(x) + 1] == want);
            }
        }
        /* the pruned tree */
        kd_tree old = *t;
        old.nodes = malloc(t->nnodes * sizeof *old.nodes);
        old.prims = malloc((t->nprims ? t->nprims : 1) * sizeof *old.prims);
        REQUIRE(old.nodes && old.prims);
        memcpy(old.nodes, t->nodes, t->nnodes * sizeof *old.nodes);
        memcpy(old.prims, t->prims, t->nprims * sizeof *old.prims);
        REQUIRE(kd_prune_to_leaves(t, budget, -INFINITY) == 1);
        size_t want_leaves = budget >= all ? all : leaves_at(&old, 0, theta);
        CHECK_MSG((t->nnodes + 1) / 2 == want_leaves, "seed %llu: %u nodes, want %zu leaves",
                  (unsigned long long)seed, t->nnodes, want_leaves);
        CHECK_MSG(same_pruned(&old, 0, t, 0, budget >= all ? -INFINITY : theta),
                  "seed %llu: the pruned tree differs from the brute force's",
                  (unsigned long long)seed);
        if (budget >= all) /* untouched */
            CHECK(t->nnodes == old.nnodes &&
                  !memcmp(t->nodes, old.nodes, t->nnodes * sizeof *t->nodes) &&
                  t->nprims == old.nprims);
        free(old.nodes);
        free(old.prims);
        free(m);
        free(scratch);
        free(vals);
        kd_tree_free(t);
    }
}

/* A copy of random tree T with its nodes and leaf lists deep-copied. */
static kd_tree copy_tree(const kd_tree *t)
{
    kd_tree c = *t;
    c.nodes = malloc(t->nnodes * sizeof *c.nodes);
    c.prims = malloc((t->nprims ? t->nprims : 1) * sizeof *c.prims);
    c.saving = malloc(t->nnodes * sizeof *c.saving);
    REQUIRE(c.nodes && c.prims && c.saving);
    memcpy(c.nodes, t->nodes, t->nnodes * sizeof *c.nodes);
    memcpy(c.prims, t->prims, t->nprims * sizeof *c.prims);
    memcpy(c.saving, t->saving, t->nnodes * sizeof *c.saving);
    c.cap_nodes = t->nnodes;
    return c;
}

/* With a cut, the pruning goes ahead exactly when the splits saving at
 * least the cut (with their ancestors) make more leaves than the budget —
 * then as without the cut — and otherwise answers -1 and leaves the tree. */
TEST(prune_with_a_cut_refuses_where_the_cut_could_matter)
{
    for (uint64_t seed = 1; seed <= 60; seed++) {
        gen g;
        random_tree(&g, seed * 104729, 3 + (int)(seed % 8));
        kd_tree *t = &g.t;
        size_t all = leaves_at(t, 0, -INFINITY);
        size_t budget = 1 + next_u32() % (all + 2);
        /* a cut at one of the tree's savings, or between two */
        double cut = t->saving[0];
        for (uint32_t v = 0; v < t->nnodes; v++)
            if (!kd_is_leaf(&t->nodes[v]) && next_u32() % 4 == 0)
                cut = t->saving[v];
        if (seed % 3 == 0)
            cut *= 0.999;
        int want = leaves_at(t, 0, cut) > budget ? 1 : -1;
        kd_tree plain = copy_tree(t), old = copy_tree(t);
        REQUIRE(kd_prune_to_leaves(&plain, budget, -INFINITY) == 1);
        int got = kd_prune_to_leaves(t, budget, cut);
        CHECK_MSG(got == want, "seed %llu: %d for a cut at %g (%zu leaves there, budget %zu)",
                  (unsigned long long)seed, got, cut, leaves_at(&old, 0, cut), budget);
        if (got == 1)
            CHECK(t->nnodes == plain.nnodes && t->nprims == plain.nprims &&
                  !memcmp(t->nodes, plain.nodes, t->nnodes * sizeof *t->nodes) &&
                  !memcmp(t->prims, plain.prims, t->nprims * sizeof *t->prims));
        else
            CHECK(t->nnodes == old.nnodes &&
                  !memcmp(t->nodes, old.nodes, t->nnodes * sizeof *t->nodes));
        kd_tree_free(&plain);
        kd_tree_free(&old);
        kd_tree_free(t);
    }
}

/* Appends a copy of SUB below leaf L of T (T has room), its root at L. */
static void graft(kd_tree *t, uint32_t l, const kd_tree *sub)
{
    uint32_t base = t->nnodes - 1; /* sub's node j >= 1 goes to base + j */
    size_t pbase = t->nprims;
    for (uint32_t j = 0; j < sub->nnodes; j++) {
        kd_node x = sub->nodes[j];
        if (kd_is_leaf(&x))
            x.u.first += (uint32_t)pbase;
        else
            x.bits = kd_pack(base + kd_child(&x), kd_axis(&x));
        uint32_t to = j == 0 ? l : base + j;
        t->nodes[to] = x;
        t->saving[to] = sub->saving[j];
    }
    t->nnodes = base + sub->nnodes;
    memcpy(t->prims + t->nprims, sub->prims, sub->nprims * sizeof *t->prims);
    t->nprims += sub->nprims;
}

/* The estimate is exact when the unbuilt parts are like the built ones: a
 * top whose every leaf holds the same subtree S. From one built part, or
 * all, it finds a threshold that prunes the whole tree as the threshold of
 * the whole tree does (it may name another saving between the same two). */
TEST(prune_estimate_is_exact_for_parts_alike)
{
    for (uint64_t seed = 1; seed <= 40; seed++) {
        gen top, sub;
        random_tree(&top, seed * 7177, 2 + (int)(seed % 4));
        random_tree(&sub, seed * 6311 + 1, 2 + (int)(seed % 5));
        kd_tree *tt = &top.t, *ts = &sub.t;
        /* the whole tree: the top with S grafted at each of its leaves */
        size_t nleaves = (tt->nnodes + 1) / 2;
        kd_tree whole;
        memset(&whole, 0, sizeof whole);
        size_t cap = tt->nnodes + nleaves * ts->nnodes;
        whole.nodes = malloc(cap * sizeof *whole.nodes);
        whole.saving = malloc(cap * sizeof *whole.saving);
        whole.prims = malloc((nleaves * ts->nprims + 1) * sizeof *whole.prims);
        REQUIRE(whole.nodes && whole.saving && whole.prims);
        memcpy(whole.nodes, tt->nodes, tt->nnodes * sizeof *whole.nodes);
        memcpy(whole.saving, tt->saving, tt->nnodes * sizeof *whole.saving);
        whole.nnodes = tt->nnodes;
        kd_budget_part *parts = malloc(nleaves * sizeof *parts);
        REQUIRE(parts);
        size_t np = 0;
        for (uint32_t v = 0; v < tt->nnodes; v++)
            if (kd_is_leaf(&tt->nodes[v])) {
                parts[np].node = v;
                parts[np].n = 10;
                parts[np].sub = NULL;
                np++;
                graft(&whole, v, ts);
            }
        size_t all = leaves_at(&whole, 0, -INFINITY);
        REQUIRE(all == (whole.nnodes + 1) / 2);
        size_t budget = 1 + next_u32() % (all + 2);
        double *m = malloc(whole.nnodes * sizeof *m), *scratch = malloc(whole.nnodes * sizeof *m);
        REQUIRE(m && scratch);
        double want = kd_prune_threshold(&whole, budget, m, scratch);
        for (int built = 0; built < 2; built++) {
            for (size_t i = 0; i < np; i++)
                parts[i].sub = (built || i == np / 2) ? ts : NULL;
            double got = kd_prune_estimate(tt, parts, np, budget);
            if (want == -INFINITY) {
                CHECK_MSG(got == -INFINITY, "seed %llu: estimate %g for a tree within budget",
                          (unsigned long long)seed, got);
                continue;
            }
            CHECK_MSG(got <= want && leaves_at(&whole, 0, got) == leaves_at(&whole, 0, want),
                      "seed %llu (%s): estimate %g keeps %zu leaves, threshold %g keeps %zu",
                      (unsigned long long)seed, built ? "all built" : "one built", got,
                      leaves_at(&whole, 0, got), want, leaves_at(&whole, 0, want));
        }
        /* nothing built: no estimate */
        for (size_t i = 0; i < np; i++)
            parts[i].sub = NULL;
        CHECK(kd_prune_estimate(tt, parts, np, budget) == -INFINITY);
        free(m);
        free(scratch);
        free(parts);
        kd_tree_free(&whole);
        kd_tree_free(tt);
        kd_tree_free(ts);
    }
}
