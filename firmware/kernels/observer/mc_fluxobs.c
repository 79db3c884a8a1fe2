/**
 * @file mc_fluxobs.c
 * @brief Flux gradient observer (paper 002, eq. (9)). Model, tuning and
 *        discretisation: see mc_fluxobs.h.
 *
 * Re-derivation notes (where the printed paper and this code differ):
 * - (1) prints the back-EMF as omega flux [sin, -cos]; with theta the
 *   electrical angle and theta' = n_P omega (2), differentiating (4) gives
 *   n_P omega flux. The observer never uses omega, so nothing here depends
 *   on it, but the error system's speed is the electrical one:
 *   Omega = -2 omega_e / (gamma flux^2), omega_e = n_P omega_m.
 * - (13) prints d/dt of xh where the error xt = xh - x is meant (the
 *   measurable y12 cancels); (15)-(17) are then correct as printed.
 */
#include "observer/mc_fluxobs.h"

#include <stddef.h>

#include "math/mc_math.h"

static bool pos_finite(float x)
{
    return (x > 0.0f) && mc_isfinite_f32(x);
}

static uint32_t fluxobs_validate(const mc_fluxobs_f32_cfg_t *cfg)
{
    uint32_t err = MC_FLUXOBS_ERR_NONE;
    const bool dt_ok = pos_finite(cfg->dt_s);
    const bool flux_ok = pos_finite(cfg->flux_wb);

    if (!(cfg->r_ohm >= 0.0f) || !mc_isfinite_f32(cfg->r_ohm) || !pos_finite(cfg->l_h) ||
        !flux_ok || !mc_isfinite_f32(cfg->ld_minus_lq_h) ||
        !((cfg->l_h + cfg->ld_minus_lq_h) > 0.0f)) {
        err |= MC_FLUXOBS_ERR_MOTOR;
    }
    if (!dt_ok) {
        err |= MC_FLUXOBS_ERR_DT;
    }
    if (!pos_finite(cfg->gamma)) {
        err |= MC_FLUXOBS_ERR_GAMMA;
    } else if (dt_ok && flux_ok) {
        const float g = cfg->gamma * cfg->flux_wb * cfg->flux_wb * cfg->dt_s;
        if (!(g <= MC_FLUXOBS_MAX_GAIN_DT)) {
            err |= MC_FLUXOBS_ERR_GAMMA;
        }
    } else {
        /* gain-step product not checkable without dt and flux */
    }
    if (!pos_finite(cfg->resid_tol) || !(cfg->resid_time_s >= 0.0f) ||
        !mc_isfinite_f32(cfg->resid_time_s)) {
        err |= MC_FLUXOBS_ERR_MONITOR;
    }
    return err;
}

/* psi_a = flux + (Ld - Lq) i_d, floored (mc_fluxobs_f32_eval_active_flux). */
static float fluxobs_psi_a(const mc_fluxobs_f32_cfg_t *cfg, float i_d_a)
{
    const float floor_wb = MC_FLUXOBS_PSI_A_MIN_FRAC * cfg->flux_wb;
    const float psi_a = cfg->flux_wb + (cfg->ld_minus_lq_h * i_d_a);
    /* a NaN current gives the floor (the step's finiteness test refuses
     * that step anyway) */
    return (psi_a >= floor_wb) ? psi_a : floor_wb;
}

uint32_t mc_fluxobs_f32_init(mc_fluxobs_f32_t *st, const mc_fluxobs_f32_cfg_t *cfg)
{
    uint32_t err;

    if ((st == NULL) || (cfg == NULL)) {
        return MC_FLUXOBS_ERR_NULL;
    }
    err = fluxobs_validate(cfg);
    if (err != MC_FLUXOBS_ERR_NONE) {
        return err;
    }
    st->cfg = *cfg;
    st->half_gamma_dt = 0.5f * cfg->gamma * cfg->dt_s;
    st->half_r_ohm = cfg->r_ohm * 0.5f;
    st->r_scale = 1.0f;
    st->inv_flux_per_wb = 1.0f / cfg->flux_wb;
    st->flux2 = cfg->flux_wb * cfg->flux_wb;
    st->psi_a_wb = cfg->flux_wb;
    st->x_alpha_wb = cfg->flux_wb;
    st->x_beta_wb = 0.0f;
    st->i_alpha_prev_a = 0.0f;
    st->i_beta_prev_a = 0.0f;
    st->theta_e_rad = 0.0f;
    st->resid = 0.0f;
    st->resid_bad_s = 0.0f;
    st->flags = MC_FLUXOBS_ERR_NONE;
    return MC_FLUXOBS_ERR_NONE;
}

uint32_t mc_fluxobs_f32_reset(mc_fluxobs_f32_t *st, float theta_guess_rad, float i_alpha_a,
                              float i_beta_a)
{
    float s;
    float c;
    float psi_a;

    if (st == NULL) {
        return MC_FLUXOBS_ERR_NULL;
    }
    if (!mc_isfinite_f32(theta_guess_rad) || !mc_isfinite_f32(i_alpha_a) ||
        !mc_isfinite_f32(i_beta_a)) {
        return MC_FLUXOBS_ERR_NAN_INPUT;
    }
    mc_sincos_f32(theta_guess_rad, &s, &c);
    psi_a = fluxobs_psi_a(&st->cfg, (c * i_alpha_a) + (s * i_beta_a));
    st->psi_a_wb = psi_a;
    st->x_alpha_wb = (st->cfg.l_h * i_alpha_a) + (psi_a * c);
    st->x_beta_wb = (st->cfg.l_h * i_beta_a) + (psi_a * s);
    st->i_alpha_prev_a = i_alpha_a;
    st->i_beta_prev_a = i_beta_a;
    st->theta_e_rad = mc_wrap_pi_f32(theta_guess_rad);
    st->resid = 0.0f;
    st->resid_bad_s = 0.0f;
    st->flags = MC_FLUXOBS_ERR_NONE;
    return MC_FLUXOBS_ERR_NONE;
}

float mc_fluxobs_f32_eval_active_flux(const mc_fluxobs_f32_cfg_t *cfg, float i_d_a)
{
    return fluxobs_psi_a(cfg, i_d_a);
}

uint32_t mc_fluxobs_f32_set_r_scale(mc_fluxobs_f32_t *st, float scale)
{
    if (st == NULL) {
        return MC_FLUXOBS_ERR_NULL;
    }
    if (!mc_r_scale_f32_ok(scale)) {
        return MC_FLUXOBS_ERR_ARG;
    }
    st->r_scale = scale;
    st->half_r_ohm = 0.5f * st->cfg.r_ohm * scale;
    return MC_FLUXOBS_ERR_NONE;
}

/* Keeps a rare path out of line (see fluxobs_finish_special). */
#if defined(__GNUC__)
#define FLUXOBS_NOINLINE __attribute__((noinline))
#else
#define FLUXOBS_NOINLINE
#endif

/* The angle when the inline atan2 cannot take it (e = 0, or |e| beyond
 * float range), stored last and out of line, so that the common step calls
 * nothing and needs no stack frame. Returns the step's flags. */
static FLUXOBS_NOINLINE uint32_t fluxobs_finish_special(mc_fluxobs_f32_t *st, float eb, float ea,
                                                        uint32_t raised)
{
    st->theta_e_rad = mc_atan2_f32(eb, ea);
    return raised;
}

/* Salient machine: the active flux psi_a = flux + (Ld - Lq) i_d with i_d
 * the new current at the PREVIOUS estimate (the angle the step starts
 * from: the new one is what the step computes). Out of line: the
 * non-salient step keeps its cost. */
static FLUXOBS_NOINLINE float fluxobs_psi_a_prev_angle(const mc_fluxobs_f32_t *st, float i_alpha_a,
                                                       float i_beta_a)
{
    float s;
    float c;
    mc_sincos_f32(st->theta_e_rad, &s, &c);
    return fluxobs_psi_a(&st->cfg, (c * i_alpha_a) + (s * i_beta_a));
}

uint32_t mc_fluxobs_f32_step(mc_fluxobs_f32_t *st, float v_alpha_v, float v_beta_v, float i_alpha_a,
                             float i_beta_a)
{
    const mc_fluxobs_f32_cfg_t *cfg;
    float xa;
    float xb;
    float ea;
    float eb;
    float e2;
    float k;
    float resid;
    float psi_a;
    float psi2;
    float inv_psi;
    uint32_t raised = MC_FLUXOBS_ERR_NONE;

    if (st == NULL) {
        return MC_FLUXOBS_ERR_NULL;
    }
    cfg = &st->cfg;
    /* non-salient: psi_a is the flux, psi_a^2 and 1/psi_a the values init
     * formed (the step bit for bit as before the active-flux form) */
    psi_a = cfg->flux_wb;
    psi2 = st->flux2;
    inv_psi = st->inv_flux_per_wb;
    if (cfg->ld_minus_lq_h != 0.0f) {
        psi_a = fluxobs_psi_a_prev_angle(st, i_alpha_a, i_beta_a);
        psi2 = psi_a * psi_a;
        inv_psi = 1.0f / psi_a;
    }

    /* Open-loop flux integration, exact for a constant voltage over the
     * period and a current linear in time (trapezoid on R i). */
    xa = st->x_alpha_wb +
         (cfg->dt_s * (v_alpha_v - (st->half_r_ohm * (st->i_alpha_prev_a + i_alpha_a))));
    xb = st->x_beta_wb +
         (cfg->dt_s * (v_beta_v - (st->half_r_ohm * (st->i_beta_prev_a + i_beta_a))));

    /* Gradient correction (9) with the new current. */
    ea = xa - (cfg->l_h * i_alpha_a);
    eb = xb - (cfg->l_h * i_beta_a);
    e2 = (ea * ea) + (eb * eb);
    k = st->half_gamma_dt * (psi2 - e2);
    if (k < -0.5f) {
        k = -0.5f; /* see the clamp in the header */
    }
    /* e <- e + k e (not (1 + k) e: 1 + k would round away the low bits of
     * a small k, and with them the observer's slow dynamics) */
    ea = ea + (k * ea);
    eb = eb + (k * eb);
    xa = ea + (cfg->l_h * i_alpha_a);
    xb = eb + (cfg->l_h * i_beta_a);

    /* A non-finite input makes xa or xb non-finite (every input enters
     * both sums with a nonzero or NaN factor: 0 * inf is NaN), and so does
     * an overflow of finite ones: one test for both, then the step is
     * refused and nothing is stored. x - x is 0 for finite x, NaN else. */
    if (((xa - xa) + (xb - xb)) != 0.0f) {
        st->flags |= MC_FLUXOBS_ERR_NAN_INPUT;
        return MC_FLUXOBS_ERR_NAN_INPUT;
    }
    st->x_alpha_wb = xa;
    st->x_beta_wb = xb;
    st->i_alpha_prev_a = i_alpha_a;
    st->i_beta_prev_a = i_beta_a;
    st->psi_a_wb = psi_a;

    /* Divergence monitor on the constraint residual of the new estimate:
     * |e| = (1 + k) |e_before| (1 + k >= 1/2 > 0), to float rounding, far
     * inside any useful resid_tol; against psi_a (the flux, non-salient). */
    resid = (((1.0f + k) * mc_sqrt_nonneg_f32(e2)) * inv_psi) - 1.0f;
    st->resid = resid;
    if (mc_fabs_f32(resid) > cfg->resid_tol) {
        st->resid_bad_s += cfg->dt_s;
        if (st->resid_bad_s > cfg->resid_time_s) {
            st->resid_bad_s = cfg->resid_time_s; /* clamp the timer */
            st->flags |= MC_FLUXOBS_ERR_DIVERGED;
            raised = MC_FLUXOBS_ERR_DIVERGED;
        }
    } else {
        st->resid_bad_s = 0.0f;
    }

    /* The angle: mc_atan2_f32's common case inline (finite, not both 0,
     * |ea| + |eb| finite), the rest out of line. */
    {
        const float ax = mc_fabs_f32(ea);
        const float ay = mc_fabs_f32(eb);
        union {
            float f;
            uint32_t u;
        } sum;
        sum.f = ax + ay;
        if ((sum.u - 1u) >= 0x7F7FFFFFu) {
            return fluxobs_finish_special(st, eb, ea, raised);
        }
        st->theta_e_rad = mc_atan2_octant_f32(ay, ax, ea < 0.0f, mc_signbit_f32(eb));
    }
    return raised;
}

uint32_t mc_fluxobs_f32_gamma_for_critical_speed(float omega_crit_m_rad_s, uint32_t pole_pairs,
                                                 float flux_wb, float *p_gamma)
{
    float g;

    if (p_gamma == NULL) {
        return MC_FLUXOBS_ERR_NULL;
    }
    if (!pos_finite(omega_crit_m_rad_s) || (pole_pairs == 0u) || !pos_finite(flux_wb)) {
        return MC_FLUXOBS_ERR_ARG;
    }
    g = (4.0f * (float)pole_pairs * omega_crit_m_rad_s) / (flux_wb * flux_wb);
    if (!pos_finite(g)) {
        return MC_FLUXOBS_ERR_ARG;
    }
    *p_gamma = g;
    return MC_FLUXOBS_ERR_NONE;
}

uint32_t mc_fluxobs_f32_critical_speed(float gamma, uint32_t pole_pairs, float flux_wb,
                                       float *p_omega_crit_m_rad_s)
{
    float w;

    if (p_omega_crit_m_rad_s == NULL) {
        return MC_FLUXOBS_ERR_NULL;
    }
    if (!pos_finite(gamma) || (pole_pairs == 0u) || !pos_finite(flux_wb)) {
        return MC_FLUXOBS_ERR_ARG;
    }
    w = (gamma * flux_wb * flux_wb) / (4.0f * (float)pole_pairs);
    if (!pos_finite(w)) {
        return MC_FLUXOBS_ERR_ARG;
    }
    *p_omega_crit_m_rad_s = w;
    return MC_FLUXOBS_ERR_NONE;
}

uint32_t mc_fluxobs_f32_time_scale(float gamma, float flux_wb, float *p_t_s)
{
    float t;

    if (p_t_s == NULL) {
        return MC_FLUXOBS_ERR_NULL;
    }
    if (!pos_finite(gamma) || !pos_finite(flux_wb)) {
        return MC_FLUXOBS_ERR_ARG;
    }
    t = 2.0f / (gamma * flux_wb * flux_wb);
    if (!pos_finite(t)) {
        return MC_FLUXOBS_ERR_ARG;
    }
    *p_t_s = t;
    return MC_FLUXOBS_ERR_NONE;
}
