/*
 * kd_view.h — the paper's modified SAH (Havran, Bittner & Kopal, section 4):
 * probability measures for restricted ray sets, and the builds that use them.
 *
 * For rays from one eye through a viewport (PER) the share of the rays that
 * cross a box B is the area of B's projection onto the image plane, clipped
 * to the viewport, over the viewport's area: rays are spread uniformly over
 * the image plane. For rays of one direction starting on a plane (PAR) it
 * is the area of B's parallel projection onto that plane, clipped to the
 * window. Either way only the part of B in front of the rays' origin (the
 * eye plane, or the plane the parallel rays start from) counts; a box that
 * contains the eye is crossed by every ray.
 *
 * The builds are the SAH builder with this measure in place of the surface
 * area (kd_build_sah_measure): the events, the termination and the node
 * layout are shared.
 */
#ifndef BSPRAY_ACCEL_KD_VIEW_H
#define BSPRAY_ACCEL_KD_VIEW_H

#include "accel/kd_cost.h"
#include "accel/kd_flux.h"
#include "accel/kd_raycount.h"
#include "accel/kd_tree.h"

/* A resolved view: an orthonormal frame and the viewport. */
typedef struct kd_view {
    int ortho;               /* 0: perspective (PER), 1: parallel (PAR) */
    bsp_vec3 eye;            /* PER: the eye; PAR: the window's centre */
    bsp_vec3 fwd, right, up; /* orthonormal; fwd is the view direction */
    /* The viewport, in the image plane at distance 1 from the eye (PER) or in
     * the plane through EYE (PAR, scene units): [-hx, hx] x [-hy, hy]. */
    double hx, hy;
} kd_view;

/* Resolves the view of O (its explicit view, or SCENE's camera) for ORTHO.
 * BSP_ERR_INVALID with a message when there is no camera or it is
 * degenerate. */
HIDDEN bsp_status kd_view_resolve(const bsp_scene *scene, const bsp_build_options *o, int ortho,
                                  kd_view *v, bsp_error *err);

/* The area of BOX's projection clipped to the viewport of V (in the units
 * of hx * hy; the viewport's own area is 4 hx hy). 0 for a box wholly
 * behind the eye plane or outside the viewport; 4 hx hy for a box that
 * contains the eye (PER). CTX of kd_area_fn is a kd_view. */
HIDDEN double kd_view_area(const bsp_box *box, const void *view);

/* The view measure of the children of a cell's splits, for the SAH sweep
 * (kd_view_split.c): the cell's corners are projected once for the sweeps
 * of its three axes, and each plane's four corners once for both of its
 * children. The cell's part, kept by a build thread from one axis's sweep
 * to the next, keyed by the cell and the view: */
typedef struct kd_view_cell {
    const kd_view *view;
    bsp_box box;
    int state;           /* 0: not prepared yet; 1: accepted; -1: refused */
    double rl[3][3], rh[3][3]; /* (lo_j - eye_j) and (hi_j - eye_j) times right, up, fwd's j */
    double cx[8], cy[8]; /* the corners, projected (bit j of c: hi on axis j) */
    signed char side[3]; /* the face seen on each axis (-1: none; PER: by the cell) */
} kd_view_cell;
/* ... and one axis's: */
typedef struct kd_view_split {
    kd_view_cell *vc;
    unsigned k;                   /* the split axis */
    int ready;                    /* the terms below are set */
    int plane_ok;                 /* the plane at P lies in front (its corners are valid) */
    double eye_k, lo_k, hi_k;     /* on the split axis */
    double rk, uk, fk;            /* right, up and fwd on the split axis */
    double sx[4], sy[4], sz[4];   /* a plane corner's terms of the other two axes */
    unsigned nside;               /* the faces of the other axes the rays see: their */
    const unsigned char (*side_src[2])[4]; /* corners by child (kd_view_split.c, face_src) */
    double cell_face2[2];         /* twice the areas of the cell's lo and hi faces of the axis */
    double vp_area;               /* the viewport's area, the most a measure can be */
    double p;                     /* the plane whose corners px, py [8, 12) hold (NaN: none) */
    double px[12], py[12];        /* the corners projected: the cell's corner c at c, the
                                     plane's corner q at 8 + q (bit 0: the side of axis
                                     k + 1, bit 1: of axis k + 2) */
    double plane_face2;           /* twice the area of the plane's face */
} kd_view_split;
/* Starts the children's measures of CELL's splits on axis K under VIEW, with
 * VC the build thread's cell part (prepared again when it holds another
 * cell or view). Nothing is computed until a child is measured. */
HIDDEN void kd_view_split_begin(kd_view_split *s, kd_view_cell *vc, const kd_view *view,
                                const bsp_box *cell, unsigned k);
/* The measures of the child below the plane at P (CHILD: the cell with hi
 * on the split axis P) and of the child above it (the cell with lo P):
 * kd_view_area's value within the error bound of kd_view_measure_noise.
 * Where the cell does not lie wholly in front of the rays' start plane and
 * inside the viewport, or (PER) contains the eye, kd_view_area of CHILD. */
HIDDEN double kd_view_split_left(kd_view_split *s, const bsp_box *child, double p);
HIDDEN double kd_view_split_right(kd_view_split *s, const bsp_box *child, double p);
/* sah-mixed: the expected share of all the render's rays that cross a box,
 * w * A_view(B) / A_viewport + (1 - w) * P_other(B), w the share of primary
 * rays: primary rays are counted by the projected area, every other ray
 * (shadow, reflected, refracted) by P_other. The surface model takes them
 * for uniformly distributed lines, P_other = SA(B) / SA(root); the sampled
 * model by the density of the pre-pass's rays (kd_flux.h), with a floor of
 * uniform lines where the sample is thin: P_other = (1 - b) F(B) / F(root)
 * + b SA(B) / SA(root); the counted model the same with F the number of
 * the pre-pass's segments that meet B (kd_raycount.h). */
typedef struct kd_mixed_measure {
    kd_view view;
    double w_view;        /* w / A_viewport */
    double w_surf;        /* (1 - w) / SA(root), or (1 - w) b / SA(root) */
    double w_flux;        /* (1 - w) (1 - b) / F(root); 0: no sampled term */
    const kd_flux *flux;  /* the sampled term's density, when w_flux > 0 */
    double w_count;       /* the counted model: (1 - w) (1 - b) / count(root); 0: none */
    const kd_raycount_cursor *count; /* the counted term's cells, when w_count > 0 (each
                                        build thread has a copy with its own cursor) */
} kd_mixed_measure;

/* The mixed measure of BOX; CTX is a kd_mixed_measure. */
HIDDEN double kd_mixed_area(const bsp_box *box, const void *mixed);
/* The same with VIEW_AREA for kd_view_area's value of BOX under M's view
 * (the sweep's children take theirs from kd_view_split). */
HIDDEN double kd_mixed_area_of_view(const kd_mixed_measure *m, const bsp_box *box,
                                    double view_area);

/* A bound on the rounding error of MEASURE (kd_view_area or kd_mixed_area;
 * CTX its context) on the children of CELL
 * split on AXIS, in its units: within that bound the measure is monotone
 * under inclusion and the two children of a split cover their parent
 * (al + ar >= A), which the pruned SAH sweep relies on — except for the
 * children at positions in [ZONE[0], ZONE[1]] (next to the eye; an empty
 * interval when there are none), which it must evaluate all. INFINITY where
 * no such bound is known (a cell face at the eye; any other measure). */
HIDDEN double kd_view_measure_noise(kd_area_fn measure, const void *ctx, const bsp_box *cell,
                                    unsigned axis, double zone[2]);

/* The sah-per, sah-par and sah-mixed builds of O->kind. */
HIDDEN bsp_status kd_build_view(kd_tree *t, const bsp_scene *scene, const bsp_build_options *o,
                                bsp_error *err);

#endif /* BSPRAY_ACCEL_KD_VIEW_H */
