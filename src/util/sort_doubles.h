/*
 * sort_doubles.h — ascending sort of finite doubles by an LSD radix sort of
 * their bits (the kd-tree's counted ray measure and the leaf budget's
 * estimate sort arrays of up to millions of values).
 */
#ifndef BSPRAY_UTIL_SORT_DOUBLES_H
#define BSPRAY_UTIL_SORT_DOUBLES_H

#include <stddef.h>
#include <stdint.h>

/* Sorts V[0..N) ascending; TMP has room for N keys. No NaN (infinities
 * are fine). -0 and +0 compare equal and may come in either order, so no
 * count by `<` or `>=` can tell the result from any other ascending order. */
void sort_doubles(double *v, size_t n, uint64_t *tmp);

#endif
