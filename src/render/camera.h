/*
 * camera.h — primary ray generation for the two sampling conventions (see
 * bsp_sampling in bspray/render.h).
 */
#ifndef BSPRAY_RENDER_CAMERA_H
#define BSPRAY_RENDER_CAMERA_H

#include "bspray/render.h"
#include "bspray/scene.h"

typedef struct camera_rays {
    bsp_vec3 eye;
    bsp_vec3 forward, right, up; /* orthonormal: right = forward x up_input */
    double x0, y0;               /* screen offset of ray (0, 0) */
    double step;                 /* screen distance between neighbouring rays */
    int ortho;                   /* parallel rays; x0, y0, step in scene units */
    int width, height;
} camera_rays;

/* Sets up ray generation for an image of WIDTH x HEIGHT (both > 0): the
 * field of view spans the image horizontally. ORTHO_WIDTH > 0: parallel
 * rays over a window that wide (scene units) instead of the angle. */
__attribute__((visibility("hidden"))) void camera_rays_init(camera_rays *cr,
                                                            const bsp_camera *cam, int width,
                                                            int height, bsp_sampling sampling,
                                                            double ortho_width);
/* The default orthographic window: the perspective view's width at the
 * look-at point, 2 tan(angle/2) |at - from|. */
__attribute__((visibility("hidden"))) double camera_default_ortho_width(const bsp_camera *cam);

/* The unit-direction primary ray of pixel (X, Y), row 0 at the top. */
__attribute__((visibility("hidden"))) bsp_ray camera_ray(const camera_rays *cr, int x, int y);

/* The image size a camera asks for under SAMPLING (SPD: resolution + 1). */
__attribute__((visibility("hidden"))) void camera_default_size(const bsp_camera *cam,
                                                               bsp_sampling sampling, int *width,
                                                               int *height);

#endif /* BSPRAY_RENDER_CAMERA_H */
