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
 * it is. Returns 0 when out of memory (T is then unchanged). */
HIDDEN int kd_prune_to_leaves(kd_tree *t, size_t max_leaves);

/* That threshold: the least value theta such that at most MAX_LEAVES
 * leaves remain when the splits saving less than theta are collapsed
 * (-inf: T has no more). M and SCRATCH: t->nnodes entries each; M[v] is
 * left the least saving among node v's strict ancestors (+inf at the root),
 * so node v stays iff M[v] >= theta. */
HIDDEN double kd_prune_threshold(const kd_tree *t, size_t max_leaves, double *m, double *scratch);

#endif /* BSPRAY_ACCEL_KD_PRUNE_H */
