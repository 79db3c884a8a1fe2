/**
 * @file mc_fake_wdg.c
 * @brief Fake watchdog: see mc_fake_wdg.h.
 */
#include "mc_fake_wdg.h"

#include <errno.h>
#include <stddef.h>

static int fake_start(void *ctx, uint32_t timeout_ms)
{
    mc_fake_wdg_t *w = ctx;
    if ((timeout_ms == 0u) || (timeout_ms > MC_HAL_WDG_TIMEOUT_MAX_MS)) {
        return -EINVAL;
    }
    w->timeout_ms = timeout_ms;
    if (timeout_ms > w->timeout_max_ms) {
        w->timeout_max_ms = timeout_ms;
    }
    w->since_feed_ms = 0u;
    w->starts++;
    return 0;
}

static int fake_feed(void *ctx)
{
    mc_fake_wdg_t *w = ctx;
    if (w->timeout_ms == 0u) {
        return -EBUSY;
    }
    w->since_feed_ms = 0u;
    w->feeds++;
    return 0;
}

static int fake_reset_cause(void *ctx, uint32_t *p_cause)
{
    const mc_fake_wdg_t *w = ctx;
    *p_cause = w->reset_cause;
    return 0;
}

static const mc_hal_wdg_ops_t fake_wdg_ops = {
    .start = fake_start,
    .feed = fake_feed,
    .reset_cause = fake_reset_cause,
};

void mc_fake_wdg_init(mc_fake_wdg_t *w, uint32_t cause)
{
    const mc_fake_wdg_t z = {0};
    *w = z;
    w->reset_cause = cause;
    w->dev.ops = &fake_wdg_ops;
    w->dev.ctx = w;
}

void mc_fake_wdg_advance(mc_fake_wdg_t *w, uint32_t ms)
{
    if (w->timeout_ms == 0u) {
        return;
    }
    w->since_feed_ms += ms;
    if (w->since_feed_ms >= w->timeout_ms) {
        w->expired = true;
    }
}
