/**
 * @file mc_boot_run.c
 * @brief The bootloader's update mode: see mc_boot_run.h.
 */
#include "mc_boot_run.h"

#include <stddef.h>

static void send(const mc_boot_board_t *b, const mc_hal_can_frame_t *f)
{
    (void)mc_hal_can_send(b->can, f); /* a full mailbox drops it: the host asks again */
}

static void drain(const mc_boot_board_t *b)
{
    const uint32_t t0 = b->now_ms(b->ctx);
    while ((b->tx_idle != NULL) && !b->tx_idle(b->ctx) &&
           ((b->now_ms(b->ctx) - t0) < MC_BOOT_TX_DRAIN_MS)) {
        if (b->idle != NULL) {
            b->idle(b->ctx);
        }
    }
}

uint32_t mc_boot_run(mc_boot_update_t *u, const mc_boot_update_cfg_t *cfg, const mc_boot_board_t *b)
{
    mc_hal_can_frame_t f;
    mc_hal_can_frame_t r;
    const uint32_t err = mc_boot_update_init(u, cfg, b->now_ms(b->ctx));
    if (err != MC_BOOT_CFG_OK) {
        return err;
    }
    for (;;) {
        bool got = false;
        if (b->feed != NULL) {
            b->feed(b->ctx);
        }
        if (mc_boot_update_poll(u, b->now_ms(b->ctx), &r) == 1u) {
            send(b, &r);
        }
        while (mc_hal_can_receive(b->can, &f) == 0) {
            got = true;
            if (mc_boot_update_rx(u, &f, &r) == 1u) {
                send(b, &r);
            }
        }
        if (mc_boot_update_action(u) == MC_BOOT_ACT_RESET) {
            drain(b);
            b->reset(b->ctx);
            return MC_BOOT_CFG_OK;
        }
        if (!got && (b->idle != NULL)) {
            b->idle(b->ctx);
        }
    }
}
