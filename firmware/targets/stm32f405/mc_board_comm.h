/**
 * @file mc_board_comm.h
 * Commissioning limits of an STM32F405 board (mc_comm_can_cfg_t) from its
 * description and the booted parameters, the same rules as the SIL's
 * can-telemetry scenario: a quarter of the current-sense range as the test
 * current, 90 % of the phase voltage the board's lowest bus allows, a tenth
 * of the sense range as the largest plausible sensor offset, the tests'
 * current loop at 0.08 / T, status frames at 10 Hz.
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
