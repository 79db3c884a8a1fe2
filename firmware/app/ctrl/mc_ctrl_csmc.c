/**
 * @file mc_ctrl_csmc.c
 * @brief CSMC stepper position loop as a drive plug-in (see mc_ctrl_csmc.h).
 */
#include "mc_ctrl_csmc.h"

#include <stddef.h>

#include "csmc/mc_stepper_dq.h"
#include "math/mc_math.h"

static uint32_t ctrl_reset(void *ctx)
{
    mc_ctrl_csmc_t *c = (mc_ctrl_csmc_t *)ctx;
    if (c->cfg.feedback == MC_CTRL_CSMC_FB_HGO) {
        mc_csmc_hgo_f32_reset(&c->ctl);
    } else {
        mc_csmc_f32_reset(&c->ctl.law);
    }
    c->pos = (mc_ctrl_csmc_pos_t){false, 0u, 0, 0.0f};
    return MC_CTRL_CSMC_ERR_NONE;
}

float mc_ctrl_csmc_step_pos(mc_ctrl_csmc_pos_t *p, const mc_drive_meas_t *m)
{
    const uint32_t cpr = m->enc_cpr;
    const uint32_t count = (m->enc_count < cpr) ? m->enc_count : (m->enc_count % cpr);
    if (!p->have_pos) {
        p->have_pos = true;
        p->pos_counts = 0;
        p->phi0_rad = mc_wrap_pi_f32(m->theta_m_rad);
    } else {
        /* shortest signed step on the circle of cpr counts */
        uint32_t fwd =
            (count >= p->last_count) ? (count - p->last_count) : (cpr - (p->last_count - count));
        if (fwd > (cpr / 2u)) {
            p->pos_counts -= (int32_t)(cpr - fwd);
        } else {
            p->pos_counts += (int32_t)fwd;
        }
    }
    p->last_count = count;
    return p->phi0_rad + (((float)p->pos_counts * MC_TWO_PI_F32) / (float)cpr);
}

uint32_t mc_ctrl_csmc_step(mc_ctrl_csmc_t *c, const mc_ctrl_csmc_meas_t *m)
{
    float s;
    float co;

    if ((c == NULL) || (m == NULL)) {
        return MC_CTRL_CSMC_ERR_NULL;
    }
    mc_ctrl_csmc_tm_t *tm = &c->tm;
    mc_sincos_f32(m->theta_e_rad, &s, &co);
    mc_stepper_ab_to_dq_sc_f32(m->ia_a, m->ib_a, s, co, &tm->i_d_a, &tm->i_q_a);
    tm->phi_rad = m->phi_rad;
    if (c->cfg.feedback == MC_CTRL_CSMC_FB_STATE) {
        if (mc_csmc_f32_err_from_state(&c->cfg.law.model, tm->i_d_a, tm->i_q_a, m->omega_m_rad_s,
                                       m->phi_rad, c->ref.i_dd_a, c->ref.phi_d_rad,
                                       c->ref.dphi_d_rad_s, c->ref.ddphi_d_rad_s2,
                                       &tm->in) != MC_CSMC_ERR_NONE) {
            return MC_CTRL_CSMC_ERR_STEP;
        }
        tm->in.e2_rad = m->e2_rad;
        tm->in.di_dd_a_s = c->ref.di_dd_a_s;
        tm->in.dddphi_d_rad_s3 = c->ref.dddphi_d_rad_s3;
        mc_csmc_f32_step(&c->ctl.law, &tm->in, &tm->out);
        if (c->ctl.law.flags != MC_CSMC_ERR_NONE) {
            return MC_CTRL_CSMC_ERR_STEP;
        }
    } else {
        /* observer and law in one step; the estimates it uses are the
         * observer's state before the step (telemetry) */
        tm->est.z1 = c->ctl.hgo.z[0];
        tm->est.z2 = c->ctl.hgo.z[1];
        tm->est.z3 = c->ctl.hgo.z[2];
        tm->in.e1_a = tm->i_d_a - c->ref.i_dd_a;
        tm->in.e2_rad = m->e2_rad;
        tm->in.de2_rad_s = tm->est.z2;
        tm->in.dde2_rad_s2 = tm->est.z3;
        tm->in.i_d_a = tm->i_d_a;
        tm->in.i_q_a = tm->i_q_a;
        tm->in.omega_m_rad_s = m->omega_m_rad_s;
        tm->in.di_dd_a_s = c->ref.di_dd_a_s;
        tm->in.dddphi_d_rad_s3 = c->ref.dddphi_d_rad_s3;
        if (mc_csmc_hgo_f32_step(&c->ctl, tm->in.e1_a, m->e2_rad, &tm->in, &tm->out) !=
            MC_CSMC_ERR_NONE) {
            return MC_CTRL_CSMC_ERR_STEP;
        }
    }
    mc_stepper_dq_to_ab_sc_f32(tm->out.v_d_v, tm->out.v_q_v, s, co, &tm->v_a_v, &tm->v_b_v);
    return MC_CTRL_CSMC_ERR_NONE;
}

static uint32_t ctrl_fast(void *ctx, const mc_drive_meas_t *m, mc_drive_out_t *out)
{
    mc_ctrl_csmc_t *c = (mc_ctrl_csmc_t *)ctx;
    mc_ctrl_csmc_meas_t cm;

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
    cm.e2_rad = cm.phi_rad - c->ref.phi_d_rad;
    const uint32_t err = mc_ctrl_csmc_step(c, &cm);
    if (err != MC_CTRL_CSMC_ERR_NONE) {
        return err;
    }
    const float inv_vbus = 1.0f / m->vbus_v;
    const float lim = c->cfg.duty_max;
    out->duty2_a = mc_sat_f32(c->tm.v_a_v * inv_vbus, -lim, lim);
    out->duty2_b = mc_sat_f32(c->tm.v_b_v * inv_vbus, -lim, lim);
    return MC_CTRL_CSMC_ERR_NONE;
}

uint32_t mc_ctrl_csmc_init(mc_ctrl_csmc_t *c, const mc_ctrl_csmc_cfg_t *cfg)
{
    uint32_t err = MC_CTRL_CSMC_ERR_NONE;
    mc_csmc_hgo_f32_t ctl;
    mc_csmc_f32_in_t probe;

    if ((c == NULL) || (cfg == NULL)) {
        return MC_CTRL_CSMC_ERR_NULL;
    }
    if (cfg->feedback == MC_CTRL_CSMC_FB_HGO) {
        const uint32_t e = mc_csmc_hgo_f32_init(&ctl, &cfg->law, &cfg->hgo);
        if ((e & ~MC_CSMC_ERR_HGO) != MC_CSMC_ERR_NONE) {
            err |= MC_CTRL_CSMC_ERR_LAW;
        }
        if ((e & MC_CSMC_ERR_HGO) != 0u) {
            err |= MC_CTRL_CSMC_ERR_HGO;
        }
    } else {
        if (mc_csmc_f32_init(&ctl.law, &cfg->law) != MC_CSMC_ERR_NONE) {
            err |= MC_CTRL_CSMC_ERR_LAW;
        }
        if (cfg->feedback == MC_CTRL_CSMC_FB_STATE) {
            /* the model must give e2'' (K_m, J > 0 ...) */
            if (mc_csmc_f32_err_from_state(&cfg->law.model, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f,
                                           0.0f, 0.0f, &probe) != MC_CSMC_ERR_NONE) {
                err |= MC_CTRL_CSMC_ERR_FEEDBACK;
            }
        } else {
            err |= MC_CTRL_CSMC_ERR_FEEDBACK;
        }
    }
    if (!(cfg->duty_max > 0.0f) || !(cfg->duty_max <= 1.0f)) {
        err |= MC_CTRL_CSMC_ERR_DUTY;
    }
    if (err != MC_CTRL_CSMC_ERR_NONE) {
        return err;
    }
    c->cfg = *cfg;
    c->ctl = ctl;
    c->ref = (mc_ctrl_csmc_ref_t){0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f};
    (void)ctrl_reset(c);
    c->tm.phi_rad = 0.0f;
    c->tm.i_d_a = 0.0f;
    c->tm.i_q_a = 0.0f;
    c->tm.in = (mc_csmc_f32_in_t){0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f};
    c->tm.out = (mc_csmc_f32_out_t){0.0f, 0.0f, 0.0f, 0.0f};
    c->tm.v_a_v = 0.0f;
    c->tm.v_b_v = 0.0f;
    c->tm.est = (mc_hgo_f32_est_t){0.0f, 0.0f, 0.0f};
    c->ops = (mc_drive_ctrl_t){.outputs = MC_DRIVE_OUT_PWM2,
                               .needs_encoder = true,
                               .reset = ctrl_reset,
                               .fast = ctrl_fast,
                               .ctx = c};
    return MC_CTRL_CSMC_ERR_NONE;
}

const mc_drive_ctrl_t *mc_ctrl_csmc_ops(mc_ctrl_csmc_t *c)
{
    return (c == NULL) ? NULL : &c->ops;
}

uint32_t mc_ctrl_csmc_set_ref_in(mc_ctrl_csmc_ref_t *r, float phi_d_rad, float dphi_d_rad_s,
                                 float ddphi_d_rad_s2, float dddphi_d_rad_s3, float i_dd_a,
                                 float di_dd_a_s)
{
    if (r == NULL) {
        return MC_CTRL_CSMC_ERR_NULL;
    }
    if (!mc_isfinite_f32(phi_d_rad) || !mc_isfinite_f32(dphi_d_rad_s) ||
        !mc_isfinite_f32(ddphi_d_rad_s2) || !mc_isfinite_f32(dddphi_d_rad_s3) ||
        !mc_isfinite_f32(i_dd_a) || !mc_isfinite_f32(di_dd_a_s)) {
        return MC_CTRL_CSMC_ERR_REF;
    }
    *r = (mc_ctrl_csmc_ref_t){phi_d_rad,       dphi_d_rad_s, ddphi_d_rad_s2,
                              dddphi_d_rad_s3, i_dd_a,       di_dd_a_s};
    return MC_CTRL_CSMC_ERR_NONE;
}

uint32_t mc_ctrl_csmc_set_ref(mc_ctrl_csmc_t *c, float phi_d_rad, float dphi_d_rad_s,
                              float ddphi_d_rad_s2, float dddphi_d_rad_s3, float i_dd_a,
                              float di_dd_a_s)
{
    return mc_ctrl_csmc_set_ref_in((c == NULL) ? NULL : &c->ref, phi_d_rad, dphi_d_rad_s,
                                   ddphi_d_rad_s2, dddphi_d_rad_s3, i_dd_a, di_dd_a_s);
}
