// RK4 order, zero-order-hold period advance and the computation-delay buffer.
#include <cmath>

#include <Eigen/Core>
#include <gtest/gtest.h>

#include "mcsim/integrator.hpp"

namespace {

// x'' + 2 zeta w0 x' + w0^2 x = 0 as x = (position, velocity).
struct DampedOscillator {
  using State = Eigen::Vector2d;
  using Input = Eigen::Matrix<double, 1, 1>;
  double w0_rad_s = 2.0 * 3.14159265358979323846;
  double zeta = 0.1;
  State deriv(double /*t_s*/, const State& x, const Input& /*u*/) const {
    return State(x(1), -2.0 * zeta * w0_rad_s * x(1) - w0_rad_s * w0_rad_s * x(0));
  }
  // Analytic solution for x(0) = (1, 0).
  double position(double t_s) const {
    const double wd = w0_rad_s * std::sqrt(1.0 - zeta * zeta);
    const double a = zeta * w0_rad_s;
    return std::exp(-a * t_s) * (std::cos(wd * t_s) + (a / wd) * std::sin(wd * t_s));
  }
};

// RL circuit L di/dt = v - R i, input v.
struct RlCircuit {
  using State = Eigen::Matrix<double, 1, 1>;
  using Input = Eigen::Matrix<double, 1, 1>;
  double R_ohm = 2.0;
  double L_h = 2.0e-3;
  State deriv(double /*t_s*/, const State& x, const Input& u) const {
    State dx;
    dx(0) = (u(0) - R_ohm * x(0)) / L_h;
    return dx;
  }
};

double oscillator_error(int n_steps, double t_end_s) {
  const DampedOscillator osc;
  const double h_s = t_end_s / n_steps;
  DampedOscillator::State x(1.0, 0.0);
  const DampedOscillator::Input u = DampedOscillator::Input::Zero();
  for (int k = 0; k < n_steps; ++k) {
    x = mcsim::rk4_step(osc, k * h_s, x, u, h_s);
  }
  return std::fabs(x(0) - osc.position(t_end_s));
}

TEST(SimRk4, FourthOrderOnDampedOscillator) {
  // h = 10, 5, 2.5, 1.25 ms over 2 s (w0 h <= 0.063): errors far above
  // round-off (~1e-15), so the ratio measures truncation only.
  const double e1 = oscillator_error(200, 2.0);
  const double e2 = oscillator_error(400, 2.0);
  const double e3 = oscillator_error(800, 2.0);
  const double e4 = oscillator_error(1600, 2.0);
  ASSERT_GT(e4, 1e-13);
  // Global error of a 4th-order method scales as h^4: ratio 2^4 = 16 when h
  // halves. Band 14..18 allows the O(h^5) terms at these step sizes; a 2nd or
  // 3rd order scheme (ratio 4 or 8) or 5th order (32) falls outside.
  EXPECT_GT(e1 / e2, 14.0);
  EXPECT_LT(e1 / e2, 18.0);
  EXPECT_GT(e2 / e3, 14.0);
  EXPECT_LT(e2 / e3, 18.0);
  EXPECT_GT(e3 / e4, 14.0);
  EXPECT_LT(e3 / e4, 18.0);
}

TEST(SimRk4, ZohPeriodMatchesExactRlResponse) {
  const RlCircuit rl;
  RlCircuit::State x;
  x(0) = 0.5;
  RlCircuit::Input u;
  u(0) = 12.0;
  const double period_s = 1.0e-3;  // = L/R: one time constant per period
  ASSERT_EQ(mcsim::advance_zoh(rl, u, 0.0, period_s, 20, &x), mcsim::Status::kOk);
  const double i_ss = u(0) / rl.R_ohm;
  const double exact = i_ss + (0.5 - i_ss) * std::exp(-rl.R_ohm * period_s / rl.L_h);
  // RK4 with a = R h / L = 0.05 per step: relative error of exp(-a) is
  // a^5/120 ~ 3e-9 per step, 20 steps -> < 1e-7 of the 5.5 A swing; 1e-6 A bound.
  EXPECT_NEAR(x(0), exact, 1e-6);

  // One sub-step (a = 1) is far less accurate: error ~ 1/120 of the swing;
  // the sub-step count really is used.
  RlCircuit::State x1;
  x1(0) = 0.5;
  ASSERT_EQ(mcsim::advance_zoh(rl, u, 0.0, period_s, 1, &x1), mcsim::Status::kOk);
  EXPECT_GT(std::fabs(x1(0) - exact), 1e-3);
}

TEST(SimRk4, ZohRejectsBadArgumentsAndKeepsState) {
  const RlCircuit rl;
  RlCircuit::State x;
  x(0) = 1.25;
  RlCircuit::Input u;
  u(0) = 1.0;
  EXPECT_EQ(mcsim::advance_zoh(rl, u, 0.0, 1e-4, 0, &x), mcsim::Status::kBadStepCount);
  EXPECT_EQ(mcsim::advance_zoh(rl, u, 0.0, 0.0, 4, &x), mcsim::Status::kBadPeriod);
  EXPECT_EQ(mcsim::advance_zoh(rl, u, 0.0, NAN, 4, &x), mcsim::Status::kBadPeriod);
  EXPECT_EQ(mcsim::advance_zoh(rl, u, INFINITY, 1e-4, 4, &x), mcsim::Status::kNotFinite);
  EXPECT_EQ(x(0), 1.25);  // exact: untouched
}

using Vin = Eigen::Vector2d;

TEST(SimDelay, OnePeriodDelayReturnsPreviousInput) {
  mcsim::InputDelay<Vin, 4> d;
  ASSERT_EQ(d.configure(1U, Vin(-1.0, -2.0)), mcsim::Status::kOk);
  // Exact comparisons: the buffer copies values, no arithmetic.
  EXPECT_EQ(d.push(Vin(1.0, 10.0)), Vin(-1.0, -2.0));
  EXPECT_EQ(d.push(Vin(2.0, 20.0)), Vin(1.0, 10.0));
  EXPECT_EQ(d.push(Vin(3.0, 30.0)), Vin(2.0, 20.0));
}

TEST(SimDelay, ZeroAndMultiPeriodDelays) {
  mcsim::InputDelay<Vin, 4> d0;
  ASSERT_EQ(d0.configure(0U, Vin::Zero()), mcsim::Status::kOk);
  EXPECT_EQ(d0.push(Vin(7.0, 8.0)), Vin(7.0, 8.0));

  mcsim::InputDelay<Vin, 4> d3;
  ASSERT_EQ(d3.configure(3U, Vin::Zero()), mcsim::Status::kOk);
  for (int k = 1; k <= 10; ++k) {
    const Vin out = d3.push(Vin(static_cast<double>(k), -static_cast<double>(k)));
    const double expected = (k <= 3) ? 0.0 : static_cast<double>(k - 3);
    EXPECT_EQ(out(0), expected) << "k=" << k;
    EXPECT_EQ(out(1), -expected) << "k=" << k;
  }

  mcsim::InputDelay<Vin, 4> d4;  // full capacity
  ASSERT_EQ(d4.configure(4U, Vin::Zero()), mcsim::Status::kOk);
  for (int k = 1; k <= 9; ++k) {
    const Vin out = d4.push(Vin(static_cast<double>(k), 0.0));
    EXPECT_EQ(out(0), (k <= 4) ? 0.0 : static_cast<double>(k - 4));
  }
}

TEST(SimDelay, TooLongDelayIsRejectedAndStateKept) {
  mcsim::InputDelay<Vin, 2> d;
  ASSERT_EQ(d.configure(1U, Vin(5.0, 5.0)), mcsim::Status::kOk);
  EXPECT_EQ(d.configure(3U, Vin::Zero()), mcsim::Status::kDelayTooLong);
  EXPECT_EQ(d.delay(), 1U);
  EXPECT_EQ(d.push(Vin(1.0, 1.0)), Vin(5.0, 5.0));
}

}  // namespace
