/**
 * @file mc_board_desc.h
 * @brief A board as data: its GPIO set-up, sense scaling, thermistors, gate
 *        driver and pins, generated per board by tools/boards/mc_boards.py
 *        from the board's pins.csv and board.toml (boards/<name>/).
 *
 * Peripherals are the same on every board (the generator refuses a pin map
 * that needs another): TIM1 complementary PWM (CH1..3, CH1N..3N, optional
 * BKIN), ADC1 injected conversions, TIM3 encoder (CH1, CH2) with its index
 * on an EXTI line, TIM5 tick, CAN1, and SPI3 for a DRV8301 and an absolute
 * encoder; Hall inputs as GPIO on the encoder's pins. mc_board_f405.h
 * binds a description to the hal/stm32f405 drivers.
 */
#ifndef MC_BOARD_DESC_H
#define MC_BOARD_DESC_H

#include <stdbool.h>
#include <stdint.h>

#include "mc_drv8301.h"
#include "mc_f405_hal.h"

#ifdef __cplusplus
extern "C" {
#endif

/** mc_board_pin_t.port of a signal the board does not have. */
#define MC_BOARD_PORT_NONE 0xFFu

/** The position sensor a board has fitted by default (board.toml
 *  [encoder] type): the A/B(/Z) encoder on TIM3, an absolute encoder on
 *  SPI3 (enc_spi_cs), or Hall sensors on the encoder's pins. */
typedef enum mc_board_enc_type {
    MC_BOARD_ENC_ABI = 0,
    MC_BOARD_ENC_AS5047P = 1,
    MC_BOARD_ENC_MA732 = 2,
    MC_BOARD_ENC_HALL = 3
} mc_board_enc_type_t;

/** One pin: port 0 = A .. 8 = I, pin 0..15, asserted level. */
typedef struct mc_board_pin {
    uint8_t port;
    uint8_t pin;
    bool active_low;
} mc_board_pin_t;

/**
 * The GPIO set-up of one port: for each register the bits the board owns
 * (mask) and their value. Pins not in pins.csv keep their reset state.
 */
typedef struct mc_board_gpio_port_init {
    uint8_t port; /**< 0 = A .. 8 = I */
    uint32_t moder_mask;
    uint32_t moder;
    uint32_t otyper_mask;
    uint32_t otyper;
    uint32_t ospeedr_mask;
    uint32_t ospeedr;
    uint32_t pupdr_mask;
    uint32_t pupdr;
    uint32_t afrl_mask; /**< AFR[0]: pins 0..7 */
    uint32_t afrl;
    uint32_t afrh_mask; /**< AFR[1]: pins 8..15 */
    uint32_t afrh;
    uint32_t bsrr; /**< output levels, written before MODER */
} mc_board_gpio_port_init_t;

typedef struct mc_board_desc {
    const char *name;
    /* GPIO */
    const mc_board_gpio_port_init_t *p_gpio;
    uint32_t n_gpio;
    uint32_t gpio_port_mask; /**< bit n: port n used (RCC_AHB1ENR GPIOxEN) */
    /* TIM1 PWM */
    uint32_t pwm_hz; /**< PWM rate = fast-loop rate of the image on this board */
    uint32_t deadtime_ns;
    bool break_enable; /**< BKIN wired (an over-current comparator) */
    bool break_active_high;
    uint32_t bkin_mask; /**< MC_HAL_FAULT_* inputs on BKIN */
    /* control pins (MC_BOARD_PORT_NONE: not wired) */
    mc_board_pin_t gate_enable;
    mc_board_pin_t gate_fault;
    /* ADC1: channels (MC_F405_ADC_CH_NONE: phase not measured) and scaling */
    uint8_t adc_ch_ia;
    uint8_t adc_ch_ib;
    uint8_t adc_ch_ic;
    uint8_t adc_ch_vbus;
    float adc_vref_v;
    float shunt_ohm;
    float amp_gain_v_per_v;
    float amp_offset_v;
    float vbus_divider;
    uint16_t adc_rail_margin_counts;
    float i_sense_max_a; /**< largest current inside the rail margin */
    mc_f405_adc_temp_sensor_t temp_power_stage;
    mc_f405_adc_temp_sensor_t temp_motor;
    /* supply limits of the board (the drive's configuration may be narrower) */
    float vbus_min_v;
    float vbus_max_v;
    float vbus_nominal_v; /**< the board's rated bus (the simulator's supply) */
    /* brake chopper (brake_l/brake_h): present, and the resistor it is used with */
    bool has_brake;
    float brake_r_ohm;             /**< 0 without a chopper */
    uint8_t brake_ch_low;          /**< TIM2 channel of brake_l (AUX_L), 1..4 */
    uint8_t brake_ch_high;         /**< TIM2 channel of brake_h (AUX_H): the
                                        resistor conducts while it is on */
    uint32_t brake_period_ticks;   /**< TIM2 ARR, centre-aligned */
    uint32_t brake_deadtime_ticks; /**< between one switch off and the other on */
    float brake_duty_max;          /**< largest duty (bootstrap charge) */
    /* position sensors */
    uint32_t enc_counts_per_rev; /**< TIM3 encoder */
    uint8_t enc_input_filter;
    mc_board_enc_type_t enc_type;                 /**< fitted by default */
    mc_board_pin_t enc_index;                     /**< enc_z: the index pulse (EXTI line = pin) */
    const mc_board_gpio_port_init_t *p_gpio_hall; /**< the Hall inputs' GPIO
                                                       set-up on the encoder's
                                                       pins; NULL: none */
    uint32_t n_gpio_hall;
    mc_board_pin_t hall[3];    /**< hall_a, hall_b, hall_c (code bits 0, 1, 2) */
    mc_board_pin_t enc_spi_cs; /**< an absolute encoder's chip select on SPI3 */
    /* DRV8301 on SPI3 */
    bool has_drv8301;
    mc_drv8301_config_t drv8301;
    mc_board_pin_t drv_spi_cs;
    uint32_t drv_spi_max_hz;
} mc_board_desc_t;

/**
 * Apply a GPIO table to ports[0..8] (A..I): per port, output levels (BSRR)
 * first, then output type, speed, pulls and alternate functions, MODER
 * last, so no pin drives a wrong level or function on the way. Entries
 * whose port is NULL are skipped.
 */
void mc_board_gpio_apply(const mc_board_gpio_port_init_t *p_table, uint32_t n,
                         mc_f405_gpio_regs_t *const p_ports[MC_F405_GPIO_PORTS]);

#ifdef __cplusplus
}
#endif

#endif /* MC_BOARD_DESC_H */
