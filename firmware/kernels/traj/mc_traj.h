/**
 * @file mc_traj.h
 * @brief Position trajectory generator, float32: a trapezoidal velocity
 *        profile with separate acceleration and deceleration limits, re-planned
 *        from the present state, and an input-filter mode for streamed
 *        setpoints (README.md in this folder has the formulas).
 *
 * Trapezoid (MC_TRAJ_MODE_TRAP). mc_traj_f32_plan() plans from a state
 * (x0, v0) to a target x_f with final velocity 0 as at most four segments of
 * constant acceleration, in the direction s of the move:
 *   0  brake:  v0 moves away from the target (or would overshoot it):
 *              |v| falls to 0 at d_max (only when needed)
 *   1  ramp:   v -> v_c at a_max (|v| rising) or at d_max (|v| falling,
 *              when |v0| > v_max)
 *   2  cruise: v = v_c, zero acceleration
 *   3  stop:   v_c -> 0 at d_max
 * v_c = v_max, or the peak of a triangle when the distance is too short to
 * reach v_max: v_p^2 = (2 a d D + d v_s^2) / (a + d). The evaluation at any
 * time t is exact (x_k + v_k tau + a_k tau^2 / 2 within segment k); at and
 * after the end it is the target itself, velocity 0.
 * mc_traj_f32_set_target() re-plans from the state the profile has at the
 * present step: position and velocity stay continuous, only the
 * acceleration changes (bounded by a_max and d_max, the limits of a
 * trapezoid).
 *
 * Input filter (MC_TRAJ_MODE_FILTER). mc_traj_f32_set_input() sets a raw
 * setpoint r; each step advances the critically damped second-order filter
 *   x'' = w^2 (r - x) - 2 w x'
 * exactly over one period with r held (zero-order hold), so streamed,
 * stair-stepped setpoints come out smooth with velocity and acceleration
 * for feed-forward; a ramp r = v t is followed with the lag 2 v / w.
 *
 * Positions are float radians in the caller's frame; keep them small (the
 * caller re-bases with mc_traj_f32_shift(), e.g. by whole turns) so that
 * float keeps its resolution. Time is a step count times dt_s, never a
 * clock.
 */
#ifndef MC_TRAJ_H
#define MC_TRAJ_H

#include <stdbool.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define MC_TRAJ_ERR_NONE   0u
#define MC_TRAJ_ERR_NULL   (1u << 0) /**< NULL pointer */
#define MC_TRAJ_ERR_LIMIT  (1u << 1) /**< v_max, a_max or d_max <= 0 or not finite */
#define MC_TRAJ_ERR_DT     (1u << 2) /**< dt_s <= 0 or not finite */
#define MC_TRAJ_ERR_FILTER (1u << 3) /**< filter_bw_rad_s < 0, not finite, or bw dt > 1 */
#define MC_TRAJ_ERR_INPUT  (1u << 4) /**< non-finite state, target or setpoint: refused */
#define MC_TRAJ_ERR_MODE   (1u << 5) /**< unknown mode, or the filter with filter_bw 0 */

typedef enum {
    MC_TRAJ_MODE_TRAP = 0,   /**< trapezoidal moves to targets */
    MC_TRAJ_MODE_FILTER = 1, /**< 2nd-order critically damped filter of streamed setpoints */
} mc_traj_mode_t;

typedef struct {
    float v_max_rad_s;     /**< cruise speed limit [rad/s], > 0 */
    float a_max_rad_s2;    /**< acceleration limit (|v| rising) [rad/s^2], > 0 */
    float d_max_rad_s2;    /**< deceleration limit (|v| falling) [rad/s^2], > 0 */
    float filter_bw_rad_s; /**< input filter's natural frequency w [rad/s], >= 0,
                                 w dt <= 1 (0: no filter mode) */
    float dt_s;            /**< step period [s], > 0 */
} mc_traj_f32_cfg_t;

/** Reference of one instant. */
typedef struct {
    float x_rad;    /**< position [rad] */
    float v_rad_s;  /**< velocity [rad/s] */
    float a_rad_s2; /**< acceleration [rad/s^2] */
    bool done;      /**< trapezoid: at the target, at rest */
} mc_traj_f32_out_t;

#define MC_TRAJ_SEGMENTS 4u

typedef struct {
    mc_traj_f32_cfg_t cfg;
    mc_traj_mode_t mode;
    /* trapezoid plan: segment k starts at t_s[k] in state (x_s[k], v_s[k])
     * and accelerates at a_s[k]; t_s[MC_TRAJ_SEGMENTS] is the end. */
    float t_s[MC_TRAJ_SEGMENTS + 1u];
    float x_s[MC_TRAJ_SEGMENTS];
    float v_s[MC_TRAJ_SEGMENTS];
    float a_s[MC_TRAJ_SEGMENTS];
    float x_target_rad;
    uint32_t k; /**< steps since the plan began */
    /* input filter: exact one-period transition (derived at init) */
    float f11, f12, f21, f22;
    float fx_rad, fv_rad_s, fr_rad;
    mc_traj_f32_out_t out; /**< the last output */
} mc_traj_f32_t;

/** Validate cfg; on success the generator rests at 0 in TRAP mode. */
uint32_t mc_traj_f32_init(mc_traj_f32_t *t, const mc_traj_f32_cfg_t *cfg);

/** Rest at x (both modes: plan of zero length, filter state (x, 0), input x). */
uint32_t mc_traj_f32_reset(mc_traj_f32_t *t, float x_rad);

/** Change the trapezoid's limits (validated as in init); takes effect at the next plan. */
uint32_t mc_traj_f32_set_limits(mc_traj_f32_t *t, float v_max_rad_s, float a_max_rad_s2,
                                float d_max_rad_s2);

/** Switch mode; the new mode starts from the present state (x, v). */
uint32_t mc_traj_f32_set_mode(mc_traj_f32_t *t, mc_traj_mode_t mode);

/** Plan a trapezoid from (x0, v0) at time 0 of the plan to x_target; TRAP mode. */
uint32_t mc_traj_f32_plan(mc_traj_f32_t *t, float x0_rad, float v0_rad_s, float x_target_rad);

/** Re-plan to a new target from the state at the present step (TRAP). */
uint32_t mc_traj_f32_set_target(mc_traj_f32_t *t, float x_target_rad);

/** Plan a stop at deceleration d (> 0) from the present state: the target is
 *  the stopping point x + v |v| / (2 d). d replaces d_max for this plan only. */
uint32_t mc_traj_f32_stop(mc_traj_f32_t *t, float d_rad_s2);

/** New raw setpoint of the input filter (FILTER mode). */
uint32_t mc_traj_f32_set_input(mc_traj_f32_t *t, float r_rad);

/** The output of the present step, then advance one period. */
uint32_t mc_traj_f32_step(mc_traj_f32_t *t, mc_traj_f32_out_t *out);

/** Exact trapezoid state at plan time t_s (no state change). */
void mc_traj_f32_eval(const mc_traj_f32_t *t, float t_s, mc_traj_f32_out_t *out);

/** Duration of the present plan [s] (0 at rest). */
float mc_traj_f32_get_duration_s(const mc_traj_f32_t *t);

/** Move the frame: every stored position minus dx_rad (e.g. whole turns). */
void mc_traj_f32_shift(mc_traj_f32_t *t, float dx_rad);

#ifdef __cplusplus
}
#endif

#endif /* MC_TRAJ_H */
