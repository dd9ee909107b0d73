/*
 * sort.h — an in-place sort of keys ordered by `<` (integers, finite
 * doubles) for the builders' arrays too long for insertion sort: introsort
 * (quicksort with a median-of-three pivot, insertion sort for parts of at
 * most SMALL keys, heapsort past a depth limit, so never worse than
 * O(n log n)), without qsort's call per comparison. DEFINE_SORT(NAME, T,
 * SMALL) defines `static void NAME(T *a, size_t n)`, sorting ascending by
 * `<` (not stable: for keys that are distinct or need not be). SMALL >= 3
 * (the median of three needs it).
 */
#ifndef BSPRAY_UTIL_SORT_H
#define BSPRAY_UTIL_SORT_H

#include <stddef.h>

#include "util/insertion_sort.h"

#define DEFINE_SORT(NAME, T, SMALL)                                                                    \
    static void NAME##_sift(T *a, size_t i, size_t n)                                           \
    {                                                                                           \
        T x = a[i];                                                                             \
        for (size_t c; (c = 2 * i + 1) < n; i = c) {                                            \
            if (c + 1 < n && a[c] < a[c + 1])                                                   \
                c++;                                                                            \
            if (!(x < a[c]))                                                                    \
                break;                                                                          \
            a[i] = a[c];                                                                        \
        }                                                                                       \
        a[i] = x;                                                                               \
    }                                                                                           \
    static void NAME##_heap(T *a, size_t n)                                                     \
    {                                                                                           \
        for (size_t i = n / 2; i-- > 0;)                                                        \
            NAME##_sift(a, i, n);                                                               \
        for (size_t e = n; e-- > 1;) {                                                          \
            T x = a[0];                                                                         \
            a[0] = a[e];                                                                        \
            a[e] = x;                                                                           \
            NAME##_sift(a, 0, e);                                                               \
        }                                                                                       \
    }                                                                                           \
    static void NAME##_intro(T *a, size_t n, int depth)                                         \
    {                                                                                           \
        while (n > (SMALL)) {                                                                \
            if (depth-- == 0) {                                                                 \
                NAME##_heap(a, n);                                                              \
                return;                                                                         \
            }                                                                                   \
            /* median of three to a[0] as the pivot; a[1] <= it <= a[n - 1] */                  \
            size_t m = n / 2;                                                                   \
            T t;                                                                                \
            if (a[m] < a[1]) { t = a[m]; a[m] = a[1]; a[1] = t; }                               \
            if (a[n - 1] < a[1]) { t = a[n - 1]; a[n - 1] = a[1]; a[1] = t; }                   \
            if (a[n - 1] < a[m]) { t = a[n - 1]; a[n - 1] = a[m]; a[m] = t; }                   \
            t = a[m]; a[m] = a[0]; a[0] = t;                                                    \
            const T p = a[0];                                                                   \
            size_t i = 1, j = n - 1; /* Hoare: a[1..i) <= p, a(j..n) >= p */                    \
            for (;;) {                                                                          \
                do i++; while (a[i] < p);                                                       \
                do j--; while (p < a[j]);                                                       \
                if (i >= j)                                                                     \
                    break;                                                                      \
                t = a[i]; a[i] = a[j]; a[j] = t;                                                \
            }                                                                                   \
            a[0] = a[j];                                                                        \
            a[j] = p;                                                                           \
            /* the smaller side by recursion, the larger by the loop */                         \
            if (j < n - 1 - j) {                                                                \
                NAME##_intro(a, j, depth);                                                      \
                a += j + 1;                                                                     \
                n -= j + 1;                                                                     \
            } else {                                                                            \
                NAME##_intro(a + j + 1, n - j - 1, depth);                                      \
                n = j;                                                                          \
            }                                                                                   \
        }                                                                                       \
        INSERTION_SORT(T, a, n);                                                                \
    }                                                                                           \
    static inline void NAME(T *a, size_t n)                                                     \
    {                                                                                           \
        if (n <= (SMALL)) { /* most calls: no depth to count */                                 \
            INSERTION_SORT(T, a, n);                                                            \
            return;                                                                             \
        }                                                                                       \
        int depth = 0;                                                                          \
        for (size_t k = n; k > 1; k >>= 1)                                                      \
            depth += 2;                                                                         \
        NAME##_intro(a, n, depth);                                                              \
    }

#endif /* BSPRAY_UTIL_SORT_H */
