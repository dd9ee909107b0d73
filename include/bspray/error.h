/*
 * bspray/error.h — status codes and the error record used by every fallible
 * call of libbspray.
 *
 * Convention: a fallible call returns a bsp_status and, when the caller passes
 * a non-NULL bsp_error, fills it with a one-line message of the form
 * "FILE:LINE: what is wrong" (without the location where there is none).
 * The library never prints, never exits and never aborts.
 */
#ifndef BSPRAY_ERROR_H
#define BSPRAY_ERROR_H

#ifdef __cplusplus
extern "C" {
#endif

typedef enum bsp_status {
    BSP_OK = 0,
    BSP_ERR_IO,      /* a file could not be opened, read or written */
    BSP_ERR_PARSE,   /* malformed input: bad token, truncated record, ... */
    BSP_ERR_INVALID, /* a value out of its domain: NaN, inf, bad camera, bad option */
    BSP_ERR_LIMIT,   /* input that would need absurd memory or counts */
    BSP_ERR_NOMEM    /* an allocation failed */
} bsp_status;

/* Room for the message of a failed call. */
#define BSP_ERROR_MESSAGE_SIZE 1024

typedef struct bsp_error {
    bsp_status status;
    char message[BSP_ERROR_MESSAGE_SIZE];
} bsp_error;

/* A short constant name for a status ("ok", "io", "parse", ...). */
const char *bsp_status_name(bsp_status status);

#ifdef __cplusplus
}
#endif

#endif /* BSPRAY_ERROR_H */
