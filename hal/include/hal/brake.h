/**
 * @file brake.h
 * @brief Brake-resistor chopper: a switch that connects a resistor across
 *        the DC bus at a PWM duty, so braking energy the supply cannot take
 *        back is burnt instead of charging the bus capacitor.
 *
 * Optional (mc_hal_t.brake may be NULL: the board has no brake resistor).
 * The duty is the fraction of each chopper period the resistor conducts;
 * the resistor takes d * vbus^2 / R on average. The drive computes the duty
 * from the bus voltage every fast step (mc_drive.h, brake_on_v..brake_full_v).
 *
 * Implementations: hal/host (the simulated DC link, mcsim::DcLink), hal/fake
 * (records the duty), hal/stm32f405 (mc_f405_brake: one timer channel in PWM
 * mode 1; on the ODrive v3.6 the AUX_L gate, PB10 = TIM2_CH3, AF1, with the
 * complementary AUX_H at PB11 = TIM2_CH4 held off; a board without a chopper
 * has no handle).
 *
 * See hal/hal.h for the conventions (error codes, timing classes).
 */
#ifndef MC_HAL_BRAKE_H
#define MC_HAL_BRAKE_H

#include <errno.h>
#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct mc_hal_brake_ops {
    /** See mc_hal_brake_set_duty(). */
    int (*set_duty)(void *ctx, float duty);
} mc_hal_brake_ops_t;

typedef struct mc_hal_brake {
    const mc_hal_brake_ops_t *ops;
    void *ctx;
} mc_hal_brake_t;

/**
 * Chopper duty in [0, 1] (0: resistor off), in force from the next chopper
 * period on.                                            Timing: FAST.
 * @return 0; -EINVAL (NaN or outside [0, 1]: nothing changed); -ENODEV.
 */
static inline int mc_hal_brake_set_duty(const mc_hal_brake_t *dev, float duty)
{
    if ((dev == NULL) || (dev->ops == NULL) || (dev->ops->set_duty == NULL)) {
        return -ENODEV;
    }
    return dev->ops->set_duty(dev->ctx, duty);
}

#ifdef __cplusplus
}
#endif

#endif /* MC_HAL_BRAKE_H */
