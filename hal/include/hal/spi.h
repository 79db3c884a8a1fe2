/**
 * @file spi.h
 * @brief SPI master, one device: 16-bit (and optionally 32-clock)
 *        full-duplex frames with the device's chip select asserted around
 *        each frame.
 *
 * Not part of mc_hal_t: the drive never talks SPI. A board uses it to set
 * up and supervise a gate driver with a register interface (hal/drv8301:
 * TI DRV8301 on the ODrive v3.6 and the VESC 6) and to read an absolute
 * encoder (hal/spienc: AS5047P, MA732). One handle addresses one device:
 * the implementation owns the bus settings (clock polarity and phase, bit
 * rate, MSB first) and the chip-select pin. Several handles may share one
 * bus (one handle per device, each frame with its own settings); who may
 * use the bus when is the caller's business (hal/spisched schedules a bus
 * shared between the fast loop and the slow loop).
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
    /** See mc_hal_spi_transfer32(); NULL where not supported. */
    int (*transfer32)(void *ctx, uint32_t tx, uint32_t *p_rx);
} mc_hal_spi_ops_t;

typedef struct mc_hal_spi {
    const mc_hal_spi_ops_t *ops;
    void *ctx;
} mc_hal_spi_t;

/**
 * One frame: chip select asserted, 16 bits shifted out MSB first while 16
 * bits are shifted in, chip select released. Blocks for the frame (a few
 * microseconds at MHz bit rates).                        Timing: SLOW
 * (a fast-loop caller that owns the bus, an SPI encoder, spends the
 * frame's duration in the fast loop: 16 clocks at 5.25 MHz = 3 us).
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

/**
 * One 32-clock frame: chip select asserted, 32 bits shifted out MSB first
 * (tx bit 31 first) while 32 bits are shifted in, chip select released.
 * For devices whose frame is longer than 16 clocks (the MA732's angle with
 * its parity bit at the 17th clock). Blocks for the frame. Timing: SLOW.
 * @return 0; -EIO (*p_rx untouched); -ENODEV (not supported).
 */
static inline int mc_hal_spi_transfer32(const mc_hal_spi_t *dev, uint32_t tx, uint32_t *p_rx)
{
    if ((dev == NULL) || (dev->ops == NULL) || (dev->ops->transfer32 == NULL)) {
        return -ENODEV;
    }
    return dev->ops->transfer32(dev->ctx, tx, p_rx);
}

#ifdef __cplusplus
}
#endif

#endif /* MC_HAL_SPI_H */
