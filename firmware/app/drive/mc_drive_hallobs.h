/**
 * @file mc_drive_hallobs.h
 * @brief Hall + observer in the drive: the flux observer and its PLL run
 *        beside the Hall angle while the drive's current loop drives the
 *        bridge, and the angle the laws use is the hand-over's blend
 *        (firmware/kernels/hall/mc_hallobs.h; issue 32 item 6).
 *
 * A board with encoder_type 1 (Hall) and hall_obs_end_e_rad_s > 0 gets this
 * (mc_app binds it with mc_drive_attach_hallobs); without it the drive's
 * fast step pays one pointer test. Each fast step in which the current loop
 * drives the bridge (CURRENT, the drive's stop, a law giving current
 * references) the drive calls mc_drive_hallobs_step with the step's phase
 * currents, the alpha-beta voltage its loop commanded in the last step and
 * the Hall angle (the encoder's electrical angle), and uses the angle
 * returned in place of the Hall angle (every sensored law reads it:
 * mc_drive_meas_t.theta_e_rad, the CURRENT mode's frame, the stop's):
 *   - the first such step after the bridge came on starts the observer at
 *     the Hall angle (its flux vector there, the PLL at the Hall speed): the
 *     estimate starts where the rotor is, at any speed; for
 *     MC_DRIVE_HALLOBS_SETTLE_T of its time scales after a (re)start it
 *     carries no weight (the Hall angle is used, nothing is compared);
 *   - the observer takes the voltage that acted over the last period (the
 *     loop's command pwm_delay_periods steps back, as the sensorless law;
 *     the drive's duty-side dead-time correction makes it the applied one);
 *   - below omega_start (on the PLL's |speed|) the weight is 0 and an
 *     observer more than disagree_max away from the Hall angle is restarted
 *     at the Hall angle (below its critical speed it may wander: that is
 *     not a fault, its angle is not used there);
 *   - from omega_start to omega_end the weight ramps to 1 (mc_hallobs):
 *     the angle is continuous through the hand-over both ways;
 *   - while the observer carries weight, |observer - Hall| above
 *     disagree_max (a wrong flux linkage or R, an observer that lost the
 *     angle, a Hall table off by a sector) is MC_HALLOBS_ERR_DISAGREE: the
 *     step returns the Hall angle and the drive keeps the Hall angle alone
 *     until the bridge is next enabled (fallback latched: no chatter
 *     between the two angles); the cause is kept (sticky since boot) in
 *     flags and reported in the parameter hall_error as
 *     MC_DRIVE_HALL_ERR_OBS_DISAGREE. It is not a fault: the drive runs on
 *     the Hall sensors, as it does without the hand-over (VESC's choice).
 */
#ifndef MC_DRIVE_HALLOBS_H
#define MC_DRIVE_HALLOBS_H

#include <stdbool.h>
#include <stdint.h>

#include "hall/mc_hallobs.h"
#include "observer/mc_fluxobs.h"
#include "observer/mc_spdpll.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MC_DRIVE_HALLOBS_ERR_NONE     0u
#define MC_DRIVE_HALLOBS_ERR_NULL     (1u << 0) /**< a required pointer is NULL */
#define MC_DRIVE_HALLOBS_ERR_BLEND    (1u << 1) /**< not 0 < start < end, disagree not in (0, pi/2] */
#define MC_DRIVE_HALLOBS_ERR_OBSERVER (1u << 2) /**< the flux observer refuses R, L, flux, gamma */
#define MC_DRIVE_HALLOBS_ERR_PLL      (1u << 3) /**< the PLL refuses its bandwidth or limit */
#define MC_DRIVE_HALLOBS_ERR_TIMING   (1u << 4) /**< dt not > 0 or pwm_delay_periods above 3 */
/* From a parameter set (mc_law_hallobs_cfg, config/mc_law_cfg.h): */
#define MC_DRIVE_HALLOBS_ERR_NOT_HALL (1u << 5) /**< encoder_type is not 1 (Hall) */
#define MC_DRIVE_HALLOBS_ERR_MOTOR \
    (1u << 6) /**< the observer's motor values, as the sensorless law needs them: no safe
                   gains, R < 0, L or flux not > 0, or a salient machine (ld, lq 5 % apart) */

/** A restarted observer carries no weight for this many of its time scales
 *  (2 / (gamma flux^2), mc_fluxobs.h): started at the Hall angle, up to 30
 *  degrees el. off with a measured table, its angle error decays over a few
 *  of them, and would meanwhile read as a disagreement. */
#define MC_DRIVE_HALLOBS_SETTLE_T 4.0f

/** The bit the parameter hall_error carries for a DISAGREE (above the Hall
 *  kernel's MC_HALL_ERR_* bits). */
#define MC_DRIVE_HALL_ERR_OBS_DISAGREE (1u << 8)
/** ... and for an observer state that was not finite (MC_HALLOBS_ERR_NAN:
 *  the same fallback). */
#define MC_DRIVE_HALL_ERR_OBS_NAN (1u << 9)

typedef struct {
    mc_hallobs_f32_cfg_t blend; /**< omega_start, omega_end, disagree_max [el.] */
    float r_ohm;                /**< the observer's motor: R [ohm], L [H], flux [Wb] */
    float l_h;
    float flux_wb;
    float gamma;     /**< observer gain [1/(Wb^2 s)] (the sensorless law's) */
    float resid_tol; /**< the observer's divergence monitor (mc_fluxobs.h) */
    float resid_time_s;
    float pll_bw_rad_s;         /**< the observer's PLL bandwidth [rad/s] */
    float omega_max_e_rad_s;    /**< the PLL's clamp [rad/s el.] */
    float dt_s;                 /**< fast step [s] */
    uint32_t pwm_delay_periods; /**< steps from the command to the voltage, 0..3 */
} mc_drive_hallobs_cfg_t;

typedef struct {
    mc_drive_hallobs_cfg_t cfg;
    mc_fluxobs_f32_t obs;
    mc_spdpll_f32_t pll;
    mc_hallobs_f32_t blend;
    float v_hist_a[4], v_hist_b[4]; /**< commanded alpha-beta voltage, newest first [V] */
    uint32_t settle_steps;          /**< derived: MC_DRIVE_HALLOBS_SETTLE_T observer time
                                         scales in fast steps */
    uint32_t settle_left;           /**< steps until a restarted observer may carry weight */
    bool running;                   /**< the observer runs since the bridge came on */
    bool fallback;                  /**< DISAGREE since then: the Hall angle alone */
    uint32_t flags;                 /**< sticky MC_HALLOBS_ERR_DISAGREE | _NAN since boot */
    float theta_obs_e_rad;          /**< telemetry: the observer's angle [rad] */
    float omega_obs_e_rad_s;        /**< its PLL's speed [rad/s el.] */
    float w_obs;                    /**< the observer's weight of the last step, [0, 1] */
} mc_drive_hallobs_t;

/** The step's inputs. */
typedef struct {
    float ia_a, ib_a;                    /**< phase currents of the step [A] */
    float v_alpha_prev_v, v_beta_prev_v; /**< the loop's command of the last step [V] */
    float theta_hall_e_rad;              /**< the Hall (encoder) electrical angle [rad] */
    float omega_hall_e_rad_s;            /**< its tracking loop's speed [rad/s el.] */
} mc_drive_hallobs_in_t;

/** Validate cfg (MC_DRIVE_HALLOBS_ERR_* bits) and initialise h (stopped);
 *  on error h is not changed. */
uint32_t mc_drive_hallobs_init(mc_drive_hallobs_t *h, const mc_drive_hallobs_cfg_t *cfg);

/** The bridge is not driven by the current loop this step: the next step
 *  starts the observer at the Hall angle and clears the fallback. */
void mc_drive_hallobs_stop(mc_drive_hallobs_t *h);

/** One fast step: the angle the drive uses [rad, [0, 2 pi)]. */
float mc_drive_hallobs_step(mc_drive_hallobs_t *h, const mc_drive_hallobs_in_t *in);

/** The observer's R = cfg.r_ohm r_scale (the winding estimate, as the
 *  sensorless law's); MC_DRIVE_HALLOBS_ERR_OBSERVER when refused. */
uint32_t mc_drive_hallobs_set_r_scale(mc_drive_hallobs_t *h, float r_scale);

#ifdef __cplusplus
}
#endif

#endif /* MC_DRIVE_HALLOBS_H */
