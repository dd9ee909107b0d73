/*
 * bspray/bspray.h — the umbrella header of libbspray: version, status codes,
 * the error record, and the other public headers.
 *
 * Threads: the library keeps no mutable global state, so calls on different
 * objects (scenes, structures, queries, images) may run on any threads at
 * once, and a built structure may be queried by many threads at once, each
 * with a bsp_query of its own (bspray/accel.h). One object must not be
 * changed by one thread while another uses it.
 */
#ifndef BSPRAY_BSPRAY_H
#define BSPRAY_BSPRAY_H

#define BSPRAY_VERSION_MAJOR 0
#define BSPRAY_VERSION_MINOR 2
#define BSPRAY_VERSION_PATCH 1
#define BSPRAY_VERSION_STRING "0.2.1"

#include "bspray/error.h"
#include "bspray/geom.h"
#include "bspray/scene.h"
#include "bspray/accel.h"
#include "bspray/render.h"
#include "bspray/spd.h"

#endif /* BSPRAY_BSPRAY_H */
