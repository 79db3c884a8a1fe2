// Encoder tracking loop (firmware/kernels/observer/mc_enctrack): the type-3
// loop the drive runs on its encoder angle. Checked against properties of the
// law (mc_enctrack.h), not against a copy of it.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>

extern "C" {
#include "observer/mc_enctrack.h"
}

namespace {

constexpr double kTwoPi = 6.283185307179586;

// The angle a real encoder reports: quantised to cpr counts per turn.
float quantised(double theta_rad, uint32_t cpr) {
  double t = std::fmod(theta_rad, kTwoPi);
  if (t < 0.0) t += kTwoPi;
  const auto count = static_cast<uint32_t>(std::floor(t / kTwoPi * cpr)) % cpr;
  return static_cast<float>(count * (kTwoPi / cpr));
}

mc_enctrack_f32_t make(float bw, float dt) {
  mc_enctrack_f32_t st{};
  const mc_enctrack_f32_cfg_t c{bw, dt};
  EXPECT_EQ(mc_enctrack_f32_init(&st, &c), MC_ENCTRACK_ERR_NONE);
  return st;
}

}  // namespace

TEST(EncTrack, RefusesBadConfigAndLeavesStateUntouched) {
  mc_enctrack_f32_t st{};
  st.omega_rad_s = 7.0f;
  const mc_enctrack_f32_cfg_t bad[] = {
      {0.0f, 5e-5f},  {-1.0f, 5e-5f}, {NAN, 5e-5f},     {INFINITY, 5e-5f},
      {100.0f, 0.0f}, {100.0f, NAN},  {6667.0f, 5e-5f},  // 3 bw dt = 1.00005 > 1: poles leave the safe region
  };
  for (const auto& c : bad) {
    EXPECT_NE(mc_enctrack_f32_init(&st, &c), MC_ENCTRACK_ERR_NONE) << c.bw_rad_s << " " << c.dt_s;
    EXPECT_EQ(st.omega_rad_s, 7.0f);
  }
  const mc_enctrack_f32_cfg_t edge{6666.0f, 5e-5f};  // 3 bw dt = 0.9999: accepted
  EXPECT_EQ(mc_enctrack_f32_init(&st, &edge), MC_ENCTRACK_ERR_NONE);
  EXPECT_EQ(mc_enctrack_f32_init(nullptr, &edge), MC_ENCTRACK_ERR_NULL);
}

TEST(EncTrack, FirstStepTakesTheAngleAndNaNChangesNothing) {
  auto st = make(200.0f, 5e-5f);
  EXPECT_EQ(mc_enctrack_f32_step(&st, 1.25f), MC_ENCTRACK_ERR_NONE);
  EXPECT_EQ(st.theta_rad, 1.25f);
  EXPECT_EQ(st.omega_rad_s, 0.0f);
  const mc_enctrack_f32_t before = st;
  EXPECT_EQ(mc_enctrack_f32_step(&st, NAN), MC_ENCTRACK_ERR_NAN_INPUT);
  EXPECT_EQ(st.theta_rad, before.theta_rad);
  EXPECT_EQ(st.omega_rad_s, before.omega_rad_s);
  EXPECT_NE(st.err & MC_ENCTRACK_ERR_NAN_INPUT, 0u);  // sticky
  EXPECT_EQ(mc_enctrack_f32_reset(&st), MC_ENCTRACK_ERR_NONE);
  EXPECT_FALSE(st.primed);
}

// Type 3: a constant acceleration is followed with no steady-state speed
// error, through the angle wrap, from a quantised 8192-count encoder.
TEST(EncTrack, FollowsConstantAccelerationWithoutSpeedLag) {
  const float dt = 5e-5f;   // 20 kHz
  const float bw = 300.0f;  // rad/s
  const uint32_t cpr = 8192u;
  const double a = 400.0;  // rad/s^2
  auto st = make(bw, dt);
  double worst_late = 0.0;
  const int n = static_cast<int>(1.0 / dt);  // 1 s: ends at 400 rad/s, 32 turns
  for (int k = 0; k <= n; ++k) {
    const double t = k * static_cast<double>(dt);
    ASSERT_EQ(mc_enctrack_f32_step(&st, quantised(0.5 * a * t * t, cpr)), MC_ENCTRACK_ERR_NONE);
    // after 20 time constants (1/bw = 3.3 ms) the transient is below e^-20 of its start
    if (t > 20.0 / bw) worst_late = std::fmax(worst_late, std::fabs(st.omega_rad_s - a * t));
  }
  // Tolerance: the count quantum 2 pi / 8192 = 7.7e-4 rad seen through the
  // loop's speed gain (about 1.5 bw for a triple pole, near the k2 = 3 bw^2
  // path's noise gain) gives ~0.35 rad/s; 0.5 rad/s bounds it. A type-2 loop
  // would lag by 2 a / bw = 2.7 rad/s here and fail.
  EXPECT_LT(worst_late, 0.5);
  EXPECT_NEAR(st.alpha_rad_s2, a, 0.05 * a);  // acceleration estimate within 5 %
}

// A speed step settles like (s + bw)^3: after 10 / bw the speed error is
// below 1 % of the step (the analytic envelope is ~ (bw t)^2/2 e^(-bw t),
// 0.23 % at bw t = 10); before 1 / bw it has not (the loop is not a
// differentiator).
TEST(EncTrack, SettlesAsATriplePoleAtBandwidth) {
  const float dt = 5e-5f;
  const float bw = 200.0f;
  auto st = make(bw, dt);
  const double w = 50.0;
  (void)mc_enctrack_f32_step(&st, 0.0f);
  double theta = 0.0;
  double err_at_1 = 0.0, err_at_10 = 0.0;
  for (int k = 1; k <= static_cast<int>(12.0 / bw / dt); ++k) {
    theta += w * dt;
    (void)mc_enctrack_f32_step(&st, static_cast<float>(std::fmod(theta, kTwoPi)));
    const double t = k * static_cast<double>(dt);
    if (std::fabs(t - 1.0 / bw) < 0.5 * dt) err_at_1 = std::fabs(st.omega_rad_s - w);
    if (std::fabs(t - 10.0 / bw) < 0.5 * dt) err_at_10 = std::fabs(st.omega_rad_s - w);
  }
  EXPECT_GT(err_at_1, 0.1 * w);
  EXPECT_LT(err_at_10, 0.01 * w);
}
