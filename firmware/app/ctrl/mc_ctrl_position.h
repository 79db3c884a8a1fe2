/**
 * @file mc_ctrl_position.h
 * @brief Position control of a PMSM on its encoder, as a control law for the
 *        drive's CTRL mode (mc_drive_attach_ctrl): trajectory -> position P
 *        -> velocity PI -> the q current reference of the drive's current
 *        loop (MC_DRIVE_OUT_CURRENT).
 *
 * Each fast step (the PWM rate):
 *   1. multi-turn position: the encoder count is unwrapped into whole turns
 *      (int32) plus the count within the turn; a step of more than half a
 *      turn per period is taken the short way round. Position and reference
 *      are kept relative to a base turn that follows the reference (re-based
 *      at every new target), so float carries only the distance of one move
 *      and never loses resolution however far the rotor has turned. The
 *      position counts from the encoder angle at enable (turn 0).
 *   2. reference: the trajectory generator (kernels/traj): a trapezoid to
 *      each target (v, a, d limits; a new target while moving re-plans from
 *      the present reference, velocity continuous), or, in the input-filter
 *      mode, a critically damped second-order filter of streamed setpoints.
 *   3. position loop:  v_cmd = v_ref + kp_pos (x_ref - x), |v_cmd| <= vel_limit
 *   4. velocity loop:  iq = PI(v_cmd - omega) + (J a_ref(t + lead) + B v_ref) / kt,
 *      |iq| <= the lower of iq_max and the drive's current limit in force
 *      (clamping anti-windup against it; the integrator tracks what the
 *      drive's regenerative limit applied); omega is the drive's encoder
 *      tracking-loop speed (mc_drive_meas_t.omega_m_rad_s).
 *   5. current loop:   the drive's (id = 0 at the encoder's electrical
 *      angle: field weakening, the regen limit and the FOC step there).
 *
 * Setpoints (mc_ctrl_pos_set_target*, set_input_mode, set_limits) may be
 * called from a lower-priority context: they are latched and taken by the
 * next fast step (one writer; a 32-bit sequence number publishes them).
 *
 * Controlled stop: the drive's stop op (mc_drive_ctrl_t.stop) re-plans a
 * stop at the given deceleration from the present reference; the position
 * loop then holds the stopping point.
 */
#ifndef MC_CTRL_POSITION_H
#define MC_CTRL_POSITION_H

#include <stdbool.h>
#include <stdint.h>

#include "foc/mc_foc.h"
#include "mc_drive.h"
#include "pi/mc_pi.h"
#include "traj/mc_traj.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MC_CTRL_POS_ERR_NONE 0u
#define MC_CTRL_POS_ERR_NULL (1u << 0) /**< NULL pointer */
#define MC_CTRL_POS_ERR_FOC  (1u << 1) /**< (unused: the current loop is the drive's) */
#define MC_CTRL_POS_ERR_TRAJ (1u << 2) /**< trajectory config rejected, or a setpoint refused */
#define MC_CTRL_POS_ERR_GAIN \
    (1u << 3) /**< a loop gain negative / not finite, kp_pos dt > 1,
                                             ff_lead_s outside [0, 0.1] */
#define MC_CTRL_POS_ERR_LIMIT \
    (1u << 4)                          /**< vel_limit or iq_max <= 0, not finite; kt <= 0;
                                             J or B < 0 */
#define MC_CTRL_POS_ERR_MEAS (1u << 5) /**< fast step without encoder, cpr 0 or bad vbus */
#define MC_CTRL_POS_ERR_REF  (1u << 6) /**< non-finite setpoint or limit: refused */

typedef struct {
    float dt_s;                /**< the fast step (PWM period) [s] */
    uint32_t pole_pairs;       /**< for the electrical speed of the decoupling, >= 1 */
    mc_traj_f32_cfg_t traj;    /**< trajectory limits and input filter; traj.dt_s = dt_s */
    float pos_kp_per_s;        /**< position P gain [(rad/s)/rad], kp dt <= 1 */
    float vel_kp_a_s_rad;      /**< velocity PI proportional gain [A/(rad/s)] */
    float vel_ki_a_rad;        /**< velocity PI integral gain [A/rad] */
    float vel_limit_rad_s;     /**< bound of the velocity command [rad/s] */
    float iq_max_a;            /**< q current limit [A] */
    float kt_nm_a;             /**< torque constant for the feed-forward [N m/A] */
    float j_kgm2;              /**< inertia for the torque feed-forward [kg m^2], >= 0 */
    float ff_lead_s;           /**< the torque feed-forward takes the trajectory's
                                         acceleration this far ahead [s], [0, 0.1]: about the
                                         current loop's lag 1/bw plus the PWM delay */
    float b_nm_s_rad;          /**< viscous friction for the feed-forward [N m s/rad], >= 0 */
    mc_traj_mode_t input_mode; /**< setpoints from init on: MC_TRAJ_MODE_TRAP (a trapezoid
                                    to each target) or MC_TRAJ_MODE_FILTER (streamed
                                    setpoints through the input filter: traj.filter_bw_rad_s
                                    > 0); mc_ctrl_pos_set_input_mode changes it later */
} mc_ctrl_pos_cfg_t;

/** Telemetry of the last fast step. */
typedef struct {
    int32_t turns;          /**< whole turns of the measured position */
    uint32_t count;         /**< count within the turn, 0 .. cpr - 1 */
    float theta_m_rad;      /**< measured multi-turn position [rad] (float: for display) */
    float theta_ref_rad;    /**< multi-turn reference [rad] */
    float pos_err_rad;      /**< theta_ref - theta_m, exact (relative frame) [rad] */
    float omega_ref_rad_s;  /**< trajectory velocity [rad/s] */
    float alpha_ref_rad_s2; /**< trajectory acceleration [rad/s^2] */
    float omega_cmd_rad_s;  /**< velocity command after the position loop [rad/s] */
    float iq_ref_a;         /**< velocity-loop output [A] */
    bool done;              /**< trajectory finished (reference at rest on the target) */
} mc_ctrl_pos_tm_t;

typedef struct {
    mc_ctrl_pos_cfg_t cfg;
    mc_pi_f32_t vel_pi;
    mc_traj_f32_t traj;
    /* multi-turn bookkeeping */
    bool have_prev;
    uint32_t count_prev;
    int32_t turns;
    int32_t base_turns; /**< the frame of the trajectory: base_turns * 2 pi */
    /* latched setpoints (written by the setters, taken by the fast step) */
    uint32_t req_seq, ack_seq;
    int32_t req_turns;
    float req_rad;
    mc_traj_mode_t req_mode;
    float req_v, req_a, req_d;
    uint32_t lim_seq, lim_ack;
    uint32_t mode_seq, mode_ack;
    mc_ctrl_pos_tm_t tm;
    mc_drive_ctrl_t ops;
} mc_ctrl_pos_t;

/** Validate cfg and initialise c and its ops table (current references,
 *  needs the encoder). */
uint32_t mc_ctrl_pos_init(mc_ctrl_pos_t *c, const mc_ctrl_pos_cfg_t *cfg);

/** The ops table to attach: mc_drive_attach_ctrl(d, mc_ctrl_pos_ops(c)). */
const mc_drive_ctrl_t *mc_ctrl_pos_ops(mc_ctrl_pos_t *c);

/** Target as whole turns plus an angle [rad] (any float; exact for large
 *  turn counts). TRAP mode: a trapezoid (re-planned if moving); FILTER mode:
 *  the filter's new input. */
uint32_t mc_ctrl_pos_set_target(mc_ctrl_pos_t *c, int32_t turns, float rad);

/** Target as one multi-turn angle [rad] (float: resolution 6e-8 |x|). */
uint32_t mc_ctrl_pos_set_target_rad(mc_ctrl_pos_t *c, float theta_rad);

/** Trapezoid (MC_TRAJ_MODE_TRAP) or input filter (MC_TRAJ_MODE_FILTER). */
uint32_t mc_ctrl_pos_set_input_mode(mc_ctrl_pos_t *c, mc_traj_mode_t mode);

/** New trapezoid limits, from the next plan on. */
uint32_t mc_ctrl_pos_set_limits(mc_ctrl_pos_t *c, float v_max_rad_s, float a_max_rad_s2,
                                float d_max_rad_s2);

#ifdef __cplusplus
}
#endif

#endif /* MC_CTRL_POSITION_H */
