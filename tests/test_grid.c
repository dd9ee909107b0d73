/*
 * test_grid.c — the uniform grid (`--accel grid`) beyond the exactness
 * tests it shares with the kd-trees (test_kdtree.c): its resolution rule,
 * its refusals, and its figures against Havran's grid statistics
 * (../shared/reference/havran_stats_grids.txt) at the resolutions he used,
 * with his assignment (a primitive in every cell its bounds overlap): the
 * cells (N_V) exactly, the empty cells and the references to rounding, and
 * on balls the per-ray figures of a 513 x 513 depth-4 render without
 * mailboxes (his figures are written here, so the tests run without
 * ../shared); and `bspray bench --grids`, which prints that comparison.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <stdlib.h>
#include <unistd.h>

#include "bspray/bspray.h"
#include "harness.h"
#include "havran_test_util.h"

static bsp_accel *grid_of(const bsp_scene *s, double density, const int res[3], int mailbox,
                          int by_bounds)
{
    bsp_build_options o;
    bsp_build_options_defaults(&o);
    o.kind = BSP_ACCEL_GRID;
    o.grid_density = density;
    if (res)
        memcpy(o.grid_res, res, sizeof o.grid_res);
    o.mailbox = mailbox;
    o.grid_assign_bounds = by_bounds;
    bsp_accel *a = NULL;
    bsp_error err;
    REQUIRE_MSG(bsp_accel_build(s, &o, &a, &err) == BSP_OK, "%s", err.message);
    CHECK_MSG(bsp_accel_check(a, &err) == BSP_OK, "%s", err.message);
    return a;
}

TEST(grid_density_gives_about_that_many_cells_per_primitive)
{
    const char *scenes[] = {"spd:balls", "spd:tetra", "spd:tree"}; /* flat, cubic, wide */
    for (int i = 0; i < 3; i++) {
        bsp_scene *s = NULL;
        bsp_error err;
        REQUIRE(bsp_scene_load(scenes[i], &s, &err) == BSP_OK);
        const double n = (double)bsp_scene_prim_count(s);
        const double densities[] = {1.0, 4.0, 10.0};
        for (int k = 0; k < 3; k++) {
            bsp_accel *a = grid_of(s, densities[k], NULL, 1, 0);
            bsp_tree_stats st;
            bsp_accel_tree_stats(a, &st);
            double ratio = (double)st.leaves / (densities[k] * n);
            CHECK_MSG(ratio > 0.5 && ratio < 2.0, "%s, density %g: %llu cells for %g primitives",
                      scenes[i], densities[k], (unsigned long long)st.leaves, n);
            CHECK(st.leaves == (uint64_t)st.grid_res[0] * (uint64_t)st.grid_res[1] *
                                   (uint64_t)st.grid_res[2]);
            CHECK(st.interior_nodes == 0 && isnan(st.expected_cost));
            bsp_accel_destroy(a);
        }
        /* the cells per axis, given, are what is built */
        const int res[3] = {7, 1, 13};
        bsp_accel *a = grid_of(s, 0.0, res, 1, 0);
        bsp_tree_stats st;
        bsp_accel_tree_stats(a, &st);
        CHECK(st.grid_res[0] == 7 && st.grid_res[1] == 1 && st.grid_res[2] == 13);
        CHECK(st.leaves == 91);
        bsp_accel_destroy(a);
        bsp_scene_destroy(s);
    }
}

TEST(grid_refuses_bad_options)
{
    bsp_scene *s = NULL;
    bsp_error err;
    REQUIRE(bsp_scene_load("spd:tetra", &s, &err) == BSP_OK);
    bsp_build_options o;
    bsp_build_options_defaults(&o);
    o.kind = BSP_ACCEL_GRID;
    bsp_accel *a = NULL;
    const double bad_density[] = {NAN, -1.0, INFINITY, 2e6};
    for (int i = 0; i < 4; i++) {
        o.grid_density = bad_density[i];
        CHECK(bsp_accel_build(s, &o, &a, &err) == BSP_ERR_INVALID && a == NULL);
        CHECK_STR_CONTAINS(err.message, "grid density");
    }
    o.grid_density = 0.0;
    const int bad_res[][3] = {{0, 4, 4}, {4, -1, 4}, {4, 4, BSP_GRID_MAX_RES + 1}};
    for (int i = 0; i < 3; i++) {
        memcpy(o.grid_res, bad_res[i], sizeof o.grid_res);
        CHECK(bsp_accel_build(s, &o, &a, &err) == BSP_ERR_INVALID && a == NULL);
        CHECK_STR_CONTAINS(err.message, "grid resolution");
    }
    const int huge[3] = {BSP_GRID_MAX_RES, BSP_GRID_MAX_RES, BSP_GRID_MAX_RES};
    memcpy(o.grid_res, huge, sizeof o.grid_res);
    CHECK(bsp_accel_build(s, &o, &a, &err) == BSP_ERR_LIMIT && a == NULL);
    /* a grid is not saved */
    memset(o.grid_res, 0, sizeof o.grid_res);
    REQUIRE(bsp_accel_build(s, &o, &a, &err) == BSP_OK);
    CHECK(bsp_accel_save(a, "/nonexistent/grid.kdt", &err) == BSP_ERR_INVALID);
    CHECK_STR_CONTAINS(err.message, "this grid is rebuilt");
    bsp_accel_destroy(a);
    bsp_scene_destroy(s);
    /* and the command line says so, with exit status 2 */
    char cmd[512];
    snprintf(cmd, sizeof cmd, "%s stats spd:tetra --accel grid --grid-res 4,4 2>&1", harness_cli());
    CHECK_RUN(cmd, 2, "three whole numbers");
    snprintf(cmd, sizeof cmd, "%s stats spd:tetra --accel grid --grid-density nan 2>&1",
             harness_cli());
    CHECK_RUN(cmd, 2, "grid-density");
}

/* Havran's uniform grids (havran_stats_grids.txt): scene, cells per axis,
 * N_V, N_EV, N_OIV. */
typedef struct havran_grid {
    const char *scene;
    int res[3];
    uint64_t nv, nev, noiv;
} havran_grid;

/* His resolutions where his figures and ours, both by bounds, agree to
 * rounding (the others differ by how a primitive lying in a cell's face is
 * assigned, or by his gears' polygons: docs/grid.md). His teapot is the SPD
 * Readme's, size factor 12. */
static const havran_grid havran[] = {
    {"balls", {46, 46, 3}, 6348, 4208, 10240},
    {"balls", {103, 103, 7}, 74263, 63393, 19966},
    {"balls", {152, 152, 9}, 207936, 184204, 33909},
    {"tree", {52, 52, 3}, 8112, 5400, 11102},
    {"tree", {117, 118, 5}, 69030, 55191, 22407},
    {"tree", {60, 60, 60}, 216000, 212179, 14322},
    {"lattice", {20, 20, 20}, 8000, 0, 32152},
    {"lattice", {44, 44, 44}, 85184, 38016, 90368},
    {"mount", {20, 20, 20}, 8000, 6502, 21746},
    {"mount", {44, 44, 42}, 81312, 71924, 51144},
    {"mount", {35, 35, 35}, 42875, 37246, 38922},
    {"rings", {21, 20, 21}, 8820, 6264, 27666},
    {"rings", {60, 60, 60}, 216000, 178930, 127217},
    {"tetra", {35, 35, 35}, 42875, 37311, 35936},
    {"teapot:12", {28, 29, 11}, 8932, 7226, 22982},
    {"teapot:12", {80, 80, 30}, 192000, 175514, 75105},
};

/* The SPD database NAME generated in code (no ../shared needed). */
static bsp_scene *spd_scene(const char *name)
{
    char spec[64];
    snprintf(spec, sizeof spec, "spd:%s", name);
    return havran_test_scene(spec);
}

TEST(grid_cells_match_havrans_at_his_resolutions)
{
    for (size_t i = 0; i < sizeof havran / sizeof *havran; i++) {
        const havran_grid *h = &havran[i];
        bsp_scene *s = spd_scene(h->scene);
        bsp_accel *a = grid_of(s, 0.0, h->res, 0, 1);
        bsp_tree_stats st;
        bsp_accel_tree_stats(a, &st);
        /* clipped, the lists only lose references, the cells none */
        bsp_accel *c = grid_of(s, 0.0, h->res, 0, 0);
        bsp_tree_stats sc;
        bsp_accel_tree_stats(c, &sc);
        CHECK(sc.leaves == st.leaves && sc.references <= st.references &&
              sc.empty_leaves >= st.empty_leaves);
        bsp_accel_destroy(c);
        CHECK_MSG(st.leaves == h->nv, "%s: N_V %llu, Havran %llu", h->scene,
                  (unsigned long long)st.leaves, (unsigned long long)h->nv);
        double ev = h->nev ? fabs((double)st.empty_leaves / (double)h->nev - 1.0)
                           : (double)st.empty_leaves; /* none: none */
        double oiv = fabs((double)st.references / (double)h->noiv - 1.0);
        CHECK_MSG(ev < 0.003, "%s %dx%dx%d: N_EV %llu, Havran %llu", h->scene, h->res[0],
                  h->res[1], h->res[2], (unsigned long long)st.empty_leaves,
                  (unsigned long long)h->nev);
        CHECK_MSG(oiv < 0.03, "%s %dx%dx%d: N_OIV %llu, Havran %llu", h->scene, h->res[0],
                  h->res[1], h->res[2], (unsigned long long)st.references,
                  (unsigned long long)h->noiv);
        bsp_accel_destroy(a);
        bsp_scene_destroy(s);
    }
}

TEST(grid_rays_match_havrans_on_balls)
{
    /* his (46, 46, 3) grid on balls, no mailboxes: N_IT 358.66, N_TS =
     * N_ETS 5.69, N_EETS 3.00 per ray of the whole render */
    harness_skip_in_quick_mode(HAVRAN_FIGURES_FULL_ONLY);
    bsp_scene *s = spd_scene("balls");
    const int res[3] = {46, 46, 3};
    bsp_accel *a = grid_of(s, 0.0, res, 0, 1);
    havran_test_totals tot = havran_test_render(a);
    double rays = tot.rays, it = tot.it, ts = tot.ts, ets = tot.ets, eets = tot.eets;
    CHECK_MSG(fabs(it / rays / 358.66 - 1.0) < 0.05, "N_IT %.2f, Havran 358.66", it / rays);
    CHECK_MSG(fabs(ts / rays / 5.69 - 1.0) < 0.02, "N_TS %.2f, Havran 5.69", ts / rays);
    CHECK_MSG(ets == ts, "N_ETS %.2f is not N_TS", ets / rays);
    CHECK_MSG(fabs(eets / rays / 3.00 - 1.0) < 0.02, "N_EETS %.2f, Havran 3.00", eets / rays);
    bsp_accel_destroy(a);
    bsp_scene_destroy(s);
}

typedef struct visit_count {
    uint64_t nodes, planes, leaves, refs;
    double volume;
} visit_count;

static int count_visit(const bsp_cell_info *c, void *ctx)
{
    visit_count *v = ctx;
    v->nodes++;
    if (c->is_leaf) {
        v->leaves++;
        v->refs += c->refs;
        v->volume += (c->box.hi.x - c->box.lo.x) * (c->box.hi.y - c->box.lo.y) *
                     (c->box.hi.z - c->box.lo.z);
    } else if (c->depth == 1) {
        v->planes++;
    }
    return 1;
}

TEST(grid_visit_reports_the_box_its_planes_and_its_cells)
{
    bsp_scene *s = NULL;
    bsp_error err;
    REQUIRE(bsp_scene_load("spd:rings", &s, &err) == BSP_OK);
    const int res[3] = {5, 7, 3};
    bsp_accel *a = grid_of(s, 0.0, res, 1, 0);
    visit_count v = {0, 0, 0, 0, 0.0};
    REQUIRE(bsp_accel_visit_cells(a, -1, count_visit, &v, &err) == BSP_OK);
    bsp_tree_stats st;
    bsp_accel_tree_stats(a, &st);
    CHECK(v.leaves == 105 && v.planes == 4 + 6 + 2 && v.nodes == 1 + 12 + 105);
    CHECK(v.refs == st.references);
    visit_count root = {0, 0, 0, 0, 0.0};
    REQUIRE(bsp_accel_visit_cells(a, 0, count_visit, &root, &err) == BSP_OK);
    CHECK(root.nodes == 1);
    /* the cells tile the box */
    bsp_box b = bsp_scene_bounds(s);
    double vol = (b.hi.x - b.lo.x) * (b.hi.y - b.lo.y) * (b.hi.z - b.lo.z);
    CHECK_MSG(fabs(v.volume / vol - 1.0) < 1e-6, "cells %.17g, box %.17g", v.volume, vol);
    bsp_accel_destroy(a);
    bsp_scene_destroy(s);
}

TEST(grid_keeps_to_the_size_limit)
{
    bsp_scene *s = NULL;
    bsp_error err;
    REQUIRE(bsp_scene_load("spd:balls", &s, &err) == BSP_OK);
    bsp_build_options o;
    bsp_build_options_defaults(&o);
    o.kind = BSP_ACCEL_GRID;
    o.max_tree_bytes = (size_t)1 << 20;
    bsp_accel *a = NULL;
    /* too many cells for the limit */
    o.grid_density = 1000.0;
    CHECK(bsp_accel_build(s, &o, &a, &err) == BSP_ERR_LIMIT && a == NULL);
    CHECK_STR_CONTAINS(err.message, "cells need");
    /* cells that fit, references that do not: the ground polygon fills a
     * layer of 1000 x 1000 cells */
    const int res[3] = {1000, 1000, 1};
    memcpy(o.grid_res, res, sizeof o.grid_res);
    o.max_tree_bytes = (size_t)5 << 20;
    CHECK(bsp_accel_build(s, &o, &a, &err) == BSP_ERR_LIMIT && a == NULL);
    CHECK_STR_CONTAINS(err.message, "references");
    /* and with room, the same grid builds */
    o.max_tree_bytes = (size_t)64 << 20;
    REQUIRE(bsp_accel_build(s, &o, &a, &err) == BSP_OK);
    bsp_tree_stats st;
    bsp_accel_tree_stats(a, &st);
    CHECK(st.bytes > ((size_t)5 << 20) && st.bytes <= ((size_t)64 << 20));
    bsp_accel_destroy(a);
    bsp_scene_destroy(s);
}

TEST(cli_bench_grids_reproduces_havrans_tetra)
{
    harness_skip_in_quick_mode(HAVRAN_FIGURES_FULL_ONLY);
    char dir[] = "/tmp/bspray-grids-XXXXXX";
    REQUIRE(mkdtemp(dir));
    char csv[256], cmd[768];
    snprintf(csv, sizeof csv, "%s/g.csv", dir);
    snprintf(cmd, sizeof cmd, "%s bench --grids spd:tetra --quiet --threads 2 --csv %s 2>&1",
             harness_cli(), csv);
    /* his 35^3 grid: every cell and reference as his */
    CHECK_RUN(cmd, 0, "| tetra | 35 x 35 x 35 | 37311 / 37311 | 35936 / 35936 |");
    FILE *f = fopen(csv, "r");
    REQUIRE(f);
    char line[512];
    int rows = 0, near = 0;
    while (fgets(line, sizeof line, f)) {
        /* scene,res_x,res_y,res_z,N_V,...: N_TS is the 12th field, his the 13th */
        char *fields[20];
        int n = havran_test_csv_fields(line, fields, 20);
        if (n < 17 || strcmp(fields[0], "tetra") != 0)
            continue;
        int rx = atoi(fields[1]), ry = atoi(fields[2]), rz = atoi(fields[3]);
        unsigned long long nv = strtoull(fields[4], NULL, 10);
        double ts = atof(fields[11]), ts_h = atof(fields[12]);
        rows++;
        CHECK(nv == (unsigned long long)rx * (unsigned long long)ry * (unsigned long long)rz);
        near += fabs(ts / ts_h - 1.0) < 0.01; /* the walk: his N_TS within 1 % */
    }
    fclose(f);
    CHECK(rows == 3 && near == 3);
    snprintf(cmd, sizeof cmd, "%s bench --grids spd:shells 2>&1", harness_cli());
    CHECK_RUN(cmd, 2, "not one of Havran's scenes");
    snprintf(cmd, sizeof cmd, "%s bench --grids spd:tetra --res 0 2>&1", harness_cli());
    CHECK_RUN(cmd, 2, "--res", "from 1 to 65536");
    remove(csv);
    rmdir(dir);
}

TEST(cli_viz_draws_a_grid_of_the_cells_asked_for)
{
    char dir[] = "/tmp/bspray-gridviz-XXXXXX";
    REQUIRE(mkdtemp(dir));
    char png[256], cmd[768];
    snprintf(png, sizeof png, "%s/g.png", dir);
    snprintf(cmd, sizeof cmd,
             "%s viz spd:tetra --accel grid --grid-res 8,8,8 --size 64 -o %s 2>&1",
             harness_cli(), png);
    CHECK_RUN(cmd, 0, "grid          512 leaves");
    FILE *f = fopen(png, "rb");
    CHECK(f != NULL);
    if (f)
        fclose(f);
    remove(png);
    rmdir(dir);
}
