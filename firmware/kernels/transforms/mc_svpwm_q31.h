/**
 * @file mc_svpwm_q31.h
 * @brief Fixed-point (q31) twin of the space-vector modulator in
 *        mc_svpwm.h: the same limits and flags, in per-unit q31.
 */
#ifndef MC_SVPWM_Q31_H
#define MC_SVPWM_Q31_H

#include <stdint.h>

#include "math/mc_q31.h"
#include "transforms/mc_svpwm.h"

#ifdef __cplusplus
extern "C" {
#endif

/**
 * q31 twin of mc_svpwm_f32. v_alpha_pu, v_beta_pu and vbus_pu are per unit
 * of one base voltage (the caller's config states it), q31 in [-1, 1); vbus
 * must be > 0. Duties are q31 in [0, 1): a duty of exactly 1 (hexagon
 * boundary) saturates to MC_Q31_MAX = 1 - 2^-31.
 *
 * Scaling and overflow: phase voltages in a 64-bit Q2.62 accumulator
 * (|v_x| <= 1.37 for any q31 inputs), mid and v_x - mid in Q2.62
 * (|v_x - mid| <= 1.23), the limit measure L and D in Q31 held in int64
 * (L <= 2.45); |v| by an exact integer square root of the Q2.62 sum of
 * squares (rounded to nearest). Each duty offset is one rounded int64
 * division (v_x - mid)_Q62 / D_Q31; nothing wraps, duties saturate to
 * [0, MC_Q31_MAX]. Error of each duty vs exact arithmetic on the same
 * inputs, with D in per unit: at most 0.77 + c / D LSB, where 0.5 is the
 * rounded division, 0.26 the Q31 constant sqrt(3)/2 (0.38 LSB times
 * |beta| / D <= 2/3), and c / D the rounding of D to Q31 seen through an
 * offset of at most 1/2 (only when limited; unlimited, D = vbus is exact):
 * c = 0.69 for the circle (|v| and sqrt(3) |v| each rounded), 0.25 for the
 * hexagon. Choose the base voltage so that vbus_pu is not tiny: at
 * vbus_pu >= 0.25 every duty is within 3.6 LSB (2^-29).
 * Cost: three 64-bit divisions (software on the Cortex-M4) plus, for the
 * circle limit, a 32-step integer square root.
 * BAD_VBUS for vbus_pu <= 0, BAD_INPUT for an unknown limit or a NULL
 * pointer (q31 has no NaN); then duties are 2^30 (0.5).
 */
uint32_t mc_svpwm_q31(q31_t v_alpha_pu, q31_t v_beta_pu, q31_t vbus_pu, mc_svpwm_limit_t limit,
                      q31_t *p_duty_a, q31_t *p_duty_b, q31_t *p_duty_c);

#ifdef __cplusplus
}
#endif

#endif /* MC_SVPWM_Q31_H */
