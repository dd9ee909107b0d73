/*
 * kd_prepass.h — sah-mixed's pre-pass (kd_prepass.c).
 */
#ifndef BSPRAY_ACCEL_KD_PREPASS_H
#define BSPRAY_ACCEL_KD_PREPASS_H

#include "accel/kd_flux.h"
#include "bspray/render.h"
#include "bspray/scene.h"

/* The camera of O's view (its explicit view, or SCENE's camera, which must
 * exist) for a render of RES x RES rays. */
HIDDEN bsp_camera kd_prepass_camera(const bsp_scene *scene, const bsp_build_options *o, int res);

/* Every ray a one-thread Whitted render through ACCEL with camera CAM and
 * ray depth MAX_DEPTH (0: 4) shoots, in a new array *RAYS (free()) of *N,
 * with its class in *CLS and the primitive its query leaves out in *FROM
 * (bsp_intersect_from; both free()). */
HIDDEN bsp_status kd_render_rays(const bsp_accel *accel, const bsp_camera *cam, int max_depth,
                                 bsp_ray **rays, uint8_t **cls, uint32_t **from, size_t *n,
                                 bsp_error *err);

/* Renders SCENE through CAM (NULL: the scene's; its resolution + 1 rays
 * across) with ray depth MAX_DEPTH (0: 4) on a `sah` tree built on
 * BUILD_THREADS threads (0: every core). *SHARE:
 * the share of primary rays among all rays. With SEG non-NULL, also the
 * non-primary (shadow, reflected, refracted) rays as segments from their
 * tmin to where they stop, in a new array *SEG (free()) of *NSEG. */
HIDDEN bsp_status kd_mixed_prepass(const bsp_scene *scene, const bsp_camera *cam, int max_depth,
                                   int build_threads, double *share, kd_flux_segment **seg,
                                   size_t *nseg, bsp_error *err);

#endif /* BSPRAY_ACCEL_KD_PREPASS_H */
