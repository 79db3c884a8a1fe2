/**
 * @file mc_svpwm_q31.c
 * @brief Space-vector PWM by min-max zero-sequence injection, q31 twin of
 *        mc_svpwm.c: the phase voltages in a 64-bit Q2.62 accumulator, one
 *        division per phase (scaling and error bound: mc_svpwm_q31.h).
 */
#include "transforms/mc_svpwm_q31.h"

#include <stdbool.h>
#include <stddef.h>

#include "math/mc_math.h"
#include "math/mc_q31.h"
#include "transforms/mc_svpwm_core.h"

/** sqrt(3) in Q30: round(2^30 * sqrt(3)). */
#define MC_SVPWM_SQRT3_Q30 ((int64_t)1859775393)

/** Duty 0.5 in q31. */
#define MC_SVPWM_HALF_Q31 ((q31_t)0x40000000)

/**
 * Square root of a 64-bit unsigned integer, rounded to nearest: bit-by-bit
 * (two result bits per step, 32 steps at most), exact, no float, so the
 * result is identical on every target. mc_sqrt_q31 takes a q31 in [0, 1) and
 * the sum of squares here reaches 2 in Q2.62, hence a local helper.
 */
static uint64_t mc_svpwm_isqrt_round_u64(uint64_t x)
{
    uint64_t rem;
    uint64_t root = mc_isqrt_u64(x, &rem);
    /* Here x = root^2 + rem; (root + 1/2)^2 = root^2 + root + 1/4. */
    if (rem > root) {
        root += 1u;
    }
    return root;
}

/** n / d rounded to nearest, ties away from zero; requires d > 0 and
 *  |n| + d / 2 below 2^63. */
static int64_t mc_svpwm_div_round_s64(int64_t n, int64_t d)
{
    if (n >= 0) {
        return (n + d / 2) / d;
    }
    return -((-n + d / 2) / d);
}

static int64_t mc_svpwm_max3_s64(int64_t a, int64_t b, int64_t c)
{
    int64_t m = (a > b) ? a : b;
    return (m > c) ? m : c;
}

static int64_t mc_svpwm_min3_s64(int64_t a, int64_t b, int64_t c)
{
    int64_t m = (a < b) ? a : b;
    return (m < c) ? m : c;
}

/** 1/2 + offset in q31, saturated to the duty range [0, MC_Q31_MAX]. */
static q31_t mc_svpwm_duty_q31(int64_t offset_q31)
{
    int64_t duty = (int64_t)MC_SVPWM_HALF_Q31 + offset_q31;
    if (duty < 0) {
        return 0;
    }
    return mc_q31_sat64(duty);
}

uint32_t mc_svpwm_q31(q31_t v_alpha_pu, q31_t v_beta_pu, q31_t vbus_pu, mc_svpwm_limit_t limit,
                      q31_t *p_duty_a, q31_t *p_duty_b, q31_t *p_duty_c)
{
    if ((p_duty_a == NULL) || (p_duty_b == NULL) || (p_duty_c == NULL)) {
        return MC_SVPWM_FLAG_BAD_INPUT;
    }
    uint32_t flags = MC_SVPWM_FLAG_NONE;
    if (vbus_pu <= 0) {
        flags |= MC_SVPWM_FLAG_BAD_VBUS;
    }
    if (!mc_svpwm_limit_ok(limit)) {
        flags |= MC_SVPWM_FLAG_BAD_INPUT;
    }
    if (flags != MC_SVPWM_FLAG_NONE) {
        *p_duty_a = MC_SVPWM_HALF_Q31;
        *p_duty_b = MC_SVPWM_HALF_Q31;
        *p_duty_c = MC_SVPWM_HALF_Q31;
        return flags;
    }

    /* Phase voltages (inverse Clarke) in Q2.62: |alpha| * 2^62 <= 2^62,
     * |beta * sqrt(3)/2| + |alpha / 2| <= 1.37 * 2^62. */
    int64_t half_alpha_q62 = (int64_t)v_alpha_pu * ((int64_t)1 << 30);
    int64_t beta_term_q62 = (int64_t)v_beta_pu * MC_TRANSFORMS_SQRT3_2_Q31;
    int64_t va_q62 = 2 * half_alpha_q62;
    int64_t vb_q62 = beta_term_q62 - half_alpha_q62;
    int64_t vc_q62 = -beta_term_q62 - half_alpha_q62;

    int64_t vmax_q62 = mc_svpwm_max3_s64(va_q62, vb_q62, vc_q62);
    int64_t vmin_q62 = mc_svpwm_min3_s64(va_q62, vb_q62, vc_q62);
    /* The phase voltages sum to zero, so vmax >= 0 >= vmin and the sum
     * cannot overflow; the shift floors (error 2^-62). */
    int64_t mid_q62 = (vmax_q62 + vmin_q62) >> 1;
    /* Half the largest line-to-line voltage, <= sqrt(3/2) * 2^62 (|v| <= sqrt(2)). */
    int64_t half_spread_q62 = vmax_q62 - mid_q62;

    int64_t measure_q31;
    if (limit == MC_SVPWM_LIMIT_CIRCLE) {
        /* |v|^2 in Q2.62: each square is at most 2^62, the sum at most 2^63. */
        uint64_t mag2_q62 = (uint64_t)((int64_t)v_alpha_pu * (int64_t)v_alpha_pu) +
                            (uint64_t)((int64_t)v_beta_pu * (int64_t)v_beta_pu);
        /* sqrt of Q2.62 is Q1.31; at most 3.04e9, times sqrt(3) Q30 < 5.7e18. */
        int64_t mag_q31 = (int64_t)mc_svpwm_isqrt_round_u64(mag2_q62);
        measure_q31 = (mag_q31 * MC_SVPWM_SQRT3_Q30 + ((int64_t)1 << 29)) >> 30;
    } else {
        /* (max - min) in Q31 = half_spread_q62 / 2^30, rounded. */
        measure_q31 = (half_spread_q62 + ((int64_t)1 << 29)) >> 30;
    }
    int64_t den_q31 = (int64_t)vbus_pu;
    if (measure_q31 > den_q31) {
        den_q31 = measure_q31;
        flags |= MC_SVPWM_FLAG_LIMITED;
    }

    /* offset = (v_x - mid) / D: Q2.62 / Q31 gives Q31. |v_x - mid| is at
     * most half_spread, below 1.23 * 2^62, so the rounding cannot overflow. */
    *p_duty_a = mc_svpwm_duty_q31(mc_svpwm_div_round_s64(va_q62 - mid_q62, den_q31));
    *p_duty_b = mc_svpwm_duty_q31(mc_svpwm_div_round_s64(vb_q62 - mid_q62, den_q31));
    *p_duty_c = mc_svpwm_duty_q31(mc_svpwm_div_round_s64(vc_q62 - mid_q62, den_q31));
    return flags;
}
