/**
 * @file mc_hallobs.h
 * @brief Hand-over from the Hall sensors' angle to the flux observer's
 *        above a speed, and back (float32): "Hall + observer".
 *
 * The rule (VESC's foc_correct_hall, motor/foc_math.c at bldc b9d287b:
 * the Hall angle below foc_sl_erpm_start, the observer's above
 * foc_sl_erpm, weight_hall mapped linearly between them on the observer
 * PLL's |speed|): with w = clamp((|omega| - omega_start) / (omega_end -
 * omega_start), 0, 1),
 *     theta = theta_hall + w wrap(theta_obs - theta_hall)
 * so the angle is continuous through the hand-over in both directions (no
 * hysteresis is needed: nothing switches). omega is the observer's speed
 * (its PLL, kernels/observer/mc_spdpll.h), as VESC takes it.
 *
 * Added here: the Hall sensors are a check on the observer. While the
 * observer carries weight (w > 0), |wrap(theta_obs - theta_hall)| above
 * disagree_max_e_rad raises MC_HALLOBS_ERR_DISAGREE (sticky) and the step
 * returns the Hall angle (an observer that lost its angle, a Hall table
 * that does not match the motor). Choose disagree_max above the Hall
 * angle's error (the table's error plus the interpolation's, below 30
 * degrees with a measured table) and below 90 degrees (no torque).
 */
#ifndef MC_HALLOBS_H
#define MC_HALLOBS_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define MC_HALLOBS_ERR_NONE     0u
#define MC_HALLOBS_ERR_NULL     (1u << 0) /**< a required pointer is NULL */
#define MC_HALLOBS_ERR_CFG      (1u << 1) /**< not 0 < start < end, disagree_max not in (0, pi/2] */
#define MC_HALLOBS_ERR_DISAGREE (1u << 2) /**< observer and Hall angles too far apart */
#define MC_HALLOBS_ERR_NAN      (1u << 3) /**< a non-finite input: the Hall angle is returned */

typedef struct {
    float
        omega_start_e_rad_s;  /**< the Hall angle alone at or below this |speed| [rad/s el.], > 0 */
    float omega_end_e_rad_s;  /**< the observer's alone at or above this one, > start */
    float disagree_max_e_rad; /**< largest |observer - Hall| while the observer is used [rad el.] */
} mc_hallobs_f32_cfg_t;

typedef struct {
    mc_hallobs_f32_cfg_t cfg;
    float inv_span; /**< derived: 1 / (end - start) */
    float w_obs;    /**< the observer's weight in the last step, [0, 1] */
    uint32_t flags; /**< sticky MC_HALLOBS_ERR_* */
} mc_hallobs_f32_t;

uint32_t mc_hallobs_f32_init(mc_hallobs_f32_t *st, const mc_hallobs_f32_cfg_t *cfg);
uint32_t mc_hallobs_f32_reset(mc_hallobs_f32_t *st);

/**
 * The angle to use [rad el., [0, 2 pi)] in *p_theta_e_rad.
 * @return MC_HALLOBS_ERR_DISAGREE or _NAN raised by this step (the Hall
 *         angle is returned then), MC_HALLOBS_ERR_NULL (nothing written).
 */
uint32_t mc_hallobs_f32_step(mc_hallobs_f32_t *st, float theta_hall_e_rad, float theta_obs_e_rad,
                             float omega_e_rad_s, float *p_theta_e_rad);

#ifdef __cplusplus
}
#endif

#endif /* MC_HALLOBS_H */
