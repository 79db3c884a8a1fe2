/**
 * @file hal/hall.h
 * @brief HAL capability: three digital Hall sensors, read as one 3-bit code.
 *
 * Not part of mc_hal_t yet: the drive reads its position through the
 * encoder capability; a board with Hall sensors offers this handle, and
 * the Hall kernel (firmware/kernels/hall) turns the codes into an angle
 * and a speed. Implementations: hal/stm32f405 (mc_f405_hall: three GPIO
 * input levels), tests supply their own.
 *
 * See hal/hal.h for the conventions (error codes, timing classes).
 */
#ifndef MC_HAL_HALL_H
#define MC_HAL_HALL_H

#include <errno.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct mc_hal_hall_ops {
    /** See mc_hal_hall_read(). */
    int (*read)(void *ctx, uint32_t *p_code);
} mc_hal_hall_ops_t;

typedef struct mc_hal_hall {
    const mc_hal_hall_ops_t *ops;
    void *ctx;
} mc_hal_hall_t;

/**
 * The sensors' levels now: bit 0 sensor A, bit 1 B, bit 2 C (1 = high, as
 * the sensor drives it; an inverting input stage is the implementation's
 * to undo).                                             Timing: FAST.
 * @return 0 and *p_code in 0..7; -ENODEV; -EINVAL.
 */
static inline int mc_hal_hall_read(const mc_hal_hall_t *dev, uint32_t *p_code)
{
    if ((dev == NULL) || (dev->ops == NULL) || (dev->ops->read == NULL)) {
        return -ENODEV;
    }
    if (p_code == NULL) {
        return -EINVAL;
    }
    return dev->ops->read(dev->ctx, p_code);
}

#ifdef __cplusplus
}
#endif

#endif /* MC_HAL_HALL_H */
