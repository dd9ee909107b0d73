/*
 * cli.h — what the subcommands of the bspray tool share: exit codes, usage
 * errors, option parsing, and loading with messages. Only the tool prints.
 */
#ifndef BSPRAY_TOOLS_CLI_H
#define BSPRAY_TOOLS_CLI_H

#include <stdio.h>

#include "bspray/bspray.h"

#define EXIT_INPUT 1 /* bad input or failure at run time */
#define EXIT_USAGE 2 /* bad command line */

extern const char *prog;

/* The command line of one subcommand, walked by index. */
typedef struct args {
    int argc, i;
    char **argv;
    const char *usage;
    const char *build_opt; /* the first option parse_build_arg took that shapes a tree
                              (not --build-threads, --max-tree-mb), or NULL */
} args;

/* Prints "bspray: " FMT (with ARG), the usage line and a hint; exits 2. */
void die_usage(const char *usage, const char *fmt, const char *arg) __attribute__((noreturn));
/* The value of option OPT (the next argument), or a usage error. */
const char *opt_value(args *a, const char *opt);
/* Whether PATH can be written (checked before a long run that writes it at
 * the end): 1, or 0 with a message naming it. Leaves no file behind that
 * was not there. */
int output_path_writable(const char *path);
/* Closes F, an output file written to PATH: 1, or 0 with a message naming
 * PATH when a write failed (a full disk), also one whose error an earlier
 * fflush met. */
int close_output(FILE *f, const char *path);
/* Removes PATH, a partial output, when it is a regular file (never a device
 * such as /dev/null, or what a symbolic link names). */
void remove_partial_output(const char *path);
/* The status a command ends with, once standard output is flushed: STATUS,
 * or EXIT_INPUT with a message when writing to it failed (a full disk, a
 * closed pipe) and STATUS was 0. */
int finish_stdout(int status);
/* A whole number in [LO, HI] as the value of OPT, or a usage error. */
int parse_int(args *a, const char *opt, long lo, long hi);
/* The expansion of macro X as a string literal (a constant inside help texts). */
#define STRINGIFY_TEXT(x) #x
#define STRINGIFY(x) STRINGIFY_TEXT(x)

int parse_on_off(args *a, const char *opt);
/* 0 when the value of OPT is W0, 1 when it is W1, or a usage error. */
int parse_one_of_two(args *a, const char *opt, const char *w0, const char *w1);
/* counted, sampled or surface: sah-mixed's model (--mixed-model). */
bsp_mixed_model parse_mixed_model(args *a, const char *opt);
int is_help(const char *s);
/* The argument a->argv[a->i], which no option took: an unknown option or a
 * second operand is a usage error; the first operand goes to *OPERAND. */
void take_operand(args *a, const char **operand);
/* A vector "x,y,z" as the value of OPT, or a usage error. */
bsp_vec3 parse_vec3(args *a, const char *opt);
/* A method of --accel: a kind, and whether it was named as a variant of
 * its kind that an option makes (VARIANT 0: the kind itself; else one of
 * "octree-cost", the octree with --octree-split cost; "grid-bounds", the
 * grid with --grid-assign bounds; "grid-rec", the recursive grid of
 * GRID_REC_LEVELS levels unless --grid-levels says more), the names
 * method_label gives them in tables. */
#define ACCEL_VARIANTS 3
#define GRID_REC_LEVELS 2
typedef struct accel_method {
    bsp_accel_kind kind;
    int variant;
} accel_method;
/* Sets O->kind to M's kind and, for a variant, the option that makes it. */
void apply_method(const accel_method *m, bsp_build_options *o);
/* M's name: its kind's, or the variant's. */
const char *accel_method_name(const accel_method *m);
/* A comma-separated list of methods (the value of --accel) into
 * METHODS[0..MAX); returns how many. An empty item, an unknown name or more
 * than MAX names is a usage error. */
int parse_accel_list(args *a, const char *list, accel_method *methods, int max);
/* --accel METHOD into OPTS (apply_method), or a usage error listing the
 * methods. */
void parse_accel(args *a, bsp_build_options *opts);
/* Options that choose and tune the acceleration structure: --accel,
 * --mailbox, --max-depth, --leaf-size, --mixed-share. Consumes the option at
 * a->argv[a->i] (and its value) and returns 1, or returns 0 for any other. */
int parse_build_arg(args *a, bsp_build_options *opts);
/* Help text of those options (one line each, indented like the commands'). */
extern const char build_args_help[];

/* The SAH cost model of the command line: --costs, --empty-bonus,
 * --min-saving, --leaf-budget, --leaf-budget-min, --budget-cut and --straddle (also taken by
 * parse_build_arg) for the commands that build
 * several structures (bench, bench --paper, bench --scaling, viz). */
typedef struct cost_args {
    bsp_sah_costs costs; /* 0 fields: the defaults */
    double empty_bonus;  /* as bsp_build_options.sah_empty_bonus */
    double min_saving;   /* as bsp_build_options.sah_min_saving */
    double leaf_budget;  /* as bsp_build_options.sah_leaf_budget */
    size_t leaf_budget_min; /* as bsp_build_options.sah_leaf_budget_min */
    double budget_cut;   /* as bsp_build_options.sah_budget_cut */
    int straddle_twice;  /* as bsp_build_options.sah_straddle_twice */
} cost_args;
/* Consumes one of those options like parse_build_arg. */
int parse_cost_arg(args *a, cost_args *c);
/* Copies C into the build options O. */
void apply_cost_args(const cost_args *c, bsp_build_options *o);

/* The camera overrides --eye, --at, --dir, --up, --fov and --ortho. */
typedef struct view_args {
    int given; /* any of eye/at/dir/up/fov */
    int has_eye, has_at, has_dir, has_up;
    bsp_vec3 eye, at, dir, up;
    double fov;
    int ortho;          /* --ortho given */
    double ortho_width; /* its width; 0: auto */
} view_args;
/* Consumes one of those options like parse_build_arg. */
int parse_view_arg(args *a, view_args *v);
extern const char view_args_help[];
/* Applies V to SCENE's camera (loaded from PATH), to the view of the modified
 * SAH rules in BOPTS and to the render options RO (either may be NULL); exits
 * 1 with a message when the result is not a valid camera. */
void apply_view_args(bsp_scene *scene, const char *path, const view_args *v,
                     bsp_build_options *bopts, bsp_render_options *ro);

/* Loads PATH (printing its warnings) or exits 1 with the message. */
bsp_scene *load_scene(const char *path);

/* Before a run of minutes over several scenes: whether each of SCENES[0..N)
 * will load, 1, or 0 after a message naming the first that will not. An SPD
 * scene's name, size and tessellation are checked (bsp_scene_check); a file
 * is loaded and freed again (a run loads one scene at a time, to hold the
 * memory of one), so that a malformed last file is reported before the work
 * on the first, not after it. */
int scenes_loadable(const char *const *scenes, int n);
/* Builds or exits 1 with the message. */
bsp_accel *build_accel(const bsp_scene *scene, const bsp_build_options *opts);
/* The help line of --tree, and the structure a command works on: the tree
 * saved in TREE_PATH (bspray build) when it is not NULL — a usage error when
 * build options were given too (A->build_opt), a message and exit 1 when it
 * cannot be loaded — else a build under OPTS (build_accel). */
extern const char tree_arg_help[];
bsp_accel *tree_or_build(const args *a, const bsp_scene *scene, const bsp_build_options *opts,
                         const char *tree_path);
/* The structure's time as a Markdown row (DIGITS decimals) and as JSON
 * member lines (indented by INDENT, each followed by a comma): T_B of a
 * build, or, when TREE_PATH (the --tree file) is not NULL, that file and
 * T_load. */
void tree_time_row(FILE *f, const char *tree_path, double seconds, int digits);
void tree_time_json(FILE *f, const char *indent, const char *tree_path, double seconds);
/* Seconds on a monotonic clock. */
double now_seconds(void);
/* A / B, or 0 when B is not positive (a per-ray figure of no rays). */
double safe_div(double a, double b);
/* The number of cores online (at least 1): the default of every --threads. */
int default_threads(void);
/* Writes S to F as a JSON string (quoted; quotes and backslashes escaped,
 * control characters dropped, each byte that is not part of well-formed
 * UTF-8 written as U+FFFD). */
void json_string(FILE *f, const char *s);
/* Writes X to F as a JSON number with up to 17 significant digits, or null
 * when it is not finite (JSON has no inf or NaN). */
void json_real(FILE *f, double x);
/* The figures of a structure (bsp_accel_tree_stats) as JSON member lines,
 * each indented by INDENT and followed by a comma: Havran's names (N_IN,
 * N_V, N_EV, N_OIV), the leaf depths, both byte counts, both expected costs,
 * the leaf budget's cut, and the digest, a string of 16 hex digits (a 64-bit
 * value is not exact as a JSON number), null for the naive method. */
void tree_stats_json(FILE *f, const char *indent, const bsp_tree_stats *t, bsp_accel_kind kind);
/* The grid's and the octree's build options (--grid-density, --grid-res,
 * --grid-assign, --octree-split) at a->argv[a->i] into OPTS: 1 when it was
 * one (its value consumed), else 0. */
int parse_subdivision_arg(args *a, bsp_build_options *opts);
/* Copies those options from FROM into TO. */
void apply_subdivision_args(const bsp_build_options *from, bsp_build_options *to);
/* The name tables and pictures give the structure O builds: its method's,
 * or for the variants those options make, "octree-cost" (the octree cut by
 * cost) and "grid-bounds" (the grid listing by bounds). */
const char *method_label(const bsp_build_options *o);
/* For a grid or an octree, the JSON member of the option that changes what
 * it is ("grid_assign": "clipped"|"bounds", "octree_split": "centre"|
 * "cost"), after INDENT and followed by a comma and a newline; nothing for
 * other methods. */
void cells_variant_json(FILE *f, const char *indent, const bsp_accel *accel);
/* method_label of the options ACCEL was built with. */
const char *accel_label(const bsp_accel *accel);

/* Whether a build of method K uses bsp_build_options.threads (the sah
 * family): the benchmarks then time it on all threads too. */
int kind_builds_in_parallel(bsp_accel_kind k);

/* The figures of `stats --stats-json` (and `build --stats-json`) in PATH: the
 * scene's (primitives by kind, bounds, lights, materials) and, with ACCEL
 * (or NULL) and its figures T (bsp_accel_tree_stats, computed once by the
 * caller), a "structure" member: T_B or the --tree file TREE_PATH and
 * T_load, tree_stats_json's figures, the method, and CHECKED's "invariants"
 * (0: no check, 1: passed, -1: failed). 0 (with a message) when PATH cannot
 * be written. */
int write_stats_json_file(const char *path, const char *scene_path, const bsp_scene *scene,
                          const bsp_accel *accel, const bsp_tree_stats *t, const char *tree_path,
                          int checked);

/* The subcommands. */
int cmd_bench(int argc, char **argv);
int cmd_viz(int argc, char **argv);
int cmd_ab(int argc, char **argv);
int cmd_trace(int argc, char **argv);
int cmd_build(int argc, char **argv);

#endif /* BSPRAY_TOOLS_CLI_H */
