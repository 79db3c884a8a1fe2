/**
 * @file mc_spisched.c
 * @brief A slow loop's SPI frames run by the fast loop (mc_spisched.h).
 */
#include "mc_spisched.h"

#include <errno.h>
#include <stddef.h>

#define TIMEOUT_US_MAX 1000000u
#define TICK_HZ_MIN    1000000u

static int sched_transfer16(void *ctx, uint16_t tx, uint16_t *p_rx)
{
    mc_spisched_t *s = ctx;
    uint32_t seq;
    uint32_t t0 = 0u;
    uint32_t now = 0u;
    const uint32_t limit_ticks = (s->cfg.timeout_us) * (s->tick_hz / 1000000u);

    if (!s->deferred) {
        return mc_hal_spi_transfer16(s->cfg.p_dev, tx, p_rx);
    }
    if (mc_hal_tick_read(s->cfg.p_tick, &t0) != 0) {
        return -EIO;
    }
    seq = s->req_seq + 1u;
    s->tx = tx;
    s->rc = -EIO;
    s->req_seq = seq; /* published: the fast slot may run it from here on */
    while (s->done_seq != seq) {
        if (s->cfg.wait != NULL) {
            s->cfg.wait(s->cfg.wait_ctx);
        }
        if ((mc_hal_tick_read(s->cfg.p_tick, &now) != 0) || ((now - t0) > limit_ticks)) {
            if (s->done_seq == seq) {
                break; /* ran just now */
            }
            s->req_seq = s->done_seq; /* withdrawn: the slot will not run it */
            s->n_timeouts++;
            return -EIO;
        }
    }
    if ((s->rc == 0) && (p_rx != NULL)) {
        *p_rx = s->rx;
    }
    return s->rc;
}

static const mc_hal_spi_ops_t sched_ops = {
    .transfer16 = sched_transfer16,
    .transfer32 = NULL,
};

int mc_spisched_init(mc_spisched_t *p_s, const mc_spisched_config_t *p_cfg)
{
    uint32_t hz = 0u;

    if ((p_s == NULL) || (p_cfg == NULL) || (p_cfg->p_dev == NULL) || (p_cfg->p_tick == NULL) ||
        (p_cfg->timeout_us == 0u) || (p_cfg->timeout_us > TIMEOUT_US_MAX) ||
        (mc_hal_tick_get_freq_hz(p_cfg->p_tick, &hz) != 0) || (hz < TICK_HZ_MIN)) {
        return -EINVAL;
    }
    p_s->cfg = *p_cfg;
    p_s->tick_hz = hz;
    p_s->deferred = false;
    p_s->req_seq = 0u;
    p_s->done_seq = 0u;
    p_s->tx = 0u;
    p_s->rx = 0u;
    p_s->rc = 0;
    p_s->n_slot_frames = 0u;
    p_s->n_timeouts = 0u;
    p_s->dev.ops = &sched_ops;
    p_s->dev.ctx = p_s;
    return 0;
}

void mc_spisched_defer(mc_spisched_t *p_s)
{
    if (p_s != NULL) {
        p_s->deferred = true;
    }
}

bool mc_spisched_fast_slot(mc_spisched_t *p_s)
{
    uint16_t rx = 0u;
    uint32_t seq;

    if ((p_s == NULL) || (p_s->req_seq == p_s->done_seq)) {
        return false;
    }
    seq = p_s->req_seq;
    p_s->rc = mc_hal_spi_transfer16(p_s->cfg.p_dev, p_s->tx, &rx);
    p_s->rx = rx;
    p_s->n_slot_frames++;
    p_s->done_seq = seq; /* last: the slow side reads rc and rx after it */
    return true;
}
