/*
 * kd_flux.h — a measure of boxes by the rays of a sample (sah-mixed's model
 * of the non-primary rays, docs/modified-sah.md).
 *
 * A ray segment that meets a convex box B crosses B's surface twice, or
 * once and has one end point inside B, or has both inside: so the number of
 * segments meeting B is exactly half the number of surface crossings plus
 * end points inside B. (The rays of a render start on surfaces — every
 * shadow ray — and stop at hits, so the end points matter most in the
 * small cells around the geometry; counting crossings alone would halve
 * those cells' measure.) The crossings of a face
 * perpendicular to axis k at a point are counted by a density phi_k: the
 * number of segment crossings per unit area of a k-plane there. On a voxel
 * grid over the scene, a segment running a length l through a voxel of
 * volume V adds l |d_k| / |d| / V to that voxel's phi_k (the chance that a
 * k-plane piece of area a, placed at random in the voxel, is crossed is
 * a l |d_k| / (|d| V)). The measure of B is then
 *
 *     F(B) = 1/2 (sum over B's six faces of the integral of phi_k over the
 *            face + the integral over B of rho),
 *
 * phi_k and rho (end points per unit volume) piecewise constant by voxel;
 * each face integral is read from 2D prefix sums of the face's slab of
 * voxels (bilinear within a voxel), the volume integral from 3D prefix sums
 * (trilinear): exact for piecewise-constant densities. For uniformly distributed lines F is
 * proportional to the surface area; for the rays of a render it follows
 * where they actually run: where they start, end at hits, and bunch
 * towards the lights.
 *
 * F covers its children (F(L) + F(R) = F(V) + the integral over the split
 * face, at least F(V)) but is not monotone under inclusion (a box's faces
 * may sit in denser voxels than its parent's), so the pruned sweep gets no
 * noise bound for it and evaluates every candidate.
 */
#ifndef BSPRAY_ACCEL_KD_FLUX_H
#define BSPRAY_ACCEL_KD_FLUX_H

#include <stddef.h>

#include "accel/kd_tree.h"

typedef struct kd_flux {
    bsp_box box;
    int n[3];       /* voxels per axis */
    double cs[3];   /* voxel size per axis (> 0) */
    double *ends;   /* (n[0] + 1) x (n[1] + 1) x (n[2] + 1) 3D prefix sums of the
                       segments' end points inside the grid (starts and ends) */
    double *pre[3]; /* axis k, with u = k+1, v = k+2 (mod 3): for slab i < n[k],
                       (n[u] + 1) x (n[v] + 1) sums: pre[k][(i * (n[u] + 1) + a) *
                       (n[v] + 1) + b] = the integral of phi_k over the voxels below
                       a on u and below b on v of slab i */
    double total;   /* F of the grid's box */
} kd_flux;

/* One ray segment of the sample: the points org + t dir, t in [t0, t1]
 * (t1 may be infinite: the segment then runs to the grid's boundary). */
typedef struct kd_flux_segment {
    bsp_vec3 org, dir;
    double t0, t1;
} kd_flux_segment;

/* Builds the density of SEG[0..N) over BOX on a grid of about CELLS voxels
 * (shaped like BOX, 1..128 per axis). Segments that are not finite or miss
 * BOX add nothing. BSP_ERR_NOMEM, or BSP_OK. */
HIDDEN bsp_status kd_flux_build(kd_flux *f, const bsp_box *box, const kd_flux_segment *seg,
                                size_t n, size_t cells, bsp_error *err);

/* F(B) for a box inside the grid's box (parts outside it count with the
 * density of the nearest voxels). */
HIDDEN double kd_flux_measure(const kd_flux *f, const bsp_box *b);

HIDDEN void kd_flux_free(kd_flux *f);

#endif /* BSPRAY_ACCEL_KD_FLUX_H */
