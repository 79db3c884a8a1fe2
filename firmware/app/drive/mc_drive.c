/**
 * @file mc_drive.c
 * @brief Drive application: see mc_drive.h.
 */
#include "mc_drive.h"

#include <errno.h>
#include <stdatomic.h>
#include <stddef.h>

#include "math/mc_math.h"
#include "transforms/mc_transforms.h"

static bool finite4(float a, float b, float c, float d)
{
    return mc_isfinite_f32(a) && mc_isfinite_f32(b) && mc_isfinite_f32(c) && mc_isfinite_f32(d);
}

/* Open-phase check: both values 0 (off), or i_min in (0, i_max] and a time
 * of 1 .. 2^24 periods (a count that a float holds exactly). */
static uint32_t validate_open_phase(const mc_drive_cfg_t *cfg)
{
    const float i_min = cfg->open_phase_i_min_a;
    const float t = cfg->open_phase_time_s;
    if (!mc_isfinite_f32(i_min) || !mc_isfinite_f32(t) || i_min < 0.0f || t < 0.0f) {
        return MC_DRIVE_CFG_ERR_OPEN_PHASE;
    }
    if (i_min == 0.0f && t == 0.0f) {
        return MC_DRIVE_CFG_OK;
    }
    const float steps = t / cfg->foc.dt_s;
    if (i_min == 0.0f || !(i_min <= cfg->i_max_a) || !(steps >= 1.0f) || !(steps <= 16777216.0f)) {
        return MC_DRIVE_CFG_ERR_OPEN_PHASE;
    }
    return MC_DRIVE_CFG_OK;
}

/* A threshold pair of the bus-power handling: both 0 (off), or
 * vbus_min < lo < hi <= vbus_max. */
static uint32_t validate_bus_pair(const mc_drive_cfg_t *cfg, float lo, float hi)
{
    if (!mc_isfinite_f32(lo) || !mc_isfinite_f32(hi)) {
        return MC_DRIVE_CFG_ERR_BUS_POWER;
    }
    if (lo == 0.0f && hi == 0.0f) {
        return MC_DRIVE_CFG_OK;
    }
    if (!(lo > cfg->vbus_min_v) || !(hi > lo) || !(hi <= cfg->vbus_max_v)) {
        return MC_DRIVE_CFG_ERR_BUS_POWER;
    }
    return MC_DRIVE_CFG_OK;
}

static uint32_t validate_cfg(const mc_drive_cfg_t *cfg, mc_foc_f32_t *foc_probe,
                             uint32_t *p_foc_err)
{
    uint32_t err = MC_DRIVE_CFG_OK;
    *p_foc_err = mc_foc_f32_init(foc_probe, &cfg->foc);
    if (*p_foc_err != MC_FOC_ERR_NONE) {
        err |= MC_DRIVE_CFG_ERR_FOC;
    }
    if (cfg->pole_pairs == 0u) {
        err |= MC_DRIVE_CFG_ERR_POLES;
    }
    if (cfg->slow_loop_div == 0u) {
        err |= MC_DRIVE_CFG_ERR_DIV;
    }
    if (!mc_isfinite_f32(cfg->i_max_a) || !mc_isfinite_f32(cfg->i_trip_a) ||
        !(cfg->i_max_a > 0.0f) || !(cfg->i_trip_a >= cfg->i_max_a)) {
        err |= MC_DRIVE_CFG_ERR_CURRENT;
    }
    if (!mc_isfinite_f32(cfg->vbus_min_v) || !mc_isfinite_f32(cfg->vbus_max_v) ||
        !(cfg->vbus_min_v > 0.0f) || !(cfg->vbus_max_v > cfg->vbus_min_v)) {
        err |= MC_DRIVE_CFG_ERR_VBUS;
    }
    /* The forward-Euler tracking loop keeps its three poles near
     * z = 1 - bw dt, well inside the unit circle, for 3 bw dt <= 1. */
    const float bw = cfg->speed_pll_bw_rad_s;
    if (!mc_isfinite_f32(bw) || !(bw > 0.0f) || !(3.0f * bw * cfg->foc.dt_s <= 1.0f)) {
        err |= MC_DRIVE_CFG_ERR_SPEED_PLL;
    }
    if (!mc_isfinite_f32(cfg->encoder_offset_rad) || !mc_isfinite_f32(cfg->i_offset_a[0]) ||
        !mc_isfinite_f32(cfg->i_offset_a[1]) || !mc_isfinite_f32(cfg->i_offset_a[2]) ||
        !(cfg->encoder_latency_s >= 0.0f) || !(cfg->encoder_latency_s <= 1e-3f)) {
        err |= MC_DRIVE_CFG_ERR_OFFSET;
    }
    if (cfg->angle_ref > MC_DRIVE_ANGLE_REF_ALIGN) {
        err |= MC_DRIVE_CFG_ERR_ANGLE_REF;
    }
    const float sup[6] = {cfg->omega_max_rad_s,   cfg->temp_max_c,   cfg->stall_current_frac,
                          cfg->stall_speed_rad_s, cfg->stall_time_s, cfg->i_unbalance_max_a};
    for (unsigned k = 0u; k < 6u; ++k) {
        if (!mc_isfinite_f32(sup[k]) || sup[k] < 0.0f) {
            err |= MC_DRIVE_CFG_ERR_SUPERVISION;
        }
    }
    if (cfg->stall_current_frac > 1.0f) {
        err |= MC_DRIVE_CFG_ERR_SUPERVISION;
    }
    const float stop[7] = {cfg->stop_decel_rad_s2, cfg->stop_rest_rad_s, cfg->stop_kp_a_s_rad,
                           cfg->stop_iq_ff_a,      cfg->temp_warn_c,     cfg->vbus_sag_v,
                           cfg->speed_accel_rad_s2};
    for (unsigned k = 0u; k < 7u; ++k) {
        if (!mc_isfinite_f32(stop[k]) || stop[k] < 0.0f) {
            err |= MC_DRIVE_CFG_ERR_SUPERVISION;
        }
    }
    if (cfg->dead_time_comp &&
        (!mc_isfinite_f32(cfg->dead_time_s) || !(cfg->dead_time_s >= 0.0f) ||
         !(cfg->dead_time_s < 0.5f * cfg->foc.dt_s) || !mc_isfinite_f32(cfg->dead_band_a) ||
         !(cfg->dead_band_a >= 0.0f))) {
        err |= MC_DRIVE_CFG_ERR_DEAD_TIME;
    }
    err |= validate_open_phase(cfg);
    err |= validate_bus_pair(cfg, cfg->vbus_regen_start_v, cfg->vbus_regen_end_v);
    err |= validate_bus_pair(cfg, cfg->brake_on_v, cfg->brake_full_v);
    if (cfg->fw_enable) {
        mc_fw_f32_t probe;
        if (mc_fw_f32_init(&probe, &cfg->fw) != MC_FW_ERR_NONE || cfg->fw.dt_s != cfg->foc.dt_s) {
            err |= MC_DRIVE_CFG_ERR_FW;
        }
    }
    if (cfg->asc_enable && !(cfg->foc.flux_wb > 0.0f && cfg->foc.ld_h > 0.0f &&
                             cfg->foc.flux_wb < cfg->i_trip_a * cfg->foc.ld_h)) {
        err |= MC_DRIVE_CFG_ERR_ASC;
    }
    if (!mc_isfinite_f32(cfg->regen_id_a) || cfg->regen_id_a < 0.0f ||
        (cfg->regen_id_a > 0.0f && !(cfg->regen_id_a <= cfg->i_max_a))) {
        err |= MC_DRIVE_CFG_ERR_BUS_POWER;
    }
    if (mc_drive_bus_check(&cfg->bus) != 0u) {
        err |= MC_DRIVE_CFG_ERR_BUS_POWER;
    }
    {
        mc_drive_thermal_t probe;
        if (mc_drive_thermal_init(&probe, &cfg->thermal) != MC_DRIVE_THERMAL_ERR_NONE) {
            err |= MC_DRIVE_CFG_ERR_THERMAL;
        }
    }
    return err;
}

uint32_t mc_drive_check_cfg(const mc_drive_cfg_t *cfg)
{
    mc_foc_f32_t foc;
    uint32_t foc_err = MC_FOC_ERR_NONE;
    if (cfg == NULL) {
        return MC_DRIVE_CFG_ERR_NULL;
    }
    return validate_cfg(cfg, &foc, &foc_err);
}

/* The regenerative limit's lead time (mc_drive.h): the current loop's
 * closed-loop time constant L / kp (kp = L bandwidth) and one and a half
 * periods of computation and PWM delay; its filter's factor per step. */
static float regen_lead_alpha(const mc_drive_cfg_t *cfg)
{
    const mc_foc_f32_cfg_t *c = &cfg->foc;
    const float t_lead =
        ((c->kp_q_v_per_a > 0.0f) ? (c->lq_h / c->kp_q_v_per_a) : 0.0f) + (1.5f * c->dt_s);
    return c->dt_s / (t_lead + c->dt_s);
}

uint32_t mc_drive_init(mc_drive_t *d, const mc_drive_cfg_t *cfg, const mc_hal_t *hal)
{
    if (d == NULL || cfg == NULL || hal == NULL) {
        return MC_DRIVE_CFG_ERR_NULL;
    }
    mc_foc_f32_t foc;
    uint32_t foc_err = MC_FOC_ERR_NONE;
    uint32_t err = validate_cfg(cfg, &foc, &foc_err);
    if (hal->adc == NULL || (hal->pwm3 == NULL && hal->pwm2 == NULL)) {
        err |= MC_DRIVE_CFG_ERR_HAL;
    }
    if (err != MC_DRIVE_CFG_OK) {
        return err;
    }
    /* Outputs off before anything else: a drive starts safe. */
    if (hal->pwm3 != NULL) {
        (void)mc_hal_pwm3_disable(hal->pwm3);
    }
    if (hal->pwm2 != NULL) {
        (void)mc_hal_pwm2_disable(hal->pwm2);
    }

    mc_drive_t z = {0};
    *d = z;
    d->cfg = *cfg;
    d->hal = hal;
    d->foc = foc;
    d->mode = MC_DRIVE_MODE_IDLE;
    d->tm.regen_scale = 1.0f;
    d->regen_lead_alpha = regen_lead_alpha(cfg);
    mc_drive_bus_init(&d->bus, &cfg->foc);
    d->bus_on = mc_drive_bus_any(&cfg->bus);
    (void)mc_drive_thermal_init(&d->thermal, &cfg->thermal); /* validated above */
    if (cfg->fw_enable) {
        (void)mc_fw_f32_init(&d->fw, &cfg->fw);
    }
    {
        /* validated above (MC_DRIVE_CFG_ERR_SPEED_PLL): cannot fail here */
        const mc_enctrack_f32_cfg_t tc = {.bw_rad_s = cfg->speed_pll_bw_rad_s,
                                          .dt_s = cfg->foc.dt_s};
        (void)mc_enctrack_f32_init(&d->enc_trk, &tc);
    }
    d->foc_err = foc_err;
    d->open_phase_trip = (cfg->open_phase_time_s > 0.0f)
                             ? (uint32_t)(cfg->open_phase_time_s / cfg->foc.dt_s + 0.5f)
                             : 0u;
    /* The control deadline in ticks: one PWM period after the ADC trigger. */
    uint32_t hz = 0u;
    if (hal->tick != NULL && mc_hal_tick_get_freq_hz(hal->tick, &hz) == 0 && hz > 0u) {
        const float ticks = (float)hz * cfg->foc.dt_s;
        d->deadline_ticks = (ticks >= 1.0f && ticks < 4.0e9f) ? (uint32_t)ticks : 0u;
    }
    return MC_DRIVE_CFG_OK;
}

static uint32_t now_ticks(const mc_drive_t *d)
{
    uint32_t t = 0u;
    if (d->hal->tick != NULL) {
        (void)mc_hal_tick_read(d->hal->tick, &t);
    }
    return t;
}

/* Outputs off; if the PWM driver cannot confirm it, the gate kill (which
 * cannot fail) does it, as hal/pwm3.h requires. */
static void outputs_off(const mc_drive_t *d)
{
    bool confirmed = true;
    if (d->hal->pwm3 != NULL && mc_hal_pwm3_disable(d->hal->pwm3) != 0) {
        confirmed = false;
    }
    if (d->hal->pwm3 != NULL) {
        /* The zero vector into the duty registers while the bridge is off:
         * the timer latches it at its next update, so a later enable, whose
         * own first duties take effect only at the update after it, closes
         * the switches on the zero vector, not on the last run's voltage
         * vector at a rotor angle long gone (after commissioning's last
         * step at 60 rad/s, that stale vector drove the paper-002 motor to
         * 15 A within the first 0.5 ms period at 2 kHz: OVERCURRENT on
         * enable, depending on when the enable came) */
        (void)mc_hal_pwm3_set_duty(d->hal->pwm3, 0.5f, 0.5f, 0.5f);
    }
    if (d->hal->pwm2 != NULL && mc_hal_pwm2_disable(d->hal->pwm2) != 0) {
        confirmed = false;
    }
    if (!confirmed) {
        (void)mc_hal_fault_gate_kill(d->hal->fault);
    }
}

/* The drive feeds a 3-phase machine unless the attached law drives the dual
 * H-bridge: then ia, ib are two independent winding currents and there is
 * no third phase to derive or check. */
static bool drives_three_phase(const mc_drive_t *d)
{
    return d->hal->pwm3 != NULL && !(d->ctrl != NULL && d->ctrl->outputs == MC_DRIVE_OUT_PWM2);
}

/* Line-to-line back-EMF peak of the encoder's speed above frac * the bus
 * (mc_drive.h, active short circuit). */
static bool asc_emf_above(const mc_drive_t *d, float frac)
{
    const float emf = MC_SQRT3_F32 * d->cfg.foc.flux_wb * (float)d->cfg.pole_pairs *
                      mc_abs_f32(d->enc_trk.omega_rad_s);
    return emf > frac * d->tm.vbus_v;
}

/* Whether a fault with these bits shorts the phases instead of opening
 * them: every fault so far of MC_DRIVE_ASC_FAULTS, a 3-phase bridge, and
 * the short already on or the back-EMF above the bus. */
static bool asc_wanted(const mc_drive_t *d, uint32_t bits)
{
    const uint32_t all = bits | d->faults;
    return d->cfg.asc_enable && drives_three_phase(d) && (all & ~MC_DRIVE_ASC_FAULTS) == 0u &&
           (d->asc_active || (d->enc_trk.primed && asc_emf_above(d, 1.0f)));
}

/* All low-side switches on (duties 0, bridge enabled); the bridge opens
 * when the PWM driver refuses either. */
static void asc_on(mc_drive_t *d)
{
    if (mc_hal_pwm3_set_duty(d->hal->pwm3, 0.0f, 0.0f, 0.0f) != 0 ||
        mc_hal_pwm3_enable(d->hal->pwm3) != 0) {
        outputs_off(d);
        d->asc_active = false;
        return;
    }
    if (d->hal->pwm2 != NULL) {
        (void)mc_hal_pwm2_disable(d->hal->pwm2);
    }
    d->asc_active = true;
}

/* Safe state: outputs off (or the active short circuit) first, then
 * bookkeeping. */
static void raise_fault(mc_drive_t *d, uint32_t bits)
{
    if (bits == 0u) {
        return;
    }
    if (asc_wanted(d, bits)) {
        asc_on(d);
    } else {
        outputs_off(d);
        d->asc_active = false;
    }
    d->id_ref_a = 0.0f;
    d->iq_ref_a = 0.0f;
    if (d->faults == 0u) {
        /* lowest set bit: the first detected cause of this step */
        d->first_fault = bits & (~bits + 1u);
        d->fault_tick = now_ticks(d);
    }
    d->faults |= bits;
    d->mode = MC_DRIVE_MODE_FAULT;
}

/* The per-cpr constants of the encoder path, computed when the counts per
 * revolution (or, through mc_drive_set_runtime_limits, omega_max) change
 * rather than every step: two float divisions (14 cycles each on the M4F)
 * less per fast step, with the same expressions, so the same values. */
static void enc_constants(mc_drive_t *d, uint32_t cpr)
{
    if (cpr != d->enc_cpr_cached) {
        d->enc_rad_per_count = MC_TWO_PI_F32 / (float)cpr;
        /* a source that checks its own steps: a threshold no step reaches
         * (at most half a turn), set here so the step costs nothing */
        d->enc_max_step_counts =
            d->cfg.enc_steps_checked
                ? (float)cpr
                : 2.0f * d->cfg.omega_max_rad_s * d->cfg.foc.dt_s * (float)cpr / MC_TWO_PI_F32 +
                      2.0f;
        d->enc_interp = (float)d->cfg.pole_pairs * d->enc_rad_per_count > MC_DRIVE_ENC_INTERP_E_RAD;
        d->enc_cpr_cached = cpr;
    }
}

/* The electrical angle of a coarse encoder (enc_interp): the count's angle
 * moved by the tracking loop's sub-count estimate, delta = wrap_pi(theta_trk
 * - count q), held within one count of the measurement (a loop that strays
 * further, e.g. just after a reset, never moves the angle beyond the count
 * next to the one read). The commissioned offset already holds the half
 * count a count's angle lags the rotor by on average (mc_commission.c
 * averages the offset over a sweep), and the loop follows the count's
 * staircase, so no other correction enters (firmware/app/README.md). */
static float enc_interp_delta(const mc_drive_t *d, uint32_t count)
{
    const float q = d->enc_rad_per_count;
    const float delta = mc_wrap_pi_f32(d->enc_trk.theta_rad - (float)count * q);
    return (float)d->cfg.pole_pairs * mc_sat_f32(delta, -q, q);
}

static void update_position(mc_drive_t *d, const mc_hal_encoder_sample_t *enc)
{
    const uint32_t cpr = enc->counts_per_rev;
    /* The HAL promises count < cpr; reduce only if a driver breaks that. */
    const uint32_t raw = (enc->count < cpr) ? enc->count : enc->count % cpr;
    /* A reversed encoder counts down as the rotor turns positive. */
    const uint32_t count = (d->cfg.encoder_reversed && raw != 0u) ? cpr - raw : raw;
    d->enc_count = count;
    const float rad_per_count = d->enc_rad_per_count;
    /* Electrical position in integer counts first: exact for any count.
     * 32-bit when the product fits (always for cpr * poles < 2^32), which
     * spares the M4F a 64-bit library division. */
    const uint64_t prod = (uint64_t)count * (uint64_t)d->cfg.pole_pairs;
    const uint32_t e_count =
        (prod <= 0xFFFFFFFFull) ? (uint32_t)prod % cpr : (uint32_t)(prod % (uint64_t)cpr);
    d->tm.theta_m_rad = (float)count * rad_per_count;

    /* Speed from the encoder tracking loop (observer/mc_enctrack.h): the
     * angle is finite by construction, so the step cannot fail. */
    (void)mc_enctrack_f32_step(&d->enc_trk, d->tm.theta_m_rad);
    d->tm.omega_m_rad_s = d->enc_trk.omega_rad_s;
    /* A sensor with a latency (an SPI encoder's frame) reports the rotor
     * as it was that long ago: the angle moves on by omega_e latency. */
    float offset = d->cfg.encoder_offset_rad;
    if (d->cfg.encoder_latency_s > 0.0f) {
        offset += d->cfg.encoder_latency_s * (float)d->cfg.pole_pairs * d->enc_trk.omega_rad_s;
    }
    if (d->enc_interp) {
        d->tm.theta_e_rad =
            mc_wrap_2pi_f32((float)e_count * rad_per_count + offset + enc_interp_delta(d, count));
    } else {
        d->tm.theta_e_rad = mc_wrap_2pi_fast_f32((float)e_count * rad_per_count + offset);
    }
}

static uint32_t check_sample(const mc_drive_t *d, const mc_hal_adc_sample_t *s, float *p_ic)
{
    const uint32_t need = MC_HAL_ADC_VALID_IA | MC_HAL_ADC_VALID_IB | MC_HAL_ADC_VALID_VBUS;
    if ((s->valid_mask & need) != need) {
        return MC_DRIVE_FAULT_ADC;
    }
    const bool have_ic = (s->valid_mask & MC_HAL_ADC_VALID_IC) != 0u;
    const float ic = have_ic ? s->ic_a : (drives_three_phase(d) ? -(s->ia_a + s->ib_a) : 0.0f);
    if (!finite4(s->ia_a, s->ib_a, ic, s->vbus_v)) {
        return MC_DRIVE_FAULT_MEAS_NAN;
    }
    *p_ic = ic;
    uint32_t f = 0u;
    const float trip = d->cfg.i_trip_a;
    if (mc_abs_f32(s->ia_a) > trip || mc_abs_f32(s->ib_a) > trip || mc_abs_f32(ic) > trip) {
        f |= MC_DRIVE_FAULT_OVERCURRENT;
    }
    if (have_ic && d->cfg.i_unbalance_max_a > 0.0f &&
        mc_abs_f32(s->ia_a + s->ib_a + s->ic_a) > d->cfg.i_unbalance_max_a) {
        f |= MC_DRIVE_FAULT_UNBALANCED;
    }
    if (s->vbus_v < d->cfg.vbus_min_v) {
        f |= MC_DRIVE_FAULT_VBUS_LOW;
    }
    if (s->vbus_v > d->cfg.vbus_max_v) {
        f |= MC_DRIVE_FAULT_VBUS_HIGH;
    }
    return f;
}

/* An encoder step larger than twice what omega_max allows in one period
 * (plus two counts of quantisation) is not a motion: lost lines, a noisy
 * cable, a slipped coupling. */
static uint32_t encoder_jump_fault(mc_drive_t *d, const mc_hal_encoder_sample_t *enc)
{
    const uint32_t cpr = enc->counts_per_rev;
    const uint32_t count = (enc->count < cpr) ? enc->count : enc->count % cpr;
    uint32_t f = 0u;
    if (d->enc_trk.primed && d->cfg.omega_max_rad_s > 0.0f) {
        uint32_t step =
            (count >= d->last_count_raw) ? count - d->last_count_raw : d->last_count_raw - count;
        if (step > cpr / 2u) {
            step = cpr - step; /* the shorter way round the circle */
        }
        if ((float)step > d->enc_max_step_counts) {
            f = MC_DRIVE_FAULT_ENCODER;
        }
    }
    d->last_count_raw = count;
    return f;
}

/* The index seen (INDEX): the HAL reports the count relative to it from
 * this sample on, a jump that is no motion: the speed tracking starts over
 * from this count (unprimed, so the jump check skips this sample). */
static void index_rebase(mc_drive_t *d, const mc_hal_encoder_sample_t *enc)
{
    const bool seen = (enc->flags & MC_HAL_ENCODER_FLAG_INDEX) != 0u;
    if (seen && !d->index_seen && (d->cfg.angle_ref == MC_DRIVE_ANGLE_REF_INDEX)) {
        /* validated at init (MC_DRIVE_CFG_ERR_SPEED_PLL): cannot fail */
        const mc_enctrack_f32_cfg_t tc = {.bw_rad_s = d->cfg.speed_pll_bw_rad_s,
                                          .dt_s = d->cfg.foc.dt_s};
        (void)mc_enctrack_f32_init(&d->enc_trk, &tc);
    }
    d->index_seen = seen;
}

/* Open-phase check of one CURRENT-mode step (mc_drive.h): per phase, a
 * net count of steps in which a large reference met no current. */
static uint32_t open_phase_check(mc_drive_t *d, const float meas_a[3], float vbus_v,
                                 float theta_e_rad)
{
    const mc_foc_f32_out_t *o = &d->tm.foc;
    const float v_lim = MC_DRIVE_OPEN_PHASE_VSAT_FRAC * d->cfg.foc.v_limit_ratio *
                        mc_svpwm_max_voltage_f32(vbus_v, d->cfg.foc.limit_mode);
    if ((o->svpwm_flags & MC_SVPWM_FLAG_LIMITED) != 0u ||
        o->vd_v * o->vd_v + o->vq_v * o->vq_v >= v_lim * v_lim) {
        return 0u; /* at the voltage limit: no evidence either way */
    }
    float s;
    float c;
    mc_sincos_f32(theta_e_rad, &s, &c);
    /* Reference in alpha-beta, then per phase (amplitude-invariant). */
    const float r_alpha = d->tm.id_ref_a * c - d->tm.iq_ref_a * s;
    const float r_beta = d->tm.id_ref_a * s + d->tm.iq_ref_a * c;
    const float h = 0.5f * MC_SQRT3_F32 * r_beta;
    const float ref[3] = {r_alpha, -0.5f * r_alpha + h, -0.5f * r_alpha - h};
    uint32_t f = 0u;
    for (unsigned k = 0u; k < 3u; ++k) {
        const float r = mc_abs_f32(ref[k]);
        if (!(r >= d->cfg.open_phase_i_min_a)) {
            continue;
        }
        if (mc_abs_f32(meas_a[k]) < MC_DRIVE_OPEN_PHASE_CONDUCTION_RATIO * r) {
            d->open_phase_count[k]++;
            if (d->open_phase_count[k] >= d->open_phase_trip) {
                d->open_phase_mask |= 1u << k;
                f = MC_DRIVE_FAULT_OPEN_PHASE;
            }
        } else if (d->open_phase_count[k] > 0u) {
            d->open_phase_count[k]--;
        }
    }
    return f;
}

/* Every valid bus sample: its first-order lag of time constant t_lead,
 * from which the regen limit takes the bus's rate (v - lag = t_lead dv/dt
 * for a steady slope). */
static void regen_track(mc_drive_t *d, float vbus_v)
{
    if (!(d->vbus_lag_v > 0.0f)) {
        d->vbus_lag_v = vbus_v;
    }
    d->vbus_lag_v += d->regen_lead_alpha * (vbus_v - d->vbus_lag_v);
}

/* The regenerative-current limit (mc_drive.h): a braking q reference
 * scaled down as the bus (with its lead) rises from vbus_regen_start_v to
 * _end_v. */
static void regen_limit(mc_drive_t *d, float vbus_meas_v, float omega, float *p_id_a, float *p_iq_a)
{
    float k = 1.0f;
    const float lo = d->cfg.vbus_regen_start_v;
    const float hi = d->cfg.vbus_regen_end_v;
    /* the bus the current loop will have brought: v + t_lead dv/dt */
    const float vbus_v = vbus_meas_v + (vbus_meas_v - d->vbus_lag_v);
    if (hi > 0.0f && vbus_v > lo && *p_iq_a * omega < 0.0f) {
        k = (vbus_v >= hi) ? 0.0f : (hi - vbus_v) / (hi - lo);
    }
    d->tm.regen_scale = k;
    if (k < 1.0f) {
        const float iq = k * *p_iq_a;
        *p_iq_a = iq;
        if (d->cfg.regen_id_a > 0.0f) {
            const float room2 = d->cfg.i_max_a * d->cfg.i_max_a - iq * iq;
            float id = -(1.0f - k) * d->cfg.regen_id_a;
            if (room2 <= 0.0f) {
                id = 0.0f;
            } else if (id * id > room2) {
                id = -mc_sqrt_f32(room2);
            }
            if (id < *p_id_a) {
                *p_id_a = id;
            }
        }
    }
}

/* MTPA / field weakening (mc_drive.h): the command iq_ref_a becomes the
 * kernel's (id, iq); the voltage it weakens against is the last step's. */
static uint32_t fw_refs(mc_drive_t *d, float vbus_v, float *p_id_a, float *p_iq_a)
{
    const mc_fw_f32_in_t in = {
        .i_cmd_a = *p_iq_a,
        .vd_v = d->tm.foc.vd_v,
        .vq_v = d->tm.foc.vq_v,
        .vbus_v = vbus_v,
    };
    if (mc_fw_f32_step(&d->fw, &in, &d->tm.fw) != MC_FW_ERR_NONE) {
        return MC_DRIVE_FAULT_CONTROL;
    }
    *p_id_a = (*p_id_a < d->tm.fw.id_ref_a) ? *p_id_a : d->tm.fw.id_ref_a;
    *p_iq_a = d->tm.fw.iq_ref_a;
    return 0u;
}

/* Brake chopper duty from the bus voltage (mc_drive.h). */
static uint32_t brake_step(mc_drive_t *d, float vbus_v)
{
    const float lo = d->cfg.brake_on_v;
    const float hi = d->cfg.brake_full_v;
    if (d->hal->brake == NULL || !(hi > 0.0f)) {
        return 0u;
    }
    float duty = (vbus_v - lo) / (hi - lo);
    duty = (duty < 0.0f) ? 0.0f : ((duty > 1.0f) ? 1.0f : duty);
    d->tm.brake_duty = duty;
    return (mc_hal_brake_set_duty(d->hal->brake, duty) != 0) ? MC_DRIVE_FAULT_PWM : 0u;
}

/* Dead-time error of one leg, in units of (dead_time / dt) vbus:
 * sat(i / band), +-1 outside the band (a hard sign for band = 0). */
/* Dead-time compensation (cfg.dead_time_comp): each leg's duty plus
 * mc_sign_band_f32(i_x) dead_time / dt from the step's sample, clamped to [0, 1]. */
static void dead_comp(const mc_drive_t *d, const float i_a[3], mc_foc_f32_out_t *o)
{
    const float kd = d->cfg.dead_time_s / d->cfg.foc.dt_s;
    const float band = d->cfg.dead_band_a;
    o->duty_a = mc_sat_f32(o->duty_a + (kd * mc_sign_band_f32(i_a[0], band)), 0.0f, 1.0f);
    o->duty_b = mc_sat_f32(o->duty_b + (kd * mc_sign_band_f32(i_a[1], band)), 0.0f, 1.0f);
    o->duty_c = mc_sat_f32(o->duty_c + (kd * mc_sign_band_f32(i_a[2], band)), 0.0f, 1.0f);
}

/* A law's frame jump (out.reframe): preset the current PIs so that, in the
 * new frame theta with decoupling speed omega_e, the next output reproduces
 * the voltage vector commanded last step (no voltage step). */
static void foc_preset(mc_drive_t *d, const mc_hal_adc_sample_t *s, float theta_e, float omega_e,
                       float id_ref, float iq_ref)
{
    const mc_foc_f32_cfg_t *c = &d->cfg.foc;
    float sn;
    float cs;
    float i_al;
    float i_be;
    float id_m;
    float iq_m;
    float vd;
    float vq;
    mc_clarke_f32(s->ia_a, s->ib_a, &i_al, &i_be);
    mc_sincos_f32(theta_e, &sn, &cs);
    mc_park_f32(i_al, i_be, sn, cs, &id_m, &iq_m);
    mc_park_f32(d->v_ab_prev_v[0], d->v_ab_prev_v[1], sn, cs, &vd, &vq);
    vd = vd + (omega_e * c->lq_h * iq_m) - (d->foc.pi_d.kp * (id_ref - id_m));
    vq = vq - (omega_e * c->ld_h * id_m) - (omega_e * c->flux_wb) -
         (d->foc.pi_q.kp * (iq_ref - iq_m));
    (void)mc_pi_f32_reset(&d->foc.pi_d, vd);
    (void)mc_pi_f32_reset(&d->foc.pi_q, vq);
}

/* What the current loop is asked to do this step. */
typedef struct {
    float id_a, iq_a;  /* references (iq: the signed command with field weakening) */
    float theta_e_rad; /* frame */
    float omega_e_rad_s;
    bool rotor_frame; /* field weakening, regen limit, open-phase check */
    bool reframe;
} cur_req_t;

/* The delay from a sample to the middle of the PWM period its voltage acts
 * in [periods]: one period of computation, half of the zero-order hold
 * (the same lag mc_law_cfg's ref_lag_s takes). */
#define MC_DRIVE_COG_DELAY_PERIODS 1.5f

/* The phase currents the references ask for at the angle this step's
 * voltage acts at, for the dead-time compensation while the anticogging
 * feed-forward runs (mc_drive_t.cog_on): there the current is a fraction of
 * an ampere swinging at the cogging frequency, inside the compensation's
 * linear band (cfg.dead_band_a), where sat(i / band) of the measured
 * current, 1.5 periods old and a few ADC counts, leaves a voltage error of
 * (dead time / T) vbus / band times the current's change: an impedance
 * many times the winding's that the feed-forward cannot push through. The
 * reference is the current the loop delivers then. */
static void ref_phases(const mc_drive_t *d, float id, float iq, const cur_req_t *r, float i_x[3])
{
    float sn;
    float cs;
    float al;
    float be;
    const float th =
        r->theta_e_rad + (r->omega_e_rad_s * MC_DRIVE_COG_DELAY_PERIODS * d->cfg.foc.dt_s);
    mc_sincos_f32(th, &sn, &cs);
    mc_inv_park_f32(id, iq, sn, cs, &al, &be);
    mc_inv_clarke_f32(al, be, &i_x[0], &i_x[1], &i_x[2]);
}

/* One step of the current loop, the same for CURRENT mode, the stop's P
 * loop and the laws that give current references (mc_drive.h): MTPA /
 * field weakening and the regenerative limit in the rotor's frame, the
 * current limit, the FOC step, dead-time compensation, the duties, the
 * open-phase check. */
static uint32_t current_loop(mc_drive_t *d, const mc_hal_adc_sample_t *s, float ic,
                             const cur_req_t *r)
{
    float id = r->id_a;
    float iq = r->iq_a;
    const float lim = mc_drive_thermal_limit_a(&d->thermal, d->cfg.i_max_a);
    uint32_t f = 0u;
    if (r->rotor_frame && d->cfg.fw_enable) {
        f |= fw_refs(d, s->vbus_v, &id, &iq);
    }
    if (r->rotor_frame) {
        regen_limit(d, s->vbus_v, r->omega_e_rad_s, &id, &iq);
    } else {
        d->tm.regen_scale = 1.0f;
    }
    if (d->bus_on) {
        const mc_drive_bus_in_t bi = {s->vbus_v,      r->omega_e_rad_s, r->rotor_frame,
                                      d->fast_count,  d->tm.foc.id_a,   d->tm.foc.iq_a,
                                      d->tm.foc.vd_v, d->tm.foc.vq_v};
        mc_drive_bus_limit(&d->bus, &d->cfg.bus, &d->cfg.foc, &bi, &id, &iq);
    }
    id = mc_sat_f32(id, -lim, lim);
    iq = mc_sat_f32(iq, -lim, lim);
    d->tm.id_ref_a = id;
    d->tm.iq_ref_a = iq;
    if (r->reframe) {
        foc_preset(d, s, r->theta_e_rad, r->omega_e_rad_s, id, iq);
    }
    {
        const mc_foc_f32_in_t in = {
            .ia_a = s->ia_a,
            .ib_a = s->ib_a,
            .ic_a = ic,
            .three_phase = false,
            .theta_e_rad = r->theta_e_rad,
            .omega_e_rad_s = r->omega_e_rad_s,
            .vbus_v = s->vbus_v,
            .id_ref_a = id,
            .iq_ref_a = iq,
        };
        const uint32_t ferr = mc_foc_f32_step(&d->foc, &in, &d->tm.foc);
        if (ferr != MC_FOC_ERR_NONE) {
            d->foc_err = ferr;
            return f | MC_DRIVE_FAULT_CONTROL;
        }
    }
    d->v_ab_prev_v[0] = d->tm.foc.v_alpha_v;
    d->v_ab_prev_v[1] = d->tm.foc.v_beta_v;
    {
        const float meas[3] = {s->ia_a, s->ib_a, ic};
        if (d->cfg.dead_time_comp) {
            float ref[3];
            if (d->cog_on) {
                ref_phases(d, id, iq - d->cog_lead_a, r, ref);
            }
            dead_comp(d, d->cog_on ? ref : meas, &d->tm.foc);
        }
        d->cog_on = false; /* one step's: cog_ff sets it again */
        if (mc_hal_pwm3_set_duty(d->hal->pwm3, d->tm.foc.duty_a, d->tm.foc.duty_b,
                                 d->tm.foc.duty_c) != 0) {
            return f | MC_DRIVE_FAULT_PWM;
        }
        if (r->rotor_frame && (d->open_phase_trip != 0u)) {
            f |= open_phase_check(d, meas, s->vbus_v, r->theta_e_rad);
        }
    }
    return f;
}

/* The speed reference of a speed law one step on: towards the target at
 * rate [rad/s^2] (0: at once), exact for the last step (mc_drive.h). The
 * law sees the reference before the step and the step's acceleration. */
static void shape_speed_ref(mc_drive_t *d, float target, float rate)
{
    const float dt = d->cfg.foc.dt_s;
    const float e = target - d->speed_ref_rad_s;
    float a;
    if (!(rate > 0.0f) || (mc_abs_f32(e) <= rate * dt)) {
        a = e / dt;
    } else {
        a = (e > 0.0f) ? rate : -rate;
    }
    d->speed_alpha_rad_s2 = a;
}

/* The feed-forward from the map's bins (a map of every order), faded as a
 * whole at its RMS order (mc_cog_map_order_rms): past MC_COG_FADE_END times
 * the loop's bandwidth it is not evaluated. */
static float cog_ff_bins(const mc_drive_t *d, const mc_drive_meas_t *m, const mc_cog_loop_t *lp,
                         float *p_i_a)
{
    const float g = mc_cog_fade_gain(mc_abs_f32(m->omega_m_rad_s) * lp->tau_s * d->cog_ord_rms);
    float i_a = 0.0f;
    float ff = 0.0f;
    if (g > 0.0f) {
        ff = g * mc_cog_ff_adv_a(d->cog, m->theta_m_rad, m->omega_m_rad_s, lp, &i_a);
        i_a *= g;
    }
    *p_i_a = i_a;
    return ff;
}

/* The anticogging feed-forward of this step [A] (mc_drive_attach_cog): a
 * speed or position law's, anticogging on, with a map and the encoder
 * read; else 0. */
static float cog_ff(mc_drive_t *d, const mc_drive_meas_t *m)
{
    float ff = 0.0f;
    d->cog_on = false;
    d->cog_lead_a = 0.0f;
    if (d->cfg.anticogging && (d->cog != NULL) && d->ctrl->cogging_ff && m->have_encoder) {
        float i_a;
        const mc_cog_loop_t lp = {.lead_i_s = d->cfg.foc.dt_s,
                                  .lead_d_s = MC_DRIVE_COG_DELAY_PERIODS * d->cfg.foc.dt_s,
                                  .tau_s = d->cfg.foc.lq_h / d->foc.pi_q.kp};
        ff = (d->cog_ser.count > 0u)
                 ? mc_cog_series_ff_adv_a(&d->cog_ser, m->theta_m_rad, m->omega_m_rad_s, &lp, &i_a)
                 : cog_ff_bins(d, m, &lp, &i_a);
        d->cog_lead_a = ff - i_a;
        d->cog_on = true;
    }
    d->tm.cog_ff_a = ff;
    return ff;
}

/* One step of the plugged law: its duties go to the bridge it drives, its
 * current references to the drive's current loop (a speed or position
 * law's q reference with the anticogging feed-forward: the one place it
 * enters, before the current loop's limits). */
static uint32_t run_ctrl(mc_drive_t *d, mc_drive_meas_t *m, const mc_hal_adc_sample_t *s, float ic)
{
    mc_drive_out_t out = {.duty_a = 0.5f, .duty_b = 0.5f, .duty_c = 0.5f};
    uint32_t cerr;
    int rc;
    const bool shaped = d->ctrl->uses_speed_ref;
    if (shaped) {
        const bool stopping = d->mode == MC_DRIVE_MODE_STOPPING;
        shape_speed_ref(d, stopping ? 0.0f : d->speed_target_rad_s,
                        stopping ? d->cfg.stop_decel_rad_s2 : d->cfg.speed_accel_rad_s2);
        m->have_speed_ref = true;
        m->omega_ref_rad_s = d->speed_ref_rad_s;
        m->alpha_ref_rad_s2 = d->speed_alpha_rad_s2;
    }
    cerr = d->ctrl->fast(d->ctrl->ctx, m, &out);
    if (shaped) {
        const float target = (d->mode == MC_DRIVE_MODE_STOPPING) ? 0.0f : d->speed_target_rad_s;
        const float next = d->speed_ref_rad_s + (d->speed_alpha_rad_s2 * m->dt_s);
        /* the last step lands on the target exactly */
        d->speed_ref_rad_s =
            (mc_abs_f32(target - d->speed_ref_rad_s) <= mc_abs_f32(d->speed_alpha_rad_s2) * m->dt_s)
                ? target
                : next;
    }
    d->tm.ctrl_out = out;
    if (cerr != 0u) {
        d->tm.ctrl_err = cerr;
        return MC_DRIVE_FAULT_CONTROL;
    }
    if (d->ctrl->outputs == MC_DRIVE_OUT_CURRENT) {
        const cur_req_t r = {out.id_ref_a,    out.iq_ref_a + cog_ff(d, m),
                             out.theta_e_rad, out.omega_e_rad_s,
                             out.rotor_frame, out.reframe};
        return current_loop(d, s, ic, &r);
    }
    rc = (d->ctrl->outputs == MC_DRIVE_OUT_PWM2)
             ? mc_hal_pwm2_set_duty(d->hal->pwm2, out.duty2_a, out.duty2_b)
             : mc_hal_pwm3_set_duty(d->hal->pwm3, out.duty_a, out.duty_b, out.duty_c);
    return (rc != 0) ? MC_DRIVE_FAULT_PWM : 0u;
}

/* STOPPING from CURRENT mode (mc_drive.h, Modes): the speed ramp to 0 and
 * its P loop write the q current reference of the current loop. */
static uint32_t stop_current_step(mc_drive_t *d, const mc_hal_adc_sample_t *s, float ic)
{
    const float step = d->cfg.stop_decel_rad_s2 * d->cfg.foc.dt_s;
    const float w = d->stop_omega_ref_rad_s;
    d->stop_omega_ref_rad_s = (w > step) ? (w - step) : ((w < -step) ? (w + step) : 0.0f);
    const float wr = d->stop_omega_ref_rad_s;
    const float ff =
        (wr > 0.0f) ? -d->cfg.stop_iq_ff_a : ((wr < 0.0f) ? d->cfg.stop_iq_ff_a : 0.0f);
    float iq = (d->cfg.stop_kp_a_s_rad * (wr - d->enc_trk.omega_rad_s)) + ff;
    const float lim = d->cfg.i_max_a;
    iq = (iq > lim) ? lim : ((iq < -lim) ? -lim : iq);
    d->id_ref_a = 0.0f;
    d->iq_ref_a = iq;
    {
        const cur_req_t r = {
            0.0f, iq,   d->tm.theta_e_rad, d->enc_trk.omega_rad_s * (float)d->cfg.pole_pairs,
            true, false};
        return current_loop(d, s, ic, &r);
    }
}

/* Begin a controlled stop (or open the bridge at once when none is possible). */
static void begin_stop(mc_drive_t *d, uint32_t cause)
{
    if (d->mode != MC_DRIVE_MODE_CURRENT && d->mode != MC_DRIVE_MODE_CTRL) {
        return; /* IDLE, FAULT, or already stopping */
    }
    d->stop_cause = cause;
    const bool ctrl = (d->mode == MC_DRIVE_MODE_CTRL);
    /* a speed law stops on its shaped reference, whose present value is the
     * speed when there is no encoder to tell it */
    const bool shaped = ctrl && d->ctrl->uses_speed_ref;
    const float w_enc = mc_abs_f32(d->enc_trk.omega_rad_s);
    const float w_ref = mc_abs_f32(d->speed_ref_rad_s);
    const float w0 = (shaped && (w_ref > w_enc)) ? w_ref : w_enc;
    bool ok = d->cfg.stop_decel_rad_s2 > 0.0f;
    if (ok && ctrl && !shaped) {
        ok = (d->ctrl->stop != NULL) &&
             (d->ctrl->stop(d->ctrl->ctx, d->cfg.stop_decel_rad_s2) == 0u);
    }
    if (ok && !ctrl) {
        ok = d->hal->encoder != NULL && d->enc_trk.primed;
    }
    if (!ok) {
        outputs_off(d);
        d->id_ref_a = 0.0f;
        d->iq_ref_a = 0.0f;
        d->mode = MC_DRIVE_MODE_IDLE;
        return;
    }
    d->stop_from_ctrl = ctrl;
    d->stop_dir = 0.0f;
    if ((d->hal->encoder != NULL) && d->enc_trk.primed && (w_enc > d->cfg.stop_rest_rad_s)) {
        d->stop_dir = (d->enc_trk.omega_rad_s > 0.0f) ? 1.0f : -1.0f;
    }
    d->stop_omega_ref_rad_s = d->enc_trk.omega_rad_s;
    d->stop_time_s = 0.0f;
    d->stop_time_max_s = (2.0f * w0 / d->cfg.stop_decel_rad_s2) + 0.1f;
    d->mode = MC_DRIVE_MODE_STOPPING;
}

int mc_drive_stop(mc_drive_t *d)
{
    begin_stop(d, MC_DRIVE_STOP_CMD);
    return 0;
}

/* The temperatures, true when every sensor the board has gave a reading
 * (a board without any gives none: false). An absent sensor's value reads
 * as 0 degC, so it never trips or warns. */
static bool read_temps(const mc_drive_t *d, mc_hal_adc_temp_t *t)
{
    if (mc_hal_adc_read_temp(d->hal->adc, t) != 0) {
        return false;
    }
    const uint32_t fitted = MC_HAL_ADC_TEMP_VALID_ALL & ~t->absent_mask;
    if ((fitted & MC_HAL_ADC_TEMP_VALID_POWER_STAGE) == 0u) {
        t->power_stage_temp_c = 0.0f;
    }
    if ((fitted & MC_HAL_ADC_TEMP_VALID_MOTOR) == 0u) {
        t->motor_temp_c = 0.0f;
    }
    return (fitted != 0u) && ((t->valid_mask & fitted) == fitted);
}

/* The thermal derating's slow step (mc_drive_thermal.h): each fitted
 * sensor's reading, the square of the measured current while the bridge
 * is driven. */
static void thermal_slow(mc_drive_t *d, float slow_dt)
{
    const mc_drive_thermal_cfg_t *c = &d->cfg.thermal;
    if (!(c->fet_end_c > 0.0f) && !(c->motor_end_c > 0.0f) && !c->model_enable) {
        return; /* nothing to derate by: k stays 1 */
    }
    mc_hal_adc_temp_t t = {0};
    mc_drive_thermal_in_t in = {0.0f, 0.0f, false, false};
    if (mc_hal_adc_read_temp(d->hal->adc, &t) == 0) {
        const uint32_t ok = t.valid_mask & ~t.absent_mask;
        in.fet_c = t.power_stage_temp_c;
        in.motor_c = t.motor_temp_c;
        in.fet_ok = (ok & MC_HAL_ADC_TEMP_VALID_POWER_STAGE) != 0u;
        in.motor_ok = (ok & MC_HAL_ADC_TEMP_VALID_MOTOR) != 0u;
    }
    const bool on = d->mode == MC_DRIVE_MODE_CURRENT || d->mode == MC_DRIVE_MODE_CTRL ||
                    d->mode == MC_DRIVE_MODE_STOPPING;
    const float isq =
        on ? (d->tm.foc.id_a * d->tm.foc.id_a) + (d->tm.foc.iq_a * d->tm.foc.iq_a) : 0.0f;
    (void)mc_drive_thermal_step(&d->thermal, slow_dt, isq, &in);
    if (c->model_enable && c->r_follow) {
        /* ki = R bw at the winding estimate (a scale in copper's range:
         * mc_drive_thermal_r_scale of a finite estimate; refused, ki stays) */
        (void)mc_foc_f32_set_r_scale(&d->foc, mc_drive_thermal_r_scale(&d->thermal));
        if (d->hallobs != NULL) {
            /* the observer's R as the sensorless law's (refused: R stays) */
            (void)mc_drive_hallobs_set_r_scale(d->hallobs, mc_drive_thermal_r_scale(&d->thermal));
        }
    }
}

/* The end of a controlled stop: the bridge opens, IDLE. */
static void stop_end(mc_drive_t *d)
{
    outputs_off(d);
    d->id_ref_a = 0.0f;
    d->iq_ref_a = 0.0f;
    d->mode = MC_DRIVE_MODE_IDLE;
}

/* Fast-step part of the controlled stop: the encoder speed crossed zero
 * against the direction the stop began in, so the rotor has just been at
 * rest; braking on would drive it backwards (mc_drive.h, STOPPING). */
static bool stop_reversed(const mc_drive_t *d, bool have_enc)
{
    return have_enc && (d->mode == MC_DRIVE_MODE_STOPPING) &&
           ((d->enc_trk.omega_rad_s * d->stop_dir) < 0.0f);
}

/* Slow-loop part of the controlled stop: warnings start one, standstill
 * (or its time limit) ends it. */
static void stop_supervise(mc_drive_t *d, float slow_dt, const mc_hal_adc_temp_t *t, bool t_ok)
{
    uint32_t w = 0u;
    if (d->cfg.temp_warn_c > 0.0f && t_ok &&
        (t->power_stage_temp_c > d->cfg.temp_warn_c || t->motor_temp_c > d->cfg.temp_warn_c)) {
        w |= MC_DRIVE_WARN_TEMP;
    }
    if (d->cfg.vbus_sag_v > 0.0f && d->tm.vbus_v < d->cfg.vbus_sag_v &&
        d->mode != MC_DRIVE_MODE_IDLE && d->mode != MC_DRIVE_MODE_FAULT) {
        w |= MC_DRIVE_WARN_VBUS_SAG;
    }
    if (w != 0u) {
        d->warnings |= w;
        begin_stop(d, MC_DRIVE_STOP_WARNING);
    }
    if (d->mode != MC_DRIVE_MODE_STOPPING) {
        return;
    }
    d->stop_time_s += slow_dt;
    /* a speed law's ramp is the drive's shaped reference; another law's
     * stop is its own */
    const bool ramp_done = d->stop_from_ctrl
                               ? (!d->ctrl->uses_speed_ref || d->speed_ref_rad_s == 0.0f)
                               : (d->stop_omega_ref_rad_s == 0.0f);
    if ((ramp_done && mc_abs_f32(d->enc_trk.omega_rad_s) <= d->cfg.stop_rest_rad_s) ||
        d->stop_time_s > d->stop_time_max_s) {
        stop_end(d);
    }
}

/* The record handed to a law, filled field by field in the drive's own
 * instance: a record initialised on the stack each step costs a zeroing
 * of the whole struct first (a memset call, about 50 instructions on the
 * M4F, tools/bench/run_isr_profile.py). Every field is written here or in
 * run_ctrl (the shaped speed reference). */
static void fill_meas(mc_drive_t *d, const mc_hal_adc_sample_t *s, float ic, bool have_enc,
                      const mc_hal_encoder_sample_t *enc, float iq_applied_prev)
{
    mc_drive_meas_t *m = &d->meas;
    m->ia_a = s->ia_a;
    m->ib_a = s->ib_a;
    m->ic_a = ic;
    m->vbus_v = s->vbus_v;
    m->have_encoder = have_enc;
    m->theta_m_rad = d->tm.theta_m_rad;
    m->theta_e_rad = d->tm.theta_e_rad;
    m->omega_m_rad_s = d->enc_trk.omega_rad_s;
    m->enc_count = d->enc_count;
    m->enc_raw_count = enc->count;
    m->enc_cpr = enc->counts_per_rev;
    m->dt_s = d->cfg.foc.dt_s;
    m->fast_count = d->fast_count;
    m->have_speed_ref = false;
    m->omega_ref_rad_s = 0.0f;
    m->alpha_ref_rad_s2 = 0.0f;
    m->i_max_a = mc_drive_thermal_limit_a(&d->thermal, d->cfg.i_max_a);
    m->iq_applied_a = iq_applied_prev;
    m->regen_scale = d->tm.regen_scale;
    m->v_alpha_prev_v = d->v_ab_prev_v[0];
    m->v_beta_prev_v = d->v_ab_prev_v[1];
}

/* Hall + observer (mc_drive_hallobs.h): in a step in which the current
 * loop drives the bridge, the angle every sensored path uses is the blend;
 * otherwise the observer waits for the next such step, which starts it
 * from the Hall angle. ok: the sample and the encoder are valid, no fault. */
static void hallobs_angle(mc_drive_t *d, bool ok, const mc_hal_adc_sample_t *s)
{
    const mc_drive_mode_t md = d->mode;
    const bool law_loop =
        (d->ctrl != NULL) && (d->ctrl->outputs == MC_DRIVE_OUT_CURRENT) && !d->ctrl->finds_angle;
    const bool loop = (md == MC_DRIVE_MODE_CURRENT) ||
                      ((md == MC_DRIVE_MODE_STOPPING) && (!d->stop_from_ctrl || law_loop)) ||
                      ((md == MC_DRIVE_MODE_CTRL) && law_loop);
    if (!ok || !loop) {
        mc_drive_hallobs_stop(d->hallobs);
        return;
    }
    const mc_drive_hallobs_in_t in = {
        s->ia_a,           s->ib_a,           d->v_ab_prev_v[0],
        d->v_ab_prev_v[1], d->tm.theta_e_rad, d->enc_trk.omega_rad_s * (float)d->cfg.pole_pairs};
    d->tm.theta_e_rad = mc_drive_hallobs_step(d->hallobs, &in);
}

bool mc_drive_fast_step(mc_drive_t *d)
{
    uint32_t f = 0u;
    mc_hal_adc_sample_t s;
    float ic = 0.0f;
    const int arc = mc_hal_adc_read(d->hal->adc, &s);
    if (arc == 0) {
        /* Sensor offsets (commissioning measures them) before any check. */
        s.ia_a -= d->cfg.i_offset_a[0];
        s.ib_a -= d->cfg.i_offset_a[1];
        if ((s.valid_mask & MC_HAL_ADC_VALID_IC) != 0u) {
            s.ic_a -= d->cfg.i_offset_a[2];
        }
    }
    if (arc != 0) {
        f |= MC_DRIVE_FAULT_ADC; /* -EAGAIN here means a stale sample */
    } else {
        f |= check_sample(d, &s, &ic);
        d->tm.ia_a = s.ia_a;
        d->tm.ib_a = s.ib_a;
        d->tm.ic_a = ic;
        d->tm.vbus_v = s.vbus_v;
        if (mc_isfinite_f32(s.vbus_v)) {
            regen_track(d, s.vbus_v);
            f |= brake_step(d, s.vbus_v);
        }
    }

    mc_hal_encoder_sample_t enc = {0u, 0u, 0u, 0u};
    bool have_enc = false;
    if (d->hal->encoder != NULL) {
        const int erc = mc_hal_encoder_read(d->hal->encoder, &enc);
        if (erc != 0 || (enc.flags & MC_HAL_ENCODER_FLAG_VALID) == 0u || enc.counts_per_rev == 0u) {
            f |= MC_DRIVE_FAULT_ENCODER;
        } else {
            enc_constants(d, enc.counts_per_rev);
            index_rebase(d, &enc);
            f |= encoder_jump_fault(d, &enc);
            update_position(d, &enc);
            have_enc = true;
            if (d->cfg.omega_max_rad_s > 0.0f &&
                mc_abs_f32(d->enc_trk.omega_rad_s) > d->cfg.omega_max_rad_s) {
                f |= MC_DRIVE_FAULT_OVERSPEED;
            }
        }
    }

    if (d->hallobs != NULL) {
        hallobs_angle(d, (arc == 0) && have_enc && (f == 0u), &s);
    }
    if (stop_reversed(d, have_enc)) {
        stop_end(d);
    }
    /* the current loop's last reference, for a law's anti-windup */
    const float iq_applied_prev = d->tm.iq_ref_a;
    d->tm.id_ref_a = d->id_ref_a;
    d->tm.iq_ref_a = d->iq_ref_a;
    if (f == 0u && d->mode == MC_DRIVE_MODE_CURRENT) {
        const cur_req_t r = {d->id_ref_a,
                             d->iq_ref_a,
                             d->tm.theta_e_rad,
                             d->enc_trk.omega_rad_s * (float)d->cfg.pole_pairs,
                             true,
                             false};
        f |= current_loop(d, &s, ic, &r);
    } else if (f == 0u && d->mode == MC_DRIVE_MODE_STOPPING && !d->stop_from_ctrl) {
        f |= stop_current_step(d, &s, ic);
    } else if (f == 0u && (d->mode == MC_DRIVE_MODE_CTRL || d->mode == MC_DRIVE_MODE_STOPPING)) {
        fill_meas(d, &s, ic, have_enc, &enc, iq_applied_prev);
        f |= run_ctrl(d, &d->meas, &s, ic);
    }
    /* Control deadline: the new duties must be written within one period of
     * the ADC trigger, or the bridge runs on stale ones. */
    if (arc == 0 && d->deadline_ticks != 0u && d->mode != MC_DRIVE_MODE_IDLE) {
        const uint32_t now = now_ticks(d);
        if (mc_hal_tick_elapsed(now, s.timestamp_ticks) > d->deadline_ticks) {
            f |= MC_DRIVE_FAULT_OVERRUN;
        }
    }
    raise_fault(d, f);
    if (d->asc_active && have_enc && !asc_emf_above(d, MC_DRIVE_ASC_EXIT_FRAC)) {
        outputs_off(d); /* slow enough: opening no longer pumps the bus */
        d->asc_active = false;
    }

    d->fast_count++;
    d->slow_phase++;
    if (d->slow_phase >= d->cfg.slow_loop_div) {
        d->slow_phase = 0u;
        return true;
    }
    return false;
}

/* The law's slow step while it runs: the phase resistance of the winding
 * estimate first (winding_r_follow; off the fast step, the estimate moves
 * in seconds), then the law's own. */
static void ctrl_slow(mc_drive_t *d)
{
    if (d->mode != MC_DRIVE_MODE_CTRL &&
        !(d->mode == MC_DRIVE_MODE_STOPPING && d->stop_from_ctrl)) {
        return;
    }
    uint32_t cerr = 0u;
    if (d->cfg.thermal.model_enable && d->cfg.thermal.r_follow && d->ctrl->set_r_scale != NULL) {
        cerr = d->ctrl->set_r_scale(d->ctrl->ctx, mc_drive_thermal_r_scale(&d->thermal));
    }
    if (cerr == 0u && d->ctrl->slow != NULL) {
        cerr = d->ctrl->slow(d->ctrl->ctx);
    }
    if (cerr != 0u) {
        d->tm.ctrl_err = cerr;
        raise_fault(d, MC_DRIVE_FAULT_CONTROL);
    }
}

void mc_drive_slow_step(mc_drive_t *d)
{
    const float slow_dt = d->cfg.foc.dt_s * (float)d->cfg.slow_loop_div;
    mc_hal_adc_temp_t t = {0};
    bool t_ok = false;
    thermal_slow(d, slow_dt);
    if (d->cfg.temp_warn_c > 0.0f || d->cfg.temp_max_c > 0.0f) {
        t_ok = read_temps(d, &t);
    }
    if (d->cfg.temp_max_c > 0.0f) {
        /* A sensor without a reading for longer than the grace counts as too
         * hot: the limit cannot be enforced without it. */
        if (t_ok) {
            d->temp_invalid_steps = 0u;
        } else if (d->temp_invalid_steps <= MC_DRIVE_TEMP_INVALID_STEPS) {
            d->temp_invalid_steps++; /* saturates one past the grace */
        }
        if (d->temp_invalid_steps > MC_DRIVE_TEMP_INVALID_STEPS ||
            (t_ok && (!(t.power_stage_temp_c <= d->cfg.temp_max_c) ||
                      !(t.motor_temp_c <= d->cfg.temp_max_c)))) {
            raise_fault(d, MC_DRIVE_FAULT_OVERTEMP);
        }
    }
    /* the stall check where the drive's current loop runs on the encoder */
    const bool current_ctrl = d->mode == MC_DRIVE_MODE_CURRENT ||
                              (d->mode == MC_DRIVE_MODE_CTRL &&
                               d->ctrl->outputs == MC_DRIVE_OUT_CURRENT && d->hal->encoder != NULL);
    if (current_ctrl && d->cfg.stall_time_s > 0.0f) {
        const bool stalled =
            mc_abs_f32(d->tm.foc.iq_a) >= d->cfg.stall_current_frac * d->cfg.i_max_a &&
            mc_abs_f32(d->enc_trk.omega_rad_s) < d->cfg.stall_speed_rad_s;
        d->stall_time_acc_s = stalled ? d->stall_time_acc_s + slow_dt : 0.0f;
        if (d->stall_time_acc_s > d->cfg.stall_time_s) {
            raise_fault(d, MC_DRIVE_FAULT_STALL);
        }
    } else {
        d->stall_time_acc_s = 0.0f;
    }
    stop_supervise(d, slow_dt, &t, t_ok);
    ctrl_slow(d);
    if (d->hal->fault != NULL) {
        mc_hal_fault_status_t fs;
        /* A fault status that cannot be read is treated as a fault: the
         * drive must not run without its hardware protection supervised. */
        if (mc_hal_fault_read(d->hal->fault, &fs) != 0 || fs.active_mask != 0u || fs.gate_killed) {
            raise_fault(d, MC_DRIVE_FAULT_HW_INPUT);
        }
    }
}

/* The duties the bridge starts with when the drive's current loop takes
 * over (CURRENT mode, a law giving current references): the back-EMF of the
 * encoder's speed, omega_e flux along q, at the angle the rotor has in the
 * middle of the next period (the duties written now act then), so that a
 * rotor turning at enable sees no current step. At the enable the bridge
 * closes within the period (the slow loop runs after the fast step) and the
 * fast step's own duties act only from the period after the next: with the
 * zero vector instead, a rotor coasting at speed would drive its back-EMF
 * into the short for that period (9 A in 200 us on the paper-002 motor at
 * 118 rad/s, 5 kHz). Without a primed encoder: the zero vector. */
static void start_duties(const mc_drive_t *d, float duty[3])
{
    duty[0] = 0.5f;
    duty[1] = 0.5f;
    duty[2] = 0.5f;
    if ((d->hal->encoder != NULL) && d->enc_trk.primed && (d->tm.vbus_v > 0.0f)) {
        const float w_e = d->enc_trk.omega_rad_s * (float)d->cfg.pole_pairs;
        const float th = mc_wrap_2pi_f32(d->tm.theta_e_rad + (1.5f * w_e * d->cfg.foc.dt_s));
        float sn;
        float cs;
        float va;
        float vb;
        mc_sincos_f32(th, &sn, &cs);
        mc_inv_park_f32(0.0f, w_e * d->cfg.foc.flux_wb, sn, cs, &va, &vb);
        (void)mc_svpwm_f32(va, vb, d->tm.vbus_v, d->cfg.foc.limit_mode, &duty[0], &duty[1],
                           &duty[2]);
    }
}

/* The law's bridge at its start (zero output, or the back-EMF's vector for
 * the drive's current loop), then close the switches. */
static int enable_ctrl_bridge(mc_drive_t *d)
{
    int rc;
    if (d->ctrl->outputs == MC_DRIVE_OUT_PWM2) {
        rc = mc_hal_pwm2_set_duty(d->hal->pwm2, 0.0f, 0.0f);
        if (rc == 0) {
            rc = mc_hal_pwm2_enable(d->hal->pwm2);
        }
    } else {
        float duty[3] = {0.5f, 0.5f, 0.5f};
        if (d->ctrl->outputs == MC_DRIVE_OUT_CURRENT) {
            start_duties(d, duty);
        }
        rc = mc_hal_pwm3_set_duty(d->hal->pwm3, duty[0], duty[1], duty[2]);
        if (rc == 0) {
            rc = mc_hal_pwm3_enable(d->hal->pwm3);
        }
    }
    if (rc != 0) {
        outputs_off(d);
        return -EBUSY;
    }
    d->mode = MC_DRIVE_MODE_CTRL;
    return 0;
}

uint32_t mc_drive_angle_state(const mc_drive_t *d)
{
    if ((d->cfg.angle_ref == MC_DRIVE_ANGLE_REF_INDEX) && !d->index_seen) {
        return MC_DRIVE_ANGLE_NEED_INDEX;
    }
    if ((d->cfg.angle_ref == MC_DRIVE_ANGLE_REF_ALIGN) && !d->aligned) {
        return MC_DRIVE_ANGLE_NEED_ALIGN;
    }
    return MC_DRIVE_ANGLE_KNOWN;
}

int mc_drive_set_encoder_offset(mc_drive_t *d, float offset_e_rad)
{
    if (!mc_isfinite_f32(offset_e_rad) || (offset_e_rad < 0.0f) ||
        !(offset_e_rad < MC_TWO_PI_F32)) {
        return -EINVAL;
    }
    if ((d->mode == MC_DRIVE_MODE_CURRENT) || (d->mode == MC_DRIVE_MODE_STOPPING)) {
        return -EBUSY;
    }
    d->cfg.encoder_offset_rad = offset_e_rad;
    d->aligned = true;
    return 0;
}

int mc_drive_attach_hallobs(mc_drive_t *d, mc_drive_hallobs_t *h)
{
    if (d->mode != MC_DRIVE_MODE_IDLE && d->mode != MC_DRIVE_MODE_FAULT) {
        return -EBUSY;
    }
    if ((h != NULL) && (d->hal->encoder == NULL)) {
        return -ENODEV;
    }
    if (h != NULL) {
        mc_drive_hallobs_stop(h);
    }
    d->hallobs = h;
    return 0;
}

int mc_drive_attach_cog(mc_drive_t *d, const mc_cog_map_t *map)
{
    if ((map != NULL) && (d->hal->encoder == NULL)) {
        return -ENODEV;
    }
    if ((map != NULL) && ((map != d->cog_ser_map) || (map->crc != d->cog_ser_crc))) {
        /* the fast step interrupts this context: it sees no map while the
         * series changes (the fences keep the stores in this order) */
        d->cog = NULL;
        atomic_signal_fence(memory_order_seq_cst);
        mc_cog_series_init(&d->cog_ser, map);
        d->cog_ord_rms = mc_cog_map_order_rms(map);
        d->cog_ser_map = map;
        d->cog_ser_crc = map->crc;
        atomic_signal_fence(memory_order_seq_cst);
    }
    d->cog = map;
    return 0;
}

int mc_drive_attach_ctrl(mc_drive_t *d, const mc_drive_ctrl_t *ctrl)
{
    if (d->mode != MC_DRIVE_MODE_IDLE && d->mode != MC_DRIVE_MODE_FAULT) {
        return -EBUSY;
    }
    if (ctrl != NULL) {
        if (ctrl->fast == NULL ||
            (ctrl->outputs != MC_DRIVE_OUT_PWM3 && ctrl->outputs != MC_DRIVE_OUT_PWM2 &&
             ctrl->outputs != MC_DRIVE_OUT_CURRENT)) {
            return -EINVAL;
        }
        const bool bridge =
            (ctrl->outputs == MC_DRIVE_OUT_PWM2) ? (d->hal->pwm2 != NULL) : (d->hal->pwm3 != NULL);
        if (ctrl->outputs == MC_DRIVE_OUT_CURRENT && d->hal->pwm3 == NULL) {
            return -ENODEV;
        }
        if (!bridge || (ctrl->needs_encoder && d->hal->encoder == NULL)) {
            return -ENODEV;
        }
    }
    d->ctrl = ctrl;
    return 0;
}

int mc_drive_set_mode(mc_drive_t *d, mc_drive_mode_t mode)
{
    switch (mode) {
    case MC_DRIVE_MODE_IDLE:
        if (d->asc_active) {
            return 0; /* FAULT with the phases shorted: the fault reaction keeps them */
        }
        outputs_off(d);
        d->id_ref_a = 0.0f;
        d->iq_ref_a = 0.0f;
        if (d->mode != MC_DRIVE_MODE_FAULT) {
            d->mode = MC_DRIVE_MODE_IDLE;
        }
        return 0;
    case MC_DRIVE_MODE_CURRENT:
        if (d->mode == MC_DRIVE_MODE_FAULT || d->faults != 0u || d->warnings != 0u) {
            return -EBUSY;
        }
        if (d->mode == MC_DRIVE_MODE_CURRENT) {
            return 0;
        }
        if (d->mode != MC_DRIVE_MODE_IDLE) {
            return -EBUSY;
        }
        if (d->hal->pwm3 == NULL || d->hal->encoder == NULL) {
            return -ENODEV;
        }
        if (mc_drive_angle_state(d) != MC_DRIVE_ANGLE_KNOWN) {
            return -EACCES;
        }
        mc_foc_f32_reset(&d->foc);
        if (d->cfg.fw_enable) {
            (void)mc_fw_f32_reset(&d->fw);
            d->tm.foc.vd_v = 0.0f; /* the FW loop's first voltage */
            d->tm.foc.vq_v = 0.0f;
        }
        d->open_phase_count[0] = d->open_phase_count[1] = d->open_phase_count[2] = 0u;
        d->v_ab_prev_v[0] = 0.0f;
        d->v_ab_prev_v[1] = 0.0f;
        /* The back-EMF's vector first (zero at standstill), then close the
         * switches. */
        float duty[3];
        start_duties(d, duty);
        if (mc_hal_pwm3_set_duty(d->hal->pwm3, duty[0], duty[1], duty[2]) != 0 ||
            mc_hal_pwm3_enable(d->hal->pwm3) != 0) {
            outputs_off(d);
            return -EBUSY;
        }
        d->mode = MC_DRIVE_MODE_CURRENT;
        return 0;
    case MC_DRIVE_MODE_CTRL:
        if (d->mode == MC_DRIVE_MODE_FAULT || d->faults != 0u || d->warnings != 0u) {
            return -EBUSY;
        }
        if (d->mode == MC_DRIVE_MODE_CTRL) {
            return 0;
        }
        if (d->mode != MC_DRIVE_MODE_IDLE) {
            return -EBUSY;
        }
        if (d->ctrl == NULL) {
            return -ENODEV;
        }
        if (d->ctrl->needs_encoder && !d->ctrl->finds_angle &&
            (mc_drive_angle_state(d) != MC_DRIVE_ANGLE_KNOWN)) {
            return -EACCES;
        }
        if (d->ctrl->reset != NULL && d->ctrl->reset(d->ctrl->ctx) != 0u) {
            return -EINVAL;
        }
        /* a speed law starts on its target (set from the present speed by
         * the caller), the current loop from zero */
        d->speed_ref_rad_s = d->speed_target_rad_s;
        d->speed_alpha_rad_s2 = 0.0f;
        d->v_ab_prev_v[0] = 0.0f;
        d->v_ab_prev_v[1] = 0.0f;
        d->tm.regen_scale = 1.0f;
        if (d->ctrl->outputs == MC_DRIVE_OUT_CURRENT) {
            mc_foc_f32_reset(&d->foc);
            if (d->cfg.fw_enable) {
                (void)mc_fw_f32_reset(&d->fw);
                d->tm.foc.vd_v = 0.0f;
                d->tm.foc.vq_v = 0.0f;
            }
            d->open_phase_count[0] = d->open_phase_count[1] = d->open_phase_count[2] = 0u;
        }
        return enable_ctrl_bridge(d);
    case MC_DRIVE_MODE_STOPPING:
        return mc_drive_stop(d);
    case MC_DRIVE_MODE_FAULT:
    default:
        return -EINVAL;
    }
}

int mc_drive_set_speed_ref(mc_drive_t *d, float omega_m_rad_s)
{
    if (!mc_isfinite_f32(omega_m_rad_s)) {
        return -EINVAL;
    }
    d->speed_target_rad_s = omega_m_rad_s;
    if (d->mode != MC_DRIVE_MODE_CTRL && d->mode != MC_DRIVE_MODE_STOPPING) {
        d->speed_ref_rad_s = omega_m_rad_s; /* the next enable starts there */
    }
    return 0;
}

int mc_drive_set_current_ref(mc_drive_t *d, float id_ref_a, float iq_ref_a)
{
    if (!mc_isfinite_f32(id_ref_a) || !mc_isfinite_f32(iq_ref_a) ||
        mc_abs_f32(id_ref_a) > d->cfg.i_max_a || mc_abs_f32(iq_ref_a) > d->cfg.i_max_a) {
        return -EINVAL;
    }
    d->id_ref_a = id_ref_a;
    d->iq_ref_a = iq_ref_a;
    return 0;
}

void mc_drive_set_runtime_limits(mc_drive_t *d, const mc_drive_cfg_t *cfg)
{
    d->cfg.i_max_a = cfg->i_max_a;
    d->cfg.anticogging = cfg->anticogging;
    d->cfg.i_trip_a = cfg->i_trip_a;
    d->cfg.vbus_min_v = cfg->vbus_min_v;
    d->cfg.vbus_max_v = cfg->vbus_max_v;
    d->cfg.omega_max_rad_s = cfg->omega_max_rad_s;
    d->enc_cpr_cached = 0u; /* the encoder-jump threshold follows omega_max */
    d->cfg.temp_max_c = cfg->temp_max_c;
    d->cfg.stall_current_frac = cfg->stall_current_frac;
    d->cfg.stall_speed_rad_s = cfg->stall_speed_rad_s;
    d->cfg.stall_time_s = cfg->stall_time_s;
    d->cfg.i_unbalance_max_a = cfg->i_unbalance_max_a;
    d->cfg.temp_warn_c = cfg->temp_warn_c;
    d->cfg.vbus_sag_v = cfg->vbus_sag_v;
    d->cfg.stop_decel_rad_s2 = cfg->stop_decel_rad_s2;
    d->cfg.stop_iq_ff_a = cfg->stop_iq_ff_a;
    d->cfg.speed_accel_rad_s2 = cfg->speed_accel_rad_s2;
    d->cfg.vbus_regen_start_v = cfg->vbus_regen_start_v;
    d->cfg.vbus_regen_end_v = cfg->vbus_regen_end_v;
    d->cfg.regen_id_a = cfg->regen_id_a;
    d->cfg.bus = cfg->bus;
    d->bus_on = mc_drive_bus_any(&cfg->bus);
    if (!d->bus_on) {
        mc_drive_bus_off(&d->bus);
    }
    d->cfg.brake_on_v = cfg->brake_on_v;
    d->cfg.brake_full_v = cfg->brake_full_v;
    d->id_ref_a = mc_sat_f32(d->id_ref_a, -cfg->i_max_a, cfg->i_max_a);
    d->iq_ref_a = mc_sat_f32(d->iq_ref_a, -cfg->i_max_a, cfg->i_max_a);
}

float mc_drive_bus_current_a(const mc_drive_t *d)
{
    return mc_drive_bus_estimate_a(d->tm.foc.vd_v, d->tm.foc.vq_v, d->tm.foc.id_a, d->tm.foc.iq_a,
                                   d->tm.vbus_v);
}

void mc_drive_raise_fault(mc_drive_t *d, uint32_t bits)
{
    raise_fault(d, bits & MC_DRIVE_FAULT_EXTERNAL);
}

void mc_drive_warning_cause(mc_drive_t *d, uint32_t bits, bool present)
{
    const uint32_t w = bits & MC_DRIVE_WARN_CAN_BUS;
    if (!present) {
        d->warn_causes &= ~w;
        return;
    }
    if (w == 0u) {
        return;
    }
    d->warn_causes |= w;
    d->warnings |= w;
    begin_stop(d, MC_DRIVE_STOP_WARNING);
}

int mc_drive_clear_faults(mc_drive_t *d)
{
    if (d->hal->fault != NULL) {
        /* zeroed: the images' link-time optimisation may fold the read's
         * wrapper with a const-argument one and then warns (-Wmaybe-
         * uninitialized) that fs goes in unset */
        mc_hal_fault_status_t fs = {0};
        if (mc_hal_fault_read(d->hal->fault, &fs) != 0 || fs.active_mask != 0u) {
            return -EBUSY;
        }
        if (fs.gate_killed && mc_hal_fault_gate_release(d->hal->fault) != 0) {
            return -EBUSY;
        }
    }
    const float v = d->tm.vbus_v;
    if (!(v >= d->cfg.vbus_min_v && v <= d->cfg.vbus_max_v) || d->warn_causes != 0u) {
        return -EBUSY;
    }
    if (d->asc_active) {
        outputs_off(d); /* ends the active short circuit */
        d->asc_active = false;
    }
    d->faults = 0u;
    d->warnings = 0u;
    d->first_fault = 0u;
    d->open_phase_mask = 0u;
    d->id_ref_a = 0.0f;
    d->iq_ref_a = 0.0f;
    d->foc_err = MC_FOC_ERR_NONE;
    mc_foc_f32_reset(&d->foc);
    d->mode = MC_DRIVE_MODE_IDLE;
    return 0;
}
