/**
 * @file mc_hgo.c
 * @brief High-gain observer, exact ZOH discretisation (see mc_hgo.h).
 */
#include "csmc/mc_hgo.h"

#include <stdbool.h>
#include <stddef.h>

#include "csmc/mc_csmc_linalg.h"
#include "math/mc_math.h"

static bool hgo_pos(float v)
{
    return (v > 0.0f) && mc_isfinite_f32(v);
}

uint32_t mc_hgo_f32_init(mc_hgo_f32_t *st, const mc_hgo_f32_cfg_t *cfg)
{
    uint32_t err = MC_HGO_ERR_NONE;
    float z[36];
    float ez[36];
    float h;
    float inv_eps;

    if ((st == NULL) || (cfg == NULL)) {
        return MC_HGO_ERR_NULL;
    }
    if (!hgo_pos(cfg->alpha1) || !hgo_pos(cfg->alpha2) || !hgo_pos(cfg->alpha3) ||
        !((cfg->alpha1 * cfg->alpha2) > cfg->alpha3)) {
        err |= MC_HGO_ERR_ALPHA;
    }
    /* 1/eps^2 must be a finite float too. */
    if (!hgo_pos(cfg->eps_s) || !mc_isfinite_f32((1.0f / cfg->eps_s) * (1.0f / cfg->eps_s))) {
        err |= MC_HGO_ERR_EPS;
    }
    if (!hgo_pos(cfg->dt_s)) {
        err |= MC_HGO_ERR_DT;
    }
    if (cfg->input_order > 2u) {
        err |= MC_HGO_ERR_ORDER;
    }
    if (err != MC_HGO_ERR_NONE) {
        return err;
    }
    inv_eps = 1.0f / cfg->eps_s;
    h = cfg->dt_s * inv_eps;
    /* Generator over one period in s = tau/dt, state (eta, u, v1, v2):
     * deta/ds = h (A0 eta + b0 u), du/ds = v1, dv1/ds = v2, dv2/ds = 0
     * (u(s) = y + v1 s + v2 s^2/2). exp of it: eta(1) = Phi eta + Gu u +
     * G1 v1 + G2 v2 in columns 0..2, 3, 4, 5 of the top three rows. */
    for (uint32_t i = 0u; i < 36u; ++i) {
        z[i] = 0.0f;
    }
    z[0] = -cfg->alpha1 * h;
    z[1] = h;
    z[3] = cfg->alpha1 * h;
    z[6] = -cfg->alpha2 * h;
    z[8] = h;
    z[9] = cfg->alpha2 * h;
    z[12] = -cfg->alpha3 * h;
    z[15] = cfg->alpha3 * h;
    z[22] = 1.0f; /* du/ds = v1 */
    z[29] = 1.0f; /* dv1/ds = v2 */
    if (!mc_linalg_expm_f32(z, 6u, ez)) {
        return MC_HGO_ERR_DISCRETE;
    }
    for (uint32_t i = 0u; i < 3u; ++i) {
        for (uint32_t j = 0u; j < 3u; ++j) {
            st->phi[(i * 3u) + j] = ez[(i * 6u) + j];
        }
        st->g1[i] = ez[(i * 6u) + 4u];
        st->g2[i] = ez[(i * 6u) + 5u];
    }
    st->input_order = cfg->input_order;
    st->n_hist = 0u;
    st->y1 = 0.0f;
    st->y2 = 0.0f;
    st->eps_s = cfg->eps_s;
    st->inv_eps = inv_eps;
    st->inv_eps2 = inv_eps * inv_eps;
    st->eta[0] = 0.0f;
    st->eta[1] = 0.0f;
    st->eta[2] = 0.0f;
    st->flags = MC_HGO_ERR_NONE;
    return MC_HGO_ERR_NONE;
}

uint32_t mc_hgo_f32_reset(mc_hgo_f32_t *st, float z1, float z2, float z3)
{
    float e1;
    float e2;
    float e3;

    if (st == NULL) {
        return MC_HGO_ERR_NULL;
    }
    e1 = z1;
    e2 = z2 * st->eps_s;
    e3 = (z3 * st->eps_s) * st->eps_s;
    if (!mc_isfinite_f32(e1) || !mc_isfinite_f32(e2) || !mc_isfinite_f32(e3)) {
        return MC_HGO_ERR_NAN_INPUT;
    }
    st->eta[0] = e1;
    st->eta[1] = e2;
    st->eta[2] = e3;
    st->n_hist = 0u;
    st->y1 = 0.0f;
    st->y2 = 0.0f;
    st->flags = MC_HGO_ERR_NONE;
    return MC_HGO_ERR_NONE;
}

void mc_hgo_f32_step(mc_hgo_f32_t *st, float y, mc_hgo_f32_est_t *p_est)
{
    float d0;
    float n0;
    float n1;
    float n2;
    float v1;
    float v2;

    if ((st == NULL) || (p_est == NULL)) {
        return;
    }
    p_est->z1 = st->eta[0];
    p_est->z2 = st->eta[1] * st->inv_eps;
    p_est->z3 = st->eta[2] * st->inv_eps2;
    if (!mc_isfinite_f32(y)) {
        st->flags |= MC_HGO_ERR_NAN_INPUT;
        return;
    }
    /* Newton backward coefficients of the input polynomial (as many as
     * the configured order and the history allow). */
    v1 = 0.0f;
    v2 = 0.0f;
    if ((st->input_order >= 1u) && (st->n_hist >= 1u)) {
        const float dy = y - st->y1;
        v1 = dy;
        if ((st->input_order >= 2u) && (st->n_hist >= 2u)) {
            v2 = (dy - st->y1) + st->y2;
            v1 = dy + (0.5f * v2);
        }
    }
    /* eta <- y e1 + Phi (eta - y e1) + G1 v1 + G2 v2 */
    d0 = st->eta[0] - y;
    n0 = (st->phi[0] * d0) + (st->phi[1] * st->eta[1]) + (st->phi[2] * st->eta[2]);
    n1 = (st->phi[3] * d0) + (st->phi[4] * st->eta[1]) + (st->phi[5] * st->eta[2]);
    n2 = (st->phi[6] * d0) + (st->phi[7] * st->eta[1]) + (st->phi[8] * st->eta[2]);
    st->eta[0] = (y + n0) + ((st->g1[0] * v1) + (st->g2[0] * v2));
    st->eta[1] = n1 + ((st->g1[1] * v1) + (st->g2[1] * v2));
    st->eta[2] = n2 + ((st->g1[2] * v1) + (st->g2[2] * v2));
    st->y2 = st->y1;
    st->y1 = y;
    if (st->n_hist < 2u) {
        st->n_hist += 1u;
    }
}
