/*
 * bench_octrees.c — `bspray bench --octrees`: Havran's 1999 octree
 * statistics (../shared/reference/havran_stats_octrees.txt) reproduced by
 * one command: for each of his scenes and his four maximum depths (4 to 7),
 * bspray's octree of centre subdivision (--accel octree: primitives listed
 * by their bounds, at most one per leaf or the depth reached, as his were)
 * without mailboxes, on the SPD database generated in code, validated
 * against the naive method, then a 513 x 513 depth-4 render: N_IN, N_V,
 * N_EV, N_OIV, N_IT, N_ETS, N_EETS next to his Octree84-C (Glassner's
 * octree), and the N_IT of the same octree with mailboxes. docs/octree.md
 * discusses the table.
 */
#include <stdio.h>
#include <string.h>

#include "bench.h"
#include "cli.h"

static const char octrees_usage[] =
    "bspray bench --octrees [SCENE...] [--threads N] [--csv FILE] [--quiet]";

/* One of Havran's octrees (Octree84-C: centre subdivision, bounds
 * assignment, at most one primitive per leaf) and his figures for it. */
typedef struct octree_row {
    const char *scene; /* the SPD database */
    int depth;         /* his maximum depth (the root at 0) */
    unsigned long nin, nv, nev, noiv;
    double nit, nts, nets, neets;
} octree_row;

/* His table "Octree84-C", maximum depths 4 to 7 (his FLUID scene is not an
 * SPD database). */
static const octree_row octree_rows[] = {
    {"balls", 4, 57, 400, 300, 9171, 1787.00, 48.53, 9.93, 3.67},
    {"balls", 5, 117, 820, 570, 10946, 577.70, 86.96, 15.39, 9.52},
    {"balls", 6, 304, 2129, 1038, 15611, 209.60, 123.20, 19.88, 12.54},
    {"balls", 7, 1108, 7757, 2905, 27288, 94.75, 167.00, 24.71, 16.12},
    {"gears", 4, 265, 1856, 652, 39440, 157.50, 27.46, 5.71, 2.07},
    {"gears", 5, 1405, 9836, 4088, 85832, 71.38, 46.49, 8.33, 4.64},
    {"gears", 6, 5837, 40860, 10334, 235526, 44.22, 65.25, 10.64, 5.66},
    {"gears", 7, 28447, 199130, 28228, 879434, 39.13, 88.60, 13.20, 6.27},
    {"lattice", 4, 585, 4096, 0, 22112, 28.60, 22.03, 4.41, 0.00},
    {"lattice", 5, 4681, 32768, 7744, 49600, 13.80, 47.88, 7.98, 1.71},
    {"lattice", 6, 17993, 125952, 28732, 147494, 11.07, 67.59, 10.35, 2.91},
    {"lattice", 7, 56235, 393646, 52822, 502272, 10.82, 77.21, 11.36, 3.17},
    {"mount", 4, 232, 1625, 777, 18107, 42.53, 22.43, 4.92, 1.82},
    {"mount", 5, 1019, 7134, 3060, 34351, 23.72, 30.89, 6.08, 2.33},
    {"mount", 6, 4716, 33013, 11720, 90456, 18.30, 43.68, 7.64, 2.83},
    {"mount", 7, 22630, 158411, 45049, 324918, 18.52, 60.08, 9.44, 3.31},
    {"rings", 4, 231, 1618, 416, 22505, 107.80, 32.34, 6.93, 2.91},
    {"rings", 5, 1216, 8513, 2127, 44555, 47.90, 53.74, 9.92, 4.98},
    {"rings", 6, 6925, 48476, 10281, 133929, 35.12, 81.90, 13.38, 6.69},
    {"rings", 7, 38648, 270537, 49888, 565631, 35.20, 120.80, 17.65, 8.29},
    {"teapot", 4, 227, 1590, 777, 18845, 184.00, 33.66, 7.61, 5.14},
    {"teapot", 5, 1001, 7008, 3450, 34072, 78.30, 48.74, 9.73, 7.07},
    {"teapot", 6, 4100, 28701, 12327, 83551, 45.63, 64.67, 11.69, 8.61},
    {"teapot", 7, 18066, 126463, 38316, 295865, 40.02, 83.40, 13.75, 9.53},
    {"tetra", 4, 305, 2136, 1072, 13312, 120.00, 21.54, 4.72, 3.05},
    {"tetra", 5, 1369, 9584, 4764, 32768, 63.58, 32.08, 6.20, 4.48},
    {"tetra", 6, 6189, 43324, 21100, 110592, 46.77, 44.09, 7.67, 5.93},
    {"tetra", 7, 28413, 198892, 80444, 512000, 47.07, 58.09, 9.21, 7.22},
    {"tree", 4, 53, 372, 278, 9029, 8066.00, 63.48, 13.10, 3.67},
    {"tree", 5, 101, 708, 556, 9670, 4201.00, 113.60, 20.24, 9.91},
    {"tree", 6, 186, 1303, 1054, 10915, 2098.00, 169.00, 27.16, 17.67},
    {"tree", 7, 352, 2465, 1801, 13725, 741.30, 219.30, 32.74, 23.33},
};
#define OCTREE_ROWS (sizeof octree_rows / sizeof *octree_rows)

static void print_help(void)
{
    printf("usage: %s\n\n", octrees_usage);
    printf("Havran's octrees (Havran 1999, the companion of his grid statistics) reproduced:\n"
           "for each of his scenes and maximum depths 4 to 7, bspray's octree of centre\n"
           "subdivision (--accel octree --max-depth D: every primitive in each octant its\n"
           "bounds overlap, a leaf at one primitive or at depth D, as his) without mailboxes,\n"
           "on the SPD database generated in code, validated against the naive method, then\n"
           "a 513 x 513 render of ray depth 4. Each figure is printed as ours / his\n"
           "(Octree84-C, Glassner's octree); \"full leaves\" is N_ETS - N_EETS, the\n"
           "non-empty leaves a ray visits; the last column is the N_IT of the same octree\n"
           "with mailboxes. docs/octree.md discusses the table.\n\n"
           "  SCENE...       balls gears lattice mount rings teapot tetra tree (or spd:NAME;\n"
           "                 default: all eight)\n"
           "  --threads N    render threads (default: every core); the counts do not depend\n"
           "                 on it\n"
           "  --csv FILE     also write one CSV row per octree\n"
           "  --quiet        no progress on stderr\n"
           "  --help         this text\n");
}

/* The octree of ROW over SCENE, with or without mailboxes. */
static bsp_accel *row_octree(const bsp_scene *scene, const octree_row *row, int mailbox)
{
    bsp_build_options o;
    bsp_build_options_defaults(&o);
    o.kind = BSP_ACCEL_OCTREE;
    o.max_depth = row->depth;
    o.max_leaf_prims = 1;
    o.mailbox = mailbox;
    return build_accel(scene, &o);
}

/* His four octrees of one scene, ours beside. */
static int octrees_of_scene(const char *bare, const char *name, const bsp_scene *scene,
                            const bsp_accel *naive, void *ctx)
{
    const havran_run *run = ctx;
    for (size_t r = 0; r < OCTREE_ROWS; r++) {
        const octree_row *h = &octree_rows[r];
        if (strcmp(h->scene, bare) != 0)
            continue;
        if (!run->quiet)
            fprintf(stderr, "%s: %s: octree of depth %d\n", prog, name, h->depth);
        bsp_accel *plain = row_octree(scene, h, 0), *mb = row_octree(scene, h, 1);
        havran_figures f, fm;
        long checked =
            havran_measure_pair(plain, mb, naive, name, "octree", run->threads, &f, &fm);
        if (checked >= 0) {
            bsp_tree_stats st;
            bsp_accel_tree_stats(plain, &st);
            printf("| %s | %d | %llu / %lu | %llu / %lu | %llu / %lu | %llu / %lu | %.2f / %.2f "
                   "| %.2f / %.2f | %.2f / %.2f | %.2f / %.2f | %.2f |\n",
                   h->scene, h->depth, (unsigned long long)st.interior_nodes, h->nin,
                   (unsigned long long)st.leaves, h->nv, (unsigned long long)st.empty_leaves,
                   h->nev, (unsigned long long)st.references, h->noiv, f.nit, h->nit,
                   f.nets - f.neets, h->nets - h->neets, f.nets, h->nets, f.neets, h->neets,
                   fm.nit);
            fflush(stdout);
            if (run->csv)
                fprintf(run->csv,
                        "%s,%d,%llu,%lu,%llu,%lu,%llu,%lu,%llu,%lu,%.4f,%.2f,%.4f,%.2f,%.4f,%.2f,"
                        "%.4f,%.2f,%.4f,%ld\n",
                        h->scene, h->depth, (unsigned long long)st.interior_nodes, h->nin,
                        (unsigned long long)st.leaves, h->nv,
                        (unsigned long long)st.empty_leaves, h->nev,
                        (unsigned long long)st.references, h->noiv, f.nit, h->nit, f.nts, h->nts,
                        f.nets, h->nets, f.neets, h->neets, fm.nit, checked);
        }
        bsp_accel_destroy(plain);
        bsp_accel_destroy(mb);
        if (checked < 0)
            return EXIT_INPUT;
    }
    return 0;
}

int bench_octrees(int argc, char **argv)
{
    static const havran_bench b = {
        octrees_usage,
        "--octrees",
        print_help,
        "scene,depth,N_IN,N_IN_havran,N_V,N_V_havran,N_EV,N_EV_havran,N_OIV,N_OIV_havran,N_IT,"
        "N_IT_havran,N_TS,N_TS_havran,N_ETS,N_ETS_havran,N_EETS,N_EETS_havran,N_IT_mailboxes,"
        "validated_rays",
        "| scene | depth | N_IN ours / his | N_V ours / his | N_EV ours / his | N_OIV ours / his "
        "| N_IT ours / his | full leaves ours / his | N_ETS ours / his | N_EETS ours / his "
        "| N_IT, mailboxes |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
        octrees_of_scene};
    return havran_bench_main(argc, argv, &b);
}
