/**
 * @file fault.h
 * @brief HAL capability: hardware fault inputs and the gate kill.
 *
 * Fault inputs: the gate driver's fault pin (nFAULT: under-voltage, over-
 * temperature, desaturation) and the over-current comparator. On boards
 * where an input is wired to the timer break input (STM32F405: TIM1/TIM8
 * BKIN), asserting it turns the outputs off in hardware within nanoseconds
 * and latches the gate kill; the drive learns it from mc_hal_fault_read().
 *
 * Gate kill: the last line of defence. It forces every power switch of
 * every bridge (pwm3 and pwm2) off immediately and latches: enables are then
 * refused with -EBUSY until mc_hal_fault_gate_release(). It must work when
 * everything else fails, so it does not depend on any other HAL call or on
 * driver state (STM32F405: software break event TIM1/TIM8 EGR.BG, which
 * clears MOE, plus the gate driver enable pin low; two register writes).
 *
 * See hal/hal.h for the conventions (error codes, timing classes).
 */
#ifndef MC_HAL_FAULT_H
#define MC_HAL_FAULT_H

#include <errno.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Fault input bits (mc_hal_fault_status_t active_mask / latched_mask). */
#define MC_HAL_FAULT_GATE_DRIVER (1u << 0) /**< gate driver nFAULT */
#define MC_HAL_FAULT_OVERCURRENT (1u << 1) /**< over-current comparator */
#define MC_HAL_FAULT_ALL         (MC_HAL_FAULT_GATE_DRIVER | MC_HAL_FAULT_OVERCURRENT)

typedef struct mc_hal_fault_status {
    uint32_t active_mask;  /**< MC_HAL_FAULT_* inputs asserted now */
    uint32_t latched_mask; /**< inputs asserted at any time since the last
                                successful mc_hal_fault_gate_release() */
    bool gate_killed;      /**< kill latched: all outputs forced off */
} mc_hal_fault_status_t;

typedef struct mc_hal_fault_ops {
    /** See mc_hal_fault_read(). */
    int (*read)(void *ctx, mc_hal_fault_status_t *p_status);
    /** See mc_hal_fault_gate_kill(). Cannot fail: no return value. */
    void (*gate_kill)(void *ctx);
    /** See mc_hal_fault_gate_release(). */
    int (*gate_release)(void *ctx);
} mc_hal_fault_ops_t;

typedef struct mc_hal_fault {
    const mc_hal_fault_ops_t *ops;
    void *ctx;
} mc_hal_fault_t;

/**
 * Fault inputs and kill state.                          Timing: FAST.
 * Called every PWM period by the fast loop (a GPIO read and a flag read).
 * @return 0 and *p_status filled; -EIO: *p_status unchanged (the drive
 *         treats this as a fault and kills the gates); -ENODEV; -EINVAL.
 */
static inline int mc_hal_fault_read(const mc_hal_fault_t *dev, mc_hal_fault_status_t *p_status)
{
    if ((dev == NULL) || (dev->ops == NULL) || (dev->ops->read == NULL)) {
        return -ENODEV;
    }
    if (p_status == NULL) {
        return -EINVAL;
    }
    return dev->ops->read(dev->ctx, p_status);
}

/**
 * Force all outputs off now and latch the kill.         Timing: ANY.
 *
 * Reentrant, idempotent, bounded (a few register writes), callable from
 * fault handlers and NMI. Works whatever state the other calls are in and
 * whatever they returned before. The outputs are off when it returns.
 * @return 0; -ENODEV if the board has no gate kill (the caller then falls
 *         back to mc_hal_pwm3_disable() / mc_hal_pwm2_disable()).
 */
static inline int mc_hal_fault_gate_kill(const mc_hal_fault_t *dev)
{
    if ((dev == NULL) || (dev->ops == NULL) || (dev->ops->gate_kill == NULL)) {
        return -ENODEV;
    }
    dev->ops->gate_kill(dev->ctx);
    return 0;
}

/**
 * Release the kill latch.                               Timing: SLOW.
 *
 * Clears gate_killed and latched_mask. Outputs stay disabled: the drive
 * enables them explicitly afterwards.
 * @return 0; -EBUSY if a fault input is still asserted (nothing changes);
 *         -EIO; -ENODEV.
 */
static inline int mc_hal_fault_gate_release(const mc_hal_fault_t *dev)
{
    if ((dev == NULL) || (dev->ops == NULL) || (dev->ops->gate_release == NULL)) {
        return -ENODEV;
    }
    return dev->ops->gate_release(dev->ctx);
}

#ifdef __cplusplus
}
#endif

#endif /* MC_HAL_FAULT_H */
