/**
 * @file mc_ctrl_sensorless_q31.c
 * @brief Sensorless FOC speed control with I-f start-up, q31 kernels
 *        (see mc_ctrl_sensorless_q31.h; the law and its reasons are in
 *        mc_ctrl_sensorless.{h,c}, which this file follows step by step).
 */
#include "mc_ctrl_sensorless_q31.h"

#include <stddef.h>

#include "math/mc_math.h"
#include "transforms/mc_transforms.h"

#define SLSQ_QUARTER_TURN ((q31_t)0x40000000) /* pi/2 as a q31 turn */

static bool slsq_pos(float x)
{
    return (x > 0.0f) && mc_isfinite_f32(x);
}

/* float (init only) to q31 per unit of base */
static q31_t slsq_q(float v, float base)
{
    return mc_q31_from_f32(v / base);
}

static uint32_t slsq_steps(float t_s, float dt_s)
{
    const float n = (t_s / dt_s) + 0.5f;
    return (n >= 4.0e9f) ? 4000000000u : (uint32_t)n;
}

/* uint32 to int32 two's complement without implementation-defined casts */
static q31_t slsq_i32(uint32_t u)
{
    if (u <= 0x7FFFFFFFu) {
        return (q31_t)u;
    }
    return -(q31_t)(~u) - 1;
}

/* a - b of two q31 turns, wrapped modulo one turn */
static q31_t slsq_ang_sub(q31_t a, q31_t b)
{
    return slsq_i32((uint32_t)a - (uint32_t)b);
}

/* Move x towards target by at most step (>= 0), saturating. */
static q31_t slsq_slew(q31_t x, q31_t target, q31_t step)
{
    const int64_t up = (int64_t)x + (int64_t)step;
    const int64_t dn = (int64_t)x - (int64_t)step;

    if ((int64_t)target > up) {
        return mc_q31_sat64(up);
    }
    if ((int64_t)target < dn) {
        return mc_q31_sat64(dn);
    }
    return target;
}

/* (a + b) / 2, rounded down */
static q31_t slsq_avg(q31_t a, q31_t b)
{
    return (q31_t)mc_q46_asr((int64_t)a + (int64_t)b, 1u);
}

uint32_t mc_ctrl_sls_q31_init(mc_ctrl_sls_q31_t *c, const mc_ctrl_sls_q31_cfg_t *cfg)
{
    mc_ctrl_sls_t ref; /* the f32 plug-in validates the config and derives gamma, kp, ki */
    mc_fluxobs_q31_cfg_t oc;
    mc_spdpll_q31_cfg_t pc;
    mc_foc_q31_cfg_t fc;
    mc_pi_f32_cfg_t sc;
    mc_pi_q31_cfg_t sq;
    mc_fluxobs_q31_t obs;
    mc_spdpll_q31_t pll;
    mc_foc_q31_t foc;
    mc_pi_q31_t spi;
    const mc_ctrl_sls_cfg_t *f;
    uint32_t err;
    uint32_t obs_err;
    float pp;
    float wbm;
    float kp_cur = 0.0f;
    float ki_cur = 0.0f;
    bool ok;
    bool band_on;
    mc_q46_gain_t g_dtheta;
    mc_q46_gain_t g_damp;
    mc_q46_gain_t g_kp_cur;
    mc_q46_gain_t g_dead_a;
    mc_q46_gain_t g_dead_b;
    mc_q46_gain_t g_inv_band;

    if ((c == NULL) || (cfg == NULL)) {
        return MC_CTRL_SLS_ERR_NULL;
    }
    f = &cfg->f;
    err = mc_ctrl_sls_init(&ref, f);
    if (f->dead_comp_duty || f->ref_from_drive) {
        /* the duty-side dead-time correction has no q31 version yet, and the
         * twin runs its own current loop and reference (a voltage-level law) */
        err |= MC_CTRL_SLS_ERR_TIMING;
    }
    if (f->align_any_angle) {
        /* the any-angle start (circle fit of the flux path) is f32 only */
        err |= MC_CTRL_SLS_ERR_STARTUP;
    }
    if (f->ld_minus_lq_h != 0.0f) {
        /* a salient machine needs MTPA's d current, which has no q31
         * version (fw/mc_fw.h is f32): the f32 plug-in runs it */
        err |= MC_CTRL_SLS_ERR_MOTOR;
    }
    if (!slsq_pos(cfg->i_base_a) || !slsq_pos(cfg->v_base_v) ||
        !slsq_pos(cfg->omega_base_e_rad_s) || !slsq_pos(cfg->flux_base_wb)) {
        return err | MC_CTRL_SLS_ERR_SCALE;
    }
    if (err != MC_CTRL_SLS_ERR_NONE) {
        return err;
    }
    pp = (float)f->pole_pairs;
    wbm = cfg->omega_base_e_rad_s / pp;
    if (!(cfg->v_base_v >= f->vbus_max_v) || !(cfg->i_base_a > (1.25f * f->iq_max_a)) ||
        !(cfg->i_base_a > f->if_current_a) ||
        !(cfg->omega_base_e_rad_s > (2.0f * f->speed_max_rad_s * pp))) {
        return MC_CTRL_SLS_ERR_SCALE;
    }

    /* the q31 kernels, from the same engineering configs as the f32 plug-in */
    oc.f = ref.obs.cfg;
    oc.i_base_a = cfg->i_base_a;
    oc.v_base_v = cfg->v_base_v;
    oc.flux_base_wb = cfg->flux_base_wb;
    obs_err = mc_fluxobs_q31_init(&obs, &oc);
    if (obs_err != MC_FLUXOBS_ERR_NONE) {
        err |= MC_CTRL_SLS_ERR_OBSERVER | MC_CTRL_SLS_ERR_SCALE;
    }
    pc.f.bw_rad_s = f->pll_bw_rad_s;
    pc.f.dt_s = f->dt_s;
    pc.f.omega_max_rad_s = 2.0f * f->speed_max_rad_s * pp;
    pc.omega_base_rad_s = cfg->omega_base_e_rad_s;
    if (mc_spdpll_q31_init(&pll, &pc) != MC_SPDPLL_ERR_NONE) {
        err |= MC_CTRL_SLS_ERR_PLL | MC_CTRL_SLS_ERR_SCALE;
    }
    /* the current loop (kp = L bw, ki = R bw: the f32 plug-in hands the
     * same references to the drive's loop of these gains) and the speed PI
     * exactly as mc_ctrl_sls_init forms it */
    (void)mc_foc_f32_gains_from_bandwidth(f->r_ohm, f->l_h, f->cur_bw_rad_s, &kp_cur, &ki_cur);
    fc.f.r_ohm = f->r_ohm;
    fc.f.ld_h = f->l_h;
    fc.f.lq_h = f->l_h;
    fc.f.flux_wb = f->flux_wb;
    fc.f.kp_d_v_per_a = kp_cur;
    fc.f.ki_d_v_per_as = ki_cur;
    fc.f.kp_q_v_per_a = kp_cur;
    fc.f.ki_q_v_per_as = ki_cur;
    fc.f.dt_s = f->dt_s;
    fc.f.aw = MC_PI_AW_CLAMP;
    fc.f.kaw_per_s = 0.0f;
    fc.f.limit_mode = MC_SVPWM_LIMIT_CIRCLE;
    fc.f.v_limit_ratio = f->v_limit_ratio;
    fc.f.v_abs_max_v = f->vbus_max_v;
    fc.f.decouple = true;
    fc.i_base_a = cfg->i_base_a;
    fc.v_base_v = cfg->v_base_v;
    fc.omega_base_rad_s = cfg->omega_base_e_rad_s;
    if (mc_foc_q31_init(&foc, &fc) != MC_FOC_ERR_NONE) {
        err |= MC_CTRL_SLS_ERR_CURRENT | MC_CTRL_SLS_ERR_SCALE;
    }
    sc.kp = f->speed_kp_a_s_rad;
    sc.ki_per_s = f->speed_ki_a_rad;
    sc.dt_s = f->dt_s * (float)f->speed_div;
    sc.out_min = -f->iq_max_a;
    sc.out_max = f->iq_max_a;
    sc.aw = MC_PI_AW_CLAMP;
    sc.kaw_per_s = 0.0f;
    if ((mc_pi_q31_cfg_from_f32(&sc, wbm, cfg->i_base_a, &sq) != MC_PI_ERR_NONE) ||
        (mc_pi_q31_init(&spi, &sq) != MC_PI_ERR_NONE)) {
        err |= MC_CTRL_SLS_ERR_SPEED | MC_CTRL_SLS_ERR_SCALE;
    }
    if (err != MC_CTRL_SLS_ERR_NONE) {
        return err;
    }
    /* gains of the plug-in's own q31 arithmetic */
    ok = mc_q46_gain_from_f32((cfg->omega_base_e_rad_s * f->dt_s) / MC_PI_F32, &g_dtheta) &&
         mc_q46_gain_from_f32((f->speed_kp_a_s_rad * wbm) / cfg->i_base_a, &g_damp) &&
         mc_q46_gain_from_f32((kp_cur * cfg->i_base_a) / cfg->v_base_v, &g_kp_cur) &&
         mc_q46_gain_from_f32((f->dead_time_s / f->dt_s) * (4.0f / 3.0f), &g_dead_a) &&
         mc_q46_gain_from_f32((f->dead_time_s / f->dt_s) * (2.0f * MC_INV_SQRT3_F32), &g_dead_b);
    /* a dead band below 2^-29 of the current base (far below one ADC LSB)
     * is a hard sign, as band 0 */
    band_on = (f->dead_band_a > 0.0f) && ((cfg->i_base_a / f->dead_band_a) < 536870912.0f);
    g_inv_band.mant = 0;
    g_inv_band.shift = 0;
    if (ok && band_on) {
        ok = mc_q46_gain_from_f32(cfg->i_base_a / f->dead_band_a, &g_inv_band);
    }
    if (!ok) {
        return MC_CTRL_SLS_ERR_SCALE;
    }
    /* all checks passed: from here on c is written */
    c->g_dtheta = g_dtheta;
    c->g_damp = g_damp;
    c->g_kp_cur = g_kp_cur;
    c->g_dead_a = g_dead_a;
    c->g_dead_b = g_dead_b;
    c->g_inv_band = g_inv_band;
    c->band_on = band_on;
    c->cfg = *cfg;
    c->gamma = ref.gamma;
    c->obs = obs;
    c->pll = pll;
    c->foc = foc;
    c->speed_pi = spi;
    c->obs_err = MC_FLUXOBS_ERR_NONE;
    c->inv_i_base = 1.0f / cfg->i_base_a;
    c->inv_v_base = 1.0f / cfg->v_base_v;
    c->if_cur = slsq_q(f->if_current_a, cfg->i_base_a);
    c->if_half = slsq_q(0.5f * f->if_current_a, cfg->i_base_a);
    c->blend_inc = slsq_q((f->if_current_a * f->dt_s) / f->blend_time_s, cfg->i_base_a);
    c->slew_inc = slsq_q(f->speed_slew_rad_s2 * f->dt_s, wbm);
    c->if_acc_inc = slsq_q(f->if_accel_rad_s2 * f->dt_s, wbm);
    c->ho = slsq_q(f->handover_speed_rad_s, wbm);
    c->ho_999 = slsq_q(0.999f * f->handover_speed_rad_s, wbm);
    c->lo = slsq_q(f->handover_speed_rad_s * (1.0f - f->handover_hyst), wbm);
    c->lock_tol = mc_q31_from_f32(f->lock_tol);
    c->speed_max = slsq_q(f->speed_max_rad_s, wbm);
    c->align_steps = slsq_steps(f->align_time_s, f->dt_s);
    c->lock_timeout_steps = slsq_steps(f->if_lock_timeout_s, f->dt_s);
    c->dead_on = f->dead_time_s > 0.0f;
    c->omega_cmd = 0;
    c->ops = (mc_drive_ctrl_t){.outputs = MC_DRIVE_OUT_PWM3,
                               .reset = mc_ctrl_sls_q31_reset,
                               .fast = mc_ctrl_sls_q31_fast,
                               .set_r_scale = mc_ctrl_sls_q31_set_r_scale,
                               .ctx = c};
    c->tm.handovers = 0u;
    c->tm.fallbacks = 0u;
    return mc_ctrl_sls_q31_reset(c);
}

uint32_t mc_ctrl_sls_q31_set_r_scale(void *ctx, float r_scale)
{
    mc_ctrl_sls_q31_t *c = (mc_ctrl_sls_q31_t *)ctx;
    if (c == NULL) {
        return MC_CTRL_SLS_ERR_NULL;
    }
    return (mc_fluxobs_q31_set_r_scale(&c->obs, r_scale) == MC_FLUXOBS_ERR_NONE)
               ? MC_CTRL_SLS_ERR_NONE
               : MC_CTRL_SLS_ERR_OBSERVER;
}

const mc_drive_ctrl_t *mc_ctrl_sls_q31_ops(mc_ctrl_sls_q31_t *c)
{
    return (c == NULL) ? NULL : &c->ops;
}

uint32_t mc_ctrl_sls_q31_set_speed_ref(mc_ctrl_sls_q31_t *c, float omega_m_rad_s)
{
    if (c == NULL) {
        return MC_CTRL_SLS_ERR_NULL;
    }
    if (!mc_isfinite_f32(omega_m_rad_s) || (mc_abs_f32(omega_m_rad_s) > c->cfg.f.speed_max_rad_s)) {
        return MC_CTRL_SLS_ERR_REF;
    }
    c->omega_cmd = slsq_q(omega_m_rad_s * (float)c->cfg.f.pole_pairs, c->cfg.omega_base_e_rad_s);
    return MC_CTRL_SLS_ERR_NONE;
}

uint32_t mc_ctrl_sls_q31_reset(void *ctx)
{
    mc_ctrl_sls_q31_t *c = (mc_ctrl_sls_q31_t *)ctx;
    uint32_t k;

    if (c == NULL) {
        return MC_CTRL_SLS_ERR_NULL;
    }
    mc_fluxobs_q31_reset(&c->obs, 0, 0, 0);
    mc_spdpll_q31_reset(&c->pll, 0, 0);
    mc_foc_q31_reset(&c->foc);
    mc_pi_q31_reset(&c->speed_pi, 0);
    c->phase = MC_CTRL_SLS_ALIGN;
    c->omega_ref = 0;
    c->theta_if = 0;
    c->omega_if = 0;
    c->i_if = 0;
    c->n_phase = 0u;
    c->n_lockwait = 0u;
    c->id_ref = 0;
    c->iq_ref = 0;
    c->dir = 1;
    for (k = 0u; k < 4u; ++k) {
        c->v_hist_a[k] = 0;
        c->v_hist_b[k] = 0;
    }
    c->speed_count = 0u;
    c->ia_prev = 0;
    c->ib_prev = 0;
    c->tm.phase = MC_CTRL_SLS_ALIGN;
    return MC_CTRL_SLS_ERR_NONE;
}

/* Dead-time error of one leg in units of (dead_time / dt) vbus:
 * sat(i / band), +-1 outside the band (a hard sign for band 0). */
static q31_t slsq_dead_sign(const mc_ctrl_sls_q31_t *c, q31_t i)
{
    if (c->band_on) {
        const int64_t x = mc_q46_clamp(mc_q46_mul_q31(c->g_inv_band, i), -MC_Q46_ONE, MC_Q46_ONE);
        return mc_q46_to_q31(x);
    }
    if (i > 0) {
        return MC_Q31_MAX;
    }
    return (i < 0) ? MC_Q31_MIN : 0;
}

/* Alpha-beta voltage lost to the dead time over the last period (pu):
 * v_alpha = k (2 s_a - s_b - s_c) / 3, v_beta = k (s_b - s_c) / sqrt(3),
 * k = (dead_time / dt) vbus (amplitude-invariant Clarke of the leg errors),
 * formed as (4/3 k) ((2 s_a - s_b - s_c) / 4) and (2/sqrt(3) k) ((s_b - s_c) / 2)
 * so that every factor is a q31 value. */
static void slsq_dead_time_error(const mc_ctrl_sls_q31_t *c, q31_t ia, q31_t ib, q31_t vbus,
                                 q31_t *p_va, q31_t *p_vb)
{
    const q31_t ka = mc_q46_to_q31(mc_q46_mul_q31(c->g_dead_a, vbus));
    const q31_t kb = mc_q46_to_q31(mc_q46_mul_q31(c->g_dead_b, vbus));
    const q31_t ia_m = slsq_avg(ia, c->ia_prev);
    const q31_t ib_m = slsq_avg(ib, c->ib_prev);
    const q31_t ic_m = mc_q31_sat64(-((int64_t)ia_m + (int64_t)ib_m));
    const int64_t sa = slsq_dead_sign(c, ia_m);
    const int64_t sb = slsq_dead_sign(c, ib_m);
    const int64_t sc = slsq_dead_sign(c, ic_m);

    *p_va = mc_q31_mul(ka, mc_q31_sat64(mc_q46_asr((2 * sa) - sb - sc, 2u)));
    *p_vb = mc_q31_mul(kb, mc_q31_sat64(mc_q46_asr(sb - sc, 1u)));
}

/* Preset the current PIs so that, in the frame theta with decoupling speed
 * omega, the next output reproduces the last commanded voltage: the PI
 * output is kp e + integrator + feed-forward (mc_foc_q31). */
static void slsq_preset_current_pis(mc_ctrl_sls_q31_t *c, q31_t theta, q31_t omega, q31_t id_m,
                                    q31_t iq_m)
{
    q31_t s;
    q31_t co;
    q31_t vd;
    q31_t vq;
    int64_t d46;
    int64_t q46;

    mc_sincos_q31(theta, &s, &co);
    mc_park_q31(c->v_hist_a[0], c->v_hist_b[0], s, co, &vd, &vq);
    d46 = mc_q46_from_q31(vd);
    d46 = mc_q46_add(d46, mc_q46_mul_q31(c->foc.g_ff_d, mc_q31_mul(omega, iq_m)));
    d46 = mc_q46_add(d46, -mc_q46_mul_q31(c->g_kp_cur, mc_q31_sub_sat(c->id_ref, id_m)));
    q46 = mc_q46_from_q31(vq);
    q46 = mc_q46_add(q46, -mc_q46_mul_q31(c->foc.g_ff_q, mc_q31_mul(omega, id_m)));
    q46 = mc_q46_add(q46, -mc_q46_mul_q31(c->foc.g_ff_psi, omega));
    q46 = mc_q46_add(q46, -mc_q46_mul_q31(c->g_kp_cur, mc_q31_sub_sat(c->iq_ref, iq_m)));
    mc_pi_q31_reset(&c->foc.pi_d, mc_q46_to_q31(d46));
    mc_pi_q31_reset(&c->foc.pi_q, mc_q46_to_q31(q46));
}

/* IF -> CLOSED, keeping the current vector and the torque. */
static void slsq_handover_to_closed(mc_ctrl_sls_q31_t *c, q31_t i_al, q31_t i_be, q31_t theta_hat,
                                    q31_t omega_hat)
{
    q31_t s;
    q31_t co;
    q31_t id_m;
    q31_t iq_m;
    const q31_t d = slsq_ang_sub(c->theta_if, theta_hat);
    const q31_t id_if = c->id_ref;
    const q31_t iq_if = c->iq_ref;

    mc_sincos_q31(d, &s, &co);
    c->id_ref = mc_q31_sub_sat(mc_q31_mul(co, id_if), mc_q31_mul(s, iq_if));
    c->iq_ref = mc_q31_add_sat(mc_q31_mul(s, id_if), mc_q31_mul(co, iq_if));
    mc_pi_q31_reset(&c->speed_pi, c->iq_ref);
    mc_sincos_q31(theta_hat, &s, &co);
    mc_park_q31(i_al, i_be, s, co, &id_m, &iq_m);
    slsq_preset_current_pis(c, theta_hat, omega_hat, id_m, iq_m);
    c->omega_ref = omega_hat;
    c->phase = MC_CTRL_SLS_CLOSED;
    c->n_phase = 0u;
    c->speed_count = 0u;
    c->tm.handovers++;
}

/* CLOSED -> IF with iq (the torque) kept and the magnitude raised to
 * I = max(I_if, 1.25 |iq|); see fallback_to_if in mc_ctrl_sensorless.c. */
static void slsq_fallback_to_if(mc_ctrl_sls_q31_t *c, q31_t i_al, q31_t i_be, q31_t theta_hat,
                                q31_t omega_hat)
{
    q31_t s;
    q31_t co;
    q31_t id_m;
    q31_t iq_m;
    q31_t mag = mc_q31_sat64(((int64_t)mc_q31_abs_sat(c->iq_ref) * 5) / 4);
    q31_t root;
    q31_t delta;

    if (mag < c->if_cur) {
        mag = c->if_cur;
    }
    /* delta = asin(iq / I) on the stable branch: atan2(iq, sqrt(I^2 - iq^2)),
     * the root exact from the Q62 difference (>= 0: |iq| <= I) */
    root = (q31_t)mc_isqrt_u64((uint64_t)(((int64_t)mag * mag) - ((int64_t)c->iq_ref * c->iq_ref)),
                               NULL);
    delta = mc_atan2_q31(c->iq_ref, root);
    c->theta_if = slsq_ang_sub(mc_q31_angle_add(theta_hat, delta), SLSQ_QUARTER_TURN);
    c->i_if = mag;
    c->omega_if = omega_hat;
    c->dir = (omega_hat < 0) ? -1 : 1;
    c->id_ref = 0;
    c->iq_ref = mag;
    mc_sincos_q31(c->theta_if, &s, &co);
    mc_park_q31(i_al, i_be, s, co, &id_m, &iq_m);
    slsq_preset_current_pis(c, c->theta_if, 0, id_m, iq_m);
    c->phase = MC_CTRL_SLS_IF;
    c->n_phase = 0u;
    c->n_lockwait = 0u;
    c->tm.fallbacks++;
}

uint32_t mc_ctrl_sls_q31_fast(void *ctx, const mc_drive_meas_t *m, mc_drive_out_t *out)
{
    mc_ctrl_sls_q31_t *c = (mc_ctrl_sls_q31_t *)ctx;
    const mc_ctrl_sls_cfg_t *cfg;
    uint32_t err = MC_CTRL_SLS_ERR_NONE;
    q31_t ia;
    q31_t ib;
    q31_t vbus;
    q31_t i_al;
    q31_t i_be;
    q31_t theta_hat;
    q31_t omega_hat;
    q31_t theta_ctrl;
    q31_t omega_ctrl;
    uint32_t k;
    mc_foc_q31_in_t in;
    mc_foc_q31_out_t fo;

    if ((c == NULL) || (m == NULL) || (out == NULL)) {
        return MC_CTRL_SLS_ERR_NULL;
    }
    cfg = &c->cfg.f;
    if (!mc_isfinite_f32(m->ia_a) || !mc_isfinite_f32(m->ib_a) || !mc_isfinite_f32(m->vbus_v)) {
        return MC_CTRL_SLS_ERR_MEAS;
    }
    /* the boundary: the drive's float measurements to per unit */
    ia = mc_q31_from_f32(m->ia_a * c->inv_i_base);
    ib = mc_q31_from_f32(m->ib_a * c->inv_i_base);
    vbus = mc_q31_from_f32(m->vbus_v * c->inv_v_base);

    /* 1. observer on the voltage that acted over the last period */
    mc_clarke_q31(ia, ib, &i_al, &i_be);
    {
        q31_t dva = 0;
        q31_t dvb = 0;
        if (c->dead_on) {
            slsq_dead_time_error(c, ia, ib, vbus, &dva, &dvb);
        }
        c->tm.v_alpha_obs = mc_q31_sub_sat(c->v_hist_a[cfg->pwm_delay_periods], dva);
        c->tm.v_beta_obs = mc_q31_sub_sat(c->v_hist_b[cfg->pwm_delay_periods], dvb);
    }
    c->ia_prev = ia;
    c->ib_prev = ib;
    if (mc_fluxobs_q31_step(&c->obs, c->tm.v_alpha_obs, c->tm.v_beta_obs, i_al, i_be) !=
        MC_FLUXOBS_ERR_NONE) {
        err |= MC_CTRL_SLS_ERR_DIVERGED;
    }
    theta_hat = c->obs.theta;
    (void)mc_spdpll_q31_step(&c->pll, theta_hat, &omega_hat); /* electrical = mechanical pu */

    /* 2. reference slew */
    c->omega_ref = slsq_slew(c->omega_ref, c->omega_cmd, c->slew_inc);
    if (c->n_phase < 0xFFFFFFFFu) {
        c->n_phase++;
    }

    /* 3. phase logic */
    if (c->phase == MC_CTRL_SLS_ALIGN) {
        c->i_if =
            (c->n_phase >= c->align_steps)
                ? c->if_cur
                : (q31_t)(((int64_t)c->if_cur * (int64_t)c->n_phase) / (int64_t)c->align_steps);
        if ((c->n_phase >= c->align_steps) && (c->omega_cmd != 0)) {
            c->phase = MC_CTRL_SLS_IF;
            c->dir = (c->omega_cmd < 0) ? -1 : 1;
            c->n_phase = 0u;
            c->n_lockwait = 0u;
        }
    } else if (c->phase == MC_CTRL_SLS_IF) {
        const q31_t target = mc_q31_sat(c->omega_ref, (q31_t)-c->ho, c->ho);
        c->omega_if = slsq_slew(c->omega_if, target, c->if_acc_inc);
        c->i_if = slsq_slew(c->i_if, c->if_cur, c->blend_inc);
        if ((mc_q31_abs_sat(c->omega_cmd) > c->ho) && (mc_q31_abs_sat(c->omega_if) >= c->ho_999)) {
            const bool locked = (mc_q31_abs_sat(mc_q31_sub_sat(omega_hat, c->omega_if)) <=
                                 mc_q31_mul(c->lock_tol, mc_q31_abs_sat(c->omega_if))) &&
                                ((c->obs.flags & MC_FLUXOBS_ERR_DIVERGED) == 0u);
            if (locked) {
                slsq_handover_to_closed(c, i_al, i_be, theta_hat, omega_hat);
            } else {
                if (c->n_lockwait < 0xFFFFFFFFu) {
                    c->n_lockwait++;
                }
                if (c->n_lockwait > c->lock_timeout_steps) {
                    err |= MC_CTRL_SLS_ERR_NO_LOCK;
                }
            }
        }
    } else {
        if (cfg->lowspeed_fallback && (mc_q31_abs_sat(c->omega_cmd) < c->lo) &&
            (mc_q31_abs_sat(omega_hat) < c->lo)) {
            slsq_fallback_to_if(c, i_al, i_be, theta_hat, omega_hat);
        }
    }

    if (c->phase == MC_CTRL_SLS_CLOSED) {
        c->speed_count++;
        if (c->speed_count >= cfg->speed_div) {
            c->speed_count = 0u;
            (void)mc_pi_q31_step(&c->speed_pi, mc_q31_sub_sat(c->omega_ref, omega_hat), &c->iq_ref);
        }
        c->id_ref = slsq_slew(c->id_ref, 0, c->blend_inc);
        theta_ctrl = theta_hat;
        omega_ctrl = omega_hat;
    } else {
        q31_t damp = 0;
        q31_t sd;
        q31_t cd;
        if (c->phase == MC_CTRL_SLS_IF) {
            c->theta_if = mc_q31_angle_add(c->theta_if,
                                           mc_q46_to_q31(mc_q46_mul_q31(c->g_dtheta, c->omega_if)));
            if (cfg->if_damping) {
                /* -kp (omega_hat - omega_if) along the estimated q axis,
                 * at most half the I-f current (not in ALIGN) */
                damp = mc_q31_sat(mc_q46_to_q31(-mc_q46_mul_q31(
                                      c->g_damp, mc_q31_sub_sat(omega_hat, c->omega_if))),
                                  (q31_t)-c->if_half, c->if_half);
            }
        }
        mc_sincos_q31(slsq_ang_sub(theta_hat, c->theta_if), &sd, &cd);
        c->id_ref = mc_q31_neg_sat(mc_q31_mul(damp, sd));
        c->iq_ref = mc_q31_add_sat(c->i_if, mc_q31_mul(damp, cd));
        theta_ctrl = c->theta_if;
        omega_ctrl = 0;
    }

    /* 4. current loop */
    in.ia = ia;
    in.ib = ib;
    in.ic = 0;
    in.three_phase = false;
    in.theta_e = theta_ctrl;
    in.omega_e = omega_ctrl;
    in.vbus = vbus;
    in.id_ref = c->id_ref;
    in.iq_ref = c->iq_ref;
    if (mc_foc_q31_step(&c->foc, &in, &fo) != MC_FOC_ERR_NONE) {
        err |= MC_CTRL_SLS_ERR_FOC;
    }
    out->duty_a = mc_q31_to_f32(fo.duty_a);
    out->duty_b = mc_q31_to_f32(fo.duty_b);
    out->duty_c = mc_q31_to_f32(fo.duty_c);
    out->duty2_a = 0.0f;
    out->duty2_b = 0.0f;
    for (k = 3u; k > 0u; --k) {
        c->v_hist_a[k] = c->v_hist_a[k - 1u];
        c->v_hist_b[k] = c->v_hist_b[k - 1u];
    }
    c->v_hist_a[0] = fo.v_alpha;
    c->v_hist_b[0] = fo.v_beta;

    c->tm.phase = c->phase;
    c->tm.theta_hat_e = theta_hat;
    c->tm.omega_hat = omega_hat;
    c->tm.theta_ctrl_e = theta_ctrl;
    c->tm.omega_ref = c->omega_ref;
    c->tm.omega_if = c->omega_if;
    c->tm.i_alpha = i_al;
    c->tm.i_beta = i_be;
    c->tm.id_ref = c->id_ref;
    c->tm.iq_ref = c->iq_ref;
    c->tm.id = fo.id;
    c->tm.iq = fo.iq;
    c->tm.obs_resid = c->obs.resid;
    return err;
}

void mc_ctrl_sls_q31_get_tm_f32(const mc_ctrl_sls_q31_t *c, mc_ctrl_sls_tm_t *p_tm)
{
    float ib;
    float vb;
    float wbm;

    if ((c == NULL) || (p_tm == NULL)) {
        return;
    }
    ib = c->cfg.i_base_a;
    vb = c->cfg.v_base_v;
    wbm = c->cfg.omega_base_e_rad_s / (float)c->cfg.f.pole_pairs;
    p_tm->phase = c->tm.phase;
    p_tm->theta_hat_e_rad = mc_q31_angle_to_rad_f32(c->tm.theta_hat_e);
    p_tm->omega_hat_m_rad_s = mc_q31_to_f32(c->tm.omega_hat) * wbm;
    p_tm->theta_ctrl_e_rad = mc_q31_angle_to_rad_f32(c->tm.theta_ctrl_e);
    p_tm->omega_ref_m_rad_s = mc_q31_to_f32(c->tm.omega_ref) * wbm;
    p_tm->omega_if_m_rad_s = mc_q31_to_f32(c->tm.omega_if) * wbm;
    p_tm->i_alpha_a = mc_q31_to_f32(c->tm.i_alpha) * ib;
    p_tm->i_beta_a = mc_q31_to_f32(c->tm.i_beta) * ib;
    p_tm->v_alpha_obs_v = mc_q31_to_f32(c->tm.v_alpha_obs) * vb;
    p_tm->v_beta_obs_v = mc_q31_to_f32(c->tm.v_beta_obs) * vb;
    p_tm->id_ref_a = mc_q31_to_f32(c->tm.id_ref) * ib;
    p_tm->iq_ref_a = mc_q31_to_f32(c->tm.iq_ref) * ib;
    p_tm->id_a = mc_q31_to_f32(c->tm.id) * ib;
    p_tm->iq_a = mc_q31_to_f32(c->tm.iq) * ib;
    p_tm->obs_resid = mc_q31_to_f32(c->tm.obs_resid);
    p_tm->handovers = c->tm.handovers;
    p_tm->fallbacks = c->tm.fallbacks;
}

void mc_ctrl_sls_q31_get_flux_wb(const mc_ctrl_sls_q31_t *c, float *p_alpha_wb, float *p_beta_wb)
{
    if ((c == NULL) || (p_alpha_wb == NULL) || (p_beta_wb == NULL)) {
        return;
    }
    *p_alpha_wb = mc_q31_to_f32(mc_q46_to_q31(c->obs.x_alpha_q46)) * c->cfg.flux_base_wb;
    *p_beta_wb = mc_q31_to_f32(mc_q46_to_q31(c->obs.x_beta_q46)) * c->cfg.flux_base_wb;
}
