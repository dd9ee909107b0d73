/*
 * build.c — `bspray build`: build a scene's kd-tree once and save it as a
 * file (bsp_accel_save), for `render`, `trace` and `stats --tree FILE` and
 * for bsp_accel_load.
 */
#include <inttypes.h>
#include <stdio.h>
#include <string.h>

#include "bspray/bspray.h"
#include "cli.h"

static const char build_usage[] =
    "bspray build SCENE -o FILE [--accel METHOD] [build options] [--check] [--stats-json F]\n"
    "                   [--quiet]";

static const char build_help[] =
    "Build SCENE's kd-tree and save it in FILE, so that later runs load it instead of\n"
    "building it again: `bspray render|trace|stats SCENE --tree FILE`, or\n"
    "bsp_accel_load in the library. The file holds the nodes and leaf lists, the method\n"
    "and options that shaped them, and a fingerprint of the scene's primitives: it can\n"
    "only be used with the very same scene. Prints the tree's figures and the file's\n"
    "size (docs/formats.md, \"kd-tree files\").\n"
    "\n"
    "  -o FILE            the file to write (whole or not at all)\n"
    "  --check            run the tree invariant checker before saving\n"
    "  --stats-json FILE  also write the scene's and the tree's figures as JSON, as\n"
    "                     `bspray stats --stats-json` does\n"
    "  --quiet            print nothing on success\n";

int cmd_build(int argc, char **argv)
{
    args a = {argc, 1, argv, build_usage, NULL};
    const char *scene_path = NULL, *out_path = NULL, *json_path = NULL;
    int check = 0, quiet = 0;
    view_args view = {0};
    bsp_build_options bopts;
    bsp_build_options_defaults(&bopts);
    for (; a.i < argc; a.i++) {
        const char *s = argv[a.i];
        if (is_help(s)) {
            printf("usage: %s\n\n%s%s%s", build_usage, build_help, build_args_help,
                   view_args_help);
            return 0;
        } else if (!strcmp(s, "-o") || !strcmp(s, "--output")) {
            out_path = opt_value(&a, s);
        } else if (!strcmp(s, "--check")) {
            check = 1;
        } else if (!strcmp(s, "--stats-json")) {
            json_path = opt_value(&a, s);
        } else if (!strcmp(s, "--quiet") || !strcmp(s, "-q")) {
            quiet = 1;
        } else if (parse_build_arg(&a, &bopts) || parse_view_arg(&a, &view)) {
            continue;
        } else {
            take_operand(&a, &scene_path);
        }
    }
    if (!scene_path)
        die_usage(a.usage, "%s", "missing SCENE");
    if (!out_path)
        die_usage(a.usage, "%s", "missing -o FILE");
    if (bopts.kind == BSP_ACCEL_NAIVE)
        die_usage(a.usage, "%s", "the naive method has no structure to save: use a kd-tree");
    if (!output_path_writable(out_path) || (json_path && !output_path_writable(json_path)))
        return EXIT_INPUT;
    bsp_scene *scene = load_scene(scene_path);
    apply_view_args(scene, scene_path, &view, &bopts, NULL);
    bsp_accel *accel = build_accel(scene, &bopts);
    bsp_error err;
    int rc = 0;
    bsp_tree_stats t;
    bsp_accel_tree_stats(accel, &t);
    if (check && bsp_accel_check(accel, &err) != BSP_OK) {
        fprintf(stderr, "%s: %s: %s\n", prog, scene_path, err.message);
        rc = EXIT_INPUT;
    } else if (bsp_accel_save(accel, out_path, &err) != BSP_OK) {
        fprintf(stderr, "%s: %s\n", prog, err.message);
        rc = EXIT_INPUT;
    } else if (json_path &&
               !write_stats_json_file(json_path, scene_path, scene, accel, &t, NULL, check)) {
        rc = EXIT_INPUT;
    } else if (!quiet) {
        long size = -1;
        FILE *f = fopen(out_path, "rb");
        if (f && fseek(f, 0, SEEK_END) == 0)
            size = ftell(f);
        if (f)
            fclose(f);
        printf("scene: %s (%zu primitives)\n", scene_path, bsp_scene_prim_count(scene));
        printf("structure: %s\n", bsp_accel_kind_name(bsp_accel_get_kind(accel)));
        printf("  T_B[s]         %.4f\n", bsp_accel_build_seconds(accel));
        printf("  N_IN           %" PRIu64 "\n", t.interior_nodes);
        printf("  N_V            %" PRIu64 "\n", t.leaves);
        printf("  N_OIV          %" PRIu64 "\n", t.references);
        printf("  expected cost  %.3f\n", t.expected_cost);
        printf("  digest         %016" PRIx64 "\n", t.digest);
        if (check)
            printf("  invariants     ok\n");
        printf("wrote %s (%ld bytes)\n", out_path, size);
    }
    bsp_accel_destroy(accel);
    bsp_scene_destroy(scene);
    return rc;
}
