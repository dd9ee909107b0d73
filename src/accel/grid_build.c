/*
 * grid_build.c — the uniform grid's construction, figures and checker
 * (grid.h).
 *
 * Resolution. With explicit cells per axis (bsp_build_options.grid_res)
 * those; else cubic cells of the box's volume over D N (D the density, N
 * the live primitives): res[k] = round(extent[k] (D N / volume)^(1/3)), at
 * least 1 — about D N cells whatever the box's shape (Woo's rule in
 * Havran's list, made exact in the count; his densities are 1 and 10). A
 * grid over BSP_GRID_MAX_CELLS cells or BSP_GRID_MAX_RES per axis is
 * coarsened, keeping its proportions.
 *
 * Assignment. Each live primitive's padded bounds give the range of cells
 * they overlap; where that is more than one cell, the primitive is clipped
 * to each (kd_clip_prim_bounded: its part in the cell grown by the padding)
 * and listed where the part's bounds overlap the cell — the kd-trees'
 * perfect-split assignment, so a large polygon is not listed in the cells of
 * its bounds it does not reach. With grid_assign_bounds it is listed in
 * every cell its padded bounds overlap, as Havran's grids listed them (his
 * figures are reproduced that way: docs/grid.md). (cell, primitive) pairs are made in
 * primitive order and counted into the cells' lists, so each list is in
 * increasing primitive order.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "accel/grid.h"
#include "accel/kd_clip.h"
#include "accel/kd_tree.h"
#include "geom/vec.h"
#include "util/bigmem.h"
#include "util/fnv.h"
#include "util/grow.h"

static bsp_box cell_box(const grid *g, const int c[3])
{
    bsp_box b;
    for (unsigned k = 0; k < 3; k++) {
        b.lo.v[k] = grid_plane(g, k, c[k]);
        b.hi.v[k] = grid_plane(g, k, c[k] + 1);
    }
    return b;
}

/* Whether A overlaps B's interior (as the kd-trees' assignment asks). */
static int overlaps(const bsp_box *a, const bsp_box *b)
{
    for (unsigned k = 0; k < 3; k++)
        if (!(a->lo.v[k] < b->hi.v[k] && a->hi.v[k] > b->lo.v[k]))
            return 0;
    return 1;
}

/* The cells whose interior the padded bounds PB overlap: LO[k]..HI[k]. */
static void cell_range(const grid *g, const bsp_box *pb, int lo[3], int hi[3])
{
    for (unsigned k = 0; k < 3; k++) {
        lo[k] = grid_cell_of(g, k, pb->lo.v[k]);
        hi[k] = grid_cell_of(g, k, pb->hi.v[k]);
        if (hi[k] > lo[k] && !(pb->hi.v[k] > grid_plane(g, k, hi[k])))
            hi[k]--; /* ends on the plane below its cell */
    }
}

/* Whether primitive P (live, bounds B) belongs in the cell whose box is
 * CB, under the padding PAD_USED (the build's, or the checker's fraction of
 * it): its part in CB grown by PAD_USED, padded, overlaps CB. SINGLE: the
 * padded bounds overlap no other cell, so no clipping is needed. -1 when
 * out of memory. */
static int belongs(const bsp_scene *scene, uint32_t p, bsp_box b, double pad_used,
                   const bsp_box *cb, int single, kd_clip_scratch *scr)
{
    if (single) {
        bsp_box pb = box_grow(b, pad_used);
        return overlaps(&pb, cb);
    }
    bsp_box part;
    int r = kd_clip_prim_bounded(scene, p, b, cb, pad_used, scr, &part);
    return r <= 0 ? r : overlaps(&part, cb);
}

/* The cells primitive P's bounds B padded by PAD_USED may belong in:
 * LO[k]..HI[k]; returns whether that is one cell. */
static int candidate_cells(const grid *g, bsp_box b, double pad_used, int lo[3], int hi[3])
{
    const bsp_box pb = box_grow(b, pad_used);
    cell_range(g, &pb, lo, hi);
    return lo[0] == hi[0] && lo[1] == hi[1] && lo[2] == hi[2];
}

/* Calls ADD(ctx, cell index) for every cell primitive P (live, bounds B)
 * belongs in under the build's padding, in cell index order; 0 when out of
 * memory or when ADD returns 0. */
static int for_each_cell(const grid *g, const bsp_scene *scene, uint32_t p, bsp_box b,
                         kd_clip_scratch *scr, int (*add)(void *ctx, uint64_t cell), void *ctx)
{
    int lo[3], hi[3], c[3];
    const int single = candidate_cells(g, b, g->pad, lo, hi) || g->by_bounds;
    for (c[2] = lo[2]; c[2] <= hi[2]; c[2]++)
        for (c[1] = lo[1]; c[1] <= hi[1]; c[1]++)
            for (c[0] = lo[0]; c[0] <= hi[0]; c[0]++) {
                bsp_box cb = cell_box(g, c);
                int r = belongs(scene, p, b, g->pad, &cb, single, scr);
                if (r < 0 || (r > 0 && !add(ctx, grid_cell_index(g, c))))
                    return 0;
            }
    return 1;
}

/* --- the resolution --------------------------------------------------------------------- */

static bsp_status resolution(grid *g, const bsp_build_options *o, size_t n, bsp_error *err)
{
    const int *given = o->grid_res;
    if (given[0] > 0 || given[1] > 0 || given[2] > 0) {
        for (int k = 0; k < 3; k++)
            if (given[k] < 1 || given[k] > BSP_GRID_MAX_RES)
                return error_set(err, BSP_ERR_INVALID, NULL, 0,
                                 "grid resolution %d x %d x %d: each axis needs 1..%d cells",
                                 given[0], given[1], given[2], BSP_GRID_MAX_RES);
        uint64_t cells = (uint64_t)given[0] * (uint64_t)given[1] * (uint64_t)given[2];
        if (cells > BSP_GRID_MAX_CELLS)
            return error_set(err, BSP_ERR_LIMIT, NULL, 0,
                             "grid resolution %d x %d x %d: %llu cells (the limit is %llu)",
                             given[0], given[1], given[2], (unsigned long long)cells,
                             (unsigned long long)BSP_GRID_MAX_CELLS);
        memcpy(g->res, given, sizeof g->res);
        return BSP_OK;
    }
    double d = o->grid_density == 0.0 ? BSP_GRID_DEFAULT_DENSITY : o->grid_density;
    if (!(d > 0.0) || !(d <= 1e6))
        return error_set(err, BSP_ERR_INVALID, NULL, 0,
                         "grid density %g: cells per primitive must lie in (0, 1e6]", d);
    double e[3], vol = 1.0;
    for (int k = 0; k < 3; k++) {
        e[k] = g->box.hi.v[k] - g->box.lo.v[k];
        vol *= e[k];
    }
    double want = d * (double)(n ? n : 1);
    if (want > (double)BSP_GRID_MAX_CELLS)
        want = (double)BSP_GRID_MAX_CELLS;
    double per_unit = cbrt(want / vol); /* the padding keeps every extent > 0 */
    for (;;) {
        double cells = 1.0;
        for (int k = 0; k < 3; k++) {
            double r = nearbyint(e[k] * per_unit);
            g->res[k] = r < 1.0 ? 1 : r > BSP_GRID_MAX_RES ? BSP_GRID_MAX_RES : (int)r;
            cells *= g->res[k];
        }
        if (cells <= (double)BSP_GRID_MAX_CELLS || !(per_unit > 0.0))
            break;
        per_unit *= 0.95 * cbrt((double)BSP_GRID_MAX_CELLS / cells);
    }
    return BSP_OK;
}

/* --- the build ------------------------------------------------------------------------------ */

typedef struct pair_list {
    uint64_t *v; /* cell << 32 | primitive */
    size_t n, cap;
    size_t most; /* the most pairs (references) the size limit leaves room for */
    uint32_t prim;
} pair_list;

static int add_pair(void *ctx, uint64_t cell)
{
    pair_list *l = ctx;
    if (l->n >= l->most || !GROW_ARRAY(l->v, l->cap, l->n + 1))
        return 0;
    l->v[l->n++] = cell << 32 | l->prim;
    return 1;
}

static void grid_free(void *impl)
{
    grid *g = impl;
    if (!g)
        return;
    free(g->start);
    free(g->prims);
    free(g);
}

static const accel_ops grid_ops = {grid_intersect, grid_occluded, grid_free};

bsp_status grid_build(bsp_accel *a, bsp_error *err)
{
    const bsp_scene *scene = a->scene;
    grid *g = calloc(1, sizeof *g);
    if (!g)
        return error_set(err, BSP_ERR_NOMEM, NULL, 0, "out of memory");
    const size_t np = bsp_scene_prim_count(scene);
    size_t n = 0;
    for (size_t p = 0; p < np; p++)
        n += scene->prims[p].shape != SHAPE_NONE;
    g->pad = KD_PAD_REL * scene_scale(scene);
    g->by_bounds = a->opts.grid_assign_bounds != 0;
    bsp_box b = bsp_scene_bounds(scene);
    g->box = n == 0 || box_is_empty(b) ? (bsp_box){{{0, 0, 0}}, {{1, 1, 1}}} : box_grow(b, g->pad);
    bsp_status st = resolution(g, &a->opts, n, err);
    if (st != BSP_OK) {
        grid_free(g);
        return st;
    }
    g->ncells = (uint64_t)g->res[0] * (uint64_t)g->res[1] * (uint64_t)g->res[2];
    for (unsigned k = 0; k < 3; k++)
        g->cell[k] = (g->box.hi.v[k] - g->box.lo.v[k]) / g->res[k];

    /* the cells' offsets and the lists within the size limit (--max-tree-mb) */
    const size_t limit = accel_max_bytes(&a->opts);
    const uint64_t cell_bytes = (g->ncells + 1) * sizeof(uint32_t);
    if (limit && cell_bytes > limit) {
        const unsigned long long cells = (unsigned long long)g->ncells;
        grid_free(g);
        return error_set(err, BSP_ERR_LIMIT, NULL, 0,
                         "grid: %llu cells need %.0f MiB, more than the limit of %.0f MiB", cells,
                         (double)cell_bytes / (1 << 20), (double)limit / (1 << 20));
    }
    size_t most = UINT32_MAX - 1;
    if (limit && (limit - cell_bytes) / sizeof(uint32_t) < most)
        most = (limit - cell_bytes) / sizeof(uint32_t);
    pair_list l = {NULL, 0, 0, most, 0};
    kd_clip_scratch scr;
    memset(&scr, 0, sizeof scr);
    int ok = 1;
    for (uint32_t p = 0; p < np && ok; p++) {
        if (scene->prims[p].shape == SHAPE_NONE)
            continue;
        l.prim = p;
        ok = for_each_cell(g, scene, p, bsp_scene_prim_bounds(scene, p), &scr, add_pair, &l);
    }
    kd_clip_scratch_free(&scr);
    g->start = ok ? calloc(g->ncells + 1, sizeof *g->start) : NULL;
    g->prims = ok ? bigmem_malloc((l.n ? l.n : 1) * sizeof *g->prims) : NULL;
    if (!g->start || !g->prims) {
        free(l.v);
        grid_free(g);
        return l.n >= most ? error_set(err, BSP_ERR_LIMIT, NULL, 0,
                                       "grid: more than %zu primitive references (the size "
                                       "limit, --max-tree-mb, or 2^32)",
                                       most)
                           : error_set(err, BSP_ERR_NOMEM, NULL, 0, "out of memory");
    }
    /* counted into the cells' lists, keeping the pairs' (primitive) order */
    for (size_t i = 0; i < l.n; i++)
        g->start[(l.v[i] >> 32) + 1]++;
    for (uint64_t c = 0; c < g->ncells; c++) {
        g->nonempty += g->start[c + 1] != 0;
        g->start[c + 1] += g->start[c];
    }
    for (size_t i = 0; i < l.n; i++)
        g->prims[g->start[l.v[i] >> 32]++] = (uint32_t)l.v[i];
    for (uint64_t c = g->ncells; c > 0; c--) /* each start moved to its list's end */
        g->start[c] = g->start[c - 1];
    g->start[0] = 0;
    g->nrefs = l.n;
    free(l.v);
    a->ops = &grid_ops;
    a->impl = g;
    return BSP_OK;
}

/* --- figures -------------------------------------------------------------------------------- */

void grid_stats(const grid *g, bsp_tree_stats *st)
{
    memset(st, 0, sizeof *st);
    st->leaves = g->ncells;
    st->empty_leaves = g->ncells - g->nonempty;
    st->references = g->nrefs;
    st->bytes = (g->ncells + 1 + g->nrefs) * sizeof(uint32_t);
    for (int k = 0; k < 3; k++)
        st->grid_res[k] = g->res[k];
    st->expected_cost = NAN;
    st->model_cost = NAN;
    uint64_t h = FNV1A_BASIS;
    for (int k = 0; k < 3; k++)
        h = fnv1a_u32(h, (uint32_t)g->res[k]);
    for (uint64_t c = 0; c <= g->ncells; c++)
        h = fnv1a_u32(h, g->start[c]);
    for (uint64_t i = 0; i < g->nrefs; i++)
        h = fnv1a_u32(h, g->prims[i]);
    st->digest = h;
}

/* --- the checker ---------------------------------------------------------------------------- */

/* Whether cell C's list (sorted) holds primitive P. */
static int listed(const grid *g, uint64_t c, uint32_t p)
{
    const uint32_t *lo = g->prims + g->start[c], *end = g->prims + g->start[c + 1], *hi = end;
    while (lo < hi) {
        const uint32_t *mid = lo + (hi - lo) / 2;
        if (*mid < p)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo < end && *lo == p;
}

bsp_status grid_check(const grid *g, const bsp_scene *scene, bsp_error *err)
{
    const size_t np = bsp_scene_prim_count(scene);
    if (g->start[0] != 0 || g->start[g->ncells] != g->nrefs)
        return error_set(err, BSP_ERR_INVALID, NULL, 0, "grid: the lists' offsets do not add up");
    for (uint64_t c = 0; c < g->ncells; c++) {
        if (g->start[c] > g->start[c + 1])
            return error_set(err, BSP_ERR_INVALID, NULL, 0,
                             "grid: cell %llu's list ends before it starts",
                             (unsigned long long)c);
        for (uint32_t i = g->start[c]; i < g->start[c + 1]; i++) {
            uint32_t p = g->prims[i];
            if (p >= np || scene->prims[p].shape == SHAPE_NONE)
                return error_set(err, BSP_ERR_INVALID, NULL, 0,
                                 "grid: cell %llu lists %u, no live primitive",
                                 (unsigned long long)c, p);
            if (i > g->start[c] && g->prims[i - 1] >= p)
                return error_set(err, BSP_ERR_INVALID, NULL, 0,
                                 "grid: cell %llu's list is not in increasing order",
                                 (unsigned long long)c);
        }
    }
    /* every primitive listed in every cell it belongs in under a fraction of
     * the padding (the build uses the whole padding: a margin far above
     * rounding); a polygon's clipped part may reach a cell the polygon does
     * not (kd_clip.h), which the build may leave out */
    const double pad_used = KD_CHECK_PAD_FRACTION * g->pad;
    kd_clip_scratch scr;
    memset(&scr, 0, sizeof scr);
    bsp_status st = BSP_OK;
    for (uint32_t p = 0; p < np && st == BSP_OK; p++) {
        if (scene->prims[p].shape == SHAPE_NONE)
            continue;
        const bsp_box b = bsp_scene_prim_bounds(scene, p);
        int lo[3], hi[3], c[3];
        const int single = candidate_cells(g, b, pad_used, lo, hi);
        for (c[2] = lo[2]; c[2] <= hi[2] && st == BSP_OK; c[2]++)
            for (c[1] = lo[1]; c[1] <= hi[1] && st == BSP_OK; c[1]++)
                for (c[0] = lo[0]; c[0] <= hi[0] && st == BSP_OK; c[0]++) {
                    const uint64_t i = grid_cell_index(g, c);
                    if (listed(g, i, p))
                        continue;
                    bsp_box cb = cell_box(g, c);
                    int r = belongs(scene, p, b, pad_used, &cb, single, &scr);
                    if (r < 0)
                        st = error_set(err, BSP_ERR_NOMEM, NULL, 0, "out of memory");
                    else if (r > 0 && (scene->prims[p].shape != SHAPE_POLYGON ||
                                       kd_polygon_meets_box(scene, p, &cb)))
                        st = error_set(err, BSP_ERR_INVALID, NULL, 0,
                                       "grid: primitive %u touches cell %llu (%d, %d, %d) and is "
                                       "not listed there",
                                       p, (unsigned long long)i, c[0], c[1], c[2]);
                }
    }
    kd_clip_scratch_free(&scr);
    return st;
}

bsp_status grid_visit(const grid *g, int max_depth,
                      int (*visit)(const bsp_cell_info *cell, void *ctx), void *ctx)
{
    /* the box, as a root whose "split" is its own low x face (a plane that
     * draws as the box's face); then each plane between cells, spanning the
     * box; then the cells */
    bsp_cell_info info;
    memset(&info, 0, sizeof info);
    info.box = g->box;
    info.split = g->box.lo.x;
    info.refs = g->nrefs;
    if (!visit(&info, ctx) || max_depth == 0)
        return BSP_OK;
    info.depth = 1;
    for (unsigned k = 0; k < 3; k++)
        for (int i = 1; i < g->res[k]; i++) {
            info.axis = k;
            info.split = grid_plane(g, k, i);
            (void)visit(&info, ctx);
        }
    int c[3];
    for (c[2] = 0; c[2] < g->res[2]; c[2]++)
        for (c[1] = 0; c[1] < g->res[1]; c[1]++)
            for (c[0] = 0; c[0] < g->res[0]; c[0]++) {
                uint64_t i = grid_cell_index(g, c);
                memset(&info, 0, sizeof info);
                info.box = cell_box(g, c);
                info.depth = 1;
                info.is_leaf = 1;
                info.refs = g->start[i + 1] - g->start[i];
                (void)visit(&info, ctx);
            }
    return BSP_OK;
}
