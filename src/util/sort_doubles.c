/*
 * sort_doubles.c — the radix sort of sort_doubles.h.
 */
#include "util/sort_doubles.h"

#include <string.h>

#include "util/insertion_sort.h"

/* Doubles as unsigned keys of the same order: a negative value's bits all
 * flipped (larger magnitudes become smaller keys), a positive value's sign
 * bit set (above every negative one). */
static uint64_t double_key(double x)
{
    uint64_t u;
    memcpy(&u, &x, sizeof u);
    return (u >> 63) ? ~u : u | ((uint64_t)1 << 63);
}

static double key_double(uint64_t k)
{
    uint64_t u = (k >> 63) ? k & ~((uint64_t)1 << 63) : ~k;
    double x;
    memcpy(&x, &u, sizeof x);
    return x;
}

#define RADIX_MIN 64 /* fewer values: insertion sort */

/* An LSD radix sort by bytes of the keys, skipping the bytes all keys share
 * (coordinates of one cell, or savings of one magnitude, share their upper
 * bytes). On gears' counted build glibc's qsort with a comparison callback
 * took 1.23 G of 9.75 G instructions, this 0.94 G. */
void sort_doubles(double *v, size_t n, uint64_t *tmp)
{
    if (n < RADIX_MIN) {
        INSERTION_SORT(double, v, n);
        return;
    }
    size_t hist[8][256];
    memset(hist, 0, sizeof hist);
    uint64_t *a = (uint64_t *)(void *)v, *b = tmp;
    for (size_t i = 0; i < n; i++) {
        uint64_t k = double_key(v[i]);
        a[i] = k;
        for (int d = 0; d < 8; d++)
            hist[d][(k >> (8 * d)) & 255]++;
    }
    for (int d = 0; d < 8; d++) {
        size_t *h = hist[d];
        if (h[(a[0] >> (8 * d)) & 255] == n)
            continue; /* every key has this byte */
        size_t sum = 0;
        for (int j = 0; j < 256; j++) {
            size_t c = h[j];
            h[j] = sum;
            sum += c;
        }
        for (size_t i = 0; i < n; i++)
            b[h[(a[i] >> (8 * d)) & 255]++] = a[i];
        uint64_t *x = a;
        a = b;
        b = x;
    }
    if (a != (uint64_t *)(void *)v)
        memcpy(v, a, n * sizeof *a);
    for (size_t i = 0; i < n; i++)
        v[i] = key_double(((uint64_t *)(void *)v)[i]);
}
