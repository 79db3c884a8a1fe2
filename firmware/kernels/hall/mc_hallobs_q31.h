/**
 * @file mc_hallobs_q31.h
 * @brief q31 twin of the Hall-to-observer hand-over (hall/mc_hallobs.h).
 *
 * The same rule. Angles are q31 turns (the difference wraps by two's
 * complement), the speed q31 per unit of omega_base_rad_s (as the
 * observer's q31 PLL gives it), the weight a q31 fraction in [0, 1]
 * (MC_Q31_MAX stands for 1): w = (|omega| - start) / (end - start) with
 * the reciprocal formed once by init (a Q46 gain), theta = theta_hall +
 * w d rounded (mc_q31_mul). The thresholds are validated by the f32
 * kernel (cfg.f) and converted to q31 pu by init (saturating at 1 pu:
 * choose omega_base above omega_end).
 * Error vs the f32 twin: the q31 weight and product round to 2^-31; the
 * f32 kernel to float (2.4e-7 rad near 2 pi). Bounds:
 * tests/unit/q31/test_hall_q31.cpp.
 */
#ifndef MC_HALLOBS_Q31_H
#define MC_HALLOBS_Q31_H

#include <stdint.h>

#include "hall/mc_hallobs.h"
#include "math/mc_q31.h"
#include "math/mc_q46.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MC_HALLOBS_ERR_SCALE (1u << 4) /**< omega_base not > 0 / finite, or not above omega_end */

typedef struct {
    mc_hallobs_f32_cfg_t f; /**< as the f32 kernel's */
    float omega_base_rad_s; /**< speed base [rad/s el.], > omega_end */
} mc_hallobs_q31_cfg_t;

typedef struct {
    mc_hallobs_q31_cfg_t cfg;
    q31_t start;            /**< omega_start, pu */
    mc_q46_gain_t inv_span; /**< 1 / (end - start) in pu^-1 */
    q31_t disagree_max;     /**< q31 turn */
    q31_t w_obs;            /**< last weight, [0, MC_Q31_MAX] */
    uint32_t flags;
} mc_hallobs_q31_t;

uint32_t mc_hallobs_q31_init(mc_hallobs_q31_t *st, const mc_hallobs_q31_cfg_t *cfg);
uint32_t mc_hallobs_q31_reset(mc_hallobs_q31_t *st);
/** As mc_hallobs_f32_step, q31 angles (turn) and speed (pu); *p_theta a q31 angle. */
uint32_t mc_hallobs_q31_step(mc_hallobs_q31_t *st, q31_t theta_hall, q31_t theta_obs, q31_t omega,
                             q31_t *p_theta);

#ifdef __cplusplus
}
#endif

#endif /* MC_HALLOBS_Q31_H */
