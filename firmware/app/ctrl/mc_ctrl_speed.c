/**
 * @file mc_ctrl_speed.c
 * @brief The sensored speed law: see mc_ctrl_speed.h.
 */
#include "mc_ctrl_speed.h"

#include <stddef.h>

#include "math/mc_math.h"

static bool nonneg_finite(float x)
{
    return mc_isfinite_f32(x) && (x >= 0.0f);
}

uint32_t mc_ctrl_speed_init(mc_ctrl_speed_t *c, const mc_ctrl_speed_cfg_t *cfg)
{
    uint32_t err = MC_CTRL_SPEED_ERR_NONE;
    mc_pi_f32_cfg_t pc;
    if ((c == NULL) || (cfg == NULL)) {
        return MC_CTRL_SPEED_ERR_NULL;
    }
    if (!nonneg_finite(cfg->kp_a_s_rad) || !nonneg_finite(cfg->ki_a_rad) ||
        !mc_isfinite_f32(cfg->dt_s) || !(cfg->dt_s > 0.0f)) {
        err |= MC_CTRL_SPEED_ERR_GAIN;
    }
    if (!mc_isfinite_f32(cfg->kt_nm_a) || !(cfg->kt_nm_a > 0.0f) || !nonneg_finite(cfg->j_kgm2) ||
        !nonneg_finite(cfg->b_nm_s_rad) || (cfg->pole_pairs == 0u) ||
        !mc_isfinite_f32(cfg->iq_max_a) || !(cfg->iq_max_a > 0.0f)) {
        err |= MC_CTRL_SPEED_ERR_MODEL;
    }
    if (!nonneg_finite(cfg->ref_lag_s)) {
        err |= MC_CTRL_SPEED_ERR_GAIN;
    }
    if (err != MC_CTRL_SPEED_ERR_NONE) {
        return err;
    }
    pc.kp = cfg->kp_a_s_rad;
    pc.ki_per_s = cfg->ki_a_rad;
    pc.dt_s = cfg->dt_s;
    pc.out_min = -cfg->iq_max_a;
    pc.out_max = cfg->iq_max_a;
    pc.aw = MC_PI_AW_CLAMP;
    pc.kaw_per_s = 0.0f;
    if (mc_pi_f32_init(&c->pi, &pc) != MC_PI_ERR_NONE) {
        return MC_CTRL_SPEED_ERR_GAIN;
    }
    c->cfg = *cfg;
    c->ref_lag_alpha = cfg->dt_s / (cfg->ref_lag_s + cfg->dt_s);
    c->ops = (mc_drive_ctrl_t){.outputs = MC_DRIVE_OUT_CURRENT,
                               .needs_encoder = true,
                               .reset = mc_ctrl_speed_reset,
                               .fast = mc_ctrl_speed_fast,
                               .ctx = c,
                               .uses_speed_ref = true,
                               .cogging_ff = true};
    return mc_ctrl_speed_reset(c);
}

const mc_drive_ctrl_t *mc_ctrl_speed_ops(mc_ctrl_speed_t *c)
{
    return (c == NULL) ? NULL : &c->ops;
}

uint32_t mc_ctrl_speed_reset(void *ctx)
{
    mc_ctrl_speed_t *c = (mc_ctrl_speed_t *)ctx;
    const mc_ctrl_speed_tm_t z = {0};
    if (c == NULL) {
        return MC_CTRL_SPEED_ERR_NULL;
    }
    (void)mc_pi_f32_reset(&c->pi, 0.0f); /* a new run starts without old torque */
    c->tm = z;
    c->have_ref_lag = false;
    return MC_CTRL_SPEED_ERR_NONE;
}

uint32_t mc_ctrl_speed_fast(void *ctx, const mc_drive_meas_t *m, mc_drive_out_t *out)
{
    mc_ctrl_speed_t *c = (mc_ctrl_speed_t *)ctx;
    const mc_ctrl_speed_cfg_t *cfg;
    float lim;
    float ff;
    float iq = 0.0f;
    if ((c == NULL) || (m == NULL) || (out == NULL)) {
        return MC_CTRL_SPEED_ERR_NULL;
    }
    cfg = &c->cfg;
    if (!m->have_encoder || !m->have_speed_ref) {
        return MC_CTRL_SPEED_ERR_MEAS;
    }
    /* the drive's regenerative limit cut the last braking reference: the
     * integrator works against what was applied */
    if (m->regen_scale < 1.0f) {
        (void)mc_pi_f32_track(&c->pi, m->iq_applied_a);
        c->tm.tracked++;
    }
    lim = (m->i_max_a < cfg->iq_max_a) ? m->i_max_a : cfg->iq_max_a;
    ff = ((cfg->j_kgm2 * m->alpha_ref_rad_s2) + (cfg->b_nm_s_rad * m->omega_ref_rad_s)) /
         cfg->kt_nm_a;
    if (!mc_isfinite_f32(m->omega_m_rad_s) || !mc_isfinite_f32(m->omega_ref_rad_s)) {
        return MC_CTRL_SPEED_ERR_STEP; /* refused before it reaches the lag's state */
    }
    if (!c->have_ref_lag) {
        c->omega_ref_lag_rad_s = m->omega_m_rad_s; /* from where the rotor is */
        c->have_ref_lag = true;
    }
    c->omega_ref_lag_rad_s += c->ref_lag_alpha * (m->omega_ref_rad_s - c->omega_ref_lag_rad_s);
    if (mc_pi_f32_step_lim(&c->pi, c->omega_ref_lag_rad_s - m->omega_m_rad_s, ff, -lim, lim, &iq) !=
        MC_PI_ERR_NONE) {
        return MC_CTRL_SPEED_ERR_STEP;
    }
    if (mc_abs_f32(iq) >= lim) {
        c->tm.saturated++;
    }
    out->id_ref_a = 0.0f;
    out->iq_ref_a = iq;
    out->theta_e_rad = m->theta_e_rad;
    out->omega_e_rad_s = m->omega_m_rad_s * (float)cfg->pole_pairs;
    out->rotor_frame = true;
    out->reframe = false;
    c->tm.omega_ref_rad_s = m->omega_ref_rad_s;
    c->tm.alpha_ref_rad_s2 = m->alpha_ref_rad_s2;
    c->tm.iq_ff_a = ff;
    c->tm.iq_ref_a = iq;
    return MC_CTRL_SPEED_ERR_NONE;
}
