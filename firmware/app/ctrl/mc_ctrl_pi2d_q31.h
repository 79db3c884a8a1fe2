/**
 * @file mc_ctrl_pi2d_q31.h
 * @brief q31 twin of the PI^2D control law plug-in (mc_ctrl_pi2d.h): the
 *        same structure, with the q31 kernels in the loop: Clarke, Park at
 *        the encoder's electrical angle (mc_sincos_q31), the law
 *        (mc_pi2d_q31), inverse Park and SVPWM (mc_svpwm_q31).
 *
 * Config: the q31 law's config (mc_pi2d_q31_cfg_t: the f32 law's config,
 * validated as mc_pi2d_f32_init does, plus one base value per signal),
 * the modulator limit, and the fast-step period in double for the position
 * bookkeeping (see below).
 *
 * Per-unit boundary: the drive hands float measurements; each is
 * converted once to q31 of its base (round to nearest even, saturated to
 * the q31 range) as an ADC driver would; the duties come back as
 * duty_pu / 2^31. The fast step between the boundaries is integer only.
 *
 * Position bookkeeping as the f32 plug-in (common origin of the measured
 * and the reference position, whole turns moved off both when the
 * reference leaves [0, 2 pi)), kept in double and rounded once to q31 of
 * theta_base: float would hold a position in [0, 2 pi) only to 4.8e-7 rad,
 * coarser than the q31 LSB of an 8 rad base (3.7e-9 rad). On the M4F
 * these few additions are software double; an MCU without double
 * support would keep them in q31 of a turn. The encoder step is taken the
 * short way (remainder to (-pi, pi], exact, no libm), valid below half a
 * turn per period; the encoder angle must be in [0, 2 pi] as the drive
 * gives it.
 *
 * Telemetry (mc_ctrl_pi2d_q31_tm_t) in per unit of the config's bases;
 * the caller converts what it logs (q * base / 2^31).
 *
 * Errors: the f32 plug-in's MC_CTRL_PI2D_ERR_* bits. A non-finite
 * measurement or reference is refused (nothing changes).
 */
#ifndef MC_CTRL_PI2D_Q31_H
#define MC_CTRL_PI2D_Q31_H

#include <stdbool.h>
#include <stdint.h>

#include "math/mc_q31.h"
#include "mc_ctrl_pi2d.h"
#include "mc_drive.h"
#include "pi2d/mc_pi2d_q31.h"
#include "transforms/mc_svpwm.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    mc_pi2d_q31_cfg_t law;       /**< law.f.dt_s = PWM period (float), bases */
    mc_svpwm_limit_t limit_mode; /**< modulator limit */
    double dt_s;                 /**< the PWM period in double, for the reference integration of the
                      position bookkeeping; law.f.dt_s must be its float rounding */
} mc_ctrl_pi2d_q31_cfg_t;

/** Telemetry of the last fast step (per unit of law.base). */
typedef struct {
    q31_t id, iq;         /**< measured dq currents (i_base) */
    q31_t id_ref, iq_ref; /**< x1*, x2* (i_base) */
    q31_t vd, vq;         /**< law output (v_base) */
    q31_t omega_ref;      /**< x3* (omega_base) */
    q31_t e4;             /**< position error (theta_base) */
    q31_t theta_f;        /**< dirty derivative of e4 (thetaf_base) */
    q31_t nu;             /**< load-torque estimate (nu_base) */
    uint32_t svpwm_flags; /**< MC_SVPWM_FLAG_* of the step */
} mc_ctrl_pi2d_q31_tm_t;

typedef struct {
    mc_ctrl_pi2d_q31_cfg_t cfg;
    mc_pi2d_q31_t law;
    uint32_t law_err; /**< last error bits of the law (init, reset or step) */
    double omega_ref_rad_s, alpha_ref_rad_s2, jerk_ref_rad_s3, id_ref_a;
    double theta_ref_rad;    /**< integrated reference, [0, 2 pi) (common origin) */
    double theta_rel_rad;    /**< unwrapped measured position (common origin) */
    double theta_m_prev_rad; /**< last encoder angle */
    bool have_prev;
    mc_ctrl_pi2d_q31_tm_t tm;
    mc_drive_ctrl_t ops; /**< the table handed to mc_drive_attach_ctrl */
} mc_ctrl_pi2d_q31_t;

/** q31 only: dt_s not finite or <= 0, or law.f.dt_s not its float rounding. */
#define MC_CTRL_PI2D_ERR_PERIOD (1u << 7)

/** Validate cfg (the law: MC_CTRL_PI2D_ERR_LAW; the limit mode: _LIMIT;
 *  dt_s: _PERIOD), initialise c and its ops table (outputs PWM3, needs the
 *  encoder). References 0. On error c is not written. */
uint32_t mc_ctrl_pi2d_q31_init(mc_ctrl_pi2d_q31_t *c, const mc_ctrl_pi2d_q31_cfg_t *cfg);

/** The ops table to attach: mc_drive_attach_ctrl(d, mc_ctrl_pi2d_q31_ops(c)). */
const mc_drive_ctrl_t *mc_ctrl_pi2d_q31_ops(mc_ctrl_pi2d_q31_t *c);

/** Set the speed reference and its derivatives (mechanical) and the d-axis
 *  current reference, as mc_ctrl_pi2d_set_ref. Non-finite:
 *  MC_CTRL_PI2D_ERR_REF, nothing changes. */
uint32_t mc_ctrl_pi2d_q31_set_ref(mc_ctrl_pi2d_q31_t *c, float omega_ref_rad_s,
                                  float alpha_ref_rad_s2, float jerk_ref_rad_s3, float id_ref_a);

#ifdef __cplusplus
}
#endif

#endif /* MC_CTRL_PI2D_Q31_H */
