/*
 * sphere.c — the sphere: setup, exact bounds, ray intersection and normal.
 *
 * The ray equation |oc + t dir|^2 = r^2 (oc = org - center) is solved in the
 * half-b form a t^2 + 2 b t + c = 0. Two precautions keep the roots accurate:
 * the discriminant b^2 - a c is evaluated as a (r^2 - |l|^2), where l is the
 * offset from the centre to the closest point of the ray's line (no
 * cancellation between two large squares when the origin is far away), and the
 * roots are q / a and c / q with q = -(b + sign(b) sqrt(disc)), so neither is
 * a difference of nearly equal numbers. t never depends on ray->tmin/tmax.
 */
#include <math.h>

#include "geom/isect.h"
#include "geom/shapes.h"
#include "geom/vec.h"

int sphere_setup(sphere_shape *s, bsp_vec3 center, double radius)
{
    double r = fabs(radius);
    double r2 = r * r;
    if (!(r2 > 0.0) || !isfinite(r2))
        return 0;
    s->center = center;
    s->radius = r;
    s->radius2 = r2;
    s->inside_only = radius < 0.0;
    return 1;
}

bsp_box sphere_bounds(const sphere_shape *s)
{
    bsp_box b;
    for (int k = 0; k < 3; k++) {
        b.lo.v[k] = s->center.v[k] - s->radius;
        b.hi.v[k] = s->center.v[k] + s->radius;
    }
    return b;
}

int sphere_intersect(const sphere_shape *s, const bsp_ray *ray, double *t)
{
    isect_ray r;
    isect_ray_init(&r, ray, INFINITY, NULL); /* no hit check: it needs the scene scale */
    return sphere_isect(s, &r, ray->tmax, t);
}

bsp_vec3 sphere_normal(const sphere_shape *s, bsp_vec3 p)
{
    return v3_normalize(v3_sub(p, s->center));
}
