/**
 * @file pwm3.h
 * @brief HAL capability: 3-phase inverter PWM (six switches, three legs).
 *
 * On the STM32F405: TIM1 centre-aligned, complementary outputs with hardware
 * dead time, preloaded compare registers (a new duty takes effect at the next
 * update event, so the duty computed from sample k drives period k+1), main
 * output enable (MOE) as the enable, the break input as the hardware kill.
 *
 * Duty of a phase = fraction of the PWM period its high-side switch is on,
 * in [0, 1]: 0 connects the phase to the negative rail for the whole period,
 * 1 to the positive rail, 0.5 on all three phases is the zero vector. Dead
 * time and minimum-pulse handling are the implementation's business; the
 * state reports the duties as accepted.
 *
 * See hal/hal.h for the conventions (error codes, timing classes).
 */
#ifndef MC_HAL_PWM3_H
#define MC_HAL_PWM3_H

#include <errno.h>
#include <stdbool.h>
#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Duties set right after initialisation (zero vector). */
#define MC_HAL_PWM3_DUTY_INIT 0.5f

/** What the outputs are doing now. */
typedef struct mc_hal_pwm3_state {
    float duty_a;   /**< last accepted duty of phase a, [0, 1] */
    float duty_b;   /**< last accepted duty of phase b, [0, 1] */
    float duty_c;   /**< last accepted duty of phase c, [0, 1] */
    float period_s; /**< PWM period [s] (fixed by the implementation's
                         config; e.g. 50e-6 for 20 kHz) */
    bool enabled;   /**< true: switches are modulating; false: all six
                         switches off (Hi-Z, safe torque off) */
} mc_hal_pwm3_state_t;

typedef struct mc_hal_pwm3_ops {
    /** See mc_hal_pwm3_set_duty(). */
    int (*set_duty)(void *ctx, float duty_a, float duty_b, float duty_c);
    /** See mc_hal_pwm3_enable(). */
    int (*enable)(void *ctx);
    /** See mc_hal_pwm3_disable(). */
    int (*disable)(void *ctx);
    /** See mc_hal_pwm3_get_state(). */
    int (*get_state)(void *ctx, mc_hal_pwm3_state_t *p_state);
} mc_hal_pwm3_ops_t;

typedef struct mc_hal_pwm3 {
    const mc_hal_pwm3_ops_t *ops;
    void *ctx;
} mc_hal_pwm3_t;

/**
 * true if d is a valid duty: 0 <= d <= 1. NaN and +-inf are invalid (every
 * comparison with NaN is false). Implementations use this so that all of
 * them reject the same values.
 */
static inline bool mc_hal_pwm3_duty_valid(float d)
{
    return (d >= 0.0f) && (d <= 1.0f);
}

/**
 * Set the three duties.                                 Timing: FAST.
 *
 * Called once per PWM period from the fast loop. Writes the preload
 * registers: the new duties take effect at the next PWM update event. Also
 * accepted while disabled (the values are then used on enable).
 * @return 0; -EINVAL if any duty is outside [0, 1] or not finite: no duty
 *         changes (all three are checked before any is written), the
 *         previous duties stay in force; -EIO hardware fault: duties
 *         unspecified, the drive must kill the gates; -ENODEV.
 */
static inline int mc_hal_pwm3_set_duty(const mc_hal_pwm3_t *dev, float duty_a, float duty_b,
                                       float duty_c)
{
    if ((dev == NULL) || (dev->ops == NULL) || (dev->ops->set_duty == NULL)) {
        return -ENODEV;
    }
    return dev->ops->set_duty(dev->ctx, duty_a, duty_b, duty_c);
}

/**
 * Start modulating with the last accepted duties.       Timing: SLOW.
 *
 * Idempotent (enabling an enabled output returns 0). Set the duties first:
 * after initialisation they are MC_HAL_PWM3_DUTY_INIT.
 * @return 0; -EBUSY if the gate kill is latched (hal/fault.h): outputs stay
 *         off until mc_hal_fault_gate_release() succeeds; -EIO hardware
 *         fault: outputs stay off; -ENODEV.
 */
static inline int mc_hal_pwm3_enable(const mc_hal_pwm3_t *dev)
{
    if ((dev == NULL) || (dev->ops == NULL) || (dev->ops->enable == NULL)) {
        return -ENODEV;
    }
    return dev->ops->enable(dev->ctx);
}

/**
 * Stop modulating: all six switches off (Hi-Z).        Timing: ANY.
 *
 * Takes effect immediately (not at the next period). Idempotent. Keeps the
 * duties. This is the normal stop; mc_hal_fault_gate_kill() is the one that
 * cannot fail.
 * @return 0; -EIO if the implementation could not confirm the outputs are
 *         off: the caller must then use mc_hal_fault_gate_kill(); -ENODEV.
 */
static inline int mc_hal_pwm3_disable(const mc_hal_pwm3_t *dev)
{
    if ((dev == NULL) || (dev->ops == NULL) || (dev->ops->disable == NULL)) {
        return -ENODEV;
    }
    return dev->ops->disable(dev->ctx);
}

/**
 * Read back duties, period and enable state.           Timing: FAST.
 * @return 0 and *p_state filled; -EIO: *p_state unchanged; -ENODEV; -EINVAL.
 */
static inline int mc_hal_pwm3_get_state(const mc_hal_pwm3_t *dev, mc_hal_pwm3_state_t *p_state)
{
    if ((dev == NULL) || (dev->ops == NULL) || (dev->ops->get_state == NULL)) {
        return -ENODEV;
    }
    if (p_state == NULL) {
        return -EINVAL;
    }
    return dev->ops->get_state(dev->ctx, p_state);
}

/**
 * PWM period [s] (convenience over mc_hal_pwm3_get_state()). Timing: FAST.
 * @return as mc_hal_pwm3_get_state(); *p_period_s unchanged on error.
 */
static inline int mc_hal_pwm3_get_period_s(const mc_hal_pwm3_t *dev, float *p_period_s)
{
    mc_hal_pwm3_state_t st;
    int rc;

    if (p_period_s == NULL) {
        return -EINVAL;
    }
    rc = mc_hal_pwm3_get_state(dev, &st);
    if (rc == 0) {
        *p_period_s = st.period_s;
    }
    return rc;
}

#ifdef __cplusplus
}
#endif

#endif /* MC_HAL_PWM3_H */
