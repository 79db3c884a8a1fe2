/**
 * @file mc_f405_brake.c
 * @brief See mc_f405_brake.h.
 */
#include "mc_f405_brake.h"

#include <errno.h>
#include <stddef.h>

static volatile uint32_t *ccr(const mc_f405_brake_t *d)
{
    switch (d->cfg.channel) {
    case 1u:
        return &d->cfg.tim->CCR1;
    case 2u:
        return &d->cfg.tim->CCR2;
    case 3u:
        return &d->cfg.tim->CCR3;
    default:
        return &d->cfg.tim->CCR4;
    }
}

static int brake_set_duty(void *ctx, float duty)
{
    mc_f405_brake_t *d = ctx;
    if (d == NULL || !(duty >= 0.0f && duty <= 1.0f)) {
        return -EINVAL;
    }
    const uint32_t top = d->cfg.tim->ARR + 1u;
    *ccr(d) = (uint32_t)(duty * (float)top + 0.5f);
    return 0;
}

static const mc_hal_brake_ops_t brake_ops = {
    .set_duty = brake_set_duty,
};

int mc_f405_brake_init(mc_f405_brake_t *p_drv, const mc_f405_brake_config_t *p_cfg)
{
    if (p_drv == NULL || p_cfg == NULL || p_cfg->tim == NULL || p_cfg->channel < 1u ||
        p_cfg->channel > 4u) {
        return -EINVAL;
    }
    p_drv->cfg = *p_cfg;
    p_drv->dev.ops = &brake_ops;
    p_drv->dev.ctx = p_drv;
    *ccr(p_drv) = 0u;
    return 0;
}
