/*
 * nurbtst.c — SPD "nurbtst" (Alexander Enzmann): a single bicubic B-spline
 * patch (6 x 5 control points, open uniform knots) tessellated into 1500
 * smooth triangles (`pp`), turned and moved into view; one light.
 *
 * SPD evaluates the basis functions in single precision and, in this
 * version, always treats the patch as non-rational (the weights are
 * ignored); both are reproduced so the numbers match. Its vertex normals
 * point against the winding of the triangles, as in SPD.
 *
 * The size factor is ignored by SPD; it is fixed at 1 here.
 */
#include <string.h>

#include "spd/spd.h"

#define ORDER 4     /* cubic in both directions */
#define NPTS 6      /* control points along u */
#define MPTS 5      /* control points along v */
#define RESOLUTION 5 /* SPD's polygonalization for this scene: steps per point */
#define MAX_KNOTS (ORDER + NPTS)

/* x, y, z, w; rows along u. SPD ignores w in its tessellation. */
static const double ctl[NPTS][MPTS][4] = {
    {{0, 0, 0, 1}, {1, 0, 3, 1}, {2, 0, -3, 1}, {3, 0, 3, 1}, {4, 0, 0, 1}},
    {{0, 1, 0, 1}, {1, 1, 0, 1}, {2, 1, 0, 1}, {3, 1, 0, 1}, {4, 1, 0, 1}},
    {{0, 2, 0, 1}, {1, 2, 0, 2}, {2, 2, 5, 0.5}, {3, 2, 0, 1}, {4, 2, 0, 1}},
    {{0, 3, 0, 1}, {1, 3, 0, 2}, {2, 3, 5, 0.5}, {3, 3, 0, 1}, {4, 3, 0, 1}},
    {{0, 4, 0, 1}, {1, 4, 0, 1}, {2, 4, 0, 20}, {3, 4, 0, 1}, {4, 4, 0, 1}},
    {{0, 5, 0, 1}, {1, 5, -3, 1}, {2, 5, 3, 1}, {3, 5, -3, 1}, {4, 5, 0, 1}}};

/* Open uniform knot vector for NPTS_ control points of order ORDER_. */
static void open_knots(int order, int npts, float *x)
{
    x[0] = 0.0f;
    for (int i = 1; i < order + npts; i++)
        x[i] = (i >= order && i < npts + 1) ? x[i - 1] + 1 : x[i - 1];
}

/* B-spline basis functions of order C at T over knots X, and their
 * derivatives (Cox-de Boor recursion in single precision). A zero knot span
 * with a nonzero numerator keeps the previous term, as SPD does (it cannot
 * happen with open uniform knots). */
static void basis_funcs(int c, float t, int npts, const float *x, float *basis,
                        float *dbasis)
{
    int nplusc = npts + c;
    float b1 = 0.0f, b2 = 0.0f, f1, f2, f3 = 0.0f, f4 = 0.0f, numer, denom;

    for (int i = 0; i < nplusc; i++) {
        basis[i] = 0.0f;
        dbasis[i] = 0.0f;
    }
    for (int i = 0; i < nplusc - 1; i++)
        basis[i] = (t >= x[i] && t < x[i + 1]) ? 1.0f : 0.0f;
    if (t >= x[nplusc - 1])
        basis[npts - 1] = 1.0f; /* the far end of the parameter range */

    for (int k = 2; k <= c; k++) {
        for (int i = 0; i < nplusc - k; i++) {
            if (basis[i] != 0.0f) {
                numer = (float)((t - x[i]) * basis[i]);
                denom = x[i + k - 1] - x[i];
                if (denom == 0.0f) {
                    if (numer == 0.0f)
                        b1 = 1.0f;
                } else {
                    b1 = numer / denom;
                }
            } else {
                b1 = 0.0f;
            }
            if (basis[i + 1] != 0.0f) {
                numer = (float)((x[i + k] - t) * basis[i + 1]);
                denom = x[i + k] - x[i + 1];
                if (denom == 0.0f) {
                    if (numer == 0.0f)
                        b2 = 1.0f;
                } else {
                    b2 = numer / denom;
                }
            } else {
                b2 = 0.0f;
            }
            f1 = basis[i] != 0.0f ? basis[i] / (x[i + k - 1] - x[i]) : 0.0f;
            f2 = basis[i + 1] != 0.0f ? -basis[i + 1] / (x[i + k] - x[i + 1]) : 0.0f;
            if (dbasis[i] != 0.0f) {
                numer = (float)((t - x[i]) * dbasis[i]);
                denom = x[i + k - 1] - x[i];
                if (denom == 0.0f) {
                    if (numer == 0.0f)
                        f3 = 1.0f;
                } else {
                    f3 = numer / denom;
                }
            } else {
                f3 = 0.0f;
            }
            if (dbasis[i + 1] != 0.0f) {
                numer = (float)((x[i + k] - t) * dbasis[i + 1]);
                denom = x[i + k] - x[i + 1];
                if (denom == 0.0f) {
                    if (numer == 0.0f)
                        f4 = 1.0f;
                } else {
                    f4 = numer / denom;
                }
            } else {
                f4 = 0.0f;
            }
            basis[i] = b1 + b2;
            dbasis[i] = f1 + f2 + f3 + f4;
        }
    }
}

/* Point P and unit normal N at (U, V), non-rational evaluation. */
static void surface_point(const float *uknots, const float *vknots, float u, float v,
                          double p[3], double n[3])
{
    float ub[MAX_KNOTS], udb[MAX_KNOTS], vb[MAX_KNOTS], vdb[MAX_KNOTS];
    basis_funcs(ORDER, u, NPTS, uknots, ub, udb);
    basis_funcs(ORDER, v, MPTS, vknots, vb, vdb);

    double du[3] = {0.0, 0.0, 0.0}, dv[3] = {0.0, 0.0, 0.0};
    p[0] = p[1] = p[2] = 0.0;
    for (int i = 0; i < NPTS; i++)
        for (int j = 0; j < MPTS; j++) {
            float t = ub[i] * vb[j], tu = udb[i] * vb[j], tv = ub[i] * vdb[j];
            for (int k = 0; k < 3; k++) {
                p[k] += t * ctl[i][j][k];
                du[k] += tu * ctl[i][j][k];
                dv[k] += tv * ctl[i][j][k];
            }
        }
    spd_cross(n, dv, du);
    spd_normalize(n);
}

void spd_gen_nurbtst(int size, spd_sink *out)
{
    (void)size;
    const double from[3] = {0, 5, -10}, at[3] = {0, 0, 0}, up[3] = {0, 1, 0};
    const double light[3] = {0, 50, -10};
    const double red[3] = {1.0, 0.0, 0.0};

    spd_background(out, 0.0, 0.0, 0.0);
    spd_view(out, from, at, up, 30.0, 0.001, 256, 256);
    spd_light(out, light);
    spd_color(out, red, 0.1, 0.7, 0.0, 0.7, 10.0, 0.0, 1.0);

    /* the patch is turned 30 degrees about y, -90 about x, then moved */
    spd_mat tx;
    const double move[3] = {-2.0, -2.5, 0.0};
    spd_mat_identity(tx);
    spd_tx_rotate(tx, 1, SPD_PI * 30.0 / 180.0);
    spd_tx_rotate(tx, 0, SPD_PI * -90.0 / 180.0);
    spd_tx_translate(tx, move);

    float uknots[MAX_KNOTS], vknots[MAX_KNOTS];
    open_knots(ORDER, NPTS, uknots);
    open_knots(ORDER, MPTS, vknots);

    enum { USTEPS = NPTS * RESOLUTION, VSTEPS = MPTS * RESOLUTION };
    float u0 = 0.0f, v0 = 0.0f;
    float u1 = (float)(NPTS - ORDER + 1), v1 = (float)(MPTS - ORDER + 1);
    float ud = (u1 - u0) / (float)USTEPS, vd = (v1 - v0) / (float)VSTEPS;
    double prow[2][VSTEPS + 1][3], nrow[2][VSTEPS + 1][3];
    int cur = 1; /* the row being computed; 1 - cur is the previous one */
    float u = u0;
    for (int i = 0; i <= USTEPS && !spd_failed(out); i++, u += ud) {
        float v = v0;
        for (int j = 0; j <= VSTEPS; j++, v += vd)
            surface_point(uknots, vknots, u, v, prow[cur][j], nrow[cur][j]);
        if (i > 0) {
            double (*p0)[3] = prow[1 - cur], (*p1)[3] = prow[cur];
            double (*n0)[3] = nrow[1 - cur], (*n1)[3] = nrow[cur];
            for (int j = 0; j < VSTEPS; j++) {
                double vert[3][3], norm[3][3];
                memcpy(vert[0], p0[j], sizeof vert[0]);
                memcpy(vert[1], p1[j], sizeof vert[0]);
                memcpy(vert[2], p1[j + 1], sizeof vert[0]);
                memcpy(norm[0], n0[j], sizeof norm[0]);
                memcpy(norm[1], n1[j], sizeof norm[0]);
                memcpy(norm[2], n1[j + 1], sizeof norm[0]);
                spd_polypatch_tx(out, 3, vert, norm, tx);
                memcpy(vert[1], vert[2], sizeof vert[0]);
                memcpy(vert[2], p0[j + 1], sizeof vert[0]);
                memcpy(norm[1], norm[2], sizeof norm[0]);
                memcpy(norm[2], n0[j + 1], sizeof norm[0]);
                spd_polypatch_tx(out, 3, vert, norm, tx);
            }
        }
        cur = 1 - cur;
    }
}
