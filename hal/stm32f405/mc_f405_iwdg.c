/**
 * @file mc_f405_iwdg.c
 * @brief STM32F405 IWDG and RCC_CSR reset flags: see mc_f405_iwdg.h.
 */
#include "mc_f405_iwdg.h"

#include <errno.h>
#include <stdbool.h>
#include <stddef.h>

int mc_f405_iwdg_divider(uint32_t timeout_ms, uint32_t *p_pr, uint32_t *p_rlr)
{
    uint32_t pr;
    if ((p_pr == NULL) || (p_rlr == NULL) || (timeout_ms == 0u) ||
        (timeout_ms > MC_HAL_WDG_TIMEOUT_MAX_MS)) {
        return -EINVAL;
    }
    for (pr = 0u; pr <= MC_F405_IWDG_PR_MAX; pr++) {
        /* LSI periods per count: 4 << pr; counts = ceil(t f / (1000 * 4 << pr)) */
        const uint64_t num = (uint64_t)timeout_ms * MC_F405_IWDG_LSI_HZ;
        const uint64_t den = 1000u * ((uint64_t)4u << pr);
        const uint64_t counts = (num + den - 1u) / den;
        if (counts <= (uint64_t)MC_F405_IWDG_RLR_MAX + 1u) {
            *p_pr = pr;
            *p_rlr = (uint32_t)counts - 1u;
            return 0;
        }
    }
    return -EINVAL;
}

uint32_t mc_f405_reset_cause_decode(uint32_t csr)
{
    uint32_t c = MC_HAL_WDG_RESET_NONE;
    if ((csr & MC_F405_RCC_CSR_IWDGRSTF) != 0u) {
        c |= MC_HAL_WDG_RESET_WATCHDOG;
    }
    if ((csr & MC_F405_RCC_CSR_WWDGRSTF) != 0u) {
        c |= MC_HAL_WDG_RESET_WINDOW;
    }
    if ((csr & MC_F405_RCC_CSR_LPWRRSTF) != 0u) {
        c |= MC_HAL_WDG_RESET_LOW_POWER;
    }
    if ((csr & MC_F405_RCC_CSR_SFTRSTF) != 0u) {
        c |= MC_HAL_WDG_RESET_SOFTWARE;
    }
    if ((csr & MC_F405_RCC_CSR_PORRSTF) != 0u) {
        c |= MC_HAL_WDG_RESET_POWER_ON;
    } else if ((csr & MC_F405_RCC_CSR_BORRSTF) != 0u) {
        c |= MC_HAL_WDG_RESET_BROWNOUT; /* BOR without POR: a supply dip */
    }
    if ((c == MC_HAL_WDG_RESET_NONE) && ((csr & MC_F405_RCC_CSR_PINRSTF) != 0u)) {
        c |= MC_HAL_WDG_RESET_PIN; /* NRST alone: an external reset */
    }
    return c;
}

static bool sr_wait(const mc_f405_iwdg_t *p)
{
    uint32_t n;
    for (n = 0u; n < MC_F405_IWDG_SR_POLLS; n++) {
        if (p->cfg.hw_poll != NULL) {
            p->cfg.hw_poll(p->cfg.hw_ctx);
        }
        if ((p->cfg.p_iwdg->SR & (MC_F405_IWDG_SR_PVU | MC_F405_IWDG_SR_RVU)) == 0u) {
            return true;
        }
    }
    return false;
}

static int iwdg_start(void *ctx, uint32_t timeout_ms)
{
    mc_f405_iwdg_t *p = ctx;
    mc_f405_iwdg_regs_t *r = p->cfg.p_iwdg;
    uint32_t pr = 0u;
    uint32_t rlr = 0u;
    if (mc_f405_iwdg_divider(timeout_ms, &pr, &rlr) != 0) {
        return -EINVAL;
    }
    /* A previous update must have completed before PR/RLR are written. */
    if (!sr_wait(p)) {
        return -EIO;
    }
    r->KR = MC_F405_IWDG_KEY_START; /* starts the LSI and the counter */
    r->KR = MC_F405_IWDG_KEY_UNLOCK;
    r->PR = pr;
    r->RLR = rlr;
    if (!sr_wait(p)) {
        return -EIO;
    }
    r->KR = MC_F405_IWDG_KEY_RELOAD; /* the new reload value in force now */
    p->timeout_ms = timeout_ms;
    return 0;
}

static int iwdg_feed(void *ctx)
{
    mc_f405_iwdg_t *p = ctx;
    if (p->timeout_ms == 0u) {
        return -EBUSY;
    }
    p->cfg.p_iwdg->KR = MC_F405_IWDG_KEY_RELOAD;
    return 0;
}

static int iwdg_reset_cause(void *ctx, uint32_t *p_cause)
{
    const mc_f405_iwdg_t *p = ctx;
    *p_cause = p->cause;
    return 0;
}

static const mc_hal_wdg_ops_t iwdg_ops = {
    .start = iwdg_start,
    .feed = iwdg_feed,
    .reset_cause = iwdg_reset_cause,
};

int mc_f405_iwdg_init(mc_f405_iwdg_t *p_drv, const mc_f405_iwdg_config_t *p_cfg)
{
    if ((p_drv == NULL) || (p_cfg == NULL) || (p_cfg->p_iwdg == NULL) ||
        (p_cfg->p_rcc_csr == NULL)) {
        return -EINVAL;
    }
    p_drv->cfg = *p_cfg;
    p_drv->csr_at_boot = *p_cfg->p_rcc_csr;
    p_drv->cause = mc_f405_reset_cause_decode(p_drv->csr_at_boot);
    *p_cfg->p_rcc_csr = p_drv->csr_at_boot | MC_F405_RCC_CSR_RMVF; /* clear the flags */
    p_drv->timeout_ms = 0u;
    p_drv->dev.ops = &iwdg_ops;
    p_drv->dev.ctx = p_drv;
    return 0;
}
