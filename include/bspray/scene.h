/*
 * bspray/scene.h — the scene: primitives, materials, lights, background and
 * camera. A scene is built once (by a loader or by the add_* calls) and is
 * read-only afterwards; acceleration structures borrow it.
 *
 * Primitive indices: every primitive keeps its 0-based index in input order.
 * A degenerate primitive (zero-radius sphere, zero-area polygon, zero-length
 * cone, ...) keeps its index too but becomes BSP_PRIM_DROPPED: it is never
 * hit and never reaches a builder, and the scene records one warning per kind.
 */
#ifndef BSPRAY_SCENE_H
#define BSPRAY_SCENE_H

#include <stddef.h>
#include <stdint.h>

#include "bspray/error.h"
#include "bspray/geom.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct bsp_scene bsp_scene;

typedef enum bsp_prim_kind {
    BSP_PRIM_SPHERE = 0, /* NFF s */
    BSP_PRIM_POLYGON,    /* NFF p: planar, any vertex count, convex or concave */
    BSP_PRIM_PATCH,      /* NFF pp: polygon with a normal per vertex */
    BSP_PRIM_CONE,       /* NFF c: open truncated cone or cylinder, no caps */
    BSP_PRIM_DROPPED,    /* degenerate input: keeps its index, never hit */
    BSP_PRIM_KIND_COUNT
} bsp_prim_kind;

/* The viewpoint of an NFF v block. */
typedef struct bsp_camera {
    bsp_vec3 from;    /* eye position */
    bsp_vec3 at;      /* point at the image centre */
    bsp_vec3 up;      /* need not be unit or perpendicular to at - from */
    double angle_deg; /* full field of view, in (0, 180) */
    double hither;    /* near plane distance, unused by the ray tracer */
    int res_x, res_y; /* resolution in pixels, > 0 */
} bsp_camera;

/* An NFF f record, and how its surfaces take light. */
typedef struct bsp_material {
    double color[3]; /* RGB in [0,1] */
    double kd;       /* diffuse weight */
    double ks;       /* specular weight; > 0 also spawns reflection rays */
    double shine;    /* Phong exponent */
    double t;        /* transmittance; > 0 spawns refraction rays, two-sided */
    double ior;      /* index of refraction, used only when t > 0 */
    int two_sided;   /* 0 (NFF, the SPD's rule): lights count only on the
                        surface's own front (a polygon's winding normal, a
                        sphere's outside); 1: on whichever side the viewer
                        sees (a mesh's default material: meshes are often
                        wound inconsistently). No other value. */
} bsp_material;

/* An NFF l record: a positional point light. */
typedef struct bsp_light {
    bsp_vec3 pos;
    double color[3]; /* (1,1,1) when the record has none */
    int has_color;   /* 1 when the record gave a colour */
} bsp_light;

/* --- Loading ------------------------------------------------------------ */

/* Reads an NFF scene from PATH; gzip-compressed input (.nff.gz) is detected
 * by its magic bytes. On success *OUT owns a new scene (free it with
 * bsp_scene_destroy). On failure *OUT is NULL and ERR names FILE:LINE. */
bsp_status bsp_scene_load(const char *path, bsp_scene **out, bsp_error *err);

/* Checks at once, without reading or generating the scene, what
 * bsp_scene_load can know before it does: for "spd:NAME[:SIZE][:tN]" the
 * name, the size and the tessellation; for a file that it opens for reading,
 * is no directory and is within the readers' size limit. BSP_OK, or the
 * error bsp_scene_load would give for those; a file that passes may still
 * hold a malformed scene. For a tool that loads several scenes in turn: a
 * mistyped last name is found before the work on the first. */
bsp_status bsp_scene_check(const char *path, bsp_error *err);

/* The same from a memory buffer of LEN bytes (plain or gzip); NAME is used in
 * messages. The buffer is not kept. */
bsp_status bsp_scene_load_nff_memory(const char *buf, size_t len, const char *name,
                              bsp_scene **out, bsp_error *err);

/* --- Building by hand ---------------------------------------------------- */

/* A new empty scene: no camera, black background, a default white material.
 * Returns NULL when out of memory. */
bsp_scene *bsp_scene_create(void);

/* Frees a scene; NULL is a no-op. */
void bsp_scene_destroy(bsp_scene *scene);

/* The largest magnitude of a coordinate or radius a scene accepts (also for
 * lights and the camera's from and at): beyond it the kd-trees' float planes,
 * surface areas and the intersection tests' squares would overflow. */
#define BSP_SCENE_MAX_COORD 1e30

/* Each add_* appends one primitive with the current material and returns
 * BSP_OK, also when the primitive is degenerate (then it is recorded as
 * BSP_PRIM_DROPPED with a warning). Non-finite input, coordinates beyond
 * BSP_SCENE_MAX_COORD and absurd sizes are errors and add nothing. */
bsp_status bsp_scene_add_sphere(bsp_scene *scene, bsp_vec3 center, double radius,
                         bsp_error *err);
bsp_status bsp_scene_add_polygon(bsp_scene *scene, const bsp_vec3 *verts, size_t n,
                          bsp_error *err);
bsp_status bsp_scene_add_patch(bsp_scene *scene, const bsp_vec3 *verts,
                        const bsp_vec3 *normals, size_t n, bsp_error *err);
/* Appends an indexed triangle mesh: triangle t (0 <= t < NTRIS) has the
 * vertices VERTS[INDICES[3t]], VERTS[INDICES[3t + 1]] and
 * VERTS[INDICES[3t + 2]], in that order, and becomes primitive
 * bsp_scene_prim_count() + t with the current material: a polygon of three
 * vertices, or with NORMALS (one per vertex, like VERTS; may be NULL) a
 * polygonal patch, the very primitive bsp_scene_add_polygon (or _add_patch)
 * makes of the same three points. Degenerate triangles are recorded as
 * BSP_PRIM_DROPPED, as there. All or nothing: every vertex (used or not)
 * must be finite and within BSP_SCENE_MAX_COORD and every index below
 * NVERTS, else BSP_ERR_INVALID with a message naming the first bad vertex or
 * triangle, and nothing is added (also on BSP_ERR_LIMIT and BSP_ERR_NOMEM).
 * NTRIS = 0 adds nothing. */
bsp_status bsp_scene_add_triangles(bsp_scene *scene, const bsp_vec3 *verts, size_t nverts,
                                   const bsp_vec3 *normals_or_null, const uint32_t *indices,
                                   size_t ntris, bsp_error *err);
bsp_status bsp_scene_add_cone(bsp_scene *scene, bsp_vec3 base, double base_radius,
                       bsp_vec3 apex, double apex_radius, bsp_error *err);

/* Sets the material used by the primitives added from now on. */
bsp_status bsp_scene_set_material(bsp_scene *scene, const bsp_material *m,
                           bsp_error *err);
bsp_status bsp_scene_add_light(bsp_scene *scene, const bsp_light *light,
                        bsp_error *err);
/* Validates and sets the camera (zero or parallel up, angle outside (0,180)
 * or a non-positive resolution are BSP_ERR_INVALID). */
bsp_status bsp_scene_set_camera(bsp_scene *scene, const bsp_camera *cam,
                         bsp_error *err);
/* Sets a camera that frames the scene (the default view of OBJ and PLY
 * meshes; see docs/formats.md). Every argument may be NULL (or 0) for its
 * default: AT the centre of the bounding box; EYE from AT along (1,1,1) far
 * enough that the box's bounding sphere fits in the view cone; UP +z, or +y
 * when the view is parallel to z; FOV_DEG 45. The resolution of an existing
 * camera is kept, else 512 x 512. A scene without lights gets one white point
 * light at the eye; a light that sat at the previous eye moves with it.
 * An empty scene is framed as a unit sphere at the origin. */
bsp_status bsp_scene_set_default_view(bsp_scene *scene, const bsp_vec3 *eye_or_null,
                                      const bsp_vec3 *at_or_null, const bsp_vec3 *up_or_null,
                                      double fov_deg_or_0, bsp_error *err);
void bsp_scene_set_background(bsp_scene *scene, const double rgb[3]);

/* --- Reading ------------------------------------------------------------- */

size_t bsp_scene_prim_count(const bsp_scene *scene);
bsp_prim_kind bsp_scene_prim_kind(const bsp_scene *scene, size_t prim);
/* Vertex count of a polygon or patch, 0 for other kinds. */
size_t bsp_scene_prim_vertex_count(const bsp_scene *scene, size_t prim);
/* Index of the primitive's material (see bsp_scene_material). */
size_t bsp_scene_prim_material(const bsp_scene *scene, size_t prim);
/* Tight bounds of one primitive (empty box for a dropped one). */
bsp_box bsp_scene_prim_bounds(const bsp_scene *scene, size_t prim);
/* Bounds of all live primitives (empty box when there are none). */
bsp_box bsp_scene_bounds(const bsp_scene *scene);
/* Number of live primitives of one kind (BSP_PRIM_DROPPED: dropped ones). */
size_t bsp_scene_kind_count(const bsp_scene *scene, bsp_prim_kind kind);

/* NULL when the scene has no camera. */
const bsp_camera *bsp_scene_camera(const bsp_scene *scene);
/* 1 when the camera is a default view framed by bsp_scene_set_default_view
 * (a mesh's), 0 for one set from a file or by bsp_scene_set_camera. */
int bsp_scene_camera_is_default(const bsp_scene *scene);
size_t bsp_scene_light_count(const bsp_scene *scene);
const bsp_light *bsp_scene_light(const bsp_scene *scene, size_t i);
size_t bsp_scene_material_count(const bsp_scene *scene);
const bsp_material *bsp_scene_material(const bsp_scene *scene, size_t i);
void bsp_scene_background(const bsp_scene *scene, double rgb[3]);

/* Warnings collected while loading (one per dropped kind, and the like). */
size_t bsp_scene_warning_count(const bsp_scene *scene);
const char *bsp_scene_warning(const bsp_scene *scene, size_t i);

/* --- Reading primitive geometry (export, comparison with other tracers) ----
 *
 * Each returns BSP_OK and writes its outputs, or BSP_ERR_INVALID and writes
 * nothing when PRIM is out of range, is of another kind (a dropped primitive
 * is of no kind) or I is not a vertex index of the primitive. The values are
 * those of the surface bspray intersects, read back from its precomputed
 * records: spheres and polygons of four or more vertices give back the input
 * bit for bit; a three-vertex polygon or patch is stored as v0 and the edges
 * v1 - v0, v2 - v0, so its vertices 1 and 2 come back as v0 + (v1 - v0), and a
 * cone's apex as base + unit axis * length: equal to the input up to a
 * rounding or two (exactly equal when those operations are exact). */

/* A sphere's centre and radius (negative when the input's was: NFF's "only
 * the inside is visible"). Any output may be NULL. */
bsp_status bsp_scene_prim_sphere(const bsp_scene *scene, size_t prim, bsp_vec3 *center,
                                 double *radius);
/* A cone's base centre and radius and apex centre and radius (both radii
 * negative, or one negative and one -0.0, when the input's were). Any output
 * may be NULL. */
bsp_status bsp_scene_prim_cone(const bsp_scene *scene, size_t prim, bsp_vec3 *base,
                               double *base_radius, bsp_vec3 *apex, double *apex_radius);
/* Vertex I (0 <= I < bsp_scene_prim_vertex_count) of a polygon or patch, in
 * input order. */
bsp_status bsp_scene_prim_vertex(const bsp_scene *scene, size_t prim, size_t i,
                                 bsp_vec3 *vertex);
/* The normal given with vertex I of a patch, normalised to unit length as the
 * scene stores it (polygons have none: BSP_ERR_INVALID). */
bsp_status bsp_scene_prim_vertex_normal(const bsp_scene *scene, size_t prim, size_t i,
                                        bsp_vec3 *normal);

/* Name of a primitive kind ("sphere", "polygon", "patch", "cone", "dropped"). */
const char *bsp_prim_kind_name(bsp_prim_kind kind);

/* Intersects one primitive with RAY, ignoring every other primitive.
 * Returns 1 and fills *HIT (t, prim, u, v) when it is hit with
 * ray->tmin <= t <= ray->tmax, else 0. The computed t does not depend on
 * tmin/tmax, so every method that calls this agrees bit for bit. */
int bsp_scene_intersect_prim(const bsp_scene *scene, size_t prim,
                             const bsp_ray *ray, bsp_hit *hit);

/* Geometric normal (unit, as the primitive's own orientation defines it) and
 * shading normal (interpolated for patches, else the geometric one) at a hit
 * found on RAY. */
void bsp_scene_hit_normals(const bsp_scene *scene, const bsp_ray *ray,
                           const bsp_hit *hit, bsp_vec3 *geometric,
                           bsp_vec3 *shading);

#ifdef __cplusplus
}
#endif

#endif /* BSPRAY_SCENE_H */
