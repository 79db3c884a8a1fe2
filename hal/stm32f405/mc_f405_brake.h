/**
 * @file mc_f405_brake.h
 * @brief Brake-resistor chopper (hal/brake.h) on two channels of one
 *        STM32F405 general-purpose timer: a half bridge with a low switch
 *        and a high switch (the resistor conducts while the high one is on).
 *
 * The timer counts centre-aligned (CMS = 3) over period_ticks (ARR); both
 * channels are in PWM mode 2 with preload: the high channel (polarity
 * active high) is on while CNT >= CCRh, the low channel (polarity active
 * low) is on while CNT < CCRl. A duty d (capped at duty_max, which leaves
 * the low switch on long enough to charge the high driver's bootstrap)
 * gives CCRh = ARR + 1 - round(d ARR) and CCRl = CCRh - deadtime_ticks, so
 * the two switches are never on together and each waits deadtime_ticks
 * after the other turns off. Duty 0 is "resistor off, low switch on".
 *
 * Off (CCRl = 0, CCRh = ARR + 1: both switches off) after init, at
 * mc_f405_brake_off() (the fault driver's gate kill calls it through its
 * kill hook) and at every set_duty while the fault driver's kill latch is
 * set. A reset leaves both channels disabled (CCER = 0) and the pins in
 * their reset state. The pins' alternate function is the board's GPIO
 * table's (ODrive v3.6: AUX_L PB10 = TIM2_CH3, AUX_H PB11 = TIM2_CH4, AF1).
 */
#ifndef MC_F405_BRAKE_H
#define MC_F405_BRAKE_H

#include <stdint.h>

#include "hal/brake.h"
#include "mc_f405_hal.h"
#include "mc_f405_regs.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct mc_f405_brake_config {
    mc_f405_tim_regs_t *tim;        /**< the timer (TIM2 on the ODrive v3.6) */
    uint32_t ch_low;                /**< 1..4: the low switch (AUX_L) */
    uint32_t ch_high;               /**< 1..4: the high switch (AUX_H) */
    uint32_t period_ticks;          /**< ARR (centre-aligned: 2 ARR ticks a period) */
    uint32_t deadtime_ticks;        /**< >= 1, 2 deadtime_ticks < period_ticks */
    float duty_max;                 /**< (0, 1 - deadtime/period] */
    const mc_f405_fault_t *p_fault; /**< kill latch to honour, or NULL */
} mc_f405_brake_config_t;

typedef struct mc_f405_brake {
    mc_f405_brake_config_t cfg;
    mc_hal_brake_t dev; /**< the handle for mc_hal_t.brake */
} mc_f405_brake_t;

/**
 * Set the timer up (prescaler 0, ARR, centre-aligned, both channels PWM
 * mode 2 with preload and their polarity, both enabled) with both switches
 * off, and start it.
 * @return 0, or -EINVAL (NULL, no timer, channels outside 1..4 or equal,
 *         a period, dead time or duty_max outside the ranges above).
 */
int mc_f405_brake_init(mc_f405_brake_t *p_drv, const mc_f405_brake_config_t *p_cfg);

/** Both switches off (the resistor disconnected). NULL-safe; a void*
 *  argument so it can be the fault driver's kill hook. */
void mc_f405_brake_off(void *p_drv);

#ifdef __cplusplus
}
#endif

#endif /* MC_F405_BRAKE_H */
