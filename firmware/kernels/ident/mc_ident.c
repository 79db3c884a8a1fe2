/**
 * @file mc_ident.c
 * @brief Identification helpers (see mc_ident.h).
 */
#include "ident/mc_ident.h"

#include <stddef.h>

#include "math/mc_math.h"

uint32_t mc_ident_avg_f32_reset(mc_ident_avg_f32_t *st)
{
    if (st == NULL) {
        return MC_IDENT_ERR_NULL;
    }
    st->sum = 0.0f;
    st->comp = 0.0f;
    st->n = 0u;
    return MC_IDENT_ERR_NONE;
}

uint32_t mc_ident_avg_f32_step(mc_ident_avg_f32_t *st, float x)
{
    if (st == NULL) {
        return MC_IDENT_ERR_NULL;
    }
    if (!mc_isfinite_f32(x)) {
        return MC_IDENT_ERR_NAN;
    }
    /* Kahan: the low-order bits lost by each addition are carried. */
    const float y = x - st->comp;
    const float t = st->sum + y;
    st->comp = (t - st->sum) - y;
    st->sum = t;
    st->n++;
    return MC_IDENT_ERR_NONE;
}

uint32_t mc_ident_avg_f32_get(const mc_ident_avg_f32_t *st, float *p_mean)
{
    if (st->n == 0u) {
        *p_mean = 0.0f;
        return MC_IDENT_ERR_EMPTY;
    }
    *p_mean = st->sum / (float)st->n;
    return MC_IDENT_ERR_NONE;
}

uint32_t mc_ident_line_f32_reset(mc_ident_line_f32_t *st)
{
    if (st == NULL) {
        return MC_IDENT_ERR_NULL;
    }
    (void)mc_ident_avg_f32_reset(&st->sx);
    (void)mc_ident_avg_f32_reset(&st->sy);
    (void)mc_ident_avg_f32_reset(&st->sxx);
    (void)mc_ident_avg_f32_reset(&st->sxy);
    return MC_IDENT_ERR_NONE;
}

uint32_t mc_ident_line_f32_step(mc_ident_line_f32_t *st, float x, float y)
{
    if (st == NULL) {
        return MC_IDENT_ERR_NULL;
    }
    if (!mc_isfinite_f32(x) || !mc_isfinite_f32(y) || !mc_isfinite_f32(x * x) ||
        !mc_isfinite_f32(x * y)) {
        return MC_IDENT_ERR_NAN;
    }
    (void)mc_ident_avg_f32_step(&st->sx, x);
    (void)mc_ident_avg_f32_step(&st->sy, y);
    (void)mc_ident_avg_f32_step(&st->sxx, x * x);
    (void)mc_ident_avg_f32_step(&st->sxy, x * y);
    return MC_IDENT_ERR_NONE;
}

uint32_t mc_ident_line_f32_get(const mc_ident_line_f32_t *st, bool with_intercept, float *p_slope,
                               float *p_intercept)
{
    float a = 0.0f;
    float b = 0.0f;
    uint32_t err = MC_IDENT_ERR_NONE;
    const uint32_t n = st->sx.n;
    if (n < 2u) {
        err = MC_IDENT_ERR_EMPTY;
    } else {
        const float fn = (float)n;
        const float mx = st->sx.sum / fn;
        const float my = st->sy.sum / fn;
        const float mxx = st->sxx.sum / fn;
        const float mxy = st->sxy.sum / fn;
        if (with_intercept) {
            const float var = mxx - mx * mx;
            if (!(var > 1e-12f * (mxx + 1e-30f))) {
                err = MC_IDENT_ERR_DEGENERATE;
            } else {
                b = (mxy - mx * my) / var;
                a = my - b * mx;
            }
        } else if (!(mxx > 0.0f)) {
            err = MC_IDENT_ERR_DEGENERATE;
        } else {
            b = mxy / mxx;
        }
    }
    *p_slope = b;
    if (p_intercept != NULL) {
        *p_intercept = a;
    }
    return err;
}

uint32_t mc_ident_circ_f32_reset(mc_ident_circ_f32_t *st)
{
    if (st == NULL) {
        return MC_IDENT_ERR_NULL;
    }
    (void)mc_ident_avg_f32_reset(&st->s);
    (void)mc_ident_avg_f32_reset(&st->c);
    return MC_IDENT_ERR_NONE;
}

uint32_t mc_ident_circ_f32_step(mc_ident_circ_f32_t *st, float angle_rad)
{
    if (st == NULL) {
        return MC_IDENT_ERR_NULL;
    }
    if (!mc_isfinite_f32(angle_rad)) {
        return MC_IDENT_ERR_NAN;
    }
    float s;
    float c;
    mc_sincos_f32(angle_rad, &s, &c);
    (void)mc_ident_avg_f32_step(&st->s, s);
    (void)mc_ident_avg_f32_step(&st->c, c);
    return MC_IDENT_ERR_NONE;
}

uint32_t mc_ident_circ_f32_get(const mc_ident_circ_f32_t *st, float *p_mean_rad, float *p_resultant)
{
    float ms = 0.0f;
    float mc = 0.0f;
    uint32_t err = mc_ident_avg_f32_get(&st->s, &ms);
    err |= mc_ident_avg_f32_get(&st->c, &mc);
    const float r = mc_sqrt_f32(ms * ms + mc * mc);
    if (err == MC_IDENT_ERR_NONE && !(r >= 1e-3f)) {
        err = MC_IDENT_ERR_DEGENERATE;
    }
    *p_mean_rad = (err == MC_IDENT_ERR_NONE) ? mc_atan2_f32(ms, mc) : 0.0f;
    if (p_resultant != NULL) {
        *p_resultant = r;
    }
    return err;
}

uint32_t mc_ident_r_two_level_f32(float v1_v, float i1_a, float v2_v, float i2_a, float *p_r_ohm)
{
    *p_r_ohm = 0.0f;
    if (!mc_isfinite_f32(v1_v) || !mc_isfinite_f32(i1_a) || !mc_isfinite_f32(v2_v) ||
        !mc_isfinite_f32(i2_a)) {
        return MC_IDENT_ERR_NAN;
    }
    const float di = i2_a - i1_a;
    if (!(mc_abs_f32(di) >= 1e-6f)) {
        return MC_IDENT_ERR_RANGE;
    }
    const float r = (v2_v - v1_v) / di;
    if (!(r > 0.0f)) {
        return MC_IDENT_ERR_RANGE;
    }
    *p_r_ohm = r;
    return MC_IDENT_ERR_NONE;
}

uint32_t mc_ident_l_square_wave_f32(float v_amp_v, float dt_s, float di_pp_a, float r_ohm,
                                    float *p_l_h)
{
    *p_l_h = 0.0f;
    if (!mc_isfinite_f32(v_amp_v) || !mc_isfinite_f32(dt_s) || !mc_isfinite_f32(di_pp_a) ||
        !mc_isfinite_f32(r_ohm)) {
        return MC_IDENT_ERR_NAN;
    }
    if (!(v_amp_v > 0.0f) || !(dt_s > 0.0f) || !(di_pp_a > 0.0f) || r_ohm < 0.0f) {
        return MC_IDENT_ERR_RANGE;
    }
    /* tanh(x) = y with x = R dt / (2 L), y = R di / (2 v). atanh(y) =
     * y + y^3/3 + y^5/5 + ...; L = R dt / (2 atanh(y)) = v dt / (di g(y)),
     * g(y) = atanh(y) / y = 1 + y^2/3 + y^4/5 + y^6/7 + y^8/9 + ... */
    const float y = r_ohm * di_pp_a / (2.0f * v_amp_v);
    if (y > 0.46f) { /* x above 0.5: outside the series' float accuracy */
        return MC_IDENT_ERR_RANGE;
    }
    const float y2 = y * y;
    float g = 1.0f / 21.0f;
    g = 1.0f / 19.0f + y2 * g;
    g = 1.0f / 17.0f + y2 * g;
    g = 1.0f / 15.0f + y2 * g;
    g = 1.0f / 13.0f + y2 * g;
    g = 1.0f / 11.0f + y2 * g;
    g = 1.0f / 9.0f + y2 * g;
    g = 1.0f / 7.0f + y2 * g;
    g = 1.0f / 5.0f + y2 * g;
    g = 1.0f / 3.0f + y2 * g;
    g = 1.0f + y2 * g;
    *p_l_h = v_amp_v * dt_s / (di_pp_a * g);
    return MC_IDENT_ERR_NONE;
}
