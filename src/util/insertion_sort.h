/*
 * insertion_sort.h — the insertion sort the builders use for short arrays
 * (below their radix or qsort thresholds), for any type ordered by `>`.
 */
#ifndef BSPRAY_UTIL_INSERTION_SORT_H
#define BSPRAY_UTIL_INSERTION_SORT_H

#include <stddef.h>

/* Sorts A[0..N) of type T ascending, stable. */
#define INSERTION_SORT(T, A, N)                                                                 \
    do {                                                                                        \
        T *is_a_ = (A);                                                                         \
        size_t is_n_ = (N);                                                                     \
        for (size_t is_i_ = 1; is_i_ < is_n_; is_i_++) {                                        \
            T is_x_ = is_a_[is_i_];                                                             \
            size_t is_j_ = is_i_;                                                               \
            for (; is_j_ > 0 && is_a_[is_j_ - 1] > is_x_; is_j_--)                              \
                is_a_[is_j_] = is_a_[is_j_ - 1];                                                \
            is_a_[is_j_] = is_x_;                                                               \
        }                                                                                       \
    } while (0)

#endif /* BSPRAY_UTIL_INSERTION_SORT_H */
