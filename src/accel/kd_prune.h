/*
 * kd_prune.h — the leaf budget of the SAH builders: a tree with more leaves
 * than the budget loses its least valuable splits (kd_prune.c).
 */
#ifndef BSPRAY_ACCEL_KD_PRUNE_H
#define BSPRAY_ACCEL_KD_PRUNE_H

#include "accel/kd_tree.h"

/* Prunes T, whose splits' savings were recorded (t->saving), to at most
 * MAX_LEAVES leaves: every split that saves less than the least threshold
 * that meets the budget, or lies below one that does, becomes a leaf of the
 * primitives of its subtree's leaves. A tree within the budget is left as
 * it is. Returns 1 when done, 0 when out of memory (T is then unchanged).
 *
 * CUT (-inf: none): the build did not make some splits that would have
 * saved less than CUT (a leaf budget's estimate, kd_prune_estimate). The
 * tree pruned is then the tree of the build without the cut only when the
 * splits of T that save at least CUT, with all their ancestors, make more
 * leaves than MAX_LEAVES (the threshold then lies above CUT, where both
 * trees have the same splits); otherwise -1 is returned and T is unchanged. */
HIDDEN int kd_prune_to_leaves(kd_tree *t, size_t max_leaves, double cut);

/* One subtree of a tree whose top is built: the top's placeholder leaf NODE
 * for N primitives, and SUB, its subtree when built (savings recorded, root
 * at 0), or NULL. */
typedef struct kd_budget_part {
    uint32_t node;
    size_t n;
    const kd_tree *sub;
} kd_budget_part;

/* The estimate's sample: one in KD_BUDGET_PROBE_EVERY of the subtrees
 * built by tasks of the SAH builder (kd_sah_tasks.c), and no estimate from
 * fewer than KD_BUDGET_MIN_PROBES; the other subtrees are built without the
 * splits that save less than a share of the estimate
 * (kd_cost_model.budget_cut; docs/kdtree.md: how far the estimates err).
 * One probe in KD_BUDGET_SCOUT_EVERY is a scout, built before the others,
 * and every other scout a pilot, built first and in full. From at least
 * KD_BUDGET_MIN_SCOUTS pilots a first estimate, and the other scouts are
 * built without the splits that save less than KD_BUDGET_PILOT_SHARE of
 * it; from pilots and scouts a second, and the other probes are built
 * without those saving less than KD_BUDGET_SCOUT_SHARE of it (their counts
 * above that are exact, and the estimate lies far above it; the least of
 * an estimate's three is taken even where they disagree, which only makes
 * it lower). For the other tasks' cut, estimates (of all probes, and of
 * each half) further apart than KD_BUDGET_SPREAD times are not trusted. */
#define KD_BUDGET_PROBE_EVERY 8
#define KD_BUDGET_MIN_PROBES 4
#define KD_BUDGET_SCOUT_EVERY 3
#define KD_BUDGET_MIN_SCOUTS 2
#define KD_BUDGET_SCOUT_SHARE 0.25
#define KD_BUDGET_PILOT_SHARE 0.125
#define KD_BUDGET_SPREAD 4.0

/* Estimates the threshold kd_prune_to_leaves will find for MAX_LEAVES
 * leaves, when the top TOP (savings recorded) and the parts PARTS[0..NP)
 * are built: the top's splits and the built parts count as they are; an
 * unbuilt part of n primitives under a chain of least saving c is taken to
 * hold, above any theta <= c, n / (the built parts' primitives) times the
 * splits of the built parts that reach theta with their chain within their
 * part. -inf when the estimate meets the budget without pruning (or no part
 * is built); 0 when out of memory. */
HIDDEN double kd_prune_estimate(const kd_tree *top, const kd_budget_part *parts, size_t np,
                                size_t max_leaves);

/* That threshold: the least value theta such that at most MAX_LEAVES
 * leaves remain when the splits saving less than theta are collapsed
 * (-inf: T has no more). M and SCRATCH: t->nnodes entries each; M[v] is
 * left the least saving among node v's strict ancestors (+inf at the root),
 * so node v stays iff M[v] >= theta. */
HIDDEN double kd_prune_threshold(const kd_tree *t, size_t max_leaves, double *m, double *scratch);

#endif /* BSPRAY_ACCEL_KD_PRUNE_H */
