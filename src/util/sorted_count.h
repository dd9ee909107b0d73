/*
 * sorted_count.h — counting the values of a sorted array at or above a
 * bound, by binary search (the leaf budget's estimate, the counted ray
 * model).
 */
#ifndef BSPRAY_UTIL_SORTED_COUNT_H
#define BSPRAY_UTIL_SORTED_COUNT_H

#include <stddef.h>

/* How many of A[0..N), sorted ascending, are >= X (NaN-free A). */
static inline size_t sorted_count_at_least(const double *a, size_t n, double x)
{
    size_t lo = 0, hi = n; /* a[0..lo) < x <= a[hi..n) */
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (a[mid] < x)
            lo = mid + 1;
        else
            hi = mid;
    }
    return n - lo;
}

#endif /* BSPRAY_UTIL_SORTED_COUNT_H */
