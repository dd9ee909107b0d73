/*
 * kd_cost.h — the cost model of the SAH kd-tree builders (MacDonald & Booth
 * 1990, as used by Havran, Bittner & Kopal): per-kind intersection costs T_i,
 * the traversal cost C_trav, the empty-space bonus, and the probability
 * measure A(box) behind the conditional probabilities A(child) / A(node).
 *
 * The measure is pluggable (kd_area_fn): plain SAH uses the surface area;
 * the paper's modified SAH replaces it by the projected area of the box seen
 * from a camera (PER) or along a direction (PAR), clipped to the viewport.
 * The builder calls the measure for the node and for both children of every
 * candidate plane, so a measure need not be separable by axis.
 */
#ifndef BSPRAY_ACCEL_KD_COST_H
#define BSPRAY_ACCEL_KD_COST_H

#include "accel/kd_tree.h"

/* The probability measure of a box (any non-negative unit; only ratios of
 * a child to its node matter). CTX is the measure's own data. */
typedef double (*kd_area_fn)(const bsp_box *box, const void *ctx);

/* Surface area 2 (dx dy + dy dz + dz dx): plain SAH (CTX unused). */
static inline double kd_surface_area(const bsp_box *b)
{
    double dx = b->hi.x - b->lo.x, dy = b->hi.y - b->lo.y, dz = b->hi.z - b->lo.z;
    return 2.0 * (dx * dy + dy * dz + dz * dx);
}
HIDDEN double kd_area_surface(const bsp_box *box, const void *ctx);

/* The resolved cost model of one build. */
typedef struct kd_cost_model {
    bsp_sah_costs c;    /* every field > 0 */
    double empty_bonus; /* in [0, 1) */
    double min_saving;  /* >= 0: the least saving of a split, in mean tests per ray
                           (bsp_build_options.sah_min_saving); 0: no limit */
    double leaf_budget; /* > 0: the most leaves per primitive
                           (bsp_build_options.sah_leaf_budget); 0: no budget */
    size_t leaf_budget_min; /* >= 1: the least budget, in leaves */
    double budget_cut;  /* > 0: the share of the budget's estimated threshold below
                           which splits are not made (bsp_build_options.sah_budget_cut);
                           0: no estimate */
    int mailbox_term;   /* the mailbox term: a straddler met again in the second
                           child costs mailbox_hit, not T_i (the default, for
                           trees traversed with or without mailboxes; 0 with
                           bsp_build_options.sah_straddle_twice: the plain model) */
    double mailbox_hit; /* the cost of that skipped test, in units of C_trav */
} kd_cost_model;

/* The built-in defaults (C_trav = 1; see kd_cost.c for how they were measured). */
HIDDEN void kd_cost_defaults(bsp_sah_costs *c);
#define KD_DEFAULT_EMPTY_BONUS 0.1
/* The default least saving of a split (bsp_build_options.sah_min_saving):
 * a node that saves 1e-9 of a test per ray repays the ~1 us of its own build
 * (some 100 tests) only after some 10^11 rays. On the SPD scenes the splits
 * it prunes changed render instructions by at most 0.006 % (docs/kdtree.md). */
#define KD_DEFAULT_MIN_SAVING 1e-9
/* The default leaf budget (bsp_build_options.sah_leaf_budget), in leaves
 * per primitive; see docs/kdtree.md. */
#define KD_DEFAULT_LEAF_BUDGET 1.0
/* The default least budget (bsp_build_options.sah_leaf_budget_min): a
 * tree of at most this many leaves is never pruned. Its nodes (2 MiB) fit
 * in a core's L2 cache, and the splits' savings are real there
 * (docs/kdtree.md). */
#define KD_DEFAULT_LEAF_BUDGET_MIN 131072
/* The default share of the budget's estimated threshold the build cuts at
 * (bsp_build_options.sah_budget_cut): the estimates of 13 large scenes fell
 * within 0.76-1.01 of the threshold (session 20). None of 23 large scenes
 * was built twice at 0.75, nor of 33 at 0.8; at 1.0 three of 21 were, and
 * at 0.95 one (session 34). 0.75 keeps a third of margin and builds the same
 * trees 4-16 % faster than 0.5 (docs/kdtree-log.md, "Session 34"). */
#define KD_DEFAULT_BUDGET_CUT 0.75
/* A test skipped by the mailbox (one stamp load and compare; often a cache
 * miss) in units of C_trav: about 2 ns against 13 ns per traversal step. */
#define KD_MAILBOX_HIT_COST 0.15

/* Resolves the SAH fields of O: every 0 (or invalid) field takes its default;
 * a negative empty bonus means none; the mailbox term unless
 * O->sah_straddle_twice. */
HIDDEN void kd_cost_resolve(const bsp_build_options *o, kd_cost_model *m);

/* T_i of primitive PRIM (a live one) under costs C. */
HIDDEN double kd_prim_cost(const bsp_scene *scene, uint32_t prim, const bsp_sah_costs *c);

/* A measure whose context follows the build down the tree (sah-mixed's
 * counted model, kd_raycount.h): each build thread measures with a context
 * of its own, made by THREAD_CTX from the shared one, and the builder calls
 * ENTER with every cell before it measures the cell and the children of its
 * candidate planes. The measure must still depend on the box alone. */
typedef struct kd_descent {
    void *(*thread_ctx)(const void *shared);      /* NULL: out of memory */
    void (*free_ctx)(void *ctx);
    int (*enter)(void *ctx, const bsp_box *cell); /* 0: out of memory */
    /* Forgets what CTX keeps from the cells entered so far: called before
     * each parallel task, so that a task measures the same whichever thread
     * runs it and whatever that thread built before (the measure need only
     * agree up to rounding between what the context keeps and what it
     * recomputes; the build must not depend on the thread count). */
    void (*reset)(void *ctx);
} kd_descent;

/* The SAH builder with a pluggable measure: fills T (already set up by
 * kd_tree_init) over SCENE with the costs and limits of O, measuring
 * probabilities with AREA(box, CTX), or with AREA(box, per-thread context)
 * when DESCENT is not NULL. kd_build_sah is this with the surface
 * area. Deterministic: the same input gives the same node array. */
HIDDEN bsp_status kd_build_sah_measure(kd_tree *t, const bsp_scene *scene,
                                       const bsp_build_options *o, kd_area_fn area,
                                       const void *ctx, const kd_descent *descent,
                                       bsp_error *err);

#endif /* BSPRAY_ACCEL_KD_COST_H */
