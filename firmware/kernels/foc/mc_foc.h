/**
 * @file mc_foc.h
 * @brief Field-oriented dq current controller (float32): two PI loops with
 *        decoupling feed-forward, a d-axis-priority voltage limit and the
 *        whole fast step from phase currents to PWM duties.
 *
 * Motor model (PMSM, dq frame aligned with the rotor flux, electrical
 * speed omega_e):
 *     v_d = R i_d + L_d di_d/dt - omega_e L_q i_q
 *     v_q = R i_q + L_q di_q/dt + omega_e L_d i_d + omega_e psi
 * The controller adds the speed-dependent terms as feed-forward (with the
 * measured currents) so that each PI sees a plain R-L load:
 *     v_d = PI_d(id_ref - i_d) - omega_e L_q i_q
 *     v_q = PI_q(iq_ref - i_q) + omega_e L_d i_d + omega_e psi
 * Without decoupling the same terms are formed with L_d, L_q and psi
 * replaced by 0 (init stores the gains so): they are +-0 then.
 * With the pole-zero cancelling gains of mc_foc_f32_gains_from_bandwidth
 * (kp = L bw, ki = R bw) each closed current loop is first order with time
 * constant 1/bw (to the discretisation error of the sample period).
 *
 * Voltage limit, d-axis priority: with v_max = v_max_per_vbus * vbus, where
 * v_max_per_vbus = v_limit_ratio times the largest voltage per volt of bus
 * the modulator delivers (mc_svpwm_max_voltage_f32: 1/sqrt(3) for the
 * circle limit, 2/3 for the hexagon), computed once by init, v_d is limited to [-v_max, v_max] and then v_q to
 * +-sqrt(v_max^2 - v_d^2). Each limit is passed to its PI
 * (mc_pi_f32_step_lim), so the anti-windup works against the limit actually
 * applied, feed-forward included. In the whole step with the hexagon limit,
 * the modulator may cut the vector further (near the hexagon's flat sides);
 * the applied vector (mc_svpwm_limit_f32) is then transformed back to dq and
 * fed to both PIs (mc_pi_f32_track).
 *
 * Computation delay (the whole steps): the currents sampled at t_k are
 * transformed at the angle theta_e they were sampled at (Park), but the
 * duties computed from them take effect one period later and are held for
 * one period, so on average the voltage acts at t_k + 1.5 T, when the rotor
 * has turned 1.5 omega_e T further. The inverse Park (and the Park of the
 * modulator's cut, fed back to the PIs) therefore runs at the voltage angle
 *     theta_v = theta_e + delay_comp_periods * dt_s * omega_e
 * (mc_foc_f32_eval_voltage_angle), delay_comp_periods = MC_FOC_DELAY_COMP_PERIODS
 * (1.5: the drive's one period of computation delay plus the half period of
 * the zero-order hold) from init; mc_foc_f32_set_delay_comp changes it
 * (0: off, the sampled angle for both transforms). The decoupling terms
 * omega_e L i act over the same interval, so they use the current predicted
 * for it from the designed first-order response,
 *     i_ff = i + w (i_ref - i),  w = min(1, delay_comp_periods dt_s kp / L)
 * per axis (kp / L is the designed bandwidth; w = 0 with the compensation
 * off: the measured current). Derivation and measured effect: README,
 * "Computation-delay compensation".
 *
 * Non-finite input (any current, reference, angle, speed or vbus): the step
 * outputs zero voltage (duties 0.5), sets the sticky MC_FOC_ERR_NAN_INPUT,
 * and leaves both integrators untouched. vbus <= 0: the same with
 * MC_FOC_ERR_VBUS. A PI that refuses its step (a feed-forward that overflows
 * to infinity) gives MC_FOC_ERR_PI, zero voltage. The sticky flags are
 * cleared by mc_foc_f32_reset() only.
 *
 * Cost: every step first tries a fast path. It relies on what init
 * validated (symmetric PI limits, v_max per volt of bus precomputed) and on
 * NaN propagation: a non-finite current, reference or speed makes a PI's
 * output non-finite (the feed-forward gains are 0 without decoupling, and
 * 0 * inf is NaN), which fails that PI's range test, so the only explicit
 * tests are the angle's range (|theta| <= 256 rad, inline sin/cos) and the
 * bus (0 < vbus <= vbus_fast_bound, computed by init: at most 2^59, so
 * v_max^2 cannot overflow, and v_max within the PIs' static limit, so the
 * dynamic limit alone bounds the output). A sticky flag sets that bound to
 * 0 until reset, so the fast path only runs with none raised (and writes
 * out->flags = 0 without reading st->flags). The fast path covers the
 * clamping anti-windup (MC_PI_AW_CLAMP, what the drive uses); with
 * back-calculation or none, init sets the bound to 0 and every step runs
 * the checked code. Each PI's common case (output and integrator inside
 * their limits) is two compares; a saturated PI takes the clamping code
 * inline without leaving the fast path. It commits nothing
 * until both PIs are good and, in the modulator's linear region (circle
 * limit), computes the duties inline. It performs the same float
 * operations in the same order as the checked code, so its results are
 * bit-identical; any step it cannot finish (non-finite value, vbus <= 0,
 * angle or bus out of its range, a PI that would refuse) runs through the
 * checked code, so errors and flags are as described above
 * (tests/unit/foc/test_foc_fast.cpp compares the two bit for bit).
 * Measured on the emulated Cortex-M4F: README, "Instruction counts".
 *
 * No heap, no globals, no I/O.
 */
#ifndef MC_FOC_H
#define MC_FOC_H

#include <stdbool.h>
#include <stdint.h>

#include "pi/mc_pi.h"
#include "transforms/mc_svpwm.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MC_FOC_ERR_NONE       0u
#define MC_FOC_ERR_NULL       (1u << 0) /**< a required pointer is NULL */
#define MC_FOC_ERR_MOTOR      (1u << 1) /**< R < 0, L <= 0, psi < 0, or not finite */
#define MC_FOC_ERR_GAIN_D     (1u << 2) /**< d-axis PI gain negative or not finite */
#define MC_FOC_ERR_GAIN_Q     (1u << 3) /**< q-axis PI gain negative or not finite */
#define MC_FOC_ERR_DT         (1u << 4) /**< dt_s <= 0 or not finite */
#define MC_FOC_ERR_LIMIT_MODE (1u << 5) /**< limit_mode not an mc_svpwm_limit_t */
#define MC_FOC_ERR_V_LIMIT \
    (1u << 6) /**< v_limit_ratio not in (0, 1], or v_abs_max_v <= 0 / not finite */
#define MC_FOC_ERR_AW \
    (1u << 7) /**< anti-windup scheme or kaw invalid (see MC_PI_ERR_AW_MODE/KAW) */
#define MC_FOC_ERR_NAN_INPUT (1u << 8)  /**< sticky: a step input was NaN or infinite */
#define MC_FOC_ERR_VBUS      (1u << 9)  /**< sticky: vbus <= 0 */
#define MC_FOC_ERR_PI        (1u << 10) /**< sticky: a PI refused its step */
#define MC_FOC_ERR_BW        (1u << 11) /**< bandwidth helper: bw <= 0 or not finite */
/* (1u << 12) is MC_FOC_ERR_SCALE of the q31 twin */
#define MC_FOC_ERR_DELAY \
    (1u << 13) /**< delay compensation not finite or outside [0, MC_FOC_DELAY_COMP_MAX] */

/** Default advance of the voltage angle, in control periods: one period of
 *  computation delay (duties written one period after the sample) plus half
 *  a period (the zero-order hold's mean delay). */
#define MC_FOC_DELAY_COMP_PERIODS 1.5f
/** Largest accepted advance (periods): a computation delay of up to 3.5. */
#define MC_FOC_DELAY_COMP_MAX 4.0f

/** Largest v_limit_ratio (circle limit) at which the modulator is known to
 *  stay in its linear case: |v| <= 0.99 vbus / sqrt(3) (1 + 1e-6) = 0.5716
 *  vbus is below its test |v| < 0.5745 vbus (MC_SVPWM_LINEAR_MAG2). */
#define MC_FOC_LINEAR_RATIO 0.99f

/** Configuration of the dq current controller. */
typedef struct {
    float r_ohm;                 /**< phase resistance [ohm], >= 0 */
    float ld_h;                  /**< d-axis inductance [H], > 0 */
    float lq_h;                  /**< q-axis inductance [H], > 0 */
    float flux_wb;               /**< permanent-magnet flux linkage psi [Wb], >= 0 */
    float kp_d_v_per_a;          /**< d-axis PI proportional gain [V/A] */
    float ki_d_v_per_as;         /**< d-axis PI integral gain [V/(A s)] */
    float kp_q_v_per_a;          /**< q-axis PI proportional gain [V/A] */
    float ki_q_v_per_as;         /**< q-axis PI integral gain [V/(A s)] */
    float dt_s;                  /**< control period [s], > 0 */
    mc_pi_aw_t aw;               /**< anti-windup of both PIs */
    float kaw_per_s;             /**< back-calculation gain [1/s] (MC_PI_AW_BACK_CALC only) */
    mc_svpwm_limit_t limit_mode; /**< modulator limit: circle (linear) or hexagon */
    float v_limit_ratio;         /**< fraction of the modulator's largest voltage used, (0, 1] */
    float v_abs_max_v;           /**< static PI output and integrator limit [V], > 0 (e.g. the
                                 largest vbus times 2/3) */
    bool decouple;               /**< add the omega_e feed-forward terms */
} mc_foc_f32_cfg_t;

/** State of the dq current controller. */
typedef struct {
    mc_pi_f32_t pi_d; /**< d-axis current PI (output V) */
    mc_pi_f32_t pi_q; /**< q-axis current PI (output V) */
    float ld_h;
    float lq_h;
    float flux_wb;
    float ff_ld_h;            /**< ld_h with decoupling, else 0 (derived) */
    float ff_lq_h;            /**< lq_h with decoupling, else 0 (derived) */
    float ff_flux_wb;         /**< flux_wb with decoupling, else 0 (derived) */
    float ff_nlq_h;           /**< -ff_lq_h (derived) */
    uint32_t vbus_fast_bound; /**< bits of the largest vbus of the fast path: v_max <= the PIs'
                                   out_max there, and vbus <= 2^59; 0 (no fast path) unless
                                   the anti-windup is MC_PI_AW_CLAMP (derived) */
    uint32_t vbus_fast_bits;  /**< vbus_fast_bound while no sticky flag is set, 0 once one is
                                  (the fast path then never runs until reset) (derived) */
    mc_svpwm_limit_t limit_mode;
    float v_limit_ratio;
    float v_max_per_vbus; /**< v_limit_ratio times the modulator's largest voltage per volt
                                 of bus: 1/sqrt(3) (circle) or 2/3 (hexagon) (derived) */
    bool decouple;
    bool svpwm_linear;        /**< circle limit and v_limit_ratio <= MC_FOC_LINEAR_RATIO: the
                                 modulator never limits what the dq step allows (derived) */
    float delay_comp_periods; /**< advance of the voltage angle [periods] */
    float adv_s;              /**< delay_comp_periods * dt_s: theta_v = theta + adv_s omega
                                   (derived) */
    float dt_s;               /**< control period [s] */
    float pred_d;             /**< w of the d current in the decoupling (derived) */
    float pred_q;             /**< w of the q current in the decoupling (derived) */
    float ki_d_cfg;           /**< the configured integral gains [V/(A s)] */
    float ki_q_cfg;
    float r_scale;  /**< ki in force / ki_*_cfg (set_r_scale; 1 after init) */
    uint32_t flags; /**< sticky MC_FOC_ERR_* */
} mc_foc_f32_t;

/** Inputs of the whole fast step. */
typedef struct {
    float ia_a;          /**< phase a current [A] */
    float ib_a;          /**< phase b current [A] */
    float ic_a;          /**< phase c current [A]; read only if three_phase */
    bool three_phase;    /**< true: Clarke from ia, ib, ic; false: from ia, ib (ia+ib+ic = 0) */
    float theta_e_rad;   /**< electrical angle of the d axis [rad] */
    float omega_e_rad_s; /**< electrical speed [rad/s] */
    float vbus_v;        /**< DC-bus voltage [V] */
    float id_ref_a;      /**< d current reference [A] */
    float iq_ref_a;      /**< q current reference [A] */
} mc_foc_f32_in_t;

/** Outputs of the whole fast step (duties plus telemetry). */
typedef struct {
    float duty_a; /**< high-side duty of phase a, [0, 1] */
    float duty_b;
    float duty_c;
    float id_a;           /**< measured d current [A] */
    float iq_a;           /**< measured q current [A] */
    float vd_v;           /**< applied d voltage [V] */
    float vq_v;           /**< applied q voltage [V] */
    float v_alpha_v;      /**< applied alpha voltage [V] */
    float v_beta_v;       /**< applied beta voltage [V] */
    uint32_t svpwm_flags; /**< MC_SVPWM_FLAG_* of this step */
    uint32_t flags;       /**< sticky MC_FOC_ERR_* after this step */
} mc_foc_f32_out_t;

/**
 * Pole-zero cancelling PI gains for a current loop on an R-L load: kp = L bw
 * [V/A], ki = R bw [V/(A s)]; the closed loop is then bw / (s + bw).
 * Returns MC_FOC_ERR_MOTOR (R < 0, L <= 0, not finite), MC_FOC_ERR_BW
 * (bw <= 0, not finite), MC_FOC_ERR_NULL; on error nothing is written.
 */
uint32_t mc_foc_f32_gains_from_bandwidth(float r_ohm, float l_h, float bw_rad_s, float *p_kp,
                                         float *p_ki);

/**
 * Validate cfg and initialise st (integrators 0, flags clear). Returns the OR
 * of the MC_FOC_ERR_* rules broken; on error st is not written.
 */
uint32_t mc_foc_f32_init(mc_foc_f32_t *st, const mc_foc_f32_cfg_t *cfg);

/**
 * Set the computation-delay compensation: the voltage angle is advanced by
 * periods * dt_s * omega_e (0: off). Returns MC_FOC_ERR_DELAY (periods not
 * finite or outside [0, MC_FOC_DELAY_COMP_MAX]) or MC_FOC_ERR_NULL with st
 * unchanged; kept by mc_foc_f32_reset.
 */
uint32_t mc_foc_f32_set_delay_comp(mc_foc_f32_t *st, float periods);

/**
 * A warm winding: the PIs' integral gains become the configured ones times
 * scale (ki = R bw follows R, mc_foc_f32_gains_from_bandwidth; kp = L bw
 * stays), bumplessly (mc_pi_f32_set_gains with kp unchanged moves nothing).
 * State, not a step input: R moves in seconds, a slow loop sets it.
 * MC_FOC_ERR_MOTOR for a scale outside
 * mc_r_scale_f32_ok (math/mc_math.h), MC_FOC_ERR_NULL; st unchanged then. Kept
 * by mc_foc_f32_reset.
 */
uint32_t mc_foc_f32_set_r_scale(mc_foc_f32_t *st, float scale);

/** The decoupling's prediction weight of one axis (shared by the twins):
 *  min(1, periods dt kp / L), kp / L the axis' designed bandwidth. */
static inline float mc_foc_f32_eval_pred_weight(float periods, float dt_s, float kp, float l_h)
{
    const float w = periods * dt_s * (kp / l_h);
    return (w < 1.0f) ? w : 1.0f;
}

/** true when periods is a valid delay compensation (shared by the twins). */
static inline bool mc_foc_f32_validate_delay_comp(float periods)
{
    return (periods >= 0.0f) && (periods <= MC_FOC_DELAY_COMP_MAX); /* false for NaN */
}

/**
 * The angle the voltage of this step acts at on average (see the file
 * comment): theta_e + adv_s * omega_e, not wrapped; the whole steps use it
 * for the inverse Park. st is not checked (a valid, initialised state).
 */
static inline float mc_foc_f32_eval_voltage_angle(const mc_foc_f32_t *st, float theta_e_rad,
                                                  float omega_e_rad_s)
{
    return theta_e_rad + (st->adv_s * omega_e_rad_s);
}

/** Integrators to 0, sticky flags cleared. Returns MC_FOC_ERR_NONE, or
 *  MC_FOC_ERR_NULL for a NULL st. */
uint32_t mc_foc_f32_reset(mc_foc_f32_t *st);

/**
 * One dq current-controller step: PIs, decoupling, d-priority limit.
 * Writes vd, vq (zero on error). Returns the MC_FOC_ERR_* bits raised by this
 * step (MC_FOC_ERR_NONE = 0 when it ran); st->flags keeps them.
 */
uint32_t mc_foc_f32_step_dq(mc_foc_f32_t *st, float id_ref_a, float iq_ref_a, float id_a,
                            float iq_a, float omega_e_rad_s, float vbus_v, float *p_vd_v,
                            float *p_vq_v);

/**
 * The whole fast step: Clarke, then mc_foc_f32_step_ab. Fills *out
 * (duties 0.5 and zero voltages on error). Returns the MC_FOC_ERR_* bits
 * raised by this step. A non-finite current (one that is read) makes a
 * non-finite alpha or beta current, hence MC_FOC_ERR_NAN_INPUT.
 */
uint32_t mc_foc_f32_step(mc_foc_f32_t *st, const mc_foc_f32_in_t *in, mc_foc_f32_out_t *out);

/**
 * The whole fast step from alpha-beta currents (the caller did the Clarke
 * transform, e.g. for an observer that needs them too): Park at theta_e
 * (mc_sincos_f32), dq step, inverse Park at the voltage angle
 * (mc_foc_f32_eval_voltage_angle), modulator limit (fed back to the PIs),
 * SVPWM. mc_foc_f32_step is exactly this after its Clarke transform.
 * Arguments as in mc_foc_f32_in_t (alpha/beta currents amplitude
 * invariant, mc_clarke_f32), passed by value so that they stay in
 * registers. Non-finite alpha/beta current or angle:
 * MC_FOC_ERR_NAN_INPUT (id, iq reported 0); so is a voltage angle that
 * overflows (a finite speed so large that adv_s omega_e is infinite); the
 * dq step's inputs and errors
 * as in mc_foc_f32_step_dq (out->id_a, iq_a are the measured values then).
 * Fills *out (duties 0.5 and zero voltages on error). Returns the
 * MC_FOC_ERR_* bits raised by this step.
 */
uint32_t mc_foc_f32_step_ab(mc_foc_f32_t *st, float i_alpha_a, float i_beta_a, float theta_e_rad,
                            float omega_e_rad_s, float vbus_v, float id_ref_a, float iq_ref_a,
                            mc_foc_f32_out_t *out);

#ifdef __cplusplus
}
#endif

#endif /* MC_FOC_H */
