// Cogging torque (mcsim/cogging.hpp): its order from the slot/pole
// combination, period, zero mean, amplitude and phase of each harmonic,
// the potential it derives from, and its place in every PMSM plant's torque
// balance (free oscillation about a detent at the closed-form frequency,
// energy conserved, the written-out RK4 equal to the generic one).
#include <cmath>
#include <random>

#include <Eigen/Core>
#include <gtest/gtest.h>

#include "mcsim/cogging.hpp"
#include "mcsim/integrator.hpp"
#include "mcsim/pmsm_ab.hpp"
#include "mcsim/pmsm_dq.hpp"
#include "mcsim/pmsm_open_phase.hpp"
#include "mcsim/pmsm_power_stage.hpp"
#include "mcsim/pmsm_rotor_frame.hpp"
#include "sim_test_util.hpp"

namespace {

using mcsim::CoggingParams;
using mcsim::CoggingTorque;
using mcsim::PmsmDq;
using mcsim::PmsmParams;
using mcsim::Status;
using mcsim_test::kPi;

// A D5065-like motor: 12 slots, 14 poles.
PmsmParams motor_with_cogging(double amplitude_nm, double phase_rad) {
  PmsmParams p;
  p.R_ohm = 0.04;
  p.Ld_h = p.Lq_h = 2.0e-5;
  p.flux_wb = 0.004;
  p.pole_pairs = 7;
  p.J_kgm2 = 1.0e-4;
  p.B_nms_rad = 0.0;
  p.cogging.slots = 12;
  p.cogging.amplitude_nm = amplitude_nm;
  p.cogging.phase_rad = phase_rad;
  return p;
}

TEST(SimCogging, OrderIsTheLcmOfSlotsAndPoles) {
  EXPECT_EQ(mcsim::cogging_order(12, 7), 84);  // 12N14P
  EXPECT_EQ(mcsim::cogging_order(9, 3), 18);   // 9N6P
  EXPECT_EQ(mcsim::cogging_order(12, 4), 24);  // 12N8P
  EXPECT_EQ(mcsim::cogging_order(24, 2), 24);  // 24 slots, 4 poles
  EXPECT_EQ(mcsim::cogging_order(0, 7), 0);    // no slots: none
  CoggingTorque c;
  CoggingParams p;
  p.slots = 12;
  p.amplitude_nm = 0.01;
  ASSERT_EQ(c.configure(p, 7), Status::kOk);
  EXPECT_EQ(c.order_per_rev(), 84);
  EXPECT_TRUE(c.active());
}

TEST(SimCogging, PeriodZeroMeanAmplitudeAndPhaseOfEachHarmonic) {
  CoggingParams p;
  p.slots = 9;
  p.amplitude_nm = 0.05;
  p.phase_rad = 0.7;
  p.harmonic_nm[0] = 0.02;  // order 2N
  p.harmonic_phase_rad[0] = -1.1;
  p.harmonic_nm[2] = 0.004;  // order 4N
  p.harmonic_phase_rad[2] = 2.5;
  CoggingTorque c;
  ASSERT_EQ(c.configure(p, 3), Status::kOk);
  const int n = c.order_per_rev();
  ASSERT_EQ(n, 18);
  // Discrete Fourier coefficients over one mechanical turn with M samples:
  // exact for harmonics below M/2 (M = 4096 > 2 * 4 * 18), so the
  // tolerance is rounding: 1e-12 N m.
  const int m = 4096;
  double mean = 0.0;
  std::vector<double> tau(m);
  for (int j = 0; j < m; ++j) {
    tau[j] = c.torque_nm(2.0 * kPi * j / m);
    mean += tau[j] / m;
  }
  EXPECT_NEAR(mean, 0.0, 1e-12);
  for (int order = 1; order <= 80; ++order) {
    double cs = 0.0, sn = 0.0;
    for (int j = 0; j < m; ++j) {
      const double a = 2.0 * kPi * order * j / m;
      cs += 2.0 * tau[j] * std::cos(a) / m;
      sn += 2.0 * tau[j] * std::sin(a) / m;
    }
    // A sin(k x + phi) = A cos(phi) sin(k x) + A sin(phi) cos(k x).
    double amp = 0.0, ph = 0.0;
    if (order == n) amp = p.amplitude_nm, ph = p.phase_rad;
    if (order == 2 * n) amp = p.harmonic_nm[0], ph = p.harmonic_phase_rad[0];
    if (order == 4 * n) amp = p.harmonic_nm[2], ph = p.harmonic_phase_rad[2];
    EXPECT_NEAR(sn, amp * std::cos(ph), 1e-12) << "order " << order;
    EXPECT_NEAR(cs, amp * std::sin(ph), 1e-12) << "order " << order;
  }
  // Periodic in 2 pi / N at any angle (1e-12 N m: sin of arguments ~1e3 rad).
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-50.0, 50.0);
  for (int k = 0; k < 100; ++k) {
    const double th = u(rng);
    EXPECT_NEAR(c.torque_nm(th + 2.0 * kPi / n), c.torque_nm(th), 1e-12);
  }
}

TEST(SimCogging, TorqueIsMinusTheGradientOfItsPotential) {
  CoggingParams p;
  p.slots = 12;
  p.amplitude_nm = 0.03;
  p.phase_rad = 0.3;
  p.harmonic_nm[1] = 0.01;  // order 3N
  p.harmonic_phase_rad[1] = 1.2;
  CoggingTorque c;
  ASSERT_EQ(c.configure(p, 4), Status::kOk);
  // Central difference with h = 1e-6 rad: truncation (N h)^2 ~ 1e-9
  // relative, rounding ~1e-10 / h: bound 1e-7 N m on 0.04 N m.
  const double h = 1.0e-6;
  for (int k = 0; k < 200; ++k) {
    const double th = 0.0123 * k;
    const double dw = (c.energy_j(th + h) - c.energy_j(th - h)) / (2.0 * h);
    EXPECT_NEAR(-dw, c.torque_nm(th), 1e-7) << "th=" << th;
  }
}

TEST(SimCogging, RotorOscillatesAboutADetentAtTheClosedFormFrequency) {
  // No current: J th'' = A sin(N th + phi). The stable detent is where
  // N th + phi = pi; small oscillations there have w_n = sqrt(A N / J).
  // No magnet flux: zero volts on the terminals is then no short-circuit
  // brake (no back-EMF), the mechanics are alone.
  const double a = 0.02, phi = 0.4;
  PmsmParams p = motor_with_cogging(a, phi);
  p.flux_wb = 0.0;
  PmsmDq dq;
  ASSERT_EQ(dq.configure(p), Status::kOk);
  const int n = dq.cogging().order_per_rev();
  const double th_eq = (kPi - phi) / n;
  const double amp0 = 1.0e-4;  // rad: N amp0 = 0.008 rad, nonlinearity ~1e-5
  PmsmDq::State x(0.0, 0.0, 0.0, th_eq + amp0);
  const double wn = std::sqrt(a * n / p.J_kgm2);
  const double period = 2.0 * kPi / wn;
  const double h = period / 2000.0;
  double e0 = dq.kinetic_energy_j(x) + dq.cogging_energy_j(x);
  // Upward zero crossings of th - th_eq, interpolated.
  std::vector<double> crossings;
  double prev = x(3) - th_eq;
  for (int k = 1; k <= 20000; ++k) {
    x = mcsim::rk4_step(dq, (k - 1) * h, x, PmsmDq::Input::Zero(), h);
    const double d = x(3) - th_eq;
    if (prev < 0.0 && d >= 0.0) crossings.push_back((k - 1 + prev / (prev - d)) * h);
    prev = d;
  }
  ASSERT_GE(crossings.size(), 8U);
  const double measured = (crossings.back() - crossings.front()) / (crossings.size() - 1);
  // Amplitude dependence of a pendulum: 1 + (N amp0)^2 / 16 = 4e-6; linear
  // interpolation of the crossings: 1e-7 of a period. Bound 1e-4.
  EXPECT_NEAR(measured / period, 1.0, 1e-4);
  // Energy (kinetic + cogging potential) conserved: RK4 at 2000 steps per
  // period drifts ~1e-12 relative per period; bound 1e-8 relative.
  const double e1 = dq.kinetic_energy_j(x) + dq.cogging_energy_j(x);
  EXPECT_NEAR(e1, e0, 1e-8 * std::fabs(e0));
}

TEST(SimCogging, EveryPlantCarriesIt) {
  // The same state in each plant gives the same acceleration, cogging
  // included: PmsmDq, PmsmAb (alpha-beta state), PmsmRotorFrame (written
  // out), PmsmOpenPhase (no current). Tolerance 1e-12 relative (reciprocals
  // against divisions).
  const PmsmParams p = motor_with_cogging(0.05, 0.2);
  PmsmDq dq;
  mcsim::PmsmAb ab;
  mcsim::PmsmRotorFrame rf;
  mcsim::PmsmOpenPhase op;
  ASSERT_EQ(dq.configure(p), Status::kOk);
  ASSERT_EQ(ab.configure(p), Status::kOk);
  ASSERT_EQ(rf.configure(p), Status::kOk);
  ASSERT_EQ(op.configure(p, 1), Status::kOk);
  for (int k = 0; k < 50; ++k) {
    const double th = 0.037 * k, w = 3.0;
    const PmsmDq::State xd(0.0, 0.0, w, th);
    const double ref = dq.deriv(0.0, xd, PmsmDq::Input::Zero())(2);
    EXPECT_NEAR(ref, (dq.cogging_nm(xd)) / p.J_kgm2, 1e-12 * std::fabs(ref) + 1e-12);
    const mcsim::PmsmAb::State xa(0.0, 0.0, w, th);
    EXPECT_NEAR(ab.deriv(0.0, xa, mcsim::PmsmAb::Input::Zero())(2), ref, 1e-12 * std::fabs(ref));
    const mcsim::PmsmRotorFrame::State xr = rf.make_state(0.0, 0.0, w, th);
    EXPECT_NEAR(rf.deriv(0.0, xr, mcsim::PmsmRotorFrame::Input::Zero())(2), ref,
                1e-12 * std::fabs(ref));
    const mcsim::PmsmOpenPhase::State xo = op.from_rotor_frame(xr);
    EXPECT_NEAR(op.deriv(0.0, xo, mcsim::PmsmOpenPhase::Input::Zero())(1), ref,
                1e-12 * std::fabs(ref));
  }
}

TEST(SimCogging, WrittenOutRk4EqualsGenericRk4WithCogging) {
  // PmsmRotorFrame::advance_zoh (hand-written stages) against advance_zoh
  // on its deriv(): 200 periods of 50 us with a rotating voltage; agreement
  // to 1e-10 relative (the two differ in rounding order only).
  const PmsmParams p = motor_with_cogging(0.08, -0.5);
  mcsim::PmsmRotorFrame rf;
  ASSERT_EQ(rf.configure(p), Status::kOk);
  mcsim::PmsmRotorFrame::State a = rf.make_state(0.0, 0.0, 20.0, 0.1);
  mcsim::PmsmRotorFrame::State b = a;
  const double T = 50.0e-6;
  for (int k = 0; k < 200; ++k) {
    const double ang = 0.05 * k;
    const mcsim::PmsmRotorFrame::Input u(2.0 * std::cos(ang), 2.0 * std::sin(ang));
    ASSERT_EQ(rf.advance_zoh(u, k * T, T, 4, &a), Status::kOk);
    ASSERT_EQ(mcsim::advance_zoh(rf, u, k * T, T, 4, &b), Status::kOk);
  }
  for (int i = 0; i < 6; ++i) EXPECT_NEAR(a(i), b(i), 1e-10 * (1.0 + std::fabs(b(i))));
  // And the cogging changed the trajectory (against the same motor without).
  PmsmParams q = p;
  q.cogging.amplitude_nm = 0.0;
  mcsim::PmsmRotorFrame rq;
  ASSERT_EQ(rq.configure(q), Status::kOk);
  mcsim::PmsmRotorFrame::State c = rq.make_state(0.0, 0.0, 20.0, 0.1);
  for (int k = 0; k < 200; ++k) {
    const double ang = 0.05 * k;
    const mcsim::PmsmRotorFrame::Input u(2.0 * std::cos(ang), 2.0 * std::sin(ang));
    ASSERT_EQ(rq.advance_zoh(u, k * T, T, 4, &c), Status::kOk);
  }
  EXPECT_GT(std::fabs(c(2) - a(2)), 1e-3);  // rad/s: 0.08 N m on 1e-4 kg m^2 over 10 ms
}

TEST(SimCogging, PowerStageRotorSettlesInADetent) {
  // Bridge off, no current, viscous friction: the rotor released off a
  // detent comes to rest in a stable one, N th + phi = pi (mod 2 pi).
  // Stiffness A N = 2.52 N m/rad on J = 1e-4: w_n = 159 rad/s; B = 0.02
  // gives a damping ratio 0.63, so 1 s is ~100 decay times.
  PmsmParams p = motor_with_cogging(0.03, 0.0);
  p.B_nms_rad = 0.02;
  mcsim::PmsmPowerStageParams sp;
  sp.motor = p;
  sp.theta_m0_rad = 0.5;
  mcsim::PmsmPowerStage st;
  ASSERT_EQ(st.configure(sp), Status::kOk);
  for (int k = 0; k < 20000; ++k)
    ASSERT_EQ(st.advance(Eigen::Vector3d::Zero(), false), Status::kOk);
  const int n = 84;
  const double th = st.rotor_frame_state()(3);
  const double k_det = std::round((th * n - kPi) / (2.0 * kPi));
  // Bound 1e-9 rad (the residual after ~100 decay times is far below it); a
  // wrong sign of the cogging term leaves the rotor on the unstable
  // equilibrium's side, pi / N = 0.037 rad away.
  EXPECT_NEAR(th, (kPi + 2.0 * kPi * k_det) / n, 1e-9);
  EXPECT_NEAR(st.rotor_frame_state()(2), 0.0, 1e-6);
  EXPECT_NE(th, 0.5);  // it moved: the cogging torque acts in the stage
}

TEST(SimCogging, InvalidParametersAreRefused) {
  PmsmParams p = motor_with_cogging(-0.01, 0.0);
  PmsmDq dq;
  EXPECT_EQ(dq.configure(p), Status::kBadCogging);
  p.cogging.amplitude_nm = 0.01;
  p.cogging.slots = -3;
  EXPECT_EQ(dq.configure(p), Status::kBadCogging);
  p.cogging.slots = 12;
  p.cogging.harmonic_nm[1] = NAN;
  EXPECT_EQ(dq.configure(p), Status::kNotFinite);
  // The previous (default, cogging-free) parameters are kept.
  EXPECT_FALSE(dq.cogging().active());
  EXPECT_EQ(dq.params().cogging.slots, 0);
  CoggingTorque c;
  CoggingParams cp;
  cp.slots = 12;
  cp.amplitude_nm = 0.01;
  EXPECT_EQ(c.configure(cp, 0), Status::kBadPolePairs);
  EXPECT_FALSE(c.active());
}

}  // namespace
