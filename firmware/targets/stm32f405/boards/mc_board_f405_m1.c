/**
 * @file mc_board_f405_m1.c
 * @brief The ODrive v3.6's second axis (M1) as driver configurations. See
 *        mc_board_f405_m1.h for the peripherals, the pins and their sources.
 */
#include "mc_board_f405_m1.h"

#include <errno.h>
#include <stddef.h>

#include "mc_board_f405.h"

#define M1_ADC_TRIGGER_LEAD_US 1u /* as M0 (mc_board_f405.c): 1 us before the peak */
#define M1_DRV_SPI_MODE        1u /* DRV8301: SCLK idle low, data captured on the falling edge */

static bool periph_complete(const mc_board_f405_m1_periph_t *p)
{
    return (p->p_tim8 != NULL) && (p->p_tim4 != NULL) && (p->p_adc2 != NULL) &&
           (p->p_adc_common != NULL) && (p->p_spi3 != NULL) && (p->p_gpioc != NULL) &&
           (p->p_syscfg != NULL) && (p->p_exti != NULL) && (p->p_tick != NULL) &&
           (p->p_fault != NULL);
}

static void pwm3_config(const mc_board_desc_t *d, const mc_board_f405_m1_periph_t *p,
                        uint32_t sysclk_hz, uint32_t pwm_hz, mc_f405_pwm3_config_t *c)
{
    *c = (mc_f405_pwm3_config_t){
        .p_tim = p->p_tim8,
        .tim = MC_F405_ADV_TIM8,
        .tim_clk_hz = sysclk_hz, /* APB2 timer clock, as TIM1 */
        .pwm_freq_hz = pwm_hz,
        .deadtime_ns = d->deadtime_ns,
        .adc_trigger_lead_ticks = (sysclk_hz / 1000000u) * M1_ADC_TRIGGER_LEAD_US,
        .adc_trigger = MC_F405_ADC_TRIG_TIM8_CC4,
        .break_enable = false, /* TIM8_BKIN is PA6, the bus-voltage input */
        .break_active_high = false,
        .high_side_active_low = false,
        .low_side_active_low = false,
        .p_fault = p->p_fault,
    };
}

static void adc_config(const mc_board_desc_t *d, const mc_board_f405_m1_periph_t *p,
                       mc_f405_adc_config_t *c)
{
    /* M0's set-up (sample times, the common ADC clock, amplifier, divider),
     * then M1's channels: ib, ic and the bus divider on ADC2, and M0's
     * thermistor network and curve on PA4 */
    mc_board_f405_adc_config(d, p->p_adc2, p->p_adc_common, p->p_tick, MC_F405_ADC_TRIG_TIM8_CC4,
                             c);
    c->ch_ia = MC_F405_ADC_CH_NONE;
    c->ch_ib = MC_BOARD_F405_M1_ADC_CH_IB;
    c->ch_ic = MC_BOARD_F405_M1_ADC_CH_IC;
    c->ch_vbus = MC_BOARD_F405_M1_ADC_CH_VBUS;
    c->temp_power_stage.channel = MC_BOARD_F405_M1_ADC_CH_TEMP;
    c->temp_motor.channel = MC_F405_ADC_CH_NONE;
}

int mc_board_f405_m1_config(const mc_board_desc_t *p_desc,
                            const mc_board_f405_m1_periph_t *p_periph, uint32_t sysclk_hz,
                            uint32_t pwm_hz, mc_board_f405_m1_cfg_t *p_out)
{
    const mc_board_desc_t *d = p_desc;
    const mc_board_f405_m1_periph_t *p = p_periph;

    if ((d == NULL) || (p == NULL) || (p_out == NULL) || !periph_complete(p) || (sysclk_hz == 0u) ||
        (pwm_hz == 0u) || !d->has_drv8301 || (d->adc_ch_ia != MC_F405_ADC_CH_NONE) ||
        (d->adc_ch_ic == MC_F405_ADC_CH_NONE)) {
        return -EINVAL;
    }
    pwm3_config(d, p, sysclk_hz, pwm_hz, &p_out->pwm3);
    adc_config(d, p, &p_out->adc);
    p_out->enc = (mc_f405_encoder_config_t){
        .p_tim = p->p_tim4,
        .counts_per_rev = d->enc_counts_per_rev,
        .counter_32bit = false, /* TIM4 is a 16-bit timer */
        .input_filter = d->enc_input_filter,
        .invert = false,
        .p_tick = p->p_tick,
        .index =
            {
                .p_exti = p->p_exti,
                .p_syscfg = p->p_syscfg,
                .port = MC_BOARD_F405_M1_INDEX_PORT,
                .pin = MC_BOARD_F405_M1_INDEX_PIN,
                .falling_edge = false, /* a high pulse, as M0's (board.cpp ENC1_Z) */
            },
    };
    p_out->drv_spi = (mc_f405_spi_config_t){
        .p_spi = p->p_spi3,
        .pclk_hz = sysclk_hz / 4u, /* APB1 */
        .max_sck_hz = d->drv_spi_max_hz,
        .mode = M1_DRV_SPI_MODE,
        .cs = {p->p_gpioc, MC_BOARD_F405_M1_DRV_CS_PIN, true},
        .cs_gap_reads = 0u, /* MC_F405_SPI_CS_GAP_READS: the DRV8301's 1.5 us */
    };
    return 0;
}
