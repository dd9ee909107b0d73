/*
 * kd_traverse.c — Havran's robust recursive traversal TA_B^rec (Havran,
 * Kopal, Bittner, Zara: "Fast robust BSP tree traversal algorithm for ray
 * tracing", JGT 1998), for closest-hit and any-hit queries.
 *
 * The ray's segment inside the current node is described by an entry and an
 * exit point on a fixed stack. An interior node is classified by comparing
 * the coordinates of those points with the splitting plane — never by a t
 * value — so rays parallel to a plane, lying in it, starting on it, or with
 * zero direction components need no epsilon and never divide by zero: t is
 * computed only when the two points lie strictly on opposite sides, where
 * d[axis] cannot be 0.
 *
 * Closest hit: every primitive of a visited leaf is tested on the original
 * ray, with tmax lowered to the best hit so far, so each t is the very value
 * the naive method computes. The loop stops once the best hit lies inside
 * the current cell (t <= exit t); at equal t the lower index wins, as in the
 * naive method. The padded assignment (kd_tree.h) makes this exact.
 */
#include <math.h>

#include "accel/kd_tree.h"
#include "geom/vec.h"

#define NO_NODE UINT32_MAX
/* entry + exit + one push per level, with room to spare */
#define KD_STACK_SIZE (BSP_KD_MAX_DEPTH_LIMIT + 4)

typedef struct stack_entry {
    uint32_t node; /* the far child to visit after this point, or NO_NODE */
    int prev;      /* the previous exit point */
    double t;      /* ray parameter of the point */
    bsp_vec3 pb;   /* the point */
} stack_entry;

/* Clips RAY's [tmin, tmax] to BOX; 0 when they do not meet. Zero direction
 * components are handled by the origin test alone. */
static int clip_to_box(const bsp_box *box, const bsp_ray *ray, double *t0, double *t1)
{
    double a = ray->tmin, b = ray->tmax;
    for (int k = 0; k < 3; k++) {
        double o = ray->org.v[k], d = ray->dir.v[k];
        if (d == 0.0) {
            if (o < box->lo.v[k] || o > box->hi.v[k])
                return 0;
            continue;
        }
        double inv = 1.0 / d;
        double ta = (box->lo.v[k] - o) * inv, tb = (box->hi.v[k] - o) * inv;
        if (ta > tb) {
            double x = ta;
            ta = tb;
            tb = x;
        }
        if (ta > a)
            a = ta;
        if (tb < b)
            b = tb;
    }
    if (!(a <= b))
        return 0;
    *t0 = a;
    *t1 = b;
    return 1;
}

/* Starts a new ray in the mailbox: returns its stamp. */
static uint32_t mailbox_next(bsp_query *q, size_t nprims)
{
    if (!q->stamp)
        return 0;
    if (++q->ray_id == 0) { /* wrapped: forget every old stamp */
        for (size_t i = 0; i < nprims; i++)
            q->stamp[i] = 0;
        q->ray_id = 1;
    }
    return q->ray_id;
}

/* Descends from CURR to a leaf, pushing far children; returns the leaf. */
static uint32_t descend(const kd_tree *t, const bsp_ray *ray, stack_entry *stack, int en,
                        int *ex_io, uint32_t curr, uint64_t *steps)
{
    int ex = *ex_io;
    const kd_node *n = &t->nodes[curr];
    while (!kd_is_leaf(n)) {
        (*steps)++;
        unsigned axis = kd_axis(n);
        double s = (double)n->u.split;
        double A = stack[en].pb.v[axis], B = stack[ex].pb.v[axis];
        uint32_t left = kd_child(n), near_c, far_c;
        if (A <= s) {
            if (B <= s) { /* N1, N2, N3, P5, Z2, Z3: the left side only */
                curr = left;
                n = &t->nodes[curr];
                continue;
            }
            if (A == s) { /* Z1: starts on the plane, goes right */
                curr = left + 1;
                n = &t->nodes[curr];
                continue;
            }
            near_c = left; /* N4 */
            far_c = left + 1;
        } else {
            if (B > s) { /* P1, P2, P3, N5: the right side only */
                curr = left + 1;
                n = &t->nodes[curr];
                continue;
            }
            near_c = left + 1; /* P4 */
            far_c = left;
        }
        /* A and B lie strictly on opposite sides: d[axis] != 0 */
        double tp = (s - ray->org.v[axis]) / ray->dir.v[axis];
        int tmp = ex++;
        if (ex == en)
            ex++;
        stack_entry *e = &stack[ex];
        e->prev = tmp;
        e->t = tp;
        e->node = far_c;
        e->pb = ray_at(ray, tp);
        e->pb.v[axis] = s;
        curr = near_c;
        n = &t->nodes[curr];
    }
    *ex_io = ex;
    return curr;
}

/* Sets up the stack for RAY; returns 0 when it misses the root box. */
static int start(const kd_tree *t, const bsp_ray *ray, stack_entry *stack)
{
    double ta, tb;
    if (box_is_empty(t->box) || !clip_to_box(&t->box, ray, &ta, &tb))
        return 0;
    stack[0].t = ta;
    stack[0].pb = ray_at(ray, ta);
    stack[0].node = NO_NODE;
    stack[0].prev = 0;
    stack[1].t = tb;
    stack[1].pb = ray_at(ray, tb);
    stack[1].node = NO_NODE;
    stack[1].prev = 0;
    return 1;
}

int kd_intersect(const bsp_accel *a, bsp_query *q, const bsp_ray *ray, bsp_hit *hit)
{
    const kd_tree *t = a->impl;
    const bsp_scene *s = a->scene;
    stack_entry stack[KD_STACK_SIZE];
    hit->prim = BSP_NO_PRIM;
    if (!start(t, ray, stack))
        return 0;
    uint32_t stamp = mailbox_next(q, s->nprims);
    uint32_t *mbox = q->stamp;
    bsp_ray r = *ray; /* r.tmax follows the best hit; t never depends on it */
    int found = 0, en = 0, ex = 1;
    uint64_t steps = 0, tests = 0, leaves = 0, empty = 0, mb_hits = 0;
    uint32_t curr = 0;
    while (curr != NO_NODE) {
        curr = descend(t, ray, stack, en, &ex, curr, &steps);
        const kd_node *leaf = &t->nodes[curr];
        uint32_t cnt = kd_count(leaf);
        const uint32_t *list = t->prims + leaf->u.first;
        steps++;
        leaves++;
        empty += cnt == 0;
        for (uint32_t k = 0; k < cnt; k++) {
            uint32_t p = list[k];
            if (mbox) {
                if (mbox[p] == stamp) {
                    mb_hits++;
                    continue;
                }
                mbox[p] = stamp;
            }
            tests++;
            bsp_hit h;
            if (scene_intersect(s, p, &r, &h) &&
                (!found || h.t < hit->t || (h.t == hit->t && p < hit->prim))) {
                *hit = h;
                r.tmax = h.t;
                found = 1;
            }
        }
        if (found && hit->t <= stack[ex].t)
            break; /* the closest hit lies inside this cell */
        en = ex;
        curr = stack[ex].node;
        ex = stack[en].prev;
    }
    q->counters.traversal_steps += steps;
    q->counters.isect_tests += tests;
    q->counters.leaves_visited += leaves;
    q->counters.empty_leaves += empty;
    q->counters.mailbox_hits += mb_hits;
    return found;
}

int kd_occluded(const bsp_accel *a, bsp_query *q, const bsp_ray *ray)
{
    const kd_tree *t = a->impl;
    const bsp_scene *s = a->scene;
    stack_entry stack[KD_STACK_SIZE];
    if (!start(t, ray, stack))
        return 0;
    uint32_t stamp = mailbox_next(q, s->nprims);
    uint32_t *mbox = q->stamp;
    int found = 0, en = 0, ex = 1;
    uint64_t steps = 0, tests = 0, leaves = 0, empty = 0, mb_hits = 0;
    uint32_t curr = 0;
    while (curr != NO_NODE && !found) {
        curr = descend(t, ray, stack, en, &ex, curr, &steps);
        const kd_node *leaf = &t->nodes[curr];
        uint32_t cnt = kd_count(leaf);
        const uint32_t *list = t->prims + leaf->u.first;
        steps++;
        leaves++;
        empty += cnt == 0;
        for (uint32_t k = 0; k < cnt; k++) {
            uint32_t p = list[k];
            if (mbox) {
                if (mbox[p] == stamp) {
                    mb_hits++;
                    continue;
                }
                mbox[p] = stamp;
            }
            tests++;
            bsp_hit h;
            if (scene_intersect(s, p, ray, &h)) {
                found = 1;
                break;
            }
        }
        en = ex;
        curr = stack[ex].node;
        ex = stack[en].prev;
    }
    q->counters.traversal_steps += steps;
    q->counters.isect_tests += tests;
    q->counters.leaves_visited += leaves;
    q->counters.empty_leaves += empty;
    q->counters.mailbox_hits += mb_hits;
    return found;
}
