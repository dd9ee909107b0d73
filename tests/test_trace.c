/*
 * test_trace.c — naive ray shooting and the `bspray trace` interface checked
 * against an independent closest-hit computation written here (long double
 * sphere and triangle formulas that share no code with src/geom).
 */
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>

#include "bspray/bspray.h"
#include "harness.h"

/* xorshift64*: a fixed-seed generator, so failures reproduce. */
static unsigned long long rng_state;
static double rnd(void)
{
    return harness_rnd(&rng_state);
}
static double rnd_range(double lo, double hi)
{
    return lo + (hi - lo) * rnd();
}

typedef struct ref_sphere {
    long double c[3], r;
} ref_sphere;
typedef struct ref_tri {
    long double a[3], b[3], c[3];
} ref_tri;

/* Smallest root t in [tmin, tmax] or -1. */
static long double ref_sphere_hit(const ref_sphere *s, const long double o[3],
                                  const long double d[3], long double tmin, long double tmax)
{
    long double oc[3] = {o[0] - s->c[0], o[1] - s->c[1], o[2] - s->c[2]};
    long double a = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    long double b = 2 * (oc[0] * d[0] + oc[1] * d[1] + oc[2] * d[2]);
    long double c = oc[0] * oc[0] + oc[1] * oc[1] + oc[2] * oc[2] - s->r * s->r;
    long double disc = b * b - 4 * a * c;
    if (disc < 0)
        return -1;
    long double sq = sqrtl(disc);
    long double t0 = (-b - sq) / (2 * a), t1 = (-b + sq) / (2 * a);
    if (t0 >= tmin && t0 <= tmax)
        return t0;
    if (t1 >= tmin && t1 <= tmax)
        return t1;
    return -1;
}

/* Plane intersection, then inside test by the signs of three edge areas. */
static long double ref_tri_hit(const ref_tri *tr, const long double o[3], const long double d[3],
                               long double tmin, long double tmax)
{
    long double e1[3], e2[3], n[3];
    for (int k = 0; k < 3; k++) {
        e1[k] = tr->b[k] - tr->a[k];
        e2[k] = tr->c[k] - tr->a[k];
    }
    n[0] = e1[1] * e2[2] - e1[2] * e2[1];
    n[1] = e1[2] * e2[0] - e1[0] * e2[2];
    n[2] = e1[0] * e2[1] - e1[1] * e2[0];
    long double dn = n[0] * d[0] + n[1] * d[1] + n[2] * d[2];
    if (dn == 0)
        return -1;
    long double t = (n[0] * (tr->a[0] - o[0]) + n[1] * (tr->a[1] - o[1]) +
                     n[2] * (tr->a[2] - o[2])) /
                    dn;
    if (t < tmin || t > tmax)
        return -1;
    long double p[3] = {o[0] + t * d[0], o[1] + t * d[1], o[2] + t * d[2]};
    const long double *v[3] = {tr->a, tr->b, tr->c};
    for (int i = 0; i < 3; i++) {
        const long double *p0 = v[i], *p1 = v[(i + 1) % 3];
        long double ed[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]};
        long double w[3] = {p[0] - p0[0], p[1] - p0[1], p[2] - p0[2]};
        long double cr[3] = {ed[1] * w[2] - ed[2] * w[1], ed[2] * w[0] - ed[0] * w[2],
                             ed[0] * w[1] - ed[1] * w[0]};
        if (cr[0] * n[0] + cr[1] * n[1] + cr[2] * n[2] < 0)
            return -1;
    }
    return t;
}

#define NS 60
#define NT 60

typedef struct ref_scene {
    ref_sphere s[NS];
    ref_tri t[NT];
    bsp_scene *scene; /* spheres 0..NS-1, then triangles NS.. */
    char nff_path[512];
} ref_scene;

static void make_ref_scene(ref_scene *rs, uint64_t seed)
{
    rng_state = seed;
    rs->scene = bsp_scene_create();
    REQUIRE(rs->scene);
    bsp_error err;
    char path[512];
    snprintf(path, sizeof path, "%s/ref_%" PRIu64 ".nff", harness_tmpdir(), seed);
    strcpy(rs->nff_path, path);
    FILE *f = fopen(path, "w");
    REQUIRE(f);
    fprintf(f, "v\nfrom 0 0 10\nat 0 0 0\nup 0 1 0\nangle 45\nhither 1\nresolution 8 8\n");
    for (int i = 0; i < NS; i++) {
        double c[3] = {rnd_range(-4, 4), rnd_range(-4, 4), rnd_range(-4, 4)};
        double r = rnd_range(0.1, 0.8);
        for (int k = 0; k < 3; k++)
            rs->s[i].c[k] = c[k];
        rs->s[i].r = r;
        /* %.17g keeps every bit, so file and memory agree */
        fprintf(f, "s %.17g %.17g %.17g %.17g\n", c[0], c[1], c[2], r);
        REQUIRE(bsp_scene_add_sphere(rs->scene, bsp_v3(c[0], c[1], c[2]), r, &err) == BSP_OK);
    }
    for (int i = 0; i < NT; i++) {
        double base[3] = {rnd_range(-4, 4), rnd_range(-4, 4), rnd_range(-4, 4)};
        bsp_vec3 v[3];
        fprintf(f, "p 3\n");
        for (int j = 0; j < 3; j++) {
            double x = base[0] + rnd_range(-1.5, 1.5), y = base[1] + rnd_range(-1.5, 1.5),
                   z = base[2] + rnd_range(-1.5, 1.5);
            v[j] = bsp_v3(x, y, z);
            fprintf(f, "%.17g %.17g %.17g\n", x, y, z);
        }
        for (int k = 0; k < 3; k++) {
            rs->t[i].a[k] = v[0].v[k];
            rs->t[i].b[k] = v[1].v[k];
            rs->t[i].c[k] = v[2].v[k];
        }
        REQUIRE(bsp_scene_add_polygon(rs->scene, v, 3, &err) == BSP_OK);
    }
    fclose(f);
}

/* Independent closest hit: index and t, or -1. */
/* The closest primitive but SKIP (-1: none) on the ray, or -1; its t in *T_OUT. */
static int ref_closest(const ref_scene *rs, const double o_[3], const double d_[3], double tmin,
                       double tmax, int skip, long double *t_out)
{
    long double o[3] = {o_[0], o_[1], o_[2]}, d[3] = {d_[0], d_[1], d_[2]};
    int best = -1;
    long double bt = 0;
    for (int i = 0; i < NS + NT; i++) {
        if (i == skip)
            continue;
        long double t = i < NS ? ref_sphere_hit(&rs->s[i], o, d, tmin, tmax)
                               : ref_tri_hit(&rs->t[i - NS], o, d, tmin, tmax);
        if (t >= 0 && (best < 0 || t < bt)) {
            best = i;
            bt = t;
        }
    }
    *t_out = bt;
    return best;
}

static void random_ray(double o[3], double d[3])
{
    for (int k = 0; k < 3; k++) {
        o[k] = rnd_range(-6, 6);
        d[k] = rnd_range(-1, 1);
    }
    double u = rnd();
    if (u < 0.15) { /* exactly axis-aligned */
        int axis = (int)(rnd() * 3) % 3;
        for (int k = 0; k < 3; k++)
            d[k] = k == axis ? (rnd() < 0.5 ? -1.0 : 1.0) : 0.0;
    } else if (u < 0.30) { /* one zero component */
        d[(int)(rnd() * 3) % 3] = 0.0;
    }
}

/* Near-ties between different primitives (within this relative gap) are
 * left out of the index comparison: the reference works in another
 * precision and may order them differently. */
#define TIE_GAP 1e-9

TEST(naive_matches_independent_reference)
{
    ref_scene rs;
    make_ref_scene(&rs, 12345);
    bsp_accel *a = NULL;
    bsp_error err;
    bsp_build_options opts;
    bsp_build_options_defaults(&opts);
    opts.kind = BSP_ACCEL_NAIVE;
    REQUIRE(bsp_accel_build(rs.scene, &opts, &a, &err) == BSP_OK);
    bsp_query *q = bsp_query_create(a);
    REQUIRE(q);
    int hits = 0, compared = 0;
    for (int i = 0; i < 20000; i++) {
        double o[3], d[3];
        random_ray(o, d);
        double tmin = rnd() < 0.2 ? rnd_range(0, 3) : 0.0;
        double tmax = rnd() < 0.2 ? rnd_range(3, 10) : INFINITY;
        bsp_ray ray = {bsp_v3(o[0], o[1], o[2]), bsp_v3(d[0], d[1], d[2]), tmin, tmax};
        bsp_hit h;
        int got = bsp_intersect(a, q, &ray, &h);
        long double rt;
        int want = ref_closest(&rs, o, d, tmin, tmax, -1, &rt);
        CHECK_EQ_INT(got, want >= 0);
        if (got && want >= 0) {
            hits++;
            CHECK_MSG(fabsl((long double)h.t - rt) <= 1e-9L * (1 + fabsl(rt)),
                      "ray %d: t %.17g vs reference %.17Lg", i, h.t, rt);
            /* compare the index unless another primitive is within TIE_GAP */
            long double t2;
            bsp_ray r2 = ray;
            int ambiguous = 0;
            for (int j = 0; j < NS + NT && !ambiguous; j++) {
                bsp_hit hj;
                if ((uint32_t)j != h.prim && bsp_scene_intersect_prim(rs.scene, (size_t)j, &r2, &hj))
                    ambiguous = fabs(hj.t - h.t) <= TIE_GAP * (1 + fabs(h.t));
            }
            (void)t2;
            if (!ambiguous) {
                compared++;
                CHECK_MSG((int)h.prim == want, "ray %d: prim %u vs reference %d", i, h.prim,
                          want);
            }
        }
        /* occlusion agrees with "some hit exists in [tmin, tmax]" */
        CHECK_EQ_INT(bsp_occluded(a, q, &ray), want >= 0);
    }
    CHECK(hits > 2000);
    CHECK(compared > hits * 9 / 10);
    bsp_query_destroy(q);
    bsp_accel_destroy(a);
    bsp_scene_destroy(rs.scene);
}

TEST(naive_ties_go_to_lowest_index)
{
    /* Three identical triangles and two identical spheres: the same t. */
    bsp_scene *s = bsp_scene_create();
    REQUIRE(s);
    bsp_error err;
    bsp_vec3 tri[3] = {bsp_v3(-1, -1, 0), bsp_v3(1, -1, 0), bsp_v3(0, 1, 0)};
    REQUIRE(bsp_scene_add_sphere(s, bsp_v3(0, 0, 5), 0.5, &err) == BSP_OK);   /* 0: behind */
    REQUIRE(bsp_scene_add_polygon(s, tri, 3, &err) == BSP_OK);                /* 1 */
    REQUIRE(bsp_scene_add_polygon(s, tri, 3, &err) == BSP_OK);                /* 2 */
    REQUIRE(bsp_scene_add_sphere(s, bsp_v3(0, 0, -3), 1.0, &err) == BSP_OK);  /* 3 */
    REQUIRE(bsp_scene_add_sphere(s, bsp_v3(0, 0, -3), 1.0, &err) == BSP_OK);  /* 4 */
    bsp_accel *a = NULL;
    bsp_build_options o;
    bsp_build_options_defaults(&o);
    o.kind = BSP_ACCEL_NAIVE;
    REQUIRE(bsp_accel_build(s, &o, &a, &err) == BSP_OK);
    bsp_query *q = bsp_query_create(a);
    bsp_ray down = {bsp_v3(0, 0, 2), bsp_v3(0, 0, -1), 0, INFINITY};
    bsp_hit h;
    REQUIRE(bsp_intersect(a, q, &down, &h));
    CHECK_EQ_INT(h.prim, 1);
    CHECK_NEAR(h.t, 2.0, 0);
    bsp_ray below = {bsp_v3(0, 0, -0.5), bsp_v3(0, 0, -1), 0, INFINITY};
    REQUIRE(bsp_intersect(a, q, &below, &h));
    CHECK_EQ_INT(h.prim, 3);
    CHECK_NEAR(h.t, 1.5, 1e-15);
    /* an interval that excludes everything */
    bsp_ray none = {bsp_v3(0, 0, 2), bsp_v3(0, 0, -1), 0, 1.5};
    CHECK(!bsp_intersect(a, q, &none, &h));
    CHECK_EQ_INT(h.prim, BSP_NO_PRIM);
    CHECK(!bsp_occluded(a, q, &none));
    bsp_query_destroy(q);
    bsp_accel_destroy(a);
    bsp_scene_destroy(s);
}

TEST(cli_trace_matches_independent_reference)
{
    ref_scene rs;
    make_ref_scene(&rs, 777);
    char rays_path[600];
    snprintf(rays_path, sizeof rays_path, "%s/rays_777.txt", harness_tmpdir());
    FILE *f = fopen(rays_path, "w");
    REQUIRE(f);
    enum { NR = 3000 };
    static double rays[NR][8];
    static int skip[NR]; /* the origin primitive a line names, or -1 */
    int skipped = 0;
    for (int i = 0; i < NR; i++) {
        random_ray(rays[i], rays[i] + 3);
        rays[i][6] = 0;
        rays[i][7] = INFINITY;
        skip[i] = -1;
        if (i % 3 == 0) {
            rays[i][6] = rnd_range(0, 2);
            rays[i][7] = rnd_range(2, 12);
            if (i % 2 == 0) { /* leave out the primitive the ray would hit first */
                long double rt;
                skip[i] = ref_closest(&rs, rays[i], rays[i] + 3, rays[i][6], rays[i][7], -1, &rt);
                skipped += skip[i] >= 0;
            }
            fprintf(f, "%.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g %d\n", rays[i][0],
                    rays[i][1], rays[i][2], rays[i][3], rays[i][4], rays[i][5], rays[i][6],
                    rays[i][7], skip[i]);
        } else {
            fprintf(f, "%.17g %.17g %.17g %.17g %.17g %.17g\n", rays[i][0], rays[i][1],
                    rays[i][2], rays[i][3], rays[i][4], rays[i][5]);
        }
    }
    fclose(f);
    CHECK_MSG(skipped > 50, "only %d lines leave a primitive out", skipped);
    for (int any = 0; any < 2; any++) {
        char cmd[2048];
        snprintf(cmd, sizeof cmd, "%s trace %s --rays %s%s", harness_cli(), rs.nff_path,
                 rays_path, any ? " --any" : "");
        int status;
        char *out = harness_run(cmd, &status);
        REQUIRE(out);
        CHECK_EQ_INT(status, 0);
        char *line = out, *next;
        int i = 0;
        for (; i < NR && line && *line; i++, line = next) {
            next = strchr(line, '\n');
            if (next)
                *next++ = 0;
            long double rt;
            int want =
                ref_closest(&rs, rays[i], rays[i] + 3, rays[i][6], rays[i][7], skip[i], &rt);
            if (any) {
                CHECK_MSG(!strcmp(line, want >= 0 ? "occluded" : "clear"), "ray %d: '%s'", i,
                          line);
                continue;
            }
            if (want < 0) {
                CHECK_MSG(!strcmp(line, "miss"), "ray %d: '%s', expected miss", i, line);
                continue;
            }
            unsigned prim;
            double t;
            CHECK_MSG(sscanf(line, "hit %u %lf", &prim, &t) == 2, "ray %d: '%s'", i, line);
            /* %.9g carries 9 significant digits */
            CHECK_MSG(fabsl((long double)t - rt) <= 1e-8L * (1 + fabsl(rt)),
                      "ray %d: t %.9g vs %.12Lg", i, t, rt);
            CHECK_MSG((int)prim == want || fabsl((long double)t - rt) < 1e-9L,
                      "ray %d: prim %u vs %d", i, prim, want);
        }
        CHECK_EQ_INT(i, NR);
        free(out);
    }
    bsp_scene_destroy(rs.scene);
}

TEST(cli_trace_rejects_bad_rays)
{
    ref_scene rs;
    make_ref_scene(&rs, 99);
    static const struct {
        const char *text, *msg;
        int line;
    } cases[] = {
        {"0 0 0 1 0 0\n0 0 0 1 0\n", "expected 6 or 8 numbers", 2},
        {"0 0 0 0 0 0\n", "zero vector", 1},
        {"0 0 0 1 0 nan\n", "malformed or non-finite", 1},
        {"0 0 0 1 0 x\n", "malformed or non-finite", 1},
        {"# c\n\n0 0 0 1 0 0 5 1\n", "tmax is smaller than tmin", 3},
        {"0 0 0 1 0 0 0 1 7 8\n", "too many fields", 1},
        {"0 0 0 1 0 0\n0 0 0 1 0 0 0 1 100000\n", "origin primitive out of range", 2},
        {"0 0 0 1 0 0 0 1 -2\n", "origin primitive out of range", 1},
        {"0 0 0 1 0 0 0 1 2.5\n", "malformed origin primitive", 1},
        {"0 0 0 1 0 0 0 1 x\n", "malformed origin primitive", 1},
        {"inf 0 0 1 0 0\n", "malformed or non-finite", 1},
        /* out of the domain where t and the kernels' squares stay finite */
        {"0 0 0 1 0 0\n2e30 0 0 1 0 0\n", "origin out of range", 2},
        {"0.2 0.2 5 0 0 -1e-308\n", "direction length outside [1e-100, 1e100]", 1},
        {"0 0 5 0 1e-101 -1e-101\n", "direction length outside [1e-100, 1e100]", 1},
        {"0 0 5 0 0 1e100\n0 0 5 0 8e99 8e99\n", "direction length outside [1e-100, 1e100]", 2},
    };
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        char path[600], cmd[2048];
        snprintf(path, sizeof path, "%s/bad_rays_%zu.txt", harness_tmpdir(), c);
        FILE *f = fopen(path, "w");
        REQUIRE(f);
        fputs(cases[c].text, f);
        fclose(f);
        snprintf(cmd, sizeof cmd, "%s trace %s --rays %s 2>&1 >/dev/null", harness_cli(),
                 rs.nff_path, path);
        int status;
        char *out = harness_run(cmd, &status);
        REQUIRE(out);
        CHECK_EQ_INT(status, 1);
        char where[700];
        snprintf(where, sizeof where, "%s:%d: ", path, cases[c].line);
        CHECK_STR_CONTAINS(out, where);
        CHECK_STR_CONTAINS(out, cases[c].msg);
        free(out);
    }
    bsp_scene_destroy(rs.scene);
}

TEST(cli_usage_errors)
{
    static const struct {
        const char *args, *msg;
        int status;
    } cases[] = {
        {"", "usage: bspray COMMAND", 2},
        {"frobnicate", "unknown command 'frobnicate'", 2},
        {"render", "missing SCENE", 2},
        {"render x.nff --bogus", "unknown option '--bogus'", 2},
        {"render x.nff --res", "option '--res' needs a value", 2},
        {"render x.nff --res 0", "whole number from 1 to 65536", 2},
        {"render x.nff --res 12abc", "whole number", 2},
        {"render x.nff --depth 99", "whole number from 0 to 64", 2},
        {"render x.nff --accel quadtree", "unknown acceleration method 'quadtree'", 2},
        {"render x.nff --sampling sideways", "spd or centres", 2},
        {"trace x.nff", "missing --rays", 2},
        {"stats", "missing SCENE", 2},
        {"stats /nonexistent/scene.nff", "/nonexistent/scene.nff: cannot open", 1},
    };
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        char cmd[1024];
        snprintf(cmd, sizeof cmd, "%s %s 2>&1", harness_cli(), cases[c].args);
        int status;
        char *out = harness_run(cmd, &status);
        REQUIRE(out);
        CHECK_MSG(status == cases[c].status, "'%s': exit %d, expected %d", cases[c].args, status,
                  cases[c].status);
        CHECK_STR_CONTAINS(out, cases[c].msg);
        if (cases[c].status == 2)
            CHECK_STR_CONTAINS(out, "usage");
        free(out);
    }
    /* every command has --help, exit 0 */
    const char *helps[] = {"--help", "render --help", "trace --help", "stats --help"};
    for (size_t c = 0; c < sizeof helps / sizeof helps[0]; c++) {
        char cmd[1024];
        snprintf(cmd, sizeof cmd, "%s %s 2>&1", harness_cli(), helps[c]);
        int status;
        char *out = harness_run(cmd, &status);
        REQUIRE(out);
        CHECK_EQ_INT(status, 0);
        CHECK_STR_CONTAINS(out, "usage");
        free(out);
    }
}
