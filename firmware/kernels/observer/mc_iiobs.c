/**
 * @file mc_iiobs.c
 * @brief I&I speed and load-torque observer (paper 002, eq. (30)); the law,
 *        the departures from the printed paper and the discretisation are
 *        in mc_iiobs.h.
 *
 * Derivation of the xi equation (checked against (32) with
 * beta = rho2(h, h_hat) delta, |h| = 1):
 *   A eta_hat                  = [-(f/J) eta1 - eta2, 0]
 *   -grad_h beta Psi eta_hat   = -(h^T h_hat) eta1 delta
 *   -grad_hh beta h_hat'       = (eta1 + rho1 rho2) delta
 * whose sum is (30). In discrete time the last line is taken as the exact
 * change of beta caused by the h_hat update (beta is linear in h_hat):
 *   -(rho2(h+, h_hat+) - rho2(h+, h_hat)) delta,
 * and the second line with the previous h, h_hat. With eta_hat = eta and
 * h_hat = h this leaves z unchanged to O(dt^3) (rho2(h+, h) = sin(omega dt)).
 */
#include "observer/mc_iiobs.h"

#include <stddef.h>

#include "math/mc_math.h"

static bool pos_finite(float x)
{
    return (x > 0.0f) && mc_isfinite_f32(x);
}

/* Largest singular value of the 2x2 matrix [[a, b], [c, d]] and |det|. */
static float norm2_2x2(float a, float b, float c, float d, float *p_absdet)
{
    const float s = (a * a) + (b * b) + (c * c) + (d * d);
    const float det = (a * d) - (b * c);
    float disc = (s * s) - (4.0f * det * det);

    if (disc < 0.0f) {
        disc = 0.0f; /* rounding for equal singular values */
    }
    *p_absdet = mc_abs_f32(det);
    return mc_sqrt_f32(0.5f * (s + mc_sqrt_f32(disc)));
}

static uint32_t iiobs_validate(const mc_iiobs_f32_cfg_t *cfg)
{
    uint32_t err = MC_IIOBS_ERR_NONE;
    const bool gains_finite = pos_finite(cfg->a1) && pos_finite(cfg->a2);
    const bool time_ok = pos_finite(cfg->t_unit_s) && pos_finite(cfg->dt_s);
    const bool mech_ok =
        pos_finite(cfg->j_kgm2) && (cfg->f_nms_rad >= 0.0f) && mc_isfinite_f32(cfg->f_nms_rad);

    if (!mech_ok) {
        err |= MC_IIOBS_ERR_MECH;
    }
    if (!gains_finite) {
        err |= MC_IIOBS_ERR_GAINS;
    } else {
        /* (27): a1 > max{2 sqrt(a2), 4}, i.e. a1^2 > 4 a2 and a1 > 4 */
        if (!(cfg->a1 > 4.0f) || !((cfg->a1 * cfg->a1) > (4.0f * cfg->a2))) {
            err |= MC_IIOBS_ERR_GAINS;
        }
        /* k1 > 2 (used after (42)) <=> a2 > 2 a1 - 4 */
        if (!(cfg->a2 > ((2.0f * cfg->a1) - 4.0f))) {
            err |= MC_IIOBS_ERR_K1;
        }
    }
    if (!pos_finite(cfg->k4)) {
        err |= MC_IIOBS_ERR_K4;
    }
    if (!time_ok) {
        err |= MC_IIOBS_ERR_TIME;
    } else if (gains_finite && ((cfg->a1 * cfg->a1) > (4.0f * cfg->a2))) {
        /* fastest pole |lambda2| = (a1 + sqrt(a1^2 - 4 a2)) / 2 < a1 */
        const float lam2 = 0.5f * (cfg->a1 + mc_sqrt_f32((cfg->a1 * cfg->a1) - (4.0f * cfg->a2)));
        if (!((lam2 * cfg->dt_s) <= (MC_IIOBS_MAX_STEP * cfg->t_unit_s))) {
            err |= MC_IIOBS_ERR_TIME;
        }
        if (mech_ok && !((cfg->f_nms_rad * cfg->dt_s) <= (MC_IIOBS_MAX_STEP * cfg->j_kgm2))) {
            err |= MC_IIOBS_ERR_TIME;
        }
    } else {
        /* step check needs valid gains */
    }
    if (!(cfg->r_max > 1.0f) || !mc_isfinite_f32(cfg->r_max)) {
        err |= MC_IIOBS_ERR_RMAX_CFG;
    }
    return err;
}

uint32_t mc_iiobs_f32_init(mc_iiobs_f32_t *st, const mc_iiobs_f32_cfg_t *cfg)
{
    uint32_t err;
    mc_iiobs_f32_const_t k;
    float root;
    float v11;
    float v12;
    float v21;
    float v22;
    float n1;
    float n2;
    float absdet;
    float smax;

    if ((st == NULL) || (cfg == NULL)) {
        return MC_IIOBS_ERR_NULL;
    }
    err = iiobs_validate(cfg);
    if (err != MC_IIOBS_ERR_NONE) {
        return err;
    }
    root = mc_sqrt_f32((cfg->a1 * cfg->a1) - (4.0f * cfg->a2));
    k.k1 = 0.5f * (cfg->a1 - root);
    k.lambda1 = -k.k1;
    k.lambda2 = -0.5f * (cfg->a1 + root);
    k.delta1 = cfg->a1 - ((cfg->f_nms_rad * cfg->t_unit_s) / cfg->j_kgm2);
    k.delta2 = -cfg->a2;
    k.k2 = (k.delta1 * k.delta1) + (k.delta2 * k.delta2);
    /* A* v = lambda v with v = [1, -(a1 + lambda)]: columns of V = T^-1,
     * each normalised to unit length. */
    v11 = 1.0f;
    v21 = -(cfg->a1 + k.lambda1);
    v12 = 1.0f;
    v22 = -(cfg->a1 + k.lambda2);
    n1 = mc_sqrt_f32((v11 * v11) + (v21 * v21));
    n2 = mc_sqrt_f32((v12 * v12) + (v22 * v22));
    v11 /= n1;
    v21 /= n1;
    v12 /= n2;
    v22 /= n2;
    smax = norm2_2x2(v11, v12, v21, v22, &absdet);
    k.k3 = smax;                   /* ||T^-1|| = ||V|| */
    k.k5 = (smax * smax) / absdet; /* ||V|| ||V^-1|| = smax / smin, smax smin = |det| */
    k.c_r = (k.k2 * k.k5 * k.k5) / (2.0f * k.k1);
    k.c_rho = 0.5f * (((k.k2 * k.k5 * k.k5) / k.k1) + (k.k3 * k.k3));
    if (!mc_isfinite_f32(k.c_rho) || !mc_isfinite_f32(k.c_r)) {
        return MC_IIOBS_ERR_GAINS;
    }

    st->cfg = *cfg;
    st->k = k;
    st->dts = cfg->dt_s / cfg->t_unit_s;
    st->f_s = (cfg->f_nms_rad * cfg->t_unit_s) / cfg->j_kgm2;
    st->tau_s_per_nm = (cfg->t_unit_s * cfg->t_unit_s) / cfg->j_kgm2;
    st->hh1 = 0.0f;
    st->hh2 = 1.0f;
    st->h1 = 0.0f;
    st->h2 = 1.0f;
    st->xi1 = 0.0f;
    st->xi2 = 0.0f;
    st->r = 1.0f;
    st->eta1 = 0.0f;
    st->eta2 = 0.0f;
    st->primed = false;
    st->flags = MC_IIOBS_ERR_NONE;
    return MC_IIOBS_ERR_NONE;
}

uint32_t mc_iiobs_f32_reset(mc_iiobs_f32_t *st, float theta_m_rad, float omega_m_rad_s,
                            float tau_load_nm)
{
    float s;
    float c;

    if (st == NULL) {
        return MC_IIOBS_ERR_NULL;
    }
    if (!mc_isfinite_f32(theta_m_rad) || !mc_isfinite_f32(omega_m_rad_s) ||
        !mc_isfinite_f32(tau_load_nm)) {
        return MC_IIOBS_ERR_NAN_INPUT;
    }
    mc_sincos_f32(theta_m_rad, &s, &c);
    st->h1 = s;
    st->h2 = c;
    st->hh1 = s;
    st->hh2 = c;
    st->r = 1.0f;
    /* h_hat = h: rho2 = 0, so xi = eta_hat */
    st->eta1 = omega_m_rad_s * st->cfg.t_unit_s;
    st->eta2 = tau_load_nm * st->tau_s_per_nm;
    st->xi1 = st->eta1;
    st->xi2 = st->eta2;
    st->primed = true;
    st->flags = MC_IIOBS_ERR_NONE;
    return MC_IIOBS_ERR_NONE;
}

uint32_t mc_iiobs_f32_step(mc_iiobs_f32_t *st, float theta_m_rad, float tau_nm)
{
    const mc_iiobs_f32_const_t *k;
    uint32_t raised = MC_IIOBS_ERR_NONE;
    float hn1;
    float hn2;
    float hm1;
    float hm2;
    float rho1;
    float den;
    float g1;
    float g2;
    float rho2_old;
    float rho2_new;
    float hth;
    float drift;
    float e;
    float r;

    if (st == NULL) {
        return MC_IIOBS_ERR_NULL;
    }
    if (!mc_isfinite_f32(theta_m_rad) || !mc_isfinite_f32(tau_nm)) {
        st->flags |= MC_IIOBS_ERR_NAN_INPUT;
        return MC_IIOBS_ERR_NAN_INPUT;
    }
    k = &st->k;
    mc_sincos_f32(theta_m_rad, &hn1, &hn2);
    if (!st->primed) {
        st->h1 = hn1;
        st->h2 = hn2;
        st->hh1 = hn1;
        st->hh2 = hn2;
        st->primed = true;
    }

    /* h_hat: backward Euler, rotation term at the mid-point of h. */
    rho1 = st->cfg.k4 + (k->c_rho * st->r * st->r);
    hm1 = 0.5f * (st->h1 + hn1);
    hm2 = 0.5f * (st->h2 + hn2);
    den = 1.0f + (rho1 * st->dts);
    g1 = (st->hh1 + (st->dts * ((hm2 * st->eta1) + (rho1 * hn1)))) / den;
    g2 = (st->hh2 + (st->dts * ((-hm1 * st->eta1) + (rho1 * hn2)))) / den;

    /* xi: model part and the predicted h-driven change of beta (previous
     * h, h_hat), then the exact h_hat-driven change of beta. */
    hth = (st->h1 * st->hh1) + (st->h2 * st->hh2);
    drift = (st->tau_s_per_nm * tau_nm) - (st->f_s * st->eta1) - st->eta2;
    rho2_old = (hn1 * st->hh2) - (st->hh1 * hn2);
    rho2_new = (hn1 * g2) - (g1 * hn2);
    st->xi1 +=
        (st->dts * (drift - (st->eta1 * hth * k->delta1))) - ((rho2_new - rho2_old) * k->delta1);
    st->xi2 += (st->dts * (-(st->eta1 * hth * k->delta2))) - ((rho2_new - rho2_old) * k->delta2);

    /* dynamic scaling */
    e = 1.0f - ((hn1 * g1) + (hn2 * g2));
    r = st->r + (st->dts * ((-0.25f * k->k1 * (st->r - 1.0f)) + (k->c_r * st->r * e * e)));
    if (r < 1.0f) {
        r = 1.0f;
    }
    if (!(r < st->cfg.r_max)) {
        r = st->cfg.r_max; /* also catches a NaN */
        raised |= MC_IIOBS_ERR_R_MAX;
    }

    st->hh1 = g1;
    st->hh2 = g2;
    st->h1 = hn1;
    st->h2 = hn2;
    st->r = r;
    st->eta1 = st->xi1 + (rho2_new * k->delta1);
    st->eta2 = st->xi2 + (rho2_new * k->delta2);
    st->flags |= raised;
    return raised;
}

float mc_iiobs_f32_get_omega_m_rad_s(const mc_iiobs_f32_t *st)
{
    return st->eta1 / st->cfg.t_unit_s;
}

float mc_iiobs_f32_get_tau_load_nm(const mc_iiobs_f32_t *st)
{
    return st->eta2 / st->tau_s_per_nm;
}
