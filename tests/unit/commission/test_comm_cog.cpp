// Commissioning's anticogging calibration (firmware/app/commission/
// mc_comm_cog.h) against a closed-form rotor: the angle advances by the
// commanded speed each step, the speed loop's q reference is the cogging
// current at the angle the loop's lag behind it, plus friction in the
// direction of motion. The result must be the cogging, friction and the
// lag's first order cancelled; each refusal by name.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>

#include "commission/mc_comm_cog.h"

namespace {

constexpr double kTwoPi = 6.283185307179586;

// 12-slot / 14-pole cogging: order 84, plus an order-12 term (a rotor's
// eccentricity), in A of q current; 0.3 A peak in all.
double cog_a(double th) {
  return 0.2 * std::sin(84.0 * th) + 0.1 * std::sin(12.0 * th + 0.3);
}

mc_comm_cog_cfg_t cfg_1khz() {
  mc_comm_cog_cfg_t g{};
  g.dt_s = 1.0e-3f;  // the application's slow loop
  g.w_rad_s = 3.0f;  // 0.48 turn/s: 2 samples per bin at 1 kHz
  g.t_ramp_s = 0.2f;
  g.t_settle_s = 0.1f;
  g.i_bound_a = 1.0f;
  g.agree_frac = 0.3f;
  g.i_floor_a = 0.01f;
  g.offset_known = true;
  return g;
}

struct Rotor {
  double th = 1.0;  // start anywhere
  double friction_a = 0.15;
  double lag_rad = 0.002;  // the loop's delay as an angle at w
  bool blocked = false;
  double gain = 1.0;  // the reverse pass's cogging amplitude scale
};

// Runs the sequence to its end (or the step limit); returns the error bits.
uint32_t run(mc_comm_cog_t* c, Rotor& r, uint32_t max_steps = 200000u) {
  float w = 0.0f;
  uint32_t err = 0u;
  for (uint32_t n = 0; n < max_steps; ++n) {
    const double sgn = (w > 0.0f) ? 1.0 : ((w < 0.0f) ? -1.0 : 0.0);
    const double amp = (sgn < 0.0) ? r.gain : 1.0;
    const double iq = amp * cog_a(r.th - sgn * r.lag_rad) + sgn * r.friction_a;
    float th = static_cast<float>(std::fmod(r.th, kTwoPi));
    if (th < 0.0f) th += static_cast<float>(kTwoPi);
    err = mc_comm_cog_step(c, th, static_cast<float>(iq), &w);
    if (c->phase == MC_COMM_COG_DONE || c->phase == MC_COMM_COG_FAILED) break;
    if (!r.blocked) r.th += static_cast<double>(w) * 1.0e-3;
  }
  return err;
}

TEST(CommCog, RecoversTheCoggingFrictionCancelled) {
  auto c = std::make_unique<mc_comm_cog_t>();
  const mc_comm_cog_cfg_t g = cfg_1khz();
  ASSERT_EQ(mc_comm_cog_start(c.get(), &g), MC_COMM_COG_ERR_NONE);
  Rotor r;
  ASSERT_EQ(run(c.get(), r), MC_COMM_COG_ERR_NONE);
  ASSERT_EQ(c->phase, MC_COMM_COG_DONE);
  const float* i = mc_comm_cog_currents(c.get());
  ASSERT_NE(i, nullptr);
  double ss_err = 0.0;
  double ss_ref = 0.0;
  double mean = 0.0;
  for (uint32_t k = 0; k < MC_COG_N; ++k) mean += i[k];
  mean /= MC_COG_N;
  for (uint32_t k = 0; k < MC_COG_N; ++k) {
    const double ref = cog_a(kTwoPi * k / MC_COG_N);
    ss_err += (i[k] - ref) * (i[k] - ref);
    ss_ref += ref * ref;
  }
  // The mean is removed: friction (0.15 A) is gone to float rounding.
  EXPECT_NEAR(mean, 0.0, 1e-5);
  // RMS error within 3 % of the cogging's RMS (measured 1.4 %): the lag's
  // second order (1 - cos(84 * 0.002) = 1.4 % of the order-84 term, most of
  // the RMS) and the interpolation between samples 3 mrad apart
  // ((84 * 0.003)^2 / 8 = 0.8 % at most); 3 % is their sum with room for
  // the float sums.
  std::printf("map rms error %.4f of the cogging rms, disagreement %.4f A\n",
              std::sqrt(ss_err / ss_ref), c->rms_dis_a);
  EXPECT_LT(std::sqrt(ss_err / ss_ref), 0.03);
  // The lag shows as disagreement: rms(d)/2 = rms of the sin(84 * lag) part,
  // 0.2 * sin(0.168) / sqrt(2) = 0.024 A; within 20 % of it (the order-12
  // part's 0.1 sin(0.024) / sqrt(2) = 0.0017 A and the binning).
  EXPECT_NEAR(c->rms_dis_a, 0.024, 0.2 * 0.024);
}

TEST(CommCog, RefusesWithoutEncoderOffset) {
  auto c = std::make_unique<mc_comm_cog_t>();
  mc_comm_cog_cfg_t g = cfg_1khz();
  g.offset_known = false;
  EXPECT_EQ(mc_comm_cog_start(c.get(), &g), MC_COMM_COG_ERR_NO_OFFSET);
  float w = 1.0f;
  EXPECT_EQ(mc_comm_cog_step(c.get(), 0.0f, 0.0f, &w), MC_COMM_COG_ERR_NO_OFFSET);
  EXPECT_EQ(w, 0.0f);  // nothing commanded
  EXPECT_EQ(mc_comm_cog_currents(c.get()), nullptr);
}

TEST(CommCog, RefusesABadCfgAndChangesNothing) {
  auto c = std::make_unique<mc_comm_cog_t>();
  c->phase = MC_COMM_COG_IDLE;
  c->err = 0u;
  mc_comm_cog_cfg_t g = cfg_1khz();
  g.w_rad_s = 7.0f;  // 7 rad/s * 1 ms > one bin (6.1 mrad): bins skipped
  EXPECT_EQ(mc_comm_cog_start(c.get(), &g), MC_COMM_COG_ERR_CFG);
  EXPECT_EQ(c->phase, MC_COMM_COG_IDLE);
  g = cfg_1khz();
  g.agree_frac = NAN;
  EXPECT_EQ(mc_comm_cog_start(c.get(), &g), MC_COMM_COG_ERR_CFG);
  EXPECT_EQ(mc_comm_cog_start(nullptr, &g), MC_COMM_COG_ERR_CFG);
}

TEST(CommCog, BlockedRotorFailsWithinTheTimeAndStops) {
  auto c = std::make_unique<mc_comm_cog_t>();
  const mc_comm_cog_cfg_t g = cfg_1khz();
  ASSERT_EQ(mc_comm_cog_start(c.get(), &g), MC_COMM_COG_ERR_NONE);
  Rotor r;
  r.blocked = true;
  uint32_t steps = 0u;
  float w = 0.0f;
  uint32_t err = 0u;
  while (c->phase != MC_COMM_COG_FAILED && steps < 100000u) {
    err = mc_comm_cog_step(c.get(), 1.0f, 0.1f, &w);
    ++steps;
  }
  EXPECT_EQ(err, MC_COMM_COG_ERR_BLOCKED);
  EXPECT_EQ(w, 0.0f);
  // Ramp + settle (0.3 s) plus twice a turn (and 8 bins) at 3 rad/s (4.21 s);
  // one step of slack for the float time sum.
  const double t_lim = 0.3 + 2.0 * (kTwoPi * (1.0 + 8.0 / 1024.0)) / 3.0;
  EXPECT_NEAR(steps * 1.0e-3, t_lim, 2.0e-3);
}

TEST(CommCog, AmplitudeBeyondTheBoundIsRefused) {
  auto c = std::make_unique<mc_comm_cog_t>();
  mc_comm_cog_cfg_t g = cfg_1khz();
  g.i_bound_a = 0.25f;  // the cogging peaks near 0.3 A
  ASSERT_EQ(mc_comm_cog_start(c.get(), &g), MC_COMM_COG_ERR_NONE);
  Rotor r;
  EXPECT_EQ(run(c.get(), r), MC_COMM_COG_ERR_AMPLITUDE);
  EXPECT_EQ(c->phase, MC_COMM_COG_FAILED);
  EXPECT_EQ(mc_comm_cog_currents(c.get()), nullptr);
}

TEST(CommCog, DirectionsThatDisagreeAreRefused) {
  auto c = std::make_unique<mc_comm_cog_t>();
  const mc_comm_cog_cfg_t g = cfg_1khz();
  ASSERT_EQ(mc_comm_cog_start(c.get(), &g), MC_COMM_COG_ERR_NONE);
  Rotor r;
  r.gain = -0.5;  // the back pass sees the cogging reversed: d = 0.75 cog,
                  // avg = 0.25 cog: rms(d) 3x rms(avg), far beyond 0.3
  EXPECT_EQ(run(c.get(), r), MC_COMM_COG_ERR_DISAGREE);
}

TEST(CommCog, NonFiniteSampleAndAbort) {
  auto c = std::make_unique<mc_comm_cog_t>();
  const mc_comm_cog_cfg_t g = cfg_1khz();
  ASSERT_EQ(mc_comm_cog_start(c.get(), &g), MC_COMM_COG_ERR_NONE);
  float w = 0.0f;
  for (int n = 0; n < 400; ++n) (void)mc_comm_cog_step(c.get(), 0.5f, 0.0f, &w);
  ASSERT_EQ(c->phase, MC_COMM_COG_REC_FWD);
  EXPECT_EQ(mc_comm_cog_step(c.get(), 0.5f, NAN, &w), MC_COMM_COG_ERR_MEAS);
  EXPECT_EQ(w, 0.0f);
  ASSERT_EQ(mc_comm_cog_start(c.get(), &g), MC_COMM_COG_ERR_NONE);
  mc_comm_cog_abort(c.get());
  EXPECT_EQ(mc_comm_cog_step(c.get(), 0.5f, 0.0f, &w), MC_COMM_COG_ERR_ABORTED);
  EXPECT_EQ(w, 0.0f);
}

}  // namespace
