/**
 * @file mc_csmc_q31.c
 * @brief CSMC / ideal SMC, q31 twin (see mc_csmc_q31.h).
 */
#include "csmc/mc_csmc_q31.h"

#include <stdbool.h>
#include <stddef.h>

#include "math/mc_math.h"

static bool cq_pos(float x)
{
    return (x > 0.0f) && mc_isfinite_f32(x);
}

static bool cq_bases_ok(const mc_csmc_q31_bases_t *b)
{
    return cq_pos(b->i_base_a) && cq_pos(b->theta_base_rad) && cq_pos(b->omega_base_rad_s) &&
           cq_pos(b->alpha_base_rad_s2) && cq_pos(b->did_base_a_s) && cq_pos(b->jerk_base_rad_s3) &&
           cq_pos(b->g_base_rad_s3) && cq_pos(b->v_base_v);
}

/* A constant (engineering value / base) as Q46, false if beyond 2^15 pu. */
static bool cq_const(float v, int64_t *p)
{
    mc_q46_gain_t g;
    if (!mc_q46_gain_from_f32(v, &g) || !(mc_abs_f32(v) < 32768.0f)) {
        return false;
    }
    *p = mc_q46_mul(g, MC_Q46_ONE);
    return true;
}

static uint32_t cq_sigma(const mc_csmc_f32_cfg_t *f, const mc_csvc_f32_model_t *m, float mu,
                         float s_base, mc_csvc_q31_t *p_sv, uint32_t *p_have)
{
    mc_csvc_q31_cfg_t c;

    if (m->order == 0u) {
        *p_have = 0u;
        return MC_CSVC_ERR_NONE;
    }
    c.f.model = *m;
    c.f.mu = mu;
    c.f.dt_s = f->dt_s;
    c.s_base = s_base;
    *p_have = 1u;
    return mc_csvc_q31_init(p_sv, &c);
}

uint32_t mc_csmc_q31_init(mc_csmc_q31_t *st, const mc_csmc_q31_cfg_t *cfg)
{
    mc_csmc_f32_t ref;
    uint32_t err;
    mc_csmc_q31_t t = {0};
    const mc_csmc_f32_cfg_t *f;
    const mc_csmc_q31_bases_t *b;
    bool ok = true;

    if ((st == NULL) || (cfg == NULL)) {
        return MC_CSMC_ERR_NULL;
    }
    f = &cfg->f;
    b = &cfg->base;
    err = mc_csmc_f32_init(&ref, f);
    if (!cq_bases_ok(b)) {
        err |= MC_CSMC_ERR_SCALE;
    }
    if (err != MC_CSMC_ERR_NONE) {
        return err;
    }
    t.law = f->law;
    t.sw = f->sw;
    t.have_sigma1 = 0u;
    t.have_sigma2 = 0u;
    if ((cq_sigma(f, &f->sigma1, f->mu1_a, b->i_base_a, &t.sigma1, &t.have_sigma1) !=
         MC_CSVC_ERR_NONE) ||
        (cq_sigma(f, &f->sigma2, f->mu2_rad_s2, b->alpha_base_rad_s2, &t.sigma2, &t.have_sigma2) !=
         MC_CSVC_ERR_NONE)) {
        return MC_CSMC_ERR_SCALE;
    }
    ok = ok && mc_q46_gain_from_f32((f->k1_per_s2 * b->theta_base_rad) / b->alpha_base_rad_s2,
                                    &t.g_s2_e2);
    ok = ok && mc_q46_gain_from_f32((f->k2_per_s * b->omega_base_rad_s) / b->alpha_base_rad_s2,
                                    &t.g_s2_de2);
    ok = ok && mc_q46_gain_from_f32(1.0f, &t.g_s2_dde2);
    ok = ok && mc_q46_gain_from_f32(b->i_base_a / f->mu1_a, &t.g_inv_mu1);
    ok = ok && mc_q46_gain_from_f32(b->alpha_base_rad_s2 / f->mu2_rad_s2, &t.g_inv_mu2);
    ok = ok && mc_q46_gain_from_f32((f->law == MC_CSMC_LAW_CONST) ? (f->m1_v / b->v_base_v) : 0.0f,
                                    &t.g_m1);
    ok = ok && mc_q46_gain_from_f32((f->law == MC_CSMC_LAW_CONST) ? (f->m2_v / b->v_base_v) : 0.0f,
                                    &t.g_m2);
    t.g_const_q46 = 0;
    t.q1_q46 = 0;
    t.q2_q46 = 0;
    {
        /* LAW_MODEL constants (zero for LAW_CONST: ref.k3 etc. are 0 there) */
        const mc_csmc_f32_model_t *m = &f->model;
        const bool model = (f->law == MC_CSMC_LAW_MODEL);
        const float k5 = model ? (float)m->rotor_teeth : 0.0f;
        const float gb = b->g_base_rad_s3;
        const float vb = b->v_base_v;
        const float inv_k3 = ref.inv_k3;
        ok = ok && mc_q46_gain_from_f32(
                       ((k5 * b->i_base_a) * b->omega_base_rad_s) / b->did_base_a_s, &t.g_f1_x23);
        ok = ok && mc_q46_gain_from_f32((f->k1_per_s2 * b->omega_base_rad_s) / gb, &t.g_g_de2);
        ok = ok && mc_q46_gain_from_f32((f->k2_per_s * b->alpha_base_rad_s2) / gb, &t.g_g_dde2);
        ok = ok && mc_q46_gain_from_f32(-b->jerk_base_rad_s3 / gb, &t.g_g_jerk);
        ok = ok && mc_q46_gain_from_f32(-((ref.k4 * ref.k3) * b->i_base_a) / gb, &t.g_g_x2);
        ok = ok && mc_q46_gain_from_f32(((ref.k4 * ref.k4) * b->omega_base_rad_s) / gb, &t.g_g_x3);
        ok = ok && mc_q46_gain_from_f32(-(((ref.k3 * k5) * b->i_base_a) * b->omega_base_rad_s) / gb,
                                        &t.g_g_x13);
        ok = ok && cq_const((ref.k4 * ref.d0) / gb, &t.g_const_q46);
        ok =
            ok && mc_q46_gain_from_f32(model ? ((m->r_nom_ohm * b->i_base_a) / vb) : 0.0f, &t.g_rx);
        ok = ok &&
             mc_q46_gain_from_f32(model ? ((m->l_nom_h * b->did_base_a_s) / vb) : 0.0f, &t.g_lf);
        ok = ok && mc_q46_gain_from_f32(model ? ((m->km_nm_a * b->omega_base_rad_s) / vb) : 0.0f,
                                        &t.g_km);
        ok = ok && mc_q46_gain_from_f32(((m->l_nom_h * inv_k3) * gb) / vb, &t.g_lg);
        ok = ok && mc_q46_gain_from_f32((ref.dr_ohm * b->i_base_a) / vb, &t.g_b_dr);
        ok = ok && mc_q46_gain_from_f32((ref.dl_h * b->did_base_a_s) / vb, &t.g_b1_dl);
        ok = ok && mc_q46_gain_from_f32(((ref.dl_h * inv_k3) * gb) / vb, &t.g_b2_dl);
        ok = ok && cq_const(model ? (m->q1_v / vb) : 0.0f, &t.q1_q46);
        ok = ok && cq_const(model ? ((inv_k3 * m->q2_radh_s3) / vb) : 0.0f, &t.q2_q46);
    }
    if (!ok) {
        return MC_CSMC_ERR_SCALE;
    }
    t.v_lim_q46 = mc_q46_from_q31(mc_q31_from_f32(f->v_limit_v / b->v_base_v));
    if (t.v_lim_q46 <= 0) {
        return MC_CSMC_ERR_SCALE;
    }
    t.out.v_d = 0;
    t.out.v_q = 0;
    t.out.s1 = 0;
    t.out.s2 = 0;
    *st = t;
    return MC_CSMC_ERR_NONE;
}

uint32_t mc_csmc_q31_reset(mc_csmc_q31_t *st)
{
    if (st == NULL) {
        return MC_CSMC_ERR_NULL;
    }
    (void)mc_csvc_q31_reset(&st->sigma1);
    (void)mc_csvc_q31_reset(&st->sigma2);
    st->out.v_d = 0;
    st->out.v_q = 0;
    st->out.s1 = 0;
    st->out.s2 = 0;
    return MC_CSMC_ERR_NONE;
}

/* psi = sat(s/mu) or sgn(s), q31 */
static q31_t cq_psi(mc_csmc_sw_t sw, int64_t s_q46, mc_q46_gain_t inv_mu)
{
    if (sw == MC_CSMC_SW_SGN) {
        if (s_q46 > 0) {
            return MC_Q31_MAX;
        }
        return (s_q46 < 0) ? MC_Q31_MIN : 0;
    }
    return mc_q46_to_q31(mc_q46_clamp(mc_q46_mul(inv_mu, s_q46), -MC_Q46_ONE, MC_Q46_ONE));
}

uint32_t mc_csmc_q31_step(mc_csmc_q31_t *st, const mc_csmc_q31_in_t *in, mc_csmc_q31_out_t *p_out)
{
    int64_t s1;
    int64_t s2;
    q31_t psi1;
    q31_t psi2;
    int64_t u1;
    int64_t u2;

    if ((st == NULL) || (in == NULL) || (p_out == NULL)) {
        return MC_CSMC_ERR_NULL;
    }
    s1 = mc_q46_from_q31(in->e1);
    s2 = mc_q46_mul_q31(st->g_s2_e2, in->e2);
    s2 = mc_q46_add(s2, mc_q46_mul_q31(st->g_s2_de2, in->de2));
    s2 = mc_q46_add(s2, mc_q46_mul_q31(st->g_s2_dde2, in->dde2));
    if (st->have_sigma1 != 0u) {
        s1 = mc_q46_add(s1, mc_csvc_q31_term_q46(&st->sigma1));
    }
    if (st->have_sigma2 != 0u) {
        s2 = mc_q46_add(s2, mc_csvc_q31_term_q46(&st->sigma2));
    }
    psi1 = cq_psi(st->sw, s1, st->g_inv_mu1);
    psi2 = cq_psi(st->sw, s2, st->g_inv_mu2);
    if (st->law == MC_CSMC_LAW_CONST) {
        u1 = -mc_q46_mul_q31(st->g_m1, psi1);
        u2 = -mc_q46_mul_q31(st->g_m2, psi2);
    } else {
        const q31_t x13 = mc_q31_mul(in->i_d, in->omega_m);
        int64_t f1;
        int64_t g;
        int64_t lb1;
        int64_t lb2;
        mc_q46_gain_t p;
        /* F1 = k5 x2 x3 - I_dd' (did_base) */
        f1 = mc_q46_add(mc_q46_mul_q31(st->g_f1_x23, mc_q31_mul(in->i_q, in->omega_m)),
                        -mc_q46_from_q31(in->di_dd));
        /* G (g_base) */
        g = mc_q46_mul_q31(st->g_g_de2, in->de2);
        g = mc_q46_add(g, mc_q46_mul_q31(st->g_g_dde2, in->dde2));
        g = mc_q46_add(g, mc_q46_mul_q31(st->g_g_jerk, in->dddphi_d));
        g = mc_q46_add(g, mc_q46_mul_q31(st->g_g_x2, in->i_q));
        g = mc_q46_add(g, mc_q46_mul_q31(st->g_g_x3, in->omega_m));
        g = mc_q46_add(g, st->g_const_q46);
        g = mc_q46_add(g, mc_q46_mul_q31(st->g_g_x13, x13));
        /* L^ beta_1 and L^ beta_2 / k3 (v_base) */
        lb1 = mc_q46_mul_q31(st->g_b_dr, mc_q31_abs_sat(in->i_d));
        lb1 = mc_q46_add(lb1, mc_q46_mul(st->g_b1_dl, mc_q46_abs(f1)));
        lb1 = mc_q46_add(lb1, st->q1_q46);
        lb2 = mc_q46_mul_q31(st->g_b_dr, mc_q31_abs_sat(in->i_q));
        lb2 = mc_q46_add(lb2, mc_q46_mul(st->g_b2_dl, mc_q46_abs(g)));
        lb2 = mc_q46_add(lb2, st->q2_q46);
        /* u1 = R^ x1 - L^ F1 - lb1 psi1 */
        u1 = mc_q46_mul_q31(st->g_rx, in->i_d);
        u1 = mc_q46_add(u1, -mc_q46_mul(st->g_lf, f1));
        p.mant = psi1;
        p.shift = 0;
        u1 = mc_q46_add(u1, -mc_q46_mul(p, lb1));
        /* u2 = R^ x2 + Km x3 - (L^/k3) G - lb2 psi2 */
        u2 = mc_q46_mul_q31(st->g_rx, in->i_q);
        u2 = mc_q46_add(u2, mc_q46_mul_q31(st->g_km, in->omega_m));
        u2 = mc_q46_add(u2, -mc_q46_mul(st->g_lg, g));
        p.mant = psi2;
        u2 = mc_q46_add(u2, -mc_q46_mul(p, lb2));
    }
    st->out.v_d = mc_q46_to_q31(mc_q46_clamp(u1, -st->v_lim_q46, st->v_lim_q46));
    st->out.v_q = mc_q46_to_q31(mc_q46_clamp(u2, -st->v_lim_q46, st->v_lim_q46));
    st->out.s1 = mc_q46_to_q31(s1);
    st->out.s2 = mc_q46_to_q31(s2);
    if (st->have_sigma1 != 0u) {
        mc_csvc_q31_update(&st->sigma1, s1);
    }
    if (st->have_sigma2 != 0u) {
        mc_csvc_q31_update(&st->sigma2, s2);
    }
    *p_out = st->out;
    return MC_CSMC_ERR_NONE;
}
