/**
 * @file mc_pi_q31.c
 * @brief PI controller, q31 twin of mc_pi.c. Scaling and overflow analysis:
 *        see mc_pi_q31.h.
 */
#include "pi/mc_pi_q31.h"

#include <stdbool.h>
#include <stddef.h>

#include "math/mc_math.h"
#include "pi/mc_pi_core.h"

/* Accumulator format Q17.46: a q31 value v is v * 2^15. */
#define PI_Q46_FROM_Q31_SHIFT 15

static int64_t pi_q46_from_q31(q31_t x)
{
    return (int64_t)x * ((int64_t)1 << PI_Q46_FROM_Q31_SHIFT);
}

/* Q17.46 value, already inside the q31 range (times 2^15), to q31 rounded
 * to nearest (ties up). */
static q31_t pi_q31_from_q46(int64_t x)
{
    return mc_q31_sat64((x + ((int64_t)1 << (PI_Q46_FROM_Q31_SHIFT - 1))) >> PI_Q46_FROM_Q31_SHIFT);
}

static int64_t pi_clamp64(int64_t x, int64_t lo, int64_t hi)
{
    return (x < lo) ? lo : ((x > hi) ? hi : x);
}

/* (mant * 2^shift / 2^31) * x in Q17.46, rounded. mant >= 0, shift 0..15:
 * |mant*x| <= 2^62 (Q2.62), shifted right by 16 - shift >= 1, so the result
 * is at most 2^61 in magnitude. */
static int64_t pi_gain_mul_q46(q31_t mant, int32_t shift, q31_t x)
{
    int64_t prod = (int64_t)mant * (int64_t)x;
    int32_t rs = 16 - shift;
    return (prod + ((int64_t)1 << (rs - 1))) >> rs;
}

/* x (Q17.46, |x| < 2^62.1) times k (q31, >= 0), rounded: split x into
 * hi * 2^31 + lo with 0 <= lo < 2^31 so no partial product exceeds 2^63. */
static int64_t pi_q46_mul_q31(int64_t x, q31_t k)
{
    int64_t hi = x >> 31;
    int64_t lo = x - (hi * ((int64_t)1 << 31));
    int64_t lo_part = ((lo * (int64_t)k) + ((int64_t)1 << 30)) >> 31;
    return (hi * (int64_t)k) + lo_part;
}

static bool pi_shift_ok(int32_t s)
{
    return (s >= 0) && (s <= MC_PI_Q31_MAX_SHIFT);
}

uint32_t mc_pi_q31_init(mc_pi_q31_t *st, const mc_pi_q31_cfg_t *cfg)
{
    uint32_t err = MC_PI_ERR_NONE;

    if ((st == NULL) || (cfg == NULL)) {
        return MC_PI_ERR_NULL;
    }
    if ((cfg->kp_mant < 0) || !pi_shift_ok(cfg->kp_shift)) {
        err |= MC_PI_ERR_KP;
    }
    if ((cfg->ki_dt_mant < 0) || !pi_shift_ok(cfg->ki_shift)) {
        err |= MC_PI_ERR_KI;
    }
    if (cfg->out_min > cfg->out_max) {
        err |= MC_PI_ERR_LIMITS;
    }
    switch (cfg->aw) {
    case MC_PI_AW_CLAMP:
    case MC_PI_AW_NONE:
        break;
    case MC_PI_AW_BACK_CALC:
        if (cfg->kaw_dt <= 0) {
            err |= MC_PI_ERR_KAW;
        }
        break;
    default:
        err |= MC_PI_ERR_AW_MODE;
        break;
    }
    if (err != MC_PI_ERR_NONE) {
        return err;
    }
    st->kp_mant = cfg->kp_mant;
    st->kp_shift = cfg->kp_shift;
    st->ki_dt_mant = cfg->ki_dt_mant;
    st->ki_shift = cfg->ki_shift;
    st->kaw_dt = (cfg->aw == MC_PI_AW_BACK_CALC) ? cfg->kaw_dt : 0;
    st->out_min = cfg->out_min;
    st->out_max = cfg->out_max;
    st->aw = cfg->aw;
    (void)mc_pi_q31_reset(st, 0);
    return MC_PI_ERR_NONE;
}

uint32_t mc_pi_q31_reset(mc_pi_q31_t *st, q31_t integrator_preset)
{
    q31_t v;

    if (st == NULL) {
        return MC_PI_ERR_NULL;
    }
    v = mc_q31_sat(integrator_preset, st->out_min, st->out_max);
    st->integ_q46 = pi_q46_from_q31(v);
    st->out = v;
    st->last_error = 0;
    st->last_ff = 0;
    st->flags = MC_PI_ERR_NONE;
    return MC_PI_ERR_NONE;
}

uint32_t mc_pi_q31_step_lim(mc_pi_q31_t *st, q31_t error, q31_t ff, q31_t lim_lo, q31_t lim_hi,
                            q31_t *p_out)
{
    q31_t lo;
    q31_t hi;
    int64_t lo46;
    int64_t hi46;
    int64_t ff46;
    int64_t p;
    int64_t inc;
    int64_t integ;
    int64_t u46;

    if ((st == NULL) || (p_out == NULL)) {
        return MC_PI_ERR_NULL;
    }
    lo = (lim_lo > st->out_min) ? lim_lo : st->out_min;
    hi = (lim_hi < st->out_max) ? lim_hi : st->out_max;
    if (lo > hi) {
        st->flags |= MC_PI_ERR_DYN_LIMIT;
        *p_out = st->out;
        return MC_PI_ERR_DYN_LIMIT;
    }
    lo46 = pi_q46_from_q31(lo);
    hi46 = pi_q46_from_q31(hi);
    ff46 = pi_q46_from_q31(ff);

    /* |p|, |inc| <= 2^61; |integ|, |ff46| <= 2^46: every sum below < 2^63. */
    p = pi_gain_mul_q46(st->kp_mant, st->kp_shift, error);
    inc = pi_gain_mul_q46(st->ki_dt_mant, st->ki_shift, error);
    integ = st->integ_q46 + inc;

    if (st->aw == MC_PI_AW_CLAMP) {
        int64_t u_try = p + integ + ff46;
        if ((u_try > hi46) && (inc > 0)) {
            int64_t room = hi46 - p - ff46;
            integ = (room > st->integ_q46) ? room : st->integ_q46;
        } else if ((u_try < lo46) && (inc < 0)) {
            int64_t room = lo46 - p - ff46;
            integ = (room < st->integ_q46) ? room : st->integ_q46;
        } else {
            /* inside the limits, or pulling back into range: integrate */
        }
    } else if (st->aw == MC_PI_AW_BACK_CALC) {
        int64_t u_unsat = p + integ + ff46;
        int64_t u_sat = pi_clamp64(u_unsat, lo46, hi46);
        integ = integ + pi_q46_mul_q31(u_sat - u_unsat, st->kaw_dt);
    } else {
        /* MC_PI_AW_NONE */
    }
    integ = pi_clamp64(integ, pi_q46_from_q31(st->out_min), pi_q46_from_q31(st->out_max));
    u46 = pi_clamp64(p + integ + ff46, lo46, hi46);

    st->integ_q46 = integ;
    st->out = mc_q31_sat(pi_q31_from_q46(u46), lo, hi);
    st->last_error = error;
    st->last_ff = ff;
    *p_out = st->out;
    return MC_PI_ERR_NONE;
}

uint32_t mc_pi_q31_step_ff(mc_pi_q31_t *st, q31_t error, q31_t ff, q31_t *p_out)
{
    if (st == NULL) {
        return MC_PI_ERR_NULL;
    }
    return mc_pi_q31_step_lim(st, error, ff, st->out_min, st->out_max, p_out);
}

uint32_t mc_pi_q31_step(mc_pi_q31_t *st, q31_t error, q31_t *p_out)
{
    return mc_pi_q31_step_ff(st, error, 0, p_out);
}

uint32_t mc_pi_q31_set_gains(mc_pi_q31_t *st, q31_t kp_mant, int32_t kp_shift, q31_t ki_dt_mant,
                             int32_t ki_shift)
{
    uint32_t err = MC_PI_ERR_NONE;
    int64_t p_old;
    int64_t p_new;

    if (st == NULL) {
        return MC_PI_ERR_NULL;
    }
    if ((kp_mant < 0) || !pi_shift_ok(kp_shift)) {
        err |= MC_PI_ERR_KP;
    }
    if ((ki_dt_mant < 0) || !pi_shift_ok(ki_shift)) {
        err |= MC_PI_ERR_KI;
    }
    if (err != MC_PI_ERR_NONE) {
        return err;
    }
    p_old = pi_gain_mul_q46(st->kp_mant, st->kp_shift, st->last_error);
    p_new = pi_gain_mul_q46(kp_mant, kp_shift, st->last_error);
    /* |p_old - p_new| <= 2^62, |integ| <= 2^46: no overflow. */
    st->integ_q46 = pi_clamp64(st->integ_q46 + (p_old - p_new), pi_q46_from_q31(st->out_min),
                               pi_q46_from_q31(st->out_max));
    st->kp_mant = kp_mant;
    st->kp_shift = kp_shift;
    st->ki_dt_mant = ki_dt_mant;
    st->ki_shift = ki_shift;
    return MC_PI_ERR_NONE;
}

/* Per-unit gain g >= 0 to mantissa/shift with the smallest shift that keeps
 * the mantissa below 1 (most precision). g >= 2^15 does not fit. */
static bool pi_gain_to_q31(float g, q31_t *p_mant, int32_t *p_shift)
{
    float m = g;
    int32_t s = 0;

    while ((m >= 1.0f) && (s < MC_PI_Q31_MAX_SHIFT)) {
        m = m * 0.5f; /* exact: power of two */
        s++;
    }
    if (m >= 1.0f) {
        return false;
    }
    *p_mant = mc_q31_from_f32(m);
    *p_shift = s;
    return true;
}

uint32_t mc_pi_q31_cfg_from_f32(const mc_pi_f32_cfg_t *cfg, float err_base, float out_base,
                                mc_pi_q31_cfg_t *p_q)
{
    uint32_t err;
    mc_pi_q31_cfg_t q;
    float kp_pu;
    float ki_dt_pu;

    if ((cfg == NULL) || (p_q == NULL)) {
        return MC_PI_ERR_NULL;
    }
    err = mc_pi_f32_validate(cfg);
    if (!(err_base > 0.0f) || !mc_isfinite_f32(err_base) || !(out_base > 0.0f) ||
        !mc_isfinite_f32(out_base)) {
        return err | MC_PI_ERR_SCALE;
    }
    if (err != MC_PI_ERR_NONE) {
        return err;
    }
    kp_pu = (cfg->kp * err_base) / out_base;
    ki_dt_pu = ((cfg->ki_per_s * cfg->dt_s) * err_base) / out_base;
    q.kp_mant = 0;
    q.kp_shift = 0;
    q.ki_dt_mant = 0;
    q.ki_shift = 0;
    if (!pi_gain_to_q31(kp_pu, &q.kp_mant, &q.kp_shift) ||
        !pi_gain_to_q31(ki_dt_pu, &q.ki_dt_mant, &q.ki_shift)) {
        return MC_PI_ERR_SCALE;
    }
    q.out_min = mc_q31_from_f32(cfg->out_min / out_base);
    q.out_max = mc_q31_from_f32(cfg->out_max / out_base);
    q.aw = cfg->aw;
    q.kaw_dt = (cfg->aw == MC_PI_AW_BACK_CALC) ? mc_q31_from_f32(cfg->kaw_per_s * cfg->dt_s) : 0;
    *p_q = q;
    return MC_PI_ERR_NONE;
}
