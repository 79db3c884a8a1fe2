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
            const uint32_t i0 = 2u * j;
            b->mean[j] = 0.5f * (b->mean[i0] + b->mean[i0 + 1u]);
        }
        b->nb = MC_COMM_BLK_N / 2u;
        b->len *= 2u;
    }
}

float mc_comm_blk_mean(const mc_comm_blk_t *b, uint32_t j0, uint32_t j1)
{
    float m = 0.0f;
    for (uint32_t j = j0; j < j1; ++j) {
        m += b->mean[j];
    }
    return m / (float)(j1 - j0);
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

uint32_t mc_comm_mech_check_f32(const mc_comm_blk_t *spin, const mc_comm_blk_t *coast, float dt_s,
                                uint32_t cpr, float tq_nm, mc_comm_mech_chk_t *out)
{
    *out = (mc_comm_mech_chk_t){0};
    const uint32_t ns = spin->nb / 4u;  /* blocks a quarter of the spin-up */
    const uint32_t nc = coast->nb / 3u; /* blocks a third of the coast */
    if (cpr == 0u || ns < 2u || nc < 2u) {
        return MC_COMM_ERR_MECH_FIT;
    }
    float s[4];
    float c[3];
    for (uint32_t k = 0u; k < 4u; ++k) {
        s[k] = mc_comm_blk_mean(spin, k * ns, (k + 1u) * ns);
    }
    for (uint32_t k = 0u; k < 3u; ++k) {
        c[k] = mc_comm_blk_mean(coast, k * nc, (k + 1u) * nc);
    }
    /* the time between neighbouring segments' centres, and the error of a
     * segment's mean count speed: its counts' angle and the filter's state
     * at each end, a count each, over its time */
    const float hs = (float)(ns * spin->len) * dt_s;
    const float hc = (float)(nc * coast->len) * dt_s;
    const float q3 = 3.0f * MC_TWO_PI_F32 / (float)cpr;
    const float es = q3 / hs;
    const float ec = q3 / hc;
    /* the coast: its middle third on the chord of the outer two within
     * MC_COMM_MECH_FIT_TOL of the fall, plus the viscous decay's own bend
     * (w0 exp(-beta t): beta T / 12 of the fall over T = 3 hc; 0.1 beta T
     * allowed) and the counts' part (2 ec) */
    const float wc = (c[0] + c[1] + c[2]) / 3.0f;
    const float fall = c[0] - c[2];
    const float beta = fall / (2.0f * hc * wc);
    const float bend = mc_abs_f32(c[1] - 0.5f * (c[0] + c[2]));
    const float allowed =
        (MC_COMM_MECH_FIT_TOL + 0.3f * mc_abs_f32(beta) * hc) * mc_abs_f32(fall) + 2.0f * ec;
    const float fall_d = mc_abs_f32(fall) + 1e-6f * wc;
    out->fit_rms = bend / fall_d;
    out->fit_tol = allowed / fall_d;
    if (!(wc > 0.0f) || !(bend <= allowed)) {
        return MC_COMM_ERR_MECH_FIT;
    }
    /* each half of the spin-up: J (a_h + beta w_h) = T, beta = B / J from
     * the coast; the counts' part of each through den */
    const float d_beta = (ec / hc + mc_abs_f32(beta) * ec) / wc;
    float j[2];
    float rel = 0.0f;
    for (uint32_t h = 0u; h < 2u; ++h) {
        const uint32_t i0 = 2u * h;
        const float w = 0.5f * (s[i0] + s[i0 + 1u]);
        const float den = (s[i0 + 1u] - s[i0]) / hs + beta * w;
        j[h] = (den > 0.0f) ? tq_nm / den : -1.0f;
        rel += (2.0f * es / hs + mc_abs_f32(beta) * es + d_beta * w) / mc_abs_f32(den);
    }
    out->j_lo_kgm2 = j[0];
    out->j_hi_kgm2 = j[1];
    out->j_tol = MC_COMM_MECH_J_TOL + rel;
    if (!(j[0] > 0.0f) || !(j[1] > 0.0f) || !(tq_nm > 0.0f)) {
        out->j_dev = 1.0f;
        return MC_COMM_ERR_MECH_SPIN_COAST;
    }
    out->j_dev = mc_abs_f32(j[0] - j[1]) / (0.5f * (j[0] + j[1]));
    return (out->j_dev <= out->j_tol) ? 0u : MC_COMM_ERR_MECH_SPIN_COAST;
}
