/**
 * @file spi.h
 * @brief SPI master, one device: 16-bit full-duplex frames with the
 *        device's chip select asserted around each frame.
 *
 * Not part of mc_hal_t: the drive never talks SPI. A board uses it to set
 * up and supervise a gate driver with a register interface (hal/drv8301:
 * TI DRV8301 on the ODrive v3.6 and the VESC 6). One handle addresses one
 * device: the implementation owns the bus settings (clock polarity and
 * phase, bit rate, MSB first) and the chip-select pin.
 *
 * Implementations: hal/stm32f405 (mc_f405_spi: SPI1..3 registers and a GPIO
 * chip select); tests supply a model of the device.
 *
 * See hal/hal.h for the conventions (error codes, timing classes).
 */
#ifndef MC_HAL_SPI_H
#define MC_HAL_SPI_H

#include <errno.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct mc_hal_spi_ops {
    /** See mc_hal_spi_transfer16(). */
    int (*transfer16)(void *ctx, uint16_t tx, uint16_t *p_rx);
} mc_hal_spi_ops_t;

typedef struct mc_hal_spi {
    const mc_hal_spi_ops_t *ops;
    void *ctx;
} mc_hal_spi_t;

/**
 * One frame: chip select asserted, 16 bits shifted out MSB first while 16
 * bits are shifted in, chip select released. Blocks for the frame (a few
 * microseconds at MHz bit rates).                        Timing: SLOW.
 * @param tx    the word sent
 * @param p_rx  the word received, or NULL to discard it
 * @return 0; -EIO (the peripheral did not complete the frame: chip select
 *         released, *p_rx untouched); -ENODEV.
 */
static inline int mc_hal_spi_transfer16(const mc_hal_spi_t *dev, uint16_t tx, uint16_t *p_rx)
{
    if ((dev == NULL) || (dev->ops == NULL) || (dev->ops->transfer16 == NULL)) {
        return -ENODEV;
    }
    return dev->ops->transfer16(dev->ctx, tx, p_rx);
}

#ifdef __cplusplus
}
#endif

#endif /* MC_HAL_SPI_H */
