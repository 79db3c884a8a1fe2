/**
 * @file mc_svpwm_core.h
 * @brief Internal to the kernels (not a public API): the float modulator's
 *        linear case, inline, so that mc_svpwm_f32 and the FOC's fast path
 *        (foc/mc_foc.c) run the very same operations and give the same
 *        bits. Method and limits: transforms/mc_svpwm.h.
 */
#ifndef MC_SVPWM_CORE_H
#define MC_SVPWM_CORE_H

#include <stdbool.h>

#include "transforms/mc_svpwm.h"
#include "transforms/mc_transforms.h"

#ifdef __cplusplus
extern "C" {
#endif

/** The limit is one the modulators know (both twins refuse others). */
static inline bool mc_svpwm_limit_ok(mc_svpwm_limit_t limit)
{
    return (limit == MC_SVPWM_LIMIT_CIRCLE) || (limit == MC_SVPWM_LIMIT_HEXAGON);
}

/** Largest |v|^2 / vbus^2 of the linear case: |v| < 0.5745 vbus. */
#define MC_SVPWM_LINEAR_MAG2 0.33f

/**
 * Duties v_x + (0.5 - mid) of the normalised request alpha_n = v_alpha /
 * vbus, beta_n = v_beta / vbus, with the phase voltages v_x of the
 * normalised request and mid = (max + min) / 2: the modulator's result for
 * a request that meets the test of mc_svpwm_circle_linear_f32 (the caller
 * has made sure of that, by that test or by a bound of its own).
 */
static inline void mc_svpwm_circle_duties_f32(float alpha_n, float beta_n, float *p_duty_a,
                                              float *p_duty_b, float *p_duty_c)
{
    float va;
    float vb;
    float vc;
    mc_inv_clarke_f32(alpha_n, beta_n, &va, &vb, &vc);
    /* vb, vc = -alpha/2 +- sqrt(3)/2 beta (mc_inv_clarke_f32): the larger of
     * the two is -alpha/2 + |sqrt(3)/2 beta|, the smaller -alpha/2 - |...|,
     * the same floats as vb and vc (x - y and -y + x round alike). So the
     * max and min of the three take one compare each. */
    const float half_alpha = 0.5f * alpha_n;
    const float beta_term = mc_fabs_f32((0.5f * MC_SQRT3_F32) * beta_n);
    const float hi_bc = beta_term - half_alpha;
    const float lo_bc = -half_alpha - beta_term;
    const float vmax = (va > hi_bc) ? va : hi_bc;
    const float vmin = (va < lo_bc) ? va : lo_bc;
    /* d_x = 1/2 + v_x - mid = v_x + off, off = 1/2 - (max + min) / 2 */
    const float off = 0.5f - (0.5f * (vmax + vmin));
    *p_duty_a = va + off;
    *p_duty_b = vb + off;
    *p_duty_c = vc + off;
}

/**
 * The circle limit's linear case from the normalised request alpha_n =
 * v_alpha / vbus, beta_n = v_beta / vbus (|v_alpha|, |v_beta| <= vbus, vbus
 * finite and > 0): the duties of mc_svpwm_circle_duties_f32. Returns false,
 * nothing written, unless alpha_n^2 + beta_n^2 < MC_SVPWM_LINEAR_MAG2 (NaN:
 * false).
 *
 * Why this is the general modulator's result there (mc_svpwm.c): k = vbus,
 * so its normalised values are these; |v| < 0.5745 vbus (rounding
 * included) puts sqrt(3) |v| <= 0.9951 vbus inside the circle, so D = vbus
 * and its phase values are scaled by 1 / vbus_n = 1 (exact); and max - min <=
 * sqrt(3) |v| < 0.9951 keeps every duty within 0.5 +- 0.4976, where its
 * clamp to [0, 1] cannot act.
 */
static inline bool mc_svpwm_circle_linear_f32(float alpha_n, float beta_n, float *p_duty_a,
                                              float *p_duty_b, float *p_duty_c)
{
    if (!(((alpha_n * alpha_n) + (beta_n * beta_n)) < MC_SVPWM_LINEAR_MAG2)) {
        return false;
    }
    mc_svpwm_circle_duties_f32(alpha_n, beta_n, p_duty_a, p_duty_b, p_duty_c);
    return true;
}

#ifdef __cplusplus
}
#endif

#endif /* MC_SVPWM_CORE_H */
