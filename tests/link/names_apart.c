/*
 * names_apart.c — a program with functions and data named like libbspray's
 * internal ones (src/), linked to the static library users get (the
 * Makefile's PUBLIC_LIB). It links only if the library keeps those names to
 * itself; run by test_examples.c, it shows that each side still calls its
 * own: the library's error path names the missing file, this program's
 * error_set returns 42.
 */
#include <stdio.h>

#include "bspray/bspray.h"

/* internal names of the library (util/error.c, render/draw.c, render/camera.c,
 * util/bigmem.c, accel/kd_split_sah.c), with other meanings here */
int error_set(int x);
int error_set(int x)
{
    return x + 41;
}
int draw_line(void);
int draw_line(void)
{
    return 2;
}
double camera_ray = 3.0;
int bigmem_malloc = 4;
int kd_build_sah(void);
int kd_build_sah(void)
{
    return 5;
}

int main(void)
{
    bsp_scene *scene = NULL;
    bsp_error err;
    if (bsp_scene_load("spd:balls", &scene, &err) != BSP_OK) {
        fprintf(stderr, "%s\n", err.message);
        return 1;
    }
    bsp_accel *accel = NULL;
    if (bsp_accel_build(scene, NULL, &accel, &err) != BSP_OK) {
        fprintf(stderr, "%s\n", err.message);
        return 1;
    }
    bsp_scene *missing = NULL;
    bsp_status st = bsp_scene_load("/nonexistent/names_apart.nff", &missing, &err);
    printf("library: status %s: %s\n", bsp_status_name(st), err.message);
    printf("own: %d %d %g %d %d\n", error_set(1), draw_line(), camera_ray, bigmem_malloc,
           kd_build_sah());
    bsp_accel_destroy(accel);
    bsp_scene_destroy(scene);
    return 0;
}
