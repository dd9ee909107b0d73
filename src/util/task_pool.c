/*
 * task_pool.c — worker threads that run listed tasks (task_pool.h).
 *
 * Shared under the lock: the list (v, n, cap), the cursor `next` (the
 * first task no thread has taken) and `closed`. A task is the caller's
 * until listed, then belongs to the one thread that takes it; the caller
 * gets it back when task_pool_finish has joined the workers.
 */
#include <pthread.h>
#include <stdlib.h>
#include <unistd.h>

#include "util/task_pool.h"

#define TASK_POOL_MAX_THREADS 256

struct task_pool {
    pthread_mutex_t lock;
    pthread_cond_t more; /* a task was listed, or the list closed */
    void **v;
    size_t n, cap, next;
    int closed; /* task_pool_finish was called: nothing more will be listed */
    task_run_fn run;
    void *ctx;
    int started; /* workers running */
    pthread_t tid[TASK_POOL_MAX_THREADS - 1];
};

/* The next task to run, NULL once the list is closed and every task taken;
 * waits for the caller to list one if WAIT. */
static void *take(task_pool *p, int wait)
{
    void *task = NULL;
    pthread_mutex_lock(&p->lock);
    for (;;) {
        if (p->next < p->n) {
            task = p->v[p->next++];
            break;
        }
        if (p->closed || !wait)
            break;
        pthread_cond_wait(&p->more, &p->lock);
    }
    pthread_mutex_unlock(&p->lock);
    return task;
}

int task_pool_threads(int requested)
{
    if (requested > 0)
        return requested < TASK_POOL_MAX_THREADS ? requested : TASK_POOL_MAX_THREADS;
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    return n > 0 ? (int)(n < TASK_POOL_MAX_THREADS ? n : TASK_POOL_MAX_THREADS) : 1;
}

static void *worker(void *arg)
{
    task_pool *p = arg;
    for (void *task; (task = take(p, 1)) != NULL;)
        p->run(p->ctx, task);
    return NULL;
}

task_pool *task_pool_create(int threads, size_t expected_tasks, task_run_fn run, void *ctx)
{
    task_pool *p = calloc(1, sizeof *p);
    if (!p)
        return NULL;
    if (pthread_mutex_init(&p->lock, NULL) != 0) {
        free(p);
        return NULL;
    }
    if (pthread_cond_init(&p->more, NULL) != 0) {
        pthread_mutex_destroy(&p->lock);
        free(p);
        return NULL;
    }
    p->run = run;
    p->ctx = ctx;
    size_t want = threads > 1 ? (size_t)threads - 1 : 0;
    if (want > TASK_POOL_MAX_THREADS - 1)
        want = TASK_POOL_MAX_THREADS - 1;
    if (expected_tasks && want > expected_tasks - 1)
        want = expected_tasks - 1; /* the caller takes one too */
    for (; (size_t)p->started < want; p->started++)
        if (pthread_create(&p->tid[p->started], NULL, worker, p) != 0)
            break; /* fewer workers: the others, and the caller, take the tasks */
    return p;
}

int task_pool_add(task_pool *p, void *task)
{
    int ok = 1;
    pthread_mutex_lock(&p->lock);
    if (p->n == p->cap) {
        size_t ncap = p->cap ? 2 * p->cap : 64;
        void **nv = realloc(p->v, ncap * sizeof *nv);
        if (nv) {
            p->v = nv;
            p->cap = ncap;
        } else {
            ok = 0;
        }
    }
    if (ok) {
        p->v[p->n++] = task;
        pthread_cond_signal(&p->more);
    }
    pthread_mutex_unlock(&p->lock);
    return ok;
}

void task_pool_finish(task_pool *p)
{
    pthread_mutex_lock(&p->lock);
    p->closed = 1;
    pthread_cond_broadcast(&p->more);
    pthread_mutex_unlock(&p->lock);
    for (void *task; (task = take(p, 0)) != NULL;)
        p->run(p->ctx, task);
    for (int i = 0; i < p->started; i++)
        pthread_join(p->tid[i], NULL);
    pthread_cond_destroy(&p->more);
    pthread_mutex_destroy(&p->lock);
    free(p->v);
    free(p);
}
