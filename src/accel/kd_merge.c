/*
 * kd_merge.c — the merges of kd_merge.h.
 *
 * On tetra:7 about 166,000 merges run per build, nearly all of 3-8 new keys
 * into fewer than 32 old ones. The branch-free merge there is a chain of
 * dependent loads and compares (session 31: 40 % of its samples on the
 * chain's head load); counting ranks with vector compares has no chain,
 * and took the one-thread build of tetra:7, teapot:12, gears and the
 * dragon's res3 2-3 % faster (session 35), with the same trees.
 */
#include "accel/kd_merge.h"

#include <string.h>

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#define MERGE_RANKED_MAX 8

/* Each key's place is its rank. An old key DST[i] goes to i + (new keys
 * below it), taken from the back so that no key is overwritten before it is
 * read (its place is at or above i, and above every place taken before it
 * in this order); a new key j to j + (old keys below it) = j + A - (old keys
 * above it), the keys being distinct. The new keys are padded to 8 with the
 * largest key: a pad is below no old key, and its own count is not used. */
__attribute__((target("avx2,popcnt"))) static void
merge_ranked_avx2(uint64_t *dst, size_t a, const uint64_t *nw, size_t nn)
{
    uint64_t k[MERGE_RANKED_MAX], above[MERGE_RANKED_MAX];
    for (size_t j = 0; j < MERGE_RANKED_MAX; j++)
        k[j] = j < nn ? nw[j] : UINT64_MAX;
    /* unsigned order from the signed compare: the sign bits flipped */
    const __m256i flip = _mm256_set1_epi64x((long long)(UINT64_C(1) << 63));
    const __m256i k0 = _mm256_xor_si256(_mm256_loadu_si256((const __m256i *)(const void *)k), flip);
    const __m256i k1 =
        _mm256_xor_si256(_mm256_loadu_si256((const __m256i *)(const void *)(k + 4)), flip);
    __m256i n0 = _mm256_setzero_si256(), n1 = _mm256_setzero_si256(); /* minus the counts */
    for (size_t i = a; i-- > 0;) {
        const uint64_t x = dst[i];
        const __m256i xv = _mm256_xor_si256(_mm256_set1_epi64x((long long)x), flip);
        const __m256i lt0 = _mm256_cmpgt_epi64(xv, k0), lt1 = _mm256_cmpgt_epi64(xv, k1);
        n0 = _mm256_add_epi64(n0, lt0); /* all ones (-1) where k[j] < x */
        n1 = _mm256_add_epi64(n1, lt1);
        const unsigned bits = (unsigned)_mm256_movemask_pd(_mm256_castsi256_pd(lt0)) |
                              (unsigned)_mm256_movemask_pd(_mm256_castsi256_pd(lt1)) << 4;
        dst[i + (size_t)__builtin_popcount(bits)] = x;
    }
    _mm256_storeu_si256((__m256i *)(void *)above, n0);
    _mm256_storeu_si256((__m256i *)(void *)(above + 4), n1);
    for (size_t j = 0; j < nn; j++)
        dst[j + a + above[j]] = nw[j]; /* above[j] holds minus the count (mod 2^64) */
}

int kd_merge_back_ranked(uint64_t *dst, size_t a, const uint64_t *nw, size_t nn)
{
    /* every CPU with AVX2 has POPCNT (Haswell, Excavator and later) */
    if (nn > MERGE_RANKED_MAX || !__builtin_cpu_supports("avx2"))
        return 0;
    merge_ranked_avx2(dst, a, nw, nn);
    return 1;
}
#else
int kd_merge_back_ranked(uint64_t *dst, size_t a, const uint64_t *nw, size_t nn)
{
    (void)dst;
    (void)a;
    (void)nw;
    (void)nn;
    return 0;
}
#endif

/* Few new keys (under 1/4 of the list): each is placed by a galloping
 * search back from the last placed one, and the block of old keys above it
 * moved at once — each old key moved once, as in the plain merge, without a
 * compare and branch per key. */
void kd_merge_back_scalar(uint64_t *dst, size_t a, const uint64_t *nw, size_t nn)
{
    if (nn * 4 < a) {
        for (; nn > 0; nn--) {
            const uint64_t x = nw[nn - 1];
            size_t hi = a, step = 1; /* dst[hi..a) > x */
            while (hi > 0 && dst[hi - 1] > x) {
                size_t lo = hi > step ? hi - step : 0;
                if (dst[lo] > x) {
                    hi = lo;
                    step *= 2;
                    continue;
                }
                while (lo + 1 < hi) { /* dst[lo] < x < dst[hi] (keys are distinct) */
                    size_t mid = lo + (hi - lo) / 2;
                    if (dst[mid] > x)
                        hi = mid;
                    else
                        lo = mid;
                }
                break;
            }
            size_t len = a - hi;
            uint64_t *from = dst + hi, *to = dst + hi + nn;
            if (len > 16)
                memmove(to, from, len * sizeof *dst);
            else
                while (len-- > 0)
                    to[len] = from[len];
            dst[hi + nn - 1] = x;
            a = hi;
        }
        return;
    }
    /* branch-free: which list gives the next key is unpredictable */
    size_t o = a + nn;
    while (nn > 0 && a > 0) {
        const uint64_t x = dst[a - 1], y = nw[nn - 1];
        const size_t from_old = x > y;
        dst[--o] = from_old ? x : y;
        a -= from_old;
        nn -= from_old ^ 1;
    }
    while (nn > 0)
        dst[--o] = nw[--nn];
}

void kd_merge_back(uint64_t *dst, size_t a, const uint64_t *nw, size_t nn)
{
    /* ranks where the plain merge would run (the old keys at most 4 times
     * the new), else the scalar ways */
    if (nn * 4 >= a && kd_merge_back_ranked(dst, a, nw, nn))
        return;
    kd_merge_back_scalar(dst, a, nw, nn);
}
