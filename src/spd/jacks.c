/*
 * jacks.c — SPD "jacks" (Alexander Enzmann): recursive jacks, a little like a
 * Menger sponge. A jack is three open cylinders along the axes with a sphere
 * at each end; every level puts a half-size copy of the whole in each of
 * the eight octants. The whole is turned 30 degrees about x and 20 about y;
 * one light, a dark purple background.
 *
 * Size factor SF = number of levels: 3 (8^0 + ... + 8^(SF-1)) cylinders and
 * twice as many spheres (SF 1, the default, is a single jack).
 */
#include <string.h>

#include "spd/spd.h"

static void make_jack(spd_sink *out, spd_mat frame)
{
    spd_mat m;
    const double shrink[3] = {0.75, 0.75, 0.75}; /* keeps neighbours apart */
    memcpy(m, frame, sizeof m);
    spd_tx_scale(m, shrink);

    for (int a = 0; a < 3; a++) {
        double base[4] = {0.0, 0.0, 0.0, 0.1}, apex[4] = {0.0, 0.0, 0.0, 0.1};
        base[a] = -1.0;
        apex[a] = 1.0;
        spd_cylcone_tx(out, base, apex, m);
    }
    for (int k = 0; k < 6; k++) {
        double c[4] = {0.0, 0.0, 0.0, 0.2};
        c[k % 3] = k < 3 ? 1.0 : -1.0;
        spd_sphere_tx(out, c, m);
    }
}

static void make_level(spd_sink *out, spd_mat frame, int depth, int max_depth)
{
    make_jack(out, frame);
    if (depth >= max_depth || spd_failed(out))
        return;
    const double half[3] = {0.5, 0.5, 0.5};
    for (double i = -0.5; i <= 0.5; i += 1)
        for (double j = -0.5; j <= 0.5; j += 1)
            for (double k = -0.5; k <= 0.5; k += 1) {
                spd_mat m;
                const double t[3] = {i, j, k};
                memcpy(m, frame, sizeof m);
                spd_tx_translate(m, t);
                spd_tx_scale(m, half);
                make_level(out, m, depth + 1, max_depth);
            }
}

void spd_gen_jacks(int size, spd_sink *out)
{
    const double from[3] = {0, 0, -8}, at[3] = {0, 0, 0}, up[3] = {0, 1, 0};
    const double light[3] = {-10, 3, -20};
    const double pink[3] = {0.737, 0.561, 0.561};

    spd_background(out, 0.2, 0.05, 0.2);
    spd_view(out, from, at, up, 25.0, 0.001, 256, 256);
    spd_light(out, light);

    spd_mat root;
    spd_mat_identity(root);
    spd_tx_rotate(root, 0, -30 * SPD_PI / 180.0);
    spd_tx_rotate(root, 1, -20 * SPD_PI / 180.0);
    spd_color(out, pink, 0.1, 0.7, 0.7, 0.4, 20.0, 0.0, 1.0);
    make_level(out, root, 1, size);
}
