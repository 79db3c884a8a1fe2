/**
 * @file main.c
 * @brief The drive application on the STM32F405: clocks, board, drive, and
 *        the two loops in their interrupts.
 *
 *   ADC_IRQHandler  (IRQ 18, priority 0, the highest): fast loop, once per
 *                   PWM period: mc_drive_fast_step(); every slow_loop_div
 *                   periods it pends PendSV.
 *   PendSV_Handler  (priority 15, the lowest): slow loop, mc_drive_slow_step().
 *   main            sleeps (WFI) between interrupts.
 *
 * The FPU is enabled by the reset handler; FP context stacking is lazy, so
 * both handlers may use floats and an interrupted slow step keeps its FP
 * registers.
 *
 * With MC_TARGET_FAST_DATA_IN_CCM defined (the drive board's build), the
 * drive instance lives in the 64 KiB core-coupled RAM: zero wait states and
 * no contention with DMA on the bus matrix. The emulated images leave it
 * undefined, because QEMU does not map the CCM.
 */
#include <stdbool.h>
#include <stdint.h>

#include "mc_board.h"
#include "mc_clock.h"
#include "mc_cortexm.h"
#include "mc_drive.h"
#include "mc_stm32f405.h"

#if defined(MC_TARGET_FAST_DATA_IN_CCM)
#define MC_FAST_DATA __attribute__((section(".ccmbss")))
#else
#define MC_FAST_DATA
#endif

#define MC_PRIO_FAST_LOOP 0u
#define MC_PRIO_SLOW_LOOP 15u

void ADC_IRQHandler(void);
void PendSV_Handler(void);

/* The application owns its instances (design notes: no globals in kernels,
 * app/ and the image's main own the statically allocated state). */
static mc_drive_t g_drive MC_FAST_DATA;
static volatile bool g_running;

void ADC_IRQHandler(void)
{
    mc_board_fast_irq_ack();
    if (!g_running) {
        return;
    }
    mc_board_apply_commands(&g_drive);
    if (mc_drive_fast_step(&g_drive)) {
        mc_scb_pend_pendsv(); /* period_done follows the slow step */
    } else {
        mc_board_period_done(&g_drive, false);
    }
}

void PendSV_Handler(void)
{
    mc_drive_slow_step(&g_drive);
    mc_board_period_done(&g_drive, true);
}

int main(void)
{
    const mc_clock_regs_t regs = mc_clock_regs_stm32f405();
    uint32_t sysclk_hz = 0u;
    /* MC_CLOCK_NO_RCC under QEMU; on silicon an HSE/PLL failure leaves the
     * HSI at 16 MHz, which the board sees in sysclk_hz. */
    (void)mc_clock_init_168mhz(&regs, MC_CLOCK_TIMEOUT_LOOPS, &sysclk_hz);

    const mc_hal_t *hal = mc_board_init(sysclk_hz);
    const mc_drive_cfg_t *cfg = mc_board_drive_cfg();
    if (hal == NULL || cfg == NULL) {
        mc_board_halt(MC_DRIVE_CFG_ERR_NULL);
    }
    const uint32_t err = mc_drive_init(&g_drive, cfg, hal);
    if (err != MC_DRIVE_CFG_OK) {
        mc_board_halt(err);
    }

    mc_nvic_set_priority(MC_IRQ_ADC, MC_PRIO_FAST_LOOP);
    mc_scb_set_pendsv_priority(MC_PRIO_SLOW_LOOP);
    g_running = true;
    mc_nvic_enable(MC_IRQ_ADC);
    mc_board_start();

    for (;;) {
        mc_wfi();
    }
}
