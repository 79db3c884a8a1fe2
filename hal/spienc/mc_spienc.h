/**
 * @file mc_spienc.h
 * @brief What the absolute SPI encoders (mc_as5047p.h, mc_ma732.h) share:
 *        the named errors of a read and the rule that turns reads into the
 *        encoder capability's samples (hal/encoder.h).
 *
 * Every read is checked (parity, the chip's error flag, the periodic
 * diagnostic word). The rule, per fast-loop read:
 *   - a good angle: reported, VALID, the run of bad reads back to 0;
 *   - no angle this period by design (the answer to a diagnostic or
 *     error-register command occupies the frame): the last angle is held,
 *     VALID, the run unchanged;
 *   - a bad read (any MC_SPIENC_ERR_*): the last good angle is held and
 *     the run counts up; VALID while the run is below bad_reads_max, clear
 *     from the bad_reads_max-th bad read in a row on (until a good angle).
 * The drive raises MC_DRIVE_FAULT_ENCODER in the fast step whose sample is
 * not VALID, so bad_reads_max = N bad reads in a row fault the drive
 * (N - 1) PWM periods after the first of them. Before the first good
 * angle the sample is not VALID. An absolute encoder is referenced at
 * every read: VALID samples carry MC_HAL_ENCODER_FLAG_INDEX.
 *
 * No heap, no globals; the caller owns the structs.
 */
#ifndef MC_SPIENC_H
#define MC_SPIENC_H

#include <stdbool.h>
#include <stdint.h>

#include "hal/encoder.h"
#include "hal/tick.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Errors of one read (bit set; err_last) and every one seen (err_seen). */
#define MC_SPIENC_ERR_NONE   0u
#define MC_SPIENC_ERR_SPI    (1u << 0) /**< the SPI transfer failed (-EIO, no frame) */
#define MC_SPIENC_ERR_PARITY (1u << 1) /**< the received frame's parity is wrong */
#define MC_SPIENC_ERR_CHIP \
    (1u << 2) /**< AS5047P EF: the chip saw an error in a command; the next
                   ERRFL read names it (MC_SPIENC_ERR_CHIP_*) */
#define MC_SPIENC_ERR_MAGNET \
    (1u << 3)                          /**< magnetic field out of range (AS5047P DIAAGC MAGH/MAGL,
                   MA732 MGH/MGL): angles are bad until a diagnostic read
                   shows the field back in range */
#define MC_SPIENC_ERR_CORDIC (1u << 4) /**< AS5047P DIAAGC COF: CORDIC overflow */
#define MC_SPIENC_ERR_DIAG \
    (1u << 5) /**< a diagnostic word no working chip sends (MISO stuck
                   low or high, chip absent) */
/* What the AS5047P's ERRFL reported (err_seen only; after MC_SPIENC_ERR_CHIP). */
#define MC_SPIENC_ERR_CHIP_FRERR   (1u << 8)  /**< framing error */
#define MC_SPIENC_ERR_CHIP_INVCOMM (1u << 9)  /**< invalid command */
#define MC_SPIENC_ERR_CHIP_PARERR  (1u << 10) /**< parity error in a command it received */

/** Bad reads in a row that clear VALID, default and limits. */
#define MC_SPIENC_BAD_READS_DEFAULT 3u
#define MC_SPIENC_BAD_READS_MAX     1000u

/** The hold rule's state (see the file comment). */
typedef struct mc_spienc_hold {
    uint32_t bad_reads_max; /**< N: bad reads in a row that clear VALID, >= 1 */
    uint32_t cpr;           /**< counts per revolution of the chip */
    uint32_t run;           /**< bad reads in a row now */
    uint32_t code;          /**< last good angle [counts] */
    bool have_code;         /**< a good angle has been read since init */
    uint32_t err_last;      /**< MC_SPIENC_ERR_* of the last read */
    uint32_t err_seen;      /**< every MC_SPIENC_ERR_* since init (sticky) */
    uint32_t n_reads;       /**< reads since init */
    uint32_t n_bad;         /**< bad reads since init */
    uint32_t n_held;        /**< reads without an angle by design (diagnostics) */
} mc_spienc_hold_t;

/** The drivers' shared limits: bad_reads_max 1 .. MC_SPIENC_BAD_READS_MAX,
 *  diag_period 0 (none) or 2 .. 1000000 (1 would leave no angle). */
bool mc_spienc_cfg_ok(const void *p_spi, uint32_t bad_reads_max, uint32_t diag_period);

/** Start the rule: nothing read yet. */
void mc_spienc_hold_init(mc_spienc_hold_t *p_hold, uint32_t bad_reads_max, uint32_t cpr);

/**
 * One read's outcome into a sample.
 * @param err         MC_SPIENC_ERR_* of this read (0: none)
 * @param have_angle  err == 0 and the frame carried an angle
 * @param code        that angle [counts], 0 .. cpr - 1
 * @param ticks       timestamp of the frame
 */
void mc_spienc_hold_apply(mc_spienc_hold_t *p_hold, uint32_t err, bool have_angle, uint32_t code,
                          uint32_t ticks, mc_hal_encoder_sample_t *p_sample);

/** Even parity over the low `bits` bits of w: true when they hold an even
 *  number of ones (AS5047P frames: 16 bits; MA732: 16 angle bits and the
 *  parity bit). */
bool mc_spienc_even_parity(uint32_t w, uint32_t bits);

/** Tick counter reading, 0 without a tick. */
uint32_t mc_spienc_ticks(const mc_hal_tick_t *p_tick);

/** Name of one MC_SPIENC_ERR_* bit ("parity", "magnet", ...), NULL if
 *  not exactly one known bit. */
const char *mc_spienc_err_name(uint32_t err_bit);

#ifdef __cplusplus
}
#endif

#endif /* MC_SPIENC_H */
