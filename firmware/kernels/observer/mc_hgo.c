/**
 * @file mc_hgo.c
 * @brief High-gain observer, exact ZOH discretisation (see mc_hgo.h).
 */
#include "observer/mc_hgo.h"

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
    {
        /* z = D^-1 eta, D = diag(1, eps, eps^2) */
        const float d[3] = {1.0f, cfg->eps_s, cfg->eps_s * cfg->eps_s};
        const float inv_d[3] = {1.0f, st->inv_eps, st->inv_eps2};
        for (uint32_t i = 0u; i < 3u; ++i) {
            for (uint32_t j = 0u; j < 3u; ++j) {
                st->pz[(i * 3u) + j] = (st->phi[(i * 3u) + j] * d[j]) * inv_d[i];
            }
            st->g1z[i] = st->g1[i] * inv_d[i];
            st->g2z[i] = st->g2[i] * inv_d[i];
            st->gdy[i] = (cfg->input_order >= 1u) ? st->g1z[i] : 0.0f;
            st->gd2y[i] = (cfg->input_order >= 2u) ? (st->g2z[i] + (0.5f * st->g1z[i])) : 0.0f;
            st->z[i] = 0.0f;
        }
    }
    st->flags = MC_HGO_ERR_NONE;
    return MC_HGO_ERR_NONE;
}

uint32_t mc_hgo_f32_reset(mc_hgo_f32_t *st, float z1, float z2, float z3)
{
    if (st == NULL) {
        return MC_HGO_ERR_NULL;
    }
    if (!mc_isfinite_f32(z1) || !mc_isfinite_f32(z2) || !mc_isfinite_f32(z3)) {
        return MC_HGO_ERR_NAN_INPUT;
    }
    st->z[0] = z1;
    st->z[1] = z2;
    st->z[2] = z3;
    st->n_hist = 0u;
    st->y1 = 0.0f;
    st->y2 = 0.0f;
    st->flags = MC_HGO_ERR_NONE;
    return MC_HGO_ERR_NONE;
}

void mc_hgo_f32_advance_start(mc_hgo_f32_t *st, float y)
{
    float v1 = 0.0f;
    float v2 = 0.0f;
    if ((st->input_order >= 1u) && (st->n_hist >= 1u)) {
        v1 = y - st->y1;
    }
    const float d0 = st->z[0] - y;
    const float z1 = st->z[1];
    const float z2 = st->z[2];
    const float *p = st->pz;
    st->z[0] =
        (y + (((p[0] * d0) + (p[1] * z1)) + (p[2] * z2))) + ((st->g1z[0] * v1) + (st->g2z[0] * v2));
    st->z[1] =
        (((p[3] * d0) + (p[4] * z1)) + (p[5] * z2)) + ((st->g1z[1] * v1) + (st->g2z[1] * v2));
    st->z[2] =
        (((p[6] * d0) + (p[7] * z1)) + (p[8] * z2)) + ((st->g1z[2] * v1) + (st->g2z[2] * v2));
    st->y2 = st->y1;
    st->y1 = y;
    st->n_hist += 1u;
}

uint32_t mc_hgo_f32_step(mc_hgo_f32_t *st, float y, mc_hgo_f32_est_t *p_est)
{
    if ((st == NULL) || (p_est == NULL)) {
        return MC_HGO_ERR_NULL;
    }
    p_est->z1 = st->z[0];
    p_est->z2 = st->z[1];
    p_est->z3 = st->z[2];
    if (__builtin_expect(!mc_isfinite_f32(y), 0)) {
        st->flags |= MC_HGO_ERR_NAN_INPUT;
        return MC_HGO_ERR_NAN_INPUT;
    }
    mc_hgo_f32_advance(st, y);
    return MC_HGO_ERR_NONE;
}
