/**
 * @file wdg.h
 * @brief HAL capability: independent watchdog and the cause of the last
 *        reset.
 *
 * An independent watchdog runs from its own clock (STM32F405: the IWDG on
 * the ~32 kHz LSI RC oscillator) and resets the MCU unless it is fed within
 * its timeout. Once started it cannot be stopped (on the STM32F405 not even
 * by a debugger unless DBGMCU freezes it). A reset puts every pin in its
 * reset state (inputs), so the gate driver's inputs fall to their pull-downs
 * and the bridge is off until the image has booted and enabled it again.
 *
 * Not part of mc_hal_t: the application (firmware/app/app/mc_app.h) takes it
 * directly and feeds it only when both the fast and the slow loop have run
 * since the last feed.
 *
 * Implementations: hal/stm32f405 (mc_f405_iwdg: IWDG and RCC_CSR), hal/fake
 * (records start, feeds and a settable reset cause).
 *
 * See hal/hal.h for the conventions (error codes, timing classes).
 */
#ifndef MC_HAL_WDG_H
#define MC_HAL_WDG_H

#include <errno.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Reset-cause bits (mc_hal_wdg_reset_cause()); several may be set (a
 *  power-on also reads as a pin reset on the STM32F405: the reset circuit
 *  drives NRST). MC_HAL_WDG_RESET_NONE: no flag (emulation, or the flags
 *  were already cleared). */
#define MC_HAL_WDG_RESET_NONE      0u
#define MC_HAL_WDG_RESET_WATCHDOG  (1u << 0) /**< independent watchdog */
#define MC_HAL_WDG_RESET_WINDOW    (1u << 1) /**< window watchdog */
#define MC_HAL_WDG_RESET_BROWNOUT  (1u << 2) /**< supply below the brown-out level */
#define MC_HAL_WDG_RESET_PIN       (1u << 3) /**< NRST pin (also set by the others) */
#define MC_HAL_WDG_RESET_SOFTWARE  (1u << 4) /**< SYSRESETREQ */
#define MC_HAL_WDG_RESET_POWER_ON  (1u << 5) /**< power-on / power-down reset */
#define MC_HAL_WDG_RESET_LOW_POWER (1u << 6) /**< entering stop/standby when forbidden */

/** Longest watchdog timeout a caller may ask for [ms] (the STM32F405's IWDG
 *  reaches 32.8 s at the LSI's 32 kHz nominal rate). */
#define MC_HAL_WDG_TIMEOUT_MAX_MS 30000u

typedef struct mc_hal_wdg_ops {
    /** See mc_hal_wdg_start(). */
    int (*start)(void *ctx, uint32_t timeout_ms);
    /** See mc_hal_wdg_feed(). */
    int (*feed)(void *ctx);
    /** See mc_hal_wdg_reset_cause(). */
    int (*reset_cause)(void *ctx, uint32_t *p_cause);
} mc_hal_wdg_ops_t;

typedef struct mc_hal_wdg {
    const mc_hal_wdg_ops_t *ops;
    void *ctx;
} mc_hal_wdg_t;

/**
 * Start the watchdog (or change the timeout of a running one) and feed it.
 * The real timeout is at least timeout_ms at the nominal clock; the
 * implementation documents its clock tolerance.          Timing: SLOW.
 * @return 0; -EINVAL timeout_ms 0 or above MC_HAL_WDG_TIMEOUT_MAX_MS (nothing
 *         changed); -EIO the peripheral did not take the setting; -ENODEV.
 */
static inline int mc_hal_wdg_start(const mc_hal_wdg_t *dev, uint32_t timeout_ms)
{
    if ((dev == NULL) || (dev->ops == NULL) || (dev->ops->start == NULL)) {
        return -ENODEV;
    }
    return dev->ops->start(dev->ctx, timeout_ms);
}

/**
 * Restart the timeout (one register write).               Timing: ANY.
 * @return 0; -EBUSY not started; -ENODEV.
 */
static inline int mc_hal_wdg_feed(const mc_hal_wdg_t *dev)
{
    if ((dev == NULL) || (dev->ops == NULL) || (dev->ops->feed == NULL)) {
        return -ENODEV;
    }
    return dev->ops->feed(dev->ctx);
}

/**
 * Cause of the last reset as MC_HAL_WDG_RESET_* bits, read once at boot
 * (the implementation latches the flags at its init and clears them in the
 * hardware, so the next reset reports only its own).     Timing: SLOW.
 * @return 0 and *p_cause; -ENODEV; -EINVAL.
 */
static inline int mc_hal_wdg_reset_cause(const mc_hal_wdg_t *dev, uint32_t *p_cause)
{
    if ((dev == NULL) || (dev->ops == NULL) || (dev->ops->reset_cause == NULL)) {
        return -ENODEV;
    }
    if (p_cause == NULL) {
        return -EINVAL;
    }
    return dev->ops->reset_cause(dev->ctx, p_cause);
}

#ifdef __cplusplus
}
#endif

#endif /* MC_HAL_WDG_H */
