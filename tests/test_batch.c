/*
 * test_batch.c — ray batches on several threads (bsp_intersect_batch,
 * bsp_occluded_batch) and `bspray trace --threads/--exact/--stats-json`:
 * every answer is the one a single query of the naive method gives for the
 * same ray, bit for bit, for any number of threads, and the counters are
 * the sums a plain loop of single queries counts. And `render --save-rays`:
 * the rays a render casts, replayed through trace, give the render's counts.
 */
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bspray/bspray.h"
#include "harness.h"
#include "kd_test_util.h"

static unsigned long long rng_state;

static int same_counters(const bsp_query_counters *a, const bsp_query_counters *b)
{
    return a->rays == b->rays && a->isect_tests == b->isect_tests &&
           a->traversal_steps == b->traversal_steps && a->leaves_visited == b->leaves_visited &&
           a->empty_leaves == b->empty_leaves && a->mailbox_hits == b->mailbox_hits;
}

TEST(batch_matches_single_naive_queries_on_any_thread_count)
{
    static const char *const scenes[] = {"spd:rings", "spd:teapot", "spd:tree"};
    /* quick mode (the sanitizer runs, ThreadSanitizer's among them): 1000
     * rays, four chunks of the batch's, still more than its threads */
    const size_t N = harness_quick() ? 1000 : 4000;
    bsp_ray *rays = malloc(N * sizeof *rays);
    uint32_t *from = malloc(N * sizeof *from);
    bsp_hit *ref = malloc(N * sizeof *ref), *hits = malloc(N * sizeof *hits);
    unsigned char *ref_occ = malloc(N), *occ = malloc(N);
    REQUIRE(rays && from && ref && hits && ref_occ && occ);
    for (size_t sc = 0; sc < sizeof scenes / sizeof scenes[0]; sc++) {
        bsp_scene *s = kd_test_load(scenes[sc]);
        bsp_error err;
        rng_state = 0x5EED0000ULL + sc;
        kd_test_rays(&rng_state, bsp_scene_bounds(s), N, bsp_scene_prim_count(s), rays, from);
        /* the reference: one naive query per ray, in a plain loop */
        bsp_accel *naive = kd_test_build(s, BSP_ACCEL_NAIVE);
        bsp_query *nq = bsp_query_create(naive);
        REQUIRE(nq);
        size_t nhits = 0;
        for (size_t i = 0; i < N; i++) {
            if (!bsp_intersect_from(naive, nq, &rays[i], from[i], &ref[i]))
                ref[i].prim = BSP_NO_PRIM;
            nhits += ref[i].prim != BSP_NO_PRIM;
            ref_occ[i] = (unsigned char)bsp_occluded_from(naive, nq, &rays[i], from[i]);
        }
        bsp_query_destroy(nq);
        CHECK_MSG(nhits > N / 20 && nhits < N, "%s: %zu hits of %zu rays", scenes[sc], nhits, N);
        for (int method = 0; method < 3; method++) {
            bsp_build_options o;
            bsp_build_options_defaults(&o);
            o.kind = method == 0 ? BSP_ACCEL_NAIVE : BSP_ACCEL_SAH;
            o.mailbox = method != 2;
            bsp_accel *a;
            REQUIRE(bsp_accel_build(s, &o, &a, &err) == BSP_OK);
            /* the counters a plain loop of single queries counts */
            bsp_query *q = bsp_query_create(a);
            REQUIRE(q);
            bsp_query_counters want_hit = {0}, want_occ = {0};
            bsp_hit h;
            for (size_t i = 0; i < N; i++)
                (void)bsp_intersect_from(a, q, &rays[i], from[i], &h);
            bsp_query_counters_add(&want_hit, bsp_query_get_counters(q));
            bsp_query_reset_counters(q);
            for (size_t i = 0; i < N; i++)
                (void)bsp_occluded_from(a, q, &rays[i], from[i]);
            bsp_query_counters_add(&want_occ, bsp_query_get_counters(q));
            bsp_query_destroy(q);
            CHECK_EQ_INT(want_hit.rays, N);
            /* the naive method on two threads only: its rays are slow */
            for (int threads = method == 0 ? 2 : 1; threads <= (method == 0 ? 2 : 3); threads++) {
                bsp_query_counters c;
                memset(hits, 0xAB, N * sizeof *hits);
                REQUIRE(bsp_intersect_batch(a, rays, from, N, threads, hits, &c, &err) == BSP_OK);
                size_t bad = 0;
                for (size_t i = 0; i < N; i++)
                    bad += hits[i].prim != ref[i].prim ||
                           (ref[i].prim != BSP_NO_PRIM &&
                            memcmp(&hits[i].t, &ref[i].t, sizeof ref[i].t) != 0);
                CHECK_MSG(bad == 0, "%s method %d, %d threads: %zu closest hits differ", scenes[sc],
                          method, threads, bad);
                CHECK_MSG(same_counters(&c, &want_hit),
                          "%s method %d, %d threads: counters (tests %" PRIu64 " vs %" PRIu64
                          ", steps %" PRIu64 " vs %" PRIu64 ")",
                          scenes[sc], method, threads, c.isect_tests, want_hit.isect_tests,
                          c.traversal_steps, want_hit.traversal_steps);
                memset(occ, 7, N);
                REQUIRE(bsp_occluded_batch(a, rays, from, N, threads, occ, &c, &err) == BSP_OK);
                CHECK_MSG(memcmp(occ, ref_occ, N) == 0, "%s method %d, %d threads: occlusion",
                          scenes[sc], method, threads);
                CHECK(same_counters(&c, &want_occ));
            }
            /* FROM NULL leaves nothing out: the plain queries' answers */
            REQUIRE(bsp_intersect_batch(a, rays, NULL, 100, 2, hits, NULL, &err) == BSP_OK);
            q = bsp_query_create(a);
            REQUIRE(q);
            for (size_t i = 0; i < 100; i++) {
                int got = bsp_intersect(a, q, &rays[i], &h);
                CHECK_EQ_INT(hits[i].prim, got ? h.prim : BSP_NO_PRIM);
            }
            bsp_query_destroy(q);
            bsp_accel_destroy(a);
        }
        bsp_accel_destroy(naive);
        bsp_scene_destroy(s);
    }
    free(rays);
    free(from);
    free(ref);
    free(hits);
    free(ref_occ);
    free(occ);
}

TEST(batch_rejects_missing_arrays_and_takes_empty_batches)
{
    bsp_scene *s;
    bsp_error err;
    REQUIRE(bsp_scene_load("spd:jacks", &s, &err) == BSP_OK);
    bsp_accel *a;
    REQUIRE(bsp_accel_build(s, NULL, &a, &err) == BSP_OK);
    bsp_ray r = {bsp_v3(0, 0, 10), bsp_v3(0, 0, -1), 0.0, INFINITY};
    bsp_hit h;
    unsigned char o;
    bsp_query_counters c;
    memset(&c, 0xFF, sizeof c);
    CHECK_EQ_INT(bsp_intersect_batch(a, NULL, NULL, 0, 4, NULL, &c, &err), BSP_OK);
    CHECK_EQ_INT(c.rays, 0);
    CHECK_EQ_INT(bsp_intersect_batch(a, NULL, NULL, 1, 1, &h, NULL, &err), BSP_ERR_INVALID);
    CHECK_EQ_INT(bsp_intersect_batch(a, &r, NULL, 1, 1, NULL, NULL, &err), BSP_ERR_INVALID);
    CHECK_EQ_INT(bsp_occluded_batch(a, &r, NULL, 1, 1, NULL, NULL, &err), BSP_ERR_INVALID);
    CHECK_EQ_INT(bsp_occluded_batch(NULL, &r, NULL, 1, 1, &o, NULL, &err), BSP_ERR_INVALID);
    CHECK_STR_CONTAINS(err.message, "ray batch");
    /* more threads than rays, and 0 (every core) */
    CHECK_EQ_INT(bsp_intersect_batch(a, &r, NULL, 1, 64, &h, &c, &err), BSP_OK);
    CHECK_EQ_INT(c.rays, 1);
    bsp_query *q = bsp_query_create(a);
    bsp_hit h1;
    int got = bsp_intersect(a, q, &r, &h1);
    CHECK_EQ_INT(h.prim, got ? h1.prim : BSP_NO_PRIM);
    CHECK_EQ_INT(bsp_occluded_batch(a, &r, NULL, 1, 0, &o, NULL, &err), BSP_OK);
    CHECK_EQ_INT(o, bsp_occluded(a, q, &r));
    bsp_query_destroy(q);
    bsp_accel_destroy(a);
    bsp_scene_destroy(s);
}

/* The value of "KEY": N in JSON text J, or -1. */
static double json_number(const char *j, const char *key)
{
    char pat[64];
    snprintf(pat, sizeof pat, "\"%s\": ", key);
    const char *p = strstr(j, pat);
    return p ? strtod(p + strlen(pat), NULL) : -1.0;
}

static char *read_file(const char *path)
{
    size_t len;
    return (char *)harness_read_file(path, &len);
}

/* `bspray trace spd:rings --rays RAYS` (on two threads) exits with status 1
 * and says WANT on stderr. */
static void expect_trace_refused(const char *rays, const char *want)
{
    char cmd[2048];
    snprintf(cmd, sizeof cmd, "%s trace spd:rings --rays %s --threads 2 2>&1 >/dev/null",
             harness_cli(), rays);
    int status;
    char *out = harness_run(cmd, &status);
    REQUIRE(out);
    CHECK_EQ_INT(status, 1);
    CHECK_STR_CONTAINS(out, want);
    free(out);
}

TEST(cli_trace_threads_exact_and_stats)
{
    bsp_scene *s = kd_test_load("spd:rings");
    const size_t np = bsp_scene_prim_count(s);
    enum { N = 3000 };
    bsp_ray *rays = malloc(N * sizeof *rays);
    uint32_t *from = malloc(N * sizeof *from);
    REQUIRE(rays && from);
    rng_state = 0xC0FFEEULL;
    kd_test_rays(&rng_state, bsp_scene_bounds(s), N, np, rays, from);
    for (size_t i = 0; i < N; i++) { /* the file gives no interval: [0, inf) */
        rays[i].tmin = 0.0;
        rays[i].tmax = INFINITY;
    }
    char rays_path[600];
    snprintf(rays_path, sizeof rays_path, "%s/batch_rays.txt", harness_tmpdir());
    FILE *f = fopen(rays_path, "w");
    REQUIRE(f);
    for (size_t i = 0; i < N; i++) /* no primitive left out: naive tests all of them */
        fprintf(f, "%.17g %.17g %.17g %.17g %.17g %.17g\n", rays[i].org.x, rays[i].org.y,
                rays[i].org.z, rays[i].dir.x, rays[i].dir.y, rays[i].dir.z);
    fclose(f);
    bsp_accel *naive = kd_test_build(s, BSP_ACCEL_NAIVE);
    bsp_query *nq = bsp_query_create(naive);
    REQUIRE(nq);
    static const char *const runs[] = {"--threads 1", "--threads 2", "--threads 3 --accel naive",
                                       "--threads 2 --mailbox off"};
    char *first = NULL;
    for (size_t r = 0; r < sizeof runs / sizeof runs[0]; r++) {
        char json[600], cmd[2048];
        snprintf(json, sizeof json, "%s/batch_%zu.json", harness_tmpdir(), r);
        snprintf(cmd, sizeof cmd, "%s trace spd:rings --rays %s --exact --stats-json %s %s",
                 harness_cli(), rays_path, json, runs[r]);
        int status;
        char *out = harness_run(cmd, &status);
        REQUIRE(out);
        CHECK_EQ_INT(status, 0);
        if (!first) { /* every line against a single naive query, bit for bit */
            char *line = out;
            size_t i = 0, hits = 0;
            for (; i < N && line && *line; i++) {
                bsp_hit h;
                int got = bsp_intersect(naive, nq, &rays[i], &h);
                unsigned prim;
                char tbuf[64];
                if (!got) {
                    CHECK_MSG(!strncmp(line, "miss\n", 5), "ray %zu: '%.40s'", i, line);
                } else if (sscanf(line, "hit %u %63s", &prim, tbuf) == 2) {
                    double t = strtod(tbuf, NULL);
                    hits++;
                    CHECK_MSG(prim == h.prim && memcmp(&t, &h.t, sizeof t) == 0,
                              "ray %zu: '%s %s' vs hit %u %.17g", i, "hit", tbuf, h.prim, h.t);
                } else {
                    CHECK_MSG(0, "ray %zu: '%.40s'", i, line);
                }
                line = strchr(line, '\n');
                if (line)
                    line++;
            }
            CHECK_EQ_INT(i, N);
            CHECK_MSG(hits > N / 20, "only %zu hits", hits);
            first = out;
        } else {
            CHECK_MSG(!strcmp(out, first), "'%s' prints other lines than '%s'", runs[r], runs[0]);
            free(out);
        }
        char *j = read_file(json);
        REQUIRE(j);
        CHECK_EQ_INT((long long)json_number(j, "rays"), N);
        size_t hit_lines = 0;
        for (const char *p = first; (p = strstr(p, "hit ")) != NULL; p++)
            hit_lines++;
        CHECK_EQ_INT((long long)json_number(j, "hits"), (long long)hit_lines);
        if (strstr(runs[r], "naive")) /* the naive method tests every primitive once */
            CHECK_EQ_INT((long long)json_number(j, "isect_tests"), (long long)(N * np));
        else
            CHECK_MSG(json_number(j, "N_IT") > 0.0 && json_number(j, "N_IT") < 0.2 * (double)np &&
                          json_number(j, "N_TS") > 1.0 && json_number(j, "N_V") > 100.0,
                      "%s: N_IT %g, N_TS %g, N_V %g", runs[r], json_number(j, "N_IT"),
                      json_number(j, "N_TS"), json_number(j, "N_V"));
        CHECK(json_number(j, "T_TR") >= 0.0);
        free(j);
    }
    free(first);
    /* --stats prints the table on stderr; a bad line after good ones: the good
     * ones are answered, then the message names the line */
    char bad_path[600], cmd[2048];
    snprintf(bad_path, sizeof bad_path, "%s/batch_bad.txt", harness_tmpdir());
    f = fopen(bad_path, "w");
    REQUIRE(f);
    fprintf(f, "0 0 20 0 0 -1\n# comment\n0 0 20 0 0 -1\n0 0 20 0 0 nan\n");
    fclose(f);
    snprintf(cmd, sizeof cmd, "%s trace spd:rings --rays %s --threads 2 2>/dev/null", harness_cli(),
             bad_path);
    int status;
    char *out = harness_run(cmd, &status);
    REQUIRE(out);
    CHECK_EQ_INT(status, 1);
    /* the same ray twice before the bad line: two equal answers */
    const char *nl = strchr(out, '\n');
    size_t len = nl ? (size_t)(nl - out) + 1 : 0;
    CHECK_MSG(len > 0 && strlen(out) == 2 * len && !memcmp(out, out + len, len),
              "two equal answers before the bad line: '%s'", out);
    free(out);
    char where[700];
    snprintf(where, sizeof where, "%s:4: malformed or non-finite number", bad_path);
    expect_trace_refused(bad_path, where);
    /* a NUL byte ends a C string early: the line is refused, not read up to
     * the NUL (the garbage after it would pass unread) */
    f = fopen(bad_path, "w");
    REQUIRE(f);
    static const char nul_line[] = "0 0 20 0 0 -1\n0 0 20 0 0 -1\0 garbage\n";
    fwrite(nul_line, 1, sizeof nul_line - 1, f);
    fclose(f);
    snprintf(where, sizeof where, "%s:2: a NUL byte in the line", bad_path);
    expect_trace_refused(bad_path, where);
    /* a directory as the ray file: refused by name before any work */
    snprintf(where, sizeof where, "%s: cannot read: Is a directory", harness_tmpdir());
    expect_trace_refused(harness_tmpdir(), where);
    snprintf(cmd, sizeof cmd, "%s trace spd:rings --rays %s --stats 2>&1 >/dev/null", harness_cli(),
             rays_path);
    out = harness_run(cmd, &status);
    REQUIRE(out);
    CHECK_EQ_INT(status, 0);
    CHECK_STR_CONTAINS(out, "| rays | 3000 |");
    CHECK_STR_CONTAINS(out, "| N_TS |");
    CHECK_STR_CONTAINS(out, "| Mrays/s |");
    free(out);
    bsp_query_destroy(nq);
    bsp_accel_destroy(naive);
    bsp_scene_destroy(s);
    free(rays);
    free(from);
}

/* Lines of PATH that begin with PREFIX. */
static long count_lines(const char *path, const char *prefix)
{
    char *s = read_file(path);
    if (!s)
        return -1;
    long n = 0;
    size_t len = strlen(prefix);
    for (const char *p = s; *p;) {
        n += !strncmp(p, prefix, len);
        const char *nl = strchr(p, '\n');
        if (!nl)
            break;
        p = nl + 1;
    }
    free(s);
    return n;
}

TEST(cli_render_saved_rays_replay_to_the_render_counts)
{
    /* the rays a render casts, replayed through trace by the naive method and
     * by the default tree, give the render's own counts of hits */
    static const char *const scenes[] = {"spd:balls", "spd:rings"};
    for (size_t sc = 0; sc < 2; sc++) {
        char prefix[600], json[700], cmd[4096], path[800];
        snprintf(prefix, sizeof prefix, "%s/saved_%zu", harness_tmpdir(), sc);
        snprintf(json, sizeof json, "%s.json", prefix);
        snprintf(cmd, sizeof cmd,
                 "%s render %s --res 25 --save-rays %s --stats-json %s -o %s.png --quiet 2>&1",
                 harness_cli(), scenes[sc], prefix, json, prefix);
        int status;
        char *out = harness_run(cmd, &status);
        REQUIRE(out);
        CHECK_MSG(status == 0, "%s", out);
        free(out);
        char *j = read_file(json);
        REQUIRE(j);
        static const struct {
            const char *cls, *rays, *hits, *yes;
            int any;
        } classes[] = {{"primary", "PrimaryRay", "UsedIntPrimRay", "hit ", 0},
                       {"shadow", "ShadowRay", "UsedIntShadRay", "occluded", 1},
                       {"secondary", "SecondaryRay", "UsedIntSecRay", "hit ", 0}};
        for (int c = 0; c < 3; c++) {
            snprintf(path, sizeof path, "%s-%s.txt", prefix, classes[c].cls);
            long want_rays = (long)json_number(j, classes[c].rays);
            long want_hits = (long)json_number(j, classes[c].hits);
            CHECK_MSG(want_rays > 0 && count_lines(path, "") == want_rays,
                      "%s %s: %ld lines, %ld rays", scenes[sc], classes[c].cls,
                      count_lines(path, ""), want_rays);
            char *first = NULL;
            for (int naive = 0; naive < 2; naive++) {
                char answers[900];
                snprintf(answers, sizeof answers, "%s-%s.%d.out", prefix, classes[c].cls, naive);
                snprintf(cmd, sizeof cmd, "%s trace %s --rays %s --exact%s%s > %s", harness_cli(),
                         scenes[sc], path, classes[c].any ? " --any" : "",
                         naive ? " --accel naive" : "", answers);
                char *o = harness_run(cmd, &status);
                free(o);
                CHECK_EQ_INT(status, 0);
                CHECK_MSG(count_lines(answers, classes[c].yes) == want_hits,
                          "%s %s (%s): %ld answers '%s', the render counted %ld", scenes[sc],
                          classes[c].cls, naive ? "naive" : "sah",
                          count_lines(answers, classes[c].yes), classes[c].yes, want_hits);
                char *a = read_file(answers);
                REQUIRE(a);
                if (!first)
                    first = a;
                else {
                    CHECK_MSG(!strcmp(a, first), "%s %s: naive and sah differ", scenes[sc],
                              classes[c].cls);
                    free(a);
                }
            }
            free(first);
        }
        free(j);
    }
    /* an unwritable prefix fails before the render, naming the file */
    char cmd[2048];
    snprintf(cmd, sizeof cmd, "%s render spd:balls --res 9 --save-rays /nonexistent/dir/r 2>&1",
             harness_cli());
    int status;
    char *out = harness_run(cmd, &status);
    REQUIRE(out);
    CHECK_EQ_INT(status, 1);
    CHECK_STR_CONTAINS(out, "/nonexistent/dir/r-primary.txt: cannot open for writing");
    free(out);
}

/* bsp_query_counters_add sums field by field: hand-made counters, then the
 * counters of rays split over two queries against one query's for them all. */
TEST(batch_counters_add_sums_every_field)
{
    bsp_query_counters sum = {1, 2, 3, 4, 5, 6};
    const bsp_query_counters c = {10, 200, 3000, 40000, 500000, 6000000};
    bsp_query_counters_add(&sum, &c);
    CHECK_EQ_INT(sum.rays, 11);
    CHECK_EQ_INT(sum.isect_tests, 202);
    CHECK_EQ_INT(sum.traversal_steps, 3003);
    CHECK_EQ_INT(sum.leaves_visited, 40004);
    CHECK_EQ_INT(sum.empty_leaves, 500005);
    CHECK_EQ_INT(sum.mailbox_hits, 6000006);

    bsp_scene *s = kd_test_load("spd:tetra:3");
    enum { N = 2000 };
    bsp_ray *rays = malloc(N * sizeof *rays);
    uint32_t *from = malloc(N * sizeof *from);
    REQUIRE(rays && from);
    rng_state = 0xADDC0DEULL;
    kd_test_rays(&rng_state, bsp_scene_bounds(s), N, bsp_scene_prim_count(s), rays, from);
    bsp_accel *a = kd_test_build(s, BSP_ACCEL_SAH);
    bsp_query *all = bsp_query_create(a), *half[2] = {bsp_query_create(a), bsp_query_create(a)};
    REQUIRE(all && half[0] && half[1]);
    bsp_hit h;
    for (size_t i = 0; i < N; i++) {
        (void)bsp_intersect_from(a, all, &rays[i], from[i], &h);
        (void)bsp_intersect_from(a, half[i & 1], &rays[i], from[i], &h);
    }
    bsp_query_counters parts = {0};
    bsp_query_counters_add(&parts, bsp_query_get_counters(half[0]));
    bsp_query_counters_add(&parts, bsp_query_get_counters(half[1]));
    const bsp_query_counters *want = bsp_query_get_counters(all);
    CHECK_EQ_INT(want->rays, N);
    CHECK(want->traversal_steps > 0 && want->isect_tests > 0);
    CHECK(same_counters(&parts, want));
    bsp_query_destroy(all);
    bsp_query_destroy(half[0]);
    bsp_query_destroy(half[1]);
    bsp_accel_destroy(a);
    bsp_scene_destroy(s);
    free(rays);
    free(from);
}
