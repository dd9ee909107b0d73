/*
 * viz.c — `bspray viz`: pictures of kd-tree cells, the paper's Fig. 5.
 *
 * One row of two panels per build rule, so that rules sit one above the
 * other for comparison:
 *   camera view  the scene rendered faintly from its camera, with the split
 *                plane of every interior node (clipped to its cell) drawn
 *                over it, coloured by depth;
 *   top view     the leaf cells seen from above (down the world axis nearest
 *                the camera's up), each pixel coloured by the deepest leaf
 *                (or the leaf with most references) in its column, with the
 *                cell outlines and the camera's view frustum.
 * The drawing itself lives in src/render/draw.c; this file parses the
 * command line, builds the trees and lays out the panels.
 */
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bspray/bspray.h"
#include "render/draw.h"

#include "cli.h"

#define VIZ_MAX_RULES 8

static const char viz_usage[] =
    "bspray viz SCENE -o OUT.png [--accel LIST] [--max-depth N] [--leaf-size N]\n"
    "                 [--color depth|refs] [--size N] [--top-zoom F] [--threads N] [--quiet]\n"
    "                 [--eye X,Y,Z] [--at X,Y,Z | --dir X,Y,Z] [--up X,Y,Z] [--fov DEG]";

static const char viz_help[] =
    "Draw the cells of kd-trees built over SCENE (the pictures of Havran, Bittner and\n"
    "Kopal's Fig. 5). Each method in LIST gives one row of two panels:\n"
    "\n"
    "  camera view   the scene rendered faintly from its camera, with the split plane\n"
    "                of every interior node, clipped to its cell, drawn over it and\n"
    "                coloured by depth (shallow yellow/orange, deep violet/blue); the\n"
    "                root cell's edges in white\n"
    "  top view      the leaf cells seen from above (along the world axis nearest the\n"
    "                camera's up vector, the camera's right pointing right), covering\n"
    "                the root cell; a pixel shows the largest value of --color among\n"
    "                the leaves in the column below it; black cell outlines; the eye\n"
    "                and the edges of its field of view in white\n"
    "\n"
    "  -o FILE          output image, (2 x SIZE) by (methods x SIZE) pixels; .ppm writes\n"
    "                   binary PPM, anything else PNG (required)\n"
    "  --accel LIST     comma-separated methods, one row each: kaplan, sah, sah-per,\n"
    "                   sah-par, sah-mixed (default sah), octree, octree-cost, grid,\n"
    "                   grid-bounds, grid-rec (see --grid-*), bvh, bvh4 or bvh8 (their\n"
    "                   camera view draws every node's box, which may overlap, instead\n"
    "                   of planes)\n"
    "  --max-depth N    the trees' maximum depth (default 10, the paper's setting for\n"
    "                   its pictures); also the end of the depth colour scale. An octree\n"
    "                   gets (N + 2) / 3 levels (three kd levels each)\n"
    "  --leaf-size N    a node with at most N primitives becomes a leaf (default: the\n"
    "                   method's own)\n"
    "  --color depth    (default) colour leaves by depth\n"
    "  --color refs     colour leaves by primitive references (log scale, the same for\n"
    "                   every row; empty leaves grey)\n"
    "  --size N         pixels per side of each square panel (default 512)\n"
    "  --top-zoom F     magnify the top view F times (default 1: the whole root cell),\n"
    "                   towards the camera's look-at point; for scenes whose ground\n"
    "                   plane dwarfs everything else\n"
    "  --threads N      render threads for the background (default: all cores)\n"
    "  --quiet          print nothing but errors\n"
    "  --costs LIST, --empty-bonus F, --min-saving X, --leaf-budget X, --leaf-budget-min N,\n"
    "                 --budget-cut F|off  the SAH model (see\n"
    "                 'bspray render --help')\n"
    "  --grid-density D, --grid-res X,Y,Z, --grid-assign clipped|bounds, --grid-levels L,\n"
    "                 --grid-cell-prims T  the grid,\n"
    "  --octree-split centre|cost  the octree (see 'bspray render --help')\n"
    "  --eye, --at, --dir, --up X,Y,Z   override the camera; --fov DEG its field of view.\n"
    "                   The sah-per, sah-par and sah-mixed trees are built for this view.\n"
    "\n"
    "Prints one line per method: leaves, empty leaves, references, the depth reached, the\n"
    "mean size of the non-empty leaves along x, y and z (their shape), and the build time.\n";

typedef struct viz_row {
    accel_method method;
    const char *label; /* method_label of its build */
    bsp_accel *accel;
    draw_cells cells;
} viz_row;

/* Splits LIST at commas into ROWS; usage error for an unknown name. */
static int parse_rules(args *a, const char *list, viz_row *rows)
{
    accel_method methods[VIZ_MAX_RULES];
    int n = parse_accel_list(a, list, methods, VIZ_MAX_RULES);
    for (int r = 0; r < n; r++)
        rows[r].method = methods[r];
    return n;
}

static void text_upper(char *s)
{
    for (; *s; s++)
        if (*s >= 'a' && *s <= 'z')
            *s = (char)(*s - 'a' + 'A');
}

/* The colour scale under the top view: low label, bar, high label. */
static void draw_legend(bsp_image *img, int font, draw_color_mode mode, double scale)
{
    char lo[32], hi[32];
    snprintf(lo, sizeof lo, "%s 0", mode == DRAW_COLOR_DEPTH ? "DEPTH" : "REFS");
    snprintf(hi, sizeof hi, "%.0f", scale);
    int pad = 3 * font, th = 7 * font;
    int bar_w = img->width / 4, x = 2 * font, y = img->height - th - 4 * font;
    int w = draw_text_width(lo, font) + bar_w + draw_text_width(hi, font) + 4 * pad;
    static const float black[3] = {0, 0, 0}, white[3] = {1, 1, 1};
    draw_fill_rect(img, x, y - font, x + w, y + th + font, black, 0.65f);
    x += pad;
    x += draw_text(img, x, y, font, lo, white) + pad;
    for (int i = 0; i < bar_w; i++) {
        double u = (i + 0.5) / bar_w;
        double v = mode == DRAW_COLOR_DEPTH ? u * scale : expm1(u * log1p(scale));
        float rgb[3];
        draw_cell_color(mode, v, scale, rgb);
        draw_fill_rect(img, x + i, y, x + i + 1, y + th, rgb, 1.f);
    }
    x += bar_w + pad;
    draw_text(img, x, y, font, hi, white);
}

/* The part of ROOT the top view shows at ZOOM: 1/ZOOM of its extent, centred
 * between ROOT's centre and AT so that it stays inside ROOT while AT does. */
static bsp_box zoom_region(bsp_box root, bsp_vec3 at, double zoom)
{
    bsp_box r;
    for (int k = 0; k < 3; k++) {
        double c = 0.5 * (root.lo.v[k] + root.hi.v[k]), half = 0.5 * (root.hi.v[k] - root.lo.v[k]);
        double p = at.v[k] < root.lo.v[k]   ? root.lo.v[k]
                   : at.v[k] > root.hi.v[k] ? root.hi.v[k]
                                            : at.v[k];
        c += (p - c) * (1.0 - 1.0 / zoom);
        r.lo.v[k] = c - half / zoom;
        r.hi.v[k] = c + half / zoom;
    }
    return r;
}

int cmd_viz(int argc, char **argv)
{
    args a = {argc, 1, argv, viz_usage, NULL};
    const char *scene_path = NULL, *out_path = NULL, *list = "sah";
    int max_depth = 10, leaf_size = 0, size = 512, threads = 0, quiet = 0;
    double zoom = 1.0;
    draw_color_mode mode = DRAW_COLOR_DEPTH;
    view_args view = {0};
    cost_args costs = {{0}, 0.0, 0.0, 0.0, 0, 0.0, 0};
    bsp_build_options subdivision_opts; /* --grid-*, --octree-split: for the grid and octree rows */
    bsp_build_options_defaults(&subdivision_opts);
    for (; a.i < argc; a.i++) {
        const char *s = argv[a.i];
        if (is_help(s)) {
            printf("usage: %s\n\n%s", viz_usage, viz_help);
            return 0;
        } else if (!strcmp(s, "-o") || !strcmp(s, "--output")) {
            out_path = opt_value(&a, s);
        } else if (!strcmp(s, "--accel")) {
            list = opt_value(&a, s);
        } else if (!strcmp(s, "--max-depth")) {
            max_depth = parse_int(&a, s, 1, BSP_KD_MAX_DEPTH_LIMIT);
        } else if (!strcmp(s, "--leaf-size")) {
            leaf_size = parse_int(&a, s, 1, 1000000);
        } else if (!strcmp(s, "--color") || !strcmp(s, "--colour")) {
            const char *v = opt_value(&a, s);
            if (!strcmp(v, "depth"))
                mode = DRAW_COLOR_DEPTH;
            else if (!strcmp(v, "refs"))
                mode = DRAW_COLOR_REFS;
            else
                die_usage(a.usage, "option '--color' takes depth or refs, got '%s'", v);
        } else if (!strcmp(s, "--size")) {
            size = parse_int(&a, s, 16, 4096);
        } else if (!strcmp(s, "--top-zoom")) {
            const char *v = opt_value(&a, s);
            char *end;
            zoom = strtod(v, &end);
            if (end == v || *end || !(zoom >= 1 && zoom <= 1e6))
                die_usage(a.usage, "option '--top-zoom' needs a factor from 1 to 1e6, got '%s'", v);
        } else if (!strcmp(s, "--threads")) {
            threads = parse_int(&a, s, 1, 256);
        } else if (!strcmp(s, "--quiet") || !strcmp(s, "-q")) {
            quiet = 1;
        } else if (parse_view_arg(&a, &view) || parse_cost_arg(&a, &costs) ||
                   parse_subdivision_arg(&a, &subdivision_opts)) {
            continue;
        } else {
            take_operand(&a, &scene_path);
        }
    }
    if (!scene_path)
        die_usage(a.usage, "%s", "missing SCENE");
    if (!out_path)
        die_usage(a.usage, "%s", "missing -o OUT.png");
    viz_row rows[VIZ_MAX_RULES];
    memset(rows, 0, sizeof rows);
    int nrows = parse_rules(&a, list, rows);
    for (int r = 0; r < nrows; r++)
        if (rows[r].method.kind == BSP_ACCEL_NAIVE) {
            fprintf(stderr,
                    "%s: viz: the naive method has no tree, so no cells to draw; "
                    "use kaplan, sah, sah-per, sah-par, sah-mixed, grid or octree\n",
                    prog);
            return EXIT_INPUT;
        }
    if (!output_path_writable(out_path)) /* before the builds and renders */
        return EXIT_INPUT;

    bsp_scene *scene = load_scene(scene_path);
    apply_view_args(scene, scene_path, &view, NULL, NULL);
    const bsp_camera *cam = bsp_scene_camera(scene);
    if (!cam) {
        fprintf(stderr, "%s: %s: the scene has no camera ('v' block); cannot draw its views\n",
                prog, scene_path);
        bsp_scene_destroy(scene);
        return EXIT_INPUT;
    }
    if (bsp_scene_prim_count(scene) == bsp_scene_kind_count(scene, BSP_PRIM_DROPPED)) {
        fprintf(stderr, "%s: %s: the scene has no primitives; there is no tree to draw\n", prog,
                scene_path);
        bsp_scene_destroy(scene);
        return EXIT_INPUT;
    }

    /* --- the trees ------------------------------------------------------------------ */
    int rc = 0;
    bsp_error err;
    uint64_t refs_scale = 1;
    for (int r = 0; r < nrows; r++) {
        bsp_build_options bopts;
        bsp_build_options_defaults(&bopts);
        /* an octree level is three kd levels: about as deep as the kd-trees */
        bopts.max_depth =
            rows[r].method.kind == BSP_ACCEL_OCTREE ? (max_depth + 2) / 3 : max_depth;
        bopts.max_leaf_prims = leaf_size;
        apply_cost_args(&costs, &bopts);
        apply_subdivision_args(&subdivision_opts, &bopts);
        apply_method(&rows[r].method, &bopts); /* a variant's name wins over the options */
        rows[r].label = method_label(&bopts);
        rows[r].accel = build_accel(scene, &bopts);
        if (draw_cells_collect(rows[r].accel, &rows[r].cells, &err) != BSP_OK) {
            fprintf(stderr, "%s: %s\n", prog, err.message);
            rc = EXIT_INPUT;
            goto done;
        }
        const draw_cells *c = &rows[r].cells;
        if (c->max_refs > refs_scale)
            refs_scale = c->max_refs;
        bsp_tree_stats ts;
        bsp_accel_tree_stats(rows[r].accel, &ts);
        /* the mean size of the non-empty leaves along x, y, z: their shape */
        double ext[3] = {0, 0, 0};
        for (size_t i = 0; i < c->count; i++)
            if (c->cell[i].is_leaf && c->cell[i].refs)
                for (int k = 0; k < 3; k++)
                    ext[k] += c->cell[i].box.hi.v[k] - c->cell[i].box.lo.v[k];
        double full = (double)(c->leaves - c->empty);
        for (int k = 0; k < 3; k++)
            ext[k] = full > 0 ? ext[k] / full : 0.0;
        if (!quiet)
            printf("%s: %-11s %5" PRIu64 " leaves (%" PRIu64 " empty), %" PRIu64
                   " references, depth %d, non-empty leaves %.3g x %.3g x %.3g on average, "
                   "built in %.3f s\n",
                   scene_path, rows[r].label, c->leaves, c->empty,
                   ts.references, c->max_depth, ext[0], ext[1], ext[2],
                   bsp_accel_build_seconds(rows[r].accel));
    }

    /* --- the faint background: one render serves every row (all methods are exact) -- */
    bsp_render_options ropts;
    bsp_render_options_defaults(&ropts);
    ropts.width = ropts.height = size;
    ropts.sampling = BSP_SAMPLING_CENTRES;
    ropts.max_depth = 0; /* primary and shadow rays: shapes and shading are enough */
    ropts.threads = threads;
    bsp_image *back = NULL;
    bsp_build_options fast;
    bsp_build_options_defaults(&fast); /* a full SAH tree: the depth-limited ones are slow */
    bsp_accel *fast_accel = build_accel(scene, &fast);
    bsp_status rs = bsp_render(fast_accel, &ropts, &back, NULL, &err);
    bsp_accel_destroy(fast_accel);
    if (rs != BSP_OK) {
        fprintf(stderr, "%s: %s: %s\n", prog, scene_path, err.message);
        rc = EXIT_INPUT;
        goto done;
    }
    draw_fade(back);

    /* --- the panels ------------------------------------------------------------------- */
    bsp_image *out = bsp_image_create(2 * size, nrows * size);
    bsp_image *panel = bsp_image_create(size, size);
    if (!out || !panel) {
        fprintf(stderr, "%s: out of memory for a %d x %d image\n", prog, 2 * size, nrows * size);
        rc = EXIT_INPUT;
        goto images;
    }
    bsp_box root = rows[0].cells.cell[0].box;
    bsp_vec3 diag = bsp_v3(root.hi.x - root.lo.x, root.hi.y - root.lo.y, root.hi.z - root.lo.z);
    double near = 1e-6 * sqrt(diag.x * diag.x + diag.y * diag.y + diag.z * diag.z);
    if (!(near > 0))
        near = 1e-9;
    draw_pinhole pin;
    draw_pinhole_init(&pin, cam, size, size, near);
    draw_topview tv;
    draw_topview_init(&tv, cam, zoom_region(root, cam->at, zoom), size, size, size / 32);
    int font = size >= 384 ? 2 : 1;
    static const float frame[3] = {0.0f, 0.0f, 0.0f};
    for (int r = 0; r < nrows; r++) {
        const draw_cells *c = &rows[r].cells;
        char text[160];
        /* camera view */
        draw_paste(panel, back, 0, 0);
        const int boxes = rows[r].method.kind == BSP_ACCEL_BVH ||
                          rows[r].method.kind == BSP_ACCEL_BVH4 ||
                          rows[r].method.kind == BSP_ACCEL_BVH8; /* overlapping boxes */
        if (boxes)
            draw_panel_boxes(panel, &pin, c, max_depth);
        else
            draw_panel_planes(panel, &pin, c, max_depth);
        draw_panel_root(panel, &pin, c);
        snprintf(text, sizeof text, "%s: %" PRIu64 " LEAVES (%" PRIu64 " EMPTY)",
                 rows[r].label, c->leaves, c->empty);
        text_upper(text);
        int y = 2 * font;
        y += draw_label(panel, 2 * font, y, font, text) + font;
        draw_label(panel, 2 * font, y, font, boxes ? "NODE BOXES BY DEPTH" : "SPLIT PLANES BY DEPTH");
        draw_frame(panel, 0, 0, size - 1, size - 1, frame, 1.f);
        draw_paste(out, panel, 0, r * size);
        /* top view */
        if (draw_panel_top(panel, &tv, c, mode,
                           mode == DRAW_COLOR_DEPTH ? max_depth : (double)refs_scale, cam,
                           &err) != BSP_OK) {
            fprintf(stderr, "%s: %s\n", prog, err.message);
            rc = EXIT_INPUT;
            goto images;
        }
        draw_label(panel, 2 * font, 2 * font, font,
                   mode == DRAW_COLOR_DEPTH ? "FROM ABOVE: DEEPEST LEAF"
                                            : "FROM ABOVE: FULLEST LEAF");
        draw_legend(panel, font, mode, mode == DRAW_COLOR_DEPTH ? max_depth : (double)refs_scale);
        draw_frame(panel, 0, 0, size - 1, size - 1, frame, 1.f);
        draw_paste(out, panel, size, r * size);
    }
    if (bsp_image_write(out, out_path, &err) != BSP_OK) {
        fprintf(stderr, "%s: %s\n", prog, err.message);
        rc = EXIT_INPUT;
    } else if (!quiet) {
        fprintf(stderr, "%s: wrote %s (%d x %d)\n", prog, out_path, 2 * size, nrows * size);
    }
images:
    bsp_image_destroy(panel);
    bsp_image_destroy(out);
    bsp_image_destroy(back);
done:
    for (int r = 0; r < nrows; r++) {
        draw_cells_free(&rows[r].cells);
        bsp_accel_destroy(rows[r].accel);
    }
    bsp_scene_destroy(scene);
    return rc;
}
