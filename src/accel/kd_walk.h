/*
 * kd_walk.h — the traversal's copy of the nodes (kd_walk.c): the tree the
 * builders made, laid out again so that an interior node says which of its
 * children are empty leaves.
 *
 * Why: on a scanned mesh a ray that hits visits about 9 leaves, 7 of them
 * empty (the SAH's cut-off slabs around the surface). A visit of an empty
 * leaf costs a push, a pop, a load and the leaf's branches, and shows the
 * traversal nothing. With the flags the descent skips an empty child
 * without loading it: where the ray passes into an empty near child and
 * then the far one, it enters the far child at the plane at once; where
 * the far child is empty, nothing is pushed (see kd_traverse.c for why
 * that stays exact).
 *
 * Layout: node 0 is the root; node 1 is a spare empty leaf that no node
 * names (the descent goes there when a ray's whole segment lies in an empty
 * child, so that the leaf loop sees an empty leaf without a load from far
 * away); every pair of children starts at an even index, so the byte
 * offset of a pair (index * 8) has bit 3 clear and an interior node's bits
 * have room for two flags:
 *
 *   bits & 3          axis 0..2 (interior) or KD_LEAF_TAG
 *   bits & 4          KD_WALK_LEFT_EMPTY: the left child is an empty leaf
 *   bits & 8          KD_WALK_RIGHT_EMPTY: the right child is an empty leaf
 *   bits & ~15        byte offset of the left child (interior)
 *   bits >> 3         primitive count (leaf); u.first indexes prims / lref
 *
 * Pairs are in the depth-first order of the built tree, so the two
 * children of a node always share a 16-byte block, and so a cache line.
 */
#ifndef BSPRAY_ACCEL_KD_WALK_H
#define BSPRAY_ACCEL_KD_WALK_H

#include "accel/kd_tree.h"

#define KD_WALK_LEFT_EMPTY 4u
#define KD_WALK_RIGHT_EMPTY 8u
#define KD_WALK_SPARE 1u /* index of the spare empty leaf */

/* Makes T's walk nodes (t->walk, t->nwalk) from its finished tree,
 * replacing any earlier copy; 0 when out of memory, or when T's nodes do not
 * form a tree (no builder makes one; bsp_accel_check says what is wrong). */
HIDDEN int kd_walk_build(kd_tree *t);

/* Checks the walk nodes against T's tree: the same tree node for node
 * (axis, split, leaf lists), pairs at even indices, the spare leaf empty,
 * every flag set exactly when its child is an empty leaf. BSP_OK, or
 * BSP_ERR_INVALID with the first violation. */
HIDDEN bsp_status kd_walk_check(const kd_tree *t, bsp_error *err);

#endif /* BSPRAY_ACCEL_KD_WALK_H */
