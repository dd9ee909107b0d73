/*
 * bench.h — what `bspray bench` shares with its --paper mode: validation of
 * a method against the naive one, and the paper's tables.
 *
 * NOTE: reconstructed by the SAH agent after it deleted this (then
 * untracked) file by mistake; the original had bench_paper at line 19.
 * Please check it against your copy.
 */
#ifndef BSPRAY_TOOLS_BENCH_H
#define BSPRAY_TOOLS_BENCH_H

#include <stddef.h>

#include "bspray/bspray.h"

/* Compares ACCEL with NAIVE on NRAND random rays and on a grid of primary
 * rays; returns the number of rays checked, or -1 on the first difference
 * (described in WHAT[0..WHAT_SIZE)). */
long bench_validate(const bsp_accel *accel, const bsp_accel *naive, const bsp_scene *scene,
                    int nrand, char *what, size_t what_size);

/* `bspray bench --paper`: the paper's tables. */
int bench_paper(int argc, char **argv);

#endif /* BSPRAY_TOOLS_BENCH_H */
