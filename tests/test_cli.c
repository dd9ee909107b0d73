/*
 * test_cli.c — the bspray tool end to end: bench's table and CSV, stats of a
 * tree, gen, and the malformed-input corpus through the command line (exit
 * status 1 and a FILE:LINE message, never a crash).
 */
#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "bspray/bspray.h"
#include "harness.h"

static int count_lines(const char *s)
{
    int n = 0;
    for (; *s; s++)
        n += *s == '\n';
    return n;
}

TEST(cli_bench_table_and_csv)
{
    char csv[512], png[512], cmd[2048];
    snprintf(csv, sizeof csv, "%s/bench.csv", harness_tmpdir());
    snprintf(png, sizeof png, "%s/bench.png", harness_tmpdir());
    snprintf(cmd, sizeof cmd,
             "%s bench spd:balls:1 spd:tetra:2 --res 17 --validate 300 --repeat 2 --quiet --csv %s "
             "--plot %s",
             harness_cli(), csv, png);
    int st;
    char *out = harness_run(cmd, &st);
    REQUIRE(out);
    CHECK_EQ_INT(st, 0);
    CHECK_STR_CONTAINS(out, "| scene | N | method | T_B 1t / ");
    /* small scenes: naive, kaplan and sah for each */
    CHECK_STR_CONTAINS(out, "| spd:balls:1 | 11 | naive |");
    CHECK_STR_CONTAINS(out, "| spd:tetra:2 | 16 | kaplan |");
    CHECK_STR_CONTAINS(out, "| spd:tetra:2 | 16 | sah |");
    free(out);
    FILE *f = fopen(csv, "r");
    REQUIRE(f);
    char line[4096];
    REQUIRE(fgets(line, sizeof line, f));
    /* the stable column names scripts read */
    CHECK(strncmp(line, "scene,N,accel,T_B,bytes,N_IN,N_V,N_EV,N_OIV,", 44) == 0);
    CHECK_STR_CONTAINS(line, ",N_IT,N_TS,");
    CHECK_STR_CONTAINS(line, "primary_Mrays_1t");
    CHECK_STR_CONTAINS(line, ",T_B_all,model_cost,digest");
    int rows = 0, digests = 0;
    while (fgets(line, sizeof line, f)) {
        rows++;
        /* the last column: a tree's 16 hex digits, empty for naive */
        const char *last = strrchr(line, ',');
        REQUIRE(last);
        size_t len = strcspn(last + 1, "\r\n");
        CHECK_MSG(len == (strstr(line, ",naive,") ? 0u : 16u), "digest column '%s'", last + 1);
        digests += len == 16;
    }
    fclose(f);
    CHECK_EQ_INT(rows, 6);
    CHECK_EQ_INT(digests, 4);
    /* --plot: a bar of each method's colour (naive, kaplan, sah: 0, 1, 2) */
    bsp_image *chart = NULL;
    bsp_error err;
    REQUIRE(bsp_image_read_png(png, &chart, &err) == BSP_OK);
    CHECK_EQ_INT(chart->width, 960);
    CHECK_EQ_INT(chart->height, 640);
    for (int k = 0; k < 3; k++)
        CHECK_MSG(harness_count_color(chart, k) > 100, "no bar of method %d", k);
    bsp_image_destroy(chart);
    /* an unwritable --plot path fails before any work, naming the file */
    snprintf(cmd, sizeof cmd, "%s bench spd:balls:1 --plot %s/no/such/dir/b.png 2>&1",
             harness_cli(), harness_tmpdir());
    CHECK_RUN(cmd, 1, "b.png: cannot open for writing");
    /* the default scene list runs too (here with one method on a tiny size
     * would take long; just check that an unknown method is a usage error) */
    snprintf(cmd, sizeof cmd, "%s bench spd:balls:1 --accel quadtree 2>&1", harness_cli());
    CHECK_RUN(cmd, 2, "unknown acceleration method 'quadtree'");
    snprintf(cmd, sizeof cmd, "%s bench spd:balls:1 --repeat 0 2>&1", harness_cli());
    CHECK_RUN(cmd, 2, "'--repeat'");
}

/* render and viz check every output path before they work: an unwritable
 * one fails at once (exit 1, the file named), with no statistics printed and
 * none of the other outputs written. */
TEST(cli_outputs_checked_before_the_render)
{
    char cmd[4096], img[512], json[512], bad[512];
    harness_tmp_path(img, sizeof img, "early.png");
    harness_tmp_path(json, sizeof json, "early.json");
    harness_tmp_path(bad, sizeof bad, "no/such/dir/out");
    const char *needle[3] = {"out.png: cannot open for writing", "out.json: cannot open for writing",
                             "out.png: cannot open for writing"};
    for (int c = 0; c < 3; c++) {
        remove(img);
        remove(json);
        char opts[2048];
        if (c == 0) /* the image */
            snprintf(opts, sizeof opts, "-o %s.png --stats-json %s", bad, json);
        else if (c == 1) /* the statistics */
            snprintf(opts, sizeof opts, "-o %s --stats-json %s.json", img, bad);
        else /* the cost map */
            snprintf(opts, sizeof opts, "-o %s --stats-json %s --cost-map %s.png", img, json, bad);
        snprintf(cmd, sizeof cmd, "%s render spd:balls:1 --res 16 %s 2>&1", harness_cli(), opts);
        int st;
        char *out = harness_run(cmd, &st);
        REQUIRE(out);
        CHECK_EQ_INT(st, 1);
        CHECK_STR_CONTAINS(out, needle[c]);
        CHECK_MSG(!strstr(out, "PrimaryRay"), "case %d rendered before failing:\n%s", c, out);
        free(out);
        FILE *f = fopen(img, "rb"), *g = fopen(json, "rb");
        CHECK_MSG(!f && !g, "case %d left an output behind (image %d, json %d)", c, f != NULL,
                  g != NULL);
        if (f)
            fclose(f);
        if (g)
            fclose(g);
    }
    snprintf(cmd, sizeof cmd, "%s viz spd:balls:1 --accel sah -o %s.png 2>&1", harness_cli(), bad);
    CHECK_RUN(cmd, 1, "out.png: cannot open for writing");
}

/* The ScnCoverage and PrimaryRay of a render's --stats-json file. */
static int json_coverage(const char *path, double *cov, long *primary)
{
    FILE *f = fopen(path, "r");
    if (!f)
        return 0;
    char buf[8192];
    size_t n = fread(buf, 1, sizeof buf - 1, f);
    fclose(f);
    buf[n] = 0;
    const char *c = strstr(buf, "\"ScnCoverage\": "), *p = strstr(buf, "\"PrimaryRay\": ");
    return c && p && sscanf(c + 15, "%lf", cov) == 1 && sscanf(p + 14, "%ld", primary) == 1;
}

/* bench --paper: #rays of the primary block is 513 x 513, and ScnCov is what
 * the plain renderer reports for the same camera (perspective and ortho). */
TEST(cli_bench_paper_counts)
{
    char csv[512], png[512], json[2][512], cmd[4096];
    snprintf(csv, sizeof csv, "%s/paper.csv", harness_tmpdir());
    snprintf(png, sizeof png, "%s/paper_plot.png", harness_tmpdir());
    snprintf(json[0], sizeof json[0], "%s/paper_persp.json", harness_tmpdir());
    snprintf(json[1], sizeof json[1], "%s/paper_ortho.json", harness_tmpdir());
    snprintf(cmd, sizeof cmd,
             "%s bench --paper spd:rings:1 --accel sah,sah-per,sah-par --validate 200 --repeat 1 --quiet "
             "--csv %s --plot %s",
             harness_cli(), csv, png);
    int st;
    char *out = harness_run(cmd, &st);
    REQUIRE(out);
    CHECK_EQ_INT(st, 0);
    CHECK_STR_CONTAINS(out, "| **# intersection tests per ray** |");
    CHECK_STR_CONTAINS(out, "| sah-par, ortho |");
    CHECK_STR_CONTAINS(out, "N_IT primary: sah-per vs sah");
    free(out);
    /* --plot: one bar per rule in its colour (sah, sah-per, sah-par: 0, 1, 2),
     * none of a fourth */
    bsp_image *chart = NULL;
    bsp_error err;
    REQUIRE(bsp_image_read_png(png, &chart, &err) == BSP_OK);
    for (int k = 0; k < 3; k++)
        CHECK_MSG(harness_count_color(chart, k) > 100, "no bar of rule %d", k);
    CHECK_EQ_INT(harness_count_color(chart, 3), 0);
    bsp_image_destroy(chart);
    for (int ortho = 0; ortho < 2; ortho++) {
        snprintf(cmd, sizeof cmd,
                 "%s render spd:rings:1 --res 513 --quiet %s --stats-json %s -o %s/paper.png",
                 harness_cli(), ortho ? "--ortho auto" : "", json[ortho], harness_tmpdir());
        out = harness_run(cmd, &st);
        CHECK_EQ_INT(st, 0);
        free(out);
    }
    double cov[2] = {-1, -1};
    long prim[2] = {0, 0};
    REQUIRE(json_coverage(json[0], &cov[0], &prim[0]));
    REQUIRE(json_coverage(json[1], &cov[1], &prim[1]));
    CHECK_EQ_INT(prim[0], 513 * 513);
    FILE *f = fopen(csv, "r");
    REQUIRE(f);
    char line[1024];
    REQUIRE(fgets(line, sizeof line, f));
    CHECK(strncmp(line, "scene,accel,camera,rays,ScnCov,nrays,N_V,N_IT,N_TS,T_B,T_TR", 59) == 0);
    int rows = 0;
    while (fgets(line, sizeof line, f)) {
        char scene[64], accel[32], camera[32], rays[16];
        double c;
        long nrays;
        REQUIRE(sscanf(line, "%63[^,],%31[^,],%31[^,],%15[^,],%lf,%ld", scene, accel, camera,
                       rays, &c, &nrays) == 6);
        int ortho = strcmp(camera, "ortho") == 0;
        CHECK_EQ_INT(ortho, strcmp(accel, "sah-par") == 0);
        CHECK_NEAR(c, cov[ortho], 1e-4);
        if (strcmp(rays, "primary") == 0)
            CHECK_EQ_INT(nrays, 513 * 513);
        else
            CHECK(nrays > 513 * 513);
        rows++;
    }
    fclose(f);
    CHECK_EQ_INT(rows, 6); /* 3 rules x primary, all */
}

/* Field K (1-based, between '|') of the row of `bspray ab`'s table that
 * starts with "| spd:", as two numbers "X / Y"; 0 when not found. */
static int ab_pair(const char *out, int k, double *x, double *y)
{
    const char *row = strstr(out, "\n| spd:");
    if (!row)
        return 0;
    row += 1; /* the '|' before field 1 */
    for (int f = 1; f < k; f++) {
        row = strchr(row + 1, '|');
        if (!row)
            return 0;
    }
    return sscanf(row + 1, " %lf / %lf", x, y) == 2;
}

/* Runs `bspray ab ARGS`; checks exit status 0, the rays column (RAYS) and
 * that every ray got the same answer from A and B; *STEPS and *LEAVES get
 * the N_TS and leaves of A ([0]) and B ([1]). */
static void ab_run(const char *args, const char *rays, double steps[2], double leaves[2])
{
    char cmd[1024];
    int st;
    snprintf(cmd, sizeof cmd, "%s ab %s", harness_cli(), args);
    char *out = harness_run(cmd, &st);
    REQUIRE(out);
    CHECK_EQ_INT(st, 0);
    CHECK_STR_CONTAINS(out, "| B/A best |");
    CHECK_STR_CONTAINS(out, rays);
    CHECK_STR_CONTAINS(out, "| yes |");
    CHECK(ab_pair(out, 7, &steps[0], &steps[1]));
    CHECK(ab_pair(out, 9, &leaves[0], &leaves[1]));
    free(out);
}

/* `bspray ab`: with no option of B the two trees are the same, so are their
 * counters; Kaplan's tree differs from sah's but answers every ray alike. */
TEST(cli_ab_times_two_structures_on_the_same_rays)
{
    double steps[2] = {-1, -2}, leaves[2] = {-1, -2};
    ab_run("spd:tetra:3 --res 33 --rounds 1 --slice 100", "| 1089 primary |", steps, leaves);
    CHECK(steps[0] > 1.0 && steps[0] == steps[1]);
    CHECK(leaves[0] > 10 && leaves[0] == leaves[1]);
    ab_run("spd:balls:2 --rays all --depth 2 --res 33 --rounds 2 --accel kaplan", " all |", steps,
           leaves);
    CHECK(leaves[0] > 10 && leaves[1] > 10 && leaves[0] != leaves[1]);
    CHECK(steps[0] > 1.0 && steps[1] > steps[0]); /* Kaplan's tree: more steps */
    char cmd[1024];
    snprintf(cmd, sizeof cmd, "%s ab spd:tetra:3 --rays some 2>&1", harness_cli());
    CHECK_RUN(cmd, 2, "--rays: expected primary or all");
    snprintf(cmd, sizeof cmd, "%s ab spd:tetra:3 --rounds 0 2>&1", harness_cli());
    CHECK_RUN(cmd, 2, "'--rounds'");
    snprintf(cmd, sizeof cmd, "%s ab 2>&1", harness_cli());
    CHECK_RUN(cmd, 2, "missing SCENE");
}

TEST(cli_stats_of_a_tree)
{
    char cmd[1024];
    snprintf(cmd, sizeof cmd, "%s stats spd:tree:4 --accel sah --check", harness_cli());
    int st;
    char *out = harness_run(cmd, &st);
    REQUIRE(out);
    CHECK_EQ_INT(st, 0);
    CHECK_STR_CONTAINS(out, "primitives: 63");
    CHECK_STR_CONTAINS(out, "N_V");
    CHECK_STR_CONTAINS(out, "invariants     ok");
    CHECK_STR_CONTAINS(out, "digest");
    free(out);
    /* with every cost 1 (a 4-gon: 0.5 + 4 x 0.125) the model cost is the
     * expected cost with unit costs */
    snprintf(cmd, sizeof cmd,
             "%s stats spd:tree:4 --accel sah --costs "
             "traversal=1,sphere=1,cone=1,triangle=1,polygon=0.5,vertex=0.125",
             harness_cli());
    out = harness_run(cmd, &st);
    REQUIRE(out);
    CHECK_EQ_INT(st, 0);
    const char *e = strstr(out, "expected cost"), *m = strstr(out, "model cost");
    double ev = -1.0, mv = -2.0;
    REQUIRE(e && m);
    CHECK(sscanf(e, "expected cost %lf", &ev) == 1 && sscanf(m, "model cost %lf", &mv) == 1);
    CHECK_MSG(ev > 1.0 && ev == mv, "expected %g, model %g", ev, mv);
    free(out);
}

/* --build-threads reaches the BVHs' threaded build: `stats` of the eight-wide
 * BVH of a scene large enough for tasks (16,384 triangles) on one thread and
 * on three prints the same digest and passes the checker both times. */
TEST(cli_stats_bvh_same_tree_on_any_thread_count)
{
    char digest[2][64] = {"", ""};
    for (int i = 0; i < 2; i++) {
        char cmd[1024];
        snprintf(cmd, sizeof cmd, "%s stats spd:tetra:7 --accel bvh8 --check --build-threads %d",
                 harness_cli(), i ? 3 : 1);
        int st;
        char *out = harness_run(cmd, &st);
        REQUIRE(out);
        CHECK_EQ_INT(st, 0);
        CHECK_STR_CONTAINS(out, "invariants     ok");
        const char *d = strstr(out, "digest");
        REQUIRE(d);
        CHECK(sscanf(d, "digest %63s", digest[i]) == 1 && strlen(digest[i]) == 16);
        free(out);
    }
    CHECK_MSG(strcmp(digest[0], digest[1]) == 0, "digests %s and %s", digest[0], digest[1]);
}

/* The member KEY of the JSON text J (its first occurrence, as the writers
 * print them: "KEY": VALUE) as text, or NULL. */
static const char *json_member(const char *j, const char *key)
{
    char pat[128];
    snprintf(pat, sizeof pat, "\"%s\": ", key);
    const char *p = strstr(j, pat);
    return p ? p + strlen(pat) : NULL;
}

static double json_num(const char *j, const char *key)
{
    const char *v = json_member(j, key);
    return v ? strtod(v, NULL) : -1.0;
}

static char *read_text(const char *path)
{
    size_t len;
    return (char *)harness_read_file(path, &len);
}

/* FILES (paths separated by spaces) parse as JSON, by python3's parser; where
 * there is no python3 that is said, and the syntax is not checked. */
static void check_json_syntax(const char *files)
{
    char cmd[4096];
    snprintf(cmd, sizeof cmd,
             "python3 -c 'import json,sys; [json.load(open(a, encoding=\"utf-8\")) for a in "
             "sys.argv[1:]]' %s 2>&1",
             files);
    int st;
    char *out = harness_run(cmd, &st);
    REQUIRE(out);
    if (st == 127)
        printf("  python3 not found: the JSON syntax of %s is not checked\n", files);
    else
        CHECK_MSG(st == 0, "%s: a file does not parse as JSON: %s", files, out);
    free(out);
}

/* Runs CMD, which must exit 0, and returns the text of the JSON file PATH it
 * wrote (NULL, with a failure, when it did not). */
static char *json_of_run(const char *cmd, const char *path)
{
    int st;
    char *out = harness_run(cmd, &st);
    CHECK_MSG(out && st == 0, "'%s' exited with %d: %s", cmd, st, out ? out : "");
    free(out);
    return read_text(path);
}

/* stats --stats-json, and the tree figures render, trace and build add to theirs:
 * every figure is the library's for the same scene and options
 * (bsp_accel_tree_stats of a build in this process: the build makes the same
 * tree on any number of threads), the numbers read back bit for bit, and
 * every file is JSON (python3's parser, where there is one). */
TEST(cli_stats_json_matches_the_library)
{
    const char *spec = "spd:tree:5";
    bsp_scene *scene;
    bsp_error err;
    REQUIRE(bsp_scene_load(spec, &scene, &err) == BSP_OK);
    bsp_build_options o;
    bsp_build_options_defaults(&o);
    bsp_accel *accel;
    REQUIRE(bsp_accel_build(scene, &o, &accel, &err) == BSP_OK);
    bsp_tree_stats t;
    bsp_accel_tree_stats(accel, &t);
    bsp_accel_destroy(accel);
    char digest[32];
    snprintf(digest, sizeof digest, "\"%016llx\"", (unsigned long long)t.digest);

    char sj[512], rj[512], tj[512], img[512], rays[512], cmd[4096];
    harness_tmp_path(sj, sizeof sj, "stats.json");
    harness_tmp_path(rj, sizeof rj, "render.json");
    harness_tmp_path(tj, sizeof tj, "trace.json");
    harness_tmp_path(img, sizeof img, "stats_json.png");
    harness_tmp_path(rays, sizeof rays, "stats_json");
    snprintf(cmd, sizeof cmd, "%s stats %s --accel sah --check --stats-json %s", harness_cli(),
             spec, sj);
    char *j = json_of_run(cmd, sj);
    REQUIRE(j);
    CHECK_EQ_INT((long)json_num(j, "primitives"), (long)bsp_scene_prim_count(scene));
    for (int k = 0; k < BSP_PRIM_KIND_COUNT; k++)
        CHECK_EQ_INT((long)json_num(j, bsp_prim_kind_name((bsp_prim_kind)k)),
                     (long)bsp_scene_kind_count(scene, (bsp_prim_kind)k));
    bsp_box b = bsp_scene_bounds(scene);
    const char *mn = json_member(j, "min"), *mx = json_member(j, "max");
    double v[6];
    REQUIRE(mn && mx && sscanf(mn, "[%lf, %lf, %lf]", &v[0], &v[1], &v[2]) == 3 &&
            sscanf(mx, "[%lf, %lf, %lf]", &v[3], &v[4], &v[5]) == 3);
    CHECK(v[0] == b.lo.x && v[1] == b.lo.y && v[2] == b.lo.z);
    CHECK(v[3] == b.hi.x && v[4] == b.hi.y && v[5] == b.hi.z); /* bit for bit */
    CHECK_EQ_INT((long)json_num(j, "N_IN"), (long)t.interior_nodes);
    CHECK_EQ_INT((long)json_num(j, "N_V"), (long)t.leaves);
    CHECK_EQ_INT((long)json_num(j, "N_EV"), (long)t.empty_leaves);
    CHECK_EQ_INT((long)json_num(j, "N_OIV"), (long)t.references);
    CHECK_EQ_INT((long)json_num(j, "leaf_depth_max"), (long)t.max_leaf_depth);
    CHECK(json_num(j, "leaf_depth_mean") == t.avg_leaf_depth);
    CHECK(json_num(j, "expected_cost") == t.expected_cost);
    CHECK(json_num(j, "model_cost") == t.model_cost);
    CHECK_EQ_INT((long)json_num(j, "tree_bytes"), (long)t.bytes);
    CHECK_STR_CONTAINS(j, digest);
    CHECK_STR_CONTAINS(j, "\"invariants\": \"ok\"");
    CHECK_STR_CONTAINS(j, "\"accel\": \"sah\"");
    free(j);

    /* render, trace, build, and stats of the tree build saved: the same figures
     * of the same tree */
    char bj[512], lj[512], kdt[512], cmds[4][4096];
    harness_tmp_path(bj, sizeof bj, "build.json");
    harness_tmp_path(lj, sizeof lj, "loaded.json");
    harness_tmp_path(kdt, sizeof kdt, "stats_json.kdt");
    snprintf(cmds[0], sizeof cmds[0],
             "%s render %s --res 9 --quiet --save-rays %s --stats-json %s -o %s", harness_cli(),
             spec, rays, rj, img);
    snprintf(cmds[1], sizeof cmds[1], "%s trace %s --rays %s-primary.txt --stats-json %s",
             harness_cli(), spec, rays, tj); /* the render's rays */
    snprintf(cmds[2], sizeof cmds[2], "%s build %s -o %s --quiet --stats-json %s", harness_cli(),
             spec, kdt, bj);
    snprintf(cmds[3], sizeof cmds[3], "%s stats %s --tree %s --stats-json %s", harness_cli(), spec,
             kdt, lj);
    const char *files[4] = {rj, tj, bj, lj};
    for (int i = 0; i < 4; i++) {
        j = json_of_run(cmds[i], files[i]);
        REQUIRE(j);
        CHECK_STR_CONTAINS(j, digest);
        CHECK_EQ_INT((long)json_num(j, "N_V"), (long)t.leaves);
        CHECK_EQ_INT((long)json_num(j, "N_OIV"), (long)t.references);
        CHECK(json_num(j, "expected_cost") == t.expected_cost);
        if (i == 3) /* loaded, not built */
            CHECK_MSG(json_member(j, "tree_file") && json_member(j, "T_load") &&
                          !json_member(j, "T_B"),
                      "%s", j);
        free(j);
    }

    /* the naive method has no digest; without --accel there is no structure member */
    char nj[512], sc[512];
    harness_tmp_path(nj, sizeof nj, "naive.json");
    harness_tmp_path(sc, sizeof sc, "scene.json");
    snprintf(cmd, sizeof cmd,
             "%s stats %s --accel naive --stats-json %s && %s stats %s --stats-json %s",
             harness_cli(), spec, nj, harness_cli(), spec, sc);
    j = json_of_run(cmd, nj);
    REQUIRE(j);
    CHECK_STR_CONTAINS(j, "\"digest\": null");
    free(j);
    j = read_text(sc);
    REQUIRE(j);
    CHECK_MSG(!strstr(j, "structure") && json_member(j, "materials"), "%s", j);
    free(j);

    /* valid JSON, by a parser of its own */
    snprintf(cmd, sizeof cmd, "%s %s %s %s %s %s %s", sj, rj, tj, bj, lj, nj, sc);
    check_json_syntax(cmd);

    /* an unwritable file: exit 1 before anything is loaded or printed */
    snprintf(cmd, sizeof cmd, "%s stats %s --accel sah --stats-json %s/no/such/dir/x.json 2>&1",
             harness_cli(), spec, harness_tmpdir());
    int st;
    char *out = harness_run(cmd, &st);
    REQUIRE(out);
    CHECK_EQ_INT(st, 1);
    CHECK_STR_CONTAINS(out, "x.json: cannot open for writing");
    CHECK_MSG(!strstr(out, "primitives:"), "stats printed before failing:\n%s", out);
    free(out);
    bsp_scene_destroy(scene);
}

/* A scene's path in the JSON files is a JSON string whatever its bytes: UTF-8
 * kept as it is, a quote escaped, a byte of another encoding replaced by
 * U+FFFD (it made the file invalid before). */
TEST(cli_json_scene_names_stay_json)
{
    static const char *const names[2] = {"szene-\xc3\xbc.nff", "bad-\xff\"q.nff"};
    static const char *const tail[2] = {"szene-\xc3\xbc.nff\"", "bad-\\ufffd\\\"q.nff\""};
    for (int i = 0; i < 2; i++) {
        char nff[512], json[512], cmd[4096];
        harness_tmp_path(nff, sizeof nff, names[i]);
        harness_tmp_path(json, sizeof json, i ? "name1.json" : "name0.json");
        /* the shell sees the name in single quotes; it holds none */
        snprintf(cmd, sizeof cmd, "%s gen balls -s 1 -o '%s' && %s stats '%s' --stats-json %s",
                 harness_cli(), nff, harness_cli(), nff, json);
        char *j = json_of_run(cmd, json);
        REQUIRE(j);
        const char *v = json_member(j, "scene");
        REQUIRE(v);
        const char *end = strchr(v + 1, '\n');
        REQUIRE(end);
        size_t tl = strlen(tail[i]);
        /* the value ends with the name as written (then a comma) */
        CHECK_MSG((size_t)(end - v) > tl && !strncmp(end - 1 - tl, tail[i], tl),
                  "case %d: %.*s", i, (int)(end - v), v);
        free(j);
        check_json_syntax(json);
    }
}

TEST(cli_gen_round_trip)
{
    char path[512], cmd[2048];
    snprintf(path, sizeof path, "%s/gen_tree.nff", harness_tmpdir());
    snprintf(cmd, sizeof cmd, "%s gen tree -s 3 -o %s && %s stats %s", harness_cli(), path,
             harness_cli(), path);
    int st;
    char *out = harness_run(cmd, &st);
    REQUIRE(out);
    CHECK_EQ_INT(st, 0);
    /* tree: 2^(SF+1) - 1 cones and spheres + 1 ground square */
    CHECK_STR_CONTAINS(out, "sphere   15");
    CHECK_STR_CONTAINS(out, "cone     15");
    CHECK_STR_CONTAINS(out, "polygon  1");
    free(out);
    /* the file holds the very scene: the tree built from it is the generator's, bit for bit */
    char digest[2][32] = {"", ""};
    for (int i = 0; i < 2; i++) {
        snprintf(cmd, sizeof cmd, "%s stats %s --accel sah", harness_cli(),
                 i ? path : "spd:tree:3");
        out = harness_run(cmd, &st);
        REQUIRE(out);
        CHECK_EQ_INT(st, 0);
        const char *d = strstr(out, "digest");
        REQUIRE(d);
        CHECK(sscanf(d, "digest %31s", digest[i]) == 1);
        free(out);
    }
    CHECK_MSG(digest[0][0] && strcmp(digest[0], digest[1]) == 0, "digests %s (generated), %s (file)",
              digest[0], digest[1]);
    /* the name may carry the size and level as a SCENE does: the same text */
    char *by_options = NULL, *by_name = NULL;
    snprintf(cmd, sizeof cmd, "%s gen balls -s 2 -t 4", harness_cli());
    by_options = harness_run(cmd, &st);
    REQUIRE(by_options);
    CHECK_EQ_INT(st, 0);
    snprintf(cmd, sizeof cmd, "%s gen spd:balls:2:t4", harness_cli());
    by_name = harness_run(cmd, &st);
    REQUIRE(by_name);
    CHECK_EQ_INT(st, 0);
    CHECK_MSG(strlen(by_options) > 1000 && strcmp(by_options, by_name) == 0,
              "gen spd:balls:2:t4 differs from gen balls -s 2 -t 4");
    free(by_options);
    free(by_name);
    static const char *const bad[] = {"balls:x", "balls:", "balls:1:t1", "balls:2 -s 3"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        snprintf(cmd, sizeof cmd, "%s gen %s 2>&1 >/dev/null", harness_cli(), bad[i]);
        out = harness_run(cmd, &st);
        REQUIRE(out);
        CHECK_MSG(st == 2 && strstr(out, "usage: bspray gen"), "gen %s: status %d, '%s'", bad[i],
                  st, out);
        free(out);
    }
}

/* Every file of the NFF malformed corpus fails through the CLI with exit
 * status 1 and a message naming the file (and a line where it has one). */
TEST(cli_nff_corpus_exit_status)
{
    DIR *d = opendir("tests/data/nff_bad");
    REQUIRE(d);
    struct dirent *e;
    int n = 0;
    while ((e = readdir(d))) {
        if (e->d_name[0] == '.')
            continue;
        char path[1024], cmd[2048];
        snprintf(path, sizeof path, "tests/data/nff_bad/%s", e->d_name);
        snprintf(cmd, sizeof cmd, "%s stats '%s' 2>&1 >/dev/null", harness_cli(), path);
        int st;
        char *out = harness_run(cmd, &st);
        REQUIRE(out);
        CHECK_MSG(st == 1, "%s: exit status %d, expected 1", path, st);
        CHECK_MSG(strstr(out, path) != NULL, "%s: message does not name the file: %s", path, out);
        CHECK_MSG(count_lines(out) >= 1 && strncmp(out, "bspray: ", 8) == 0,
                  "%s: unexpected output: %s", path, out);
        free(out);
        n++;
    }
    closedir(d);
    CHECK(n >= 20);
}

/* The value after LABEL in stats output (e.g. "N_V"), or -1. */
static long stats_field(const char *out, const char *label)
{
    const char *p = strstr(out, label);
    return p ? strtol(p + strlen(label), NULL, 10) : -1;
}

/* --costs, --empty-bonus, --min-saving, --leaf-budget and --straddle reach the builder: the CLI's tree has the
 * leaves and references of the tree the API builds with the same costs (an independent build),
 * which differ from the default tree's; bad lists are usage errors (exit 2) that name the option.
 */
TEST(cli_costs_reach_the_builder)
{
    bsp_scene *s = NULL;
    bsp_error err;
    REQUIRE(bsp_scene_load("spd:lattice:2", &s, &err) == BSP_OK);
    bsp_build_options o;
    bsp_build_options_defaults(&o);
    o.sah_costs.traversal = 0.3;
    o.sah_costs.cone = 4.0;
    o.sah_empty_bonus = -1.0; /* --empty-bonus 0: none */
    bsp_accel *a = NULL;
    REQUIRE(bsp_accel_build(s, &o, &a, &err) == BSP_OK);
    bsp_tree_stats want;
    bsp_accel_tree_stats(a, &want);
    bsp_accel_destroy(a);
    bsp_build_options_defaults(&o);
    REQUIRE(bsp_accel_build(s, &o, &a, &err) == BSP_OK);
    bsp_tree_stats plain;
    bsp_accel_tree_stats(a, &plain);
    bsp_accel_destroy(a);
    bsp_scene_destroy(s);
    CHECK(want.leaves != plain.leaves); /* the costs matter on this scene */

    char cmd[1024];
    snprintf(cmd, sizeof cmd,
             "%s stats spd:lattice:2 --accel sah --costs traversal=0.3,cone=4 --empty-bonus 0",
             harness_cli());
    int st;
    char *out = harness_run(cmd, &st);
    REQUIRE(out);
    CHECK_EQ_INT(st, 0);
    CHECK(stats_field(out, "N_V") == (long)want.leaves);
    CHECK(stats_field(out, "N_OIV") == (long)want.references);
    free(out);

    /* bench --scaling takes them too: its CSV's 10th column is N_V */
    char csv[512];
    snprintf(csv, sizeof csv, "%s/costs.csv", harness_tmpdir());
    snprintf(cmd, sizeof cmd,
             "%s bench --scaling spd:lattice:2 --repeat 1 --quiet --costs traversal=0.3,cone=4 "
             "--empty-bonus 0 --csv %s",
             harness_cli(), csv);
    out = harness_run(cmd, &st);
    REQUIRE(out);
    CHECK_EQ_INT(st, 0);
    free(out);
    FILE *f = fopen(csv, "r");
    REQUIRE(f);
    char line[1024];
    REQUIRE(fgets(line, sizeof line, f)); /* header */
    CHECK_STR_CONTAINS(line, ",N_IN,N_V,N_OIV,");
    REQUIRE(fgets(line, sizeof line, f));
    fclose(f);
    remove(csv);
    const char *field = line;
    for (int i = 0; i < 9 && field; i++) {
        field = strchr(field, ',');
        field = field ? field + 1 : NULL;
    }
    REQUIRE(field);
    CHECK(strtol(field, NULL, 10) == (long)want.leaves);

    /* --min-saving 0 (none) reaches it too: tetra's unlimited tree */
    REQUIRE(bsp_scene_load("spd:tetra", &s, &err) == BSP_OK);
    bsp_build_options_defaults(&o);
    o.sah_min_saving = -1.0;
    REQUIRE(bsp_accel_build(s, &o, &a, &err) == BSP_OK);
    bsp_accel_tree_stats(a, &want);
    bsp_accel_destroy(a);
    bsp_scene_destroy(s);
    snprintf(cmd, sizeof cmd, "%s stats spd:tetra --accel sah --min-saving 0", harness_cli());
    out = harness_run(cmd, &st);
    REQUIRE(out);
    CHECK_EQ_INT(st, 0);
    CHECK(stats_field(out, "N_V") == (long)want.leaves);
    free(out);
    snprintf(cmd, sizeof cmd, "%s stats spd:tetra --accel sah", harness_cli());
    out = harness_run(cmd, &st);
    REQUIRE(out);
    CHECK(stats_field(out, "N_V") < (long)want.leaves); /* the default limit prunes */
    free(out);

    /* --leaf-budget and --leaf-budget-min reach it: tetra's tree of at most
     * half a leaf per primitive, as the API builds it */
    REQUIRE(bsp_scene_load("spd:tetra", &s, &err) == BSP_OK);
    bsp_build_options_defaults(&o);
    o.sah_leaf_budget = 0.5;
    o.sah_leaf_budget_min = 1;
    REQUIRE(bsp_accel_build(s, &o, &a, &err) == BSP_OK);
    bsp_accel_tree_stats(a, &want);
    bsp_accel_destroy(a);
    CHECK(want.leaves <= bsp_scene_prim_count(s) / 2);
    bsp_scene_destroy(s);
    snprintf(cmd, sizeof cmd, "%s stats spd:tetra --leaf-budget 0.5 --leaf-budget-min 1",
             harness_cli());
    out = harness_run(cmd, &st);
    REQUIRE(out);
    CHECK_EQ_INT(st, 0);
    CHECK(stats_field(out, "N_V") == (long)want.leaves);
    CHECK(stats_field(out, "N_OIV") == (long)want.references);
    free(out);

    /* --straddle twice reaches it (shells:2: the plain model's tree is far
     * smaller); --mailbox off alone keeps the default tree */
    REQUIRE(bsp_scene_load("spd:shells:2", &s, &err) == BSP_OK);
    bsp_build_options_defaults(&o);
    o.sah_straddle_twice = 1;
    REQUIRE(bsp_accel_build(s, &o, &a, &err) == BSP_OK);
    bsp_accel_tree_stats(a, &want);
    bsp_accel_destroy(a);
    bsp_build_options_defaults(&o);
    REQUIRE(bsp_accel_build(s, &o, &a, &err) == BSP_OK);
    bsp_accel_tree_stats(a, &plain);
    bsp_accel_destroy(a);
    bsp_scene_destroy(s);
    CHECK(want.leaves < plain.leaves);
    const char *straddle[] = {"--straddle twice", "--mailbox off --straddle twice",
                              "--mailbox off", "--straddle once"};
    for (int i = 0; i < 4; i++) {
        snprintf(cmd, sizeof cmd, "%s stats spd:shells:2 --accel sah %s", harness_cli(),
                 straddle[i]);
        out = harness_run(cmd, &st);
        REQUIRE(out);
        CHECK_EQ_INT(st, 0);
        CHECK_MSG(stats_field(out, "N_V") == (long)(i < 2 ? want.leaves : plain.leaves),
                  "%s: N_V %ld", straddle[i], stats_field(out, "N_V"));
        free(out);
    }
    for (int i = 0; i < 2; i++) {
        snprintf(cmd, sizeof cmd, "%s stats spd:shells:2 --accel sah --straddle %s 2>&1",
                 harness_cli(), i ? "" : "thrice");
        out = harness_run(cmd, &st);
        REQUIRE(out);
        CHECK_EQ_INT(st, 2);
        CHECK_STR_CONTAINS(out, "--straddle");
        free(out);
    }

    const char *bad[] = {
        "--costs sphere",         "--costs sphere=0",         "--costs bogus=1",
        "--costs sphere=1,",      "--costs cone=inf",         "--empty-bonus 1",
        "--min-saving -1",        "--min-saving inf",         "--min-saving x",
        "--costs triangle=1e308", "--costs traversal=1e-308", "--costs sphere=2e6",
        "--leaf-budget -1",       "--leaf-budget nan",        "--leaf-budget-min 0",
        "--leaf-budget-min x"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        snprintf(cmd, sizeof cmd, "%s stats spd:lattice:2 --accel sah %s 2>&1", harness_cli(),
                 bad[i]);
        out = harness_run(cmd, &st);
        REQUIRE(out);
        CHECK_EQ_INT(st, 2);
        CHECK(strstr(out, "--costs") || strstr(out, "--empty-bonus") ||
              strstr(out, "--min-saving") || strstr(out, "--leaf-budget"));
        if (strstr(bad[i], "e308") || strstr(bad[i], "2e6"))
            CHECK_STR_CONTAINS(out, "every cost must be a number in [1e-6, 1e6]");
        free(out);
    }

    /* the API clamps a cost to [BSP_SAH_COST_MIN, BSP_SAH_COST_MAX]: 1e308
     * builds the tree of 1e6 (before, the sums overflowed: the tree was one
     * leaf and its model cost inf) */
    REQUIRE(bsp_scene_load("spd:tetra:3", &s, &err) == BSP_OK);
    bsp_tree_stats clamped[2];
    for (int v = 0; v < 2; v++) {
        bsp_build_options_defaults(&o);
        o.sah_costs.triangle = v ? 1e308 : BSP_SAH_COST_MAX;
        REQUIRE(bsp_accel_build(s, &o, &a, &err) == BSP_OK);
        bsp_accel_tree_stats(a, &clamped[v]);
        bsp_accel_destroy(a);
    }
    bsp_scene_destroy(s);
    CHECK(clamped[1].interior_nodes > 0 && isfinite(clamped[1].model_cost));
    CHECK(clamped[0].interior_nodes == clamped[1].interior_nodes &&
          clamped[0].references == clamped[1].references &&
          clamped[0].model_cost == clamped[1].model_cost);
}

/* sah-mixed's check through the CLI: render reports which tree it kept
 * (table and JSON), and the kept tree is the one the C API keeps;
 * --mixed-check off reports none; bench --paper names the scenes where the
 * sah tree was kept and its CSV's last column says so; a bad model is a
 * usage error naming the three models. */
TEST(cli_mixed_check_reports_the_tree_it_kept)
{
    bsp_scene *s = NULL;
    bsp_error err;
    REQUIRE(bsp_scene_load("spd:tree:2", &s, &err) == BSP_OK);
    bsp_build_options o;
    bsp_build_options_defaults(&o);
    o.kind = BSP_ACCEL_SAH_MIXED;
    bsp_accel *a = NULL;
    REQUIRE(bsp_accel_build(s, &o, &a, &err) == BSP_OK);
    bsp_mixed_check chk;
    bsp_accel_mixed_check(a, &chk);
    bsp_tree_stats want;
    bsp_accel_tree_stats(a, &want);
    bsp_accel_destroy(a);
    bsp_scene_destroy(s);
    CHECK(chk.ran);
    const char *kept = chk.kept_sah ? "sah" : "sah-mixed";

    char cmd[1024], json[512], expect[128];
    snprintf(json, sizeof json, "%s/mixed.json", harness_tmpdir());
    snprintf(cmd, sizeof cmd,
             "%s render spd:tree:2 --accel sah-mixed --res 33 --stats-json %s -o %s/mixed.png",
             harness_cli(), json, harness_tmpdir());
    int st;
    char *out = harness_run(cmd, &st);
    REQUIRE(out);
    CHECK_EQ_INT(st, 0);
    snprintf(expect, sizeof expect, "| sah-mixed check | kept the %s tree: ", kept);
    CHECK_STR_CONTAINS(out, expect);
    char nv[64];
    snprintf(nv, sizeof nv, "| N_IN / N_V / N_EV / N_OIV | %llu / %llu /",
             (unsigned long long)want.interior_nodes, (unsigned long long)want.leaves);
    CHECK_STR_CONTAINS(out, nv);
    free(out);
    FILE *f = fopen(json, "r");
    REQUIRE(f);
    char buf[8192];
    size_t n = fread(buf, 1, sizeof buf - 1, f);
    buf[n] = '\0';
    fclose(f);
    snprintf(expect, sizeof expect, "\"mixed_check\": {\"kept\": \"%s\"", kept);
    CHECK_STR_CONTAINS(buf, expect);

    snprintf(cmd, sizeof cmd,
             "%s render spd:tree:2 --accel sah-mixed --mixed-check off --res 17 -o %s/mixed.png",
             harness_cli(), harness_tmpdir());
    out = harness_run(cmd, &st);
    REQUIRE(out);
    CHECK_EQ_INT(st, 0);
    CHECK(strstr(out, "sah-mixed check") == NULL);
    free(out);

    char csv[512];
    snprintf(csv, sizeof csv, "%s/mixed.csv", harness_tmpdir());
    snprintf(cmd, sizeof cmd,
             "%s bench --paper spd:tree:2 --accel sah,sah-mixed --res 33 --validate 100 "
             "--repeat 1 --quiet --csv %s",
             harness_cli(), csv);
    out = harness_run(cmd, &st);
    REQUIRE(out);
    CHECK_EQ_INT(st, 0);
    CHECK_STR_CONTAINS(out, "sah-mixed counted with its check against sah");
    CHECK_STR_CONTAINS(out, chk.kept_sah ? "kept the sah tree on: spd:tree:2;"
                                         : "kept the sah tree on: none.");
    free(out);
    f = fopen(csv, "r");
    REQUIRE(f);
    char line[1024];
    int rows = 0;
    REQUIRE(fgets(line, sizeof line, f));
    CHECK_STR_CONTAINS(line, ",threads,tree");
    while (fgets(line, sizeof line, f)) {
        if (strncmp(line, "spd:tree:2,sah-mixed,", 21) != 0)
            continue;
        const char *last = strrchr(line, ',');
        REQUIRE(last);
        CHECK(strncmp(last + 1, kept, strlen(kept)) == 0 && last[1 + strlen(kept)] == '\n');
        rows++;
    }
    fclose(f);
    CHECK_EQ_INT(rows, 2); /* primary, all */

    snprintf(cmd, sizeof cmd, "%s render spd:tree:2 --accel sah-mixed --mixed-model exact 2>&1",
             harness_cli());
    out = harness_run(cmd, &st);
    REQUIRE(out);
    CHECK_EQ_INT(st, 2);
    CHECK_STR_CONTAINS(out, "expected surface, sampled or counted, got 'exact'");
    free(out);
}

/* bench, bench --paper and bench --scaling check every scene before the work
 * on the first: a bad last scene ends the run at once with exit status 1, its
 * message, and nothing on stdout (no table begun, no rows of the scenes
 * before it). The good first scene, jacks, would take seconds. */
TEST(cli_bench_checks_every_scene_first)
{
    static const char *const modes[] = {"", "--paper", "--scaling"};
    static const struct {
        const char *scene, *message;
    } bad[] = {
        {"spd:nosuch", "unknown SPD scene 'nosuch'"},
        {"spd:tetra:99", "bad size factor '99'"},
        {"spd:balls:2:t99", "bad tessellation 't99'"},
        {"/nonexistent/scene.nff", "/nonexistent/scene.nff: cannot open"},
        {"tests/data/nff_bad/binary_garbage.nff", "binary_garbage.nff"},
    };
    char cmd[1024];
    for (size_t m = 0; m < sizeof modes / sizeof *modes; m++)
        for (size_t i = 0; i < sizeof bad / sizeof *bad; i++) {
            int st;
            snprintf(cmd, sizeof cmd, "%s bench %s spd:jacks %s --quiet 2>/dev/null", harness_cli(),
                     modes[m], bad[i].scene);
            char *out = harness_run(cmd, &st);
            REQUIRE(out);
            CHECK_MSG(st == 1 && out[0] == '\0', "bench %s ... %s: exit %d, stdout '%.80s'",
                      modes[m], bad[i].scene, st, out);
            free(out);
            snprintf(cmd, sizeof cmd, "%s bench %s spd:jacks %s --quiet 2>&1 >/dev/null",
                     harness_cli(), modes[m], bad[i].scene);
            out = harness_run(cmd, &st);
            REQUIRE(out);
            CHECK_STR_CONTAINS(out, bad[i].message);
            free(out);
        }
}

/* The four bench modes read their shared options through one reader
 * (tools/bench_cmdline.c): each refuses an option no mode takes, an option
 * that belongs to another mode, and a --csv it cannot write (before any
 * work, naming the file), and each accepts its own mode word. */
TEST(cli_bench_modes_share_their_options)
{
    static const struct {
        const char *mode;    /* "" for the plain bench */
        const char *foreign; /* an option of another mode */
        const char *scene;
    } modes[] = {
        {"", "--mixed-check", "spd:balls:1"},
        {"--paper", "--grid-res", "spd:balls:1"},
        {"--scaling", "--res", "spd:balls:1"},
        {"--grids", "--plot", "tetra"},
    };
    char cmd[1024];
    for (size_t i = 0; i < sizeof modes / sizeof modes[0]; i++) {
        const char *m = modes[i].mode, *sc = modes[i].scene;
        snprintf(cmd, sizeof cmd, "%s bench %s %s --frobnicate 2>&1", harness_cli(), m, sc);
        CHECK_RUN(cmd, 2, "unknown option '--frobnicate'");
        snprintf(cmd, sizeof cmd, "%s bench %s %s %s 1 2>&1", harness_cli(), m, sc,
                 modes[i].foreign);
        CHECK_RUN(cmd, 2, "unknown option");
        snprintf(cmd, sizeof cmd, "%s bench %s %s --threads 0 2>&1", harness_cli(), m, sc);
        CHECK_RUN(cmd, 2, "--threads");
        snprintf(cmd, sizeof cmd, "%s bench %s %s --quiet --csv %s/no/such/dir/b.csv 2>&1",
                 harness_cli(), m, sc, harness_tmpdir());
        CHECK_RUN(cmd, 1, "b.csv: cannot open for writing");
        snprintf(cmd, sizeof cmd, "%s bench %s --help 2>&1", harness_cli(), m);
        CHECK_RUN(cmd, 0, "usage: bspray bench");
    }
    /* --paper's least resolution is 2 (its per-pixel figures), bench's 1 */
    snprintf(cmd, sizeof cmd, "%s bench --paper spd:balls:1 --res 1 2>&1", harness_cli());
    CHECK_RUN(cmd, 2, "from 2 to 65536");
    snprintf(cmd, sizeof cmd, "%s bench spd:balls:1 --res 0 2>&1", harness_cli());
    CHECK_RUN(cmd, 2, "from 1 to 65536");
    /* the grid's and the octree's options: the plain bench's only */
    snprintf(cmd, sizeof cmd, "%s bench --scaling spd:balls:1 --octree-split cost 2>&1",
             harness_cli());
    CHECK_RUN(cmd, 2, "unknown option '--octree-split'");
}

TEST(cli_bench_names_the_cells_variants)
{
    /* the grid listing by bounds and the octree cut by cost are named as
     * such in the table (and its CSV), so a pasted table says what it is,
     * and --accel takes those names */
    char cmd[1024];
    snprintf(cmd, sizeof cmd,
             "%s bench spd:balls:1 --accel octree,grid --octree-split cost --grid-assign bounds "
             "--res 9 --validate 200 --repeat 1 --quiet 2>&1",
             harness_cli());
    int st;
    char *out = harness_run(cmd, &st);
    REQUIRE(out);
    CHECK_EQ_INT(st, 0);
    CHECK_STR_CONTAINS(out, "| spd:balls:1 | 11 | octree-cost |");
    CHECK_STR_CONTAINS(out, "| spd:balls:1 | 11 | grid-bounds |");
    free(out);
    /* the same names as methods: both octrees and both grids in one run */
    snprintf(cmd, sizeof cmd,
             "%s bench spd:balls:1 --accel octree,octree-cost,grid,grid-bounds --res 9 "
             "--validate 200 --repeat 1 --quiet 2>&1",
             harness_cli());
    out = harness_run(cmd, &st);
    REQUIRE(out);
    CHECK_EQ_INT(st, 0);
    CHECK_STR_CONTAINS(out, "| spd:balls:1 | 11 | octree |");
    CHECK_STR_CONTAINS(out, "| spd:balls:1 | 11 | octree-cost |");
    CHECK_STR_CONTAINS(out, "| spd:balls:1 | 11 | grid |");
    CHECK_STR_CONTAINS(out, "| spd:balls:1 | 11 | grid-bounds |");
    free(out);
    snprintf(cmd, sizeof cmd, "%s render spd:balls:1 --accel octree-centre 2>&1", harness_cli());
    CHECK_RUN(cmd, 2, "(known: naive, kaplan, sah, sah-per, sah-par, sah-mixed, grid, octree, "
                      "bvh, bvh4, bvh8, octree-cost, grid-bounds, grid-rec)");
}

/* render --pixel-order: tiles and rows write the same image (compared byte
 * for byte, on two threads and one); a bad value exits 2 with its message. */
TEST(cli_render_pixel_orders_write_the_same_image)
{
    char cmd[4096], a[512], b[512];
    harness_tmp_path(a, sizeof a, "order-rows.png");
    harness_tmp_path(b, sizeof b, "order-tiles.png");
    snprintf(cmd, sizeof cmd,
             "%s render spd:balls:1 --res 45 --pixel-order rows --threads 1 -o %s 2>&1",
             harness_cli(), a);
    CHECK_RUN(cmd, 0, "PrimaryRay");
    snprintf(cmd, sizeof cmd,
             "%s render spd:balls:1 --res 45 --pixel-order tiles --threads 2 -o %s 2>&1",
             harness_cli(), b);
    CHECK_RUN(cmd, 0, "PrimaryRay");
    FILE *f = fopen(a, "rb"), *g = fopen(b, "rb");
    REQUIRE(f && g);
    static unsigned char x[1 << 16], y[1 << 16];
    size_t nx = fread(x, 1, sizeof x, f), ny = fread(y, 1, sizeof y, g);
    fclose(f);
    fclose(g);
    CHECK(nx > 100 && nx < sizeof x);
    CHECK(nx == ny && memcmp(x, y, nx) == 0);
    snprintf(cmd, sizeof cmd, "%s render spd:balls:1 --pixel-order diagonal -o %s 2>&1",
             harness_cli(), a);
    CHECK_RUN(cmd, 2, "option '--pixel-order' takes tiles or rows, got 'diagonal'");
}

/* Output that cannot be written (a full device) fails the command with a
 * message: standard output, a CSV, a JSON file, a tree file, a scene. And
 * what is not a regular file is written where it is and never replaced or
 * removed: a tree saved through a symbolic link leaves the link, and a
 * failed `gen` through a link to the full device leaves that link. */
TEST(cli_write_failures_exit_1_and_keep_what_is_not_a_file)
{
    struct stat full;
    if (stat("/dev/full", &full) != 0 || !S_ISCHR(full.st_mode))
        harness_skip("no /dev/full on this system");
    char link[512], target[512], gen_link[512], cmd[2048];
    harness_tmp_path(link, sizeof link, "saved-through.kdt");
    harness_tmp_path(target, sizeof target, "saved-target.kdt");
    harness_tmp_path(gen_link, sizeof gen_link, "full-link.nff");
    static const struct {
        const char *args, *message;
    } cases[] = {
        {"stats spd:balls:1 > /dev/full", "standard output: write failed"},
        {"render spd:balls:1 --res 8 -o /dev/null > /dev/full", "standard output: write failed"},
        {"gen balls -s 1 > /dev/full", "failed"}, /* by the writer or at the end */
        {"bench spd:balls:1 --accel sah --res 9 --validate 50 --quiet --csv /dev/full > /dev/null",
         "/dev/full: write failed"},
        {"trace spd:balls:1 --rays /dev/null --stats-json /dev/full", "/dev/full: write failed"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        /* stderr to the pipe first, then the case's own redirections */
        snprintf(cmd, sizeof cmd, "%s 2>&1 %s", harness_cli(), cases[i].args);
        int st;
        char *out = harness_run(cmd, &st);
        REQUIRE(out);
        CHECK_MSG(st == 1, "'%s' exited with %d: %s", cases[i].args, st, out);
        CHECK_STR_CONTAINS(out, cases[i].message);
        free(out);
    }
    /* the device itself is never what a tree or a scene is written to here:
     * a regression would replace or remove it; through a link only the link
     * is at stake */
    remove(gen_link);
    REQUIRE(symlink("/dev/full", gen_link) == 0);
    int st;
    char *out;
    snprintf(cmd, sizeof cmd, "%s build spd:balls:1 -o %s 2>&1 >/dev/null", harness_cli(),
             gen_link);
    out = harness_run(cmd, &st);
    REQUIRE(out);
    CHECK_EQ_INT(st, 1);
    CHECK_STR_CONTAINS(out, "cannot write: No space left on device");
    free(out);
    struct stat ls, ts;
    CHECK_MSG(lstat(gen_link, &ls) == 0 && S_ISLNK(ls.st_mode),
              "a failed save replaced the link %s", gen_link);

    remove(link);
    remove(target);
    REQUIRE(symlink(target, link) == 0);
    snprintf(cmd, sizeof cmd, "%s build spd:balls:1 -o %s > /dev/null 2>&1", harness_cli(), link);
    out = harness_run(cmd, &st);
    REQUIRE(out);
    CHECK_EQ_INT(st, 0);
    free(out);
    CHECK_MSG(lstat(link, &ls) == 0 && S_ISLNK(ls.st_mode), "%s is no longer a link", link);
    CHECK_MSG(stat(target, &ts) == 0 && S_ISREG(ts.st_mode) && ts.st_size > 100,
              "the tree did not reach %s", target);
    snprintf(cmd, sizeof cmd, "%s stats spd:balls:1 --tree %s 2>&1", harness_cli(), link);
    out = harness_run(cmd, &st);
    REQUIRE(out);
    CHECK_MSG(st == 0, "the tree saved through a link cannot be loaded: %s", out);
    free(out);

    snprintf(cmd, sizeof cmd, "%s gen balls -s 1 -o %s 2>&1", harness_cli(), gen_link);
    out = harness_run(cmd, &st);
    REQUIRE(out);
    CHECK_EQ_INT(st, 1);
    free(out);
    CHECK_MSG(lstat(gen_link, &ls) == 0 && S_ISLNK(ls.st_mode),
              "a failed gen removed the link %s", gen_link);
    remove(gen_link);
    remove(link);
    remove(target);
}
