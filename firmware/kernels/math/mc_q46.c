/**
 * @file mc_q46.c
 * @brief Q46 accumulator and gain helpers of the q31 kernels (see mc_q46.h).
 */
#include "math/mc_q46.h"

#include <stddef.h>

#include "math/mc_math.h"

int64_t mc_q46_asr(int64_t v, uint32_t n)
{
    if (v >= 0) {
        return v >> n;
    }
    return ~((~v) >> n);
}

/* round(v / 2^n) ties up, n in [1, 62]; |v| < 2^63 - 2^61. */
static int64_t q46_rshift_round(int64_t v, uint32_t n)
{
    return mc_q46_asr(v + ((int64_t)1 << (n - 1u)), n);
}

/* v * 2^n saturated to +-MC_Q46_LIM, n in [0, 62]. */
static int64_t q46_lshift_sat(int64_t v, uint32_t n)
{
    const int64_t room = MC_Q46_LIM >> n;
    if (v > room) {
        return MC_Q46_LIM;
    }
    if (v < -room) {
        return -MC_Q46_LIM;
    }
    return v * ((int64_t)1 << n);
}

bool mc_q46_gain_from_f32(float g, mc_q46_gain_t *p_g)
{
    float m;
    int32_t s = 31;

    if (p_g == NULL) {
        return false;
    }
    p_g->mant = 0;
    p_g->shift = 0;
    if (!mc_isfinite_f32(g) || (mc_abs_f32(g) >= 1073741824.0f)) {
        return false;
    }
    m = mc_abs_f32(g);
    if (m < 3.5527136788005009e-15f) { /* 2^-48 */
        return true;
    }
    /* m * 2^(31 - s) in [2^30, 2^31): scale by exact powers of two. */
    while (m >= 2147483648.0f) {
        m *= 0.5f;
        s++;
    }
    while (m < 1073741824.0f) {
        m *= 2.0f;
        s--;
    }
    /* m is an integer-valued float in [2^30, 2^31) only when g has <= 24
     * significant bits, which every float has: exact conversion. */
    p_g->mant = (g < 0.0f) ? -(int32_t)m : (int32_t)m;
    p_g->shift = s;
    if (s < MC_Q46_SHIFT_MIN) {
        p_g->mant = 0;
        p_g->shift = 0;
    }
    return true;
}

float mc_q46_gain_to_f32(mc_q46_gain_t g)
{
    float v = (float)g.mant;
    int32_t e = g.shift - 31;
    while (e > 0) {
        v *= 2.0f;
        e--;
    }
    while (e < 0) {
        v *= 0.5f;
        e++;
    }
    return v;
}

q31_t mc_q46_to_q31(int64_t a)
{
    return mc_q31_sat64(q46_rshift_round(mc_q46_sat(a), 15u));
}

int64_t mc_q46_mul_q31(mc_q46_gain_t g, q31_t x)
{
    const int64_t p = (int64_t)g.mant * (int64_t)x; /* |p| < 2^62 */
    const int32_t e = g.shift - 16;                 /* result = p * 2^e */

    if (e >= 0) {
        return q46_lshift_sat(p, (uint32_t)e);
    }
    if (e < -62) {
        return 0;
    }
    return q46_rshift_round(p, (uint32_t)(-e));
}

int64_t mc_q46_mul(mc_q46_gain_t g, int64_t a)
{
    const int64_t as = mc_q46_sat(a);
    const int64_t hi = mc_q46_asr(as, 31u);            /* |hi| <= 2^31 */
    const int64_t lo = as - (hi * ((int64_t)1 << 31)); /* [0, 2^31) */
    const int64_t t = hi * (int64_t)g.mant;            /* |t| <= 2^62 */
    const int64_t u = lo * (int64_t)g.mant;            /* |u| < 2^62 */
    int64_t r_hi;
    int64_t r_lo;
    const int32_t s = g.shift; /* a*g = t 2^s + u 2^(s-31) */

    if (s >= 0) {
        r_hi = q46_lshift_sat(t, (uint32_t)s);
        if ((r_hi == MC_Q46_LIM) || (r_hi == -MC_Q46_LIM)) {
            return r_hi; /* beyond the range (to 2^-31 of it): saturated */
        }
    } else if (s < -62) {
        r_hi = 0;
    } else {
        r_hi = q46_rshift_round(t, (uint32_t)(-s));
    }
    if ((31 - s) > 62) {
        r_lo = 0;
    } else {
        r_lo = q46_rshift_round(u, (uint32_t)(31 - s)); /* 31 - s >= 1 */
    }
    return mc_q46_add(r_hi, r_lo);
}

int64_t mc_q46_mul_q46(int64_t a, int64_t b)
{
    int64_t m = mc_q46_sat(b);
    int64_t am = mc_q46_abs(m);
    int32_t k = 0;
    mc_q46_gain_t g;

    if (m == 0) {
        return 0;
    }
    /* b = mant * 2^k (mant normalised), value b / 2^46 = mant 2^(k-15-31). */
    while (am >= ((int64_t)1 << 31)) {
        am >>= 1;
        k++;
    }
    while (am < ((int64_t)1 << 30)) {
        am <<= 1;
        k--;
    }
    if (k > 0) {
        m = q46_rshift_round(m, (uint32_t)k);
        if (m >= ((int64_t)1 << 31)) { /* rounding carried: one more bit */
            m = q46_rshift_round(m, 1u);
            k++;
        }
    } else {
        m = m * ((int64_t)1 << (uint32_t)(-k));
    }
    g.mant = (int32_t)m;
    g.shift = k - 15;
    return mc_q46_mul(g, a);
}

bool mc_q46_limit_vec(int64_t *p_a, int64_t *p_b, int64_t lim)
{
    int64_t aa;
    int64_t ab;
    int64_t mx;
    int32_t sh = 0;
    int32_t sl = 0;
    int64_t a1;
    int64_t b1;
    int64_t l1;
    uint64_t mag;
    mc_q46_gain_t g;

    if ((p_a == NULL) || (p_b == NULL) || (lim <= 0)) {
        return false;
    }
    aa = mc_q46_abs(mc_q46_sat(*p_a));
    ab = mc_q46_abs(mc_q46_sat(*p_b));
    if ((aa + ab) <= lim) {
        return false; /* |v| <= |a| + |b| <= lim */
    }
    mx = (aa > ab) ? aa : ab;
    /* common scale 2^-sh bringing mx into [2^30, 2^31) */
    if (mx >= ((int64_t)1 << 31)) {
        while ((mx >> (uint32_t)sh) >= ((int64_t)1 << 31)) {
            sh++;
        }
    } else {
        while ((mx * ((int64_t)1 << (uint32_t)(-sh))) < ((int64_t)1 << 30)) {
            sh--;
        }
    }
    if (sh >= 0) {
        a1 = aa >> (uint32_t)sh;
        b1 = ab >> (uint32_t)sh;
    } else {
        a1 = aa * ((int64_t)1 << (uint32_t)(-sh));
        b1 = ab * ((int64_t)1 << (uint32_t)(-sh));
    }
    mag = mc_isqrt_u64(((uint64_t)a1 * (uint64_t)a1) + ((uint64_t)b1 * (uint64_t)b1), NULL);
    /* lim = l1 2^sl with l1 in [2^30, 2^31) (truncated: < 2^-30 relative) */
    l1 = lim;
    while (l1 >= ((int64_t)1 << 31)) {
        l1 >>= 1;
        sl++;
    }
    while (l1 < ((int64_t)1 << 30)) {
        l1 <<= 1;
        sl--;
    }
    /* factor lim/|v| = (l1/mag) 2^(sl - sh) = mant 2^(shift - 31) */
    {
        uint64_t m = (((uint64_t)l1) << 31) / mag; /* < 2^32: mag >= 2^30 */
        int32_t shift = sl - sh;
        if (m >= ((uint64_t)1 << 31)) {
            m >>= 1;
            shift++;
        }
        if (m < ((uint64_t)1 << 30)) { /* l1/mag > 2^-1.5: one step at most */
            m <<= 1;
            shift--;
        }
        g.mant = (int32_t)m;
        g.shift = shift;
    }
    if (g.shift >= 1) {
        return false; /* factor >= 1: |v| <= lim to the resolution of the test */
    }
    *p_a = mc_q46_mul(g, mc_q46_sat(*p_a));
    *p_b = mc_q46_mul(g, mc_q46_sat(*p_b));
    return true;
}
