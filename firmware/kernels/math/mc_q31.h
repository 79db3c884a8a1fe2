/**
 * @file mc_q31.h
 * @brief Fixed-point (Q1.31 / Q1.15) helpers: saturating arithmetic,
 *        conversions, and fixed-point sin/cos, atan2, sqrt.
 *
 * Formats
 * - q31_t: value v represents v / 2^31, range [-1, 1 - 2^-31]. Physical
 *   quantities are stored per unit of a base value stated in the owning
 *   kernel's config (base current, base voltage, base speed, ...).
 * - q15_t: value v represents v / 2^15.
 * - Angles in q31: a normalised turn. The full int32 range is one
 *   electrical turn: v represents v * pi / 2^31 rad, i.e. [-pi, pi). Adding
 *   two angles with mc_q31_angle_add wraps exactly, by construction.
 *
 * Every function saturates instead of wrapping (except angle addition, where
 * wrapping is the meaning). Integer arithmetic is bit-identical on every
 * target; tests bound the difference to the f32 twins.
 */
#ifndef MC_Q31_H
#define MC_Q31_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef int32_t q31_t;
typedef int16_t q15_t;

#define MC_Q31_MAX ((q31_t)0x7FFFFFFF)
#define MC_Q31_MIN ((q31_t)(-0x7FFFFFFF - 1))
#define MC_Q15_MAX ((q15_t)0x7FFF)
#define MC_Q15_MIN ((q15_t)(-0x7FFF - 1))

/** Saturate a 64-bit value to the q31 range. */
static inline q31_t mc_q31_sat64(int64_t x)
{
    if (x > (int64_t)MC_Q31_MAX) {
        return MC_Q31_MAX;
    }
    if (x < (int64_t)MC_Q31_MIN) {
        return MC_Q31_MIN;
    }
    return (q31_t)x;
}

/** a + b, saturated. */
static inline q31_t mc_q31_add_sat(q31_t a, q31_t b)
{
    return mc_q31_sat64((int64_t)a + (int64_t)b);
}

/** a - b, saturated. */
static inline q31_t mc_q31_sub_sat(q31_t a, q31_t b)
{
    return mc_q31_sat64((int64_t)a - (int64_t)b);
}

/** -a, saturated (-(-1) = 1 - 2^-31). */
static inline q31_t mc_q31_neg_sat(q31_t a)
{
    return mc_q31_sat64(-(int64_t)a);
}

/** |a|, saturated. */
static inline q31_t mc_q31_abs_sat(q31_t a)
{
    return (a < 0) ? mc_q31_neg_sat(a) : a;
}

/**
 * a * b in q31, rounded to nearest (ties up), saturated: the only overflow
 * is (-1) * (-1), which gives MC_Q31_MAX. Accumulator: 64-bit Q2.62.
 */
static inline q31_t mc_q31_mul(q31_t a, q31_t b)
{
    int64_t p = (int64_t)a * (int64_t)b; /* Q2.62 */
    return mc_q31_sat64((p + ((int64_t)1 << 30)) >> 31);
}

/** Clamp to [lo, hi] (requires lo <= hi). */
static inline q31_t mc_q31_sat(q31_t x, q31_t lo, q31_t hi)
{
    return (x < lo) ? lo : ((x > hi) ? hi : x);
}

/** Add two q31 angles (normalised turn): wraps modulo one turn, exactly. */
static inline q31_t mc_q31_angle_add(q31_t a, q31_t b)
{
    uint32_t s = (uint32_t)a + (uint32_t)b; /* modular, no UB */
    return (q31_t)(int32_t)s;               /* two's complement (C11 impl.-defined, GCC: modular) */
}

/**
 * Float to q31 (x in per unit), rounded to nearest (ties away from zero),
 * saturated to the q31 range: x >= 1 (incl. +inf) gives MC_Q31_MAX,
 * x <= -1 (incl. -inf) gives MC_Q31_MIN (-1 is exact). NaN gives 0
 * (defined; the float is range-checked before any conversion, so the
 * conversion never sees a NaN or an out-of-range float).
 * Accuracy: <= 0.5 LSB (2^-32) from x in range; the largest float below 1,
 * 1 - 2^-24, converts exactly to 2^31 - 128.
 */
q31_t mc_q31_from_f32(float x);

/** q31 to float: x / 2^31 rounded once to float (exact for |x| <= 2^24;
 * MC_Q31_MIN gives -1.0f exactly, MC_Q31_MAX rounds to 1.0f). */
float mc_q31_to_f32(q31_t x);

/** Float to q15 (x * 2^15), rounded to nearest (ties away from zero),
 * saturated to [MC_Q15_MIN, MC_Q15_MAX] (x >= 1 - 2^-16 gives MC_Q15_MAX);
 * NaN gives 0. */
q15_t mc_q15_from_f32(float x);

/**
 * Radians (float) to a q31 angle (normalised turn), wrapped modulo one turn
 * and rounded to nearest: exact to <= 0.5 LSB (pi/2^31 rad = 1.46e-9 rad)
 * from the real x * 2^31 / pi mod 2^32 for every finite float, via the
 * integer reduction mc_turn_from_rad_f32 (no float rounding in between).
 * Note MC_PI_F32 lies 8.7e-8 rad (60 LSB) above pi, so it maps to
 * MC_Q31_MIN + 60. NaN and +-inf give 0.
 */
q31_t mc_q31_angle_from_rad_f32(float x_rad);

/**
 * q31 angle (normalised turn) to radians in [-MC_PI_F32, MC_PI_F32).
 * Error <= 3.2e-7 rad (int32-to-float rounding, 2^-24 relative, and the
 * product's half ulp). Angles within float rounding of +pi (>= 2^31 - 64)
 * come out as -MC_PI_F32: the same angle, kept in the half-open range.
 */
float mc_q31_angle_to_rad_f32(q31_t angle);

/**
 * sin and cos of a q31 angle (normalised turn), results in q31.
 *
 * Method: nearest quarter turn (exact integer split), remainder t in
 * [-1/8, 1/8) turn as Q31 of a quarter turn; own polynomial fits
 * sin(pi/2 t) = t * A(t^2) (degree 11) and cos(pi/2 t) = B(t^2) (degree 12),
 * coefficients Q2.30, Horner in int64 with a rounded shift per step
 * (accumulator Q2.30 in int64, products < 2^62).
 * Accuracy: <= 3 LSB (1.4e-9) from the exact sin/cos of the angle, every
 * angle; measured max 1.8 LSB.
 * Saturation: +1 gives MC_Q31_MAX (e.g. cos(0)); -1 is exact (MC_Q31_MIN,
 * e.g. cos(-pi) and sin(-pi/2)). Bit-identical on every target.
 */
void mc_sincos_q31(q31_t angle, q31_t *p_sin, q31_t *p_cos);

/**
 * atan2(y, x) of two q31 values (any common scale), result a q31 angle
 * (normalised turn) in [-pi, pi): the direction +pi (y = 0, x < 0) is
 * returned as MC_Q31_MIN (-pi, the same angle). atan2(0, 0) = 0.
 *
 * Method: integer CORDIC (vectoring, 34 steps) on the vector normalised to
 * [2^59, 2^60) in int64 (full resolution for small inputs, headroom for the
 * CORDIC gain 1.65 and sqrt(2): no overflow for any input incl. MIN);
 * angle accumulator in int64 units of 2^-40 turn, rounded to 2^-32 turn.
 * Accuracy: <= 1 LSB (1.46e-9 rad) from atan2 of the same integers;
 * measured max 0.6 LSB. Never saturates (the angle wraps by definition).
 */
q31_t mc_atan2_q31(q31_t y, q31_t x);

/**
 * Square root of x in q31 (x <= 0 gives 0), result q31: round(sqrt(x *
 * 2^31)) by a digit-by-digit integer square root of the 62-bit product
 * (uint64 accumulator), rounded to nearest from the exact remainder.
 * Accuracy: <= 0.5 LSB. Saturation: the result never exceeds MC_Q31_MAX
 * (sqrt of MC_Q31_MAX rounds to it exactly).
 */
q31_t mc_sqrt_q31(q31_t x);

/**
 * Integer square root: floor(sqrt(x)) of any 64-bit x, digit by digit (at
 * most 32 iterations of shifts and adds), with the remainder x - root^2
 * through p_rem (may be NULL). The one integer square root of the kernels:
 * mc_sqrt_q31, mc_sqrt_f32_soft and the q31 SVPWM use it.
 */
uint64_t mc_isqrt_u64(uint64_t x, uint64_t *p_rem);

#ifdef __cplusplus
}
#endif

#endif /* MC_Q31_H */
