/*
 * sorted_count.h — binary searches in sorted arrays: the first value at or
 * above a bound (the SAH builder's split event), and how many values lie at
 * or above it (the leaf budget's estimate, the counted ray model).
 */
#ifndef BSPRAY_UTIL_SORTED_COUNT_H
#define BSPRAY_UTIL_SORTED_COUNT_H

#include <stddef.h>
#include <stdint.h>

/* Defines `static inline size_t NAME(const T *a, size_t n, T x)`: the index
 * of the first of A[0..N), sorted ascending by `<`, that is not below X
 * (N when all are). */
#define DEFINE_SORTED_FIRST_AT_LEAST(NAME, T)                                                   \
    static inline size_t NAME(const T *a, size_t n, T x)                                        \
    {                                                                                           \
        size_t lo = 0, hi = n; /* a[0..lo) < x <= a[hi..n) */                                   \
        while (lo < hi) {                                                                       \
            size_t mid = lo + (hi - lo) / 2;                                                    \
            if (a[mid] < x)                                                                     \
                lo = mid + 1;                                                                   \
            else                                                                                \
                hi = mid;                                                                       \
        }                                                                                       \
        return lo;                                                                              \
    }

DEFINE_SORTED_FIRST_AT_LEAST(sorted_first_at_least, double)
DEFINE_SORTED_FIRST_AT_LEAST(sorted_first_at_least_u64, uint64_t)

/* How many of A[0..N), sorted ascending, are >= X (NaN-free A). */
static inline size_t sorted_count_at_least(const double *a, size_t n, double x)
{
    return n - sorted_first_at_least(a, n, x);
}

#endif /* BSPRAY_UTIL_SORTED_COUNT_H */
