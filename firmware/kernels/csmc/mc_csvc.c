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

static float mc_max_f32_local(float a, float b)
{
    return (a > b) ? a : b;
}

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

/* ---- modal realisation ------------------------------------------------ */

/* |x| for the checks below. */
static float csvc_abs(float x)
{
    return (x < 0.0f) ? -x : x;
}

/*
 * The modal realisation (see mc_csvc.h), for S with the eigenvalues 0 and
 * +-j w_k (distinct), i.e. odd n, c_i = 0 for even i, and
 * p(l) = l^n - sum c_i l^i = l q(l^2) with q's roots -w_k^2 real, negative
 * and distinct. Fills st->real, xi, h, e, t; false if S is not of that
 * kind or the realisation does not reproduce Phi, Gam (then the dense one
 * is used).
 *
 * Eigenvectors of the companion S: v = (1, l, .., l^(n-1)); e_n = sum
 * v_i / p'(l_i), so Gam = sum v_i phi_i / p'(l_i) with
 * phi_i = (exp(l_i dt) - 1)/l_i (dt for l = 0). Real basis per pair:
 * a = Re v, b = Im v, on which Phi acts as R = [c s; -s c]
 * (c = cos(w dt), s = sin(w dt)). The pair's coordinates (x, y) are chosen
 * with z = P (x, y), P = [p1 p2], p1 = R^T g_ab (g_ab: Gam in (a, b)),
 * p2 = (R p1 - p1)/e, so that P^-1 R P = [1 -e; e 1-e^2] and the input
 * enters as (1, e): the update x <- x - e y + v, y <- y + e x.
 */
static bool csvc_modal(mc_csvc_f32_t *st, const mc_csvc_f32_model_t *m, float dt)
{
    const uint32_t n = m->order;
    float w[2] = {0.0f, 0.0f};
    uint32_t np;
    float tm[CSVC_N * CSVC_N];
    float g[CSVC_N];

    if ((n % 2u) == 0u) {
        return false;
    }
    for (uint32_t i = 0u; i < n; i += 2u) {
        if (m->c[i] != 0.0f) {
            return false;
        }
    }
    np = (n - 1u) / 2u;
    if (np == 1u) {
        if (!(m->c[1] < 0.0f)) {
            return false;
        }
        w[0] = mc_sqrt_f32(-m->c[1]);
    } else if (np == 2u) {
        /* q(mu) = mu^2 - c3 mu - c1: roots (c3 -+ sqrt(c3^2 + 4 c1))/2,
         * the second as -c1/first (no cancellation). */
        const float c1 = m->c[1];
        const float c3 = m->c[3];
        const float disc = (c3 * c3) + (4.0f * c1);
        if (!(c3 < 0.0f) || !(c1 < 0.0f) || !(disc > 0.0f)) {
            return false;
        }
        const float mu_a = 0.5f * (c3 - mc_sqrt_f32(disc));
        const float mu_b = -c1 / mu_a;
        if (!(mu_b < 0.0f) || !(mu_b > mu_a)) {
            return false;
        }
        w[0] = mc_sqrt_f32(-mu_b);
        w[1] = mc_sqrt_f32(-mu_a);
    } else {
        /* n = 1: eigenvalue 0 only */
    }
    for (uint32_t i = 0u; i < (CSVC_N * CSVC_N); ++i) {
        tm[i] = 0.0f;
    }
    /* Eigenvalue 0: v = e_1, p'(0) = prod w_k^2, phi = dt. */
    {
        float dp0 = 1.0f;
        for (uint32_t k = 0u; k < np; ++k) {
            dp0 *= w[k] * w[k];
        }
        tm[0] = dt / dp0;
        g[0] = 1.0f;
    }
    for (uint32_t k = 0u; k < np; ++k) {
        const float wk = w[k];
        float sh;
        float ch;
        mc_sincos_f32(0.5f * (wk * dt), &sh, &ch);
        const float e = 2.0f * sh;
        const float sn = e * ch;                  /* sin(w dt) */
        const float cs = 1.0f - (0.5f * (e * e)); /* cos(w dt) */
        /* p'(j w) = j w * 2 j w * prod_{l != k} (w_l^2 - w^2) = -dk */
        float dk = 2.0f * (wk * wk);
        for (uint32_t l = 0u; l < np; ++l) {
            if (l != k) {
                dk *= (w[l] * w[l]) - (wk * wk);
            }
        }
        /* alpha phi = -(s + j e^2/2)/(dk w); g_ab = (2 Re, -2 Im) */
        const float ga = (-2.0f * sn) / (dk * wk);
        const float gb = (e * e) / (dk * wk);
        const float p1x = (cs * ga) - (sn * gb);
        const float p1y = (sn * ga) + (cs * gb);
        const float p2x = (-(0.5f * e) * p1x) + (ch * p1y);
        const float p2y = (-ch * p1x) - ((0.5f * e) * p1y);
        /* a = (1, 0, -w^2, 0, w^4), b = (0, w, 0, -w^3, 0) */
        float a[CSVC_N];
        float b[CSVC_N];
        const float w2 = wk * wk;
        a[0] = 1.0f;
        b[0] = 0.0f;
        a[1] = 0.0f;
        b[1] = wk;
        a[2] = -w2;
        b[2] = 0.0f;
        a[3] = 0.0f;
        b[3] = -(w2 * wk);
        a[4] = w2 * w2;
        b[4] = 0.0f;
        const uint32_t jx = 1u + (2u * k);
        for (uint32_t i = 0u; i < n; ++i) {
            tm[(i * n) + jx] = (a[i] * p1x) + (b[i] * p1y);
            tm[(i * n) + jx + 1u] = (a[i] * p2x) + (b[i] * p2y);
        }
        g[jx] = 1.0f;
        g[jx + 1u] = e;
        st->e[k] = e;
    }
    /* Check: Phi T = T A and Gam = T g, to 1e-4 of the largest entries
     * (Phi and Gam carry the matrix exponential's rounding, ~1e-6). */
    {
        float tmax = 0.0f;
        float gmax = 0.0f;
        float worst_t = 0.0f;
        float worst_g = 0.0f;
        for (uint32_t i = 0u; i < n; ++i) {
            float tg = 0.0f;
            for (uint32_t j = 0u; j < n; ++j) {
                float lhs = 0.0f;
                for (uint32_t l = 0u; l < n; ++l) {
                    lhs += st->phi[(i * n) + l] * tm[(l * n) + j];
                }
                /* (T A)_ij: A = 1 on mode 0, the pair blocks [1 -e; e 1-e^2] */
                float rhs;
                if (j == 0u) {
                    rhs = tm[(i * n) + 0u];
                } else {
                    const uint32_t k = (j - 1u) / 2u;
                    const float e = st->e[k];
                    const float tx = tm[(i * n) + 1u + (2u * k)];
                    const float ty = tm[(i * n) + 2u + (2u * k)];
                    rhs = (((j - 1u) % 2u) == 0u) ? (tx + (e * ty))
                                                  : ((-e * tx) + ((1.0f - (e * e)) * ty));
                }
                worst_t = mc_max_f32_local(worst_t, csvc_abs(lhs - rhs));
                tmax = mc_max_f32_local(tmax, csvc_abs(tm[(i * n) + j]));
                tg += tm[(i * n) + j] * g[j];
            }
            worst_g = mc_max_f32_local(worst_g, csvc_abs(tg - st->gam[i]));
            gmax = mc_max_f32_local(gmax, csvc_abs(st->gam[i]));
        }
        if (!mc_isfinite_f32(worst_t + worst_g + tmax + gmax) || !(worst_t <= (1.0e-4f * tmax)) ||
            !(worst_g <= (1.0e-4f * gmax))) {
            return false;
        }
    }
    for (uint32_t j = 0u; j < CSVC_N; ++j) {
        float hj = 0.0f;
        for (uint32_t i = 0u; (i < n) && (j < n); ++i) {
            hj += m->k0[i] * tm[(i * n) + j];
        }
        st->h[j] = hj;
        st->xi[j] = 0.0f;
        st->xi_lo[j] = 0.0f;
    }
    for (uint32_t i = 0u; i < (CSVC_N * CSVC_N); ++i) {
        st->t[i] = tm[i];
    }
    st->real = MC_CSVC_REAL_MODAL0 + np;
    return true;
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
        st->xi[i] = 0.0f;
        st->h[i] = 0.0f;
    }
    for (uint32_t i = 0u; i < (CSVC_N * CSVC_N); ++i) {
        st->t[i] = 0.0f;
    }
    st->e[0] = 0.0f;
    st->e[1] = 0.0f;
    st->real = MC_CSVC_REAL_DENSE;
    if (!csvc_modal(st, &cfg->model, cfg->dt_s)) {
        st->real = MC_CSVC_REAL_DENSE;
        st->e[0] = 0.0f;
        st->e[1] = 0.0f;
    }
    st->flags = MC_CSVC_ERR_NONE;
    return MC_CSVC_ERR_NONE;
}

void mc_csvc_f32_force_dense(mc_csvc_f32_t *st)
{
    if (st != NULL) {
        st->real = MC_CSVC_REAL_DENSE;
    }
}

uint32_t mc_csvc_f32_reset(mc_csvc_f32_t *st)
{
    if (st == NULL) {
        return MC_CSVC_ERR_NULL;
    }
    for (uint32_t i = 0u; i < CSVC_N; ++i) {
        st->sigma[i] = 0.0f;
        st->xi[i] = 0.0f;
        st->xi_lo[i] = 0.0f;
    }
    st->flags = MC_CSVC_ERR_NONE;
    return MC_CSVC_ERR_NONE;
}

float mc_csvc_f32_term(const mc_csvc_f32_t *st)
{
    float acc = 0.0f;

    if (st == NULL) {
        return 0.0f;
    }
    if (st->real == MC_CSVC_REAL_MODAL0) {
        return mc_csvc_f32_term_m0(st);
    }
    if (st->real == MC_CSVC_REAL_MODAL1) {
        return mc_csvc_f32_term_m1(st);
    }
    if (st->real == MC_CSVC_REAL_MODAL2) {
        return mc_csvc_f32_term_m2(st);
    }
    for (uint32_t i = 0u; i < st->n; ++i) {
        acc += st->k0[i] * st->sigma[i];
    }
    return acc;
}

void mc_csvc_f32_advance(mc_csvc_f32_t *st, float v)
{
    float next[CSVC_N];
    const uint32_t n = (st != NULL) ? st->n : 0u;

    if ((st == NULL) || (n == 0u) || (n > CSVC_N)) {
        return;
    }
    if (st->real == MC_CSVC_REAL_MODAL0) {
        mc_csvc_f32_advance_m0(st, v);
        return;
    }
    if (st->real == MC_CSVC_REAL_MODAL1) {
        mc_csvc_f32_advance_m1(st, v);
        return;
    }
    if (st->real == MC_CSVC_REAL_MODAL2) {
        mc_csvc_f32_advance_m2(st, v);
        return;
    }
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

void mc_csvc_f32_update(mc_csvc_f32_t *st, float s)
{
    if ((st == NULL) || (st->n == 0u) || (st->n > CSVC_N)) {
        return;
    }
    if (!mc_isfinite_f32(s)) {
        st->flags |= MC_CSVC_ERR_NAN_INPUT;
        return;
    }
    /* v = mu sat(s/mu) - K0 sigma  (= s* inside the boundary layer) */
    mc_csvc_f32_advance(st, mc_sat_f32(s, -st->mu, st->mu) - mc_csvc_f32_term(st));
}

void mc_csvc_f32_sigma(const mc_csvc_f32_t *st, float *p_sigma)
{
    if ((st == NULL) || (p_sigma == NULL) || (st->n > CSVC_N)) {
        return;
    }
    for (uint32_t i = 0u; i < st->n; ++i) {
        if (st->real == MC_CSVC_REAL_DENSE) {
            p_sigma[i] = st->sigma[i];
        } else {
            float acc = 0.0f;
            for (uint32_t j = 0u; j < st->n; ++j) {
                acc += st->t[(i * st->n) + j] * st->xi[j];
            }
            p_sigma[i] = acc;
        }
    }
}
