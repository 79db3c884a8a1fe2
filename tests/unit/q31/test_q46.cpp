// mc_q46: gains and the Q46 accumulator shared by the q31 kernels.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "q31_test_util.hpp"

extern "C" {
#include "math/mc_q46.h"
}

using namespace q31t;

namespace
{
constexpr double kQ46 = 70368744177664.0; // 2^46
double q46_val(int64_t a)
{
    return static_cast<double>(a) / kQ46;
}
} // namespace

TEST(Q46, GainHoldsTheFloatExactly)
{
    // Every float in the accepted range converts without rounding: the
    // normalised mantissa has 31 bits, a float 24.
    std::mt19937 rng(1);
    std::uniform_real_distribution<float> m(-1.0f, 1.0f);
    std::uniform_int_distribution<int> e(-40, 29);
    for (int i = 0; i < 20000; ++i) {
        const float g = std::ldexp(m(rng), e(rng));
        if (std::abs(g) < 7.2e-15f)
            continue; // below 2^-47: 0 by design
        mc_q46_gain_t q;
        ASSERT_TRUE(mc_q46_gain_from_f32(g, &q));
        EXPECT_EQ(mc_q46_gain_to_f32(q), g);
    }
    mc_q46_gain_t q;
    EXPECT_FALSE(mc_q46_gain_from_f32(1073741824.0f, &q)); // 2^30: out of range
    EXPECT_FALSE(mc_q46_gain_from_f32(std::nanf(""), &q));
    EXPECT_FALSE(mc_q46_gain_from_f32(INFINITY, &q));
    EXPECT_TRUE(mc_q46_gain_from_f32(0.0f, &q));
    EXPECT_EQ(q.mant, 0);
}

TEST(Q46, ProductsWithinOneQ46LsbOfExact)
{
    // mul_q31 rounds once (<= 0.5 LSB of Q46); mul rounds twice (<= 1 LSB).
    std::mt19937 rng(2);
    std::uniform_real_distribution<float> m(-1.0f, 1.0f);
    std::uniform_int_distribution<int> e(-30, 12);
    std::uniform_int_distribution<int32_t> x(MC_Q31_MIN, MC_Q31_MAX);
    std::uniform_real_distribution<double> a(-2000.0, 2000.0);
    double worst1 = 0.0, worst2 = 0.0;
    for (int i = 0; i < 50000; ++i) {
        const float gf = std::ldexp(m(rng), e(rng));
        mc_q46_gain_t g;
        ASSERT_TRUE(mc_q46_gain_from_f32(gf, &g));
        const q31_t xi = x(rng);
        const double exact1 = static_cast<double>(gf) * static_cast<double>(xi) / kQ31 * kQ46;
        if (std::abs(exact1) < 4.0e18) {
            // long double: 64-bit mantissa holds the exact product here
            const long double ex =
                static_cast<long double>(gf) * xi / 2147483648.0L * 70368744177664.0L;
            worst1 = std::max(worst1, static_cast<double>(std::fabs(
                                          static_cast<long double>(mc_q46_mul_q31(g, xi)) - ex)));
        }
        const int64_t ai = static_cast<int64_t>(a(rng) * kQ46);
        const long double ex2 = static_cast<long double>(gf) * static_cast<long double>(ai);
        if (std::fabs(ex2) < 4.0e18L) {
            worst2 = std::max(worst2, static_cast<double>(std::fabs(
                                          static_cast<long double>(mc_q46_mul(g, ai)) - ex2)));
        }
    }
    report("q46 mul_q31 max error", worst1, 0.5, "Q46 LSB");
    report("q46 mul max error", worst2, 1.0, "Q46 LSB");
    EXPECT_LE(worst1, 0.5);
    EXPECT_LE(worst2, 1.0);
}

TEST(Q46, SaturatesAtTheRangeEdgesNeverWraps)
{
    mc_q46_gain_t big;
    ASSERT_TRUE(mc_q46_gain_from_f32(1.0e9f, &big));
    EXPECT_EQ(mc_q46_mul_q31(big, MC_Q31_MAX), MC_Q46_LIM);
    EXPECT_EQ(mc_q46_mul_q31(big, MC_Q31_MIN), -MC_Q46_LIM);
    EXPECT_EQ(mc_q46_mul(big, MC_Q46_LIM), MC_Q46_LIM);
    EXPECT_EQ(mc_q46_mul(big, -MC_Q46_LIM), -MC_Q46_LIM);
    EXPECT_EQ(mc_q46_mul(big, INT64_MAX), MC_Q46_LIM); // input saturated first
    EXPECT_EQ(mc_q46_mul(big, INT64_MIN), -MC_Q46_LIM);
    mc_q46_gain_t neg;
    ASSERT_TRUE(mc_q46_gain_from_f32(-1.0e9f, &neg));
    EXPECT_EQ(mc_q46_mul_q31(neg, MC_Q31_MIN), MC_Q46_LIM);
    EXPECT_EQ(mc_q46_add(MC_Q46_LIM, MC_Q46_LIM), MC_Q46_LIM);
    EXPECT_EQ(mc_q46_add(-MC_Q46_LIM, -MC_Q46_LIM), -MC_Q46_LIM);
    EXPECT_EQ(mc_q46_to_q31(MC_Q46_LIM), MC_Q31_MAX);
    EXPECT_EQ(mc_q46_to_q31(-MC_Q46_LIM), MC_Q31_MIN);
    EXPECT_EQ(mc_q46_to_q31(mc_q46_from_q31(MC_Q31_MIN)), MC_Q31_MIN);
    EXPECT_EQ(mc_q46_mul_q46(MC_Q46_LIM, MC_Q46_LIM), MC_Q46_LIM);
    EXPECT_EQ(mc_q46_mul_q46(MC_Q46_LIM, -MC_Q46_LIM), -MC_Q46_LIM);
}

TEST(Q46, LimitVecKeepsDirectionAndLength)
{
    // Scaled vectors have length lim to 2^-30 relative (the factor is q31,
    // the length is the integer root of 30+ bit components), direction to
    // the same; short vectors are untouched.
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-3000.0, 3000.0);
    std::uniform_real_distribution<double> l(1e-3, 100.0);
    double worst_len = 0.0, worst_dir = 0.0;
    for (int i = 0; i < 20000; ++i) {
        const double a = u(rng), b = u(rng), lim = l(rng);
        int64_t ai = static_cast<int64_t>(a * kQ46), bi = static_cast<int64_t>(b * kQ46);
        const int64_t li = static_cast<int64_t>(lim * kQ46);
        const double len = std::hypot(q46_val(ai), q46_val(bi));
        const int64_t a0 = ai, b0 = bi;
        const bool s = mc_q46_limit_vec(&ai, &bi, li);
        if (len > q46_val(li) * (1.0 + 1e-8)) {
            ASSERT_TRUE(s);
            worst_len = std::max(
                worst_len, std::abs(std::hypot(q46_val(ai), q46_val(bi)) / q46_val(li) - 1.0));
            worst_dir = std::max(worst_dir, std::abs(std::atan2(q46_val(bi), q46_val(ai)) -
                                                     std::atan2(q46_val(b0), q46_val(a0))));
        } else if (!s) {
            EXPECT_EQ(ai, a0);
            EXPECT_EQ(bi, b0);
        }
    }
    report("limit_vec relative length error", worst_len, 2e-9, "1");
    report("limit_vec direction error", worst_dir, 2e-9, "rad");
    EXPECT_LE(worst_len, 2e-9);
    EXPECT_LE(worst_dir, 2e-9);
    int64_t a = MC_Q46_LIM, b = -MC_Q46_LIM;
    EXPECT_TRUE(mc_q46_limit_vec(&a, &b, MC_Q46_ONE));
    EXPECT_NEAR(q46_val(a), std::sqrt(0.5), 1e-9);
    EXPECT_NEAR(q46_val(b), -std::sqrt(0.5), 1e-9);
}
