/*
 * kd_prune.c — the leaf budget of the SAH builders: a built tree with more
 * leaves than the budget loses its least valuable splits.
 *
 * Why. The SAH builder splits while a split pays in the cost model, which
 * counts traversal steps and intersection tests but not the memory they
 * read. On large meshes that makes trees of 5-13 leaves per primitive whose
 * deepest splits save almost nothing, and a tree of 10^6 nodes no longer
 * fits in the caches: teapot:60 renders 10 % faster with a third of its
 * leaves (docs/kdtree-log.md, session 19). A least saving per split
 * (sah_min_saving) prunes the same splits, but one threshold for every
 * scene is too much for some (tree: its ground polygon dominates the root
 * box, so the plant's cells look cheap) and too little for others; the
 * budget finds the threshold of each tree.
 *
 * What a split is worth. The builder records each split's saving per ray
 * of the root: its cell's surface area over the root's, times the leaf's
 * cost less the split's (the greedy estimate the split was chosen by; for a
 * speculative split, its subtree's actual saving) — the very quantity
 * sah_min_saving bounds. Why not the subtree's whole saving, with the
 * cost-complexity pruning of CART? Tried: on shells (nested spheres), whose
 * rays end at the first shell they meet, the SAH, blind to that, judged
 * deep subtrees nearly worthless and the pruned tree rendered 26-30 % slower;
 * the split-by-split saving prunes shells:6 to 64 % of its leaves for 0.7 %.
 *
 * The pruning. For a threshold theta, the tree keeps a split when it and
 * all its ancestors save at least theta; a split below theta becomes a
 * leaf of the primitives of its subtree's leaves (each once, sorted) — the
 * tree the builder would have made with sah_min_saving = theta, less its
 * speculative splits' subtleties. With m(v) the least saving among node v's
 * strict ancestors, v stays iff m(v) >= theta, so the least theta that
 * keeps at most 2B - 1 nodes (B leaves) is found by one selection over
 * m, O(nodes). Then the tree is written anew: nodes in depth-first order
 * with adjacent children. A collapsed subtree's leaf lists the primitives
 * its root held, less those its splits found outside every child cell, so
 * the conservative assignment invariant (kd_tree.h) still holds.
 *
 * The estimate (kd_prune_estimate). The SAH builder need not make the
 * splits the prune will remove: it estimates theta from the top of the tree
 * and a sample of its subtrees, builds the rest without the splits saving
 * less than a share of the estimate, and kd_prune_to_leaves then checks
 * that this cut lay below theta (docs/kdtree-log.md, session 20).
 *
 * Children always have larger indices than their parent (the builder and
 * the splice of parallel subtrees allocate pairs after their parent), so
 * one pass in index order visits parents first.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "accel/kd_prune.h"
#include "util/bigmem.h"
#include "util/sort_doubles.h"
#include "util/sorted_count.h"

/* The value of rank K (0-based) in A[0..N) sorted in decreasing order
 * (K < N); reorders A. Quickselect with a median-of-three pivot and a
 * three-way partition, so that runs of equal values (siblings share theirs)
 * cost nothing extra. */
static double select_desc(double *a, size_t n, size_t k)
{
    size_t lo = 0, hi = n; /* the rank lies in a[lo..hi) */
    for (;;) {
        double x = a[lo], y = a[lo + (hi - lo) / 2], z = a[hi - 1];
        double pivot = x > y ? (y > z ? y : (x > z ? z : x)) : (x > z ? x : (y > z ? z : y));
        size_t gt = lo, i = lo,
               lt = hi; /* a[lo..gt) > pivot, a[gt..i) == pivot, a[lt..hi) < pivot */
        while (i < lt) {
            double v = a[i];
            if (v > pivot) {
                a[i++] = a[gt];
                a[gt++] = v;
            } else if (v < pivot) {
                a[i] = a[--lt];
                a[lt] = v;
            } else {
                i++;
            }
        }
        if (k < gt)
            hi = gt;
        else if (k >= lt)
            lo = lt;
        else
            return pivot;
    }
}

/* Writing the pruned tree: the old tree T, the threshold, the new arrays. */
typedef struct prune_out {
    const kd_tree *t;
    double theta; /* a split saving less becomes a leaf */
    kd_node *nodes;
    uint32_t nnodes;
    uint32_t *prims;
    size_t nprims;
} prune_out;

/* Appends the leaf list of old node V, or the union of its subtree's leaf
 * lists when it is interior, as new node TO. */
static void write_leaf(prune_out *o, uint32_t v, uint32_t to)
{
    const kd_tree *t = o->t;
    size_t first = o->nprims;
    uint32_t stack[BSP_KD_MAX_DEPTH_LIMIT + 2]; /* depth-first: one pending sibling per level */
    size_t top = 0;
    stack[top++] = v;
    while (top > 0) {
        const kd_node *x = &t->nodes[stack[--top]];
        if (kd_is_leaf(x)) {
            uint32_t c = kd_count(x);
            memcpy(o->prims + o->nprims, t->prims + x->u.first, c * sizeof *o->prims);
            o->nprims += c;
        } else {
            stack[top++] = kd_child(x) + 1;
            stack[top++] = kd_child(x);
        }
    }
    size_t n = o->nprims - first;
    if (!kd_is_leaf(&t->nodes[v]))
        n = kd_sort_unique_prims(o->prims + first, n);
    o->nprims = first + n;
    o->nodes[to].u.first = (uint32_t)first;
    o->nodes[to].bits = kd_pack((uint32_t)n, KD_LEAF_TAG);
}

/* Writes old node V's pruned subtree as new node TO, depth-first. */
static void write_node(prune_out *o, uint32_t v, uint32_t to)
{
    const kd_node *x = &o->t->nodes[v];
    if (kd_is_leaf(x) || !(o->t->saving[v] >= o->theta)) {
        write_leaf(o, v, to);
        return;
    }
    uint32_t c = o->nnodes;
    o->nnodes += 2;
    o->nodes[to].u.split = x->u.split;
    o->nodes[to].bits = kd_pack(c, kd_axis(x));
    write_node(o, kd_child(x), c);
    write_node(o, kd_child(x) + 1, c + 1);
}

/* Appends to OUT the value of each interior node of T (its saving and its
 * strict ancestors' least, min(s_v, m(v))), the root's chain being ROOT_M;
 * leaves M[v] = m(v) for every node. Returns the count appended. */
static size_t chain_values(const kd_tree *t, double root_m, double *m, double *out)
{
    size_t k = 0;
    m[0] = root_m;
    for (uint32_t v = 0; v < t->nnodes; v++) {
        const kd_node *x = &t->nodes[v];
        if (kd_is_leaf(x))
            continue;
        double s = t->saving[v];
        double below = s < m[v] ? s : m[v]; /* NaN would keep nothing below */
        m[kd_child(x)] = m[kd_child(x) + 1] = below;
        out[k++] = below;
    }
    return k;
}

double kd_prune_threshold(const kd_tree *t, size_t max_leaves, double *m, double *scratch)
{
    size_t pairs = (max_leaves > 0 ? max_leaves : 1) - 1; /* child pairs kept */
    if (2 * pairs + 1 >= t->nnodes)
        return -INFINITY;
    /* the value of each pair of children (both share it), gathered in
     * SCRATCH: the rank of the first pair that must go is PAIRS */
    size_t np = chain_values(t, INFINITY, m, scratch);
    double q = select_desc(scratch, np, pairs); /* the first value that must go */
    double theta = INFINITY;                    /* the least value above q */
    for (size_t i = 0; i < pairs; i++)          /* select_desc left them in front */
        if (scratch[i] > q && scratch[i] < theta)
            theta = scratch[i];
    return theta;
}

int kd_prune_to_leaves(kd_tree *t, size_t max_leaves, double cut)
{
    size_t leaves = ((size_t)t->nnodes + 1) / 2; /* a full binary tree */
    if (!t->saving)
        return 1;
    if (leaves <= max_leaves)
        return cut > -INFINITY ? -1 : 1;
    double *m = bigmem_malloc((size_t)t->nnodes * sizeof *m);
    double *scratch = bigmem_malloc((size_t)t->nnodes * sizeof *scratch);
    if (!m || !scratch) {
        free(m);
        free(scratch);
        return 0;
    }
    double theta = kd_prune_threshold(t, max_leaves, m, scratch);
    if (cut > -INFINITY) {
        /* the tree the cut would have kept (its leaves: 1 + the interior
         * nodes whose values, in SCRATCH, reach it) must exceed the budget */
        size_t interior = ((size_t)t->nnodes - 1) / 2, above = 0;
        for (size_t i = 0; i < interior; i++)
            above += scratch[i] >= cut;
        if (above + 1 <= max_leaves) {
            free(m);
            free(scratch);
            return -1;
        }
    }
    size_t kept = 2 * (max_leaves > 0 ? max_leaves : 1) - 1; /* at most */
    free(m);
    free(scratch);
    prune_out o = {t, theta, NULL, 1, NULL, 0};
    o.nodes = bigmem_malloc((kept ? kept : 1) * sizeof *o.nodes);
    o.prims = bigmem_malloc((t->nprims ? t->nprims : 1) * sizeof *o.prims);
    if (!o.nodes || !o.prims) {
        free(o.nodes);
        free(o.prims);
        return 0;
    }
    write_node(&o, 0, 0);
    free(t->nodes);
    free(t->prims);
    t->nodes = o.nodes;
    t->nnodes = t->cap_nodes = o.nnodes;
    t->prims = o.prims;
    t->nprims = o.nprims;
    t->cap_prims = t->nprims ? t->nprims : 1;
    return 1;
}

/* --- the estimate of the threshold from a built sample ------------------------------------- */

typedef struct estimate_sets {
    double *top, *exact, *pooled; /* sorted ascending */
    size_t ntop, nexact, npooled;
    double *chain;   /* unbuilt parts: their chains' least saving, ascending */
    double *weight;  /* weight[i]: the primitives of the unbuilt parts with chain >= chain[i] */
    size_t nunbuilt;
    double built_n;  /* the built parts' primitives */
} estimate_sets;

/* The estimated leaves of the tree pruned at THETA. */
static double leaves_at(const estimate_sets *e, double theta)
{
    double c = 1.0 + (double)sorted_count_at_least(e->top, e->ntop, theta) +
               (double)sorted_count_at_least(e->exact, e->nexact, theta);
    size_t u = sorted_count_at_least(e->chain, e->nunbuilt, theta);
    if (u > 0)
        c += e->weight[e->nunbuilt - u] / e->built_n *
             (double)sorted_count_at_least(e->pooled, e->npooled, theta);
    return c;
}

double kd_prune_estimate(const kd_tree *top, const kd_budget_part *parts, size_t np,
                         size_t max_leaves)
{
    size_t nodes = top->nnodes, values = top->nnodes;
    double built_n = 0.0;
    size_t nunbuilt = 0;
    for (size_t i = 0; i < np; i++) {
        if (parts[i].sub) {
            nodes = parts[i].sub->nnodes > nodes ? parts[i].sub->nnodes : nodes;
            values += 2 * (size_t)parts[i].sub->nnodes;
            built_n += (double)parts[i].n;
        } else {
            nunbuilt++;
        }
    }
    if (!(built_n > 0.0))
        return -INFINITY;
    estimate_sets e;
    memset(&e, 0, sizeof e);
    double *m = bigmem_malloc(nodes * sizeof *m), *mtop = bigmem_malloc(top->nnodes * sizeof *mtop);
    double *buf = bigmem_malloc(values * sizeof *buf);
    double *chain = malloc((nunbuilt + 1) * 2 * sizeof *chain);
    /* the radix sort's scratch, as long as the longest set (at most VALUES;
     * the chains are fewer than the top's values) */
    uint64_t *tmp = bigmem_malloc(values * sizeof *tmp);
    double theta = 0.0;
    if (!m || !mtop || !buf || !chain || !tmp)
        goto out;
    e.top = buf;
    e.ntop = chain_values(top, INFINITY, mtop, e.top);
    e.exact = e.top + e.ntop;
    for (size_t i = 0; i < np; i++) /* within the part, then under the top's chain */
        if (parts[i].sub) {
            size_t k = chain_values(parts[i].sub, mtop[parts[i].node], m, e.exact + e.nexact);
            e.nexact += k;
        }
    e.pooled = e.exact + e.nexact;
    for (size_t i = 0; i < np; i++)
        if (parts[i].sub)
            e.npooled += chain_values(parts[i].sub, INFINITY, m, e.pooled + e.npooled);
    /* the unbuilt parts by chain, with the primitives of those at or above each */
    e.chain = chain;
    e.weight = chain + nunbuilt + 1;
    for (size_t i = 0; i < np; i++)
        if (!parts[i].sub)
            e.chain[e.nunbuilt++] = mtop[parts[i].node];
    sort_doubles(e.chain, e.nunbuilt, tmp);
    {
        /* each part's n at its chain's first place in the sorted array (parts
         * of equal chains share it), then suffix sums */
        double *w = e.weight;
        for (size_t i = 0; i < e.nunbuilt; i++)
            w[i] = 0.0;
        for (size_t i = 0; i < np; i++)
            if (!parts[i].sub)
                w[e.nunbuilt - sorted_count_at_least(e.chain, e.nunbuilt, mtop[parts[i].node])] +=
                    (double)parts[i].n;
        for (size_t i = e.nunbuilt; i-- > 1;)
            w[i - 1] += w[i];
    }
    e.built_n = built_n;
    /* every value counts at -inf, sorted or not: a tree estimated within its
     * budget needs no sorting */
    if (leaves_at(&e, -INFINITY) <= (double)max_leaves) {
        theta = -INFINITY;
        goto out;
    }
    sort_doubles(e.top, e.ntop, tmp);
    sort_doubles(e.exact, e.nexact, tmp);
    sort_doubles(e.pooled, e.npooled, tmp);
    /* the least candidate theta at which the estimate meets the budget: the
     * count changes only at the values (the chains are values of the top),
     * and it falls as theta grows, so a search of each sorted set finds its
     * least such value, and the least of the three is the answer */
    theta = INFINITY;
    const double *set[3] = {e.top, e.exact, e.pooled};
    const size_t nset[3] = {e.ntop, e.nexact, e.npooled};
    for (int k = 0; k < 3; k++) {
        size_t lo = 0, hi = nset[k]; /* the estimate meets the budget at set[k][hi..) */
        while (lo < hi) {
            size_t mid = lo + (hi - lo) / 2;
            if (leaves_at(&e, set[k][mid]) <= (double)max_leaves)
                hi = mid;
            else
                lo = mid + 1;
        }
        if (lo < nset[k] && set[k][lo] < theta)
            theta = set[k][lo];
    }
out:
    free(m);
    free(mtop);
    free(buf);
    free(chain);
    free(tmp);
    return theta;
}
