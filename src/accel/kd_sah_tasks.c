/*
 * kd_sah_tasks.c — the SAH build's subtrees built in parallel.
 *
 * The main build (kd_split_sah.c, kd_sah_node.c) builds the top of the tree itself and
 * defers every node of a middle size (sah_tasks.min_n..max_n primitives)
 * whose ancestors are all "good" splits: such a subtree's cost is never
 * needed by an ancestor (only a speculative "bad refine" retracts its
 * subtree by cost), so it can be built apart. Each task gets a copy of its
 * node's three event lists and builds into a kd_tree of its own. Worker
 * threads, started before the main build, take the tasks in order as they
 * are deferred, each with scratch of its own (the per-primitive bounds,
 * costs and classes are shared read-only); when the main build is done, its
 * thread joins them. With a leaf budget's estimate (sah_tasks.probe_every)
 * the sampled tasks go first, pilots, scouts, then probes; once the main
 * build is done and the pilots are built, the calling thread makes a first
 * estimate from them, and the scouts not yet taken are built with a small
 * share of it as their least saving; from pilots and scouts a second, for
 * the probes; once the probes are built too, the estimate from the whole
 * sample, and the tasks not yet taken are built with its raised least
 * saving (estimate_and_cut). The subtrees are then appended
 * to the main array in task order, their child and leaf indices rebased.
 * Which nodes become tasks depends only on the scene, so every thread count
 * builds the very same node array: within a task, and in the top part,
 * nodes are in depth-first order; children stay adjacent everywhere.
 *
 * Shared between the threads, under the pool's lock: the task list (count,
 * the array of task pointers, which the main build grows) and the pool's
 * cursors, counts and flags. A task itself belongs to the main build until it is
 * listed, then to the one worker that takes it, then, after the join, to the
 * main thread again.
 */
#include <math.h>
#include <pthread.h>

#include "accel/kd_prune.h"
#include "accel/kd_sah.h"

struct sah_task {
    uint32_t node; /* its placeholder leaf in the main tree */
    bsp_box cell;
    size_t n, cap; /* primitives; room of ev */
    double tsum;
    int depth, surface;
    uint64_t *ev;  /* its three lists (axis k at k * 2n), then room to grow */
    kd_tree sub;   /* its subtree, root at 0 */
    int kind;      /* TASK_PILOT, TASK_SCOUT, TASK_PROBE (the leaf budget's sample,
                      built first: sah_tasks.probe_every) or TASK_OTHER */
    double min_saving_sure; /* > the build's: its raised least saving (sah_build) */
    bsp_status st;
    bsp_error err;
};

/* The kinds of task, in the order the threads take them. A pilot is built
 * in full; a scout, once the pilots' estimate is made, without the splits
 * that save less than a very small share of it; a probe, once the estimate
 * of the pilots and scouts is made, without those that save less than a
 * small share of it; the others, once the estimate of the whole sample is
 * made, without those that save less than cut_share of it. A task taken
 * before its estimate is made (while the main build is still listing
 * tasks) is built in full. */
enum { TASK_PILOT, TASK_SCOUT, TASK_PROBE, TASK_OTHER, TASK_KINDS };

struct sah_pool {
    pthread_mutex_t lock;
    pthread_cond_t more; /* a task was listed, or the pool closed */
    sah_tasks *tasks;
    size_t next[TASK_KINDS];  /* per kind: where to look for the next task to take */
    size_t taken[TASK_KINDS], built[TASK_KINDS]; /* per kind: tasks taken by a thread,
                                                    and built */
    int open[TASK_KINDS]; /* per kind: its estimate is made (or none is wanted), so that
                             the tasks of the kind may go (pilots: always) */
    pthread_cond_t done; /* a sample task was built */
    int closed;          /* the main build is over: no task will be listed */
    int abort;           /* ... and it failed: build no more tasks */
    int started;         /* worker threads running */
    pthread_t tid[255];
    kd_tree limits;      /* the main tree's limits (no nodes), for the subtrees */
    sah_build proto;     /* the shared part of the main build's state */
};

static bsp_status task_oom(bsp_error *err)
{
    return error_set(err, BSP_ERR_NOMEM, NULL, 0, "out of memory while building the kd-tree");
}

/* Whether task I is a probe of the leaf budget's estimate: one in
 * probe_every, drawn by a hash of I (every K-th task in order can alias with
 * a regular scene: on shells it sampled a threshold 2.5x too high). */
static int is_probe(const sah_tasks *ts, size_t i)
{
    uint64_t h = (uint64_t)i * 0x9e3779b97f4a7c15ull;
    h ^= h >> 29;
    h *= 0xbf58476d1ce4e5b9ull;
    h ^= h >> 32;
    return ts->probe_every && h % ts->probe_every == 0;
}

/* The kind of task I: every KD_BUDGET_SCOUT_EVERY-th probe in task order
 * (the probes' hash spreads them, so the scouts too) is a scout, and every
 * other scout, from the first, a pilot. */
static int task_kind(sah_tasks *ts, size_t i)
{
    if (!is_probe(ts, i))
        return TASK_OTHER;
    if (ts->nprobes++ % KD_BUDGET_SCOUT_EVERY != 0)
        return TASK_PROBE;
    return ts->nscouts++ % 2 == 0 ? TASK_PILOT : TASK_SCOUT;
}

static int is_sample(const sah_task *tk)
{
    return tk->kind != TASK_OTHER;
}

/* Lists TK as task number ts->n (under the pool's lock when there is one).
 * 0 when out of memory. */
static int list_task(sah_tasks *ts, sah_task *tk)
{
    sah_pool *pool = ts->pool;
    int ok = 1;
    if (pool)
        pthread_mutex_lock(&pool->lock);
    if (ts->n == ts->cap) {
        size_t ncap = ts->cap ? 2 * ts->cap : 64;
        sah_task **nv = realloc(ts->v, ncap * sizeof *nv);
        if (nv) {
            ts->v = nv;
            ts->cap = ncap;
        } else {
            ok = 0;
        }
    }
    if (ok) {
        tk->kind = task_kind(ts, ts->n);
        ts->v[ts->n++] = tk;
    }
    if (pool) {
        pthread_cond_signal(&pool->more);
        pthread_mutex_unlock(&pool->lock);
    }
    return ok;
}

bsp_status kd_sah_defer(sah_build *b, uint32_t node, const bsp_box *cell, const node_lists *L,
                        int depth, int surface)
{
    sah_tasks *ts = b->tasks;
    sah_task *tk = calloc(1, sizeof *tk);
    if (!tk)
        return task_oom(b->err);
    const size_t m = 2 * L->n;
    tk->cap = 3 * m; /* just its lists: the worker grows them (deferred tasks wait in memory) */
    tk->ev = malloc(tk->cap * sizeof *tk->ev);
    if (!tk->ev) {
        free(tk);
        return task_oom(b->err);
    }
    for (unsigned k = 0; k < 3; k++)
        memcpy(tk->ev + k * m, b->ev + L->base + k * L->stride, m * sizeof *tk->ev);
    tk->node = node;
    tk->cell = *cell;
    tk->n = L->n;
    tk->tsum = L->tsum;
    tk->depth = depth;
    tk->surface = surface;
    /* until a worker runs it */
    tk->st = task_oom(&tk->err);
    /* an empty leaf until spliced */
    b->t->nodes[node].u.first = 0;
    b->t->nodes[node].bits = KD_LEAF_TAG;
    if (!list_task(ts, tk)) {
        free(tk->ev);
        free(tk);
        return task_oom(b->err);
    }
    return BSP_OK;
}

/* Grows W's event stack to NEED events at least; its contents are not kept
 * (a task's lists are copied in after). 0 when out of memory. */
static int reserve_events(sah_build *w, size_t need)
{
    if (need <= w->cap)
        return 1;
    size_t ncap = w->cap * 2 > need ? w->cap * 2 : need;
    free(w->ev);
    w->ev = bigmem_malloc(ncap * sizeof *w->ev);
    w->cap = w->ev ? ncap : 0;
    return w->ev != NULL;
}

/* Builds task TK with W, a worker's copy of the main build's state: the
 * task's lists are copied to the foot of the worker's event stack, which
 * stays from task to task: memory the thread has written before. On the VM
 * the benchmarks run on, the kernel's zeroing of fresh pages made a stack per
 * task cost balls:6's first build 0.67 s against 0.59 s on average
 * (docs/kdtree-log.md, "Session 29"). */
static void run_task(sah_build *w, sah_task *tk)
{
    kd_tree *sub = &tk->sub;
    const kd_tree *main_t = w->t;
    memset(sub, 0, sizeof *sub);
    sub->max_depth = main_t->max_depth;
    sub->max_leaf_prims = main_t->max_leaf_prims;
    sub->max_bytes = main_t->max_bytes; /* the whole tree is checked when spliced */
    sub->pad = main_t->pad;
    sub->box = tk->cell;
    sub->cap_nodes = 1024;
    sub->nodes = malloc(sub->cap_nodes * sizeof *sub->nodes);
    const size_t m = 2 * tk->n;
    if (!sub->nodes || (w->record_savings && !kd_tree_record_savings(sub)) ||
        !reserve_events(w, 3 * m + 1024)) {
        tk->st = task_oom(&tk->err);
        return;
    }
    memcpy(w->ev, tk->ev, 3 * m * sizeof *w->ev);
    free(tk->ev);
    tk->ev = NULL;
    sub->nnodes = 1;
    sub->nodes[0].u.first = 0;
    sub->nodes[0].bits = KD_LEAF_TAG;
    w->t = sub;
    w->err = &tk->err;
    node_lists L = {0, m, tk->n, tk->tsum};
    if (w->descent)
        w->descent->reset(w->dctx);
    double cost;
    const double sure = w->min_saving_sure;
    if (tk->min_saving_sure > sure)
        w->min_saving_sure = tk->min_saving_sure;
    tk->st = kd_sah_build_node(w, 0, tk->cell, L, 3 * m, tk->depth, 0, tk->surface, &cost);
    w->min_saving_sure = sure;
    w->t = (kd_tree *)main_t;
}

/* Whether a task of KIND may be taken now: any while the main build is
 * still listing tasks (it is then built in full, as a pilot is: the tree is
 * the same either way, kd_prune.h, and the thread would otherwise wait for
 * the main build); after that a pilot at once, any other kind once the
 * estimate of the kinds before it is made (estimate_and_cut). */
static int may_take(const sah_pool *pool, int kind)
{
    return !pool->closed || pool->open[kind];
}

/* The next task for a thread to build, under the pool's lock: the first of
 * the kinds up to MOST (pilots, scouts, probes, then the others, each in
 * task order) that may be taken; waits while none may. NULL when there is
 * nothing more for it: the pool is closed and every task of those kinds
 * taken, or the build failed. */
static sah_task *take_task(sah_pool *pool, int most)
{
    sah_tasks *ts = pool->tasks;
    sah_task *tk = NULL;
    pthread_mutex_lock(&pool->lock);
    while (!pool->abort) {
        int left = 0; /* a task of those kinds not taken yet */
        for (int k = 0; k <= most && !tk; k++) {
            size_t *c = &pool->next[k];
            while (*c < ts->n && ts->v[*c]->kind != k)
                (*c)++;
            if (*c == ts->n)
                continue;
            left = 1;
            if (may_take(pool, k)) {
                tk = ts->v[(*c)++];
                pool->taken[k]++;
            }
        }
        if (tk || (pool->closed && !left))
            break;
        pthread_cond_wait(&pool->more, &pool->lock);
    }
    pthread_mutex_unlock(&pool->lock);
    return tk;
}

/* Frees what worker_init gave W. */
static void worker_free(sah_build *w)
{
    kd_sah_scratch_free(w);
    if (w->descent && w->dctx)
        w->descent->free_ctx(w->dctx);
    w->dctx = NULL;
}

/* A thread's state for building tasks of POOL in W: the shared part of the
 * main build's, with scratch of its own. FROM (or NULL): a build whose
 * scratch W takes over (the main build's, when its thread builds tasks),
 * its pages written already; the per-primitive classes need no clearing and
 * the parts along the path are all restored to none when a build returns.
 * 0 when out of memory (W is then free of scratch). */
static int worker_init(sah_pool *pool, sah_build *w, sah_build *from)
{
    *w = pool->proto;
    if (from) {
        kd_sah_scratch_move(w, from);
    } else {
        w->cls = calloc((size_t)w->spare + 1, 1);
        w->path.of = calloc((size_t)w->spare + 1, sizeof *w->path.of); /* each task starts with none */
    }
    if (w->descent) /* a measure context of its own */
        w->actx = w->dctx = w->descent->thread_ctx(w->shared_actx);
    if (w->cls && w->path.of && (!w->descent || w->dctx))
        return 1;
    worker_free(w);
    return 0;
}

/* Builds tasks from POOL (see take_task) with W (worker_init). REPORT: the
 * thread that called the build, which reports the progress
 * (proto.progress) after each task it builds. */
static void run_tasks(sah_pool *pool, sah_build *w, int most, int report)
{
    sah_task *tk;
    while ((tk = take_task(pool, most)) != NULL) {
        run_task(w, tk);
        sah_tasks *ts = pool->tasks;
        pthread_mutex_lock(&pool->lock);
        ts->n_done += (double)tk->n;
        double done = ts->n_all > 0.0 ? ts->n_done / ts->n_all : 0.0;
        pool->built[tk->kind]++;
        if (is_sample(tk))
            pthread_cond_broadcast(&pool->done);
        pthread_mutex_unlock(&pool->lock);
        if (report && w->progress)
            w->progress(done < 1.0 ? done : 1.0, w->progress_ctx);
    }
}

static void *worker(void *arg)
{
    sah_pool *pool = arg;
    sah_build w;
    if (worker_init(pool, &w, NULL)) /* if it cannot, the other threads take the tasks */
        run_tasks(pool, &w, TASK_OTHER, 0);
    worker_free(&w);
    return NULL;
}

/* A pool for the tasks TS of B, with no thread yet; NULL when out of
 * memory. Its copy of B's state shares the per-primitive inputs and none of
 * B's scratch. */
static sah_pool *pool_create(const sah_build *b, sah_tasks *ts)
{
    sah_pool *pool = calloc(1, sizeof *pool);
    if (!pool)
        return NULL;
    if (pthread_mutex_init(&pool->lock, NULL) != 0) {
        free(pool);
        return NULL;
    }
    if (pthread_cond_init(&pool->more, NULL) != 0) {
        pthread_mutex_destroy(&pool->lock);
        free(pool);
        return NULL;
    }
    if (pthread_cond_init(&pool->done, NULL) != 0) {
        pthread_cond_destroy(&pool->more);
        pthread_mutex_destroy(&pool->lock);
        free(pool);
        return NULL;
    }
    pool->tasks = ts;
    pool->open[TASK_PILOT] = 1;
    for (int k = TASK_SCOUT; k < TASK_KINDS; k++)
        pool->open[k] = ts->probe_every == 0;
    pool->limits.max_depth = b->t->max_depth;
    pool->limits.max_leaf_prims = b->t->max_leaf_prims;
    pool->limits.pad = b->t->pad;
    sah_build *w = &pool->proto;
    *w = *b;
    w->t = &pool->limits;
    w->err = NULL;
    w->tasks = NULL; /* a task defers nothing */
    w->actx = w->descent ? NULL : b->actx;
    w->dctx = NULL;
    kd_sah_scratch_forget(w);
    return pool;
}

static void pool_destroy(sah_pool *pool)
{
    pthread_cond_destroy(&pool->done);
    pthread_cond_destroy(&pool->more);
    pthread_mutex_destroy(&pool->lock);
    free(pool);
}

void kd_sah_start_workers(sah_build *b, int threads, size_t n)
{
    /* a task has at least min_n primitives; straddlers can count twice */
    size_t most = b->tasks && b->tasks->min_n ? 2 * n / b->tasks->min_n : 0;
    if (threads <= 1 || most == 0)
        return; /* the tasks, if any, wait for kd_sah_finish_tasks */
    sah_pool *pool = pool_create(b, b->tasks);
    if (!pool)
        return;
    b->tasks->pool = pool;
    size_t want = (size_t)threads - 1;
    want = want < most ? want : most;
    want = want < 255 ? want : 255;
    for (; (size_t)pool->started < want; pool->started++)
        if (pthread_create(&pool->tid[pool->started], NULL, worker, pool) != 0)
            break; /* fewer threads: the others take the tasks */
}

/* Appends task TK's subtree to T: node j >= 1 goes to base + j - 1, the root
 * to the placeholder; child and leaf indices rebased. */
static int splice(kd_tree *t, const sah_task *tk)
{
    const kd_tree *s = &tk->sub;
    size_t add = s->nnodes - 1, base = t->nnodes;
    if (!kd_tree_fits(t, base + add, t->nprims + s->nprims))
        return 0;
    if (!kd_reserve_nodes(t, base + add))
        return 0;
    if (!kd_reserve_prims(t, s->nprims))
        return 0;
    const uint32_t pbase = (uint32_t)t->nprims;
    for (size_t j = 0; j < s->nnodes; j++) {
        kd_node x = s->nodes[j];
        if (kd_is_leaf(&x))
            x.u.first += pbase;
        else
            x.bits = kd_pack((uint32_t)(base + kd_child(&x) - 1), kd_axis(&x));
        size_t to = j == 0 ? tk->node : base + j - 1;
        t->nodes[to] = x;
        if (t->saving)
            t->saving[to] = s->saving[j];
    }
    t->nnodes = (uint32_t)(base + add);
    if (s->nprims > 0)
        memcpy(t->prims + t->nprims, s->prims, s->nprims * sizeof *s->prims);
    t->nprims += s->nprims;
    return 1;
}

/* The leaf budget's threshold estimated from the top of the tree and the
 * sample tasks of the kinds in MASK (a bit per kind), every one taken built
 * (or the build failed): from all of them and from each half (alternate
 * ones in task order), the least into *LO and the greatest into *HI; both
 * -inf when fewer than MIN of them were built, or one failed (the build
 * fails anyway). 0 when out of memory. */
static int estimate_threshold(const sah_build *b, const sah_tasks *ts, unsigned mask, size_t min,
                              double *lo, double *hi)
{
    *lo = *hi = -INFINITY;
    size_t used = 0;
    for (size_t i = 0; i < ts->n; i++) {
        const sah_task *tk = ts->v[i];
        if (!(mask >> tk->kind & 1u))
            continue;
        if (tk->st != BSP_OK)
            return 1;
        used++;
    }
    if (used < min)
        return 1; /* too few to tell */
    kd_budget_part *parts = malloc((ts->n ? ts->n : 1) * sizeof *parts);
    if (!parts)
        return 0;
    for (size_t i = 0; i < ts->n; i++) {
        parts[i].node = ts->v[i]->node;
        parts[i].n = ts->v[i]->n;
    }
    double theta[3];
    for (int h = 0; h < 3; h++) {
        size_t k = 0;
        for (size_t i = 0; i < ts->n; i++) {
            const sah_task *tk = ts->v[i];
            int in = mask >> tk->kind & 1u;
            int use = in && (h == 0 || (int)(k % 2) == h - 1);
            k += (size_t)in;
            parts[i].sub = use ? &tk->sub : NULL;
        }
        theta[h] = kd_prune_estimate(b->t, parts, ts->n, ts->budget);
    }
    free(parts);
    *lo = fmin(theta[0], fmin(theta[1], theta[2]));
    *hi = fmax(theta[0], fmax(theta[1], theta[2]));
    return 1;
}

/* SHARE times the estimate LO (HI: the greatest of its three), when the
 * three agree well enough to trust (or AGREE is 0: the least of them is
 * taken whatever the others say), that is above the build's least saving
 * and finite (a cut at +inf, the budget met by no split at all, cannot be
 * proved); else -inf: no cut. */
static double cut_of_estimate(const sah_build *b, double lo, double hi, double share, int agree)
{
    double cut = share * lo;
    return (!agree || hi <= KD_BUDGET_SPREAD * lo) && cut > b->min_saving && isfinite(cut)
               ? cut
               : -INFINITY;
}

/* Gives CUT as their least saving to the tasks of KIND not taken yet, under
 * the pool's lock (taking moves pool->next[KIND] past a task); returns
 * whether any got it. */
static int give_cut(sah_pool *pool, int kind, double cut)
{
    sah_tasks *ts = pool->tasks;
    int any = 0;
    for (size_t i = pool->next[kind]; i < ts->n && cut > -INFINITY; i++)
        if (ts->v[i]->kind == kind) {
            ts->v[i]->min_saving_sure = cut;
            any = 1;
        }
    return any;
}

/* Waits until every sample task taken so far is built. */
static void wait_for_samples(sah_pool *pool)
{
    pthread_mutex_lock(&pool->lock);
    for (int k = 0; k < TASK_OTHER; k++)
        while (pool->built[k] < pool->taken[k])
            pthread_cond_wait(&pool->done, &pool->lock);
    pthread_mutex_unlock(&pool->lock);
}

/* The leaf budget's estimates, once the top of the tree is built, and the
 * tasks they cut (the calling thread builds tasks with W when READY, with the
 * workers), in three phases, one per kind of sample: the pilots, then their
 * estimate, KD_BUDGET_PILOT_SHARE of which the scouts not yet taken get as
 * their least saving; the scouts, then the estimate of pilots and scouts,
 * KD_BUDGET_SCOUT_SHARE of which the probes get; the probes, then the
 * estimate of the whole sample, cut_share of which the other tasks get.
 * Each phase then opens the next kind to the threads. A task so cut counts
 * exactly the splits that save at least its cut, so the next estimate,
 * which lies far above it, is the one its whole tree would give. The
 * pilots' and scouts' cuts take the least of their three estimates whether
 * the three agree or not: the cut lies far under it, and estimates that
 * disagree make the least one lower still (teapot:40's scouts lie 16x
 * apart, their least at a quarter of the threshold, and its probes had been
 * built in full: 40 % of the build); the other tasks' cut, near the
 * threshold, waits for the three to agree. ts->cuts: the cuts given. */
static bsp_status estimate_and_cut(sah_build *b, sah_pool *pool, sah_build *w, int ready)
{
    sah_tasks *ts = pool->tasks;
    bsp_status st = ready ? BSP_OK : task_oom(b->err);
    /* per phase: the sample it needs and the share of its estimate it cuts at */
    const size_t least[TASK_OTHER] = {KD_BUDGET_MIN_SCOUTS, KD_BUDGET_MIN_SCOUTS,
                                      KD_BUDGET_MIN_PROBES};
    const double share[TASK_OTHER] = {fmin(KD_BUDGET_PILOT_SHARE, ts->cut_share),
                                      fmin(KD_BUDGET_SCOUT_SHARE, ts->cut_share),
                                      ts->cut_share};
    double given[TASK_OTHER] = {-INFINITY, -INFINITY, -INFINITY}; /* the cut each gave */
    for (int k = TASK_PILOT; k < TASK_OTHER; k++) {
        /* when this thread finds none of kind K left to take, every one is
         * taken; then wait for those still being built */
        if (st == BSP_OK)
            run_tasks(pool, w, k, 1);
        wait_for_samples(pool);
        const unsigned kinds = (2u << k) - 1u; /* this kind and the ones before */
        double lo, hi;
        if (st == BSP_OK && !estimate_threshold(b, ts, kinds, least[k], &lo, &hi))
            st = task_oom(b->err);
        pthread_mutex_lock(&pool->lock);
        if (st == BSP_OK) {
            double cut = cut_of_estimate(b, lo, hi, share[k], k + 1 == TASK_OTHER);
            given[k] = give_cut(pool, k + 1, cut) ? cut : -INFINITY;
        }
        pool->open[k + 1] = 1;
        pool->abort = st != BSP_OK;
        pthread_cond_broadcast(&pool->more);
        pthread_mutex_unlock(&pool->lock);
    }
    ts->cuts.raised = fmax(given[TASK_PILOT], fmax(given[TASK_SCOUT], given[TASK_PROBE]));
    ts->cuts.scout = given[TASK_PILOT];
    ts->cuts.probe = given[TASK_SCOUT];
    return st;
}

bsp_status kd_sah_finish_tasks(sah_build *b, bsp_status st)
{
    sah_tasks *ts = b->tasks;
    b->tasks = NULL;
    if (!ts)
        return st;
    sah_pool *pool = ts->pool;
    if (!pool && ts->n > 0 && st == BSP_OK && !(pool = pool_create(b, ts)))
        st = task_oom(b->err);
    /* the main thread builds tasks now, in the main build's scratch */
    sah_build w;
    const int ready = pool && st == BSP_OK && worker_init(pool, &w, b);
    kd_sah_scratch_free(b); /* what was not taken over */
    if (pool) {
        pthread_mutex_lock(&pool->lock);
        for (size_t i = 0; i < ts->n; i++) /* every task is listed now */
            ts->n_all += (double)ts->v[i]->n;
        pool->closed = 1;
        pool->abort = st != BSP_OK;
        pthread_cond_broadcast(&pool->more);
        pthread_mutex_unlock(&pool->lock);
        if (st == BSP_OK && !pool->open[TASK_OTHER])
            st = estimate_and_cut(b, pool, &w, ready);
        if (st == BSP_OK && ready)
            run_tasks(pool, &w, TASK_OTHER, 1); /* if it cannot, a task left unbuilt fails
                                                   the build */
        for (int i = 0; i < pool->started; i++)
            pthread_join(pool->tid[i], NULL);
        pool_destroy(pool);
    }
    if (ready)
        worker_free(&w);
    /* room for every subtree at once (on huge pages, util/bigmem.h): grown
     * splice by splice, the arrays were copied a dozen times into fresh
     * memory; if this fails, splice says so */
    size_t add_nodes = 0, add_prims = 0;
    for (size_t i = 0; i < ts->n; i++) {
        add_nodes += ts->v[i]->st == BSP_OK ? ts->v[i]->sub.nnodes - 1 : 0;
        add_prims += ts->v[i]->st == BSP_OK ? ts->v[i]->sub.nprims : 0;
    }
    if (st == BSP_OK && kd_tree_fits(b->t, b->t->nnodes + add_nodes, b->t->nprims + add_prims) &&
        kd_reserve_nodes(b->t, b->t->nnodes + add_nodes))
        (void)kd_reserve_prims(b->t, add_prims);
    for (size_t i = 0; i < ts->n && st == BSP_OK; i++) {
        const sah_task *tk = ts->v[i];
        if (tk->st != BSP_OK) { /* failed, or no thread could run it */
            if (b->err)
                *b->err = tk->err;
            st = tk->st;
        } else {
            if (!splice(b->t, tk))
                st = kd_build_failed(b->t, b->err);
            kd_tree_free(&ts->v[i]->sub); /* copied: its memory for the next one */
        }
    }
    for (size_t i = 0; i < ts->n; i++) {
        free(ts->v[i]->ev);
        kd_tree_free(&ts->v[i]->sub);
        free(ts->v[i]);
    }
    free(ts->v);
    ts->v = NULL; /* ts->cuts stays for the caller */
    ts->n = ts->cap = 0;
    ts->pool = NULL;
    return st;
}
