/**
 * @file mc_comm_can.h
 * @brief Commissioning over CAN: COMMISSION_CMD starts, aborts or reports
 *        the sequence of mc_commission.h; COMMISSION_STATUS tells its
 *        progress; COMMISSION_RESULT carries what it measured; the results
 *        are staged in the parameter table (tools/can/motordrive.dbc,
 *        cmd 0x1C-0x1E).
 *
 * Bound to the CAN command handler by mc_can_cmd_attach_commission (the
 * handler checks the frame, that the drive is not enabled or stopping, and
 * then calls mc_comm_can_command); mc_comm_can_step runs in the slow loop.
 *
 * START (options 0 = the board's default from the cfg): refused MODE when
 * a sequence runs or the drive is not IDLE, REFUSED with a fault latched
 * (clear it first) or when the drive will not take the plug-in, RANGE when
 * the options fail mc_comm_init or the drive's limits (below); refused,
 * nothing is energised. The drive's control-law plug-in is swapped for
 * commissioning's and restored when the sequence ends.
 *
 * The drive's limits, checked on the test values in force: i_test_a <=
 * the drive's i_max_a; v_test_max_v <= the largest voltage vector the
 * measured bus can make, v_bus / sqrt(3) (a bus not measured, not finite
 * or not positive: RANGE); speed_max_m_rad_s <= the speed limit of the
 * parameter set in force (speed_max_rad_s, with a parameter service) and
 * below the drive's over-speed trip (omega_max_rad_s, when it is on). An
 * option beyond them is refused; a zero option takes the board's default
 * bounded by them (the spin-up cap to 0.9 of the trip). Protocol 3
 * accepted 65 A on a 20 A sensor and 600 V on a 200 V bus, and the
 * image's default, a quarter of the sense range, above i_max_a.
 *
 * Keep-alive: the CAN handler times a running sequence out as an enabled
 * drive (mc_can_cmd.h): without a fresh HOST_HEARTBEAT for timeout_s it
 * calls mc_comm_can_host_lost(): the bridge opens at once and the run
 * ends FAILED with MC_COMM_ERR_ABORTED | MC_COMM_ERR_HOST_LOST.
 *
 * Frames: COMMISSION_STATUS and COMMISSION_RESULT are replies and take a
 * token of the CAN handler's reply limiter (mc_comm_can_step's lim); one
 * without a token waits for a later step (nothing is lost).
 * ABORT: bridge off at once (IDLE), the run ends FAILED with
 * MC_COMM_ERR_ABORTED, nothing staged. REPORT: the results of the last
 * successful run sent again (REFUSED when there are none).
 *
 * When the sequence is DONE: the drive goes IDLE and every result is
 * written into the parameter service's staged set with the service's own
 * WRITE checks (range, access): r_ohm, ld_h, lq_h, flux_wb, pole_pairs,
 * encoder_offset_rad, encoder_reversed, i_offset_{a,b,c}_a (the offsets in
 * use plus the measured ones), and, when the mechanics were measured,
 * j_kgm2, b_nm_s_rad and the speed PI re-derived from them (mc_gains.h,
 * the simulator's formulas), and with Hall sensors the measured table
 * (hall_codes, hall_edge0..5_e_rad, hall_hysteresis_e_rad: WRITE and
 * CONFIRM, reboot parameters) with encoder_offset_rad 0 and
 * encoder_reversed 0 (the edges are the d axis's angles). One refused write restores the staged set
 * as it was: the run reports MC_COMM_ERR_RANGE and stages nothing. The
 * host then APPLYs (the whole-set validation of PARAM_REQ APPLY, which also
 * re-derives the current-loop gains) and SAVEs. A failed run stages
 * nothing and the drive keeps the fault that stopped it.
 */
#ifndef MC_COMM_CAN_H
#define MC_COMM_CAN_H

#include <stdbool.h>
#include <stdint.h>

#include "can/mc_can_proto.h"
#include "can/mc_telemetry.h"
#include "commission/mc_commission.h"
#include "config/mc_param_srv.h"
#include "hal/can.h"
#include "mc_drive.h"

#ifdef __cplusplus
extern "C" {
#endif

/* COMMISSION_CMD.action (DBC values). */
#define MC_COMM_CAN_ABORT  0u
#define MC_COMM_CAN_START  1u
#define MC_COMM_CAN_REPORT 2u

/* COMMISSION_RESULT.item (DBC values). */
#define MC_COMM_CAN_ITEM_R_OHM              0u
#define MC_COMM_CAN_ITEM_LD_H               1u
#define MC_COMM_CAN_ITEM_LQ_H               2u
#define MC_COMM_CAN_ITEM_FLUX_WB            3u
#define MC_COMM_CAN_ITEM_POLE_PAIRS         4u
#define MC_COMM_CAN_ITEM_ENCODER_OFFSET_RAD 5u
#define MC_COMM_CAN_ITEM_ENCODER_DIRECTION  6u
#define MC_COMM_CAN_ITEM_ADC_OFFSET_A_A     7u
#define MC_COMM_CAN_ITEM_ADC_OFFSET_B_A     8u
#define MC_COMM_CAN_ITEM_ADC_OFFSET_C_A     9u
#define MC_COMM_CAN_ITEM_J_KGM2             10u
#define MC_COMM_CAN_ITEM_B_NM_S_RAD         11u
#define MC_COMM_CAN_ITEM_COUNT              12u

/* Configuration errors of mc_comm_can_init. */
#define MC_COMM_CAN_CFG_OK       0u
#define MC_COMM_CAN_CFG_ERR_NULL (1u << 0) /**< NULL module, cfg, comm or drive */
#define MC_COMM_CAN_CFG_ERR_VALUE \
    (1u << 1) /**< base cfg refused by mc_comm_init,
                                                 node > 62, status_div 0, speed_wc <= 0 */

typedef struct {
    mc_comm_cfg_t base;     /**< the board's defaults (START options 0) */
    uint8_t node_id;        /**< 0..62 */
    uint32_t status_div;    /**< slow steps between status frames while running */
    float enc_pll_bw_rad_s; /**< encoder tracking loop (speed PI crossover) */
} mc_comm_can_cfg_t;

typedef struct {
    mc_comm_can_cfg_t cfg;
    mc_comm_t *comm;
    mc_drive_t *drive;
    mc_param_srv_t *params;           /**< NULL: results reported, not staged */
    const mc_drive_ctrl_t *prev_ctrl; /**< the plug-in restored after a run */
    bool running;
    bool have_result; /**< the last run ended DONE */
    bool staged;      /**< ... and its results are in params->staged */
    uint32_t err;     /**< MC_COMM_ERR_* of the last run */
    uint8_t step;     /**< mc_comm_step_t reported */
    uint8_t status_seq;
    uint8_t result_seq;
    uint8_t result_next; /**< next item to send; COUNT: none pending */
    bool status_due;
    uint32_t div_n;
    float result[MC_COMM_CAN_ITEM_COUNT];
    uint32_t tx_dropped; /**< frames the HAL refused */
} mc_comm_can_t;

/** The commissioning limits of a board from its parameters p (pwm_hz,
 *  slow_loop_div, dead_time_s, speed_max_rad_s, the encoder loop's bandwidth
 *  derived unless set, can_node_id) and three board facts: the current-sense
 *  range i_sense_max_a, the lowest bus it runs on vbus_low_v and whether it
 *  measures three phases. A quarter of the sense range as the test current,
 *  90 % of the phase voltage vbus_low_v allows, a tenth of the sense range as
 *  the largest plausible sensor offset, the tests' current loop at 0.08 / T,
 *  the spin-up capped at speed_max_rad_s, status frames at 10 Hz. The boards'
 *  images (firmware/targets/stm32f405/mc_board_comm.c, from the board's
 *  description), the PIL image and the simulator's application target (from
 *  the parameter table: the nominal bus, current_sensors) use this one rule.
 *  mc_comm_can_init validates the result. */
void mc_comm_can_cfg_for_board(const mc_params_t *p, float i_sense_max_a, float vbus_low_v,
                               bool three_shunts, mc_comm_can_cfg_t *p_out);

/** Validate cfg and bind: comm is (re)initialised with cfg->base, params
 *  may be NULL. Returns MC_COMM_CAN_CFG_* bits; on error m is unchanged. */
uint32_t mc_comm_can_init(mc_comm_can_t *m, const mc_comm_can_cfg_t *cfg, mc_comm_t *comm,
                          mc_drive_t *drive, mc_param_srv_t *params);

/** COMMISSION_CMD (signal values in DBC order, MC_CAN_COMMISSION_CMD_*):
 *  MC_CAN_ERR_NONE or the refusal (nothing changed). */
mc_can_err_t mc_comm_can_command(void *ctx, const float *v);

/** true while a sequence runs (the CAN handler refuses enable and mode
 *  commands meanwhile). */
bool mc_comm_can_busy(const void *ctx);

/** The host's keep-alive stopped (the CAN handler's timeout): a running
 *  sequence ends at once, bridge off, MC_COMM_ERR_HOST_LOST. */
void mc_comm_can_host_lost(void *ctx);

/** Slow loop: follows the sequence, stages the results when it is done,
 *  sends COMMISSION_STATUS (every status_div steps while running and once
 *  at the end) and the COMMISSION_RESULT frames (one per step), each with
 *  a token of lim (NULL: no limiter; the application passes the CAN
 *  handler's). can may be NULL (nothing sent). */
void mc_comm_can_step(mc_comm_can_t *m, const mc_hal_can_t *can, mc_tm_reply_lim_t *lim);

#ifdef __cplusplus
}
#endif

#endif /* MC_COMM_CAN_H */
