/*
 * rings.c — SPD "rings": objects made of six pentagonal rings (cylinders
 * joined by spheres) through the edge midpoints of a dodecahedron, stacked
 * in a pyramid that the viewer looks at from its tip, with a white wall
 * behind it for shadows; three lights.
 *
 * Size factor SF = number of pyramid layers; layer k (1-based) holds k^2
 * objects of 30 cylinders and 30 spheres: 5 SF (SF+1) (2 SF+1) of each,
 * plus the wall (SF 7, the default, gives 4200 of each).
 */
#include <math.h>

#include "spd/spd.h"

/* The 30 ring vertices: one pentagon in the XY plane, five copies tilted by
 * the dihedral angle and turned about Z. */
static void make_dodec(double minor_radius, double v[30][3])
{
    double scale = 1.0 / (1.0 + minor_radius);
    for (int k = 0; k < 5; k++) {
        v[k][0] = scale * cos((double)k * 2.0 * SPD_PI / 5.0);
        v[k][1] = scale * sin((double)k * 2.0 * SPD_PI / 5.0);
        v[k][2] = 0.0;
    }
    spd_mat mx, mz;
    spd_mat_rotate(mx, 0, 2.0 * acos(cos(SPD_PI / 3.0) / sin(SPD_PI / 5.0)));
    for (int p = 1; p < 6; p++) {
        spd_mat_rotate(mz, 2, SPD_PI * (2.0 * (double)(p - 1) + 1.0) / 5.0);
        for (int k = 0; k < 5; k++) {
            double t[3];
            spd_xform_point(t, v[k], mx);
            spd_xform_point(v[5 * p + k], t, mz);
        }
    }
}

void spd_gen_rings(int size, spd_sink *out)
{
    const double radius = 0.07412; /* cylinder and sphere radius */
    const double white[3] = {1.0, 1.0, 1.0};
    const double ring_rgb[6][3] = {{1.0, 0.0, 0.0}, {0.0, 1.0, 0.0}, {0.0, 0.0, 1.0},
                                   {0.0, 1.0, 1.0}, {1.0, 0.0, 1.0}, {1.0, 1.0, 0.0}};

    /* layer spacing (SPD's SPREAD_OUT is 1, so only y spreads) */
    double spread = 1 / sin(SPD_PI / 8.0);
    double y_diff, xz_diff;
    if (1 <= spread) {
        y_diff = spread / 1;
        xz_diff = 1.0;
    } else {
        y_diff = 1.0;
        xz_diff = 1 / spread;
    }

    double from[3] = {-1.0, -spread, 0.5};
    double at[3] = {from[0], from[1] + 1.0, from[2]};
    const double up[3] = {0.0, 0.0, 1.0};
    spd_background(out, 0.078, 0.361, 0.753);
    spd_view(out, from, at, up, 45.0, 1.0, 512, 512);
    const double lights[3][3] = {{3.0, -spread, 3.0}, {-4.0, -spread, 1.0}, {2.0, -spread, -4.0}};
    for (int i = 0; i < 3; i++)
        spd_light(out, lights[i]);

    /* the wall just spans the 45 degree view, plus 1% */
    spd_color(out, white, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    double wy = y_diff * (size + 1);
    double wx = 1.01 * (wy - from[1]) * tan(SPD_PI / 8.0), wz = wx;
    double wall[4][3] = {{wx + from[0], wy, wz + from[2]},
                         {-wx + from[0], wy, wz + from[2]},
                         {-wx + from[0], wy, -wz + from[2]},
                         {wx + from[0], wy, -wz + from[2]}};
    spd_polygon(out, 4, wall);

    double dodec[30][3];
    make_dodec(radius, dodec);
    for (int layer = 0; layer < size && !spd_failed(out); layer++) {
        double off[3];
        off[1] = y_diff * (double)(layer + 1);
        for (int iz = 0; iz <= layer; iz++) {
            off[2] = xz_diff * (double)(2 * iz - layer);
            for (int ix = 0; ix <= layer; ix++) {
                off[0] = xz_diff * (double)(2 * ix - layer);
                for (int e = 0; e < 30; e++) {
                    int prev;
                    if (e % 5 == 0) {
                        prev = e + 4;
                        spd_color(out, ring_rgb[e / 5], 0.0, 0.5, 0.2, 0.3, 37.0, 0.0, 0.0);
                    } else {
                        prev = e - 1;
                    }
                    double base[4], apex[4];
                    for (int a = 0; a < 3; a++) {
                        base[a] = dodec[e][a] + off[a];
                        apex[a] = dodec[prev][a] + off[a];
                    }
                    base[3] = apex[3] = radius;
                    spd_cylcone(out, base, apex);
                    spd_sphere(out, base);
                }
            }
        }
    }
}
