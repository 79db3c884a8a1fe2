/**
 * @file boot_f405.c
 * @brief The STM32F405 bootloader (sector 0, firmware/boot/README.md): at
 *        every reset it checks the application image and starts it, or
 *        stays and serves the update protocol on CAN1.
 *
 * At reset, before any clock or peripheral is touched:
 *   1. a running independent watchdog (the application started it, then
 *      reset into here) gets its longest timeout (32 s), so the checks below
 *      cannot be cut by it; a stopped one stays stopped;
 *   2. the mailbox is read and cleared (the application's request);
 *   3. the decision (mc_boot_start.h): the image check over the slot, the
 *      node id and bit rate from the configuration store (read only);
 *   4. a valid image without a request is started as the reset left the
 *      core (HSI 16 MHz, no interrupt enabled; the check takes about 8
 *      cycles per byte there, 60 ms for 128 KiB).
 * Otherwise (update mode): clock 168 MHz (mc_clock.h), the board's GPIO
 * table (as the application applies it first: gate driver disabled, the
 * bridge's inputs low or floating with the driver's pull-downs; no timer
 * runs), TIM5 as the millisecond clock, CAN1 at the stored bit rate with
 * its receive interrupt and a hardware filter passing only this node's 32
 * identifiers, the IWDG started at 4 s (a 128 KiB sector erase
 * takes up to 2 s) and fed in the loop. The loop serves mc_boot_update and
 * resets after COMMIT or RUN, once the last reply has left.
 *
 * The flash driver refuses every sector but the slot's (MC_BOOT_PROTECT_MASK):
 * the bootloader can neither erase itself nor touch the configuration.
 */
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "mc_board_desc.h"
#include "mc_boot_handoff.h"
#include "mc_boot_layout.h"
#include "mc_boot_run.h"
#include "mc_boot_start.h"
#include "mc_clock.h"
#include "mc_cortexm.h"
#include "mc_f405_flash.h"
#include "mc_f405_hal.h"
#include "mc_f405_iwdg.h"
#include "mc_stm32f405.h"

#ifndef MC_BOARD_DESC
#define MC_BOARD_DESC mc_board_example_desc
#endif
#ifndef MC_BOOT_BOARD_ID
#define MC_BOOT_BOARD_ID MC_BOOT_BOARD_EXAMPLE
#endif
extern const mc_board_desc_t MC_BOARD_DESC;

#define CAN_SAMPLE_POINT_PERMILLE 875u       /* as the application's set-up */
#define FLASH_BUSY_POLLS          100000000u /* >= 2 s at 168 MHz (board_stm32f405.c) */
#define WDG_TIMEOUT_MS            4000u
#define RCC_AHB1ENR               MC_REG32(MC_RCC_BASE + MC_RCC_AHB1ENR_OFS)
#define RCC_APB1ENR               MC_REG32(MC_RCC_BASE + MC_RCC_APB1ENR_OFS)
#define RCC_APB1ENR_TIM5EN        (1u << 3)
#define RCC_APB1ENR_CAN1EN        (1u << 25)
#define PRIO_CAN_RX               8u
#define RCC_CSR_LSIRDY            (1u << 1) /* RM0090 7.3.21 */
#define NODE_MASK                 0x7E0u    /* the node bits of an 11-bit id */

void CAN1_RX0_IRQHandler(void);

typedef struct {
    mc_f405_flash_t flash;
    mc_f405_tick_t tick;
    mc_f405_can_t can;
    mc_f405_iwdg_t iwdg;
    mc_f405_can_filter_t node_filter[1];
    mc_boot_crc_table_t crc;
    mc_cfg_store_t store;
    mc_boot_start_t start;
    mc_boot_update_t upd;
    uint32_t ms;        /* the millisecond clock */
    uint32_t tick_last; /* TIM5 at the last update of ms */
    uint32_t tick_frac; /* ticks not yet a millisecond */
    uint32_t ticks_1ms; /* TIM5 ticks per millisecond */
} boot_t;

static boot_t g_boot;

static void *periph_at(uintptr_t a)
{
    return (void *)a; /* NOLINT(performance-no-int-to-ptr): peripheral address */
}

/* A running IWDG (the application's, 50 ms) gets the longest timeout before
 * the image check: unlock, PR /256, RLR max, reload. A running IWDG keeps
 * the LSI on (RCC_CSR.LSIRDY); without it nothing is written (the update of
 * PR and RLR would never complete with the LSI off). */
static void iwdg_stretch(void)
{
    mc_f405_iwdg_regs_t *w = periph_at(MC_F405_IWDG_BASE);
    if ((MC_REG32(MC_F405_RCC_CSR_ADDR) & RCC_CSR_LSIRDY) == 0u) {
        return;
    }
    w->KR = MC_F405_IWDG_KEY_UNLOCK;
    w->PR = MC_F405_IWDG_PR_MAX;
    w->RLR = MC_F405_IWDG_RLR_MAX;
    for (uint32_t i = 0u; (i < MC_F405_IWDG_SR_POLLS) && (w->SR != 0u); ++i) {
    }
    /* cppcheck-suppress redundantAssignment ; KR is a write-only key register: each write acts */
    w->KR = MC_F405_IWDG_KEY_RELOAD;
}

static mc_boot_slot_t slot(void)
{
    return mc_boot_slot_layout1(&g_boot.flash.dev, MC_BOOT_BOARD_ID, &g_boot.crc);
}

static void decide(bool asked)
{
    const mc_f405_flash_config_t fc = {
        .p_regs = periph_at(MC_F405_FLASH_R_BASE),
        .p_mem = periph_at(MC_F405_FLASH_MEM_BASE),
        .protect_mask = MC_BOOT_PROTECT_MASK,
        .busy_spin_max = FLASH_BUSY_POLLS,
        .hw_poll = NULL,
        .hw_ctx = NULL,
    };
    mc_boot_start_cfg_t sc;
    (void)mc_f405_flash_init(&g_boot.flash, &fc);
    mc_boot_crc_table_init(&g_boot.crc);
    sc.slot = slot();
    sc.store.flash = &g_boot.flash.dev;
    sc.store.sector[0] = MC_BOOT_CFG_SECTOR_A;
    sc.store.sector[1] = MC_BOOT_CFG_SECTOR_B;
    sc.store.axis = 0u; /* the node id and bit rate it listens with: axis 0's */
    sc.requested = asked;
    mc_boot_start_decide(&sc, &g_boot.store, &g_boot.start);
}

/* The peripherals of update mode; false if CAN could not start. */
static bool peripherals(uint32_t sysclk_hz)
{
    mc_f405_gpio_regs_t *ports[MC_F405_GPIO_PORTS];
    for (uint32_t k = 0u; k < MC_F405_GPIO_PORTS; k++) {
        ports[k] = periph_at((uintptr_t)MC_F405_GPIOA_BASE + (uintptr_t)MC_F405_GPIO_STRIDE * k);
    }
    RCC_AHB1ENR |= MC_BOARD_DESC.gpio_port_mask;
    RCC_APB1ENR |= RCC_APB1ENR_TIM5EN | RCC_APB1ENR_CAN1EN;
    mc_dsb();
    mc_board_gpio_apply(MC_BOARD_DESC.p_gpio, MC_BOARD_DESC.n_gpio, ports);
    const mc_f405_tick_config_t tc = {periph_at(MC_F405_TIM5_BASE), sysclk_hz / 2u, 0u};
    (void)mc_f405_tick_init(&g_boot.tick, &tc);
    g_boot.ticks_1ms = g_boot.tick.freq_hz / 1000u;
    g_boot.node_filter[0].id = (uint32_t)g_boot.start.node_id << 5;
    g_boot.node_filter[0].mask = NODE_MASK;
    g_boot.node_filter[0].ext = false;
    const mc_f405_can_config_t cc = {
        .p_can = periph_at(MC_F405_CAN1_BASE),
        .pclk_hz = sysclk_hz / 4u,
        .bitrate_bps = g_boot.start.bitrate_bps,
        .sample_point_permille = CAN_SAMPLE_POINT_PERMILLE,
        .sjw_tq = 1u,
        .auto_bus_off_recovery = true,
        .no_auto_retransmit = false,
        .p_filters = g_boot.node_filter, /* only this node's 32 identifiers */
        .n_filters = 1u,
        .filter_bank_start = 0u,
        .rx_irq = true,
        .p_tick = &g_boot.tick.dev,
    };
    if (mc_f405_can_init(&g_boot.can, &cc) != 0) {
        return false;
    }
    mc_nvic_set_priority(MC_IRQ_CAN1_RX0, PRIO_CAN_RX);
    mc_nvic_enable(MC_IRQ_CAN1_RX0);
    const mc_f405_iwdg_config_t wc = {periph_at(MC_F405_IWDG_BASE), periph_at(MC_F405_RCC_CSR_ADDR),
                                      NULL, NULL};
    if (mc_f405_iwdg_init(&g_boot.iwdg, &wc) == 0) {
        (void)mc_hal_wdg_start(&g_boot.iwdg.dev, WDG_TIMEOUT_MS);
    }
    return true;
}

void CAN1_RX0_IRQHandler(void)
{
    mc_f405_can_rx_isr(&g_boot.can);
}

/* The millisecond clock from TIM5 (wraps with its 32 bits). */
static uint32_t now_ms(void)
{
    uint32_t t = 0u;
    (void)mc_hal_tick_read(&g_boot.tick.dev, &t);
    g_boot.tick_frac += t - g_boot.tick_last;
    g_boot.tick_last = t;
    while ((g_boot.ticks_1ms != 0u) && (g_boot.tick_frac >= g_boot.ticks_1ms)) {
        g_boot.tick_frac -= g_boot.ticks_1ms;
        g_boot.ms++;
    }
    return g_boot.ms;
}

static uint32_t board_now_ms(void *ctx)
{
    (void)ctx;
    return now_ms();
}

static void board_feed(void *ctx)
{
    (void)ctx;
    (void)mc_hal_wdg_feed(&g_boot.iwdg.dev);
}

static bool board_tx_idle(void *ctx)
{
    (void)ctx;
    return mc_f405_can_tx_idle(&g_boot.can);
}

static void board_reset(void *ctx)
{
    (void)ctx;
    mc_boot_system_reset();
}

static void serve(void)
{
    mc_boot_update_cfg_t uc;
    mc_boot_board_t b;
    uc.slot = slot();
    uc.node_id = g_boot.start.node_id;
    uc.reason = (uint8_t)g_boot.start.reason;
    b.can = &g_boot.can.dev;
    b.now_ms = board_now_ms;
    b.idle = NULL; /* poll: the receive interrupt fills the driver's ring */
    b.feed = board_feed;
    b.tx_idle = board_tx_idle;
    b.reset = board_reset;
    b.ctx = NULL;
    (void)mc_boot_run(&g_boot.upd, &uc, &b);
    mc_boot_system_reset(); /* a slot this map cannot have: start over */
}

int main(void)
{
    iwdg_stretch();
    decide(mc_boot_mailbox_take());
    if (g_boot.start.reason == MC_BOOT_IMG_OK) {
        mc_boot_start_image(MC_BOOT_APP_ADDR);
    }
    const mc_clock_regs_t regs = mc_clock_regs_stm32f405();
    uint32_t sysclk_hz = 0u;
    (void)mc_clock_init_168mhz(&regs, MC_CLOCK_TIMEOUT_LOOPS, &sysclk_hz);
    if (!peripherals((sysclk_hz != 0u) ? sysclk_hz : MC_CLOCK_SYSCLK_HZ)) {
        mc_boot_system_reset(); /* no CAN: try again from reset (the IWDG would too) */
    }
    mc_irq_enable();
    serve();
    return 0;
}
