/**
 * @file mc_board_f405.c
 * @brief A board description bound to the hal/stm32f405 drivers. See
 *        mc_board_f405.h for the order of the steps and why.
 */
#include "mc_board_f405.h"

#include <stddef.h>

#include "mc_cortexm.h"

#define ADC_CLK_DIV               4u /* PCLK2 84 MHz / 4 = 21 MHz (max 36 MHz) */
#define ADC_TRIGGER_LEAD_US       1u /* ADC trigger 1 us before the PWM peak */
#define CAN_BITRATE_BPS           500000u
#define CAN_SAMPLE_POINT_PERMILLE 875u

static mc_f405_pin_t pin_of(const mc_board_f405_periph_t *p, mc_board_pin_t b)
{
    mc_f405_pin_t pin = {NULL, 0u, false};

    if (b.port < MC_F405_GPIO_PORTS) {
        pin.p_port = p->p_gpio[b.port];
        pin.pin = b.pin;
        pin.active_low = b.active_low;
    }
    return pin;
}

static void delay(const mc_board_f405_periph_t *p, uint32_t us)
{
    if (p->delay_us != NULL) {
        p->delay_us(p->delay_ctx, us);
    }
}

static bool has_pin(mc_board_pin_t b)
{
    return b.port < MC_F405_GPIO_PORTS;
}

static bool spi_encoder(const mc_board_desc_t *d)
{
    return (d->enc_type == MC_BOARD_ENC_AS5047P) || (d->enc_type == MC_BOARD_ENC_MA732);
}

static void clocks_on(const mc_board_desc_t *d, const mc_board_f405_periph_t *p)
{
    uint32_t apb1 =
        MC_BOARD_F405_APB1ENR_TIM3EN | MC_BOARD_F405_APB1ENR_TIM5EN | MC_BOARD_F405_APB1ENR_CAN1EN;
    uint32_t apb2 = MC_BOARD_F405_APB2ENR_TIM1EN | MC_BOARD_F405_APB2ENR_ADC1EN;

    if (d->has_drv8301 || spi_encoder(d)) {
        apb1 |= MC_BOARD_F405_APB1ENR_SPI3EN;
    }
    if (d->has_brake) {
        apb1 |= MC_BOARD_F405_APB1ENR_TIM2EN;
    }
    if (has_pin(d->enc_index)) {
        apb2 |= MC_BOARD_F405_APB2ENR_SYSCFGEN; /* EXTICR */
    }
    *p->p_rcc_ahb1enr |= d->gpio_port_mask; /* GPIOxEN = bit x */
    *p->p_rcc_apb1enr |= apb1;
    *p->p_rcc_apb2enr |= apb2;
    mc_dsb(); /* the clocks are on before the first register access */
}

static bool periph_complete(const mc_board_desc_t *d, const mc_board_f405_periph_t *p)
{
    uint32_t k;

    if ((p->p_rcc_ahb1enr == NULL) || (p->p_rcc_apb1enr == NULL) || (p->p_rcc_apb2enr == NULL) ||
        (p->p_tim1 == NULL) || (p->p_tim3 == NULL) || (p->p_tim5 == NULL) || (p->p_adc1 == NULL) ||
        (p->p_adc_common == NULL) || (p->p_can1 == NULL) ||
        ((d->has_drv8301 || spi_encoder(d)) && (p->p_spi3 == NULL)) ||
        (d->has_brake && (p->p_tim2 == NULL)) ||
        (has_pin(d->enc_index) && ((p->p_syscfg == NULL) || (p->p_exti == NULL))) ||
        (spi_encoder(d) && !has_pin(d->enc_spi_cs)) ||
        ((d->enc_type == MC_BOARD_ENC_HALL) && (d->p_gpio_hall == NULL))) {
        return false;
    }
    for (k = 0u; k < MC_F405_GPIO_PORTS; k++) {
        if (((d->gpio_port_mask >> k) & 1u) != 0u && (p->p_gpio[k] == NULL)) {
            return false;
        }
    }
    return true;
}

static mc_board_f405_err_t fail(mc_board_f405_t *b, mc_board_f405_err_t err)
{
    b->err = err;
    return err;
}

/* The brake chopper on TIM2 (APB1 timer clock), both switches off. */
static int setup_brake(mc_board_f405_t *b, const mc_board_desc_t *d,
                       const mc_board_f405_periph_t *p)
{
    const mc_f405_brake_config_t c = {
        .tim = p->p_tim2,
        .ch_low = d->brake_ch_low,
        .ch_high = d->brake_ch_high,
        .period_ticks = d->brake_period_ticks,
        .deadtime_ticks = d->brake_deadtime_ticks,
        .duty_max = d->brake_duty_max,
        .p_fault = &b->fault,
    };
    return mc_f405_brake_init(&b->brake, &c);
}

/* SPI3 shared by the fast loop and the slow loop (mc_spisched.h): the
 * DRV8301's frames direct until mc_spisched_defer. */
static int setup_sched(mc_board_f405_t *b)
{
    const mc_spisched_config_t c = {
        .p_dev = &b->spi.dev,
        .p_tick = &b->tick.dev,
        .timeout_us = MC_SPISCHED_TIMEOUT_US_DEFAULT,
        .wait = NULL,
        .wait_ctx = NULL,
    };
    return mc_spisched_init(&b->sched, &c);
}

/* An absolute encoder on SPI3: its device, its driver, its probe. */
static mc_board_f405_err_t setup_spi_encoder(mc_board_f405_t *b, const mc_board_desc_t *d,
                                             const mc_board_f405_periph_t *p, uint32_t pclk1_hz)
{
    const bool as5047p = (d->enc_type == MC_BOARD_ENC_AS5047P);
    const mc_f405_spi_config_t sc = {
        .p_spi = p->p_spi3,
        .pclk_hz = pclk1_hz,
        .max_sck_hz = as5047p ? MC_AS5047P_SPI_MAX_HZ : MC_MA732_SPI_MAX_HZ,
        .mode = (uint8_t)(as5047p ? MC_AS5047P_SPI_MODE : MC_MA732_SPI_MODE),
        .cs = pin_of(p, d->enc_spi_cs),
        .cs_gap_reads = MC_BOARD_F405_SPIENC_CS_GAP_READS,
    };
    if (mc_f405_spi_init(&b->enc_spi, &sc) != 0) {
        return MC_BOARD_F405_ERR_SPI;
    }
    if (as5047p) {
        const mc_as5047p_config_t c = {
            .p_spi = &b->enc_spi.dev,
            .p_tick = &b->tick.dev,
            .daec = true,
            .bad_reads_max = MC_BOARD_F405_SPIENC_BAD_READS,
            .diag_period = MC_BOARD_F405_SPIENC_DIAG_PERIOD,
        };
        if (mc_as5047p_init(&b->as5047p, &c) != 0) {
            return MC_BOARD_F405_ERR_SPIENC;
        }
        b->enc_probe_rc = mc_as5047p_probe(&b->as5047p);
        b->hal.encoder = &b->as5047p.dev;
    } else {
        const mc_ma732_config_t c = {
            .p_spi = &b->enc_spi.dev,
            .p_tick = &b->tick.dev,
            .parity = true,
            .bad_reads_max = MC_BOARD_F405_SPIENC_BAD_READS,
            .diag_period = MC_BOARD_F405_SPIENC_DIAG_PERIOD,
        };
        if (mc_ma732_init(&b->ma732, &c) != 0) {
            return MC_BOARD_F405_ERR_SPIENC;
        }
        b->enc_probe_rc = mc_ma732_probe(&b->ma732);
        b->hal.encoder = &b->ma732.dev;
    }
    return (b->enc_probe_rc == 0) ? MC_BOARD_F405_OK : MC_BOARD_F405_ERR_SPIENC;
}

/* The position sensor the board names (hal.encoder, or the Hall inputs). */
static mc_board_f405_err_t setup_sensor(mc_board_f405_t *b, const mc_board_desc_t *d,
                                        const mc_board_f405_periph_t *p, uint32_t pclk1_hz)
{
    b->enc_probe_rc = 0;
    b->hal.encoder = NULL;
    switch (d->enc_type) {
    case MC_BOARD_ENC_ABI:
        b->hal.encoder = &b->enc.dev;
        return MC_BOARD_F405_OK;
    case MC_BOARD_ENC_HALL: {
        mc_f405_hall_config_t hc;
        uint32_t k;
        /* the Hall inputs take over the encoder's pins */
        mc_board_gpio_apply(d->p_gpio_hall, d->n_gpio_hall, p->p_gpio);
        for (k = 0u; k < 3u; k++) {
            hc.pin[k] = pin_of(p, d->hall[k]);
        }
        return (mc_f405_hall_init(&b->hall, &hc) == 0) ? MC_BOARD_F405_OK : MC_BOARD_F405_ERR_HALL;
    }
    case MC_BOARD_ENC_AS5047P:
    case MC_BOARD_ENC_MA732:
        return setup_spi_encoder(b, d, p, pclk1_hz);
    default:
        return MC_BOARD_F405_ERR_ARG;
    }
}

void mc_board_f405_adc_config(const mc_board_desc_t *p_desc, mc_f405_adc_regs_t *p_adc,
                              mc_f405_adc_common_regs_t *p_common, const mc_hal_tick_t *p_tick,
                              mc_f405_adc_trigger_t trigger, mc_f405_adc_config_t *p_cfg)
{
    const mc_board_desc_t *d = p_desc;
    *p_cfg = (mc_f405_adc_config_t){
        .p_adc = p_adc,
        .p_common = p_common,
        .p_tick = p_tick,
        .ch_ia = d->adc_ch_ia,
        .ch_ib = d->adc_ch_ib,
        .ch_ic = d->adc_ch_ic,
        .ch_vbus = d->adc_ch_vbus,
        .smp_current = MC_F405_ADC_SMP_15,
        .smp_vbus = MC_F405_ADC_SMP_15,
        .smp_temp = MC_F405_ADC_SMP_144,
        .trigger = trigger,
        .clk_div = ADC_CLK_DIV,
        .jeoc_irq = true,
        .vref_v = d->adc_vref_v,
        .shunt_ohm = d->shunt_ohm,
        .amp_gain_v_per_v = d->amp_gain_v_per_v,
        .ia_offset_v = d->amp_offset_v,
        .ib_offset_v = d->amp_offset_v,
        .ic_offset_v = d->amp_offset_v,
        .vbus_divider = d->vbus_divider,
        .rail_margin_counts = d->adc_rail_margin_counts,
        .temp_power_stage = d->temp_power_stage,
        .temp_motor = d->temp_motor,
    };
}

mc_board_f405_err_t mc_board_f405_setup(mc_board_f405_t *p_board, const mc_board_desc_t *p_desc,
                                        const mc_board_f405_periph_t *p_periph, uint32_t sysclk_hz,
                                        uint32_t pwm_hz)
{
    const mc_board_desc_t *d = p_desc;
    const mc_board_f405_periph_t *p = p_periph;
    mc_board_f405_t *b = p_board;

    if (b == NULL) {
        return MC_BOARD_F405_ERR_ARG;
    }
    b->hal = (mc_hal_t){0};
    b->can_ok = false;
    b->drv.status = MC_DRV8301_STATUS_NOT_INIT;
    b->drv_ready = false;
    b->rearm_wait_us = 0u;
    b->nfault_seen = false;
    b->drv_latch_reset = false;
    if ((d == NULL) || (p == NULL) || (sysclk_hz == 0u) || !periph_complete(d, p)) {
        return fail(b, MC_BOARD_F405_ERR_ARG);
    }
    /* Timer and bus clocks (RM0090 §6.2; mc_clock.c sets APB1 = /4,
     * APB2 = /2, so timers run at 2 x their bus clock). */
    const uint32_t tim1_clk_hz = sysclk_hz;
    const uint32_t tim_apb1_clk_hz = sysclk_hz / 2u;
    const uint32_t pclk1_hz = sysclk_hz / 4u;

    clocks_on(d, p);
    mc_board_gpio_apply(d->p_gpio, d->n_gpio, p->p_gpio);

    const mc_f405_tick_config_t tc = {
        .p_tim = p->p_tim5,
        .tim_clk_hz = tim_apb1_clk_hz,
        .prescaler = 0u,
    };
    if (mc_f405_tick_init(&b->tick, &tc) != 0) {
        return fail(b, MC_BOARD_F405_ERR_TICK);
    }
    const mc_f405_pwm3_config_t pc = {
        .p_tim = p->p_tim1,
        .tim_clk_hz = tim1_clk_hz,
        .pwm_freq_hz = pwm_hz,
        .deadtime_ns = d->deadtime_ns,
        .adc_trigger_lead_ticks = (tim1_clk_hz / 1000000u) * ADC_TRIGGER_LEAD_US,
        .adc_trigger = MC_F405_ADC_TRIG_TIM1_TRGO,
        .break_enable = d->break_enable,
        .break_active_high = d->break_active_high,
        .high_side_active_low = false,
        .low_side_active_low = false,
        .p_fault = &b->fault,
    };
    if (mc_f405_pwm3_init(&b->pwm3, &pc) != 0) {
        return fail(b, MC_BOARD_F405_ERR_PWM);
    }
    /* EN_GATE has been low since the GPIO table; hold it for the reset
     * pulse, then the fault driver raises it. A BKIN input stays in its
     * alternate function: the fault driver only sees it through BIF. */
    delay(p, MC_BOARD_F405_GATE_RESET_US);
    if (d->has_brake && (setup_brake(b, d, p) != 0)) {
        return fail(b, MC_BOARD_F405_ERR_BRAKE);
    }
    const mc_f405_fault_config_t fc = {
        .p_tim1 = p->p_tim1,
        .p_tim8 = NULL,
        .gate_driver_fault = pin_of(p, d->gate_fault),
        .overcurrent = {NULL, 0u, false},
        .gate_enable = pin_of(p, d->gate_enable),
        .bkin_mask = d->bkin_mask,
        .kill_hook = d->has_brake ? mc_f405_brake_off : NULL,
        .kill_hook_ctx = d->has_brake ? &b->brake : NULL,
    };
    if (mc_f405_fault_init(&b->fault, &fc) != 0) {
        return fail(b, MC_BOARD_F405_ERR_FAULT);
    }
    if (d->has_drv8301) {
        delay(p, MC_BOARD_F405_GATE_STARTUP_US);
    }

    mc_f405_adc_config_t ac;
    mc_board_f405_adc_config(d, p->p_adc1, p->p_adc_common, &b->tick.dev,
                             MC_F405_ADC_TRIG_TIM1_TRGO, &ac);
    if (mc_f405_adc_init(&b->adc, &ac) != 0) {
        return fail(b, MC_BOARD_F405_ERR_ADC);
    }
    const mc_f405_encoder_config_t ec = {
        .p_tim = p->p_tim3,
        .counts_per_rev = d->enc_counts_per_rev,
        .counter_32bit = false,
        .input_filter = d->enc_input_filter,
        .invert = false,
        .p_tick = &b->tick.dev,
        .index =
            {
                .p_exti = has_pin(d->enc_index) ? p->p_exti : NULL,
                .p_syscfg = p->p_syscfg,
                .port = d->enc_index.port,
                .pin = d->enc_index.pin,
                .falling_edge = d->enc_index.active_low,
            },
    };
    if (mc_f405_encoder_init(&b->enc, &ec) != 0) {
        return fail(b, MC_BOARD_F405_ERR_ENCODER);
    }
    const mc_f405_can_config_t cc = {
        .p_can = p->p_can1,
        .pclk_hz = pclk1_hz,
        .bitrate_bps = CAN_BITRATE_BPS,
        .sample_point_permille = CAN_SAMPLE_POINT_PERMILLE,
        .sjw_tq = 1u,
        .auto_bus_off_recovery = true,
        .no_auto_retransmit = false,
        .p_filters = NULL,
        .n_filters = 0u,
        .filter_bank_start = 0u,
        .rx_irq = true,
        .p_tick = &b->tick.dev,
    };
    /* A CAN controller that does not leave init mode (no transceiver, bus
     * stuck) does not stop the drive: it runs without CAN. */
    b->can_ok = (mc_f405_can_init(&b->can, &cc) == 0);
    if (d->has_drv8301) {
        const mc_f405_spi_config_t sc = {
            .p_spi = p->p_spi3,
            .pclk_hz = pclk1_hz,
            .max_sck_hz = d->drv_spi_max_hz,
            .mode = 1u, /* DRV8301: SCLK idle low, data captured on the falling edge */
            .cs = pin_of(p, d->drv_spi_cs),
        };
        if (mc_f405_spi_init(&b->spi, &sc) != 0) {
            return fail(b, MC_BOARD_F405_ERR_SPI);
        }
    }

    if (d->has_drv8301 && (setup_sched(b) != 0)) {
        return fail(b, MC_BOARD_F405_ERR_SPI);
    }
    const mc_board_f405_err_t se = setup_sensor(b, d, p, pclk1_hz);
    if (se != MC_BOARD_F405_OK) {
        return fail(b, se);
    }

    b->hal.adc = &b->adc.dev;
    b->hal.pwm3 = &b->pwm3.dev;
    b->hal.pwm2 = NULL;
    b->hal.can = b->can_ok ? &b->can.dev : NULL;
    b->hal.tick = &b->tick.dev;
    b->hal.fault = &b->fault.dev;
    b->hal.brake = d->has_brake ? &b->brake.dev : NULL;
    b->drv_ready = !d->has_drv8301; /* a DRV8301 becomes ready when set up */
    b->err = MC_BOARD_F405_OK;
    return MC_BOARD_F405_OK;
}

mc_board_f405_err_t mc_board_f405_gate_driver_setup(mc_board_f405_t *p_board,
                                                    const mc_board_desc_t *p_desc,
                                                    const mc_hal_spi_t *p_spi)
{
    if ((p_board == NULL) || (p_desc == NULL)) {
        return MC_BOARD_F405_ERR_ARG;
    }
    if (!p_desc->has_drv8301) {
        return MC_BOARD_F405_OK;
    }
    if (mc_drv8301_init(&p_board->drv, p_spi, &p_desc->drv8301) != 0) {
        p_board->drv_ready = false;
        if (p_board->hal.fault != NULL) {
            (void)mc_hal_fault_gate_kill(p_board->hal.fault);
        }
        return fail(p_board, MC_BOARD_F405_ERR_GATE_DRIVER);
    }
    p_board->drv_ready = true;
    return MC_BOARD_F405_OK;
}

/* nFAULT level from IDR: no side effect on the fault driver's latches. */
static bool nfault_asserted(const mc_board_f405_t *b)
{
    const mc_f405_pin_t *f = &b->fault.cfg.gate_driver_fault;
    bool level;

    if (f->p_port == NULL) {
        return false;
    }
    level = ((f->p_port->IDR >> f->pin) & 1u) != 0u;
    return f->active_low ? !level : level;
}

bool mc_board_f405_gate_driver_supervise(mc_board_f405_t *p_board, const mc_board_desc_t *p_desc,
                                         const mc_hal_spi_t *p_spi, uint32_t period_us,
                                         bool drive_hw_fault)
{
    mc_board_f405_t *b = p_board;
    bool asserted;

    if ((b == NULL) || (p_desc == NULL)) {
        return false;
    }
    if (!p_desc->has_drv8301) {
        return b->drv_ready;
    }
    if (b->fault.killed) {
        b->drv_ready = false;
        b->rearm_wait_us = 0u;
        b->nfault_seen = false;
        b->drv_latch_reset = false;
        return false;
    }
    if (!b->drv_ready) {
        b->rearm_wait_us += period_us;
        if (b->rearm_wait_us >= MC_BOARD_F405_GATE_STARTUP_US) {
            b->rearm_wait_us = 0u;
            if (mc_drv8301_init(&b->drv, p_spi, &p_desc->drv8301) == 0) {
                b->drv_ready = true;
            } else if (b->hal.fault != NULL) {
                (void)mc_hal_fault_gate_kill(b->hal.fault);
            }
        }
        return b->drv_ready;
    }
    asserted = nfault_asserted(b);
    if (asserted && !b->nfault_seen) {
        (void)mc_drv8301_read_faults(&b->drv, NULL);
        b->drv_latch_reset = false;
    }
    if (asserted && drive_hw_fault && !b->drv_latch_reset) {
        (void)mc_drv8301_reset_faults(&b->drv);
        b->drv_latch_reset = true;
    }
    b->nfault_seen = asserted;
    return b->drv_ready;
}

mc_board_f405_err_t mc_board_f405_can_set_bitrate(mc_board_f405_t *p_board, uint32_t bitrate_bps)
{
    mc_f405_can_config_t cc;
    uint32_t btr = 0u;
    if (p_board == NULL) {
        return MC_BOARD_F405_ERR_ARG;
    }
    if (!p_board->can_ok) {
        return MC_BOARD_F405_OK; /* no CAN on this start: nothing to time */
    }
    cc = p_board->can.cfg;
    if (((bitrate_bps != 125000u) && (bitrate_bps != 250000u) && (bitrate_bps != 500000u) &&
         (bitrate_bps != 1000000u)) ||
        (mc_f405_can_bit_timing(cc.pclk_hz, bitrate_bps, cc.sample_point_permille, cc.sjw_tq,
                                &btr) != 0)) {
        return MC_BOARD_F405_ERR_CAN_BITRATE;
    }
    if (bitrate_bps == cc.bitrate_bps) {
        return MC_BOARD_F405_OK;
    }
    cc.bitrate_bps = bitrate_bps;
    if (mc_f405_can_init(&p_board->can, &cc) != 0) {
        p_board->can_ok = false;
        p_board->hal.can = NULL;
    }
    return MC_BOARD_F405_OK;
}

bool mc_board_f405_fast_slot(mc_board_f405_t *p_board)
{
    return (p_board != NULL) && mc_spisched_fast_slot(&p_board->sched);
}

uint32_t mc_board_f405_exti_irq(const mc_board_desc_t *p_desc)
{
    if ((p_desc == NULL) || !has_pin(p_desc->enc_index)) {
        return 0xFFFFFFFFu;
    }
    return mc_f405_exti_irq(p_desc->enc_index.pin);
}

const char *mc_board_f405_err_name(mc_board_f405_err_t err)
{
    switch (err) {
    case MC_BOARD_F405_OK:
        return "ok";
    case MC_BOARD_F405_ERR_ARG:
        return "bad description or peripheral map";
    case MC_BOARD_F405_ERR_TICK:
        return "tick timer";
    case MC_BOARD_F405_ERR_PWM:
        return "PWM timer";
    case MC_BOARD_F405_ERR_FAULT:
        return "fault pins";
    case MC_BOARD_F405_ERR_ADC:
        return "ADC";
    case MC_BOARD_F405_ERR_ENCODER:
        return "encoder timer";
    case MC_BOARD_F405_ERR_SPI:
        return "SPI";
    case MC_BOARD_F405_ERR_GATE_DRIVER:
        return "gate driver";
    case MC_BOARD_F405_ERR_CAN_BITRATE:
        return "CAN bit rate";
    case MC_BOARD_F405_ERR_SPIENC:
        return "absolute encoder";
    case MC_BOARD_F405_ERR_HALL:
        return "Hall inputs";
    case MC_BOARD_F405_ERR_BRAKE:
        return "brake chopper timer";
    default:
        return "unknown";
    }
}
