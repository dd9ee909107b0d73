/*
 * grid.h — the uniform grid (`--accel grid`): the scene's box cut into
 * res[0] x res[1] x res[2] equal cells, each with the list of the
 * primitives that touch it, traversed cell by cell along the ray by a 3D-DDA
 * (Amanatides & Woo 1987). It is the classic baseline of Havran's grid
 * statistics (../shared/reference/havran_stats_grids.txt) and a second
 * structure, built by other code, that must answer as the naive method does.
 *
 * Recursive grid (bsp_build_options.grid_levels > 1; Jevans & Wyvill 1989):
 * a cell that lists more than grid_cell_prims primitives, above the deepest
 * level, is cut by a grid of its own (a subgrid over the cell's box, its
 * resolution by the same density rule over the cell's primitives), and so
 * on down; the walk descends into a subdivided cell's grid over the ray's
 * segment in that cell. Only the cells no grid cuts (elementary cells) hold
 * lists.
 *
 * Assignment invariant (the kd-trees', kd_tree.h): a primitive is listed in
 * every elementary cell that its padded bounds, clipped to the cell grown by
 * the padding (kd_clip.h), overlap (or, with grid_assign_bounds, every cell
 * its padded bounds overlap: a superset); so it is listed in every
 * elementary cell whose closed box it touches, and the traversal, which
 * stops once the closest hit lies at or before the current cell's exit,
 * answers exactly as the naive method, ties at equal t included (the lower
 * index wins).
 *
 * Cell boundaries: the plane between cells i - 1 and i on axis k of a grid
 * lies at grid_plane(s, k, i) = lo[k] + i * cell[k] for 0 < i < res[k], and
 * at the grid's box faces for i = 0 and res[k]; the build and the traversal
 * compute it by that one expression, so they agree on every cell's box to
 * the bit, and a subgrid's box is its parent cell's box.
 */
#ifndef BSPRAY_ACCEL_GRID_H
#define BSPRAY_ACCEL_GRID_H

#include <math.h>

#include "accel/accel_internal.h"

/* One grid of the hierarchy: the root (the scene's box) or a cell's own grid
 * (the cell's box, cut again). */
typedef struct subgrid {
    bsp_box box;    /* the root: the scene's bounds grown by pad; a subgrid: its
                       parent cell's box, bit for bit (grid_plane) */
    double cell[3]; /* a cell's extent per axis */
    int res[3];     /* cells per axis */
    int depth;      /* 0: the root; a subgrid's parent is one less */
    uint64_t first; /* its cells are first .. first + res[0] res[1] res[2] - 1 of the
                       grid's cell arrays */
} subgrid;

typedef struct grid {
    double pad;      /* the kd-trees' padding (KD_PAD_REL of the scene scale) */
    int by_bounds;   /* bsp_build_options.grid_assign_bounds: no clipping */
    int levels;      /* the most grids nested (bsp_build_options.grid_levels; 1: uniform) */
    subgrid *subs;   /* subs[0] the root grid; a subgrid's index is above its parent's
                        (they are made breadth first) */
    uint32_t nsubs;  /* 1: a uniform grid */
    uint64_t ncells; /* all grids' cells */
    uint32_t *start; /* cell c lists prims[start[c] .. start[c + 1]); ncells + 1 entries;
                        a subdivided cell's list is empty (its grid's cells list its
                        primitives) */
    uint32_t *child; /* per cell: 0, or the index of the subgrid that cuts it (NULL
                        for a uniform grid) */
    uint32_t *prims; /* the lists, each in increasing primitive order */
    uint64_t nrefs;  /* N_OIV */
    uint64_t nonempty;
} grid;

/* The coordinate of the plane below cell I of grid S on AXIS (I = 0 ..
 * res[AXIS]). */
static inline double grid_plane(const subgrid *s, unsigned axis, int i)
{
    if (i <= 0)
        return s->box.lo.v[axis];
    if (i >= s->res[axis])
        return s->box.hi.v[axis];
    return s->box.lo.v[axis] + (double)i * s->cell[axis];
}

/* The cell of AXIS whose half-open slab [plane(i), plane(i + 1)) holds X
 * (the first or last cell for X outside the box), by the planes' own
 * expression, so that build and traversal agree. */
static inline int grid_cell_of(const subgrid *s, unsigned axis, double x)
{
    double f = floor((x - s->box.lo.v[axis]) / s->cell[axis]);
    int i = f < 0.0 ? 0 : f >= (double)s->res[axis] ? s->res[axis] - 1 : (int)f;
    while (i > 0 && x < grid_plane(s, axis, i))
        i--;
    while (i < s->res[axis] - 1 && x >= grid_plane(s, axis, i + 1))
        i++;
    return i;
}

/* The index of cell C (x, y, z) of grid S in the grid's cell arrays. */
static inline uint64_t grid_cell_index(const subgrid *s, const int c[3])
{
    return s->first +
           ((uint64_t)c[2] * (uint64_t)s->res[1] + (uint64_t)c[1]) * (uint64_t)s->res[0] +
           (uint64_t)c[0];
}

/* The cells of grid S. */
static inline uint64_t subgrid_cells(const subgrid *s)
{
    return (uint64_t)s->res[0] * (uint64_t)s->res[1] * (uint64_t)s->res[2];
}

/* Builds A's grid over A->scene with A->opts (grid_density, grid_res,
 * grid_assign_bounds, grid_levels, grid_cell_prims). */
HIDDEN bsp_status grid_build(bsp_accel *a, bsp_error *err);
/* The grid's figures in Havran's names (a cell is a leaf, N_IN = 0). */
HIDDEN void grid_stats(const grid *g, bsp_tree_stats *st);
/* The assignment invariant above, checked cell by cell. */
HIDDEN bsp_status grid_check(const grid *g, const bsp_scene *scene, bsp_error *err);
/* Visits the grid as bsp_accel_visit_cells describes it (accel.h). */
HIDDEN bsp_status grid_visit(const grid *g, int max_depth,
                             int (*visit)(const bsp_cell_info *cell, void *ctx), void *ctx);

/* The queries (grid_traverse.c), for accel_ops. */
HIDDEN int grid_intersect(const bsp_accel *a, bsp_query *q, const bsp_ray *ray, uint32_t from,
                          bsp_hit *hit);
HIDDEN int grid_occluded(const bsp_accel *a, bsp_query *q, const bsp_ray *ray, uint32_t from);

#endif /* BSPRAY_ACCEL_GRID_H */
