/*
 * kd_local.h — the traversal's copy of the primitives, in the order the
 * leaves first list them (kd_local.c).
 *
 * Why: on a large mesh most of a primary ray's time went in waiting for
 * memory, and a test read three scattered places: the scene's record of the
 * primitive (its shape and slot), the shape's 104-byte record in input order,
 * and the mailbox stamp. The tree keeps instead, per primitive it lists, one
 * 80-byte record holding what the shape's kernel reads (kd_local), numbered
 * by the primitive's first appearance in a walk of the leaves in node order,
 * and its leaf lists a second time in those numbers (lref, parallel to
 * prims). The primitives of neighbouring cells then lie side by side, a test
 * reads one record, and the mailbox is indexed by the same numbers.
 * Primary rays per second on the Stanford dragon (47,794 / 202,520 /
 * 871,414 triangles), against the scene's records: 1.07x / 1.13-1.24x /
 * 1.24-1.36x; SPD scenes of about 10^4 primitives within noise
 * (docs/kdtree-log.md, "Session 22").
 *
 * Exactness: a record holds a bit-for-bit copy of the shape's data and the
 * kernel is the same function, so every t is the one the naive method
 * computes; ties compare the scene's indices (prim), as before. Cones (96
 * bytes) are not copied: their record points at the scene's cone.
 */
#ifndef BSPRAY_ACCEL_KD_LOCAL_H
#define BSPRAY_ACCEL_KD_LOCAL_H

#include "accel/kd_tree.h"

typedef struct kd_local {
    union {
        triangle_edges triangle; /* triangle_edges_of the scene's vertices */
        sphere_shape sphere;
        polygon_shape polygon; /* its vertices and slabs stay in the scene's pools */
        const cone_shape *cone;
    } u;
    uint32_t prim;   /* the scene's index */
    uint8_t shape;   /* shape_kind of the primitive */
    int8_t edge_exp; /* a triangle's triangle_edge_exp (its shape's), else 0 */
} kd_local;

_Static_assert(sizeof(kd_local) == 80, "a local record is 80 bytes");

/* Fills *L with the record of primitive P of S: its kernel's data (a copy,
 * bit for bit; a cone's pointer) and its index. Also the BVH's leaf records
 * (bvh.h). */
HIDDEN void kd_local_fill(kd_local *L, const bsp_scene *s, uint32_t p);

/* Makes T's local copy (t->loc, t->nloc) and its leaf lists in local numbers
 * (t->lref) from T's finished tree over SCENE, replacing any earlier copy;
 * 0 when out of memory. */
HIDDEN int kd_local_build(kd_tree *t, const bsp_scene *scene);

/* Checks the copy against T's leaf lists and SCENE: every entry of lref names
 * a record of the same primitive as prims, every record is the scene's data
 * bit for bit and listed, first listed in its number's order, and no
 * primitive has two records. BSP_OK, or
 * BSP_ERR_INVALID with the first violation. */
HIDDEN bsp_status kd_local_check(const kd_tree *t, const bsp_scene *scene, bsp_error *err);

/* The primitive of record L against RAY: scene_isect on the copy. */
static inline __attribute__((always_inline)) int
kd_local_isect(const bsp_scene *s, const kd_local *L, const isect_ray *ray, double tmax,
               scene_isect_hit *h)
{
    const void *data = L->shape == SHAPE_CONE ? (const void *)L->u.cone : (const void *)&L->u;
    return shape_isect(s, L->shape, data, L->prim, L->edge_exp, ray, tmax, h);
}

#endif /* BSPRAY_ACCEL_KD_LOCAL_H */
