/**
 * @file mc_q46.h
 * @brief The 64-bit accumulator and the gain format shared by the q31
 *        control kernels (pi2d, filters, observer, foc, csmc twins).
 *
 * Q46 accumulator (int64_t): a per-unit value v is held as v * 2^46, i.e.
 * a q31 value x is x * 2^15 there (15 guard bits below the q31 LSB, 17
 * integer bits above it). Every helper here saturates to +-MC_Q46_LIM =
 * +-(2^62 - 1) (+-2^16 per unit) and never wraps, so the sum of two
 * saturated values (< 2^63) still fits in int64 before it is saturated.
 *
 * Gain (mc_q46_gain_t): a signed real constant g = mant * 2^(shift - 31),
 * |mant| < 2^31, shift in [MC_Q46_SHIFT_MIN, MC_Q46_SHIFT_MAX]. Formed once
 * at init from a float (mc_q46_gain_from_f32): the mantissa is normalised to
 * |mant| in [2^30, 2^31) and holds the float exactly (its 24 significant
 * bits; relative resolution 2^-31 for gains formed in integers), whatever
 * the gain's size, from 2^-48 to 2^30. This is
 * the "block exponent" of the kernels: one exponent per constant, chosen at
 * init, and a fixed-point state with 15 guard bits.
 *
 * Products:
 * - mc_q46_mul_q31(g, x): g * x for a q31 input, in Q46, rounded to nearest
 *   (one rounding, <= 0.5 Q46 LSB = 2^-47 per unit), saturated.
 * - mc_q46_mul(g, a): g * a for a Q46 value |a| <= 2^62, in Q46: a is split
 *   into 31-bit halves so no partial product exceeds 2^62; at most two
 *   roundings (<= 1 Q46 LSB), saturated.
 * All right shifts of negative values go through floor division written
 * with defined operations; the results are bit-identical on every target.
 */
#ifndef MC_Q46_H
#define MC_Q46_H

#include <stdbool.h>
#include <stdint.h>

#include "math/mc_q31.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MC_Q46_ONE       ((int64_t)1 << 46)       /**< 1.0 per unit */
#define MC_Q46_LIM       (((int64_t)1 << 62) - 1) /**< saturation bound (2^16 per unit, less 1 LSB) */
#define MC_Q46_SHIFT_MIN (-48)
#define MC_Q46_SHIFT_MAX 30

/** g = mant * 2^(shift - 31). */
typedef struct {
    int32_t mant;  /**< |mant| < 2^31; normalised to [2^30, 2^31) unless 0 */
    int32_t shift; /**< MC_Q46_SHIFT_MIN .. MC_Q46_SHIFT_MAX */
} mc_q46_gain_t;

/**
 * Gain from a float: returns false (and writes a zero gain) for a
 * non-finite g or |g| >= 2^30; |g| < 2^-48 becomes 0 (returns true).
 * Float arithmetic: meant for init, not for the fast loop.
 */
bool mc_q46_gain_from_f32(float g, mc_q46_gain_t *p_g);

/** The gain's value as a float (tests, telemetry). */
float mc_q46_gain_to_f32(mc_q46_gain_t g);

/** Saturate to [-MC_Q46_LIM, MC_Q46_LIM]. */
static inline int64_t mc_q46_sat(int64_t x)
{
    if (x > MC_Q46_LIM) {
        return MC_Q46_LIM;
    }
    if (x < -MC_Q46_LIM) {
        return -MC_Q46_LIM;
    }
    return x;
}

/** a + b of two values within +-MC_Q46_LIM (no overflow), saturated. */
static inline int64_t mc_q46_add(int64_t a, int64_t b)
{
    return mc_q46_sat(a + b);
}

/** Clamp to [lo, hi] (lo <= hi). */
static inline int64_t mc_q46_clamp(int64_t x, int64_t lo, int64_t hi)
{
    return (x < lo) ? lo : ((x > hi) ? hi : x);
}

/** q31 to Q46 (exact). */
static inline int64_t mc_q46_from_q31(q31_t x)
{
    return (int64_t)x * ((int64_t)1 << 15);
}

/** Q46 to q31, rounded to nearest (ties up), saturated to the q31 range. */
q31_t mc_q46_to_q31(int64_t a);

/** floor(v / 2^n), n in [0, 63], without shifting a negative value. */
int64_t mc_q46_asr(int64_t v, uint32_t n);

/** g * x (x q31) in Q46, rounded, saturated to +-MC_Q46_LIM. */
int64_t mc_q46_mul_q31(mc_q46_gain_t g, q31_t x);

/** g * a (a Q46, saturated first to +-MC_Q46_LIM) in Q46, saturated. */
int64_t mc_q46_mul(mc_q46_gain_t g, int64_t a);

/**
 * Product of two Q46 values a * b / 2^46 for |a|, |b| <= MC_Q46_LIM,
 * rounded, saturated: b is rounded to a q31-mantissa gain first (relative
 * error <= 2^-31 of b), then mc_q46_mul.
 */
int64_t mc_q46_mul_q46(int64_t a, int64_t b);

/** |a| for |a| <= MC_Q46_LIM. */
static inline int64_t mc_q46_abs(int64_t a)
{
    return (a < 0) ? -a : a;
}

/**
 * The vector (a, b) (Q46, |a|, |b| <= MC_Q46_LIM) scaled down to length
 * lim (Q46, > 0) if it is longer, in place. |v| by the exact integer square
 * root of the sum of squares after a common shift that brings the larger
 * component into [2^30, 2^31) (relative error < 2^-29); the factor lim/|v|
 * as a gain with a 31-bit mantissa (lim normalised the same way, one
 * int64 division), applied to both components: direction kept to 2^-31,
 * length lim to < 2^-28 relative. Returns true when it scaled.
 */
bool mc_q46_limit_vec(int64_t *p_a, int64_t *p_b, int64_t lim);

#ifdef __cplusplus
}
#endif

#endif /* MC_Q46_H */
