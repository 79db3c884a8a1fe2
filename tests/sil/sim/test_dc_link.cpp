// The DC link (mcsim/dc_link.hpp) with one and with several loads: the
// exact solution of the capacitor equation, the energy and charge balances,
// the supply's mean current, and two PMSM power stages on one link, one
// braking while the other drives (issue 34 item 2): the braking axis feeds
// the driving one and the supply gives only the difference.
#include <cmath>

#include <Eigen/Core>
#include <gtest/gtest.h>

#include "mcsim/dc_link.hpp"
#include "mcsim/pmsm_power_stage.hpp"
#include "mcsim/pmsm_rotor_frame.hpp"

namespace {

using mcsim::DcLink;
using mcsim::DcLinkParams;
using mcsim::Status;

DcLinkParams link_params(bool sink) {
  DcLinkParams p;
  p.source_v = 24.0;
  p.source_r_ohm = 0.1;
  p.source_sink = sink;
  p.c_f = 1.0e-3;
  p.brake_r_ohm = 0.0;
  return p;
}

TEST(SimDcLink, ConstantLoadFollowsTheClosedFormAndTheSupplyCurrentIsItsMean) {
  // C dv/dt = (v_s - v)/r_s - I: v = v_s - r_s I (1 - e^(-t / (r_s C))).
  DcLink l;
  ASSERT_EQ(l.configure(link_params(true)), Status::kOk);
  const double i = 10.0, tau = 0.1 * 1.0e-3, h = 50.0e-6;
  double q = 0.0;
  for (int k = 1; k <= 400; ++k) {
    l.advance(h, 4, i, 0.0);
    q += l.source_avg_a() * h;
    const double t = k * h;
    // Exact per sub-step (the equation is linear): rounding only, 1e-12 V.
    ASSERT_NEAR(l.v(), 24.0 - 0.1 * i * (1.0 - std::exp(-t / tau)), 1e-12) << "t=" << t;
  }
  // Steady: the supply gives the load's current (e^-200 left).
  EXPECT_NEAR(l.source_avg_a(), i, 1e-9);
  EXPECT_NEAR(l.source_a(), i, 1e-9);
  // Charge: what the source gave = the load's + the capacitor's change.
  EXPECT_NEAR(q, l.energy().source_c, 1e-12 * q);
  EXPECT_NEAR(l.energy().source_c, i * 400 * h + 1.0e-3 * (l.v() - 24.0), 1e-12 * q);
}

TEST(SimDcLink, SeveralLoadsAddUpAndKeepTheirOwnEnergies) {
  // Two loads advance the link exactly as one load of their sum; each
  // load's energy is its share (i_k int v); the balance holds.
  DcLinkParams p = link_params(false);
  p.brake_r_ohm = 5.0;
  DcLink two, one;
  ASSERT_EQ(two.configure(p), Status::kOk);
  ASSERT_EQ(one.configure(p), Status::kOk);
  const double h = 50.0e-6;
  for (int k = 0; k < 2000; ++k) {
    const double t = k * h;
    // Axis 0 brakes harder than axis 1 drives after 40 ms.
    const double i0 = (t < 0.04) ? -2.0 : -20.0, i1 = 6.0;
    const double loads[2] = {i0, i1};
    const double brake = (two.v() > 26.0) ? 1.0 : 0.0;
    ASSERT_EQ(two.advance_loads(h, 4, loads, 2, brake), Status::kOk);
    one.advance(h, 4, i0 + i1, brake);
    ASSERT_EQ(two.v(), one.v());  // bit for bit: the same sum
  }
  const auto& e = two.energy();
  // The loads' energies sum to the inverter total (rounding: 1e-12 rel).
  EXPECT_NEAR(two.load_j(0) + two.load_j(1), e.inverter_j, 1e-12 * std::fabs(two.load_j(0)));
  EXPECT_LT(two.load_j(0), 0.0);
  EXPECT_GT(two.load_j(1), 0.0);
  // E_source = E_rs + E_brake + sum E_load + dE_cap (closed-form integrals:
  // rounding, 1e-9 of the largest flow).
  const double lhs = e.source_j;
  const double rhs = e.source_r_j + e.brake_j + two.load_j(0) + two.load_j(1) + two.cap_delta_j();
  EXPECT_NEAR(lhs, rhs, 1e-9 * std::fabs(two.load_j(0)));
  // The one-way supply stopped delivering while the bus was above it, and
  // the brake took the surplus.
  EXPECT_GT(e.brake_j, 0.0);
  EXPECT_GE(two.source_avg_a(), 0.0);
  // Bad load counts are refused and change nothing.
  const double v = two.v();
  const double loads[5] = {1, 1, 1, 1, 1};
  EXPECT_EQ(two.advance_loads(h, 4, loads, 5, 0.0), Status::kBadLoadCount);
  EXPECT_EQ(two.advance_loads(h, 4, loads, 0, 0.0), Status::kBadLoadCount);
  EXPECT_EQ(two.advance_loads(h, 4, nullptr, 1, 0.0), Status::kBadLoadCount);
  EXPECT_EQ(two.v(), v);
}

// Duties that put (v_d, v_q) on a PMSM stage's windings at its present
// angle (sinusoidal modulation about mid-bus; |v| < vbus / 2).
Eigen::Vector3d duties_for(const mcsim::PmsmPowerStage& st, double vd, double vq) {
  const mcsim::PmsmPowerStage::State& x = st.rotor_frame_state();
  const double c = x(mcsim::PmsmRotorFrame::kCos), s = x(mcsim::PmsmRotorFrame::kSin);
  const double va = c * vd - s * vq, vb = s * vd + c * vq;
  const double s3 = std::sqrt(3.0) / 2.0;
  const double vbus = st.vbus_v();
  return {0.5 + va / vbus, 0.5 + (-0.5 * va + s3 * vb) / vbus, 0.5 + (-0.5 * va - s3 * vb) / vbus};
}

TEST(SimDcLink, BrakingAxisFeedsTheDrivingAxis) {
  // Axis 0 spins at 200 rad/s and is braked (v_q below its back-EMF of
  // p flux w = 8 V: i_q < 0, power into the bus); axis 1 starts from rest
  // and is driven. Both on one link with a supply that cannot sink. Per
  // period, as the SIL board does: each axis's power over the period
  // (trapezoid of the currents, the voltage held) drawn as P_k / v.
  mcsim::PmsmPowerStageParams sp;
  sp.motor.R_ohm = 0.1;
  sp.motor.Ld_h = sp.motor.Lq_h = 1.0e-4;
  sp.motor.flux_wb = 0.01;
  sp.motor.pole_pairs = 4;
  sp.motor.J_kgm2 = 5.0e-3;
  sp.vbus_v = 24.0;
  mcsim::PmsmPowerStage ax[2];
  sp.omega_m0_rad_s = 200.0;
  ASSERT_EQ(ax[0].configure(sp), Status::kOk);
  sp.omega_m0_rad_s = 0.0;
  ASSERT_EQ(ax[1].configure(sp), Status::kOk);
  DcLink link;
  ASSERT_EQ(link.configure(link_params(false)), Status::kOk);
  const double T = sp.inverter.t_pwm_s;
  const double vq[2] = {7.5, 3.0};
  double motor_in_j[2] = {0.0, 0.0}, copper_j[2] = {0.0, 0.0};
  double ke0[2], supply_min_a = 1e9;
  for (int k = 0; k < 2; ++k)
    ke0[k] = ax[k].plant().dq().kinetic_energy_j(ax[k].rotor_frame_state().head<4>());
  for (int n = 0; n < 4000; ++n) {  // 0.2 s
    double i_inv[2];
    for (int k = 0; k < 2; ++k) {
      const Eigen::Vector2d i0 = mcsim::PmsmRotorFrame::i_alpha_beta_a(ax[k].rotor_frame_state());
      const double cu0 = ax[k].plant().dq().copper_loss_w(ax[k].rotor_frame_state().head<4>());
      ASSERT_EQ(ax[k].advance(duties_for(ax[k], 0.0, vq[k]), true), Status::kOk);
      const Eigen::Vector2d i1 = mcsim::PmsmRotorFrame::i_alpha_beta_a(ax[k].rotor_frame_state());
      const double cu1 = ax[k].plant().dq().copper_loss_w(ax[k].rotor_frame_state().head<4>());
      const double p_w = 0.75 * ax[k].v_alpha_beta_applied().dot(i0 + i1);
      motor_in_j[k] += p_w * T;
      copper_j[k] += 0.5 * (cu0 + cu1) * T;
      i_inv[k] = p_w / ax[k].vbus_v();
    }
    ASSERT_EQ(link.advance_loads(T, 4, i_inv, 2, 0.0), Status::kOk);
    supply_min_a = std::min(supply_min_a, link.source_avg_a());
    for (auto& a : ax) a.set_vbus_v(link.v());
  }
  const auto& e = link.energy();
  // Axis 0 fed the link, axis 1 drew from it, and the supply delivered
  // less than axis 1 took: the difference came from axis 0's braking.
  EXPECT_LT(link.load_j(0), -1.0);
  EXPECT_GT(link.load_j(1), 1.0);
  EXPECT_LT(e.source_j, link.load_j(1) - 0.9 * std::fabs(link.load_j(0)));
  EXPECT_GE(supply_min_a, 0.0);  // a one-way supply
  // The link's balance (closed form: rounding, 1e-9 of the flows).
  EXPECT_NEAR(e.source_j,
              e.source_r_j + e.brake_j + link.load_j(0) + link.load_j(1) + link.cap_delta_j(),
              1e-9 * link.load_j(1));
  // The link's view of each axis equals the motor's: it drew P_k / v0 at
  // the period's voltage v(t), which moves by millivolts per period:
  // 1e-3 relative.
  for (int k = 0; k < 2; ++k) {
    EXPECT_NEAR(link.load_j(k), motor_in_j[k], 1e-3 * std::fabs(motor_in_j[k])) << "axis " << k;
    // And each motor's input equals its kinetic, magnetic and copper
    // energies (B = 0, no load): trapezoid of the copper loss per period
    // ~1e-4 relative; bound 1e-2 of the input.
    const auto xs = ax[k].rotor_frame_state().head<4>();
    const double stored =
        ax[k].plant().dq().kinetic_energy_j(xs) - ke0[k] + ax[k].plant().dq().magnetic_energy_j(xs);
    EXPECT_NEAR(motor_in_j[k], stored + copper_j[k], 1e-2 * std::fabs(motor_in_j[k]))
        << "axis " << k;
  }
}

}  // namespace
