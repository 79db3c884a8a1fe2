/**
 * @file pwm2.h
 * @brief HAL capability: 2-phase PWM for a dual H-bridge (bipolar stepper).
 *
 * Two full bridges, one per winding (a and b). The duty of a bridge is the
 * signed average voltage across its winding as a fraction of the DC bus, in
 * [-1, 1]: +1 applies +Vbus (current driven a+ -> a-), -1 applies -Vbus, 0
 * applies zero average voltage. How the implementation modulates (bipolar or
 * unipolar, slow or fast decay) is its business; the state reports the
 * duties as accepted. As for pwm3, a new duty takes effect at the next PWM
 * update event.
 *
 * See hal/hal.h for the conventions (error codes, timing classes).
 */
#ifndef MC_HAL_PWM2_H
#define MC_HAL_PWM2_H

#include <errno.h>
#include <stdbool.h>
#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Duties set right after initialisation (zero voltage on both windings). */
#define MC_HAL_PWM2_DUTY_INIT 0.0f

typedef struct mc_hal_pwm2_state {
    float duty_a;   /**< last accepted signed duty of bridge a, [-1, 1] */
    float duty_b;   /**< last accepted signed duty of bridge b, [-1, 1] */
    float period_s; /**< PWM period [s] */
    bool enabled;   /**< false: all eight switches off (Hi-Z) */
} mc_hal_pwm2_state_t;

typedef struct mc_hal_pwm2_ops {
    /** See mc_hal_pwm2_set_duty(). */
    int (*set_duty)(void *ctx, float duty_a, float duty_b);
    /** See mc_hal_pwm2_enable(). */
    int (*enable)(void *ctx);
    /** See mc_hal_pwm2_disable(). */
    int (*disable)(void *ctx);
    /** See mc_hal_pwm2_get_state(). */
    int (*get_state)(void *ctx, mc_hal_pwm2_state_t *p_state);
} mc_hal_pwm2_ops_t;

typedef struct mc_hal_pwm2 {
    const mc_hal_pwm2_ops_t *ops;
    void *ctx;
} mc_hal_pwm2_t;

/** true if d is a valid signed duty: -1 <= d <= 1 (NaN, +-inf: false). */
static inline bool mc_hal_pwm2_duty_valid(float d)
{
    return (d >= -1.0f) && (d <= 1.0f);
}

/**
 * Set both bridge duties.                               Timing: FAST.
 * @return 0; -EINVAL if either duty is outside [-1, 1] or not finite: neither
 *         changes; -EIO hardware fault: the drive must kill the gates;
 *         -ENODEV.
 */
static inline int mc_hal_pwm2_set_duty(const mc_hal_pwm2_t *dev, float duty_a, float duty_b)
{
    if ((dev == NULL) || (dev->ops == NULL) || (dev->ops->set_duty == NULL)) {
        return -ENODEV;
    }
    return dev->ops->set_duty(dev->ctx, duty_a, duty_b);
}

/**
 * Start modulating with the last accepted duties.       Timing: SLOW.
 * @return 0 (also if already enabled); -EBUSY gate kill latched; -EIO;
 *         -ENODEV.
 */
static inline int mc_hal_pwm2_enable(const mc_hal_pwm2_t *dev)
{
    if ((dev == NULL) || (dev->ops == NULL) || (dev->ops->enable == NULL)) {
        return -ENODEV;
    }
    return dev->ops->enable(dev->ctx);
}

/**
 * All switches off, immediately. Idempotent.            Timing: ANY.
 * @return 0; -EIO outputs not confirmed off (use the gate kill); -ENODEV.
 */
static inline int mc_hal_pwm2_disable(const mc_hal_pwm2_t *dev)
{
    if ((dev == NULL) || (dev->ops == NULL) || (dev->ops->disable == NULL)) {
        return -ENODEV;
    }
    return dev->ops->disable(dev->ctx);
}

/**
 * Read back duties, period and enable state.           Timing: FAST.
 * @return 0; -EIO: *p_state unchanged; -ENODEV; -EINVAL.
 */
static inline int mc_hal_pwm2_get_state(const mc_hal_pwm2_t *dev, mc_hal_pwm2_state_t *p_state)
{
    if ((dev == NULL) || (dev->ops == NULL) || (dev->ops->get_state == NULL)) {
        return -ENODEV;
    }
    if (p_state == NULL) {
        return -EINVAL;
    }
    return dev->ops->get_state(dev->ctx, p_state);
}

#ifdef __cplusplus
}
#endif

#endif /* MC_HAL_PWM2_H */
