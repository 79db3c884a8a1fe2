/**
 * @file board_stm32f405.c
 * @brief The drive image's board binding (mc_board.h) for real hardware:
 *        one board description (boards/<name>/, chosen at build time by
 *        MC_BOARD: example, odrive36, vesc6) bound to the hal/stm32f405
 *        drivers by boards/mc_board_f405.c.
 *
 *   TIM1 PWM      the board's rate (board.toml), centre-aligned, the board's dead time; ADC trigger
 *                 TIM1 TRGO = OC4REF, 1 us before the counter peak.
 *   ADC1          injected: the board's measured phases and bus voltage;
 *                 JEOC interrupt runs the fast loop. Temperatures regular.
 *   encoder       the board's fitted sensor (board.toml [encoder] type,
 *                 mc_board_f405.h): TIM3 with its index on EXTI (the EXTI
 *                 interrupt, priority 0 as the fast loop, latches the count
 *                 at the first index), an AS5047P or MA732 on SPI3, or the
 *                 Hall inputs. tick TIM5 (32 bit, 84 MHz). CAN1 500 kbit/s: every
 *                 frame accepted until the application has loaded its
 *                 configuration, then only this node's identifiers
 *                 (mc_f405_can_set_filters, id & 0x7E0 == node << 5). The
 *                 receive interrupt drains FIFO 0 into the application's
 *                 ring (mc_main_can_rx).
 *   application   firmware/app/app/mc_app (mc_board_app_cfg): the A/B
 *                 configuration store in flash sectors 10 and 11 (128 KiB
 *                 each at 0x080C0000 / 0x080E0000, far above the image;
 *                 sectors 0..9 refused by the flash driver), the IWDG
 *                 (50 ms, 4 s around an erase) and the reset flags of
 *                 RCC_CSR, the board's defaults below (what runs when no
 *                 stored configuration is valid).
 *   update        BOOT_REQ INFO, VERSION and the confirmed ENTER answered
 *                 from this image's header (mc_image_header.h); ENTER
 *                 waits for the OK to leave, then resets into the
 *                 bootloader through the mailbox (mc_boot_handoff.h).
 *   gate driver   EN_GATE and nFAULT pins; a DRV8301 set up over SPI3
 *                 (gain, over-current threshold and mode) and verified
 *                 before the drive starts; a failed set-up halts the image
 *                 with the gates killed. SPI3 is scheduled (hal/spisched):
 *                 once the fast loop runs, the DRV8301's frames run in the
 *                 fast-loop interrupt, one per period before the drive's
 *                 step (and its encoder frame). The slow loop's end supervises it
 *                 (mc_board_f405_gate_driver_supervise): set up again after
 *                 a gate kill and release, status registers read when nFAULT
 *                 asserts (g_board.f405.drv.faults, names:
 *                 mc_drv8301_fault_name), the chip's latch reset once the
 *                 drive has recorded the fault.
 *
 * The motor defaults are the paper-002 test motor of the simulator (R 0.675
 * ohm, L 1.14 mH, psi 0.11 Wb, 4 pole pairs), current loop bandwidth 200 Hz.
 */
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "mc_app.h"
#include "mc_board.h"
#include "mc_board_comm.h"
#include "mc_board_f405.h"
#include "mc_boot_handoff.h"
#include "mc_clock.h"
#include "mc_cortexm.h"
#include "mc_f405_flash.h"
#include "mc_f405_iwdg.h"
#include "mc_image_header.h"
#include "mc_params.h"
#include "mc_stm32f405.h"

/* The board: its generated description, mc_board_<name>_desc, named by the
 * build (firmware/targets/stm32f405/CMakeLists.txt, MC_BOARD). Static
 * analysis without the build's definitions sees the example board. */
#ifndef MC_BOARD_DESC
#define MC_BOARD_DESC mc_board_example_desc
#endif
extern const mc_board_desc_t MC_BOARD_DESC;

/* The board's PWM rate (board.toml [pwm] frequency_hz, the rate mcsim runs
 * the board at) and a slow loop of about 1 kHz. */
#define PWM_HZ           (MC_BOARD_DESC.pwm_hz)
#define CURRENT_BW_RAD_S 1256.6371f /* 2 pi 200 Hz */
#define I_MAX_A          10.0f
#define I_TRIP_A         15.0f
#define DELAY_POLL_SLACK 1000u
#define SLOW_LOOP_DIV    (slow_loop_div())
#define SLOW_PERIOD_US   (1000000u * SLOW_LOOP_DIV / PWM_HZ) /* 1000 us at 20/24/30 kHz */
#define CFG_SECTOR_A     10u
#define CFG_SECTOR_B     11u
#define CFG_PROTECT_MASK 0x3FFu /* sectors 0..9: the code's side of the flash */
/* SR.BSY polls of one flash operation: a 128 KiB erase takes up to 2 s
 * (DS8626, x32), a poll at least 4 cycles at 168 MHz (84e6 per 2 s). */
#define FLASH_BUSY_POLLS 100000000u
#define WDG_TIMEOUT_MS   50u   /* 50 slow periods; >= 34 ms at the fastest LSI */
#define WDG_ERASE_MS     4000u /* >= 2.7 s at the fastest LSI: a 128 KiB erase */
#define TM_BUDGET_FRAC   0.5f
#define TX_DRAIN_POLLS   200000u /* >= 5 ms of TSR reads: the OK of ENTER leaves */

/* The slow loop's divider: about 1 kHz at the board's PWM rate (20, 24
 * and 30 at 20, 24 and 30 kHz). */
static uint32_t slow_loop_div(void)
{
    return (PWM_HZ + 500u) / 1000u;
}

void CAN1_RX0_IRQHandler(void);
void EXTI0_IRQHandler(void);
void EXTI1_IRQHandler(void);
void EXTI2_IRQHandler(void);
void EXTI3_IRQHandler(void);
void EXTI4_IRQHandler(void);
void EXTI9_5_IRQHandler(void);
void EXTI15_10_IRQHandler(void);

typedef struct drive_board {
    mc_board_f405_t f405;
    mc_drive_cfg_t cfg;
    mc_f405_flash_t flash;
    mc_f405_iwdg_t iwdg;
    mc_f405_can_filter_t node_filter[1];
    mc_params_t defaults;
    mc_app_cfg_t app;
    mc_comm_can_cfg_t comm;
} drive_board_t;

static drive_board_t g_board;

/* Peripheral register blocks at their RM0090 addresses (through uintptr_t,
 * so this file also compiles on a 64-bit host for the lint checks). */
static void *periph_at(uintptr_t a)
{
    return (void *)a; /* NOLINT(performance-no-int-to-ptr): peripheral address */
}

/* Busy wait on the tick timer: at least `us` microseconds. A read of TIM5
 * takes at least one APB1 clock (2 ticks), so the loop bound cannot end
 * the wait early. */
static void delay_us(void *ctx, uint32_t us)
{
    const mc_f405_tick_t *t = ctx;
    const uint32_t ticks = us * (t->freq_hz / 1000000u);
    uint32_t start = 0u;
    uint32_t now = 0u;
    uint32_t n;

    if (mc_hal_tick_read(&t->dev, &start) != 0) {
        return;
    }
    for (n = 0u; n < (ticks + DELAY_POLL_SLACK); n++) {
        if ((mc_hal_tick_read(&t->dev, &now) != 0) || ((now - start) >= ticks)) {
            return;
        }
    }
}

void CAN1_RX0_IRQHandler(void)
{
    /* FIFO 0 into the driver's ring, then into the application's ring */
    mc_f405_can_rx_isr(&g_board.f405.can);
    mc_main_can_rx();
}

/* The encoder's index on its EXTI line (whichever vector the board's pin
 * has; a shared vector's other lines are not this board's). */
static void index_irq(void)
{
    (void)mc_f405_encoder_index_isr(&g_board.f405.enc);
}

void EXTI0_IRQHandler(void)
{
    index_irq();
}

void EXTI1_IRQHandler(void)
{
    index_irq();
}

void EXTI2_IRQHandler(void)
{
    index_irq();
}

void EXTI3_IRQHandler(void)
{
    index_irq();
}

void EXTI4_IRQHandler(void)
{
    index_irq();
}

void EXTI9_5_IRQHandler(void)
{
    index_irq();
}

void EXTI15_10_IRQHandler(void)
{
    index_irq();
}

static int set_node_filter(void *ctx, uint32_t id, uint32_t mask)
{
    drive_board_t *b = ctx;
    if (!b->f405.can_ok) {
        return -ENODEV;
    }
    b->node_filter[0].id = id;
    b->node_filter[0].mask = mask;
    b->node_filter[0].ext = false;
    return mc_f405_can_set_filters(&b->f405.can, b->node_filter, 1u);
}

/* A confirmed ENTER (mc_app.h): the bridge is off; the OK leaves, then the
 * bootloader. */
static void enter_boot(void *ctx)
{
    const drive_board_t *b = ctx;
    for (uint32_t i = 0u;
         (i < TX_DRAIN_POLLS) && b->f405.can_ok && !mc_f405_can_tx_idle(&b->f405.can); ++i) {
    }
    mc_boot_mailbox_enter(NULL);
}

const mc_hal_t *mc_board_init(uint32_t sysclk_hz)
{
    mc_board_f405_periph_t p = {0};
    uint32_t k;

    for (k = 0u; k < MC_F405_GPIO_PORTS; k++) {
        p.p_gpio[k] = periph_at((uintptr_t)MC_F405_GPIOA_BASE + (uintptr_t)MC_F405_GPIO_STRIDE * k);
    }
    p.p_rcc_ahb1enr = periph_at((uintptr_t)MC_RCC_BASE + MC_RCC_AHB1ENR_OFS);
    p.p_rcc_apb1enr = periph_at((uintptr_t)MC_RCC_BASE + MC_RCC_APB1ENR_OFS);
    p.p_rcc_apb2enr = periph_at((uintptr_t)MC_RCC_BASE + MC_RCC_APB2ENR_OFS);
    p.p_tim1 = periph_at(MC_F405_TIM1_BASE);
    p.p_tim2 = periph_at(MC_F405_TIM2_BASE);
    p.p_tim3 = periph_at(MC_F405_TIM3_BASE);
    p.p_tim5 = periph_at(MC_F405_TIM5_BASE);
    p.p_adc1 = periph_at(MC_F405_ADC1_BASE);
    p.p_adc_common = periph_at(MC_F405_ADC_COMMON_BASE);
    p.p_can1 = periph_at(MC_F405_CAN1_BASE);
    p.p_spi3 = periph_at(MC_F405_SPI3_BASE);
    p.p_syscfg = periph_at(MC_F405_SYSCFG_BASE);
    p.p_exti = periph_at(MC_F405_EXTI_BASE);
    p.delay_us = delay_us;
    p.delay_ctx = &g_board.f405.tick;

    /* An HSE/PLL failure leaves the HSI at 16 MHz (sysclk_hz says so); 0
     * means no RCC (emulation), where the nominal clock is assumed. */
    const uint32_t clk_hz = (sysclk_hz != 0u) ? sysclk_hz : MC_CLOCK_SYSCLK_HZ;
    if (mc_board_f405_setup(&g_board.f405, &MC_BOARD_DESC, &p, clk_hz, PWM_HZ) !=
        MC_BOARD_F405_OK) {
        return NULL;
    }
    if (mc_board_f405_gate_driver_setup(&g_board.f405, &MC_BOARD_DESC, &g_board.f405.sched.dev) !=
        MC_BOARD_F405_OK) {
        return NULL;
    }
    /* From here on the fast loop owns SPI3: the DRV8301's frames go through
     * its slot (nothing in thread mode uses the bus after this). */
    mc_spisched_defer(&g_board.f405.sched);
    return &g_board.f405.hal;
}

/* The board's defaults as a parameter set: the table's defaults with this
 * board's PWM rate, slow divider, sensing and bus window, and the motor and
 * current loop of mc_board_drive_cfg (the paper-002 test motor). */
static void board_defaults(mc_params_t *p)
{
    *p = mc_params_default;
    p->pwm_hz = PWM_HZ;
    p->slow_loop_div = SLOW_LOOP_DIV;
    p->r_ohm = 0.675f;
    p->ld_h = 1.14e-3f;
    p->lq_h = 1.14e-3f;
    p->flux_wb = 0.11f;
    p->pole_pairs = 4u;
    p->v_limit_ratio = 0.95f;
    p->i_max_a = I_MAX_A;
    p->i_sense_max_a = MC_BOARD_DESC.i_sense_max_a;
    p->dead_time_s = (float)MC_BOARD_DESC.deadtime_ns * 1e-9f;
    p->encoder_cpr = MC_BOARD_DESC.enc_counts_per_rev;
    /* an absolute SPI encoder's latency (firmware/app/drive mc_drive.h):
     * the AS5047P's angle is latched at the end of the previous period's
     * frame (DAEC on), the MA732's at its frame's start less its 3 us */
    if (MC_BOARD_DESC.enc_type == MC_BOARD_ENC_AS5047P) {
        p->encoder_latency_s = 1.0f / (float)PWM_HZ;
    } else if (MC_BOARD_DESC.enc_type == MC_BOARD_ENC_MA732) {
        p->encoder_latency_s = 3e-6f;
    } else if (MC_BOARD_DESC.enc_type == MC_BOARD_ENC_HALL) {
        /* the Hall kernel on the Hall inputs (mc_board_app_cfg binds them):
         * 6 edges per electrical turn, referenced at power-up */
        p->encoder_type = MC_PARAMS_ENCODER_HALL;
        p->encoder_cpr = 6u * p->pole_pairs;
        p->angle_ref = MC_DRIVE_ANGLE_REF_STORED;
    }
    p->vbus_min_v = MC_BOARD_DESC.vbus_min_v;
    /* the board's bus limit (its description's vbus_max_v, inside what its
     * divider reads): the trip and the braking thresholds derive from it */
    p->vbus_board_max_v = MC_BOARD_DESC.vbus_max_v;
    p->vbus_v = MC_BOARD_DESC.vbus_nominal_v;
    p->vbus_max_v = 0.0f;         /* derived: min(1.5 vbus_v, vbus_board_max_v) */
    p->can_bitrate_bps = 500000u; /* the set-up's rate; a stored one applies at boot */
    /* A board without any thermistor (the example board) cannot enforce a
     * temperature limit: the drive would trip OVERTEMP at once with the
     * table's temp_max_c, so the trip is off in its defaults (a user who
     * sets it there gets OVERTEMP, the limit being unenforceable). */
    if ((MC_BOARD_DESC.temp_power_stage.channel == MC_F405_ADC_CH_NONE) &&
        (MC_BOARD_DESC.temp_motor.channel == MC_F405_ADC_CH_NONE)) {
        p->temp_max_c = 0.0f;
    }
}

const mc_app_cfg_t *mc_board_app_cfg(void)
{
    drive_board_t *b = &g_board;
    const mc_f405_flash_config_t fc = {
        .p_regs = periph_at(MC_F405_FLASH_R_BASE),
        .p_mem = periph_at(MC_F405_FLASH_MEM_BASE),
        .protect_mask = CFG_PROTECT_MASK,
        .busy_spin_max = FLASH_BUSY_POLLS,
        .hw_poll = NULL,
        .hw_ctx = NULL,
    };
    const mc_f405_iwdg_config_t wc = {
        .p_iwdg = periph_at(MC_F405_IWDG_BASE),
        .p_rcc_csr = periph_at(MC_F405_RCC_CSR_ADDR),
        .hw_poll = NULL,
        .hw_ctx = NULL,
    };
    const mc_app_cfg_t zero = {0};
    b->app = zero;
    board_defaults(&b->defaults);
    b->app.defaults = &b->defaults;
    b->app.pwm_hz_fixed = PWM_HZ;
    b->app.slow_loop_div_fixed = SLOW_LOOP_DIV;
    b->app.tm_budget_frac = TM_BUDGET_FRAC;
    if (mc_f405_flash_init(&b->flash, &fc) == 0) {
        b->app.flash = &b->flash.dev;
        b->app.flash_sectors[0] = CFG_SECTOR_A;
        b->app.flash_sectors[1] = CFG_SECTOR_B;
    }
    if (mc_f405_iwdg_init(&b->iwdg, &wc) == 0) {
        b->app.wdg = &b->iwdg.dev;
        b->app.wdg_timeout_ms = WDG_TIMEOUT_MS;
        b->app.wdg_erase_timeout_ms = WDG_ERASE_MS;
    }
    /* SPEED by the law of the speed_law parameter, POSITION by the
     * position cascade, every gain from the parameters (derived from the
     * motor values unless set: firmware/app/config/mc_params.h) */
    b->app.laws_from_params = true;
    if (MC_BOARD_DESC.enc_type == MC_BOARD_ENC_HALL) {
        b->app.hall = &b->f405.hall.dev; /* the drive's encoder: mc_drive_hall */
    }
    b->app.set_rx_filter = set_node_filter;
    b->app.filter_ctx = b;
    b->app.boot = &mc_image_boot_cfg;
    b->app.enter_boot = enter_boot;
    b->app.boot_ctx = b;
    return &b->app;
}

int mc_board_can_bitrate(uint32_t bitrate_bps)
{
    const mc_board_f405_err_t e = mc_board_f405_can_set_bitrate(&g_board.f405, bitrate_bps);
    if (e != MC_BOARD_F405_OK) {
        g_board.f405.err = e; /* for the debugger: the bus stays at 500 kbit/s */
        return -1;
    }
    return 0;
}

const mc_comm_can_cfg_t *mc_board_comm_cfg(const mc_params_t *p)
{
    mc_board_comm_cfg_from(&MC_BOARD_DESC, p, &g_board.comm);
    return &g_board.comm;
}

const mc_drive_cfg_t *mc_board_drive_cfg(void)
{
    mc_drive_cfg_t *c = &g_board.cfg;
    float kp = 0.0f;
    float ki = 0.0f;
    if (mc_foc_f32_gains_from_bandwidth(0.675f, 1.14e-3f, CURRENT_BW_RAD_S, &kp, &ki) != 0u) {
        return NULL;
    }
    /* The trip must lie inside what the board can measure. */
    if (!(I_TRIP_A < MC_BOARD_DESC.i_sense_max_a)) {
        return NULL;
    }
    c->foc.r_ohm = 0.675f;
    c->foc.ld_h = 1.14e-3f;
    c->foc.lq_h = 1.14e-3f;
    c->foc.flux_wb = 0.11f;
    c->foc.kp_d_v_per_a = kp;
    c->foc.ki_d_v_per_as = ki;
    c->foc.kp_q_v_per_a = kp;
    c->foc.ki_q_v_per_as = ki;
    c->foc.dt_s = 1.0f / (float)PWM_HZ;
    c->foc.aw = MC_PI_AW_CLAMP;
    c->foc.kaw_per_s = 0.0f;
    c->foc.limit_mode = MC_SVPWM_LIMIT_CIRCLE;
    c->foc.v_limit_ratio = 0.95f;
    c->foc.v_abs_max_v = 60.0f;
    c->foc.decouple = true;
    c->pole_pairs = 4u;
    c->encoder_offset_rad = 0.0f;
    c->speed_pll_bw_rad_s = 1000.0f;
    c->slow_loop_div = SLOW_LOOP_DIV;
    c->i_max_a = I_MAX_A;
    c->i_trip_a = I_TRIP_A;
    c->vbus_min_v = MC_BOARD_DESC.vbus_min_v;
    c->vbus_max_v = MC_BOARD_DESC.vbus_max_v;
    return c;
}

void mc_board_start(void)
{
    /* TIM1 already counts (mc_f405_pwm3_init) and triggers the ADC; the
     * fast-loop interrupt is enabled by main. CAN receive runs at a
     * priority between the two loops. */
    if (g_board.f405.hal.can != NULL) {
        mc_nvic_set_priority(MC_IRQ_CAN1_RX0, 8u);
        mc_nvic_enable(MC_IRQ_CAN1_RX0);
    }
    /* The index: at the fast loop's priority (0), so the latch waits at
     * most one fast step (the index search turns slowly: a fraction of a
     * count at its speed). */
    if ((MC_BOARD_DESC.enc_type == MC_BOARD_ENC_ABI) &&
        (mc_board_f405_exti_irq(&MC_BOARD_DESC) != 0xFFFFFFFFu)) {
        mc_nvic_set_priority(mc_board_f405_exti_irq(&MC_BOARD_DESC), 0u);
        mc_nvic_enable(mc_board_f405_exti_irq(&MC_BOARD_DESC));
    }
}

void mc_board_fast_irq_ack(void)
{
    /* JEOC is cleared by the driver's adc read in the fast step. */
}

void mc_board_apply_commands(mc_drive_t *d)
{
    /* ADC interrupt, before the drive's step (and its encoder frame): one
     * waiting DRV8301 frame on SPI3. */
    (void)mc_board_f405_fast_slot(&g_board.f405);
    /* Commands arrive over CAN (firmware/app CAN protocol), outside this
     * binding. While the DRV8301 does not hold its set-up (after a gate
     * kill until the slow loop has written it again) the drive is held in
     * an external fault: its current scaling assumes the set-up's gain. */
    if (!g_board.f405.drv_ready) {
        mc_drive_raise_fault(d, MC_DRIVE_FAULT_EXTERNAL);
    }
}

void mc_board_period_done(const mc_drive_t *d, bool slow_ran)
{
    if (!slow_ran) {
        return;
    }
    /* PendSV (slow loop) context: a few SPI frames when something happens. */
    (void)mc_board_f405_gate_driver_supervise(&g_board.f405, &MC_BOARD_DESC,
                                              &g_board.f405.sched.dev, SLOW_PERIOD_US,
                                              (d->faults & MC_DRIVE_FAULT_HW_INPUT) != 0u);
}

void mc_board_halt(uint32_t drive_cfg_err)
{
    (void)drive_cfg_err;
    if (g_board.f405.hal.fault != NULL) {
        (void)mc_hal_fault_gate_kill(g_board.f405.hal.fault);
    } else if (MC_BOARD_DESC.gate_enable.port < MC_F405_GPIO_PORTS) {
        /* Set-up failed before the fault driver ran: EN_GATE is still at
         * its disabled level from the GPIO table; keep it there. */
        mc_f405_gpio_regs_t *g =
            periph_at((uintptr_t)MC_F405_GPIOA_BASE +
                      (uintptr_t)MC_F405_GPIO_STRIDE * MC_BOARD_DESC.gate_enable.port);
        const uint32_t pin = MC_BOARD_DESC.gate_enable.pin;
        g->BSRR = MC_BOARD_DESC.gate_enable.active_low ? (1u << pin) : (1u << (pin + 16u));
    }
    for (;;) {
        mc_wfi();
    }
}
