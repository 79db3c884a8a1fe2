/**
 * @file mc_f405_hall.c
 * @brief hall capability (hal/hall.h) on three GPIO inputs of the
 *        STM32F405: the levels from each port's IDR (RM0090 §8.4.5).
 *        See mc_f405_hal.h.
 */
#include "mc_f405_hal.h"

#include <errno.h>
#include <stddef.h>

static int hall_read(void *ctx, uint32_t *p_code)
{
    const mc_f405_hall_t *p = ctx;
    uint32_t code = 0u;
    uint32_t k;

    if ((p == NULL) || (p_code == NULL)) {
        return -EINVAL;
    }
    for (k = 0u; k < 3u; k++) {
        const mc_f405_pin_t *pin = &p->cfg.pin[k];
        const bool level = ((pin->p_port->IDR >> pin->pin) & 1u) != 0u;
        if (level != pin->active_low) {
            code |= 1u << k;
        }
    }
    *p_code = code;
    return 0;
}

static const mc_hal_hall_ops_t hall_ops = {
    .read = hall_read,
};

int mc_f405_hall_init(mc_f405_hall_t *p_drv, const mc_f405_hall_config_t *p_cfg)
{
    uint32_t k;

    if ((p_drv == NULL) || (p_cfg == NULL)) {
        return -EINVAL;
    }
    for (k = 0u; k < 3u; k++) {
        if ((p_cfg->pin[k].p_port == NULL) || (p_cfg->pin[k].pin > 15u)) {
            return -EINVAL;
        }
    }
    p_drv->cfg = *p_cfg;
    p_drv->dev.ops = &hall_ops;
    p_drv->dev.ctx = p_drv;
    return 0;
}
