/**
 * @file mc_enctrack.c
 * @brief Encoder tracking loop, float32. Law and limits: mc_enctrack.h.
 */
#include "observer/mc_enctrack.h"

#include <stddef.h>

#include "math/mc_math.h"

uint32_t mc_enctrack_f32_init(mc_enctrack_f32_t *st, const mc_enctrack_f32_cfg_t *cfg)
{
    if ((st == NULL) || (cfg == NULL)) {
        return MC_ENCTRACK_ERR_NULL;
    }
    uint32_t err = MC_ENCTRACK_ERR_NONE;
    const float dt = cfg->dt_s;
    const float bw = cfg->bw_rad_s;
    const bool dt_ok = mc_isfinite_f32(dt) && (dt > 0.0f);
    if (!dt_ok) {
        err |= MC_ENCTRACK_ERR_DT;
    }
    if (!mc_isfinite_f32(bw) || !(bw > 0.0f) || (dt_ok && !(3.0f * bw * dt <= 1.0f))) {
        err |= MC_ENCTRACK_ERR_BW;
    }
    if (err != MC_ENCTRACK_ERR_NONE) {
        return err;
    }
    st->cfg = *cfg;
    st->k1_dt = 3.0f * bw * dt;
    st->k2_dt = 3.0f * bw * bw * dt;
    st->k3_dt = bw * bw * bw * dt;
    st->err = MC_ENCTRACK_ERR_NONE;
    return mc_enctrack_f32_reset(st);
}

uint32_t mc_enctrack_f32_reset(mc_enctrack_f32_t *st)
{
    if (st == NULL) {
        return MC_ENCTRACK_ERR_NULL;
    }
    st->theta_rad = 0.0f;
    st->omega_rad_s = 0.0f;
    st->alpha_rad_s2 = 0.0f;
    st->primed = false;
    return MC_ENCTRACK_ERR_NONE;
}

uint32_t mc_enctrack_f32_step(mc_enctrack_f32_t *st, float theta_meas_rad)
{
    if (st == NULL) {
        return MC_ENCTRACK_ERR_NULL;
    }
    if (!mc_isfinite_f32(theta_meas_rad)) {
        st->err |= MC_ENCTRACK_ERR_NAN_INPUT;
        return MC_ENCTRACK_ERR_NAN_INPUT;
    }
    if (!st->primed) {
        st->theta_rad = theta_meas_rad;
        st->omega_rad_s = 0.0f;
        st->alpha_rad_s2 = 0.0f;
        st->primed = true;
        return MC_ENCTRACK_ERR_NONE;
    }
    const float dt = st->cfg.dt_s;
    const float predicted = mc_wrap_2pi_fast_f32(st->theta_rad + st->omega_rad_s * dt);
    const float e = mc_wrap_pi_fast_f32(theta_meas_rad - predicted);
    st->theta_rad = mc_wrap_2pi_fast_f32(predicted + st->k1_dt * e);
    st->omega_rad_s += st->alpha_rad_s2 * dt + st->k2_dt * e;
    st->alpha_rad_s2 += st->k3_dt * e;
    return MC_ENCTRACK_ERR_NONE;
}
