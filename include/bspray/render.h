/*
 * bspray/render.h — images, the Whitted ray tracer over a scene, and the ray
 * statistics of a render (with the names of Havran's SPD tables).
 */
#ifndef BSPRAY_RENDER_H
#define BSPRAY_RENDER_H

#include <stddef.h>
#include <stdint.h>

#include "bspray/accel.h"
#include "bspray/error.h"

#ifdef __cplusplus
extern "C" {
#endif

/* --- Images ---------------------------------------------------------------- */

/* An RGB image, 3 floats per pixel, row 0 at the top. Values are linear and
 * written clamped to [0,1], 8 bits per channel. */
typedef struct bsp_image {
    int width, height;
    float *rgb; /* width * height * 3 */
} bsp_image;

/* The most pixels an image may have. */
#define BSP_IMAGE_MAX_PIXELS ((long long)1 << 28)

/* A black image; NULL when out of memory or the size is not positive or is
 * absurd (more than BSP_IMAGE_MAX_PIXELS). Free with bsp_image_destroy. */
bsp_image *bsp_image_create(int width, int height);
void bsp_image_destroy(bsp_image *img);
/* PNG through libpng (8-bit RGB). */
bsp_status bsp_image_write_png(const bsp_image *img, const char *path, bsp_error *err);
/* Binary PPM (P6, maxval 255). */
bsp_status bsp_image_write_ppm(const bsp_image *img, const char *path, bsp_error *err);
/* By extension: .ppm writes PPM, anything else PNG. */
bsp_status bsp_image_write(const bsp_image *img, const char *path, bsp_error *err);
/* Reads an 8-bit RGB or RGBA PNG (for tests and tools). */
bsp_status bsp_image_read_png(const char *path, bsp_image **out, bsp_error *err);

/* --- Ray statistics ----------------------------------------------------------- */

/* Counts of one ray kind. */
typedef struct bsp_ray_class_stats {
    uint64_t rays;            /* rays cast */
    uint64_t hits;            /* rays that hit something (shadow: blocked) */
    uint64_t isect_tests;     /* ray-primitive intersection tests */
    uint64_t traversal_steps; /* acceleration structure nodes visited */
    uint64_t leaves_visited;
    uint64_t empty_leaves;
    uint64_t mailbox_hits;
} bsp_ray_class_stats;

typedef enum bsp_ray_class {
    BSP_RAY_PRIMARY = 0,
    BSP_RAY_SHADOW,
    BSP_RAY_SECONDARY, /* reflected + refracted */
    BSP_RAY_CLASS_COUNT
} bsp_ray_class;

/* Statistics of one render. Havran's names:
 *   PrimaryRay = cls[PRIMARY].rays, UsedIntPrimRay = cls[PRIMARY].hits,
 *   ScnCoverage = UsedIntPrimRay / PrimaryRay, ShadowRay, UsedIntShadRay,
 *   SecondaryRay, UsedIntSecRay likewise; AllRays = the sum of rays;
 *   IntersRequired = the sum of hits. */
typedef struct bsp_render_stats {
    bsp_ray_class_stats cls[BSP_RAY_CLASS_COUNT];
    uint64_t reflected_rays; /* part of SecondaryRay */
    uint64_t refracted_rays; /* part of SecondaryRay */
    int width, height, max_depth, threads;
    double build_seconds;  /* T_B of the structure used */
    double render_seconds; /* T_TR: wall time of the render */
} bsp_render_stats;

/* --- Rendering -------------------------------------------------------------------- */

typedef enum bsp_sampling {
    /* SPD timing protocol: for a file that says resolution 512 512 the image
     * is 513 x 513 rays through the pixel corners, and the field of view
     * spans the first to the last ray. An explicit resolution N gives N x N
     * rays with the same spanning rule. */
    BSP_SAMPLING_SPD = 0,
    /* Ordinary convention: N x N pixels, one ray through each pixel centre,
     * the field of view spanning the outer pixel edges. */
    BSP_SAMPLING_CENTRES
} bsp_sampling;

/* The order in which bsp_render hands out and traces the pixels. */
typedef enum bsp_pixel_order {
    /* Square tiles of BSP_RENDER_TILE x BSP_RENDER_TILE pixels (smaller at
     * the right and bottom edges), taken by the threads in rows of tiles and
     * each traced row by row. Neighbouring rays take nearly the same path
     * through a tree, so a tile keeps a thread's caches and branch predictor
     * warm: renders 5-12 % faster than in rows on most SPD scenes and
     * the Stanford dragon (docs/renderer.md, "Pixel order"). */
    BSP_PIXELS_TILES = 0,
    /* Whole rows, taken by the threads in turn; with one thread the image's
     * scanline order. */
    BSP_PIXELS_ROWS
} bsp_pixel_order;

#define BSP_RENDER_TILE 16

typedef struct bsp_render_options {
    int width, height; /* 0: from the scene's camera (see bsp_sampling) */
    int max_depth;     /* secondary ray generations: primary rays have depth 0, and
                          hits spawn reflected/refracted rays while their depth is
                          below this; 0 = primary and shadow rays only; default 4 */
    int threads;       /* 0: all cores */
    bsp_sampling sampling;
    /* The camera; NULL: the scene's (its resolution then gives the default size). */
    const bsp_camera *camera;
    /* 1: an orthographic camera (the rays of sah-par): parallel rays along
     * at - from that start on the plane through from, over a window
     * ortho_width wide (scene units) centred on from, spaced like the
     * perspective rays (the sampling rule above, with the window in place of
     * the angle). ortho_width 0: 2 tan(angle/2) |at - from|, the width of the
     * perspective view at the look-at point. */
    int orthographic;
    double ortho_width;
    /* The order of the pixels (default BSP_PIXELS_TILES). The image, the
     * statistics and the pixel costs are the same in either order and for
     * any thread count; only the order of the ray_log calls differs. */
    bsp_pixel_order pixel_order;
    /* Called now and then from one thread with the share of the image done; may be NULL. */
    void (*progress)(double done, void *ctx);
    void *progress_ctx;
    /* Called for every ray cast, with its class, before it is shot; may be
     * NULL. FROM: the primitive its query leaves out (bsp_intersect_from:
     * the one a shadow or secondary ray leaves, when it cannot meet it
     * again), or BSP_NO_PRIM. Called from the render threads at once: with
     * threads > 1 it must be thread-safe. (bench records a render's rays
     * this way.) */
    void (*ray_log)(bsp_ray_class cls, const bsp_ray *ray, uint32_t from, void *ctx);
    void *ray_log_ctx;
    /* Per-pixel work, when not NULL: PIXEL_COSTS[y * width + x] receives the
     * counters of every query made for pixel (x, y) — its primary ray and the
     * shadow and secondary rays it spawns — summed (rays: how many). Room for
     * PIXEL_COSTS_COUNT records, at least width * height of the render
     * (bsp_render_size), or the render fails with BSP_ERR_INVALID. The
     * counts are the same for any thread count, and over all pixels they sum
     * to the statistics' counts. */
    bsp_query_counters *pixel_costs;
    size_t pixel_costs_count;
} bsp_render_options;

void bsp_render_options_defaults(bsp_render_options *opts);

/* The size, in rays across and down, that bsp_render renders SCENE at with
 * OPTS (NULL: the defaults): OPTS's width and height, or the camera's
 * (bsp_sampling). BSP_ERR_INVALID when there is no camera or a size is
 * negative. */
bsp_status bsp_render_size(const bsp_scene *scene, const bsp_render_options *opts, int *width,
                           int *height, bsp_error *err);

/* Renders ACCEL's scene from its camera. On success *OUT owns a new image and
 * *STATS (if not NULL) holds the statistics. The image is identical whatever
 * the thread count. */
bsp_status bsp_render(const bsp_accel *accel, const bsp_render_options *opts, bsp_image **out,
                      bsp_render_stats *stats, bsp_error *err);

/* The share of primary rays among all the rays (primary, shadow, reflected,
 * refracted) of a Whitted render of SCENE through CAMERA (NULL: the scene's;
 * its resolution + 1 rays across, SPD protocol) with ray depth MAX_DEPTH
 * (0: 4): the pre-pass of sah-mixed. */
bsp_status bsp_measure_primary_share(const bsp_scene *scene, const bsp_camera *camera,
                                     int max_depth, double *share, bsp_error *err);

#ifdef __cplusplus
}
#endif

#endif /* BSPRAY_RENDER_H */
