/*
 * gunzip.c — gzip input for every scene reader (NFF, OBJ, PLY): whole
 * buffers inflated with zlib, concatenated members included, under a size
 * limit (contract in scene_internal.h).
 */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

#include "scene/scene_internal.h"

int scene_is_gzip(const char *buf, size_t len)
{
    return len >= 2 && (unsigned char)buf[0] == 0x1f && (unsigned char)buf[1] == 0x8b;
}

bsp_status scene_gunzip(const char *in, size_t inlen, const char *name, size_t limit, char **out,
                        size_t *outlen, bsp_error *err)
{
    const size_t chunk = (size_t)1 << 30; /* zlib counts in 32-bit unsigned */
    z_stream zs;
    memset(&zs, 0, sizeof zs);
    if (inflateInit2(&zs, 15 + 32) != Z_OK)
        return error_set(err, BSP_ERR_NOMEM, name, 0, "out of memory (zlib)");
    size_t cap = inlen < limit / 4 ? inlen * 4 : limit;
    if (cap < 4096)
        cap = 4096;
    char *buf = malloc(cap);
    size_t used = 0, consumed = 0;
    bsp_status st = BSP_OK;
    if (!buf) {
        inflateEnd(&zs);
        return error_set(err, BSP_ERR_NOMEM, name, 0, "out of memory");
    }
    for (;;) {
        if (zs.avail_in == 0 && consumed < inlen) {
            size_t n = inlen - consumed < chunk ? inlen - consumed : chunk;
            zs.next_in = (Bytef *)(uintptr_t)(in + consumed);
            zs.avail_in = (uInt)n;
            consumed += n;
        }
        if (used == cap) {
            size_t ncap = cap * 2 > limit + 1 ? limit + 1 : cap * 2;
            char *nb = realloc(buf, ncap);
            if (!nb) {
                st = error_set(err, BSP_ERR_NOMEM, name, 0, "out of memory");
                break;
            }
            buf = nb;
            cap = ncap;
        }
        size_t room = cap - used < chunk ? cap - used : chunk;
        zs.next_out = (Bytef *)(buf + used);
        zs.avail_out = (uInt)room;
        int ret = inflate(&zs, Z_NO_FLUSH);
        used += room - zs.avail_out;
        if (used > limit) {
            st = error_set(err, BSP_ERR_LIMIT, name, 0, "gzip data inflates to more than %zu bytes",
                           limit);
            break;
        }
        if (ret == Z_STREAM_END) {
            if (zs.avail_in == 0 && consumed == inlen)
                break;
            if (inflateReset(&zs) != Z_OK) { /* another member follows */
                st = error_set(err, BSP_ERR_PARSE, name, 0, "corrupt gzip data");
                break;
            }
            continue;
        }
        if (ret == Z_OK)
            continue;
        if (ret == Z_BUF_ERROR && !(zs.avail_in == 0 && consumed == inlen))
            continue; /* needs more output room */
        if (ret == Z_MEM_ERROR) {
            st = error_set(err, BSP_ERR_NOMEM, name, 0, "out of memory (zlib)");
            break;
        }
        if (ret == Z_BUF_ERROR)
            st = error_set(err, BSP_ERR_PARSE, name, 0, "corrupt gzip data (truncated)");
        else
            st = error_set(err, BSP_ERR_PARSE, name, 0, "corrupt gzip data (%s)",
                           zs.msg ? zs.msg : "bad stream");
        break;
    }
    inflateEnd(&zs);
    if (st != BSP_OK) {
        free(buf);
        return st;
    }
    *out = buf;
    *outlen = used;
    return BSP_OK;
}


bsp_status scene_parse_maybe_gzip(scene_parse_fn parse, const char *buf, size_t len,
                                  const char *name, size_t limit, int gzip, bsp_scene **out,
                                  bsp_error *err)
{
    if (!gzip && !scene_is_gzip(buf, len))
        return parse(buf, len, name, out, err);
    char *plain = NULL;
    size_t plain_len = 0;
    bsp_status st = scene_gunzip(buf, len, name, limit, &plain, &plain_len, err);
    if (st != BSP_OK)
        return st;
    st = parse(plain, plain_len, name, out, err);
    free(plain);
    return st;
}
