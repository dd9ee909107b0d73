/*
 * bench_recgrids.c — `bspray bench --grids --grid-kind recursive`: Havran's
 * 1999 recursive grids (../shared/reference/havran_stats_grids.txt,
 * "Recursive Grid": Jevans and Wyvill's grids, every level by Klimaszewski's
 * heterogeneous rule, "RHT +") reproduced: for each of his scenes and his two
 * depths, bspray's recursive grid of that many levels at density 1, cells of
 * more than 8 primitives cut (the limit his counts of grids give: docs/grid.md),
 * with his assignment (by bounds) and no mailboxes, validated against the
 * naive method, then a 513 x 513 depth-4 render; his figures beside, and the
 * N_IT of the same grids clipped and with mailboxes.
 */
#include <stdio.h>
#include <string.h>

#include "bench.h"
#include "cli.h"

/* One of his recursive grids (RMD levels, RHT +) and his figures for it. */
typedef struct recgrid_row {
    const char *scene;
    int levels;
    unsigned long nin, nv, nev, noiv; /* his N_IN counts the root grid too */
    double nit, nts, nets, neets;
} recgrid_row;

static const recgrid_row recgrid_rows[] = {
    {"balls", 2, 49, 16821, 8867, 34255, 25.67, 14.29, 11.66, 7.04},
    {"balls", 3, 1531, 38877, 11519, 117525, 16.94, 16.87, 13.02, 7.49},
    {"gears", 2, 1673, 48443, 13694, 313791, 27.18, 11.42, 8.66, 4.36},
    {"gears", 3, 19645, 298119, 17422, 2527805, 27.72, 14.27, 10.03, 4.47},
    {"lattice", 2, 289, 11568, 0, 62836, 34.87, 6.40, 5.30, 0.00},
    {"lattice", 3, 289, 11568, 0, 62836, 34.87, 6.40, 5.30, 0.00},
    {"mount", 2, 1163, 37987, 13215, 185273, 15.97, 11.45, 9.74, 5.08},
    {"mount", 3, 10573, 143477, 16203, 769408, 15.51, 12.42, 10.19, 5.11},
    {"rings", 2, 1369, 28536, 8373, 94511, 30.88, 18.25, 14.72, 7.77},
    {"rings", 3, 2094, 35503, 8895, 113662, 30.46, 18.51, 14.84, 7.80},
    {"teapot", 2, 784, 32372, 15180, 135576, 18.16, 18.75, 16.66, 12.99},
    {"teapot", 3, 6334, 110582, 22961, 691621, 17.53, 19.67, 17.13, 13.09},
    {"tetra", 2, 1057, 31768, 14220, 117056, 21.32, 12.29, 9.97, 6.83},
    {"tetra", 3, 1565, 40404, 14220, 218944, 21.49, 12.34, 10.00, 6.83},
    {"tree", 2, 5, 16818, 11586, 21978, 19.86, 13.65, 12.25, 7.76},
    {"tree", 3, 501, 32376, 19476, 63640, 12.03, 14.62, 12.88, 8.26},
};
#define RECGRID_ROWS (sizeof recgrid_rows / sizeof *recgrid_rows)

const char recgrids_csv_header[] =
    "scene,levels,grids,grids_havran,N_V,N_V_havran,N_EV,N_EV_havran,N_OIV,N_OIV_havran,N_IT,"
    "N_IT_havran,N_TS,N_TS_havran,N_ETS,N_ETS_havran,N_EETS,N_EETS_havran,"
    "N_IT_clipped_mailboxes,validated_rays";
const char recgrids_table_header[] =
    "| scene | levels | grids ours / his | N_V ours / his | N_EV ours / his | N_OIV ours / his "
    "| N_IT ours / his | N_TS ours / his | N_ETS ours / his | N_EETS ours / his "
    "| N_IT, clipped, mailboxes |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|";

/* The recursive grid of ROW over SCENE: his (bounds, no mailboxes) or
 * bspray's (clipped, mailboxes). */
static bsp_accel *row_recgrid(const bsp_scene *scene, const recgrid_row *row, int havrans)
{
    bsp_build_options o;
    bsp_build_options_defaults(&o);
    o.kind = BSP_ACCEL_GRID;
    o.grid_levels = row->levels;
    o.grid_density = 1.0;
    o.grid_cell_prims = 8;
    o.grid_assign_bounds = havrans;
    o.mailbox = !havrans;
    return build_accel(scene, &o);
}

int recgrids_of_scene(const char *bare, const char *name, const bsp_scene *scene,
                      const bsp_accel *naive, void *ctx)
{
    const havran_run *run = ctx;
    for (size_t r = 0; r < RECGRID_ROWS; r++) {
        const recgrid_row *h = &recgrid_rows[r];
        if (strcmp(h->scene, bare) != 0)
            continue;
        if (!run->quiet)
            fprintf(stderr, "%s: %s: recursive grid of %d levels\n", prog, name, h->levels);
        bsp_accel *his = row_recgrid(scene, h, 1), *ours = row_recgrid(scene, h, 0);
        havran_figures f, fo;
        long checked =
            havran_measure_pair(his, ours, naive, name, "recursive grid", run, &f, &fo);
        if (checked >= 0) {
            bsp_tree_stats st;
            bsp_accel_tree_stats(his, &st);
            const unsigned long long grids = (unsigned long long)st.interior_nodes + 1;
            printf("| %s | %d | %llu / %lu | %llu / %lu | %llu / %lu | %llu / %lu | %.2f / %.2f "
                   "| %.2f / %.2f | %.2f / %.2f | %.2f / %.2f | %.2f |\n",
                   h->scene, h->levels, grids, h->nin, (unsigned long long)st.leaves, h->nv,
                   (unsigned long long)st.empty_leaves, h->nev,
                   (unsigned long long)st.references, h->noiv, f.nit, h->nit, f.nts, h->nts,
                   f.nets, h->nets, f.neets, h->neets, fo.nit);
            fflush(stdout);
            if (run->csv)
                fprintf(run->csv,
                        "%s,%d,%llu,%lu,%llu,%lu,%llu,%lu,%llu,%lu,%.4f,%.2f,%.4f,%.2f,%.4f,%.2f,"
                        "%.4f,%.2f,%.4f,%ld\n",
                        h->scene, h->levels, grids, h->nin, (unsigned long long)st.leaves, h->nv,
                        (unsigned long long)st.empty_leaves, h->nev,
                        (unsigned long long)st.references, h->noiv, f.nit, h->nit, f.nts, h->nts,
                        f.nets, h->nets, f.neets, h->neets, fo.nit, checked);
        }
        bsp_accel_destroy(his);
        bsp_accel_destroy(ours);
        if (checked < 0)
            return EXIT_INPUT;
    }
    return 0;
}
