// firmware/kernels/ident against closed forms: averages, least-squares
// lines, circular means, R from two DC levels, L from a square wave on an
// R-L winding (the exact ripple 2 v / R tanh(R dt / 2 L)).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

extern "C" {
#include "ident/mc_ident.h"
}

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

TEST(IdentAvg, MeanEmptyAndNaN) {
  mc_ident_avg_f32_t a;
  mc_ident_avg_f32_reset(&a);
  float m = 1.0f;
  EXPECT_EQ(MC_IDENT_ERR_EMPTY, mc_ident_avg_f32_get(&a, &m));
  EXPECT_EQ(0.0f, m);
  for (int k = 1; k <= 4; ++k) EXPECT_EQ(MC_IDENT_ERR_NONE, mc_ident_avg_f32_step(&a, (float)k));
  EXPECT_EQ(MC_IDENT_ERR_NAN, mc_ident_avg_f32_step(&a, kNaN));  // refused, not added
  EXPECT_EQ(4u, a.n);
  EXPECT_EQ(MC_IDENT_ERR_NONE, mc_ident_avg_f32_get(&a, &m));
  EXPECT_FLOAT_EQ(2.5f, m);
}

// Compensated: 10^6 samples of 1 + 1e-4 keep float's relative precision
// (a plain float sum drifts by about 1e-2 here).
TEST(IdentAvg, CompensatedOverAMillionSamples) {
  mc_ident_avg_f32_t a;
  mc_ident_avg_f32_reset(&a);
  for (int k = 0; k < 1000000; ++k) (void)mc_ident_avg_f32_step(&a, 1.0001f);
  float m = 0.0f;
  ASSERT_EQ(MC_IDENT_ERR_NONE, mc_ident_avg_f32_get(&a, &m));
  EXPECT_NEAR(1.0001f, m, 2e-7f);
}

TEST(IdentLine, ExactLineWithAndWithoutIntercept) {
  mc_ident_line_f32_t l;
  mc_ident_line_f32_reset(&l);
  for (int k = -10; k <= 10; ++k)
    (void)mc_ident_line_f32_step(&l, 0.1f * k, 2.0f + 3.0f * 0.1f * k);
  float b = 0.0f, a = 0.0f;
  ASSERT_EQ(MC_IDENT_ERR_NONE, mc_ident_line_f32_get(&l, true, &b, &a));
  EXPECT_NEAR(3.0f, b, 1e-5f);
  EXPECT_NEAR(2.0f, a, 1e-5f);
  // Through the origin: y = 0.5 x.
  mc_ident_line_f32_reset(&l);
  for (int k = 1; k <= 50; ++k) (void)mc_ident_line_f32_step(&l, (float)k, 0.5f * k);
  ASSERT_EQ(MC_IDENT_ERR_NONE, mc_ident_line_f32_get(&l, false, &b, nullptr));
  EXPECT_NEAR(0.5f, b, 1e-6f);
}

TEST(IdentLine, TooFewOrDegenerate) {
  mc_ident_line_f32_t l;
  mc_ident_line_f32_reset(&l);
  float b = 0.0f;
  (void)mc_ident_line_f32_step(&l, 1.0f, 1.0f);
  EXPECT_EQ(MC_IDENT_ERR_EMPTY, mc_ident_line_f32_get(&l, true, &b, nullptr));
  (void)mc_ident_line_f32_step(&l, 1.0f, 2.0f);  // x does not vary
  EXPECT_NE(0u, mc_ident_line_f32_get(&l, true, &b, nullptr) & MC_IDENT_ERR_DEGENERATE);
}

TEST(IdentCirc, MeanAcrossTheWrapAndOpposites) {
  mc_ident_circ_f32_t c;
  mc_ident_circ_f32_reset(&c);
  (void)mc_ident_circ_f32_step(&c, 3.1f);
  (void)mc_ident_circ_f32_step(&c, -3.1f);  // the mean is pi, not 0
  float m = 0.0f, r = 0.0f;
  ASSERT_EQ(MC_IDENT_ERR_NONE, mc_ident_circ_f32_get(&c, &m, &r));
  EXPECT_NEAR(3.14159265f, std::fabs(m), 1e-3f);
  EXPECT_NEAR(std::cos(0.0416f), r, 1e-3f);
  mc_ident_circ_f32_reset(&c);
  (void)mc_ident_circ_f32_step(&c, 0.3f);
  (void)mc_ident_circ_f32_step(&c, 0.3f + 3.14159265f);
  EXPECT_EQ(MC_IDENT_ERR_DEGENERATE, mc_ident_circ_f32_get(&c, &m, &r));
}

// v = R i + v0 at both levels (the dead-time drop v0 is the same): R exact.
TEST(IdentR, TwoLevelsCancelAConstantDrop) {
  const float r = 0.039f, v0 = 0.35f;
  float est = 0.0f;
  ASSERT_EQ(MC_IDENT_ERR_NONE,
            mc_ident_r_two_level_f32(r * 5.0f + v0, 5.0f, r * 10.0f + v0, 10.0f, &est));
  EXPECT_NEAR(r, est, 1e-6f);
  EXPECT_EQ(MC_IDENT_ERR_RANGE, mc_ident_r_two_level_f32(1.0f, 5.0f, 1.1f, 5.0f, &est));
  EXPECT_EQ(MC_IDENT_ERR_RANGE, mc_ident_r_two_level_f32(1.0f, 5.0f, 0.9f, 10.0f, &est));
  EXPECT_EQ(MC_IDENT_ERR_NAN, mc_ident_r_two_level_f32(kNaN, 5.0f, 0.9f, 10.0f, &est));
  EXPECT_EQ(0.0f, est);
}

// The steady ripple of +-v alternating every dt on R-L:
// di_pp = 2 v / R tanh(R dt / (2 L)); the estimator inverts it.
TEST(IdentL, SquareWaveInvertsTheExactRipple) {
  const double v = 2.0, dt = 1.0 / 20000.0;
  for (double l : {8e-6, 25e-6, 1.14e-3}) {
    for (double r : {0.0, 0.02, 0.675, 5.0}) {
      const double x = r * dt / (2 * l);
      if (x > 0.45) continue;  // the documented domain
      const double di = (r == 0.0) ? v * dt / l : 2 * v / r * std::tanh(x);
      float est = 0.0f;
      ASSERT_EQ(MC_IDENT_ERR_NONE,
                mc_ident_l_square_wave_f32((float)v, (float)dt, (float)di, (float)r, &est))
          << "L " << l << " R " << r;
      EXPECT_NEAR(1.0, est / l, 2e-6) << "L " << l << " R " << r;
    }
  }
}

TEST(IdentL, OutsideTheDomain) {
  float est = 1.0f;
  EXPECT_EQ(MC_IDENT_ERR_RANGE, mc_ident_l_square_wave_f32(0.0f, 5e-5f, 0.1f, 0.1f, &est));
  EXPECT_EQ(MC_IDENT_ERR_RANGE, mc_ident_l_square_wave_f32(1.0f, 5e-5f, 0.0f, 0.1f, &est));
  EXPECT_EQ(MC_IDENT_ERR_RANGE, mc_ident_l_square_wave_f32(1.0f, 5e-5f, 0.1f, -0.1f, &est));
  // R di / 2v = 0.5 > 0.46: the series would be inaccurate.
  EXPECT_EQ(MC_IDENT_ERR_RANGE, mc_ident_l_square_wave_f32(1.0f, 5e-5f, 1.0f, 1.0f, &est));
  EXPECT_EQ(MC_IDENT_ERR_NAN, mc_ident_l_square_wave_f32(1.0f, kNaN, 0.1f, 0.1f, &est));
  EXPECT_EQ(0.0f, est);
}

// Return convention (kernels/README.md): reset and step return the bits the
// call raised; a NULL accumulator is MC_IDENT_ERR_NULL.
TEST(IdentAccumulators, ResetAndStepReturnTheirBits) {
  mc_ident_avg_f32_t a;
  mc_ident_line_f32_t l;
  mc_ident_circ_f32_t c;
  EXPECT_EQ(MC_IDENT_ERR_NONE, mc_ident_avg_f32_reset(&a));
  EXPECT_EQ(MC_IDENT_ERR_NONE, mc_ident_line_f32_reset(&l));
  EXPECT_EQ(MC_IDENT_ERR_NONE, mc_ident_circ_f32_reset(&c));
  EXPECT_EQ(MC_IDENT_ERR_NULL, mc_ident_avg_f32_reset(nullptr));
  EXPECT_EQ(MC_IDENT_ERR_NULL, mc_ident_line_f32_reset(nullptr));
  EXPECT_EQ(MC_IDENT_ERR_NULL, mc_ident_circ_f32_reset(nullptr));
  EXPECT_EQ(MC_IDENT_ERR_NULL, mc_ident_avg_f32_step(nullptr, 1.0f));
  EXPECT_EQ(MC_IDENT_ERR_NULL, mc_ident_line_f32_step(nullptr, 1.0f, 2.0f));
  EXPECT_EQ(MC_IDENT_ERR_NULL, mc_ident_circ_f32_step(nullptr, 1.0f));
  EXPECT_EQ(MC_IDENT_ERR_NAN, mc_ident_line_f32_step(&l, kNaN, 2.0f));
  EXPECT_EQ(MC_IDENT_ERR_NAN, mc_ident_circ_f32_step(&c, kNaN));
  EXPECT_EQ(0u, l.sx.n);  // refused samples are not added
  EXPECT_EQ(0u, c.s.n);
  EXPECT_EQ(MC_IDENT_ERR_NONE, mc_ident_line_f32_step(&l, 1.0f, 2.0f));
  EXPECT_EQ(MC_IDENT_ERR_NONE, mc_ident_circ_f32_step(&c, 1.0f));
  EXPECT_EQ(1u, l.sx.n);
  EXPECT_EQ(1u, c.s.n);
}

}  // namespace
