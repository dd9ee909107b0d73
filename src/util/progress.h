/*
 * progress.h — a small terminal progress bar for the CLI:
 *   "render [##########          ]  50%  1.2s, ~1.2s left"
 * redrawn in place with \r at most ~10 times a second. It draws only when the
 * stream is a terminal and BSPRAY_NO_PROGRESS is not set; otherwise every call
 * is a silent no-op. Use from one thread only.
 */
#ifndef BSPRAY_UTIL_PROGRESS_H
#define BSPRAY_UTIL_PROGRESS_H

#include <stdio.h>

typedef struct progress_bar progress_bar;

/* A new bar writing to OUT (enabled only when OUT is a terminal and the
 * environment has no BSPRAY_NO_PROGRESS). LABEL may be NULL. NULL only when
 * out of memory; every function accepts NULL. */
__attribute__((visibility("hidden"))) progress_bar *progress_create(FILE *out, const char *label);
/* Nonzero when the bar draws anything. */
__attribute__((visibility("hidden"))) int progress_enabled(const progress_bar *p);
/* Reports FRACTION (0..1, clamped) done; redraws at most ~10 times a second. */
__attribute__((visibility("hidden"))) void progress_update(progress_bar *p, double fraction);
/* Draws the final 100% line and a newline (when enabled) and frees P. */
__attribute__((visibility("hidden"))) void progress_finish(progress_bar *p);

#endif /* BSPRAY_UTIL_PROGRESS_H */
