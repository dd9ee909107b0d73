/*
 * scene.c — storage of a bsp_scene: the add_* builders shared by every loader
 * and generator (validation, degenerate-primitive dropping, refusal of absurd
 * sizes), and the read accessors.
 *
 * Invariants: prims[i] describes primitive i in input order; a dropped
 * primitive has shape SHAPE_NONE and is counted under BSP_PRIM_DROPPED;
 * bounds always covers every live primitive.
 */
#include <inttypes.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "geom/vec.h"
#include "scene/scene_internal.h"
#include "util/bigmem.h"

/* Ensures room for NEED elements of size ELEM in *P (capacity *CAP); large
 * arrays on huge pages (util/bigmem.h: a million-triangle scene's arrays
 * grown on 4 KiB pages cost a fifth of its load in page faults). */
static int grow(void **p, size_t *cap, size_t need, size_t elem)
{
    if (need <= *cap)
        return 1;
    size_t ncap = *cap ? *cap : 16;
    while (ncap < need) {
        if (ncap > SIZE_MAX / 2 / elem)
            return 0;
        ncap *= 2;
    }
    void *np = bigmem_realloc(*p, *cap * elem, ncap * elem);
    if (!np)
        return 0;
    *p = np;
    *cap = ncap;
    return 1;
}

#define GROW(arr, cap, need) grow((void **)&(arr), &(cap), (need), sizeof *(arr))

static const bsp_material default_material = {{1.0, 1.0, 1.0}, 1.0, 0.0, 0.0, 0.0, 1.0, 0};

bsp_scene *bsp_scene_create(void)
{
    bsp_scene *s = calloc(1, sizeof *s);
    if (!s)
        return NULL;
    if (!GROW(s->materials, s->cap_materials, 1)) {
        free(s);
        return NULL;
    }
    s->materials[0] = default_material;
    s->nmaterials = 1;
    s->bounds = box_empty();
    s->tri_edge_exp_max = TRIANGLE_EDGE_EXP_NONE;
    scene_update_scale(s);
    return s;
}

void bsp_scene_destroy(bsp_scene *s)
{
    if (!s)
        return;
    free(s->prims);
    free(s->spheres);
    free(s->triangles);
    free(s->polygons);
    free(s->cones);
    free(s->verts);
    free(s->plane_verts);
    free(s->normals);
    polygon_slab_pool_free(&s->slabs);
    free(s->materials);
    free(s->lights);
    for (size_t i = 0; i < s->nwarnings; i++)
        free(s->warnings[i]);
    free(s);
}

void scene_set_source(bsp_scene *s, const char *name, size_t line)
{
    s->src_name = name;
    s->src_line = line;
}

void scene_warn(bsp_scene *s, const char *fmt, ...)
{
    if (s->nwarnings >= SCENE_MAX_WARNINGS)
        return;
    char buf[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    char *copy = malloc(strlen(buf) + 1);
    if (!copy)
        return;
    strcpy(copy, buf);
    s->warnings[s->nwarnings++] = copy;
}

static const char *const drop_reason[BSP_PRIM_KIND_COUNT] = {
    "spheres with zero radius",
    "polygons with zero area",
    "polygonal patches with zero area",
    "cones with zero length or both radii zero",
    "",
};

void scene_finish(bsp_scene *s)
{
    if (s->finished)
        return;
    s->finished = 1;
    for (int k = 0; k < BSP_PRIM_DROPPED; k++) {
        size_t n = s->dropped_by_kind[k];
        if (!n)
            continue;
        if (s->src_name && s->dropped_first_line[k])
            scene_warn(s, "%s:%zu: dropped %zu degenerate %s (first here)", s->src_name,
                       s->dropped_first_line[k], n, drop_reason[k]);
        else
            scene_warn(s, "%s%sdropped %zu degenerate %s (the first is primitive %zu)",
                       s->src_name ? s->src_name : "", s->src_name ? ": " : "", n, drop_reason[k],
                       s->dropped_first_prim[k]);
    }
}

/* Appends a primitive record; SHAPE_NONE records a dropped one of KIND. */
static bsp_status push_prim(bsp_scene *s, bsp_prim_kind kind, shape_kind shape, size_t slot,
                            bsp_error *err)
{
    if (s->nprims >= SCENE_MAX_PRIMS)
        return scene_fail(s, err, BSP_ERR_LIMIT, "more than %zu primitives", SCENE_MAX_PRIMS);
    if (!GROW(s->prims, s->cap_prims, s->nprims + 1))
        return scene_fail(s, err, BSP_ERR_NOMEM, "out of memory");
    prim_record *p = &s->prims[s->nprims++];
    p->kind = (uint8_t)(shape == SHAPE_NONE ? BSP_PRIM_DROPPED : kind);
    p->shape = (uint8_t)shape;
    p->slot = (uint32_t)slot;
    p->material = (uint32_t)s->current_material;
    if (shape == SHAPE_NONE) {
        s->kind_count[BSP_PRIM_DROPPED]++;
        if (s->dropped_by_kind[kind]++ == 0) {
            s->dropped_first_line[kind] = s->src_line;
            s->dropped_first_prim[kind] = s->nprims - 1;
        }
    } else {
        s->kind_count[kind]++;
        if (shape == SHAPE_TRIANGLE && s->triangles[slot].edge_exp > s->tri_edge_exp_max)
            s->tri_edge_exp_max = s->triangles[slot].edge_exp;
        s->bounds = box_union(s->bounds, bsp_scene_prim_bounds(s, s->nprims - 1));
        scene_update_scale(s);
    }
    return BSP_OK;
}

static int finite_all(const double *x, size_t n)
{
    for (size_t i = 0; i < n; i++)
        if (!isfinite(x[i]))
            return 0;
    return 1;
}

/* Coordinates and radii must be finite and at most BSP_SCENE_MAX_COORD in
 * magnitude: beyond it the float split planes of the kd-trees, surface areas
 * and the intersection tests' squares would overflow. */
static bsp_status check_coords(bsp_scene *s, bsp_error *err, const char *what, const double *x,
                               size_t n)
{
    if (!finite_all(x, n))
        return scene_fail(s, err, BSP_ERR_INVALID, "%s: non-finite number", what);
    for (size_t i = 0; i < n; i++)
        if (fabs(x[i]) > BSP_SCENE_MAX_COORD)
            return scene_fail(s, err, BSP_ERR_INVALID,
                              "%s: %g is out of range (coordinates and radii must lie within "
                              "+-%g)",
                              what, x[i], BSP_SCENE_MAX_COORD);
    return BSP_OK;
}

bsp_status bsp_scene_add_sphere(bsp_scene *s, bsp_vec3 center, double radius, bsp_error *err)
{
    double all[4] = {center.x, center.y, center.z, radius};
    bsp_status bad = check_coords(s, err, "sphere", all, 4);
    if (bad != BSP_OK)
        return bad;
    sphere_shape sh;
    if (!sphere_setup(&sh, center, radius))
        return push_prim(s, BSP_PRIM_SPHERE, SHAPE_NONE, 0, err);
    if (!GROW(s->spheres, s->cap_spheres, s->nspheres + 1))
        return scene_fail(s, err, BSP_ERR_NOMEM, "out of memory");
    s->spheres[s->nspheres] = sh;
    bsp_status st = push_prim(s, BSP_PRIM_SPHERE, SHAPE_SPHERE, s->nspheres, err);
    if (st == BSP_OK)
        s->nspheres++;
    return st;
}

/* Shared by polygons and patches: NORMALS may be NULL. */
static bsp_status add_polygonal(bsp_scene *s, bsp_prim_kind kind, const bsp_vec3 *verts,
                                const bsp_vec3 *normals, size_t n, bsp_error *err)
{
    const char *what = kind == BSP_PRIM_PATCH ? "polygonal patch" : "polygon";
    if (n > SCENE_MAX_POLY_VERTS)
        return scene_fail(s, err, BSP_ERR_LIMIT, "%s with %zu vertices (the limit is %zu)", what,
                          n, SCENE_MAX_POLY_VERTS);
    for (size_t i = 0; i < n; i++) {
        bsp_status bad = check_coords(s, err, what, verts[i].v, 3);
        if (bad != BSP_OK)
            return bad;
        if (normals && !v3_is_finite(normals[i]))
            return scene_fail(s, err, BSP_ERR_INVALID, "%s: non-finite number", what);
    }
    if (n < 3)
        return push_prim(s, kind, SHAPE_NONE, 0, err);
    if (s->nverts + n > SCENE_MAX_TOTAL_VERTS)
        return scene_fail(s, err, BSP_ERR_LIMIT, "more than %zu polygon vertices in all",
                          SCENE_MAX_TOTAL_VERTS);

    uint32_t nrm_first = SHAPE_NO_NORMALS;
    size_t old_nnormals = s->nnormals, old_nverts = s->nverts;
    if (normals) {
        if (!GROW(s->normals, s->cap_normals, s->nnormals + n))
            return scene_fail(s, err, BSP_ERR_NOMEM, "out of memory");
        nrm_first = (uint32_t)s->nnormals;
        for (size_t i = 0; i < n; i++)
            s->normals[s->nnormals++] = v3_normalize(normals[i]);
    }
    bsp_status st;
    if (n == 3) {
        triangle_shape tr;
        if (!triangle_setup(&tr, verts[0], verts[1], verts[2], nrm_first)) {
            s->nnormals = old_nnormals;
            return push_prim(s, kind, SHAPE_NONE, 0, err);
        }
        if (!GROW(s->triangles, s->cap_triangles, s->ntriangles + 1))
            return scene_fail(s, err, BSP_ERR_NOMEM, "out of memory");
        s->triangles[s->ntriangles] = tr;
        st = push_prim(s, kind, SHAPE_TRIANGLE, s->ntriangles, err);
        if (st == BSP_OK)
            s->ntriangles++;
        return st;
    }
    if (!GROW(s->verts, s->cap_verts, s->nverts + n) ||
        !GROW(s->plane_verts, s->cap_plane_verts, s->nverts + n))
        return scene_fail(s, err, BSP_ERR_NOMEM, "out of memory");
    memcpy(s->verts + s->nverts, verts, n * sizeof *verts);
    polygon_shape pg;
    if (!polygon_setup(&pg, s->verts, (uint32_t)s->nverts, (uint32_t)n, nrm_first)) {
        s->nnormals = old_nnormals;
        return push_prim(s, kind, SHAPE_NONE, 0, err);
    }
    for (size_t i = 0; i < n; i++)
        s->plane_verts[s->nverts + i] = polygon_plane_vertex(&pg, s->verts[s->nverts + i]);
    s->nverts += n;
    if (!GROW(s->polygons, s->cap_polygons, s->npolygons + 1) ||
        !polygon_slabs_build(&pg, s->verts, &s->slabs)) {
        s->nverts = old_nverts;
        return scene_fail(s, err, BSP_ERR_NOMEM, "out of memory");
    }
    s->polygons[s->npolygons] = pg;
    st = push_prim(s, kind, SHAPE_POLYGON, s->npolygons, err);
    if (st == BSP_OK)
        s->npolygons++;
    return st;
}

bsp_status bsp_scene_add_polygon(bsp_scene *s, const bsp_vec3 *verts, size_t n, bsp_error *err)
{
    return add_polygonal(s, BSP_PRIM_POLYGON, verts, NULL, n, err);
}

bsp_status bsp_scene_add_patch(bsp_scene *s, const bsp_vec3 *verts, const bsp_vec3 *normals,
                               size_t n, bsp_error *err)
{
    return add_polygonal(s, BSP_PRIM_PATCH, verts, normals, n, err);
}

bsp_status bsp_scene_add_triangles(bsp_scene *s, const bsp_vec3 *verts, size_t nverts,
                                   const bsp_vec3 *normals, const uint32_t *indices, size_t ntris,
                                   bsp_error *err)
{
    const char *what = normals ? "triangle mesh (patches)" : "triangle mesh";
    if (ntris == 0)
        return BSP_OK;
    if (!indices || (nverts > 0 && !verts))
        return scene_fail(s, err, BSP_ERR_INVALID, "%s: NULL vertex or index array", what);
    if (ntris > SCENE_MAX_PRIMS - s->nprims)
        return scene_fail(s, err, BSP_ERR_LIMIT,
                          "%s: %zu triangles after %zu primitives (the limit is %zu)", what, ntris,
                          s->nprims, SCENE_MAX_PRIMS);
    if (s->nverts + 3 > SCENE_MAX_TOTAL_VERTS) /* add_polygonal's check, made once */
        return scene_fail(s, err, BSP_ERR_LIMIT, "more than %zu polygon vertices in all",
                          SCENE_MAX_TOTAL_VERTS);
    /* everything checked before anything is added: the mesh goes in whole
     * or not at all (vertices a triangle does not use are checked too) */
    for (size_t i = 0; i < nverts; i++) {
        if (!v3_is_finite(verts[i]) || (normals && !v3_is_finite(normals[i])))
            return scene_fail(s, err, BSP_ERR_INVALID, "%s: vertex %zu: non-finite number",
                              what, i);
        for (int k = 0; k < 3; k++)
            if (fabs(verts[i].v[k]) > BSP_SCENE_MAX_COORD)
                return scene_fail(s, err, BSP_ERR_INVALID,
                                  "%s: vertex %zu: %g is out of range (coordinates must lie "
                                  "within +-%g)",
                                  what, i, verts[i].v[k], BSP_SCENE_MAX_COORD);
    }
    for (size_t t = 0; t < ntris; t++)
        for (int c = 0; c < 3; c++)
            if (indices[3 * t + (size_t)c] >= nverts)
                return scene_fail(s, err, BSP_ERR_INVALID,
                                  "%s: triangle %zu: vertex index %" PRIu32
                                  " is out of range (%zu vertices)",
                                  what, t, indices[3 * t + (size_t)c], nverts);
    /* room for all of it, so that no triangle below can fail half-way */
    if (!GROW(s->prims, s->cap_prims, s->nprims + ntris) ||
        !GROW(s->triangles, s->cap_triangles, s->ntriangles + ntris) ||
        (normals && !GROW(s->normals, s->cap_normals, s->nnormals + 3 * ntris)))
        return scene_fail(s, err, BSP_ERR_NOMEM, "out of memory");
    for (size_t t = 0; t < ntris; t++) {
        const uint32_t *ix = indices + 3 * t;
        const bsp_vec3 v[3] = {verts[ix[0]], verts[ix[1]], verts[ix[2]]};
        bsp_status st;
        if (normals) {
            const bsp_vec3 n[3] = {normals[ix[0]], normals[ix[1]], normals[ix[2]]};
            st = add_polygonal(s, BSP_PRIM_PATCH, v, n, 3, err);
        } else {
            st = add_polygonal(s, BSP_PRIM_POLYGON, v, NULL, 3, err);
        }
        if (st != BSP_OK)
            return st; /* cannot happen: checked and reserved above */
    }
    return BSP_OK;
}

bsp_status bsp_scene_add_cone(bsp_scene *s, bsp_vec3 base, double base_radius, bsp_vec3 apex,
                              double apex_radius, bsp_error *err)
{
    double all[8] = {base.x, base.y, base.z, base_radius, apex.x, apex.y, apex.z, apex_radius};
    bsp_status bad = check_coords(s, err, "cone", all, 8);
    if (bad != BSP_OK)
        return bad;
    if ((base_radius < 0 || apex_radius < 0) && (base_radius > 0 || apex_radius > 0))
        return scene_fail(s, err, BSP_ERR_INVALID,
                          "cone: radii %g and %g have different signs (negative radii, "
                          "meaning only the inside is visible, must both be negative)",
                          base_radius, apex_radius);
    cone_shape c;
    if (!cone_setup(&c, base, base_radius, apex, apex_radius))
        return push_prim(s, BSP_PRIM_CONE, SHAPE_NONE, 0, err);
    if (!GROW(s->cones, s->cap_cones, s->ncones + 1))
        return scene_fail(s, err, BSP_ERR_NOMEM, "out of memory");
    s->cones[s->ncones] = c;
    bsp_status st = push_prim(s, BSP_PRIM_CONE, SHAPE_CONE, s->ncones, err);
    if (st == BSP_OK)
        s->ncones++;
    return st;
}

bsp_status bsp_scene_set_material(bsp_scene *s, const bsp_material *m, bsp_error *err)
{
    double all[8] = {m->color[0], m->color[1], m->color[2], m->kd, m->ks, m->shine, m->t, m->ior};
    if (!finite_all(all, 8))
        return scene_fail(s, err, BSP_ERR_INVALID, "material: non-finite number");
    if (m->color[0] < 0 || m->color[1] < 0 || m->color[2] < 0)
        return scene_fail(s, err, BSP_ERR_INVALID, "material: negative colour");
    if (m->kd < 0 || m->ks < 0 || m->t < 0 || m->shine < 0)
        return scene_fail(s, err, BSP_ERR_INVALID,
                          "material: Kd, Ks, Shine and T must not be negative");
    if (m->two_sided != 0 && m->two_sided != 1)
        return scene_fail(s, err, BSP_ERR_INVALID, "material: two_sided must be 0 or 1, not %d",
                          m->two_sided);
    if (m->t > 0 && m->ior <= 0)
        return scene_fail(s, err, BSP_ERR_INVALID,
                          "material: transmittance %g needs a positive index of refraction, "
                          "got %g",
                          m->t, m->ior);
    if (s->material_explicit && s->nmaterials >= SCENE_MAX_MATERIALS)
        return scene_fail(s, err, BSP_ERR_LIMIT, "more than %zu materials",
                          (size_t)SCENE_MAX_MATERIALS);
    /* The first explicit material replaces the default one unless a
     * primitive already uses the default. */
    if (!s->material_explicit && s->nprims == 0) {
        s->materials[0] = *m;
    } else {
        if (!GROW(s->materials, s->cap_materials, s->nmaterials + 1))
            return scene_fail(s, err, BSP_ERR_NOMEM, "out of memory");
        s->materials[s->nmaterials++] = *m;
    }
    s->material_explicit = 1;
    s->current_material = s->nmaterials - 1;
    return BSP_OK;
}

bsp_status bsp_scene_add_light(bsp_scene *s, const bsp_light *light, bsp_error *err)
{
    double all[6] = {light->pos.x, light->pos.y, light->pos.z,
                     light->color[0], light->color[1], light->color[2]};
    if (!finite_all(all, 6))
        return scene_fail(s, err, BSP_ERR_INVALID, "light: non-finite number");
    bsp_status bad = check_coords(s, err, "light", all, 3);
    if (bad != BSP_OK)
        return bad;
    if (light->color[0] < 0 || light->color[1] < 0 || light->color[2] < 0)
        return scene_fail(s, err, BSP_ERR_INVALID, "light: negative colour");
    if (s->nlights >= SCENE_MAX_LIGHTS)
        return scene_fail(s, err, BSP_ERR_LIMIT, "more than %zu lights", SCENE_MAX_LIGHTS);
    if (!GROW(s->lights, s->cap_lights, s->nlights + 1))
        return scene_fail(s, err, BSP_ERR_NOMEM, "out of memory");
    s->lights[s->nlights++] = *light;
    return BSP_OK;
}

/* Largest accepted image side. */
#define CAMERA_MAX_RES 65536

bsp_status bsp_scene_set_camera(bsp_scene *s, const bsp_camera *c, bsp_error *err)
{
    double all[11] = {c->from.x, c->from.y, c->from.z, c->at.x, c->at.y, c->at.z,
                      c->up.x,   c->up.y,   c->up.z,   c->angle_deg, c->hither};
    if (!finite_all(all, 11))
        return scene_fail(s, err, BSP_ERR_INVALID, "camera: non-finite number");
    bsp_status bad = check_coords(s, err, "camera", all, 6); /* from and at */
    if (bad != BSP_OK)
        return bad;
    bsp_vec3 dir = v3_sub(c->at, c->from);
    double ldir = v3_length(dir), lup = v3_length(c->up);
    if (ldir == 0)
        return scene_fail(s, err, BSP_ERR_INVALID, "camera: 'from' and 'at' are the same point");
    if (lup == 0)
        return scene_fail(s, err, BSP_ERR_INVALID, "camera: 'up' is the zero vector");
    if (v3_length(v3_cross(dir, c->up)) <= 1e-9 * ldir * lup)
        return scene_fail(s, err, BSP_ERR_INVALID,
                          "camera: 'up' is parallel to the view direction");
    if (!(c->angle_deg > 0 && c->angle_deg < 180))
        return scene_fail(s, err, BSP_ERR_INVALID,
                          "camera: angle %g is outside (0, 180) degrees", c->angle_deg);
    if (c->res_x <= 0 || c->res_y <= 0)
        return scene_fail(s, err, BSP_ERR_INVALID,
                          "camera: resolution %d x %d is not positive", c->res_x, c->res_y);
    if (c->res_x > CAMERA_MAX_RES || c->res_y > CAMERA_MAX_RES)
        return scene_fail(s, err, BSP_ERR_LIMIT, "camera: resolution %d x %d exceeds %d",
                          c->res_x, c->res_y, CAMERA_MAX_RES);
    s->camera = *c;
    s->has_camera = 1;
    s->camera_is_default = 0;
    return BSP_OK;
}

void bsp_scene_set_background(bsp_scene *s, const double rgb[3])
{
    for (int i = 0; i < 3; i++)
        s->background[i] = rgb[i];
}

/* --- accessors ------------------------------------------------------------ */

size_t bsp_scene_prim_count(const bsp_scene *s)
{
    return s->nprims;
}

bsp_prim_kind bsp_scene_prim_kind(const bsp_scene *s, size_t prim)
{
    return prim < s->nprims ? (bsp_prim_kind)s->prims[prim].kind : BSP_PRIM_DROPPED;
}

size_t bsp_scene_prim_vertex_count(const bsp_scene *s, size_t prim)
{
    if (prim >= s->nprims)
        return 0;
    switch ((shape_kind)s->prims[prim].shape) {
    case SHAPE_TRIANGLE:
        return 3;
    case SHAPE_POLYGON:
        return s->polygons[s->prims[prim].slot].count;
    default:
        return 0;
    }
}

size_t bsp_scene_prim_material(const bsp_scene *s, size_t prim)
{
    return prim < s->nprims ? s->prims[prim].material : 0;
}

bsp_box bsp_scene_prim_bounds(const bsp_scene *s, size_t prim)
{
    if (prim >= s->nprims)
        return box_empty();
    const prim_record *p = &s->prims[prim];
    switch ((shape_kind)p->shape) {
    case SHAPE_SPHERE:
        return sphere_bounds(&s->spheres[p->slot]);
    case SHAPE_TRIANGLE:
        return triangle_bounds(&s->triangles[p->slot]);
    case SHAPE_POLYGON:
        return polygon_bounds(&s->polygons[p->slot], s->verts);
    case SHAPE_CONE:
        return cone_bounds(&s->cones[p->slot]);
    case SHAPE_NONE:
        break;
    }
    return box_empty();
}

bsp_box bsp_scene_bounds(const bsp_scene *s)
{
    return s->bounds;
}

double scene_scale(const bsp_scene *s)
{
    double scale = 1.0;
    if (!box_is_empty(s->bounds)) {
        for (int k = 0; k < 3; k++) {
            scale = fmax(scale, fabs(s->bounds.lo.v[k]));
            scale = fmax(scale, fabs(s->bounds.hi.v[k]));
        }
    }
    return scale;
}

void scene_update_scale(bsp_scene *s)
{
    double scale = scene_scale(s);
    s->far_origin = RAY_FAR_ORIGIN_REL * scale;
    s->hit_tol = ISECT_HIT_TOL_REL * scale;
    /* every vertex lies in the bounds: |v|_1 is at most the sum over the
     * axes of the larger end's magnitude (rounding: tri_bound's factor 2) */
    triangle_reach *r = &s->tri_reach;
    r->radius = 0.0;
    r->enorm = 0.0;
    if (s->tri_edge_exp_max != TRIANGLE_EDGE_EXP_NONE && !box_is_empty(s->bounds)) {
        for (int k = 0; k < 3; k++)
            r->radius += fmax(fabs(s->bounds.lo.v[k]), fabs(s->bounds.hi.v[k]));
        r->enorm = triangle_edge_norm(s->tri_edge_exp_max);
    }
}

size_t bsp_scene_kind_count(const bsp_scene *s, bsp_prim_kind kind)
{
    return (unsigned)kind < BSP_PRIM_KIND_COUNT ? s->kind_count[kind] : 0;
}

const bsp_camera *bsp_scene_camera(const bsp_scene *s)
{
    return s->has_camera ? &s->camera : NULL;
}

int bsp_scene_camera_is_default(const bsp_scene *s)
{
    return s->has_camera && s->camera_is_default;
}

size_t bsp_scene_light_count(const bsp_scene *s)
{
    return s->nlights;
}

const bsp_light *bsp_scene_light(const bsp_scene *s, size_t i)
{
    return i < s->nlights ? &s->lights[i] : NULL;
}

size_t bsp_scene_material_count(const bsp_scene *s)
{
    return s->nmaterials;
}

const bsp_material *bsp_scene_material(const bsp_scene *s, size_t i)
{
    return i < s->nmaterials ? &s->materials[i] : NULL;
}

void bsp_scene_background(const bsp_scene *s, double rgb[3])
{
    for (int i = 0; i < 3; i++)
        rgb[i] = s->background[i];
}

size_t bsp_scene_warning_count(const bsp_scene *s)
{
    return s->nwarnings;
}

const char *bsp_scene_warning(const bsp_scene *s, size_t i)
{
    return i < s->nwarnings ? s->warnings[i] : NULL;
}

const char *bsp_prim_kind_name(bsp_prim_kind kind)
{
    static const char *const names[BSP_PRIM_KIND_COUNT] = {"sphere", "polygon", "patch", "cone",
                                                           "dropped"};
    return (unsigned)kind < BSP_PRIM_KIND_COUNT ? names[kind] : "unknown";
}

int bsp_scene_intersect_prim(const bsp_scene *s, size_t prim, const bsp_ray *ray, bsp_hit *hit)
{
    hit->prim = BSP_NO_PRIM;
    if (prim >= s->nprims)
        return 0;
    return scene_intersect(s, (uint32_t)prim, ray, hit);
}

void bsp_scene_hit_normals(const bsp_scene *s, const bsp_ray *ray, const bsp_hit *hit,
                           bsp_vec3 *geometric, bsp_vec3 *shading)
{
    bsp_vec3 g = bsp_v3(0, 0, 1), n;
    bsp_vec3 p = ray_at(ray, hit->t);
    const prim_record *pr = &s->prims[hit->prim];
    switch ((shape_kind)pr->shape) {
    case SHAPE_SPHERE: {
        const sphere_shape *sp = &s->spheres[pr->slot];
        g = sphere_normal(sp, p);
        if (sp->inside_only)
            g = v3_neg(g);
        n = g;
        break;
    }
    case SHAPE_TRIANGLE: {
        const triangle_shape *tr = &s->triangles[pr->slot];
        g = tr->normal;
        n = triangle_shading_normal(tr, s->normals, hit->u, hit->v);
        break;
    }
    case SHAPE_POLYGON: {
        const polygon_shape *pg = &s->polygons[pr->slot];
        g = pg->normal;
        n = polygon_shading_normal(pg, s->verts, s->normals, p);
        break;
    }
    case SHAPE_CONE: {
        const cone_shape *c = &s->cones[pr->slot];
        g = cone_normal(c, p);
        if (c->inside_only)
            g = v3_neg(g);
        n = g;
        break;
    }
    case SHAPE_NONE:
    default:
        n = g;
        break;
    }
    if (geometric)
        *geometric = g;
    if (shading)
        *shading = n;
}
