/*
 * tetra.c — SPD "tetra": a recursive tetrahedral pyramid (Sierpinski
 * tetrahedron) after the test scene of Glassner and of Kay & Kajiya; one
 * light, one matte red material.
 *
 * Size factor SF = recursion depth: 4^SF triangles (SF 6, the default,
 * gives 4096). A tetrahedron is four alternate corners of a cube; each level
 * replaces it by four half-size ones in the same corners.
 */
#include "spd/spd.h"

/* Writes the four faces of the tetrahedron in the cube CENTER (x, y, z,
 * half side). */
static void emit_tetra(spd_sink *out, const double c[4])
{
    double corner[4][3];
    int n = 0;
    for (int dx = -1; dx <= 1; dx += 2)
        for (int dy = -1; dy <= 1; dy += 2)
            for (int dz = -1; dz <= 1; dz += 2)
                if (dx * dy * dz == 1) {
                    corner[n][0] = c[0] + (double)dx * c[3];
                    corner[n][1] = c[1] + (double)dy * c[3];
                    corner[n][2] = c[2] + (double)dz * c[3];
                    n++;
                }
    /* face k uses corners k, k+1, k+2 (mod 4), reversed for odd k */
    for (int face = 0; face < 4; face++) {
        int order[3];
        for (int k = 0; k < 3; k++)
            order[k] = (face + k) % 4;
        if (face % 2 == 1) {
            int t = order[0];
            order[0] = order[2];
            order[2] = t;
        }
        double tri[3][3];
        for (int k = 0; k < 3; k++)
            for (int a = 0; a < 3; a++)
                tri[k][a] = corner[order[k]][a];
        spd_polygon(out, 3, tri);
    }
}

static void subdivide(spd_sink *out, int depth, const double c[4])
{
    if (spd_failed(out))
        return;
    if (depth <= 1) {
        emit_tetra(out, c);
        return;
    }
    for (int dx = -1; dx <= 1; dx += 2)
        for (int dy = -1; dy <= 1; dy += 2)
            for (int dz = -1; dz <= 1; dz += 2)
                if (dx * dy * dz == 1) {
                    double sub[4];
                    sub[0] = c[0] + (double)dx * c[3] / 2.0;
                    sub[1] = c[1] + (double)dy * c[3] / 2.0;
                    sub[2] = c[2] + (double)dz * c[3] / 2.0;
                    sub[3] = c[3] / 2.0;
                    subdivide(out, depth - 1, sub);
                }
}

void spd_gen_tetra(int size, spd_sink *out)
{
    const double from[3] = {1.022846, -3.177154, -2.174512};
    const double at[3] = {-0.004103, -0.004103, 0.216539};
    const double up[3] = {-0.816497, -0.816497, 0.816497};
    const double light[3] = {2.0, -18.0, -5.0};
    const double red[3] = {1.0, 0.2, 0.2};
    const double center[4] = {0.0, 0.0, 0.0, 1.0};

    spd_background(out, 0.078, 0.361, 0.753);
    spd_view(out, from, at, up, 45.0, 1.0, 512, 512);
    spd_light(out, light);
    spd_color(out, red, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    subdivide(out, size, center);
}
