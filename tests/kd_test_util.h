/*
 * kd_test_util.h — helpers shared by the tests of the kd-tree's copies
 * (test_kd_local.c, test_kd_walk.c).
 */
#ifndef BSPRAY_TESTS_KD_TEST_UTIL_H
#define BSPRAY_TESTS_KD_TEST_UTIL_H

#include "accel/kd_tree.h"
#include "harness.h"

/* S's tree by rule KIND with the default options on one thread; ends the
 * test when the build fails. */
static inline bsp_accel *kd_test_build(const bsp_scene *s, bsp_accel_kind kind)
{
    bsp_build_options o;
    bsp_build_options_defaults(&o);
    o.kind = kind;
    o.threads = 1;
    bsp_accel *a = NULL;
    bsp_error err;
    bsp_status st = bsp_accel_build(s, &o, &a, &err);
    CHECK_MSG(st == BSP_OK, "build: %s", err.message);
    if (st != BSP_OK)
        harness_abort_test();
    return a;
}

/* Whether the checker accepts A's tree (prints nothing). */
static inline int kd_test_accepted(const bsp_accel *a)
{
    bsp_error err;
    return bsp_accel_check(a, &err) == BSP_OK;
}

/* Scene SPEC, loaded; ends the test when it cannot be. */
static inline bsp_scene *kd_test_load(const char *spec)
{
    bsp_scene *s = NULL;
    bsp_error err;
    bsp_status st = bsp_scene_load(spec, &s, &err);
    CHECK_MSG(st == BSP_OK, "%s: %s", spec, err.message);
    if (st != BSP_OK)
        harness_abort_test();
    return s;
}

/* Calls FN on the sah and the kaplan tree (KIND 0 and 1) of each of the
 * NSPECS scenes SPECS, then frees them. */
typedef void (*kd_test_tree_fn)(const bsp_scene *s, const bsp_accel *a, const char *spec,
                                size_t scene, size_t kind, void *ctx);
static inline void kd_test_each_tree(const char *const *specs, size_t nspecs, kd_test_tree_fn fn,
                                     void *ctx)
{
    const bsp_accel_kind kinds[] = {BSP_ACCEL_SAH, BSP_ACCEL_KAPLAN};
    for (size_t si = 0; si < nspecs; si++) {
        bsp_scene *s = kd_test_load(specs[si]);
        for (size_t ki = 0; ki < 2; ki++) {
            bsp_accel *a = kd_test_build(s, kinds[ki]);
            fn(s, a, specs[si], si, ki, ctx);
            bsp_accel_destroy(a);
        }
        bsp_scene_destroy(s);
    }
}

#endif /* BSPRAY_TESTS_KD_TEST_UTIL_H */
