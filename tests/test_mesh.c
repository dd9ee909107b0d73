/*
 * test_mesh.c — the triangle-mesh readers (src/scene/obj.c, ply.c) and the
 * default view of a mesh (bsp_scene_set_default_view).
 *
 * OBJ: every face form with known coordinates, relative indices, line
 * continuation, a quad and a concave pentagon kept as one primitive each,
 * ignored statements and their warnings. PLY: ascii files with extra
 * properties, lists and elements, CRLF headers, type aliases, a face element
 * before the vertex element; binary files in both byte orders with float and
 * double coordinates and uchar/int/uint list types, generated here. The same
 * mesh written as OBJ, ascii PLY and binary PLY loads to identical primitives
 * (bounds and ray hits bit for bit). A corpus of malformed files per format
 * (tests/data/obj/bad_*, tests/data/ply/bad_*, and binary PLY cases built
 * here from their bytes) with the status, location and message each must
 * give, through the file and the memory entry points; every prefix of valid
 * files fails cleanly. The default camera sees the whole bounding box.
 */
#include <dirent.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

#include "bspray/scene.h"
#include "geom/vec.h"
#include "harness.h"
#include "same_util.h"
#include "scene/mesh.h"

#define OBJ_DIR "tests/data/obj"
#define PLY_DIR "tests/data/ply"

/* --- helpers ------------------------------------------------------------------ */

static int write_file(const char *path, const void *buf, size_t len)
{
    FILE *fp = fopen(path, "wb");
    if (!fp)
        return 0;
    int ok = fwrite(buf, 1, len, fp) == len;
    return (fclose(fp) == 0) && ok;
}

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

typedef bsp_status (*mem_loader)(const char *, size_t, const char *, bsp_scene **, bsp_error *);

static bsp_scene *load_mem_ok(mem_loader fn, const char *buf, size_t len, const char *name)
{
    bsp_scene *s = NULL;
    bsp_error err;
    memset(&err, 0, sizeof err);
    bsp_status st = fn(buf, len, name, &s, &err);
    CHECK_MSG(st == BSP_OK, "loading %s from memory: %s: %s", name, bsp_status_name(st),
              err.message);
    REQUIRE(st == BSP_OK && s != NULL);
    return s;
}

/* Checks the kind, vertex count and exact bounds of primitive I. */
static void check_prim(const bsp_scene *s, size_t i, bsp_prim_kind kind, size_t nverts,
                       bsp_vec3 lo, bsp_vec3 hi)
{
    CHECK_MSG(bsp_scene_prim_kind(s, i) == kind, "prim %zu: kind %s, expected %s", i,
              bsp_prim_kind_name(bsp_scene_prim_kind(s, i)), bsp_prim_kind_name(kind));
    CHECK_MSG(bsp_scene_prim_vertex_count(s, i) == nverts, "prim %zu: %zu vertices, expected %zu",
              i, bsp_scene_prim_vertex_count(s, i), nverts);
    bsp_box b = bsp_scene_prim_bounds(s, i);
    CHECK_MSG(same_vec(b.lo, lo) && same_vec(b.hi, hi),
              "prim %zu: bounds (%g %g %g)-(%g %g %g), expected (%g %g %g)-(%g %g %g)", i, b.lo.x,
              b.lo.y, b.lo.z, b.hi.x, b.hi.y, b.hi.z, lo.x, lo.y, lo.z, hi.x, hi.y, hi.z);
}

static bsp_ray ray_down(double x, double y, double z)
{
    bsp_ray r = {bsp_v3(x, y, z), bsp_v3(0, 0, -1), 0.0, INFINITY};
    return r;
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
    return found ? found : "";
}

/* --- OBJ ---------------------------------------------------------------------- */

TEST(mesh_obj_every_face_form)
{
    bsp_scene *s = load_ok(OBJ_DIR "/forms.obj");
    REQUIRE(bsp_scene_prim_count(s) == 5);
    bsp_vec3 lo0 = bsp_v3(0, 0, 0), hi0 = bsp_v3(2, 3, 0);
    bsp_vec3 lo1 = bsp_v3(0, 0, 5), hi1 = bsp_v3(7, 11, 5);
    check_prim(s, 0, BSP_PRIM_POLYGON, 3, lo0, hi0); /* f v */
    check_prim(s, 1, BSP_PRIM_POLYGON, 3, lo1, hi1); /* f v/vt */
    check_prim(s, 2, BSP_PRIM_PATCH, 3, lo0, hi0);   /* f v//vn */
    check_prim(s, 3, BSP_PRIM_PATCH, 3, lo1, hi1);   /* f v/vt/vn */
    check_prim(s, 4, BSP_PRIM_POLYGON, 3, lo0, hi0); /* v/vt and v mixed */
    CHECK_EQ_INT(bsp_scene_kind_count(s, BSP_PRIM_POLYGON), 3);
    CHECK_EQ_INT(bsp_scene_kind_count(s, BSP_PRIM_PATCH), 2);
    CHECK_EQ_INT(bsp_scene_warning_count(s), 0);

    /* prim 3 has normals 1 2 1 at its corners: (0 0 1) (0 0 -1) (0 0 1) */
    bsp_hit hit;
    bsp_ray r = ray_down(6, 0.5, 10); /* near the second corner */
    REQUIRE(bsp_scene_intersect_prim(s, 3, &r, &hit));
    CHECK(hit.t == 5);
    bsp_vec3 g, n;
    bsp_scene_hit_normals(s, &r, &hit, &g, &n);
    CHECK(n.z < 0);
    r = ray_down(0.5, 0.5, 10); /* near the first corner */
    REQUIRE(bsp_scene_intersect_prim(s, 3, &r, &hit));
    bsp_scene_hit_normals(s, &r, &hit, &g, &n);
    CHECK(n.z > 0);
    bsp_scene_destroy(s);
}

TEST(mesh_obj_negative_indices)
{
    bsp_scene *s = load_ok(OBJ_DIR "/negative.obj");
    REQUIRE(bsp_scene_prim_count(s) == 3);
    check_prim(s, 0, BSP_PRIM_POLYGON, 3, bsp_v3(0, 0, 0), bsp_v3(1, 1, 0));
    check_prim(s, 1, BSP_PRIM_PATCH, 3, bsp_v3(0, 0, 4), bsp_v3(1, 1, 4));
    check_prim(s, 2, BSP_PRIM_POLYGON, 3, bsp_v3(0, 0, 0), bsp_v3(1, 1, 4));
    bsp_scene_destroy(s);
}

TEST(mesh_obj_line_continuation)
{
    bsp_scene *s = load_ok(OBJ_DIR "/continuation.obj");
    REQUIRE(bsp_scene_prim_count(s) == 3);
    check_prim(s, 0, BSP_PRIM_POLYGON, 3, bsp_v3(0, 0, 0), bsp_v3(1, 1, 0));
    /* the comment's trailing backslash does not swallow 'v 0 0 9' */
    check_prim(s, 1, BSP_PRIM_POLYGON, 3, bsp_v3(0, 0, 0), bsp_v3(1, 0, 9));
    check_prim(s, 2, BSP_PRIM_POLYGON, 3, bsp_v3(0, 0, 0), bsp_v3(1, 1, 0)); /* '\' at EOF */
    bsp_scene_destroy(s);
}

TEST(mesh_obj_quad_and_concave_pentagon_are_one_primitive_each)
{
    bsp_scene *s = load_ok(OBJ_DIR "/polygons.obj");
    REQUIRE(bsp_scene_prim_count(s) == 3);
    check_prim(s, 0, BSP_PRIM_POLYGON, 4, bsp_v3(0, 0, 0), bsp_v3(4, 4, 0));
    check_prim(s, 1, BSP_PRIM_POLYGON, 5, bsp_v3(0, 0, 1), bsp_v3(4, 4, 1));
    CHECK_EQ_INT(bsp_scene_prim_kind(s, 2), BSP_PRIM_PATCH);
    CHECK_EQ_INT(bsp_scene_prim_vertex_count(s, 2), 6);
    bsp_hit hit;
    bsp_ray r = ray_down(2, 3, 5); /* inside the quad, in the pentagon's notch */
    CHECK(bsp_scene_intersect_prim(s, 0, &r, &hit) && hit.t == 5);
    CHECK(!bsp_scene_intersect_prim(s, 1, &r, &hit));
    r = ray_down(2, 0.5, 5);
    CHECK(bsp_scene_intersect_prim(s, 1, &r, &hit) && hit.t == 4);
    r = ray_down(1, 2, 5); /* in the left lobe */
    CHECK(bsp_scene_intersect_prim(s, 1, &r, &hit) && hit.t == 4);
    r = ray_down(3, 2, 5); /* in the right lobe */
    CHECK(bsp_scene_intersect_prim(s, 1, &r, &hit) && hit.t == 4);
    r = ray_down(0, 0, 5);
    CHECK(bsp_scene_intersect_prim(s, 2, &r, &hit) && hit.t == 3);
    bsp_scene_destroy(s);
}

TEST(mesh_obj_ignored_statements)
{
    const char *path = OBJ_DIR "/ignored.obj";
    bsp_scene *s = load_ok(path);
    CHECK_EQ_INT(bsp_scene_prim_count(s), 1);
    /* g o s usemtl mtllib: silent; l (twice) p vp cstype call: one warning each */
    CHECK_EQ_INT(bsp_scene_warning_count(s), 5);
    char where[256];
    snprintf(where, sizeof where, "%s:12: ignored 2 'l' statements: lines are not surfaces", path);
    CHECK_STR_CONTAINS(warning_with(s, "'l'"), where);
    snprintf(where, sizeof where, "%s:14: ignored 1 'p' statement: points", path);
    CHECK_STR_CONTAINS(warning_with(s, "'p'"), where);
    CHECK_STR_CONTAINS(warning_with(s, "'vp'"), ":15: ");
    CHECK_STR_CONTAINS(warning_with(s, "'cstype'"), "free-form geometry is not supported");
    CHECK_STR_CONTAINS(warning_with(s, "'call'"), "other files are not read");
    bsp_scene_destroy(s);
}

TEST(mesh_obj_empty_and_degenerate)
{
    bsp_scene *s = load_ok(OBJ_DIR "/empty.obj");
    CHECK_EQ_INT(bsp_scene_prim_count(s), 0);
    CHECK(bsp_scene_camera(s) != NULL); /* framed as a unit sphere at the origin */
    CHECK_EQ_INT(bsp_scene_light_count(s), 1);
    bsp_scene_destroy(s);

    s = load_mem_ok(obj_load_memory, NULL, 0, "nothing");
    CHECK_EQ_INT(bsp_scene_prim_count(s), 0);
    bsp_scene_destroy(s);

    const char text[] = "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\n"
                        "f 1 2 3\n"       /* collinear: dropped */
                        "f 1 2 4\n"       /* kept */
                        "f 1 1 4 4\n"     /* zero area: dropped */
                        "f 1//1 2//1 3//1\n"; /* no vn: an error, see the corpus */
    bsp_error err;
    bsp_scene *out = NULL;
    CHECK_EQ_INT(obj_load_memory(text, sizeof text - 1, "degenerate", &out, &err), BSP_ERR_PARSE);
    CHECK(out == NULL);
    CHECK_STR_CONTAINS(err.message, "degenerate:8: normal index '1' in '1//1' is out of range");
    size_t len = strlen(text) - strlen("f 1//1 2//1 3//1\n");
    s = load_mem_ok(obj_load_memory, text, len, "degenerate");
    REQUIRE(bsp_scene_prim_count(s) == 3); /* dropped faces keep their index */
    CHECK_EQ_INT(bsp_scene_prim_kind(s, 0), BSP_PRIM_DROPPED);
    CHECK_EQ_INT(bsp_scene_prim_kind(s, 1), BSP_PRIM_POLYGON);
    CHECK_EQ_INT(bsp_scene_prim_kind(s, 2), BSP_PRIM_DROPPED);
    CHECK_EQ_INT(bsp_scene_warning_count(s), 1);
    CHECK_STR_CONTAINS(warning_with(s, "polygons"), "degenerate:5: dropped 2 degenerate");
    bsp_scene_destroy(s);
}

/* --- PLY ---------------------------------------------------------------------- */

TEST(mesh_ply_ascii_extra_properties_and_elements)
{
    bsp_scene *s = load_ok(PLY_DIR "/extras.ply");
    REQUIRE(bsp_scene_prim_count(s) == 2);
    check_prim(s, 0, BSP_PRIM_POLYGON, 4, bsp_v3(0, 0, 0), bsp_v3(1, 1, 0));
    check_prim(s, 1, BSP_PRIM_POLYGON, 3, bsp_v3(0, 0, 0), bsp_v3(1, 0.5, 2));
    CHECK_EQ_INT(bsp_scene_warning_count(s), 0);
    bsp_scene_destroy(s);

    s = load_ok(PLY_DIR "/alias_crlf.ply");
    REQUIRE(bsp_scene_prim_count(s) == 1);
    check_prim(s, 0, BSP_PRIM_POLYGON, 3, bsp_v3(0, 0, -1), bsp_v3(4, 2.5, 3));
    bsp_scene_destroy(s);

    s = load_ok(PLY_DIR "/points.ply");
    CHECK_EQ_INT(bsp_scene_prim_count(s), 0);
    CHECK_STR_CONTAINS(warning_with(s, "face"), "no element 'face'");
    bsp_scene_destroy(s);
}

/* PLY faces have no line of their own (binary files have no lines): the
 * warning about dropped faces names the file and the first face's index. */
TEST(mesh_ply_degenerate_faces_warning_names_file_and_face)
{
    const char text[] = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\n"
                        "property float y\nproperty float z\nelement face 4\n"
                        "property list uchar int vertex_indices\nend_header\n"
                        "0 0 0\n1 0 0\n2 0 0\n0 1 0\n"
                        "3 0 1 3\n3 0 1 2\n3 0 1 3\n4 0 0 1 1\n";
    bsp_scene *s = load_mem_ok(ply_load_memory, text, sizeof text - 1, "flat.ply");
    REQUIRE(bsp_scene_prim_count(s) == 4);
    CHECK_EQ_INT(bsp_scene_prim_kind(s, 1), BSP_PRIM_DROPPED);
    CHECK_EQ_INT(bsp_scene_prim_kind(s, 3), BSP_PRIM_DROPPED);
    CHECK_EQ_INT(bsp_scene_warning_count(s), 1);
    CHECK_STR_CONTAINS(warning_with(s, "polygons"),
                       "flat.ply: dropped 2 degenerate polygons with zero area (the first is "
                       "primitive 1)");
    bsp_scene_destroy(s);
}

/* A mesh written in every supported form. Coordinates are exact in float. */
static const double mesh_verts[][3] = {
    {0, 0, 0},     {1, 0, 0},      {1, 1, 0},   {0, 1, 0},     {0.5, 0.5, 1.25}, {2, 0, 0},
    {3, 0, 0},     {3, 2, 0},      {2.5, 0.5, 0}, {2, 2, 0},   {-1, -1, -0.5},   {0.125, -3, 7.75},
};
static const int mesh_faces[][6] = {
    /* count, indices */
    {3, 0, 1, 4}, {3, 1, 2, 4},       {3, 2, 3, 4},    {3, 3, 0, 4}, {4, 0, 3, 2, 1},
    {5, 5, 6, 7, 8, 9}, /* concave */ {3, 0, 10, 1},   {3, 0, 1, 0}, /* degenerate */
    {3, 11, 10, 5},
};
#define MESH_NV (sizeof mesh_verts / sizeof mesh_verts[0])
#define MESH_NF (sizeof mesh_faces / sizeof mesh_faces[0])

typedef struct buf {
    char *p;
    size_t len, cap;
} buf;

static void put(buf *b, const void *data, size_t n)
{
    if (b->len + n > b->cap) {
        size_t ncap = b->cap ? b->cap : 1024;
        while (ncap < b->len + n)
            ncap *= 2;
        char *np = realloc(b->p, ncap);
        REQUIRE(np);
        b->p = np;
        b->cap = ncap;
    }
    if (n) /* b->p is still NULL when the first piece is empty */
        memcpy(b->p + b->len, data, n);
    b->len += n;
}

static void putf(buf *b, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

static void putf(buf *b, const char *fmt, ...)
{
    char tmp[512];
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(tmp, sizeof tmp, fmt, ap);
    va_end(ap);
    REQUIRE(n >= 0 && (size_t)n < sizeof tmp);
    put(b, tmp, (size_t)n);
}

/* Appends VALUE as the PLY TYPE ("char" ... "double") in byte order BIG. */
static void put_binary(buf *b, const char *type, double value, int big)
{
    unsigned char bytes[8];
    size_t n;
    uint64_t u;
    if (!strcmp(type, "float")) {
        float f = (float)value;
        uint32_t w;
        memcpy(&w, &f, 4);
        u = w;
        n = 4;
    } else if (!strcmp(type, "double")) {
        memcpy(&u, &value, 8);
        n = 8;
    } else {
        long long i = (long long)value;
        u = (uint64_t)i;
        n = !strcmp(type, "char") || !strcmp(type, "uchar")   ? 1
            : !strcmp(type, "short") || !strcmp(type, "ushort") ? 2
                                                                : 4;
    }
    for (size_t k = 0; k < n; k++) {
        unsigned char byte = (unsigned char)(u >> (8 * k));
        bytes[big ? n - 1 - k : k] = byte;
    }
    put(b, bytes, n);
}

static char *mesh_as_obj(size_t *len)
{
    buf b = {0};
    putf(&b, "# the test mesh\n");
    for (size_t i = 0; i < MESH_NV; i++)
        putf(&b, "v %.17g %.17g %.17g\n", mesh_verts[i][0], mesh_verts[i][1], mesh_verts[i][2]);
    for (size_t f = 0; f < MESH_NF; f++) {
        putf(&b, "f");
        for (int k = 0; k < mesh_faces[f][0]; k++)
            putf(&b, " %d", mesh_faces[f][1 + k] + 1);
        putf(&b, "\n");
    }
    *len = b.len;
    return b.p;
}

/* Options of a generated PLY. */
typedef struct ply_opts {
    const char *format; /* "ascii", "binary_little_endian", "binary_big_endian" */
    const char *coord;  /* "float" or "double" */
    const char *count;  /* list count type */
    const char *index;  /* list index type */
    int extras;         /* extra properties, lists and elements to skip */
} ply_opts;

static char *mesh_as_ply(const ply_opts *o, size_t *len)
{
    buf b = {0};
    int ascii = !strcmp(o->format, "ascii"), big = !strcmp(o->format, "binary_big_endian");
    putf(&b, "ply\nformat %s 1.0\ncomment the test mesh\n", o->format);
    if (o->extras)
        putf(&b, "element camera 1\nproperty float view_px\nproperty list uchar int junk\n");
    putf(&b, "element vertex %zu\n", MESH_NV);
    if (o->extras)
        putf(&b, "property uchar red\n");
    putf(&b, "property %s x\nproperty %s y\n", o->coord, o->coord);
    if (o->extras)
        putf(&b, "property list ushort double weights\nproperty short s\n");
    putf(&b, "property %s z\n", o->coord);
    if (o->extras)
        putf(&b, "property double confidence\n");
    putf(&b, "element face %zu\n", MESH_NF);
    if (o->extras)
        putf(&b, "property int flags\n");
    putf(&b, "property list %s %s vertex_indices\n", o->count, o->index);
    if (o->extras)
        putf(&b, "property list uchar float texcoord\nelement edge 2\nproperty char a\n"
                 "property list uint short b\n");
    putf(&b, "end_header\n");
    if (o->extras) { /* camera */
        if (ascii) {
            putf(&b, "1.5 2 -7 9\n");
        } else {
            put_binary(&b, "float", 1.5, big);
            put_binary(&b, "uchar", 2, big);
            put_binary(&b, "int", -7, big);
            put_binary(&b, "int", 9, big);
        }
    }
    for (size_t i = 0; i < MESH_NV; i++) {
        const double *v = mesh_verts[i];
        if (ascii) {
            if (o->extras)
                putf(&b, "%zu ", i * 20);
            putf(&b, "%.17g %.17g ", v[0], v[1]);
            if (o->extras)
                putf(&b, "%zu%s -3 ", i % 3, i % 3 == 2 ? " 0.25 1e300" : i % 3 ? " -1" : "");
            putf(&b, "%.17g", v[2]);
            if (o->extras)
                putf(&b, " -0.75");
            putf(&b, "\n");
        } else {
            if (o->extras)
                put_binary(&b, "uchar", (double)(i * 20), big);
            put_binary(&b, o->coord, v[0], big);
            put_binary(&b, o->coord, v[1], big);
            if (o->extras) {
                put_binary(&b, "ushort", (double)(i % 3), big);
                for (size_t k = 0; k < i % 3; k++)
                    put_binary(&b, "double", 0.5 * (double)k, big);
                put_binary(&b, "short", -3, big);
            }
            put_binary(&b, o->coord, v[2], big);
            if (o->extras)
                put_binary(&b, "double", -0.75, big);
        }
    }
    for (size_t f = 0; f < MESH_NF; f++) {
        int n = mesh_faces[f][0];
        if (ascii) {
            if (o->extras)
                putf(&b, "%zu ", f);
            putf(&b, "%d", n);
            for (int k = 0; k < n; k++)
                putf(&b, " %d", mesh_faces[f][1 + k]);
            if (o->extras)
                putf(&b, " 2 0.25 0.5");
            putf(&b, "\n");
        } else {
            if (o->extras)
                put_binary(&b, "int", (double)f, big);
            put_binary(&b, o->count, n, big);
            for (int k = 0; k < n; k++)
                put_binary(&b, o->index, mesh_faces[f][1 + k], big);
            if (o->extras) {
                put_binary(&b, "uchar", 2, big);
                put_binary(&b, "float", 0.25, big);
                put_binary(&b, "float", 0.5, big);
            }
        }
    }
    if (o->extras) { /* edges */
        if (ascii) {
            putf(&b, "-1 0\n2 2 3 4\n");
        } else {
            put_binary(&b, "char", -1, big);
            put_binary(&b, "uint", 0, big);
            put_binary(&b, "char", 2, big);
            put_binary(&b, "uint", 2, big);
            put_binary(&b, "short", 3, big);
            put_binary(&b, "short", 4, big);
        }
    }
    *len = b.len;
    return b.p;
}

/* Rays that hit or graze the primitives of the test mesh. */
static bsp_ray test_ray(const bsp_scene *ref, size_t i, int k)
{
    static const double origins[4][3] = {
        {-3.1, -2.7, 4.3}, {4.2, 3.3, -2.9}, {0.6, 0.4, 9.5}, {2.45, 0.55, -6.5}};
    bsp_box b = bsp_scene_prim_bounds(ref, i % MESH_NF);
    bsp_vec3 target = box_is_empty(b) ? bsp_v3(0.5, 0.5, 0)
                                      : v3_scale(v3_add(b.lo, b.hi), 0.5);
    bsp_vec3 o = bsp_v3(origins[k][0], origins[k][1], origins[k][2]);
    bsp_ray r = {o, v3_sub(target, o), 0.0, INFINITY};
    return r;
}

/* Checks that A and B have the same primitives: kinds, vertex counts, exact
 * bounds and the same hits (t, u, v bit for bit) on a set of rays. */
static void check_same_prims(const bsp_scene *a, const bsp_scene *b, const char *what)
{
    REQUIRE(a && b);
    CHECK_MSG(bsp_scene_prim_count(a) == bsp_scene_prim_count(b), "%s: %zu vs %zu primitives",
              what, bsp_scene_prim_count(a), bsp_scene_prim_count(b));
    size_t n = bsp_scene_prim_count(a) < bsp_scene_prim_count(b) ? bsp_scene_prim_count(a)
                                                                  : bsp_scene_prim_count(b);
    size_t bad = 0, hits = 0;
    for (size_t i = 0; i < n; i++) {
        bsp_box x = bsp_scene_prim_bounds(a, i), y = bsp_scene_prim_bounds(b, i);
        if (bsp_scene_prim_kind(a, i) != bsp_scene_prim_kind(b, i) ||
            bsp_scene_prim_vertex_count(a, i) != bsp_scene_prim_vertex_count(b, i) ||
            !same_vec(x.lo, y.lo) || !same_vec(x.hi, y.hi)) {
            CHECK_MSG(0, "%s: primitive %zu differs", what, i);
            bad++;
        }
        for (size_t j = 0; j < n; j++)
            for (int k = 0; k < 4; k++) {
                bsp_ray r = test_ray(a, j, k);
                bsp_hit ha, hb;
                int ka = bsp_scene_intersect_prim(a, i, &r, &ha);
                int kb = bsp_scene_intersect_prim(b, i, &r, &hb);
                if (ka != kb || (ka && (!same_double(ha.t, hb.t) || !same_double(ha.u, hb.u) ||
                                        !same_double(ha.v, hb.v) || ha.prim != hb.prim))) {
                    if (bad++ < 5)
                        CHECK_MSG(0, "%s: ray %zu/%d on primitive %zu: %d %.17g vs %d %.17g",
                                  what, j, k, i, ka, ka ? ha.t : 0, kb, kb ? hb.t : 0);
                }
                hits += (size_t)ka;
            }
    }
    CHECK_EQ_INT(bad, 0);
    CHECK_MSG(hits >= n, "%s: only %zu hits: the rays test too little", what, hits);
    bsp_box xa = bsp_scene_bounds(a), xb = bsp_scene_bounds(b);
    CHECK(same_vec(xa.lo, xb.lo) && same_vec(xa.hi, xb.hi));
    CHECK_EQ_INT(bsp_scene_kind_count(a, BSP_PRIM_DROPPED), bsp_scene_kind_count(b, BSP_PRIM_DROPPED));
}

/* The test mesh as an OBJ file FILE in the test directory, loaded; its text
 * in *TEXT (free with free()) and *LEN when TEXT is not NULL. */
static bsp_scene *load_mesh_obj(const char *file, char **text, size_t *len)
{
    char path[1024];
    size_t n;
    char *obj = mesh_as_obj(&n);
    snprintf(path, sizeof path, "%s/%s", harness_tmpdir(), file);
    REQUIRE(write_file(path, obj, n));
    bsp_scene *s = load_ok(path);
    if (text) {
        *text = obj;
        *len = n;
    } else {
        free(obj);
    }
    return s;
}

TEST(mesh_same_mesh_in_every_format_loads_identically)
{
    char path[1024];
    size_t len;
    char *text;
    bsp_scene *ref = load_mesh_obj("mesh.obj", NULL, NULL);
    REQUIRE(bsp_scene_prim_count(ref) == MESH_NF);
    CHECK_EQ_INT(bsp_scene_kind_count(ref, BSP_PRIM_DROPPED), 1);
    CHECK_EQ_INT(bsp_scene_prim_kind(ref, 7), BSP_PRIM_DROPPED);
    CHECK_EQ_INT(bsp_scene_prim_vertex_count(ref, 4), 4);
    CHECK_EQ_INT(bsp_scene_prim_vertex_count(ref, 5), 5);

    static const ply_opts variants[] = {
        {"ascii", "float", "uchar", "int", 0},
        {"ascii", "double", "int", "uint", 1},
        {"binary_little_endian", "float", "uchar", "int", 0},
        {"binary_little_endian", "double", "int", "uint", 1},
        {"binary_little_endian", "float", "uint", "uchar", 1},
        {"binary_big_endian", "float", "uchar", "int", 0},
        {"binary_big_endian", "double", "uint", "int", 1},
        {"binary_big_endian", "float", "int", "ushort", 1},
        {"binary_big_endian", "double", "char", "short", 1},
    };
    for (size_t v = 0; v < sizeof variants / sizeof variants[0]; v++) {
        const ply_opts *o = &variants[v];
        char what[256];
        snprintf(what, sizeof what, "%s %s %s/%s%s", o->format, o->coord, o->count, o->index,
                 o->extras ? " with extras" : "");
        text = mesh_as_ply(o, &len);
        snprintf(path, sizeof path, "%s/mesh%zu.ply", harness_tmpdir(), v);
        REQUIRE(write_file(path, text, len));
        bsp_scene *s = load_ok(path);
        check_same_prims(ref, s, what);
        CHECK_MSG(bsp_scene_warning_count(s) == bsp_scene_warning_count(ref), "%s: %zu warnings",
                  what, bsp_scene_warning_count(s));
        const bsp_camera *ca = bsp_scene_camera(ref), *cb = bsp_scene_camera(s);
        REQUIRE(ca && cb);
        CHECK(same_vec(ca->from, cb->from) && same_vec(ca->at, cb->at));
        bsp_scene_destroy(s);
        s = load_mem_ok(ply_load_memory, text, len, what);
        check_same_prims(ref, s, what);
        bsp_scene_destroy(s);
        free(text);
    }
    bsp_scene_destroy(ref);
}

TEST(mesh_extension_dispatch_ignores_case)
{
    char path[1024];
    size_t len;
    char *text = mesh_as_obj(&len);
    snprintf(path, sizeof path, "%s/Mesh.OBJ", harness_tmpdir());
    REQUIRE(write_file(path, text, len));
    free(text);
    bsp_scene *s = load_ok(path);
    CHECK_EQ_INT(bsp_scene_prim_count(s), MESH_NF);
    bsp_scene_destroy(s);

    ply_opts o = {"binary_little_endian", "float", "uchar", "int", 0};
    text = mesh_as_ply(&o, &len);
    snprintf(path, sizeof path, "%s/Mesh.Ply", harness_tmpdir());
    REQUIRE(write_file(path, text, len));
    free(text);
    s = load_ok(path);
    CHECK_EQ_INT(bsp_scene_prim_count(s), MESH_NF);
    bsp_scene_destroy(s);

    /* an NFF file named .obj is read as OBJ (and refused), not as NFF */
    snprintf(path, sizeof path, "%s/sphere.obj", harness_tmpdir());
    REQUIRE(write_file(path, "b 0.1 0.2 0.3\n", 14));
    bsp_scene *out = NULL;
    bsp_error err;
    CHECK_EQ_INT(bsp_scene_load(path, &out, &err), BSP_ERR_PARSE);
    CHECK_STR_CONTAINS(err.message, "sphere.obj:1: unknown statement 'b'");
    CHECK(out == NULL);
    /* "x.obj.nff" is NFF */
    snprintf(path, sizeof path, "%s/x.obj.nff", harness_tmpdir());
    REQUIRE(write_file(path, "s 0 0 0 1\n", 10));
    s = load_ok(path);
    CHECK_EQ_INT(bsp_scene_kind_count(s, BSP_PRIM_SPHERE), 1);
    bsp_scene_destroy(s);
}

/* Writes LEN bytes of BUF gzip-compressed to PATH. */
static int write_gzip_file(const char *path, const char *data, size_t len)
{
    gzFile gz = gzopen(path, "wb");
    if (!gz)
        return 0;
    int ok = gzwrite(gz, data, (unsigned)len) == (int)len;
    return gzclose(gz) == Z_OK && ok;
}

/* Gzip-compressed meshes (.obj.gz, .ply.gz, any case; and a gzip buffer in
 * memory) load as the plain files do, primitive for primitive; a truncated
 * one is refused as corrupt, naming the file, and leaves no scene. */
TEST(mesh_gzip_input_loads_as_the_plain_file)
{
    char path[1024];
    size_t len;
    char *text;
    bsp_scene *ref = load_mesh_obj("gz.obj", &text, &len);
    snprintf(path, sizeof path, "%s/gz.OBJ.GZ", harness_tmpdir());
    REQUIRE(write_gzip_file(path, text, len));
    bsp_scene *s = load_ok(path);
    check_same_prims(ref, s, "obj.gz");
    bsp_scene_destroy(s);
    free(text);

    ply_opts o = {"binary_big_endian", "double", "uint", "int", 1};
    text = mesh_as_ply(&o, &len);
    snprintf(path, sizeof path, "%s/gz.ply.gz", harness_tmpdir());
    REQUIRE(write_gzip_file(path, text, len));
    s = load_ok(path);
    check_same_prims(ref, s, "ply.gz");
    bsp_scene_destroy(s);

    /* the compressed bytes in memory */
    size_t zlen = 0;
    char *z = (char *)harness_read_file(path, &zlen);
    REQUIRE(z && zlen > 20);
    s = load_mem_ok(ply_load_memory, z, zlen, "gz in memory");
    check_same_prims(ref, s, "ply.gz in memory");
    bsp_scene_destroy(s);

    /* cut short: refused, with the file's name */
    snprintf(path, sizeof path, "%s/cut.ply.gz", harness_tmpdir());
    REQUIRE(write_file(path, z, zlen / 2));
    bsp_scene *out = NULL;
    bsp_error err;
    CHECK_EQ_INT(bsp_scene_load(path, &out, &err), BSP_ERR_PARSE);
    CHECK_STR_CONTAINS(err.message, "cut.ply.gz: corrupt gzip data");
    CHECK(out == NULL);
    free(z);
    free(text);
    bsp_scene_destroy(ref);
}

/* A grid of N x N squares, each split into two triangles. */
TEST(mesh_many_faces_obj_and_binary_ply)
{
    enum { N = 120 };
    buf o = {0}, p = {0};
    putf(&p, "ply\nformat binary_little_endian 1.0\nelement vertex %d\nproperty float x\n"
             "property float y\nproperty float z\nelement face %d\n"
             "property list uchar uint vertex_indices\nend_header\n",
         (N + 1) * (N + 1), 2 * N * N);
    for (int j = 0; j <= N; j++)
        for (int i = 0; i <= N; i++) {
            double z = (double)((i * 7 + j * 13) % 17) / 16.0;
            putf(&o, "v %d %d %.17g\n", i, j, z);
            put_binary(&p, "float", i, 0);
            put_binary(&p, "float", j, 0);
            put_binary(&p, "float", z, 0);
        }
    for (int j = 0; j < N; j++)
        for (int i = 0; i < N; i++) {
            int a = j * (N + 1) + i, b = a + 1, c = a + N + 1, d = c + 1;
            putf(&o, "f %d %d %d\nf %d %d %d\n", a + 1, b + 1, d + 1, a - (N + 1) * (N + 1),
                 d - (N + 1) * (N + 1), c - (N + 1) * (N + 1)); /* relative indices too */
            int tri[2][3] = {{a, b, d}, {a, d, c}};
            for (int t = 0; t < 2; t++) {
                put_binary(&p, "uchar", 3, 0);
                for (int k = 0; k < 3; k++)
                    put_binary(&p, "uint", tri[t][k], 0);
            }
        }
    bsp_scene *a = load_mem_ok(obj_load_memory, o.p, o.len, "grid.obj");
    bsp_scene *b = load_mem_ok(ply_load_memory, p.p, p.len, "grid.ply");
    CHECK_EQ_INT(bsp_scene_prim_count(a), 2 * N * N);
    CHECK_EQ_INT(bsp_scene_prim_count(b), 2 * N * N);
    CHECK_EQ_INT(bsp_scene_kind_count(a, BSP_PRIM_DROPPED), 0);
    size_t bad = 0;
    for (size_t i = 0; i < bsp_scene_prim_count(a); i++) {
        bsp_box x = bsp_scene_prim_bounds(a, i), y = bsp_scene_prim_bounds(b, i);
        bad += !same_vec(x.lo, y.lo) || !same_vec(x.hi, y.hi);
    }
    CHECK_EQ_INT(bad, 0);
    bsp_box bb = bsp_scene_bounds(a);
    CHECK(bb.lo.x == 0 && bb.hi.x == N && bb.hi.y == N && bb.lo.z == 0 && bb.hi.z == 1);
    bsp_scene_destroy(a);
    bsp_scene_destroy(b);
    free(o.p);
    free(p.p);
}

/* --- malformed input ------------------------------------------------------------ */

/* A non-NULL pointer a failed load must overwrite with NULL (never used). */
static char not_null_target;
#define NOT_NULL_SCENE ((bsp_scene *)(void *)&not_null_target)

typedef struct bad_case {
    const char *file;    /* bad_* in tests/data/obj or tests/data/ply */
    bsp_status status;   /* expected status */
    int line;            /* > 0: the message starts "PATH:LINE: " */
    long offset;         /* line 0: >= 0 "PATH: byte OFFSET: ", < 0 "PATH: " */
    const char *message; /* expected substring of the message */
} bad_case;

static const bad_case obj_bad[] = {
    /* references */
    {"bad_index_zero.obj", BSP_ERR_PARSE, 4, 0, "vertex index '0' in '0' is invalid (indices start at 1"},
    {"bad_index_range.obj", BSP_ERR_PARSE, 4, 0,
     "vertex index '4' in '4' is out of range (3 defined so far)"},
    {"bad_negative_range.obj", BSP_ERR_PARSE, 4, 0,
     "vertex index '-4' in '-4' is out of range (3 defined so far)"},
    {"bad_forward_reference.obj", BSP_ERR_PARSE, 1, 0,
     "vertex index '1' in '1' is out of range (0 defined so far)"},
    {"bad_normal_range.obj", BSP_ERR_PARSE, 5, 0,
     "normal index '2' in '3//2' is out of range (1 defined so far)"},
    {"bad_texture_range.obj", BSP_ERR_PARSE, 5, 0,
     "texture coordinate index '5' in '3/5' is out of range (1 defined so far)"},
    {"bad_absurd_index.obj", BSP_ERR_PARSE, 4, 0,
     "vertex index '99999999999999999999999' in '99999999999999999999999' is out of range"},
    {"bad_ref_four_parts.obj", BSP_ERR_PARSE, 4, 0, "malformed vertex reference '1/1/1/1'"},
    {"bad_ref_trailing_slash.obj", BSP_ERR_PARSE, 4, 0, "malformed vertex reference '1/'"},
    {"bad_ref_letters.obj", BSP_ERR_PARSE, 4, 0, "malformed vertex reference 'a' in 'f'"},
    {"bad_ref_fraction.obj", BSP_ERR_PARSE, 4, 0, "malformed vertex reference '1.0'"},
    /* faces */
    {"bad_two_vertices.obj", BSP_ERR_PARSE, 4, 0, "face with 2 vertices (at least 3 are needed)"},
    {"bad_empty_face.obj", BSP_ERR_PARSE, 4, 0, "face with 0 vertices"},
    {"bad_mixed_normals.obj", BSP_ERR_PARSE, 5, 0,
     "face mixes corners with and without normals: '1//1' (v//vn) and '3' (v)"},
    /* numbers */
    {"bad_malformed_number.obj", BSP_ERR_PARSE, 2, 0, "malformed number '1.2.3' in 'v' statement"},
    {"bad_nan.obj", BSP_ERR_INVALID, 1, 0, "non-finite number 'nan' in 'v' statement"},
    {"bad_inf_normal.obj", BSP_ERR_INVALID, 3, 0, "non-finite number '-inf' in 'vn' statement"},
    {"bad_overflow.obj", BSP_ERR_INVALID, 1, 0, "non-finite number '1e999'"},
    {"bad_hex.obj", BSP_ERR_PARSE, 1, 0, "malformed number '0x10'"},
    {"bad_crlf.obj", BSP_ERR_PARSE, 3, 0, "malformed number 'zz'"},
    {"bad_backslash_mid_line.obj", BSP_ERR_PARSE, 1, 0, "malformed number '\\x5c' in 'v'"},
    /* value counts */
    {"bad_truncated_v.obj", BSP_ERR_PARSE, 1, 0,
     "truncated 'v' statement: expected at least 3 numbers, found 2"},
    {"bad_v_five_numbers.obj", BSP_ERR_PARSE, 1, 0, "'v' statement with 5 numbers"},
    {"bad_v_seven_numbers.obj", BSP_ERR_PARSE, 1, 0, "extra value '7' in 'v' statement (at most 6)"},
    {"bad_vn_extra.obj", BSP_ERR_PARSE, 1, 0, "extra value '0' in 'vn' statement (at most 3)"},
    {"bad_vt_empty.obj", BSP_ERR_PARSE, 1, 0,
     "truncated 'vt' statement: expected at least 1 number, found 0"},
    /* statements */
    {"bad_unknown_statement.obj", BSP_ERR_PARSE, 2, 0, "unknown statement 'foo'"},
    {"bad_uppercase.obj", BSP_ERR_PARSE, 1, 0, "unknown statement 'V'"},
    {"bad_number_statement.obj", BSP_ERR_PARSE, 2, 0,
     "unexpected number '1' where a statement keyword was expected"},
    {"bad_ply_content.obj", BSP_ERR_PARSE, 1, 0, "unknown statement 'ply'"},
    {"bad_binary.obj", BSP_ERR_PARSE, 1, 0, "unknown statement '\\x89PNG'"},
    {"bad_error_after_continuation.obj", BSP_ERR_PARSE, 7, 0, "malformed vertex reference 'x'"},
};

static const bad_case ply_bad[] = {
    /* header */
    {"bad_not_ply.ply", BSP_ERR_PARSE, 1, 0, "not a PLY file: the first line is 'plx'"},
    {"bad_empty.ply", BSP_ERR_PARSE, 1, 0, "not a PLY file: the file is empty"},
    {"bad_format.ply", BSP_ERR_PARSE, 2, 0, "unsupported format 'binary_middle_endian'"},
    {"bad_version.ply", BSP_ERR_PARSE, 2, 0, "unsupported PLY version '2.0'"},
    {"bad_no_format.ply", BSP_ERR_PARSE, 7, 0, "no 'format' line before 'end_header'"},
    {"bad_no_end_header.ply", BSP_ERR_PARSE, 7, 0, "truncated header: no 'end_header' line"},
    {"bad_missing_z.ply", BSP_ERR_PARSE, 3, 0, "element 'vertex' has no property 'z'"},
    {"bad_no_index_list.ply", BSP_ERR_PARSE, 7, 0, "element 'face' has no list 'vertex_indices'"},
    {"bad_x_list.ply", BSP_ERR_PARSE, 4, 0, "property 'x' of element 'vertex' is a list"},
    {"bad_float_indices.ply", BSP_ERR_PARSE, 8, 0,
     "item type 'float': vertex indices must be of an integer type"},
    {"bad_float_count.ply", BSP_ERR_PARSE, 4, 0, "count type 'float': it must be an integer type"},
    {"bad_unknown_type.ply", BSP_ERR_PARSE, 4, 0, "unknown property type 'int64'"},
    {"bad_property_first.ply", BSP_ERR_PARSE, 3, 0, "'property' before any 'element'"},
    {"bad_element_count.ply", BSP_ERR_PARSE, 3, 0,
     "element count must be a whole number, found '-3'"},
    {"bad_unknown_header.ply", BSP_ERR_PARSE, 3, 0, "unknown header line 'elemnt vertex 3'"},
    {"bad_duplicate_property.ply", BSP_ERR_PARSE, 6, 0,
     "duplicate property 'x' in element 'vertex'"},
    {"bad_duplicate_element.ply", BSP_ERR_PARSE, 8, 0,
     "second element 'vertex' (the first is on line 3)"},
    {"bad_face_without_vertex.ply", BSP_ERR_PARSE, 3, 0, "element 'face' but no element 'vertex'"},
    /* sizes */
    {"bad_vertex_limit.ply", BSP_ERR_LIMIT, 3, 0, "element 'vertex' with 999999999999 items"},
    {"bad_face_limit.ply", BSP_ERR_LIMIT, 7, 0,
     "element 'face' with 99999999999999999999 items (the limit is 268435456)"},
    {"bad_ascii_count_exceeds_file.ply", BSP_ERR_PARSE, 3, 0,
     "element 'vertex' declares 3 items of at least 6 bytes each, but only 12 bytes"},
    /* ascii data */
    {"bad_ascii_truncated.ply", BSP_ERR_PARSE, 12, 0,
     "truncated data: face 0, property 'vertex_indices' is missing (end of input)"},
    {"bad_ascii_index_range.ply", BSP_ERR_PARSE, 13, 0,
     "vertex index 3 in face 0 is out of range (3 vertices)"},
    {"bad_ascii_negative_index.ply", BSP_ERR_PARSE, 13, 0,
     "vertex index -1 in face 0 is out of range"},
    {"bad_ascii_nan.ply", BSP_ERR_INVALID, 11, 0,
     "non-finite number 'NaN' in vertex 1, property 'y'"},
    {"bad_ascii_inf.ply", BSP_ERR_INVALID, 12, 0,
     "non-finite number '-inf' in vertex 2, property 'z'"},
    {"bad_ascii_malformed.ply", BSP_ERR_PARSE, 11, 0,
     "malformed number '1.0.0' in vertex 1, property 'x'"},
    {"bad_ascii_two_vertices.ply", BSP_ERR_PARSE, 13, 0, "face 0 has 2 vertices (at least 3"},
    {"bad_ascii_negative_count.ply", BSP_ERR_PARSE, 13, 0,
     "'-1' in face 0, property 'vertex_indices' is out of range of type uchar (0 to 255)"},
    {"bad_ascii_fraction_count.ply", BSP_ERR_PARSE, 13, 0,
     "malformed integer '3.0' in face 0, property 'vertex_indices'"},
    {"bad_ascii_extra_data.ply", BSP_ERR_PARSE, 14, 0, "extra data '3' after the last element"},
    {"bad_ascii_skipped_malformed.ply", BSP_ERR_PARSE, 12, 0,
     "malformed integer 'abc' in vertex 1, property 'red' (type uchar)"},
    /* ascii values must fit their declared type, as binary ones do */
    {"bad_ascii_uchar_negative.ply", BSP_ERR_PARSE, 11, 0,
     "'-5' in vertex 1, property 'x' is out of range of type uchar (0 to 255)"},
    {"bad_ascii_uchar_fraction.ply", BSP_ERR_PARSE, 12, 0,
     "malformed integer '0.5' in vertex 2, property 'x' (type uchar)"},
    {"bad_ascii_list_count_range.ply", BSP_ERR_PARSE, 13, 0,
     "'256' in face 0, property 'vertex_indices' is out of range of type uchar (0 to 255)"},
    {"bad_ascii_float_range.ply", BSP_ERR_PARSE, 11, 0,
     "'1e39' in vertex 1, property 'x' is out of range of type float"},
    {"bad_ascii_huge_coordinate.ply", BSP_ERR_INVALID, 12, 0,
     "'-2e30' in vertex 2, property 'x' is out of range (coordinates must lie within +-1e+30)"},
};

/* Binary PLY cases: the header, the data bytes after it, and the expected
 * byte offset relative to the start of the data (or a header line). */
typedef struct bin_case {
    const char *file;
    const char *header;
    const char *data;
    size_t data_len;
    bsp_status status;
    int line;        /* > 0: a header error on this line */
    long rel_offset; /* else: the offset from the first data byte */
    const char *message;
} bin_case;

#define TRI_LE_HEADER                                                                      \
    "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"          \
    "property float y\nproperty float z\nelement face 1\n"                               \
    "property list uchar int vertex_indices\nend_header\n"
#define TRI_BE_DOUBLE_HEADER                                                               \
    "ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty double x\n"            \
    "property double y\nproperty double z\nelement face 1\n"                             \
    "property list uint uint vertex_indices\nend_header\n"
/* (0 0 0) (1 0 0) (0 1 0) as little-endian floats */
#define TRI_LE_VERTS                                                                       \
    "\0\0\0\0\0\0\0\0\0\0\0\0"                                                             \
    "\0\0\x80\x3f\0\0\0\0\0\0\0\0"                                                         \
    "\0\0\0\0\0\0\x80\x3f\0\0\0\0"
/* the same as big-endian doubles */
#define TRI_BE_VERTS                                                                       \
    "\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0"                                     \
    "\x3f\xf0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0"                                 \
    "\0\0\0\0\0\0\0\0\x3f\xf0\0\0\0\0\0\0\0\0\0\0\0\0\0\0"
#define BIN(s) s, sizeof(s) - 1

static const bin_case bin_bad[] = {
    {"bad_bin_truncated_list.ply", TRI_LE_HEADER, BIN(TRI_LE_VERTS "\x03\x00\x00\x00\x00"),
     BSP_ERR_PARSE, 0, 36,
     "truncated data: list of 3 items in face 0, property 'vertex_indices', but only 4 bytes "
     "remain"},
    {"bad_bin_truncated_scalar.ply",
     "ply\nformat binary_little_endian 1.0\nelement junk 1\nproperty list uchar double w\n"
     "element vertex 3\nproperty float x\nproperty float y\nproperty float z\nend_header\n",
     BIN("\x02\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0"       /* junk: two doubles */
         "\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0"), /* 1 2/3 vertices */
     BSP_ERR_PARSE, 0, 37, "truncated data: vertex 1, property 'z' needs 4 bytes, 0 remain"},
    {"bad_bin_truncated_last_face.ply",
     "ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\n"
     "property float y\nproperty float z\nelement face 3\nproperty list int int "
     "vertex_indices\nend_header\n",
     BIN("\0\0\0\0\0\0\0\0\0\0\0\0"           /* the vertex */
         "\x03\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0" /* face 0 */
         "\x03\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0" /* face 1 */
         "\x03\0\0\0"),                       /* face 2: count only */
     BSP_ERR_PARSE, 0, 44,
     "truncated data: list of 3 items in face 2, property 'vertex_indices', but only 0 bytes"},
    {"bad_bin_count_exceeds_file.ply",
     "ply\nformat binary_little_endian 1.0\nelement vertex 100\nproperty float x\n"
     "property float y\nproperty float z\nend_header\n",
     BIN(TRI_LE_VERTS), BSP_ERR_PARSE, 3, 0,
     "element 'vertex' declares 100 items of at least 12 bytes each, but only 36 bytes"},
    {"bad_bin_index_range.ply", TRI_LE_HEADER, BIN(TRI_LE_VERTS "\x03\0\0\0\0\x07\0\0\0\x02\0\0\0"),
     BSP_ERR_PARSE, 0, 41, "vertex index 7 in face 0 is out of range (3 vertices)"},
    {"bad_bin_index_negative_be.ply", TRI_BE_DOUBLE_HEADER,
     BIN(TRI_BE_VERTS "\0\0\0\x03\0\0\0\0\0\0\0\x01\xff\xff\xff\xff"), BSP_ERR_PARSE, 0, 84,
     "vertex index 4294967295 in face 0 is out of range (3 vertices)"},
    {"bad_bin_index_negative_int.ply",
     "ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty double x\n"
     "property double y\nproperty double z\nelement face 1\n"
     "property list uchar int vertex_indices\nend_header\n",
     BIN(TRI_BE_VERTS "\x03\0\0\0\0\xff\xff\xff\xfe\0\0\0\x01"), BSP_ERR_PARSE, 0, 77,
     "vertex index -2 in face 0 is out of range"},
    {"bad_bin_nan_float.ply", TRI_LE_HEADER,
     BIN("\0\0\0\0\0\0\0\0\0\0\0\0"
         "\0\0\x80\x3f\0\0\xc0\x7f\0\0\0\0"
         "\0\0\0\0\0\0\x80\x3f\0\0\0\0"
         "\x03\0\0\0\0\x01\0\0\0\x02\0\0\0"),
     BSP_ERR_INVALID, 0, 16, "non-finite number (nan) in vertex 1, property 'y'"},
    {"bad_bin_inf_double_be.ply", TRI_BE_DOUBLE_HEADER,
     BIN("\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\xff\xf0\0\0\0\0\0\0"
         "\x3f\xf0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0"
         "\0\0\0\0\0\0\0\0\x3f\xf0\0\0\0\0\0\0\0\0\0\0\0\0\0\0"
         "\0\0\0\x03\0\0\0\0\0\0\0\x01\0\0\0\x02"),
     BSP_ERR_INVALID, 0, 16, "non-finite number (-inf) in vertex 0, property 'z'"},
    {"bad_bin_huge_double_be.ply", TRI_BE_DOUBLE_HEADER,
     BIN("\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0"
         "\x3f\xf0\0\0\0\0\0\0\x69\x74\xe7\x18\xd7\xd7\x62\x5a\0\0\0\0\0\0\0\0"
         "\0\0\0\0\0\0\0\0\x3f\xf0\0\0\0\0\0\0\0\0\0\0\0\0\0\0"
         "\0\0\0\x03\0\0\0\0\0\0\0\x01\0\0\0\x02"),
     BSP_ERR_INVALID, 0, 32,
     "1e+200 in vertex 1, property 'y' is out of range (coordinates must lie within +-1e+30)"},
    {"bad_bin_two_vertices.ply", TRI_LE_HEADER, BIN(TRI_LE_VERTS "\x02\0\0\0\0\x01\0\0\0"),
     BSP_ERR_PARSE, 0, 36, "face 0 has 2 vertices (at least 3 are needed)"},
    {"bad_bin_negative_count.ply",
     "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
     "property float y\nproperty float z\nelement face 1\n"
     "property list char int vertex_indices\nend_header\n",
     BIN(TRI_LE_VERTS "\xff\0\0\0\0\x01\0\0\0\x02\0\0\0"), BSP_ERR_PARSE, 0, 36,
     "negative list count -1 in face 0"},
    {"bad_bin_face_too_large.ply",
     "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
     "property float y\nproperty float z\nelement face 1\n"
     "property list uint int vertex_indices\nend_header\n",
     BIN(TRI_LE_VERTS "\x01\0\x10\0\0\0\0\0\x01\0\0\0\x02\0\0\0"), BSP_ERR_LIMIT, 0, 36,
     "face 0 has 1048577 vertices (the limit is 1048576)"},
    {"bad_bin_skipped_list_overrun.ply",
     "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
     "property float y\nproperty float z\nelement junk 1\nproperty list ushort double "
     "w\nend_header\n",
     BIN(TRI_LE_VERTS "\xff\x00\0\0\0\0\0\0\0\0"), BSP_ERR_PARSE, 0, 36,
     "truncated data: list of 255 items in element 'junk' item 0, property 'w', but only 8 "
     "bytes remain"},
    {"bad_bin_header_only.ply", TRI_LE_HEADER, BIN(""), BSP_ERR_PARSE, 3, 0,
     "element 'vertex' declares 3 items of at least 12 bytes each, but only 0 bytes"},
    {"bad_bin_garbage_header.ply", "ply\nformat binary_little_endian 1.0\n\x01\x02\x03\n",
     BIN("\0\0\0"), BSP_ERR_PARSE, 3, 0, "unknown header line '\\x01\\x02\\x03'"},
};

/* Checks one failed load against its expected status and location. */
static void check_failure(const char *file, const char *path, const char *via, bsp_status want,
                          int line, long offset, const char *message, bsp_status st,
                          const bsp_scene *out, const bsp_error *err)
{
    CHECK_MSG(out == NULL, "%s (%s): *out is not NULL after a failure", file, via);
    CHECK_MSG(st == want, "%s (%s): status %s, expected %s: %s", file, via, bsp_status_name(st),
              bsp_status_name(want), err->message);
    CHECK_MSG(err->status == st, "%s (%s): err.status %d != returned %d", file, via,
              (int)err->status, (int)st);
    char prefix[1100];
    if (line > 0)
        snprintf(prefix, sizeof prefix, "%s:%d: ", path, line);
    else if (offset >= 0)
        snprintf(prefix, sizeof prefix, "%s: byte %ld: ", path, offset);
    else
        snprintf(prefix, sizeof prefix, "%s: ", path);
    CHECK_MSG(strncmp(err->message, prefix, strlen(prefix)) == 0,
              "%s (%s): message '%s' does not start with '%s'", file, via, err->message, prefix);
    CHECK_MSG(strstr(err->message, message) != NULL, "%s (%s): message '%s' does not contain '%s'",
              file, via, err->message, message);
}

/* Loads PATH through the file and the memory entry point; both must fail as
 * expected. */
static void check_bad_file(const char *file, const char *path, mem_loader mem, bsp_status want,
                           int line, long offset, const char *message)
{
    bsp_scene *out = NOT_NULL_SCENE;
    bsp_error err;
    memset(&err, 0, sizeof err);
    bsp_status st = bsp_scene_load(path, &out, &err);
    check_failure(file, path, "file", want, line, offset, message, st, out, &err);
    if (st == BSP_OK)
        bsp_scene_destroy(out);

    size_t len = 0;
    char *text = (char *)harness_read_file(path, &len);
    CHECK_MSG(text != NULL, "cannot read %s", path);
    if (!text)
        return;
    char *exact = malloc(len ? len : 1); /* exactly LEN bytes: ASan sees any overread */
    REQUIRE(exact);
    memcpy(exact, text, len);
    free(text);
    out = NOT_NULL_SCENE;
    memset(&err, 0, sizeof err);
    st = mem(exact, len, path, &out, &err);
    check_failure(file, path, "memory", want, line, offset, message, st, out, &err);
    if (st == BSP_OK)
        bsp_scene_destroy(out);
    free(exact);
}

/* Every bad_* file of DIR is in the table of N cases. */
static void check_corpus_listed(const char *dir, const bad_case *cases, size_t n)
{
    DIR *d = opendir(dir);
    REQUIRE(d != NULL);
    struct dirent *e;
    size_t files = 0;
    while ((e = readdir(d)) != NULL) {
        if (strncmp(e->d_name, "bad_", 4) != 0)
            continue;
        files++;
        int found = 0;
        for (size_t i = 0; i < n; i++)
            found |= strcmp(cases[i].file, e->d_name) == 0;
        CHECK_MSG(found, "%s/%s has no entry in the table", dir, e->d_name);
    }
    closedir(d);
    CHECK_EQ_INT(files, n);
    for (size_t i = 0; i < n; i++)
        for (size_t j = 0; j < i; j++)
            CHECK_MSG(strcmp(cases[i].file, cases[j].file) != 0, "%s is listed twice",
                      cases[i].file);
}

TEST(mesh_obj_bad_corpus)
{
    size_t n = sizeof obj_bad / sizeof obj_bad[0];
    CHECK(n >= 15);
    for (size_t i = 0; i < n; i++) {
        char path[512];
        snprintf(path, sizeof path, OBJ_DIR "/%s", obj_bad[i].file);
        check_bad_file(obj_bad[i].file, path, obj_load_memory, obj_bad[i].status, obj_bad[i].line,
                       obj_bad[i].offset, obj_bad[i].message);
    }
    check_corpus_listed(OBJ_DIR, obj_bad, n);
}

TEST(mesh_ply_bad_corpus)
{
    size_t n = sizeof ply_bad / sizeof ply_bad[0];
    CHECK(n >= 15);
    for (size_t i = 0; i < n; i++) {
        char path[512];
        snprintf(path, sizeof path, PLY_DIR "/%s", ply_bad[i].file);
        check_bad_file(ply_bad[i].file, path, ply_load_memory, ply_bad[i].status, ply_bad[i].line,
                       ply_bad[i].offset, ply_bad[i].message);
    }
    check_corpus_listed(PLY_DIR, ply_bad, n);
}

TEST(mesh_ply_bad_binary_corpus)
{
    size_t n = sizeof bin_bad / sizeof bin_bad[0];
    CHECK(n >= 10);
    for (size_t i = 0; i < n; i++) {
        const bin_case *c = &bin_bad[i];
        buf b = {0};
        size_t hlen = strlen(c->header);
        put(&b, c->header, hlen);
        put(&b, c->data, c->data_len);
        char path[1024];
        snprintf(path, sizeof path, "%s/%s", harness_tmpdir(), c->file);
        REQUIRE(write_file(path, b.p, b.len));
        free(b.p);
        long offset = c->line > 0 ? -1 : (long)hlen + c->rel_offset;
        check_bad_file(c->file, path, ply_load_memory, c->status, c->line, offset, c->message);
    }
}

TEST(mesh_obj_face_with_too_many_vertices)
{
    size_t corners = SCENE_MAX_POLY_VERTS + 1;
    size_t cap = 32 + 2 * corners, len = 0;
    char *text = malloc(cap);
    REQUIRE(text);
    len += (size_t)snprintf(text, cap, "v 0 0 0\nf");
    for (size_t i = 0; i < corners; i++) {
        text[len++] = ' ';
        text[len++] = '1';
    }
    text[len++] = '\n';
    bsp_scene *out = NOT_NULL_SCENE;
    bsp_error err;
    CHECK_EQ_INT(obj_load_memory(text, len, "big", &out, &err), BSP_ERR_LIMIT);
    CHECK(out == NULL);
    CHECK_STR_CONTAINS(err.message, "big:2: face with more than 1048576 vertices");
    free(text);
}

/* Every prefix of a valid file either loads or fails cleanly (no crash, no
 * leak under the sanitizers, *out NULL on failure, a located message). */
static void check_prefixes(mem_loader fn, const char *text, size_t len)
{
    for (size_t n = 0; n <= len; n++) {
        bsp_scene *out = NOT_NULL_SCENE;
        bsp_error err;
        memset(&err, 0, sizeof err);
        char *copy = malloc(n ? n : 1); /* exactly N bytes: ASan sees any overread */
        REQUIRE(copy);
        memcpy(copy, text, n);
        bsp_status st = fn(copy, n, "prefix", &out, &err);
        free(copy);
        if (st == BSP_OK) {
            CHECK(out != NULL && out != NOT_NULL_SCENE);
            if (out && out != NOT_NULL_SCENE)
                bsp_scene_destroy(out);
        } else {
            CHECK(out == NULL);
            CHECK_STR_CONTAINS(err.message, "prefix:");
        }
    }
}

TEST(mesh_every_prefix_fails_cleanly)
{
    const char *files[] = {OBJ_DIR "/forms.obj", OBJ_DIR "/continuation.obj", PLY_DIR "/extras.ply",
                           PLY_DIR "/alias_crlf.ply"};
    for (size_t i = 0; i < sizeof files / sizeof files[0]; i++) {
        size_t len = 0;
        char *text = (char *)harness_read_file(files[i], &len);
        REQUIRE(text != NULL);
        check_prefixes(strstr(files[i], ".obj") ? obj_load_memory : ply_load_memory, text, len);
        free(text);
    }
    static const ply_opts variants[] = {
        {"binary_little_endian", "double", "int", "uint", 1},
        {"binary_big_endian", "float", "uchar", "ushort", 1},
    };
    for (size_t v = 0; v < 2; v++) {
        size_t len;
        char *text = mesh_as_ply(&variants[v], &len);
        check_prefixes(ply_load_memory, text, len);
        free(text);
    }
}

TEST(mesh_io_errors_and_arguments)
{
    bsp_scene *out = NOT_NULL_SCENE;
    bsp_error err;
    CHECK_EQ_INT(bsp_scene_load(OBJ_DIR "/no-such-file.obj", &out, &err), BSP_ERR_IO);
    CHECK(out == NULL);
    CHECK_STR_CONTAINS(err.message, OBJ_DIR "/no-such-file.obj: cannot open: ");
    out = NOT_NULL_SCENE;
    CHECK_EQ_INT(bsp_scene_load(PLY_DIR "/no-such-file.PLY", &out, &err), BSP_ERR_IO);
    CHECK(out == NULL);
    CHECK_STR_CONTAINS(err.message, "no-such-file.PLY: cannot open: ");
    CHECK_EQ_INT(obj_load_memory("v 0 0 0", 7, "x", NULL, &err), BSP_ERR_INVALID);
    CHECK_EQ_INT(ply_load_memory(NULL, 5, "x", &out, &err), BSP_ERR_INVALID);
    CHECK(out == NULL);
    /* a NULL error record is allowed */
    CHECK_EQ_INT(bsp_scene_load(OBJ_DIR "/bad_nan.obj", &out, NULL), BSP_ERR_INVALID);
    CHECK_EQ_INT(bsp_scene_load(PLY_DIR "/bad_ascii_nan.ply", &out, NULL), BSP_ERR_INVALID);
    CHECK(out == NULL);
    /* a number cut by the end of a buffer that is not NUL-terminated */
    const char text[] = "v 0 0 0\nv 1 0 0\nv 0 1 125\nf 1 2 3";
    char *exact = malloc(sizeof text - 1);
    REQUIRE(exact);
    memcpy(exact, text, sizeof text - 1);
    bsp_scene *s = load_mem_ok(obj_load_memory, exact, sizeof text - 1, "exact");
    CHECK_EQ_INT(bsp_scene_prim_count(s), 1);
    CHECK(bsp_scene_bounds(s).hi.z == 125);
    bsp_scene_destroy(s);
    free(exact);
}

/* --- the default view --------------------------------------------------------------- */

/* Checks that the camera of S sees the 8 corners of its bounding box (the
 * angle spans the image horizontally and, the image being square,
 * vertically) and that the view is not much wider than needed. */
static void check_corners_visible(const bsp_scene *s, const char *what, double min_fill)
{
    const bsp_camera *c = bsp_scene_camera(s);
    REQUIRE(c != NULL);
    bsp_box b = bsp_scene_bounds(s);
    REQUIRE(!box_is_empty(b));
    bsp_vec3 fwd = v3_normalize(v3_sub(c->at, c->from));
    bsp_vec3 right = v3_normalize(v3_cross(fwd, c->up));
    bsp_vec3 up = v3_cross(right, fwd);
    double lim = tan(c->angle_deg * BSP_PI / 360.0);
    double widest = 0;
    for (int k = 0; k < 8; k++) {
        bsp_vec3 p = bsp_v3(k & 1 ? b.hi.x : b.lo.x, k & 2 ? b.hi.y : b.lo.y,
                            k & 4 ? b.hi.z : b.lo.z);
        bsp_vec3 d = v3_sub(p, c->from);
        double z = v3_dot(d, fwd);
        CHECK_MSG(z > 0, "%s: corner %d is behind the eye", what, k);
        if (!(z > 0))
            continue;
        double x = v3_dot(d, right) / z, y = v3_dot(d, up) / z;
        CHECK_MSG(fabs(x) <= lim * (1 + 1e-9) && fabs(y) <= lim * (1 + 1e-9),
                  "%s: corner %d projects to (%g, %g), outside +-%g", what, k, x, y, lim);
        widest = fmax(widest, fmax(fabs(x), fabs(y)));
    }
    CHECK_MSG(widest >= min_fill * lim, "%s: the box fills only %g of the half-width %g", what,
              widest, lim);
}

/* The default view of a mesh: 45 degrees, 512 x 512, the light at the eye,
 * the eye on the (1,1,1) diagonal through the centre, framing the bounding
 * sphere exactly. */
static void check_default_view(const bsp_scene *s, const char *what)
{
    const bsp_camera *c = bsp_scene_camera(s);
    REQUIRE(c != NULL);
    CHECK(c->angle_deg == 45 && c->res_x == 512 && c->res_y == 512);
    CHECK(c->up.x == 0 && c->up.y == 0 && c->up.z == 1);
    bsp_box b = bsp_scene_bounds(s);
    bsp_vec3 centre = v3_scale(v3_add(b.lo, b.hi), 0.5);
    double r = 0.5 * v3_length(v3_sub(b.hi, b.lo));
    CHECK_NEAR(c->at.x, centre.x, 1e-12 * (1 + fabs(centre.x)));
    CHECK_NEAR(c->at.y, centre.y, 1e-12 * (1 + fabs(centre.y)));
    CHECK_NEAR(c->at.z, centre.z, 1e-12 * (1 + fabs(centre.z)));
    bsp_vec3 d = v3_sub(c->from, c->at);
    CHECK_NEAR(v3_length(d), r / sin(22.5 * BSP_PI / 180.0), 1e-9 * v3_length(d));
    CHECK_NEAR(d.x, d.y, 1e-9 * v3_length(d));
    CHECK_NEAR(d.y, d.z, 1e-9 * v3_length(d));
    CHECK(d.x > 0);
    REQUIRE(bsp_scene_light_count(s) == 1);
    CHECK(same_vec(bsp_scene_light(s, 0)->pos, c->from));
    REQUIRE(bsp_scene_material_count(s) == 1);
    const bsp_material *m = bsp_scene_material(s, 0);
    CHECK(m->color[0] == 1 && m->color[1] == 1 && m->color[2] == 1 && m->kd > 0.5 && m->ks > 0 &&
          m->ks < 0.5 && m->t == 0);
    check_corners_visible(s, what, 0.5);
}

TEST(mesh_default_camera_sees_the_whole_mesh)
{
    const char *files[] = {OBJ_DIR "/forms.obj", OBJ_DIR "/polygons.obj", PLY_DIR "/extras.ply",
                           PLY_DIR "/alias_crlf.ply"};
    for (size_t i = 0; i < sizeof files / sizeof files[0]; i++) {
        bsp_scene *s = load_ok(files[i]);
        check_default_view(s, files[i]);
        bsp_scene_destroy(s);
    }
    /* long and thin, flat, far from the origin, tiny */
    static const char *const texts[] = {
        "v 0 0 0\nv 1000 0 0\nv 1000 0.5 0.25\nf 1 2 3\n",
        "v -5 -5 3\nv 5 -5 3\nv 5 5 3\nv -5 5 3\nf 1 2 3 4\n",
        "v 1e6 2e6 -3e6\nv 1000001 2e6 -3e6\nv 1e6 2000001 -2999999\nf 1 2 3\n",
        "v 0 0 0\nv 1e-9 0 0\nv 0 0 1e-9\nf 1 2 3\n",
        "v 0 0 0\nv 0 0 10\nv 0 0.001 5\nf 1 2 3\n",
    };
    for (size_t i = 0; i < sizeof texts / sizeof texts[0]; i++) {
        bsp_scene *s = load_mem_ok(obj_load_memory, texts[i], strlen(texts[i]), texts[i]);
        check_default_view(s, texts[i]);
        bsp_scene_destroy(s);
    }
}

TEST(mesh_default_view_overrides)
{
    bsp_scene *s = load_ok(OBJ_DIR "/polygons.obj");
    bsp_error err;
    memset(&err, 0, sizeof err);
    bsp_box b = bsp_scene_bounds(s);
    bsp_vec3 centre = v3_scale(v3_add(b.lo, b.hi), 0.5);

    /* a narrower angle: further away, still everything in view */
    CHECK_EQ_INT(bsp_scene_set_default_view(s, NULL, NULL, NULL, 30, &err), BSP_OK);
    CHECK(bsp_scene_camera(s)->angle_deg == 30);
    check_corners_visible(s, "fov 30", 0);
    REQUIRE(bsp_scene_light_count(s) == 1);
    CHECK(same_vec(bsp_scene_light(s, 0)->pos, bsp_scene_camera(s)->from)); /* moved */

    /* the eye straight above the centre: up becomes +y */
    bsp_vec3 eye = v3_add(centre, bsp_v3(0, 0, 20));
    CHECK_EQ_INT(bsp_scene_set_default_view(s, &eye, NULL, NULL, 0, &err), BSP_OK);
    const bsp_camera *c = bsp_scene_camera(s);
    CHECK(same_vec(c->from, eye) && same_vec(c->at, centre));
    CHECK(c->up.x == 0 && c->up.y == 1 && c->up.z == 0);
    CHECK(c->angle_deg == 45);
    check_corners_visible(s, "from above", 0);
    CHECK_EQ_INT(bsp_scene_light_count(s), 1);
    CHECK(same_vec(bsp_scene_light(s, 0)->pos, eye));

    /* everything given */
    bsp_vec3 at = bsp_v3(1, 2, 0), up = bsp_v3(1, 0, 0);
    eye = bsp_v3(-10, 2, 3);
    CHECK_EQ_INT(bsp_scene_set_default_view(s, &eye, &at, &up, 60, &err), BSP_OK);
    c = bsp_scene_camera(s);
    CHECK(same_vec(c->from, eye) && same_vec(c->at, at) && same_vec(c->up, up));
    CHECK(c->angle_deg == 60 && c->res_x == 512);

    /* only 'at': the eye backs off by the displacement, so the box stays in view */
    at = b.lo;
    CHECK_EQ_INT(bsp_scene_set_default_view(s, NULL, &at, NULL, 0, &err), BSP_OK);
    check_corners_visible(s, "at a corner", 0);

    /* refusals leave the camera and the light alone */
    bsp_camera before = *bsp_scene_camera(s);
    CHECK_EQ_INT(bsp_scene_set_default_view(s, NULL, NULL, NULL, 180, &err), BSP_ERR_INVALID);
    CHECK_STR_CONTAINS(err.message, "field of view 180 is outside (0, 180)");
    CHECK_EQ_INT(bsp_scene_set_default_view(s, NULL, NULL, NULL, -5, &err), BSP_ERR_INVALID);
    CHECK_EQ_INT(bsp_scene_set_default_view(s, NULL, NULL, NULL, NAN, &err), BSP_ERR_INVALID);
    bsp_vec3 bad = bsp_v3(NAN, 0, 0);
    CHECK_EQ_INT(bsp_scene_set_default_view(s, &bad, NULL, NULL, 0, &err), BSP_ERR_INVALID);
    CHECK_STR_CONTAINS(err.message, "non-finite");
    CHECK_EQ_INT(bsp_scene_set_default_view(s, &centre, NULL, NULL, 0, &err), BSP_ERR_INVALID);
    CHECK_STR_CONTAINS(err.message, "'from' and 'at' are the same point");
    up = bsp_v3(1, 1, 1);
    CHECK_EQ_INT(bsp_scene_set_default_view(s, NULL, NULL, &up, 0, &err), BSP_ERR_INVALID);
    CHECK_STR_CONTAINS(err.message, "parallel");
    c = bsp_scene_camera(s);
    CHECK(same_vec(c->from, before.from) && same_vec(c->at, before.at));
    CHECK(same_vec(bsp_scene_light(s, 0)->pos, before.from));
    CHECK_EQ_INT(bsp_scene_set_default_view(NULL, NULL, NULL, NULL, 0, &err), BSP_ERR_INVALID);
    bsp_scene_destroy(s);

    /* an NFF scene keeps its own lights and its resolution */
    s = load_ok("tests/data/nff_good/order.nff");
    REQUIRE(bsp_scene_camera(s) && bsp_scene_light_count(s) == 1);
    int rx = bsp_scene_camera(s)->res_x, ry = bsp_scene_camera(s)->res_y;
    bsp_vec3 light = bsp_scene_light(s, 0)->pos;
    CHECK_EQ_INT(bsp_scene_set_default_view(s, NULL, NULL, NULL, 0, &err), BSP_OK);
    CHECK(bsp_scene_camera(s)->res_x == rx && bsp_scene_camera(s)->res_y == ry);
    CHECK_EQ_INT(bsp_scene_light_count(s), 1);
    CHECK(same_vec(bsp_scene_light(s, 0)->pos, light));
    check_corners_visible(s, "order.nff", 0);
    bsp_scene_destroy(s);

    /* a scene built by hand without lights gets one at the eye */
    s = bsp_scene_create();
    REQUIRE(s);
    CHECK_EQ_INT(bsp_scene_add_sphere(s, bsp_v3(1, 2, 3), 0.5, &err), BSP_OK);
    CHECK_EQ_INT(bsp_scene_set_default_view(s, NULL, NULL, NULL, 0, &err), BSP_OK);
    CHECK_EQ_INT(bsp_scene_light_count(s), 1);
    CHECK(bsp_scene_camera(s)->res_x == 512);
    check_corners_visible(s, "sphere", 0);
    bsp_scene_destroy(s);
}

/* An ASCII float holds every decimal that rounds to a finite float: FLT_MAX
 * as printed with 9 digits (3.40282347e+38) or as the shortest string that
 * reads back (3.4028235e+38) lies above FLT_MAX but rounds to it, as a
 * binary file's float would be; past the midpoint to 2^128 it rounds to
 * infinity and is refused (found by fuzzing: the first two were refused). */
TEST(mesh_ply_ascii_float_range_is_what_rounds_to_a_float)
{
    static const struct {
        const char *value;
        int ok;
    } cases[] = {
        {"3.40282347e+38", 1}, {"3.4028235e+38", 1}, {"-3.4028235e+38", 1},
        {"3.4028236e+38", 0},  {"-3.4028236e+38", 0}, {"1e39", 0},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        char path[1024], text[512];
        snprintf(path, sizeof path, "%s/float_range_%zu.ply", harness_tmpdir(), i);
        int n = snprintf(text, sizeof text,
                         "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                         "property float y\nproperty float z\nproperty float quality\n"
                         "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
                         "0 0 0 %s\n1 0 0 1\n0 1 0 1\n3 0 1 2\n",
                         cases[i].value);
        REQUIRE(write_file(path, text, (size_t)n));
        bsp_scene *s = NULL;
        bsp_error err;
        bsp_status st = bsp_scene_load(path, &s, &err);
        if (cases[i].ok) {
            CHECK_MSG(st == BSP_OK, "%s: %s", cases[i].value, err.message);
            CHECK(s && bsp_scene_prim_count(s) == 1);
        } else {
            CHECK_EQ_INT(st, BSP_ERR_PARSE);
            char want[256];
            snprintf(want, sizeof want, ":11: '%s' in vertex 0, property 'quality' is out of "
                     "range of type float", cases[i].value);
            CHECK_STR_CONTAINS(err.message, want);
        }
        bsp_scene_destroy(s);
    }
}

/* bsp_scene_camera_is_default says where the camera came from: 1 for the
 * view a mesh is framed with (and after bsp_scene_set_default_view), 0 for
 * an NFF file's own camera, for a camera set by bsp_scene_set_camera, and
 * for a scene without one. */
TEST(mesh_camera_is_default_follows_the_cameras_origin)
{
    bsp_error err;
    memset(&err, 0, sizeof err);
    bsp_scene *s = bsp_scene_create();
    REQUIRE(s);
    CHECK(bsp_scene_camera(s) == NULL);
    CHECK_EQ_INT(bsp_scene_camera_is_default(s), 0);
    bsp_scene_destroy(s);

    s = load_ok(OBJ_DIR "/polygons.obj");
    REQUIRE(bsp_scene_camera(s));
    CHECK_EQ_INT(bsp_scene_camera_is_default(s), 1);
    bsp_camera cam = *bsp_scene_camera(s);
    cam.angle_deg = 20;
    CHECK_EQ_INT(bsp_scene_set_camera(s, &cam, &err), BSP_OK);
    CHECK_EQ_INT(bsp_scene_camera_is_default(s), 0);
    CHECK_EQ_INT(bsp_scene_set_default_view(s, NULL, NULL, NULL, 0, &err), BSP_OK);
    CHECK_EQ_INT(bsp_scene_camera_is_default(s), 1);
    bsp_scene_destroy(s);

    s = load_ok("tests/data/nff_good/order.nff");
    REQUIRE(bsp_scene_camera(s));
    CHECK_EQ_INT(bsp_scene_camera_is_default(s), 0);
    bsp_scene_destroy(s);
}

/* The background: black in a new scene, what bsp_scene_set_background set,
 * and an NFF file's 'b' line. */
TEST(mesh_background_round_trip)
{
    bsp_scene *s = bsp_scene_create();
    REQUIRE(s);
    double bg[3] = {-1, -1, -1};
    bsp_scene_background(s, bg);
    CHECK(bg[0] == 0 && bg[1] == 0 && bg[2] == 0);
    const double set[3] = {0.25, 0.5, 0.078};
    bsp_scene_set_background(s, set);
    bsp_scene_background(s, bg);
    CHECK(bg[0] == 0.25 && bg[1] == 0.5 && bg[2] == 0.078);
    bsp_scene_destroy(s);

    s = NULL;
    bsp_error err;
    memset(&err, 0, sizeof err);
    const char *text = "b 0.078 0.361 0.753\np 3\n0 0 0\n1 0 0\n0 1 0\n";
    REQUIRE(bsp_scene_load_nff_memory(text, strlen(text), "bg.nff", &s, &err) == BSP_OK);
    bsp_scene_background(s, bg);
    CHECK(bg[0] == 0.078 && bg[1] == 0.361 && bg[2] == 0.753);
    bsp_scene_destroy(s);
}
