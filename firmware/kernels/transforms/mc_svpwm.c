/**
 * @file mc_svpwm.c
 * @brief Space-vector PWM by min-max zero-sequence injection, f32 (the q31
 *        twin is mc_svpwm_q31.c).
 *
 * Both twins compute d_x = 1/2 + (v_x - mid) / D with D = max(vbus, L) as
 * described in mc_svpwm.h; they differ only in arithmetic. The float twin
 * first divides everything by k = max(vbus, |v_alpha|, |v_beta|), so every
 * intermediate is at most about 2.5 in magnitude and no finite request can
 * overflow (the duties do not depend on k). The q31 twin keeps the phase
 * voltages in a 64-bit Q2.62 accumulator and divides once per phase.
 */
#include "transforms/mc_svpwm.h"

#include <stdbool.h>
#include <stddef.h>

#include "math/mc_math.h"
#include "transforms/mc_svpwm_core.h"
#include "transforms/mc_transforms.h"

/** Keeps a rarely taken path out of line (its stack frame and saved
 *  registers then cost nothing on the common path). */
#if defined(__GNUC__)
#define MC_SVPWM_NOINLINE __attribute__((noinline))
#else
#define MC_SVPWM_NOINLINE
#endif

/* ------------------------------------------------------------------ f32 */

/** Everything the f32 modulator derives from one request, normalised by k. */
typedef struct {
    float phase_n[3]; /* va, vb, vc divided by k */
    float mid_n;      /* (max + min) / 2 of the phase voltages, divided by k */
    float den_n;      /* D = max(vbus, L), divided by k */
    float vbus_n;     /* vbus divided by k */
} mc_svpwm_solution_f32_t;

static float mc_svpwm_max3_f32(float a, float b, float c)
{
    float m = (a > b) ? a : b;
    return (m > c) ? m : c;
}

static float mc_svpwm_min3_f32(float a, float b, float c)
{
    float m = (a < b) ? a : b;
    return (m < c) ? m : c;
}

/** Validate and solve one request; the solution is valid only if the
 *  returned flags hold neither BAD_VBUS nor BAD_INPUT. */
static inline uint32_t mc_svpwm_solve_f32(float v_alpha_v, float v_beta_v, float vbus_v,
                                          mc_svpwm_limit_t limit, mc_svpwm_solution_f32_t *p_sol)
{
    uint32_t flags = MC_SVPWM_FLAG_NONE;
    if (!mc_isfinite_f32(vbus_v) || (vbus_v <= 0.0f)) {
        flags |= MC_SVPWM_FLAG_BAD_VBUS;
    }
    if (!mc_isfinite_f32(v_alpha_v) || !mc_isfinite_f32(v_beta_v) || !mc_svpwm_limit_ok(limit)) {
        flags |= MC_SVPWM_FLAG_BAD_INPUT;
    }
    if (flags != MC_SVPWM_FLAG_NONE) {
        return flags;
    }

    /* k > 0 because vbus > 0; every normalised input is in [-1, 1]. */
    float k = vbus_v;
    float abs_alpha = mc_abs_f32(v_alpha_v);
    float abs_beta = mc_abs_f32(v_beta_v);
    if (abs_alpha > k) {
        k = abs_alpha;
    }
    if (abs_beta > k) {
        k = abs_beta;
    }
    /* Divisions, not a product with 1/k: 1/k is subnormal for k above
     * 8.5e37 (and flushed to zero where the FPU flushes denormals), while
     * x / k with |x| <= k is always in [-1, 1]. vbus_n may underflow to 0:
     * see below. */
    float alpha_n = v_alpha_v / k;
    float beta_n = v_beta_v / k;
    p_sol->vbus_n = vbus_v / k;

    mc_inv_clarke_f32(alpha_n, beta_n, &p_sol->phase_n[0], &p_sol->phase_n[1], &p_sol->phase_n[2]);
    float vmax = mc_svpwm_max3_f32(p_sol->phase_n[0], p_sol->phase_n[1], p_sol->phase_n[2]);
    float vmin = mc_svpwm_min3_f32(p_sol->phase_n[0], p_sol->phase_n[1], p_sol->phase_n[2]);
    /* mid as the linear case forms it (mc_svpwm_core.h) */
    p_sol->mid_n = 0.5f * (vmax + vmin);

    float measure_n;
    if (limit == MC_SVPWM_LIMIT_CIRCLE) {
        float mag2_n = alpha_n * alpha_n + beta_n * beta_n;
        if ((p_sol->vbus_n == 1.0f) && (mag2_n < MC_SVPWM_LINEAR_MAG2)) {
            /* Shortcut, same result: here |v| < 0.5745 vbus (rounding
             * included), so sqrt(3) |v| <= 0.9951 vbus is inside the circle
             * and the rounded measure below would not exceed vbus_n = 1
             * either; the measure is not used when not limited. vbus_n is
             * exactly 1 whenever |v_alpha|, |v_beta| <= vbus (k = vbus), the
             * current controller's case. */
            p_sol->den_n = 1.0f;
            return flags;
        }
        measure_n = MC_SQRT3_F32 * mc_sqrt_f32(mag2_n);
    } else {
        measure_n = vmax - vmin;
    }
    p_sol->den_n = p_sol->vbus_n;
    if (measure_n > p_sol->vbus_n) {
        /* If vbus_n underflowed to 0 the request is nonzero (|alpha_n| or
         * |beta_n| is 1), so measure_n > 0 and den_n stays positive. */
        p_sol->den_n = measure_n;
        flags |= MC_SVPWM_FLAG_LIMITED;
    }
    return flags;
}

/**
 * The circle limit with vbus finite and > 0 and |v_alpha|, |v_beta| <= vbus
 * (every request of a current controller, limited or not): the case of
 * mc_svpwm_circle_kv_f32. A NaN fails every comparison: the voltage tests
 * also rule out NaN and infinite voltages once vbus is known finite.
 */
static inline bool mc_svpwm_circle_kv_case(float v_alpha_v, float v_beta_v, float vbus_v,
                                           mc_svpwm_limit_t limit)
{
    return (limit == MC_SVPWM_LIMIT_CIRCLE) && (vbus_v > 0.0f) && (vbus_v <= 3.40282347e38f) &&
           (mc_fabs_f32(v_alpha_v) <= vbus_v) && (mc_fabs_f32(v_beta_v) <= vbus_v);
}

/**
 * mc_svpwm_circle_kv_case on its own: then k = vbus and vbus_n = vbus /
 * vbus = 1 exactly, and the general solution (mc_svpwm_solve_f32,
 * mc_svpwm_duties_f32) reduces to the operations below, the very same ones
 * on the same values, so the results are bit-identical; the checks, the
 * normalisation of vbus and the solution struct are left out. Inside
 * MC_SVPWM_LINEAR_MAG2 the linear case (mc_svpwm_core.h); beyond it the
 * measure sqrt(3) |v_n| and, only when it exceeds 1, the division by it.
 * Writes the duties and *p_den (D / vbus), returns MC_SVPWM_FLAG_NONE or
 * _LIMITED. Calls nothing (the square root of a sum of squares is the FPU
 * instruction mc_sqrt_f32 would run).
 */
static inline uint32_t mc_svpwm_circle_kv_f32(float v_alpha_v, float v_beta_v, float vbus_v,
                                              float *p_duty_a, float *p_duty_b, float *p_duty_c,
                                              float *p_den)
{
    const float alpha_n = v_alpha_v / vbus_v;
    const float beta_n = v_beta_v / vbus_v;
    *p_den = 1.0f;
    /* the solver's shortcut test and the duties it leads to:
     * transforms/mc_svpwm_core.h */
    if (mc_svpwm_circle_linear_f32(alpha_n, beta_n, p_duty_a, p_duty_b, p_duty_c)) {
        return MC_SVPWM_FLAG_NONE;
    }
    float phase[3];
    mc_inv_clarke_f32(alpha_n, beta_n, &phase[0], &phase[1], &phase[2]);
    const float vmax = mc_svpwm_max3_f32(phase[0], phase[1], phase[2]);
    const float vmin = mc_svpwm_min3_f32(phase[0], phase[1], phase[2]);
    const float mid = 0.5f * (vmax + vmin);
    const float measure =
        MC_SQRT3_F32 * mc_sqrt_nonneg_f32((alpha_n * alpha_n) + (beta_n * beta_n));
    uint32_t flags = MC_SVPWM_FLAG_NONE;
    float den = 1.0f;
    if (measure > 1.0f) {
        den = measure;
        flags = MC_SVPWM_FLAG_LIMITED;
    }
    const float inv_den = 1.0f / den;
    const float off = 0.5f - (mid * inv_den);
    *p_duty_a = mc_sat_f32((phase[0] * inv_den) + off, 0.0f, 1.0f);
    *p_duty_b = mc_sat_f32((phase[1] * inv_den) + off, 0.0f, 1.0f);
    *p_duty_c = mc_sat_f32((phase[2] * inv_den) + off, 0.0f, 1.0f);
    *p_den = den;
    return flags;
}

/** The duties of a valid solution. */
static inline void mc_svpwm_duties_f32(const mc_svpwm_solution_f32_t *p_sol, float *p_duty_a,
                                       float *p_duty_b, float *p_duty_c)
{
    float inv_den = 1.0f / p_sol->den_n;
    /* d_x = 1/2 + (v_x - mid) / D = v_x / D + off, off = 1/2 - mid / D
     * (one offset for the three phases). Rounding can leave a duty a few
     * ulp outside [0, 1] on the boundary. */
    float off = 0.5f - (p_sol->mid_n * inv_den);
    *p_duty_a = mc_sat_f32((p_sol->phase_n[0] * inv_den) + off, 0.0f, 1.0f);
    *p_duty_b = mc_sat_f32((p_sol->phase_n[1] * inv_den) + off, 0.0f, 1.0f);
    *p_duty_c = mc_sat_f32((p_sol->phase_n[2] * inv_den) + off, 0.0f, 1.0f);
}

static bool mc_svpwm_bad_f32(uint32_t flags)
{
    return (flags & (MC_SVPWM_FLAG_BAD_VBUS | MC_SVPWM_FLAG_BAD_INPUT)) != 0u;
}

/* The general modulator (every request), out of line so that the linear
 * case's call stays light. */
static MC_SVPWM_NOINLINE uint32_t mc_svpwm_general_f32(float v_alpha_v, float v_beta_v,
                                                       float vbus_v, mc_svpwm_limit_t limit,
                                                       float *p_duty_a, float *p_duty_b,
                                                       float *p_duty_c)
{
    mc_svpwm_solution_f32_t sol;
    uint32_t flags = mc_svpwm_solve_f32(v_alpha_v, v_beta_v, vbus_v, limit, &sol);
    if (mc_svpwm_bad_f32(flags)) {
        *p_duty_a = 0.5f;
        *p_duty_b = 0.5f;
        *p_duty_c = 0.5f;
        return flags;
    }
    mc_svpwm_duties_f32(&sol, p_duty_a, p_duty_b, p_duty_c);
    return flags;
}

uint32_t mc_svpwm_f32(float v_alpha_v, float v_beta_v, float vbus_v, mc_svpwm_limit_t limit,
                      float *p_duty_a, float *p_duty_b, float *p_duty_c)
{
    if ((p_duty_a == NULL) || (p_duty_b == NULL) || (p_duty_c == NULL)) {
        return MC_SVPWM_FLAG_BAD_INPUT;
    }
    if (!mc_svpwm_circle_kv_case(v_alpha_v, v_beta_v, vbus_v, limit)) {
        return mc_svpwm_general_f32(v_alpha_v, v_beta_v, vbus_v, limit, p_duty_a, p_duty_b,
                                    p_duty_c);
    }
    float den;
    return mc_svpwm_circle_kv_f32(v_alpha_v, v_beta_v, vbus_v, p_duty_a, p_duty_b, p_duty_c, &den);
}

/* mc_svpwm_limit_duty_f32 for every request, out of line (see above). */
static MC_SVPWM_NOINLINE uint32_t mc_svpwm_limit_duty_general_f32(float *p_v_alpha_v,
                                                                  float *p_v_beta_v, float vbus_v,
                                                                  mc_svpwm_limit_t limit,
                                                                  float *p_duty_a, float *p_duty_b,
                                                                  float *p_duty_c)
{
    mc_svpwm_solution_f32_t sol;
    uint32_t flags = mc_svpwm_solve_f32(*p_v_alpha_v, *p_v_beta_v, vbus_v, limit, &sol);
    if (mc_svpwm_bad_f32(flags)) {
        /* mc_svpwm_limit_f32 zeroes the vector; the modulator then gives
         * 0.5 for a zero vector as for a bad one. */
        *p_v_alpha_v = 0.0f;
        *p_v_beta_v = 0.0f;
        *p_duty_a = 0.5f;
        *p_duty_b = 0.5f;
        *p_duty_c = 0.5f;
        return flags;
    }
    if ((flags & MC_SVPWM_FLAG_LIMITED) != 0u) {
        /* As mc_svpwm_limit_f32, then the modulator on the limited vector
         * (a new solution: the scaled vector is normalised anew). */
        float scale = sol.vbus_n / sol.den_n;
        *p_v_alpha_v *= scale;
        *p_v_beta_v *= scale;
        return flags | mc_svpwm_general_f32(*p_v_alpha_v, *p_v_beta_v, vbus_v, limit, p_duty_a,
                                            p_duty_b, p_duty_c);
    }
    /* Not limited: the modulator's solution for the unchanged vector is
     * this one. */
    mc_svpwm_duties_f32(&sol, p_duty_a, p_duty_b, p_duty_c);
    return flags;
}

uint32_t mc_svpwm_limit_duty_f32(float *p_v_alpha_v, float *p_v_beta_v, float vbus_v,
                                 mc_svpwm_limit_t limit, float *p_duty_a, float *p_duty_b,
                                 float *p_duty_c)
{
    if ((p_v_alpha_v == NULL) || (p_v_beta_v == NULL) || (p_duty_a == NULL) || (p_duty_b == NULL) ||
        (p_duty_c == NULL)) {
        return MC_SVPWM_FLAG_BAD_INPUT;
    }
    if (!mc_svpwm_circle_kv_case(*p_v_alpha_v, *p_v_beta_v, vbus_v, limit)) {
        return mc_svpwm_limit_duty_general_f32(p_v_alpha_v, p_v_beta_v, vbus_v, limit, p_duty_a,
                                               p_duty_b, p_duty_c);
    }
    float den;
    const uint32_t flags = mc_svpwm_circle_kv_f32(*p_v_alpha_v, *p_v_beta_v, vbus_v, p_duty_a,
                                                  p_duty_b, p_duty_c, &den);
    if (flags == MC_SVPWM_FLAG_NONE) {
        return MC_SVPWM_FLAG_NONE; /* inside the limit: the vector stays */
    }
    {
        /* As mc_svpwm_limit_f32 (scale vbus_n / den_n = 1 / den), then the
         * modulator on the limited vector (a new solution, which is again
         * this function's case: the scaled vector is shorter). */
        const float scale = 1.0f / den;
        *p_v_alpha_v *= scale;
        *p_v_beta_v *= scale;
        return flags |
               mc_svpwm_f32(*p_v_alpha_v, *p_v_beta_v, vbus_v, limit, p_duty_a, p_duty_b, p_duty_c);
    }
}

uint32_t mc_svpwm_limit_f32(float *p_v_alpha_v, float *p_v_beta_v, float vbus_v,
                            mc_svpwm_limit_t limit)
{
    if ((p_v_alpha_v == NULL) || (p_v_beta_v == NULL)) {
        return MC_SVPWM_FLAG_BAD_INPUT;
    }
    mc_svpwm_solution_f32_t sol;
    uint32_t flags = mc_svpwm_solve_f32(*p_v_alpha_v, *p_v_beta_v, vbus_v, limit, &sol);
    if (mc_svpwm_bad_f32(flags)) {
        *p_v_alpha_v = 0.0f;
        *p_v_beta_v = 0.0f;
        return flags;
    }
    if ((flags & MC_SVPWM_FLAG_LIMITED) != 0u) {
        /* Dividing the duties' offsets by D is scaling the request by
         * vbus / D (< 1); the ratio of normalised values is that ratio. */
        float scale = sol.vbus_n / sol.den_n;
        *p_v_alpha_v *= scale;
        *p_v_beta_v *= scale;
    }
    return flags;
}

float mc_svpwm_max_voltage_f32(float vbus_v, mc_svpwm_limit_t limit)
{
    if (!mc_isfinite_f32(vbus_v) || (vbus_v <= 0.0f)) {
        return 0.0f;
    }
    if (limit == MC_SVPWM_LIMIT_CIRCLE) {
        return vbus_v * MC_INV_SQRT3_F32;
    }
    if (limit == MC_SVPWM_LIMIT_HEXAGON) {
        return vbus_v * (2.0f / 3.0f);
    }
    return 0.0f;
}
