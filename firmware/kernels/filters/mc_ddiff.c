/**
 * @file mc_ddiff.c
 * @brief Dirty-derivative filter, Tustin discretisation (see mc_ddiff.h).
 */
#include "filters/mc_ddiff.h"

#include <stddef.h>

#include "math/mc_math.h"

uint32_t mc_ddiff_f32_init(mc_ddiff_f32_t *st, const mc_ddiff_f32_cfg_t *cfg)
{
    if ((st == NULL) || (cfg == NULL)) {
        return MC_DDIFF_ERR_NULL;
    }
    uint32_t err = MC_DDIFF_ERR_NONE;
    if (!mc_isfinite_f32(cfg->a_per_s) || !(cfg->a_per_s > 0.0f)) {
        err |= MC_DDIFF_ERR_A;
    }
    if (!mc_isfinite_f32(cfg->b) || !(cfg->b > 0.0f)) {
        err |= MC_DDIFF_ERR_B;
    }
    if (!mc_isfinite_f32(cfg->dt_s) || !(cfg->dt_s > 0.0f)) {
        err |= MC_DDIFF_ERR_DT;
    }
    if (err != MC_DDIFF_ERR_NONE) {
        return err;
    }
    const float h = 0.5f * cfg->a_per_s * cfg->dt_s; /* a dt / 2 */
    const float den = 1.0f + h;
    const float c_q = (1.0f - h) / den;
    const float g = cfg->b / den;
    if (!mc_isfinite_f32(c_q) || !mc_isfinite_f32(g)) {
        /* a dt so large that the coefficients overflow: treat as a bad a. */
        return MC_DDIFF_ERR_A;
    }
    st->a_per_s = cfg->a_per_s;
    st->b = cfg->b;
    st->dt_s = cfg->dt_s;
    st->c_q = c_q;
    st->g = g;
    st->out = 0.0f;
    st->c_k = 1.0f;
    st->g_k = cfg->b;
    st->y_prev = 0.0f;
    st->flags = MC_DDIFF_ERR_NONE;
    return MC_DDIFF_ERR_NONE;
}

uint32_t mc_ddiff_f32_reset(mc_ddiff_f32_t *st, float q0)
{
    if (st == NULL) {
        return MC_DDIFF_ERR_NULL;
    }
    if (!mc_isfinite_f32(q0)) {
        return MC_DDIFF_ERR_NAN_INPUT;
    }
    st->out = q0;
    st->c_k = 1.0f;
    st->g_k = st->b;
    st->y_prev = 0.0f;
    st->flags = MC_DDIFF_ERR_NONE;
    return MC_DDIFF_ERR_NONE;
}

uint32_t mc_ddiff_f32_step(mc_ddiff_f32_t *st, float y, float *p_theta_f)
{
    if ((st == NULL) || (p_theta_f == NULL)) {
        return MC_DDIFF_ERR_NULL;
    }
    if (!mc_isfinite_f32(y)) {
        st->flags |= MC_DDIFF_ERR_NAN_INPUT;
        *p_theta_f = st->out;
        return MC_DDIFF_ERR_NAN_INPUT;
    }
    /* Tustin on theta_f = b s/(s+a) y (see the header for why theta_f, not
     * q_c, is the state); the first sample gives q_c(0) + b y(0), as (12). */
    const float th = mc_ddiff_f32_next(st, y);
    mc_ddiff_f32_commit(st, y, th);
    *p_theta_f = th;
    return MC_DDIFF_ERR_NONE;
}
