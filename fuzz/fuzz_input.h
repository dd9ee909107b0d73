/*
 * fuzz_input.h — what the fuzz targets share: an input is one format byte
 * and a scene file. The byte's value modulo 3 picks the reader (NFF, OBJ,
 * PLY), its value divided by 3 (modulo 6) the structure the target compares
 * with the naive method (sah, kaplan, sah-per, grid, octree, bvh), and its
 * value divided by 18 (modulo 2) the variant: for the octree where the nodes are
 * cut (the centre, the cost estimate), for the grid uniform or recursive
 * (three levels, cells of more than 2 primitives cut).
 */
#ifndef BSPRAY_FUZZ_INPUT_H
#define BSPRAY_FUZZ_INPUT_H

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include "bspray/bspray.h"
#include "scene/mesh.h"

/* Scenes larger than this are skipped: the targets look for wrong answers,
 * not slow builds. */
#define FUZZ_MAX_PRIMS 3000

/* The scene of input D[0..N) (NULL when the reader refuses it, which must
 * come with a message), the kind of structure to compare and its variant
 * (0 or 1). */
static inline bsp_scene *fuzz_scene(const uint8_t *d, size_t n, bsp_accel_kind *kind,
                                    int *variant)
{
    if (n < 1)
        return NULL;
    static const bsp_accel_kind kinds[8] = {BSP_ACCEL_SAH,    BSP_ACCEL_KAPLAN,
                                            BSP_ACCEL_SAH_PER, BSP_ACCEL_GRID,
                                            BSP_ACCEL_OCTREE, BSP_ACCEL_BVH,
                                            BSP_ACCEL_BVH4,   BSP_ACCEL_BVH8};
    int fmt = d[0] % 3;
    *kind = kinds[(d[0] / 3) % 8];
    *variant = (d[0] / 24) % 2;
    const char *buf = (const char *)d + 1;
    bsp_scene *s = NULL;
    bsp_error err = {0};
    bsp_status st = fmt == 0   ? bsp_scene_load_nff_memory(buf, n - 1, "fuzz.nff", &s, &err)
                    : fmt == 1 ? obj_load_memory(buf, n - 1, "fuzz.obj", &s, &err)
                               : ply_load_memory(buf, n - 1, "fuzz.ply", &s, &err);
    if (st != BSP_OK) {
        if (!err.message[0]) {
            fprintf(stderr, "refused without a message (status %d)\n", (int)st);
            abort();
        }
        return NULL;
    }
    if (bsp_scene_prim_count(s) > FUZZ_MAX_PRIMS) {
        bsp_scene_destroy(s);
        return NULL;
    }
    return s;
}

/* A scene read from an input, with its structure and the naive method. */
typedef struct fuzz_case {
    bsp_accel_kind kind;
    int variant; /* the octree cut by cost; the grid recursive */
    bsp_scene *scene;
    bsp_accel *accel, *naive;
} fuzz_case;

/* Reads and builds input D[0..N) into *C: 1, or 0 when the input is skipped
 * (refused, too large, or the structure not built). */
static inline int fuzz_prepare(const uint8_t *d, size_t n, fuzz_case *c)
{
    c->scene = fuzz_scene(d, n, &c->kind, &c->variant);
    if (!c->scene)
        return 0;
    /* the structure on one thread with a small memory cap (skipped when the
     * build refuses: the cap, or sah-per without a camera); the naive
     * method must build */
    bsp_build_options o, on;
    bsp_build_options_defaults(&o);
    o.kind = c->kind;
    o.octree_split = c->variant ? BSP_OCTREE_COST : BSP_OCTREE_CENTRE;
    o.grid_levels = c->kind == BSP_ACCEL_GRID && c->variant ? 3 : 1;
    o.grid_cell_prims = 2;
    o.threads = 1;
    o.max_tree_bytes = (size_t)64 << 20;
    bsp_build_options_defaults(&on);
    on.kind = BSP_ACCEL_NAIVE;
    bsp_error err;
    c->accel = c->naive = NULL;
    if (bsp_accel_build(c->scene, &o, &c->accel, &err) != BSP_OK) {
        bsp_scene_destroy(c->scene);
        return 0;
    }
    if (bsp_accel_build(c->scene, &on, &c->naive, &err) != BSP_OK) {
        fprintf(stderr, "naive build failed: %s\n", err.message);
        abort();
    }
    return 1;
}

static inline void fuzz_case_free(fuzz_case *c)
{
    bsp_accel_destroy(c->accel);
    bsp_accel_destroy(c->naive);
    bsp_scene_destroy(c->scene);
}

#endif
