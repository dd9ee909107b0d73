/*
 * error.c — status names and the formatting of bsp_error records
 * ("NAME:LINE: message").
 */
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "scene/scene_internal.h"
#include "util/errno_text.h"

const char *bsp_status_name(bsp_status status)
{
    switch (status) {
    case BSP_OK:
        return "ok";
    case BSP_ERR_IO:
        return "io";
    case BSP_ERR_PARSE:
        return "parse";
    case BSP_ERR_INVALID:
        return "invalid";
    case BSP_ERR_LIMIT:
        return "limit";
    case BSP_ERR_NOMEM:
        return "out of memory";
    }
    return "unknown";
}

static void error_vrecord(bsp_error *err, bsp_status status, const char *name, size_t line,
                          const char *fmt, va_list ap)
{
    if (!err)
        return;
    err->status = status;
    int n = 0;
    if (name && line > 0)
        n = snprintf(err->message, sizeof err->message, "%s:%zu: ", name, line);
    else if (name)
        n = snprintf(err->message, sizeof err->message, "%s: ", name);
    if (n < 0 || (size_t)n >= sizeof err->message)
        n = 0;
    vsnprintf(err->message + n, sizeof err->message - (size_t)n, fmt, ap);
}

void error_record(bsp_error *err, bsp_status status, const char *name, size_t line,
                  const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    error_vrecord(err, status, name, line, fmt, ap);
    va_end(ap);
}

void scene_fail_record(const bsp_scene *s, bsp_error *err, bsp_status status, const char *fmt,
                       ...)
{
    va_list ap;
    va_start(ap, fmt);
    error_vrecord(err, status, s ? s->src_name : NULL, s ? s->src_line : 0, fmt, ap);
    va_end(ap);
}

const char *error_errno_text(int e, char *buf, size_t n)
{
    /* the XSI strerror_r (0 on success): _GNU_SOURCE is not defined here */
    if (strerror_r(e, buf, n) != 0)
        snprintf(buf, n, "error %d", e);
    return buf;
}
