/**
 * @file mc_ddiff_q31.c
 * @brief Dirty-derivative filter, q31 twin (see mc_ddiff_q31.h).
 */
#include "filters/mc_ddiff_q31.h"

#include <stddef.h>

#include "math/mc_math.h"

static bool ddq_base_ok(float b)
{
    return (b > 0.0f) && mc_isfinite_f32(b);
}

uint32_t mc_ddiff_q31_init(mc_ddiff_q31_t *st, const mc_ddiff_q31_cfg_t *cfg)
{
    mc_ddiff_f32_t ref;
    uint32_t err;
    mc_q46_gain_t cq;
    mc_q46_gain_t g;
    mc_q46_gain_t b;

    if ((st == NULL) || (cfg == NULL)) {
        return MC_DDIFF_ERR_NULL;
    }
    /* The f32 twin validates a, b, dt and forms c_q and g the same way. */
    err = mc_ddiff_f32_init(&ref, &cfg->f);
    if (!ddq_base_ok(cfg->y_base) || !ddq_base_ok(cfg->out_base)) {
        err |= MC_DDIFF_ERR_SCALE;
    }
    if (err != MC_DDIFF_ERR_NONE) {
        return err;
    }
    {
        const float ratio = cfg->y_base / cfg->out_base;
        if (!mc_q46_gain_from_f32(ref.c_q, &cq) || !mc_q46_gain_from_f32(ref.g * ratio, &g) ||
            !mc_q46_gain_from_f32(ref.b * ratio, &b)) {
            return MC_DDIFF_ERR_SCALE;
        }
    }
    st->c_q = cq;
    st->g = g;
    st->b = b;
    st->out_q46 = 0;
    st->y_prev = 0;
    st->out = 0;
    st->primed = false;
    st->flags = MC_DDIFF_ERR_NONE;
    return MC_DDIFF_ERR_NONE;
}

uint32_t mc_ddiff_q31_reset(mc_ddiff_q31_t *st, q31_t q0)
{
    if (st == NULL) {
        return MC_DDIFF_ERR_NULL;
    }
    st->out_q46 = mc_q46_from_q31(q0);
    st->y_prev = 0;
    st->out = q0;
    st->primed = false;
    st->flags = MC_DDIFF_ERR_NONE;
    return MC_DDIFF_ERR_NONE;
}

uint32_t mc_ddiff_q31_step(mc_ddiff_q31_t *st, q31_t y, q31_t *p_theta_f)
{
    const int64_t lo = mc_q46_from_q31(MC_Q31_MIN);
    const int64_t hi = mc_q46_from_q31(MC_Q31_MAX);
    int64_t acc;

    if ((st == NULL) || (p_theta_f == NULL)) {
        return MC_DDIFF_ERR_NULL;
    }
    if (st->primed) {
        acc = mc_q46_mul(st->c_q, st->out_q46);
        acc = mc_q46_add(acc, mc_q46_mul_q31(st->g, y));
        acc = mc_q46_add(acc, -mc_q46_mul_q31(st->g, st->y_prev));
    } else {
        acc = mc_q46_add(st->out_q46, mc_q46_mul_q31(st->b, y));
    }
    st->out_q46 = mc_q46_clamp(acc, lo, hi);
    st->primed = true;
    st->y_prev = y;
    st->out = mc_q46_to_q31(st->out_q46);
    *p_theta_f = st->out;
    return MC_DDIFF_ERR_NONE;
}
