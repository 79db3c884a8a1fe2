/**
 * @file mc_csmc.c
 * @brief CSMC with conditional integrators/servocompensators and ideal SMC
 *        for the two-phase PM stepper (see mc_csmc.h for the law and the
 *        departures from the printed paper).
 */
#include "csmc/mc_csmc.h"

#include <stdbool.h>
#include <stddef.h>

#include "observer/mc_hgo.h"
#include "math/mc_math.h"

/* Per axis: no sigma, or its realisation (kind = 1 + st->real). */
#define CSMC_SV_NONE 0u
/* mc_csmc_hgo_f32_step: the general path (kinds are 0..4) */
#define CSMC_HGO_GENERAL 5u

static bool csmc_pos(float v)
{
    return (v > 0.0f) && mc_isfinite_f32(v);
}

static float csmc_max(float a, float b)
{
    return (a > b) ? a : b;
}

/* Mechanical part of the model: K_m, J > 0, B >= 0, N_r >= 1, tau_L finite. */
static bool csmc_mech_ok(const mc_csmc_f32_model_t *m)
{
    return csmc_pos(m->km_nm_a) && csmc_pos(m->j_kgm2) && (m->b_nms_rad >= 0.0f) &&
           mc_isfinite_f32(m->b_nms_rad) && (m->rotor_teeth >= 1u) &&
           mc_isfinite_f32(m->tau_load_nm);
}

static bool csmc_bounds_ok(const mc_csmc_f32_model_t *m)
{
    const bool r_ok = csmc_pos(m->r_min_ohm) && mc_isfinite_f32(m->r_max_ohm) &&
                      (m->r_min_ohm <= m->r_nom_ohm) && (m->r_nom_ohm <= m->r_max_ohm);
    const bool l_ok = csmc_pos(m->l_min_h) && mc_isfinite_f32(m->l_max_h) &&
                      (m->l_min_h <= m->l_nom_h) && (m->l_nom_h <= m->l_max_h);
    return r_ok && l_ok && csmc_pos(m->q1_v) && csmc_pos(m->q2_radh_s3);
}

/* Validate and initialise one sigma (order 0: none). */
static uint32_t csmc_sigma_init(const mc_csvc_f32_model_t *m, float mu, float dt_s,
                                mc_csvc_f32_t *p_sv, uint32_t *p_have)
{
    mc_csvc_f32_cfg_t c;

    if (m->order == 0u) {
        *p_have = 0u;
        return MC_CSVC_ERR_NONE;
    }
    c.model = *m;
    c.mu = mu;
    c.dt_s = dt_s;
    *p_have = 1u;
    return mc_csvc_f32_init(p_sv, &c);
}

uint32_t mc_csmc_f32_init(mc_csmc_f32_t *st, const mc_csmc_f32_cfg_t *cfg)
{
    uint32_t err = MC_CSMC_ERR_NONE;
    mc_csvc_f32_t sv1;
    mc_csvc_f32_t sv2;
    uint32_t have1 = 0u;
    uint32_t have2 = 0u;
    const bool dt_ok = csmc_pos((cfg != NULL) ? cfg->dt_s : 0.0f);
    const bool mu_ok = (cfg != NULL) && csmc_pos(cfg->mu1_a) && csmc_pos(cfg->mu2_rad_s2);

    if ((st == NULL) || (cfg == NULL)) {
        return MC_CSMC_ERR_NULL;
    }
    if (((cfg->law != MC_CSMC_LAW_MODEL) && (cfg->law != MC_CSMC_LAW_CONST)) ||
        ((cfg->sw != MC_CSMC_SW_SAT) && (cfg->sw != MC_CSMC_SW_SGN))) {
        err |= MC_CSMC_ERR_LAW;
    }
    if (!csmc_pos(cfg->k1_per_s2) || !csmc_pos(cfg->k2_per_s)) {
        err |= MC_CSMC_ERR_SURFACE;
    }
    if (!mu_ok) {
        err |= MC_CSMC_ERR_MU;
    }
    if (!dt_ok) {
        err |= MC_CSMC_ERR_DT;
    }
    if (!csmc_pos(cfg->v_limit_v)) {
        err |= MC_CSMC_ERR_VLIMIT;
    }
    if (cfg->law == MC_CSMC_LAW_CONST) {
        if (!csmc_pos(cfg->m1_v) || !csmc_pos(cfg->m2_v)) {
            err |= MC_CSMC_ERR_GAIN_M;
        }
    } else if (cfg->law == MC_CSMC_LAW_MODEL) {
        if (!csmc_mech_ok(&cfg->model)) {
            err |= MC_CSMC_ERR_MODEL;
        }
        if (!csmc_bounds_ok(&cfg->model)) {
            err |= MC_CSMC_ERR_BOUNDS;
        }
    } else {
        /* unknown law: already flagged */
    }
    /* The sigma kernels need a valid mu and dt to be checked. */
    if (mu_ok && dt_ok) {
        if (csmc_sigma_init(&cfg->sigma1, cfg->mu1_a, cfg->dt_s, &sv1, &have1) !=
            MC_CSVC_ERR_NONE) {
            err |= MC_CSMC_ERR_SIGMA_1;
        }
        if (csmc_sigma_init(&cfg->sigma2, cfg->mu2_rad_s2, cfg->dt_s, &sv2, &have2) !=
            MC_CSVC_ERR_NONE) {
            err |= MC_CSMC_ERR_SIGMA_2;
        }
    }
    if (err != MC_CSMC_ERR_NONE) {
        return err;
    }
    st->law = cfg->law;
    st->sw = cfg->sw;
    st->k1_per_s2 = cfg->k1_per_s2;
    st->k2_per_s = cfg->k2_per_s;
    st->mu1_a = cfg->mu1_a;
    st->mu2_rad_s2 = cfg->mu2_rad_s2;
    st->m1_v = cfg->m1_v;
    st->m2_v = cfg->m2_v;
    st->v_limit_v = cfg->v_limit_v;
    st->model = cfg->model;
    st->k3 = 0.0f;
    st->k4 = 0.0f;
    st->d0 = 0.0f;
    st->dr_ohm = 0.0f;
    st->dl_h = 0.0f;
    st->inv_k3 = 0.0f;
    if (cfg->law == MC_CSMC_LAW_MODEL) {
        const mc_csmc_f32_model_t *m = &cfg->model;
        st->k3 = m->km_nm_a / m->j_kgm2;
        st->k4 = m->b_nms_rad / m->j_kgm2;
        st->d0 = m->tau_load_nm / m->j_kgm2;
        st->inv_k3 = m->j_kgm2 / m->km_nm_a;
        st->dr_ohm = csmc_max(m->r_max_ohm - m->r_nom_ohm, m->r_nom_ohm - m->r_min_ohm);
        st->dl_h = csmc_max(m->l_max_h - m->l_nom_h, m->l_nom_h - m->l_min_h);
    }
    st->inv_mu1 = 1.0f / cfg->mu1_a;
    st->inv_mu2 = 1.0f / cfg->mu2_rad_s2;
    st->neg_m1_per_mu1 = -(cfg->m1_v / cfg->mu1_a);
    st->neg_m2_per_mu2 = -(cfg->m2_v / cfg->mu2_rad_s2);
    st->may_clamp = ((cfg->law != MC_CSMC_LAW_CONST) || (cfg->m1_v > cfg->v_limit_v) ||
                     (cfg->m2_v > cfg->v_limit_v))
                        ? 1u
                        : 0u;
    st->const_sat = ((cfg->law == MC_CSMC_LAW_CONST) && (cfg->sw == MC_CSMC_SW_SAT)) ? 1u : 0u;
    st->fast_kind2 = CSMC_HGO_GENERAL; /* set below once kind2 is known */
    st->have_sigma1 = have1;
    st->have_sigma2 = have2;
    st->kind1 = CSMC_SV_NONE;
    st->kind2 = CSMC_SV_NONE;
    if (have1 != 0u) {
        st->sigma1 = sv1;
        st->kind1 = 1u + sv1.real;
    }
    if (have2 != 0u) {
        st->sigma2 = sv2;
        st->kind2 = 1u + sv2.real;
    }
    if ((st->const_sat != 0u) && (st->may_clamp == 0u)) {
        st->fast_kind2 = st->kind2;
    }
    st->out.v_d_v = 0.0f;
    st->out.v_q_v = 0.0f;
    st->out.s1_a = 0.0f;
    st->out.s2_rad_s2 = 0.0f;
    st->flags = MC_CSMC_ERR_NONE;
    return MC_CSMC_ERR_NONE;
}

uint32_t mc_csmc_f32_reset(mc_csmc_f32_t *st)
{
    if (st == NULL) {
        return MC_CSMC_ERR_NULL;
    }
    if (st->have_sigma1 != 0u) {
        (void)mc_csvc_f32_reset(&st->sigma1);
    }
    if (st->have_sigma2 != 0u) {
        (void)mc_csvc_f32_reset(&st->sigma2);
    }
    st->out.v_d_v = 0.0f;
    st->out.v_q_v = 0.0f;
    st->out.s1_a = 0.0f;
    st->out.s2_rad_s2 = 0.0f;
    st->flags = MC_CSMC_ERR_NONE;
    return MC_CSMC_ERR_NONE;
}

/* |x| as the FPU's absolute value (one instruction; only compared here). */
static inline float csmc_fabs(float x)
{
    return __builtin_fabsf(x);
}

/* K0 sigma of one axis (0 without a sigma). */
static inline float csmc_term(const mc_csvc_f32_t *sv, uint32_t kind)
{
    switch (kind) {
    case 1u + MC_CSVC_REAL_MODAL2:
        return mc_csvc_f32_term_m2(sv);
    case 1u + MC_CSVC_REAL_MODAL1:
        return mc_csvc_f32_term_m1(sv);
    case 1u + MC_CSVC_REAL_MODAL0:
        return mc_csvc_f32_term_m0(sv);
    case 1u + MC_CSVC_REAL_DENSE:
        return mc_csvc_f32_term(sv);
    default:
        return 0.0f;
    }
}

/* Advance one axis' sigma with v = mu sat(s/mu) - K0 sigma. */
static inline void csmc_advance(mc_csvc_f32_t *sv, uint32_t kind, float v)
{
    switch (kind) {
    case 1u + MC_CSVC_REAL_MODAL2:
        mc_csvc_f32_advance_m2(sv, v);
        break;
    case 1u + MC_CSVC_REAL_MODAL1:
        mc_csvc_f32_advance_m1(sv, v);
        break;
    case 1u + MC_CSVC_REAL_MODAL0:
        mc_csvc_f32_advance_m0(sv, v);
        break;
    case 1u + MC_CSVC_REAL_DENSE:
        mc_csvc_f32_advance(sv, v);
        break;
    default:
        break;
    }
}

/* psi for SW_SGN: sgn(s), sgn(0) = 0. */
static float csmc_sgn(float s)
{
    if (s > 0.0f) {
        return 1.0f;
    }
    return (s < 0.0f) ? -1.0f : 0.0f;
}

/* The step of mc_csmc_f32_step without its pointer checks; false when the
 * input was refused (st->out returned, flag set). */
static bool csmc_step(mc_csmc_f32_t *st, const mc_csmc_f32_in_t *in, mc_csmc_f32_out_t *p_out)
{
    float u1;
    float u2;

    /* Into locals first; the state is written once the step is accepted. */
    const float t1 = csmc_term(&st->sigma1, st->kind1);
    const float t2 = csmc_term(&st->sigma2, st->kind2);
    const float s1 = in->e1_a + t1;
    const float s2 =
        ((st->k1_per_s2 * in->e2_rad) + (st->k2_per_s * in->de2_rad_s)) + in->dde2_rad_s2 + t2;
    /* One finiteness test for all inputs: e1, e2, e2', e2'' reach s1, s2
     * (t1, t2 are finite), the others are added in; the sum is not finite
     * when one of them is not (or when it overflows, |values| > 1e38). */
    const float chk = (s1 + s2) + ((in->i_d_a + in->i_q_a) + in->omega_m_rad_s) +
                      (in->di_dd_a_s + in->dddphi_d_rad_s3);
    if (__builtin_expect(!mc_isfinite_f32(chk), 0)) {
        st->flags |= MC_CSMC_ERR_NAN_INPUT;
        *p_out = st->out;
        return false;
    }
    /* mu sat(s/mu): s itself inside the boundary layer. */
    float sm1 = s1;
    float sm2 = s2;
    if (__builtin_expect(csmc_fabs(s1) > st->mu1_a, 0)) {
        sm1 = (s1 < 0.0f) ? -st->mu1_a : st->mu1_a;
    }
    if (__builtin_expect(csmc_fabs(s2) > st->mu2_rad_s2, 0)) {
        sm2 = (s2 < 0.0f) ? -st->mu2_rad_s2 : st->mu2_rad_s2;
    }
    if (__builtin_expect(st->const_sat != 0u, 1)) {
        /* u = -M sat(s/mu) = (-M/mu) (mu sat(s/mu)) */
        u1 = st->neg_m1_per_mu1 * sm1;
        u2 = st->neg_m2_per_mu2 * sm2;
    } else {
        float psi1;
        float psi2;
        if (st->sw == MC_CSMC_SW_SGN) {
            psi1 = csmc_sgn(s1);
            psi2 = csmc_sgn(s2);
        } else {
            psi1 = sm1 * st->inv_mu1;
            psi2 = sm2 * st->inv_mu2;
        }
        if (st->law == MC_CSMC_LAW_CONST) {
            u1 = -st->m1_v * psi1;
            u2 = -st->m2_v * psi2;
        } else {
            const mc_csmc_f32_model_t *m = &st->model;
            const float x1 = in->i_d_a;
            const float x2 = in->i_q_a;
            const float x3 = in->omega_m_rad_s;
            const float k5 = (float)m->rotor_teeth;
            /* d axis: the part of F1 known up to the factor L: k5 x2 x3 - I_dd'. */
            const float f1k = (k5 * x2 * x3) - in->di_dd_a_s;
            /* q axis: G (see mc_csmc.h); k3 x2 - k4 x3 - d0 is w' from the model. */
            const float wdot = (st->k3 * x2) - (st->k4 * x3) - st->d0;
            const float g = (st->k1_per_s2 * in->de2_rad_s) + (st->k2_per_s * in->dde2_rad_s2) -
                            in->dddphi_d_rad_s3 - (st->k4 * wdot) - (st->k3 * k5 * x1 * x3);
            /* L^ beta_1 and L^ beta_2 / k3 (volts) */
            const float lb1 =
                (st->dr_ohm * mc_abs_f32(x1)) + (st->dl_h * mc_abs_f32(f1k)) + m->q1_v;
            const float lb2 = (st->dr_ohm * mc_abs_f32(x2)) +
                              (st->inv_k3 * ((st->dl_h * mc_abs_f32(g)) + m->q2_radh_s3));
            u1 = (m->r_nom_ohm * x1) - (m->l_nom_h * f1k) - (lb1 * psi1);
            u2 = (m->r_nom_ohm * x2) + (m->km_nm_a * x3) - (m->l_nom_h * st->inv_k3 * g) -
                 (lb2 * psi2);
        }
    }
    /* Output clamp (with LAW_CONST it can act only if M_i > v_limit). */
    if (st->may_clamp != 0u) {
        u1 = mc_sat_f32(u1, -st->v_limit_v, st->v_limit_v);
        u2 = mc_sat_f32(u2, -st->v_limit_v, st->v_limit_v);
    }
    st->out.v_d_v = u1;
    st->out.v_q_v = u2;
    st->out.s1_a = s1;
    st->out.s2_rad_s2 = s2;
    *p_out = st->out;
    /* Servocompensators: v = mu sat(s/mu) - K0 sigma (= s* inside the layer). */
    csmc_advance(&st->sigma1, st->kind1, sm1 - t1);
    csmc_advance(&st->sigma2, st->kind2, sm2 - t2);
    return true;
}

uint32_t mc_csmc_f32_step(mc_csmc_f32_t *st, const mc_csmc_f32_in_t *in, mc_csmc_f32_out_t *p_out)
{
    if ((st == NULL) || (in == NULL) || (p_out == NULL)) {
        return MC_CSMC_ERR_NULL;
    }
    return csmc_step(st, in, p_out) ? MC_CSMC_ERR_NONE : MC_CSMC_ERR_NAN_INPUT;
}

/* ------------------------------------------------------------------------ */
/* Law and high-gain observer in one step                                    */
/* ------------------------------------------------------------------------ */

uint32_t mc_csmc_hgo_f32_init(mc_csmc_hgo_f32_t *st, const mc_csmc_f32_cfg_t *law,
                              const mc_hgo_f32_cfg_t *hgo)
{
    mc_csmc_f32_t l;
    mc_hgo_f32_t h;

    if ((st == NULL) || (law == NULL) || (hgo == NULL)) {
        return MC_CSMC_ERR_NULL;
    }
    uint32_t err = mc_csmc_f32_init(&l, law);
    if ((mc_hgo_f32_init(&h, hgo) != MC_HGO_ERR_NONE) || !(hgo->dt_s == law->dt_s)) {
        err |= MC_CSMC_ERR_HGO;
    }
    if (err != MC_CSMC_ERR_NONE) {
        return err;
    }
    st->law = l;
    st->hgo = h;
    st->fast = CSMC_HGO_GENERAL;
    return MC_CSMC_ERR_NONE;
}

uint32_t mc_csmc_hgo_f32_reset(mc_csmc_hgo_f32_t *st)
{
    if (st == NULL) {
        return MC_CSMC_ERR_NULL;
    }
    (void)mc_csmc_f32_reset(&st->law);
    (void)mc_hgo_f32_reset(&st->hgo, 0.0f, 0.0f, 0.0f);
    st->fast = CSMC_HGO_GENERAL;
    return MC_CSMC_ERR_NONE;
}

static __attribute__((noinline, cold)) uint32_t csmc_hgo_refuse(mc_csmc_hgo_f32_t *st,
                                                                mc_csmc_f32_out_t *out)
{
    st->law.flags |= MC_CSMC_ERR_NAN_INPUT;
    out->v_d_v = 0.0f;
    out->v_q_v = 0.0f;
    out->s1_a = 0.0f;
    out->s2_rad_s2 = 0.0f;
    return MC_CSMC_ERR_NAN_INPUT;
}

/* Any law other than LAW_CONST with SW_SAT (and the first two steps of
 * any law): the general law on an input built from the measurements and
 * the estimates. */
static __attribute__((noinline)) uint32_t csmc_hgo_general(mc_csmc_hgo_f32_t *st, float e1_a,
                                                           float e2_rad,
                                                           const mc_csmc_f32_in_t *model,
                                                           mc_csmc_f32_out_t *out)
{
    mc_csmc_f32_in_t in = {0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f};
    mc_csmc_f32_out_t o;

    if (st->law.law == MC_CSMC_LAW_MODEL) {
        if (model == NULL) {
            return MC_CSMC_ERR_NULL;
        }
        in = *model;
    }
    in.e1_a = e1_a;
    in.e2_rad = e2_rad;
    in.de2_rad_s = st->hgo.z[1];
    in.dde2_rad_s2 = st->hgo.z[2];
    if (!csmc_step(&st->law, &in, &o)) {
        return csmc_hgo_refuse(st, out);
    }
    mc_hgo_f32_advance(&st->hgo, e2_rad);
    if (st->hgo.n_hist >= 2u) {
        st->fast = st->law.fast_kind2;
    }
    *out = o;
    return MC_CSMC_ERR_NONE;
}

/* The combined step's fast path (LAW_CONST, SW_SAT, no output clamp) per
 * axis, always inlined with a constant kind so that the realisation's term
 * and advance are one straight block (sigma stays in registers between
 * them). The arithmetic is that of csmc_step, value for value. */
#define CSMC_INLINE static inline __attribute__((always_inline))

/* q axis: t2, s2 = s2_part + t2, the one finiteness test, sat, advance.
 * false: refused, nothing written. */
CSMC_INLINE bool csmc_fast_q(mc_csmc_f32_t *law, uint32_t kind, float s2_part, float e1_a,
                             float *p_s2, float *p_u2)
{
    const float t2 = csmc_term(&law->sigma2, kind);
    const float s2 = s2_part + t2;
    /* e2 reaches s2_part, e1 is added: the sum is not finite when either
     * is not (see mc_csmc_hgo_f32_step). */
    if (__builtin_expect(!mc_isfinite_f32(s2 + e1_a), 0)) {
        return false;
    }
    float sm2 = s2;
    if (__builtin_expect(csmc_fabs(s2) > law->mu2_rad_s2, 0)) {
        sm2 = (s2 < 0.0f) ? -law->mu2_rad_s2 : law->mu2_rad_s2;
    }
    csmc_advance(&law->sigma2, kind, sm2 - t2);
    *p_s2 = s2;
    *p_u2 = law->neg_m2_per_mu2 * sm2;
    return true;
}

/* d axis: t1, s1 = e1 + t1, sat, advance (e1 finite, t1 finite: s1 is not
 * NaN, and sat keeps sigma finite even if s1 overflowed). */
CSMC_INLINE void csmc_fast_d(mc_csmc_f32_t *law, uint32_t kind, float e1_a, float *p_s1,
                             float *p_u1)
{
    const float t1 = csmc_term(&law->sigma1, kind);
    const float s1 = e1_a + t1;
    float sm1 = s1;
    if (__builtin_expect(csmc_fabs(s1) > law->mu1_a, 0)) {
        sm1 = (s1 < 0.0f) ? -law->mu1_a : law->mu1_a;
    }
    csmc_advance(&law->sigma1, kind, sm1 - t1);
    *p_s1 = s1;
    *p_u1 = law->neg_m1_per_mu1 * sm1;
}

uint32_t mc_csmc_hgo_f32_step(mc_csmc_hgo_f32_t *st, float e1_a, float e2_rad,
                              const mc_csmc_f32_in_t *model, mc_csmc_f32_out_t *out)
{
    float s1;
    float s2;
    float u1;
    float u2;
    bool ok;

    if ((st == NULL) || (out == NULL)) {
        return MC_CSMC_ERR_NULL;
    }
    mc_csmc_f32_t *law = &st->law;
    /* The estimates at this sample: the observer's state, finite because
     * only accepted steps write it (see the header). */
    const float s2_part =
        ((law->k1_per_s2 * e2_rad) + (law->k2_per_s * st->hgo.z[1])) + st->hgo.z[2];
    switch (st->fast) {
    case CSMC_SV_NONE:
        ok = csmc_fast_q(law, CSMC_SV_NONE, s2_part, e1_a, &s2, &u2);
        break;
    case 1u + MC_CSVC_REAL_DENSE:
        ok = csmc_fast_q(law, 1u + MC_CSVC_REAL_DENSE, s2_part, e1_a, &s2, &u2);
        break;
    case 1u + MC_CSVC_REAL_MODAL0:
        ok = csmc_fast_q(law, 1u + MC_CSVC_REAL_MODAL0, s2_part, e1_a, &s2, &u2);
        break;
    case 1u + MC_CSVC_REAL_MODAL1:
        ok = csmc_fast_q(law, 1u + MC_CSVC_REAL_MODAL1, s2_part, e1_a, &s2, &u2);
        break;
    case 1u + MC_CSVC_REAL_MODAL2:
        ok = csmc_fast_q(law, 1u + MC_CSVC_REAL_MODAL2, s2_part, e1_a, &s2, &u2);
        break;
    default:
        /* another law, SW_SGN, an output clamp that can act, or the
         * observer's first two steps */
        return csmc_hgo_general(st, e1_a, e2_rad, model, out);
    }
    if (__builtin_expect(!ok, 0)) {
        return csmc_hgo_refuse(st, out);
    }
    switch (law->kind1) {
    case CSMC_SV_NONE:
        csmc_fast_d(law, CSMC_SV_NONE, e1_a, &s1, &u1);
        break;
    case 1u + MC_CSVC_REAL_DENSE:
        csmc_fast_d(law, 1u + MC_CSVC_REAL_DENSE, e1_a, &s1, &u1);
        break;
    case 1u + MC_CSVC_REAL_MODAL0:
        csmc_fast_d(law, 1u + MC_CSVC_REAL_MODAL0, e1_a, &s1, &u1);
        break;
    case 1u + MC_CSVC_REAL_MODAL1:
        csmc_fast_d(law, 1u + MC_CSVC_REAL_MODAL1, e1_a, &s1, &u1);
        break;
    case 1u + MC_CSVC_REAL_MODAL2:
        csmc_fast_d(law, 1u + MC_CSVC_REAL_MODAL2, e1_a, &s1, &u1);
        break;
    default:
        csmc_fast_d(law, CSMC_SV_NONE, e1_a, &s1, &u1);
        break;
    }
    mc_hgo_f32_advance_run(&st->hgo, e2_rad); /* fast != 0: n_hist >= 2 */
    /* out last: the compiler must assume that it may alias the state */
    out->v_d_v = u1;
    out->v_q_v = u2;
    out->s1_a = s1;
    out->s2_rad_s2 = s2;
    return MC_CSMC_ERR_NONE;
}

uint32_t mc_csmc_f32_err_from_state(const mc_csmc_f32_model_t *model, float i_d_a, float i_q_a,
                                    float omega_m_rad_s, float theta_m_rad, float i_dd_a,
                                    float phi_d_rad, float dphi_d_rad_s, float ddphi_d_rad_s2,
                                    mc_csmc_f32_in_t *p_in)
{
    float k3;
    float k4;
    float d0;
    float dde2;

    if ((model == NULL) || (p_in == NULL)) {
        return MC_CSMC_ERR_NULL;
    }
    if (!csmc_mech_ok(model)) {
        return MC_CSMC_ERR_MODEL;
    }
    k3 = model->km_nm_a / model->j_kgm2;
    k4 = model->b_nms_rad / model->j_kgm2;
    d0 = model->tau_load_nm / model->j_kgm2;
    dde2 = (k3 * i_q_a) - (k4 * omega_m_rad_s) - d0 - ddphi_d_rad_s2;
    p_in->e1_a = i_d_a - i_dd_a;
    p_in->e2_rad = theta_m_rad - phi_d_rad;
    p_in->de2_rad_s = omega_m_rad_s - dphi_d_rad_s;
    p_in->dde2_rad_s2 = dde2;
    p_in->i_d_a = i_d_a;
    p_in->i_q_a = i_q_a;
    p_in->omega_m_rad_s = omega_m_rad_s;
    return MC_CSMC_ERR_NONE;
}
