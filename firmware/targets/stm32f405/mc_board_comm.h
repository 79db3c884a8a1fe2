/**
 * @file mc_board_comm.h
 * Commissioning limits of an STM32F405 board (mc_comm_can_cfg_t) from its
 * description and the booted parameters: the rule of
 * mc_comm_can_cfg_for_board (commission/mc_comm_can.h) with the board's
 * current-sense range, its lowest bus voltage and whether it has a third
 * shunt.
 */
#ifndef MC_BOARD_COMM_H
#define MC_BOARD_COMM_H

#include "commission/mc_comm_can.h"
#include "mc_board_desc.h"
#include "mc_params.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Fill p_out from the board p_desc and the parameters p (pwm_hz,
 *  slow_loop_div, dead time, speed limit, encoder tracking bandwidth, node
 *  id). mc_comm_can_init validates the result. */
void mc_board_comm_cfg_from(const mc_board_desc_t *p_desc, const mc_params_t *p,
                            mc_comm_can_cfg_t *p_out);

#ifdef __cplusplus
}
#endif

#endif /* MC_BOARD_COMM_H */
