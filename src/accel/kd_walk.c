/*
 * kd_walk.c — the traversal's copy of the nodes, with empty-child flags
 * (layout and reasons in kd_walk.h).
 */
#include <stdlib.h>

#include "accel/kd_walk.h"
#include "util/bigmem.h"

static int is_empty_leaf(const kd_node *n)
{
    return kd_is_leaf(n) && kd_count(n) == 0;
}

/* The walk node of tree node N whose children's pair is at walk index C. */
static kd_node walk_interior(const kd_tree *t, const kd_node *n, uint32_t c)
{
    const kd_node *kids = &t->nodes[kd_child(n)];
    kd_node w = *n;
    w.bits = (c << KD_INDEX_SHIFT) | kd_axis(n) | (is_empty_leaf(&kids[0]) ? KD_WALK_LEFT_EMPTY : 0) |
             (is_empty_leaf(&kids[1]) ? KD_WALK_RIGHT_EMPTY : 0);
    return w;
}

/* Pushes the children of a tree node (pair at TREE) and of its walk node
 * (pair at WALK) on a depth-first stack of TOP entries, the left ones on
 * top, so that the left child is taken first and its pair follows its
 * parent's at once; returns the new TOP. */
static uint32_t push_children(uint32_t (*stack)[2], uint32_t top, uint32_t tree, uint32_t walk)
{
    stack[top][0] = tree + 1;
    stack[top][1] = walk + 1;
    stack[top + 1][0] = tree;
    stack[top + 1][1] = walk;
    return top + 2;
}

int kd_walk_build(kd_tree *t)
{
    free(t->walk);
    t->walk = NULL;
    t->nwalk = 0;
    /* the root, the spare leaf, then the pairs: as many nodes as the tree
     * and one (a tree is its root and pairs, so an odd count) */
    size_t nw = (size_t)t->nnodes + 1;
    kd_node *walk = bigmem_malloc(nw * sizeof *walk);
    /* a depth-first stack of (tree node, walk node): at most one entry per
     * tree node */
    uint32_t(*stack)[2] = malloc((t->nnodes ? t->nnodes : 1) * sizeof *stack);
    if (!walk || !stack) {
        free(walk);
        free(stack);
        return 0;
    }
    walk[KD_WALK_SPARE].bits = kd_pack(0, KD_LEAF_TAG);
    walk[KD_WALK_SPARE].u.first = 0;
    uint32_t next = 2, top = 0;
    stack[top][0] = 0;
    stack[top][1] = 0;
    top++;
    while (top) {
        top--;
        uint32_t ti = stack[top][0], wi = stack[top][1];
        const kd_node *n = &t->nodes[ti];
        if (kd_is_leaf(n)) {
            walk[wi] = *n;
            continue;
        }
        if (kd_child(n) + 1 >= t->nnodes || top + 2 > t->nnodes || next + 2 > nw) {
            /* not a tree: the checker says so */
            free(stack);
            free(walk);
            return 0;
        }
        uint32_t c = next;
        next += 2;
        walk[wi] = walk_interior(t, n, c);
        top = push_children(stack, top, kd_child(n), c);
    }
    free(stack);
    t->walk = walk;
    t->nwalk = next;
    return 1;
}

bsp_status kd_walk_check(const kd_tree *t, bsp_error *err)
{
    if (!t->walk)
        return error_set(err, BSP_ERR_INVALID, NULL, 0, "kd-tree: no walk nodes");
    if (t->nwalk != (size_t)t->nnodes + 1)
        return error_set(err, BSP_ERR_INVALID, NULL, 0, "kd-tree: %u walk nodes for %u nodes",
                         t->nwalk, t->nnodes);
    const kd_node *spare = &t->walk[KD_WALK_SPARE];
    if (!is_empty_leaf(spare) || spare->u.first != 0)
        return error_set(err, BSP_ERR_INVALID, NULL, 0, "kd-tree: the spare walk node is not an empty leaf");
    /* walk both trees together, depth first; every walk node is met once */
    uint32_t(*stack)[2] = malloc((t->nnodes ? t->nnodes : 1) * sizeof *stack);
    uint8_t *met = calloc(t->nwalk, 1);
    if (!stack || !met) {
        free(stack);
        free(met);
        return error_set(err, BSP_ERR_NOMEM, NULL, 0, "out of memory");
    }
    bsp_status st = BSP_OK;
    uint32_t top = 0, count = 1;
    stack[top][0] = 0;
    stack[top][1] = 0;
    top++;
    met[0] = 1;
    while (top && st == BSP_OK) {
        top--;
        uint32_t ti = stack[top][0], wi = stack[top][1];
        const kd_node *n = &t->nodes[ti], *w = &t->walk[wi];
        if (kd_is_leaf(n)) {
            if (w->bits != n->bits || w->u.first != n->u.first)
                st = error_set(err, BSP_ERR_INVALID, NULL, 0,
                               "kd-tree: walk node %u is not leaf %u", wi, ti);
            continue;
        }
        uint32_t c = (w->bits & ~15u) >> KD_INDEX_SHIFT;
        if (kd_is_leaf(w) || kd_axis(w) != kd_axis(n) || w->u.first != n->u.first) {
            st = error_set(err, BSP_ERR_INVALID, NULL, 0,
                           "kd-tree: walk node %u is not interior node %u", wi, ti);
            continue;
        }
        if (c < 2 || c + 1 >= t->nwalk || (c & 1) || met[c] || met[c + 1]) {
            st = error_set(err, BSP_ERR_INVALID, NULL, 0,
                           "kd-tree: walk node %u names children %u and %u", wi, c, c + 1);
            continue;
        }
        if (kd_child(n) + 1 >= t->nnodes || top + 2 > t->nnodes) {
            st = error_set(err, BSP_ERR_INVALID, NULL, 0, "kd-tree: walk node %u: not a tree", wi);
            continue;
        }
        const kd_node *kids = &t->nodes[kd_child(n)];
        unsigned flags = (is_empty_leaf(&kids[0]) ? KD_WALK_LEFT_EMPTY : 0) |
                         (is_empty_leaf(&kids[1]) ? KD_WALK_RIGHT_EMPTY : 0);
        if ((w->bits & (KD_WALK_LEFT_EMPTY | KD_WALK_RIGHT_EMPTY)) != flags) {
            st = error_set(err, BSP_ERR_INVALID, NULL, 0,
                           "kd-tree: walk node %u: wrong empty-child flags", wi);
            continue;
        }
        met[c] = met[c + 1] = 1;
        count += 2;
        top = push_children(stack, top, kd_child(n), c);
    }
    if (st == BSP_OK && count + 1 != t->nwalk)
        st = error_set(err, BSP_ERR_INVALID, NULL, 0, "kd-tree: %u of %u walk nodes in the tree",
                       count, t->nwalk);
    free(stack);
    free(met);
    return st;
}
