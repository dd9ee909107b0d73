/*
 * bench.h — what `bspray bench` and its --paper (paper.c) and --scaling
 * (bench_scaling.c) and --grids (bench_grids.c) modes share.
 */
#ifndef BSPRAY_TOOLS_BENCH_H
#define BSPRAY_TOOLS_BENCH_H

#include <stddef.h>

#include "bspray/bspray.h"
#include "cli.h"

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

/* The command line of a bench mode. The mode presets the fields to its
 * defaults (TAKES: which of the shared options it accepts; MODE_FLAG: the
 * word that chose the mode, skipped; DEFAULT_SCENES: when no scene is given;
 * RES_MIN: the least --res, 1 when 0; bench_cmdline_init sets the shared
 * defaults); bench_read_cmdline fills the rest. */
enum {
    BENCH_TAKES_RENDER = 1, /* --res, --depth, --mailbox, --validate */
    BENCH_TAKES_REPEAT = 2, /* --repeat */
    BENCH_TAKES_COSTS = 4,  /* the SAH cost model (parse_cost_arg) */
    BENCH_TAKES_PLOT = 8,   /* --plot */
    BENCH_TAKES_CELLS = 16, /* the grid's and the octree's (parse_subdivision_arg) */
    BENCH_TAKES_RES = 32    /* --res alone (Havran's tables) */
};
typedef struct bench_cmdline {
    unsigned takes;
    const char *mode_flag;
    const char *const *default_scenes;
    int res_min;
    int res, depth, mailbox, nvalidate; /* BENCH_TAKES_RENDER (res: or _RES) */
    int repeat, repeat_given;           /* BENCH_TAKES_REPEAT */
    cost_args costs;                    /* BENCH_TAKES_COSTS */
    const char *plot_path;              /* BENCH_TAKES_PLOT */
    bsp_build_options cells; /* BENCH_TAKES_CELLS (apply_subdivision_args) */
    int threads, quiet;                 /* always: --threads, --quiet (-q) */
    const char *csv_path;               /* always: --csv */
    const char **scenes;                /* the operands (free: bench_free_cmdline) */
    int nscenes;
} bench_cmdline;
/* A mode's own options: consumes a->argv[a->i] (S; and its value, or takes
 * it as a scene) and returns 1, or returns 0 when it is none of them. */
typedef int (*bench_own_option)(args *a, const char *s, void *ctx);
/* Reads a->argv[a->i..]: the shared options into C, the others through OWN
 * (may be NULL) with CTX, every other operand as a scene; an unknown option
 * is a usage error. Returns 1 when --help was asked for (HELP printed it;
 * C is freed), else 0. */
int bench_read_cmdline(args *a, bench_cmdline *c, bench_own_option own, void *ctx,
                       void (*help)(void));
/* C zeroed, then the defaults the modes share: 513 x 513 rays of depth 4,
 * mailboxes on, 3 repeats, every thread. */
void bench_cmdline_init(bench_cmdline *c, unsigned takes, const char *mode_flag,
                        const char *const *default_scenes);
/* After the command line, before the long run: the default scenes when none
 * was given, the --plot file writable, (CHECK_LOAD) every scene loadable,
 * and the --csv file opened into *CSV (else NULL). 1, or 0 after a message,
 * C then freed. */
int bench_cmdline_ready(bench_cmdline *c, int check_load, FILE **csv);
void bench_free_cmdline(bench_cmdline *c);

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
/* `bspray bench --octrees ...`: Havran's octrees reproduced (bench_octrees.c). */
int bench_octrees(int argc, char **argv);

/* --- Havran's 1999 statistics (bench_havran.c) --- */

/* His SPD scenes (NULL-terminated): balls gears lattice mount rings teapot
 * tetra tree. */
extern const char *const havran_scenes[];
/* A bench_own_option (CTX the bench_cmdline): an operand must be one of his
 * scenes (or spd:NAME), kept by its bare name; else a usage error. */
int havran_scene_arg(args *a, const char *s, void *ctx);
/* Calls FN for each scene of CL (bare NAME, "spd:NAME", the scene
 * generated in code and the naive method over it) until FN returns
 * non-zero, which is returned. */
typedef int (*havran_scene_fn)(const char *bare, const char *name, const bsp_scene *scene,
                               const bsp_accel *naive, void *ctx);
int havran_each_scene(const bench_cmdline *cl, havran_scene_fn fn, void *ctx);
/* His per-ray figures of a render (every class): N_IT, N_TS, N_ETS, N_EETS. */
typedef struct havran_figures {
    double nit, nts, nets, neets;
} havran_figures;
/* How a bench of his tables runs: --res (his 513 by default), --threads,
 * --quiet, --csv (NULL without), and the index of the VARIANT_OPTION's word
 * (0 without one). */
typedef struct havran_run {
    int res, threads, quiet;
    FILE *csv;
    int variant;
} havran_run;
/* HIS (the structure as his table built it) and OURS (bspray's variant of
 * it), each validated against NAIVE (2,000 random rays and the eye rays),
 * then rendered (RUN's res x res, his 513 by default, ray depth 4, RUN's
 * threads) into *F_HIS and *F_OURS. Returns the rays validated, or -1 after
 * a message naming NAME and STRUCTURE. */
long havran_measure_pair(const bsp_accel *his, const bsp_accel *ours, const bsp_accel *naive,
                         const char *name, const char *structure, const havran_run *run,
                         havran_figures *f_his, havran_figures *f_ours);
/* A bench of his tables: its command line (USAGE, MODE_FLAG, HELP; the
 * operands his scenes, --res, --threads, --csv, --quiet, and VARIANT_OPTION when
 * not NULL, which takes one of VARIANT_WORDS and chooses which of his
 * tables), the CSV's header line and the Markdown table's header (its two
 * lines) of each variant, each variant's caption (a line printed above the table; NULL:
 * none), and EACH, called for every scene with a havran_run as its
 * context, printing its rows. */
typedef struct havran_bench {
    const char *usage, *mode_flag;
    void (*help)(void);
    const char *csv_header[2], *table_header[2]; /* per variant ([1] NULL: [0]'s) */
    havran_scene_fn each;
    const char *variant_option;
    const char *variant_words[2];
    const char *variant_captions[2];
} havran_bench;
/* Runs B on the command line ARGC, ARGV; returns the exit status. */
int havran_bench_main(int argc, char **argv, const havran_bench *b);

/* His recursive grids (bench_recgrids.c), for `bench --grids --grid-kind
 * recursive`: the table's CSV and Markdown headers, and the rows of one
 * scene (a havran_scene_fn). */
extern const char recgrids_csv_header[], recgrids_table_header[];
int recgrids_of_scene(const char *bare, const char *name, const bsp_scene *scene,
                      const bsp_accel *naive, void *ctx);

#endif /* BSPRAY_TOOLS_BENCH_H */
