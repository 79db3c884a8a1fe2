/**
 * @file mc_comm_cog.h
 * @brief Commissioning's anticogging calibration: the q-axis current the
 *        drive's speed loop asks per mechanical bin during a slow constant-
 *        speed turn forward and one back, averaged over both ways, as the
 *        currents mc_cog_build (drive/mc_drive_cog.h) makes the map from.
 *
 * Why a speed pass, not position holds: 1024 holds (one per bin) each
 * settled for tens of milliseconds take minutes; a turn each way at a
 * constant slow speed visits every bin in seconds. The speed loop rejects
 * the cogging torque, so its q reference carries it (plus friction and,
 * behind the loop's finite bandwidth, a lag in angle).
 *
 * The law. At a constant speed +w the mean reference in bin k is
 *   i_fwd[k] = cog(k - lag) + f,    going back at -w:  i_rev[k] = cog(k + lag) - f
 * (f: the friction's current, the same magnitude either way; lag: the
 * loop's delay as an angle, the same either way at the same speed). So
 *   cog[k] ~= (i_fwd[k] + i_rev[k]) / 2   (friction cancels; a lag's first
 * order cancels), and the mean is removed (a constant is load, not
 * cogging). The directions' disagreement d[k] = (i_fwd[k] - mean_fwd) -
 * (i_rev[k] - mean_rev) is what the average hid: lag, noise, a load that
 * depends on the angle one way only.
 *
 * Each bin's value is the reference interpolated linearly at the bin's
 * centre between the two samples around it (every crossing of it averaged):
 * a mean of the samples that fall in a bin is biased by where in the bin
 * they fall (up to half a bin's phase of a harmonic).
 *
 * The sequence (mc_comm_cog_step, called every dt_s with the angle and the
 * speed loop's q reference; it returns the speed reference to command):
 *   ramp to +w (t_ramp_s), settle (t_settle_s), record a turn and
 *   MC_COMM_COG_MARGIN_BINS bins, ramp to -w, settle, record the same back,
 *   ramp to 0; then DONE with the currents in mc_comm_cog_currents.
 *   Each recording ends within MC_COMM_COG_TIME_FACTOR times the turn's
 *   time at w, else ROTOR_BLOCKED.
 *
 * Current bound: the speed loop's own limit (the drive's i_max_a) bounds
 * what the pass can draw; the calibrated amplitude is refused beyond
 * i_bound_a (the share of the limit a map may take, MC_APP_COG_BOUND_FRAC).
 *
 * The errors (its own status field, 16 bits, not the commissioning's: that
 * one is full; MC_COMM_COG_ERR_*):
 *   NO_OFFSET  the encoder's electrical offset is not known (not
 *              commissioned): the speed loop's FOC would run on a wrong
 *              axis, and a map is bound to the offset (refused at start);
 *   BLOCKED    a recording did not cover a turn within its time;
 *   MEAS       an angle or current not finite, or a bin left without a
 *              sample in a direction (the rotor jumped over it);
 *   AMPLITUDE  |cog[k]| above i_bound_a;
 *   DISAGREE   rms(d) / 2 above agree_frac rms(cog) + i_floor_a;
 *   ABORTED    mc_comm_cog_abort.
 * cfg errors: MC_COMM_COG_ERR_CFG (init refuses, nothing changes).
 */
#ifndef MC_COMM_COG_H
#define MC_COMM_COG_H

#include <stdbool.h>
#include <stdint.h>

#include "drive/mc_drive_cog.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MC_COMM_COG_ERR_NONE      0u
#define MC_COMM_COG_ERR_CFG       (1u << 0)
#define MC_COMM_COG_ERR_NO_OFFSET (1u << 1)
#define MC_COMM_COG_ERR_BLOCKED   (1u << 2)
#define MC_COMM_COG_ERR_MEAS      (1u << 3)
#define MC_COMM_COG_ERR_AMPLITUDE (1u << 4)
#define MC_COMM_COG_ERR_DISAGREE  (1u << 5)
#define MC_COMM_COG_ERR_ABORTED   (1u << 6)

/** Bins recorded beyond a turn: the start bin's neighbours seen twice, a
 *  jitter of the angle at the turn's end does not leave a bin empty. */
#define MC_COMM_COG_MARGIN_BINS 8u
/** A recording's time limit over the turn's time at w: the speed loop
 *  holds w within a few percent against the cogging; twice the time is a
 *  rotor that does not follow (blocked, a load). */
#define MC_COMM_COG_TIME_FACTOR 2.0f

typedef enum {
    MC_COMM_COG_IDLE = 0,
    MC_COMM_COG_RAMP_FWD = 1,
    MC_COMM_COG_REC_FWD = 2,
    MC_COMM_COG_RAMP_REV = 3,
    MC_COMM_COG_REC_REV = 4,
    MC_COMM_COG_STOP = 5,
    MC_COMM_COG_DONE = 6,
    MC_COMM_COG_FAILED = 7,
} mc_comm_cog_phase_t;

typedef struct {
    float dt_s;        /**< step period [s], > 0 */
    float w_rad_s;     /**< calibration speed, mechanical [rad/s], > 0, with
                            w dt <= one bin (2 pi / MC_COG_N): every bin sampled */
    float t_ramp_s;    /**< ramp between speeds [s], > 0 */
    float t_settle_s;  /**< settle at speed before recording [s], >= 0 */
    float i_bound_a;   /**< largest |cog[k]| accepted [A], > 0 */
    float agree_frac;  /**< directions' disagreement bound (above), (0, 1] */
    float i_floor_a;   /**< ... plus this current [A] (noise), >= 0 */
    bool offset_known; /**< the encoder offset is commissioned */
} mc_comm_cog_cfg_t;

typedef struct {
    mc_comm_cog_cfg_t cfg;
    mc_comm_cog_phase_t phase;
    uint32_t err;
    float t_s;    /**< time in the phase [s] */
    float w_ref;  /**< speed reference now [rad/s] */
    float travel; /**< angle covered while recording [rad] */
    float theta_prev;
    float iq_prev;
    float sum[2][MC_COG_N];   /**< [0] forward, [1] back; currents on DONE */
    uint8_t cnt[2][MC_COG_N]; /**< crossings per bin (saturating: the image's RAM) */
    float rms_cog_a;          /**< rms of the result [A] (DONE) */
    float rms_dis_a;          /**< rms of d / 2 [A] (DONE) */
} mc_comm_cog_t;

/** Validate cfg and arm c (phase RAMP_FWD). MC_COMM_COG_ERR_CFG (c not
 *  changed) or NO_OFFSET (c FAILED). */
uint32_t mc_comm_cog_start(mc_comm_cog_t *c, const mc_comm_cog_cfg_t *cfg);

/** One step: theta_m_rad the encoder's mechanical angle, iq_ref_a the speed
 *  loop's q reference without any anticogging feed-forward. Writes the
 *  speed reference to command (0 once DONE or FAILED) and returns the
 *  sticky MC_COMM_COG_ERR_* bits. */
uint32_t mc_comm_cog_step(mc_comm_cog_t *c, float theta_m_rad, float iq_ref_a, float *p_w_ref);

/** Stop: FAILED with ABORTED, speed reference 0. */
void mc_comm_cog_abort(mc_comm_cog_t *c);

/** The MC_COG_N currents [A] for mc_cog_build once DONE, else NULL. */
const float *mc_comm_cog_currents(const mc_comm_cog_t *c);

#ifdef __cplusplus
}
#endif

#endif /* MC_COMM_COG_H */
