/**
 * @file mc_pi_core.h
 * @brief Internal to the kernels (not a public API): the arithmetic of one
 *        float PI step, split from its checks and its commit so that
 *        mc_pi_f32_step_lim() and the FOC's fast path (foc/mc_foc.c) run the
 *        very same operations and give the same bits. Law and anti-windup:
 *        pi/mc_pi.h.
 */
#ifndef MC_PI_CORE_H
#define MC_PI_CORE_H

#include "math/mc_math.h"
#include "pi/mc_pi.h"

#ifdef __cplusplus
extern "C" {
#endif

/**
 * One step's new integrator (*p_integ) and output (returned) for finite
 * error, ff and limits lo <= hi already intersected with the static limits.
 * Reads st, writes nothing else. The results may still be non-finite (an
 * overflow of kp*e against ff): the caller must check before committing.
 */
static inline float mc_pi_f32_core(const mc_pi_f32_t *st, float error, float ff, float lo,
                                   float hi, float *p_integ)
{
    const float p = st->kp * error;
    const float inc = st->ki_dt * error;
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
    *p_integ = integ;
    return mc_sat_f32(p + integ + ff, lo, hi);
}

/** Store an accepted step (finite integ and u). */
static inline void mc_pi_f32_commit(mc_pi_f32_t *st, float error, float ff, float integ, float u)
{
    st->integ_prev = st->integ;
    st->integ = integ;
    st->out = u;
    st->last_error = error;
    st->last_ff = ff;
}

#ifdef __cplusplus
}
#endif

#endif /* MC_PI_CORE_H */
