// Dirty-derivative filter theta = b s/(s+a) y (paper 000, (11)-(12)):
// frequency response against the transfer function, ramp response, first
// step, config validation, non-finite input.
#include <cmath>
#include <complex>

#include <gtest/gtest.h>

extern "C" {
#include "filters/mc_ddiff.h"
}

namespace {

constexpr double kPi = 3.14159265358979323846;

mc_ddiff_f32_t make(float a, float b, float dt) {
  mc_ddiff_f32_t st{};
  const mc_ddiff_f32_cfg_t c{a, b, dt};
  EXPECT_EQ(mc_ddiff_f32_init(&st, &c), MC_DDIFF_ERR_NONE);
  return st;
}

// The step's output theta_f; the step must have run (MC_DDIFF_ERR_NONE).
float step(mc_ddiff_f32_t* st, float y) {
  float th = NAN;
  EXPECT_EQ(mc_ddiff_f32_step(st, y, &th), MC_DDIFF_ERR_NONE);
  return th;
}

std::complex<double> h_cont(double a, double b, double w) {
  const std::complex<double> s(0.0, w);
  return b * s / (s + a);
}

// Measured complex gain of the kernel at w: drive with sin(w t), skip the
// transient (10 time constants 1/a), then project one whole number of periods
// of the output onto sin and cos (least squares for a pure sinusoid).
std::complex<double> measured_gain(float a, float b, float dt, double w) {
  mc_ddiff_f32_t st = make(a, b, dt);
  const long skip = static_cast<long>(std::ceil(10.0 / (a * dt)));
  const long per = static_cast<long>(std::lround(2.0 * kPi / (w * dt)));
  const long cycles = std::max(1L, 2000L / per);
  double ss = 0, sc = 0, cc = 0, ys = 0, yc = 0;
  for (long k = 0; k < skip + cycles * per; ++k) {
    const double t = k * dt;
    const float y = step(&st, static_cast<float>(std::sin(w * t)));
    if (k >= skip) {
      const double s = std::sin(w * t), c = std::cos(w * t);
      ss += s * s;
      sc += s * c;
      cc += c * c;
      ys += y * s;
      yc += y * c;
    }
  }
  // y = A s + B c -> gain = A + j B (sin(wt + phi) = cos(phi) s + sin(phi) c).
  const double det = ss * cc - sc * sc;
  const double A = (ys * cc - yc * sc) / det, B = (yc * ss - ys * sc) / det;
  return {A, B};
}

TEST(Ddiff, FrequencyResponseMatchesPrewarpedTransferFunction) {
  const float a = 50.0f, b = 50.0f, dt = 1.0e-3f;
  for (double f_hz : {0.5, 2.0, 8.0, 30.0, 100.0, 250.0}) {
    const double w = 2.0 * kPi * f_hz;
    const std::complex<double> g = measured_gain(a, b, dt, w);
    // Tustin: H_d(e^{jwT}) = H((2/T) tan(wT/2)) exactly; what is left is
    // float rounding of a sum over ~2000 samples and the leakage of the
    // decayed transient (exp(-10) of a gain-b step response): 1e-4 relative.
    const std::complex<double> hw = h_cont(a, b, 2.0 / dt * std::tan(w * dt / 2.0));
    EXPECT_LT(std::abs(g - hw), 1.0e-4 * std::abs(hw)) << f_hz << " Hz";
    // Against H(jw) itself the warping error is ~ (wT)^2/12 relative in
    // frequency; at f <= 8 Hz (wT <= 0.05) that is < 3e-4 of the gain.
    if (f_hz <= 8.0) {
      const std::complex<double> hc = h_cont(a, b, w);
      EXPECT_LT(std::abs(g - hc), 3.0e-4 * std::abs(hc)) << f_hz << " Hz";
    }
  }
}

TEST(Ddiff, LowFrequencyGainIsBOverATimesDerivative) {
  // A ramp y = v t: Tustin differentiates it exactly, theta -> (b/a) v.
  const float a = 200.0f, b = 3.0f, dt = 1.0e-4f, v = 2.5f;
  mc_ddiff_f32_t st = make(a, b, dt);
  float out = 0.0f;
  for (int k = 0; k < 20000; ++k) out = step(&st, v * static_cast<float>(k) * dt);
  // Float rounding only: theta is the state (size 0.0375, ulp 3.7e-9) and
  // y enters by its increment (rounded to ulp(5) = 4.8e-7 relative to
  // g = 3/1.01): one rounding per step decays with c_q = 1 - a dt, so at
  // most 1/(a dt) = 50 add up: 50 * g * ulp(y)... bounded by 1e-6 (the
  // realisation on q_c of the printed (11)-(12) was 6.3e-6 off here).
  EXPECT_NEAR(out, b / a * v, 1.0e-6);
}

TEST(Ddiff, FirstStepIsPresetPlusBY) {
  mc_ddiff_f32_t st = make(10.0f, 4.0f, 1e-3f);
  ASSERT_EQ(mc_ddiff_f32_reset(&st, 0.25f), MC_DDIFF_ERR_NONE);
  // No integration on the first sample: q0 + b y exactly.
  EXPECT_EQ(step(&st, 0.5f), 0.25f + 4.0f * 0.5f);
  // Second step is one trapezoidal step of (11): q1 = c_q q0 - c_y (y1 + y0),
  // c_y = (a b dt/2)/(1 + a dt/2).
  const float h = 0.5f * 10.0f * 1e-3f;
  const float q1 = (1.0f - h) / (1.0f + h) * 0.25f - (h * 4.0f) / (1.0f + h) * (0.5f + 0.5f);
  EXPECT_NEAR(step(&st, 0.5f), q1 + 2.0f, 1e-6f);
}

TEST(Ddiff, StepResponseMatchesContinuousFilter) {
  // y steps from 0 to 1 after the first sample: continuous theta(t) =
  // b exp(-a t). Trapezoidal rule on a step: the step is seen spread over one
  // sample, so compare from t = 5 dt on with the half-sample shift
  // (exp(-a (t - dt/2)) correction) and an O((a dt)^2) tolerance.
  const float a = 20.0f, b = 2.0f, dt = 1.0e-3f;
  mc_ddiff_f32_t st = make(a, b, dt);
  (void)step(&st, 0.0f);
  for (int k = 1; k < 300; ++k) {
    const float out = step(&st, 1.0f);
    const double t = (k - 0.5) * dt;
    if (k >= 5) {
      // (a dt)^2 = 4e-4 relative error of the discrete pole, times b.
      EXPECT_NEAR(out, b * std::exp(-a * t), 2e-3) << k;
    }
  }
}

TEST(Ddiff, InitRejectsBadConfigAndLeavesStateAlone) {
  mc_ddiff_f32_t st = make(1.0f, 1.0f, 1.0f);
  st.out = 42.0f;
  const mc_ddiff_f32_cfg_t bad_a{0.0f, 1.0f, 1e-3f}, bad_b{1.0f, -1.0f, 1e-3f},
      bad_dt{1.0f, 1.0f, NAN}, bad_all{NAN, 0.0f, 0.0f};
  EXPECT_EQ(mc_ddiff_f32_init(&st, &bad_a), MC_DDIFF_ERR_A);
  EXPECT_EQ(mc_ddiff_f32_init(&st, &bad_b), MC_DDIFF_ERR_B);
  EXPECT_EQ(mc_ddiff_f32_init(&st, &bad_dt), MC_DDIFF_ERR_DT);
  EXPECT_EQ(mc_ddiff_f32_init(&st, &bad_all), MC_DDIFF_ERR_A | MC_DDIFF_ERR_B | MC_DDIFF_ERR_DT);
  EXPECT_EQ(mc_ddiff_f32_init(nullptr, &bad_a), MC_DDIFF_ERR_NULL);
  EXPECT_EQ(st.out, 42.0f);
}

TEST(Ddiff, NonFiniteInputIsRefusedAndSticky) {
  mc_ddiff_f32_t st = make(10.0f, 1.0f, 1e-3f);
  const float y1 = step(&st, 0.1f);
  // Refused: the bit returned (and made sticky), the last output written.
  float th = 0.0f;
  EXPECT_EQ(mc_ddiff_f32_step(&st, NAN, &th), MC_DDIFF_ERR_NAN_INPUT);
  EXPECT_EQ(th, y1);
  th = 0.0f;
  EXPECT_EQ(mc_ddiff_f32_step(&st, INFINITY, &th), MC_DDIFF_ERR_NAN_INPUT);
  EXPECT_EQ(th, y1);
  EXPECT_NE(st.flags & MC_DDIFF_ERR_NAN_INPUT, 0u);
  (void)step(&st, 0.1f);
  EXPECT_NE(st.flags & MC_DDIFF_ERR_NAN_INPUT, 0u);
  EXPECT_EQ(mc_ddiff_f32_reset(&st, NAN), MC_DDIFF_ERR_NAN_INPUT);
  EXPECT_EQ(mc_ddiff_f32_reset(&st, 0.0f), MC_DDIFF_ERR_NONE);
  EXPECT_EQ(st.flags, 0u);
}

TEST(Ddiff, NullPointersAreRefusedAndNothingIsWritten) {
  mc_ddiff_f32_t st = make(10.0f, 1.0f, 1e-3f);
  (void)step(&st, 0.1f);
  const float out_before = st.out;
  const float y_before = st.y_prev;
  float th = 42.0f;
  EXPECT_EQ(mc_ddiff_f32_step(nullptr, 0.2f, &th), MC_DDIFF_ERR_NULL);
  EXPECT_EQ(th, 42.0f);
  EXPECT_EQ(mc_ddiff_f32_step(&st, 0.2f, nullptr), MC_DDIFF_ERR_NULL);
  EXPECT_EQ(st.out, out_before);
  EXPECT_EQ(st.y_prev, y_before);
  EXPECT_EQ(mc_ddiff_f32_reset(nullptr, 0.0f), MC_DDIFF_ERR_NULL);
}

}  // namespace
