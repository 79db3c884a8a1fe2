/**
 * @file mc_pi_q31.h
 * @brief Fixed-point (q31) twin of the PI controller in mc_pi.h: the same
 *        law, anti-windup schemes and error bits, in per-unit q31.
 */
#ifndef MC_PI_Q31_H
#define MC_PI_Q31_H

#include <stdint.h>

#include "math/mc_q31.h"
#include "pi/mc_pi.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Largest gain shift accepted by the q31 kernel: gains up to 2^15 per unit. */
#define MC_PI_Q31_MAX_SHIFT 15

/**
 * Fixed-point PI configuration. Error, feed-forward and output are q31 per
 * unit of bases chosen by the caller (err_base, out_base in
 * mc_pi_q31_cfg_from_f32). Gains are a q31 mantissa with a left shift:
 *     kp_pu      = kp_mant    * 2^kp_shift / 2^31
 *     ki_dt_pu   = ki_dt_mant * 2^ki_shift / 2^31   (ki * dt, per step)
 *     kaw_dt_pu  = kaw_dt / 2^31                     (kaw * dt, <= 1)
 * Mantissas >= 0, shifts in [0, MC_PI_Q31_MAX_SHIFT].
 *
 * Scaling and overflow: every product is formed in a 64-bit accumulator in
 * Q17.46 (a q31 value v is v * 2^15 there). |kp_pu * e| <= 2^15, so a sum of
 * the proportional term, the integrator (|I| <= 1) and the feed-forward
 * (|ff| <= 1) stays below 2^17 per unit and never overflows. The integrator is
 * kept in Q17.46 (15 fractional bits below the q31 LSB so that small ki*dt*e
 * increments are not lost) and clamped to [out_min, out_max]. The output is
 * rounded to nearest and saturated to [lo, hi]: the kernel saturates,
 * never wraps.
 */
typedef struct {
    q31_t kp_mant;    /**< proportional gain mantissa, >= 0 */
    int32_t kp_shift; /**< proportional gain left shift, 0..15 */
    q31_t ki_dt_mant; /**< ki*dt mantissa, >= 0 */
    int32_t ki_shift; /**< ki*dt left shift, 0..15 */
    q31_t out_min;    /**< lower output limit (per unit) */
    q31_t out_max;    /**< upper output limit (per unit), >= out_min */
    mc_pi_aw_t aw;    /**< anti-windup scheme */
    q31_t kaw_dt;     /**< kaw*dt in q31, > 0; only read for MC_PI_AW_BACK_CALC */
} mc_pi_q31_cfg_t;

/** Fixed-point PI state. */
typedef struct {
    q31_t kp_mant;
    int32_t kp_shift;
    q31_t ki_dt_mant;
    int32_t ki_shift;
    q31_t kaw_dt;
    q31_t out_min;
    q31_t out_max;
    mc_pi_aw_t aw;
    int64_t integ_q46; /**< integrator in Q17.46, within [out_min, out_max] */
    q31_t out;         /**< last output */
    q31_t last_error;  /**< error of the last accepted step */
    q31_t last_ff;     /**< feed-forward of the last accepted step */
    uint32_t flags;    /**< sticky MC_PI_ERR_* raised by steps */
} mc_pi_q31_t;

/**
 * Convert a float config to q31: kp_pu = kp * err_base / out_base,
 * ki_dt_pu = ki * dt * err_base / out_base, limits / out_base (saturated to
 * the q31 range), kaw_dt = kaw * dt. The float config is validated as by
 * mc_pi_f32_init; additionally MC_PI_ERR_SCALE for a base <= 0 or not finite
 * or a per-unit gain >= 2^15. On error *p_q is not written.
 */
uint32_t mc_pi_q31_cfg_from_f32(const mc_pi_f32_cfg_t *cfg, float err_base, float out_base,
                                mc_pi_q31_cfg_t *p_q);

/** Validate cfg and initialise st (integrator 0). On error st is not written. */
uint32_t mc_pi_q31_init(mc_pi_q31_t *st, const mc_pi_q31_cfg_t *cfg);

/** Integrator and last output to preset (clamped), last error/ff 0, flags
 *  cleared. Returns MC_PI_ERR_NONE, or MC_PI_ERR_NULL for a NULL st. */
uint32_t mc_pi_q31_reset(mc_pi_q31_t *st, q31_t integrator_preset);

/** One step, no feed-forward, static limits: the output (per unit) in
 *  *p_out. Returns MC_PI_ERR_NONE or MC_PI_ERR_NULL (st or p_out NULL:
 *  nothing written); q31 has no non-finite input. */
uint32_t mc_pi_q31_step(mc_pi_q31_t *st, q31_t error, q31_t *p_out);

/** One step with feed-forward; returns as mc_pi_q31_step. */
uint32_t mc_pi_q31_step_ff(mc_pi_q31_t *st, q31_t error, q31_t ff, q31_t *p_out);

/**
 * One step with feed-forward and dynamic limits (intersected with the static
 * ones); lim_lo > lim_hi is refused (state unchanged, *p_out the last output,
 * MC_PI_ERR_DYN_LIMIT returned and made sticky). Otherwise returns as
 * mc_pi_q31_step.
 */
uint32_t mc_pi_q31_step_lim(mc_pi_q31_t *st, q31_t error, q31_t ff, q31_t lim_lo, q31_t lim_hi,
                            q31_t *p_out);

/** Bumpless gain change (mantissa/shift as in the config); on error nothing changes. */
uint32_t mc_pi_q31_set_gains(mc_pi_q31_t *st, q31_t kp_mant, int32_t kp_shift, q31_t ki_dt_mant,
                             int32_t ki_shift);

#ifdef __cplusplus
}
#endif

#endif /* MC_PI_Q31_H */
