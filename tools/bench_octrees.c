/*
 * bench_octrees.c — `bspray bench --octrees`: Havran's 1999 octree
 * statistics (../shared/reference/havran_stats_octrees.txt) reproduced by
 * one command: for each of his scenes and his four maximum depths (4 to 7),
 * bspray's octree (--accel octree: primitives listed by their bounds, at
 * most one per leaf or the depth reached, as his were) without mailboxes,
 * on the SPD database generated in code, validated against the naive
 * method, then a 513 x 513 depth-4 render: N_IN, N_V, N_EV, N_OIV, N_IT,
 * N_ETS, N_EETS next to his, and the N_IT of the same octree with
 * mailboxes. The octree of centre subdivision is set beside his Octree84-C
 * (Glassner's octree), with --octree-split cost the adaptive one beside his
 * Octree84-A. docs/octree.md discusses the tables.
 */
#include <stdio.h>
#include <string.h>

#include "bench.h"
#include "cli.h"

static const char octrees_usage[] = "bspray bench --octrees [SCENE...] [--octree-split "
                                    "centre|cost] [--res N] [--threads N] [--csv FILE] [--quiet]";

/* One of Havran's octrees (bounds assignment, at most one primitive per
 * leaf) and his figures for it. */
typedef struct octree_row {
    const char *scene; /* the SPD database */
    int depth;         /* his maximum depth (the root at 0) */
    unsigned long nin, nv, nev, noiv;
    double nit, nts, nets, neets;
} octree_row;

/* His table "Octree84-C" (centre subdivision), maximum depths 4 to 7 (his
 * FLUID scene is not an SPD database). */
static const octree_row centre_rows[] = {
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
/* His table "Octree84-A" (each node cut by his cost estimate), the same. */
static const octree_row cost_rows[] = {
    {"balls", 4, 131, 918, 214, 10160, 81.20, 27.73, 6.63, 3.23},
    {"balls", 5, 661, 4628, 1202, 16289, 28.62, 40.09, 8.35, 4.62},
    {"balls", 6, 3077, 21540, 4233, 42107, 16.29, 52.18, 9.83, 5.48},
    {"balls", 7, 15283, 106982, 14059, 172506, 14.85, 64.91, 11.21, 6.00},
    {"gears", 4, 349, 2444, 580, 31144, 68.78, 23.50, 5.15, 2.60},
    {"gears", 5, 1709, 11964, 1120, 95016, 41.18, 31.33, 6.18, 2.69},
    {"gears", 6, 10301, 72108, 5300, 344580, 29.43, 46.99, 8.11, 2.92},
    {"gears", 7, 59649, 417544, 20092, 1737482, 30.75, 66.50, 10.24, 3.24},
    {"lattice", 4, 585, 4096, 0, 18768, 24.00, 22.33, 4.47, 0.00},
    {"lattice", 5, 4681, 32768, 7133, 42789, 9.97, 46.89, 7.82, 2.65},
    {"lattice", 6, 18218, 127527, 33332, 121693, 6.71, 62.82, 9.73, 4.55},
    {"lattice", 7, 45496, 318473, 34508, 467745, 6.73, 64.34, 9.87, 4.60},
    {"mount", 4, 312, 2185, 866, 21489, 31.38, 22.61, 4.86, 1.99},
    {"mount", 5, 1534, 10739, 3615, 47351, 17.58, 29.26, 5.77, 2.51},
    {"mount", 6, 7893, 55252, 14018, 150938, 14.00, 38.53, 6.90, 2.91},
    {"mount", 7, 42826, 299783, 41862, 692664, 15.77, 51.66, 8.34, 3.14},
    {"rings", 4, 347, 2430, 406, 20867, 58.00, 30.24, 6.58, 3.39},
    {"rings", 5, 2055, 14386, 1718, 54320, 32.11, 44.74, 8.55, 3.92},
    {"rings", 6, 12898, 90287, 10688, 210965, 26.16, 70.31, 11.67, 5.01},
    {"rings", 7, 73091, 511638, 41430, 1175184, 31.31, 103.40, 15.29, 5.84},
    {"teapot", 4, 330, 2311, 853, 25332, 106.30, 35.82, 8.02, 5.65},
    {"teapot", 5, 1703, 11922, 3462, 59058, 51.53, 49.20, 9.87, 6.77},
    {"teapot", 6, 9055, 63386, 14005, 199511, 36.74, 63.93, 11.66, 7.69},
    {"teapot", 7, 49691, 347838, 49218, 922951, 37.72, 81.95, 13.63, 8.33},
    {"tetra", 4, 325, 2276, 1116, 13792, 99.56, 21.15, 4.68, 3.40},
    {"tetra", 5, 1485, 10396, 5432, 34304, 45.46, 27.69, 5.56, 4.48},
    {"tetra", 6, 6449, 45144, 20976, 120336, 23.03, 33.72, 6.26, 5.33},
    {"tetra", 7, 30617, 214320, 77992, 587888, 25.08, 39.05, 6.82, 5.70},
    {"tree", 4, 71, 498, 231, 9489, 236.40, 31.83, 8.38, 5.34},
    {"tree", 5, 278, 1947, 837, 11352, 66.88, 37.13, 9.13, 6.01},
    {"tree", 6, 1130, 7911, 3511, 17245, 30.99, 42.18, 9.75, 6.64},
    {"tree", 7, 4300, 30101, 11205, 44516, 24.33, 45.84, 10.16, 6.95},
};
#define OCTREE_ROWS (sizeof centre_rows / sizeof *centre_rows)
_Static_assert(sizeof cost_rows == sizeof centre_rows, "one row per scene and depth in each");

static void print_help(void)
{
    printf("usage: %s\n\n", octrees_usage);
    printf("Havran's octrees (Havran 1999, the companion of his grid statistics) reproduced:\n"
           "for each of his scenes and maximum depths 4 to 7, bspray's octree (--accel octree\n"
           "--max-depth D: every primitive in each octant its bounds overlap, a leaf at one\n"
           "primitive or at depth D, as his) without mailboxes, on the SPD database generated\n"
           "in code, validated against the naive method, then a 513 x 513 render of ray depth\n"
           "4. Each figure is printed as ours / his; \"full leaves\" is N_ETS - N_EETS, the\n"
           "non-empty leaves a ray visits; the last column is the N_IT of the same octree\n"
           "with mailboxes. docs/octree.md discusses the tables.\n\n"
           "  SCENE...       balls gears lattice mount rings teapot tetra tree (or spd:NAME;\n"
           "                 default: all eight)\n"
           "  --octree-split centre|cost  the octree of centre subdivision beside his\n"
           "                 Octree84-C (Glassner's; default), or the adaptive one, cut by\n"
           "                 his cost estimate, beside his Octree84-A\n"
           "  --res N        render N x N rays (default 513, his protocol; at another size\n"
           "                 the per-ray figures do not compare with his, the structure's do)\n"
           "  --threads N    render threads (default: every core); the counts do not depend\n"
           "                 on it\n"
           "  --csv FILE     also write one CSV row per octree\n"
           "  --quiet        no progress on stderr\n"
           "  --help         this text\n");
}

/* The octree of ROW over SCENE, cut by SPLIT, with or without mailboxes. */
static bsp_accel *row_octree(const bsp_scene *scene, const octree_row *row,
                             bsp_octree_split split, int mailbox)
{
    bsp_build_options o;
    bsp_build_options_defaults(&o);
    o.kind = BSP_ACCEL_OCTREE;
    o.octree_split = split;
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
    bsp_octree_split split = run->variant ? BSP_OCTREE_COST : BSP_OCTREE_CENTRE;
    const octree_row *rows = run->variant ? cost_rows : centre_rows;
    for (size_t r = 0; r < OCTREE_ROWS; r++) {
        const octree_row *h = &rows[r];
        if (strcmp(h->scene, bare) != 0)
            continue;
        if (!run->quiet)
            fprintf(stderr, "%s: %s: octree of depth %d\n", prog, name, h->depth);
        bsp_accel *plain = row_octree(scene, h, split, 0), *mb = row_octree(scene, h, split, 1);
        havran_figures f, fm;
        long checked =
            havran_measure_pair(plain, mb, naive, name, "octree", run, &f, &fm);
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
                        "%.4f,%.2f,%.4f,%ld,%s\n",
                        h->scene, h->depth, (unsigned long long)st.interior_nodes, h->nin,
                        (unsigned long long)st.leaves, h->nv,
                        (unsigned long long)st.empty_leaves, h->nev,
                        (unsigned long long)st.references, h->noiv, f.nit, h->nit, f.nts, h->nts,
                        f.nets, h->nets, f.neets, h->neets, fm.nit, checked,
                        run->variant ? "cost" : "centre");
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
        {"scene,depth,N_IN,N_IN_havran,N_V,N_V_havran,N_EV,N_EV_havran,N_OIV,N_OIV_havran,N_IT,"
         "N_IT_havran,N_TS,N_TS_havran,N_ETS,N_ETS_havran,N_EETS,N_EETS_havran,N_IT_mailboxes,"
         "validated_rays,split",
         NULL},
        {"| scene | depth | N_IN ours / his | N_V ours / his | N_EV ours / his | N_OIV ours / his "
         "| N_IT ours / his | full leaves ours / his | N_ETS ours / his | N_EETS ours / his "
         "| N_IT, mailboxes |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
         NULL},
        octrees_of_scene,
        "--octree-split",
        {"centre", "cost"},
        {"Octree84-C: centre subdivision (his Glassner 1984 octree)",
         "Octree84-A: each node cut by his cost estimate (Octree-R, after MacDonald and Booth)"}};
    return havran_bench_main(argc, argv, &b);
}
