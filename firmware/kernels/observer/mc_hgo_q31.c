/**
 * @file mc_hgo_q31.c
 * @brief High-gain observer, q31 twin (see mc_hgo_q31.h).
 */
#include "observer/mc_hgo_q31.h"

#include <stdbool.h>
#include <stddef.h>

#include "math/mc_math.h"

static bool hq_pos(float x)
{
    return (x > 0.0f) && mc_isfinite_f32(x);
}

uint32_t mc_hgo_q31_init(mc_hgo_q31_t *st, const mc_hgo_q31_cfg_t *cfg)
{
    mc_hgo_f32_t ref;
    uint32_t err;
    mc_hgo_q31_t t;
    bool ok = true;

    if ((st == NULL) || (cfg == NULL)) {
        return MC_HGO_ERR_NULL;
    }
    err = mc_hgo_f32_init(&ref, &cfg->f);
    if (!hq_pos(cfg->y_base) || !hq_pos(cfg->z2_base) || !hq_pos(cfg->z3_base)) {
        err |= MC_HGO_ERR_SCALE;
    }
    if (err != MC_HGO_ERR_NONE) {
        return err;
    }
    for (uint32_t i = 0u; i < 9u; ++i) {
        ok = ok && mc_q46_gain_from_f32(ref.phi[i], &t.phi[i]);
    }
    for (uint32_t i = 0u; i < 3u; ++i) {
        ok = ok && mc_q46_gain_from_f32(ref.g1[i], &t.g1[i]);
        ok = ok && mc_q46_gain_from_f32(ref.g2[i], &t.g2[i]);
    }
    ok = ok && mc_q46_gain_from_f32((cfg->y_base * ref.inv_eps) / cfg->z2_base, &t.out2);
    ok = ok &&
         mc_q46_gain_from_f32(((cfg->y_base * ref.inv_eps) * ref.inv_eps) / cfg->z3_base, &t.out3);
    ok = ok && mc_q46_gain_from_f32((cfg->z2_base * ref.eps_s) / cfg->y_base, &t.in2);
    ok = ok && mc_q46_gain_from_f32(((cfg->z3_base * ref.eps_s) * ref.eps_s) / cfg->y_base, &t.in3);
    if (!ok) {
        return MC_HGO_ERR_SCALE;
    }
    t.input_order = ref.input_order;
    t.n_hist = 0u;
    t.y1 = 0;
    t.y2 = 0;
    t.eta_q46[0] = 0;
    t.eta_q46[1] = 0;
    t.eta_q46[2] = 0;
    *st = t;
    return MC_HGO_ERR_NONE;
}

uint32_t mc_hgo_q31_reset(mc_hgo_q31_t *st, q31_t z1, q31_t z2, q31_t z3)
{
    if (st == NULL) {
        return MC_HGO_ERR_NULL;
    }
    st->n_hist = 0u;
    st->y1 = 0;
    st->y2 = 0;
    st->eta_q46[0] = mc_q46_from_q31(z1);
    st->eta_q46[1] = mc_q46_mul_q31(st->in2, z2);
    st->eta_q46[2] = mc_q46_mul_q31(st->in3, z3);
    return MC_HGO_ERR_NONE;
}

uint32_t mc_hgo_q31_step(mc_hgo_q31_t *st, q31_t y, mc_hgo_q31_est_t *p_est)
{
    int64_t v1 = 0;
    int64_t v2 = 0;
    int64_t y46;
    int64_t d0;
    int64_t n[3];

    if ((st == NULL) || (p_est == NULL)) {
        return MC_HGO_ERR_NULL;
    }
    p_est->z1 = mc_q46_to_q31(st->eta_q46[0]);
    p_est->z2 = mc_q46_to_q31(mc_q46_mul(st->out2, st->eta_q46[1]));
    p_est->z3 = mc_q46_to_q31(mc_q46_mul(st->out3, st->eta_q46[2]));

    /* Newton backward coefficients in Q46, exact from the q31 samples. */
    if ((st->input_order >= 1u) && (st->n_hist >= 1u)) {
        const int64_t dy = (int64_t)y - (int64_t)st->y1;
        v1 = dy * ((int64_t)1 << 15);
        if ((st->input_order >= 2u) && (st->n_hist >= 2u)) {
            const int64_t d2 = (dy - (int64_t)st->y1) + (int64_t)st->y2;
            v2 = d2 * ((int64_t)1 << 15);
            v1 = v1 + (d2 * ((int64_t)1 << 14)); /* dy + v2/2 */
        }
    }
    y46 = mc_q46_from_q31(y);
    d0 = mc_q46_add(st->eta_q46[0], -y46);
    for (uint32_t i = 0u; i < 3u; ++i) {
        int64_t acc = mc_q46_mul(st->phi[(i * 3u) + 0u], d0);
        acc = mc_q46_add(acc, mc_q46_mul(st->phi[(i * 3u) + 1u], st->eta_q46[1]));
        acc = mc_q46_add(acc, mc_q46_mul(st->phi[(i * 3u) + 2u], st->eta_q46[2]));
        acc = mc_q46_add(acc, mc_q46_mul(st->g1[i], v1));
        acc = mc_q46_add(acc, mc_q46_mul(st->g2[i], v2));
        n[i] = acc;
    }
    st->eta_q46[0] = mc_q46_add(y46, n[0]);
    st->eta_q46[1] = n[1];
    st->eta_q46[2] = n[2];
    st->y2 = st->y1;
    st->y1 = y;
    if (st->n_hist < 2u) {
        st->n_hist += 1u;
    }
    return MC_HGO_ERR_NONE;
}
