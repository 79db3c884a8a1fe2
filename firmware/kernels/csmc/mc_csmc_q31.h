/**
 * @file mc_csmc_q31.h
 * @brief q31 twin of the CSMC stepper position law with conditional
 *        integrators / servocompensators and the ideal-SMC baseline
 *        (csmc/mc_csmc.h, paper 001 eqs. (3)-(5), (7), (9)-(11)).
 *
 * Same law, switching functions and output clamp as mc_csmc_f32_step;
 * sigma by mc_csvc_q31. Per unit (config bases, all > 0):
 *   e1, i_d, i_q, s1, mu1:   i_base_a      e2:          theta_base_rad
 *   e2', omega:              omega_base    e2'', s2, mu2: alpha_base
 *   I_dd', F1 = k5 x2 x3 - I_dd': did_base_a_s
 *   phi_d''':                jerk_base     G (internal): g_base_rad_s3
 *   v_d, v_q:                v_base_v
 * Every constant of the law (k1^2, k2^2, K_m, J, B, N_r, R^, L^, the
 * bounds' dR, dL, q_i, M_i and 1/mu_i) is folded with the bases into one
 * mc_q46 gain per term at init (float, once).
 *
 * Scaling and overflow: s1, s2, F1, G, the beta functions and u are Q46
 * accumulators (17 integer bits, saturating at 2^16 per unit, never
 * wrapping): G, whose size is of the order of k1^2 e2' (1e5..1e7 rad/s^3
 * in the paper's transients), only needs g_base chosen so that it stays
 * below 2^16 g_base; its resolution is 2^-46 g_base. The products x2 x3
 * and x1 x3 are rounded q31 products. psi = sat(s/mu) is a Q46 product
 * clamped to +-1 and rounded to q31 (sgn: +-1 exactly, MC_Q31_MAX for +1).
 * The output clamp v_limit is clamped to one v_base. sigma advances with s
 * held (Q46), as the f32 kernel.
 */
#ifndef MC_CSMC_Q31_H
#define MC_CSMC_Q31_H

#include <stdint.h>

#include "csmc/mc_csmc.h"
#include "csmc/mc_csvc_q31.h"
#include "math/mc_q46.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MC_CSMC_ERR_SCALE (1u << 12) /**< a base <= 0 / not finite, or a gain out of range */

typedef struct {
    float i_base_a;
    float theta_base_rad;
    float omega_base_rad_s;
    float alpha_base_rad_s2;
    float did_base_a_s;
    float jerk_base_rad_s3;
    float g_base_rad_s3;
    float v_base_v;
} mc_csmc_q31_bases_t;

typedef struct {
    mc_csmc_f32_cfg_t f; /**< validated as by mc_csmc_f32_init */
    mc_csmc_q31_bases_t base;
} mc_csmc_q31_cfg_t;

typedef struct {
    q31_t e1;       /**< i_base */
    q31_t e2;       /**< theta_base */
    q31_t de2;      /**< omega_base */
    q31_t dde2;     /**< alpha_base */
    q31_t i_d, i_q; /**< i_base (LAW_MODEL) */
    q31_t omega_m;  /**< omega_base (LAW_MODEL) */
    q31_t di_dd;    /**< did_base (LAW_MODEL) */
    q31_t dddphi_d; /**< jerk_base (LAW_MODEL) */
} mc_csmc_q31_in_t;

typedef struct {
    q31_t v_d, v_q; /**< v_base */
    q31_t s1;       /**< i_base */
    q31_t s2;       /**< alpha_base */
} mc_csmc_q31_out_t;

typedef struct {
    mc_csmc_law_t law;
    mc_csmc_sw_t sw;
    /* s2 = g_e2 e2 + g_de2 e2' + g_dde2 e2'' (alpha_base) */
    mc_q46_gain_t g_s2_e2, g_s2_de2, g_s2_dde2;
    mc_q46_gain_t g_inv_mu1, g_inv_mu2; /**< s_base/mu */
    mc_q46_gain_t g_m1, g_m2;           /**< M/v_base (LAW_CONST) */
    /* LAW_MODEL */
    mc_q46_gain_t g_f1_x23; /**< k5 i_b w_b / did_b on x2 x3 */
    mc_q46_gain_t g_g_de2, g_g_dde2, g_g_jerk, g_g_x2, g_g_x3, g_g_x13;
    int64_t g_const_q46; /**< k4 d0 / g_base */
    mc_q46_gain_t g_rx, g_lf, g_km,
        g_lg; /**< R^ i_b/v_b, L^ did_b/v_b, Km w_b/v_b, L^ g_b/(k3 v_b) */
    mc_q46_gain_t g_b_dr, g_b1_dl, g_b2_dl; /**< dR i_b/v_b, dL did_b/v_b, dL g_b/(k3 v_b) */
    int64_t q1_q46, q2_q46;                 /**< q1/v_b, q2/(k3 v_b) */
    int64_t v_lim_q46;
    uint32_t have_sigma1, have_sigma2;
    mc_csvc_q31_t sigma1, sigma2;
    mc_csmc_q31_out_t out;
} mc_csmc_q31_t;

uint32_t mc_csmc_q31_init(mc_csmc_q31_t *st, const mc_csmc_q31_cfg_t *cfg);
/** sigma = 0, last output 0. Returns MC_CSMC_ERR_NONE, or MC_CSMC_ERR_NULL
 *  for a NULL st. */
uint32_t mc_csmc_q31_reset(mc_csmc_q31_t *st);

/** One control step (as mc_csmc_f32_step), the outputs in *p_out. Returns
 *  MC_CSMC_ERR_NONE, or MC_CSMC_ERR_NULL (st, in or p_out NULL: nothing
 *  written); q31 inputs are always finite and every sum saturates, so no
 *  MC_CSMC_ERR_NAN_INPUT. */
uint32_t mc_csmc_q31_step(mc_csmc_q31_t *st, const mc_csmc_q31_in_t *in, mc_csmc_q31_out_t *p_out);

#ifdef __cplusplus
}
#endif

#endif /* MC_CSMC_Q31_H */
