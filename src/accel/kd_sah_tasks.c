/*
 * kd_sah_tasks.c — the SAH build's subtrees built in parallel.
 *
 * The main build (kd_split_sah.c) builds the top of the tree itself and
 * defers every node of a middle size (sah_tasks.min_n..max_n primitives)
 * whose ancestors are all "good" splits: such a subtree's cost is never
 * needed by an ancestor (only a speculative "bad refine" retracts its
 * subtree by cost), so it can be built later and apart. Each task gets a
 * copy of its node's three event lists and builds into a kd_tree of its own;
 * worker threads take tasks in order, each with scratch of its own (the
 * per-primitive bounds, costs and classes are shared read-only). The
 * subtrees are then appended to the main array in task order, their child
 * and leaf indices rebased. Which nodes become tasks depends only on the
 * scene, so every thread count builds the very same node array: within a
 * task, and in the top part, nodes are in depth-first order; children stay
 * adjacent everywhere.
 */
#include <pthread.h>
#include <unistd.h>

#include "accel/kd_sah.h"

struct sah_task {
    uint32_t node; /* its placeholder leaf in the main tree */
    bsp_box cell;
    size_t n, cap; /* primitives; room of ev */
    double tsum;
    int depth, surface;
    uint64_t *ev;  /* its three lists (axis k at k * 2n), then room to grow */
    kd_tree sub;   /* its subtree, root at 0 */
    bsp_status st;
    bsp_error err;
};

int kd_build_threads(const bsp_build_options *o)
{
    if (o && o->threads > 0)
        return o->threads;
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    return n > 0 ? (int)(n < 256 ? n : 256) : 1;
}

bsp_status kd_sah_defer(sah_build *b, uint32_t node, const bsp_box *cell, const node_lists *L,
                        int depth, int surface)
{
    sah_tasks *ts = b->tasks;
    if (ts->n == ts->cap) {
        size_t ncap = ts->cap ? 2 * ts->cap : 64;
        sah_task *nv = realloc(ts->v, ncap * sizeof *nv);
        if (!nv)
            return error_set(b->err, BSP_ERR_NOMEM, NULL, 0, "out of memory while building the kd-tree");
        ts->v = nv;
        ts->cap = ncap;
    }
    sah_task *tk = &ts->v[ts->n];
    memset(tk, 0, sizeof *tk);
    const size_t m = 2 * L->n;
    tk->cap = 3 * m; /* just its lists: the worker grows them (deferred tasks wait in memory) */
    tk->ev = malloc(tk->cap * sizeof *tk->ev);
    if (!tk->ev)
        return error_set(b->err, BSP_ERR_NOMEM, NULL, 0, "out of memory while building the kd-tree");
    for (unsigned k = 0; k < 3; k++)
        memcpy(tk->ev + k * m, b->ev + L->base + k * L->stride, m * sizeof *tk->ev);
    tk->node = node;
    tk->cell = *cell;
    tk->n = L->n;
    tk->tsum = L->tsum;
    tk->depth = depth;
    tk->surface = surface;
    /* until a worker runs it */
    tk->st = error_set(&tk->err, BSP_ERR_NOMEM, NULL, 0, "out of memory while building the kd-tree");
    ts->n++;
    /* an empty leaf until spliced */
    b->t->nodes[node].u.first = 0;
    b->t->nodes[node].bits = KD_LEAF_TAG;
    return BSP_OK;
}

/* Builds task TK with W, a worker's copy of the main build's state. */
static void run_task(sah_build *w, sah_task *tk)
{
    kd_tree *sub = &tk->sub;
    const kd_tree *main_t = w->t;
    memset(sub, 0, sizeof *sub);
    sub->max_depth = main_t->max_depth;
    sub->max_leaf_prims = main_t->max_leaf_prims;
    sub->pad = main_t->pad;
    sub->box = tk->cell;
    sub->cap_nodes = 1024;
    sub->nodes = malloc(sub->cap_nodes * sizeof *sub->nodes);
    if (!sub->nodes) {
        tk->st = error_set(&tk->err, BSP_ERR_NOMEM, NULL, 0,
                           "out of memory while building the kd-tree");
        return;
    }
    sub->nnodes = 1;
    sub->nodes[0].u.first = 0;
    sub->nodes[0].bits = KD_LEAF_TAG;
    w->t = sub;
    w->err = &tk->err;
    w->ev = tk->ev; /* the task's event stack, for as long as it runs */
    w->cap = tk->cap;
    tk->ev = NULL;
    node_lists L = {0, 2 * tk->n, tk->n, tk->tsum};
    if (w->descent)
        w->descent->reset(w->dctx);
    double cost;
    tk->st = kd_sah_build_node(w, 0, tk->cell, L, 6 * tk->n, tk->depth, 0, tk->surface, &cost);
    free(w->ev);
    w->ev = NULL;
    w->cap = 0;
    w->t = (kd_tree *)main_t;
}

typedef struct task_pool {
    const sah_build *main;
    sah_tasks *tasks;
    size_t next; /* the next task to take, under lock */
    pthread_mutex_t lock;
} task_pool;

static void *worker(void *arg)
{
    task_pool *pool = arg;
    /* the main build's state with no scratch (kd_sah_run_tasks freed it):
     * each worker grows its own; the per-primitive inputs stay shared */
    sah_build w = *pool->main;
    w.cls = calloc((size_t)w.spare + 1, 1);
    if (w.descent) /* a measure context of its own */
        w.actx = w.dctx = w.descent->thread_ctx(w.shared_actx);
    while (w.cls && (!w.descent || w.dctx)) { /* without it, the other workers take the tasks */
        pthread_mutex_lock(&pool->lock);
        size_t i = pool->next++;
        pthread_mutex_unlock(&pool->lock);
        if (i >= pool->tasks->n)
            break;
        run_task(&w, &pool->tasks->v[i]);
    }
    kd_sah_scratch_free(&w);
    if (w.descent && w.dctx)
        w.descent->free_ctx(w.dctx);
    return NULL;
}

/* Appends task TK's subtree to T: node j >= 1 goes to base + j - 1, the root
 * to the placeholder; child and leaf indices rebased. */
static int splice(kd_tree *t, const sah_task *tk)
{
    const kd_tree *s = &tk->sub;
    size_t add = s->nnodes - 1, base = t->nnodes;
    if (base + add > KD_MAX_NODES)
        return 0;
    if (base + add > t->cap_nodes) {
        size_t ncap = t->cap_nodes;
        while (ncap < base + add)
            ncap *= 2;
        if (ncap > KD_MAX_NODES)
            ncap = KD_MAX_NODES;
        kd_node *nn = realloc(t->nodes, ncap * sizeof *nn);
        if (!nn)
            return 0;
        t->nodes = nn;
        t->cap_nodes = (uint32_t)ncap;
    }
    if (!kd_reserve_prims(t, s->nprims))
        return 0;
    const uint32_t pbase = (uint32_t)t->nprims;
    for (size_t j = 0; j < s->nnodes; j++) {
        kd_node x = s->nodes[j];
        if (kd_is_leaf(&x))
            x.u.first += pbase;
        else
            x.bits = (uint32_t)((base + kd_child(&x) - 1) << 2) | kd_axis(&x);
        t->nodes[j == 0 ? tk->node : base + j - 1] = x;
    }
    t->nnodes = (uint32_t)(base + add);
    if (s->nprims > 0)
        memcpy(t->prims + t->nprims, s->prims, s->nprims * sizeof *s->prims);
    t->nprims += s->nprims;
    return 1;
}

bsp_status kd_sah_run_tasks(sah_build *b, int threads)
{
    sah_tasks *ts = b->tasks;
    bsp_status st = BSP_OK;
    b->tasks = NULL;
    kd_sah_scratch_free(b); /* the workers copy B: with no scratch to share */
    if (threads > 0 && ts->n > 0) {
        task_pool pool = {b, ts, 0, PTHREAD_MUTEX_INITIALIZER};
        if ((size_t)threads > ts->n)
            threads = (int)ts->n;
        pthread_t tid[256];
        int started = 0;
        for (; started < threads - 1; started++)
            if (pthread_create(&tid[started], NULL, worker, &pool) != 0)
                break; /* fewer threads: the others take the tasks */
        worker(&pool);
        for (int i = 0; i < started; i++)
            pthread_join(tid[i], NULL);
        for (size_t i = 0; i < ts->n && st == BSP_OK; i++) {
            if (ts->v[i].st != BSP_OK) { /* failed, or no worker could run it */
                if (b->err)
                    *b->err = ts->v[i].err;
                st = ts->v[i].st;
            } else if (!splice(b->t, &ts->v[i])) {
                st = error_set(b->err, BSP_ERR_NOMEM, NULL, 0,
                               "out of memory while building the kd-tree");
            }
        }
    }
    for (size_t i = 0; i < ts->n; i++) {
        free(ts->v[i].ev);
        kd_tree_free(&ts->v[i].sub);
    }
    free(ts->v);
    memset(ts, 0, sizeof *ts);
    return st;
}
