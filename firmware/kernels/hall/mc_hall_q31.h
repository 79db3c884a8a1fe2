/**
 * @file mc_hall_q31.h
 * @brief q31 twin of the Hall-sensor rotor angle (hall/mc_hall.h).
 *
 * The same law; the sector logic is the f32 kernel's integer code
 * (mc_hall_f32_step_sector) and the table is validated by
 * mc_hall_f32_validate. Formats: angles are q31 normalised turns (v pi /
 * 2^31 rad, mc_q31.h; the edge table converted once by init); distances
 * within the turn (sector widths, the travel since an edge) are unsigned
 * 32-bit fractions of a turn (2^-32 turn), so the wrap of an angle is the
 * integer's; the speed is kept as a travel per sample in the same unit:
 *   at an edge      step = width crossed / samples between the edges
 *                   (integer division: rounded down, at most 1 unit of
 *                   2^-32 turn per sample)
 *   between edges   step <= 2 width / (2 n + 1), n samples since the edge
 *   interpolation   travel = step n + step / 2, at most the width
 * and reported as q31 per unit of omega_base_rad_s (init's gain pi / (dt
 * omega_base), applied in Q46; saturates at +-1 pu: choose omega_base
 * above the top electrical speed).
 * Error vs the f32 twin on the same inputs: the f32 kernel rounds its angle
 * to float every sample (2.4e-7 rad near 2 pi) and its speed to float; the
 * q31 one truncates the step to 2^-32 turn. Bounds:
 * tests/unit/q31/test_hall_q31.cpp.
 */
#ifndef MC_HALL_Q31_H
#define MC_HALL_Q31_H

#include <stdbool.h>
#include <stdint.h>

#include "hall/mc_hall.h"
#include "math/mc_q31.h"
#include "math/mc_q46.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MC_HALL_ERR_SCALE \
    (1u << 4) /**< omega_base not > 0 / finite, or omega_min below one
                   2^-32 turn per sample or above half a turn */

typedef struct {
    mc_hall_f32_cfg_t f;    /**< the table, dt, omega_min: as the f32 kernel's */
    float omega_base_rad_s; /**< speed base [rad/s el.], > 0 */
} mc_hall_q31_cfg_t;

typedef struct {
    mc_hall_q31_cfg_t cfg;
    uint8_t sector_of_code[8];
    q31_t start[MC_HALL_SECTORS];    /**< edge[k] as a q31 angle */
    uint32_t width[MC_HALL_SECTORS]; /**< sector widths [2^-32 turn] */
    uint32_t h2;                     /**< half the band [2^-32 turn] */
    uint32_t step_min;               /**< omega_min [2^-32 turn per sample] */
    mc_q46_gain_t omega_gain;        /**< (step / 2) as q31 -> speed q31 pu */
    mc_hall_seq_t seq;
    q31_t theta_edge;
    uint32_t step_edge; /**< travel per sample at the last edge, 0 unknown */
    q31_t theta;
    bool have_theta;
    uint32_t flags;
} mc_hall_q31_t;

typedef struct {
    q31_t theta_e; /**< electrical angle, q31 turn */
    q31_t omega_e; /**< electrical speed, q31 pu of omega_base (0 below omega_min) */
    uint8_t sector;
    bool edge;
    bool interpolating;
} mc_hall_q31_out_t;

/** Validate (MC_HALL_ERR_* of the f32 kernel, MC_HALL_ERR_SCALE) and
 *  initialise; on error st is not written. */
uint32_t mc_hall_q31_init(mc_hall_q31_t *st, const mc_hall_q31_cfg_t *cfg);

/** Forget the sector, the speed and the flags (power-up). */
uint32_t mc_hall_q31_reset(mc_hall_q31_t *st);

/** One sample (code: A bit 0, B bit 1, C bit 2); as mc_hall_f32_step. */
uint32_t mc_hall_q31_step(mc_hall_q31_t *st, uint32_t code, mc_hall_q31_out_t *out);

#ifdef __cplusplus
}
#endif

#endif /* MC_HALL_Q31_H */
