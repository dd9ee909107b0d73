/*
 * bvh_traverse.c — closest-hit and any-hit queries on the BVH (bvh.h):
 * depth first, the child on the ray's side of the node's axis first, the
 * other on a stack; a node is entered when the ray's interval [tmin, best t]
 * meets its box (slab test on the reciprocal direction), and popped nodes
 * are tested again against the best t found since they were pushed.
 *
 * Slabs of zero direction components: 1 / d is +-inf, so (lo - o) / d is
 * -inf or +inf, the whole line, when o lies strictly inside the slab, and
 * an empty interval when outside; NaN only when o lies exactly on a face,
 * where no accepted hit of the node can lie (bvh.h: hits lie 3/4 pad inside)
 * and either answer is safe. The min and max below are written as compares
 * so that a NaN cannot make a loop run on: every path ends.
 *
 * Counters: N_TS counts the node boxes tested, N_ETS / leaves the leaves
 * entered (none is empty), N_IT the primitives tested; the mailbox counts
 * nothing (each primitive is in one leaf).
 */
#include <math.h>

#include "accel/bvh.h"

typedef struct bvh_ray {
    double o[3], inv[3];
    unsigned neg[3]; /* direction component negative: the right child first */
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
 * direction components). */
static inline int box_hit(const bvh_node *n, const bvh_ray *r, double t0, double t1)
{
    for (unsigned k = 0; k < 3; k++) {
        double a = ((double)n->lo[k] - r->o[k]) * r->inv[k];
        double b = ((double)n->hi[k] - r->o[k]) * r->inv[k];
        t0 = max2(t0, min2(a, b));
        t1 = min2(t1, max2(a, b));
    }
    return t0 <= t1;
}

static inline void bvh_ray_init(bvh_ray *r, const bsp_ray *ray)
{
    for (unsigned k = 0; k < 3; k++) {
        r->o[k] = ray->org.v[k];
        r->inv[k] = 1.0 / ray->dir.v[k];
        r->neg[k] = signbit(ray->dir.v[k]) != 0;
    }
}

/* 1 when RAY lies in S's precision domain (scene_internal.h). */
static inline int bvh_in_domain(const bsp_scene *s, const bsp_ray *ray)
{
    const double *d = ray->dir.v;
    return scene_ray_in_domain(s, ray->org.v, d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
}

/* The near child of interior node I (N) for R, and the far one in *FAR. */
static inline uint32_t near_child(const bvh_node *n, uint32_t i, const bvh_ray *r,
                                  uint32_t *far)
{
    if (r->neg[BVH_AXIS(n)]) {
        *far = i + 1;
        return n->index;
    }
    *far = n->index;
    return i + 1;
}

/* A depth-first walk: the node to look at next (UINT32_MAX: pop one), the
 * far children still to look at, and the count of boxes tested. */
typedef struct bvh_walk {
    uint32_t next;
    unsigned sp;
    uint64_t tested;
    uint32_t stack[BVH_MAX_DEPTH + 2]; /* one far child per level at most */
} bvh_walk;

/* The next leaf of T whose box R's interval [T0, T1] meets, or NULL when the
 * walk is over. Popped nodes are tested with the T1 of now, the best hit's. */
static inline const bvh_node *next_leaf(const bvh *t, const bvh_ray *r, double t0, double t1,
                                        bvh_walk *w)
{
    for (;;) {
        if (w->next == UINT32_MAX) {
            if (!w->sp)
                return NULL;
            w->next = w->stack[--w->sp];
        }
        uint32_t i = w->next;
        const bvh_node *n = &t->nodes[i];
        w->tested++;
        w->next = UINT32_MAX;
        if (!box_hit(n, r, t0, t1))
            continue;
        if (BVH_COUNT(n))
            return n;
        uint32_t far;
        w->next = near_child(n, i, r, &far);
        w->stack[w->sp++] = far;
    }
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
    isect_ray r;
    isect_ray_init(&r, ray, s->hit_tol); /* in the domain: checked */
    const double tmin = ray->tmin;
    double tmax = ray->tmax; /* follows the best hit; t never depends on it */
    scene_isect_hit best = {INFINITY, 0.0, 0.0, 1.0}, h;
    uint32_t best_p = BSP_NO_PRIM;
    uint64_t leaves = 0, refs = 0, tests = 0;
    bvh_walk w = {.next = 0};
    const bvh_node *n;
    while ((n = next_leaf(t, &br, tmin, tmax, &w))) {
        uint32_t cnt = BVH_COUNT(n);
        leaves++;
        refs += cnt;
        for (const kd_local *L = t->rec + n->index, *end = L + cnt; L != end; L++) {
            if (L->prim == from)
                continue;
            tests++;
            /* every hit found is at most tmax: better when its t is smaller
             * or, at equal t, its index lower (the naive order) */
            if (kd_local_isect(s, L, &r, tmax, &h) && (h.t < best.t || L->prim < best_p)) {
                best = h;
                best_p = L->prim;
                tmax = h.t;
            }
        }
    }
    /* interior: every box tested but the leaves entered; no empty leaves,
     * no skips; mailbox hits = refs - tests = the left-out primitive */
    query_count(q, w.tested - leaves, leaves, 0, leaves, refs, tests);
    if (best_p == BSP_NO_PRIM)
        return 0;
    scene_hit_finish(&best, best_p, hit);
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
    isect_ray r;
    isect_ray_init(&r, ray, s->hit_tol);
    scene_isect_hit h;
    uint64_t leaves = 0, refs = 0, tests = 0;
    bvh_walk w = {.next = 0};
    const bvh_node *n;
    int found = 0;
    while (!found && (n = next_leaf(t, &br, ray->tmin, ray->tmax, &w))) {
        uint32_t cnt = BVH_COUNT(n);
        leaves++;
        refs += cnt;
        for (const kd_local *L = t->rec + n->index, *end = L + cnt; L != end && !found; L++) {
            if (L->prim == from)
                continue;
            tests++;
            found = kd_local_isect(s, L, &r, ray->tmax, &h);
        }
    }
    query_count(q, w.tested - leaves, leaves, 0, leaves, refs, tests);
    return found;
}
