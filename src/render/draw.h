/*
 * draw.h — raster drawing for the kd-tree pictures of `bspray viz` (the
 * paper's Fig. 5): alpha-blended lines clipped to the image, filled and
 * outlined rectangles, a depth colour map, a 5 x 7 bitmap font, a pinhole
 * projection identical to the renderer's pixel-centre camera (with segments
 * clipped against a near plane), an orthographic top view, and the two
 * panels built from them: split planes over a camera view and leaf cells
 * seen from above.
 *
 * Pixel coordinates are continuous: pixel (i, j) covers [i, i+1) x [j, j+1),
 * row 0 at the top, so its centre is (i + 0.5, j + 0.5). Nothing here ever
 * writes outside an image, whatever the coordinates (infinities and NaN
 * included). Colours are linear RGB in [0, 1], as in bsp_image.
 */
#ifndef BSPRAY_RENDER_DRAW_H
#define BSPRAY_RENDER_DRAW_H

#include <stddef.h>
#include <stdint.h>

#include "bspray/accel.h"
#include "bspray/render.h"
#include "bspray/scene.h"

#define DRAW_HIDDEN __attribute__((visibility("hidden")))

/* --- 2D raster helpers -------------------------------------------------------------- */

/* Mixes RGB into pixel (X, Y) with weight ALPHA (1: replace); no-op outside. */
DRAW_HIDDEN void draw_blend(bsp_image *img, int x, int y, const float rgb[3], float alpha);
/* A one-pixel line from (X0, Y0) to (X1, Y1), clipped to the image first;
 * each covered pixel is blended once. */
DRAW_HIDDEN void draw_line(bsp_image *img, double x0, double y0, double x1, double y1,
                           const float rgb[3], float alpha);
/* Blends every pixel whose centre lies in [X0, X1) x [Y0, Y1). */
DRAW_HIDDEN void draw_fill_rect(bsp_image *img, double x0, double y0, double x1, double y1,
                                const float rgb[3], float alpha);
/* The border of the pixel rectangle [X0, X1] x [Y0, Y1] (inclusive pixel
 * indices), one pixel wide. */
DRAW_HIDDEN void draw_frame(bsp_image *img, int x0, int y0, int x1, int y1, const float rgb[3],
                            float alpha);
/* Copies SRC into DST with its top-left corner at (DX, DY), clipped. */
DRAW_HIDDEN void draw_paste(bsp_image *dst, const bsp_image *src, int dx, int dy);
/* Turns a render into a faint background: each pixel becomes a dark grey
 * from its luminance (in 32 levels) with a little of its own colour left. */
DRAW_HIDDEN void draw_fade(bsp_image *img);

/* The colour map of depths: T = 0 (shallow) bright yellow, through orange,
 * red and violet, to T = 1 (deep) blue; T is clamped to [0, 1]. */
DRAW_HIDDEN void draw_colormap(double t, float rgb[3]);
/* The colour at T in [0, 1] (clamped) of the ramp through NSTOPS >= 2
 * colours STOPS, evenly spaced, interpolated linearly. */
DRAW_HIDDEN void draw_ramp(const float (*stops)[3], int nstops, double t, float rgb[3]);

/* --- text: a 5 x 7 bitmap font (upper case, digits, a few signs) --------------------- */

/* Height of a line of text at SCALE (pixels per font dot). */
#define DRAW_TEXT_HEIGHT(scale) (8 * (scale))
/* Width in pixels of TEXT at SCALE. */
DRAW_HIDDEN int draw_text_width(const char *text, int scale);
/* Draws TEXT with its top-left corner at (X, Y); lower case is drawn as
 * upper case, unknown characters as '?'. Returns the width drawn. */
DRAW_HIDDEN int draw_text(bsp_image *img, int x, int y, int scale, const char *text,
                          const float rgb[3]);
/* TEXT in white on a translucent black box with a margin of SCALE pixels;
 * returns the box's height. */
DRAW_HIDDEN int draw_label(bsp_image *img, int x, int y, int scale, const char *text);

/* --- projections -------------------------------------------------------------------- */

/* The pinhole camera of bsp_render with BSP_SAMPLING_CENTRES: a point whose
 * direction from the eye is the primary ray of pixel (i, j) projects to its
 * centre (i + 0.5, j + 0.5). */
typedef struct draw_pinhole {
    bsp_vec3 eye;
    bsp_vec3 forward, right, up; /* orthonormal, as the renderer builds them */
    double focal;                /* pixels per unit of the image plane at distance 1 */
    double cx, cy;               /* the image centre (where the view axis lands) */
    double near;                 /* segments are clipped to forward distance >= near */
} draw_pinhole;

/* The camera CAM on a WIDTH x HEIGHT image (the angle spans the width);
 * NEAR > 0 is the near-plane distance. */
DRAW_HIDDEN void draw_pinhole_init(draw_pinhole *p, const bsp_camera *cam, int width, int height,
                                   double near);
/* Projects P to (*PX, *PY); returns 0 (and leaves them unset) when P is
 * closer than the near plane or behind the eye. */
DRAW_HIDDEN int draw_pinhole_project(const draw_pinhole *p, bsp_vec3 q, double *px, double *py);
/* The segment A-B clipped against the near plane, projected and drawn. */
DRAW_HIDDEN void draw_segment_3d(bsp_image *img, const draw_pinhole *p, bsp_vec3 a, bsp_vec3 b,
                                 const float rgb[3], float alpha);

/* An orthographic view down the world axis nearest the camera's up vector,
 * turned so that the camera's right points right (and its view direction,
 * unless it looks straight down, points up the image), never mirrored. */
typedef struct draw_topview {
    int up_axis;           /* the world axis looked along */
    int h_axis, v_axis;    /* world axes of image x and of image -y */
    double h_sign, v_sign; /* +1 or -1 */
    double hc, vc;         /* world coordinates of the image centre */
    double scale;          /* pixels per scene unit */
    double cx, cy;         /* the image centre in pixels */
} draw_topview;

/* Fits REGION's extent across the view into WIDTH x HEIGHT with MARGIN
 * pixels on each side, keeping its aspect ratio. */
DRAW_HIDDEN void draw_topview_init(draw_topview *tv, const bsp_camera *cam, bsp_box region,
                                   int width, int height, int margin);
DRAW_HIDDEN void draw_topview_project(const draw_topview *tv, bsp_vec3 q, double *px, double *py);

/* --- kd-tree cells and the two panels ------------------------------------------------- */

/* Every cell of a tree, in the order of bsp_accel_visit_cells. */
typedef struct draw_cells {
    bsp_cell_info *cell;
    size_t count, cap;
    int max_depth;     /* deepest cell */
    uint64_t leaves;   /* leaf cells */
    uint64_t empty;    /* leaf cells with no reference */
    uint64_t max_refs; /* most references in one leaf */
} draw_cells;

/* Walks ACCEL's whole tree into *CELLS (zeroed first; free with
 * draw_cells_free). The naive method gives no cells. */
DRAW_HIDDEN bsp_status draw_cells_collect(const bsp_accel *accel, draw_cells *cells,
                                          bsp_error *err);
DRAW_HIDDEN void draw_cells_free(draw_cells *cells);

typedef enum draw_color_mode {
    DRAW_COLOR_DEPTH = 0, /* a leaf's depth, 0 .. the depth scale */
    DRAW_COLOR_REFS       /* a leaf's references, log scale up to the refs scale */
} draw_color_mode;

/* The colour of a leaf with VALUE (depth or references) in MODE, where SCALE
 * is the value mapped to the end of the colour map. Depth: shallow warm, deep
 * cool. References: an empty leaf dark grey, then cool (few) to warm (many). */
DRAW_HIDDEN void draw_cell_color(draw_color_mode mode, double value, double scale, float rgb[3]);

/* Camera panel: draws over IMG the split plane of every interior cell (the
 * plane clipped to its cell, a rectangle whose four edges are projected by
 * P), coloured by depth / DEPTH_SCALE, deepest first so that the shallow
 * planes stay on top; deeper planes are more translucent. */
DRAW_HIDDEN void draw_panel_planes(bsp_image *img, const draw_pinhole *p, const draw_cells *cells,
                                   int depth_scale);
/* Camera panel for a hierarchy of boxes (a BVH, whose boxes may overlap):
 * the twelve edges of every node's box below the root, coloured and faded by
 * depth as draw_panel_planes does, deepest first. */
DRAW_HIDDEN void draw_panel_boxes(bsp_image *img, const draw_pinhole *p, const draw_cells *cells,
                                  int depth_scale);
/* The twelve edges of the root cell, in white. */
DRAW_HIDDEN void draw_panel_root(bsp_image *img, const draw_pinhole *p, const draw_cells *cells);

/* Top panel: fills IMG (cleared to dark grey) with the leaf cells seen from
 * above through TV. Each pixel shows the largest value (depth, or references
 * in MODE) among the leaves whose projection covers its centre, that is the
 * maximum over the column of space below it; then every leaf's outline is
 * drawn, and the horizontal edges of CAM's view frustum (NULL: none). */
DRAW_HIDDEN bsp_status draw_panel_top(bsp_image *img, const draw_topview *tv,
                                      const draw_cells *cells, draw_color_mode mode, double scale,
                                      const bsp_camera *cam, bsp_error *err);

#endif /* BSPRAY_RENDER_DRAW_H */
