/*
 * same_util.h — "the same answer" as the tests mean it: the same bits.
 * Issue #3 asks every structure for the naive method's primitive and a
 * bit-identical t, so hits are compared by their bits, not with ==
 * (which takes -0 for +0 and never matches a NaN to itself).
 */
#ifndef BSPRAY_TESTS_SAME_UTIL_H
#define BSPRAY_TESTS_SAME_UTIL_H

#include <string.h>

#include "bspray/bspray.h"

/* A and B are the same bits. */
static inline int same_double(double a, double b)
{
    return memcmp(&a, &b, sizeof a) == 0;
}

/* Every coordinate the same bits. */
static inline int same_vec(bsp_vec3 a, bsp_vec3 b)
{
    return same_double(a.x, b.x) && same_double(a.y, b.y) && same_double(a.z, b.z);
}

/* Two closest-hit answers agree: both missed (F1, F2 the queries' results),
 * or both hit the same primitive at the same t to the bit. */
static inline int same_hit(int f1, const bsp_hit *a, int f2, const bsp_hit *b)
{
    if (f1 != f2)
        return 0;
    return !f1 || (a->prim == b->prim && same_double(a->t, b->t));
}

/* Two materials: every number the same bits, the same flag (not memcmp of
 * the structs, whose padding after the flag holds whatever the copy left). */
static inline int same_material(const bsp_material *a, const bsp_material *b)
{
    for (int k = 0; k < 3; k++)
        if (!same_double(a->color[k], b->color[k]))
            return 0;
    return same_double(a->kd, b->kd) && same_double(a->ks, b->ks) &&
           same_double(a->shine, b->shine) && same_double(a->t, b->t) &&
           same_double(a->ior, b->ior) && a->two_sided == b->two_sided;
}

#endif
