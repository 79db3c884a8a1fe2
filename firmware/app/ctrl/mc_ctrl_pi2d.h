/**
 * @file mc_ctrl_pi2d.h
 * @brief The PI^2D output-feedback speed controller (firmware/kernels/pi2d)
 *        as a control law for the drive's CTRL mode (mc_drive_attach_ctrl).
 *
 * Each fast step: phase currents -> Clarke -> Park at the encoder's
 * electrical angle -> PI^2D (position only: the encoder speed of
 * mc_drive_meas_t is NOT used) -> inverse Park -> SVPWM -> 3-phase duties.
 *
 * Position bookkeeping: the law needs the unwrapped position error
 * e4 = theta_m - theta_ref. The plug-in keeps the measured position and the
 * integrated reference with a common origin (the encoder's wrapped steps are
 * unwrapped with the shortest-way difference, valid below half a turn per
 * period), and subtracts whole turns from both when the reference leaves
 * [0, 2 pi): both stay small, so float keeps its resolution however long it
 * runs; only the difference enters the law.
 *
 * Reference: mc_ctrl_pi2d_set_ref() sets the speed, acceleration and jerk
 * (mechanical) in force from the next fast step on; the plug-in integrates
 * the position reference exactly for a constant acceleration over a period:
 * theta_ref += omega dt + alpha dt^2/2, omega += alpha dt between calls.
 * With cfg.ref_from_drive the drive's shaped reference (mc_drive_meas_t)
 * replaces it each step. The clamp of the q current the law asks for is
 * the lower of its own and the drive's current limit in force
 * (mc_drive_meas_t.i_max_a: a limit lowered at run time applies at once).
 *
 * Telemetry (mc_ctrl_pi2d_t.tm): the law's signals of the last fast step,
 * for the drive's telemetry and the CAN stream.
 */
#ifndef MC_CTRL_PI2D_H
#define MC_CTRL_PI2D_H

#include <stdbool.h>
#include <stdint.h>

#include "mc_drive.h"
#include "pi2d/mc_pi2d.h"
#include "transforms/mc_svpwm.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MC_CTRL_PI2D_ERR_NONE  0u
#define MC_CTRL_PI2D_ERR_NULL  (1u << 0) /**< NULL pointer */
#define MC_CTRL_PI2D_ERR_LAW   (1u << 1) /**< the PI2D config was rejected (see law_err) */
#define MC_CTRL_PI2D_ERR_LIMIT (1u << 2) /**< unknown modulator limit mode */
#define MC_CTRL_PI2D_ERR_REF   (1u << 3) /**< non-finite reference */
#define MC_CTRL_PI2D_ERR_MEAS  (1u << 4) /**< fast step without encoder or with bad vbus */
#define MC_CTRL_PI2D_ERR_STEP  (1u << 5) /**< the law refused its step (non-finite input) */
#define MC_CTRL_PI2D_ERR_ADVANCE \
    (1u << 6) /**< angle_advance_periods not finite or outside [0, 4] */

typedef struct {
    mc_pi2d_f32_cfg_t law;       /**< plant, gains, limits; law.dt_s = PWM period */
    mc_svpwm_limit_t limit_mode; /**< modulator limit */
    /** Delay compensation of the output frame, in PWM periods: the inverse
     *  Park uses theta_e + angle_advance_periods * p * omega_ref * dt. The
     *  voltage computed from the sample at t_k acts over
     *  [t_k + d dt, t_k + (d + 1) dt] (d: the board's computation delay), when
     *  the rotor has turned (d + 0.5) omega_e dt on average: d + 0.5 cancels
     *  that rotation. Without it, the lag turns part of the back-EMF
     *  feed-forward into the d axis; the law's d loop is proportional only
     *  (L k1 - R), so on a low-inductance motor at speed this leaves a
     *  large steady i_d (measured on the D5065 in tests/sil/motors). The
     *  speed is the reference's (the law is position-only). 0: off (the
     *  paper's law as printed). [0, 4]. */
    float angle_advance_periods;
    /** The speed reference is the drive's shaped one (uses_speed_ref:
     *  mc_drive_set_speed_ref, the drive's ramp and controlled stop; its
     *  acceleration is the law's feed-forward, jerk 0); false: the law's own
     *  (mc_ctrl_pi2d_set_ref). */
    bool ref_from_drive;
} mc_ctrl_pi2d_cfg_t;

/** Telemetry of the last fast step. */
typedef struct {
    float id_a, iq_a;         /**< measured dq currents [A] */
    float id_ref_a, iq_ref_a; /**< x1*, x2* [A] */
    float vd_v, vq_v;         /**< law output [V] (before the modulator) */
    float omega_ref_rad_s;    /**< x3* [rad/s] */
    float e4_rad;             /**< position error [rad] */
    float theta_f_rad;        /**< dirty derivative of e4 [rad] */
    float nu_nm;              /**< load-torque estimate [N m] */
    uint32_t svpwm_flags;     /**< MC_SVPWM_FLAG_* of the step */
} mc_ctrl_pi2d_tm_t;

typedef struct {
    mc_ctrl_pi2d_cfg_t cfg;
    mc_pi2d_f32_t law;
    uint32_t law_err; /**< last error bits of the law (init or step) */
    float omega_ref_rad_s, alpha_ref_rad_s2, jerk_ref_rad_s3, id_ref_a;
    float theta_ref_rad;    /**< integrated reference, [0, 2 pi) (common origin) */
    float theta_rel_rad;    /**< unwrapped measured position (common origin) */
    float theta_m_prev_rad; /**< last encoder angle [0, 2 pi) */
    bool have_prev;
    mc_ctrl_pi2d_tm_t tm;
    mc_drive_ctrl_t ops; /**< the table handed to mc_drive_attach_ctrl */
} mc_ctrl_pi2d_t;

/** Validate cfg, initialise c and its ops table (outputs PWM3, needs the
 *  encoder). References 0. On error c is not written. */
uint32_t mc_ctrl_pi2d_init(mc_ctrl_pi2d_t *c, const mc_ctrl_pi2d_cfg_t *cfg);

/** The ops table to attach: mc_drive_attach_ctrl(d, mc_ctrl_pi2d_ops(c)). */
const mc_drive_ctrl_t *mc_ctrl_pi2d_ops(mc_ctrl_pi2d_t *c);

/** Set the speed reference and its derivatives (mechanical) and the d-axis
 *  current reference. Non-finite: MC_CTRL_PI2D_ERR_REF, nothing changes. */
uint32_t mc_ctrl_pi2d_set_ref(mc_ctrl_pi2d_t *c, float omega_ref_rad_s, float alpha_ref_rad_s2,
                              float jerk_ref_rad_s3, float id_ref_a);

#ifdef __cplusplus
}
#endif

#endif /* MC_CTRL_PI2D_H */
