/*
 * kd_test_util.h — helpers shared by the tests of the kd-tree's copies
 * (test_kd_local.c, test_kd_walk.c, and others that need a structure built).
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

/* N rays around box B from the generator *RNG: random origins and
 * directions, a share of them axis-aligned or with a zero component, every
 * fifth leaving a primitive out (FROM; NPRIMS primitives), every third with
 * a finite interval. */
static inline void kd_test_rays(unsigned long long *rng, bsp_box b, size_t n, size_t nprims,
                                bsp_ray *rays, uint32_t *from)
{
    for (size_t i = 0; i < n; i++) {
        double o[3], d[3];
        for (int k = 0; k < 3; k++) {
            double lo = b.lo.v[k], hi = b.hi.v[k], w = hi - lo;
            o[k] = lo - 0.2 * w + 1.4 * w * harness_rnd(rng);
            d[k] = 2.0 * harness_rnd(rng) - 1.0;
        }
        if (i % 7 == 0)
            d[(i / 7) % 3] = 0.0;
        if (i % 11 == 0) {
            int axis = (int)((i / 11) % 3);
            for (int k = 0; k < 3; k++)
                d[k] = k == axis ? (i % 2 ? 1.0 : -1.0) : 0.0;
        }
        if (d[0] == 0.0 && d[1] == 0.0 && d[2] == 0.0)
            d[2] = 1.0;
        rays[i] = (bsp_ray){bsp_v3(o[0], o[1], o[2]), bsp_v3(d[0], d[1], d[2]), 0.0, INFINITY};
        if (i % 3 == 0)
            rays[i].tmax = harness_rnd(rng) * 2.0;
        from[i] = i % 5 == 0 ? (uint32_t)(harness_rnd(rng) * (double)nprims) : BSP_NO_PRIM;
    }
}

#endif /* BSPRAY_TESTS_KD_TEST_UTIL_H */
