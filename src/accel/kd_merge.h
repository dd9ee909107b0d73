/*
 * kd_merge.h — the SAH builder's merge of a few new event keys into a
 * child's sorted list (the straddlers' clipped events, kd_sah_node.c).
 */
#ifndef BSPRAY_ACCEL_KD_MERGE_H
#define BSPRAY_ACCEL_KD_MERGE_H

#include <stddef.h>
#include <stdint.h>

#include "scene/scene_internal.h" /* HIDDEN */

/* Merges the sorted NW[0..NN) into the sorted DST[0..A), in place from the
 * back (DST has room for A + NN). The keys are distinct (event keys carry
 * their primitive). Picks the fastest of the ways below for the sizes. */
HIDDEN void kd_merge_back(uint64_t *dst, size_t a, const uint64_t *nw, size_t nn);

/* The same by scalar code alone: a galloping search per new key when the
 * new keys are few, else a branch-free two-list merge. */
HIDDEN void kd_merge_back_scalar(uint64_t *dst, size_t a, const uint64_t *nw, size_t nn);

/* The same by counted ranks (AVX2) when NN <= 8 and the CPU has AVX2;
 * returns 0, leaving DST as it was, where it cannot. */
HIDDEN int kd_merge_back_ranked(uint64_t *dst, size_t a, const uint64_t *nw, size_t nn);

#endif
