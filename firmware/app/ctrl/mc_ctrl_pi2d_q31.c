/**
 * @file mc_ctrl_pi2d_q31.c
 * @brief q31 PI^2D control law plugged into the drive (see mc_ctrl_pi2d_q31.h).
 */
#include "mc_ctrl_pi2d_q31.h"

#include <stddef.h>

#include "math/mc_math.h"
#include "mc_pu.h"
#include "transforms/mc_svpwm_q31.h"
#include "transforms/mc_transforms.h"

#define PI2D_Q31_TWOPI 6.28318530717958647692

/* The encoder step the short way: d - 2 pi round(d / 2 pi) (IEEE remainder)
 * for |d| < 2 pi + 2^-20 (two angles in [0, 2 pi]). Exact: when a turn is
 * taken off, d and 2 pi are within a factor of two of each other, so the
 * difference is representable (Sterbenz). */
static double pi2d_q31_wrap_pi(double d)
{
    const double half = 0.5 * PI2D_Q31_TWOPI;
    if (d > half) {
        return d - PI2D_Q31_TWOPI;
    }
    if (d < -half) {
        return d + PI2D_Q31_TWOPI;
    }
    return d;
}

static uint32_t ctrl_reset(void *ctx)
{
    mc_ctrl_pi2d_q31_t *c = (mc_ctrl_pi2d_q31_t *)ctx;
    if (c == NULL) {
        return MC_CTRL_PI2D_ERR_NULL;
    }
    c->law_err = mc_pi2d_q31_reset(&c->law, 0, 0);
    c->theta_ref_rad = 0.0;
    c->theta_rel_rad = 0.0;
    c->have_prev = false;
    return (c->law_err == 0u) ? MC_CTRL_PI2D_ERR_NONE : MC_CTRL_PI2D_ERR_LAW;
}

static uint32_t ctrl_fast(void *ctx, const mc_drive_meas_t *m, mc_drive_out_t *out)
{
    mc_ctrl_pi2d_q31_t *c = (mc_ctrl_pi2d_q31_t *)ctx;
    if ((c == NULL) || (m == NULL) || (out == NULL)) {
        return MC_CTRL_PI2D_ERR_NULL;
    }
    if (!m->have_encoder || !mc_isfinite_f32(m->theta_m_rad) || !mc_isfinite_f32(m->theta_e_rad) ||
        !mc_isfinite_f32(m->ia_a) || !mc_isfinite_f32(m->ib_a) || !mc_isfinite_f32(m->vbus_v) ||
        !(m->vbus_v > 0.0f)) {
        return MC_CTRL_PI2D_ERR_MEAS;
    }
    const mc_pi2d_q31_bases_t *b = &c->cfg.law.base;

    /* Unwrap the encoder into the common origin. On the first step the
     * reference starts where the rotor is (e4 = 0). */
    const double theta_m = (double)m->theta_m_rad;
    if (c->have_prev) {
        c->theta_rel_rad += pi2d_q31_wrap_pi(theta_m - c->theta_m_prev_rad);
    } else {
        c->theta_rel_rad = 0.0;
        c->have_prev = true;
    }
    c->theta_m_prev_rad = theta_m;

    const q31_t ia = mc_pu_to_q31((double)m->ia_a, (double)b->i_base_a);
    const q31_t ib = mc_pu_to_q31((double)m->ib_a, (double)b->i_base_a);
    q31_t i_alpha, i_beta, s, co, id, iq;
    mc_clarke_q31(ia, ib, &i_alpha, &i_beta);
    mc_sincos_q31(mc_q31_angle_from_rad_f32(m->theta_e_rad), &s, &co);
    mc_park_q31(i_alpha, i_beta, s, co, &id, &iq);

    mc_pi2d_q31_in_t in;
    in.id = id;
    in.iq = iq;
    in.theta_m = mc_pu_to_q31(c->theta_rel_rad, (double)b->theta_base_rad);
    in.theta_ref = mc_pu_to_q31(c->theta_ref_rad, (double)b->theta_base_rad);
    in.omega_ref = mc_pu_to_q31(c->omega_ref_rad_s, (double)b->omega_base_rad_s);
    in.alpha_ref = mc_pu_to_q31(c->alpha_ref_rad_s2, (double)b->alpha_base_rad_s2);
    in.jerk_ref = mc_pu_to_q31(c->jerk_ref_rad_s3, (double)b->jerk_base_rad_s3);
    in.id_ref = mc_pu_to_q31(c->id_ref_a, (double)b->i_base_a);
    in.did_ref = 0;
    mc_pi2d_q31_out_t o;
    const uint32_t err = mc_pi2d_q31_step(&c->law, &in, &o);
    if (err != MC_PI2D_ERR_NONE) {
        c->law_err = err;
        return MC_CTRL_PI2D_ERR_STEP;
    }

    q31_t v_alpha, v_beta, da, db, dc;
    mc_inv_park_q31(o.vd, o.vq, s, co, &v_alpha, &v_beta);
    c->tm.svpwm_flags =
        mc_svpwm_q31(v_alpha, v_beta, mc_pu_to_q31((double)m->vbus_v, (double)b->v_base_v),
                     c->cfg.limit_mode, &da, &db, &dc);
    out->duty_a = (float)mc_pu_from_q31(da, 1.0);
    out->duty_b = (float)mc_pu_from_q31(db, 1.0);
    out->duty_c = (float)mc_pu_from_q31(dc, 1.0);
    out->duty2_a = 0.0f;
    out->duty2_b = 0.0f;

    c->tm.id = id;
    c->tm.iq = iq;
    c->tm.id_ref = o.id_ref;
    c->tm.iq_ref = o.iq_ref;
    c->tm.vd = o.vd;
    c->tm.vq = o.vq;
    c->tm.omega_ref = in.omega_ref;
    c->tm.e4 = o.e4;
    c->tm.theta_f = o.theta_f;
    c->tm.nu = o.nu;

    /* Advance the reference by one period (exact for constant alpha), and
     * move the common origin by whole turns. */
    const double dt = c->cfg.dt_s;
    c->theta_ref_rad += (c->omega_ref_rad_s * dt) + (((0.5 * c->alpha_ref_rad_s2) * dt) * dt);
    c->omega_ref_rad_s += c->alpha_ref_rad_s2 * dt;
    if (c->theta_ref_rad >= PI2D_Q31_TWOPI) {
        c->theta_ref_rad -= PI2D_Q31_TWOPI;
        c->theta_rel_rad -= PI2D_Q31_TWOPI;
    } else if (c->theta_ref_rad < 0.0) {
        c->theta_ref_rad += PI2D_Q31_TWOPI;
        c->theta_rel_rad += PI2D_Q31_TWOPI;
    } else {
        /* inside [0, 2 pi): nothing to move */
    }
    return MC_CTRL_PI2D_ERR_NONE;
}

uint32_t mc_ctrl_pi2d_q31_init(mc_ctrl_pi2d_q31_t *c, const mc_ctrl_pi2d_q31_cfg_t *cfg)
{
    if ((c == NULL) || (cfg == NULL)) {
        return MC_CTRL_PI2D_ERR_NULL;
    }
    uint32_t err = MC_CTRL_PI2D_ERR_NONE;
    if ((cfg->limit_mode != MC_SVPWM_LIMIT_CIRCLE) && (cfg->limit_mode != MC_SVPWM_LIMIT_HEXAGON)) {
        err |= MC_CTRL_PI2D_ERR_LIMIT;
    }
    /* dt_s finite and positive (NaN fails both comparisons), and the law's
     * float period its rounding */
    if (!(cfg->dt_s > 0.0) || !(cfg->dt_s < 1.0) || ((float)cfg->dt_s != cfg->law.f.dt_s)) {
        err |= MC_CTRL_PI2D_ERR_PERIOD;
    }
    mc_pi2d_q31_t law;
    if (mc_pi2d_q31_init(&law, &cfg->law) != MC_PI2D_ERR_NONE) {
        err |= MC_CTRL_PI2D_ERR_LAW;
    }
    if (err != MC_CTRL_PI2D_ERR_NONE) {
        return err;
    }
    const mc_ctrl_pi2d_q31_tm_t tm0 = {0};
    c->cfg = *cfg;
    c->law = law;
    c->law_err = 0u;
    c->omega_ref_rad_s = 0.0;
    c->alpha_ref_rad_s2 = 0.0;
    c->jerk_ref_rad_s3 = 0.0;
    c->id_ref_a = 0.0;
    c->theta_ref_rad = 0.0;
    c->theta_rel_rad = 0.0;
    c->theta_m_prev_rad = 0.0;
    c->have_prev = false;
    c->tm = tm0;
    c->ops = (mc_drive_ctrl_t){.outputs = MC_DRIVE_OUT_PWM3,
                               .needs_encoder = true,
                               .reset = ctrl_reset,
                               .fast = ctrl_fast,
                               .ctx = c};
    return MC_CTRL_PI2D_ERR_NONE;
}

const mc_drive_ctrl_t *mc_ctrl_pi2d_q31_ops(mc_ctrl_pi2d_q31_t *c)
{
    return (c == NULL) ? NULL : &c->ops;
}

uint32_t mc_ctrl_pi2d_q31_set_ref(mc_ctrl_pi2d_q31_t *c, float omega_ref_rad_s,
                                  float alpha_ref_rad_s2, float jerk_ref_rad_s3, float id_ref_a)
{
    if (c == NULL) {
        return MC_CTRL_PI2D_ERR_NULL;
    }
    if (!mc_isfinite_f32(omega_ref_rad_s) || !mc_isfinite_f32(alpha_ref_rad_s2) ||
        !mc_isfinite_f32(jerk_ref_rad_s3) || !mc_isfinite_f32(id_ref_a)) {
        return MC_CTRL_PI2D_ERR_REF;
    }
    c->omega_ref_rad_s = (double)omega_ref_rad_s;
    c->alpha_ref_rad_s2 = (double)alpha_ref_rad_s2;
    c->jerk_ref_rad_s3 = (double)jerk_ref_rad_s3;
    c->id_ref_a = (double)id_ref_a;
    return MC_CTRL_PI2D_ERR_NONE;
}
