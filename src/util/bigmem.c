/*
 * bigmem.c — huge-page advice for large arrays (bigmem.h).
 */
#define _DEFAULT_SOURCE /* madvise's MADV_HUGEPAGE (a Linux extension) */
#include "util/bigmem.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#if defined(__linux__)
#include <sys/mman.h>
#endif

#define HUGE_PAGE ((uintptr_t)2 << 20)

void bigmem_advise(void *p, size_t bytes)
{
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    if (!p || bytes < HUGE_PAGE)
        return; /* no whole huge page inside */
    uintptr_t lo = ((uintptr_t)p + HUGE_PAGE - 1) & ~(HUGE_PAGE - 1);
    uintptr_t hi = ((uintptr_t)p + bytes) & ~(HUGE_PAGE - 1);
    if (hi > lo)
        (void)madvise((void *)lo, hi - lo, MADV_HUGEPAGE); /* advice: failure is harmless */
#else
    (void)p;
    (void)bytes;
#endif
}

void *bigmem_malloc(size_t bytes)
{
    void *p = malloc(bytes);
    bigmem_advise(p, bytes);
    return p;
}

void *bigmem_realloc(void *p, size_t used, size_t bytes)
{
    if (bytes < HUGE_PAGE)
        return realloc(p, bytes);
    void *np = bigmem_malloc(bytes);
    if (!np)
        return NULL;
    if (p)
        memcpy(np, p, used < bytes ? used : bytes);
    free(p);
    return np;
}
