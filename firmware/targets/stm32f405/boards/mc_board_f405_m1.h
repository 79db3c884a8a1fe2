/**
 * @file mc_board_f405_m1.h
 * @brief The ODrive v3.6's second axis (M1) as hal/stm32f405 driver
 *        configurations, for a dual-axis image (not yet built: the image
 *        drives M0 alone, M1's gate inputs are held low by the GPIO table).
 *
 * M1's peripherals and pins (pins.csv m1_*, from ODrive commit f9b5419c,
 * Firmware/Board/v3/Inc/main.h, Src/tim.c, Src/adc.c, board.cpp):
 *   pwm3     TIM8 CH1..3 PC6/PC7/PC8, CH1N..3N PA7/PB0/PB1 (AF3), the M0
 *            board's dead time and rate; no break input (TIM8_BKIN would be
 *            PA6, the bus-voltage pin); the ADC trigger is TIM8's CC4 event
 *            (TIM8 TRGO cannot start injected conversions), 1 us before the
 *            counter peak as M0's.
 *   adc      ADC2 injected: ib on channel 13 (PC3), ic on 12 (PC2), vbus on
 *            6 (PA6, ADC12_IN6: the same divider M0's ADC1 reads, converted
 *            by ADC2 half a period later, never at the same time as ADC1);
 *            ia = -(ib + ic). The FET thermistor on channel 4 (PA4,
 *            ADC12_IN4) as a regular conversion, M0's curve. The ODrive
 *            firmware reads M1's currents as ADC2 and ADC3 regular
 *            conversions on TIM8 TRGO (Src/adc.c, board.cpp
 *            fetch_and_reset_adcs); here one ADC's injected sequence holds
 *            the axis' whole sample, as for M0, so the same driver serves
 *            both axes. ADC clock divider: ADCPRE is common to the three
 *            ADCs, so M1 writes the value M0's set-up wrote (PCLK2 / 4).
 *   encoder  TIM4 (16 bit) on PB6/PB7 (AF2), x4, the M0 board's counts per
 *            revolution and filter; index on PC15 (EXTI line 15, the
 *            EXTI15_10 interrupt, rising edge).
 *   drv_spi  M1's DRV8301 on SPI3 (shared with M0's and an absolute
 *            encoder), chip select PC14 active low, mode 1 at M0's rate;
 *            the DRV8301 settings are M0's (desc->drv8301).
 * Shared with M0: EN_GATE (PB12) and nFAULT (PD2), so M1's pwm3 honours
 * M0's fault driver (p_fault), whose config must then name TIM8 as p_tim8
 * (a gate kill stops both bridges).
 *
 * What the dual image does with these (its order): M1's GPIO to AF3 on the
 * gate pins; RCC TIM4EN, TIM8EN, ADC2EN; mc_f405_pwm3_init(M1), then
 * mc_f405_pwm3_start_phased(&m0, &m1, m0.arr - 1) with the outputs off
 * (half a PWM period between the two axes' samples); mc_f405_adc_init,
 * mc_f405_encoder_init, mc_f405_spi_init with these configs; the ADC
 * interrupt asks mc_f405_adc_jeoc_pending() of each axis' adc.
 */
#ifndef MC_BOARD_F405_M1_H
#define MC_BOARD_F405_M1_H

#include <stdint.h>

#include "mc_board_desc.h"
#include "mc_f405_hal.h"

#ifdef __cplusplus
extern "C" {
#endif

/** M1's ADC2 channels and pins (RM0090 / DS8626 pin table: PC3 ADC123_IN13,
 *  PC2 ADC123_IN12, PA6 ADC12_IN6, PA4 ADC12_IN4). */
#define MC_BOARD_F405_M1_ADC_CH_IB   13u
#define MC_BOARD_F405_M1_ADC_CH_IC   12u
#define MC_BOARD_F405_M1_ADC_CH_VBUS 6u
#define MC_BOARD_F405_M1_ADC_CH_TEMP 4u
/** RCC enable bits of M1's peripherals (RM0090 §7.3.13 APB1ENR TIM4EN,
 *  §7.3.14 APB2ENR TIM8EN, ADC2EN), for the dual image's clock set-up. */
#define MC_BOARD_F405_M1_APB1ENR_TIM4EN (1u << 2)
#define MC_BOARD_F405_M1_APB2ENR_TIM8EN (1u << 1)
#define MC_BOARD_F405_M1_APB2ENR_ADC2EN (1u << 9)
/** Index pin PC15: port C, EXTI line 15. DRV8301 chip select PC14. */
#define MC_BOARD_F405_M1_INDEX_PORT 2u
#define MC_BOARD_F405_M1_INDEX_PIN  15u
#define MC_BOARD_F405_M1_DRV_CS_PIN 14u

/** M1's registers and what it shares with M0. */
typedef struct mc_board_f405_m1_periph {
    mc_f405_tim_regs_t *p_tim8;
    mc_f405_tim_regs_t *p_tim4;
    mc_f405_adc_regs_t *p_adc2;
    mc_f405_adc_common_regs_t *p_adc_common;
    mc_f405_spi_regs_t *p_spi3;
    mc_f405_gpio_regs_t *p_gpioc; /**< PC14 chip select, PC15 index */
    mc_f405_syscfg_regs_t *p_syscfg;
    mc_f405_exti_regs_t *p_exti;
    const mc_hal_tick_t *p_tick; /**< M0's tick (TIM5) */
    mc_f405_fault_t *p_fault;    /**< M0's fault driver (shared EN_GATE, nFAULT) */
} mc_board_f405_m1_periph_t;

/** The four driver configurations of M1. */
typedef struct mc_board_f405_m1_cfg {
    mc_f405_pwm3_config_t pwm3;
    mc_f405_adc_config_t adc;
    mc_f405_encoder_config_t enc;
    mc_f405_spi_config_t drv_spi;
} mc_board_f405_m1_cfg_t;

/**
 * M1's configurations from the board's description (the M0 figures M1
 * shares: dead time, sense scaling, thermistor curve, encoder resolution,
 * DRV8301 rate) and the clocks (sysclk_hz: TIM8 at sysclk, SPI3 at sysclk
 * / 4, as mc_board_f405_setup). Writes no register.
 * @return 0 and *p_out; -EINVAL (nothing written) NULL argument or
 *         register pointer, zero clock or rate, a description without a
 *         DRV8301 or without phases b and c (not an ODrive v3.6).
 */
int mc_board_f405_m1_config(const mc_board_desc_t *p_desc,
                            const mc_board_f405_m1_periph_t *p_periph, uint32_t sysclk_hz,
                            uint32_t pwm_hz, mc_board_f405_m1_cfg_t *p_out);

#ifdef __cplusplus
}
#endif

#endif /* MC_BOARD_F405_M1_H */
