/**
 * @file tick.h
 * @brief HAL capability: free-running tick counter.
 *
 * A 32-bit up-counter at a fixed frequency that wraps from 0xFFFFFFFF to 0
 * (STM32F405: the DWT cycle counter at 168 MHz wraps every 25.6 s; a 32-bit
 * timer at 1 MHz every 71.6 min). Timestamps in ADC and encoder samples are
 * in these ticks. Measure intervals with mc_hal_tick_elapsed(), which is
 * correct across one wrap; an interval longer than 2^32 ticks cannot be
 * measured with one pair of reads.
 *
 * See hal/hal.h for the conventions (error codes, timing classes).
 */
#ifndef MC_HAL_TICK_H
#define MC_HAL_TICK_H

#include <errno.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct mc_hal_tick_ops {
    /** See mc_hal_tick_read(). */
    int (*read)(void *ctx, uint32_t *p_ticks);
    /** See mc_hal_tick_get_freq_hz(). */
    int (*get_freq_hz)(void *ctx, uint32_t *p_freq_hz);
} mc_hal_tick_ops_t;

typedef struct mc_hal_tick {
    const mc_hal_tick_ops_t *ops;
    void *ctx;
} mc_hal_tick_t;

/**
 * Current counter value [ticks].                        Timing: ANY.
 * One register read; monotonic modulo 2^32.
 * @return 0; -ENODEV; -EINVAL.
 */
static inline int mc_hal_tick_read(const mc_hal_tick_t *dev, uint32_t *p_ticks)
{
    if ((dev == NULL) || (dev->ops == NULL) || (dev->ops->read == NULL)) {
        return -ENODEV;
    }
    if (p_ticks == NULL) {
        return -EINVAL;
    }
    return dev->ops->read(dev->ctx, p_ticks);
}

/**
 * Counter frequency [Hz], > 0, constant after init.     Timing: ANY.
 * @return 0; -ENODEV; -EINVAL.
 */
static inline int mc_hal_tick_get_freq_hz(const mc_hal_tick_t *dev, uint32_t *p_freq_hz)
{
    if ((dev == NULL) || (dev->ops == NULL) || (dev->ops->get_freq_hz == NULL)) {
        return -ENODEV;
    }
    if (p_freq_hz == NULL) {
        return -EINVAL;
    }
    return dev->ops->get_freq_hz(dev->ctx, p_freq_hz);
}

/**
 * Ticks from `since_ticks` to `now_ticks`, correct across a wrap of the
 * counter (unsigned arithmetic is modulo 2^32 in C): e.g. since 0xFFFFFFF0,
 * now 0x10 gives 0x20. Valid while the true interval is below 2^32 ticks.
 */
static inline uint32_t mc_hal_tick_elapsed(uint32_t now_ticks, uint32_t since_ticks)
{
    return now_ticks - since_ticks;
}

/**
 * Convert a tick count to microseconds, rounded down, exact integer
 * arithmetic (no float). freq_hz == 0 gives 0 (no frequency, no time).
 * The result fits: 2^32 ticks at 1 Hz is 4.3e15 us < 2^64.
 */
static inline uint64_t mc_hal_tick_to_us(uint32_t ticks, uint32_t freq_hz)
{
    if (freq_hz == 0u) {
        return 0u;
    }
    return ((uint64_t)ticks * 1000000u) / freq_hz;
}

#ifdef __cplusplus
}
#endif

#endif /* MC_HAL_TICK_H */
