/*
 * bspray/spd.h — Eric Haines' Standard Procedural Databases, generated in
 * code. Every scene that bsp_scene_load accepts as "spd:NAME[:SIZE][:tN]"
 * can also be written out as NFF text, formatted as the SPD programs print
 * it. ":tN" (N = 2..64) replaces spheres and cones by triangle patches, like
 * the SPD programs' -t option (scheme: src/spd/spd.h).
 */
#ifndef BSPRAY_SPD_API_H
#define BSPRAY_SPD_API_H

#include <stdio.h>

#include "bspray/error.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Writes the NFF text of scene NAME at size factor SIZE (0: the scene's
 * default) to OUT, with spheres and cones tessellated at level TESSELLATE
 * (0: not tessellated; else 2..64). Loading that text gives exactly the
 * scene "spd:NAME:SIZE:tN" builds. An unknown name, a size outside the
 * scene's range or a bad level is BSP_ERR_INVALID (nothing written); a
 * failed write BSP_ERR_IO. */
bsp_status bsp_spd_write_nff(const char *name, int size, int tessellate, FILE *out,
                             bsp_error *err);

/* The known scene names separated by single spaces (a static string). */
const char *bsp_spd_scene_names(void);

/* Default, smallest and largest size factor of scene NAME; returns 0 when the
 * name is unknown. Any pointer may be NULL. */
int bsp_spd_scene_sizes(const char *name, int *def, int *min, int *max);

#ifdef __cplusplus
}
#endif

#endif /* BSPRAY_SPD_API_H */
