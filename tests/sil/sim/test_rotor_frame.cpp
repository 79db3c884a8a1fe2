// PmsmRotorFrame (the SIL board's fast plant) against the reference models:
// its hand-written derivative must equal PmsmDq's, and its trajectories must
// equal PmsmAb's under the same stationary-frame voltages.
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
    ASSERT_EQ(mcsim::advance_zoh(rf, v, t, T, 4, &xr), Status::kOk);
    if (((k + 1) & 31) == 0) rf.resync(&xr);
    const Eigen::Vector2d iab = PmsmRotorFrame::i_alpha_beta_a(xr);
    max_di = std::max(max_di, (iab - xa.head<2>()).cwiseAbs().maxCoeff());
    max_dw = std::max(max_dw, std::abs(xr(2) - xa(2)));
    max_dth = std::max(max_dth, std::abs(xr(3) - xa(3)));
  }
  std::printf("rotor frame vs alpha-beta: max |di| %.3g A, |dw| %.3g rad/s, |dth| %.3g rad, "
              "final w %.1f rad/s\n", max_di, max_dw, max_dth, xa(2));
  EXPECT_GT(std::abs(xa(2)), 10.0) << "the run must actually spin the rotor";
  EXPECT_LT(max_di, 1e-5);
  EXPECT_LT(max_dw, 1e-5);
  EXPECT_LT(max_dth, 1e-7);
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
