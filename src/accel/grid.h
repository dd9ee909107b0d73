/*
 * grid.h — the uniform grid (`--accel grid`): the scene's box cut into
 * res[0] x res[1] x res[2] equal cells, each with the list of the
 * primitives that touch it, traversed cell by cell along the ray by a 3D-DDA
 * (Amanatides & Woo 1987). It is the classic baseline of Havran's grid
 * statistics (../shared/reference/havran_stats_grids.txt) and a second
 * structure, built by other code, that must answer as the naive method does.
 *
 * Assignment invariant (the kd-trees', kd_tree.h): a primitive is listed in
 * every cell that its padded bounds, clipped to the cell grown by the
 * padding (kd_clip.h), overlap (or, with grid_assign_bounds, every cell its
 * padded bounds overlap: a superset); so it is listed in every cell whose closed
 * box it touches, and the traversal, which stops once the closest hit lies
 * at or before the current cell's exit, answers exactly as the naive method,
 * ties at equal t included (the lower index wins).
 *
 * Cell boundaries: the plane between cells i - 1 and i on axis k lies at
 * grid_plane(g, k, i) = lo[k] + i * cell[k] for 0 < i < res[k], and at the
 * box's faces for i = 0 and res[k]; the build and the traversal compute it
 * by that one expression, so they agree on every cell's box to the bit.
 */
#ifndef BSPRAY_ACCEL_GRID_H
#define BSPRAY_ACCEL_GRID_H

#include <math.h>

#include "accel/accel_internal.h"

typedef struct grid {
    bsp_box box;      /* the scene's bounds grown by pad (empty for a scene of
                         no live primitive) */
    double pad;       /* the kd-trees' padding (KD_PAD_REL of the scene scale) */
    int by_bounds;    /* bsp_build_options.grid_assign_bounds: no clipping */
    int res[3];       /* cells per axis */
    double cell[3];   /* a cell's extent per axis */
    uint64_t ncells;  /* res[0] * res[1] * res[2] */
    uint32_t *start;  /* cell c lists prims[start[c] .. start[c + 1]), c = (z res[1] +
                         y) res[0] + x; ncells + 1 entries */
    uint32_t *prims;  /* the lists, each in increasing primitive order */
    uint64_t nrefs;   /* N_OIV */
    uint64_t nonempty;
} grid;

/* The coordinate of the plane below cell I on AXIS (I = 0 .. res[AXIS]). */
static inline double grid_plane(const grid *g, unsigned axis, int i)
{
    if (i <= 0)
        return g->box.lo.v[axis];
    if (i >= g->res[axis])
        return g->box.hi.v[axis];
    return g->box.lo.v[axis] + (double)i * g->cell[axis];
}

/* The cell of AXIS whose half-open slab [plane(i), plane(i + 1)) holds X
 * (the first or last cell for X outside the box), by the planes' own
 * expression, so that build and traversal agree. */
static inline int grid_cell_of(const grid *g, unsigned axis, double x)
{
    double f = floor((x - g->box.lo.v[axis]) / g->cell[axis]);
    int i = f < 0.0 ? 0 : f >= (double)g->res[axis] ? g->res[axis] - 1 : (int)f;
    while (i > 0 && x < grid_plane(g, axis, i))
        i--;
    while (i < g->res[axis] - 1 && x >= grid_plane(g, axis, i + 1))
        i++;
    return i;
}

/* The index of cell C (x, y, z) in the lists' order. */
static inline uint64_t grid_cell_index(const grid *g, const int c[3])
{
    return ((uint64_t)c[2] * (uint64_t)g->res[1] + (uint64_t)c[1]) * (uint64_t)g->res[0] +
           (uint64_t)c[0];
}

/* Builds A's grid over A->scene with A->opts (grid_density, grid_res). */
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
