/*
 * cli.c — the helpers every subcommand of the bspray tool shares (cli.h).
 */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "cli.h"

const char *prog = "bspray";

void die_usage(const char *usage, const char *fmt, const char *arg)
{
    fprintf(stderr, "%s: ", prog);
    fprintf(stderr, fmt, arg);
    fprintf(stderr, "\nusage: %s\nTry '%s --help' for more.\n", usage, prog);
    exit(EXIT_USAGE);
}

/* The value of option OPT (the next argument), or a usage error. */
const char *opt_value(args *a, const char *opt)
{
    if (a->i + 1 >= a->argc)
        die_usage(a->usage, "option '%s' needs a value", opt);
    return a->argv[++a->i];
}

int parse_int(args *a, const char *opt, long lo, long hi)
{
    const char *v = opt_value(a, opt);
    char *end;
    errno = 0;
    long x = strtol(v, &end, 10);
    if (errno || end == v || *end || x < lo || x > hi) {
        char msg[160];
        snprintf(msg, sizeof msg, "option '%s' needs a whole number from %ld to %ld, got '%%s'",
                 opt, lo, hi);
        die_usage(a->usage, msg, v);
    }
    return (int)x;
}

int parse_on_off(args *a, const char *opt)
{
    const char *v = opt_value(a, opt);
    if (!strcmp(v, "on") || !strcmp(v, "1") || !strcmp(v, "yes"))
        return 1;
    if (!strcmp(v, "off") || !strcmp(v, "0") || !strcmp(v, "no"))
        return 0;
    die_usage(a->usage, "expected on or off, got '%s'", v);
    return 0;
}

int is_help(const char *s)
{
    return !strcmp(s, "-h") || !strcmp(s, "--help");
}

bsp_scene *load_scene(const char *path)
{
    bsp_scene *scene = NULL;
    bsp_error err;
    if (bsp_scene_load(path, &scene, &err) != BSP_OK) {
        fprintf(stderr, "%s: %s\n", prog, err.message);
        exit(EXIT_INPUT);
    }
    for (size_t i = 0; i < bsp_scene_warning_count(scene); i++)
        fprintf(stderr, "%s: warning: %s\n", prog, bsp_scene_warning(scene, i));
    return scene;
}

bsp_accel *build_accel(const bsp_scene *scene, const bsp_build_options *opts)
{
    bsp_accel *accel = NULL;
    bsp_error err;
    if (bsp_accel_build(scene, opts, &accel, &err) != BSP_OK) {
        fprintf(stderr, "%s: %s\n", prog, err.message);
        exit(EXIT_INPUT);
    }
    return accel;
}

void parse_accel(args *a, bsp_build_options *opts)
{
    const char *v = opt_value(a, "--accel");
    bsp_error err;
    if (bsp_accel_kind_parse(v, &opts->kind, &err) != BSP_OK)
        die_usage(a->usage, "%s", err.message);
}


bsp_vec3 parse_vec3(args *a, const char *opt)
{
    const char *v = opt_value(a, opt);
    double x, y, z;
    char extra;
    if (sscanf(v, "%lf,%lf,%lf%c", &x, &y, &z, &extra) != 3 || !isfinite(x) || !isfinite(y) ||
        !isfinite(z)) {
        char msg[160];
        snprintf(msg, sizeof msg, "option '%s' needs three finite numbers x,y,z, got '%%s'", opt);
        die_usage(a->usage, msg, v);
    }
    return bsp_v3(x, y, z);
}

double now_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}
