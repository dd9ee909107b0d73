/*
 * cone.c — the open truncated cone or cylinder (NFF "c", no caps): setup,
 * exact bounds, ray intersection and the lateral normal.
 *
 * In the axis frame a point at axial coordinate h (0 at the base, length at
 * the apex) and perpendicular offset p lies on the surface when
 * |p| = r(h) = base_radius + slope * h with 0 <= h <= length. Squaring gives
 * a quadratic in t that also describes the mirrored nappe (r(h) < 0) and the
 * infinite extension; roots outside [0, length] or with r(h) < 0 are dropped.
 * A vanishing leading coefficient (ray parallel to a cylinder's axis or to a
 * cone's generator) leaves a linear equation, or none: such a ray hits at most
 * once and a ray lying on the surface misses. t never depends on
 * ray->tmin/tmax.
 */
#include <math.h>

#include "geom/isect.h"
#include "geom/shapes.h"
#include "geom/vec.h"

int cone_setup(cone_shape *c, bsp_vec3 base, double base_radius, bsp_vec3 apex,
               double apex_radius)
{
    bsp_vec3 axis = v3_sub(apex, base);
    double len = v3_length(axis);
    double r0 = fabs(base_radius), r1 = fabs(apex_radius);
    if (!(len > 0.0) || !isfinite(len) || (r0 == 0.0 && r1 == 0.0))
        return 0;
    double slope = (r1 - r0) / len;
    bsp_vec3 unit = bsp_v3(axis.x / len, axis.y / len, axis.z / len);
    if (!isfinite(slope) || !v3_is_finite(unit))
        return 0;
    c->base = base;
    c->axis = unit;
    c->length = len;
    c->base_radius = r0;
    c->apex_radius = r1;
    c->slope = slope;
    double rmax = r0 > r1 ? r0 : r1;
    c->far2 = CONE_NEAR_SIZES * CONE_NEAR_SIZES * (len * len + rmax * rmax);
    c->inside_only = base_radius < 0.0 || apex_radius < 0.0;
    return 1;
}

bsp_box cone_disc_bounds(bsp_vec3 center, double r, bsp_vec3 a)
{
    bsp_box b;
    for (int k = 0; k < 3; k++) {
        double ai = a.v[(k + 1) % 3], aj = a.v[(k + 2) % 3];
        double s = sqrt(ai * ai + aj * aj); /* sqrt(1 - a_k^2) without cancellation */
        double e = r * (s < 1.0 ? s : 1.0);
        b.lo.v[k] = center.v[k] - e;
        b.hi.v[k] = center.v[k] + e;
    }
    return b;
}

bsp_box cone_bounds(const cone_shape *c)
{
    bsp_vec3 apex = v3_madd(c->base, c->axis, c->length);
    return box_union(cone_disc_bounds(c->base, c->base_radius, c->axis),
                     cone_disc_bounds(apex, c->apex_radius, c->axis));
}

int cone_intersect(const cone_shape *c, const bsp_ray *ray, double *t)
{
    isect_ray r;
    isect_ray_init(&r, ray, INFINITY, NULL); /* no hit check: it needs the scene scale */
    return cone_isect(c, &r, ray->tmax, t);
}

/* The gradient of |p| - r(h): the radial direction tilted by -slope along the
 * axis. At a point on the axis (a cone's tip) it degenerates to -slope * axis;
 * a cylinder has no surface point there and gets the axis. */
bsp_vec3 cone_normal(const cone_shape *c, bsp_vec3 p)
{
    bsp_vec3 oc = v3_sub(p, c->base);
    bsp_vec3 radial = v3_normalize(v3_madd(oc, c->axis, -v3_dot(oc, c->axis)));
    bsp_vec3 n = v3_normalize(v3_madd(radial, c->axis, -c->slope));
    return v3_dot(n, n) > 0.0 ? n : c->axis;
}
