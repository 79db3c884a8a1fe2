// Flux gradient observer: q31 twin against the f32 kernel.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "q31_test_util.hpp"

extern "C" {
#include "observer/mc_fluxobs_q31.h"
#include "math/mc_math.h"
}

using namespace q31t;

namespace
{
constexpr double kIb = 20.0, kVb = 400.0, kFb = 0.25;
constexpr double kR = 0.675, kL = 1.14e-3, kPsi = 0.11, kDt = 1.25e-4;

mc_fluxobs_q31_cfg_t cfg()
{
    mc_fluxobs_q31_cfg_t c{};
    float gamma = 0.0f;
    // paper-002 test motor, critical speed 2.1 rad/s (20 r/min), 4 pole pairs
    EXPECT_EQ(mc_fluxobs_f32_gamma_for_critical_speed(2.1f, 4u, 0.11f, &gamma), 0u);
    c.f = {0.675f, 1.14e-3f, 0.11f, gamma, 1.25e-4f, 0.3f, 0.05f, 0.0f}; // non-salient
    c.i_base_a = static_cast<float>(kIb);
    c.v_base_v = static_cast<float>(kVb);
    c.flux_base_wb = static_cast<float>(kFb);
    return c;
}

// Synthetic machine: electrical angle th(t), dq currents (0, iq): the
// voltage that gives exactly that flux trajectory over each period.
struct Drive {
    double th = 0.3, w = 0.0;
    void currents(double t_th, double iq, double *ia, double *ib) const
    {
        *ia = -iq * std::sin(t_th);
        *ib = iq * std::cos(t_th);
    }
};
} // namespace

TEST(FluxobsQ31, InitRules)
{
    mc_fluxobs_q31_t q{};
    q.theta = 5;
    mc_fluxobs_q31_cfg_t c = cfg();
    c.flux_base_wb = 0.1f; // below the flux: would saturate on the circle itself
    EXPECT_EQ(mc_fluxobs_q31_init(&q, &c), MC_FLUXOBS_ERR_SCALE);
    c = cfg();
    c.i_base_a = 0.0f;
    EXPECT_EQ(mc_fluxobs_q31_init(&q, &c), MC_FLUXOBS_ERR_SCALE);
    c = cfg();
    c.f.gamma = -1.0f;
    EXPECT_EQ(mc_fluxobs_q31_init(&q, &c), MC_FLUXOBS_ERR_GAMMA);
    EXPECT_EQ(q.theta, 5);
    c = cfg();
    EXPECT_EQ(mc_fluxobs_q31_init(&q, &c), 0u);
    EXPECT_EQ(mc_fluxobs_q31_reset(nullptr, 0, 0, 0), MC_FLUXOBS_ERR_NULL);
}

TEST(FluxobsQ31, MatchesF32FromAWrongStartOnANoisyRun)
{
    // 0.5 rad wrong start, speed ramps 0 -> 300 rad/s electrical, iq 3 A,
    // current noise 20 mA, 40000 steps (5 s): both converge and track; the
    // angles are compared every step.
    const mc_fluxobs_q31_cfg_t c = cfg();
    mc_fluxobs_f32_t f{};
    mc_fluxobs_q31_t q{};
    ASSERT_EQ(mc_fluxobs_f32_init(&f, &c.f), 0u);
    ASSERT_EQ(mc_fluxobs_q31_init(&q, &c), 0u);
    Drive d;
    ASSERT_EQ(mc_fluxobs_f32_reset(&f, static_cast<float>(d.th + 0.5), 0.0f, 3.0f), 0u);
    ASSERT_EQ(mc_fluxobs_q31_reset(&q, ang_q(d.th + 0.5), to_q(0.0, kIb), to_q(3.0, kIb)),
              MC_FLUXOBS_ERR_NONE);
    std::mt19937 rng(30);
    std::normal_distribution<double> n(0.0, 0.02);
    double worst = 0.0, worst_x = 0.0, worst_true_late = 0.0;
    double ia0, ib0;
    d.currents(d.th, 3.0, &ia0, &ib0);
    for (int k = 0; k < 40000; ++k) {
        const double t = k * kDt;
        d.w = std::min(300.0, 100.0 * t + 20.0);
        const double th1 = d.th + d.w * kDt;
        double ia1, ib1;
        d.currents(th1, 3.0, &ia1, &ib1);
        // v_avg = R avg(i) + (x1 - x0)/dt (trapezoid, as the kernel integrates)
        const double va = kR * 0.5 * (ia0 + ia1) +
                          (kL * (ia1 - ia0) + kPsi * (std::cos(th1) - std::cos(d.th))) / kDt;
        const double vb = kR * 0.5 * (ib0 + ib1) +
                          (kL * (ib1 - ib0) + kPsi * (std::sin(th1) - std::sin(d.th))) / kDt;
        const q31_t vaq = to_q(va, kVb), vbq = to_q(vb, kVb);
        const q31_t iaq = to_q(ia1 + n(rng), kIb), ibq = to_q(ib1 + n(rng), kIb);
        mc_fluxobs_f32_step(
            &f, static_cast<float>(from_q(vaq, kVb)), static_cast<float>(from_q(vbq, kVb)),
            static_cast<float>(from_q(iaq, kIb)), static_cast<float>(from_q(ibq, kIb)));
        mc_fluxobs_q31_step(&q, vaq, vbq, iaq, ibq);
        worst = std::max(worst, ang_diff(f.theta_e_rad, ang_rad(q.theta)));
        worst_x =
            std::max(worst_x, std::abs(f.x_alpha_wb - q.x_alpha_q46 / 70368744177664.0 * kFb));
        if (t > 1.0)
            worst_true_late = std::max(worst_true_late, ang_diff(ang_rad(q.theta), th1));
        d.th = th1;
        ia0 = ia1;
        ib0 = ib1;
    }
    // Bound: the f32 flux integration rounds xh (ulp 7.5e-9 Wb at 0.11 Wb)
    // every step; the gradient term pulls both back within T_obs = 2/(gamma
    // flux^2) = 60 ms (480 steps), so the f32 drift stays ~ sqrt(480) ulp
    // ~ 2e-7 Wb, i.e. 2e-6 rad of angle. Bound 2e-5 rad (0.1 % of the
    // observer's own error under this noise) = 14000 LSB of the q31 turn.
    const double bound = 2.0e-5;
    report("fluxobs |theta_f32 - theta_q31|", worst, bound, "rad");
    report("fluxobs same in q31 turn LSB", worst / kPi * kQ31, bound / kPi * kQ31, "LSB");
    report("fluxobs |x_f32 - x_q31|", worst_x, 2e-6, "Wb");
    report("fluxobs q31 vs true angle after 1 s", worst_true_late, 0.05, "rad");
    EXPECT_LE(worst, bound);
    EXPECT_LE(worst_x, 2e-6);
    EXPECT_LE(worst_true_late, 0.05); // it works: 3 deg under 20 mA noise
    EXPECT_EQ(q.flags, 0u);
}

TEST(FluxobsQ31, FullScaleVoltageSaturatesNeverWraps)
{
    // +full-scale voltage for long: the estimate climbs to the +1 base
    // and stays there (a wrap would send it to -1); the residual monitor
    // flags the divergence after resid_time_s (400 steps), as f32 does.
    const mc_fluxobs_q31_cfg_t c = cfg();
    mc_fluxobs_q31_t q{};
    ASSERT_EQ(mc_fluxobs_q31_init(&q, &c), 0u);
    mc_fluxobs_f32_t f{};
    ASSERT_EQ(mc_fluxobs_f32_init(&f, &c.f), 0u);
    int first_q = -1, first_f = -1;
    for (int k = 0; k < 3000; ++k) {
        if (mc_fluxobs_q31_step(&q, MC_Q31_MAX, 0, 0, 0) != 0u && first_q < 0)
            first_q = k;
        if (mc_fluxobs_f32_step(&f, static_cast<float>(kVb), 0.0f, 0.0f, 0.0f) != 0u && first_f < 0)
            first_f = k;
        ASSERT_GE(q.x_alpha_q46, 0);
    }
    EXPECT_EQ(mc_q46_to_q31(q.x_alpha_q46), MC_Q31_MAX);
    EXPECT_NE(q.flags & MC_FLUXOBS_ERR_DIVERGED, 0u);
    EXPECT_NEAR(first_q, first_f, 1); // same step (timer in steps vs dt sum)
    EXPECT_EQ(q.theta, 0);            // e along +alpha
    // the opposite corner
    ASSERT_EQ(mc_fluxobs_q31_init(&q, &c), 0u);
    for (int k = 0; k < 3000; ++k) {
        mc_fluxobs_q31_step(&q, MC_Q31_MIN, MC_Q31_MIN, MC_Q31_MAX, MC_Q31_MAX);
        ASSERT_LE(q.x_beta_q46, 0);
    }
    EXPECT_EQ(mc_q46_to_q31(q.x_beta_q46), MC_Q31_MIN + 1); // clamp at -MAX
}

// A warm winding (issue 33 item 2): the machine's R is 1.37 times the
// configured one (copper from 25 to 120 C). Both twins given the scale
// (set_r_scale) track the true angle and agree with each other; given none
// (R stale) the integration's error dR i drags the angle. Bounds: with the
// scale, 1e-3 rad (no noise, the voltages exact for the scaled R: what is
// left is rounding, measured 8e-6 rad); twins within the 2e-5 rad of the
// matching test (the same rounding argument); without, more than 0.1 rad
// at 40 rad/s electrical and 3 A (measured 0.143 rad: the flux error dR i
// per second against the gradient's pull, of the order of dR i / (omega
// flux) = 0.17 rad).
TEST(FluxobsQ31, RScaleTwinsFollowAWarmWinding)
{
    const double scale = 1.37;
    double err_true[2] = {0.0, 0.0};
    double twins = 0.0;
    for (int with = 0; with < 2; ++with) {
        const mc_fluxobs_q31_cfg_t c = cfg();
        mc_fluxobs_f32_t f{};
        mc_fluxobs_q31_t q{};
        ASSERT_EQ(mc_fluxobs_f32_init(&f, &c.f), 0u);
        ASSERT_EQ(mc_fluxobs_q31_init(&q, &c), 0u);
        if (with == 1) {
            ASSERT_EQ(mc_fluxobs_f32_set_r_scale(&f, static_cast<float>(scale)), 0u);
            ASSERT_EQ(mc_fluxobs_q31_set_r_scale(&q, static_cast<float>(scale)), 0u);
        }
        Drive d;
        d.w = 40.0;
        ASSERT_EQ(mc_fluxobs_f32_reset(&f, static_cast<float>(d.th), 0.0f, 3.0f), 0u);
        ASSERT_EQ(mc_fluxobs_q31_reset(&q, ang_q(d.th), to_q(0.0, kIb), to_q(3.0, kIb)), 0u);
        double ia0, ib0;
        d.currents(d.th, 3.0, &ia0, &ib0);
        for (int k = 0; k < 16000; ++k) { // 2 s
            const double th1 = d.th + d.w * kDt;
            double ia1, ib1;
            d.currents(th1, 3.0, &ia1, &ib1);
            const double rr = scale * kR;
            const double va = rr * 0.5 * (ia0 + ia1) +
                              (kL * (ia1 - ia0) + kPsi * (std::cos(th1) - std::cos(d.th))) / kDt;
            const double vb = rr * 0.5 * (ib0 + ib1) +
                              (kL * (ib1 - ib0) + kPsi * (std::sin(th1) - std::sin(d.th))) / kDt;
            const q31_t vaq = to_q(va, kVb), vbq = to_q(vb, kVb);
            const q31_t iaq = to_q(ia1, kIb), ibq = to_q(ib1, kIb);
            mc_fluxobs_f32_step(
                &f, static_cast<float>(from_q(vaq, kVb)), static_cast<float>(from_q(vbq, kVb)),
                static_cast<float>(from_q(iaq, kIb)), static_cast<float>(from_q(ibq, kIb)));
            mc_fluxobs_q31_step(&q, vaq, vbq, iaq, ibq);
            if (k * kDt > 1.0) {
                err_true[with] = std::max(err_true[with], ang_diff(ang_rad(q.theta), th1));
                err_true[with] = std::max(err_true[with], ang_diff(f.theta_e_rad, th1));
            }
            if (with == 1)
                twins = std::max(twins, ang_diff(f.theta_e_rad, ang_rad(q.theta)));
            d.th = th1;
            ia0 = ia1;
            ib0 = ib1;
        }
    }
    report("fluxobs warm winding, R scaled: angle error", err_true[1], 1e-3, "rad");
    report("fluxobs warm winding, R stale: angle error", err_true[0], 0.1, "rad");
    EXPECT_LE(err_true[1], 1e-3);
    EXPECT_GT(err_true[0], 0.1);
    EXPECT_LE(twins, 2.0e-5);
}

// Both twins refuse the same scales (mc_r_scale_f32_ok) and change nothing.
TEST(FluxobsQ31, RScaleRefusedAlikeByBothTwins)
{
    const mc_fluxobs_q31_cfg_t c = cfg();
    mc_fluxobs_f32_t f{};
    mc_fluxobs_q31_t q{};
    ASSERT_EQ(mc_fluxobs_f32_init(&f, &c.f), 0u);
    ASSERT_EQ(mc_fluxobs_q31_init(&q, &c), 0u);
    const float half_r = f.half_r_ohm;
    const mc_q46_gain_t g = q.g_r;
    for (float bad : {std::nanf(""), INFINITY, 0.0f, 0.2f, 3.5f, -1.0f}) {
        EXPECT_EQ(mc_fluxobs_f32_set_r_scale(&f, bad), MC_FLUXOBS_ERR_ARG) << bad;
        EXPECT_EQ(mc_fluxobs_q31_set_r_scale(&q, bad), MC_FLUXOBS_ERR_ARG) << bad;
    }
    EXPECT_EQ(f.half_r_ohm, half_r);
    EXPECT_EQ(f.r_scale, 1.0f);
    EXPECT_EQ(q.g_r.mant, g.mant);
    EXPECT_EQ(q.r_scale, 1.0f);
    EXPECT_EQ(mc_fluxobs_f32_set_r_scale(nullptr, 1.0f), MC_FLUXOBS_ERR_NULL);
    EXPECT_EQ(mc_fluxobs_q31_set_r_scale(nullptr, 1.0f), MC_FLUXOBS_ERR_NULL);
    // the edges are accepted, and reset keeps the scale
    EXPECT_EQ(mc_fluxobs_f32_set_r_scale(&f, MC_R_SCALE_MAX), 0u);
    EXPECT_EQ(mc_fluxobs_q31_set_r_scale(&q, MC_R_SCALE_MIN), 0u);
    EXPECT_EQ(mc_fluxobs_f32_reset(&f, 0.0f, 0.0f, 0.0f), 0u);
    EXPECT_FLOAT_EQ(f.half_r_ohm, 0.5f * c.f.r_ohm * MC_R_SCALE_MAX);
    EXPECT_EQ(mc_fluxobs_q31_reset(&q, 0, 0, 0), 0u);
    EXPECT_EQ(q.r_scale, MC_R_SCALE_MIN);
}
