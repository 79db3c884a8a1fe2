/**
 * @file mc_math.c
 * @brief Float32 fast math: sin/cos, atan2, sqrt, angle wrapping.
 *
 * No libm, no double, no float-to-int conversion of a NaN or out-of-range
 * value. Every operation is a plain IEEE-754 single-precision add, multiply
 * or divide (built with -ffp-contract=off, so no fused multiply-add), or an
 * integer operation: results are bit-identical on x86-64 and Cortex-M4F.
 *
 * sin/cos for |x| <= MC_MATH_NEAR_LIMIT_RAD (256 rad): mc_sincos_near_f32 in
 * mc_math.h (a table of 128 steps per turn, two-constant Cody-Waite to the
 * nearest step, short polynomials, angle sum), inline for the kernels.
 *
 * Range reduction (sin/cos beyond 256 rad, wrap):
 * - |x| <= MC_MATH_CW_LIMIT_RAD (8192 rad): Cody-Waite, x - k*(pi/2) with
 *   pi/2 = C1 + C2 + C3, where C1 and C2 have 11 significant bits (13
 *   trailing zero bits), so k*C1 and k*C2 are exact for |k| < 2^13;
 *   x - k*C1 is exact (Sterbenz) and so is the next step (its result is a
 *   multiple of 2^-24 below 1, or of 2^-22 below 4, i.e. fits 24 bits). Only
 *   the product k*C3 (< 2e-11) and the last subtraction (half an ulp of the
 *   result) round; the residual pi/2 - C1 - C2 - C3 = -1.7e-15 adds < 1e-11.
 * - larger |x|: Payne-Hanek in integer arithmetic (mc_turn_from_rad_f32):
 *   the float's 24-bit significand times a 96-bit window of the bits of 2/pi
 *   gives x/(2*pi) modulo one turn as a Q0.64 fraction, exactly up to
 *   2^-64 turn. Defined and accurate for every finite float.
 */
#include "math/mc_math.h"
#include "math/mc_q31.h"

/* ---------------------------------------------------------------- helpers */

/* Type punning through a union is defined in C11 (6.5.2.3 note 95) and,
 * unlike memcpy under -fno-builtin, compiles to a register move. */
typedef union {
    float f;
    uint32_t u;
} f32_bits_t;

static uint32_t bits_from_f32(float x)
{
    f32_bits_t b;
    b.f = x;
    return b.u;
}

static float f32_from_bits(uint32_t u)
{
    f32_bits_t b;
    b.u = u;
    return b.f;
}

/** Quiet NaN (built from its bits: no 0/0 at run time). */
static float nan_f32(void)
{
    return f32_from_bits(0x7FC00000u);
}

/** true if the sign bit is set (distinguishes -0 from +0). */
static bool signbit_f32(float x)
{
    return (bits_from_f32(x) & 0x80000000u) != 0u;
}

/**
 * Round to the nearest integer (ties to even) for |v| < 2^22, using the
 * float adder itself: adding 1.5*2^23 pushes the fraction bits out. Exact
 * IEEE semantics are guaranteed because the kernels are not built with
 * -ffast-math and float arithmetic is evaluated in float (FLT_EVAL_METHOD 0
 * on SSE and on the M4F).
 */
static float round_small_f32(float v)
{
    const float magic = 12582912.0f; /* 1.5 * 2^23 */
    return (v + magic) - magic;
}

/* Cody-Waite split of pi/2: C1, C2 with 11 significant bits. */
static const float cw_c1 = 0x1.92p+0f;      /* 1.5703125, 11 bits */
static const float cw_c2 = 0x1.fb4p-12f;    /* 4.8375129699707e-4, 11 bits */
static const float cw_c3 = 0x1.4442d2p-24f; /* 7.5497901264043e-8, 24 bits */
static const float cw_two_over_pi = 0.636619772367581343f;

/*
 * Bits of 2/pi, most significant first: 2/pi = 0.A2F9836E 4E441529 ... (hex).
 * 8 words = 256 bits cover the window needed by the largest float exponent
 * (x < 2^128: window ends at bit 102 + 96 = 198, read one word beyond).
 */
static const uint32_t k_two_over_pi_bits[8] = {
    0xA2F9836EU, 0x4E441529U, 0xFC2757D1U, 0xF534DDC0U,
    0xDB629599U, 0x3C439041U, 0xFE5163ABU, 0xDEBBC561U,
};

/** Bit-field read of 32 bits of 2/pi starting after bit position `pos`. */
static uint32_t two_over_pi_word(uint32_t pos)
{
    uint32_t wi = pos / 32u;
    uint32_t bo = pos % 32u;
    uint32_t hi = k_two_over_pi_bits[wi];
    if (bo == 0u) {
        return hi;
    }
    return (hi << bo) | (k_two_over_pi_bits[wi + 1u] >> (32u - bo));
}

bool mc_turn_from_rad_f32(float x_rad, uint64_t *p_turn_q64)
{
    if (!mc_isfinite_f32(x_rad)) {
        *p_turn_q64 = 0u;
        return false;
    }
    uint32_t u = bits_from_f32(x_rad);
    bool neg = (u & 0x80000000u) != 0u;
    uint32_t ebits = (u >> 23) & 0xFFu;
    uint32_t m = u & 0x7FFFFFu;
    int32_t e; /* |x| = m * 2^e */
    if (ebits == 0u) {
        e = -149;
    } else {
        m |= 0x800000u;
        e = (int32_t)ebits - 150;
    }
    if (m == 0u) {
        *p_turn_q64 = 0u;
        return true;
    }

    /*
     * |x| * 2/pi modulo 4, as an unsigned Q2.62 number V. Bits of 2/pi at
     * positions 1..s weigh at least 2^-s, so m * 2^e times them is a
     * multiple of 4 once s <= e - 2: skip them (s = max(e - 2, 0)) and use
     * the 96-bit window W of bits s+1 .. s+96:
     *   V = m * W * 2^(e - s - 96 + 62) = (m * W) >> (34 - e + s).
     * The bits of 2/pi beyond the window contribute less than 2^-70.
     */
    uint32_t s = (e > 2) ? (uint32_t)(e - 2) : 0u;
    uint64_t w0 = two_over_pi_word(s);
    uint64_t w1 = two_over_pi_word(s + 32u);
    uint64_t w2 = two_over_pi_word(s + 64u);
    uint64_t mm = m;
    /* 120-bit product m*W as 32-bit limbs r3:r2:r1:r0. */
    uint64_t t = mm * w2;
    uint64_t r0 = t & 0xFFFFFFFFu;
    t = mm * w1 + (t >> 32);
    uint64_t r1 = t & 0xFFFFFFFFu;
    t = mm * w0 + (t >> 32);
    uint64_t r2 = t & 0xFFFFFFFFu;
    uint64_t r3 = t >> 32;
    int32_t shift = 34 - e + (int32_t)s; /* >= 32 */
    uint64_t v;
    if (shift >= 128) {
        v = 0u;
    } else if (shift >= 96) {
        v = r3 >> (uint32_t)(shift - 96);
    } else if (shift >= 64) {
        uint32_t k = (uint32_t)(shift - 64);
        uint64_t hi = (r3 << 32) | r2;
        v = (k == 0u) ? hi : (hi >> k);
    } else {
        /* 32 <= shift < 64: bits above 2^64 of the shifted value drop
         * (multiples of 4 quarter turns). */
        uint32_t k = (uint32_t)(shift - 32);
        uint64_t hi = (r3 << 32) | r2;
        v = (hi << (32u - k)) | (r1 >> k);
    }
    (void)r0; /* below the 2^-62 quarter-turn resolution */

    /* V / 2^62 quarter turns = V / 2^64 turns. */
    *p_turn_q64 = neg ? (0u - v) : v;
    return true;
}

/**
 * Split a turn fraction (Q0.64) into the nearest quarter q (0..3) and the
 * remainder r in radians, |r| <= pi/4.
 */
static float quarter_from_turn(uint64_t turn, uint32_t *p_q)
{
    uint64_t rounded = turn + ((uint64_t)1 << 61);
    uint32_t q = (uint32_t)(rounded >> 62);
    uint64_t rem = turn - ((uint64_t)q << 62); /* mod 2^64 */
    bool neg = rem >= ((uint64_t)1 << 63);
    uint64_t mag = neg ? (0u - rem) : rem; /* <= 2^61 */
    /* r = mag / 2^62 * pi/2: (mag >> 30) is Q0.32, pi/2 is Q1.31 (rounded),
     * product Q1.63 < 2^63; converted to float with one rounding. */
    uint64_t prod = (mag >> 30) * 0xC90FDAA2u;
    float r = (float)prod * 1.08420217248550443e-19f; /* 2^-63 */
    *p_q = q & 3u;
    return neg ? -r : r;
}

/** reduce_quadrant for |x| <= MC_MATH_CW_LIMIT_RAD: Cody-Waite. */
static float reduce_cw(float x, uint32_t *p_q)
{
    float kf = round_small_f32(x * cw_two_over_pi); /* |k| <= 5216 */
    int32_t k = (int32_t)kf;                        /* in range: exact */
    float r = x - kf * cw_c1;                       /* exact */
    r = r - kf * cw_c2;
    r = r - kf * cw_c3;
    *p_q = (uint32_t)k & 3u;
    return r;
}

/** Reduce x to r in [-pi/4, pi/4] and quadrant q: x = r + q*pi/2 (mod 2pi). */
static float reduce_quadrant(float x, uint32_t *p_q)
{
    if (mc_abs_f32(x) <= MC_MATH_CW_LIMIT_RAD) {
        return reduce_cw(x, p_q);
    }
    uint64_t turn = 0u;
    (void)mc_turn_from_rad_f32(x, &turn);
    return quarter_from_turn(turn, p_q);
}

/** sin and cos of r + q pi/2 for |r| <= pi/4 (about): the quadrant
 * polynomials (mc_math.h) and the quadrant q mod 4 by swap and sign. */
static void sincos_quadrant(float r, uint32_t q, float *p_sin, float *p_cos)
{
    const float z = r * r;
    const float s =
        r * (1.0f + (z * (MC_MATH_SIN_S1 + (z * (MC_MATH_SIN_S2 + (z * MC_MATH_SIN_S3))))));
    const float c =
        1.0f +
        (z * (-0.5f + (z * (MC_MATH_COS_C1 + (z * (MC_MATH_COS_C2 + (z * MC_MATH_COS_C3)))))));
    float a = s;
    float b = c;
    if ((q & 1u) != 0u) {
        /* a quarter turn: (sin, cos) -> (cos, -sin) */
        a = c;
        b = -s;
    }
    if ((q & 2u) != 0u) {
        /* a half turn: both change sign */
        a = -a;
        b = -b;
    }
    *p_sin = a;
    *p_cos = b;
}

/* {sin, cos} of k 2 pi / 128, rounded to float from double sin/cos (whose
 * error, < 2^-52, is far below the float rounding; the multiples of pi/2
 * are written exactly). Generated once with numpy: float32(sin(2 pi k /
 * 128)), float32(cos(2 pi k / 128)). */
const float mc_math_sincos_table[MC_MATH_SINCOS_STEPS][2] = {
    {-0.0f, 1.000000000e+00f}, /* 0 */
    {4.906767607e-02f, 9.987954497e-01f},
    {9.801714122e-02f, 9.951847196e-01f},
    {1.467304677e-01f, 9.891765118e-01f},
    {1.950903237e-01f, 9.807852507e-01f},
    {2.429801822e-01f, 9.700312614e-01f},
    {2.902846634e-01f, 9.569403529e-01f},
    {3.368898630e-01f, 9.415440559e-01f},
    {3.826834261e-01f, 9.238795042e-01f}, /* 8 */
    {4.275550842e-01f, 9.039893150e-01f},
    {4.713967443e-01f, 8.819212914e-01f},
    {5.141027570e-01f, 8.577286005e-01f},
    {5.555702448e-01f, 8.314695954e-01f},
    {5.956993103e-01f, 8.032075167e-01f},
    {6.343932748e-01f, 7.730104327e-01f},
    {6.715589762e-01f, 7.409511209e-01f},
    {7.071067691e-01f, 7.071067691e-01f}, /* 16 */
    {7.409511209e-01f, 6.715589762e-01f},
    {7.730104327e-01f, 6.343932748e-01f},
    {8.032075167e-01f, 5.956993103e-01f},
    {8.314695954e-01f, 5.555702448e-01f},
    {8.577286005e-01f, 5.141027570e-01f},
    {8.819212914e-01f, 4.713967443e-01f},
    {9.039893150e-01f, 4.275550842e-01f},
    {9.238795042e-01f, 3.826834261e-01f}, /* 24 */
    {9.415440559e-01f, 3.368898630e-01f},
    {9.569403529e-01f, 2.902846634e-01f},
    {9.700312614e-01f, 2.429801822e-01f},
    {9.807852507e-01f, 1.950903237e-01f},
    {9.891765118e-01f, 1.467304677e-01f},
    {9.951847196e-01f, 9.801714122e-02f},
    {9.987954497e-01f, 4.906767607e-02f},
    {1.000000000e+00f, 0.0f}, /* 32 */
    {9.987954497e-01f, -4.906767607e-02f},
    {9.951847196e-01f, -9.801714122e-02f},
    {9.891765118e-01f, -1.467304677e-01f},
    {9.807852507e-01f, -1.950903237e-01f},
    {9.700312614e-01f, -2.429801822e-01f},
    {9.569403529e-01f, -2.902846634e-01f},
    {9.415440559e-01f, -3.368898630e-01f},
    {9.238795042e-01f, -3.826834261e-01f}, /* 40 */
    {9.039893150e-01f, -4.275550842e-01f},
    {8.819212914e-01f, -4.713967443e-01f},
    {8.577286005e-01f, -5.141027570e-01f},
    {8.314695954e-01f, -5.555702448e-01f},
    {8.032075167e-01f, -5.956993103e-01f},
    {7.730104327e-01f, -6.343932748e-01f},
    {7.409511209e-01f, -6.715589762e-01f},
    {7.071067691e-01f, -7.071067691e-01f}, /* 48 */
    {6.715589762e-01f, -7.409511209e-01f},
    {6.343932748e-01f, -7.730104327e-01f},
    {5.956993103e-01f, -8.032075167e-01f},
    {5.555702448e-01f, -8.314695954e-01f},
    {5.141027570e-01f, -8.577286005e-01f},
    {4.713967443e-01f, -8.819212914e-01f},
    {4.275550842e-01f, -9.039893150e-01f},
    {3.826834261e-01f, -9.238795042e-01f}, /* 56 */
    {3.368898630e-01f, -9.415440559e-01f},
    {2.902846634e-01f, -9.569403529e-01f},
    {2.429801822e-01f, -9.700312614e-01f},
    {1.950903237e-01f, -9.807852507e-01f},
    {1.467304677e-01f, -9.891765118e-01f},
    {9.801714122e-02f, -9.951847196e-01f},
    {4.906767607e-02f, -9.987954497e-01f},
    {0.0f, -1.000000000e+00f}, /* 64 */
    {-4.906767607e-02f, -9.987954497e-01f},
    {-9.801714122e-02f, -9.951847196e-01f},
    {-1.467304677e-01f, -9.891765118e-01f},
    {-1.950903237e-01f, -9.807852507e-01f},
    {-2.429801822e-01f, -9.700312614e-01f},
    {-2.902846634e-01f, -9.569403529e-01f},
    {-3.368898630e-01f, -9.415440559e-01f},
    {-3.826834261e-01f, -9.238795042e-01f}, /* 72 */
    {-4.275550842e-01f, -9.039893150e-01f},
    {-4.713967443e-01f, -8.819212914e-01f},
    {-5.141027570e-01f, -8.577286005e-01f},
    {-5.555702448e-01f, -8.314695954e-01f},
    {-5.956993103e-01f, -8.032075167e-01f},
    {-6.343932748e-01f, -7.730104327e-01f},
    {-6.715589762e-01f, -7.409511209e-01f},
    {-7.071067691e-01f, -7.071067691e-01f}, /* 80 */
    {-7.409511209e-01f, -6.715589762e-01f},
    {-7.730104327e-01f, -6.343932748e-01f},
    {-8.032075167e-01f, -5.956993103e-01f},
    {-8.314695954e-01f, -5.555702448e-01f},
    {-8.577286005e-01f, -5.141027570e-01f},
    {-8.819212914e-01f, -4.713967443e-01f},
    {-9.039893150e-01f, -4.275550842e-01f},
    {-9.238795042e-01f, -3.826834261e-01f}, /* 88 */
    {-9.415440559e-01f, -3.368898630e-01f},
    {-9.569403529e-01f, -2.902846634e-01f},
    {-9.700312614e-01f, -2.429801822e-01f},
    {-9.807852507e-01f, -1.950903237e-01f},
    {-9.891765118e-01f, -1.467304677e-01f},
    {-9.951847196e-01f, -9.801714122e-02f},
    {-9.987954497e-01f, -4.906767607e-02f},
    {-1.000000000e+00f, 0.0f}, /* 96 */
    {-9.987954497e-01f, 4.906767607e-02f},
    {-9.951847196e-01f, 9.801714122e-02f},
    {-9.891765118e-01f, 1.467304677e-01f},
    {-9.807852507e-01f, 1.950903237e-01f},
    {-9.700312614e-01f, 2.429801822e-01f},
    {-9.569403529e-01f, 2.902846634e-01f},
    {-9.415440559e-01f, 3.368898630e-01f},
    {-9.238795042e-01f, 3.826834261e-01f}, /* 104 */
    {-9.039893150e-01f, 4.275550842e-01f},
    {-8.819212914e-01f, 4.713967443e-01f},
    {-8.577286005e-01f, 5.141027570e-01f},
    {-8.314695954e-01f, 5.555702448e-01f},
    {-8.032075167e-01f, 5.956993103e-01f},
    {-7.730104327e-01f, 6.343932748e-01f},
    {-7.409511209e-01f, 6.715589762e-01f},
    {-7.071067691e-01f, 7.071067691e-01f}, /* 112 */
    {-6.715589762e-01f, 7.409511209e-01f},
    {-6.343932748e-01f, 7.730104327e-01f},
    {-5.956993103e-01f, 8.032075167e-01f},
    {-5.555702448e-01f, 8.314695954e-01f},
    {-5.141027570e-01f, 8.577286005e-01f},
    {-4.713967443e-01f, 8.819212914e-01f},
    {-4.275550842e-01f, 9.039893150e-01f},
    {-3.826834261e-01f, 9.238795042e-01f}, /* 120 */
    {-3.368898630e-01f, 9.415440559e-01f},
    {-2.902846634e-01f, 9.569403529e-01f},
    {-2.429801822e-01f, 9.700312614e-01f},
    {-1.950903237e-01f, 9.807852507e-01f},
    {-1.467304677e-01f, 9.891765118e-01f},
    {-9.801714122e-02f, 9.951847196e-01f},
    {-4.906767607e-02f, 9.987954497e-01f},
};

void mc_sincos_f32(float x_rad, float *p_sin, float *p_cos)
{
    uint32_t q = 0u;
    float r;
    if (mc_fabs_f32(x_rad) <= MC_MATH_NEAR_LIMIT_RAD) {
        /* the common range first (it excludes NaN and inf) */
        mc_sincos_near_f32(x_rad, p_sin, p_cos);
        return;
    }
    if (!mc_isfinite_f32(x_rad)) {
        float nan = x_rad - x_rad; /* NaN for NaN and +-inf */
        *p_sin = nan;
        *p_cos = nan;
        return;
    }
    r = reduce_quadrant(x_rad, &q);
    sincos_quadrant(r, q, p_sin, p_cos);
}

/* ------------------------------------------------------------------ atan2 */

/* Everything the common case leaves: NaN, infinities, both zero, and finite
 * pairs whose |x| + |y| overflows. */
static float atan2_special(float y, float x)
{
    if ((x != x) || (y != y)) {
        return x + y; /* NaN */
    }
    bool x_inf = !mc_isfinite_f32(x);
    bool y_inf = !mc_isfinite_f32(y);
    float ax = mc_fabs_f32(x);
    float ay = mc_fabs_f32(y);
    if (x_inf && y_inf) {
        ax = 1.0f;
        ay = 1.0f;
    } else if (x_inf) {
        ax = 1.0f;
        ay = 0.0f;
    } else if (y_inf) {
        ax = 0.0f;
        ay = 1.0f;
    } else if ((ax == 0.0f) && (ay == 0.0f)) {
        return 0.0f; /* defined: no direction yet */
    } else {
        /* finite, |x| + |y| overflows: halve both (exact, as both are
         * large), the angle is the same */
        ax = 0.5f * ax;
        ay = 0.5f * ay;
    }
    return mc_atan2_octant_f32(ay, ax, signbit_f32(x), signbit_f32(y));
}

float mc_atan2_f32(float y, float x)
{
    const float ax = mc_fabs_f32(x);
    const float ay = mc_fabs_f32(y);
    const float sum = ax + ay;
    /* false for NaN, both zero, an infinity or an overflowing sum */
    if ((sum > 0.0f) && (sum <= 3.40282347e38f)) {
        /* x < 0 as a float compare: x = -0 (with y != 0) gives the same
         * +-pi/2 as +0, as C99 wants; y's sign bit decides -0 vs +0. */
        return mc_atan2_octant_f32(ay, ax, x < 0.0f, signbit_f32(y));
    }
    return atan2_special(y, x);
}

/* ------------------------------------------------------------------- sqrt */

float mc_sqrt_f32(float x)
{
    if (x != x) {
        return x; /* NaN propagates */
    }
    if (x == 0.0f) {
        return x; /* +0 -> +0, -0 -> -0 (as IEEE sqrt) */
    }
    if (x < 0.0f) {
        return nan_f32();
    }
    if (!mc_isfinite_f32(x)) {
        return x; /* +inf */
    }
#if defined(__ARM_FP) || defined(__SSE_MATH__)
    /* Single-precision FPUs with a square-root instruction (Cortex-M4F
     * VSQRT.F32, x86-64 SQRTSS): IEEE 754 requires it correctly rounded, so
     * it returns exactly what the integer algorithm below returns (the test
     * compares both over every exponent), in 14 cycles on the M4F instead of
     * ~700 instructions. This is an instruction, not a libm call. */
    return __builtin_sqrtf(x);
#else
    return mc_sqrt_f32_soft(x);
#endif
}

float mc_sqrt_f32_soft(float x)
{
    if (x != x) {
        return x;
    }
    if (x == 0.0f) {
        return x;
    }
    if (x < 0.0f) {
        return nan_f32();
    }
    if (!mc_isfinite_f32(x)) {
        return x;
    }

    /* x = m * 2^e with m a 24-bit integer in [2^23, 2^24) (denormals
     * normalised), then e made even. */
    uint32_t u = bits_from_f32(x);
    uint32_t ebits = u >> 23; /* sign is 0 */
    uint32_t m = u & 0x7FFFFFu;
    int32_t e;
    if (ebits == 0u) {
        e = -149;
        while (m < 0x800000u) {
            m <<= 1;
            e -= 1;
        }
    } else {
        m |= 0x800000u;
        e = (int32_t)ebits - 150;
    }
    if ((e & 1) != 0) {
        m <<= 1;
        e -= 1;
    }

    /* sqrt(m * 2^26) = sqrt(m) * 2^13 has 25 or 26 bits: the digit-by-digit
     * integer square root gives its floor and the remainder (sticky). */
    uint64_t rem;
    uint64_t root = mc_isqrt_u64((uint64_t)m << 26, &rem); /* argument < 2^51 */
    bool sticky = rem != 0u;

    /* Keep 24 bits, round to nearest even (a sqrt is never an exact tie,
     * but the rule is written out in full). */
    uint32_t drop = (root >= ((uint64_t)1 << 25)) ? 2u : 1u;
    uint64_t keep = root >> drop;
    uint64_t rest = root & (((uint64_t)1 << drop) - 1u);
    uint64_t half = (uint64_t)1 << (drop - 1u);
    if ((rest > half) || ((rest == half) && (sticky || ((keep & 1u) != 0u)))) {
        keep += 1u;
    }
    int32_t f = (e / 2) - 13 + (int32_t)drop; /* result = keep * 2^f */
    if (keep >= ((uint64_t)1 << 24)) {
        keep >>= 1;
        f += 1;
    }
    /* sqrt of a positive finite float is a normal float: 2^-75 .. 2^64. */
    uint32_t out = ((uint32_t)(f + 150) << 23) | ((uint32_t)keep & 0x7FFFFFu);
    return f32_from_bits(out);
}

/* ------------------------------------------------------------------- wrap */

/* 2*pi = MC_TWO_PI_F32 + TWO_PI_LO (the float constant is 1.7e-7 high). */
static const float two_pi_lo = -0x1.777a5cp-23f; /* -1.7484556e-7 */

/**
 * Cody-Waite x - k*2*pi for |k| <= 1306 (4k quarter turns < 2^13), split as
 * r2 - p3: r2 = x - 4k*C1 - 4k*C2 is exact (Sterbenz, then 24-bit fit) when
 * k = round(x / 2pi) or its neighbour, and p3 = 4k*C3 carries < 2e-11.
 */
static float cw_wrap(float x, float kf, float *p_p3)
{
    float k4 = 4.0f * kf;
    float r = x - k4 * cw_c1;
    r = r - k4 * cw_c2;
    *p_p3 = k4 * cw_c3;
    return r;
}

/**
 * x - 2*pi*k for the k that puts the result in [lo, hi), lo = -pi (centered)
 * or 0, hi = lo + 2*pi (the float constants). Cody-Waite for moderate |x|,
 * integer reduction beyond. Inputs already in range come back unchanged.
 */
static float wrap_impl(float x, bool centered)
{
    if (!mc_isfinite_f32(x)) {
        return x - x; /* NaN */
    }
    float lo = centered ? -MC_PI_F32 : 0.0f;
    float hi = centered ? MC_PI_F32 : MC_TWO_PI_F32;
    if ((x >= lo) && (x < hi)) {
        return x;
    }
    float r;
    if (mc_abs_f32(x) <= MC_MATH_CW_LIMIT_RAD) {
        /* Centered reduction first: with k = round(x / 2pi), x and k*2pi
         * are within a factor 2, so the leading steps are exact. */
        float kf = round_small_f32(x * (0.25f * cw_two_over_pi));
        float p3 = 0.0f;
        float r2 = cw_wrap(x, kf, &p3);
        r = r2 - p3;
        /* The rounded x/(2pi) can pick a k one off near +-pi: redo the
         * exact reduction with the neighbour instead of adding a rounded
         * 2*pi. */
        if (r >= MC_PI_F32) {
            r2 = cw_wrap(x, kf + 1.0f, &p3);
            r = r2 - p3;
        } else if (r < -MC_PI_F32) {
            r2 = cw_wrap(x, kf - 1.0f, &p3);
            r = r2 - p3;
        } else {
            /* in range */
        }
        if (!centered && (r < 0.0f)) {
            /* r2 - p3 + 2*pi with one final rounding: Fast2Sum of the float
             * 2*pi and r2 (|r2| <= 2*pi) is exact as s + e. */
            float s = MC_TWO_PI_F32 + r2;
            float e = (MC_TWO_PI_F32 - s) + r2;
            r = s + ((e + two_pi_lo) - p3);
        }
    } else {
        uint64_t turn = 0u;
        (void)mc_turn_from_rad_f32(x, &turn);
        uint64_t half_turn = (uint64_t)1 << 63;
        bool neg = centered && (turn >= half_turn);
        uint64_t mag = neg ? (0u - turn) : turn;
        /* mag / 2^64 turns * 2*pi: (mag >> 32) Q0.32 times 2*pi in Q3.29,
         * product Q3.61 < 2^64. */
        uint64_t prod = (mag >> 32) * 0xC90FDAA2u;
        r = (float)prod * 4.33680868994201774e-19f; /* 2^-61 */
        r = neg ? -r : r;
    }
    /* A result within rounding of the upper bound (e.g. 2*pi - 1e-8 rounds
     * to the float 2*pi) is the same angle as the lower bound. */
    if ((r >= hi) || (r < lo)) {
        r = lo;
    }
    return r;
}

float mc_wrap_pi_f32(float x_rad)
{
    /* The common case on its own: |x| <= 8192 rad and the first k right.
     * wrap_impl performs the very same operations then (an input already
     * in range has k = 0 and comes back unchanged), so the result is the
     * same; everything else (NaN, inf, a neighbour k, -pi itself, huge |x|)
     * goes there. */
    if (mc_fabs_f32(x_rad) <= MC_MATH_CW_LIMIT_RAD) {
        float kf = round_small_f32(x_rad * (0.25f * cw_two_over_pi));
        float p3 = 0.0f;
        float r = cw_wrap(x_rad, kf, &p3) - p3;
        if (mc_fabs_f32(r) < MC_PI_F32) {
            return r;
        }
    }
    return wrap_impl(x_rad, true);
}

float mc_wrap_2pi_f32(float x_rad)
{
    return wrap_impl(x_rad, false);
}
