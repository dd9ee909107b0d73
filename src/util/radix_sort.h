/*
 * radix_sort.h — a stable LSD radix sort of 64-bit keys by their upper bits
 * (the SAH builder's root event lists, the sort of doubles by their bits).
 */
#ifndef BSPRAY_UTIL_RADIX_SORT_H
#define BSPRAY_UTIL_RADIX_SORT_H

#include <stddef.h>
#include <stdint.h>

#define RADIX_SORT_MAX_BITS 12 /* the widest digit: a histogram of 32 KiB on the stack */

/* Sorts A[0..N) stably by key bits LOW..63, in digits of BITS bits (1 to
 * RADIX_SORT_MAX_BITS) from the lowest up, through TMP[0..N). A digit that
 * every key shares (keys from one cell, or values of one magnitude, share
 * their upper bits) is counted but not moved. Keys whose bits 0..LOW-1
 * rise with their index end up in the order of the whole key. */
void radix_sort_u64(uint64_t *a, uint64_t *tmp, size_t n, unsigned low, unsigned bits);

#endif /* BSPRAY_UTIL_RADIX_SORT_H */
