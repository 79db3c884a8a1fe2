/**
 * @file mc_law_cfg.h
 * @brief The control laws' configurations from the motor's values: the
 *        sensorless law (flux observer + PLL, I-f start; paper 002), PI2D
 *        (paper 000) and the position cascade, built from the gains of
 *        mc_gains_derive. The one place their formulas live: the MCU images
 *        and the SIL's can-telemetry scenario build them from the parameter
 *        table (mc_law_cfg_from_params), and so does the simulator's drive
 *        application, booted from the motor and board files' table
 *        (sim/cli/app_params.hpp).
 *
 * SPEED-mode law (parameter speed_law, MC_LAW_SPEED_*): the sensored PI of
 * the application, the sensorless law, or PI2D. POSITION mode runs the
 * position cascade wherever the drive has an encoder.
 */
#ifndef MC_LAW_CFG_H
#define MC_LAW_CFG_H

#include <stdint.h>

#include "foc/mc_foc.h"
#include "mc_ctrl_align.h"
#include "mc_ctrl_pi2d.h"
#include "mc_ctrl_position.h"
#include "mc_ctrl_sensorless.h"
#include "mc_ctrl_speed.h"
#include "mc_drive_hallobs.h"
#include "mc_gains.h"
#include "mc_params.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Values of the speed_law parameter. */
#define MC_LAW_SPEED_PI         0u /**< sensored speed PI (encoder) */
#define MC_LAW_SPEED_SENSORLESS 1u /**< flux observer + PLL, I-f start (no encoder) */
#define MC_LAW_SPEED_PI2D       2u /**< output-feedback PI2D (encoder) */

/* Why a law is not available (the law_error parameter, readonly): the low
 * bits are mc_gains' MC_GAINS_ERR_* of its gains, these its init's. */
#define MC_LAW_ERR_SLS_INIT  (1u << 16) /**< mc_ctrl_sls_init refused the sensorless law */
#define MC_LAW_ERR_PI2D_INIT (1u << 17) /**< mc_ctrl_pi2d_init refused PI2D */
#define MC_LAW_ERR_POS_INIT  (1u << 18) /**< mc_ctrl_pos_init refused the position law */
#define MC_LAW_ERR_RUNNING   (1u << 19) /**< an APPLY would change a law while it runs */
#define MC_LAW_ERR_ENCODER \
    (1u << 20)                         /**< a sensored law (speed, PI2D, position) on a drive
                                              without an encoder */
#define MC_LAW_ERR_SPD_INIT (1u << 21) /**< mc_ctrl_speed_init refused the sensored speed law */

/** MC_GAINS_ERR_* bits that refuse the speed law `law` (the sensored PI:
 *  none; sensorless: the gains' refusals (a salient machine is run, see
 *  mc_ctrl_sensorless.h); PI2D: those, saliency and its own) of a parameter set: the pure part of the check, no instance. */
uint32_t mc_law_speed_check(const mc_params_t *p);

/** The sensorless law's configuration (mc_gains.h documents
 *  each value): speed loop at about 1 kHz, dead-time compensation in the
 *  duties, I-f current, ramp, hand-over and alignment from the gains. */
void mc_law_sls_cfg(const mc_gains_motor_t *m, const mc_gains_t *g, mc_ctrl_sls_cfg_t *c);

/** PI2D: triple pole wn, dirty-derivative pole a (b = 1), eps = 2 ki / kp,
 *  k1 = k2 = cur_bw. Returns 0 or MC_GAINS_ERR_PI2D_FILTER (a < 3 wn),
 *  MC_GAINS_ERR_PI2D_COUPLING, MC_GAINS_ERR_SALIENT; *c is written anyway. */
uint32_t mc_law_pi2d_cfg(const mc_gains_motor_t *m, const mc_gains_t *g, mc_ctrl_pi2d_cfg_t *c);

/** The position cascade on the drive's current loop: P gain, velocity PI
 *  (the sensored speed PI: speed_kp, speed_ki), trajectory limits, torque
 *  feed-forward lead 1/cur_bw + (delay + 0.5) T. */
void mc_law_pos_cfg(const mc_gains_motor_t *m, const mc_gains_t *g, mc_ctrl_pos_cfg_t *c);

/** The sensored speed law (mc_ctrl_speed.h): speed_kp, speed_ki at the PWM
 *  rate, the current limit, the torque feed-forward's kt, J, B. */
void mc_law_speed_cfg(const mc_gains_motor_t *m, const mc_gains_t *g, mc_ctrl_speed_cfg_t *c);

/* Why a law that finds the rotor angle is not available (law_error). */
#define MC_LAW_ERR_ALIGN_INIT (1u << 22) /**< mc_ctrl_align_init refused the alignment */
#define MC_LAW_ERR_IDX_INIT   (1u << 23) /**< mc_ctrl_idx_init refused the index search */

/** The laws that find the rotor angle after a power-up (ctrl/mc_ctrl_align.h:
 *  the alignment, angle_ref 2; the index search, angle_ref 1), from a
 *  parameter set, its gains and the drive's configuration dc (the current
 *  loop, the current limit, pole pairs), with p_enc the board's encoder
 *  (the index search reads its flags). With i the vector's magnitude and
 *  kt the torque per ampere:
 *    i          angle_find_current_a, or 0.5 i_rated (derived; the init
 *               refuses i above the current limit: law_error);
 *    damping    2 z sqrt(k J) / kt, z = 0.7, k = kt i p the vector's spring
 *               per rad mech. (N m/rad), J the rotor's inertia;
 *    alignment  sweep s = pi/2 el. at 20 rad/s el., ramps 50 ms, rest 100 ms
 *               within 4 encoder counts (at most 0.1 rad), a settle at most
 *               2 s, sweep tolerance 0.3 rad el., load tolerance 0.1 rad el.
 *               (about the offset error a load may leave: cos 0.1 = 0.995 of the
 *               torque), travel angle_find_travel_rad or 1.5 (pi + 3 s) / p;
 *    search     10 rad/s mech. (10 p el., at most 2000), forward first,
 *               travel each way angle_find_travel_rad or 1.25 turns (the
 *               index passes once per turn).
 *  The inits check the ranges (mc_ctrl_align.h). */
void mc_law_find_cfg(const mc_params_t *p, const mc_gains_motor_t *m, const mc_gains_t *g,
                     const mc_drive_cfg_t *dc, const mc_hal_encoder_t *p_enc,
                     mc_ctrl_align_cfg_t *al, mc_ctrl_idx_cfg_t *ix);

/** The Hall + observer hand-over of a parameter set (mc_drive_hallobs.h):
 *  start, end and disagree from hall_obs_*, the observer and its PLL as the
 *  sensorless law's (mc_law_sls_cfg: R, L = lq, flux, gamma from the
 *  critical speed, its monitor, the PLL bandwidth, the PWM delay; the PLL's
 *  clamp twice the speed limit). Returns MC_DRIVE_HALLOBS_ERR_* bits:
 *  NOT_HALL (encoder_type not 1), MOTOR (see there), and
 *  mc_drive_hallobs_init's refusals; 0: *c runs. */
uint32_t mc_law_hallobs_cfg(const mc_params_t *p, mc_drive_hallobs_cfg_t *c);

/** The motor and board values of a parameter set (one PWM period of
 *  computation delay, as the drive's fast loop writes the duties for the
 *  next period). */
void mc_law_motor_from_params(const mc_params_t *p, mc_gains_motor_t *m);

/** The gains of a parameter set: derived from its motor values
 *  (mc_gains_derive), every gain parameter that is not 0 taken as given
 *  (current_bw, speed_pll_bw, speed_bw, speed_kp/ki, speed_ramp, the
 *  observer's, the sensorless start's, PI2D's, the position loop's and the
 *  trajectory's, stop_decel). Returns mc_gains_derive's bits. */
uint32_t mc_law_gains_from_params(const mc_params_t *p, mc_gains_motor_t *m, mc_gains_t *g);

#ifdef __cplusplus
}
#endif

#endif /* MC_LAW_CFG_H */
