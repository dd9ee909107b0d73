/*
 * kd_clip.h — tight, conservative bounds of the part of a primitive inside a
 * box ("split-clipped bounds"), for the perfect splits of the SAH builder
 * (Havran & Bittner 2002; Wald & Havran 2006) and for the invariant checker.
 *
 * Contract of kd_clip_prim(scene, prim, box, pad, ...): let G be BOX grown by
 * PAD on every side. The result is the bounds of (primitive ∩ G), grown by
 * PAD — with every rounding error of the clipping far below PAD (the padding
 * is KD_PAD_REL of the scene scale, the errors a few ulps of it), so every
 * point of the primitive inside G lies at least about PAD inside the result,
 * exactly as kd_prim_box pads the unclipped bounds. "Empty" (return 0) is
 * answered only when the primitive is at least about PAD away from BOX.
 *
 * Triangles and polygons are clipped exactly (Sutherland–Hodgman against the
 * planes of G that their bounds cross); a sphere uses the ball ∩ G (exact
 * per axis) and is dropped when G lies wholly inside it; a cone uses the box
 * of its part over the range of its axis where its cross-section can reach G,
 * and, along a coordinate axis, its circles ∩ G's cross-section as for the
 * sphere (kd_clip.c). A primitive whose bounds lie inside G gets its plain padded
 * bounds, bit for bit what kd_prim_box returns.
 */
#ifndef BSPRAY_ACCEL_KD_CLIP_H
#define BSPRAY_ACCEL_KD_CLIP_H

#include "accel/kd_tree.h"

/* Vertex scratch for clipping large polygons, grown on demand; zero it
 * before first use. Without scratch (NULL) large polygons allocate per call. */
typedef struct kd_clip_scratch {
    bsp_vec3 *buf[2]; /* ping-pong vertex buffers */
    size_t cap[2];
} kd_clip_scratch;

HIDDEN void kd_clip_scratch_free(kd_clip_scratch *scr);

/* Writes the clipped, padded bounds of live primitive PRIM against BOX (see
 * above) to *OUT and returns 1; returns 0 when the part is empty, -1 when out
 * of memory. */
HIDDEN int kd_clip_prim(const bsp_scene *scene, uint32_t prim, const bsp_box *box, double pad,
                        kd_clip_scratch *scr, bsp_box *out);
/* The same with PB = bsp_scene_prim_bounds(scene, prim) given (a builder
 * that clips a primitive many times keeps its bounds). */
HIDDEN int kd_clip_prim_bounded(const bsp_scene *scene, uint32_t prim, bsp_box pb,
                                const bsp_box *box, double pad, kd_clip_scratch *scr,
                                bsp_box *out);

/* kd_clip_prim_bounded for both children of CELL split at S on AXIS, into
 * OUT[0] (left) and OUT[1] (right): returns a bit mask of the children the
 * part is not empty in (bit 0: left), or -1 when out of memory. Triangles
 * are clipped once to CELL and that part once by each side. */
HIDDEN int kd_clip_prim_split(const bsp_scene *scene, uint32_t prim, bsp_box pb,
                              const bsp_box *cell, unsigned axis, double s, double pad,
                              kd_clip_scratch *scr, bsp_box out[2]);

/* The parts of triangles and polygons inside the cells along an SAH
 * build's path (kd_sah_node.c), so that a straddler is clipped by the one
 * plane of each split instead of to the whole cell every time: OF[p] is the
 * handle of primitive p's part in the current cell's G (the cell grown by
 * the padding), the polygon of the vertices V[h >> KD_PART_COUNT_BITS ..][0
 * .. h & KD_PART_COUNT_MASK); 0 means the primitive itself, clipped afresh
 * to the cell when it straddles, which is always right (kd_clip_prim_split).
 * The builder sets OF along the path and restores it when it returns from a
 * subtree, and pops V to where it was. A part stays valid below its cell:
 * where the primitive does not straddle a split, its part lies on one side,
 * inside that child's G. Each plane adds a few ulps of error to a vertex,
 * far below the padding (kd_clip.c's rounding note), and the bounds are
 * clamped to the exact ones as ever. A concave polygon's part may carry
 * zero-width bridges along earlier planes; as with clipping afresh, they
 * can only make its bounds larger than the true part's, never smaller. */
typedef struct kd_clip_path {
    uint64_t *of;     /* per primitive: its part's handle, 0: none */
    bsp_vec3 *v;      /* the parts' vertices, a stack */
    size_t top, cap;
} kd_clip_path;

#define KD_PART_COUNT_BITS 16
#define KD_PART_COUNT_MASK ((1u << KD_PART_COUNT_BITS) - 1)
/* Parts of more vertices are not kept (the primitive is clipped afresh) */
#define KD_PART_MAX_VERTS KD_PART_COUNT_MASK

HIDDEN void kd_clip_path_free(kd_clip_path *path);

/* kd_clip_prim_split for triangle or polygon PRIM whose part in CELL's G is
 * PART (a handle of PATH; 0: the primitive itself), which also returns the
 * parts of both children in PARTS[2] (pushed on PATH's stack; 0 where the
 * child needs none: the primitive's bounds lie inside its G, or the part was
 * too large to keep, or it is empty). SCR: scratch for clipping a large
 * polygon afresh. */
HIDDEN int kd_clip_split_part(const bsp_scene *scene, uint32_t prim, bsp_box pb,
                              const bsp_box *cell, unsigned axis, double s, double pad,
                              kd_clip_path *path, kd_clip_scratch *scr, uint64_t part,
                              bsp_box out[2], uint64_t parts[2]);

/* Whether the hits of polygon PRIM (its vertices moved onto its plane,
 * even-odd inside) meet the closed box B: exactly, up to rounding, where
 * clipping gives only bounds of a superset. Clipping a concave or
 * self-crossing polygon leaves zero-width "bridges" along the clipping
 * planes, and a later plane can cut a bridge where the polygon is not: the
 * builder, which clips along the path from the root, and the checker, which
 * clips the whole polygon to a leaf, can then disagree about a leaf neither
 * needs. The checker (kd_tree_check) asks this before it calls an unlisted
 * polygon an error. */
HIDDEN int kd_polygon_meets_box(const bsp_scene *scene, uint32_t prim, const bsp_box *b);

/* The checker (kd_tree_check) asks for a primitive in every leaf its bounds
 * clipped with this fraction of the tree's padding overlap: the builder clips
 * with the whole padding, so its assignment is a superset with a margin of
 * half the padding — far above rounding — whatever cell it last clipped
 * against, and the checked property (every primitive within pad/2 of a leaf
 * is listed there) is still far stronger than exactness needs. */
#define KD_CHECK_PAD_FRACTION 0.5

#endif /* BSPRAY_ACCEL_KD_CLIP_H */
