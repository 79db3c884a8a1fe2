// PmsmOpenPhase (one phase conductor broken): closed-form locked-rotor
// responses of the series circuit, agreement with PmsmDq's torque and
// mechanics at the same current vector, the energy balance, the mapping from
// and to the rotor-frame state, and configuration errors.
#include <cmath>
#include <random>

#include <Eigen/Core>
#include <gtest/gtest.h>

#include "mcsim/integrator.hpp"
#include "mcsim/pmsm_dq.hpp"
#include "mcsim/pmsm_open_phase.hpp"
#include "mcsim/pmsm_rotor_frame.hpp"

namespace {

using mcsim::PmsmDq;
using mcsim::PmsmOpenPhase;
using mcsim::PmsmParams;
using mcsim::PmsmRotorFrame;
using mcsim::Status;

constexpr double kPi = 3.14159265358979323846;

// Paper 002's test motor (the SIL motor), optionally made salient.
PmsmParams motor(double lq_h = 1.14e-3, double flux_wb = 0.11) {
  PmsmParams p;
  p.R_ohm = 0.675;
  p.Ld_h = 1.14e-3;
  p.Lq_h = lq_h;
  p.flux_wb = flux_wb;
  p.pole_pairs = 4;
  p.J_kgm2 = 1.0e-3;
  p.B_nms_rad = 1.0e-4;
  return p;
}

PmsmOpenPhase::State state_at(const PmsmParams& p, double i_a, double omega_m, double theta_m) {
  PmsmOpenPhase::State x;
  const double th_e = p.pole_pairs * theta_m;
  x << i_a, omega_m, theta_m, std::cos(th_e), std::sin(th_e);
  return x;
}

// Direction of the series current in alpha-beta for open phase k (header).
double phi(int k) {
  return kPi / 2.0 + k * 2.0 * kPi / 3.0;
}

// Locked rotor: a constant voltage v across the pair, rotor at an angle
// where the torque is zero (so it stays locked exactly: omega stays 0), 20
// kHz periods with 4 RK4 sub-steps. The series circuit is first order:
//   i(t) = v/(2R) (1 - exp(-t 2R/L_yz)),  L_yz = (Ld + Lq) + (Ld - Lq) cos 2(th - phi).
// Tolerance 1e-9 relative to v/(2R): RK4's error on a linear ODE with
// h/tau = 12.5 us / 1.69 ms is ~(h/tau)^5/120 = 2e-13 per step, so 1e-9 is
// far above it, and a wrong inductance or resistance is off by > 1e-2.
void expect_locked_rotor_rl(const PmsmParams& p, int k, double th_e_minus_phi, double l_yz) {
  PmsmOpenPhase m;
  ASSERT_EQ(m.configure(p, k), Status::kOk);
  const double theta_m = (phi(k) + th_e_minus_phi) / p.pole_pairs;
  PmsmOpenPhase::State x = state_at(p, 0.0, 0.0, theta_m);
  EXPECT_NEAR(m.line_inductance_h(x), l_yz, 1e-15) << "phase " << k;
  const double v = 10.0, T = 50e-6;
  const double i_inf = v / (2.0 * p.R_ohm), tau = l_yz / (2.0 * p.R_ohm);
  double worst = 0.0;
  for (int n = 1; n <= 400; ++n) {  // 20 ms: ~12 time constants
    ASSERT_EQ(mcsim::advance_zoh(m, PmsmOpenPhase::Input(v), (n - 1) * T, T, 4, &x), Status::kOk);
    const double want = i_inf * (1.0 - std::exp(-n * T / tau));
    worst = std::max(worst, std::abs(x(PmsmOpenPhase::kI) - want));
  }
  EXPECT_LT(worst, 1e-9 * i_inf) << "phase " << k;
  // Zero torque at this angle to rounding (~1e-14 N m): the rotor stays;
  // 1e-9 rad/s would add 1e-9 V of back-EMF, nothing against 10 V.
  EXPECT_LT(std::abs(x(PmsmOpenPhase::kOmegaM)), 1e-9) << "the rotor must stay locked";
}

TEST(SimOpenPhase, LockedRotorFirstOrderNonSalient) {
  // Ld = Lq = L: L_yz = 2 L at every angle, time constant L / R = 1.69 ms.
  // The torque is zero where the current is along the rotor flux
  // (th_e = phi), so the rotor stays locked.
  const PmsmParams p = motor();
  for (int k = 0; k < 3; ++k) expect_locked_rotor_rl(p, k, 0.0, 2.0 * p.Ld_h);
}

TEST(SimOpenPhase, LockedRotorFirstOrderSalient) {
  // Ld = 1.14 mH, Lq = 2 mH: along d (th_e = phi) L_yz = 2 Ld; along q
  // (th_e = phi + pi/2) L_yz = 2 Lq. With the magnet flux at 0 the torque
  // (reluctance only, ~ sin 2(th - phi)) is zero at both angles.
  const PmsmParams p = motor(2.0e-3, 0.0);
  for (int k = 0; k < 3; ++k) {
    expect_locked_rotor_rl(p, k, 0.0, 2.0 * p.Ld_h);
    expect_locked_rotor_rl(p, k, kPi / 2.0, 2.0 * p.Lq_h);
  }
}

TEST(SimOpenPhase, OpenPhaseCurrentIsExactlyZero) {
  const PmsmParams p = motor();
  for (int k = 0; k < 3; ++k) {
    PmsmOpenPhase m;
    ASSERT_EQ(m.configure(p, k), Status::kOk);
    const Eigen::Vector3d i = m.phase_currents_a(state_at(p, 3.7, 10.0, 0.3));
    EXPECT_EQ(i(k), 0.0);
    EXPECT_EQ(i(m.phase_y()), 3.7);
    EXPECT_EQ(i(m.phase_z()), -3.7);
    EXPECT_NE(m.phase_y(), k);
    EXPECT_NE(m.phase_z(), k);
    EXPECT_NE(m.phase_y(), m.phase_z());
  }
}

TEST(SimOpenPhase, TorqueAndMechanicsEqualPmsmDqAtTheSameCurrentVector) {
  // The series current i is the dq vector to_rotor_frame() gives; PmsmDq's
  // torque 3/2 p (psi iq + (Ld - Lq) id iq) and speed derivative at that
  // vector must equal the open-phase model's (co-energy) ones, salient or
  // not. Tolerance: 1e-12 relative (rounding of a few dozen operations).
  for (const double lq : {1.14e-3, 2.0e-3}) {
    PmsmParams p = motor(lq);
    p.load = mcsim::load_constant(0.3);
    PmsmDq dq;
    ASSERT_EQ(dq.configure(p), Status::kOk);
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> U(-1.0, 1.0);
    for (int k = 0; k < 3; ++k) {
      PmsmOpenPhase m;
      ASSERT_EQ(m.configure(p, k), Status::kOk);
      for (int n = 0; n < 300; ++n) {
        const PmsmOpenPhase::State x = state_at(p, 10 * U(rng), 100 * U(rng), 7 * U(rng));
        const PmsmRotorFrame::State xr = m.to_rotor_frame(x);
        const double tau_dq = dq.torque_nm(xr.head<4>());
        const double tau_op = m.torque_nm(x);
        EXPECT_NEAR(tau_op, tau_dq, 1e-12 * (1.0 + std::abs(tau_dq)));
        const PmsmDq::State ddq = dq.deriv(0.0, xr.head<4>(), PmsmDq::Input::Zero());
        const PmsmOpenPhase::State dop = m.deriv(0.0, x, PmsmOpenPhase::Input(0.0));
        EXPECT_NEAR(dop(PmsmOpenPhase::kOmegaM), ddq(PmsmDq::kOmegaM),
                    1e-12 * (1.0 + std::abs(ddq(PmsmDq::kOmegaM))));
        // Round trip: the series current survives to_rotor_frame/from_rotor_frame.
        EXPECT_NEAR(m.from_rotor_frame(xr)(PmsmOpenPhase::kI), x(PmsmOpenPhase::kI),
                    1e-13 * (1.0 + std::abs(x(PmsmOpenPhase::kI))));
      }
    }
  }
}

TEST(SimOpenPhase, BreakProjectsTheCurrentVector) {
  // A healthy state with phase currents (ia, ib, ic): breaking phase a
  // leaves i = (ib - ic)/2 in the pair b-c, i.e. +i in b and -i in c.
  const PmsmParams p = motor();
  PmsmRotorFrame rf;
  ASSERT_EQ(rf.configure(p), Status::kOk);
  const PmsmRotorFrame::State xr = rf.make_state(1.5, -2.5, 20.0, 0.7);
  const Eigen::Vector2d iab = PmsmRotorFrame::i_alpha_beta_a(xr);
  const double ia = iab(0);
  const double ib = -0.5 * iab(0) + 0.5 * std::sqrt(3.0) * iab(1);
  const double ic = -0.5 * iab(0) - 0.5 * std::sqrt(3.0) * iab(1);
  const double iabc[3] = {ia, ib, ic};
  for (int k = 0; k < 3; ++k) {
    PmsmOpenPhase m;
    ASSERT_EQ(m.configure(p, k), Status::kOk);
    const PmsmOpenPhase::State x = m.from_rotor_frame(xr);
    // 1e-14 A: a handful of roundings on currents of ~3 A.
    EXPECT_NEAR(x(PmsmOpenPhase::kI), 0.5 * (iabc[m.phase_y()] - iabc[m.phase_z()]), 1e-14);
    EXPECT_EQ(x(PmsmOpenPhase::kOmegaM), 20.0);
    EXPECT_EQ(x(PmsmOpenPhase::kThetaM), 0.7);
  }
}

TEST(SimOpenPhase, EnergyBalanceWhileTurning) {
  // Salient machine, phase b open, spinning with a voltage across the pair
  // that changes every period: input energy = copper loss + change of the
  // magnetic energy 1/2 L_yz i^2 + electromagnetic work (integral of tau
  // omega_m). Sub-steps of 0.5 us (RK4) and trapezoidal quadrature of the
  // three powers: the quadrature error is O(h^2) (measured 3e-8 of the
  // 17 J input); bound 1e-5 of the input energy. A wrong sign or factor in the
  // dL/dtheta term or in the torque breaks it by > 1e-2.
  PmsmParams p = motor(2.0e-3);
  p.J_kgm2 = 2.0e-4;
  PmsmOpenPhase m;
  ASSERT_EQ(m.configure(p, 1), Status::kOk);
  PmsmOpenPhase::State x = state_at(p, 0.5, 80.0, 0.2);
  const double w0 = m.magnetic_energy_j(x);
  const double h = 0.5e-6;
  double e_in = 0.0, e_cu = 0.0, e_mech = 0.0;
  for (int n = 0; n < 400; ++n) {  // 400 periods of 50 us = 20 ms
    const double v = 60.0 * std::sin(2.0 * kPi * 150.0 * n * 50e-6) + 5.0;
    const PmsmOpenPhase::Input u(v);
    for (int j = 0; j < 100; ++j) {
      const double t = n * 50e-6 + j * h;
      const double i0 = x(PmsmOpenPhase::kI), pm0 = m.torque_nm(x) * x(PmsmOpenPhase::kOmegaM);
      x = mcsim::rk4_step(m, t, x, u, h);
      const double i1 = x(PmsmOpenPhase::kI), pm1 = m.torque_nm(x) * x(PmsmOpenPhase::kOmegaM);
      e_in += 0.5 * h * v * (i0 + i1);
      e_cu += 0.5 * h * 2.0 * p.R_ohm * (i0 * i0 + i1 * i1);
      e_mech += 0.5 * h * (pm0 + pm1);
    }
    // (cos, sin) drift: re-derive from theta_m every period.
    const double th_e = p.pole_pairs * x(PmsmOpenPhase::kThetaM);
    x(PmsmOpenPhase::kCos) = std::cos(th_e);
    x(PmsmOpenPhase::kSin) = std::sin(th_e);
  }
  const double dw = m.magnetic_energy_j(x) - w0;
  ASSERT_GT(std::abs(e_in), 1.0) << "the test must move real energy";
  EXPECT_NEAR(e_in, e_cu + dw + e_mech, 1e-5 * std::abs(e_in))
      << "in " << e_in << " cu " << e_cu << " mag " << dw << " mech " << e_mech;
}

TEST(SimOpenPhase, ConfigurationErrorsChangeNothing) {
  PmsmOpenPhase m;
  ASSERT_EQ(m.configure(motor(), 2), Status::kOk);
  EXPECT_EQ(m.configure(motor(), 3), Status::kBadPhase);
  EXPECT_EQ(m.configure(motor(), -1), Status::kBadPhase);
  PmsmParams bad = motor();
  bad.Lq_h = 0.0;
  EXPECT_EQ(m.configure(bad, 0), Status::kNonPositiveInductance);
  EXPECT_EQ(m.open_phase(), 2);
  EXPECT_EQ(m.params().Lq_h, motor().Lq_h);
}

}  // namespace
