/**
 * @file mc_law_cfg.h
 * @brief The control laws' configurations from the motor's values: the
 *        sensorless law (flux observer + PLL, I-f start; paper 002), PI2D
 *        (paper 000) and the position cascade, built from the gains of
 *        mc_gains_derive. The one place their formulas live: the MCU images
 *        and the SIL's can-telemetry scenario build them from the parameter
 *        table (mc_law_cfg_from_params), the simulator's motor scenarios
 *        from the motor and board files (sim/cli/drive_setup.cpp).
 *
 * SPEED-mode law (parameter speed_law, MC_LAW_SPEED_*): the sensored PI of
 * the application, the sensorless law, or PI2D. POSITION mode runs the
 * position cascade wherever the drive has an encoder.
 */
#ifndef MC_LAW_CFG_H
#define MC_LAW_CFG_H

#include <stdint.h>

#include "foc/mc_foc.h"
#include "mc_ctrl_pi2d.h"
#include "mc_ctrl_position.h"
#include "mc_ctrl_sensorless.h"
#include "mc_ctrl_speed.h"
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
 *  none; sensorless: the gains' refusals and saliency; PI2D: those and its
 *  own) of a parameter set: the pure part of the check, no instance. */
uint32_t mc_law_speed_check(const mc_params_t *p);

/** The sensorless law's configuration (sim/cli/drive_setup.hpp documents
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
