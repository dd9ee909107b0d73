/*
 * sample.c — SPD "sample" (Alexander Enzmann): a small demo scene of three
 * interlocking tori, a cone and a disc on a light grey background; one
 * light. NFF has no torus or disc, so SPD tessellates them: each torus into
 * 288 smooth triangles (12 x 12 quads, SPD's default resolution 3), the disc
 * into 16 flat triangles (resolution 4 x 1; the inner edge collapses).
 *
 * The size factor is ignored by SPD; it is fixed at 1 here.
 */
#include <math.h>
#include <string.h>

#include "spd/spd.h"

/* The inverse half of SPD's canonical matrix: it takes the local frame
 * (z = UP, origin at 0) to the world with its origin at ORIGIN. */
static void canonical_inverse(spd_mat itrans, const double origin[3], const double up[3])
{
    double axis[3];
    if (fabs(up[2]) == 1.0) {
        axis[0] = 1.0;
        axis[1] = 0.0;
        axis[2] = 0.0;
    } else {
        axis[0] = -up[1];
        axis[1] = up[0];
        axis[2] = 0.0;
    }
    spd_normalize(axis);
    spd_mat rot, move;
    spd_mat_axis_rotate(rot, axis, acos(up[2]));
    spd_mat_translate(move, origin);
    spd_mat_mul(itrans, rot, move);
}

/* Point and unit normal of the torus (radii R0, R1) at angles THETA (around
 * the tube) and PHI (around the axis), taken to the world by M. */
static void torus_point(spd_mat m, double theta, double phi, double r0, double r1,
                        double vert[3], double norm[3])
{
    double ring = r0 + r1 * sin(theta);
    double p[3] = {ring * cos(phi), ring * sin(phi), r1 * cos(theta)};
    double dtheta[3] = {r1 * cos(theta) * cos(phi), r1 * cos(theta) * sin(phi),
                        -r1 * sin(theta)};
    double dphi[3] = {-(r0 + r1 * sin(theta)) * sin(phi), (r0 + r1 * sin(theta)) * cos(phi),
                      0.0};
    double n[3];
    spd_cross(n, dtheta, dphi);
    spd_normalize(n);
    spd_xform_point(vert, p, m);
    spd_xform_vector(norm, n, m);
}

/* SPD's polygonal torus at resolution RES (4 RES x 4 RES quads, each as two
 * patch triangles). Angles advance by accumulation, as in SPD. */
static void torus(spd_sink *out, const double center[3], double normal[3], double r0,
                  double r1, int res)
{
    if (spd_normalize(normal) < SPD_EPSILON2)
        return;
    spd_mat m;
    canonical_inverse(m, center, normal);
    int steps = 4 * res;
    double du = 2.0 * SPD_PI / (double)steps, dv = 2.0 * SPD_PI / (double)steps;
    double u = 0.0;
    for (int i = 0; i < steps; i++, u += du) {
        double v = 0.0;
        for (int j = 0; j < steps; j++, v += dv) {
            double vert[3][3], norm[3][3];
            torus_point(m, u, v, r0, r1, vert[2], norm[2]);
            torus_point(m, u, v + dv, r0, r1, vert[1], norm[1]);
            torus_point(m, u + du, v + dv, r0, r1, vert[0], norm[0]);
            spd_polypatch(out, 3, vert, norm);
            memcpy(vert[1], vert[0], sizeof vert[0]);
            memcpy(norm[1], norm[0], sizeof norm[0]);
            torus_point(m, u + du, v, r0, r1, vert[0], norm[0]);
            spd_polypatch(out, 3, vert, norm);
        }
    }
}

static void disc_point(spd_mat m, double theta, double v, double r, double vert[3])
{
    double p[3] = {(r + v) * cos(theta), (r + v) * sin(theta), 0.0};
    spd_xform_point(vert, p, m);
}

/* SPD's polygonal disc (radii IR to OR) at resolution RES: 4 RES quads. */
static void disc(spd_sink *out, const double center[3], const double normal[3], double ir,
                 double or_, int res)
{
    double n[3] = {normal[0], normal[1], normal[2]};
    if (spd_normalize(n) < SPD_EPSILON2)
        return;
    spd_mat m;
    canonical_inverse(m, center, n);
    int steps = 4 * res;
    double du = 2.0 * SPD_PI / (double)steps, dv = or_ - ir;
    double u = 0.0;
    for (int i = 0; i < steps; i++, u += du) {
        double vert[4][3];
        disc_point(m, u, 0.0, ir, vert[3]);
        disc_point(m, u + du, 0.0, ir, vert[2]);
        disc_point(m, u + du, 0.0 + dv, ir, vert[1]);
        disc_point(m, u, 0.0 + dv, ir, vert[0]);
        spd_polygon(out, 4, vert);
    }
}

void spd_gen_sample(int size, spd_sink *out)
{
    (void)size;
    const double from[3] = {0, 5, -5}, at[3] = {0, 0, 0}, up[3] = {0, 1, 0};
    const double light[3] = {-10, 20, -20};
    /* SPD's names for the last two colours are swapped; the values count */
    const double red[3] = {1.0, 0.0, 0.0}, cyan[3] = {0.0, 1.0, 1.0};
    const double magenta_ish[3] = {1.0, 1.0, 0.0}, yellow_ish[3] = {1.0, 0.0, 1.0};
    const int torus_res = 3; /* SPD's default tessellation resolution */

    spd_background(out, 0.8, 0.8, 0.8);
    spd_view(out, from, at, up, 45.0, 0.001, 512, 512);
    spd_light(out, light);

    const double *torus_rgb[3] = {cyan, magenta_ish, yellow_ish};
    const double centers[3][3] = {{-1, 0, 0}, {0, 0, 0}, {1, 0, 0}};
    double normals[3][3] = {{1, 1, -0.5}, {0, 1, -0.5}, {-1, 1, -0.5}};
    for (int k = 0; k < 3; k++) {
        spd_color(out, torus_rgb[k], 0.1, 0.7, 0.0, 0.7, 10.0, 0.0, 1.0);
        torus(out, centers[k], normals[k], 2.0, 0.5, torus_res);
    }

    spd_color(out, red, 0.1, 0.7, 0.0, 0.7, 10.0, 0.0, 1.0);
    const double base[4] = {0, -2, 0, 2}, apex[4] = {0, 2, 0, 0.1};
    spd_cylcone(out, base, apex);

    spd_color(out, red, 0.1, 0.7, 0.0, 0.7, 10.0, 0.0, 1.0);
    const double dc[3] = {0, -2, 0}, dn[3] = {0, 1, 0};
    disc(out, dc, dn, 0.0, 4.0, 4);
}
