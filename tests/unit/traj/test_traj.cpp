// Trajectory generator (firmware/kernels/traj): the trapezoid against its
// closed forms, re-planning continuity, the input filter against the
// critically damped step and ramp responses.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>

extern "C" {
#include "traj/mc_traj.h"
}

namespace
{

constexpr double kTwoPi = 6.283185307179586476925;

mc_traj_f32_cfg_t Cfg(float v = 50.0f, float a = 200.0f, float d = 100.0f, float bw = 100.0f,
                      float dt = 5e-5f)
{
    mc_traj_f32_cfg_t c{};
    c.v_max_rad_s = v;
    c.a_max_rad_s2 = a;
    c.d_max_rad_s2 = d;
    c.filter_bw_rad_s = bw;
    c.dt_s = dt;
    return c;
}

// float position tolerance: a few ulp of the largest position plus the
// accumulated rounding of the segment chaining.
double PosTol(double x)
{
    return 4e-6 * std::max(1.0, std::abs(x));
}

TEST(Traj, InitRejectsBadConfig)
{
    mc_traj_f32_t t;
    EXPECT_EQ(MC_TRAJ_ERR_NULL, mc_traj_f32_init(nullptr, nullptr));
    mc_traj_f32_cfg_t c = Cfg();
    c.v_max_rad_s = 0.0f;
    EXPECT_EQ(MC_TRAJ_ERR_LIMIT, mc_traj_f32_init(&t, &c));
    c = Cfg();
    c.a_max_rad_s2 = NAN;
    EXPECT_EQ(MC_TRAJ_ERR_LIMIT, mc_traj_f32_init(&t, &c));
    c = Cfg();
    c.d_max_rad_s2 = -1.0f;
    EXPECT_EQ(MC_TRAJ_ERR_LIMIT, mc_traj_f32_init(&t, &c));
    c = Cfg();
    c.dt_s = 0.0f;
    EXPECT_EQ(MC_TRAJ_ERR_DT, mc_traj_f32_init(&t, &c));
    c = Cfg();
    c.filter_bw_rad_s = -1.0f;
    EXPECT_EQ(MC_TRAJ_ERR_FILTER, mc_traj_f32_init(&t, &c));
    c = Cfg();
    c.filter_bw_rad_s = 1.0f / c.dt_s * 1.01f; // w dt > 1
    EXPECT_EQ(MC_TRAJ_ERR_FILTER, mc_traj_f32_init(&t, &c));
    c = Cfg();
    c.filter_bw_rad_s = 0.0f;
    ASSERT_EQ(MC_TRAJ_ERR_NONE, mc_traj_f32_init(&t, &c));
    EXPECT_EQ(MC_TRAJ_ERR_MODE, mc_traj_f32_set_mode(&t, MC_TRAJ_MODE_FILTER));
    EXPECT_EQ(MC_TRAJ_ERR_INPUT, mc_traj_f32_plan(&t, 0.0f, NAN, 1.0f));
    EXPECT_EQ(MC_TRAJ_ERR_LIMIT, mc_traj_f32_set_limits(&t, 1.0f, 0.0f, 1.0f));
}

// Full trapezoid from rest: T = D/v + v/(2a) + v/(2d); x(t) in each phase.
TEST(Traj, TrapezoidFromRestClosedForm)
{
    const double v = 50, a = 200, d = 100, x0 = 0.5, D = 10 * kTwoPi;
    mc_traj_f32_t t;
    const mc_traj_f32_cfg_t c = Cfg(50, 200, 100);
    ASSERT_EQ(0u, mc_traj_f32_init(&t, &c));
    ASSERT_EQ(0u, mc_traj_f32_plan(&t, static_cast<float>(x0), 0.0f, static_cast<float>(x0 + D)));
    const double T = D / v + v / (2 * a) + v / (2 * d);
    EXPECT_NEAR(T, mc_traj_f32_get_duration_s(&t), 1e-6 * T);
    const double t1 = v / a, t3 = T - v / d;
    for (double tt = 0.0; tt < T + 0.01; tt += 0.0123) {
        double x, vv, aa;
        if (tt < t1) {
            x = x0 + 0.5 * a * tt * tt, vv = a * tt, aa = a;
        } else if (tt < t3) {
            x = x0 + 0.5 * a * t1 * t1 + v * (tt - t1), vv = v, aa = 0;
        } else if (tt < T) {
            x = x0 + D - 0.5 * d * (T - tt) * (T - tt), vv = d * (T - tt), aa = -d;
        } else {
            x = x0 + D, vv = 0, aa = 0;
        }
        mc_traj_f32_out_t o;
        mc_traj_f32_eval(&t, static_cast<float>(tt), &o);
        EXPECT_NEAR(x, o.x_rad, PosTol(x)) << "t=" << tt;
        EXPECT_NEAR(vv, o.v_rad_s, 1e-4 * v) << "t=" << tt;
        EXPECT_EQ(static_cast<float>(aa), o.a_rad_s2) << "t=" << tt;
        EXPECT_EQ(tt >= T, o.done);
    }
    mc_traj_f32_out_t o;
    mc_traj_f32_eval(&t, static_cast<float>(T) + 1e-3f, &o);
    EXPECT_EQ(static_cast<float>(x0 + D), o.x_rad); // the target itself
}

// Short move: a triangle with v_p = sqrt(2 a d D / (a + d)), T = v_p/a + v_p/d;
// negative direction.
TEST(Traj, TriangleShortMoveNegative)
{
    const double a = 200, d = 100, D = 1.0;
    mc_traj_f32_t t;
    const mc_traj_f32_cfg_t c = Cfg(50, 200, 100);
    ASSERT_EQ(0u, mc_traj_f32_init(&t, &c));
    ASSERT_EQ(0u, mc_traj_f32_plan(&t, 2.0f, 0.0f, static_cast<float>(2.0 - D)));
    const double vp = std::sqrt(2 * a * d * D / (a + d)), T = vp / a + vp / d;
    EXPECT_NEAR(T, mc_traj_f32_get_duration_s(&t), 1e-6);
    double vmin = 0;
    for (double tt = 0.0; tt < T; tt += 1e-4) {
        mc_traj_f32_out_t o;
        mc_traj_f32_eval(&t, static_cast<float>(tt), &o);
        vmin = std::min(vmin, static_cast<double>(o.v_rad_s));
    }
    EXPECT_NEAR(-vp, vmin, 200 * 1e-4 + 1e-4);
    mc_traj_f32_out_t o;
    mc_traj_f32_eval(&t, static_cast<float>(vp / a), &o);
    EXPECT_NEAR(2.0 - 0.5 * vp * vp / a, o.x_rad, 1e-5);
}

// A state that cannot stop before the target: brake at d past it, return.
TEST(Traj, OvershootBrakesAtDecelThenReturns)
{
    const double d = 100, v0 = 40;
    mc_traj_f32_t t;
    const mc_traj_f32_cfg_t c = Cfg(50, 200, 100);
    ASSERT_EQ(0u, mc_traj_f32_init(&t, &c));
    // Stopping takes v0^2 / (2 d) = 8 rad; the target is 1 rad ahead.
    ASSERT_EQ(0u, mc_traj_f32_plan(&t, 0.0f, static_cast<float>(v0), 1.0f));
    mc_traj_f32_out_t o;
    mc_traj_f32_eval(&t, static_cast<float>(v0 / d), &o);
    EXPECT_NEAR(v0 * v0 / (2 * d), o.x_rad, 1e-5); // the stopping point
    EXPECT_NEAR(0.0, o.v_rad_s, 1e-4);
    // then a from-rest move of 7 rad back: a triangle (a, d)
    const double D = v0 * v0 / (2 * d) - 1.0, a = 200;
    const double vp = std::sqrt(2 * a * d * D / (a + d));
    EXPECT_NEAR(v0 / d + vp / a + vp / d, mc_traj_f32_get_duration_s(&t), 1e-5);
    mc_traj_f32_eval(&t, 10.0f, &o);
    EXPECT_EQ(1.0f, o.x_rad);
}

// Faster than v_max at the plan: the ramp decelerates at d to v_max.
TEST(Traj, AboveVmaxDeceleratesAtD)
{
    mc_traj_f32_t t;
    const mc_traj_f32_cfg_t c = Cfg(50, 200, 100);
    ASSERT_EQ(0u, mc_traj_f32_init(&t, &c));
    ASSERT_EQ(0u, mc_traj_f32_plan(&t, 0.0f, 80.0f, 100.0f));
    mc_traj_f32_out_t o;
    mc_traj_f32_eval(&t, 0.1f, &o);
    EXPECT_FLOAT_EQ(-100.0f, o.a_rad_s2);
    EXPECT_NEAR(70.0, o.v_rad_s, 1e-4);
    // ramp 0.3 s (80 -> 50, 19.5 rad), stop 0.5 s (12.5 rad), cruise 68 rad
    EXPECT_NEAR(0.3 + 68.0 / 50.0 + 0.5, mc_traj_f32_get_duration_s(&t), 1e-5);
}

// Stop: from cruise, decelerate at the given rate to the stopping point.
TEST(Traj, StopAtGivenDecel)
{
    mc_traj_f32_t t;
    const mc_traj_f32_cfg_t c = Cfg(50, 200, 100, 100, 1e-3f);
    ASSERT_EQ(0u, mc_traj_f32_init(&t, &c));
    ASSERT_EQ(0u, mc_traj_f32_plan(&t, 0.0f, 0.0f, 1000.0f));
    mc_traj_f32_out_t o;
    for (int k = 0; k < 1000; ++k) {
        ASSERT_EQ(0u, mc_traj_f32_step(&t, &o)); // 1 s: cruising at 50
    }
    mc_traj_f32_out_t now;
    mc_traj_f32_eval(&t, static_cast<float>(t.k) * c.dt_s, &now);
    ASSERT_FLOAT_EQ(50.0f, now.v_rad_s);
    ASSERT_EQ(0u, mc_traj_f32_stop(&t, 25.0f));
    EXPECT_NEAR(2.0, mc_traj_f32_get_duration_s(&t), 1e-6);
    mc_traj_f32_eval(&t, 5.0f, &o);
    EXPECT_NEAR(now.x_rad + 50.0 * 50.0 / 50.0, o.x_rad, PosTol(o.x_rad));
}

// Random re-plans while moving: position and velocity continuous from step
// to step (|dv| <= max(a, d) dt), |a| within the limits, |v| <= v_max once
// the plan starts below it, and every last plan ends exactly at its target.
TEST(Traj, ReplanWhileMovingIsContinuous)
{
    const float dt = 1e-4f, a = 300, d = 120, v = 40;
    mc_traj_f32_t t;
    const mc_traj_f32_cfg_t c = Cfg(v, a, d, 100, dt);
    ASSERT_EQ(0u, mc_traj_f32_init(&t, &c));
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> tgt(-60.0f, 60.0f);
    std::uniform_int_distribution<int> gap(50, 6000);
    mc_traj_f32_out_t prev{}, o{};
    ASSERT_EQ(0u, mc_traj_f32_step(&t, &prev));
    int next = gap(rng);
    float target = 0;
    for (int k = 1; k < 200000; ++k) {
        if (k == next) {
            target = tgt(rng);
            ASSERT_EQ(0u, mc_traj_f32_set_target(&t, target));
            next = k + gap(rng);
        }
        ASSERT_EQ(0u, mc_traj_f32_step(&t, &o));
        const double dv = o.v_rad_s - prev.v_rad_s;
        ASSERT_LE(std::abs(dv), std::max(a, d) * dt * 1.001 + 1e-4) << k;
        const double dx = o.x_rad - prev.x_rad;
        ASSERT_NEAR(dx, 0.5 * (o.v_rad_s + prev.v_rad_s) * dt,
                    0.5 * std::max(a, d) * dt * dt + 2e-5)
            << k;
        ASSERT_LE(std::abs(o.v_rad_s), v * 1.0001f) << k;
        ASSERT_TRUE(o.a_rad_s2 == 0.0f || std::abs(o.a_rad_s2) == a || std::abs(o.a_rad_s2) == d);
        if (o.a_rad_s2 != 0.0f && std::abs(o.a_rad_s2) == a) {
            ASSERT_GE(o.a_rad_s2 * o.v_rad_s, -1e-3f) << "a_max only while |v| rises, k=" << k;
        }
        prev = o;
    }
    for (int k = 0; k < 200000 && !o.done; ++k) {
        ASSERT_EQ(0u, mc_traj_f32_step(&t, &o));
    }
    EXPECT_TRUE(o.done);
    EXPECT_EQ(target, o.x_rad);
}

// Re-basing by whole turns moves every position and nothing else.
TEST(Traj, ShiftMovesTheFrame)
{
    mc_traj_f32_t t;
    const mc_traj_f32_cfg_t c = Cfg();
    ASSERT_EQ(0u, mc_traj_f32_init(&t, &c));
    ASSERT_EQ(0u, mc_traj_f32_plan(&t, 10.0f, 0.0f, 30.0f));
    mc_traj_f32_out_t a, b;
    mc_traj_f32_eval(&t, 0.2f, &a);
    mc_traj_f32_shift(&t, static_cast<float>(kTwoPi));
    mc_traj_f32_eval(&t, 0.2f, &b);
    EXPECT_NEAR(a.x_rad - kTwoPi, b.x_rad, 2e-6);
    EXPECT_EQ(a.v_rad_s, b.v_rad_s);
}

// Filter step response: x = r (1 - (1 + w t) e^(-w t)), v = r w^2 t e^(-w t).
TEST(Traj, FilterStepClosedForm)
{
    const double w = 80, dt = 1e-4, r = 3.0;
    mc_traj_f32_t t;
    const mc_traj_f32_cfg_t c = Cfg(50, 200, 100, static_cast<float>(w), static_cast<float>(dt));
    ASSERT_EQ(0u, mc_traj_f32_init(&t, &c));
    ASSERT_EQ(0u, mc_traj_f32_set_mode(&t, MC_TRAJ_MODE_FILTER));
    ASSERT_EQ(0u, mc_traj_f32_set_input(&t, static_cast<float>(r)));
    double vmax = 0;
    for (int k = 0; k < 2000; ++k) {
        mc_traj_f32_out_t o;
        ASSERT_EQ(0u, mc_traj_f32_step(&t, &o));
        const double tt = k * dt, e = std::exp(-w * tt);
        ASSERT_NEAR(r * (1 - (1 + w * tt) * e), o.x_rad, 2e-6 * (1 + k * 1e-2)) << k;
        ASSERT_NEAR(r * w * w * tt * e, o.v_rad_s, 1e-4 * r * w) << k;
        ASSERT_NEAR(r * w * w * (1 - w * tt) * e, o.a_rad_s2, 1e-4 * r * w * w) << k;
        ASSERT_LE(o.x_rad, r * (1 + 1e-6)) << "critically damped: no overshoot";
        vmax = std::max(vmax, static_cast<double>(o.v_rad_s));
    }
    EXPECT_NEAR(r * w / std::exp(1.0), vmax, 1e-3 * r * w); // peak at t = 1/w
}

// Streamed ramp setpoints (held between updates): the filter follows with
// the lag 2 v / w and a smooth velocity.
TEST(Traj, FilterFollowsStreamedRamp)
{
    const double w = 60, dt = 1e-4, vr = 5.0;
    mc_traj_f32_t t;
    const mc_traj_f32_cfg_t c = Cfg(50, 200, 100, static_cast<float>(w), static_cast<float>(dt));
    ASSERT_EQ(0u, mc_traj_f32_init(&t, &c));
    ASSERT_EQ(0u, mc_traj_f32_set_mode(&t, MC_TRAJ_MODE_FILTER));
    mc_traj_f32_out_t o{};
    const int every = 10; // setpoints at 1 kHz, filter at 10 kHz
    for (int k = 0; k < 20000; ++k) {
        if (k % every == 0) {
            ASSERT_EQ(0u, mc_traj_f32_set_input(&t, static_cast<float>(vr * k * dt)));
        }
        ASSERT_EQ(0u, mc_traj_f32_step(&t, &o));
    }
    // the held input lags the ramp by half an update on average
    const double tt = 19999 * dt, lag = 2 * vr / w + vr * (every - 1) * dt / 2;
    EXPECT_NEAR(vr * tt - lag, o.x_rad, 2e-3);
    EXPECT_NEAR(vr, o.v_rad_s, 0.05 * vr);
}

// Switching modes keeps the state: filter -> trapezoid plans from (x, v).
TEST(Traj, ModeSwitchKeepsState)
{
    mc_traj_f32_t t;
    const mc_traj_f32_cfg_t c = Cfg(50, 200, 100, 50, 1e-4f);
    ASSERT_EQ(0u, mc_traj_f32_init(&t, &c));
    ASSERT_EQ(0u, mc_traj_f32_set_mode(&t, MC_TRAJ_MODE_FILTER));
    ASSERT_EQ(0u, mc_traj_f32_set_input(&t, 5.0f));
    mc_traj_f32_out_t o, p;
    for (int k = 0; k < 300; ++k)
        ASSERT_EQ(0u, mc_traj_f32_step(&t, &o));
    const float x = t.fx_rad, v = t.fv_rad_s;
    ASSERT_EQ(0u, mc_traj_f32_set_mode(&t, MC_TRAJ_MODE_TRAP));
    ASSERT_EQ(0u, mc_traj_f32_step(&t, &p));
    EXPECT_EQ(x, p.x_rad);
    EXPECT_EQ(v, p.v_rad_s);
    for (int k = 0; k < 100000 && !p.done; ++k)
        ASSERT_EQ(0u, mc_traj_f32_step(&t, &p));
    EXPECT_EQ(5.0f, p.x_rad);
}

} // namespace
