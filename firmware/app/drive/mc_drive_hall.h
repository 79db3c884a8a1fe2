/**
 * @file mc_drive_hall.h
 * @brief Three Hall sensors as the drive's position source: the Hall
 *        kernel (firmware/kernels/hall, mc_hall_f32) behind the encoder
 *        capability the drive reads (hal/encoder.h).
 *
 * A board with Hall inputs (hal/hall.h) and the parameter encoder_type 1
 * gets this adapter as its hal.encoder (mc_app binds it; the drive itself
 * does not know it reads a Hall, and a board without one pays nothing).
 * Each read (the drive's fast step, once per PWM period):
 *   - the three inputs are read (mc_hal_hall_read; -EIO when they cannot
 *     be: the drive's ENCODER fault);
 *   - the kernel decodes the sector and, at or above omega_min,
 *     interpolates the electrical angle between edges with the
 *     edge-interval speed (mc_hall.h); below it the angle is the middle of
 *     the sector (within 30 degrees el. either way, the same whichever way
 *     the rotor came: commissioning's sweeps read no direction-dependent
 *     lag, a start has at least cos 30 deg of the torque), also at power-up
 *     (the angle is referenced from the first sample, angle_ref 0);
 *   - an illegal code (000/111 with the usual placement) or a jump by two
 *     or three sectors clears MC_HAL_ENCODER_FLAG_VALID for that sample:
 *     the drive raises its ENCODER fault, and error keeps the reason
 *     (MC_HALL_ERR_ILLEGAL, MC_HALL_ERR_SEQUENCE; sticky: the parameter
 *     hall_error);
 *   - the count is the electrical angle in MC_DRIVE_HALL_COUNTS_E counts
 *     per electrical turn, the electrical turns counted modulo pole_pairs:
 *     counts_per_rev = pole_pairs MC_DRIVE_HALL_COUNTS_E, so the drive's
 *     electrical angle from the count is the Hall angle itself
 *     (encoder_offset_rad 0 with a table measured against the d axis) and
 *     its mechanical angle is relative to the power-up turn.
 * The kernel's angle moves by up to a sector at an edge where the speed
 * changed (the interpolation lagged): the drive skips its encoder-jump
 * check for this source (mc_drive_cfg_t.enc_steps_checked; the kernel's
 * SEQUENCE check is the Hall's own).
 */
#ifndef MC_DRIVE_HALL_H
#define MC_DRIVE_HALL_H

#include <stdbool.h>
#include <stdint.h>

#include "hal/encoder.h"
#include "hal/hall.h"
#include "hal/tick.h"
#include "hall/mc_hall.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Counts per electrical turn of the adapter's count (2^12: 0.09 degree). */
#define MC_DRIVE_HALL_COUNTS_E 4096u

#define MC_DRIVE_HALL_ERR_NONE 0u
#define MC_DRIVE_HALL_ERR_NULL (1u << 0) /**< a required pointer is NULL */
#define MC_DRIVE_HALL_ERR_CFG  (1u << 1) /**< the table (mc_hall_f32_validate's MC_HALL_ERR_CFG) */
#define MC_DRIVE_HALL_ERR_POLES \
    (1u << 2) /**< pole_pairs 0 or above 65535 (the count would not fit) */

typedef struct {
    mc_hall_f32_cfg_t table; /**< codes, edges, band, dt_s, omega_min (mc_hall.h) */
    uint32_t pole_pairs;     /**< electrical turns per mechanical turn, 1..65535 */
} mc_drive_hall_cfg_t;

typedef struct {
    mc_hall_f32_t k;           /**< the kernel */
    const mc_hal_hall_t *hall; /**< the inputs */
    const mc_hal_tick_t *tick; /**< timestamps (may be NULL: 0) */
    mc_hal_encoder_ops_t ops;  /**< read = the adapter's */
    mc_hal_encoder_t dev;      /**< what the drive reads (hal.encoder) */
    uint32_t pole_pairs;       /**< from the configuration */
    uint32_t e_turn;           /**< electrical turns since power-up, mod pole_pairs */
    uint32_t frac_prev;        /**< the last count within the electrical turn */
    uint32_t error;            /**< sticky MC_HALL_ERR_ILLEGAL | MC_HALL_ERR_SEQUENCE */
    uint32_t code;             /**< the last code read */
    bool have_frac;            /**< frac_prev is valid */
} mc_drive_hall_t;

/** Validate cfg, bind hall and tick, power up (no sector yet). On error h
 *  is not changed. */
uint32_t mc_drive_hall_init(mc_drive_hall_t *h, const mc_drive_hall_cfg_t *cfg,
                            const mc_hal_hall_t *hall, const mc_hal_tick_t *tick);

/** The encoder capability the drive reads (h->dev). */
const mc_hal_encoder_t *mc_drive_hall_encoder(mc_drive_hall_t *h);

#ifdef __cplusplus
}
#endif

#endif /* MC_DRIVE_HALL_H */
