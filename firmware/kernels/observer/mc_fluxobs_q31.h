/**
 * @file mc_fluxobs_q31.h
 * @brief q31 twin of the flux gradient observer with its angle estimate
 *        (observer/mc_fluxobs.h, paper 002 eq. (9); theta from
 *        mc_atan2_q31).
 *
 * Same discretisation as the f32 kernel:
 *     xh <- xh + dt (v - R (i_prev + i)/2)
 *     e  =  xh - L i
 *     k  =  dt (gamma/2) (flux^2 - |e|^2),  clamped to k >= -1/2
 *     e  <- e + k e,  xh = e + L i,  theta = atan2(e_beta, e_alpha)
 *
 * Per unit (config): currents q31 of i_base_a, voltages q31 of v_base_v,
 * fluxes of flux_base_wb; the angle is a q31 normalised turn. Gains formed
 * once at init (float) as mc_q46 gains: dt v_base/flux_base,
 * dt R i_base/(2 flux_base), L i_base/flux_base, gamma dt flux_base^2/2.
 *
 * Scaling and overflow: xh and e are Q46 accumulators (15 guard bits:
 * the per-step flux increment dt v is ~1e-4 of the flux, so a q31 state
 * would lose its low bits every step); |e|^2 is formed exactly from e
 * rounded to q31 (uint64 Q62 sum of squares, <= 2^63), flux^2 - |e|^2 in
 * Q46; k is Q46, clamped to [-1/2, ...] and then to q31 (k <= gamma flux^2
 * dt / 2 <= 0.1 by the init rule). xh saturates at +-1 flux_base per
 * component (never wraps); e rounds to q31 for atan2 and |e|^2, so keep
 * |e| <= flux + L |i| below one flux base: choose
 * flux_base >= 1.5 (flux + L i_max) for headroom.
 * Divergence monitor: the residual |e|/flux - 1 in q31 (exact integer
 * sqrt and one int64 division) against resid_tol; the time out of
 * tolerance is counted in steps (resid_time_s/dt rounded): the f32 kernel
 * accumulates dt in float, so both raise MC_FLUXOBS_ERR_DIVERGED on the
 * same step up to that rounding.
 * Salient machine (cfg.f.ld_minus_lq_h != 0): the f32 kernel's active-flux
 * form, psi_a = flux + (Ld - Lq) i_d with i_d = c(theta_prev) . i_ab
 * (mc_sincos_q31 of the previous estimate), floored at
 * MC_FLUXOBS_PSI_A_MIN_FRAC flux, in place of the flux in the constraint
 * and the residual; non-salient: the constants, as before.
 * Error vs f32: tests/unit/q31/test_fluxobs_q31.cpp.
 */
#ifndef MC_FLUXOBS_Q31_H
#define MC_FLUXOBS_Q31_H

#include <stdbool.h>
#include <stdint.h>

#include "math/mc_q46.h"
#include "observer/mc_fluxobs.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MC_FLUXOBS_ERR_SCALE \
    (1u << 8) /**< a base <= 0 / not finite, flux >= flux_base, or a gain out of range */

typedef struct {
    mc_fluxobs_f32_cfg_t f; /**< R, L, flux, gamma, dt, monitor: as the f32 kernel */
    float i_base_a;         /**< current base [A], > 0 */
    float v_base_v;         /**< voltage base [V], > 0 */
    float flux_base_wb;     /**< flux base [Wb], > flux */
} mc_fluxobs_q31_cfg_t;

typedef struct {
    mc_q46_gain_t g_v;    /**< dt v_base/flux_base */
    mc_q46_gain_t g_r;    /**< dt R i_base/(2 flux_base), R in force (cfg R r_scale) */
    float g_r_cfg;        /**< the same for the configured R (set_r_scale scales it) */
    float r_scale;        /**< R in force / configured R (1 after init) */
    mc_q46_gain_t g_l;    /**< L i_base/flux_base */
    mc_q46_gain_t g_k;    /**< gamma dt flux_base^2 / 2 */
    mc_q46_gain_t g_dl;   /**< (Ld - Lq) i_base/flux_base (salient machine) */
    bool salient;         /**< cfg ld_minus_lq_h != 0 */
    q31_t psi_a_floor;    /**< MC_FLUXOBS_PSI_A_MIN_FRAC flux/flux_base */
    q31_t psi_a_pu;       /**< active flux of the last step (flux_pu if non-salient) */
    uint64_t flux2_q62;   /**< (flux/flux_base)^2 in Q62 */
    q31_t flux_pu;        /**< flux/flux_base */
    q31_t resid_tol;      /**< tolerated | |e|/flux - 1 | in q31 */
    uint32_t resid_steps; /**< steps out of tolerance before the flag */
    int64_t x_alpha_q46;  /**< flux estimate (Q46 of flux_base) */
    int64_t x_beta_q46;
    q31_t i_alpha_prev; /**< current at the start of the step (pu) */
    q31_t i_beta_prev;
    q31_t theta;              /**< angle estimate (q31 turn) */
    q31_t resid;              /**< |e|/flux - 1 of the last step (q31, saturated) */
    uint32_t resid_bad_steps; /**< steps out of tolerance */
    uint32_t flags;           /**< sticky MC_FLUXOBS_ERR_DIVERGED */
} mc_fluxobs_q31_t;

/** Validate cfg, estimate for angle 0 at zero current. On error st is not written. */
uint32_t mc_fluxobs_q31_init(mc_fluxobs_q31_t *st, const mc_fluxobs_q31_cfg_t *cfg);

/** Restart from an angle guess (q31 turn) and the present current (pu),
 *  flags cleared. Returns MC_FLUXOBS_ERR_NONE, or MC_FLUXOBS_ERR_NULL for a
 *  NULL st. */
uint32_t mc_fluxobs_q31_reset(mc_fluxobs_q31_t *st, q31_t theta_guess, q31_t i_alpha, q31_t i_beta);

/** R in force = the configured R times scale (mc_fluxobs_f32_set_r_scale):
 *  the R gain re-formed from the configured one. A scale outside
 *  mc_r_scale_f32_ok: MC_FLUXOBS_ERR_ARG, nothing changed. Float
 *  arithmetic, meant for a slow loop. */
uint32_t mc_fluxobs_q31_set_r_scale(mc_fluxobs_q31_t *st, float scale);

/** One step (see mc_fluxobs_f32_step); returns the bits raised (DIVERGED). */
uint32_t mc_fluxobs_q31_step(mc_fluxobs_q31_t *st, q31_t v_alpha, q31_t v_beta, q31_t i_alpha,
                             q31_t i_beta);

#ifdef __cplusplus
}
#endif

#endif /* MC_FLUXOBS_Q31_H */
