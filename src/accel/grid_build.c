/*
 * grid_build.c — the uniform and recursive grids' construction, figures and
 * checker (grid.h).
 *
 * Resolution. With explicit cells per axis (bsp_build_options.grid_res)
 * those for the root grid; else, for a uniform grid, cubic cells of the
 * box's volume over D N (D the density, N the live primitives): res[k] =
 * round(extent[k] (D N / volume)^(1/3)), at least 1 — about D N cells
 * whatever the box's shape (Woo's rule in Havran's list, made exact in the
 * count; his densities are 1 and 10). A recursive grid takes Klimaszewski's
 * heterogeneous rule (hetero_res) at every level, over the grid's box and
 * the primitives it holds, as Havran's recursive grids did: with it, his
 * figures for tetra come out to the cell (docs/grid.md). A grid over
 * BSP_GRID_MAX_CELLS cells or BSP_GRID_MAX_RES per axis is coarsened,
 * keeping its proportions.
 *
 * Assignment. Each primitive's padded bounds give the range of a grid's
 * cells they overlap; where that is more than one cell, the primitive is
 * clipped to each (kd_clip_prim_bounded: its part in the cell grown by the
 * padding) and listed where the part's bounds overlap the cell — the
 * kd-trees' perfect-split assignment, so a large polygon is not listed in the
 * cells of its bounds it does not reach. With grid_assign_bounds it is listed
 * in every cell its padded bounds overlap, as Havran's grids listed them (his
 * figures are reproduced that way: docs/grid.md). (cell, primitive) pairs
 * are made in primitive order and counted into the cells' lists, so each
 * list is in increasing primitive order.
 *
 * Recursion (grid_levels > 1). The grids are made breadth first: a grid's
 * cells are assigned, then each cell listing more than grid_cell_prims
 * primitives (above the deepest level, where the rule gives its grid more
 * than one cell and that grid is expected to test fewer primitives per ray:
 * subgrid_pays) becomes a subgrid, queued with its list, and its own list
 * left empty. A grid's cells follow those of every grid made before
 * it, so the cell arrays grow in the order the grids are made.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "accel/grid.h"
#include "accel/kd_clip.h"
#include "accel/kd_tree.h"
#include "geom/vec.h"
#include "util/fnv.h"
#include "util/grow.h"

static bsp_box cell_box(const subgrid *s, const int c[3])
{
    bsp_box b;
    for (unsigned k = 0; k < 3; k++) {
        b.lo.v[k] = grid_plane(s, k, c[k]);
        b.hi.v[k] = grid_plane(s, k, c[k] + 1);
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

/* The cells of grid S whose interior the padded bounds PB overlap:
 * LO[k]..HI[k] (clamped to the grid). */
static void cell_range(const subgrid *s, const bsp_box *pb, int lo[3], int hi[3])
{
    for (unsigned k = 0; k < 3; k++) {
        lo[k] = grid_cell_of(s, k, pb->lo.v[k]);
        hi[k] = grid_cell_of(s, k, pb->hi.v[k]);
        if (hi[k] > lo[k] && !(pb->hi.v[k] > grid_plane(s, k, hi[k])))
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

/* The cells of grid S primitive P's bounds B padded by PAD_USED may belong
 * in: LO[k]..HI[k]; returns whether the padded bounds lie inside one cell
 * (then the primitive's part in it is all of it: no clipping needed). A
 * subgrid's range is clamped to its box, which a primitive may reach
 * beyond. */
static int candidate_cells(const subgrid *s, bsp_box b, double pad_used, int lo[3], int hi[3])
{
    const bsp_box pb = box_grow(b, pad_used);
    cell_range(s, &pb, lo, hi);
    for (unsigned k = 0; k < 3; k++)
        if (lo[k] != hi[k] || pb.lo.v[k] < s->box.lo.v[k] || pb.hi.v[k] > s->box.hi.v[k])
            return 0;
    return 1;
}

/* Calls ADD(ctx, cell index within S) for every cell of grid S primitive P
 * (live, bounds B) belongs in under the build's padding, in cell index
 * order; 0 when out of memory or when ADD returns 0. */
static int for_each_cell(const grid *g, const subgrid *s, const bsp_scene *scene, uint32_t p,
                         bsp_box b, kd_clip_scratch *scr, int (*add)(void *ctx, uint64_t cell),
                         void *ctx)
{
    int lo[3], hi[3], c[3];
    const int single = candidate_cells(s, b, g->pad, lo, hi) || g->by_bounds;
    for (c[2] = lo[2]; c[2] <= hi[2]; c[2]++)
        for (c[1] = lo[1]; c[1] <= hi[1]; c[1]++)
            for (c[0] = lo[0]; c[0] <= hi[0]; c[0]++) {
                bsp_box cb = cell_box(s, c);
                int r = belongs(scene, p, b, g->pad, &cb, single, scr);
                if (r < 0 || (r > 0 && !add(ctx, grid_cell_index(s, c) - s->first)))
                    return 0;
            }
    return 1;
}

/* --- the resolution --------------------------------------------------------------------- */

/* The density rule: about D N cells, cubes as far as rounding allows, over
 * BOX (N at least 1), each axis at least 1 cell, coarsened to fit
 * BSP_GRID_MAX_CELLS and BSP_GRID_MAX_RES. */
static void density_res(const bsp_box *box, double d, size_t n, int res[3])
{
    double e[3], vol = 1.0;
    for (int k = 0; k < 3; k++) {
        e[k] = box->hi.v[k] - box->lo.v[k];
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
            res[k] = r < 1.0 ? 1 : r > BSP_GRID_MAX_RES ? BSP_GRID_MAX_RES : (int)r;
            cells *= res[k];
        }
        if (cells <= (double)BSP_GRID_MAX_CELLS || !(per_unit > 0.0))
            break;
        per_unit *= 0.95 * cbrt((double)BSP_GRID_MAX_CELLS / cells);
    }
}

/* Klimaszewski's rule for a heterogeneous grid, as Havran lists it (the
 * rule of his recursive grids' "RHT +"): about D N cells, x and y first, z
 * taking what is left, so the count stays near D N also for the few
 * primitives of a subgrid, where cubes would round far from it (9 to 15
 * primitives: 8 cubes). Coarsened as density_res when over the limits. */
static void hetero_res(const bsp_box *box, double d, size_t n, int res[3])
{
    double e[3];
    for (int k = 0; k < 3; k++)
        e[k] = box->hi.v[k] - box->lo.v[k];
    const double v = d * (double)(n ? n : 1);
    double x = floor(cbrt(v * e[0] * e[0] / (e[1] * e[2])) + 0.5);
    x = x < 1.0 ? 1.0 : x;
    double y = floor(sqrt(v * e[1] / (x * e[2])) + 0.5);
    y = y < 1.0 ? 1.0 : y;
    double z = floor(v / (x * y) + 0.5);
    z = z < 1.0 ? 1.0 : z;
    if (x > BSP_GRID_MAX_RES || y > BSP_GRID_MAX_RES || z > BSP_GRID_MAX_RES ||
        x * y * z > (double)BSP_GRID_MAX_CELLS) {
        density_res(box, d, n, res);
        return;
    }
    res[0] = (int)x;
    res[1] = (int)y;
    res[2] = (int)z;
}

static double density_of(const bsp_build_options *o)
{
    return o->grid_density == 0.0 ? BSP_GRID_DEFAULT_DENSITY : o->grid_density;
}

/* The root grid's resolution over BOX for N primitives, from the options. */
static bsp_status root_resolution(const bsp_build_options *o, const bsp_box *box, size_t n,
                                  int res[3], bsp_error *err)
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
        memcpy(res, given, 3 * sizeof *res);
        return BSP_OK;
    }
    double d = density_of(o);
    if (!(d > 0.0) || !(d <= 1e6))
        return error_set(err, BSP_ERR_INVALID, NULL, 0,
                         "grid density %g: cells per primitive must lie in (0, 1e6]", d);
    if (o->grid_levels > 1)
        hetero_res(box, d, n, res);
    else
        density_res(box, d, n, res);
    return BSP_OK;
}

/* The recursion's options, checked: *LEVELS grids nested at most, a cell of
 * more than *CELL_PRIMS primitives cut. */
static bsp_status recursion_options(const bsp_build_options *o, int *levels, int *cell_prims,
                                    bsp_error *err)
{
    *levels = o->grid_levels == 0 ? 1 : o->grid_levels;
    *cell_prims = o->grid_cell_prims == 0 ? BSP_GRID_DEFAULT_CELL_PRIMS : o->grid_cell_prims;
    if (*levels < 1 || *levels > BSP_GRID_MAX_LEVELS)
        return error_set(err, BSP_ERR_INVALID, NULL, 0,
                         "grid levels %d: a grid nests 1..%d grids", o->grid_levels,
                         BSP_GRID_MAX_LEVELS);
    if (*cell_prims < 1)
        return error_set(err, BSP_ERR_INVALID, NULL, 0,
                         "grid cell primitives %d: a cell must be allowed at least 1 primitive "
                         "before a subgrid cuts it",
                         o->grid_cell_prims);
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
    free(g->subs);
    free(g->start);
    free(g->child);
    free(g->prims);
    free(g);
}

static const accel_ops grid_ops = {grid_intersect, grid_occluded, grid_free};

/* The build's state: the grid as it grows, and the lists of the grids
 * queued (grid i's primitives are queued[list_at[i] .. list_at[i] +
 * queued_count(b, i)); the lists follow each other in the order the grids were
 * made, so each ends where the next begins). */
typedef struct grid_builder {
    grid *g;
    const bsp_scene *scene;
    int levels, cell_prims;
    double density;
    size_t limit;       /* the size limit in bytes (0: none) */
    size_t subs_cap, start_cap, child_cap, prims_cap;
    uint32_t *queued;
    size_t queued_n, queued_cap;
    size_t *list_at, list_at_cap;
    pair_list pairs;
    uint32_t *count, *sorted; /* one grid's lists, by counting (scratch) */
    size_t count_cap, sorted_cap;
    kd_clip_scratch scr;
    int over_limit; /* a failure was the size limit, not memory */
} grid_builder;

/* The bytes the grid takes so far, with EXTRA_CELLS more cells and
 * EXTRA_REFS more references. */
static uint64_t grid_bytes(const grid_builder *b, uint64_t extra_cells, uint64_t extra_refs)
{
    const uint64_t cells = b->g->ncells + extra_cells;
    return (cells + 1 + b->g->nrefs + extra_refs) * sizeof(uint32_t) +
           (b->levels > 1 ? cells * sizeof(uint32_t) : 0);
}

/* The number of grid I's queued primitives. */
static size_t queued_count(const grid_builder *b, uint32_t i)
{
    return (i + 1 < b->g->nsubs ? b->list_at[i + 1] : b->queued_n) - b->list_at[i];
}

/* The grid over BOX of resolution RES at DEPTH, its cells to follow those
 * of grid G so far. */
static subgrid subgrid_over(const grid *g, const bsp_box *box, const int res[3], int depth)
{
    subgrid s;
    s.box = *box;
    memcpy(s.res, res, sizeof s.res);
    for (unsigned k = 0; k < 3; k++)
        s.cell[k] = (box->hi.v[k] - box->lo.v[k]) / res[k];
    s.depth = depth;
    s.first = g->ncells;
    return s;
}

/* Adds grid S (subgrid_over), its primitives LIST[0 .. N), to the queue. 0
 * when out of memory or over the size limit. */
static int add_subgrid(grid_builder *b, const subgrid *s, const uint32_t *list, size_t n)
{
    grid *g = b->g;
    const uint64_t cells = subgrid_cells(s);
    if (b->limit && grid_bytes(b, cells, 0) > b->limit) {
        b->over_limit = 1;
        return 0;
    }
    if (g->nsubs == UINT32_MAX || !GROW_ARRAY(g->subs, b->subs_cap, g->nsubs + 1u) ||
        !GROW_ARRAY(b->list_at, b->list_at_cap, g->nsubs + 1u) ||
        !GROW_ARRAY(g->start, b->start_cap, g->ncells + cells + 1) ||
        (b->levels > 1 && !GROW_ARRAY(g->child, b->child_cap, g->ncells + cells)) ||
        !GROW_ARRAY(b->queued, b->queued_cap, b->queued_n + n))
        return 0;
    if (b->levels > 1)
        memset(g->child + g->ncells, 0, cells * sizeof *g->child);
    g->subs[g->nsubs] = *s;
    b->list_at[g->nsubs] = b->queued_n;
    if (n)
        memcpy(b->queued + b->queued_n, list, n * sizeof *list);
    b->queued_n += n;
    g->nsubs++;
    g->ncells += cells;
    return 1;
}

/* Whether grid S, for the primitives LIST[0 .. N) of the cell it would
 * cut, is not expected to test more than twice as
 * many per ray as the cell's list: a ray crosses at least about
 * cells^(1/3) of its cells (one row), and each lists on average the
 * references over the cells (counted by the primitives' padded bounds, an
 * upper bound of the clipped lists). A lenient test, which keeps every cut
 * of Havran's recursive grids of tetra (docs/grid.md) but stops the case
 * that runs away: primitives that overlap all over a cell (shells' nested
 * spheres) would be listed again in every cell of its grid, level after
 * level, n^2 references per grid (shells, 3 levels, cells of more than 4
 * cut: 785 M references and 170 s without the test, 1.7 M and 0.35 s with
 * it). */
static int subgrid_pays(const grid *g, const subgrid *s, const bsp_scene *scene,
                        const uint32_t *list, size_t n)
{
    const double cells = (double)subgrid_cells(s), crossed = cbrt(cells);
    double refs = 0.0;
    for (size_t j = 0; j < n; j++) {
        const bsp_box pb = box_grow(bsp_scene_prim_bounds(scene, list[j]), g->pad);
        int lo[3], hi[3];
        cell_range(s, &pb, lo, hi);
        refs += (double)(hi[0] - lo[0] + 1) * (hi[1] - lo[1] + 1) * (hi[2] - lo[2] + 1);
    }
    return crossed * refs < 2.0 * (double)n * cells;
}

/* Assigns grid I's queued primitives to its cells: each cell either gets
 * its list, or (listing too many, above the deepest level) a subgrid of its
 * own, queued. 0 when out of memory or over the size limit. */
static int fill_subgrid(grid_builder *b, uint32_t i)
{
    grid *g = b->g;
    const subgrid s = g->subs[i]; /* a copy: adding subgrids moves the array */
    const uint64_t ncell = subgrid_cells(&s);
    pair_list *l = &b->pairs;
    l->n = 0;
    const size_t nqueued = queued_count(b, i);
    for (size_t j = 0; j < nqueued; j++) {
        const uint32_t p = b->queued[b->list_at[i] + j];
        l->prim = p;
        if (!for_each_cell(g, &s, b->scene, p, bsp_scene_prim_bounds(b->scene, p), &b->scr,
                           add_pair, l)) {
            b->over_limit = l->n >= l->most;
            return 0;
        }
    }
    /* counted into the cells' lists, keeping the pairs' (primitive) order */
    if (!GROW_ARRAY(b->count, b->count_cap, ncell + 1) ||
        !GROW_ARRAY(b->sorted, b->sorted_cap, l->n ? l->n : 1))
        return 0;
    memset(b->count, 0, (ncell + 1) * sizeof *b->count);
    for (size_t j = 0; j < l->n; j++)
        b->count[(l->v[j] >> 32) + 1]++;
    for (uint64_t c = 0; c < ncell; c++)
        b->count[c + 1] += b->count[c];
    for (size_t j = 0; j < l->n; j++)
        b->sorted[b->count[l->v[j] >> 32]++] = (uint32_t)l->v[j];
    /* (each count is now its list's end) */
    int c3[3];
    uint64_t c = 0;
    for (c3[2] = 0; c3[2] < s.res[2]; c3[2]++)
        for (c3[1] = 0; c3[1] < s.res[1]; c3[1]++)
            for (c3[0] = 0; c3[0] < s.res[0]; c3[0]++, c++) {
                const uint32_t lo = c ? b->count[c - 1] : 0, n = b->count[c] - lo;
                const uint64_t gc = s.first + c;
                /* cut: a crowded cell above the deepest level, where its
                 * grid pays */
                if (s.depth + 1 < b->levels && n > (uint32_t)b->cell_prims) {
                    const bsp_box cb = cell_box(&s, c3);
                    int res[3];
                    hetero_res(&cb, b->density, n, res);
                    const subgrid sub_grid = subgrid_over(g, &cb, res, s.depth + 1);
                    if (res[0] * res[1] * res[2] > 1 &&
                        subgrid_pays(g, &sub_grid, b->scene, b->sorted + lo, n)) {
                        const uint32_t sub = g->nsubs;
                        if (!add_subgrid(b, &sub_grid, b->sorted + lo, n))
                            return 0;
                        g->child[gc] = sub;
                        g->start[gc + 1] = (uint32_t)g->nrefs;
                        continue;
                    }
                }
                if (n && (g->nrefs + n > l->most || (b->limit && grid_bytes(b, 0, n) > b->limit))) {
                    b->over_limit = 1;
                    return 0;
                }
                if (n) {
                    if (!GROW_ARRAY(g->prims, b->prims_cap, g->nrefs + n))
                        return 0;
                    memcpy(g->prims + g->nrefs, b->sorted + lo, n * sizeof *g->prims);
                    g->nrefs += n;
                    g->nonempty++;
                }
                g->start[gc + 1] = (uint32_t)g->nrefs;
            }
    return 1;
}

bsp_status grid_build(bsp_accel *a, bsp_error *err)
{
    const bsp_scene *scene = a->scene;
    grid_builder b;
    memset(&b, 0, sizeof b);
    b.scene = scene;
    bsp_status st = recursion_options(&a->opts, &b.levels, &b.cell_prims, err);
    if (st != BSP_OK)
        return st;
    b.density = density_of(&a->opts);
    grid *g = b.g = calloc(1, sizeof *g);
    if (!g)
        return error_set(err, BSP_ERR_NOMEM, NULL, 0, "out of memory");
    const size_t np = bsp_scene_prim_count(scene);
    uint32_t *live = malloc((np ? np : 1) * sizeof *live);
    size_t n = 0;
    for (size_t p = 0; live && p < np; p++)
        if (scene->prims[p].shape != SHAPE_NONE)
            live[n++] = (uint32_t)p;
    g->pad = KD_PAD_REL * scene_scale(scene);
    g->by_bounds = a->opts.grid_assign_bounds != 0;
    g->levels = b.levels;
    bsp_box box = bsp_scene_bounds(scene);
    box = n == 0 || box_is_empty(box) ? (bsp_box){{{0, 0, 0}}, {{1, 1, 1}}}
                                      : box_grow(box, g->pad);
    int res[3];
    st = live ? root_resolution(&a->opts, &box, n, res, err)
              : error_set(err, BSP_ERR_NOMEM, NULL, 0, "out of memory");
    if (st != BSP_OK) {
        free(live);
        grid_free(g);
        return st;
    }

    /* the root's cells within the size limit (--max-tree-mb); then every
     * grid in the order made */
    b.limit = accel_max_bytes(&a->opts);
    const uint64_t root_cells = (uint64_t)res[0] * (uint64_t)res[1] * (uint64_t)res[2];
    if (b.limit && grid_bytes(&b, root_cells, 0) > b.limit) {
        const double need = (double)grid_bytes(&b, root_cells, 0);
        free(live);
        grid_free(g);
        return error_set(err, BSP_ERR_LIMIT, NULL, 0,
                         "grid: %llu cells need %.0f MiB, more than the limit of %.0f MiB",
                         (unsigned long long)root_cells, need / (1 << 20),
                         (double)b.limit / (1 << 20));
    }
    b.pairs.most = UINT32_MAX - 1;
    if (b.limit && (b.limit - grid_bytes(&b, root_cells, 0)) / sizeof(uint32_t) < b.pairs.most)
        b.pairs.most = (b.limit - grid_bytes(&b, root_cells, 0)) / sizeof(uint32_t);
    const subgrid root = subgrid_over(g, &box, res, 0);
    int ok = add_subgrid(&b, &root, live, n);
    free(live);
    if (ok)
        g->start[0] = 0;
    /* progress: the share of the grids made so far that are filled, never
     * going back (a grid filled may queue more), now and then */
    double shown = 0.0;
    for (uint32_t i = 0; ok && i < g->nsubs; i++) {
        ok = fill_subgrid(&b, i);
        const double done = (double)(i + 1) / g->nsubs;
        if (a->opts.progress && done >= shown + 0.01 && (i & 255) == 255) {
            shown = done;
            a->opts.progress(done, a->opts.progress_ctx);
        }
    }
    kd_clip_scratch_free(&b.scr);
    free(b.pairs.v);
    free(b.queued);
    free(b.list_at);
    free(b.count);
    free(b.sorted);
    if (ok && !g->prims)
        ok = (g->prims = malloc(sizeof *g->prims)) != NULL;
    if (!ok) {
        const size_t most = b.pairs.most;
        const int limit = b.over_limit;
        grid_free(g);
        return limit ? error_set(err, BSP_ERR_LIMIT, NULL, 0,
                                 "grid: more than %zu primitive references or more cells than "
                                 "the size limit (--max-tree-mb) or 2^32 allow",
                                 most)
                     : error_set(err, BSP_ERR_NOMEM, NULL, 0, "out of memory");
    }
    a->opts.grid_levels = b.levels; /* the defaults filled in (bsp_accel_get_options) */
    a->opts.grid_cell_prims = b.cell_prims;
    a->ops = &grid_ops;
    a->impl = g;
    return BSP_OK;
}

/* --- figures -------------------------------------------------------------------------------- */

/* Whether cell C (an index of the grid's cell arrays) is cut by a subgrid. */
static inline int subdivided(const grid *g, uint64_t c)
{
    return g->child && g->child[c] != 0;
}

void grid_stats(const grid *g, bsp_tree_stats *st)
{
    memset(st, 0, sizeof *st);
    st->interior_nodes = g->nsubs - 1u;
    st->leaves = g->ncells - st->interior_nodes;
    st->empty_leaves = st->leaves - g->nonempty;
    st->references = g->nrefs;
    st->bytes = (g->ncells + 1 + g->nrefs) * sizeof(uint32_t);
    if (g->child)
        st->bytes += g->ncells * sizeof *g->child + g->nsubs * sizeof *g->subs;
    for (int k = 0; k < 3; k++)
        st->grid_res[k] = g->subs[0].res[k];
    /* a cell's depth is its grid's (the root grid's cells: 0) */
    double depth_sum = 0.0;
    for (uint32_t i = 0; i < g->nsubs; i++) {
        const subgrid *s = &g->subs[i];
        const uint64_t cells = subgrid_cells(s);
        uint64_t cut = 0;
        for (uint64_t c = 0; c < cells; c++)
            cut += subdivided(g, s->first + c);
        if (cells > cut && s->depth > st->max_leaf_depth)
            st->max_leaf_depth = s->depth;
        depth_sum += (double)s->depth * (double)(cells - cut);
    }
    st->avg_leaf_depth = st->leaves ? depth_sum / (double)st->leaves : 0.0;
    st->expected_cost = NAN;
    st->model_cost = NAN;
    uint64_t h = FNV1A_BASIS;
    for (int k = 0; k < 3; k++)
        h = fnv1a_u32(h, (uint32_t)g->subs[0].res[k]);
    for (uint64_t c = 0; c <= g->ncells; c++)
        h = fnv1a_u32(h, g->start[c]);
    for (uint64_t i = 0; i < g->nrefs; i++)
        h = fnv1a_u32(h, g->prims[i]);
    if (g->child) { /* (a uniform grid's digest stays what it was before subgrids) */
        for (uint32_t i = 1; i < g->nsubs; i++)
            for (int k = 0; k < 3; k++)
                h = fnv1a_u32(h, (uint32_t)g->subs[i].res[k]);
        for (uint64_t c = 0; c < g->ncells; c++)
            h = fnv1a_u32(h, g->child[c]);
    }
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

/* The hierarchy's shape: the grids' cells one after another, each subgrid
 * cutting exactly one cell of a grid made before it, over that cell's box,
 * one level deeper and within the deepest level; a cut cell lists nothing. */
static bsp_status check_shape(const grid *g, bsp_error *err)
{
    if (g->nsubs == 0 || g->subs[0].first != 0 || g->subs[0].depth != 0 ||
        (g->nsubs > 1 && !g->child))
        return error_set(err, BSP_ERR_INVALID, NULL, 0, "grid: the root grid is malformed");
    uint64_t next = 0;
    for (uint32_t i = 0; i < g->nsubs; i++) {
        const subgrid *s = &g->subs[i];
        for (int k = 0; k < 3; k++)
            if (s->res[k] < 1 || s->res[k] > BSP_GRID_MAX_RES)
                return error_set(err, BSP_ERR_INVALID, NULL, 0,
                                 "grid: grid %u has %d cells on axis %d", i, s->res[k], k);
        if (s->first != next)
            return error_set(err, BSP_ERR_INVALID, NULL, 0,
                             "grid: grid %u's cells do not follow the grid before it", i);
        next += subgrid_cells(s);
    }
    if (next != g->ncells)
        return error_set(err, BSP_ERR_INVALID, NULL, 0,
                         "grid: the grids' cells do not add up to the cell arrays");
    if (!g->child)
        return BSP_OK;
    uint32_t *parent = calloc(g->nsubs, sizeof *parent);
    if (!parent)
        return error_set(err, BSP_ERR_NOMEM, NULL, 0, "out of memory");
    bsp_status st = BSP_OK;
    for (uint32_t i = 0; i < g->nsubs && st == BSP_OK; i++) {
        const subgrid *s = &g->subs[i];
        int c[3];
        for (c[2] = 0; c[2] < s->res[2] && st == BSP_OK; c[2]++)
            for (c[1] = 0; c[1] < s->res[1] && st == BSP_OK; c[1]++)
                for (c[0] = 0; c[0] < s->res[0] && st == BSP_OK; c[0]++) {
                    const uint64_t gc = grid_cell_index(s, c);
                    const uint32_t j = g->child[gc];
                    if (j == 0)
                        continue;
                    const bsp_box cb = cell_box(s, c);
                    if (j <= i || j >= g->nsubs || parent[j])
                        st = error_set(err, BSP_ERR_INVALID, NULL, 0,
                                       "grid: cell %llu names grid %u, not a grid of its own "
                                       "made after its grid",
                                       (unsigned long long)gc, j);
                    else if (g->subs[j].depth != s->depth + 1 || s->depth + 1 >= g->levels)
                        st = error_set(err, BSP_ERR_INVALID, NULL, 0,
                                       "grid: grid %u lies at depth %d under one at %d "
                                       "(at most %d levels)",
                                       j, g->subs[j].depth, s->depth, g->levels);
                    else if (memcmp(&g->subs[j].box, &cb, sizeof cb) != 0)
                        st = error_set(err, BSP_ERR_INVALID, NULL, 0,
                                       "grid: grid %u's box is not its cell's", j);
                    else if (g->start[gc] != g->start[gc + 1])
                        st = error_set(err, BSP_ERR_INVALID, NULL, 0,
                                       "grid: cell %llu is cut by grid %u and lists primitives",
                                       (unsigned long long)gc, j);
                    parent[j] = i + 1;
                }
    }
    for (uint32_t j = 1; j < g->nsubs && st == BSP_OK; j++)
        if (!parent[j])
            st = error_set(err, BSP_ERR_INVALID, NULL, 0, "grid: no cell is cut by grid %u", j);
    free(parent);
    return st;
}

/* Every elementary cell of grid S (and of the grids below it) that
 * primitive P (bounds B) belongs in under PAD_USED lists it. */
static bsp_status check_prim(const grid *g, const subgrid *s, const bsp_scene *scene, uint32_t p,
                             bsp_box b, double pad_used, kd_clip_scratch *scr, bsp_error *err)
{
    int lo[3], hi[3], c[3];
    const int single = candidate_cells(s, b, pad_used, lo, hi);
    for (c[2] = lo[2]; c[2] <= hi[2]; c[2]++)
        for (c[1] = lo[1]; c[1] <= hi[1]; c[1]++)
            for (c[0] = lo[0]; c[0] <= hi[0]; c[0]++) {
                const uint64_t i = grid_cell_index(s, c);
                if (subdivided(g, i)) {
                    bsp_status st = check_prim(g, &g->subs[g->child[i]], scene, p, b, pad_used,
                                               scr, err);
                    if (st != BSP_OK)
                        return st;
                    continue;
                }
                if (listed(g, i, p))
                    continue;
                bsp_box cb = cell_box(s, c);
                int r = belongs(scene, p, b, pad_used, &cb, single, scr);
                if (r < 0)
                    return error_set(err, BSP_ERR_NOMEM, NULL, 0, "out of memory");
                if (r > 0 && (scene->prims[p].shape != SHAPE_POLYGON ||
                              kd_polygon_meets_box(scene, p, &cb)))
                    return error_set(err, BSP_ERR_INVALID, NULL, 0,
                                     "grid: primitive %u touches cell %llu (%d, %d, %d of grid "
                                     "%u) and is not listed there",
                                     p, (unsigned long long)i, c[0], c[1], c[2],
                                     (unsigned)(s - g->subs));
            }
    return BSP_OK;
}

bsp_status grid_check(const grid *g, const bsp_scene *scene, bsp_error *err)
{
    const size_t np = bsp_scene_prim_count(scene);
    bsp_status st = check_shape(g, err);
    if (st != BSP_OK)
        return st;
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
    /* every primitive listed in every elementary cell it belongs in under a
     * fraction of the padding (the build uses the whole padding: a margin
     * far above rounding); a polygon's clipped part may reach a cell the
     * polygon does not (kd_clip.h), which the build may leave out */
    const double pad_used = KD_CHECK_PAD_FRACTION * g->pad;
    kd_clip_scratch scr;
    memset(&scr, 0, sizeof scr);
    for (uint32_t p = 0; p < np && st == BSP_OK; p++)
        if (scene->prims[p].shape != SHAPE_NONE)
            st = check_prim(g, &g->subs[0], scene, p, bsp_scene_prim_bounds(scene, p), pad_used,
                            &scr, err);
    kd_clip_scratch_free(&scr);
    return st;
}

bsp_status grid_visit(const grid *g, int max_depth,
                      int (*visit)(const bsp_cell_info *cell, void *ctx), void *ctx)
{
    /* the box, as a root whose "split" is its own low x face (a plane that
     * draws as the box's face); then, grid by grid in the order they were
     * made, each plane between its cells, spanning its box, and its
     * elementary cells, one level below the grid */
    bsp_cell_info info;
    memset(&info, 0, sizeof info);
    info.box = g->subs[0].box;
    info.split = g->subs[0].box.lo.x;
    info.refs = g->nrefs;
    if (!visit(&info, ctx) || max_depth == 0)
        return BSP_OK;
    for (uint32_t i = 0; i < g->nsubs; i++) {
        const subgrid *s = &g->subs[i];
        if (max_depth >= 0 && s->depth + 1 > max_depth)
            continue;
        memset(&info, 0, sizeof info);
        info.box = s->box;
        info.depth = s->depth + 1;
        for (unsigned k = 0; k < 3; k++)
            for (int j = 1; j < s->res[k]; j++) {
                info.axis = k;
                info.split = grid_plane(s, k, j);
                (void)visit(&info, ctx);
            }
        int c[3];
        for (c[2] = 0; c[2] < s->res[2]; c[2]++)
            for (c[1] = 0; c[1] < s->res[1]; c[1]++)
                for (c[0] = 0; c[0] < s->res[0]; c[0]++) {
                    const uint64_t gc = grid_cell_index(s, c);
                    if (subdivided(g, gc))
                        continue;
                    memset(&info, 0, sizeof info);
                    info.box = cell_box(s, c);
                    info.depth = s->depth + 1;
                    info.is_leaf = 1;
                    info.refs = g->start[gc + 1] - g->start[gc];
                    (void)visit(&info, ctx);
                }
    }
    return BSP_OK;
}
