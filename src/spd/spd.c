/*
 * spd.c — the SPD scene registry ("spd:NAME[:SIZE][:tN]"), the two sinks (one
 * builds a bsp_scene through the public add_* calls, one prints NFF text the
 * way the SPD programs do) and the entry points declared in spd.h.
 */
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "scene/scene_internal.h"
#include "spd/spd.h"

/* --- registry -------------------------------------------------------------- */

typedef struct spd_entry {
    const char *name;
    int def, min, max; /* size factors; max keeps scenes under ~10^8 primitives */
    spd_generator gen;
} spd_entry;

/* In priority order (balls is the project's default scene). The defaults are
 * the SPD programs' own; every entry reproduces the reference NFF file of
 * its program (../shared/scenes/spd) exactly. */
static const spd_entry registry[] = {
    /* 9^0 + ... + 9^SF spheres: SF 8 gives 48 million */
    {"balls", 4, 1, 8, spd_gen_balls},
    /* 4^SF triangles: SF 13 gives 67 million */
    {"tetra", 6, 1, 13, spd_gen_tetra},
    /* 2^(SF+1) - 1 cones and as many spheres: SF 24 gives 67 million in all */
    {"tree", 11, 1, 24, spd_gen_tree},
    /* 10 SF (SF+1) (2 SF+1) + 1 primitives: SF 170 gives 99 million */
    {"rings", 7, 1, 170, spd_gen_rings},
    /* 146 SF^3 + 1 polygons: SF 88 gives 99.5 million */
    {"gears", 4, 1, 88, spd_gen_gears},
    /* 2 * 4^SF + 4: the original hash shifts by 7 - SF bits, so SF <= 7 */
    {"mount", 6, 1, 7, spd_gen_mount},
    /* (SF+1)^3 spheres + 3 SF (SF+1)^2 cylinders: SF 290 gives 99 million */
    {"lattice", 12, 1, 290, spd_gen_lattice},
    /* 64 SF^2 - 8 SF triangles + SF^2 squares: SF 1240 gives 99.9 million */
    {"teapot", 6, 1, 1240, spd_gen_teapot},
    /* 180 * 2^SF + 1 spheres: SF 19 gives 94 million */
    {"shells", 5, 1, 19, spd_gen_shells},
    /* 9 (8^SF - 1) / 7 primitives: SF 8 gives 21.6 million (SF 9: 173 million) */
    {"jacks", 1, 1, 8, spd_gen_jacks},
    /* 2 (32 * 2^(SF-1) - 1)^2 triangles: SF 8 gives 33.5 million */
    {"sombrero", 1, 1, 8, spd_gen_sombrero},
    /* fixed: 864 patch triangles, 16 triangles, 1 cone (SPD ignores the size) */
    {"sample", 1, 1, 1, spd_gen_sample},
    /* fixed: 1500 patch triangles (SPD ignores the size) */
    {"nurbtst", 1, 1, 1, spd_gen_nurbtst},
};

#define REGISTRY_COUNT (sizeof registry / sizeof registry[0])

static const spd_entry *find_entry(const char *name, size_t len)
{
    for (size_t i = 0; i < REGISTRY_COUNT; i++)
        if (strlen(registry[i].name) == len && strncasecmp(registry[i].name, name, len) == 0)
            return &registry[i];
    return NULL;
}

/* The names joined by spaces, made once: pthread_once, since the first
 * calls may come from several threads at once (each loading a scene). */
static char scene_names[256];
static pthread_once_t scene_names_once = PTHREAD_ONCE_INIT;

static void make_scene_names(void)
{
    size_t used = 0;
    for (size_t i = 0; i < REGISTRY_COUNT; i++) {
        int n = snprintf(scene_names + used, sizeof scene_names - used, "%s%s", i ? " " : "",
                         registry[i].name);
        if (n < 0 || (size_t)n >= sizeof scene_names - used)
            break;
        used += (size_t)n;
    }
}

const char *bsp_spd_scene_names(void)
{
    pthread_once(&scene_names_once, make_scene_names);
    return scene_names;
}

int bsp_spd_scene_sizes(const char *name, int *def, int *min, int *max)
{
    const spd_entry *e = name ? find_entry(name, strlen(name)) : NULL;
    if (!e)
        return 0;
    if (def)
        *def = e->def;
    if (min)
        *min = e->min;
    if (max)
        *max = e->max;
    return 1;
}

static bsp_status unknown_name(bsp_error *err, const char *name, size_t len)
{
    return error_set(err, BSP_ERR_INVALID, NULL, 0,
                     "unknown SPD scene '%.*s' (known scenes: %s)", (int)(len > 64 ? 64 : len),
                     name, bsp_spd_scene_names());
}

static bsp_status bad_size(bsp_error *err, const spd_entry *e, const char *size_text)
{
    if (e->min == e->max)
        return error_set(err, BSP_ERR_INVALID, NULL, 0,
                         "SPD scene '%s': bad size factor '%s' (this scene has a fixed size; "
                         "the only valid size is %d)",
                         e->name, size_text, e->min);
    return error_set(err, BSP_ERR_INVALID, NULL, 0,
                     "SPD scene '%s': bad size factor '%s' (valid sizes are %d to %d; "
                     "the default is %d)",
                     e->name, size_text, e->min, e->max, e->def);
}

static bsp_status bad_tess(bsp_error *err, const spd_entry *e, const char *text)
{
    return error_set(err, BSP_ERR_INVALID, NULL, 0,
                     "SPD scene '%s': bad tessellation '%.32s' (expected tN with a level N "
                     "from %d to %d, as in spd:%s:%d:t8 or spd:%s:t8)",
                     e->name, text, SPD_TESS_MIN, SPD_TESS_MAX, e->name, e->def, e->name);
}

/* Parses a decimal size factor (digits only) into *SIZE. */
static int parse_size(const char *text, int *size)
{
    if (!*text || strlen(text) > 9)
        return 0;
    long v = 0;
    for (const char *p = text; *p; p++) {
        if (*p < '0' || *p > '9')
            return 0;
        v = v * 10 + (*p - '0');
    }
    *size = (int)v;
    return 1;
}

/* --- the scene sink -------------------------------------------------------- */

/* The double that strtod returns for printf("%g", x): x rounded to six
 * significant digits, then correctly rounded back to binary. The scene sink
 * passes every number through it, so that spd:NAME is exactly the scene its
 * SPD file describes (and renders with the very same rays). The fast path
 * scales by an exact power of ten in long double and rounds; near a decimal
 * tie, or out of the exact range, it asks snprintf/strtod themselves. */
static double round_g6(double x)
{
    if (x == 0.0 || !isfinite(x))
        return x;
    double ax = fabs(x);
    int e = (int)floor(log10(ax));
    for (int attempt = 0; attempt < 2; attempt++) {
        int k = 5 - e; /* the six digits are ax * 10^k, in [99999.5, 999999.5) */
        if (k < -22 || k > 22)
            break;
        long double p10 = 1.0L;
        for (int i = 0; i < (k < 0 ? -k : k); i++)
            p10 *= 10.0L; /* exact: 10^22 needs 52 bits of mantissa */
        long double scaled = k >= 0 ? (long double)ax * p10 : (long double)ax / p10;
        if (scaled >= 999999.5L) {
            e++;
            continue;
        }
        if (scaled < 99999.5L) {
            e--;
            continue;
        }
        long double frac = scaled - floorl(scaled);
        if (fabsl(frac - 0.5L) < 1e-6L)
            break; /* too close to a tie to trust */
        double m = (double)(frac < 0.5L ? floorl(scaled) : floorl(scaled) + 1.0L);
        double p = (double)p10; /* exact */
        double r = k >= 0 ? m / p : m * p; /* one correctly rounded operation */
        return copysign(r, x);
    }
    char buf[64];
    snprintf(buf, sizeof buf, "%g", x);
    return strtod(buf, NULL);
}

static bsp_vec3 round_v(bsp_vec3 v)
{
    return bsp_v3(round_g6(v.x), round_g6(v.y), round_g6(v.z));
}

/* Polygons can be large; rounded copies go through this buffer. */
#define SINK_MAX_VERTS 4096

typedef struct scene_ctx {
    bsp_scene *scene;
    bsp_error *err;
} scene_ctx;

/* The scene's add_* calls already wrote their message into the error. */
static void scene_check(spd_sink *s, bsp_status st)
{
    if (st != BSP_OK && s->failed == BSP_OK)
        s->failed = st;
}

static void sc_background(spd_sink *s, const double rgb[3])
{
    double r[3] = {round_g6(rgb[0]), round_g6(rgb[1]), round_g6(rgb[2])};
    bsp_scene_set_background(((scene_ctx *)s->ctx)->scene, r);
}

static void sc_view(spd_sink *s, bsp_vec3 from, bsp_vec3 at, bsp_vec3 up, double angle,
                    double hither, int resx, int resy)
{
    scene_ctx *c = s->ctx;
    bsp_camera cam;
    cam.from = round_v(from);
    cam.at = round_v(at);
    cam.up = round_v(up);
    cam.angle_deg = round_g6(angle);
    cam.hither = round_g6(hither);
    cam.res_x = resx;
    cam.res_y = resy;
    scene_check(s, bsp_scene_set_camera(c->scene, &cam, c->err));
}

static void sc_light(spd_sink *s, bsp_vec3 pos)
{
    scene_ctx *c = s->ctx;
    bsp_light l;
    l.pos = round_v(pos);
    l.color[0] = l.color[1] = l.color[2] = 1.0;
    l.has_color = 0;
    scene_check(s, bsp_scene_add_light(c->scene, &l, c->err));
}

static void sc_material(spd_sink *s, const double rgb[3], double kd, double ks, double shine,
                        double t, double ior)
{
    scene_ctx *c = s->ctx;
    bsp_material m;
    m.color[0] = round_g6(rgb[0]);
    m.color[1] = round_g6(rgb[1]);
    m.color[2] = round_g6(rgb[2]);
    m.kd = round_g6(kd);
    m.ks = round_g6(ks);
    m.shine = round_g6(shine);
    m.t = round_g6(t);
    m.ior = round_g6(ior);
    m.two_sided = 0;
    scene_check(s, bsp_scene_set_material(c->scene, &m, c->err));
}

static void sc_sphere(spd_sink *s, bsp_vec3 center, double radius)
{
    scene_ctx *c = s->ctx;
    scene_check(s, bsp_scene_add_sphere(c->scene, round_v(center), round_g6(radius), c->err));
}

static void sc_cone(spd_sink *s, bsp_vec3 base, double rb, bsp_vec3 apex, double ra)
{
    scene_ctx *c = s->ctx;
    scene_check(s, bsp_scene_add_cone(c->scene, round_v(base), round_g6(rb), round_v(apex),
                                      round_g6(ra), c->err));
}

static void sc_polygon(spd_sink *s, const bsp_vec3 *v, int n)
{
    scene_ctx *c = s->ctx;
    bsp_vec3 r[SINK_MAX_VERTS];
    if (n > SINK_MAX_VERTS || n < 0) {
        scene_check(s, error_set(c->err, BSP_ERR_LIMIT, NULL, 0, "polygon with %d vertices", n));
        return;
    }
    for (int i = 0; i < n; i++)
        r[i] = round_v(v[i]);
    scene_check(s, bsp_scene_add_polygon(c->scene, r, (size_t)n, c->err));
}

static void sc_patch(spd_sink *s, const bsp_vec3 *v, const bsp_vec3 *nrm, int n)
{
    scene_ctx *c = s->ctx;
    bsp_vec3 r[SINK_MAX_VERTS], rn[SINK_MAX_VERTS];
    if (n > SINK_MAX_VERTS || n < 0) {
        scene_check(s, error_set(c->err, BSP_ERR_LIMIT, NULL, 0, "patch with %d vertices", n));
        return;
    }
    for (int i = 0; i < n; i++) {
        r[i] = round_v(v[i]);
        rn[i] = round_v(nrm[i]);
    }
    scene_check(s, bsp_scene_add_patch(c->scene, r, rn, (size_t)n, c->err));
}

/* --- the counting sink: a tessellated scene's size before it is made ---------- */

typedef struct count_ctx {
    const spd_tess *tess;
    size_t n;
} count_ctx;

/* The count so far plus K; past SPD_MAX_PRIMS the generator is stopped. */
static void count_add(spd_sink *s, size_t k)
{
    count_ctx *c = s->ctx;
    c->n += k;
    if (c->n > SPD_MAX_PRIMS)
        spd_fail(s, BSP_ERR_LIMIT, "too many primitives");
}

static void ct_background(spd_sink *s, const double rgb[3])
{
    (void)s, (void)rgb;
}

static void ct_view(spd_sink *s, bsp_vec3 from, bsp_vec3 at, bsp_vec3 up, double angle,
                    double hither, int resx, int resy)
{
    (void)s, (void)from, (void)at, (void)up, (void)angle, (void)hither, (void)resx, (void)resy;
}

static void ct_light(spd_sink *s, bsp_vec3 pos)
{
    (void)s, (void)pos;
}

static void ct_material(spd_sink *s, const double rgb[3], double kd, double ks, double shine,
                        double t, double ior)
{
    (void)s, (void)rgb, (void)kd, (void)ks, (void)shine, (void)t, (void)ior;
}

static void ct_sphere(spd_sink *s, bsp_vec3 center, double radius)
{
    const spd_tess *t = ((count_ctx *)s->ctx)->tess;
    count_add(s, t ? spd_tess_sphere_count(t, center, radius) : 1);
}

static void ct_cone(spd_sink *s, bsp_vec3 base, double rb, bsp_vec3 apex, double ra)
{
    const spd_tess *t = ((count_ctx *)s->ctx)->tess;
    count_add(s, t ? spd_tess_cone_count(t, base, rb, apex, ra) : 1);
}

static void ct_polygon(spd_sink *s, const bsp_vec3 *v, int n)
{
    (void)v, (void)n;
    count_add(s, 1);
}

static void ct_patch(spd_sink *s, const bsp_vec3 *v, const bsp_vec3 *nrm, int n)
{
    (void)v, (void)nrm, (void)n;
    count_add(s, 1);
}

size_t spd_count(spd_generator gen, int size, const spd_tess *tess)
{
    count_ctx ctx = {tess, 0};
    /* the sink does not tessellate: its sphere and cone count what the
     * tessellation would make of them */
    spd_sink sink = {.ctx = &ctx,
                     .failed = BSP_OK,
                     .gen_error = NULL,
                     .tess = NULL,
                     .background = ct_background,
                     .view = ct_view,
                     .light = ct_light,
                     .material = ct_material,
                     .sphere = ct_sphere,
                     .cone = ct_cone,
                     .polygon = ct_polygon,
                     .patch = ct_patch};
    gen(size, &sink);
    return ctx.n;
}

/* Refuses a tessellated scene of more than SPD_MAX_PRIMS primitives, counted
 * first (a second pass of the generator that stores nothing: cheap next to
 * making the scene, and stopped as soon as the count passes the limit). */
static bsp_status check_tess_size(const spd_entry *e, int size, const spd_tess *tess,
                                  bsp_error *err)
{
    if (!tess || spd_count(e->gen, size, tess) <= SPD_MAX_PRIMS)
        return BSP_OK;
    return error_set(err, BSP_ERR_LIMIT, NULL, 0,
                     "spd:%s:%d:t%d: the tessellation would make more than %u primitives "
                     "(level %d makes %zu triangles of a sphere, %d of a cone): choose a "
                     "smaller size or level",
                     e->name, size, tess->slices, SPD_MAX_PRIMS, tess->slices,
                     spd_tess_sphere_triangles(tess), 2 * tess->slices);
}

/* Parses "tN" (or "TN") into T; returns 0 when TEXT is not that or N is
 * out of range. */
static int parse_tess(const char *text, spd_tess *t)
{
    int level;
    return (text[0] == 't' || text[0] == 'T') && parse_size(text + 1, &level) &&
           spd_tess_init(t, level);
}

/* Parses SPEC ("spd:NAME[:SIZE][:tN]") into its entry, size and
 * tessellation (*TP: TESS, or NULL for none), and checks that the scene it
 * names may be built (the size's range, the tessellated size's limit). */
static bsp_status parse_spec(const char *spec, const spd_entry **entry, int *size_out,
                             spd_tess *tess, const spd_tess **tp_out, bsp_error *err)
{
    if (!spec)
        return error_set(err, BSP_ERR_INVALID, NULL, 0, "spd: no scene specification given");
    if (strncmp(spec, "spd:", 4) != 0)
        return error_set(err, BSP_ERR_INVALID, NULL, 0,
                         "'%.64s' is not an SPD scene (expected spd:NAME[:SIZE][:tN]; "
                         "known scenes: %s)",
                         spec, bsp_spd_scene_names());
    const char *name = spec + 4;
    const char *colon = strchr(name, ':');
    size_t len = colon ? (size_t)(colon - name) : strlen(name);
    const spd_entry *e = find_entry(name, len);
    if (!e)
        return unknown_name(err, name, len);
    /* up to two fields after the name: SIZE, tN, or SIZE:tN */
    int size = e->def;
    const spd_tess *tp = NULL;
    if (colon) {
        const char *field = colon + 1, *next = strchr(field, ':');
        if (!next && (field[0] == 't' || field[0] == 'T')) {
            next = field; /* spd:NAME:tN */
        } else {
            char size_text[32];
            size_t n = next ? (size_t)(next - field) : strlen(field);
            snprintf(size_text, sizeof size_text, "%.*s", (int)(n < 31 ? n : 31), field);
            if (n > 31 || !parse_size(size_text, &size) || size < e->min || size > e->max)
                return bad_size(err, e, n > 31 ? field : size_text);
            if (next)
                next++;
        }
        if (next) {
            if (!parse_tess(next, tess))
                return bad_tess(err, e, next);
            tp = tess;
        }
    }
    bsp_status big = check_tess_size(e, size, tp, err);
    if (big != BSP_OK)
        return big;
    *entry = e;
    *size_out = size;
    *tp_out = tp;
    return BSP_OK;
}

bsp_status spd_spec_check(const char *spec, bsp_error *err)
{
    const spd_entry *e;
    int size;
    spd_tess tess;
    const spd_tess *tp;
    return parse_spec(spec, &e, &size, &tess, &tp, err);
}

bsp_status spd_scene_generate_spec(const char *spec, bsp_scene **out, bsp_error *err)
{
    if (out)
        *out = NULL;
    if (!out)
        return error_set(err, BSP_ERR_INVALID, NULL, 0, "spd: no scene specification given");
    const spd_entry *e;
    int size;
    spd_tess tess;
    const spd_tess *tp;
    bsp_status st = parse_spec(spec, &e, &size, &tess, &tp, err);
    if (st != BSP_OK)
        return st;
    bsp_scene *scene = bsp_scene_create();
    if (!scene)
        return error_set(err, BSP_ERR_NOMEM, NULL, 0, "spd:%s: out of memory", e->name);
    scene_ctx ctx = {scene, err};
    spd_sink sink = {.ctx = &ctx,
                     .failed = BSP_OK,
                     .gen_error = NULL,
                     .tess = tp,
                     .background = sc_background,
                     .view = sc_view,
                     .light = sc_light,
                     .material = sc_material,
                     .sphere = sc_sphere,
                     .cone = sc_cone,
                     .polygon = sc_polygon,
                     .patch = sc_patch};
    e->gen(size, &sink);
    if (sink.failed != BSP_OK) {
        bsp_scene_destroy(scene);
        if (sink.gen_error) {
            error_set(err, sink.failed, NULL, 0, "spd:%s:%d: %s", e->name, size,
                      sink.gen_error);
        } else if (err) { /* the scene's own message (e.g. out of memory): name the scene */
            char msg[BSP_ERROR_MESSAGE_SIZE];
            snprintf(msg, sizeof msg, "%s", err->message);
            error_set(err, sink.failed, NULL, 0, "spd:%s:%d: %s", e->name, size, msg);
        }
        return sink.failed;
    }
    scene_finish(scene);
    *out = scene;
    return BSP_OK;
}

/* --- the NFF text sink ------------------------------------------------------ */

static void nff_check(spd_sink *s, int printed)
{
    if (printed < 0 && s->failed == BSP_OK)
        s->failed = BSP_ERR_IO;
}

static void nf_background(spd_sink *s, const double rgb[3])
{
    nff_check(s, fprintf(s->ctx, "b %g %g %g\n", rgb[0], rgb[1], rgb[2]));
}

static void nf_view(spd_sink *s, bsp_vec3 from, bsp_vec3 at, bsp_vec3 up, double angle,
                    double hither, int resx, int resy)
{
    nff_check(s, fprintf(s->ctx,
                         "v\nfrom %g %g %g\nat %g %g %g\nup %g %g %g\nangle %g\nhither %g\n"
                         "resolution %d %d\n",
                         from.x, from.y, from.z, at.x, at.y, at.z, up.x, up.y, up.z, angle,
                         hither, resx, resy));
}

static void nf_light(spd_sink *s, bsp_vec3 pos)
{
    nff_check(s, fprintf(s->ctx, "l %g %g %g\n", pos.x, pos.y, pos.z));
}

static void nf_material(spd_sink *s, const double rgb[3], double kd, double ks, double shine,
                        double t, double ior)
{
    nff_check(s, fprintf(s->ctx, "f %g %g %g %g %g %g %g %g\n", rgb[0], rgb[1], rgb[2], kd, ks,
                         shine, t, ior));
}

static void nf_sphere(spd_sink *s, bsp_vec3 c, double r)
{
    nff_check(s, fprintf(s->ctx, "s %g %g %g %g\n", c.x, c.y, c.z, r));
}

static void nf_cone(spd_sink *s, bsp_vec3 b, double rb, bsp_vec3 a, double ra)
{
    nff_check(s, fprintf(s->ctx, "c %g %g %g %g %g %g %g %g\n", b.x, b.y, b.z, rb, a.x, a.y,
                         a.z, ra));
}

static void nf_polygon(spd_sink *s, const bsp_vec3 *v, int n)
{
    nff_check(s, fprintf(s->ctx, "p %d\n", n));
    for (int i = 0; i < n; i++)
        nff_check(s, fprintf(s->ctx, "%g %g %g\n", v[i].x, v[i].y, v[i].z));
}

static void nf_patch(spd_sink *s, const bsp_vec3 *v, const bsp_vec3 *nrm, int n)
{
    nff_check(s, fprintf(s->ctx, "pp %d\n", n));
    for (int i = 0; i < n; i++)
        nff_check(s, fprintf(s->ctx, "%g %g %g %g %g %g\n", v[i].x, v[i].y, v[i].z, nrm[i].x,
                             nrm[i].y, nrm[i].z));
}

bsp_status bsp_spd_write_nff(const char *name, int size, int tessellate, FILE *out,
                             bsp_error *err)
{
    if (!name || !out)
        return error_set(err, BSP_ERR_INVALID, NULL, 0, "spd: no scene name or no output");
    const spd_entry *e = find_entry(name, strlen(name));
    if (!e)
        return unknown_name(err, name, strlen(name));
    if (size == 0)
        size = e->def;
    if (size < e->min || size > e->max) {
        char text[32];
        snprintf(text, sizeof text, "%d", size);
        return bad_size(err, e, text);
    }
    spd_tess tess;
    if (tessellate != 0 && !spd_tess_init(&tess, tessellate)) {
        char text[32];
        snprintf(text, sizeof text, "t%d", tessellate);
        return bad_tess(err, e, text);
    }
    bsp_status big = check_tess_size(e, size, tessellate ? &tess : NULL, err);
    if (big != BSP_OK)
        return big;
    spd_sink sink = {.ctx = out,
                     .failed = BSP_OK,
                     .gen_error = NULL,
                     .tess = tessellate ? &tess : NULL,
                     .background = nf_background,
                     .view = nf_view,
                     .light = nf_light,
                     .material = nf_material,
                     .sphere = nf_sphere,
                     .cone = nf_cone,
                     .polygon = nf_polygon,
                     .patch = nf_patch};
    e->gen(size, &sink);
    if (sink.gen_error)
        return error_set(err, sink.failed, NULL, 0, "spd:%s:%d: %s", e->name, size,
                         sink.gen_error);
    if (sink.failed != BSP_OK || ferror(out))
        return error_set(err, BSP_ERR_IO, NULL, 0, "spd:%s:%d: writing the NFF text failed",
                         e->name, size);
    return BSP_OK;
}
