/*
 * bench_grids.c — `bspray bench --grids`: Havran's 1999 uniform-grid
 * statistics (../shared/reference/havran_stats_grids.txt) reproduced by one
 * command: for each of his scenes and his three resolutions, bspray's grid
 * with his assignment (a primitive in every cell its bounds overlap) and
 * without mailboxes, as his grids were, on the SPD database generated in
 * code (bit for bit the SPD programs' files), validated against the naive
 * method, then a 513 x 513 depth-4 render: N_EV, N_OIV, N_IT, N_TS, N_EETS
 * next to his; and the N_IT of the default grid (clipped, mailboxes) at the
 * same resolution. docs/grid.md discusses the table.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench.h"
#include "cli.h"

static const char grids_usage[] = "bspray bench --grids [SCENE...] [--grid-kind "
                                  "uniform|recursive] [--res N] [--threads N] [--csv FILE] "
                                  "[--quiet]";

/* One of Havran's uniform grids and his figures for it. */
typedef struct havran_row {
    const char *scene; /* the SPD database */
    int res[3];
    unsigned long nv, nev, noiv;
    double nit, nts, neets;
} havran_row;

/* His table "Uniform Grid": Woo's rule at densities 1 and 10, and his
 * "customary setting", per scene. */
static const havran_row havran_rows[] = {
    {"balls", {46, 46, 3}, 6348, 4208, 10240, 358.66, 5.69, 3.00},
    {"balls", {103, 103, 7}, 74263, 63393, 19966, 72.54, 12.40, 9.27},
    {"balls", {152, 152, 9}, 207936, 184204, 33909, 41.48, 17.32, 13.93},
    {"gears", {32, 33, 9}, 9504, 6080, 39344, 39.76, 6.84, 3.62},
    {"gears", {71, 71, 18}, 90738, 66531, 110029, 22.82, 13.83, 9.19},
    {"gears", {98, 98, 25}, 240100, 194920, 171316, 17.52, 18.95, 14.62},
    {"lattice", {20, 20, 20}, 8000, 0, 32152, 20.67, 5.09, 0.00},
    {"lattice", {44, 44, 44}, 85184, 38016, 90368, 9.26, 10.56, 5.09},
    {"lattice", {59, 59, 59}, 205379, 102640, 160819, 8.81, 13.70, 7.51},
    {"mount", {20, 20, 20}, 8000, 6502, 21746, 19.01, 8.85, 4.97},
    {"mount", {44, 44, 42}, 81312, 71924, 51144, 13.17, 18.43, 11.93},
    {"mount", {35, 35, 35}, 42875, 37246, 38922, 13.32, 15.01, 9.60},
    {"rings", {21, 20, 21}, 8820, 6264, 27666, 45.29, 11.78, 7.33},
    {"rings", {44, 43, 44}, 83248, 66753, 71303, 23.36, 24.51, 18.84},
    {"rings", {60, 60, 60}, 216000, 178930, 127217, 21.48, 33.71, 27.22},
    {"teapot", {28, 29, 11}, 8932, 7226, 22982, 33.65, 14.98, 12.25},
    {"teapot", {61, 61, 25}, 93025, 83721, 52781, 15.13, 32.50, 29.60},
    {"teapot", {80, 80, 30}, 192000, 175514, 75105, 13.30, 41.24, 38.08},
    {"tetra", {16, 16, 16}, 4096, 3104, 12556, 20.64, 7.43, 5.83},
    {"tetra", {35, 35, 35}, 42875, 37311, 35936, 10.01, 15.97, 14.36},
    {"tetra", {40, 40, 40}, 64000, 56696, 44696, 9.17, 18.24, 16.63},
    {"tree", {52, 52, 3}, 8112, 5400, 11102, 727.62, 7.60, 4.50},
    {"tree", {117, 118, 5}, 69030, 55191, 22407, 246.08, 15.45, 11.67},
    {"tree", {60, 60, 60}, 216000, 212179, 14322, 355.45, 56.36, 45.36},
};
#define HAVRAN_ROWS (sizeof havran_rows / sizeof *havran_rows)

static void print_help(void)
{
    printf("usage: %s\n\n", grids_usage);
    printf("Havran's uniform grids (Havran and Sixta 1999, the statistics beside bspray's\n"
           "kd-tree comparison) reproduced: for each of his scenes and the three resolutions\n"
           "he lists, bspray's grid at that resolution with his assignment (a primitive in\n"
           "every cell its bounds overlap, --grid-assign bounds) and no mailboxes, on the SPD\n"
           "database generated in code, validated against the naive method, then a 513 x 513\n"
           "render of ray depth 4. Each figure is printed as ours / his; the last column is\n"
           "the N_IT of bspray's default grid (clipped, mailboxes) at the same resolution.\n"
           "With --grid-kind recursive: his recursive grids (Jevans and Wyvill's, every\n"
           "level by Klimaszewski's heterogeneous rule) of 2 and 3 levels, bspray's of as\n"
           "many levels at density 1 with cells of more than 8 primitives cut, by bounds and\n"
           "without mailboxes; his N_IN counts the grids (the root too); the last column is\n"
           "the N_IT of the same grids clipped and with mailboxes.\n"
           "docs/grid.md discusses the tables. His teapot is the SPD Readme's, size 12.\n\n"
           "  SCENE...       balls gears lattice mount rings teapot tetra tree (or spd:NAME;\n"
           "                 default: all eight)\n"
           "  --grid-kind uniform|recursive  his uniform grids (default) or his recursive\n"
           "                 grids\n"
           "  --res N        render N x N rays (default 513, his protocol; at another size\n"
           "                 the per-ray figures do not compare with his, the structure's do)\n"
           "  --threads N    render threads (default: every core); the counts do not depend\n"
           "                 on it\n"
           "  --csv FILE     also write one CSV row per grid\n"
           "  --quiet        no progress on stderr\n"
           "  --help         this text\n");
}

/* The grid of ROW over SCENE: Havran's (bounds, no mailboxes) or the
 * default one (clipped, mailboxes) at his resolution. */
static bsp_accel *row_grid(const bsp_scene *scene, const havran_row *row, int havrans)
{
    bsp_build_options o;
    bsp_build_options_defaults(&o);
    o.kind = BSP_ACCEL_GRID;
    memcpy(o.grid_res, row->res, sizeof o.grid_res);
    o.grid_assign_bounds = havrans;
    o.mailbox = !havrans;
    return build_accel(scene, &o);
}

/* His three grids of one scene, ours beside. */
static int grids_of_scene(const char *bare, const char *name, const bsp_scene *scene,
                          const bsp_accel *naive, void *ctx)
{
    const havran_run *run = ctx;
    if (run->variant)
        return recgrids_of_scene(bare, name, scene, naive, ctx);
    for (size_t r = 0; r < HAVRAN_ROWS; r++) {
        const havran_row *h = &havran_rows[r];
        if (strcmp(h->scene, bare) != 0)
            continue;
        if (!run->quiet)
            fprintf(stderr, "%s: %s: grid %d x %d x %d\n", prog, name, h->res[0], h->res[1],
                    h->res[2]);
        bsp_accel *hg = row_grid(scene, h, 1), *dg = row_grid(scene, h, 0);
        havran_figures f, fd;
        long checked = havran_measure_pair(hg, dg, naive, name, "grid", run, &f, &fd);
        if (checked >= 0) {
            bsp_tree_stats st;
            bsp_accel_tree_stats(hg, &st);
            printf("| %s | %d x %d x %d | %llu / %lu | %llu / %lu | %.2f / %.2f | %.2f / %.2f "
                   "| %.2f / %.2f | %.2f |\n",
                   h->scene, h->res[0], h->res[1], h->res[2], (unsigned long long)st.empty_leaves,
                   h->nev, (unsigned long long)st.references, h->noiv, f.nit, h->nit, f.nts,
                   h->nts, f.neets, h->neets, fd.nit);
            fflush(stdout);
            if (run->csv)
                fprintf(run->csv,
                        "%s,%d,%d,%d,%llu,%llu,%lu,%llu,%lu,%.4f,%.2f,%.4f,%.2f,%.4f,%.2f,%.4f,"
                        "%ld\n",
                        h->scene, h->res[0], h->res[1], h->res[2], (unsigned long long)st.leaves,
                        (unsigned long long)st.empty_leaves, h->nev,
                        (unsigned long long)st.references, h->noiv, f.nit, h->nit, f.nts, h->nts,
                        f.neets, h->neets, fd.nit, checked);
        }
        bsp_accel_destroy(hg);
        bsp_accel_destroy(dg);
        if (checked < 0)
            return EXIT_INPUT;
    }
    return 0;
}

int bench_grids(int argc, char **argv)
{
    static const havran_bench b = {
        grids_usage,
        "--grids",
        print_help,
        {"scene,res_x,res_y,res_z,N_V,N_EV,N_EV_havran,N_OIV,N_OIV_havran,N_IT,N_IT_havran,N_TS,"
         "N_TS_havran,N_EETS,N_EETS_havran,N_IT_default_grid,validated_rays",
         recgrids_csv_header},
        {"| scene | cells | N_EV ours / his | N_OIV ours / his | N_IT ours / his | N_TS ours / his "
         "| N_EETS ours / his | N_IT, default grid |\n|---|---|---:|---:|---:|---:|---:|---:|",
         recgrids_table_header},
        grids_of_scene,
        "--grid-kind",
        {"uniform", "recursive"},
        {"Uniform grids (his table \"Uniform Grid\")",
         "Recursive grids (his table \"Recursive Grid\", RHT +: Klimaszewski's rule at every "
         "level)"}};
    return havran_bench_main(argc, argv, &b);
}
