/**
 * @file mc_q31.c
 * @brief Fixed-point helpers: conversions, sin/cos, atan2, sqrt in q31.
 *
 * Integer-only kernels (sincos, atan2, sqrt) use int64 accumulators and are
 * bit-identical on every target. Right shifts of negative values go through
 * asr64(), which is floor division by a power of two written with defined
 * operations only.
 */
#include "math/mc_q31.h"

#include <stddef.h>

#include "math/mc_math.h"

/* ---------------------------------------------------------------- helpers */

/** floor(v / 2^n), n in [0, 63], without right-shifting a negative value. */
static int64_t asr64(int64_t v, uint32_t n)
{
    if (v >= 0) {
        return v >> n;
    }
    return ~((~v) >> n);
}

/** round(v / 2^n), ties towards +inf, n in [1, 62]. */
static int64_t rshift_round(int64_t v, uint32_t n)
{
    return asr64(v + ((int64_t)1 << (n - 1u)), n);
}

/** uint32 to int32 two's complement (modular), written without
 * implementation-defined conversion. */
static int32_t i32_from_u32(uint32_t u)
{
    if (u <= 0x7FFFFFFFu) {
        return (int32_t)u;
    }
    return -(int32_t)(~u) - 1;
}

/**
 * round(x * 2^frac_bits) to nearest, ties away from zero, saturated to
 * [lo, hi]; NaN gives 0. The float is compared against the bounds before
 * any conversion, so the conversion only ever sees |v| < 2^31.
 */
static int32_t fixed_from_f32(float x, float scale, int32_t lo, int32_t hi)
{
    if (x != x) {
        return 0;
    }
    float v = x * scale;      /* power of two: exact unless it overflows to inf */
    if (v >= 2147483648.0f) { /* 2^31: out of range (2^31 - 128 is the largest float below) */
        return hi;
    }
    if (v <= -2147483648.0f) {
        return lo;
    }
    int32_t t = (int32_t)v; /* truncation, in range */
    float d = v - (float)t; /* exact: |v| < 2^24 or v is an integer */
    int64_t r = t;
    if (d >= 0.5f) {
        r += 1;
    } else if (d <= -0.5f) {
        r -= 1;
    } else {
        /* already nearest */
    }
    if (r > hi) {
        return hi;
    }
    if (r < lo) {
        return lo;
    }
    return (int32_t)r;
}

/* ------------------------------------------------------------ conversions */

q31_t mc_q31_from_f32(float x)
{
    return fixed_from_f32(x, 2147483648.0f, MC_Q31_MIN, MC_Q31_MAX);
}

float mc_q31_to_f32(q31_t x)
{
    return (float)x * 4.65661287307739258e-10f; /* 2^-31, exact scaling */
}

q15_t mc_q15_from_f32(float x)
{
    return (q15_t)fixed_from_f32(x, 32768.0f, MC_Q15_MIN, MC_Q15_MAX);
}

q31_t mc_q31_angle_from_rad_f32(float x_rad)
{
    uint64_t turn = 0u;
    if (!mc_turn_from_rad_f32(x_rad, &turn)) {
        return 0;
    }
    /* Q0.64 turn to Q0.32 turn, rounded, modulo one turn. */
    uint64_t rounded = turn + ((uint64_t)1 << 31);
    return i32_from_u32((uint32_t)(rounded >> 32));
}

float mc_q31_angle_to_rad_f32(q31_t angle)
{
    /* pi / 2^31 rounded to float; the int32 to float conversion and the
     * product are each rounded once. */
    float r = (float)angle * 1.46291812e-09f;
    if (r >= MC_PI_F32) {
        r = -MC_PI_F32; /* angles within float rounding of +pi are -pi */
    }
    return r;
}

/* ----------------------------------------------------------------- sincos */

/*
 * Polynomials in t = fraction of a quarter turn, |t| <= 1/2, coefficients
 * Q2.30 (own Chebyshev-node fit; error with the Q2.30 coefficients, exact
 * evaluation, < 0.03 LSB of q31):
 *   sin(pi/2 t) = t * (A0 + A1 t^2 + ... + A5 t^10)
 *   cos(pi/2 t) = B0 + B1 t^2 + ... + B6 t^12
 */
static const int64_t k_sin_q30[6] = {
    1686629713, -693598668, 85569306, -5026994, 172260, -3819,
};
static const int64_t k_cos_q30[7] = {
    1073741824, -1324675879, 272375560, -22401992, 987048, -27058, 500,
};

void mc_sincos_q31(q31_t angle, q31_t *p_sin, q31_t *p_cos)
{
    /* Nearest quarter turn q and the remainder in [-1/8, 1/8) turn. */
    uint32_t u = (uint32_t)angle;
    uint32_t q = ((u + 0x20000000u) >> 30) & 3u;
    uint32_t rem_u = u - (q << 30);
    int64_t rem = i32_from_u32(rem_u);   /* [-2^29, 2^29) */
    int64_t t = rem * 2;                 /* t in Q31, |t| <= 2^30 */
    int64_t v = rshift_round(t * t, 31); /* t^2 in Q31, <= 2^29 */

    int64_t ps = k_sin_q30[5];
    for (int i = 4; i >= 0; --i) {
        ps = k_sin_q30[i] + rshift_round(ps * v, 31);
    }
    int64_t s = rshift_round(ps * t, 31); /* Q30 */
    int64_t pc = k_cos_q30[6];
    for (int i = 5; i >= 0; --i) {
        pc = k_cos_q30[i] + rshift_round(pc * v, 31);
    }
    int64_t c = pc; /* Q30 */

    int64_t so;
    int64_t co;
    switch (q) {
    case 0u:
        so = s;
        co = c;
        break;
    case 1u:
        so = c;
        co = -s;
        break;
    case 2u:
        so = -s;
        co = -c;
        break;
    default:
        so = -c;
        co = s;
        break;
    }
    /* Q30 -> Q31; +1 saturates to MC_Q31_MAX, -1 is exact. */
    *p_sin = mc_q31_sat64(so * 2);
    *p_cos = mc_q31_sat64(co * 2);
}

/* ------------------------------------------------------------------ atan2 */

/* atan(2^-i) / (2*pi) in units of 2^-40 turn (q31 angle LSB / 256). */
#define CORDIC_STEPS 34
static const int64_t k_cordic_atan[CORDIC_STEPS] = {
    137438953472, 81134951838, 42869480287, 21761217566, 10922836750, 5466743129, 2734038620,
    1367102738,   683561799,   341782203,   170891265,   85445653,    42722829,   21361415,
    10680707,     5340354,     2670177,     1335088,     667544,      333772,     166886,
    83443,        41722,       20861,       10430,       5215,        2608,       1304,
    652,          326,         163,         81,          41,          20,
};

q31_t mc_atan2_q31(q31_t y, q31_t x)
{
    if ((x == 0) && (y == 0)) {
        return 0;
    }
    int64_t xx = x;
    int64_t yy = y;
    /* Normalise: the larger magnitude into [2^59, 2^60): full resolution
     * for small inputs, headroom for the CORDIC gain 1.65 and sqrt(2). */
    int64_t ax = (xx < 0) ? -xx : xx;
    int64_t ay = (yy < 0) ? -yy : yy;
    int64_t mag = (ax > ay) ? ax : ay;
    int64_t scale = 1;
    while (mag < ((int64_t)1 << 59)) {
        mag *= 2;
        scale *= 2;
    }
    xx *= scale;
    yy *= scale;

    /* Into the right half plane by a quarter-turn rotation. */
    const int64_t quarter = (int64_t)1 << 38;
    int64_t z = 0;
    if (xx < 0) {
        int64_t tmp = xx;
        if (yy >= 0) {
            xx = yy; /* rotate by -90 degrees */
            yy = -tmp;
            z = quarter;
        } else {
            xx = -yy; /* rotate by +90 degrees */
            yy = tmp;
            z = -quarter;
        }
    }
    /* Vectoring: drive y to 0, accumulating the rotation. */
    for (uint32_t i = 0u; i < (uint32_t)CORDIC_STEPS; ++i) {
        int64_t dx = asr64(xx, i);
        int64_t dy = asr64(yy, i);
        if (yy > 0) {
            xx += dy;
            yy -= dx;
            z += k_cordic_atan[i];
        } else {
            xx -= dy;
            yy += dx;
            z -= k_cordic_atan[i];
        }
    }
    /* 2^-40 turn -> 2^-32 turn, rounded; +1/2 turn wraps to -1/2 (-pi). */
    int64_t a = rshift_round(z, 8);
    return i32_from_u32((uint32_t)((uint64_t)a & 0xFFFFFFFFu));
}

/* ------------------------------------------------------------------- sqrt */

uint64_t mc_isqrt_u64(uint64_t x, uint64_t *p_rem)
{
    uint64_t rem = x;
    uint64_t root = 0u;
    uint64_t bit = (uint64_t)1 << 62;
    while (bit > rem) {
        bit >>= 2;
    }
    while (bit != 0u) {
        if (rem >= root + bit) {
            rem -= root + bit;
            root = (root >> 1) + bit;
        } else {
            root >>= 1;
        }
        bit >>= 2;
    }
    if (p_rem != NULL) {
        *p_rem = rem;
    }
    return root;
}

q31_t mc_sqrt_q31(q31_t x)
{
    if (x <= 0) {
        return 0;
    }
    /* sqrt(x / 2^31) * 2^31 = sqrt(x * 2^31): integer square root of a
     * 62-bit number, then rounded to nearest: the remainder x*2^31 - root^2
     * exceeds root exactly when x*2^31 > (root + 1/2)^2. */
    uint64_t rem;
    uint64_t root = mc_isqrt_u64((uint64_t)x << 31, &rem);
    if (rem > root) {
        root += 1u;
    }
    return mc_q31_sat64((int64_t)root);
}
