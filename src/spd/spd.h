/*
 * spd.h — built-in generators for Eric Haines' Standard Procedural Databases
 * (SPD 3.14), so that "spd:NAME[:SIZE]" is a scene without any file.
 *
 * Every generator writes the same entity stream the SPD program prints (in
 * the same order, with the same arithmetic) into a sink. Two sinks exist: one
 * builds a bsp_scene through the public add_* calls, one prints NFF text the
 * way SPD does (%g numbers, one `c` per line). The tests compare the second
 * against NFF files made by Haines' own programs.
 *
 * Private to the library except for the entry points at the end.
 */
#ifndef BSPRAY_SPD_H
#define BSPRAY_SPD_H

#include <stdio.h>

#include "bspray/error.h"
#include "bspray/geom.h"
#include "bspray/spd.h"
#include "bspray/scene.h"

#define SPD_HIDDEN __attribute__((visibility("hidden")))

/* --- tessellation ("spd:NAME[:SIZE]:tN", the SPD programs' -t) ------------
 *
 * At level N (SPD_TESS_MIN..SPD_TESS_MAX) every sphere and every cone or
 * cylinder becomes polygonal patches (NFF "pp" triangles) carrying the true
 * outward surface normal at each vertex, emitted in place of the primitive;
 * polygons and patches pass unchanged. Every vertex lies on the original
 * surface, so the result is inscribed in it.
 *
 * Sphere: a latitude/longitude grid about the world z axis with N slices
 * (longitude 2 pi i / N, i = 0 at +x, increasing counterclockwise seen from
 * +z) and M = max(2, ceil(N / 2)) bands (colatitude pi j / M from +z).
 * Bands are emitted from +z down, each slice in order: the two polar bands
 * as triangle fans around the pole vertex (one triangle per slice, so no
 * degenerate triangle is produced), every other band as two triangles per
 * quad, split along the diagonal from (j, i) to (j + 1, i + 1). That is
 * 2 N (M - 1) triangles per sphere (48 at N = 8).
 *
 * Cone: N quads around the axis (base to apex, in a right-handed frame
 * (u, v, axis) with u perpendicular to the axis and to the world axis the
 * axis is least aligned with), each split into two triangles along the
 * diagonal from base vertex i to apex vertex i + 1; open ends, as NFF cones
 * have. When one end's radius is zero that end is a point and each slice
 * is one triangle (the fan around it), its normal there the one at the
 * slice's mid angle: 2 N triangles per cone, N with a pointed end.
 *
 * Triangles wind counterclockwise seen from outside. A negative radius
 * (NFF's inside-only surface; no SPD generator emits one) is tessellated
 * like its absolute value. A degenerate or non-finite sphere or cone (which
 * the scene drops or refuses) is passed on untessellated. */

#define SPD_TESS_MIN 2
#define SPD_TESS_MAX 64

typedef struct spd_tess {
    int slices; /* N */
    int bands;  /* M */
    /* angles 2 pi i / N and 2 pi (i + 1/2) / N; colatitudes pi j / M (values
     * below 1e-15 in magnitude are snapped to 0, the poles are exact) */
    double cos_lon[SPD_TESS_MAX], sin_lon[SPD_TESS_MAX];
    double cos_mid[SPD_TESS_MAX], sin_mid[SPD_TESS_MAX];
    double cos_lat[SPD_TESS_MAX / 2 + 1], sin_lat[SPD_TESS_MAX / 2 + 1];
} spd_tess;

/* Fills T for level LEVEL; returns 0 (T untouched) when LEVEL is out of
 * range. */
SPD_HIDDEN int spd_tess_init(spd_tess *t, int level);

/* The triangles the tessellation T makes of a sphere. */
SPD_HIDDEN size_t spd_tess_sphere_triangles(const spd_tess *t);
/* How many primitives the tessellation T makes of a sphere or a cone: its
 * triangles, or 1 when it passes the primitive on as it is. */
SPD_HIDDEN size_t spd_tess_sphere_count(const spd_tess *t, bsp_vec3 c, double radius);
SPD_HIDDEN size_t spd_tess_cone_count(const spd_tess *t, bsp_vec3 base, double base_r,
                                      bsp_vec3 apex, double apex_r);

/* The most primitives a generated scene may have: the size factors of the
 * registry (spd.c) keep every untessellated scene under it, and a
 * tessellated one is counted before it is made (spd_count) and refused
 * above it, instead of filling the memory (rings:100:t8 would make some
 * 650 million triangles, over 60 GB). */
#define SPD_MAX_PRIMS 100000000u

/* --- the sink ------------------------------------------------------------ */

/* Where a generator writes. FAILED is BSP_OK until the first error, then
 * that error's status; callbacks are never called once it is set (the emit
 * helpers below check it). A sink that fails keeps its message itself; a
 * generator that fails (out of memory) calls spd_fail, which records a
 * message for the entry point. Generators check spd_failed() in their loops
 * to stop early. */
typedef struct spd_sink spd_sink;
struct spd_sink {
    void *ctx;
    bsp_status failed;
    const char *gen_error; /* set by spd_fail */
    const spd_tess *tess;  /* NULL, or tessellate spheres and cones (above) */
    void (*background)(spd_sink *s, const double rgb[3]);
    void (*view)(spd_sink *s, bsp_vec3 from, bsp_vec3 at, bsp_vec3 up, double angle,
                 double hither, int resx, int resy);
    void (*light)(spd_sink *s, bsp_vec3 pos);
    void (*material)(spd_sink *s, const double rgb[3], double kd, double ks, double shine,
                     double t, double ior);
    void (*sphere)(spd_sink *s, bsp_vec3 center, double radius);
    void (*cone)(spd_sink *s, bsp_vec3 base, double base_radius, bsp_vec3 apex,
                 double apex_radius);
    void (*polygon)(spd_sink *s, const bsp_vec3 *v, int n);
    void (*patch)(spd_sink *s, const bsp_vec3 *v, const bsp_vec3 *nrm, int n);
};

static inline int spd_failed(const spd_sink *s)
{
    return s->failed != BSP_OK;
}

/* A generator's own failure (STATUS, e.g. BSP_ERR_NOMEM, with a constant
 * message WHAT): stops the output. */
static inline void spd_fail(spd_sink *s, bsp_status status, const char *what)
{
    if (s->failed == BSP_OK) {
        s->failed = status;
        s->gen_error = what;
    }
}

/* --- SPD-style arithmetic (libvec semantics, so results match bit for bit) */

typedef double spd_mat[4][4]; /* row vectors: p' = p * M */

#define SPD_PI 3.141592653589793
#define SPD_EPSILON 1.0e-8
#define SPD_EPSILON2 1.0e-6

/* Scales V to unit length unless it is zero; returns the old length. */
SPD_HIDDEN double spd_normalize(double v[3]);
SPD_HIDDEN void spd_cross(double r[3], const double a[3], const double b[3]);
static inline double spd_dot(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
SPD_HIDDEN void spd_mat_zero(spd_mat m);
SPD_HIDDEN void spd_mat_identity(spd_mat m);
/* Rotation by ANGLE radians about coordinate axis AXIS (0 = x, 1 = y, 2 = z). */
SPD_HIDDEN void spd_mat_rotate(spd_mat m, int axis, double angle);
/* Rotation by ANGLE radians about the unit vector AXIS. */
SPD_HIDDEN void spd_mat_axis_rotate(spd_mat m, const double axis[3], double angle);
SPD_HIDDEN void spd_mat_translate(spd_mat m, const double t[3]);
SPD_HIDDEN void spd_mat_scale(spd_mat m, const double s[3]);
/* R = A * B (R must not alias A or B). */
SPD_HIDDEN void spd_mat_mul(spd_mat r, spd_mat a, spd_mat b);
/* Homogeneous 4-vector times matrix (R may alias V). */
SPD_HIDDEN void spd_xform4(double r[4], const double v[4], spd_mat m);
/* Point (w = 1) and direction (w = 0) times matrix (R may alias V). */
SPD_HIDDEN void spd_xform_point(double r[3], const double v[3], spd_mat m);
SPD_HIDDEN void spd_xform_vector(double r[3], const double v[3], spd_mat m);

/* R = inverse of M by adjugate and determinant (the identity when M is
 * singular); R must not alias M. */
SPD_HIDDEN void spd_mat_invert(spd_mat r, spd_mat m);
/* Normal times the transpose of M (pass the inverse of a transform). */
SPD_HIDDEN void spd_xform_normal(double r[3], const double v[3], spd_mat m);

/* Phong exponent for a highlight half-angle in degrees, as SPD derives it
 * (0 or less: 100000; 90 or more: 1). */
SPD_HIDDEN double spd_phong(double angle_deg);

/* --- emitting (mirrors lib_output_*; all check the failed flag) --------- */

SPD_HIDDEN void spd_background(spd_sink *s, double r, double g, double b);
SPD_HIDDEN void spd_view(spd_sink *s, const double from[3], const double at[3],
                         const double up[3], double angle, double hither, int resx,
                         int resy);
SPD_HIDDEN void spd_light(spd_sink *s, const double pos[3]);
/* SPD's lib_output_color arguments: ambient KA is not part of NFF and is
 * ignored; KS_SPEC likewise; ANG is the highlight half-angle in degrees. */
SPD_HIDDEN void spd_color(spd_sink *s, const double rgb[3], double ka, double kd, double ks,
                          double ks_spec, double ang, double kt, double ior);
/* C: x, y, z, radius. With s->tess set: the patches of the tessellation. */
SPD_HIDDEN void spd_sphere(spd_sink *s, const double c[4]);
/* BASE, APEX: x, y, z, radius. With s->tess set: the patches. */
SPD_HIDDEN void spd_cylcone(spd_sink *s, const double base[4], const double apex[4]);
/* Like lib_output_polygon: first collapses adjacent vertices closer than
 * SPD_EPSILON2 (editing V in place, as SPD does) and drops the polygon when
 * fewer than 3 remain. At most 1024 vertices (SPD's largest is 144). */
SPD_HIDDEN void spd_polygon(spd_sink *s, int n, double (*v)[3]);
/* Like lib_output_polypatch: SPD splits the patch into triangles. */
SPD_HIDDEN void spd_polypatch(spd_sink *s, int n, double (*v)[3], double (*nrm)[3]);

/* --- SPD's transform stack: a generator keeps the current matrix itself
 * (pushing = copying it); each call below pre-multiplies, as libtx does. */

SPD_HIDDEN int spd_tx_active(spd_mat m); /* differs from the identity */
SPD_HIDDEN void spd_tx_rotate(spd_mat m, int axis, double angle);
SPD_HIDDEN void spd_tx_scale(spd_mat m, const double sc[3]);
SPD_HIDDEN void spd_tx_translate(spd_mat m, const double t[3]);
/* spd_sphere / spd_cylcone through transform M: centres are transformed,
 * radii scaled by the matrix's x scale factor (SPD assumes uniform scaling). */
SPD_HIDDEN void spd_sphere_tx(spd_sink *s, const double c[4], spd_mat m);
SPD_HIDDEN void spd_cylcone_tx(spd_sink *s, const double base[4], const double apex[4],
                               spd_mat m);
/* spd_polypatch through transform M (a triangle). */
SPD_HIDDEN void spd_polypatch_tx(spd_sink *s, int n, double (*v)[3], double (*nrm)[3],
                                 spd_mat m);

/* --- the generators -------------------------------------------------------- */

typedef void (*spd_generator)(int size, spd_sink *out);

/* The primitives GEN at SIZE makes under the tessellation TESS (NULL: none),
 * counted without making them; the count stops a little past
 * SPD_MAX_PRIMS. */
SPD_HIDDEN size_t spd_count(spd_generator gen, int size, const spd_tess *tess);

SPD_HIDDEN void spd_gen_balls(int size, spd_sink *out);
SPD_HIDDEN void spd_gen_tetra(int size, spd_sink *out);
SPD_HIDDEN void spd_gen_tree(int size, spd_sink *out);
SPD_HIDDEN void spd_gen_rings(int size, spd_sink *out);
SPD_HIDDEN void spd_gen_gears(int size, spd_sink *out);
SPD_HIDDEN void spd_gen_mount(int size, spd_sink *out);
SPD_HIDDEN void spd_gen_lattice(int size, spd_sink *out);
SPD_HIDDEN void spd_gen_shells(int size, spd_sink *out);
SPD_HIDDEN void spd_gen_jacks(int size, spd_sink *out);
SPD_HIDDEN void spd_gen_sombrero(int size, spd_sink *out);
SPD_HIDDEN void spd_gen_teapot(int size, spd_sink *out);
SPD_HIDDEN void spd_gen_sample(int size, spd_sink *out);
SPD_HIDDEN void spd_gen_nurbtst(int size, spd_sink *out);

/* --- entry points ------------------------------------------------------- */

/* Builds the scene for SPEC, "spd:NAME[:SIZE][:tN]" (NAME is matched
 * without regard to case; tN, or TN, tessellates at level N as above). An
 * unknown name, a size outside the scene's range or a bad tessellation is
 * BSP_ERR_INVALID with a message naming the known scenes or the valid
 * range. On success *OUT owns a new scene; on failure it is NULL. */
SPD_HIDDEN bsp_status spd_scene_generate_spec(const char *spec, bsp_scene **out,
                                              bsp_error *err);

/* The checks of spd_scene_generate_spec without the scene: BSP_OK when SPEC
 * names a scene it would build, else its error. */
SPD_HIDDEN bsp_status spd_spec_check(const char *spec, bsp_error *err);

#endif /* BSPRAY_SPD_H */
