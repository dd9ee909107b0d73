/*
 * kd_sweep_linear.c — the SAH plane sweep for the surface area with a linear
 * cost: pruned by runs of events on large nodes, one pass on small ones.
 */
#include "accel/kd_sah.h"

/* --- the fast sweep: surface area, linear cost ------------------------------------------------ */

/*
 * With the surface area, and when every T_i >= T_mb (always with the default
 * costs; otherwise the sweep above), the cost of a plane p is linear in the
 * sums it depends on. With half areas al = cross + (p - lo) perim and
 * ar = cross + (hi - p) perim (cross, perim of the other two axes), the
 * mailbox saving A(V_B) sum_both (T_i - T_mb) cancels the cross terms:
 *     C = C_trav + scale * g,
 *     g = perim ((p - lo) TL + (hi - p) TR) + cross (W + W0),
 * W = T_mb (NL + NR) and W0 = sum T_i - T_mb n with mailboxes, W = TL + TR
 * and W0 = 0 without (TL, NL: sum and count of the left side; uniform costs
 * count primitives, T_i = 1, and put T into scale). g is non-decreasing in
 * every input, so a run of events whose first position is pf and last pl,
 * starting from (TL, NL) and ending at (TR, NR), has no candidate cheaper
 * than g evaluated at (pf, TL, NL, pl, TR, NR). The sums are exact (costs
 * are multiples of a power of two small enough for every sum of a node: see
 * quantize_costs), so this bound holds bit for bit, and a sweep of a node with
 * many events first sums each run of SWEEP_CHUNK events, then evaluates only
 * the runs whose bound lies below the best cost of a first probe (the run of
 * least bound on each axis): the same plane as the full sweep, far fewer
 * evaluations (the cost is smooth at large nodes). The empty bonus applies
 * only at the first candidate (when no primitive starts at or below the cell)
 * and at the last event of the list: those two are evaluated apart.
 */
#define SWEEP_CHUNK 32
#define SWEEP_PRUNE_MIN 256 /* events of an axis from which runs are pruned */
/* Nodes of fewer primitives are swept in one pass (lin_node_small): build
 * instructions against the sweep of runs at 8, 12, 16, 32, 64 and 128 (of
 * tetra:7, balls:5, teapot:12) were least, within 0.5 %, at 8 to 16. */
#define SWEEP_ONE_PASS_N 16
_Static_assert(2 * SWEEP_ONE_PASS_N <= SWEEP_PRUNE_MIN, "one-pass nodes have no runs to prune");

typedef struct lin_axis {
    const uint64_t *e;
    size_t m;
    double lo, hi, perim, cross;
    size_t a, z;        /* the runs cover e[a..z) */
    int first_bonus;    /* e[a - 1] is a candidate with nothing left of it */
    int last_bonus;     /* e[m - 1] is a candidate */
    double tl0, tr0, mc0; /* the state before e[a] (after e[a - 1] when first_bonus) */
} lin_axis;

typedef struct lin_state {
    double tl, tr, mc; /* left and right sums, and NL + NR (classes with mailboxes) */
} lin_state;

typedef struct lin_model {
    double scale, w0, mbw, ctrav, bonus;
} lin_model;



static inline __attribute__((always_inline)) double
lin_g(const lin_axis *ax, const lin_model *lm, double p_l, double p_r, double tl, double tr,
      double mc, const int mode, const int mailbox)
{
    double w = mailbox ? lm->mbw * (mode == COST_UNIFORM ? tl + tr : mc) : tl + tr;
    return ax->perim * ((p_l - ax->lo) * tl + (ax->hi - p_r) * tr) + ax->cross * (w + lm->w0);
}

/* G with the empty bonus: the whole cost C_trav + scale g scaled, as g. */
static inline __attribute__((always_inline)) double lin_bonus(const lin_model *lm, double g)
{
    const double c = (lm->ctrav + lm->scale * g) * lm->bonus;
    return (c - lm->ctrav) / lm->scale;
}

/* One event X (at P) of a sweep from state (TL, TR, MC): an END leaves the
 * right side before its candidate, a START joins the left side after it;
 * returns the g of the candidate. */
static inline __attribute__((always_inline)) double
lin_step(const sah_build *b, uint64_t x, double p, double lo, double hi, double perim, double cross,
         double mbw, double w0, double *tl, double *tr, double *mc, const int mode,
         const int mailbox)
{
    const ev_delta d = ev_terms(b, x, mode);
    const double ts = d.ts, te = d.te, mb = d.mb, ma = d.ma;
    *tr -= te;
    double w;
    if (mailbox && mode != COST_UNIFORM) {
        *mc -= mb;
        w = mbw * *mc;
    } else {
        w = mailbox ? mbw * (*tl + *tr) : *tl + *tr;
    }
    const double g = perim * ((p - lo) * *tl + (hi - p) * *tr) + cross * (w + w0);
    *tl += ts;
    if (mailbox && mode != COST_UNIFORM)
        *mc += ma;
    return g;
}

/* Sweeps e[from..to) from state *ST (left at the state after e[to - 1]),
 * keeping the least g in *BG at index *BI (strictly less only). */
static inline __attribute__((always_inline)) void
lin_run(const sah_build *b, const lin_axis *ax, const lin_model *lm, size_t from, size_t to,
        lin_state *st, double *bg, size_t *bi, const int mode, const int mailbox)
{
    const uint64_t *e = ax->e;
    const double lo = ax->lo, hi = ax->hi, perim = ax->perim, cross = ax->cross;
    const double w0 = lm->w0, mbw = lm->mbw;
    double tl = st->tl, tr = st->tr, mc = st->mc, best = *bg;
    size_t best_i = *bi;
#pragma GCC unroll 4
    for (size_t i = from; i < to; i++) {
        const uint64_t x = e[i];
        double g = lin_step(b, x, ev_pos(x), lo, hi, perim, cross, mbw, w0, &tl, &tr, &mc, mode,
                            mailbox);
        best_i = g < best ? i : best_i;
        best = g < best ? g : best;
    }
    st->tl = tl;
    st->tr = tr;
    st->mc = mc;
    *bg = best;
    *bi = best_i;
}

/* The g of candidate e[i] from the state before it, with the empty bonus
 * when a side is empty (NL, NR: the counts at the plane). */
static inline __attribute__((always_inline)) double
lin_single(const sah_build *b, const lin_axis *ax, const lin_model *lm, size_t i, lin_state *st,
           size_t nl, size_t nr, const int mode, const int mailbox)
{
    uint64_t x = ax->e[i];
    int start = (int)((x >> 31) & 1);
    double t = ev_t(b, x, mode);
    if (!start) {
        st->tr -= t;
        st->mc -= 1.0;
    }
    double p = ev_pos(x);
    double g = lin_g(ax, lm, p, p, st->tl, st->tr, st->mc, mode, mailbox);
    if (start) {
        st->tl += t;
        st->mc += 1.0;
    }
    if (nl == 0 || nr == 0)
        g = lin_bonus(lm, g);
    return g;
}

typedef struct lin_chunk {
    double tl, tr, mc; /* state before the run */
    double lb;         /* no candidate of the run has a smaller g */
} lin_chunk;

static inline __attribute__((always_inline)) void
lin_node(sah_build *b, const uint64_t *ev, size_t stride, size_t n, double tsum,
         const bsp_box *cell, const lin_model *lm, split_choice *best, const int mode,
         const int mailbox)
{
    if (mode == COST_UNIFORM)
        tsum = (double)n;
    const size_t m = 2 * n;
    lin_axis ax[3];
    size_t nchunks[3] = {0, 0, 0}, total_chunks = 0;
    for (unsigned k = 0; k < 3; k++) {
        lin_axis *A = &ax[k];
        const unsigned j1 = (k + 1) % 3, j2 = (k + 2) % 3;
        const double d1 = cell->hi.v[j1] - cell->lo.v[j1], d2 = cell->hi.v[j2] - cell->lo.v[j2];
        A->e = ev + k * stride;
        A->m = m;
        A->lo = cell->lo.v[k];
        A->hi = cell->hi.v[k];
        A->cross = d1 * d2;
        A->perim = d1 + d2;
        /* the events at or below the cell's low end only count */
        double tl = 0.0, tr = 0.0, mc = (double)n;
        size_t i = 0, nl = 0;
        for (; i < m; i++) {
            uint64_t x = A->e[i];
            if (ev_pos(x) > A->lo)
                break;
            int start = (int)((x >> 31) & 1);
            nl += (size_t)start;
            const ev_delta d = ev_terms(b, x, mode);
            tl += d.ts;
            tr += d.te; /* subtracted below from the right sum */
            mc += d.ma - d.mb;
        }
        A->tl0 = tl;
        A->mc0 = mc;
        A->tr0 = tsum - tr; /* exact: the sums are exact */
        size_t z = m;
        while (z > i && ev_pos(A->e[z - 1]) >= A->hi)
            z--;
        A->first_bonus = nl == 0 && i < z;
        A->last_bonus = z == m && i < z;
        A->a = i;
        A->z = z;
    }
    double bg = INFINITY;
    size_t bi[3] = {SIZE_MAX, SIZE_MAX, SIZE_MAX};
    lin_state first_st[3];
    for (unsigned k = 0; k < 3; k++) {
        lin_axis *A = &ax[k];
        lin_state st = {A->tl0, A->tr0, A->mc0};
        if (A->first_bonus) {
            /* evaluated apart: the state moves past it */
            (void)lin_single(b, A, lm, A->a, &st, 0, 1, mode, mailbox);
            A->a++;
        }
        if (A->last_bonus)
            A->z--; /* e[m - 1] is an END, the first candidate with nothing left a START */
        first_st[k] = st;
        if (A->z > A->a && A->z - A->a >= SWEEP_PRUNE_MIN)
            nchunks[k] = (A->z - A->a + SWEEP_CHUNK - 1) / SWEEP_CHUNK;
        total_chunks += nchunks[k];
    }
    lin_chunk *ch = NULL;
    double U = INFINITY;
    if (total_chunks > 0) {
        if (!grow_u64((uint64_t **)&b->chunks, &b->chunks_cap,
                      total_chunks * (sizeof(lin_chunk) / sizeof(uint64_t))))
            nchunks[0] = nchunks[1] = nchunks[2] = 0; /* no pruning */
        else
            ch = (lin_chunk *)b->chunks;
    }
    /* pass 1: the sums of each run, and the bound of each; the probe */
    if (ch) {
        lin_chunk *c = ch;
        for (unsigned k = 0; k < 3; k++) {
            lin_axis *A = &ax[k];
            if (!nchunks[k])
                continue;
            lin_state st = first_st[k];
            size_t least = 0;
            double least_lb = INFINITY;
            for (size_t j = 0; j < nchunks[k]; j++) {
                size_t from = A->a + j * SWEEP_CHUNK;
                size_t to = from + SWEEP_CHUNK < A->z ? from + SWEEP_CHUNK : A->z;
                double ts = 0.0, te = 0.0, ns = 0.0;
#pragma GCC unroll 4
                for (size_t i = from; i < to; i++) {
                    const ev_delta d = ev_terms(b, A->e[i], mode);
                    ts += d.ts;
                    te += d.te;
                    ns += d.ma;
                }
                double ne = (double)(to - from) - ns;
                c[j].tl = st.tl;
                c[j].tr = st.tr;
                c[j].mc = st.mc;
                double pf = ev_pos(A->e[from]), pl = ev_pos(A->e[to - 1]);
                c[j].lb = lin_g(A, lm, pf, pl, st.tl, st.tr - te, st.mc - ne, mode, mailbox);
                if (c[j].lb < least_lb) {
                    least_lb = c[j].lb;
                    least = j;
                }
                st.tl += ts;
                st.tr -= te;
                st.mc += ns - ne;
            }
            /* the probe: the run of least bound, evaluated */
            size_t from = A->a + least * SWEEP_CHUNK;
            size_t to = from + SWEEP_CHUNK < A->z ? from + SWEEP_CHUNK : A->z;
            lin_state ps = {c[least].tl, c[least].tr, c[least].mc};
            size_t dummy = SIZE_MAX;
            lin_run(b, A, lm, from, to, &ps, &U, &dummy, mode, mailbox);
            c += nchunks[k];
        }
    }
    /* pass 2: in order (axis, position), only what can beat the probe */
    lin_chunk *c = ch;
    unsigned best_k = 0;
    for (unsigned k = 0; k < 3; k++) {
        lin_axis *A = &ax[k];
        double bg_before = bg;
        if (A->first_bonus) {
            lin_state st = {A->tl0, A->tr0, A->mc0};
            double g = lin_single(b, A, lm, A->a - 1, &st, 0, 1, mode, mailbox);
            if (g < bg) {
                bg = g;
                bi[k] = A->a - 1;
            }
        }
        if (!nchunks[k]) {
            lin_state st = first_st[k];
            lin_run(b, A, lm, A->a, A->z, &st, &bg, &bi[k], mode, mailbox);
        } else {
            for (size_t j = 0; j < nchunks[k]; j++) {
                if (!(c[j].lb < bg && c[j].lb <= U))
                    continue;
                size_t from = A->a + j * SWEEP_CHUNK;
                size_t to = from + SWEEP_CHUNK < A->z ? from + SWEEP_CHUNK : A->z;
                lin_state st = {c[j].tl, c[j].tr, c[j].mc};
                lin_run(b, A, lm, from, to, &st, &bg, &bi[k], mode, mailbox);
            }
            c += nchunks[k];
        }
        if (A->last_bonus) {
            /* the state before e[m - 1]: every START in, every END but its own out */
            double t = ev_t(b, A->e[m - 1], mode);
            lin_state st = {tsum, t, mailbox && mode != COST_UNIFORM ? (double)n + 1.0 : 0.0};
            double g = lin_single(b, A, lm, m - 1, &st, n, 0, mode, mailbox);
            if (g < bg) {
                bg = g;
                bi[k] = m - 1;
            }
        }
        if (bg < bg_before)
            best_k = k;
    }
    if (bg < INFINITY && bi[best_k] != SIZE_MAX) {
        best->cost = lm->ctrav + lm->scale * bg;
        best->axis = best_k;
        best->pos = key_float((uint32_t)(ax[best_k].e[bi[best_k]] >> 32));
        best->found = 1;
    }
}

/*
 * The same sweep for a small node (fewer than SWEEP_ONE_PASS_N primitives:
 * no axis has runs to prune), in one pass per axis: the events at or below
 * the cell's low end only move the state, every event strictly inside the
 * cell is a candidate in list order, and the sweep stops at the first event
 * at or above its high end. The empty bonus goes to the first candidate when no
 * START lies at or below the low end and to the last event when it is a
 * candidate, as in lin_node; the states are the same exact sums and the
 * candidates are compared in the same order (strictly less), so it finds
 * the same cost, axis and plane bit for bit. Most nodes of a build are this
 * small, and for them lin_node's set-up per axis (the scans for the first
 * and last candidates, the bonus candidates apart) is a large share.
 */
static inline __attribute__((always_inline)) void
lin_node_small(const sah_build *b, const uint64_t *ev, size_t stride, size_t n, double tsum,
               const bsp_box *cell, const lin_model *lm, split_choice *best, const int mode,
               const int mailbox)
{
    if (mode == COST_UNIFORM)
        tsum = (double)n;
    const size_t m = 2 * n;
    const double w0 = lm->w0, mbw = lm->mbw;
    double bg = INFINITY;
    uint64_t best_ev = 0;
    unsigned best_k = 0;
    for (unsigned k = 0; k < 3; k++) {
        const unsigned j1 = k == 2 ? 0 : k + 1, j2 = k == 0 ? 2 : k - 1;
        const double d1 = cell->hi.v[j1] - cell->lo.v[j1], d2 = cell->hi.v[j2] - cell->lo.v[j2];
        const double lo = cell->lo.v[k], hi = cell->hi.v[k], cross = d1 * d2, perim = d1 + d2;
        const uint64_t *e = ev + k * stride;
        double tl = 0.0, tr = tsum, mc = (double)n;
        int bonus_next = 1; /* no START at or below the low end (yet) */
        size_t i = 0;
        for (; i < m; i++) {
            const uint64_t x = e[i];
            if (ev_pos(x) > lo)
                break;
            const int start = (int)((x >> 31) & 1);
            bonus_next &= start ^ 1;
            const ev_delta d = ev_terms(b, x, mode);
            tl += d.ts;
            tr -= d.te;
            mc += d.ma - d.mb;
        }
        for (; i < m; i++) {
            const uint64_t x = e[i];
            const double p = ev_pos(x);
            if (p >= hi)
                break;
            double g = lin_step(b, x, p, lo, hi, perim, cross, mbw, w0, &tl, &tr, &mc, mode,
                                mailbox);
            if (bonus_next | (i == m - 1)) { /* a side is empty */
                g = lin_bonus(lm, g);
                bonus_next = 0;
            }
            /* masks, not a branch: whether a candidate is the best so far is
             * data, not a pattern (the compiler turns selections into one) */
            const uint64_t better = 0u - (uint64_t)(g < bg);
            best_ev = (x & better) | (best_ev & ~better);
            best_k = ((unsigned)better & k) | (~(unsigned)better & best_k);
            bg = g < bg ? g : bg;
        }
    }
    if (bg < INFINITY) {
        best->cost = lm->ctrav + lm->scale * bg;
        best->axis = best_k;
        best->pos = key_float((uint32_t)(best_ev >> 32));
        best->found = 1;
    }
}

/* lin_node of each cost mode, with and without mailboxes: a function each,
 * called from both entry points below (inlined into each, the file took
 * 7 s to compile, 41 s under the sanitizers; now 3 s and 16 s); a call
 * per node of SWEEP_ONE_PASS_N or more primitives. */
#define LIN_NODE_SPEC(MODE, MAILBOX)                                                            \
    static __attribute__((noinline)) void lin_node_##MODE##_##MAILBOX(                         \
        sah_build *b, const uint64_t *ev, size_t stride, size_t n, double tsum,                \
        const bsp_box *cell, const lin_model *lm, split_choice *best)                          \
    {                                                                                           \
        lin_node(b, ev, stride, n, tsum, cell, lm, best, MODE, MAILBOX);                        \
    }
LIN_NODE_SPEC(COST_UNIFORM, 0)
LIN_NODE_SPEC(COST_UNIFORM, 1)
LIN_NODE_SPEC(COST_CLASS, 0)
LIN_NODE_SPEC(COST_CLASS, 1)
LIN_NODE_SPEC(COST_ARRAY, 0)
LIN_NODE_SPEC(COST_ARRAY, 1)

#define LIN_CASE(MODE)                                                                          \
    case MODE:                                                                                  \
        if (small && b->mailbox)                                                                \
            lin_node_small(b, ev, stride, n, tsum, cell, &lm, best, MODE, 1);                   \
        else if (small)                                                                         \
            lin_node_small(b, ev, stride, n, tsum, cell, &lm, best, MODE, 0);                   \
        else if (b->mailbox)                                                                    \
            lin_node_##MODE##_1(b, ev, stride, n, tsum, cell, &lm, best);                       \
        else                                                                                    \
            lin_node_##MODE##_0(b, ev, stride, n, tsum, cell, &lm, best);                       \
        break;

/* The best plane by the one-pass sweep when the node is too small for runs
 * (SMALL), else by the pruned sweep of runs. */
static inline __attribute__((always_inline)) void
sweep_linear(sah_build *b, const uint64_t *ev, size_t stride, size_t n, double tsum,
             const bsp_box *cell, double inv_area, split_choice *best, int small)
{
    lin_model lm;
    const double ctr = b->ctrav;
    lm.ctrav = ctr;
    lm.bonus = b->bonus_mul;
    if (b->cost_mode == COST_UNIFORM) {
        lm.scale = b->unif * inv_area;
        lm.mbw = b->mb_hit / b->unif;
        lm.w0 = b->mailbox ? (double)n - lm.mbw * (double)n : 0.0;
    } else {
        lm.scale = inv_area;
        lm.mbw = b->mb_hit;
        lm.w0 = b->mailbox ? tsum - lm.mbw * (double)n : 0.0;
    }
    if (lm.w0 < 0.0)
        lm.w0 = 0.0;
    switch (b->cost_mode) {
        LIN_CASE(COST_UNIFORM)
        LIN_CASE(COST_CLASS)
        LIN_CASE(COST_ARRAY)
    }
}

void kd_sweep_linear(sah_build *b, const uint64_t *ev, size_t stride, size_t n, double tsum,
                     const bsp_box *cell, double inv_area, split_choice *best)
{
    sweep_linear(b, ev, stride, n, tsum, cell, inv_area, best, n < SWEEP_ONE_PASS_N);
}

void kd_sweep_linear_runs(sah_build *b, const uint64_t *ev, size_t stride, size_t n, double tsum,
                          const bsp_box *cell, double inv_area, split_choice *best)
{
    sweep_linear(b, ev, stride, n, tsum, cell, inv_area, best, 0);
}
