/*
 * sombrero.c — SPD "sombrero" (Alexander Enzmann): a height field of the
 * damped radial wave 3 cos(2 pi r) exp(-r) / 3 over [-4, 4]^2, output as flat
 * triangles (two per grid cell); one light, one shiny red material.
 *
 * Size factor SF: a grid of N = 32 * 2^(SF-1) samples per side, giving
 * 2 (N-1)^2 triangles (SF 1, the default, gives 1922). Heights are stored
 * as float, as SPD does, so the numbers match its output.
 */
#include <math.h>
#include <stdlib.h>

#include "spd/spd.h"

/* The N x N height samples (row i: y, column j: x), or NULL when out of
 * memory. X and y advance by accumulation, as in SPD. */
static float *sample_heights(unsigned n, double x0, double x1, double y0, double y1)
{
    float *h = malloc((size_t)n * n * sizeof *h);
    if (!h)
        return NULL;
    const double two_pi_a = 2.0 * 3.14159265358 * 1.0; /* SPD's constants a = b = 1, c = 3 */
    double dx = (x1 - x0) / (double)n, dy = (y1 - y0) / (double)n;
    double y = y0;
    for (unsigned i = 0; i < n; i++, y += dy) {
        double x = x0;
        for (unsigned j = 0; j < n; j++, x += dx)
            h[(size_t)i * n + j] = (float)(3.0 * cos(two_pi_a * sqrt(x * x + y * y)) *
                                           exp(-1.0 * sqrt(x * x + y * y)) / 3.0);
    }
    return h;
}

void spd_gen_sombrero(int size, spd_sink *out)
{
    const double from[3] = {0, 5, -8}, at[3] = {0, 0, 0}, up[3] = {0, 0, 1};
    const double light[3] = {10, 10, -10};
    const double red[3] = {1, 0.1, 0.1};

    spd_background(out, 0.078, 0.361, 0.753);
    spd_view(out, from, at, up, 40.0, 0.01, 512, 512);
    spd_light(out, light);
    spd_color(out, red, 0.1, 0.8, 0.0, 0.5, 40.0, 0.0, 1.0);

    if (spd_failed(out))
        return;
    unsigned n = 32u * (1u << (size - 1));
    float *h = sample_heights(n, -4.0, 4.0, -4.0, 4.0);
    if (!h) {
        spd_fail(out, BSP_ERR_NOMEM, "out of memory for the height field");
        return;
    }

    /* the field spans x, z in [-4, 4] with heights added to y = -3 */
    const double x0 = -4.0, x1 = 4.0, y0 = -3.0, z0 = -4.0, z1 = 4.0;
    double xd = (x1 - x0) / (double)(n - 1), zd = (z1 - z0) / (double)(n - 1);
    for (int i = 0; i < (int)n - 1 && !spd_failed(out); i++) {
        const float *row = h + (size_t)i * n, *next = row + n;
        for (int j = 0; j < (int)n - 1; j++) {
            double v[3][3] = {{x0 + j * xd, y0 + row[j], z0 + i * zd},
                              {x0 + (j + 1) * xd, y0 + next[j + 1], z0 + (i + 1) * zd},
                              {x0 + (j + 1) * xd, y0 + row[j + 1], z0 + i * zd}};
            spd_polygon(out, 3, v);
            /* the second triangle reuses the far corner, as SPD does */
            for (int a = 0; a < 3; a++)
                v[2][a] = v[1][a];
            v[1][0] = x0 + j * xd;
            v[1][1] = y0 + next[j];
            v[1][2] = z0 + (i + 1) * zd;
            spd_polygon(out, 3, v);
        }
    }
    free(h);
}
