/**
 * @file mc_pi.c
 * @brief PI controller, float32. Law and anti-windup: see mc_pi.h.
 */
#include "pi/mc_pi.h"

#include <stdbool.h>
#include <stddef.h>

#include "math/mc_math.h"
#include "pi/mc_pi_core.h"

/* ------------------------------------------------------------------------ */
/* float32                                                                   */
/* ------------------------------------------------------------------------ */

static bool pi_gain_ok_f32(float g)
{
    /* !(g >= 0) is true for NaN too. */
    return (g >= 0.0f) && mc_isfinite_f32(g);
}

uint32_t mc_pi_f32_validate(const mc_pi_f32_cfg_t *cfg)
{
    uint32_t err = MC_PI_ERR_NONE;
    bool dt_ok = (cfg->dt_s > 0.0f) && mc_isfinite_f32(cfg->dt_s);

    if (!pi_gain_ok_f32(cfg->kp)) {
        err |= MC_PI_ERR_KP;
    }
    if (!dt_ok) {
        err |= MC_PI_ERR_DT;
    }
    /* ki*dt must not overflow either (only checked with a valid dt). */
    if (!pi_gain_ok_f32(cfg->ki_per_s) || (dt_ok && !mc_isfinite_f32(cfg->ki_per_s * cfg->dt_s))) {
        err |= MC_PI_ERR_KI;
    }
    if (!mc_isfinite_f32(cfg->out_min) || !mc_isfinite_f32(cfg->out_max) ||
        (cfg->out_min > cfg->out_max)) {
        err |= MC_PI_ERR_LIMITS;
    }
    switch (cfg->aw) {
    case MC_PI_AW_CLAMP:
    case MC_PI_AW_NONE:
        break;
    case MC_PI_AW_BACK_CALC:
        /* 0 < kaw*dt <= 1 (the dt part only checked with a valid dt). */
        if (!(cfg->kaw_per_s > 0.0f) || !mc_isfinite_f32(cfg->kaw_per_s) ||
            (dt_ok && !(cfg->kaw_per_s * cfg->dt_s <= 1.0f))) {
            err |= MC_PI_ERR_KAW;
        }
        break;
    default:
        err |= MC_PI_ERR_AW_MODE;
        break;
    }
    return err;
}

uint32_t mc_pi_f32_init(mc_pi_f32_t *st, const mc_pi_f32_cfg_t *cfg)
{
    uint32_t err;

    if ((st == NULL) || (cfg == NULL)) {
        return MC_PI_ERR_NULL;
    }
    err = mc_pi_f32_validate(cfg);
    if (err != MC_PI_ERR_NONE) {
        return err;
    }
    st->kp = cfg->kp;
    st->ki_per_s = cfg->ki_per_s;
    st->ki_dt = cfg->ki_per_s * cfg->dt_s;
    st->kaw_dt = (cfg->aw == MC_PI_AW_BACK_CALC) ? (cfg->kaw_per_s * cfg->dt_s) : 0.0f;
    st->dt_s = cfg->dt_s;
    st->out_min = cfg->out_min;
    st->out_max = cfg->out_max;
    st->aw = cfg->aw;
    /* Start from zero, or from the limit nearest to zero if 0 is outside them. */
    st->integ = mc_sat_f32(0.0f, cfg->out_min, cfg->out_max);
    st->integ_prev = st->integ;
    st->out = st->integ;
    st->last_error = 0.0f;
    st->last_ff = 0.0f;
    st->flags = MC_PI_ERR_NONE;
    return MC_PI_ERR_NONE;
}

uint32_t mc_pi_f32_reset(mc_pi_f32_t *st, float integrator_preset)
{
    float v;

    if (st == NULL) {
        return MC_PI_ERR_NULL;
    }
    if (!mc_isfinite_f32(integrator_preset)) {
        return MC_PI_ERR_NAN_INPUT;
    }
    v = mc_sat_f32(integrator_preset, st->out_min, st->out_max);
    st->integ = v;
    st->integ_prev = v;
    st->out = v;
    st->last_error = 0.0f;
    st->last_ff = 0.0f;
    st->flags = MC_PI_ERR_NONE;
    return MC_PI_ERR_NONE;
}

mc_pi_f32_res_t mc_pi_f32_core_sat(const mc_pi_f32_t *st, float p, float inc, float ff, float lo,
                                   float hi)
{
    mc_pi_f32_res_t r;
    float integ = st->integ + inc;

    if (st->aw == MC_PI_AW_CLAMP) {
        const float u_try = p + integ + ff;
        if ((u_try > hi) && (inc > 0.0f)) {
            /* Integrate only up to the point where the output meets hi, never backwards. */
            const float room = hi - p - ff;
            integ = (room > st->integ) ? room : st->integ;
        } else if ((u_try < lo) && (inc < 0.0f)) {
            const float room = lo - p - ff;
            integ = (room < st->integ) ? room : st->integ;
        } else {
            /* inside the limits, or the error pulls back into range: integrate */
        }
    } else if (st->aw == MC_PI_AW_BACK_CALC) {
        const float u_unsat = p + integ + ff;
        const float u_sat = mc_sat_f32(u_unsat, lo, hi);
        integ = integ + (st->kaw_dt * (u_sat - u_unsat));
    } else {
        /* MC_PI_AW_NONE: plain integration, clamp below only */
    }
    integ = mc_sat_f32(integ, st->out_min, st->out_max);
    r.integ = integ;
    r.u = mc_sat_f32(p + integ + ff, lo, hi);
    return r;
}

uint32_t mc_pi_f32_step_lim(mc_pi_f32_t *st, float error, float ff, float lim_lo, float lim_hi,
                            float *p_out)
{
    float lo;
    float hi;
    float integ;
    float u;

    if ((st == NULL) || (p_out == NULL)) {
        return MC_PI_ERR_NULL;
    }
    /* 0 * (sum) is +-0 when the four are finite (and their sum does not
     * overflow); only then is the test per value skipped. */
    if (((0.0f * (error + ff + lim_lo + lim_hi)) != 0.0f) &&
        (!mc_isfinite_f32(error) || !mc_isfinite_f32(ff) || !mc_isfinite_f32(lim_lo) ||
         !mc_isfinite_f32(lim_hi))) {
        st->flags |= MC_PI_ERR_NAN_INPUT;
        *p_out = st->out;
        return MC_PI_ERR_NAN_INPUT;
    }
    lo = (lim_lo > st->out_min) ? lim_lo : st->out_min;
    hi = (lim_hi < st->out_max) ? lim_hi : st->out_max;
    if (lo > hi) {
        st->flags |= MC_PI_ERR_DYN_LIMIT;
        *p_out = st->out;
        return MC_PI_ERR_DYN_LIMIT;
    }

    /* The arithmetic (anti-windup, clamps) is shared with the FOC's fast
     * path: pi/mc_pi_core.h. */
    u = mc_pi_f32_core(st, error, ff, lo, hi, &integ);

    /* A finite input can still overflow (huge kp*e against an opposite ff):
     * refuse rather than store a NaN. */
    /* Both are clamped to finite limits, so each is finite or NaN: their
     * sum is NaN iff one of them is. */
    if ((integ + u) != (integ + u)) {
        st->flags |= MC_PI_ERR_NAN_INPUT;
        *p_out = st->out;
        return MC_PI_ERR_NAN_INPUT;
    }
    mc_pi_f32_commit(st, error, ff, integ, u);
    *p_out = u;
    return MC_PI_ERR_NONE;
}

uint32_t mc_pi_f32_step_ff(mc_pi_f32_t *st, float error, float ff, float *p_out)
{
    if (st == NULL) {
        return MC_PI_ERR_NULL;
    }
    return mc_pi_f32_step_lim(st, error, ff, st->out_min, st->out_max, p_out);
}

uint32_t mc_pi_f32_step(mc_pi_f32_t *st, float error, float *p_out)
{
    return mc_pi_f32_step_ff(st, error, 0.0f, p_out);
}

uint32_t mc_pi_f32_track(mc_pi_f32_t *st, float applied_out)
{
    float applied;
    float integ;

    if (st == NULL) {
        return MC_PI_ERR_NULL;
    }
    if (!mc_isfinite_f32(applied_out)) {
        st->flags |= MC_PI_ERR_NAN_INPUT;
        return MC_PI_ERR_NAN_INPUT;
    }
    applied = mc_sat_f32(applied_out, st->out_min, st->out_max);
    integ = st->integ;
    if (st->aw == MC_PI_AW_CLAMP) {
        /* Integrator value that puts the last output exactly at applied. */
        float target = applied - (st->kp * st->last_error) - st->last_ff;
        if ((applied < st->out) && (integ > st->integ_prev)) {
            float cut = (target < integ) ? target : integ;
            integ = (cut > st->integ_prev) ? cut : st->integ_prev;
        } else if ((applied > st->out) && (integ < st->integ_prev)) {
            float cut = (target > integ) ? target : integ;
            integ = (cut < st->integ_prev) ? cut : st->integ_prev;
        } else {
            /* the last increment did not push towards the cut: keep it */
        }
    } else if (st->aw == MC_PI_AW_BACK_CALC) {
        integ = integ + (st->kaw_dt * (applied - st->out));
    } else {
        /* MC_PI_AW_NONE */
    }
    integ = mc_sat_f32(integ, st->out_min, st->out_max);
    if (!mc_isfinite_f32(integ)) {
        st->flags |= MC_PI_ERR_NAN_INPUT;
        return MC_PI_ERR_NAN_INPUT;
    }
    st->integ = integ;
    st->out = applied;
    return MC_PI_ERR_NONE;
}

uint32_t mc_pi_f32_set_gains(mc_pi_f32_t *st, float kp, float ki_per_s)
{
    uint32_t err = MC_PI_ERR_NONE;
    float ki_dt;
    float shift;

    if (st == NULL) {
        return MC_PI_ERR_NULL;
    }
    if (!pi_gain_ok_f32(kp)) {
        err |= MC_PI_ERR_KP;
    }
    ki_dt = ki_per_s * st->dt_s;
    if (!pi_gain_ok_f32(ki_per_s) || !mc_isfinite_f32(ki_dt)) {
        err |= MC_PI_ERR_KI;
    }
    if (err != MC_PI_ERR_NONE) {
        return err;
    }
    /* Keep kp*e_last + I unchanged; I is in output units so ki does not enter. */
    shift = (st->kp - kp) * st->last_error;
    st->integ = mc_sat_f32(st->integ + shift, st->out_min, st->out_max);
    st->integ_prev = mc_sat_f32(st->integ_prev + shift, st->out_min, st->out_max);
    st->kp = kp;
    st->ki_per_s = ki_per_s;
    st->ki_dt = ki_dt;
    return MC_PI_ERR_NONE;
}
