/*
 * fuzz_rays.c — libFuzzer target: a scene file through its reader, then a
 * kd-tree (fuzz_input.h) and the naive method answer 64 rays (origins in and
 * around the scene's box, some directions with zero components): the same
 * primitive, the same t bit for bit, the same occlusion; so do the naive
 * method's scalar loops (the definition) and its blocks (the method's own
 * scans, docs/naive.md). Any difference, a refusal without a message, or a
 * sanitizer report is a finding.
 */
#include <math.h>
#include <string.h>

#include "accel/accel_internal.h"
#include "fuzz_input.h"

static double unit(uint64_t *s)
{
    *s ^= *s << 13;
    *s ^= *s >> 7;
    *s ^= *s << 17;
    return (double)(*s >> 11) * 0x1p-53;
}

int LLVMFuzzerTestOneInput(const uint8_t *d, size_t n);
int LLVMFuzzerTestOneInput(const uint8_t *d, size_t n)
{
    fuzz_case fc;
    if (!fuzz_prepare(d, n, &fc))
        return 0;
    bsp_accel_kind kind = fc.kind;
    bsp_scene *s = fc.scene;
    bsp_accel *a = fc.accel, *naive = fc.naive;
    bsp_query *qa = bsp_query_create(a), *qn = bsp_query_create(naive);
    bsp_box b = bsp_scene_bounds(s);
    uint64_t rng = 88172645463325252ull ^ n;
    for (int i = 0; i < 64; i++) {
        double w[3] = {b.hi.x - b.lo.x, b.hi.y - b.lo.y, b.hi.z - b.lo.z};
        bsp_ray r;
        r.org = bsp_v3(b.lo.x + (unit(&rng) * 1.4 - 0.2) * w[0],
                       b.lo.y + (unit(&rng) * 1.4 - 0.2) * w[1],
                       b.lo.z + (unit(&rng) * 1.4 - 0.2) * w[2]);
        r.dir = bsp_v3(unit(&rng) - 0.5, unit(&rng) - 0.5, unit(&rng) - 0.5);
        if (i % 4 == 1)
            r.dir.x = 0.0;
        if (i % 4 == 2)
            r.dir = bsp_v3(1.0, 0.0, 0.0);
        if (r.dir.x == 0.0 && r.dir.y == 0.0 && r.dir.z == 0.0)
            continue;
        r.tmin = 0.0;
        r.tmax = INFINITY;
        bsp_hit ha, hn;
        int xa = bsp_intersect(a, qa, &r, &ha), xn = bsp_intersect(naive, qn, &r, &hn);
        if (xa != xn || (xa && (ha.prim != hn.prim || memcmp(&ha.t, &hn.t, sizeof ha.t)))) {
            fprintf(stderr, "ray %d: %s says %d (prim %u, t %.17g), naive %d (prim %u, t %.17g)\n",
                    i, bsp_accel_kind_name(kind), xa, ha.prim, ha.t, xn, hn.prim, hn.t);
            abort();
        }
        int on = bsp_occluded(naive, qn, &r);
        if (bsp_occluded(a, qa, &r) != on) {
            fprintf(stderr, "ray %d: occlusion differs from naive\n", i);
            abort();
        }
        bsp_hit hs;
        int xs = naive_scene_intersect(s, qn, &r, BSP_NO_PRIM, &hs);
        if (xs != xn || (xs && (hs.prim != hn.prim || memcmp(&hs.t, &hn.t, sizeof hs.t))) ||
            naive_scene_occluded(s, qn, &r, BSP_NO_PRIM) != on) {
            fprintf(stderr, "ray %d: the naive method's blocks differ from its scalar loop\n", i);
            abort();
        }
    }
    bsp_query_destroy(qa);
    bsp_query_destroy(qn);
    fuzz_case_free(&fc);
    return 0;
}
