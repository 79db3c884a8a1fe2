/**
 * @file mc_ma732.h
 * @brief MPS MagAlpha MA732 magnetic angle encoder over SPI (hal/spi.h),
 *        as the encoder capability (hal/encoder.h).
 *
 * Frames (MPS MA732 datasheet, "SPI" and the register map; MPS application
 * note AN137 "Using the MagAlpha Serial Interface Advanced Features",
 * "Parity bit (SPI and SSI)" for the parity):
 *   SPI mode 0 or 3 (this driver: 3, as ODrive's MA732 mode), MSB first,
 *   SCK <= 25 MHz; the angle leaves the output buffer as it was when CS
 *   fell (no command pipeline for the angle).
 *   angle read    MOSI 0x0000; MISO the 16-bit angle, most significant
 *                 bit first.
 *   parity        at the 17th clock the chip sends an even-parity bit over
 *                 the 16 angle bits (AN137 table 1: 0x8C62 -> 0, 0x8C63
 *                 -> 1, 0x5D00 -> 1); clocks after it are ignored by the
 *                 reader. A 16-bit SPI reads it in a 32-clock frame
 *                 (hal/spi.h transfer32): bits 31:16 the angle, bit 15 the
 *                 parity, bits 14:0 ignored.
 *   read register MOSI 010 aaaaa 00000000: this frame's MISO is still the
 *                 angle; the NEXT frame's MISO is the register's 8-bit
 *                 value in bits 15:8 (then the chip returns to angles).
 *   0x1B          bit 7 MGH (field above the high threshold), bit 6 MGL
 *                 (below the low threshold); read-only.
 *
 * The driver, one frame per mc_hal_encoder_read() (the fast loop):
 *   - normally MOSI 0x0000 (16 clocks, or 32 with parity);
 *   - every diag_period reads, and every read while a field error is
 *     latched: READ 0x1B (this read's angle is still used; the next read
 *     carries the register: MGH or MGL -> MC_SPIENC_ERR_MAGNET, latched
 *     until a clean read of it; both set -> MC_SPIENC_ERR_DIAG, which no
 *     chip sends: MISO stuck high or no chip).
 * With parity every frame (angle or register) is checked
 * (MC_SPIENC_ERR_PARITY); without it a flipped bit passes unseen (only the
 * drive's plausibility check of the angle step can catch a large one):
 * use parity wherever the SPI supports 32-clock frames.
 *
 * Latency: the angle at the frame's start (CS falling), plus the chip's
 * delay and the lag of its digital filter under a changing speed (its
 * filter window FW sets a time constant; none at a constant speed).
 * Resolution: 16-bit codes, 2 pi / 65536 rad; the filter's noise sets the
 * useful resolution (11..13 bits depending on FW, the datasheet's table).
 */
#ifndef MC_MA732_H
#define MC_MA732_H

#include <stdbool.h>
#include <stdint.h>

#include "hal/encoder.h"
#include "hal/spi.h"
#include "hal/tick.h"
#include "mc_spienc.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MC_MA732_CPR                 65536u    /**< counts per revolution (16-bit codes) */
#define MC_MA732_SPI_MODE            3u        /**< CPOL 1, CPHA 1 (mode 0 works too) */
#define MC_MA732_SPI_MAX_HZ          25000000u /**< SCK limit */
#define MC_MA732_REG_STATUS          0x1Bu     /**< MGH bit 7, MGL bit 6 */
#define MC_MA732_STATUS_MGH          (1u << 7)
#define MC_MA732_STATUS_MGL          (1u << 6)
#define MC_MA732_CMD_READ            0x4000u /**< 010 in bits 15:13 */
#define MC_MA732_DIAG_PERIOD_DEFAULT 1000u

/** Read-register command for a 5-bit address. */
uint16_t mc_ma732_cmd_read(uint32_t address);
/** The parity bit AN137 appends to a 16-bit word (even over the 17 bits). */
uint32_t mc_ma732_parity_bit(uint16_t word);
/**
 * A 32-clock frame's 16-bit word with its parity checked.
 * @return MC_SPIENC_ERR_NONE and *p_word, or MC_SPIENC_ERR_PARITY.
 */
uint32_t mc_ma732_frame32_check(uint32_t rx, uint16_t *p_word);
/** Register 0x1B's value as MC_SPIENC_ERR_* bits (MAGNET, DIAG). */
uint32_t mc_ma732_status_errs(uint32_t status);

typedef struct mc_ma732_config {
    const mc_hal_spi_t *p_spi;   /**< the chip's SPI device (mode 3, <= 25 MHz) */
    const mc_hal_tick_t *p_tick; /**< timestamps; NULL: 0 */
    bool parity;                 /**< 32-clock frames with the parity bit
                                      (the SPI must offer transfer32) */
    uint32_t bad_reads_max;      /**< N, 1 .. MC_SPIENC_BAD_READS_MAX */
    uint32_t diag_period;        /**< reads between 0x1B reads, 0 (none) or
                                      2 .. 1000000 */
} mc_ma732_config_t;

typedef struct mc_ma732 {
    mc_ma732_config_t cfg;
    mc_spienc_hold_t hold;
    bool reg_pending;      /**< the previous frame read a register: this
                               frame's MISO carries it */
    uint32_t since_diag;   /**< reads since the last 0x1B command */
    uint32_t diag_latched; /**< MC_SPIENC_ERR_* of the last bad 0x1B read (MAGNET,
                                DIAG): every read bad until a clean one */
    uint8_t status;        /**< last 0x1B value */
    mc_hal_encoder_t dev;  /**< the encoder capability (ctx = this struct) */
} mc_ma732_t;

/**
 * Validate the configuration and set up the driver (no SPI traffic).
 * @return 0; -EINVAL (NULL, no SPI, bad_reads_max or diag_period out of
 *         range; *p_drv unchanged).
 */
int mc_ma732_init(mc_ma732_t *p_drv, const mc_ma732_config_t *p_cfg);

/**
 * Talk to the chip once before the fast loop runs (SLOW, 2 frames): read
 * 0x1B and check it (and, with parity, both frames' parity).
 * @return 0; -EIO (an SPI transfer failed), -ENODEV (parity asked but the
 *         SPI has no 32-clock frame), -EPROTO (parity error, or MGH and MGL
 *         together: no chip, MISO stuck high), -ERANGE (field out of range).
 */
int mc_ma732_probe(mc_ma732_t *p_drv);

#ifdef __cplusplus
}
#endif

#endif /* MC_MA732_H */
