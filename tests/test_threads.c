/*
 * test_threads.c — the library's thread contract (bspray/bspray.h): calls on
 * different objects run on any threads at once. Four threads each load
 * scenes (a file and a generated one), fail to load a missing file, list
 * the SPD scenes, build a structure and answer rays against the naive
 * method built on the same thread, all at the same time. In `make
 * tsan-test` ThreadSanitizer watches it, so shared state in any of those
 * paths fails the test; here the answers are checked.
 */
#include <pthread.h>

#include "bspray/bspray.h"
#include "harness.h"
#include "kd_test_util.h"
#include "same_util.h"

enum { THREADS = 4, RAYS = 400 };

typedef struct thread_job {
    int id;
    /* results, checked by the main thread (the harness's checks are not
     * made from the workers) */
    int loaded, missing_refused, names_ok, built;
    size_t rays, wrong;
    char message[sizeof(((bsp_error *)0)->message)];
} thread_job;

/* The job's scenes and structures, one set per thread id. */
static const char *const job_files[THREADS] = {
    "tests/data/obj/polygons.obj", "tests/data/nff_good/cones.nff",
    "tests/data/obj/forms.obj", "tests/data/nff_good/numbers.nff"};
static const char *const job_spd[THREADS] = {"spd:tetra:3", "spd:balls:2", "spd:rings:1",
                                             "spd:gears:1"};
static const bsp_accel_kind job_kind[THREADS] = {BSP_ACCEL_SAH, BSP_ACCEL_BVH8,
                                                 BSP_ACCEL_KAPLAN, BSP_ACCEL_GRID};

/* RAYS rays through S by KIND against the naive method: the rays whose
 * closest hits (primitive, bits of t) or occlusion answers differ. */
static size_t wrong_answers(const bsp_scene *s, bsp_accel_kind kind, int seed, int *built)
{
    bsp_build_options o;
    bsp_build_options_defaults(&o);
    o.threads = 1;
    bsp_accel *naive = NULL, *a = NULL;
    bsp_error err;
    o.kind = BSP_ACCEL_NAIVE;
    bsp_status st = bsp_accel_build(s, &o, &naive, &err);
    o.kind = kind;
    if (st == BSP_OK)
        st = bsp_accel_build(s, &o, &a, &err);
    bsp_query *qn = naive ? bsp_query_create(naive) : NULL, *qa = a ? bsp_query_create(a) : NULL;
    bsp_ray rays[RAYS];
    uint32_t from[RAYS];
    size_t wrong = RAYS;
    *built = st == BSP_OK && qn && qa;
    if (*built) {
        unsigned long long rng = 0x7E57ULL + (unsigned long long)seed;
        kd_test_rays(&rng, bsp_scene_bounds(s), RAYS, bsp_scene_prim_count(s), rays, from);
        wrong = 0;
        for (size_t i = 0; i < RAYS; i++) {
            bsp_hit hn, ha;
            int gn = bsp_intersect_from(naive, qn, &rays[i], from[i], &hn);
            int ga = bsp_intersect_from(a, qa, &rays[i], from[i], &ha);
            int on = bsp_occluded_from(naive, qn, &rays[i], from[i]);
            int oa = bsp_occluded_from(a, qa, &rays[i], from[i]);
            wrong += !same_hit(gn, &hn, ga, &ha) || on != oa;
        }
    }
    bsp_query_destroy(qn);
    bsp_query_destroy(qa);
    bsp_accel_destroy(naive);
    bsp_accel_destroy(a);
    return wrong;
}

static void *run_job(void *arg)
{
    thread_job *j = arg;
    bsp_error err;
    memset(&err, 0, sizeof err);
    /* a missing file: its message carries the errno's text */
    char missing[600];
    snprintf(missing, sizeof missing, "%s/no_such_scene_%d.obj", harness_tmpdir(), j->id);
    bsp_scene *s = NULL;
    j->missing_refused = bsp_scene_load(missing, &s, &err) == BSP_ERR_IO && s == NULL &&
                         strstr(err.message, "No such file or directory") != NULL;
    snprintf(j->message, sizeof j->message, "%s", err.message);
    const char *names = bsp_spd_scene_names();
    j->names_ok = names && strstr(names, "balls") == names;
    const char *specs[2] = {job_files[j->id], job_spd[j->id]};
    for (int k = 0; k < 2; k++) {
        s = NULL;
        if (bsp_scene_load(specs[k], &s, &err) != BSP_OK) {
            snprintf(j->message, sizeof j->message, "%s", err.message);
            return NULL;
        }
        j->loaded++;
        int built = 0;
        j->wrong += wrong_answers(s, job_kind[j->id], j->id * 2 + k, &built);
        j->built += built;
        j->rays += RAYS;
        bsp_scene_destroy(s);
    }
    return NULL;
}

TEST(threads_share_nothing_the_library_owns)
{
    thread_job jobs[THREADS];
    pthread_t tid[THREADS];
    int started[THREADS];
    memset(jobs, 0, sizeof jobs);
    for (int i = 0; i < THREADS; i++) {
        jobs[i].id = i;
        started[i] = pthread_create(&tid[i], NULL, run_job, &jobs[i]) == 0;
    }
    for (int i = 0; i < THREADS; i++) {
        if (started[i])
            pthread_join(tid[i], NULL);
        else
            run_job(&jobs[i]);
    }
    for (int i = 0; i < THREADS; i++) {
        const thread_job *j = &jobs[i];
        CHECK_MSG(j->missing_refused, "thread %d: a missing file gave '%s'", i, j->message);
        CHECK_MSG(j->names_ok, "thread %d: the SPD names", i);
        CHECK_MSG(j->loaded == 2, "thread %d: loaded %d scenes: %s", i, j->loaded, j->message);
        CHECK_MSG(j->built == 2, "thread %d: built %d structures", i, j->built);
        CHECK_EQ_INT(j->rays, 2 * RAYS);
        CHECK_MSG(j->wrong == 0, "thread %d (%s): %zu of %zu rays answered otherwise than naive",
                  i, bsp_accel_kind_name(job_kind[i]), j->wrong, j->rays);
    }
}
