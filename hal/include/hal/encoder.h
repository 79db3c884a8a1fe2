/**
 * @file encoder.h
 * @brief HAL capability: rotor position (incremental or absolute encoder).
 *
 * On the STM32F405: a timer in encoder mode (x4 quadrature counting, auto
 * reload = counts_per_rev - 1) with the index pulse resetting the counter;
 * or an SPI absolute encoder. Either way the drive sees one mechanical
 * revolution as counts 0 .. counts_per_rev - 1, increasing in the positive
 * direction of rotation. Multi-turn position is unwrapped by the drive from
 * successive reads (it reads every PWM period, far faster than half a turn).
 *
 * See hal/hal.h for the conventions (error codes, timing classes).
 */
#ifndef MC_HAL_ENCODER_H
#define MC_HAL_ENCODER_H

#include <errno.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Bits of mc_hal_encoder_sample_t.flags. */
/** The position signal is usable (absolute encoder: frame and CRC good;
 *  incremental: no quadrature error). Clear: do not use count. */
#define MC_HAL_ENCODER_FLAG_VALID (1u << 0)
/** The index pulse has been seen (or the encoder is absolute): count is
 *  referenced to the index. Clear: count is relative to power-up. */
#define MC_HAL_ENCODER_FLAG_INDEX (1u << 1)
#define MC_HAL_ENCODER_FLAG_ALL   (MC_HAL_ENCODER_FLAG_VALID | MC_HAL_ENCODER_FLAG_INDEX)

typedef struct mc_hal_encoder_sample {
    uint32_t count;           /**< position [counts], 0 .. counts_per_rev-1 */
    uint32_t counts_per_rev;  /**< counts per mechanical revolution, > 0
                                   (x4 quadrature included); constant */
    uint32_t flags;           /**< MC_HAL_ENCODER_FLAG_* */
    uint32_t timestamp_ticks; /**< tick counter (hal/tick.h) when latched */
} mc_hal_encoder_sample_t;

typedef struct mc_hal_encoder_ops {
    /** See mc_hal_encoder_read(). */
    int (*read)(void *ctx, mc_hal_encoder_sample_t *p_sample);
} mc_hal_encoder_ops_t;

typedef struct mc_hal_encoder {
    const mc_hal_encoder_ops_t *ops;
    void *ctx;
} mc_hal_encoder_t;

/**
 * Latest position.                                      Timing: FAST.
 *
 * Called once per PWM period from the fast loop, right after the ADC read
 * (incremental: reads the counter register; SPI absolute: returns the frame
 * received during the previous period).
 * @return 0 and *p_sample filled (check MC_HAL_ENCODER_FLAG_VALID);
 *         -EIO encoder does not respond: *p_sample unchanged; -ENODEV;
 *         -EINVAL.
 */
static inline int mc_hal_encoder_read(const mc_hal_encoder_t *dev,
                                      mc_hal_encoder_sample_t *p_sample)
{
    if ((dev == NULL) || (dev->ops == NULL) || (dev->ops->read == NULL)) {
        return -ENODEV;
    }
    if (p_sample == NULL) {
        return -EINVAL;
    }
    return dev->ops->read(dev->ctx, p_sample);
}

#ifdef __cplusplus
}
#endif

#endif /* MC_HAL_ENCODER_H */
