/*
 * bench_scaling.c — `bspray bench --scaling`: how the build time grows with
 * the number of primitives (issue #3: SAH construction in O(N log N), build
 * time per primitive roughly flat from 10^4 to 10^6 primitives, at least one
 * million primitives per second on one thread).
 *
 * For every scene x method: the best of --repeat builds on one thread, timed
 * by the CPU time of the building (calling) thread, which a shared machine
 * disturbs less than the wall clock; then as many builds on --threads
 * threads, timed by the wall clock (the same tree), and the tree's figures.
 * The trees are not validated here (plain `bspray bench` does that; a naive
 * reference on 10^6 primitives would take hours). A second table gives, per
 * generator (the scene name without its size factor) and method, the growth
 * of µs per primitive from its smallest to its largest scene next to the
 * growth of log N: an O(N log N) build grows like log N, an O(N) build stays
 * flat, an O(N log^2 N) build grows like its square.
 */
#include <errno.h>
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench.h"
#include "cli.h"
#include "render/plot.h"

static const char scaling_usage[] =
    "bspray bench --scaling [SCENE...] [--accel LIST] [--repeat N] [--threads N]\n"
    "                       [--csv FILE] [--plot FILE.png] [--quiet]";

/* Two generators from ~10^4 to ~10^6 primitives: sphereflakes (spheres) and
 * the Sierpinski tetrahedron (triangles). */
const char *const bench_scaling_default_scenes[] = {
    "spd:balls:4", "spd:balls:5", "spd:balls:6",  "spd:tetra:7",
    "spd:tetra:8", "spd:tetra:9", "spd:tetra:10", NULL};

/* Scenes above this many primitives get at most SCALING_BIG_REPEAT builds
 * per thread count unless --repeat is given. Two, not one: a process's first
 * build of a large scene writes 100-200 MB it never wrote before, and on a
 * virtual machine the system time of that first touch swings from 0.02 to
 * 0.2 s between identical runs (balls:6, whose build's user time stays at
 * 0.52-0.55 s; docs/kdtree-log.md, "Session 34"), so a single build measures
 * the host as much as the builder. */
#define SCALING_BIG_PRIMS 500000
#define SCALING_BIG_REPEAT 2

#define MAX_KINDS (BSP_ACCEL_KIND_COUNT + ACCEL_VARIANTS) /* every kind, and the variants' names */

typedef struct scaling_opts {
    accel_method kinds[MAX_KINDS];
    int nkinds;
    bench_cmdline cl;
} scaling_opts;

/* The figures of one scene x method. */
typedef struct scaling_row {
    const char *scene;
    accel_method method;
    size_t n;
    int builds;         /* builds per thread count */
    double t1_cpu;      /* best build, 1 thread, its CPU time */
    double t1_first;    /* the first of those builds' CPU time: with fresh memory pages
                           (what a process that builds once pays) */
    double t1_wall;     /* best build, 1 thread, wall clock */
    double tn_wall;     /* best build, --threads threads, wall clock */
    bsp_tree_stats tree; /* the first build's (one thread); every build must match its digest */
    int mismatch;        /* a build made another tree (the thread counts' trees differ) */
} scaling_row;

static void print_help(void)
{
    printf("usage: %s\n\n"
           "Build-time scaling of the kd-tree construction: for every scene and method the\n"
           "build time on one thread, per primitive, and on all threads, with the tree's\n"
           "figures; then, per generator, how the time per primitive grows from the\n"
           "smallest to the largest scene (O(N log N): like log N, ~1.5x from 10^4 to 10^6).\n"
           "Markdown on stdout, progress on stderr. The trees are not validated here\n"
           "(plain 'bspray bench' does that).\n"
           "\n"
           "  SCENE...        scenes (files or spd:NAME[:SIZE]); default: spd:balls:4..6\n"
           "                  (7,382 to 597,872 spheres) and spd:tetra:7..10 (16,384 to\n"
           "                  1,048,576 triangles); about 2 minutes on 2 cores\n"
           "  --accel LIST    comma-separated methods (default sah; kaplan and the view\n"
           "                  rules sah-per, sah-par, sah-mixed too; not naive)\n"
           "  --repeat N      the best of N builds per thread count (default 3; scenes of\n"
           "                  more than %d primitives get %d unless --repeat is given)\n"
           "  --threads N     the all-threads build uses N threads (default: all cores)\n"
           "  --csv FILE      also write one CSV row per scene x method\n"
           "  --plot FILE.png also draw the series: us/prim against N (log scale), one\n"
           "                  line per generator and method, each with a dashed line of\n"
           "                  how an O(N log N) build would grow from its smallest scene,\n"
           "                  and a grey dashed line at 1 us (a million per second)\n"
           "  --quiet         no progress lines on stderr\n"
           "  --costs LIST, --empty-bonus F, --min-saving X, --leaf-budget X, --leaf-budget-min N,\n"
           "                 --budget-cut F|off  the SAH model (see\n"
           "                 'bspray render --help')\n"
           "\n"
           "Columns (CSV names in brackets):\n"
           "  N [N]           primitives of the scene\n"
           "  T_B 1t [T_B_1t] seconds of the best single-threaded build, the CPU time of\n"
           "                  the building thread\n"
           "  us/prim [us_per_prim]  T_B 1t per primitive, in microseconds\n"
           "  Mprim/s [Mprim_per_s]  primitives per second of T_B 1t, in millions\n"
           "  first 1t [T_B_1t_first]  the first of the single-threaded builds, which\n"
           "                  writes memory the process may never have written: what one\n"
           "                  build in a fresh process costs, page faults included\n"
           "  T_B Nt wall [T_B_nt]  seconds of the best build on N threads, wall clock\n"
           "                  [threads: N]; with --threads 1, the wall time of the\n"
           "                  single-threaded builds\n"
           "  speed-up        T_B Nt against the best single-threaded build's wall time\n"
           "                  [speedup]; kaplan builds on one thread whatever N\n"
           "  N_IN, N_V, N_OIV  interior nodes, leaves, primitive references in leaves\n"
           "  cost [cost]     the finished tree's expected SAH cost\n"
           "  MB [bytes]      the tree's memory: nodes, leaf index lists and the\n"
           "                  traversal's leaf-ordered copy of the primitives\n"
           "  [builds]        builds timed per thread count\n"
           "  [digest]        the tree's digest (bspray stats); every build, on any thread\n"
           "                  count, must make the same tree, or the run stops (exit 1)\n"
           "The summary: per generator and method, us/prim of the largest scene over that\n"
           "of the smallest, next to ln N of the largest over ln N of the smallest.\n",
           scaling_usage, SCALING_BIG_PRIMS, SCALING_BIG_REPEAT);
}

/* The best of R->builds builds of KIND on THREADS threads: CPU and wall
 * seconds into *CPU and *WALL, the tree's figures into R->tree. */
static void timed_builds(const scaling_opts *o, const bsp_scene *scene, scaling_row *r,
                         int threads, double *cpu, double *wall)
{
    bsp_build_options bo;
    bsp_build_options_defaults(&bo);
    apply_method(&r->method, &bo);
    bo.threads = threads;
    apply_cost_args(&o->cl.costs, &bo);
    *cpu = *wall = INFINITY;
    for (int rep = 0; rep < r->builds; rep++) {
        if (!o->cl.quiet)
            fprintf(stderr, "%s: %s (%zu primitives): %s: build %d of %d on %d thread%s\n", prog,
                    r->scene, r->n, accel_method_name(&r->method), rep + 1, r->builds, threads,
                    threads == 1 ? "" : "s");
        double c0 = bench_cpu_seconds();
        bsp_accel *accel = build_accel(scene, &bo);
        double c = bench_cpu_seconds() - c0;
        double w = bsp_accel_build_seconds(accel);
        *cpu = c < *cpu ? c : *cpu;
        *wall = w < *wall ? w : *wall;
        bsp_tree_stats ts; /* after the timing: every build's tree is checked */
        bsp_accel_tree_stats(accel, &ts);
        if (threads == 1 && rep == 0) {
            r->tree = ts;
            r->t1_first = c;
        } else if (ts.digest != r->tree.digest)
            r->mismatch = 1;
        bsp_accel_destroy(accel);
    }
}

static void measure(const scaling_opts *o, const bsp_scene *scene, scaling_row *r)
{
    r->builds = o->cl.repeat;
    if (!o->cl.repeat_given && r->n > SCALING_BIG_PRIMS && r->builds > SCALING_BIG_REPEAT)
        r->builds = SCALING_BIG_REPEAT;
    timed_builds(o, scene, r, 1, &r->t1_cpu, &r->t1_wall);
    r->tn_wall = r->t1_wall;
    if (o->cl.threads > 1 && kind_builds_in_parallel(r->method.kind)) {
        double cpu_unused;
        timed_builds(o, scene, r, o->cl.threads, &cpu_unused, &r->tn_wall);
    }
}

static double us_per_prim(const scaling_row *r)
{
    return r->n ? r->t1_cpu / (double)r->n * 1e6 : 0.0;
}

static double mprim_per_s(const scaling_row *r)
{
    return r->t1_cpu > 0.0 ? (double)r->n / r->t1_cpu * 1e-6 : 0.0;
}

static double speedup(const scaling_row *r)
{
    return r->tn_wall > 0.0 ? r->t1_wall / r->tn_wall : 0.0;
}

static void print_header(int threads)
{
    printf("| scene | accel | N | T_B 1t [s] | µs/prim | Mprim/s | first 1t [s] | T_B %dt wall [s] | "
           "speed-up | N_IN | N_V | N_OIV | cost | MB |\n",
           threads);
    printf("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
}

static void print_row(const scaling_row *r)
{
    char cost[32] = "–"; /* a grid has no SAH cost */
    if (isfinite(r->tree.expected_cost))
        snprintf(cost, sizeof cost, "%.2f", r->tree.expected_cost);
    printf("| %s | %s | %zu | %.4g | %.3f | %.2f | %.4g | %.4g | %.2f | %" PRIu64 " | %" PRIu64
           " | %" PRIu64 " | %s | %.2f |\n",
           r->scene, accel_method_name(&r->method), r->n, r->t1_cpu, us_per_prim(r),
           mprim_per_s(r), r->t1_first, r->tn_wall, speedup(r), r->tree.interior_nodes,
           r->tree.leaves, r->tree.references, cost,
           (double)(r->tree.bytes + r->tree.trace_bytes) / (1024.0 * 1024.0));
    fflush(stdout);
}

static void csv_header(FILE *f)
{
    fprintf(f, "scene,accel,N,T_B_1t,us_per_prim,Mprim_per_s,T_B_nt,threads,N_IN,N_V,N_OIV,cost,"
               "bytes,speedup,builds,T_B_1t_first,digest\n");
}

static void csv_row(FILE *f, const scaling_row *r, int threads)
{
    fprintf(f,
            "%s,%s,%zu,%.9f,%.6f,%.4f,%.9f,%d,%" PRIu64 ",%" PRIu64 ",%" PRIu64 ",%.4f,%" PRIu64
            ",%.4f,%d,%.9f,%016" PRIx64 "\n",
            r->scene, accel_method_name(&r->method), r->n, r->t1_cpu, us_per_prim(r),
            mprim_per_s(r), r->tn_wall, threads, r->tree.interior_nodes, r->tree.leaves,
            r->tree.references, r->tree.expected_cost, r->tree.bytes + r->tree.trace_bytes,
            speedup(r), r->builds, r->t1_first, r->tree.digest);
    fflush(f);
}

/* The generator of a scene name: "spd:NAME[:tN]" without its size factor;
 * a file is its own generator. Into BUF. */
static const char *generator_of(const char *scene, char *buf, size_t size)
{
    snprintf(buf, size, "%s", scene);
    if (strncmp(buf, "spd:", 4) == 0) {
        char *colon = strchr(buf + 4, ':');
        if (colon && colon[1] >= '0' && colon[1] <= '9') {
            char *next = strchr(colon + 1, ':'); /* ":tN" stays */
            memmove(colon, next ? next : colon + strlen(colon), strlen(next ? next : "") + 1);
        }
    }
    return buf;
}

/* The rows of row I's group (its generator, GEN, and method) not yet SEEN:
 * marked in SEEN and listed in ORDER by increasing N (rows of equal N in
 * table order); returns how many. */
static size_t take_group(const scaling_row *rows, int nrows, int i, char *seen, int *order,
                         char *gen, size_t gen_size)
{
    char gj[256];
    generator_of(rows[i].scene, gen, gen_size);
    size_t m = 0;
    for (int j = i; j < nrows; j++) {
        if (seen[j] || rows[j].method.kind != rows[i].method.kind ||
            rows[j].method.variant != rows[i].method.variant ||
            strcmp(generator_of(rows[j].scene, gj, sizeof gj), gen))
            continue;
        seen[j] = 1;
        size_t at = m++;
        while (at > 0 && rows[order[at - 1]].n > rows[j].n) {
            order[at] = order[at - 1];
            at--;
        }
        order[at] = j;
    }
    return m;
}

/* Per generator x method with at least two sizes: the growth of µs/prim
 * from the smallest to the largest scene. */
static void print_summary(const scaling_row *rows, int nrows)
{
    int printed = 0;
    char *seen = calloc((size_t)nrows + 1, 1);
    int *order = calloc((size_t)nrows + 1, sizeof *order);
    for (int i = 0; seen && order && i < nrows; i++) {
        if (seen[i])
            continue;
        char gi[256];
        size_t m = take_group(rows, nrows, i, seen, order, gi, sizeof gi);
        size_t top = m - 1; /* the first of the largest scenes */
        while (top > 0 && rows[order[top - 1]].n == rows[order[m - 1]].n)
            top--;
        const int lo = order[0], hi = order[top];
        if (m < 2 || rows[lo].n == rows[hi].n || rows[lo].n < 2)
            continue;
        if (!printed) {
            printf("\n| generator | accel | N smallest → largest | µs/prim smallest → largest | "
                   "µs/prim growth | ln N growth |\n");
            printf("|---|---|---:|---:|---:|---:|\n");
            printed = 1;
        }
        double ua = us_per_prim(&rows[lo]), ub = us_per_prim(&rows[hi]);
        printf("| %s | %s | %zu → %zu | %.3f → %.3f | %.2fx | %.2fx |\n", gi,
               accel_method_name(&rows[i].method), rows[lo].n, rows[hi].n, ua, ub,
               ua > 0.0 ? ub / ua : 0.0, log((double)rows[hi].n) / log((double)rows[lo].n));
    }
    free(seen);
    free(order);
}

/* --plot: us/prim against N per generator x method (the rows of one group in
 * increasing N), and for a group of two sizes or more a dashed line from its
 * smallest scene growing like ln N, what an O(N log N) build does. 0 when the
 * file could not be written (with a message). */
static int write_plot(const char *path, const scaling_row *rows, int nrows)
{
    const size_t nr = (size_t)nrows;
    plot_series *series = calloc(2 * nr + 1, sizeof *series);
    double *xs = calloc(nr + 1, sizeof *xs), *ys = calloc(2 * nr + 1, sizeof *ys);
    char(*names)[160] = calloc(2 * nr + 1, sizeof *names);
    int *order = calloc(nr + 1, sizeof *order);
    char *seen = calloc(nr + 1, 1);
    int ok = series && xs && ys && names && order && seen;
    size_t ns = 0, nx = 0, ny = 0; /* series, and values used in XS and YS */
    int group = 0;
    for (int i = 0; ok && i < nrows; i++) {
        if (seen[i])
            continue;
        char gi[128];
        size_t m = take_group(rows, nrows, i, seen, order, gi, sizeof gi);
        double *x = xs + nx, *y = ys + ny;
        for (size_t k = 0; k < m; k++) {
            x[k] = (double)rows[order[k]].n;
            y[k] = us_per_prim(&rows[order[k]]);
        }
        nx += m;
        ny += m;
        snprintf(names[ns], sizeof names[ns], "%s %s", gi, accel_method_name(&rows[i].method));
        series[ns] = (plot_series){names[ns], x, y, m, 0, group};
        ns++;
        if (m >= 2 && x[0] >= 2.0) { /* its ln N line, through the same N */
            double *ry = ys + ny;
            for (size_t k = 0; k < m; k++)
                ry[k] = y[0] * log(x[k]) / log(x[0]);
            ny += m;
            snprintf(names[ns], sizeof names[ns], "%s: LN N", gi);
            series[ns] = (plot_series){names[ns], x, ry, m, 1, group};
            ns++;
        }
        group++;
    }
    /* the target of issue #3: a million primitives per second, 1 us each */
    double target_x[2] = {INFINITY, -INFINITY}, target_y[2] = {1.0, 1.0};
    for (int i = 0; i < nrows; i++) {
        target_x[0] = fmin(target_x[0], (double)rows[i].n);
        target_x[1] = fmax(target_x[1], (double)rows[i].n);
    }
    if (ok && nrows > 0)
        series[ns++] = (plot_series){"1M PRIMITIVES/S", target_x, target_y, 2, 1, 7};
    int rc = 1;
    if (!ok) {
        fprintf(stderr, "%s: %s: out of memory\n", prog, path);
        rc = 0;
    } else {
        plot_chart c = {"BUILD TIME PER PRIMITIVE, ONE THREAD",
                        {"PRIMITIVES N (LOG SCALE)", 1, 0.0, 0.0},
                        {"MICROSECONDS PER PRIMITIVE", 0, 0.0, 0.0},
                        series,
                        ns,
                        NULL,
                        0};
        plot_fit_axes(&c);
        bsp_error err;
        if (plot_write_png(&c, 960, 640, path, &err) != BSP_OK) {
            fprintf(stderr, "%s: %s\n", prog, err.message);
            rc = 0;
        }
    }
    free(series);
    free(xs);
    free(ys);
    free(names);
    free(order);
    free(seen);
    return rc;
}

/* --scaling's own option: --accel, trees only. */
static int scaling_option(args *a, const char *s, void *ctx)
{
    scaling_opts *o = ctx;
    if (strcmp(s, "--accel"))
        return 0;
    o->nkinds = parse_accel_list(a, opt_value(a, s), o->kinds, MAX_KINDS);
    for (int k = 0; k < o->nkinds; k++)
        if (o->kinds[k].kind == BSP_ACCEL_NAIVE)
            die_usage(a->usage, "%s", "--scaling times tree builds; naive has none");
    return 1;
}

int bench_scaling(int argc, char **argv)
{
    args a = {argc, 1, argv, scaling_usage, NULL};
    scaling_opts o;
    memset(&o, 0, sizeof o);
    o.kinds[o.nkinds++] = (accel_method){BSP_ACCEL_SAH, 0};
    bench_cmdline_init(&o.cl, BENCH_TAKES_REPEAT | BENCH_TAKES_COSTS | BENCH_TAKES_PLOT,
                       "--scaling", bench_scaling_default_scenes);
    if (bench_read_cmdline(&a, &o.cl, scaling_option, &o, print_help))
        return 0;
    FILE *csv;
    if (!bench_cmdline_ready(&o.cl, 1, &csv))
        return EXIT_INPUT;
    const char **scenes = o.cl.scenes;
    int nscenes = o.cl.nscenes;
    const char *csv_path = o.cl.csv_path, *plot_path = o.cl.plot_path;
    scaling_row *rows = calloc((size_t)nscenes * (size_t)o.nkinds, sizeof *rows);
    if (!rows) {
        fprintf(stderr, "%s: out of memory\n", prog);
        if (csv)
            fclose(csv);
        bench_free_cmdline(&o.cl);
        return EXIT_INPUT;
    }
    if (csv)
        csv_header(csv);
    printf("## Build-time scaling (T_B 1t: best single-threaded build, thread CPU time; "
           "T_B %dt wall: wall clock)\n\n",
           o.cl.threads);
    print_header(o.cl.threads);
    int nrows = 0, mismatch = 0;
    for (int s = 0; s < nscenes; s++) {
        bsp_scene *scene = load_scene(scenes[s]); /* exits 1 with a message */
        for (int k = 0; k < o.nkinds; k++) {
            scaling_row *r = &rows[nrows++];
            r->scene = scenes[s];
            r->method = o.kinds[k];
            r->n = bsp_scene_prim_count(scene);
            measure(&o, scene, r);
            print_row(r);
            if (csv)
                csv_row(csv, r, o.cl.threads);
            if (r->mismatch) {
                fprintf(stderr,
                        "%s: %s: %s: the builds made different trees (1 and %d threads, "
                        "or repeated builds): the build is not deterministic\n",
                        prog, r->scene, accel_method_name(&r->method), o.cl.threads);
                mismatch = 1;
            }
        }
        bsp_scene_destroy(scene);
        if (mismatch)
            break;
    }
    if (!mismatch)
        print_summary(rows, nrows);
    int rc = mismatch ? EXIT_INPUT : 0;
    if (!mismatch && plot_path && !write_plot(plot_path, rows, nrows))
        rc = EXIT_INPUT;
    if (csv && !close_output(csv, csv_path))
        rc = EXIT_INPUT;
    free(rows);
    bench_free_cmdline(&o.cl);
    return rc;
}
