/*
 * spdlib.c — the small part of SPD's support library the generators need:
 * 4x4 matrix and vector arithmetic with libvec's exact semantics (same
 * operations in the same order, so the generated numbers match Haines'
 * programs bit for bit), the Phong exponent rule, and the emit helpers that
 * apply SPD's output-time rules (polygon vertex collapsing, patch splitting)
 * before handing entities to a sink, tessellating spheres and cones into
 * patches when the sink asks for it (the scheme is described in spd.h).
 *
 * Bit-for-bit agreement assumes plain IEEE double arithmetic without fused
 * multiply-adds, which is what gcc and clang emit for x86-64 by default
 * (-std=c11 turns contraction off in gcc; baseline x86-64 has no FMA). With
 * FMA contraction the numbers may differ in the last bits (the tests compare
 * the text within %g precision).
 */
#include <math.h>
#include <string.h>

#include "spd/spd.h"

/* --- vectors and matrices ----------------------------------------------- */

double spd_normalize(double v[3])
{
    double len = sqrt(spd_dot(v, v));
    if (len > 0.0) {
        v[0] /= len;
        v[1] /= len;
        v[2] /= len;
    }
    return len;
}

void spd_cross(double r[3], const double a[3], const double b[3])
{
    double x = a[1] * b[2] - a[2] * b[1];
    double y = a[2] * b[0] - a[0] * b[2];
    double z = a[0] * b[1] - a[1] * b[0];
    r[0] = x;
    r[1] = y;
    r[2] = z;
}

void spd_mat_zero(spd_mat m)
{
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++)
            m[i][j] = 0.0;
}

void spd_mat_identity(spd_mat m)
{
    spd_mat_zero(m);
    for (int i = 0; i < 4; i++)
        m[i][i] = 1.0;
}

void spd_mat_rotate(spd_mat m, int axis, double angle)
{
    double c = cos(angle), s = sin(angle);
    /* the two coordinates that turn, in the order SPD fills them */
    int a = axis == 0 ? 1 : axis == 1 ? 2 : 0;
    int b = axis == 0 ? 2 : axis == 1 ? 0 : 1;
    spd_mat_zero(m);
    m[axis][axis] = 1.0;
    m[a][a] = c;
    m[b][b] = c;
    m[a][b] = s;
    m[b][a] = -s;
    m[3][3] = 1.0;
}

void spd_mat_axis_rotate(spd_mat m, const double ax[3], double angle)
{
    double c = cos(angle), s = sin(angle), omc = 1.0 - c;
    double x = ax[0], y = ax[1], z = ax[2];

    m[0][0] = x * x + (1.0 - x * x) * c;
    m[0][1] = x * y * omc + z * s;
    m[0][2] = x * z * omc - y * s;
    m[0][3] = 0.0;

    m[1][0] = x * y * omc - z * s;
    m[1][1] = y * y + (1.0 - y * y) * c;
    m[1][2] = y * z * omc + x * s;
    m[1][3] = 0.0;

    m[2][0] = x * z * omc + y * s;
    m[2][1] = y * z * omc - x * s;
    m[2][2] = z * z + (1.0 - z * z) * c;
    m[2][3] = 0.0;

    m[3][0] = 0.0;
    m[3][1] = 0.0;
    m[3][2] = 0.0;
    m[3][3] = 1.0;
}

void spd_mat_translate(spd_mat m, const double t[3])
{
    spd_mat_identity(m);
    m[3][0] = t[0];
    m[3][1] = t[1];
    m[3][2] = t[2];
}

void spd_mat_scale(spd_mat m, const double sc[3])
{
    spd_mat_zero(m);
    m[0][0] = sc[0];
    m[1][1] = sc[1];
    m[2][2] = sc[2];
    m[3][3] = 1.0;
}

void spd_mat_mul(spd_mat r, spd_mat a, spd_mat b)
{
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++)
            r[i][j] = a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j] +
                      a[i][3] * b[3][j];
}

void spd_xform4(double r[4], const double v[4], spd_mat m)
{
    double t[4];
    for (int j = 0; j < 4; j++)
        t[j] = v[0] * m[0][j] + v[1] * m[1][j] + v[2] * m[2][j] + v[3] * m[3][j];
    memcpy(r, t, sizeof t);
}

void spd_xform_point(double r[3], const double v[3], spd_mat m)
{
    double t[3];
    for (int j = 0; j < 3; j++)
        t[j] = v[0] * m[0][j] + v[1] * m[1][j] + v[2] * m[2][j] + m[3][j];
    memcpy(r, t, sizeof t);
}

void spd_xform_vector(double r[3], const double v[3], spd_mat m)
{
    double t[3];
    for (int j = 0; j < 3; j++)
        t[j] = v[0] * m[0][j] + v[1] * m[1][j] + v[2] * m[2][j];
    memcpy(r, t, sizeof t);
}

double spd_phong(double angle_deg)
{
    double rad = SPD_PI * angle_deg / 180.0;
    if (rad <= 0.0)
        return 100000.0;
    if (rad >= SPD_PI / 2.0)
        return 1.0;
    return log(0.5) / log(cos(rad));
}

/* --- emitting ------------------------------------------------------------- */

static bsp_vec3 v3_of(const double p[3])
{
    return bsp_v3(p[0], p[1], p[2]);
}

void spd_background(spd_sink *s, double r, double g, double b)
{
    double rgb[3] = {r, g, b};
    if (!s->failed)
        s->background(s, rgb);
}

void spd_view(spd_sink *s, const double from[3], const double at[3], const double up[3],
              double angle, double hither, int resx, int resy)
{
    if (!s->failed)
        s->view(s, v3_of(from), v3_of(at), v3_of(up), angle, hither, resx, resy);
}

void spd_light(spd_sink *s, const double pos[3])
{
    if (!s->failed)
        s->light(s, v3_of(pos));
}

void spd_color(spd_sink *s, const double rgb[3], double ka, double kd, double ks,
               double ks_spec, double ang, double kt, double ior)
{
    (void)ka;
    (void)ks_spec;
    if (!s->failed)
        s->material(s, rgb, kd, ks, spd_phong(ang), kt, ior);
}

/* --- tessellation ------------------------------------------------------------ */

/* sin/cos of A, with round-off residue at the multiples of pi/2 made 0. */
static void tess_sincos(double a, double *sn, double *cs)
{
    *sn = sin(a);
    *cs = cos(a);
    if (fabs(*sn) < 1e-15)
        *sn = 0.0;
    if (fabs(*cs) < 1e-15)
        *cs = 0.0;
}

int spd_tess_init(spd_tess *t, int level)
{
    if (level < SPD_TESS_MIN || level > SPD_TESS_MAX)
        return 0;
    t->slices = level;
    t->bands = (level + 1) / 2 < 2 ? 2 : (level + 1) / 2;
    for (int i = 0; i < level; i++) {
        tess_sincos(2.0 * SPD_PI * i / level, &t->sin_lon[i], &t->cos_lon[i]);
        tess_sincos(2.0 * SPD_PI * (i + 0.5) / level, &t->sin_mid[i], &t->cos_mid[i]);
    }
    for (int j = 0; j <= t->bands; j++)
        tess_sincos(SPD_PI * j / t->bands, &t->sin_lat[j], &t->cos_lat[j]);
    t->sin_lat[0] = t->sin_lat[t->bands] = 0.0;
    t->cos_lat[0] = 1.0;
    t->cos_lat[t->bands] = -1.0;
    return 1;
}

/* One triangle patch (V, N: three points and normals each). */
static void tess_emit(spd_sink *s, const bsp_vec3 v[3], const bsp_vec3 n[3])
{
    if (!s->failed)
        s->patch(s, v, n, 3);
}

static int v3_finite(bsp_vec3 a)
{
    return isfinite(a.x) && isfinite(a.y) && isfinite(a.z);
}

/* Grid point (J, I) of the sphere C, R: its position and unit normal. */
static void sphere_point(const spd_tess *t, bsp_vec3 c, double r, int j, int i, bsp_vec3 *p,
                         bsp_vec3 *n)
{
    *n = bsp_v3(t->sin_lat[j] * t->cos_lon[i], t->sin_lat[j] * t->sin_lon[i], t->cos_lat[j]);
    *p = bsp_v3(c.x + r * n->x, c.y + r * n->y, c.z + r * n->z);
}

/* A sphere the tessellation passes on as it is (the scene drops or refuses
 * it as usual). */
static int sphere_untessellated(bsp_vec3 c, double radius)
{
    double r = fabs(radius);
    return !(r > 0.0) || !isfinite(r) || !v3_finite(c);
}

static void tess_sphere(spd_sink *s, bsp_vec3 c, double radius)
{
    const spd_tess *t = s->tess;
    double r = fabs(radius);
    if (sphere_untessellated(c, radius)) {
        s->sphere(s, c, radius);
        return;
    }
    const int nsl = t->slices, m = t->bands;
    bsp_vec3 v[3], n[3];
    for (int j = 0; j < m && !s->failed; j++) {
        for (int i = 0; i < nsl && !s->failed; i++) {
            int i1 = i + 1 < nsl ? i + 1 : 0;
            if (j == 0) { /* fan around +z */
                sphere_point(t, c, r, 0, 0, &v[0], &n[0]);
                sphere_point(t, c, r, 1, i, &v[1], &n[1]);
                sphere_point(t, c, r, 1, i1, &v[2], &n[2]);
                tess_emit(s, v, n);
            } else if (j == m - 1) { /* fan around -z */
                sphere_point(t, c, r, j, i, &v[0], &n[0]);
                sphere_point(t, c, r, m, 0, &v[1], &n[1]);
                sphere_point(t, c, r, j, i1, &v[2], &n[2]);
                tess_emit(s, v, n);
            } else {
                sphere_point(t, c, r, j, i, &v[0], &n[0]);
                sphere_point(t, c, r, j + 1, i, &v[1], &n[1]);
                sphere_point(t, c, r, j + 1, i1, &v[2], &n[2]);
                tess_emit(s, v, n);
                v[1] = v[2];
                n[1] = n[2];
                sphere_point(t, c, r, j, i1, &v[2], &n[2]);
                tess_emit(s, v, n);
            }
        }
    }
}

/* The frame of a cone: unit axis W, and U, V with (U, V, W) right-handed. */
typedef struct cone_frame {
    double u[3], v[3], w[3];
    double nd, nw; /* normal = nd * (radial direction) + nw * W */
} cone_frame;

/* Point at angle (COS, SIN) on the circle of radius R about CENTER, and the
 * surface normal there. */
static void cone_point(const cone_frame *f, bsp_vec3 center, double r, double cs, double sn,
                       bsp_vec3 *p, bsp_vec3 *n)
{
    double d[3];
    for (int k = 0; k < 3; k++)
        d[k] = f->u[k] * cs + f->v[k] * sn;
    *p = bsp_v3(center.x + r * d[0], center.y + r * d[1], center.z + r * d[2]);
    *n = bsp_v3(f->nd * d[0] + f->nw * f->w[0], f->nd * d[1] + f->nw * f->w[1],
                f->nd * d[2] + f->nw * f->w[2]);
}

/* A cone the tessellation passes on as it is (dropped or refused as usual);
 * W: its unit axis, *H: the axis's length. */
static int cone_untessellated(bsp_vec3 base, double base_r, bsp_vec3 apex, double apex_r,
                              double w[3], double *h)
{
    double rb = fabs(base_r), ra = fabs(apex_r);
    w[0] = apex.x - base.x;
    w[1] = apex.y - base.y;
    w[2] = apex.z - base.z;
    *h = spd_normalize(w);
    return !(*h > 0.0) || !isfinite(*h) || !isfinite(rb) || !isfinite(ra) ||
           (rb == 0.0 && ra == 0.0) || !v3_finite(base) || !v3_finite(apex);
}

static void tess_cone(spd_sink *s, bsp_vec3 base, double base_r, bsp_vec3 apex,
                      double apex_r)
{
    const spd_tess *t = s->tess;
    double rb = fabs(base_r), ra = fabs(apex_r);
    cone_frame f;
    double h;
    if (cone_untessellated(base, base_r, apex, apex_r, f.w, &h)) {
        s->cone(s, base, base_r, apex, apex_r);
        return;
    }
    /* U: perpendicular to W and to the world axis W is least aligned with */
    int least = 0;
    for (int k = 1; k < 3; k++)
        if (fabs(f.w[k]) < fabs(f.w[least]))
            least = k;
    double e[3] = {0.0, 0.0, 0.0};
    e[least] = 1.0;
    spd_cross(f.u, f.w, e);
    spd_normalize(f.u);
    spd_cross(f.v, f.w, f.u);
    /* the normal leans towards the apex by (rb - ra) / h */
    double len = sqrt(h * h + (rb - ra) * (rb - ra));
    f.nd = h / len;
    f.nw = (rb - ra) / len;

    const int nsl = t->slices;
    bsp_vec3 v[3], n[3];
    for (int i = 0; i < nsl && !s->failed; i++) {
        int i1 = i + 1 < nsl ? i + 1 : 0;
        double c0 = t->cos_lon[i], s0 = t->sin_lon[i];
        double c1 = t->cos_lon[i1], s1 = t->sin_lon[i1];
        if (ra == 0.0) { /* fan around the apex */
            cone_point(&f, base, rb, c0, s0, &v[0], &n[0]);
            cone_point(&f, base, rb, c1, s1, &v[1], &n[1]);
            cone_point(&f, apex, 0.0, t->cos_mid[i], t->sin_mid[i], &v[2], &n[2]);
            tess_emit(s, v, n);
        } else if (rb == 0.0) { /* fan around the base point */
            cone_point(&f, base, 0.0, t->cos_mid[i], t->sin_mid[i], &v[0], &n[0]);
            cone_point(&f, apex, ra, c1, s1, &v[1], &n[1]);
            cone_point(&f, apex, ra, c0, s0, &v[2], &n[2]);
            tess_emit(s, v, n);
        } else {
            cone_point(&f, base, rb, c0, s0, &v[0], &n[0]);
            cone_point(&f, base, rb, c1, s1, &v[1], &n[1]);
            cone_point(&f, apex, ra, c1, s1, &v[2], &n[2]);
            tess_emit(s, v, n);
            v[1] = v[2];
            n[1] = n[2];
            cone_point(&f, apex, ra, c0, s0, &v[2], &n[2]);
            tess_emit(s, v, n);
        }
    }
}

size_t spd_tess_sphere_triangles(const spd_tess *t)
{
    /* two fans of N triangles around the poles, two per quad between */
    return 2 * (size_t)t->slices * (size_t)(t->bands - 1);
}

size_t spd_tess_sphere_count(const spd_tess *t, bsp_vec3 c, double radius)
{
    return sphere_untessellated(c, radius) ? 1 : spd_tess_sphere_triangles(t);
}

size_t spd_tess_cone_count(const spd_tess *t, bsp_vec3 base, double base_r, bsp_vec3 apex,
                           double apex_r)
{
    double w[3], h;
    if (cone_untessellated(base, base_r, apex, apex_r, w, &h))
        return 1;
    /* a pointed end makes each slice one triangle, else two */
    return (base_r == 0.0 || apex_r == 0.0 ? 1 : 2) * (size_t)t->slices;
}

void spd_sphere(spd_sink *s, const double c[4])
{
    if (s->failed)
        return;
    if (s->tess)
        tess_sphere(s, v3_of(c), c[3]);
    else
        s->sphere(s, v3_of(c), c[3]);
}

void spd_cylcone(spd_sink *s, const double base[4], const double apex[4])
{
    if (s->failed)
        return;
    if (s->tess)
        tess_cone(s, v3_of(base), base[3], v3_of(apex), apex[3]);
    else
        s->cone(s, v3_of(base), base[3], v3_of(apex), apex[3]);
}

/* Largest polygon any generator emits (gears: 144 vertices). */
#define SPD_MAX_VERTS 1024

void spd_polygon(spd_sink *s, int n, double (*v)[3])
{
    if (s->failed)
        return;
    /* collapse a vertex onto its successor (cyclically) when they nearly
     * coincide, exactly as lib_output_polygon does */
    for (int i = 0; i < n;) {
        double d[3];
        const double *a = v[i], *b = v[(i + 1) % n];
        d[0] = a[0] - b[0];
        d[1] = a[1] - b[1];
        d[2] = a[2] - b[2];
        if (spd_normalize(d) < SPD_EPSILON2) {
            memmove(&v[i], &v[i + 1], (size_t)(n - 1 - i) * sizeof v[0]);
            n--;
        } else {
            i++;
        }
    }
    if (n < 3 || n > SPD_MAX_VERTS)
        return;
    bsp_vec3 out[SPD_MAX_VERTS];
    for (int i = 0; i < n; i++)
        out[i] = v3_of(v[i]);
    s->polygon(s, out, n);
}

void spd_polypatch(spd_sink *s, int n, double (*v)[3], double (*nrm)[3])
{
    if (s->failed)
        return;
    /* SPD's patch splitter keeps a triangle as it is (its collinearity test
     * is a no-op); every SPD generator emits patches as triangles. */
    if (n != 3)
        return;
    bsp_vec3 pv[3], pn[3];
    for (int i = 0; i < 3; i++) {
        pv[i] = v3_of(v[i]);
        pn[i] = v3_of(nrm[i]);
    }
    s->patch(s, pv, pn, 3);
}

/* --- the transform stack (libtx semantics) ---------------------------------- */

int spd_tx_active(spd_mat m)
{
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++)
            if (fabs(m[i][j] - (i == j ? 1.0 : 0.0)) > SPD_EPSILON)
                return 1;
    return 0;
}

/* M = OP * M: the new operation applies to points before the old ones. */
static void tx_premultiply(spd_mat m, spd_mat op)
{
    spd_mat old;
    memcpy(old, m, sizeof old);
    spd_mat_mul(m, op, old);
}

void spd_tx_rotate(spd_mat m, int axis, double angle)
{
    spd_mat op;
    spd_mat_rotate(op, axis, angle);
    tx_premultiply(m, op);
}

void spd_tx_scale(spd_mat m, const double sc[3])
{
    spd_mat op;
    spd_mat_scale(op, sc);
    tx_premultiply(m, op);
}

void spd_tx_translate(spd_mat m, const double t[3])
{
    spd_mat op;
    spd_mat_translate(op, t);
    tx_premultiply(m, op);
}

/* The x scale factor SPD's matrix "unwinding" finds (it scales radii, which
 * assumes uniform scaling): the length of the first row after dividing by
 * the homogeneous element. */
static double tx_scale_x(spd_mat m)
{
    double row[3] = {m[0][0], m[0][1], m[0][2]};
    if (m[3][3] != 0.0)
        for (int j = 0; j < 3; j++)
            row[j] /= m[3][3];
    return spd_normalize(row);
}

void spd_sphere_tx(spd_sink *s, const double c[4], spd_mat m)
{
    double t[4] = {c[0], c[1], c[2], c[3]};
    if (spd_tx_active(m)) {
        spd_xform_point(t, c, m);
        t[3] = c[3] * fabs(tx_scale_x(m));
    }
    spd_sphere(s, t);
}

void spd_cylcone_tx(spd_sink *s, const double base[4], const double apex[4], spd_mat m)
{
    double b[4] = {base[0], base[1], base[2], base[3]};
    double a[4] = {apex[0], apex[1], apex[2], apex[3]};
    if (spd_tx_active(m)) {
        double sc = fabs(tx_scale_x(m));
        spd_xform_point(b, base, m);
        b[3] = base[3] * sc;
        spd_xform_point(a, apex, m);
        a[3] = apex[3] * sc;
    }
    spd_cylcone(s, b, a);
}

/* Determinant of the 3x3 matrix with columns (a1 a2 a3), (b1 b2 b3),
 * (c1 c2 c3), expanded as libvec does. */
static double det3(double a1, double a2, double a3, double b1, double b2, double b3,
                   double c1, double c2, double c3)
{
    return a1 * (b2 * c3 - b3 * c2) - b1 * (a2 * c3 - a3 * c2) + c1 * (a2 * b3 - a3 * b2);
}

/* Minor of M without row I and column J. */
static double minor3(spd_mat m, int i, int j)
{
    int r[3], c[3];
    for (int k = 0, n = 0; k < 4; k++)
        if (k != i)
            r[n++] = k;
    for (int k = 0, n = 0; k < 4; k++)
        if (k != j)
            c[n++] = k;
    return det3(m[r[0]][c[0]], m[r[1]][c[0]], m[r[2]][c[0]], m[r[0]][c[1]], m[r[1]][c[1]],
                m[r[2]][c[1]], m[r[0]][c[2]], m[r[1]][c[2]], m[r[2]][c[2]]);
}

void spd_mat_invert(spd_mat r, spd_mat m)
{
    /* adjugate (transposed cofactors) over the determinant expanded along
     * row 0; a (nearly) singular matrix gives the identity, as in SPD */
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) {
            double minor = minor3(m, i, j);
            r[j][i] = (i + j) % 2 ? -minor : minor;
        }
    double det = m[0][0] * minor3(m, 0, 0) - m[0][1] * minor3(m, 0, 1) +
                 m[0][2] * minor3(m, 0, 2) - m[0][3] * minor3(m, 0, 3);
    if (fabs(det) < SPD_EPSILON) {
        spd_mat_identity(r);
        return;
    }
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++)
            r[i][j] /= det;
}

void spd_xform_normal(double r[3], const double v[3], spd_mat m)
{
    double t[3];
    for (int i = 0; i < 3; i++)
        t[i] = v[0] * m[i][0] + v[1] * m[i][1] + v[2] * m[i][2];
    memcpy(r, t, sizeof t);
}

void spd_polypatch_tx(spd_sink *s, int n, double (*v)[3], double (*nrm)[3], spd_mat m)
{
    if (n != 3 || s->failed)
        return;
    double tv[3][3], tn[3][3];
    memcpy(tv, v, sizeof tv);
    memcpy(tn, nrm, sizeof tn);
    if (spd_tx_active(m)) {
        /* vertices by the matrix, normals by the transpose of its inverse,
         * not renormalized (as SPD's patch splitter does) */
        spd_mat inv;
        spd_mat_invert(inv, m);
        for (int i = 0; i < 3; i++) {
            spd_xform_point(tv[i], tv[i], m);
            spd_xform_normal(tn[i], tn[i], inv);
        }
    }
    spd_polypatch(s, 3, tv, tn);
}
