/**
 * @file mc_math.h
 * @brief Float32 fast math for the control kernels: sin/cos, atan2, sqrt,
 *        angle wrapping, saturation, finiteness checks.
 *
 * Own implementations, no libm: the same C source gives bit-identical results
 * on the host (x86-64, SSE) and on the Cortex-M4F (both built with
 * -ffp-contract=off). Error bounds against libm are stated per function and
 * asserted in tests/unit/math.
 *
 * Non-finite inputs: every function documents what a NaN or infinity gives.
 * The rule is that a non-finite input never produces a finite-looking wrong
 * answer silently: it propagates as NaN, so the drive's fault manager, which
 * checks kernel outputs, sees it. No function here converts a NaN or an
 * out-of-range float to an integer (that is undefined in C and differs
 * between x86 and ARM).
 */
#ifndef MC_MATH_H
#define MC_MATH_H

#include <stdbool.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define MC_PI_F32      3.14159265358979323846f
#define MC_TWO_PI_F32  6.28318530717958647692f
#define MC_HALF_PI_F32 1.57079632679489661923f
#define MC_SQRT3_F32   1.73205080756887729353f
#define MC_INV_SQRT3_F32 0.57735026918962576451f

/** true if x is neither NaN nor +-infinity (no libm, no integer conversion). */
static inline bool mc_isfinite_f32(float x)
{
    /* x - x is 0 for finite x, NaN for NaN and +-inf; NaN != NaN. */
    float d = x - x;
    return d == d;
}

/** Clamp x to [lo, hi] (requires lo <= hi). NaN in x gives NaN out. */
static inline float mc_sat_f32(float x, float lo, float hi)
{
    if (x < lo) {
        return lo;
    }
    if (x > hi) {
        return hi;
    }
    return x;
}

/** |x| without libm. */
static inline float mc_abs_f32(float x)
{
    return (x < 0.0f) ? -x : x;
}

/**
 * sin and cos of x (radians) in one call.
 * Error vs libm (double reference rounded): see the implementation header
 * comment and tests/unit/math. NaN or +-inf in: *p_sin = *p_cos = NaN.
 */
void mc_sincos_f32(float x_rad, float *p_sin, float *p_cos);

/**
 * atan2(y, x) in radians, range [-pi, pi]. atan2(0, 0) = 0 (defined, as the
 * kernels need a value when a vector has no direction yet). NaN in: NaN out.
 */
float mc_atan2_f32(float y, float x);

/** Square root. x < 0 or NaN: NaN. +inf: +inf. */
float mc_sqrt_f32(float x);

/** Wrap an angle to [-pi, pi). NaN/inf in: NaN out. */
float mc_wrap_pi_f32(float x_rad);

/** Wrap an angle to [0, 2*pi). NaN/inf in: NaN out. */
float mc_wrap_2pi_f32(float x_rad);

/** |x| up to which sin/cos and wrap use Cody-Waite reduction (rad). */
#define MC_MATH_CW_LIMIT_RAD 8192.0f

/**
 * x_rad / (2*pi) modulo one turn, as an unsigned Q0.64 fraction of a turn.
 * Returns false (and 0) for NaN/inf.
 */
bool mc_turn_from_rad_f32(float x_rad, uint64_t *p_turn_q64);

#ifdef __cplusplus
}
#endif

#endif /* MC_MATH_H */
