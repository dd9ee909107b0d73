/*
 * test_nff.c — the NFF reader: every SPD scene in ../shared against the
 * counts, views and backgrounds of its MANIFEST.md (parsed here, so the
 * manifest stays the independent answer); memory, gzip and file input give
 * the same scene; hand-written valid files (tests/data/nff_good: comments,
 * layouts, optional light colours, number syntax, degenerate primitives);
 * numbers read bit for bit like strtod; and a corpus of malformed files
 * (tests/data/nff_bad) with the status, line and message each must give,
 * through both the file and the memory entry points.
 */
#include <dirent.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>
#include <unistd.h>

#include <zlib.h>

#include "bspray/scene.h"
#include "harness.h"
#include "same_util.h"

#define GOOD_DIR "tests/data/nff_good"
#define BAD_DIR "tests/data/nff_bad"

/* --- helpers ------------------------------------------------------------------ */

/* Loads PATH, which must succeed (the test ends otherwise). */
static bsp_scene *load_ok(const char *path)
{
    bsp_scene *s = NULL;
    bsp_error err;
    memset(&err, 0, sizeof err);
    bsp_status st = bsp_scene_load(path, &s, &err);
    CHECK_MSG(st == BSP_OK, "loading %s: %s: %s", path, bsp_status_name(st), err.message);
    REQUIRE(st == BSP_OK && s != NULL);
    return s;
}

static bsp_scene *load_mem_ok(const char *buf, size_t len, const char *name)
{
    bsp_scene *s = NULL;
    bsp_error err;
    memset(&err, 0, sizeof err);
    bsp_status st = bsp_scene_load_nff_memory(buf, len, name, &s, &err);
    CHECK_MSG(st == BSP_OK, "loading %s from memory: %s: %s", name, bsp_status_name(st),
              err.message);
    REQUIRE(st == BSP_OK && s != NULL);
    return s;
}

/* Checks that A and B hold the same scene; warnings are compared word for
 * word only when SAME_NAME (they carry the file name). */
static void check_same_scene(const bsp_scene *a, const bsp_scene *b, int same_name)
{
    REQUIRE(a && b);
    CHECK_EQ_INT(bsp_scene_prim_count(a), bsp_scene_prim_count(b));
    size_t n = bsp_scene_prim_count(a);
    if (n > bsp_scene_prim_count(b))
        n = bsp_scene_prim_count(b);
    size_t bad = 0;
    for (size_t i = 0; i < n; i++) {
        bsp_box x = bsp_scene_prim_bounds(a, i), y = bsp_scene_prim_bounds(b, i);
        if (bsp_scene_prim_kind(a, i) != bsp_scene_prim_kind(b, i) ||
            bsp_scene_prim_vertex_count(a, i) != bsp_scene_prim_vertex_count(b, i) ||
            bsp_scene_prim_material(a, i) != bsp_scene_prim_material(b, i) ||
            !same_vec(x.lo, y.lo) || !same_vec(x.hi, y.hi))
            bad++;
    }
    CHECK_EQ_INT(bad, 0);
    for (int k = 0; k < BSP_PRIM_KIND_COUNT; k++)
        CHECK_EQ_INT(bsp_scene_kind_count(a, (bsp_prim_kind)k),
                     bsp_scene_kind_count(b, (bsp_prim_kind)k));
    REQUIRE(bsp_scene_light_count(a) == bsp_scene_light_count(b));
    for (size_t i = 0; i < bsp_scene_light_count(a); i++) {
        const bsp_light *la = bsp_scene_light(a, i), *lb = bsp_scene_light(b, i);
        CHECK(same_vec(la->pos, lb->pos));
        for (int c = 0; c < 3; c++)
            CHECK(same_double(la->color[c], lb->color[c]));
        CHECK_EQ_INT(la->has_color, lb->has_color);
    }
    REQUIRE(bsp_scene_material_count(a) == bsp_scene_material_count(b));
    for (size_t i = 0; i < bsp_scene_material_count(a); i++) {
        const bsp_material *ma = bsp_scene_material(a, i), *mb = bsp_scene_material(b, i);
        for (int c = 0; c < 3; c++)
            CHECK(same_double(ma->color[c], mb->color[c]));
        CHECK(same_double(ma->kd, mb->kd) && same_double(ma->ks, mb->ks) &&
              same_double(ma->shine, mb->shine) && same_double(ma->t, mb->t) &&
              same_double(ma->ior, mb->ior));
    }
    const bsp_camera *ca = bsp_scene_camera(a), *cb = bsp_scene_camera(b);
    CHECK((ca == NULL) == (cb == NULL));
    if (ca && cb) {
        CHECK(same_vec(ca->from, cb->from) && same_vec(ca->at, cb->at) && same_vec(ca->up, cb->up));
        CHECK(same_double(ca->angle_deg, cb->angle_deg) && same_double(ca->hither, cb->hither));
        CHECK(ca->res_x == cb->res_x && ca->res_y == cb->res_y);
    }
    double ba[3], bb[3];
    bsp_scene_background(a, ba);
    bsp_scene_background(b, bb);
    for (int c = 0; c < 3; c++)
        CHECK(same_double(ba[c], bb[c]));
    bsp_box xa = bsp_scene_bounds(a), xb = bsp_scene_bounds(b);
    CHECK(same_vec(xa.lo, xb.lo) && same_vec(xa.hi, xb.hi));
    CHECK_EQ_INT(bsp_scene_warning_count(a), bsp_scene_warning_count(b));
    if (same_name && bsp_scene_warning_count(a) == bsp_scene_warning_count(b))
        for (size_t i = 0; i < bsp_scene_warning_count(a); i++)
            CHECK(strcmp(bsp_scene_warning(a, i), bsp_scene_warning(b, i)) == 0);
}

/* Writes LEN bytes of BUF gzip-compressed to PATH ("wb") or as one more
 * gzip member ("ab"). */
static int write_gzip(const char *path, const char *mode, const char *buf, size_t len)
{
    gzFile gz = gzopen(path, mode);
    if (!gz)
        return 0;
    int ok = len == 0 || gzwrite(gz, buf, (unsigned)len) == (int)len;
    return gzclose(gz) == Z_OK && ok;
}

/* --- the SPD manifest --------------------------------------------------------- */

#define MAX_CELLS 24
#define CELL_SIZE 160

/* Splits a Markdown table row "| a | b |" into trimmed cells; returns how many. */
static int split_row(const char *line, char cells[MAX_CELLS][CELL_SIZE])
{
    int n = 0;
    const char *p = strchr(line, '|');
    if (!p)
        return 0;
    p++;
    while (*p && *p != '\n' && n < MAX_CELLS) {
        const char *e = p;
        while (*e && *e != '|' && *e != '\n')
            e++;
        if (*e != '|')
            break;
        const char *a = p, *b = e;
        while (a < b && (*a == ' ' || *a == '`'))
            a++;
        while (b > a && (b[-1] == ' ' || b[-1] == '`'))
            b--;
        size_t len = (size_t)(b - a) < CELL_SIZE - 1 ? (size_t)(b - a) : CELL_SIZE - 1;
        memcpy(cells[n], a, len);
        cells[n][len] = '\0';
        n++;
        p = e + 1;
    }
    return n;
}

static int column(char cells[MAX_CELLS][CELL_SIZE], int n, const char *name, int prefix)
{
    for (int i = 0; i < n; i++)
        if (prefix ? strncmp(cells[i], name, strlen(name)) == 0 : strcmp(cells[i], name) == 0)
            return i;
    return -1;
}

/* The section "### FILE" of the manifest, up to the next heading (or NULL). */
static const char *manifest_section(const char *md, const char *file, size_t *len)
{
    char head[128];
    snprintf(head, sizeof head, "\n### %s\n", file);
    const char *s = strstr(md, head);
    if (!s)
        return NULL;
    s += strlen(head);
    const char *e = strstr(s, "\n#");
    *len = e ? (size_t)(e - s) : strlen(s);
    return s;
}

/* Checks the view block and background of FILE's manifest section. */
static void check_view_and_background(const char *md, const char *file, const bsp_scene *s)
{
    size_t len = 0;
    const char *sec = manifest_section(md, file, &len);
    CHECK_MSG(sec != NULL, "%s: no '### %s' section in MANIFEST.md", file, file);
    if (!sec)
        return;
    char *text = malloc(len + 1);
    REQUIRE(text);
    memcpy(text, sec, len);
    text[len] = '\0';
    const char *bg = strstr(text, "background `b ");
    CHECK_MSG(bg != NULL, "%s: no background in the manifest", file);
    if (bg) {
        char *end;
        double want[3], got[3];
        const char *p = bg + strlen("background `b ");
        for (int i = 0; i < 3; i++) {
            want[i] = strtod(p, &end);
            p = end;
        }
        bsp_scene_background(s, got);
        for (int i = 0; i < 3; i++)
            CHECK_MSG(got[i] == want[i], "%s: background[%d] %g, manifest %g", file, i, got[i],
                      want[i]);
    }
    const char *v = strstr(text, "```\nv\n");
    CHECK_MSG(v != NULL, "%s: no view block in the manifest", file);
    const bsp_camera *cam = bsp_scene_camera(s);
    CHECK_MSG(cam != NULL, "%s: no camera", file);
    if (v && cam) {
        double f[3], a[3], u[3], angle, hither;
        int rx, ry;
        int got = sscanf(v + 6,
                         "from %lf %lf %lf at %lf %lf %lf up %lf %lf %lf angle %lf hither %lf "
                         "resolution %d %d",
                         &f[0], &f[1], &f[2], &a[0], &a[1], &a[2], &u[0], &u[1], &u[2], &angle,
                         &hither, &rx, &ry);
        CHECK_EQ_INT(got, 13);
        if (got == 13) {
            CHECK_MSG(same_vec(cam->from, bsp_v3(f[0], f[1], f[2])) &&
                          same_vec(cam->at, bsp_v3(a[0], a[1], a[2])) &&
                          same_vec(cam->up, bsp_v3(u[0], u[1], u[2])),
                      "%s: camera vectors differ from the manifest", file);
            CHECK_MSG(cam->angle_deg == angle && cam->hither == hither,
                      "%s: angle/hither %g %g, manifest %g %g", file, cam->angle_deg, cam->hither,
                      angle, hither);
            CHECK_MSG(cam->res_x == rx && cam->res_y == ry, "%s: resolution %dx%d, manifest %dx%d",
                      file, cam->res_x, cam->res_y, rx, ry);
        }
    }
    free(text);
}

/* Checks the "NxV, ..." breakdown of polygons by vertex count. */
static void check_polygon_breakdown(const char *file, const char *cell, const bsp_scene *s)
{
    const char *p = strchr(cell, '(');
    if (!p)
        return;
    p++;
    for (;;) {
        char *end;
        long count = strtol(p, &end, 10);
        if (end == p || *end != 'x')
            break;
        p = end + 1;
        long verts = strtol(p, &end, 10);
        if (end == p)
            break;
        p = end;
        size_t have = 0;
        for (size_t i = 0; i < bsp_scene_prim_count(s); i++)
            if (bsp_scene_prim_kind(s, i) == BSP_PRIM_POLYGON &&
                bsp_scene_prim_vertex_count(s, i) == (size_t)verts)
                have++;
        CHECK_MSG(have == (size_t)count, "%s: %zu polygons with %ld vertices, manifest %ld", file,
                  have, verts, count);
        while (*p == ',' || *p == ' ')
            p++;
    }
}

TEST(nff_spd_scenes_match_manifest)
{
    const char *shared = harness_shared_dir();
    if (!shared)
        harness_skip("../shared (the SPD scenes and their MANIFEST.md) is not present; set "
                     "BSPRAY_SHARED to its path to run this test");
    char dir[1024], path[1400];
    snprintf(dir, sizeof dir, "%s/scenes/spd", shared);
    snprintf(path, sizeof path, "%s/MANIFEST.md", dir);
    char *md = (char *)harness_read_file(path, &(size_t){0});
    REQUIRE(md != NULL);

    const char *sum = strstr(md, "## Summary");
    REQUIRE(sum != NULL);
    const char *line = strstr(sum, "\n| file");
    REQUIRE(line != NULL);
    line++;
    char cells[MAX_CELLS][CELL_SIZE];
    int ncol = split_row(line, cells);
    int c_file = column(cells, ncol, "file", 0), c_s = column(cells, ncol, "s", 0),
        c_c = column(cells, ncol, "c", 0), c_p = column(cells, ncol, "p ", 1),
        c_pp = column(cells, ncol, "pp", 0), c_l = column(cells, ncol, "l", 0),
        c_f = column(cells, ncol, "f", 0), c_prims = column(cells, ncol, "primitives", 0);
    REQUIRE(c_file >= 0 && c_s >= 0 && c_c >= 0 && c_p >= 0 && c_pp >= 0 && c_l >= 0 && c_f >= 0 &&
            c_prims >= 0);

    int rows = 0;
    char listed[64][CELL_SIZE];
    line = strchr(line, '\n'); /* the |---| separator */
    REQUIRE(line != NULL);
    line = strchr(line + 1, '\n');
    while (line && line[1] == '|') {
        line++;
        int n = split_row(line, cells);
        line = strchr(line, '\n');
        if (n < ncol)
            continue;
        const char *file = cells[c_file];
        if (rows < 64)
            snprintf(listed[rows], CELL_SIZE, "%s", file);
        rows++;
        snprintf(path, sizeof path, "%s/%s", dir, file);
        bsp_scene *s = load_ok(path);
        struct {
            const char *name;
            size_t got;
            int col;
        } want[] = {
            {"s", bsp_scene_kind_count(s, BSP_PRIM_SPHERE), c_s},
            {"c", bsp_scene_kind_count(s, BSP_PRIM_CONE), c_c},
            {"p", bsp_scene_kind_count(s, BSP_PRIM_POLYGON), c_p},
            {"pp", bsp_scene_kind_count(s, BSP_PRIM_PATCH), c_pp},
            {"l", bsp_scene_light_count(s), c_l},
            {"f", bsp_scene_material_count(s), c_f},
            {"primitives", bsp_scene_prim_count(s), c_prims},
        };
        for (size_t k = 0; k < sizeof want / sizeof want[0]; k++) {
            long expect = strtol(cells[want[k].col], NULL, 10);
            CHECK_MSG(want[k].got == (size_t)expect, "%s: %s count %zu, manifest %ld", file,
                      want[k].name, want[k].got, expect);
        }
        CHECK_EQ_INT(bsp_scene_kind_count(s, BSP_PRIM_DROPPED), 0);
        check_polygon_breakdown(file, cells[c_p], s);
        check_view_and_background(md, file, s);
        if (strcmp(file, "balls.nff") == 0) { /* spelled out once, as a sanity check */
            const bsp_camera *cam = bsp_scene_camera(s);
            REQUIRE(cam);
            CHECK(cam->from.x == 2.1 && cam->from.y == 1.3 && cam->from.z == 1.7);
            CHECK(cam->at.x == 0 && cam->at.y == 0 && cam->at.z == 0);
            CHECK(cam->up.x == 0 && cam->up.y == 0 && cam->up.z == 1);
            CHECK(cam->angle_deg == 45 && cam->hither == 0.01);
            CHECK(cam->res_x == 512 && cam->res_y == 512);
            double bg[3];
            bsp_scene_background(s, bg);
            CHECK(bg[0] == 0.078 && bg[1] == 0.361 && bg[2] == 0.753);
        }
        bsp_scene_destroy(s);
    }
    CHECK_MSG(rows >= 14, "only %d rows in the manifest's summary table", rows);

    /* every .nff in the folder is in the table */
    DIR *d = opendir(dir);
    REQUIRE(d != NULL);
    struct dirent *e;
    int files = 0;
    while ((e = readdir(d)) != NULL) {
        size_t len = strlen(e->d_name);
        if (len < 4 || strcmp(e->d_name + len - 4, ".nff") != 0)
            continue;
        files++;
        int found = 0;
        for (int i = 0; i < rows && i < 64; i++)
            found |= strcmp(listed[i], e->d_name) == 0;
        CHECK_MSG(found, "%s is not in the manifest's summary table", e->d_name);
    }
    closedir(d);
    CHECK_EQ_INT(files, rows);
    free(md);
}

/* --- memory and gzip input ------------------------------------------------------- */

/* Loads PATH as a file, from memory and gzipped (file and memory, one and two
 * members) and checks that all give the same scene. */
static void check_input_forms(const char *path, const char *tag)
{
    size_t len = 0;
    char *text = (char *)harness_read_file(path, &len);
    REQUIRE(text != NULL);
    bsp_scene *ref = load_ok(path);

    bsp_scene *mem = load_mem_ok(text, len, path);
    check_same_scene(ref, mem, 1);
    bsp_scene_destroy(mem);

    char gz[1024];
    snprintf(gz, sizeof gz, "%s/%s.nff.gz", harness_tmpdir(), tag);
    REQUIRE(write_gzip(gz, "wb", text, len));
    bsp_scene *zf = load_ok(gz);
    check_same_scene(ref, zf, 0);
    bsp_scene_destroy(zf);

    size_t zlen = 0;
    char *zbuf = (char *)harness_read_file(gz, &zlen);
    REQUIRE(zbuf != NULL);
    CHECK(zlen >= 2 && (unsigned char)zbuf[0] == 0x1f && (unsigned char)zbuf[1] == 0x8b);
    bsp_scene *zm = load_mem_ok(zbuf, zlen, path); /* no .gz in the name: magic bytes */
    check_same_scene(ref, zm, 1);
    bsp_scene_destroy(zm);
    free(zbuf);

    /* the same text split over two gzip members */
    snprintf(gz, sizeof gz, "%s/%s-2.gz", harness_tmpdir(), tag);
    REQUIRE(write_gzip(gz, "wb", text, len / 2));
    REQUIRE(write_gzip(gz, "ab", text + len / 2, len - len / 2));
    bsp_scene *z2 = load_ok(gz);
    check_same_scene(ref, z2, 0);
    bsp_scene_destroy(z2);

    bsp_scene_destroy(ref);
    free(text);
}

TEST(nff_memory_and_gzip_match_file)
{
    check_input_forms(GOOD_DIR "/comments.nff", "comments");
    check_input_forms(GOOD_DIR "/degenerate.nff", "degenerate");
    check_input_forms(GOOD_DIR "/order.nff", "order");
    check_input_forms(GOOD_DIR "/empty.nff", "empty");
    const char *shared = harness_shared_dir();
    if (!shared)
        harness_skip("../shared is not present: only the small files were compared");
    char path[1024];
    snprintf(path, sizeof path, "%s/scenes/spd/teapot.nff", shared);
    check_input_forms(path, "teapot");
    snprintf(path, sizeof path, "%s/scenes/spd/rings.nff", shared);
    check_input_forms(path, "rings");
}

/* --- valid hand-written files ------------------------------------------------------ */

TEST(nff_good_comments_everywhere)
{
    bsp_scene *s = load_ok(GOOD_DIR "/comments.nff");
    double bg[3];
    bsp_scene_background(s, bg);
    CHECK(bg[0] == 0.1 && bg[1] == 0.2 && bg[2] == 0.3);
    const bsp_camera *cam = bsp_scene_camera(s);
    REQUIRE(cam != NULL);
    CHECK(cam->from.x == 0 && cam->from.y == 0 && cam->from.z == -5);
    CHECK(cam->up.y == 1);
    CHECK(cam->angle_deg == 45 && cam->hither == 0.01);
    CHECK(cam->res_x == 64 && cam->res_y == 48);
    CHECK_EQ_INT(bsp_scene_light_count(s), 1);
    CHECK_EQ_INT(bsp_scene_material_count(s), 1);
    const bsp_material *m = bsp_scene_material(s, 0);
    CHECK(m->color[0] == 1 && m->color[1] == 0 && m->kd == 0.5 && m->ks == 0.5 && m->shine == 10 &&
          m->t == 0 && m->ior == 1);
    CHECK_EQ_INT(bsp_scene_prim_count(s), 2);
    CHECK_EQ_INT(bsp_scene_prim_kind(s, 0), BSP_PRIM_SPHERE);
    CHECK_EQ_INT(bsp_scene_prim_kind(s, 1), BSP_PRIM_POLYGON);
    bsp_box b = bsp_scene_prim_bounds(s, 0);
    CHECK(b.lo.x <= -1 && b.hi.x >= 1 && b.hi.x < 1.01); /* radius 1 came after a comment */
    CHECK_EQ_INT(bsp_scene_warning_count(s), 0);
    bsp_scene_destroy(s);

    s = load_ok(GOOD_DIR "/comments_only.nff");
    CHECK_EQ_INT(bsp_scene_prim_count(s), 0);
    CHECK(bsp_scene_camera(s) == NULL);
    bsp_scene_destroy(s);

    s = load_ok(GOOD_DIR "/empty.nff");
    CHECK_EQ_INT(bsp_scene_prim_count(s), 0);
    CHECK_EQ_INT(bsp_scene_light_count(s), 0);
    CHECK(bsp_scene_camera(s) == NULL);
    bsp_scene_destroy(s);

    s = load_mem_ok(NULL, 0, "nothing"); /* an empty buffer is an empty scene too */
    CHECK_EQ_INT(bsp_scene_prim_count(s), 0);
    bsp_scene_destroy(s);

    s = load_ok(GOOD_DIR "/crlf.nff");
    cam = bsp_scene_camera(s);
    REQUIRE(cam != NULL);
    CHECK(cam->angle_deg == 30 && cam->res_x == 32 && cam->res_y == 16);
    CHECK_EQ_INT(bsp_scene_kind_count(s, BSP_PRIM_SPHERE), 1);
    CHECK_EQ_INT(bsp_scene_kind_count(s, BSP_PRIM_POLYGON), 1);
    bsp_scene_destroy(s);
}

TEST(nff_good_cone_layouts)
{
    bsp_scene *s = load_ok(GOOD_DIR "/cones.nff");
    REQUIRE(bsp_scene_prim_count(s) == 5);
    CHECK_EQ_INT(bsp_scene_kind_count(s, BSP_PRIM_CONE), 5);
    /* one line, three lines and an odd split of the same numbers */
    bsp_box a = bsp_scene_prim_bounds(s, 0), b = bsp_scene_prim_bounds(s, 1),
            c = bsp_scene_prim_bounds(s, 2);
    CHECK(same_vec(a.lo, b.lo) && same_vec(a.hi, b.hi));
    CHECK(same_vec(a.lo, c.lo) && same_vec(a.hi, c.hi));
    CHECK(a.lo.z == 0 && a.hi.z == 2);
    bsp_box cyl = bsp_scene_prim_bounds(s, 3);
    CHECK_NEAR(cyl.lo.x, 2.75, 1e-12);
    CHECK_NEAR(cyl.hi.z, 1, 1e-12);
    CHECK(!(bsp_scene_prim_bounds(s, 4).lo.x > bsp_scene_prim_bounds(s, 4).hi.x));
    bsp_scene_destroy(s);
}

TEST(nff_good_lights_with_and_without_colour)
{
    bsp_scene *s = load_ok(GOOD_DIR "/lights.nff");
    REQUIRE(bsp_scene_light_count(s) == 4);
    const bsp_light *l0 = bsp_scene_light(s, 0), *l1 = bsp_scene_light(s, 1),
                    *l2 = bsp_scene_light(s, 2), *l3 = bsp_scene_light(s, 3);
    CHECK(l0->pos.x == 1 && l0->pos.y == 2 && l0->pos.z == 3);
    CHECK(!l0->has_color && l0->color[0] == 1 && l0->color[1] == 1 && l0->color[2] == 1);
    CHECK(l1->has_color && l1->color[0] == 0.5 && l1->color[1] == 0.25 && l1->color[2] == 0);
    CHECK(l1->pos.z == 6);
    CHECK(l2->has_color && l2->color[0] == 1 && l2->color[1] == 0.5 && l2->color[2] == 0.125);
    CHECK(l3->pos.x == -1 && !l3->has_color && l3->color[2] == 1);
    CHECK_EQ_INT(bsp_scene_prim_count(s), 1);
    bsp_scene_destroy(s);

    s = load_ok(GOOD_DIR "/lights_colour_at_eof.nff");
    REQUIRE(bsp_scene_light_count(s) == 1);
    CHECK(bsp_scene_light(s, 0)->has_color && bsp_scene_light(s, 0)->color[2] == 0.3);
    bsp_scene_destroy(s);
}

TEST(nff_good_number_syntax)
{
    bsp_scene *s = load_ok(GOOD_DIR "/numbers.nff");
    REQUIRE(bsp_scene_light_count(s) == 5);
    const bsp_light *l = bsp_scene_light(s, 0);
    CHECK(l->pos.x == 0 && signbit(l->pos.x) && !signbit(l->pos.y) && signbit(l->pos.z));
    l = bsp_scene_light(s, 1);
    CHECK(l->pos.x == 1000 && l->pos.y == -0.025 && l->pos.z == 4);
    l = bsp_scene_light(s, 2);
    CHECK(l->pos.x == 4.44089e-16 && l->pos.y == -2.55836e-17 && l->pos.z == 100);
    CHECK(l->has_color && l->color[0] == 0 && l->color[1] == 5 && l->color[2] == 0.25);
    l = bsp_scene_light(s, 3);
    CHECK(l->pos.x == 5 && l->pos.y == 0.000001 && l->pos.z == 123456789012345678901234567890.0);
    l = bsp_scene_light(s, 4);
    CHECK(l->color[0] == 1.7976931348623157e308 && l->color[1] == 2.2250738585072014e-308 &&
          l->color[2] == 4.9e-324);
    CHECK_EQ_INT(bsp_scene_kind_count(s, BSP_PRIM_SPHERE), 1);
    bsp_scene_destroy(s);
}

TEST(nff_good_material_order_and_view_last)
{
    bsp_scene *s = load_ok(GOOD_DIR "/order.nff");
    REQUIRE(bsp_scene_prim_count(s) == 4);
    CHECK_EQ_INT(bsp_scene_material_count(s), 3);
    CHECK_EQ_INT(bsp_scene_prim_material(s, 0), 0); /* the default, before any f */
    CHECK_EQ_INT(bsp_scene_prim_material(s, 1), 1);
    CHECK_EQ_INT(bsp_scene_prim_material(s, 2), 2);
    CHECK_EQ_INT(bsp_scene_prim_material(s, 3), 2);
    CHECK_EQ_INT(bsp_scene_prim_kind(s, 3), BSP_PRIM_PATCH);
    const bsp_material *m = bsp_scene_material(s, 2);
    CHECK(m->color[1] == 1 && m->ks == 0.5 && m->shine == 20 && m->t == 0.5 && m->ior == 1.5);
    const bsp_camera *cam = bsp_scene_camera(s);
    REQUIRE(cam);
    CHECK(cam->hither == 0 && cam->res_x == 16);
    double bg[3];
    bsp_scene_background(s, bg);
    CHECK(bg[2] == 0.5);
    CHECK_EQ_INT(bsp_scene_light_count(s), 1);
    bsp_scene_destroy(s);
}

/* The warning that mentions WORD; fails unless exactly one does. */
static const char *warning_with(const bsp_scene *s, const char *word)
{
    const char *found = NULL;
    int n = 0;
    for (size_t i = 0; i < bsp_scene_warning_count(s); i++)
        if (strstr(bsp_scene_warning(s, i), word)) {
            found = bsp_scene_warning(s, i);
            n++;
        }
    CHECK_MSG(n == 1, "%d warnings mention '%s'", n, word);
    return found;
}

TEST(nff_good_degenerate_primitives_dropped)
{
    const char *path = GOOD_DIR "/degenerate.nff";
    bsp_scene *s = load_ok(path);
    REQUIRE(bsp_scene_prim_count(s) == 10); /* every record keeps its index */
    static const int dropped[10] = {0, 1, 1, 1, 1, 1, 1, 1, 0, 1};
    for (size_t i = 0; i < 10; i++)
        CHECK_MSG((bsp_scene_prim_kind(s, i) == BSP_PRIM_DROPPED) == dropped[i],
                  "prim %zu has kind %s", i, bsp_prim_kind_name(bsp_scene_prim_kind(s, i)));
    CHECK_EQ_INT(bsp_scene_prim_kind(s, 0), BSP_PRIM_SPHERE);
    CHECK_EQ_INT(bsp_scene_prim_kind(s, 8), BSP_PRIM_POLYGON);
    CHECK_EQ_INT(bsp_scene_kind_count(s, BSP_PRIM_DROPPED), 8);
    CHECK_EQ_INT(bsp_scene_kind_count(s, BSP_PRIM_SPHERE), 1);
    CHECK_EQ_INT(bsp_scene_kind_count(s, BSP_PRIM_POLYGON), 1);
    CHECK_EQ_INT(bsp_scene_warning_count(s), 4); /* one per kind */
    char where[256];
    snprintf(where, sizeof where, "%s:3:", path);
    CHECK_STR_CONTAINS(warning_with(s, "sphere"), where);
    CHECK_STR_CONTAINS(warning_with(s, "sphere"), "dropped 2 ");
    snprintf(where, sizeof where, "%s:4:", path);
    CHECK_STR_CONTAINS(warning_with(s, "degenerate polygons"), where);
    CHECK_STR_CONTAINS(warning_with(s, "degenerate polygons"), "dropped 3 ");
    snprintf(where, sizeof where, "%s:12:", path);
    CHECK_STR_CONTAINS(warning_with(s, "cone"), where);
    CHECK_STR_CONTAINS(warning_with(s, "cone"), "dropped 2 ");
    snprintf(where, sizeof where, "%s:14:", path);
    CHECK_STR_CONTAINS(warning_with(s, "patch"), where);
    CHECK_STR_CONTAINS(warning_with(s, "patch"), "dropped 1 ");
    bsp_scene_destroy(s);
}

/* --- numbers read bit for bit like strtod -------------------------------------- */

static uint64_t rng_state = 0x9e3779b97f4a7c15u;

static uint64_t rng(void)
{
    return harness_xorshift64(&rng_state);
}

/* A random decimal token (finite, possibly negative when SIGNED) into BUF. */
static void random_number(char *buf, size_t size, int allow_negative)
{
    double mag = ldexp((double)(rng() >> 11), -53) * pow(10.0, (double)(rng() % 40) - 20.0);
    double v = allow_negative && (rng() & 1) ? -mag : mag;
    switch (rng() % 6) {
    case 0:
        snprintf(buf, size, "%g", v);
        break;
    case 1:
        snprintf(buf, size, "%.17g", v);
        break;
    case 2:
        snprintf(buf, size, "%.3e", v);
        break;
    case 3:
        snprintf(buf, size, "%.12f", v);
        break;
    case 4: { /* raw digits with a point and an exponent somewhere */
        size_t n = 1 + rng() % 24, i = 0, point = rng() % (n + 1);
        if (allow_negative && (rng() & 1))
            buf[i++] = '-';
        for (size_t k = 0; k < n && i + 12 < size; k++) {
            if (k == point)
                buf[i++] = '.';
            buf[i++] = (char)('0' + rng() % 10);
        }
        if (rng() & 1)
            i += (size_t)snprintf(buf + i, size - i, "e%d", (int)(rng() % 60) - 30);
        buf[i] = '\0';
        break;
    }
    default:
        snprintf(buf, size, "%.*g", (int)(1 + rng() % 17), v);
        break;
    }
}

TEST(nff_numbers_match_strtod_bit_for_bit)
{
    enum { LIGHTS = 4000 };
    size_t cap = (size_t)LIGHTS * 7 * 40 + 64, len = 0;
    char *text = malloc(cap);
    double *want = malloc(sizeof(double) * LIGHTS * 6);
    REQUIRE(text && want);
    for (int i = 0; i < LIGHTS; i++) {
        len += (size_t)snprintf(text + len, cap - len, "l");
        for (int k = 0; k < 6; k++) {
            char num[64];
            do /* a position must lie within BSP_SCENE_MAX_COORD; a colour may be larger */
                random_number(num, sizeof num, k < 3);
            while (k < 3 && fabs(strtod(num, NULL)) > BSP_SCENE_MAX_COORD);
            want[i * 6 + k] = strtod(num, NULL);
            len += (size_t)snprintf(text + len, cap - len, " %s", num);
        }
        len += (size_t)snprintf(text + len, cap - len, "\n");
    }
    bsp_scene *s = load_mem_ok(text, len, "random-numbers");
    REQUIRE(bsp_scene_light_count(s) == LIGHTS);
    int bad = 0;
    for (int i = 0; i < LIGHTS; i++) {
        const bsp_light *l = bsp_scene_light(s, (size_t)i);
        double got[6] = {l->pos.x, l->pos.y, l->pos.z, l->color[0], l->color[1], l->color[2]};
        for (int k = 0; k < 6; k++)
            if (!same_double(got[k], want[i * 6 + k]) && bad++ < 5)
                CHECK_MSG(0, "light %d value %d: %.17g, strtod %.17g", i, k, got[k],
                          want[i * 6 + k]);
    }
    CHECK_EQ_INT(bad, 0);
    bsp_scene_destroy(s);
    free(text);
    free(want);

    /* a token longer than any internal buffer: 1 with 300 zeros, e-300 */
    char longnum[400];
    char rec[480];
    memset(longnum, '0', sizeof longnum);
    longnum[0] = '1';
    snprintf(longnum + 301, sizeof longnum - 301, "e-300");
    snprintf(rec, sizeof rec, "l 0 0 %s", longnum);
    s = load_mem_ok(rec, strlen(rec), "long-number");
    CHECK(bsp_scene_light(s, 0)->pos.z == 1.0);
    bsp_scene_destroy(s);
}

TEST(nff_many_polygons_reuse_the_vertex_buffer)
{
    enum { N = 20000 };
    size_t cap = (size_t)N * 9 * 64 + 64, len = 0; /* 9 vertices of < 64 bytes */
    char *text = malloc(cap);
    REQUIRE(text);
    for (int i = 0; i < N; i++) {
        int nv = 3 + i % 7;
        len += (size_t)snprintf(text + len, cap - len, "%s %d\n", i % 2 ? "pp" : "p", nv);
        for (int k = 0; k < nv; k++) {
            double a = 6.283185307179586 * k / nv;
            len += (size_t)snprintf(text + len, cap - len, "%g %g %d", cos(a), sin(a), i);
            len += (size_t)snprintf(text + len, cap - len, i % 2 ? " 0 0 1\n" : "\n");
        }
    }
    bsp_scene *s = load_mem_ok(text, len, "polygons");
    CHECK_EQ_INT(bsp_scene_prim_count(s), N);
    CHECK_EQ_INT(bsp_scene_kind_count(s, BSP_PRIM_POLYGON), N / 2);
    CHECK_EQ_INT(bsp_scene_kind_count(s, BSP_PRIM_PATCH), N / 2);
    int bad = 0;
    for (int i = 0; i < N; i++)
        bad += bsp_scene_prim_vertex_count(s, (size_t)i) != (size_t)(3 + i % 7);
    CHECK_EQ_INT(bad, 0);
    bsp_box b = bsp_scene_bounds(s);
    CHECK(b.lo.z == 0 && b.hi.z == N - 1);
    bsp_scene_destroy(s);
    free(text);
}

/* A non-NULL pointer a failed load must overwrite with NULL (never used). */
static char not_null_target;
#define NOT_NULL_SCENE ((bsp_scene *)(void *)&not_null_target)

/* --- malformed input ------------------------------------------------------------ */

typedef struct bad_case {
    const char *file;    /* in tests/data/nff_bad */
    bsp_status status;   /* expected status */
    int line;            /* expected line in "PATH:LINE: ", 0: "PATH: " */
    const char *message; /* expected substring of the message */
} bad_case;

static const bad_case bad_cases[] = {
    /* numbers */
    {"nan.nff", BSP_ERR_INVALID, 1, "non-finite number 'nan'"},
    {"inf.nff", BSP_ERR_INVALID, 3, "non-finite number 'inf'"},
    {"neg_infinity.nff", BSP_ERR_INVALID, 2, "non-finite number '-Infinity'"},
    {"nan_payload.nff", BSP_ERR_INVALID, 1, "non-finite number 'nan(123)'"},
    {"overflow.nff", BSP_ERR_INVALID, 1, "non-finite number '1e999'"},
    {"nan_in_polygon.nff", BSP_ERR_INVALID, 3, "non-finite number 'NaN' in 'p' record"},
    {"nan_in_camera.nff", BSP_ERR_INVALID, 5, "non-finite number 'nan'"},
    /* magnitudes beyond BSP_SCENE_MAX_COORD: the record's first line */
    {"huge_radius.nff", BSP_ERR_INVALID, 2,
     "sphere: 2e+30 is out of range (coordinates and "
     "radii must lie within +-1e+30)"},
    {"huge_polygon.nff", BSP_ERR_INVALID, 1, "polygon: 1e+200 is out of range"},
    {"huge_cone.nff", BSP_ERR_INVALID, 1, "cone: -1e+308 is out of range"},
    {"huge_camera.nff", BSP_ERR_INVALID, 1, "camera: 1e+31 is out of range"},
    {"huge_light.nff", BSP_ERR_INVALID, 1, "light: 1e+40 is out of range"},
    {"malformed_number.nff", BSP_ERR_PARSE, 1, "malformed number '1.2.3' in 's' record"},
    {"hex_number.nff", BSP_ERR_PARSE, 3, "malformed number '0x10'"},
    {"exponent_missing.nff", BSP_ERR_PARSE, 1, "malformed number '1e'"},
    {"lone_sign.nff", BSP_ERR_PARSE, 1, "malformed number '-' in 'b' record"},
    {"crlf_malformed.nff", BSP_ERR_PARSE, 4, "malformed number 'zz'"},
    /* keywords */
    {"unknown_keyword.nff", BSP_ERR_PARSE, 2, "unknown keyword 'sphere'"},
    {"uppercase_keyword.nff", BSP_ERR_PARSE, 1, "unknown keyword 'S'"},
    {"extra_number.nff", BSP_ERR_PARSE, 1, "unexpected number '2'"},
    {"long_token.nff", BSP_ERR_PARSE, 1, "unknown keyword 'aaaaaaaaaaaaaaaaaaaa"},
    {"from_outside_v.nff", BSP_ERR_PARSE, 1, "'from' outside a 'v' block"},
    {"binary_garbage.nff", BSP_ERR_PARSE, 1, "unknown keyword '\\x89PNG'"},
    {"nul_bytes.nff", BSP_ERR_PARSE, 2, "unknown keyword '\\x00\\x00\\x00'"},
    /* truncated records */
    {"missing_number.nff", BSP_ERR_PARSE, 1,
     "truncated 's' record: expected 4 numbers, found 's' on line 2"},
    {"comment_swallows_number.nff", BSP_ERR_PARSE, 1,
     "truncated 's' record: expected 4 numbers, found end of input"},
    {"trunc_s.nff", BSP_ERR_PARSE, 1,
     "truncated 's' record: expected 4 numbers, found end of input"},
    {"trunc_p.nff", BSP_ERR_PARSE, 1,
     "truncated 'p' record: expected 12 numbers, found 's' on line 6"},
    {"trunc_p_eof.nff", BSP_ERR_PARSE, 1,
     "truncated 'p' record: expected 9 numbers, found end of input"},
    {"p_count_exceeds_input.nff", BSP_ERR_PARSE, 1, "truncated 'p' record: 1000 vertices"},
    {"missing_p_count.nff", BSP_ERR_PARSE, 1,
     "truncated 'p' record: expected a vertex count, found 's'"},
    {"trunc_pp.nff", BSP_ERR_PARSE, 1,
     "truncated 'pp' record: expected 18 numbers, found 's' on line 5"},
    {"pp_count_exceeds_input.nff", BSP_ERR_PARSE, 1, "truncated 'pp' record: 1048576 vertices"},
    {"trunc_c.nff", BSP_ERR_PARSE, 1,
     "truncated 'c' record: expected 8 numbers, found end of input"},
    {"trunc_c_multiline.nff", BSP_ERR_PARSE, 1,
     "truncated 'c' record: expected 8 numbers, found 's' on line 4"},
    {"trunc_f.nff", BSP_ERR_PARSE, 1,
     "truncated 'f' record: expected 8 numbers, found 's' on line 2"},
    {"trunc_l.nff", BSP_ERR_PARSE, 1,
     "truncated 'l' record: expected 3 numbers, found end of input"},
    {"trunc_l_colour.nff", BSP_ERR_PARSE, 1,
     "truncated 'l' record: expected 6 numbers, found 's' on line 2"},
    {"trunc_b.nff", BSP_ERR_PARSE, 1,
     "truncated 'b' record: expected 3 numbers, found 'v' on line 2"},
    /* the v block */
    {"trunc_v.nff", BSP_ERR_PARSE, 1, "truncated 'v' block: expected 'hither', found end of input"},
    {"v_missing_at.nff", BSP_ERR_PARSE, 3, "'v' block: expected 'at', found 'up'"},
    {"v_out_of_order.nff", BSP_ERR_PARSE, 5, "'v' block: expected 'angle', found 'hither'"},
    {"v_short_from.nff", BSP_ERR_PARSE, 2,
     "truncated 'from' line of the 'v' block: expected 3 numbers, found 'at' on line 3"},
    {"v_short_resolution.nff", BSP_ERR_PARSE, 7,
     "truncated 'resolution' line of the 'v' block: expected 2 numbers, found 's' on line 8"},
    {"zero_up.nff", BSP_ERR_INVALID, 2, "'up' is the zero vector"},
    {"up_parallel.nff", BSP_ERR_INVALID, 1, "'up' is parallel to the view direction"},
    {"angle_zero.nff", BSP_ERR_INVALID, 5, "angle 0 is outside (0, 180)"},
    {"angle_180.nff", BSP_ERR_INVALID, 5, "angle 180 is outside (0, 180)"},
    {"resolution_zero.nff", BSP_ERR_INVALID, 7, "resolution 0 x 512 is not positive"},
    {"resolution_negative.nff", BSP_ERR_INVALID, 7, "resolution 512 x -1 is not positive"},
    {"resolution_huge.nff", BSP_ERR_LIMIT, 7, "resolution 99999999999 is out of range"},
    {"resolution_fraction.nff", BSP_ERR_PARSE, 7, "whole number of pixels, found '512.5'"},
    {"resolution_over_limit.nff", BSP_ERR_LIMIT, 1, "exceeds"},
    {"from_equals_at.nff", BSP_ERR_INVALID, 1, "'from' and 'at' are the same point"},
    {"second_v.nff", BSP_ERR_PARSE, 9, "second 'v' block (the first is on line 1)"},
    /* polygon counts */
    {"negative_p_count.nff", BSP_ERR_PARSE, 1, "vertex count must be at least 1, found -3"},
    {"zero_p_count.nff", BSP_ERR_PARSE, 1, "vertex count must be at least 1, found 0"},
    {"absurd_p_count.nff", BSP_ERR_LIMIT, 1, "polygon with 2000000000 vertices"},
    {"p_count_19_digits.nff", BSP_ERR_LIMIT, 1, "vertices"},
    {"fraction_p_count.nff", BSP_ERR_PARSE, 1, "vertex count must be a whole number, found '3.0'"},
    /* values the builder refuses */
    {"negative_material.nff", BSP_ERR_INVALID, 1, "must not be negative"},
    {"negative_material_colour.nff", BSP_ERR_INVALID, 2, "material: negative colour"},
    {"transmissive_without_ior.nff", BSP_ERR_INVALID, 1, "positive index of refraction"},
    {"cone_mixed_sign.nff", BSP_ERR_INVALID, 1, "different signs"},
    {"negative_light_colour.nff", BSP_ERR_INVALID, 1, "light: negative colour"},
    {"negative_background.nff", BSP_ERR_INVALID, 1, "background: negative colour"},
    /* gzip */
    {"corrupt.nff.gz", BSP_ERR_PARSE, 0, "corrupt gzip data"},
    {"truncated.nff.gz", BSP_ERR_PARSE, 0, "corrupt gzip data"},
    {"not_gzip.nff.gz", BSP_ERR_PARSE, 0, "corrupt gzip data"},
    {"gzip_bad_content.nff.gz", BSP_ERR_INVALID, 2, "non-finite number 'nan'"},
};

/* Checks one failed load against its case. */
static void check_failure(const bad_case *c, const char *path, const char *via, bsp_status st,
                          const bsp_scene *out, const bsp_error *err)
{
    CHECK_MSG(out == NULL, "%s (%s): *out is not NULL after a failure", c->file, via);
    CHECK_MSG(st == c->status, "%s (%s): status %s, expected %s: %s", c->file, via,
              bsp_status_name(st), bsp_status_name(c->status), err->message);
    CHECK_MSG(err->status == st, "%s (%s): err.status %d != returned %d", c->file, via,
              (int)err->status, (int)st);
    char prefix[1100];
    if (c->line > 0)
        snprintf(prefix, sizeof prefix, "%s:%d: ", path, c->line);
    else
        snprintf(prefix, sizeof prefix, "%s: ", path);
    CHECK_MSG(strncmp(err->message, prefix, strlen(prefix)) == 0,
              "%s (%s): message '%s' does not start with '%s'", c->file, via, err->message, prefix);
    CHECK_MSG(strstr(err->message, c->message) != NULL,
              "%s (%s): message '%s' does not contain '%s'", c->file, via, err->message,
              c->message);
}

TEST(nff_bad_corpus)
{
    size_t ncases = sizeof bad_cases / sizeof bad_cases[0];
    CHECK(ncases >= 24);
    for (size_t i = 0; i < ncases; i++) {
        const bad_case *c = &bad_cases[i];
        char path[512];
        snprintf(path, sizeof path, BAD_DIR "/%s", c->file);
        for (size_t j = 0; j < i; j++)
            CHECK_MSG(strcmp(bad_cases[j].file, c->file) != 0, "%s is listed twice", c->file);

        bsp_scene *out = NOT_NULL_SCENE;
        bsp_error err;
        memset(&err, 0, sizeof err);
        bsp_status st = bsp_scene_load(path, &out, &err);
        check_failure(c, path, "file", st, out, &err);
        if (st == BSP_OK)
            bsp_scene_destroy(out);

        size_t len = 0;
        char *buf = (char *)harness_read_file(path, &len);
        CHECK_MSG(buf != NULL, "cannot read %s", path);
        if (!buf)
            continue;
        out = NOT_NULL_SCENE;
        memset(&err, 0, sizeof err);
        st = bsp_scene_load_nff_memory(buf, len, path, &out, &err);
        check_failure(c, path, "memory", st, out, &err);
        if (st == BSP_OK)
            bsp_scene_destroy(out);
        free(buf);
    }

    /* every file of the corpus is in the table */
    DIR *d = opendir(BAD_DIR);
    REQUIRE(d != NULL);
    struct dirent *e;
    size_t files = 0;
    while ((e = readdir(d)) != NULL) {
        if (e->d_name[0] == '.')
            continue;
        files++;
        int found = 0;
        for (size_t i = 0; i < ncases; i++)
            found |= strcmp(bad_cases[i].file, e->d_name) == 0;
        CHECK_MSG(found, "%s/%s has no entry in bad_cases", BAD_DIR, e->d_name);
    }
    closedir(d);
    CHECK_EQ_INT(files, ncases);
}

/* Every prefix of a valid file either loads or fails cleanly (no crash, no
 * leak under the sanitizers, *out NULL on failure). */
TEST(nff_every_prefix_fails_cleanly)
{
    size_t len = 0;
    char *text = (char *)harness_read_file(GOOD_DIR "/order.nff", &len);
    REQUIRE(text != NULL);
    for (size_t n = 0; n <= len; n++) {
        bsp_scene *out = NULL;
        bsp_error err;
        memset(&err, 0, sizeof err);
        char *copy = malloc(n ? n : 1); /* exactly N bytes: ASan sees any overread */
        REQUIRE(copy);
        memcpy(copy, text, n);
        bsp_status st = bsp_scene_load_nff_memory(copy, n, "prefix", &out, &err);
        free(copy);
        if (st == BSP_OK) {
            CHECK(out != NULL);
            bsp_scene_destroy(out);
        } else {
            CHECK(out == NULL);
            CHECK_STR_CONTAINS(err.message, "prefix:");
        }
    }
    free(text);
}

TEST(nff_io_errors_and_arguments)
{
    bsp_scene *out = NOT_NULL_SCENE;
    bsp_error err;
    memset(&err, 0, sizeof err);
    CHECK_EQ_INT(bsp_scene_load(BAD_DIR "/no-such-file.nff", &out, &err), BSP_ERR_IO);
    CHECK(out == NULL);
    CHECK_STR_CONTAINS(err.message, BAD_DIR "/no-such-file.nff: cannot open: ");
    CHECK_STR_CONTAINS(err.message, "No such file");

    out = NOT_NULL_SCENE;
    CHECK_EQ_INT(bsp_scene_load(BAD_DIR, &out, &err), BSP_ERR_IO);
    CHECK(out == NULL);
    CHECK_STR_CONTAINS(err.message, BAD_DIR ": cannot open: ");

    CHECK_EQ_INT(bsp_scene_load(NULL, &out, &err), BSP_ERR_INVALID);
    CHECK_EQ_INT(bsp_scene_load(GOOD_DIR "/empty.nff", NULL, &err), BSP_ERR_INVALID);
    CHECK_EQ_INT(bsp_scene_load_nff_memory("s 0 0 0 1", 9, "x", NULL, &err), BSP_ERR_INVALID);
    CHECK_EQ_INT(bsp_scene_load_nff_memory(NULL, 5, "x", &out, &err), BSP_ERR_INVALID);
    CHECK(out == NULL);

    /* a NULL error record is allowed */
    CHECK_EQ_INT(bsp_scene_load(BAD_DIR "/nan.nff", &out, NULL), BSP_ERR_INVALID);
    CHECK(out == NULL);

    /* a memory buffer without a name is called "<memory>" */
    CHECK_EQ_INT(bsp_scene_load_nff_memory("s 1 2", 5, NULL, &out, &err), BSP_ERR_PARSE);
    CHECK_STR_CONTAINS(err.message, "<memory>:1: truncated 's' record");

    /* a number cut by the end of a buffer that is not NUL-terminated */
    char exact[] = {'s', ' ', '0', ' ', '0', ' ', '0', ' ', '1', '2', '5'};
    CHECK_EQ_INT(bsp_scene_load_nff_memory(exact, sizeof exact, "exact", &out, &err), BSP_OK);
    if (out) {
        bsp_box b = bsp_scene_prim_bounds(out, 0);
        CHECK(b.hi.x >= 125 && b.hi.x < 125.01);
        bsp_scene_destroy(out);
    }
}

TEST(nff_file_over_2_gib_refused_before_reading)
{
    char path[512];
    snprintf(path, sizeof path, "%s/huge.nff", harness_tmpdir());
    FILE *fp = fopen(path, "wb");
    REQUIRE(fp != NULL);
    int made = ftruncate(fileno(fp), (off_t)((1LL << 31) + 1)) == 0; /* sparse: no disk used */
    fclose(fp);
    if (!made) {
        remove(path);
        harness_skip("cannot make a sparse 2 GiB file in %s", harness_tmpdir());
    }
    bsp_scene *out = NOT_NULL_SCENE;
    bsp_error err;
    memset(&err, 0, sizeof err);
    CHECK_EQ_INT(bsp_scene_load(path, &out, &err), BSP_ERR_LIMIT);
    CHECK(out == NULL);
    CHECK_STR_CONTAINS(err.message, path);
    CHECK_STR_CONTAINS(err.message, "larger than");
    remove(path);
}

TEST(nff_spd_prefix_is_left_to_the_generators)
{
    bsp_scene *out = NULL;
    bsp_error err;
    memset(&err, 0, sizeof err);
    bsp_status st = bsp_scene_load("spd:balls", &out, &err);
    if (st == BSP_OK) { /* the generator module is linked in */
        CHECK(out != NULL);
        bsp_scene_destroy(out);
    } else {
        CHECK(out == NULL);
        CHECK_MSG(st == BSP_ERR_INVALID || st == BSP_ERR_PARSE, "status %s: %s",
                  bsp_status_name(st), err.message);
        CHECK_STR_CONTAINS(err.message, "spd:balls");
        CHECK(strstr(err.message, "cannot open") == NULL); /* not read as a file */
    }
}

/* 'f' numbers above NFF.TXT's ranges (colours 0 to 1, Kd and Ks usually at
 * most 1, T a fraction) are read as given, with one warning per kind naming
 * the first record's line and value; 1 itself is in range. */
TEST(nff_material_ranges_warned)
{
    static const char text[] = "b 0 0 0\n"
                               "f 1 1 1 1 1 10 1 1\n"          /* line 2: all at the limit */
                               "s 0 0 0 1\n"
                               "f 1.5 0.2 0.2 0.5 0.5 3 0 1\n" /* line 4: colour */
                               "s 3 0 0 1\n"
                               "f 0.2 0.2 2.5 0.5 0.5 3 0 1\n" /* line 6: colour again */
                               "s 6 0 0 1\n"
                               "f 0.5 0.5 0.5 0.5 4 3 0 1\n"   /* line 8: Ks */
                               "s 9 0 0 1\n"
                               "f 0.5 0.5 0.5 0.5 0.5 3 3e29 1.5\n" /* line 10: T */
                               "s 12 0 0 1\n";
    bsp_scene *s = load_mem_ok(text, sizeof text - 1, "ranges.nff");
    CHECK_EQ_INT(bsp_scene_warning_count(s), 3);
    const char *want[3] = {"ranges.nff:4: 2 'f' records with a colour component above 1",
                           "ranges.nff:8: 1 'f' record with Kd or Ks above 1",
                           "ranges.nff:10: 1 'f' record with a transmittance T above 1"};
    const char *value[3] = {"the first has 1.5", "the first has 4", "the first has 3e+29"};
    for (size_t i = 0; i < 3 && i < bsp_scene_warning_count(s); i++) {
        CHECK_STR_CONTAINS(bsp_scene_warning(s, i), want[i]);
        CHECK_STR_CONTAINS(bsp_scene_warning(s, i), value[i]);
    }
    /* read as given */
    REQUIRE(bsp_scene_prim_count(s) == 5);
    CHECK(bsp_scene_material(s, bsp_scene_prim_material(s, 4))->t == 3e29);
    bsp_scene_destroy(s);

    static const char in_range[] = "f 1 0 1 1 0 0 1 1\ns 0 0 0 1\nf 0 0 0 0 0 0 0 0\ns 3 0 0 1\n";
    s = load_mem_ok(in_range, sizeof in_range - 1, "in_range.nff");
    CHECK_EQ_INT(bsp_scene_warning_count(s), 0);
    bsp_scene_destroy(s);
}
