/*
 * load.c — bsp_scene_load: one entry point for every kind of scene a user
 * names. "spd:NAME[:SIZE]" is generated in code (src/spd); anything else is
 * read as NFF (plain or gzip, detected by content).
 */
#include <string.h>

#include "scene/scene_internal.h"
#include "spd/spd.h"

bsp_status bsp_scene_load(const char *path, bsp_scene **out, bsp_error *err)
{
    if (out)
        *out = NULL;
    if (path && strncmp(path, "spd:", 4) == 0)
        return spd_scene_generate_spec(path, out, err);
    return nff_load_file(path, out, err);
}
