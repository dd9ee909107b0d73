/*
 * test_recgrid.c — the recursive grid (`--accel grid --grid-levels L`,
 * Jevans and Wyvill 1989) beyond the exactness tests it shares with the
 * kd-trees (test_kdtree.c, a variant of three levels): which cells are cut
 * and how, checked against a scene whose grids are worked out by hand; the
 * walk's counts on rays through a cut cell, closest and any hit, also worked
 * out by hand; that
 * one level is the uniform grid; the refusals and the size limit; the
 * command line's names for it; and Havran's recursive grids of tetra
 * (../shared/reference/havran_stats_grids.txt, "Recursive Grid", RHT +),
 * which come out to the cell, with `bspray bench --grids --grid-kind
 * recursive`, which prints them beside his.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bspray/bspray.h"
#include "harness.h"
#include "havran_test_util.h"
#include "kd_test_util.h"
#include "same_util.h"

/* The hand-made scene: a box of about [-4, 4]^3, made by a sphere of
 * radius 0.1 at (-3.9, -3.9, -3.9) and one of radius 1 at (3, 3, 3); and
 * 27 spheres of radius 0.25 at the centres of the 3 x 3 x 3 cells of the
 * box's low octant [-4, 0]^3: -4 + (i + 0.5) 4/3 = -3.333, -2, -0.667. */
static bsp_scene *cluster_scene(void)
{
    bsp_scene *s = bsp_scene_create();
    bsp_error err;
    REQUIRE(s != NULL);
    REQUIRE(bsp_scene_add_sphere(s, bsp_v3(-3.9, -3.9, -3.9), 0.1, &err) == BSP_OK);
    REQUIRE(bsp_scene_add_sphere(s, bsp_v3(3, 3, 3), 1.0, &err) == BSP_OK);
    for (int z = 0; z < 3; z++)
        for (int y = 0; y < 3; y++)
            for (int x = 0; x < 3; x++) {
                const double c[3] = {x, y, z};
                bsp_vec3 p;
                for (int k = 0; k < 3; k++)
                    p.v[k] = -4.0 + (c[k] + 0.5) * 4.0 / 3.0;
                REQUIRE(bsp_scene_add_sphere(s, p, 0.25, &err) == BSP_OK);
            }
    return s;
}

/* The grid over S: the root cut 2 x 2 x 2, at density 1, LEVELS grids
 * nested, cells of more than CELL_PRIMS primitives cut. */
static bsp_accel *cluster_grid(const bsp_scene *s, int levels, int cell_prims)
{
    bsp_build_options o;
    bsp_build_options_defaults(&o);
    o.kind = BSP_ACCEL_GRID;
    o.grid_res[0] = o.grid_res[1] = o.grid_res[2] = 2;
    o.grid_density = 1.0;
    o.grid_levels = levels;
    o.grid_cell_prims = cell_prims;
    bsp_accel *a = NULL;
    bsp_error err;
    REQUIRE_MSG(bsp_accel_build(s, &o, &a, &err) == BSP_OK, "%s", err.message);
    CHECK_MSG(bsp_accel_check(a, &err) == BSP_OK, "%s", err.message);
    return a;
}

/* Counts of the visit: cells at depth 2 (a subgrid's), their references. */
typedef struct visit_count {
    int leaves[3], planes[3];
    uint64_t refs[3];
    bsp_box sub_box; /* the box of the depth-2 planes */
} visit_count;

static int count_cell(const bsp_cell_info *c, void *ctx)
{
    visit_count *v = ctx;
    if (c->depth > 2)
        return 1;
    if (c->is_leaf) {
        v->leaves[c->depth]++;
        v->refs[c->depth] += c->refs;
    } else {
        v->planes[c->depth]++;
        if (c->depth == 2)
            v->sub_box = c->box;
    }
    return 1;
}

TEST(recgrid_cuts_the_crowded_cell_by_hand)
{
    bsp_scene *s = cluster_scene();
    /* one level: the uniform 2 x 2 x 2 grid; the low octant lists the small
     * sphere and the 27 (28), the high one the large sphere */
    bsp_accel *u = cluster_grid(s, 1, 8);
    bsp_tree_stats st;
    bsp_accel_tree_stats(u, &st);
    CHECK(st.interior_nodes == 0 && st.leaves == 8 && st.empty_leaves == 6 &&
          st.references == 29 && st.max_leaf_depth == 0);
    /* two levels: the low octant (28 > 8) is cut by its own grid of about
     * 1 x 28 cells by Klimaszewski's rule over a cube: x = round(28^(1/3)) =
     * 3, y = round(sqrt(28 / 3)) = 3, z = round(28 / 9) = 3; 27 cells, each
     * holding one sphere of the 27 (and the first, the small one); 7 + 27
     * elementary cells, 6 of them empty (the root's) */
    bsp_accel *r = cluster_grid(s, 2, 8);
    bsp_accel_tree_stats(r, &st);
    CHECK_MSG(st.interior_nodes == 1 && st.leaves == 34 && st.empty_leaves == 6 &&
                  st.references == 29,
              "N_IN %llu, N_V %llu, N_EV %llu, N_OIV %llu", (unsigned long long)st.interior_nodes,
              (unsigned long long)st.leaves, (unsigned long long)st.empty_leaves,
              (unsigned long long)st.references);
    CHECK(st.max_leaf_depth == 1 && fabs(st.avg_leaf_depth - 27.0 / 34.0) < 1e-12);
    CHECK(st.grid_res[0] == 2 && st.grid_res[1] == 2 && st.grid_res[2] == 2);
    /* the visit: the root's 3 planes and 7 cells, then the subgrid's 6
     * planes over the low octant and its 27 cells */
    visit_count v;
    memset(&v, 0, sizeof v);
    bsp_error err;
    REQUIRE(bsp_accel_visit_cells(r, -1, count_cell, &v, &err) == BSP_OK);
    CHECK(v.planes[1] == 3 && v.leaves[1] == 7 && v.refs[1] == 1);
    CHECK(v.planes[2] == 6 && v.leaves[2] == 27 && v.refs[2] == 28);
    for (int k = 0; k < 3; k++)
        CHECK(v.sub_box.lo.v[k] < -3.99 && v.sub_box.lo.v[k] > -4.01 &&
              fabs(v.sub_box.hi.v[k]) < 1e-3);
    /* a cell is cut only when it lists more than the limit, and never at
     * the deepest level */
    bsp_accel *at = cluster_grid(s, 2, 28), *below = cluster_grid(s, 2, 27);
    bsp_accel_tree_stats(at, &st);
    CHECK(st.interior_nodes == 0 && st.leaves == 8);
    bsp_accel_tree_stats(below, &st);
    CHECK(st.interior_nodes == 1 && st.leaves == 34);
    /* three levels: the subcell (0, 0, 0) lists two spheres, under 8: the
     * same grids as two levels */
    bsp_accel *three = cluster_grid(s, 3, 8);
    bsp_tree_stats st2;
    bsp_accel_tree_stats(three, &st2);
    bsp_accel_tree_stats(r, &st);
    CHECK(st2.interior_nodes == 1 && st2.leaves == 34 && st2.digest == st.digest);
    /* with cells of more than 1 primitive cut, that subcell gets a grid:
     * Klimaszewski's rule over its two spheres at density 1 gives x =
     * round(2^(1/3)) = 1, y = round(sqrt(2 / 1)) = 1, z = round(2 / 1) = 2;
     * the cluster's sphere, centred on the new plane z = -3.333, is listed
     * in both halves, the small sphere in the low one */
    bsp_accel *ones = cluster_grid(s, 3, 1);
    bsp_accel_tree_stats(ones, &st2);
    CHECK_MSG(st2.interior_nodes == 2 && st2.leaves == 35 && st2.references == 30 &&
                  st2.max_leaf_depth == 2,
              "N_IN %llu, N_V %llu, N_OIV %llu", (unsigned long long)st2.interior_nodes,
              (unsigned long long)st2.leaves, (unsigned long long)st2.references);
    bsp_accel_destroy(u);
    bsp_accel_destroy(r);
    bsp_accel_destroy(at);
    bsp_accel_destroy(below);
    bsp_accel_destroy(three);
    bsp_accel_destroy(ones);
    bsp_scene_destroy(s);
}

/* One ray along +x from x = -10 at height Y = Z through ACCEL: its hit and
 * counters, checked against the naive method's hit. */
static void shoot_x(const bsp_scene *s, const bsp_accel *a, double yz, bsp_hit *hit, int *found,
                    bsp_query_counters *c)
{
    bsp_ray ray = {bsp_v3(-10, yz, yz), bsp_v3(1, 0, 0), 0.0, INFINITY};
    bsp_query *q = bsp_query_create(a);
    REQUIRE(q != NULL);
    *found = bsp_intersect(a, q, &ray, hit);
    *c = *bsp_query_get_counters(q);
    bsp_query_destroy(q);
    bsp_accel *naive = kd_test_build(s, BSP_ACCEL_NAIVE);
    bsp_query *nq = bsp_query_create(naive);
    bsp_hit nh;
    int nf = bsp_intersect(naive, nq, &ray, &nh);
    CHECK(same_hit(nf, &nh, *found, hit));
    bsp_query_destroy(nq);
    bsp_accel_destroy(naive);
}

TEST(recgrid_walk_descends_into_the_cut_cell)
{
    bsp_scene *s = cluster_scene();
    bsp_accel *r = cluster_grid(s, 2, 8), *u = cluster_grid(s, 1, 8);
    bsp_hit h;
    int found;
    bsp_query_counters c;
    /* at y = z = -2 the ray meets the sphere at (-3.333, -2, -2) (number 2 +
     * 0 + 3 + 9 = 14) at x = -3.333 - 0.25: the root's low octant (cut: a
     * step, no leaf), its first subcell on that row (a leaf), and the walk
     * stops there, the hit lying inside it */
    shoot_x(s, r, -2.0, &h, &found, &c);
    CHECK(found && h.prim == 14 && fabs(h.t - (10.0 - 4.0 + 2.0 / 3.0 - 0.25)) < 1e-12);
    CHECK_MSG(c.traversal_steps == 2 && c.leaves_visited == 1 && c.isect_tests == 1,
              "steps %llu leaves %llu tests %llu", (unsigned long long)c.traversal_steps,
              (unsigned long long)c.leaves_visited, (unsigned long long)c.isect_tests);
    /* the uniform grid tests all 28 of the octant's list */
    shoot_x(s, u, -2.0, &h, &found, &c);
    CHECK(found && h.prim == 14 && c.traversal_steps == 1 && c.isect_tests == 28);
    /* at y = z = -2.4 it passes the three spheres of that row 0.4 from their
     * centres: the octant (a step), its three subcells of the row (each
     * listing one sphere), then the root's empty cell (1, 0, 0) */
    shoot_x(s, r, -2.4, &h, &found, &c);
    CHECK(!found);
    CHECK_MSG(c.traversal_steps == 5 && c.leaves_visited == 4 && c.empty_leaves == 1 &&
                  c.isect_tests == 3,
              "steps %llu leaves %llu empty %llu tests %llu",
              (unsigned long long)c.traversal_steps, (unsigned long long)c.leaves_visited,
              (unsigned long long)c.empty_leaves, (unsigned long long)c.isect_tests);
    bsp_accel_destroy(r);
    bsp_accel_destroy(u);
    bsp_scene_destroy(s);
}

/* The same ray as shoot_x as an occlusion query: its answer and counters,
 * checked against the naive method's answer. */
static int shoot_x_any(const bsp_scene *s, const bsp_accel *a, double yz, bsp_query_counters *c)
{
    bsp_ray ray = {bsp_v3(-10, yz, yz), bsp_v3(1, 0, 0), 0.0, INFINITY};
    bsp_query *q = bsp_query_create(a);
    REQUIRE(q != NULL);
    int on = bsp_occluded(a, q, &ray);
    *c = *bsp_query_get_counters(q);
    bsp_query_destroy(q);
    bsp_accel *naive = kd_test_build(s, BSP_ACCEL_NAIVE);
    bsp_query *nq = bsp_query_create(naive);
    CHECK(bsp_occluded(naive, nq, &ray) == on);
    bsp_query_destroy(nq);
    bsp_accel_destroy(naive);
    return on;
}

/* Whether C counts STEPS traversal steps, LEAVES cells, EMPTY empty cells,
 * TESTS tests and no mailbox hit; prints what it counts when not. */
static int counts_are(const bsp_query_counters *c, uint64_t steps, uint64_t leaves,
                      uint64_t empty, uint64_t tests)
{
    int ok = c->traversal_steps == steps && c->leaves_visited == leaves &&
             c->empty_leaves == empty && c->isect_tests == tests && c->mailbox_hits == 0;
    if (!ok)
        fprintf(stderr, "  counted: steps %llu leaves %llu empty %llu tests %llu mailbox %llu\n",
                (unsigned long long)c->traversal_steps, (unsigned long long)c->leaves_visited,
                (unsigned long long)c->empty_leaves, (unsigned long long)c->isect_tests,
                (unsigned long long)c->mailbox_hits);
    return ok;
}

TEST(recgrid_any_hit_walk_stops_at_the_first_hit)
{
    bsp_scene *s = cluster_scene();
    bsp_accel *r = cluster_grid(s, 2, 8), *u = cluster_grid(s, 1, 8);
    bsp_query_counters c;
    /* at y = z = -2: the octant (cut, a step), its first subcell on that row,
     * which lists sphere 14 alone, hit: one test */
    CHECK(shoot_x_any(s, r, -2.0, &c));
    CHECK(counts_are(&c, 2, 1, 0, 1));
    /* the uniform grid's octant lists spheres 0, 2, ..., 28 in that order;
     * the first the ray meets is 14 (0 and 2..13 lie off its row): 14 tests,
     * and the walk stops there */
    CHECK(shoot_x_any(s, u, -2.0, &c));
    CHECK(counts_are(&c, 1, 1, 0, 14));
    /* at y = z = -2.4 nothing blocks: every cell the ray passes is tested
     * whole, as by the closest-hit walk: the octant (a step), its three
     * subcells of the row, the root's empty cell (1, 0, 0); on the uniform
     * grid the octant's 28 spheres and that empty cell */
    CHECK(!shoot_x_any(s, r, -2.4, &c));
    CHECK(counts_are(&c, 5, 4, 1, 3));
    CHECK(!shoot_x_any(s, u, -2.4, &c));
    CHECK(counts_are(&c, 2, 2, 1, 28));
    bsp_accel_destroy(r);
    bsp_accel_destroy(u);
    bsp_scene_destroy(s);
}

TEST(recgrid_of_one_level_is_the_uniform_grid)
{
    const char *scenes[] = {"spd:balls", "spd:gears"};
    for (int i = 0; i < 2; i++) {
        bsp_scene *s = NULL;
        bsp_error err;
        REQUIRE(bsp_scene_load(scenes[i], &s, &err) == BSP_OK);
        bsp_build_options o;
        bsp_build_options_defaults(&o);
        o.kind = BSP_ACCEL_GRID;
        bsp_accel *def = NULL, *one = NULL, *uncut = NULL, *rec = NULL;
        REQUIRE(bsp_accel_build(s, &o, &def, &err) == BSP_OK);
        o.grid_levels = 1;
        REQUIRE(bsp_accel_build(s, &o, &one, &err) == BSP_OK);
        o.grid_levels = 3;
        o.grid_cell_prims = 1 << 30; /* no cell lists that many: nothing cut */
        bsp_tree_stats a;
        bsp_accel_tree_stats(def, &a);
        memcpy(o.grid_res, a.grid_res, sizeof o.grid_res); /* the uniform grid's root */
        REQUIRE(bsp_accel_build(s, &o, &uncut, &err) == BSP_OK);
        o.grid_cell_prims = 0;
        REQUIRE(bsp_accel_build(s, &o, &rec, &err) == BSP_OK);
        CHECK(bsp_accel_check(rec, &err) == BSP_OK);
        bsp_tree_stats b, c, d;
        bsp_accel_tree_stats(one, &b);
        bsp_accel_tree_stats(uncut, &c);
        bsp_accel_tree_stats(rec, &d);
        CHECK(a.digest == b.digest);
        CHECK(c.interior_nodes == 0 && c.leaves == a.leaves && c.references == a.references &&
              c.empty_leaves == a.empty_leaves);
        /* cut: more cells, the root's the same */
        CHECK_MSG(d.interior_nodes > 0 && d.leaves > a.leaves && d.max_leaf_depth >= 1 &&
                      d.grid_res[0] == a.grid_res[0] && d.grid_res[2] == a.grid_res[2],
                  "%s: N_IN %llu N_V %llu", scenes[i], (unsigned long long)d.interior_nodes,
                  (unsigned long long)d.leaves);
        /* the defaults the build chose, filled in */
        bsp_build_options got;
        bsp_accel_get_options(def, &got);
        CHECK(got.grid_levels == 1);
        bsp_accel_get_options(rec, &got);
        CHECK(got.grid_levels == 3 && got.grid_cell_prims == BSP_GRID_DEFAULT_CELL_PRIMS);
        bsp_accel_destroy(def);
        bsp_accel_destroy(one);
        bsp_accel_destroy(uncut);
        bsp_accel_destroy(rec);
        bsp_scene_destroy(s);
    }
}

TEST(recgrid_refuses_bad_options_and_keeps_to_the_size_limit)
{
    bsp_scene *s = NULL;
    bsp_error err;
    REQUIRE(bsp_scene_load("spd:balls", &s, &err) == BSP_OK);
    bsp_build_options o;
    bsp_build_options_defaults(&o);
    o.kind = BSP_ACCEL_GRID;
    bsp_accel *a = NULL;
    const int bad_levels[] = {-1, BSP_GRID_MAX_LEVELS + 1, 1000};
    for (int i = 0; i < 3; i++) {
        o.grid_levels = bad_levels[i];
        CHECK(bsp_accel_build(s, &o, &a, &err) == BSP_ERR_INVALID && a == NULL);
        CHECK_STR_CONTAINS(err.message, "grid levels");
    }
    o.grid_levels = 3;
    o.grid_cell_prims = -5;
    CHECK(bsp_accel_build(s, &o, &a, &err) == BSP_ERR_INVALID && a == NULL);
    CHECK_STR_CONTAINS(err.message, "grid cell primitives");
    /* the subgrids count against the size limit: the uniform grid fits in
     * 1 MiB, the recursive one of density 64 at every level does not */
    o.grid_cell_prims = 1;
    o.grid_levels = 1;
    o.max_tree_bytes = 1 << 20;
    REQUIRE(bsp_accel_build(s, &o, &a, &err) == BSP_OK);
    bsp_accel_destroy(a);
    a = NULL;
    o.grid_levels = 4;
    o.grid_density = 64.0;
    o.grid_res[0] = o.grid_res[1] = o.grid_res[2] = 8;
    CHECK(bsp_accel_build(s, &o, &a, &err) == BSP_ERR_LIMIT && a == NULL);
    CHECK_STR_CONTAINS(err.message, "size limit");
    bsp_scene_destroy(s);
    char cmd[512];
    snprintf(cmd, sizeof cmd, "%s stats spd:tetra --accel grid --grid-levels 9 2>&1",
             harness_cli());
    CHECK_RUN(cmd, 2, "grid-levels");
    snprintf(cmd, sizeof cmd, "%s stats spd:tetra --accel grid --grid-cell-prims 0 2>&1",
             harness_cli());
    CHECK_RUN(cmd, 2, "grid-cell-prims");
}

TEST(recgrid_is_named_grid_rec_on_the_command_line)
{
    char cmd[512];
    /* --accel grid-rec is the grid of two levels; the JSON says so */
    snprintf(cmd, sizeof cmd,
             "%s stats spd:tetra --accel grid-rec --check --stats-json /dev/stdout 2>&1",
             harness_cli());
    CHECK_RUN(cmd, 0, "\"grid_levels\": 2", "\"grid_cell_prims\": 8", "invariants     ok",
              "(cells cut by a grid of their own)", "grid levels    2");
    snprintf(cmd, sizeof cmd,
             "%s stats spd:tetra --accel grid --grid-levels 3 --grid-cell-prims 20 "
             "--stats-json /dev/stdout 2>&1",
             harness_cli());
    CHECK_RUN(cmd, 0, "\"grid_levels\": 3", "\"grid_cell_prims\": 20");
    /* a bench table names the rows as --accel does */
    snprintf(cmd, sizeof cmd,
             "%s bench spd:tetra --accel grid,grid-rec --res 33 --repeat 1 --quiet 2>&1",
             harness_cli());
    CHECK_RUN(cmd, 0, "| grid-rec |", "| grid |");
}

/* Havran's recursive grid of LEVELS levels over tetra, as his: density 1,
 * cells of more than 8 primitives cut, by bounds, no mailboxes. */
static bsp_accel *havran_recgrid(const bsp_scene *s, int levels)
{
    bsp_build_options o;
    bsp_build_options_defaults(&o);
    o.kind = BSP_ACCEL_GRID;
    o.grid_levels = levels;
    o.grid_density = 1.0;
    o.grid_cell_prims = 8;
    o.grid_assign_bounds = 1;
    o.mailbox = 0;
    bsp_accel *a = NULL;
    bsp_error err;
    REQUIRE_MSG(bsp_accel_build(s, &o, &a, &err) == BSP_OK, "%s", err.message);
    CHECK_MSG(bsp_accel_check(a, &err) == BSP_OK, "%s", err.message);
    return a;
}

TEST(recgrid_matches_havrans_on_tetra)
{
    /* his "Recursive Grid" table, tetra, RHT +: RMD 2: N_IN 1057 (his count
     * of grids, the root's too), N_V 31768, N_EV 14220, N_OIV 117056; RMD 3:
     * N_IN 1565, N_V 40404. Per ray of the 513 x 513 depth-4 render at RMD
     * 2: N_IT 21.32, N_TS 12.29, N_ETS 9.97, N_EETS 6.83 */
    bsp_scene *s = havran_test_scene("spd:tetra");
    bsp_accel *two = havran_recgrid(s, 2), *three = havran_recgrid(s, 3);
    bsp_tree_stats st;
    bsp_accel_tree_stats(two, &st);
    CHECK_MSG(st.interior_nodes + 1 == 1057 && st.leaves == 31768 && st.empty_leaves == 14220 &&
                  st.references == 117056,
              "grids %llu N_V %llu N_EV %llu N_OIV %llu",
              (unsigned long long)st.interior_nodes + 1, (unsigned long long)st.leaves,
              (unsigned long long)st.empty_leaves, (unsigned long long)st.references);
    bsp_accel_tree_stats(three, &st);
    CHECK_MSG(st.interior_nodes + 1 == 1565 && st.leaves == 40404, "grids %llu N_V %llu",
              (unsigned long long)st.interior_nodes + 1, (unsigned long long)st.leaves);
    bsp_render_options ro;
    bsp_render_options_defaults(&ro);
    bsp_image *img = NULL;
    bsp_render_stats rs;
    bsp_error err;
    REQUIRE(bsp_render(two, &ro, &img, &rs, &err) == BSP_OK);
    bsp_image_destroy(img);
    havran_test_totals t = havran_test_sum(&rs);
    REQUIRE(t.rays > 3e5); /* his 309,431 */
    const double his[4] = {21.32, 12.29, 9.97, 6.83};
    const double ours[4] = {t.it / t.rays, t.ts / t.rays, t.ets / t.rays, t.eets / t.rays};
    for (int i = 0; i < 4; i++)
        CHECK_MSG(fabs(ours[i] / his[i] - 1.0) < 0.04, "figure %d: ours %.2f, his %.2f", i,
                  ours[i], his[i]);
    /* a cut cell is a traversal step but no cell traversed */
    CHECK(t.ts > t.ets);
    bsp_accel_destroy(two);
    bsp_accel_destroy(three);
    bsp_scene_destroy(s);
}

TEST(cli_bench_grids_reproduces_havrans_recursive_tetra)
{
    harness_skip_in_quick_mode(HAVRAN_FIGURES_FULL_ONLY);
    char dir[] = "/tmp/bspray-recgrids-XXXXXX";
    REQUIRE(mkdtemp(dir));
    char csv[256], cmd[768];
    snprintf(csv, sizeof csv, "%s/r.csv", dir);
    snprintf(cmd, sizeof cmd,
             "%s bench --grids spd:tetra --grid-kind recursive --quiet --threads 2 --csv %s 2>&1",
             harness_cli(), csv);
    CHECK_RUN(cmd, 0,
              "| tetra | 2 | 1057 / 1057 | 31768 / 31768 | 14220 / 14220 | 117056 / 117056 |",
              "| tetra | 3 | 1565 / 1565 | 40404 / 40404 |");
    FILE *f = fopen(csv, "r");
    REQUIRE(f);
    char line[512];
    int rows = 0;
    while (fgets(line, sizeof line, f)) {
        /* scene,levels,grids,grids_havran,...,N_IT (11th),N_IT_havran, ...,
         * N_IT_clipped_mailboxes (19th) */
        char *fields[24];
        int n = havran_test_csv_fields(line, fields, 24);
        if (n < 20 || strcmp(fields[0], "tetra") != 0)
            continue;
        rows++;
        CHECK(atoi(fields[2]) == atoi(fields[3]));
        /* clipping and mailboxes take tests off */
        CHECK(atof(fields[18]) < atof(fields[10]));
    }
    fclose(f);
    CHECK(rows == 2);
    snprintf(cmd, sizeof cmd, "%s bench --grids --grid-kind octree 2>&1", harness_cli());
    CHECK_RUN(cmd, 2, "--grid-kind");
    remove(csv);
    rmdir(dir);
}

/* The shares a build reported, in order. */
typedef struct progress_log {
    double v[4096];
    int n;
} progress_log;

static void log_progress(double done, void *ctx)
{
    progress_log *l = ctx;
    if (l->n < 4096)
        l->v[l->n++] = done;
}

TEST(recgrid_build_reports_progress_that_never_goes_back)
{
    bsp_scene *s = havran_test_scene("spd:gears");
    bsp_build_options o;
    bsp_build_options_defaults(&o);
    o.kind = BSP_ACCEL_GRID;
    o.grid_levels = 4;
    o.grid_cell_prims = 2;
    static progress_log l;
    l.n = 0;
    o.progress = log_progress;
    o.progress_ctx = &l;
    bsp_accel *a = NULL;
    bsp_error err;
    REQUIRE_MSG(bsp_accel_build(s, &o, &a, &err) == BSP_OK, "%s", err.message);
    bsp_tree_stats st;
    bsp_accel_tree_stats(a, &st);
    /* thousands of grids: reported along the way, then 1 */
    CHECK_MSG(st.interior_nodes > 1000 && l.n > 2, "N_IN %llu, %d reports",
              (unsigned long long)st.interior_nodes, l.n);
    for (int i = 0; i < l.n; i++)
        CHECK(l.v[i] >= 0.0 && l.v[i] <= 1.0 && (i == 0 || l.v[i] >= l.v[i - 1]));
    CHECK(l.n > 0 && l.v[l.n - 1] == 1.0);
    bsp_accel_destroy(a);
    bsp_scene_destroy(s);
}
