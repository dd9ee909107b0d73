/*
 * lattice.c — SPD "lattice" (Antonio Costa): a cubic lattice of shiny
 * spheres in the unit cube, each joined to its +x, +y and +z neighbours by a
 * matte red, green or blue open cylinder; six lights. As in SPD, an `f`
 * record precedes every primitive.
 *
 * Size factor SF = cells per cube edge: (SF+1)^3 spheres and 3 SF (SF+1)^2
 * cylinders (SF 12, the default, gives 2197 spheres and 6084 cylinders).
 * The view shifts slightly with SF.
 */
#include <math.h>

#include "spd/spd.h"

#define RADIUS1 (1.0 / 4.0)  /* sphere radius times SF */
#define RADIUS2 (1.0 / 16.0) /* cylinder radius times SF */

void spd_gen_lattice(int size, spd_sink *out)
{
    const double inv = 1.0 / (double)size;
    const double r1 = (double)RADIUS1 / (double)size, r2 = (double)RADIUS2 / (double)size;
    /* cylinders stop just inside the spheres */
    const double delta = (r1 * (1.0 - sqrt((double)RADIUS2 / (double)RADIUS1))) * 0.99;
    const double white[3] = {0.9, 0.9, 0.9};
    const double axis_rgb[3][3] = {{0.9, 0.1, 0.1}, {0.1, 0.9, 0.1}, {0.1, 0.1, 0.9}};
    const double lights[6][3] = {{2.0, 0.5, 0.5}, {-1.0, 0.5, 0.5}, {0.5, 2.0, 0.5},
                                 {0.5, -1.0, 0.5}, {0.5, 0.5, 2.0}, {0.5, 0.5, -1.0}};

    double from[3] = {((double)(size >> 1) + 0.5) * inv, 1.0, 1.0 - 1.0 / (double)(size << 1)};
    double at[3] = {((double)(size >> 1) + 0.5) * inv, -1.0, -1.0 - 1.0 / (double)(size << 1)};
    const double up[3] = {0.2, 1.0, 0.0};

    spd_background(out, 0.078, 0.361, 0.753);
    spd_view(out, from, at, up, 60.0, 0.0, 512, 512);
    for (int i = 0; i < 6; i++)
        spd_light(out, lights[i]);

    for (long x = 0; x <= size; x++) {
        double p[3];
        p[0] = (double)x / (double)size;
        for (long y = 0; y <= size && !spd_failed(out); y++) {
            p[1] = (double)y / (double)size;
            for (long z = 0; z <= size; z++) {
                p[2] = (double)z / (double)size;
                spd_color(out, white, 0.0, 0.5, 0.5, 0.5, 37.0, 0.0, 0.0);
                double sphere[4] = {p[0], p[1], p[2], r1};
                spd_sphere(out, sphere);

                const long idx[3] = {x, y, z};
                for (int a = 0; a < 3; a++) {
                    if (idx[a] == size)
                        continue;
                    spd_color(out, axis_rgb[a], 0.1, 0.99, 0.0, 0.0, 0.0, 0.0, 0.0);
                    double b[4] = {p[0], p[1], p[2], r2}, e[4] = {p[0], p[1], p[2], r2};
                    b[a] = p[a] + delta;
                    e[a] = p[a] + inv - delta;
                    spd_cylcone(out, b, e);
                }
            }
        }
    }
}
