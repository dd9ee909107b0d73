/*
 * kd_sweep_measure.c — the SAH plane sweep for any probability measure
 * (the view measures of sah-per, sah-par and sah-mixed, and the surface
 * area when the linear sweep does not apply). A candidate plane's cost is
 * exactly that of a full sweep, but candidates that provably cannot be the
 * cheapest are not evaluated (branch and bound, see "Pruning"): the same
 * plane as the full sweep, with a fraction of the measure's evaluations.
 */
#include "accel/kd_sah.h"
#include "accel/kd_view.h"

/* --- the cost of a candidate -------------------------------------------------------------- */

/*
 * The cost is evaluated at every event, between its END part and its START
 * part: after subtracting the ENDs up to and including it, before adding the
 * STARTs from it on. At the first START of a position (or at its last END
 * when no START follows) that gives the true counts at the plane (left:
 * lo < p, right: hi > p); at the other events of the position one side is
 * overcounted, and the cost is monotone in both counts (also across the empty
 * bonus and in floating point), so those evaluations never win. So the loop
 * needs no data-dependent branch.
 */

/* The constants of one axis's sweep. */
typedef struct msweep {
    sah_build *b; /* its scratch (b->mruns) grows */
    const uint64_t *e;
    size_t n;
    unsigned k;
    double lo, hi, cross, perim, ctrav, bonus, unif_inv, inv_area, anode, mb_hit, unif_save,
        tsum;
    double margin_abs; /* the measure's rounding, in cost units (see msweep_pruned) */
    kd_area_fn area;
    const void *actx;
    bsp_box lb, rb; /* the cell, for the children at a position */
    /* sah-per, sah-par: the children's measures are SPLIT's (kd_view_split.c);
     * sah-mixed: their view terms, in MIXED's measure */
    int split_fast;
    kd_view_split split;
    const kd_mixed_measure *mixed;
} msweep;

/* The sweep state before an event: counts and cost sums of both sides. */
typedef struct mstate {
    size_t nl, nr;
    double tl, tr;
} mstate;

static void msweep_init(msweep *s, sah_build *b, const uint64_t *e, unsigned k,
                        const bsp_box *cell, double inv_area, double tsum, size_t n)
{
    s->b = b;
    s->e = e;
    s->n = n;
    s->k = k;
    s->lo = cell->lo.v[k];
    s->hi = cell->hi.v[k];
    const unsigned j1 = (k + 1) % 3, j2 = (k + 2) % 3;
    const double d1 = cell->hi.v[j1] - cell->lo.v[j1], d2 = cell->hi.v[j2] - cell->lo.v[j2];
    s->cross = d1 * d2;
    s->perim = d1 + d2;
    s->ctrav = b->ctrav;
    s->bonus = b->bonus_mul;
    s->unif_inv = b->unif * inv_area;
    s->inv_area = inv_area;
    s->anode = 1.0 / inv_area;
    s->mb_hit = b->mb_hit;
    s->unif_save = b->unif > b->mb_hit ? 1.0 - b->mb_hit / b->unif : 0.0;
    s->tsum = tsum;
    s->margin_abs = 0.0;
    s->area = b->area;
    s->actx = b->actx;
    s->lb = *cell;
    s->rb = *cell;
    s->split_fast = 0; /* sweep_axis decides, once it has candidates */
    s->mixed = NULL;
}

/* Moves the state past the event X (END part, then START part). */
static inline __attribute__((always_inline)) void mstep(const msweep *s, mstate *st, uint64_t x,
                                                        const int mode)
{
    size_t start = (size_t)(x >> 31) & 1;
    st->nr -= start ^ 1;
    st->nl += start;
    if (mode != COST_UNIFORM) {
        double t = ev_cost(s->b, x, mode);
        st->tr -= start ? 0.0 : t;
        st->tl += start ? t : 0.0;
    }
}

/* The measures of the children at P: left (lo, p), right (p, hi). */
static inline __attribute__((always_inline)) double left_measure(msweep *s, double p,
                                                                 const int surface)
{
    if (surface)
        return s->cross + (p - s->lo) * s->perim; /* half areas: the factor 2 is in inv_area */
    s->lb.hi.v[s->k] = p;
    if (s->split_fast) {
        double v = kd_view_split_left(&s->split, &s->lb, p);
        return s->mixed ? kd_mixed_area_of_view(s->mixed, &s->lb, v) : v;
    }
    return s->area(&s->lb, s->actx);
}

static inline __attribute__((always_inline)) double right_measure(msweep *s, double p,
                                                                  const int surface)
{
    if (surface)
        return s->cross + (s->hi - p) * s->perim;
    s->rb.lo.v[s->k] = p;
    if (s->split_fast) {
        double v = kd_view_split_right(&s->split, &s->rb, p);
        return s->mixed ? kd_mixed_area_of_view(s->mixed, &s->rb, v) : v;
    }
    return s->area(&s->rb, s->actx);
}

/* The cost of a candidate with NL, NR, TL, TR (after its END part) and the
 * children's measures AL, AR. MODE, SURFACE and MAILBOX are constants after
 * inlining (COST_*, whether the measure is the surface area, mailbox-aware
 * costs). */
static inline __attribute__((always_inline)) double
mcost(const msweep *s, size_t nl, size_t nr, double tl, double tr, double al, double ar,
      const int mode, const int surface, const int mailbox)
{
    double c;
    if (mailbox) {
        /* the rays through both children, measure al + ar - A(V), test
         * each straddler once and skip it at mb_hit the second time */
        double ab = surface ? s->cross : al + ar - s->anode;
        double ns = (double)(nl + nr - s->n); /* straddlers: never negative */
        ab = ab > 0.0 ? ab : 0.0;
        if (mode == COST_UNIFORM) {
            c = s->ctrav +
                (al * (double)nl + ar * (double)nr - ab * ns * s->unif_save) * s->unif_inv;
        } else {
            double save = (tl + tr - s->tsum) - s->mb_hit * ns;
            c = s->ctrav + (al * tl + ar * tr - ab * (save > 0.0 ? save : 0.0)) * s->inv_area;
        }
    } else if (mode == COST_UNIFORM) {
        c = s->ctrav + (al * (double)nl + ar * (double)nr) * s->unif_inv;
    } else {
        c = s->ctrav + (al * tl + ar * tr) * s->inv_area;
    }
    return ((nl == 0) | (nr == 0)) ? c * s->bonus : c;
}

/* Evaluates the candidates e[from..to), all at one position whose measures
 * are AL and AR, from the state ST before them; returns the least cost and
 * in *AT the first event that has it. */
static inline __attribute__((always_inline)) double
meval_at(const msweep *s, size_t from, size_t to, mstate st, double al, double ar, size_t *at,
         const int mode, const int surface, const int mailbox)
{
    double best = INFINITY;
    size_t best_i = SIZE_MAX;
    for (size_t i = from; i < to; i++) {
        uint64_t x = s->e[i];
        size_t start = (size_t)(x >> 31) & 1;
        double t = 0.0;
        st.nr -= start ^ 1;
        if (mode != COST_UNIFORM) {
            t = ev_cost(s->b, x, mode);
            st.tr -= start ? 0.0 : t;
        }
        double c = mcost(s, st.nl, st.nr, st.tl, st.tr, al, ar, mode, surface, mailbox);
        best_i = c < best ? i : best_i;
        best = c < best ? c : best;
        st.nl += start;
        if (mode != COST_UNIFORM)
            st.tl += start ? t : 0.0;
    }
    *at = best_i;
    return best;
}

/* --- pruning ------------------------------------------------------------------------------ */

/*
 * Pruning. A range of candidates e[from..to) (positions pf <= ... <= pl)
 * gets a lower bound of the cost of every candidate in it, and is evaluated
 * only when the bound does not exceed the best cost so far.
 *
 * The measures are monotone under inclusion — a box inside another projects
 * inside its projection, for PER and PAR (a box containing the eye has the
 * whole viewport, the most any box gets; the part in front of the start
 * plane and the clipping to the viewport keep inclusion, and so does the cap
 * at its area; see kd_view_measure_noise for the one exception, next to the
 * eye), the mixed measure (a positive combination) and the surface area — so
 * for a candidate p of the range, al(p) >= al(pf) and ar(p) >= ar(pl). And
 * the children of a split cover their node, so al(p) + ar(p) >= A = A(V)
 * (the projections of the two children cover that of the node; one of them
 * contains the eye when the node does; the surface: al + ar = A + cross).
 *
 * The cost. At candidate i let L and R be the primitives counted left and
 * right (every primitive is in L or R), B = L n R the straddlers. Then
 * (C - C_trav) / scale =
 *     al T(L\B) + ar T(R\B) + (al + ar) T(B) - ab max(0, T(B) - T_mb |B|)
 * with ab = max(0, al + ar - A) (the surface area: ab = cross, and
 * al + ar - ab = A), or without mailboxes no ab term; T(S) the cost sum of
 * S (uniform costs: the count, and the saving scaled by 1 - T_mb/T <= 1);
 * scale = 1 / A (uniform costs: T / A). As 0 <= max(0, T(B) - T_mb |B|) <=
 * T(B), the straddlers contribute at least m T(B), m = al + ar - ab =
 * min(al + ar, A) >= max(al, ar) (measures clamped to A).
 *
 * Over the range, the state before e[from] has the left set L0 (NL0, TL0)
 * and the state after e[to - 1] the right set R1 (NR1, TR1); every candidate
 * of the range has L >= L0, R >= R1. Take any a <= min(al(p), A) and
 * b <= min(ar(p), A) for all p of the range, ab0 = max(0, a + b - A) <=
 * min(a, b): a primitive of L0 \ R1 is in L (coefficient al or m, both >= a),
 * one of R1 \ L0 in R (>= b), one of L0 n R1 in B (m >= min(a + b, A) =
 * a + b - ab0), and any other one in L or R (>= min(a, b) >= ab0). Summing,
 * with T(L0 n R1) - T(neither) = TL0 + TR1 - tsum:
 *     (C - C_trav) / scale >= g(a, b) = a TL0 + b TR1 - ab0 (TL0 + TR1 - tsum)
 * (without mailboxes a TL0 + b TR1), non-decreasing in a and b. With a =
 * al(pf), b = ar(pl) (clamped to A) that is the bound, except that when
 * a + b < A the covering lifts it: (al(p), ar(p)) lies on or above the
 * segment a' + b' = A, a' >= a, b' >= b, where g is linear (no ab0 term), so
 * g >= min(g(a, A - a), g(A - b, b)). The empty bonus multiplies the cost by
 * bonus_mul <= 1 only where NL = 0 or NR = 0, which in the range needs
 * NL0 = 0 or NR1 = 0: the bound is multiplied there. So the bound holds for
 * every evaluation of the range, also at the overcounted events.
 *
 * The search: per axis, runs of MRUN events, each bounded (two evaluations
 * of the measure) and visited from the least bound; in a run, branch and
 * bound over its positions: a range of positions is bounded by the measures
 * known around it, and unless ruled out, its middle position is looked at —
 * bounded by its own sums first, then its left measure taken, and its right
 * one only when the position itself can still win — and the two halves
 * follow, the lesser bound first. The best is the least cost, then the
 * lowest event index: the full sweep's choice (ties: the earlier axis, then
 * the lower position), whatever the order of the evaluations. On the SPD
 * scenes this measures 0.5-0.8 children per position, against 2 for the
 * full sweep.
 *
 * Floating point. The sums are exact (quantized costs, see quantize_costs
 * in kd_split_sah.c; counts), and the bound and the costs are evaluated from
 * the same measures, but the measures are not exactly monotone nor covering
 * in floating point (projection, clipping, a hull: on tiny cells, or at
 * corners next to the eye plane, relative errors reach 1e-2 and more). So a
 * range is skipped only when its bound exceeds the best cost by a relative
 * margin for the rounding of the formulas (PRUNE_MARGIN) plus the effect of
 * the measure's own error bound (kd_view_measure_noise, over the node's
 * cell: each of the measures involved, the node's included, may be off by
 * it; the costs move by at most that times 2 tsum scale each): then every
 * candidate skipped costs more than the best, and the chosen plane is the
 * full sweep's. Where the measure has no error bound (a cell face next to
 * the eye; an unknown measure) every candidate is evaluated, and so are the
 * positions next to the eye in a cell that contains it (the bound's ZONE).
 * The error bound is an analysis with a wide factor, checked: violations of
 * monotonicity or covering on random boxes (tests/test_kd_view.c) stay
 * below 2 % of it, and on the SPD builds their effect on the costs below
 * 1e-5 of the margin.
 */
#define MRUN 256           /* events per run of an axis */
#define PRUNE_MARGIN 1e-9  /* relative: the rounding of the bound and of the costs */
#define NOISE_WEIGHT 16.0  /* the measure's error bound, times this times tsum scale */

/* A position of a run: its events e[first..next group's first) and the
 * state before them. */
typedef struct mgroup {
    mstate st;
    double p;
    size_t first;
} mgroup;

/* A run of an axis: its events, the state before them, the left measure at
 * its first position and the right one at its last, its bound. */
typedef struct mrun {
    mstate st;
    double al, ar, lb;
    size_t from, to;
} mrun;

/* The scratch: NRUNS runs, then MRUN + 1 groups. */
static int grow_scratch(sah_build *b, size_t nruns, mrun **runs, mgroup **groups)
{
    size_t need = nruns * sizeof(mrun) + (MRUN + 1) * sizeof(mgroup);
    if (need > b->mruns_cap) {
        size_t ncap = b->mruns_cap * 2 > need ? b->mruns_cap * 2 : need;
        void *np = realloc(b->mruns, ncap);
        if (!np)
            return 0;
        b->mruns = np;
        b->mruns_cap = ncap;
    }
    *runs = b->mruns;
    *groups = (mgroup *)((char *)b->mruns + nruns * sizeof(mrun));
    return 1;
}

/* The lower bound of the costs of the candidates from the state S0 (before
 * the first of them) to the state S1 (after the last of them: its START part
 * changes neither NR nor TR), AL the left measure at or below their first
 * position and AR the right one at or above their last. */
static inline __attribute__((always_inline)) double
mbound(const msweep *s, const mstate *s0, const mstate *s1, double al, double ar, const int mode,
       const int surface, const int mailbox)
{
    double tl, tr, tot, scale;
    if (mode == COST_UNIFORM) {
        tl = (double)s0->nl;
        tr = (double)s1->nr;
        tot = (double)s->n;
        scale = s->unif_inv;
    } else {
        tl = s0->tl;
        tr = s1->tr;
        tot = s->tsum;
        scale = s->inv_area;
    }
    const double A = s->anode;
    double a = al < A ? al : A, b = ar < A ? ar : A, x;
    if (!surface && a + b < A) {
        /* covering: on a' + b' = A the bound is linear (no mailbox term) */
        double x1 = a * tl + (A - a) * tr, x2 = (A - b) * tl + b * tr;
        x = x1 < x2 ? x1 : x2;
    } else if (mailbox) {
        double ab = a + b - A;
        ab = ab > 0.0 ? ab : 0.0;
        x = a * tl + b * tr - ab * (tl + tr - tot);
    } else {
        x = a * tl + b * tr;
    }
    double c = s->ctrav + x * scale;
    if ((s0->nl == 0) | (s1->nr == 0))
        c *= s->bonus < 1.0 ? s->bonus : 1.0;
    return c;
}

/* The best of the axis so far: cost and event index; SIZE_MAX: an earlier
 * axis's, which wins ties. */
typedef struct mbest {
    double c;
    size_t i;
} mbest;

static inline int prunable(const msweep *s, double lb, const mbest *best)
{
    return lb > best->c + fabs(best->c) * PRUNE_MARGIN + s->margin_abs;
}

static inline void merge_best(mbest *best, double c, size_t i)
{
    if (i != SIZE_MAX && (c < best->c || (c == best->c && best->i != SIZE_MAX && i < best->i))) {
        best->c = c;
        best->i = i;
    }
}

/* The full sweep of the candidates e[from..to) from state ST, merging into
 * *BEST. A view measure costs far more than the surface area: the events at
 * one position share its measures. */
static inline __attribute__((always_inline)) void
mfull(msweep *s, size_t from, size_t to, mstate st, mbest *best, const int mode,
      const int surface, const int mailbox)
{
    while (from < to) {
        uint64_t key = s->e[from] >> 32;
        size_t next = from + 1;
        while (next < to && s->e[next] >> 32 == key)
            next++;
        double p = ev_pos(s->e[from]);
        double al = left_measure(s, p, surface), ar = right_measure(s, p, surface);
        size_t at;
        double c = meval_at(s, from, next, st, al, ar, &at, mode, surface, mailbox);
        merge_best(best, c, at);
        for (size_t i = from; i < next; i++)
            mstep(s, &st, s->e[i], mode);
        from = next;
    }
}

/* A range [gi, gj) of the positions of a run, AL a left measure at or below
 * its first position (measured at AL_P) and AR a right one at or above its
 * last (at AR_P), and its bound. */
typedef struct mrange {
    size_t gi, gj;
    double al, al_p, ar, ar_p, lb;
} mrange;

/* Evaluates position G of a range whose measures are AL (left, measured at
 * AL_P <= G's position: reused when equal) and AR (right, at AR_P >= G's
 * position), merging into *BEST. Its left measure comes first: with it and
 * AR the position may be ruled out (returns 0, *GAR unset); else its right
 * measure, and its candidates are evaluated (returns 1). *GAL, *GAR: its
 * measures. */
static inline __attribute__((always_inline)) int
meval_group(msweep *s, const mgroup *g, double al, double al_p, double ar, double ar_p,
            double *gal, double *gar, mbest *best, const int mode, const int surface,
            const int mailbox)
{
    double p = g[0].p;
    double gl = al_p == p ? al : left_measure(s, p, surface);
    *gal = gl;
    if (!surface && ar_p != p &&
        prunable(s, mbound(s, &g[0].st, &g[1].st, gl, ar, mode, surface, mailbox), best))
        return 0;
    double gr = ar_p == p ? ar : right_measure(s, p, surface);
    *gar = gr;
    size_t at;
    double c = meval_at(s, g[0].first, g[1].first, g[0].st, gl, gr, &at, mode, surface, mailbox);
    merge_best(best, c, at);
    return 1;
}

/* Branch and bound over the positions of the run R (at most MRUN events). */
static inline __attribute__((always_inline)) void
mrun_bb(msweep *s, mgroup *g, const mrun *r, mbest *best, const int mode, const int surface,
        const int mailbox)
{
    const uint64_t *e = s->e;
    size_t ng = 0;
    uint64_t prev = ~(uint64_t)0;
    mstate st = r->st;
    for (size_t i = r->from; i < r->to; i++) {
        uint64_t key = e[i] >> 32;
        g[ng].st = st; /* kept when E[I] opens a position */
        g[ng].first = i;
        ng += key != prev;
        prev = key;
        mstep(s, &st, e[i], mode);
    }
    g[ng].st = st; /* after the last event */
    g[ng].first = r->to;
    for (size_t j = 0; j < ng; j++)
        g[j].p = ev_pos(e[g[j].first]);
    /* depth first, the half of lesser bound first; a range is at most half
     * its parent, so the stack holds at most one per level and a spare */
    mrange stack[2 * 64];
    size_t sp = 1;
    stack[0] = (mrange){0, ng, r->al, g[0].p, r->ar, g[ng - 1].p, 0.0};
    stack[0].lb = mbound(s, &g[0].st, &g[ng].st, r->al, r->ar, mode, surface, mailbox);
    while (sp > 0) {
        mrange q = stack[--sp];
        if (prunable(s, q.lb, best))
            continue;
        size_t gm = q.gi + (q.gj - q.gi) / 2;
        double mal = q.al, mal_p = q.al_p, mar = q.ar, mar_p = q.ar_p, mp = g[gm].p;
        /* the middle position by its own sums first: unless they rule it
         * out, it is measured, and its measures bound the halves */
        if (surface || (q.al_p == mp && q.ar_p == mp) ||
            !prunable(s, mbound(s, &g[gm].st, &g[gm + 1].st, q.al, q.ar, mode, surface, mailbox),
                      best)) {
            int has_r = meval_group(s, &g[gm], q.al, q.al_p, q.ar, q.ar_p, &mal, &mar, best,
                                    mode, surface, mailbox);
            mal_p = mp;
            if (has_r)
                mar_p = mp;
            else
                mar = q.ar;
        }
        mrange lo = {q.gi, gm, q.al, q.al_p, mar, mar_p, 0.0};
        mrange hi = {gm + 1, q.gj, mal, mal_p, q.ar, q.ar_p, 0.0};
        int has_lo = gm > q.gi, has_hi = q.gj > gm + 1;
        if (has_lo) {
            lo.lb = mbound(s, &g[lo.gi].st, &g[lo.gj].st, lo.al, lo.ar, mode, surface, mailbox);
            has_lo = !prunable(s, lo.lb, best);
        }
        if (has_hi) {
            hi.lb = mbound(s, &g[hi.gi].st, &g[hi.gj].st, hi.al, hi.ar, mode, surface, mailbox);
            has_hi = !prunable(s, hi.lb, best);
        }
        if (has_lo && has_hi) {
            int lo_first = lo.lb <= hi.lb;
            stack[sp++] = lo_first ? hi : lo;
            stack[sp++] = lo_first ? lo : hi;
        } else if (has_lo) {
            stack[sp++] = lo;
        } else if (has_hi) {
            stack[sp++] = hi;
        }
    }
}

/* Candidates e[a..z) from state ST, pruned (see above), merging into *BEST.
 * Returns 0 when there is no memory for the scratch (nothing done). */
static inline __attribute__((always_inline)) int
mpruned(msweep *s, size_t a, size_t z, mstate st, mbest *best, const int mode,
        const int surface, const int mailbox)
{
    const uint64_t *e = s->e;
    const size_t nruns = (z - a + MRUN - 1) / MRUN;
    mrun *r;
    mgroup *g;
    if (!grow_scratch(s->b, nruns, &r, &g))
        return 0;
    size_t least = 0;
    for (size_t j = 0; j < nruns; j++) {
        r[j].st = st;
        r[j].from = a + j * MRUN;
        r[j].to = r[j].from + MRUN < z ? r[j].from + MRUN : z;
        r[j].al = left_measure(s, ev_pos(e[r[j].from]), surface);
        r[j].ar = right_measure(s, ev_pos(e[r[j].to - 1]), surface);
        r[j].lb = -INFINITY; /* one run: bounded with its positions */
        if (nruns > 1) {
            for (size_t i = r[j].from; i < r[j].to; i++)
                mstep(s, &st, e[i], mode);
            r[j].lb = mbound(s, &r[j].st, &st, r[j].al, r[j].ar, mode, surface, mailbox);
            least = r[j].lb < r[least].lb ? j : least;
        }
    }
    for (size_t o = 0; o < nruns; o++) {
        size_t j = o == 0 ? least : o <= least ? o - 1 : o; /* the least bound first */
        if (!prunable(s, r[j].lb, best))
            mrun_bb(s, g, &r[j], best, mode, surface, mailbox);
    }
    return 1;
}

/* --- the sweep ---------------------------------------------------------------------------- */

/* mfull and mpruned of one specialisation (SWEEP_SPEC). */
typedef void (*mfull_fn)(msweep *s, size_t from, size_t to, mstate st, mbest *best);
typedef int (*mpruned_fn)(msweep *s, size_t a, size_t z, mstate st, mbest *best);

/* Evaluates the candidates of axis K (the node's sorted events E[0..M))
 * strictly inside CELL, keeping the cheapest in *BEST (ties: the earlier
 * axis, then the lower position); FULL and PRUNED: mfull and mpruned of
 * this MODE, SURFACE and MAILBOX. */
static inline __attribute__((always_inline)) void
sweep_axis(sah_build *b, const uint64_t *e, size_t m, unsigned k, const bsp_box *cell,
           double inv_area, double tsum, size_t n, const int mode, const int surface,
           mfull_fn full, mpruned_fn pruned, split_choice *best_out)
{
    msweep s;
    msweep_init(&s, b, e, k, cell, inv_area, tsum, n);
    mstate st = {0, n, 0.0, tsum};
    size_t i = 0;
    /* the events at or below the cell's low end only count */
    for (; i < m; i++) {
        uint64_t x = e[i];
        if (ev_pos(x) > s.lo)
            break;
        mstep(&s, &st, x, mode);
    }
    /* the candidates, strictly inside the cell; those at or above its high
     * end are never candidates and change nothing after */
    size_t z = m;
    while (z > i && ev_pos(e[z - 1]) >= s.hi)
        z--;
    if (z == i)
        return;
    if (!surface && (b->area == kd_view_area || b->area == kd_mixed_area)) {
        s.mixed = b->area == kd_mixed_area ? b->actx : NULL;
        kd_view_split_begin(&s.split, &b->vcell, s.mixed ? &s.mixed->view : b->actx, cell, k);
        s.split_fast = 1;
    }
    /* the measure's error bound, in cost units (see "Pruning"), and the
     * positions next to the eye, evaluated all */
    double zone[2] = {INFINITY, -INFINITY};
    double noise = surface ? 0.0 : kd_view_measure_noise(b->area, b->actx, cell, k, zone);
    double tot_scale = mode == COST_UNIFORM ? (double)n * s.unif_inv : tsum * inv_area;
    s.margin_abs = NOISE_WEIGHT * noise * tot_scale;
    mbest best = {best_out->cost, SIZE_MAX};
    if (!(s.margin_abs < INFINITY)) {
        full(&s, i, z, st, &best);
    } else {
        size_t z1 = z, z2 = z;
        mstate st1 = st, st2 = st;
        if (zone[0] <= zone[1]) {
            for (z1 = i; z1 < z && ev_pos(e[z1]) < zone[0]; z1++)
                mstep(&s, &st1, e[z1], mode);
            st2 = st1;
            for (z2 = z1; z2 < z && ev_pos(e[z2]) <= zone[1]; z2++)
                mstep(&s, &st2, e[z2], mode);
        }
        if (z1 > i && !pruned(&s, i, z1, st, &best))
            full(&s, i, z1, st, &best);
        if (z2 > z1)
            full(&s, z1, z2, st1, &best);
        if (z > z2 && !pruned(&s, z2, z, st2, &best))
            full(&s, z2, z, st2, &best);
    }
    if (best.i != SIZE_MAX) {
        best_out->cost = best.c;
        best_out->axis = k;
        best_out->pos = key_float((uint32_t)(e[best.i] >> 32));
        best_out->found = 1;
    }
}

/* Each specialisation of the sweep (cost mode x measure x mailboxes): its
 * sweep of an axis, its mfull and its mpruned, each a function of its own.
 * sweep_axis calls mfull from four places and mpruned from two; with all of
 * it inlined into one function the file took 19 s to compile, 75 s under
 * the sanitizers (now 6 s and 22 s). A call per range of candidates costs
 * nothing measurable. */
#define SWEEP_SPEC(MODE, SURFACE, MAILBOX)                                                      \
    static __attribute__((noinline)) void mfull_##MODE##_##SURFACE##_##MAILBOX(                \
        msweep *s, size_t from, size_t to, mstate st, mbest *best)                             \
    {                                                                                           \
        mfull(s, from, to, st, best, MODE, SURFACE, MAILBOX);                                   \
    }                                                                                           \
    static __attribute__((noinline)) int mpruned_##MODE##_##SURFACE##_##MAILBOX(               \
        msweep *s, size_t a, size_t z, mstate st, mbest *best)                                 \
    {                                                                                           \
        return mpruned(s, a, z, st, best, MODE, SURFACE, MAILBOX);                              \
    }                                                                                           \
    static __attribute__((noinline)) void sweep_##MODE##_##SURFACE##_##MAILBOX(                \
        sah_build *b, const uint64_t *e, size_t m, unsigned k, const bsp_box *cell,            \
        double inv_area, double tsum, size_t n, split_choice *best)                            \
    {                                                                                           \
        sweep_axis(b, e, m, k, cell, inv_area, tsum, n, MODE, SURFACE,                         \
                   mfull_##MODE##_##SURFACE##_##MAILBOX,                                       \
                   mpruned_##MODE##_##SURFACE##_##MAILBOX, best);                              \
    }
#define SWEEP_SPECS(MODE)                                                                       \
    SWEEP_SPEC(MODE, 1, 1)                                                                      \
    SWEEP_SPEC(MODE, 1, 0)                                                                      \
    SWEEP_SPEC(MODE, 0, 1)                                                                      \
    SWEEP_SPEC(MODE, 0, 0)
SWEEP_SPECS(COST_UNIFORM)
SWEEP_SPECS(COST_CLASS)
SWEEP_SPECS(COST_ARRAY)

#define SWEEP_CASE(MODE)                                                                        \
    case MODE:                                                                                  \
        if (surface && b->mailbox)                                                              \
            sweep_##MODE##_1_1(b, e, m, k, cell, inv_area, tsum, n, best);                      \
        else if (surface)                                                                       \
            sweep_##MODE##_1_0(b, e, m, k, cell, inv_area, tsum, n, best);                      \
        else if (b->mailbox)                                                                    \
            sweep_##MODE##_0_1(b, e, m, k, cell, inv_area, tsum, n, best);                      \
        else                                                                                    \
            sweep_##MODE##_0_0(b, e, m, k, cell, inv_area, tsum, n, best);                      \
        break;

/* The sweep of axis K, specialised by cost mode and measure. */
void kd_sweep_measure(sah_build *b, const uint64_t *e, size_t m, unsigned k, const bsp_box *cell,
                      double inv_area, double tsum, size_t n, int surface, split_choice *best)
{
    switch (b->cost_mode) {
        SWEEP_CASE(COST_UNIFORM)
        SWEEP_CASE(COST_CLASS)
        SWEEP_CASE(COST_ARRAY)
    }
}
