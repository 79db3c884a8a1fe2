/**
 * @file flash.h
 * @brief HAL capability: non-volatile storage in erasable sectors (NOR
 *        flash): erase a sector, program 32-bit words, read.
 *
 * A board names sectors by index (0 .. n-1 of its own map; the STM32F405
 * driver uses the RM0090 sector numbers). Erased bytes read 0xFF. Programming
 * can only clear bits: the caller programs only erased words (the result of
 * programming a non-erased word is the implementation's: a bitwise AND on
 * NOR flash, or an error). Offsets are byte offsets inside the sector.
 *
 * Power failure: an erase or a word program cut by a power loss may leave
 * that sector (erase) or that word (program) in any state; every operation
 * completed before it is intact. The configuration store
 * (firmware/app/config) is built on exactly this assumption and tested
 * against it with the fake's power-cut injection (hal/fake/mc_fake_flash.h).
 *
 * Timing: BLOCKING. An erase takes up to seconds (STM32F405: 16 KiB sector
 * up to 0.5 s, 128 KiB up to 2 s at x32) and stalls instruction fetches
 * from the same flash bank: call erase and program only while the bridge
 * is off (the drive's save path refuses otherwise). read is SLOW.
 *
 * See hal/hal.h for the conventions (error codes).
 */
#ifndef MC_HAL_FLASH_H
#define MC_HAL_FLASH_H

#include <errno.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define MC_HAL_FLASH_WORD_BYTES  4u /**< program granularity */
#define MC_HAL_FLASH_ERASED_WORD 0xFFFFFFFFu

typedef struct mc_hal_flash_ops {
    /** See mc_hal_flash_sector_size(). */
    int (*sector_size)(void *ctx, uint32_t sector, uint32_t *p_bytes);
    /** See mc_hal_flash_erase(). */
    int (*erase)(void *ctx, uint32_t sector);
    /** See mc_hal_flash_program(). */
    int (*program)(void *ctx, uint32_t sector, uint32_t offset, const uint32_t *p_words,
                   uint32_t n_words);
    /** See mc_hal_flash_read(). */
    int (*read)(void *ctx, uint32_t sector, uint32_t offset, void *p_buf, uint32_t len);
} mc_hal_flash_ops_t;

typedef struct mc_hal_flash {
    const mc_hal_flash_ops_t *ops;
    void *ctx;
} mc_hal_flash_t;

/**
 * Size of a sector [bytes].
 * @return 0; -EINVAL (no such sector); -ENODEV.
 */
static inline int mc_hal_flash_sector_size(const mc_hal_flash_t *dev, uint32_t sector,
                                           uint32_t *p_bytes)
{
    if ((dev == NULL) || (dev->ops == NULL) || (dev->ops->sector_size == NULL)) {
        return -ENODEV;
    }
    if (p_bytes == NULL) {
        return -EINVAL;
    }
    return dev->ops->sector_size(dev->ctx, sector, p_bytes);
}

/**
 * Erase a whole sector (every byte reads 0xFF afterwards).     BLOCKING.
 * @return 0; -EINVAL (no such sector, or a sector the board protects, e.g.
 *         the one holding the code); -EIO (the controller reported an
 *         error: write protection, sequence; the sector is in an unknown
 *         state); -ENODEV.
 */
static inline int mc_hal_flash_erase(const mc_hal_flash_t *dev, uint32_t sector)
{
    if ((dev == NULL) || (dev->ops == NULL) || (dev->ops->erase == NULL)) {
        return -ENODEV;
    }
    return dev->ops->erase(dev->ctx, sector);
}

/**
 * Program n_words 32-bit words at offset (a multiple of 4), in order, one
 * word at a time.                                                BLOCKING.
 * @return 0; -EINVAL (no such sector, offset misaligned, range outside the
 *         sector, NULL data; nothing programmed); -EIO (controller error:
 *         the words before the failing one are programmed); -ENODEV.
 */
static inline int mc_hal_flash_program(const mc_hal_flash_t *dev, uint32_t sector, uint32_t offset,
                                       const uint32_t *p_words, uint32_t n_words)
{
    if ((dev == NULL) || (dev->ops == NULL) || (dev->ops->program == NULL)) {
        return -ENODEV;
    }
    if (p_words == NULL) {
        return -EINVAL;
    }
    return dev->ops->program(dev->ctx, sector, offset, p_words, n_words);
}

/**
 * Copy len bytes at offset into p_buf.                           SLOW.
 * @return 0; -EINVAL (no such sector, range outside it, NULL buffer);
 *         -EIO; -ENODEV.
 */
static inline int mc_hal_flash_read(const mc_hal_flash_t *dev, uint32_t sector, uint32_t offset,
                                    void *p_buf, uint32_t len)
{
    if ((dev == NULL) || (dev->ops == NULL) || (dev->ops->read == NULL)) {
        return -ENODEV;
    }
    if (p_buf == NULL) {
        return -EINVAL;
    }
    return dev->ops->read(dev->ctx, sector, offset, p_buf, len);
}

#ifdef __cplusplus
}
#endif

#endif /* MC_HAL_FLASH_H */
