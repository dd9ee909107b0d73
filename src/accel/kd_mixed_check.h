/*
 * kd_mixed_check.h — sah-mixed's check against plain sah (kd_mixed_check.c).
 */
#ifndef BSPRAY_ACCEL_KD_MIXED_CHECK_H
#define BSPRAY_ACCEL_KD_MIXED_CHECK_H

#include "accel/accel_internal.h"

/* A, a built sah-mixed accelerator with A->opts resolved: builds the plain
 * sah tree of the same options, measures both on the rays of a small render
 * of the view and keeps in A whichever costs less (the sah tree on a tie
 * goes to sah-mixed's; see kd_mixed_check.c). Fills A->check. */
HIDDEN bsp_status kd_mixed_check(bsp_accel *a, bsp_error *err);

#endif /* BSPRAY_ACCEL_KD_MIXED_CHECK_H */
