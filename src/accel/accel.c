/*
 * accel.c — the public front of the acceleration structures: build options,
 * method names, building through the method's table, and per-thread queries.
 */
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "accel/bvh.h"
#include "accel/grid.h"
#include "accel/kd_cost.h"
#include "accel/kd_mixed_check.h"
#include "accel/kd_tree.h"

static const char *const kind_names[BSP_ACCEL_KIND_COUNT] = {
    "naive", "kaplan", "sah", "sah-per", "sah-par", "sah-mixed", "grid", "octree", "bvh", "bvh4", "bvh8"};

size_t accel_max_bytes(const bsp_build_options *o)
{
    if (o->max_tree_bytes)
        return o->max_tree_bytes;
    long pages = sysconf(_SC_PHYS_PAGES), size = sysconf(_SC_PAGESIZE);
    if (pages <= 0 || size <= 0)
        return 0;
    return (size_t)pages / 2 * (size_t)size;
}

double accel_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

void bsp_build_options_defaults(bsp_build_options *opts)
{
    memset(opts, 0, sizeof *opts);
    opts->kind = BSP_ACCEL_SAH; /* the default for render, trace and make run */
    opts->mailbox = 1;
    kd_cost_defaults(&opts->sah_costs);
    opts->sah_empty_bonus = KD_DEFAULT_EMPTY_BONUS;
    opts->sah_min_saving = KD_DEFAULT_MIN_SAVING;
    opts->sah_leaf_budget = KD_DEFAULT_LEAF_BUDGET;
    opts->mixed_model = BSP_MIXED_COUNTED;
    opts->mixed_check = 1;
}

const char *bsp_accel_kind_name(bsp_accel_kind kind)
{
    return (unsigned)kind < BSP_ACCEL_KIND_COUNT ? kind_names[kind] : NULL;
}

bsp_status bsp_accel_kind_parse(const char *name, bsp_accel_kind *kind, bsp_error *err)
{
    for (int k = 0; k < BSP_ACCEL_KIND_COUNT; k++) {
        if (strcmp(name, kind_names[k]) == 0) {
            *kind = (bsp_accel_kind)k;
            return BSP_OK;
        }
    }
    char list[256] = "";
    for (int k = 0; k < BSP_ACCEL_KIND_COUNT; k++) {
        if (k)
            strncat(list, ", ", sizeof list - strlen(list) - 1);
        strncat(list, kind_names[k], sizeof list - strlen(list) - 1);
    }
    return error_set(err, BSP_ERR_INVALID, NULL, 0,
                     "unknown acceleration method '%s' (known: %s)", name, list);
}

bsp_status bsp_accel_build(const bsp_scene *scene, const bsp_build_options *opts,
                           bsp_accel **out, bsp_error *err)
{
    *out = NULL;
    bsp_accel *a = calloc(1, sizeof *a);
    if (!a)
        return error_set(err, BSP_ERR_NOMEM, NULL, 0, "out of memory");
    a->scene = scene;
    if (opts)
        a->opts = *opts;
    else
        bsp_build_options_defaults(&a->opts);
    double t0 = accel_now();
    bsp_status st;
    switch (a->opts.kind) {
    case BSP_ACCEL_NAIVE:
        st = naive_build(a, err);
        break;
    case BSP_ACCEL_KAPLAN:
    case BSP_ACCEL_SAH:
    case BSP_ACCEL_SAH_PER:
    case BSP_ACCEL_SAH_PAR:
    case BSP_ACCEL_SAH_MIXED:
    case BSP_ACCEL_OCTREE:
        st = kd_accel_build(a, err);
        if (st == BSP_OK && a->opts.kind == BSP_ACCEL_SAH_MIXED && a->opts.mixed_check)
            st = kd_mixed_check(a, err);
        break;
    case BSP_ACCEL_GRID:
        st = grid_build(a, err);
        break;
    case BSP_ACCEL_BVH:
    case BSP_ACCEL_BVH4:
    case BSP_ACCEL_BVH8:
        st = bvh_build(a, err);
        break;
    default:
        st = error_set(err, BSP_ERR_INVALID, NULL, 0, "unknown acceleration method %d",
                       (int)a->opts.kind);
        break;
    }
    if (st != BSP_OK) {
        bsp_accel_destroy(a);
        return st;
    }
    a->build_seconds = accel_now() - t0;
    if (a->opts.progress)
        a->opts.progress(1.0, a->opts.progress_ctx);
    a->opts.progress = NULL; /* the caller's context need not outlive the build */
    a->opts.progress_ctx = NULL;
    *out = a;
    return BSP_OK;
}

void bsp_accel_destroy(bsp_accel *a)
{
    if (!a)
        return;
    if (a->ops && a->ops->destroy)
        a->ops->destroy(a->impl);
    free(a);
}

const bsp_scene *bsp_accel_scene(const bsp_accel *a)
{
    return a->scene;
}

bsp_accel_kind bsp_accel_get_kind(const bsp_accel *a)
{
    return a->opts.kind;
}

void bsp_accel_get_options(const bsp_accel *a, bsp_build_options *out)
{
    *out = a->opts;
}

double bsp_accel_build_seconds(const bsp_accel *a)
{
    return a->build_seconds;
}

void bsp_accel_tree_stats(const bsp_accel *a, bsp_tree_stats *st)
{
    if (a->opts.kind == BSP_ACCEL_NAIVE) {
        memset(st, 0, sizeof *st);
        return;
    }
    if (a->opts.kind == BSP_ACCEL_GRID) {
        grid_stats(a->impl, st);
        return;
    }
    if (accel_is_bvh(a->opts.kind)) {
        bvh_stats(a->impl, a->scene, st);
        return;
    }
    kd_cost_model m;
    kd_cost_resolve(&a->opts, &m);
    kd_tree_stats(a->impl, a->scene, &m.c, st);
}

bsp_status bsp_accel_check(const bsp_accel *a, bsp_error *err)
{
    if (a->opts.kind == BSP_ACCEL_NAIVE)
        return BSP_OK;
    if (a->opts.kind == BSP_ACCEL_GRID)
        return grid_check(a->impl, a->scene, err);
    if (accel_is_bvh(a->opts.kind))
        return bvh_check(a->impl, a->scene, err);
    return kd_tree_check(a->impl, a->scene, err);
}

bsp_status bsp_accel_visit_cells(const bsp_accel *a, int max_depth,
                                 int (*visit)(const bsp_cell_info *cell, void *ctx), void *ctx,
                                 bsp_error *err)
{
    if (a->opts.kind == BSP_ACCEL_NAIVE)
        return BSP_OK;
    if (a->opts.kind == BSP_ACCEL_GRID)
        return grid_visit(a->impl, max_depth, visit, ctx);
    if (accel_is_bvh(a->opts.kind))
        return bvh_visit(a->impl, max_depth, visit, ctx);
    return kd_tree_visit(a->impl, max_depth, visit, ctx, err);
}

bsp_query *bsp_query_create(const bsp_accel *a)
{
    bsp_query *q = calloc(1, sizeof *q);
    if (!q)
        return NULL;
    q->accel = a;
    size_t n = bsp_scene_prim_count(a->scene);
    if (a->opts.mailbox && n > 0) {
        q->stamp = calloc(n, sizeof *q->stamp);
        if (!q->stamp) {
            free(q);
            return NULL;
        }
    }
    return q;
}

void bsp_query_destroy(bsp_query *q)
{
    if (!q)
        return;
    free(q->stamp);
    free(q);
}

const bsp_query_counters *bsp_query_get_counters(const bsp_query *q)
{
    return &q->counters;
}

void bsp_query_counters_add(bsp_query_counters *sum, const bsp_query_counters *c)
{
    sum->rays += c->rays;
    sum->isect_tests += c->isect_tests;
    sum->traversal_steps += c->traversal_steps;
    sum->leaves_visited += c->leaves_visited;
    sum->empty_leaves += c->empty_leaves;
    sum->mailbox_hits += c->mailbox_hits;
}

void bsp_query_reset_counters(bsp_query *q)
{
    memset(&q->counters, 0, sizeof q->counters);
}

int bsp_intersect(const bsp_accel *a, bsp_query *q, const bsp_ray *ray, bsp_hit *hit)
{
    q->counters.rays++;
    return a->ops->intersect(a, q, ray, BSP_NO_PRIM, hit);
}

int bsp_occluded(const bsp_accel *a, bsp_query *q, const bsp_ray *ray)
{
    q->counters.rays++;
    return a->ops->occluded(a, q, ray, BSP_NO_PRIM);
}

int bsp_intersect_from(const bsp_accel *a, bsp_query *q, const bsp_ray *ray, uint32_t from,
                       bsp_hit *hit)
{
    q->counters.rays++;
    return a->ops->intersect(a, q, ray, from, hit);
}

int bsp_occluded_from(const bsp_accel *a, bsp_query *q, const bsp_ray *ray, uint32_t from)
{
    q->counters.rays++;
    return a->ops->occluded(a, q, ray, from);
}
