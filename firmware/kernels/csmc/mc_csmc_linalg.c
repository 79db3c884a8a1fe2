/**
 * @file mc_csmc_linalg.c
 * @brief Init-time linear algebra of the csmc kernels (see the header).
 */
#include "csmc/mc_csmc_linalg.h"

#include <stddef.h>

#include "math/mc_math.h"

#define LA_N  MC_LINALG_MAX_N
#define LA_NN (MC_LINALG_MAX_N * MC_LINALG_MAX_N)

/* c = a * b, all n x n (c must not alias a or b). */
static void la_mul(const float *p_a, const float *p_b, uint32_t n, float *p_c)
{
    for (uint32_t i = 0u; i < n; ++i) {
        for (uint32_t j = 0u; j < n; ++j) {
            float acc = 0.0f;
            for (uint32_t k = 0u; k < n; ++k) {
                acc += p_a[(i * n) + k] * p_b[(k * n) + j];
            }
            p_c[(i * n) + j] = acc;
        }
    }
}

bool mc_linalg_expm_f32(const float *p_a, uint32_t n, float *p_out)
{
    float scaled[LA_NN];
    float term[LA_NN];
    float tmp[LA_NN];
    float sum[LA_NN];
    float norm = 0.0f;
    float scale = 1.0f;
    uint32_t squarings = 0u;

    if ((p_a == NULL) || (p_out == NULL) || (n == 0u) || (n > LA_N)) {
        return false;
    }
    for (uint32_t i = 0u; i < n; ++i) {
        float row = 0.0f;
        for (uint32_t j = 0u; j < n; ++j) {
            const float v = p_a[(i * n) + j];
            if (!mc_isfinite_f32(v)) {
                return false;
            }
            row += mc_abs_f32(v);
        }
        if (row > norm) {
            norm = row;
        }
    }
    /* Scale by 2^-s until the norm is <= 1/2 (s <= 41). */
    while (norm > 0.5f) {
        if (squarings >= 41u) {
            return false;
        }
        norm *= 0.5f;
        scale *= 0.5f;
        ++squarings;
    }
    for (uint32_t i = 0u; i < (n * n); ++i) {
        scaled[i] = p_a[i] * scale;
    }
    /* Taylor: sum_{k=0}^{12} M^k / k!, term_k = term_{k-1} * M / k. */
    for (uint32_t i = 0u; i < n; ++i) {
        for (uint32_t j = 0u; j < n; ++j) {
            const float id = (i == j) ? 1.0f : 0.0f;
            term[(i * n) + j] = id;
            sum[(i * n) + j] = id;
        }
    }
    for (uint32_t k = 1u; k <= 12u; ++k) {
        const float inv_k = 1.0f / (float)k;
        la_mul(term, scaled, n, tmp);
        for (uint32_t i = 0u; i < (n * n); ++i) {
            term[i] = tmp[i] * inv_k;
            sum[i] += term[i];
        }
    }
    for (uint32_t s = 0u; s < squarings; ++s) {
        la_mul(sum, sum, n, tmp);
        for (uint32_t i = 0u; i < (n * n); ++i) {
            sum[i] = tmp[i];
        }
    }
    for (uint32_t i = 0u; i < (n * n); ++i) {
        p_out[i] = sum[i];
    }
    return true;
}

bool mc_linalg_hurwitz_f32(const float *p_p, uint32_t n)
{
    /* Routh array of a0 s^n + a1 s^(n-1) + ... + an with a0 = 1,
     * a_k = p[n-k]. Row r has ceil((n+1-r)/2) meaningful entries. */
    float r_prev[LA_N + 2u];
    float r_cur[LA_N + 2u];
    float r_next[LA_N + 2u];
    const uint32_t w = (LA_N / 2u) + 2u;

    if ((p_p == NULL) || (n == 0u) || (n > LA_N)) {
        return false;
    }
    for (uint32_t i = 0u; i < n; ++i) {
        if (!mc_isfinite_f32(p_p[i])) {
            return false;
        }
    }
    for (uint32_t j = 0u; j < (LA_N + 2u); ++j) {
        r_prev[j] = 0.0f;
        r_cur[j] = 0.0f;
        r_next[j] = 0.0f;
    }
    /* a_k for k = 0..n: a_0 = 1, a_k = p[n - k]. */
    for (uint32_t k = 0u; k <= n; ++k) {
        const float ak = (k == 0u) ? 1.0f : p_p[n - k];
        if ((k % 2u) == 0u) {
            r_prev[k / 2u] = ak;
        } else {
            r_cur[k / 2u] = ak;
        }
    }
    /* First column: r_prev[0] = 1 > 0; check r_cur[0] and every next row. */
    for (uint32_t row = 1u; row <= n; ++row) {
        if (!(r_cur[0] > 0.0f)) {
            return false;
        }
        for (uint32_t j = 0u; j < w; ++j) {
            r_next[j] = ((r_cur[0] * r_prev[j + 1u]) - (r_prev[0] * r_cur[j + 1u])) / r_cur[0];
        }
        for (uint32_t j = 0u; j < w; ++j) {
            r_prev[j] = r_cur[j];
            r_cur[j] = r_next[j];
        }
    }
    return true;
}

bool mc_linalg_poly_from_roots_f32(const float *p_re, const float *p_im, uint32_t n, float *p_p)
{
    /* c[0..deg] of the product so far, c[deg] = 1. */
    float c[LA_N + 1u];
    uint32_t deg = 0u;
    uint32_t i = 0u;

    if ((p_re == NULL) || (p_im == NULL) || (p_p == NULL) || (n == 0u) || (n > LA_N)) {
        return false;
    }
    for (uint32_t k = 0u; k < n; ++k) {
        if (!mc_isfinite_f32(p_re[k]) || !mc_isfinite_f32(p_im[k])) {
            return false;
        }
    }
    for (uint32_t k = 0u; k <= LA_N; ++k) {
        c[k] = 0.0f;
    }
    c[0] = 1.0f;
    while (i < n) {
        /* Multiply c (degree deg, c[k] = 0 above deg) by a factor
         * lambda^2 + b lambda + q (complex pair) or lambda + q (real root):
         * next[k] = c[k-2] + b c[k-1] + q c[k] (pair), c[k-1] + q c[k] (real). */
        float next[LA_N + 1u];
        float b = 0.0f;
        float q;
        uint32_t step = 1u;
        if (p_im[i] == 0.0f) {
            q = -p_re[i];
        } else {
            if (((i + 1u) >= n) || (p_re[i + 1u] != p_re[i]) || (p_im[i + 1u] != -p_im[i])) {
                return false;
            }
            b = -2.0f * p_re[i];
            q = (p_re[i] * p_re[i]) + (p_im[i] * p_im[i]);
            step = 2u;
        }
        for (uint32_t k = 0u; k <= (deg + step); ++k) {
            const float ck = (k <= deg) ? c[k] : 0.0f;
            const float ck1 = ((k >= 1u) && ((k - 1u) <= deg)) ? c[k - 1u] : 0.0f;
            const float ck2 = ((k >= 2u) && ((k - 2u) <= deg)) ? c[k - 2u] : 0.0f;
            if (step == 1u) {
                next[k] = ck1 + (q * ck);
            } else {
                next[k] = ck2 + (b * ck1) + (q * ck);
            }
        }
        deg += step;
        i += step;
        for (uint32_t k = 0u; k <= deg; ++k) {
            c[k] = next[k];
        }
    }
    for (uint32_t k = 0u; k < n; ++k) {
        p_p[k] = c[k];
    }
    return true;
}
