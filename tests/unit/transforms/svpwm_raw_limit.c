#include "svpwm_raw_limit.h"

#include "transforms/mc_svpwm.h"
#include "transforms/mc_svpwm_q31.h"

uint32_t svpwm_f32_raw_limit(float v_alpha_v, float v_beta_v, float vbus_v, int raw_limit,
                             float *p_duty_a, float *p_duty_b, float *p_duty_c)
{
    return mc_svpwm_f32(v_alpha_v, v_beta_v, vbus_v, (mc_svpwm_limit_t)raw_limit, p_duty_a,
                        p_duty_b, p_duty_c);
}

uint32_t svpwm_q31_raw_limit(q31_t v_alpha_pu, q31_t v_beta_pu, q31_t vbus_pu, int raw_limit,
                             q31_t *p_duty_a, q31_t *p_duty_b, q31_t *p_duty_c)
{
    return mc_svpwm_q31(v_alpha_pu, v_beta_pu, vbus_pu, (mc_svpwm_limit_t)raw_limit, p_duty_a,
                        p_duty_b, p_duty_c);
}

float svpwm_max_voltage_raw_limit(float vbus_v, int raw_limit)
{
    return mc_svpwm_max_voltage_f32(vbus_v, (mc_svpwm_limit_t)raw_limit);
}
