/**
 * @file mc_f405_brake.h
 * @brief Brake-resistor chopper (hal/brake.h) on one STM32F405 timer
 *        channel in PWM mode 1.
 *
 * The timer (its ARR, prescaler, output-compare mode, CCER enable and the
 * pin's alternate function) is set up by the board's start-up code; this
 * driver only writes the compare register: CCRx = duty * (ARR + 1), which
 * keeps the output high for that fraction of the period (PWM mode 1,
 * up-counting). ODrive v3.6: AUX_L at PB10 = TIM2_CH3 (AF1); the high-side
 * AUX_H at PB11 = TIM2_CH4 must stay off (CCR4 = 0). Never left on by a
 * reset: the timer's reset value CCR = 0 is "resistor off".
 */
#ifndef MC_F405_BRAKE_H
#define MC_F405_BRAKE_H

#include <stdint.h>

#include "hal/brake.h"
#include "mc_f405_regs.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct mc_f405_brake_config {
    mc_f405_tim_regs_t *tim; /**< the timer (TIM2 on the ODrive v3.6) */
    uint32_t channel;        /**< 1..4: the channel driving the low-side gate */
} mc_f405_brake_config_t;

typedef struct mc_f405_brake {
    mc_f405_brake_config_t cfg;
    mc_hal_brake_t dev; /**< the handle for mc_hal_t.brake */
} mc_f405_brake_t;

/** 0, or -EINVAL (NULL, no timer, channel outside 1..4). Sets duty 0. */
int mc_f405_brake_init(mc_f405_brake_t *p_drv, const mc_f405_brake_config_t *p_cfg);

#ifdef __cplusplus
}
#endif

#endif /* MC_F405_BRAKE_H */
