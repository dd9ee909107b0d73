/*
 * kd_raycount.c — the counted measure of kd_raycount.h: the parts of the
 * sample's segments inside each cell the build enters, and counts of the
 * boxes of its candidate planes by binary search.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "accel/kd_raycount.h"
#include "util/sort_doubles.h"
#include "util/sorted_count.h"

/* Clips the part [*TA, *TB] of the segment OD (origin, direction) to box
 * B; 0 when nothing is left. */
static int clip_part(const double od[6], const bsp_box *b, double *ta, double *tb)
{
    double a = *ta, e = *tb;
    if (!line_clip_box(od, od + 3, b, &a, &e) || !(a <= e))
        return 0;
    *ta = a;
    *tb = e;
    return 1;
}

/* Grows C to hold N parts; 0 when out of memory. The arrays share one block. */
static int cell_reserve(kd_raycount_cell *c, size_t n)
{
    if (n <= c->cap)
        return 1;
    size_t cap = c->cap * 2 > n ? c->cap * 2 : n;
    /* doubles first (and the sort's scratch), then the indices: every array
     * stays aligned */
    char *blk = malloc(cap * (9 * sizeof(double) + sizeof(uint32_t)));
    if (!blk)
        return 0;
    free(c->ta); /* the block's start */
    double *d = (double *)(void *)blk;
    c->ta = d;
    c->tb = d + cap;
    for (int k = 0; k < 3; k++) {
        c->lo[k] = d + (2 + 2 * k) * cap;
        c->hi[k] = d + (3 + 2 * k) * cap;
    }
    c->sort_tmp = (uint64_t *)(void *)(d + 8 * cap);
    c->seg = (uint32_t *)(void *)(d + 9 * cap);
    c->cap = cap;
    return 1;
}

static void cell_free(kd_raycount_cell *c)
{
    free(c->ta);
    memset(c, 0, sizeof *c);
}

/* Sorts the per-axis extremes of C's parts (its parts must be set). */
static void cell_sort_extremes(const kd_raycount *rc, kd_raycount_cell *c)
{
    for (size_t i = 0; i < c->n; i++) {
        const double *od = rc->od[c->seg[i]];
        for (int k = 0; k < 3; k++) {
            /* a zero component gives the origin's coordinate exactly */
            double x0 = od[3 + k] == 0.0 ? od[k] : od[k] + od[3 + k] * c->ta[i];
            double x1 = od[3 + k] == 0.0 ? od[k] : od[k] + od[3 + k] * c->tb[i];
            c->lo[k][i] = x0 < x1 ? x0 : x1;
            c->hi[k][i] = x0 < x1 ? x1 : x0;
        }
    }
    for (int k = 0; k < 3; k++) {
        sort_doubles(c->lo[k], c->n, c->sort_tmp);
        sort_doubles(c->hi[k], c->n, c->sort_tmp);
    }
}

/* C becomes the parts of FROM's parts inside BOX; 0 when out of memory. */
static int cell_filter(const kd_raycount *rc, const kd_raycount_cell *from, const bsp_box *box,
                       kd_raycount_cell *c)
{
    if (!cell_reserve(c, from->n))
        return 0;
    size_t n = 0;
    for (size_t i = 0; i < from->n; i++) {
        double ta = from->ta[i], tb = from->tb[i];
        if (clip_part(rc->od[from->seg[i]], box, &ta, &tb)) {
            c->seg[n] = from->seg[i];
            c->ta[n] = ta;
            c->tb[n] = tb;
            n++;
        }
    }
    c->n = n;
    c->box = *box;
    cell_sort_extremes(rc, c);
    return 1;
}

bsp_status kd_raycount_init(kd_raycount *rc, const bsp_box *root, const kd_flux_segment *seg,
                            size_t n, bsp_error *err)
{
    memset(rc, 0, sizeof *rc);
    if (n > UINT32_MAX)
        return error_set(err, BSP_ERR_INVALID, NULL, 0,
                         "sah-mixed: %zu pre-pass rays are too many to count", n);
    rc->od = malloc((n ? n : 1) * sizeof *rc->od);
    if (!rc->od || !cell_reserve(&rc->root, n ? n : 1)) {
        kd_raycount_free(rc);
        return error_set(err, BSP_ERR_NOMEM, NULL, 0, "out of memory");
    }
    size_t m = 0;
    for (size_t i = 0; i < n; i++) {
        const kd_flux_segment *s = &seg[i];
        double od[6] = {s->org.x, s->org.y, s->org.z, s->dir.x, s->dir.y, s->dir.z};
        int finite = !isnan(s->t0) && !isnan(s->t1) && s->t0 <= s->t1;
        for (int k = 0; k < 6; k++)
            finite = finite && isfinite(od[k]);
        double ta = s->t0, tb = s->t1;
        if (!finite || !clip_part(od, root, &ta, &tb) || !isfinite(ta) || !isfinite(tb))
            continue;
        memcpy(rc->od[m], od, sizeof od);
        rc->root.seg[m] = (uint32_t)m;
        rc->root.ta[m] = ta;
        rc->root.tb[m] = tb;
        m++;
    }
    rc->nseg = m;
    rc->root.n = m;
    rc->root.box = *root;
    cell_sort_extremes(rc, &rc->root);
    return BSP_OK;
}

void kd_raycount_free(kd_raycount *rc)
{
    free(rc->od);
    cell_free(&rc->root);
    memset(rc, 0, sizeof *rc);
}

void kd_raycount_cursor_init(kd_raycount_cursor *c, const kd_raycount *rc)
{
    memset(c, 0, sizeof *c);
    c->rc = rc;
}

void kd_raycount_cursor_free(kd_raycount_cursor *c)
{
    for (size_t i = 0; i < c->cap; i++)
        cell_free(&c->cells[i]);
    free(c->cells);
    memset(c, 0, sizeof *c);
}

void kd_raycount_reset(kd_raycount_cursor *c)
{
    c->top = 0;
}

static int box_contains(const bsp_box *outer, const bsp_box *b)
{
    for (int k = 0; k < 3; k++)
        if (b->lo.v[k] < outer->lo.v[k] || b->hi.v[k] > outer->hi.v[k])
            return 0;
    return 1;
}

static int box_equal(const bsp_box *a, const bsp_box *b)
{
    for (int k = 0; k < 3; k++)
        if (a->lo.v[k] != b->lo.v[k] || a->hi.v[k] != b->hi.v[k])
            return 0;
    return 1;
}

/* The deepest kept cell of C (cells[0..top), then the root) that contains
 * B; *DEPTH its index + 1, 0 for the root. The root stands for every box:
 * it holds every segment meeting the build's box. */
static const kd_raycount_cell *containing(const kd_raycount_cursor *c, const bsp_box *b,
                                          size_t *depth)
{
    for (size_t i = c->top; i > 0; i--)
        if (box_contains(&c->cells[i - 1].box, b)) {
            *depth = i;
            return &c->cells[i - 1];
        }
    *depth = 0;
    return &c->rc->root;
}

int kd_raycount_enter(kd_raycount_cursor *c, const bsp_box *cell)
{
    size_t d;
    const kd_raycount_cell *from = containing(c, cell, &d);
    c->top = d;
    if (box_equal(&from->box, cell))
        return 1;
    if (d == c->cap) {
        size_t cap = c->cap ? 2 * c->cap : 32;
        kd_raycount_cell *nc = realloc(c->cells, cap * sizeof *nc);
        if (!nc)
            return 0;
        memset(nc + c->cap, 0, (cap - c->cap) * sizeof *nc);
        c->cells = nc;
        c->cap = cap;
        from = d ? &c->cells[d - 1] : &c->rc->root; /* the array moved */
    }
    if (!cell_filter(c->rc, from, cell, &c->cells[d]))
        return 0;
    c->top = d + 1;
    return 1;
}

/* How many of the N sorted values V are <= X (>= X: sorted_count_at_least). */
static size_t count_le(const double *v, size_t n, double x)
{
    size_t lo = 0, hi = n;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (v[mid] <= x)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo;
}


double kd_raycount_measure(const kd_raycount_cursor *c, const bsp_box *b)
{
    size_t d;
    const kd_raycount_cell *e = containing(c, b, &d);
    /* the faces where B differs from E: one moved face is two binary searches */
    int moved = 0, axis = 0, upper = 0;
    for (int k = 0; k < 3; k++) {
        if (b->lo.v[k] != e->box.lo.v[k]) {
            moved++;
            axis = k;
            upper = 0;
        }
        if (b->hi.v[k] != e->box.hi.v[k]) {
            moved++;
            axis = k;
            upper = 1;
        }
    }
    if (moved == 0)
        return (double)e->n;
    if (moved == 1)
        return upper ? (double)count_le(e->lo[axis], e->n, b->hi.v[axis])
                     : (double)sorted_count_at_least(e->hi[axis], e->n, b->lo.v[axis]);
    size_t n = 0;
    for (size_t i = 0; i < e->n; i++) {
        double ta = e->ta[i], tb = e->tb[i];
        n += (size_t)clip_part(c->rc->od[e->seg[i]], b, &ta, &tb);
    }
    return (double)n;
}
