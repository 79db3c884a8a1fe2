/**
 * @file mc_telemetry.h
 * @brief Cyclic CAN telemetry with a rate per message and a bus budget.
 *
 * Messages (tools/can/motordrive.dbc; slot = command id - 1 up to
 * POSITION_REF, then in the order below; SET_TM_RATE names a message by its
 * command id: mc_telemetry_slot_of_cmd):
 *   HEARTBEAT  drive mode, CAN control mode, enabled/stopping, stop reason,
 *              fault bits, last rejected command; its rate is at least
 *              MC_TM_HEARTBEAT_MIN_HZ (it cannot be switched off)
 *   CURRENTS   i_d, i_q (Park of the sampled phase currents at the FOC's
 *              electrical angle)
 *   VOLTAGES   v_d, v_q of the current loop (0 outside CURRENT mode), DC bus
 *   SPEED      mechanical speed (encoder tracking loop) and CAN reference
 *   POSITION   multi-turn mechanical angle, electrical angle
 *   OBSERVER, CONTROLLER, STEPPER
 *              internals of a plugged control law (mc_telemetry_ext_t);
 *              not sent while the application gives none.
 *   CURRENT_REFS  the drive's dq current references
 *   POSITION_REF  the multi-turn CAN position reference
 *   BUS_CURRENT   the estimated DC-bus current and the bus limits in force
 *                 (mc_drive_bus.h)
 *   THERMAL       the winding estimate and the derated current limit
 * Every frame ends with its message's rolling 8-bit sequence counter, which
 * advances for every frame generated, so a frame the HAL could not queue
 * shows up as a gap at the logger.
 *
 * Ranges: the signals are sized for any motor the configuration allows
 * (currents +-8388 A at 1 mA, speeds +-8388 rad/s at 1 mrad/s, voltages
 * +-1310 V, position +-214748 rad = 34178 turns at 0.1 mrad). A value that
 * still does not fit is sent saturated to its range and the message's `sat`
 * bit says so (also for a value that is not a number, sent as 0).
 *
 * Multi-turn position: mc_telemetry_step() unwraps the drive's encoder
 * angle (theta_m, [0, 2 pi)) at every tick into whole turns, choosing the
 * turn count whose step is nearest the measured speed times the tick, so it
 * holds at any speed as long as the speed estimate is right to within half
 * a turn per tick. Turns count from the first step (the angle at boot).
 *
 * Scheduling: mc_telemetry_step() is called at tick_hz (the slow loop).
 * A phase accumulator per message sends rate_hz frames per second on
 * average for any rate up to tick_hz; the messages start at staggered
 * phases so their frames do not all fall on the same tick.
 *
 * Bus budget: the load of a configuration is
 *     (sum over messages of rate_hz * (55 + 10 dlc)
 *      + MC_TM_REPLY_RESERVE_HZ * (55 + 10 * 8)) / bitrate_bps
 * (worst-case stuffed length of an 11-bit classic frame, intermission
 * included; the second term the replies, below). init and
 * mc_telemetry_set_rate() refuse a configuration whose load exceeds
 * bus_budget_frac, itself at most MC_TM_BUDGET_FRAC_MAX so that commands
 * and other nodes keep at least 30 % of the bus.
 *
 * Replies: every frame the drive sends in answer to a host (CMD_ERROR,
 * PARAM_REPLY, COMMISSION_STATUS, COMMISSION_RESULT, the application's
 * BOOT_REPLY) takes a token of one
 * limiter (mc_tm_reply_lim_t, the command handler's): a bucket of
 * MC_TM_REPLY_BURST tokens refilled at MC_TM_REPLY_MAX_HZ. In any window
 * of T seconds at most MC_TM_REPLY_BURST + MC_TM_REPLY_MAX_HZ * T + 1
 * replies go out: 50 in any second, 40 per second sustained, whatever
 * arrives; the budget reserves MC_TM_REPLY_RESERVE_HZ = 50 frames per
 * second of the longest reply (8 bytes) for them.
 */
#ifndef MC_TELEMETRY_H
#define MC_TELEMETRY_H

#include <stdbool.h>
#include <stdint.h>

#include "hal/can.h"
#include "mc_can_proto.h"
#include "mc_drive.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Telemetry slots (the DBC command id - 1 up to POSITION_REF). */
typedef enum {
    MC_TM_HEARTBEAT = 0,
    MC_TM_CURRENTS = 1,
    MC_TM_VOLTAGES = 2,
    MC_TM_SPEED = 3,
    MC_TM_POSITION = 4,
    MC_TM_OBSERVER = 5,
    MC_TM_CONTROLLER = 6,
    MC_TM_STEPPER = 7,
    MC_TM_CURRENT_REFS = 8,
    MC_TM_POSITION_REF = 9,
    MC_TM_BUS_CURRENT = 10,
    MC_TM_THERMAL = 11,
    MC_TM_COUNT = 12
} mc_tm_slot_t;

#define MC_TM_HEARTBEAT_MIN_HZ 1u /**< the drive's HEARTBEAT cannot go below this */

/** Replies (CMD_ERROR, PARAM_REPLY, COMMISSION_*) sustained per second
 *  and the bucket's depth (see the file comment). */
#define MC_TM_REPLY_MAX_HZ 40u
#define MC_TM_REPLY_BURST  10u
/** Reply frames per second the bus budget reserves: the most a window of
 *  one second can carry. */
#define MC_TM_REPLY_RESERVE_HZ (MC_TM_REPLY_MAX_HZ + MC_TM_REPLY_BURST)
/** Data bytes of the longest reply (all four are 8 bytes). */
#define MC_TM_REPLY_DLC 8u

#define MC_TM_BUDGET_FRAC_MAX 0.7f /**< largest accepted bus_budget_frac */
#define MC_TM_BITRATE_MIN_BPS 10000u
#define MC_TM_BITRATE_MAX_BPS 1000000u
#define MC_TM_TICK_MAX_HZ     100000u

/* Configuration errors (bits) of mc_telemetry_init / _set_rate. */
#define MC_TM_CFG_OK            0u
#define MC_TM_CFG_ERR_NULL      (1u << 0) /**< NULL argument */
#define MC_TM_CFG_ERR_NODE      (1u << 1) /**< node_id > 62 */
#define MC_TM_CFG_ERR_BITRATE   (1u << 2) /**< bitrate outside [10 k, 1 M] bit/s */
#define MC_TM_CFG_ERR_TICK      (1u << 3) /**< tick_hz 0 or > 100 kHz */
#define MC_TM_CFG_ERR_RATE      (1u << 4) /**< a rate above tick_hz, or bad slot */
#define MC_TM_CFG_ERR_BUDGET    (1u << 5) /**< budget not in (0, MC_TM_BUDGET_FRAC_MAX] */
#define MC_TM_CFG_ERR_LOAD      (1u << 6) /**< load of the rates above the budget */
#define MC_TM_CFG_ERR_HEARTBEAT (1u << 7) /**< HEARTBEAT rate below MC_TM_HEARTBEAT_MIN_HZ */

/** The reply limiter: a token bucket refilled at MC_TM_REPLY_MAX_HZ by a
 *  step at tick_hz. */
typedef struct {
    uint32_t tick_hz; /**< call rate of mc_tm_reply_lim_step [Hz], > 0 */
    uint32_t tokens;  /**< replies that may go out now, <= MC_TM_REPLY_BURST */
    uint32_t acc;     /**< refill accumulator, < tick_hz */
    uint32_t taken;   /**< tokens taken since init */
} mc_tm_reply_lim_t;

/** A full bucket for a step at tick_hz (0 is taken as 1). */
void mc_tm_reply_lim_init(mc_tm_reply_lim_t *l, uint32_t tick_hz);
/** One step (at tick_hz): the refill. */
void mc_tm_reply_lim_step(mc_tm_reply_lim_t *l);
/** Take a token for one reply: true if the reply may go out now. */
bool mc_tm_reply_lim_take(mc_tm_reply_lim_t *l);
/** A token is there (nothing taken). */
bool mc_tm_reply_lim_ready(const mc_tm_reply_lim_t *l);

typedef struct {
    uint8_t node_id;               /**< 0..62 */
    uint32_t bitrate_bps;          /**< nominal bus bit rate [bit/s] */
    float bus_budget_frac;         /**< share of the bus telemetry may use */
    uint32_t tick_hz;              /**< call rate of mc_telemetry_step [Hz] */
    uint16_t rate_hz[MC_TM_COUNT]; /**< frames per second, 0 = off */
} mc_telemetry_cfg_t;

/** Internals of a plugged control law, for OBSERVER, CONTROLLER, STEPPER. */
typedef struct {
    bool have_observer;
    float tau_l_hat_nm, omega_hat_rad_s, theta_hat_rad;
    bool have_controller;
    float nu_pu, vartheta_pu;
    bool have_stepper;
    float e1_rad, e2_rad_s, s1, s2;
} mc_telemetry_ext_t;

struct mc_can_cmd;   /* mc_can_cmd.h */
struct mc_telemetry; /* below */

/** What the telemetry reads each step. */
typedef struct {
    const mc_drive_t *drive;       /**< required */
    const struct mc_can_cmd *cmd;  /**< CAN command state, or NULL */
    const mc_telemetry_ext_t *ext; /**< control-law internals, or NULL */
    const struct mc_telemetry *tm; /**< for the multi-turn position, or NULL
                                         (POSITION then carries the single-turn
                                         angle) */
} mc_telemetry_src_t;

typedef struct mc_telemetry {
    mc_telemetry_cfg_t cfg;
    uint32_t acc[MC_TM_COUNT]; /**< phase accumulators, < tick_hz */
    uint8_t seq[MC_TM_COUNT];  /**< next sequence number per message */
    float load_frac;           /**< bus load of the present rates */
    uint32_t tx_frames;        /**< frames queued by the HAL */
    uint32_t tx_dropped;       /**< frames the HAL refused (any reason) */
    uint32_t tx_nobufs;        /**< ... of which tx queue full */
    uint32_t tx_busoff;        /**< ... of which bus-off */
    uint32_t last_fail_mask;   /**< slots whose frame the HAL refused, last step */
    uint32_t saturated;        /**< frames sent with their sat bit set */
    /* multi-turn position (see the header) */
    bool have_theta;
    float theta_prev_rad; /**< drive angle at the last tick, [0, 2 pi) */
    int32_t turns;        /**< whole turns since the first tick */
} mc_telemetry_t;

/** Bus load (fraction of bitrate_bps) of cfg's rates plus the replies'
 *  reserve (MC_TM_REPLY_RESERVE_HZ frames of MC_TM_REPLY_DLC bytes); 0 for
 *  a NULL cfg or a zero bit rate. */
float mc_telemetry_bus_load(const mc_telemetry_cfg_t *cfg);

/** Validate cfg (including the load against the budget) and initialise t.
 *  Returns MC_TM_CFG_* bits; on error t is not changed. */
uint32_t mc_telemetry_init(mc_telemetry_t *t, const mc_telemetry_cfg_t *cfg);

/** Change one message's rate. Returns MC_TM_CFG_OK, MC_TM_CFG_ERR_NULL,
 *  MC_TM_CFG_ERR_RATE (bad slot or rate > tick_hz), MC_TM_CFG_ERR_HEARTBEAT
 *  (HEARTBEAT below its minimum) or MC_TM_CFG_ERR_LOAD; on error nothing
 *  changes. */
uint32_t mc_telemetry_set_rate(mc_telemetry_t *t, uint32_t slot, uint16_t rate_hz);

/**
 * The signal values message `slot` would carry now (sequence counter
 * excluded: values[last] is left as is), in DBC signal order, with the
 * message's `sat` signal set if another signal does not fit its range.
 * @return false if the source has no data for it (ext NULL or its have_*
 *         flag false, bad slot, NULL argument).
 */
bool mc_telemetry_values(uint32_t slot, const mc_telemetry_src_t *src,
                         float values[MC_CAN_NSIG_MAX]);

/**
 * One scheduler tick: pack and queue the messages that are due.
 * @return bit mask (1 << slot) of the frames generated this tick (each
 *         advanced its sequence counter); t->last_fail_mask tells which of
 *         them the HAL refused.
 */
uint32_t mc_telemetry_step(mc_telemetry_t *t, const mc_hal_can_t *can,
                           const mc_telemetry_src_t *src);

/** Multi-turn mechanical angle [rad] of the last step (single-turn drive
 *  angle before the first step). */
float mc_telemetry_theta_multi_rad(const mc_telemetry_t *t, const mc_drive_t *drive);

/** DBC message index (MC_CAN_MSG_*) of a slot. */
uint32_t mc_telemetry_msg(uint32_t slot);

/** The slot of the telemetry message with command id cmd (MC_CAN_CMD_*),
 *  MC_TM_COUNT if none. */
uint32_t mc_telemetry_slot_of_cmd(uint32_t cmd);

#ifdef __cplusplus
}
#endif

#endif /* MC_TELEMETRY_H */
