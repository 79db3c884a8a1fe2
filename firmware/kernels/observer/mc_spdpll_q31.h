/**
 * @file mc_spdpll_q31.h
 * @brief q31 twin of the type-2 PLL speed estimator (observer/mc_spdpll.h).
 *
 * Same law as the f32 kernel (kp = 2 bw, ki = bw^2):
 *     e    = theta_in - z1                 (wraps: q31 angles are a turn)
 *     w_i += ki dt e                       (clamped to +-omega_max)
 *     w    = kp e + w_i                    (clamped to +-omega_max)
 *     z1  += dt w                          (modulo one turn)
 *
 * Formats: angles are q31 normalised turns (v * pi / 2^31 rad, mc_q31.h),
 * so the angle error wraps exactly by two's-complement subtraction (the
 * f32 kernel's mc_wrap_pi_f32). Speeds are q31 per unit of omega_base_rad_s
 * (config). w_i and w are Q46 accumulators (mc_q46.h); z1 is a 64-bit turn
 * (the q31 angle in the upper 32 bits, 32 bits of sub-LSB fraction below),
 * advanced modulo 2^64 = one turn: slow speeds integrate without loss and
 * the angle never wraps incorrectly. Gains (init, float): kp pi/omega_base,
 * ki dt pi/omega_base (rad per q31 turn to speed pu) and dt omega_base/pi
 * 2^17 (speed Q46 to the 64-bit turn).
 *
 * Saturation: omega_max_rad_s is clamped to the q31 range of omega_base
 * (use omega_base > omega_max); the speed and the integral saturate there
 * and raise the sticky MC_SPDPLL_ERR_SAT, as the f32 kernel does.
 * Error vs the f32 twin on the same inputs: the f32 kernel rounds its angle
 * to float (ulp 2.4e-7 rad near pi) every step; the q31 one is exact to
 * 2^-63 turn. Bounds: tests/unit/q31/test_spdpll_q31.cpp.
 */
#ifndef MC_SPDPLL_Q31_H
#define MC_SPDPLL_Q31_H

#include <stdint.h>

#include "math/mc_q46.h"
#include "observer/mc_spdpll.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MC_SPDPLL_ERR_SCALE (1u << 6) /**< omega_base <= 0 / not finite, or a gain out of range */

typedef struct {
    mc_spdpll_f32_cfg_t f;  /**< bw, dt, omega_max: validated as by the f32 kernel */
    float omega_base_rad_s; /**< speed base [rad/s], > 0 */
} mc_spdpll_q31_cfg_t;

typedef struct {
    mc_q46_gain_t kp;    /**< e (turn) -> speed pu */
    mc_q46_gain_t ki_dt; /**< e (turn) -> speed pu per step */
    mc_q46_gain_t dz;    /**< speed Q46 -> 64-bit turn per step */
    int64_t omega_max_q46;
    uint64_t theta_turn64; /**< z1 as a 64-bit turn */
    int64_t omega_i_q46;   /**< integral part */
    q31_t theta;           /**< z1 rounded to a q31 angle */
    q31_t omega;           /**< last speed estimate (pu) */
    uint32_t flags;        /**< sticky MC_SPDPLL_ERR_SAT */
} mc_spdpll_q31_t;

/** Validate cfg (MC_SPDPLL_ERR_* of the f32 kernel on cfg->f, plus
 *  MC_SPDPLL_ERR_SCALE) and initialise (angle 0, speed 0). On error st is
 *  not written. */
uint32_t mc_spdpll_q31_init(mc_spdpll_q31_t *st, const mc_spdpll_q31_cfg_t *cfg);

/** Restart at (theta, omega) (omega clamped), flags cleared. Returns
 *  MC_SPDPLL_ERR_NONE, or MC_SPDPLL_ERR_NULL for a NULL st. */
uint32_t mc_spdpll_q31_reset(mc_spdpll_q31_t *st, q31_t theta, q31_t omega);

/** One step with the new angle (q31 turn): the speed (q31 pu) in *p_omega.
 *  Returns the bits raised by this step: MC_SPDPLL_ERR_NONE or
 *  MC_SPDPLL_ERR_SAT (clamped at +-omega_max, also sticky), or
 *  MC_SPDPLL_ERR_NULL (st or p_omega NULL: nothing written). */
uint32_t mc_spdpll_q31_step(mc_spdpll_q31_t *st, q31_t theta_in, q31_t *p_omega);

#ifdef __cplusplus
}
#endif

#endif /* MC_SPDPLL_Q31_H */
