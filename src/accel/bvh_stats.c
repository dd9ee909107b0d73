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

/* What a walk's step says: go into the node's children, skip them, or stop. */
enum { WALK_STOP = -1, WALK_SKIP = 0, WALK_DOWN = 1 };

/* Walks B (not empty) depth first, a node before its children, left to
 * right, calling STEP with each node's id, the node and its depth; STEP's
 * answer for an interior node decides whether its children follow. STEP must
 * not send the walk below BVH_MAX_DEPTH (the built trees do not go there;
 * the checker refuses a node that would). */
static void walk_nodes(const bvh *b, int (*step)(void *ctx, uint32_t id, const bvh_node *n,
                                                 int depth),
                       void *ctx)
{
    struct {
        uint32_t id;
        int depth;
    } stack[(BVH_WIDEST - 1) * BVH_MAX_DEPTH + 4]; /* at most W - 1 pushed per level,
                                                    * beside the one taken */
    unsigned sp = 0;
    stack[sp].id = 0;
    stack[sp++].depth = 0;
    while (sp) {
        sp--;
        uint32_t id = stack[sp].id;
        int depth = stack[sp].depth;
        const bvh_node n = bvh_get(b, id);
        int go = step(ctx, id, &n, depth);
        if (go == WALK_STOP)
            return;
        if (go == WALK_DOWN && !BVH_COUNT(&n)) {
            uint32_t ids[BVH_WIDEST];
            for (unsigned c = bvh_children(b, &n, ids); c-- > 0;) { /* the right under the left */
                stack[sp].id = ids[c];
                stack[sp++].depth = depth + 1;
            }
        }
    }
}

/* bvh_stats's sums over the walk. */
typedef struct stats_walk {
    const bvh *b;
    const bsp_scene *scene;
    bsp_tree_stats *st;
    double inv_root, depth_sum, expected, model;
} stats_walk;

static int stats_step(void *ctx, uint32_t id, const bvh_node *n, int depth)
{
    (void)id;
    stats_walk *w = ctx;
    bsp_box box = node_box(n);
    double p = kd_surface_area(&box) * w->inv_root;
    uint32_t cnt = BVH_COUNT(n);
    if (!cnt) {
        w->st->interior_nodes++;
        w->expected += p;
        w->model += p * w->b->costs.traversal;
        return WALK_DOWN;
    }
    w->st->leaves++;
    w->st->references += cnt;
    w->depth_sum += depth;
    if (depth > w->st->max_leaf_depth)
        w->st->max_leaf_depth = depth;
    double tsum = 0.0;
    for (uint32_t j = n->index; j < n->index + cnt; j++)
        tsum += kd_prim_cost(w->scene, w->b->rec[j].prim, &w->b->costs);
    w->expected += p * cnt;
    w->model += p * tsum;
    return WALK_DOWN;
}

void bvh_stats(const bvh *b, const bsp_scene *scene, bsp_tree_stats *st)
{
    memset(st, 0, sizeof *st);
    if (b->width != 2)
        st->bytes = b->nnodes ? sizeof(bvh_node) + (uint64_t)(b->nnodes - 1) / b->width *
                                                       BVH_WIDE_BYTES(b->width)
                              : 0;
    else
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
    stats_walk w = {b, scene, st, 1.0 / kd_surface_area(&root), 0.0, 0.0, 0.0};
    walk_nodes(b, stats_step, &w);
    for (uint32_t i = 0; i < b->nnodes; i++) {
        if (i == 1 && b->width == 2)
            continue; /* unused */
        const bvh_node n = bvh_get(b, i);
        uint32_t words[8];
        memcpy(words, &n, sizeof words);
        for (int k = 0; k < 8; k++)
            h = fnv1a_u32(h, words[k]);
    }
    st->avg_leaf_depth = st->leaves ? w.depth_sum / (double)st->leaves : 0.0;
    st->expected_cost = w.expected;
    st->model_cost = w.model / b->costs.traversal;
    st->digest = h;
}

static int box_inside(const bsp_box *in, const bsp_box *out)
{
    for (unsigned k = 0; k < 3; k++)
        if (!(in->lo.v[k] >= out->lo.v[k] && in->hi.v[k] <= out->hi.v[k]))
            return 0;
    return 1;
}

/* bvh_check's state over the walk. */
typedef struct check_walk {
    const bvh *b;
    const bsp_scene *scene;
    bsp_error *err;
    bsp_status st;
    unsigned char *seen;              /* per primitive: listed already */
    uint32_t next_rec, visited, unused; /* unused: wide nodes' lanes not in use */
    bsp_box path[BVH_MAX_DEPTH + 1];  /* the boxes from the root to the node */
} check_walk;

static int check_fail(check_walk *w, bsp_status st)
{
    w->st = st;
    return WALK_STOP;
}

static int check_step(void *ctx, uint32_t id, const bvh_node *n, int depth)
{
    check_walk *w = ctx;
    const bvh *b = w->b;
    w->visited++;
    w->path[depth] = node_box(n);
    uint32_t cnt = BVH_COUNT(n);
    if (!cnt && b->width != 2) {
        /* wide nodes after the node's own: each reached once, no cycle; two
         * to W lanes in use, first, the others empty (+inf..-inf) */
        const unsigned wd = b->width;
        uint32_t nq = (b->nnodes - 1) / wd, own = id ? (id - 1) / wd : 0;
        int bad = depth >= BVH_MAX_DEPTH || n->index >= nq || (id && n->index <= own) ||
                  BVH_AXIS(n) > 2;
        unsigned used = 0;
        for (unsigned c = 0; !bad && c < wd; c++) {
            const unsigned char *q = bvh_wide_node(b, n->index);
            if (bvh_wide_index(q, wd, c) != BVH_NONE) {
                bad |= used != c;
                used++;
                continue;
            }
            bad |= bvh_wide_meta(q, wd, c) != 0;
            for (unsigned k = 0; k < 3; k++)
                bad |= !(bvh_wide_lo(q, wd, k, c) == INFINITY &&
                         bvh_wide_hi(q, wd, k, c) == -INFINITY);
        }
        if (bad || used < 2)
            return check_fail(w, error_set(w->err, BSP_ERR_INVALID, NULL, 0,
                                           "BVH node %u: wide node %u of %u (%u children), "
                                           "depth %d",
                                           id, n->index, nq, used, depth));
        w->unused += wd - used;
        return WALK_DOWN;
    }
    if (!cnt) {
        /* pairs at even indices after the node: each reached once, no cycle */
        if (depth >= BVH_MAX_DEPTH || n->index % 2 || n->index <= id ||
            n->index + 1 >= b->nnodes || BVH_AXIS(n) > 2)
            return check_fail(w, error_set(w->err, BSP_ERR_INVALID, NULL, 0,
                                           "BVH node %u: children %u and %u of %u nodes, "
                                           "depth %d",
                                           id, n->index, n->index + 1, b->nnodes, depth));
        return WALK_DOWN;
    }
    /* leaves come in record order, left before right */
    if (n->index != w->next_rec || cnt > b->nrec - w->next_rec)
        return check_fail(w, error_set(w->err, BSP_ERR_INVALID, NULL, 0,
                                       "BVH leaf %u: records %u..%u, expected from %u of %u",
                                       id, n->index, n->index + cnt, w->next_rec, b->nrec));
    w->next_rec += cnt;
    for (uint32_t j = n->index; j < n->index + cnt; j++) {
        uint32_t p = b->rec[j].prim;
        if (p >= w->scene->nprims || w->scene->prims[p].shape == SHAPE_NONE || w->seen[p])
            return check_fail(w, error_set(w->err, BSP_ERR_INVALID, NULL, 0,
                                           "BVH leaf %u: primitive %u dropped, unknown or "
                                           "listed twice",
                                           id, p));
        w->seen[p] = 1;
        kd_local fresh;
        kd_local_fill(&fresh, w->scene, p);
        if (memcmp(&fresh, &b->rec[j], sizeof fresh) != 0)
            return check_fail(w, error_set(w->err, BSP_ERR_INVALID, NULL, 0,
                                           "BVH record %u: not primitive %u's data", j, p));
        bsp_box pb = box_grow(bsp_scene_prim_bounds(w->scene, p), b->pad);
        for (int d = 0; d <= depth; d++)
            if (!box_inside(&pb, &w->path[d]))
                return check_fail(w, error_set(w->err, BSP_ERR_INVALID, NULL, 0,
                                               "BVH: primitive %u's padded bounds leave the "
                                               "box of its ancestor at depth %d (leaf %u)",
                                               p, d, id));
    }
    return WALK_DOWN;
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
    check_walk w = {.b = b, .scene = scene, .err = err, .st = BSP_OK};
    w.seen = calloc(scene->nprims ? scene->nprims : 1, 1);
    if (!w.seen)
        return error_set(err, BSP_ERR_NOMEM, NULL, 0, "out of memory while checking the BVH");
    walk_nodes(b, check_step, &w);
    /* every node but the unused slot 1 (width 2) or the wide nodes' unused lanes */
    uint32_t unused = b->width != 2 ? w.unused : 1;
    if (w.st == BSP_OK && (w.next_rec != b->nrec || w.visited + unused != b->nnodes))
        w.st = error_set(err, BSP_ERR_INVALID, NULL, 0,
                         "BVH: %u of %u records and %u of %u nodes reached", w.next_rec,
                         b->nrec, w.visited, b->nnodes);
    free(w.seen);
    return w.st;
}

/* bvh_visit's caller and limit. */
typedef struct visit_walk {
    const bvh *b;
    int max_depth;
    int (*visit)(const bsp_cell_info *cell, void *ctx);
    void *ctx;
} visit_walk;

static int visit_step(void *ctx, uint32_t id, const bvh_node *n, int depth)
{
    (void)id;
    visit_walk *w = ctx;
    bsp_cell_info c;
    memset(&c, 0, sizeof c);
    c.box = node_box(n);
    c.depth = depth;
    uint32_t cnt = BVH_COUNT(n);
    c.is_leaf = cnt != 0;
    if (cnt) {
        c.refs = cnt;
    } else {
        uint32_t ids[BVH_WIDEST] = {0};
        bvh_children(w->b, n, ids);
        c.axis = BVH_AXIS(n);
        c.split = bvh_get(w->b, ids[1]).lo[c.axis];
        /* the references below: the records from the leftmost leaf's
         * first to the rightmost leaf's last, in record order */
        bvh_node l = *n, r = *n;
        while (!BVH_COUNT(&l)) {
            bvh_children(w->b, &l, ids);
            l = bvh_get(w->b, ids[0]);
        }
        while (!BVH_COUNT(&r))
            r = bvh_get(w->b, ids[bvh_children(w->b, &r, ids) - 1]);
        c.refs = (uint64_t)r.index + BVH_COUNT(&r) - l.index;
    }
    int go = w->visit(&c, w->ctx);
    return go && (w->max_depth < 0 || depth < w->max_depth) ? WALK_DOWN : WALK_SKIP;
}

bsp_status bvh_visit(const bvh *b, int max_depth,
                     int (*visit)(const bsp_cell_info *cell, void *ctx), void *ctx)
{
    if (!b->nnodes)
        return BSP_OK;
    visit_walk w = {b, max_depth, visit, ctx};
    walk_nodes(b, visit_step, &w);
    return BSP_OK;
}
