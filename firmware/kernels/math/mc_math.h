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

#define MC_PI_F32        3.14159265358979323846f
#define MC_TWO_PI_F32    6.28318530717958647692f
#define MC_HALF_PI_F32   1.57079632679489661923f
#define MC_SQRT3_F32     1.73205080756887729353f
#define MC_INV_SQRT3_F32 0.57735026918962576451f

/** true if x is neither NaN nor +-infinity (no libm, no integer conversion). */
static inline bool mc_isfinite_f32(float x)
{
    /* x - x is 0 for finite x, NaN for NaN and +-inf; NaN != NaN. */
    float d = x - x;
    return d == d;
}

/** Scales of a phase resistance a kernel accepts at run time (a warm or
 *  cold winding: mc_fluxobs_*_set_r_scale, mc_foc_f32_set_r_scale): copper
 *  from -200 C to 570 C referred to 20 C ((1 + a (T - 20)), a = 0.00393 / K)
 *  lies inside. */
#define MC_R_SCALE_MIN 0.25f
#define MC_R_SCALE_MAX 3.0f

/** true for a scale of R in [MC_R_SCALE_MIN, MC_R_SCALE_MAX] (false for NaN). */
static inline bool mc_r_scale_f32_ok(float scale)
{
    return (scale >= MC_R_SCALE_MIN) && (scale <= MC_R_SCALE_MAX);
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

/** The sign of x softened over a band: x / band clamped to [-1, 1] for
 * band > 0, else -1, 0 or +1 (the dead-time compensation's current sign,
 * shared by the drive and the sensorless observer's voltage error). */
static inline float mc_sign_band_f32(float x, float band)
{
    if (band > 0.0f) {
        return mc_sat_f32(x / band, -1.0f, 1.0f);
    }
    if (x > 0.0f) {
        return 1.0f;
    }
    return (x < 0.0f) ? -1.0f : 0.0f;
}

/** |x| without libm. */
static inline float mc_abs_f32(float x)
{
    return (x < 0.0f) ? -x : x;
}

/** |x| without libm, for comparisons and magnitudes: -0 gives +0 (unlike
 * mc_abs_f32, which keeps it), NaN stays NaN. One instruction where the
 * compiler has the builtin (VABS.F32 on the M4F, ANDPS on x86-64): the
 * sign bit is cleared, nothing else, so the result is the same everywhere. */
static inline float mc_fabs_f32(float x)
{
#if defined(__GNUC__)
    return __builtin_fabsf(x);
#else
    return (x < 0.0f) ? -x : (x + 0.0f);
#endif
}

/** |x| up to which sin/cos and wrap use Cody-Waite reduction (rad); beyond
 * it an integer Payne-Hanek reduction keeps the same accuracy. */
#define MC_MATH_CW_LIMIT_RAD 8192.0f

/** |x| up to which mc_sincos_near_f32 applies (rad): 5215 table steps at
 * most. */
#define MC_MATH_NEAR_LIMIT_RAD 256.0f

/* Constants of the inline sin/cos (internal, named for the header only). */
/** 1.5 * 2^23: (v + M) - M rounds v to an integer (ties to even), |v| < 2^22. */
#define MC_MATH_ROUND_MAGIC_F32 12582912.0f
#define MC_MATH_TWO_OVER_PI_F32 0.636619772367581343f
/** Entries of the sin/cos table: one turn in steps of 2 pi / 128. */
#define MC_MATH_SINCOS_STEPS 128u
/** 128 / (2 pi), rounded to float. */
#define MC_MATH_STEPS_PER_RAD_F32 20.3718327157626f
/** 2 pi / 128 = MC_MATH_STEP_C1 + MC_MATH_STEP_C2 + 8e-14: C1 has 11
 * significant bits, so k*C1 is exact for |k| < 2^13 and x - k*C1 is exact
 * (a multiple of ulp(x) that fits 24 bits); k*C2 and the last subtraction
 * round. C2 > 0, so that x = -0 (k = +0) keeps its sign through
 * x - (+0) - (+0). */
#define MC_MATH_STEP_C1 0x1.92p-5f
#define MC_MATH_STEP_C2 0x1.fb5444p-17f
/** -1/6 (float), the cubic term of sin r on |r| <= pi/128. */
#define MC_MATH_SIN_R3 (-0x1.555556p-3f)

/**
 * {sin, cos} of k 2 pi / 128 for k = 0..127, each rounded to float (exact
 * for the multiples of pi/2; entry 0 holds sin = -0, so that sin(-0) = -0
 * comes out of the same sum). mc_math.c.
 */
extern const float mc_math_sincos_table[MC_MATH_SINCOS_STEPS][2];

/**
 * mc_sincos_f32 for |x_rad| <= MC_MATH_NEAR_LIMIT_RAD, inline, bit for bit
 * the same results (mc_sincos_f32 runs this very code in that range).
 * The caller guarantees the range (|x| <= 256 rad, so not NaN or inf);
 * outside it the results are wrong or NaN (no undefined behaviour: no
 * float-to-int conversion, the table index is 7 bits). Cost: about 32
 * instructions on the Cortex-M4F, no branch.
 * Method: k = round(x 128 / (2 pi)), r = x - k 2 pi / 128 (two-constant
 * Cody-Waite, error < 5e-10 before the final rounding), |r| <= pi/128;
 * sin r = r (1 - r^2/6) (error < 8e-11), cos r = 1 - r^2/2 (< 1.6e-8);
 * then the angle sum with the table entry (S, C) of k mod 128:
 * sin x = C sin r + S cos r, cos x = C cos r - S sin r.
 */
static inline void mc_sincos_near_f32(float x_rad, float *p_sin, float *p_cos)
{
    union {
        float f;
        uint32_t u;
    } t;
    /* t = 1.5 2^23 + k with k = round(x 128 / 2pi), |k| <= 5215: k is in
     * the low significand bits of t (offset by 2^22, a multiple of 128), so
     * they give k mod 128 directly, negative k included; no float-to-int
     * conversion */
    t.f = (x_rad * MC_MATH_STEPS_PER_RAD_F32) + MC_MATH_ROUND_MAGIC_F32;
    const float kf = t.f - MC_MATH_ROUND_MAGIC_F32;
    const uint32_t idx = t.u & (MC_MATH_SINCOS_STEPS - 1u);
    const float r = (x_rad - (kf * MC_MATH_STEP_C1)) - (kf * MC_MATH_STEP_C2);
    const float z = r * r;
    const float sr = r * (1.0f + (z * MC_MATH_SIN_R3));
    const float cr = 1.0f - (0.5f * z);
    const float ts = mc_math_sincos_table[idx][0];
    const float tc = mc_math_sincos_table[idx][1];
    *p_sin = (tc * sr) + (ts * cr);
    *p_cos = (tc * cr) - (ts * sr);
}

/* Quadrant polynomials of mc_sincos_f32 beyond 256 rad (internal):
 * sin r = r (1 + z (S1 + z (S2 + z S3))), cos r = 1 + z (-1/2 + z (C1 + z (C2
 * + z C3))), z = r^2, |r| <= pi/4: own minimax fits (Lawson iteration on
 * 20000 Chebyshev nodes, weighted to the absolute error), fit error 1.8e-9
 * (sin) and 1e-10 (cos) with the float coefficients. */
#define MC_MATH_SIN_S1 (-1.666665077e-01f)
#define MC_MATH_SIN_S2 8.331978694e-03f
#define MC_MATH_SIN_S3 (-1.949563593e-04f)
#define MC_MATH_COS_C1 4.166664556e-02f
#define MC_MATH_COS_C2 (-1.388736768e-03f)
#define MC_MATH_COS_C3 2.443845187e-05f

/**
 * sin and cos of x (radians) in one call.
 *
 * Range: every finite float. |x| <= 256 rad (the control loops' range):
 * mc_sincos_near_f32 (table of 128 steps, short polynomials, angle sum).
 * Beyond: quadrant reduction, three-constant Cody-Waite up to 8192 rad,
 * integer Payne-Hanek with a table of the bits of 2/pi further out, and
 * own polynomial fits of degree 7 (sin) and 8 (cos) on |r| <= pi/4 (fit
 * error < 1.8e-9 with the float coefficients).
 * Accuracy: |error| <= 2e-7 absolute against libm (double sin/cos rounded
 * to float), over the whole range (tests/unit/math: dense sweeps, huge
 * arguments).
 * Exact values: sin(+-0) = +-0, cos(0) = 1; for |x| < 2^-12,
 * sin x = x and cos x = 1 exactly (denormals included).
 * NaN or +-inf in: *p_sin = *p_cos = NaN.
 * Cost: about 40 instructions on the Cortex-M4F for |x| <= 256 rad (a
 * call, one compare, then mc_sincos_near_f32).
 */
void mc_sincos_f32(float x_rad, float *p_sin, float *p_cos);

/**
 * atan2(y, x) in radians, range [-MC_PI_F32, MC_PI_F32].
 *
 * Accuracy: |error| <= 5e-7 rad against libm atan2 (double) for every
 * finite or infinite input pair, all quadrants, denormals (tests/unit/math).
 * Method: octant reduction and pi/8 argument reduction sharing one
 * division (atan z = pi/4 + atan((n - d) / (n + d)) for z = n/d above
 * tan(pi/8)), own odd polynomial of degree 9 (fit error < 5e-9).
 * Cost: about 40 instructions on the Cortex-M4F for finite arguments.
 * Signed zeros and infinities follow C99 Annex F (atan2(-0, -1) = -pi,
 * atan2(+inf, -inf) = 3pi/4, ...), except atan2(+-0, +-0) = 0 for every
 * sign combination (defined, as the kernels need a value when a vector has
 * no direction yet). NaN in either argument: NaN out.
 */
float mc_atan2_f32(float y, float x);

/* atan2's common case, inline (internal, named for the header only): own
 * minimax fit of atan t = t + t^3 (A1 + A2 t^2 + A3 t^4 + A4 t^6) on
 * |t| <= tan(pi/8) (Lawson iteration, weighted to the absolute error),
 * error < 5e-9 rad with the float coefficients. */
#define MC_MATH_ATAN_A1        (-3.333275616e-01f)
#define MC_MATH_ATAN_A2        1.997187883e-01f
#define MC_MATH_ATAN_A3        (-1.382445395e-01f)
#define MC_MATH_ATAN_A4        7.902597636e-02f
#define MC_MATH_TAN_PI_8_F32   0.414213562373095049f
#define MC_MATH_QUARTER_PI_F32 0.785398163397448310f

/**
 * atan(num / den) for 0 <= num <= den, den > 0, num + den finite
 * (internal to mc_atan2_f32): with z = num / den, z > tan(pi/8) is reduced
 * by atan z = pi/4 + atan((z - 1) / (z + 1)) = pi/4 + atan((num - den) /
 * (num + den)), so one division serves both cases and |t| <= tan(pi/8)
 * (to rounding).
 */
static inline float mc_atan_ratio_f32(float num, float den)
{
    float base = 0.0f;
    float n = num;
    float d = den;
    if (num > (MC_MATH_TAN_PI_8_F32 * den)) {
        base = MC_MATH_QUARTER_PI_F32;
        n = num - den;
        d = num + den;
    }
    const float t = n / d;
    const float t2 = t * t;
    const float p = MC_MATH_ATAN_A1 +
                    (t2 * (MC_MATH_ATAN_A2 + (t2 * (MC_MATH_ATAN_A3 + (t2 * MC_MATH_ATAN_A4)))));
    return base + (t + ((t * t2) * p));
}

/** The octant-to-circle mapping of mc_atan2_f32 for finite |y| = ay,
 * |x| = ax (not both 0, ax + ay finite) and the signs (internal). */
static inline float mc_atan2_octant_f32(float ay, float ax, bool x_neg, bool y_neg)
{
    float a;
    if (ay <= ax) {
        a = mc_atan_ratio_f32(ay, ax);
    } else {
        a = MC_HALF_PI_F32 - mc_atan_ratio_f32(ax, ay);
    }
    if (x_neg) {
        a = MC_PI_F32 - a;
    }
    return y_neg ? -a : a;
}

/** true if the sign bit of x is set (-0 included). */
static inline bool mc_signbit_f32(float x)
{
    union {
        float f;
        uint32_t u;
    } b;
    b.f = x;
    return (b.u & 0x80000000u) != 0u;
}

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
 * mc_sqrt_f32 for x >= 0 (+0, denormals and +inf included), inline: the
 * FPU's square-root instruction where the core has one (the instruction
 * mc_sqrt_f32 runs after its checks), so the results are the same. NaN in:
 * NaN out. Not for negative x (the caller knows x >= 0, e.g. a sum of
 * squares).
 */
static inline float mc_sqrt_nonneg_f32(float x)
{
#if defined(__ARM_FP) || defined(__SSE_MATH__)
    return __builtin_sqrtf(x);
#else
    return mc_sqrt_f32(x);
#endif
}

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
 * Cost: about 30 instructions on the Cortex-M4F for |x| <= 8192 rad.
 */
float mc_wrap_pi_f32(float x_rad);

/**
 * mc_wrap_pi_f32 with the in-range test inline: an input with |x| < pi
 * (the common case of a wrapped sum or difference of two wrapped angles)
 * is returned as is, which is what mc_wrap_pi_f32 returns for it; any
 * other input goes to mc_wrap_pi_f32. Same results, about 5 instructions
 * when in range.
 */
static inline float mc_wrap_pi_fast_f32(float x_rad)
{
    return (mc_fabs_f32(x_rad) < MC_PI_F32) ? x_rad : mc_wrap_pi_f32(x_rad);
}

/**
 * Wrap an angle to [0, MC_TWO_PI_F32). As mc_wrap_pi_f32; error
 * <= 2.5e-7 rad (half an ulp of a result up to 2*pi). -0 in range: -0 out.
 * NaN/inf in: NaN out.
 */
float mc_wrap_2pi_f32(float x_rad);

/**
 * mc_wrap_2pi_f32 with the in-range test inline: an input in [0, 2*pi)
 * (-0 included) is returned as is, which is what mc_wrap_2pi_f32 returns
 * for it; any other input (NaN too: both comparisons are false) goes to
 * mc_wrap_2pi_f32. Same results, about 5 instructions when in range
 * instead of a call and the reduction's set-up.
 */
static inline float mc_wrap_2pi_fast_f32(float x_rad)
{
    return ((x_rad >= 0.0f) && (x_rad < MC_TWO_PI_F32)) ? x_rad : mc_wrap_2pi_f32(x_rad);
}

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
