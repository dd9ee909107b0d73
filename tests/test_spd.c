/*
 * test_spd.c — the built-in SPD generators (src/spd): the NFF text of every
 * generated scene against the reference file made by Haines' own program
 * (../shared/scenes/spd, token by token within %g precision), a check that
 * this comparison does catch small changes, primitive counts of the built
 * scenes at other sizes against the MANIFEST formulas, error messages for
 * unknown names and bad sizes, the time to build ~6 * 10^5 spheres, and
 * tessellation (":tN"): counts, vertices on the surfaces, inscribed bounds,
 * hits near the true sphere, spec errors, text and scene bit for bit; and
 * bsp_scene_check against bsp_scene_load.
 */
#include <ctype.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bspray/scene.h"
#include "harness.h"
#include "same_util.h"
#include "spd/spd.h"

/* --- comparing NFF texts ------------------------------------------------------- */

/* %g keeps 6 significant digits, so a printed number is its true value
 * rounded to 10^(e-5), where 10^e <= |x| < 10^(e+1). Two printings of values
 * that agree to far better than that can still differ by one unit in the
 * last digit when they straddle a rounding boundary: that is at most
 * 10^(e-5) <= 1e-5 * |x| (also across a decade, 9.99999 vs 10). So
 * |a - b| <= 1e-5 * max(|a|, |b|) is the honest tolerance; a difference of
 * two units in the sixth digit fails. The absolute 1e-12 only lets through
 * round-off noise printed in place of a true zero (SPD prints e.g.
 * -2.55836e-17); a fixed absolute slack of 1e-5 would hide real errors in
 * shells, whose first spheres are 0.0035 in size. */
#define REL_TOL 1e-5
#define ABS_TOL 1e-12

typedef struct nff_diff {
    size_t tokens;     /* tokens compared */
    size_t mismatches; /* tokens outside the tolerance, or differing words */
    size_t textual;    /* numbers within tolerance but printed differently */
    char first[512];   /* the first mismatch, for the failure message */
} nff_diff;

/* The next whitespace-separated token of *P (advancing it), counting lines
 * in *LINE; returns its length, 0 at the end. */
static size_t next_token(const char **p, const char **tok, size_t *line)
{
    const char *s = *p;
    while (*s && isspace((unsigned char)*s)) {
        if (*s == '\n')
            (*line)++;
        s++;
    }
    *tok = s;
    while (*s && !isspace((unsigned char)*s))
        s++;
    *p = s;
    return (size_t)(s - *tok);
}

/* Parses a whole token as a number. */
static int token_number(const char *tok, size_t len, double *v)
{
    char buf[64], *end;
    if (len == 0 || len >= sizeof buf)
        return 0;
    memcpy(buf, tok, len);
    buf[len] = '\0';
    *v = strtod(buf, &end);
    return *end == '\0';
}

/* Compares GOT with the reference text WANT token by token. */
static void nff_compare(const char *got, const char *want, nff_diff *d)
{
    memset(d, 0, sizeof *d);
    size_t gline = 1, wline = 1;
    for (;;) {
        const char *gt, *wt;
        size_t gl = next_token(&got, &gt, &gline), wl = next_token(&want, &wt, &wline);
        if (gl == 0 && wl == 0)
            return;
        d->tokens++;
        double gv, wv;
        int same;
        if (gl == 0 || wl == 0) {
            same = 0;
        } else if (token_number(gt, gl, &gv) && token_number(wt, wl, &wv)) {
            double scale = fabs(gv) > fabs(wv) ? fabs(gv) : fabs(wv);
            same = fabs(gv - wv) <= REL_TOL * scale + ABS_TOL;
            if (same && (gl != wl || memcmp(gt, wt, gl) != 0))
                d->textual++;
        } else {
            same = gl == wl && memcmp(gt, wt, gl) == 0;
        }
        if (!same) {
            if (d->mismatches++ == 0)
                snprintf(d->first, sizeof d->first,
                         "token %zu (reference line %zu): got '%.*s', reference '%.*s'",
                         d->tokens, wline, (int)(gl > 60 ? 60 : gl), gl ? gt : "",
                         (int)(wl > 60 ? 60 : wl), wl ? wt : "");
            if (gl == 0 || wl == 0) /* one text ended: the rest cannot line up */
                return;
        }
    }
}

/* The whole file as a NUL-terminated string, or NULL. */
static char *read_text(const char *path)
{
    FILE *fp = fopen(path, "rb");
    if (!fp)
        return NULL;
    char *buf = harness_read_all(fp);
    fclose(fp);
    return buf;
}

/* The NFF text of NAME at SIZE (tessellated at level TESS unless 0) from
 * bsp_spd_write_nff, or NULL (with a failed check). Free with free(). */
static char *generate_text(const char *name, int size, int tess)
{
    char *text = NULL;
    size_t len = 0;
    FILE *mem = open_memstream(&text, &len);
    REQUIRE(mem != NULL);
    bsp_error err = {0};
    bsp_status st = bsp_spd_write_nff(name, size, tess, mem, &err);
    fclose(mem);
    CHECK_MSG(st == BSP_OK, "bsp_spd_write_nff(%s, %d, %d): %s", name, size, tess, err.message);
    if (st != BSP_OK) {
        free(text);
        return NULL;
    }
    return text;
}

/* The reference file FILE_NAME of ../shared/scenes/spd (skips the test when
 * the shared folder is absent). */
static char *reference_text(const char *file_name)
{
    const char *shared = harness_shared_dir();
    if (!shared)
        harness_skip("no ../shared directory with the SPD reference files");
    char path[1024];
    snprintf(path, sizeof path, "%s/scenes/spd/%s", shared, file_name);
    char *text = read_text(path);
    if (!text)
        harness_skip("cannot read %s", path);
    return text;
}

static void check_against_reference(const char *name, int size, const char *file_name)
{
    char *want = reference_text(file_name);
    char *got = generate_text(name, size, 0);
    if (got) {
        nff_diff d;
        nff_compare(got, want, &d);
        CHECK_MSG(d.mismatches == 0, "spd:%s:%d vs %s: %zu of %zu tokens differ; first: %s",
                  name, size, file_name, d.mismatches, d.tokens, d.first);
        CHECK_MSG(d.tokens > 10, "%s: only %zu tokens", file_name, d.tokens);
        fprintf(stderr, "  %s: %zu tokens match (%zu printed differently within %%g precision)\n",
                file_name, d.tokens, d.textual);
    }
    free(got);
    free(want);
}

/* Size factors as the MANIFEST gives them (the programs' defaults, and
 * teapot-s12 for the Readme's 9264-primitive teapot). */
TEST(spd_reference_balls) { check_against_reference("balls", 4, "balls.nff"); }
TEST(spd_reference_tetra) { check_against_reference("tetra", 6, "tetra.nff"); }
TEST(spd_reference_tree) { check_against_reference("tree", 11, "tree.nff"); }
TEST(spd_reference_rings) { check_against_reference("rings", 7, "rings.nff"); }
TEST(spd_reference_gears) { check_against_reference("gears", 4, "gears.nff"); }
TEST(spd_reference_mount) { check_against_reference("mount", 6, "mount.nff"); }
TEST(spd_reference_lattice) { check_against_reference("lattice", 12, "lattice.nff"); }
TEST(spd_reference_teapot) { check_against_reference("teapot", 6, "teapot.nff"); }
TEST(spd_reference_teapot_s12) { check_against_reference("teapot", 12, "teapot-s12.nff"); }
TEST(spd_reference_shells) { check_against_reference("shells", 5, "shells.nff"); }
TEST(spd_reference_jacks) { check_against_reference("jacks", 1, "jacks.nff"); }
TEST(spd_reference_sombrero) { check_against_reference("sombrero", 1, "sombrero.nff"); }
TEST(spd_reference_sample) { check_against_reference("sample", 1, "sample.nff"); }
TEST(spd_reference_nurbtst) { check_against_reference("nurbtst", 1, "nurbtst.nff"); }

/* Size 0 means the default, which is the reference file's size. */
TEST(spd_default_size_is_the_programs_default)
{
    char *a = generate_text("balls", 0, 0), *b = generate_text("balls", 4, 0);
    REQUIRE(a && b);
    CHECK(strcmp(a, b) == 0);
    free(a);
    free(b);
}

/* Replaces the first occurrence of OLD (a whole token) in TEXT by NEW of the
 * same length. */
static int replace_token(char *text, const char *old, const char *new_)
{
    size_t n = strlen(old);
    for (char *p = strstr(text, old); p; p = strstr(p + 1, old)) {
        int starts = p == text || isspace((unsigned char)p[-1]);
        int ends = p[n] == '\0' || isspace((unsigned char)p[n]);
        if (starts && ends) {
            memcpy(p, new_, n);
            return 1;
        }
    }
    return 0;
}

/* The comparison must be able to fail: small perturbations of a generated
 * text are caught, a last-digit rounding difference is not. */
TEST(spd_compare_catches_perturbations)
{
    char *ref = generate_text("balls", 2, 0);
    REQUIRE(ref);
    size_t len = strlen(ref);
    char *t = malloc(len + 1);
    REQUIRE(t);
    nff_diff d;

    nff_compare(ref, ref, &d);
    CHECK_EQ_INT(d.mismatches, 0);

    /* two units in the sixth significant digit of a radius */
    memcpy(t, ref, len + 1);
    REQUIRE(replace_token(t, "0.166667", "0.166669"));
    nff_compare(t, ref, &d);
    CHECK_EQ_INT(d.mismatches, 1);
    CHECK_STR_CONTAINS(d.first, "0.166669");

    /* one unit: within what %g rounding can produce, accepted but noticed */
    memcpy(t, ref, len + 1);
    REQUIRE(replace_token(t, "0.166667", "0.166668"));
    nff_compare(t, ref, &d);
    CHECK_EQ_INT(d.mismatches, 0);
    CHECK_EQ_INT(d.textual, 1);

    /* a small absolute change of a value near zero */
    memcpy(t, ref, len + 1);
    REQUIRE(replace_token(t, "0.01", "0.02")); /* hither */
    nff_compare(t, ref, &d);
    CHECK_EQ_INT(d.mismatches, 1);

    /* a sign */
    memcpy(t, ref, len + 1);
    REQUIRE(replace_token(t, "-0.5", "+0.5"));
    nff_compare(t, ref, &d);
    CHECK_EQ_INT(d.mismatches, 1);

    /* a keyword */
    memcpy(t, ref, len + 1);
    REQUIRE(replace_token(t, "s", "c"));
    nff_compare(t, ref, &d);
    CHECK_EQ_INT(d.mismatches, 1);

    /* a vertex count (the floor's "p 4") */
    memcpy(t, ref, len + 1);
    char *p4 = strstr(t, "\np 4\n");
    REQUIRE(p4);
    p4[3] = '5';
    nff_compare(t, ref, &d);
    CHECK(d.mismatches >= 1);

    /* a missing last primitive */
    memcpy(t, ref, len + 1);
    char *last = strrchr(t, 's');
    REQUIRE(last);
    *last = '\0';
    nff_compare(t, ref, &d);
    CHECK(d.mismatches >= 1);

    free(t);
    free(ref);
}

/* --- built scenes ------------------------------------------------------------ */

static bsp_scene *build(const char *spec)
{
    bsp_scene *s = NULL;
    bsp_error err = {0};
    bsp_status st = spd_scene_generate_spec(spec, &s, &err);
    CHECK_MSG(st == BSP_OK, "%s: %s", spec, err.message);
    if (st != BSP_OK)
        return NULL;
    REQUIRE(s != NULL);
    return s;
}

typedef struct counts {
    const char *spec;
    size_t spheres, cones, polygons, patches;
} counts;

/* Primitive counts from the MANIFEST formulas (and SPD's program headers)
 * at sizes other than the reference files'. */
TEST(spd_counts_follow_the_manifest_formulas)
{
    const counts table[] = {
        {"spd:balls:2", 1 + 9 + 81, 0, 1, 0},
        {"spd:balls:1", 10, 0, 1, 0},
        {"spd:tetra:3", 0, 0, 64, 0},
        {"spd:tree:3", 15, 15, 1, 0},
        {"spd:rings:2", 150, 150, 1, 0},
        {"spd:gears:2", 0, 0, 2 * 8 + 144 * 8 + 1, 0},
        {"spd:mount:3", 4, 0, 2 * 64, 0},
        {"spd:lattice:3", 64, 3 * 3 * 16, 0, 0},
        /* 64 SF^2 - 8 SF (the MANIFEST's "128" is a slip: its table has
         * 2256 triangles at SF 6 and 9120 at SF 12) */
        {"spd:teapot:3", 0, 0, 9, 64 * 9 - 8 * 3},
        {"spd:teapot:2", 0, 0, 4, 64 * 4 - 8 * 2},
        {"spd:teapot:1", 0, 0, 1, 64 - 8},
        {"spd:shells:2", 180 * 4 + 1, 0, 0, 0},
        {"spd:jacks:2", 2 * 3 * 9, 3 * 9, 0, 0},
        {"spd:sombrero:2", 0, 0, 2 * 63 * 63, 0},
        {"spd:sample", 0, 1, 16, 864},
        {"spd:nurbtst", 0, 0, 0, 1500},
    };
    for (size_t i = 0; i < sizeof table / sizeof table[0]; i++) {
        const counts *c = &table[i];
        bsp_scene *s = build(c->spec);
        if (!s)
            continue;
        size_t want = c->spheres + c->cones + c->polygons + c->patches;
        CHECK_MSG(bsp_scene_prim_count(s) == want, "%s: %zu primitives, expected %zu", c->spec,
                  bsp_scene_prim_count(s), want);
        CHECK_MSG(bsp_scene_kind_count(s, BSP_PRIM_SPHERE) == c->spheres, "%s: %zu spheres",
                  c->spec, bsp_scene_kind_count(s, BSP_PRIM_SPHERE));
        CHECK_MSG(bsp_scene_kind_count(s, BSP_PRIM_CONE) == c->cones, "%s: %zu cones", c->spec,
                  bsp_scene_kind_count(s, BSP_PRIM_CONE));
        CHECK_MSG(bsp_scene_kind_count(s, BSP_PRIM_POLYGON) == c->polygons, "%s: %zu polygons",
                  c->spec, bsp_scene_kind_count(s, BSP_PRIM_POLYGON));
        /* %g rounding can make a tiny patch degenerate (teapot at size 1): it
         * is dropped, keeping its index, exactly as when its NFF text is read */
        size_t dropped = bsp_scene_kind_count(s, BSP_PRIM_DROPPED);
        CHECK_MSG(bsp_scene_kind_count(s, BSP_PRIM_PATCH) + dropped == c->patches,
                  "%s: %zu patches + %zu dropped", c->spec,
                  bsp_scene_kind_count(s, BSP_PRIM_PATCH), dropped);
        char *text = NULL;
        size_t text_len = 0;
        FILE *mem = open_memstream(&text, &text_len);
        REQUIRE(mem);
        const char *name = c->spec + 4, *colon = strchr(name, ':');
        char nm[32];
        snprintf(nm, sizeof nm, "%.*s", colon ? (int)(colon - name) : (int)strlen(name), name);
        bsp_error err;
        REQUIRE(bsp_spd_write_nff(nm, colon ? atoi(colon + 1) : 0, 0, mem, &err) == BSP_OK);
        fclose(mem);
        bsp_scene *from_text = NULL;
        REQUIRE(bsp_scene_load_nff_memory(text, text_len, c->spec, &from_text, &err) == BSP_OK);
        CHECK_MSG(bsp_scene_kind_count(from_text, BSP_PRIM_DROPPED) == dropped,
                  "%s: %zu dropped, its NFF text %zu", c->spec, dropped,
                  bsp_scene_kind_count(from_text, BSP_PRIM_DROPPED));
        bsp_scene_destroy(from_text);
        free(text);
        CHECK_MSG(bsp_scene_camera(s) != NULL, "%s: no camera", c->spec);
        bsp_scene_destroy(s);
    }
}

/* The default scene carries SPD's view, lights, materials and background. */
TEST(spd_balls_scene_contents)
{
    bsp_scene *s = build("spd:balls");
    REQUIRE(s);
    CHECK_EQ_INT(bsp_scene_kind_count(s, BSP_PRIM_SPHERE), 7381);
    CHECK_EQ_INT(bsp_scene_kind_count(s, BSP_PRIM_POLYGON), 1);
    CHECK_EQ_INT(bsp_scene_light_count(s), 3);
    CHECK_EQ_INT(bsp_scene_material_count(s), 2);
    const bsp_camera *cam = bsp_scene_camera(s);
    REQUIRE(cam);
    CHECK(cam->from.x == 2.1 && cam->from.y == 1.3 && cam->from.z == 1.7);
    CHECK(cam->angle_deg == 45.0 && cam->hither == 0.01);
    CHECK(cam->res_x == 512 && cam->res_y == 512);
    double bg[3];
    bsp_scene_background(s, bg);
    CHECK(bg[0] == 0.078 && bg[1] == 0.361 && bg[2] == 0.753);
    /* prim 0 is the floor, prim 1 the big sphere: radius 0.5 at the origin */
    CHECK_EQ_INT(bsp_scene_prim_kind(s, 0), BSP_PRIM_POLYGON);
    CHECK_EQ_INT(bsp_scene_prim_material(s, 0), 0);
    CHECK_EQ_INT(bsp_scene_prim_material(s, 1), 1);
    bsp_box b = bsp_scene_prim_bounds(s, 1);
    CHECK_NEAR(b.lo.x, -0.5, 1e-12);
    CHECK_NEAR(b.hi.z, 0.5, 1e-12);
    const bsp_material *m = bsp_scene_material(s, 1);
    CHECK_NEAR(m->ks, 0.5, 0);
    CHECK_NEAR(m->shine, 3.0827, 1e-4);
    bsp_box all = bsp_scene_bounds(s);
    CHECK_NEAR(all.lo.x, -12, 1e-12);
    CHECK_NEAR(all.lo.z, -0.5, 1e-12);
    CHECK_NEAR(all.hi.z, 0.830567, 1e-6); /* MANIFEST bounding box */
    bsp_scene_destroy(s);
}

/* Names are matched without regard to case. */
TEST(spd_name_case_insensitive)
{
    bsp_scene *s = build("spd:BaLLs:1");
    REQUIRE(s);
    CHECK_EQ_INT(bsp_scene_prim_count(s), 11);
    bsp_scene_destroy(s);
}

/* --- errors ---------------------------------------------------------------------- */

static void expect_invalid(const char *spec, const char *needle)
{
    bsp_scene *s = (bsp_scene *)&s; /* must be reset to NULL */
    bsp_error err = {0};
    bsp_status st = spd_scene_generate_spec(spec, &s, &err);
    CHECK_MSG(st == BSP_ERR_INVALID, "%s: status %d", spec, (int)st);
    CHECK_MSG(s == NULL, "%s: output not cleared", spec);
    CHECK_STR_CONTAINS(err.message, needle);
}

TEST(spd_unknown_names_and_bad_sizes)
{
    expect_invalid("spd:nosuch", "unknown SPD scene 'nosuch'");
    expect_invalid("spd:nosuch", "balls tetra tree rings gears mount lattice teapot shells "
                                 "jacks sombrero sample nurbtst");
    expect_invalid("spd:", "unknown SPD scene ''");
    expect_invalid("spd:ball", "unknown SPD scene");
    expect_invalid("spd:ballsx:2", "unknown SPD scene 'ballsx'");
    expect_invalid("balls", "not an SPD scene");
    expect_invalid("spd:balls:0", "valid sizes are 1 to 8");
    expect_invalid("spd:balls:9", "bad size factor '9'");
    expect_invalid("spd:balls:-1", "valid sizes are 1 to 8");
    expect_invalid("spd:balls:", "bad size factor ''");
    expect_invalid("spd:balls:4x", "bad size factor '4x'");
    expect_invalid("spd:balls: 4", "bad size factor");
    expect_invalid("spd:balls:4:4", "bad tessellation '4'"); /* the third field is tN */
    expect_invalid("spd:balls:99999999999999999999", "bad size factor");
    expect_invalid("spd:mount:8", "valid sizes are 1 to 7");
    expect_invalid("spd:sample:2", "fixed size");
    expect_invalid("spd:tetra:14", "valid sizes are 1 to 13");

    bsp_error err = {0};
    char *text = NULL;
    size_t len = 0;
    FILE *mem = open_memstream(&text, &len);
    REQUIRE(mem);
    CHECK_EQ_INT(bsp_spd_write_nff("nosuch", 1, 0, mem, &err), BSP_ERR_INVALID);
    CHECK_STR_CONTAINS(err.message, "known scenes: balls");
    CHECK_EQ_INT(bsp_spd_write_nff("jacks", 9, 0, mem, &err), BSP_ERR_INVALID);
    CHECK_STR_CONTAINS(err.message, "valid sizes are 1 to 8");
    CHECK_EQ_INT(bsp_spd_write_nff("jacks", -3, 0, mem, &err), BSP_ERR_INVALID);
    fclose(mem);
    CHECK_EQ_INT(len, 0); /* nothing written on refusal */
    free(text);

    int def = 0, lo = 0, hi = 0;
    CHECK(bsp_spd_scene_sizes("teapot", &def, &lo, &hi));
    CHECK(def == 6 && lo == 1 && hi > 12);
    CHECK(!bsp_spd_scene_sizes("nosuch", NULL, NULL, NULL));
}

/* --- speed ------------------------------------------------------------------------ */

/* ~6 * 10^5 spheres through the public add_* calls; reports the time (no
 * assertion on it: sanitizer builds are much slower). */
TEST(spd_balls_large_build_time)
{
    struct timespec t0, t1;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    bsp_scene *s = build("spd:balls:6");
    clock_gettime(CLOCK_MONOTONIC, &t1);
    REQUIRE(s);
    double secs = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
    size_t n = bsp_scene_prim_count(s);
    CHECK_EQ_INT(n, 597871 + 1);
    fprintf(stderr, "  spd:balls:6: %zu primitives built in %.3f s (%.0f per second)\n", n, secs,
            (double)n / secs);
    bsp_scene_destroy(s);
}

/* spd:NAME builds exactly the scene its SPD file describes: every number
 * goes through the same %g rounding, so the primitives, camera, lights and
 * materials are bit for bit those of the parsed reference file, and so are
 * the hits of rays. */
TEST(spd_generated_scene_equals_parsed_reference_file)
{
    const char *shared = harness_shared_dir();
    if (!shared)
        harness_skip("../shared is absent: no reference files to compare with");
    static const struct {
        const char *file, *spec;
    } pairs[] = {
        {"balls.nff", "spd:balls"},     {"gears.nff", "spd:gears"},
        {"mount.nff", "spd:mount"},     {"rings.nff", "spd:rings"},
        {"teapot.nff", "spd:teapot"},   {"teapot-s12.nff", "spd:teapot:12"},
        {"tetra.nff", "spd:tetra"},     {"tree.nff", "spd:tree"},
        {"lattice.nff", "spd:lattice"}, {"shells.nff", "spd:shells"},
        {"jacks.nff", "spd:jacks"},     {"sombrero.nff", "spd:sombrero"},
        {"sample.nff", "spd:sample"},   {"nurbtst.nff", "spd:nurbtst"},
    };
    for (size_t i = 0; i < sizeof pairs / sizeof pairs[0]; i++) {
        char path[1024];
        snprintf(path, sizeof path, "%s/scenes/spd/%s", shared, pairs[i].file);
        bsp_scene *f = NULL, *g = NULL;
        bsp_error err;
        REQUIRE(bsp_scene_load(path, &f, &err) == BSP_OK);
        REQUIRE(bsp_scene_load(pairs[i].spec, &g, &err) == BSP_OK);
        size_t n = bsp_scene_prim_count(f);
        CHECK_EQ_INT(bsp_scene_prim_count(g), n);
        int differ = 0;
        for (size_t p = 0; p < n && p < bsp_scene_prim_count(g) && differ < 3; p++) {
            bsp_box a = bsp_scene_prim_bounds(f, p), b = bsp_scene_prim_bounds(g, p);
            if (bsp_scene_prim_kind(f, p) != bsp_scene_prim_kind(g, p) ||
                memcmp(&a, &b, sizeof a) != 0 ||
                bsp_scene_prim_material(f, p) != bsp_scene_prim_material(g, p)) {
                differ++;
                harness_fail(__FILE__, __LINE__, "%s: primitive %zu differs from %s",
                             pairs[i].spec, p, pairs[i].file);
            }
        }
        CHECK(memcmp(bsp_scene_camera(f), bsp_scene_camera(g), sizeof(bsp_camera)) == 0);
        CHECK_EQ_INT(bsp_scene_light_count(f), bsp_scene_light_count(g));
        for (size_t l = 0; l < bsp_scene_light_count(f) && l < bsp_scene_light_count(g); l++)
            CHECK(memcmp(&bsp_scene_light(f, l)->pos, &bsp_scene_light(g, l)->pos,
                         sizeof(bsp_vec3)) == 0);
        CHECK_EQ_INT(bsp_scene_material_count(f), bsp_scene_material_count(g));
        for (size_t m = 0; m < bsp_scene_material_count(f) && m < bsp_scene_material_count(g);
             m++)
            CHECK(same_material(bsp_scene_material(f, m), bsp_scene_material(g, m)));
        /* the same t, bit for bit, for rays from the eye through every primitive */
        const bsp_camera *cam = bsp_scene_camera(f);
        for (size_t p = 0; p < n && cam; p += 1 + n / 500) {
            bsp_box b = bsp_scene_prim_bounds(f, p);
            bsp_ray r;
            r.org = cam->from;
            for (int k = 0; k < 3; k++)
                r.dir.v[k] = 0.5 * (b.lo.v[k] + b.hi.v[k]) - cam->from.v[k];
            r.tmin = 0;
            r.tmax = INFINITY;
            bsp_hit ha, hb;
            int fa = bsp_scene_intersect_prim(f, p, &r, &ha);
            int fb = bsp_scene_intersect_prim(g, p, &r, &hb);
            CHECK_EQ_INT(fa, fb);
            if (fa && fb)
                CHECK(memcmp(&ha.t, &hb.t, sizeof ha.t) == 0);
        }
        bsp_scene_destroy(f);
        bsp_scene_destroy(g);
    }
}

/* --- tessellation ("spd:NAME[:SIZE]:tN") ------------------------------------------ */

/* Triangles per sphere and per cone (no pointed end) at level N, as spd.h
 * describes the scheme: N slices, M = max(2, ceil(N/2)) bands, polar fans. */
static size_t tess_bands(int n)
{
    return (size_t)((n + 1) / 2 < 2 ? 2 : (n + 1) / 2);
}
static size_t tess_sphere_tris(int n)
{
    return 2 * (size_t)n * (tess_bands(n) - 1);
}
static size_t tess_cone_tris(int n)
{
    return 2 * (size_t)n;
}

/* The tessellated scenes hold the predicted number of patches and no
 * sphere, cone or dropped primitive. */
TEST(spd_tessellated_counts)
{
    static const struct {
        const char *spec;
        int level;
        size_t spheres, cones, polygons, patches; /* of the untessellated scene */
    } table[] = {
        {"spd:balls:1:t8", 8, 10, 0, 1, 0},     {"spd:balls:1:t2", 2, 10, 0, 1, 0},
        {"spd:balls:1:t3", 3, 10, 0, 1, 0},     {"spd:BALLS:1:T64", 64, 10, 0, 1, 0},
        {"spd:tree:3:t6", 6, 15, 15, 1, 0},     {"spd:tree:t3", 3, 4095, 4095, 1, 0},
        {"spd:lattice:1:t4", 4, 8, 12, 0, 0},   {"spd:jacks:1:t7", 7, 6, 3, 0, 0},
        {"spd:sample:t5", 5, 0, 1, 16, 864},    {"spd:tetra:2:t9", 9, 0, 0, 16, 0},
        {"spd:rings:1:t10", 10, 30, 30, 1, 0},  {"spd:shells:1:t11", 11, 361, 0, 0, 0},
    };
    for (size_t i = 0; i < sizeof table / sizeof table[0]; i++) {
        bsp_scene *s = build(table[i].spec);
        if (!s)
            continue;
        int n = table[i].level;
        size_t want = table[i].patches + table[i].spheres * tess_sphere_tris(n) +
                      table[i].cones * tess_cone_tris(n);
        CHECK_MSG(bsp_scene_kind_count(s, BSP_PRIM_PATCH) == want, "%s: %zu patches, expected %zu",
                  table[i].spec, bsp_scene_kind_count(s, BSP_PRIM_PATCH), want);
        CHECK_MSG(bsp_scene_kind_count(s, BSP_PRIM_POLYGON) == table[i].polygons,
                  "%s: %zu polygons", table[i].spec, bsp_scene_kind_count(s, BSP_PRIM_POLYGON));
        CHECK_EQ_INT(bsp_scene_kind_count(s, BSP_PRIM_SPHERE), 0);
        CHECK_EQ_INT(bsp_scene_kind_count(s, BSP_PRIM_CONE), 0);
        CHECK_MSG(bsp_scene_kind_count(s, BSP_PRIM_DROPPED) == 0, "%s: %zu dropped",
                  table[i].spec, bsp_scene_kind_count(s, BSP_PRIM_DROPPED));
        CHECK_EQ_INT(bsp_scene_prim_count(s), want + table[i].polygons);
        bsp_scene_destroy(s);
    }
    /* the numbers spd.h gives */
    CHECK_EQ_INT(tess_sphere_tris(8), 48);
    CHECK_EQ_INT(tess_sphere_tris(2), 4);
    CHECK_EQ_INT(tess_sphere_tris(64), 64 * 62);
}

/* spd_count, the pass that sizes a tessellated scene before it is made,
 * counts what the generator then makes: the built scene's primitives. */
TEST(spd_count_predicts_the_scene)
{
    static const struct {
        const char *spec;
        spd_generator gen;
        int size, level; /* level 0: untessellated */
    } table[] = {
        {"spd:balls:2:t8", spd_gen_balls, 2, 8},       {"spd:balls:3", spd_gen_balls, 3, 0},
        {"spd:tree:4:t6", spd_gen_tree, 4, 6},         {"spd:rings:2:t5", spd_gen_rings, 2, 5},
        {"spd:lattice:2:t3", spd_gen_lattice, 2, 3},   {"spd:jacks:2:t7", spd_gen_jacks, 2, 7},
        {"spd:sample:t5", spd_gen_sample, 1, 5},       {"spd:shells:1:t4", spd_gen_shells, 1, 4},
        {"spd:gears:1:t8", spd_gen_gears, 1, 8},       {"spd:teapot:2:t4", spd_gen_teapot, 2, 4},
        {"spd:mount:2", spd_gen_mount, 2, 0},          {"spd:nurbtst:t2", spd_gen_nurbtst, 1, 2},
    };
    for (size_t i = 0; i < sizeof table / sizeof table[0]; i++) {
        spd_tess t;
        REQUIRE(!table[i].level || spd_tess_init(&t, table[i].level));
        size_t counted = spd_count(table[i].gen, table[i].size, table[i].level ? &t : NULL);
        bsp_scene *s = build(table[i].spec);
        if (!s)
            continue;
        CHECK_MSG(counted == bsp_scene_prim_count(s), "%s: counted %zu, made %zu",
                  table[i].spec, counted, bsp_scene_prim_count(s));
        bsp_scene_destroy(s);
    }
}

/* A tessellated scene of more than SPD_MAX_PRIMS primitives is refused before
 * anything is made (rings:100:t8 would be some 650 million triangles, far
 * more than this machine's memory), by the scene and by the NFF writer. */
TEST(spd_tessellated_scene_too_large)
{
    static const char *const specs[] = {"spd:rings:100:t8", "spd:balls:8:t64",
                                        "spd:balls:7:t8", "spd:lattice:290:t2"};
    for (size_t i = 0; i < sizeof specs / sizeof specs[0]; i++) {
        bsp_scene *s = (bsp_scene *)&s; /* must be reset to NULL */
        bsp_error err = {0};
        bsp_status st = spd_scene_generate_spec(specs[i], &s, &err);
        CHECK_MSG(st == BSP_ERR_LIMIT, "%s: status %d", specs[i], (int)st);
        CHECK(s == NULL);
        CHECK_STR_CONTAINS(err.message, specs[i] + 4);
        CHECK_STR_CONTAINS(err.message, "would make more than 100000000 primitives");
    }
    /* balls:7 has 5,380,840 spheres: 48 triangles each at level 8 */
    spd_tess t;
    REQUIRE(spd_tess_init(&t, 8));
    CHECK(spd_count(spd_gen_balls, 7, &t) > SPD_MAX_PRIMS);
    CHECK_EQ_INT(spd_count(spd_gen_balls, 6, &t), 48 * 597871 + 1);
    /* the NFF writer refuses it too, and writes nothing */
    char *text = NULL;
    size_t len = 0;
    FILE *mem = open_memstream(&text, &len);
    REQUIRE(mem != NULL);
    bsp_error err = {0};
    CHECK(bsp_spd_write_nff("rings", 100, 8, mem, &err) == BSP_ERR_LIMIT);
    fclose(mem);
    CHECK_EQ_INT(len, 0);
    CHECK_STR_CONTAINS(err.message, "spd:rings:100:t8: the tessellation would make more than");
    free(text);
}

/* %g and back, as a reader of the NFF text sees a number. */
static double g6(double x)
{
    char buf[64];
    snprintf(buf, sizeof buf, "%g", x);
    return strtod(buf, NULL);
}

static double maxabs3(bsp_vec3 a)
{
    double m = fabs(a.x);
    if (fabs(a.y) > m)
        m = fabs(a.y);
    return fabs(a.z) > m ? fabs(a.z) : m;
}

static bsp_vec3 sub3(bsp_vec3 a, bsp_vec3 b)
{
    return bsp_v3(a.x - b.x, a.y - b.y, a.z - b.z);
}

static double dot3(bsp_vec3 a, bsp_vec3 b)
{
    return a.x * b.x + a.y * b.y + a.z * b.z;
}

static double len3(bsp_vec3 a)
{
    return sqrt(dot3(a, a));
}

static bsp_vec3 g6v(bsp_vec3 a)
{
    return bsp_v3(g6(a.x), g6(a.y), g6(a.z));
}

/* One original sphere or cone whose tessellation is being checked. */
typedef struct tess_check {
    spd_tess tess;
    const char *what; /* scene, for messages */
    int is_cone;
    bsp_vec3 c;       /* sphere */
    double r;
    bsp_vec3 b, a;    /* cone */
    double rb, ra;
    size_t patches;   /* emitted for the current primitive */
    size_t originals; /* spheres and cones checked */
    size_t passed_on; /* spheres or cones not tessellated */
    size_t vertices;
    size_t bad;
    double worst_g;   /* largest %g-rounded deviation / its tolerance */
    char first[300];
} tess_check;

static void tc_fail(tess_check *k, const char *fmt, double x, double tol)
{
    if (k->bad++ == 0)
        snprintf(k->first, sizeof k->first, "%s %s %s: %.17g (tolerance %.3g)", k->what,
                 k->is_cone ? "cone" : "sphere", fmt, x, tol);
}

/* Checks P (with normal N) against the current sphere, unrounded and as %g
 * text, and returns nothing: failures are counted in K. */
static void tc_sphere_vertex(tess_check *k, bsp_vec3 p, bsp_vec3 n)
{
    double scale = maxabs3(k->c) + k->r;
    double d = fabs(len3(sub3(p, k->c)) - k->r), tol = 1e-13 * scale;
    if (!(d <= tol))
        tc_fail(k, "vertex off the surface by", d, tol);
    bsp_vec3 radial = sub3(p, k->c);
    bsp_vec3 want = bsp_v3(radial.x / k->r, radial.y / k->r, radial.z / k->r);
    double dn = len3(sub3(n, want));
    if (!(dn <= 1e-12))
        tc_fail(k, "normal differs from the radial direction by", dn, 1e-12);
    /* as the NFF text and the scene see it: all numbers through %g */
    bsp_vec3 pg = g6v(p), cg = g6v(k->c);
    double dg = fabs(len3(sub3(pg, cg)) - g6(k->r));
    double tolg = 1e-5 * (maxabs3(p) + maxabs3(k->c) + k->r);
    if (!(dg <= tolg))
        tc_fail(k, "%g-rounded vertex off the %g-rounded surface by", dg, tolg);
    if (dg / tolg > k->worst_g)
        k->worst_g = dg / tolg;
    double dng = len3(sub3(g6v(n), want));
    if (!(dng <= 1e-5))
        tc_fail(k, "%g-rounded normal off by", dng, 1e-5);
}

/* Axial coordinate and radial offset of P from the cone axis (BASE, unit W). */
static void cone_coords(bsp_vec3 p, bsp_vec3 base, bsp_vec3 w, double *s, bsp_vec3 *radial)
{
    bsp_vec3 q = sub3(p, base);
    *s = dot3(q, w);
    *radial = bsp_v3(q.x - *s * w.x, q.y - *s * w.y, q.z - *s * w.z);
}

static void tc_cone_vertex_with(tess_check *k, bsp_vec3 p, bsp_vec3 b, bsp_vec3 a, double rb,
                                double ra, double tol, int check_normal, bsp_vec3 n)
{
    bsp_vec3 axis = sub3(a, b);
    double h = len3(axis);
    bsp_vec3 w = bsp_v3(axis.x / h, axis.y / h, axis.z / h);
    double s;
    bsp_vec3 radial;
    cone_coords(p, b, w, &s, &radial);
    /* every vertex lies on one of the two rims */
    double off_rim = fabs(s) < fabs(s - h) ? fabs(s) : fabs(s - h);
    if (!(off_rim <= tol))
        tc_fail(k, "vertex off both end planes by", off_rim, tol);
    double want_r = rb + (ra - rb) * (s / h);
    double dr = fabs(len3(radial) - want_r);
    if (!(dr <= tol))
        tc_fail(k, "vertex off the surface by", dr, tol);
    if (!check_normal)
        return;
    double len = sqrt(h * h + (rb - ra) * (rb - ra));
    double nw = dot3(n, w), want_nw = (rb - ra) / len;
    if (!(fabs(nw - want_nw) <= 1e-12))
        tc_fail(k, "normal's axial part off by", fabs(nw - want_nw), 1e-12);
    if (!(fabs(len3(n) - 1.0) <= 1e-12))
        tc_fail(k, "normal's length off 1 by", fabs(len3(n) - 1.0), 1e-12);
    double rl = len3(radial);
    if (rl > 1e-9 * (maxabs3(b) + h)) { /* on a rim with a radius: n leans outward */
        bsp_vec3 nr = bsp_v3(n.x - nw * w.x, n.y - nw * w.y, n.z - nw * w.z);
        double cosang = dot3(nr, radial) / (len3(nr) * rl);
        if (!(cosang >= 1.0 - 1e-12))
            tc_fail(k, "normal not in the radial plane, cosine", cosang, 1e-12);
    }
}

static void tc_cone_vertex(tess_check *k, bsp_vec3 p, bsp_vec3 n)
{
    double scale = maxabs3(k->b) + maxabs3(k->a) + k->rb + k->ra;
    tc_cone_vertex_with(k, p, k->b, k->a, k->rb, k->ra, 1e-13 * scale, 1, n);
    double tolg = 1e-5 * (scale + maxabs3(p));
    tc_cone_vertex_with(k, g6v(p), g6v(k->b), g6v(k->a), g6(k->rb), g6(k->ra), tolg, 0, n);
}

static void tc_patch(spd_sink *s, const bsp_vec3 *v, const bsp_vec3 *nrm, int n)
{
    tess_check *k = s->ctx;
    k->patches++;
    if (n != 3) {
        tc_fail(k, "patch with vertex count", n, 0);
        return;
    }
    for (int i = 0; i < 3; i++) {
        k->vertices++;
        if (k->is_cone)
            tc_cone_vertex(k, v[i], nrm[i]);
        else
            tc_sphere_vertex(k, v[i], nrm[i]);
    }
    /* counterclockwise seen from outside: the winding's normal agrees with
     * the vertex normals; and no triangle is degenerate */
    bsp_vec3 e1 = sub3(v[1], v[0]), e2 = sub3(v[2], v[0]);
    bsp_vec3 g = bsp_v3(e1.y * e2.z - e1.z * e2.y, e1.z * e2.x - e1.x * e2.z,
                        e1.x * e2.y - e1.y * e2.x);
    bsp_vec3 ns = bsp_v3(nrm[0].x + nrm[1].x + nrm[2].x, nrm[0].y + nrm[1].y + nrm[2].y,
                         nrm[0].z + nrm[1].z + nrm[2].z);
    double cosang = dot3(g, ns) / (len3(g) * len3(ns));
    if (k->tess.slices > 2 && !(cosang > 0.5)) /* level 2 is flat: the normals lie in it */
        tc_fail(k, "triangle winding against its normals, cosine", cosang, 0.5);
}

static void tc_passed_sphere(spd_sink *s, bsp_vec3 c, double r)
{
    (void)c;
    (void)r;
    ((tess_check *)s->ctx)->passed_on++;
}

static void tc_passed_cone(spd_sink *s, bsp_vec3 b, double rb, bsp_vec3 a, double ra)
{
    (void)b;
    (void)rb;
    (void)a;
    (void)ra;
    ((tess_check *)s->ctx)->passed_on++;
}

/* The sink tessellating into the checks of K. */
static spd_sink tess_check_sink(tess_check *k)
{
    spd_sink s = {.ctx = k,
                  .failed = BSP_OK,
                  .tess = &k->tess,
                  .sphere = tc_passed_sphere,
                  .cone = tc_passed_cone,
                  .patch = tc_patch};
    return s;
}

/* Tessellates one sphere or cone into the checks, and checks the count. */
static void tc_run_sphere(tess_check *k, bsp_vec3 c, double r)
{
    k->is_cone = 0;
    k->c = c;
    k->r = fabs(r); /* a negative (inside-only) radius: tessellated as its size */
    k->patches = 0;
    k->originals++;
    spd_sink inner = tess_check_sink(k);
    double c4[4] = {c.x, c.y, c.z, r};
    spd_sphere(&inner, c4);
    size_t want = tess_sphere_tris(k->tess.slices);
    if (k->patches != want)
        tc_fail(k, "patch count", (double)k->patches, (double)want);
}

static void tc_run_cone(tess_check *k, bsp_vec3 b, double rb, bsp_vec3 a, double ra)
{
    k->is_cone = 1;
    k->b = b;
    k->a = a;
    k->rb = fabs(rb);
    k->ra = fabs(ra);
    k->patches = 0;
    k->originals++;
    spd_sink inner = tess_check_sink(k);
    double b4[4] = {b.x, b.y, b.z, rb}, a4[4] = {a.x, a.y, a.z, ra};
    spd_cylcone(&inner, b4, a4);
    size_t want = tess_cone_tris(k->tess.slices) / (rb == 0.0 || ra == 0.0 ? 2 : 1);
    if (k->patches != want)
        tc_fail(k, "patch count", (double)k->patches, (double)want);
}

/* The outer sink: the scene's own primitives, untessellated. */
static void oc_sphere(spd_sink *s, bsp_vec3 c, double r)
{
    tc_run_sphere(s->ctx, c, r);
}
static void oc_cone(spd_sink *s, bsp_vec3 b, double rb, bsp_vec3 a, double ra)
{
    tc_run_cone(s->ctx, b, rb, a, ra);
}
static void oc_background(spd_sink *s, const double rgb[3])
{
    (void)s;
    (void)rgb;
}
static void oc_view(spd_sink *s, bsp_vec3 from, bsp_vec3 at, bsp_vec3 up, double angle,
                    double hither, int resx, int resy)
{
    (void)s, (void)from, (void)at, (void)up, (void)angle, (void)hither, (void)resx, (void)resy;
}
static void oc_light(spd_sink *s, bsp_vec3 pos)
{
    (void)s;
    (void)pos;
}
static void oc_material(spd_sink *s, const double rgb[3], double kd, double ks, double shine,
                        double t, double ior)
{
    (void)s, (void)rgb, (void)kd, (void)ks, (void)shine, (void)t, (void)ior;
}
static void oc_polygon(spd_sink *s, const bsp_vec3 *v, int n)
{
    (void)s, (void)v, (void)n;
}
static void oc_patch(spd_sink *s, const bsp_vec3 *v, const bsp_vec3 *nrm, int n)
{
    (void)s, (void)v, (void)nrm, (void)n;
}

static void tc_report(tess_check *k)
{
    CHECK_MSG(k->bad == 0, "%s: %zu failed checks; first: %s", k->what, k->bad, k->first);
    CHECK_MSG(k->passed_on == 0, "%s: %zu primitives not tessellated", k->what, k->passed_on);
}

/* Every vertex of every tessellated sphere and cone of real scenes lies on
 * the original surface (to round-off unrounded, within %g precision as NFF
 * text), with the true outward unit normal, on counterclockwise triangles,
 * in the predicted number. Also synthetic cones with a pointed end. */
TEST(spd_tessellated_vertices_lie_on_the_surfaces)
{
    static const struct {
        const char *what;
        spd_generator gen;
        int size, level;
    } runs[] = {
        {"balls:2:t8", spd_gen_balls, 2, 8},        {"balls:1:t64", spd_gen_balls, 1, 64},
        {"tree:4:t5", spd_gen_tree, 4, 5},          {"tree:6:t2", spd_gen_tree, 6, 2},
        {"lattice:2:t16", spd_gen_lattice, 2, 16},  {"rings:2:t3", spd_gen_rings, 2, 3},
        {"jacks:2:t12", spd_gen_jacks, 2, 12},      {"sample:t33", spd_gen_sample, 1, 33},
        {"mount:2:t6", spd_gen_mount, 2, 6},        {"shells:2:t7", spd_gen_shells, 2, 7},
    };
    for (size_t i = 0; i < sizeof runs / sizeof runs[0]; i++) {
        tess_check k;
        memset(&k, 0, sizeof k);
        REQUIRE(spd_tess_init(&k.tess, runs[i].level));
        k.what = runs[i].what;
        spd_sink outer = {.ctx = &k,
                          .failed = BSP_OK,
                          .background = oc_background,
                          .view = oc_view,
                          .light = oc_light,
                          .material = oc_material,
                          .sphere = oc_sphere,
                          .cone = oc_cone,
                          .polygon = oc_polygon,
                          .patch = oc_patch};
        runs[i].gen(runs[i].size, &outer);
        CHECK_EQ_INT(outer.failed, BSP_OK);
        CHECK_MSG(k.originals > 0, "%s: no sphere or cone", k.what);
        tc_report(&k);
        fprintf(stderr, "  %s: %zu spheres/cones, %zu vertices checked (worst %%g deviation "
                        "%.2f of its tolerance)\n",
                k.what, k.originals, k.vertices, k.worst_g);
    }

    /* pointed cones, a cylinder along each axis, and slanted ones */
    tess_check k;
    memset(&k, 0, sizeof k);
    k.what = "synthetic";
    for (int level = 2; level <= 64; level += level < 8 ? 1 : 7) {
        REQUIRE(spd_tess_init(&k.tess, level));
        tc_run_cone(&k, bsp_v3(1, 2, 3), 0.5, bsp_v3(1, 2, 5), 0.0);
        tc_run_cone(&k, bsp_v3(1, 2, 3), 0.0, bsp_v3(-2, 1, 1), 0.7);
        tc_run_cone(&k, bsp_v3(0, 0, 0), 1.0, bsp_v3(3, 0, 0), 1.0);
        tc_run_cone(&k, bsp_v3(0, 0, 0), 1.0, bsp_v3(0, -3, 0), 1.0);
        tc_run_cone(&k, bsp_v3(0.1, 0.2, 0.3), 0.25, bsp_v3(-0.4, 0.9, 0.05), 1.5);
        tc_run_cone(&k, bsp_v3(5, 5, 5), -0.5, bsp_v3(6, 5, 4), -0.2); /* inside only */
        tc_run_sphere(&k, bsp_v3(-3, 0.25, 7), 1.25);
        tc_run_sphere(&k, bsp_v3(0, 0, 0), -2.0); /* inside only */
    }
    tc_report(&k);
    /* degenerate ones go on untessellated (the scene drops them as before) */
    spd_sink inner = tess_check_sink(&k);
    double c4[4] = {1, 2, 3, 0.0}, b4[4] = {0, 0, 0, 1}, a4[4] = {0, 0, 0, 2};
    spd_sphere(&inner, c4);
    spd_cylcone(&inner, b4, a4);
    CHECK_EQ_INT(k.passed_on, 2);
}

/* The patches that replace each primitive of the untessellated scene U in
 * the tessellated scene T (whose level is LEVEL): *FIRST and *COUNT for
 * primitive P. Returns 0 when the layouts disagree. */
static int tess_layout(const bsp_scene *u, const bsp_scene *t, int level, size_t *first,
                       size_t *count)
{
    size_t at = 0;
    for (size_t p = 0; p < bsp_scene_prim_count(u); p++) {
        bsp_prim_kind kind = bsp_scene_prim_kind(u, p);
        size_t n = kind == BSP_PRIM_SPHERE ? tess_sphere_tris(level)
                   : kind == BSP_PRIM_CONE ? tess_cone_tris(level)
                                           : 1;
        first[p] = at;
        count[p] = n;
        at += n;
    }
    return at == bsp_scene_prim_count(t);
}

static double box_scale(bsp_box b)
{
    return maxabs3(b.lo) > maxabs3(b.hi) ? maxabs3(b.lo) : maxabs3(b.hi);
}

/* B within A, up to TOL. */
static int box_within(bsp_box b, bsp_box a, double tol)
{
    for (int k = 0; k < 3; k++)
        if (b.lo.v[k] < a.lo.v[k] - tol || b.hi.v[k] > a.hi.v[k] + tol)
            return 0;
    return 1;
}

/* Tessellation inscribes: the patches of each sphere or cone lie within its
 * bounds (up to %g rounding of the vertices), reach its poles, and the
 * whole scene's bounds lie within the original's; polygons and patches are
 * unchanged, bit for bit, as are materials. */
TEST(spd_tessellation_is_inscribed)
{
    static const struct {
        const char *plain, *tess;
        int level;
    } pairs[] = {
        {"spd:balls:2", "spd:balls:2:t6", 6},   {"spd:tree:5", "spd:tree:5:t7", 7},
        {"spd:lattice:2", "spd:lattice:2:t4", 4}, {"spd:sample", "spd:sample:t9", 9},
        {"spd:rings:1", "spd:rings:1:t2", 2},   {"spd:jacks:2", "spd:jacks:2:t16", 16},
    };
    for (size_t i = 0; i < sizeof pairs / sizeof pairs[0]; i++) {
        bsp_scene *u = build(pairs[i].plain), *t = build(pairs[i].tess);
        if (!u || !t) {
            bsp_scene_destroy(u);
            bsp_scene_destroy(t);
            continue;
        }
        size_t np = bsp_scene_prim_count(u);
        size_t *first = malloc(np * sizeof *first), *count = malloc(np * sizeof *count);
        REQUIRE(first && count);
        int fails = 0;
        CHECK_MSG(tess_layout(u, t, pairs[i].level, first, count), "%s: layout", pairs[i].tess);
        for (size_t p = 0; p < np && fails < 3 && tess_layout(u, t, pairs[i].level, first, count);
             p++) {
            bsp_box orig = bsp_scene_prim_bounds(u, p);
            bsp_prim_kind kind = bsp_scene_prim_kind(u, p);
            if (kind != BSP_PRIM_SPHERE && kind != BSP_PRIM_CONE) {
                bsp_box b = bsp_scene_prim_bounds(t, first[p]);
                if (bsp_scene_prim_kind(t, first[p]) != kind || memcmp(&b, &orig, sizeof b) ||
                    bsp_scene_prim_material(t, first[p]) != bsp_scene_prim_material(u, p)) {
                    fails++;
                    harness_fail(__FILE__, __LINE__, "%s: primitive %zu changed", pairs[i].tess,
                                 p);
                }
                continue;
            }
            bsp_box all = bsp_scene_prim_bounds(t, first[p]);
            for (size_t q = first[p]; q < first[p] + count[p] && fails < 3; q++) {
                bsp_box b = bsp_scene_prim_bounds(t, q);
                for (int k = 0; k < 3; k++) {
                    all.lo.v[k] = fmin(all.lo.v[k], b.lo.v[k]);
                    all.hi.v[k] = fmax(all.hi.v[k], b.hi.v[k]);
                }
                if (bsp_scene_prim_kind(t, q) != BSP_PRIM_PATCH ||
                    bsp_scene_prim_material(t, q) != bsp_scene_prim_material(u, p)) {
                    fails++;
                    harness_fail(__FILE__, __LINE__, "%s: patch %zu of primitive %zu",
                                 pairs[i].tess, q, p);
                }
            }
            double tol = 1e-5 * box_scale(orig); /* one %g unit of a coordinate */
            if (!box_within(all, orig, tol)) {
                fails++;
                harness_fail(__FILE__, __LINE__,
                             "%s: primitive %zu's patches leave its bounds: z %.9g..%.9g vs "
                             "%.9g..%.9g",
                             pairs[i].tess, p, all.lo.z, all.hi.z, orig.lo.z, orig.hi.z);
            }
            /* a sphere's tessellation reaches both poles */
            if (kind == BSP_PRIM_SPHERE &&
                (fabs(all.lo.z - orig.lo.z) > tol || fabs(all.hi.z - orig.hi.z) > tol)) {
                fails++;
                harness_fail(__FILE__, __LINE__, "%s: sphere %zu's poles missing", pairs[i].tess,
                             p);
            }
        }
        bsp_box bu = bsp_scene_bounds(u), bt = bsp_scene_bounds(t);
        CHECK_MSG(box_within(bt, bu, 1e-5 * box_scale(bu)),
                  "%s: bounds (%g %g %g)-(%g %g %g) not within (%g %g %g)-(%g %g %g)",
                  pairs[i].tess, bt.lo.x, bt.lo.y, bt.lo.z, bt.hi.x, bt.hi.y, bt.hi.z, bu.lo.x,
                  bu.lo.y, bu.lo.z, bu.hi.x, bu.hi.y, bu.hi.z);
        CHECK_EQ_INT(bsp_scene_material_count(t), bsp_scene_material_count(u));
        CHECK_EQ_INT(bsp_scene_light_count(t), bsp_scene_light_count(u));
        free(first);
        free(count);
        bsp_scene_destroy(u);
        bsp_scene_destroy(t);
    }
}

/* The longest edge of any triangle of a unit sphere at LEVEL: the fans'
 * ring and pole edges, the bands' sides and diagonals. */
static double tess_longest_edge(int level)
{
    int m = (int)tess_bands(level);
    double dlon = 2.0 * 3.141592653589793 / level, dlat = 3.141592653589793 / m;
    double longest = 2.0 * sin(dlat / 2.0); /* along a meridian */
    for (int j = 1; j < m; j++) {
        double a = dlat * j, b = dlat * (j + 1);
        /* along the ring j */
        double ring = 2.0 * sin(a) * sin(dlon / 2.0);
        if (ring > longest)
            longest = ring;
        if (j + 1 < m) { /* the diagonal (j, i) - (j + 1, i + 1) */
            double dot = sin(a) * sin(b) * cos(dlon) + cos(a) * cos(b);
            double diag = sqrt(2.0 - 2.0 * dot);
            if (diag > longest)
                longest = diag;
        }
    }
    return longest;
}

/* A ray through a sphere's centre hits its tessellation where the true
 * sphere is hit, at most the chord error later: a point of a triangle whose
 * vertices lie on a sphere of radius r and whose edges are at most L long
 * is at least sqrt(r^2 - L^2 / 3) from the centre (|sum l_k v_k|^2 =
 * r^2 - 1/2 sum_{k != l} l_k l_l |v_k - v_l|^2). And never earlier, up to
 * %g rounding of the vertices. */
TEST(spd_tessellated_sphere_hit_near_true_sphere)
{
    static const double dirs[][3] = {
        {0.3, 0.5, 0.81},   {-0.7, 0.2, 0.4},  {0.11, -0.9, -0.3}, {-0.45, -0.55, 0.61},
        {0.9, 0.05, -0.21}, {0.02, 0.97, 0.1}, {-0.3, 0.31, -0.88}, {0.6, -0.6, 0.05},
    };
    bsp_scene *u = build("spd:balls:1");
    REQUIRE(u);
    static const int levels[] = {4, 6, 8, 16, 64};
    for (size_t li = 0; li < sizeof levels / sizeof levels[0]; li++) {
        int level = levels[li];
        char spec[32];
        snprintf(spec, sizeof spec, "spd:balls:1:t%d", level);
        bsp_scene *t = build(spec);
        if (!t)
            continue;
        size_t np = bsp_scene_prim_count(u), first[16], count[16];
        REQUIRE(np <= 16);
        REQUIRE(tess_layout(u, t, level, first, count));
        double L = tess_longest_edge(level), worst = 0.0;
        double dev = 1.0 - sqrt(1.0 - L * L / 3.0); /* relative to r */
        if (level == 16)
            CHECK_MSG(dev < 0.06, "level 16: chord error bound %g", dev);
        if (level == 64)
            CHECK_MSG(dev < 0.004, "level 64: chord error bound %g", dev);
        int fails = 0;
        for (size_t p = 0; p < np && fails < 3; p++) {
            if (bsp_scene_prim_kind(u, p) != BSP_PRIM_SPHERE)
                continue;
            bsp_box b = bsp_scene_prim_bounds(u, p);
            bsp_vec3 c;
            for (int k = 0; k < 3; k++)
                c.v[k] = 0.5 * (b.lo.v[k] + b.hi.v[k]);
            double r = 0.5 * (b.hi.x - b.lo.x);
            double eps = 2e-5 * (maxabs3(c) + r); /* %g rounding of vertices */
            for (size_t d = 0; d < sizeof dirs / sizeof dirs[0]; d++) {
                bsp_vec3 w = bsp_v3(dirs[d][0], dirs[d][1], dirs[d][2]);
                double wl = len3(w);
                w = bsp_v3(w.x / wl, w.y / wl, w.z / wl);
                bsp_ray ray;
                ray.org = bsp_v3(c.x + 3 * r * w.x, c.y + 3 * r * w.y, c.z + 3 * r * w.z);
                ray.dir = bsp_v3(-w.x, -w.y, -w.z);
                ray.tmin = 0;
                ray.tmax = INFINITY;
                double best = INFINITY;
                for (size_t q = first[p]; q < first[p] + count[p]; q++) {
                    bsp_hit h;
                    if (bsp_scene_intersect_prim(t, q, &ray, &h) && h.t < best)
                        best = h.t;
                }
                double lo = 2 * r - eps, hi = 2 * r + dev * r + eps;
                if (!(best >= lo && best <= hi)) {
                    fails++;
                    harness_fail(__FILE__, __LINE__,
                                 "%s: sphere %zu, direction %zu: t %.9g, true sphere %.9g, "
                                 "allowed %.9g..%.9g",
                                 spec, p, d, best, 2 * r, lo, hi);
                }
                if (isfinite(best) && (best - 2 * r) / r > worst)
                    worst = (best - 2 * r) / r;
            }
        }
        fprintf(stderr, "  level %2d: hits at most %.5f r behind the true sphere (bound %.5f r)\n",
                level, worst, dev);
        bsp_scene_destroy(t);
    }
    bsp_scene_destroy(u);
}

/* Spec syntax errors name the problem and the valid range. */
TEST(spd_tessellation_spec_errors)
{
    expect_invalid("spd:balls:t1", "bad tessellation 't1'");
    expect_invalid("spd:balls:t1", "from 2 to 64");
    expect_invalid("spd:balls:t999", "bad tessellation 't999'");
    expect_invalid("spd:balls:4:x3", "bad tessellation 'x3'");
    expect_invalid("spd:balls:4:x3", "spd:balls:4:t8");
    expect_invalid("spd:balls:t65", "from 2 to 64");
    expect_invalid("spd:balls:t", "bad tessellation 't'");
    expect_invalid("spd:balls:4:t", "bad tessellation 't'");
    expect_invalid("spd:balls:t-3", "bad tessellation 't-3'");
    expect_invalid("spd:balls:4:t8:1", "bad tessellation 't8:1'");
    expect_invalid("spd:balls:9:t8", "bad size factor '9'");
    expect_invalid("spd:balls:t8:4", "bad size factor 't8'");
    expect_invalid("spd:balls::t8", "bad size factor ''");
    expect_invalid("spd:sample:2:t8", "fixed size");

    bsp_error err = {0};
    char *text = NULL;
    size_t len = 0;
    FILE *mem = open_memstream(&text, &len);
    REQUIRE(mem);
    CHECK_EQ_INT(bsp_spd_write_nff("balls", 1, 1, mem, &err), BSP_ERR_INVALID);
    CHECK_STR_CONTAINS(err.message, "bad tessellation 't1'");
    CHECK_EQ_INT(bsp_spd_write_nff("balls", 1, 65, mem, &err), BSP_ERR_INVALID);
    CHECK_STR_CONTAINS(err.message, "from 2 to 64");
    CHECK_EQ_INT(bsp_spd_write_nff("balls", 1, -4, mem, &err), BSP_ERR_INVALID);
    fclose(mem);
    CHECK_EQ_INT(len, 0);
    free(text);
}

/* The NFF text of a tessellated scene (bspray gen NAME -s SIZE -t N), read
 * back, is exactly the scene "spd:NAME:SIZE:tN" builds: every primitive's
 * kind, bounds and material bit for bit, and the t of rays. */
TEST(spd_tessellated_text_equals_generated_scene)
{
    static const struct {
        const char *name;
        int size, level;
    } runs[] = {
        {"balls", 2, 6}, {"tree", 4, 5},  {"lattice", 2, 8}, {"rings", 1, 4},   {"jacks", 2, 3},
        {"sample", 1, 7}, {"mount", 2, 2}, {"shells", 1, 9}, {"balls", 1, 64}, {"teapot", 2, 5},
    };
    for (size_t i = 0; i < sizeof runs / sizeof runs[0]; i++) {
        char spec[64];
        snprintf(spec, sizeof spec, "spd:%s:%d:t%d", runs[i].name, runs[i].size, runs[i].level);
        char *text = generate_text(runs[i].name, runs[i].size, runs[i].level);
        bsp_scene *g = build(spec), *f = NULL;
        if (!text || !g) {
            free(text);
            bsp_scene_destroy(g);
            continue;
        }
        bsp_error err;
        REQUIRE(bsp_scene_load_nff_memory(text, strlen(text), spec, &f, &err) == BSP_OK);
        size_t n = bsp_scene_prim_count(f);
        CHECK_EQ_INT(bsp_scene_prim_count(g), n);
        CHECK_EQ_INT(bsp_scene_kind_count(f, BSP_PRIM_SPHERE) + bsp_scene_kind_count(f, BSP_PRIM_CONE),
                     0);
        int differ = 0;
        for (size_t p = 0; p < n && p < bsp_scene_prim_count(g) && differ < 3; p++) {
            bsp_box a = bsp_scene_prim_bounds(f, p), b = bsp_scene_prim_bounds(g, p);
            if (bsp_scene_prim_kind(f, p) != bsp_scene_prim_kind(g, p) ||
                memcmp(&a, &b, sizeof a) != 0 ||
                bsp_scene_prim_material(f, p) != bsp_scene_prim_material(g, p)) {
                differ++;
                harness_fail(__FILE__, __LINE__, "%s: primitive %zu differs from its NFF text",
                             spec, p);
            }
        }
        CHECK(memcmp(bsp_scene_camera(f), bsp_scene_camera(g), sizeof(bsp_camera)) == 0);
        CHECK_EQ_INT(bsp_scene_material_count(f), bsp_scene_material_count(g));
        for (size_t m = 0; m < bsp_scene_material_count(f) && m < bsp_scene_material_count(g);
             m++)
            CHECK(same_material(bsp_scene_material(f, m), bsp_scene_material(g, m)));
        const bsp_camera *cam = bsp_scene_camera(f);
        size_t rays = 0;
        for (size_t p = 0; p < n && cam; p += 1 + n / 400) {
            bsp_box b = bsp_scene_prim_bounds(f, p);
            bsp_ray r;
            r.org = cam->from;
            for (int k = 0; k < 3; k++)
                r.dir.v[k] = 0.5 * (b.lo.v[k] + b.hi.v[k]) - cam->from.v[k];
            r.tmin = 0;
            r.tmax = INFINITY;
            bsp_hit ha, hb;
            int fa = bsp_scene_intersect_prim(f, p, &r, &ha);
            int fb = bsp_scene_intersect_prim(g, p, &r, &hb);
            CHECK_EQ_INT(fa, fb);
            if (fa && fb) {
                CHECK(memcmp(&ha.t, &hb.t, sizeof ha.t) == 0);
                rays++;
            }
        }
        CHECK_MSG(rays > 0, "%s: no ray hit", spec);
        bsp_scene_destroy(f);
        bsp_scene_destroy(g);
        free(text);
    }
}

/* bsp_scene_check says what bsp_scene_load would, without the scene: the
 * same status and message for every SPD spec (good and bad names, sizes,
 * tessellations and their limit), and for files that cannot be opened or
 * are directories; a readable file passes, malformed or not. */
TEST(scene_check_agrees_with_scene_load)
{
    static const char *const specs[] = {
        "spd:balls",        "spd:balls:1",       "spd:BALLS:2",     "spd:nosuch",
        "spd:",             "spd:balls:0",       "spd:balls:99",    "spd:balls:x",
        "spd:balls:2:t8",   "spd:balls:t8",      "spd:balls:2:t99", "spd:balls:2:tx",
        "spd:balls:2:3",    "spd:tetra:13",      "spd:balls:6:t64", "spd:gears:1:t4",
        "spd:balls:2:t8:x", "spd:balls:12345678901234567890123456789012345",
        "tests/data/nff_good/comments.nff", "tests/data/nff_bad", "tests/nonexistent.nff",
        "tests/nonexistent.ply.gz",
    };
    for (size_t i = 0; i < sizeof specs / sizeof *specs; i++) {
        bsp_error ec, el;
        memset(&ec, 0, sizeof ec);
        memset(&el, 0, sizeof el);
        bsp_status sc = bsp_scene_check(specs[i], &ec);
        bsp_scene *s = NULL;
        /* a large spec passes the check; loading it is not needed to agree */
        int big = !strcmp(specs[i], "spd:tetra:13") || !strcmp(specs[i], "spd:balls:6:t64");
        if (big) {
            CHECK_MSG(sc == BSP_OK || sc == BSP_ERR_LIMIT, "%s: check gave %d", specs[i], (int)sc);
            continue;
        }
        bsp_status sl = bsp_scene_load(specs[i], &s, &el);
        bsp_scene_destroy(s);
        if (sc != BSP_OK) {
            CHECK_MSG(sl == sc && !strcmp(ec.message, el.message),
                      "%s: check %d '%s', load %d '%s'", specs[i], (int)sc, ec.message, (int)sl,
                      el.message);
        } else {
            /* passed: a load fails only on the file's content (no such spec
             * here but the readable good file, which loads) */
            CHECK_MSG(sl == BSP_OK, "%s: check passed, load gave %d '%s'", specs[i], (int)sl,
                      el.message);
        }
    }
    /* the check reads nothing of a file: a malformed one passes, and only
     * the load refuses it */
    bsp_error e;
    bsp_scene *s = NULL;
    CHECK_EQ_INT(bsp_scene_check("tests/data/nff_bad/binary_garbage.nff", &e), BSP_OK);
    CHECK(bsp_scene_load("tests/data/nff_bad/binary_garbage.nff", &s, &e) != BSP_OK);
    bsp_scene_destroy(s);
    CHECK(bsp_scene_check(NULL, &e) != BSP_OK && e.message[0]);
}

/* --- the list of names ---------------------------------------------------------------- */

/* The thirteen SPD databases of ../shared/scenes/spd/MANIFEST.md, in the
 * registry's order (balls first: the default scene). */
static const char *const spd_manifest_names[] = {"balls",   "tetra",  "tree",  "rings",   "gears",
                                                 "mount",   "lattice", "teapot", "shells",
                                                 "jacks",   "sombrero", "sample", "nurbtst"};

typedef struct names_call {
    const char *got;
} names_call;

static void *call_scene_names(void *arg)
{
    ((names_call *)arg)->got = bsp_spd_scene_names();
    return NULL;
}

/* bsp_spd_scene_names lists exactly the scenes spd:NAME builds, space-
 * separated in the registry's order; each listed name has size bounds and
 * builds at its smallest size. Its first calls are made by four threads at
 * once (this test runs alone in `make tsan-test`, so under ThreadSanitizer
 * those are the process's first calls), and all get the same string. */
TEST(spd_names_list_every_scene)
{
    names_call calls[4];
    pthread_t tid[4];
    int started[4];
    for (int i = 0; i < 4; i++)
        started[i] = pthread_create(&tid[i], NULL, call_scene_names, &calls[i]) == 0;
    for (int i = 0; i < 4; i++)
        if (started[i])
            pthread_join(tid[i], NULL);
        else
            call_scene_names(&calls[i]);
    const char *names = bsp_spd_scene_names();
    REQUIRE(names);
    for (int i = 0; i < 4; i++)
        CHECK(calls[i].got == names);

    char want[256] = "";
    size_t count = sizeof spd_manifest_names / sizeof spd_manifest_names[0];
    for (size_t i = 0; i < count; i++) {
        if (i)
            strcat(want, " ");
        strcat(want, spd_manifest_names[i]);
    }
    CHECK_MSG(strcmp(names, want) == 0, "names '%s', want '%s'", names, want);

    /* every listed name is a scene (tokenised from the string itself) */
    char copy[256];
    snprintf(copy, sizeof copy, "%s", names);
    size_t listed = 0;
    for (char *save = NULL, *tok = strtok_r(copy, " ", &save); tok;
         tok = strtok_r(NULL, " ", &save)) {
        listed++;
        int def = 0, lo = 0, hi = 0;
        CHECK_MSG(bsp_spd_scene_sizes(tok, &def, &lo, &hi), "%s has no sizes", tok);
        CHECK_MSG(lo >= 1 && lo <= def && def <= hi, "%s: sizes %d <= %d <= %d", tok, lo, def,
                  hi);
        char spec[64];
        snprintf(spec, sizeof spec, "spd:%s:%d", tok, lo);
        bsp_scene *s = build(spec);
        CHECK_MSG(s && bsp_scene_prim_count(s) > 0, "%s builds no scene", spec);
        bsp_scene_destroy(s);
    }
    CHECK_EQ_INT(listed, count);
}
