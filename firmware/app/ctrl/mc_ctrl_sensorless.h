/**
 * @file mc_ctrl_sensorless.h
 * @brief Sensorless field-oriented speed control of a PMSM (paper 002,
 *        Section V; a salient machine with the observer's active-flux form
 *        and MTPA), as a control law plugged into the drive
 *        (mc_drive_attach_ctrl, MC_DRIVE_MODE_CTRL).
 *
 * Each fast step (PWM rate), from the phase currents only:
 *   1. Clarke -> i_ab; the alpha-beta voltage applied over the period that
 *      just ended (the drive's current loop commanded it pwm_delay_periods
 *      steps before: mc_drive_meas_t.v_alpha_prev_v into the law's history,
 *      after the modulator's limit, minus the dead-time voltage error
 *      sat(i_x / dead_band) (dead_time / dt) vbus of each leg, with the
 *      mean of the currents at both ends of the period; with
 *      dead_comp_duty the drive's duties carry the correction instead
 *      (mc_drive_cfg_t.dead_time_comp), and the commanded voltage is used)
 *      -> flux gradient observer (mc_fluxobs) -> theta_hat; PLL
 *      (mc_spdpll) -> omega_hat.
 *      At low speed the back-EMF is a few volts and an uncompensated
 *      2 us dead time at 8 kHz and 200 V is 3.2 V per leg: the observer
 *      integrates it as flux.
 *   2. Every speed_div steps: speed PI on the PLL speed -> the current
 *      command (iq_ref; on a salient machine with law_mtpa, MTPA's
 *      (id, iq) for its magnitude: see "Salient machine" below), limited
 *      to +-iq_max_a (torque limit; the drive's current limit in force /
 *      1.25 when lower), clamping anti-windup; the integrator tracks what
 *      the drive's regenerative limit applied. The reference is the drive's
 *      shaped one with ref_from_drive (the drive's ramp and controlled
 *      stop), else the law's own slew.
 *   3. the current references in the frame the law controls go to the
 *      drive's current loop (MC_DRIVE_OUT_CURRENT: MTPA / field weakening
 *      and the regen limit once the frame is the rotor's estimate, the
 *      dq PIs with decoupling, SVPWM, the duty-side dead-time correction);
 *      across a hand-over or fallback the drive presets its current PIs so
 *      that the voltage vector is continuous (mc_drive_out_t.reframe).
 *      Without the dead-time correction, at light load (phase currents
 *      near zero) that error makes the speed loop oscillate (README,
 *      "Light load with dead time").
 *
 * Start-up and low speed (the observer cannot see the angle at standstill,
 * Prop. 4 i, and below the critical speed it has extra equilibria):
 *   ALIGN  current vector ramped from 0 to if_current_a at a fixed angle;
 *   IF     open-loop current-frequency drive: iq_ref = current magnitude in
 *          a frame theta_if turning at omega_if, ramped at if_accel towards
 *          the handover speed (or the reference, if lower); the rotor follows
 *          with a load angle. The observer and PLL run all the time. The
 *          rotor on the I-f "spring" is undamped (it rings at
 *          sqrt(kt I / J)); with if_damping a current -speed_kp (omega_hat -
 *          omega_if) along the estimated q axis damps it (the observer is
 *          used for damping only, never for the frame).
 *   CLOSED sensorless speed loop. Hand-over IF -> CLOSED when |omega_if| has
 *          reached handover_speed and the PLL speed agrees with omega_if to
 *          lock_tol; it keeps the current VECTOR (in the stator frame)
 *          unchanged: id_ref = -I sin(d), iq_ref = I cos(d) with
 *          d = theta_if - theta_hat, the speed PI's integrator preset to that
 *          iq_ref (the torque, 3/2 p flux iq, does not jump), id_ref then
 *          ramped to 0 (MTPA's, salient) over blend_time_s (no torque effect
 *          on a non-salient machine), the current PIs' integrators preset so the voltage
 *          vector is continuous.
 *   Back to IF when the reference and the speed estimate fall below
 *          handover_speed (1 - handover_hyst) (if lowspeed_fallback): the
 *          I-f frame is placed so that iq (the torque) is unchanged and the
 *          rotor sits on the stable side of the I-f equilibrium: magnitude
 *          I = max(if_current_a, 1.25 |iq|), load angle asin(iq / I); only
 *          id steps (0 -> I cos(delta) > 0, no torque on a non-salient
 *          machine). omega_if starts at omega_hat and follows the reference
 *          down to zero (holding torque at standstill). Keeping the whole
 *          current vector instead would put the rotor on the I-f stability
 *          limit (and, while braking, past it: pole slip).
 *
 * Salient machine (ld_minus_lq_h != 0; mc_law_sls_cfg sets it from the
 * parameters' Ld and Lq, l_h = Lq):
 *   - the observer runs its active-flux form (mc_fluxobs.h: psi_a = flux +
 *     (Ld - Lq) i_d, i_d at the previous estimate);
 *   - CLOSED: the speed PI's output is the current command i; with
 *     law_mtpa the d reference goes (at the blend's slew) to MTPA's for
 *     |i| (mc_fw_f32_mtpa_id, the drive's MTPA kernel, here without its
 *     field weakening) and iq = sign(i) sqrt(i^2 - id^2). law_mtpa false
 *     (mc_app: the drive's own MTPA, fw_enable, shapes the command): id 0
 *     from the law, the drive's kernel sets it;
 *   - gamma is chosen at the LARGEST active flux of the closed loop,
 *     psi_a_max = flux + (Ld - Lq) id_mtpa(1.25 iq_max) (MTPA's d current
 *     has the sign of Ld - Lq, so it raises psi_a): the observer's
 *     critical speed gamma psi_a^2 / (4 n_P) is then at most the configured
 *     omega_crit at every operating point, and the hand-over margin below
 *     holds. Where psi_a is smaller (the I-f start: its d current is >= 0
 *     on the stable side, which lowers psi_a for Ld < Lq) the observer is
 *     slower by (psi_a_max / psi_a)^2;
 *   - the I-f start, the hand-over and the fallback are unchanged; their
 *     d current steps (hand-over: id -> MTPA's over blend_time; fallback:
 *     0 -> I cos(delta)) now move the torque by 3/2 n_P (Ld - Lq) id iq,
 *     which the speed loop (closed) or the I-f spring (fallback) takes up;
 *   - the q31 twin refuses a salient machine (MOTOR): it has no MTPA
 *     (mc_fw is f32).
 *
 * Tuning the observer: gamma from the critical speed (mc_fluxobs.h):
 *   gamma = 4 n_P omega_crit / psi_a_max^2 (the flux if non-salient),
 *   time scale 1 / (2 n_P omega_crit) at psi_a_max.
 * init requires handover_speed (1 - handover_hyst) > 2 omega_crit (the
 * closed loop never runs within a factor two of the critical speed unless
 * lowspeed_fallback is off, which the low-speed sweep uses on purpose).
 *
 * Errors (return of the fast step, bits MC_CTRL_SLS_ERR_*): observer
 * divergence, start-up not locked within if_lock_timeout_s, FOC error,
 * bad measurement. Any of them makes the drive fault (outputs off).
 *
 * Lives in firmware/app: includes kernels and the drive's interface only.
 * No heap, no globals; the caller allocates mc_ctrl_sls_t.
 */
#ifndef MC_CTRL_SENSORLESS_H
#define MC_CTRL_SENSORLESS_H

#include <stdbool.h>
#include <stdint.h>

#include "foc/mc_foc.h"
#include "fw/mc_fw.h"
#include "mc_drive.h"
#include "observer/mc_fluxobs.h"
#include "observer/mc_spdpll.h"
#include "pi/mc_pi.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MC_CTRL_SLS_ERR_NONE   0u
#define MC_CTRL_SLS_ERR_NULL   (1u << 0) /**< a required pointer is NULL */
#define MC_CTRL_SLS_ERR_MOTOR  (1u << 1) /**< R, L, flux or pole pairs invalid */
#define MC_CTRL_SLS_ERR_TIMING (1u << 2) /**< dt, speed_div, pwm delay (0..3) invalid */
#define MC_CTRL_SLS_ERR_OBSERVER \
    (1u << 3) /**< observer config rejected (see obs_err), or set_r_scale's scale */
#define MC_CTRL_SLS_ERR_PLL     (1u << 4) /**< PLL config rejected */
#define MC_CTRL_SLS_ERR_CURRENT (1u << 5) /**< current loop config rejected */
#define MC_CTRL_SLS_ERR_SPEED   (1u << 6) /**< speed PI gains / limits / slew invalid */
#define MC_CTRL_SLS_ERR_STARTUP \
    (1u << 7)                               /**< I-f parameters invalid, or handover too close
                                                    to the critical speed */
#define MC_CTRL_SLS_ERR_DIVERGED (1u << 8)  /**< run: observer residual out of tolerance */
#define MC_CTRL_SLS_ERR_NO_LOCK  (1u << 9)  /**< run: start-up did not lock in time */
#define MC_CTRL_SLS_ERR_FOC      (1u << 10) /**< run: the current loop refused a step */
#define MC_CTRL_SLS_ERR_MEAS     (1u << 11) /**< run: non-finite measurement */
#define MC_CTRL_SLS_ERR_REF      (1u << 12) /**< set_speed_ref: NaN/inf or beyond the limit */

typedef enum {
    MC_CTRL_SLS_ALIGN = 0,
    MC_CTRL_SLS_IF = 1,
    MC_CTRL_SLS_CLOSED = 2,
} mc_ctrl_sls_phase_t;

typedef struct {
    /* motor */
    float r_ohm;         /**< stator resistance [ohm] */
    float l_h;           /**< stator inductance [H]: Lq of a salient machine */
    float flux_wb;       /**< PM flux linkage (peak) [Wb] */
    uint32_t pole_pairs; /**< >= 1 */
    float ld_minus_lq_h; /**< Ld - Lq [H], finite, l_h + it > 0; 0: non-salient */
    bool law_mtpa;       /**< salient machine: the law sets id by MTPA (false: iq_ref
                                      is the current command, id 0, for a drive whose
                                      own MTPA shapes it: fw_enable) */
    /* timing */
    float dt_s;                 /**< fast step = PWM period [s] */
    uint32_t pwm_delay_periods; /**< periods between writing duties and their taking
                                      effect (1 on a drive that updates at the next
                                      period), 0..3 */
    uint32_t speed_div;         /**< speed loop every speed_div fast steps, >= 1 */
    /* inverter voltage error seen by the observer (0: no compensation) */
    float dead_time_s;   /**< dead time of a bridge leg [s], [0, dt/2) */
    float dead_band_a;   /**< current over which the dead-time error reverses
                                      (linear inside), >= 0 [A] */
    bool dead_comp_duty; /**< correct the duties instead: each leg's duty plus
                                      sat(i_x / dead_band) dead_time / dt, from the latest
                                      current sample, clamped to [0, 1]; the observer then
                                      takes the commanded voltage as applied. f32 only */
    /* observer */
    float omega_crit_m_rad_s; /**< critical speed of the flux observer [rad/s] (sets gamma) */
    float resid_tol;          /**< divergence monitor tolerance (see mc_fluxobs.h) */
    float resid_time_s;       /**< divergence monitor time [s] */
    float pll_bw_rad_s;       /**< PLL bandwidth [rad/s] */
    /* current loop */
    float cur_bw_rad_s;  /**< current-loop bandwidth: kp = L bw, ki = R bw */
    float v_limit_ratio; /**< fraction of the SVPWM circle used, (0, 1] */
    float vbus_max_v;    /**< largest DC bus [V] (static PI limit) */
    /* speed loop */
    float speed_kp_a_s_rad;  /**< speed PI kp [A / (rad/s)] */
    float speed_ki_a_rad;    /**< speed PI ki [A / rad] */
    float iq_max_a;          /**< torque limit as |iq| [A] */
    float speed_slew_rad_s2; /**< reference slew rate (mechanical) [rad/s^2] */
    float speed_max_rad_s;   /**< largest |reference| accepted [rad/s] */
    /* start-up */
    float if_current_a;         /**< I-f current magnitude [A] */
    float align_time_s;         /**< current ramp before the frequency ramp [s] */
    float if_accel_rad_s2;      /**< I-f frequency ramp (mechanical) [rad/s^2] */
    float handover_speed_rad_s; /**< IF -> CLOSED hand-over speed (mechanical) [rad/s] */
    float handover_hyst;        /**< back to IF below (1 - hyst) handover, [0, 0.9] */
    float lock_tol;             /**< |omega_pll - omega_if| <= lock_tol omega_if to hand over */
    float if_lock_timeout_s;    /**< give up (NO_LOCK) after this long at the hand-over speed */
    float blend_time_s;         /**< id (or I-f magnitude) ramp after a hand-over [s] */
    bool lowspeed_fallback;     /**< return to I-f at low speed (normal use: true) */
    bool if_damping;            /**< I-f active damping from the observer's speed (true:
                                      -speed_kp (omega_hat - omega_if) along the estimated
                                      q axis, at most if_current_a / 2) */
    bool ref_from_drive;        /**< the speed reference is the drive's shaped one
                                      (uses_speed_ref: mc_drive_set_speed_ref, the
                                      drive's ramp and controlled stop); false: the
                                      law's own (mc_ctrl_sls_set_speed_ref, slewed at
                                      speed_slew_rad_s2). f32 only */
    bool align_any_angle;       /**< start from any rotor angle (true: two holds a
                                      quarter turn apart, pi/4 and 3 pi/4 ahead of
                                      angle 0 in the command's direction (a rotor at
                                      rest near 0 is pulled forwards by both; from
                                      elsewhere the first hold may pull it either
                                      way), the observer restarted at
                                      the angle the flux path's circle fit gives;
                                      false: one hold, the observer from angle 0,
                                      which needs the rotor near 0: diverges from
                                      some other angles). f32 only: the q31 twin
                                      refuses it (STARTUP) */
} mc_ctrl_sls_cfg_t;

/** Telemetry of the last fast step. */
typedef struct {
    mc_ctrl_sls_phase_t phase;
    float theta_hat_e_rad;             /**< observer angle [rad] */
    float omega_hat_m_rad_s;           /**< PLL speed, mechanical [rad/s] */
    float theta_ctrl_e_rad;            /**< angle of the frame the current loop used [rad] */
    float omega_ref_m_rad_s;           /**< slewed speed reference [rad/s] */
    float omega_if_m_rad_s;            /**< I-f frame speed [rad/s] */
    float i_alpha_a, i_beta_a;         /**< currents fed to the observer [A] */
    float v_alpha_obs_v, v_beta_obs_v; /**< voltage fed to the observer [V] */
    float id_ref_a, iq_ref_a;          /**< current references in the control frame [A] */
    float id_a, iq_a;   /**< measured currents in the control frame [A] (the q31 twin,
                           which runs its own current loop; the f32 plug-in hands its
                           references to the drive's, whose tm.foc has them: 0 here) */
    float obs_resid;    /**< observer residual |e|/flux - 1 */
    uint32_t handovers; /**< number of IF -> CLOSED hand-overs */
    uint32_t fallbacks; /**< number of CLOSED -> IF returns */
} mc_ctrl_sls_tm_t;

typedef struct {
    mc_ctrl_sls_cfg_t cfg;
    float gamma;        /**< observer gain from omega_crit [1/(Wb^2 s)] at psi_a_max_wb */
    float psi_a_max_wb; /**< the largest active flux of the closed loop (the flux if
                             non-salient) [Wb] */
    mc_fw_f32_t mtpa;   /**< MTPA (fw/mc_fw.h, no weakening) */
    float id_mtpa_a;    /**< MTPA's d current for the speed PI's command [A] */
    mc_fluxobs_f32_t obs;
    mc_spdpll_f32_t pll;
    mc_pi_f32_t speed_pi;
    bool reframe; /**< a hand-over or fallback this step: out.reframe */
    mc_ctrl_sls_phase_t phase;
    float omega_cmd_m_rad_s; /**< requested speed [rad/s] */
    float omega_ref_m_rad_s; /**< slewed reference [rad/s] */
    float theta_if_e_rad;
    float omega_if_e_rad_s;
    float i_if_a;       /**< present I-f current magnitude [A] */
    float t_phase_s;    /**< time in the present phase [s] */
    float t_lockwait_s; /**< time spent at the hand-over speed waiting for lock */
    float id_ref_a, iq_ref_a;
    float dir;                      /**< +1 / -1: direction of the I-f ramp */
    bool align_dir_set;             /**< ALIGN (any angle): dir latched from the command */
    float v_hist_a[4], v_hist_b[4]; /**< applied alpha-beta voltage, newest first */
    float ia_prev_a, ib_prev_a;     /**< phase currents of the previous sample */
    uint32_t speed_count;
    uint32_t obs_err; /**< observer init error, if any */
    /* ALIGN: the flux integrated without the observer's correction, and
     * the sums of a circle fit (Kasa) of its path, in units of flux_wb
     * relative to the first point: the path is a circle of radius flux
     * about an unknown centre (the start angle's offset), whose centre
     * gives the rotor angle whatever the rotor's start and swing. */
    float al_x_a, al_x_b; /**< integrated flux [Wb] */
    float al_i_prev_a, al_i_prev_b;
    float al_p0_a, al_p0_b; /**< first point [flux units] */
    float al_u, al_v;       /**< last point, relative to the first */
    float al_n, al_su, al_sv, al_suu, al_svv, al_suv, al_sz, al_suz, al_svz;
    mc_ctrl_sls_tm_t tm;
    mc_drive_ctrl_t ops; /**< the drive's plug-in table, bound to this instance */
} mc_ctrl_sls_t;

/** Validate cfg and initialise. Returns MC_CTRL_SLS_ERR_* bits; on error c
 *  is not usable (and not partially trusted: init again). */
uint32_t mc_ctrl_sls_init(mc_ctrl_sls_t *c, const mc_ctrl_sls_cfg_t *cfg);

/** The plug-in table for mc_drive_attach_ctrl() (PWM3, no encoder needed). */
const mc_drive_ctrl_t *mc_ctrl_sls_ops(mc_ctrl_sls_t *c);

/** Set the speed reference [rad/s, mechanical]; slewed inside. Returns 0 or
 *  MC_CTRL_SLS_ERR_REF (NaN/inf, |ref| > speed_max_rad_s; previous kept). */
uint32_t mc_ctrl_sls_set_speed_ref(mc_ctrl_sls_t *c, float omega_m_rad_s);

/** Plug-in functions (also callable directly, e.g. from a test loop). */
uint32_t mc_ctrl_sls_reset(void *ctx);
/** The observer's R = cfg.r_ohm * r_scale (mc_fluxobs_f32_set_r_scale; the
 *  drive calls it from its slow step with the winding estimate's scale);
 *  kept across reset. MC_CTRL_SLS_ERR_OBSERVER for a scale the observer
 *  refuses (nothing changed). */
uint32_t mc_ctrl_sls_set_r_scale(void *ctx, float r_scale);
uint32_t mc_ctrl_sls_fast(void *ctx, const mc_drive_meas_t *m, mc_drive_out_t *out);

#ifdef __cplusplus
}
#endif

#endif /* MC_CTRL_SENSORLESS_H */
