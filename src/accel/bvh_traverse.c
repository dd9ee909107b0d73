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
 * Slabs of zero direction components: 1 / d is +-inf, so (lo - o) / d is
 * -inf or +inf, the whole line, when o lies strictly inside the slab, and
 * an empty interval when outside; NaN only when o lies exactly on a face,
 * where no accepted hit of the node can lie and either answer is safe. The
 * min and max below are written as compares so that a NaN cannot make a
 * loop run on: every path ends.
 *
 * Counters: N_TS counts the node boxes tested, N_ETS / leaves the leaves
 * entered (none is empty), N_IT the primitives tested; the mailbox counts
 * nothing (each primitive is in one leaf).
 */
#include <math.h>

#include "accel/bvh.h"

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

/* Whether R's interval [T0, T1] meets the box of N (see above for zero
 * direction components); *ENTRY is where it enters. */
static inline int box_hit(const bvh_node *n, const bvh_ray *r, double t0, double t1,
                          double *entry)
{
    for (unsigned k = 0; k < 3; k++) {
        double a = ((double)n->lo[k] - r->o[k]) * r->inv[k];
        double b = ((double)n->hi[k] - r->o[k]) * r->inv[k];
        t0 = max2(t0, min2(a, b));
        t1 = min2(t1, max2(a, b));
    }
    *entry = t0;
    return t0 <= t1;
}

static inline void bvh_ray_init(bvh_ray *r, const bsp_ray *ray)
{
    for (unsigned k = 0; k < 3; k++) {
        r->o[k] = ray->org.v[k];
        r->inv[k] = 1.0 / ray->dir.v[k];
    }
}

/* 1 when RAY lies in S's precision domain (scene_internal.h). */
static inline int bvh_in_domain(const bsp_scene *s, const bsp_ray *ray)
{
    const double *d = ray->dir.v;
    return scene_ray_in_domain(s, ray->org.v, d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
}

/* A walk of the tree: the nodes still to visit, each with its entry t, and
 * the count of boxes tested. */
typedef struct bvh_walk {
    unsigned sp;
    uint64_t tested;
    uint32_t node[BVH_MAX_DEPTH + 2]; /* one pushed child per level at most */
    double entry[BVH_MAX_DEPTH + 2];
} bvh_walk;

/* One query's leaf step: tests the records of leaf N against the ray and
 * says whether the query is over (an any-hit query found one). */
typedef int (*leaf_fn)(void *ctx, const bvh_node *n);

/* The walk of T for R over [TMIN, *TMAX] (*TMAX may shrink as LEAF finds
 * hits), calling LEAF for every leaf whose box the interval meets, nearer
 * siblings first; returns 1 when LEAF ended it. Inlined into both queries,
 * so LEAF is a direct call. */
static inline __attribute__((always_inline)) int
walk(const bvh *t, const bvh_ray *r, double tmin, const double *tmax, bvh_walk *w, leaf_fn leaf,
     void *ctx)
{
    double e0;
    const bvh_node *nodes = t->nodes;
    w->tested++;
    if (!box_hit(&nodes[0], r, tmin, *tmax, &e0))
        return 0;
    if (BVH_COUNT(&nodes[0]))
        return leaf(ctx, &nodes[0]);
    uint32_t pair = nodes[0].index;
    for (;;) {
        const bvh_node *c = &nodes[pair];
        double e[2];
        int hit0 = box_hit(&c[0], r, tmin, *tmax, &e[0]);
        int hit1 = box_hit(&c[1], r, tmin, *tmax, &e[1]);
        w->tested += 2;
        unsigned near = hit1 && (!hit0 || e[1] < e[0]), far = !near;
        int hit_far = near ? hit0 : hit1;
        int go = -1; /* the child to enter */
        if (hit0 | hit1) {
            if (!BVH_COUNT(&c[near]))
                go = (int)near;
            else if (leaf(ctx, &c[near]))
                return 1;
        }
        if (hit_far && e[far] <= *tmax) { /* not beyond a hit the near leaf found */
            if (go >= 0) {
                w->node[w->sp] = pair + far;
                w->entry[w->sp++] = e[far];
            } else if (!BVH_COUNT(&c[far])) {
                go = (int)far;
            } else if (leaf(ctx, &c[far])) {
                return 1;
            }
        }
        if (go >= 0) {
            pair = c[go].index;
            continue;
        }
        for (;;) { /* the next node pushed still nearer than the best hit */
            if (!w->sp)
                return 0;
            w->sp--;
            if (w->entry[w->sp] > *tmax)
                continue;
            const bvh_node *n = &nodes[w->node[w->sp]];
            if (!BVH_COUNT(n)) {
                pair = n->index;
                break;
            }
            if (leaf(ctx, n))
                return 1;
        }
    }
}

/* A query's state, for its leaf steps. */
typedef struct query_state {
    const bsp_scene *s;
    const kd_local *rec;
    isect_ray r;
    uint32_t from, best_p;
    double tmax; /* closest hit: follows the best hit; t never depends on it */
    scene_isect_hit best;
    uint64_t leaves, refs, tests;
} query_state;

/* Tests leaf N's records for the query C, closest hit or ANY hit; 1 when an
 * any-hit query found one. */
static inline __attribute__((always_inline)) int leaf_records(query_state *c,
                                                              const bvh_node *n, int any)
{
    uint32_t cnt = BVH_COUNT(n);
    scene_isect_hit h;
    c->leaves++;
    c->refs += cnt;
    for (const kd_local *L = c->rec + n->index, *end = L + cnt; L != end; L++) {
        if (L->prim == c->from)
            continue;
        c->tests++;
        if (!kd_local_isect(c->s, L, &c->r, c->tmax, &h))
            continue;
        if (any)
            return 1;
        /* every hit found is at most tmax: better when its t is smaller or,
         * at equal t, its index lower (the naive order) */
        if (h.t < c->best.t || L->prim < c->best_p) {
            c->best = h;
            c->best_p = L->prim;
            c->tmax = h.t;
        }
    }
    return 0;
}

static inline __attribute__((always_inline)) int closest_leaf(void *ctx, const bvh_node *n)
{
    return leaf_records(ctx, n, 0);
}

static inline __attribute__((always_inline)) int any_leaf(void *ctx, const bvh_node *n)
{
    return leaf_records(ctx, n, 1);
}

int bvh_intersect(const bsp_accel *a, bsp_query *q, const bsp_ray *ray, uint32_t from,
                  bsp_hit *hit)
{
    const bvh *t = a->impl;
    const bsp_scene *s = a->scene;
    hit->prim = BSP_NO_PRIM;
    if (__builtin_expect(!bvh_in_domain(s, ray), 0))
        return naive_scene_intersect(s, q, ray, from, hit);
    if (!t->nnodes)
        return 0;
    bvh_ray br;
    bvh_ray_init(&br, ray);
    query_state c = {.s = s, .rec = t->rec, .from = from, .best_p = BSP_NO_PRIM,
                     .tmax = ray->tmax};
    c.best = (scene_isect_hit){INFINITY, 0.0, 0.0, 1.0};
    isect_ray_init(&c.r, ray, s->hit_tol); /* in the domain: checked */
    bvh_walk w;
    w.sp = 0;
    w.tested = 0;
    walk(t, &br, ray->tmin, &c.tmax, &w, closest_leaf, &c);
    /* interior: every box tested but the leaves entered; no empty leaves,
     * no skips; mailbox hits = refs - tests = the left-out primitive */
    query_count(q, w.tested - c.leaves, c.leaves, 0, c.leaves, c.refs, c.tests);
    if (c.best_p == BSP_NO_PRIM)
        return 0;
    scene_hit_finish(&c.best, c.best_p, hit);
    return 1;
}

int bvh_occluded(const bsp_accel *a, bsp_query *q, const bsp_ray *ray, uint32_t from)
{
    const bvh *t = a->impl;
    const bsp_scene *s = a->scene;
    if (__builtin_expect(!bvh_in_domain(s, ray), 0))
        return naive_scene_occluded(s, q, ray, from);
    if (!t->nnodes)
        return 0;
    bvh_ray br;
    bvh_ray_init(&br, ray);
    query_state c = {.s = s, .rec = t->rec, .from = from, .tmax = ray->tmax};
    isect_ray_init(&c.r, ray, s->hit_tol);
    bvh_walk w;
    w.sp = 0;
    w.tested = 0;
    int found = walk(t, &br, ray->tmin, &c.tmax, &w, any_leaf, &c);
    query_count(q, w.tested - c.leaves, c.leaves, 0, c.leaves, c.refs, c.tests);
    return found;
}
