/*
 * bench.c — `bspray bench`: build, validate and time acceleration methods on
 * scenes, and print Havran's figures as a Markdown table (and CSV).
 *
 * For each scene x method:
 *   1. build (T_B) and take the tree's figures (N_IN, N_V, N_EV, N_OIV, bytes);
 *   2. validate before timing: seeded random rays around the scene and the
 *      camera's primary rays are shot with the method and with the naive
 *      method; any difference (primitive, bit-identical t, occlusion) aborts;
 *   3. render once single-threaded while recording every ray by class, and
 *      take the per-ray figures N_IT, N_TS, N_ETS, N_EETS;
 *   4. time renders without the recording: T_TR 1t and T_TR Nt, each the
 *      best of --repeat renders (default 3; one render is disturbed easily
 *      on a shared machine), on one thread by its CPU time;
 *   5. shoot the recorded primary, shadow and secondary rays alone, with 1
 *      and with all threads, for the pure ray-shooting throughput of each
 *      class (closest hit for primary and secondary rays, any hit for shadow
 *      rays), in Mrays/s, the best of three passes.
 * Times on all threads are wall-clock seconds on a monotonic clock; times
 * on one thread are its CPU time. Single-thread figures are the ones to
 * compare across machines.
 */
#include <errno.h>
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bench.h"
#include "cli.h"
#include "render/plot.h"

static const char bench_usage[] =
    "bspray bench [SCENE...] [--accel LIST] [--res N] [--depth N] [--threads N]\n"
    "                        [--mailbox on|off] [--validate N] [--repeat N] [--csv FILE]\n"
    "                        [--plot FILE.png] [--quiet] [--grid-* ...] [--octree-split S]\n"
    "       bspray bench --paper [SCENE...] [--accel LIST] [--csv FILE] ...  (see --paper --help)\n"
    "       bspray bench --scaling [SCENE...] [--accel LIST] [--repeat N] ...  (see --scaling --help)\n"
    "       bspray bench --grids [SCENE...] [--csv FILE] ...  (see --grids --help)\n"
    "       bspray bench --octrees [SCENE...] [--csv FILE] ...  (see --octrees --help)";

/* The default scene list of bench and bench --paper: every SPD database at
 * its default size, teapot at the size of the SPD Readme and Havran's
 * tables; the paper's three SPD scenes first (its fourth, "fluid", is not an
 * SPD database). */
const char *const bench_default_scenes[] = {
    "spd:lattice", "spd:rings", "spd:tree",   "spd:balls",  "spd:gears",
    "spd:mount",   "spd:teapot:12", "spd:tetra", "spd:shells", "spd:jacks",
    "spd:sombrero", "spd:sample", "spd:nurbtst", NULL};

/* naive is benchmarked by default only up to this many primitives */
#define NAIVE_DEFAULT_MAX_PRIMS 2000

static void print_help(void)
{
    printf("usage: %s\n\n"
           "Benchmark acceleration methods: build time and memory, Havran's tree and per-ray\n"
           "figures, render times and ray-shooting throughput per ray class.\n"
           "\n"
           "Every method is validated before it is timed: random rays and the camera's\n"
           "primary rays must give exactly the naive method's answers, or bench stops\n"
           "with exit status 1.\n"
           "\n"
           "  SCENE...          scenes (files or spd:NAME[:SIZE]); default: every SPD scene\n"
           "  --accel LIST      comma-separated methods (default: naive where the scene has\n"
           "                    at most %d primitives, kaplan and sah)\n"
           "  --res N           N x N rays, SPD corner sampling (default 513: Havran's protocol)\n"
           "  --depth N         ray depth (default 4)\n"
           "  --threads N       the 'all threads' figures use N threads (default: all cores)\n"
           "  --mailbox on|off  mailboxes for kd-trees (default on)\n"
           "  --validate N      random rays compared with naive before timing (default 20000)\n"
           "  --repeat N        timed renders per T_TR figure, the best counts (default 3)\n"
           "  --csv FILE        also write one CSV row per scene x method\n"
           "  --plot FILE.png   also draw T_TR 1t per scene and method as bars (log scale)\n"
           "  --quiet           no progress lines on stderr\n"
           "  --costs LIST, --empty-bonus F, --min-saving X, --leaf-budget X, --leaf-budget-min N,\n"
           "                 --budget-cut F|off  the SAH model (see\n"
           "                 'bspray render --help')\n"
           "  --grid-density D, --grid-res X,Y,Z, --grid-assign clipped|bounds, --grid-levels L,\n"
           "                 --grid-cell-prims T  the grid,\n"
           "  --octree-split centre|cost  the octree (see 'bspray render --help')\n"
           "\n"
           "Columns: T_B build seconds on 1 and N threads (the same tree); MB structure size (a\n"
           "kd-tree's nodes, leaf lists and leaf-ordered copy of the primitives);\n"
           "N_V leaves; N_IT intersection tests and N_TS traversal steps per ray (all rays of\n"
           "the render); T_TR render seconds on 1 and N threads (the best of --repeat renders);\n"
           "Mrays/s of pure ray shooting per class on 1 and N threads (the best of 3 passes\n"
           "over the recorded rays, recorded row by row of the image, each pixel's rays depth\n"
           "first; the renders of T_TR trace " STRINGIFY(BSP_RENDER_TILE) " x " STRINGIFY(
               BSP_RENDER_TILE) " tiles). On 1 thread times are its CPU\n"
           "time, on N threads the wall clock.\n",
           bench_usage, NAIVE_DEFAULT_MAX_PRIMS);
}

/* --- recorded rays ------------------------------------------------------------ */

void bench_free_ray_sets(bench_ray_set sets[BSP_RAY_CLASS_COUNT])
{
    for (int c = 0; c < BSP_RAY_CLASS_COUNT; c++) {
        free(sets[c].rays);
        free(sets[c].from);
        sets[c].rays = NULL;
        sets[c].from = NULL;
    }
}

void bench_log_ray(bsp_ray_class cls, const bsp_ray *ray, uint32_t from, void *ctx)
{
    bench_ray_set *set = &((bench_ray_set *)ctx)[cls];
    if (set->failed)
        return;
    if (set->n == set->cap) {
        size_t ncap = set->cap ? set->cap * 2 : 1 << 16;
        bsp_ray *nr = realloc(set->rays, ncap * sizeof *nr);
        if (nr)
            set->rays = nr;
        uint32_t *nf = nr ? realloc(set->from, ncap * sizeof *nf) : NULL;
        if (nf)
            set->from = nf;
        if (!nr || !nf) {
            set->failed = 1;
            return;
        }
        set->cap = ncap;
    }
    set->from[set->n] = from;
    set->rays[set->n++] = *ray;
}

/* --- timed shooting of a ray set -------------------------------------------- */

double bench_cpu_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Passes over a recorded ray set; bench reports the fastest. */
#define SHOOT_REPEATS 3

/* Mrays/s of shooting SET with THREADS threads (bsp_intersect_batch or
 * bsp_occluded_batch, into HITS or OCC, of room for SET->n answers); 0 when
 * the set is empty or the batch fails. */
static double shoot_rate(const bsp_accel *accel, const bench_ray_set *set, int any, int threads,
                         bsp_hit *hits, unsigned char *occ)
{
    if (set->n == 0)
        return 0.0;
    /* one thread: its CPU time, steadier than the wall clock on a shared
     * machine (time the thread spends descheduled is not its own) */
    const int cpu = threads == 1;
    double t0 = cpu ? bench_cpu_seconds() : now_seconds();
    bsp_error err;
    bsp_status st = any ? bsp_occluded_batch(accel, set->rays, set->from, set->n, threads, occ,
                                             NULL, &err)
                        : bsp_intersect_batch(accel, set->rays, set->from, set->n, threads, hits,
                                              NULL, &err);
    double dt = (cpu ? bench_cpu_seconds() : now_seconds()) - t0;
    if (st != BSP_OK) {
        fprintf(stderr, "%s: %s\n", prog, err.message);
        return 0.0;
    }
    return dt > 0 ? (double)set->n / dt * 1e-6 : 0.0;
}

/* --- validation -------------------------------------------------------------- */

static uint64_t rng_state;
static double rnd(void)
{
    rng_state ^= rng_state >> 12;
    rng_state ^= rng_state << 25;
    rng_state ^= rng_state >> 27;
    return (double)((rng_state * 2685821657736338717ULL) >> 11) * (1.0 / 9007199254740992.0);
}

static int same_answer(const bsp_accel *a, bsp_query *qa, const bsp_accel *n, bsp_query *qn,
                       const bsp_ray *r)
{
    bsp_hit ha, hn;
    int fa = bsp_intersect(a, qa, r, &ha), fn = bsp_intersect(n, qn, r, &hn);
    if (fa != fn || (fa && (ha.prim != hn.prim || memcmp(&ha.t, &hn.t, sizeof ha.t) != 0)))
        return 0;
    return bsp_occluded(a, qa, r) == bsp_occluded(n, qn, r);
}

/* Compares ACCEL with NAIVE on NRAND random rays and on a grid of primary
 * rays; returns the number of rays checked, or -1 on the first difference
 * (described in *WHAT). */
long bench_validate(const bsp_accel *accel, const bsp_accel *naive, const bsp_scene *scene,
                    int nrand, char *what, size_t what_size)
{
    bsp_query *qa = bsp_query_create(accel), *qn = bsp_query_create(naive);
    if (!qa || !qn) {
        bsp_query_destroy(qa);
        bsp_query_destroy(qn);
        snprintf(what, what_size, "out of memory");
        return -1;
    }
    bsp_box b = bsp_scene_bounds(scene);
    if (b.lo.x > b.hi.x)
        b.lo = bsp_v3(-1, -1, -1), b.hi = bsp_v3(1, 1, 1);
    rng_state = 0x9E3779B97F4A7C15ULL;
    long checked = 0;
    for (int i = 0; i < nrand; i++, checked++) {
        bsp_ray r;
        for (int k = 0; k < 3; k++) {
            double c = 0.5 * (b.lo.v[k] + b.hi.v[k]), h = 0.5 * (b.hi.v[k] - b.lo.v[k]) + 1e-3;
            r.org.v[k] = c + (rnd() * 3.0 - 1.5) * h;
            r.dir.v[k] = rnd() * 2.0 - 1.0;
        }
        if (i % 7 == 0) /* axis-aligned */
            for (int k = 0; k < 3; k++)
                r.dir.v[k] = k == i % 3 ? 1.0 : 0.0;
        r.tmin = 0;
        r.tmax = INFINITY;
        if (!same_answer(accel, qa, naive, qn, &r)) {
            snprintf(what, what_size, "random ray %d (%.17g %.17g %.17g  %.17g %.17g %.17g)", i,
                     r.org.x, r.org.y, r.org.z, r.dir.x, r.dir.y, r.dir.z);
            checked = -1;
            break;
        }
    }
    const bsp_camera *cam = bsp_scene_camera(scene);
    if (checked >= 0 && cam) {
        /* a 64 x 64 grid of eye rays through the view */
        bsp_vec3 f = {{cam->at.x - cam->from.x, cam->at.y - cam->from.y, cam->at.z - cam->from.z}};
        double lf = sqrt(f.x * f.x + f.y * f.y + f.z * f.z);
        bsp_vec3 u = cam->up;
        bsp_vec3 rgt = {{f.y * u.z - f.z * u.y, f.z * u.x - f.x * u.z, f.x * u.y - f.y * u.x}};
        double lr = sqrt(rgt.x * rgt.x + rgt.y * rgt.y + rgt.z * rgt.z);
        bsp_vec3 up = {{rgt.y * f.z - rgt.z * f.y, rgt.z * f.x - rgt.x * f.z,
                        rgt.x * f.y - rgt.y * f.x}};
        double lu = sqrt(up.x * up.x + up.y * up.y + up.z * up.z);
        double half = tan(cam->angle_deg * 3.14159265358979323846 / 360.0);
        for (int y = 0; y < 64 && checked >= 0; y++)
            for (int x = 0; x < 64; x++, checked++) {
                double sx = (2.0 * x / 63.0 - 1.0) * half, sy = (1.0 - 2.0 * y / 63.0) * half;
                bsp_ray r;
                r.org = cam->from;
                for (int k = 0; k < 3; k++)
                    r.dir.v[k] = f.v[k] / lf + sx * rgt.v[k] / lr + sy * up.v[k] / lu;
                r.tmin = 0;
                r.tmax = INFINITY;
                if (!same_answer(accel, qa, naive, qn, &r)) {
                    snprintf(what, what_size, "eye ray (%d, %d)", x, y);
                    checked = -1;
                    break;
                }
            }
    }
    bsp_query_destroy(qa);
    bsp_query_destroy(qn);
    return checked;
}

/* --- the benchmark ---------------------------------------------------------------- */

/* every kind, and the variants' names (accel_method) */
#define BENCH_MAX_METHODS (BSP_ACCEL_KIND_COUNT + ACCEL_VARIANTS)

typedef struct bench_opts {
    bench_cmdline cl; /* repeat: timed renders per figure; T_TR is the best */
    accel_method methods[BENCH_MAX_METHODS];
    int nmethods, methods_given;
    FILE *csv;
} bench_opts;

typedef struct bench_row {
    const char *scene;
    size_t nprims;
    const char *method; /* method_label of its build */
    int method_index;   /* in bench_opts.methods */
    double t_build, mbytes;
    bsp_tree_stats tree;
    double n_it, n_ts, n_ets, n_eets;
    uint64_t rays[BSP_RAY_CLASS_COUNT];
    double t_tr1, t_trn;
    double rate1[BSP_RAY_CLASS_COUNT], raten[BSP_RAY_CLASS_COUNT];
    long validated;
    double t_build_n; /* T_B on all threads (the same tree) */
} bench_row;

static void print_header(int threads)
{
    printf("| scene | N | method | T_B 1t / %dt[s] | MB | N_V | N_IT | N_TS | T_TR 1t[s] | T_TR "
           "%dt[s] | primary Mrays/s 1t / %dt | shadow Mrays/s 1t / %dt | secondary Mrays/s 1t "
           "/ %dt |\n",
           threads, threads, threads, threads, threads);
    printf("|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
}

static void print_rate(double r1, double rn, uint64_t n)
{
    if (n == 0)
        printf(" – |");
    else
        printf(" %.2f / %.2f |", r1, rn);
}

static void print_row(const bench_row *r)
{
    printf("| %s | %zu | %s | %.3f / %.3f | %.2f | %" PRIu64 " | %.2f | %.2f | %.2f | %.2f |",
           r->scene, r->nprims, r->method, r->t_build, r->t_build_n, r->mbytes, r->tree.leaves,
           r->n_it, r->n_ts, r->t_tr1, r->t_trn);
    for (int c = 0; c < BSP_RAY_CLASS_COUNT; c++)
        print_rate(r->rate1[c], r->raten[c], r->rays[c]);
    printf("\n");
    fflush(stdout);
}

static void csv_header(FILE *f)
{
    fprintf(f, "scene,N,accel,T_B,bytes,N_IN,N_V,N_EV,N_OIV,max_depth,expected_cost,N_IT,N_TS,"
               "N_ETS,N_EETS,primary_rays,shadow_rays,secondary_rays,T_TR_1t,T_TR_all,threads,"
               "primary_Mrays_1t,primary_Mrays_all,shadow_Mrays_1t,shadow_Mrays_all,"
               "secondary_Mrays_1t,secondary_Mrays_all,validated_rays,T_B_all,model_cost,digest\n");
}

static void csv_row(FILE *f, const bench_row *r, int threads)
{
    fprintf(f,
            "%s,%zu,%s,%.6f,%" PRIu64 ",%" PRIu64 ",%" PRIu64 ",%" PRIu64 ",%" PRIu64
            ",%d,%.4f,%.4f,%.4f,%.4f,%.4f,%" PRIu64 ",%" PRIu64 ",%" PRIu64 ",%.4f,%.4f,%d",
            r->scene, r->nprims, r->method, r->t_build, r->tree.bytes, r->tree.interior_nodes,
            r->tree.leaves, r->tree.empty_leaves, r->tree.references, r->tree.max_leaf_depth,
            r->tree.expected_cost, r->n_it, r->n_ts, r->n_ets, r->n_eets,
            r->rays[BSP_RAY_PRIMARY], r->rays[BSP_RAY_SHADOW], r->rays[BSP_RAY_SECONDARY],
            r->t_tr1, r->t_trn, threads);
    for (int c = 0; c < BSP_RAY_CLASS_COUNT; c++)
        fprintf(f, ",%.4f,%.4f", r->rate1[c], r->raten[c]);
    fprintf(f, ",%ld,%.6f,%.4f,", r->validated, r->t_build_n, r->tree.model_cost);
    if (r->tree.leaves) /* a tree (bsp_tree_stats.digest); the naive method has none */
        fprintf(f, "%016" PRIx64, r->tree.digest);
    fprintf(f, "\n");
    fflush(f);
}

/* Benchmarks one method on SCENE into *OUT; returns 0, or 1 when validation
 * failed. */
static int bench_method(const bench_opts *o, const char *scene_name, const bsp_scene *scene,
                        const bsp_accel *naive, int method_index, bench_row *out)
{
    bench_row row;
    memset(&row, 0, sizeof row);
    row.scene = scene_name;
    row.nprims = bsp_scene_prim_count(scene);
    bsp_build_options bo;
    bsp_build_options_defaults(&bo);
    bo.mailbox = o->cl.mailbox;
    apply_cost_args(&o->cl.costs, &bo);
    apply_subdivision_args(&o->cl.cells, &bo);
    apply_method(&o->methods[method_index], &bo); /* a variant's name wins over the options */
    const bsp_accel_kind kind = bo.kind;
    row.method = method_label(&bo);
    row.method_index = method_index;
    if (!o->cl.quiet)
        fprintf(stderr, "%s: %s: %s: building\n", prog, scene_name, row.method);
    bo.threads = 1; /* T_B is the single-threaded build */
    bsp_accel *accel = build_accel(scene, &bo);
    row.t_build = bsp_accel_build_seconds(accel);
    row.t_build_n = row.t_build;
    bsp_accel_tree_stats(accel, &row.tree);
    if (o->cl.threads > 1 && kind_builds_in_parallel(kind)) {
        bo.threads = o->cl.threads; /* the same tree, on all threads: checked by its digest */
        bsp_accel *again = build_accel(scene, &bo);
        row.t_build_n = bsp_accel_build_seconds(again);
        bsp_tree_stats ts;
        bsp_accel_tree_stats(again, &ts);
        bsp_accel_destroy(again);
        if (ts.digest != row.tree.digest) {
            fprintf(stderr,
                    "%s: %s: %s built another tree on %d threads than on one (digests "
                    "%016" PRIx64 ", %016" PRIx64 "); aborting\n",
                    prog, scene_name, row.method, o->cl.threads, ts.digest, row.tree.digest);
            bsp_accel_destroy(accel);
            return 1;
        }
    }
    row.mbytes = (double)(row.tree.bytes + row.tree.trace_bytes) / (1024.0 * 1024.0);

    if (kind != BSP_ACCEL_NAIVE) {
        char what[256];
        row.validated = bench_validate(accel, naive, scene, o->cl.nvalidate, what, sizeof what);
        if (row.validated < 0) {
            fprintf(stderr, "%s: %s: %s differs from the naive method on %s; aborting\n", prog,
                    scene_name, row.method, what);
            bsp_accel_destroy(accel);
            return 1;
        }
    }

    bench_ray_set sets[BSP_RAY_CLASS_COUNT];
    memset(sets, 0, sizeof sets);
    bsp_render_options ro;
    bsp_render_options_defaults(&ro);
    ro.width = ro.height = o->cl.res;
    ro.max_depth = o->cl.depth;
    ro.threads = 1;
    /* the rays recorded row by row: the ray order every session's figures
     * and bspray-embree use; the timed renders below trace in tiles */
    ro.pixel_order = BSP_PIXELS_ROWS;
    ro.ray_log = bench_log_ray;
    ro.ray_log_ctx = sets;
    bsp_image *img = NULL;
    bsp_render_stats st;
    bsp_error err;
    if (!o->cl.quiet)
        fprintf(stderr, "%s: %s: %s: rendering\n", prog, scene_name, row.method);
    if (bsp_render(accel, &ro, &img, &st, &err) != BSP_OK) {
        fprintf(stderr, "%s: %s: %s\n", prog, scene_name, err.message);
        bsp_accel_destroy(accel);
        bench_free_ray_sets(sets);
        return 1;
    }
    bsp_image_destroy(img);
    uint64_t all = 0, tests = 0, steps = 0, ets = 0, eets = 0;
    for (int c = 0; c < BSP_RAY_CLASS_COUNT; c++) {
        row.rays[c] = st.cls[c].rays;
        all += st.cls[c].rays;
        tests += st.cls[c].isect_tests;
        steps += st.cls[c].traversal_steps;
        ets += st.cls[c].leaves_visited;
        eets += st.cls[c].empty_leaves;
    }
    if (all) {
        row.n_it = (double)tests / (double)all;
        row.n_ts = (double)steps / (double)all;
        row.n_ets = (double)ets / (double)all;
        row.n_eets = (double)eets / (double)all;
    }
    /* the timed renders: no recording; one thread (the calling one) by its
     * CPU time, time descheduled not being its own */
    ro.ray_log = NULL;
    ro.pixel_order = BSP_PIXELS_TILES;
    row.t_tr1 = row.t_trn = INFINITY;
    for (int rep = 0; rep < o->cl.repeat; rep++) {
        ro.threads = 1;
        double c0 = bench_cpu_seconds();
        bsp_status rs = bsp_render(accel, &ro, &img, NULL, &err);
        double dt = bench_cpu_seconds() - c0;
        if (rs == BSP_OK) {
            bsp_image_destroy(img);
            ro.threads = o->cl.threads;
            rs = bsp_render(accel, &ro, &img, &st, &err);
        }
        if (rs != BSP_OK) {
            fprintf(stderr, "%s: %s: %s\n", prog, scene_name, err.message);
            bsp_accel_destroy(accel);
            bench_free_ray_sets(sets);
            return 1;
        }
        bsp_image_destroy(img);
        row.t_tr1 = dt < row.t_tr1 ? dt : row.t_tr1;
        row.t_trn = st.render_seconds < row.t_trn ? st.render_seconds : row.t_trn;
    }
    for (int c = 0; c < BSP_RAY_CLASS_COUNT; c++) {
        if (sets[c].failed) {
            fprintf(stderr, "%s: out of memory recording rays\n", prog);
            continue;
        }
        int any = c == BSP_RAY_SHADOW;
        bsp_hit *hits = any ? NULL : malloc(sets[c].n * sizeof *hits);
        unsigned char *occ = any ? malloc(sets[c].n) : NULL;
        if (sets[c].n > 0 && !hits && !occ) {
            fprintf(stderr, "%s: out of memory for the answers of %zu rays\n", prog, sets[c].n);
            continue;
        }
        /* best of SHOOT_REPEATS: one pass takes well under a second, and
         * a shared machine disturbs single passes */
        for (int rep = 0; rep < SHOOT_REPEATS; rep++) {
            double r1 = shoot_rate(accel, &sets[c], any, 1, hits, occ);
            double rn = shoot_rate(accel, &sets[c], any, o->cl.threads, hits, occ);
            row.rate1[c] = r1 > row.rate1[c] ? r1 : row.rate1[c];
            row.raten[c] = rn > row.raten[c] ? rn : row.raten[c];
        }
        free(hits);
        free(occ);
    }
    bench_free_ray_sets(sets);
    print_row(&row);
    if (o->csv)
        csv_row(o->csv, &row, o->cl.threads);
    bsp_accel_destroy(accel);
    *out = row;
    return 0;
}

int bench_write_bars(const char *path, const char *title, const char *ylabel,
                     const char *const *scenes, size_t nscenes, const char *const *names,
                     size_t nseries, const double *values)
{
    const char **cats = calloc(nscenes + 1, sizeof *cats);
    plot_series *series = calloc(nseries + 1, sizeof *series);
    int rc = 1;
    if (!cats || !series) {
        fprintf(stderr, "%s: %s: out of memory\n", prog, path);
        rc = 0;
    } else {
        for (size_t c = 0; c < nscenes; c++) /* "spd:balls" is "balls" under its bars */
            cats[c] = strncmp(scenes[c], "spd:", 4) ? scenes[c] : scenes[c] + 4;
        for (size_t k = 0; k < nseries; k++)
            series[k] = (plot_series){names[k], NULL, values + k * nscenes, nscenes, 0, (int)k};
        plot_chart c = {title, {"SCENE", 0, 0.0, 0.0}, {ylabel, 1, 0.0, 0.0}, series, nseries,
                        cats, nscenes};
        plot_fit_axes(&c);
        int width = 140 + 120 * (int)nscenes; /* room for a label like TEAPOT:12 at full size */
        width = width < 960 ? 960 : width > 4000 ? 4000 : width;
        bsp_error err;
        if (plot_write_png(&c, width, 640, path, &err) != BSP_OK) {
            fprintf(stderr, "%s: %s\n", prog, err.message);
            rc = 0;
        }
    }
    free(cats);
    free(series);
    return rc;
}

/* --plot: T_TR 1t of every scene (a group of bars) and method (a bar of its
 * colour), on a log scale: the paper's comparison of rendering times. 0 when
 * the file could not be written (with a message). */
static int write_plot(const char *path, const bench_row *rows, int nrows, const bench_opts *o)
{
    const size_t nr = (size_t)nrows, nk = (size_t)o->nmethods;
    const char **scenes = calloc(nr + 1, sizeof *scenes), **names = calloc(nk + 1, sizeof *names);
    double *t = calloc(nk * (nr + 1), sizeof *t);
    int rc = 0;
    if (!scenes || !names || !t) {
        fprintf(stderr, "%s: %s: out of memory\n", prog, path);
    } else {
        size_t ns = 0;
        for (size_t i = 0; i < nr; i++) /* the scenes, in the order run (a scene's rows are adjacent) */
            if (ns == 0 || strcmp(scenes[ns - 1], rows[i].scene))
                scenes[ns++] = rows[i].scene;
        for (size_t k = 0; k < nk; k++)
            names[k] = accel_method_name(&o->methods[k]);
        for (size_t i = 0; i < nr; i++) /* the names the table gives */
            names[rows[i].method_index] = rows[i].method;
        for (size_t i = 0; i < nk * ns; i++)
            t[i] = NAN; /* no bar: the method did not run on the scene */
        for (size_t i = 0, c = 0; i < nr; i++) {
            c += i > 0 && strcmp(rows[i - 1].scene, rows[i].scene) != 0;
            t[(size_t)rows[i].method_index * ns + c] = rows[i].t_tr1;
        }
        char title[160];
        snprintf(title, sizeof title, "RENDER TIME, ONE THREAD (%d X %d, DEPTH %d)", o->cl.res,
                 o->cl.res, o->cl.depth);
        rc = bench_write_bars(path, title, "SECONDS, LOG SCALE (LOWER IS FASTER)", scenes, ns,
                              names, nk, t);
    }
    free(scenes);
    free(names);
    free(t);
    return rc;
}

/* bench's own option: --accel. */
static int bench_option(args *a, const char *s, void *ctx)
{
    bench_opts *o = ctx;
    if (strcmp(s, "--accel"))
        return 0;
    o->nmethods = parse_accel_list(a, opt_value(a, s), o->methods, BENCH_MAX_METHODS);
    o->methods_given = 1;
    return 1;
}

int cmd_bench(int argc, char **argv)
{
    for (int i = 1; i < argc; i++)
        if (!strcmp(argv[i], "--paper"))
            return bench_paper(argc, argv);
        else if (!strcmp(argv[i], "--scaling"))
            return bench_scaling(argc, argv);
        else if (!strcmp(argv[i], "--grids"))
            return bench_grids(argc, argv);
        else if (!strcmp(argv[i], "--octrees"))
            return bench_octrees(argc, argv);
    args a = {argc, 1, argv, bench_usage, NULL};
    bench_opts o;
    memset(&o, 0, sizeof o);
    bench_cmdline_init(&o.cl,
                       BENCH_TAKES_RENDER | BENCH_TAKES_REPEAT | BENCH_TAKES_COSTS |
                           BENCH_TAKES_PLOT | BENCH_TAKES_CELLS,
                       NULL, bench_default_scenes);
    o.cl.nvalidate = 20000;
    /* the default methods: naive, kaplan, sah (the view rules: --accel, or --paper) */
    for (int k = BSP_ACCEL_NAIVE; k <= BSP_ACCEL_SAH; k++)
        o.methods[o.nmethods++] = (accel_method){(bsp_accel_kind)k, 0};
    if (bench_read_cmdline(&a, &o.cl, bench_option, &o, print_help))
        return 0;
    if (!bench_cmdline_ready(&o.cl, 1, &o.csv))
        return EXIT_INPUT;
    const char **scenes = o.cl.scenes;
    int nscenes = o.cl.nscenes;
    const char *csv_path = o.cl.csv_path, *plot_path = o.cl.plot_path;
    bench_row *rows = calloc((size_t)nscenes * (size_t)o.nmethods + 1, sizeof *rows);
    if (!rows) {
        fprintf(stderr, "%s: out of memory\n", prog);
        if (o.csv)
            fclose(o.csv);
        bench_free_cmdline(&o.cl);
        return EXIT_INPUT;
    }
    if (o.csv)
        csv_header(o.csv);
    print_header(o.cl.threads);
    int rc = 0, nrows = 0;
    for (int i = 0; i < nscenes && rc == 0; i++) {
        bsp_scene *scene = load_scene(scenes[i]);
        if (!bsp_scene_camera(scene)) {
            fprintf(stderr, "%s: %s: no camera; skipped\n", prog, scenes[i]);
            bsp_scene_destroy(scene);
            continue;
        }
        bsp_build_options naive_opts;
        bsp_build_options_defaults(&naive_opts);
        naive_opts.kind = BSP_ACCEL_NAIVE; /* the reference; the default is a tree */
        bsp_accel *naive = build_accel(scene, &naive_opts);
        for (int k = 0; k < o.nmethods && rc == 0; k++) {
            if (o.methods[k].kind == BSP_ACCEL_NAIVE && !o.methods_given &&
                bsp_scene_prim_count(scene) > NAIVE_DEFAULT_MAX_PRIMS)
                continue; /* would not finish in reasonable time */
            rc = bench_method(&o, scenes[i], scene, naive, k, &rows[nrows]);
            nrows += rc == 0;
        }
        bsp_accel_destroy(naive);
        bsp_scene_destroy(scene);
    }
    if (o.csv && !close_output(o.csv, csv_path))
        rc = EXIT_INPUT;
    if (rc == 0 && plot_path && !write_plot(plot_path, rows, nrows, &o))
        rc = EXIT_INPUT;
    free(rows);
    bench_free_cmdline(&o.cl);
    return rc ? EXIT_INPUT : 0;
}
