/**
 * @file mc_csvc_q31.c
 * @brief Conditional servocompensator / integrator, q31 twin (see
 *        mc_csvc_q31.h).
 */
#include "csmc/mc_csvc_q31.h"

#include <stdbool.h>
#include <stddef.h>

#include "math/mc_math.h"

uint32_t mc_csvc_q31_init(mc_csvc_q31_t *st, const mc_csvc_q31_cfg_t *cfg)
{
    mc_csvc_f32_t ref;
    uint32_t err;
    mc_csvc_q31_t t;
    float base[MC_CSVC_MAX_ORDER];
    bool ok = true;

    if ((st == NULL) || (cfg == NULL)) {
        return MC_CSVC_ERR_NULL;
    }
    err = mc_csvc_f32_init(&ref, &cfg->f);
    if (!(cfg->s_base > 0.0f) || !mc_isfinite_f32(cfg->s_base)) {
        err |= MC_CSVC_ERR_SCALE;
    }
    if (err != MC_CSVC_ERR_NONE) {
        return err;
    }
    t.n = ref.n;
    for (uint32_t i = 0u; i < MC_CSVC_MAX_ORDER; ++i) {
        const float k = (i < ref.n) ? ref.k0[i] : 0.0f;
        base[i] = (k != 0.0f) ? (cfg->s_base / mc_abs_f32(k)) : cfg->s_base;
        t.k0_sign[i] = (k > 0.0f) ? 1 : ((k < 0.0f) ? -1 : 0);
        t.w_q46[i] = 0;
        t.gam[i].mant = 0;
        t.gam[i].shift = 0;
        for (uint32_t j = 0u; j < MC_CSVC_MAX_ORDER; ++j) {
            t.phi[(i * MC_CSVC_MAX_ORDER) + j].mant = 0;
            t.phi[(i * MC_CSVC_MAX_ORDER) + j].shift = 0;
        }
    }
    for (uint32_t i = 0u; i < ref.n; ++i) {
        for (uint32_t j = 0u; j < ref.n; ++j) {
            ok = ok && mc_q46_gain_from_f32((ref.phi[(i * ref.n) + j] * base[j]) / base[i],
                                            &t.phi[(i * MC_CSVC_MAX_ORDER) + j]);
        }
        ok = ok && mc_q46_gain_from_f32((ref.gam[i] * cfg->s_base) / base[i], &t.gam[i]);
    }
    if (!ok) {
        return MC_CSVC_ERR_SCALE;
    }
    t.mu_q46 = mc_q46_from_q31(mc_q31_from_f32(cfg->f.mu / cfg->s_base));
    if (t.mu_q46 <= 0) {
        return MC_CSVC_ERR_SCALE;
    }
    *st = t;
    return MC_CSVC_ERR_NONE;
}

uint32_t mc_csvc_q31_reset(mc_csvc_q31_t *st)
{
    if (st == NULL) {
        return MC_CSVC_ERR_NULL;
    }
    for (uint32_t i = 0u; i < MC_CSVC_MAX_ORDER; ++i) {
        st->w_q46[i] = 0;
    }
    return MC_CSVC_ERR_NONE;
}

int64_t mc_csvc_q31_term_q46(const mc_csvc_q31_t *st)
{
    int64_t acc = 0;

    if (st == NULL) {
        return 0;
    }
    for (uint32_t i = 0u; (i < st->n) && (i < MC_CSVC_MAX_ORDER); ++i) {
        if (st->k0_sign[i] > 0) {
            acc = mc_q46_add(acc, st->w_q46[i]);
        } else if (st->k0_sign[i] < 0) {
            acc = mc_q46_add(acc, -st->w_q46[i]);
        } else {
            /* K0_i = 0: no share in the term */
        }
    }
    return acc;
}

void mc_csvc_q31_update(mc_csvc_q31_t *st, int64_t s_q46)
{
    int64_t v;
    int64_t next[MC_CSVC_MAX_ORDER];
    const uint32_t n = (st != NULL) ? st->n : 0u;

    if ((st == NULL) || (n == 0u) || (n > MC_CSVC_MAX_ORDER)) {
        return;
    }
    /* v = mu sat(s/mu) - K0 sigma */
    v = mc_q46_add(mc_q46_clamp(mc_q46_sat(s_q46), -st->mu_q46, st->mu_q46),
                   -mc_csvc_q31_term_q46(st));
    for (uint32_t i = 0u; i < n; ++i) {
        int64_t acc = mc_q46_mul(st->gam[i], v);
        for (uint32_t j = 0u; j < n; ++j) {
            acc = mc_q46_add(acc, mc_q46_mul(st->phi[(i * MC_CSVC_MAX_ORDER) + j], st->w_q46[j]));
        }
        next[i] = acc;
    }
    for (uint32_t i = 0u; i < n; ++i) {
        st->w_q46[i] = next[i];
    }
}
