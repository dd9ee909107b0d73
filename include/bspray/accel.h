/*
 * bspray/accel.h — acceleration structures for ray shooting and the queries
 * on them: closest hit and any hit (point-to-point visibility).
 *
 * Life cycle: bsp_accel_build borrows a scene (which must outlive the
 * structure) and returns an immutable structure that any number of threads
 * may query at once. Everything a query changes (mailbox stamps, counters)
 * lives in a bsp_query, one per thread.
 *
 * Exactness contract: every method returns, for every ray, the same closest
 * primitive and a bit-identical t as the naive method (ties at equal t go to
 * the lowest primitive index), and the same occlusion answer.
 */
#ifndef BSPRAY_ACCEL_H
#define BSPRAY_ACCEL_H

#include <stddef.h>
#include <stdint.h>

#include "bspray/error.h"
#include "bspray/geom.h"
#include "bspray/scene.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct bsp_accel bsp_accel;
typedef struct bsp_query bsp_query;

typedef enum bsp_accel_kind {
    BSP_ACCEL_NAIVE = 0, /* test every primitive: O(N) per ray, the reference */
    BSP_ACCEL_KAPLAN,    /* kd-tree, Kaplan's rule: spatial median, axes x, y, z in turn */
    BSP_ACCEL_SAH,       /* kd-tree, surface area heuristic (MacDonald & Booth), exact
                            O(N log N) build with perfect splits (Wald & Havran 2006) */
    BSP_ACCEL_SAH_PER,   /* kd-tree, the paper's modified SAH for rays from one eye
                            (perspective): probability = projected area clipped to the
                            viewport; see bsp_view */
    BSP_ACCEL_SAH_PAR,   /* kd-tree, modified SAH for rays of one direction (parallel
                            projection): projected area along it, clipped to the window */
    BSP_ACCEL_SAH_MIXED, /* kd-tree, SAH whose probability mixes the PER measure (primary
                            rays) and the surface area (all other rays) by their share */
    BSP_ACCEL_GRID,      /* uniform grid (Fujimoto et al. 1986), traversed by a 3D-DDA
                            (Amanatides & Woo 1987): the classic baseline of Havran's
                            grid statistics; see bsp_build_options.grid_density; or,
                            with grid_levels > 1, a recursive grid (Jevans and Wyvill
                            1989) */
    BSP_ACCEL_OCTREE,    /* octree (Glassner 1984), kept as a kd-tree of three levels
                            per octree node and traversed as one; primitives listed by
                            their bounds, as in Havran's 1999 octree statistics; cut
                            at the centre or by a cost estimate (octree_split).
                            max_depth counts octree levels */
    BSP_ACCEL_BVH,       /* bounding volume hierarchy: binary, object partitioning, binned
                            SAH (Wald 2007) with the kd-trees' per-kind costs T_i and
                            C_trav twice theirs (sah_costs.traversal, default 1);
                            the structure most ray tracers use, for comparison.
                            Threads as the sah family's; max_leaf_prims (default 8) and max_depth
                            (default and at most 60) bound its leaves, which may
                            exceed max_leaf_prims only where their centroids
                            coincide; the mailbox does not apply */
    BSP_ACCEL_BVH4,      /* the same BVH collapsed to four children per node (Embree's
                            layout), whose four boxes a ray tests at once in float
                            SIMD lanes; exact like every structure here */
    BSP_ACCEL_BVH8,      /* ... to eight children per node (what Embree builds for
                            triangles on CPUs with AVX), their boxes tested four at
                            a time in float SIMD lanes */
    BSP_ACCEL_KIND_COUNT
} bsp_accel_kind;

/* The grid's default cells per primitive, its most cells per axis, and its
 * most cells in all (a finer grid is coarsened to fit, keeping its shape). */
#define BSP_GRID_DEFAULT_DENSITY 4.0
#define BSP_GRID_MAX_RES 4096
#define BSP_GRID_MAX_CELLS ((uint64_t)1 << 27)
/* A recursive grid's most nested grids, and the default primitives a cell
 * may list before a subgrid cuts it. */
#define BSP_GRID_MAX_LEVELS 8
#define BSP_GRID_DEFAULT_CELL_PRIMS 8

/* Hard ceiling of kd-tree depth (it sizes the traversal stack). */
#define BSP_KD_MAX_DEPTH_LIMIT 64
/* The octree's deepest level: three kd levels each, within that ceiling. */
#define BSP_OCTREE_MAX_DEPTH 21

/* Costs of the SAH cost model (MacDonald & Booth): a split costs
 * traversal + (A_L/A) sum T_i(L) + (A_R/A) sum T_i(R), a leaf sum T_i, where
 * T_i is the intersection cost of primitive i by its kind. Any unit (only
 * ratios matter); bsp_calibrate_costs measures them in nanoseconds. In build
 * options a field 0 means the default (measured on the development machine,
 * see src/accel/kd_cost.c). */
/* The range of a cost (relative to one traversal step) the builders use; a
 * cost outside it is clamped to it (0, negative or non-finite: the default).
 * Beyond it the SAH's sums overflow or vanish. */
#define BSP_SAH_COST_MIN 1e-6
#define BSP_SAH_COST_MAX 1e6

typedef struct bsp_sah_costs {
    double traversal;      /* C_trav: one traversal step */
    double sphere;         /* one ray-sphere test */
    double triangle;       /* one ray-triangle test (also 3-vertex polygons, patches) */
    double polygon_base;   /* a polygon with n >= 4 vertices costs */
    double polygon_vertex; /*   polygon_base + polygon_vertex * n (n >= 9: n is the
                                edges its test visits, fewer: docs/kdtree.md) */
    double cone;           /* one ray-cone (cylinder) test */
} bsp_sah_costs;

/* The restricted ray set of sah-per, sah-par and sah-mixed: the camera the
 * tree is built for. With explicit == 0 it is the scene's own camera (NFF
 * from/at/up/angle/resolution, SPD protocol: the angle spans the first to
 * the last of res+1 rays); bsp_accel_build fails when the scene has none. */
typedef struct bsp_view {
    int explicit_view;  /* 1: the fields below; 0: the scene's camera */
    bsp_vec3 eye;       /* PER: the rays' common origin. PAR: the centre of the window,
                           on the plane the rays start from */
    bsp_vec3 dir;       /* the view direction (PAR: the rays' common direction) */
    bsp_vec3 up;        /* not parallel to dir */
    double fov_deg;     /* PER: full horizontal angle from the first to the last ray */
    int width, height;  /* rays across and down (only the ratio matters) */
    double ortho_width; /* PAR: the window's width in scene units; 0: the width of the
                           perspective view at the look-at point, 2 tan(fov/2) |at - eye|
                           (for an explicit view |dir| stands for |at - eye|) */
} bsp_view;

/* sah-mixed: how the rays other than the primary ones are modelled. */
typedef enum bsp_mixed_model {
    /* as uniformly distributed lines through the scene's box: the surface
       area (the SAH's own assumption) */
    BSP_MIXED_SURFACE = 0,
    /* by where they actually run: their density, sampled from the pre-pass's
       shadow and secondary rays on a voxel grid (docs/modified-sah.md) */
    BSP_MIXED_SAMPLED = 1,
    /* by where they actually run: the number of the pre-pass's shadow and
       secondary rays that meet each box, counted exactly (docs/modified-sah.md) */
    BSP_MIXED_COUNTED = 2
} bsp_mixed_model;

/* Where an octree node is cut (bsp_build_options.octree_split). */
typedef enum bsp_octree_split {
    /* at the centre of its box on each axis: eight equal octants (Glassner
       1984; Havran's Octree84-C) */
    BSP_OCTREE_CENTRE = 0,
    /* on each axis at the least of a cost estimate over ten positions from the
       box's centre to the median of its primitives' centres (Whang et al.'s
       Octree-R 1995 after MacDonald and Booth 1990; Havran's Octree84-A;
       docs/octree.md) */
    BSP_OCTREE_COST = 1
} bsp_octree_split;

/* Build options; always start from bsp_build_options_defaults(). */
typedef struct bsp_build_options {
    bsp_accel_kind kind;
    int mailbox;        /* 1: test each primitive at most once per ray (default 1) */
    int max_depth;      /* kd-trees: deepest leaf, 1..BSP_KD_MAX_DEPTH_LIMIT; 0: the
                           method's default (kaplan: 18, the paper's value). octree:
                           its levels, 1..BSP_OCTREE_MAX_DEPTH (0: the default,
                           by the primitive count: docs/octree.md) */
    int max_leaf_prims; /* kd-trees: a node with at most this many primitives becomes a
                           leaf; 0: the method's default (kaplan: 2, the paper's value;
                           octree: 1, Havran's) */
                        /* sah: max_depth 0 means round(8 + 1.3 log2 N), max_leaf_prims 0
                           means 1 (the cost decides); the paper's setting is 18 and 2 */
    bsp_sah_costs sah_costs; /* sah: cost model; 0 fields take the defaults */
    double sah_empty_bonus;  /* sah: a split with one empty side costs (1 - bonus) times
                                its cost; 0: the default (0.1), negative: no bonus */
    double sah_min_saving;   /* sah family: a split that pays is made only when it saves
                                at least this many mean intersection tests per ray: its
                                cell's surface area over the root's, times its cost below
                                the leaf's, over the mean T_i. 0: the default (1e-9,
                                which prunes the chains of tiny cells around shared
                                vertices; docs/kdtree.md), negative: none */
    double sah_leaf_budget;  /* sah family: a tree of more than this many leaves per
                                primitive (and more than sah_leaf_budget_min) loses
                                the splits that save least until it has no more
                                (docs/kdtree.md). 0: the default, negative: no budget */
    size_t sah_leaf_budget_min; /* sah family: the budget is never below this many
                                   leaves (0: the default, 131072: 2 MiB of nodes) */
    double sah_budget_cut;   /* sah family with a leaf budget: the budget's threshold is
                                estimated from a sample of subtrees, and the splits that
                                save less than this share of the estimate are not made
                                (docs/kdtree.md). Any value builds the same tree: a
                                share too high only costs a second build, one too low
                                saves less. 0: the default (0.75), negative: no
                                estimate (the whole tree is built, then pruned) */
    int sah_split_to_limits; /* sah family: 1 splits every node until max_depth or
                                max_leaf_prims ends it (the paper's termination criteria);
                                0 (default): also a leaf when the best split does not pay */
    int sah_straddle_twice;  /* sah family: 1 charges a primitive that straddles a split
                                in full in both children, also for the rays through both
                                (MacDonald and Booth's plain model); 0 (default): its
                                second test is charged as a mailbox hit — with or without
                                mailboxes, whose trees it makes faster too (docs/kdtree.md) */
    bsp_view view;           /* sah-per, sah-par, sah-mixed: the camera (default: the scene's) */
    double mixed_primary_share; /* sah-mixed: primary rays / all rays of the render, in
                                   (0, 1]; 0: measured by a 65 x 65 pre-pass of the Whitted
                                   renderer (depth 4) from the view */
    int threads;             /* sah family, bvh, bvh4, bvh8: build threads; 0: every
                                online core. The tree is the same for any count */
    bsp_mixed_model mixed_model; /* sah-mixed: the model of the non-primary rays (default
                                    BSP_MIXED_COUNTED) */
    int mixed_check; /* sah-mixed: 1 (default) also builds the plain sah tree of the same
                        options, measures both on the rays of a 64 x 64 render of the view
                        and keeps the cheaper (bsp_accel_mixed_check); 0 keeps the
                        sah-mixed tree whatever it costs */
    size_t max_tree_bytes; /* kd-trees, grids, BVHs: the most bytes the nodes (cells) and
                              leaf references may take; a build that needs more fails
                              with BSP_ERR_LIMIT (deep trees of overlapping primitives
                              grow as 2^depth). naive: where its blocks (docs/naive.md)
                              would take more, it scans by the scalar loop instead.
                              0 (default): half the machine's physical memory */
    double grid_density;   /* grid: about this many cells per primitive, cubic cells over
                              the scene's box (each axis at least 1 cell); 0: the default
                              (BSP_GRID_DEFAULT_DENSITY) */
    int grid_res[3];       /* grid: the cells per axis, overriding grid_density when all
                              three are > 0 (each at most BSP_GRID_MAX_RES) */
    int grid_assign_bounds; /* grid: 0 (default) lists a primitive in the cells its part
                              reaches (clipped to each cell, as the kd-trees' perfect
                              splits); 1 in every cell its bounds overlap (padded), as
                              Havran's 1999 grids did */
    bsp_octree_split octree_split; /* octree: where a node is cut (default
                              BSP_OCTREE_CENTRE) */
    int grid_levels;       /* grid: 1 (0: the default) a uniform grid; L > 1 a recursive
                              grid (Jevans and Wyvill 1989) of at most L grids nested: a
                              cell listing more than grid_cell_prims primitives (and
                              fewer than its grid) gets a grid of its own over its box;
                              every grid's resolution about grid_density cells per
                              primitive it holds, by Klimaszewski's heterogeneous rule
                              (docs/grid.md). At most BSP_GRID_MAX_LEVELS */
    int grid_cell_prims;   /* recursive grid: a cell listing more primitives than this is
                              cut by a subgrid; 0: the default
                              (BSP_GRID_DEFAULT_CELL_PRIMS) */
    void (*progress)(double done, void *ctx); /* NULL (default), or called now and then on
                              the thread that calls bsp_accel_build with the share of the
                              tree built, in [0, 1], and with 1 when the build is done.
                              The sah family reports as its subtrees (about a hundred)
                              are built, a recursive grid as its grids are filled; a build that makes a second tree (sah-mixed's
                              check, a leaf budget's estimate found too high) may report
                              from 0 again */
    void *progress_ctx;    /* passed to progress */
} bsp_build_options;

void bsp_build_options_defaults(bsp_build_options *opts);

/* What sah-mixed's check against sah found (bsp_build_options.mixed_check). */
typedef struct bsp_mixed_check {
    int ran;           /* 1: the check ran (sah-mixed with mixed_check) */
    int kept_sah;      /* 1: the plain sah tree measured cheaper and was kept */
    uint64_t rays;     /* rays of the check's render */
    double cost_mixed; /* estimated cost per ray of the sah-mixed tree, in traversal steps:
                          C_trav steps + T tests + T_mb mailbox hits, T the mean T_i */
    double cost_sah;   /* the same for the plain sah tree */
} bsp_mixed_check;

/* The check of a sah-mixed accelerator (all zero for other methods). */
void bsp_accel_mixed_check(const bsp_accel *accel, bsp_mixed_check *out);

/* Measures on this machine, on synthetic random rays, the time in ns of one
 * ray-primitive test per kind (polygons as polygon_base + polygon_vertex * n,
 * fitted over several vertex counts) and of one kd-tree traversal step.
 * Takes one to two seconds; on a busy machine results vary between runs. */
bsp_status bsp_calibrate_costs(bsp_sah_costs *ns_out, bsp_error *err);

/* "naive", ...; NULL for an unknown kind. */
const char *bsp_accel_kind_name(bsp_accel_kind kind);
/* Parses a name; returns BSP_ERR_INVALID (with the list of known names in
 * ERR) for an unknown one. */
bsp_status bsp_accel_kind_parse(const char *name, bsp_accel_kind *kind, bsp_error *err);

/* Builds a structure over SCENE (borrowed; must outlive it). OPTS may be
 * NULL for the defaults. On success *OUT owns the structure. */
bsp_status bsp_accel_build(const bsp_scene *scene, const bsp_build_options *opts,
                           bsp_accel **out, bsp_error *err);
void bsp_accel_destroy(bsp_accel *accel);
const bsp_scene *bsp_accel_scene(const bsp_accel *accel);
bsp_accel_kind bsp_accel_get_kind(const bsp_accel *accel);
/* The options ACCEL was built with into *OUT, with what its build chose
 * for a 0 filled in (a kd-tree's or octree's max_depth and max_leaf_prims);
 * for a loaded tree, the saved ones (bsp_accel_load), the rest the
 * defaults. */
void bsp_accel_get_options(const bsp_accel *accel, bsp_build_options *out);
/* Seconds spent in bsp_accel_build (for a loaded tree: in bsp_accel_load). */
double bsp_accel_build_seconds(const bsp_accel *accel);

/* A built kd-tree as a file, so that a large scene's tree is built once and
 * loaded in later runs (docs/formats.md, "kd-tree files"): its nodes and leaf
 * lists, the options that shaped it (method, limits, resolved cost model,
 * mailboxes) and a fingerprint of the scene's primitives, checksummed.
 * Writes PATH whole or not at all (through a temporary file beside it).
 * BSP_ERR_INVALID for the naive method (no structure), BSP_ERR_IO when PATH
 * cannot be written. */
bsp_status bsp_accel_save(const bsp_accel *accel, const char *path, bsp_error *err);
/* Loads a tree that bsp_accel_save wrote over SCENE (borrowed; must outlive
 * it), which must have the very primitives it was built over (checked by
 * their count and fingerprint). The file is checked whole before it is used:
 * size, checksum, every node's indices and leaf range, every reference a
 * live primitive of SCENE, each node reached once, depths within the limit,
 * planes inside their cells. So no file can make a query crash or loop; that
 * every leaf lists the primitives it must is what bsp_accel_check verifies,
 * which costs about a build (a file bsp_accel_save wrote passes it).
 * Errors name PATH: BSP_ERR_IO (cannot read), BSP_ERR_PARSE (not a tree file,
 * another format version, damaged), BSP_ERR_INVALID (another scene),
 * BSP_ERR_NOMEM. The options of the result (bsp_accel_get_kind, the cost
 * model of bsp_accel_tree_stats) are the saved ones; bsp_accel_mixed_check
 * gives zeros. */
bsp_status bsp_accel_load(const bsp_scene *scene, const char *path, bsp_accel **out,
                          bsp_error *err);

/* Figures of a built tree, with Havran's names (all 0 for the naive method). */
typedef struct bsp_tree_stats {
    uint64_t interior_nodes; /* N_IN (an octree: its nodes of eight children, each three
                                kd nodes; its leaf depths count octree levels too) */
    uint64_t leaves;         /* N_V */
    uint64_t empty_leaves;   /* N_EV */
    uint64_t references;     /* N_OIV: primitive references in leaves */
    int max_leaf_depth;
    double avg_leaf_depth;
    uint64_t bytes;       /* nodes + leaf index lists */
    uint64_t trace_bytes; /* kd-tree: the traversal's copies, beside bytes: the
                             primitives in leaf order, its leaf lists in that
                             numbering, and the nodes with empty-child flags */
    int grid_res[3];      /* grid: its cells per axis (N_V is their product); else 0 */
    double expected_cost; /* SAH cost of the finished tree (traversal 1, intersection 1);
                             NaN for a grid (expected_cost and model_cost are the
                             kd-trees' cost model) */
    double model_cost;    /* the same under the build's cost model: C_trav per interior
                             node, T_i per reference (bsp_build_options.sah_costs resolved:
                             the calibrated defaults where 0, also for kaplan), surface
                             area, without the mailbox term; in units of C_trav */
    double budget_cut;    /* sah with a leaf budget (bsp_build_options.sah_leaf_budget):
                             the splits saving less than this (per ray of the root, in
                             units of C_trav) were not made, the budget's estimate
                             having shown that the budget prunes them; 0: none */
    int budget_rebuilt;   /* 1: that estimate proved too high and the tree was built
                             again without it */
    uint64_t digest;      /* a 64-bit FNV-1a hash of the nodes (in array order) and the
                             leaf lists: two builds with equal digests made the same tree
                             bit for bit (thread counts, options, versions compared) */
} bsp_tree_stats;

void bsp_accel_tree_stats(const bsp_accel *accel, bsp_tree_stats *stats);

/* Checks the structure's invariants (child indices in range, split planes
 * inside their cells, depth within the limit, every primitive whose part
 * inside a leaf's cell — its padded bounds clipped to the cell — overlaps
 * that cell listed in that leaf). BSP_OK, or BSP_ERR_INVALID with the first
 * violation in ERR. */
bsp_status bsp_accel_check(const bsp_accel *accel, bsp_error *err);

/* One cell of a kd-tree, as bsp_accel_visit_cells reports it. */
typedef struct bsp_cell_info {
    bsp_box box;     /* the cell */
    int depth;       /* the root is 0 */
    int is_leaf;     /* 0 also for an interior node at the visit's depth limit */
    unsigned axis;   /* interior: the splitting plane's axis (0 x, 1 y, 2 z) */
    double split;    /* interior: the plane's coordinate */
    uint64_t refs;   /* primitive references in the leaves of this subtree */
} bsp_cell_info;

/* Calls VISIT for every node of a kd-tree in depth-first order (a node
 * before its children, left before right), not descending below depth
 * MAX_DEPTH (negative: the whole tree). VISIT returns 0 to skip the node's
 * children. Nothing is visited for the naive method. A grid is visited as a
 * tree of two levels: its box (depth 0, not a leaf, with its low x face as
 * the "split"), then each plane between cells spanning the box (depth 1,
 * not a leaf), then each cell (depth 1, a leaf; in x, then y, then z order).
 * A recursive grid's cells cut by a grid of their own are not leaves and
 * are not visited; after the root grid, each such grid, in the order they
 * were made (breadth first), is visited the same way one level deeper (its
 * planes spanning its box, then its uncut cells).
 * Returns BSP_ERR_NOMEM when out of memory, else BSP_OK. */
bsp_status bsp_accel_visit_cells(const bsp_accel *accel, int max_depth,
                                 int (*visit)(const bsp_cell_info *cell, void *ctx), void *ctx,
                                 bsp_error *err);

/* Per-query counters, accumulated over every call made with one bsp_query. */
typedef struct bsp_query_counters {
    uint64_t rays;            /* queries made */
    uint64_t isect_tests;     /* ray-primitive tests (N_IT numerator) */
    uint64_t traversal_steps; /* nodes visited (N_TS numerator) */
    uint64_t leaves_visited;  /* N_ETS numerator */
    uint64_t empty_leaves;    /* N_EETS numerator */
    uint64_t mailbox_hits;    /* leaf entries not tested: tested before with the same ray
                                 (mailbox), the ray's origin primitive
                                 (bsp_intersect_from), or, without mailboxes, the
                                 primitive of the closest hit so far */
} bsp_query_counters;

/* *SUM += *C, field by field (summing the counters of several queries). */
void bsp_query_counters_add(bsp_query_counters *sum, const bsp_query_counters *c);

/* Per-thread query state for ACCEL (borrowed). NULL when out of memory. */
bsp_query *bsp_query_create(const bsp_accel *accel);
void bsp_query_destroy(bsp_query *query);
const bsp_query_counters *bsp_query_get_counters(const bsp_query *query);
void bsp_query_reset_counters(bsp_query *query);

/* Closest hit on RAY within [tmin, tmax]. Returns 1 and fills *HIT, or 0 and
 * sets hit->prim = BSP_NO_PRIM. Every method returns the naive method's
 * answer for every ray: a kd-tree takes the naive loop itself for a ray
 * whose origin lies over 10^6 scene scales away or whose direction is
 * shorter than 1e-100 or longer than 1e100, where its traversal could not
 * place points to within its padding. A hit is reported only where the
 * ray's point at t lies on the primitive (to within 2.5e-8 scene scales):
 * a ray almost in a triangle's plane, a line passing a cone by a hair or a
 * tangent from a sphere's surface can make the intersection arithmetic
 * claim a hit elsewhere, and every method refuses it alike (outside the
 * range above no such check is made). t is measured in lengths of the
 * direction: keep |dir| within [1e-100, 1e100] (and the origin within the
 * scene coordinates' range), or a hit's t can overflow to inf (`bspray trace`
 * refuses such rays). */
int bsp_intersect(const bsp_accel *accel, bsp_query *query, const bsp_ray *ray, bsp_hit *hit);

/* Any hit on RAY within [tmin, tmax]: 1 when something blocks the segment. */
int bsp_occluded(const bsp_accel *accel, bsp_query *query, const bsp_ray *ray);

/* The same queries for a ray that leaves the surface of primitive FROM:
 * FROM is left out, never tested (BSP_NO_PRIM, or an index of no primitive:
 * nothing is left out). Every method leaves it out alike, so the answers
 * are still the naive method's for the same FROM. Meant for rays that start
 * on FROM and cannot meet it again: a ray leaving a planar primitive (a
 * triangle, polygon or patch), or leaving a sphere or cone on the outer side
 * of its surface. For those it spares a test (one per shadow or secondary
 * ray: lattice's render makes 5.11 tests per ray instead of 5.91) and any
 * self-hit that rounding could report. The renderer casts its shadow and
 * secondary rays this way where that holds. */
int bsp_intersect_from(const bsp_accel *accel, bsp_query *query, const bsp_ray *ray,
                       uint32_t from, bsp_hit *hit);
int bsp_occluded_from(const bsp_accel *accel, bsp_query *query, const bsp_ray *ray,
                      uint32_t from);

/* Batches: the N queries of RAYS[0..N) on THREADS threads (0 or less: every
 * core), each thread with a query of its own. bsp_intersect_batch writes
 * ray i's closest hit to HITS[i] (prim BSP_NO_PRIM on a miss);
 * bsp_occluded_batch writes 1 or 0 to OCCLUDED[i]. FROM, when not NULL, names
 * the primitive each ray leaves out (as bsp_intersect_from; BSP_NO_PRIM:
 * none). COUNTERS, when not NULL, receives the batch's counters, summed over
 * its rays. The answers and counters are the same for any THREADS. Returns
 * BSP_OK, BSP_ERR_INVALID (no structure, or NULL arrays for N > 0) or
 * BSP_ERR_NOMEM (before any ray is shot). */
bsp_status bsp_intersect_batch(const bsp_accel *accel, const bsp_ray *rays, const uint32_t *from,
                               size_t n, int threads, bsp_hit *hits,
                               bsp_query_counters *counters, bsp_error *err);
bsp_status bsp_occluded_batch(const bsp_accel *accel, const bsp_ray *rays, const uint32_t *from,
                              size_t n, int threads, unsigned char *occluded,
                              bsp_query_counters *counters, bsp_error *err);

#ifdef __cplusplus
}
#endif

#endif /* BSPRAY_ACCEL_H */
