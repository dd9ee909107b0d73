/*
 * kd_traverse.c — Havran's robust recursive traversal TA_B^rec (Havran,
 * Kopal, Bittner, Zara: "Fast robust BSP tree traversal algorithm for ray
 * tracing", JGT 1998), for closest-hit and any-hit queries.
 *
 * The ray's segment inside the current node is described by an entry point
 * and an exit point; the exit points of the cells still to visit form a
 * stack (the top is the current cell's exit), the entry point is a copy of
 * the last exit popped. An interior node is classified by comparing the
 * coordinates of those points with the splitting plane — never by a t
 * value — so rays parallel to a plane, lying in it, starting on it, or with
 * zero direction components need no epsilon: t is computed only when the
 * two points lie strictly on opposite sides, where d[axis] cannot be 0.
 * That t is (s - o) * (1 / d) with the reciprocal taken once per ray, not
 * the quotient (s - o) / d: it may differ from the quotient by an ulp or
 * two, far below the padding (kd_tree.h), and it never becomes the t of a
 * hit — those come from the shape kernels alone. (A subnormal d makes 1 / d
 * infinite: such a push falls back to the quotient.)
 *
 * Closest hit: every primitive of a visited leaf is tested on the original
 * ray, with tmax lowered to the best hit so far, so each t is the very value
 * the naive method computes. The loop stops once the best hit lies inside
 * the current cell (t <= exit t); at equal t the lower index wins, as in the
 * naive method. The padded assignment (kd_tree.h) makes this exact.
 *
 * Speed (primary rays spend most of their time here, not in the shape
 * tests): the descent is latency-bound, one node's load waiting for its
 * parent's, so it is one inlined loop over node byte offsets in which a
 * child's load is one AND after its parent's (NODE_WORD: +0.3 to +12 % rays
 * per second on the SPD scenes against pointers, index >> 2 and a scaled
 * add, which put three operations between the loads); its branches
 * are kept (coherent rays predict them well, and a branch-free selection
 * puts the loads and compares on the loop-carried path: measured 1.3-2x
 * slower); a push computes no quotient and stores only the point, its t and
 * the far child; the shape kernels (geom/isect.h) are inlined into the leaf
 * loop and see dot(dir, dir) computed once per ray; a hit keeps only t and,
 * for triangles, the unnormalised barycentrics, and u, v are divided out
 * once for the final hit. Counters are kept in locals and derived where
 * possible (mailbox hits = entries met - tests, empty leaves = leaves -
 * non-empty leaves).
 */
#include <math.h>
#include <stddef.h>
#include <string.h>

#include "accel/kd_local.h"
#include "accel/kd_tree.h"
#include "accel/kd_walk.h"
#include "geom/vec.h"

/* root exit + one push per level, with room to spare */
#define KD_STACK_SIZE (BSP_KD_MAX_DEPTH_LIMIT + 4)

/* An exit point: where the ray leaves the current cell, and the far child
 * whose cell it enters there (the exit of the root box, at the bottom of the
 * stack, has none). */
typedef struct exit_point {
    double pb[3]; /* the point */
    double t;     /* ray parameter of the point (+inf for the root box's: start) */
    size_t node;  /* byte offset of the far child to visit after this point */
} exit_point;

/* The ray as the traversal sees it: origin, direction and its reciprocal. */
typedef struct trav_ray {
    double o[3], d[3], inv[3];
} trav_ray;

static inline void trav_ray_init(trav_ray *r, const bsp_ray *ray)
{
    r->o[0] = ray->org.x;
    r->o[1] = ray->org.y;
    r->o[2] = ray->org.z;
    r->d[0] = ray->dir.x;
    r->d[1] = ray->dir.y;
    r->d[2] = ray->dir.z;
    r->inv[0] = 1.0 / ray->dir.x;
    r->inv[1] = 1.0 / ray->dir.y;
    r->inv[2] = 1.0 / ray->dir.z;
}

/* Clips the interval [*A, *B] to the slab LO <= o + t d <= HI (INV = 1 / d);
 * 0 when the ray is parallel to the slab and outside it. */
static inline int clip_slab(double o, double d, double inv, double lo, double hi, double *a,
                            double *b)
{
    if (d == 0.0)
        return !(o < lo || o > hi);
    double ta = (lo - o) * inv, tb = (hi - o) * inv;
    if (ta > tb) {
        double x = ta;
        ta = tb;
        tb = x;
    }
    if (ta > *a)
        *a = ta;
    if (tb < *b)
        *b = tb;
    return 1;
}

/* Sets up the entry point EN and the exit point EX of RAY's segment inside
 * the root box; returns 0 when they do not meet. EX gets node NULL and t
 * +inf, not the exit's t: every query ends in the last cell, and so the
 * closest-hit loop's stop test (best t <= exit t) ends it there, with a hit
 * or without, and the loop needs no NULL test (3 instructions per leaf). Zero
 * direction components are handled by the origin test alone. Inlined into
 * both queries (as a call: 2-9 more instructions per primary ray). */
static inline __attribute__((always_inline)) int
start(const kd_tree *t, const bsp_ray *ray, const trav_ray *r, double *en, exit_point *ex)
{
    const bsp_box *box = &t->box;
    double a = ray->tmin, b = ray->tmax;
    if (t->box_empty || !clip_slab(r->o[0], r->d[0], r->inv[0], box->lo.x, box->hi.x, &a, &b) ||
        !clip_slab(r->o[1], r->d[1], r->inv[1], box->lo.y, box->hi.y, &a, &b) ||
        !clip_slab(r->o[2], r->d[2], r->inv[2], box->lo.z, box->hi.z, &a, &b) || !(a <= b))
        return 0;
    /* unrolled (the loop was not: 40 instructions per ray) */
    en[0] = r->o[0] + r->d[0] * a;
    en[1] = r->o[1] + r->d[1] * a;
    en[2] = r->o[2] + r->d[2] * a;
    ex->pb[0] = r->o[0] + r->d[0] * b;
    ex->pb[1] = r->o[1] + r->d[1] * b;
    ex->pb[2] = r->o[2] + r->d[2] * b;
    ex->t = INFINITY;
    ex->node = 0;
    return 1;
}

/* 1 when RAY lies in the precision domain (scene_internal.h). */
static inline int in_domain(const bsp_scene *s, const trav_ray *r)
{
    double dd = r->d[0] * r->d[0] + r->d[1] * r->d[1] + r->d[2] * r->d[2];
    return scene_ray_in_domain(s, r->o, dd);
}

/* The t where the ray crosses the plane S on AXIS (d[axis] != 0). */
static inline __attribute__((always_inline)) double crossing_t(const trav_ray *r, unsigned axis,
                                                               double s)
{
    double tp = (s - r->o[axis]) * r->inv[axis];
    if (__builtin_expect(!(fabs(tp) < INFINITY), 0))
        tp = (s - r->o[axis]) / r->d[axis]; /* a subnormal d: 1 / d overflowed */
    return tp;
}

/* P = the ray's point at TP, on the plane S of AXIS. */
static inline __attribute__((always_inline)) void plane_point(const trav_ray *r, unsigned axis,
                                                              double s, double tp, double p[3])
{
    p[0] = r->o[0] + r->d[0] * tp;
    p[1] = r->o[1] + r->d[1] * tp;
    p[2] = r->o[2] + r->d[2] * tp;
    p[axis] = s;
}

/* Pushes the exit point where the ray crosses the plane S on AXIS (the
 * endpoints lie strictly on opposite sides of it, so d[axis] != 0), with the
 * far child FAR to visit after it. */
static inline __attribute__((always_inline)) exit_point *
push(exit_point *ex, const trav_ray *r, unsigned axis, double s, size_t far)
{
    double tp = crossing_t(r, axis, s);
    ex++;
    ex->t = tp;
    ex->node = far;
    plane_point(r, axis, s, tp, ex->pb);
    return ex;
}

/* Enters the far side of the plane S on AXIS at once, its near side being an
 * empty leaf: the entry point EN becomes the crossing, the very point a push
 * and the pop after the empty leaf would have made it. */
static inline __attribute__((always_inline)) void skip_to_far(const trav_ray *r, unsigned axis,
                                                              double s, double en[3])
{
    plane_point(r, axis, s, crossing_t(r, axis, s), en);
}

/* The 64-bit word of the node at byte offset OFF + DISP of BASE (DISP a
 * constant): on x86-64 one load whose address is BASE + OFF + DISP, which
 * compilers otherwise compute with an add before the load, one more cycle
 * on the descent's critical path (node load -> AND -> next load). */
#if defined(__x86_64__) && defined(__GNUC__)
#define NODE_WORD(base, off, disp, w)                                                         \
    __asm__("movq %c3(%1,%2,1), %0"                                                           \
            : "=r"(w)                                                                         \
            : "r"(base), "r"(off), "i"(disp),                                                 \
              "m"(*(const char(*)[sizeof(kd_node)])((base) + (off) + (disp))))
#else
#define NODE_WORD(base, off, disp, w) memcpy(&(w), (base) + (off) + (disp), sizeof(w))
#endif

/* A node word's bits: its low half (kd_node's first member on a
 * little-endian machine). */
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__
#define WORD_BITS(w) ((uint32_t)((w) >> 32))
#else
#define WORD_BITS(w) ((uint32_t)(w))
#endif

/* The split of the interior node at byte offset OFF of BASE, read by itself
 * (a convert from memory) rather than taken from the node's word, which put
 * a shift and a move from the integer registers between the load and the
 * compare the branch waits for: +1 to +5 % rays per second (dragon, tetra:8,
 * lattice, teapot). */
static inline double node_split(const char *base, size_t off)
{
    float f;
    memcpy(&f, base + off + offsetof(kd_node, u), sizeof f);
    return (double)f;
}

/* A ray's counts of interior nodes visited and of empty leaves skipped,
 * packed in one word (the low and the high 32 bits: a ray meets fewer than
 * 2^32 nodes), so the descent's skips add a constant and its loop keeps one
 * counter. */
#define KD_SKIPPED_ONE ((uint64_t)1 << 32)
#define KD_STEPS_MASK (KD_SKIPPED_ONE - 1)

/* Descends from the node at byte offset OFF of BASE (the walk nodes,
 * kd_walk.h) to a leaf between the entry point EN and the exit point *EX (the
 * top of the stack), pushing the far children and counting interior nodes and
 * skipped empty leaves in *STEPS (packed: KD_SKIPPED_ONE); returns the leaf's
 * offset. Each "both" case pushes its own far
 * child (no near/far selection: 3 moves per push fewer). A node is tracked as
 * its byte offset, and the next node's load takes the offset of the
 * children's pair (bits & ~15) with the right child's +8 as the load's
 * displacement: one AND between one node's load and the next. (Handing the
 * leaf's word to the caller instead of its load there measured 3-8 % slower.)
 *
 * Empty children (the flags of kd_walk.h), with the same cells visited in the
 * same order from the same points, so the same tests and answers:
 * - the segment lies in an empty child alone: the spare empty leaf is
 *   returned, whose word is in cache, instead of a load of the child's;
 * - the segment crosses the plane from an empty near child: nothing is
 *   pushed and the far child is entered at the crossing (EN moves there).
 *   The empty leaf is not visited (no step) but counted as a cell traversed
 *   (N_ETS, N_EETS, as Havran counts the cells a ray passes): it holds nothing to test,
 *   and the closest hit's stop test loses nothing, since no hit lies in an
 *   empty cell (the invariant of kd_tree.h) and a best hit before it was
 *   already caught by the stop test of the cell before it.
 * An empty far child is still pushed and visited: skipping it would stretch
 * the near child's segment into it and, in a near subtree, the stretched
 * segment meets cells the ray does not (measured: more tests and steps,
 * slower). Primary rays on the Stanford dragon (202,520 triangles): 2.13
 * leaves per ray instead of 2.88, +5 to +8 % rays per second. */
static inline __attribute__((always_inline)) size_t
descend(const char *base, size_t off, const trav_ray *r, double *en, exit_point **ex_io,
        uint64_t *steps)
{
    const size_t spare = KD_WALK_SPARE * sizeof(kd_node);
    exit_point *ex = *ex_io;
    uint64_t w, k = 0;
    NODE_WORD(base, off, 0, w);
    for (;;) {
        uint32_t bits = WORD_BITS(w);
        if ((bits & 3u) == KD_LEAF_TAG)
            break;
        k++;
        unsigned axis = bits & 3u;
        double s = node_split(base, off);
        double A = en[axis], B = ex->pb[axis];
        size_t left = bits & ~(uint32_t)15, right = left + sizeof(kd_node);
        if (A <= s) {
            if (B <= s) { /* N1, N2, N3, P5, Z2, Z3: the left side only */
                if (bits & KD_WALK_LEFT_EMPTY) {
                    off = spare;
                    break;
                }
                off = left;
                NODE_WORD(base, left, 0, w);
                continue;
            }
            if (A == s) { /* Z1: starts on the plane, goes right */
                if (bits & KD_WALK_RIGHT_EMPTY) {
                    off = spare;
                    break;
                }
                off = right;
                NODE_WORD(base, left, sizeof(kd_node), w);
                continue;
            }
            /* N4: A < s < B, left then right */
            if (bits & KD_WALK_LEFT_EMPTY) {
                skip_to_far(r, axis, s, en);
                *steps += KD_SKIPPED_ONE;
                off = right;
                NODE_WORD(base, left, sizeof(kd_node), w);
                continue;
            }
            ex = push(ex, r, axis, s, right);
            off = left;
            NODE_WORD(base, left, 0, w);
        } else {
            off = right;
            NODE_WORD(base, left, sizeof(kd_node), w);
            if (B > s) { /* P1, P2, P3, N5: the right side only */
                if (bits & KD_WALK_RIGHT_EMPTY) {
                    off = spare;
                    break;
                }
                continue;
            }
            /* P4: B <= s < A, right then left; B < s: A and B differ */
            if (bits & KD_WALK_RIGHT_EMPTY) {
                skip_to_far(r, axis, s, en);
                *steps += KD_SKIPPED_ONE;
                off = left;
                NODE_WORD(base, left, 0, w);
                continue;
            }
            ex = push(ex, r, axis, s, left);
        }
    }
    *steps += k;
    *ex_io = ex;
    return off;
}

/* Moves to the cell after the current one: its entry point EN is the
 * current exit point, which is popped; returns that cell's node offset. Not
 * for the root box's exit (the bottom of the stack). */
static inline size_t pop_exit(double en[3], exit_point **ex)
{
    exit_point *x = *ex;
    en[0] = x->pb[0];
    en[1] = x->pb[1];
    en[2] = x->pb[2];
    *ex = x - 1;
    return x->node;
}

/* The local number of primitive FROM, which a query leaves out
 * (bsp_intersect_from), or UINT32_MAX: no leaf lists it, or FROM names no
 * primitive. With the mailbox its stamp is set before the first leaf, so it
 * costs the leaf loop nothing (its entries count as mailbox hits);
 * without, the loop compares each entry with it. */
static inline uint32_t left_out(const kd_tree *t, uint32_t from)
{
    return from < t->nlocal_of ? t->local_of[from] - 1 : UINT32_MAX;
}

int kd_intersect(const bsp_accel *a, bsp_query *q, const bsp_ray *ray, uint32_t from,
                 bsp_hit *hit)
{
    const kd_tree *t = a->impl;
    const bsp_scene *s = a->scene;
    exit_point stack[KD_STACK_SIZE];
    double en[3];
    trav_ray tr;
    hit->prim = BSP_NO_PRIM;
    trav_ray_init(&tr, ray);
    if (__builtin_expect(!in_domain(s, &tr), 0))
        return naive_scene_intersect(s, q, ray, from, hit);
    if (!start(t, ray, &tr, en, stack))
        return 0;
    uint32_t stamp = query_mailbox_next(q, s->nprims);
    uint32_t *mbox = q->stamp;
    const uint32_t skip = left_out(t, from);
    if (mbox && skip != UINT32_MAX)
        mbox[skip] = stamp;
    /* tmax follows the best hit; t never depends on it. Every hit found is at
     * most tmax, so a hit is better than the best so far when its t is
     * smaller or, at equal t, its index is lower. */
    isect_ray r;
    isect_ray_init(&r, ray, s->hit_tol, &s->tri_reach); /* in the domain: checked */
    double tmax = ray->tmax;
    scene_isect_hit best = {INFINITY, 0.0, 0.0, 1.0}, h;
    uint32_t best_p = BSP_NO_PRIM;
    /* without the mailbox, the best hit's local number: met again in a later
     * leaf, its test would find the same hit at t = tmax, not a better one,
     * so it is not made (the hit record is the one memory of the ray) */
    uint32_t best_l = UINT32_MAX;
    uint64_t steps = 0, leaves = 0, nonempty = 0, refs = 0, tests = 0;
    const char *base = (const char *)t->walk; /* kd_walk.h */
    size_t off = 0; /* the root */
    const uint32_t *lref = t->lref; /* the leaf lists in local numbers (kd_local.h) */
    const kd_local *loc = t->loc;
    exit_point *ex = stack;
    for (;;) {
        off = descend(base, off, &tr, en, &ex, &steps);
        const kd_node *n = (const kd_node *)(base + off);
        uint32_t cnt = kd_count(n);
        leaves++;
        if (cnt) {
            const uint32_t *list = lref + n->u.first, *end = list + cnt;
            nonempty++;
            refs += cnt;
            do {
                uint32_t l = *list++;
                if (mbox) {
                    if (mbox[l] == stamp)
                        continue;
                    mbox[l] = stamp;
                } else if (l == skip || l == best_l) {
                    continue;
                }
                tests++;
                if (kd_local_isect(s, &loc[l], &r, tmax, &h)) {
                    uint32_t p = loc[l].prim;
                    if (h.t < best.t || p < best_p) {
                        best = h;
                        best_p = p;
                        best_l = l;
                        tmax = h.t;
                    }
                }
            } while (list != end);
        }
        if (best.t <= ex->t)
            break; /* the closest hit lies inside this cell, or this is the last cell */
        off = pop_exit(en, &ex);
    }
    query_count(q, steps & KD_STEPS_MASK, leaves, steps >> 32, nonempty, refs, tests);
    if (best_p == BSP_NO_PRIM)
        return 0;
    scene_hit_finish(&best, best_p, hit);
    return 1;
}

int kd_occluded(const bsp_accel *a, bsp_query *q, const bsp_ray *ray, uint32_t from)
{
    const kd_tree *t = a->impl;
    const bsp_scene *s = a->scene;
    exit_point stack[KD_STACK_SIZE];
    double en[3];
    trav_ray tr;
    trav_ray_init(&tr, ray);
    if (__builtin_expect(!in_domain(s, &tr), 0))
        return naive_scene_occluded(s, q, ray, from);
    if (!start(t, ray, &tr, en, stack))
        return 0;
    uint32_t stamp = query_mailbox_next(q, s->nprims);
    uint32_t *mbox = q->stamp;
    const uint32_t skip = left_out(t, from);
    if (mbox && skip != UINT32_MAX)
        mbox[skip] = stamp;
    isect_ray r;
    isect_ray_init(&r, ray, s->hit_tol, &s->tri_reach); /* in the domain: checked */
    const double tmax = ray->tmax;
    scene_isect_hit h;
    int found = 0;
    uint64_t steps = 0, leaves = 0, nonempty = 0, refs = 0, tests = 0;
    const char *base = (const char *)t->walk; /* kd_walk.h */
    size_t off = 0; /* the root */
    const uint32_t *lref = t->lref; /* the leaf lists in local numbers (kd_local.h) */
    const kd_local *loc = t->loc;
    exit_point *ex = stack;
    for (;;) {
        off = descend(base, off, &tr, en, &ex, &steps);
        const kd_node *n = (const kd_node *)(base + off);
        uint32_t cnt = kd_count(n);
        leaves++;
        if (cnt) {
            const uint32_t *list = lref + n->u.first, *end = list + cnt;
            nonempty++;
            do {
                uint32_t l = *list++;
                refs++;
                if (mbox) {
                    if (mbox[l] == stamp)
                        continue;
                    mbox[l] = stamp;
                } else if (l == skip) {
                    continue;
                }
                tests++;
                if (kd_local_isect(s, &loc[l], &r, tmax, &h)) {
                    found = 1;
                    break;
                }
            } while (list != end);
            if (found)
                break;
        }
        if (ex == stack)
            break; /* the ray leaves the root box */
        off = pop_exit(en, &ex);
    }
    query_count(q, steps & KD_STEPS_MASK, leaves, steps >> 32, nonempty, refs, tests);
    return found;
}
