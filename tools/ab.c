/*
 * ab.c — `bspray ab`: two structures timed on the same rays, side by side.
 *
 * A is the default structure (bsp_build_options_defaults: sah), or the
 * defaults changed by the build options after --a; B is the defaults
 * changed by the other build options on the command line (--accel,
 * --costs, --empty-bonus, --max-depth, ...). The rays of one render are recorded
 * once; then each round shoots them through A and B in alternating slices,
 * the order alternating from slice to slice and from round to round, on one
 * thread, timed by the thread's CPU time. This VM's speed swings within
 * seconds, by more than most changes one wants to measure: rates taken in
 * separate runs (or even separate passes) cannot show a few percent, while
 * two methods that share every slice see the same machine (two identical
 * trees measure within about 0.5 %; docs/kdtree.md).
 *
 * Every ray's answer from B must equal A's (primitive, t bit for bit, the
 * occlusion answer): both are exact, so a difference is a bug, reported
 * with exit status 1.
 */
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench.h"
#include "cli.h"

static const char ab_usage[] =
    "bspray ab SCENE [OPTIONS OF B...] [--a OPTIONS OF A... --b] [--res N] [--depth N]\n"
    "                [--rays primary|all] [--origin skip|test] [--rounds R] [--slice N]";

static const char ab_help[] =
    "Time two structures on the same rays: A, the default (sah with the default costs), and\n"
    "B, A changed by the build options given. The rays of a RES x RES render of SCENE are\n"
    "recorded once (the primary rays, or every ray to --depth); each round then shoots them\n"
    "through A and B in alternating slices, on one thread, by its CPU time, so that both\n"
    "see the same machine. Prints the rays per second of both, B over A (the ratio of the\n"
    "best rounds, and the median of the rounds' ratios), and per ray the traversal steps\n"
    "N_TS, the intersection tests N_IT and the leaves of each tree. Every ray must get the\n"
    "same answer from both (primitive, t, occlusion): exit status 1 if not. With no\n"
    "build option, B is A's very tree (no difference of placement in memory).\n"
    "\n"
    "  --res N            N x N rays, SPD corner sampling (default 513)\n"
    "  --depth N          ray depth of the recorded render with --rays all (default 4)\n"
    "  --rays primary|all the primary rays only (default), or every ray of the render\n"
    "                     (shadow rays as occlusion queries)\n"
    "  --rounds R         rounds (default 5)\n"
    "  --slice N          rays per slice (default 2048)\n"
    "  --origin skip|test B's queries leave out the primitive a shadow or secondary ray\n"
    "                     leaves, as the renderer's do (skip, default; bsp_intersect_from),\n"
    "                     or test it (the plain queries); A always leaves it out\n"
    "  --a, --b           the build options after --a change A instead of B, up to --b;\n"
    "                     e.g. `--a --mailbox off --b --mailbox off --empty-bonus 0.2`\n"
    "                     times two trees without mailboxes against each other\n"
    "\n"
    "Options of B (A keeps the defaults unless given after --a):\n";

/* One ray through ACCEL: its answer as (hit, primitive, t); shadow rays as
 * occlusion queries. */
typedef struct answer {
    int hit;
    uint32_t prim;
    double t;
} answer;

static answer shoot(const bsp_accel *accel, bsp_query *q, const bsp_ray *ray, uint32_t origin,
                    int shadow)
{
    answer a = {0, BSP_NO_PRIM, 0.0};
    if (shadow) {
        a.hit = bsp_occluded_from(accel, q, ray, origin);
        return a;
    }
    bsp_hit h;
    a.hit = bsp_intersect_from(accel, q, ray, origin, &h);
    if (a.hit) {
        a.prim = h.prim;
        a.t = h.t;
    }
    return a;
}

/* CPU seconds of shooting SET's rays [from..to) through ACCEL (SHADOW: as
 * occlusion queries; ORIGIN: each leaving out its origin primitive,
 * set->from, else testing it). The calls update the query's counters, so
 * they stay. */
static double slice_seconds(const bsp_accel *accel, bsp_query *q, const bench_ray_set *set,
                            size_t from, size_t to, int shadow, int origin)
{
    double t0 = bench_cpu_seconds();
    for (size_t i = from; i < to; i++)
        (void)shoot(accel, q, &set->rays[i], origin ? set->from[i] : BSP_NO_PRIM, shadow);
    return bench_cpu_seconds() - t0;
}

static int cmp_double(const void *x, const void *y)
{
    double a = *(const double *)x, b = *(const double *)y;
    return (a > b) - (a < b);
}

int cmd_ab(int argc, char **argv)
{
    args a = {argc, 1, argv, ab_usage, NULL};
    const char *scene_path = NULL;
    int res = 513, depth = 4, all = 0, rounds = 5, slice = 2048;
    int b_origin = 1, a_options = 0, b_options = 0; /* B leaves origins out; options given */
    bsp_build_options oa, ob;
    bsp_build_options_defaults(&oa);
    bsp_build_options_defaults(&ob);
    int to_a = 0; /* the build options go to A (after --a, up to --b) */
    for (; a.i < argc; a.i++) {
        const char *s = argv[a.i];
        if (is_help(s)) {
            printf("usage: %s\n\n%s%s", ab_usage, ab_help, build_args_help);
            return 0;
        } else if (!strcmp(s, "--a") || !strcmp(s, "--b")) {
            to_a = s[2] == 'a';
        } else if (parse_build_arg(&a, to_a ? &oa : &ob)) {
            *(to_a ? &a_options : &b_options) = 1;
            continue;
        } else if (!strcmp(s, "--origin")) {
            b_origin = !parse_one_of_two(&a, s, "skip", "test");
        } else if (!strcmp(s, "--res")) {
            res = parse_int(&a, s, 2, 8192);
        } else if (!strcmp(s, "--depth")) {
            depth = parse_int(&a, s, 0, 64);
        } else if (!strcmp(s, "--rounds")) {
            rounds = parse_int(&a, s, 1, 1000);
        } else if (!strcmp(s, "--slice")) {
            slice = parse_int(&a, s, 1, 1 << 24);
        } else if (!strcmp(s, "--rays")) {
            all = parse_one_of_two(&a, s, "primary", "all");
        } else {
            take_operand(&a, &scene_path);
        }
    }
    if (!scene_path)
        die_usage(a.usage, "%s", "missing SCENE");
    bsp_scene *scene = load_scene(scene_path);
    if (!a_options)
        oa.threads = ob.threads;
    bsp_accel *A = build_accel(scene, &oa),
              *B = a_options || b_options ? build_accel(scene, &ob) : A;

    /* the rays: every class, or the primary rays alone (a depth-0 render
     * also spawns shadow rays; they are not used then) */
    bench_ray_set sets[BSP_RAY_CLASS_COUNT];
    memset(sets, 0, sizeof sets);
    bsp_render_options ro;
    bsp_render_options_defaults(&ro);
    ro.width = ro.height = res;
    ro.max_depth = all ? depth : 0;
    ro.threads = 1;
    ro.pixel_order = BSP_PIXELS_ROWS; /* the rays row by row, as bench records them */
    ro.ray_log = bench_log_ray;
    ro.ray_log_ctx = sets;
    bsp_image *img = NULL;
    bsp_error err;
    int failed = bsp_render(A, &ro, &img, NULL, &err) != BSP_OK;
    for (int c = 0; c < BSP_RAY_CLASS_COUNT; c++)
        failed |= sets[c].failed;
    bsp_query *qa = NULL, *qb = NULL;
    double *ratio = NULL;
    size_t differ = 0;
    int status = EXIT_INPUT;
    if (failed) {
        fprintf(stderr, "%s: %s: %s\n", prog, scene_path, img ? "out of memory" : err.message);
        goto done;
    }
    bsp_image_destroy(img);
    img = NULL;
    const int nclasses = all ? BSP_RAY_CLASS_COUNT : 1; /* BSP_RAY_PRIMARY is 0 */
    size_t nrays = 0;
    for (int c = 0; c < nclasses; c++)
        nrays += sets[c].n;

    qa = bsp_query_create(A);
    qb = bsp_query_create(B);
    ratio = malloc((size_t)rounds * sizeof *ratio);
    if (!qa || !qb || !ratio) {
        fprintf(stderr, "%s: out of memory\n", prog);
        goto done;
    }
    /* the answers, and the per-ray counters of one untimed pass */
    for (int c = 0; c < nclasses; c++) {
        for (size_t i = 0; i < sets[c].n; i++) {
            const bsp_ray *r = &sets[c].rays[i];
            int shadow = c == BSP_RAY_SHADOW;
            uint32_t o = sets[c].from[i];
            answer x = shoot(A, qa, r, o, shadow),
                   y = shoot(B, qb, r, b_origin ? o : BSP_NO_PRIM, shadow);
            differ += x.hit != y.hit || x.prim != y.prim || x.t != y.t;
        }
    }
    bsp_query_counters ca = *bsp_query_get_counters(qa), cb = *bsp_query_get_counters(qb);
    double best_a = 1e300, best_b = 1e300;
    for (int round = 0; round < rounds; round++) {
        double ta = 0.0, tb = 0.0;
        size_t k = 0; /* slices so far: the order alternates with each */
        for (int c = 0; c < nclasses; c++) {
            const bench_ray_set *rays = &sets[c];
            size_t n = sets[c].n;
            int shadow = c == BSP_RAY_SHADOW;
            for (size_t from = 0; from < n; from += (size_t)slice, k++) {
                size_t to = n - from < (size_t)slice ? n : from + (size_t)slice;
                if ((k + (size_t)round) % 2 == 0) {
                    ta += slice_seconds(A, qa, rays, from, to, shadow, 1);
                    tb += slice_seconds(B, qb, rays, from, to, shadow, b_origin);
                } else {
                    tb += slice_seconds(B, qb, rays, from, to, shadow, b_origin);
                    ta += slice_seconds(A, qa, rays, from, to, shadow, 1);
                }
            }
        }
        best_a = ta < best_a ? ta : best_a;
        best_b = tb < best_b ? tb : best_b;
        ratio[round] = tb > 0.0 ? ta / tb : 0.0;
    }
    qsort(ratio, (size_t)rounds, sizeof *ratio, cmp_double);
    int h = rounds / 2;
    double median = rounds % 2 ? ratio[h] : 0.5 * (ratio[h - 1] + ratio[h]);

    bsp_tree_stats sa, sb;
    bsp_accel_tree_stats(A, &sa);
    bsp_accel_tree_stats(B, &sb);
    double n = nrays ? (double)nrays : 1.0;
    printf("| scene | rays | A Mrays/s | B Mrays/s | B/A best | B/A median | N_TS A / B | "
           "N_IT A / B | leaves A / B | same answers |\n");
    printf("|---|---:|---:|---:|---:|---:|---:|---:|---:|---|\n");
    printf("| %s | %zu %s | %.3f | %.3f | %.4f | %.4f | %.2f / %.2f | %.3f / %.3f | %" PRIu64
           " / %" PRIu64 " | %s |\n",
           scene_path, nrays, all ? "all" : "primary", best_a > 0.0 ? n / best_a * 1e-6 : 0.0,
           best_b > 0.0 ? n / best_b * 1e-6 : 0.0, best_b > 0.0 ? best_a / best_b : 0.0,
           median, (double)ca.traversal_steps / n, (double)cb.traversal_steps / n,
           (double)ca.isect_tests / n, (double)cb.isect_tests / n, sa.leaves, sb.leaves,
           differ ? "NO" : "yes");
    if (differ)
        fprintf(stderr, "%s: %s: %zu of %zu rays got different answers from A and B\n", prog,
                scene_path, differ, nrays);
    status = differ ? EXIT_INPUT : 0;
done:
    bsp_image_destroy(img);
    free(ratio);
    bench_free_ray_sets(sets);
    bsp_query_destroy(qa);
    bsp_query_destroy(qb);
    if (B != A)
        bsp_accel_destroy(B);
    bsp_accel_destroy(A);
    bsp_scene_destroy(scene);
    return status;
}
