/*
 * task_pool.h — worker threads that run listed tasks, for builds whose
 * result must not depend on the thread count.
 *
 * The calling thread creates the pool, lists tasks as it finds them
 * (task_pool_add) while the workers already take them in list order, and
 * then joins the workers in task_pool_finish, which returns once every
 * listed task has run. Which thread runs a task is left to chance, so a
 * task must write only what it owns; the caller reads the tasks' results
 * after task_pool_finish, in list order. A pool of one thread (or one whose
 * threads could not start) runs every task in task_pool_finish, in order.
 */
#ifndef BSPRAY_UTIL_TASK_POOL_H
#define BSPRAY_UTIL_TASK_POOL_H

#include <stddef.h>

typedef struct task_pool task_pool;

/* REQUESTED threads when positive, else the cores online (at most 256; 1
 * when unknown): what a build option's 0 means. */
__attribute__((visibility("hidden"))) int task_pool_threads(int requested);

/* Runs TASK (as listed) with the pool's CTX. */
typedef void (*task_run_fn)(void *ctx, void *task);

/* A pool that will run the tasks on THREADS threads in all (the caller's
 * included; at most 256): THREADS - 1 workers are started, fewer when the
 * system refuses some. EXPECTED_TASKS (0: unknown) caps the workers at what
 * the tasks can keep busy. NULL when out of memory. */
__attribute__((visibility("hidden"))) task_pool *task_pool_create(int threads,
                                                                 size_t expected_tasks,
                                                                 task_run_fn run, void *ctx);

/* Lists TASK: a worker may run it from now on. 0 when out of memory (the
 * task is not listed and will not run). */
__attribute__((visibility("hidden"))) int task_pool_add(task_pool *p, void *task);

/* Runs the tasks not yet taken on the calling thread too, waits for every
 * task, joins the workers and frees P. */
__attribute__((visibility("hidden"))) void task_pool_finish(task_pool *p);

#endif /* BSPRAY_UTIL_TASK_POOL_H */
