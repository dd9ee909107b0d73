/*
 * balls.c — SPD "balls", the sphereflake: a shiny sphere that sprouts nine
 * spheres of a third its radius, each of which does the same, over a
 * beige floor square, lit by three lights.
 *
 * Size factor SF = recursion depth: 9^0 + 9^1 + ... + 9^SF spheres plus the
 * floor (SF 4, the default, gives 7381 spheres). Emitted depth first, parent
 * before children, as balls.c of SPD 3.14 (with its 2021 epsilon fix) does.
 */
#include <math.h>

#include "spd/spd.h"

typedef struct flake {
    spd_sink *out;
    double dirs[9][4]; /* the nine child directions around +Z (w = 0) */
} flake;

/* The nine child directions: a trio of directions tilted up from the
 * horizontal, copied three times around the Z axis. */
static void make_directions(flake *f)
{
    double d = 1.0 / sqrt(2.0);
    double trio[3][4] = {{d, d, 0.0, 0.0}, {d, 0.0, -d, 0.0}, {0.0, d, -d, 0.0}};
    double axis[3] = {1.0, -1.0, 0.0};
    spd_mat m;

    spd_normalize(axis);
    spd_mat_axis_rotate(m, axis, asin(2.0 / sqrt(6.0)));
    for (int k = 0; k < 3; k++)
        spd_xform4(trio[k], trio[k], m);
    for (int set = 0; set < 3; set++) {
        spd_mat_rotate(m, 2, set * 2.0 * SPD_PI / 3.0);
        for (int k = 0; k < 3; k++)
            spd_xform4(f->dirs[set * 3 + k], trio[k], m);
    }
}

/* CENTER: x, y, z, radius. DIR: unit growth direction, w = child/parent
 * radius ratio. */
static void grow(flake *f, int depth, const double center[4], const double dir[4])
{
    spd_sphere(f->out, center);
    if (depth <= 0 || spd_failed(f->out))
        return;
    depth--;

    spd_mat m;
    if (dir[2] >= 0.9999) {
        spd_mat_identity(m);
    } else if (dir[2] <= -0.9999) {
        spd_mat_rotate(m, 1, SPD_PI);
    } else {
        const double z[3] = {0.0, 0.0, 1.0};
        double axis[3];
        spd_cross(axis, z, dir);
        spd_normalize(axis);
        spd_mat_axis_rotate(m, axis, acos(spd_dot(z, dir)));
    }

    double scale = center[3] * (1.0 + dir[3]);
    for (int k = 0; k < 9; k++) {
        double child[4], child_dir[4];
        spd_xform4(child, f->dirs[k], m);
        child[0] = child[0] * scale + center[0];
        child[1] = child[1] * scale + center[1];
        child[2] = child[2] * scale + center[2];
        child[3] = center[3] * dir[3];
        child_dir[0] = (child[0] - center[0]) / scale;
        child_dir[1] = (child[1] - center[1]) / scale;
        child_dir[2] = (child[2] - center[2]) / scale;
        child_dir[3] = dir[3];
        grow(f, depth, child, child_dir);
    }
}

void spd_gen_balls(int size, spd_sink *out)
{
    const double radius = 1.0;
    const double from[3] = {2.1, 1.3, 1.7}, at[3] = {0.0, 0.0, 0.0}, up[3] = {0.0, 0.0, 1.0};
    const double lights[3][3] = {{4.0, 3.0, 2.0}, {1.0, -4.0, 4.0}, {-3.0, 1.0, 5.0}};
    const double floor_rgb[3] = {1.0, 0.75, 0.33}, ball_rgb[3] = {1.0, 0.9, 0.7};

    spd_background(out, 0.078, 0.361, 0.753);
    spd_view(out, from, at, up, 45.0, 0.01, 512, 512);
    for (int i = 0; i < 3; i++)
        spd_light(out, lights[i]);

    spd_color(out, floor_rgb, 0.2, 0.8, 0.0, 0.0, 0.0, 0.0, 1.0);
    double x = 12.0 * radius, y = 12.0 * radius, z = -radius / 2.0;
    double floor_v[4][3] = {{x, y, z}, {-x, y, z}, {-x, -y, z}, {x, -y, z}};
    spd_polygon(out, 4, floor_v);

    spd_color(out, ball_rgb, 0.0, 0.5, 0.5, 0.5, 37.0, 0.0, 1.0);
    flake f;
    f.out = out;
    make_directions(&f);
    const double center[4] = {0.0, 0.0, 0.0, radius / 2.0};
    const double dir[4] = {0.0, 0.0, 1.0, 1.0 / 3.0};
    grow(&f, size, center, dir);
}
