/*
 * test_bigmem.c — the builders' huge-page arrays (src/util/bigmem.h): growing
 * and shrinking an array through bigmem_realloc keeps its used bytes, across
 * the 2 MiB line where it stops being realloc and becomes a new array and a
 * copy; the advice leaves contents alone, whatever the pointer's alignment.
 */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"
#include "util/bigmem.h"

static uint8_t pattern(size_t i)
{
    return (uint8_t)(i * 2654435761u >> 13);
}

/* 1 when the first N bytes of P follow the pattern. */
static int holds_pattern(const uint8_t *p, size_t n)
{
    for (size_t i = 0; i < n; i++)
        if (p[i] != pattern(i))
            return 0;
    return 1;
}

TEST(bigmem_realloc_keeps_the_used_bytes)
{
    /* sizes around the huge page (2 MiB): small, just under, at, over, down again */
    const size_t sizes[] = {100,       4096,      (2u << 20) - 1, 2u << 20, (2u << 20) + 1,
                            9u << 20,  3u << 20,  1u << 20,       64,       12u << 20};
    uint8_t *p = NULL;
    size_t used = 0;
    for (size_t k = 0; k < sizeof sizes / sizeof sizes[0]; k++) {
        size_t n = sizes[k];
        uint8_t *q = bigmem_realloc(p, used, n);
        REQUIRE(q);
        size_t kept = used < n ? used : n;
        CHECK_MSG(holds_pattern(q, kept), "step %zu: %zu -> %zu bytes", k, used, n);
        for (size_t i = kept; i < n; i++)
            q[i] = pattern(i);
        p = q;
        used = n;
    }
    CHECK(holds_pattern(p, used));
    free(p);
}

TEST(bigmem_advice_leaves_contents_alone)
{
    bigmem_advise(NULL, 8u << 20); /* nothing to advise */
    size_t n = 9u << 20;
    uint8_t *p = malloc(n + 4096);
    REQUIRE(p);
    for (size_t i = 0; i < n + 4096; i++)
        p[i] = pattern(i);
    /* unaligned starts and lengths, and arrays too small for a huge page */
    bigmem_advise(p + 1, n - 3);
    bigmem_advise(p + 4095, 5u << 20);
    bigmem_advise(p, 100);
    CHECK(holds_pattern(p, n + 4096));
    free(p);
    uint8_t *q = bigmem_malloc(n);
    REQUIRE(q);
    memset(q, 0xa5, n);
    CHECK(q[0] == 0xa5 && q[n / 2] == 0xa5 && q[n - 1] == 0xa5);
    free(q);
}
