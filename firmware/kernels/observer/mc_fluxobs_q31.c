/**
 * @file mc_fluxobs_q31.c
 * @brief Flux gradient observer, q31 twin (see mc_fluxobs_q31.h).
 */
#include "observer/mc_fluxobs_q31.h"

#include <stdbool.h>
#include <stddef.h>

#include "math/mc_math.h"

static bool fq_pos(float x)
{
    return (x > 0.0f) && mc_isfinite_f32(x);
}

uint32_t mc_fluxobs_q31_init(mc_fluxobs_q31_t *st, const mc_fluxobs_q31_cfg_t *cfg)
{
    mc_fluxobs_f32_t ref;
    uint32_t err;
    const mc_fluxobs_f32_cfg_t *f;
    float fb;
    float steps;

    mc_fluxobs_q31_t t;

    if ((st == NULL) || (cfg == NULL)) {
        return MC_FLUXOBS_ERR_NULL;
    }
    f = &cfg->f;
    err = mc_fluxobs_f32_init(&ref, f);
    fb = cfg->flux_base_wb;
    if (!fq_pos(cfg->i_base_a) || !fq_pos(cfg->v_base_v) || !fq_pos(fb) ||
        (fq_pos(f->flux_wb) && !(f->flux_wb < fb))) {
        err |= MC_FLUXOBS_ERR_SCALE;
    }
    if (err != MC_FLUXOBS_ERR_NONE) {
        return err;
    }
    t.g_r_cfg = (0.5f * f->dt_s * f->r_ohm * cfg->i_base_a) / fb;
    t.r_scale = 1.0f;
    if (!mc_q46_gain_from_f32((f->dt_s * cfg->v_base_v) / fb, &t.g_v) ||
        !mc_q46_gain_from_f32(t.g_r_cfg, &t.g_r) ||
        !mc_q46_gain_from_f32((f->l_h * cfg->i_base_a) / fb, &t.g_l) ||
        !mc_q46_gain_from_f32((f->ld_minus_lq_h * cfg->i_base_a) / fb, &t.g_dl) ||
        !mc_q46_gain_from_f32(ref.half_gamma_dt * fb * fb, &t.g_k)) {
        return MC_FLUXOBS_ERR_SCALE;
    }
    t.flux_pu = mc_q31_from_f32(f->flux_wb / fb);
    if (t.flux_pu <= 0) {
        return MC_FLUXOBS_ERR_SCALE; /* flux below one LSB of the base */
    }
    t.flux2_q62 = (uint64_t)((int64_t)t.flux_pu * (int64_t)t.flux_pu);
    t.psi_a_floor = mc_q31_from_f32(MC_FLUXOBS_PSI_A_MIN_FRAC * (f->flux_wb / fb));
    t.salient = f->ld_minus_lq_h != 0.0f; /* as the f32 step's test */
    t.psi_a_pu = t.flux_pu;
    t.resid_tol = mc_q31_from_f32(f->resid_tol);
    steps = (f->resid_time_s / f->dt_s) + 0.5f;
    t.resid_steps = (steps >= 4.0e9f) ? 4000000000u : (uint32_t)steps;
    t.x_alpha_q46 = mc_q46_from_q31(t.flux_pu);
    t.x_beta_q46 = 0;
    t.i_alpha_prev = 0;
    t.i_beta_prev = 0;
    t.theta = 0;
    t.resid = 0;
    t.resid_bad_steps = 0u;
    t.flags = MC_FLUXOBS_ERR_NONE;
    *st = t;
    return MC_FLUXOBS_ERR_NONE;
}

/* The active flux psi_a = flux + (Ld - Lq) i_d (pu), i_d of i_ab at the
 * angle whose sine and cosine are given, floored as the f32 kernel's
 * (mc_fluxobs_f32_eval_active_flux); the flux itself if non-salient. */
static q31_t fq_psi_a(const mc_fluxobs_q31_t *st, q31_t s, q31_t c, q31_t i_alpha, q31_t i_beta)
{
    q31_t i_d;
    int64_t psi;
    if (!st->salient) {
        return st->flux_pu;
    }
    i_d = mc_q31_add_sat(mc_q31_mul(c, i_alpha), mc_q31_mul(s, i_beta));
    psi = mc_q46_add(mc_q46_from_q31(st->flux_pu), mc_q46_mul_q31(st->g_dl, i_d));
    {
        const q31_t p = mc_q46_to_q31(psi);
        return (p >= st->psi_a_floor) ? p : st->psi_a_floor;
    }
}

uint32_t mc_fluxobs_q31_reset(mc_fluxobs_q31_t *st, q31_t theta_guess, q31_t i_alpha, q31_t i_beta)
{
    q31_t s;
    q31_t c;
    q31_t psi;

    if (st == NULL) {
        return MC_FLUXOBS_ERR_NULL;
    }
    mc_sincos_q31(theta_guess, &s, &c);
    psi = fq_psi_a(st, s, c, i_alpha, i_beta);
    st->psi_a_pu = psi;
    st->x_alpha_q46 =
        mc_q46_add(mc_q46_mul_q31(st->g_l, i_alpha), mc_q46_from_q31(mc_q31_mul(psi, c)));
    st->x_beta_q46 =
        mc_q46_add(mc_q46_mul_q31(st->g_l, i_beta), mc_q46_from_q31(mc_q31_mul(psi, s)));
    st->i_alpha_prev = i_alpha;
    st->i_beta_prev = i_beta;
    st->theta = theta_guess;
    st->resid = 0;
    st->resid_bad_steps = 0u;
    st->flags = MC_FLUXOBS_ERR_NONE;
    return MC_FLUXOBS_ERR_NONE;
}

uint32_t mc_fluxobs_q31_set_r_scale(mc_fluxobs_q31_t *st, float scale)
{
    mc_q46_gain_t g;

    if (st == NULL) {
        return MC_FLUXOBS_ERR_NULL;
    }
    /* the configured gain formed at init; scale <= 3 keeps it below 2^30 */
    if (!mc_r_scale_f32_ok(scale) || !mc_q46_gain_from_f32(st->g_r_cfg * scale, &g)) {
        return MC_FLUXOBS_ERR_ARG;
    }
    st->g_r = g;
    st->r_scale = scale;
    return MC_FLUXOBS_ERR_NONE;
}

/* xh + dt (v - R (i_prev + i)/2), one axis, Q46 */
static int64_t fq_integrate(const mc_fluxobs_q31_t *st, int64_t x, q31_t v, q31_t i_prev, q31_t i)
{
    int64_t acc = mc_q46_add(x, mc_q46_mul_q31(st->g_v, v));
    acc = mc_q46_add(acc, -mc_q46_mul_q31(st->g_r, i_prev));
    return mc_q46_add(acc, -mc_q46_mul_q31(st->g_r, i));
}

uint32_t mc_fluxobs_q31_step(mc_fluxobs_q31_t *st, q31_t v_alpha, q31_t v_beta, q31_t i_alpha,
                             q31_t i_beta)
{
    const int64_t lim = mc_q46_from_q31(MC_Q31_MAX);
    uint32_t raised = MC_FLUXOBS_ERR_NONE;
    int64_t xa;
    int64_t xb;
    int64_t ea;
    int64_t eb;
    int64_t li_a;
    int64_t li_b;
    int64_t d46;
    int64_t k46;
    q31_t ea31;
    q31_t eb31;
    q31_t k31;
    uint64_t e2;
    uint64_t mag;
    uint64_t psi2_q62 = 0u;
    q31_t psi = 0;

    if (st == NULL) {
        return MC_FLUXOBS_ERR_NULL;
    }
    /* the active flux at the previous estimate (mc_fluxobs.h); the
     * non-salient step uses the constants, as before the active-flux form */
    if (st->salient) {
        q31_t sn;
        q31_t cs;
        mc_sincos_q31(st->theta, &sn, &cs);
        psi = fq_psi_a(st, sn, cs, i_alpha, i_beta);
        psi2_q62 = (uint64_t)((int64_t)psi * (int64_t)psi);
    } else {
        psi = st->flux_pu;
        psi2_q62 = st->flux2_q62;
    }
    st->psi_a_pu = psi;
    xa = fq_integrate(st, st->x_alpha_q46, v_alpha, st->i_alpha_prev, i_alpha);
    xb = fq_integrate(st, st->x_beta_q46, v_beta, st->i_beta_prev, i_beta);

    li_a = mc_q46_mul_q31(st->g_l, i_alpha);
    li_b = mc_q46_mul_q31(st->g_l, i_beta);
    ea = mc_q46_add(xa, -li_a);
    eb = mc_q46_add(xb, -li_b);
    ea31 = mc_q46_to_q31(ea);
    eb31 = mc_q46_to_q31(eb);
    /* |e|^2 in Q62, exact: each square <= 2^62, the sum <= 2^63 */
    e2 = (uint64_t)((int64_t)ea31 * (int64_t)ea31) + (uint64_t)((int64_t)eb31 * (int64_t)eb31);
    /* psi_a^2 - |e|^2 in Q46: both < 2^63.1, the difference after >> 16 fits */
    if (psi2_q62 >= e2) {
        d46 = (int64_t)((psi2_q62 - e2) >> 16);
    } else {
        d46 = -(int64_t)((e2 - psi2_q62) >> 16);
    }
    k46 = mc_q46_mul(st->g_k, d46);
    if (k46 < -(MC_Q46_ONE / 2)) {
        k46 = -(MC_Q46_ONE / 2); /* as the f32 kernel: see mc_fluxobs.h */
    }
    k31 = mc_q46_to_q31(k46);
    {
        const mc_q46_gain_t kg = {k31, 0};
        ea = mc_q46_add(ea, mc_q46_mul(kg, ea));
        eb = mc_q46_add(eb, mc_q46_mul(kg, eb));
    }
    st->x_alpha_q46 = mc_q46_clamp(mc_q46_add(ea, li_a), -lim, lim);
    st->x_beta_q46 = mc_q46_clamp(mc_q46_add(eb, li_b), -lim, lim);
    st->i_alpha_prev = i_alpha;
    st->i_beta_prev = i_beta;
    ea31 = mc_q46_to_q31(ea);
    eb31 = mc_q46_to_q31(eb);
    st->theta = mc_atan2_q31(eb31, ea31);

    /* residual |e|/flux - 1 */
    e2 = (uint64_t)((int64_t)ea31 * (int64_t)ea31) + (uint64_t)((int64_t)eb31 * (int64_t)eb31);
    mag = mc_isqrt_u64(e2, NULL); /* Q31, < 2^31.5 */
    {
        const uint64_t ratio = (mag << 31) / (uint64_t)psi; /* Q31 of |e|/psi_a */
        const int64_t r = (int64_t)ratio - ((int64_t)1 << 31);
        st->resid = mc_q31_sat64(r);
    }
    if (mc_q31_abs_sat(st->resid) > st->resid_tol) {
        st->resid_bad_steps += 1u;
        if (st->resid_bad_steps > st->resid_steps) {
            st->resid_bad_steps = st->resid_steps;
            raised |= MC_FLUXOBS_ERR_DIVERGED;
        }
    } else {
        st->resid_bad_steps = 0u;
    }
    st->flags |= raised;
    return raised;
}
