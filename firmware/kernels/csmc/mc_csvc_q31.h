/**
 * @file mc_csvc_q31.h
 * @brief q31 twin of the conditional servocompensator / integrator
 *        (csmc/mc_csvc.h): sigma <- Phi sigma + Gam (mu sat(s/mu) - K0 sigma).
 *
 * Per unit: s (and mu) in q31 of s_base_units (config). The state is kept
 * in scaled coordinates w_i = sigma_i / base_i with base_i = s_base/|K0_i|
 * (s_base when K0_i = 0), so that every component of K0 sigma is w_i (or
 * -w_i) per unit of s_base: the compensator's states, whose units differ
 * by powers of 1/s, all live in [-1, 1] of the same scale. Phi and Gam are
 * the f32 kernel's (exact ZOH of S, computed once by mc_csvc_f32_init)
 * transformed to these coordinates (Phi_ij base_j/base_i,
 * Gam_i s_base/base_i) and held as mc_q46 gains: one exponent per
 * coefficient, so entries from 1e-10 to 1e9 (the servocompensator's w0^4)
 * keep 24 significant bits.
 * Scaling and overflow: w and the term are Q46 accumulators (saturate at
 * 2^16 per unit, never wrap); s is clamped to +-mu in Q46. A coefficient
 * outside the mc_q46 range (|g| >= 2^30) is rejected at init
 * (MC_CSVC_ERR_SCALE).
 */
#ifndef MC_CSVC_Q31_H
#define MC_CSVC_Q31_H

#include <stdint.h>

#include "csmc/mc_csvc.h"
#include "math/mc_q46.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MC_CSVC_ERR_SCALE (1u << 8) /**< s_base <= 0 / not finite, or a coefficient out of range */

typedef struct {
    mc_csvc_f32_cfg_t f; /**< model, mu, dt: validated as by mc_csvc_f32_init */
    float s_base;        /**< base of s and mu, > 0 */
} mc_csvc_q31_cfg_t;

typedef struct {
    uint32_t n;
    mc_q46_gain_t phi[MC_CSVC_MAX_ORDER * MC_CSVC_MAX_ORDER];
    mc_q46_gain_t gam[MC_CSVC_MAX_ORDER];
    int32_t k0_sign[MC_CSVC_MAX_ORDER]; /**< sign of K0_i (0 if K0_i = 0) */
    int64_t mu_q46;
    int64_t w_q46[MC_CSVC_MAX_ORDER]; /**< scaled state */
} mc_csvc_q31_t;

uint32_t mc_csvc_q31_init(mc_csvc_q31_t *st, const mc_csvc_q31_cfg_t *cfg);
/** sigma = 0. Returns MC_CSVC_ERR_NONE, or MC_CSVC_ERR_NULL for a NULL st. */
uint32_t mc_csvc_q31_reset(mc_csvc_q31_t *st);
/** K0 sigma in Q46 of s_base. */
int64_t mc_csvc_q31_term_q46(const mc_csvc_q31_t *st);
/** Advance one period with s (Q46 of s_base) held. */
void mc_csvc_q31_update(mc_csvc_q31_t *st, int64_t s_q46);

#ifdef __cplusplus
}
#endif

#endif /* MC_CSVC_Q31_H */
