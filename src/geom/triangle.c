/*
 * triangle.c — the triangle: setup, exact bounds, Möller–Trumbore ray
 * intersection and the interpolated shading normal of patch triangles.
 *
 * Möller–Trumbore computes t and the barycentrics on v0 and the edges
 * e1 = v1 - v0, e2 = v2 - v0 (rounded); whether the ray passes inside is
 * decided on the vertices themselves where rounding could matter (the
 * watertight decision, geom/isect.h), so that a ray through an edge that two
 * triangles share hits at least one of them. Points exactly on an edge or a
 * vertex are inside. A ray parallel to the plane (determinant 0, which
 * includes rays lying in the plane) misses. t never depends on
 * ray->tmin/tmax.
 */
#include <math.h>

#include "geom/isect.h"
#include "geom/shapes.h"
#include "geom/vec.h"

/* A sliver (the sine of the angle between e1 and e2 below this) is dropped
 * as degenerate: the barycentrics below lose 1/sine of relative precision,
 * and beyond about 1e-8 of an edge their error could report hits outside
 * the triangle's padded bounds, where no kd-tree lists it. With 1e-6 the
 * error stays near 1e-9 of an edge. */
#define TRIANGLE_MIN_SINE 1e-6

int triangle_setup(triangle_shape *tr, bsp_vec3 a, bsp_vec3 b, bsp_vec3 c, uint32_t normals)
{
    bsp_vec3 e1 = v3_sub(b, a), e2 = v3_sub(c, a);
    bsp_vec3 n = v3_cross(e1, e2);
    double len = v3_length(n);
    if (!(len > 0.0) || !isfinite(len))
        return 0;
    if (len < TRIANGLE_MIN_SINE * v3_length(e1) * v3_length(e2))
        return 0;
    bsp_vec3 unit = bsp_v3(n.x / len, n.y / len, n.z / len);
    if (!v3_is_finite(unit))
        return 0;
    tr->v0 = a;
    tr->v1 = b;
    tr->v2 = c;
    triangle_edges te = triangle_edges_of(&tr->verts);
    tr->edge_exp = (int8_t)triangle_edge_exp(&te);
    tr->normal = unit;
    tr->normals = normals;
    return 1;
}

/* Widens BOX to hold the exact value of base[k] + edge[k] on every axis: the
 * rounded sum, moved one ulp outward when the rounding lost something
 * (the error term is Knuth's TwoSum). */
static bsp_box add_exact_sum(bsp_box box, bsp_vec3 base, bsp_vec3 edge)
{
    for (int k = 0; k < 3; k++) {
        double a = base.v[k], b = edge.v[k];
        double s = a + b;
        double bb = s - a;
        double err = (a - (s - bb)) + (b - bb);
        double lo = err < 0.0 ? nextafter(s, -INFINITY) : s;
        double hi = err > 0.0 ? nextafter(s, INFINITY) : s;
        if (lo < box.lo.v[k])
            box.lo.v[k] = lo;
        if (hi > box.hi.v[k])
            box.hi.v[k] = hi;
    }
    return box;
}

/* The vertices, and the exact v0 + e1 and v0 + e2 of the rounded edges, whose
 * triangle Möller–Trumbore's points lie on (within an ulp of v1 and v2). */
bsp_box triangle_bounds(const triangle_shape *tr)
{
    bsp_box box = {tr->v0, tr->v0};
    box = box_add_point(box, tr->v1);
    box = box_add_point(box, tr->v2);
    const triangle_edges e = triangle_edges_of(&tr->verts);
    box = add_exact_sum(box, tr->v0, e.e1);
    return add_exact_sum(box, tr->v0, e.e2);
}

int triangle_intersect(const triangle_shape *tr, const bsp_ray *ray, double *t, double *u,
                       double *v)
{
    isect_ray r;
    isect_ray_init(&r, ray, INFINITY, NULL); /* no hit check: it needs the scene scale */
    double bu, bv, det;
    int hit = triangle_isect_verts(&tr->verts, tr->edge_exp, &r, ray->tmax, t, &bu, &bv, &det);
    if (!hit)
        return 0;
    triangle_uv(bu, bv, det, u, v);
    return 1;
}

bsp_vec3 triangle_shading_normal(const triangle_shape *tr, const bsp_vec3 *normal_pool, double u,
                                 double v)
{
    if (tr->normals == SHAPE_NO_NORMALS)
        return tr->normal;
    const bsp_vec3 *n = normal_pool + tr->normals;
    bsp_vec3 sum = v3_scale(n[0], 1.0 - u - v);
    sum = v3_madd(sum, n[1], u);
    sum = v3_madd(sum, n[2], v);
    bsp_vec3 unit = v3_normalize(sum);
    if (!v3_is_finite(unit) || !(v3_dot(unit, unit) > 0.0))
        return tr->normal;
    return unit;
}
