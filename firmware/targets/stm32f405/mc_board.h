/**
 * @file mc_board.h
 * @brief What the STM32F405 image's main needs from a board binding.
 *
 * main.c (the drive application's entry point) is the same for every image;
 * one board file supplies these functions:
 *   board_stm32f405.c  the drive board: hal/stm32f405 drivers (TIM1 PWM, ADC
 *                      injected conversions, encoder timer, bxCAN, tick);
 *   hal/pil/mc_hal_pil.c  processor-in-the-loop: the same HAL contract served
 *                      over USART1 by the host simulator (QEMU netduinoplus2).
 *
 * Interrupt structure (both boards): the fast loop runs in ADC_IRQHandler
 * (IRQ 18, the end of the TIM1-triggered injected conversions; the PIL board
 * pends it when a measurement frame has arrived), at the highest priority;
 * the slow loop runs in PendSV at the lowest priority, pended by the fast
 * loop every slow_loop_div periods.
 */
#ifndef MC_BOARD_H
#define MC_BOARD_H

#include <stdbool.h>
#include <stdint.h>

#include "hal/hal.h"
#include "mc_app.h"
#include "mc_drive.h"

/** Configure the board's peripherals (clocks already set: sysclk_hz, or 0
 *  under emulation) and return its HAL. NULL: the board cannot run. */
const mc_hal_t *mc_board_init(uint32_t sysclk_hz);

/** The drive configuration for this board (the PIL board receives it from
 *  the host). NULL: none available. */
const mc_drive_cfg_t *mc_board_drive_cfg(void);

/** The drive application's binding (flash store, watchdog, defaults, node
 *  filter), called once after mc_board_init. NULL (the default of main.c,
 *  a weak symbol; the PIL board when the host asks for the drive alone): no
 *  application, the drive alone runs on mc_board_drive_cfg and the board's
 *  own command path. */
const mc_app_cfg_t *mc_board_app_cfg(void);

/** The CAN bit rate of the booted configuration (can_bitrate_bps), applied
 *  once after mc_app_boot and before the application starts: the board
 *  re-times its controller (mc_board_f405_can_set_bitrate). Returns 0, or
 *  -1 when the rate is refused (the controller keeps the set-up's 500
 *  kbit/s). The default of main.c (weak; the PIL board): 0, nothing done. */
int mc_board_can_bitrate(uint32_t bitrate_bps);

/** Commissioning over CAN for this board, from the booted parameters p
 *  (test current and voltage from the board's sense range and lowest bus,
 *  its dead time, the PWM period). NULL (the default of main.c, a weak
 *  symbol): not offered, COMMISSION_CMD answers UNSUPPORTED. The PIL board
 *  offers it from its parameters (hal/pil/mc_hal_pil.c). */
const mc_comm_can_cfg_t *mc_board_comm_cfg(const mc_params_t *p);

/** Provided by main.c for the board's CAN receive interrupt: move the
 *  received frames into the application's ring (nothing before the
 *  application runs). */
void mc_main_can_rx(void);

/** Provided by main.c: the drive application once it runs, else NULL (the
 *  PIL board reads its probe for the host after each period). */
const mc_app_t *mc_main_app(void);

/** Start the PWM-synchronous conversions (the fast-loop interrupt source). */
void mc_board_start(void);

/** Fast-loop interrupt entry: acknowledge the interrupt source. */
void mc_board_fast_irq_ack(void);

/** Fast-loop interrupt, before the drive's fast step: apply the commands
 *  that arrived since the previous period (references, mode). */
void mc_board_apply_commands(mc_drive_t *d);

/** The period's work is complete (fast step, and the slow step when one was
 *  due: slow_ran). Called from the fast-loop interrupt or from PendSV. */
void mc_board_period_done(const mc_drive_t *d, bool slow_ran);

/** The drive refused its configuration (MC_DRIVE_CFG_* bits). Does not
 *  return: the outputs stay off. */
void mc_board_halt(uint32_t drive_cfg_err) __attribute__((noreturn));

#endif /* MC_BOARD_H */
