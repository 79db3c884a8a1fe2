/**
 * @file mc_spdpll.h
 * @brief Speed estimator from an angle (paper 002, Section V (iii)): a
 *        type-2 phase-locked loop, float32.
 *
 * Continuous law of the paper (theta_hat the measured or estimated angle):
 *     z1' = kp (theta_hat - z1) + ki z2
 *     z2' = theta_hat - z1
 *     omega_hat = kp (theta_hat - z1) + ki z2
 * From theta_hat to z1 this is (kp s + ki) / (s^2 + kp s + ki): a ramp in
 * theta_hat (constant speed) is tracked with zero steady error. The kernel
 * is parameterised by one bandwidth bw [rad/s]: both poles at -bw,
 *     kp = 2 bw [1/s],  ki = bw^2 [1/s^2].
 * The speed estimate omega_hat (output of the loop, not a derivative of
 * theta_hat) sees an angle step through (kp s + ki) s / (s^2 + kp s + ki).
 *
 * Departures from the printed law, on purpose:
 * - angles live on the circle: the error theta_hat - z1 is wrapped to
 *   [-pi, pi) and z1 is kept in [-pi, pi), so the loop runs forever at any
 *   speed (the paper's z1 grows without bound);
 * - the integral part is stored as a speed w_i = ki z2 [rad/s] and clamped,
 *   like the output, to [-omega_max, omega_max] (every integrator clamped);
 * - discretisation (backward Euler on the integral, forward on z1):
 *     e    = wrap(theta_hat[k] - z1[k])
 *     w_i += ki dt e                       (clamped)
 *     omega_hat[k] = kp e + w_i            (clamped)
 *     z1[k+1] = wrap(z1[k] + dt omega_hat[k])
 *   init requires bw dt <= 0.1 so this matches the continuous loop to a few
 *   per cent (tests/unit/observer compares with it).
 *
 * Angle and speed are in the same frame as the input (electrical for the
 * flux observer's angle). Non-finite input: refused, sticky
 * MC_SPDPLL_ERR_NAN_INPUT. No heap, no globals, no I/O.
 */
#ifndef MC_SPDPLL_H
#define MC_SPDPLL_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define MC_SPDPLL_ERR_NONE      0u
#define MC_SPDPLL_ERR_NULL      (1u << 0) /**< a required pointer is NULL */
#define MC_SPDPLL_ERR_BW        (1u << 1) /**< bw <= 0, not finite, or bw dt > 0.1 */
#define MC_SPDPLL_ERR_DT        (1u << 2) /**< dt_s <= 0 or not finite */
#define MC_SPDPLL_ERR_LIMIT     (1u << 3) /**< omega_max <= 0 or not finite */
#define MC_SPDPLL_ERR_NAN_INPUT (1u << 4) /**< sticky: non-finite input refused */
#define MC_SPDPLL_ERR_SAT       (1u << 5) /**< sticky: the speed reached +-omega_max */

/** Largest bw dt accepted. */
#define MC_SPDPLL_MAX_BW_DT 0.1f

typedef struct {
    float bw_rad_s;        /**< loop bandwidth (double pole at -bw) [rad/s], > 0 */
    float dt_s;            /**< step period [s], > 0, bw dt <= 0.1 */
    float omega_max_rad_s; /**< clamp of the integral and of the output [rad/s], > 0 */
} mc_spdpll_f32_cfg_t;

typedef struct {
    float kp_per_s;    /**< 2 bw (derived) */
    float ki_dt_per_s; /**< bw^2 dt (derived) [1/s] */
    float dt_s;
    float omega_max_rad_s;
    float theta_rad;     /**< z1: tracked angle, [-pi, pi); after a step it is the
                                prediction for the next sample (theta + omega dt) */
    float omega_i_rad_s; /**< integral part ki z2 [rad/s] */
    float omega_rad_s;   /**< last speed estimate [rad/s] */
    uint32_t flags;      /**< sticky MC_SPDPLL_ERR_* */
} mc_spdpll_f32_t;

/** Validate cfg and initialise (angle 0, speed 0). On error st is not written. */
uint32_t mc_spdpll_f32_init(mc_spdpll_f32_t *st, const mc_spdpll_f32_cfg_t *cfg);

/** Restart at (theta, omega) (omega clamped): the next step with a
 *  consistent angle continues without a transient. Flags cleared.
 *  Non-finite: MC_SPDPLL_ERR_NAN_INPUT, nothing changed. */
uint32_t mc_spdpll_f32_reset(mc_spdpll_f32_t *st, float theta_rad, float omega_rad_s);

/** One step with the new angle: the speed estimate [rad/s] in
 *  *p_omega_rad_s (the last one if the input was refused). Returns the bits
 *  raised by this step: MC_SPDPLL_ERR_NONE, MC_SPDPLL_ERR_SAT (the integral
 *  or the speed reached +-omega_max and was clamped), MC_SPDPLL_ERR_NAN_INPUT
 *  (theta_in not finite: refused, state unchanged), both also made sticky in
 *  st->flags; or MC_SPDPLL_ERR_NULL (st or p_omega_rad_s NULL: nothing
 *  written). */
uint32_t mc_spdpll_f32_step(mc_spdpll_f32_t *st, float theta_in_rad, float *p_omega_rad_s);

#ifdef __cplusplus
}
#endif

#endif /* MC_SPDPLL_H */
