/*
 * paper.c — `bspray bench --paper`: Table 1 of Havran, Bittner & Kopal
 * ("BSPT for perspective projection") by one command.
 *
 * The paper's protocol: 513 x 513 rays, ray depth 4, trees of maximum depth
 * 18 with at most 2 primitives per leaf — its only termination criteria, so
 * the SAH trees split until those limits (--cost-termination: also a leaf
 * where no split pays) — mailboxes on. For every scene and
 * rule: build, validate against the naive method (as plain bench does), then
 * render and count; the renders of a scene's rules take turns, --repeat
 * rounds of them, and each rule's best time is reported. The paper counts
 * primary rays; a second block has the same figures over all the render's
 * rays, a third the times. sah-par
 * trees are built for, and rendered with, the orthographic camera of the
 * same view (its own rays); an `sah` tree rendered with those rays is the
 * reference next to it. The paper's own numbers sit in rows of their own.
 */
#include <errno.h>
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench.h"
#include "cli.h"

static const char paper_usage[] =
    "bspray bench --paper [SCENE...] [--accel LIST] [--res N] [--depth N] [--threads N]\n"
    "                     [--validate N] [--repeat N] [--mailbox on|off] [--mixed-model M]\n"
    "                     [--mixed-check on|off] [--cost-termination] [--csv FILE]\n"
    "                     [--plot FILE.png] [--quiet]";

typedef struct paper_rule {
    const char *label;
    bsp_accel_kind kind;
    int ortho;   /* rendered with (and for sah-par, built for) the orthographic camera */
    int variant; /* accel_method.variant: octree-cost, grid-bounds */
} paper_rule;

#define MAX_RULES 16

static const paper_rule default_rules[] = {
    {"kaplan", BSP_ACCEL_KAPLAN, 0, 0},   {"sah", BSP_ACCEL_SAH, 0, 0},
    {"sah-per", BSP_ACCEL_SAH_PER, 0, 0}, {"sah-mixed", BSP_ACCEL_SAH_MIXED, 0, 0},
    {"sah, ortho", BSP_ACCEL_SAH, 1, 0},  {"sah-par, ortho", BSP_ACCEL_SAH_PAR, 1, 0}};

/* Table 1 of the paper (scenes fluid, lattice, rings, tree; fluid is not
 * one of ours). */
typedef struct paper_figures {
    const char *scene;
    double cov, leaves_sah, leaves_per, nit_sah, nit_per, nts_sah, nts_per;
} paper_figures;

static const paper_figures paper_table[] = {
    {"spd:lattice", 99.24, 15722, 13247, 11.9, 9.13, 44.9, 29.7},
    {"spd:rings", 100.0, 11845, 16322, 11.1, 9.15, 40.9, 38.1},
    {"spd:tree", 64.6, 2750, 3992, 10.1, 6.39, 23.1, 19.0}};

static const paper_figures *paper_of(const char *scene)
{
    for (size_t i = 0; i < sizeof paper_table / sizeof paper_table[0]; i++)
        if (!strcmp(paper_table[i].scene, scene))
            return &paper_table[i];
    return NULL;
}

/* The figures of one scene x rule. */
typedef struct cell {
    int done;
    int kept_sah; /* sah-mixed: its check kept the plain sah tree */
    double t_build, t_render;
    bsp_tree_stats tree;
    uint64_t rays_primary, hits_primary, rays_all;
    double nit_primary, nts_primary, nit_all, nts_all;
} cell;

typedef struct paper_opts {
    bench_cmdline cl;     /* mailbox: traversal with mailboxes (default 1) */
    int cost_termination; /* 0: split to the limits, as the paper */
    bsp_mixed_model mixed_model; /* sah-mixed's model of the other rays */
    int mixed_check;             /* sah-mixed's check against sah (default 1) */
    paper_rule rules[MAX_RULES];
    int nrules;
} paper_opts;

static void print_help(void)
{
    printf("usage: %s\n\n"
           "Table 1 of Havran, Bittner & Kopal, \"Adaptive data structures for visibility\n"
           "computing\": for every scene and rule, a 513 x 513 render with ray depth 4 on a\n"
           "tree of maximum depth 18 (an octree: 6 octree levels, 18 kd levels) and at most 2\n"
           "primitives per leaf (mailboxes on), after validating the tree against the naive\n"
           "method. Printed as Markdown: the paper's\n"
           "figures for primary rays (scene coverage, rays, leaves, intersection tests and\n"
           "traversal steps per ray), the same over all rays, then build and render times;\n"
           "the paper's own numbers are in the rows marked (paper).\n"
           "\n"
           "  SCENE...        scenes (default: lattice, rings, tree, then the other SPD scenes)\n"
           "  --accel LIST    rules (default: kaplan, sah, sah-per, sah-mixed, and with the\n"
           "                  orthographic camera sah and sah-par); sah-par always renders\n"
           "                  with the orthographic camera it is built for\n"
           "  --res N         N x N rays (default 513)\n"
           "  --depth N       ray depth (default 4)\n"
           "  --threads N     build and render threads (default 1: single-thread times)\n"
           "  --validate N    random rays compared with naive before each render (default 5000)\n"
           "  --repeat N      N rounds, each rendering every rule's tree once; the best\n"
           "                  time of each (default 3; on 1 thread CPU time, else wall)\n"
           "  --mailbox on|off  mailboxes in the traversal (default on; Havran's reference\n"
           "                  tables count without them); the trees keep the mailbox term\n"
           "                  of the cost model either way unless --straddle twice\n"
           "  --mixed-model M sah-mixed's model of the non-primary rays: counted (default),\n"
           "                  sampled or surface (see 'bspray render --help')\n"
           "  --mixed-check on|off  sah-mixed keeps the sah tree where a 64 x 64 render's\n"
           "                  rays cost less on it (default on; see 'bspray render --help')\n"
           "  --cost-termination  SAH trees also make a leaf where no split pays (bspray's\n"
           "                  everyday rule); by default they split until the limits, as the\n"
           "                  paper's trees do\n"
           "  --csv FILE      one row per scene x rule x ray set, columns scene, accel, camera,\n"
           "                  rays (primary or all), ScnCov, nrays, N_V, N_IT, N_TS, T_B, T_TR,\n"
           "                  threads, tree (the rule, or sah where sah-mixed kept sah's tree)\n"
           "  --plot FILE.png also draw T_B + T_TR per scene and rule as bars (log scale)\n"
           "  --quiet         no progress lines\n"
           "  --costs LIST, --empty-bonus F, --min-saving X, --leaf-budget X, --leaf-budget-min N,\n"
           "                 --budget-cut F|off  the SAH model (see\n"
           "                 'bspray render --help')\n",
           paper_usage);
}

static void parse_rules(args *a, paper_opts *o)
{
    accel_method methods[MAX_RULES];
    o->nrules = parse_accel_list(a, opt_value(a, "--accel"), methods, MAX_RULES);
    for (int r = 0; r < o->nrules; r++) {
        if (methods[r].kind == BSP_ACCEL_NAIVE)
            die_usage(a->usage, "%s", "--paper compares trees; naive has none");
        int ortho = methods[r].kind == BSP_ACCEL_SAH_PAR;
        o->rules[r] = (paper_rule){ortho ? "sah-par, ortho" : accel_method_name(&methods[r]),
                                   methods[r].kind, ortho, methods[r].variant};
    }
}

/* Builds and validates one scene x rule: its tree in *OUT, T_B and the tree
 * figures in *C; 0, or 1 on failure (a message printed). */
static int build_cell(const paper_opts *o, const char *name, const bsp_scene *scene,
                      const bsp_accel *naive, const paper_rule *r, cell *c, bsp_accel **out)
{
    bsp_build_options bo;
    bsp_build_options_defaults(&bo);
    apply_method(&(accel_method){r->kind, r->variant}, &bo);
    /* the paper's 18 levels; an octree's levels are three kd levels each */
    bo.max_depth = r->kind == BSP_ACCEL_OCTREE ? 18 / 3 : 18;
    bo.max_leaf_prims = 2;
    bo.sah_split_to_limits = !o->cost_termination;
    bo.threads = o->cl.threads; /* T_B on as many threads as the render (default 1) */
    bo.mailbox = o->cl.mailbox;
    bo.mixed_model = o->mixed_model;
    bo.mixed_check = o->mixed_check;
    apply_cost_args(&o->cl.costs, &bo);
    if (!o->cl.quiet)
        fprintf(stderr, "%s: %s: %s: building\n", prog, name, r->label);
    bsp_accel *accel = build_accel(scene, &bo);
    c->t_build = bsp_accel_build_seconds(accel);
    bsp_accel_tree_stats(accel, &c->tree);
    bsp_mixed_check chk;
    bsp_accel_mixed_check(accel, &chk);
    c->kept_sah = chk.ran && chk.kept_sah;
    char what[256];
    if (bench_validate(accel, naive, scene, o->cl.nvalidate, what, sizeof what) < 0) {
        fprintf(stderr, "%s: %s: %s differs from the naive method on %s; aborting\n", prog, name,
                r->label, what);
        bsp_accel_destroy(accel);
        return 1;
    }
    c->t_render = INFINITY;
    *out = accel;
    return 0;
}

/* Renders one scene x rule once with ACCEL: the counts into *C (the same
 * every time), the render time kept when it is C's best; 0, or 1 on failure.
 * On one thread (the render runs on the calling thread) the time is its CPU time (less disturbed by other
 * work on the machine than the wall clock), on more the wall clock. */
static int render_cell(const paper_opts *o, const char *name, const paper_rule *r,
                       const bsp_accel *accel, cell *c)
{
    bsp_render_options ro;
    bsp_render_options_defaults(&ro);
    ro.width = ro.height = o->cl.res;
    ro.max_depth = o->cl.depth;
    ro.threads = o->cl.threads;
    ro.orthographic = r->ortho;
    bsp_render_stats st;
    bsp_error err;
    bsp_image *img = NULL;
    double c0 = bench_cpu_seconds();
    bsp_status rs = bsp_render(accel, &ro, &img, &st, &err);
    double cpu = bench_cpu_seconds() - c0;
    bsp_image_destroy(img);
    if (rs != BSP_OK) {
        fprintf(stderr, "%s: %s: %s\n", prog, name, err.message);
        return 1;
    }
    double t = o->cl.threads == 1 ? cpu : st.render_seconds;
    c->t_render = t < c->t_render ? t : c->t_render;
    const bsp_ray_class_stats *P = &st.cls[BSP_RAY_PRIMARY];
    uint64_t tests = 0, steps = 0;
    c->rays_all = 0;
    for (int k = 0; k < BSP_RAY_CLASS_COUNT; k++) {
        c->rays_all += st.cls[k].rays;
        tests += st.cls[k].isect_tests;
        steps += st.cls[k].traversal_steps;
    }
    c->rays_primary = P->rays;
    c->hits_primary = P->hits;
    c->nit_primary = P->rays ? (double)P->isect_tests / (double)P->rays : 0.0;
    c->nts_primary = P->rays ? (double)P->traversal_steps / (double)P->rays : 0.0;
    c->nit_all = c->rays_all ? (double)tests / (double)c->rays_all : 0.0;
    c->nts_all = c->rays_all ? (double)steps / (double)c->rays_all : 0.0;
    c->done = 1;
    return 0;
}

/* One scene: every rule's tree built and validated first, then REPEAT
 * rounds that render each tree once, so that a slow spell of the machine
 * falls on every rule alike; each rule's best time is kept. 0, or 1. */
static int run_scene(const paper_opts *o, const char *name, const bsp_scene *scene,
                     cell *cells)
{
    bsp_build_options nb;
    bsp_build_options_defaults(&nb);
    nb.kind = BSP_ACCEL_NAIVE; /* the reference */
    bsp_accel *naive = build_accel(scene, &nb);
    bsp_accel *trees[MAX_RULES] = {NULL};
    int rc = 0;
    for (int r = 0; r < o->nrules && rc == 0; r++)
        rc = build_cell(o, name, scene, naive, &o->rules[r], &cells[r], &trees[r]);
    bsp_accel_destroy(naive);
    for (int rep = 0; rep < o->cl.repeat && rc == 0; rep++) {
        if (!o->cl.quiet)
            fprintf(stderr, "%s: %s: rendering, round %d of %d\n", prog, name, rep + 1,
                    o->cl.repeat);
        for (int r = 0; r < o->nrules && rc == 0; r++)
            rc = render_cell(o, name, &o->rules[r], trees[r], &cells[r]);
    }
    for (int r = 0; r < o->nrules; r++)
        bsp_accel_destroy(trees[r]);
    return rc;
}

/* --- output ------------------------------------------------------------------------- */

typedef struct table {
    const paper_opts *o;
    const char **scenes;
    int nscenes;
    cell *cells; /* [scene * nrules + rule] */
} table;

static const cell *at(const table *t, int s, int r)
{
    return &t->cells[(size_t)s * (size_t)t->o->nrules + (size_t)r];
}

static void header(const table *t, const char *first)
{
    printf("| %s |", first);
    for (int s = 0; s < t->nscenes; s++)
        printf(" %s |", t->scenes[s]);
    printf("\n|---|");
    for (int s = 0; s < t->nscenes; s++)
        printf("---:|");
    printf("\n");
}

/* Which figure a row shows. */
enum figure { F_COV, F_RAYS, F_LEAVES, F_NIT, F_NTS, F_TB, F_TR, F_TOTAL };

static double figure_of(const cell *c, enum figure f, int all)
{
    switch (f) {
    case F_COV:
        return c->rays_primary ? 100.0 * (double)c->hits_primary / (double)c->rays_primary : 0.0;
    case F_RAYS:
        return (double)(all ? c->rays_all : c->rays_primary) * 1e-4;
    case F_LEAVES:
        return (double)c->tree.leaves;
    case F_NIT:
        return all ? c->nit_all : c->nit_primary;
    case F_NTS:
        return all ? c->nts_all : c->nts_primary;
    case F_TB:
        return c->t_build;
    case F_TR:
        return c->t_render;
    case F_TOTAL:
        return c->t_build + c->t_render;
    }
    return 0.0;
}

static void value(double v, enum figure f)
{
    if (f == F_LEAVES)
        printf(" %.0f |", v);
    else if (f == F_TB || f == F_TR || f == F_TOTAL)
        printf(" %.3f |", v);
    else
        printf(" %.2f |", v);
}

/* One row per rule, under a bold caption row. */
static void rule_rows(const table *t, const char *caption, enum figure f, int all)
{
    printf("| **%s** |", caption);
    for (int s = 0; s < t->nscenes; s++)
        printf(" |");
    printf("\n");
    for (int r = 0; r < t->o->nrules; r++) {
        printf("| %s |", t->o->rules[r].label);
        for (int s = 0; s < t->nscenes; s++) {
            const cell *c = at(t, s, r);
            if (c->done)
                value(figure_of(c, f, all), f);
            else
                printf(" – |");
        }
        printf("\n");
    }
}

/* The paper's SAH and PER rows of a figure (primary rays only). */
static void paper_rows(const table *t, enum figure f)
{
    for (int per = 0; per < 2; per++) {
        printf("| %s (paper) |", per ? "PER" : "SAH");
        for (int s = 0; s < t->nscenes; s++) {
            const paper_figures *p = paper_of(t->scenes[s]);
            double v = !p                ? NAN
                       : f == F_LEAVES   ? (per ? p->leaves_per : p->leaves_sah)
                       : f == F_NIT      ? (per ? p->nit_per : p->nit_sah)
                                         : (per ? p->nts_per : p->nts_sah);
            if (isnan(v))
                printf(" – |");
            else
                value(v, f);
        }
        printf("\n");
    }
}

/* Coverage and ray counts of the two cameras: the first rule of each. */
static void camera_rows(const table *t, enum figure f, int all, const char *label)
{
    for (int ortho = 0; ortho < 2; ortho++) {
        int r0 = -1;
        for (int r = 0; r < t->o->nrules && r0 < 0; r++)
            if (t->o->rules[r].ortho == ortho)
                r0 = r;
        if (r0 < 0)
            continue;
        printf("| %s%s |", label, ortho ? ", ortho" : "");
        for (int s = 0; s < t->nscenes; s++) {
            const cell *c = at(t, s, r0);
            if (c->done)
                value(figure_of(c, f, all), f);
            else
                printf(" – |");
        }
        printf("\n");
    }
}

/* The change of a figure from rule A to rule B in percent, per scene. */
static void change_row(const table *t, int a, int b, enum figure f, int all, const char *what)
{
    printf("| %s: %s vs %s |", what, t->o->rules[b].label, t->o->rules[a].label);
    for (int s = 0; s < t->nscenes; s++) {
        const cell *ca = at(t, s, a), *cb = at(t, s, b);
        double va = ca->done ? figure_of(ca, f, all) : 0.0;
        double vb = cb->done ? figure_of(cb, f, all) : 0.0;
        if (ca->done && cb->done && va > 0.0)
            printf(" %+.1f%% |", 100.0 * (vb - va) / va);
        else
            printf(" – |");
    }
    printf("\n");
}

static int find_rule(const paper_opts *o, bsp_accel_kind k, int ortho)
{
    for (int r = 0; r < o->nrules; r++)
        if (o->rules[r].kind == k && o->rules[r].ortho == ortho && !o->rules[r].variant)
            return r;
    return -1;
}

static void print_tables(const table *t)
{
    const paper_opts *o = t->o;
    printf("\n### Primary rays (as the paper counts them)\n\n");
    header(t, "scene");
    camera_rows(t, F_COV, 0, "ScnCov[%]");
    printf("| ScnCov[%%] (paper) |");
    for (int s = 0; s < t->nscenes; s++) {
        const paper_figures *p = paper_of(t->scenes[s]);
        if (p)
            printf(" %.2f |", p->cov);
        else
            printf(" – |");
    }
    printf("\n");
    camera_rows(t, F_RAYS, 0, "#rays [x10^4]");
    rule_rows(t, "# leaves of the BSP tree", F_LEAVES, 0);
    paper_rows(t, F_LEAVES);
    rule_rows(t, "# intersection tests per ray", F_NIT, 0);
    paper_rows(t, F_NIT);
    rule_rows(t, "# traversal steps per ray", F_NTS, 0);
    paper_rows(t, F_NTS);

    printf("\n### All rays (primary, shadow, reflected, refracted)\n\n");
    header(t, "scene");
    rule_rows(t, "#rays [x10^4]", F_RAYS, 1);
    rule_rows(t, "# intersection tests per ray", F_NIT, 1);
    rule_rows(t, "# traversal steps per ray", F_NTS, 1);

    printf("\n### Times (seconds; render on %d thread%s, %s, best of %d round%s)\n\n",
           o->cl.threads, o->cl.threads == 1 ? "" : "s", o->cl.threads == 1 ? "CPU time" : "wall clock",
           o->cl.repeat, o->cl.repeat == 1 ? "" : "s");
    header(t, "scene");
    rule_rows(t, "T_B build", F_TB, 0);
    rule_rows(t, "T_TR render", F_TR, 0);
    rule_rows(t, "T_B + T_TR", F_TOTAL, 0);

    int sah = find_rule(o, BSP_ACCEL_SAH, 0), per = find_rule(o, BSP_ACCEL_SAH_PER, 0);
    int mixed = find_rule(o, BSP_ACCEL_SAH_MIXED, 0), kap = find_rule(o, BSP_ACCEL_KAPLAN, 0);
    int sah_o = find_rule(o, BSP_ACCEL_SAH, 1), par = find_rule(o, BSP_ACCEL_SAH_PAR, 1);
    if (mixed >= 0 && o->mixed_check) {
        printf("\nsah-mixed's check (a 64 x 64 render's rays through its tree and the sah tree) "
               "kept the sah tree on:");
        int n = 0;
        for (int s = 0; s < t->nscenes; s++)
            if (at(t, s, mixed)->kept_sah)
                printf("%s %s", n++ ? "," : "", t->scenes[s]);
        printf("%s\n", n ? "; its own tree elsewhere." : " none.");
    }
    if (sah < 0)
        return;
    printf("\n### Changes against sah (negative: fewer / faster)\n\n");
    header(t, "change");
    if (per >= 0) {
        change_row(t, sah, per, F_NIT, 0, "N_IT primary");
        change_row(t, sah, per, F_NTS, 0, "N_TS primary");
        change_row(t, sah, per, F_NIT, 1, "N_IT all");
        change_row(t, sah, per, F_TR, 0, "T_TR");
        change_row(t, sah, per, F_TOTAL, 0, "T_B + T_TR");
    }
    if (mixed >= 0) {
        change_row(t, sah, mixed, F_NIT, 0, "N_IT primary");
        change_row(t, sah, mixed, F_NIT, 1, "N_IT all");
        change_row(t, sah, mixed, F_TR, 0, "T_TR");
        change_row(t, sah, mixed, F_TOTAL, 0, "T_B + T_TR");
    }
    if (par >= 0 && sah_o >= 0) {
        change_row(t, sah_o, par, F_NIT, 0, "N_IT primary");
        change_row(t, sah_o, par, F_NTS, 0, "N_TS primary");
        change_row(t, sah_o, par, F_TR, 0, "T_TR");
    }
    if (kap >= 0)
        change_row(t, kap, sah, F_TR, 0, "T_TR");
}

static void csv_rows(FILE *f, const table *t)
{
    fprintf(f, "scene,accel,camera,rays,ScnCov,nrays,N_V,N_IT,N_TS,T_B,T_TR,threads,tree\n");
    for (int s = 0; s < t->nscenes; s++)
        for (int r = 0; r < t->o->nrules; r++) {
            const cell *c = at(t, s, r);
            if (!c->done)
                continue;
            const paper_rule *pr = &t->o->rules[r];
            const char *name = accel_method_name(&(accel_method){pr->kind, pr->variant});
            for (int all = 0; all < 2; all++)
                fprintf(f, "%s,%s,%s,%s,%.4f,%" PRIu64 ",%" PRIu64 ",%.4f,%.4f,%.6f,%.6f,%d,%s\n",
                        t->scenes[s], name,
                        pr->ortho ? "ortho" : "perspective", all ? "all" : "primary",
                        figure_of(c, F_COV, 0), all ? c->rays_all : c->rays_primary,
                        c->tree.leaves, all ? c->nit_all : c->nit_primary,
                        all ? c->nts_all : c->nts_primary, c->t_build, c->t_render,
                        t->o->cl.threads, c->kept_sah ? "sah" : name);
        }
}

/* --plot: the paper's measure, T_B + T_TR, per scene (a group of bars) and
 * rule (a colour), on a log scale. 0 with a message when it cannot be
 * written. */
static int write_plot(const char *path, const table *t)
{
    const paper_opts *o = t->o;
    const size_t ns = (size_t)t->nscenes, nr = (size_t)o->nrules;
    double *v = calloc(ns * nr + 1, sizeof *v);
    const char **names = calloc(nr + 1, sizeof *names);
    int rc = 0;
    if (!v || !names) {
        fprintf(stderr, "%s: %s: out of memory\n", prog, path);
    } else {
        for (size_t r = 0; r < nr; r++) {
            names[r] = o->rules[r].label;
            for (size_t s = 0; s < ns; s++) {
                const cell *c = &t->cells[s * nr + r];
                v[r * ns + s] = c->done ? figure_of(c, F_TOTAL, 1) : NAN;
            }
        }
        char title[160];
        snprintf(title, sizeof title, "BUILD + RENDER TIME (%d X %d, DEPTH %d, %d THREAD%s)",
                 o->cl.res, o->cl.res, o->cl.depth, o->cl.threads, o->cl.threads == 1 ? "" : "S");
        rc = bench_write_bars(path, title, "T_B + T_TR IN SECONDS, LOG SCALE (LOWER IS FASTER)",
                              t->scenes, ns, names, nr, v);
    }
    free(v);
    free(names);
    return rc;
}

/* --paper's own options. */
static int paper_option(args *a, const char *s, void *ctx)
{
    paper_opts *o = ctx;
    if (!strcmp(s, "--accel"))
        parse_rules(a, o);
    else if (!strcmp(s, "--mixed-model"))
        o->mixed_model = parse_mixed_model(a, s);
    else if (!strcmp(s, "--mixed-check"))
        o->mixed_check = parse_on_off(a, s);
    else if (!strcmp(s, "--cost-termination"))
        o->cost_termination = 1;
    else
        return 0;
    return 1;
}

int bench_paper(int argc, char **argv)
{
    args a = {argc, 1, argv, paper_usage, NULL};
    paper_opts o;
    memset(&o, 0, sizeof o);
    bench_cmdline_init(&o.cl,
                       BENCH_TAKES_RENDER | BENCH_TAKES_REPEAT | BENCH_TAKES_COSTS |
                           BENCH_TAKES_PLOT,
                       "--paper", bench_default_scenes);
    o.cl.res_min = 2;
    o.cl.threads = 1;
    o.cl.nvalidate = 5000;
    o.mixed_model = BSP_MIXED_COUNTED;
    o.mixed_check = 1;
    o.nrules = (int)(sizeof default_rules / sizeof default_rules[0]);
    memcpy(o.rules, default_rules, sizeof default_rules);
    if (bench_read_cmdline(&a, &o.cl, paper_option, &o, print_help))
        return 0;
    FILE *csv;
    if (!bench_cmdline_ready(&o.cl, 1, &csv))
        return EXIT_INPUT;
    const char **scenes = o.cl.scenes;
    int nscenes = o.cl.nscenes;
    const char *csv_path = o.cl.csv_path, *plot_path = o.cl.plot_path;
    table t = {&o, scenes, nscenes, calloc((size_t)nscenes * (size_t)o.nrules, sizeof(cell))};
    if (!t.cells) {
        fprintf(stderr, "%s: out of memory\n", prog);
        if (csv)
            fclose(csv);
        bench_free_cmdline(&o.cl);
        return EXIT_INPUT;
    }
    printf("## Table 1: BSP trees for restricted ray sets (%d x %d rays, ray depth %d, tree "
           "depth 18, 2 primitives per leaf%s, %s%s%s)\n",
           o.cl.res, o.cl.res, o.cl.depth, o.cost_termination ? ", leaves also by cost" : "",
           o.cl.mailbox ? "mailboxes" : "no mailboxes",
           o.mixed_model == BSP_MIXED_SAMPLED   ? ", sah-mixed sampled"
           : o.mixed_model == BSP_MIXED_SURFACE ? ", sah-mixed surface"
                                                : ", sah-mixed counted",
           o.mixed_check ? " with its check against sah" : "");
    int rc = 0;
    for (int s = 0; s < nscenes && rc == 0; s++) {
        bsp_scene *scene = load_scene(scenes[s]);
        if (!bsp_scene_camera(scene)) {
            fprintf(stderr, "%s: %s: no camera; skipped\n", prog, scenes[s]);
            bsp_scene_destroy(scene);
            continue;
        }
        rc = run_scene(&o, scenes[s], scene, &t.cells[(size_t)s * (size_t)o.nrules]);
        bsp_scene_destroy(scene);
    }
    if (rc == 0)
        print_tables(&t);
    if (rc == 0 && plot_path && !write_plot(plot_path, &t))
        rc = 1;
    if (csv) {
        csv_rows(csv, &t);
        if (!close_output(csv, csv_path))
            rc = 1;
    }
    free(t.cells);
    bench_free_cmdline(&o.cl);
    return rc ? EXIT_INPUT : 0;
}
