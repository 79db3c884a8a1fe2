/**
 * @file mc_svpwm.h
 * @brief Space-vector PWM: alpha/beta voltage request to three high-side
 *        duties, float32 and q31 twins.
 *
 * Method: min-max (centred) zero-sequence injection, which gives the same
 * switching pattern as symmetric seven-segment SVPWM. With the phase voltages
 * va, vb, vc of the request (inverse Clarke, amplitude invariant) and
 * mid = (max(va,vb,vc) + min(va,vb,vc)) / 2, the duties are
 *     d_x = 1/2 + (v_x - mid) / D,      D = max(vbus, L)
 * where L measures the request against the chosen limit:
 * - MC_SVPWM_LIMIT_CIRCLE:  L = sqrt(3) * |v|. Requests up to the inscribed
 *   circle |v| <= vbus / sqrt(3) pass unchanged; longer ones are scaled to
 *   exactly vbus / sqrt(3), direction kept.
 * - MC_SVPWM_LIMIT_HEXAGON: L = max - min (the largest line-to-line voltage).
 *   Requests inside the hexagon (max - min <= vbus, vertices at 2/3 vbus)
 *   pass unchanged; longer ones are scaled along their direction to the
 *   hexagon boundary, where one duty is 0 and another 1.
 * Dividing by D > vbus is the same as scaling the request by vbus / D, so the
 * average line-to-line voltages (d_a - d_b) * vbus, (d_b - d_c) * vbus,
 * (d_c - d_a) * vbus are those of the (limited) request.
 *
 * Duties are for the high-side switch of each phase: 0 = always low side,
 * 1 = always high side; 0.5 on all three phases is zero line-to-line voltage.
 */
#ifndef MC_SVPWM_H
#define MC_SVPWM_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef enum {
    MC_SVPWM_LIMIT_CIRCLE = 0,
    MC_SVPWM_LIMIT_HEXAGON = 1
} mc_svpwm_limit_t;

/** Nothing to report: the request was inside the linear region. */
#define MC_SVPWM_FLAG_NONE 0u
/** The request was outside the chosen limit and was scaled down to it. */
#define MC_SVPWM_FLAG_LIMITED (1u << 0)
/** vbus NaN, infinite or <= 0: all duties 0.5 (zero line-to-line voltage). */
#define MC_SVPWM_FLAG_BAD_VBUS (1u << 1)
/** A voltage NaN or infinite or a limit value outside mc_svpwm_limit_t:
 *  duties 0.5. Also a NULL output pointer: then nothing is written. */
#define MC_SVPWM_FLAG_BAD_INPUT (1u << 2)

/**
 * Float32 SVPWM. Voltages in volts (amplitude-invariant alpha/beta, the same
 * convention as mc_inv_clarke_f32), vbus in volts. Writes duties in [0, 1].
 * Returns a set of MC_SVPWM_FLAG_* bits (MC_SVPWM_FLAG_NONE = 0 in the
 * linear region). BAD_VBUS and BAD_INPUT may be set together; with either,
 * LIMITED is never set. Any finite request, however large, is handled
 * without overflow (the computation is normalised by
 * max(vbus, |v_alpha|, |v_beta|)).
 * Cost: in general four float divisions, one mc_sqrt_f32 (circle limit
 * only), about 30 other flops. With the circle limit and |v_alpha|,
 * |v_beta| <= vbus (every current-controller request) the same results
 * from two divisions and about 20 flops when |v| < 0.574 vbus, plus one
 * square root and one division beyond (the benchmark's svpwm_circle on the
 * Cortex-M4F: 82 and 127 instructions with its call site).
 */
uint32_t mc_svpwm_f32(float v_alpha_v, float v_beta_v, float vbus_v, mc_svpwm_limit_t limit,
                      float *p_duty_a, float *p_duty_b, float *p_duty_c);

/**
 * The voltage vector mc_svpwm_f32 actually applies for this request, in
 * place: unchanged in the linear region, scaled to the limit otherwise, and
 * (0, 0) when the function reports BAD_VBUS or BAD_INPUT (the modulator then
 * applies zero voltage). Same flags as mc_svpwm_f32. Meant for the current
 * controller's anti-windup (back-calculation from the applied voltage).
 * With a NULL pointer: BAD_INPUT, nothing written.
 */
uint32_t mc_svpwm_limit_f32(float *p_v_alpha_v, float *p_v_beta_v, float vbus_v,
                            mc_svpwm_limit_t limit);

/**
 * mc_svpwm_limit_f32 and then mc_svpwm_f32 on the limited vector, in one
 * call: the request is limited in place (unchanged in the linear region,
 * scaled to the limit, or zeroed with BAD_VBUS / BAD_INPUT) and the duties
 * are those of the limited request. Returns the OR of the two calls' flags.
 * Bit-identical to the two calls in sequence; cheaper, since in the linear
 * region one solution serves both. With a NULL pointer: BAD_INPUT, nothing
 * written.
 */
uint32_t mc_svpwm_limit_duty_f32(float *p_v_alpha_v, float *p_v_beta_v, float vbus_v,
                                 mc_svpwm_limit_t limit, float *p_duty_a, float *p_duty_b,
                                 float *p_duty_c);

/**
 * The largest voltage magnitude |v| the modulator delivers, over every
 * direction:
 * - circle: vbus / sqrt(3), the same in every direction;
 * - hexagon: 2 * vbus / 3, reached along the phase axes (the hexagon's
 *   vertices); midway between them (the flat sides) only vbus / sqrt(3) is
 *   available, and mc_svpwm_limit_f32 tells the caller what was applied.
 * A request longer than this is scaled in every direction.
 * Returns 0 for a bad vbus (NaN, infinite, <= 0) or an unknown limit.
 */
float mc_svpwm_max_voltage_f32(float vbus_v, mc_svpwm_limit_t limit);

#ifdef __cplusplus
}
#endif

#endif /* MC_SVPWM_H */
