// Closed-loop tests of the CSMC position loop of paper 001 (Seshagiri and
// Khalil) with the firmware kernels on the simulated stepper
// (sim/cli/scenarios/csmc_loop.hpp). Each test states its tolerances and
// why; the reference of the first test is an independent continuous-time
// solution written here from the paper's equations (dq model (2), law (5)
// with the printed beta functions, integrators (4)), in double.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "mc_ctrl_csmc.h"
#include "mc_record.hpp"
#include "scenarios/csmc_drive.hpp"
#include "scenarios/csmc_loop.hpp"

namespace {

using mcsim::csmc::Feedback;
using mcsim::csmc::LoopOptions;
using mcsim::csmc::LoopResult;
using mcsim::csmc::RefKind;
using mcsim::csmc::Sample;

constexpr double kPi = 3.14159265358979323846;
constexpr double kStep = mcsim::csmc::kPaperStepRad;

// ---- independent continuous-time closed loop (paper Sec. III, Fig. 2) ----
// State: i_d, i_q, w, phi, sigma1, sigma2.
using X = std::array<double, 6>;

struct RefLoop {
  // plant (actual) and controller (nominal, bounds) as printed in the paper
  double R = 19.0, L = 0.040, Km = 0.1349, J = 4.1295e-4, B = 0.0013, Nr = 50, tl = 0.2;
  double Rh = 20.0, Lh = 0.035, RM = 21.0, LM = 0.040;
  double k01 = 20, k02 = 100, k1 = 7.5e4, k2 = 550, mu1 = 0.1, mu2 = 50;
  bool integ = true;

  static double sat(double v) { return std::max(-1.0, std::min(1.0, v)); }

  X deriv(double t, const X& x) const {
    const double phid = kStep * ((t >= 0.0 ? 1.0 : 0.0) + (t >= 0.5 ? 1.0 : 0.0));
    const double x1 = x[0], x2 = x[1], x3 = x[2], x4 = x[3];
    const double k3 = Km / J, k4 = B / J, d0 = tl / J;
    const double e1 = x1, e2 = x4 - phid, de2 = x3, dde2 = k3 * x2 - k4 * x3 - d0;
    const double s1 = (integ ? k01 * x[4] : 0.0) + e1;
    const double s2 = (integ ? k02 * x[5] : 0.0) + k1 * e2 + k2 * de2 + dde2;
    // nominal parts, theta^ = (Rh/Lh, Km/Lh, 1/Lh)
    const double F1h = -(Rh / Lh) * x1 + Nr * x2 * x3;
    const double G = k1 * de2 + k2 * dde2 - k4 * (k3 * x2 - k4 * x3 - d0) - k3 * Nr * x1 * x3;
    const double F2h = G - k3 * (Rh / Lh) * x2 - k3 * (Km / Lh) * x3;
    const double q1 = 2.1 * k01 * mu1 * LM, q2 = 2.1 * k02 * mu2 * LM;
    const double b1 = ((RM - Rh) * std::abs(x1) + (LM - Lh) * Nr * std::abs(x2 * x3) + q1) / Lh;
    const double b2 = ((RM - Rh) * k3 * std::abs(x2) + (LM - Lh) * std::abs(G) + q2) / Lh;
    const double u1 = (-F1h - b1 * sat(s1 / mu1)) / (1.0 / Lh);
    const double u2 = (-F2h - b2 * sat(s2 / mu2)) / (k3 / Lh);
    X d;
    d[0] = (-R * x1 + u1) / L + Nr * x2 * x3;  // (2), k1 = R/L, k6 = 1/L
    d[1] = (-R * x2 - Km * x3 + u2) / L - Nr * x1 * x3;
    d[2] = k3 * x2 - k4 * x3 - d0;
    d[3] = x3;
    d[4] = integ ? -k01 * x[4] + mu1 * sat(s1 / mu1) : 0.0;  // (4)
    d[5] = integ ? -k02 * x[5] + mu2 * sat(s2 / mu2) : 0.0;
    return d;
  }

  // RK4 with step h from 0 to t_end; records (t, phi).
  void run(double t_end, double h, std::vector<double>* t, std::vector<double>* phi) const {
    X x{};
    const long n = std::lround(t_end / h);
    for (long k = 0; k <= n; ++k) {
      const double tk = static_cast<double>(k) * h;
      if (k % 10 == 0) {
        t->push_back(tk);
        phi->push_back(x[3]);
      }
      if (k == n) break;
      // never straddle the reference jump at 0.5 s inside one RK4 step
      auto add = [](const X& a, const X& b, double c) {
        X r;
        for (size_t i = 0; i < 6; ++i) r[i] = a[i] + c * b[i];
        return r;
      };
      const X d1 = deriv(tk, x);
      const X d2 = deriv(tk + 0.5 * h, add(x, d1, 0.5 * h));
      const X d3 = deriv(tk + 0.5 * h, add(x, d2, 0.5 * h));
      const X d4 = deriv(tk + h, add(x, d3, h));
      for (size_t i = 0; i < 6; ++i) x[i] += h / 6.0 * (d1[i] + 2 * d2[i] + 2 * d3[i] + d4[i]);
    }
  }
};

struct Metrics {
  double over, settle;
};

Metrics metrics(const std::vector<double>& t, const std::vector<double>& phi, double t0, double t1,
                double final_v) {
  double over = 0.0, last = t0;
  for (size_t k = 0; k < t.size(); ++k) {
    if (t[k] < t0 || t[k] > t1) continue;
    over = std::max(over, phi[k] - final_v);
    if (std::abs(phi[k] - final_v) > 0.02 * kStep) last = t[k];
  }
  return {over / kStep, last - t0};
}

TEST(CsmcSil, StateFeedbackStepMatchesContinuousTimeReference) {
  // Reference: RK4, h = 2 us (fastest closed-loop rates ~1e3/s: step error
  // far below the 1e-5 s resolution that matters here).
  RefLoop ref;
  std::vector<double> rt, rphi;
  ref.run(1.0, 2e-6, &rt, &rphi);

  LoopOptions o;
  o.duration_s = 1.0;
  o.dt_s = 1e-5;
  o.ctrl = mcsim::csmc::paper_ctrl(true, true, false);
  const LoopResult r = mcsim::csmc::run_loop(o);
  std::vector<double> kt, kphi;
  for (const Sample& s : r.trace) {
    kt.push_back(s.t);
    kphi.push_back(s.x4);
  }
  for (int stepno = 0; stepno < 2; ++stepno) {
    const double t0 = 0.5 * stepno, t1 = t0 + 0.5, fin = kStep * (stepno + 1);
    const Metrics mr = metrics(rt, rphi, t0, t1, fin);
    const Metrics mk = metrics(kt, kphi, t0, t1, fin);
    // Sanity of the reference itself: the paper's "very little overshoot".
    EXPECT_LT(mr.over, 0.03);
    EXPECT_GT(mr.settle, 0.02);
    // Overshoot within 0.05 % of the step (measured 0.845 % vs 0.844 %):
    // the kernel loop is sampled at 100 kHz with a held voltage (delay
    // ~dt/2 against a ~20 ms response) and runs in float.
    EXPECT_NEAR(mk.over, mr.over, 5e-4) << "step " << stepno;
    // 2 % settling time within 0.5 ms (measured 68.91 vs 68.92 ms and
    // 58.07 vs 58.08 ms): same reasons, plus the 2 % band crossing of a
    // slowly converging tail moves a lot for a small offset.
    EXPECT_NEAR(mk.settle, mr.settle, 5e-4) << "step " << stepno;
  }
}

TEST(CsmcSil, ConditionalIntegratorRemovesTheSteadyStateError) {
  LoopOptions o;
  o.duration_s = 0.4;
  o.dt_s = 1e-5;
  o.step2_t_s = -1.0;
  o.record_every = 10;
  o.ctrl = mcsim::csmc::paper_ctrl(true, true, false);
  const LoopResult with = mcsim::csmc::run_loop(o);
  o.ctrl = mcsim::csmc::paper_ctrl(true, false, false);
  const LoopResult without = mcsim::csmc::run_loop(o);
  // With integral action e2 -> 0: float resolution of phi near 0.03 rad
  // (ulp 3.7e-9) and the e2'' cancellation (k3 iq - d0 ~ 480 rad/s^2 in
  // float, 3e-5 / k1) leave ~1e-8 rad.
  EXPECT_LT(std::abs(with.e2_end), 5e-8);
  // Without: the boundary layer leaves e2 = O(mu2/k1) = O(7e-4 rad); the
  // R, L mismatch makes it at least 1e-5 rad (measured ~1e-4).
  EXPECT_GT(std::abs(without.e2_end), 1e-5);
  EXPECT_GT(std::abs(without.e2_end), 100.0 * std::abs(with.e2_end));
}

TEST(CsmcSil, SampledDataCsmcRegulatesWithoutChatteringIdealSmcChatters) {
  // Paper Fig. 4: T = 0.1 ms, ZOH; CSMC -M sat with conditional integrators
  // against ideal SMC -M sgn (M = 50 V).
  LoopOptions o;
  o.duration_s = 0.4;
  o.dt_s = 1e-4;
  o.substeps = 4;
  o.plant.R_ohm = 19.5;
  o.plant.L_h = 0.030;
  o.step2_t_s = -1.0;
  o.ctrl = mcsim::csmc::paper_ctrl(false, true, false);
  const LoopResult cs = mcsim::csmc::run_loop(o);
  o.ctrl = mcsim::csmc::paper_ctrl(false, false, true);
  const LoopResult sm = mcsim::csmc::run_loop(o);
  const double t0 = 0.3, t1 = 0.4;
  const auto ecs = mcsim::csmc::window_stats(cs.trace, &Sample::e2, t0, t1);
  const auto vcs = mcsim::csmc::window_stats(cs.trace, &Sample::u2, t0, t1);
  const auto esm = mcsim::csmc::window_stats(sm.trace, &Sample::e2, t0, t1);
  const auto vsm = mcsim::csmc::window_stats(sm.trace, &Sample::u2, t0, t1);
  // CSMC: regulation kept (float-limited, see above) and v_q never changes
  // sign (it sits at R i_q + ... ~ 29 V holding the 0.2 N m load); its
  // ripple is float noise (measured 6e-5 V).
  EXPECT_LT(ecs.max_abs, 5e-8);
  EXPECT_EQ(vcs.sign_changes_per_s, 0.0);
  EXPECT_LT(vcs.peak_to_peak, 1e-2);
  // Ideal SMC: v_q switches between +-50 V thousands of times per second
  // (measured 4220/s), and the error does not go to zero (measured mean
  // -4.2e-4 rad).
  EXPECT_GT(vsm.sign_changes_per_s, 1000.0);
  EXPECT_GT(vsm.peak_to_peak, 99.0);
  EXPECT_GT(esm.max_abs, 1e-4);
}

// Paper Fig. 5, output feedback (HGO, eps = 1e-4), T = 50 us by default
// (at T = eps = 100 us the sampled observer limits both designs alike, see
// README). Returns the max |e2| over the last reference period with and
// without the servocompensators (the trace every record_every periods).
std::array<double, 2> sinusoid_errors(double r0, double w0, double duration, double dt = 5e-5,
                                      size_t record_every = 4) {
  LoopOptions o;
  o.duration_s = duration;
  o.dt_s = dt;
  o.plant.R_ohm = 19.5;
  o.plant.L_h = 0.030;
  o.ref = RefKind::kCos;
  o.r0_rad = r0;
  o.w0_rad_s = w0;
  o.fb = Feedback::kHgo;
  o.hgo = mcsim::csmc::paper_hgo(1e-4);
  o.record_every = record_every;
  o.ctrl = mcsim::csmc::paper_ctrl(false, false, false);
  mcsim::csmc::paper_servo(w0, &o.ctrl);
  const LoopResult sv = mcsim::csmc::run_loop(o);
  o.ctrl = mcsim::csmc::paper_ctrl(false, false, false);
  const LoopResult ns = mcsim::csmc::run_loop(o);
  const double t1 = o.duration_s, t0 = t1 - 2.0 * kPi / w0;  // last period
  return {mcsim::csmc::window_stats(sv.trace, &Sample::e2, t0, t1).max_abs,
          mcsim::csmc::window_stats(ns.trace, &Sample::e2, t0, t1).max_abs};
}

// The criterion: at least 10x smaller steady-state error with the
// servocompensator. Its slowest pole is -1 rad/s, so the residual decays as
// ~e^-t (measured: 10x reached after ~6 s); 7 s runs keep the test short.
// Without it the error is O(mu2/k1) = O(7e-4 rad) (measured 3.9e-4).
TEST(CsmcSil, ServocompensatorCutsSinusoidalErrorTenfoldFastReference) {
  const auto e = sinusoid_errors(kPi / 10.0, 5.0, 7.0);
  EXPECT_GT(e[1], 10.0 * e[0]) << "with " << e[0] << ", without " << e[1];
  EXPECT_GT(e[1], 1e-4);
}

TEST(CsmcSil, ServocompensatorCutsSinusoidalErrorTenfoldLargeReference) {
  const auto e = sinusoid_errors(kPi / 2.0, 2.0, 7.0);
  EXPECT_GT(e[1], 10.0 * e[0]) << "with " << e[0] << ", without " << e[1];
  EXPECT_GT(e[1], 1e-4);
}

// ---- Fig. 5 in double precision: the reference for the float32 floor ----
// The same closed loop in continuous time, written here from the paper:
// dq model (2) with the Fig. 5 plant (R = 19.5, L = 0.030), law
// u_i = -M_i sat(s_i / mu_i), state feedback, the conditional
// servocompensators (9) sigma_i' = S_i sigma_i + J (mu_i sat(s_i/mu_i) -
// K0_i sigma_i), s1 = K01 sigma1 + e1, s2 = K02 sigma2 + k1 e2 + k2 e2' +
// e2'', with K0 placing {-1, -2+-j, -3+-j} and {-1, -2+-j} (computed here
// in double); RK4 at h = 5 us (the fastest closed-loop rate, about
// k3 M2 / (mu2 L) = 1.1e4 /s, gives h lambda = 0.05).
struct SinRefLoop {
  double R = 19.5, L = 0.030, Km = 0.1349, J = 4.1295e-4, B = 0.0013, Nr = 50, tl = 0.2;
  double k1 = 7.5e4, k2 = 550, mu1 = 0.1, mu2 = 50, M1 = 50, M2 = 50;
  double r0, w0;
  double c1[5], k01[5], c2[3], k02[3];
  static constexpr size_t kN = 4 + 5 + 3;
  using Y = std::array<double, kN>;

  // Monic polynomial with the given roots (complex ones in conjugate
  // pairs: re +- j im), coefficients p_0 .. p_{n-1}.
  static void poly(const std::vector<std::array<double, 2>>& roots, double* p, size_t n) {
    std::vector<double> c{1.0};  // highest power first
    for (const auto& r : roots) {
      std::vector<double> f =
          r[1] == 0.0 ? std::vector<double>{1.0, -r[0]}
                      : std::vector<double>{1.0, -2.0 * r[0], r[0] * r[0] + r[1] * r[1]};
      std::vector<double> m(c.size() + f.size() - 1, 0.0);
      for (size_t i = 0; i < c.size(); ++i)
        for (size_t j = 0; j < f.size(); ++j) m[i + j] += c[i] * f[j];
      c = m;
    }
    for (size_t i = 0; i < n; ++i) p[i] = c[n - i];
  }

  SinRefLoop(double r0_rad, double w0_rad_s) : r0(r0_rad), w0(w0_rad_s) {
    const double w2 = w0 * w0;
    const double cc1[5] = {0.0, -4.0 * w2 * w2, 0.0, -5.0 * w2, 0.0};
    const double cc2[3] = {0.0, -w2, 0.0};
    double p1[5], p2[3];
    poly({{-1, 0}, {-2, 1}, {-3, 1}}, p1, 5);
    poly({{-1, 0}, {-2, 1}}, p2, 3);
    for (int i = 0; i < 5; ++i) c1[i] = cc1[i], k01[i] = cc1[i] + p1[i];
    for (int i = 0; i < 3; ++i) c2[i] = cc2[i], k02[i] = cc2[i] + p2[i];
  }

  static double sat(double v) { return std::max(-1.0, std::min(1.0, v)); }

  Y deriv(double t, const Y& y) const {
    const double x1 = y[0], x2 = y[1], x3 = y[2], x4 = y[3];
    const double c = std::cos(w0 * t), sn = std::sin(w0 * t);
    const double phid = r0 * c, dphid = -r0 * w0 * sn, ddphid = -r0 * w0 * w0 * c;
    const double k3 = Km / J, k4 = B / J, d0 = tl / J;
    const double e1 = x1, e2 = x4 - phid, de2 = x3 - dphid;
    const double dde2 = k3 * x2 - k4 * x3 - d0 - ddphid;
    const double* s1v = &y[4];
    const double* s2v = &y[9];
    double t1 = 0.0, t2 = 0.0;
    for (int i = 0; i < 5; ++i) t1 += k01[i] * s1v[i];
    for (int i = 0; i < 3; ++i) t2 += k02[i] * s2v[i];
    const double s1 = t1 + e1, s2 = t2 + k1 * e2 + k2 * de2 + dde2;
    const double u1 = -M1 * sat(s1 / mu1), u2 = -M2 * sat(s2 / mu2);
    Y d{};
    d[0] = (-R * x1 + u1) / L + Nr * x2 * x3;
    d[1] = (-R * x2 - Km * x3 + u2) / L - Nr * x1 * x3;
    d[2] = k3 * x2 - k4 * x3 - d0;
    d[3] = x3;
    // companion S: sigma_i' = sigma_{i+1}, last row c . sigma + input
    const double v1 = mu1 * sat(s1 / mu1) - t1, v2 = mu2 * sat(s2 / mu2) - t2;
    for (int i = 0; i < 4; ++i) d[4 + i] = s1v[i + 1];
    d[8] = v1;
    for (int i = 0; i < 5; ++i) d[8] += c1[i] * s1v[i];
    for (int i = 0; i < 2; ++i) d[9 + i] = s2v[i + 1];
    d[11] = v2;
    for (int i = 0; i < 3; ++i) d[11] += c2[i] * s2v[i];
    return d;
  }

  // max |e2| over [t_end - 2 pi / w0, t_end], plant at rest at 0 (as run_loop).
  double tail_max_abs_e2(double t_end, double h) const {
    Y y{};
    const long n = std::lround(t_end / h);
    const double t0 = t_end - 2.0 * kPi / w0;
    double emax = 0.0;
    for (long k = 0; k <= n; ++k) {
      const double tk = static_cast<double>(k) * h;
      if (tk >= t0) emax = std::max(emax, std::abs(y[3] - r0 * std::cos(w0 * tk)));
      if (k == n) break;
      auto add = [](const Y& a, const Y& b, double cf) {
        Y r;
        for (size_t i = 0; i < kN; ++i) r[i] = a[i] + cf * b[i];
        return r;
      };
      const Y d1 = deriv(tk, y);
      const Y d2 = deriv(tk + 0.5 * h, add(y, d1, 0.5 * h));
      const Y d3 = deriv(tk + 0.5 * h, add(y, d2, 0.5 * h));
      const Y d4 = deriv(tk + h, add(y, d3, h));
      for (size_t i = 0; i < kN; ++i) y[i] += h / 6.0 * (d1[i] + 2 * d2[i] + 2 * d3[i] + d4[i]);
    }
    return emax;
  }
};

// Paper Fig. 5 as `mcsim run csmc-sinusoid` runs it (output feedback, eps =
// 1e-4, dt = 10 us, 10 s; the last reference period) at both of the paper's
// settings, against the double-precision reference above (state feedback,
// continuous time, the same 10 s). Recorded for the csmc README.
//
// The float32 floor was the servocompensators' modal states: at steady
// state they carry the internal model's sinusoids and each step adds w dt
// (5e-5) of them plus an input of the size of the tracking error; rounding
// every new sum to float lost ulp(xi)/2 per step, a random walk of the
// internal model's phase that the loop saw as a disturbance (it grew as dt
// shrank). MC_CSVC_ACC_F32 carries each sum's rounding error.
void SinusoidAgainstDouble(double r0, double w0, const char* tag, double bound_over_ref) {
  const double duration_s = 10.0;
  const auto e = sinusoid_errors(r0, w0, duration_s, 1e-5, 10);
  const double e_sv = e[0], e_ns = e[1];
  const double e_ref = SinRefLoop(r0, w0).tail_max_abs_e2(duration_s, 5e-6);
  const std::string k(tag);
  mc_record("svc_e2_max_abs_rad." + k, e_sv);
  mc_record("nosvc_e2_max_abs_rad." + k, e_ns);
  mc_record("ratio." + k, e_ns / e_sv);
  mc_record("double_ref_e2_max_abs_rad." + k, e_ref);
  mc_record("svc_over_double_ref." + k, e_sv / e_ref, bound_over_ref);
  // Without the servocompensators the error is O(mu2 / k1) (7e-4 rad).
  EXPECT_GT(e_ns, 1e-4);
  // The paper's claim, in the README before: "more than 300x"; with the
  // floor gone the factor must exceed it at both settings.
  EXPECT_GT(e_ns / e_sv, 300.0) << "with " << e_sv << ", without " << e_ns;
  // Against the double-precision continuous loop: the tail left is the
  // decaying transient of the slowest servocompensator pole (-1 rad/s), the
  // same in both; the sampled (10 us), output-feedback (HGO) float loop
  // differs from the continuous state-feedback one by a few % of it
  // (measured +0.8 % at (pi/10, 5), -2.1 % at (pi/2, 2)): within 5 %.
  // With the floor the float tail was 3.5x the double one at (pi/10, 5).
  EXPECT_LT(e_sv, bound_over_ref * e_ref) << "float " << e_sv << ", double " << e_ref;
  EXPECT_GT(e_sv, (2.0 - bound_over_ref) * e_ref) << "float " << e_sv << ", double " << e_ref;
}

TEST(CsmcSil, ServocompensatorFloorFastSetting) {
  SinusoidAgainstDouble(kPi / 10.0, 5.0, "pi_10_w5", 1.05);
}

TEST(CsmcSil, ServocompensatorFloorLargeSetting) {
  SinusoidAgainstDouble(kPi / 2.0, 2.0, "pi_2_w2", 1.05);
}

TEST(CsmcSil, OutputFeedbackApproachesStateFeedbackAsEpsDecreases) {
  // Paper Fig. 3(b): max |e2_of - e2_sf| over the step response shrinks
  // monotonically with eps (measured 1.2e-2, 7.0e-3, 4.0e-3 rad for
  // eps = 2e-4, 1e-4, 5e-5).
  LoopOptions o;
  o.duration_s = 0.1;
  o.dt_s = 1e-5;
  o.plant.R_ohm = 19.5;
  o.plant.L_h = 0.030;
  o.step2_t_s = -1.0;
  o.ctrl = mcsim::csmc::paper_ctrl(false, true, false);
  const LoopResult sf = mcsim::csmc::run_loop(o);
  std::vector<double> dev;
  for (double eps : {2e-4, 1e-4, 5e-5}) {
    o.fb = Feedback::kHgo;
    o.hgo = mcsim::csmc::paper_hgo(eps);
    const LoopResult of = mcsim::csmc::run_loop(o);
    double d = 0.0;
    for (size_t k = 0; k < of.trace.size(); ++k) {
      d = std::max(d, std::abs(of.trace[k].e2 - sf.trace[k].e2));
    }
    dev.push_back(d);
  }
  // Each halving of eps must cut the deviation by at least 25 % (the theory
  // says O(eps); measured ratios ~0.58).
  EXPECT_LT(dev[1], 0.75 * dev[0]);
  EXPECT_LT(dev[2], 0.75 * dev[1]);
  // ... and at eps = 5e-5 it is below 20 % of the step.
  EXPECT_LT(dev[2], 0.2 * kStep);
}

// ---- through the firmware path: drive (CTRL mode) + plug-in + board ----
TEST(CsmcSil, DrivePluginRegulatesTheStepperOnTheSimulatedBoard) {
  // 10 kHz fast loop, one-period computation delay, 12-bit currents (5 A
  // full scale), 2^18-count encoder, state feedback (speed from the drive's
  // tracking loop), mu widened for the delay (see csmc_drive.hpp).
  mcsim::csmc::DriveOptions o;
  o.plant.R_ohm = 19.5;
  o.plant.L_h = 0.030;
  o.duration_s = 0.3;
  const auto r = mcsim::csmc::run_drive(o);
  ASSERT_EQ(r.faults, 0u);
  double emax = 0.0, over = 0.0, last_out = 0.0;
  long changes = 0;
  double prev = 0.0;
  for (const auto& s : r.trace) {
    over = std::max(over, s.e2);
    if (std::abs(s.e2) > 0.02 * kStep) last_out = s.t;
    if (s.t >= 0.2) {
      emax = std::max(emax, std::abs(s.e2));
      if ((s.v_q > 0.0 && prev < 0.0) || (s.v_q < 0.0 && prev > 0.0)) ++changes;
      if (s.v_q != 0.0) prev = s.v_q;
    }
  }
  // Regulated to the encoder's resolution: 2 counts = 4.8e-5 rad (measured
  // 1.7e-5), no v_q sign change at steady state (it holds the load).
  EXPECT_LT(emax, 2.0 * 2.0 * kPi / (1 << 18));
  EXPECT_EQ(changes, 0);
  // Step response as the kernel loop's at 10 kHz, slowed a little by the
  // delay and the wider layers: overshoot < 2 % (measured 0.05 %), 2 %
  // settling < 60 ms (measured 29 ms).
  EXPECT_LT(over, 0.02 * kStep);
  EXPECT_LT(last_out, 0.06);
}

TEST(CsmcSil, DrivePluginRejectsBadConfigAndReference) {
  mc_ctrl_csmc_cfg_t c{};
  c.law = mcsim::csmc::paper_ctrl(false, true, false);
  c.law.dt_s = 1e-4f;
  c.feedback = MC_CTRL_CSMC_FB_HGO;
  c.hgo = mcsim::csmc::paper_hgo(1e-3);
  c.hgo.dt_s = 1e-4f;
  c.duty_max = 1.5f;
  mc_ctrl_csmc_t p{};
  EXPECT_EQ(mc_ctrl_csmc_init(&p, &c), MC_CTRL_CSMC_ERR_DUTY);
  c.duty_max = 1.0f;
  c.hgo.alpha3 = 1e4f;
  EXPECT_EQ(mc_ctrl_csmc_init(&p, &c), MC_CTRL_CSMC_ERR_HGO);
  c.hgo.alpha3 = 100.0f;
  c.law.mu2_rad_s2 = -1.0f;
  EXPECT_EQ(mc_ctrl_csmc_init(&p, &c), MC_CTRL_CSMC_ERR_LAW);
  c.law.mu2_rad_s2 = 50.0f;
  c.feedback = MC_CTRL_CSMC_FB_STATE;
  c.law.model.j_kgm2 = 0.0f;  // state feedback needs the model for e2''
  EXPECT_EQ(mc_ctrl_csmc_init(&p, &c), MC_CTRL_CSMC_ERR_FEEDBACK);
  c.law.model.j_kgm2 = 4.1295e-4f;
  ASSERT_EQ(mc_ctrl_csmc_init(&p, &c), MC_CTRL_CSMC_ERR_NONE);
  const mc_drive_ctrl_t* ops = mc_ctrl_csmc_ops(&p);
  ASSERT_NE(ops, nullptr);
  EXPECT_EQ(ops->outputs, MC_DRIVE_OUT_PWM2);
  EXPECT_EQ(mc_ctrl_csmc_set_ref(&p, std::nanf(""), 0, 0, 0, 0, 0), MC_CTRL_CSMC_ERR_REF);
  EXPECT_EQ(p.ref.phi_d_rad, 0.0f);
  // No encoder reading: the law refuses to run (the drive then faults).
  mc_drive_meas_t m{};
  m.vbus_v = 60.0f;
  mc_drive_out_t out{};
  EXPECT_EQ(ops->fast(ops->ctx, &m, &out), MC_CTRL_CSMC_ERR_ENCODER);
  m.have_encoder = true;
  m.enc_cpr = 4096u;
  m.vbus_v = 0.0f;
  EXPECT_EQ(ops->fast(ops->ctx, &m, &out), MC_CTRL_CSMC_ERR_VBUS);
  m.vbus_v = 60.0f;
  EXPECT_EQ(ops->fast(ops->ctx, &m, &out), MC_CTRL_CSMC_ERR_NONE);
}

}  // namespace
