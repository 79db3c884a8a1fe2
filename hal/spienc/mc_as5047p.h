/**
 * @file mc_as5047p.h
 * @brief ams AS5047P 14-bit magnetic angle encoder over SPI (hal/spi.h),
 *        as the encoder capability (hal/encoder.h).
 *
 * Frames (ams AS5047P datasheet, "SPI Interface" and the register table;
 * the same interface as its sibling AS5147P, datasheet v1-02, and the
 * scheme of the family's AS5050/AS5055A datasheets, "Error Monitoring"):
 *   16 bits, SPI mode 1 (CPOL 0, CPHA 1), MSB first, SCK <= 10 MHz.
 *   command    bit 15 PARC even parity of bits 14:0, bit 14 R/W (1 read),
 *              bits 13:0 the address
 *   read data  bit 15 PARD even parity of bits 14:0, bit 14 EF (an error
 *              occurred in a previous command), bits 13:0 data
 *   write data bit 15 PARD, bit 14 0, bits 13:0 data
 *   A command executes at the end of its frame (CSn rising); the register
 *   it reads is latched then and shifted out in the NEXT frame (so READ
 *   ANGLECOM every frame returns the angle latched one frame earlier). EF
 *   stays set until ERRFL (0x0001: bit 0 FRERR framing, bit 1 INVCOMM
 *   invalid command, bit 2 PARERR parity) is read, which clears it.
 *   DIAAGC (0x3FFC): bit 11 MAGL field too low, bit 10 MAGH too high,
 *   bit 9 COF CORDIC overflow, bit 8 LF offset loop finished, 7:0 AGC.
 *   ANGLEUNC (0x3FFE): the angle without dynamic angle error compensation;
 *   ANGLECOM (0x3FFF): with DAEC (unless SETTINGS1 DAECDIS), which
 *   extrapolates the angle over the chip's signal-path delay with the
 *   speed: almost no latency at a constant speed (the datasheet's DAEC).
 *
 * The driver, one frame per mc_hal_encoder_read() (the fast loop):
 *   - normally READ ANGLECOM (daec) or READ ANGLEUNC;
 *   - after a response with EF: READ ERRFL (its answer names the chip's
 *     error in err_seen: MC_SPIENC_ERR_CHIP_*);
 *   - every diag_period reads, and every read while a field error is
 *     latched: READ DIAAGC (its answer: MAGL/MAGH -> MC_SPIENC_ERR_MAGNET,
 *     COF -> MC_SPIENC_ERR_CORDIC, both latched until a DIAAGC read is
 *     clean; LF clear -> MC_SPIENC_ERR_DIAG, a word a settled chip never
 *     sends, e.g. MISO stuck low).
 * Each response is checked against the command it answers: parity
 * (MC_SPIENC_ERR_PARITY), EF (MC_SPIENC_ERR_CHIP; expected in ERRFL's own
 * answer), then its content; mc_spienc.h turns that into the sample (one
 * bad read holds the last angle, bad_reads_max in a row clear VALID).
 * A single bit flipped on MISO is one bad read; on MOSI the chip answers
 * the next command with EF until ERRFL has been read: two bad reads and
 * one held read (so bad_reads_max >= 3 rides through it).
 *
 * Latency of the reported angle: the angle is latched at the end of the
 * previous read's frame, one PWM period before the read returns it, plus
 * the chip's own delay (with DAEC: about 0 at a constant speed).
 * Resolution 2 pi / 16384 rad.
 */
#ifndef MC_AS5047P_H
#define MC_AS5047P_H

#include <stdbool.h>
#include <stdint.h>

#include "hal/encoder.h"
#include "hal/spi.h"
#include "hal/tick.h"
#include "mc_spienc.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MC_AS5047P_CPR        16384u    /**< counts per revolution (14 bits) */
#define MC_AS5047P_SPI_MODE   1u        /**< CPOL 0, CPHA 1 */
#define MC_AS5047P_SPI_MAX_HZ 10000000u /**< SCK limit */
/* Registers */
#define MC_AS5047P_REG_NOP       0x0000u
#define MC_AS5047P_REG_ERRFL     0x0001u
#define MC_AS5047P_REG_SETTINGS1 0x0018u
#define MC_AS5047P_REG_DIAAGC    0x3FFCu
#define MC_AS5047P_REG_ANGLEUNC  0x3FFEu
#define MC_AS5047P_REG_ANGLECOM  0x3FFFu
/* Frame fields */
#define MC_AS5047P_PAR       (1u << 15)
#define MC_AS5047P_READ      (1u << 14) /**< command: read */
#define MC_AS5047P_EF        (1u << 14) /**< read data: error flag */
#define MC_AS5047P_DATA_MASK 0x3FFFu
/* ERRFL */
#define MC_AS5047P_ERRFL_FRERR   (1u << 0)
#define MC_AS5047P_ERRFL_INVCOMM (1u << 1)
#define MC_AS5047P_ERRFL_PARERR  (1u << 2)
/* DIAAGC */
#define MC_AS5047P_DIAAGC_MAGL (1u << 11)
#define MC_AS5047P_DIAAGC_MAGH (1u << 10)
#define MC_AS5047P_DIAAGC_COF  (1u << 9)
#define MC_AS5047P_DIAAGC_LF   (1u << 8)
/* SETTINGS1: bit 0 reads 1 (factory setting) */
#define MC_AS5047P_SETTINGS1_FACTORY (1u << 0)

/** Diagnostic period default [reads]: one DIAAGC read per 1000 reads
 *  (20 per second at 20 kHz; each costs one held angle). */
#define MC_AS5047P_DIAG_PERIOD_DEFAULT 1000u

/** A read command (R/W = 1) for a 14-bit address, parity set. */
uint16_t mc_as5047p_cmd_read(uint16_t address);
/** A write command (R/W = 0) for a 14-bit address, parity set. */
uint16_t mc_as5047p_cmd_write(uint16_t address);
/** A write data frame for 14 data bits, parity set. */
uint16_t mc_as5047p_data_write(uint16_t data);
/**
 * Check a received read-data frame.
 * @param p_data  out: bits 13:0 (written whenever the parity holds)
 * @return MC_SPIENC_ERR_NONE, MC_SPIENC_ERR_PARITY (odd number of ones;
 *         *p_data untouched), or MC_SPIENC_ERR_CHIP (EF set).
 */
uint32_t mc_as5047p_frame_check(uint16_t rx, uint16_t *p_data);
/** ERRFL content as MC_SPIENC_ERR_CHIP_* bits. */
uint32_t mc_as5047p_errfl_errs(uint16_t errfl);
/** DIAAGC content as MC_SPIENC_ERR_* bits (MAGNET, CORDIC, DIAG for LF clear). */
uint32_t mc_as5047p_diaagc_errs(uint16_t diaagc);

typedef struct mc_as5047p_config {
    const mc_hal_spi_t *p_spi;   /**< the chip's SPI device (mode 1, <= 10 MHz) */
    const mc_hal_tick_t *p_tick; /**< timestamps; NULL: 0 */
    bool daec;                   /**< read ANGLECOM (DAEC) rather than ANGLEUNC */
    uint32_t bad_reads_max;      /**< N, 1 .. MC_SPIENC_BAD_READS_MAX */
    uint32_t diag_period;        /**< reads between DIAAGC reads, 0 (none) or
                                       2 .. 1000000 */
} mc_as5047p_config_t;

/** What the previous frame asked for (what this frame's response holds). */
typedef enum mc_as5047p_pending {
    MC_AS5047P_PENDING_NONE = 0, /**< nothing known (after init) */
    MC_AS5047P_PENDING_ANGLE,
    MC_AS5047P_PENDING_ERRFL,
    MC_AS5047P_PENDING_DIAAGC
} mc_as5047p_pending_t;

typedef struct mc_as5047p {
    mc_as5047p_config_t cfg;
    mc_spienc_hold_t hold;
    mc_as5047p_pending_t pending;
    uint32_t since_diag;   /**< reads since the last DIAAGC command */
    bool need_errfl;       /**< EF seen: read ERRFL next */
    uint32_t diag_latched; /**< MC_SPIENC_ERR_* of the last bad DIAAGC (MAGNET,
                                CORDIC, DIAG): every read bad until a clean one */
    uint16_t errfl;        /**< last ERRFL read */
    uint16_t diaagc;       /**< last DIAAGC read */
    mc_hal_encoder_t dev;  /**< the encoder capability (ctx = this struct) */
} mc_as5047p_t;

/**
 * Validate the configuration and set up the driver (no SPI traffic).
 * @return 0; -EINVAL (NULL, no SPI, bad_reads_max or diag_period out of
 *         range; *p_drv unchanged).
 */
int mc_as5047p_init(mc_as5047p_t *p_drv, const mc_as5047p_config_t *p_cfg);

/**
 * Talk to the chip once before the fast loop runs (SLOW, a few frames):
 * clear ERRFL, check DIAAGC (offset loop finished, field in range) and
 * SETTINGS1's factory bit, then leave an angle command in the pipeline.
 * @return 0; -EIO (an SPI transfer failed), -EPROTO (a parity error or a
 *         word no chip sends: nothing or something else on the bus),
 *         -ERANGE (field out of range or CORDIC overflow: magnet).
 */
int mc_as5047p_probe(mc_as5047p_t *p_drv);

#ifdef __cplusplus
}
#endif

#endif /* MC_AS5047P_H */
