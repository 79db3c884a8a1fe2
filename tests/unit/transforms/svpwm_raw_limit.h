/* C helpers that call the SVPWM with a limit value outside mc_svpwm_limit_t
 * (well defined in C, where an enum is an integer type; not in C++). */
#ifndef SVPWM_RAW_LIMIT_H
#define SVPWM_RAW_LIMIT_H

#include <stdint.h>

#include "math/mc_q31.h"

#ifdef __cplusplus
extern "C" {
#endif

uint32_t svpwm_f32_raw_limit(float v_alpha_v, float v_beta_v, float vbus_v, int raw_limit,
                             float *p_duty_a, float *p_duty_b, float *p_duty_c);
uint32_t svpwm_q31_raw_limit(q31_t v_alpha_pu, q31_t v_beta_pu, q31_t vbus_pu, int raw_limit,
                             q31_t *p_duty_a, q31_t *p_duty_b, q31_t *p_duty_c);
float svpwm_max_voltage_raw_limit(float vbus_v, int raw_limit);

#ifdef __cplusplus
}
#endif

#endif /* SVPWM_RAW_LIMIT_H */
