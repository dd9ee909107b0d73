/*
 * bspray.c — the command-line tool, a client of include/bspray only.
 *
 *   bspray render SCENE [options]   Whitted render to PNG/PPM + ray statistics
 *   bspray trace  SCENE --rays FILE batch closest-hit / occlusion queries (trace.c)
 *   bspray stats  SCENE             what a scene contains
 *   bspray gen    NAME              a built-in SPD scene as NFF text
 *   bspray bench  [SCENE...]        build, validate and time methods (bench.c)
 *
 * Exit status: 0 success, 1 bad input or failure at run time, 2 usage error.
 * Only this file prints; the library reports through bsp_error.
 */
#include <errno.h>
#include <inttypes.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bspray/bspray.h"
#include "render/costmap.h"
#include "util/progress.h"

#include "cli.h"

/* --- render ------------------------------------------------------------------ */

static const char render_usage[] =
    "bspray render SCENE [-o OUT.png|OUT.ppm] [--res N | --size WxH] [--depth N]\n"
    "                    [--sampling spd|centres] [--accel METHOD] [--mailbox on|off]\n"
    "                    [--max-depth N] [--leaf-size N] [--mixed-share F]\n"
    "                    [--threads N] [--pixel-order tiles|rows] [--stats-json FILE]\n"
    "                    [--save-rays PREFIX] [--quiet]\n"
    "                    [--cost-map FILE.png [--cost-measure steps|tests|leaves|rays]]\n"
    "                    [--eye X,Y,Z] [--at X,Y,Z | --dir X,Y,Z] [--up X,Y,Z] [--fov DEG]\n"
    "                    [--ortho W|auto] [--tree FILE]";

static const char render_help[] =
    "Render SCENE with the Whitted ray tracer of the SPD and print its ray statistics.\n"
    "\n"
    "SCENE is an NFF file (.nff or .nff.gz), a mesh (.obj, .ply, also .gz) or\n"
    "spd:NAME[:SIZE][:tN] for a built-in SPD scene. A mesh has no camera: it is viewed from outside its bounding box\n"
    "along the diagonal with a 45 degree field of view and a light at the eye.\n"
    "\n"
    "  -o FILE            output image; .ppm writes binary PPM, anything else PNG\n"
    "                     (default: out.png)\n"
    "  --res N            N x N rays (see --sampling); default: from the scene's camera\n"
    "  --size WxH         W x H rays\n"
    "  --sampling spd     (default) the SPD timing protocol: a file that says\n"
    "                     'resolution 512 512' is traced with 513 x 513 rays through the\n"
    "                     pixel corners, and the view angle spans the first to the last ray;\n"
    "                     --res N then means N x N rays on the same rule, so --res 513 is\n"
    "                     the protocol of Havran's tables and of 'bspray bench'\n"
    "  --sampling centres the ordinary convention: N x N pixels, one ray through each pixel\n"
    "                     centre, the view angle spanning the outer pixel edges\n"
    "  --depth N          maximum ray depth: primary rays have depth 0 and spawn reflected\n"
    "                     and refracted rays while below N (default 4, the paper's and\n"
    "                     Havran's setting; the SPD Readme calls it depth 5)\n"
    "  --threads N        worker threads (default: all cores); the image does not depend on it\n"
    "  --pixel-order O    tiles (default): the threads take " STRINGIFY(BSP_RENDER_TILE) " x " STRINGIFY(
        BSP_RENDER_TILE) " tiles of the image,\n"
    "                     whose neighbouring rays keep a thread's caches and branch\n"
    "                     predictor warm (5-12 % faster); rows: whole rows, the scanline\n"
    "                     order with one thread. The image and the statistics are the same\n"
    "                     either way\n"
    "  --stats-json FILE  also write the statistics as JSON\n"
    "  --save-rays PREFIX also write every ray the render casts, in the format of\n"
    "                     'bspray trace' ('ox oy oz dx dy dz tmin tmax from', %.17g), one\n"
    "                     file per class: PREFIX-primary.txt, PREFIX-shadow.txt (replay\n"
    "                     with 'trace --any') and PREFIX-secondary.txt; the render then\n"
    "                     runs on one thread, so the files list the rays in the order\n"
    "                     they are cast (row by row unless --pixel-order tiles is given)\n"
    "  --cost-map FILE    also draw where the work went: each pixel coloured by what its\n"
    "                     rays cost (the primary ray and every ray it spawned), from dark\n"
    "                     (none) to bright (the most), beside a colour bar with the scale;\n"
    "                     .ppm writes PPM, anything else PNG\n"
    "  --cost-measure M   what --cost-map shows: steps (traversal steps, the default),\n"
    "                     tests (intersection tests), leaves (leaves visited) or rays\n"
    "  --quiet            print no statistics table\n";

/* --save-rays: one file per ray class, written by the render's ray log. */
typedef struct ray_files {
    FILE *f[BSP_RAY_CLASS_COUNT];
    char path[BSP_RAY_CLASS_COUNT][4096];
} ray_files;

static const char *const ray_class_file[BSP_RAY_CLASS_COUNT] = {
    [BSP_RAY_PRIMARY] = "primary", [BSP_RAY_SHADOW] = "shadow", [BSP_RAY_SECONDARY] = "secondary"};

static void save_ray(bsp_ray_class cls, const bsp_ray *r, uint32_t from, void *ctx)
{
    FILE *f = ((ray_files *)ctx)->f[cls];
    fprintf(f, "%.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g %lld\n", r->org.x, r->org.y,
            r->org.z, r->dir.x, r->dir.y, r->dir.z, r->tmin, r->tmax,
            from == BSP_NO_PRIM ? -1LL : (long long)from);
}

/* Opens PREFIX-CLASS.txt for each class; 0 with a message when one cannot be. */
static int open_ray_files(ray_files *rf, const char *prefix)
{
    for (int c = 0; c < BSP_RAY_CLASS_COUNT; c++) {
        snprintf(rf->path[c], sizeof rf->path[c], "%s-%s.txt", prefix, ray_class_file[c]);
        rf->f[c] = fopen(rf->path[c], "w");
        if (!rf->f[c]) {
            fprintf(stderr, "%s: %s: cannot open for writing: %s\n", prog, rf->path[c],
                    strerror(errno));
            for (int k = 0; k < c; k++)
                fclose(rf->f[k]);
            return 0;
        }
    }
    return 1;
}

/* Closes the files; 0 with a message when a write failed. */
static int close_ray_files(ray_files *rf)
{
    int ok = 1;
    for (int c = 0; c < BSP_RAY_CLASS_COUNT; c++) {
        if (!close_output(rf->f[c], rf->path[c]))
            ok = 0;
    }
    return ok;
}

typedef struct progress_ctx {
    progress_bar *bar;
} progress_ctx;

static void on_progress(double done, void *ctx)
{
    progress_update(((progress_ctx *)ctx)->bar, done);
}

/* TREE_PATH: the kd-tree file the structure was loaded from (--tree), or
 * NULL; its time is then the load's (T_load), not a build's (T_B). */
static void print_stats_table(FILE *f, const char *scene_name, const char *accel_name,
                              const bsp_render_stats *st, int sampling,
                              const bsp_tree_stats *tree, const bsp_mixed_check *chk,
                              const char *tree_path)
{
    const bsp_ray_class_stats *P = &st->cls[BSP_RAY_PRIMARY], *S = &st->cls[BSP_RAY_SHADOW],
                              *R = &st->cls[BSP_RAY_SECONDARY];
    uint64_t all = P->rays + S->rays + R->rays;
    uint64_t req = P->hits + S->hits + R->hits;
    uint64_t tests = P->isect_tests + S->isect_tests + R->isect_tests;
    fprintf(f, "| %s | %s |\n|---|---:|\n", "statistic", scene_name);
    fprintf(f, "| image | %d x %d rays, %s sampling |\n", st->width, st->height,
            sampling == BSP_SAMPLING_SPD ? "SPD corner" : "pixel-centre");
    fprintf(f, "| method | %s, depth %d, %d threads |\n", accel_name, st->max_depth, st->threads);
    if (chk->ran)
        fprintf(f,
                "| sah-mixed check | kept the %s tree: %.3f against %.3f per ray (%" PRIu64
                " rays) |\n",
                chk->kept_sah ? "sah" : "sah-mixed", chk->kept_sah ? chk->cost_sah : chk->cost_mixed,
                chk->kept_sah ? chk->cost_mixed : chk->cost_sah, chk->rays);
    fprintf(f, "| PrimaryRay | %" PRIu64 " |\n", P->rays);
    fprintf(f, "| UsedIntPrimRay | %" PRIu64 " |\n", P->hits);
    fprintf(f, "| ScnCoverage[%%] | %.2f |\n", 100.0 * safe_div((double)P->hits, (double)P->rays));
    fprintf(f, "| ShadowRay | %" PRIu64 " |\n", S->rays);
    fprintf(f, "| UsedIntShadRay | %" PRIu64 " |\n", S->hits);
    fprintf(f, "| SecondaryRay | %" PRIu64 " |\n", R->rays);
    fprintf(f, "| (reflected, refracted) | %" PRIu64 ", %" PRIu64 " |\n", st->reflected_rays,
            st->refracted_rays);
    fprintf(f, "| UsedIntSecRay | %" PRIu64 " |\n", R->hits);
    fprintf(f, "| AllRays | %" PRIu64 " |\n", all);
    fprintf(f, "| IntersRequired | %" PRIu64 " |\n", req);
    fprintf(f, "| N_IT primary | %.2f |\n", safe_div((double)P->isect_tests, (double)P->rays));
    fprintf(f, "| N_IT shadow | %.2f |\n", safe_div((double)S->isect_tests, (double)S->rays));
    fprintf(f, "| N_IT secondary | %.2f |\n", safe_div((double)R->isect_tests, (double)R->rays));
    fprintf(f, "| N_IT all | %.2f |\n", safe_div((double)tests, (double)all));
    uint64_t steps = P->traversal_steps + S->traversal_steps + R->traversal_steps;
    uint64_t ets = P->leaves_visited + S->leaves_visited + R->leaves_visited;
    uint64_t eets = P->empty_leaves + S->empty_leaves + R->empty_leaves;
    uint64_t mb = P->mailbox_hits + S->mailbox_hits + R->mailbox_hits;
    if (steps) {
        fprintf(f, "| N_TS primary | %.2f |\n",
                safe_div((double)P->traversal_steps, (double)P->rays));
        fprintf(f, "| N_TS all | %.2f |\n", safe_div((double)steps, (double)all));
        fprintf(f, "| N_ETS all | %.2f |\n", safe_div((double)ets, (double)all));
        fprintf(f, "| N_EETS all | %.2f |\n", safe_div((double)eets, (double)all));
        fprintf(f, "| mailbox hits per ray | %.2f |\n", safe_div((double)mb, (double)all));
    }
    if (tree && tree->leaves) {
        fprintf(f, "| N_IN / N_V / N_EV / N_OIV | %" PRIu64 " / %" PRIu64 " / %" PRIu64 " / %" PRIu64
                   " |\n",
                tree->interior_nodes, tree->leaves, tree->empty_leaves, tree->references);
        fprintf(f, "| tree bytes | %" PRIu64 " |\n", tree->bytes);
        fprintf(f, "| trace copy bytes | %" PRIu64 " |\n", tree->trace_bytes);
    }
    tree_time_row(f, tree_path, st->build_seconds, 3);
    fprintf(f, "| T_TR[s] | %.3f |\n", st->render_seconds);
    fprintf(f, "| Mrays/s | %.3f |\n", safe_div((double)all, st->render_seconds) * 1e-6);
}

static void json_class(FILE *f, const char *name, const bsp_ray_class_stats *c, int last)
{
    fprintf(f,
            "    \"%s\": {\"rays\": %" PRIu64 ", \"hits\": %" PRIu64 ", \"isect_tests\": %" PRIu64
            ", \"traversal_steps\": %" PRIu64 ", \"N_IT\": %.6f, \"N_TS\": %.6f}%s\n",
            name, c->rays, c->hits, c->isect_tests, c->traversal_steps,
            safe_div((double)c->isect_tests, (double)c->rays),
            safe_div((double)c->traversal_steps, (double)c->rays), last ? "" : ",");
}

static int write_stats_json(const char *path, const char *scene_name, const bsp_accel *accel,
                            const bsp_render_stats *st, const bsp_tree_stats *tree,
                            const bsp_mixed_check *chk, const char *tree_path)
{
    bsp_accel_kind kind = bsp_accel_get_kind(accel);
    FILE *f = fopen(path, "w");
    if (!f) {
        fprintf(stderr, "%s: %s: cannot open for writing: %s\n", prog, path, strerror(errno));
        return 0;
    }
    const bsp_ray_class_stats *P = &st->cls[BSP_RAY_PRIMARY], *S = &st->cls[BSP_RAY_SHADOW],
                              *R = &st->cls[BSP_RAY_SECONDARY];
    uint64_t all = P->rays + S->rays + R->rays;
    uint64_t tests = P->isect_tests + S->isect_tests + R->isect_tests;
    fprintf(f, "{\n  \"scene\": ");
    json_string(f, scene_name);
    fprintf(f, ",\n  \"accel\": \"%s\",\n", bsp_accel_kind_name(kind));
    cells_variant_json(f, "  ", accel);
    fprintf(f, "  \"width\": %d,\n  \"height\": %d,\n", st->width, st->height);
    fprintf(f, "  \"max_depth\": %d,\n  \"threads\": %d,\n", st->max_depth, st->threads);
    fprintf(f, "  \"PrimaryRay\": %" PRIu64 ",\n  \"UsedIntPrimRay\": %" PRIu64 ",\n", P->rays,
            P->hits);
    fprintf(f, "  \"ScnCoverage\": %.4f,\n", 100.0 * safe_div((double)P->hits, (double)P->rays));
    fprintf(f, "  \"ShadowRay\": %" PRIu64 ",\n  \"UsedIntShadRay\": %" PRIu64 ",\n", S->rays,
            S->hits);
    fprintf(f, "  \"SecondaryRay\": %" PRIu64 ",\n  \"UsedIntSecRay\": %" PRIu64 ",\n", R->rays,
            R->hits);
    fprintf(f, "  \"ReflectedRay\": %" PRIu64 ",\n  \"RefractedRay\": %" PRIu64 ",\n",
            st->reflected_rays, st->refracted_rays);
    fprintf(f, "  \"AllRays\": %" PRIu64 ",\n  \"IntersRequired\": %" PRIu64 ",\n", all,
            P->hits + S->hits + R->hits);
    fprintf(f, "  \"N_IT\": %.6f,\n", safe_div((double)tests, (double)all));
    uint64_t steps = P->traversal_steps + S->traversal_steps + R->traversal_steps;
    uint64_t ets = P->leaves_visited + S->leaves_visited + R->leaves_visited;
    uint64_t eets = P->empty_leaves + S->empty_leaves + R->empty_leaves;
    uint64_t mb = P->mailbox_hits + S->mailbox_hits + R->mailbox_hits;
    fprintf(f, "  \"N_TS\": %.6f,\n  \"N_ETS\": %.6f,\n  \"N_EETS\": %.6f,\n",
            safe_div((double)steps, (double)all), safe_div((double)ets, (double)all),
            safe_div((double)eets, (double)all));
    fprintf(f, "  \"mailbox_hits\": %" PRIu64 ",\n", mb);
    tree_stats_json(f, "  ", tree, kind);
    tree_time_json(f, "  ", tree_path, st->build_seconds);
    fprintf(f, "  \"T_TR\": %.6f,\n", st->render_seconds);
    if (chk->ran)
        fprintf(f,
                "  \"mixed_check\": {\"kept\": \"%s\", \"cost_mixed\": %.6f, \"cost_sah\": %.6f, "
                "\"rays\": %" PRIu64 "},\n",
                chk->kept_sah ? "sah" : "sah-mixed", chk->cost_mixed, chk->cost_sah, chk->rays);
    fprintf(f, "  \"classes\": {\n");
    json_class(f, "primary", P, 0);
    json_class(f, "shadow", S, 0);
    json_class(f, "secondary", R, 1);
    fprintf(f, "  }\n}\n");
    return close_output(f, path);
}

static int cmd_render(int argc, char **argv)
{
    args a = {argc, 1, argv, render_usage, NULL};
    const char *scene_path = NULL, *out_path = "out.png", *json_path = NULL, *rays_prefix = NULL;
    int order_given = 0; /* --pixel-order given: --save-rays keeps it */
    const char *cost_path = NULL, *tree_path = NULL;
    costmap_measure cost_measure = COSTMAP_STEPS;
    int quiet = 0;
    view_args view = {0};
    bsp_build_options bopts;
    bsp_build_options_defaults(&bopts);
    bsp_render_options ropts;
    bsp_render_options_defaults(&ropts);
    for (; a.i < argc; a.i++) {
        const char *s = argv[a.i];
        if (is_help(s)) {
            printf("usage: %s\n\n%s%s%s%s", render_usage, render_help, build_args_help,
                   tree_arg_help, view_args_help);
            return 0;
        } else if (!strcmp(s, "-o") || !strcmp(s, "--output")) {
            out_path = opt_value(&a, s);
        } else if (!strcmp(s, "--res")) {
            ropts.width = ropts.height = parse_int(&a, s, 1, 65536);
        } else if (!strcmp(s, "--size")) {
            const char *v = opt_value(&a, s);
            int w, h;
            char extra;
            if (sscanf(v, "%dx%d%c", &w, &h, &extra) != 2 || w < 1 || h < 1 || w > 65536 ||
                h > 65536)
                die_usage(a.usage, "option '--size' needs WxH with sides from 1 to 65536, got '%s'",
                          v);
            ropts.width = w;
            ropts.height = h;
        } else if (!strcmp(s, "--depth")) {
            ropts.max_depth = parse_int(&a, s, 0, 64);
        } else if (!strcmp(s, "--threads")) {
            ropts.threads = parse_int(&a, s, 1, 256);
        } else if (!strcmp(s, "--pixel-order")) {
            const char *v = opt_value(&a, s);
            if (!strcmp(v, "tiles"))
                ropts.pixel_order = BSP_PIXELS_TILES;
            else if (!strcmp(v, "rows"))
                ropts.pixel_order = BSP_PIXELS_ROWS;
            else
                die_usage(a.usage, "option '--pixel-order' takes tiles or rows, got '%s'", v);
            order_given = 1;
        } else if (!strcmp(s, "--sampling")) {
            const char *v = opt_value(&a, s);
            if (!strcmp(v, "spd"))
                ropts.sampling = BSP_SAMPLING_SPD;
            else if (!strcmp(v, "centres") || !strcmp(v, "centers"))
                ropts.sampling = BSP_SAMPLING_CENTRES;
            else
                die_usage(a.usage, "option '--sampling' takes spd or centres, got '%s'", v);
        } else if (parse_build_arg(&a, &bopts) || parse_view_arg(&a, &view)) {
            continue;
        } else if (!strcmp(s, "--stats-json")) {
            json_path = opt_value(&a, s);
        } else if (!strcmp(s, "--tree")) {
            tree_path = opt_value(&a, s);
        } else if (!strcmp(s, "--save-rays")) {
            rays_prefix = opt_value(&a, s);
        } else if (!strcmp(s, "--cost-map")) {
            cost_path = opt_value(&a, s);
        } else if (!strcmp(s, "--cost-measure")) {
            const char *v = opt_value(&a, s);
            if (!costmap_measure_parse(v, &cost_measure))
                die_usage(a.usage,
                          "option '--cost-measure' takes steps, tests, leaves or rays, got '%s'",
                          v);
        } else if (!strcmp(s, "--quiet") || !strcmp(s, "-q")) {
            quiet = 1;
        } else {
            take_operand(&a, &scene_path);
        }
    }
    if (!scene_path)
        die_usage(a.usage, "%s", "missing SCENE");

    bsp_scene *scene = load_scene(scene_path);
    apply_view_args(scene, scene_path, &view, &bopts, &ropts);
    if (!bsp_scene_camera(scene)) {
        fprintf(stderr, "%s: %s: the scene has no camera ('v' block); cannot render\n", prog,
                scene_path);
        bsp_scene_destroy(scene);
        return EXIT_INPUT;
    }
    /* every output before the render, which may take minutes */
    if (!output_path_writable(out_path) || (json_path && !output_path_writable(json_path)) ||
        (cost_path && !output_path_writable(cost_path))) {
        bsp_scene_destroy(scene);
        return EXIT_INPUT;
    }
    bsp_query_counters *costs = NULL;
    int cost_w = 0, cost_h = 0;
    if (cost_path) {
        bsp_error serr;
        if (bsp_render_size(scene, &ropts, &cost_w, &cost_h, &serr) != BSP_OK ||
            !(costs = calloc((size_t)cost_w * (size_t)cost_h, sizeof *costs))) {
            fprintf(stderr, "%s: %s: %s\n", prog, scene_path,
                    costs ? serr.message : "out of memory for the cost map");
            bsp_scene_destroy(scene);
            return EXIT_INPUT;
        }
        ropts.pixel_costs = costs;
        ropts.pixel_costs_count = (size_t)cost_w * (size_t)cost_h;
    }
    ray_files rf;
    if (rays_prefix) {
        if (!open_ray_files(&rf, rays_prefix)) {
            bsp_scene_destroy(scene);
            return EXIT_INPUT;
        }
        ropts.ray_log = save_ray;
        ropts.ray_log_ctx = &rf;
        ropts.threads = 1; /* the rays in the order they are cast, */
        if (!order_given)
            ropts.pixel_order = BSP_PIXELS_ROWS; /* row by row (docs/renderer.md) */
    }
    bsp_accel *accel = tree_or_build(&a, scene, &bopts, tree_path);
    progress_ctx pc = {progress_create(stderr, "render")};
    ropts.progress = on_progress;
    ropts.progress_ctx = &pc;
    bsp_image *img = NULL;
    bsp_render_stats st;
    bsp_error err;
    bsp_status rs = bsp_render(accel, &ropts, &img, &st, &err);
    progress_finish(pc.bar);
    int rc = 0;
    if (rays_prefix && !close_ray_files(&rf))
        rc = EXIT_INPUT;
    if (rs != BSP_OK) {
        fprintf(stderr, "%s: %s: %s\n", prog, scene_path, err.message);
        rc = EXIT_INPUT;
    } else {
        if (bsp_image_write(img, out_path, &err) != BSP_OK) {
            fprintf(stderr, "%s: %s\n", prog, err.message);
            rc = EXIT_INPUT;
        }
        const char *an = accel_label(accel);
        bsp_tree_stats tree;
        bsp_accel_tree_stats(accel, &tree);
        bsp_mixed_check chk;
        bsp_accel_mixed_check(accel, &chk);
        if (!quiet)
            print_stats_table(stdout, scene_path, an, &st, ropts.sampling, &tree, &chk,
                              tree_path);
        if (json_path &&
            !write_stats_json(json_path, scene_path, accel, &st, &tree, &chk, tree_path))
            rc = EXIT_INPUT;
        if (costs) {
            bsp_image *map = costmap_draw(costs, cost_w, cost_h, cost_measure);
            if (!map) {
                fprintf(stderr, "%s: %s: out of memory for the cost map\n", prog, cost_path);
                rc = EXIT_INPUT;
            } else if (bsp_image_write(map, cost_path, &err) != BSP_OK) {
                fprintf(stderr, "%s: %s\n", prog, err.message); /* it names the file */
                rc = EXIT_INPUT;
            } else if (!quiet) {
                fprintf(stderr, "%s: wrote %s\n", prog, cost_path);
            }
            bsp_image_destroy(map);
        }
        if (rc == 0 && !quiet)
            fprintf(stderr, "%s: wrote %s\n", prog, out_path);
    }
    bsp_image_destroy(img);
    free(costs);
    bsp_accel_destroy(accel);
    bsp_scene_destroy(scene);
    return rc;
}

/* --- stats --------------------------------------------------------------------------- */

static const char stats_usage[] =
    "bspray stats SCENE [--accel METHOD] [--max-depth N] [--leaf-size N] [--tree FILE]\n"
    "                   [--check] [--stats-json FILE] [--eye X,Y,Z] [--at X,Y,Z | --dir X,Y,Z]\n"
    "                   [--up X,Y,Z] [--fov DEG] [--ortho W|auto]";
static const char stats_help[] =
    "Print what SCENE contains: primitives by kind (with polygon vertex counts), bounds,\n"
    "camera, lights, materials, background, and load warnings. With --accel, also build\n"
    "that structure and print its figures with Havran's names (N_IN interior nodes, N_V\n"
    "leaves, N_EV empty leaves, N_OIV references in leaves, leaf depths, bytes, the expected\n"
    "SAH cost with unit costs and under the build's own costs, build time T_B). With\n"
    "--tree, the same figures of a saved tree (bspray build), and its load time.\n"
    "\n"
    "  --check            run the tree invariant checker too\n"
    "  --stats-json FILE  also write the figures as JSON: the primitives by kind, the\n"
    "                     bounds and, with a structure, T_B (or the file and T_load),\n"
    "                     N_IN, N_V, N_EV, N_OIV, leaf depths, bytes, both expected\n"
    "                     costs, the leaf budget's cut, the digest and the check\n";

static int cmd_stats(int argc, char **argv)
{
    args a = {argc, 1, argv, stats_usage, NULL};
    const char *scene_path = NULL, *tree_path = NULL, *json_path = NULL;
    int want_tree = 0, check = 0;
    view_args view = {0};
    bsp_build_options bopts;
    bsp_build_options_defaults(&bopts);
    for (; a.i < argc; a.i++) {
        const char *s = argv[a.i];
        if (is_help(s)) {
            printf("usage: %s\n\n%s%s%s%s", stats_usage, stats_help, build_args_help,
                   tree_arg_help, view_args_help);
            return 0;
        } else if (parse_build_arg(&a, &bopts)) {
            want_tree = 1;
        } else if (parse_view_arg(&a, &view)) {
            continue;
        } else if (!strcmp(s, "--check")) {
            check = 1;
        } else if (!strcmp(s, "--stats-json")) {
            json_path = opt_value(&a, s);
        } else if (!strcmp(s, "--tree")) {
            tree_path = opt_value(&a, s);
            want_tree = 1;
        } else {
            take_operand(&a, &scene_path);
        }
    }
    if (!scene_path)
        die_usage(a.usage, "%s", "missing SCENE");
    if (json_path && !output_path_writable(json_path)) /* before the load and the build */
        return EXIT_INPUT;
    bsp_scene *scene = load_scene(scene_path);
    apply_view_args(scene, scene_path, &view, &bopts, NULL);
    /* the structure first: a tree file that does not load, or a build that
     * fails, ends the command before anything is printed */
    bsp_accel *accel = want_tree ? tree_or_build(&a, scene, &bopts, tree_path) : NULL;
    size_t n = bsp_scene_prim_count(scene);
    printf("scene: %s\n", scene_path);
    printf("primitives: %zu\n", n);
    for (int k = 0; k < BSP_PRIM_KIND_COUNT; k++) {
        size_t c = bsp_scene_kind_count(scene, (bsp_prim_kind)k);
        if (!c && k == BSP_PRIM_DROPPED)
            continue;
        printf("  %-8s %zu", bsp_prim_kind_name((bsp_prim_kind)k), c);
        if ((k == BSP_PRIM_POLYGON || k == BSP_PRIM_PATCH) && c) {
            /* histogram of vertex counts, smallest first */
            size_t done = 0, last = 0;
            printf(" (");
            while (done < c) {
                size_t best = SIZE_MAX, cnt = 0;
                for (size_t i = 0; i < n; i++) {
                    if (bsp_scene_prim_kind(scene, i) != (bsp_prim_kind)k)
                        continue;
                    size_t vc = bsp_scene_prim_vertex_count(scene, i);
                    if (vc > last && vc < best)
                        best = vc, cnt = 0;
                    if (vc == best)
                        cnt++;
                }
                if (best == SIZE_MAX)
                    break;
                printf("%s%zu x %zu vertices", done ? ", " : "", cnt, best);
                done += cnt;
                last = best;
            }
            printf(")");
        }
        printf("\n");
    }
    bsp_box b = bsp_scene_bounds(scene);
    if (b.lo.x <= b.hi.x)
        printf("bounds: min (%g, %g, %g) max (%g, %g, %g)\n", b.lo.x, b.lo.y, b.lo.z, b.hi.x,
               b.hi.y, b.hi.z);
    else
        printf("bounds: empty\n");
    const bsp_camera *c = bsp_scene_camera(scene);
    if (c) {
        printf("camera: from (%g, %g, %g) at (%g, %g, %g) up (%g, %g, %g)\n", c->from.x,
               c->from.y, c->from.z, c->at.x, c->at.y, c->at.z, c->up.x, c->up.y, c->up.z);
        printf("        angle %g, hither %g, resolution %d x %d\n", c->angle_deg, c->hither,
               c->res_x, c->res_y);
    } else {
        printf("camera: none\n");
    }
    printf("lights: %zu\n", bsp_scene_light_count(scene));
    for (size_t i = 0; i < bsp_scene_light_count(scene); i++) {
        const bsp_light *l = bsp_scene_light(scene, i);
        printf("  (%g, %g, %g)", l->pos.x, l->pos.y, l->pos.z);
        if (l->has_color)
            printf(" colour %g %g %g", l->color[0], l->color[1], l->color[2]);
        printf("\n");
    }
    size_t nm = bsp_scene_material_count(scene), refl = 0, transm = 0, two_sided = 0;
    for (size_t i = 0; i < nm; i++) {
        const bsp_material *m = bsp_scene_material(scene, i);
        refl += m->ks > 0;
        transm += m->t > 0;
        two_sided += m->two_sided != 0;
    }
    printf("materials: %zu (%zu with Ks > 0, %zu with T > 0, %zu lit on the side seen)\n", nm,
           refl, transm, two_sided);
    double bg[3];
    bsp_scene_background(scene, bg);
    printf("background: %g %g %g\n", bg[0], bg[1], bg[2]);
    int rc = 0, checked = 0;
    bsp_tree_stats t;
    if (accel) {
        bsp_accel_tree_stats(accel, &t);
        bsp_accel_kind kind = bsp_accel_get_kind(accel);
        printf("structure: %s%s%s\n", accel_label(accel), tree_path ? ", loaded from " : "",
               tree_path ? tree_path : "");
        if (tree_path)
            printf("  load[s]        %.4f\n", bsp_accel_build_seconds(accel));
        else
            printf("  T_B[s]         %.4f\n", bsp_accel_build_seconds(accel));
        printf("  N_IN           %" PRIu64 "%s\n", t.interior_nodes,
               kind == BSP_ACCEL_OCTREE ? " (octree nodes of 8 children, 3 kd levels each)"
               : kind == BSP_ACCEL_GRID && t.interior_nodes ? " (cells cut by a grid of their own)"
                                                            : "");
        printf("  N_V            %" PRIu64 "\n", t.leaves);
        printf("  N_EV           %" PRIu64 "\n", t.empty_leaves);
        printf("  N_OIV          %" PRIu64 "\n", t.references);
        printf("  leaf depth     max %d, mean %.2f%s\n", t.max_leaf_depth, t.avg_leaf_depth,
               kind == BSP_ACCEL_OCTREE ? " (octree levels)" : "");
        printf("  bytes          %" PRIu64 " (nodes and leaf lists)\n", t.bytes);
        if (t.trace_bytes)
            printf("  trace bytes    %" PRIu64 " (the traversal's copies: the primitives in leaf\n"
                   "                 order, the leaf lists in that numbering, the nodes\n"
                   "                 with empty-child flags)\n",
                   t.trace_bytes);
        if (kind == BSP_ACCEL_GRID) {
            printf("  resolution     %d x %d x %d cells\n", t.grid_res[0], t.grid_res[1],
                   t.grid_res[2]);
            if (t.interior_nodes)
                printf("  grid levels    %d (the root grid's resolution above; grids nested in\n"
                       "                 the cut cells below it)\n",
                       t.max_leaf_depth + 1);
        } else {
            printf("  expected cost  %.3f (SAH, traversal and intersection cost 1)\n",
                   t.expected_cost);
            printf("  model cost     %.3f (SAH under the build's costs, in traversal steps; no\n"
                   "                 mailbox term)\n",
                   t.model_cost);
        }
        if (kind != BSP_ACCEL_NAIVE)
            printf("  digest         %016" PRIx64 " (nodes and leaf lists hashed: equal digests,\n"
               "                 the same tree bit for bit)\n",
               t.digest);
        if (t.budget_cut > 0.0)
            printf("  leaf budget    splits saving < %.3g per ray of the root skipped (estimate)\n",
                   t.budget_cut);
        else if (t.budget_rebuilt)
            printf("  leaf budget    estimate too high: built again without it\n");
        if (check) {
            bsp_error err;
            if (bsp_accel_check(accel, &err) == BSP_OK) {
                printf("  invariants     ok\n");
                checked = 1;
            } else {
                printf("  invariants     FAILED: %s\n", err.message);
                checked = -1;
                rc = EXIT_INPUT;
            }
        }
    }
    if (json_path &&
        !write_stats_json_file(json_path, scene_path, scene, accel, accel ? &t : NULL, tree_path,
                               checked))
        rc = EXIT_INPUT;
    bsp_accel_destroy(accel);
    bsp_scene_destroy(scene);
    return rc;
}

/* --- gen ------------------------------------------------------------------------------ */

static const char gen_usage[] = "bspray gen NAME [-s SIZE] [-t N] [-o FILE.nff]";

static void print_gen_help(void)
{
    printf("usage: %s\n\n"
           "Write an SPD scene, generated in code, as NFF (to standard output without -o).\n"
           "The output equals what Haines' SPD 3.14 programs print for the same size factor.\n"
           "\n"
           "  -s SIZE   the SPD size factor (default: the program's default)\n"
           "  -t N, --tessellate N\n"
           "            replace spheres and cones by triangle patches, N slices around\n"
           "            (N = 2..64); like the SPD programs' -t, in bspray's own scheme\n"
           "  -o FILE   output file\n"
           "\n"
           "NAME, with default and valid sizes:\n",
           gen_usage);
    char names[512];
    snprintf(names, sizeof names, "%s", bsp_spd_scene_names());
    for (char *tok = strtok(names, " "); tok; tok = strtok(NULL, " ")) {
        int def, lo, hi;
        if (bsp_spd_scene_sizes(tok, &def, &lo, &hi))
            printf("  %-10s default %d, %d..%d\n", tok, def, lo, hi);
    }
    printf("\nNAME may also be given as a SCENE is, spd:NAME[:SIZE][:tN] (gen spd:balls:4:t8 is\n"
           "gen balls -s 4 -t 8). Any SCENE argument accepts that form directly, e.g.\n"
           "spd:tree:11 or spd:balls:4:t8 (tessellated at level N, as gen -t N writes it).\n");
}

static int cmd_gen(int argc, char **argv)
{
    args a = {argc, 1, argv, gen_usage, NULL};
    const char *name = NULL, *out_path = NULL;
    int size = 0, tessellate = 0;
    for (; a.i < argc; a.i++) {
        const char *s = argv[a.i];
        if (is_help(s)) {
            print_gen_help();
            return 0;
        } else if (!strcmp(s, "-s") || !strcmp(s, "--size")) {
            size = parse_int(&a, s, 1, 100000);
        } else if (!strcmp(s, "-t") || !strcmp(s, "--tessellate")) {
            tessellate = parse_int(&a, s, 2, 64);
        } else if (!strcmp(s, "-o") || !strcmp(s, "--output")) {
            out_path = opt_value(&a, s);
        } else {
            take_operand(&a, &name);
        }
    }
    if (!name)
        die_usage(a.usage, "%s", "missing NAME");
    if (!strncmp(name, "spd:", 4))
        name += 4;
    /* NAME may carry its size factor and level as a SCENE does: NAME[:SIZE][:tN] */
    char base[64];
    const char *colon = strchr(name, ':');
    if (colon) {
        if ((size_t)(colon - name) >= sizeof base)
            die_usage(a.usage, "unknown SPD scene '%s'", name);
        memcpy(base, name, (size_t)(colon - name));
        base[colon - name] = '\0';
        for (const char *p = colon; *p == ':';) {
            const char *part = p + 1;
            size_t len = strcspn(part, ":");
            char *end;
            long v = strtol(part + (*part == 't'), &end, 10);
            if (len == 0 || end != part + len || part[*part == 't'] < '0' ||
                part[*part == 't'] > '9')
                die_usage(a.usage, "bad scene '%s' (expected NAME[:SIZE][:tN])", name);
            if (*part == 't' && !tessellate)
                tessellate = v >= 2 && v <= 64 ? (int)v : -1;
            else if (*part != 't' && !size)
                size = v >= 1 && v <= 100000 ? (int)v : -1;
            else
                die_usage(a.usage, "scene '%s' repeats a size or level given apart", name);
            if (size < 0 || tessellate < 0)
                die_usage(a.usage, "bad size or level in scene '%s'", name);
            p = part + len;
        }
        name = base;
    }
    FILE *out = out_path ? fopen(out_path, "w") : stdout;
    if (!out) {
        fprintf(stderr, "%s: %s: cannot open for writing: %s\n", prog, out_path, strerror(errno));
        return EXIT_INPUT;
    }
    bsp_error err;
    bsp_status st = bsp_spd_write_nff(name, size, tessellate, out, &err);
    int rc = 0;
    if (st != BSP_OK) {
        fprintf(stderr, "%s: %s\n", prog, err.message);
        rc = EXIT_INPUT;
    }
    if (out != stdout) {
        if (!close_output(out, out_path))
            rc = EXIT_INPUT;
        if (rc)
            remove_partial_output(out_path);
    }
    return rc; /* standard output: checked by main (finish_stdout) */
}

/* --- calibrate ---------------------------------------------------------------------------- */

static int cmd_calibrate(int argc, char **argv)
{
    if (argc > 1 && is_help(argv[1])) {
        printf("usage: bspray calibrate\n\n"
               "Measure the cost of a kd-tree traversal step and of one ray-primitive test for\n"
               "each primitive kind on this machine (ns), and print them with their ratios to\n"
               "the traversal step: the T_i of the SAH cost model. The built-in defaults were\n"
               "measured this way, except the triangle's, set lower from render timings\n"
               "(src/accel/kd_cost.c, docs/kdtree.md). Run it on a quiet machine; the\n"
               "last line gives the --costs option that builds with the measured ratios.\n");
        return 0;
    }
    if (argc > 1)
        die_usage("bspray calibrate", "unexpected argument '%s'", argv[1]);
    bsp_sah_costs c;
    bsp_error err;
    if (bsp_calibrate_costs(&c, &err) != BSP_OK) {
        fprintf(stderr, "%s: %s\n", prog, err.message);
        return EXIT_INPUT;
    }
    printf("| cost | ns | relative to a traversal step |\n|---|---:|---:|\n");
    printf("| traversal step | %.2f | 1 |\n", c.traversal);
    printf("| sphere | %.2f | %.3f |\n", c.sphere, c.sphere / c.traversal);
    printf("| triangle | %.2f | %.3f |\n", c.triangle, c.triangle / c.traversal);
    printf("| polygon, base | %.2f | %.3f |\n", c.polygon_base, c.polygon_base / c.traversal);
    printf("| polygon, per vertex | %.2f | %.3f |\n", c.polygon_vertex,
           c.polygon_vertex / c.traversal);
    printf("| cone | %.2f | %.3f |\n", c.cone, c.cone / c.traversal);
    printf("\nto build with these costs: --costs sphere=%.3g,triangle=%.3g,polygon=%.3g,"
           "vertex=%.3g,cone=%.3g\n",
           c.sphere / c.traversal, c.triangle / c.traversal, c.polygon_base / c.traversal,
           c.polygon_vertex / c.traversal, c.cone / c.traversal);
    return 0;
}

/* --- main ----------------------------------------------------------------------------------- */

static void print_main_help(FILE *f)
{
    fprintf(f,
            "bspray %s — exact ray shooting with adaptive BSP trees\n"
            "\n"
            "usage: bspray COMMAND [options]   (bspray COMMAND --help for each)\n"
            "\n"
            "commands:\n"
            "  render   Whitted ray tracing of a scene to PNG/PPM, with ray statistics\n"
            "  trace    batch ray queries (closest hit or occlusion) from a ray file\n"
            "  stats    what a scene contains (and a structure's figures)\n"
            "  build    build a scene's kd-tree once and save it (render, trace and stats\n"
            "           load it with --tree FILE)\n"
            "  bench    build, validate and time acceleration methods (Markdown + CSV)\n"
            "  gen      write a built-in SPD scene as NFF\n"
            "  calibrate  measure the SAH's per-primitive intersection costs on this machine\n"
            "  viz      pictures of a kd-tree's cells: camera view and top view (PNG)\n"
            "  ab       two structures (the default, and one changed by options) timed\n"
            "           side by side on the same rays\n"
            "\n"
            "SCENE is an NFF file (.nff, .nff.gz), a mesh (.obj, .ply, either also .gz) or\n"
            "spd:NAME[:SIZE][:tN], a built-in SPD scene (tN: spheres and cones as triangles):\n"
            "  %s\n",
            BSPRAY_VERSION_STRING, bsp_spd_scene_names());
}

static int run_command(int argc, char **argv)
{
    if (argc < 2) {
        print_main_help(stderr);
        return EXIT_USAGE;
    }
    const char *cmd = argv[1];
    if (is_help(cmd) || !strcmp(cmd, "help")) {
        print_main_help(stdout);
        return 0;
    }
    if (!strcmp(cmd, "--version")) {
        printf("bspray %s\n", BSPRAY_VERSION_STRING);
        return 0;
    }
    if (!strcmp(cmd, "render"))
        return cmd_render(argc - 1, argv + 1);
    if (!strcmp(cmd, "trace"))
        return cmd_trace(argc - 1, argv + 1);
    if (!strcmp(cmd, "stats"))
        return cmd_stats(argc - 1, argv + 1);
    if (!strcmp(cmd, "build"))
        return cmd_build(argc - 1, argv + 1);
    if (!strcmp(cmd, "gen"))
        return cmd_gen(argc - 1, argv + 1);
    if (!strcmp(cmd, "bench"))
        return cmd_bench(argc - 1, argv + 1);
    if (!strcmp(cmd, "calibrate"))
        return cmd_calibrate(argc - 1, argv + 1);
    if (!strcmp(cmd, "viz"))
        return cmd_viz(argc - 1, argv + 1);
    if (!strcmp(cmd, "ab"))
        return cmd_ab(argc - 1, argv + 1);
    fprintf(stderr, "%s: unknown command '%s'\n", prog, cmd);
    print_main_help(stderr);
    return EXIT_USAGE;
}

int main(int argc, char **argv)
{
    return finish_stdout(run_command(argc, argv));
}
