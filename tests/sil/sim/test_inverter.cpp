// Average-value inverters: line voltages, common mode, Clarke, dead time,
// DC-bus limit.
#include <cmath>
#include <cstdint>

#include <Eigen/Core>
#include <gtest/gtest.h>

#include "mcsim/frames.hpp"
#include "mcsim/inverter.hpp"
#include "sim_test_util.hpp"

namespace {

using Eigen::Vector2d;
using Eigen::Vector3d;
using mcsim::Inverter3Ph;
using mcsim::InverterHBridge2;
using mcsim::InverterParams;
using mcsim::Status;
using mcsim_test::kPi;

Vector3d no_current() {
  return Vector3d::Zero();
}

TEST(SimInverter3Ph, LineToLineVoltagesFollowDuties) {
  Inverter3Ph inv;
  const double vbus = 48.0;
  for (int k = 0; k < 20; ++k) {
    const Vector3d d(0.5 + 0.45 * std::sin(0.3 * k), 0.5 + 0.4 * std::cos(0.7 * k),
                     0.05 * (k % 19));
    const Vector3d v = inv.phase_voltages_v(d, vbus, no_current());
    // 1e-12 V: a few roundings of ~50 V quantities.
    EXPECT_NEAR(v(0) - v(1), (d(0) - d(1)) * vbus, 1e-12);
    EXPECT_NEAR(v(1) - v(2), (d(1) - d(2)) * vbus, 1e-12);
    EXPECT_NEAR(v(2) - v(0), (d(2) - d(0)) * vbus, 1e-12);
    EXPECT_NEAR(v.sum(), 0.0, 1e-12);  // star point: no common mode
  }
}

TEST(SimInverter3Ph, CommonModeOfDutiesIsRemoved) {
  Inverter3Ph inv;
  const Vector3d d(0.6, 0.3, 0.45);
  const Vector3d v1 = inv.phase_voltages_v(d, 24.0, no_current());
  const Vector3d v2 = inv.phase_voltages_v(d + Vector3d::Constant(0.2), 24.0, no_current());
  // Shifting every duty by the same amount (zero-sequence injection, as SVPWM
  // does) changes no phase voltage: 1e-12 V round-off bound.
  EXPECT_LT((v1 - v2).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_NEAR(v1(0), (0.6 - 0.45) * 24.0, 1e-12);  // v_a = (2 d_a - d_b - d_c)/3 vbus
}

TEST(SimInverter3Ph, AlphaBetaIsAmplitudeInvariant) {
  Inverter3Ph inv;
  const double m = 0.8;
  const double vbus = 36.0;
  for (int k = 0; k < 12; ++k) {
    const double th = 0.5 * k;
    const Vector3d d(0.5 + 0.5 * m * std::cos(th), 0.5 + 0.5 * m * std::cos(th - 2.0 * kPi / 3.0),
                     0.5 + 0.5 * m * std::cos(th + 2.0 * kPi / 3.0));
    const Vector2d vab = inv.alpha_beta_v(d, vbus, no_current());
    // Sinusoidal duties of depth m give a vector of length m vbus / 2.
    EXPECT_NEAR(vab(0), 0.5 * m * vbus * std::cos(th), 1e-12);
    EXPECT_NEAR(vab(1), 0.5 * m * vbus * std::sin(th), 1e-12);
  }
  // inverse_clarke(clarke(v)) == v for zero-sum v (frames consistency).
  const Vector3d v(3.0, -1.0, -2.0);
  EXPECT_LT((mcsim::inverse_clarke(mcsim::clarke(v)) - v).cwiseAbs().maxCoeff(), 1e-15);
}

TEST(SimInverter3Ph, AlphaBetaIsTheClarkeOfThePhaseVoltages) {
  // alpha_beta_v() forms the Clarke transform from the pole voltages (the
  // common mode cancels) with products for 1/3 and 1/sqrt(3): equal to
  // clarke(phase_voltages_v()) to a few roundings of vbus (1e-14 relative:
  // a handful of 1.1e-16 roundings; a wrong sign or factor is off by >1e-2),
  // with and without dead time, inside and at the rails.
  Inverter3Ph inv;
  InverterParams p;
  p.t_dead_s = 1.0e-6;
  p.i_dead_band_a = 0.2;
  for (const bool dead : {false, true}) {
    if (dead) {
      ASSERT_EQ(inv.configure(p), Status::kOk);
    }
    std::uint64_t r = 99U;
    auto uni = [&r](double lo, double hi) {
      r = r * 6364136223846793005ULL + 1442695040888963407ULL;
      return lo + (hi - lo) * (static_cast<double>(r >> 11) * 0x1p-53);
    };
    for (int k = 0; k < 2000; ++k) {
      const double vbus = uni(10.0, 400.0);
      const Vector3d d(uni(-0.1, 1.1), uni(-0.1, 1.1), uni(-0.1, 1.1));
      const Vector3d i(uni(-5.0, 5.0), uni(-5.0, 5.0), uni(-5.0, 5.0));
      const Vector2d got = inv.alpha_beta_v(d, vbus, i);
      const Vector2d ref = mcsim::clarke(inv.phase_voltages_v(d, vbus, i));
      ASSERT_NEAR(got(0), ref(0), 1e-14 * vbus) << "k " << k;
      ASSERT_NEAR(got(1), ref(1), 1e-14 * vbus) << "k " << k;
    }
  }
}

TEST(SimInverter3Ph, DeadTimeErrorOpposesCurrent) {
  Inverter3Ph inv;
  InverterParams p;
  p.t_pwm_s = 50.0e-6;
  p.t_dead_s = 1.0e-6;  // 2 % of the period
  p.i_dead_band_a = 0.1;
  ASSERT_EQ(inv.configure(p), Status::kOk);
  const double vbus = 50.0;
  const double dv = 0.02 * vbus;  // t_dead / T_pwm * vbus = 1 V
  const Vector3d d(0.5, 0.5, 0.5);
  // 1e-12 V round-off bounds throughout.
  // Current out of leg a (positive): its pole voltage drops by dv.
  EXPECT_NEAR(inv.pole_voltages_v(d, vbus, Vector3d(5.0, 0.0, 0.0))(0), 25.0 - dv, 1e-12);
  // Current into leg a (negative): the pole voltage rises by dv.
  EXPECT_NEAR(inv.pole_voltages_v(d, vbus, Vector3d(-5.0, 0.0, 0.0))(0), 25.0 + dv, 1e-12);
  // Zero current: no error; half the linear band: half the error.
  EXPECT_NEAR(inv.pole_voltages_v(d, vbus, no_current())(0), 25.0, 1e-12);
  EXPECT_NEAR(inv.pole_voltages_v(d, vbus, Vector3d(0.05, 0.0, 0.0))(0), 25.0 - 0.5 * dv, 1e-12);
  // Currents (+5, -2.5, -2.5): poles (25 - dv, 25 + dv, 25 + dv); removing
  // the common mode 25 + dv/3 leaves (-4/3 dv, 2/3 dv, 2/3 dv).
  const Vector3d v = inv.phase_voltages_v(d, vbus, Vector3d(5.0, -2.5, -2.5));
  EXPECT_NEAR(v(0), -4.0 / 3.0 * dv, 1e-12);
  EXPECT_NEAR(v(1), 2.0 / 3.0 * dv, 1e-12);
}

TEST(SimInverter3Ph, BusLimitClampsDutiesAndPoles) {
  Inverter3Ph inv;
  const double vbus = 40.0;
  const Vector3d v = inv.pole_voltages_v(Vector3d(1.7, -0.3, 0.5), vbus, no_current());
  EXPECT_EQ(v(0), vbus);  // exact: clamped
  EXPECT_EQ(v(1), 0.0);
  const Vector3d ph = inv.phase_voltages_v(Vector3d(1.7, -0.3, 0.5), vbus, no_current());
  EXPECT_NEAR(ph(0) - ph(1), vbus, 1e-12);  // line voltage never exceeds vbus
  InverterParams p;
  p.t_dead_s = 2.0e-6;
  ASSERT_EQ(inv.configure(p), Status::kOk);
  // Dead time cannot push a pole outside the rails.
  EXPECT_EQ(inv.pole_voltages_v(Vector3d(0.0, 1.0, 0.5), vbus, Vector3d(3.0, -3.0, 0.0))(0), 0.0);
  EXPECT_EQ(inv.pole_voltages_v(Vector3d(0.0, 1.0, 0.5), vbus, Vector3d(3.0, -3.0, 0.0))(1), vbus);
  // DC current = sum d_x i_x (power balance of a lossless bridge).
  EXPECT_NEAR(Inverter3Ph::dc_current_a(Vector3d(0.7, 0.2, 0.4), Vector3d(2.0, -1.0, -1.0)),
              1.4 - 0.2 - 0.4, 1e-15);
}

// A leg held at duty 0 or 1 does not switch: one of its switches is on for
// the whole period and there is no dead-time interval, whatever the current
// (the active short circuit: all three legs at 0, every phase at the
// negative rail, no power to or from the bus).
TEST(SimInverter3Ph, LegsThatDoNotSwitchHaveNoDeadTime) {
  Inverter3Ph inv;
  InverterParams p;
  p.t_pwm_s = 50.0e-6;
  p.t_dead_s = 1.0e-6;
  ASSERT_EQ(inv.configure(p), Status::kOk);
  const double vbus = 50.0;
  const Vector3d i(-40.0, 70.0, -30.0);  // currents into legs a and c
  // exact: no arithmetic on a rail
  const Vector3d v0 = inv.pole_voltages_v(Vector3d(0.0, 0.0, 0.0), vbus, i);
  EXPECT_EQ(v0(0), 0.0);
  EXPECT_EQ(v0(1), 0.0);
  EXPECT_EQ(v0(2), 0.0);
  EXPECT_EQ(inv.pole_voltages_v(Vector3d(1.0, 1.0, 1.0), vbus, -i)(0), vbus);
  EXPECT_EQ(Inverter3Ph::dc_current_a(Vector3d(0.0, 0.0, 0.0), i), 0.0);
  // A switching leg next to them keeps its dead-time error (2 % of vbus).
  EXPECT_NEAR(inv.pole_voltages_v(Vector3d(0.5, 0.0, 0.0), vbus, i)(0), 25.0 + 0.02 * vbus, 1e-12);
}

TEST(SimInverter3Ph, InvalidConfigKeepsOldOne) {
  Inverter3Ph inv;
  InverterParams p;
  p.t_pwm_s = 0.0;
  EXPECT_EQ(inv.configure(p), Status::kBadPwmPeriod);
  p = InverterParams{};
  p.t_dead_s = 0.5 * p.t_pwm_s;
  EXPECT_EQ(inv.configure(p), Status::kBadDeadTime);
  p = InverterParams{};
  p.t_dead_s = -1e-9;
  EXPECT_EQ(inv.configure(p), Status::kBadDeadTime);
  p = InverterParams{};
  p.i_dead_band_a = 0.0;
  EXPECT_EQ(inv.configure(p), Status::kBadDeadBand);
  p = InverterParams{};
  p.t_pwm_s = NAN;
  EXPECT_EQ(inv.configure(p), Status::kNotFinite);
  EXPECT_EQ(inv.params().t_dead_s, 0.0);
  EXPECT_EQ(inv.params().t_pwm_s, InverterParams{}.t_pwm_s);
}

TEST(SimInverterHBridge, SignedDutiesDeadTimeAndLimit) {
  InverterHBridge2 hb;
  const double vbus = 24.0;
  const Vector2d v = hb.voltages_v(Vector2d(0.25, -0.5), vbus, Vector2d::Zero());
  EXPECT_NEAR(v(0), 6.0, 1e-12);
  EXPECT_NEAR(v(1), -12.0, 1e-12);
  const Vector2d vc = hb.voltages_v(Vector2d(1.5, -2.0), vbus, Vector2d::Zero());
  EXPECT_EQ(vc(0), vbus);  // exact: clamped to the bus
  EXPECT_EQ(vc(1), -vbus);
  InverterParams p;
  p.t_pwm_s = 40.0e-6;
  p.t_dead_s = 0.4e-6;  // 1 %, two legs -> 2 % of vbus
  ASSERT_EQ(hb.configure(p), Status::kOk);
  const Vector2d vd = hb.voltages_v(Vector2d(0.25, 0.25), vbus, Vector2d(1.0, -1.0));
  EXPECT_NEAR(vd(0), 6.0 - 0.02 * vbus, 1e-12);
  EXPECT_NEAR(vd(1), 6.0 + 0.02 * vbus, 1e-12);
}

}  // namespace
