/**
 * @file mc_comm_check.c
 * @brief Consistency checks of the flux step (see mc_comm_check.h).
 */
#include "commission/mc_comm_check.h"

#include <stddef.h>

#include "commission/mc_commission.h"
#include "math/mc_math.h"

void mc_comm_blk_reset(mc_comm_blk_t *b)
{
    *b = (mc_comm_blk_t){0};
    b->len = 1u;
}

void mc_comm_blk_step(mc_comm_blk_t *b, float y)
{
    b->acc += y;
    b->k++;
    if (b->k < b->len) {
        return;
    }
    b->mean[b->nb] = b->acc / (float)b->len;
    b->nb++;
    b->acc = 0.0f;
    b->k = 0u;
    if (b->nb == MC_COMM_BLK_N) {
        for (uint32_t j = 0u; j < MC_COMM_BLK_N / 2u; ++j) {
            b->mean[j] = 0.5f * (b->mean[2u * j] + b->mean[2u * j + 1u]);
        }
        b->nb = MC_COMM_BLK_N / 2u;
        b->len *= 2u;
    }
}

bool mc_comm_blk_line(const mc_comm_blk_t *b, uint32_t j0, uint32_t j1, float dt_s, float *p_slope,
                      float *p_mean, float *p_rms, float *p_slope_per_err)
{
    if (j1 > b->nb || j1 < j0 + 3u) {
        return false;
    }
    /* centre of block j: (j + 1/2) len dt, up to a constant that the
     * slope does not see; centred on the blocks' middle */
    const float tb = (float)b->len * dt_s;
    const float n = (float)(j1 - j0);
    const float xm = 0.5f * (float)(j0 + j1 - 1u) * tb + 0.5f * tb;
    float ym = 0.0f;
    for (uint32_t j = j0; j < j1; ++j) {
        ym += b->mean[j];
    }
    ym /= n;
    float sxx = 0.0f;
    float sxy = 0.0f;
    float sabs = 0.0f;
    for (uint32_t j = j0; j < j1; ++j) {
        const float x = ((float)j + 0.5f) * tb - xm;
        sxx += x * x;
        sxy += x * (b->mean[j] - ym);
        sabs += mc_abs_f32(x);
    }
    const float a = sxy / sxx;
    float ss = 0.0f;
    for (uint32_t j = j0; j < j1; ++j) {
        const float e = b->mean[j] - ym - a * (((float)j + 0.5f) * tb - xm);
        ss += e * e;
    }
    *p_slope = a;
    *p_mean = ym;
    *p_rms = mc_sqrt_f32(ss / n);
    *p_slope_per_err = sabs / sxx;
    return true;
}

float mc_comm_flux_band_res_f32(uint32_t cpr, float t_band_s, float tau_s, float w_m_rad_s,
                                float v_dead_v, float v_mag_v)
{
    if (cpr == 0u || !(t_band_s > 0.0f) || !(tau_s > 0.0f) || !(w_m_rad_s > 0.0f) ||
        !(v_mag_v > 0.0f)) {
        return 1.0f; /* nothing to resolve with: the bands cannot agree within it */
    }
    const float q = MC_TWO_PI_F32 / (float)cpr;
    /* the band's mean speed: the counts' angle over the band and the
     * filter's state at each end, a count each: 3 counts over T_band */
    const float r_mean = 3.0f * q / (t_band_s * w_m_rad_s);
    /* the per-sample speed: a count now and then (a Bernoulli train of
     * q / dt spikes at the rate w / q) through the one-pole filter of tau:
     * variance w q / (2 tau); through the fit it biases by var / w^2 */
    const float r_noise = q / (2.0f * tau_s * w_m_rad_s);
    return r_mean + r_noise + v_dead_v / v_mag_v;
}

uint32_t mc_comm_flux_check_f32(const mc_ident_line_f32_t *hi, const mc_ident_line_f32_t *lo,
                                float tol, mc_comm_flux_chk_t *out)
{
    *out = (mc_comm_flux_chk_t){0};
    out->tol = tol;
    float ph = 0.0f;
    float pl = 0.0f;
    if (mc_ident_line_f32_get(hi, false, &ph, NULL) != 0u ||
        mc_ident_line_f32_get(lo, false, &pl, NULL) != 0u || !(ph > 0.0f) || !(pl > 0.0f)) {
        out->dev = 1.0f;
        return MC_COMM_ERR_FLUX_SPEEDS;
    }
    out->psi_hi_wb = ph;
    out->psi_lo_wb = pl;
    out->dev = mc_abs_f32(ph - pl) / (0.5f * (ph + pl));
    return (out->dev <= tol) ? 0u : MC_COMM_ERR_FLUX_SPEEDS;
}

/* J of a spin-up half (slope a, mean w) with the coast's beta = B / J, and
 * the relative error the counts allow (slope errors per unit of block error
 * spe_s, spe_c; block errors e_s, e_c; the coast's mean wc). */
static float j_half(float tq, float a, float w, float beta, float spe_s, float e_s, float spe_c,
                    float e_c, float wc, float *p_rel)
{
    const float den = a + beta * w;
    if (!(den > 0.0f) || !(tq > 0.0f)) {
        *p_rel = 0.0f;
        return -1.0f;
    }
    const float d_beta = (spe_c * e_c + mc_abs_f32(beta) * e_c) / wc;
    const float d_den = spe_s * e_s + d_beta * w + mc_abs_f32(beta) * e_s;
    *p_rel = d_den / den;
    return tq / den;
}

uint32_t mc_comm_mech_check_f32(const mc_comm_blk_t *spin, const mc_comm_blk_t *coast, float dt_s,
                                uint32_t cpr, float tq_spin_nm, float tq_coast_nm,
                                mc_comm_mech_chk_t *out)
{
    *out = (mc_comm_mech_chk_t){0};
    float ac;
    float wc;
    float rc;
    float spe_c;
    float a1;
    float w1;
    float r1;
    float spe1;
    float a2;
    float w2;
    float r2;
    float spe2;
    const uint32_t h = spin->nb / 2u;
    if (cpr == 0u || spin->nb < 6u ||
        !mc_comm_blk_line(coast, 0u, coast->nb, dt_s, &ac, &wc, &rc, &spe_c) ||
        !mc_comm_blk_line(spin, 0u, h, dt_s, &a1, &w1, &r1, &spe1) ||
        !mc_comm_blk_line(spin, h, spin->nb, dt_s, &a2, &w2, &r2, &spe2) || !(wc > 0.0f)) {
        return MC_COMM_ERR_MECH_FIT;
    }
    const float q = MC_TWO_PI_F32 / (float)cpr;
    /* a block mean of the count speed: its counts' angle and the filter's
     * state at each end, a count each, over the block's time */
    const float e_c = 3.0f * q / ((float)coast->len * dt_s);
    const float e_s = 3.0f * q / ((float)spin->len * dt_s);
    /* the coast: a line within MC_COMM_MECH_FIT_TOL of its fall, plus the
     * viscous decay's own bend (w0 exp(-beta t) about its line over T:
     * RMS T^2 / (6 sqrt 5) w0 beta^2 / 2 over the fall w0 beta T, under
     * 0.04 beta T) and the counts' part */
    const float t_win = (float)(coast->nb * coast->len) * dt_s;
    const float beta = -ac / wc;
    const float fall = mc_abs_f32(ac) * t_win;
    const float fall_min = 1e-6f * wc;
    const float fall_d = (fall > fall_min) ? fall : fall_min;
    const float bend = 0.04f * mc_abs_f32(beta) * t_win;
    out->fit_rms = rc / fall_d;
    out->fit_tol = MC_COMM_MECH_FIT_TOL + bend + e_c / fall_d;
    if (rc > (MC_COMM_MECH_FIT_TOL + bend) * fall + e_c) {
        return MC_COMM_ERR_MECH_FIT;
    }
    float rel1;
    float rel2;
    /* J a_h = T_s - B w_h and J a_c = T_c - B w_c: J (a_h - a_c w_h / w_c)
     * = T_s - T_c w_h / w_c, beta = -a_c / w_c */
    const float j1 =
        j_half(tq_spin_nm - tq_coast_nm * w1 / wc, a1, w1, beta, spe1, e_s, spe_c, e_c, wc, &rel1);
    const float j2 =
        j_half(tq_spin_nm - tq_coast_nm * w2 / wc, a2, w2, beta, spe2, e_s, spe_c, e_c, wc, &rel2);
    out->j_lo_kgm2 = j1;
    out->j_hi_kgm2 = j2;
    out->j_tol = MC_COMM_MECH_J_TOL + rel1 + rel2;
    if (!(j1 > 0.0f) || !(j2 > 0.0f)) {
        out->j_dev = 1.0f;
        return MC_COMM_ERR_MECH_SPIN_COAST;
    }
    out->j_dev = mc_abs_f32(j1 - j2) / (0.5f * (j1 + j2));
    return (out->j_dev <= out->j_tol) ? 0u : MC_COMM_ERR_MECH_SPIN_COAST;
}
