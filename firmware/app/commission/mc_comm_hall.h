/**
 * @file mc_comm_hall.h
 * @brief Commissioning's Hall table: the six edges, the code order and the
 *        band from the code changes seen while a current vector at a forced
 *        electrical angle swept the rotor slowly up, then down.
 *
 * A pure function (no state, f32): the step that sweeps and records is
 * mc_commission.c (README.md, "Hall table").
 *
 * The law. Going up, the code changes from code_of_sector[k-1] to
 * code_of_sector[k] at the forced angle u_k = edge_k + h/2 + lag; going
 * down, back at d_k = edge_k - h/2 - lag (h: the sensors' band; lag: the
 * rotor's angle behind the vector, the friction's torque over the vector's
 * stiffness, the same at the same slow speed either way). So
 *   edge_k = (u_k + d_k) / 2           (the lag and the band cancel),
 *   h_meas = mean over k of (u_k - d_k) = h + 2 lag
 * (an upper bound of the band: with the lag included the decoder places an
 * edge seen at speed by up to the lag late, never early). Several changes
 * of the same edge in one direction are averaged on the circle.
 *
 * The refusals (named, the table not written):
 *   MC_COMM_HALL_ERR_CODES   a code 000 or 111 seen (a sensor stuck, its
 *                            supply lost, a connector off), or fewer than
 *                            six distinct codes;
 *   MC_COMM_HALL_ERR_ORDER   a change of more than one sensor at a time,
 *                            an up order that is not one cycle through the
 *                            six codes, a change down that is not an up
 *                            change reversed, or more changes than
 *                            MC_COMM_HALL_EVENTS_MAX (chatter);
 *   MC_COMM_HALL_ERR_WIDTH   a sector outside [MC_COMM_HALL_WIDTH_MIN_RAD,
 *                            MC_COMM_HALL_WIDTH_MAX_RAD], or a band of half
 *                            the narrowest sector or more (the decoder's
 *                            own rule, mc_hall_f32_validate);
 *   MC_COMM_HALL_ERR_MOTION  no change at all in a direction, or an edge
 *                            not seen both ways (the rotor did not follow
 *                            the vector over the turn).
 */
#ifndef MC_COMM_HALL_H
#define MC_COMM_HALL_H

#include <stdint.h>

#include "hall/mc_hall.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MC_COMM_HALL_ERR_NONE   0u
#define MC_COMM_HALL_ERR_NULL   (1u << 0)
#define MC_COMM_HALL_ERR_CODES  (1u << 1)
#define MC_COMM_HALL_ERR_ORDER  (1u << 2)
#define MC_COMM_HALL_ERR_WIDTH  (1u << 3)
#define MC_COMM_HALL_ERR_MOTION (1u << 4)

/** Changes recorded per direction: a turn and two sectors is 8; twice that
 *  leaves room for a few swings of the rotor at an edge. */
#define MC_COMM_HALL_EVENTS_MAX 16u

/** Plausible sector widths: a 120-degree placement makes 60 degrees el.;
 *  30 either way is a sensor a quarter of its 120-degree spacing off, far
 *  beyond a mounting tolerance (a few degrees): wider or narrower means the
 *  magnet's pole count or the sensors' placement (60 degrees: two sectors
 *  of 0 and 120) is not what the decoder assumes. */
#define MC_COMM_HALL_WIDTH_MIN_RAD 0.52359878f /* 30 degrees */
#define MC_COMM_HALL_WIDTH_MAX_RAD 1.5707963f  /* 90 degrees */

typedef struct {
    uint8_t from;    /**< code before the change */
    uint8_t to;      /**< code after */
    float theta_rad; /**< forced electrical angle at the change [rad] */
} mc_comm_hall_event_t;

typedef struct {
    mc_comm_hall_event_t up[MC_COMM_HALL_EVENTS_MAX];
    mc_comm_hall_event_t down[MC_COMM_HALL_EVENTS_MAX];
    uint32_t n_up;      /**< changes recorded going up */
    uint32_t n_down;    /**< ... going down */
    uint32_t seen_mask; /**< bit c: code c read at any time of the sweep */
    uint32_t overflow;  /**< changes beyond MC_COMM_HALL_EVENTS_MAX (not recorded) */
} mc_comm_hall_rec_t;

typedef struct {
    uint8_t code_of_sector[MC_HALL_SECTORS]; /**< sector 0: the edge nearest above 0 */
    float edge_e_rad[MC_HALL_SECTORS];       /**< [0, 2 pi), increasing */
    float hysteresis_e_rad;                  /**< h + 2 lag (above), >= 0 */
} mc_comm_hall_table_t;

/** Record one change (from != to) going up (dir > 0) or down. */
void mc_comm_hall_record(mc_comm_hall_rec_t *rec, int32_t dir, uint32_t from, uint32_t to,
                         float theta_rad);

/** The table from rec (the law above). Returns MC_COMM_HALL_ERR_* bits; *out
 *  is written only when it returns MC_COMM_HALL_ERR_NONE. */
uint32_t mc_comm_hall_table_f32(const mc_comm_hall_rec_t *rec, mc_comm_hall_table_t *out);

#ifdef __cplusplus
}
#endif

#endif /* MC_COMM_HALL_H */
