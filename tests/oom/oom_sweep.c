/*
 * oom_sweep.c — every allocation of the library made to fail, one at a time.
 *
 * Linked with -Wl,--wrap=malloc,--wrap=calloc,--wrap=realloc,--wrap=free
 * (Makefile), so the library's calls to those reach the wrappers below: they
 * count every allocation and every block still live, and can make the K-th
 * allocation return NULL ("once"), or the K-th and every later one ("from").
 * For each scenario — loading each reader's files, building each structure,
 * a query, a batch on two threads, a render, a tree file read back — a run
 * without failures counts its allocations N and gives the reference answer;
 * then for every K < N, in both modes, the same call must either succeed
 * with the reference answer (the rays' primitives and t bit for bit, the
 * image float for float) or fail with BSP_ERR_NOMEM and a message, and leave
 * no block allocated once its objects are destroyed. No crash, no other
 * status, no leak, no silently wrong answer.
 *
 *   oom_sweep [DATA_DIR [NAME_PART]]   (default tests/data; with NAME_PART,
 *                                       only the scenarios whose names hold it)
 *
 * Prints one line per scenario and exits 0 when every run held, 1 otherwise
 * (each failing run named on stderr). tests/test_examples.c runs it.
 */
#include <math.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <zlib.h>

#include "bspray/bspray.h"

/* --- the wrapped allocator ------------------------------------------------ */

void *__real_malloc(size_t n);
void *__real_calloc(size_t n, size_t size);
void *__real_realloc(void *p, size_t n);
void __real_free(void *p);
void *__wrap_malloc(size_t n);
void *__wrap_calloc(size_t n, size_t size);
void *__wrap_realloc(void *p, size_t n);
void __wrap_free(void *p);

enum { FAIL_NEVER, FAIL_ONCE, FAIL_FROM };

/* Written by the main thread between the calls it tests; atomic because the
 * library's worker threads allocate too. */
static atomic_int counting;     /* 1 between arm() and disarm() */
static atomic_long calls;       /* allocations asked for while counting */
static atomic_long live;        /* blocks allocated and not freed */
static atomic_long fail_at;     /* the allocation (0-based since arm) that fails */
static atomic_int fail_mode;    /* FAIL_NEVER, FAIL_ONCE or FAIL_FROM */

static int should_fail(void)
{
    if (!atomic_load(&counting))
        return 0;
    long k = atomic_fetch_add(&calls, 1);
    int mode = atomic_load(&fail_mode);
    long at = atomic_load(&fail_at);
    return (mode == FAIL_ONCE && k == at) || (mode == FAIL_FROM && k >= at);
}

void *__wrap_malloc(size_t n)
{
    if (should_fail())
        return NULL;
    void *p = __real_malloc(n);
    if (p)
        atomic_fetch_add(&live, 1);
    return p;
}

void *__wrap_calloc(size_t n, size_t size)
{
    if (should_fail())
        return NULL;
    void *p = __real_calloc(n, size);
    if (p)
        atomic_fetch_add(&live, 1);
    return p;
}

void *__wrap_realloc(void *p, size_t n)
{
    if (n == 0 || should_fail()) /* realloc(p, 0) is not asked of the library */
        return n == 0 ? (__wrap_free(p), NULL) : NULL;
    void *q = __real_realloc(p, n);
    if (q && !p)
        atomic_fetch_add(&live, 1);
    return q;
}

void __wrap_free(void *p)
{
    if (p)
        atomic_fetch_sub(&live, 1);
    __real_free(p);
}

/* Counts allocations from now, failing the K-th in MODE. */
static void arm(int mode, long k)
{
    atomic_store(&counting, 0);
    atomic_store(&calls, 0);
    atomic_store(&fail_at, k);
    atomic_store(&fail_mode, mode);
    atomic_store(&counting, 1);
}

/* Ends the counting (a scenario's checks after its call allocate freely);
 * the allocations counted since arm(). */
static long disarm(void)
{
    atomic_store(&counting, 0);
    return atomic_load(&calls);
}

/* --- rays and their reference answers ------------------------------------- */

#define NRAYS 300

static uint64_t rng_state;
static double uniform(void)
{
    rng_state = rng_state * 6364136223846793005ull + 1442695040888963407ull;
    return (double)(rng_state >> 11) / 9007199254740992.0;
}

/* Rays from inside and around BOX in random directions, some along an axis. */
static void make_rays(bsp_box box, bsp_ray *rays)
{
    rng_state = 12345;
    for (int i = 0; i < NRAYS; i++) {
        bsp_vec3 o, d;
        for (int k = 0; k < 3; k++) {
            double lo = box.lo.v[k], hi = box.hi.v[k], w = hi - lo;
            o.v[k] = lo - 0.2 * w + 1.4 * w * uniform();
            d.v[k] = uniform() - 0.5;
        }
        if (i % 7 == 0)
            d = bsp_v3(i % 2 ? 1.0 : -1.0, 0.0, 0.0);
        rays[i] = (bsp_ray){o, d, 0.0, INFINITY};
    }
}

/* ACCEL's answers to RAYS, with failures off; 0 when out of memory. */
static int answer(const bsp_accel *accel, const bsp_ray *rays, bsp_hit *hits)
{
    bsp_query *q = bsp_query_create(accel);
    if (!q)
        return 0;
    for (int i = 0; i < NRAYS; i++)
        if (!bsp_intersect(accel, q, &rays[i], &hits[i]))
            hits[i].prim = BSP_NO_PRIM;
    bsp_query_destroy(q);
    return 1;
}

static int same_hits(const bsp_hit *a, const bsp_hit *b, char *why, size_t n)
{
    for (int i = 0; i < NRAYS; i++)
        if (a[i].prim != b[i].prim ||
            (a[i].prim != BSP_NO_PRIM && memcmp(&a[i].t, &b[i].t, sizeof a[i].t) != 0)) {
            snprintf(why, n, "ray %d: primitive %u at %.17g, naive %u at %.17g", i, a[i].prim,
                     a[i].t, b[i].prim, b[i].t);
            return 0;
        }
    return 1;
}

/* --- scenarios -------------------------------------------------------------- */

/* A scenario's run: RUN_OK (the reference answer), RUN_NOMEM (refused with
 * BSP_ERR_NOMEM and a message) or RUN_WRONG (WHY says how). */
enum { RUN_OK, RUN_NOMEM, RUN_WRONG };

typedef struct scenario scenario;
struct scenario {
    char name[160];
    int (*run)(const scenario *sc, char *why, size_t n);
    /* inputs and references, made without failures */
    const char *path;              /* load */
    size_t ref_prims;              /* load */
    bsp_box ref_bounds;            /* load */
    const bsp_scene *scene;        /* build */
    bsp_accel_kind kind;           /* build */
    bsp_octree_split octree_split; /* build */
    int grid_levels;               /* build */
    int budget;                    /* build: 1, a leaf budget tight enough to prune */
    int threads;                   /* build: 0 for 1 */
    const bsp_accel *accel;        /* query, batch, render, tree file */
    const char *tree_path;         /* tree file */
    const bsp_ray *rays;
    const bsp_hit *ref_hits;
    const bsp_image *ref_image;    /* render; png: the image to write */
    const char *png_path;          /* png */
    const bsp_image *ref_png;      /* png: the image written, read back */
};

static int refused(bsp_status st, const bsp_error *err, char *why, size_t n)
{
    if (st == BSP_ERR_NOMEM && err->message[0])
        return RUN_NOMEM;
    snprintf(why, n, "status %s, message '%s'", bsp_status_name(st), err->message);
    return RUN_WRONG;
}

static int run_load(const scenario *sc, char *why, size_t n)
{
    bsp_scene *s = NULL;
    bsp_error err = {0};
    bsp_status st = bsp_scene_load(sc->path, &s, &err);
    disarm();
    if (st != BSP_OK)
        return refused(st, &err, why, n);
    bsp_box b = bsp_scene_bounds(s);
    int same =
        bsp_scene_prim_count(s) == sc->ref_prims && memcmp(&b, &sc->ref_bounds, sizeof b) == 0;
    if (!same)
        snprintf(why, n, "%zu primitives, %zu without failures", bsp_scene_prim_count(s),
                 sc->ref_prims);
    bsp_scene_destroy(s);
    return same ? RUN_OK : RUN_WRONG;
}

/* Whether A (made under failures) answers SC's rays as the reference does;
 * its queries run without failures. */
static int answers_hold(const bsp_accel *a, const scenario *sc, char *why, size_t n)
{
    bsp_hit hits[NRAYS];
    if (!answer(a, sc->rays, hits)) {
        snprintf(why, n, "out of memory without failures");
        return RUN_WRONG;
    }
    return same_hits(hits, sc->ref_hits, why, n) ? RUN_OK : RUN_WRONG;
}

/* The scene of run_scene_in_code, made through the API's add_* calls: a
 * material, a light, a camera, a sphere, a cone, a polygon, a patch and an
 * indexed mesh of a G x G grid (200 triangles), with normals. Each call's
 * status is its own; the mesh is all or nothing. BSP_OK or the first
 * failure's status (ERR says which). */
#define MESH_G 10
static bsp_status make_scene_in_code(bsp_scene *s, bsp_error *err)
{
    static bsp_vec3 verts[(MESH_G + 1) * (MESH_G + 1)], normals[(MESH_G + 1) * (MESH_G + 1)];
    static uint32_t idx[6 * MESH_G * MESH_G];
    for (int j = 0; j <= MESH_G; j++)
        for (int i = 0; i <= MESH_G; i++) {
            verts[j * (MESH_G + 1) + i] = bsp_v3(i, j, 0.1 * ((i * j) % 3));
            normals[j * (MESH_G + 1) + i] = bsp_v3(0, 0, 1);
        }
    for (int j = 0, t = 0; j < MESH_G; j++)
        for (int i = 0; i < MESH_G; i++, t++) {
            uint32_t a = (uint32_t)(j * (MESH_G + 1) + i), b = a + 1, c = a + MESH_G + 1;
            uint32_t d = c + 1, *q = &idx[6 * t];
            q[0] = a, q[1] = b, q[2] = d, q[3] = a, q[4] = d, q[5] = c;
        }
    const bsp_material m = {{0.8, 0.2, 0.1}, 0.7, 0.3, 20.0, 0.0, 1.0, 0};
    const bsp_light l = {bsp_v3(5, 5, 20), {1, 1, 1}, 0};
    const bsp_camera cam = {bsp_v3(5, -10, 8), bsp_v3(5, 5, 0), bsp_v3(0, 0, 1), 45.0, 0.01, 32, 32};
    const bsp_vec3 poly[4] = {bsp_v3(-1, -1, -1), bsp_v3(12, -1, -1), bsp_v3(12, 12, -1),
                              bsp_v3(-1, 12, -1)};
    bsp_status st = bsp_scene_set_material(s, &m, err);
    if (st == BSP_OK)
        st = bsp_scene_add_light(s, &l, err);
    if (st == BSP_OK)
        st = bsp_scene_set_camera(s, &cam, err);
    if (st == BSP_OK)
        st = bsp_scene_add_sphere(s, bsp_v3(3, 3, 2), 1.0, err);
    if (st == BSP_OK)
        st = bsp_scene_add_cone(s, bsp_v3(7, 7, 0), 1.0, bsp_v3(7, 7, 3), 0.5, err);
    if (st == BSP_OK)
        st = bsp_scene_add_polygon(s, poly, 4, err);
    if (st == BSP_OK)
        st = bsp_scene_add_patch(s, verts, normals, 3, err);
    if (st == BSP_OK) {
        size_t before = bsp_scene_prim_count(s);
        st = bsp_scene_add_triangles(s, verts, (MESH_G + 1) * (MESH_G + 1), normals, idx,
                                     2 * MESH_G * MESH_G, err);
        if (st != BSP_OK && bsp_scene_prim_count(s) != before) {
            snprintf(err->message, sizeof err->message,
                     "a failed add_triangles added %zu primitives", bsp_scene_prim_count(s) - before);
            return BSP_ERR_INVALID; /* not all or nothing: reported as wrong */
        }
    }
    return st;
}

static int run_scene_in_code(const scenario *sc, char *why, size_t n)
{
    bsp_scene *s = bsp_scene_create();
    if (!s) {
        disarm();
        return RUN_NOMEM; /* the documented refusal: NULL */
    }
    bsp_error err = {0};
    bsp_status st = make_scene_in_code(s, &err);
    disarm();
    int r = RUN_OK;
    if (st != BSP_OK) {
        r = refused(st, &err, why, n);
    } else {
        bsp_box b = bsp_scene_bounds(s);
        if (bsp_scene_prim_count(s) != sc->ref_prims || memcmp(&b, &sc->ref_bounds, sizeof b)) {
            snprintf(why, n, "%zu primitives, %zu without failures", bsp_scene_prim_count(s),
                     sc->ref_prims);
            r = RUN_WRONG;
        }
    }
    bsp_scene_destroy(s);
    return r;
}

static void build_options(const scenario *sc, bsp_build_options *o)
{
    bsp_build_options_defaults(o);
    o->kind = sc->kind;
    /* one thread: the same allocations in the same order every run */
    o->threads = sc->threads > 0 ? sc->threads : 1;
    o->octree_split = sc->octree_split;
    o->grid_levels = sc->grid_levels;
    if (sc->budget) { /* half a leaf per primitive: the estimate, the pruning */
        o->sah_leaf_budget = 0.5;
        o->sah_leaf_budget_min = 1;
    }
}

static int run_build(const scenario *sc, char *why, size_t n)
{
    bsp_build_options o;
    build_options(sc, &o);
    bsp_accel *a = NULL;
    bsp_error err = {0};
    bsp_status st = bsp_accel_build(sc->scene, &o, &a, &err);
    disarm();
    if (st != BSP_OK)
        return refused(st, &err, why, n);
    int r = RUN_OK;
    if (bsp_accel_check(a, &err) != BSP_OK) {
        snprintf(why, n, "the built structure fails its check: %s", err.message);
        r = RUN_WRONG;
    } else {
        r = answers_hold(a, sc, why, n);
    }
    bsp_accel_destroy(a);
    return r;
}

static int run_query(const scenario *sc, char *why, size_t n)
{
    bsp_query *q = bsp_query_create(sc->accel);
    if (!q) {
        disarm();
        return RUN_NOMEM; /* the documented refusal: NULL */
    }
    bsp_hit hits[NRAYS];
    for (int i = 0; i < NRAYS; i++)
        if (!bsp_intersect(sc->accel, q, &sc->rays[i], &hits[i]))
            hits[i].prim = BSP_NO_PRIM;
    disarm();
    bsp_query_destroy(q);
    return same_hits(hits, sc->ref_hits, why, n) ? RUN_OK : RUN_WRONG;
}

static int run_batch(const scenario *sc, char *why, size_t n)
{
    bsp_hit hits[NRAYS];
    bsp_query_counters c;
    bsp_error err = {0};
    bsp_status st = bsp_intersect_batch(sc->accel, sc->rays, NULL, NRAYS, 2, hits, &c, &err);
    disarm();
    if (st != BSP_OK)
        return refused(st, &err, why, n);
    return same_hits(hits, sc->ref_hits, why, n) ? RUN_OK : RUN_WRONG;
}

static void render_options(bsp_render_options *o)
{
    bsp_render_options_defaults(o);
    o->width = o->height = 24;
    o->threads = 1;
}

static int same_image(const bsp_image *a, const bsp_image *b)
{
    return a->width == b->width && a->height == b->height &&
           memcmp(a->rgb, b->rgb, sizeof(float) * 3 * (size_t)a->width * (size_t)a->height) == 0;
}

/* Whether IMG (made under failures; destroyed here) equals REF; WHY says
 * which image differed. */
static int image_holds(bsp_image *img, const bsp_image *ref, const char *what, char *why, size_t n)
{
    int same = same_image(img, ref);
    if (!same)
        snprintf(why, n, "%s differs from the one made without failures", what);
    bsp_image_destroy(img);
    return same ? RUN_OK : RUN_WRONG;
}

static int run_render(const scenario *sc, char *why, size_t n)
{
    bsp_render_options o;
    render_options(&o);
    bsp_image *img = NULL;
    bsp_error err = {0};
    bsp_status st = bsp_render(sc->accel, &o, &img, NULL, &err);
    disarm();
    if (st != BSP_OK)
        return refused(st, &err, why, n);
    return image_holds(img, sc->ref_image, "the image rendered", why, n);
}

/* The image written as PNG under failures, then read back without. */
static int run_png_write(const scenario *sc, char *why, size_t n)
{
    bsp_error err = {0};
    bsp_status st = bsp_image_write_png(sc->ref_image, sc->png_path, &err);
    disarm();
    if (st != BSP_OK)
        return refused(st, &err, why, n);
    bsp_image *back = NULL;
    if (bsp_image_read_png(sc->png_path, &back, &err) != BSP_OK) {
        snprintf(why, n, "the PNG written cannot be read: %s", err.message);
        return RUN_WRONG;
    }
    return image_holds(back, sc->ref_png, "the PNG written", why, n);
}

/* The PNG read under failures. */
static int run_png_read(const scenario *sc, char *why, size_t n)
{
    bsp_image *img = NULL;
    bsp_error err = {0};
    bsp_status st = bsp_image_read_png(sc->png_path, &img, &err);
    disarm();
    if (st != BSP_OK)
        return refused(st, &err, why, n);
    return image_holds(img, sc->ref_png, "the PNG read", why, n);
}

static int run_tree_file(const scenario *sc, char *why, size_t n)
{
    bsp_accel *a = NULL;
    bsp_error err = {0};
    bsp_status st = bsp_accel_load(bsp_accel_scene(sc->accel), sc->tree_path, &a, &err);
    disarm();
    if (st != BSP_OK)
        return refused(st, &err, why, n);
    int r = answers_hold(a, sc, why, n);
    bsp_accel_destroy(a);
    return r;
}

/* --- the sweep -------------------------------------------------------------- */

static int failures;
static const char *only; /* NAME_PART: sweep only scenarios whose names hold it */
static int swept;        /* scenarios swept */

/* Runs SC once without failures (its allocation count N), then with each
 * of its N allocations failing, in both modes. */
static void sweep(const scenario *sc)
{
    if (only && !strstr(sc->name, only))
        return;
    swept++;
    char why[512] = "";
    long base = atomic_load(&live);
    arm(FAIL_NEVER, -1);
    int r = sc->run(sc, why, sizeof why);
    long total = disarm();
    if (r != RUN_OK) {
        fprintf(stderr, "oom_sweep: %s: without failures: %s\n", sc->name, why);
        failures++;
        return;
    }
    long runs = 0, refusals = 0, bad = 0;
    for (int mode = FAIL_ONCE; mode <= FAIL_FROM; mode++)
        for (long k = 0; k < total; k++) {
            why[0] = '\0';
            arm(mode, k);
            r = sc->run(sc, why, sizeof why);
            disarm();
            runs++;
            refusals += r == RUN_NOMEM;
            long leaked = atomic_load(&live) - base;
            if (r == RUN_WRONG || leaked != 0) {
                if (bad < 5)
                    fprintf(stderr,
                            "oom_sweep: %s: allocation %ld of %ld failing (%s): %s%s%ld block(s) "
                            "left\n",
                            sc->name, k + 1, total,
                            mode == FAIL_ONCE ? "once" : "and every later one",
                            r == RUN_WRONG ? why : "", r == RUN_WRONG ? "; " : "", leaked);
                bad++;
                atomic_store(&live, base); /* report each run's own leaks */
            }
        }
    printf("%-40s %6ld allocations, %6ld runs, %6ld refused, %s\n", sc->name, total, runs, refusals,
           bad ? "FAILED" : "ok");
    failures += bad > 0;
}

static bsp_scene *load_or_die(const char *path)
{
    bsp_scene *s = NULL;
    bsp_error err;
    if (bsp_scene_load(path, &s, &err) != BSP_OK) {
        fprintf(stderr, "oom_sweep: %s\n", err.message);
        exit(2);
    }
    return s;
}

static bsp_accel *build_or_die(const bsp_scene *s, bsp_accel_kind kind)
{
    const scenario sc = {.kind = kind};
    bsp_build_options o;
    build_options(&sc, &o);
    bsp_accel *a = NULL;
    bsp_error err;
    if (bsp_accel_build(s, &o, &a, &err) != BSP_OK) {
        fprintf(stderr, "oom_sweep: %s\n", err.message);
        exit(2);
    }
    return a;
}

/* Scene PATH loaded, the sweep's RAYS made in its box and the naive
 * method's answers to them in REF. */
static bsp_scene *load_with_reference(const char *path, bsp_ray *rays, bsp_hit *ref)
{
    bsp_scene *s = load_or_die(path);
    make_rays(bsp_scene_bounds(s), rays);
    bsp_accel *naive = build_or_die(s, BSP_ACCEL_NAIVE);
    if (!answer(naive, rays, ref)) {
        fprintf(stderr, "oom_sweep: %s: the naive method's answers failed\n", path);
        exit(2);
    }
    bsp_accel_destroy(naive);
    return s;
}

/* A gzip copy of SRC at DST (the reader's gunzip path); 0 on failure. */
static int gzip_copy(const char *src, const char *dst)
{
    FILE *in = fopen(src, "rb");
    gzFile out = gzopen(dst, "wb");
    int ok = in && out;
    char buf[4096];
    size_t got;
    while (ok && (got = fread(buf, 1, sizeof buf, in)) > 0)
        ok = gzwrite(out, buf, (unsigned)got) == (int)got;
    if (in)
        fclose(in);
    if (out)
        ok = gzclose(out) == Z_OK && ok;
    return ok;
}

/* Whether SC's build, without failures, cuts by the leaf budget's estimate
 * (so that a sweep of it covers the estimate); says why not on stderr. */
static int budget_estimated(const scenario *sc)
{
    bsp_build_options o;
    build_options(sc, &o);
    bsp_accel *a = NULL;
    bsp_error err;
    if (bsp_accel_build(sc->scene, &o, &a, &err) != BSP_OK) {
        fprintf(stderr, "oom_sweep: %s\n", err.message);
        return 0;
    }
    bsp_tree_stats t;
    bsp_accel_tree_stats(a, &t);
    bsp_accel_destroy(a);
    if (!(t.budget_cut > 0.0))
        fprintf(stderr, "oom_sweep: %s: the build made no estimate of its leaf budget\n",
                sc->name);
    return t.budget_cut > 0.0;
}

static const char *const scene_names[] = {"spd:balls:1", "spd:tree:3", "spd:teapot:2",
                                          "spd:gears:1"};
#define NSCENES (sizeof scene_names / sizeof scene_names[0])

int main(int argc, char **argv)
{
    const char *data = argc > 1 ? argv[1] : "tests/data";
    only = argc > 2 ? argv[2] : NULL;
    char gz[256], tree[256], png[256];
    snprintf(gz, sizeof gz, "/tmp/bspray-oom-%ld.nff.gz", (long)getpid());
    snprintf(tree, sizeof tree, "/tmp/bspray-oom-%ld.kdt", (long)getpid());
    snprintf(png, sizeof png, "/tmp/bspray-oom-%ld.png", (long)getpid());
    char nff[512], obj[512], ply[512];
    snprintf(nff, sizeof nff, "%s/nff_good/cones.nff", data);
    snprintf(obj, sizeof obj, "%s/obj/polygons.obj", data);
    snprintf(ply, sizeof ply, "%s/ply/extras.ply", data);
    if (!gzip_copy(nff, gz)) {
        fprintf(stderr, "oom_sweep: cannot make %s from %s\n", gz, nff);
        return 2;
    }

    /* loading: each reader, a gzip file and a generated scene */
    /* a scene made in code, through every add_* call */
    {
        scenario sc = {.run = run_scene_in_code};
        snprintf(sc.name, sizeof sc.name, "scene in code");
        bsp_scene *s = bsp_scene_create();
        bsp_error err;
        if (!s || make_scene_in_code(s, &err) != BSP_OK) {
            fprintf(stderr, "oom_sweep: the scene in code: %s\n", s ? err.message : "no memory");
            return 2;
        }
        sc.ref_prims = bsp_scene_prim_count(s);
        sc.ref_bounds = bsp_scene_bounds(s);
        bsp_scene_destroy(s);
        sweep(&sc);
    }
    const char *loads[] = {nff, obj, ply, gz, "spd:teapot:2"};
    for (size_t i = 0; i < sizeof loads / sizeof loads[0]; i++) {
        scenario sc = {.run = run_load, .path = loads[i]};
        snprintf(sc.name, sizeof sc.name, "load %s",
                 strrchr(loads[i], '/') ? strrchr(loads[i], '/') + 1 : loads[i]);
        bsp_scene *s = load_or_die(loads[i]);
        sc.ref_prims = bsp_scene_prim_count(s);
        sc.ref_bounds = bsp_scene_bounds(s);
        bsp_scene_destroy(s);
        sweep(&sc);
    }

    static const struct {
        const char *name;
        bsp_accel_kind kind;
        bsp_octree_split split;
        int levels, budget, threads;
    } methods[] = {
        {"kaplan", BSP_ACCEL_KAPLAN, BSP_OCTREE_CENTRE, 0, 0, 0},
        {"sah", BSP_ACCEL_SAH, BSP_OCTREE_CENTRE, 0, 0, 0},
        {"sah+budget", BSP_ACCEL_SAH, BSP_OCTREE_CENTRE, 0, 1, 0},
        {"sah+2threads", BSP_ACCEL_SAH, BSP_OCTREE_CENTRE, 0, 0, 2},
        {"sah-per", BSP_ACCEL_SAH_PER, BSP_OCTREE_CENTRE, 0, 0, 0},
        {"sah-par", BSP_ACCEL_SAH_PAR, BSP_OCTREE_CENTRE, 0, 0, 0},
        {"sah-mixed", BSP_ACCEL_SAH_MIXED, BSP_OCTREE_CENTRE, 0, 0, 0},
        {"grid", BSP_ACCEL_GRID, BSP_OCTREE_CENTRE, 0, 0, 0},
        {"grid-rec", BSP_ACCEL_GRID, BSP_OCTREE_CENTRE, 2, 0, 0},
        {"octree", BSP_ACCEL_OCTREE, BSP_OCTREE_CENTRE, 0, 0, 0},
        {"octree-cost", BSP_ACCEL_OCTREE, BSP_OCTREE_COST, 0, 0, 0},
        {"bvh", BSP_ACCEL_BVH, BSP_OCTREE_CENTRE, 0, 0, 0},
        {"bvh4", BSP_ACCEL_BVH4, BSP_OCTREE_CENTRE, 0, 0, 0},
        {"bvh8", BSP_ACCEL_BVH8, BSP_OCTREE_CENTRE, 0, 0, 0},
    };
    static bsp_ray rays[NRAYS];
    static bsp_hit ref[NRAYS];
    for (size_t si = 0; si < NSCENES; si++) {
        bsp_scene *s = load_with_reference(scene_names[si], rays, ref);

        for (size_t m = 0; m < sizeof methods / sizeof methods[0]; m++) {
            /* sah-mixed renders two small images per build: on the first scene only */
            if (methods[m].kind == BSP_ACCEL_SAH_MIXED && si > 0)
                continue;
            scenario sc = {.run = run_build,
                           .scene = s,
                           .kind = methods[m].kind,
                           .octree_split = methods[m].split,
                           .grid_levels = methods[m].levels,
                           .budget = methods[m].budget,
                           .threads = methods[m].threads,
                           .rays = rays,
                           .ref_hits = ref};
            snprintf(sc.name, sizeof sc.name, "build %s %s", methods[m].name, scene_names[si]);
            sweep(&sc);
        }

        /* the default tree: queries, a batch, a render, the tree read back */
        bsp_accel *a = build_or_die(s, BSP_ACCEL_SAH);
        bsp_error err;
        if (bsp_accel_save(a, tree, &err) != BSP_OK) {
            fprintf(stderr, "oom_sweep: %s\n", err.message);
            return 2;
        }
        bsp_render_options ro;
        render_options(&ro);
        bsp_image *img = NULL;
        if (bsp_render(a, &ro, &img, NULL, &err) != BSP_OK) {
            fprintf(stderr, "oom_sweep: %s\n", err.message);
            return 2;
        }
        /* the render as PNG, read back: the PNG scenarios' reference */
        bsp_image *png_img = NULL;
        if (bsp_image_write_png(img, png, &err) != BSP_OK ||
            bsp_image_read_png(png, &png_img, &err) != BSP_OK) {
            fprintf(stderr, "oom_sweep: %s\n", err.message);
            return 2;
        }
        scenario base = {.accel = a,
                         .rays = rays,
                         .ref_hits = ref,
                         .tree_path = tree,
                         .ref_image = img,
                         .png_path = png,
                         .ref_png = png_img};
        static const struct {
            const char *name;
            int (*run)(const scenario *, char *, size_t);
        } uses[] = {{"query", run_query},
                    {"batch on 2 threads", run_batch},
                    {"render 24 x 24", run_render},
                    {"tree file", run_tree_file},
                    {"png write", run_png_write},
                    {"png read", run_png_read}};
        for (size_t u = 0; u < sizeof uses / sizeof uses[0]; u++) {
            scenario sc = base;
            sc.run = uses[u].run;
            snprintf(sc.name, sizeof sc.name, "%s %s", uses[u].name, scene_names[si]);
            sweep(&sc);
        }
        bsp_image_destroy(png_img);
        bsp_image_destroy(img);
        bsp_accel_destroy(a);
        bsp_scene_destroy(s);
    }
    /* The leaf budget's estimate from sampled subtrees ("probes", built as
     * tasks: kd_sah_tasks.c) needs enough of them, so a scene of thousands
     * of primitives; on one thread and on two (probes and tasks taken by the
     * workers, the estimate made while they wait). */
    {
        bsp_scene *s = load_with_reference("spd:balls:4", rays, ref);
        for (int threads = 1; threads <= 2; threads++) {
            scenario sc = {.run = run_build,
                           .scene = s,
                           .kind = BSP_ACCEL_SAH,
                           .budget = 1,
                           .threads = threads,
                           .rays = rays,
                           .ref_hits = ref};
            snprintf(sc.name, sizeof sc.name, "build sah+estimate%s spd:balls:4",
                     threads > 1 ? "+2threads" : "");
            if (!budget_estimated(&sc))
                return 2;
            sweep(&sc);
        }
        bsp_scene_destroy(s);
    }
    /* The BVHs' threaded build defers subtrees as tasks (bvh_build.c) in a
     * scene of more than 8,192 primitives: on one thread (the calling
     * thread builds them all) and on two. */
    {
        bsp_scene *s = load_with_reference("spd:tetra:7", rays, ref);
        static const bsp_accel_kind bvhs[] = {BSP_ACCEL_BVH, BSP_ACCEL_BVH4, BSP_ACCEL_BVH8};
        for (int b = 0; b < 3; b++)
            for (int threads = 1; threads <= 2; threads++) {
                scenario sc = {.run = run_build,
                               .scene = s,
                               .kind = bvhs[b],
                               .threads = threads,
                               .rays = rays,
                               .ref_hits = ref};
                snprintf(sc.name, sizeof sc.name, "build %s+tasks%s spd:tetra:7",
                         bsp_accel_kind_name(bvhs[b]), threads > 1 ? "+2threads" : "");
                sweep(&sc);
            }
        bsp_scene_destroy(s);
    }
    remove(gz);
    remove(tree);
    remove(png);
    if (swept == 0) {
        fprintf(stderr, "oom_sweep: no scenario's name holds '%s'\n", only ? only : "");
        return 2;
    }
    printf("%s\n", failures ? "oom_sweep: FAILED" : "oom_sweep: every run held");
    return failures ? 1 : 0;
}
