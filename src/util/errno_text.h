/*
 * errno_text.h — the text of an error number for messages, without the
 * buffer strerror may share between threads (the library keeps no state
 * that threads share: bspray/bspray.h).
 */
#ifndef BSPRAY_UTIL_ERRNO_TEXT_H
#define BSPRAY_UTIL_ERRNO_TEXT_H

#include <stddef.h>

/* The text of error number E in BUF (of N bytes), by strerror_r; "error E"
 * for a number it does not know. Returns BUF. */
__attribute__((visibility("hidden"))) const char *error_errno_text(int e, char *buf, size_t n);
/* The same in a buffer of the calling expression's own (a compound literal,
 * which lives until the end of the enclosing block). */
#define ERRNO_TEXT(e) error_errno_text((e), (char[128]){0}, 128)

#endif /* BSPRAY_UTIL_ERRNO_TEXT_H */
