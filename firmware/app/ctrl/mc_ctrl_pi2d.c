/**
 * @file mc_ctrl_pi2d.c
 * @brief PI^2D control law plugged into the drive (see mc_ctrl_pi2d.h).
 */
#include "mc_ctrl_pi2d.h"

#include <stddef.h>

#include "math/mc_math.h"
#include "transforms/mc_transforms.h"

static uint32_t ctrl_reset(void *ctx)
{
    mc_ctrl_pi2d_t *c = (mc_ctrl_pi2d_t *)ctx;
    if (c == NULL) {
        return MC_CTRL_PI2D_ERR_NULL;
    }
    c->law_err = mc_pi2d_f32_reset(&c->law, 0.0f, 0.0f);
    c->theta_ref_rad = 0.0f;
    c->theta_rel_rad = 0.0f;
    c->have_prev = false;
    return (c->law_err == 0u) ? MC_CTRL_PI2D_ERR_NONE : MC_CTRL_PI2D_ERR_LAW;
}

static uint32_t ctrl_fast(void *ctx, const mc_drive_meas_t *m, mc_drive_out_t *out)
{
    mc_ctrl_pi2d_t *c = (mc_ctrl_pi2d_t *)ctx;
    if ((c == NULL) || (m == NULL) || (out == NULL)) {
        return MC_CTRL_PI2D_ERR_NULL;
    }
    if (!m->have_encoder || !mc_isfinite_f32(m->theta_m_rad) || !(m->vbus_v > 0.0f)) {
        return MC_CTRL_PI2D_ERR_MEAS;
    }
    /* Unwrap the encoder into the common origin. On the first step the
     * reference starts where the rotor is (e4 = 0). */
    if (c->have_prev) {
        c->theta_rel_rad += mc_wrap_pi_f32(m->theta_m_rad - c->theta_m_prev_rad);
    } else {
        c->theta_rel_rad = 0.0f;
        c->have_prev = true;
    }
    c->theta_m_prev_rad = m->theta_m_rad;
    if (c->cfg.ref_from_drive) {
        /* the drive's shaped reference (its ramp and controlled stop) */
        if (!m->have_speed_ref) {
            return MC_CTRL_PI2D_ERR_REF;
        }
        c->omega_ref_rad_s = m->omega_ref_rad_s;
        c->alpha_ref_rad_s2 = m->alpha_ref_rad_s2;
        c->jerk_ref_rad_s3 = 0.0f;
    }
    {
        /* the drive's current limit in force, when it is below the law's */
        const float lim = (m->i_max_a > 0.0f) && (m->i_max_a < c->cfg.law.iq_max_a)
                              ? m->i_max_a
                              : c->cfg.law.iq_max_a;
        if (lim != c->law.cfg.iq_max_a) {
            (void)mc_pi2d_f32_set_iq_max(&c->law, lim);
        }
    }

    float i_alpha, i_beta, s, co, id, iq;
    mc_clarke_f32(m->ia_a, m->ib_a, &i_alpha, &i_beta);
    mc_sincos_f32(m->theta_e_rad, &s, &co);
    mc_park_f32(i_alpha, i_beta, s, co, &id, &iq);

    mc_pi2d_f32_in_t in;
    in.id_a = id;
    in.iq_a = iq;
    in.theta_m_rad = c->theta_rel_rad;
    in.theta_ref_rad = c->theta_ref_rad;
    in.omega_ref_rad_s = c->omega_ref_rad_s;
    in.alpha_ref_rad_s2 = c->alpha_ref_rad_s2;
    in.jerk_ref_rad_s3 = c->jerk_ref_rad_s3;
    in.id_ref_a = c->id_ref_a;
    in.did_ref_a_s = 0.0f;
    mc_pi2d_f32_out_t o;
    const uint32_t err = mc_pi2d_f32_step(&c->law, &in, &o);
    if (err != MC_PI2D_ERR_NONE) {
        c->law_err = err;
        return MC_CTRL_PI2D_ERR_STEP;
    }

    float v_alpha, v_beta;
    if (c->cfg.angle_advance_periods > 0.0f) {
        const float adv = c->cfg.angle_advance_periods * (float)c->cfg.law.pole_pairs *
                          c->omega_ref_rad_s * c->cfg.law.dt_s;
        mc_sincos_f32(mc_wrap_pi_f32(m->theta_e_rad + adv), &s, &co);
    }
    mc_inv_park_f32(o.vd_v, o.vq_v, s, co, &v_alpha, &v_beta);
    c->tm.svpwm_flags = mc_svpwm_f32(v_alpha, v_beta, m->vbus_v, c->cfg.limit_mode, &out->duty_a,
                                     &out->duty_b, &out->duty_c);
    out->duty2_a = 0.0f;
    out->duty2_b = 0.0f;

    c->tm.id_a = id;
    c->tm.iq_a = iq;
    c->tm.id_ref_a = o.id_ref_a;
    c->tm.iq_ref_a = o.iq_ref_a;
    c->tm.vd_v = o.vd_v;
    c->tm.vq_v = o.vq_v;
    c->tm.omega_ref_rad_s = c->omega_ref_rad_s;
    c->tm.e4_rad = o.e4_rad;
    c->tm.theta_f_rad = o.theta_f_rad;
    c->tm.nu_nm = o.nu_nm;

    /* Advance the reference by one period (exact for constant alpha), and
     * move the common origin by whole turns. */
    const float dt = c->cfg.law.dt_s;
    c->theta_ref_rad += (c->omega_ref_rad_s * dt) + (0.5f * c->alpha_ref_rad_s2 * dt * dt);
    c->omega_ref_rad_s += c->alpha_ref_rad_s2 * dt;
    if (c->theta_ref_rad >= MC_TWO_PI_F32) {
        c->theta_ref_rad -= MC_TWO_PI_F32;
        c->theta_rel_rad -= MC_TWO_PI_F32;
    } else if (c->theta_ref_rad < 0.0f) {
        c->theta_ref_rad += MC_TWO_PI_F32;
        c->theta_rel_rad += MC_TWO_PI_F32;
    } else {
        /* inside [0, 2 pi): nothing to move */
    }
    return MC_CTRL_PI2D_ERR_NONE;
}

uint32_t mc_ctrl_pi2d_init(mc_ctrl_pi2d_t *c, const mc_ctrl_pi2d_cfg_t *cfg)
{
    if ((c == NULL) || (cfg == NULL)) {
        return MC_CTRL_PI2D_ERR_NULL;
    }
    uint32_t err = MC_CTRL_PI2D_ERR_NONE;
    if ((cfg->limit_mode != MC_SVPWM_LIMIT_CIRCLE) && (cfg->limit_mode != MC_SVPWM_LIMIT_HEXAGON)) {
        err |= MC_CTRL_PI2D_ERR_LIMIT;
    }
    if (!mc_isfinite_f32(cfg->angle_advance_periods) || (cfg->angle_advance_periods < 0.0f) ||
        (cfg->angle_advance_periods > 4.0f)) {
        err |= MC_CTRL_PI2D_ERR_ADVANCE;
    }
    mc_pi2d_f32_t law;
    const uint32_t lerr = mc_pi2d_f32_init(&law, &cfg->law);
    if (lerr != MC_PI2D_ERR_NONE) {
        err |= MC_CTRL_PI2D_ERR_LAW;
    }
    if (err != MC_CTRL_PI2D_ERR_NONE) {
        return err;
    }
    const mc_ctrl_pi2d_tm_t tm0 = {0};
    c->cfg = *cfg;
    c->law = law;
    c->law_err = 0u;
    c->omega_ref_rad_s = 0.0f;
    c->alpha_ref_rad_s2 = 0.0f;
    c->jerk_ref_rad_s3 = 0.0f;
    c->id_ref_a = 0.0f;
    c->theta_ref_rad = 0.0f;
    c->theta_rel_rad = 0.0f;
    c->theta_m_prev_rad = 0.0f;
    c->have_prev = false;
    c->tm = tm0;
    c->ops = (mc_drive_ctrl_t){.outputs = MC_DRIVE_OUT_PWM3,
                               .needs_encoder = true,
                               .reset = ctrl_reset,
                               .fast = ctrl_fast,
                               .ctx = c,
                               .uses_speed_ref = cfg->ref_from_drive};
    return MC_CTRL_PI2D_ERR_NONE;
}

const mc_drive_ctrl_t *mc_ctrl_pi2d_ops(mc_ctrl_pi2d_t *c)
{
    return (c == NULL) ? NULL : &c->ops;
}

uint32_t mc_ctrl_pi2d_set_ref(mc_ctrl_pi2d_t *c, float omega_ref_rad_s, float alpha_ref_rad_s2,
                              float jerk_ref_rad_s3, float id_ref_a)
{
    if (c == NULL) {
        return MC_CTRL_PI2D_ERR_NULL;
    }
    if (!mc_isfinite_f32(omega_ref_rad_s) || !mc_isfinite_f32(alpha_ref_rad_s2) ||
        !mc_isfinite_f32(jerk_ref_rad_s3) || !mc_isfinite_f32(id_ref_a)) {
        return MC_CTRL_PI2D_ERR_REF;
    }
    c->omega_ref_rad_s = omega_ref_rad_s;
    c->alpha_ref_rad_s2 = alpha_ref_rad_s2;
    c->jerk_ref_rad_s3 = jerk_ref_rad_s3;
    c->id_ref_a = id_ref_a;
    return MC_CTRL_PI2D_ERR_NONE;
}
