/**
 * @file mc_pu.h
 * @brief Per-unit conversion at a q31 plug-in's boundary (mc_ctrl_*_q31):
 *        a value in engineering units to q31 of its base, in double, round
 *        to nearest with ties to even, saturated; no libm.
 *
 * Double because the conversion is exact to the q31 LSB for any float or
 * double input and any base (float would round v / base to 24 bits before
 * the 31-bit result). On the M4F this is software double: a few dozen
 * instructions per converted signal, at the boundary only.
 */
#ifndef MC_PU_H
#define MC_PU_H

#include "math/mc_q31.h"

#define MC_PU_Q31_ONE  2147483648.0       /* 2^31 */
#define MC_PU_F64_2P52 4503599627370496.0 /* 2^52: every double at or above is an integer */

/** Round to nearest, ties to even (nearbyint in the default rounding mode):
 *  for 0 <= x < 2^52 the sum x + 2^52 keeps no fraction bit, so the
 *  addition rounds x and the subtraction is exact. */
static inline double mc_pu_round_f64(double x)
{
    if (x >= 0.0) {
        return (x < MC_PU_F64_2P52) ? ((x + MC_PU_F64_2P52) - MC_PU_F64_2P52) : x;
    }
    return (x > -MC_PU_F64_2P52) ? -((-x + MC_PU_F64_2P52) - MC_PU_F64_2P52) : x;
}

/** v [unit] as q31 of base [unit]: round(v / base 2^31), saturated to
 *  [MC_Q31_MIN, MC_Q31_MAX]; NaN gives 0. */
static inline q31_t mc_pu_to_q31(double v, double base)
{
    const double x = mc_pu_round_f64((v / base) * MC_PU_Q31_ONE);
    if (x >= (MC_PU_Q31_ONE - 1.0)) {
        return MC_Q31_MAX;
    }
    if (x <= -MC_PU_Q31_ONE) {
        return MC_Q31_MIN;
    }
    if (x > -MC_PU_Q31_ONE) {
        return (q31_t)x;
    }
    return 0; /* NaN: no ordering holds */
}

/** q31 of base back to engineering units: q / 2^31 base, in double. */
static inline double mc_pu_from_q31(q31_t q, double base)
{
    return ((double)q / MC_PU_Q31_ONE) * base;
}

#endif /* MC_PU_H */
