// A two-phase stepper on a three-leg bridge with a common leg
// (InverterCommonLeg, StepperCommonLegStage): the topology's voltage limit
// (the hexagon |v_a|, |v_b|, |v_a - v_b| <= V; quadrature amplitude
// V / sqrt 2), its dead time, its DC current, the stage against the
// two-H-bridge stage under the same winding voltages, and the diodes'
// freewheeling with the bridge off against closed forms.
#include <algorithm>
#include <cmath>
#include <random>

#include <Eigen/Core>
#include <gtest/gtest.h>

#include "mcsim/inverter.hpp"
#include "mcsim/stepper_common_leg_stage.hpp"
#include "mcsim/stepper_power_stage.hpp"
#include "sim_test_util.hpp"

namespace {

using mcsim::InverterCommonLeg;
using mcsim::InverterParams;
using mcsim::Status;
using mcsim_test::kPi;

InverterCommonLeg bridge(double t_dead_s) {
  InverterParams p;
  p.t_pwm_s = 50.0e-6;
  p.t_dead_s = t_dead_s;
  p.i_dead_band_a = 0.05;
  InverterCommonLeg b;
  EXPECT_EQ(b.configure(p), Status::kOk);
  return b;
}

// Duties putting (v_a, v_b) on the windings with the smallest common leg
// (v_3 = max(0, -v_a, -v_b)): the constructive half of the limit.
Eigen::Vector3d duties_for(double va, double vb, double vbus) {
  const double v3 = std::max({0.0, -va, -vb});
  return Eigen::Vector3d(va + v3, vb + v3, v3) / vbus;
}

TEST(SimCommonLeg, EveryDutyGivesAPointOfTheHexagonAndEveryPointIsReachable) {
  const InverterCommonLeg b = bridge(0.0);
  const double vbus = 24.0;
  const Eigen::Vector2d i0 = Eigen::Vector2d::Zero();
  // Any duties: inside |v_a|, |v_b|, |v_a - v_b| <= V (a 21^3 grid).
  for (int x = 0; x <= 20; ++x) {
    for (int y = 0; y <= 20; ++y) {
      for (int z = 0; z <= 20; ++z) {
        const Eigen::Vector3d d(0.05 * x, 0.05 * y, 0.05 * z);
        ASSERT_TRUE(InverterCommonLeg::reachable(b.voltages_v(d, vbus, i0), vbus));
      }
    }
  }
  // Any point of the hexagon: its duties lie in [0, 1] and the bridge gives
  // exactly it (1e-12 V: two roundings).
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-vbus, vbus);
  int inside = 0;
  for (int k = 0; k < 20000; ++k) {
    const Eigen::Vector2d v(u(rng), u(rng));
    if (!InverterCommonLeg::reachable(v, vbus)) continue;
    ++inside;
    const Eigen::Vector3d d = duties_for(v(0), v(1), vbus);
    ASSERT_GE(d.minCoeff(), 0.0);
    ASSERT_LE(d.maxCoeff(), 1.0 + 1e-12);
    const Eigen::Vector2d got = b.voltages_v(d, vbus, i0);
    ASSERT_NEAR(got(0), v(0), 1e-12);
    ASSERT_NEAR(got(1), v(1), 1e-12);
  }
  // The hexagon is 3/4 of the square [-V, V]^2 (area 3 V^2 of 4 V^2).
  EXPECT_NEAR(inside / 20000.0, 0.75, 0.02);  // 4.6 sigma of the binomial
}

TEST(SimCommonLeg, QuadratureAmplitudeLimitIsVbusOverSqrt2) {
  const double vbus = 24.0;
  const double umax = InverterCommonLeg::max_quadrature_amplitude_v(vbus);
  EXPECT_NEAR(umax, vbus / std::sqrt(2.0), 1e-12);
  // (U cos p, U sin p) for U = U_max is reachable at every angle; the
  // binding angle p = 3 pi / 4 (v_a - v_b = -sqrt2 U) puts the poles at
  // 0 and V.
  for (int k = 0; k < 3600; ++k) {
    const double p = 2.0 * kPi * k / 3600.0;
    ASSERT_TRUE(InverterCommonLeg::reachable({umax * std::cos(p), umax * std::sin(p)}, vbus));
  }
  // 0.1 % more is out of reach at p = 3 pi / 4 (and -pi / 4), and not even
  // the clamped duties reach it: the bridge falls short.
  const double u = 1.001 * umax;
  const Eigen::Vector2d want(u * std::cos(0.75 * kPi), u * std::sin(0.75 * kPi));
  EXPECT_FALSE(InverterCommonLeg::reachable(want, vbus));
  const Eigen::Vector3d d = duties_for(want(0), want(1), vbus);
  EXPECT_GT(d.maxCoeff(), 1.0);
  const Eigen::Vector2d got = bridge(0.0).voltages_v(d, vbus, Eigen::Vector2d::Zero());
  EXPECT_GT((got - want).norm(), 1e-3 * umax);
  // Two full H-bridges reach V at every angle: the topology gives up 29 %.
  EXPECT_NEAR(umax / vbus, 0.70710678118654752, 1e-15);
}

TEST(SimCommonLeg, DeadTimeAndDcCurrent) {
  // Leg currents (i_a, i_b, -(i_a + i_b)) = (2, 1, -3) A, all beyond the
  // dead band: legs 1 and 2 lose t_d / T of V, leg 3 gains it; both
  // windings lose 2 t_d / T V. (Exact to rounding: 1e-12 V.)
  const double td = 1.0e-6, vbus = 24.0;
  const InverterCommonLeg b = bridge(td);
  const Eigen::Vector3d d(0.6, 0.45, 0.3);
  const Eigen::Vector2d i(2.0, 1.0);
  const Eigen::Vector2d ideal((0.6 - 0.3) * vbus, (0.45 - 0.3) * vbus);
  const Eigen::Vector2d got = b.voltages_v(d, vbus, i);
  const double err = 2.0 * td / 50.0e-6 * vbus;
  EXPECT_NEAR(got(0), ideal(0) - err, 1e-12);
  EXPECT_NEAR(got(1), ideal(1) - err, 1e-12);
  // i_b reversed (-1 A): leg 2 gains, leg 3 current -(2 - 1) = -1: gains.
  const Eigen::Vector2d got2 = b.voltages_v(d, vbus, Eigen::Vector2d(2.0, -1.0));
  EXPECT_NEAR(got2(0), ideal(0) - err, 1e-12);
  EXPECT_NEAR(got2(1), ideal(1), 1e-12);
  // DC current: sum d_k i_k; without dead time the bridge is lossless,
  // V i_dc = v_a i_a + v_b i_b (rounding: 1e-12 W).
  const InverterCommonLeg ideal_bridge = bridge(0.0);
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0), ui(-10.0, 10.0);
  for (int k = 0; k < 1000; ++k) {
    const Eigen::Vector3d dk(u(rng), u(rng), u(rng));
    const Eigen::Vector2d ik(ui(rng), ui(rng));
    const Eigen::Vector2d v = ideal_bridge.voltages_v(dk, vbus, ik);
    ASSERT_NEAR(vbus * InverterCommonLeg::dc_current_a(dk, ik), v.dot(ik), 1e-12 * 500.0);
  }
}

mcsim::Stepper2PhParams motor() {
  mcsim::Stepper2PhParams m;  // the paper's stepper: R 19 ohm, L 40 mH
  return m;
}

TEST(SimCommonLeg, StageEqualsTheHBridgeStageUnderTheSameWindingVoltages) {
  // The windings do not know the topology: for the same (v_a, v_b) each
  // period, the common-leg stage and the two-H-bridge stage integrate the
  // same plant the same way (bit for bit: same voltages, same RK4).
  mcsim::StepperCommonLegStageParams cp;
  cp.motor = motor();
  cp.inverter.t_pwm_s = 1.0e-4;
  cp.vbus_v = 48.0;
  cp.theta_m0_rad = 0.01;
  mcsim::StepperPowerStageParams hp;
  hp.motor = motor();
  hp.t_pwm_s = 1.0e-4;
  hp.vbus_v = 48.0;
  hp.theta_m0_rad = 0.01;
  mcsim::StepperCommonLegStage cl;
  mcsim::StepperPowerStage hb;
  ASSERT_EQ(cl.configure(cp), Status::kOk);
  ASSERT_EQ(hb.configure(hp), Status::kOk);
  const double u = 0.6 * InverterCommonLeg::max_quadrature_amplitude_v(48.0);
  for (int k = 0; k < 5000; ++k) {
    const double p = 2.0 * kPi * 2.0 * k * 1.0e-4;  // 2 Hz electrical
    const double va = u * std::cos(p), vb = u * std::sin(p);
    ASSERT_EQ(cl.advance(duties_for(va, vb, 48.0), true), Status::kOk);
    ASSERT_EQ(hb.advance(Eigen::Vector2d(va, vb) / 48.0, true), Status::kOk);
    // The duties' round trip through the pole voltages: a few roundings on
    // 20 V (1e-12 V); the states then agree to ~1e-12 relative.
    ASSERT_NEAR(cl.v_applied()(0), hb.v_applied()(0), 1e-12);
    ASSERT_NEAR(cl.v_applied()(1), hb.v_applied()(1), 1e-12);
  }
  for (int i = 0; i < 4; ++i) {
    EXPECT_NEAR(cl.state()(i), hb.state()(i), 1e-9 * (1.0 + std::fabs(hb.state()(i)))) << i;
  }
  // It moved: 2 Hz electrical on 50 teeth is 0.25 rad/s.
  EXPECT_GT(std::fabs(cl.state()(3) - 0.01), 0.05);
  // Power into the windings over the last period equals V i_dc (lossless
  // bridge): trapezoid of v . i.
  EXPECT_GT(std::fabs(cl.last_input_power_w()), 0.0);
}

// Brings the stage's currents to (i_a, i_b) with the rotor held by a huge
// inertia, then opens the bridge.
mcsim::StepperCommonLegStage charged(double ia, double ib, double vbus) {
  mcsim::StepperCommonLegStageParams cp;
  cp.motor = motor();
  cp.motor.J_kgm2 = 1.0e6;  // the rotor does not move: no back-EMF
  cp.inverter.t_pwm_s = 1.0e-4;
  cp.vbus_v = vbus;
  cp.substeps = 8;
  mcsim::StepperCommonLegStage st;
  EXPECT_EQ(st.configure(cp), Status::kOk);
  const double r = cp.motor.R_ohm;
  for (int k = 0; k < 400; ++k) {  // 40 ms = 19 L/R
    EXPECT_EQ(st.advance(duties_for(r * ia, r * ib, vbus), true), Status::kOk);
  }
  return st;
}

TEST(SimCommonLeg, BridgeOffCurrentsDecayAsTheDiodesImpose) {
  const double vbus = 48.0, r = 19.0, l = 0.040, tau = l / r;
  const double h = 1.0e-4 / 8.0;
  {
    // i_a = i_b = 1 A: legs 1, 2 at 0 V, leg 3 at V: both windings at -V:
    // i(t) = (I + V/R) e^(-t/tau) - V/R, zero at tau ln(1 + R I / V).
    mcsim::StepperCommonLegStage st = charged(1.0, 1.0, vbus);
    EXPECT_NEAR(st.state()(0), 1.0, 1e-6);
    const double t0 = tau * std::log(1.0 + r * 1.0 / vbus);
    double t_zero = -1.0;
    for (int k = 0; k < 100 && t_zero < 0.0; ++k) {
      ASSERT_EQ(st.advance(Eigen::Vector3d::Zero(), false), Status::kOk);
      for (int j = 0; j < 2 && k < 3; ++j) {
        EXPECT_NEAR(st.v_applied()(j), -vbus, 1e-12);
      }
      if (st.state()(0) == 0.0 && st.state()(1) == 0.0) t_zero = (k + 1) * 1.0e-4;
    }
    // Zero within the period that contains t0 (the stage reports per period).
    EXPECT_GE(t_zero, t0);
    EXPECT_LE(t_zero, t0 + 1.0e-4 + h);
    ASSERT_EQ(st.advance(Eigen::Vector3d::Zero(), false), Status::kOk);
    EXPECT_EQ(st.state()(0), 0.0);  // stays open
  }
  {
    // i_a = 1, i_b = -1: the common leg carries nothing; the windings in
    // series between legs 1 (0 V) and 2 (V): 2 L di/dt = -V - 2 R i,
    // zero at tau ln(1 + 2 R I / V); i_a = -i_b throughout.
    mcsim::StepperCommonLegStage st = charged(1.0, -1.0, vbus);
    const double t0 = tau * std::log(1.0 + 2.0 * r / vbus);
    double t_zero = -1.0;
    for (int k = 0; k < 100 && t_zero < 0.0; ++k) {
      ASSERT_EQ(st.advance(Eigen::Vector3d::Zero(), false), Status::kOk);
      ASSERT_EQ(st.state()(0), -st.state()(1));
      if (k == 0) {
        EXPECT_NEAR(st.v_applied()(0) - st.v_applied()(1), -vbus, 1e-12);
      }
      if (st.state()(0) == 0.0) t_zero = (k + 1) * 1.0e-4;
    }
    EXPECT_GE(t_zero, t0);
    EXPECT_LE(t_zero, t0 + 1.0e-4 + h);
  }
  {
    // i_a = 1.5, i_b = -0.5: legs (0, V, V): v_a = -V, v_b = 0: winding a
    // falls fast, b only through R; when i_a + i_b reaches zero the pair
    // continues in series. The magnetic energy goes back to the bus: the
    // power drawn is negative while a decays.
    mcsim::StepperCommonLegStage st = charged(1.5, -0.5, vbus);
    ASSERT_EQ(st.advance(Eigen::Vector3d::Zero(), false), Status::kOk);
    EXPECT_NEAR(st.v_applied()(0), -vbus, 1e-12);
    EXPECT_NEAR(st.v_applied()(1), 0.0, 1e-12);
    EXPECT_LT(st.last_input_power_w(), 0.0);
    for (int k = 0; k < 200; ++k)
      ASSERT_EQ(st.advance(Eigen::Vector3d::Zero(), false), Status::kOk);
    EXPECT_EQ(st.state()(0), 0.0);
    EXPECT_EQ(st.state()(1), 0.0);
  }
}

TEST(SimCommonLeg, InvalidConfigurationIsRefused) {
  mcsim::StepperCommonLegStageParams cp;
  cp.vbus_v = 0.0;
  mcsim::StepperCommonLegStage st;
  EXPECT_EQ(st.configure(cp), Status::kNotFinite);
  cp.vbus_v = 24.0;
  cp.inverter.t_dead_s = cp.inverter.t_pwm_s;
  EXPECT_EQ(st.configure(cp), Status::kBadDeadTime);
  cp.inverter.t_dead_s = 0.0;
  cp.substeps = 0;
  EXPECT_EQ(st.configure(cp), Status::kBadStepCount);
}

}  // namespace
