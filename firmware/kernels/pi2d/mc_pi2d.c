/**
 * @file mc_pi2d.c
 * @brief PI^2D output-feedback speed controller and its gain certificate
 *        (see mc_pi2d.h for the equations and where they depart from the
 *        printed paper).
 */
#include "pi2d/mc_pi2d.h"

#include <float.h>
#include <stddef.h>
#include <string.h>

#include "math/mc_math.h"

/* |x| as the FPU's absolute value (one instruction; mc_abs_f32 keeps the
 * sign of -0, so the compiler cannot use it there). Only compared here. */
static inline float pi2d_fabs(float x)
{
    return __builtin_fabsf(x);
}

/* The next float above x, for x >= 0 finite. */
static float pi2d_next_up(float x)
{
    uint32_t b;
    memcpy(&b, &x, sizeof b);
    b += 1u;
    float r;
    memcpy(&r, &b, sizeof r);
    return r;
}

/* The next float below x, for x > 0 (inf gives FLT_MAX). */
static float pi2d_next_down(float x)
{
    uint32_t b;
    memcpy(&b, &x, sizeof b);
    b -= 1u;
    float r;
    memcpy(&r, &b, sizeof r);
    return r;
}

/* The largest float m with mc_sqrt_f32(m) <= v (v > 0 finite). The square
 * root is correctly rounded, hence monotone, so sqrt(x) > v exactly when
 * x > m: the step compares squares and takes a root only when the limit
 * acts. v^2 rounded is within an ulp or two of m; the loops correct that. */
static float pi2d_sq_threshold(float v)
{
    float m = v * v;
    for (uint32_t i = 0u; (i < 16u) && (mc_sqrt_f32(m) > v); ++i) {
        m = pi2d_next_down(m);
    }
    for (uint32_t i = 0u; (i < 16u) && (m < FLT_MAX) && (mc_sqrt_f32(pi2d_next_up(m)) <= v); ++i) {
        m = pi2d_next_up(m);
    }
    return m;
}

static bool pos_finite(float x)
{
    return mc_isfinite_f32(x) && (x > 0.0f);
}

static uint32_t validate(const mc_pi2d_f32_cfg_t *c)
{
    uint32_t err = MC_PI2D_ERR_NONE;
    if (!pos_finite(c->r_ohm) || !pos_finite(c->l_h) || (c->pole_pairs == 0u) ||
        !mc_isfinite_f32(c->ke_v_s_rad) || (c->ke_v_s_rad < 0.0f) || !pos_finite(c->kt_nm_a) ||
        !pos_finite(c->j_kgm2)) {
        err |= MC_PI2D_ERR_PLANT;
    }
    if (!pos_finite(c->k1_per_s) || !pos_finite(c->k2_per_s)) {
        err |= MC_PI2D_ERR_K12;
    }
    if (!pos_finite(c->kp_per_s2) || !pos_finite(c->kd_per_s2)) {
        err |= MC_PI2D_ERR_KPKD;
    }
    if (!pos_finite(c->a_per_s) || !pos_finite(c->b)) {
        err |= MC_PI2D_ERR_FILTER;
    }
    if (!pos_finite(c->ki_per_s3) || !pos_finite(c->eps_per_s)) {
        err |= MC_PI2D_ERR_KI_EPS;
    } else if ((err & MC_PI2D_ERR_PLANT) == 0u) {
        /* Paper: 0 < ki < eps in its normalised time (base T = L/R). With
         * ki_n = ki T^3 and eps_n = eps T this is ki T^2 < eps. */
        const float t_s = c->l_h / c->r_ohm;
        if (!((c->ki_per_s3 * t_s * t_s) < c->eps_per_s)) {
            err |= MC_PI2D_ERR_KI_EPS;
        }
    } else {
        /* the plant is already rejected; the ratio cannot be checked */
    }
    if (((err & (MC_PI2D_ERR_KI_EPS | MC_PI2D_ERR_KPKD)) == 0u) &&
        !((c->kp_per_s2 - (c->ki_per_s3 / c->eps_per_s)) > 0.0f)) {
        err |= MC_PI2D_ERR_KP_PRIME;
    }
    if (!pos_finite(c->dt_s)) {
        err |= MC_PI2D_ERR_DT;
    }
    if (!pos_finite(c->iq_max_a) || !pos_finite(c->v_max_v) || !pos_finite(c->nu_max_nm)) {
        err |= MC_PI2D_ERR_LIMITS;
    }
    return err;
}

uint32_t mc_pi2d_f32_init(mc_pi2d_f32_t *st, const mc_pi2d_f32_cfg_t *cfg)
{
    if ((st == NULL) || (cfg == NULL)) {
        return MC_PI2D_ERR_NULL;
    }
    uint32_t err = validate(cfg);
    if (err != MC_PI2D_ERR_NONE) {
        return err;
    }
    mc_ddiff_f32_t dd;
    const mc_ddiff_f32_cfg_t dcfg = {cfg->a_per_s, cfg->b, cfg->dt_s};
    if (mc_ddiff_f32_init(&dd, &dcfg) != MC_DDIFF_ERR_NONE) {
        return MC_PI2D_ERR_FILTER;
    }
    st->cfg = *cfg;
    st->sigma = cfg->kt_nm_a / cfg->j_kgm2;
    st->r_minus_lk1 = (cfg->l_h * cfg->k1_per_s) - cfg->r_ohm;
    st->r_minus_lk2 = (cfg->l_h * cfg->k2_per_s) - cfg->r_ohm;
    st->pl = (float)cfg->pole_pairs * cfg->l_h;
    st->l_k1 = cfg->l_h * cfg->k1_per_s;
    st->l_k2 = cfg->l_h * cfg->k2_per_s;
    st->inv_kt = 1.0f / cfg->kt_nm_a;
    st->neg_j_ki = -(cfg->j_kgm2 * cfg->ki_per_s3);
    st->a_kd = cfg->a_per_s * cfg->kd_per_s2;
    st->neg_eps_sigma = -(cfg->eps_per_s * st->sigma);
    st->v_lim_sq = pi2d_sq_threshold(cfg->v_max_v);
    st->dd = dd;
    st->nu_nm = 0.0f;
    st->nu_comp_nm = 0.0f;
    st->flags = MC_PI2D_ERR_NONE;
    return MC_PI2D_ERR_NONE;
}

uint32_t mc_pi2d_f32_set_iq_max(mc_pi2d_f32_t *st, float iq_max_a)
{
    if (st == NULL) {
        return MC_PI2D_ERR_NULL;
    }
    if (!pos_finite(iq_max_a)) {
        return MC_PI2D_ERR_LIMITS;
    }
    st->cfg.iq_max_a = iq_max_a;
    return MC_PI2D_ERR_NONE;
}

uint32_t mc_pi2d_f32_reset(mc_pi2d_f32_t *st, float qc0_rad, float nu0_nm)
{
    if (st == NULL) {
        return MC_PI2D_ERR_NULL;
    }
    if (!mc_isfinite_f32(qc0_rad) || !mc_isfinite_f32(nu0_nm)) {
        return MC_PI2D_ERR_NAN_INPUT;
    }
    (void)mc_ddiff_f32_reset(&st->dd, qc0_rad);
    st->nu_nm = mc_sat_f32(nu0_nm, -st->cfg.nu_max_nm, st->cfg.nu_max_nm);
    st->nu_comp_nm = 0.0f;
    st->flags = MC_PI2D_ERR_NONE;
    return MC_PI2D_ERR_NONE;
}

static __attribute__((noinline, cold)) uint32_t pi2d_refuse(mc_pi2d_f32_t *st,
                                                            mc_pi2d_f32_out_t *out)
{
    const mc_pi2d_f32_out_t zero = {0};
    st->flags |= MC_PI2D_ERR_NAN_INPUT;
    *out = zero;
    return MC_PI2D_ERR_NAN_INPUT;
}

uint32_t mc_pi2d_f32_step(mc_pi2d_f32_t *st, const mc_pi2d_f32_in_t *in, mc_pi2d_f32_out_t *out)
{
    if ((st == NULL) || (in == NULL) || (out == NULL)) {
        return MC_PI2D_ERR_NULL;
    }
    const mc_pi2d_f32_cfg_t *c = &st->cfg;

    /* Everything into locals first: the state is written only once the
     * step is accepted (finite inputs, see the header). */

    /* Position error and its dirty derivative, (11)-(12). */
    const float e4 = in->theta_m_rad - in->theta_ref_rad;
    const float th = mc_ddiff_f32_next(&st->dd, e4);
    const float ed = e4 - th;

    /* PD on the position error (9) and the adaptation rate (10), scaled by J
     * so that nu is a torque [N m]: nu/J is the paper's nu. */
    const float v3 = -(c->kp_per_s2 * e4) - (c->kd_per_s2 * th);
    const float dnu = st->neg_j_ki * ed;

    /* Reference current (8) and rho, the implementable part of d(x2*)/dt:
     * d(x2*)/dt = rho - (J/kt)(kp + b kd) e3 (the e3 part is not measured). */
    const float iq_ref_raw = (st->nu_nm + (c->j_kgm2 * (in->alpha_ref_rad_s2 + v3))) * st->inv_kt;
    const float rho_raw =
        (dnu + (c->j_kgm2 * (in->jerk_ref_rad_s3 + (st->a_kd * th)))) * st->inv_kt;
    float iq_ref = iq_ref_raw;
    float rho = rho_raw;
    bool iq_lim = false;
    if (__builtin_expect(pi2d_fabs(iq_ref_raw) > c->iq_max_a, 0)) {
        iq_ref = (iq_ref_raw < 0.0f) ? -c->iq_max_a : c->iq_max_a;
        iq_lim = true;
        rho = 0.0f; /* the clamped reference is constant */
    }

    /* Stabilising term (35): cancels eps sigma (e4 - theta_f) e2 in dV3/dt. */
    const float v2 = st->neg_eps_sigma * ed;

    /* Current-loop voltages (6) and (14) in physical units, with
     * R x1* - (L k1 - R) e1 = L k1 x1* - (L k1 - R) x1 (and the same on q):
     * the errors e1, e2 are not formed. */
    const float om = in->omega_ref_rad_s;
    const float id_ref = in->id_ref_a;
    float u1 = (st->l_k1 * id_ref) + (c->l_h * in->did_ref_a_s) - ((st->pl * in->iq_a) * om) -
               (st->r_minus_lk1 * in->id_a);
    float u2 = ((c->ke_v_s_rad + (st->pl * in->id_a)) * om) + (st->l_k2 * iq_ref) +
               (c->l_h * (rho + v2)) - (st->r_minus_lk2 * in->iq_a);
    const float mag_sq = (u1 * u1) + (u2 * u2);

    /* One finiteness test for all inputs (see the header): the sum is not
     * finite when a term is not (or when it overflows, |values| > 1e38). */
    const float chk = (iq_ref_raw + rho_raw) + mag_sq;
    if (__builtin_expect(!mc_isfinite_f32(chk), 0)) {
        return pi2d_refuse(st, out);
    }

    /* Voltage circle: |u| > v_max exactly when |u|^2 > v_lim_sq. */
    const bool v_lim = mag_sq > st->v_lim_sq;
    if (__builtin_expect(v_lim, 0)) {
        const float s = c->v_max_v / mc_sqrt_f32(mag_sq);
        u1 *= s;
        u2 *= s;
    }

    /* Adaptation (10), forward Euler, conditional integration; the state
     * first (its reads come before any store through out, which the
     * compiler must assume may alias it), then the outputs. */
    const float nu = st->nu_nm;
    float dnu_used = 0.0f;
    if (__builtin_expect(!(iq_lim | v_lim), 1)) {
        dnu_used = dnu;
        /* Compensated (Kahan) sum: y is the increment plus what the last
         * addition lost; (s - nu) - y is what this one loses. */
        const float y = (c->dt_s * dnu) - st->nu_comp_nm;
        const float s = nu + y;
        if (__builtin_expect(pi2d_fabs(s) > c->nu_max_nm, 0)) {
            st->nu_nm = (s < 0.0f) ? -c->nu_max_nm : c->nu_max_nm;
            st->nu_comp_nm = 0.0f; /* at the clamp: nothing owed */
        } else {
            st->nu_comp_nm = (s - nu) - y;
            st->nu_nm = s;
        }
    }
    mc_ddiff_f32_commit(&st->dd, e4, th);

    out->vd_v = u1;
    out->vq_v = u2;
    out->id_ref_a = id_ref;
    out->iq_ref_a = iq_ref;
    out->e4_rad = e4;
    out->theta_f_rad = th;
    out->nu_nm = nu;
    out->dnu_nm_s = dnu_used;
    out->rho_a_s = rho;
    out->v2_a_s = v2;
    out->iq_limited = iq_lim;
    out->v_limited = v_lim;
    return MC_PI2D_ERR_NONE;
}

/* |Delta + sigma| with Delta = (kp + b kd)/sigma - ke/L - p x1 (re-derived)
 * or the printed Delta = (kp + b kd)/sigma + ke/L - p x1, at x1. */
static float delta_sigma(const mc_pi2d_f32_cfg_t *c, float sigma, float x1, bool printed)
{
    const float g = c->ke_v_s_rad / c->l_h;
    const float d = ((c->kp_per_s2 + (c->b * c->kd_per_s2)) / sigma) + (printed ? g : -g) -
                    ((float)c->pole_pairs * x1);
    return mc_abs_f32(d + sigma);
}

uint32_t mc_pi2d_f32_certify(const mc_pi2d_f32_cfg_t *cfg, const mc_pi2d_envelope_t *env,
                             mc_pi2d_cert_t *out)
{
    if ((cfg == NULL) || (env == NULL) || (out == NULL)) {
        return MC_PI2D_ERR_NULL;
    }
    const uint32_t err = validate(cfg);
    if (err != MC_PI2D_ERR_NONE) {
        return err;
    }
    if (!mc_isfinite_f32(env->id_min_a) || !mc_isfinite_f32(env->id_max_a) ||
        !mc_isfinite_f32(env->iq_abs_max_a) || (env->id_min_a > env->id_max_a) ||
        (env->iq_abs_max_a < 0.0f)) {
        return MC_PI2D_ERR_ENVELOPE;
    }
    mc_pi2d_cert_t r;
    const float sigma = cfg->kt_nm_a / cfg->j_kgm2;
    const float eps = cfg->eps_per_s;
    const float a = cfg->a_per_s;
    const float b = cfg->b;
    const float kd = cfg->kd_per_s2;
    const float kpp = cfg->kp_per_s2 - (cfg->ki_per_s3 / eps);
    const float bp = b - 1.0f;
    const float dk = kpp - kd;
    r.kp_prime_per_s2 = kpp;

    /* (34) */
    r.c34_lhs = (kd * a) / b;
    r.c34_printed_rhs = eps * ((2.0f * kd) + ((a * a) / b) + ((dk * dk) / kpp));
    r.c34_printed_margin = r.c34_lhs - r.c34_printed_rhs;
    if (bp > 0.0f) {
        r.c34_rhs = eps * ((2.0f * kd) + ((a * a) / bp) + ((dk * dk) / kpp));
        r.c34_margin = r.c34_lhs - r.c34_rhs;
    } else {
        r.c34_rhs = FLT_MAX; /* b <= 1: eps b' e3^2 is not negative */
        r.c34_margin = -FLT_MAX;
    }

    /* (38), worst case over the envelope. */
    const float ds_lo = delta_sigma(cfg, sigma, env->id_min_a, false);
    const float ds_hi = delta_sigma(cfg, sigma, env->id_max_a, false);
    const float ds = (ds_lo > ds_hi) ? ds_lo : ds_hi;
    const float dsp_lo = delta_sigma(cfg, sigma, env->id_min_a, true);
    const float dsp_hi = delta_sigma(cfg, sigma, env->id_max_a, true);
    const float dsp = (dsp_lo > dsp_hi) ? dsp_lo : dsp_hi;
    r.delta_sigma_max = ds;
    const float px2 = (float)cfg->pole_pairs * env->iq_abs_max_a;
    const float k1 = cfg->k1_per_s;
    const float k2 = cfg->k2_per_s;
    const float coup = (px2 * px2) / k1;
    r.c38_lhs = 2.0f * eps * bp;
    r.c38_rhs = coup + ((ds * ds) / k2);
    r.c38_margin = r.c38_lhs - r.c38_rhs;
    if (r.c38_lhs > coup) {
        r.c38_k2_min_per_s = (ds * ds) / (r.c38_lhs - coup);
    } else {
        r.c38_k2_min_per_s = FLT_MAX;
    }
    if (bp > 0.0f) {
        const float x2 = env->iq_abs_max_a;
        r.c38_printed_rhs = ((dsp * dsp) / (eps * bp)) + ((x2 * x2) / k1);
    } else {
        r.c38_printed_rhs = FLT_MAX;
    }
    r.c38_printed_margin = k2 - r.c38_printed_rhs;
    r.holds = (r.c34_margin >= 0.0f) && (r.c38_margin >= 0.0f);
    *out = r;
    return MC_PI2D_ERR_NONE;
}
