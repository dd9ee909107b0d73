/*
 * polygon_slabs.c — slabs for the crossing test of polygons with many
 * vertices (gears' 144-gons: the walk of every edge was 55 % of the
 * instructions of its primary rays).
 *
 * In the polygon's projection (axes axis_u, axis_v), the distinct v values
 * of its vertices y[0] < ... < y[k-1] cut the plane into slabs. Which edges
 * cross the line v = py depends only on py's slab: an edge crosses when one
 * endpoint lies above py and the other at or below it, that is, for py in
 * [y[j], y[j+1]), when its lower endpoint's v is at most y[j] and its upper
 * one's at least y[j+1]. So each slab lists its crossing edges once, and a
 * test finds py's slab by binary search and computes only those edges'
 * abscissas (polygon_contains_slabs in isect.h) — from the same operands as
 * the walk of every edge (polygon_contains_2d), so the same answer, bit for
 * bit. An edge spans the slabs between its endpoints' ranks, so the lists
 * hold O(n^2) entries at worst (a zigzag); a polygon whose lists would hold
 * more than POLYGON_SLAB_BUDGET entries per vertex keeps the walk.
 */
#include <stdlib.h>

#include "geom/isect.h"

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* Room for NEED elements of SIZE bytes in *P of capacity *CAP. */
static int grow(void **p, size_t *cap, size_t need, size_t size)
{
    if (need <= *cap)
        return 1;
    size_t ncap = *cap ? *cap : 64;
    while (ncap < need)
        ncap *= 2;
    void *np = realloc(*p, ncap * size);
    if (!np)
        return 0;
    *p = np;
    *cap = ncap;
    return 1;
}

void polygon_slab_pool_free(polygon_slab_pool *pool)
{
    free(pool->y);
    free(pool->off);
    free(pool->entry);
    free(pool->edge);
    *pool = (polygon_slab_pool){0};
}

int polygon_slabs_build(polygon_shape *p, const bsp_vec3 *verts, polygon_slab_pool *pool)
{
    p->slab_first = 0;
    p->nslabs = 0;
    const uint32_t n = p->count;
    if (n < POLYGON_SLAB_MIN)
        return 1;
    const int au = p->axis_u, av = p->axis_v;
    const bsp_vec3 *vs = verts + p->first;
    double *y = malloc(n * sizeof *y);
    uint32_t *count = calloc(n, sizeof *count);
    int ok = y && count;
    if (!ok)
        goto done;
    for (uint32_t i = 0; i < n; i++)
        y[i] = vs[i].v[av];
    qsort(y, n, sizeof *y, cmp_double);
    uint32_t k = 1; /* distinct values (-0 and 0 are one) */
    for (uint32_t i = 1; i < n; i++)
        if (y[i] > y[k - 1])
            y[k++] = y[i];
    if (k < 2)
        goto done; /* (not after setup: the polygon has an area) */
    /* entries per slab: edge (i-1, i) spans the slabs rank(lower) .. rank(upper) - 1 */
    size_t total = 0;
    for (uint32_t i = 0; i < n; i++) {
        double a = vs[i == 0 ? n - 1 : i - 1].v[av], b = vs[i].v[av];
        if (a == b)
            continue; /* never crosses */
        uint32_t r0 = polygon_slab_of(y, k, a < b ? a : b),
                 r1 = polygon_slab_of(y, k, a < b ? b : a);
        total += r1 - r0;
        count[r0]++; /* a difference array: +1 at r0, -1 at r1 */
        count[r1]--;
    }
    if (total > (size_t)POLYGON_SLAB_BUDGET * n || pool->nentry + total > UINT32_MAX ||
        pool->nedge + n > UINT32_MAX || pool->ny + k > UINT32_MAX)
        goto done; /* the walk of every edge */
    ok = grow((void **)&pool->y, &pool->cap_y, pool->ny + k, sizeof *pool->y) &&
         grow((void **)&pool->off, &pool->cap_off, pool->ny + k, sizeof *pool->off) &&
         grow((void **)&pool->entry, &pool->cap_entry, pool->nentry + total, sizeof *pool->entry) &&
         grow((void **)&pool->edge, &pool->cap_edge, pool->nedge + n, sizeof *pool->edge);
    if (!ok)
        goto done;
    /* off[j]: slab j's first entry; running sums of the difference array,
     * then each slab's fill position */
    uint32_t *off = pool->off + pool->ny;
    size_t at = pool->nentry;
    uint32_t live = 0; /* edges spanning slab j */
    for (uint32_t j = 0; j < k; j++) {
        off[j] = (uint32_t)at;
        live += count[j];
        count[j] = (uint32_t)at; /* the fill position of slab j */
        at += j + 1 < k ? live : 0;
    }
    for (uint32_t i = 0; i < n; i++) {
        const double *a = vs[i == 0 ? n - 1 : i - 1].v, *b = vs[i].v;
        if (a[av] == b[av])
            continue;
        /* the walk's lower endpoint is the one not above py: the lower v */
        const double *lo = a[av] < b[av] ? a : b, *hi = a[av] < b[av] ? b : a;
        uint32_t e = (uint32_t)pool->nedge++;
        pool->edge[e] = (polygon_edge){lo[au], lo[av], hi[au] - lo[au], hi[av] - lo[av]};
        uint32_t r0 = polygon_slab_of(y, k, lo[av]), r1 = polygon_slab_of(y, k, hi[av]);
        for (uint32_t j = r0; j < r1; j++)
            pool->entry[count[j]++] = e;
    }
    for (uint32_t j = 0; j < k; j++)
        pool->y[pool->ny + j] = y[j];
    p->slab_first = (uint32_t)pool->ny;
    p->nslabs = k;
    pool->ny += k;
    pool->nentry += total;
done:
    free(y);
    free(count);
    return ok;
}

uint32_t polygon_test_units(const polygon_shape *p, const polygon_slab_pool *pool)
{
    if (p->nslabs == 0)
        return p->count;
    const uint32_t k = p->nslabs, slabs = k - 1;
    uint32_t steps = 0; /* ceil(log2(slabs)) */
    while (((uint64_t)1 << steps) < slabs)
        steps++;
    const uint32_t *off = pool->off + p->slab_first;
    uint32_t entries = off[k - 1] - off[0];
    return steps + (entries + slabs - 1) / slabs;
}
