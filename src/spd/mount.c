/*
 * mount.c — SPD "mount": a fractal mountain made by Carpenter's midpoint
 * subdivision on a square grid, with a pyramid of four glass spheres in
 * front of it; one light. It keeps SPD's original (repetitive) 1987 hash so
 * the mountain is the one of the IEEE CG&A article and of the reference data.
 *
 * Size factor SF = subdivision depth: 2 * 4^SF triangles plus 4 spheres (SF
 * 6, the default, gives 8192 triangles). The hash shifts by 7 - SF bits, so
 * SF is limited to 7: above that SPD's own result is undefined behaviour.
 */
#include <math.h>

#include "spd/spd.h"

#define FRACTAL_DIMENSION 2.2 /* between 2 and 3: sets the variance of z */
#define MOUNTAIN_NO 21        /* seed offset: another value, another mountain */
#define X_CORNER -1.0
#define Y_CORNER -1.0
#define WIDTH 2.0

typedef struct mountain {
    spd_sink *out;
    int size;
    double fnum;      /* grid points per side, as a double */
    double roughness; /* rise of a midpoint per unit of half side length */
} mountain;

/* The original hash: the seed of a grid point (A, B) at size factor C. */
static long old_hash(int a, int b, int c)
{
    unsigned long ua = (unsigned long)a, ub = (unsigned long)b;
    return (long)(((ua << (23 - c)) + (ub << (15 - c)) + (ua << (7 - c))) & 0xffff);
}

/* A normally distributed deviate determined by SEED (polar Box-Muller on a
 * small linear congruential generator, as SPD's lib_gauss_rand). */
static double gauss_rand(long seed)
{
    const long m = 134456, ia = 8121, ic = 28411;
    long x1, x2 = seed;
    double v1, v2, r;
    do {
        x1 = (ic + x2 * ia) % m;
        x2 = (ic + x1 * ia) % m;
        v1 = (double)x1 * 2.0 * 1.0 / (double)m - 1.0;
        v2 = (double)x2 * 2.0 * 1.0 / (double)m - 1.0;
        r = v1 * v1 + v2 * v2;
    } while (r >= 1.0);
    return v1 * sqrt(-2.0 * log(r) / r);
}

static double rise(const mountain *mt, int x, int y)
{
    return gauss_rand(MOUNTAIN_NO + old_hash(x, y, mt->size));
}

/* A square of WIDTH grid cells with lower left corner (X, Y) and corner
 * heights lower-left, lower-right, upper-right, upper-left. */
static void grow(const mountain *mt, int width, int x, int y, double ll, double lr,
                 double ur, double ul)
{
    if (spd_failed(mt->out))
        return;
    if (width == 1) {
        double lx = X_CORNER + (double)x * WIDTH / mt->fnum;
        double rx = X_CORNER + (double)(x + 1) * WIDTH / mt->fnum;
        double ly = Y_CORNER + (double)y * WIDTH / mt->fnum;
        double uy = Y_CORNER + (double)(y + 1) * WIDTH / mt->fnum;
        double corner[4][3] = {{lx, ly, ll}, {rx, ly, lr}, {rx, uy, ur}, {lx, uy, ul}};
        /* corners 0 1 2, then 2 3 0 */
        for (int tri = 0; tri < 2; tri++) {
            double v[3][3];
            for (int k = 0; k < 3; k++)
                for (int a = 0; a < 3; a++)
                    v[k][a] = corner[(k + tri * 2) % 4][a];
            spd_polygon(mt->out, 3, v);
        }
        return;
    }
    int half = width >> 1;
    double hside = (double)half * WIDTH / mt->fnum;
    double h = hside * mt->roughness;
    double lower = (ll + lr) / 2.0 + h * rise(mt, x + half, y);
    double right = (lr + ur) / 2.0 + h * rise(mt, x + width, y + half);
    double upper = (ur + ul) / 2.0 + h * rise(mt, x + half, y + width);
    double left = (ul + ll) / 2.0 + h * rise(mt, x, y + half);
    double middle = (ll + lr + ur + ul) / 4.0 + 1.4142136 * h * rise(mt, x + half, y + half);
    grow(mt, half, x, y, ll, lower, middle, left);
    grow(mt, half, x + half, y, lower, lr, right, middle);
    grow(mt, half, x + half, y + half, middle, right, ur, upper);
    grow(mt, half, x, y + half, left, middle, upper, ul);
}

/* Four spheres of radius CENTER[3] stacked as a tetrahedron on CENTER. */
static void make_spheres(spd_sink *out, const double center[4])
{
    double axis[3] = {1.0, 1.0, 0.0};
    spd_normalize(axis);
    double angle = acos(-1.0 / 3.0);
    double top[3] = {0.0, 0.0, center[3] * sqrt(3.0 / 2.0)};
    double sphere[4] = {center[0] + top[0], center[1] + top[1], center[2] + top[2], center[3]};
    spd_sphere(out, sphere);

    spd_mat m;
    double foot[3];
    spd_mat_axis_rotate(m, axis, angle);
    spd_xform_vector(foot, top, m);
    for (int i = 0; i < 3; i++) {
        spd_mat_rotate(m, 2, (double)i * 2.0 * SPD_PI / 3.0);
        spd_xform_vector(sphere, foot, m);
        sphere[0] += center[0];
        sphere[1] += center[1];
        sphere[2] += center[2];
        spd_sphere(out, sphere);
    }
}

void spd_gen_mount(int size, spd_sink *out)
{
    const double from[3] = {-1.6, 1.6, 1.7}, at[3] = {0.0, 0.0, 0.0}, up[3] = {0.0, 0.0, 1.0};
    const double light[3] = {-100.0, -100.0, 100.0};
    const double glass[3] = {1.0, 1.0, 1.0}, rock[3] = {0.5, 0.45, 0.35};
    const double center[4] = {-0.8, 0.8, 1.00, 0.17};

    spd_background(out, 0.078, 0.361, 0.753);
    spd_view(out, from, at, up, 45.0, 0.01, 512, 512);
    spd_light(out, light);
    spd_color(out, glass, 0.0, 0.1, 0.1, 0.4, 6.7, 0.9, 1.5);
    make_spheres(out, center);
    spd_color(out, rock, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0);

    mountain mt;
    mt.out = out;
    mt.size = size;
    int num = 1 << size;
    mt.fnum = (double)num;
    double ratio = 2.0 / exp(log(2.0) / (FRACTAL_DIMENSION - 1.0));
    mt.roughness = sqrt(ratio * ratio - 1.0);
    grow(&mt, num, 0, 0, 0.0, 0.0, 0.0, 0.0);
}
