/*
 * kd_tree.c — storage of the compact kd-tree, the accel front end for all
 * kd-tree rules, the tree statistics walk and the invariant checker.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "accel/kd_clip.h"
#include "accel/kd_cost.h"
#include "accel/kd_local.h"
#include "accel/kd_walk.h"
#include "accel/kd_tree.h"
#include "accel/kd_view.h"
#include "geom/vec.h"
#include "util/bigmem.h"
#include "util/sort.h"
#include "util/fnv.h"

int kd_tree_init(kd_tree *t, const bsp_scene *scene, int max_depth, int max_leaf_prims)
{
    memset(t, 0, sizeof *t);
    t->max_depth = max_depth;
    t->max_leaf_prims = max_leaf_prims;
    t->pad = KD_PAD_REL * scene_scale(scene);
    bsp_box b = bsp_scene_bounds(scene);
    t->box = box_is_empty(b) ? b : box_grow(b, t->pad);
    t->cap_nodes = 1024;
    t->nodes = malloc(t->cap_nodes * sizeof *t->nodes);
    if (!t->nodes)
        return 0;
    t->budget_cut = t->budget_probe_cut = t->budget_scout_cut = -INFINITY;
    t->nnodes = 1; /* the root */
    t->nodes[0].u.first = 0;
    t->nodes[0].bits = KD_LEAF_TAG; /* an empty leaf until built */
    return 1;
}

void kd_tree_reset(kd_tree *t)
{
    t->nnodes = 1;
    t->nprims = 0;
    t->over_limit = 0;
    t->nodes[0].u.first = 0;
    t->nodes[0].bits = KD_LEAF_TAG;
}

int kd_trace_build(kd_tree *t, const bsp_scene *scene)
{
    return kd_local_build(t, scene) && kd_walk_build(t);
}

void kd_tree_free(kd_tree *t)
{
    if (!t)
        return;
    free(t->nodes);
    free(t->prims);
    free(t->saving);
    free(t->lref);
    free(t->loc);
    free(t->local_of);
    free(t->walk);
    memset(t, 0, sizeof *t);
}

int kd_tree_fits(kd_tree *t, size_t nodes, size_t prims)
{
    if (nodes > KD_MAX_NODES || prims > UINT32_MAX ||
        (t->max_bytes && nodes * sizeof(kd_node) + prims * sizeof(uint32_t) > t->max_bytes)) {
        t->over_limit = 1;
        return 0;
    }
    return 1;
}

bsp_status kd_build_failed(const kd_tree *t, bsp_error *err)
{
    if (!t->over_limit)
        return error_set(err, BSP_ERR_NOMEM, NULL, 0, "out of memory while building the kd-tree");
    /* an octree's depth is given in octree levels, three kd levels each */
    return error_set(
        err, BSP_ERR_LIMIT, NULL, 0,
        "the %s outgrew its size limit (%.1f MiB, and at most %u kd nodes) at %u kd nodes and "
        "%zu references: lower the maximum depth (now %d; --max-depth), raise the leaf size "
        "(now %d; --leaf-size) or raise the limit (--max-tree-mb)",
        t->octree ? "octree" : "kd-tree", (double)t->max_bytes / (1 << 20),
        (unsigned)KD_MAX_NODES, (unsigned)t->nnodes, t->nprims,
        t->octree ? t->max_depth / 3 : t->max_depth, t->max_leaf_prims);
}

int kd_reserve_nodes(kd_tree *t, size_t nodes)
{
    if (!kd_tree_fits(t, nodes, t->nprims))
        return 0;
    if (nodes <= t->cap_nodes)
        return 1;
    size_t ncap = t->cap_nodes ? t->cap_nodes : 1024;
    while (ncap < nodes)
        ncap *= 2;
    if (ncap > KD_MAX_NODES)
        ncap = KD_MAX_NODES;
    kd_node *nn = bigmem_realloc(t->nodes, t->cap_nodes * sizeof *nn, ncap * sizeof *nn);
    if (!nn)
        return 0;
    t->nodes = nn;
    if (t->saving) {
        double *ns = bigmem_realloc(t->saving, t->cap_nodes * sizeof *ns, ncap * sizeof *ns);
        if (!ns)
            return 0; /* cap_nodes unchanged: the savings stay the smaller array */
        t->saving = ns;
    }
    t->cap_nodes = (uint32_t)ncap;
    return 1;
}

int kd_tree_record_savings(kd_tree *t)
{
    free(t->saving);
    t->saving = calloc(t->cap_nodes ? t->cap_nodes : 1, sizeof *t->saving);
    return t->saving != NULL;
}

uint32_t kd_alloc_pair(kd_tree *t)
{
    if (!kd_reserve_nodes(t, (size_t)t->nnodes + 2))
        return UINT32_MAX;
    uint32_t i = t->nnodes;
    t->nnodes += 2;
    return i;
}

int kd_reserve_prims(kd_tree *t, size_t more)
{
    if (!kd_tree_fits(t, t->nnodes, t->nprims + more))
        return 0;
    if (t->nprims + more > t->cap_prims) {
        size_t ncap = t->cap_prims ? t->cap_prims : 1024;
        while (ncap < t->nprims + more)
            ncap *= 2;
        uint32_t *np = bigmem_realloc(t->prims, t->cap_prims * sizeof *np, ncap * sizeof *np);
        if (!np)
            return 0;
        t->prims = np;
        t->cap_prims = ncap;
    }
    return 1;
}

DEFINE_SORT(sort_u32, uint32_t, 32)

void kd_sort_prims(uint32_t *a, size_t n)
{
    sort_u32(a, n);
}

size_t kd_sort_unique_prims(uint32_t *a, size_t n)
{
    kd_sort_prims(a, n);
    size_t c = 0;
    for (size_t i = 0; i < n; i++)
        if (c == 0 || a[i] != a[c - 1])
            a[c++] = a[i];
    return c;
}

int kd_make_leaf(kd_tree *t, uint32_t i, const uint32_t *prims, size_t n)
{
    if (n >= KD_MAX_LEAF_COUNT || !kd_reserve_prims(t, n))
        return 0;
    if (n > 0) /* prims may be NULL for an empty leaf */
        memcpy(t->prims + t->nprims, prims, n * sizeof *prims);
    t->nodes[i].u.first = (uint32_t)t->nprims;
    t->nodes[i].bits = kd_pack((uint32_t)n, KD_LEAF_TAG);
    t->nprims += n;
    return 1;
}

void kd_make_interior(kd_tree *t, uint32_t i, unsigned axis, float split, uint32_t child)
{
    t->nodes[i].u.split = split;
    t->nodes[i].bits = kd_pack(child, axis);
}

bsp_box kd_prim_box(const kd_tree *t, const bsp_scene *scene, uint32_t prim)
{
    return box_grow(bsp_scene_prim_bounds(scene, prim), t->pad);
}

/* --- statistics ------------------------------------------------------------------- */

static double box_area(bsp_box b)
{
    double dx = b.hi.x - b.lo.x, dy = b.hi.y - b.lo.y, dz = b.hi.z - b.lo.z;
    return 2.0 * (dx * dy + dy * dz + dz * dx);
}

typedef struct stats_walk {
    const kd_tree *t;
    bsp_tree_stats *st;
    const bsp_scene *scene;
    const bsp_sah_costs *costs;
    double depth_sum;
    double cost;  /* sum of area-weighted costs, divided by the root area at the end */
    double model; /* the same under COSTS */
} stats_walk;

static void stats_node(stats_walk *w, uint32_t i, bsp_box box, int depth)
{
    const kd_node *n = &w->t->nodes[i];
    /* an octree's figures count its own nodes and levels: three kd levels each */
    int group = w->t->octree ? 3 : 1;
    if (kd_is_leaf(n)) {
        uint32_t c = kd_count(n);
        w->st->leaves++;
        w->st->empty_leaves += c == 0;
        w->st->references += c;
        w->depth_sum += depth / group;
        if (depth / group > w->st->max_leaf_depth)
            w->st->max_leaf_depth = depth / group;
        double area = box_area(box), tsum = 0.0;
        const uint32_t *list = w->t->prims + n->u.first;
        for (uint32_t j = 0; j < c; j++)
            tsum += kd_prim_cost(w->scene, list[j], w->costs);
        w->cost += area * (double)c;
        w->model += area * tsum;
        return;
    }
    w->st->interior_nodes += depth % group == 0;
    double area = box_area(box);
    w->cost += area;
    w->model += area * w->costs->traversal;
    unsigned axis = kd_axis(n);
    bsp_box l = box, r = box;
    l.hi.v[axis] = r.lo.v[axis] = (double)n->u.split;
    stats_node(w, kd_child(n), l, depth + 1);
    stats_node(w, kd_child(n) + 1, r, depth + 1);
}

/* The tree's digest (bsp_tree_stats.digest): every node's two words in
 * array order, then the leaf lists. */
static uint64_t tree_digest(const kd_tree *t)
{
    uint64_t h = FNV1A_BASIS;
    for (uint32_t i = 0; i < t->nnodes; i++) {
        uint32_t word;
        memcpy(&word, &t->nodes[i].u, sizeof word); /* the split's bits or the first entry */
        h = fnv1a_u32(fnv1a_u32(h, t->nodes[i].bits), word);
    }
    for (size_t i = 0; i < t->nprims; i++)
        h = fnv1a_u32(h, t->prims[i]);
    return h;
}

void kd_tree_stats(const kd_tree *t, const bsp_scene *scene, const bsp_sah_costs *costs,
                   bsp_tree_stats *st)
{
    memset(st, 0, sizeof *st);
    stats_walk w = {t, st, scene, costs, 0.0, 0.0, 0.0};
    stats_node(&w, 0, t->box, 0);
    st->avg_leaf_depth = st->leaves ? w.depth_sum / (double)st->leaves : 0.0;
    st->bytes = (uint64_t)t->nnodes * sizeof(kd_node) + (uint64_t)t->nprims * sizeof(uint32_t);
    st->trace_bytes = (t->loc ? (uint64_t)t->nloc * sizeof(kd_local) + (uint64_t)t->nprims * sizeof(uint32_t) : 0) +
                      (t->local_of ? (uint64_t)t->nlocal_of * sizeof(uint32_t) : 0) +
                      (uint64_t)t->nwalk * sizeof(kd_node);
    /* no primitive: an empty root box, nothing to test (its "area" would be
     * inf - -inf, and the costs nan) */
    double root = box_is_empty(t->box) ? 0.0 : box_area(t->box);
    st->expected_cost = root > 0 ? w.cost / root : 0.0;
    st->model_cost = root > 0 ? w.model / root / costs->traversal : 0.0;
    st->budget_cut = t->budget_cut > 0.0 ? t->budget_cut / costs->traversal : 0.0;
    st->budget_rebuilt = t->budget_rebuilt;
    st->digest = tree_digest(t);
}

/* --- invariant checker -------------------------------------------------------------- */

typedef struct check_walk {
    const kd_tree *t;
    const bsp_scene *scene;
    bsp_box *bounds;  /* per primitive: bsp_scene_prim_bounds, made once (a polygon's
                         took 5 % of gears' exactness test when made at every clip) */
    bsp_box *pbox;    /* padded bounds per primitive */
    uint32_t *lists;  /* scratch: primitive lists of the nodes on the path */
    size_t cap, top;
    char *seen;       /* per primitive: listed in the current leaf */
    kd_clip_scratch clip;
    bsp_error *err;
    bsp_status st;
} check_walk;

/* Open overlap: padded bounds that merely touch a cell need not be listed
 * there (see the invariant in kd_tree.h). */
static int boxes_overlap(bsp_box a, bsp_box b)
{
    for (int k = 0; k < 3; k++)
        if (!(a.lo.v[k] < b.hi.v[k] && b.lo.v[k] < a.hi.v[k]))
            return 0;
    return 1;
}

/* Whether primitive P must be listed in the leaves of CELL where it is: its
 * bounds clipped to CELL (kd_clip.h; KD_CHECK_PAD_FRACTION of the padding)
 * overlap CELL. Builders that clip (sah) list a primitive only where its
 * clipped bounds reach, so unclipped bounds would reject their trees. */
static int clipped_overlap(check_walk *w, uint32_t p, bsp_box cell)
{
    bsp_box cl;
    int r = kd_clip_prim_bounded(w->scene, p, w->bounds[p], &cell,
                                 w->t->pad * KD_CHECK_PAD_FRACTION, &w->clip, &cl);
    if (r < 0 && w->st == BSP_OK)
        w->st = error_set(w->err, BSP_ERR_NOMEM, NULL, 0, "out of memory");
    return r != 0 && (r < 0 || boxes_overlap(cl, cell));
}

/* Whether P may be missing from the leaf of CELL, which clipped_overlap
 * asked it to be in: a polygon whose hits do not come within the checker's
 * padding of CELL (clipping overstates concave and self-crossing polygons;
 * kd_polygon_meets_box). */
static int unlisted_ok(const check_walk *w, uint32_t p, bsp_box cell)
{
    if (w->scene->prims[p].shape != SHAPE_POLYGON)
        return 0;
    bsp_box g = box_grow(cell, w->t->pad * KD_CHECK_PAD_FRACTION);
    return !kd_polygon_meets_box(w->scene, p, &g);
}

static int check_fail(check_walk *w, const char *fmt, uint32_t a, uint32_t b)
{
    if (w->st == BSP_OK)
        w->st = error_set(w->err, BSP_ERR_INVALID, NULL, 0, fmt, a, b);
    return 0;
}

/* LIST..LIST+N: the primitives whose padded bounds overlap BOX. */
static int check_node(check_walk *w, uint32_t i, bsp_box box, size_t list, size_t n, int depth)
{
    const kd_tree *t = w->t;
    if (depth > t->max_depth)
        return check_fail(w, "kd-tree: node %u is deeper than the limit %u", i,
                          (uint32_t)t->max_depth);
    const kd_node *nd = &t->nodes[i];
    if (kd_is_leaf(nd)) {
        uint32_t first = nd->u.first, c = kd_count(nd);
        if ((size_t)first + c > t->nprims)
            return check_fail(w, "kd-tree: leaf %u lists entries past the end (%u)", i, first);
        for (uint32_t k = 0; k < c; k++) {
            uint32_t p = t->prims[first + k];
            if (p >= bsp_scene_prim_count(w->scene))
                return check_fail(w, "kd-tree: leaf %u lists primitive %u, out of range", i, p);
            w->seen[p] = 1;
        }
        int ok = 1;
        for (size_t k = 0; k < n && ok; k++) {
            uint32_t p = w->lists[list + k];
            if (!w->seen[p] && !unlisted_ok(w, p, box))
                ok = check_fail(w, "kd-tree: primitive %u overlaps leaf %u but is not listed", p,
                                i);
        }
        for (uint32_t k = 0; k < c; k++)
            w->seen[t->prims[first + k]] = 0;
        return ok;
    }
    uint32_t child = kd_child(nd);
    if (child <= i || child + 1 >= t->nnodes)
        return check_fail(w, "kd-tree: node %u has child index %u out of range", i, child);
    unsigned axis = kd_axis(nd);
    double s = (double)nd->u.split;
    if (!(s >= box.lo.v[axis] && s <= box.hi.v[axis]))
        return check_fail(w, "kd-tree: node %u splits outside its box on axis %u", i, axis);
    bsp_box lb = box, rb = box;
    lb.hi.v[axis] = rb.lo.v[axis] = s;
    for (int side = 0; side < 2; side++) {
        bsp_box cb = side ? rb : lb;
        size_t base = w->top;
        if (base + n > w->cap) {
            size_t ncap = w->cap * 2 > base + n ? w->cap * 2 : base + n;
            uint32_t *nl = realloc(w->lists, ncap * sizeof *nl);
            if (!nl) {
                w->st = error_set(w->err, BSP_ERR_NOMEM, NULL, 0, "out of memory");
                return 0;
            }
            w->lists = nl;
            w->cap = ncap;
        }
        size_t m = 0;
        for (size_t k = 0; k < n; k++) {
            uint32_t p = w->lists[list + k];
            if (boxes_overlap(w->pbox[p], cb) && clipped_overlap(w, p, cb))
                w->lists[base + m++] = p;
        }
        w->top = base + m;
        int ok = check_node(w, child + (uint32_t)side, cb, base, m, depth + 1);
        w->top = base;
        if (!ok)
            return 0;
    }
    return 1;
}

bsp_status kd_tree_check(const kd_tree *t, const bsp_scene *scene, bsp_error *err)
{
    size_t np = bsp_scene_prim_count(scene);
    check_walk w = {t, scene, NULL, NULL, NULL, 0, 0, NULL, {{NULL, NULL}, {0, 0}}, err, BSP_OK};
    w.bounds = malloc((np ? np : 1) * sizeof *w.bounds);
    w.pbox = malloc((np ? np : 1) * sizeof *w.pbox);
    w.seen = calloc(np ? np : 1, 1);
    w.cap = 2 * np + 16;
    w.lists = malloc(w.cap * sizeof *w.lists);
    if (!w.bounds || !w.pbox || !w.seen || !w.lists) {
        free(w.bounds);
        free(w.pbox);
        free(w.seen);
        free(w.lists);
        return error_set(err, BSP_ERR_NOMEM, NULL, 0, "out of memory");
    }
    size_t n = 0;
    for (uint32_t p = 0; p < np; p++) {
        if (bsp_scene_prim_kind(scene, p) == BSP_PRIM_DROPPED)
            continue;
        w.bounds[p] = bsp_scene_prim_bounds(scene, p);
        w.pbox[p] = box_grow(w.bounds[p], t->pad); /* kd_prim_box */
        w.lists[n++] = p;
    }
    w.top = n;
    if (t->nnodes == 0)
        error_set(err, BSP_ERR_INVALID, NULL, 0, "kd-tree: no nodes");
    else if (n > 0 && box_is_empty(t->box))
        w.st = error_set(err, BSP_ERR_INVALID, NULL, 0, "kd-tree: empty root box");
    else
        check_node(&w, 0, t->box, 0, n, 0);
    if (w.st == BSP_OK)
        w.st = kd_local_check(t, scene, err);
    if (w.st == BSP_OK)
        w.st = kd_walk_check(t, err);
    kd_clip_scratch_free(&w.clip);
    free(w.bounds);
    free(w.pbox);
    free(w.seen);
    free(w.lists);
    return w.st;
}

/* --- cell walk (bsp_accel_visit_cells) ------------------------------------------------ */

typedef struct visit_walk {
    const kd_tree *t;
    const uint64_t *refs; /* per node: references in its subtree's leaves */
    int max_depth;
    int (*visit)(const bsp_cell_info *cell, void *ctx);
    void *ctx;
} visit_walk;

static void visit_node(const visit_walk *w, uint32_t i, bsp_box box, int depth)
{
    const kd_node *n = &w->t->nodes[i];
    bsp_cell_info c;
    c.box = box;
    c.depth = depth;
    c.is_leaf = kd_is_leaf(n);
    c.axis = c.is_leaf ? 0 : kd_axis(n);
    c.split = c.is_leaf ? 0.0 : (double)n->u.split;
    c.refs = w->refs[i];
    int descend = w->visit(&c, w->ctx);
    if (c.is_leaf || !descend || (w->max_depth >= 0 && depth >= w->max_depth))
        return;
    bsp_box l = box, r = box;
    l.hi.v[c.axis] = r.lo.v[c.axis] = c.split;
    visit_node(w, kd_child(n), l, depth + 1);
    visit_node(w, kd_child(n) + 1, r, depth + 1);
}

bsp_status kd_tree_visit(const kd_tree *t, int max_depth,
                         int (*visit)(const bsp_cell_info *cell, void *ctx), void *ctx,
                         bsp_error *err)
{
    uint64_t *refs = malloc((size_t)t->nnodes * sizeof *refs);
    if (!refs)
        return error_set(err, BSP_ERR_NOMEM, NULL, 0, "out of memory");
    /* children always follow their parent in the array: one backward pass */
    for (uint32_t i = t->nnodes; i-- > 0;) {
        const kd_node *n = &t->nodes[i];
        refs[i] = kd_is_leaf(n) ? kd_count(n) : refs[kd_child(n)] + refs[kd_child(n) + 1];
    }
    visit_walk w = {t, refs, max_depth, visit, ctx};
    visit_node(&w, 0, t->box, 0);
    free(refs);
    return BSP_OK;
}

/* --- accel front end ------------------------------------------------------------------ */

static void kd_destroy(void *impl)
{
    kd_tree_free(impl);
    free(impl);
}

static const accel_ops kd_ops = {kd_intersect, kd_occluded, kd_destroy};

bsp_status kd_accel_build(bsp_accel *a, bsp_error *err)
{
    bsp_build_options *o = &a->opts;
    int sah_family = o->kind == BSP_ACCEL_SAH || o->kind == BSP_ACCEL_SAH_PER ||
                     o->kind == BSP_ACCEL_SAH_PAR || o->kind == BSP_ACCEL_SAH_MIXED;
    int octree = o->kind == BSP_ACCEL_OCTREE;
    if (sah_family)
        kd_sah_default_limits(o, a->scene);
    if (o->max_depth == 0)
        o->max_depth = octree ? kd_octree_default_depth(bsp_scene_prim_count(a->scene)) : 18;
    if (o->max_leaf_prims == 0)
        o->max_leaf_prims = octree ? 1 : 2;
    int depth_limit = octree ? BSP_OCTREE_MAX_DEPTH : BSP_KD_MAX_DEPTH_LIMIT;
    if (o->max_depth < 1 || o->max_depth > depth_limit)
        return error_set(err, BSP_ERR_INVALID, NULL, 0, "%s depth %d is outside 1..%d",
                         octree ? "octree" : "kd-tree", o->max_depth, depth_limit);
    if (o->max_leaf_prims < 1)
        return error_set(err, BSP_ERR_INVALID, NULL, 0,
                         "kd-tree leaf size %d must be at least 1", o->max_leaf_prims);
    if (octree && o->octree_split != BSP_OCTREE_CENTRE && o->octree_split != BSP_OCTREE_COST)
        return error_set(err, BSP_ERR_INVALID, NULL, 0, "octree split %d is not one of %d, %d",
                         (int)o->octree_split, BSP_OCTREE_CENTRE, BSP_OCTREE_COST);
    kd_tree *t = malloc(sizeof *t);
    /* an octree level is three kd levels */
    if (!t || !kd_tree_init(t, a->scene, octree ? 3 * o->max_depth : o->max_depth,
                            o->max_leaf_prims)) {
        if (t)
            kd_tree_free(t);
        free(t);
        return error_set(err, BSP_ERR_NOMEM, NULL, 0, "out of memory");
    }
    t->max_bytes = accel_max_bytes(o);
    bsp_status st;
    switch (o->kind) {
    case BSP_ACCEL_KAPLAN:
        st = kd_build_median(t, a->scene, err);
        break;
    case BSP_ACCEL_OCTREE:
        st = kd_build_octree(t, a->scene, o->octree_split, err);
        break;
    case BSP_ACCEL_SAH:
        st = kd_build_sah(t, a->scene, o, err);
        break;
    case BSP_ACCEL_SAH_PER:
    case BSP_ACCEL_SAH_PAR:
    case BSP_ACCEL_SAH_MIXED:
        st = kd_build_view(t, a->scene, o, err);
        break;
    default:
        st = error_set(err, BSP_ERR_INVALID, NULL, 0, "not a kd-tree rule");
        break;
    }
    if (st != BSP_OK) {
        kd_destroy(t);
        return st;
    }
    return kd_accel_adopt(a, t, err);
}

bsp_status kd_accel_adopt(bsp_accel *a, kd_tree *t, bsp_error *err)
{
    t->box_empty = box_is_empty(t->box);
    if (!kd_trace_build(t, a->scene)) {
        kd_destroy(t);
        return error_set(err, BSP_ERR_NOMEM, NULL, 0, "out of memory");
    }
    a->ops = &kd_ops;
    a->impl = t;
    return BSP_OK;
}
