// The power stages (mcsim::PmsmPowerStage, mcsim::StepperPowerStage): the
// bridge, its diodes and a broken phase as plant, tested on their own
// against closed-form solutions (no HAL, no firmware).
//
// Common set-up: a rotor so heavy (J = 1e3 kg m^2) that it stays at
// standstill within rounding over the test, so there is no back-EMF and the
// electrical circuits are linear RL circuits with a closed-form solution.
// Tolerance while a current flows: 1e-9 A against the closed form (RK4 on a
// linear ODE with h = T/4 = 12.5 us and tau = L/R = 1.69 ms has a local
// error ~ (h/tau)^5 / 120 ~ 2e-13 relative per step); the period in which
// the current reaches zero is skipped (there the diode cut-off is resolved
// to one sub-step, not to the exact instant).
#include <cmath>

#include <Eigen/Core>
#include <gtest/gtest.h>

#include "mcsim/pmsm_power_stage.hpp"
#include "mcsim/stepper_power_stage.hpp"

namespace {

constexpr double kT = 50.0e-6;  // 20 kHz

mcsim::PmsmPowerStageParams heavy_pmsm() {
  mcsim::PmsmPowerStageParams p;
  p.motor.R_ohm = 0.675;  // paper 002's test motor
  p.motor.Ld_h = 1.14e-3;
  p.motor.Lq_h = 1.14e-3;
  p.motor.flux_wb = 0.11;
  p.motor.pole_pairs = 4;
  p.motor.J_kgm2 = 1.0e3;
  p.inverter.t_pwm_s = kT;
  p.vbus_v = 24.0;
  p.substeps = 4;
  return p;
}

TEST(SimPowerStage, PmsmDiodesFreewheelToZeroAndBlock) {
  // Duties (0.5 + d, 0.5 - d/2, 0.5 - d/2), d = 0.1, at theta = 0: phase a
  // carries i0 = d vbus / R, b and c -i0/2 each (pure d-axis current: no
  // torque). Bridge off: a's lower diode (pole at 0 V) and the upper diodes
  // of b and c (vbus) conduct: v_a = -2/3 vbus, so
  //   i_a(t) = (i0 + 2 vbus / 3R) exp(-t R/L) - 2 vbus / 3R,
  // zero at t0 = (L/R) ln(1 + 3 R i0 / (2 vbus)) = 0.16 ms, then exactly 0.
  mcsim::PmsmPowerStage st;
  const mcsim::PmsmPowerStageParams p = heavy_pmsm();
  ASSERT_EQ(st.configure(p), mcsim::Status::kOk);
  const double R = p.motor.R_ohm, L = p.motor.Ld_h, vbus = p.vbus_v;
  const Eigen::Vector3d duty(0.6, 0.45, 0.45);
  for (int k = 0; k < 400; ++k) ASSERT_EQ(st.advance(duty, true), mcsim::Status::kOk);
  const double i0 = st.phase_currents_true_a()(0);
  // 400 periods = 11.8 tau: exp(-11.8) = 7.5e-6 of the step left.
  EXPECT_NEAR(i0, 0.1 * vbus / R, 1e-5 * 3.556);
  EXPECT_FALSE(st.open_circuit());
  const double tau = L / R, i_inf = 2.0 * vbus / (3.0 * R);
  const double t0 = tau * std::log(1.0 + i0 / i_inf);
  for (int k = 1; k <= 20; ++k) {
    ASSERT_EQ(st.advance(duty, false), mcsim::Status::kOk);
    const Eigen::Vector3d i = st.phase_currents_true_a();
    const double t = k * kT;
    if (std::abs(t - t0) < kT) continue;
    const double want = (t < t0) ? (i0 + i_inf) * std::exp(-t / tau) - i_inf : 0.0;
    EXPECT_NEAR(i(0), want, 1e-9) << "period " << k;
    EXPECT_NEAR(i(1), -0.5 * i(0), 1e-12) << "b and c share the return";
  }
  EXPECT_TRUE(st.open_circuit());
  EXPECT_EQ(st.phase_currents_true_a().norm(), 0.0) << "the diodes block the reverse current";
  EXPECT_EQ(st.duties_applied(), Eigen::Vector3d::Constant(0.5));
}

TEST(SimPowerStage, PmsmRectifiesOnlyWhenTheBackEmfExceedsTheBus) {
  // Bridge off, no current, spinning rotor. The line-to-line back-EMF peak
  // is sqrt(3) p omega flux: at 20 rad/s 15.2 V < 24 V (the diodes stay
  // blocked, the current stays exactly 0), at 40 rad/s 30.5 V > 24 V (the
  // rectifier conducts and brakes the rotor: power flows into the bus).
  for (const double w0 : {20.0, 40.0}) {
    mcsim::PmsmPowerStageParams p = heavy_pmsm();
    p.motor.J_kgm2 = 1.0e-3;
    p.omega_m0_rad_s = w0;
    mcsim::PmsmPowerStage st;
    ASSERT_EQ(st.configure(p), mcsim::Status::kOk);
    double max_i = 0.0, min_torque = 0.0;
    for (int k = 0; k < 200; ++k) {
      ASSERT_EQ(st.advance(Eigen::Vector3d::Constant(0.5), false), mcsim::Status::kOk);
      max_i = std::max(max_i, st.phase_currents_true_a().cwiseAbs().maxCoeff());
      min_torque = std::min(min_torque, st.torque_nm());
    }
    if (w0 < 30.0) {
      EXPECT_EQ(max_i, 0.0) << "below the bus: open circuit";
      EXPECT_NEAR(st.rotor_frame_state()(2), w0, 1e-12) << "no torque, no friction";
    } else {
      EXPECT_GT(max_i, 0.5) << "above the bus: the rectifier conducts";
      EXPECT_LT(min_torque, -0.05) << "and brakes";
      EXPECT_LT(st.rotor_frame_state()(2), w0);
    }
  }
}

TEST(SimPowerStage, PmsmOpenPhaseSeriesCircuit) {
  // Phase a broken: b and c form one series circuit 2R, 2L driven by the
  // difference of their pole voltages, (0.6 - 0.4) vbus, so i -> 0.2 vbus /
  // 2R. Bridge off: the low diode of b and the high diode of c give
  // v_bc = -vbus: i(t) = (i0 + vbus/2R) exp(-t R/L) - vbus/2R, zero at
  // t0 = (L/R) ln(1 + 2 R i0 / vbus), exactly 0 after it.
  mcsim::PmsmPowerStageParams p = heavy_pmsm();
  p.theta_m0_rad = 3.14159265358979 / 8.0;
  mcsim::PmsmPowerStage st;
  ASSERT_EQ(st.configure(p), mcsim::Status::kOk);
  ASSERT_EQ(st.set_open_phase(0), mcsim::Status::kOk);
  const double R = p.motor.R_ohm, L = p.motor.Ld_h, vbus = p.vbus_v;
  const Eigen::Vector3d duty(0.5, 0.6, 0.4);
  for (int k = 0; k < 400; ++k) {
    ASSERT_EQ(st.advance(duty, true), mcsim::Status::kOk);
    const Eigen::Vector3d i = st.phase_currents_true_a();
    ASSERT_EQ(i(0), 0.0);
    ASSERT_EQ(i(1), -i(2));
  }
  const double i0 = st.phase_currents_true_a()(1);
  EXPECT_NEAR(i0, 0.2 * vbus / (2.0 * R), 5e-5 * 3.556);
  const double tau = L / R, i_inf = vbus / (2.0 * R);
  const double t0 = tau * std::log(1.0 + i0 / i_inf);
  for (int k = 1; k <= 40; ++k) {
    ASSERT_EQ(st.advance(duty, false), mcsim::Status::kOk);
    const double t = k * kT;
    if (std::abs(t - t0) < kT) continue;
    const double want = (t < t0) ? (i0 + i_inf) * std::exp(-t / tau) - i_inf : 0.0;
    EXPECT_NEAR(st.phase_currents_true_a()(1), want, 1e-9) << "period " << k;
  }
  EXPECT_EQ(st.phase_currents_true_a()(1), 0.0);
  EXPECT_EQ(std::hypot(st.rotor_frame_state()(0), st.rotor_frame_state()(1)), 0.0)
      << "the rotor-frame state agrees";
}

TEST(SimPowerStage, PmsmRejectsBadConfigurationAndKeepsState) {
  mcsim::PmsmPowerStage st;
  mcsim::PmsmPowerStageParams p = heavy_pmsm();
  ASSERT_EQ(st.configure(p), mcsim::Status::kOk);
  for (int k = 0; k < 10; ++k) ASSERT_EQ(st.advance({0.6, 0.4, 0.5}, true), mcsim::Status::kOk);
  const mcsim::PmsmPowerStage::State x = st.rotor_frame_state();
  mcsim::PmsmPowerStageParams bad = p;
  bad.substeps = 0;
  EXPECT_EQ(st.configure(bad), mcsim::Status::kBadStepCount);
  bad = p;
  bad.vbus_v = -1.0;
  EXPECT_EQ(st.configure(bad), mcsim::Status::kNotFinite);
  bad = p;
  bad.motor.R_ohm = 0.0;
  EXPECT_EQ(st.configure(bad), mcsim::Status::kNonPositiveResistance);
  bad = p;
  bad.inverter.t_pwm_s = 0.0;
  EXPECT_EQ(st.configure(bad), mcsim::Status::kBadPwmPeriod);
  EXPECT_EQ(st.set_open_phase(3), mcsim::Status::kBadPhase);
  EXPECT_EQ(st.set_open_phase(-2), mcsim::Status::kBadPhase);
  EXPECT_EQ(st.open_phase(), -1);
  EXPECT_EQ(st.rotor_frame_state(), x);
  EXPECT_DOUBLE_EQ(st.t_s(), 10 * kT);  // a sum of ten periods: to rounding
}

TEST(SimPowerStage, StepperWindingsFreewheelAgainstTheBus) {
  // Winding a driven to i0 = d vbus / R (d = 0.2), b at zero, heavy rotor at
  // phi = 0 (the current in a makes no torque there: -K_m i_a sin(N_r phi)).
  // Bridges off: L di/dt = -vbus - R i, i(t) = (i0 + vbus/R) exp(-t R/L) -
  // vbus/R, zero at t0 = (L/R) ln(1 + R i0 / vbus) and 0 after; b stays 0.
  mcsim::StepperPowerStageParams p;
  p.motor.R_ohm = 19.5;
  p.motor.L_h = 0.030;
  p.motor.J_kgm2 = 1.0e3;
  p.t_pwm_s = 1.0e-4;
  p.vbus_v = 60.0;
  mcsim::StepperPowerStage st;
  ASSERT_EQ(st.configure(p), mcsim::Status::kOk);
  const double R = p.motor.R_ohm, L = p.motor.L_h, vbus = p.vbus_v, T = p.t_pwm_s;
  const Eigen::Vector2d duty(0.2, 0.0);
  for (int k = 0; k < 200; ++k) ASSERT_EQ(st.advance(duty, true), mcsim::Status::kOk);  // 13 tau
  const double i0 = st.state()(0);
  EXPECT_NEAR(i0, 0.2 * vbus / R, 1e-5 * 0.615);
  EXPECT_EQ(st.state()(1), 0.0);
  const double tau = L / R, i_inf = vbus / R;
  const double t0 = tau * std::log(1.0 + i0 / i_inf);
  for (int k = 1; k <= 20; ++k) {
    ASSERT_EQ(st.advance(duty, false), mcsim::Status::kOk);
    const double t = k * T;
    if (std::abs(t - t0) < T) continue;
    const double want = (t < t0) ? (i0 + i_inf) * std::exp(-t / tau) - i_inf : 0.0;
    EXPECT_NEAR(st.state()(0), want, 1e-9) << "period " << k;
    EXPECT_EQ(st.state()(1), 0.0);
  }
  EXPECT_EQ(st.state()(0), 0.0) << "blocked by the diodes";
  EXPECT_EQ(st.v_applied(), Eigen::Vector2d::Zero()) << "open windings";
  EXPECT_EQ(st.t_s(), 220 * T) << "count times period, exactly";
}

TEST(SimPowerStage, StepperRejectsBadConfiguration) {
  mcsim::StepperPowerStage st;
  mcsim::StepperPowerStageParams p;
  p.t_pwm_s = 0.0;
  EXPECT_EQ(st.configure(p), mcsim::Status::kBadPwmPeriod);
  p.t_pwm_s = 1e-4;
  p.substeps = 0;
  EXPECT_EQ(st.configure(p), mcsim::Status::kBadStepCount);
  p.substeps = 4;
  p.vbus_v = std::nan("");
  EXPECT_EQ(st.configure(p), mcsim::Status::kNotFinite);
  p.vbus_v = 60.0;
  p.motor.L_h = 0.0;
  EXPECT_EQ(st.configure(p), mcsim::Status::kNonPositiveInductance);
}

}  // namespace
