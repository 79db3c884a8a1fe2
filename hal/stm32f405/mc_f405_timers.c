/**
 * @file mc_f405_timers.c
 * @brief encoder (timer in encoder mode) and tick (32-bit free-running
 *        timer) on the STM32F405. Register facts: RM0090 §18 (TIM2..TIM5).
 *        See mc_f405_hal.h.
 */
#include "mc_f405_hal.h"

#include <errno.h>
#include <stddef.h>

#define ENC_MAX_CPR_16BIT 0x10000u /* ARR = cpr - 1 must fit in 16 bits */
#define IC_FILTER_MAX     15u
#define PSC_MAX           0xFFFFu
#define GPIO_PORT_MAX     8u  /* I */
#define EXTI_LINE_MAX     15u /* the GPIO lines */
#define EXTICR_FIELD_MASK 0xFu

static uint32_t now_ticks(const mc_hal_tick_t *p_tick)
{
    uint32_t t = 0u;

    if (p_tick != NULL) {
        (void)mc_hal_tick_read(p_tick, &t);
    }
    return t;
}

/* ---- encoder ----------------------------------------------------------- */

/* Count relative to the latched index: (count - index) mod cpr, both in
 * 0 .. cpr - 1 (no overflow for a 32-bit counter). */
static uint32_t rel_to_index(uint32_t count, uint32_t index, uint32_t cpr)
{
    return (count >= index) ? (count - index) : (count + (cpr - index));
}

static int encoder_read(void *ctx, mc_hal_encoder_sample_t *p_sample)
{
    mc_f405_encoder_t *p = ctx;
    const mc_f405_tim_regs_t *t;
    uint32_t count;
    uint32_t flags = 0u;

    if ((p == NULL) || (p_sample == NULL)) {
        return -EINVAL;
    }
    t = p->cfg.p_tim;
    if ((t->CR1 & MC_F405_TIM_CR1_CEN) == 0u) {
        return -EIO; /* counter stopped (timer reset or clock gated) */
    }
    count = t->CNT;
    if (!p->cfg.counter_32bit) {
        count &= 0xFFFFu;
    }
    /* ARR = cpr - 1 keeps CNT in range; anything else is a broken timer. */
    if (count < p->cfg.counts_per_rev) {
        flags |= MC_HAL_ENCODER_FLAG_VALID;
        /* index_seen is set after index_count by the ISR: a true flag
         * means the latch is complete. */
        if (p->index_seen) {
            const uint32_t index = p->index_count;
            if (index < p->cfg.counts_per_rev) {
                count = rel_to_index(count, index, p->cfg.counts_per_rev);
                flags |= MC_HAL_ENCODER_FLAG_INDEX;
            } else {
                flags = 0u; /* a latch outside the turn: the timer was broken */
                count = 0u;
            }
        }
    } else {
        count = 0u;
    }
    p_sample->count = count;
    p_sample->counts_per_rev = p->cfg.counts_per_rev;
    p_sample->flags = flags;
    p_sample->timestamp_ticks = now_ticks(p->cfg.p_tick);
    return 0;
}

static const mc_hal_encoder_ops_t encoder_ops = {
    .read = encoder_read,
};

static bool index_cfg_ok(const mc_f405_encoder_index_t *ix)
{
    return (ix->p_exti == NULL) ||
           ((ix->p_syscfg != NULL) && (ix->port <= GPIO_PORT_MAX) && (ix->pin <= EXTI_LINE_MAX));
}

/* Route the pin's EXTI line to its port, one edge, pending cleared, then
 * unmasked (RM0090 §9.2.3..6 EXTICR, §12.3 IMR/RTSR/FTSR/PR). */
static void index_setup(const mc_f405_encoder_index_t *ix)
{
    const uint32_t bit = 1u << ix->pin;
    const uint32_t reg = (uint32_t)ix->pin / 4u;
    const uint32_t shift = 4u * ((uint32_t)ix->pin % 4u);
    mc_f405_exti_regs_t *e = ix->p_exti;

    e->IMR &= ~bit;
    ix->p_syscfg->EXTICR[reg] =
        (ix->p_syscfg->EXTICR[reg] & ~(EXTICR_FIELD_MASK << shift)) | ((uint32_t)ix->port << shift);
    if (ix->falling_edge) {
        e->FTSR |= bit;
        e->RTSR &= ~bit;
    } else {
        e->RTSR |= bit;
        e->FTSR &= ~bit;
    }
    e->PR = bit;
    e->IMR |= bit;
}

int mc_f405_encoder_init(mc_f405_encoder_t *p_drv, const mc_f405_encoder_config_t *p_cfg)
{
    mc_f405_tim_regs_t *t;
    uint32_t ccmr1;

    if ((p_drv == NULL) || (p_cfg == NULL) || (p_cfg->p_tim == NULL)) {
        return -EINVAL;
    }
    if ((p_cfg->counts_per_rev == 0u) ||
        (!p_cfg->counter_32bit && (p_cfg->counts_per_rev > ENC_MAX_CPR_16BIT)) ||
        (p_cfg->input_filter > IC_FILTER_MAX) || !index_cfg_ok(&p_cfg->index)) {
        return -EINVAL;
    }
    p_drv->cfg = *p_cfg;
    p_drv->index_seen = false;
    p_drv->index_count = 0u;
    p_drv->index_events = 0u;
    p_drv->dev.ops = &encoder_ops;
    p_drv->dev.ctx = p_drv;

    /* IC1 on TI1, IC2 on TI2, same digital filter on both. */
    ccmr1 = MC_F405_TIM_CC1S_TI1 | MC_F405_TIM_CC2S_TI2 |
            ((uint32_t)p_cfg->input_filter << MC_F405_TIM_IC1F_SHIFT) |
            ((uint32_t)p_cfg->input_filter << MC_F405_TIM_IC2F_SHIFT);

    t = p_cfg->p_tim;
    t->CR1 = 0u;
    t->SMCR = MC_F405_TIM_SMS_ENCODER3; /* count both edges of TI1 and TI2 */
    t->CCMR1 = ccmr1;
    /* CC1P inverts TI1: the counting direction flips. */
    t->CCER = p_cfg->invert ? MC_F405_TIM_CCER_P(0u) : 0u;
    t->PSC = 0u;
    t->ARR = p_cfg->counts_per_rev - 1u;
    t->EGR = MC_F405_TIM_EGR_UG;
    t->CNT = 0u;
    t->CR1 = MC_F405_TIM_CR1_CEN;
    if (p_cfg->index.p_exti != NULL) {
        index_setup(&p_cfg->index);
    }
    return 0;
}

bool mc_f405_encoder_index_isr(mc_f405_encoder_t *p_drv)
{
    mc_f405_exti_regs_t *e;
    uint32_t bit;
    uint32_t count;

    if ((p_drv == NULL) || (p_drv->cfg.index.p_exti == NULL)) {
        return false;
    }
    e = p_drv->cfg.index.p_exti;
    bit = 1u << p_drv->cfg.index.pin;
    /* The pending bit is set by an edge even while the line is masked
     * (RM0090 §12.2, the controller's block diagram: the mask gates the request, not the pending
     * register): a masked line is not this interrupt's. */
    if (((e->PR & e->IMR) & bit) == 0u) {
        return false; /* another line of a shared vector, or masked */
    }
    count = p_drv->cfg.p_tim->CNT; /* first: the latch lags the edge least */
    if (!p_drv->cfg.counter_32bit) {
        count &= 0xFFFFu;
    }
    e->PR = bit;
    p_drv->index_events++;
    if (!p_drv->index_seen) {
        p_drv->index_count = count;
        p_drv->index_seen = true; /* after the count: readers see a whole latch */
        e->IMR &= ~bit;
    }
    return true;
}

int mc_f405_encoder_index_rearm(mc_f405_encoder_t *p_drv)
{
    mc_f405_exti_regs_t *e;
    uint32_t bit;

    if ((p_drv == NULL) || (p_drv->cfg.index.p_exti == NULL)) {
        return -EINVAL;
    }
    e = p_drv->cfg.index.p_exti;
    bit = 1u << p_drv->cfg.index.pin;
    e->IMR &= ~bit;
    p_drv->index_seen = false;
    p_drv->index_count = 0u;
    e->PR = bit; /* an edge seen while masked is not this search's */
    e->IMR |= bit;
    return 0;
}

uint32_t mc_f405_exti_irq(uint32_t line)
{
    static const uint8_t k_irq_0_4[5] = {6u, 7u, 8u, 9u, 10u};

    if (line <= 4u) {
        return k_irq_0_4[line];
    }
    if (line <= 9u) {
        return 23u;
    }
    return (line <= EXTI_LINE_MAX) ? 40u : 0xFFFFFFFFu;
}

/* ---- tick -------------------------------------------------------------- */

static int tick_read(void *ctx, uint32_t *p_ticks)
{
    const mc_f405_tick_t *p = ctx;

    if ((p == NULL) || (p_ticks == NULL)) {
        return -EINVAL;
    }
    *p_ticks = p->cfg.p_tim->CNT;
    return 0;
}

static int tick_get_freq_hz(void *ctx, uint32_t *p_freq_hz)
{
    const mc_f405_tick_t *p = ctx;

    if ((p == NULL) || (p_freq_hz == NULL)) {
        return -EINVAL;
    }
    *p_freq_hz = p->freq_hz;
    return 0;
}

static const mc_hal_tick_ops_t tick_ops = {
    .read = tick_read,
    .get_freq_hz = tick_get_freq_hz,
};

int mc_f405_tick_init(mc_f405_tick_t *p_drv, const mc_f405_tick_config_t *p_cfg)
{
    mc_f405_tim_regs_t *t;

    if ((p_drv == NULL) || (p_cfg == NULL) || (p_cfg->p_tim == NULL) || (p_cfg->tim_clk_hz == 0u) ||
        (p_cfg->prescaler > PSC_MAX)) {
        return -EINVAL;
    }
    p_drv->cfg = *p_cfg;
    p_drv->freq_hz = p_cfg->tim_clk_hz / (p_cfg->prescaler + 1u);
    p_drv->dev.ops = &tick_ops;
    p_drv->dev.ctx = p_drv;

    t = p_cfg->p_tim;
    t->CR1 = 0u;
    t->SMCR = 0u;
    t->DIER = 0u;
    t->PSC = p_cfg->prescaler;
    t->ARR = 0xFFFFFFFFu;        /* wrap at 2^32 */
    t->EGR = MC_F405_TIM_EGR_UG; /* load PSC now, not at the first wrap */
    t->CNT = 0u;
    t->CR1 = MC_F405_TIM_CR1_CEN;
    return 0;
}
