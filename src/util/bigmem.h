/*
 * bigmem.h — the builders' large arrays on transparent huge pages.
 *
 * A build touches tens of megabytes of fresh memory (balls:6: the event
 * stack alone reaches 80 MB), and on 4 KiB pages each page costs a page fault
 * when first written and a TLB entry while it is read: on the VM the
 * benchmarks run on that was a fifth to a third of a one-thread build's
 * CPU time (docs/kdtree-log.md, "Session 21: the build on huge pages"). bigmem_advise asks
 * the kernel for 2 MiB pages on an array's aligned interior where the system
 * offers them (Linux madvise MADV_HUGEPAGE, which "madvise" mode of
 * transparent_hugepage honours); elsewhere, and for arrays under 2 MiB, it
 * does nothing. The memory stays malloc's: free it with free.
 */
#ifndef BSPRAY_UTIL_BIGMEM_H
#define BSPRAY_UTIL_BIGMEM_H

#include <stddef.h>

/* Advises huge pages for the BYTES at P (from malloc or realloc); no effect
 * on its contents, and none at all when P is NULL or the array is small. */
void bigmem_advise(void *p, size_t bytes);

/* malloc, then bigmem_advise. */
void *bigmem_malloc(size_t bytes);

/* Like realloc(P, BYTES) for an array of which the first USED bytes are
 * kept. An array of a huge page or more is made anew (bigmem_malloc), the
 * USED bytes copied and P freed: realloc would copy into fresh memory before
 * the advice could reach it. NULL on failure, P untouched. */
void *bigmem_realloc(void *p, size_t used, size_t bytes);

#endif /* BSPRAY_UTIL_BIGMEM_H */
