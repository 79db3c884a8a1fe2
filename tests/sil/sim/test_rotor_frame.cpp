// PmsmRotorFrame (the SIL board's fast plant) against the reference models:
// its hand-written derivative must equal PmsmDq's, and its trajectories must
// equal PmsmAb's under the same stationary-frame voltages.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include <Eigen/Core>
#include <gtest/gtest.h>

#include "mcsim/integrator.hpp"
#include "mcsim/pmsm_ab.hpp"
#include "mcsim/pmsm_dq.hpp"
#include "mcsim/pmsm_rotor_frame.hpp"

namespace {

using mcsim::PmsmAb;
using mcsim::PmsmDq;
using mcsim::PmsmParams;
using mcsim::PmsmRotorFrame;
using mcsim::Status;

PmsmParams salient(mcsim::LoadTorque load) {
  PmsmParams p;
  p.R_ohm = 0.2;
  p.Ld_h = 2.0e-4;
  p.Lq_h = 3.5e-4;
  p.flux_wb = 0.015;
  p.pole_pairs = 7;
  p.J_kgm2 = 2.0e-5;
  p.B_nms_rad = 1.0e-5;
  p.load = load;
  return p;
}

TEST(SimRotorFrame, DerivativeEqualsPmsmDq) {
  // Same equations, reciprocals instead of divisions: agreement to a few
  // roundings. Tolerance 1e-12 relative to the largest term's magnitude
  // (double rounding is 1.1e-16; the terms add up ~10 roundings).
  for (const auto& load : {mcsim::load_constant(0.05), mcsim::load_step(0.0, 0.01, 0.1)}) {
    PmsmParams p = salient(load);
    PmsmDq dq;
    PmsmRotorFrame rf;
    ASSERT_EQ(dq.configure(p), Status::kOk);
    ASSERT_EQ(rf.configure(p), Status::kOk);
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> U(-1.0, 1.0);
    for (int k = 0; k < 1000; ++k) {
      const double th = 10.0 * U(rng);
      PmsmRotorFrame::State x = rf.make_state(20 * U(rng), 20 * U(rng), 300 * U(rng), th);
      const PmsmRotorFrame::Input u(24 * U(rng), 24 * U(rng));
      const double t = 0.02 * (U(rng) + 1.0);
      const double the = p.pole_pairs * th;
      const PmsmDq::Input vdq(std::cos(the) * u(0) + std::sin(the) * u(1),
                              -std::sin(the) * u(0) + std::cos(the) * u(1));
      const PmsmDq::State ref = dq.deriv(t, x.head<4>(), vdq);
      const PmsmRotorFrame::State got = rf.deriv(t, x, u);
      for (int i = 0; i < 4; ++i) {
        EXPECT_NEAR(got(i), ref(i), 1e-12 * (1.0 + std::abs(ref(i)))) << "component " << i;
      }
      const double we = p.pole_pairs * x(2);
      EXPECT_NEAR(got(4), -we * x(5), 1e-12 * (1.0 + std::abs(we)));
      EXPECT_NEAR(got(5), we * x(4), 1e-12 * (1.0 + std::abs(we)));
    }
  }
}

TEST(SimRotorFrame, TrajectoryEqualsAlphaBetaModel) {
  // Both models integrate the same machine under the same ZOH alpha-beta
  // voltages (a rotating vector with a step), 20 kHz, 4 RK4 sub-steps,
  // (cos, sin) re-synced every 32 periods as the SIL board does. The two
  // state representations differ, so they agree to the RK4 truncation error:
  // bounds 1e-5 A on currents of ~10 A, 1e-5 rad/s, 1e-7 rad (measured
  // 2e-7 A, 1.2e-6 rad/s, 2.4e-9 rad: the bounds leave room for compilers
  // and libm, and a sign or a term wrong in the derivative is off by >1e-2).
  PmsmParams p = salient(mcsim::load_constant(0.02));
  PmsmAb ab;
  PmsmRotorFrame rf;
  ASSERT_EQ(ab.configure(p), Status::kOk);
  ASSERT_EQ(rf.configure(p), Status::kOk);
  PmsmAb::State xa = PmsmAb::State::Zero();
  PmsmRotorFrame::State xr = rf.make_state(0, 0, 0, 0);
  const double T = 50e-6;
  double max_di = 0, max_dw = 0, max_dth = 0;
  for (int k = 0; k < 4000; ++k) {
    const double t = k * T;
    const double amp = (t < 0.05) ? 3.0 : 6.0;
    const double ang = 2.0 * 3.14159265358979 * 40.0 * t * t * 20.0;  // chirp
    const Eigen::Vector2d v(amp * std::cos(ang), amp * std::sin(ang));
    ASSERT_EQ(mcsim::advance_zoh(ab, v, t, T, 4, &xa), Status::kOk);
    ASSERT_EQ(rf.advance_zoh(v, t, T, 4, &xr), Status::kOk);  // the SIL board's integrator
    if (((k + 1) & 31) == 0) rf.resync(&xr);
    const Eigen::Vector2d iab = PmsmRotorFrame::i_alpha_beta_a(xr);
    max_di = std::max(max_di, (iab - xa.head<2>()).cwiseAbs().maxCoeff());
    max_dw = std::max(max_dw, std::abs(xr(2) - xa(2)));
    max_dth = std::max(max_dth, std::abs(xr(3) - xa(3)));
  }
  std::printf(
      "rotor frame vs alpha-beta: max |di| %.3g A, |dw| %.3g rad/s, |dth| %.3g rad, "
      "final w %.1f rad/s\n",
      max_di, max_dw, max_dth, xa(2));
  EXPECT_GT(std::abs(xa(2)), 10.0) << "the run must actually spin the rotor";
  EXPECT_LT(max_di, 1e-5);
  EXPECT_LT(max_dw, 1e-5);
  EXPECT_LT(max_dth, 1e-7);
}

// An angle- and speed-dependent load with Coulomb friction: exercises the
// load call at the stage times, angles and speeds of RK4.
mcsim::LoadTorque ripple_load() {
  mcsim::LoadTorque l;
  l.kind = mcsim::LoadKind::kAngleSpeed;
  l.tau0_nm = 0.01;
  l.k_omega_nms_rad = 2.0e-5;
  l.k_omega2_nms2_rad2 = 1.0e-7;
  l.ripple_nm = 0.02;
  l.ripple_per_rev = 6.0;
  l.coulomb_nm = 0.005;
  l.coulomb_band_rad_s = 0.5;
  return l;
}

// Largest |a_i - b_i| / (1 + |b_i|) over the six states.
double rel_diff(const PmsmRotorFrame::State& a, const PmsmRotorFrame::State& b) {
  return ((a - b).array().abs() / (1.0 + b.array().abs())).maxCoeff();
}

TEST(SimRotorFrame, WrittenOutRk4EqualsGenericRk4) {
  // PmsmRotorFrame::advance_zoh() is advance_zoh(plant, ...) (rk4_step on
  // deriv()) with the step factors folded into the constants: the same
  // stages and weights, roundings in other places. One period from random
  // states and inputs, 1, 3 and 4 sub-steps, constant, step and
  // angle/speed/Coulomb loads, a salient and a round-rotor machine.
  // Tolerance 1e-13 relative: a period adds ~100 roundings of terms no
  // larger than the state (1.1e-16 each); a wrong weight or stage time is
  // off by the RK4 increment itself, >1e-4 here.
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  double worst = 0.0;
  for (const auto& load :
       {mcsim::load_constant(0.05), mcsim::load_step(0.0, 0.01, 0.1), ripple_load()}) {
    for (const bool round_rotor : {false, true}) {
      PmsmParams p = salient(load);
      if (round_rotor) p.Lq_h = p.Ld_h;
      PmsmRotorFrame rf;
      ASSERT_EQ(rf.configure(p), Status::kOk);
      for (const int n : {1, 3, 4}) {
        for (int k = 0; k < 300; ++k) {
          const PmsmRotorFrame::State x0 =
              rf.make_state(20 * U(rng), 20 * U(rng), 300 * U(rng), 10.0 * U(rng));
          const PmsmRotorFrame::Input u(24 * U(rng), 24 * U(rng));
          const double t0 = 0.01 * (U(rng) + 1.0);  // straddles the load step
          PmsmRotorFrame::State ref = x0, got = x0;
          ASSERT_EQ(mcsim::advance_zoh(rf, u, t0, 50e-6, n, &ref), Status::kOk);
          ASSERT_EQ(rf.advance_zoh(u, t0, 50e-6, n, &got), Status::kOk);
          ASSERT_GT((ref - x0).norm(), 1e-4) << "the period must move the state";
          worst = std::max(worst, rel_diff(got, ref));
          ASSERT_LT(rel_diff(got, ref), 1e-13) << "n " << n << " k " << k;
        }
      }
    }
  }
  std::printf("written-out vs generic RK4, one period: worst relative difference %.3g\n", worst);
}

TEST(SimRotorFrame, WrittenOutRk4FollowsParameterAndPeriodChanges) {
  // The step constants are cached per (period, sub-steps) and parameters:
  // a new period, a new sub-step count and a re-configure must all be seen.
  // Over 2000 periods of a chirp drive (the rotor slips poles, which
  // amplifies rounding differences) the two integrators stay within 1e-10
  // relative (measured 6.5e-12; a stale constant is off by more than 1e-3).
  PmsmRotorFrame rf;
  ASSERT_EQ(rf.configure(salient(mcsim::load_constant(0.02))), Status::kOk);
  PmsmRotorFrame::State ref = rf.make_state(0, 0, 0, 0), got = ref;
  double worst = 0.0;
  for (int k = 0; k < 2000; ++k) {
    if (k == 500) {
      PmsmParams p = salient(ripple_load());
      p.R_ohm = 0.4;
      ASSERT_EQ(rf.configure(p), Status::kOk);
    }
    const double T = (k < 1000) ? 50e-6 : 40e-6;
    const int n = (k < 1500) ? 4 : 2;
    const double t = k * T;
    const double ang = 2.0 * 3.14159265358979 * 40.0 * t * t * 20.0;  // chirp
    const Eigen::Vector2d v(6.0 * std::cos(ang), 6.0 * std::sin(ang));
    ASSERT_EQ(mcsim::advance_zoh(rf, v, t, T, n, &ref), Status::kOk);
    ASSERT_EQ(rf.advance_zoh(v, t, T, n, &got), Status::kOk);
    if (((k + 1) & 31) == 0) {
      rf.resync(&ref);
      rf.resync(&got);
    }
    worst = std::max(worst, rel_diff(got, ref));
  }
  std::printf(
      "written-out vs generic RK4, 2000 periods: worst relative difference %.3g, "
      "final w %.1f rad/s\n",
      worst, ref(2));
  EXPECT_GT(std::abs(ref(2)), 10.0) << "the run must actually spin the rotor";
  EXPECT_LT(worst, 1e-10);
}

TEST(SimRotorFrame, WrittenOutRk4RejectsBadArgumentsAndKeepsState) {
  PmsmRotorFrame rf;
  ASSERT_EQ(rf.configure(salient(mcsim::load_constant(0.0))), Status::kOk);
  const PmsmRotorFrame::State x0 = rf.make_state(1, 2, 3, 0.4);
  PmsmRotorFrame::State x = x0;
  const PmsmRotorFrame::Input u(1.0, -2.0);
  const double nan = std::nan("");
  EXPECT_EQ(rf.advance_zoh(u, 0.0, 50e-6, 0, &x), Status::kBadStepCount);
  EXPECT_EQ(rf.advance_zoh(u, 0.0, 0.0, 4, &x), Status::kBadPeriod);
  EXPECT_EQ(rf.advance_zoh(u, 0.0, nan, 4, &x), Status::kBadPeriod);
  EXPECT_EQ(rf.advance_zoh(u, nan, 50e-6, 4, &x), Status::kNotFinite);
  EXPECT_EQ(rf.advance_zoh(u, 0.0, 50e-6, 4, nullptr), Status::kNotFinite);
  for (int i = 0; i < 6; ++i) EXPECT_EQ(x(i), x0(i)) << "state changed, component " << i;
}

TEST(SimRotorFrame, ResyncRestoresUnitVector) {
  // Drifted (cos, sin) are replaced by the exact values of p * theta_m.
  PmsmRotorFrame rf;
  ASSERT_EQ(rf.configure(salient(mcsim::load_constant(0.0))), Status::kOk);
  PmsmRotorFrame::State x = rf.make_state(1, 2, 3, 0.4);
  x(4) *= 1.01;
  x(5) += 0.02;
  rf.resync(&x);
  EXPECT_DOUBLE_EQ(x(4), std::cos(7 * 0.4));
  EXPECT_DOUBLE_EQ(x(5), std::sin(7 * 0.4));
}

TEST(SimRotorFrame, InvalidParametersRejected) {
  PmsmRotorFrame rf;
  PmsmParams p = salient(mcsim::load_constant(0.0));
  p.Ld_h = -1.0;
  EXPECT_EQ(rf.configure(p), Status::kNonPositiveInductance);
}

}  // namespace
