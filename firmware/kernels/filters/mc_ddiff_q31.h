/**
 * @file mc_ddiff_q31.h
 * @brief q31 twin of the dirty-derivative filter (filters/mc_ddiff.h):
 *        theta_f = b s/(s + a) y, Tustin, with theta_f as the state.
 *
 *     theta_f[k] = c_q theta_f[k-1] + g (y[k] - y[k-1])
 *     c_q = (1 - a dt/2)/(1 + a dt/2),  g = b/(1 + a dt/2)
 *     first step after init/reset: theta_f = q0 + b y[0]
 *
 * Per unit: y is q31 per unit of y_base, theta_f q31 per unit of out_base
 * (both in the unit of y, e.g. rad; theta_f ~ (b/a) dy/dt is often much
 * smaller or larger than y, hence its own base). The coefficients are
 * formed once at init (float) as mc_q46 gains: c_q, g y_base/out_base,
 * b y_base/out_base.
 *
 * Scaling and overflow: the state is a Q46 accumulator (mc_q46.h; 15 guard
 * bits below the output LSB, so the slow pole c_q ~ 1 - a dt does not
 * accumulate rounding: each step rounds twice by <= 2^-47 per unit). The
 * increment is g y[k] - g y[k-1], each product rounded in Q46. The state
 * is clamped to the q31 range of out_base after every step, so the output
 * saturates at [-1, 1 - 2^-31] out_base and the filter recovers from there;
 * it never wraps. Error against the f32 twin on the same inputs: <= 1 output
 * LSB from the q31 arithmetic plus the f32 twin's own rounding (tests).
 *
 * No NaN in q31: the step always runs. No heap, no globals, no I/O.
 */
#ifndef MC_DDIFF_Q31_H
#define MC_DDIFF_Q31_H

#include <stdbool.h>
#include <stdint.h>

#include "filters/mc_ddiff.h"
#include "math/mc_q46.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MC_DDIFF_ERR_SCALE (1u << 5) /**< a base <= 0 / not finite, or a gain beyond mc_q46 */

typedef struct {
    mc_ddiff_f32_cfg_t f; /**< a [1/s], b [1], dt [s]: validated as by mc_ddiff_f32_init */
    float y_base;         /**< base of y [unit of y], > 0 */
    float out_base;       /**< base of theta_f [unit of y], > 0 */
} mc_ddiff_q31_cfg_t;

typedef struct {
    mc_q46_gain_t c_q; /**< pole coefficient */
    mc_q46_gain_t g;   /**< increment gain, y pu -> out pu */
    mc_q46_gain_t b;   /**< first-step gain b y_base/out_base */
    int64_t out_q46;   /**< theta_f, Q46 per unit of out_base */
    q31_t y_prev;      /**< y of the last step */
    q31_t out;         /**< last output */
    bool primed;
    uint32_t flags; /**< sticky flags (none raised by steps today) */
} mc_ddiff_q31_t;

/** Validate cfg (MC_DDIFF_ERR_* as the f32 twin, plus MC_DDIFF_ERR_SCALE);
 *  state with q_c = 0. On error st is not written. */
uint32_t mc_ddiff_q31_init(mc_ddiff_q31_t *st, const mc_ddiff_q31_cfg_t *cfg);

/** Preset q_c (q31 per unit of out_base): the next step outputs q0 + b y.
 *  Returns MC_DDIFF_ERR_NONE, or MC_DDIFF_ERR_NULL for a NULL st. */
uint32_t mc_ddiff_q31_reset(mc_ddiff_q31_t *st, q31_t q0);

/** One sample: theta_f[k] (q31, out_base) for y[k] (q31, y_base) in
 *  *p_theta_f. Returns MC_DDIFF_ERR_NONE, or MC_DDIFF_ERR_NULL (st or
 *  p_theta_f NULL: nothing written). */
uint32_t mc_ddiff_q31_step(mc_ddiff_q31_t *st, q31_t y, q31_t *p_theta_f);

#ifdef __cplusplus
}
#endif

#endif /* MC_DDIFF_Q31_H */
