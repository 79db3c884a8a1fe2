/**
 * @file mc_hallobs.c
 * @brief Hall-to-observer hand-over, float32 (see mc_hallobs.h).
 */
#include "hall/mc_hallobs.h"

#include <stddef.h>

#include "math/mc_math.h"

uint32_t mc_hallobs_f32_init(mc_hallobs_f32_t *st, const mc_hallobs_f32_cfg_t *cfg)
{
    if ((st == NULL) || (cfg == NULL)) {
        return MC_HALLOBS_ERR_NULL;
    }
    if (!mc_isfinite_f32(cfg->omega_start_e_rad_s) || !mc_isfinite_f32(cfg->omega_end_e_rad_s) ||
        !(cfg->omega_start_e_rad_s > 0.0f) ||
        !(cfg->omega_end_e_rad_s > cfg->omega_start_e_rad_s) ||
        !mc_isfinite_f32(cfg->disagree_max_e_rad) || !(cfg->disagree_max_e_rad > 0.0f) ||
        !(cfg->disagree_max_e_rad <= 0.5f * MC_PI_F32)) {
        return MC_HALLOBS_ERR_CFG;
    }
    st->cfg = *cfg;
    st->inv_span = 1.0f / (cfg->omega_end_e_rad_s - cfg->omega_start_e_rad_s);
    return mc_hallobs_f32_reset(st);
}

uint32_t mc_hallobs_f32_reset(mc_hallobs_f32_t *st)
{
    if (st == NULL) {
        return MC_HALLOBS_ERR_NULL;
    }
    st->w_obs = 0.0f;
    st->flags = MC_HALLOBS_ERR_NONE;
    return MC_HALLOBS_ERR_NONE;
}

uint32_t mc_hallobs_f32_step(mc_hallobs_f32_t *st, float theta_hall_e_rad, float theta_obs_e_rad,
                             float omega_e_rad_s, float *p_theta_e_rad)
{
    float w;
    float d;

    if ((st == NULL) || (p_theta_e_rad == NULL)) {
        return MC_HALLOBS_ERR_NULL;
    }
    if (!mc_isfinite_f32(theta_hall_e_rad) || !mc_isfinite_f32(theta_obs_e_rad) ||
        !mc_isfinite_f32(omega_e_rad_s)) {
        st->w_obs = 0.0f;
        st->flags |= MC_HALLOBS_ERR_NAN;
        *p_theta_e_rad =
            mc_isfinite_f32(theta_hall_e_rad) ? mc_wrap_2pi_f32(theta_hall_e_rad) : 0.0f;
        return MC_HALLOBS_ERR_NAN;
    }
    w = mc_sat_f32((mc_fabs_f32(omega_e_rad_s) - st->cfg.omega_start_e_rad_s) * st->inv_span, 0.0f,
                   1.0f);
    d = mc_wrap_pi_f32(theta_obs_e_rad - theta_hall_e_rad);
    if ((w > 0.0f) && (mc_fabs_f32(d) > st->cfg.disagree_max_e_rad)) {
        st->w_obs = 0.0f;
        st->flags |= MC_HALLOBS_ERR_DISAGREE;
        *p_theta_e_rad = mc_wrap_2pi_f32(theta_hall_e_rad);
        return MC_HALLOBS_ERR_DISAGREE;
    }
    st->w_obs = w;
    *p_theta_e_rad = mc_wrap_2pi_f32(theta_hall_e_rad + (w * d));
    return MC_HALLOBS_ERR_NONE;
}
