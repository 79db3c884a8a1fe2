/**
 * @file mc_f405_pwm.c
 * @brief pwm3 (TIM1, or TIM8 for a second axis), pwm2 (TIM8) and fault (break input, gate kill) on the
 *        STM32F405. Register facts: RM0090 §17 (advanced-control timers),
 *        §8.4 (GPIO). See mc_f405_hal.h.
 */
#include "mc_f405_hal.h"

#include <errno.h>
#include <stddef.h>

/* ---- helpers ----------------------------------------------------------- */

/* Smallest ARR the drivers accept: below 100 counter ticks per half period
 * the duty resolution is worse than 1 %. */
#define MIN_ARR     100u
#define MAX_ARR     0xFFFFu /* TIM1/TIM8 counters are 16 bit */
#define MAX_PSC_DIV 0x10000u

/* Worst case dead time: 1008 tDTS (DTG = 0xFF). */
#define DTG_MAX_TICKS 1008u

int mc_f405_deadtime_encode(uint32_t deadtime_ns, uint32_t tim_clk_hz, uint32_t *p_dtg,
                            uint32_t *p_actual_ns)
{
    uint64_t ticks;
    uint32_t dtg;
    uint32_t actual_ticks;

    if ((p_dtg == NULL) || (deadtime_ns == 0u) || (tim_clk_hz == 0u)) {
        return -EINVAL;
    }
    /* Round up: the dead time is a safety margin, never shorten it. */
    ticks = (((uint64_t)deadtime_ns * tim_clk_hz) + 999999999u) / 1000000000u;
    if (ticks > DTG_MAX_TICKS) {
        return -EINVAL;
    }
    if (ticks <= 127u) {
        dtg = (uint32_t)ticks;
        actual_ticks = dtg;
    } else if (ticks <= 254u) {
        const uint32_t n = (uint32_t)((ticks + 1u) / 2u); /* 64..127 */
        dtg = 0x80u | (n - 64u);
        actual_ticks = 2u * n;
    } else if (ticks <= 504u) {
        const uint32_t n = (uint32_t)((ticks + 7u) / 8u); /* 32..63 */
        dtg = 0xC0u | (n - 32u);
        actual_ticks = 8u * n;
    } else {
        const uint32_t n = (uint32_t)((ticks + 15u) / 16u); /* 32..63 */
        dtg = 0xE0u | (n - 32u);
        actual_ticks = 16u * n;
    }
    *p_dtg = dtg;
    if (p_actual_ns != NULL) {
        *p_actual_ns =
            (uint32_t)((((uint64_t)actual_ticks * 1000000000u) + (tim_clk_hz / 2u)) / tim_clk_hz);
    }
    return 0;
}

/* Centre-aligned period = 2 (PSC + 1) ARR counter-clock ticks. Picks the
 * smallest prescaler that fits ARR in 16 bits; ARR rounded to nearest. */
static int pwm_timebase(uint32_t tim_clk_hz, uint32_t pwm_freq_hz, uint32_t *p_psc, uint32_t *p_arr,
                        float *p_period_s)
{
    uint64_t half;
    uint64_t div;
    uint64_t arr;

    if ((tim_clk_hz == 0u) || (pwm_freq_hz == 0u) || (pwm_freq_hz > tim_clk_hz)) {
        return -EINVAL;
    }
    half = (uint64_t)tim_clk_hz / (2u * (uint64_t)pwm_freq_hz);
    div = (half + (MAX_ARR - 1u)) / MAX_ARR;
    if (div == 0u) {
        div = 1u;
    }
    if (div > MAX_PSC_DIV) {
        return -EINVAL;
    }
    arr =
        ((uint64_t)tim_clk_hz + ((uint64_t)pwm_freq_hz * div)) / (2u * (uint64_t)pwm_freq_hz * div);
    if ((arr < MIN_ARR) || (arr > MAX_ARR)) {
        return -EINVAL;
    }
    *p_psc = (uint32_t)(div - 1u);
    *p_arr = (uint32_t)arr;
    *p_period_s = (float)(2u * arr * div) / (float)tim_clk_hz;
    return 0;
}

/* Compare value for a duty in [0, 1] (already validated). */
static uint32_t duty_to_ccr(float duty, uint32_t arr)
{
    return (uint32_t)((duty * (float)arr) + 0.5f);
}

/* OCxM = mode with preload, for the low (ch 1/3) or high (ch 2/4) byte. */
static uint32_t ccmr_oc(uint32_t mode)
{
    return (mode << MC_F405_TIM_OC_M_SHIFT) | MC_F405_TIM_OC_PE;
}

static uint32_t bdtr_break_bits(bool enable, bool active_high)
{
    uint32_t v = 0u;

    if (enable) {
        v |= MC_F405_TIM_BDTR_BKE;
        if (active_high) {
            v |= MC_F405_TIM_BDTR_BKP;
        }
    }
    return v;
}

/* The kill latch as the PWM drivers see it: software latch of the fault
 * driver, or the hardware break flag of their own timer. */
static bool kill_latched(const mc_f405_fault_t *p_fault, const mc_f405_tim_regs_t *p_tim)
{
    if ((p_fault != NULL) && p_fault->killed) {
        return true;
    }
    return (p_tim->SR & MC_F405_TIM_SR_BIF) != 0u;
}

/* Common enable: MOE on, then re-check the latch, since a gate kill from a
 * higher-priority context may have fired between the check and the write. */
static int tim_outputs_enable(const mc_f405_fault_t *p_fault, mc_f405_tim_regs_t *p_tim,
                              uint32_t bdtr_off)
{
    if (kill_latched(p_fault, p_tim)) {
        return -EBUSY;
    }
    p_tim->BDTR = bdtr_off | MC_F405_TIM_BDTR_MOE;
    if (kill_latched(p_fault, p_tim)) {
        p_tim->BDTR = bdtr_off;
        return -EBUSY;
    }
    return 0;
}

static int tim_outputs_disable(mc_f405_tim_regs_t *p_tim, uint32_t bdtr_off)
{
    p_tim->BDTR = bdtr_off;
    return ((p_tim->BDTR & MC_F405_TIM_BDTR_MOE) != 0u) ? -EIO : 0;
}

/* ---- pwm3 -------------------------------------------------------------- */

/* The ADC trigger is one of the timer's own events: TIM1 TRGO / CC4 on
 * TIM1, CC4 on TIM8. The trigger's bit 1 names its timer (one shift and one
 * compare: the image's flash budget is tight). */
_Static_assert(((MC_F405_ADC_TRIG_TIM1_TRGO >> 1) == MC_F405_ADV_TIM1) &&
                   ((MC_F405_ADC_TRIG_TIM1_CC4 >> 1) == MC_F405_ADV_TIM1) &&
                   ((MC_F405_ADC_TRIG_TIM8_CC4 >> 1) == MC_F405_ADV_TIM8),
               "an ADC trigger's bit 1 is its timer");

static bool trigger_of_timer(mc_f405_adc_trigger_t trig, mc_f405_adv_tim_t tim)
{
    return ((uint32_t)trig <= (uint32_t)MC_F405_ADC_TRIG_TIM8_CC4) &&
           (((uint32_t)trig >> 1) == (uint32_t)tim);
}

static int pwm3_set_duty(void *ctx, float duty_a, float duty_b, float duty_c)
{
    mc_f405_pwm3_t *p = ctx;
    mc_f405_tim_regs_t *t;

    if (p == NULL) {
        return -EINVAL;
    }
    if (!mc_hal_pwm3_duty_valid(duty_a) || !mc_hal_pwm3_duty_valid(duty_b) ||
        !mc_hal_pwm3_duty_valid(duty_c)) {
        return -EINVAL;
    }
    t = p->cfg.p_tim;
    /* Preloaded (OCxPE): all three take effect at the same update event. */
    t->CCR1 = duty_to_ccr(duty_a, p->arr);
    t->CCR2 = duty_to_ccr(duty_b, p->arr);
    t->CCR3 = duty_to_ccr(duty_c, p->arr);
    p->duty_a = duty_a;
    p->duty_b = duty_b;
    p->duty_c = duty_c;
    return 0;
}

static int pwm3_enable(void *ctx)
{
    mc_f405_pwm3_t *p = ctx;

    if (p == NULL) {
        return -EINVAL;
    }
    return tim_outputs_enable(p->cfg.p_fault, p->cfg.p_tim, p->bdtr_off);
}

static int pwm3_disable(void *ctx)
{
    mc_f405_pwm3_t *p = ctx;

    if (p == NULL) {
        return -EINVAL;
    }
    return tim_outputs_disable(p->cfg.p_tim, p->bdtr_off);
}

static int pwm3_get_state(void *ctx, mc_hal_pwm3_state_t *p_state)
{
    const mc_f405_pwm3_t *p = ctx;

    if ((p == NULL) || (p_state == NULL)) {
        return -EINVAL;
    }
    p_state->duty_a = p->duty_a;
    p_state->duty_b = p->duty_b;
    p_state->duty_c = p->duty_c;
    p_state->period_s = p->period_s;
    /* From the hardware: a break clears MOE without asking the driver. */
    p_state->enabled = (p->cfg.p_tim->BDTR & MC_F405_TIM_BDTR_MOE) != 0u;
    return 0;
}

static const mc_hal_pwm3_ops_t pwm3_ops = {
    .set_duty = pwm3_set_duty,
    .enable = pwm3_enable,
    .disable = pwm3_disable,
    .get_state = pwm3_get_state,
};

int mc_f405_pwm3_init(mc_f405_pwm3_t *p_drv, const mc_f405_pwm3_config_t *p_cfg)
{
    uint32_t psc;
    uint32_t arr;
    uint32_t dtg;
    uint32_t ccer = 0u;
    uint32_t cr2;
    uint32_t ccr_init;
    float period_s;
    mc_f405_tim_regs_t *t;
    uint32_t n;

    if ((p_drv == NULL) || (p_cfg == NULL) || (p_cfg->p_tim == NULL)) {
        return -EINVAL;
    }
    if (!trigger_of_timer(p_cfg->adc_trigger, p_cfg->tim)) {
        return -EINVAL;
    }
    if (pwm_timebase(p_cfg->tim_clk_hz, p_cfg->pwm_freq_hz, &psc, &arr, &period_s) != 0) {
        return -EINVAL;
    }
    /* tDTS = counter clock before the prescaler (CKD = 00). */
    if (mc_f405_deadtime_encode(p_cfg->deadtime_ns, p_cfg->tim_clk_hz, &dtg, NULL) != 0) {
        return -EINVAL;
    }
    if ((p_cfg->adc_trigger_lead_ticks == 0u) || (p_cfg->adc_trigger_lead_ticks >= arr)) {
        return -EINVAL;
    }

    p_drv->cfg = *p_cfg;
    p_drv->arr = arr;
    p_drv->psc = psc;
    p_drv->period_s = period_s;
    p_drv->duty_a = MC_HAL_PWM3_DUTY_INIT;
    p_drv->duty_b = MC_HAL_PWM3_DUTY_INIT;
    p_drv->duty_c = MC_HAL_PWM3_DUTY_INIT;
    /* OSSI/OSSR: with MOE = 0 the outputs are driven to their idle level
     * (OISx = OISxN = 0: both switches off) instead of floating. */
    p_drv->bdtr_off = dtg | MC_F405_TIM_BDTR_OSSI | MC_F405_TIM_BDTR_OSSR |
                      bdtr_break_bits(p_cfg->break_enable, p_cfg->break_active_high);
    p_drv->dev.ops = &pwm3_ops;
    p_drv->dev.ctx = p_drv;

    for (n = 0u; n < 3u; n++) {
        ccer |= MC_F405_TIM_CCER_E(n) | MC_F405_TIM_CCER_NE(n);
        if (p_cfg->high_side_active_low) {
            ccer |= MC_F405_TIM_CCER_P(n);
        }
        if (p_cfg->low_side_active_low) {
            ccer |= MC_F405_TIM_CCER_NP(n);
        }
    }
    /* The CC4 event reaches the ADC only with the channel enabled (there is
     * no CH4 pin function in use, the output stays internal to the AF mux). */
    if (p_cfg->adc_trigger != MC_F405_ADC_TRIG_TIM1_TRGO) {
        ccer |= MC_F405_TIM_CCER_E(3u);
    }
    cr2 = MC_F405_TIM_MMS_OC4REF << MC_F405_TIM_CR2_MMS_SHIFT;
    ccr_init = duty_to_ccr(MC_HAL_PWM3_DUTY_INIT, arr);

    t = p_cfg->p_tim;
    t->CR1 = 0u;               /* counter stopped while configuring */
    t->BDTR = p_drv->bdtr_off; /* outputs off, dead time, break */
    t->PSC = psc;
    t->ARR = arr;
    /* Centre-aligned: an update event at every over- and underflow; RCR = 1
     * keeps one per PWM period, so preloaded duties change once a period. */
    t->RCR = 1u;
    t->CCMR1 = ccmr_oc(MC_F405_TIM_OCM_PWM1) | (ccmr_oc(MC_F405_TIM_OCM_PWM1) << 8);
    /* CH4: PWM mode 2, OC4REF rises at CNT = ARR - lead while counting up:
     * one ADC trigger per period, just before the counter peak where all
     * low-side switches conduct. */
    t->CCMR2 = ccmr_oc(MC_F405_TIM_OCM_PWM1) | (ccmr_oc(MC_F405_TIM_OCM_PWM2) << 8);
    t->CCR1 = ccr_init;
    t->CCR2 = ccr_init;
    t->CCR3 = ccr_init;
    t->CCR4 = arr - p_cfg->adc_trigger_lead_ticks;
    t->CCER = ccer;
    t->CR2 = cr2;
    t->EGR = MC_F405_TIM_EGR_UG; /* load PSC, ARR, RCR, CCRx preloads */
    t->CR1 = (1u << MC_F405_TIM_CR1_CMS_SHIFT) | MC_F405_TIM_CR1_ARPE | MC_F405_TIM_CR1_CEN;
    return 0;
}

int mc_f405_pwm3_start_phased(mc_f405_pwm3_t *p_lead, mc_f405_pwm3_t *p_lag, uint32_t lag_ticks)
{
    mc_f405_tim_regs_t *a;
    mc_f405_tim_regs_t *b;
    uint32_t cr1_a;
    uint32_t cr1_b;

    if ((p_lead == NULL) || (p_lag == NULL) || (p_lead->cfg.p_tim == p_lag->cfg.p_tim) ||
        (p_lead->cfg.tim == p_lag->cfg.tim) || (p_lead->arr != p_lag->arr) ||
        (p_lead->psc != p_lag->psc) || (lag_ticks >= p_lead->arr)) {
        return -EINVAL;
    }
    a = p_lead->cfg.p_tim;
    b = p_lag->cfg.p_tim;
    cr1_a = a->CR1 | MC_F405_TIM_CR1_CEN;
    cr1_b = b->CR1 | MC_F405_TIM_CR1_CEN;
    a->CR1 = cr1_a & ~MC_F405_TIM_CR1_CEN;
    b->CR1 = cr1_b & ~MC_F405_TIM_CR1_CEN;
    /* UG: prescaler and repetition counters reloaded, the counter restarts
     * counting up (ODrive's Stm32Timer::start_synchronously relies on the
     * same); then the counts that set the phase. */
    a->EGR = MC_F405_TIM_EGR_UG;
    b->EGR = MC_F405_TIM_EGR_UG;
    a->CNT = lag_ticks;
    b->CNT = 0u;
    a->CR1 = cr1_a;
    b->CR1 = cr1_b;
    return 0;
}

/* ---- pwm2 -------------------------------------------------------------- */

static int pwm2_set_duty(void *ctx, float duty_a, float duty_b)
{
    mc_f405_pwm2_t *p = ctx;
    mc_f405_tim_regs_t *t;

    if (p == NULL) {
        return -EINVAL;
    }
    if (!mc_hal_pwm2_duty_valid(duty_a) || !mc_hal_pwm2_duty_valid(duty_b)) {
        return -EINVAL;
    }
    t = p->cfg.p_tim;
    /* Bipolar: the two legs of a bridge swing symmetrically about 50 %. */
    t->CCR1 = duty_to_ccr(0.5f * (1.0f + duty_a), p->arr);
    t->CCR2 = duty_to_ccr(0.5f * (1.0f - duty_a), p->arr);
    t->CCR3 = duty_to_ccr(0.5f * (1.0f + duty_b), p->arr);
    t->CCR4 = duty_to_ccr(0.5f * (1.0f - duty_b), p->arr);
    p->duty_a = duty_a;
    p->duty_b = duty_b;
    return 0;
}

static int pwm2_enable(void *ctx)
{
    mc_f405_pwm2_t *p = ctx;

    if (p == NULL) {
        return -EINVAL;
    }
    return tim_outputs_enable(p->cfg.p_fault, p->cfg.p_tim, p->bdtr_off);
}

static int pwm2_disable(void *ctx)
{
    mc_f405_pwm2_t *p = ctx;

    if (p == NULL) {
        return -EINVAL;
    }
    return tim_outputs_disable(p->cfg.p_tim, p->bdtr_off);
}

static int pwm2_get_state(void *ctx, mc_hal_pwm2_state_t *p_state)
{
    const mc_f405_pwm2_t *p = ctx;

    if ((p == NULL) || (p_state == NULL)) {
        return -EINVAL;
    }
    p_state->duty_a = p->duty_a;
    p_state->duty_b = p->duty_b;
    p_state->period_s = p->period_s;
    p_state->enabled = (p->cfg.p_tim->BDTR & MC_F405_TIM_BDTR_MOE) != 0u;
    return 0;
}

static const mc_hal_pwm2_ops_t pwm2_ops = {
    .set_duty = pwm2_set_duty,
    .enable = pwm2_enable,
    .disable = pwm2_disable,
    .get_state = pwm2_get_state,
};

int mc_f405_pwm2_init(mc_f405_pwm2_t *p_drv, const mc_f405_pwm2_config_t *p_cfg)
{
    uint32_t psc;
    uint32_t arr;
    uint32_t ccer = 0u;
    uint32_t ccr_init;
    float period_s;
    mc_f405_tim_regs_t *t;
    uint32_t n;

    if ((p_drv == NULL) || (p_cfg == NULL) || (p_cfg->p_tim == NULL)) {
        return -EINVAL;
    }
    if (pwm_timebase(p_cfg->tim_clk_hz, p_cfg->pwm_freq_hz, &psc, &arr, &period_s) != 0) {
        return -EINVAL;
    }

    p_drv->cfg = *p_cfg;
    p_drv->arr = arr;
    p_drv->psc = psc;
    p_drv->period_s = period_s;
    p_drv->duty_a = MC_HAL_PWM2_DUTY_INIT;
    p_drv->duty_b = MC_HAL_PWM2_DUTY_INIT;
    /* No complementary outputs here, so no dead time (DTG = 0). */
    p_drv->bdtr_off = MC_F405_TIM_BDTR_OSSI | MC_F405_TIM_BDTR_OSSR |
                      bdtr_break_bits(p_cfg->break_enable, p_cfg->break_active_high);
    p_drv->dev.ops = &pwm2_ops;
    p_drv->dev.ctx = p_drv;

    for (n = 0u; n < 4u; n++) {
        ccer |= MC_F405_TIM_CCER_E(n);
        if (p_cfg->outputs_active_low) {
            ccer |= MC_F405_TIM_CCER_P(n);
        }
    }
    ccr_init = duty_to_ccr(0.5f, arr); /* duty 0: both legs at 50 % */

    t = p_cfg->p_tim;
    t->CR1 = 0u;
    t->BDTR = p_drv->bdtr_off;
    t->PSC = psc;
    t->ARR = arr;
    t->RCR = 1u;
    t->CCMR1 = ccmr_oc(MC_F405_TIM_OCM_PWM1) | (ccmr_oc(MC_F405_TIM_OCM_PWM1) << 8);
    t->CCMR2 = ccmr_oc(MC_F405_TIM_OCM_PWM1) | (ccmr_oc(MC_F405_TIM_OCM_PWM1) << 8);
    t->CCR1 = ccr_init;
    t->CCR2 = ccr_init;
    t->CCR3 = ccr_init;
    t->CCR4 = ccr_init;
    t->CCER = ccer;
    t->CR2 = 0u;
    t->EGR = MC_F405_TIM_EGR_UG;
    t->CR1 = (1u << MC_F405_TIM_CR1_CMS_SHIFT) | MC_F405_TIM_CR1_ARPE | MC_F405_TIM_CR1_CEN;
    return 0;
}

/* ---- fault ------------------------------------------------------------- */

static bool pin_wired(const mc_f405_pin_t *p_pin)
{
    return p_pin->p_port != NULL;
}

static bool pin_valid(const mc_f405_pin_t *p_pin)
{
    return !pin_wired(p_pin) || (p_pin->pin <= 15u);
}

static bool pin_asserted(const mc_f405_pin_t *p_pin)
{
    bool level;

    if (!pin_wired(p_pin)) {
        return false;
    }
    level = ((p_pin->p_port->IDR >> p_pin->pin) & 1u) != 0u;
    return p_pin->active_low ? !level : level;
}

/* BSRR: one atomic write, no read-modify-write of ODR. */
static void pin_drive(const mc_f405_pin_t *p_pin, bool on)
{
    bool level;

    if (!pin_wired(p_pin)) {
        return;
    }
    level = p_pin->active_low ? !on : on;
    p_pin->p_port->BSRR = level ? (1u << p_pin->pin) : (1u << (p_pin->pin + 16u));
}

static void pin_mode(const mc_f405_pin_t *p_pin, uint32_t mode)
{
    uint32_t moder;
    const uint32_t shift = 2u * (uint32_t)p_pin->pin;

    if (!pin_wired(p_pin)) {
        return;
    }
    moder = p_pin->p_port->MODER & ~(3u << shift);
    p_pin->p_port->MODER = moder | (mode << shift);
}

static uint32_t fault_inputs(const mc_f405_fault_t *f)
{
    uint32_t active = 0u;

    if (pin_asserted(&f->cfg.gate_driver_fault)) {
        active |= MC_HAL_FAULT_GATE_DRIVER;
    }
    if (pin_asserted(&f->cfg.overcurrent)) {
        active |= MC_HAL_FAULT_OVERCURRENT;
    }
    return active;
}

static void kill_timer(mc_f405_tim_regs_t *p_tim)
{
    if (p_tim != NULL) {
        /* Software break: the hardware clears MOE and sets BIF. Clearing
         * MOE ourselves as well does not depend on the break logic. */
        p_tim->EGR = MC_F405_TIM_EGR_BG;
        p_tim->BDTR &= ~MC_F405_TIM_BDTR_MOE;
    }
}

static void fault_gate_kill(void *ctx)
{
    mc_f405_fault_t *f = ctx;

    if (f == NULL) {
        return;
    }
    f->killed = true; /* first, so a racing enable sees it (re-check) */
    kill_timer(f->cfg.p_tim1);
    kill_timer(f->cfg.p_tim8);
    pin_drive(&f->cfg.gate_enable, false);
    if (f->cfg.kill_hook != NULL) {
        f->cfg.kill_hook(f->cfg.kill_hook_ctx);
    }
}

static bool break_flag(const mc_f405_tim_regs_t *p_tim)
{
    return (p_tim != NULL) && ((p_tim->SR & MC_F405_TIM_SR_BIF) != 0u);
}

static int fault_read(void *ctx, mc_hal_fault_status_t *p_status)
{
    mc_f405_fault_t *f = ctx;
    uint32_t active;

    if ((f == NULL) || (p_status == NULL)) {
        return -EINVAL;
    }
    active = fault_inputs(f);
    if (!f->killed && (break_flag(f->cfg.p_tim1) || break_flag(f->cfg.p_tim8))) {
        /* A hardware break on one timer: latch the kill for every bridge
         * and name the inputs wired to BKIN (the pulse may be over). */
        const uint32_t cause = active & f->cfg.bkin_mask;
        f->latched_mask |= (cause != 0u) ? cause : f->cfg.bkin_mask;
        fault_gate_kill(f);
    }
    f->latched_mask |= active;
    p_status->active_mask = active;
    p_status->latched_mask = f->latched_mask;
    p_status->gate_killed = f->killed;
    return 0;
}

static void release_timer(mc_f405_tim_regs_t *p_tim)
{
    if (p_tim != NULL) {
        p_tim->BDTR &= ~MC_F405_TIM_BDTR_MOE; /* outputs stay off */
        p_tim->SR = ~MC_F405_TIM_SR_BIF;      /* rc_w0: clears BIF only */
    }
}

static int fault_gate_release(void *ctx)
{
    mc_f405_fault_t *f = ctx;

    if (f == NULL) {
        return -EINVAL;
    }
    if (fault_inputs(f) != 0u) {
        return -EBUSY;
    }
    release_timer(f->cfg.p_tim1);
    release_timer(f->cfg.p_tim8);
    f->latched_mask = 0u;
    f->killed = false;
    pin_drive(&f->cfg.gate_enable, true);
    return 0;
}

static const mc_hal_fault_ops_t fault_ops = {
    .read = fault_read,
    .gate_kill = fault_gate_kill,
    .gate_release = fault_gate_release,
};

int mc_f405_fault_init(mc_f405_fault_t *p_drv, const mc_f405_fault_config_t *p_cfg)
{
    if ((p_drv == NULL) || (p_cfg == NULL)) {
        return -EINVAL;
    }
    if ((p_cfg->p_tim1 == NULL) && (p_cfg->p_tim8 == NULL)) {
        return -EINVAL;
    }
    if (!pin_valid(&p_cfg->gate_driver_fault) || !pin_valid(&p_cfg->overcurrent) ||
        !pin_valid(&p_cfg->gate_enable) || ((p_cfg->bkin_mask & ~MC_HAL_FAULT_ALL) != 0u)) {
        return -EINVAL;
    }
    p_drv->cfg = *p_cfg;
    p_drv->killed = false;
    p_drv->latched_mask = 0u;
    p_drv->dev.ops = &fault_ops;
    p_drv->dev.ctx = p_drv;

    pin_mode(&p_cfg->gate_driver_fault, 0u); /* input */
    pin_mode(&p_cfg->overcurrent, 0u);
    pin_drive(&p_cfg->gate_enable, true); /* level first, then output */
    pin_mode(&p_cfg->gate_enable, MC_F405_GPIO_MODER_OUTPUT);
    return 0;
}
