/*
 * bench_cmdline.c — the command line of every `bspray bench` mode (plain,
 * --paper, --scaling, --grids, --octrees): the options they share are read here, once,
 * the same way; a mode's own options go through its callback.
 */
#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "bench.h"
#include "cli.h"

/* Room for every operand of the command line, or for the defaults,
 * whichever is more. */
static const char **scene_array(int argc, const char *const *defaults)
{
    size_t n = 0;
    while (defaults[n])
        n++;
    const char **a = calloc((size_t)argc + n + 1, sizeof(const char *));
    if (!a) {
        fprintf(stderr, "%s: out of memory\n", prog);
        exit(EXIT_INPUT);
    }
    return a;
}

/* Consumes argv[a->i] when it is one of the shared options C takes. */
static int shared_option(args *a, const char *s, bench_cmdline *c)
{
    unsigned t = c->takes;
    if (c->mode_flag && !strcmp(s, c->mode_flag))
        return 1;
    if (!strcmp(s, "--threads"))
        c->threads = parse_int(a, s, 1, 256);
    else if (!strcmp(s, "--csv"))
        c->csv_path = opt_value(a, s);
    else if (!strcmp(s, "--quiet") || !strcmp(s, "-q"))
        c->quiet = 1;
    else if ((t & BENCH_TAKES_PLOT) && !strcmp(s, "--plot"))
        c->plot_path = opt_value(a, s);
    else if ((t & BENCH_TAKES_REPEAT) && !strcmp(s, "--repeat")) {
        c->repeat = parse_int(a, s, 1, 100);
        c->repeat_given = 1;
    } else if ((t & (BENCH_TAKES_RENDER | BENCH_TAKES_RES)) && !strcmp(s, "--res"))
        c->res = parse_int(a, s, c->res_min > 0 ? c->res_min : 1, 65536);
    else if ((t & BENCH_TAKES_RENDER) && !strcmp(s, "--depth"))
        c->depth = parse_int(a, s, 0, 64);
    else if ((t & BENCH_TAKES_RENDER) && !strcmp(s, "--mailbox"))
        c->mailbox = parse_on_off(a, s);
    else if ((t & BENCH_TAKES_RENDER) && !strcmp(s, "--validate"))
        c->nvalidate = parse_int(a, s, 0, 100000000);
    else
        return ((t & BENCH_TAKES_COSTS) && parse_cost_arg(a, &c->costs)) ||
               ((t & BENCH_TAKES_CELLS) && parse_subdivision_arg(a, &c->cells));
    return 1;
}

int bench_read_cmdline(args *a, bench_cmdline *c, bench_own_option own, void *ctx,
                       void (*help)(void))
{
    c->scenes = scene_array(a->argc, c->default_scenes);
    c->nscenes = 0;
    for (; a->i < a->argc; a->i++) {
        const char *s = a->argv[a->i];
        if (is_help(s)) {
            help();
            bench_free_cmdline(c);
            return 1;
        }
        if (shared_option(a, s, c) || (own && own(a, s, ctx)))
            continue;
        if (s[0] == '-' && s[1])
            die_usage(a->usage, "unknown option '%s'", s);
        c->scenes[c->nscenes++] = s;
    }
    return 0;
}

void bench_cmdline_init(bench_cmdline *c, unsigned takes, const char *mode_flag,
                        const char *const *default_scenes)
{
    memset(c, 0, sizeof *c);
    c->takes = takes;
    c->mode_flag = mode_flag;
    c->default_scenes = default_scenes;
    c->res = 513;
    c->depth = 4;
    c->mailbox = 1;
    c->repeat = 3;
    c->threads = default_threads();
    bsp_build_options_defaults(&c->cells);
}

int bench_cmdline_ready(bench_cmdline *c, int check_load, FILE **csv)
{
    *csv = NULL;
    if (c->nscenes == 0)
        while (c->default_scenes[c->nscenes]) {
            c->scenes[c->nscenes] = c->default_scenes[c->nscenes];
            c->nscenes++;
        }
    /* before minutes of renders or builds */
    int ok = (!c->plot_path || output_path_writable(c->plot_path)) &&
             (!check_load || scenes_loadable(c->scenes, c->nscenes));
    if (ok && c->csv_path && !(*csv = fopen(c->csv_path, "w"))) {
        fprintf(stderr, "%s: %s: cannot open for writing: %s\n", prog, c->csv_path,
                strerror(errno));
        ok = 0;
    }
    if (!ok)
        bench_free_cmdline(c);
    return ok;
}

void bench_free_cmdline(bench_cmdline *c)
{
    free(c->scenes);
    c->scenes = NULL;
    c->nscenes = 0;
}
