/**
 * @file mc_csvc.c
 * @brief Conditional servocompensator / integrator (see mc_csvc.h).
 */
#include "csmc/mc_csvc.h"

#include <stdbool.h>
#include <stddef.h>

#include "csmc/mc_csmc_linalg.h"
#include "math/mc_math.h"

#define CSVC_N MC_CSVC_MAX_ORDER

uint32_t mc_csvc_f32_integrator(float k0_per_s, mc_csvc_f32_model_t *p_model)
{
    if (p_model == NULL) {
        return MC_CSVC_ERR_NULL;
    }
    if (!(k0_per_s > 0.0f) || !mc_isfinite_f32(k0_per_s)) {
        return MC_CSVC_ERR_MODEL;
    }
    for (uint32_t i = 0u; i < CSVC_N; ++i) {
        p_model->c[i] = 0.0f;
        p_model->k0[i] = 0.0f;
    }
    p_model->order = 1u;
    p_model->k0[0] = k0_per_s;
    return MC_CSVC_ERR_NONE;
}

uint32_t mc_csvc_f32_place(uint32_t order, const float *p_c, const float *p_pole_re,
                           const float *p_pole_im, mc_csvc_f32_model_t *p_model)
{
    float p[MC_LINALG_MAX_N];

    if ((p_c == NULL) || (p_pole_re == NULL) || (p_pole_im == NULL) || (p_model == NULL)) {
        return MC_CSVC_ERR_NULL;
    }
    if ((order == 0u) || (order > CSVC_N)) {
        return MC_CSVC_ERR_ORDER;
    }
    for (uint32_t i = 0u; i < order; ++i) {
        if (!mc_isfinite_f32(p_c[i])) {
            return MC_CSVC_ERR_MODEL;
        }
        if (!(p_pole_re[i] < 0.0f)) {
            return MC_CSVC_ERR_POLES;
        }
    }
    if (!mc_linalg_poly_from_roots_f32(p_pole_re, p_pole_im, order, p)) {
        return MC_CSVC_ERR_POLES;
    }
    for (uint32_t i = 0u; i < CSVC_N; ++i) {
        p_model->c[i] = (i < order) ? p_c[i] : 0.0f;
        p_model->k0[i] = (i < order) ? (p_c[i] + p[i]) : 0.0f;
    }
    p_model->order = order;
    return MC_CSVC_ERR_NONE;
}

uint32_t mc_csvc_f32_init(mc_csvc_f32_t *st, const mc_csvc_f32_cfg_t *cfg)
{
    uint32_t err = MC_CSVC_ERR_NONE;
    uint32_t n;
    float norm = 0.0f;
    bool model_ok = true;

    if ((st == NULL) || (cfg == NULL)) {
        return MC_CSVC_ERR_NULL;
    }
    n = cfg->model.order;
    if ((n == 0u) || (n > CSVC_N)) {
        return MC_CSVC_ERR_ORDER;
    }
    for (uint32_t i = 0u; i < n; ++i) {
        if (!mc_isfinite_f32(cfg->model.c[i]) || !mc_isfinite_f32(cfg->model.k0[i])) {
            model_ok = false;
        }
    }
    if (!model_ok) {
        err |= MC_CSVC_ERR_MODEL;
    } else {
        /* char. polynomial of S - J K0: lambda^n + sum (K0_i - c_i) lambda^i */
        float charp[CSVC_N];
        for (uint32_t i = 0u; i < n; ++i) {
            charp[i] = cfg->model.k0[i] - cfg->model.c[i];
        }
        if (!mc_linalg_hurwitz_f32(charp, n)) {
            err |= MC_CSVC_ERR_NOT_HURWITZ;
        }
        /* ||S - J K0||_inf: rows 0..n-2 have a single 1, the last row c - K0. */
        for (uint32_t i = 0u; i < n; ++i) {
            norm += mc_abs_f32(charp[i]);
        }
        if ((n > 1u) && (norm < 1.0f)) {
            norm = 1.0f;
        }
    }
    if (!(cfg->mu > 0.0f) || !mc_isfinite_f32(cfg->mu)) {
        err |= MC_CSVC_ERR_MU;
    }
    if (!(cfg->dt_s > 0.0f) || !mc_isfinite_f32(cfg->dt_s) ||
        (model_ok && !((cfg->dt_s * norm) <= 0.1f))) {
        err |= MC_CSVC_ERR_DT;
    }
    if (err != MC_CSVC_ERR_NONE) {
        return err;
    }
    /* exp([[S, J], [0, 0]] dt) = [[Phi, Gam], [0, 1]]; order n + 1. */
    {
        float aug[MC_LINALG_MAX_N * MC_LINALG_MAX_N];
        float eaug[MC_LINALG_MAX_N * MC_LINALG_MAX_N];
        const uint32_t m = n + 1u;
        for (uint32_t i = 0u; i < (m * m); ++i) {
            aug[i] = 0.0f;
        }
        for (uint32_t i = 0u; (i + 1u) < n; ++i) {
            aug[(i * m) + i + 1u] = cfg->dt_s;
        }
        for (uint32_t j = 0u; j < n; ++j) {
            aug[((n - 1u) * m) + j] = cfg->model.c[j] * cfg->dt_s;
        }
        aug[((n - 1u) * m) + n] = cfg->dt_s;
        if (!mc_linalg_expm_f32(aug, m, eaug)) {
            return MC_CSVC_ERR_DT;
        }
        for (uint32_t i = 0u; i < n; ++i) {
            for (uint32_t j = 0u; j < n; ++j) {
                st->phi[(i * n) + j] = eaug[(i * m) + j];
            }
            st->gam[i] = eaug[(i * m) + n];
        }
    }
    st->n = n;
    st->mu = cfg->mu;
    for (uint32_t i = 0u; i < CSVC_N; ++i) {
        st->k0[i] = (i < n) ? cfg->model.k0[i] : 0.0f;
        st->sigma[i] = 0.0f;
    }
    st->flags = MC_CSVC_ERR_NONE;
    return MC_CSVC_ERR_NONE;
}

void mc_csvc_f32_reset(mc_csvc_f32_t *st)
{
    if (st == NULL) {
        return;
    }
    for (uint32_t i = 0u; i < CSVC_N; ++i) {
        st->sigma[i] = 0.0f;
    }
    st->flags = MC_CSVC_ERR_NONE;
}

float mc_csvc_f32_term(const mc_csvc_f32_t *st)
{
    float acc = 0.0f;

    if (st == NULL) {
        return 0.0f;
    }
    for (uint32_t i = 0u; i < st->n; ++i) {
        acc += st->k0[i] * st->sigma[i];
    }
    return acc;
}

void mc_csvc_f32_update(mc_csvc_f32_t *st, float s)
{
    float v;
    float next[CSVC_N];
    const uint32_t n = (st != NULL) ? st->n : 0u;

    if ((st == NULL) || (n == 0u) || (n > CSVC_N)) {
        return;
    }
    if (!mc_isfinite_f32(s)) {
        st->flags |= MC_CSVC_ERR_NAN_INPUT;
        return;
    }
    /* v = mu sat(s/mu) - K0 sigma  (= s* inside the boundary layer) */
    v = mc_sat_f32(s, -st->mu, st->mu) - mc_csvc_f32_term(st);
    for (uint32_t i = 0u; i < n; ++i) {
        float acc = st->gam[i] * v;
        for (uint32_t j = 0u; j < n; ++j) {
            acc += st->phi[(i * n) + j] * st->sigma[j];
        }
        next[i] = acc;
    }
    for (uint32_t i = 0u; i < n; ++i) {
        st->sigma[i] = next[i];
    }
}
