/**
 * @file mc_drive_hallobs.c
 * @brief Hall + observer in the drive: see mc_drive_hallobs.h.
 */
#include "mc_drive_hallobs.h"

#include <stddef.h>

#include "math/mc_math.h"
#include "transforms/mc_transforms.h"

uint32_t mc_drive_hallobs_init(mc_drive_hallobs_t *h, const mc_drive_hallobs_cfg_t *cfg)
{
    mc_fluxobs_f32_t obs;
    mc_spdpll_f32_t pll;
    mc_hallobs_f32_t blend;
    uint32_t err = MC_DRIVE_HALLOBS_ERR_NONE;

    if ((h == NULL) || (cfg == NULL)) {
        return MC_DRIVE_HALLOBS_ERR_NULL;
    }
    if (mc_hallobs_f32_init(&blend, &cfg->blend) != MC_HALLOBS_ERR_NONE) {
        err |= MC_DRIVE_HALLOBS_ERR_BLEND;
    }
    if (!(cfg->dt_s > 0.0f) || !mc_isfinite_f32(cfg->dt_s) || (cfg->pwm_delay_periods > 3u)) {
        err |= MC_DRIVE_HALLOBS_ERR_TIMING;
    }
    {
        const mc_fluxobs_f32_cfg_t oc = {.r_ohm = cfg->r_ohm,
                                         .l_h = cfg->l_h,
                                         .flux_wb = cfg->flux_wb,
                                         .gamma = cfg->gamma,
                                         .dt_s = cfg->dt_s,
                                         .resid_tol = cfg->resid_tol,
                                         .resid_time_s = cfg->resid_time_s};
        if (mc_fluxobs_f32_init(&obs, &oc) != MC_FLUXOBS_ERR_NONE) {
            err |= MC_DRIVE_HALLOBS_ERR_OBSERVER;
        }
    }
    {
        const mc_spdpll_f32_cfg_t pc = {.bw_rad_s = cfg->pll_bw_rad_s,
                                        .dt_s = cfg->dt_s,
                                        .omega_max_rad_s = cfg->omega_max_e_rad_s};
        if (mc_spdpll_f32_init(&pll, &pc) != MC_SPDPLL_ERR_NONE) {
            err |= MC_DRIVE_HALLOBS_ERR_PLL;
        }
    }
    if (err != MC_DRIVE_HALLOBS_ERR_NONE) {
        return err;
    }
    {
        float t_obs = 0.0f;
        (void)mc_fluxobs_f32_time_scale(cfg->gamma, cfg->flux_wb, &t_obs); /* valid above */
        h->settle_steps = (uint32_t)((MC_DRIVE_HALLOBS_SETTLE_T * t_obs / cfg->dt_s) + 1.0f);
    }
    h->cfg = *cfg;
    h->obs = obs;
    h->pll = pll;
    h->blend = blend;
    h->flags = MC_HALLOBS_ERR_NONE;
    h->theta_obs_e_rad = 0.0f;
    h->omega_obs_e_rad_s = 0.0f;
    mc_drive_hallobs_stop(h);
    return MC_DRIVE_HALLOBS_ERR_NONE;
}

void mc_drive_hallobs_stop(mc_drive_hallobs_t *h)
{
    if (h != NULL) {
        h->running = false;
        h->fallback = false;
        h->w_obs = 0.0f;
    }
}

uint32_t mc_drive_hallobs_set_r_scale(mc_drive_hallobs_t *h, float r_scale)
{
    if (h == NULL) {
        return MC_DRIVE_HALLOBS_ERR_NULL;
    }
    return (mc_fluxobs_f32_set_r_scale(&h->obs, r_scale) == MC_FLUXOBS_ERR_NONE)
               ? MC_DRIVE_HALLOBS_ERR_NONE
               : MC_DRIVE_HALLOBS_ERR_OBSERVER;
}

/* The observer and its PLL from the Hall angle and speed (the flux vector
 * where the Hall says the rotor is). */
static void restart(mc_drive_hallobs_t *h, const mc_drive_hallobs_in_t *in, float i_al, float i_be)
{
    uint32_t k;
    (void)mc_fluxobs_f32_reset(&h->obs, mc_wrap_pi_f32(in->theta_hall_e_rad), i_al, i_be);
    (void)mc_spdpll_f32_reset(&h->pll, mc_wrap_pi_f32(in->theta_hall_e_rad),
                              in->omega_hall_e_rad_s);
    (void)mc_hallobs_f32_reset(&h->blend);
    h->settle_left = h->settle_steps;
    for (k = 0u; k < 4u; ++k) {
        h->v_hist_a[k] = in->v_alpha_prev_v;
        h->v_hist_b[k] = in->v_beta_prev_v;
    }
}

float mc_drive_hallobs_step(mc_drive_hallobs_t *h, const mc_drive_hallobs_in_t *in)
{
    float i_al;
    float i_be;
    float omega = 0.0f;
    float theta = in->theta_hall_e_rad;
    uint32_t k;
    uint32_t e;

    if (h->fallback) {
        return theta; /* DISAGREE this run: the Hall angle until the next enable */
    }
    mc_clarke_f32(in->ia_a, in->ib_a, &i_al, &i_be);
    if (!h->running) {
        restart(h, in, i_al, i_be);
        h->running = true;
    }
    for (k = 3u; k > 0u; --k) {
        h->v_hist_a[k] = h->v_hist_a[k - 1u];
        h->v_hist_b[k] = h->v_hist_b[k - 1u];
    }
    h->v_hist_a[0] = in->v_alpha_prev_v;
    h->v_hist_b[0] = in->v_beta_prev_v;
    (void)mc_fluxobs_f32_step(&h->obs, h->v_hist_a[h->cfg.pwm_delay_periods],
                              h->v_hist_b[h->cfg.pwm_delay_periods], i_al, i_be);
    (void)mc_spdpll_f32_step(&h->pll, h->obs.theta_e_rad, &omega);
    h->theta_obs_e_rad = h->obs.theta_e_rad;
    h->omega_obs_e_rad_s = omega;
    if (h->settle_left > 0u) {
        h->settle_left--;
        h->w_obs = 0.0f;
        return mc_wrap_2pi_f32(theta); /* the restarted observer settles */
    }
    if ((mc_fabs_f32(omega) <= h->cfg.blend.omega_start_e_rad_s) &&
        (mc_fabs_f32(mc_wrap_pi_f32(h->obs.theta_e_rad - in->theta_hall_e_rad)) >
         h->cfg.blend.disagree_max_e_rad)) {
        /* below the hand-over the observer's angle is not used: one that
         * wandered (its critical speed) starts again from the Hall's */
        restart(h, in, i_al, i_be);
        h->w_obs = 0.0f;
        return mc_wrap_2pi_f32(theta);
    }
    e = mc_hallobs_f32_step(&h->blend, in->theta_hall_e_rad, h->obs.theta_e_rad, omega, &theta);
    h->w_obs = h->blend.w_obs;
    if (e != MC_HALLOBS_ERR_NONE) {
        /* DISAGREE (or a non-finite observer state): the Hall angle, latched */
        h->flags |= e;
        h->fallback = true;
        h->w_obs = 0.0f;
    }
    return theta;
}
