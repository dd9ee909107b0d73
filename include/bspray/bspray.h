/*
 * bspray/bspray.h — the umbrella header of libbspray: version, status codes,
 * the error record, and the other public headers.
 */
#ifndef BSPRAY_BSPRAY_H
#define BSPRAY_BSPRAY_H

#define BSPRAY_VERSION_MAJOR 0
#define BSPRAY_VERSION_MINOR 1
#define BSPRAY_VERSION_PATCH 0
#define BSPRAY_VERSION_STRING "0.1.0"

#include "bspray/error.h"
#include "bspray/geom.h"
#include "bspray/scene.h"
#include "bspray/accel.h"
#include "bspray/render.h"
#include "bspray/spd.h"

#endif /* BSPRAY_BSPRAY_H */
