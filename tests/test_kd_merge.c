/*
 * test_kd_merge.c — the SAH builder's merge of new event keys into a sorted
 * list (src/accel/kd_merge.h): every way (the dispatch, the scalar ways, the
 * AVX2 ranks where the CPU has them) against the sorted union, over the
 * sizes each way takes and keys across the whole 64-bit range.
 */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "accel/kd_merge.h"
#include "harness.h"

static int cmp_u64(const void *x, const void *y)
{
    uint64_t a = *(const uint64_t *)x, b = *(const uint64_t *)y;
    return (a > b) - (a < b);
}

/* N distinct keys into K, of pattern P: spread over the whole range (the
 * sign bit both ways), crowded near 0 and near UINT64_MAX, or consecutive. */
static void distinct_keys(uint64_t *k, size_t n, int p, unsigned long long *rng)
{
    size_t got = 0;
    while (got < n) {
        uint64_t x = harness_xorshift64star(rng);
        switch (p) {
        case 0: break;
        case 1: x %= 3 * n + 1; break;
        case 2: x = UINT64_MAX - x % (3 * n + 1); break;
        default: x = (uint64_t)1 << 63 | (x % (2 * n + 2)); break;
        }
        int dup = 0;
        for (size_t i = 0; i < got; i++)
            dup |= k[i] == x;
        if (!dup)
            k[got++] = x;
    }
}

typedef void (*merge_fn)(uint64_t *, size_t, const uint64_t *, size_t);

static void ranked_or_scalar(uint64_t *dst, size_t a, const uint64_t *nw, size_t nn)
{
    if (!kd_merge_back_ranked(dst, a, nw, nn))
        kd_merge_back_scalar(dst, a, nw, nn);
}

TEST(kd_merge_back_matches_the_sorted_union)
{
    enum { MAXA = 80, MAXN = 24 };
    const merge_fn way[3] = {kd_merge_back, kd_merge_back_scalar, ranked_or_scalar};
    const char *name[3] = {"kd_merge_back", "scalar", "ranked"};
    unsigned long long rng = 0x9e3779b97f4a7c15ULL;
    uint64_t keys[MAXA + MAXN], want[MAXA + MAXN], dst[MAXA + MAXN + 1], nw[MAXN];
    int ranked_used = 0;
    for (size_t a = 0; a <= MAXA; a += a < 40 ? 1 : 7)
        for (size_t nn = 0; nn <= MAXN; nn++)
            for (int p = 0; p < 4; p++)
                for (int w = 0; w < 3; w++) {
                    distinct_keys(keys, a + nn, p, &rng);
                    memcpy(want, keys, (a + nn) * sizeof *keys);
                    qsort(want, a + nn, sizeof *want, cmp_u64);
                    /* which keys are old: a random choice, each side sorted */
                    for (size_t i = a + nn; i-- > 1;) {
                        size_t j = harness_xorshift64star(&rng) % (i + 1);
                        uint64_t t = keys[i];
                        keys[i] = keys[j];
                        keys[j] = t;
                    }
                    memcpy(dst, keys, a * sizeof *keys);
                    memcpy(nw, keys + a, nn * sizeof *keys);
                    qsort(dst, a, sizeof *dst, cmp_u64);
                    qsort(nw, nn, sizeof *nw, cmp_u64);
                    dst[a + nn] = 0x5a5a5a5a5a5a5a5aULL; /* past the room: untouched */
                    if (w == 2) {
                        uint64_t probe[MAXA + MAXN];
                        memcpy(probe, dst, a * sizeof *dst);
                        ranked_used |= kd_merge_back_ranked(probe, a, nw, nn);
                    }
                    way[w](dst, a, nw, nn);
                    CHECK_MSG(!memcmp(dst, want, (a + nn) * sizeof *dst) &&
                                  dst[a + nn] == 0x5a5a5a5a5a5a5a5aULL,
                              "%s: %zu old, %zu new keys, pattern %d", name[w], a, nn, p);
                }
    if (!ranked_used)
        printf("  note: this CPU has no AVX2 (or is not x86-64): the ranked merge was not run\n");
}
