/**
 * @file board_stm32f405.c
 * @brief The drive board: the hal/stm32f405 drivers wired to an example
 *        3-phase inverter with an incremental encoder (ODrive v3-like pins).
 *
 * Board bring-up done here (the drivers leave it to the port): peripheral
 * clocks, GPIO alternate functions and analog pins, and the drivers' configs.
 *
 *   TIM1 PWM      CH1..3 PA8, PA9, PA10; CH1N..3N PB13, PB14, PB15 (AF1);
 *                 BKIN PA6 (AF1) from the over-current comparator (active low);
 *                 20 kHz centre-aligned, 250 ns dead time; ADC trigger TIM1
 *                 TRGO = OC4REF, 1 us before the counter peak.
 *   ADC1          injected ia PC0 (IN10), ib PC1 (IN11), vbus PA0 (IN0);
 *                 2 shunts of 0.5 mOhm, amplifier gain 40, offset 1.65 V;
 *                 bus divider 18.72; JEOC interrupt runs the fast loop.
 *   encoder       TIM3 PB4, PB5 (AF2), 2048 lines x4 = 8192 counts/rev.
 *   tick          TIM5, 32 bit, 84 MHz (no prescaler).
 *   CAN1          PB8 RX, PB9 TX (AF9), 500 kbit/s, every frame accepted.
 *   gate driver   EN_GATE PB12 (output, active high), nFAULT PD2 (input,
 *                 active low).
 *
 * The motor defaults are the paper-002 test motor of the simulator (R 0.675
 * ohm, L 1.14 mH, psi 0.11 Wb, 4 pole pairs), current loop bandwidth 200 Hz.
 */
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "mc_board.h"
#include "mc_clock.h"
#include "mc_cortexm.h"
#include "mc_f405_hal.h"
#include "mc_stm32f405.h"

#define RCC_AHB1ENR MC_REG32(MC_RCC_BASE + MC_RCC_AHB1ENR_OFS)
#define RCC_APB1ENR MC_REG32(MC_RCC_BASE + MC_RCC_APB1ENR_OFS)
#define RCC_APB2ENR MC_REG32(MC_RCC_BASE + MC_RCC_APB2ENR_OFS)
#define RCC_AHB1ENR_GPIOAEN (1u << 0)
#define RCC_AHB1ENR_GPIOBEN (1u << 1)
#define RCC_AHB1ENR_GPIOCEN (1u << 2)
#define RCC_AHB1ENR_GPIODEN (1u << 3)
#define RCC_APB1ENR_TIM3EN (1u << 1)
#define RCC_APB1ENR_TIM5EN (1u << 3)
#define RCC_APB1ENR_CAN1EN (1u << 25)
#define RCC_APB2ENR_TIM1EN (1u << 0)
#define RCC_APB2ENR_ADC1EN (1u << 8)

#define GPIO_MODE_AF 2u
#define GPIO_MODE_ANALOG 3u
#define GPIO_PORT_A 0u
#define GPIO_PORT_B 1u
#define GPIO_PORT_C 2u
#define GPIO_PORT_D 3u

#define PWM_HZ 20000u
#define CURRENT_BW_RAD_S 1256.6371f /* 2 pi 200 Hz */

void CAN1_RX0_IRQHandler(void);

typedef struct {
    mc_f405_fault_t fault;
    mc_f405_pwm3_t pwm3;
    mc_f405_tick_t tick;
    mc_f405_adc_t adc;
    mc_f405_encoder_t enc;
    mc_f405_can_t can;
    mc_drive_cfg_t cfg;
    mc_hal_t hal;
} drive_board_t;

static drive_board_t g_board;

/* Peripheral register blocks at their RM0090 addresses (through uintptr_t,
 * so this file also compiles on a 64-bit host for the lint checks). */
static mc_f405_gpio_regs_t *gpio_port(uint32_t port)
{
    const uintptr_t a = (uintptr_t)MC_F405_GPIOA_BASE + (uintptr_t)MC_F405_GPIO_STRIDE * port;
    return (mc_f405_gpio_regs_t *)a; /* NOLINT(performance-no-int-to-ptr): peripheral address */
}

static mc_f405_tim_regs_t *tim_at(uintptr_t a)
{
    return (mc_f405_tim_regs_t *)a; /* NOLINT(performance-no-int-to-ptr): peripheral address */
}

/* Pin mode (and alternate function number for GPIO_MODE_AF). */
static void pin_config(uint32_t port, uint32_t pin, uint32_t mode, uint32_t af)
{
    mc_f405_gpio_regs_t *g = gpio_port(port);
    if (mode == GPIO_MODE_AF) {
        const uint32_t idx = pin >> 3;
        const uint32_t sh = (pin & 7u) * 4u;
        g->AFR[idx] = (g->AFR[idx] & ~(0xFu << sh)) | ((af & 0xFu) << sh);
        g->OSPEEDR |= 3u << (pin * 2u); /* very high speed: sharp gate edges */
    }
    g->MODER = (g->MODER & ~(3u << (pin * 2u))) | ((mode & 3u) << (pin * 2u));
}

static void board_pins(void)
{
    RCC_AHB1ENR |= RCC_AHB1ENR_GPIOAEN | RCC_AHB1ENR_GPIOBEN | RCC_AHB1ENR_GPIOCEN |
                   RCC_AHB1ENR_GPIODEN;
    RCC_APB1ENR |= RCC_APB1ENR_TIM3EN | RCC_APB1ENR_TIM5EN | RCC_APB1ENR_CAN1EN;
    RCC_APB2ENR |= RCC_APB2ENR_TIM1EN | RCC_APB2ENR_ADC1EN;
    mc_dsb(); /* the clocks are on before the first register access */

    static const uint8_t tim1_a[] = {6u, 8u, 9u, 10u}; /* BKIN, CH1..CH3 */
    static const uint8_t tim1_b[] = {13u, 14u, 15u};   /* CH1N..CH3N */
    for (size_t i = 0u; i < sizeof tim1_a; ++i) {
        pin_config(GPIO_PORT_A, tim1_a[i], GPIO_MODE_AF, 1u);
    }
    for (size_t i = 0u; i < sizeof tim1_b; ++i) {
        pin_config(GPIO_PORT_B, tim1_b[i], GPIO_MODE_AF, 1u);
    }
    pin_config(GPIO_PORT_B, 4u, GPIO_MODE_AF, 2u); /* TIM3 CH1 */
    pin_config(GPIO_PORT_B, 5u, GPIO_MODE_AF, 2u); /* TIM3 CH2 */
    pin_config(GPIO_PORT_B, 8u, GPIO_MODE_AF, 9u); /* CAN1 RX */
    pin_config(GPIO_PORT_B, 9u, GPIO_MODE_AF, 9u); /* CAN1 TX */
    pin_config(GPIO_PORT_C, 0u, GPIO_MODE_ANALOG, 0u);
    pin_config(GPIO_PORT_C, 1u, GPIO_MODE_ANALOG, 0u);
    pin_config(GPIO_PORT_A, 0u, GPIO_MODE_ANALOG, 0u);
}

static bool board_drivers(uint32_t sysclk_hz)
{
    /* Timer clocks: APB2 timers at 2 x 84 MHz, APB1 timers at 2 x 42 MHz
     * (RM0090 section 6.2); scaled if the clock set-up fell back to HSI. */
    const uint32_t tim1_clk_hz = (sysclk_hz != 0u) ? sysclk_hz : MC_CLOCK_SYSCLK_HZ;
    const uint32_t tim_apb1_clk_hz = tim1_clk_hz / 2u;
    const uint32_t pclk1_hz = tim1_clk_hz / 4u;

    const mc_f405_fault_config_t fc = {
        .p_tim1 = tim_at(MC_F405_TIM1_BASE),
        .p_tim8 = NULL,
        .gate_driver_fault = {gpio_port(GPIO_PORT_D), 2u, true},
        .overcurrent = {gpio_port(GPIO_PORT_A), 6u, true},
        .gate_enable = {gpio_port(GPIO_PORT_B), 12u, false},
        .bkin_mask = MC_HAL_FAULT_OVERCURRENT,
    };
    if (mc_f405_fault_init(&g_board.fault, &fc) != 0) {
        return false;
    }
    const mc_f405_tick_config_t tc = {
        .p_tim = tim_at(MC_F405_TIM5_BASE),
        .tim_clk_hz = tim_apb1_clk_hz,
        .prescaler = 0u,
    };
    if (mc_f405_tick_init(&g_board.tick, &tc) != 0) {
        return false;
    }
    const mc_f405_pwm3_config_t pc = {
        .p_tim = tim_at(MC_F405_TIM1_BASE),
        .tim_clk_hz = tim1_clk_hz,
        .pwm_freq_hz = PWM_HZ,
        .deadtime_ns = 250u,
        .adc_trigger_lead_ticks = tim1_clk_hz / 1000000u, /* 1 us */
        .adc_trigger = MC_F405_ADC_TRIG_TIM1_TRGO,
        .break_enable = true,
        .break_active_high = false,
        .high_side_active_low = false,
        .low_side_active_low = false,
        .p_fault = &g_board.fault,
    };
    if (mc_f405_pwm3_init(&g_board.pwm3, &pc) != 0) {
        return false;
    }
    const mc_f405_adc_temp_sensor_t no_temp = {MC_F405_ADC_CH_NONE, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, NULL, 0u};
    const mc_f405_adc_config_t ac = {
        .p_adc = (mc_f405_adc_regs_t *)(uintptr_t)MC_F405_ADC1_BASE, /* NOLINT(performance-no-int-to-ptr) */
        .p_common = (mc_f405_adc_common_regs_t *)(uintptr_t)MC_F405_ADC_COMMON_BASE, /* NOLINT(performance-no-int-to-ptr) */
        .p_tick = &g_board.tick.dev,
        .ch_ia = 10u,
        .ch_ib = 11u,
        .ch_ic = MC_F405_ADC_CH_NONE,
        .ch_vbus = 0u,
        .smp_current = MC_F405_ADC_SMP_15,
        .smp_vbus = MC_F405_ADC_SMP_15,
        .smp_temp = MC_F405_ADC_SMP_144,
        .trigger = MC_F405_ADC_TRIG_TIM1_TRGO,
        .clk_div = 4u, /* 84 MHz / 4 = 21 MHz (max 36 MHz) */
        .jeoc_irq = true,
        .vref_v = 3.3f,
        .shunt_ohm = 0.0005f,
        .amp_gain_v_per_v = 40.0f,
        .ia_offset_v = 1.65f,
        .ib_offset_v = 1.65f,
        .ic_offset_v = 1.65f,
        .vbus_divider = 18.72f,
        .rail_margin_counts = 16u,
        .temp_power_stage = no_temp,
        .temp_motor = no_temp,
    };
    if (mc_f405_adc_init(&g_board.adc, &ac) != 0) {
        return false;
    }
    const mc_f405_encoder_config_t ec = {
        .p_tim = tim_at(MC_F405_TIM3_BASE),
        .counts_per_rev = 8192u,
        .counter_32bit = false,
        .input_filter = 4u,
        .invert = false,
        .p_tick = &g_board.tick.dev,
    };
    if (mc_f405_encoder_init(&g_board.enc, &ec) != 0) {
        return false;
    }
    const mc_f405_can_config_t cc = {
        .p_can = (mc_f405_can_regs_t *)(uintptr_t)MC_F405_CAN1_BASE, /* NOLINT(performance-no-int-to-ptr) */
        .pclk_hz = pclk1_hz,
        .bitrate_bps = 500000u,
        .sample_point_permille = 875u,
        .sjw_tq = 1u,
        .auto_bus_off_recovery = true,
        .no_auto_retransmit = false,
        .p_filters = NULL,
        .n_filters = 0u,
        .filter_bank_start = 0u,
        .rx_irq = true,
        .p_tick = &g_board.tick.dev,
    };
    /* A CAN controller that does not leave init mode (no transceiver, bus
     * stuck) does not stop the drive: it runs without CAN. */
    const bool have_can = (mc_f405_can_init(&g_board.can, &cc) == 0);

    g_board.hal.adc = &g_board.adc.dev;
    g_board.hal.pwm3 = &g_board.pwm3.dev;
    g_board.hal.pwm2 = NULL;
    g_board.hal.encoder = &g_board.enc.dev;
    g_board.hal.can = have_can ? &g_board.can.dev : NULL;
    g_board.hal.tick = &g_board.tick.dev;
    g_board.hal.fault = &g_board.fault.dev;
    return true;
}

void CAN1_RX0_IRQHandler(void)
{
    mc_f405_can_rx_isr(&g_board.can);
}

const mc_hal_t *mc_board_init(uint32_t sysclk_hz)
{
    board_pins();
    if (!board_drivers(sysclk_hz)) {
        return NULL;
    }
    return &g_board.hal;
}

const mc_drive_cfg_t *mc_board_drive_cfg(void)
{
    mc_drive_cfg_t *c = &g_board.cfg;
    float kp = 0.0f;
    float ki = 0.0f;
    if (mc_foc_f32_gains_from_bandwidth(0.675f, 1.14e-3f, CURRENT_BW_RAD_S, &kp, &ki) != 0u) {
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
    c->slow_loop_div = 20u; /* 1 kHz */
    c->i_max_a = 10.0f;
    c->i_trip_a = 15.0f;
    c->vbus_min_v = 12.0f;
    c->vbus_max_v = 56.0f;
    return c;
}

void mc_board_start(void)
{
    /* TIM1 already counts (mc_f405_pwm3_init) and triggers the ADC; the
     * fast-loop interrupt is enabled by main. CAN receive runs at a
     * priority between the two loops. */
    if (g_board.hal.can != NULL) {
        mc_nvic_set_priority(MC_IRQ_CAN1_RX0, 8u);
        mc_nvic_enable(MC_IRQ_CAN1_RX0);
    }
}

void mc_board_fast_irq_ack(void)
{
    /* JEOC is cleared by the driver's adc read in the fast step. */
}

void mc_board_apply_commands(mc_drive_t *d)
{
    /* Commands arrive over CAN (firmware/app CAN protocol), outside this
     * binding. */
    (void)d;
}

void mc_board_period_done(const mc_drive_t *d, bool slow_ran)
{
    (void)d;
    (void)slow_ran;
}

void mc_board_halt(uint32_t drive_cfg_err)
{
    (void)drive_cfg_err;
    if (g_board.hal.fault != NULL) {
        (void)mc_hal_fault_gate_kill(g_board.hal.fault);
    }
    for (;;) {
        mc_wfi();
    }
}
