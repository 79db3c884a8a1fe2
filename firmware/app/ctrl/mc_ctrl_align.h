/**
 * @file mc_ctrl_align.h
 * @brief The rotor angle after a power-up, as two control laws for the
 *        drive's CTRL mode (mc_drive_attach_ctrl): a power-up alignment
 *        that measures the encoder offset (mc_ctrl_align_*), and an index
 *        search that finds the encoder's index (mc_ctrl_idx_*).
 *
 * Both drive a current vector of a bounded magnitude along a commanded
 * electrical angle (the FOC kernel at that angle: id_ref = i, iq_ref = 0)
 * and watch the rotor on the encoder (the drive's mc_drive_meas_t:
 * theta_m_rad, its direction already applied, and the tracking loop's
 * omega_m_rad_s). A rotor on a current vector is a spring: with little
 * friction it rings for seconds. Damping: a current at 90 degrees to the
 * vector, iq_ref = -damping_a_s_rad omega_m (the encoder's speed; near the
 * vector it makes the torque k iq), bounded so that |i| <= i_max_a; it is
 * zero at rest, so it does not bias where the rotor settles. They need neither the encoder offset nor the index: they
 * find them. A failure returns its error bits from the fast step (the
 * drive's MC_DRIVE_FAULT_CONTROL: the bridge opens in that step) and names
 * the reason in the result (MC_CTRL_ALIGN_ERR_*). After success the
 * current ramps down to 0 and stays there (bridge on, no torque) until the
 * integrator switches to the sensored law.
 *
 * ---- Power-up alignment (mc_ctrl_align_*): no index, no absolute sensor.
 * With a the electrical angle a0 = 0, s = sweep_e_rad, i = i_align_a:
 *   RAMP     the vector at a0 - s, its magnitude ramped 0 -> i over
 *            t_ramp_s; the rotor turns onto it (at most half an electrical
 *            turn); settle; then the vector turned to a0 (a rotor that sat
 *            on the dead point opposite the first vector, where it feels
 *            no torque, is pulled off it by that turn); settle: position P_A
 *   SWEEP    the vector turned to a0 + s at omega_sweep; settle: P_B
 *            (approached going forward); check the measured P_B - P_A
 *            against s (encoder direction, pole pairs, counts per turn:
 *            MC_CTRL_ALIGN_ERR_DIRECTION beyond sweep_tol_e_rad);
 *   BACK     on to a0 + 2 s, then back to a0 + s; settle: P_C (approached
 *            going backward): friction holds the rotor short of the vector
 *            by the same angle on either side, so their mean cancels it;
 *   HALVE    the magnitude ramped to i / 2; settle: P_D. A load torque T
 *            holds the rotor asin(T / (k i)) behind the vector (k the
 *            torque per ampere at 90 degrees); halving the current about
 *            doubles that angle, so |P_D - P_C| is about the offset error
 *            the load causes: above load_tol_e_rad the alignment is
 *            refused (MC_CTRL_ALIGN_ERR_LOAD);
 *   RELEASE  offset = wrap(a0 + s - (P_B + P_C) / 2), the magnitude ramped
 *            to 0: DONE.
 * A "settle" is the rotor staying within still_band_m_rad (the spread of
 * its measured angle) for t_settle_s (a position window, not the speed
 * estimate, whose count-step spikes would never let a rotor dithering by a
 * count count as still); more than t_timeout_s in one settle is
 * MC_CTRL_ALIGN_ERR_NOT_SETTLED (a load that keeps the rotor moving). Motion: |theta_m - theta_m at reset| is
 * checked every step against travel_max_m_rad (MC_CTRL_ALIGN_ERR_TRAVEL),
 * and against the vector: before the first rest the rotor may move at most
 * half an electrical turn onto it (3/2 pi el. allowed), after it the rotor
 * must follow the vector's turns within pi/2 el. (beyond, the vector's
 * torque falls: it is slipping): MC_CTRL_ALIGN_ERR_SLIP, a load beyond
 * the holding torque k i, caught within a quarter of an electrical turn
 * (before the rotor gathers speed); moving against the vector's turn
 * instead is MC_CTRL_ALIGN_ERR_DIRECTION (the encoder counts the other
 * way). A lighter load is refused by HALVE. A rotor that cannot follow
 * (jammed) slips. The rotor may fall towards the load while the current
 * ramps up: a ramp fast against the rotor's fall keeps a holdable load
 * from looking like a slip.
 *
 * ---- Index search (mc_ctrl_idx_*): an incremental encoder with an index.
 * The vector's magnitude ramped to i_search_a, then turned at
 * omega_search_e_rad_s in the first direction; the rotor follows. The
 * index is found when the encoder capability (cfg.p_enc, read each step
 * for its flags) reports MC_HAL_ENCODER_FLAG_INDEX: the current ramps to 0,
 * DONE. From then on the encoder's count is referenced to the index
 * (hal/encoder.h): the drive's angle jumps once (the integrator resets the
 * drive's unwrapping there). Bounded travel: once the rotor has moved
 * travel_max_m_rad one way from where it started, the vector turns back
 * and searches travel_max_m_rad the other way; then
 * MC_CTRL_ALIGN_ERR_NOT_FOUND. The rotor must follow: once the vector has
 * turned a full electrical turn, a measured travel that lags it by more
 * than 3/2 pi electrical (the rotor may start up to pi from the vector)
 * means it is blocked (an end stop, a jam, a load): in the first direction
 * the search turns back, in the second it fails with
 * MC_CTRL_ALIGN_ERR_NO_MOTION.
 *
 * Parameters (units and ranges: the cfg structs below; the integration
 * maps them from the parameter table). Timing in the fast loop only: every
 * duration is counted in PWM periods (foc.dt_s).
 */
#ifndef MC_CTRL_ALIGN_H
#define MC_CTRL_ALIGN_H

#include <stdbool.h>
#include <stdint.h>

#include "foc/mc_foc.h"
#include "hal/encoder.h"
#include "mc_drive.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MC_CTRL_ALIGN_ERR_NONE        0u
#define MC_CTRL_ALIGN_ERR_NULL        (1u << 0) /**< NULL pointer */
#define MC_CTRL_ALIGN_ERR_CFG         (1u << 1) /**< a parameter out of its range (init) */
#define MC_CTRL_ALIGN_ERR_FOC         (1u << 2) /**< the current loop's config or step failed */
#define MC_CTRL_ALIGN_ERR_MEAS        (1u << 3) /**< no encoder, bus <= 0, a non-finite value */
#define MC_CTRL_ALIGN_ERR_TRAVEL      (1u << 4) /**< the rotor moved beyond travel_max_m_rad */
#define MC_CTRL_ALIGN_ERR_NOT_SETTLED (1u << 5) /**< no rest within t_timeout_s */
#define MC_CTRL_ALIGN_ERR_DIRECTION \
    (1u << 6) /**< the sweep measured off by more than sweep_tol: encoder
                   direction, pole pairs or counts per turn wrong */
#define MC_CTRL_ALIGN_ERR_LOAD \
    (1u << 7) /**< the rotor moved more than load_tol when the current
                   halved: a load would bias the offset */
#define MC_CTRL_ALIGN_ERR_NO_MOTION (1u << 8)  /**< the rotor does not follow the vector */
#define MC_CTRL_ALIGN_ERR_NOT_FOUND (1u << 9)  /**< no index within the travel, both ways */
#define MC_CTRL_ALIGN_ERR_ENCODER   (1u << 10) /**< the encoder capability's read failed */
#define MC_CTRL_ALIGN_ERR_SLIP \
    (1u << 11) /**< the rotor left the vector: more than 3/2 pi el. from its start
                    before the first rest, more than pi/2 el. off the vector's
                    turn after it (a load it cannot hold) */

typedef enum {
    MC_CTRL_ALIGN_RUNNING = 0,
    MC_CTRL_ALIGN_DONE = 1,  /**< result valid; current ramped to 0 */
    MC_CTRL_ALIGN_FAILED = 2 /**< fail names why; the step returned it */
} mc_ctrl_align_status_t;

/** The vector and the rotor's travel (shared by both laws). */
typedef struct {
    mc_foc_f32_t foc;
    float theta_cmd_e_rad;  /**< the vector's angle, [0, 2 pi) */
    float cmd_travel_e_rad; /**< signed angle the vector has turned since reset */
    float i_cmd_a;          /**< its magnitude (the d current along it) */
    float iq_cmd_a;         /**< the damping current at 90 degrees to it */
    float damping_a_s_rad;  /**< iq = -this omega_m */
    float iq_max_a;         /**< sqrt(i_max^2 - i_cmd^2): |i| <= i_max */
    float i_max_a;
    bool have_pos;
    float theta_m_prev_rad;
    float theta_m0_rad; /**< mechanical angle at the first step */
    float travel_m_rad; /**< signed travel since the first step [rad] */
    uint32_t foc_err;
} mc_ctrl_align_vec_t;

typedef struct {
    mc_foc_f32_cfg_t foc;      /**< the current loop (as the drive's); foc.dt_s the PWM period */
    uint32_t pole_pairs;       /**< >= 1 */
    float i_max_a;             /**< the drive's current limit [A], > 0 */
    float i_align_a;           /**< the vector's magnitude [A], (0, i_max_a] */
    float t_ramp_s;            /**< each current ramp [s], [1e-3, 5] */
    float t_settle_s;          /**< rest this long counts as settled [s], [1e-3, 5] */
    float t_timeout_s;         /**< longest settle [s], [t_settle_s, 60] */
    float still_band_m_rad;    /**< spread of the angle at rest [rad mech.], (0, 0.1]:
                                      a few counts */
    float sweep_e_rad;         /**< s [rad el.], [pi/8, pi/2] */
    float omega_sweep_e_rad_s; /**< the vector's speed in the sweeps [rad/s el.], (0, 1000] */
    float sweep_tol_e_rad;     /**< |measured sweep - s| allowed [rad el.], (0, s/2] */
    float load_tol_e_rad;      /**< |P_D - P_C| allowed [rad el.], (0, pi/4] */
    float damping_a_s_rad;     /**< iq per rad/s [A s/rad], [0, 1e3]; for a damping ratio
                                      z: 2 z sqrt(k J) / k_t with k = k_t i p, k_t = 3/2 p psi */
    float travel_max_m_rad;    /**< |theta_m - start| allowed [rad mech.],
                                      >= 1.25 (pi + 3 s) / pole_pairs, <= 4 pi:
                                      the snap onto the first vector (up to
                                      pi el.) and the sweeps (3 s) */
} mc_ctrl_align_cfg_t;

typedef struct {
    mc_ctrl_align_status_t status;
    uint32_t fail;           /**< MC_CTRL_ALIGN_ERR_* when FAILED */
    float offset_e_rad;      /**< DONE: the electrical angle of the d axis at
                                 encoder count 0 [rad], [0, 2 pi): the drive's
                                 encoder_offset_rad */
    float sweep_e_rad;       /**< measured P_B - P_A [rad el.] */
    float hysteresis_e_rad;  /**< (P_C - P_B) / 2: friction's hold [rad el.] */
    float load_shift_e_rad;  /**< P_D - P_C [rad el.] */
    float travel_peak_m_rad; /**< largest |travel| [rad mech.] */
} mc_ctrl_align_result_t;

typedef struct {
    mc_ctrl_align_cfg_t cfg;
    uint32_t n_ramp, n_settle, n_timeout; /**< derived: periods */
    mc_ctrl_align_vec_t v;
    uint32_t phase;                   /**< internal sequence step */
    uint32_t n_phase;                 /**< periods in this phase */
    uint32_t n_still;                 /**< periods at rest in a row (the window's length) */
    float win_lo_m_rad, win_hi_m_rad; /**< the window's angle spread */
    float i_from_a;                   /**< the ramp's start */
    float i_to_a;                     /**< the ramp's end */
    float target_e_rad;               /**< the sweep's end (commanded travel) */
    float p_0, cmd_0;                 /**< the first rest: position, vector's travel [rad el.] */
    float p_a, p_b, p_c, p_d;         /**< positions [rad el., travel since the start] */
    mc_ctrl_align_result_t res;
    mc_drive_ctrl_t ops;
} mc_ctrl_align_t;

/** Validate cfg and set up (the sequence starts at the drive's reset op).
 *  @return MC_CTRL_ALIGN_ERR_CFG / _FOC / _NULL; c untouched on error. */
uint32_t mc_ctrl_align_init(mc_ctrl_align_t *c, const mc_ctrl_align_cfg_t *cfg);
/** The table for mc_drive_attach_ctrl (PWM3, needs the encoder). */
const mc_drive_ctrl_t *mc_ctrl_align_ops(mc_ctrl_align_t *c);
/** Start over (the table's reset). */
uint32_t mc_ctrl_align_reset(mc_ctrl_align_t *c);
/** One fast step (the table's fast): the error bits on failure. */
uint32_t mc_ctrl_align_fast(mc_ctrl_align_t *c, const mc_drive_meas_t *m, mc_drive_out_t *out);
/** The status and result so far. */
uint32_t mc_ctrl_align_get_result(const mc_ctrl_align_t *c, mc_ctrl_align_result_t *p_res);

typedef struct {
    mc_foc_f32_cfg_t foc;          /**< the current loop (as the drive's) */
    uint32_t pole_pairs;           /**< >= 1 */
    float i_max_a;                 /**< the drive's current limit [A], > 0 */
    float i_search_a;              /**< the vector's magnitude [A], (0, i_max_a] */
    float t_ramp_s;                /**< current ramps [s], [1e-3, 5] */
    float omega_search_e_rad_s;    /**< the vector's speed [rad/s el.], (0, 2000] */
    float damping_a_s_rad;         /**< iq per rad/s of the speed error [A s/rad], [0, 1e3]:
                                        iq = -this (omega_m - the vector's speed / p) */
    float travel_max_m_rad;        /**< search this far each way [rad mech.],
                                        [2 pi / pole_pairs, 20 pi] */
    int32_t first_direction;       /**< +1 or -1 */
    const mc_hal_encoder_t *p_enc; /**< read each step for FLAG_INDEX; required */
} mc_ctrl_idx_cfg_t;

typedef struct {
    mc_ctrl_align_status_t status;
    uint32_t fail;               /**< MC_CTRL_ALIGN_ERR_* when FAILED */
    int32_t direction;           /**< the direction it was found in (+-1), 0 before */
    float travel_at_index_m_rad; /**< the rotor's travel from the start when found */
    float travel_peak_m_rad;     /**< largest |travel| [rad mech.] */
} mc_ctrl_idx_result_t;

typedef struct {
    mc_ctrl_idx_cfg_t cfg;
    uint32_t n_ramp;
    mc_ctrl_align_vec_t v;
    uint32_t phase;
    uint32_t n_phase;
    int32_t dir;          /**< present direction */
    float cmd_leg0_e_rad; /**< commanded travel when this leg started */
    float pos_leg0_e_rad; /**< measured travel when this leg started */
    float i_from_a;
    mc_ctrl_idx_result_t res;
    mc_drive_ctrl_t ops;
} mc_ctrl_idx_t;

/** Validate cfg and set up. @return MC_CTRL_ALIGN_ERR_*; c untouched on error. */
uint32_t mc_ctrl_idx_init(mc_ctrl_idx_t *c, const mc_ctrl_idx_cfg_t *cfg);
const mc_drive_ctrl_t *mc_ctrl_idx_ops(mc_ctrl_idx_t *c);
uint32_t mc_ctrl_idx_reset(mc_ctrl_idx_t *c);
uint32_t mc_ctrl_idx_fast(mc_ctrl_idx_t *c, const mc_drive_meas_t *m, mc_drive_out_t *out);
uint32_t mc_ctrl_idx_get_result(const mc_ctrl_idx_t *c, mc_ctrl_idx_result_t *p_res);

#ifdef __cplusplus
}
#endif

#endif /* MC_CTRL_ALIGN_H */
