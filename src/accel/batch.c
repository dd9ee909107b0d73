/*
 * batch.c — many queries at once on several threads (bsp_intersect_batch,
 * bsp_occluded_batch): the rays are handed out in chunks from one atomic
 * counter, each thread answers its chunks with a query of its own, and the
 * answers land at the rays' own indices, so they do not depend on the
 * number of threads or on which thread took which chunk. The counters are
 * sums of per-ray counts, so they do not either.
 */
#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "accel/accel_internal.h"

/* Rays per chunk: enough that taking a chunk (one atomic add on a shared
 * line) is rare against the rays' own work, few enough that the last
 * chunks spread over the threads. */
#define BATCH_CHUNK 256
#define BATCH_MAX_THREADS 256

typedef struct batch_job {
    const bsp_accel *accel;
    const bsp_ray *rays;
    const uint32_t *from; /* NULL: nothing left out */
    size_t n;
    bsp_hit *hits;           /* closest hits, or NULL */
    unsigned char *occluded; /* occlusion answers, when hits is NULL */
    atomic_size_t next;      /* the first ray of the next chunk to take */
} batch_job;

typedef struct batch_worker {
    batch_job *job;
    bsp_query *q;
} batch_worker;

static void *batch_main(void *arg)
{
    batch_worker *w = arg;
    batch_job *j = w->job;
    for (;;) {
        size_t begin = atomic_fetch_add(&j->next, BATCH_CHUNK);
        if (begin >= j->n)
            break;
        size_t end = j->n - begin > BATCH_CHUNK ? begin + BATCH_CHUNK : j->n;
        for (size_t i = begin; i < end; i++) {
            uint32_t from = j->from ? j->from[i] : BSP_NO_PRIM;
            if (j->hits)
                (void)bsp_intersect_from(j->accel, w->q, &j->rays[i], from, &j->hits[i]);
            else
                j->occluded[i] =
                    (unsigned char)bsp_occluded_from(j->accel, w->q, &j->rays[i], from);
        }
    }
    return NULL;
}

/* The number of threads worth starting for N rays when THREADS are asked
 * for (0 or less: every core). */
static int batch_threads(int threads, size_t n)
{
    if (threads <= 0) {
        long c = sysconf(_SC_NPROCESSORS_ONLN);
        threads = c > 0 ? (int)c : 1;
    }
    if (threads > BATCH_MAX_THREADS)
        threads = BATCH_MAX_THREADS;
    size_t chunks = (n + BATCH_CHUNK - 1) / BATCH_CHUNK;
    if ((size_t)threads > chunks)
        threads = chunks > 0 ? (int)chunks : 1;
    return threads;
}

static bsp_status run_batch(batch_job *job, int threads, bsp_query_counters *counters,
                            bsp_error *err)
{
    if (counters)
        memset(counters, 0, sizeof *counters);
    if (!job->accel || (job->n > 0 && (!job->rays || (!job->hits && !job->occluded))))
        return error_set(err, BSP_ERR_INVALID, NULL, 0,
                         "a ray batch needs a structure, the rays and room for the answers");
    if (job->n == 0)
        return BSP_OK;
    threads = batch_threads(threads, job->n);
    batch_worker *w = calloc((size_t)threads, sizeof *w);
    pthread_t *tids = calloc((size_t)threads, sizeof *tids);
    int nq = 0;
    if (w && tids) /* every query is made before any ray, so a failure changes nothing */
        for (; nq < threads; nq++) {
            w[nq].job = job;
            w[nq].q = bsp_query_create(job->accel);
            if (!w[nq].q)
                break;
        }
    bsp_status st = BSP_OK;
    if (nq < threads) {
        st = error_set(err, BSP_ERR_NOMEM, NULL, 0, "out of memory for %d ray queries", threads);
    } else {
        atomic_init(&job->next, 0);
        int started = 1;
        for (; started < threads; started++)
            if (pthread_create(&tids[started], NULL, batch_main, &w[started]) != 0)
                break; /* the threads that did start, and this one, take every chunk */
        batch_main(&w[0]);
        for (int t = 1; t < started; t++)
            pthread_join(tids[t], NULL);
        if (counters)
            for (int t = 0; t < threads; t++)
                bsp_query_counters_add(counters, bsp_query_get_counters(w[t].q));
    }
    for (int t = 0; t < nq; t++)
        bsp_query_destroy(w[t].q);
    free(w);
    free(tids);
    return st;
}

bsp_status bsp_intersect_batch(const bsp_accel *accel, const bsp_ray *rays, const uint32_t *from,
                               size_t n, int threads, bsp_hit *hits, bsp_query_counters *counters,
                               bsp_error *err)
{
    batch_job job = {.accel = accel, .rays = rays, .from = from, .n = n, .hits = hits};
    return run_batch(&job, threads, counters, err);
}

bsp_status bsp_occluded_batch(const bsp_accel *accel, const bsp_ray *rays, const uint32_t *from,
                              size_t n, int threads, unsigned char *occluded,
                              bsp_query_counters *counters, bsp_error *err)
{
    batch_job job = {.accel = accel, .rays = rays, .from = from, .n = n, .occluded = occluded};
    return run_batch(&job, threads, counters, err);
}
