// pi2d-paper (the firmware kernel sampled at 10 kHz with zero-order hold on
// the simulator's normalised PMSM) against an independent continuous-time
// solution of the same closed loop: plant (1)-(4) and the law (6), (8)-(12),
// (14), (35) written here from the paper in double precision, integrated by
// RK4 with a step 1/4 of the control period, split at the profile's corners.
#include <algorithm>
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "scenarios/pi2d_sil.hpp"
#include "mc_record.hpp"

namespace {

// Section V values.
constexpr double kSigma = 0.51, kGamma = 0.17, kTau = 1.0;
constexpr double kK1 = 4.0, kK2 = 75.0, kKp = 5.0, kKd = 10.0, kKi = 0.01, kA = 50.0, kB = 50.0,
                 kEps = 0.02;

// Speed profile, written again from the paper's text (not shared with the
// scenario): piecewise-linear speed through (0,0), (1,5.25), (3,5.25),
// (5,12.6), (7,12.6), (9,0), then 0. The segment is chosen by t_sel (the
// middle of the integration step), so that an RK4 stage at the end of a step
// that ends on a corner uses the left-hand limit of the acceleration (else
// the integration is only first-order accurate across the corners).
void profile(double t, double* w, double* a, double* th, double t_sel) {
  static const double tk[] = {0, 1, 3, 5, 7, 9, 1e9};
  static const double wk[] = {0, 5.25, 5.25, 12.6, 12.6, 0, 0};
  double acc_th = 0.0;
  for (int i = 0; i < 6; ++i) {
    const double slope = (wk[i + 1] - wk[i]) / (tk[i + 1] - tk[i]);
    if (t_sel < tk[i + 1]) {
      const double s = t - tk[i];
      *w = wk[i] + slope * s;
      *a = slope;
      *th = acc_th + wk[i] * s + 0.5 * slope * s * s;
      return;
    }
    const double s = tk[i + 1] - tk[i];
    acc_th += wk[i] * s + 0.5 * slope * s * s;
  }
}

// State: x1, x2, x3, x4, q_c, nu.
using X = std::array<double, 6>;

struct LawOut {
  double u1, u2, x2s, th;
};

LawOut law(const X& x, double t, double t_sel) {
  double w = 0.0, a = 0.0,
         th_ref = 0.0;  // set by profile() for t < 1e9 s; initialised for -O3 -Wmaybe-uninitialized
  profile(t, &w, &a, &th_ref, t_sel);
  const double e4 = x[3] - th_ref;
  const double th = x[4] + kB * e4;                         // (12)
  const double v3 = -kKp * e4 - kKd * th;                   // (9)
  const double dnu = -kKi * (e4 - th);                      // (10)
  const double x2s = (x[5] + a + v3) / kSigma;              // (8)
  const double rho = (dnu + 0.0 + kA * kKd * th) / kSigma;  // jerk 0 between corners
  const double v2 = -kEps * kSigma * (e4 - th);             // (35)
  const double e1 = x[0], e2 = x[1] - x2s;
  const double u1 = 0.0 + 0.0 - x[1] * w - (kK1 - 1.0) * e1;                    // (6)
  const double u2 = kGamma * w + x[0] * w + x2s + v2 + rho - (kK2 - 1.0) * e2;  // (14)
  return {u1, u2, x2s, th};
}

X deriv(const X& x, double t, double t_sel) {
  double w = 0.0, a = 0.0,
         th_ref = 0.0;  // set by profile() for t < 1e9 s; initialised for -O3 -Wmaybe-uninitialized
  profile(t, &w, &a, &th_ref, t_sel);
  const LawOut u = law(x, t, t_sel);
  const double e4 = x[3] - th_ref;
  X d;
  d[0] = -x[0] + x[1] * x[2] + u.u1;                  // (1)
  d[1] = -x[1] - x[0] * x[2] - kGamma * x[2] + u.u2;  // (2)
  d[2] = kSigma * x[1] - kTau;                        // (3)
  d[3] = x[2];                                        // (4)
  d[4] = -kA * (x[4] + kB * e4);                      // (11)
  d[5] = -kKi * (e4 - u.th);                          // (10)
  return d;
}

// Continuous solution sampled every 1e-4 (same instants as the SIL rows).
std::vector<X> continuous(double h, double t_end) {
  std::vector<X> out;
  X x{};
  const double rate = std::round(1.0 / h);
  const long n = std::lround(t_end * rate);
  const long every = std::lround(1e-4 * rate);
  for (long k = 0; k <= n; ++k) {
    const double t = static_cast<double>(k) / rate;  // integer seconds exactly
    if (k % every == 0) out.push_back(x);
    if (k == n) break;
    auto add = [](const X& p, const X& q, double s) {
      X r;
      for (int i = 0; i < 6; ++i) r[i] = p[i] + s * q[i];
      return r;
    };
    // Corners fall on multiples of h (integer seconds): no step straddles a
    // jump of the acceleration; every stage uses the step's own segment.
    const double tm = t + h / 2;
    const X k1 = deriv(x, t, tm), k2 = deriv(add(x, k1, h / 2), tm, tm),
            k3 = deriv(add(x, k2, h / 2), tm, tm), k4 = deriv(add(x, k3, h), t + h, tm);
    for (int i = 0; i < 6; ++i) x[i] += h / 6 * (k1[i] + 2 * k2[i] + 2 * k3[i] + k4[i]);
  }
  return out;
}

struct Err {
  double x2 = 0, x3 = 0, x4 = 0, nu = 0;
};

Err compare(double rate_hz, const std::vector<X>& ref) {
  mcsim::pi2d::PaperOptions o;
  o.rate_hz = rate_hz;
  o.substeps = 2;
  Err e;
  const long every = std::lround(rate_hz * 1e-4);
  long k = 0;
  mcsim::pi2d::run_paper(o, [&](const mcsim::pi2d::PaperSample& s) {
    if (k % every == 0) {
      const X& r = ref[static_cast<size_t>(k / every)];
      e.x2 = std::max(e.x2, std::abs(s.x2 - r[1]));
      e.x3 = std::max(e.x3, std::abs(s.x3 - r[2]));
      e.x4 = std::max(e.x4, std::abs(s.x4 - r[3]));
      e.nu = std::max(e.nu, std::abs(s.nu - r[5]));
    }
    ++k;
  });
  return e;
}

TEST(Pi2dPaper, SampledFirmwareLawMatchesContinuousClosedLoop) {
  const std::vector<X> ref = continuous(5.0e-5, 14.0);
  const std::vector<X> coarse = continuous(1.0e-4, 14.0);
  // The reference itself: RK4's error goes as h^4, so the reference's own
  // error is about 1/15 of its difference to the solution with twice the
  // step; that difference (measured 2.6e-12 on x3; bound 1e-9) keeps the
  // reference's error many decades below the tolerances below.
  double ref_err = 0.0;
  for (size_t k = 0; k < ref.size(); ++k) {
    ref_err = std::max(ref_err, std::abs(ref[k][2] - coarse[k][2]));
  }
  EXPECT_LT(ref_err, 1.0e-9);

  const Err e10 = compare(10000.0, ref);
  const Err e20 = compare(20000.0, ref);
  std::printf("max |SIL - continuous| at 10 kHz: x2 %.3g x3 %.3g x4 %.3g nu %.3g\n", e10.x2, e10.x3,
              e10.x4, e10.nu);
  std::printf("                       at 20 kHz: x2 %.3g x3 %.3g x4 %.3g nu %.3g\n", e20.x2, e20.x3,
              e20.x4, e20.nu);
  // Tolerance: the sampled law differs from the continuous one by the
  // zero-order hold (an average delay of T/2 = 5e-5 on every input) and the
  // one-step discretisations of theta_f (Tustin) and nu (Euler): errors of
  // first order in T. Measured at 10 kHz: x3 2.9e-4 (0.002 % of the 12.6
  // peak speed), x2 1.7e-2 (at the current spikes of the profile's
  // corners, where u2 jumps by ~900), x4 6.5e-5, nu 1.1e-6. Bounds: 2x the
  // measured values; float rounding of the kernel is far below (with the
  // theta_f state and the compensated nu sum; before those two fixes nu was
  // 3e-5 off and grew with the rate).
  EXPECT_LT(e10.x3, 6.0e-4);
  EXPECT_LT(e10.x2, 3.5e-2);
  EXPECT_LT(e10.x4, 1.3e-4);
  EXPECT_LT(e10.nu, 2.2e-6);
  // And it is the sampling: doubling the rate halves the error (first
  // order; measured ratios 2.0 for x3 and x4; 1.6..2.4 allows for the
  // float floor).
  EXPECT_GT(e10.x3 / e20.x3, 1.6);
  EXPECT_LT(e10.x3 / e20.x3, 2.4);
  mc_record("x3_err_10khz", e10.x3, 6.0e-4);
  mc_record("x2_err_10khz", e10.x2, 3.5e-2);
  mc_record("x3_err_ratio_10_over_20khz", e10.x3 / e20.x3);
  EXPECT_GT(e10.x4 / e20.x4, 1.6);
  EXPECT_LT(e10.x4 / e20.x4, 2.4);
}

TEST(Pi2dPaper, ReproducesSectionVBehaviour) {
  // The qualitative results of Figs. 1-6 on the SIL run: speed tracks the
  // profile (error well below 1 % of the 12.6 peak after the transients),
  // a small residual position error at 14 s (Fig. 5) and a load estimate
  // that is still far from tau_L = 1 (Fig. 6: "quite slow").
  mcsim::pi2d::PaperOptions o;
  double e3_max_late = 0.0, e3_max = 0.0;
  mcsim::pi2d::PaperSample last{};
  mcsim::pi2d::run_paper(o, [&](const mcsim::pi2d::PaperSample& s) {
    e3_max = std::max(e3_max, std::abs(s.x3 - s.x3_ref));
    if (s.t > 10.0) e3_max_late = std::max(e3_max_late, std::abs(s.x3 - s.x3_ref));
    last = s;
  });
  EXPECT_LT(e3_max, 0.25);                           // measured 0.17 (start-up against tau_L = 1)
  EXPECT_LT(e3_max_late, 0.05);                      // measured 0.018
  EXPECT_LT(std::abs(last.x4 - last.x4_ref), 0.3);   // measured 0.195
  EXPECT_GT(std::abs(last.x4 - last.x4_ref), 0.05);  // but not zero (Fig. 5)
  EXPECT_GT(last.nu, 0.0);
  EXPECT_LT(last.nu, 0.1);  // measured 0.024
}

}  // namespace
