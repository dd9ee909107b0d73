/*
 * test_examples.c — the programs of examples/, built against the public
 * headers alone (Makefile), linked to the static library and (NAME-shared)
 * to the shared one (and shoot_cxx.cpp, the same program in C++), run and
 * checked against the naive method: the centre
 * ray's primitive and t bit for bit, the shadow answer, and the number of
 * grid rays that hit. And the shared library's exports, against the
 * functions the public headers declare.
 */
#include <ctype.h>
#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bspray/bspray.h"
#include "harness.h"
#include "kd_test_util.h"

/* REL in the CLI's build directory (BUF: room): the libraries, examples/
 * and tests/ binaries the Makefile builds there. */
static const char *beside_cli(const char *rel, char *buf, size_t size)
{
    const char *cli = harness_cli();
    const char *slash = strrchr(cli, '/');
    int dir = slash ? (int)(slash - cli) : 0;
    snprintf(buf, size, "%.*s%s%s", dir, cli, slash ? "/" : "", rel);
    return buf;
}

/* examples/NAME's binary beside the CLI. */
static const char *example_path(const char *name, char *buf, size_t size)
{
    char rel[256];
    snprintf(rel, sizeof rel, "examples/%s", name);
    return beside_cli(rel, buf, size);
}

/* The number of rays of examples/shoot.c's G x G grid around the centre
 * ray that the naive method sees hit something (the grid as shoot.c makes
 * it: R and U perpendicular to the view and as long as it). */
static size_t naive_grid_hits(const bsp_accel *naive, bsp_query *q, bsp_vec3 eye, bsp_vec3 dir,
                              bsp_vec3 up, int g)
{
    bsp_vec3 r = bsp_v3(dir.y * up.z - dir.z * up.y, dir.z * up.x - dir.x * up.z,
                        dir.x * up.y - dir.y * up.x);
    bsp_vec3 u =
        bsp_v3(r.y * dir.z - r.z * dir.y, r.z * dir.x - r.x * dir.z, r.x * dir.y - r.y * dir.x);
    double len = sqrt(dir.x * dir.x + dir.y * dir.y + dir.z * dir.z);
    double rl = sqrt(r.x * r.x + r.y * r.y + r.z * r.z),
           ul = sqrt(u.x * u.x + u.y * u.y + u.z * u.z);
    size_t hits = 0;
    bsp_hit h;
    for (int j = 0; j < g; j++)
        for (int i = 0; i < g; i++) {
            double a = ((i + 0.5) / g - 0.5) * len / rl, b = ((j + 0.5) / g - 0.5) * len / ul;
            bsp_ray ray = {eye,
                           bsp_v3(dir.x + a * r.x + b * u.x, dir.y + a * r.y + b * u.y,
                                  dir.z + a * r.z + b * u.z),
                           0.0, INFINITY};
            hits += (size_t)bsp_intersect(naive, q, &ray, &h);
        }
    return hits;
}

/* the side of the grid the test asks for: the naive method shoots it too */
#define GRID 48

/* examples/shoot.c's binary EXE checked against the naive method */
static void check_shoot(const char *exe)
{
    static const char *const scenes[] = {"spd:teapot", "spd:tree"};
    for (size_t sc = 0; sc < 2; sc++) {
        char cmd[2048];
        snprintf(cmd, sizeof cmd, "%s %s %d", exe, scenes[sc], GRID);
        int status;
        char *out = harness_run(cmd, &status);
        REQUIRE(out);
        CHECK_MSG(status == 0, "'%s' exited with %d: %s", cmd, status, out);
        bsp_scene *s = kd_test_load(scenes[sc]);
        bsp_accel *naive = kd_test_build(s, BSP_ACCEL_NAIVE);
        bsp_query *q = bsp_query_create(naive);
        REQUIRE(q);
        const bsp_camera *cam = bsp_scene_camera(s);
        REQUIRE(cam);
        bsp_vec3 dir =
            bsp_v3(cam->at.x - cam->from.x, cam->at.y - cam->from.y, cam->at.z - cam->from.z);
        bsp_ray ray = {cam->from, dir, 0.0, INFINITY};
        bsp_hit h;
        REQUIRE(bsp_intersect(naive, q, &ray, &h)); /* both views look at the model */
        unsigned prim = 0;
        char tbuf[64] = "";
        const char *line = strstr(out, "centre ray: primitive ");
        CHECK_MSG(line && sscanf(line, "centre ray: primitive %u at t = %63s", &prim, tbuf) == 2,
                  "%s: '%s'", scenes[sc], out);
        double t = strtod(tbuf, NULL);
        CHECK_MSG(prim == h.prim && memcmp(&t, &h.t, sizeof t) == 0,
                  "%s: primitive %u at %s, naive %u at %.17g", scenes[sc], prim, tbuf, h.prim, h.t);
        bsp_vec3 p =
            bsp_v3(cam->from.x + h.t * dir.x, cam->from.y + h.t * dir.y, cam->from.z + h.t * dir.z);
        bsp_vec3 l = bsp_scene_light(s, 0)->pos;
        bsp_ray shadow = {p, bsp_v3(l.x - p.x, l.y - p.y, l.z - p.z), 0.0, 1.0};
        int blocked = bsp_occluded_from(naive, q, &shadow, h.prim);
        CHECK_STR_CONTAINS(out, blocked ? "light 0 is blocked" : "light 0 is visible");
        size_t want = naive_grid_hits(naive, q, cam->from, dir, cam->up, GRID), got = 0;
        line = strstr(out, "grid: ");
        CHECK_MSG(line && sscanf(line, "grid: %zu of %*d", &got) == 1, "'%s'", out);
        CHECK_MSG(got == want, "%s: %zu grid rays hit, naive %zu", scenes[sc], got, want);
        CHECK_MSG(want > GRID && want < GRID * GRID, "%s: %zu grid hits", scenes[sc], want);
        bsp_query_destroy(q);
        bsp_accel_destroy(naive);
        bsp_scene_destroy(s);
        free(out);
    }
    /* a scene that cannot be loaded: a message and exit status 1 */
    char cmd[2048];
    snprintf(cmd, sizeof cmd, "%s /nonexistent/x.nff 2>&1", exe);
    int status;
    char *out = harness_run(cmd, &status);
    REQUIRE(out);
    CHECK_EQ_INT(status, 1);
    CHECK_STR_CONTAINS(out, "/nonexistent/x.nff");
    free(out);
}

TEST(example_shoot_gives_the_naive_answers)
{
    char exe[1024];
    check_shoot(example_path("shoot", exe, sizeof exe));
}

TEST(example_shoot_linked_to_the_shared_library_gives_the_naive_answers)
{
    char exe[1024];
    check_shoot(example_path("shoot-shared", exe, sizeof exe));
}

/* examples/shoot_cxx.cpp: the same program in C++ (the public headers
 * included as they are, built with -std=c++11 -Wpedantic), so the same
 * check against the naive method */
TEST(example_shoot_from_cplusplus_gives_the_naive_answers)
{
    char exe[1024];
    check_shoot(example_path("shoot_cxx", exe, sizeof exe));
}

/* --- the shared library's exports ------------------------------------------------------ */

/* A set of names, as one string "\nname1\nname2\n...". */
typedef struct name_set {
    char buf[16384];
    size_t len;
} name_set;

static int set_has(const name_set *ns, const char *name, size_t n)
{
    char key[300];
    if (n + 3 > sizeof key)
        return 0;
    key[0] = '\n';
    memcpy(key + 1, name, n);
    key[n + 1] = '\n';
    key[n + 2] = '\0';
    return ns->len > 0 && strstr(ns->buf, key) != NULL;
}

static void set_add(name_set *ns, const char *name, size_t n)
{
    if (ns->len == 0)
        ns->buf[ns->len++] = '\n';
    if (set_has(ns, name, n) || ns->len + n + 2 > sizeof ns->buf)
        return;
    memcpy(ns->buf + ns->len, name, n);
    ns->len += n;
    ns->buf[ns->len++] = '\n';
    ns->buf[ns->len] = '\0';
}

/* The functions that header text H declares (and does not define static
 * inline): the names bsp_* followed by '(' outside braces, in a declaration
 * without "static"; comments and preprocessor lines skipped. */
static void declared_functions(const char *h, name_set *out)
{
    int depth = 0, is_static = 0, line_start = 1;
    for (const char *p = h; *p;) {
        if (p[0] == '/' && p[1] == '*') {
            const char *e = strstr(p + 2, "*/");
            p = e ? e + 2 : p + strlen(p);
            continue;
        }
        if (p[0] == '/' && p[1] == '/') {
            p += strcspn(p, "\n");
            continue;
        }
        if (line_start && *p == '#') { /* a directive, with its continuation lines */
            while (*p && !(*p == '\n' && p[-1] != '\\'))
                p++;
            continue;
        }
        line_start = *p == '\n' || (line_start && isspace((unsigned char)*p));
        if (strncmp(p, "extern \"C\" {", 12) == 0) { /* C++'s linkage block: no scope */
            p += 12;
            continue;
        }
        if (*p == '{')
            depth++;
        else if (*p == '}' && depth == 0) {
            /* the close of the extern "C" block */
        } else if (*p == '}') {
            depth--;
            if (depth == 0)
                is_static = 0;
        } else if (*p == ';' && depth == 0)
            is_static = 0;
        if (isalpha((unsigned char)*p) || *p == '_') {
            const char *w = p;
            while (isalnum((unsigned char)*p) || *p == '_')
                p++;
            size_t n = (size_t)(p - w);
            if (w > h && (isalnum((unsigned char)w[-1]) || w[-1] == '_'))
                continue;
            if (n == 6 && strncmp(w, "static", 6) == 0)
                is_static = 1;
            const char *q = p;
            while (*q == ' ' || *q == '\t' || *q == '\n')
                q++;
            if (depth == 0 && !is_static && *q == '(' && n > 4 && strncmp(w, "bsp_", 4) == 0)
                set_add(out, w, n);
            continue;
        }
        p++;
    }
}

/* The functions include/bspray/ declares, into *OUT; 0 when the headers
 * are not found from the working directory. */
static int public_declarations(name_set *out, size_t *headers)
{
    DIR *d = opendir("include/bspray");
    if (!d)
        return 0;
    struct dirent *de;
    *headers = 0;
    while ((de = readdir(d)) != NULL) {
        size_t n = strlen(de->d_name);
        if (n < 3 || strcmp(de->d_name + n - 2, ".h") != 0)
            continue;
        char path[512];
        snprintf(path, sizeof path, "include/bspray/%s", de->d_name);
        FILE *f = fopen(path, "rb");
        REQUIRE(f);
        static char text[1 << 18];
        size_t got = fread(text, 1, sizeof text - 1, f);
        fclose(f);
        text[got] = '\0';
        declared_functions(text, out);
        (*headers)++;
    }
    closedir(d);
    return 1;
}

/* LIB (beside the CLI) read by `nm NM_FLAGS`: the symbols it defines for a
 * program to link are exactly the functions the public headers declare. */
static void check_exports(const char *lib_name, const char *nm_flags)
{
    char lib[1024], cmd[1200];
    beside_cli(lib_name, lib, sizeof lib);
    name_set declared = {.len = 0}, exported = {.len = 0};
    size_t headers = 0;
    if (!public_declarations(&declared, &headers))
        harness_skip("include/bspray not found from the working directory");
    snprintf(cmd, sizeof cmd, "nm %s '%s' 2>/dev/null", nm_flags, lib);
    int status;
    char *out = harness_run(cmd, &status);
    REQUIRE(out);
    if (status != 0 || !*out) {
        free(out);
        harness_skip("nm could not read %s (binutils missing?)", lib);
    }
    size_t nexp = 0;
    for (char *line = strtok(out, "\n"); line; line = strtok(NULL, "\n")) {
        char addr[64], type[8], name[256];
        if (sscanf(line, "%63s %7s %255s", addr, type, name) == 3) { /* not "member.o:" */
            set_add(&exported, name, strlen(name));
            nexp++;
        }
    }
    free(out);
    /* every export is declared, every declared function exported */
    size_t ndecl = 0;
    for (const char *p = exported.buf + 1; *p; p += strcspn(p, "\n") + 1) {
        size_t n = strcspn(p, "\n");
        CHECK_MSG(set_has(&declared, p, n), "%s exports %.*s, which no public header declares",
                  lib, (int)n, p);
    }
    for (const char *p = declared.buf + 1; *p; p += strcspn(p, "\n") + 1) {
        size_t n = strcspn(p, "\n");
        ndecl++;
        CHECK_MSG(set_has(&exported, p, n), "%.*s is declared in include/bspray/ but %s does "
                  "not export it", (int)n, p, lib);
    }
    CHECK_MSG(headers >= 5 && ndecl >= 50, "%zu headers, %zu functions: parsed too few", headers,
              ndecl);
    CHECK_MSG(nexp == ndecl, "%s: %zu exported, %zu declared", lib, nexp, ndecl);
}

TEST(shared_library_exports_exactly_the_public_api)
{
    check_exports("libbspray.so", "-D --defined-only");
}

TEST(static_library_defines_only_the_public_api)
{
    check_exports("public/libbspray.a", "-g --defined-only");
}

TEST(static_library_keeps_internal_names_to_itself)
{
    char exe[1024];
    beside_cli("tests/names_apart", exe, sizeof exe);
    int status;
    char *out = harness_run(exe, &status);
    REQUIRE(out);
    CHECK_MSG(status == 0, "'%s' exited with %d: %s", exe, status, out);
    /* the library's own error path, and the program's own functions and data */
    CHECK_STR_CONTAINS(out, "library: status io: /nonexistent/names_apart.nff: cannot open");
    CHECK_STR_CONTAINS(out, "own: 42 2 3 4 5");
    free(out);
}

/* Whether this build runs under AddressSanitizer: its shared library then
 * cannot be loaded into a program built without it (Python). */
#if defined(__SANITIZE_ADDRESS__)
#define BUILT_WITH_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define BUILT_WITH_ASAN 1
#endif
#endif
#ifndef BUILT_WITH_ASAN
#define BUILT_WITH_ASAN 0
#endif

/* Whether this build runs under ThreadSanitizer (make tsan-test). */
#if defined(__SANITIZE_THREAD__)
#define BUILT_WITH_TSAN 1
#elif defined(__has_feature)
#if __has_feature(thread_sanitizer)
#define BUILT_WITH_TSAN 1
#endif
#endif
#ifndef BUILT_WITH_TSAN
#define BUILT_WITH_TSAN 0
#endif

/* tests/oom/oom_sweep.c, linked with the allocator wrapped: every
 * allocation of each scenario (the readers, every structure's build, a query,
 * a batch, a render, a tree file) made to fail in turn, alone and with every
 * later one. Each run must give the answer of the run without failures or
 * BSP_ERR_NOMEM with a message, and leave no block allocated. */
TEST(every_allocation_failing_in_turn_gives_nomem_or_the_right_answer)
{
    char exe[1024], cmd[1200];
    beside_cli("tests/oom_sweep", exe, sizeof exe);
    /* under ThreadSanitizer (make tsan-test) only the scenarios that run
     * threads: the single-threaded ones are the other runs' work */
    snprintf(cmd, sizeof cmd, "%s tests/data%s 2>&1", exe, BUILT_WITH_TSAN ? " thread" : "");
    int status;
    char *out = harness_run(cmd, &status);
    REQUIRE(out);
    CHECK_MSG(status == 0, "'%s' exited with %d: %s", cmd, status, out);
    CHECK_STR_CONTAINS(out, "oom_sweep: every run held");
    /* the sweep did fail allocations: the SAH build of the teapot, the OBJ
     * reader, a tree file and a scene made by the add_* calls were refused
     * (under ThreadSanitizer: a build and a batch on two threads) */
    static const char *const all_names[] = {"build sah spd:teapot:2", "load polygons.obj",
                                            "tree file spd:gears:1", "scene in code"};
    static const char *const thread_names[] = {"build sah+2threads spd:teapot:2",
                                               "batch on 2 threads spd:gears:1",
                                               "build bvh8+tasks+2threads spd:tetra:7"};
    const char *const *names = BUILT_WITH_TSAN ? thread_names : all_names;
    size_t nnames = BUILT_WITH_TSAN ? sizeof thread_names / sizeof *thread_names
                                    : sizeof all_names / sizeof *all_names;
    if (BUILT_WITH_TSAN)
        CHECK(strstr(out, "load polygons.obj") == NULL);
    for (size_t i = 0; i < nnames; i++) {
        const char *line = strstr(out, names[i]);
        long allocs = 0, runs = 0, refused = 0;
        CHECK_MSG(line && sscanf(line + strlen(names[i]), " %ld allocations, %ld runs, %ld refused",
                                 &allocs, &runs, &refused) == 3,
                  "no line for '%s' in: %s", names[i], out);
        CHECK_MSG(allocs >= 5 && runs == 2 * allocs && refused > 0,
                  "%s: %ld allocations, %ld runs, %ld refused", names[i], allocs, runs, refused);
    }
    free(out);
}

TEST(example_shoot_py_through_ctypes_prints_what_shoot_prints)
{
    if (BUILT_WITH_ASAN)
        harness_skip("an AddressSanitizer build's shared library cannot be loaded into Python");
    int status;
    char *out = harness_run("python3 -c 'import ctypes' 2>&1", &status);
    REQUIRE(out);
    free(out);
    if (status != 0)
        harness_skip("python3 with ctypes is not available");
    char lib[1024], exe[1024], cmd[2600];
    beside_cli("libbspray.so", lib, sizeof lib);
    example_path("shoot", exe, sizeof exe);
    static const char *const scenes[] = {"spd:teapot", "spd:tree"};
    for (size_t sc = 0; sc < 2; sc++) {
        snprintf(cmd, sizeof cmd, "python3 examples/shoot.py '%s' %s %d 2>&1", lib, scenes[sc],
                 GRID);
        char *py = harness_run(cmd, &status);
        REQUIRE(py);
        CHECK_MSG(status == 0, "'%s' exited with %d: %s", cmd, status, py);
        snprintf(cmd, sizeof cmd, "%s %s %d", exe, scenes[sc], GRID);
        char *c = harness_run(cmd, &status);
        REQUIRE(c);
        /* shoot's answers are checked against naive above */
        CHECK_MSG(strcmp(py, c) == 0, "%s: shoot.py printed\n%s\nshoot printed\n%s", scenes[sc],
                  py, c);
        CHECK_STR_CONTAINS(py, "centre ray: primitive ");
        free(py);
        free(c);
    }
    snprintf(cmd, sizeof cmd, "python3 examples/shoot.py '%s' /nonexistent/x.nff 2>&1", lib);
    char *bad = harness_run(cmd, &status);
    REQUIRE(bad);
    CHECK_EQ_INT(status, 1);
    CHECK_STR_CONTAINS(bad, "/nonexistent/x.nff");
    free(bad);
}
