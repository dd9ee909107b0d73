/*
 * test_sort.c — the builders' integer sort (src/util/sort.h) against qsort
 * on arrays that stress it: random keys with many or no repeats, sorted,
 * reversed, all equal, organ-pipe, and the lengths around its insertion
 * sort threshold; and the heapsort that bounds its worst case, alone. The
 * radix sort of doubles (src/util/sort_doubles.h) against qsort on values of
 * both signs, zeros of both signs, repeats, infinities and magnitudes from
 * subnormal to huge. The radix sort of keys by their upper bits
 * (src/util/radix_sort.h), which must be stable, against qsort of the whole
 * keys whose low bits are the original index.
 */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"
#include "util/radix_sort.h"
#include "util/sort.h"
#include "util/sort_doubles.h"

DEFINE_SORT(sort_u64_under_test, uint64_t, 24)

static int cmp_u64(const void *x, const void *y)
{
    uint64_t a = *(const uint64_t *)x, b = *(const uint64_t *)y;
    return (a > b) - (a < b);
}

static uint64_t rng = 88172645463325252ull;
static uint64_t next_u64(void)
{
    return harness_xorshift64(&rng);
}

/* Fills A[0..N) by pattern P. */
static void fill(uint64_t *a, size_t n, int p)
{
    for (size_t i = 0; i < n; i++) {
        switch (p) {
        case 0: a[i] = next_u64(); break;                 /* distinct, random */
        case 1: a[i] = next_u64() % 5; break;             /* many repeats */
        case 2: a[i] = i; break;                          /* sorted */
        case 3: a[i] = n - i; break;                      /* reversed */
        case 4: a[i] = 7; break;                          /* all equal */
        default: a[i] = i < n / 2 ? i : n - i; break;     /* organ pipe */
        }
    }
}

TEST(sort_matches_qsort)
{
    const size_t lens[] = {0, 1, 2, 3, 23, 24, 25, 26, 48, 49, 100, 1000, 4097, 30000};
    uint64_t *a = malloc(30000 * sizeof *a), *b = malloc(30000 * sizeof *b);
    REQUIRE(a && b);
    for (size_t li = 0; li < sizeof lens / sizeof *lens; li++)
        for (int p = 0; p < 6; p++) {
            size_t n = lens[li];
            fill(a, n, p);
            memcpy(b, a, n * sizeof *a);
            sort_u64_under_test(a, n);
            qsort(b, n, sizeof *b, cmp_u64);
            CHECK_MSG(n == 0 || !memcmp(a, b, n * sizeof *a), "length %zu, pattern %d", n, p);
        }
    free(a);
    free(b);
}

TEST(sort_heap_fallback_sorts)
{
    uint64_t a[1000], b[1000];
    for (int p = 0; p < 6; p++) {
        fill(a, 1000, p);
        memcpy(b, a, sizeof a);
        sort_u64_under_test_heap(a, 1000);
        qsort(b, 1000, sizeof *b, cmp_u64);
        CHECK_MSG(!memcmp(a, b, sizeof a), "pattern %d", p);
    }
}

static int cmp_double(const void *x, const void *y)
{
    double a = *(const double *)x, b = *(const double *)y;
    return (a > b) - (a < b);
}

/* A double of pattern P at I. */
static double double_of(size_t i, size_t n, int p)
{
    uint64_t r = next_u64();
    double u = (double)(r >> 11) / 9007199254740992.0; /* [0, 1) */
    switch (p) {
    case 0: return (u - 0.5) * 1e3;                           /* both signs */
    case 1: return ldexp(u + 0.5, (int)(r % 2000) - 1000) * ((r >> 20) & 1 ? -1 : 1); /* magnitudes */
    case 2: return (double)(r % 5) - 2.0;                    /* repeats, a zero */
    case 3: return (r & 1) ? 0.0 : -0.0;                     /* zeros of both signs */
    case 4: return (double)(n - i);                          /* reversed */
    default: /* specials among ordinary values */
        switch (r % 6) {
        case 0: return INFINITY;
        case 1: return -INFINITY;
        case 2: return 4.9e-324;
        case 3: return -4.9e-324;
        default: return u;
        }
    }
}

TEST(sort_doubles_matches_qsort)
{
    const size_t lens[] = {0, 1, 2, 63, 64, 65, 1000, 30000};
    double *a = malloc(30000 * sizeof *a), *b = malloc(30000 * sizeof *b);
    uint64_t *tmp = malloc(30000 * sizeof *tmp);
    REQUIRE(a && b && tmp);
    for (size_t li = 0; li < sizeof lens / sizeof *lens; li++)
        for (int p = 0; p < 6; p++) {
            size_t n = lens[li];
            for (size_t i = 0; i < n; i++)
                a[i] = b[i] = double_of(i, n, p);
            sort_doubles(a, n, tmp);
            qsort(b, n, sizeof *b, cmp_double);
            /* equal as values: -0 and +0 compare equal, and either sort
             * may put them in either order */
            int same = 1;
            for (size_t i = 0; i < n; i++)
                same &= a[i] == b[i];
            CHECK_MSG(same, "length %zu, pattern %d", n, p);
        }
    free(a);
    free(b);
    free(tmp);
}

/* Keys of pattern P in bits LOW..63 (the rest below LOW is the index, so
 * qsort of whole keys gives the one stable order by the upper bits). */
static uint64_t upper_of(size_t i, unsigned low, int p)
{
    uint64_t r = next_u64();
    switch (p) {
    case 0: break;                                             /* random */
    case 1: r %= 7; if (64 - low > 3) r <<= 61 - low; break;  /* few values, top digits only */
    case 2: r = (uint64_t)0xabcdef << 20 | (r & 0xfff); break; /* shared upper digits */
    case 3: r = 42; break;                                     /* all equal: every digit skipped */
    default: r = ~(uint64_t)i; break;                          /* reversed */
    }
    return low == 0 ? r : r << low;
}

TEST(radix_sort_is_stable_by_the_upper_bits)
{
    const size_t lens[] = {0, 1, 2, 3, 100, 4097, 30000};
    const unsigned lows[] = {0, 28, 40, 63};
    const unsigned widths[] = {1, 5, 8, 11, 12};
    uint64_t *a = malloc(30000 * sizeof *a), *b = malloc(30000 * sizeof *b);
    uint64_t *tmp = malloc(30000 * sizeof *tmp);
    REQUIRE(a && b && tmp);
    for (size_t li = 0; li < sizeof lens / sizeof *lens; li++)
        for (size_t lo = 0; lo < sizeof lows / sizeof *lows; lo++)
            for (size_t wi = 0; wi < sizeof widths / sizeof *widths; wi++)
                for (int p = 0; p < 5; p++) {
                    size_t n = lens[li];
                    unsigned low = lows[lo];
                    /* the index below LOW (as much of it as fits) */
                    uint64_t index_mask = low == 0 ? 0 : (low >= 64 ? ~0ull : ((uint64_t)1 << low) - 1);
                    for (size_t i = 0; i < n; i++)
                        a[i] = b[i] = upper_of(i, low, p) | (i & index_mask);
                    radix_sort_u64(a, tmp, n, low, widths[wi]);
                    int ok = 1;
                    if (low == 0 || n <= index_mask + 1) {
                        qsort(b, n, sizeof *b, cmp_u64);
                        ok = n == 0 || !memcmp(a, b, n * sizeof *a);
                    } else { /* the index does not fit: ascending by the upper bits, a permutation */
                        for (size_t i = 1; i < n; i++)
                            ok &= (a[i - 1] >> low) <= (a[i] >> low);
                        uint64_t sa = 0, sb = 0;
                        for (size_t i = 0; i < n; i++)
                            sa += a[i] * 0x9e3779b97f4a7c15ull ^ a[i], sb += b[i] * 0x9e3779b97f4a7c15ull ^ b[i];
                        ok &= sa == sb;
                    }
                    CHECK_MSG(ok, "length %zu, low %u, width %u, pattern %d", n, low, widths[wi], p);
                }
    free(a);
    free(b);
    free(tmp);
}
