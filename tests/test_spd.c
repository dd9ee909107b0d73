/*
 * test_spd.c — the built-in SPD generators (src/spd): the NFF text of every
 * generated scene against the reference file made by Haines' own program
 * (../shared/scenes/spd, token by token within %g precision), a check that
 * this comparison does catch small changes, primitive counts of the built
 * scenes at other sizes against the MANIFEST formulas, error messages for
 * unknown names and bad sizes, and the time to build ~6 * 10^5 spheres.
 */
#include <ctype.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bspray/scene.h"
#include "harness.h"
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
    size_t cap = 1 << 16, n = 0, got;
    char *buf = malloc(cap);
    while (buf && (got = fread(buf + n, 1, cap - n - 1, fp)) > 0) {
        n += got;
        if (cap - n < 2) {
            char *nb = realloc(buf, cap * 2);
            if (!nb) {
                free(buf);
                buf = NULL;
                break;
            }
            buf = nb;
            cap *= 2;
        }
    }
    fclose(fp);
    if (buf)
        buf[n] = '\0';
    return buf;
}

/* The NFF text of NAME at SIZE from bsp_spd_write_nff, or NULL (with a failed
 * check). Free with free(). */
static char *generate_text(const char *name, int size)
{
    char *text = NULL;
    size_t len = 0;
    FILE *mem = open_memstream(&text, &len);
    REQUIRE(mem != NULL);
    bsp_error err = {0};
    bsp_status st = bsp_spd_write_nff(name, size, mem, &err);
    fclose(mem);
    CHECK_MSG(st == BSP_OK, "bsp_spd_write_nff(%s, %d): %s", name, size, err.message);
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
    char *got = generate_text(name, size);
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
    char *a = generate_text("balls", 0), *b = generate_text("balls", 4);
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
    char *ref = generate_text("balls", 2);
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
        REQUIRE(bsp_spd_write_nff(nm, colon ? atoi(colon + 1) : 0, mem, &err) == BSP_OK);
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
    expect_invalid("spd:balls:4:4", "bad size factor");
    expect_invalid("spd:balls:99999999999999999999", "bad size factor");
    expect_invalid("spd:mount:8", "valid sizes are 1 to 7");
    expect_invalid("spd:sample:2", "fixed size");
    expect_invalid("spd:tetra:14", "valid sizes are 1 to 13");

    bsp_error err = {0};
    char *text = NULL;
    size_t len = 0;
    FILE *mem = open_memstream(&text, &len);
    REQUIRE(mem);
    CHECK_EQ_INT(bsp_spd_write_nff("nosuch", 1, mem, &err), BSP_ERR_INVALID);
    CHECK_STR_CONTAINS(err.message, "known scenes: balls");
    CHECK_EQ_INT(bsp_spd_write_nff("jacks", 9, mem, &err), BSP_ERR_INVALID);
    CHECK_STR_CONTAINS(err.message, "valid sizes are 1 to 8");
    CHECK_EQ_INT(bsp_spd_write_nff("jacks", -3, mem, &err), BSP_ERR_INVALID);
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
            CHECK(memcmp(bsp_scene_material(f, m), bsp_scene_material(g, m),
                         sizeof(bsp_material)) == 0);
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
