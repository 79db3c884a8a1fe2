/**
 * @file mc_ctrl_csmc_q31.h
 * @brief q31 twin of the CSMC stepper plug-in (mc_ctrl_csmc.h): the same
 *        loop with the q31 law (mc_csmc_q31, q31 conditional integrators)
 *        in it; state feedback (the q31 high-gain observer is not wired
 *        here: FB_HGO is refused with MC_CTRL_CSMC_ERR_FEEDBACK).
 *
 * Each step: dq transform of the winding currents and the model's errors
 * (mc_csmc_f32_err_from_state) in float, as the f32 plug-in forms them;
 * then per unit of the law's bases at the kernel boundary (round to nearest
 * even, saturated: as an ADC driver would hand them), the q31 law, and the
 * voltages back in volts for the inverse transform and the bridge. The
 * position error e2 enters in per unit of theta_base, rounded once by the
 * caller from what it has: the drive's fast op from phi - phi_d in float,
 * a SIL loop from its plant's exact angle (e2 ~ 1e-9 rad at rest, far below
 * a float angle's resolution).
 *
 * Errors: the f32 plug-in's MC_CTRL_CSMC_ERR_* bits.
 */
#ifndef MC_CTRL_CSMC_Q31_H
#define MC_CTRL_CSMC_Q31_H

#include <stdbool.h>
#include <stdint.h>

#include "csmc/mc_csmc_q31.h"
#include "math/mc_q31.h"
#include "mc_ctrl_csmc.h"
#include "mc_drive.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    mc_csmc_q31_cfg_t law;      /**< law.f.dt_s must be the drive's PWM period; the bases */
    mc_ctrl_csmc_fb_t feedback; /**< MC_CTRL_CSMC_FB_STATE only */
    float duty_max;             /**< |duty| limit of each bridge, (0, 1] */
} mc_ctrl_csmc_q31_cfg_t;

/** Measurements of one step (mc_ctrl_csmc_q31_step): as the f32 plug-in's,
 *  the position error per unit. */
typedef struct {
    float ia_a, ib_a;    /**< winding currents, phase A and B [A] */
    float theta_e_rad;   /**< electrical angle of the dq transform [rad] */
    float omega_m_rad_s; /**< shaft speed [rad/s] */
    float phi_rad;       /**< shaft angle [rad] */
    q31_t e2;            /**< position error phi - phi_d (theta_base) */
} mc_ctrl_csmc_q31_meas_t;

/** Telemetry of the last step. */
typedef struct {
    float phi_rad;         /**< shaft angle [rad] */
    float i_d_a, i_q_a;    /**< winding currents in the rotor frame [A] */
    mc_csmc_f32_in_t fin;  /**< the errors in engineering units (e2: not set, see in.e2) */
    mc_csmc_q31_in_t in;   /**< what the q31 law got (per unit) */
    mc_csmc_q31_out_t out; /**< v_d, v_q, s1, s2 (per unit) */
    float v_d_v, v_q_v;    /**< the law's voltages [V] */
    float v_a_v, v_b_v;    /**< winding voltages asked for [V] */
} mc_ctrl_csmc_q31_tm_t;

typedef struct {
    mc_ctrl_csmc_q31_cfg_t cfg;
    mc_csmc_q31_t law;
    mc_ctrl_csmc_ref_t ref;
    mc_ctrl_csmc_pos_t pos;
    mc_ctrl_csmc_q31_tm_t tm;
    mc_drive_ctrl_t ops;
} mc_ctrl_csmc_q31_t;

/** Validate cfg (the law: MC_CTRL_CSMC_ERR_LAW; feedback other than STATE
 *  or a model that cannot give e2'': _FEEDBACK; duty_max: _DUTY) and
 *  initialise; reference 0. On error c is not written. */
uint32_t mc_ctrl_csmc_q31_init(mc_ctrl_csmc_q31_t *c, const mc_ctrl_csmc_q31_cfg_t *cfg);

/** The plug-in table for mc_drive_attach_ctrl() (NULL for c == NULL). */
const mc_drive_ctrl_t *mc_ctrl_csmc_q31_ops(mc_ctrl_csmc_q31_t *c);

/** As mc_ctrl_csmc_set_ref. */
uint32_t mc_ctrl_csmc_q31_set_ref(mc_ctrl_csmc_q31_t *c, float phi_d_rad, float dphi_d_rad_s,
                                  float ddphi_d_rad_s2, float dddphi_d_rad_s3, float i_dd_a,
                                  float di_dd_a_s);

/** As mc_ctrl_csmc_step, with the q31 law; the result in c->tm. */
uint32_t mc_ctrl_csmc_q31_step(mc_ctrl_csmc_q31_t *c, const mc_ctrl_csmc_q31_meas_t *m);

#ifdef __cplusplus
}
#endif

#endif /* MC_CTRL_CSMC_Q31_H */
