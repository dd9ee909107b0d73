/*
 * gears.c — SPD "gears": a cubic grid of intermeshing 36-tooth gears over a
 * reflective ground square; some gears are transmissive. Each gear is a
 * concave 144-gon top and bottom (its first three vertices form a convex
 * corner) and 144 side rectangles; five lights.
 *
 * Size factor SF = gears per grid edge: SF^3 gears, that is 2 SF^3 concave
 * 144-gons and 144 SF^3 rectangles, plus the ground (SF 4, the default,
 * gives 64 gears).
 */
#include <math.h>

#include "spd/spd.h"

#define TEETH 36
#define OUTER_EDGE_RATIO 0.995
#define INNER_EDGE_RATIO 0.9
#define EDGE_DIFF (1.0 - INNER_EDGE_RATIO)
#define DEPTH_RATIO 0.1 /* gear thickness / width */

/* The four outline points of one tooth, rotated to GEAR_ANGLE. */
static void make_tooth(double gear_angle, double tooth_angle, const double center[3],
                       const double outer[3], const double inner[3], double pts[4][3])
{
    const double frac[4] = {-0.19, 0.19, 0.3, 0.7};
    for (int k = 0; k < 4; k++) {
        spd_mat m;
        /* a + (-0.19 t) equals a - 0.19 t exactly in IEEE arithmetic */
        spd_mat_rotate(m, 2, gear_angle + frac[k] * tooth_angle);
        spd_xform_vector(pts[k], k < 2 ? outer : inner, m);
        pts[k][0] += center[0];
        pts[k][1] += center[1];
        pts[k][2] += center[2];
    }
}

static void make_gear(spd_sink *out, const double center[3], double offset_angle,
                      double outer_radius, double inner_radius, double thickness)
{
    double outer[3] = {outer_radius, 0.0, 0.0}, inner[3] = {inner_radius, 0.0, 0.0};
    double pts[4 * TEETH][3];
    double tooth_angle = 2.0 * SPD_PI / (double)TEETH;

    /* top face */
    for (int t = 0; t < TEETH; t++) {
        double a = offset_angle + 2.0 * SPD_PI * (double)t / (double)TEETH;
        make_tooth(a, tooth_angle, center, outer, inner, &pts[t * 4]);
    }
    spd_polygon(out, 4 * TEETH, pts);

    /* sides: one rectangle down from each top edge */
    for (int k = 0; k < 4 * TEETH; k++) {
        int next = (k + 1) % (4 * TEETH);
        double side[4][3];
        for (int a = 0; a < 3; a++) {
            side[0][a] = side[1][a] = pts[k][a];
            side[2][a] = side[3][a] = pts[next][a];
        }
        side[1][2] -= thickness;
        side[2][2] -= thickness;
        spd_polygon(out, 4, side);
    }

    /* bottom face, wound the other way */
    outer[2] = inner[2] = -thickness;
    for (int t = 0; t < TEETH; t++) {
        double a = offset_angle - 2.0 * SPD_PI * (double)t / (double)TEETH;
        make_tooth(a, -tooth_angle, center, outer, inner, &pts[t * 4]);
    }
    spd_polygon(out, 4 * TEETH, pts);
}

static double fraction(double a)
{
    return a - (int)a;
}

void spd_gen_gears(int size, spd_sink *out)
{
    const double from[3] = {-1.1, -2.1, 2.6}, at[3] = {0.0, 0.0, 0.0}, up[3] = {0.0, 0.0, 1.0};
    const double lights[5][3] = {{2.0, 4.0, 4.0},
                                 {-2.0, 4.0, 3.0},
                                 {2.0, -2.5, 2.5},
                                 {-1.0, -4.0, 2.0},
                                 {-1.111, -2.121, 2.626}}; /* just behind the eye */
    const double ground_rgb[3] = {1.0, 0.85, 0.7};

    spd_background(out, 0.078, 0.361, 0.753);
    spd_view(out, from, at, up, 45.0, 1.0, 512, 512);
    for (int i = 0; i < 5; i++)
        spd_light(out, lights[i]);

    spd_color(out, ground_rgb, 0.0, 0.3, 0.6, 0.3, 37.0, 0.0, 0.0);
    double ground[4][3] = {{2.0, 2.0, 0.0}, {-2.0, 2.0, 0.0}, {-2.0, -2.0, 0.0}, {2.0, -2.0, 0.0}};
    spd_polygon(out, 4, ground);

    double outer_radius = 1.0 / ((double)size - (double)(size - 1) * EDGE_DIFF / 2.0);
    double zero[3], step[3];
    zero[0] = zero[1] = -1.0 + outer_radius;
    zero[2] = 1.0;
    step[0] = step[1] = outer_radius * (2.0 - EDGE_DIFF);
    step[2] = -1.0 / (double)size;

    for (int iz = 0; iz < size; iz++) {
        double center[3];
        center[2] = zero[2] + (double)iz * step[2];
        for (int iy = 0; iy < size && !spd_failed(out); iy++) {
            center[1] = zero[1] + (double)iy * step[1];
            for (int ix = 0; ix < size; ix++) {
                center[0] = zero[0] + (double)ix * step[0];
                /* pseudo-random colour, scaled so its largest component is 1 */
                double rgb[3];
                rgb[0] = 0.01 + fraction((double)(ix * 3 + iy * 2 + iz + 1) * 5.0 / 7.0);
                rgb[1] = 0.01 + fraction((double)(iy * 3 + iz * 2 + ix + 1) * 3.0 / 7.0);
                rgb[2] = 0.01 + fraction((double)(iz * 3 + ix * 2 + iy + 1) * 2.0 / 7.0);
                double cs = rgb[0] > rgb[1] ? rgb[0] : rgb[1];
                cs = cs > rgb[2] ? cs : rgb[2];
                rgb[0] /= cs;
                rgb[1] /= cs;
                rgb[2] /= cs;
                if ((ix * 4 + iy * 2 + iz) % 5 == 0)
                    spd_color(out, rgb, 0.0, 0.2, 0.0, 0.0, 0.0, 0.8, 1.1);
                else
                    spd_color(out, rgb, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0);

                double angle = SPD_PI * (double)((ix + iy + iz) % 2) / (double)TEETH;
                double thick = 1.0 / (2.0 * (double)size);
                if (DEPTH_RATIO < thick)
                    thick = DEPTH_RATIO;
                make_gear(out, center, angle, OUTER_EDGE_RATIO * outer_radius,
                          (1.0 - EDGE_DIFF) * outer_radius, thick);
            }
        }
    }
}
