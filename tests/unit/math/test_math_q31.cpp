// Unit tests: q31 math kernels and helpers (firmware/kernels/math/mc_q31.h).
//
// Integer kernels are compared with the exact value computed in double
// (a q31 value has 31 bits, double 53: the reference is exact to < 1e-6 LSB
// for the magnitudes used), and with their float32 twins, bounded in LSB.
#include <gtest/gtest.h>

#include <cfloat>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>

#include "math/mc_math.h"
#include "math/mc_q31.h"

namespace
{

constexpr double kPi = 3.14159265358979323846;
constexpr double kQ31 = 2147483648.0; // 2^31
constexpr float kNan = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

// Stated bounds (mc_q31.h), in LSB of q31 (2^-31 ~ 4.66e-10):
// sincos: polynomial fit with Q30 coefficients < 0.03 LSB, six Q30
// Horner roundings and the t^2 rounding give < 1.5 LSB of Q30 = 3 LSB.
constexpr double kSincosQ31BoundLsb = 3.0;
// atan2: CORDIC residual atan(2^-33) = 0.08 LSB, 34 table entries rounded to
// 2^-40 turn (0.07 LSB), final rounding 0.5 LSB, shift truncation of the
// normalised (2^59..2^60) vector negligible: < 1 LSB.
constexpr double kAtan2Q31BoundLsb = 1.0;
// sqrt: rounded to nearest from the exact integer root: 0.5 LSB.
constexpr double kSqrtQ31BoundLsb = 0.5;

// Angle difference in LSB of a q31 angle, folded modulo one turn (2^32).
double angle_lsb_diff(double a, double b)
{
    return std::remainder(a - b, 4294967296.0);
}

} // namespace

// ----------------------------------------------------- saturating helpers

TEST(MathQ31Helpers, SaturateAtRangeEdgesNeverWrap)
{
    EXPECT_EQ(mc_q31_add_sat(MC_Q31_MAX, 1), MC_Q31_MAX);
    EXPECT_EQ(mc_q31_add_sat(MC_Q31_MAX, MC_Q31_MAX), MC_Q31_MAX);
    EXPECT_EQ(mc_q31_add_sat(MC_Q31_MIN, -1), MC_Q31_MIN);
    EXPECT_EQ(mc_q31_add_sat(MC_Q31_MIN, MC_Q31_MIN), MC_Q31_MIN);
    EXPECT_EQ(mc_q31_add_sat(MC_Q31_MAX, MC_Q31_MIN), -1);
    EXPECT_EQ(mc_q31_sub_sat(MC_Q31_MIN, 1), MC_Q31_MIN);
    EXPECT_EQ(mc_q31_sub_sat(MC_Q31_MAX, -1), MC_Q31_MAX);
    EXPECT_EQ(mc_q31_sub_sat(0, MC_Q31_MIN), MC_Q31_MAX);
    EXPECT_EQ(mc_q31_neg_sat(MC_Q31_MIN), MC_Q31_MAX);
    EXPECT_EQ(mc_q31_neg_sat(MC_Q31_MAX), -MC_Q31_MAX);
    EXPECT_EQ(mc_q31_abs_sat(MC_Q31_MIN), MC_Q31_MAX);
    EXPECT_EQ(mc_q31_abs_sat(-5), 5);
    EXPECT_EQ(mc_q31_sat64(INT64_MAX), MC_Q31_MAX);
    EXPECT_EQ(mc_q31_sat64(INT64_MIN), MC_Q31_MIN);
    EXPECT_EQ(mc_q31_sat(7, -3, 3), 3);
    EXPECT_EQ(mc_q31_sat(-7, -3, 3), -3);
}

TEST(MathQ31Helpers, MulMinusOneTimesMinusOneSaturates)
{
    // (-1) * (-1) = +1 is the only product outside the range.
    EXPECT_EQ(mc_q31_mul(MC_Q31_MIN, MC_Q31_MIN), MC_Q31_MAX);
    EXPECT_EQ(mc_q31_mul(MC_Q31_MIN, MC_Q31_MAX), -MC_Q31_MAX);
    EXPECT_EQ(mc_q31_mul(MC_Q31_MAX, MC_Q31_MAX), MC_Q31_MAX - 1);
    EXPECT_EQ(mc_q31_mul(1 << 30, 1 << 30), 1 << 29); // 0.5 * 0.5
}

TEST(MathQ31Helpers, MulRoundsToNearestTiesUp)
{
    EXPECT_EQ(mc_q31_mul(1, 1 << 30), 1);  // +0.5 LSB -> 1
    EXPECT_EQ(mc_q31_mul(-1, 1 << 30), 0); // -0.5 LSB -> 0 (ties up)
    EXPECT_EQ(mc_q31_mul(3, 1 << 29), 1);  // 0.75 LSB -> 1
    EXPECT_EQ(mc_q31_mul(1, 1 << 29), 0);  // 0.25 LSB -> 0
    // Random products: within 0.5 LSB of the exact product (exact rounding).
    std::mt19937 rng(1u);
    std::uniform_int_distribution<int32_t> d(MC_Q31_MIN, MC_Q31_MAX);
    double worst = 0.0;
    for (int i = 0; i < 200000; ++i) {
        const int32_t a = d(rng);
        const int32_t b = d(rng);
        const long double exact = static_cast<long double>(a) * b / 2147483648.0L;
        const double err = static_cast<double>(std::fabs(mc_q31_mul(a, b) - exact));
        worst = std::max(worst, err);
    }
    EXPECT_LE(worst, 0.5);
}

TEST(MathQ31Helpers, AngleAddWrapsExactly)
{
    EXPECT_EQ(mc_q31_angle_add(MC_Q31_MAX, 1), MC_Q31_MIN); // pi wraps to -pi
    EXPECT_EQ(mc_q31_angle_add(MC_Q31_MIN, -1), MC_Q31_MAX);
    EXPECT_EQ(mc_q31_angle_add(1 << 30, 1 << 30), MC_Q31_MIN);
    EXPECT_EQ(mc_q31_angle_add(-5, 3), -2);
}

// ------------------------------------------------------------ conversions

TEST(MathQ31Conv, FromF32SaturatesAndHandlesNaN)
{
    EXPECT_EQ(mc_q31_from_f32(0.0f), 0);
    EXPECT_EQ(mc_q31_from_f32(-0.0f), 0);
    EXPECT_EQ(mc_q31_from_f32(0.5f), 1 << 30);
    EXPECT_EQ(mc_q31_from_f32(-1.0f), MC_Q31_MIN); // exactly representable
    EXPECT_EQ(mc_q31_from_f32(1.0f), MC_Q31_MAX);  // saturates (never wraps)
    EXPECT_EQ(mc_q31_from_f32(2.0f), MC_Q31_MAX);
    EXPECT_EQ(mc_q31_from_f32(-2.0f), MC_Q31_MIN);
    EXPECT_EQ(mc_q31_from_f32(-1.0000001f), MC_Q31_MIN);
    EXPECT_EQ(mc_q31_from_f32(FLT_MAX), MC_Q31_MAX);
    EXPECT_EQ(mc_q31_from_f32(-FLT_MAX), MC_Q31_MIN);
    EXPECT_EQ(mc_q31_from_f32(kInf), MC_Q31_MAX);
    EXPECT_EQ(mc_q31_from_f32(-kInf), MC_Q31_MIN);
    EXPECT_EQ(mc_q31_from_f32(kNan), 0);
    EXPECT_EQ(mc_q31_from_f32(-kNan), 0);
    // Largest float below 1 is exactly 2^31 - 128: converted, not saturated.
    EXPECT_EQ(mc_q31_from_f32(std::nextafter(1.0f, 0.0f)), 2147483520);
    EXPECT_EQ(mc_q31_from_f32(std::nextafter(-1.0f, 0.0f)), -2147483520);
}

TEST(MathQ31Conv, FromF32RoundsToNearestTiesAway)
{
    const float lsb = std::ldexp(1.0f, -31);
    EXPECT_EQ(mc_q31_from_f32(0.5f * lsb), 1); // tie -> away from zero
    EXPECT_EQ(mc_q31_from_f32(-0.5f * lsb), -1);
    EXPECT_EQ(mc_q31_from_f32(0.25f * lsb), 0);
    EXPECT_EQ(mc_q31_from_f32(0.75f * lsb), 1);
    EXPECT_EQ(mc_q31_from_f32(-0.75f * lsb), -1);
    EXPECT_EQ(mc_q31_from_f32(1.5f * lsb), 2);
    EXPECT_EQ(mc_q31_from_f32(2.5f * lsb), 3);
    EXPECT_EQ(mc_q31_from_f32(std::ldexp(1.0f, -140)), 0); // denormal
    // Dense: within 0.5 LSB of x * 2^31 (exact in double), 1e6 values of
    // all magnitudes in (-1, 1).
    std::mt19937 rng(2u);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    std::uniform_int_distribution<int> e(-40, 0);
    double worst = 0.0;
    for (int i = 0; i < 1000000; ++i) {
        const float x = std::ldexp(u(rng), e(rng));
        const double err = std::fabs(mc_q31_from_f32(x) - static_cast<double>(x) * kQ31);
        worst = std::max(worst, err);
    }
    EXPECT_LE(worst, 0.5);
}

TEST(MathQ31Conv, ToF32AndRoundTrip)
{
    EXPECT_EQ(mc_q31_to_f32(MC_Q31_MIN), -1.0f);
    EXPECT_EQ(mc_q31_to_f32(MC_Q31_MAX), 1.0f); // 1 - 2^-31 rounds to 1.0f
    EXPECT_EQ(mc_q31_to_f32(0), 0.0f);
    EXPECT_EQ(mc_q31_to_f32(1), std::ldexp(1.0f, -31));
    EXPECT_EQ(mc_q31_to_f32(1 << 30), 0.5f);
    // Exact to float rounding: equals the double value rounded to float.
    for (int64_t q = MC_Q31_MIN; q <= MC_Q31_MAX; q += 65537) {
        const q31_t v = static_cast<q31_t>(q);
        EXPECT_EQ(mc_q31_to_f32(v), static_cast<float>(static_cast<double>(v) / kQ31)) << v;
    }
    // Round trip f32 -> q31 -> f32 is exact for |x| >= 2^-8 (then x has at
    // most 31 fraction bits) and x < 1.
    std::mt19937 rng(3u);
    std::uniform_real_distribution<float> u(0.00390625f, 1.0f);
    for (int i = 0; i < 100000; ++i) {
        float x = u(rng);
        if (x >= 1.0f) {
            continue;
        }
        x = (i & 1) ? -x : x;
        ASSERT_EQ(mc_q31_to_f32(mc_q31_from_f32(x)), x);
    }
}

TEST(MathQ15Conv, FromF32RoundsAndSaturates)
{
    EXPECT_EQ(mc_q15_from_f32(0.5f), 16384);
    EXPECT_EQ(mc_q15_from_f32(-1.0f), MC_Q15_MIN);
    EXPECT_EQ(mc_q15_from_f32(1.0f), MC_Q15_MAX);
    EXPECT_EQ(mc_q15_from_f32(1.0f - std::ldexp(1.0f, -16)),
              MC_Q15_MAX); // rounds to 2^15: saturates
    EXPECT_EQ(mc_q15_from_f32(-1.5f), MC_Q15_MIN);
    EXPECT_EQ(mc_q15_from_f32(1e30f), MC_Q15_MAX);
    EXPECT_EQ(mc_q15_from_f32(-kInf), MC_Q15_MIN);
    EXPECT_EQ(mc_q15_from_f32(kNan), 0);
    EXPECT_EQ(mc_q15_from_f32(std::ldexp(1.0f, -16)), 1); // 0.5 LSB, ties away
    EXPECT_EQ(mc_q15_from_f32(-std::ldexp(1.0f, -16)), -1);
    EXPECT_EQ(mc_q15_from_f32(std::ldexp(1.0f, -17)), 0); // 0.25 LSB
    for (int i = -40000; i <= 40000; ++i) {
        const float x = static_cast<float>(i) / 32768.0f + 1e-7f;
        const double exact = static_cast<double>(x) * 32768.0;
        const double clamped = std::min(32767.0, std::max(-32768.0, std::round(exact)));
        ASSERT_EQ(mc_q15_from_f32(x), static_cast<q15_t>(clamped)) << x;
    }
}

TEST(MathQ31Angle, FromRadWrapsAndRounds)
{
    EXPECT_EQ(mc_q31_angle_from_rad_f32(0.0f), 0);
    EXPECT_EQ(mc_q31_angle_from_rad_f32(kNan), 0);
    EXPECT_EQ(mc_q31_angle_from_rad_f32(kInf), 0);
    EXPECT_EQ(mc_q31_angle_from_rad_f32(-kInf), 0);
    // (float)pi is 8.7e-8 rad above pi: it wraps to just above -pi
    // (8.7e-8 rad = 60 LSB).
    EXPECT_EQ(mc_q31_angle_from_rad_f32(MC_PI_F32), MC_Q31_MIN + 60);
    EXPECT_EQ(mc_q31_angle_from_rad_f32(-MC_PI_F32), MC_Q31_MAX - 59);
    // Dense: the exact x * 2^31 / pi modulo 2^32, rounded: within 0.5 LSB
    // (+ 1e-3 LSB for the long double reference, 2^-64 relative).
    const long double scale = 2147483648.0L / 3.14159265358979323846264338L;
    double worst = 0.0;
    const int n = 1000000;
    for (int i = 0; i <= n; ++i) {
        const float x = static_cast<float>(-8192.0 + 16384.0 * i / n);
        const long double ref = static_cast<long double>(x) * scale;
        const double err =
            std::fabs(angle_lsb_diff(static_cast<double>(mc_q31_angle_from_rad_f32(x)),
                                     static_cast<double>(std::remainder(ref, 4294967296.0L))));
        worst = std::max(worst, err);
    }
    EXPECT_LE(worst, 0.5 + 1e-3);
}

TEST(MathQ31Angle, ToRadWithinBoundAndRange)
{
    // Two float roundings (int32 -> float: 2^-24 relative, i.e. <= 1.9e-7
    // rad near pi; the product: half an ulp of pi, 1.2e-7): <= 3.2e-7 rad.
    const double bound = 3.2e-7;
    double worst = 0.0;
    bool range_ok = true;
    for (int64_t a = MC_Q31_MIN; a <= MC_Q31_MAX; a += 4099) {
        const float r = mc_q31_angle_to_rad_f32(static_cast<q31_t>(a));
        range_ok = range_ok && (r >= -MC_PI_F32) && (r < MC_PI_F32);
        const double err =
            std::fabs(std::remainder(static_cast<double>(r) - a * kPi / kQ31, 2.0 * kPi));
        worst = std::max(worst, err);
    }
    for (q31_t a : {MC_Q31_MAX, MC_Q31_MIN, 0, 1, -1, MC_Q31_MAX - 64}) {
        const float r = mc_q31_angle_to_rad_f32(a);
        range_ok = range_ok && (r >= -MC_PI_F32) && (r < MC_PI_F32);
        worst = std::max(
            worst, std::fabs(std::remainder(static_cast<double>(r) - a * kPi / kQ31, 2.0 * kPi)));
    }
    EXPECT_TRUE(range_ok);
    EXPECT_LE(worst, bound);
    EXPECT_EQ(mc_q31_angle_to_rad_f32(MC_Q31_MIN), -MC_PI_F32);
    EXPECT_EQ(mc_q31_angle_to_rad_f32(1 << 30), MC_HALF_PI_F32);
}

// ------------------------------------------------------------------ sincos

TEST(MathSincosQ31, FullTurnSweepWithinBound)
{
    // 4.3e6 angles spread over the whole int32 range (stride 997, prime, so
    // every residue pattern of the low bits is visited) plus all 2^16 angles
    // around each quadrant boundary.
    double worst = 0.0;
    int64_t worst_a = 0;
    auto check = [&](int64_t a) {
        q31_t s = 0;
        q31_t c = 0;
        mc_sincos_q31(static_cast<q31_t>(a), &s, &c);
        const double th = static_cast<double>(a) * kPi / kQ31;
        const double es = std::fabs(s - std::min(std::sin(th) * kQ31, kQ31 - 1.0));
        const double ec = std::fabs(c - std::min(std::cos(th) * kQ31, kQ31 - 1.0));
        if (std::max(es, ec) > worst) {
            worst = std::max(es, ec);
            worst_a = a;
        }
    };
    for (int64_t a = MC_Q31_MIN; a <= MC_Q31_MAX; a += 997) {
        check(a);
    }
    for (int64_t b : {-2147483648LL, -1610612736LL, -1073741824LL, -536870912LL, 0LL, 536870912LL,
                      1073741824LL, 1610612736LL, 2147483647LL}) {
        for (int64_t d = -32768; d <= 32768; ++d) {
            const int64_t a = b + d;
            if (a >= MC_Q31_MIN && a <= MC_Q31_MAX) {
                check(a);
            }
        }
    }
    // The reference is clamped at 1 - 2^-31 (what q31 can hold), so a
    // saturated +1 does not count as an error.
    EXPECT_LE(worst, kSincosQ31BoundLsb) << "worst angle = " << worst_a;
}

TEST(MathSincosQ31, QuadrantValues)
{
    q31_t s = 1;
    q31_t c = 1;
    mc_sincos_q31(0, &s, &c);
    EXPECT_EQ(s, 0);
    EXPECT_EQ(c, MC_Q31_MAX);       // +1 saturates
    mc_sincos_q31(1 << 30, &s, &c); // +pi/2
    EXPECT_EQ(s, MC_Q31_MAX);
    EXPECT_EQ(c, 0);
    mc_sincos_q31(-(1 << 30), &s, &c); // -pi/2
    EXPECT_EQ(s, MC_Q31_MIN);          // -1 is exact
    EXPECT_EQ(c, 0);
    mc_sincos_q31(MC_Q31_MIN, &s, &c); // -pi
    EXPECT_EQ(s, 0);
    EXPECT_EQ(c, MC_Q31_MIN);
    // pi/6: sin = 0.5 exactly = 2^30, within the stated bound.
    mc_sincos_q31(357913941, &s, &c);                  // round(2^31 / 6)
    EXPECT_NEAR(s, 1 << 30, kSincosQ31BoundLsb + 2.0); // + angle rounding (1/3 LSB * pi * cos)
}

TEST(MathSincosQ31, PythagoreanIdentity)
{
    // s = S + e1, c = C + e2 with |e| <= 3 LSB: |s^2 + c^2 - 1| <=
    // 2 (|S| + |C|) 3 LSB + 18 LSB^2 <= 2 sqrt(2) * 3 LSB = 8.5 LSB (2^-31).
    const double bound = 2.0 * std::sqrt(2.0) * kSincosQ31BoundLsb + 1e-6;
    double worst = 0.0;
    for (int64_t a = MC_Q31_MIN; a <= MC_Q31_MAX; a += 10007) {
        q31_t s = 0;
        q31_t c = 0;
        mc_sincos_q31(static_cast<q31_t>(a), &s, &c);
        const double sd = s / kQ31;
        const double cd = c / kQ31;
        worst = std::max(worst, std::fabs(sd * sd + cd * cd - 1.0) * kQ31);
    }
    EXPECT_LE(worst, bound);
}

TEST(MathSincosQ31, MatchesF32TwinInLsb)
{
    // f32 twin on the same angle: mc_sincos_f32(mc_q31_angle_to_rad_f32(a)).
    // Difference <= f32 bound 2e-7 + angle conversion 3.2e-7 (|d sin| <= |d
    // theta|) + q31 bound 3 LSB = 5.2e-7 * 2^31 + 3 = 1120 LSB.
    const double bound = (2e-7 + 3.2e-7) * kQ31 + kSincosQ31BoundLsb;
    double worst = 0.0;
    for (int64_t a = MC_Q31_MIN; a <= MC_Q31_MAX; a += 2003) {
        q31_t s = 0;
        q31_t c = 0;
        mc_sincos_q31(static_cast<q31_t>(a), &s, &c);
        float sf = 0.0f;
        float cf = 0.0f;
        mc_sincos_f32(mc_q31_angle_to_rad_f32(static_cast<q31_t>(a)), &sf, &cf);
        worst = std::max(worst, std::fabs(s - static_cast<double>(sf) * kQ31));
        worst = std::max(worst, std::fabs(c - static_cast<double>(cf) * kQ31));
    }
    EXPECT_LE(worst, bound);
}

// ------------------------------------------------------------------- atan2

TEST(MathAtan2Q31, SweepAllQuadrantsAndMagnitudes)
{
    // 1e6 directions; magnitudes from 100 LSB to full scale (scale does
    // not matter: the kernel normalises). Reference atan2 of the same
    // integers, in LSB of angle.
    double worst = 0.0;
    const int n = 1000000;
    const double radii[] = {100.0, 12345.0, 1e7, 2.1e9};
    for (int i = 0; i < n; ++i) {
        const double th = -kPi + 2.0 * kPi * (i + 0.5) / n;
        const double r = radii[i % 4];
        const q31_t y = static_cast<q31_t>(std::lround(r * std::sin(th)));
        const q31_t x = static_cast<q31_t>(std::lround(r * std::cos(th)));
        if (x == 0 && y == 0) {
            continue;
        }
        const double ref = std::atan2(static_cast<double>(y), static_cast<double>(x)) / kPi * kQ31;
        worst = std::max(worst, std::fabs(angle_lsb_diff(mc_atan2_q31(y, x), ref)));
    }
    // Random pairs over the full int32 range, incl. MIN.
    std::mt19937 rng(8u);
    std::uniform_int_distribution<int32_t> d(MC_Q31_MIN, MC_Q31_MAX);
    for (int i = 0; i < 300000; ++i) {
        const q31_t y = d(rng);
        const q31_t x = (i % 3 == 0) ? static_cast<q31_t>(d(rng) >> (i % 31)) : d(rng);
        if (x == 0 && y == 0) {
            continue;
        }
        const double ref = std::atan2(static_cast<double>(y), static_cast<double>(x)) / kPi * kQ31;
        worst = std::max(worst, std::fabs(angle_lsb_diff(mc_atan2_q31(y, x), ref)));
    }
    EXPECT_LE(worst, kAtan2Q31BoundLsb);
}

TEST(MathAtan2Q31, EdgeCases)
{
    EXPECT_EQ(mc_atan2_q31(0, 0), 0);
    EXPECT_EQ(mc_atan2_q31(0, 1), 0);
    EXPECT_EQ(mc_atan2_q31(0, MC_Q31_MAX), 0);
    EXPECT_EQ(mc_atan2_q31(0, -1), MC_Q31_MIN); // pi is -pi in [-pi, pi)
    EXPECT_EQ(mc_atan2_q31(0, MC_Q31_MIN), MC_Q31_MIN);
    EXPECT_EQ(mc_atan2_q31(1, 0), 1 << 30);
    EXPECT_EQ(mc_atan2_q31(MC_Q31_MIN, 0), -(1 << 30));
    EXPECT_EQ(mc_atan2_q31(MC_Q31_MAX, MC_Q31_MAX), 1 << 29); // 45 deg
    EXPECT_EQ(mc_atan2_q31(1, 1), 1 << 29);
    EXPECT_EQ(mc_atan2_q31(MC_Q31_MIN, MC_Q31_MIN), -1610612736); // -135 deg
    EXPECT_EQ(mc_atan2_q31(-7, 7), -(1 << 29));
    // Tiny angle: atan(1 / (2^31 - 1)) = 0.32 LSB -> 0.
    EXPECT_EQ(mc_atan2_q31(1, MC_Q31_MAX), 0);
    // Just below -pi on the negative x axis: y = -1, x = MIN -> -pi + 0.32 LSB.
    EXPECT_EQ(mc_atan2_q31(-1, MC_Q31_MIN), MC_Q31_MIN);
}

TEST(MathAtan2Q31, MatchesF32Twin)
{
    // f32 twin on the same inputs converted with mc_q31_to_f32: difference
    // <= f32 bound 5e-7 rad + the input rounding (2^-24 relative on each
    // component turns the direction by <= 2^-24 * sqrt(2) = 8.4e-8 rad)
    // + q31 bound 1 LSB (1.5e-9 rad) = 5.9e-7 rad.
    const double bound = 5e-7 + 8.4e-8 + kAtan2Q31BoundLsb * kPi / kQ31;
    double worst = 0.0;
    std::mt19937 rng(9u);
    std::uniform_int_distribution<int32_t> d(MC_Q31_MIN, MC_Q31_MAX);
    for (int i = 0; i < 300000; ++i) {
        const q31_t y = d(rng);
        const q31_t x = d(rng);
        const double aq = mc_atan2_q31(y, x) * kPi / kQ31;
        const double af = static_cast<double>(mc_atan2_f32(mc_q31_to_f32(y), mc_q31_to_f32(x)));
        worst = std::max(worst, std::fabs(std::remainder(aq - af, 2.0 * kPi)));
    }
    EXPECT_LE(worst, bound);
}

// -------------------------------------------------------------------- sqrt

TEST(MathSqrtQ31, RoundedToNearestOverFullRange)
{
    double worst = 0.0;
    auto check = [&](int64_t x) {
        const long double exact = std::sqrt(static_cast<long double>(x) * 2147483648.0L);
        const double err =
            static_cast<double>(std::fabs(mc_sqrt_q31(static_cast<q31_t>(x)) - exact));
        worst = std::max(worst, err);
    };
    for (int64_t x = 1; x <= MC_Q31_MAX; x += 2039) {
        check(x);
    }
    for (int64_t x = 1; x < 100000; ++x) {
        check(x);
    }
    for (int64_t x = MC_Q31_MAX - 100000; x <= MC_Q31_MAX; ++x) {
        check(x);
    }
    // long double sqrt (64-bit significand) is exact to < 1e-9 LSB here.
    EXPECT_LE(worst, kSqrtQ31BoundLsb + 1e-6);
}

TEST(MathSqrtQ31, EdgeCases)
{
    EXPECT_EQ(mc_sqrt_q31(0), 0);
    EXPECT_EQ(mc_sqrt_q31(-1), 0);
    EXPECT_EQ(mc_sqrt_q31(MC_Q31_MIN), 0);
    EXPECT_EQ(mc_sqrt_q31(1 << 29), 1 << 30); // sqrt(0.25) = 0.5
    EXPECT_EQ(mc_sqrt_q31(1), 46341);         // sqrt(2^31) = 46340.95
    EXPECT_EQ(mc_sqrt_q31(MC_Q31_MAX), MC_Q31_MAX);
}

TEST(MathSqrtQ31, MatchesF32Twin)
{
    // f32 twin: mc_sqrt_f32(mc_q31_to_f32(x)). The input rounding (2^-24
    // relative) moves sqrt by 2^-25 relative, the result rounding by half
    // an ulp (<= 2^-25 below 1): <= 2^-24 = 128 LSB, + 0.5 LSB (q31 bound).
    const double bound = 128.0 + kSqrtQ31BoundLsb;
    double worst = 0.0;
    for (int64_t x = 0; x <= MC_Q31_MAX; x += 4093) {
        const double q = mc_sqrt_q31(static_cast<q31_t>(x));
        const double f =
            static_cast<double>(mc_sqrt_f32(mc_q31_to_f32(static_cast<q31_t>(x)))) * kQ31;
        worst = std::max(worst, std::fabs(q - f));
    }
    EXPECT_LE(worst, bound);
}
