/**
 * @file mc_hall.h
 * @brief Hall-sensor rotor angle (float32): sector decoding, edge angles,
 *        speed from the edge intervals, the angle interpolated between
 *        edges, illegal states and impossible sequences as named errors.
 *
 * Three digital Hall sensors (A bit 0, B bit 1, C bit 2 of the code) split
 * an electrical turn into six sectors. The configuration is the table a
 * commissioning measures: code_of_sector[k], the code read in sector k
 * (k = 0..5 in the positive direction), and edge_e_rad[k], the electrical
 * angle where sector k begins; sector k spans [edge[k], edge[k+1]) with
 * edge[6] = edge[0] + 2 pi. Adjacent sectors differ in one sensor; the two
 * codes the table lacks are illegal (000 and 111 with the usual 120-degree
 * placement; 010 and 101 with 60 degrees).
 *
 * Hysteresis: a Hall switch changes state once the field is past its
 * operate point, so moving positive an edge is seen at edge + h/2, moving
 * negative at edge - h/2 (h = hysteresis_e_rad, the full band).
 *
 * Each step (one sample of the three inputs, every dt_s):
 *   - the code maps to its sector; an illegal code raises
 *     MC_HALL_ERR_ILLEGAL (the angle and speed are held; a stuck, broken
 *     or unsupplied sensor shows as 000 or 111);
 *   - a change to an adjacent sector is an edge, at the angle where it is
 *     seen (edge +- h/2, by direction); a change by two or three sectors
 *     raises MC_HALL_ERR_SEQUENCE (the angle cannot move that far in one
 *     sample at any speed the sampling supports: 60 degrees electrical per
 *     sample; the sector is taken, the speed forgotten);
 *   - speed: at an edge that continues the previous edge's direction,
 *     omega = (width of the sector just crossed) / (time between the two
 *     edges), the time counted in samples (an edge is known to within one
 *     sample); between edges it is bounded by what the sensors allow:
 *     |omega| <= width of the present sector / time since the edge (a
 *     slowing rotor); a reversal forgets it;
 *   - angle: with a speed of at least omega_min_e_rad_s, the edge's angle
 *     plus omega (n + 1/2) dt, n samples after the edge's (the edge
 *     happened on average half a sample before it was seen), never past
 *     the next edge; without, at an edge the edge's angle, at power-up the
 *     middle of the sector, otherwise the last angle (kept inside the
 *     sector): speed 0.
 * Error of the interpolated angle at a constant speed: the edge-table error
 * plus the sampling error of the speed, |omega| dt / (samples per sector);
 * at a changing speed the speed lags by one sector.
 *
 * The sector logic is shared with the q31 twin (mc_hall_q31.h):
 * mc_hall_f32_step_sector works on integers only.
 */
#ifndef MC_HALL_H
#define MC_HALL_H

#include <stdbool.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define MC_HALL_ERR_NONE 0u
#define MC_HALL_ERR_NULL (1u << 0) /**< a required pointer is NULL */
#define MC_HALL_ERR_CFG \
    (1u << 1)                          /**< codes not six distinct 3-bit codes with neighbours one
                   bit apart; a sector narrower than 10 or wider than 110
                   degrees or edges not in order round one turn; the band
                   not below half the narrowest sector; dt or omega_min not
                   > 0 and finite */
#define MC_HALL_ERR_ILLEGAL  (1u << 2) /**< a code the table lacks (000/111): sensor fault */
#define MC_HALL_ERR_SEQUENCE (1u << 3) /**< a jump by two or three sectors in one sample */

#define MC_HALL_SECTORS   6u
#define MC_HALL_NO_SECTOR 0xFFu /**< sector_of_code of an illegal code */

/** Sector tracking shared by both twins (integers only). */
typedef struct {
    uint8_t sector;      /**< present sector 0..5 */
    bool have_sector;    /**< a legal code has been read */
    int8_t dir;          /**< direction of the last edge: +1, -1; 0 none yet */
    bool have_interval;  /**< the last two edges went the same way */
    uint32_t n_since;    /**< samples since the last edge (saturating) */
    uint32_t n_interval; /**< samples between the last two edges */
} mc_hall_seq_t;

typedef struct {
    uint8_t code_of_sector[MC_HALL_SECTORS]; /**< code read in sector k */
    float edge_e_rad[MC_HALL_SECTORS];       /**< where sector k begins [rad el.] */
    float hysteresis_e_rad;                  /**< the sensors' full band [rad el.], >= 0 */
    float dt_s;                              /**< sample period [s], > 0 */
    float omega_min_e_rad_s; /**< interpolate at or above this speed [rad/s el.], > 0 */
} mc_hall_f32_cfg_t;

typedef struct {
    mc_hall_f32_cfg_t cfg;
    uint8_t sector_of_code[8];        /**< derived: MC_HALL_NO_SECTOR if illegal */
    float width_rad[MC_HALL_SECTORS]; /**< derived: edge[k+1] - edge[k] */
    float start_rad[MC_HALL_SECTORS]; /**< derived: edge[k] in [0, 2 pi) */
    mc_hall_seq_t seq;
    float theta_edge_rad; /**< the last edge's angle (as seen) */
    float omega_edge;     /**< |speed| at the last edge [rad/s], 0 unknown */
    float theta_rad;      /**< last output angle */
    bool have_theta;      /**< an angle other than the sector middle exists */
    uint32_t flags;       /**< sticky MC_HALL_ERR_* */
} mc_hall_f32_t;

typedef struct {
    float theta_e_rad;   /**< electrical angle [rad], [0, 2 pi) */
    float omega_e_rad_s; /**< electrical speed [rad/s] (0 below omega_min) */
    uint8_t sector;      /**< 0..5 */
    bool edge;           /**< a sector change this sample */
    bool interpolating;  /**< the angle moves with the speed */
} mc_hall_f32_out_t;

/**
 * Check the table (codes, edge order and widths) and derive
 * sector_of_code and the widths: MC_HALL_ERR_CFG on a bad one. Shared by
 * both twins; writes *p_sector_of_code and p_width_rad (may be NULL) only
 * when it returns MC_HALL_ERR_NONE.
 */
uint32_t mc_hall_f32_validate(const mc_hall_f32_cfg_t *cfg, uint8_t p_sector_of_code[8],
                              float *p_width_rad);

/** Validate cfg and initialise (no sector yet). On error st is not written. */
uint32_t mc_hall_f32_init(mc_hall_f32_t *st, const mc_hall_f32_cfg_t *cfg);

/** Forget the sector, the speed and the flags (power-up). */
uint32_t mc_hall_f32_reset(mc_hall_f32_t *st);

/**
 * The sector logic of one sample (shared with the q31 twin): code -> sector,
 * edge and its direction (*p_edge: +1, -1 or 0), interval bookkeeping.
 * @return MC_HALL_ERR_NONE, MC_HALL_ERR_ILLEGAL (seq keeps its sector,
 *         time advances) or MC_HALL_ERR_SEQUENCE (the new sector taken, no
 *         edge, the interval forgotten).
 */
uint32_t mc_hall_f32_step_sector(mc_hall_seq_t *seq, const uint8_t sector_of_code[8], uint32_t code,
                                 int32_t *p_edge);

/**
 * One sample of the three inputs (code: A bit 0, B bit 1, C bit 2).
 * @return the bits raised by this sample (also sticky in st->flags):
 *         MC_HALL_ERR_ILLEGAL or MC_HALL_ERR_SEQUENCE; MC_HALL_ERR_NULL.
 *         *out is always written (held values on an error).
 */
uint32_t mc_hall_f32_step(mc_hall_f32_t *st, uint32_t code, mc_hall_f32_out_t *out);

#ifdef __cplusplus
}
#endif

#endif /* MC_HALL_H */
