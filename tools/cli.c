/*
 * cli.c — the helpers every subcommand of the bspray tool shares (cli.h).
 */
#include <errno.h>
#include <inttypes.h>
#include <limits.h>
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "cli.h"
#include "util/progress.h"

const char *prog = "bspray";

void die_usage(const char *usage, const char *fmt, const char *arg)
{
    fprintf(stderr, "%s: ", prog);
    fprintf(stderr, fmt, arg);
    fprintf(stderr, "\nusage: %s\nTry '%s --help' for more.\n", usage, prog);
    exit(EXIT_USAGE);
}

/* The value of option OPT (the next argument), or a usage error. */
const char *opt_value(args *a, const char *opt)
{
    if (a->i + 1 >= a->argc)
        die_usage(a->usage, "option '%s' needs a value", opt);
    return a->argv[++a->i];
}

int parse_int(args *a, const char *opt, long lo, long hi)
{
    const char *v = opt_value(a, opt);
    char *end;
    errno = 0;
    long x = strtol(v, &end, 10);
    if (errno || end == v || *end || x < lo || x > hi) {
        char msg[160];
        snprintf(msg, sizeof msg, "option '%s' needs a whole number from %ld to %ld, got '%%s'",
                 opt, lo, hi);
        die_usage(a->usage, msg, v);
    }
    return (int)x;
}

int parse_on_off(args *a, const char *opt)
{
    const char *v = opt_value(a, opt);
    if (!strcmp(v, "on") || !strcmp(v, "1") || !strcmp(v, "yes"))
        return 1;
    if (!strcmp(v, "off") || !strcmp(v, "0") || !strcmp(v, "no"))
        return 0;
    die_usage(a->usage, "expected on or off, got '%s'", v);
    return 0;
}

int parse_one_of_two(args *a, const char *opt, const char *w0, const char *w1)
{
    const char *v = opt_value(a, opt);
    if (!strcmp(v, w0))
        return 0;
    if (!strcmp(v, w1))
        return 1;
    char msg[256];
    snprintf(msg, sizeof msg, "%s: expected %s or %s, got '%s'", opt, w0, w1, v);
    die_usage(a->usage, "%s", msg);
    return 0;
}

bsp_mixed_model parse_mixed_model(args *a, const char *opt)
{
    const char *v = opt_value(a, opt);
    if (!strcmp(v, "surface"))
        return BSP_MIXED_SURFACE;
    if (!strcmp(v, "sampled"))
        return BSP_MIXED_SAMPLED;
    if (!strcmp(v, "counted"))
        return BSP_MIXED_COUNTED;
    die_usage(a->usage, "expected surface, sampled or counted, got '%s'", v);
    return BSP_MIXED_SURFACE;
}

void take_operand(args *a, const char **operand)
{
    const char *s = a->argv[a->i];
    if (s[0] == '-' && s[1])
        die_usage(a->usage, "unknown option '%s'", s);
    if (*operand)
        die_usage(a->usage, "unexpected argument '%s'", s);
    *operand = s;
}

int is_help(const char *s)
{
    return !strcmp(s, "-h") || !strcmp(s, "--help");
}

bsp_scene *load_scene(const char *path)
{
    bsp_scene *scene = NULL;
    bsp_error err;
    if (bsp_scene_load(path, &scene, &err) != BSP_OK) {
        fprintf(stderr, "%s: %s\n", prog, err.message);
        exit(EXIT_INPUT);
    }
    for (size_t i = 0; i < bsp_scene_warning_count(scene); i++)
        fprintf(stderr, "%s: warning: %s\n", prog, bsp_scene_warning(scene, i));
    return scene;
}

int scenes_loadable(const char *const *scenes, int n)
{
    for (int i = 0; i < n; i++) {
        bsp_error err;
        bsp_status st;
        if (strncmp(scenes[i], "spd:", 4) == 0) {
            st = bsp_scene_check(scenes[i], &err);
        } else {
            bsp_scene *s = NULL;
            st = bsp_scene_load(scenes[i], &s, &err);
            bsp_scene_destroy(s);
        }
        if (st != BSP_OK) {
            fprintf(stderr, "%s: %s\n", prog, err.message);
            return 0;
        }
    }
    return 1;
}

/* The build's progress bar, drawn only for a build that takes more than
 * half a second (most take less), on a terminal. A second tree (sah-mixed's
 * check) restarts the count, so the bar shows the most reported. */
typedef struct build_bar {
    progress_bar *bar; /* made at the first report after BUILD_BAR_DELAY */
    double start, most;
} build_bar;

#define BUILD_BAR_DELAY 0.5

static void on_build_progress(double done, void *ctx)
{
    build_bar *b = ctx;
    if (done > b->most)
        b->most = done;
    if (!b->bar && done < 1.0 && now_seconds() - b->start > BUILD_BAR_DELAY)
        b->bar = progress_create(stderr, "build");
    progress_update(b->bar, b->most);
}

bsp_accel *build_accel(const bsp_scene *scene, const bsp_build_options *opts)
{
    bsp_accel *accel = NULL;
    bsp_error err;
    bsp_build_options o = *opts;
    build_bar bar = {NULL, now_seconds(), 0.0};
    o.progress = on_build_progress;
    o.progress_ctx = &bar;
    bsp_status st = bsp_accel_build(scene, &o, &accel, &err);
    progress_finish(bar.bar);
    if (st != BSP_OK) {
        fprintf(stderr, "%s: %s\n", prog, err.message);
        exit(EXIT_INPUT);
    }
    return accel;
}

/* The variants (accel_method.variant is 1 + the index here): a name, the
 * kind, and the option that makes it. */
typedef enum { VARIANT_OCTREE_COST, VARIANT_GRID_BOUNDS, VARIANT_GRID_REC } variant_id;
static const struct {
    const char *name;
    bsp_accel_kind kind;
    variant_id id;
} variant_names[] = {{"octree-cost", BSP_ACCEL_OCTREE, VARIANT_OCTREE_COST},
                     {"grid-bounds", BSP_ACCEL_GRID, VARIANT_GRID_BOUNDS},
                     {"grid-rec", BSP_ACCEL_GRID, VARIANT_GRID_REC}};
#define VARIANTS (sizeof variant_names / sizeof *variant_names)

void apply_method(const accel_method *m, bsp_build_options *o)
{
    o->kind = m->kind;
    if (m->variant <= 0 || (size_t)m->variant > VARIANTS)
        return;
    switch (variant_names[m->variant - 1].id) {
    case VARIANT_OCTREE_COST:
        o->octree_split = BSP_OCTREE_COST;
        break;
    case VARIANT_GRID_BOUNDS:
        o->grid_assign_bounds = 1;
        break;
    case VARIANT_GRID_REC:
        if (o->grid_levels <= 1)
            o->grid_levels = GRID_REC_LEVELS;
        break;
    }
}

const char *accel_method_name(const accel_method *m)
{
    if (m->variant > 0 && (size_t)m->variant <= VARIANTS)
        return variant_names[m->variant - 1].name;
    return bsp_accel_kind_name(m->kind);
}

/* The variant whose option O carries (0: none), so that a table names it
 * as --accel would: one that applying would not change. The table is read
 * from its end, so that a grid of several levels listed by bounds is named
 * grid-rec, the variant that changes more of what it is. */
static int variant_of(const bsp_build_options *o)
{
    for (size_t i = VARIANTS; i-- > 0;) {
        if (variant_names[i].kind != o->kind)
            continue;
        bsp_build_options applied;
        memcpy(&applied, o, sizeof applied); /* byte for byte, for the memcmp */
        const accel_method m = {o->kind, (int)i + 1};
        apply_method(&m, &applied);
        if (memcmp(&applied, o, sizeof applied) == 0)
            return (int)i + 1;
    }
    return 0;
}

/* NAME as a method into *M, or a usage error listing every name. */
static void parse_method(args *a, const char *name, accel_method *m)
{
    for (size_t i = 0; i < VARIANTS; i++)
        if (!strcmp(name, variant_names[i].name)) {
            m->kind = variant_names[i].kind;
            m->variant = (int)i + 1;
            return;
        }
    bsp_error err;
    m->variant = 0;
    if (bsp_accel_kind_parse(name, &m->kind, &err) != BSP_OK) {
        /* the library's message lists its kinds ("... (known: a, b)"); the
         * variants are the CLI's, added before its closing parenthesis */
        char msg[sizeof err.message + 64];
        snprintf(msg, sizeof msg, "%s", err.message);
        char *close = strrchr(msg, ')');
        size_t len = close ? (size_t)(close - msg) : strlen(msg);
        /* room: err.message's length, and 64 bytes for the names added */
        for (size_t i = 0; i < VARIANTS && len < sizeof msg; i++)
            len += (size_t)snprintf(msg + len, sizeof msg - len, ", %s", variant_names[i].name);
        if (len < sizeof msg)
            snprintf(msg + len, sizeof msg - len, ")");
        die_usage(a->usage, "%s", msg);
    }
}

void parse_accel(args *a, bsp_build_options *opts)
{
    accel_method m;
    parse_method(a, opt_value(a, "--accel"), &m);
    apply_method(&m, opts);
}


int parse_accel_list(args *a, const char *list, accel_method *methods, int max)
{
    int n = 0;
    for (const char *p = list;;) {
        const char *comma = strchr(p, ',');
        size_t len = comma ? (size_t)(comma - p) : strlen(p);
        char name[64];
        if (len == 0 || len >= sizeof name)
            die_usage(a->usage,
                      "option '--accel' needs a comma-separated list of methods, got '%s'", list);
        if (n == max) {
            char msg[96];
            snprintf(msg, sizeof msg, "option '--accel' takes at most %d methods, got '%%s'", max);
            die_usage(a->usage, msg, list);
        }
        memcpy(name, p, len);
        name[len] = 0;
        parse_method(a, name, &methods[n]);
        n++;
        if (!comma)
            return n;
        p = comma + 1;
    }
}

bsp_vec3 parse_vec3(args *a, const char *opt)
{
    const char *v = opt_value(a, opt);
    double x, y, z;
    char extra;
    if (sscanf(v, "%lf,%lf,%lf%c", &x, &y, &z, &extra) != 3 || !isfinite(x) || !isfinite(y) ||
        !isfinite(z)) {
        char msg[160];
        snprintf(msg, sizeof msg, "option '%s' needs three finite numbers x,y,z, got '%%s'", opt);
        die_usage(a->usage, msg, v);
    }
    return bsp_v3(x, y, z);
}

double now_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

double safe_div(double a, double b)
{
    return b > 0 ? a / b : 0.0;
}

int default_threads(void)
{
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    return n > 0 ? (int)n : 1;
}

/* The length of the well-formed UTF-8 sequence at S (no overlong forms, no
 * surrogates, at most U+10FFFF), or 0 when S does not start one. */
static int utf8_length(const unsigned char *s)
{
    int n;
    unsigned min;
    unsigned cp;
    if (s[0] < 0x80)
        return 1;
    if ((s[0] & 0xe0) == 0xc0)
        n = 2, min = 0x80, cp = s[0] & 0x1fu;
    else if ((s[0] & 0xf0) == 0xe0)
        n = 3, min = 0x800, cp = s[0] & 0x0fu;
    else if ((s[0] & 0xf8) == 0xf0)
        n = 4, min = 0x10000, cp = s[0] & 0x07u;
    else
        return 0;
    for (int i = 1; i < n; i++) {
        if ((s[i] & 0xc0) != 0x80) /* also stops at the terminating NUL */
            return 0;
        cp = cp << 6 | (s[i] & 0x3fu);
    }
    if (cp < min || cp > 0x10ffff || (cp >= 0xd800 && cp <= 0xdfff))
        return 0;
    return n;
}

void json_string(FILE *f, const char *s)
{
    const unsigned char *u = (const unsigned char *)s;
    fputc('"', f);
    while (*u) {
        int n = utf8_length(u);
        if (n == 0) { /* not UTF-8 (a path's bytes in another encoding): the replacement
                         character, so that the file stays JSON */
            fputs("\\ufffd", f);
            u++;
        } else if (*u < 0x20) { /* a control character */
            u++;
        } else {
            if (*u == '"' || *u == '\\')
                fputc('\\', f);
            fwrite(u, 1, (size_t)n, f);
            u += n;
        }
    }
    fputc('"', f);
}

void json_real(FILE *f, double x)
{
    if (!isfinite(x)) {
        fputs("null", f);
        return;
    }
    char buf[32];
    for (int digits = 15; digits <= 17; digits++) { /* the shortest that reads back as X */
        snprintf(buf, sizeof buf, "%.*g", digits, x);
        if (strtod(buf, NULL) == x)
            break;
    }
    fputs(buf, f);
}

int kind_builds_in_parallel(bsp_accel_kind k)
{
    return k != BSP_ACCEL_NAIVE && k != BSP_ACCEL_KAPLAN && k != BSP_ACCEL_GRID &&
           k != BSP_ACCEL_OCTREE;
}

void tree_stats_json(FILE *f, const char *indent, const bsp_tree_stats *t, bsp_accel_kind kind)
{
    fprintf(f,
            "%s\"N_IN\": %" PRIu64 ",\n%s\"N_V\": %" PRIu64 ",\n%s\"N_EV\": %" PRIu64
            ",\n%s\"N_OIV\": %" PRIu64 ",\n",
            indent, t->interior_nodes, indent, t->leaves, indent, t->empty_leaves, indent,
            t->references);
    fprintf(f, "%s\"leaf_depth_max\": %d,\n%s\"leaf_depth_mean\": ", indent, t->max_leaf_depth,
            indent);
    json_real(f, t->avg_leaf_depth);
    fprintf(f, ",\n%s\"tree_bytes\": %" PRIu64 ",\n%s\"trace_bytes\": %" PRIu64 ",\n", indent,
            t->bytes, indent, t->trace_bytes);
    fprintf(f, "%s\"expected_cost\": ", indent);
    json_real(f, t->expected_cost);
    fprintf(f, ",\n%s\"model_cost\": ", indent);
    json_real(f, t->model_cost);
    fprintf(f, ",\n%s\"budget_cut\": ", indent);
    json_real(f, t->budget_cut);
    fprintf(f, ",\n%s\"budget_rebuilt\": %s,\n%s\"digest\": ", indent,
            t->budget_rebuilt ? "true" : "false", indent);
    if (kind == BSP_ACCEL_NAIVE)
        fputs("null", f);
    else
        fprintf(f, "\"%016" PRIx64 "\"", t->digest);
    fputs(",\n", f);
    if (kind == BSP_ACCEL_GRID)
        fprintf(f, "%s\"grid_res\": [%d, %d, %d],\n", indent, t->grid_res[0], t->grid_res[1],
                t->grid_res[2]);
}

/* The number TEXT of option OPT, or a usage error saying WHAT it must be
 * when it is not a whole number string or fails OK. */
static double parse_real(args *a, const char *opt, const char *text, int (*ok)(double),
                         const char *what)
{
    char *end;
    double x = strtod(text, &end);
    if (end == text || *end || !ok(x)) {
        char msg[160];
        snprintf(msg, sizeof msg, "option '%s' needs %s, got '%%s'", opt, what);
        die_usage(a->usage, msg, text);
    }
    return x;
}

static int in_share_range(double x)
{
    return x > 0.0 && x <= 1.0;
}
static int in_angle_range(double x)
{
    return x > 0.0 && x < 180.0;
}
static int positive_finite(double x)
{
    return x > 0.0 && isfinite(x);
}

/* The SAH cost names of --costs, with the field each sets. */
static double *cost_field(bsp_sah_costs *c, const char *name, size_t len)
{
    static const struct {
        const char *name;
        size_t offset;
    } fields[] = {{"traversal", offsetof(bsp_sah_costs, traversal)},
                  {"sphere", offsetof(bsp_sah_costs, sphere)},
                  {"triangle", offsetof(bsp_sah_costs, triangle)},
                  {"polygon", offsetof(bsp_sah_costs, polygon_base)},
                  {"vertex", offsetof(bsp_sah_costs, polygon_vertex)},
                  {"cone", offsetof(bsp_sah_costs, cone)}};
    for (size_t i = 0; i < sizeof fields / sizeof fields[0]; i++)
        if (strlen(fields[i].name) == len && !strncmp(fields[i].name, name, len))
            return (double *)((char *)c + fields[i].offset);
    return NULL;
}

/* --costs NAME=X[,NAME=X...]: the SAH's C_trav and T_i, each in
 * [BSP_SAH_COST_MIN, BSP_SAH_COST_MAX]; names not given keep their defaults
 * (0 in the options). */
static void parse_costs(args *a, const char *opt, bsp_sah_costs *c)
{
    const char *v = opt_value(a, opt), *p = v;
    bsp_sah_costs out = *c;
    while (*p) {
        const char *eq = strchr(p, '='), *comma = strchr(p, ',');
        size_t len = eq ? (size_t)(eq - p) : 0;
        double *f = eq && (!comma || eq < comma) ? cost_field(&out, p, len) : NULL;
        if (!f)
            die_usage(a->usage,
                      "--costs: expected NAME=X[,NAME=X...] with NAME one of traversal, "
                      "sphere, triangle, polygon, vertex, cone; got '%s'",
                      v);
        char *end;
        double x = strtod(eq + 1, &end);
        if (end == eq + 1 || (*end && *end != ',') ||
            !(x >= BSP_SAH_COST_MIN && x <= BSP_SAH_COST_MAX))
            die_usage(a->usage,
                      "--costs: every cost must be a number in [" STRINGIFY(
                          BSP_SAH_COST_MIN) ", " STRINGIFY(BSP_SAH_COST_MAX) "]; got '%s'",
                      v);
        *f = x;
        p = *end == ',' ? end + 1 : end;
        if (*end == ',' && !*p)
            die_usage(a->usage, "--costs: trailing comma in '%s'", v);
    }
    *c = out;
}

static int in_bonus_range(double x)
{
    return x >= 0.0 && x < 1.0;
}

static int positive_share(double x)
{
    return x > 0.0 && x <= 1e6;
}

static int in_saving_range(double x)
{
    return x >= 0.0 && x < INFINITY;
}

#define COST_ARGS_HELP                                                                             \
    "  --costs LIST       sah family: the cost model, NAME=X,... relative to one traversal\n"      \
    "                     step: traversal (C_trav, default 1), sphere, triangle, polygon\n"        \
    "                     and vertex (an n-gon costs polygon + n * vertex), cone; the\n"           \
    "                     defaults are `bspray calibrate`'s ratios (docs/kdtree.md)\n"             \
    "  --empty-bonus F    sah family: a split with an empty side costs (1 - F) times as\n"         \
    "                     much, F in [0, 1) (default 0.1; 0: no bonus)\n"                          \
    "  --min-saving X     sah family: make a split only when it saves at least X mean\n"           \
    "                     intersection tests per ray of the whole tree, X >= 0 (default\n"         \
    "                     1e-9: prunes chains of tiny cells at shared vertices; 0: none)\n"        \
    "  --leaf-budget X    sah family: at most X leaves per primitive, X >= 0: a larger\n"          \
    "                     tree loses the splits that save least (default 1; 0: none)\n"            \
    "  --leaf-budget-min N  sah family: ... but never fewer than N leaves (default 131072)\n"  \
    "  --budget-cut F|off sah family: estimate the budget's threshold from a sample of\n"     \
    "                     subtrees and skip the splits saving less than F times it, F > 0\n" \
    "                     (default 0.75; any F builds the same tree, a large one only\n"       \
    "                     twice); off builds the whole tree, then prunes\n"                   \
    "  --straddle once|twice  sah family: a primitive straddling a split costs a ray\n"      \
    "                     through both children one test and a mailbox hit (once, the\n"    \
    "                     default, with mailboxes on or off) or two tests (twice:\n"        \
    "                     MacDonald and Booth's plain model)\n"

int parse_cost_arg(args *a, cost_args *c)
{
    const char *s = a->argv[a->i];
    if (!strcmp(s, "--costs")) {
        parse_costs(a, s, &c->costs);
    } else if (!strcmp(s, "--empty-bonus")) {
        double f = parse_real(a, s, opt_value(a, s), in_bonus_range, "a number in [0, 1)");
        c->empty_bonus = f > 0.0 ? f : -1.0; /* the options' 0 means the default */
    } else if (!strcmp(s, "--min-saving")) {
        double x = parse_real(a, s, opt_value(a, s), in_saving_range, "a number >= 0");
        c->min_saving = x > 0.0 ? x : -1.0; /* likewise */
    } else if (!strcmp(s, "--leaf-budget")) {
        double x = parse_real(a, s, opt_value(a, s), in_saving_range, "a number >= 0");
        c->leaf_budget = x > 0.0 ? x : -1.0; /* likewise */
    } else if (!strcmp(s, "--leaf-budget-min")) {
        c->leaf_budget_min = (size_t)parse_int(a, s, 1, 1 << 30);
    } else if (!strcmp(s, "--budget-cut")) {
        const char *v = opt_value(a, s);
        c->budget_cut = !strcmp(v, "off") ? -1.0
                                           : parse_real(a, s, v, positive_share, "a number > 0 or 'off'");
    } else if (!strcmp(s, "--straddle")) {
        c->straddle_twice = parse_one_of_two(a, s, "once", "twice");
    } else {
        return 0;
    }
    return 1;
}

void apply_cost_args(const cost_args *c, bsp_build_options *o)
{
    o->sah_costs = c->costs;
    o->sah_empty_bonus = c->empty_bonus;
    o->sah_min_saving = c->min_saving;
    o->sah_leaf_budget = c->leaf_budget;
    o->sah_leaf_budget_min = c->leaf_budget_min;
    o->sah_budget_cut = c->budget_cut;
    o->sah_straddle_twice = c->straddle_twice;
}

static int in_density_range(double x)
{
    return x > 0.0 && x <= 1e6;
}

/* --grid-res X,Y,Z: three whole numbers in 1..BSP_GRID_MAX_RES. */
static void parse_grid_res(args *a, const char *opt, int res[3])
{
    const char *v = opt_value(a, opt), *p = v;
    for (int k = 0; k < 3; k++) {
        char *end;
        errno = 0;
        long x = strtol(p, &end, 10);
        if (errno || end == p || x < 1 || x > BSP_GRID_MAX_RES || *end != (k < 2 ? ',' : '\0')) {
            char msg[160];
            snprintf(msg, sizeof msg,
                     "option '%s' needs three whole numbers X,Y,Z from 1 to %d, got '%%s'", opt,
                     BSP_GRID_MAX_RES);
            die_usage(a->usage, msg, v);
        }
        res[k] = (int)x;
        p = end + 1;
    }
}

#define SUBDIVISION_ARGS_HELP                                                                             \
    "  --grid-density D   grid: about D cells per primitive, cubic cells over the scene's\n"      \
    "                     box, 0 < D <= 1e6 (default 4; Havran's tables use 1 and 10)\n"         \
    "  --grid-res X,Y,Z   grid: exactly these cells per axis (overrides --grid-density)\n"       \
    "  --grid-assign clipped|bounds  grid: a primitive goes in the cells its part reaches\n"    \
    "                     (clipped, default) or in every cell its bounds overlap (bounds:\n"     \
    "                     Havran's 1999 grids; see docs/grid.md)\n"                        \
    "  --grid-levels L    grid: 1 (default) uniform; 2..8 a recursive grid of at most L\n"    \
    "                     grids nested (Jevans and Wyvill): a cell listing more than\n"       \
    "                     --grid-cell-prims primitives gets a grid of its own, at the\n"      \
    "                     same density over them (grid-rec: L = 2)\n"                         \
    "  --grid-cell-prims T  recursive grid: cut the cells that list more than T\n"            \
    "                     primitives (default 8)\n"                                           \
    "  --octree-split centre|cost  octree: cut each node at the centre of its box\n"       \
    "                     (default) or, on each axis, at the least of a cost estimate\n"   \
    "                     between the centre and the median of its primitives (the\n"     \
    "                     adaptive octree of Havran's 1999 statistics; docs/octree.md)\n"

int parse_subdivision_arg(args *a, bsp_build_options *opts)
{
    const char *s = a->argv[a->i];
    if (!strcmp(s, "--grid-density"))
        opts->grid_density =
            parse_real(a, s, opt_value(a, s), in_density_range, "a number in (0, 1e6]");
    else if (!strcmp(s, "--grid-assign"))
        opts->grid_assign_bounds = parse_one_of_two(a, s, "clipped", "bounds");
    else if (!strcmp(s, "--grid-res"))
        parse_grid_res(a, s, opts->grid_res);
    else if (!strcmp(s, "--grid-levels"))
        opts->grid_levels = parse_int(a, s, 1, BSP_GRID_MAX_LEVELS);
    else if (!strcmp(s, "--grid-cell-prims"))
        opts->grid_cell_prims = parse_int(a, s, 1, INT_MAX);
    else if (!strcmp(s, "--octree-split"))
        opts->octree_split =
            parse_one_of_two(a, s, "centre", "cost") ? BSP_OCTREE_COST : BSP_OCTREE_CENTRE;
    else
        return 0;
    return 1;
}

void apply_subdivision_args(const bsp_build_options *from, bsp_build_options *to)
{
    to->grid_density = from->grid_density;
    memcpy(to->grid_res, from->grid_res, sizeof to->grid_res);
    to->grid_assign_bounds = from->grid_assign_bounds;
    to->grid_levels = from->grid_levels;
    to->grid_cell_prims = from->grid_cell_prims;
    to->octree_split = from->octree_split;
}

const char *method_label(const bsp_build_options *o)
{
    /* the variant apply_method makes, read back from the options */
    const accel_method m = {o->kind, variant_of(o)};
    return accel_method_name(&m);
}

const char *accel_label(const bsp_accel *accel)
{
    bsp_build_options o;
    bsp_accel_get_options(accel, &o);
    return method_label(&o);
}

void cells_variant_json(FILE *f, const char *indent, const bsp_accel *accel)
{
    bsp_build_options o;
    bsp_accel_get_options(accel, &o);
    if (o.kind == BSP_ACCEL_GRID) {
        fprintf(f, "%s\"grid_assign\": \"%s\",\n", indent,
                o.grid_assign_bounds ? "bounds" : "clipped");
        fprintf(f, "%s\"grid_levels\": %d,\n", indent, o.grid_levels);
        if (o.grid_levels > 1)
            fprintf(f, "%s\"grid_cell_prims\": %d,\n", indent, o.grid_cell_prims);
    }
    else if (o.kind == BSP_ACCEL_OCTREE)
        fprintf(f, "%s\"octree_split\": \"%s\",\n", indent,
                o.octree_split == BSP_OCTREE_COST ? "cost" : "centre");
}

const char build_args_help[] =
    "  --accel METHOD     acceleration method: sah (default), sah-per, sah-par, sah-mixed,\n"
    "                     kaplan, grid (a uniform grid), octree (--octree-split), bvh\n"
    "                     (a binned-SAH bounding volume hierarchy, to compare with),\n"
    "                     bvh4, bvh8 (that BVH with four or eight children per node,\n"
    "                     float SIMD tests), naive (sah-per/-par/-mixed build for the\n"
    "                     camera's rays); also octree-cost, grid-bounds and grid-rec\n"
    "                     (the octree with --octree-split cost, the grid with\n"
    "                     --grid-assign bounds, the recursive grid of --grid-levels 2)\n"
    "  --mailbox on|off   test each primitive at most once per ray (default on)\n"
    "  --max-depth N      kd-tree: deepest leaf (default kaplan 18, sah round(8 + 1.3 log2 N));\n"
    "                     octree: its levels, at most 21 (default: the least d, 8^d >= 8 N);\n"
    "                     bvh, bvh4, bvh8: the binary build's levels, at most 60 (default)\n"
    "  --leaf-size N      kd-tree: a node of at most N primitives is a leaf (default kaplan\n"
    "                     2, sah 1: the cost decides, octree 1); the paper: --max-depth 18\n"
    "                     --leaf-size 2; bvh, bvh4, bvh8: the most a leaf holds (default 8)\n"
    "  --split-to-limits  sah family: split until --max-depth or --leaf-size ends it, even\n"
    "                     where the cost model would make a leaf (the paper's criteria)\n"
    "  --mixed-share F    sah-mixed: share of primary rays among all rays, in (0, 1]\n"
    "                     (default: measured by a 65 x 65 pre-pass)\n"
    "  --mixed-model M    sah-mixed: how the non-primary rays are modelled: counted\n"
    "                     (default: the pre-pass's rays that meet each cell, counted\n"
    "                     exactly), sampled (their density on a voxel grid) or surface\n"
    "                     (uniform lines: the surface area); see docs/modified-sah.md\n"
    "  --mixed-check on|off  sah-mixed: also build the sah tree, shoot a 64 x 64 render's\n"
    "                     rays through both and keep the cheaper (default on)\n"
    "  --build-threads N  sah family, BVHs: build threads (default: every core);\n"
    "                     the tree is the same for any N\n"
    "  --max-tree-mb N    kd-tree, octree, grid, BVH: fail when the nodes (cells) and\n"
    "                     lists need more than N MiB (default: half the machine's memory)\n"
    SUBDIVISION_ARGS_HELP COST_ARGS_HELP;

int parse_build_arg(args *a, bsp_build_options *opts)
{
    const char *s = a->argv[a->i];
    if (!strcmp(s, "--accel")) {
        parse_accel(a, opts);
    } else if (!strcmp(s, "--mailbox")) {
        opts->mailbox = parse_on_off(a, s);
    } else if (!strcmp(s, "--max-depth")) {
        opts->max_depth = parse_int(a, s, 1, BSP_KD_MAX_DEPTH_LIMIT);
    } else if (!strcmp(s, "--leaf-size")) {
        opts->max_leaf_prims = parse_int(a, s, 1, 1 << 20);
    } else if (!strcmp(s, "--split-to-limits")) {
        opts->sah_split_to_limits = 1;
    } else if (!strcmp(s, "--build-threads")) {
        opts->threads = parse_int(a, s, 1, 256);
    } else if (!strcmp(s, "--max-tree-mb")) {
        opts->max_tree_bytes = (size_t)parse_int(a, s, 1, 1 << 30) << 20;
    } else if (!strcmp(s, "--mixed-model")) {
        opts->mixed_model = parse_mixed_model(a, s);
    } else if (!strcmp(s, "--mixed-check")) {
        opts->mixed_check = parse_on_off(a, s);
    } else if (!strcmp(s, "--costs") || !strcmp(s, "--empty-bonus") || !strcmp(s, "--min-saving") ||
               !strcmp(s, "--leaf-budget") || !strcmp(s, "--leaf-budget-min") ||
               !strcmp(s, "--budget-cut") || !strcmp(s, "--straddle")) {
        cost_args c = {opts->sah_costs, opts->sah_empty_bonus, opts->sah_min_saving,
                       opts->sah_leaf_budget, opts->sah_leaf_budget_min,
                       opts->sah_budget_cut, opts->sah_straddle_twice};
        parse_cost_arg(a, &c);
        apply_cost_args(&c, opts);
    } else if (parse_subdivision_arg(a, opts)) {
        ;
    } else if (!strcmp(s, "--mixed-share")) {
        opts->mixed_primary_share =
            parse_real(a, s, opt_value(a, s), in_share_range, "a number in (0, 1]");
    } else {
        return 0;
    }
    /* what --tree refuses beside it: the options that shape a tree (not the
     * build's threads or its size limit, which a saved tree does not need) */
    if (!a->build_opt && strcmp(s, "--build-threads") != 0 && strcmp(s, "--max-tree-mb") != 0)
        a->build_opt = s;
    return 1;
}

const char tree_arg_help[] =
    "  --tree FILE        use the kd-tree saved in FILE (bspray build) instead of building\n"
    "                     one: built for this very scene (its primitives are checked),\n"
    "                     with the method and options it was built with (so no option\n"
    "                     that shapes a tree may be given beside it)\n";

bsp_accel *tree_or_build(const args *a, const bsp_scene *scene, const bsp_build_options *opts,
                         const char *tree_path)
{
    if (!tree_path)
        return build_accel(scene, opts);
    if (a->build_opt)
        die_usage(a->usage,
                  "option '--tree' uses a saved tree, built with its own options: drop '%s'",
                  a->build_opt);
    bsp_accel *accel = NULL;
    bsp_error err;
    if (bsp_accel_load(scene, tree_path, &accel, &err) != BSP_OK) {
        fprintf(stderr, "%s: %s\n", prog, err.message);
        exit(EXIT_INPUT);
    }
    return accel;
}

void tree_time_row(FILE *f, const char *tree_path, double seconds, int digits)
{
    if (tree_path)
        fprintf(f, "| tree file | %s |\n| T_load[s] | %.*f |\n", tree_path, digits, seconds);
    else
        fprintf(f, "| T_B[s] | %.*f |\n", digits, seconds);
}

void tree_time_json(FILE *f, const char *indent, const char *tree_path, double seconds)
{
    if (tree_path) {
        fprintf(f, "%s\"tree_file\": ", indent);
        json_string(f, tree_path);
        fprintf(f, ",\n%s\"T_load\": %.6f,\n", indent, seconds);
    } else {
        fprintf(f, "%s\"T_B\": %.6f,\n", indent, seconds);
    }
}

int write_stats_json_file(const char *path, const char *scene_path, const bsp_scene *scene,
                          const bsp_accel *accel, const bsp_tree_stats *t, const char *tree_path,
                          int checked)
{
    FILE *f = fopen(path, "w");
    if (!f) {
        fprintf(stderr, "%s: %s: cannot open for writing: %s\n", prog, path, strerror(errno));
        return 0;
    }
    fprintf(f, "{\n  \"scene\": ");
    json_string(f, scene_path);
    fprintf(f, ",\n  \"primitives\": %zu,\n  \"kinds\": {", bsp_scene_prim_count(scene));
    for (int k = 0; k < BSP_PRIM_KIND_COUNT; k++)
        fprintf(f, "%s\"%s\": %zu", k ? ", " : "", bsp_prim_kind_name((bsp_prim_kind)k),
                bsp_scene_kind_count(scene, (bsp_prim_kind)k));
    bsp_box b = bsp_scene_bounds(scene);
    fprintf(f, "},\n  \"bounds\": ");
    if (b.lo.x <= b.hi.x) {
        const double v[6] = {b.lo.x, b.lo.y, b.lo.z, b.hi.x, b.hi.y, b.hi.z};
        for (int i = 0; i < 6; i++) {
            fputs(i == 0 ? "{\"min\": [" : i == 3 ? "], \"max\": [" : ", ", f);
            json_real(f, v[i]);
        }
        fputs("]}", f);
    } else {
        fputs("null", f); /* no primitive */
    }
    fprintf(f, ",\n  \"lights\": %zu,\n  \"materials\": %zu", bsp_scene_light_count(scene),
            bsp_scene_material_count(scene));
    if (accel && t) {
        bsp_accel_kind kind = bsp_accel_get_kind(accel);
        fprintf(f, ",\n  \"structure\": {\n");
        tree_time_json(f, "    ", tree_path, bsp_accel_build_seconds(accel));
        tree_stats_json(f, "    ", t, kind);
        if (checked)
            fprintf(f, "    \"invariants\": \"%s\",\n", checked > 0 ? "ok" : "failed");
        cells_variant_json(f, "    ", accel);
        fprintf(f, "    \"accel\": \"%s\"\n  }", bsp_accel_kind_name(kind));
    }
    fputs("\n}\n", f);
    return close_output(f, path);
}

const char view_args_help[] =
    "  --eye, --at, --up X,Y,Z   override the camera (any of them; for meshes, the rest\n"
    "                     of the default view adapts); --dir X,Y,Z: look along X,Y,Z\n"
    "                     (at = eye + dir); --fov DEG its field of view\n"
    "  --ortho W|auto     orthographic camera: parallel rays along the view direction from\n"
    "                     a window W scene units wide centred on the eye (auto: the\n"
    "                     perspective view's width at the look-at point); sah-par builds\n"
    "                     for these rays\n";

int parse_view_arg(args *a, view_args *v)
{
    const char *s = a->argv[a->i];
    if (!strcmp(s, "--eye")) {
        v->eye = parse_vec3(a, s);
        v->has_eye = v->given = 1;
    } else if (!strcmp(s, "--at")) {
        v->at = parse_vec3(a, s);
        v->has_at = v->given = 1;
    } else if (!strcmp(s, "--dir")) {
        v->dir = parse_vec3(a, s);
        v->has_dir = v->given = 1;
    } else if (!strcmp(s, "--up")) {
        v->up = parse_vec3(a, s);
        v->has_up = v->given = 1;
    } else if (!strcmp(s, "--fov")) {
        v->fov = parse_real(a, s, opt_value(a, s), in_angle_range, "degrees in (0, 180)");
        v->given = 1;
    } else if (!strcmp(s, "--ortho")) {
        const char *val = opt_value(a, s);
        v->ortho = 1;
        v->ortho_width = !strcmp(val, "auto")
                             ? 0.0
                             : parse_real(a, s, val, positive_finite, "a positive width or 'auto'");
    } else {
        return 0;
    }
    if (v->has_at && v->has_dir)
        die_usage(a->usage, "%s", "give either --at or --dir, not both");
    return 1;
}

void apply_view_args(bsp_scene *scene, const char *path, const view_args *v,
                     bsp_build_options *bopts, bsp_render_options *ro)
{
    bsp_error err;
    const bsp_camera *c = bsp_scene_camera(scene);
    if (v->given && c && !bsp_scene_camera_is_default(scene)) {
        /* a scene with its own camera keeps whatever is not overridden */
        bsp_camera cam = *c;
        if (v->has_eye)
            cam.from = v->eye;
        if (v->has_at)
            cam.at = v->at;
        else if (v->has_dir)
            cam.at = (bsp_vec3){{cam.from.x + v->dir.x, cam.from.y + v->dir.y,
                                 cam.from.z + v->dir.z}};
        else if (v->has_eye) /* keep the view direction */
            cam.at = (bsp_vec3){{cam.from.x + c->at.x - c->from.x, cam.from.y + c->at.y - c->from.y,
                                 cam.from.z + c->at.z - c->from.z}};
        if (v->has_up)
            cam.up = v->up;
        if (v->fov > 0.0)
            cam.angle_deg = v->fov;
        if (bsp_scene_set_camera(scene, &cam, &err) != BSP_OK)
            goto fail;
    } else if (v->given) {
        /* a mesh: the default view, adapted to what is given */
        if (bsp_scene_set_default_view(scene, v->has_eye ? &v->eye : NULL,
                                       v->has_at ? &v->at : NULL, v->has_up ? &v->up : NULL,
                                       v->fov, &err) != BSP_OK)
            goto fail;
        c = bsp_scene_camera(scene);
        if (v->has_dir && c) {
            bsp_vec3 eye = c->from;
            bsp_vec3 at = {{eye.x + v->dir.x, eye.y + v->dir.y, eye.z + v->dir.z}};
            if (bsp_scene_set_default_view(scene, &eye, &at, v->has_up ? &v->up : NULL, v->fov,
                                           &err) != BSP_OK)
                goto fail;
        }
    }
    if (v->ortho) {
        if (bopts)
            bopts->view.ortho_width = v->ortho_width;
        if (ro) {
            ro->orthographic = 1;
            ro->ortho_width = v->ortho_width;
        }
    }
    return;
fail:
    fprintf(stderr, "%s: %s: %s\n", prog, path, err.message);
    exit(EXIT_INPUT);
}

int close_output(FILE *f, const char *path)
{
    int failed = ferror(f) != 0, saved = 0; /* an earlier flush's error: its errno is gone */
    if (fclose(f) != 0) {
        failed = 1;
        saved = errno;
    }
    if (failed)
        fprintf(stderr, "%s: %s: write failed%s%s\n", prog, path, saved ? ": " : "",
                saved ? strerror(saved) : "");
    return !failed;
}

void remove_partial_output(const char *path)
{
    struct stat st;
    if (lstat(path, &st) == 0 && S_ISREG(st.st_mode))
        remove(path);
}

int finish_stdout(int status)
{
    errno = 0;
    int failed = ferror(stdout) != 0;
    if (fflush(stdout) != 0)
        failed = 1;
    if (failed && status == 0) {
        int saved = errno;
        fprintf(stderr, "%s: standard output: write failed%s%s\n", prog, saved ? ": " : "",
                saved ? strerror(saved) : "");
        return EXIT_INPUT;
    }
    return status;
}

int output_path_writable(const char *path)
{
    struct stat st;
    const int existed = lstat(path, &st) == 0; /* a symbolic link to nothing yet, too */
    FILE *f = fopen(path, "ab"); /* appends nothing: the file stays as it is */
    if (!f) {
        fprintf(stderr, "%s: %s: cannot open for writing: %s\n", prog, path, strerror(errno));
        return 0;
    }
    fclose(f);
    if (!existed)
        remove(path);
    return 1;
}
