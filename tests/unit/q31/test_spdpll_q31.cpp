// PLL speed estimator: q31 twin against the f32 kernel.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "q31_test_util.hpp"

extern "C" {
#include "observer/mc_spdpll_q31.h"
}

using namespace q31t;

namespace
{
constexpr double kWb = 2000.0; // speed base [rad/s]
mc_spdpll_q31_cfg_t cfg(float bw, float dt, float wmax)
{
    return mc_spdpll_q31_cfg_t{{bw, dt, wmax}, static_cast<float>(kWb)};
}
// One step of each twin: the speed; the bits returned are the ones raised
// (each also in the sticky flags), never NULL here.
double step_f(mc_spdpll_f32_t *f, float th)
{
    float w = NAN;
    const uint32_t rc = mc_spdpll_f32_step(f, th, &w);
    EXPECT_EQ(rc & ~f->flags, 0u);
    EXPECT_EQ(rc & MC_SPDPLL_ERR_NULL, 0u);
    return w;
}
q31_t step_q(mc_spdpll_q31_t *q, q31_t th, uint32_t *p_rc = nullptr)
{
    q31_t w = 0x5A5A5A5A;
    const uint32_t rc = mc_spdpll_q31_step(q, th, &w);
    EXPECT_EQ(rc & ~q->flags, 0u);
    EXPECT_EQ(rc & MC_SPDPLL_ERR_NULL, 0u);
    if (p_rc != nullptr) {
        *p_rc = rc;
    }
    return w;
}
} // namespace

TEST(SpdpllQ31, InitRules)
{
    mc_spdpll_q31_t q{};
    q.omega = 99;
    mc_spdpll_q31_cfg_t c = cfg(300.0f, 1.25e-4f, 1000.0f);
    c.omega_base_rad_s = -1.0f;
    EXPECT_EQ(mc_spdpll_q31_init(&q, &c), MC_SPDPLL_ERR_SCALE);
    c.omega_base_rad_s = 2000.0f;
    c.f.bw_rad_s = 2000.0f; // bw dt > 0.1: the f32 rule
    EXPECT_EQ(mc_spdpll_q31_init(&q, &c), MC_SPDPLL_ERR_BW);
    EXPECT_EQ(q.omega, 99);
    c.f.bw_rad_s = 300.0f;
    EXPECT_EQ(mc_spdpll_q31_init(&q, &c), 0u);
    // NULL state or output: MC_SPDPLL_ERR_NULL, nothing written.
    const mc_spdpll_q31_t before = q;
    q31_t w = 42;
    EXPECT_EQ(mc_spdpll_q31_step(nullptr, 1, &w), MC_SPDPLL_ERR_NULL);
    EXPECT_EQ(w, 42);
    EXPECT_EQ(mc_spdpll_q31_step(&q, 1, nullptr), MC_SPDPLL_ERR_NULL);
    EXPECT_EQ(q.theta_turn64, before.theta_turn64);
    EXPECT_EQ(q.omega_i_q46, before.omega_i_q46);
    EXPECT_EQ(mc_spdpll_q31_reset(nullptr, 0, 0), MC_SPDPLL_ERR_NULL);
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
        const double wf = step_f(&f, af);
        const double wq = from_q(step_q(&q, aq), kWb);
        worst_w = std::max(worst_w, std::abs(wf - wq));
        worst_th = std::max(worst_th, ang_diff(f.theta_rad, ang_rad(q.theta)));
    }
    // Bound: the f32 kernel rounds its angle to float every step (ulp of pi
    // 2.4e-7 rad; mc_wrap_pi_f32 and the product add a few ulp); through kp
    // = 600 that is ~1e-4..1e-3 rad/s of speed jitter. q31: 2^-63 turn.
    const double bound_w = 2.0e-3;  // rad/s (2.1 LSB of a 2000 rad/s base)
    const double bound_th = 2.0e-6; // rad (1400 LSB of the q31 turn)
    report("spdpll |w_f32 - w_q31|", worst_w, bound_w, "rad/s");
    report("spdpll same in LSB of the speed base", worst_w / kWb * kQ31, bound_w / kWb * kQ31,
           "LSB");
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
    uint32_t rc_any = 0u;
    for (int k = 0; k < 20000; ++k) {
        th += 1500.0 * 1.25e-4;
        uint32_t rc = 0u;
        w = step_q(&q, ang_q(th), &rc);
        rc_any |= rc;
        wmax = std::max(wmax, w);
        ASSERT_LE(std::abs(from_q(w, kWb)), 1000.0 + kWb / kQ31);
    }
    EXPECT_NE(q.flags & MC_SPDPLL_ERR_SAT, 0u);
    EXPECT_EQ(rc_any, MC_SPDPLL_ERR_SAT); // the clamping steps returned it
    EXPECT_NEAR(from_q(wmax, kWb), 1000.0, 2.0 * kWb / kQ31);
    const mc_spdpll_q31_cfg_t c2 = cfg(300.0f, 1.25e-4f, 5000.0f); // clamped to one base
    ASSERT_EQ(mc_spdpll_q31_init(&q, &c2), 0u);
    ASSERT_EQ(mc_spdpll_q31_reset(&q, 0, MC_Q31_MIN), MC_SPDPLL_ERR_NONE);
    EXPECT_EQ(q.omega, -MC_Q31_MAX); // the preset is clamped too
    th = 0.0;
    q31_t wmin = 0;
    for (int k = 0; k < 400; ++k) {
        th -= 0.1; // 800 rad/s backwards, then the PLL is pushed at its limit
        w = step_q(&q, ang_q(th));
        wmin = std::min(wmin, w);
        ASSERT_GE(w, -MC_Q31_MAX);
    }
    EXPECT_LT(from_q(wmin, kWb), -700.0);
}
