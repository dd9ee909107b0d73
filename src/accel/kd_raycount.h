/*
 * kd_raycount.h — sah-mixed's counted model (docs/modified-sah.md): the
 * measure of a box is the number of the pre-pass's ray segments that meet
 * it, counted exactly (after the ray distribution heuristic of Bittner &
 * Havran 2009), not read from a density grid as the sampled model does.
 *
 * Counting every segment against every candidate box would cost the whole
 * sample per candidate. The count follows the build down the tree instead:
 * each cell the builder enters keeps the parts of the segments that meet it
 * (a parameter interval per segment, filtered from the enclosing cell's),
 * and per axis the least and the greatest coordinate of every part, sorted.
 * A child of that cell — the cell with one face moved to a plane at s on
 * axis k — is met by exactly the parts whose least k coordinate is <= s
 * (below the plane) or whose greatest is >= s (above it): two binary
 * searches per candidate.
 *
 * The count of a box depends on the box alone (a segment meets it or not),
 * so the cells kept are only a cache: a box is counted from the deepest
 * kept cell that contains it, and a box that is not such a cell with one
 * face moved is counted part by part from there. The measure is monotone
 * under inclusion and the children of a split cover their parent
 * (count(L) + count(R) >= count(V)).
 *
 * The kept cells are per build thread (a kd_raycount_cursor); the sample
 * and the root cell's parts (kd_raycount) are shared and read-only.
 */
#ifndef BSPRAY_ACCEL_KD_RAYCOUNT_H
#define BSPRAY_ACCEL_KD_RAYCOUNT_H

#include <stddef.h>
#include <stdint.h>

#include "accel/kd_flux.h"

/* The parts of the segments that meet one box. */
typedef struct kd_raycount_cell {
    bsp_box box;
    size_t n, cap;
    uint32_t *seg;         /* segment index per part */
    double *ta, *tb;       /* the part: seg's points at t in [ta, tb] */
    double *lo[3], *hi[3]; /* per axis, sorted: the least / greatest coordinate of each part */
    uint64_t *sort_tmp;    /* scratch of the sort */
} kd_raycount_cell;

/* The sample: segments (origin, direction) and the root cell's parts. */
typedef struct kd_raycount {
    size_t nseg;
    double (*od)[6]; /* per segment: origin x, y, z, direction x, y, z */
    kd_raycount_cell root;
} kd_raycount;

/* Takes the segments SEG[0..N) that meet ROOT (not finite ones are left
 * out). BSP_ERR_NOMEM, BSP_ERR_INVALID for more than 2^32 - 1 segments, or
 * BSP_OK; RC->root.n is then the count of ROOT. */
HIDDEN bsp_status kd_raycount_init(kd_raycount *rc, const bsp_box *root,
                                   const kd_flux_segment *seg, size_t n, bsp_error *err);
HIDDEN void kd_raycount_free(kd_raycount *rc);

/* One build thread's kept cells: a stack from the root down. */
typedef struct kd_raycount_cursor {
    const kd_raycount *rc;
    kd_raycount_cell *cells; /* cells[0..top): each inside the one before; the root
                                (rc->root) stands below cells[0] */
    size_t top, cap;
} kd_raycount_cursor;

HIDDEN void kd_raycount_cursor_init(kd_raycount_cursor *c, const kd_raycount *rc);
HIDDEN void kd_raycount_cursor_free(kd_raycount_cursor *c);

/* Keeps the parts of the segments meeting CELL (before the builder
 * measures CELL and its children): the kept cells that do not contain CELL
 * are dropped. 0 when out of memory. */
HIDDEN int kd_raycount_enter(kd_raycount_cursor *c, const bsp_box *cell);

/* Drops every kept cell (the memory stays for reuse). */
HIDDEN void kd_raycount_reset(kd_raycount_cursor *c);

/* The number of segments that meet the closed box B. */
HIDDEN double kd_raycount_measure(const kd_raycount_cursor *c, const bsp_box *b);

#endif /* BSPRAY_ACCEL_KD_RAYCOUNT_H */
