/**
 * @file mc_foc_q31.c
 * @brief dq current controller, q31 twin (see mc_foc_q31.h).
 */
#include "foc/mc_foc_q31.h"

#include <stddef.h>

#include "math/mc_math.h"
#include "transforms/mc_svpwm.h"
#include "transforms/mc_svpwm_q31.h"
#include "transforms/mc_transforms.h"

static bool fq31_pos(float x)
{
    return (x > 0.0f) && mc_isfinite_f32(x);
}

/* The advance gain for a valid periods (MC_FOC_ERR_SCALE if it does not fit,
 * nothing written then). */
static uint32_t foc_q31_set_adv(mc_foc_q31_t *st, float periods)
{
    mc_q46_gain_t g;

    if (!mc_q46_gain_from_f32(periods * st->adv_pu_per_period, &g)) {
        return MC_FOC_ERR_SCALE;
    }
    st->g_adv = g;
    st->delay_comp_periods = periods;
    st->pred_d = mc_q31_from_f32(mc_foc_f32_eval_pred_weight(periods, 1.0f, st->bw_dt_d, 1.0f));
    st->pred_q = mc_q31_from_f32(mc_foc_f32_eval_pred_weight(periods, 1.0f, st->bw_dt_q, 1.0f));
    return MC_FOC_ERR_NONE;
}

uint32_t mc_foc_q31_set_delay_comp(mc_foc_q31_t *st, float periods)
{
    if (st == NULL) {
        return MC_FOC_ERR_NULL;
    }
    if (!mc_foc_f32_validate_delay_comp(periods)) {
        return MC_FOC_ERR_DELAY;
    }
    return foc_q31_set_adv(st, periods);
}

uint32_t mc_foc_q31_init(mc_foc_q31_t *st, const mc_foc_q31_cfg_t *cfg)
{
    mc_foc_f32_t ref;
    uint32_t err;
    mc_foc_q31_t t;
    mc_pi_f32_cfg_t pc;
    mc_pi_q31_cfg_t qc;
    const mc_foc_f32_cfg_t *f;
    float k;

    if ((st == NULL) || (cfg == NULL)) {
        return MC_FOC_ERR_NULL;
    }
    f = &cfg->f;
    err = mc_foc_f32_init(&ref, f);
    if (f->limit_mode != MC_SVPWM_LIMIT_CIRCLE) {
        err |= MC_FOC_ERR_LIMIT_MODE;
    }
    if (!fq31_pos(cfg->i_base_a) || !fq31_pos(cfg->v_base_v) || !fq31_pos(cfg->omega_base_rad_s)) {
        err |= MC_FOC_ERR_SCALE;
    }
    if (err != MC_FOC_ERR_NONE) {
        return err;
    }
    pc.kp = f->kp_d_v_per_a;
    pc.ki_per_s = f->ki_d_v_per_as;
    pc.dt_s = f->dt_s;
    pc.out_max = f->v_abs_max_v;
    pc.out_min = -f->v_abs_max_v;
    pc.aw = f->aw;
    pc.kaw_per_s = f->kaw_per_s;
    if ((mc_pi_q31_cfg_from_f32(&pc, cfg->i_base_a, cfg->v_base_v, &qc) != MC_PI_ERR_NONE) ||
        (mc_pi_q31_init(&t.pi_d, &qc) != MC_PI_ERR_NONE)) {
        return MC_FOC_ERR_SCALE;
    }
    pc.kp = f->kp_q_v_per_a;
    pc.ki_per_s = f->ki_q_v_per_as;
    if ((mc_pi_q31_cfg_from_f32(&pc, cfg->i_base_a, cfg->v_base_v, &qc) != MC_PI_ERR_NONE) ||
        (mc_pi_q31_init(&t.pi_q, &qc) != MC_PI_ERR_NONE)) {
        return MC_FOC_ERR_SCALE;
    }
    k = (cfg->omega_base_rad_s * cfg->i_base_a) / cfg->v_base_v;
    if (!mc_q46_gain_from_f32(k * f->lq_h, &t.g_ff_d) ||
        !mc_q46_gain_from_f32(k * f->ld_h, &t.g_ff_q) ||
        !mc_q46_gain_from_f32((cfg->omega_base_rad_s * f->flux_wb) / cfg->v_base_v, &t.g_ff_psi) ||
        !mc_q46_gain_from_f32(f->v_limit_ratio * mc_svpwm_max_voltage_f32(1.0f, f->limit_mode),
                              &t.g_vmax)) {
        return MC_FOC_ERR_SCALE;
    }
    t.adv_pu_per_period = (f->dt_s * cfg->omega_base_rad_s) / MC_PI_F32;
    t.bw_dt_d = f->dt_s * (f->kp_d_v_per_a / f->ld_h);
    t.bw_dt_q = f->dt_s * (f->kp_q_v_per_a / f->lq_h);
    if (foc_q31_set_adv(&t, ref.delay_comp_periods) != MC_FOC_ERR_NONE) {
        return MC_FOC_ERR_SCALE;
    }
    t.decouple = f->decouple;
    t.vd = 0;
    t.vq = 0;
    t.flags = MC_FOC_ERR_NONE;
    *st = t;
    return MC_FOC_ERR_NONE;
}

uint32_t mc_foc_q31_reset(mc_foc_q31_t *st)
{
    if (st == NULL) {
        return MC_FOC_ERR_NULL;
    }
    (void)mc_pi_q31_reset(&st->pi_d, 0);
    (void)mc_pi_q31_reset(&st->pi_q, 0);
    st->vd = 0;
    st->vq = 0;
    st->flags = MC_FOC_ERR_NONE;
    return MC_FOC_ERR_NONE;
}

/* The dq step proper, vbus > 0. */
static void foc_q31_core(mc_foc_q31_t *st, q31_t id_ref, q31_t iq_ref, q31_t id, q31_t iq,
                         q31_t omega_e, q31_t vbus, q31_t *p_vd, q31_t *p_vq)
{
    const q31_t v_max = mc_q46_to_q31(mc_q46_mul_q31(st->g_vmax, vbus));
    q31_t ff_d = 0;
    q31_t ff_q = 0;
    q31_t vd;
    q31_t vq_max;
    uint64_t room;

    if (st->decouple) {
        /* the currents predicted for the voltage's interval (mc_foc_q31.h) */
        const q31_t id_ff = mc_q31_add_sat(id, mc_q31_mul(st->pred_d, mc_q31_sub_sat(id_ref, id)));
        const q31_t iq_ff = mc_q31_add_sat(iq, mc_q31_mul(st->pred_q, mc_q31_sub_sat(iq_ref, iq)));
        ff_d = mc_q46_to_q31(-mc_q46_mul_q31(st->g_ff_d, mc_q31_mul(omega_e, iq_ff)));
        ff_q = mc_q46_to_q31(mc_q46_add(mc_q46_mul_q31(st->g_ff_q, mc_q31_mul(omega_e, id_ff)),
                                        mc_q46_mul_q31(st->g_ff_psi, omega_e)));
    }
    (void)mc_pi_q31_step_lim(&st->pi_d, mc_q31_sub_sat(id_ref, id), ff_d, (q31_t)-v_max, v_max,
                             &vd);
    /* |vd| <= v_max: the Q62 difference is >= 0 and < 2^62 */
    room = (uint64_t)(((int64_t)v_max * (int64_t)v_max) - ((int64_t)vd * (int64_t)vd));
    vq_max = (q31_t)mc_isqrt_u64(room, NULL);
    *p_vd = vd;
    (void)mc_pi_q31_step_lim(&st->pi_q, mc_q31_sub_sat(iq_ref, iq), ff_q, (q31_t)-vq_max, vq_max,
                             p_vq);
}

uint32_t mc_foc_q31_step_dq(mc_foc_q31_t *st, q31_t id_ref, q31_t iq_ref, q31_t id, q31_t iq,
                            q31_t omega_e, q31_t vbus, q31_t *p_vd, q31_t *p_vq)
{
    q31_t vd = 0;
    q31_t vq = 0;
    uint32_t err = MC_FOC_ERR_NONE;

    if ((st == NULL) || (p_vd == NULL) || (p_vq == NULL)) {
        return MC_FOC_ERR_NULL;
    }
    if (vbus <= 0) {
        err = MC_FOC_ERR_VBUS;
    } else {
        foc_q31_core(st, id_ref, iq_ref, id, iq, omega_e, vbus, &vd, &vq);
    }
    st->flags |= err;
    st->vd = vd;
    st->vq = vq;
    *p_vd = vd;
    *p_vq = vq;
    return err;
}

uint32_t mc_foc_q31_step(mc_foc_q31_t *st, const mc_foc_q31_in_t *in, mc_foc_q31_out_t *out)
{
    q31_t i_alpha;
    q31_t i_beta;
    q31_t s;
    q31_t c;
    q31_t s_v;
    q31_t c_v;
    q31_t id;
    q31_t iq;
    q31_t vd = 0;
    q31_t vq = 0;
    q31_t va = 0;
    q31_t vb = 0;

    if ((st == NULL) || (in == NULL) || (out == NULL)) {
        return MC_FOC_ERR_NULL;
    }
    if (in->three_phase) {
        mc_clarke3_q31(in->ia, in->ib, in->ic, &i_alpha, &i_beta);
    } else {
        mc_clarke_q31(in->ia, in->ib, &i_alpha, &i_beta);
    }
    mc_sincos_q31(in->theta_e, &s, &c);
    mc_park_q31(i_alpha, i_beta, s, c, &id, &iq);
    out->id = id;
    out->iq = iq;
    if (in->vbus <= 0) {
        st->flags |= MC_FOC_ERR_VBUS;
        st->vd = 0;
        st->vq = 0;
        out->duty_a = (q31_t)1 << 30;
        out->duty_b = (q31_t)1 << 30;
        out->duty_c = (q31_t)1 << 30;
        out->vd = 0;
        out->vq = 0;
        out->v_alpha = 0;
        out->v_beta = 0;
        out->svpwm_flags = MC_SVPWM_FLAG_NONE;
        out->flags = st->flags;
        return MC_FOC_ERR_VBUS;
    }
    foc_q31_core(st, in->id_ref, in->iq_ref, id, iq, in->omega_e, in->vbus, &vd, &vq);
    if (st->delay_comp_periods > 0.0f) {
        mc_sincos_q31(mc_foc_q31_eval_voltage_angle(st, in->theta_e, in->omega_e), &s_v, &c_v);
    } else {
        s_v = s;
        c_v = c;
    }
    mc_inv_park_q31(vd, vq, s_v, c_v, &va, &vb);
    out->svpwm_flags = mc_svpwm_q31(va, vb, in->vbus, MC_SVPWM_LIMIT_CIRCLE, &out->duty_a,
                                    &out->duty_b, &out->duty_c);
    st->vd = vd;
    st->vq = vq;
    out->vd = vd;
    out->vq = vq;
    out->v_alpha = va;
    out->v_beta = vb;
    out->flags = st->flags;
    return MC_FOC_ERR_NONE;
}
