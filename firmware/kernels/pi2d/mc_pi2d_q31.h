/**
 * @file mc_pi2d_q31.h
 * @brief q31 twin of the PI^2D output-feedback speed controller
 *        (pi2d/mc_pi2d.h, paper 000): the same law, limits, conditional
 *        integration and discretisation, in per-unit integer arithmetic.
 *
 * Per unit (config, every signal has its base):
 *   id, iq, id_ref, iq_ref: i_base_a        vd, vq: v_base_v
 *   theta_m, theta_ref, e4: theta_base_rad  theta_f: thetaf_base_rad
 *   omega_ref: omega_base_rad_s             alpha_ref: alpha_base_rad_s2
 *   jerk_ref: jerk_base_rad_s3              did_ref: did_base_a_s
 *   nu: nu_base_nm
 * The law is linear in these signals except for the two speed products
 * p L i omega_ref; init folds every constant of mc_pi2d.h (with the bases)
 * into one mc_q46 gain per term (float, once), e.g. for x2*:
 *     iq_ref = [nu_b/(kt i_b)] nu + [J alpha_b/(kt i_b)] alpha_ref
 *            - [J kp theta_b/(kt i_b)] e4 - [J kd thetaf_b/(kt i_b)] theta_f
 * and for u2 the rho and v2 terms combine into one gain on e4 and one on
 * theta_f (two sets: with rho, and with rho = 0 while x2* is clamped).
 *
 * Scaling and overflow: every sum is a Q46 accumulator (mc_q46.h: 17
 * integer bits, saturating at 2^16 per unit, never wraps); the dirty
 * derivative is mc_ddiff_q31 (Q46 state); nu is a Q46 state (the paper's
 * per-step increment ~1e-7 N m is ~3e3 Q46 LSB of a 2 N m base: no
 * compensated sum needed, unlike the f32 kernel). The voltage circle is
 * applied in Q46 (mc_q46_limit_vec: exact integer |u|, direction kept);
 * the outputs round to q31 and saturate at one base. The configured limits
 * iq_max, v_max, nu_max are clamped to one base (so a base below a limit
 * makes the base the limit). Choose the bases above the signals' ranges;
 * tests/unit/q31 and tests/sil/q31 bound the difference to the f32 kernel.
 * e4 = theta_m - theta_ref saturates at +-1 theta_base.
 */
#ifndef MC_PI2D_Q31_H
#define MC_PI2D_Q31_H

#include <stdbool.h>
#include <stdint.h>

#include "filters/mc_ddiff_q31.h"
#include "math/mc_q46.h"
#include "pi2d/mc_pi2d.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MC_PI2D_ERR_SCALE (1u << 11) /**< a base <= 0 / not finite, or a gain beyond mc_q46 */

/** Bases of the per-unit signals (all > 0). */
typedef struct {
    float i_base_a;
    float v_base_v;
    float theta_base_rad;
    float thetaf_base_rad;
    float omega_base_rad_s;
    float alpha_base_rad_s2;
    float jerk_base_rad_s3;
    float did_base_a_s;
    float nu_base_nm;
} mc_pi2d_q31_bases_t;

typedef struct {
    mc_pi2d_f32_cfg_t f; /**< engineering config, validated as by mc_pi2d_f32_init */
    mc_pi2d_q31_bases_t base;
} mc_pi2d_q31_cfg_t;

typedef struct {
    q31_t id, iq;             /**< measured x1, x2 (i_base) */
    q31_t theta_m, theta_ref; /**< positions with a common offset removed (theta_base) */
    q31_t omega_ref;          /**< omega_base */
    q31_t alpha_ref;          /**< alpha_base */
    q31_t jerk_ref;           /**< jerk_base */
    q31_t id_ref;             /**< i_base */
    q31_t did_ref;            /**< did_base */
} mc_pi2d_q31_in_t;

typedef struct {
    q31_t vd, vq;         /**< after the voltage limit (v_base) */
    q31_t id_ref, iq_ref; /**< x1*, x2* after its clamp (i_base) */
    q31_t e4;             /**< theta_base */
    q31_t theta_f;        /**< thetaf_base */
    q31_t nu;             /**< load estimate used in this step (nu_base) */
    bool iq_limited;
    bool v_limited;
} mc_pi2d_q31_out_t;

typedef struct {
    mc_ddiff_q31_t dd;
    /* x2* */
    mc_q46_gain_t g_iq_nu, g_iq_alpha, g_iq_e4, g_iq_th;
    /* u1 */
    mc_q46_gain_t g_u1_idref, g_u1_id, g_u1_did, g_plw;
    /* u2 */
    mc_q46_gain_t g_u2_w, g_u2_iqref, g_u2_iq;
    mc_q46_gain_t g_u2_e4_rho, g_u2_th_rho, g_u2_jerk; /* rho + v2 */
    mc_q46_gain_t g_u2_e4_v2, g_u2_th_v2;              /* v2 only (x2* clamped) */
    /* nu */
    mc_q46_gain_t g_nu_e4, g_nu_th;
    int64_t iq_max_q46, v_max_q46, nu_max_q46;
    int64_t nu_q46; /**< load estimate (Q46 of nu_base) */
} mc_pi2d_q31_t;

/** Validate cfg (MC_PI2D_ERR_* of mc_pi2d_f32_init on cfg->f, plus
 *  MC_PI2D_ERR_SCALE) and initialise st (q_c = 0, nu = 0). Returns the OR of
 *  the rules broken; on error st is not written. */
uint32_t mc_pi2d_q31_init(mc_pi2d_q31_t *st, const mc_pi2d_q31_cfg_t *cfg);

/** Preset q_c (thetaf_base) and nu (nu_base, clamped to +-nu_max). Returns
 *  MC_PI2D_ERR_NONE, or MC_PI2D_ERR_NULL for a NULL st (q31 values are
 *  always finite: no MC_PI2D_ERR_NAN_INPUT). */
uint32_t mc_pi2d_q31_reset(mc_pi2d_q31_t *st, q31_t qc0, q31_t nu0);

/** One control step, as mc_pi2d_f32_step: out is the only place the outputs
 *  are written (the kernel keeps no copy). Returns MC_PI2D_ERR_NONE, or
 *  MC_PI2D_ERR_NULL when st, in or out is NULL (nothing written). q31 inputs
 *  are always finite and every sum saturates: no MC_PI2D_ERR_NAN_INPUT. */
uint32_t mc_pi2d_q31_step(mc_pi2d_q31_t *st, const mc_pi2d_q31_in_t *in, mc_pi2d_q31_out_t *out);

#ifdef __cplusplus
}
#endif

#endif /* MC_PI2D_Q31_H */
