/**
 * @file mc_pi.h
 * @brief PI controller with output limits and anti-windup: float32 kernel
 *        (mc_pi_f32_*); its fixed-point twin (mc_pi_q31_*) is in mc_pi_q31.h.
 *
 * Discrete law (backward-Euler integral, the integrator already contains the
 * current error; the output is valid in the same step):
 *
 *     p[k]   = kp * e[k]
 *     I[k]   = I[k-1] + ki * dt * e[k]          (subject to anti-windup)
 *     u[k]   = sat(p[k] + I[k] + ff[k], lo, hi)
 *
 * With a constant error e from a zero integrator and no saturation the output
 * is u[k] = kp*e + ki*dt*e*(k+1), k = 0, 1, ...
 *
 * The integrator I is stored in output units and is always clamped to the
 * configured output limits [out_min, out_max].
 *
 * Anti-windup schemes (mc_pi_aw_t):
 * - MC_PI_AW_CLAMP: conditional integration. The increment ki*dt*e is taken
 *   whole when the unsaturated output stays inside [lo, hi]. When it would
 *   push the output beyond a limit in the direction of the error, the
 *   integrator only moves up to the point where the output reaches the limit
 *   (never backwards); an error that pulls the output back into range is
 *   always integrated. The integrator therefore never stores more than the
 *   output can use, and the output leaves saturation as soon as the error
 *   changes sign.
 * - MC_PI_AW_BACK_CALC: back-calculation. The integrator receives
 *   ki*dt*e + kaw*dt*(u_sat - u_unsat); kaw (1/s) sets how fast the excess is
 *   bled off; init requires 0 < kaw*dt <= 1 (a larger step over-corrects).
 * - MC_PI_AW_NONE: no anti-windup, only the integrator clamp to the output
 *   limits (kept as a baseline for tests and comparisons).
 *
 * Dynamic limits: mc_pi_f32_step_lim() lets the caller narrow the limits for
 * one step (e.g. the FOC current loop's voltage circle); the anti-windup
 * then works against the limit actually applied. The integrator clamp stays
 * the static [out_min, out_max].
 *
 * Return convention (as every kernel's init/reset/step, kernels/README.md):
 * a step returns the MC_PI_ERR_* bits raised by that call (MC_PI_ERR_NONE =
 * 0 when it ran) and writes its output to *p_out.
 *
 * Non-finite input (float kernel): a step whose error, feed-forward or limits
 * are NaN or infinite is refused: the state is not changed, *p_out is the
 * last output, MC_PI_ERR_NAN_INPUT is returned and made sticky in st->flags.
 * Only mc_pi_f32_reset() clears the sticky flags.
 *
 * Bumpless gain change: mc_pi_f32_set_gains() moves the integrator by
 * (kp_old - kp_new) * e_last so that kp*e_last + I is unchanged: the output
 * with the new gains and the last error equals the last output (before the
 * next step's own integral increment).
 *
 * No heap, no globals, no I/O. All functions are re-entrant on distinct
 * state objects.
 */
#ifndef MC_PI_H
#define MC_PI_H

#include <stdint.h>

#include "math/mc_q31.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Error bits (init / set_gains / reset return them; st->flags keeps the sticky ones). */
#define MC_PI_ERR_NONE 0u
#define MC_PI_ERR_NULL (1u << 0) /**< a required pointer is NULL */
#define MC_PI_ERR_KP \
    (1u << 1) /**< kp negative or not finite (q31: mantissa < 0 or shift out of range) */
#define MC_PI_ERR_KI \
    (1u << 2) /**< ki negative or not finite (q31: mantissa < 0 or shift out of range) */
#define MC_PI_ERR_DT        (1u << 3) /**< dt_s <= 0 or not finite */
#define MC_PI_ERR_LIMITS    (1u << 4) /**< out_min > out_max, or a limit not finite */
#define MC_PI_ERR_AW_MODE   (1u << 5) /**< unknown anti-windup scheme */
#define MC_PI_ERR_KAW       (1u << 6) /**< back-calculation: kaw <= 0, not finite, or kaw*dt > 1 */
#define MC_PI_ERR_NAN_INPUT (1u << 7) /**< sticky: a step got a non-finite input and was refused */
#define MC_PI_ERR_SCALE \
    (1u << 8) /**< q31 from f32: base value <= 0 / not finite, or gain beyond the q31 range */
#define MC_PI_ERR_DYN_LIMIT \
    (1u << 9) /**< sticky: a step got dynamic limits lo > hi and was refused */

/** Anti-windup scheme. */
typedef enum {
    MC_PI_AW_CLAMP = 0,     /**< conditional integration (clamping) */
    MC_PI_AW_BACK_CALC = 1, /**< back-calculation with gain kaw_per_s */
    MC_PI_AW_NONE = 2       /**< integrator clamp only (baseline) */
} mc_pi_aw_t;

/**
 * Float PI configuration. Units are those of the loop: "out" is the output
 * unit (e.g. V), "err" the error unit (e.g. A).
 */
typedef struct {
    float kp;        /**< proportional gain [out/err], >= 0 */
    float ki_per_s;  /**< integral gain [out/(err*s)], >= 0 */
    float dt_s;      /**< sample period [s], > 0 */
    float out_min;   /**< lower output limit [out] */
    float out_max;   /**< upper output limit [out], >= out_min */
    mc_pi_aw_t aw;   /**< anti-windup scheme */
    float kaw_per_s; /**< back-calculation gain [1/s]; only read for MC_PI_AW_BACK_CALC */
} mc_pi_f32_cfg_t;

/** Float PI state. Read-only for callers except through the functions below. */
typedef struct {
    float kp;       /**< current proportional gain [out/err] */
    float ki_per_s; /**< current integral gain [out/(err*s)] */
    float ki_dt;    /**< ki_per_s * dt_s (derived) */
    float kaw_dt;   /**< kaw_per_s * dt_s (derived; 0 unless back-calculation) */
    float dt_s;     /**< sample period [s] */
    float out_min;  /**< static output / integrator limits [out] */
    float out_max;
    mc_pi_aw_t aw;    /**< anti-windup scheme */
    float integ;      /**< integrator, output units, in [out_min, out_max] */
    float integ_prev; /**< integrator before the last accepted step (for track) */
    float out;        /**< last output (saturated) */
    float last_error; /**< error of the last accepted step */
    float last_ff;    /**< feed-forward of the last accepted step */
    uint32_t flags;   /**< sticky MC_PI_ERR_* raised by steps */
} mc_pi_f32_t;

/**
 * Validate cfg and initialise st: integrator 0, last output clamped 0, flags
 * cleared. Returns MC_PI_ERR_NONE or the OR of every rule the config breaks;
 * on any error st is not written.
 */
/**
 * Check a configuration without touching any state: the error bits init
 * would return (the q31 twin's cfg_from_f32 uses it too).
 */
uint32_t mc_pi_f32_validate(const mc_pi_f32_cfg_t *cfg);

uint32_t mc_pi_f32_init(mc_pi_f32_t *st, const mc_pi_f32_cfg_t *cfg);

/**
 * Set the integrator to integrator_preset (clamped to the output limits),
 * the last output to the same clamped value, the last error and feed-forward
 * to 0, and clear the sticky flags. A non-finite preset is refused
 * (MC_PI_ERR_NAN_INPUT returned, st not written).
 */
uint32_t mc_pi_f32_reset(mc_pi_f32_t *st, float integrator_preset);

/**
 * One step without feed-forward, static limits: the output [out] in *p_out.
 * Returns MC_PI_ERR_NONE, MC_PI_ERR_NAN_INPUT (refused, see the file
 * comment) or MC_PI_ERR_NULL (st or p_out NULL: nothing written).
 */
uint32_t mc_pi_f32_step(mc_pi_f32_t *st, float error, float *p_out);

/** One step with a feed-forward term added before the limits; returns as
 *  mc_pi_f32_step. */
uint32_t mc_pi_f32_step_ff(mc_pi_f32_t *st, float error, float ff, float *p_out);

/**
 * One step with feed-forward and dynamic limits [lim_lo, lim_hi] (intersected
 * with the static limits). The anti-windup works against the limit actually
 * applied. lim_lo > lim_hi (after intersection) is refused: state unchanged,
 * *p_out the last output, MC_PI_ERR_DYN_LIMIT returned and made sticky.
 * Otherwise returns as mc_pi_f32_step.
 */
uint32_t mc_pi_f32_step_lim(mc_pi_f32_t *st, float error, float ff, float lim_lo, float lim_hi,
                            float *p_out);

/**
 * Tell the PI the output actually applied after its last step, when a later
 * stage cut it further (e.g. the modulator's hexagon). The anti-windup then
 * acts as if the last step had run with applied_out as its limit:
 * - clamp: the last increment is taken back as far as needed for
 *   kp*e_last + I + ff_last to reach applied_out, never beyond the
 *   integrator value before that step;
 * - back-calculation: I += kaw*dt*(applied_out - out);
 * - none: only the stored last output changes.
 * The stored last output becomes applied_out (clamped to the static limits).
 * A non-finite value is refused (MC_PI_ERR_NAN_INPUT returned and made
 * sticky, nothing else changes).
 */
uint32_t mc_pi_f32_track(mc_pi_f32_t *st, float applied_out);

/**
 * Change kp and ki bumplessly (see file comment). Gains are validated as in
 * init (MC_PI_ERR_KP / MC_PI_ERR_KI); on error nothing changes.
 */
uint32_t mc_pi_f32_set_gains(mc_pi_f32_t *st, float kp, float ki_per_s);

#ifdef __cplusplus
}
#endif

#endif /* MC_PI_H */
