/**
 * @file mc_param_srv.h
 * @brief The parameter service: read / write / apply / save / load defaults
 *        on the drive's configuration, with every check before anything
 *        changes. The CAN handler (mc_can_cmd.c, PARAM_REQ) is its front end.
 *
 * Two copies: `active` (what the drive runs) and `staged` (where writes
 * land). The apply point is APPLY: the staged set is validated as a whole
 * (mc_params_validate: ranges, sensor full scale, bandwidth vs PWM rate,
 * dead time, bit rate, then the drive's own init checks) and only then put
 * into effect, all at once, in the context that calls the service (the
 * slow loop on the MCU: between two slow steps, never inside a fast step).
 *   bridge off:  the drive is re-initialised with the new mc_drive_cfg_t
 *                (mc_drive_init; the attached control law is re-attached);
 *   bridge on:   allowed only if no stopped/reboot parameter differs from
 *                the active set; the runtime limits are copied into the
 *                running drive's configuration.
 * reboot parameters (CAN node id, bit rate) are part of the applied and
 * saved set but used only at the next boot.
 *
 * Confirmation (reboot parameters): a WRITE of a new value for one of
 * them stages nothing; it is answered NEEDS_CONFIRM and arms a CONFIRM.
 * The very next PARAM_REQ must be CONFIRM with the same id and value,
 * within MC_PARAM_CONFIRM_WINDOW_S: then the value is staged (OK). Any
 * other request in between, another id or value, or a late CONFIRM:
 * NOT_CONFIRMED, nothing staged (a lone CONFIRM likewise). A WRITE of the
 * value already staged is a plain OK. LOAD_DEFAULTS keeps the staged
 * reboot values (it cannot move the node). So a node id or bit rate
 * takes two distinct frames in order, then APPLY, SAVE and a reset
 * (protocol 3: WRITE, APPLY, SAVE from any node).
 *
 * SAVE and the flash: SAVE of a set the store's newest record already
 * holds (mc_cfg_store_holds) writes nothing and answers OK with that
 * record's sequence number. Other SAVEs take a token of a bucket of
 * MC_PARAM_SAVE_BURST saves refilled one per MC_PARAM_SAVE_PERIOD_S (the
 * bucket is full at boot); without one: RATE_LIMIT, the reply value the
 * seconds until the next. Worst case, a host saving a changed set as
 * often as allowed for a year: 8766 h x 30 saves, each sector erased
 * once per 2 x (records per sector) saves (mc_cfg_store.h): on the F405's
 * 128 KiB sectors the erases per sector per year are in
 * firmware/app/config/README.md (measured by test_mc_app, McAppGuards,
 * which requires the F405's 10 000 cycles to last at least 10 years of
 * it: a parameter table grown past about 120 stored parameters needs a
 * longer MC_PARAM_SAVE_PERIOD_S). A reset refills the bucket: the one
 * reset a CAN node can cause, into the bootloader (BOOT_REQ ENTER), is
 * refused BUSY until the bucket is full again (mc_param_srv_save_budget_full),
 * so resets add no SAVE to that bound. The time base is mc_param_srv_tick (the CAN
 * handler's step): without it the bucket does not refill and the CONFIRM
 * window does not close.
 *
 * Refusals (nothing changes): any mutating operation while a fault is
 * latched (FAULT: only the clear path works then); a stopped/reboot write,
 * SAVE, LOAD_DEFAULTS or an APPLY that needs the bridge off while it is on
 * (RUNNING); unknown id; readonly id written; a value out of range or not
 * finite (RANGE); a staged set that fails validation (INVALID, with the
 * MC_PARAMS_ERR_* bits as the reply value).
 */
#ifndef MC_PARAM_SRV_H
#define MC_PARAM_SRV_H

#include <stdbool.h>
#include <stdint.h>

#include "mc_cfg_store.h"
#include "mc_drive.h"
#include "mc_params.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Opcodes (DBC PARAM_REQ.opcode). */
#define MC_PARAM_OP_READ          0u
#define MC_PARAM_OP_WRITE         1u
#define MC_PARAM_OP_APPLY         2u
#define MC_PARAM_OP_SAVE          3u
#define MC_PARAM_OP_LOAD_DEFAULTS 4u
#define MC_PARAM_OP_CONFIRM       5u

/** SAVE rate limit: bucket depth, and seconds per refilled save. */
#define MC_PARAM_SAVE_BURST    4u
#define MC_PARAM_SAVE_PERIOD_S 120u
/** A CONFIRM must follow its WRITE within this [s]. */
#define MC_PARAM_CONFIRM_WINDOW_S 2u

/** Extra check of a staged set by the front end (e.g. the CAN bus budget of
 *  the telemetry rates), and its apply: check returns 0 to accept. save
 *  (optional) runs after a SAVE stored the configuration (or found it
 *  stored): the front end's own records (the application's anticogging map
 *  from a calibration), 0 or a negative errno (the SAVE answers STORE). */
typedef struct {
    uint32_t (*check)(void *ctx, const mc_params_t *staged);
    void (*apply)(void *ctx, const mc_params_t *active);
    void *ctx;
    int (*save)(void *ctx);
} mc_param_hook_t;

typedef struct {
    mc_params_t active; /**< the configuration in effect */
    mc_params_t staged; /**< writes land here */
    bool pending;       /**< staged differs from active (written since APPLY) */
    mc_drive_t *drive;
    const mc_hal_t *hal;
    mc_cfg_store_t *store;   /**< NULL: SAVE answers STORE */
    uint8_t boot_status;     /**< mc_cfg_boot_t of the boot */
    uint8_t store_status;    /**< the store's status now (HEARTBEAT.cfg_status,
                                cfg_store_status): the boot status until a SAVE,
                                then STORED (the applied set is the newest record)
                                or, when the SAVE failed, FLASH */
    mc_param_hook_t hook;    /**< optional (fields NULL) */
    uint32_t applied;        /**< successful APPLYs */
    uint32_t law_error;      /**< the law_error parameter (the application's) */
    uint32_t angle_error;    /**< the angle_error parameter (the application's) */
    uint32_t hall_error;     /**< the hall_error parameter (the application's) */
    float hall_obs_weight;   /**< the hall_obs_weight parameter (the application's) */
    uint32_t cog_status;     /**< the cog_status parameter (the application's) */
    uint32_t cog_cal_status; /**< the cog_cal_status parameter (the application's) */
    uint32_t cog_persist;    /**< what a SAVE stores for anticogging while the
                                  set in force has 2 (a calibration runs: 2
                                  is a request, not a setting to boot with):
                                  the value before it (the application's) */
    /* time base (mc_param_srv_tick) */
    uint32_t tick_hz;       /**< rate of mc_param_srv_tick [Hz] (0: not yet known) */
    uint32_t save_tokens;   /**< SAVEs allowed now, <= MC_PARAM_SAVE_BURST */
    uint32_t save_acc;      /**< ticks towards the next token */
    uint32_t saves_skipped; /**< SAVEs of an unchanged set (nothing written) */
    uint32_t saves_limited; /**< SAVEs refused RATE_LIMIT */
    /* a reboot parameter's WRITE waiting for its CONFIRM */
    bool confirm_have;
    uint32_t confirm_id;
    uint32_t confirm_value;
    uint32_t confirm_left; /**< ticks left in the window */
} mc_param_srv_t;

/**
 * Start from a loaded configuration (mc_cfg_store_load, or the defaults)
 * that the drive already runs (the caller did mc_drive_init with
 * mc_params_to_drive_cfg(p)). store may be NULL. Returns 0, or -EINVAL
 * (NULL drive/hal/p, or p not valid).
 */
int mc_param_srv_init(mc_param_srv_t *s, const mc_params_t *p, mc_drive_t *drive,
                      const mc_hal_t *hal, mc_cfg_store_t *store, uint8_t boot_status);

/**
 * One request. *p_value: in, the raw value (WRITE, CONFIRM); out, the
 * reply value (READ/WRITE/CONFIRM: the staged value, NEEDS_CONFIRM: the
 * value waiting; APPLY refused INVALID: MC_PARAMS_ERR_* bits; SAVE: the
 * record's sequence number, RATE_LIMIT: seconds to wait; else 0).
 */
mc_param_status_t mc_param_srv_request(mc_param_srv_t *s, uint32_t op, uint32_t id,
                                       uint32_t *p_value);

/** The time base, called at tick_hz (> 0): the SAVE bucket's refill and
 *  the CONFIRM window. */
void mc_param_srv_tick(mc_param_srv_t *s, uint32_t tick_hz);

/** The SAVE bucket is full (or there is no service): a reset now gives the
 *  next boot no SAVE the limiter had not already allowed. The application
 *  refuses to reset into the bootloader otherwise (BOOT_REQ ENTER BUSY). */
bool mc_param_srv_save_budget_full(const mc_param_srv_t *s);

#ifdef __cplusplus
}
#endif

#endif /* MC_PARAM_SRV_H */
