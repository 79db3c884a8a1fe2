/**
 * @file main.c
 * @brief The drive application on the STM32F405: clocks, board, drive, and
 *        the two loops in their interrupts.
 *
 *   ADC_IRQHandler  (IRQ 18, priority 0, the highest): fast loop, once per
 *                   PWM period: mc_app_fast_step() (the drive's fast step
 *                   and the application's fast-loop mark for the watchdog);
 *                   every slow_loop_div periods it pends PendSV.
 *   CAN1_RX0        (the board's, priority 8): received frames into the
 *                   application's ring (mc_main_can_rx).
 *   PendSV_Handler  (priority 15, the lowest): slow loop, mc_app_slow_step()
 *                   (the drive's slow step and the application's slow work:
 *                   commands, timeout, CAN state, telemetry, watchdog feed).
 * The two bodies are the application's functions, which the simulator's
 * one period (hal/host/include/hal_host/app_rig.hpp) calls in the same
 * order: what a scenario shows is what this image runs.
 *   main            sleeps (WFI) between interrupts.
 *
 * The application (firmware/app/app/mc_app) is bound when the board gives
 * its configuration (mc_board_app_cfg): it boots the stored configuration
 * (or the board's defaults), initialises the drive from it and starts the
 * watchdog. A board without one runs the drive alone on
 * mc_board_drive_cfg() (the PIL board when the host asks for the drive
 * alone; it binds the application when the host asks for the whole image).
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

#include "mc_app.h"
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
static mc_app_t g_app;
static mc_comm_t g_comm;         /* commissioning's state (one run at a time) */
static mc_comm_can_t g_comm_can; /* its CAN binding */
static bool g_app_on;
static volatile bool g_running;

/* Boards without an application binding (the PIL board) keep this one. */
__attribute__((weak)) const mc_app_cfg_t *mc_board_app_cfg(void)
{
    return NULL;
}

/* Boards without a CAN controller of their own (the PIL board) keep this. */
__attribute__((weak)) int mc_board_can_bitrate(uint32_t bitrate_bps)
{
    (void)bitrate_bps;
    return 0;
}

/* Boards without commissioning keep this one. */
__attribute__((weak)) const mc_comm_can_cfg_t *mc_board_comm_cfg(const mc_params_t *p)
{
    (void)p;
    return NULL;
}

void mc_main_can_rx(void)
{
    if (g_running && g_app_on) {
        (void)mc_app_can_rx_isr(&g_app);
    }
}

const mc_app_t *mc_main_app(void)
{
    return g_app_on ? &g_app : NULL;
}

void ADC_IRQHandler(void)
{
    mc_board_fast_irq_ack();
    if (!g_running) {
        return;
    }
    mc_board_apply_commands(&g_drive);
    const bool slow_due = g_app_on ? mc_app_fast_step(&g_app) : mc_drive_fast_step(&g_drive);
    if (slow_due) {
        mc_scb_pend_pendsv(); /* period_done follows the slow step */
    } else {
        mc_board_period_done(&g_drive, false);
    }
}

void PendSV_Handler(void)
{
    if (g_app_on) {
        mc_app_slow_step(&g_app);
    } else {
        mc_drive_slow_step(&g_drive);
    }
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
    if (hal == NULL) {
        mc_board_halt(MC_DRIVE_CFG_ERR_NULL);
    }
    const mc_app_cfg_t *app_cfg = mc_board_app_cfg();
    /* cppcheck-suppress knownConditionTrueFalse ; the board's strong symbol replaces the weak NULL */
    if (app_cfg != NULL) {
        /* A store that cannot be read boots the defaults (boot_status says
         * so); a configuration the drive refuses halts with the outputs off. */
        (void)mc_app_boot(&g_app, app_cfg);
        /* The configuration's CAN bit rate (a reboot parameter: it takes
         * effect here, at the boot after a SAVE). A refused rate keeps the
         * set-up's 500 kbit/s; a stored set with another rate than 125k,
         * 250k, 500k or 1M never boots (mc_params_validate, INVALID). */
        (void)mc_board_can_bitrate(g_app.params.can_bitrate_bps);
        const uint32_t aerr = mc_app_start(&g_app, &g_drive, hal, hal->can, true);
        if (aerr != MC_APP_CFG_OK) {
            mc_board_halt((g_app.drive_err != 0u) ? g_app.drive_err : MC_DRIVE_CFG_ERR_NULL);
        }
        /* Commissioning over CAN where the board offers it; a configuration
         * it refuses leaves it out (COMMISSION_CMD then answers UNSUPPORTED). */
        const mc_comm_can_cfg_t *comm_cfg = mc_board_comm_cfg(&g_app.params);
        /* cppcheck-suppress knownConditionTrueFalse ; the board's strong symbol replaces the weak NULL */
        if ((comm_cfg != NULL) &&
            (mc_comm_can_init(&g_comm_can, comm_cfg, &g_comm, &g_drive,
                              g_app.params_valid ? &g_app.srv : NULL) == MC_COMM_CAN_CFG_OK)) {
            mc_app_attach_commission(&g_app, &g_comm_can);
        }
        g_app_on = true;
    } else {
        const mc_drive_cfg_t *cfg = mc_board_drive_cfg();
        if (cfg == NULL) {
            mc_board_halt(MC_DRIVE_CFG_ERR_NULL);
        }
        const uint32_t err = mc_drive_init(&g_drive, cfg, hal);
        if (err != MC_DRIVE_CFG_OK) {
            mc_board_halt(err);
        }
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
