/*
 * bvh_stats.c — the BVH's figures, its invariant checker and its visit of
 * node boxes (bvh.h).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "accel/bvh.h"
#include "accel/kd_cost.h"
#include "geom/vec.h"
#include "util/fnv.h"

static bsp_box node_box(const bvh_node *n)
{
    bsp_box b;
    for (unsigned k = 0; k < 3; k++) {
        b.lo.v[k] = n->lo[k];
        b.hi.v[k] = n->hi[k];
    }
    return b;
}

/* A node and its depth on the explicit stacks of the walks below. */
typedef struct node_at {
    uint32_t i;
    int depth;
} node_at;

/* Pushes the children of interior node AT (N), the left one on top. */
static void push_children(node_at *stack, unsigned *sp, const bvh_node *n, node_at at)
{
    stack[(*sp)++] = (node_at){n->index + 1, at.depth + 1};
    stack[(*sp)++] = (node_at){n->index, at.depth + 1};
}

void bvh_stats(const bvh *b, const bsp_scene *scene, bsp_tree_stats *st)
{
    memset(st, 0, sizeof *st);
    st->bytes = b->nnodes ? sizeof(bvh_node) + (uint64_t)(b->nnodes - 2) / 2 * sizeof(bvh_pair) : 0;
    st->trace_bytes = (uint64_t)b->nrec * sizeof(kd_local);
    uint64_t h = FNV1A_BASIS;
    for (uint32_t i = 0; i < b->nrec; i++)
        h = fnv1a_u32(h, b->rec[i].prim);
    if (!b->nnodes) {
        st->digest = h;
        return;
    }
    const bsp_box root = node_box(&b->root);
    const double inv_root = 1.0 / kd_surface_area(&root);
    double depth_sum = 0.0, expected = 0.0, model = 0.0;
    node_at stack[BVH_MAX_DEPTH + 2];
    unsigned sp = 0;
    stack[sp++] = (node_at){0, 0};
    while (sp) {
        node_at at = stack[--sp];
        const bvh_node node = bvh_get(b, at.i), *n = &node;
        bsp_box box = node_box(n);
        double p = kd_surface_area(&box) * inv_root;
        uint32_t cnt = BVH_COUNT(n);
        if (cnt) {
            st->leaves++;
            st->references += cnt;
            depth_sum += at.depth;
            st->max_leaf_depth = at.depth > st->max_leaf_depth ? at.depth : st->max_leaf_depth;
            double tsum = 0.0;
            for (uint32_t j = n->index; j < n->index + cnt; j++)
                tsum += kd_prim_cost(scene, b->rec[j].prim, &b->costs);
            expected += p * cnt;
            model += p * tsum;
        } else {
            st->interior_nodes++;
            expected += p;
            model += p * b->ctrav;
            push_children(stack, &sp, n, at);
        }
    }
    for (uint32_t i = 0; i < b->nnodes; i++) {
        if (i == 1)
            continue; /* unused */
        const bvh_node n = bvh_get(b, i);
        uint32_t w[8];
        memcpy(w, &n, sizeof w);
        for (int k = 0; k < 8; k++)
            h = fnv1a_u32(h, w[k]);
    }
    st->avg_leaf_depth = st->leaves ? depth_sum / (double)st->leaves : 0.0;
    st->expected_cost = expected;
    st->model_cost = model / b->ctrav;
    st->digest = h;
}

static int box_inside(const bsp_box *in, const bsp_box *out)
{
    for (unsigned k = 0; k < 3; k++)
        if (!(in->lo.v[k] >= out->lo.v[k] && in->hi.v[k] <= out->hi.v[k]))
            return 0;
    return 1;
}

bsp_status bvh_check(const bvh *b, const bsp_scene *scene, bsp_error *err)
{
    size_t live = 0;
    for (size_t p = 0; p < scene->nprims; p++)
        live += scene->prims[p].shape != SHAPE_NONE;
    if (b->nrec != live)
        return error_set(err, BSP_ERR_INVALID, NULL, 0, "BVH: %u records for %zu primitives",
                         b->nrec, live);
    if (!b->nnodes)
        return live ? error_set(err, BSP_ERR_INVALID, NULL, 0, "BVH: no nodes") : BSP_OK;
    unsigned char *seen = calloc(scene->nprims ? scene->nprims : 1, 1);
    if (!seen)
        return error_set(err, BSP_ERR_NOMEM, NULL, 0, "out of memory while checking the BVH");
    bsp_status st = BSP_OK;
    /* the boxes along the path: a primitive's padded bounds must lie in each */
    bsp_box path[BVH_MAX_DEPTH + 1];
    node_at stack[BVH_MAX_DEPTH + 2];
    unsigned sp = 0;
    uint32_t next_rec = 0, visited = 0;
    stack[sp++] = (node_at){0, 0};
    while (sp && st == BSP_OK) {
        node_at at = stack[--sp];
        const bvh_node node = bvh_get(b, at.i), *n = &node;
        visited++;
        path[at.depth] = node_box(n);
        uint32_t cnt = BVH_COUNT(n);
        if (!cnt) {
            /* pairs at even indices after the node: each reached once, no cycle */
            if (at.depth >= BVH_MAX_DEPTH || n->index % 2 || n->index <= at.i ||
                n->index + 1 >= b->nnodes || BVH_AXIS(n) > 2) {
                st = error_set(err, BSP_ERR_INVALID, NULL, 0,
                               "BVH node %u: children %u and %u of %u nodes, depth %d", at.i,
                               n->index, n->index + 1, b->nnodes, at.depth);
                break;
            }
            push_children(stack, &sp, n, at);
            continue;
        }
        /* leaves come in record order, left before right */
        if (n->index != next_rec || cnt > b->nrec - next_rec) {
            st = error_set(err, BSP_ERR_INVALID, NULL, 0,
                           "BVH leaf %u: records %u..%u, expected from %u of %u", at.i,
                           n->index, n->index + cnt, next_rec, b->nrec);
            break;
        }
        next_rec += cnt;
        for (uint32_t j = n->index; j < n->index + cnt && st == BSP_OK; j++) {
            uint32_t p = b->rec[j].prim;
            kd_local fresh;
            if (p >= scene->nprims || scene->prims[p].shape == SHAPE_NONE || seen[p]) {
                st = error_set(err, BSP_ERR_INVALID, NULL, 0,
                               "BVH leaf %u: primitive %u dropped, unknown or listed twice",
                               at.i, p);
                break;
            }
            seen[p] = 1;
            kd_local_fill(&fresh, scene, p);
            if (memcmp(&fresh, &b->rec[j], sizeof fresh) != 0) {
                st = error_set(err, BSP_ERR_INVALID, NULL, 0,
                               "BVH record %u: not primitive %u's data", j, p);
                break;
            }
            bsp_box pb = box_grow(bsp_scene_prim_bounds(scene, p), b->pad);
            for (int d = 0; d <= at.depth; d++)
                if (!box_inside(&pb, &path[d])) {
                    st = error_set(err, BSP_ERR_INVALID, NULL, 0,
                                   "BVH: primitive %u's padded bounds leave the box of its "
                                   "ancestor at depth %d (leaf %u)",
                                   p, d, at.i);
                    break;
                }
        }
    }
    /* every node but the unused slot 1 */
    if (st == BSP_OK && (next_rec != b->nrec || visited + 1 != b->nnodes))
        st = error_set(err, BSP_ERR_INVALID, NULL, 0,
                       "BVH: %u of %u records and %u of %u nodes reached", next_rec, b->nrec,
                       visited, b->nnodes);
    free(seen);
    return st;
}

bsp_status bvh_visit(const bvh *b, int max_depth,
                     int (*visit)(const bsp_cell_info *cell, void *ctx), void *ctx)
{
    if (!b->nnodes)
        return BSP_OK;
    node_at stack[BVH_MAX_DEPTH + 2];
    unsigned sp = 0;
    stack[sp++] = (node_at){0, 0};
    while (sp) {
        node_at at = stack[--sp];
        const bvh_node node = bvh_get(b, at.i), *n = &node;
        bsp_cell_info c;
        memset(&c, 0, sizeof c);
        c.box = node_box(n);
        c.depth = at.depth;
        uint32_t cnt = BVH_COUNT(n);
        c.is_leaf = cnt != 0;
        if (cnt) {
            c.refs = cnt;
        } else {
            c.axis = BVH_AXIS(n);
            c.split = bvh_get(b, n->index + 1).lo[c.axis];
            /* the references below: the records from the leftmost leaf's
             * first to the rightmost leaf's last, in record order */
            bvh_node l = *n, r = *n;
            while (!BVH_COUNT(&l))
                l = bvh_get(b, l.index);
            while (!BVH_COUNT(&r))
                r = bvh_get(b, r.index + 1);
            c.refs = (uint64_t)r.index + BVH_COUNT(&r) - l.index;
        }
        int go = visit(&c, ctx);
        if (go && !cnt && (max_depth < 0 || at.depth < max_depth)) {
            push_children(stack, &sp, n, at);
        }
    }
    return BSP_OK;
}
