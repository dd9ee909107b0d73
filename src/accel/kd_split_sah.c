/*
 * kd_split_sah.c — the SAH kd-tree builder's entry points (kd_build_sah,
 * kd_build_sah_measure): the costs resolved and quantised, each primitive's
 * bounds, the root's three event lists made and radix-sorted (one thread per
 * axis on large scenes), the recursion started (kd_sah_node.c, with its
 * subtrees built as tasks by kd_sah_tasks.c), and the leaf budget's loop: a
 * build with the budget's estimate, pruned (kd_prune.c), and built once more
 * without the estimate in the rare case it proved too high. The algorithm
 * and its conventions are described at the head of kd_sah_node.c.
 */
#include <pthread.h>

#include "accel/kd_prune.h"
#include "accel/kd_sah.h"
#include "util/radix_sort.h"
#include "util/task_pool.h"

#define ROOT_LISTS_PARALLEL_MIN (1u << 17) /* events per axis: a thread for fewer costs more */

/* --- helpers -------------------------------------------------------------------------- */

static bsp_status oom(sah_build *b)
{
    return kd_build_failed(b->t, b->err);
}

/* Rounds the costs C[0..N) to multiples of one power of two q, the smallest
 * with sum C < 2^52 q: then every sum of costs the builder forms (a node's,
 * in any order) is exact, which the fast sweep's bounds rely on. The change
 * is below 2^-52 of the total. */
static void quantize_costs(double *c, size_t n)
{
    double tot = 0.0;
    for (size_t i = 0; i < n; i++)
        tot += c[i];
    if (!(tot > 0.0) || !isfinite(tot))
        return;
    double q = ldexp(1.0, ilogb(tot) + 2 - 52); /* + 2: room for the rounding of tot */
    for (size_t i = 0; i < n; i++) {
        if (c[i] > 0.0) {
            double r = nearbyint(c[i] / q) * q;
            c[i] = r > 0.0 ? r : q;
        }
    }
}

/* --- entry points ------------------------------------------------------------------------------ */

/* The root's events on axis K (2 per live primitive), made in primitive
 * order into E and radix-sorted through TMP (M events each). */
typedef struct root_axis {
    const sah_build *b;
    unsigned k;
    uint64_t *e, *tmp;
    size_t m;
} root_axis;

static void *root_axis_events(void *arg)
{
    const root_axis *r = arg;
    const sah_build *b = r->b;
    const double pad = b->t->pad;
    size_t i = 0;
    for (uint32_t p = 0; p < b->spare; p++) {
        if (b->scene->prims[p].shape == SHAPE_NONE)
            continue;
        bsp_box pb = b->bounds[p]; /* padded as kd_prim_box pads */
        pb.lo.v[r->k] -= pad;
        pb.hi.v[r->k] += pad;
        uint64_t cls = b->pclass ? (uint64_t)b->pclass[p] << EV_CLASS_SHIFT : 0;
        r->e[i++] = make_event(round_down(pb.lo.v[r->k]), 1, p) | cls;
        r->e[i++] = make_event(round_up(pb.hi.v[r->k]), 0, p) | cls;
    }
    /* by position, type and cost class (bits EV_CLASS_SHIFT..63) in 3
     * digits of 12 bits; made in primitive order, so ties stay in it */
    _Static_assert(EV_CLASS_SHIFT + 3 * 12 == 64, "3 digits cover the bits above the primitive");
    radix_sort_u64(r->e, r->tmp, r->m, EV_CLASS_SHIFT, 12);
    return NULL;
}

/* The root's three lists at b->ev + k M (M events each; b->ev has room for
 * 5 M). With THREADS > 1 and a large scene, axis 0 is made on a thread of
 * its own (radix buffer at 4 M) while this one makes axes 1 and 2 (at 3 M):
 * the same lists; balls:6's two-thread build 0.99 -> 0.95 s. */
static void root_lists(sah_build *b, size_t m, int threads)
{
    root_axis ax[3];
    for (unsigned k = 0; k < 3; k++)
        ax[k] = (root_axis){b, k, b->ev + k * m, b->ev + 3 * m, m};
    pthread_t tid;
    int apart = threads > 1 && m >= ROOT_LISTS_PARALLEL_MIN;
    if (apart) {
        ax[0].tmp = b->ev + 4 * m;
        apart = pthread_create(&tid, NULL, root_axis_events, &ax[0]) == 0;
    }
    for (unsigned k = apart ? 1 : 0; k < 3; k++)
        root_axis_events(&ax[k]);
    if (apart)
        pthread_join(tid, NULL);
}

/* One build of the tree B->t over the N live primitives (of NP; cost sum
 * TSUM) from fresh root lists, with its tasks (on the threads O asks for);
 * with CUT_SHARE > 0, CUT_SHARE times the leaf budget BUDGET's estimate
 * raises the least saving of the tasks built after it, and shares of its
 * pilots' and scouts' estimates those of its scouts and probes
 * (kd_sah_tasks.c): *CUTS. The savings are recorded when b->record_savings;
 * the tree is not pruned here. */
static bsp_status build_tree(sah_build *b, const bsp_build_options *o, size_t n, size_t np,
                             double tsum, size_t budget, double cut_share,
                             sah_budget_cuts *cuts)
{
    kd_tree *t = b->t;
    b->min_saving_sure = b->min_saving;
    b->cls = calloc(np + 1, 1); /* + 1: the spare slot */
    b->path.of = calloc(np + 1, sizeof *b->path.of); /* untouched pages cost nothing */
    /* the root's lists and two radix buffers (root_lists), then room: the
     * stack's peak is 8.9-14.1 n on the SPD scenes (balls:6 11.5 n); pages
     * never written cost nothing, a stack grown is copied */
    b->cap = 20 * n + 1024;
    b->ev = bigmem_malloc(b->cap * sizeof *b->ev);
    if (!b->cls || !b->path.of || !b->ev || (b->record_savings && !kd_tree_record_savings(t))) {
        kd_sah_scratch_free(b);
        return oom(b);
    }
    /* the root's events, made in primitive order, then sorted once */
    const size_t m = 2 * n;
    const int threads = task_pool_threads(o->threads);
    root_lists(b, m, threads);
    node_lists root = {0, m, n, tsum};
    /* subtrees of n/64 (at least 512) primitives and down to an eighth of that
     * are built as tasks, on the threads asked for */
    sah_tasks tasks;
    memset(&tasks, 0, sizeof tasks);
    tasks.max_n = n / 64 > 512 ? n / 64 : 512;
    tasks.min_n = tasks.max_n / 8;
    tasks.probe_every = cut_share > 0.0 ? KD_BUDGET_PROBE_EVERY : 0;
    tasks.budget = budget;
    tasks.cut_share = cut_share;
    tasks.cuts = (sah_budget_cuts){-INFINITY, -INFINITY, -INFINITY};
    b->tasks = &tasks;
    kd_sah_start_workers(b, threads, n);
    double cost;
    bsp_status st = kd_sah_build_node(b, 0, t->box, root, 3 * m, 0, 0, b->surface, &cost);
    st = kd_sah_finish_tasks(b, st);
    *cuts = tasks.cuts;
    b->tasks = NULL; /* TASKS lives in this frame only */
    kd_sah_scratch_free(b);
    return st;
}

void kd_sah_default_limits(bsp_build_options *o, const bsp_scene *scene)
{
    size_t n = bsp_scene_prim_count(scene) - bsp_scene_kind_count(scene, BSP_PRIM_DROPPED);
    if (o->max_depth == 0) {
        double d = 8.0 + 1.3 * log2(n > 1 ? (double)n : 1.0);
        int di = (int)lround(d);
        o->max_depth = di < BSP_KD_MAX_DEPTH_LIMIT ? di : BSP_KD_MAX_DEPTH_LIMIT;
    }
    if (o->max_leaf_prims == 0)
        o->max_leaf_prims = 1;
}

bsp_status kd_build_sah_measure(kd_tree *t, const bsp_scene *scene, const bsp_build_options *o,
                                kd_area_fn area, const void *ctx, const kd_descent *descent,
                                bsp_error *err)
{
    kd_cost_model cm;
    kd_cost_resolve(o, &cm);
    size_t np = bsp_scene_prim_count(scene);
    sah_build b;
    memset(&b, 0, sizeof b);
    b.t = t;
    b.scene = scene;
    b.area = area;
    b.actx = ctx;
    b.descent = descent;
    b.shared_actx = ctx;
    b.surface = area == kd_area_surface;
    b.to_limits = o->sah_split_to_limits != 0;
    b.ctrav = cm.c.traversal;
    b.bonus_mul = 1.0 - cm.empty_bonus;
    b.mailbox = cm.mailbox_term;
    b.mb_hit = cm.mailbox_hit;
    b.err = err;
    b.progress = o->progress;
    b.progress_ctx = o->progress_ctx;

    bsp_status st = BSP_OK;
    size_t n = 0;
    for (uint32_t p = 0; p < np; p++)
        n += scene->prims[p].shape != SHAPE_NONE;
    if (n == 0)
        return BSP_OK; /* the root stays an empty leaf */
    if (descent && !(b.actx = b.dctx = descent->thread_ctx(ctx)))
        return oom(&b);

    b.bounds = bigmem_malloc(np * sizeof *b.bounds);
    b.spare = (uint32_t)np;
    if (!b.bounds) {
        st = oom(&b);
        goto done;
    }
    /* per-primitive costs, unless they are all the same */
    double first = -1.0;
    int uniform = 1;
    for (uint32_t p = 0; p < np && uniform; p++) {
        if (scene->prims[p].shape == SHAPE_NONE)
            continue;
        double c = kd_prim_cost(scene, p, &cm.c);
        if (first < 0)
            first = c;
        else if (c != first)
            uniform = 0;
    }
    b.unif = first;
    b.cost_mode = uniform ? COST_UNIFORM : COST_ARRAY;
    if (!uniform) {
        b.cost = bigmem_malloc(np * sizeof *b.cost);
        if (!b.cost) {
            st = oom(&b);
            goto done;
        }
        for (uint32_t p = 0; p < np; p++)
            b.cost[p] = scene->prims[p].shape == SHAPE_NONE ? 0.0
                                                           : kd_prim_cost(scene, p, &cm.c);
        quantize_costs(b.cost, np);
        /* at most 8 distinct costs: classes in the events */
        int ncls = 0;
        b.pclass = malloc(np);
        if (!b.pclass) {
            st = oom(&b);
            goto done;
        }
        for (uint32_t p = 0; p < np && ncls <= 8; p++) {
            int c = 0;
            if (scene->prims[p].shape == SHAPE_NONE) {
                b.pclass[p] = 0;
                continue;
            }
            while (c < ncls && b.class_cost[c] != (double)b.cost[p])
                c++;
            if (c == ncls && ncls < 8)
                b.class_cost[ncls] = (double)b.cost[p];
            if (c == ncls)
                ncls++;
            b.pclass[p] = (uint8_t)c;
        }
        if (ncls <= 8) {
            b.cost_mode = COST_CLASS;
        } else {
            free(b.pclass);
            b.pclass = NULL;
        }
    }

    for (uint32_t p = 0; p < np; p++)
        if (scene->prims[p].shape != SHAPE_NONE)
            b.bounds[p] = bsp_scene_prim_bounds(scene, p);
    double tsum = 0.0, tmin = INFINITY;
    for (uint32_t p = 0; p < np; p++)
        if (scene->prims[p].shape != SHAPE_NONE) {
            double tp = b.cost ? b.cost[p] : b.unif;
            tsum += tp;
            tmin = tp < tmin ? tp : tmin;
        }
    kd_sah_event_deltas(&b);
    b.linear = !b.mailbox || tmin >= b.mb_hit;
    b.min_saving = b.min_saving_sure = n > 0 ? cm.min_saving * tsum / (double)n : 0.0;
    b.inv_root_area = 1.0 / kd_surface_area(&t->box);
    /* a leaf budget: record the splits' savings, prune afterwards */
    b.record_savings = cm.leaf_budget > 0.0 && !b.to_limits;
    size_t budget = 0;
    if (b.record_savings) {
        double most = fmax(ceil(cm.leaf_budget * (double)n), (double)cm.leaf_budget_min);
        budget = most < (double)KD_MAX_NODES ? (size_t)most : KD_MAX_NODES;
    }
    /* With a budget, first with its estimate; when the estimate proves too
     * high (the tree's threshold would lie at or below the raised least
     * saving, so splits it cut might have stayed), once more without. */
    int estimate = b.record_savings && cm.budget_cut > 0.0;
    for (;;) {
        sah_budget_cuts cuts = {-INFINITY, -INFINITY, -INFINITY};
        st = build_tree(&b, o, n, np, tsum, budget, estimate ? cm.budget_cut : 0.0, &cuts);
        if (st != BSP_OK || !b.record_savings)
            break;
        int r = kd_prune_to_leaves(t, budget, cuts.raised);
        if (r == 0)
            st = oom(&b);
        t->budget_cut = r > 0 ? cuts.raised : -INFINITY;
        t->budget_probe_cut = r > 0 ? cuts.probe : -INFINITY;
        t->budget_scout_cut = r > 0 ? cuts.scout : -INFINITY;
        if (r >= 0 || !estimate)
            break;
        estimate = 0; /* the estimate was too high: the tree without it */
        t->budget_rebuilt = 1;
        kd_tree_reset(t);
    }
done:
    free(t->saving);
    t->saving = NULL;
    kd_sah_scratch_free(&b);
    if (descent)
        descent->free_ctx(b.dctx);
    free(b.bounds);
    free(b.cost);
    free(b.pclass);
    return st;
}

void kd_sah_scratch_forget(sah_build *b)
{
    b->cls = NULL;
    b->ev = NULL;
    b->nev[0] = b->nev[1] = b->both = b->reord = NULL;
    b->sidx = b->slot = NULL;
    b->slot_cap = 0;
    b->list = NULL;
    b->chunks = NULL;
    b->mruns = NULL;
    b->saved = NULL;
    memset(&b->clip, 0, sizeof b->clip);
    memset(&b->path, 0, sizeof b->path);
    b->cap = b->nev_cap = b->list_cap = b->chunks_cap = b->mruns_cap = 0;
    b->nsaved = b->saved_cap = 0;
}

void kd_sah_scratch_free(sah_build *b)
{
    free(b->cls);
    free(b->ev);
    free(b->nev[0]);
    free(b->nev[1]);
    free(b->both);
    free(b->reord);
    free(b->sidx);
    free(b->slot);
    free(b->list);
    free(b->chunks);
    free(b->mruns);
    kd_clip_scratch_free(&b->clip);
    kd_clip_path_free(&b->path);
    free(b->saved);
    kd_sah_scratch_forget(b);
}

void kd_sah_scratch_move(sah_build *to, sah_build *from)
{
    to->cls = from->cls;
    to->ev = from->ev;
    to->cap = from->cap;
    to->nev[0] = from->nev[0];
    to->nev[1] = from->nev[1];
    to->both = from->both;
    to->reord = from->reord;
    to->sidx = from->sidx;
    to->slot = from->slot;
    to->slot_cap = from->slot_cap;
    to->nev_cap = from->nev_cap;
    to->list = from->list;
    to->list_cap = from->list_cap;
    to->chunks = from->chunks;
    to->chunks_cap = from->chunks_cap;
    to->mruns = from->mruns;
    to->mruns_cap = from->mruns_cap;
    to->saved = from->saved;
    to->saved_cap = from->saved_cap;
    to->nsaved = 0;
    to->clip = from->clip;
    to->path = from->path;
    kd_sah_scratch_forget(from);
}

bsp_status kd_build_sah(kd_tree *t, const bsp_scene *scene, const bsp_build_options *o,
                        bsp_error *err)
{
    return kd_build_sah_measure(t, scene, o, kd_area_surface, NULL, NULL, err);
}
