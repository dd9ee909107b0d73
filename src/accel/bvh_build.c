/*
 * bvh_build.c — the BVH's top-down build by the binned surface area
 * heuristic (Wald, "On fast construction of SAH-based bounding volume
 * hierarchies", 2007): at each node the primitives' centroids are put in
 * BVH_BINS bins along each axis, the SAH cost
 *     C_trav + (A_L / A) sum_{i in L} T_i + (A_R / A) sum_{i in R} T_i
 * (A the surface area of a box, T_i the kd-trees' per-kind intersection
 * costs, bsp_build_options.sah_costs) is evaluated between every two bins,
 * and the cheapest split is taken when it beats the leaf's cost sum_i T_i or
 * the node holds more than the most primitives a leaf may hold
 * (bsp_build_options.max_leaf_prims, default BVH_LEAF_MAX). Centroids that
 * all coincide are halved in index order; a node at max_depth (default and
 * at most BVH_MAX_DEPTH) is a leaf. O(N log N) for a tree of logarithmic
 * depth. The wide trees (`--accel bvh4`, `bvh8`) are this binary tree
 * collapsed (collapse_node). Layout and exactness: bvh.h.
 *
 * Threads (bsp_build_options.threads): in a scene of at least
 * 2 BVH_TASK_FLOOR primitives, the calling thread builds the top of the
 * tree and defers each node of task_min..task_max primitives (about 1/512
 * to 1/64 of the scene) as a task, which the pool's workers build (each
 * into pairs of its own) while the top goes on; the subtrees are then
 * appended after the top's pairs in task order, their child ids rebased.
 * Which nodes become tasks depends only on the scene, and one thread defers
 * them too, so every thread count gives the same bytes. A task's subtree
 * partitions only its own range of the primitives' order, and every leaf
 * fills its own range of the records as it is made. The bounds pre-pass
 * before it runs on the same threads, in parts (prim_bounds_and_costs).
 */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "accel/bvh.h"
#include "accel/kd_cost.h"
#include "geom/vec.h"
#include "util/bigmem.h"
#include "util/task_pool.h"

/* No tasks below 2 x this many primitives; a task has at most this many or
 * 1/64 of the scene, whichever is more. */
#define BVH_TASK_FLOOR 4096

typedef struct bvh_task bvh_task;

typedef struct builder {
    const bsp_scene *s;
    const bsp_box *bounds; /* per primitive: its bounds grown by pad */
    const double *cost;    /* per primitive: T_i */
    uint32_t *order;       /* the live primitives, partitioned as the build goes */
    kd_local *rec;         /* the records in leaf order: a leaf fills its range */
    bvh_node *root;        /* node id 0 goes here */
    bvh_pair *pairs;       /* node id 2 + 2p + c goes to pairs[p], lane c */
    uint32_t nnodes;       /* the next pair's first id */
    double ctrav;
    uint32_t leaf_max; /* a node of more primitives is split (if it can be) */
    int depth_max;     /* a node this deep is a leaf */
    /* the top of a threaded build (pool not NULL): its deferred tasks */
    task_pool *pool;
    uint32_t task_min, task_max; /* the sizes of node deferred */
    bvh_task **tasks;            /* in the order listed */
    size_t ntasks, cap;
    int failed; /* out of memory: a task could not be listed */
} builder;

/* A deferred subtree: node ME of the top, ORDER[begin, end) at DEPTH, built
 * by its own builder into ROOT and PAIRS (ids from 2, as in a whole tree). */
struct bvh_task {
    builder b;
    uint32_t me, begin, end;
    int depth;
    bvh_node root;
    bvh_pair *pairs; /* room for end - begin - 1 pairs (a tree of that many leaves) */
    int failed;      /* out of memory */
};


static double centroid(const bsp_box *b, unsigned k)
{
    return 0.5 * (b->lo.v[k] + b->hi.v[k]);
}

/* The bin of centroid C on an axis whose centroids span [LO, LO + extent),
 * SCALE = BVH_BINS / extent: the same function bins and partitions. */
static int bin_of(double c, double lo, double scale)
{
    int i = (int)((c - lo) * scale);
    return i < 0 ? 0 : i >= BVH_BINS ? BVH_BINS - 1 : i;
}

typedef struct split_choice {
    unsigned axis;
    int last_left; /* the last bin on the left side */
    double lo, scale;
} split_choice;

/* The cheapest binned split of ORDER[begin, end) (box BOX, centroids in
 * CBOX, cost sum TSUM): 1 and *OUT when it is to be made (it beats the leaf,
 * or the node is too large for one), else 0. */
static int choose_split(const builder *b, uint32_t begin, uint32_t end, const bsp_box *box,
                        const bsp_box *cbox, double tsum, split_choice *out)
{
    const uint32_t n = end - begin;
    const double inv_area = 1.0 / kd_surface_area(box);
    double best = INFINITY;
    for (unsigned k = 0; k < 3; k++) {
        double extent = cbox->hi.v[k] - cbox->lo.v[k];
        if (!(extent > 0.0))
            continue;
        double scale = BVH_BINS / extent;
        bsp_box bin_box[BVH_BINS];
        double bin_cost[BVH_BINS];
        uint32_t bin_n[BVH_BINS];
        for (int i = 0; i < BVH_BINS; i++) {
            bin_box[i] = box_empty();
            bin_cost[i] = 0.0;
            bin_n[i] = 0;
        }
        for (uint32_t j = begin; j < end; j++) {
            uint32_t p = b->order[j];
            int i = bin_of(centroid(&b->bounds[p], k), cbox->lo.v[k], scale);
            bin_box[i] = box_union(bin_box[i], b->bounds[p]);
            bin_cost[i] += b->cost[p];
            bin_n[i]++;
        }
        /* right side's area x cost for the splits after bins 0 .. BINS-2 */
        double right[BVH_BINS];
        bsp_box acc = box_empty();
        double csum = 0.0;
        uint32_t nsum = 0;
        for (int i = BVH_BINS - 1; i > 0; i--) {
            acc = box_union(acc, bin_box[i]);
            csum += bin_cost[i];
            nsum += bin_n[i];
            right[i - 1] = nsum ? kd_surface_area(&acc) * csum : -1.0;
        }
        acc = box_empty();
        csum = 0.0;
        nsum = 0;
        for (int i = 0; i < BVH_BINS - 1; i++) {
            acc = box_union(acc, bin_box[i]);
            csum += bin_cost[i];
            nsum += bin_n[i];
            if (!nsum || right[i] < 0.0)
                continue; /* a side would be empty */
            double c = b->ctrav + (kd_surface_area(&acc) * csum + right[i]) * inv_area;
            if (c < best) {
                best = c;
                out->axis = k;
                out->last_left = i;
                out->lo = cbox->lo.v[k];
                out->scale = scale;
            }
        }
    }
    if (best == INFINITY) /* every centroid the same: halve by index when too many */
        return n > b->leaf_max ? (out->axis = 0, out->last_left = -1, 1) : 0;
    return best < tsum || n > b->leaf_max;
}

/* Partitions ORDER[begin, end) by C: the left side first; returns where the
 * right side starts (the middle when C halves by index). */
static uint32_t partition(builder *b, uint32_t begin, uint32_t end, const split_choice *c)
{
    if (c->last_left < 0)
        return begin + (end - begin) / 2;
    uint32_t i = begin, j = end;
    while (i < j) {
        uint32_t p = b->order[i];
        if (bin_of(centroid(&b->bounds[p], c->axis), c->lo, c->scale) <= c->last_left) {
            i++;
        } else {
            b->order[i] = b->order[--j];
            b->order[j] = p;
        }
    }
    return i;
}

/* Stores N as node ID of B's output (bvh.h). */
static void set_node(builder *b, uint32_t id, const bvh_node *n)
{
    if (id == 0) {
        *b->root = *n;
        return;
    }
    bvh_pair *p = &b->pairs[(id - 2) >> 1];
    unsigned c = id & 1u;
    for (unsigned k = 0; k < 3; k++) {
        p->lo[k][c] = n->lo[k];
        p->hi[k][c] = n->hi[k];
    }
    p->index[c] = n->index;
    p->meta[c] = n->meta;
}

/* Lists ORDER[begin, end) at DEPTH as a task for node ME of B (the top). */
static void defer(builder *b, uint32_t me, uint32_t begin, uint32_t end, int depth)
{
    bvh_task *tk = calloc(1, sizeof *tk);
    if (b->ntasks == b->cap && tk) {
        size_t ncap = b->cap ? 2 * b->cap : 64;
        bvh_task **nv = realloc(b->tasks, ncap * sizeof *nv);
        if (nv) {
            b->tasks = nv;
            b->cap = ncap;
        }
    }
    if (!tk || b->ntasks == b->cap) {
        free(tk);
        b->failed = 1;
        return;
    }
    tk->b = *b;
    tk->b.pool = NULL; /* a task defers nothing */
    tk->b.tasks = NULL;
    tk->b.ntasks = tk->b.cap = 0;
    tk->me = me;
    tk->begin = begin;
    tk->end = end;
    tk->depth = depth;
    if (!task_pool_add(b->pool, tk)) {
        free(tk);
        b->failed = 1;
        return;
    }
    b->tasks[b->ntasks++] = tk;
}

/* Builds the subtree of ORDER[begin, end) (not empty) at DEPTH as node ME,
 * its children's pairs from b->nnodes on, or defers it (defer). Never runs
 * out of room: a tree of n non-empty leaves has n - 1 pairs, and b->pairs
 * holds that many. */
static void build_node(builder *b, uint32_t me, uint32_t begin, uint32_t end, int depth)
{
    if (b->pool && end - begin <= b->task_max && end - begin >= b->task_min) {
        defer(b, me, begin, end, depth);
        return;
    }
    bsp_box box = box_empty(), cbox = box_empty();
    double tsum = 0.0;
    for (uint32_t j = begin; j < end; j++) {
        const bsp_box *pb = &b->bounds[b->order[j]];
        box = box_union(box, *pb);
        for (unsigned k = 0; k < 3; k++) {
            double c = centroid(pb, k);
            cbox.lo.v[k] = c < cbox.lo.v[k] ? c : cbox.lo.v[k];
            cbox.hi.v[k] = c > cbox.hi.v[k] ? c : cbox.hi.v[k];
        }
        tsum += b->cost[b->order[j]];
    }
    bvh_node node;
    for (unsigned k = 0; k < 3; k++) {
        node.lo[k] = bvh_float_down(box.lo.v[k]);
        node.hi[k] = bvh_float_up(box.hi.v[k]);
    }
    split_choice c = {0, -1, 0.0, 0.0};
    if (depth >= b->depth_max || !choose_split(b, begin, end, &box, &cbox, tsum, &c)) {
        node.index = begin;
        node.meta = (end - begin) << 2;
        set_node(b, me, &node);
        for (uint32_t j = begin; j < end; j++)
            kd_local_fill(&b->rec[j], b->s, b->order[j]);
        return;
    }
    uint32_t mid = partition(b, begin, end, &c);
    uint32_t pair = b->nnodes;
    b->nnodes += 2;
    node.index = pair;
    node.meta = c.axis;
    set_node(b, me, &node);
    build_node(b, pair, begin, mid, depth + 1);
    build_node(b, pair + 1, mid, end, depth + 1);
}

/* Builds task TASK (a task_run_fn). */
static void run_task(void *ctx, void *task)
{
    (void)ctx;
    bvh_task *tk = task;
    uint32_t m = tk->end - tk->begin;
    tk->pairs = malloc((m > 1 ? m - 1 : 1) * sizeof *tk->pairs);
    if (!tk->pairs) {
        tk->failed = 1;
        return;
    }
    tk->b.root = &tk->root;
    tk->b.pairs = tk->pairs;
    tk->b.nnodes = 2;
    build_node(&tk->b, 0, tk->begin, tk->end, tk->depth);
}

/* Appends the tasks' subtrees to B's tree, in task order, after its pairs:
 * the task's id j >= 2 becomes b->nnodes + j - 2 at the time, its root goes
 * to its node of the top. Frees the tasks; 0 when one of them failed. */
static int splice_tasks(builder *b)
{
    int ok = !b->failed;
    for (size_t i = 0; i < b->ntasks; i++) {
        bvh_task *tk = b->tasks[i];
        ok = ok && !tk->failed;
        if (ok) {
            const uint32_t shift = b->nnodes - 2, npairs = (tk->b.nnodes - 2) / 2;
            for (uint32_t p = 0; p < npairs; p++) {
                bvh_pair x = tk->pairs[p];
                for (unsigned c = 0; c < 2; c++)
                    x.index[c] += (x.meta[c] >> 2) ? 0 : shift; /* interior: a pair's id */
                b->pairs[(b->nnodes - 2) / 2 + p] = x;
            }
            if (!BVH_COUNT(&tk->root))
                tk->root.index += shift;
            set_node(b, tk->me, &tk->root);
            b->nnodes += 2 * npairs;
        }
        free(tk->pairs);
        free(tk);
    }
    free(b->tasks);
    b->tasks = NULL;
    b->ntasks = b->cap = 0;
    return ok;
}

/* The children of binary node N (interior) that its wide node (width W)
 * takes, in KIDS, left to right: its two, then, while fewer than W, the
 * interior one of the largest surface area replaced by its two (Embree's
 * collapse). Returns how many. */
static unsigned wide_children(const bvh *bin, const bvh_node *n, unsigned w,
                              bvh_node kids[BVH_WIDEST])
{
    unsigned m = 2;
    kids[0] = bvh_get(bin, n->index);
    kids[1] = bvh_get(bin, n->index + 1);
    while (m < w) {
        int open = -1;
        double most = -1.0;
        for (unsigned i = 0; i < m; i++) {
            if (BVH_COUNT(&kids[i]))
                continue;
            bsp_box box;
            for (unsigned k = 0; k < 3; k++) {
                box.lo.v[k] = kids[i].lo[k];
                box.hi.v[k] = kids[i].hi[k];
            }
            double area = kd_surface_area(&box);
            if (area > most) {
                most = area;
                open = (int)i;
            }
        }
        if (open < 0)
            break;
        const bvh_node o = kids[open];
        memmove(&kids[open + 2], &kids[open + 1], (m - (unsigned)open - 1) * sizeof *kids);
        kids[open] = bvh_get(bin, o.index);
        kids[open + 1] = bvh_get(bin, o.index + 1);
        m++;
    }
    return m;
}

/* Collapses the subtree of binary node N (interior) of BIN into wide nodes
 * of width W from *NQ on, in the block NODES, depth first, a node before
 * its children's (NODES NULL: counts them only); returns N's wide node.
 * The leaves keep their left-to-right order, so the records stay in leaf
 * order. */
static uint32_t collapse_node(const bvh *bin, const bvh_node *n, unsigned w,
                              unsigned char *nodes, uint32_t *nq)
{
    bvh_node kids[BVH_WIDEST];
    unsigned m = wide_children(bin, n, w, kids);
    uint32_t me = (*nq)++;
    unsigned char *q = nodes ? nodes + (size_t)me * BVH_WIDE_BYTES(w) : NULL;
    const bvh_node unused = {{INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY},
                             BVH_NONE, 0};
    for (unsigned c = 0; q && c < w; c++)
        bvh_wide_set(q, w, c, c < m ? &kids[c] : &unused);
    for (unsigned c = 0; c < m; c++) {
        if (BVH_COUNT(&kids[c]))
            continue;
        bvh_node child = kids[c];
        child.index = collapse_node(bin, &kids[c], w, nodes, nq);
        if (q)
            bvh_wide_set(q, w, c, &child);
    }
    return me;
}

/* Turns T's binary tree into its wide form of width W (bvh.h): BSP_OK, or
 * BSP_ERR_NOMEM with T unchanged. */
static bsp_status collapse(bvh *t, unsigned w)
{
    uint32_t nq = 0;
    if (t->nnodes && !BVH_COUNT(&t->root))
        collapse_node(t, &t->root, w, NULL, &nq);
    void *block = bigmem_malloc((nq ? nq : 1) * (size_t)BVH_WIDE_BYTES(w) + 63);
    if (!block)
        return BSP_ERR_NOMEM;
    unsigned char *nodes = (unsigned char *)(((uintptr_t)block + 63) & ~(uintptr_t)63);
    uint32_t filled = 0;
    if (nq)
        t->root.index = collapse_node(t, &t->root, w, nodes, &filled);
    free(t->nodes_block);
    t->nodes_block = block;
    t->pairs = NULL;
    t->wide = nodes;
    t->width = w;
    t->nnodes = t->nnodes ? 1 + w * nq : 0;
    return BSP_OK;
}

void bvh_destroy(void *impl)
{
    bvh *t = impl;
    if (!t)
        return;
    free(t->nodes_block);
    free(t->rec);
    free(t);
}

static const accel_ops bvh_ops = {bvh_intersect, bvh_occluded, bvh_destroy};
static const accel_ops bvh_wide_ops = {bvh_wide_intersect, bvh_wide_occluded, bvh_destroy};

static bsp_status bvh_oom(bsp_error *err)
{
    return error_set(err, BSP_ERR_NOMEM, NULL, 0, "out of memory while building the BVH");
}

/* The bounds pre-pass over primitives [begin, end) of a scene: each live
 * one's padded bounds and T_i, at its index (a task_run_fn; each task
 * writes its own range). */
typedef struct prepass_part {
    const bsp_scene *s;
    double pad;
    const bsp_sah_costs *costs;
    bsp_box *bounds;
    double *cost;
    uint32_t begin, end;
} prepass_part;

static void run_prepass(void *ctx, void *task)
{
    (void)ctx;
    const prepass_part *pp = task;
    for (uint32_t p = pp->begin; p < pp->end; p++) {
        if (pp->s->prims[p].shape == SHAPE_NONE)
            continue;
        pp->bounds[p] = box_grow(bsp_scene_prim_bounds(pp->s, p), pp->pad);
        pp->cost[p] = kd_prim_cost(pp->s, p, pp->costs);
    }
}

/* BOUNDS[p] and COST[p] for every live primitive p of S, on THREADS threads
 * (in parts of PREPASS_PARTS, whichever thread runs a part, the same
 * values); 0 when out of memory. */
#define PREPASS_PARTS 32
static int prim_bounds_and_costs(const bsp_scene *s, double pad, const bsp_sah_costs *costs,
                                 bsp_box *bounds, double *cost, int threads)
{
    const uint32_t np = (uint32_t)s->nprims;
    prepass_part parts[PREPASS_PARTS];
    for (uint32_t i = 0; i < PREPASS_PARTS; i++)
        parts[i] = (prepass_part){s, pad, costs, bounds, cost,
                                  (uint32_t)((uint64_t)np * i / PREPASS_PARTS),
                                  (uint32_t)((uint64_t)np * (i + 1) / PREPASS_PARTS)};
    if (threads <= 1) {
        for (uint32_t i = 0; i < PREPASS_PARTS; i++)
            run_prepass(NULL, &parts[i]);
        return 1;
    }
    task_pool *pool = task_pool_create(threads, PREPASS_PARTS, run_prepass, NULL);
    if (!pool)
        return 0;
    uint32_t listed = 0;
    while (listed < PREPASS_PARTS && task_pool_add(pool, &parts[listed]))
        listed++;
    task_pool_finish(pool);
    /* a part the pool could not list: made here */
    for (uint32_t i = listed; i < PREPASS_PARTS; i++)
        run_prepass(NULL, &parts[i]);
    return 1;
}

bsp_status bvh_build(bsp_accel *a, bsp_error *err)
{
    const bsp_scene *s = a->scene;
    const size_t np = s->nprims;
    size_t n = 0;
    for (size_t p = 0; p < np; p++)
        n += s->prims[p].shape != SHAPE_NONE;
    if (n >= BVH_MAX_PRIMS)
        return error_set(err, BSP_ERR_LIMIT, NULL, 0,
                         "a BVH holds at most %u primitives, the scene has %zu",
                         (unsigned)BVH_MAX_PRIMS - 1, n);
    /* the wide trees' width, 0 for the binary one */
    const unsigned wide = a->opts.kind == BSP_ACCEL_BVH8   ? 8
                          : a->opts.kind == BSP_ACCEL_BVH4 ? 4
                                                           : 0;
    const size_t npairs = n ? n - 1 : 0;
    /* a wide tree: at most a wide node per pair, made while the pairs live */
    const size_t bytes =
        npairs * (sizeof(bvh_pair) + (wide ? BVH_WIDE_BYTES(wide) : 0)) + n * sizeof(kd_local);
    const size_t limit = accel_max_bytes(&a->opts);
    if (limit && bytes > limit)
        return error_set(err, BSP_ERR_LIMIT, NULL, 0,
                         "the BVH would take %zu bytes, over the limit of %zu", bytes, limit);
    kd_cost_model cm;
    kd_cost_resolve(&a->opts, &cm);
    /* a step tests a pair of boxes: BVH_TRAVERSAL_COST kd-tree steps (the
     * T_i stay the kd-trees') */
    cm.c.traversal *= BVH_TRAVERSAL_COST;
    bvh *t = calloc(1, sizeof *t);
    if (!t)
        return bvh_oom(err);
    t->width = 2;
    t->pad = KD_PAD_REL * scene_scale(s);
    t->float_origin = -1.0; /* no float tests */
    if (wide) {
        /* the float tests' error grows with |face| + |o|: the pad with the
         * largest coordinate M of the scene, and the origins they take
         * within 2^19 pads less M (bvh.h); no float tests where M nears
         * the float range */
        double m = 0.0;
        for (unsigned k = 0; k < 3 && !box_is_empty(s->bounds); k++)
            m = fmax(m, fmax(fabs(s->bounds.lo.v[k]), fabs(s->bounds.hi.v[k])));
        t->pad = fmax(t->pad, BVH_WIDE_PAD_REL * m);
        if (m <= 1e30)
            t->float_origin = BVH_WIDE_FLOAT_ORIGIN_PADS * t->pad - m;
    }
    t->costs = cm.c;
    builder b = {0};
    b.ctrav = cm.c.traversal;
    /* the limits, 0s filled in (bsp_accel_get_options reports them) */
    if (a->opts.max_leaf_prims <= 0)
        a->opts.max_leaf_prims = BVH_LEAF_MAX;
    if (a->opts.max_depth <= 0 || a->opts.max_depth > BVH_MAX_DEPTH)
        a->opts.max_depth = BVH_MAX_DEPTH;
    b.leaf_max = (uint32_t)a->opts.max_leaf_prims;
    b.depth_max = a->opts.max_depth;
    bsp_box *bounds = bigmem_malloc((np ? np : 1) * sizeof *bounds);
    double *cost = bigmem_malloc((np ? np : 1) * sizeof *cost);
    b.order = malloc((n ? n : 1) * sizeof *b.order);
    /* 63 bytes more, to start the array on a line */
    t->nodes_block = bigmem_malloc((npairs ? npairs : 1) * sizeof *t->pairs + 63);
    if (t->nodes_block)
        t->pairs = (bvh_pair *)(((uintptr_t)t->nodes_block + 63) & ~(uintptr_t)63);
    t->rec = bigmem_malloc((n ? n : 1) * sizeof *t->rec);
    bsp_status st = BSP_OK;
    if (!bounds || !cost || !b.order || !t->pairs || !t->rec) {
        st = bvh_oom(err);
        goto done;
    }
    if (!prim_bounds_and_costs(s, t->pad, &cm.c, bounds, cost,
                               n >= 2 * BVH_TASK_FLOOR ? task_pool_threads(a->opts.threads) : 1)) {
        st = bvh_oom(err);
        goto done;
    }
    uint32_t live = 0;
    for (uint32_t p = 0; p < (uint32_t)np; p++)
        if (s->prims[p].shape != SHAPE_NONE)
            b.order[live++] = p;
    b.s = s;
    b.bounds = bounds;
    b.cost = cost;
    b.rec = t->rec;
    b.root = &t->root;
    b.pairs = t->pairs;
    if (n >= 2 * BVH_TASK_FLOOR) {
        b.task_max = (uint32_t)(n / 64 > BVH_TASK_FLOOR ? n / 64 : BVH_TASK_FLOOR);
        b.task_min = b.task_max / 8;
        b.pool = task_pool_create(task_pool_threads(a->opts.threads), n / b.task_min + 1,
                                  run_task, NULL);
        if (!b.pool) {
            st = bvh_oom(err);
            goto done;
        }
    }
    if (n) {
        b.nnodes = 2; /* the root, and id 1, unused */
        build_node(&b, 0, 0, (uint32_t)n, 0);
    }
    if (b.pool) {
        task_pool_finish(b.pool);
        if (!splice_tasks(&b)) {
            st = bvh_oom(err);
            goto done;
        }
    }
    t->nnodes = b.nnodes;
    t->nrec = (uint32_t)n;
    if (wide && collapse(t, wide) != BSP_OK)
        st = bvh_oom(err);
done:
    free(bounds);
    free(cost);
    free(b.order);
    if (st != BSP_OK) {
        bvh_destroy(t);
        return st;
    }
    a->ops = wide ? &bvh_wide_ops : &bvh_ops;
    a->impl = t;
    return BSP_OK;
}
