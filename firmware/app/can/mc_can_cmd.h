/**
 * @file mc_can_cmd.h
 * @brief CAN command handler: validates and applies the commands of
 *        tools/can/motordrive.dbc, replies to a rejected one, and stops the
 *        drive safely when the host falls silent.
 *
 * Commands (host -> drive, id = node_id << 5 | cmd):
 *   DISABLE           (cmd 0x00, the node's lowest id: it wins arbitration
 *                     against everything the node and its host send)
 *                     outputs off at once (IDLE), stop_reason DISABLE_CMD
 *   SET_ENABLE        1: enter the drive mode of the selected control mode,
 *                     the references starting from the present state:
 *                     CURRENT zero current, SPEED the measured speed,
 *                     POSITION the position at enable;
 *                     0: as DISABLE
 *   SET_CONTROL_MODE  CURRENT, SPEED or POSITION; only while disabled; SPEED
 *                     and POSITION need the application's setpoint hooks
 *   SET_CURRENT_REF   id, iq references (control mode CURRENT)
 *   SET_SPEED_REF     speed reference (SPEED), |w| <= speed_max_rad_s
 *   SET_POSITION_REF  multi-turn angle target (POSITION) [rad] in the frame
 *                     of the POSITION telemetry (mc_telemetry_theta_multi_rad,
 *                     from boot), |theta| <= 200000 rad (DBC); the hook gets
 *                     it relative to the angle at enable (the position law
 *                     counts from there)
 *                     The three references are refused (MODE) while the
 *                     drive is disabled: a reference set then would be a
 *                     step on enable.
 *   CLEAR_FAULTS      mc_drive_clear_faults(); not while enabled
 *   SET_TM_RATE       one telemetry message's rate (bus budget checked;
 *                     HEARTBEAT not below MC_TM_HEARTBEAT_MIN_HZ:
 *                     HEARTBEAT_MIN)
 *   HOST_HEARTBEAT    keep-alive (the only one, below): its counter must
 *                     advance by 1..MC_CAN_HB_STEP_MAX modulo 256 over the
 *                     last accepted one; a repeat, a step back or a larger
 *                     jump is refused STALE and changes nothing (the first
 *                     one of a run sets the reference)
 *   PARAM_REQ         parameter read / write / apply / save / load defaults
 *                     / confirm (mc_param_srv.h), answered by one
 *                     PARAM_REPLY with a status; needs
 *                     mc_can_cmd_attach_params (else UNSUPPORTED); served
 *                     only when its reply can go out (below)
 *   BOOT_REQ          firmware update requests the application serves
 *                     (INFO, VERSION, the confirmed ENTER; can/mc_boot_enter.h),
 *                     each answered by its BOOT_REPLY; needs
 *                     mc_can_cmd_attach_boot (else UNSUPPORTED). BOOT_DATA
 *                     is the bootloader's: refused MODE
 *   COMMISSION_CMD    start / abort / report commissioning
 *                     (commission/mc_comm_can.h); needs
 *                     mc_can_cmd_attach_commission (else UNSUPPORTED);
 *                     START refused MODE while enabled or stopping; while
 *                     it runs SET_ENABLE 1, SET_CONTROL_MODE and
 *                     CLEAR_FAULTS are refused MODE (SET_ENABLE 0 stops
 *                     it), and it needs the keep-alive as an enabled drive
 *
 * Validation, in this order, before anything changes: format (classic data
 * frame), known command, exact length, every signal in its DBC range, then
 * the state (control mode, enabled, stopping) and the drive's own checks.
 * A rejected command changes nothing; the drive answers with CMD_ERROR
 * (rejected command id, error code, received length) and records it for
 * the heartbeat. Frames for another node, extended frames and frames with
 * telemetry ids of other nodes are ignored silently.
 *
 * Replies: every reply (CMD_ERROR, PARAM_REPLY, the application's
 * BOOT_REPLY, and the commissioning frames through mc_comm_can_step)
 * takes a token of one limiter, `reply`
 * (mc_telemetry.h: MC_TM_REPLY_BURST, MC_TM_REPLY_MAX_HZ; reserved in the
 * telemetry's bus budget). A CMD_ERROR without a token is not sent: the
 * rejection is counted (reply_limited) and still shown in the HEARTBEAT.
 * A PARAM_REQ is served only if its PARAM_REPLY can go out now or wait in
 * the one held slot (sent at the next step with a token, before anything
 * else); while a reply is held a further PARAM_REQ is not served at all
 * (LIMITED, counted, in the HEARTBEAT): a host that waits for each reply
 * is never refused, a flood costs the bus the limiter's share and the
 * drive nothing. A BOOT_REQ takes its token before it is served (no held
 * slot: without one, LIMITED; the boot handler's own budget,
 * mc_boot_proto.h, is the looser one).
 *
 * Receive filter: mc_can_cmd_poll() drops a frame of another node (or an
 * extended frame) after one comparison of its identifier, and such frames
 * do not use the poll's budget of max_frames handled frames (they have
 * their own, larger one,
 * MC_CAN_RX_FOREIGN_MAX per call), so a flood from other nodes cannot
 * delay this node's commands. At a 1 kHz tick the poll drains 64000
 * foreign frames per second, three times a 1 Mbit/s bus full of the
 * shortest frames (about 21000 per second).
 *
 * Command timeout: while enabled (and while commissioning runs), only a
 * HOST_HEARTBEAT whose counter advanced (above) keeps the drive alive; no
 * other command does (protocol 3 counted any accepted command, refused
 * PARAM_REQs included). A run (enable, commissioning START) starts the
 * count and takes its first HOST_HEARTBEAT's counter as the reference.
 * If no keep-alive arrives for timeout_s the drive stops safely and
 * reports stop_reason CMD_TIMEOUT (commissioning: aborted with
 * MC_COMM_ERR_HOST_LOST, bridge off at once).
 *   CURRENT   (torque mode, any configuration) both current references
 *             ramp to zero at stop_ramp_a_per_s, then IDLE.
 * SPEED and POSITION with the drive's controlled stop configured
 * (mc_drive_cfg_t.stop_decel_rad_s2 > 0; always from the parameter table):
 * mc_drive_stop(), the drive decelerates to standstill at that rate without
 * reversing the rotor and opens the bridge (MODE_STOPPING); the run ends
 * when it has. Without it:
 *   SPEED     the speed reference ramps to zero at stop_decel_rad_s2
 *             through the application's hook; the bridge opens when the
 *             rotor is at rest (|omega_m| <= the drive's stop_rest_rad_s,
 *             or MC_CAN_STOP_REST_RAD_S if that is 0), at the latest
 *             2 |omega_0| / decel + 0.1 s after the stop began;
 *   POSITION  with a control law that has a stop op (mc_drive_ctrl_t.stop,
 *             e.g. the position law: it re-plans a stop at
 *             stop_decel_rad_s2): that stop, then IDLE at rest as in SPEED;
 *             without one, IDLE at once.
 * During the stop, setpoint and enable commands are refused (MODE);
 * SET_ENABLE 0 ends it at once. A drive fault while enabled ends the run
 * with stop_reason FAULT.
 *
 * The rotor angle at enable (mc_drive.h, angle_ref): an enable whose drive
 * mode needs the encoder while the angle is unknown since power-up is
 * refused ANGLE_UNKNOWN (the drive's -EACCES), unless the application finds
 * the angle first (mc_can_cmd_attach_angle: its hook starts an alignment or
 * an index search in CTRL mode). The run then begins at once (the keep-alive
 * counts, SET_ENABLE 0 ends it, a lost keep-alive ends it at once with
 * CMD_TIMEOUT); SET_SPEED_REF is accepted and takes effect, slewed, when
 * the angle is found; SET_CURRENT_REF and SET_POSITION_REF are refused MODE
 * until then (their references start from the present state at the
 * hand-over, as at an enable).
 * mc_can_cmd_angle_found() enters the selected mode: the references from
 * the present state, as at an enable (SPEED then slews to the reference the
 * host set during the find); the application ends a failed find with
 * mc_can_cmd_end_run(MC_CAN_STOP_ANGLE_FIND).
 */
#ifndef MC_CAN_CMD_H
#define MC_CAN_CMD_H

#include <stdbool.h>
#include <stdint.h>

#include "hal/can.h"
#include "mc_can_proto.h"
#include "mc_drive.h"
#include "mc_param_srv.h"
#include "mc_telemetry.h"

#ifdef __cplusplus
extern "C" {
#endif

/* CAN control modes (DBC values of control_mode). */
#define MC_CAN_CTRL_NONE     0u
#define MC_CAN_CTRL_CURRENT  1u
#define MC_CAN_CTRL_SPEED    2u
#define MC_CAN_CTRL_POSITION 3u

/* Stop reasons (DBC values of HEARTBEAT.stop_reason). */
#define MC_CAN_STOP_NONE        0u
#define MC_CAN_STOP_CMD_TIMEOUT 1u
#define MC_CAN_STOP_DISABLE_CMD 2u
#define MC_CAN_STOP_FAULT       3u
#define MC_CAN_STOP_ANGLE_FIND  4u /**< the find of the angle at enable failed */

/** |omega_m| at which a CAN-side stop counts the rotor at rest when the
 *  drive's stop_rest_rad_s is 0 [rad/s]. */
#define MC_CAN_STOP_REST_RAD_S 0.5f

/** Foreign frames (other nodes) mc_can_cmd_poll drops per call at most. */
#define MC_CAN_RX_FOREIGN_MAX 64u

/** Largest advance of the HOST_HEARTBEAT counter (modulo 256) accepted as
 *  a keep-alive: a host may lose up to 7 frames in a row and go on. A
 *  random counter passes with probability 8/256; a repeated set of values
 *  needs at least 256 / 8 = 32 different frames in a cycle. */
#define MC_CAN_HB_STEP_MAX 8u

/* Configuration errors (bits) of mc_can_cmd_init. */
#define MC_CAN_CMD_CFG_OK          0u
#define MC_CAN_CMD_CFG_ERR_NULL    (1u << 0) /**< NULL command state, cfg or drive */
#define MC_CAN_CMD_CFG_ERR_NODE    (1u << 1) /**< node_id > 62 */
#define MC_CAN_CMD_CFG_ERR_TICK    (1u << 2) /**< tick_hz 0 or > 100 kHz */
#define MC_CAN_CMD_CFG_ERR_TIMEOUT (1u << 3) /**< timeout_s not in [1 tick, 60 s] */
#define MC_CAN_CMD_CFG_ERR_RAMP    (1u << 4) /**< a stop ramp <= 0 or not finite */
#define MC_CAN_CMD_CFG_ERR_SPEED   (1u << 5) /**< speed_max_rad_s <= 0 or not finite */
#define MC_CAN_CMD_CFG_ERR_MODE    (1u << 6) /**< a hook without a usable drive mode */

/** Setpoint hook of the application (speed loop, position loop): 0 to
 *  accept, non-zero to refuse (the command is then REFUSED). */
typedef int (*mc_can_cmd_ref_fn)(void *ctx, float ref);

typedef struct {
    uint8_t node_id;                    /**< 0..62 */
    uint32_t tick_hz;                   /**< call rate of mc_can_cmd_step [Hz] */
    float timeout_s;                    /**< command timeout while enabled [s] */
    float stop_ramp_a_per_s;            /**< current ramp of a safe stop [A/s] */
    float stop_decel_rad_s2;            /**< speed ramp of a safe stop [rad/s^2] */
    float speed_max_rad_s;              /**< largest |speed reference| [rad/s] */
    mc_can_cmd_ref_fn set_speed_ref;    /**< NULL: SPEED unsupported */
    mc_can_cmd_ref_fn set_position_ref; /**< NULL: POSITION unsupported */
    void *hook_ctx;
    mc_drive_mode_t speed_drive_mode;    /**< drive mode that runs the speed
                                              loop (CTRL, or CURRENT if the
                                              hook sets current references) */
    mc_drive_mode_t position_drive_mode; /**< same for POSITION */
} mc_can_cmd_cfg_t;

/** Commissioning front end (commission/mc_comm_can.h): the command with
 *  its signal values in DBC order, whether a sequence runs, and the abort
 *  when the host's keep-alive stops. */
typedef mc_can_err_t (*mc_can_cmd_comm_fn)(void *ctx, const float *v);
typedef bool (*mc_can_cmd_busy_fn)(const void *ctx);
typedef void (*mc_can_cmd_lost_fn)(void *ctx);

/** Firmware update requests (BOOT_REQ): the frame, whether the drive must
 *  not reset now (enabled, stopping, commissioning, or the SAVE bucket not
 *  full: mc_param_srv_save_budget_full); the handler answers
 *  on can itself (BOOT_REPLY). */
typedef void (*mc_can_cmd_boot_fn)(void *ctx, const mc_hal_can_frame_t *p_frame, bool busy,
                                   const mc_hal_can_t *can);

/** The angle at enable (mc_can_cmd_attach_angle): called by SET_ENABLE 1
 *  with the drive mode it is about to enter, the references already set.
 *  Returns 0: enter it (the angle is known or not needed); 1: a find of the
 *  angle started (the drive runs it in CTRL mode); < 0: refuse the enable
 *  ANGLE_UNKNOWN (nothing started). */
typedef int (*mc_can_cmd_angle_fn)(void *ctx, mc_drive_mode_t mode);

typedef struct mc_can_cmd {
    mc_can_cmd_cfg_t cfg;
    mc_drive_t *drive;
    mc_telemetry_t *tm;     /**< for SET_TM_RATE, or NULL */
    uint32_t timeout_ticks; /**< derived at init */
    uint8_t control_mode;   /**< MC_CAN_CTRL_* */
    bool enabled;
    bool stopping;              /**< safe stop in progress */
    bool stop_by_law;           /**< POSITION: the control law's stop op decelerates */
    bool stop_by_drive;         /**< the drive's controlled stop (SPEED, POSITION) */
    uint32_t stop_ticks_left;   /**< steps the stop may still wait for rest */
    uint8_t stop_reason;        /**< MC_CAN_STOP_* */
    uint32_t ticks_since_alive; /**< steps since the last keep-alive (a fresh
                                     HOST_HEARTBEAT, or the start of a run) */
    float omega_ref_rad_s;      /**< last accepted speed reference */
    float theta_ref_rad;        /**< last accepted angle reference (multi-turn) */
    float theta_enable_rad;     /**< multi-turn angle at enable (telemetry's frame) */
    uint8_t last_error;         /**< mc_can_err_t of the last rejection */
    uint8_t last_error_cmd;
    uint8_t err_seq; /**< sequence counter of CMD_ERROR */
    uint32_t rx_accepted;
    uint32_t rx_rejected;
    uint32_t reply_dropped;       /**< CMD_ERROR / PARAM_REPLY frames the HAL refused */
    uint32_t reply_limited;       /**< replies not sent (CMD_ERROR) or requests not
                                       served (PARAM_REQ): the reply limiter */
    uint32_t rx_foreign;          /**< frames of other nodes dropped by the poll */
    uint32_t poll_max;            /**< most frames (own + foreign) one poll read: the
                                 bound of the slow loop's CAN receive work */
    mc_tm_reply_lim_t reply;      /**< the one limiter of every reply */
    mc_hal_can_frame_t held;      /**< a PARAM_REPLY waiting for a token */
    const mc_hal_can_t *held_can; /**< ... the bus it goes to */
    bool held_have;               /**< ... there is one */
    bool hb_have;                 /**< a HOST_HEARTBEAT was accepted in this run */
    uint8_t hb_last;              /**< its counter */
    mc_param_srv_t *params;       /**< parameter service, or NULL */
    uint8_t can_state;            /**< HEARTBEAT.can_state (mc_hal_can_bus_state_t): set by
                                 the application from the controller's status */
    uint8_t cfg_status;           /**< HEARTBEAT.cfg_status: the parameter store's
                                       status (mc_param_srv_t.store_status: the boot
                                       status, STORED after a SAVE); EMPTY without a
                                       service (the configuration is not from flash) */
    mc_can_cmd_comm_fn comm_fn;   /**< COMMISSION_CMD, or NULL */
    mc_can_cmd_busy_fn comm_busy; /**< commissioning runs, or NULL */
    mc_can_cmd_lost_fn comm_lost; /**< abort it: the keep-alive stopped, or NULL */
    void *comm_ctx;
    mc_can_cmd_boot_fn boot_fn; /**< BOOT_REQ, or NULL */
    void *boot_ctx;
    mc_can_cmd_angle_fn angle_fn; /**< the angle at enable, or NULL */
    void *angle_ctx;
    bool angle_finding; /**< enabled, the application finds the angle */
} mc_can_cmd_t;

/** Validate cfg and initialise c (disabled, control mode NONE). tm may be
 *  NULL (SET_TM_RATE is then UNSUPPORTED). Returns MC_CAN_CMD_CFG_* bits;
 *  on error c is not changed. */
uint32_t mc_can_cmd_init(mc_can_cmd_t *c, const mc_can_cmd_cfg_t *cfg, mc_drive_t *drive,
                         mc_telemetry_t *tm);

/**
 * Serve PARAM_REQ with srv (NULL: detach). Installs srv's hook so that an
 * APPLY also checks and applies the CAN-side parameters: telemetry rates
 * (bus budget, refused as a whole), command timeout, stop ramps, speed
 * limit. The node id and bit rate are used only at the next boot.
 */
void mc_can_cmd_attach_params(mc_can_cmd_t *c, mc_param_srv_t *srv);

/** Serve COMMISSION_CMD with fn (NULL: detach; the command is then
 *  UNSUPPORTED); busy tells when other commands must wait and when the
 *  keep-alive is needed; lost aborts the sequence when it stops. */
void mc_can_cmd_attach_commission(mc_can_cmd_t *c, mc_can_cmd_comm_fn fn, mc_can_cmd_busy_fn busy,
                                  mc_can_cmd_lost_fn lost, void *ctx);

/** Serve BOOT_REQ with fn (NULL: detach; the request is then UNSUPPORTED). */
void mc_can_cmd_attach_boot(mc_can_cmd_t *c, mc_can_cmd_boot_fn fn, void *ctx);

/** Ask fn at every enable whether the angle must be found first (NULL:
 *  detach; an enable the drive refuses for the angle is ANGLE_UNKNOWN). */
void mc_can_cmd_attach_angle(mc_can_cmd_t *c, mc_can_cmd_angle_fn fn, void *ctx);

/** The application found the angle (the drive IDLE, the selected mode's law
 *  attached): enter the selected mode, the references from the present
 *  state (see the file comment). Returns 0, or -1 when the drive refused
 *  (the run then ends with stop_reason FAULT). */
int mc_can_cmd_angle_found(mc_can_cmd_t *c);

/** End the run now (bridge off, IDLE) with reason (MC_CAN_STOP_*). */
void mc_can_cmd_end_run(mc_can_cmd_t *c, uint8_t reason);

/**
 * Handle one received frame; on rejection queue a CMD_ERROR reply on can
 * (if can is not NULL).
 * @return MC_CAN_ERR_NONE (applied), MC_CAN_ERR_IGNORED (not for this
 *         node) or the rejection's code.
 */
mc_can_err_t mc_can_cmd_handle(mc_can_cmd_t *c, const mc_hal_can_frame_t *p_frame,
                               const mc_hal_can_t *can);

/** Receive and handle up to max_frames queued frames of this node,
 *  dropping up to MC_CAN_RX_FOREIGN_MAX frames of other nodes on the way.
 *  Returns how many frames were handled (foreign ones not counted). */
uint32_t mc_can_cmd_poll(mc_can_cmd_t *c, const mc_hal_can_t *can, uint32_t max_frames);

/** Supervision at tick_hz (slow loop): the reply limiter's refill and the
 *  held PARAM_REPLY, the parameter service's SAVE limiter, command timeout
 *  (also of commissioning), safe-stop ramp, end of the run on a drive
 *  fault. */
void mc_can_cmd_step(mc_can_cmd_t *c);

#ifdef __cplusplus
}
#endif

#endif /* MC_CAN_CMD_H */
