/**
 * @file mc_spdpll_q31.c
 * @brief PLL speed estimator, q31 twin (see mc_spdpll_q31.h).
 */
#include "observer/mc_spdpll_q31.h"

#include <stdbool.h>
#include <stddef.h>

#include "math/mc_math.h"

/* uint32 to int32 two's complement without implementation-defined casts. */
static int32_t pll_i32(uint32_t u)
{
    if (u <= 0x7FFFFFFFu) {
        return (int32_t)u;
    }
    return -(int32_t)(~u) - 1;
}

static q31_t pll_angle_of(uint64_t turn64)
{
    /* rounded to the nearest q31 turn, modulo one turn */
    return pll_i32((uint32_t)((turn64 + ((uint64_t)1 << 31)) >> 32));
}

uint32_t mc_spdpll_q31_init(mc_spdpll_q31_t *st, const mc_spdpll_q31_cfg_t *cfg)
{
    mc_spdpll_f32_t ref;
    uint32_t err;
    mc_q46_gain_t kp;
    mc_q46_gain_t ki;
    mc_q46_gain_t dz;
    float wb;

    if ((st == NULL) || (cfg == NULL)) {
        return MC_SPDPLL_ERR_NULL;
    }
    err = mc_spdpll_f32_init(&ref, &cfg->f);
    wb = cfg->omega_base_rad_s;
    if (!(wb > 0.0f) || !mc_isfinite_f32(wb)) {
        err |= MC_SPDPLL_ERR_SCALE;
    }
    if (err != MC_SPDPLL_ERR_NONE) {
        return err;
    }
    if (!mc_q46_gain_from_f32((ref.kp_per_s * MC_PI_F32) / wb, &kp) ||
        !mc_q46_gain_from_f32((ref.ki_dt_per_s * MC_PI_F32) / wb, &ki) ||
        !mc_q46_gain_from_f32(((cfg->f.dt_s * wb) / MC_PI_F32) * 131072.0f, &dz)) {
        return MC_SPDPLL_ERR_SCALE;
    }
    st->kp = kp;
    st->ki_dt = ki;
    st->dz = dz;
    st->omega_max_q46 = mc_q46_from_q31(mc_q31_from_f32(cfg->f.omega_max_rad_s / wb));
    st->theta_turn64 = 0u;
    st->omega_i_q46 = 0;
    st->theta = 0;
    st->omega = 0;
    st->flags = MC_SPDPLL_ERR_NONE;
    return MC_SPDPLL_ERR_NONE;
}

uint32_t mc_spdpll_q31_reset(mc_spdpll_q31_t *st, q31_t theta, q31_t omega)
{
    int64_t w;

    if (st == NULL) {
        return MC_SPDPLL_ERR_NULL;
    }
    w = mc_q46_clamp(mc_q46_from_q31(omega), -st->omega_max_q46, st->omega_max_q46);
    st->theta_turn64 = ((uint64_t)(uint32_t)theta) << 32;
    st->theta = theta;
    st->omega_i_q46 = w;
    st->omega = mc_q46_to_q31(w);
    st->flags = MC_SPDPLL_ERR_NONE;
    return MC_SPDPLL_ERR_NONE;
}

uint32_t mc_spdpll_q31_step(mc_spdpll_q31_t *st, q31_t theta_in, q31_t *p_omega)
{
    q31_t e;
    int64_t wi;
    int64_t w;
    int64_t dz;
    uint32_t err = MC_SPDPLL_ERR_NONE;
    const int64_t lim = (st != NULL) ? st->omega_max_q46 : 0;

    if ((st == NULL) || (p_omega == NULL)) {
        return MC_SPDPLL_ERR_NULL;
    }
    /* wrapped error: modular difference of two turns */
    e = pll_i32((uint32_t)theta_in - (uint32_t)st->theta);
    wi = mc_q46_add(st->omega_i_q46, mc_q46_mul_q31(st->ki_dt, e));
    if ((wi > lim) || (wi < -lim)) {
        err = MC_SPDPLL_ERR_SAT;
        wi = mc_q46_clamp(wi, -lim, lim);
    }
    w = mc_q46_add(mc_q46_mul_q31(st->kp, e), wi);
    if ((w > lim) || (w < -lim)) {
        err = MC_SPDPLL_ERR_SAT;
        w = mc_q46_clamp(w, -lim, lim);
    }
    st->flags |= err;
    st->omega_i_q46 = wi;
    st->omega = mc_q46_to_q31(w);
    /* z1 += dt w, modulo one turn (uint64 arithmetic is modular) */
    dz = mc_q46_mul(st->dz, w);
    st->theta_turn64 += (uint64_t)dz;
    st->theta = pll_angle_of(st->theta_turn64);
    *p_omega = st->omega;
    return err;
}
