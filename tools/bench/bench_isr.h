/**
 * @file bench_isr.h
 * @brief The drive image's code as the interrupt benchmark (bench_isr.c)
 *        reaches it: bench_isr_main.c wraps the image's main.c,
 *        bench_isr_board.c its board binding board_stm32f405.c; both only
 *        add accessors to the image's statics and the set-up on RAM
 *        stand-ins of the peripherals.
 */
#ifndef MC_BENCH_ISR_H
#define MC_BENCH_ISR_H

#include <stdbool.h>
#include <stdint.h>

#include "mc_app.h"
#include "mc_board_f405.h"
#include "mc_drive.h"
#include "mc_f405_hal.h"

/* The image's handlers (main.c, board_stm32f405.c). */
void ADC_IRQHandler(void);
void PendSV_Handler(void);
void CAN1_RX0_IRQHandler(void);

/** RAM stand-ins of the board's peripherals. */
typedef struct {
    mc_f405_gpio_regs_t gpio[MC_F405_GPIO_PORTS];
    volatile uint32_t ahb1, apb1, apb2;
    mc_f405_tim_regs_t tim1, tim2, tim3, tim5;
    mc_f405_adc_regs_t adc;
    mc_f405_adc_common_regs_t adc_common;
    mc_f405_can_regs_t can;
    mc_f405_spi_regs_t spi3;
    mc_f405_syscfg_regs_t syscfg;
    mc_f405_exti_regs_t exti;
} bench_regs_t;

/* ---- bench_isr_board.c (the board binding) ---- */

/** mc_board_init on the stand-ins (DRV8301 set-up skipped, marked ready);
 *  the board's state zeroed first. NULL if the set-up failed. */
const mc_hal_t *bench_board_init(bench_regs_t *regs);
/** The board's state (drivers, hal). */
mc_board_f405_t *bench_board_f405(void);
/** The board's description. */
const mc_board_desc_t *bench_board_desc(void);
/** The board's application configuration (mc_board_app_cfg's result,
 *  writable: the bench plugs a speed law into it). */
mc_app_cfg_t *bench_board_app_cfg(void);

/* ---- bench_isr_main.c (the image's main) ---- */

/** main()'s set-up after mc_board_init: the application booted and started
 *  on hal, commissioning attached, the loops marked running (priorities as
 *  main sets them). Returns 0 or the failing step. */
int bench_image_start(const mc_hal_t *hal, const mc_app_cfg_t *app_cfg);
mc_drive_t *bench_image_drive(void);
mc_app_t *bench_image_app(void);

#endif /* MC_BENCH_ISR_H */
