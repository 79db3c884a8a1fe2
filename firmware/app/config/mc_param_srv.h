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

/** Extra check of a staged set by the front end (e.g. the CAN bus budget of
 *  the telemetry rates), and its apply: check returns 0 to accept. */
typedef struct {
    uint32_t (*check)(void *ctx, const mc_params_t *staged);
    void (*apply)(void *ctx, const mc_params_t *active);
    void *ctx;
} mc_param_hook_t;

typedef struct {
    mc_params_t active; /**< the configuration in effect */
    mc_params_t staged; /**< writes land here */
    bool pending;       /**< staged differs from active (written since APPLY) */
    mc_drive_t *drive;
    const mc_hal_t *hal;
    mc_cfg_store_t *store; /**< NULL: SAVE answers STORE */
    uint8_t boot_status;   /**< mc_cfg_boot_t of the boot */
    uint8_t store_status;  /**< the store's status now (HEARTBEAT.cfg_status,
                                cfg_store_status): the boot status until a SAVE,
                                then STORED (the applied set is the newest record)
                                or, when the SAVE failed, FLASH */
    mc_param_hook_t hook;  /**< optional (fields NULL) */
    uint32_t applied;      /**< successful APPLYs */
    uint32_t law_error;    /**< the law_error parameter (the application's) */
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
 * One request. *p_value: in, the raw value (WRITE); out, the reply value
 * (READ/WRITE: the staged value; APPLY refused INVALID: MC_PARAMS_ERR_*
 * bits; SAVE: the record's sequence number; else 0).
 */
mc_param_status_t mc_param_srv_request(mc_param_srv_t *s, uint32_t op, uint32_t id,
                                       uint32_t *p_value);

#ifdef __cplusplus
}
#endif

#endif /* MC_PARAM_SRV_H */
