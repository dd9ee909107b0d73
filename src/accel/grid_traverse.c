/*
 * grid_traverse.c — the uniform grid's queries (grid.h): the ray clipped to
 * the grid's box, then its cells in the order it meets them, by a 3D-DDA
 * (Amanatides & Woo 1987).
 *
 * Robustness without epsilons: a cell's exit on axis k is the t of the plane
 * the ray leaves it by, computed afresh from that plane's coordinate (no
 * sum of increments drifts); an axis the ray does not move along (d = 0)
 * is never stepped. Rounding may start the walk in a neighbour of the true
 * first cell, or take the two sides of an edge in the other order; the
 * segments missed that way lie within a few ulps of a plane, and the hits
 * there are in the cells visited too, since every primitive is listed in
 * every cell it comes within the padding of (grid.h). The closest-hit walk
 * stops once the best hit's t is at most the current cell's exit: any
 * primitive hit at that t or before is listed in a cell visited so far.
 * Rays outside the precision domain are answered by the naive method, as
 * the kd-trees' are.
 */
#include <math.h>

#include "accel/grid.h"
#include "geom/vec.h"

/* The walk's state: the cell C, its exits TNEXT per axis, the steps. */
typedef struct dda {
    int c[3], step[3];
    double tnext[3];
    double t_end; /* where the ray's segment in the box ends */
} dda;

/* The t where the ray leaves cell C on axis K (it moves along K). */
static inline double exit_t(const grid *g, const double o[3], const double d[3], const dda *w,
                            unsigned k)
{
    int i = w->c[k] + (w->step[k] > 0);
    return (grid_plane(g, k, i) - o[k]) / d[k];
}

/* Clips the ray to the grid's box and sets up the walk; 0 when the ray
 * misses the box. */
static int dda_start(const grid *g, const bsp_ray *ray, const double o[3], const double d[3],
                     dda *w)
{
    double t0 = ray->tmin, t1 = ray->tmax;
    if (!line_clip_box(o, d, &g->box, &t0, &t1))
        return 0;
    if (!(t0 <= t1))
        return 0;
    w->t_end = t1;
    for (unsigned k = 0; k < 3; k++) {
        w->c[k] = grid_cell_of(g, k, o[k] + d[k] * t0);
        w->step[k] = d[k] > 0.0 ? 1 : d[k] < 0.0 ? -1 : 0;
        /* (a subnormal d may make a crossing infinite: such an axis is
         * stepped at most once, and the ray hardly moves along it) */
        w->tnext[k] = w->step[k] ? exit_t(g, o, d, w, k) : INFINITY;
    }
    return 1;
}

/* The axis of the current cell's exit (the nearest plane; the lowest axis
 * on a tie). */
static inline unsigned exit_axis(const dda *w)
{
    unsigned k = w->tnext[1] < w->tnext[0] ? 1 : 0;
    return w->tnext[2] < w->tnext[k] ? 2 : k;
}

/* Moves to the next cell across axis K; 0 when the ray leaves the box. */
static inline int dda_step(const grid *g, const double o[3], const double d[3], dda *w,
                           unsigned k)
{
    if (w->tnext[k] > w->t_end)
        return 0;
    w->c[k] += w->step[k];
    if (w->c[k] < 0 || w->c[k] >= g->res[k])
        return 0;
    w->tnext[k] = exit_t(g, o, d, w, k);
    return 1;
}

/* A query's start on grid G of scene S: the ray's origin O and direction
 * D, the walk W, and the mailbox's stamp for this ray (FROM, the primitive
 * left out, already stamped). -1: the ray lies outside the precision
 * domain (the naive method answers it); 0: it misses the grid; 1: walk. */
static int walk_begin(const grid *g, const bsp_scene *s, bsp_query *q, const bsp_ray *ray,
                      uint32_t from, double o[3], double d[3], dda *w, uint32_t *stamp)
{
    for (unsigned k = 0; k < 3; k++) {
        o[k] = ray->org.v[k];
        d[k] = ray->dir.v[k];
    }
    if (!scene_ray_in_domain(s, o, d[0] * d[0] + d[1] * d[1] + d[2] * d[2]))
        return -1;
    if (g->nrefs == 0 || !dda_start(g, ray, o, d, w))
        return 0;
    *stamp = query_mailbox_next(q, s->nprims);
    if (q->stamp && from < s->nprims)
        q->stamp[from] = *stamp;
    return 1;
}

int grid_intersect(const bsp_accel *a, bsp_query *q, const bsp_ray *ray, uint32_t from,
                   bsp_hit *hit)
{
    const grid *g = a->impl;
    const bsp_scene *s = a->scene;
    double o[3], d[3];
    dda w;
    uint32_t stamp = 0;
    hit->prim = BSP_NO_PRIM;
    int go = walk_begin(g, s, q, ray, from, o, d, &w, &stamp);
    if (go <= 0)
        return go < 0 ? naive_scene_intersect(s, q, ray, from, hit) : 0;
    uint32_t *mbox = q->stamp;
    /* as in the kd-trees' loop (kd_traverse.c): tmax follows the best hit,
     * and at equal t the lower index wins */
    isect_ray r;
    isect_ray_init(&r, ray, s->hit_tol); /* in the domain: checked */
    double tmax = ray->tmax;
    scene_isect_hit best = {INFINITY, 0.0, 0.0, 1.0}, h;
    uint32_t best_p = BSP_NO_PRIM;
    uint64_t cells = 0, nonempty = 0, refs = 0, tests = 0;
    for (;;) {
        const uint64_t c = grid_cell_index(g, w.c);
        const uint32_t *list = g->prims + g->start[c], *end = g->prims + g->start[c + 1];
        cells++;
        nonempty += list != end;
        refs += (uint64_t)(end - list);
        for (; list != end; list++) {
            const uint32_t p = *list;
            if (mbox) {
                if (mbox[p] == stamp)
                    continue;
                mbox[p] = stamp;
            } else if (p == from || p == best_p) {
                continue;
            }
            tests++;
            if (scene_isect(s, p, &r, tmax, &h) && (h.t < best.t || p < best_p)) {
                best = h;
                best_p = p;
                tmax = h.t;
            }
        }
        const unsigned k = exit_axis(&w);
        if (best.t <= w.tnext[k] || !dda_step(g, o, d, &w, k))
            break; /* the closest hit lies in this cell, or the ray leaves the box */
    }
    query_count(q, 0, cells, 0, nonempty, refs, tests);
    if (best_p == BSP_NO_PRIM)
        return 0;
    scene_hit_finish(&best, best_p, hit);
    return 1;
}

int grid_occluded(const bsp_accel *a, bsp_query *q, const bsp_ray *ray, uint32_t from)
{
    const grid *g = a->impl;
    const bsp_scene *s = a->scene;
    double o[3], d[3];
    dda w;
    uint32_t stamp = 0;
    int go = walk_begin(g, s, q, ray, from, o, d, &w, &stamp);
    if (go <= 0)
        return go < 0 ? naive_scene_occluded(s, q, ray, from) : 0;
    uint32_t *mbox = q->stamp;
    isect_ray r;
    isect_ray_init(&r, ray, s->hit_tol);
    scene_isect_hit h;
    int found = 0;
    uint64_t cells = 0, nonempty = 0, refs = 0, tests = 0;
    do {
        const uint64_t c = grid_cell_index(g, w.c);
        const uint32_t *list = g->prims + g->start[c], *end = g->prims + g->start[c + 1];
        cells++;
        nonempty += list != end;
        for (; list != end && !found; list++) {
            const uint32_t p = *list;
            refs++;
            if (mbox) {
                if (mbox[p] == stamp)
                    continue;
                mbox[p] = stamp;
            } else if (p == from) {
                continue;
            }
            tests++;
            found = scene_isect(s, p, &r, ray->tmax, &h);
        }
    } while (!found && dda_step(g, o, d, &w, exit_axis(&w)));
    query_count(q, 0, cells, 0, nonempty, refs, tests);
    return found;
}
