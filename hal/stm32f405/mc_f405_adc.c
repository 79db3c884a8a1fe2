/**
 * @file mc_f405_adc.c
 * @brief adc capability on ADC1 (or ADC2, a second axis) of the STM32F405:
 *        injected group triggered by TIM1 (or TIM8 CC4) for currents and bus
 *        voltage, software-started regular
 *        conversions for temperatures. Register facts: RM0090 §13. See
 *        mc_f405_hal.h.
 */
#include "mc_f405_hal.h"

#include <errno.h>
#include <float.h>
#include <stddef.h>

#define ADC_FULL_SCALE_COUNTS 4096.0f /* 12 bit: 1 LSB = Vref / 4096 */
#define ADC_MAX_RAW           4095u
#define VREF_MAX_V            3.6f       /* datasheet limit of VREF+ */
#define TSVREFE               (1u << 23) /* ADC_CCR: temp sensor and VREFINT */
#define CH_TEMP_SENSOR        16u
#define CH_VREFINT            17u

/* adc_read sets the current valid bits as 1 << phase index. */
_Static_assert((MC_HAL_ADC_VALID_IA == 1u) && (MC_HAL_ADC_VALID_IB == 2u) &&
                   (MC_HAL_ADC_VALID_IC == 4u),
               "valid bits are phase-indexed");

static bool finite_f(float x)
{
    /* NaN fails both comparisons, +-inf fails one. */
    return (x >= -FLT_MAX) && (x <= FLT_MAX);
}

static bool channel_valid(uint8_t ch)
{
    return ch <= MC_F405_ADC_CH_MAX;
}

static bool channel_or_none(uint8_t ch)
{
    return (ch == MC_F405_ADC_CH_NONE) || channel_valid(ch);
}

static bool smp_valid(mc_f405_adc_smp_t smp)
{
    return ((uint32_t)smp) <= (uint32_t)MC_F405_ADC_SMP_480;
}

static bool temp_table_valid(const mc_f405_adc_temp_sensor_t *s)
{
    uint32_t k;

    if ((s->p_table == NULL) || (s->n_table < 2u) || (s->n_table > MC_F405_ADC_TEMP_TABLE_MAX)) {
        return false;
    }
    for (k = 0u; k < s->n_table; k++) {
        if (!finite_f(s->p_table[k].v) || !finite_f(s->p_table[k].t_c)) {
            return false;
        }
        if ((k > 0u) && !(s->p_table[k].v > s->p_table[k - 1u].v)) {
            return false;
        }
    }
    return true;
}

static bool temp_sensor_valid(const mc_f405_adc_temp_sensor_t *s)
{
    if (s->channel == MC_F405_ADC_CH_NONE) {
        return true;
    }
    if (s->n_table != 0u) {
        return channel_valid(s->channel) && temp_table_valid(s);
    }
    return channel_valid(s->channel) && finite_f(s->offset_c) && finite_f(s->slope_c_per_v) &&
           finite_f(s->c2_c_per_v2) && finite_f(s->c3_c_per_v3) && finite_f(s->v_min_v) &&
           finite_f(s->v_max_v) && (s->v_min_v < s->v_max_v);
}

static bool config_valid(const mc_f405_adc_config_t *c)
{
    if ((c->p_adc == NULL) || (c->p_common == NULL)) {
        return false;
    }
    /* Phases a and b, a b and c, or b and c. */
    if (!channel_or_none(c->ch_ia) || !channel_valid(c->ch_ib) || !channel_or_none(c->ch_ic) ||
        !channel_valid(c->ch_vbus)) {
        return false;
    }
    if ((c->ch_ia == MC_F405_ADC_CH_NONE) && (c->ch_ic == MC_F405_ADC_CH_NONE)) {
        return false;
    }
    if (!smp_valid(c->smp_current) || !smp_valid(c->smp_vbus) || !smp_valid(c->smp_temp)) {
        return false;
    }
    if ((uint32_t)c->trigger > (uint32_t)MC_F405_ADC_TRIG_TIM8_CC4) {
        return false;
    }
    if ((c->clk_div != 2u) && (c->clk_div != 4u) && (c->clk_div != 6u) && (c->clk_div != 8u)) {
        return false;
    }
    if (!(c->vref_v > 0.0f) || !(c->vref_v <= VREF_MAX_V)) {
        return false;
    }
    if (!(c->shunt_ohm > 0.0f) || !finite_f(c->shunt_ohm) || !finite_f(c->amp_gain_v_per_v) ||
        (c->amp_gain_v_per_v == 0.0f)) {
        return false;
    }
    if (!(c->ia_offset_v >= 0.0f) || !(c->ia_offset_v <= c->vref_v) || !(c->ib_offset_v >= 0.0f) ||
        !(c->ib_offset_v <= c->vref_v) || !(c->ic_offset_v >= 0.0f) ||
        !(c->ic_offset_v <= c->vref_v)) {
        return false;
    }
    if (!(c->vbus_divider >= 1.0f) || !finite_f(c->vbus_divider)) {
        return false;
    }
    if (c->rail_margin_counts >= 2048u) {
        return false;
    }
    return temp_sensor_valid(&c->temp_power_stage) && temp_sensor_valid(&c->temp_motor);
}

/* SMPx[2:0] of one channel into the SMPR1 (ch 10..18) / SMPR2 (ch 0..9)
 * images. */
static void smp_set(uint32_t *p_smpr1, uint32_t *p_smpr2, uint8_t ch, mc_f405_adc_smp_t smp)
{
    uint32_t shift;

    if (!channel_valid(ch)) {
        return;
    }
    if (ch >= 10u) {
        shift = 3u * ((uint32_t)ch - 10u);
        *p_smpr1 = (*p_smpr1 & ~(7u << shift)) | ((uint32_t)smp << shift);
    } else {
        shift = 3u * (uint32_t)ch;
        *p_smpr2 = (*p_smpr2 & ~(7u << shift)) | ((uint32_t)smp << shift);
    }
}

/* Raw value usable: not at (or within margin of) either rail, where the
 * amplifier or the ADC saturates. */
static bool raw_in_range(uint32_t raw, uint32_t margin)
{
    return (raw > margin) && (raw < (ADC_MAX_RAW - margin));
}

static uint32_t now_ticks(const mc_hal_tick_t *p_tick)
{
    uint32_t t = 0u;

    if (p_tick != NULL) {
        (void)mc_hal_tick_read(p_tick, &t);
    }
    return t;
}

/* ---- ops --------------------------------------------------------------- */

static int adc_read(void *ctx, mc_hal_adc_sample_t *p_sample)
{
    mc_f405_adc_t *p = ctx;
    mc_f405_adc_regs_t *r;
    uint32_t raw[4] = {0u, 0u, 0u, 0u};
    float cur[3] = {0.0f, 0.0f, 0.0f};
    uint32_t valid = 0u;
    uint32_t k;
    float vbus_v = 0.0f;
    const uint32_t margin = (p != NULL) ? p->cfg.rail_margin_counts : 0u;

    if ((p == NULL) || (p_sample == NULL)) {
        return -EINVAL;
    }
    r = p->cfg.p_adc;
    if ((r->CR2 & MC_F405_ADC_CR2_ADON) == 0u) {
        return -EIO; /* powered down or reset behind our back */
    }
    if ((r->SR & MC_F405_ADC_SR_JEOC) == 0u) {
        return -EAGAIN;
    }
    /* All four data registers, unrolled (the fast loop's hot path): a rank
     * beyond n_inj is read but never used, and reading JDRx has no side
     * effect (RM0090 13.13.9). */
    raw[0] = r->JDR[0] & MC_F405_ADC_DATA_MASK;
    raw[1] = r->JDR[1] & MC_F405_ADC_DATA_MASK;
    raw[2] = r->JDR[2] & MC_F405_ADC_DATA_MASK;
    raw[3] = r->JDR[3] & MC_F405_ADC_DATA_MASK;
    r->SR = ~MC_F405_ADC_SR_JEOC; /* rc_w0: clear JEOC, leave the others */

    for (k = 0u; k < p->n_phase; k++) {
        const uint32_t ph = p->phase_of_rank[k];
        if (raw_in_range(raw[k], margin)) {
            cur[ph] = ((float)raw[k] - p->offset_counts[ph]) * p->a_per_count[ph];
            valid |= (1u << ph); /* MC_HAL_ADC_VALID_IA/IB/IC are bits 0..2 */
        }
    }
    if (p->derive_ia && ((valid & (MC_HAL_ADC_VALID_IB | MC_HAL_ADC_VALID_IC)) ==
                         (MC_HAL_ADC_VALID_IB | MC_HAL_ADC_VALID_IC))) {
        cur[0] = -(cur[1] + cur[2]);
        valid |= MC_HAL_ADC_VALID_IA;
    }
    if (raw_in_range(raw[p->rank_vbus], margin)) {
        vbus_v = (float)raw[p->rank_vbus] * p->v_per_count * p->cfg.vbus_divider;
        valid |= MC_HAL_ADC_VALID_VBUS;
    }

    p->seq++;
    p_sample->ia_a = cur[0];
    p_sample->ib_a = cur[1];
    p_sample->ic_a = cur[2];
    p_sample->vbus_v = vbus_v;
    p_sample->valid_mask = valid;
    /* Time of the read, a few microseconds (the conversions) after the
     * trigger: within the tolerance of the drive's deadline check. */
    p_sample->timestamp_ticks = now_ticks(p->cfg.p_tick);
    p_sample->seq = p->seq;
    return 0;
}

/* Temperature of a sensor at pin voltage v; false outside its window. */
static bool temp_convert(const mc_f405_adc_temp_sensor_t *s, float v, float *p_t_c)
{
    if (s->n_table != 0u) {
        const mc_f405_adc_temp_point_t *t = s->p_table;
        uint32_t k;
        if ((v < t[0].v) || (v > t[s->n_table - 1u].v)) {
            return false;
        }
        for (k = 1u; k < (s->n_table - 1u); k++) {
            if (v <= t[k].v) {
                break;
            }
        }
        /* v in [t[k-1].v, t[k].v] */
        *p_t_c = t[k - 1u].t_c +
                 ((v - t[k - 1u].v) * (t[k].t_c - t[k - 1u].t_c) / (t[k].v - t[k - 1u].v));
        return true;
    }
    if ((v < s->v_min_v) || (v > s->v_max_v)) {
        return false;
    }
    /* Horner: offset + v (slope + v (c2 + v c3)). */
    *p_t_c = s->offset_c + (v * (s->slope_c_per_v + (v * (s->c2_c_per_v2 + (v * s->c3_c_per_v3)))));
    return true;
}

static const mc_f405_adc_temp_sensor_t *temp_sensor(const mc_f405_adc_t *p, uint32_t slot)
{
    return (slot == 0u) ? &p->cfg.temp_power_stage : &p->cfg.temp_motor;
}

static uint32_t temp_next_slot(const mc_f405_adc_t *p, uint32_t slot)
{
    const uint32_t other = 1u - slot;

    return (temp_sensor(p, other)->channel != MC_F405_ADC_CH_NONE) ? other : slot;
}

static int adc_read_temp(void *ctx, mc_hal_adc_temp_t *p_temp)
{
    mc_f405_adc_t *p = ctx;
    mc_f405_adc_regs_t *r;

    if ((p == NULL) || (p_temp == NULL)) {
        return -EINVAL;
    }
    r = p->cfg.p_adc;
    if ((r->CR2 & MC_F405_ADC_CR2_ADON) == 0u) {
        return -EIO;
    }
    if (p->temp_running && ((r->SR & MC_F405_ADC_SR_EOC) != 0u)) {
        const mc_f405_adc_temp_sensor_t *s = temp_sensor(p, p->temp_slot);
        const uint32_t bit =
            (p->temp_slot == 0u) ? MC_HAL_ADC_TEMP_VALID_POWER_STAGE : MC_HAL_ADC_TEMP_VALID_MOTOR;
        /* Reading DR clears EOC in hardware. */
        const float v = (float)(r->DR & MC_F405_ADC_DATA_MASK) * p->v_per_count;
        float t_c = 0.0f;

        if (temp_convert(s, v, &t_c)) {
            p->temp.valid_mask |= bit;
        } else {
            t_c = 0.0f;
            p->temp.valid_mask &= ~bit; /* open or short circuit */
        }
        if (p->temp_slot == 0u) {
            p->temp.power_stage_temp_c = t_c;
        } else {
            p->temp.motor_temp_c = t_c;
        }
        p->temp_running = false;
        p->temp_slot = temp_next_slot(p, p->temp_slot);
    }
    if (!p->temp_running) {
        r->SQR3 = temp_sensor(p, p->temp_slot)->channel; /* SQ1 */
        r->CR2 |= MC_F405_ADC_CR2_SWSTART;
        p->temp_running = true;
    }
    *p_temp = p->temp;
    return 0;
}

static const mc_hal_adc_ops_t adc_ops_temp = {
    .read = adc_read,
    .read_temp = adc_read_temp,
};

static const mc_hal_adc_ops_t adc_ops_no_temp = {
    .read = adc_read, .read_temp = NULL, /* no temperature channel on this board */
};

bool mc_f405_adc_jeoc_pending(const mc_f405_adc_t *p_drv)
{
    const uint32_t irq = MC_F405_ADC_SR_JEOC;

    if (p_drv == NULL) {
        return false;
    }
    return ((p_drv->cfg.p_adc->SR & irq) != 0u) &&
           ((p_drv->cfg.p_adc->CR1 & MC_F405_ADC_CR1_JEOCIE) != 0u);
}

/* ---- init -------------------------------------------------------------- */

/* JEXTSEL of each trigger (RM0090 §13.6, external trigger for injected
 * channels), in mc_f405_adc_trigger_t order. */
static const uint8_t jextsel_of[3] = {MC_F405_ADC_JEXTSEL_TIM1_TRGO, MC_F405_ADC_JEXTSEL_TIM1_CC4,
                                      MC_F405_ADC_JEXTSEL_TIM8_CC4};

int mc_f405_adc_init(mc_f405_adc_t *p_drv, const mc_f405_adc_config_t *p_cfg)
{
    const mc_f405_adc_config_t *c = p_cfg;
    uint8_t seq[4];
    uint32_t phase_of_rank[3] = {0u, 0u, 0u};
    uint32_t n;
    uint32_t n_phase;
    uint32_t k;
    uint32_t jsqr;
    uint32_t smpr1 = 0u;
    uint32_t smpr2 = 0u;
    uint32_t ccr;
    uint32_t jextsel;
    float offsets_v[3];
    bool have_temp;
    mc_f405_adc_regs_t *r;

    if ((p_drv == NULL) || (c == NULL) || !config_valid(c)) {
        return -EINVAL;
    }

    /* Injected sequence: the measured phases in phase order, then vbus. */
    n = 0u;
    if (c->ch_ia != MC_F405_ADC_CH_NONE) {
        phase_of_rank[n] = 0u;
        seq[n++] = c->ch_ia;
    }
    phase_of_rank[n] = 1u;
    seq[n++] = c->ch_ib;
    if (c->ch_ic != MC_F405_ADC_CH_NONE) {
        phase_of_rank[n] = 2u;
        seq[n++] = c->ch_ic;
    }
    n_phase = n;
    seq[n++] = c->ch_vbus;
    /* Rank k of an n-long sequence sits in field JSQ(4 - n + k), i.e. the
     * sequence fills the last fields (RM0090 §13.13.12). */
    jsqr = (n - 1u) << MC_F405_ADC_JSQR_JL_SHIFT;
    for (k = 0u; k < n; k++) {
        jsqr |= (uint32_t)seq[k] << (5u * (4u - n + k));
    }

    smp_set(&smpr1, &smpr2, c->ch_ia, c->smp_current);
    smp_set(&smpr1, &smpr2, c->ch_ib, c->smp_current);
    smp_set(&smpr1, &smpr2, c->ch_ic, c->smp_current);
    smp_set(&smpr1, &smpr2, c->ch_vbus, c->smp_vbus);
    smp_set(&smpr1, &smpr2, c->temp_power_stage.channel, c->smp_temp);
    smp_set(&smpr1, &smpr2, c->temp_motor.channel, c->smp_temp);

    p_drv->cfg = *c;
    p_drv->n_inj = n;
    p_drv->n_phase = n_phase;
    for (k = 0u; k < 3u; k++) {
        p_drv->phase_of_rank[k] = (k < n_phase) ? phase_of_rank[k] : 0u;
    }
    p_drv->derive_ia = (c->ch_ia == MC_F405_ADC_CH_NONE);
    p_drv->rank_vbus = n - 1u;
    offsets_v[0] = c->ia_offset_v;
    offsets_v[1] = c->ib_offset_v;
    offsets_v[2] = c->ic_offset_v;
    p_drv->v_per_count = c->vref_v / ADC_FULL_SCALE_COUNTS;
    for (k = 0u; k < 3u; k++) {
        p_drv->a_per_count[k] = p_drv->v_per_count / (c->amp_gain_v_per_v * c->shunt_ohm);
        p_drv->offset_counts[k] = offsets_v[k] / p_drv->v_per_count;
    }
    p_drv->seq = 0u;
    p_drv->temp.power_stage_temp_c = 0.0f;
    p_drv->temp.motor_temp_c = 0.0f;
    p_drv->temp.valid_mask = 0u;
    p_drv->temp.absent_mask =
        ((c->temp_power_stage.channel == MC_F405_ADC_CH_NONE) ? MC_HAL_ADC_TEMP_VALID_POWER_STAGE
                                                              : 0u) |
        ((c->temp_motor.channel == MC_F405_ADC_CH_NONE) ? MC_HAL_ADC_TEMP_VALID_MOTOR : 0u);
    p_drv->temp_running = false;
    p_drv->temp_slot = (c->temp_power_stage.channel != MC_F405_ADC_CH_NONE) ? 0u : 1u;
    have_temp = (c->temp_power_stage.channel != MC_F405_ADC_CH_NONE) ||
                (c->temp_motor.channel != MC_F405_ADC_CH_NONE);
    p_drv->dev.ops = have_temp ? &adc_ops_temp : &adc_ops_no_temp;
    p_drv->dev.ctx = p_drv;

    /* ADC clock = PCLK2 / clk_div (ADCPRE = clk_div / 2 - 1); max 36 MHz. */
    ccr = c->p_common->CCR & ~MC_F405_ADC_CCR_ADCPRE_MASK;
    ccr |= (((uint32_t)c->clk_div / 2u) - 1u) << MC_F405_ADC_CCR_ADCPRE_SHIFT;
    if ((c->temp_power_stage.channel == CH_TEMP_SENSOR) ||
        (c->temp_motor.channel == CH_TEMP_SENSOR) || (c->temp_power_stage.channel == CH_VREFINT) ||
        (c->temp_motor.channel == CH_VREFINT)) {
        ccr |= TSVREFE;
    }
    c->p_common->CCR = ccr;

    jextsel = jextsel_of[c->trigger];
    r = c->p_adc;
    r->CR2 = 0u; /* off while configuring */
    r->CR1 = MC_F405_ADC_CR1_SCAN | (c->jeoc_irq ? MC_F405_ADC_CR1_JEOCIE : 0u);
    r->SMPR1 = smpr1;
    r->SMPR2 = smpr2;
    for (k = 0u; k < 4u; k++) {
        r->JOFR[k] = 0u; /* offsets are applied in float, not by the ADC */
    }
    r->JSQR = jsqr;
    r->SQR1 = 0u; /* L = 0: one regular conversion per start */
    r->SQR3 = have_temp ? temp_sensor(p_drv, p_drv->temp_slot)->channel : 0u;
    r->SR = 0u; /* rc_w0: clear stale flags */
    r->CR2 = MC_F405_ADC_CR2_ADON | (jextsel << MC_F405_ADC_CR2_JEXTSEL_SHIFT) |
             (MC_F405_ADC_JEXTEN_RISING << MC_F405_ADC_CR2_JEXTEN_SHIFT);
    return 0;
}
