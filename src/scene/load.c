/*
 * load.c — bsp_scene_load: one entry point for every kind of scene a user
 * names. "spd:NAME[:SIZE]" is generated in code (src/spd); a name ending in
 * ".obj" or ".ply" (any case), or in either and ".gz", is read as a
 * Wavefront OBJ or PLY mesh (src/scene/obj.c, ply.c); anything else is read
 * as NFF. Every reader inflates gzip input, detected by content (gunzip.c).
 */
#include <stdio.h>
#include <string.h>

#include "scene/mesh.h"
#include "scene/scene_internal.h"
#include "spd/spd.h"

/* True when PATH ends with EXT (a lower-case ".xyz"), ignoring case. */
static int has_extension(const char *path, const char *ext)
{
    size_t n = strlen(path), m = strlen(ext);
    if (n <= m)
        return 0;
    for (size_t i = 0; i < m; i++) {
        char c = path[n - m + i];
        if (c >= 'A' && c <= 'Z')
            c = (char)(c - 'A' + 'a');
        if (c != ext[i])
            return 0;
    }
    return 1;
}

bsp_status bsp_scene_load(const char *path, bsp_scene **out, bsp_error *err)
{
    if (out)
        *out = NULL;
    if (path && strncmp(path, "spd:", 4) == 0)
        return spd_scene_generate_spec(path, out, err);
    if (path && (has_extension(path, ".obj") || has_extension(path, ".obj.gz")))
        return obj_load_file(path, out, err);
    if (path && (has_extension(path, ".ply") || has_extension(path, ".ply.gz")))
        return ply_load_file(path, out, err);
    return nff_load_file(path, out, err);
}

bsp_status bsp_scene_check(const char *path, bsp_error *err)
{
    if (path && strncmp(path, "spd:", 4) == 0)
        return spd_spec_check(path, err);
    FILE *fp;
    size_t cap;
    bsp_status st = mesh_open_file(path, &fp, &cap, err);
    if (st == BSP_OK)
        fclose(fp);
    return st;
}
