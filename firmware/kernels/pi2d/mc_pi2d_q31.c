/**
 * @file mc_pi2d_q31.c
 * @brief PI^2D speed controller, q31 twin (see mc_pi2d_q31.h).
 */
#include "pi2d/mc_pi2d_q31.h"

#include <stddef.h>

#include "math/mc_math.h"

static bool pq_pos(float x)
{
    return (x > 0.0f) && mc_isfinite_f32(x);
}

static bool pq_bases_ok(const mc_pi2d_q31_bases_t *b)
{
    return pq_pos(b->i_base_a) && pq_pos(b->v_base_v) && pq_pos(b->theta_base_rad) &&
           pq_pos(b->thetaf_base_rad) && pq_pos(b->omega_base_rad_s) &&
           pq_pos(b->alpha_base_rad_s2) && pq_pos(b->jerk_base_rad_s3) && pq_pos(b->did_base_a_s) &&
           pq_pos(b->nu_base_nm);
}

/* A limit in engineering units as Q46 of its base, clamped to one base. */
static int64_t pq_limit(float lim, float base)
{
    return mc_q46_from_q31(mc_q31_from_f32(lim / base));
}

uint32_t mc_pi2d_q31_init(mc_pi2d_q31_t *st, const mc_pi2d_q31_cfg_t *cfg)
{
    mc_pi2d_f32_t ref;
    uint32_t err;
    mc_pi2d_q31_t t;
    const mc_pi2d_f32_cfg_t *c;
    const mc_pi2d_q31_bases_t *b;
    bool ok = true;

    if ((st == NULL) || (cfg == NULL)) {
        return MC_PI2D_ERR_NULL;
    }
    c = &cfg->f;
    b = &cfg->base;
    err = mc_pi2d_f32_init(&ref, c);
    if (!pq_bases_ok(b)) {
        err |= MC_PI2D_ERR_SCALE;
    }
    if (err != MC_PI2D_ERR_NONE) {
        return err;
    }
    {
        const mc_ddiff_q31_cfg_t dc = {
            {c->a_per_s, c->b, c->dt_s}, b->theta_base_rad, b->thetaf_base_rad};
        if (mc_ddiff_q31_init(&t.dd, &dc) != MC_DDIFF_ERR_NONE) {
            return MC_PI2D_ERR_SCALE;
        }
    }
    {
        const float j_kt = c->j_kgm2 / c->kt_nm_a; /* [kg m^2 A/(N m)] */
        const float l = c->l_h;
        const float iv = b->i_base_a / b->v_base_v;
        const float ktib = c->kt_nm_a * b->i_base_a;
        const float th = b->theta_base_rad;
        const float thf = b->thetaf_base_rad;
        const float lrho = (l * j_kt) * c->ki_per_s3;               /* L J ki / kt */
        const float lv2 = (l * c->eps_per_s) * ref.sigma;           /* L eps sigma */
        const float lad = ((l * j_kt) * c->a_per_s) * c->kd_per_s2; /* L J a kd / kt */
        const float jki_dt = (c->j_kgm2 * c->ki_per_s3) * c->dt_s;

        ok = ok && mc_q46_gain_from_f32(b->nu_base_nm / ktib, &t.g_iq_nu);
        ok = ok && mc_q46_gain_from_f32((c->j_kgm2 * b->alpha_base_rad_s2) / ktib, &t.g_iq_alpha);
        ok = ok && mc_q46_gain_from_f32(-((c->j_kgm2 * c->kp_per_s2) * th) / ktib, &t.g_iq_e4);
        ok = ok && mc_q46_gain_from_f32(-((c->j_kgm2 * c->kd_per_s2) * thf) / ktib, &t.g_iq_th);

        ok = ok && mc_q46_gain_from_f32((l * c->k1_per_s) * iv, &t.g_u1_idref);
        ok = ok && mc_q46_gain_from_f32(-ref.r_minus_lk1 * iv, &t.g_u1_id);
        ok = ok && mc_q46_gain_from_f32((l * b->did_base_a_s) / b->v_base_v, &t.g_u1_did);
        ok = ok && mc_q46_gain_from_f32((ref.pl * b->omega_base_rad_s) * iv, &t.g_plw);

        ok = ok &&
             mc_q46_gain_from_f32((c->ke_v_s_rad * b->omega_base_rad_s) / b->v_base_v, &t.g_u2_w);
        ok = ok && mc_q46_gain_from_f32((l * c->k2_per_s) * iv, &t.g_u2_iqref);
        ok = ok && mc_q46_gain_from_f32(-ref.r_minus_lk2 * iv, &t.g_u2_iq);
        ok = ok && mc_q46_gain_from_f32(-((lrho + lv2) * th) / b->v_base_v, &t.g_u2_e4_rho);
        ok = ok && mc_q46_gain_from_f32(((lrho + lv2 + lad) * thf) / b->v_base_v, &t.g_u2_th_rho);
        ok = ok &&
             mc_q46_gain_from_f32(((l * j_kt) * b->jerk_base_rad_s3) / b->v_base_v, &t.g_u2_jerk);
        ok = ok && mc_q46_gain_from_f32(-(lv2 * th) / b->v_base_v, &t.g_u2_e4_v2);
        ok = ok && mc_q46_gain_from_f32((lv2 * thf) / b->v_base_v, &t.g_u2_th_v2);

        ok = ok && mc_q46_gain_from_f32(-(jki_dt * th) / b->nu_base_nm, &t.g_nu_e4);
        ok = ok && mc_q46_gain_from_f32((jki_dt * thf) / b->nu_base_nm, &t.g_nu_th);
    }
    if (!ok) {
        return MC_PI2D_ERR_SCALE;
    }
    t.iq_max_q46 = pq_limit(c->iq_max_a, b->i_base_a);
    t.v_max_q46 = pq_limit(c->v_max_v, b->v_base_v);
    t.nu_max_q46 = pq_limit(c->nu_max_nm, b->nu_base_nm);
    if ((t.iq_max_q46 <= 0) || (t.v_max_q46 <= 0) || (t.nu_max_q46 <= 0)) {
        return MC_PI2D_ERR_SCALE; /* a limit below one LSB of its base */
    }
    t.nu_q46 = 0;
    *st = t;
    return MC_PI2D_ERR_NONE;
}

uint32_t mc_pi2d_q31_reset(mc_pi2d_q31_t *st, q31_t qc0, q31_t nu0)
{
    if (st == NULL) {
        return MC_PI2D_ERR_NULL;
    }
    (void)mc_ddiff_q31_reset(&st->dd, qc0);
    st->nu_q46 = mc_q46_clamp(mc_q46_from_q31(nu0), -st->nu_max_q46, st->nu_max_q46);
    return MC_PI2D_ERR_NONE;
}

uint32_t mc_pi2d_q31_step(mc_pi2d_q31_t *st, const mc_pi2d_q31_in_t *in, mc_pi2d_q31_out_t *out)
{
    mc_pi2d_q31_out_t o;
    q31_t e4;
    q31_t th;
    int64_t iq_raw;
    int64_t iq_ref;
    q31_t iq_ref31;
    int64_t u1;
    int64_t u2;
    bool iq_lim;
    bool v_lim;

    if ((st == NULL) || (in == NULL) || (out == NULL)) {
        return MC_PI2D_ERR_NULL;
    }
    /* Position error and its dirty derivative, (11)-(12). */
    e4 = mc_q31_sub_sat(in->theta_m, in->theta_ref);
    (void)mc_ddiff_q31_step(&st->dd, e4, &th);

    /* x2* (8) and its clamp. */
    iq_raw = mc_q46_mul(st->g_iq_nu, st->nu_q46);
    iq_raw = mc_q46_add(iq_raw, mc_q46_mul_q31(st->g_iq_alpha, in->alpha_ref));
    iq_raw = mc_q46_add(iq_raw, mc_q46_mul_q31(st->g_iq_e4, e4));
    iq_raw = mc_q46_add(iq_raw, mc_q46_mul_q31(st->g_iq_th, th));
    iq_ref = mc_q46_clamp(iq_raw, -st->iq_max_q46, st->iq_max_q46);
    iq_lim = (iq_ref != iq_raw);
    iq_ref31 = mc_q46_to_q31(iq_ref);

    /* u1 (6) */
    u1 = mc_q46_mul_q31(st->g_u1_idref, in->id_ref);
    u1 = mc_q46_add(u1, mc_q46_mul_q31(st->g_u1_id, in->id));
    u1 = mc_q46_add(u1, mc_q46_mul_q31(st->g_u1_did, in->did_ref));
    u1 = mc_q46_add(u1, -mc_q46_mul_q31(st->g_plw, mc_q31_mul(in->iq, in->omega_ref)));

    /* u2 (14) with L (rho + v2) (35); rho = 0 while x2* is clamped. */
    u2 = mc_q46_mul_q31(st->g_u2_w, in->omega_ref);
    u2 = mc_q46_add(u2, mc_q46_mul_q31(st->g_plw, mc_q31_mul(in->id, in->omega_ref)));
    u2 = mc_q46_add(u2, mc_q46_mul_q31(st->g_u2_iqref, iq_ref31));
    u2 = mc_q46_add(u2, mc_q46_mul_q31(st->g_u2_iq, in->iq));
    if (iq_lim) {
        u2 = mc_q46_add(u2, mc_q46_mul_q31(st->g_u2_e4_v2, e4));
        u2 = mc_q46_add(u2, mc_q46_mul_q31(st->g_u2_th_v2, th));
    } else {
        u2 = mc_q46_add(u2, mc_q46_mul_q31(st->g_u2_e4_rho, e4));
        u2 = mc_q46_add(u2, mc_q46_mul_q31(st->g_u2_th_rho, th));
        u2 = mc_q46_add(u2, mc_q46_mul_q31(st->g_u2_jerk, in->jerk_ref));
    }

    /* Voltage circle, direction kept. */
    v_lim = mc_q46_limit_vec(&u1, &u2, st->v_max_q46);

    o.vd = mc_q46_to_q31(u1);
    o.vq = mc_q46_to_q31(u2);
    o.id_ref = in->id_ref;
    o.iq_ref = iq_ref31;
    o.e4 = e4;
    o.theta_f = th;
    o.nu = mc_q46_to_q31(st->nu_q46);
    o.iq_limited = iq_lim;
    o.v_limited = v_lim;

    /* Adaptation (10), forward Euler, conditional integration. */
    if (!iq_lim && !v_lim) {
        int64_t nu = mc_q46_add(st->nu_q46, mc_q46_mul_q31(st->g_nu_e4, e4));
        nu = mc_q46_add(nu, mc_q46_mul_q31(st->g_nu_th, th));
        st->nu_q46 = mc_q46_clamp(nu, -st->nu_max_q46, st->nu_max_q46);
    }
    *out = o;
    return MC_PI2D_ERR_NONE;
}
