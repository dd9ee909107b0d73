/*
 * mesh.h — private helpers shared by the triangle-mesh readers (obj.c, ply.c)
 * and their memory entry points (used by the tests).
 *
 * The helpers live in obj.c: whole-file reading with a size limit, decimal
 * numbers read exactly like strtod (with a fast path), integers, quoting of a
 * token for messages, and the scene defaults of a mesh (material before the
 * first face; camera and light, via bsp_scene_set_default_view, at the end).
 * Like the rest of the library they never print.
 */
#ifndef BSPRAY_SCENE_MESH_H
#define BSPRAY_SCENE_MESH_H

#include <stddef.h>
#include <stdio.h>

#include "bspray/error.h"
#include "bspray/scene.h"
#include "scene/scene_internal.h"

/* Largest input file accepted (the same as NFF). */
#define MESH_MAX_INPUT ((size_t)1 << 31)
/* Largest vertex (and normal, texture coordinate) count of one mesh. */
#define MESH_MAX_VERTS ((size_t)1 << 28)

/* The default view of a mesh: full field of view and image size. */
#define MESH_DEFAULT_FOV 45.0
#define MESH_DEFAULT_RES 512

/* Room for a token quoted by mesh_show_token. */
#define MESH_SHOW_SIZE 64

typedef enum mesh_number {
    MESH_NUM_OK = 0,
    MESH_NUM_MALFORMED, /* not [+-]digits[.digits][e[+-]digits] */
    MESH_NUM_NONFINITE  /* nan, inf, infinity, nan(...), or overflow to infinity */
} mesh_number;

/* Reads S[0..LEN) (not NUL-terminated) as a decimal number: the value strtod
 * gives, bit for bit; hex, nan and inf are refused. Shared by the NFF, OBJ
 * and PLY readers. */
HIDDEN mesh_number mesh_parse_number(const char *s, size_t len, double *out);

/* Reads S[0..LEN) as [+-]?[0-9]+, saturated at +-10^18; 0 if it is not one. */
HIDDEN int mesh_parse_integer(const char *s, size_t len, long long *out);

/* S[0..LEN) quoted for a message ('...'), unprintable bytes as \xNN, long
 * tokens cut; "end of line" when S is NULL. Returns BUF. */
HIDDEN const char *mesh_show_token(const char *s, size_t len, char *buf, size_t size);

/* Opens PATH for reading (*FP; *CAP: a buffer size that holds a regular
 * file whole, plus one byte), refusing a directory and a regular file larger
 * than MESH_MAX_INPUT. Errors are "PATH: ...". */
HIDDEN bsp_status mesh_open_file(const char *path, FILE **fp, size_t *cap, bsp_error *err);

/* Reads the whole file PATH into *OUT (free with free()); files larger than
 * MESH_MAX_INPUT are refused before reading. Errors are "PATH: ...". */
HIDDEN bsp_status mesh_read_file(const char *path, char **out, size_t *outlen, bsp_error *err);

/* A reader's parser (scene_internal.h). */
typedef scene_parse_fn mesh_parse_fn;
/* The loaders' common entry checks (output pointer, buffer, size limit)
 * around PARSE, for memory input and for a file read whole. */
HIDDEN bsp_status mesh_load_memory(mesh_parse_fn parse, const char *buf, size_t len,
                                   const char *name, bsp_scene **out, bsp_error *err);
HIDDEN bsp_status mesh_load_file(mesh_parse_fn parse, const char *path, bsp_scene **out,
                                 bsp_error *err);

/* A new scene with the default mesh material as its current material (white,
 * diffuse, a little specular); NULL when out of memory. */
HIDDEN bsp_scene *mesh_scene_create(void);

/* Ends a successful mesh load: the default view (camera and light at the
 * eye), then scene_finish (the warnings of dropped faces, naming NAME). */
HIDDEN bsp_status mesh_finish(bsp_scene *s, const char *name, bsp_error *err);

/* The readers on a memory buffer of LEN bytes; NAME is used in messages. On
 * failure *OUT is NULL. */
HIDDEN bsp_status obj_load_memory(const char *buf, size_t len, const char *name,
                                  bsp_scene **out, bsp_error *err);
HIDDEN bsp_status ply_load_memory(const char *buf, size_t len, const char *name,
                                  bsp_scene **out, bsp_error *err);

#endif /* BSPRAY_SCENE_MESH_H */
