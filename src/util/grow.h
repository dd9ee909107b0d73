/*
 * grow.h — room for more elements in a heap array that doubles as it grows
 * (build scratch, the clip path's vertex stack, leaf lists).
 */
#ifndef BSPRAY_UTIL_GROW_H
#define BSPRAY_UTIL_GROW_H

#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>

/* Makes *P (capacity *CAP elements of ELEM bytes) hold at least NEED
 * elements: the capacity doubles, or jumps to NEED when doubling is not
 * enough. 1 on success; 0 when out of memory or the size overflows, with *P
 * and *CAP unchanged. */
static inline int grow_array(void **p, size_t *cap, size_t need, size_t elem)
{
    if (need <= *cap)
        return 1;
    size_t ncap = *cap * 2 > need ? *cap * 2 : need;
    if (ncap > SIZE_MAX / elem)
        return 0;
    void *np = realloc(*p, ncap * elem);
    if (!np)
        return 0;
    *p = np;
    *cap = ncap;
    return 1;
}

/* grow_array for the array ARR of capacity CAP (lvalues). */
#define GROW_ARRAY(arr, cap, need) grow_array((void **)&(arr), &(cap), (need), sizeof *(arr))

#endif /* BSPRAY_UTIL_GROW_H */
