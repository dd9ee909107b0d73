/*
 * tree.c — SPD "tree": a branching tree grown with Aono & Kunii's method
 * (IEEE CG&A, May 1984): every branch is a cone capped by a sphere and forks
 * into two smaller branches; a 100 x 100 green field lies beneath it; seven
 * lights.
 *
 * Size factor SF = number of forkings: 2^(SF+1) - 1 cones and as many
 * spheres, plus the field (SF 11, the default, gives 4095 of each).
 */
#include "spd/spd.h"

#define BRANCH_DIAMETER 0.67   /* radius ratio child / parent */
#define WIDTH_HEIGHT_RATIO 0.15 /* base radius / length of a branch */

typedef struct tree {
    spd_sink *out;
    spd_mat grow[2]; /* child branch frame relative to its parent */
} tree;

static void setup_growth(tree *t)
{
    /* branching angle, divergence angle (degrees), length contraction */
    const double shape[2][3] = {{40.0, 90.0, 0.65}, {25.0, 140.0 + 90.0, 0.70}};
    for (int i = 0; i < 2; i++) {
        spd_mat rx, rz, r, st;
        spd_mat_rotate(rx, 0, shape[i][0] * SPD_PI / 180.0);
        spd_mat_rotate(rz, 2, shape[i][1] * SPD_PI / 180.0);
        spd_mat_mul(r, rx, rz);
        spd_mat_identity(st);
        st[0][0] = shape[i][2];
        st[1][1] = shape[i][2];
        st[2][2] = shape[i][2];
        st[3][2] = 1.0;
        spd_mat_mul(t->grow[i], r, st);
    }
}

/* FRAME maps the unit branch (0,0,0)-(0,0,1) into place; SCALE is the
 * branch's size relative to the trunk. */
static void branch(tree *t, spd_mat frame, double scale, int depth)
{
    const double origin[3] = {0.0, 0.0, 0.0}, tip[3] = {0.0, 0.0, 1.0};
    double base[4], apex[4];
    spd_xform_point(base, origin, frame);
    base[3] = scale * WIDTH_HEIGHT_RATIO;
    spd_xform_point(apex, tip, frame);
    apex[3] = base[3] * BRANCH_DIAMETER;
    spd_cylcone(t->out, base, apex);
    spd_sphere(t->out, apex);

    if (depth <= 0 || spd_failed(t->out))
        return;
    for (int i = 0; i < 2; i++) {
        spd_mat child;
        spd_mat_mul(child, t->grow[i], frame);
        branch(t, child, scale * BRANCH_DIAMETER, depth - 1);
    }
}

void spd_gen_tree(int size, spd_sink *out)
{
    const double from[3] = {4.5, 0.4, 2.0}, at[3] = {0.0, 0.0, 1.5}, up[3] = {0.0, 0.0, 1.0};
    const double lights[7][3] = {{-5.0, 5.0, 50.0},   {30.0, -30.0, 30.0}, {-40.0, -30.0, 20.0},
                                 {10.0, 30.0, 40.0},  {-30.0, 40.0, 10.0}, {50.0, 25.0, 20.0},
                                 {-10.0, -60.0, 30.0}};
    const double green[3] = {0.2, 0.7, 0.2}, brown[3] = {0.55, 0.4, 0.2};

    spd_background(out, 0.078, 0.361, 0.753);
    spd_view(out, from, at, up, 45.0, 1.0, 512, 512);
    for (int i = 0; i < 7; i++)
        spd_light(out, lights[i]);

    spd_color(out, green, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    double field[4][3] = {{50.0, 50.0, 0.0}, {-50.0, 50.0, 0.0}, {-50.0, -50.0, 0.0},
                          {50.0, -50.0, 0.0}};
    spd_polygon(out, 4, field);

    spd_color(out, brown, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    tree t;
    t.out = out;
    setup_growth(&t);
    spd_mat trunk;
    spd_mat_identity(trunk);
    branch(&t, trunk, 1.0, size);
}
