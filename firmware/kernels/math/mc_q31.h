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
    int64_t p = (int64_t)a * (int64_t)b;          /* Q2.62 */
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
    uint32_t s = (uint32_t)a + (uint32_t)b;   /* modular, no UB */
    return (q31_t)(int32_t)s;                  /* two's complement (C11 impl.-defined, GCC: modular) */
}

/**
 * Float to q31 (x in per unit), rounded to nearest, saturated to the q31
 * range. NaN gives 0 (defined; conversion never sees a NaN or an
 * out-of-range float).
 */
q31_t mc_q31_from_f32(float x);

/** q31 to float (exact to float rounding). */
float mc_q31_to_f32(q31_t x);

/** Float to q15, rounded, saturated; NaN gives 0. */
q15_t mc_q15_from_f32(float x);

/** Radians (float) to a q31 angle (normalised turn), wrapped. NaN gives 0. */
q31_t mc_q31_angle_from_rad_f32(float x_rad);

/** q31 angle (normalised turn) to radians in [-pi, pi). */
float mc_q31_angle_to_rad_f32(q31_t angle);

/**
 * sin and cos of a q31 angle (normalised turn), results in q31.
 * Error bound vs the exact value: stated in the implementation and tests.
 */
void mc_sincos_q31(q31_t angle, q31_t *p_sin, q31_t *p_cos);

/**
 * atan2(y, x) of two q31 values (any common scale), result a q31 angle
 * (normalised turn). atan2(0, 0) = 0.
 */
q31_t mc_atan2_q31(q31_t y, q31_t x);

/** Square root of x in q31 (x <= 0 gives 0), result q31. */
q31_t mc_sqrt_q31(q31_t x);

#ifdef __cplusplus
}
#endif

#endif /* MC_Q31_H */
