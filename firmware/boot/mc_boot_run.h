/**
 * @file mc_boot_run.h
 * @brief The bootloader's update mode, the part every board shares: serve
 *        mc_boot_update on the board's CAN until a reset is due, then let
 *        the replies leave and reset. The boards (the STM32F405's
 *        boot_f405.c, the emulated one hal/pil/mc_boot_pil.c) supply the
 *        clock, the CAN bus, the wait and the reset.
 */
#ifndef MC_BOOT_RUN_H
#define MC_BOOT_RUN_H

#include <stdbool.h>
#include <stdint.h>

#include "hal/can.h"
#include "mc_boot_update.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Longest wait for the last reply to leave before the reset [ms]. */
#define MC_BOOT_TX_DRAIN_MS 20u

typedef struct mc_boot_board {
    const mc_hal_can_t *can;
    uint32_t (*now_ms)(void *ctx); /**< a millisecond clock (wraps) */
    void (*idle)(void *ctx);       /**< nothing to do: wait (or NULL) */
    void (*feed)(void *ctx);       /**< the watchdog (or NULL) */
    bool (*tx_idle)(void *ctx);    /**< every frame sent has left (or NULL) */
    void (*reset)(void *ctx);      /**< does not return on the MCU */
    void *ctx;
} mc_boot_board_t;

/**
 * Update mode: initialise u from cfg at the board's time, then loop: feed,
 * ANNOUNCE when due, every received frame into mc_boot_update, idle when
 * nothing came; when a reset is due (COMMIT, RUN), wait up to
 * MC_BOOT_TX_DRAIN_MS for the replies to leave and reset. Returns only if
 * the reset returns (a host test) or cfg is refused (the init's bits).
 */
uint32_t mc_boot_run(mc_boot_update_t *u, const mc_boot_update_cfg_t *cfg,
                     const mc_boot_board_t *b);

#ifdef __cplusplus
}
#endif

#endif /* MC_BOOT_RUN_H */
