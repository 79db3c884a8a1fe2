/**
 * @file mc_hallobs_q31.c
 * @brief Hall-to-observer hand-over, q31 (see mc_hallobs_q31.h).
 */
#include "hall/mc_hallobs_q31.h"

#include <stddef.h>

#include "math/mc_math.h"

/* b - a as a q31 angle difference: wraps modulo one turn, exactly. */
static q31_t angle_diff(q31_t b, q31_t a)
{
    return (q31_t)(int32_t)((uint32_t)b - (uint32_t)a); /* two's complement (GCC: modular) */
}

uint32_t mc_hallobs_q31_init(mc_hallobs_q31_t *st, const mc_hallobs_q31_cfg_t *cfg)
{
    mc_hallobs_f32_t f;
    mc_q46_gain_t g;
    uint32_t err;

    if ((st == NULL) || (cfg == NULL)) {
        return MC_HALLOBS_ERR_NULL;
    }
    err = mc_hallobs_f32_init(&f, &cfg->f);
    if (err != MC_HALLOBS_ERR_NONE) {
        return err;
    }
    if (!mc_isfinite_f32(cfg->omega_base_rad_s) ||
        !(cfg->omega_base_rad_s > cfg->f.omega_end_e_rad_s) ||
        !mc_q46_gain_from_f32(
            cfg->omega_base_rad_s / (cfg->f.omega_end_e_rad_s - cfg->f.omega_start_e_rad_s), &g)) {
        return MC_HALLOBS_ERR_SCALE;
    }
    st->cfg = *cfg;
    st->start = mc_q31_from_f32(cfg->f.omega_start_e_rad_s / cfg->omega_base_rad_s);
    st->inv_span = g;
    st->disagree_max = mc_q31_angle_from_rad_f32(cfg->f.disagree_max_e_rad);
    return mc_hallobs_q31_reset(st);
}

uint32_t mc_hallobs_q31_reset(mc_hallobs_q31_t *st)
{
    if (st == NULL) {
        return MC_HALLOBS_ERR_NULL;
    }
    st->w_obs = 0;
    st->flags = MC_HALLOBS_ERR_NONE;
    return MC_HALLOBS_ERR_NONE;
}

uint32_t mc_hallobs_q31_step(mc_hallobs_q31_t *st, q31_t theta_hall, q31_t theta_obs, q31_t omega,
                             q31_t *p_theta)
{
    q31_t over;
    q31_t w;
    q31_t d;

    if ((st == NULL) || (p_theta == NULL)) {
        return MC_HALLOBS_ERR_NULL;
    }
    over = mc_q31_sub_sat(mc_q31_abs_sat(omega), st->start);
    w = (over <= 0) ? 0 : mc_q46_to_q31(mc_q46_mul_q31(st->inv_span, over)); /* saturates at 1 */
    d = angle_diff(theta_obs, theta_hall);
    if ((w > 0) && (mc_q31_abs_sat(d) > st->disagree_max)) {
        st->w_obs = 0;
        st->flags |= MC_HALLOBS_ERR_DISAGREE;
        *p_theta = theta_hall;
        return MC_HALLOBS_ERR_DISAGREE;
    }
    st->w_obs = w;
    *p_theta = mc_q31_angle_add(theta_hall, mc_q31_mul(w, d));
    return MC_HALLOBS_ERR_NONE;
}
