/**
 * @file mc_stepper_dq.h
 * @brief DQ transformation of the two-phase PM stepper (paper 001, Sec. II):
 *        fixed phase axes (a, b) <-> rotor axes (d, q) at the electrical
 *        angle N_r * phi.
 *
 *     [x_d]   [ cos(N_r phi)  sin(N_r phi)] [x_a]
 *     [x_q] = [-sin(N_r phi)  cos(N_r phi)] [x_b]
 *
 * With this transformation the phase model (1) of the paper (with the
 * energy-consistent sign of the phase-b back-EMF, -K_m w cos(N_r phi), see
 * sim/include/mcsim/stepper_2ph.hpp) becomes exactly the dq model (2):
 *     di_d/dt = (-R i_d + v_d)/L + N_r w i_q
 *     di_q/dt = (-R i_q - K_m w + v_q)/L - N_r w i_d
 *     J dw/dt = K_m i_q - B w - tau_L
 * (derivation: i_q = -s i_a + c i_b, d/dt adds -N_r w (c i_a + s i_b)
 * = -N_r w i_d; the back-EMF terms K_m w (-s sin - c cos) sum to -K_m w).
 *
 * The transformation is a rotation: it keeps the vector length, and its
 * inverse is the transpose. Stateless, static inline; the angle is the
 * mechanical shaft angle phi [rad] and the tooth count N_r; the product is
 * formed in float and reduced by mc_sincos_f32 (any finite angle).
 */
#ifndef MC_STEPPER_DQ_H
#define MC_STEPPER_DQ_H

#include <stdint.h>

#include "math/mc_math.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Electrical angle N_r * phi [rad] (not wrapped). */
static inline float mc_stepper_theta_e_f32(float theta_m_rad, uint32_t rotor_teeth)
{
    return (float)rotor_teeth * theta_m_rad;
}

/** (x_a, x_b) -> (x_d, x_q) with the sine and cosine of N_r phi given. */
static inline void mc_stepper_ab_to_dq_sc_f32(float x_a, float x_b, float sin_e, float cos_e,
                                              float *p_x_d, float *p_x_q)
{
    *p_x_d = cos_e * x_a + sin_e * x_b;
    *p_x_q = cos_e * x_b - sin_e * x_a;
}

/** (x_d, x_q) -> (x_a, x_b), the inverse (transpose) rotation. */
static inline void mc_stepper_dq_to_ab_sc_f32(float x_d, float x_q, float sin_e, float cos_e,
                                              float *p_x_a, float *p_x_b)
{
    *p_x_a = cos_e * x_d - sin_e * x_q;
    *p_x_b = sin_e * x_d + cos_e * x_q;
}

/** (x_a, x_b) -> (x_d, x_q) at shaft angle theta_m_rad, N_r = rotor_teeth. */
static inline void mc_stepper_ab_to_dq_f32(float x_a, float x_b, float theta_m_rad,
                                           uint32_t rotor_teeth, float *p_x_d, float *p_x_q)
{
    float s;
    float c;
    mc_sincos_f32(mc_stepper_theta_e_f32(theta_m_rad, rotor_teeth), &s, &c);
    mc_stepper_ab_to_dq_sc_f32(x_a, x_b, s, c, p_x_d, p_x_q);
}

/** (x_d, x_q) -> (x_a, x_b) at shaft angle theta_m_rad, N_r = rotor_teeth. */
static inline void mc_stepper_dq_to_ab_f32(float x_d, float x_q, float theta_m_rad,
                                           uint32_t rotor_teeth, float *p_x_a, float *p_x_b)
{
    float s;
    float c;
    mc_sincos_f32(mc_stepper_theta_e_f32(theta_m_rad, rotor_teeth), &s, &c);
    mc_stepper_dq_to_ab_sc_f32(x_d, x_q, s, c, p_x_a, p_x_b);
}

#ifdef __cplusplus
}
#endif

#endif /* MC_STEPPER_DQ_H */
