/**
 * @file mc_f405_brake.c
 * @brief See mc_f405_brake.h.
 */
#include "mc_f405_brake.h"

#include <errno.h>
#include <stddef.h>

static volatile uint32_t *ccr(mc_f405_tim_regs_t *tim, uint32_t channel)
{
    switch (channel) {
    case 1u:
        return &tim->CCR1;
    case 2u:
        return &tim->CCR2;
    case 3u:
        return &tim->CCR3;
    default:
        return &tim->CCR4;
    }
}

/* CCMRx field of channel ch (1..4): OCxM = PWM mode 2, OCxPE. */
static void pwm2_mode(mc_f405_tim_regs_t *tim, uint32_t ch)
{
    const uint32_t field = (MC_F405_TIM_OCM_PWM2 << MC_F405_TIM_OC_M_SHIFT) | MC_F405_TIM_OC_PE;
    const uint32_t shift = ((ch - 1u) & 1u) * 8u;
    volatile uint32_t *ccmr = (ch <= 2u) ? &tim->CCMR1 : &tim->CCMR2;
    *ccmr = (*ccmr & ~(0xFFu << shift)) | (field << shift);
}

void mc_f405_brake_off(void *p_drv)
{
    const mc_f405_brake_t *d = p_drv;
    if ((d == NULL) || (d->cfg.tim == NULL)) {
        return;
    }
    *ccr(d->cfg.tim, d->cfg.ch_high) = d->cfg.period_ticks + 1u;
    *ccr(d->cfg.tim, d->cfg.ch_low) = 0u;
}

static int brake_set_duty(void *ctx, float duty)
{
    mc_f405_brake_t *d = ctx;
    if ((d == NULL) || !((duty >= 0.0f) && (duty <= 1.0f))) {
        return -EINVAL;
    }
    if ((d->cfg.p_fault != NULL) && d->cfg.p_fault->killed) {
        mc_f405_brake_off(d);
        return 0;
    }
    const float dc = (duty < d->cfg.duty_max) ? duty : d->cfg.duty_max;
    const uint32_t arr = d->cfg.period_ticks;
    const uint32_t high = arr + 1u - (uint32_t)((dc * (float)arr) + 0.5f);
    const uint32_t low = high - d->cfg.deadtime_ticks; /* duty_max keeps high > dead time */
    volatile uint32_t *p_high = ccr(d->cfg.tim, d->cfg.ch_high);
    volatile uint32_t *p_low = ccr(d->cfg.tim, d->cfg.ch_low);
    /* An update event between the two writes latches one old and one new
     * value: move first the edge that widens the gap between the switches. */
    if (high < *p_high) {
        *p_low = low;
        *p_high = high;
    } else {
        *p_high = high;
        *p_low = low;
    }
    return 0;
}

static const mc_hal_brake_ops_t brake_ops = {
    .set_duty = brake_set_duty,
};

static bool config_valid(const mc_f405_brake_config_t *c)
{
    return (c->tim != NULL) && (c->ch_low >= 1u) && (c->ch_low <= 4u) && (c->ch_high >= 1u) &&
           (c->ch_high <= 4u) && (c->ch_low != c->ch_high) && (c->deadtime_ticks >= 1u) &&
           (c->period_ticks > 2u * c->deadtime_ticks) && (c->period_ticks <= 0xFFFFu) &&
           (c->duty_max > 0.0f) &&
           (c->duty_max <= 1.0f - ((float)c->deadtime_ticks / (float)c->period_ticks));
}

int mc_f405_brake_init(mc_f405_brake_t *p_drv, const mc_f405_brake_config_t *p_cfg)
{
    if ((p_drv == NULL) || (p_cfg == NULL) || !config_valid(p_cfg)) {
        return -EINVAL;
    }
    mc_f405_tim_regs_t *tim = p_cfg->tim;
    p_drv->cfg = *p_cfg;
    p_drv->dev.ops = &brake_ops;
    p_drv->dev.ctx = p_drv;
    tim->CR1 = 0u; /* stopped while it is set up */
    tim->CCER &=
        ~(MC_F405_TIM_CCER_E(p_cfg->ch_low - 1u) | MC_F405_TIM_CCER_E(p_cfg->ch_high - 1u));
    tim->PSC = 0u;
    tim->ARR = p_cfg->period_ticks;
    mc_f405_brake_off(p_drv);
    pwm2_mode(tim, p_cfg->ch_low);
    pwm2_mode(tim, p_cfg->ch_high);
    tim->EGR = MC_F405_TIM_EGR_UG; /* load ARR and the off compares */
    tim->CCER = (tim->CCER & ~(MC_F405_TIM_CCER_P(p_cfg->ch_high - 1u))) |
                MC_F405_TIM_CCER_P(p_cfg->ch_low - 1u) | MC_F405_TIM_CCER_E(p_cfg->ch_low - 1u) |
                MC_F405_TIM_CCER_E(p_cfg->ch_high - 1u);
    tim->CR1 = (3u << MC_F405_TIM_CR1_CMS_SHIFT) | MC_F405_TIM_CR1_ARPE | MC_F405_TIM_CR1_CEN;
    return 0;
}
