/**
 * @file mc_spdpll.c
 * @brief Type-2 PLL speed estimator (paper 002, Section V (iii)); see
 *        mc_spdpll.h.
 */
#include "observer/mc_spdpll.h"

#include <stdbool.h>
#include <stddef.h>

#include "math/mc_math.h"

static bool pos_finite(float x)
{
    return (x > 0.0f) && mc_isfinite_f32(x);
}

uint32_t mc_spdpll_f32_init(mc_spdpll_f32_t *st, const mc_spdpll_f32_cfg_t *cfg)
{
    uint32_t err = MC_SPDPLL_ERR_NONE;

    if ((st == NULL) || (cfg == NULL)) {
        return MC_SPDPLL_ERR_NULL;
    }
    if (!pos_finite(cfg->dt_s)) {
        err |= MC_SPDPLL_ERR_DT;
    }
    if (!pos_finite(cfg->bw_rad_s) ||
        (pos_finite(cfg->dt_s) && !(cfg->bw_rad_s * cfg->dt_s <= MC_SPDPLL_MAX_BW_DT))) {
        err |= MC_SPDPLL_ERR_BW;
    }
    if (!pos_finite(cfg->omega_max_rad_s)) {
        err |= MC_SPDPLL_ERR_LIMIT;
    }
    if (err != MC_SPDPLL_ERR_NONE) {
        return err;
    }
    st->kp_per_s = 2.0f * cfg->bw_rad_s;
    st->ki_dt_per_s = cfg->bw_rad_s * cfg->bw_rad_s * cfg->dt_s;
    st->dt_s = cfg->dt_s;
    st->omega_max_rad_s = cfg->omega_max_rad_s;
    st->theta_rad = 0.0f;
    st->omega_i_rad_s = 0.0f;
    st->omega_rad_s = 0.0f;
    st->flags = MC_SPDPLL_ERR_NONE;
    return MC_SPDPLL_ERR_NONE;
}

uint32_t mc_spdpll_f32_reset(mc_spdpll_f32_t *st, float theta_rad, float omega_rad_s)
{
    float w;

    if (st == NULL) {
        return MC_SPDPLL_ERR_NULL;
    }
    if (!mc_isfinite_f32(theta_rad) || !mc_isfinite_f32(omega_rad_s)) {
        return MC_SPDPLL_ERR_NAN_INPUT;
    }
    w = mc_sat_f32(omega_rad_s, -st->omega_max_rad_s, st->omega_max_rad_s);
    st->theta_rad = mc_wrap_pi_f32(theta_rad);
    st->omega_i_rad_s = w;
    st->omega_rad_s = w;
    st->flags = MC_SPDPLL_ERR_NONE;
    return MC_SPDPLL_ERR_NONE;
}

/* Keeps a rare path out of line: the common step then calls nothing and
 * needs no stack frame. */
#if defined(__GNUC__)
#define SPDPLL_NOINLINE __attribute__((noinline))
#else
#define SPDPLL_NOINLINE
#endif

/* The step's last part when the new angle leaves [-pi, pi): the full wrap,
 * out of line so that the common step calls nothing. Returns err. */
static SPDPLL_NOINLINE uint32_t spdpll_store_wrapped(mc_spdpll_f32_t *st, float theta_next,
                                                     uint32_t err)
{
    st->theta_rad = mc_wrap_pi_fast_f32(theta_next);
    return err;
}

/* The step for an angle error outside (-pi, pi): input check and full
 * wrap, then the same loop as the common case. */
static SPDPLL_NOINLINE uint32_t spdpll_step_far(mc_spdpll_f32_t *st, float theta_in_rad,
                                                float e_raw, float *p_omega_rad_s);

uint32_t mc_spdpll_f32_step(mc_spdpll_f32_t *st, float theta_in_rad, float *p_omega_rad_s)
{
    float e;
    float wi;
    float w;
    float theta_next;
    float lim;
    uint32_t err = MC_SPDPLL_ERR_NONE;

    if ((st == NULL) || (p_omega_rad_s == NULL)) {
        return MC_SPDPLL_ERR_NULL;
    }
    e = theta_in_rad - st->theta_rad;
    lim = st->omega_max_rad_s;
    /* The common case: |e| < pi is its own wrap (and excludes a non-finite
     * input); anything else is checked and wrapped out of line. */
    if (!(mc_fabs_f32(e) < MC_PI_F32)) {
        return spdpll_step_far(st, theta_in_rad, e, p_omega_rad_s);
    }
    wi = st->omega_i_rad_s + (st->ki_dt_per_s * e);
    if (mc_fabs_f32(wi) > lim) {
        st->flags |= MC_SPDPLL_ERR_SAT;
        err = MC_SPDPLL_ERR_SAT;
        wi = mc_sat_f32(wi, -lim, lim);
    }
    w = (st->kp_per_s * e) + wi;
    if (mc_fabs_f32(w) > lim) {
        st->flags |= MC_SPDPLL_ERR_SAT;
        err = MC_SPDPLL_ERR_SAT;
        w = mc_sat_f32(w, -lim, lim);
    }
    st->omega_i_rad_s = wi;
    st->omega_rad_s = w;
    *p_omega_rad_s = w;
    theta_next = st->theta_rad + (st->dt_s * w);
    if (!(mc_fabs_f32(theta_next) < MC_PI_F32)) {
        return spdpll_store_wrapped(st, theta_next, err);
    }
    st->theta_rad = theta_next; /* = mc_wrap_pi_f32(theta_next) */
    return err;
}

static SPDPLL_NOINLINE uint32_t spdpll_step_far(mc_spdpll_f32_t *st, float theta_in_rad,
                                                float e_raw, float *p_omega_rad_s)
{
    float e;
    float wi;
    float w;
    uint32_t err = MC_SPDPLL_ERR_NONE;
    const float lim = st->omega_max_rad_s;

    if (!mc_isfinite_f32(theta_in_rad)) {
        st->flags |= MC_SPDPLL_ERR_NAN_INPUT;
        *p_omega_rad_s = st->omega_rad_s;
        return MC_SPDPLL_ERR_NAN_INPUT;
    }
    e = mc_wrap_pi_fast_f32(e_raw);
    wi = st->omega_i_rad_s + (st->ki_dt_per_s * e);
    if (mc_fabs_f32(wi) > lim) {
        err = MC_SPDPLL_ERR_SAT;
        wi = mc_sat_f32(wi, -lim, lim);
    }
    w = (st->kp_per_s * e) + wi;
    if (mc_fabs_f32(w) > lim) {
        err = MC_SPDPLL_ERR_SAT;
        w = mc_sat_f32(w, -lim, lim);
    }
    st->flags |= err;
    st->omega_i_rad_s = wi;
    st->omega_rad_s = w;
    st->theta_rad = mc_wrap_pi_fast_f32(st->theta_rad + (st->dt_s * w));
    *p_omega_rad_s = w;
    return err;
}
