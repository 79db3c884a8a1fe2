/**
 * @file bench_isr_board.c
 * @brief The drive image's board binding (board_stm32f405.c), unchanged,
 *        for the interrupt benchmark (bench_isr.h): mc_board_init's set-up
 *        on RAM stand-ins of the peripherals, accessors to its state.
 */
#include <string.h>

#include "bench_isr.h"

#include "board_stm32f405.c" /* NOLINT(bugprone-suspicious-include): the image's own code */

static void no_delay(void *ctx, uint32_t us)
{
    (void)ctx;
    (void)us;
}

const mc_hal_t *bench_board_init(bench_regs_t *regs)
{
    mc_board_f405_periph_t p = {0};
    memset(&g_board, 0, sizeof g_board);
    for (uint32_t k = 0u; k < MC_F405_GPIO_PORTS; k++) {
        p.p_gpio[k] = &regs->gpio[k];
    }
    p.p_rcc_ahb1enr = &regs->ahb1;
    p.p_rcc_apb1enr = &regs->apb1;
    p.p_rcc_apb2enr = &regs->apb2;
    p.p_tim1 = &regs->tim1;
    p.p_tim2 = &regs->tim2;
    p.p_tim3 = &regs->tim3;
    p.p_tim5 = &regs->tim5;
    p.p_adc1 = &regs->adc;
    p.p_adc_common = &regs->adc_common;
    p.p_can1 = &regs->can;
    p.p_spi3 = &regs->spi3;
    p.p_syscfg = &regs->syscfg;
    p.p_exti = &regs->exti;
    p.delay_us = no_delay;
    p.delay_ctx = NULL;
    regs->can.MSR = MC_F405_CAN_MSR_INAK; /* init mode acknowledged */
    if (mc_board_f405_setup(&g_board.f405, &MC_BOARD_DESC, &p, MC_CLOCK_SYSCLK_HZ, PWM_HZ) !=
        MC_BOARD_F405_OK) {
        return NULL;
    }
    g_board.f405.drv_ready = true; /* DRV8301 set-up over SPI not emulated (boot only) */
    return &g_board.f405.hal;
}

mc_board_f405_t *bench_board_f405(void)
{
    return &g_board.f405;
}

const mc_board_desc_t *bench_board_desc(void)
{
    return &MC_BOARD_DESC;
}

mc_app_cfg_t *bench_board_app_cfg(void)
{
    (void)mc_board_app_cfg();
    return &g_board.app;
}
