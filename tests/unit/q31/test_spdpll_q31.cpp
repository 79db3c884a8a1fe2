// PLL speed estimator: q31 twin against the f32 kernel.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "q31_test_util.hpp"

extern "C" {
#include "observer/mc_spdpll_q31.h"
}

using namespace q31t;

namespace {
constexpr double kWb = 2000.0;  // speed base [rad/s]
mc_spdpll_q31_cfg_t cfg(float bw, float dt, float wmax) {
    return mc_spdpll_q31_cfg_t{{bw, dt, wmax}, static_cast<float>(kWb)};
}
}  // namespace

TEST(SpdpllQ31, InitRules)
{
    mc_spdpll_q31_t q{};
    q.omega = 99;
    mc_spdpll_q31_cfg_t c = cfg(300.0f, 1.25e-4f, 1000.0f);
    c.omega_base_rad_s = -1.0f;
    EXPECT_EQ(mc_spdpll_q31_init(&q, &c), MC_SPDPLL_ERR_SCALE);
    c.omega_base_rad_s = 2000.0f;
    c.f.bw_rad_s = 2000.0f;  // bw dt > 0.1: the f32 rule
    EXPECT_EQ(mc_spdpll_q31_init(&q, &c), MC_SPDPLL_ERR_BW);
    EXPECT_EQ(q.omega, 99);
    c.f.bw_rad_s = 300.0f;
    EXPECT_EQ(mc_spdpll_q31_init(&q, &c), 0u);
}

TEST(SpdpllQ31, MatchesF32OnNoisyRamps)
{
    // Angle of a rotor accelerating from 0 to 800 rad/s and back, with
    // +-0.05 rad noise, wrapping thousands of times. Inputs are the same
    // angle for both (the q31 angle converted to float rad).
    const mc_spdpll_q31_cfg_t c = cfg(300.0f, 1.25e-4f, 1500.0f);
    mc_spdpll_f32_t f{};
    mc_spdpll_q31_t q{};
    ASSERT_EQ(mc_spdpll_f32_init(&f, &c.f), 0u);
    ASSERT_EQ(mc_spdpll_q31_init(&q, &c), 0u);
    std::mt19937 rng(20);
    std::uniform_real_distribution<double> n(-0.05, 0.05);
    double th = 0.0, w = 0.0, worst_w = 0.0, worst_th = 0.0;
    const double dt = 1.25e-4;
    for (int k = 0; k < 80000; ++k) {
        const double t = k * dt;
        const double acc = (t < 4.0) ? 200.0 : -200.0;
        w += acc * dt;
        th += w * dt;
        const q31_t aq = ang_q(th + n(rng));
        const float af = static_cast<float>(ang_rad(aq));
        const double wf = mc_spdpll_f32_step(&f, af);
        const double wq = from_q(mc_spdpll_q31_step(&q, aq), kWb);
        worst_w = std::max(worst_w, std::abs(wf - wq));
        worst_th = std::max(worst_th, ang_diff(f.theta_rad, ang_rad(q.theta)));
    }
    // Bound: the f32 kernel rounds its angle to float every step (ulp of pi
    // 2.4e-7 rad; mc_wrap_pi_f32 and the product add a few ulp); through kp
    // = 600 that is ~1e-4..1e-3 rad/s of speed jitter. q31: 2^-63 turn.
    const double bound_w = 2.0e-3;     // rad/s (2.1 LSB of a 2000 rad/s base)
    const double bound_th = 2.0e-6;    // rad (1400 LSB of the q31 turn)
    report("spdpll |w_f32 - w_q31|", worst_w, bound_w, "rad/s");
    report("spdpll same in LSB of the speed base", worst_w / kWb * kQ31, bound_w / kWb * kQ31, "LSB");
    report("spdpll |theta_f32 - theta_q31|", worst_th, bound_th, "rad");
    EXPECT_LE(worst_w, bound_w);
    EXPECT_LE(worst_th, bound_th);
}

TEST(SpdpllQ31, SaturatesAtOmegaMaxNeverWraps)
{
    // A rotor at 1.5x omega_max: the loop cannot follow (it slips cycles,
    // as the f32 kernel does), but the speed never leaves +-omega_max and
    // SAT is raised. Then omega_max above the base: the limit is the q31
    // range itself; a rotor beyond it drives the speed to -(1 - 2^-31)
    // base, never past it (a wrap would show as a positive speed).
    const mc_spdpll_q31_cfg_t c = cfg(300.0f, 1.25e-4f, 1000.0f);
    mc_spdpll_q31_t q{};
    ASSERT_EQ(mc_spdpll_q31_init(&q, &c), 0u);
    double th = 0.0;
    q31_t w = 0, wmax = 0;
    for (int k = 0; k < 20000; ++k) {
        th += 1500.0 * 1.25e-4;
        w = mc_spdpll_q31_step(&q, ang_q(th));
        wmax = std::max(wmax, w);
        ASSERT_LE(std::abs(from_q(w, kWb)), 1000.0 + kWb / kQ31);
    }
    EXPECT_NE(q.flags & MC_SPDPLL_ERR_SAT, 0u);
    EXPECT_NEAR(from_q(wmax, kWb), 1000.0, 2.0 * kWb / kQ31);
    const mc_spdpll_q31_cfg_t c2 = cfg(300.0f, 1.25e-4f, 5000.0f);  // clamped to one base
    ASSERT_EQ(mc_spdpll_q31_init(&q, &c2), 0u);
    mc_spdpll_q31_reset(&q, 0, MC_Q31_MIN);
    EXPECT_EQ(q.omega, -MC_Q31_MAX);  // the preset is clamped too
    th = 0.0;
    q31_t wmin = 0;
    for (int k = 0; k < 400; ++k) {
        th -= 0.1;  // 800 rad/s backwards, then the PLL is pushed at its limit
        w = mc_spdpll_q31_step(&q, ang_q(th));
        wmin = std::min(wmin, w);
        ASSERT_GE(w, -MC_Q31_MAX);
    }
    EXPECT_LT(from_q(wmin, kWb), -700.0);
}
