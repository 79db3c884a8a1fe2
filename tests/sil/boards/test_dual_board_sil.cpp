// The two-axis board (hal_host::DualPmsmBoard, issue 34 item 2): two axes
// on one DC link through the boards' HAL, against the plant coupled by hand
// (two mcsim::PmsmPowerStage on one mcsim::DcLink, advanced as
// tests/sil/sim/test_dc_link.cpp does): bit for bit, since the board must
// add no physics of its own; the chopper at the larger of the axes' duties;
// and the refusals of two axes that cannot share a link.
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <Eigen/Core>
#include <gtest/gtest.h>

#include "hal_host/dual_pmsm_board.hpp"
#include "mcsim/dc_link.hpp"
#include "mcsim/pmsm_power_stage.hpp"
#include "mcsim/pmsm_rotor_frame.hpp"

namespace {

using hal_host::DualPmsmBoard;
using hal_host::PmsmBoardConfig;

mcsim::DcLinkParams link_params(double brake_r_ohm) {
  mcsim::DcLinkParams p;
  p.source_v = 24.0;
  p.source_r_ohm = 0.1;
  p.source_sink = false;  // a one-way supply: what one axis brakes must go to the other
  p.c_f = 1.0e-3;
  p.brake_r_ohm = brake_r_ohm;
  return p;
}

PmsmBoardConfig axis_cfg(double omega0, double brake_r_ohm) {
  PmsmBoardConfig c;
  c.motor.R_ohm = 0.1;
  c.motor.Ld_h = c.motor.Lq_h = 1.0e-4;
  c.motor.flux_wb = 0.01;
  c.motor.pole_pairs = 4;
  c.motor.J_kgm2 = 5.0e-3;
  c.vbus_v = 24.0;
  c.dc_link_enabled = true;
  c.dc_link = link_params(brake_r_ohm);
  c.delay_periods = 0;  // the duty acts in the period it is written, as the reference applies it
  c.omega_m0_rad_s = omega0;
  return c;
}

// Duties that put (v_d, v_q) on the windings at the stage's present angle.
Eigen::Vector3d duties_for(const mcsim::PmsmRotorFrame::State& x, double vbus, double vd,
                           double vq) {
  const double c = x(mcsim::PmsmRotorFrame::kCos), s = x(mcsim::PmsmRotorFrame::kSin);
  const double va = c * vd - s * vq, vb = s * vd + c * vq;
  const double s3 = std::sqrt(3.0) / 2.0;
  return {0.5 + va / vbus, 0.5 + (-0.5 * va + s3 * vb) / vbus, 0.5 + (-0.5 * va - s3 * vb) / vbus};
}

TEST(DualPmsmBoard, TwoAxesOnOneLinkEqualThePlantCoupledByHand) {
  // Axis 0 spins at 200 rad/s and is braked (v_q 7.5 V below its back-EMF
  // of 8 V), axis 1 starts at rest and is driven (v_q 3 V); 0.2 s.
  const double omega0[2] = {200.0, 0.0}, vq[2] = {7.5, 3.0};
  DualPmsmBoard board(axis_cfg(omega0[0], 0.0), axis_cfg(omega0[1], 0.0));
  mcsim::PmsmPowerStage ref[2];
  for (int k = 0; k < 2; ++k) {
    const PmsmBoardConfig c = axis_cfg(omega0[k], 0.0);
    mcsim::PmsmPowerStageParams sp;
    sp.motor = c.motor;
    sp.inverter = c.inverter;
    sp.vbus_v = c.vbus_v;
    sp.substeps = c.substeps;
    sp.omega_m0_rad_s = c.omega_m0_rad_s;
    ASSERT_EQ(ref[k].configure(sp), mcsim::Status::kOk);
  }
  mcsim::DcLink link;
  ASSERT_EQ(link.configure(link_params(0.0)), mcsim::Status::kOk);
  const double T = board.period_s();
  for (int k = 0; k < 2; ++k) {
    ASSERT_EQ(mc_hal_pwm3_enable(board.axis(k).hal()->pwm3), 0);
  }
  for (int n = 0; n < 4000; ++n) {
    board.sample();
    double i_inv[2];
    for (int k = 0; k < 2; ++k) {
      const Eigen::Vector3d d =
          duties_for(board.axis(k).rotor_frame_state(), board.axis(k).vbus_v(), 0.0, vq[k]);
      ASSERT_EQ(mc_hal_pwm3_set_duty(board.axis(k).hal()->pwm3, static_cast<float>(d(0)),
                                     static_cast<float>(d(1)), static_cast<float>(d(2))),
                0);
      // The reference applies the duties the board's register holds (float).
      const Eigen::Vector3d df(static_cast<float>(d(0)), static_cast<float>(d(1)),
                               static_cast<float>(d(2)));
      const Eigen::Vector2d i0 = mcsim::PmsmRotorFrame::i_alpha_beta_a(ref[k].rotor_frame_state());
      ASSERT_EQ(ref[k].advance(df, true), mcsim::Status::kOk);
      const Eigen::Vector2d i1 = mcsim::PmsmRotorFrame::i_alpha_beta_a(ref[k].rotor_frame_state());
      i_inv[k] = 0.75 * ref[k].v_alpha_beta_applied().dot(i0 + i1) / ref[k].vbus_v();
    }
    board.advance();
    ASSERT_EQ(link.advance_loads(T, 4, i_inv, 2, 0.0), mcsim::Status::kOk);
    for (auto& r : ref) r.set_vbus_v(link.v());
    // Bit for bit: the board adds no physics (same stage, same link steps).
    ASSERT_EQ(board.link().v(), link.v()) << "period " << n;
    for (int k = 0; k < 2; ++k) {
      ASSERT_EQ(board.axis(k).rotor_frame_state(), ref[k].rotor_frame_state())
          << "axis " << k << " period " << n;
      ASSERT_EQ(board.axis(k).vbus_v(), link.v());
    }
  }
  // What the coupling is for: axis 0 fed the link, axis 1 drew from it, and
  // the one-way supply gave less than axis 1 took (axis 0's braking made up
  // at least 0.9 of its own share: the rest is the supply's and the
  // capacitor's part of the balance). Each axis's dc_link() is the shared one.
  const mcsim::DcLink& l = board.link();
  EXPECT_LT(l.load_j(0), -1.0);
  EXPECT_GT(l.load_j(1), 1.0);
  EXPECT_LT(l.energy().source_j, l.load_j(1) - 0.9 * std::fabs(l.load_j(0)));
  for (int k = 0; k < 2; ++k) {
    EXPECT_EQ(board.axis(k).dc_link(), &board.link());
    // Each axis's account of the energy into its motor equals the link's
    // view of that axis: the link drew P_k / v at the period's start
    // voltage while v moves by millivolts per period: 1e-3 relative.
    EXPECT_NEAR(board.axis(k).motor_in_j(), l.load_j(k), 1e-3 * std::fabs(l.load_j(k)))
        << "axis " << k;
  }
  // The balance (closed form: rounding, 1e-9 of the flows).
  const auto& e = l.energy();
  EXPECT_NEAR(e.source_j, e.source_r_j + e.brake_j + l.load_j(0) + l.load_j(1) + l.cap_delta_j(),
              1e-9 * l.load_j(1));
}

TEST(DualPmsmBoard, TheChopperRunsAtTheLargerOfTheAxesDuties) {
  // Both bridges off (no inverter current); the axes ask 0.2 and 0.6 of
  // the board's one chopper: the link discharges through it at 0.6, bit for
  // bit as a link advanced at 0.6. Then axis 1 stops asking (a fault): 0.2.
  DualPmsmBoard board(axis_cfg(0.0, 2.0), axis_cfg(0.0, 2.0));
  ASSERT_NE(board.axis(0).hal()->brake, nullptr);
  ASSERT_NE(board.axis(1).hal()->brake, nullptr);
  mcsim::DcLink link;
  ASSERT_EQ(link.configure(link_params(2.0)), mcsim::Status::kOk);
  const double zero[2] = {0.0, 0.0};
  const float ask[2][2] = {{0.2f, 0.6f}, {0.2f, 0.0f}};
  for (int phase = 0; phase < 2; ++phase) {
    ASSERT_EQ(mc_hal_brake_set_duty(board.axis(0).hal()->brake, ask[phase][0]), 0);
    ASSERT_EQ(mc_hal_brake_set_duty(board.axis(1).hal()->brake, ask[phase][1]), 0);
    const double want =
        std::max(static_cast<double>(ask[phase][0]), static_cast<double>(ask[phase][1]));
    for (int n = 0; n < 200; ++n) {
      board.sample();
      board.advance();
      ASSERT_EQ(link.advance_loads(board.period_s(), 4, zero, 2, want), mcsim::Status::kOk);
      ASSERT_EQ(board.brake_duty(), want);
      ASSERT_EQ(board.link().v(), link.v()) << "phase " << phase << " period " << n;
    }
  }
  EXPECT_GT(board.link().energy().brake_j, 0.0);
  EXPECT_EQ(board.link().energy().brake_j, link.energy().brake_j);
}

std::string refusal(const PmsmBoardConfig& a, const PmsmBoardConfig& b) {
  try {
    DualPmsmBoard board(a, b);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(DualPmsmBoard, RefusesAxesThatCannotShareOneLinkNamingWhy) {
  PmsmBoardConfig ok = axis_cfg(0.0, 0.0);
  PmsmBoardConfig stiff = ok;
  stiff.dc_link_enabled = false;
  EXPECT_NE(refusal(ok, stiff).find("needs the DC link on both axes"), std::string::npos);
  PmsmBoardConfig other_cap = ok;
  other_cap.dc_link.c_f = 2.0e-3;
  EXPECT_NE(refusal(ok, other_cap).find("DC-link values differ"), std::string::npos);
  PmsmBoardConfig other_pwm = ok;
  other_pwm.inverter.t_pwm_s = 0.5 * ok.inverter.t_pwm_s;
  EXPECT_NE(refusal(ok, other_pwm).find("PWM periods or sub-steps differ"), std::string::npos);
  PmsmBoardConfig bad_motor = ok;
  bad_motor.motor.R_ohm = -1.0;
  EXPECT_EQ(refusal(ok, bad_motor).rfind("axis M1: ", 0), 0u) << refusal(ok, bad_motor);
  EXPECT_EQ(refusal(ok, ok), "");
  DualPmsmBoard board(ok, ok);
  EXPECT_THROW(board.axis(2), std::out_of_range);
  EXPECT_THROW(board.axis(-1), std::out_of_range);
  // A one-axis board cannot share a link it does not have.
  PmsmBoardConfig shared_alone = ok;
  shared_alone.dc_link_enabled = false;
  shared_alone.dc_link_shared = true;
  EXPECT_THROW(hal_host::PmsmBoard b(shared_alone), std::invalid_argument);
}

}  // namespace
