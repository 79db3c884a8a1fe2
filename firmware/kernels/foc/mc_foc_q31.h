/**
 * @file mc_foc_q31.h
 * @brief q31 twin of the dq current controller (foc/mc_foc.h): two q31 PIs
 *        (mc_pi_q31), decoupling feed-forward, d-axis-priority voltage
 *        limit, and the whole fast step (Clarke, Park, dq step, inverse
 *        Park, SVPWM, all q31).
 *
 * Law (as mc_foc_f32):
 *     v_d = PI_d(id_ref - i_d) - omega_e L_q i_q
 *     v_q = PI_q(iq_ref - i_q) + omega_e L_d i_d + omega_e psi
 *     v_max = v_limit_ratio vbus / sqrt(3);  |v_d| <= v_max,
 *     |v_q| <= sqrt(v_max^2 - v_d^2)  (each limit passed to its PI)
 *
 * Per unit (config): currents q31 of i_base_a, voltages (and vbus) q31 of
 * v_base_v, the electrical speed q31 of omega_base_rad_s, the angle a q31
 * normalised turn. Choose v_base above the largest vbus and i_base above
 * the largest phase current (e.g. the sensor range): inputs and errors
 * saturate at one base.
 *
 * Scaling and overflow:
 * - the PIs: mc_pi_q31 (gains kp i_base/v_base, ki dt i_base/v_base as
 *   mantissa + shift, Q17.46 integrator; see mc_pi.h); the current error
 *   id_ref - i_d is formed with mc_q31_sub_sat (saturates at +-1 base);
 * - feed-forward: omega_e i_q as a rounded q31 product (mc_q31_mul), times
 *   the mc_q46 gain omega_base L_q i_base/v_base (and L_d, psi likewise),
 *   summed in Q46 and saturated to q31;
 * - v_max = (ratio/sqrt(3)) vbus as a Q46 product rounded to q31;
 *   sqrt(v_max^2 - v_d^2) by the exact integer square root of the Q62
 *   difference (mc_isqrt_u64): never negative, never above v_max.
 * DEPARTURE from the f32 kernel: the circle limit only (MC_SVPWM_LIMIT_
 * HEXAGON is rejected with MC_FOC_ERR_LIMIT_MODE): the q31 PI has no
 * tracking step to feed the hexagon's extra cut back. With the circle the
 * dq limit is the modulator's, so nothing is cut after the PIs (up to the
 * modulator's own rounding, reported in svpwm_flags).
 * Computation delay: as the f32 kernel (mc_foc.h), the inverse Park runs
 * at the voltage angle theta_e + delay_comp_periods dt omega_e
 * (mc_foc_q31_eval_voltage_angle: the advance as the Q46 gain
 * delay_comp_periods dt omega_base / pi times omega_e, rounded to a q31
 * turn, saturated at half a turn, added with the turn's wrap), 1.5 periods
 * from init, mc_foc_q31_set_delay_comp to change it (same rule,
 * mc_foc_f32_validate_delay_comp); the decoupling's currents predicted as
 * i + w (i_ref - i) with the f32 kernel's w (mc_foc_f32_eval_pred_weight) as a q31
 * fraction, the difference saturated at one base.
 * Error vs f32: tests/unit/q31/test_foc_q31.cpp.
 */
#ifndef MC_FOC_Q31_H
#define MC_FOC_Q31_H

#include <stdbool.h>
#include <stdint.h>

#include "foc/mc_foc.h"
#include "math/mc_q46.h"
#include "pi/mc_pi.h"
#include "pi/mc_pi_q31.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MC_FOC_ERR_SCALE \
    (1u << 12) /**< a base <= 0 / not finite, or a gain beyond the q31 formats */

typedef struct {
    mc_foc_f32_cfg_t f;     /**< engineering config, validated as by mc_foc_f32_init */
    float i_base_a;         /**< current base [A], > 0 */
    float v_base_v;         /**< voltage base [V], > 0 */
    float omega_base_rad_s; /**< electrical speed base [rad/s], > 0 */
} mc_foc_q31_cfg_t;

typedef struct {
    mc_pi_q31_t pi_d;
    mc_pi_q31_t pi_q;
    mc_q46_gain_t g_ff_d;     /**< omega_base L_q i_base / v_base */
    mc_q46_gain_t g_ff_q;     /**< omega_base L_d i_base / v_base */
    mc_q46_gain_t g_ff_psi;   /**< omega_base psi / v_base */
    mc_q46_gain_t g_vmax;     /**< v_limit_ratio / sqrt(3) */
    mc_q46_gain_t g_adv;      /**< delay_comp_periods dt omega_base / pi: q31 turn per pu speed */
    float adv_pu_per_period;  /**< dt omega_base / pi (derived) */
    float delay_comp_periods; /**< advance of the voltage angle [periods] */
    float bw_dt_d;            /**< dt kp_d / L_d (derived) */
    float bw_dt_q;            /**< dt kp_q / L_q (derived) */
    q31_t pred_d;             /**< w of the d current in the decoupling, q31 fraction */
    q31_t pred_q;             /**< w of the q current in the decoupling, q31 fraction */
    bool decouple;
    q31_t vd; /**< last applied voltages (pu) */
    q31_t vq;
    uint32_t flags; /**< sticky MC_FOC_ERR_VBUS */
} mc_foc_q31_t;

typedef struct {
    q31_t ia, ib, ic; /**< phase currents (pu); ic read only if three_phase */
    bool three_phase;
    q31_t theta_e;        /**< electrical angle (q31 turn) */
    q31_t omega_e;        /**< electrical speed (pu) */
    q31_t vbus;           /**< DC bus (pu of v_base) */
    q31_t id_ref, iq_ref; /**< current references (pu) */
} mc_foc_q31_in_t;

typedef struct {
    q31_t duty_a, duty_b, duty_c; /**< [0, 1) */
    q31_t id, iq;                 /**< measured dq currents (pu) */
    q31_t vd, vq;                 /**< applied dq voltages (pu) */
    q31_t v_alpha, v_beta;        /**< applied alpha-beta voltages (pu) */
    uint32_t svpwm_flags;
    uint32_t flags;
} mc_foc_q31_out_t;

/** Validate cfg (MC_FOC_ERR_* as the f32 kernel, plus _SCALE and _LIMIT_MODE
 *  for the hexagon) and initialise st. On error st is not written. */
uint32_t mc_foc_q31_init(mc_foc_q31_t *st, const mc_foc_q31_cfg_t *cfg);

/** The delay compensation (mc_foc_f32_set_delay_comp's rule): returns
 *  MC_FOC_ERR_DELAY, MC_FOC_ERR_NULL (st unchanged) or MC_FOC_ERR_NONE. */
uint32_t mc_foc_q31_set_delay_comp(mc_foc_q31_t *st, float periods);

/** The voltage angle (q31 turn) of a step at theta_e, omega_e (see the file
 *  comment); st is not checked. */
static inline q31_t mc_foc_q31_eval_voltage_angle(const mc_foc_q31_t *st, q31_t theta_e,
                                                  q31_t omega_e)
{
    return mc_q31_angle_add(theta_e, mc_q46_to_q31(mc_q46_mul_q31(st->g_adv, omega_e)));
}

/** Integrators and voltages to 0, flags cleared. Returns MC_FOC_ERR_NONE,
 *  or MC_FOC_ERR_NULL for a NULL st. */
uint32_t mc_foc_q31_reset(mc_foc_q31_t *st);

/** dq step (see the file comment); vbus <= 0: zero voltage, MC_FOC_ERR_VBUS. */
uint32_t mc_foc_q31_step_dq(mc_foc_q31_t *st, q31_t id_ref, q31_t iq_ref, q31_t id, q31_t iq,
                            q31_t omega_e, q31_t vbus, q31_t *p_vd, q31_t *p_vq);

/** The whole fast step (duties 0.5, zero voltage on error). */
uint32_t mc_foc_q31_step(mc_foc_q31_t *st, const mc_foc_q31_in_t *in, mc_foc_q31_out_t *out);

#ifdef __cplusplus
}
#endif

#endif /* MC_FOC_Q31_H */
