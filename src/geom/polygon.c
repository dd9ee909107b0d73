/*
 * polygon.c — planar polygons of four or more vertices, convex or concave:
 * setup, exact bounds, ray intersection and the shading normal of patches.
 *
 * The plane is (normal, d) with the Newell normal and the mean offset of the
 * vertices. A hit is the plane crossing of the ray followed by an even-odd
 * crossing test of the hit point in the projection that drops the normal's
 * dominant axis (no triangulation, so concave polygons are exact). The
 * crossing rule is half-open: an edge counts when exactly one endpoint lies
 * strictly above the point, and the point must be strictly left of the
 * crossing. Each edge's crossing abscissa is computed from its lower endpoint,
 * so an edge shared by two coplanar polygons gives both the same abscissa
 * and a point on it belongs to exactly one of them. Where the point lies
 * within rounding of an edge, the crossing test on the ray's own shear
 * decides (watertight: geom/isect.h), so that two polygons that share an
 * edge but not a plane let no ray through between them. Rays parallel to
 * the plane miss. t never depends on ray->tmin/tmax.
 */
#include <math.h>

#include "geom/isect.h"
#include "geom/shapes.h"
#include "geom/vec.h"

/* A polygon whose vertices lie off its plane by more than this fraction of
 * its extent is not planar: its neighbours' surfaces (each on its own mean
 * plane) do not meet even in exact arithmetic, and no crossing test can
 * close that gap; it gets no watertight decision. */
#define POLYGON_PLANAR_REL 0x1p-30

/* polygon_shape.wt_base for the vertices VS (COUNT) on the plane
 * (N, D): 2^-40 R + 2^12 h, R the largest |v|_1 (the size of the rounding
 * of coordinates) and h the largest distance of a vertex from the plane;
 * -1 when h exceeds POLYGON_PLANAR_REL of the extent. */
static double polygon_wt_base(bsp_vec3 n, double d, const bsp_vec3 *vs, uint32_t count)
{
    double r = 0.0, h = 0.0, extent = 0.0;
    for (uint32_t i = 0; i < count; i++) {
        r = fmax(r, fabs(vs[i].x) + fabs(vs[i].y) + fabs(vs[i].z));
        h = fmax(h, fabs(v3_dot(n, vs[i]) - d));
        bsp_vec3 e = v3_sub(vs[i], vs[0]);
        extent = fmax(extent, fabs(e.x) + fabs(e.y) + fabs(e.z));
    }
    if (!(h <= POLYGON_PLANAR_REL * extent))
        return -1.0;
    return 0x1p-40 * r + 0x1p12 * h;
}

int polygon_setup(polygon_shape *p, const bsp_vec3 *verts, uint32_t first, uint32_t count,
                  uint32_t normals)
{
    if (count < 3)
        return 0;
    const bsp_vec3 *vs = verts + first;
    bsp_vec3 o = vs[0], n = bsp_v3(0.0, 0.0, 0.0);
    for (uint32_t i = 0; i < count; i++) {
        bsp_vec3 a = v3_sub(vs[i], o);
        bsp_vec3 b = v3_sub(vs[i + 1 < count ? i + 1 : 0], o);
        n.x += (a.y - b.y) * (a.z + b.z);
        n.y += (a.z - b.z) * (a.x + b.x);
        n.z += (a.x - b.x) * (a.y + b.y);
    }
    double len = v3_length(n);
    if (!(len > 0.0) || !isfinite(len))
        return 0;
    n = bsp_v3(n.x / len, n.y / len, n.z / len);
    if (!v3_is_finite(n))
        return 0;

    double sum = 0.0;
    for (uint32_t i = 0; i < count; i++)
        sum += v3_dot(n, vs[i]);

    double ax = fabs(n.x), ay = fabs(n.y), az = fabs(n.z);
    int drop = ax >= ay ? (ax >= az ? 0 : 2) : (ay >= az ? 1 : 2);
    p->normal = n;
    p->d = sum / (double)count;
    p->first = first;
    p->count = count;
    p->normals = normals;
    p->axis_u = (uint8_t)((drop + 1) % 3);
    p->axis_v = (uint8_t)((drop + 2) % 3);
    p->slab_first = 0;
    p->nslabs = 0;
    p->wt_base = polygon_wt_base(n, p->d, vs, count);
    return 1;
}

/* Hits lie on the mean plane, inside the polygon's projection
 * (polygon_plane_vertex). The bounds cover both the vertices and their
 * projections onto the plane along the dropped axis, which is where every
 * hit point can be. */
bsp_box polygon_bounds(const polygon_shape *p, const bsp_vec3 *verts)
{
    bsp_box box = box_empty();
    for (uint32_t i = 0; i < p->count; i++) {
        bsp_vec3 v = verts[p->first + i];
        box = box_add_point(box, v);
        box = box_add_point(box, polygon_plane_vertex(p, v));
    }
    return box;
}

int polygon_intersect(const polygon_shape *p, const bsp_vec3 *verts,
                      const polygon_slab_pool *slabs, const bsp_ray *ray, double *t)
{
    isect_ray r;
    isect_ray_init(&r, ray, INFINITY, NULL); /* no hit check: it needs the scene scale */
    return polygon_isect(p, verts, slabs, &r, ray->tmax, t);
}

/* The normalised pool normal, or FALLBACK when it has no direction. */
static bsp_vec3 unit_or(bsp_vec3 n, bsp_vec3 fallback)
{
    bsp_vec3 u = v3_normalize(n);
    return v3_is_finite(u) && v3_dot(u, u) > 0.0 ? u : fallback;
}

/* tan(a/2) for the signed angle a between two vectors of lengths R and NR,
 * their cross and dot products DET and DOT: sin a / (1 + cos a) while the
 * angle is at most a right one, (1 - cos a) / sin a beyond. The first form
 * alone divides, near an edge (a close to pi), by r nr + dot, which cancels
 * to nothing: it rounded to 0 within about 5e-9 of the edge of a unit square,
 * and the normal there fell back to the flat one. Not finite only where the
 * point lies on the edge to rounding (det 0 or tiny, dot < 0). */
static double half_angle_tan(double det, double dot, double r, double nr)
{
    return dot >= 0.0 ? det / (r * nr + dot) : (r * nr - dot) / det;
}

/* The normal on the edge from vertex I (normal NI, at distance RI) to vertex
 * J (NJ, RJ): the linear blend of its ends, the coordinates' limit there. */
static bsp_vec3 edge_normal(bsp_vec3 ni, double ri, bsp_vec3 nj, double rj, bsp_vec3 fallback)
{
    return unit_or(v3_add(v3_scale(ni, rj), v3_scale(nj, ri)), fallback);
}

/*
 * Mean value coordinates (Floater; Hormann & Floater's signed-angle form for
 * arbitrary polygons): w_i = (tan(a_{i-1}/2) + tan(a_i/2)) / r_i, where r_i is
 * the distance to vertex i and a_i the signed angle subtended by edge
 * (i, i+1) (half_angle_tan). On a vertex the result is that vertex's normal;
 * on an edge, or within rounding of one, it is the linear blend of its
 * endpoints (the limit of the coordinates there).
 */
bsp_vec3 polygon_shading_normal(const polygon_shape *p, const bsp_vec3 *verts,
                                const bsp_vec3 *normal_pool, bsp_vec3 p_hit)
{
    if (p->normals == SHAPE_NO_NORMALS)
        return p->normal;
    const bsp_vec3 *vs = verts + p->first;
    const bsp_vec3 *ns = normal_pool + p->normals;
    int au = p->axis_u, av = p->axis_v;
    uint32_t n = p->count;
    double px = p_hit.v[au], py = p_hit.v[av];

    double lx = vs[n - 1].v[au] - px, ly = vs[n - 1].v[av] - py;
    double sx = vs[0].v[au] - px, sy = vs[0].v[av] - py;
    double lr = hypot(lx, ly), r = hypot(sx, sy);
    double tan_prev = half_angle_tan(lx * sy - ly * sx, lx * sx + ly * sy, lr, r);
    /* on the edge (n-1, 0), or on vertex n-1 (the blend is then its normal);
     * on vertex 0 the loop's first step answers */
    if (r != 0.0 && !isfinite(tan_prev))
        return edge_normal(ns[n - 1], lr, ns[0], r, p->normal);

    bsp_vec3 acc = bsp_v3(0.0, 0.0, 0.0);
    double wsum = 0.0;
    for (uint32_t i = 0; i < n; i++) {
        uint32_t j = i + 1 < n ? i + 1 : 0;
        double nx = vs[j].v[au] - px, ny = vs[j].v[av] - py;
        double nr = hypot(nx, ny);
        if (r == 0.0)
            return unit_or(ns[i], p->normal);
        double tan_i = half_angle_tan(sx * ny - sy * nx, sx * nx + sy * ny, r, nr);
        if (!isfinite(tan_i)) /* on the edge (i, j), or on vertex j */
            return edge_normal(ns[i], r, ns[j], nr, p->normal);
        double w = (tan_prev + tan_i) / r;
        acc = v3_madd(acc, ns[i], w);
        wsum += w;
        tan_prev = tan_i;
        sx = nx;
        sy = ny;
        r = nr;
    }
    bsp_vec3 mean = v3_scale(acc, 1.0 / wsum);
    return unit_or(mean, p->normal);
}
