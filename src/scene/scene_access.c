/*
 * scene_access.c — the public read accessors of primitive geometry
 * (bsp_scene_prim_sphere, _cone, _vertex, _vertex_normal): what a program
 * needs to export a scene or hand it to another ray tracer.
 *
 * They read the shape records the intersection kernels use (scene_internal.h)
 * and undo their precomputation, so the geometry returned is the surface
 * bspray intersects. Only radii signs and the stored sums are reconstructed;
 * nothing here writes to the scene.
 */
#include "geom/vec.h"
#include "scene/scene_internal.h"

/* The record of PRIM when it exists and is stored as SHAPE, else NULL. */
static const prim_record *record_of(const bsp_scene *s, size_t prim, shape_kind shape)
{
    if (!s || prim >= s->nprims || s->prims[prim].shape != (uint8_t)shape)
        return NULL;
    return &s->prims[prim];
}

/* NFF's negative radius ("only the inside is visible") is stored as its
 * magnitude plus a flag; this gives the signed value back. */
static double signed_radius(double magnitude, int inside_only)
{
    return inside_only ? -magnitude : magnitude;
}

bsp_status bsp_scene_prim_sphere(const bsp_scene *s, size_t prim, bsp_vec3 *center,
                                 double *radius)
{
    const prim_record *p = record_of(s, prim, SHAPE_SPHERE);
    if (!p)
        return BSP_ERR_INVALID;
    const sphere_shape *sp = &s->spheres[p->slot];
    if (center)
        *center = sp->center;
    if (radius)
        *radius = signed_radius(sp->radius, sp->inside_only);
    return BSP_OK;
}

bsp_status bsp_scene_prim_cone(const bsp_scene *s, size_t prim, bsp_vec3 *base,
                               double *base_radius, bsp_vec3 *apex, double *apex_radius)
{
    const prim_record *p = record_of(s, prim, SHAPE_CONE);
    if (!p)
        return BSP_ERR_INVALID;
    const cone_shape *c = &s->cones[p->slot];
    if (base)
        *base = c->base;
    if (base_radius)
        *base_radius = signed_radius(c->base_radius, c->inside_only);
    /* the cone keeps base, unit axis and length, not the apex itself */
    if (apex)
        *apex = v3_madd(c->base, c->axis, c->length);
    if (apex_radius)
        *apex_radius = signed_radius(c->apex_radius, c->inside_only);
    return BSP_OK;
}

/* Polygons and patches of three vertices are triangles (v0, e1, e2), larger
 * ones index the shared vertex pool; PATCH_ONLY refuses polygons. Returns the
 * record's vertex count through *COUNT, or NULL when PRIM has no vertices. */
static const prim_record *polygonal_record(const bsp_scene *s, size_t prim, int patch_only,
                                           size_t *count)
{
    if (!s || prim >= s->nprims)
        return NULL;
    const prim_record *p = &s->prims[prim];
    if (patch_only && p->kind != BSP_PRIM_PATCH)
        return NULL;
    if (p->shape == SHAPE_TRIANGLE)
        *count = 3;
    else if (p->shape == SHAPE_POLYGON)
        *count = s->polygons[p->slot].count;
    else
        return NULL;
    return p;
}

bsp_status bsp_scene_prim_vertex(const bsp_scene *s, size_t prim, size_t i, bsp_vec3 *vertex)
{
    size_t count = 0;
    const prim_record *p = polygonal_record(s, prim, 0, &count);
    if (!p || i >= count)
        return BSP_ERR_INVALID;
    bsp_vec3 v;
    if (p->shape == SHAPE_TRIANGLE) {
        const triangle_shape *tr = &s->triangles[p->slot];
        v = i == 0 ? tr->v0 : i == 1 ? tr->v1 : tr->v2;
    } else {
        v = s->verts[s->polygons[p->slot].first + i];
    }
    if (vertex)
        *vertex = v;
    return BSP_OK;
}

bsp_status bsp_scene_prim_vertex_normal(const bsp_scene *s, size_t prim, size_t i,
                                        bsp_vec3 *normal)
{
    size_t count = 0;
    const prim_record *p = polygonal_record(s, prim, 1, &count);
    if (!p || i >= count)
        return BSP_ERR_INVALID;
    /* a patch added with NULL normals has none */
    uint32_t first = p->shape == SHAPE_TRIANGLE ? s->triangles[p->slot].normals
                                                : s->polygons[p->slot].normals;
    if (first == SHAPE_NO_NORMALS)
        return BSP_ERR_INVALID;
    if (normal)
        *normal = s->normals[first + i];
    return BSP_OK;
}
