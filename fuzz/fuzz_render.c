/*
 * fuzz_render.c — libFuzzer target: a scene file through its reader, then a
 * 24 x 24 Whitted render (depth 4: primary, shadow, reflected and refracted
 * rays) through a kd-tree (fuzz_input.h) and through the naive method. The
 * two images must be identical, float for float, with no NaN or negative
 * value, and the ray counts of every class equal. (+inf is allowed: a
 * material far outside NFF's ranges overflows, with a warning at load.)
 */
#include <math.h>
#include <string.h>

#include "fuzz_input.h"

#define SIDE 24

int LLVMFuzzerTestOneInput(const uint8_t *d, size_t n);
int LLVMFuzzerTestOneInput(const uint8_t *d, size_t n)
{
    fuzz_case fc;
    if (!fuzz_prepare(d, n, &fc))
        return 0;
    bsp_render_options ro;
    bsp_render_options_defaults(&ro);
    ro.width = ro.height = SIDE;
    ro.threads = 1;
    bsp_image *ia = NULL, *in = NULL;
    bsp_render_stats sa, sn;
    bsp_error err;
    bsp_status ra = bsp_render(fc.accel, &ro, &ia, &sa, &err),
               rn = bsp_render(fc.naive, &ro, &in, &sn, &err);
    if (ra != rn) {
        fprintf(stderr, "render status %d, naive's %d\n", (int)ra, (int)rn);
        abort();
    }
    if (ra == BSP_OK) {
        if (memcmp(ia->rgb, in->rgb, sizeof(float) * 3 * SIDE * SIDE) != 0) {
            fprintf(stderr, "%s's image differs from naive's\n", bsp_accel_kind_name(fc.kind));
            abort();
        }
        for (int i = 0; i < 3 * SIDE * SIDE; i++)
            if (isnan(ia->rgb[i]) || ia->rgb[i] < 0.0f) {
                fprintf(stderr, "pixel value %g\n", (double)ia->rgb[i]);
                abort();
            }
        for (int c = 0; c < BSP_RAY_CLASS_COUNT; c++)
            if (sa.cls[c].rays != sn.cls[c].rays) {
                fprintf(stderr, "ray class %d: %llu rays, naive %llu\n", c,
                        (unsigned long long)sa.cls[c].rays, (unsigned long long)sn.cls[c].rays);
                abort();
            }
        bsp_image_destroy(ia);
        bsp_image_destroy(in);
    }
    fuzz_case_free(&fc);
    return 0;
}
