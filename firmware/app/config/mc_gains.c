/**
 * @file mc_gains.c
 * @brief Controller gains from the motor's values: see mc_gains.h.
 */
#include "mc_gains.h"

#include <stddef.h>
#include <string.h>

static int positive_finite(double x)
{
    return (x > 0.0) && (x < 1e300); /* NaN fails both, inf the second */
}

double mc_gains_kt_nm_a(double pole_pairs, double flux_wb)
{
    return 1.5 * pole_pairs * flux_wb;
}

double mc_gains_enc_bw_quant_rad_s(const mc_gains_motor_t *m, const mc_gains_t *g)
{
    /* One count q = 2 pi / cpr stepping the tracking loop's input moves its
     * speed by 3 bw q at once (k2 / bw: the loop's gain from an angle step
     * to its speed), which the speed PI (kp = J wc / kt, wc = bw / 4) turns
     * into 3 kp bw q of current: at most MC_GAINS_ENC_NOISE_FRAC of the
     * rated current, 3 J bw^2 q / (4 kt) <= frac i_rated. No encoder: no
     * bound. */
    if (!(m->encoder_cpr > 0.0) || !(m->j_kgm2 > 0.0) || !(g->kt_nm_a > 0.0)) {
        return __builtin_inf();
    }
    const double q = 2.0 * 3.14159265358979323846 / m->encoder_cpr;
    return mc_gains_sqrt(4.0 * MC_GAINS_ENC_NOISE_FRAC * g->i_rated_eff_a * g->kt_nm_a /
                         (3.0 * m->j_kgm2 * q));
}

double mc_gains_speed_wc_rad_s(double cur_bw_rad_s, double enc_pll_bw_rad_s)
{
    const double a = cur_bw_rad_s / 10.0;
    const double b = enc_pll_bw_rad_s / 4.0;
    return (b < a) ? b : a;
}

uint32_t mc_gains_speed_pi(double j_kgm2, double kt_nm_a, double wc_rad_s, float *p_kp_a_s_rad,
                           float *p_ki_a_rad)
{
    if ((p_kp_a_s_rad == NULL) || (p_ki_a_rad == NULL) || !positive_finite(j_kgm2) ||
        !positive_finite(kt_nm_a) || !positive_finite(wc_rad_s)) {
        return MC_GAINS_ERR_VALUE;
    }
    {
        const float kp = (float)(j_kgm2 * wc_rad_s / kt_nm_a);
        *p_kp_a_s_rad = kp;
        *p_ki_a_rad = (float)((double)kp * wc_rad_s / 4.0);
    }
    return MC_GAINS_OK;
}

/* ------------------------------------------------ the laws' gains (issue 19) */

double mc_gains_sqrt(double x)
{
    uint64_t b;
    uint64_t m;
    uint64_t q = 0u;
    uint64_t r = 0u;
    int32_t e;
    if (!(x >= 0.0)) {
        return __builtin_nan(""); /* NaN and negatives have no root */
    }
    if ((x == 0.0) || (x > 1.7976931348623157e308)) {
        return x; /* 0 and inf are their own roots */
    }
    (void)memcpy(&b, &x, sizeof b);
    e = (int32_t)((b >> 52u) & 0x7FFu);
    m = b & 0xFFFFFFFFFFFFFull;
    if (e == 0) { /* subnormal: normalise */
        while ((m & (1ull << 52u)) == 0u) {
            m <<= 1u;
            e--;
        }
        e++;
    } else {
        m |= 1ull << 52u;
    }
    e -= 1023;
    if ((e & 1) != 0) {
        m <<= 1u;
        e -= 1;
    }
    /* m in [2^52, 2^54): q = floor(sqrt(m 2^54)) in [2^53, 2^54), bit by
     * bit from the top pair of the 108-bit radicand; r < 2 q + 1 < 2^55 */
    for (int32_t j = 53; j >= 0; j--) {
        const int32_t pos = (2 * j) - 54;
        const uint64_t pair = (pos >= 0) ? ((m >> (uint32_t)pos) & 3u) : 0u;
        const uint64_t t = (q << 2u) | 1u;
        r = (r << 2u) | pair;
        q <<= 1u;
        if (r >= t) {
            r -= t;
            q |= 1u;
        }
    }
    {
        /* 53 bits, the next one and the rest: round to nearest, ties even */
        uint64_t mant = q >> 1u;
        if (((q & 1u) != 0u) && ((r != 0u) || ((mant & 1u) != 0u))) {
            mant++; /* 2^53 carries into the exponent below */
        }
        b = ((uint64_t)(int64_t)((e / 2) + 1022) << 52u) + mant;
    }
    (void)memcpy(&x, &b, sizeof x);
    return x;
}

/* std::min's choice (the first of equals): the same double as the
 * simulator's C++ always computed, bit for bit. */
static double dmin(double a, double b)
{
    return (b < a) ? b : a;
}

/* A given value (not NaN) or the derived one. */
static double pick(double fixed, double derived)
{
    return (fixed == fixed) ? fixed : derived; /* NaN != NaN */
}

void mc_gains_fix_none(mc_gains_t *fix)
{
    const double nan = __builtin_nan("");
    fix->cur_bw_rad_s = nan;
    fix->i_limit_a = nan;
    fix->enc_pll_bw_rad_s = nan;
    fix->speed_wc_rad_s = nan;
    fix->speed_accel_rad_s2 = nan;
    fix->speed_kp_a_s_rad = nan;
    fix->speed_ki_a_rad = nan;
    fix->obs_crit_rad_s = nan;
    fix->pll_bw_rad_s = nan;
    fix->sls_wc_rad_s = nan;
    fix->handover_rad_s = nan;
    fix->if_current_a = nan;
    fix->if_accel_rad_s2 = nan;
    fix->align_time_s = nan;
    fix->pi2d_wn_rad_s = nan;
    fix->pi2d_a_per_s = nan;
    fix->pos_kp_per_s = nan;
    fix->pos_v_max_rad_s = nan;
    fix->pos_a_max_rad_s2 = nan;
    fix->pos_d_max_rad_s2 = nan;
    fix->pos_filter_bw_rad_s = nan;
    fix->stop_decel_rad_s2 = nan;
    fix->kt_nm_a = nan;
    fix->v_max_v = nan;
    fix->i_rated_eff_a = nan;
    fix->torque_rated_nm = nan;
    fix->speed_limit_rad_s = nan;
    fix->speed_rated_eff_rad_s = nan;
    fix->pi2d_coupling = nan;
    fix->speed_voltage_rad_s = nan;
    fix->speed_delay_rad_s = nan;
}

/* Speed at which current i needs v_max (steady state, id = 0, iq = i):
 * (R i)^2 + 2 R i ke w + (ke^2 + (p L i)^2) w^2 = v_max^2, positive root. */
static double voltage_limited_speed(const mc_gains_motor_t *m, double i_a, double v_max)
{
    const double ke = m->pole_pairs * m->flux_wb;
    const double pl = m->pole_pairs * m->lq_h * i_a;
    const double a = ke * ke + pl * pl;
    const double b = 2.0 * m->r_ohm * i_a * ke;
    const double c = m->r_ohm * i_a * m->r_ohm * i_a - v_max * v_max;
    if (c >= 0.0) {
        return 0.0;
    }
    return (-b + mc_gains_sqrt(b * b - 4.0 * a * c)) / (2.0 * a);
}

static int motor_ok(const mc_gains_motor_t *m)
{
    /* the values every formula divides by, or takes a root of */
    return positive_finite(m->r_ohm) && positive_finite(m->ld_h) && positive_finite(m->lq_h) &&
           positive_finite(m->flux_wb) && positive_finite(m->pole_pairs) &&
           positive_finite(m->j_kgm2) && positive_finite(m->i_max_a) &&
           positive_finite(m->i_rated_a) && positive_finite(m->speed_max_rad_s) &&
           positive_finite(m->speed_rated_rad_s) && positive_finite(m->vbus_v) &&
           positive_finite(m->pwm_hz) && positive_finite(m->i_sense_max_a) &&
           (m->b_nm_s_rad >= 0.0) && (m->dead_time_s >= 0.0) && (m->delay_periods >= 0.0);
}

uint32_t mc_gains_derive(const mc_gains_motor_t *m, const mc_gains_t *fix, mc_gains_t *g)
{
    mc_gains_t none;
    uint32_t err = MC_GAINS_OK;
    double T;
    double l_min;
    double w_r;
    double sigma;
    double t_hold;
    double t_lag;
    if ((m == NULL) || (g == NULL)) {
        return MC_GAINS_ERR_VALUE;
    }
    if (fix == NULL) {
        mc_gains_fix_none(&none);
        fix = &none;
    }
    mc_gains_fix_none(g);
    if (!motor_ok(m)) {
        return MC_GAINS_ERR_VALUE;
    }
    T = 1.0 / m->pwm_hz;
    l_min = dmin(m->ld_h, m->lq_h);
    if (l_min / m->r_ohm < 2.0 * T) {
        err |= MC_GAINS_ERR_LR_SHORT;
    }
    if (m->vbus_v * T / (4.0 * l_min) > m->i_max_a) {
        err |= MC_GAINS_ERR_RIPPLE;
    }
    g->kt_nm_a = mc_gains_kt_nm_a(m->pole_pairs, m->flux_wb);
    g->v_max_v = 0.95 * m->vbus_v / mc_gains_sqrt(3.0);
    g->cur_bw_rad_s = pick(fix->cur_bw_rad_s, 0.08 / T);
    g->i_limit_a = pick(fix->i_limit_a, dmin(dmin(m->i_max_a, m->i_sense_max_a / 1.25),
                                             0.8 * g->v_max_v / m->r_ohm));
    if (g->i_limit_a < 0.1 * m->i_max_a) {
        err |= MC_GAINS_ERR_I_LIMIT;
    }
    if (g->i_limit_a > m->i_sense_max_a / 1.1) {
        err |= MC_GAINS_ERR_SENSE;
    }
    g->i_rated_eff_a = dmin(m->i_rated_a, g->i_limit_a);
    g->torque_rated_nm = g->kt_nm_a * g->i_rated_eff_a;
    g->speed_voltage_rad_s = voltage_limited_speed(m, g->i_rated_eff_a, g->v_max_v);
    g->speed_delay_rad_s = MC_GAINS_WE_T_MAX / (m->pole_pairs * T);
    /* 0.9 min(a, b) is min(0.9 a, 0.9 b) bit for bit (a product by a
     * positive constant keeps the order) */
    g->speed_limit_rad_s =
        dmin(m->speed_max_rad_s, 0.9 * dmin(g->speed_voltage_rad_s, g->speed_delay_rad_s));
    if (!(g->speed_limit_rad_s > 0.0)) {
        err |= MC_GAINS_ERR_SPEED_LIMIT;
    }
    g->speed_rated_eff_rad_s = dmin(m->speed_rated_rad_s, g->speed_limit_rad_s);
    /* the sample period or the encoder's latency, the longer: 0.1 rad of
     * phase at the loop's bandwidth */
    t_lag = (m->encoder_latency_s > T) ? m->encoder_latency_s : T;
    g->enc_pll_bw_rad_s = pick(fix->enc_pll_bw_rad_s,
                               dmin(dmin(1000.0, 0.1 / t_lag), mc_gains_enc_bw_quant_rad_s(m, g)));
    g->speed_wc_rad_s =
        pick(fix->speed_wc_rad_s, mc_gains_speed_wc_rad_s(g->cur_bw_rad_s, g->enc_pll_bw_rad_s));
    g->speed_accel_rad_s2 =
        pick(fix->speed_accel_rad_s2, 0.5 * g->kt_nm_a * g->i_limit_a / m->j_kgm2);
    {
        /* the speed PI at speed_wc (kp = J wc / kt, zero at wc / 4); a gain
         * given alone keeps the other derived */
        float kp = 0.0f;
        float ki = 0.0f;
        (void)mc_gains_speed_pi(m->j_kgm2, g->kt_nm_a, g->speed_wc_rad_s, &kp, &ki);
        g->speed_kp_a_s_rad = pick(fix->speed_kp_a_s_rad, (double)kp);
        g->speed_ki_a_rad = pick(fix->speed_ki_a_rad, (double)ki);
    }
    w_r = g->speed_rated_eff_rad_s;
    g->obs_crit_rad_s = pick(fix->obs_crit_rad_s, 0.02 * w_r);
    g->pll_bw_rad_s = pick(fix->pll_bw_rad_s, dmin(300.0, 0.04 / T));
    g->sls_wc_rad_s = pick(fix->sls_wc_rad_s, dmin(g->pll_bw_rad_s / 3.0, g->cur_bw_rad_s / 10.0));
    g->handover_rad_s = pick(fix->handover_rad_s, 0.1 * w_r);
    g->if_current_a = pick(fix->if_current_a, dmin(g->i_limit_a, 0.8 * g->i_rated_eff_a));
    g->if_accel_rad_s2 = pick(fix->if_accel_rad_s2, 0.15 * g->torque_rated_nm / m->j_kgm2);
    /* a 30 % rated load cannot turn the rotor 0.2 rad (electrical) while the
     * current ramps up; long enough for the current loop (std::clamp) */
    t_hold = 2.0 * mc_gains_sqrt(0.2 * m->j_kgm2 / (m->pole_pairs * 0.3 * g->torque_rated_nm));
    {
        const double lo = 10.0 / g->cur_bw_rad_s;
        const double hi = 0.05;
        const double cl = (t_hold < lo) ? lo : ((hi < t_hold) ? hi : t_hold);
        g->align_time_s = pick(fix->align_time_s, cl);
    }
    g->pi2d_wn_rad_s =
        pick(fix->pi2d_wn_rad_s, dmin(g->speed_wc_rad_s / 3.0, 0.5 * m->r_ohm / m->lq_h));
    /* the dirty-derivative pole: the law's coupling of the speed error into
     * the q-current error, Delta ~ 3 wn a J / kt, below 2 k2 */
    sigma = g->kt_nm_a / m->j_kgm2;
    g->pi2d_a_per_s =
        pick(fix->pi2d_a_per_s, dmin(dmin(g->enc_pll_bw_rad_s, 0.1 / T),
                                     2.0 * g->cur_bw_rad_s * sigma / (3.0 * g->pi2d_wn_rad_s)));
    g->pos_kp_per_s = pick(fix->pos_kp_per_s, g->speed_wc_rad_s / 6.0);
    g->pos_v_max_rad_s = pick(fix->pos_v_max_rad_s, 0.5 * w_r);
    g->pos_a_max_rad_s2 = pick(fix->pos_a_max_rad_s2, g->speed_accel_rad_s2);
    g->pos_d_max_rad_s2 = pick(fix->pos_d_max_rad_s2, g->speed_accel_rad_s2);
    g->pos_filter_bw_rad_s = pick(fix->pos_filter_bw_rad_s, g->pos_kp_per_s);
    g->stop_decel_rad_s2 = pick(fix->stop_decel_rad_s2, g->speed_accel_rad_s2);
    g->pi2d_coupling = sigma * m->pole_pairs * m->flux_wb / (m->lq_h * g->cur_bw_rad_s);
    return err;
}

double mc_gains_sls_slew_rad_s2(const mc_gains_motor_t *m, const mc_gains_t *g)
{
    return 0.5 * g->torque_rated_nm / m->j_kgm2;
}

double mc_gains_vbus_max_v(const mc_gains_motor_t *m)
{
    const double v = 1.5 * m->vbus_v;
    if (m->vbus_max_v > 0.0) {
        return m->vbus_max_v;
    }
    return ((m->vbus_board_max_v > 0.0) && (m->vbus_board_max_v < v)) ? m->vbus_board_max_v : v;
}
