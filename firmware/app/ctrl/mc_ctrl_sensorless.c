/**
 * @file mc_ctrl_sensorless.c
 * @brief Sensorless FOC speed control with I-f start-up (paper 002,
 *        Section V); see mc_ctrl_sensorless.h.
 *
 * Departures from the paper's Section V, on purpose:
 * - the current loop uses the kernels' dq PI with decoupling (mc_foc): the
 *   paper's iv) with the measured currents in the feed-forward and the
 *   PLL speed as omega_hat; identical in the continuous limit;
 * - the paper's speed loop i_dq* = PI(omega* - omega_hat) is read as
 *   iq* = PI(...), id* = 0 on a non-salient machine below base speed, and
 *   as MTPA's (id*, iq*) for the magnitude PI(...) on a salient one (the
 *   paper's "field weakening provisions" are not reproduced: the drive's
 *   fw kernel with fw_enable);
 * - start-up (ALIGN, I-f) and the low-speed fallback are additions: the
 *   paper reports that below about 50 r/min the loop degrades or goes
 *   unstable, which Prop. 4 explains (no information at zero speed).
 */
#include "mc_ctrl_sensorless.h"

#include <stddef.h>

#include "fw/mc_fw.h"
#include "math/mc_math.h"
#include "transforms/mc_transforms.h"

static bool pos_finite(float x)
{
    return (x > 0.0f) && mc_isfinite_f32(x);
}

static float sign_f32(float x)
{
    return (x < 0.0f) ? -1.0f : 1.0f;
}

/* Move x towards target by at most step (>= 0). */
static float slew_f32(float x, float target, float step)
{
    if (target > (x + step)) {
        return x + step;
    }
    if (target < (x - step)) {
        return x - step;
    }
    return target;
}

static uint32_t sls_validate(const mc_ctrl_sls_cfg_t *cfg)
{
    uint32_t err = MC_CTRL_SLS_ERR_NONE;

    if (!(cfg->r_ohm >= 0.0f) || !mc_isfinite_f32(cfg->r_ohm) || !pos_finite(cfg->l_h) ||
        !pos_finite(cfg->flux_wb) || (cfg->pole_pairs == 0u) ||
        !mc_isfinite_f32(cfg->ld_minus_lq_h) || !((cfg->l_h + cfg->ld_minus_lq_h) > 0.0f)) {
        err |= MC_CTRL_SLS_ERR_MOTOR;
    }
    if (!pos_finite(cfg->dt_s) || (cfg->speed_div == 0u) || (cfg->pwm_delay_periods > 3u) ||
        !(cfg->dead_time_s >= 0.0f) || !(cfg->dead_time_s < (0.5f * cfg->dt_s)) ||
        !(cfg->dead_band_a >= 0.0f) || !mc_isfinite_f32(cfg->dead_band_a)) {
        err |= MC_CTRL_SLS_ERR_TIMING;
    }
    if (!pos_finite(cfg->speed_kp_a_s_rad) || !(cfg->speed_ki_a_rad >= 0.0f) ||
        !mc_isfinite_f32(cfg->speed_ki_a_rad) || !pos_finite(cfg->iq_max_a) ||
        !pos_finite(cfg->speed_slew_rad_s2) || !pos_finite(cfg->speed_max_rad_s)) {
        err |= MC_CTRL_SLS_ERR_SPEED;
    }
    {
        const bool startup_ok =
            pos_finite(cfg->if_current_a) && (cfg->align_time_s >= 0.0f) &&
            mc_isfinite_f32(cfg->align_time_s) && pos_finite(cfg->if_accel_rad_s2) &&
            pos_finite(cfg->handover_speed_rad_s) && (cfg->handover_hyst >= 0.0f) &&
            (cfg->handover_hyst <= 0.9f) && pos_finite(cfg->lock_tol) && (cfg->lock_tol <= 1.0f) &&
            pos_finite(cfg->if_lock_timeout_s) && pos_finite(cfg->blend_time_s) &&
            (cfg->handover_speed_rad_s < cfg->speed_max_rad_s);
        /* the closed loop must stay a factor 2 above the critical speed
         * (an invalid critical speed is reported by the observer check) */
        const bool margin_ok = !pos_finite(cfg->omega_crit_m_rad_s) ||
                               ((cfg->handover_speed_rad_s * (1.0f - cfg->handover_hyst)) >
                                (2.0f * cfg->omega_crit_m_rad_s));
        if (!startup_ok || !margin_ok) {
            err |= MC_CTRL_SLS_ERR_STARTUP;
        }
    }
    return err;
}

/* The MTPA kernel (fw/mc_fw.h: its MTPA only, no weakening: ki_fw = 0)
 * for the machine of c->cfg, the current circle the law's largest
 * current: the I-f vector's 1.25 iq_max. */
static uint32_t sls_mtpa_init(mc_ctrl_sls_t *c)
{
    const mc_ctrl_sls_cfg_t *cfg = &c->cfg;
    const mc_fw_f32_cfg_t fc = {.ld_h = cfg->l_h + cfg->ld_minus_lq_h,
                                .lq_h = cfg->l_h,
                                .flux_wb = cfg->flux_wb,
                                .i_max_a = 1.25f * cfg->iq_max_a,
                                .v_margin = 1.0f,
                                .ki_fw_a_per_vs = 0.0f,
                                .k_demag = 1.0f,
                                .dt_s = cfg->dt_s};
    return mc_fw_f32_init(&c->mtpa, &fc);
}

/* The largest active flux of the closed loop (mc_fluxobs.h), where the
 * observer's critical speed is highest: MTPA's d current at the largest
 * current always raises psi_a (id_mtpa has the sign of Ld - Lq), so
 * flux + (Ld - Lq) id_mtpa(1.25 iq_max); I-f's d current (>= 0 on its
 * stable side) lowers it for Ld < Lq. The flux if non-salient (exactly:
 * MTPA's d current is 0 there). */
static float sls_psi_a_max(const mc_ctrl_sls_t *c)
{
    const float id = mc_fw_f32_mtpa_id(&c->mtpa, 1.25f * c->cfg.iq_max_a);
    return c->cfg.flux_wb + (c->cfg.ld_minus_lq_h * id);
}

uint32_t mc_ctrl_sls_init(mc_ctrl_sls_t *c, const mc_ctrl_sls_cfg_t *cfg)
{
    uint32_t err;
    mc_fluxobs_f32_cfg_t oc;
    mc_spdpll_f32_cfg_t pc;
    mc_pi_f32_cfg_t sc;
    float kp = 0.0f;
    float ki = 0.0f;

    if ((c == NULL) || (cfg == NULL)) {
        return MC_CTRL_SLS_ERR_NULL;
    }
    err = sls_validate(cfg);
    if ((err & (MC_CTRL_SLS_ERR_MOTOR | MC_CTRL_SLS_ERR_TIMING)) != 0u) {
        return err; /* the kernels' configs below need these */
    }
    c->cfg = *cfg;
    c->psi_a_max_wb = cfg->flux_wb;
    if (sls_mtpa_init(c) != MC_FW_ERR_NONE) {
        err |= MC_CTRL_SLS_ERR_SPEED; /* the current limit (iq_max_a) */
        c->mtpa.salient = false;
    } else {
        c->psi_a_max_wb = sls_psi_a_max(c);
    }
    c->obs_err = mc_fluxobs_f32_gamma_for_critical_speed(cfg->omega_crit_m_rad_s, cfg->pole_pairs,
                                                         c->psi_a_max_wb, &c->gamma);
    if (c->obs_err == MC_FLUXOBS_ERR_NONE) {
        oc.r_ohm = cfg->r_ohm;
        oc.l_h = cfg->l_h;
        oc.flux_wb = cfg->flux_wb;
        oc.gamma = c->gamma;
        oc.dt_s = cfg->dt_s;
        oc.resid_tol = cfg->resid_tol;
        oc.resid_time_s = cfg->resid_time_s;
        oc.ld_minus_lq_h = cfg->ld_minus_lq_h;
        c->obs_err = mc_fluxobs_f32_init(&c->obs, &oc);
    }
    if (c->obs_err != MC_FLUXOBS_ERR_NONE) {
        err |= MC_CTRL_SLS_ERR_OBSERVER;
    }
    pc.bw_rad_s = cfg->pll_bw_rad_s;
    pc.dt_s = cfg->dt_s;
    pc.omega_max_rad_s = 2.0f * cfg->speed_max_rad_s * (float)cfg->pole_pairs;
    if (mc_spdpll_f32_init(&c->pll, &pc) != MC_SPDPLL_ERR_NONE) {
        err |= MC_CTRL_SLS_ERR_PLL;
    }
    /* the current loop is the drive's (MC_DRIVE_OUT_CURRENT); its
     * bandwidth is checked as the q31 twin builds its own from it */
    if ((mc_foc_f32_gains_from_bandwidth(cfg->r_ohm, cfg->l_h, cfg->cur_bw_rad_s, &kp, &ki) !=
         MC_FOC_ERR_NONE) ||
        !(cfg->v_limit_ratio > 0.0f) || !(cfg->v_limit_ratio <= 1.0f) ||
        !(cfg->vbus_max_v > 0.0f) || !mc_isfinite_f32(cfg->vbus_max_v)) {
        err |= MC_CTRL_SLS_ERR_CURRENT;
    }
    if ((err & MC_CTRL_SLS_ERR_SPEED) == 0u) {
        sc.kp = cfg->speed_kp_a_s_rad;
        sc.ki_per_s = cfg->speed_ki_a_rad;
        sc.dt_s = cfg->dt_s * (float)cfg->speed_div;
        sc.out_min = -cfg->iq_max_a;
        sc.out_max = cfg->iq_max_a;
        sc.aw = MC_PI_AW_CLAMP;
        sc.kaw_per_s = 0.0f;
        if (mc_pi_f32_init(&c->speed_pi, &sc) != MC_PI_ERR_NONE) {
            err |= MC_CTRL_SLS_ERR_SPEED;
        }
    }
    if (err != MC_CTRL_SLS_ERR_NONE) {
        return err;
    }
    c->omega_cmd_m_rad_s = 0.0f;
    c->ops = (mc_drive_ctrl_t){.outputs = MC_DRIVE_OUT_CURRENT,
                               .reset = mc_ctrl_sls_reset,
                               .fast = mc_ctrl_sls_fast,
                               .set_r_scale = mc_ctrl_sls_set_r_scale,
                               .ctx = c,
                               .uses_speed_ref = cfg->ref_from_drive};
    c->tm.handovers = 0u;
    c->tm.fallbacks = 0u;
    return mc_ctrl_sls_reset(c);
}

uint32_t mc_ctrl_sls_set_r_scale(void *ctx, float r_scale)
{
    mc_ctrl_sls_t *c = (mc_ctrl_sls_t *)ctx;
    if (c == NULL) {
        return MC_CTRL_SLS_ERR_NULL;
    }
    return (mc_fluxobs_f32_set_r_scale(&c->obs, r_scale) == MC_FLUXOBS_ERR_NONE)
               ? MC_CTRL_SLS_ERR_NONE
               : MC_CTRL_SLS_ERR_OBSERVER;
}

const mc_drive_ctrl_t *mc_ctrl_sls_ops(mc_ctrl_sls_t *c)
{
    return (c == NULL) ? NULL : &c->ops;
}

uint32_t mc_ctrl_sls_set_speed_ref(mc_ctrl_sls_t *c, float omega_m_rad_s)
{
    if (c == NULL) {
        return MC_CTRL_SLS_ERR_NULL;
    }
    if (!mc_isfinite_f32(omega_m_rad_s) || (mc_abs_f32(omega_m_rad_s) > c->cfg.speed_max_rad_s)) {
        return MC_CTRL_SLS_ERR_REF;
    }
    c->omega_cmd_m_rad_s = omega_m_rad_s;
    return MC_CTRL_SLS_ERR_NONE;
}

uint32_t mc_ctrl_sls_reset(void *ctx)
{
    mc_ctrl_sls_t *c = (mc_ctrl_sls_t *)ctx;
    uint32_t k;

    if (c == NULL) {
        return MC_CTRL_SLS_ERR_NULL;
    }
    (void)mc_fluxobs_f32_reset(&c->obs, 0.0f, 0.0f, 0.0f);
    (void)mc_spdpll_f32_reset(&c->pll, 0.0f, 0.0f);
    (void)mc_pi_f32_reset(&c->speed_pi, 0.0f);
    c->reframe = false;
    c->phase = MC_CTRL_SLS_ALIGN;
    c->omega_ref_m_rad_s = 0.0f;
    c->theta_if_e_rad = 0.0f;
    c->omega_if_e_rad_s = 0.0f;
    c->i_if_a = 0.0f;
    c->t_phase_s = 0.0f;
    c->t_lockwait_s = 0.0f;
    c->id_ref_a = 0.0f;
    c->iq_ref_a = 0.0f;
    c->id_mtpa_a = 0.0f;
    c->dir = 1.0f;
    c->align_dir_set = false;
    c->al_x_a = 0.0f;
    c->al_x_b = 0.0f;
    c->al_i_prev_a = 0.0f;
    c->al_i_prev_b = 0.0f;
    c->al_p0_a = 0.0f;
    c->al_p0_b = 0.0f;
    c->al_u = 0.0f;
    c->al_v = 0.0f;
    c->al_n = 0.0f;
    c->al_su = 0.0f;
    c->al_sv = 0.0f;
    c->al_suu = 0.0f;
    c->al_svv = 0.0f;
    c->al_suv = 0.0f;
    c->al_sz = 0.0f;
    c->al_suz = 0.0f;
    c->al_svz = 0.0f;
    for (k = 0u; k < 4u; ++k) {
        c->v_hist_a[k] = 0.0f;
        c->v_hist_b[k] = 0.0f;
    }
    c->speed_count = 0u;
    c->ia_prev_a = 0.0f;
    c->ib_prev_a = 0.0f;
    c->tm.phase = MC_CTRL_SLS_ALIGN;
    return MC_CTRL_SLS_ERR_NONE;
}

/* Dead-time voltage error of one leg in units of (dead_time / dt) vbus:
 * sat(i / band), +-1 outside the band (a hard sign for band = 0). */
/* Alpha-beta voltage lost to the dead time over the last period. */
static void dead_time_error(const mc_ctrl_sls_t *c, float ia_a, float ib_a, float vbus_v,
                            float *p_va, float *p_vb)
{
    const float k = (c->cfg.dead_time_s / c->cfg.dt_s) * vbus_v;
    const float ia = 0.5f * (ia_a + c->ia_prev_a);
    const float ib = 0.5f * (ib_a + c->ib_prev_a);
    const float sa = mc_sign_band_f32(ia, c->cfg.dead_band_a);
    const float sb = mc_sign_band_f32(ib, c->cfg.dead_band_a);
    const float sc = mc_sign_band_f32(-(ia + ib), c->cfg.dead_band_a);

    /* amplitude-invariant Clarke of the three leg errors (common mode drops) */
    *p_va = k * (2.0f / 3.0f) * (sa - (0.5f * (sb + sc)));
    *p_vb = k * MC_INV_SQRT3_F32 * (sb - sc);
}

/* The holds' current angles ahead of the observer's reset guess (0) in the
 * run's direction [rad, electrical]: a quarter turn apart (see ALIGN). */
#define ALIGN_LEAD1 (0.25f * MC_PI_F32)
#define ALIGN_LEAD2 (0.75f * MC_PI_F32)

/* The hold waits for a trusted circle fit up to this many align times. */
#define ALIGN_WAIT 4.0f

/* At the end of ALIGN, with the rotor's angle from the circle fit: the I-f
 * current (the frame's q axis) is meant to lead the rotor's d axis by 0 to
 * a quarter turn in the run's direction (I-f's stable region: forward
 * torque that grows as the rotor falls behind). A load the holds could not
 * turn (or a rotor too heavy to reach the second hold within the align
 * time) leaves it further back: the second hold's current up to 160 deg
 * ahead on the U8-class motor under 30 % load, where the torque is a third
 * of its most and falls as the frame accelerates away (issue 31: no lock).
 * Then the frame restarts with the current a quarter turn ahead of the
 * fitted rotor (the most torque); a rotor within the region keeps the
 * frame the hold gave it. dir: the run's direction (+-1). */
static void if_frame_to_rotor(mc_ctrl_sls_t *c, float theta_rotor, float dir)
{
    const float lead = dir * mc_wrap_pi_f32(c->theta_if_e_rad + MC_HALF_PI_F32 - theta_rotor);
    if ((dir != 0.0f) && !(mc_abs_f32(lead) <= MC_HALF_PI_F32)) {
        c->theta_if_e_rad = mc_wrap_pi_f32(theta_rotor + (dir * MC_HALF_PI_F32) - MC_HALF_PI_F32);
    }
}

/* ALIGN: integrate the flux without correction (the observer's formula)
 * and add the point to the circle fit's sums. */
static void align_track(mc_ctrl_sls_t *c, float i_al, float i_be)
{
    const mc_ctrl_sls_cfg_t *cfg = &c->cfg;
    const float inv_flux = 1.0f / cfg->flux_wb;
    float ea;
    float eb;
    float u;
    float v;
    float z;
    c->al_x_a += cfg->dt_s * (c->tm.v_alpha_obs_v - (0.5f * cfg->r_ohm * (c->al_i_prev_a + i_al)));
    c->al_x_b += cfg->dt_s * (c->tm.v_beta_obs_v - (0.5f * cfg->r_ohm * (c->al_i_prev_b + i_be)));
    c->al_i_prev_a = i_al;
    c->al_i_prev_b = i_be;
    ea = (c->al_x_a - (cfg->l_h * i_al)) * inv_flux;
    eb = (c->al_x_b - (cfg->l_h * i_be)) * inv_flux;
    if (c->al_n == 0.0f) {
        c->al_p0_a = ea;
        c->al_p0_b = eb;
    }
    u = ea - c->al_p0_a;
    v = eb - c->al_p0_b;
    z = (u * u) + (v * v);
    c->al_u = u;
    c->al_v = v;
    c->al_n += 1.0f;
    c->al_su += u;
    c->al_sv += v;
    c->al_suu += u * u;
    c->al_svv += v * v;
    c->al_suv += u * v;
    c->al_sz += z;
    c->al_suz += u * z;
    c->al_svz += v * z;
}

/* The rotor angle at the end of ALIGN from the circle fit: the centre
 * (a, b) and k of u^2 + v^2 = 2 a u + 2 b v + k by least squares
 * (Kasa), trusted when the path spread (rms
 * about its mean, about 0.05 of the flux: an arc of about 10 deg or more) and the fitted radius is
 * within 20 % of the flux. Returns false otherwise: the rotor hardly moved,
 * so it sits where the hold put it. */
static bool align_fit(const mc_ctrl_sls_t *c, float *p_theta_rad)
{
    const float n = c->al_n;
    float m11;
    float m12;
    float m13;
    float m22;
    float m23;
    float m33;
    float r1;
    float r2;
    float r3;
    float det;
    float a;
    float b;
    float k;
    float rad2;
    float spread;
    if (n < 3.0f) {
        return false;
    }
    spread =
        ((c->al_suu - ((c->al_su * c->al_su) / n)) + (c->al_svv - ((c->al_sv * c->al_sv) / n))) / n;
    if (!(spread >= 0.0025f)) {
        return false;
    }
    /* normal equations of [2u 2v 1] [a b k]' = z */
    m11 = 4.0f * c->al_suu;
    m12 = 4.0f * c->al_suv;
    m13 = 2.0f * c->al_su;
    m22 = 4.0f * c->al_svv;
    m23 = 2.0f * c->al_sv;
    m33 = n;
    r1 = 2.0f * c->al_suz;
    r2 = 2.0f * c->al_svz;
    r3 = c->al_sz;
    det = (m11 * ((m22 * m33) - (m23 * m23))) - (m12 * ((m12 * m33) - (m23 * m13))) +
          (m13 * ((m12 * m23) - (m22 * m13)));
    if (!(mc_abs_f32(det) > 0.0f) || !mc_isfinite_f32(det)) {
        return false;
    }
    a = ((r1 * ((m22 * m33) - (m23 * m23))) - (m12 * ((r2 * m33) - (m23 * r3))) +
         (m13 * ((r2 * m23) - (m22 * r3)))) /
        det;
    b = ((m11 * ((r2 * m33) - (m23 * r3))) - (r1 * ((m12 * m33) - (m23 * m13))) +
         (m13 * ((m12 * r3) - (r2 * m13)))) /
        det;
    k = ((m11 * ((m22 * r3) - (r2 * m23))) - (m12 * ((m12 * r3) - (r2 * m13))) +
         (r1 * ((m12 * m23) - (m22 * m13)))) /
        det;
    rad2 = k + (a * a) + (b * b);
    if (!(rad2 > 0.64f) || !(rad2 < 1.44f)) {
        return false;
    }
    *p_theta_rad = mc_atan2_f32(c->al_v - b, c->al_u - a);
    return true;
}

/* MTPA (law_mtpa on a salient machine): the speed PI's output, left in
 * iq_ref_a, is the signed current command i; MTPA's d current for |i|
 * (mc_fw_f32_mtpa_id) becomes id's target and iq = sign(i) sqrt(i^2 -
 * id^2). Else the output stays iq_ref_a and id's target 0 (a non-salient
 * machine bit for bit as before; with the drive's MTPA (fw_enable) the
 * drive shapes the command). The PI's preset at the hand-over and its
 * tracking of the regenerative limit take a q current as the command:
 * MTPA then gives a q current lower by about id^2 / (2 iq) (under 1 % of
 * it while |id| < iq / 8), which the integrator takes up. */
static void sls_mtpa_refs(mc_ctrl_sls_t *c)
{
    const float i_cmd = c->iq_ref_a;
    float id;
    float iq2;
    if (!c->cfg.law_mtpa || !c->mtpa.salient) {
        c->id_mtpa_a = 0.0f;
        return;
    }
    id = mc_fw_f32_mtpa_id(&c->mtpa, mc_abs_f32(i_cmd));
    iq2 = (i_cmd * i_cmd) - (id * id);
    c->id_mtpa_a = id;
    c->iq_ref_a = sign_f32(i_cmd) * ((iq2 > 0.0f) ? mc_sqrt_f32(iq2) : 0.0f);
}

/* IF -> CLOSED, keeping the current vector and the torque. */
static void handover_to_closed(mc_ctrl_sls_t *c, float omega_hat_e)
{
    float s;
    float co;
    const float d = mc_wrap_pi_f32(c->theta_if_e_rad - c->obs.theta_e_rad);
    const float id_if = c->id_ref_a; /* last references, I-f frame */
    const float iq_if = c->iq_ref_a;

    /* the same current vector in the frame of theta_hat: rotate by d */
    mc_sincos_f32(d, &s, &co);
    c->id_ref_a = (co * id_if) - (s * iq_if);
    c->iq_ref_a = (s * id_if) + (co * iq_if);
    (void)mc_pi_f32_reset(&c->speed_pi, c->iq_ref_a);
    c->id_mtpa_a = 0.0f; /* until the speed loop's first step */
    c->reframe = true;   /* the drive keeps the voltage vector in the new frame */
    c->omega_ref_m_rad_s = omega_hat_e / (float)c->cfg.pole_pairs;
    c->phase = MC_CTRL_SLS_CLOSED;
    c->t_phase_s = 0.0f;
    c->speed_count = 0u;
    c->tm.handovers++;
}

/* CLOSED -> IF. In the I-f frame (current I along its q axis) the rotor
 * sits at the load angle delta = theta_if + pi/2 - theta, with
 * iq = I sin(delta) (the torque) and id = I cos(delta) in the rotor frame;
 * it is a stable equilibrium only for cos(delta) > 0. Keeping the current
 * VECTOR (id = 0) would put the rotor on the stability limit (delta =
 * +-pi/2) and, while braking, on the wrong side (observed: pole slip and a
 * reversal). So the torque-producing iq is kept exactly and the magnitude
 * is raised to I = max(I_if, 1.25 |iq|) (|sin delta| <= 0.8): only id
 * steps, from 0 to I cos(delta) > 0, which produces no torque on a
 * non-salient machine; the current loop takes it over its bandwidth. */
static void fallback_to_if(mc_ctrl_sls_t *c, float theta_hat, float omega_hat_e)
{
    float mag = 1.25f * mc_abs_f32(c->iq_ref_a);
    float delta;

    if (mag < c->cfg.if_current_a) {
        mag = c->cfg.if_current_a;
    }
    /* delta = asin(iq / I) on the stable branch: atan2(iq, sqrt(I^2 - iq^2)) */
    delta = mc_atan2_f32(c->iq_ref_a, mc_sqrt_f32((mag * mag) - (c->iq_ref_a * c->iq_ref_a)));
    c->theta_if_e_rad = mc_wrap_pi_f32(theta_hat + delta - MC_HALF_PI_F32);
    c->i_if_a = mag;
    c->omega_if_e_rad_s = omega_hat_e;
    c->dir = sign_f32(omega_hat_e);
    c->id_ref_a = 0.0f;
    c->iq_ref_a = mag;
    c->reframe = true; /* the drive keeps the voltage vector in the I-f frame */
    c->phase = MC_CTRL_SLS_IF;
    c->t_phase_s = 0.0f;
    c->t_lockwait_s = 0.0f;
    c->tm.fallbacks++;
}

uint32_t mc_ctrl_sls_fast(void *ctx, const mc_drive_meas_t *m, mc_drive_out_t *out)
{
    mc_ctrl_sls_t *c = (mc_ctrl_sls_t *)ctx;
    const mc_ctrl_sls_cfg_t *cfg;
    uint32_t err = MC_CTRL_SLS_ERR_NONE;
    float i_al;
    float i_be;
    float theta_hat;
    float omega_hat_e;
    float omega_hat_m;
    float pp;
    float ho_e;
    float theta_ctrl;
    float omega_ctrl;
    uint32_t k;
    float cmd;
    float lim;
    const uint32_t delay_idx = (c == NULL) ? 0u : c->cfg.pwm_delay_periods;

    if ((c == NULL) || (m == NULL) || (out == NULL)) {
        return MC_CTRL_SLS_ERR_NULL;
    }
    cfg = &c->cfg;
    if (!mc_isfinite_f32(m->ia_a) || !mc_isfinite_f32(m->ib_a) || !mc_isfinite_f32(m->vbus_v)) {
        return MC_CTRL_SLS_ERR_MEAS;
    }
    pp = (float)cfg->pole_pairs;
    ho_e = cfg->handover_speed_rad_s * pp;

    /* 1. observer on the voltage that acted over the last period: the
     * drive's current loop commanded it (its history, newest first) */
    for (k = 3u; k > 0u; --k) {
        c->v_hist_a[k] = c->v_hist_a[k - 1u];
        c->v_hist_b[k] = c->v_hist_b[k - 1u];
    }
    c->v_hist_a[0] = m->v_alpha_prev_v;
    c->v_hist_b[0] = m->v_beta_prev_v;
    mc_clarke_f32(m->ia_a, m->ib_a, &i_al, &i_be);
    {
        float dva = 0.0f;
        float dvb = 0.0f;
        /* With the duty-side correction (the drive's dead_time_comp) the
         * commanded voltage is taken as applied (the correction cancels the
         * error it estimates). */
        if ((cfg->dead_time_s > 0.0f) && !cfg->dead_comp_duty) {
            dead_time_error(c, m->ia_a, m->ib_a, m->vbus_v, &dva, &dvb);
        }
        c->tm.v_alpha_obs_v = c->v_hist_a[delay_idx] - dva;
        c->tm.v_beta_obs_v = c->v_hist_b[delay_idx] - dvb;
    }
    c->ia_prev_a = m->ia_a;
    c->ib_prev_a = m->ib_a;
    {
        /* In ALIGN the observer still runs from the reset guess (angle 0)
         * while the hold pulls the rotor from wherever it was: an estimate
         * off the constraint circle there is expected, not a divergence.
         * The estimate restarts from the hold's angle when ALIGN ends. */
        const uint32_t oe =
            mc_fluxobs_f32_step(&c->obs, c->tm.v_alpha_obs_v, c->tm.v_beta_obs_v, i_al, i_be);
        if ((oe != MC_FLUXOBS_ERR_NONE) &&
            !(cfg->align_any_angle && (c->phase == MC_CTRL_SLS_ALIGN) &&
              (oe == MC_FLUXOBS_ERR_DIVERGED))) {
            err |= MC_CTRL_SLS_ERR_DIVERGED;
        }
    }
    if (cfg->align_any_angle && (c->phase == MC_CTRL_SLS_ALIGN)) {
        align_track(c, i_al, i_be);
    }
    theta_hat = c->obs.theta_e_rad;
    (void)mc_spdpll_f32_step(&c->pll, theta_hat, &omega_hat_e);
    omega_hat_m = omega_hat_e / pp;

    /* 2. reference: the drive's shaped one (ref_from_drive; the phase logic
     * then reads it as the command too), or the law's own slew */
    if (cfg->ref_from_drive) {
        if (!m->have_speed_ref) {
            return MC_CTRL_SLS_ERR_REF;
        }
        c->omega_ref_m_rad_s = m->omega_ref_rad_s;
        c->omega_cmd_m_rad_s = m->omega_ref_rad_s;
    } else {
        c->omega_ref_m_rad_s = slew_f32(c->omega_ref_m_rad_s, c->omega_cmd_m_rad_s,
                                        cfg->speed_slew_rad_s2 * cfg->dt_s);
    }
    cmd = c->omega_cmd_m_rad_s;
    c->t_phase_s += cfg->dt_s;

    /* 3. phase logic */
    if ((c->phase == MC_CTRL_SLS_ALIGN) && !cfg->align_any_angle) {
        c->i_if_a =
            (cfg->align_time_s > 0.0f)
                ? (cfg->if_current_a * mc_sat_f32(c->t_phase_s / cfg->align_time_s, 0.0f, 1.0f))
                : cfg->if_current_a;
        if ((c->t_phase_s >= cfg->align_time_s) && (cmd != 0.0f)) {
            c->phase = MC_CTRL_SLS_IF;
            c->dir = sign_f32(cmd);
            c->t_phase_s = 0.0f;
            c->t_lockwait_s = 0.0f;
        }
    } else if (c->phase == MC_CTRL_SLS_ALIGN) {
        /* Two holds, a quarter turn apart in the run's direction: the
         * current ramps up along dir pi/2 in the first half of align_time,
         * then holds at dir pi (the I-f frame at dir pi - pi/2, its q
         * axis). A rotor whose d axis sits opposite one hold's current
         * feels no torque from it (an unstable rest), but the full torque
         * from the other: from any start the rotor ends at the second
         * hold's angle, reached from the first in the run's direction. A
         * rotor at the observer's reset guess (0) feels the first hold a
         * quarter turn ahead: the full torque forwards, which holds an
         * active load from the moment the current exceeds it (holds along
         * 0, then pi/2 let such a load turn it backwards while the first
         * current, along its d axis, gave no torque: issue 31, -8 rad/s
         * on the D5065). dir is the command's direction (its ramp's with
         * ref_from_drive: the ramp may start from a rotor turning the
         * other way), latched at the first step that has one. */
        const float half_s = 0.5f * cfg->align_time_s;
        if (!c->align_dir_set) {
            const float hint = (cfg->ref_from_drive && (m->alpha_ref_rad_s2 != 0.0f))
                                   ? sign_f32(m->alpha_ref_rad_s2)
                                   : ((cmd != 0.0f) ? sign_f32(cmd) : 0.0f);
            if (hint != 0.0f) {
                c->dir = hint;
                c->align_dir_set = true;
            }
        }
        c->i_if_a = (half_s > 0.0f)
                        ? (cfg->if_current_a * mc_sat_f32(c->t_phase_s / half_s, 0.0f, 1.0f))
                        : cfg->if_current_a;
        c->theta_if_e_rad = mc_wrap_pi_f32(
            (c->dir * ((c->t_phase_s < half_s) ? ALIGN_LEAD1 : ALIGN_LEAD2)) - MC_HALF_PI_F32);
        /* Observer and PLL restart at the rotor's angle, not from the
         * reset guess, which knew nothing of the start angle: from the
         * circle fit of the flux path once the rotor has moved enough for
         * it (the hold waits for that up to ALIGN_WAIT align times: the
         * rotor is barely damped and may still swing), else along the
         * hold's current (the I-f frame's q axis), where a rotor that has
         * not moved under the full hold current sits. */
        float theta_rotor = c->theta_if_e_rad + MC_HALF_PI_F32;
        float theta_fit = 0.0f;
        const bool fitted = (c->t_phase_s >= cfg->align_time_s) && align_fit(c, &theta_fit);
        if ((cmd != 0.0f) && (fitted || (c->t_phase_s >= (ALIGN_WAIT * cfg->align_time_s)))) {
            if (fitted) {
                theta_rotor = theta_fit;
                if_frame_to_rotor(c, theta_rotor, sign_f32(cmd));
            }
            (void)mc_fluxobs_f32_reset(&c->obs, theta_rotor, i_al, i_be);
            (void)mc_spdpll_f32_reset(&c->pll, theta_rotor, 0.0f);
            theta_hat = c->obs.theta_e_rad;
            omega_hat_e = 0.0f;
            omega_hat_m = 0.0f;
            c->phase = MC_CTRL_SLS_IF;
            c->dir = sign_f32(cmd);
            c->t_phase_s = 0.0f;
            c->t_lockwait_s = 0.0f;
        }
    } else if (c->phase == MC_CTRL_SLS_IF) {
        const float target = pp * mc_sat_f32(c->omega_ref_m_rad_s, -cfg->handover_speed_rad_s,
                                             cfg->handover_speed_rad_s);
        c->omega_if_e_rad_s =
            slew_f32(c->omega_if_e_rad_s, target, cfg->if_accel_rad_s2 * pp * cfg->dt_s);
        c->i_if_a = slew_f32(c->i_if_a, cfg->if_current_a,
                             cfg->if_current_a * cfg->dt_s / cfg->blend_time_s);
        if ((mc_abs_f32(cmd) > cfg->handover_speed_rad_s) &&
            (mc_abs_f32(c->omega_if_e_rad_s) >= (0.999f * ho_e))) {
            const bool locked = (mc_abs_f32(omega_hat_e - c->omega_if_e_rad_s) <=
                                 (cfg->lock_tol * mc_abs_f32(c->omega_if_e_rad_s))) &&
                                ((c->obs.flags & MC_FLUXOBS_ERR_DIVERGED) == 0u);
            if (locked) {
                handover_to_closed(c, omega_hat_e);
            } else {
                c->t_lockwait_s += cfg->dt_s;
                if (c->t_lockwait_s > cfg->if_lock_timeout_s) {
                    err |= MC_CTRL_SLS_ERR_NO_LOCK;
                }
            }
        }
    } else {
        const float lo = cfg->handover_speed_rad_s * (1.0f - cfg->handover_hyst);
        if (cfg->lowspeed_fallback && (mc_abs_f32(cmd) < lo) && (mc_abs_f32(omega_hat_m) < lo)) {
            fallback_to_if(c, theta_hat, omega_hat_e);
        }
    }

    /* the torque limit: the configured one, or the drive's current limit in
     * force (a lower limit set at run time) over the I-f vector's 1.25 */
    lim = ((m->i_max_a / 1.25f) < cfg->iq_max_a) ? (m->i_max_a / 1.25f) : cfg->iq_max_a;
    if (c->phase == MC_CTRL_SLS_CLOSED) {
        /* speed loop at dt * speed_div; the integrator tracks what the
         * drive's regenerative limit applied, saturates at the limit */
        if (m->regen_scale < 1.0f) {
            (void)mc_pi_f32_track(&c->speed_pi, m->iq_applied_a);
        }
        c->speed_count++;
        if (c->speed_count >= cfg->speed_div) {
            c->speed_count = 0u;
            (void)mc_pi_f32_step_lim(&c->speed_pi, c->omega_ref_m_rad_s - omega_hat_m, 0.0f, -lim,
                                     lim, &c->iq_ref_a);
            sls_mtpa_refs(c);
        }
        /* id from the hand-over goes to MTPA's (0 if non-salient) over blend_time */
        c->id_ref_a =
            slew_f32(c->id_ref_a, c->id_mtpa_a, cfg->if_current_a * cfg->dt_s / cfg->blend_time_s);
        theta_ctrl = theta_hat;
        omega_ctrl = omega_hat_e;
    } else {
        float damp_a = 0.0f;
        float sd;
        float cd;
        if (c->phase == MC_CTRL_SLS_IF) {
            c->theta_if_e_rad =
                mc_wrap_pi_f32(c->theta_if_e_rad + (c->omega_if_e_rad_s * cfg->dt_s));
            if (cfg->if_damping) {
                /* Active damping of the I-f "spring": a current along the
                 * estimated rotor q axis, -kp_speed (omega_hat - omega_if),
                 * limited to half the I-f current. Not in ALIGN: from
                 * standstill the observer's angle is still the reset guess
                 * (no information at zero speed, Prop. 4 i). */
                damp_a =
                    mc_sat_f32(-cfg->speed_kp_a_s_rad * ((omega_hat_e - c->omega_if_e_rad_s) / pp),
                               -0.5f * cfg->if_current_a, 0.5f * cfg->if_current_a);
            }
        }
        /* rotor q axis seen from the I-f frame: angle theta_hat - theta_if */
        mc_sincos_f32(theta_hat - c->theta_if_e_rad, &sd, &cd);
        c->id_ref_a = -damp_a * sd;
        c->iq_ref_a = c->i_if_a + (damp_a * cd);
        theta_ctrl = c->theta_if_e_rad;
        omega_ctrl = 0.0f;
    }

    /* 4. the drive's current loop: the references in the frame the law
     * controls (the rotor's estimate once closed), the voltage kept across
     * a frame jump */
    out->id_ref_a = c->id_ref_a;
    out->iq_ref_a = c->iq_ref_a;
    out->theta_e_rad = theta_ctrl;
    out->omega_e_rad_s = omega_ctrl;
    out->rotor_frame = c->phase == MC_CTRL_SLS_CLOSED;
    out->reframe = c->reframe;
    c->reframe = false;

    c->tm.phase = c->phase;
    c->tm.theta_hat_e_rad = theta_hat;
    c->tm.omega_hat_m_rad_s = omega_hat_m;
    c->tm.theta_ctrl_e_rad = theta_ctrl;
    c->tm.omega_ref_m_rad_s = c->omega_ref_m_rad_s;
    c->tm.omega_if_m_rad_s = c->omega_if_e_rad_s / pp;
    c->tm.i_alpha_a = i_al;
    c->tm.i_beta_a = i_be;
    c->tm.id_ref_a = c->id_ref_a;
    c->tm.iq_ref_a = c->iq_ref_a;
    c->tm.obs_resid = c->obs.resid;
    return err;
}
