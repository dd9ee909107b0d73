/*
 * kd_sweep_measure.c — the SAH plane sweep for any probability measure
 * (the view measures of sah-per, sah-par and sah-mixed, and the surface
 * area when the linear sweep does not apply): every candidate evaluated.
 */
#include "accel/kd_sah.h"

/* --- the sweep ---------------------------------------------------------------------------- */



/* Evaluates the candidates of axis K (the node's sorted events E[0..M))
 * strictly inside CELL, keeping the cheapest in *BEST (ties: the earlier
 * axis, then the lower position). MODE and SURFACE are constants after
 * inlining (COST_*, and whether the measure is the surface area).
 *
 * The cost is evaluated at every event, between its END part and its START
 * part: after subtracting the ENDs up to and including it, before adding the
 * STARTs from it on. At the first START of a position (or at its last END
 * when no START follows) that gives the true counts at the plane (left:
 * lo < p, right: hi > p); at the other events of the position one side is
 * overcounted, and the cost is monotone in both counts (also across the empty
 * bonus and in floating point), so those evaluations never win. So the loop
 * needs no data-dependent branch. */
static inline __attribute__((always_inline)) void
sweep_axis(const sah_build *b, const uint64_t *e, size_t m, unsigned k, const bsp_box *cell,
           double inv_area, double tsum, size_t n, const int mode, const int surface,
           const int mailbox, split_choice *best)
{
    const double lo = cell->lo.v[k], hi = cell->hi.v[k];
    const unsigned j1 = (k + 1) % 3, j2 = (k + 2) % 3;
    const double d1 = cell->hi.v[j1] - cell->lo.v[j1], d2 = cell->hi.v[j2] - cell->lo.v[j2];
    const double cross = d1 * d2, perim = d1 + d2;
    const double ctrav = b->ctrav, bonus = b->bonus_mul, unif_inv = b->unif * inv_area;
    const double anode = 1.0 / inv_area, mb_hit = b->mb_hit;
    const double unif_save = b->unif > mb_hit ? 1.0 - mb_hit / b->unif : 0.0;
    const kd_area_fn area = b->area;
    const void *actx = b->actx;
    bsp_box lb = *cell, rb = *cell;
    double last_p = NAN, last_al = 0.0, last_ar = 0.0; /* see the view-measure branch */
    double tl = 0.0, tr = tsum, best_cost = best->cost;
    size_t nl = 0, nr = n, best_i = SIZE_MAX, i = 0;
    /* the events at or below the cell's low end only count */
    for (; i < m; i++) {
        uint64_t x = e[i];
        if ((double)key_float((uint32_t)(x >> 32)) > lo)
            break;
        size_t start = (size_t)(x >> 31) & 1;
        nr -= start ^ 1;
        nl += start;
        if (mode != COST_UNIFORM) {
            double t = ev_cost(b, x, mode);
            tr -= start ? 0.0 : t;
            tl += start ? t : 0.0;
        }
    }
    /* the candidates, strictly inside the cell; those at or above its high
     * end are never candidates and change nothing after */
    for (; i < m; i++) {
        uint64_t x = e[i];
        double p = (double)key_float((uint32_t)(x >> 32));
        if (p >= hi)
            break;
        size_t start = (size_t)(x >> 31) & 1;
        double t = 0.0;
        nr -= start ^ 1;
        if (mode != COST_UNIFORM) {
            t = ev_cost(b, x, mode);
            tr -= start ? 0.0 : t;
        }
        double al, ar, c;
        if (surface) {
            al = cross + (p - lo) * perim; /* half areas: the factor 2 is in inv_area */
            ar = cross + (hi - p) * perim;
        } else {
            /* a view measure costs far more than the surface area: events at
             * the position just measured reuse its areas */
            if (p != last_p) {
                lb.hi.v[k] = p;
                rb.lo.v[k] = p;
                last_al = area(&lb, actx);
                last_ar = area(&rb, actx);
                last_p = p;
            }
            al = last_al;
            ar = last_ar;
        }
        if (mailbox) {
            /* the rays through both children, measure al + ar - A(V), test
             * each straddler once and skip it at mb_hit the second time */
            double ab = surface ? cross : al + ar - anode;
            double ns = (double)(nl + nr - n); /* straddlers: never negative */
            ab = ab > 0.0 ? ab : 0.0;
            if (mode == COST_UNIFORM) {
                c = ctrav + (al * (double)nl + ar * (double)nr - ab * ns * unif_save) * unif_inv;
            } else {
                double save = (tl + tr - tsum) - mb_hit * ns;
                c = ctrav + (al * tl + ar * tr - ab * (save > 0.0 ? save : 0.0)) * inv_area;
            }
        } else if (mode == COST_UNIFORM) {
            c = ctrav + (al * (double)nl + ar * (double)nr) * unif_inv;
        } else {
            c = ctrav + (al * tl + ar * tr) * inv_area;
        }
        c = ((nl == 0) | (nr == 0)) ? c * bonus : c;
        best_i = c < best_cost ? i : best_i;
        best_cost = c < best_cost ? c : best_cost;
        nl += start;
        if (mode != COST_UNIFORM)
            tl += start ? t : 0.0;
    }
    if (best_i != SIZE_MAX) {
        best->cost = best_cost;
        best->axis = k;
        best->pos = key_float((uint32_t)(e[best_i] >> 32));
        best->found = 1;
    }
}

#define SWEEP_CASE(MODE)                                                                        \
    case MODE:                                                                                  \
        if (surface && b->mailbox)                                                              \
            sweep_axis(b, e, m, k, cell, inv_area, tsum, n, MODE, 1, 1, best);                  \
        else if (surface)                                                                       \
            sweep_axis(b, e, m, k, cell, inv_area, tsum, n, MODE, 1, 0, best);                  \
        else                                                                                    \
            sweep_axis(b, e, m, k, cell, inv_area, tsum, n, MODE, 0, b->mailbox, best);         \
        break;

/* The sweep of axis K, specialised by cost mode and measure. */
void kd_sweep_measure(const sah_build *b, const uint64_t *e, size_t m, unsigned k,
                  const bsp_box *cell, double inv_area, double tsum, size_t n, int surface,
                  split_choice *best)
{
    switch (b->cost_mode) {
        SWEEP_CASE(COST_UNIFORM)
        SWEEP_CASE(COST_CLASS)
        SWEEP_CASE(COST_ARRAY)
    }
}
