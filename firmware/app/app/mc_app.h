/**
 * @file mc_app.h
 * @brief The drive application around the drive: CAN receive (an interrupt
 *        ring), the node filter, command handling, telemetry, the command
 *        timeout, parameter access and the configuration loaded from flash,
 *        the control modes (plug-ins), the CAN controller's state and the
 *        watchdog. The MCU image's main and the SIL's AppTarget (the
 *        simulator's scenarios) only bind it; both run exactly this code.
 *
 * Instances are the caller's (static on the MCU, no heap). One mc_app_t per
 * drive; the drive (mc_drive_t) is the caller's too, since on the MCU it
 * lives in core-coupled RAM and in the SIL inside the simulated board's rig.
 *
 * Life cycle
 *   mc_app_boot()    reset cause (watchdog HAL), the configuration: the
 *                    newest valid record of the A/B flash store, else the
 *                    board's defaults, and why (boot_status, the heartbeat's
 *                    cfg_status). A stored set that the board cannot run
 *                    (another PWM rate or slow-loop divider than the board's
 *                    fixed ones) boots the defaults with status INVALID.
 *   mc_app_start()   the drive from those parameters (unless the caller
 *                    initialised it itself), telemetry, command handler,
 *                    parameter service, the hardware receive filter for
 *                    this node's ids, the watchdog. A stored set with
 *                    brake_enable on a board without a brake chopper
 *                    (mc_hal_t.brake NULL), or with vbus_board_max_v above
 *                    the board's (its defaults': the bus limit its divider
 *                    reads and its rating allow) or 0 where the board has
 *                    one, boots the defaults with status INVALID; an APPLY
 *                    of it is refused INVALID with MC_PARAMS_ERR_BOARD
 *                    (nothing changes). vbus_max_v above vbus_board_max_v
 *                    is refused the same way (mc_params_validate).
 *   mc_app_fast_step()  ADC interrupt: the drive's fast step, and the mark
 *                    that the fast loop ran.
 *   mc_app_can_rx_isr() CAN receive interrupt: moves every received frame
 *                    from the HAL into the ring, dropping other nodes' ids
 *                    first; a full ring counts an overflow (rx_overflows).
 *   mc_app_slow_step()  slow loop: the drive's slow step, then
 *                    mc_app_slow_work(): commands from the ring, the command
 *                    handler's supervision (timeout), the CAN controller's
 *                    state, telemetry, the watchdog.
 *
 * Watchdog: fed at the end of a slow step only when the fast loop has run
 * since the previous feed (mc_app_fast_step marks it): a hung fast loop (no
 * ADC interrupt, or stuck in it) and a hung slow loop both stop the feeding,
 * and the watchdog resets the MCU; the pins' reset state turns the bridge
 * off. Around a flash erase (a configuration SAVE, bridge off, the CPU
 * stalled for up to 2 s on a 128 KiB sector) the timeout is stretched to
 * wdg_erase_timeout_ms and restored afterwards.
 *
 * APP_STATUS (tools/can/motordrive.dbc, cmd 0x0E): reset cause, boot
 * status of the configuration, CAN state and error counters, application
 * faults, frames lost; queued at the first slow step when the watchdog HAL
 * reports a reset cause, and at every change of the CAN state or of the
 * application faults (retried while the controller refuses to send).
 *
 * CAN controller state (slow loop, mc_hal_can_get_status): error-passive or
 * bus-off latches MC_APP_FAULT_CAN_PASSIVE / MC_APP_FAULT_CAN_BUS_OFF and
 * sets the drive's warning MC_DRIVE_WARN_CAN_BUS: a running drive makes a
 * controlled stop (mc_drive.h, STOPPING) and cannot be enabled again until
 * CLEAR_FAULTS once the controller is error-active or warning again; the
 * CAN run ends with stop_reason FAULT when the drive has stopped.
 *
 * Control modes: CURRENT (the drive's dq loop); SPEED by a plugged speed
 * law (mc_drive_ctrl_t in CTRL mode: the sensored speed law, sensorless
 * with I-f start, PI2D, ...); POSITION by a plugged position law. A law's
 * setpoint hook and telemetry extension come with it (mc_app_law_t).
 *
 * Firmware update (mc_app_cfg_t.boot and enter_boot, the board's): BOOT_REQ
 * INFO, VERSION and the confirmed ENTER (can/mc_boot_enter.h). Once ENTER
 * is confirmed, the next slow step opens the bridge and calls enter_boot,
 * which resets into the bootloader (the board's; it does not return on the
 * MCU). Without a binding BOOT_REQ is refused UNSUPPORTED.
 *
 * Laws from the parameters (mc_app_cfg_t.laws_from_params; the MCU images
 * and the SIL): the application owns the sensorless, PI2D and position
 * instances and fills the two slots itself from the booted parameters:
 * SPEED runs the law the speed_law parameter selects (MC_LAW_SPEED_*: the
 * sensored speed law mc_ctrl_speed, sensorless with I-f start, PI2D),
 * POSITION the position cascade (with an encoder, encoder_cpr > 0). Gains
 * come from the parameters (derived from the motor values unless set:
 * mc_params.h, mc_law_cfg.h, mc_gains.h). A law its values cannot run is
 * not plugged (SPEED or POSITION answers UNSUPPORTED) and the readonly
 * parameter law_error says why. An APPLY with the bridge off rebuilds the
 * laws; it is refused INVALID with MC_PARAMS_ERR_LAW when a law's init
 * refuses the new values (law_error: why; the previous laws stay). With the
 * bridge on an APPLY changes only runtime parameters (the service refuses
 * the others, RUNNING) and never rebuilds a law: the laws take the drive's
 * limits in force each step (a lower i_max_a saturates them at once). The
 * speed laws' reference is the drive's (mc_drive_set_speed_ref): SET_SPEED_REF
 * sets its target, the drive slews it at speed_ramp_rad_s2 (its
 * acceleration is the laws' feed-forward) and ramps it to zero in a
 * controlled stop: one owner of the reference for every speed law.
 *
 * The rotor angle after a power-up (laws_from_params; angle_ref,
 * mc_drive.h): with angle_ref index or align the application builds the
 * index search or the alignment (ctrl/mc_ctrl_align.h, mc_law_find_cfg).
 * An enable whose mode needs the encoder (CURRENT, the sensored laws)
 * while mc_drive_angle_state() says the angle is unknown:
 *   angle_find_at_enable 1  the finder is attached and runs in CTRL mode
 *                      (the run has begun: the keep-alive counts); when it
 *                      is done (the slow step sees it) the measured offset
 *                      is set (align; index: the drive took the index), the
 *                      bridge opens for that step, the selected law is
 *                      attached and the selected mode entered from the
 *                      present state (mc_can_cmd_angle_found). A failure
 *                      (the finder's error bits fault the drive, bridge
 *                      off in that fast step) ends the run with stop_reason
 *                      ANGLE_FIND and the readonly parameter angle_error
 *                      = the finder's MC_CTRL_ALIGN_ERR_* bits;
 *   angle_find_at_enable 0  the enable is refused ANGLE_UNKNOWN (CMD_ERROR,
 *                      HEARTBEAT.last_error), the bridge stays off.
 * The finders run only during a find: the fast loop's cost afterwards is
 * the selected law's. A re-init of the drive (an APPLY that changes its
 * configuration) forgets the angle (align) as mc_drive_init does.
 */
#ifndef MC_APP_H
#define MC_APP_H

#include <stdbool.h>
#include <stdint.h>

#include "hal/flash.h"
#include "hal/hal.h"
#include "hal/hall.h"
#include "hal/wdg.h"
#include "commission/mc_comm_can.h"
#include "commission/mc_comm_cog.h"
#include "mc_boot_enter.h"
#include "mc_can_cmd.h"
#include "mc_cfg_store.h"
#include "mc_ctrl_pi2d.h"
#include "mc_ctrl_position.h"
#include "mc_ctrl_sensorless.h"
#include "mc_ctrl_speed.h"
#include "mc_drive.h"
#include "mc_drive_hall.h"
#include "mc_law_cfg.h"
#include "mc_param_srv.h"
#include "mc_params.h"
#include "mc_telemetry.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Frames the receive ring holds (a power of two). */
#define MC_APP_RX_RING_LEN 32u
/** Frames handled per slow step (the rest wait in the ring). */
#define MC_APP_RX_PER_STEP 16u

/* Application faults (mc_app_t.faults): sticky until CLEAR_FAULTS. */
#define MC_APP_FAULT_NONE           0u
#define MC_APP_FAULT_CAN_PASSIVE    (1u << 0) /**< CAN controller error-passive */
#define MC_APP_FAULT_CAN_BUS_OFF    (1u << 1) /**< CAN controller bus-off */
#define MC_APP_FAULT_CAN_RX_OVERRUN (1u << 2) /**< receive ring (or controller FIFO) overflowed */
#define MC_APP_FAULT_WDG            (1u << 3) /**< the watchdog could not be started */

/* Configuration errors (bits) of mc_app_boot / mc_app_start. */
#define MC_APP_CFG_OK         0u
#define MC_APP_CFG_ERR_NULL   (1u << 0) /**< NULL app, cfg, hal, drive or defaults */
#define MC_APP_CFG_ERR_PARAMS (1u << 1) /**< the parameters do not give a drive config */
#define MC_APP_CFG_ERR_DRIVE  (1u << 2) /**< mc_drive_init refused (drive_err) */
#define MC_APP_CFG_ERR_TM     (1u << 3) /**< telemetry refused (tm_err) */
#define MC_APP_CFG_ERR_CMD    (1u << 4) /**< command handler refused (cmd_err) */
#define MC_APP_CFG_ERR_STORE  (1u << 5) /**< the flash sectors refused by the store */
#define MC_APP_CFG_ERR_WDG    (1u << 6) /**< wdg_timeout_ms out of range */
#define MC_APP_CFG_ERR_SPEED  (1u << 7) /**< (unused: the speed loop is a law) */
#define MC_APP_CFG_ERR_LAW    (1u << 8) /**< a plugged law refused by the drive */

/** Single-producer (the CAN interrupt) single-consumer (the slow loop)
 *  ring: the producer writes a slot, then publishes tail with a release
 *  store; the consumer loads tail with acquire, copies the frame, then
 *  publishes head (GCC/Clang __atomic builtins on 32-bit words: single
 *  loads and stores on the Cortex-M4, with the barriers the ordering needs).
 *  The indices run freely and wrap at 2^32; the slot is index % length. */
typedef struct {
    mc_hal_can_frame_t frames[MC_APP_RX_RING_LEN];
    uint32_t head; /**< next frame to take; written by the consumer only */
    uint32_t tail; /**< next free slot; written by the producer only */
} mc_app_rx_ring_t;

/** Push (producer side). Returns false, and stores nothing, when full. */
bool mc_app_rx_ring_push(mc_app_rx_ring_t *r, const mc_hal_can_frame_t *p_frame);
/** Pop (consumer side). Returns false when empty. */
bool mc_app_rx_ring_pop(mc_app_rx_ring_t *r, mc_hal_can_frame_t *p_frame);

/** A control law plugged for SPEED or POSITION (CTRL mode). */
typedef struct {
    const mc_drive_ctrl_t *ctrl;      /**< the law (attached while its mode runs) */
    mc_can_cmd_ref_fn set_ref;        /**< its setpoint */
    void *ctx;                        /**< set_ref's context */
    const mc_telemetry_ext_t *tm_ext; /**< its internals for OBSERVER ..., or NULL */
} mc_app_law_t;

typedef struct {
    const mc_hal_flash_t *flash; /**< configuration store's flash, or NULL */
    uint32_t flash_sectors[2];   /**< its A and B sectors */
    uint32_t flash_axis;         /**< whose records this application keeps there: 0
                                      (a one-axis board, a two-axis board's M0) or 1
                                      (its M1); the two share the sectors
                                      (mc_cfg_store.h, "Axes") */
    const mc_hal_wdg_t *wdg;     /**< independent watchdog, or NULL */
    /** The board's Hall inputs, or NULL: with encoder_type 1 the drive's
     *  encoder is the Hall kernel on them (mc_drive_hall.h; the board's own
     *  hal.encoder is not used); encoder_type 1 without them is refused
     *  (MC_PARAMS_ERR_BOARD). */
    const mc_hal_hall_t *hall;
    uint32_t wdg_timeout_ms;       /**< normal timeout (> 2 slow periods) */
    uint32_t wdg_erase_timeout_ms; /**< timeout around a flash erase */
    const mc_params_t *defaults;   /**< the board's defaults */
    uint32_t pwm_hz_fixed;         /**< the board's PWM rate (0: any) */
    uint32_t slow_loop_div_fixed;  /**< the board's slow divider (0: any) */
    float tm_budget_frac;          /**< share of the bus telemetry may use */
    /** Rates of the messages past POSITION: OBSERVER, CONTROLLER, STEPPER,
     *  CURRENT_REFS, POSITION_REF, THERMAL [Hz] (the parameter table has the first
     *  five). */
    uint16_t tm_ext_rate_hz[MC_TM_COUNT - MC_TM_OBSERVER];
    mc_app_law_t speed_law;    /**< plugged speed law (ctrl NULL: SPEED unsupported) */
    mc_app_law_t position_law; /**< plugged position law (ctrl NULL: none) */
    /** true: the two slots above are the application's, built from the
     *  parameters (see the file comment); false: the caller's. */
    bool laws_from_params;
    /** Program the hardware receive filter for this node's identifiers
     *  (id & mask == node << 5); NULL: the board has none. */
    int (*set_rx_filter)(void *ctx, uint32_t id, uint32_t mask);
    void *filter_ctx;
    /** The running image's identity for BOOT_REQ, or NULL (not served). */
    const mc_boot_enter_cfg_t *boot;
    /** Reset into the bootloader (after a confirmed ENTER); with boot. */
    void (*enter_boot)(void *ctx);
    void *boot_ctx;
} mc_app_cfg_t;

/** The laws the application builds from the parameters, and the
 *  configurations they were built from (to see what an APPLY changes). */
typedef struct {
    mc_ctrl_speed_t spd;
    mc_ctrl_sls_t sls;
    mc_ctrl_pi2d_t pi2d;
    mc_ctrl_pos_t pos;
    mc_ctrl_speed_cfg_t spd_cfg;
    mc_ctrl_sls_cfg_t sls_cfg;
    mc_ctrl_pi2d_cfg_t pi2d_cfg;
    mc_ctrl_pos_cfg_t pos_cfg;
    mc_ctrl_align_t align; /**< the alignment at enable (angle_ref align) */
    mc_ctrl_idx_t idx;     /**< the index search at enable (angle_ref index) */
    mc_ctrl_align_cfg_t align_cfg;
    mc_ctrl_idx_cfg_t idx_cfg;
    mc_telemetry_ext_t sls_ext; /**< OBSERVER from the sensorless law */
    float sls_speed_max_rad_s;  /**< the sensorless law's speed limit [rad/s] */
    uint32_t speed_law;         /**< MC_LAW_SPEED_* plugged */
    uint32_t error;             /**< law_error: MC_GAINS_ERR_* | MC_LAW_ERR_* */
    uint32_t angle_ref;         /**< MC_DRIVE_ANGLE_REF_* of the laws' set */
    bool spd_ok, sls_ok, pi2d_ok, pos_ok;
    bool align_ok, idx_ok; /**< the finder angle_ref selects is built */
    bool find_at_enable;   /**< angle_find_at_enable */
} mc_app_laws_t;

/* Fields ordered by size (pointers, structs, words, bytes): no padding. */
typedef struct {
    mc_drive_t *drive;
    const mc_hal_t *hal;        /**< the drive's board */
    const mc_hal_can_t *can;    /**< the CAN bus, or NULL */
    mc_comm_can_t *comm;        /**< commissioning over CAN, or NULL */
    mc_hal_flash_t flash_wrap;  /**< the store's flash: stretches the watchdog */
    mc_hal_t hal_hall;          /**< the board's HAL with the Hall as its encoder
                                    (encoder_type 1: hal points here) */
    mc_drive_hall_t hall;       /**< the Hall sensors as the drive's encoder */
    mc_drive_hallobs_t hallobs; /**< Hall + observer (hall_obs_end_e_rad_s > 0) */
    bool hallobs_on;            /**< hallobs attached to the drive */
    mc_cog_map_t cog_map;       /**< the anticogging map (valid when cog_loaded) */
    bool cog_loaded;            /**< cog_map holds a map (loaded or stored) */
    bool cog_unsaved;           /**< cog_map built since its last save: a SAVE stores it */
    uint32_t cog_load_status;   /**< MC_COG_ST_* of the map's load (EMPTY: none) */
    mc_comm_cog_t cog_cal;      /**< the anticogging calibration (anticogging 2) */
    bool cog_cal_run;           /**< cog_cal runs (mc_app.h, MC_APP_COG_CAL_*) */
    uint32_t cog_cal_pass;      /**< cog_cal's pass, 0 .. MC_APP_COG_CAL_PASSES - 1 */
    mc_param_hook_t cmd_hook;   /**< the command handler's APPLY hook, chained */
    mc_telemetry_src_t tm_src;
    mc_can_cmd_t cmd;
    mc_app_cfg_t cfg;
    mc_param_srv_t srv;
    mc_cfg_store_t store;
    /* boot */
    uint32_t reset_cause; /**< MC_HAL_WDG_RESET_* at boot */
    /* CAN */
    uint32_t rx_overflows;   /**< frames lost: ring full (in the interrupt) */
    uint32_t rx_foreign;     /**< frames of other nodes dropped */
    uint32_t hw_rx_overruns; /**< controller FIFO overruns (HAL status) */
    uint32_t tm_sent;        /**< frames mask of the last telemetry step */
    /* APP_STATUS (cmd 0x0E): at boot when a reset cause is known, and at each
     * change of the CAN state, of the application faults or of the store's
     * status (a SAVE); retried at the next slow steps while the HAL refuses
     * it (bus-off) */
    uint32_t status_sent_key; /**< (faults, can_state) of the last one queued */
    uint8_t status_sent_cfg;  /**< cfg_status of the last one queued (boot: the boot status) */
    uint32_t status_frames;   /**< APP_STATUS frames queued */
    /* supervision */
    uint32_t faults;  /**< MC_APP_FAULT_* (sticky) */
    uint32_t tick_hz; /**< slow-loop rate [Hz] */
    /* watchdog */
    uint32_t fast_runs;     /**< fast steps (interrupt; __atomic access) */
    uint32_t fast_runs_fed; /**< fast_runs at the last feed */
    uint32_t wdg_feeds;
    /* errors of the start */
    uint32_t drive_err, tm_err, cmd_err;
    mc_hal_can_status_t can_status; /**< last status read */
    mc_telemetry_cfg_t tm_cfg;      /**< the telemetry configuration asked for */
    mc_telemetry_t tm;
    mc_params_t params; /**< the configuration booted */
    mc_app_rx_ring_t rx;
    mc_app_laws_t laws;    /**< laws_from_params */
    mc_boot_enter_t boot;  /**< BOOT_REQ (cfg.boot) */
    uint32_t boot_entries; /**< enter_boot calls (it returns only off the MCU) */
    uint8_t boot_status;   /**< mc_cfg_boot_t */
    bool params_valid;     /**< the parameter service runs */
    bool have_store;
    bool status_pending;
    uint8_t status_seq;
    bool was_enabled;  /**< CAN run state of the previous slow step */
    bool laws_rebuilt; /**< the last APPLY's check rebuilt the laws (bridge off) */
    bool wdg_running;
    bool boot_on; /**< BOOT_REQ served */
    /* the angle at enable (laws_from_params) */
    bool angle_running;   /**< a find runs (the finder attached, CTRL) */
    uint32_t angle_error; /**< MC_CTRL_ALIGN_ERR_* of the last find (0: none failed) */
    float pos_theta0_rad; /**< the encoder's angle at enable: the position law's frame */
} mc_app_t;

/** What a scenario reads of the drive after a period (the simulator's
 *  scenarios, in the SIL and through the processor-in-the-loop link): the
 *  drive's state and its loops' signals, and the plugged laws' telemetry. */
typedef struct {
    uint32_t mode, faults, first_fault, warnings, ctrl_err, stop_cause;
    uint32_t cmd_enabled, cmd_stop_reason, law_error;
    float id_ref_a, iq_ref_a; /**< the current loop's references (PI2D: the law's) */
    float id_a, iq_a;         /**< measured, in the loop's frame [A] */
    float vd_v, vq_v;         /**< the loop's voltage [V] */
    float theta_e_rad;        /**< the electrical angle the drive used [rad] (the encoder's,
                                   or the Hall + observer blend: mc_drive_hallobs.h) */
    float omega_m_rad_s;      /**< the encoder tracking loop's speed [rad/s] */
    float vbus_v;
    float regen_scale, brake_duty;
    float i_bus_est_a;            /**< the drive's estimated DC-bus current [A] (mc_drive_bus.h) */
    float i_bus_mot_lim_a;        /**< its motoring limit in force [A] (0: off) */
    float i_bus_regen_lim_a;      /**< its regenerative limit in force [A] (0: off) */
    float fw_v_mag_v, fw_v_max_v; /**< field weakening: |v| and its target [V] */
    float omega_ref_rad_s;        /**< the speed law's reference; the position law's
                                       trajectory speed [rad/s] */
    uint32_t asc_active;
    /* the sensorless law */
    uint32_t sls_phase, sls_handovers, sls_fallbacks;
    float sls_theta_hat_e_rad;
    float sls_omega_if_rad_s; /**< the I-f frame's speed, mechanical (mc_ctrl_sls_tm_t.
                                   omega_if_m_rad_s: 0 in ALIGN, the ramp in IF; in
                                   CLOSED the value it handed over at) [rad/s] */
    /* the position law */
    int32_t pos_turns;
    uint32_t pos_count;
    float pos_theta_ref_rad;
    float pos_traj_duration_s;
    uint32_t pos_traj_k;
    /* the CAN side's counters (a scenario's summary; tools see the same
     * through the frames): telemetry (mc_telemetry_t), the command handler
     * (mc_can_cmd_t), the receive interrupt (mc_app_t.rx_*) */
    float tm_load_frac;
    uint32_t tm_tx_frames, tm_tx_dropped, tm_tx_nobufs, tm_tx_busoff, tm_saturated;
    uint32_t cmd_rx_accepted, cmd_rx_rejected, cmd_reply_dropped, cmd_reply_limited;
    uint32_t cmd_rx_foreign, cmd_poll_max, app_rx_foreign, app_rx_overflows;
    /* the configuration: which law SPEED runs, the store at boot and since */
    uint32_t speed_law, tick_hz, boot_status, store_seq, store_saves, srv_applied;
    /* the rotor angle after a power-up: mc_drive_angle_state() (KNOWN,
     * NEED_INDEX, NEED_ALIGN), 1 while a find at enable runs, and the
     * MC_CTRL_ALIGN_ERR_* bits of the last find that failed */
    uint32_t angle_state, angle_finding, angle_error;
    /* thermal derating (mc_drive_thermal.h): the winding estimate [C] (the
     * ambient while the model is off) and the current limit in force [A] */
    float t_winding_est_c, i_limit_a;
    /* the Hall sensors (encoder_type 1): MC_HALL_ERR_* behind an ENCODER
     * fault (the parameter hall_error) */
    uint32_t hall_error;
    /* anticogging (mc_drive_cog.h): the cog_status parameter (MC_COG_ST_*:
     * OK the map is valid for the encoder in force and attached) and the
     * feed-forward the drive added to the q reference this period [A] */
    uint32_t cog_status;
    float cog_ff_a;
} mc_app_probe_t;

/** Fill *p from the application and its drive (after a period). */
void mc_app_probe(const mc_app_t *app, mc_app_probe_t *p);

/** Anticogging (mc_drive_cog.h; parameters anticogging, cog_status): the
 *  largest |feed-forward| a loaded map may ask, as a share of i_max_a (the
 *  law keeps the rest; the sum is clamped to the limit in force). */
#define MC_APP_COG_BOUND_FRAC 0.5f

/** The anticogging calibration (anticogging 2; mc_comm_cog.h, driven by
 *  the slow step with the speed law's reference): its ramps, the settle at
 *  speed (the speed loop's integral takes the friction), and the bounds: the
 *  two directions' disagreement at most MC_APP_COG_CAL_AGREE of the map's
 *  RMS plus MC_APP_COG_CAL_FLOOR_FRAC of i_max_a (the encoder's counts and
 *  the loop's noise on a motor with little cogging). The current is the
 *  speed loop's own, bounded by i_max_a; the map's amplitude by
 *  MC_APP_COG_BOUND_FRAC i_max_a (the builder's bound, checked first by the
 *  calibration). When it ends the application sets anticogging to 1 with the
 *  new map (0 when refused), the speed reference stays 0, cog_cal_status
 *  says the phase, the MC_COMM_COG_ERR_* bits << 8 and the builder's
 *  MC_COG_ST_* << 16. Leaving SPEED or disabling aborts it. */
/** The turns' speed [rad/s mechanical]: the speed loop's q reference is the
 *  cogging current only while the cogging frequency (the speed times the
 *  cogging order, 84 per turn for 12 slots / 14 poles: 8.4 rad/s) is well
 *  inside the speed loop's bandwidth (hundreds of rad/s); one map bin per
 *  slow step (refused MC_COMM_COG_ERR_CFG above it) allows 6 rad/s at 1 kHz. */
#define MC_APP_COG_CAL_SPEED_RAD_S 0.1f
#define MC_APP_COG_CAL_RAMP_S      0.5f
#define MC_APP_COG_CAL_SETTLE_S    1.0f
#define MC_APP_COG_CAL_AGREE       0.5f
#define MC_APP_COG_CAL_FLOOR_FRAC  0.005f
/** Passes of the calibration (iterative learning): the speed loop rejects
 *  the cogging torque only within its bandwidth, so one pass's reference
 *  carries a share of it (on the SK3 93 %, on the GM4108 55 %, where the
 *  cogging frequency at the turns' speed is 26 rad/s) and the rotor's
 *  speed ripple the rest; the next pass runs with the map of the one
 *  before as feed-forward and records the whole q reference (the map's
 *  current plus the loop's correction), which leaves the loop a residual
 *  that share smaller. Each pass is the whole sequence of mc_comm_cog.h;
 *  cog_cal_status carries the pass (0 first) in bits 24..31 while it runs.
 *  A later pass that fails leaves the map of the pass before it loaded
 *  (anticogging 0: not applied; SAVE would store it), not the map the drive
 *  had before the calibration. */
#define MC_APP_COG_CAL_PASSES 2u

/**
 * Load an anticogging map from a calibration's MC_COG_N q-axis currents [A]
 * per mechanical-angle bin (mc_cog_build, bound MC_APP_COG_BOUND_FRAC
 * i_max_a, the identity of the encoder the active parameters describe),
 * from the host (the SIL, mcsim) for now; the calibration will call it. The
 * map is detached while it is rebuilt and attached again when anticogging
 * is 1. A refused load changes nothing (the previous map, if any, stays).
 * @return MC_COG_ST_OK or the builder's refusal.
 */
mc_cog_status_t mc_app_cog_load(mc_app_t *app, const float *i_q_a, uint32_t n);

/**
 * Store the loaded map in the configuration store (its own record kind,
 * mc_cfg_store.h). BLOCKING (may erase a sector): only while the bridge is
 * off. Returns 0, -ENOENT (no valid map loaded), -EBUSY (the bridge is on),
 * -ENODEV (no store), -EIO (flash: the previous stored map stays).
 */
int mc_app_cog_save(mc_app_t *app);

/** Boot: reset cause, configuration (see the file comment). app is
 *  zeroed first. Returns MC_APP_CFG_* bits (only NULL, STORE, WDG); with
 *  STORE the defaults boot. */
uint32_t mc_app_boot(mc_app_t *app, const mc_app_cfg_t *cfg);

/**
 * Start with the booted parameters (app->params) on the board hal, CAN on
 * can (NULL: none; on the MCU hal->can). init_drive: initialise drive from
 * them (mc_params_to_drive_cfg, mc_drive_init); false: the caller
 * initialised it (the SIL with settings outside the parameter table), and
 * parameter access is then not served. The booted PWM rate and slow-loop
 * divider stay for the run: an APPLY that changes them is refused INVALID
 * (MC_PARAMS_ERR_DRIVE). Returns MC_APP_CFG_* bits.
 */
uint32_t mc_app_start(mc_app_t *app, mc_drive_t *drive, const mc_hal_t *hal,
                      const mc_hal_can_t *can, bool init_drive);

/** The body of the image's ADC interrupt (main.c ADC_IRQHandler, and the
 *  simulator's one period, hal_host::app_period): the drive's fast step and
 *  the fast-loop mark. Returns true when the slow step is due (the image
 *  pends PendSV, whose body is mc_app_slow_step). */
bool mc_app_fast_step(mc_app_t *app);

/** The fast-loop mark alone (when the caller runs the drive's fast step). */
void mc_app_fast_mark(mc_app_t *app);

/** CAN receive interrupt (or the SIL before each slow step): every frame
 *  the HAL has goes into the ring (foreign ids dropped). Returns how many
 *  were taken from the HAL. */
uint32_t mc_app_can_rx_isr(mc_app_t *app);

/** The body of the image's PendSV (main.c PendSV_Handler, and the
 *  simulator's hal_host::app_period): mc_drive_slow_step() then
 *  mc_app_slow_work(). */
void mc_app_slow_step(mc_app_t *app);

/** The application's part of the slow loop (see the file comment). Returns
 *  the telemetry frames generated (bit = slot). */
uint32_t mc_app_slow_work(mc_app_t *app);

/** Commissioning over CAN (COMMISSION_CMD/STATUS/RESULT): m initialised by
 *  the caller with mc_comm_can_init on app->drive and &app->srv (NULL when
 *  parameter access is not served). The command handler refuses enable and
 *  mode changes while it runs; the slow work steps it after the commands. */
void mc_app_attach_commission(mc_app_t *app, mc_comm_can_t *m);

/** HEARTBEAT can_state value (0 error-active .. 3 bus-off) now. */
uint32_t mc_app_can_state(const mc_app_t *app);

#ifdef __cplusplus
}
#endif

#endif /* MC_APP_H */
