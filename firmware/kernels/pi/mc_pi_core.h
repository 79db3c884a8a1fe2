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

/** Branch hint: the common case laid out as the fall-through. */
#if defined(__GNUC__)
#define MC_PI_LIKELY(c) __builtin_expect(!!(c), 1)
#else
#define MC_PI_LIKELY(c) (c)
#endif

/** Always inlined (the FOC's fast path: one frame, values in registers). */
#if defined(__GNUC__)
#define MC_PI_ALWAYS_INLINE static inline __attribute__((always_inline))
#else
#define MC_PI_ALWAYS_INLINE static inline
#endif

/** A step's new integrator and output (returned in two FPU registers). */
typedef struct {
    float integ;
    float u;
} mc_pi_f32_res_t;

/**
 * The saturated (or non-finite) case of mc_pi_f32_core: the anti-windup
 * scheme, the static integrator clamp and the output clamp, from the
 * step's proportional term p and increment inc (mc_pi.c, out of line:
 * run only when a limit acts). Same contract as mc_pi_f32_core.
 */
mc_pi_f32_res_t mc_pi_f32_core_sat(const mc_pi_f32_t *st, float p, float inc, float ff, float lo,
                                   float hi);

/**
 * One step's new integrator (*p_integ) and output (returned) for finite
 * error, ff and limits lo <= hi already intersected with the static limits.
 * Reads st, writes nothing else. The results may still be non-finite (an
 * overflow of kp*e against ff): the caller must check before committing.
 *
 * The common case first: when u = p + (I + inc) + ff is inside [lo, hi]
 * and I + inc inside the static limits, every anti-windup scheme takes the
 * whole increment and no clamp acts, so (I + inc, u) is the result. (The
 * back-calculation term kaw*dt*(u_sat - u) is then exactly +0 and is not
 * added: an integrator of -0 stays -0.) Every other case goes to
 * mc_pi_f32_core_sat, which starts again from p and inc.
 */
static inline float mc_pi_f32_core(const mc_pi_f32_t *st, float error, float ff, float lo, float hi,
                                   float *p_integ)
{
    const float p = st->kp * error;
    const float inc = st->ki_dt * error;
    const float integ = st->integ + inc;
    const float u = (p + integ) + ff;

    if ((u <= hi) && (u >= lo) && (integ <= st->out_max) && (integ >= st->out_min)) {
        *p_integ = integ;
        return u;
    }
    {
        const mc_pi_f32_res_t r = mc_pi_f32_core_sat(st, p, inc, ff, lo, hi);
        *p_integ = r.integ;
        return r.u;
    }
}

/**
 * mc_pi_f32_core for the clamping scheme (st->aw == MC_PI_AW_CLAMP: the
 * caller guarantees it; the FOC's fast path runs only then) and symmetric
 * limits inside the static ones: dynamic limits -lim, lim with
 * 0 <= lim <= out_max on a state whose static limits are symmetric
 * (out_min = -out_max, as the FOC's init makes them), so that the step's
 * limits are -lim, lim (the checked step's max(-lim, out_min),
 * min(lim, out_max)). The caller guarantees lim <= out_max (the FOC bounds
 * the bus voltage for that). The common-case test on magnitudes (|u| <= lim,
 * |I + inc| <= out_max: two compares; |u| <= out_max follows) has the same
 * outcome as mc_pi_f32_core's. Returns false, with nothing written, when
 * the error or feed-forward is not finite or the step overflows: the
 * caller then runs the checked mc_pi_f32_step_lim, which decides (it
 * refuses a non-finite input and gives the same bits otherwise).
 */
MC_PI_ALWAYS_INLINE bool mc_pi_f32_core_in(const mc_pi_f32_t *st, float error, float ff, float lim,
                                           float *p_integ, float *p_u)
{
    const float p = st->kp * error;
    const float inc = st->ki_dt * error;
    const float integ = st->integ + inc;
    const float u = (p + integ) + ff;

    /* NaN fails both tests; so does an infinite error or ff (it makes u
     * infinite or NaN whatever kp is). */
    if (MC_PI_LIKELY((mc_fabs_f32(u) <= lim) && (mc_fabs_f32(integ) <= st->out_max))) {
        *p_integ = integ;
        *p_u = u;
        return true;
    }
    /* |u| as bits: at least those of inf for a non-finite u, which a
     * non-finite error or ff makes (and an overflow, which the checked
     * step then takes). A finite u means finite p, I + inc and ff, so
     * nothing below is NaN. */
    union {
        float f;
        uint32_t b;
    } abs_u;
    abs_u.f = mc_fabs_f32(u);
    if (abs_u.b >= 0x7F800000u) {
        return false;
    }
    /* mc_pi_f32_core_sat's clamping branch and clamps with lo = -lim,
     * hi = lim, the very same operations, with the compares whose
     * outcome is known left out: the stored integrator I lies in
     * [-out_max, out_max]; inc > 0 gives I + inc >= I (rounding is
     * monotonic), so max(room, I) and I + inc need only their upper
     * clamp, and inc <= 0 their lower one. */
    const float i0 = st->integ;
    const float out_max = st->out_max;
    float i2;
    float w;
    if (u > lim) {
        if (inc > 0.0f) {
            const float room = (lim - p) - ff;
            i2 = (room > i0) ? ((room > out_max) ? out_max : room) : i0;
        } else if (integ >= -out_max) {
            /* The error pulls back and I + inc needs no clamp: the
             * output (p + (I + inc)) + ff is u again, above lim. */
            *p_integ = integ;
            *p_u = lim;
            return true;
        } else {
            i2 = -out_max;
        }
    } else if (u < -lim) {
        if (inc < 0.0f) {
            const float room = (-lim - p) - ff;
            i2 = (room < i0) ? ((room < -out_max) ? -out_max : room) : i0;
        } else if (integ <= out_max) {
            /* as above, on the other side */
            *p_integ = integ;
            *p_u = -lim;
            return true;
        } else {
            i2 = out_max;
        }
    } else {
        /* |u| <= lim with |I + inc| > out_max */
        i2 = mc_sat_f32(integ, -out_max, out_max);
    }
    w = (p + i2) + ff; /* may overflow to +-inf: clamped as in the checked step */
    *p_integ = i2;
    *p_u = (w > lim) ? lim : ((w < -lim) ? -lim : w);
    return true;
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
