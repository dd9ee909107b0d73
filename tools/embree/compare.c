/*
 * compare.c — bspray-embree: primary-ray throughput of bspray against Intel
 * Embree 3 on the same rays, in the same run (issue #3's target: bspray at
 * least half of Embree's single-threaded rate). Built only by
 * `make embree-compare`; see docs/embree.md.
 *
 * Per scene: load it, build bspray's default structure (SAH kd-tree with
 * mailboxes, what `bspray bench` times) and an Embree scene of the same
 * surfaces (high-quality BVH, robust flag off); record the primary rays of a
 * RES x RES render (SPD sampling) with the renderer's ray log; check that the
 * two agree ray by ray; then time both on every ray, round by round, in
 * slices of 4096 rays that go through both methods in turn (alternating
 * which goes first), and keep each one's best round. Times are
 * the thread's CPU time, so a descheduled thread is not charged on a shared
 * machine; both run in one thread, one ray per call (rtcIntersect1 with an
 * incoherent context, bsp_intersect).
 *
 * Surfaces: triangles (three-vertex polygons and patches) as Embree
 * triangles; polygons of four or more vertices as triangles too, by a fan
 * when convex in bspray's projection plane, else by ear clipping, with their
 * vertices moved onto the plane bspray intersects; spheres and open cones
 * (NFF c) as Embree user geometry whose callbacks solve bspray's equations in
 * double precision on Embree's float rays.
 */
#include <embree3/rtcore.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bspray/bspray.h"

static const char *prog = "bspray-embree";

/* The 13 SPD scenes in the order of `bspray bench` (tools/bench.c). */
static const char *const default_scenes[] = {
    "spd:lattice",  "spd:rings",     "spd:tree",   "spd:balls",  "spd:gears",
    "spd:mount",    "spd:teapot:12", "spd:tetra",  "spd:shells", "spd:jacks",
    "spd:sombrero", "spd:sample",    "spd:nurbtst"};
#define DEFAULT_SCENE_COUNT (sizeof default_scenes / sizeof default_scenes[0])

/* Hits agree when their t differ by at most this much relative to bspray's. */
#define T_REL_TOL 1e-6
/* More disagreement than this (as a share of the rays) means a conversion bug. */
#define MAX_DISAGREEMENT 0.01

static const char usage[] =
    "usage: bspray-embree [SCENE...] [--res N] [--rounds R] [--threads N] [--csv FILE]\n"
    "                     [--by-outcome] [--twice] [--pixel-order rows|tiles]\n"
    "                     [--accel METHOD] [--rays primary|shadow]\n"
    "\n"
    "Primary-ray throughput of bspray (SAH kd-tree, mailboxes: what `bspray bench`\n"
    "times) against Embree 3 (high-quality BVH, robust off, rtcIntersect1,\n"
    "incoherent context; spheres and cones as exact user geometry) on the same\n"
    "rays, in the same run: each round shoots every ray through both, in slices of\n"
    "4096 rays that alternate between the two; the best round of each counts.\n"
    "Single thread, CPU time. With --rays shadow, the shadow rays of the same render\n"
    "instead: occlusion queries (bsp_occluded_from, rtcOccluded1).\n"
    "\n"
    "  SCENE...       files or spd:NAME[:SIZE]; default: the 13 SPD scenes of bench\n"
    "  --res N        N x N primary rays, SPD corner sampling (default 513)\n"
    "  --rounds R     timed rounds per method (default 5)\n"
    "  --threads N    threads of both builds (default 1); rays are always shot on one\n"
    "  --csv FILE     also write one CSV row per scene to FILE\n"
    "  --by-outcome   also time the rays that hit, the rays that miss inside the\n"
    "                 scene's box and those that miss the box itself apart, as up\n"
    "                 to three more rows per scene ('NAME [hits]', 'NAME [misses in\n"
    "                 box]', 'NAME [misses off box]'; by bspray's answer and its\n"
    "                 count of cells visited), to see where the two tracers differ\n"
    "  --twice        shoot every ray twice in a row, in both tracers; the rates still\n"
    "                 count rays, so a ray's time covers both shots. Against a run\n"
    "                 without it, it shows what the second shot costs, with the\n"
    "                 ray's nodes in the caches and its branches just seen\n"
    "  --pixel-order O  the order of the rays, the same for both tracers: rows\n"
    "                 (default, the order of every earlier session: row by row of\n"
    "                 the image) or tiles (the square tiles 'bspray render' traces,\n"
    "                 each row by row)\n"
    "  --rays R       primary (default) or shadow: the shadow rays the renderer casts\n"
    "                 from the primary rays' hits to the lights (SPD rule: only to\n"
    "                 lights on a surface's front), each from its hit point at\n"
    "                 tmin = the renderer's epsilon to the light less it. bspray\n"
    "                 also leaves the ray's own primitive out, as the renderer does;\n"
    "                 Embree cannot, and relies on tmin alone (the agreement column\n"
    "                 counts where that differs). With --by-outcome the parts are\n"
    "                 'occluded' and 'clear', by bspray's answer\n"
    "  --accel METHOD bspray's structure (default sah, with its default options):\n"
    "                 any method of 'bspray render --accel' but the named variants;\n"
    "                 e.g. bvh, to set bspray's BVH against Embree's on the same\n"
    "                 kernels' answers\n"
    "  --help         this text\n"
    "\n"
    "Prints a Markdown table (progress on stderr); its last column gives bspray's\n"
    "traversal steps, cells traversed, empty cells and intersection tests per ray\n"
    "(N_TS / N_ETS / N_EETS / N_IT) of the row's rays. Exit status 1 on bad arguments or\n"
    "a scene that cannot be loaded, 2 when a scene's rays disagree on more than 1%.\n";

typedef struct options {
    const char *const *scenes;
    const char **given; /* the scenes named on the command line */
    size_t nscenes;
    int res, rounds, threads;
    const char *csv_path;
    int by_outcome; /* --by-outcome */
    int shots;      /* queries per ray in a timed pass: 1, or 2 with --twice */
    bsp_pixel_order order; /* --pixel-order: the order the rays are recorded and shot in */
    bsp_accel_kind kind;   /* --accel: bspray's structure */
    int shadow;            /* --rays shadow: occlusion queries on the shadow rays */
} options;

/* --- small utilities ---------------------------------------------------------------- */

static double cpu_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static double wall_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void *xmalloc(size_t n)
{
    void *p = malloc(n ? n : 1);
    if (!p) {
        fprintf(stderr, "%s: out of memory\n", prog);
        exit(1);
    }
    return p;
}

/* A growable array of T: p, n, cap. */
#define PUSH(arr, n, cap, value)                                                                   \
    do {                                                                                           \
        if ((n) == (cap)) {                                                                        \
            (cap) = (cap) ? 2 * (cap) : 256;                                                       \
            void *np_ = realloc((arr), (cap) * sizeof *(arr));                                     \
            if (!np_) {                                                                            \
                fprintf(stderr, "%s: out of memory\n", prog);                                      \
                exit(1);                                                                           \
            }                                                                                      \
            (arr) = np_;                                                                           \
        }                                                                                          \
        (arr)[(n)++] = (value);                                                                    \
    } while (0)

static int parse_int(const char *s, int lo, int hi, int *out)
{
    char *end;
    errno = 0;
    long v = strtol(s, &end, 10);
    if (errno || end == s || *end || v < lo || v > hi)
        return 0;
    *out = (int)v;
    return 1;
}

/* --- recording the primary rays -------------------------------------------------------- */

/* The rays of one class, appended by the renderer's ray log (this program's
 * own recorder; the render runs on one thread, so no locking). */
typedef struct ray_list {
    bsp_ray *rays;
    uint32_t *from; /* the primitive each ray leaves out (BSP_NO_PRIM: none) */
    size_t n, cap;
    bsp_ray_class cls; /* the class recorded */
} ray_list;

/* Appends RAY, leaving FROM out, to LIST. */
static void ray_list_push(ray_list *list, const bsp_ray *ray, uint32_t from)
{
    if (list->n == list->cap) {
        size_t cap = list->cap ? 2 * list->cap : 256;
        bsp_ray *r = realloc(list->rays, cap * sizeof *r);
        if (r)
            list->rays = r;
        uint32_t *f = realloc(list->from, cap * sizeof *f);
        if (f)
            list->from = f;
        if (!r || !f) {
            fprintf(stderr, "%s: out of memory\n", prog);
            exit(1);
        }
        list->cap = cap;
    }
    list->rays[list->n] = *ray;
    list->from[list->n++] = from;
}

static void ray_list_free(ray_list *list)
{
    free(list->rays);
    free(list->from);
}

static void record_class(bsp_ray_class cls, const bsp_ray *ray, uint32_t from, void *ctx)
{
    ray_list *list = ctx;
    if (cls == list->cls)
        ray_list_push(list, ray, from);
}

/* The rays of class OUT->cls (primary or shadow) of a RES x RES render of
 * ACCEL's scene (depth 0: primary and shadow rays only, the fewest that
 * still give every primary ray and its shadow rays). */
static int record_rays(const bsp_accel *accel, int res, bsp_pixel_order order, ray_list *out)
{
    bsp_render_options ro;
    bsp_render_options_defaults(&ro);
    ro.width = ro.height = res;
    ro.max_depth = 0;
    ro.threads = 1;
    ro.pixel_order = order; /* rows: screen order, as in every session before 43 */
    ro.ray_log = record_class;
    ro.ray_log_ctx = out;
    bsp_image *img = NULL;
    bsp_error err;
    if (bsp_render(accel, &ro, &img, NULL, &err) != BSP_OK) {
        fprintf(stderr, "%s: render: %s\n", prog, err.message);
        return 0;
    }
    bsp_image_destroy(img);
    return 1;
}

/* --- user geometry: spheres and cones in double precision ------------------------------ */

/* bspray's sphere (src/geom/sphere.c): |p - c|^2 = r^2. */
typedef struct user_sphere {
    double c[3], r2;
} user_sphere;

/* bspray's open cone (src/geom/cone.c): |p_perp| = r0 + slope * h, 0 <= h <= len. */
typedef struct user_cone {
    double base[3], axis[3]; /* axis: unit, base to apex */
    double len, r0, slope;
} user_cone;

/* What a user geometry's callbacks see: its shapes, their bounds and the
 * bspray primitive of each. */
typedef struct user_geom {
    void *shapes; /* user_sphere[] or user_cone[] */
    struct RTCBounds *bounds;
    uint32_t *prim;
    size_t n, cap;
} user_geom;

static double dot3(const double *a, const double *b)
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* The roots t0 <= t1 of a t^2 + 2 b t + c = 0 with disc = b^2 - a c >= 0,
 * by the cancellation-free formula bspray uses. */
static void roots(double a, double b, double c, double disc, double *t0, double *t1)
{
    double q = -(b + copysign(sqrt(disc), b));
    double r0 = q != 0.0 ? q / a : 0.0, r1 = q != 0.0 ? c / q : 0.0;
    *t0 = fmin(r0, r1);
    *t1 = fmax(r0, r1);
}

/* The sphere's t along the ray O + t D in [TNEAR, TFAR], or NAN; the
 * discriminant as bspray computes it (from the closest point, stable). */
static double sphere_t(const user_sphere *s, const double *o, const double *d, double tnear,
                       double tfar)
{
    double oc[3] = {o[0] - s->c[0], o[1] - s->c[1], o[2] - s->c[2]};
    double a = dot3(d, d), b = dot3(oc, d);
    if (!(a > 0.0))
        return NAN;
    double l[3];
    for (int k = 0; k < 3; k++)
        l[k] = oc[k] - d[k] * (b / a);
    double disc = a * (s->r2 - dot3(l, l));
    if (!(disc >= 0.0))
        return NAN;
    double t0, t1;
    roots(a, b, dot3(oc, oc) - s->r2, disc, &t0, &t1);
    if (t0 >= tnear && t0 <= tfar)
        return t0;
    return t1 >= tnear && t1 <= tfar ? t1 : NAN;
}

/* A cone root at height H is on the surface when H is within [0, len] and
 * the radius there is not negative (else it is on the mirrored nappe). */
static int cone_keep(const user_cone *c, double h)
{
    return h >= 0.0 && h <= c->len && c->r0 + c->slope * h >= 0.0;
}

static double cone_t(const user_cone *c, const double *o, const double *d, double tnear,
                     double tfar)
{
    double oc[3] = {o[0] - c->base[0], o[1] - c->base[1], o[2] - c->base[2]};
    double h0 = dot3(oc, c->axis), hd = dot3(d, c->axis);
    double po[3], pd[3];
    for (int k = 0; k < 3; k++) {
        po[k] = oc[k] - c->axis[k] * h0; /* the parts perpendicular to the axis */
        pd[k] = d[k] - c->axis[k] * hd;
    }
    double ro = c->r0 + c->slope * h0, rd = c->slope * hd;
    double qa = dot3(pd, pd) - rd * rd, qb = dot3(po, pd) - ro * rd, qc = dot3(po, po) - ro * ro;
    double t0, t1;
    if (qa == 0.0) { /* parallel to the axis or a generator: linear, or no root */
        if (qb == 0.0)
            return NAN;
        t0 = t1 = -qc / (2.0 * qb);
    } else {
        double disc = qb * qb - qa * qc;
        if (!(disc >= 0.0))
            return NAN;
        roots(qa, qb, qc, disc, &t0, &t1);
    }
    if (t0 >= tnear && t0 <= tfar && cone_keep(c, h0 + t0 * hd))
        return t0;
    return t1 >= tnear && t1 <= tfar && cone_keep(c, h0 + t1 * hd) ? t1 : NAN;
}

/* Ray I of an Embree SOA packet of N rays (a plain RTCRayHit when N == 1):
 * field K of the ray part is at float index K * N + I, the hit part starts
 * after the ray's 12 fields (the layout of rtcore_ray.h). */
enum {
    F_ORG = 0,
    F_TNEAR = 3,
    F_DIR = 4,
    F_TFAR = 8,
    F_NG = 12,
    F_U = 15,
    F_V = 16,
    F_PRIM = 17,
    F_GEOM = 18,
    F_INST = 19
};

typedef double (*shape_t_fn)(const user_geom *g, unsigned prim, const double *o, const double *d,
                             double tnear, double tfar, double ng[3]);

static double sphere_hit(const user_geom *g, unsigned prim, const double *o, const double *d,
                         double tnear, double tfar, double ng[3])
{
    const user_sphere *s = (const user_sphere *)g->shapes + prim;
    double t = sphere_t(s, o, d, tnear, tfar);
    for (int k = 0; k < 3; k++)
        ng[k] = o[k] + t * d[k] - s->c[k];
    return t;
}

static double cone_hit(const user_geom *g, unsigned prim, const double *o, const double *d,
                       double tnear, double tfar, double ng[3])
{
    const user_cone *c = (const user_cone *)g->shapes + prim;
    double t = cone_t(c, o, d, tnear, tfar);
    /* the gradient of |p_perp| - r(h), scaled by r(h) = |p_perp| at a hit:
     * p_perp - slope r(h) axis (no square root) */
    double p[3];
    for (int k = 0; k < 3; k++)
        p[k] = o[k] + t * d[k] - c->base[k];
    double h = dot3(p, c->axis), tilt = c->slope * (c->r0 + c->slope * h);
    for (int k = 0; k < 3; k++)
        ng[k] = p[k] - (h + tilt) * c->axis[k];
    return t;
}

/* The shared body of both intersect callbacks: every valid ray of the
 * packet, its closest root in [tnear, tfar] written as Embree's hit. */
static void user_intersect(const struct RTCIntersectFunctionNArguments *args, shape_t_fn hit)
{
    const user_geom *g = args->geometryUserPtr;
    unsigned n = args->N;
    float *f = (float *)args->rayhit;
    unsigned *u = (unsigned *)args->rayhit;
    for (unsigned i = 0; i < n; i++) {
        if (!args->valid[i])
            continue;
        double o[3], d[3], ng[3];
        for (int k = 0; k < 3; k++) {
            o[k] = f[(F_ORG + k) * n + i];
            d[k] = f[(F_DIR + k) * n + i];
        }
        double t = hit(g, args->primID, o, d, f[F_TNEAR * n + i], f[F_TFAR * n + i], ng);
        if (isnan(t))
            continue;
        f[F_TFAR * n + i] = (float)t;
        for (int k = 0; k < 3; k++)
            f[(F_NG + k) * n + i] = (float)ng[k];
        f[F_U * n + i] = 0.0f;
        f[F_V * n + i] = 0.0f;
        u[F_PRIM * n + i] = args->primID;
        u[F_GEOM * n + i] = args->geomID;
        u[F_INST * n + i] = args->context->instID[0];
    }
}

static void sphere_intersect_cb(const struct RTCIntersectFunctionNArguments *args)
{
    user_intersect(args, sphere_hit);
}

static void cone_intersect_cb(const struct RTCIntersectFunctionNArguments *args)
{
    user_intersect(args, cone_hit);
}

/* Occlusion: not used by the comparison, but Embree wants one per user
 * geometry; it marks a hit by setting tfar to -inf. */
static void user_occluded(const struct RTCOccludedFunctionNArguments *args, shape_t_fn hit)
{
    const user_geom *g = args->geometryUserPtr;
    unsigned n = args->N;
    float *f = (float *)args->ray;
    for (unsigned i = 0; i < n; i++) {
        double o[3], d[3], ng[3];
        for (int k = 0; k < 3; k++) {
            o[k] = f[(F_ORG + k) * n + i];
            d[k] = f[(F_DIR + k) * n + i];
        }
        if (args->valid[i] &&
            !isnan(hit(g, args->primID, o, d, f[F_TNEAR * n + i], f[F_TFAR * n + i], ng)))
            f[F_TFAR * n + i] = -INFINITY;
    }
}

static void sphere_occluded_cb(const struct RTCOccludedFunctionNArguments *args)
{
    user_occluded(args, sphere_hit);
}

static void cone_occluded_cb(const struct RTCOccludedFunctionNArguments *args)
{
    user_occluded(args, cone_hit);
}

static void user_bounds_cb(const struct RTCBoundsFunctionArguments *args)
{
    const user_geom *g = args->geometryUserPtr;
    *args->bounds_o = g->bounds[args->primID];
}

/* bspray's exact bounds, rounded outward to float so they still enclose. */
static struct RTCBounds float_bounds(bsp_box b)
{
    struct RTCBounds r;
    float *lo = &r.lower_x, *hi = &r.upper_x;
    for (int k = 0; k < 3; k++) {
        lo[k] = nextafterf((float)b.lo.v[k], -INFINITY);
        hi[k] = nextafterf((float)b.hi.v[k], INFINITY);
    }
    r.align0 = r.align1 = 0.0f;
    return r;
}

/* --- polygons as triangles ---------------------------------------------------------------- */

typedef struct tri_mesh {
    float *verts; /* x, y, z per vertex */
    size_t nverts, cap_verts;
    unsigned *index; /* 3 per triangle */
    size_t nindex, cap_index;
    uint32_t *prim; /* bspray primitive of each triangle */
    size_t ntris, cap_tris;
    size_t ear_clipped; /* concave polygons triangulated by ear clipping */
    size_t forced_ears; /* ears taken without a proper one (degenerate input) */
} tri_mesh;

static unsigned mesh_vertex(tri_mesh *m, bsp_vec3 v)
{
    unsigned id = (unsigned)(m->nverts / 3);
    for (int k = 0; k < 3; k++)
        PUSH(m->verts, m->nverts, m->cap_verts, (float)v.v[k]);
    return id;
}

static void mesh_triangle(tri_mesh *m, unsigned a, unsigned b, unsigned c, uint32_t prim)
{
    PUSH(m->index, m->nindex, m->cap_index, a);
    PUSH(m->index, m->nindex, m->cap_index, b);
    PUSH(m->index, m->nindex, m->cap_index, c);
    PUSH(m->prim, m->ntris, m->cap_tris, prim);
}

/* A polygon in bspray's frame: its vertices, the Newell normal, the mean
 * plane offset and the two projection axes (the normal's dominant axis
 * dropped) — the same construction as src/geom/polygon.c, so the plane and
 * the inside test are those bspray intersects. */
typedef struct poly {
    bsp_vec3 *v;
    size_t n;
    bsp_vec3 normal;
    double d;
    int drop, au, av;
} poly;

static void poly_frame(poly *p)
{
    bsp_vec3 o = p->v[0], nn = bsp_v3(0, 0, 0);
    for (size_t i = 0; i < p->n; i++) {
        bsp_vec3 a = p->v[i], b = p->v[i + 1 < p->n ? i + 1 : 0];
        for (int k = 0; k < 3; k++) {
            a.v[k] -= o.v[k];
            b.v[k] -= o.v[k];
        }
        nn.x += (a.y - b.y) * (a.z + b.z);
        nn.y += (a.z - b.z) * (a.x + b.x);
        nn.z += (a.x - b.x) * (a.y + b.y);
    }
    double len = sqrt(dot3(nn.v, nn.v));
    p->normal = bsp_v3(nn.x / len, nn.y / len, nn.z / len);
    double sum = 0.0;
    for (size_t i = 0; i < p->n; i++)
        sum += dot3(p->normal.v, p->v[i].v);
    p->d = sum / (double)p->n;
    double ax = fabs(p->normal.x), ay = fabs(p->normal.y), az = fabs(p->normal.z);
    p->drop = ax >= ay ? (ax >= az ? 0 : 2) : (ay >= az ? 1 : 2);
    p->au = (p->drop + 1) % 3;
    p->av = (p->drop + 2) % 3;
}

/* Moves every vertex along the dropped axis onto the mean plane: its
 * projection, which bspray's inside test uses, is unchanged, and the
 * triangles then lie on the plane bspray's hits lie on. */
static void poly_flatten(poly *p)
{
    const double *nv = p->normal.v;
    for (size_t i = 0; i < p->n; i++) {
        double *x = p->v[i].v;
        x[p->drop] = (p->d - nv[p->au] * x[p->au] - nv[p->av] * x[p->av]) / nv[p->drop];
    }
}

/* Twice the signed area of triangle (A, B, C) in the projection. */
static double cross2(const poly *p, size_t a, size_t b, size_t c)
{
    const double *pa = p->v[a].v, *pb = p->v[b].v, *pc = p->v[c].v;
    return (pb[p->au] - pa[p->au]) * (pc[p->av] - pa[p->av]) -
           (pb[p->av] - pa[p->av]) * (pc[p->au] - pa[p->au]);
}

static double signed_area2(const poly *p)
{
    double s = 0.0;
    for (size_t i = 1; i + 1 < p->n; i++)
        s += cross2(p, 0, i, i + 1);
    return s;
}

/* Convex (in the projection) when no turn goes against the winding. */
static int poly_convex(const poly *p, double orient)
{
    for (size_t i = 0; i < p->n; i++)
        if (orient * cross2(p, i, (i + 1) % p->n, (i + 2) % p->n) < 0.0)
            return 0;
    return 1;
}

/* Whether vertex Q lies inside or on triangle (A, B, C) of orientation ORIENT. */
static int in_triangle(const poly *p, size_t a, size_t b, size_t c, size_t q, double orient)
{
    return orient * cross2(p, a, b, q) >= 0.0 && orient * cross2(p, b, c, q) >= 0.0 &&
           orient * cross2(p, c, a, q) >= 0.0;
}

/* Whether corner IDX[J] of the remaining ring (M vertices) is an ear: convex
 * and with no other remaining vertex in its triangle. */
static int is_ear(const poly *p, const size_t *idx, size_t m, size_t j, double orient)
{
    size_t a = idx[(j + m - 1) % m], b = idx[j], c = idx[(j + 1) % m];
    if (!(orient * cross2(p, a, b, c) > 0.0))
        return 0;
    for (size_t k = 0; k < m; k++) {
        size_t q = idx[k];
        if (q != a && q != b && q != c && in_triangle(p, a, b, c, q, orient))
            return 0;
    }
    return 1;
}

/* Ear clipping of a simple polygon; IDS are the mesh vertex ids. */
static void ear_clip(tri_mesh *m, const poly *p, const unsigned *ids, double orient, uint32_t prim)
{
    size_t *ring = xmalloc(p->n * sizeof *ring), nr = p->n;
    for (size_t i = 0; i < nr; i++)
        ring[i] = i;
    size_t j = 0, tried = 0;
    while (nr > 3) {
        /* a full lap without an ear: degenerate input, take the corner anyway */
        int forced = tried >= nr;
        if (forced || is_ear(p, ring, nr, j, orient)) {
            m->forced_ears += (size_t)forced;
            mesh_triangle(m, ids[ring[(j + nr - 1) % nr]], ids[ring[j]], ids[ring[(j + 1) % nr]],
                          prim);
            memmove(ring + j, ring + j + 1, (nr - j - 1) * sizeof *ring);
            nr--;
            j = j % nr;
            tried = 0;
        } else {
            j = (j + 1) % nr;
            tried++;
        }
    }
    mesh_triangle(m, ids[ring[0]], ids[ring[1]], ids[ring[2]], prim);
    free(ring);
}

/* Polygon or patch PRIM as triangles. */
static void add_polygon(tri_mesh *m, const bsp_scene *scene, size_t prim)
{
    size_t n = bsp_scene_prim_vertex_count(scene, prim);
    poly p = {xmalloc(n * sizeof(bsp_vec3)), n, {{0, 0, 0}}, 0.0, 0, 0, 0};
    for (size_t i = 0; i < n; i++)
        bsp_scene_prim_vertex(scene, prim, i, &p.v[i]);
    /* a triangle is stored as such: its vertices are already bspray's surface */
    if (n > 3) {
        poly_frame(&p);
        poly_flatten(&p);
    }
    unsigned *ids = xmalloc(n * sizeof *ids);
    for (size_t i = 0; i < n; i++)
        ids[i] = mesh_vertex(m, p.v[i]);
    if (n > 3) {
        double orient = signed_area2(&p) >= 0.0 ? 1.0 : -1.0;
        if (!poly_convex(&p, orient)) {
            m->ear_clipped++;
            ear_clip(m, &p, ids, orient, (uint32_t)prim);
            n = 0; /* done */
        }
    }
    for (size_t i = 1; i + 1 < n; i++) /* the fan of a convex polygon */
        mesh_triangle(m, ids[0], ids[i], ids[i + 1], (uint32_t)prim);
    free(ids);
    free(p.v);
}

/* --- the Embree scene --------------------------------------------------------------------- */

typedef struct embree_scene {
    RTCScene scene;
    tri_mesh mesh;
    user_geom spheres, cones;
    unsigned geom_mesh, geom_spheres, geom_cones; /* RTC_INVALID_GEOMETRY_ID when absent */
    double build_seconds;
} embree_scene;

/* Appends one shape (SIZE bytes) of bspray primitive PRIM to G; the three
 * arrays grow together, so G->n indexes all of them. */
static void user_geom_push(user_geom *g, const void *shape, size_t size, const bsp_scene *scene,
                           size_t prim)
{
    if (g->n == g->cap) {
        g->cap = g->cap ? 2 * g->cap : 256;
        g->shapes = realloc(g->shapes, g->cap * size);
        g->bounds = realloc(g->bounds, g->cap * sizeof *g->bounds);
        g->prim = realloc(g->prim, g->cap * sizeof *g->prim);
        if (!g->shapes || !g->bounds || !g->prim) {
            fprintf(stderr, "%s: out of memory\n", prog);
            exit(1);
        }
    }
    memcpy((char *)g->shapes + g->n * size, shape, size);
    g->bounds[g->n] = float_bounds(bsp_scene_prim_bounds(scene, prim));
    g->prim[g->n] = (uint32_t)prim;
    g->n++;
}

static void add_sphere(user_geom *g, const bsp_scene *scene, size_t prim)
{
    bsp_vec3 c;
    double r;
    bsp_scene_prim_sphere(scene, prim, &c, &r);
    user_sphere s = {{c.x, c.y, c.z}, r * r};
    user_geom_push(g, &s, sizeof s, scene, prim);
}

static void add_cone(user_geom *g, const bsp_scene *scene, size_t prim)
{
    bsp_vec3 b, a;
    double rb, ra;
    bsp_scene_prim_cone(scene, prim, &b, &rb, &a, &ra);
    double ax[3] = {a.x - b.x, a.y - b.y, a.z - b.z}, len = sqrt(dot3(ax, ax));
    /* the sign of NFF radii only decides shading: both sides are hit */
    user_cone c = {{b.x, b.y, b.z},
                   {ax[0] / len, ax[1] / len, ax[2] / len},
                   len,
                   fabs(rb),
                   (fabs(ra) - fabs(rb)) / len};
    user_geom_push(g, &c, sizeof c, scene, prim);
}

/* Sorts every live primitive of SCENE into the mesh and the user geometries. */
static void convert_scene(embree_scene *es, const bsp_scene *scene)
{
    size_t n = bsp_scene_prim_count(scene);
    for (size_t i = 0; i < n; i++) {
        switch (bsp_scene_prim_kind(scene, i)) {
        case BSP_PRIM_SPHERE:
            add_sphere(&es->spheres, scene, i);
            break;
        case BSP_PRIM_CONE:
            add_cone(&es->cones, scene, i);
            break;
        case BSP_PRIM_POLYGON:
        case BSP_PRIM_PATCH:
            add_polygon(&es->mesh, scene, i);
            break;
        default: /* dropped: never hit by bspray either */
            break;
        }
    }
}

static unsigned attach_mesh(RTCDevice dev, RTCScene sc, const tri_mesh *m)
{
    if (m->ntris == 0)
        return RTC_INVALID_GEOMETRY_ID;
    RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
    float *v = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                       3 * sizeof(float), m->nverts / 3);
    unsigned *ix = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                           3 * sizeof(unsigned), m->ntris);
    if (!v || !ix) {
        fprintf(stderr, "%s: Embree could not allocate the triangle buffers\n", prog);
        exit(1);
    }
    memcpy(v, m->verts, m->nverts * sizeof *v);
    memcpy(ix, m->index, m->nindex * sizeof *ix);
    rtcSetGeometryBuildQuality(g, RTC_BUILD_QUALITY_HIGH);
    rtcCommitGeometry(g);
    unsigned id = rtcAttachGeometry(sc, g);
    rtcReleaseGeometry(g);
    return id;
}

static unsigned attach_user(RTCDevice dev, RTCScene sc, user_geom *ug, RTCIntersectFunctionN isect,
                            RTCOccludedFunctionN occl)
{
    if (ug->n == 0)
        return RTC_INVALID_GEOMETRY_ID;
    RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_USER);
    rtcSetGeometryUserPrimitiveCount(g, (unsigned)ug->n);
    rtcSetGeometryUserData(g, ug);
    rtcSetGeometryBoundsFunction(g, user_bounds_cb, NULL);
    rtcSetGeometryIntersectFunction(g, isect);
    rtcSetGeometryOccludedFunction(g, occl);
    rtcSetGeometryBuildQuality(g, RTC_BUILD_QUALITY_HIGH);
    rtcCommitGeometry(g);
    unsigned id = rtcAttachGeometry(sc, g);
    rtcReleaseGeometry(g);
    return id;
}

/* Builds ES from SCENE on DEV; the commit (the BVH build) is timed. */
static void embree_build(embree_scene *es, RTCDevice dev, const bsp_scene *scene)
{
    memset(es, 0, sizeof *es);
    convert_scene(es, scene);
    es->scene = rtcNewScene(dev);
    rtcSetSceneFlags(es->scene, RTC_SCENE_FLAG_NONE); /* robust off, not compact */
    rtcSetSceneBuildQuality(es->scene, RTC_BUILD_QUALITY_HIGH);
    es->geom_mesh = attach_mesh(dev, es->scene, &es->mesh);
    es->geom_spheres =
        attach_user(dev, es->scene, &es->spheres, sphere_intersect_cb, sphere_occluded_cb);
    es->geom_cones = attach_user(dev, es->scene, &es->cones, cone_intersect_cb, cone_occluded_cb);
    double t0 = wall_seconds();
    rtcCommitScene(es->scene);
    es->build_seconds = wall_seconds() - t0;
}

static void user_geom_free(user_geom *g)
{
    free(g->shapes);
    free(g->bounds);
    free(g->prim);
}

static void embree_free(embree_scene *es)
{
    rtcReleaseScene(es->scene);
    free(es->mesh.verts);
    free(es->mesh.index);
    free(es->mesh.prim);
    user_geom_free(&es->spheres);
    user_geom_free(&es->cones);
}

/* The bspray primitive of an Embree hit. */
static uint32_t embree_prim(const embree_scene *es, const struct RTCHit *h)
{
    if (h->geomID == es->geom_mesh)
        return es->mesh.prim[h->primID];
    if (h->geomID == es->geom_spheres)
        return es->spheres.prim[h->primID];
    if (h->geomID == es->geom_cones)
        return es->cones.prim[h->primID];
    return BSP_NO_PRIM;
}

/* --- shooting -------------------------------------------------------------------------------- */

/* Embree's tnear for shadow rays, relative to the scene's size: Embree
 * cannot leave the ray's own primitive out, and its float test of a ray
 * that starts on a surface errs by about 1e-7 of the coordinates, so the
 * renderer's tmin (1e-9 of the scene) would let the surface block its own
 * shadow rays. 1e-5 is a hundred times that error. */
#define EMBREE_SHADOW_TNEAR_REL 1e-5

/* The Embree form of every ray, converted once (not timed); shadow rays
 * start at least TNEAR_MIN along. */
static struct RTCRay *embree_rays(const ray_list *rl, double tnear_min)
{
    struct RTCRay *out = xmalloc(rl->n * sizeof *out);
    for (size_t i = 0; i < rl->n; i++) {
        const bsp_ray *r = &rl->rays[i];
        double tnear = rl->cls == BSP_RAY_SHADOW ? fmax(r->tmin, tnear_min) : r->tmin;
        out[i] = (struct RTCRay){(float)r->org.x, (float)r->org.y, (float)r->org.z, (float)tnear,
                                 (float)r->dir.x, (float)r->dir.y, (float)r->dir.z, 0.0f,
                                 (float)r->tmax,  0xffffffffu,     (unsigned)i,     0};
    }
    return out;
}

/* EMBREE_SHADOW_TNEAR_REL times the largest extent of ACCEL's scene. */
static double shadow_tnear(const bsp_accel *accel)
{
    bsp_box b = bsp_scene_bounds(bsp_accel_scene(accel));
    double ext = fmax(b.hi.x - b.lo.x, fmax(b.hi.y - b.lo.y, b.hi.z - b.lo.z));
    return isfinite(ext) && ext > 0.0 ? EMBREE_SHADOW_TNEAR_REL * ext : 0.0;
}

/* One Embree closest-hit query; returns the hit record (geomID invalid: miss). */
static inline void embree_shoot(RTCScene sc, const struct RTCRay *ray, struct RTCRayHit *rh)
{
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx); /* incoherent: single rays, no coherence hint */
    rh->ray = *ray;
    rh->hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh->hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(sc, &ctx, rh);
}

/* One Embree occlusion query: 1 when RAY is blocked. */
static inline int embree_blocked(RTCScene sc, const struct RTCRay *ray)
{
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    struct RTCRay r = *ray;
    rtcOccluded1(sc, &ctx, &r);
    return r.tfar < 0.0f; /* -inf once blocked */
}

/* CPU seconds of one Embree pass over every ray (closest hits, or with
 * SHADOW occlusion); *HITS counts the hits (blocked rays) so the work cannot
 * be optimised away. */
static double embree_pass(RTCScene sc, const struct RTCRay *rays, size_t n, int shots,
                          int shadow, size_t *hits)
{
    struct RTCRayHit rh;
    size_t h = 0;
    double t0 = cpu_seconds();
    for (size_t i = 0; i < n; i++) {
        for (int k = 0; k < shots; k++) {
            if (shadow) {
                h += (size_t)embree_blocked(sc, &rays[i]);
            } else {
                embree_shoot(sc, &rays[i], &rh);
                h += rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
            }
        }
    }
    double t = cpu_seconds() - t0;
    *hits = h;
    return t;
}

/* The same through bspray: rays [I, I + N) of RL. */
static double bspray_pass(const bsp_accel *accel, bsp_query *q, const ray_list *rl, size_t i0,
                          size_t n, int shots, int shadow, size_t *hits)
{
    bsp_hit hit;
    size_t h = 0;
    const bsp_ray *rays = rl->rays + i0;
    const uint32_t *from = rl->from + i0;
    double t0 = cpu_seconds();
    for (size_t i = 0; i < n; i++)
        for (int k = 0; k < shots; k++)
            h += shadow ? (size_t)bsp_occluded_from(accel, q, &rays[i], from[i])
                        : (size_t)bsp_intersect(accel, q, &rays[i], &hit);
    double t = cpu_seconds() - t0;
    *hits = h;
    return t;
}

/* --- agreement ----------------------------------------------------------------------------- */

typedef struct agreement {
    size_t rays, disagree, hit_miss, t_differs, other_prim;
    bsp_query_counters counts; /* bspray's figures over these rays */
} agreement;

/* Shoots every ray through both (untimed) and compares hit/miss and t
 * (shadow rays: blocked or not); counts bspray's figures of the rays. */
static agreement compare_rays(const embree_scene *es, const struct RTCRay *erays,
                              const bsp_accel *accel, bsp_query *q, const ray_list *rl)
{
    agreement a = {rl->n, 0, 0, 0, 0, {0}};
    bsp_query_reset_counters(q);
    if (rl->cls == BSP_RAY_SHADOW) {
        for (size_t i = 0; i < rl->n; i++)
            a.hit_miss += embree_blocked(es->scene, &erays[i]) !=
                          bsp_occluded_from(accel, q, &rl->rays[i], rl->from[i]);
        a.disagree = a.hit_miss;
        a.counts = *bsp_query_get_counters(q);
        return a;
    }
    for (size_t i = 0; i < rl->n; i++) {
        struct RTCRayHit rh;
        embree_shoot(es->scene, &erays[i], &rh);
        bsp_hit bh;
        int bhit = bsp_intersect(accel, q, &rl->rays[i], &bh);
        int ehit = rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
        if (bhit != ehit) {
            a.hit_miss++;
        } else if (bhit && !(fabs((double)rh.ray.tfar - bh.t) <= T_REL_TOL * fabs(bh.t))) {
            a.t_differs++;
        } else if (bhit && embree_prim(es, &rh.hit) != bh.prim) {
            a.other_prim++; /* the same t on another primitive: coincident surfaces */
        }
    }
    a.disagree = a.hit_miss + a.t_differs;
    a.counts = *bsp_query_get_counters(q);
    return a;
}

/* --- one scene ----------------------------------------------------------------------------- */

typedef struct result {
    const char *scene;
    const char *part; /* the rays timed: "all", or with --by-outcome "hits", "misses in box"
                         or "misses off box" */
    size_t nprims, tris, users, rays;
    double rate_embree, rate_bspray; /* Mrays/s, best round */
    double ratio_median;             /* the median over the rounds of bspray's rate over Embree's in
                                        that round (both on the same slices, so the same machine) */
    double build_embree, build_bspray; /* seconds */
    agreement agree; /* with bspray's figures of the rays (compare_rays' pass) */
    size_t ear_clipped, forced_ears;
} result;

static int cmp_double(const void *x, const void *y)
{
    double a = *(const double *)x, b = *(const double *)y;
    return (a > b) - (a < b);
}

/* Rays per slice: a round shoots the rays slice by slice, each slice through
 * both methods, so that both see the same machine (this VM's speed swings
 * within seconds; whole-pass rounds gave ratios from 0.38 to 0.51 for the
 * same code), with enough rays per slice to amortise the clock reads and the
 * cache refill after the other method's slice. */
#define SLICE_RAYS 4096

/* Best-of-R rounds; within a round the methods alternate slice by slice,
 * and which goes first alternates too. */
static void time_rounds(const options *o, const embree_scene *es, const struct RTCRay *erays,
                        const bsp_accel *accel, bsp_query *q, const ray_list *rl, result *r)
{
    double best_e = INFINITY, best_b = INFINITY;
    double *ratio = xmalloc((size_t)o->rounds * sizeof *ratio);
    size_t he = 0, hb = 0;
    for (int round = 0; round < o->rounds; round++) {
        double te = 0.0, tb = 0.0;
        he = hb = 0;
        for (size_t i = 0, k = 0; i < rl->n; i += SLICE_RAYS, k++) {
            size_t n = rl->n - i < SLICE_RAYS ? rl->n - i : SLICE_RAYS, h1, h2;
            if ((k + (size_t)round) % 2 == 0) {
                te += embree_pass(es->scene, erays + i, n, o->shots, o->shadow, &h1);
                tb += bspray_pass(accel, q, rl, i, n, o->shots, o->shadow, &h2);
            } else {
                tb += bspray_pass(accel, q, rl, i, n, o->shots, o->shadow, &h2);
                te += embree_pass(es->scene, erays + i, n, o->shots, o->shadow, &h1);
            }
            he += h1;
            hb += h2;
        }
        best_e = fmin(best_e, te);
        best_b = fmin(best_b, tb);
        ratio[round] = tb > 0.0 ? te / tb : 0.0;
        fprintf(stderr, "%s: %s [%s]: round %d: Embree %.3f s, bspray %.3f s (hits %zu / %zu)\n",
                prog, r->scene, r->part, round + 1, te, tb, he, hb);
    }
    r->rate_embree = best_e > 0.0 ? (double)rl->n / best_e * 1e-6 : 0.0;
    r->rate_bspray = best_b > 0.0 ? (double)rl->n / best_b * 1e-6 : 0.0;
    qsort(ratio, (size_t)o->rounds, sizeof *ratio, cmp_double);
    int h = o->rounds / 2;
    r->ratio_median = o->rounds % 2 ? ratio[h] : 0.5 * (ratio[h - 1] + ratio[h]);
    free(ratio);
}

static bsp_accel *build_bspray(const bsp_scene *scene, int threads, bsp_accel_kind kind)
{
    bsp_build_options bo;
    bsp_build_options_defaults(&bo); /* sah, mailboxes: what bench times */
    bo.threads = threads;
    bo.kind = kind;
    bsp_accel *accel = NULL;
    bsp_error err;
    if (bsp_accel_build(scene, &bo, &accel, &err) != BSP_OK) {
        fprintf(stderr, "%s: build: %s\n", prog, err.message);
        return NULL;
    }
    return accel;
}

/* Times three parts of RL apart, by bspray's answer and its counters: the
 * rays that hit, those that miss after crossing at least one cell of the
 * tree (inside the scene's box), and those that visit no cell (they miss
 * the box, or leave the precision domain); into R[0..] (copies of *ALL but
 * for the rays and rates). Returns how many parts had rays. */
static int time_by_outcome(const options *o, const embree_scene *es, const bsp_accel *accel,
                           bsp_query *q, const ray_list *rl, const result *all, result *r)
{
    static const char *const names[3] = {"hits", "misses in box", "misses off box"};
    static const char *const shadow_names[3] = {"occluded", "clear", ""};
    ray_list part[3] = {{.cls = rl->cls}, {.cls = rl->cls}, {.cls = rl->cls}};
    for (size_t i = 0; i < rl->n; i++) {
        bsp_hit h;
        bsp_query_reset_counters(q);
        int k;
        if (o->shadow)
            k = bsp_occluded_from(accel, q, &rl->rays[i], rl->from[i]) ? 0 : 1;
        else
            k = bsp_intersect(accel, q, &rl->rays[i], &h)            ? 0
                : bsp_query_get_counters(q)->leaves_visited ? 1
                                                            : 2;
        ray_list_push(&part[k], &rl->rays[i], rl->from[i]);
    }
    int n = 0;
    for (int k = 0; k < 3; k++) {
        if (part[k].n) {
            struct RTCRay *erays = embree_rays(&part[k], shadow_tnear(accel));
            r[n] = *all;
            r[n].part = o->shadow ? shadow_names[k] : names[k];
            r[n].rays = part[k].n;
            r[n].agree = compare_rays(es, erays, accel, q, &part[k]);
            time_rounds(o, es, erays, accel, q, &part[k], &r[n]);
            free(erays);
            n++;
        }
        ray_list_free(&part[k]);
    }
    return n;
}

/* Runs one scene into R[0] (and, with --by-outcome, the parts of its rays
 * into R[1..3]); *NROWS gets the rows filled. Returns 0, or 1 when
 * it could not run. */
static int run_scene(const options *o, RTCDevice dev, const char *name, result r[4], int *nrows)
{
    memset(r, 0, sizeof *r);
    *nrows = 0;
    r->scene = name;
    r->part = "all";
    bsp_scene *scene = NULL;
    bsp_error err;
    fprintf(stderr, "%s: %s: loading\n", prog, name);
    if (bsp_scene_load(name, &scene, &err) != BSP_OK) {
        fprintf(stderr, "%s: %s: %s\n", prog, name, err.message);
        return 1;
    }
    r->nprims = bsp_scene_prim_count(scene);
    fprintf(stderr, "%s: %s: building bspray and Embree\n", prog, name);
    bsp_accel *accel = build_bspray(scene, o->threads, o->kind);
    if (!accel) {
        bsp_scene_destroy(scene);
        return 1;
    }
    r->build_bspray = bsp_accel_build_seconds(accel);
    embree_scene es;
    embree_build(&es, dev, scene);
    r->build_embree = es.build_seconds;
    r->tris = es.mesh.ntris;
    r->users = es.spheres.n + es.cones.n;
    r->ear_clipped = es.mesh.ear_clipped;
    r->forced_ears = es.mesh.forced_ears;

    ray_list rl = {.cls = o->shadow ? BSP_RAY_SHADOW : BSP_RAY_PRIMARY};
    bsp_query *q = bsp_query_create(accel);
    int status = 1;
    if (q && record_rays(accel, o->res, o->order, &rl)) {
        r->rays = rl.n;
        struct RTCRay *erays = embree_rays(&rl, shadow_tnear(accel));
        fprintf(stderr, "%s: %s: %zu %s rays; checking agreement\n", prog, name, rl.n,
                o->shadow ? "shadow" : "primary");
        r->agree = compare_rays(&es, erays, accel, q, &rl);
        time_rounds(o, &es, erays, accel, q, &rl, r);
        free(erays);
        *nrows = 1 + (o->by_outcome ? time_by_outcome(o, &es, accel, q, &rl, r, r + 1) : 0);
        status = 0;
    }
    ray_list_free(&rl);
    bsp_query_destroy(q);
    embree_free(&es);
    bsp_accel_destroy(accel);
    bsp_scene_destroy(scene);
    return status;
}

/* --- output -------------------------------------------------------------------------------- */

static double agree_pct(const agreement *a)
{
    return a->rays ? 100.0 * (double)(a->rays - a->disagree) / (double)a->rays : 100.0;
}

static void print_header(RTCDevice dev, const options *o)
{
    ssize_t v = rtcGetDeviceProperty(dev, RTC_DEVICE_PROPERTY_VERSION);
    printf("Embree %ld.%ld.%ld: scene flags none (robust off), build quality high, "
           "%s with an incoherent context; spheres and cones as user geometry "
           "(double-precision callbacks); builds on %d thread(s).\n",
           (long)(v / 10000), (long)(v / 100 % 100), (long)(v % 100),
           o->shadow ? "rtcOccluded1" : "rtcIntersect1", o->threads);
    printf("bspray: %s build (%s, mailboxes), %s. %s of %d x %d primary rays, "
           "single thread, thread CPU time, best of %d interleaved rounds%s.\n\n",
           o->kind == BSP_ACCEL_SAH ? "default" : "--accel", bsp_accel_kind_name(o->kind),
           o->shadow ? "bsp_occluded_from" : "bsp_intersect",
           o->shadow ? "The shadow rays of a depth-0 render" : "The rays", o->res, o->res,
           o->rounds,
           o->shots == 2 ? "; every ray shot twice in a row (--twice), its time covering both"
                         : "");
    if (o->order == BSP_PIXELS_TILES)
        printf("The rays in %d x %d tiles of the image, each row by row (--pixel-order tiles).\n\n",
               BSP_RENDER_TILE, BSP_RENDER_TILE);
    printf("| scene | prims | Embree tris / user | rays | Embree Mrays/s | bspray Mrays/s "
           "| bspray/Embree | median round ratio | agree %% | build ms Embree / bspray "
           "| bspray N_TS / N_ETS / N_EETS / N_IT |\n");
    printf("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
}

/* C's figure NUM per query (0 without queries). */
static double per_ray(const bsp_query_counters *c, uint64_t num)
{
    return c->rays ? (double)num / (double)c->rays : 0.0;
}

static void print_row(const result *r)
{
    int whole = !strcmp(r->part, "all");
    const bsp_query_counters *c = &r->agree.counts;
    printf("| %s%s%s%s | %zu | %zu / %zu | %zu | %.3f | %.3f | %.2f | %.3f | %.3f | %.0f / %.0f "
           "| %.2f / %.2f / %.2f / %.2f |\n",
           r->scene, whole ? "" : " [", whole ? "" : r->part, whole ? "" : "]", r->nprims, r->tris,
           r->users, r->rays, r->rate_embree, r->rate_bspray,
           r->rate_embree > 0.0 ? r->rate_bspray / r->rate_embree : 0.0, r->ratio_median,
           agree_pct(&r->agree), 1e3 * r->build_embree, 1e3 * r->build_bspray,
           per_ray(c, c->traversal_steps), per_ray(c, c->leaves_visited),
           per_ray(c, c->empty_leaves), per_ray(c, c->isect_tests));
    fflush(stdout);
}

static const char csv_header[] =
    "scene,prims,embree_triangles,embree_user_prims,ear_clipped_polygons,rays,"
    "embree_mrays_s,bspray_mrays_s,ratio_bspray_embree,agree_pct,disagree_hit_miss,"
    "disagree_t,same_t_other_prim,build_ms_embree,build_ms_bspray,res,rounds,threads,"
    "ratio_median_round,rays_part,shots,pixel_order,ray_class,bspray_n_ts,bspray_n_ets,"
    "bspray_n_eets,bspray_n_it\n";

static void csv_row(FILE *f, const result *r, const options *o)
{
    const bsp_query_counters *c = &r->agree.counts;
    fprintf(f,
            "%s,%zu,%zu,%zu,%zu,%zu,%.4f,%.4f,%.4f,%.4f,%zu,%zu,%zu,"
            "%.3f,%.3f,%d,%d,%d,%.4f,%s,%d,%s,%s,%.4f,%.4f,%.4f,%.4f\n",
            r->scene, r->nprims, r->tris, r->users, r->ear_clipped, r->rays, r->rate_embree,
            r->rate_bspray, r->rate_embree > 0.0 ? r->rate_bspray / r->rate_embree : 0.0,
            agree_pct(&r->agree), r->agree.hit_miss, r->agree.t_differs, r->agree.other_prim,
            1e3 * r->build_embree, 1e3 * r->build_bspray, o->res, o->rounds, o->threads,
            r->ratio_median, r->part, o->shots, o->order == BSP_PIXELS_TILES ? "tiles" : "rows",
            o->shadow ? "shadow" : "primary", per_ray(c, c->traversal_steps),
            per_ray(c, c->leaves_visited), per_ray(c, c->empty_leaves),
            per_ray(c, c->isect_tests));
    fflush(f);
}

/* --- main ---------------------------------------------------------------------------------- */

/* Parses ARGV into *O; returns -1 to go on, else the exit status. */
static int parse_args(int argc, char **argv, options *o)
{
    o->given = xmalloc((size_t)argc * sizeof *o->given);
    o->scenes = o->given;
    o->nscenes = 0;
    o->res = 513;
    o->rounds = 5;
    o->threads = 1;
    o->shots = 1;
    o->kind = BSP_ACCEL_SAH;
    o->csv_path = NULL;
    o->by_outcome = 0;
    o->order = BSP_PIXELS_ROWS;
    o->shadow = 0;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        int has_value = i + 1 < argc;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            fputs(usage, stdout);
            return 0;
        } else if (!strcmp(a, "--res") && has_value) {
            if (!parse_int(argv[++i], 1, 16384, &o->res))
                return fprintf(stderr, "%s: --res wants 1..16384, not '%s'\n", prog, argv[i]), 1;
        } else if (!strcmp(a, "--rounds") && has_value) {
            if (!parse_int(argv[++i], 1, 1000, &o->rounds))
                return fprintf(stderr, "%s: --rounds wants 1..1000, not '%s'\n", prog, argv[i]), 1;
        } else if (!strcmp(a, "--threads") && has_value) {
            if (!parse_int(argv[++i], 1, 256, &o->threads))
                return fprintf(stderr, "%s: --threads wants 1..256, not '%s'\n", prog, argv[i]), 1;
        } else if (!strcmp(a, "--csv") && has_value) {
            o->csv_path = argv[++i];
        } else if (!strcmp(a, "--accel") && has_value) {
            bsp_error err;
            if (bsp_accel_kind_parse(argv[++i], &o->kind, &err) != BSP_OK)
                return fprintf(stderr, "%s: %s\n", prog, err.message), 1;
        } else if (!strcmp(a, "--twice")) {
            o->shots = 2;
        } else if (!strcmp(a, "--by-outcome")) {
            o->by_outcome = 1;
        } else if (!strcmp(a, "--rays") && has_value) {
            const char *v = argv[++i];
            if (!strcmp(v, "primary") || !strcmp(v, "shadow"))
                o->shadow = !strcmp(v, "shadow");
            else
                return fprintf(stderr, "%s: --rays wants primary or shadow, not '%s'\n", prog, v),
                       1;
        } else if (!strcmp(a, "--pixel-order") && has_value) {
            const char *v = argv[++i];
            if (!strcmp(v, "rows"))
                o->order = BSP_PIXELS_ROWS;
            else if (!strcmp(v, "tiles"))
                o->order = BSP_PIXELS_TILES;
            else
                return fprintf(stderr, "%s: --pixel-order wants rows or tiles, not '%s'\n", prog,
                               v),
                       1;
        } else if (a[0] == '-' && a[1]) {
            fprintf(stderr, "%s: unknown option or missing value: '%s'\n%s", prog, a, usage);
            return 1;
        } else {
            o->given[o->nscenes++] = a;
        }
    }
    if (o->nscenes == 0) {
        o->scenes = default_scenes;
        o->nscenes = DEFAULT_SCENE_COUNT;
    }
    return -1;
}

static void embree_error(void *user, enum RTCError code, const char *str)
{
    (void)user;
    fprintf(stderr, "%s: Embree error %d: %s\n", prog, (int)code, str ? str : "");
    exit(1);
}

/* Loads every scene first, so that a bad name fails before any timing. */
static int check_scenes(const options *o)
{
    for (size_t i = 0; i < o->nscenes; i++) {
        bsp_scene *s = NULL;
        bsp_error err;
        if (bsp_scene_load(o->scenes[i], &s, &err) != BSP_OK) {
            fprintf(stderr, "%s: %s: %s\n", prog, o->scenes[i], err.message);
            return 0;
        }
        bsp_scene_destroy(s);
    }
    return 1;
}

int main(int argc, char **argv)
{
    options o;
    int st = parse_args(argc, argv, &o);
    if (st < 0 && !check_scenes(&o))
        st = 1;
    if (st >= 0) {
        free(o.given);
        return st;
    }
    FILE *csv = NULL;
    if (o.csv_path && !(csv = fopen(o.csv_path, "w"))) {
        fprintf(stderr, "%s: %s: %s\n", prog, o.csv_path, strerror(errno));
        free(o.given);
        return 1;
    }
    if (csv)
        fputs(csv_header, csv);
    char config[64];
    snprintf(config, sizeof config, "threads=%d,verbose=0", o.threads);
    RTCDevice dev = rtcNewDevice(config);
    if (!dev) {
        fprintf(stderr, "%s: rtcNewDevice failed (error %d)\n", prog, (int)rtcGetDeviceError(NULL));
        if (csv)
            fclose(csv);
        free(o.given);
        return 1;
    }
    rtcSetDeviceErrorFunction(dev, embree_error, NULL);
    print_header(dev, &o);
    int status = 0;
    for (size_t i = 0; i < o.nscenes; i++) {
        result rows[4];
        int nrows;
        if (run_scene(&o, dev, o.scenes[i], rows, &nrows)) {
            status = 1;
            continue;
        }
        for (int k = 0; k < nrows; k++) {
            print_row(&rows[k]);
            if (csv)
                csv_row(csv, &rows[k], &o);
        }
        const result *r = &rows[0]; /* every ray; the parts are subsets of it */
        if (r->forced_ears)
            fprintf(stderr, "%s: %s: %zu ears forced in degenerate polygons\n", prog, r->scene,
                    r->forced_ears);
        if ((double)r->agree.disagree > MAX_DISAGREEMENT * (double)r->agree.rays) {
            fprintf(stderr,
                    "%s: %s: %zu of %zu rays disagree (%zu hit/miss, %zu t): more than 1%%, "
                    "a conversion bug?\n",
                    prog, r->scene, r->agree.disagree, r->agree.rays, r->agree.hit_miss,
                    r->agree.t_differs);
            if (status == 0)
                status = 2;
        }
    }
    rtcReleaseDevice(dev);
    if (csv)
        fclose(csv);
    free(o.given);
    return status;
}
