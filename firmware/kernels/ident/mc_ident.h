/**
 * @file mc_ident.h
 * @brief Parameter-identification helpers: running averages, a straight-line
 *        least-squares fit, a circular mean, and the closed-form estimators
 *        the commissioning sequence uses (resistance from two DC levels,
 *        inductance from a square-wave voltage).
 *
 * All f32, no heap, no libm (mc_math only). Accumulators are plain structs
 * the caller owns: `reset` zeroes them, `step` adds one sample; both return
 * the MC_IDENT_ERR_* bits raised by the call (MC_IDENT_ERR_NULL for a NULL
 * accumulator; a non-finite sample is refused and not added: _NAN),
 * `get` reads the result and returns error bits (too few samples, a
 * degenerate fit). Sums are compensated (Kahan), so averages over 10^5
 * samples keep float's relative precision.
 */
#ifndef MC_IDENT_H
#define MC_IDENT_H

#include <stdbool.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define MC_IDENT_ERR_NONE       0u
#define MC_IDENT_ERR_NAN        (1u << 0) /**< a non-finite input */
#define MC_IDENT_ERR_EMPTY      (1u << 1) /**< no (or too few) samples */
#define MC_IDENT_ERR_DEGENERATE (1u << 2) /**< the fit has no unique solution */
#define MC_IDENT_ERR_NULL       (1u << 3) /**< a NULL pointer */
#define MC_IDENT_ERR_RANGE      (1u << 4) /**< an input outside the estimator's domain */

/** Compensated running sum / mean. */
typedef struct {
    float sum;  /**< running sum */
    float comp; /**< Kahan compensation */
    uint32_t n; /**< samples added */
} mc_ident_avg_f32_t;

uint32_t mc_ident_avg_f32_reset(mc_ident_avg_f32_t *st);
uint32_t mc_ident_avg_f32_step(mc_ident_avg_f32_t *st, float x);
/** Mean of the samples; MC_IDENT_ERR_EMPTY (and 0) with none. */
uint32_t mc_ident_avg_f32_get(const mc_ident_avg_f32_t *st, float *p_mean);

/**
 * Least squares y = a + b x (with_intercept) or y = b x (through the
 * origin), from the compensated sums of x, y, x^2, xy. The caller keeps x
 * and y of moderate dynamic range (centre them if they sit far from 0).
 */
typedef struct {
    mc_ident_avg_f32_t sx, sy, sxx, sxy;
} mc_ident_line_f32_t;

uint32_t mc_ident_line_f32_reset(mc_ident_line_f32_t *st);
uint32_t mc_ident_line_f32_step(mc_ident_line_f32_t *st, float x, float y);
/** Slope b (and intercept a, which may be NULL). With with_intercept false
 *  the line passes through the origin (a = 0). MC_IDENT_ERR_EMPTY with
 *  fewer than 2 samples, MC_IDENT_ERR_DEGENERATE when x does not vary
 *  (or is all zero through the origin). */
uint32_t mc_ident_line_f32_get(const mc_ident_line_f32_t *st, bool with_intercept, float *p_slope,
                               float *p_intercept);

/** Circular mean of angles (sum of unit vectors). */
typedef struct {
    mc_ident_avg_f32_t s, c;
} mc_ident_circ_f32_t;

uint32_t mc_ident_circ_f32_reset(mc_ident_circ_f32_t *st);
uint32_t mc_ident_circ_f32_step(mc_ident_circ_f32_t *st, float angle_rad);
/** Mean angle in (-pi, pi] and the resultant length in [0, 1] (1: all
 *  samples equal; may be NULL). MC_IDENT_ERR_DEGENERATE when the resultant
 *  is below 1e-3 (no defined mean). */
uint32_t mc_ident_circ_f32_get(const mc_ident_circ_f32_t *st, float *p_mean_rad,
                               float *p_resultant);

/**
 * Resistance from two DC operating points along one axis:
 * R = (v2 - v1) / (i2 - i1). The inverter's dead-time and switch drops
 * add a voltage that is the same at both points (both currents on the same
 * side of the dead band), so the difference cancels it.
 * MC_IDENT_ERR_RANGE when |i2 - i1| is below 1e-6 A or R comes out <= 0.
 */
uint32_t mc_ident_r_two_level_f32(float v1_v, float i1_a, float v2_v, float i2_a, float *p_r_ohm);

/**
 * Inductance from a square-wave voltage +-v_amp_v alternating every period
 * dt_s on a winding of resistance r_ohm, given the peak-to-peak current
 * ripple di_pp_a it produced in steady state. Exact for the R-L winding:
 * di_pp = (2 v / R) tanh(R dt / (2 L)), solved for L; with r_ohm = 0 the
 * pure inductance L = v dt / di_pp. The tanh is inverted by its series
 * (exact to float precision while R dt / (2 L) <= 0.5; MC_IDENT_ERR_RANGE
 * beyond, or for non-positive v, dt, di).
 */
uint32_t mc_ident_l_square_wave_f32(float v_amp_v, float dt_s, float di_pp_a, float r_ohm,
                                    float *p_l_h);

#ifdef __cplusplus
}
#endif

#endif /* MC_IDENT_H */
