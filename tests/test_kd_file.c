/*
 * test_kd_file.c — kd-trees saved and loaded (bsp_accel_save,
 * bsp_accel_load, `bspray build`, `--tree`): the loaded tree is the built
 * one bit for bit (digest, figures) and answers every ray as the naive
 * method does; every damaged, truncated or foreign file is refused with a
 * message naming it, also files whose checksum was made to match a broken
 * structure.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

#include "bspray/bspray.h"
#include "harness.h"
#include "kd_test_util.h"
#include "same_util.h"

/* the header's size and the offsets the tests edit (kd_file.c's layout) */
#define HDR 248
#define OFF_VERSION 8
#define OFF_MAX_DEPTH 20
#define OFF_NNODES (HDR - 16)

static void write_file(const char *path, const unsigned char *b, size_t n)
{
    FILE *f = fopen(path, "wb");
    REQUIRE(f);
    REQUIRE(fwrite(b, 1, n, f) == n);
    fclose(f);
}

static uint32_t get32(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

static void put32(unsigned char *p, uint32_t x)
{
    for (int i = 0; i < 4; i++)
        p[i] = (unsigned char)(x >> (8 * i));
}

/* Rewrites the checksum of file bytes B[0..N) to match its contents. */
static void fix_crc(unsigned char *b, size_t n)
{
    put32(b + n - 4, (uint32_t)crc32(crc32(0L, Z_NULL, 0), b, (uInt)(n - 4)));
}

/* Loads PATH over S and requires a refusal of status WANT (0: any) whose
 * message names PATH and contains WHAT (NULL: anything). */
static void expect_refused(const bsp_scene *s, const char *path, bsp_status want,
                           const char *what, const char *label)
{
    bsp_accel *a = (bsp_accel *)1;
    bsp_error err;
    bsp_status st = bsp_accel_load(s, path, &a, &err);
    if (st == BSP_OK) {
        CHECK_MSG(0, "%s: loaded", label);
        bsp_accel_destroy(a);
        return;
    }
    CHECK_MSG(a == NULL, "%s: *out not NULL after a failure", label);
    if (want)
        CHECK_MSG(st == want, "%s: status %s, want %s (%s)", label, bsp_status_name(st),
                  bsp_status_name(want), err.message);
    CHECK_MSG(strstr(err.message, path) != NULL, "%s: message without the path: %s", label,
              err.message);
    if (what)
        CHECK_MSG(strstr(err.message, what) != NULL, "%s: message '%s' lacks '%s'", label,
                  err.message, what);
}

/* The rays of A and B, and of B and the naive method N: the same answers
 * (primitive, t bit for bit, occlusion); A and B also the same counters. */
static void check_same_answers(const bsp_scene *s, const bsp_accel *a, const bsp_accel *b,
                               const bsp_accel *n, const char *label)
{
    enum { NR = 4000 };
    static bsp_ray rays[NR];
    static uint32_t from[NR];
    unsigned long long rng = 0xF11E5EEDULL;
    kd_test_rays(&rng, bsp_scene_bounds(s), NR, bsp_scene_prim_count(s), rays, from);
    bsp_query *qa = bsp_query_create(a), *qb = bsp_query_create(b), *qn = bsp_query_create(n);
    REQUIRE(qa && qb && qn);
    size_t bad = 0, hits = 0;
    for (size_t i = 0; i < NR; i++) {
        bsp_hit ha, hb, hn;
        int ra = bsp_intersect_from(a, qa, &rays[i], from[i], &ha);
        int rb = bsp_intersect_from(b, qb, &rays[i], from[i], &hb);
        int rn = bsp_intersect_from(n, qn, &rays[i], from[i], &hn);
        hits += (size_t)rn;
        if (!same_hit(ra, &ha, rn, &hn) || !same_hit(rb, &hb, rn, &hn)) {
            if (bad++ < 3)
                CHECK_MSG(0, "%s: ray %zu: built %d/%u, loaded %d/%u, naive %d/%u", label, i,
                          ra, ra ? ha.prim : 0, rb, rb ? hb.prim : 0, rn, rn ? hn.prim : 0);
        }
        int oa = bsp_occluded_from(a, qa, &rays[i], from[i]);
        int ob = bsp_occluded_from(b, qb, &rays[i], from[i]);
        int on = bsp_occluded_from(n, qn, &rays[i], from[i]);
        if ((oa != ob || ob != on) && bad++ < 3)
            CHECK_MSG(0, "%s: ray %zu: occluded built %d, loaded %d, naive %d", label, i, oa, ob,
                      on);
    }
    CHECK_MSG(bad == 0, "%s: %zu rays differ", label, bad);
    CHECK_MSG(hits > NR / 20, "%s: only %zu of %d rays hit: the rays miss the scene", label, hits,
              (int)NR);
    const bsp_query_counters *ca = bsp_query_get_counters(qa), *cb = bsp_query_get_counters(qb);
    CHECK_MSG(ca->isect_tests == cb->isect_tests && ca->traversal_steps == cb->traversal_steps &&
                  ca->mailbox_hits == cb->mailbox_hits,
              "%s: counters differ: tests %llu/%llu, steps %llu/%llu, mailbox %llu/%llu", label,
              (unsigned long long)ca->isect_tests, (unsigned long long)cb->isect_tests,
              (unsigned long long)ca->traversal_steps, (unsigned long long)cb->traversal_steps,
              (unsigned long long)ca->mailbox_hits, (unsigned long long)cb->mailbox_hits);
    bsp_query_destroy(qa);
    bsp_query_destroy(qb);
    bsp_query_destroy(qn);
}

TEST(kd_file_round_trip_is_the_built_tree)
{
    static const char *const scenes[] = {"spd:balls", "spd:tree", "spd:teapot", "spd:gears",
                                          "spd:mount"};
    static const bsp_accel_kind kinds[] = {BSP_ACCEL_SAH, BSP_ACCEL_KAPLAN, BSP_ACCEL_SAH_PER,
                                           BSP_ACCEL_SAH_PAR, BSP_ACCEL_SAH_MIXED};
    char path[1024];
    harness_tmp_path(path, sizeof path, "round.kdt");
    for (size_t sc = 0; sc < sizeof scenes / sizeof *scenes; sc++) {
        bsp_scene *s = kd_test_load(scenes[sc]);
        bsp_accel *naive = kd_test_build(s, BSP_ACCEL_NAIVE);
        for (size_t k = 0; k < sizeof kinds / sizeof *kinds; k++) {
            /* the view builds on three scenes are enough (quick mode, the
             * sanitizer run: on balls) */
            if (k >= 2 && sc >= (harness_quick() ? 1u : 3u))
                continue;
            bsp_build_options o;
            bsp_build_options_defaults(&o);
            o.kind = kinds[k];
            o.threads = 1;
            o.mailbox = sc != 1; /* tree without mailboxes: the setting comes back too */
            if (sc == 2)
                o.sah_costs.triangle = 2.5; /* a cost model of its own */
            bsp_accel *built = NULL, *loaded = NULL;
            bsp_error err;
            REQUIRE(bsp_accel_build(s, &o, &built, &err) == BSP_OK);
            char label[128];
            snprintf(label, sizeof label, "%s %s", scenes[sc], bsp_accel_kind_name(kinds[k]));
            bsp_status st = bsp_accel_save(built, path, &err);
            CHECK_MSG(st == BSP_OK, "%s: save: %s", label, err.message);
            st = bsp_accel_load(s, path, &loaded, &err);
            CHECK_MSG(st == BSP_OK, "%s: load: %s", label, err.message);
            if (st != BSP_OK) {
                bsp_accel_destroy(built);
                continue;
            }
            bsp_tree_stats tb, tl;
            bsp_accel_tree_stats(built, &tb);
            bsp_accel_tree_stats(loaded, &tl);
            CHECK_MSG(tb.digest == tl.digest, "%s: digest %016llx, loaded %016llx", label,
                      (unsigned long long)tb.digest, (unsigned long long)tl.digest);
            CHECK_MSG(tb.interior_nodes == tl.interior_nodes && tb.leaves == tl.leaves &&
                          tb.references == tl.references && tb.max_leaf_depth == tl.max_leaf_depth,
                      "%s: figures differ", label);
            CHECK_MSG(tb.expected_cost == tl.expected_cost && tb.model_cost == tl.model_cost,
                      "%s: costs %.17g/%.17g, loaded %.17g/%.17g", label, tb.expected_cost,
                      tb.model_cost, tl.expected_cost, tl.model_cost);
            CHECK_MSG(bsp_accel_get_kind(loaded) == kinds[k], "%s: kind %s", label,
                      bsp_accel_kind_name(bsp_accel_get_kind(loaded)));
            CHECK_MSG(kd_test_accepted(loaded), "%s: the checker refuses the loaded tree", label);
            if (k < 2 || sc == 0)
                check_same_answers(s, built, loaded, naive, label);
            bsp_accel_destroy(built);
            bsp_accel_destroy(loaded);
        }
        bsp_accel_destroy(naive);
        bsp_scene_destroy(s);
    }
}

/* A small tree's file (spd:jacks) in *N bytes, written to PATH. */
static unsigned char *small_tree_file(const bsp_scene *s, const char *path, size_t *n)
{
    bsp_accel *a = kd_test_build(s, BSP_ACCEL_SAH);
    bsp_error err;
    REQUIRE(bsp_accel_save(a, path, &err) == BSP_OK);
    bsp_accel_destroy(a);
    unsigned char *b = harness_read_file(path, n);
    REQUIRE(b && *n > HDR + 4);
    return b;
}

/* Saves the SAH tree of the NFF text SAVED_FOR and loads the file for the
 * NFF text LOADED_FOR: it must be refused as BSP_ERR_INVALID, the message
 * containing WANT. */
static void expect_refused_for(const char *saved_for, const char *loaded_for, const char *want,
                               const char *label)
{
    bsp_scene *saved = NULL, *loaded = NULL;
    bsp_error err;
    REQUIRE(bsp_scene_load_nff_memory(saved_for, strlen(saved_for), "saved.nff", &saved, &err) ==
            BSP_OK);
    REQUIRE(bsp_scene_load_nff_memory(loaded_for, strlen(loaded_for), "loaded.nff", &loaded,
                                      &err) == BSP_OK);
    char path[1024];
    harness_tmp_path(path, sizeof path, "saved.kdt");
    bsp_accel *a = kd_test_build(saved, BSP_ACCEL_SAH);
    REQUIRE(bsp_accel_save(a, path, &err) == BSP_OK);
    bsp_accel_destroy(a);
    expect_refused(loaded, path, BSP_ERR_INVALID, want, label);
    bsp_scene_destroy(saved);
    bsp_scene_destroy(loaded);
}

TEST(kd_file_refuses_foreign_truncated_and_flipped_files)
{
    bsp_scene *s = kd_test_load("spd:jacks");
    char good[1024], bad[1024];
    harness_tmp_path(good, sizeof good, "jacks.kdt");
    harness_tmp_path(bad, sizeof bad, "bad.kdt");
    size_t n;
    unsigned char *b = small_tree_file(s, good, &n);

    /* another scene; the same scene with one sphere smaller, within the same
     * bounds (so only the fingerprint tells them apart) */
    bsp_scene *other = kd_test_load("spd:balls");
    expect_refused(other, good, BSP_ERR_INVALID, "another scene", "spd:balls");
    bsp_scene_destroy(other);
    const char *nff = "v\nfrom 0 -5 0\nat 0 0 0\nup 0 0 1\nangle 40\nhither 1\nresolution 8 8\n"
                      "f 1 0 0 1 0 0 0 1\ns 0 0 0 1\ns 2 0 0 1\ns 1 0 0 0.5\n";
    char nff2[512];
    snprintf(nff2, sizeof nff2, "%s", nff);
    char *at = strstr(nff2, "s 1 0 0 0.5");
    REQUIRE(at);
    at[10] = '4';
    expect_refused_for(nff, nff2, "another scene", "a sphere shrunk");

    /* a file bspray 0.2.0 wrote for a scene of triangles: it read a
     * triangle's vertex v back as v0 + (v - v0), and 0.1 + (0.01 - 0.1) is
     * 0.009999999999999995. A tree saved for the scene with that vertex
     * carries the fingerprint 0.2.0 gave the scene with 0.01, and is named
     * as such; the other way round it is another scene */
    const char *tri = "p 3\n0.1 0 0\n0.01 1 0\n0 0 1\ns 0 0 3 0.5\n";
    const char *tri_rounded = "p 3\n0.1 0 0\n0.009999999999999995 1 0\n0 0 1\ns 0 0 3 0.5\n";
    expect_refused_for(tri_rounded, tri, "by bspray 0.2.0 or older", "0.2.0's rounding");
    expect_refused_for(tri, tri_rounded, "another scene", "the rounded vertex");

    /* not a file of ours, missing, a directory, truncated anywhere, padded */
    expect_refused(s, "/nonexistent/x.kdt", BSP_ERR_IO, "cannot open", "missing");
    expect_refused(s, harness_tmpdir(), BSP_ERR_IO, "regular file", "directory");
    const size_t cuts[] = {0, 7, 8, HDR - 1, HDR, HDR + 3, HDR + 8, n - 5, n - 1};
    for (size_t i = 0; i < sizeof cuts / sizeof *cuts; i++) {
        write_file(bad, b, cuts[i]);
        char label[64];
        snprintf(label, sizeof label, "cut at %zu", cuts[i]);
        expect_refused(s, bad, BSP_ERR_PARSE, NULL, label);
    }
    unsigned char *pad = malloc(n + 1);
    REQUIRE(pad);
    memcpy(pad, b, n);
    pad[n] = 0;
    write_file(bad, pad, n + 1);
    expect_refused(s, bad, BSP_ERR_PARSE, "damaged", "one byte more");
    free(pad);

    /* every single bit of the file flipped in turn: each refused */
    bsp_error err;
    size_t loaded = 0;
    for (size_t i = 0; i < n; i++) {
        for (int bit = 0; bit < 8; bit += 3) {
            b[i] ^= (unsigned char)(1u << bit);
            write_file(bad, b, n);
            bsp_accel *a = NULL;
            if (bsp_accel_load(s, bad, &a, &err) == BSP_OK) {
                loaded++;
                bsp_accel_destroy(a);
            }
            b[i] ^= (unsigned char)(1u << bit);
        }
    }
    CHECK_MSG(loaded == 0, "%zu of %zu flipped files loaded", loaded, 3 * n);
    /* and the file itself still loads */
    bsp_accel *a = NULL;
    CHECK(bsp_accel_load(s, good, &a, &err) == BSP_OK);
    bsp_accel_destroy(a);

    /* another format version, with a matching checksum */
    put32(b + OFF_VERSION, 2);
    fix_crc(b, n);
    write_file(bad, b, n);
    expect_refused(s, bad, BSP_ERR_PARSE, "version 2", "version 2");
    free(b);
    bsp_scene_destroy(s);
}

/* The offset of node I's first word in a tree file (its second follows). */
static size_t node_off(size_t i)
{
    return HDR + 8 * i;
}

TEST(kd_file_refuses_broken_structure_under_a_matching_checksum)
{
    bsp_scene *s = kd_test_load("spd:jacks");
    char good[1024], bad[1024];
    harness_tmp_path(good, sizeof good, "jacks2.kdt");
    harness_tmp_path(bad, sizeof bad, "bad2.kdt");
    size_t n;
    unsigned char *b = small_tree_file(s, good, &n);
    uint32_t nnodes = get32(b + OFF_NNODES);
    size_t nrefs = get32(b + OFF_NNODES + 8);
    REQUIRE(nnodes >= 5 && nrefs >= 2);
    /* the first interior node and the first non-empty leaf */
    size_t inner = nnodes, leaf = nnodes;
    for (size_t i = 0; i < nnodes; i++) {
        uint32_t bits = get32(b + node_off(i));
        if ((bits & 3) != 3 && inner == nnodes)
            inner = i;
        if ((bits & 3) == 3 && (bits >> 3) > 0 && leaf == nnodes)
            leaf = i;
    }
    REQUIRE(inner < nnodes && leaf < nnodes);
    uint32_t ibits = get32(b + node_off(inner)), child = ibits >> 3;
    uint32_t lbits = get32(b + node_off(leaf));
    uint32_t first = get32(b + node_off(leaf) + 4);
    float nanf_ = NAN, far_ = 1e30f;
    uint32_t nan_bits, far_bits;
    memcpy(&nan_bits, &nanf_, 4);
    memcpy(&far_bits, &far_, 4);
    struct {
        const char *label;
        size_t off;
        uint32_t value;
        const char *what;
    } edits[] = {
        {"child index past the end", node_off(inner), (nnodes - 1) << 3 | (ibits & 3), "children"},
        {"child index before its parent", node_off(inner), (uint32_t)inner << 3 | (ibits & 3),
         "children"},
        {"child index far past the end", node_off(inner), 0xFFFFFFF8u | (ibits & 3), "children"},
        {"children shared with another node", node_off(inner),
         (child + 2 < nnodes ? child + 2 : child) << 3 | (ibits & 3), NULL},
        {"a stray flag bit", node_off(inner), ibits | 4u, "stray flag"},
        {"a NaN plane", node_off(inner) + 4, nan_bits, "outside its cell"},
        {"a plane outside the cell", node_off(inner) + 4, far_bits, "outside its cell"},
        {"a leaf past the references", node_off(leaf) + 4, (uint32_t)nrefs, "references"},
        {"a leaf count past the references", node_off(leaf), (uint32_t)(nrefs + 1) << 3 | 3u,
         "references"},
        {"a huge leaf count", node_off(leaf), 0xFFFFFFF8u | 3u, "references"},
        {"a reference out of range", HDR + 8 * (size_t)nnodes + 4 * (size_t)first, 1000000u,
         "does not have"},
        {"a depth limit of 1", OFF_MAX_DEPTH, 1u, "deeper than the limit"},
        {"a depth limit of 0", OFF_MAX_DEPTH, 0u, "options are invalid"},
        {"a leaf where a subtree was", node_off(inner), (lbits >> 3) << 3 | 3u, NULL},
    };
    for (size_t e = 0; e < sizeof edits / sizeof *edits; e++) {
        unsigned char *c = malloc(n);
        REQUIRE(c);
        memcpy(c, b, n);
        put32(c + edits[e].off, edits[e].value);
        fix_crc(c, n);
        write_file(bad, c, n);
        expect_refused(s, bad, BSP_ERR_PARSE, edits[e].what, edits[e].label);
        free(c);
    }
    free(b);
    bsp_scene_destroy(s);

    /* a reference to a dropped primitive: a scene whose third primitive is a
     * degenerate polygon (all its vertices one point) */
    const char *nff = "f 1 0 0 1 0 0 0 1\ns 0 0 0 1\ns 3 0 0 1\np 3\n5 5 5\n5 5 5\n5 5 5\n";
    bsp_scene *d = NULL;
    bsp_error err;
    REQUIRE(bsp_scene_load_nff_memory(nff, strlen(nff), "dropped.nff", &d, &err) == BSP_OK);
    REQUIRE(bsp_scene_prim_kind(d, 2) == BSP_PRIM_DROPPED);
    bsp_accel *a = kd_test_build(d, BSP_ACCEL_SAH);
    REQUIRE(bsp_accel_save(a, good, &err) == BSP_OK);
    bsp_accel_destroy(a);
    b = harness_read_file(good, &n);
    REQUIRE(b);
    nnodes = get32(b + OFF_NNODES);
    REQUIRE(get32(b + OFF_NNODES + 8) >= 1);
    put32(b + HDR + 8 * (size_t)nnodes, 2); /* the first reference */
    fix_crc(b, n);
    write_file(bad, b, n);
    expect_refused(d, bad, BSP_ERR_PARSE, "dropped", "a dropped primitive");
    free(b);
    bsp_scene_destroy(d);
}

TEST(kd_file_save_refuses_naive_and_unwritable_paths)
{
    bsp_scene *s = kd_test_load("spd:jacks");
    bsp_accel *naive = kd_test_build(s, BSP_ACCEL_NAIVE), *a = kd_test_build(s, BSP_ACCEL_SAH);
    char path[1024];
    harness_tmp_path(path, sizeof path, "naive.kdt");
    bsp_error err;
    CHECK(bsp_accel_save(naive, path, &err) == BSP_ERR_INVALID);
    CHECK_STR_CONTAINS(err.message, "naive");
    FILE *f = fopen(path, "rb");
    CHECK_MSG(!f, "%s was written", path);
    if (f)
        fclose(f);
    const char *nodir = "/nonexistent-dir/x.kdt";
    CHECK(bsp_accel_save(a, nodir, &err) == BSP_ERR_IO);
    CHECK_STR_CONTAINS(err.message, nodir);
    /* over an existing file: replaced whole */
    harness_tmp_path(path, sizeof path, "over.kdt");
    write_file(path, (const unsigned char *)"old contents", 12);
    CHECK(bsp_accel_save(a, path, &err) == BSP_OK);
    bsp_accel *l = NULL;
    CHECK(bsp_accel_load(s, path, &l, &err) == BSP_OK);
    bsp_accel_destroy(l);
    bsp_accel_destroy(naive);
    bsp_accel_destroy(a);
    bsp_scene_destroy(s);
}

TEST(cli_build_and_tree_give_the_built_answers)
{
    const char *cli = harness_cli();
    char tree[1024], rays[1024], cmd[4096];
    harness_tmp_path(tree, sizeof tree, "cli_teapot.kdt");
    harness_tmp_path(rays, sizeof rays, "cli_rays.txt");
    snprintf(cmd, sizeof cmd, "%s build spd:teapot -o %s --accel kaplan --check", cli, tree);
    int status;
    char *out = harness_run(cmd, &status);
    REQUIRE(out);
    CHECK_MSG(status == 0, "'%s': %d: %s", cmd, status, out);
    CHECK_STR_CONTAINS(out, "invariants     ok");
    CHECK_STR_CONTAINS(out, "wrote ");
    free(out);
    /* trace through the loaded tree, and through the same rule built afresh */
    bsp_scene *s = kd_test_load("spd:teapot");
    enum { NR = 3000 };
    static bsp_ray r[NR];
    static uint32_t from[NR];
    unsigned long long rng = 0x7EA907ULL;
    kd_test_rays(&rng, bsp_scene_bounds(s), NR, bsp_scene_prim_count(s), r, from);
    FILE *f = fopen(rays, "w");
    REQUIRE(f);
    for (size_t i = 0; i < NR; i++)
        fprintf(f, "%.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g %d\n", r[i].org.x, r[i].org.y,
                r[i].org.z, r[i].dir.x, r[i].dir.y, r[i].dir.z, r[i].tmin, r[i].tmax,
                from[i] == BSP_NO_PRIM ? -1 : (int)from[i]);
    fclose(f);
    bsp_scene_destroy(s);
    char *outs[3];
    const char *how[3] = {"--tree", "--accel kaplan", "--accel naive"};
    for (int i = 0; i < 3; i++) {
        snprintf(cmd, sizeof cmd, "%s trace spd:teapot --rays %s --exact --threads 2 %s %s", cli,
                 rays, how[i], i == 0 ? tree : "");
        outs[i] = harness_run(cmd, &status);
        REQUIRE(outs[i]);
        CHECK_MSG(status == 0, "'%s': %d", cmd, status);
    }
    CHECK_MSG(strcmp(outs[0], outs[1]) == 0, "%s", "trace --tree differs from the built kaplan tree");
    CHECK_MSG(strcmp(outs[0], outs[2]) == 0, "%s", "trace --tree differs from naive");
    CHECK_MSG(strstr(outs[0], "hit ") != NULL, "%s", "no ray hits");
    for (int i = 0; i < 3; i++)
        free(outs[i]);
    /* stats reads the saved method back */
    snprintf(cmd, sizeof cmd, "%s stats spd:teapot --tree %s", cli, tree);
    out = harness_run(cmd, &status);
    REQUIRE(out);
    CHECK_MSG(status == 0, "'%s': %d", cmd, status);
    CHECK_STR_CONTAINS(out, "structure: kaplan, loaded from");
    free(out);
    /* render through the loaded tree: the very image of the built one, and
     * its figures say the tree was loaded */
    char png_a[1024], png_b[1024], json[1024];
    harness_tmp_path(png_a, sizeof png_a, "cli_tree.ppm");
    harness_tmp_path(png_b, sizeof png_b, "cli_built.ppm");
    harness_tmp_path(json, sizeof json, "cli_tree.json");
    snprintf(cmd, sizeof cmd, "%s render spd:teapot --res 65 --tree %s -o %s --stats-json %s 2>&1",
             cli, tree, png_a, json);
    CHECK_RUN(cmd, 0, "wrote");
    snprintf(cmd, sizeof cmd, "%s render spd:teapot --res 65 --accel kaplan -o %s 2>&1", cli,
             png_b);
    CHECK_RUN(cmd, 0, "wrote");
    size_t na = 0, nb = 0;
    unsigned char *ia = harness_read_file(png_a, &na), *ib = harness_read_file(png_b, &nb);
    REQUIRE(ia && ib);
    CHECK_MSG(na == nb && na > 65 * 65 * 3 && memcmp(ia, ib, na) == 0,
              "render --tree: %zu bytes, built: %zu bytes, or they differ", na, nb);
    free(ia);
    free(ib);
    size_t nj = 0;
    unsigned char *js = harness_read_file(json, &nj);
    REQUIRE(js);
    js[nj - 1] = '\0';
    CHECK_STR_CONTAINS((const char *)js, "\"tree_file\": ");
    CHECK_STR_CONTAINS((const char *)js, "\"T_load\": ");
    CHECK_MSG(strstr((const char *)js, "\"T_B\"") == NULL, "%s", "a loaded tree's JSON has T_B");
    free(js);

    /* usage errors and bad trees */
    snprintf(cmd, sizeof cmd, "%s render spd:teapot --tree %s --accel sah -o /dev/null 2>&1", cli,
             tree);
    out = harness_run(cmd, &status);
    REQUIRE(out);
    CHECK_EQ_INT(status, 2);
    CHECK_STR_CONTAINS(out, "--accel");
    free(out);
    /* options that do not shape a tree are allowed beside it */
    snprintf(cmd, sizeof cmd, "%s stats spd:teapot --tree %s --build-threads 1 --max-tree-mb 64", cli,
             tree);
    CHECK_RUN(cmd, 0, "structure: kaplan, loaded from");
    snprintf(cmd, sizeof cmd, "%s render spd:balls --tree %s -o /dev/null 2>&1", cli, tree);
    out = harness_run(cmd, &status);
    REQUIRE(out);
    CHECK_EQ_INT(status, 1);
    CHECK_STR_CONTAINS(out, tree);
    CHECK_STR_CONTAINS(out, "another scene");
    free(out);
    /* stats refuses such a tree before it prints anything of the scene */
    snprintf(cmd, sizeof cmd, "%s stats spd:balls --tree %s 2>/dev/null", cli, tree);
    out = harness_run(cmd, &status);
    REQUIRE(out);
    CHECK_EQ_INT(status, 1);
    CHECK_MSG(out[0] == '\0', "stats with a tree of another scene printed: %.200s", out);
    free(out);
    snprintf(cmd, sizeof cmd, "%s build spd:teapot -o %s --accel naive 2>&1", cli, tree);
    out = harness_run(cmd, &status);
    REQUIRE(out);
    CHECK_EQ_INT(status, 2);
    free(out);
    snprintf(cmd, sizeof cmd, "%s build spd:teapot 2>&1", cli);
    out = harness_run(cmd, &status);
    REQUIRE(out);
    CHECK_EQ_INT(status, 2);
    CHECK_STR_CONTAINS(out, "-o FILE");
    free(out);
}
