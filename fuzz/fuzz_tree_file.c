/*
 * fuzz_tree_file.c — libFuzzer target: the input is a kd-tree file
 * (bsp_accel_save) for the scene spd:balls:1; its CRC-32 (the last four
 * bytes, docs/formats.md) is set to match, so that mutations reach the
 * loader's structural checks instead of stopping at the checksum. A file
 * the loader accepts is then traversed (64 closest-hit and occlusion
 * queries) and checked whole (bsp_accel_check). Its answers need not be the
 * naive method's — the load checks promise safety, not that every leaf
 * lists its primitives (that is bsp_accel_check's job) — but nothing may
 * crash, read out of bounds, hang or leak. Seeds: `bspray build
 * spd:balls:1 -o FILE` with several options (fuzz/run.sh).
 */
#include <math.h>
#include <string.h>
#include <unistd.h>
#include <zlib.h>

#include "fuzz_input.h"

static bsp_scene *scene;
static char path[64];

static void remove_file(void)
{
    unlink(path);
}

static void setup(void)
{
    bsp_error err;
    if (bsp_scene_load("spd:balls:1", &scene, &err) != BSP_OK)
        abort();
    snprintf(path, sizeof path, "/tmp/bspray-fuzz-tree-%ld.kdt", (long)getpid());
    atexit(remove_file);
}

int LLVMFuzzerTestOneInput(const uint8_t *d, size_t n);
int LLVMFuzzerTestOneInput(const uint8_t *d, size_t n)
{
    if (!scene)
        setup();
    if (n < 8)
        return 0;
    uint8_t *c = malloc(n);
    if (!c)
        return 0;
    memcpy(c, d, n);
    uint32_t crc = (uint32_t)crc32(crc32(0L, Z_NULL, 0), c, (uInt)(n - 4));
    for (int i = 0; i < 4; i++) /* little-endian, as the file stores it */
        c[n - 4 + (size_t)i] = (uint8_t)(crc >> (8 * i));
    FILE *f = fopen(path, "wb");
    if (!f || fwrite(c, 1, n, f) != n) {
        if (f)
            fclose(f);
        free(c);
        abort();
    }
    fclose(f);
    free(c);
    bsp_accel *a = NULL;
    bsp_error err = {0};
    if (bsp_accel_load(scene, path, &a, &err) != BSP_OK) {
        if (!err.message[0])
            abort();
        return 0;
    }
    bsp_query *q = bsp_query_create(a);
    bsp_box b = bsp_scene_bounds(scene);
    for (int i = 0; i < 64; i++) {
        double u = (i + 0.5) / 64.0;
        bsp_ray r = {bsp_v3(b.lo.x - 1.0, b.lo.y + u * (b.hi.y - b.lo.y), b.lo.z + u * (b.hi.z - b.lo.z)),
                     bsp_v3(1.0, i % 3 ? 0.3 - u : 0.0, i % 2 ? u - 0.5 : 0.0), 0.0, INFINITY};
        bsp_hit h;
        bsp_intersect(a, q, &r, &h);
        bsp_occluded(a, q, &r);
    }
    bsp_query_destroy(q);
    bsp_accel_check(a, &err);
    bsp_accel_destroy(a);
    return 0;
}
