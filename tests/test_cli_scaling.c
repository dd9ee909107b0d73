/*
 * test_cli_scaling.c — `bspray bench --scaling` end to end: the Markdown
 * table, the CSV (its stable column names, one row per scene, N as the
 * library counts the loaded scene, the tree's figures), the per-generator
 * summary, and bad arguments (a message and a non-zero exit).
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bspray/bspray.h"
#include "harness.h"

static const char scaling_csv_header[] =
    "scene,accel,N,T_B_1t,us_per_prim,Mprim_per_s,T_B_nt,threads,N_IN,N_V,N_OIV,cost,bytes,"
    "speedup,builds,T_B_1t_first,digest";

/* The primitive count of SPEC loaded in this process: the CLI's N must match
 * it. */
static size_t prim_count_of(const char *spec)
{
    bsp_scene *s = NULL;
    bsp_error err;
    if (bsp_scene_load(spec, &s, &err) != BSP_OK)
        return 0;
    size_t n = bsp_scene_prim_count(s);
    bsp_scene_destroy(s);
    return n;
}

TEST(cli_bench_scaling_table_and_csv)
{
    char csv[512], png[512], cmd[2048];
    snprintf(csv, sizeof csv, "%s/scaling.csv", harness_tmpdir());
    snprintf(png, sizeof png, "%s/scaling.png", harness_tmpdir());
    snprintf(cmd, sizeof cmd,
             "%s bench --scaling spd:balls:2 spd:balls:3 --repeat 1 --threads 2 --quiet "
             "--csv %s --plot %s",
             harness_cli(), csv, png);
    int st;
    char *out = harness_run(cmd, &st);
    REQUIRE(out);
    CHECK_EQ_INT(st, 0);
    CHECK_STR_CONTAINS(out, "| scene | accel | N | T_B 1t [s] | µs/prim | Mprim/s | first 1t [s] | "
                            "T_B 2t wall [s] | speed-up | N_IN | N_V | N_OIV | cost | MB |");
    CHECK_STR_CONTAINS(out, "| spd:balls:2 | sah | ");
    CHECK_STR_CONTAINS(out, "| spd:balls:3 | sah | ");
    /* two sizes of one generator: the summary line */
    CHECK_STR_CONTAINS(out, "| generator | accel |");
    CHECK_STR_CONTAINS(out, "| spd:balls | sah | ");
    free(out);

    const char *specs[] = {"spd:balls:2", "spd:balls:3"};
    FILE *f = fopen(csv, "r");
    REQUIRE(f);
    char line[4096];
    REQUIRE(fgets(line, sizeof line, f));
    CHECK(strncmp(line, scaling_csv_header, strlen(scaling_csv_header)) == 0);
    int rows = 0;
    while (fgets(line, sizeof line, f)) {
        char scene[64], accel[32];
        unsigned long long n, n_in, n_v, n_oiv, bytes;
        double t1, us, mps, tn, cost;
        int threads;
        int got = sscanf(line,
                         "%63[^,],%31[^,],%llu,%lf,%lf,%lf,%lf,%d,%llu,%llu,%llu,%lf,%llu", scene,
                         accel, &n, &t1, &us, &mps, &tn, &threads, &n_in, &n_v, &n_oiv, &cost,
                         &bytes);
        CHECK_EQ_INT(got, 13);
        if (got != 13 || rows >= 2) {
            rows++;
            continue;
        }
        CHECK(strcmp(scene, specs[rows]) == 0);
        CHECK(strcmp(accel, "sah") == 0);
        size_t expect = prim_count_of(specs[rows]);
        CHECK(expect > 0);
        CHECK_EQ_INT(n, expect);
        CHECK_MSG(t1 > 0.0, "%s: T_B_1t %g", scene, t1);
        CHECK_MSG(tn > 0.0, "%s: T_B_nt %g", scene, tn);
        CHECK_NEAR(us, t1 / (double)n * 1e6, 1e-3 * us + 1e-6);
        CHECK_EQ_INT(threads, 2);
        CHECK_MSG(n_oiv >= n, "%s: N_OIV %llu < N %llu", scene, n_oiv, n);
        CHECK_EQ_INT(n_v, n_in + 1); /* a binary tree */
        CHECK(cost > 0.0);
        CHECK(bytes > 0);
        /* the last column, the tree's digest, is the one `stats` reports for the scene
         * (built there on every core: the same tree) */
        const char *last = strrchr(line, ',');
        REQUIRE(last);
        /* before it, the first build's time: the best of the builds is at most it */
        const char *before = last - 1;
        while (before > line && *before != ',')
            before--;
        double first = -1.0;
        CHECK(sscanf(before + 1, "%lf", &first) == 1);
        CHECK_MSG(first > 0.0 && t1 <= first, "%s: T_B_1t %g, T_B_1t_first %g", scene, t1,
                  first);
        char digest[32] = "", stats_digest[32] = "";
        CHECK(sscanf(last + 1, "%31s", digest) == 1 && strlen(digest) == 16);
        snprintf(cmd, sizeof cmd, "%s stats %s --accel sah", harness_cli(), specs[rows]);
        out = harness_run(cmd, &st);
        REQUIRE(out);
        const char *d = strstr(out, "digest");
        CHECK(d && sscanf(d, "digest %31s", stats_digest) == 1);
        CHECK_MSG(strcmp(digest, stats_digest) == 0, "%s: digest %s in the CSV, %s from stats",
                  scene, digest, stats_digest);
        free(out);
        rows++;
    }
    fclose(f);
    CHECK_EQ_INT(rows, 2);
    /* --plot: the balls line (colour 0, two sizes, and its dashed ln N line)
     * and the grey line of a million primitives per second (colour 7) */
    bsp_image *chart = NULL;
    bsp_error err;
    REQUIRE(bsp_image_read_png(png, &chart, &err) == BSP_OK);
    CHECK_EQ_INT(chart->width, 960);
    CHECK_EQ_INT(chart->height, 640);
    CHECK(harness_count_color(chart, 0) > 50);
    CHECK(harness_count_color(chart, 7) > 50);
    CHECK(harness_count_color(chart, 1) == 0); /* no second generator */
    bsp_image_destroy(chart);
}

TEST(cli_bench_scaling_help_and_bad_arguments)
{
    char cmd[1024];
    int st;
    /* an unwritable --plot path fails before any build, naming the file */
    snprintf(cmd, sizeof cmd, "%s bench --scaling spd:balls:1 --plot %s/no/such/dir/s.png 2>&1",
             harness_cli(), harness_tmpdir());
    CHECK_RUN(cmd, 1, "s.png: cannot open for writing");
    snprintf(cmd, sizeof cmd, "%s bench --scaling --help", harness_cli());
    char *out = harness_run(cmd, &st);
    REQUIRE(out);
    CHECK_EQ_INT(st, 0);
    CHECK_STR_CONTAINS(out, "usage: bspray bench --scaling");
    CHECK_STR_CONTAINS(out, "us_per_prim");
    free(out);

    static const struct {
        const char *args;
        int status;
        const char *message;
    } bad[] = {
        {"spd:nosuchscene:3", 1, "unknown SPD scene 'nosuchscene'"},
        {"spd:balls:2 spd:balls:99", 1, "size factor '99'"},
        {"spd:balls:2 /nonexistent/scene.nff", 1, "/nonexistent/scene.nff: cannot open"},
        {"spd:balls:2 --repeat 0", 2, "--repeat"},
        {"spd:balls:2 --repeat many", 2, "--repeat"},
        {"spd:balls:2 --accel quadtree", 2, "unknown acceleration method 'quadtree'"},
        {"spd:balls:2 --accel naive", 2, "naive"},
        {"spd:balls:2 --frobnicate", 2, "unknown option '--frobnicate'"},
        {"spd:balls:2 --threads 0", 2, "--threads"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        snprintf(cmd, sizeof cmd, "%s bench --scaling %s --quiet 2>&1", harness_cli(),
                 bad[i].args);
        out = harness_run(cmd, &st);
        REQUIRE(out);
        CHECK_MSG(st == bad[i].status, "'%s': exit %d, expected %d", bad[i].args, st,
                  bad[i].status);
        CHECK_STR_CONTAINS(out, bad[i].message);
        free(out);
    }

    /* a malformed file after a good scene: named with its line before any build,
     * so no table is printed */
    char nff[512];
    snprintf(nff, sizeof nff, "%s/scaling_bad.nff", harness_tmpdir());
    FILE *f = fopen(nff, "w");
    REQUIRE(f);
    fputs("v\nfrom 0 0 5\nat 0 0 0\nup 0 1 0\nangle 45\nhither 1\nresolution 8 8\n"
          "s 0 0 0 abc\n",
          f);
    fclose(f);
    snprintf(cmd, sizeof cmd, "%s bench --scaling spd:balls:2 %s --quiet 2>&1", harness_cli(),
             nff);
    out = harness_run(cmd, &st);
    REQUIRE(out);
    CHECK_EQ_INT(st, 1);
    CHECK_STR_CONTAINS(out, "scaling_bad.nff:8: malformed number 'abc'");
    CHECK_MSG(strstr(out, "| spd:balls:2 |") == NULL, "a scene was measured first:\n%s", out);
    free(out);
}
