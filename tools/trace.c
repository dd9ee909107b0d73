/*
 * trace.c — `bspray trace`: closest-hit or occlusion queries read from a ray
 * file, answered on every core, with the per-ray figures of Havran's tables.
 *
 * The file is read in batches of TRACE_BATCH rays; each batch is shot by
 * bsp_intersect_batch / bsp_occluded_batch (every thread its own query) and
 * printed in input order, so the output does not depend on --threads. A bad
 * line stops the run: the rays before it are answered and printed, then the
 * message names the file and line.
 */
#include <errno.h>
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "bspray/bspray.h"
#include "util/progress.h"

#include "cli.h"

#define TRACE_BATCH 65536
/* A run that takes longer than this draws a progress bar (on a terminal),
 * by the share of the ray file read */
#define TRACE_BAR_DELAY 0.5

static const char trace_usage[] =
    "bspray trace SCENE --rays FILE [--any] [--threads N] [--exact] [--stats]\n"
    "                   [--stats-json FILE] [--accel METHOD] [--mailbox on|off] [build options]\n"
    "                   [--tree FILE]";

static const char trace_help[] =
    "Shoot the rays of FILE ('-' for standard input) into SCENE, one query per line.\n"
    "\n"
    "Input: one ray per line, 'ox oy oz dx dy dz [tmin tmax [from]]' (blank lines and\n"
    "lines starting with '#' are skipped). The direction need not be unit length: t is\n"
    "in units of the given direction. tmin defaults to 0 and tmax to infinity ('inf').\n"
    "from: the 0-based index of a primitive the query leaves out, the one a shadow or\n"
    "reflected ray starts on (bsp_intersect_from), or -1 for none (the default).\n"
    "\n"
    "Output: one line per ray, in input order, 'hit INDEX T' (INDEX the 0-based primitive\n"
    "index in file order, T printed with %.9g, or %.17g with --exact) or 'miss'; with\n"
    "--any, 'occluded' or 'clear' for the segment [tmin, tmax]. Ties at equal t go to\n"
    "the lowest index. Every method, on any number of threads, prints the same lines.\n"
    "\n"
    "  --rays FILE        the rays (required)\n"
    "  --any              occlusion queries instead of closest hits\n"
    "  --threads N        threads shooting the rays (default: every core); the output\n"
    "                     does not depend on it\n"
    "  --exact            print t with 17 significant digits, enough to read back the\n"
    "                     very double (compare methods bit for bit)\n"
    "  --stats            print the figures of the run on stderr as a Markdown table:\n"
    "                     rays, hits, N_IT, N_TS, N_ETS, N_EETS and mailbox hits per ray,\n"
    "                     the tree's N_IN, N_V, N_EV, N_OIV, T_B, T_TR (the wall-clock\n"
    "                     time of the queries alone, reading and printing excluded) and\n"
    "                     Mrays/s\n"
    "  --stats-json FILE  write the same figures as JSON\n";

/* A batch of the file's rays and room for their answers. */
typedef struct trace_batch {
    bsp_ray *rays;
    uint32_t *from;
    bsp_hit *hits;           /* closest hits (or NULL with --any) */
    unsigned char *occluded; /* --any */
    size_t n;
} trace_batch;

typedef struct trace_run {
    const bsp_accel *accel;
    const char *tree_path; /* --tree: the file the structure was loaded from, else NULL */
    FILE *in;
    double in_size; /* bytes of a regular ray file, else 0: no progress bar */
    double start;
    progress_bar *bar;
    int any, exact, threads;
    uint64_t answered;           /* hits (or occluded segments) among the queries */
    bsp_query_counters counters; /* counters.rays: the queries */
    double seconds;              /* T_TR */
} trace_run;

/* A direction whose length lies in [1e-100, 1e100]: t counts lengths of the
 * direction, so a shorter or longer one can put a hit's t past the doubles
 * (a hit at t = inf) or its square past the kernels' range. */
static int ray_direction_in_range(double x, double y, double z)
{
    double m = fmax(fabs(x), fmax(fabs(y), fabs(z)));
    if (!(m > 0.0))
        return 0;
    /* the length, scaled so that its square cannot overflow */
    x /= m;
    y /= m;
    z /= m;
    double len = m * sqrt(x * x + y * y + z * z);
    return len >= 1e-100 && len <= 1e100;
}

/* Parses one number of a ray line; accepts inf/-inf only where ALLOW_INF.
 * 1: a number, 0: the end of the line, -1: not a finite number. */
static int ray_number(char **p, double *out, int allow_inf)
{
    char *end;
    while (**p == ' ' || **p == '\t')
        (*p)++;
    if (!**p || **p == '\n' || **p == '\r')
        return 0;
    double x = strtod(*p, &end);
    if (end == *p || (*end && *end != ' ' && *end != '\t' && *end != '\n' && *end != '\r'))
        return -1;
    if (isnan(x) || (isinf(x) && !allow_inf))
        return -1;
    *out = x;
    *p = end;
    return 1;
}

static int is_space(char c)
{
    return c == ' ' || c == '\t' || c == '\r' || c == '\n';
}

/* Parses the ray line P of a scene of NPRIMS primitives into *RAY and
 * *FROM: NULL, or what is wrong with it. */
static const char *parse_ray_line(char *p, size_t nprims, bsp_ray *ray, uint32_t *from_out)
{
    double v[8] = {0, 0, 0, 0, 0, 0, 0, INFINITY};
    int n = 0, r = 0;
    while (n < 8 && (r = ray_number(&p, &v[n], n >= 6)) == 1)
        n++;
    while (is_space(*p))
        p++;
    long long from = -1; /* the primitive left out, after tmin and tmax */
    if (n == 8 && *p) {
        char *e;
        errno = 0;
        from = strtoll(p, &e, 10);
        if (e == p || errno || !(*e == 0 || is_space(*e)))
            return "malformed origin primitive (expected an integer index, or -1)";
        if (from < -1 || from >= (long long)nprims)
            return "origin primitive out of range (a primitive index of the scene, or -1)";
        for (p = e; is_space(*p);)
            p++;
    }
    if (n < 8 && r < 0)
        return "malformed or non-finite number";
    if (*p)
        return "too many fields (expected 'ox oy oz dx dy dz [tmin tmax [from]]')";
    if (n != 6 && n != 8)
        return "expected 6 or 8 numbers: 'ox oy oz dx dy dz [tmin tmax [from]]'";
    if (v[3] == 0 && v[4] == 0 && v[5] == 0)
        return "the direction is the zero vector";
    if (fabs(v[0]) > BSP_SCENE_MAX_COORD || fabs(v[1]) > BSP_SCENE_MAX_COORD ||
        fabs(v[2]) > BSP_SCENE_MAX_COORD)
        return "origin out of range (coordinates must lie within +-1e+30, as a scene's)";
    if (!ray_direction_in_range(v[3], v[4], v[5]))
        return "direction length outside [1e-100, 1e100]: t is measured in units of the "
               "direction, so scale it";
    if (isinf(v[6]) && v[6] > 0)
        return "tmin is +inf";
    if (v[7] < v[6])
        return "tmax is smaller than tmin";
    *ray = (bsp_ray){bsp_v3(v[0], v[1], v[2]), bsp_v3(v[3], v[4], v[5]), v[6], v[7]};
    *from_out = from < 0 ? BSP_NO_PRIM : (uint32_t)from;
    return NULL;
}

/* Shoots batch B and prints its answers; 0 on failure (with a message). */
static int shoot_and_print(trace_run *run, trace_batch *b)
{
    if (b->n == 0)
        return 1;
    bsp_query_counters c;
    bsp_error err;
    double t0 = now_seconds();
    bsp_status st = run->any ? bsp_occluded_batch(run->accel, b->rays, b->from, b->n, run->threads,
                                                  b->occluded, &c, &err)
                             : bsp_intersect_batch(run->accel, b->rays, b->from, b->n, run->threads,
                                                   b->hits, &c, &err);
    run->seconds += now_seconds() - t0;
    if (st != BSP_OK) {
        fprintf(stderr, "%s: %s\n", prog, err.message);
        return 0;
    }
    bsp_query_counters_add(&run->counters, &c);
    for (size_t i = 0; i < b->n; i++) {
        if (run->any) {
            run->answered += b->occluded[i];
            fputs(b->occluded[i] ? "occluded\n" : "clear\n", stdout);
        } else if (b->hits[i].prim != BSP_NO_PRIM) {
            run->answered++;
            printf(run->exact ? "hit %" PRIu32 " %.17g\n" : "hit %" PRIu32 " %.9g\n",
                   b->hits[i].prim, b->hits[i].t + 0.0); /* -0 prints as 0 */
        } else {
            fputs("miss\n", stdout);
        }
    }
    b->n = 0;
    if (run->in_size > 0.0) {
        if (!run->bar && now_seconds() - run->start > TRACE_BAR_DELAY)
            run->bar = progress_create(stderr, "trace");
        progress_update(run->bar, (double)ftello(run->in) / run->in_size);
    }
    return 1;
}

static void print_stats(FILE *f, const char *scene, const trace_run *r, const bsp_tree_stats *t)
{
    const bsp_query_counters *c = &r->counters;
    fprintf(f, "| figure | value |\n|---|---:|\n");
    fprintf(f, "| scene | %s |\n", scene);
    fprintf(f, "| accel | %s |\n", bsp_accel_kind_name(bsp_accel_get_kind(r->accel)));
    fprintf(f, "| queries | %s |\n", r->any ? "occlusion" : "closest hit");
    fprintf(f, "| rays | %" PRIu64 " |\n", c->rays);
    fprintf(f, "| %s | %" PRIu64 " |\n", r->any ? "occluded" : "hits", r->answered);
    fprintf(f, "| N_IT | %.4f |\n", safe_div((double)c->isect_tests, (double)c->rays));
    fprintf(f, "| N_TS | %.4f |\n", safe_div((double)c->traversal_steps, (double)c->rays));
    fprintf(f, "| N_ETS | %.4f |\n", safe_div((double)c->leaves_visited, (double)c->rays));
    fprintf(f, "| N_EETS | %.4f |\n", safe_div((double)c->empty_leaves, (double)c->rays));
    fprintf(f, "| mailbox hits per ray | %.4f |\n",
            safe_div((double)c->mailbox_hits, (double)c->rays));
    fprintf(f,
            "| N_IN / N_V / N_EV / N_OIV | %" PRIu64 " / %" PRIu64 " / %" PRIu64 " / %" PRIu64
            " |\n",
            t->interior_nodes, t->leaves, t->empty_leaves, t->references);
    tree_time_row(f, r->tree_path, bsp_accel_build_seconds(r->accel), 4);
    fprintf(f, "| T_TR[s] | %.4f |\n", r->seconds);
    fprintf(f, "| threads | %d |\n", r->threads);
    fprintf(f, "| Mrays/s | %.3f |\n", r->seconds > 0 ? (double)c->rays / r->seconds * 1e-6 : 0.0);
}

static int write_json(const char *path, const char *scene, const trace_run *r,
                      const bsp_tree_stats *t)
{
    FILE *f = fopen(path, "w");
    if (!f) {
        fprintf(stderr, "%s: %s: cannot open for writing: %s\n", prog, path, strerror(errno));
        return 0;
    }
    const bsp_query_counters *c = &r->counters;
    fprintf(f, "{\n  \"scene\": ");
    json_string(f, scene);
    fprintf(f, ",\n  \"accel\": \"%s\",\n", bsp_accel_kind_name(bsp_accel_get_kind(r->accel)));
    cells_variant_json(f, "  ", r->accel);
    fprintf(f, "  \"queries\": \"%s\",\n", r->any ? "occlusion" : "closest");
    fprintf(f, "  \"threads\": %d,\n  \"rays\": %" PRIu64 ",\n  \"%s\": %" PRIu64 ",\n", r->threads,
            c->rays, r->any ? "occluded" : "hits", r->answered);
    fprintf(f,
            "  \"isect_tests\": %" PRIu64 ",\n  \"traversal_steps\": %" PRIu64
            ",\n  \"leaves_visited\": %" PRIu64 ",\n  \"empty_leaves\": %" PRIu64
            ",\n  \"mailbox_hits\": %" PRIu64 ",\n",
            c->isect_tests, c->traversal_steps, c->leaves_visited, c->empty_leaves,
            c->mailbox_hits);
    fprintf(f, "  \"N_IT\": %.6f,\n  \"N_TS\": %.6f,\n  \"N_ETS\": %.6f,\n  \"N_EETS\": %.6f,\n",
            safe_div((double)c->isect_tests, (double)c->rays),
            safe_div((double)c->traversal_steps, (double)c->rays),
            safe_div((double)c->leaves_visited, (double)c->rays),
            safe_div((double)c->empty_leaves, (double)c->rays));
    tree_stats_json(f, "  ", t, bsp_accel_get_kind(r->accel));
    tree_time_json(f, "  ", r->tree_path, bsp_accel_build_seconds(r->accel));
    fprintf(f, "  \"T_TR\": %.6f\n}\n", r->seconds);
    return close_output(f, path);
}

static int alloc_batch(trace_batch *b, int any)
{
    b->n = 0;
    b->rays = malloc(TRACE_BATCH * sizeof *b->rays);
    b->from = malloc(TRACE_BATCH * sizeof *b->from);
    b->hits = any ? NULL : malloc(TRACE_BATCH * sizeof *b->hits);
    b->occluded = any ? malloc(TRACE_BATCH) : NULL;
    return b->rays && b->from && (b->hits || b->occluded);
}

static void free_batch(trace_batch *b)
{
    free(b->rays);
    free(b->from);
    free(b->hits);
    free(b->occluded);
}

int cmd_trace(int argc, char **argv)
{
    args a = {argc, 1, argv, trace_usage, NULL};
    const char *scene_path = NULL, *rays_path = NULL, *json_path = NULL, *tree_path = NULL;
    trace_run run = {0};
    int stats = 0;
    bsp_build_options bopts;
    bsp_build_options_defaults(&bopts);
    view_args view = {0};
    for (; a.i < argc; a.i++) {
        const char *s = argv[a.i];
        if (is_help(s)) {
            printf("usage: %s\n\n%s%s%s%s", trace_usage, trace_help, build_args_help, tree_arg_help,
                   view_args_help);
            return 0;
        } else if (!strcmp(s, "--rays")) {
            rays_path = opt_value(&a, s);
        } else if (!strcmp(s, "--any")) {
            run.any = 1;
        } else if (!strcmp(s, "--exact")) {
            run.exact = 1;
        } else if (!strcmp(s, "--stats")) {
            stats = 1;
        } else if (!strcmp(s, "--stats-json")) {
            json_path = opt_value(&a, s);
        } else if (!strcmp(s, "--threads")) {
            run.threads = parse_int(&a, s, 1, 256);
        } else if (!strcmp(s, "--tree")) {
            tree_path = opt_value(&a, s);
        } else if (parse_build_arg(&a, &bopts) || parse_view_arg(&a, &view)) {
            continue;
        } else {
            take_operand(&a, &scene_path);
        }
    }
    if (!scene_path)
        die_usage(a.usage, "%s", "missing SCENE");
    if (!rays_path)
        die_usage(a.usage, "%s", "missing --rays FILE");
    if (json_path && !output_path_writable(json_path))
        return EXIT_INPUT;
    FILE *in = strcmp(rays_path, "-") ? fopen(rays_path, "r") : stdin;
    if (!in) {
        fprintf(stderr, "%s: %s: cannot open: %s\n", prog, rays_path, strerror(errno));
        return EXIT_INPUT;
    }
    struct stat in_stat;
    if (fstat(fileno(in), &in_stat) == 0 && S_ISREG(in_stat.st_mode))
        run.in_size = (double)in_stat.st_size;
    if (fstat(fileno(in), &in_stat) == 0 && S_ISDIR(in_stat.st_mode)) {
        fprintf(stderr, "%s: %s: cannot read: %s\n", prog, rays_path, strerror(EISDIR));
        fclose(in);
        return EXIT_INPUT;
    }
    run.in = in;
    bsp_scene *scene = load_scene(scene_path);
    apply_view_args(scene, scene_path, &view, &bopts, NULL);
    bsp_accel *accel = tree_or_build(&a, scene, &bopts, tree_path);
    run.accel = accel;
    run.tree_path = tree_path;
    if (run.threads == 0)
        run.threads = default_threads();
    run.start = now_seconds();
    const size_t nprims = bsp_scene_prim_count(scene);
    trace_batch b;
    int rc = 0;
    if (!alloc_batch(&b, run.any)) {
        fprintf(stderr, "%s: out of memory\n", prog);
        rc = EXIT_INPUT;
    }
    char *line = NULL;
    size_t cap = 0, lineno = 0;
    ssize_t got;
    while (rc == 0 && (got = getline(&line, &cap, in)) >= 0) {
        lineno++;
        char *p = line;
        while (*p == ' ' || *p == '\t')
            p++;
        const char *bad;
        /* a NUL byte would end the line early, and what follows it would
         * pass unread: refused, as the scene readers refuse it */
        if (memchr(line, 0, (size_t)got))
            bad = "a NUL byte in the line";
        else if (!*p || *p == '\n' || *p == '\r' || *p == '#')
            continue;
        else
            bad = parse_ray_line(p, nprims, &b.rays[b.n], &b.from[b.n]);
        if (bad) {
            if (shoot_and_print(&run, &b)) /* the rays before it are answered */
                fprintf(stderr, "%s: %s:%zu: %s\n", prog, rays_path, lineno, bad);
            rc = EXIT_INPUT;
            break;
        }
        if (++b.n == TRACE_BATCH && !shoot_and_print(&run, &b))
            rc = EXIT_INPUT;
    }
    if (rc == 0 && ferror(in)) { /* errno: getline's, the last call made */
        fprintf(stderr, "%s: %s: read failed: %s\n", prog, rays_path, strerror(errno));
        rc = EXIT_INPUT;
    }
    if (rc == 0 && !shoot_and_print(&run, &b))
        rc = EXIT_INPUT;
    progress_finish(run.bar);
    free(line);
    if (in != stdin)
        fclose(in);
    rc = finish_stdout(rc); /* the answers written before the figures */
    if (rc == 0 && (stats || json_path)) {
        bsp_tree_stats ts;
        bsp_accel_tree_stats(accel, &ts);
        if (stats)
            print_stats(stderr, scene_path, &run, &ts);
        if (json_path && !write_json(json_path, scene_path, &run, &ts))
            rc = EXIT_INPUT;
    }
    free_batch(&b);
    bsp_accel_destroy(accel);
    bsp_scene_destroy(scene);
    return rc;
}
