/*
 * bench_havran.c — what `bench --grids` (bench_grids.c) and `bench --octrees`
 * (bench_octrees.c) share: Havran's 1999 SPD scenes as operands, the loop
 * over them with the naive method beside, and one structure measured the way
 * his tables were (validated against naive, then a 513 x 513 render of ray
 * depth 4, figures per ray of every class).
 */
#include <stdio.h>
#include <string.h>

#include "bench.h"
#include "cli.h"

const char *const havran_scenes[] = {"balls", "gears", "lattice", "mount",
                                     "rings", "teapot", "tetra",  "tree", NULL};

/* SCENE's name without "spd:", if it is one of Havran's; else NULL. */
static const char *havran_scene(const char *scene)
{
    const char *name = strncmp(scene, "spd:", 4) == 0 ? scene + 4 : scene;
    for (int i = 0; havran_scenes[i]; i++)
        if (!strcmp(name, havran_scenes[i]))
            return havran_scenes[i];
    return NULL;
}

int havran_scene_arg(args *a, const char *s, void *ctx)
{
    bench_cmdline *c = ctx;
    if (s[0] == '-' && s[1])
        return 0;
    if (!havran_scene(s))
        die_usage(a->usage,
                  "'%s' is not one of Havran's scenes (balls gears lattice mount rings teapot "
                  "tetra tree)",
                  s);
    c->scenes[c->nscenes++] = havran_scene(s);
    return 1;
}

/* The database of his scene BARE: the SPD program at its default size, but
 * the teapot at size factor 12 (9,264 primitives), the size of the SPD
 * Readme's table that his statistics use (his renders' ray counts and his
 * grids' cells are those of teapot -s 12: docs/renderer.md, docs/grid.md). */
static void havran_scene_spec(const char *bare, char *spec, size_t size)
{
    snprintf(spec, size, "spd:%s%s", bare, strcmp(bare, "teapot") == 0 ? ":12" : "");
}

int havran_each_scene(const bench_cmdline *cl, havran_scene_fn fn, void *ctx)
{
    int rc = 0;
    for (int si = 0; si < cl->nscenes && rc == 0; si++) {
        char name[64];
        havran_scene_spec(cl->scenes[si], name, sizeof name);
        bsp_scene *scene = load_scene(name);
        bsp_build_options no;
        bsp_build_options_defaults(&no);
        no.kind = BSP_ACCEL_NAIVE;
        bsp_accel *naive = build_accel(scene, &no);
        rc = fn(cl->scenes[si], name, scene, naive, ctx);
        bsp_accel_destroy(naive);
        bsp_scene_destroy(scene);
    }
    return rc;
}

/* One structure of havran_measure_pair. */
static long measure_one(const bsp_accel *accel, const bsp_accel *naive, const char *name,
                        const char *structure, const havran_run *run, havran_figures *f)
{
    char what[256];
    long checked = bench_validate(accel, naive, bsp_accel_scene(accel), 2000, what, sizeof what);
    if (checked < 0) {
        fprintf(stderr, "%s: %s: the %s differs from naive: %s; aborting\n", prog, name,
                structure, what);
        return -1;
    }
    bsp_render_options ro;
    bsp_render_options_defaults(&ro);
    ro.width = ro.height = run->res;
    ro.max_depth = 4;
    ro.threads = run->threads;
    bsp_image *img = NULL;
    bsp_render_stats st;
    bsp_error err;
    if (bsp_render(accel, &ro, &img, &st, &err) != BSP_OK) {
        fprintf(stderr, "%s: %s: %s\n", prog, name, err.message);
        return -1;
    }
    bsp_image_destroy(img);
    double rays = 0, it = 0, ts = 0, ets = 0, eets = 0;
    for (int c = 0; c < BSP_RAY_CLASS_COUNT; c++) {
        rays += (double)st.cls[c].rays;
        it += (double)st.cls[c].isect_tests;
        ts += (double)st.cls[c].traversal_steps;
        ets += (double)st.cls[c].leaves_visited;
        eets += (double)st.cls[c].empty_leaves;
    }
    double per = rays > 0 ? 1.0 / rays : 0.0;
    f->nit = it * per;
    f->nts = ts * per;
    f->nets = ets * per;
    f->neets = eets * per;
    return checked;
}

long havran_measure_pair(const bsp_accel *his, const bsp_accel *ours, const bsp_accel *naive,
                         const char *name, const char *structure, const havran_run *run,
                         havran_figures *f_his, havran_figures *f_ours)
{
    long a = measure_one(his, naive, name, structure, run, f_his);
    if (a < 0)
        return -1;
    char what[96];
    snprintf(what, sizeof what, "%s (bspray's variant)", structure);
    long b = measure_one(ours, naive, name, what, run, f_ours);
    return b < 0 ? -1 : a + b;
}

/* The command line of havran_bench_main: his scenes, and the bench's
 * variant option. */
typedef struct havran_cmdline {
    bench_cmdline *cl;
    const havran_bench *b;
    int variant;
} havran_cmdline;

static int havran_arg(args *a, const char *s, void *ctx)
{
    havran_cmdline *h = ctx;
    if (h->b->variant_option && !strcmp(s, h->b->variant_option)) {
        h->variant = parse_one_of_two(a, s, h->b->variant_words[0], h->b->variant_words[1]);
        return 1;
    }
    return havran_scene_arg(a, s, h->cl);
}

int havran_bench_main(int argc, char **argv, const havran_bench *b)
{
    args a = {argc, 1, argv, b->usage, NULL};
    bench_cmdline cl;
    bench_cmdline_init(&cl, BENCH_TAKES_RES, b->mode_flag, havran_scenes);
    havran_cmdline h = {&cl, b, 0};
    if (bench_read_cmdline(&a, &cl, havran_arg, &h, b->help))
        return 0;
    havran_run run = {cl.res, cl.threads, cl.quiet, NULL, h.variant};
    if (!bench_cmdline_ready(&cl, 0, &run.csv))
        return EXIT_INPUT;
    const int v = b->table_header[run.variant] ? run.variant : 0;
    if (run.csv)
        fprintf(run.csv, "%s\n", b->csv_header[v]);
    if (b->variant_captions[run.variant])
        printf("%s\n\n", b->variant_captions[run.variant]);
    if (run.res != 513) /* his protocol: the structure's figures still are his */
        printf("Rendered at %d x %d, not his 513 x 513: the per-ray figures (N_IT, N_TS, "
               "N_ETS, N_EETS) are not comparable with his.\n\n",
               run.res, run.res);
    printf("%s\n", b->table_header[v]);
    int rc = havran_each_scene(&cl, b->each, &run);
    if (run.csv && !close_output(run.csv, cl.csv_path))
        rc = EXIT_INPUT;
    bench_free_cmdline(&cl);
    return rc;
}
