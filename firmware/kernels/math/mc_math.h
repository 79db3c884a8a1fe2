/**
 * @file mc_math.h
 * @brief Float32 fast math for the control kernels: sin/cos, atan2, sqrt,
 *        angle wrapping, saturation, finiteness checks.
 *
 * Own implementations, no libm: the same C source gives bit-identical results
 * on the host (x86-64, SSE) and on the Cortex-M4F (both built with
 * -ffp-contract=off): only IEEE single-precision +, -, *, / and integer
 * operations, no double, no fused multiply-add. Error bounds against libm
 * are stated per function and asserted in tests/unit/math (dense sweeps
 * over the stated ranges, plus 0, -0, +-pi, multiples of pi/2, huge
 * arguments, NaN, inf, denormals).
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

/** |x| up to which sin/cos and wrap use Cody-Waite reduction (rad); beyond
 * it an integer Payne-Hanek reduction keeps the same accuracy. */
#define MC_MATH_CW_LIMIT_RAD 8192.0f

/**
 * sin and cos of x (radians) in one call.
 *
 * Range: every finite float (Cody-Waite reduction for |x| <= 8192 rad,
 * integer Payne-Hanek reduction with a table of the bits of 2/pi beyond).
 * Accuracy: |error| <= 2e-7 absolute against libm (double sin/cos rounded
 * to float), over the whole range; measured max 1.2e-7 (2 ulp of a result
 * in [0.5, 1)). Polynomials: own fits of degree 9 (sin) and 10 (cos) on
 * |r| <= pi/4, fit error < 2.4e-9 with the float coefficients.
 * Exact values: sin(+-0) = +-0, cos(0) = 1; for |x| < 2^-12,
 * sin x = x and cos x = 1 exactly (denormals included).
 * NaN or +-inf in: *p_sin = *p_cos = NaN.
 * Cost: about 20 float operations (+ ~10 integer multiplies beyond 8192).
 */
void mc_sincos_f32(float x_rad, float *p_sin, float *p_cos);

/**
 * atan2(y, x) in radians, range [-MC_PI_F32, MC_PI_F32].
 *
 * Accuracy: |error| <= 5e-7 rad against libm atan2 (double) for every
 * finite or infinite input pair, all quadrants, denormals; measured max
 * 2.7e-7. Method: octant reduction, one division, pi/8 argument reduction,
 * own odd polynomial of degree 13 (fit error < 7e-10).
 * Signed zeros and infinities follow C99 Annex F (atan2(-0, -1) = -pi,
 * atan2(+inf, -inf) = 3pi/4, ...), except atan2(+-0, +-0) = 0 for every
 * sign combination (defined, as the kernels need a value when a vector has
 * no direction yet). NaN in either argument: NaN out.
 */
float mc_atan2_f32(float y, float x);

/**
 * Square root, correctly rounded (0 ulp: bit-identical to an IEEE sqrtf)
 * for every non-negative float, denormals included. Method: the FPU's
 * square-root instruction where the core has one (Cortex-M4F VSQRT.F32,
 * x86-64 SQRTSS), else mc_sqrt_f32_soft (below). No libm.
 * x = +-0: x (sign kept, as IEEE). x < 0 (incl. -inf, -denormal) or NaN:
 * NaN. +inf: +inf.
 */
float mc_sqrt_f32(float x);

/**
 * The same square root by integer arithmetic only (digit-by-digit root of the
 * significand, round to nearest even), for cores without an FPU square root.
 * mc_sqrt_f32 uses the FPU instruction where there is one (ARM VFP, x86 SSE);
 * IEEE 754 makes both correctly rounded, so the results are bit-identical,
 * and tests/unit/math checks that they are.
 */
float mc_sqrt_f32_soft(float x);

/**
 * Wrap an angle to [-MC_PI_F32, MC_PI_F32) ("[-pi, pi)" with the float pi,
 * which is 8.7e-8 above the real one).
 *
 * Exact for inputs already in range (returned bit for bit). Otherwise the
 * result is x - 2*pi*k with the real 2*pi (not the float constant): error
 * <= 1.25e-7 rad (half an ulp of the result, + < 3e-11) for every finite x:
 * Cody-Waite with exact leading steps for |x| <= 8192 rad, integer
 * reduction (exact to 2^-64 turn) beyond. A result within rounding of the
 * upper bound is returned as the lower bound (same angle).
 * NaN/inf in: NaN out.
 */
float mc_wrap_pi_f32(float x_rad);

/**
 * Wrap an angle to [0, MC_TWO_PI_F32). As mc_wrap_pi_f32; error
 * <= 2.5e-7 rad (half an ulp of a result up to 2*pi). -0 in range: -0 out.
 * NaN/inf in: NaN out.
 */
float mc_wrap_2pi_f32(float x_rad);

/**
 * x_rad / (2*pi) modulo one turn, as an unsigned Q0.64 fraction of a turn
 * (2^64 = one turn), for every finite float. Integer Payne-Hanek: the 24-bit
 * significand times a 96-bit window of the bits of 2/pi (128-bit product
 * in 32-bit limbs); error < 2^-62 turn. Used for huge arguments of sin/cos
 * and wrap and for the exact float-to-q31 angle conversion.
 * Returns false and sets *p_turn_q64 = 0 for NaN/inf; true otherwise.
 */
bool mc_turn_from_rad_f32(float x_rad, uint64_t *p_turn_q64);

#ifdef __cplusplus
}
#endif

#endif /* MC_MATH_H */
