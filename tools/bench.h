/*
 * bench.h — what `bspray bench` and its --paper (paper.c) and --scaling
 * (bench_scaling.c) modes share.
 */
#ifndef BSPRAY_TOOLS_BENCH_H
#define BSPRAY_TOOLS_BENCH_H

#include <stddef.h>

#include "bspray/bspray.h"

/* Compares ACCEL with NAIVE on NRAND seeded random rays around SCENE and on
 * a 64 x 64 grid of the camera's eye rays: the same primitive, a
 * bit-identical t and the same occlusion answer. Returns the number of rays
 * checked, or -1 at the first difference (described in WHAT). */
long bench_validate(const bsp_accel *accel, const bsp_accel *naive, const bsp_scene *scene,
                    int nrand, char *what, size_t what_size);

/* The rays of one class recorded from a render: a render's ray_log is
 * bench_log_ray with an array of BSP_RAY_CLASS_COUNT sets, zeroed, as its
 * context; FAILED when out of memory (the set is then incomplete). */
typedef struct bench_ray_set {
    bsp_ray *rays;
    uint32_t *from; /* the primitive each ray's query leaves out (bsp_intersect_from) */
    size_t n, cap;
    int failed;
} bench_ray_set;
void bench_log_ray(bsp_ray_class cls, const bsp_ray *ray, uint32_t from, void *ctx);
void bench_free_ray_sets(bench_ray_set sets[BSP_RAY_CLASS_COUNT]);

/* The CPU time of the calling thread, in seconds. */
double bench_cpu_seconds(void);

/* The default scenes (NULL-terminated): lattice, rings, tree, then every
 * other SPD scene. */
extern const char *const bench_default_scenes[];

/* Room for the scenes of a command line of ARGC words, or for DEFAULTS
 * (NULL-terminated), whichever is more (free()); exits with a message when
 * out of memory, as load_scene does. */
const char **bench_scene_array(int argc, const char *const *defaults);
/* N scenes were given in SCENES: when none, copies DEFAULTS there. Returns
 * the count. */
int bench_scenes_or_defaults(const char **scenes, int n, const char *const *defaults);

/* --plot: a bar chart on a log scale written to PATH, one group of bars per
 * scene (SCENES[0..NSCENES), shown without an "spd:" prefix) and one bar
 * colour per series (NAMES[0..NSERIES)); VALUES[s * NSCENES + c] is series
 * s's bar in scene c (NAN, 0 or less: none). 0, with a message, when the
 * chart cannot be written. */
int bench_write_bars(const char *path, const char *title, const char *ylabel,
                     const char *const *scenes, size_t nscenes, const char *const *names,
                     size_t nseries, const double *values);

/* `bspray bench --paper ...`: the paper's Table 1 (paper.c). */
int bench_paper(int argc, char **argv);

/* The default scenes of --scaling (NULL-terminated): two generators from
 * ~10^4 to ~10^6 primitives. */
extern const char *const bench_scaling_default_scenes[];

/* `bspray bench --scaling ...`: build time against the number of primitives
 * (bench_scaling.c). */
int bench_scaling(int argc, char **argv);

/* `bspray bench --grids ...`: Havran's uniform grids reproduced
 * (bench_grids.c). */
int bench_grids(int argc, char **argv);

#endif /* BSPRAY_TOOLS_BENCH_H */
