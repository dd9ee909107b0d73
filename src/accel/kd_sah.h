/*
 * kd_sah.h — what the SAH builder (kd_split_sah.c, kd_sah_node.c) shares with its plane
 * sweeps (kd_sweep_measure.c: any measure; kd_sweep_linear.c: the surface
 * area with a linear cost): the 64-bit events and their keys, the builder's
 * state, and the two sweeps. See kd_sah_node.c for the events and the cost
 * model.
 */
#ifndef BSPRAY_ACCEL_KD_SAH_H
#define BSPRAY_ACCEL_KD_SAH_H

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "accel/kd_clip.h"
#include "accel/kd_cost.h"
#include "accel/kd_tree.h"
#include "accel/kd_view.h"
#include "util/bigmem.h"


#define EV_START ((uint64_t)1 << 31)
#define EV_PRIM 0x0fffffffu /* SCENE_MAX_PRIMS = 2^28 */

_Static_assert(SCENE_MAX_PRIMS <= (size_t)EV_PRIM + 1, "primitive index fits an event");

/* a primitive's side at a split: one bit per one-sided list (see build_node) */
enum { CLS_BOTH = 0, CLS_LEFT = 1, CLS_RIGHT = 2 };

/* --- keys ------------------------------------------------------------------------------ */

static inline uint32_t float_key(float f)
{
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    return (u & 0x80000000u) ? ~u : (u | 0x80000000u);
}

static inline float key_float(uint32_t k)
{
    uint32_t u = k ^ (((k >> 31) - 1u) | 0x80000000u); /* branch-free inverse */
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

static inline uint64_t make_event(float pos, int start, uint32_t prim)
{
    return ((uint64_t)float_key(pos) << 32) | (start ? EV_START : 0) | prim;
}

static inline uint32_t ev_prim(uint64_t e)
{
    return (uint32_t)e & EV_PRIM;
}

/* The largest float <= X and the smallest float >= X (never -0), branch-free:
 * whether (float)X rounded the wrong way is data, not a pattern (a clipped
 * bound's rounding is a coin toss), so the step to the next float is
 * selected, not branched to: the next float towards -inf (+inf) of the
 * rounded value where it overshot, the neighbour of either zero being the
 * least subnormal of that sign (the same bits as the branching version of
 * session 26 over 2 x 10^8 doubles and the zeros, subnormals, infinities
 * and their neighbours). */
static inline float round_down(double x)
{
    float f = (float)x;
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    const uint32_t below = (u & 0x7fffffffu) ? u + 2u * (u >> 31) - 1u : 0x80000001u;
    const uint32_t step = 0u - (uint32_t)((double)f > x); /* a mask: no branch */
    u ^= (u ^ below) & step;
    if ((u & 0x7fffffffu) == 0) /* rare, and so predicted */
        u = 0;
    memcpy(&f, &u, sizeof f);
    return f;
}

static inline float round_up(double x)
{
    float f = (float)x;
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    const uint32_t above = (u & 0x7fffffffu) ? u + 1u - 2u * (u >> 31) : 0x00000001u;
    const uint32_t step = 0u - (uint32_t)((double)f < x);
    u ^= (u ^ above) & step;
    if ((u & 0x7fffffffu) == 0)
        u = 0;
    memcpy(&f, &u, sizeof f);
    return f;
}

/* --- builder state ---------------------------------------------------------------------- */

/* How the sweep finds T_i: all equal; by one of at most 8 distinct values,
 * whose index rides in the spare bits 28..30 of the event (so events order
 * by position, type, cost class, primitive); or by primitive (more kinds of
 * cost, e.g. polygons of many vertex counts). */
enum { COST_UNIFORM, COST_CLASS, COST_ARRAY };
#define EV_CLASS_SHIFT 28

/* The least savings a build's leaf budget estimates raised, above the
 * build's own (-inf: none; b->min_saving applied as ever): RAISED the
 * greatest any task was built with, the cut the prune must prove harmless;
 * PROBE the probes', from the scouts' estimate; SCOUT the scouts', from the
 * pilots' (kd_sah_tasks.c). */
typedef struct sah_budget_cuts {
    double raised, probe, scout;
} sah_budget_cuts;

/* Subtrees deferred by the main build to be built in parallel
 * (kd_sah_tasks.c): worker threads build them while the main build goes on. */
typedef struct sah_task sah_task;
typedef struct sah_pool sah_pool;
typedef struct sah_tasks {
    sah_task **v;        /* in the order deferred; each task apart, so that growing
                            v moves no task a worker is building */
    size_t n, cap;
    size_t min_n, max_n; /* a node of min_n..max_n primitives with no speculative
                            ancestor becomes a task (independent of the thread count,
                            so every thread count builds the same array) */
    sah_pool *pool;      /* the workers (NULL: the tasks wait for kd_sah_finish_tasks) */
    /* The leaf budget's estimate (kd_prune_estimate): with probe_every > 0,
     * one task in probe_every (drawn by a hash of its number) is a probe,
     * built before the others; from the probes and the top of the tree the
     * budget's threshold is estimated, and the other tasks are built with a
     * least saving of cut_share times it (splits below it would be pruned
     * anyway). One probe in KD_BUDGET_SCOUT_EVERY is a scout and every
     * other scout a pilot: the pilots first and in full, then the scouts and
     * then the other probes, each with a least saving of a small share of
     * the estimate from the sample before them (kd_sah_tasks.c, kd_prune.h).
     * 0: no estimate, every task in full. */
    size_t probe_every;
    size_t nprobes;      /* probes listed so far (which of them are scouts) */
    size_t nscouts;      /* scouts listed so far (which of them are pilots) */
    size_t budget;       /* the leaf budget the estimate is for */
    double cut_share;    /* the share of the estimate the other tasks cut at */
    sah_budget_cuts cuts; /* out: the least savings the estimates raised */
    double n_done, n_all; /* the primitives of the tasks built, and of all (progress) */
} sah_tasks;

typedef struct ev_delta {
    double ts, te, mb, ma; /* see kd_sah_event_deltas */
} ev_delta;

typedef struct sah_build {
    kd_tree *t;
    const bsp_scene *scene;
    kd_area_fn area;
    const void *actx;
    const kd_descent *descent; /* ACTX follows the descent (NULL: ACTX is shared) */
    const void *shared_actx;   /* with DESCENT: what each thread's ACTX is made from */
    void *dctx;                /* with DESCENT: this thread's context (ACTX) */
    int surface;        /* AREA is the surface area: evaluated inline */
    int to_limits;      /* split until the depth/leaf-size limits, whatever the cost */
    double ctrav;       /* C_trav */
    double bonus_mul;   /* 1 - empty bonus */
    double min_saving;  /* the least saving of a split that pays, in cost units per ray
                           of the root: kd_cost_model.min_saving times the mean T_i */
    double min_saving_sure; /* the same, >= min_saving, for a node with no speculative
                               ancestor (bad == 0): raised by the leaf budget's estimate
                               in the tasks built after it (sah_tasks.cuts) */
    double inv_root_area; /* 1 / the root cell's surface area */
    int record_savings;   /* record every split's saving in t->saving (kd_prune.h) */
    int mailbox;        /* mailbox-aware costs (kd_cost_model.mailbox_term) */
    double mb_hit;      /* the cost of a test the mailbox skips */
    int cost_mode;      /* COST_*: how an event finds its T_i */
    double unif;        /* COST_UNIFORM: the T_i of every primitive */
    double class_cost[8]; /* COST_CLASS: T_i by the class in event bits 28..30 */
    /* COST_UNIFORM and COST_CLASS: what an event does to the sweep's sums,
     * by its bits 28..31 (type and class; kd_sah_event_deltas) */
    ev_delta delta[16];
    uint8_t *pclass;    /* COST_CLASS: the class per primitive */
    double *cost;       /* T_i per primitive (NULL when uniform), quantized */
    int linear;         /* every T_i >= mb_hit: the fast sweep's linear cost applies */
    uint64_t *chunks;   /* the fast sweep's run sums (lin_chunk), grown on demand */
    size_t chunks_cap;
    uint8_t *cls;       /* per primitive: CLS_* at the latest split it took part in;
                           cls[spare] absorbs the writes of a branch-free loop */
    uint32_t spare;
    bsp_box *bounds;    /* per primitive: bsp_scene_prim_bounds, for clipping */
    sah_tasks *tasks;   /* the main build's deferred subtrees; NULL inside a task */
    uint64_t *ev;       /* the event stack */
    size_t cap;
    uint64_t *nev[2];   /* new events of straddlers per side, axis j at j * stride */
    uint64_t *both;     /* a split of many straddlers: their old events, axis j at
                           j * stride, in the lists' order, then room for one
                           side's unchanged new events (sort_new_in_order) */
    uint64_t *reord;    /* and for its changed ones */
    size_t nev_cap;     /* of each of the four */
    uint32_t *sidx;     /* per primitive: its index among a split's straddlers */
    uint32_t *slot;     /* per straddler and side: its new events' pair in nev, or none */
    size_t slot_cap;
    uint32_t *list;     /* straddlers, leaf lists */
    size_t list_cap;
    kd_clip_scratch clip;
    kd_clip_path path;    /* straddling triangles' and polygons' parts along the path (kd_clip.h) */
    struct part_save *saved; /* the parts a split changed in OF, to restore (kd_sah_node.c) */
    size_t nsaved, saved_cap;
    bsp_error *err;
    void (*progress)(double done, void *ctx); /* bsp_build_options.progress, or NULL */
    void *progress_ctx;
    void *mruns;        /* kd_sweep_measure's scratch (runs, positions), grown on demand */
    size_t mruns_cap;
    kd_view_cell vcell; /* sah-per, sah-par: the cell part of its children's measures, kept
                           from one axis's sweep to the next (kd_view_split.c) */
} sah_build;

static inline int grow_u64(uint64_t **p, size_t *cap, size_t need)
{
    if (need <= *cap)
        return 1;
    size_t ncap = *cap * 2 > need ? *cap * 2 : need;
    uint64_t *np = bigmem_realloc(*p, *cap * sizeof *np, ncap * sizeof *np);
    if (!np)
        return 0;
    *p = np;
    *cap = ncap;
    return 1;
}

typedef struct split_choice {
    double cost;
    unsigned axis;
    float pos;
    int found;
} split_choice;

/* Whether two sweeps chose the same split: both none, or the same axis,
 * plane and cost bit for bit (the tests compare sweeps with it). */
static inline int split_choice_same(const split_choice *a, const split_choice *b)
{
    return a->found == b->found &&
           (!a->found || (a->axis == b->axis && a->pos == b->pos &&
                          memcmp(&a->cost, &b->cost, sizeof a->cost) == 0));
}

/* The sums' changes at an event of the given type and T_i (ev_t's units),
 * as lin_step applies them: before its candidate the right sum loses TE and
 * the count NL + NR loses MB (an END leaves the right side), after it the
 * left sum gains TS and the count MA (a START joins the left side). With the
 * cost classes in the key, a table of these by bits 28..31 replaces the
 * per-event arithmetic of the type and the class look-up; the values are
 * the same doubles that arithmetic gives. */
static inline void kd_sah_event_deltas(sah_build *b)
{
    for (unsigned i = 0; i < 16; i++) {
        const int start = (int)(i >> 3);
        const double t = b->cost_mode == COST_CLASS ? b->class_cost[i & 7] : 1.0;
        b->delta[i] = (ev_delta){start ? t : 0.0, start ? 0.0 : t, start ? 0.0 : 1.0,
                                 start ? 1.0 : 0.0};
    }
}

static inline double ev_cost(const sah_build *b, uint64_t x, int mode)
{
    return mode == COST_UNIFORM ? b->unif
           : mode == COST_CLASS ? b->class_cost[(x >> EV_CLASS_SHIFT) & 7]
                                : (double)b->cost[ev_prim(x)];
}

static inline double ev_t(const sah_build *b, uint64_t x, int mode)
{
    return mode == COST_UNIFORM ? 1.0
           : mode == COST_CLASS ? b->class_cost[(x >> EV_CLASS_SHIFT) & 7]
                                : (double)b->cost[ev_prim(x)];
}

/* What event X adds to a sweep's sums (ev_t's units): kd_sah_event_deltas'
 * table entry for its type and class bits, or with costs per primitive the
 * same terms computed (T_i times the START bit, not a branch). */
static inline __attribute__((always_inline)) ev_delta ev_terms(const sah_build *b, uint64_t x,
                                                               const int mode)
{
    if (mode != COST_ARRAY)
        return b->delta[(x >> EV_CLASS_SHIFT) & 15];
    const int start = (int)((x >> 31) & 1);
    const double t = ev_t(b, x, mode), ts = t * (double)start;
    return (ev_delta){ts, t - ts, (double)(start ^ 1), (double)start};
}

static inline double ev_pos(uint64_t x)
{
    return (double)key_float((uint32_t)(x >> 32));
}

/* A node's event lists: axis k at ev[base + k * stride], 2n events each. */
typedef struct node_lists {
    size_t base, stride, n;
    double tsum; /* sum of T_i */
} node_lists;

/* Builds the subtree of NODE over CELL from the lists L; b->ev[top, ...) is
 * free (kd_sah_node.c). */
HIDDEN bsp_status kd_sah_build_node(sah_build *b, uint32_t node, bsp_box cell, node_lists L,
                                    size_t top, int depth, int bad, int surface, double *cost_out);

/* Whether the main build defers a node of N primitives after BAD bad refines
 * to a task: only with no speculative ancestor, whose retraction would need
 * the subtree's cost at once. */
static inline int kd_sah_task_wanted(const sah_build *b, size_t n, int bad)
{
    return b->tasks && bad == 0 && n >= b->tasks->min_n && n <= b->tasks->max_n;
}

/* Defers NODE (lists L, CELL, DEPTH, SURFACE) to a task: copies its lists and
 * leaves NODE an empty leaf until kd_sah_run_tasks (kd_sah_tasks.c). */
HIDDEN bsp_status kd_sah_defer(sah_build *b, uint32_t node, const bsp_box *cell,
                               const node_lists *L, int depth, int surface);

/* Starts THREADS - 1 worker threads (THREADS <= 1: none; no more than a
 * build of N primitives can have tasks for) that build the tasks b->tasks
 * defers from now on, as they come; call it when B is set up and before the
 * main build starts: each worker copies B's shared state. */
HIDDEN void kd_sah_start_workers(sah_build *b, int threads, size_t n);

/* After the main build (status ST): the calling thread frees B's scratch and
 * builds the tasks left, with the workers (ST != BSP_OK: none is built),
 * then splices the subtrees into b->t in task order and frees the tasks. */
HIDDEN bsp_status kd_sah_finish_tasks(sah_build *b, bsp_status st);

/* Frees B's scratch (not the shared per-primitive arrays). */
HIDDEN void kd_sah_scratch_free(sah_build *b);
/* B holds no scratch (its pointers NULL, its sizes 0), whatever it held:
 * for a copy of a build that must not share its scratch. */
HIDDEN void kd_sah_scratch_forget(sah_build *b);
/* TO takes over FROM's scratch, which then holds none (for a thread that
 * goes on building in memory another build has written). */
HIDDEN void kd_sah_scratch_move(sah_build *to, sah_build *from);

/* The best plane on axis K of a node (its sorted events E[0..M), N
 * primitives, cost sum TSUM, cell CELL, 1 / its measure INV_AREA — halved
 * measures when SURFACE) by a sweep of any measure, kept in *BEST when
 * cheaper (kd_sweep_measure.c: candidates that cannot win are left out by
 * branch and bound, the same plane as a full sweep; grows b->mruns). */
HIDDEN void kd_sweep_measure(sah_build *b, const uint64_t *e, size_t m, unsigned k,
                             const bsp_box *cell, double inv_area, double tsum, size_t n,
                             int surface, split_choice *best);

/* The best plane of a node on all three axes (lists at EV + k * STRIDE) by
 * the pruned sweep of the surface area (b->linear; kd_sweep_linear.c). */
HIDDEN void kd_sweep_linear(sah_build *b, const uint64_t *ev, size_t stride, size_t n,
                            double tsum, const bsp_box *cell, double inv_area,
                            split_choice *best);

/* No plane the linear sweep finds costs less than this: its g is never
 * negative, so a plane costs at least C_trav, C_trav (1 - bonus) with the
 * empty bonus; the margin covers the rounding of the bonus's transform
 * (lin_bonus). The builder skips the sweep of a node that no split could
 * make worth a node (no_split_saves_enough in kd_sah_node.c). */
static inline double kd_sweep_linear_least_cost(const sah_build *b)
{
    return b->ctrav * b->bonus_mul * (1.0 - 1e-9);
}

/* The same by the sweep of runs at any size (kd_sweep_linear sweeps nodes of
 * fewer than 16 primitives in one pass; the tests compare the two). */
HIDDEN void kd_sweep_linear_runs(sah_build *b, const uint64_t *ev, size_t stride, size_t n,
                                 double tsum, const bsp_box *cell, double inv_area,
                                 split_choice *best);

#endif /* BSPRAY_ACCEL_KD_SAH_H */
