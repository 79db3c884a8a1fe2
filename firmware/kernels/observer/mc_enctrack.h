/**
 * @file mc_enctrack.h
 * @brief Encoder tracking loop: angle, speed and acceleration from a
 *        quantised angle, float32 (a type-3 tracking loop).
 *
 * Why not the count difference: one period of counts quantises the speed to
 * 2 pi / (cpr dt) (15 rad/s at 8192 counts and 20 kHz). Why type 3: a type-2
 * loop (mc_spdpll.h) lags by 2 a / bw under a constant acceleration a; this
 * one follows constant acceleration with no steady-state speed error, so the
 * current loop's back-EMF feed-forward stays right while the rotor speeds up.
 *
 * States: angle estimate theta, speed omega, acceleration alpha.
 * Characteristic polynomial (s + bw)^3, i.e. gains k1 = 3 bw, k2 = 3 bw^2,
 * k3 = bw^3, discretised by forward Euler:
 *     predicted  = wrap_2pi(theta[k] + dt omega[k])
 *     e          = wrap_pi(theta_meas[k] - predicted)
 *     theta[k+1] = wrap_2pi(predicted + k1 dt e)
 *     omega[k+1] = omega[k] + dt alpha[k] + k2 dt e
 *     alpha[k+1] = alpha[k] + k3 dt e
 * The three poles stay near z = 1 - bw dt, well inside the unit circle, for
 * 3 bw dt <= 1 (init refuses more). The first step after init or reset takes
 * the measured angle as the estimate, with zero speed and acceleration.
 *
 * Angles in [0, 2 pi) in the frame of the input (mechanical in the drive);
 * the loop runs forever at any speed (angles live on the circle).
 * Non-finite input: refused, nothing changes, sticky MC_ENCTRACK_ERR_NAN_INPUT.
 * No heap, no globals, no I/O.
 */
#ifndef MC_ENCTRACK_H
#define MC_ENCTRACK_H

#include <stdbool.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define MC_ENCTRACK_ERR_NONE      0u
#define MC_ENCTRACK_ERR_NULL      (1u << 0) /**< a required pointer is NULL */
#define MC_ENCTRACK_ERR_BW        (1u << 1) /**< bw <= 0, not finite, or 3 bw dt > 1 */
#define MC_ENCTRACK_ERR_DT        (1u << 2) /**< dt_s <= 0 or not finite */
#define MC_ENCTRACK_ERR_NAN_INPUT (1u << 3) /**< sticky: non-finite input refused */

typedef struct {
    float bw_rad_s; /**< bandwidth (triple pole at -bw) [rad/s], > 0, 3 bw dt <= 1 */
    float dt_s;     /**< step period [s], > 0 */
} mc_enctrack_f32_cfg_t;

typedef struct {
    mc_enctrack_f32_cfg_t cfg;
    float k1_dt;        /**< 3 bw dt, derived at init */
    float k2_dt;        /**< 3 bw^2 dt [rad/s per rad], derived at init */
    float k3_dt;        /**< bw^3 dt [rad/s^2 per rad], derived at init */
    float theta_rad;    /**< angle estimate, [0, 2 pi) */
    float omega_rad_s;  /**< speed estimate [rad/s] */
    float alpha_rad_s2; /**< acceleration estimate [rad/s^2] */
    bool primed;        /**< a first angle has been taken */
    uint32_t err;       /**< sticky MC_ENCTRACK_ERR_* */
} mc_enctrack_f32_t;

/** Validate cfg, derive the gains, reset. On error st is left untouched. */
uint32_t mc_enctrack_f32_init(mc_enctrack_f32_t *st, const mc_enctrack_f32_cfg_t *cfg);

/** Forget the estimate: the next step takes its angle as is. */
uint32_t mc_enctrack_f32_reset(mc_enctrack_f32_t *st);

/** One step with the measured angle theta_meas_rad in [0, 2 pi). */
uint32_t mc_enctrack_f32_step(mc_enctrack_f32_t *st, float theta_meas_rad);

#ifdef __cplusplus
}
#endif

#endif /* MC_ENCTRACK_H */
