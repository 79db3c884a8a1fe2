/**
 * @file mc_ctrl_speed.h
 * @brief The sensored speed law: a PI (the mc_pi kernel) on the drive's
 *        encoder speed with the torque feed-forward of the drive's shaped
 *        reference, handing the q current to the drive's current loop
 *        (mc_drive_attach_ctrl, MC_DRIVE_MODE_CTRL, MC_DRIVE_OUT_CURRENT).
 *
 * Each fast step (the PWM rate, the rate of the drive's encoder tracking
 * loop that measures the speed):
 *
 *   iq = PI(omega_ref - omega_m) + (J alpha_ref + B omega_ref) / kt,
 *   |iq| <= the drive's current limit in force (mc_drive_meas_t.i_max_a),
 *
 * clamping anti-windup against the limit actually applied (mc_pi_f32_step_lim:
 * a limit lowered at run time saturates the output and stops the integrator
 * there); while the drive's regenerative limit scales a braking reference
 * (mc_drive_meas_t.regen_scale < 1) the integrator first tracks the current
 * that was applied (mc_pi_f32_track), so the loop does not wind up against
 * a full bus. id = 0: MTPA and field weakening, when on, are the drive's
 * (the q current is then its signed current command).
 *
 * The reference is the drive's (uses_speed_ref): set with
 * mc_drive_set_speed_ref, slewed at the speed ramp by the drive, ramped to
 * zero by the drive's controlled stop; the law never sees a step.
 *
 * Gains (firmware/app/config/mc_gains.c): kp = J wc / kt, ki = kp wc / 4
 * (the PI's zero a quarter of the crossover wc), unless set.
 */
#ifndef MC_CTRL_SPEED_H
#define MC_CTRL_SPEED_H

#include <stdbool.h>
#include <stdint.h>

#include "mc_drive.h"
#include "pi/mc_pi.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MC_CTRL_SPEED_ERR_NONE  0u
#define MC_CTRL_SPEED_ERR_NULL  (1u << 0) /**< NULL pointer */
#define MC_CTRL_SPEED_ERR_GAIN  (1u << 1) /**< kp, ki negative or not finite; dt <= 0 */
#define MC_CTRL_SPEED_ERR_MODEL (1u << 2) /**< kt <= 0, J or B < 0, pole_pairs 0, iq_max <= 0 */
#define MC_CTRL_SPEED_ERR_MEAS  (1u << 3) /**< a step without the encoder or the drive's reference */
#define MC_CTRL_SPEED_ERR_STEP  (1u << 4) /**< the PI refused its step (non-finite input) */

typedef struct {
    float kp_a_s_rad;    /**< proportional gain [A/(rad/s)] */
    float ki_a_rad;      /**< integral gain [A/rad] */
    float dt_s;          /**< the fast step (PWM period) [s] */
    float iq_max_a;      /**< static clamp of the output and the integrator [A] (the
                              drive's current limit at configuration; a lower limit
                              in force comes with each step) */
    float kt_nm_a;       /**< torque constant of the feed-forward [N m/A] */
    float j_kgm2;        /**< inertia of the feed-forward [kg m^2], >= 0 */
    float b_nm_s_rad;    /**< viscous friction of the feed-forward [N m s/rad], >= 0 */
    uint32_t pole_pairs; /**< for the frame's electrical speed, >= 1 */
    float ref_lag_s;     /**< the lag between the feed-forward's current and the measured
                              speed's answer to it (current loop, speed measurement,
                              computation delay) [s], >= 0: the PI compares the measured
                              speed with the reference passed through that lag, so a
                              ramp the feed-forward follows leaves it no error to wind
                              up on; 0: the reference as it is */
} mc_ctrl_speed_cfg_t;

/** Telemetry of the last fast step. */
typedef struct {
    float omega_ref_rad_s;  /**< the drive's reference [rad/s] */
    float alpha_ref_rad_s2; /**< its acceleration [rad/s^2] */
    float iq_ff_a;          /**< the feed-forward [A] */
    float iq_ref_a;         /**< the law's q current [A] */
    uint32_t saturated;     /**< steps whose output was at the current limit */
    uint32_t tracked;       /**< steps the integrator tracked the regen limit */
} mc_ctrl_speed_tm_t;

typedef struct {
    mc_ctrl_speed_cfg_t cfg;
    mc_pi_f32_t pi;
    mc_ctrl_speed_tm_t tm;
    mc_drive_ctrl_t ops;
    float ref_lag_alpha;       /**< dt / (ref_lag_s + dt) */
    float omega_ref_lag_rad_s; /**< the reference through the lag [rad/s] */
    bool have_ref_lag;         /**< omega_ref_lag_rad_s holds a value (not after a reset) */
} mc_ctrl_speed_t;

/** Validate cfg and initialise c and its ops table (current references,
 *  needs the encoder, the drive's speed reference). Returns
 *  MC_CTRL_SPEED_ERR_* bits; on error c is not usable. */
uint32_t mc_ctrl_speed_init(mc_ctrl_speed_t *c, const mc_ctrl_speed_cfg_t *cfg);

/** The ops table to attach: mc_drive_attach_ctrl(d, mc_ctrl_speed_ops(c)). */
const mc_drive_ctrl_t *mc_ctrl_speed_ops(mc_ctrl_speed_t *c);

/** Plug-in functions (also callable directly). */
uint32_t mc_ctrl_speed_reset(void *ctx);
uint32_t mc_ctrl_speed_fast(void *ctx, const mc_drive_meas_t *m, mc_drive_out_t *out);

#ifdef __cplusplus
}
#endif

#endif /* MC_CTRL_SPEED_H */
