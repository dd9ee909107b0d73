/*
 * bvh_traverse.c — closest-hit and any-hit queries on the BVH (bvh.h).
 * At an interior node both children's boxes (one cache line) are tested
 * against the ray's interval [tmin, best t] (slab tests on the reciprocal
 * direction); a leaf that is met is tested at once, the nearer first, and of
 * two interior children met the nearer is entered and the other pushed with
 * its entry t. A popped node is skipped when that entry lies beyond the best
 * t found since: the entry computed is at most the t of any hit in its
 * subtree (bvh.h: hits lie 3/4 pad inside every box above them, and the slab
 * arithmetic errs far less), so the skip loses no hit, ties included.
 *
 * The two boxes of a pair are tested at once, in SSE2's two double lanes
 * where the compiler offers them (x86-64 always does), else one after the
 * other: the same operations on the same doubles either way (their min and
 * max differ only in which operand a NaN yields, below).
 *
 * Slabs of zero direction components: 1 / d is +-inf, so (lo - o) / d is
 * -inf or +inf, the whole line, when o lies strictly inside the slab, and
 * an empty interval when outside; NaN only when o lies exactly on a face,
 * where no accepted hit of the node can lie and either answer is safe. No
 * loop depends on those values: every path ends.
 *
 * Counters: N_TS counts the node boxes tested, N_ETS / leaves the leaves
 * entered (none is empty), N_IT the primitives tested; the mailbox counts
 * nothing (each primitive is in one leaf).
 */
#include <math.h>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "accel/bvh.h"
#include "accel/bvh_query.h"

typedef struct bvh_ray {
    double o[3], inv[3];
} bvh_ray;

static inline double min2(double a, double b)
{
    return b < a ? b : a;
}
static inline double max2(double a, double b)
{
    return b > a ? b : a;
}

/* Clips [*T0, *T1] to R's slab LO..HI on axis K. */
static inline void slab(const bvh_ray *r, unsigned k, float lo, float hi, double *t0, double *t1)
{
    double a = ((double)lo - r->o[k]) * r->inv[k];
    double b = ((double)hi - r->o[k]) * r->inv[k];
    *t0 = max2(*t0, min2(a, b));
    *t1 = min2(*t1, max2(a, b));
}

/* Whether R's interval [T0, T1] meets the box of N (see above for zero
 * direction components); *ENTRY is where it enters. (The root's test.) */
static inline int box_hit(const bvh_node *n, const bvh_ray *r, double t0, double t1,
                          double *entry)
{
    for (unsigned k = 0; k < 3; k++)
        slab(r, k, n->lo[k], n->hi[k], &t0, &t1);
    *entry = t0;
    return t0 <= t1;
}

/* Which boxes of pair P R's interval [T0, T1] meets (bit c for child c);
 * E[c] is where it enters child c's. */
static inline __attribute__((always_inline)) unsigned
pair_hit(const bvh_pair *p, const bvh_ray *r, double t0, double t1, double e[2])
{
#if defined(__SSE2__)
    __m128d lo_t = _mm_set1_pd(t0), hi_t = _mm_set1_pd(t1);
    for (unsigned k = 0; k < 3; k++) {
        /* both siblings' bounds on axis k, converted at once */
        __m128d lo = _mm_cvtps_pd(_mm_castsi128_ps(_mm_loadl_epi64((const __m128i *)p->lo[k])));
        __m128d hi = _mm_cvtps_pd(_mm_castsi128_ps(_mm_loadl_epi64((const __m128i *)p->hi[k])));
        __m128d o = _mm_set1_pd(r->o[k]), inv = _mm_set1_pd(r->inv[k]);
        __m128d a = _mm_mul_pd(_mm_sub_pd(lo, o), inv);
        __m128d b = _mm_mul_pd(_mm_sub_pd(hi, o), inv);
        lo_t = _mm_max_pd(lo_t, _mm_min_pd(a, b));
        hi_t = _mm_min_pd(hi_t, _mm_max_pd(a, b));
    }
    _mm_storeu_pd(e, lo_t);
    return (unsigned)_mm_movemask_pd(_mm_cmple_pd(lo_t, hi_t));
#else
    unsigned mask = 0;
    for (unsigned c = 0; c < 2; c++) {
        double a0 = t0, a1 = t1;
        for (unsigned k = 0; k < 3; k++)
            slab(r, k, p->lo[k][c], p->hi[k][c], &a0, &a1);
        e[c] = a0;
        mask |= (unsigned)(a0 <= a1) << c;
    }
    return mask;
#endif
}

static inline void bvh_ray_init(bvh_ray *r, const bsp_ray *ray)
{
    for (unsigned k = 0; k < 3; k++) {
        r->o[k] = ray->org.v[k];
        r->inv[k] = 1.0 / ray->dir.v[k];
    }
}

/* A walk of the tree: the nodes still to visit (ids, bvh.h), each with its
 * entry t, and the count of boxes tested. */
typedef struct bvh_walk {
    unsigned sp;
    uint64_t tested;
    uint32_t node[BVH_MAX_DEPTH + 2]; /* one pushed child per level at most */
    double entry[BVH_MAX_DEPTH + 2];
} bvh_walk;

/* One query's leaf step: tests COUNT records from FIRST against the ray and
 * says whether the query is over (an any-hit query found one). */
typedef int (*leaf_fn)(void *ctx, uint32_t first, uint32_t count);

/* The walk of T for R over [TMIN, *TMAX] (*TMAX may shrink as LEAF finds
 * hits), calling LEAF for every leaf whose box the interval meets, nearer
 * siblings first; returns 1 when LEAF ended it. Inlined into both queries,
 * so LEAF is a direct call. */
static inline __attribute__((always_inline)) int
walk(const bvh *t, const bvh_ray *r, double tmin, const double *tmax, bvh_walk *w, leaf_fn leaf,
     void *ctx)
{
    double e0;
    w->tested++;
    if (!box_hit(&t->root, r, tmin, *tmax, &e0))
        return 0;
    if (BVH_COUNT(&t->root))
        return leaf(ctx, t->root.index, BVH_COUNT(&t->root));
    uint32_t pair = t->root.index; /* the pair's first id */
    for (;;) {
        const bvh_pair *p = &t->pairs[(pair - 2) >> 1];
        double e[2];
        unsigned hit = pair_hit(p, r, tmin, *tmax, e);
        w->tested += 2;
        unsigned near = hit == 2 || (hit == 3 && e[1] < e[0]), far = !near;
        int go = -1; /* the child to enter */
        if (hit) {
            uint32_t cnt = p->meta[near] >> 2;
            if (!cnt)
                go = (int)near;
            else if (leaf(ctx, p->index[near], cnt))
                return 1;
        }
        if (hit == 3 && e[far] <= *tmax) { /* not beyond a hit the near leaf found */
            uint32_t cnt = p->meta[far] >> 2;
            if (go >= 0) {
                w->node[w->sp] = pair + far;
                w->entry[w->sp++] = e[far];
            } else if (!cnt) {
                go = (int)far;
            } else if (leaf(ctx, p->index[far], cnt)) {
                return 1;
            }
        }
        if (go >= 0) {
            pair = p->index[go];
            continue;
        }
        for (;;) { /* the next node pushed still nearer than the best hit */
            if (!w->sp)
                return 0;
            w->sp--;
            if (w->entry[w->sp] > *tmax)
                continue;
            uint32_t id = w->node[w->sp];
            const bvh_pair *q = &t->pairs[(id - 2) >> 1];
            uint32_t cnt = q->meta[id & 1u] >> 2;
            if (!cnt) {
                pair = q->index[id & 1u];
                break;
            }
            if (leaf(ctx, q->index[id & 1u], cnt))
                return 1;
        }
    }
}

/* The leaves' tests, a function each: walk calls a leaf from four places,
 * and the kernels inlined into each took the compiler most of its time on
 * this file (a call per leaf, whose tests cost far more). */
static __attribute__((noinline)) int closest_leaf(void *ctx, uint32_t first, uint32_t cnt)
{
    return leaf_records(ctx, first, cnt, 0);
}

static __attribute__((noinline)) int any_leaf(void *ctx, uint32_t first, uint32_t cnt)
{
    return leaf_records(ctx, first, cnt, 1);
}

/* Closest hit into HIT, or occlusion when HIT is NULL. */
static inline __attribute__((always_inline)) int query2(const bsp_accel *a, bsp_query *q,
                                                        const bsp_ray *ray, uint32_t from,
                                                        bsp_hit *hit)
{
    int out;
    if (query_without_walk(a, q, ray, from, hit, &out))
        return out;
    const bvh *t = a->impl;
    bvh_ray br;
    bvh_ray_init(&br, ray);
    query_state c;
    query_start(&c, a->scene, t, ray, from);
    bvh_walk w;
    w.sp = 0;
    w.tested = 0;
    int found = hit ? walk(t, &br, ray->tmin, &c.tmax, &w, closest_leaf, &c)
                    : walk(t, &br, ray->tmin, &c.tmax, &w, any_leaf, &c);
    int closest = query_finish(q, &c, w.tested, hit);
    return hit ? closest : found;
}

int bvh_intersect(const bsp_accel *a, bsp_query *q, const bsp_ray *ray, uint32_t from,
                  bsp_hit *hit)
{
    return query2(a, q, ray, from, hit);
}

int bvh_occluded(const bsp_accel *a, bsp_query *q, const bsp_ray *ray, uint32_t from)
{
    return query2(a, q, ray, from, NULL);
}
