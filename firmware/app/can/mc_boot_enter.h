/**
 * @file mc_boot_enter.h
 * @brief The application's side of the firmware update (BOOT_REQ of
 *        tools/can/motordrive.dbc): INFO and VERSION, and entering the
 *        bootloader only with a confirmation.
 *
 *   INFO           OK, value board_id | layout_id << 8 | protocol << 16
 *   VERSION        OK, value the running image's version
 *   ENTER          value MC_BOOT_ENTER_KEY (else KEY); refused BUSY while
 *                  the drive runs (enabled, stopping, commissioning);
 *                  answered CONFIRM with a fresh token in value
 *   ENTER_CONFIRM  value = that token, within MC_BOOT_CONFIRM_MS of the
 *                  ENTER (else KEY, and the token is spent); BUSY as
 *                  above; OK: mc_boot_enter_due() becomes true, and the
 *                  application resets into the bootloader at its next slow
 *                  step (after the OK has left)
 *   BEGIN .. RUN   STATE: only the bootloader updates (boot_state APP)
 *   other ops      OPCODE; a frame that is not 8 bytes: FORMAT
 * Every answer is one BOOT_REPLY with boot_state APP, through the shared
 * reply budget (mc_boot_proto.h).
 *
 * No heap, no globals: the instance is the application's.
 */
#ifndef MC_BOOT_ENTER_H
#define MC_BOOT_ENTER_H

#include <stdbool.h>
#include <stdint.h>

#include "hal/can.h"
#include "mc_boot_proto.h"

#ifdef __cplusplus
extern "C" {
#endif

/** How long a token stays valid [ms]. */
#define MC_BOOT_CONFIRM_MS 1000u

/** What the running image says about itself (its header). */
typedef struct {
    uint32_t board_id;
    uint32_t layout_id;
    uint32_t app_version;
} mc_boot_enter_cfg_t;

typedef struct {
    mc_boot_enter_cfg_t cfg;
    uint8_t node_id;
    uint32_t us_per_step; /**< period of mc_boot_enter_step's calls */
    uint32_t now_us;      /**< wraps after 71 minutes: only differences are used */
    uint32_t token;       /**< 0: none outstanding */
    uint32_t token_us;    /**< when it was given */
    uint32_t rng;         /**< token generator state (xorshift32) */
    bool due;             /**< confirmed: reset into the bootloader */
    mc_boot_bucket_t bucket;
    uint32_t replies_limited;
} mc_boot_enter_t;

/** Start with the image's identity; node_id of this node, step_hz the rate
 *  of mc_boot_enter_step (1 .. 1 MHz; the slow loop's). seed mixes into the
 *  tokens (the board's tick counter, for instance). */
void mc_boot_enter_init(mc_boot_enter_t *e, const mc_boot_enter_cfg_t *cfg, uint8_t node_id,
                        uint32_t step_hz, uint32_t seed);

/**
 * Handle one BOOT_REQ of this node (the caller checked its identifier).
 * busy: the drive must not stop now (running, stopping, commissioning).
 * Returns 1 with *p_reply filled when a reply is to be sent (0: the reply
 * budget is spent, counted in replies_limited).
 */
uint32_t mc_boot_enter_handle(mc_boot_enter_t *e, const mc_hal_can_frame_t *p_frame, bool busy,
                              mc_hal_can_frame_t *p_reply);

/** Once per slow step: time, token expiry, reply budget. */
void mc_boot_enter_step(mc_boot_enter_t *e);

/** The confirmation arrived: the caller resets into the bootloader. */
bool mc_boot_enter_due(const mc_boot_enter_t *e);

#ifdef __cplusplus
}
#endif

#endif /* MC_BOOT_ENTER_H */
