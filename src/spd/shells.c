/*
 * shells.c — SPD "shells": a sea shell grown with Pickover's method (IEEE
 * CG&A, November 1989) as a logarithmic spiral of heavily overlapping
 * spheres, many of them tiny — a realistic yet pathological test; one light.
 * Uses SPD's default shape parameters (gamma 1, alpha 0, beta -2, a 0.15).
 *
 * Size factor SF: 180 * 2^SF + 1 spheres (SF 5, the default, gives 5761; the
 * SPD header's "5760 spheres + 1 square" is off: there is no square).
 */
#include <math.h>

#include "spd/spd.h"

void spd_gen_shells(int size, spd_sink *out)
{
    const double gamma_ = 1.0, alpha = 0.0, beta = -2.0, a = 0.15, k = 1.0;
    const double from[3] = {-6.0, -60.0, 35.0}, at[3] = {0.0, 8.0, -15.0};
    const double up[3] = {0.0, 0.0, 1.0}, light[3] = {-100.0, -100.0, 100.0};
    const double rgb[3] = {1.0, 0.8, 0.4};

    spd_background(out, 0.078, 0.361, 0.753);
    spd_view(out, from, at, up, 45.0, 0.5, 512, 512);
    spd_light(out, light);
    spd_color(out, rgb, 0.0, 0.8, 0.2, 0.5, 10.0, 0.0, 1.0);

    long steps = (long)(180.0 * pow(2.0, (double)size));
    for (long i = -steps * 2 / 3; i <= steps / 3 && !spd_failed(out); ++i) {
        double angle = 3.0 * 6.0 * SPD_PI * (double)i / (double)steps;
        double r = k * exp(a * angle);
        double s[4];
        s[0] = r * sin(angle);
        s[1] = r * cos(angle);
        s[2] = alpha > 0.0 ? alpha * angle : beta * r;
        s[3] = r / gamma_;
        spd_sphere(out, s);
    }
}
