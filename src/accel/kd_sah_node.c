/*
 * kd_sah_node.c — the SAH kd-tree builder's recursion (kd_sah_build_node):
 * MacDonald & Booth's cost model (1990; the "surface area heuristics" of
 * Havran, Bittner & Kopal), built exactly in O(N log N) from presorted event
 * lists (Wald & Havran 2006), with perfect splits (straddling primitives
 * clipped to each child). The entry points, the root's lists and the leaf
 * budget's loop are kd_split_sah.c's.
 *
 * Cost of a candidate plane in node V (T_i from kd_cost.c, A the pluggable
 * measure of kd_cost.h, evaluated for the node and both children):
 *     C = C_trav + A(V_L)/A(V) sum_{i in L} T_i + A(V_R)/A(V) sum_{i in R} T_i,
 * times (1 - empty_bonus) when one side holds no primitive — empty space
 * culling; the whole cost is scaled, as in Mitsuba (pbrt scales only the
 * intersection term), default bonus 0.1. A leaf costs sum T_i.
 *
 * Mailboxes (o->mailbox, the default): the rays through both children —
 * measure A(V_L) + A(V_R) - A(V), for any measure of rays or lines — test a
 * straddler once and skip it by its mailbox the second time, so the split
 * costs A(V_B)/A(V) * sum_{i in both} (T_i - T_mb) less (T_mb: a skipped
 * test, KD_MAILBOX_HIT_COST). Without this term the model charges a
 * straddler twice and calls a split that duplicates most primitives a loss:
 * on shells (thousands of nested, overlapping spheres) it left leaves of
 * 200-1000 spheres (N_IT 239, Kaplan 106); with it, N_IT 44. The cost stays
 * monotone in both counts, so the sweep argument below holds. Mailboxes
 * off: the plain model.
 *
 * Events. Each primitive of a node carries a box: its padded bounds, clipped
 * (kd_clip.c) to the cell where it last straddled a plane, rounded outward
 * to floats (lo down, hi up). Per axis it has a START event at lo and an END
 * event at hi; lo < hi always (the padding is positive). An event is one
 * 64-bit key: orderable float bits of the position, the type (END = 0 <
 * START = 1), a cost class, the primitive index — so comparing keys orders
 * by (position, type, cost class, primitive), a total order, and the build is
 * deterministic. The three lists of the root (2N events each) are radix-
 * sorted once; a child inherits their order by stable filtering, and only
 * the events of straddlers are made anew (clipped), sorted and merged in.
 * Per node: one sweep per axis finds the best plane, one sweep of the split
 * axis classifies, one pass per axis splits the lists — O(n) plus the
 * straddlers' O(s log s). Never a per-node full sort.
 *
 * Exactness conventions (kd_tree.h). Candidates are event positions, floats
 * strictly inside the cell; that float is the stored plane and the child
 * boundary. Classification is strict: left if lo < s, right if hi > s. A
 * primitive lying in a plane c has the box [c - pad, c + pad] (rounded
 * outward): a split at c puts it in both children, and the candidates
 * c - pad and c + pad cut it off on either side — this is how in-plane
 * primitives are handled, explicitly, without planar events. A straddler is
 * clipped to each child cell and dropped from a child its clipped box does
 * not overlap (it is then about pad away from that cell).
 *
 * Termination: a leaf at max_depth, with <= max_leaf_prims primitives, when
 * no candidate lies inside the cell, or when the best split does not beat
 * the leaf cost — except that one such "bad refine" is allowed along a path
 * (pbrt and Mitsuba allow 3; on the SPD scenes the second and third saved at
 * most a few percent of intersection tests and doubled the build time,
 * speculative subtrees being mostly retracted), unless the split costs
 * over 4x the leaf with < 16 primitives (pbrt) or the node has fewer than
 * MIN_BAD_REFINE_PRIMS primitives. A subtree under a bad refine whose actual
 * cost is not below its leaf cost is retracted into one leaf afterwards
 * (Mitsuba). The small-node limit: on 11 SPD scenes, bad refines of nodes
 * of 2-7 primitives changed render instructions by -0.05 to +0.2 % (the
 * rest of their subtrees were retracted) and cost 14-26 % of the build's
 * instructions; on shells, whose nested spheres need them, they happen at
 * large nodes.
 *
 * And a leaf when the best split pays but saves less than min_saving mean
 * tests per ray of the whole tree (its cell's surface area over the root's,
 * times leaf cost minus split cost, over the mean T_i): around a vertex
 * shared by several triangles every split of a cell "pays" a little, as the
 * cell shrinks towards the vertex, so without this limit such chains run to
 * the depth limit through cells down to a few paddings wide (tetra: 60 % of its
 * leaves; docs/kdtree.md).
 *
 * With a leaf budget (kd_prune.c) each split's saving, as above, is
 * recorded in t->saving, and a tree with more leaves than the budget loses
 * the splits that save least once it is built.
 *
 * Not used: min-max binning near the root (Mitsuba). Tried with 256 bins
 * above 4096 primitives, it saved ~15% of the build on balls but cost 6-8%
 * of expected cost on tetra (its planes must hit the Sierpinski grid
 * exactly), beyond the 2% allowed. Instead the sweep of the surface area
 * (kd_sweep_linear.c) is exact and prunes: the cost is linear in exact sums, so a
 * run of events has a lower bound, and only runs that can beat a probe are
 * evaluated — the same planes as a full sweep, fewer evaluations.
 *
 * Memory: one event stack addressed by index (growing it is safe). A node's
 * lists are at base + k * stride (stride >= 2n); the smaller child's lists
 * are written above the node's free top, the larger child's made in place
 * (stable compaction forward, merge backward), so a chain of cuts reuses one
 * region, a one-sided split copies nothing, and the lists stored along a
 * path sum to at most the root's. No allocation per node: every
 * scratch array is grown amortized, and the large ones lie on huge pages
 * (util/bigmem.h): on 4 KiB pages, page faults and TLB misses were a fifth
 * to a third of a large scene's first build.
 */
#include "accel/kd_merge.h"
#include "accel/kd_sah.h"
#include "util/grow.h"
#include "util/sort.h"
#include "util/sorted_count.h"

#define MAX_BAD_REFINES 1
#define MIN_BAD_REFINE_PRIMS 8
/* The straddle guard (below): a node of at least STRADDLE_GUARD_MIN
 * primitives whose best split more than NUM/DEN of them straddle is a leaf */
#define STRADDLE_GUARD_MIN 64
#define STRADDLE_GUARD_NUM 19
#define STRADDLE_GUARD_DEN 20
/* A split of at least ORDERED_NEW_MIN straddlers, one in ORDERED_NEW_SHARE
 * of its primitives or more, keeps the order of their events that clipping
 * leaves as they were (kd_sah_build_node, step 4): 2 x 25 keys are past the
 * insertion sort of sort_keys, and gathering the old events costs a pass
 * over all of the node's, which fewer straddlers do not repay. */
#define ORDERED_NEW_MIN 25
#define ORDERED_NEW_SHARE 4

/* --- the recursion ---------------------------------------------------------------------- */

/* short runs of new events: insertion sort up to 48 keys (measured) */
DEFINE_SORT(sort_keys, uint64_t, 48)

static bsp_status oom(sah_build *b)
{
    return kd_build_failed(b->t, b->err);
}


static int grow_list(sah_build *b, size_t need)
{
    return GROW_ARRAY(b->list, b->list_cap, need);
}

static int grow_nev(sah_build *b, size_t need)
{
    if (need <= b->nev_cap)
        return 1;
    size_t ncap = b->nev_cap * 2 > need ? b->nev_cap * 2 : need;
    uint64_t **bufs[4] = {&b->nev[0], &b->nev[1], &b->both, &b->reord};
    for (int s = 0; s < 4; s++) {
        uint64_t *np = realloc(*bufs[s], ncap * sizeof *np);
        if (!np)
            return 0;
        *bufs[s] = np;
    }
    b->nev_cap = ncap;
    return 1;
}

/* The probability measure of BOX; SURFACE: the surface area whatever the
 * build's measure (a view measure's fallback, see build_node). */
static double measure(const sah_build *b, const bsp_box *box, int surface)
{
    return surface ? kd_surface_area(box) : b->area(box, b->actx);
}

/* --- nodes ---------------------------------------------------------------------------------- */

/* kd_make_leaf, except that an empty leaf is written directly: with no
 * primitive stored yet kd_make_leaf would memcpy from/to NULL (0 bytes, but
 * undefined behaviour). */
static int put_leaf(kd_tree *t, uint32_t node, const uint32_t *prims, size_t n)
{
    if (n > 0)
        return kd_make_leaf(t, node, prims, n);
    t->nodes[node].u.first = (uint32_t)t->nprims;
    t->nodes[node].bits = KD_LEAF_TAG;
    return 1;
}

/* Makes NODE a leaf of the primitives whose axis-0 events are E[0..2N). */
static bsp_status make_leaf(sah_build *b, uint32_t node, const uint64_t *e, size_t n)
{
    if (!grow_list(b, n))
        return oom(b);
    size_t c = 0;
    for (size_t i = 0; i < 2 * n; i++)
        if (e[i] & EV_START)
            b->list[c++] = ev_prim(e[i]);
    kd_sort_prims(b->list, c);
    return put_leaf(b->t, node, b->list, c) ? BSP_OK : oom(b);
}

/* Writes the 6 events of straddler P's clipped box CB at OUT[k * stride + at]
 * (k = 0..2) when CB rounded outward to floats overlaps CELL; returns 1 then. */
static int clipped_events(const sah_build *b, uint32_t p, const bsp_box *cb, const bsp_box *cell,
                          uint64_t *out, size_t stride, size_t at)
{
    float lo[3], hi[3];
    for (int k = 0; k < 3; k++) {
        lo[k] = round_down(cb->lo.v[k]);
        hi[k] = round_up(cb->hi.v[k]);
        if (!((double)lo[k] < cell->hi.v[k] && (double)hi[k] > cell->lo.v[k]))
            return 0; /* touches the cell at most on its boundary */
    }
    uint64_t cls = b->pclass ? (uint64_t)b->pclass[p] << EV_CLASS_SHIFT : 0;
    for (int k = 0; k < 3; k++) {
        out[k * stride + at] = make_event(lo[k], 1, p) | cls;
        out[k * stride + at + 1] = make_event(hi[k], 0, p) | cls;
    }
    return 1;
}

/* A straddling triangle's or polygon's part in a split's cell and in each child
 * (handles of b->path): set in b->path.of for the subtree being built,
 * restored when the split's node returns. */
struct part_save {
    uint32_t prim;
    uint64_t parent, child[2];
};

/* Clips straddler P of the split at S on AXIS of CELL to both children into
 * CB (kd_clip_prim_split's result); a triangle or polygon from its part
 * along the path, its children's parts saved for the subtrees (b->saved). */
static int clip_straddler(sah_build *b, uint32_t p, const bsp_box *cell, unsigned axis, double s,
                          bsp_box cb[2])
{
    const shape_kind kind = (shape_kind)b->scene->prims[p].shape;
    if (kind != SHAPE_TRIANGLE && kind != SHAPE_POLYGON) /* parts are polygons */
        return kd_clip_prim_split(b->scene, p, b->bounds[p], cell, axis, s, b->t->pad, &b->clip,
                                  cb);
    const uint64_t parent = b->path.of[p];
    uint64_t parts[2];
    int got = kd_clip_split_part(b->scene, p, b->bounds[p], cell, axis, s, b->t->pad, &b->path,
                                 &b->clip, parent, cb, parts);
    if (got > 0 && (parent | parts[0] | parts[1])) {
        if (!GROW_ARRAY(b->saved, b->saved_cap, b->nsaved + 1))
            return -1;
        b->saved[b->nsaved++] = (struct part_save){p, parent, {parts[0], parts[1]}};
    }
    return got;
}

/* The parts of the saved straddlers [FROM, b->nsaved) for child C (0, 1),
 * or their parent's (C = 2). */
static void set_parts(sah_build *b, size_t from, int c)
{
    for (size_t i = from; i < b->nsaved; i++) {
        const struct part_save *ps = &b->saved[i];
        b->path.of[ps->prim] = c < 2 ? ps->child[c] : ps->parent;
    }
}

/* Whether a node over CELL (N primitives, cost sum TSUM, after BAD bad
 * refines) is a leaf whatever the linear sweep finds, so that it need not
 * sweep: a split saves at most the cell's share of the root times TSUM less
 * the least cost of a plane, and when that is below min_saving, the split
 * the sweep finds is either no better than the leaf or saves too little
 * (step 1 below). Only where a bad refine cannot happen, since that would
 * split a node that does not pay: so the tree is the one the sweep would
 * have built. Deep in a tree most nodes are this small and most end as
 * leaves. */
static int no_split_saves_enough(const sah_build *b, const bsp_box *cell, double tsum, size_t n,
                                 int bad, double min_saving)
{
    if (b->to_limits || (bad < MAX_BAD_REFINES && n >= MIN_BAD_REFINE_PRIMS))
        return 0;
    return kd_surface_area(cell) * b->inv_root_area * (tsum - kd_sweep_linear_least_cost(b)) <
           min_saving;
}

/* The least saving of a split at a node after BAD bad refines. Below a
 * speculative split the plain one: that subtree's actual cost decides its
 * retraction and its recorded saving, so it is built as without a leaf
 * budget's estimate. Elsewhere a split saving less than the estimate's
 * raised least saving would be pruned with its subtree (kd_prune.h). */
static inline double node_min_saving(const sah_build *b, int bad)
{
    return bad ? b->min_saving : b->min_saving_sure;
}

/* The one-sided primitives' counts and cost sums of a split (step 2 of
 * kd_sah_build_node). */
typedef struct classify_counts {
    size_t n_cand; /* b->list[0..n_cand): the primitives that start below the key,
                      the straddlers among them */
    size_t n_lonly, n_ronly;
    double t_lonly, t_ronly;
} classify_counts;

/* Step 2 of kd_sah_build_node over the split axis's events E[0..M), the
 * first SPLIT_I of them below the split key: inlined with MODE constant, so
 * that each cost mode's loops have no test of it. */
static inline __attribute__((always_inline)) void
classify(sah_build *b, const uint64_t *e, size_t split_i, size_t m, classify_counts *cc,
         const int mode)
{
    uint8_t *cls = b->cls;
    const uint32_t spare = b->spare;
    uint32_t *cand = b->list; /* room for one more than the STARTs below the key */
    size_t n_lonly = 0, n_ronly = 0, nc = 0;
    double t_lonly = 0.0, t_ronly = 0.0;
#pragma GCC unroll 4
    for (size_t i = 0; i < split_i; i++) {
        uint64_t x = e[i];
        size_t start = (size_t)(x >> 31) & 1;
        cls[ev_prim(x)] = start ? CLS_BOTH : CLS_LEFT;
        cand[nc] = ev_prim(x); /* every straddler starts below the key */
        nc += start;
        n_lonly += start ^ 1;
        if (mode != COST_UNIFORM) /* TE: T_i for an END, else 0 */
            t_lonly += ev_terms(b, x, mode).te;
    }
#pragma GCC unroll 4
    for (size_t i = split_i; i < m; i++) {
        uint64_t x = e[i];
        size_t start = (size_t)(x >> 31) & 1;
        cls[start ? ev_prim(x) : spare] = CLS_RIGHT;
        n_ronly += start;
        if (mode != COST_UNIFORM) /* TS: T_i for a START, else 0 */
            t_ronly += ev_terms(b, x, mode).ts;
    }
    cc->n_cand = nc;
    cc->n_lonly = n_lonly;
    cc->n_ronly = n_ronly;
    cc->t_lonly = t_lonly;
    cc->t_ronly = t_ronly;
}

/* Step 3 of kd_sah_build_node for one axis: the events of SRC[0..M) whose
 * primitive's class is IN_PLACE (CLS_LEFT or CLS_RIGHT) compacted in place,
 * those of the other one-sided class copied to DST, both stable; a
 * straddler's (CLS_BOTH) go nowhere, or with GATHER into BOTH, in order
 * (returns their count then). Stores one event past the last of DST (and of
 * BOTH). Inlined with IN_PLACE and GATHER constant: no test of them per
 * event. */
static inline __attribute__((always_inline)) size_t
split_list(uint64_t *src, uint64_t *dst, uint64_t *both, size_t m, const uint8_t *cls,
           const unsigned in_place, const int gather)
{
    const unsigned other = CLS_LEFT + CLS_RIGHT - in_place;
    size_t a = 0, o = 0, s = 0;
#pragma GCC unroll 4
    for (size_t i = 0; i < m; i++) {
        uint64_t x = src[i];
        unsigned c = cls[ev_prim(x)];
        src[a] = x;
        a += (c & in_place) != 0;
        dst[o] = x;
        o += (c & other) != 0;
        if (gather) {
            both[s] = x;
            s += c == CLS_BOTH;
        }
    }
    return s;
}

/* Sorts the new events NW of side C's straddlers on one axis (their pairs
 * at b->slot, kd_sah_build_node step 4), given the straddlers' old events
 * of that axis in the lists' order, BOTH[0..NBOTH) (room for STRIDE more
 * after the three axes'). A new event equal to its old one keeps its place:
 * those, taken in the old order, are sorted already; only the others are
 * sorted, and merged into them (kd_merge_back). */
static void sort_new_in_order(sah_build *b, uint64_t *nw, const uint64_t *both, size_t nboth,
                              size_t stride, int c)
{
    uint64_t *same_run = b->both + 3 * stride, *moved = b->reord;
    size_t same = 0, nmoved = 0;
    for (size_t j = 0; j < nboth; j++) {
        const uint64_t x = both[j];
        const uint32_t sl = b->slot[2 * (size_t)b->sidx[ev_prim(x)] + (size_t)c];
        if (sl == UINT32_MAX)
            continue; /* not in this child */
        const uint64_t y = nw[2 * (size_t)sl + ((x & EV_START) ? 0 : 1)]; /* START, END */
        if (y == x)
            same_run[same++] = y;
        else
            moved[nmoved++] = y;
    }
    sort_keys(moved, nmoved);
    memcpy(nw, same_run, same * sizeof *nw);
    kd_merge_back(nw, same, moved, nmoved);
}

/* Builds the subtree of NODE over CELL from the lists L; ev[top, ...) is
 * free. *COST_OUT: the subtree's cost under the model (for retraction).
 * SURFACE: measure by the surface area. A view measure (sah-per, sah-par)
 * is 0 for a cell no ray of its view reaches — outside the viewport or
 * behind the eye — and the ratio child/node is then undefined; such a cell
 * and its subtree are built by the plain surface area instead, so that the
 * secondary and shadow rays that do reach it find a good tree. */
bsp_status kd_sah_build_node(sah_build *b, uint32_t node, bsp_box cell, node_lists L, size_t top,
                             int depth, int bad, int surface, double *cost_out)
{
    kd_tree *t = b->t;
    const size_t n = L.n, m = 2 * n;
    const double tsum = L.tsum;
    *cost_out = tsum;
    if (n <= (size_t)t->max_leaf_prims || depth >= t->max_depth)
        return make_leaf(b, node, b->ev + L.base, n);
    if (kd_sah_task_wanted(b, n, bad))
        return kd_sah_defer(b, node, &cell, &L, depth, surface); /* built later, in parallel */
    if (!surface && b->descent && !b->descent->enter(b->dctx, &cell))
        return oom(b);
    double area = measure(b, &cell, surface);
    if (!surface && !(area > 0.0)) {
        surface = 1;
        area = kd_surface_area(&cell);
    }
    if (!(area > 0.0))
        return make_leaf(b, node, b->ev + L.base, n);

    /* 1. the best plane: one sweep per axis */
    split_choice best = {INFINITY, 0, 0.0f, 0};
    double inv_area = (surface ? 2.0 : 1.0) / area; /* the sweep uses half areas */
    if (surface && b->linear) {
        if (no_split_saves_enough(b, &cell, tsum, n, bad, node_min_saving(b, bad)))
            return make_leaf(b, node, b->ev + L.base, n);
        kd_sweep_linear(b, b->ev + L.base, L.stride, n, tsum, &cell, inv_area, &best);
    } else {
        for (unsigned k = 0; k < 3; k++) {
            const uint64_t *e = b->ev + L.base + k * L.stride;
            kd_sweep_measure(b, e, m, k, &cell, inv_area, tsum, n, surface, &best);
        }
    }
    if (!best.found)
        return make_leaf(b, node, b->ev + L.base, n);
    /* a split that pays, but saves so little per ray of the whole tree that
     * it is not worth a node (the uniform-line probability of the cell, by
     * surface area, whatever the build's measure) */
    const double share = kd_surface_area(&cell) * b->inv_root_area;
    if (best.cost < tsum && !b->to_limits && share * (tsum - best.cost) < node_min_saving(b, bad))
        return make_leaf(b, node, b->ev + L.base, n);
    if (t->saving) /* a bad refine's is its subtree's, below */
        t->saving[node] = share * (tsum - best.cost);
    int bad_here = 0;
    if (best.cost >= tsum && !b->to_limits) {
        if (bad >= MAX_BAD_REFINES || n < MIN_BAD_REFINE_PRIMS ||
            (best.cost > 4.0 * tsum && n < 16))
            return make_leaf(b, node, b->ev + L.base, n);
        bad_here = 1;
    }

    /* 2. classify by the split axis's events. In key order, the events below
     * the split key SK (positions < s, and ENDs at s) come first: there a
     * START (lo < s) makes its primitive tentatively BOTH and an END
     * (hi <= s) makes it LEFT; above SK a START (lo >= s) makes it RIGHT and
     * an END changes nothing (a primitive whose START lay below stays BOTH:
     * a straddler). So neither loop reads the class back: the first writes
     * every event's primitive, the second only STARTs' (the others go to the
     * spare slot cls[np]). Counts and cost sums of the one-sided ones on the
     * way. */
    const unsigned axis = best.axis;
    const double s = (double)best.pos;
    size_t n_lonly = 0, n_ronly = 0, n_cand = 0;
    double t_lonly = 0.0, t_ronly = 0.0;
    {
        const uint64_t *e = b->ev + L.base + axis * L.stride;
        const uint64_t sk = ((uint64_t)float_key(best.pos) << 32) | EV_START;
        const size_t split_i = sorted_first_at_least_u64(e, m, sk); /* the first event >= SK */
        classify_counts cc = {0, 0, 0, 0.0, 0.0};
        if (!grow_list(b, n + 1))
            return oom(b);
        switch (b->cost_mode) {
        case COST_UNIFORM: classify(b, e, split_i, m, &cc, COST_UNIFORM); break;
        case COST_CLASS: classify(b, e, split_i, m, &cc, COST_CLASS); break;
        default: classify(b, e, split_i, m, &cc, COST_ARRAY); break;
        }
        n_cand = cc.n_cand;
        n_lonly = cc.n_lonly;
        n_ronly = cc.n_ronly;
        t_lonly = cc.t_lonly;
        t_ronly = cc.t_ronly;
    }
    const size_t ns = n - n_lonly - n_ronly;
    /* A split of a large node that nearly every primitive straddles is made a
     * leaf (the straddle guard). In a flat cell, where the children's areas
     * add up to the cell's, such a split still pays a little under the SAH,
     * and so does the next and the next: a pile of large overlapping
     * polygons in one plane built a tree of 26,000 references per primitive
     * (1,000 squares: 26.6 M references, 9.5 s; 2,000: 46 M, 49 s and
     * 1.3 GB; with the guard 0.73 M and 0.19 s for 1,000, the expected cost
     * 2.2 % above). In a cell of some depth, A_L + A_R > A and such a split
     * rarely pays: of the SPD scenes only shells' trees change (N_IT +0.00
     * and +0.15 % on shells and shells:6). */
    if (!b->to_limits && n >= STRADDLE_GUARD_MIN && ns * STRADDLE_GUARD_DEN > n * STRADDLE_GUARD_NUM)
        return make_leaf(b, node, b->ev + L.base, n);

    /* 3. the one-sided events, in one pass per axis: the larger side's
     * compacted in place, the smaller side's written above TOP (CLS_LEFT and
     * CLS_RIGHT are one bit each; the straddlers, CLS_BOTH = 0, come from
     * step 2's candidates). Keeping the larger side in place bounds the
     * stack: the lists stored above a node's own are at most half of them,
     * so along any path they sum to at most the root's (about 6 n events),
     * where always storing the right side let unbalanced splits pile up
     * (the peak on the SPD scenes: 12.7-19.8 n events, now 8.9-14.1 n). */
    bsp_box lcell = cell, rcell = cell;
    lcell.hi.v[axis] = rcell.lo.v[axis] = s;
    node_lists LL = {L.base, L.stride, 0, 0.0}, RL = {L.base, L.stride, 0, 0.0};
    size_t free_top = top, right_top = top;
    /* the straddlers' parts this split saves for its children (clip_straddler),
     * and the path's vertex stack to pop to */
    const size_t saved_from = b->nsaved, path_top = b->path.top;
    if (ns == 0 && n_ronly == 0) {
        LL.n = n; /* all left: the lists stay as they are */
        LL.tsum = tsum;
    } else if (ns == 0 && n_lonly == 0) {
        RL.n = n; /* all right: likewise */
        RL.tsum = tsum;
    } else {
        const int right_in_place = n_ronly > n_lonly;
        node_lists *stored = right_in_place ? &LL : &RL;
        stored->base = top;
        stored->stride = 2 * ((right_in_place ? n_lonly : n_ronly) + ns);
        free_top = top + 3 * stored->stride;
        /* the right child's subtree is built after the left one's: when the
         * left lists lay above TOP, their room is free again by then */
        right_top = right_in_place ? top : free_top;
        /* + 1: the branch-free loops below store one event past the last */
        if (!grow_u64(&b->ev, &b->cap, free_top + 1))
            return oom(b);
        const uint8_t *cls = b->cls;
        /* the straddlers: the candidates of step 2 that stayed BOTH, in the
         * split axis's order */
        uint32_t *strad = b->list;
        size_t nsg = 0;
        for (size_t i = 0; i < n_cand; i++) {
            uint32_t p = strad[i];
            strad[nsg] = p;
            nsg += cls[p] == CLS_BOTH;
        }
        /* Many straddlers: their old events are gathered in the lists' order
         * as the lists are split, so that in step 4 the new events equal to
         * old ones keep that order and only the others are sorted
         * (sort_new_in_order). Sorting all of them afresh was over a third of
         * the build of shells, whose nested spheres straddle most splits. */
        const size_t stride = 2 * ns;
        const int ordered = ns >= ORDERED_NEW_MIN && ns * ORDERED_NEW_SHARE >= n;
        if (ns > 0 && !grow_nev(b, 4 * stride + 1))
            return oom(b);
        size_t nboth[3] = {0, 0, 0};
        for (unsigned k = 0; k < 3; k++) {
            uint64_t *src = b->ev + L.base + k * L.stride; /* in place, a <= i */
            uint64_t *dst = b->ev + stored->base + k * stored->stride;
            uint64_t *both = ordered ? b->both + k * stride : NULL;
            if (ordered && right_in_place)
                nboth[k] = split_list(src, dst, both, m, cls, CLS_RIGHT, 1);
            else if (ordered)
                nboth[k] = split_list(src, dst, both, m, cls, CLS_LEFT, 1);
            else if (right_in_place)
                split_list(src, dst, NULL, m, cls, CLS_RIGHT, 0);
            else
                split_list(src, dst, NULL, m, cls, CLS_LEFT, 0);
        }

        /* 4. clip the straddlers to each child; their new events, sorted,
         * merged into the compacted lists */
        size_t kept[2] = {0, 0};
        double tkept[2] = {0.0, 0.0};
        if (ns > 0) {
            if (ordered && ((!b->sidx && !(b->sidx = malloc((size_t)b->spare * sizeof *b->sidx))) ||
                            !GROW_ARRAY(b->slot, b->slot_cap, 2 * ns)))
                return oom(b);
            int fail = 0;
            for (size_t i = 0; i < ns; i++) {
                uint32_t p = strad[i];
                double tp = b->cost ? (double)b->cost[p] : 0.0;
                if (ordered)
                    b->sidx[p] = (uint32_t)i;
                bsp_box cb[2];
                int got = clip_straddler(b, p, &cell, axis, s, cb);
                if (got < 0) {
                    fail = 1;
                    break;
                }
                const bsp_box *cc[2] = {&lcell, &rcell};
                for (int c = 0; c < 2; c++) {
                    const int in = (got >> c & 1) &&
                        clipped_events(b, p, &cb[c], cc[c], b->nev[c], stride, 2 * kept[c]);
                    if (ordered) /* where its new events lie, for sort_new_in_order */
                        b->slot[2 * i + (size_t)c] = in ? (uint32_t)kept[c] : UINT32_MAX;
                    if (in) {
                        kept[c]++;
                        tkept[c] += tp;
                    }
                }
            }
            if (fail)
                return oom(b);
            for (unsigned k = 0; k < 3; k++) {
                uint64_t *nl_ev = b->nev[0] + k * stride, *nr_ev = b->nev[1] + k * stride;
                if (ordered) {
                    sort_new_in_order(b, nl_ev, b->both + k * stride, nboth[k], stride, 0);
                    sort_new_in_order(b, nr_ev, b->both + k * stride, nboth[k], stride, 1);
                } else {
                    sort_keys(nl_ev, 2 * kept[0]);
                    sort_keys(nr_ev, 2 * kept[1]);
                }
                kd_merge_back(b->ev + LL.base + k * LL.stride, 2 * n_lonly, nl_ev, 2 * kept[0]);
                kd_merge_back(b->ev + RL.base + k * RL.stride, 2 * n_ronly, nr_ev, 2 * kept[1]);
            }
        }
        LL.n = n_lonly + kept[0];
        RL.n = n_ronly + kept[1];
        if (b->cost_mode != COST_UNIFORM) {
            LL.tsum = t_lonly + tkept[0];
            RL.tsum = t_ronly + tkept[1];
        } else {
            LL.tsum = b->unif * (double)LL.n;
            RL.tsum = b->unif * (double)RL.n;
        }
    }

    /* 5. the node and its children */
    uint32_t child = kd_alloc_pair(t);
    if (child == UINT32_MAX)
        return oom(b);
    kd_make_interior(t, node, axis, best.pos, child);
    size_t saved_prims = t->nprims;
    double cl, cr;
    set_parts(b, saved_from, 0);
    bsp_status st =
        kd_sah_build_node(b, child, lcell, LL, free_top, depth + 1, bad + bad_here, surface, &cl);
    set_parts(b, saved_from, 1);
    if (st == BSP_OK)
        st = kd_sah_build_node(b, child + 1, rcell, RL, right_top, depth + 1, bad + bad_here, surface, &cr);
    if (st != BSP_OK)
        return st;
    set_parts(b, saved_from, 2);
    b->nsaved = saved_from;
    b->path.top = path_top;
    double ml = measure(b, &lcell, surface), mr = measure(b, &rcell, surface), save = 0.0;
    if (b->mailbox) { /* as in the sweep: the references duplicated by this split */
        double both = ml + mr - area;
        double dup = (LL.tsum + RL.tsum - tsum) - b->mb_hit * ((double)LL.n + (double)RL.n - (double)n);
        save = both > 0.0 && dup > 0.0 ? both * dup : 0.0;
    }
    double cost = b->ctrav + (ml * cl + mr * cr - save) / area;
    if (!bad_here || cost < tsum) {
        if (bad_here && t->saving)
            t->saving[node] = share * (tsum - cost);
        *cost_out = cost;
        return BSP_OK;
    }

    /* 6. retract: the speculative split did not pay off; one leaf of the
     * primitives of the subtree's leaves (each once, in index order) */
    size_t refs = t->nprims - saved_prims;
    if (!grow_list(b, refs))
        return oom(b);
    memcpy(b->list, t->prims + saved_prims, refs * sizeof *b->list);
    size_t c = kd_sort_unique_prims(b->list, refs);
    t->nnodes = child;
    t->nprims = saved_prims;
    return put_leaf(t, node, b->list, c) ? BSP_OK : oom(b);
}
