/**
 * @file mc_transforms.h
 * @brief Clarke, inverse Clarke, Park and inverse Park transforms, float32
 *        and q31 twins. Stateless, `static inline`, results through pointers.
 *
 * Convention: amplitude invariant, alpha axis on phase a.
 *   Clarke (3 phases):  alpha = (2 a - b - c) / 3,  beta = (b - c) / sqrt(3)
 *   Clarke (2 phases, assumes a + b + c = 0):
 *                       alpha = a,                  beta = (a + 2 b) / sqrt(3)
 *   inverse Clarke:     a = alpha
 *                       b = -alpha / 2 + sqrt(3) / 2 * beta
 *                       c = -alpha / 2 - sqrt(3) / 2 * beta
 *   Park (angle theta of the d axis from the alpha axis):
 *                       d =  alpha cos + beta sin
 *                       q = -alpha sin + beta cos
 *   inverse Park:       alpha = d cos - q sin,  beta = d sin + q cos
 * A balanced set a = I cos(th), b = I cos(th - 2pi/3), c = I cos(th + 2pi/3)
 * gives |alpha + j beta| = I and, with Park at th, d = I, q = 0.
 *
 * The Park pair takes sin and cos of the angle rather than the angle, so one
 * mc_sincos_* call serves Park and inverse Park in the same control period.
 *
 * Float32: every constant is float, nothing promotes to double; builds use
 * -ffp-contract=off, so results are bit-identical on host and Cortex-M4F.
 * No NaN check here (hot path): a NaN in gives NaN out.
 *
 * Scaling and overflow (q31 twins). Inputs are q31 per-unit values (any base,
 * the same for all inputs of one call), sin/cos are q31 in [-1, 1).
 * Accumulation is in int64 so no intermediate can wrap:
 * - Clarke / inverse Clarke: one exact integer sum (Q31 with 3 integer bits)
 *   times one Q31 constant, or a sum of two Q2.62 products; accumulator
 *   64-bit Q2.62 (bounds below 1.8 * 2^62 for every input), then one
 *   rounding to nearest (ties up) to q31.
 * - Park / inverse Park: two Q2.62 products each halved to Q3.61 (their sum
 *   reaches 2 when every operand is -1, which Q2.62 cannot hold); the halving
 *   drops at most 2^-62 per product, far below one q31 LSB (2^-31); then one
 *   rounding to nearest (ties up).
 * - Every result saturates to [MC_Q31_MIN, MC_Q31_MAX]; nothing wraps.
 * Where each result saturates (|x| means the per-unit magnitude):
 *   mc_clarke_q31:     alpha never; beta when |a + 2 b| > sqrt(3) (never for a
 *                      balanced set with amplitude <= 1).
 *   mc_clarke3_q31:    alpha when |2a - b - c| > 3, beta when |b - c| > sqrt(3)
 *                      (neither for a balanced set with amplitude <= 1).
 *   mc_park_q31, mc_inv_park_q31: when the input vector is longer than 1.
 *   mc_inv_clarke_q31: a never; b, c when |alpha + j beta| > 1 (at some angles).
 * Error vs exact arithmetic on the same q31 inputs, for results that do not
 * saturate: one rounding (0.5 LSB) plus the rounding of the Q31 constant
 * times the integer sum: mc_clarke_q31 and mc_inv_clarke_q31 below 1 LSB
 * (0.25 and 0.38 LSB constant error), mc_clarke3_q31 below 1.5 LSB (1/3 is
 * 0.33 LSB off, times a sum of up to 3); Park pair below 1 LSB (the two
 * dropped bits weigh 2^-61 each).
 * Note that sin = 1 is MC_Q31_MAX = 1 - 2^-31, a gain error of 1 LSB.
 */
#ifndef MC_TRANSFORMS_H
#define MC_TRANSFORMS_H

#include <stdint.h>

#include "math/mc_math.h"
#include "math/mc_q31.h"

#ifdef __cplusplus
extern "C" {
#endif

/** 1/sqrt(3) in Q31: round(2^31 / sqrt(3)). */
#define MC_TRANSFORMS_INV_SQRT3_Q31 ((int64_t)1239850262)
/** sqrt(3)/2 in Q31: round(2^31 * sqrt(3) / 2). */
#define MC_TRANSFORMS_SQRT3_2_Q31 ((int64_t)1859775393)
/** 1/3 in Q31: round(2^31 / 3). */
#define MC_TRANSFORMS_ONE_THIRD_Q31 ((int64_t)715827883)

/* ------------------------------------------------------------------ f32 */

/** Two-phase Clarke: alpha, beta from ia, ib, assuming ia + ib + ic = 0. */
static inline void mc_clarke_f32(float ia_a, float ib_a, float *p_alpha, float *p_beta)
{
    *p_alpha = ia_a;
    *p_beta = (ia_a + 2.0f * ib_a) * MC_INV_SQRT3_F32;
}

/** Three-phase Clarke: any common mode in ia+ib+ic is removed. */
static inline void mc_clarke3_f32(float ia_a, float ib_a, float ic_a, float *p_alpha, float *p_beta)
{
    *p_alpha = (2.0f * ia_a - ib_a - ic_a) * (1.0f / 3.0f);
    *p_beta = (ib_a - ic_a) * MC_INV_SQRT3_F32;
}

/** Park: alpha/beta to d/q with the sin and cos of the d-axis angle. */
static inline void mc_park_f32(float alpha, float beta, float sin_th, float cos_th, float *p_d,
                               float *p_q)
{
    *p_d = alpha * cos_th + beta * sin_th;
    *p_q = beta * cos_th - alpha * sin_th;
}

/** Inverse Park: d/q to alpha/beta with the sin and cos of the d-axis angle. */
static inline void mc_inv_park_f32(float d, float q, float sin_th, float cos_th, float *p_alpha,
                                   float *p_beta)
{
    *p_alpha = d * cos_th - q * sin_th;
    *p_beta = d * sin_th + q * cos_th;
}

/** Inverse Clarke: phase values (a + b + c = 0) from alpha/beta. */
static inline void mc_inv_clarke_f32(float alpha, float beta, float *p_a, float *p_b, float *p_c)
{
    float half_alpha = 0.5f * alpha;
    float beta_term = (0.5f * MC_SQRT3_F32) * beta;
    *p_a = alpha;
    *p_b = beta_term - half_alpha;
    *p_c = -half_alpha - beta_term;
}

/* ------------------------------------------------------------------ q31 */

/** Round a Q2.62 accumulator to q31 (to nearest, ties up) and saturate. */
static inline q31_t mc_transforms_q62_to_q31(int64_t acc_q62)
{
    return mc_q31_sat64((acc_q62 + ((int64_t)1 << 30)) >> 31);
}

/** Round a Q3.61 accumulator to q31 (to nearest, ties up) and saturate. */
static inline q31_t mc_transforms_q61_to_q31(int64_t acc_q61)
{
    return mc_q31_sat64((acc_q61 + ((int64_t)1 << 29)) >> 30);
}

/** q31 twin of mc_clarke_f32. |ia + 2 ib| <= 3 so the sum times 1/sqrt(3)
 *  stays below 1.74 * 2^62 in the Q2.62 accumulator. */
static inline void mc_clarke_q31(q31_t ia, q31_t ib, q31_t *p_alpha, q31_t *p_beta)
{
    int64_t sum_q31 = (int64_t)ia + 2 * (int64_t)ib;
    *p_alpha = ia;
    *p_beta = mc_transforms_q62_to_q31(sum_q31 * MC_TRANSFORMS_INV_SQRT3_Q31);
}

/** q31 twin of mc_clarke3_f32. |2a - b - c| <= 4 gives at most 1.34 * 2^62;
 *  |b - c| <= 2 gives at most 1.16 * 2^62. */
static inline void mc_clarke3_q31(q31_t ia, q31_t ib, q31_t ic, q31_t *p_alpha, q31_t *p_beta)
{
    int64_t sum_alpha_q31 = 2 * (int64_t)ia - (int64_t)ib - (int64_t)ic;
    int64_t diff_beta_q31 = (int64_t)ib - (int64_t)ic;
    *p_alpha = mc_transforms_q62_to_q31(sum_alpha_q31 * MC_TRANSFORMS_ONE_THIRD_Q31);
    *p_beta = mc_transforms_q62_to_q31(diff_beta_q31 * MC_TRANSFORMS_INV_SQRT3_Q31);
}

/** q31 twin of mc_park_f32 (Q3.61 accumulator, see the file comment). */
static inline void mc_park_q31(q31_t alpha, q31_t beta, q31_t sin_th, q31_t cos_th, q31_t *p_d,
                               q31_t *p_q)
{
    int64_t a_cos = ((int64_t)alpha * (int64_t)cos_th) >> 1;
    int64_t a_sin = ((int64_t)alpha * (int64_t)sin_th) >> 1;
    int64_t b_cos = ((int64_t)beta * (int64_t)cos_th) >> 1;
    int64_t b_sin = ((int64_t)beta * (int64_t)sin_th) >> 1;
    *p_d = mc_transforms_q61_to_q31(a_cos + b_sin);
    *p_q = mc_transforms_q61_to_q31(b_cos - a_sin);
}

/** q31 twin of mc_inv_park_f32 (Q3.61 accumulator, see the file comment). */
static inline void mc_inv_park_q31(q31_t d, q31_t q, q31_t sin_th, q31_t cos_th, q31_t *p_alpha,
                                   q31_t *p_beta)
{
    int64_t d_cos = ((int64_t)d * (int64_t)cos_th) >> 1;
    int64_t d_sin = ((int64_t)d * (int64_t)sin_th) >> 1;
    int64_t q_cos = ((int64_t)q * (int64_t)cos_th) >> 1;
    int64_t q_sin = ((int64_t)q * (int64_t)sin_th) >> 1;
    *p_alpha = mc_transforms_q61_to_q31(d_cos - q_sin);
    *p_beta = mc_transforms_q61_to_q31(d_sin + q_cos);
}

/** q31 twin of mc_inv_clarke_f32. Q2.62 accumulator: sqrt(3)/2 * beta and
 *  alpha / 2 are each at most 0.87 * 2^62 and 0.5 * 2^62 in magnitude. */
static inline void mc_inv_clarke_q31(q31_t alpha, q31_t beta, q31_t *p_a, q31_t *p_b, q31_t *p_c)
{
    int64_t half_alpha_q62 = (int64_t)alpha * ((int64_t)1 << 30);
    int64_t beta_term_q62 = (int64_t)beta * MC_TRANSFORMS_SQRT3_2_Q31;
    *p_a = alpha;
    *p_b = mc_transforms_q62_to_q31(beta_term_q62 - half_alpha_q62);
    *p_c = mc_transforms_q62_to_q31(-beta_term_q62 - half_alpha_q62);
}

#ifdef __cplusplus
}
#endif

#endif /* MC_TRANSFORMS_H */
