// Unit tests: float32 math kernels (firmware/kernels/math/mc_math.h).
//
// Reference: libm in double (glibc's sin/cos/atan2 are accurate to < 1 ulp of
// double, with exact argument reduction for huge arguments), rounded to float
// where the brief's bound is "vs libm rounded". Every bound below is the one
// stated in mc_math.h; the comment next to it gives the reason.
#include <gtest/gtest.h>

#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>

#include "math/mc_math.h"

namespace
{

constexpr double kPi = 3.14159265358979323846;
constexpr float kNan = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

// Stated bound of mc_sincos_f32 (mc_math.h): reduction error <= half an ulp
// of |r| <= pi/4 (3e-8), polynomial fit 2.4e-9, float evaluation ~1.5 ulp of
// the result (9e-8), and the rounding of the float reference itself (3e-8),
// over every finite x: 1.5e-7, stated with margin as 2e-7.
constexpr double kSincosBound = 2e-7;
// Stated bound of mc_atan2_f32: polynomial fit 7e-10, rounding of the ratio
// and of the reduction (pi/4 + ...) about 2 ulp of pi/2 (2.4e-7), float pi.
constexpr double kAtan2Bound = 5e-7;
// Stated bound of mc_wrap_pi_f32: the leading Cody-Waite steps are exact,
// so only the last rounding of a result of magnitude <= pi remains: half an
// ulp of pi (1.19e-7) + < 3e-11 (k*C3 product, pi/2 residual).
constexpr double kWrapPiBound = 1.25e-7;
// mc_wrap_2pi_f32: the same for results up to 2*pi (half ulp 2.4e-7).
constexpr double kWrap2PiBound = 2.5e-7;

float from_bits(uint32_t u)
{
    float f;
    std::memcpy(&f, &u, sizeof f);
    return f;
}

uint32_t to_bits(float f)
{
    uint32_t u;
    std::memcpy(&u, &f, sizeof u);
    return u;
}

struct SincosErr {
    double max_err = 0.0;
    float worst_x = 0.0f;
};

void check_sincos(float x, SincosErr *e)
{
    float s = 0.0f;
    float c = 0.0f;
    mc_sincos_f32(x, &s, &c);
    const double rs = static_cast<double>(static_cast<float>(std::sin(static_cast<double>(x))));
    const double rc = static_cast<double>(static_cast<float>(std::cos(static_cast<double>(x))));
    const double err =
        std::max(std::fabs(static_cast<double>(s) - rs), std::fabs(static_cast<double>(c) - rc));
    if (err > e->max_err || std::isnan(err)) {
        e->max_err = std::isnan(err) ? 1e9 : err;
        e->worst_x = x;
    }
}

// Angle difference a - b folded to [-pi, pi] (exact enough in double).
double angle_diff(double a, double b)
{
    return std::remainder(a - b, 2.0 * kPi);
}

} // namespace

// ------------------------------------------------------------------ sincos

TEST(MathSincosF32, DenseSweepOneTurnWithinBound)
{
    // The range the control loop lives in: 1e6 points over [-2pi, 2pi].
    SincosErr e;
    const int n = 1000000;
    for (int i = 0; i <= n; ++i) {
        check_sincos(static_cast<float>(-2.0 * kPi + 4.0 * kPi * i / n), &e);
    }
    EXPECT_LE(e.max_err, kSincosBound) << "worst x = " << e.worst_x;
}

TEST(MathSincosF32, DenseSweepCodyWaiteRangeWithinBound)
{
    // 2e6 points over the whole Cody-Waite range [-8192, 8192].
    SincosErr e;
    const int n = 2000000;
    const double lim = static_cast<double>(MC_MATH_CW_LIMIT_RAD);
    for (int i = 0; i <= n; ++i) {
        check_sincos(static_cast<float>(-lim + 2.0 * lim * i / n), &e);
    }
    EXPECT_LE(e.max_err, kSincosBound) << "worst x = " << e.worst_x;
}

TEST(MathSincosF32, HugeArgumentsPayneHanekWithinBound)
{
    // 1e6 random floats with exponents from 2^13 up to FLT_MAX, both signs:
    // the integer Payne-Hanek path. Same bound as the Cody-Waite range.
    SincosErr e;
    std::mt19937 rng(12345u);
    std::uniform_int_distribution<uint32_t> mant(0u, 0x7FFFFFu);
    std::uniform_int_distribution<uint32_t> expo(127u + 13u, 254u);
    for (int i = 0; i < 1000000; ++i) {
        uint32_t u = (expo(rng) << 23) | mant(rng) | ((i & 1) ? 0x80000000u : 0u);
        check_sincos(from_bits(u), &e);
    }
    // Every float just around the switch point and a few landmarks.
    for (uint32_t u = to_bits(MC_MATH_CW_LIMIT_RAD) - 2000u;
         u <= to_bits(MC_MATH_CW_LIMIT_RAD) + 2000u; ++u) {
        check_sincos(from_bits(u), &e);
        check_sincos(-from_bits(u), &e);
    }
    check_sincos(FLT_MAX, &e);
    check_sincos(-FLT_MAX, &e);
    check_sincos(1e22f, &e);
    check_sincos(16777216.0f, &e);
    EXPECT_LE(e.max_err, kSincosBound) << "worst x = " << e.worst_x;
}

TEST(MathSincosF32, InlineNearFormSameBitsAsFunction)
{
    // mc_sincos_near_f32 is what mc_sincos_f32 runs for |x| <= 256 rad:
    // the same bits over that whole range (a sweep with a step that is not
    // a multiple of the table's 2pi/128, and the range ends).
    const float ends[] = {MC_MATH_NEAR_LIMIT_RAD, -MC_MATH_NEAR_LIMIT_RAD, 0.0f, -0.0f};
    for (int i = -2000000; i <= 2000000; ++i) {
        const float x = static_cast<float>(i) * 1.28e-4f;
        float s1 = 0.0f, c1 = 0.0f, s2 = 0.0f, c2 = 0.0f;
        mc_sincos_near_f32(x, &s1, &c1);
        mc_sincos_f32(x, &s2, &c2);
        ASSERT_EQ(to_bits(s1), to_bits(s2)) << x;
        ASSERT_EQ(to_bits(c1), to_bits(c2)) << x;
    }
    for (const float x : ends) {
        float s1 = 0.0f, c1 = 0.0f, s2 = 0.0f, c2 = 0.0f;
        mc_sincos_near_f32(x, &s1, &c1);
        mc_sincos_f32(x, &s2, &c2);
        EXPECT_EQ(to_bits(s1), to_bits(s2)) << x;
        EXPECT_EQ(to_bits(c1), to_bits(c2)) << x;
    }
}

TEST(MathSincosF32, SmallAndDenormalArguments)
{
    // Below 2^-12, sin x rounds to x and cos x to 1 (x^3/6 and x^2/2 are
    // below half an ulp): the kernel must return them exactly.
    const float xs[] = {FLT_MIN, from_bits(1u), from_bits(0x007FFFFFu), 1e-20f, 1e-10f,
                        1e-5f,   2.4e-4f};
    for (float x : xs) {
        for (float sx : {x, -x}) {
            float s = 1.0f;
            float c = 0.0f;
            mc_sincos_f32(sx, &s, &c);
            EXPECT_EQ(to_bits(s), to_bits(sx)) << sx;
            EXPECT_EQ(c, 1.0f) << sx;
        }
    }
}

TEST(MathSincosF32, ZerosAndSignedZero)
{
    float s = 1.0f;
    float c = 0.0f;
    mc_sincos_f32(0.0f, &s, &c);
    EXPECT_EQ(to_bits(s), 0u); // +0
    EXPECT_EQ(c, 1.0f);
    mc_sincos_f32(-0.0f, &s, &c);
    EXPECT_EQ(to_bits(s), 0x80000000u); // -0: sin is odd
    EXPECT_EQ(c, 1.0f);
}

TEST(MathSincosF32, MultiplesOfHalfPi)
{
    // k * (float)(pi/2) for |k| <= 20000 (inside and beyond the Cody-Waite
    // range): the float multiple is not the exact multiple, so the result
    // is checked against libm on the same float, same bound.
    SincosErr e;
    for (int k = -20000; k <= 20000; ++k) {
        check_sincos(static_cast<float>(k * (kPi / 2.0)), &e);
    }
    check_sincos(MC_PI_F32, &e);
    check_sincos(-MC_PI_F32, &e);
    check_sincos(MC_HALF_PI_F32, &e);
    check_sincos(-MC_HALF_PI_F32, &e);
    EXPECT_LE(e.max_err, kSincosBound) << "worst x = " << e.worst_x;
    // Exact quadrant values: sin(pi_f) = -(pi_f - pi) rounded, tiny.
    float s = 0.0f;
    float c = 0.0f;
    mc_sincos_f32(MC_PI_F32, &s, &c);
    EXPECT_EQ(c, -1.0f);
    // |sin(pi_f)| = pi_f - pi = 8.74e-8: 1% relative tolerance (the reduced
    // argument is exact to 1e-15 here; only the final rounding remains).
    EXPECT_NEAR(s, -8.742278e-8, 1e-9);
}

TEST(MathSincosF32, NonFiniteGivesNaN)
{
    for (float x : {kNan, -kNan, kInf, -kInf}) {
        float s = 0.0f;
        float c = 0.0f;
        mc_sincos_f32(x, &s, &c);
        EXPECT_TRUE(std::isnan(s)) << x;
        EXPECT_TRUE(std::isnan(c)) << x;
    }
}

TEST(MathSincosF32, PythagoreanIdentityWithinBound)
{
    // s = S + e1, c = C + e2 with |e| <= 2e-7 (stated bound) gives
    // |s^2 + c^2 - 1| <= 2(|S| + |C|) 2e-7 + 8e-14 <= 2 sqrt(2) 2e-7 = 5.7e-7;
    // evaluated in double, so no further rounding.
    const double bound = 2.0 * std::sqrt(2.0) * kSincosBound + 1e-13;
    double worst = 0.0;
    const int n = 1000000;
    for (int i = 0; i <= n; ++i) {
        float s = 0.0f;
        float c = 0.0f;
        mc_sincos_f32(static_cast<float>(-100.0 + 200.0 * i / n), &s, &c);
        const double sd = static_cast<double>(s);
        const double cd = static_cast<double>(c);
        worst = std::max(worst, std::fabs(sd * sd + cd * cd - 1.0));
    }
    EXPECT_LE(worst, bound);
}

// ------------------------------------------------------------------- atan2

TEST(MathAtan2F32, DenseSweepAllQuadrantsAndScales)
{
    // 1e6 directions around the circle at radii from 1e-30 to 1e30
    // (the ratio, not the scale, matters), compared with atan2 in double.
    double worst = 0.0;
    float wy = 0.0f;
    float wx = 0.0f;
    const int n = 1000000;
    const double radii[] = {1e-30, 1e-3, 1.0, 7.5, 1e6, 1e30};
    for (int i = 0; i < n; ++i) {
        const double th = -kPi + 2.0 * kPi * (i + 0.5) / n;
        const double r = radii[i % 6];
        const float y = static_cast<float>(r * std::sin(th));
        const float x = static_cast<float>(r * std::cos(th));
        const double ref = std::atan2(static_cast<double>(y), static_cast<double>(x));
        const double err = std::fabs(static_cast<double>(mc_atan2_f32(y, x)) - ref);
        if (!(err <= worst)) {
            worst = err;
            wy = y;
            wx = x;
        }
    }
    EXPECT_LE(worst, kAtan2Bound) << "worst y=" << wy << " x=" << wx;
}

TEST(MathAtan2F32, RandomPairsAndExtremeRatios)
{
    double worst = 0.0;
    std::mt19937 rng(777u);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    std::uniform_int_distribution<uint32_t> bits(0u, 0x7F7FFFFFu); // finite
    for (int i = 0; i < 500000; ++i) {
        float y = u(rng);
        float x = u(rng);
        if (i % 2 == 1) { // any finite magnitudes, incl. denormals
            y = from_bits(bits(rng) | ((i & 2) ? 0x80000000u : 0u));
            x = from_bits(bits(rng) | ((i & 4) ? 0x80000000u : 0u));
        }
        const double ref = std::atan2(static_cast<double>(y), static_cast<double>(x));
        worst = std::max(worst, std::fabs(static_cast<double>(mc_atan2_f32(y, x)) - ref));
    }
    EXPECT_LE(worst, kAtan2Bound);
}

TEST(MathAtan2F32, ZerosAndAxes)
{
    // atan2(0, 0) = 0 for every sign combination (defined by the contract).
    for (float y : {0.0f, -0.0f}) {
        for (float x : {0.0f, -0.0f}) {
            EXPECT_EQ(mc_atan2_f32(y, x), 0.0f);
        }
    }
    // Exact values on the axes (float pi, pi/2 are the nearest floats).
    EXPECT_EQ(to_bits(mc_atan2_f32(0.0f, 1.0f)), 0u);
    EXPECT_EQ(to_bits(mc_atan2_f32(-0.0f, 1.0f)), 0x80000000u);
    EXPECT_EQ(mc_atan2_f32(0.0f, -1.0f), MC_PI_F32);
    EXPECT_EQ(mc_atan2_f32(-0.0f, -1.0f), -MC_PI_F32);
    EXPECT_EQ(mc_atan2_f32(1.0f, 0.0f), MC_HALF_PI_F32);
    EXPECT_EQ(mc_atan2_f32(1.0f, -0.0f), MC_HALF_PI_F32);
    EXPECT_EQ(mc_atan2_f32(-1.0f, 0.0f), -MC_HALF_PI_F32);
    EXPECT_EQ(mc_atan2_f32(from_bits(1u), 0.0f), MC_HALF_PI_F32);
}

TEST(MathAtan2F32, InfinitiesMatchLibm)
{
    const float vals[] = {kInf, -kInf, 1.0f, -1.0f, 0.0f, -0.0f, FLT_MAX, -FLT_MAX};
    for (float y : vals) {
        for (float x : vals) {
            if (y == 0.0f && x == 0.0f) {
                continue; // our defined atan2(0,0) = 0 differs from libm's +-pi
            }
            const double ref = std::atan2(static_cast<double>(y), static_cast<double>(x));
            EXPECT_NEAR(mc_atan2_f32(y, x), ref, kAtan2Bound) << "y=" << y << " x=" << x;
        }
    }
}

TEST(MathAtan2F32, NaNGivesNaN)
{
    EXPECT_TRUE(std::isnan(mc_atan2_f32(kNan, 1.0f)));
    EXPECT_TRUE(std::isnan(mc_atan2_f32(1.0f, kNan)));
    EXPECT_TRUE(std::isnan(mc_atan2_f32(kNan, kNan)));
    EXPECT_TRUE(std::isnan(mc_atan2_f32(kNan, kInf)));
    EXPECT_TRUE(std::isnan(mc_atan2_f32(0.0f, kNan)));
}

// -------------------------------------------------------------------- sqrt

TEST(MathSqrtF32, CorrectlyRoundedOverAllExponents)
{
    // Stated: correctly rounded (0 ulp from sqrtf, which IEEE requires to be
    // correctly rounded), so the test asserts bit equality. 2.1e6 bit
    // patterns evenly spread over every positive finite float (denormals
    // included) plus 1e6 random ones.
    uint64_t mismatches = 0;
    float first_bad = 0.0f;
    // Both paths: mc_sqrt_f32 (FPU instruction on this host) and the
    // integer-only mc_sqrt_f32_soft used on cores without one.
    auto check = [&](float x) {
        const float got = mc_sqrt_f32(x);
        const float soft = mc_sqrt_f32_soft(x);
        const float ref = std::sqrt(x);
        if (to_bits(got) != to_bits(ref) || to_bits(soft) != to_bits(ref)) {
            if (mismatches == 0) {
                first_bad = x;
            }
            ++mismatches;
        }
    };
    for (uint32_t u = 1u; u < 0x7F800000u; u += 1021u) {
        check(from_bits(u));
    }
    std::mt19937 rng(99u);
    std::uniform_int_distribution<uint32_t> bits(1u, 0x7F7FFFFFu);
    for (int i = 0; i < 1000000; ++i) {
        check(from_bits(bits(rng)));
    }
    for (uint32_t u = 1u; u < 5000u; ++u) { // smallest denormals, one by one
        check(from_bits(u));
    }
    for (uint32_t k = 1u; k < 4096u; ++k) { // perfect squares: exact results
        check(static_cast<float>(k * k));
    }
    EXPECT_EQ(mismatches, 0u) << "first mismatch at x = " << first_bad;
}

TEST(MathSqrtF32, SpecialValues)
{
    EXPECT_EQ(to_bits(mc_sqrt_f32(0.0f)), 0u);
    EXPECT_EQ(to_bits(mc_sqrt_f32(-0.0f)), 0x80000000u); // as IEEE sqrt
    EXPECT_EQ(mc_sqrt_f32(kInf), kInf);
    EXPECT_TRUE(std::isnan(mc_sqrt_f32(-kInf)));
    EXPECT_TRUE(std::isnan(mc_sqrt_f32(-1.0f)));
    EXPECT_TRUE(std::isnan(mc_sqrt_f32(-from_bits(1u)))); // negative denormal
    EXPECT_TRUE(std::isnan(mc_sqrt_f32(kNan)));
    EXPECT_EQ(mc_sqrt_f32(4.0f), 2.0f);
    EXPECT_EQ(mc_sqrt_f32(0.25f), 0.5f);
    EXPECT_EQ(mc_sqrt_f32(FLT_MAX), std::sqrt(FLT_MAX));
    EXPECT_EQ(mc_sqrt_f32(from_bits(1u)), std::sqrt(from_bits(1u))); // 2^-74.5
}

TEST(MathSqrtF32, SoftSpecialValues)
{
    EXPECT_EQ(to_bits(mc_sqrt_f32_soft(0.0f)), 0u);
    EXPECT_EQ(to_bits(mc_sqrt_f32_soft(-0.0f)), 0x80000000u); // as IEEE sqrt
    EXPECT_EQ(mc_sqrt_f32_soft(kInf), kInf);
    EXPECT_TRUE(std::isnan(mc_sqrt_f32_soft(-kInf)));
    EXPECT_TRUE(std::isnan(mc_sqrt_f32_soft(-1.0f)));
    EXPECT_TRUE(std::isnan(mc_sqrt_f32_soft(-from_bits(1u)))); // negative denormal
    EXPECT_TRUE(std::isnan(mc_sqrt_f32_soft(kNan)));
    EXPECT_EQ(mc_sqrt_f32_soft(4.0f), 2.0f);
    EXPECT_EQ(mc_sqrt_f32_soft(0.25f), 0.5f);
    EXPECT_EQ(mc_sqrt_f32_soft(FLT_MAX), std::sqrt(FLT_MAX));
    EXPECT_EQ(mc_sqrt_f32_soft(from_bits(1u)), std::sqrt(from_bits(1u))); // 2^-74.5
}

// -------------------------------------------------------------------- wrap

namespace
{

struct WrapErr {
    double max_err = 0.0;
    float worst_x = 0.0f;
    bool range_ok = true;
};

// Error of w = wrap(x) against the exact x mod 2pi, measured as the angle
// difference in double (glibc reduces huge doubles exactly inside sin/cos,
// so for |x| beyond 2^53 the difference is taken through sin/cos).
void check_wrap(float x, bool centered, WrapErr *e)
{
    const float w = centered ? mc_wrap_pi_f32(x) : mc_wrap_2pi_f32(x);
    const float lo = centered ? -MC_PI_F32 : 0.0f;
    const float hi = centered ? MC_PI_F32 : MC_TWO_PI_F32;
    if (!(w >= lo && w < hi)) {
        e->range_ok = false;
        e->worst_x = x;
    }
    const double xd = static_cast<double>(x);
    const double wd = static_cast<double>(w);
    double err;
    if (std::fabs(xd) < 1e6) {
        err = std::fabs(angle_diff(xd, wd));
    } else {
        // sin(x - w) = sin x cos w - cos x sin w: w is small, x reduced by libm.
        const double sd = std::sin(xd) * std::cos(wd) - std::cos(xd) * std::sin(wd);
        const double cd = std::cos(xd) * std::cos(wd) + std::sin(xd) * std::sin(wd);
        err = std::fabs(std::atan2(sd, cd));
    }
    if (err > e->max_err) {
        e->max_err = err;
        e->worst_x = x;
    }
}

} // namespace

TEST(MathWrapF32, InRangeInputsUnchanged)
{
    // Exact: inputs already in range come back bit for bit.
    const int n = 100000;
    for (int i = 0; i < n; ++i) {
        const float x = static_cast<float>(-kPi + 2.0 * kPi * i / n);
        if (x >= -MC_PI_F32 && x < MC_PI_F32) {
            EXPECT_EQ(to_bits(mc_wrap_pi_f32(x)), to_bits(x));
        }
        const float x2 = static_cast<float>(2.0 * kPi * i / n);
        if (x2 < MC_TWO_PI_F32) {
            EXPECT_EQ(to_bits(mc_wrap_2pi_f32(x2)), to_bits(x2));
        }
    }
    EXPECT_EQ(mc_wrap_pi_f32(-MC_PI_F32), -MC_PI_F32);
    EXPECT_EQ(mc_wrap_2pi_f32(0.0f), 0.0f);
}

TEST(MathWrapF32, InlineFormSameBitsAsFunction)
{
    // mc_wrap_pi_fast_f32 promises mc_wrap_pi_f32's result: no tolerance.
    // A sweep over +-30 rad (several turns) with the float neighbours of
    // +-pi, plus the non-finite values (NaN compared as NaN).
    for (int i = -300000; i <= 300000; ++i) {
        const float x = static_cast<float>(i) * 1e-4f;
        ASSERT_EQ(to_bits(mc_wrap_pi_fast_f32(x)), to_bits(mc_wrap_pi_f32(x))) << x;
    }
    const float edges[] = {MC_PI_F32,
                           -MC_PI_F32,
                           std::nextafter(MC_PI_F32, 0.0f),
                           std::nextafter(-MC_PI_F32, 0.0f),
                           std::nextafter(MC_PI_F32, 4.0f),
                           std::nextafter(-MC_PI_F32, -4.0f),
                           0.0f,
                           -0.0f,
                           1e30f,
                           -1e30f};
    for (const float x : edges) {
        EXPECT_EQ(to_bits(mc_wrap_pi_fast_f32(x)), to_bits(mc_wrap_pi_f32(x))) << x;
    }
    EXPECT_TRUE(std::isnan(mc_wrap_pi_fast_f32(kNan)));
    EXPECT_TRUE(std::isnan(mc_wrap_pi_fast_f32(kInf)));
}

TEST(MathSqrtF32, NonNegativeInlineFormSameBits)
{
    // mc_sqrt_nonneg_f32 promises mc_sqrt_f32's result for x >= 0 (+0,
    // denormals, +inf included): every exponent, a few significands each.
    for (uint32_t e = 0u; e <= 255u; ++e) {
        for (uint32_t m : {0u, 1u, 0x400000u, 0x7FFFFFu, 0x123457u}) {
            if (e == 255u && m != 0u) {
                continue; // NaN: only "NaN out" is promised
            }
            const float x = from_bits((e << 23) | m);
            ASSERT_EQ(to_bits(mc_sqrt_nonneg_f32(x)), to_bits(mc_sqrt_f32(x))) << x;
        }
    }
    EXPECT_TRUE(std::isnan(mc_sqrt_nonneg_f32(kNan)));
}

TEST(MathWrapF32, DenseSweepWithinBoundAndRange)
{
    // 2e6 points over [-8192, 8192] (Cody-Waite) plus the float landmarks.
    WrapErr ep;
    WrapErr e2;
    const int n = 2000000;
    const double lim = static_cast<double>(MC_MATH_CW_LIMIT_RAD);
    for (int i = 0; i <= n; ++i) {
        const float x = static_cast<float>(-lim + 2.0 * lim * i / n);
        check_wrap(x, true, &ep);
        check_wrap(x, false, &e2);
    }
    for (float x : {MC_PI_F32, -MC_PI_F32, MC_TWO_PI_F32, -MC_TWO_PI_F32, 3.0f * MC_PI_F32, -0.0f,
                    std::nextafter(MC_TWO_PI_F32, 0.0f), -from_bits(1u), from_bits(1u)}) {
        check_wrap(x, true, &ep);
        check_wrap(x, false, &e2);
    }
    EXPECT_TRUE(ep.range_ok) << ep.worst_x;
    EXPECT_TRUE(e2.range_ok) << e2.worst_x;
    EXPECT_LE(ep.max_err, kWrapPiBound) << "worst x = " << ep.worst_x;
    EXPECT_LE(e2.max_err, kWrap2PiBound) << "worst x = " << e2.worst_x;
}

TEST(MathWrapF32, HugeArgumentsDefinedAndAccurate)
{
    WrapErr ep;
    WrapErr e2;
    std::mt19937 rng(4242u);
    std::uniform_int_distribution<uint32_t> mant(0u, 0x7FFFFFu);
    std::uniform_int_distribution<uint32_t> expo(127u + 13u, 254u);
    for (int i = 0; i < 300000; ++i) {
        const uint32_t u = (expo(rng) << 23) | mant(rng) | ((i & 1) ? 0x80000000u : 0u);
        check_wrap(from_bits(u), true, &ep);
        check_wrap(from_bits(u), false, &e2);
    }
    check_wrap(FLT_MAX, true, &ep);
    check_wrap(-FLT_MAX, false, &e2);
    EXPECT_TRUE(ep.range_ok) << ep.worst_x;
    EXPECT_TRUE(e2.range_ok) << e2.worst_x;
    EXPECT_LE(ep.max_err, kWrapPiBound) << "worst x = " << ep.worst_x;
    EXPECT_LE(e2.max_err, kWrap2PiBound) << "worst x = " << e2.worst_x;
}

TEST(MathWrapF32, NonFiniteGivesNaN)
{
    for (float x : {kNan, kInf, -kInf}) {
        EXPECT_TRUE(std::isnan(mc_wrap_pi_f32(x))) << x;
        EXPECT_TRUE(std::isnan(mc_wrap_2pi_f32(x))) << x;
    }
}

// ------------------------------------------------- exact turn reduction

TEST(MathTurnFromRadF32, MatchesLongDoubleReference)
{
    // For |x| <= 8192, x / (2 pi) in long double (64-bit significand) is
    // within 8192/(2pi) * 2^-63 < 2^-52 turn of the exact value, so the
    // top 48 bits of the Q0.64 turn must agree to +-1 (2^-48 turn).
    const long double two_pi = 6.283185307179586476925286766559L;
    std::mt19937 rng(5u);
    std::uniform_real_distribution<float> u(-8192.0f, 8192.0f);
    int bad = 0;
    for (int i = 0; i < 200000; ++i) {
        const float x = u(rng);
        uint64_t turn = 0u;
        ASSERT_TRUE(mc_turn_from_rad_f32(x, &turn));
        long double t = static_cast<long double>(x) / two_pi;
        t -= std::floor(t);                               // [0, 1)
        const long double ref48 = t * 281474976710656.0L; // 2^48
        const long double got48 = static_cast<long double>(turn >> 16);
        long double d = std::fabs(got48 - ref48);
        d = std::min(d, 281474976710656.0L - d); // modulo one turn
        if (d > 1.0L) {
            ++bad;
        }
    }
    EXPECT_EQ(bad, 0);
    uint64_t turn = 1u;
    EXPECT_FALSE(mc_turn_from_rad_f32(kNan, &turn));
    EXPECT_EQ(turn, 0u);
    EXPECT_FALSE(mc_turn_from_rad_f32(-kInf, &turn));
    EXPECT_TRUE(mc_turn_from_rad_f32(0.0f, &turn));
    EXPECT_EQ(turn, 0u);
}

// mc_sign_band_f32: linear inside the band, +-1 outside, the plain sign
// without a band. Exact: each case is one division of representable values.
TEST(MathF32, SignBandIsLinearInsideTheBandAndTheSignOutside)
{
    EXPECT_EQ(0.5f, mc_sign_band_f32(0.25f, 0.5f));
    EXPECT_EQ(-0.5f, mc_sign_band_f32(-0.25f, 0.5f));
    EXPECT_EQ(1.0f, mc_sign_band_f32(3.0f, 0.5f));
    EXPECT_EQ(-1.0f, mc_sign_band_f32(-3.0f, 0.5f));
    EXPECT_EQ(0.0f, mc_sign_band_f32(0.0f, 0.5f));
    EXPECT_EQ(1.0f, mc_sign_band_f32(1e-20f, 0.0f));
    EXPECT_EQ(-1.0f, mc_sign_band_f32(-1e-20f, 0.0f));
    EXPECT_EQ(0.0f, mc_sign_band_f32(0.0f, 0.0f));
}
