/**
 * @file mc_board_comm.c
 * Commissioning limits of a board (mc_board_comm.h).
 */
#include "mc_board_comm.h"

#include "mc_f405_hal.h"

void mc_board_comm_cfg_from(const mc_board_desc_t *p_desc, const mc_params_t *p,
                            mc_comm_can_cfg_t *p_out)
{
    const bool three = (p_desc->adc_ch_ia != MC_F405_ADC_CH_NONE) &&
                       (p_desc->adc_ch_ib != MC_F405_ADC_CH_NONE) &&
                       (p_desc->adc_ch_ic != MC_F405_ADC_CH_NONE);
    mc_comm_can_cfg_for_board(p, p_desc->i_sense_max_a, p_desc->vbus_min_v, three, p_out);
}
