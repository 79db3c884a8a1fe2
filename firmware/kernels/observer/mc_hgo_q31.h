/**
 * @file mc_hgo_q31.h
 * @brief q31 twin of the high-gain observer (observer/mc_hgo.h, paper 001
 *        eq. (6)), exact discretisation with the same input polynomial.
 *
 * Where q31 cannot hold the dynamic range, and what this kernel does:
 * the observer's outputs are z2 = eta2/eps and z3 = eta3/eps^2; at
 * eps = 1e-4 the last is eta3 amplified 1e8 times. A q31 state (31
 * fractional bits of y_base) would put one LSB of eta3 at
 * y_base 2^-31/eps^2 = 4.7e-3 rad/s^2 for y_base = 0.1 rad, and every
 * product Phi eta rounds by half of that, each period: a rounding walk
 * in z3 that the observer's fast poles do not average out. So the state
 * eta = (z1, eps z2, eps^2 z3) is held in Q46 (mc_q46: 64-bit, 15 guard
 * bits below the q31 LSB of y_base): the per-step rounding of eta3 seen
 * in z3 is 2^-47 y_base/eps^2 = 7e-8 rad/s^2 (y_base 0.1 rad, eps 1e-4).
 * The coefficients Phi, G1, G2 (entries of order one, from the f32
 * kernel's matrix exponential, computed once at init) are mc_q46 gains
 * (each with its own exponent); the outputs are formed by one gain each:
 *     z2 = [y_base/(eps z2_base)] eta2,   z3 = [y_base/(eps^2 z3_base)] eta3
 * and rounded to q31 at the very end. The amplification 1/eps^2 lives
 * in those two constants (block exponent), not in the state.
 *
 * Per unit (config): y and z1 in q31 of y_base, z2 of z2_base (y/s), z3 of
 * z3_base (y/s^2). Overflow: eta saturates at 2^16 y_base (never reached
 * for |y| < y_base); z2, z3 saturate at one base.
 */
#ifndef MC_HGO_Q31_H
#define MC_HGO_Q31_H

#include <stdint.h>

#include "observer/mc_hgo.h"
#include "math/mc_q46.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MC_HGO_ERR_SCALE (1u << 7) /**< a base <= 0 / not finite, or an output gain out of range */

typedef struct {
    mc_hgo_f32_cfg_t f; /**< alpha, eps, dt, input order: as the f32 kernel */
    float y_base;       /**< base of y and z1, > 0 */
    float z2_base;      /**< base of z2 [y/s], > 0 */
    float z3_base;      /**< base of z3 [y/s^2], > 0 */
} mc_hgo_q31_cfg_t;

typedef struct {
    mc_q46_gain_t phi[9];
    mc_q46_gain_t g1[3];
    mc_q46_gain_t g2[3];
    mc_q46_gain_t out2; /**< y_base/(eps z2_base) */
    mc_q46_gain_t out3; /**< y_base/(eps^2 z3_base) */
    mc_q46_gain_t in2;  /**< eps z2_base/y_base (reset: z2 to eta2) */
    mc_q46_gain_t in3;  /**< eps^2 z3_base/y_base (reset: z3 to eta3) */
    uint32_t input_order;
    uint32_t n_hist;
    q31_t y1, y2; /**< y[k-1], y[k-2] */
    int64_t eta_q46[3];
} mc_hgo_q31_t;

typedef struct {
    q31_t z1, z2, z3;
} mc_hgo_q31_est_t;

/** Validate cfg (MC_HGO_ERR_* of the f32 kernel on cfg->f, plus
 *  MC_HGO_ERR_SCALE for a base <= 0 / not finite or an output or reset gain
 *  out of range), form the coefficients, zero the state. On error st is
 *  not written. */
uint32_t mc_hgo_q31_init(mc_hgo_q31_t *st, const mc_hgo_q31_cfg_t *cfg);

/** Set the estimates (z1 in y_base, z2 in z2_base, z3 in z3_base, as
 *  mc_hgo_f32_reset in engineering units) and forget the past samples.
 *  eta = (z1, eps z2, eps^2 z3) is formed in Q46 by one gain each (in2,
 *  in3: one rounding, <= 2^-47 y_base); zeros give the zero state exactly.
 *  Returns MC_HGO_ERR_NONE, or MC_HGO_ERR_NULL for a NULL st (q31 values
 *  are finite: no MC_HGO_ERR_NAN_INPUT). */
uint32_t mc_hgo_q31_reset(mc_hgo_q31_t *st, q31_t z1, q31_t z2, q31_t z3);

/** The estimate at this sample in *p_est, then one period ahead (as
 *  mc_hgo_f32_step). Returns MC_HGO_ERR_NONE, or MC_HGO_ERR_NULL (st or
 *  p_est NULL: nothing written); q31 has no non-finite input. */
uint32_t mc_hgo_q31_step(mc_hgo_q31_t *st, q31_t y, mc_hgo_q31_est_t *p_est);

#ifdef __cplusplus
}
#endif

#endif /* MC_HGO_Q31_H */
