/**
 * @file mc_ctrl_csmc_q31.c
 * @brief q31 CSMC stepper position loop as a drive plug-in (see
 *        mc_ctrl_csmc_q31.h).
 */
#include "mc_ctrl_csmc_q31.h"

#include <stddef.h>

#include "csmc/mc_stepper_dq.h"
#include "math/mc_math.h"
#include "mc_pu.h"

static uint32_t ctrl_reset(void *ctx)
{
    mc_ctrl_csmc_q31_t *c = (mc_ctrl_csmc_q31_t *)ctx;
    (void)mc_csmc_q31_reset(&c->law);
    c->pos = (mc_ctrl_csmc_pos_t){false, 0u, 0, 0.0f};
    return MC_CTRL_CSMC_ERR_NONE;
}

uint32_t mc_ctrl_csmc_q31_step(mc_ctrl_csmc_q31_t *c, const mc_ctrl_csmc_q31_meas_t *m)
{
    float s;
    float co;

    if ((c == NULL) || (m == NULL)) {
        return MC_CTRL_CSMC_ERR_NULL;
    }
    mc_ctrl_csmc_q31_tm_t *tm = &c->tm;
    const mc_csmc_q31_bases_t *b = &c->cfg.law.base;
    mc_sincos_f32(m->theta_e_rad, &s, &co);
    mc_stepper_ab_to_dq_sc_f32(m->ia_a, m->ib_a, s, co, &tm->i_d_a, &tm->i_q_a);
    tm->phi_rad = m->phi_rad;
    if (mc_csmc_f32_err_from_state(&c->cfg.law.f.model, tm->i_d_a, tm->i_q_a, m->omega_m_rad_s,
                                   m->phi_rad, c->ref.i_dd_a, c->ref.phi_d_rad, c->ref.dphi_d_rad_s,
                                   c->ref.ddphi_d_rad_s2, &tm->fin) != MC_CSMC_ERR_NONE) {
        return MC_CTRL_CSMC_ERR_STEP;
    }
    tm->in.e1 = mc_pu_to_q31((double)tm->fin.e1_a, (double)b->i_base_a);
    tm->in.e2 = m->e2;
    tm->in.de2 = mc_pu_to_q31((double)tm->fin.de2_rad_s, (double)b->omega_base_rad_s);
    tm->in.dde2 = mc_pu_to_q31((double)tm->fin.dde2_rad_s2, (double)b->alpha_base_rad_s2);
    tm->in.i_d = mc_pu_to_q31((double)tm->i_d_a, (double)b->i_base_a);
    tm->in.i_q = mc_pu_to_q31((double)tm->i_q_a, (double)b->i_base_a);
    tm->in.omega_m = mc_pu_to_q31((double)m->omega_m_rad_s, (double)b->omega_base_rad_s);
    tm->in.di_dd = mc_pu_to_q31((double)c->ref.di_dd_a_s, (double)b->did_base_a_s);
    tm->in.dddphi_d = mc_pu_to_q31((double)c->ref.dddphi_d_rad_s3, (double)b->jerk_base_rad_s3);
    if (mc_csmc_q31_step(&c->law, &tm->in, &tm->out) != MC_CSMC_ERR_NONE) {
        return MC_CTRL_CSMC_ERR_STEP;
    }
    tm->v_d_v = (float)mc_pu_from_q31(tm->out.v_d, (double)b->v_base_v);
    tm->v_q_v = (float)mc_pu_from_q31(tm->out.v_q, (double)b->v_base_v);
    mc_stepper_dq_to_ab_sc_f32(tm->v_d_v, tm->v_q_v, s, co, &tm->v_a_v, &tm->v_b_v);
    return MC_CTRL_CSMC_ERR_NONE;
}

static uint32_t ctrl_fast(void *ctx, const mc_drive_meas_t *m, mc_drive_out_t *out)
{
    mc_ctrl_csmc_q31_t *c = (mc_ctrl_csmc_q31_t *)ctx;
    mc_ctrl_csmc_q31_meas_t cm;

    out->duty2_a = 0.0f;
    out->duty2_b = 0.0f;
    if (!m->have_encoder || (m->enc_cpr == 0u)) {
        return MC_CTRL_CSMC_ERR_ENCODER;
    }
    if (!(m->vbus_v > 0.0f) || !mc_isfinite_f32(m->vbus_v)) {
        return MC_CTRL_CSMC_ERR_VBUS;
    }
    cm.ia_a = m->ia_a;
    cm.ib_a = m->ib_a;
    cm.theta_e_rad = m->theta_e_rad;
    cm.omega_m_rad_s = m->omega_m_rad_s;
    cm.phi_rad = mc_ctrl_csmc_step_pos(&c->pos, m);
    cm.e2 = mc_pu_to_q31((double)(cm.phi_rad - c->ref.phi_d_rad),
                         (double)c->cfg.law.base.theta_base_rad);
    const uint32_t err = mc_ctrl_csmc_q31_step(c, &cm);
    if (err != MC_CTRL_CSMC_ERR_NONE) {
        return err;
    }
    const float inv_vbus = 1.0f / m->vbus_v;
    const float lim = c->cfg.duty_max;
    out->duty2_a = mc_sat_f32(c->tm.v_a_v * inv_vbus, -lim, lim);
    out->duty2_b = mc_sat_f32(c->tm.v_b_v * inv_vbus, -lim, lim);
    return MC_CTRL_CSMC_ERR_NONE;
}

uint32_t mc_ctrl_csmc_q31_init(mc_ctrl_csmc_q31_t *c, const mc_ctrl_csmc_q31_cfg_t *cfg)
{
    uint32_t err = MC_CTRL_CSMC_ERR_NONE;
    mc_csmc_q31_t law;
    mc_csmc_f32_in_t probe;

    if ((c == NULL) || (cfg == NULL)) {
        return MC_CTRL_CSMC_ERR_NULL;
    }
    if (mc_csmc_q31_init(&law, &cfg->law) != MC_CSMC_ERR_NONE) {
        err |= MC_CTRL_CSMC_ERR_LAW;
    }
    /* state feedback only; the model must give e2'' (K_m, J > 0 ...) */
    if ((cfg->feedback != MC_CTRL_CSMC_FB_STATE) ||
        (mc_csmc_f32_err_from_state(&cfg->law.f.model, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f,
                                    0.0f, &probe) != MC_CSMC_ERR_NONE)) {
        err |= MC_CTRL_CSMC_ERR_FEEDBACK;
    }
    if (!(cfg->duty_max > 0.0f) || !(cfg->duty_max <= 1.0f)) {
        err |= MC_CTRL_CSMC_ERR_DUTY;
    }
    if (err != MC_CTRL_CSMC_ERR_NONE) {
        return err;
    }
    const mc_ctrl_csmc_q31_tm_t tm0 = {0};
    c->cfg = *cfg;
    c->law = law;
    c->ref = (mc_ctrl_csmc_ref_t){0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f};
    (void)ctrl_reset(c);
    c->tm = tm0;
    c->ops = (mc_drive_ctrl_t){.outputs = MC_DRIVE_OUT_PWM2,
                               .needs_encoder = true,
                               .reset = ctrl_reset,
                               .fast = ctrl_fast,
                               .ctx = c};
    return MC_CTRL_CSMC_ERR_NONE;
}

const mc_drive_ctrl_t *mc_ctrl_csmc_q31_ops(mc_ctrl_csmc_q31_t *c)
{
    return (c == NULL) ? NULL : &c->ops;
}

uint32_t mc_ctrl_csmc_q31_set_ref(mc_ctrl_csmc_q31_t *c, float phi_d_rad, float dphi_d_rad_s,
                                  float ddphi_d_rad_s2, float dddphi_d_rad_s3, float i_dd_a,
                                  float di_dd_a_s)
{
    return mc_ctrl_csmc_set_ref_in((c == NULL) ? NULL : &c->ref, phi_d_rad, dphi_d_rad_s,
                                   ddphi_d_rad_s2, dddphi_d_rad_s3, i_dd_a, di_dd_a_s);
}
