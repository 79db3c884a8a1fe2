/**
 * @file mc_board_comm.c
 * Commissioning limits of a board (mc_board_comm.h).
 */
#include "mc_board_comm.h"

#include "mc_f405_hal.h"

void mc_board_comm_cfg_from(const mc_board_desc_t *p_desc, const mc_params_t *p,
                            mc_comm_can_cfg_t *p_out)
{
    const float dt_s = 1.0f / (float)p->pwm_hz;
    const mc_comm_can_cfg_t zero = {0};
    mc_comm_can_cfg_t k = zero;
    mc_params_eff_t e;
    (void)mc_params_resolve(p, &e); /* the encoder loop's bandwidth, derived unless set */
    k.base.dt_s = dt_s;
    k.base.i_test_a = 0.25f * p_desc->i_sense_max_a;
    k.base.v_test_max_v = 0.9f * p_desc->vbus_min_v * 0.577350269f; /* / sqrt(3) */
    k.base.offset_max_a = 0.1f * p_desc->i_sense_max_a;
    k.base.dead_time_s = p->dead_time_s;
    k.base.cur_bw_rad_s = 0.08f / dt_s;
    k.base.speed_max_m_rad_s = p->speed_max_rad_s;
    k.base.bemf_frac = 0.5f;
    k.base.pole_pairs_max = 32u;
    k.base.three_shunts = (p_desc->adc_ch_ia != MC_F405_ADC_CH_NONE) &&
                          (p_desc->adc_ch_ib != MC_F405_ADC_CH_NONE) &&
                          (p_desc->adc_ch_ic != MC_F405_ADC_CH_NONE);
    k.node_id = (uint8_t)p->can_node_id;
    k.status_div = (p->pwm_hz / p->slow_loop_div) / 10u; /* 10 Hz */
    if (k.status_div == 0u) {
        k.status_div = 1u;
    }
    k.enc_pll_bw_rad_s = e.p.speed_pll_bw_rad_s;
    *p_out = k;
}
