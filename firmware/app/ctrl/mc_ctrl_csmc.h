/**
 * @file mc_ctrl_csmc.h
 * @brief Stepper position control by CSMC with conditional integrators /
 *        servocompensators (paper 001) as a drive plug-in (MC_DRIVE_MODE_CTRL)
 *        on the dual H-bridge (MC_DRIVE_OUT_PWM2).
 *
 * Each fast step (from the drive, mc_drive_meas_t):
 *   position   phi: unwrapped from the encoder counts since the law's reset
 *              (exact integer count, so many turns lose nothing), starting at
 *              the encoder's theta_m at the first step after reset, wrapped
 *              to [-pi, pi) (a rotor resting just below 0 is at -0.0..., not
 *              at 2 pi);
 *   dq         i_d, i_q of the winding currents (ia = phase A, ib = phase B)
 *              at the electrical angle the drive gives, theta_e = N_r phi +
 *              offset: configure the drive with pole_pairs = N_r and the
 *              offset that puts the d axis on phase A at theta_e = 0;
 *   errors     e1 = i_d - I_dd, e2 = phi - phi_d;
 *              STATE feedback: e2' = w - phi_d' (w: the drive's encoder
 *              tracking loop), e2'' = k3 i_q - k4 w - d0 - phi_d'' (model);
 *              HGO feedback: e2', e2'' from the high-gain observer on e2;
 *   law        STATE: mc_csmc_f32_step (eq. (5) or (7)/(11), sat or sgn);
 *              HGO: mc_csmc_hgo_f32_step, observer and law in one step on
 *              the measured e1, e2 (the estimates it used in tm.in);
 *   bridge     (v_a, v_b) = inverse dq at theta_e; duty = v / vbus, clamped
 *              to [-duty_max, duty_max] (the conditional integrator needs no
 *              other anti-windup: sigma stays O(mu) outside the layer).
 * Errors (non-zero return of fast(), the drive then faults with
 * MC_DRIVE_FAULT_CONTROL): no encoder, vbus <= 0, the law or observer
 * refusing a non-finite input.
 */
#ifndef MC_CTRL_CSMC_H
#define MC_CTRL_CSMC_H

#include <stdbool.h>
#include <stdint.h>

#include "csmc/mc_csmc.h"
#include "observer/mc_hgo.h"
#include "mc_drive.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MC_CTRL_CSMC_ERR_NONE     0u
#define MC_CTRL_CSMC_ERR_NULL     (1u << 0) /**< a required pointer is NULL */
#define MC_CTRL_CSMC_ERR_LAW      (1u << 1) /**< law config rejected (mc_csmc_f32_init tells why) */
#define MC_CTRL_CSMC_ERR_HGO      (1u << 2) /**< observer config rejected (mc_hgo_f32_init tells why) */
#define MC_CTRL_CSMC_ERR_FEEDBACK (1u << 3) /**< unknown feedback, or STATE without a valid model */
#define MC_CTRL_CSMC_ERR_DUTY     (1u << 4) /**< duty_max not in (0, 1] */
#define MC_CTRL_CSMC_ERR_REF      (1u << 5) /**< set_ref: a value not finite */
#define MC_CTRL_CSMC_ERR_ENCODER  (1u << 6) /**< fast: no encoder reading */
#define MC_CTRL_CSMC_ERR_VBUS     (1u << 7) /**< fast: vbus <= 0 or not finite */
#define MC_CTRL_CSMC_ERR_STEP     (1u << 8) /**< fast: the law or observer refused an input */

typedef enum {
    MC_CTRL_CSMC_FB_STATE = 0, /**< e2' from the encoder speed, e2'' from the model and i_q */
    MC_CTRL_CSMC_FB_HGO = 1    /**< e2', e2'' from the high-gain observer (output feedback) */
} mc_ctrl_csmc_fb_t;

typedef struct {
    mc_csmc_f32_cfg_t law; /**< law.dt_s must be the drive's PWM period */
    mc_ctrl_csmc_fb_t feedback;
    mc_hgo_f32_cfg_t hgo; /**< FB_HGO only; hgo.dt_s = law.dt_s */
    float duty_max;       /**< |duty| limit of each bridge, (0, 1] */
} mc_ctrl_csmc_cfg_t;

/** The reference of a CSMC plug-in, f32 and q31 alike (see mc_ctrl_csmc_set_ref). */
typedef struct {
    float phi_d_rad, dphi_d_rad_s, ddphi_d_rad_s2, dddphi_d_rad_s3, i_dd_a, di_dd_a_s;
} mc_ctrl_csmc_ref_t;

/** The shaft angle unwrapped from the encoder counts (f32 and q31 plug-ins). */
typedef struct {
    bool have_pos;
    uint32_t last_count;
    int32_t pos_counts; /**< counts moved since the first step after reset */
    float phi0_rad;     /**< encoder angle at the first step after reset, [-pi, pi) */
} mc_ctrl_csmc_pos_t;

/** Telemetry of the last fast step. */
typedef struct {
    float phi_rad;         /**< unwrapped shaft angle [rad] */
    float i_d_a, i_q_a;    /**< winding currents in the rotor frame [A] */
    mc_csmc_f32_in_t in;   /**< errors handed to the law */
    mc_csmc_f32_out_t out; /**< v_d, v_q, s1, s2 */
    float v_a_v, v_b_v;    /**< winding voltages asked for [V] */
    mc_hgo_f32_est_t est;  /**< FB_HGO: the observer's estimates this step used (else 0) */
} mc_ctrl_csmc_tm_t;

/** The measurements of one step in the law's frame (mc_ctrl_csmc_step). The
 *  drive's fast op forms them from mc_drive_meas_t: phi from the encoder
 *  counts, e2 = phi - phi_d in float; a loop without the drive (the paper
 *  scenarios, sim/cli/scenarios/csmc_loop) forms them from its plant, e2
 *  at the precision it has. */
typedef struct {
    float ia_a, ib_a;    /**< winding currents, phase A and B [A] */
    float theta_e_rad;   /**< electrical angle of the dq transform, N_r phi + offset [rad] */
    float omega_m_rad_s; /**< shaft speed (STATE feedback) [rad/s] */
    float phi_rad;       /**< shaft angle (STATE: the model's e2) [rad] */
    float e2_rad;        /**< position error phi - phi_d handed to the law [rad] */
} mc_ctrl_csmc_meas_t;

typedef struct {
    mc_ctrl_csmc_cfg_t cfg;
    mc_csmc_hgo_f32_t ctl; /**< the law (ctl.law) and, for FB_HGO, the observer */
    mc_ctrl_csmc_ref_t ref;
    mc_ctrl_csmc_pos_t pos;
    mc_ctrl_csmc_tm_t tm;
    mc_drive_ctrl_t ops;
} mc_ctrl_csmc_t;

/** Validate cfg, initialise the kernels; reference 0. On error c is not written. */
uint32_t mc_ctrl_csmc_init(mc_ctrl_csmc_t *c, const mc_ctrl_csmc_cfg_t *cfg);

/**
 * One step of the loop on measurements in the law's frame: dq transform,
 * errors (STATE: from the model; HGO: from the observer), law, inverse
 * transform; the result in c->tm (v_a_v, v_b_v: the winding voltages to
 * apply). The drive's fast op is this step between the encoder and the
 * bridge. Returns MC_CTRL_CSMC_ERR_STEP when the law or observer refuses an
 * input (their state unchanged), _NULL for a NULL pointer.
 */
uint32_t mc_ctrl_csmc_step(mc_ctrl_csmc_t *c, const mc_ctrl_csmc_meas_t *m);

/** The plug-in table for mc_drive_attach_ctrl() (NULL for c == NULL). */
const mc_drive_ctrl_t *mc_ctrl_csmc_ops(mc_ctrl_csmc_t *c);

/**
 * Position reference phi_d (unwrapped shaft angle [rad]: the encoder's
 * angle, in [-pi, pi) at the first step after CTRL is entered, then
 * counted on over turns) and its derivatives, d-axis current
 * reference I_dd and its derivative. The derivatives are used by the STATE
 * feedback and law MODEL only (zero for set points). Non-finite:
 * MC_CTRL_CSMC_ERR_REF, nothing changes.
 */
uint32_t mc_ctrl_csmc_set_ref(mc_ctrl_csmc_t *c, float phi_d_rad, float dphi_d_rad_s,
                              float ddphi_d_rad_s2, float dddphi_d_rad_s3, float i_dd_a,
                              float di_dd_a_s);

/** The validation and store of mc_ctrl_csmc_set_ref on a reference struct
 *  (shared with the q31 twin). */
uint32_t mc_ctrl_csmc_set_ref_in(mc_ctrl_csmc_ref_t *r, float phi_d_rad, float dphi_d_rad_s,
                                 float ddphi_d_rad_s2, float dddphi_d_rad_s3, float i_dd_a,
                                 float di_dd_a_s);

/** The shaft angle [rad] of this fast step from the encoder counts (exact
 *  integer count, the shortest way between steps): the encoder's angle
 *  wrapped to [-pi, pi) at the first step after reset (p->have_pos false),
 *  then counted on. m->enc_cpr must be > 0. Shared with the q31 twin. */
float mc_ctrl_csmc_step_pos(mc_ctrl_csmc_pos_t *p, const mc_drive_meas_t *m);

#ifdef __cplusplus
}
#endif

#endif /* MC_CTRL_CSMC_H */
