/*
 * fnv.h — the 64-bit FNV-1a hash of 32-bit words, for the structures'
 * digests (bsp_tree_stats.digest).
 */
#ifndef BSPRAY_UTIL_FNV_H
#define BSPRAY_UTIL_FNV_H

#include <stdint.h>

#define FNV1A_BASIS 14695981039346656037ull

/* FNV-1a (64 bits) of H extended by the 4 bytes of X, least significant
 * first (the same digest on every byte order). */
static inline uint64_t fnv1a_u32(uint64_t h, uint32_t x)
{
    for (int i = 0; i < 4; i++) {
        h ^= (x >> (8 * i)) & 0xffu;
        h *= 1099511628211ull;
    }
    return h;
}

#endif /* BSPRAY_UTIL_FNV_H */
