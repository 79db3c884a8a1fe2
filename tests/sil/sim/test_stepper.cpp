// Two-phase PM stepper of paper 001, eq. (1), with the phase-b back-EMF sign
// re-derived (see stepper_2ph.hpp).
#include <cmath>

#include <Eigen/Core>
#include <gtest/gtest.h>

#include "mcsim/integrator.hpp"
#include "mcsim/load_torque.hpp"
#include "mcsim/stepper_2ph.hpp"
#include "sim_test_util.hpp"

namespace {

using mcsim::Status;
using mcsim::Stepper2Ph;
using mcsim::Stepper2PhParams;
using mcsim_test::kPi;

TEST(SimStepper, TorqueVersusAngleFollowsEquationOne) {
  Stepper2PhParams p;  // paper values
  p.B_nms_rad = 0.0;
  Stepper2Ph m;
  ASSERT_EQ(m.configure(p), Status::kOk);
  const double ia = 1.3;
  const double ib = -0.4;
  for (int k = 0; k <= 64; ++k) {
    const double th = (2.0 * kPi / 50.0) * k / 64.0;  // one tooth pitch
    const Stepper2Ph::State x(ia, ib, 0.0, th);
    const Stepper2Ph::State dx = m.deriv(0.0, x, Stepper2Ph::Input::Zero());
    const double expected =
        -p.Km_nm_a * ia * std::sin(50.0 * th) + p.Km_nm_a * ib * std::cos(50.0 * th);
    // J dw/dt is the torque (no friction, no load, standstill); 1e-12 N m is
    // round-off on a torque of ~0.2 N m.
    EXPECT_NEAR(dx(Stepper2Ph::kOmegaM) * p.J_kgm2, expected, 1e-12) << "k=" << k;
    EXPECT_NEAR(m.torque_nm(x), expected, 1e-15);
  }
  // Sign convention: phase A alone pulls the rotor back to N_r th = 0
  // (restoring torque for a small positive angle), phase B alone to
  // N_r th = pi/2: a full step is 2 pi / (4 N_r) = 1.8 degrees.
  EXPECT_LT(m.torque_nm(Stepper2Ph::State(1.0, 0.0, 0.0, 0.001)), 0.0);
  EXPECT_GT(m.torque_nm(Stepper2Ph::State(1.0, 0.0, 0.0, -0.001)), 0.0);
  const double step = kPi / (2.0 * 50.0);
  EXPECT_LT(m.torque_nm(Stepper2Ph::State(0.0, 1.0, 0.0, step + 0.001)), 0.0);
  EXPECT_GT(m.torque_nm(Stepper2Ph::State(0.0, 1.0, 0.0, step - 0.001)), 0.0);
}

// The model exactly as printed in the paper (+K_m w cos in phase b), to show
// that the energy test below catches that sign.
struct PaperAsPrinted {
  using State = Stepper2Ph::State;
  using Input = Stepper2Ph::Input;
  Stepper2Ph base;
  State deriv(double t_s, const State& x, const Input& u) const {
    State dx = base.deriv(t_s, x, u);
    const Stepper2PhParams& p = base.params();
    const double c = std::cos(p.rotor_teeth * x(3));
    dx(1) += 2.0 * p.Km_nm_a * x(2) * c / p.L_h;  // flip -K_m w cos -> +K_m w cos
    return dx;
  }
  const Stepper2PhParams& params() const { return base.params(); }
  double input_power_w(const State& x, const Input& u) const { return base.input_power_w(x, u); }
  double copper_loss_w(const State& x) const { return base.copper_loss_w(x); }
  double load_nm(double t_s, const State& x) const { return base.load_nm(t_s, x); }
  double magnetic_energy_j(const State& x) const { return base.magnetic_energy_j(x); }
  double kinetic_energy_j(const State& x) const { return base.kinetic_energy_j(x); }
};

// Microstepping drive: rotating voltage vector, 4 rev/s electrical.
Stepper2Ph::Input microstep_volts(double t_s) {
  const double a = 2.0 * kPi * 4.0 * t_s;
  return Stepper2Ph::Input(30.0 * std::cos(a), 30.0 * std::sin(a));
}

template <class Plant>
double relative_energy_residual(const Plant& plant) {
  mcsim_test::EnergyAudit<Plant> audit;
  audit.plant = &plant;
  typename mcsim_test::EnergyAudit<Plant>::State xa = mcsim_test::EnergyAudit<Plant>::State::Zero();
  const auto xa0 = xa;
  const double period_s = 50.0e-6;
  for (int k = 0; k < 10000; ++k) {  // 0.5 s
    const double t_s = k * period_s;
    EXPECT_EQ(mcsim::advance_zoh(audit, microstep_volts(t_s), t_s, period_s, 2, &xa), Status::kOk);
  }
  EXPECT_GT(std::fabs(xa(2)), 0.5);  // the rotor follows the field
  return std::fabs(audit.residual_j(xa0, xa)) / xa(4);
}

TEST(SimStepper, EnergyBalanceHoldsAndCatchesThePrintedSign) {
  Stepper2PhParams p;
  p.load = mcsim::load_constant(0.05);
  Stepper2Ph m;
  ASSERT_EQ(m.configure(p), Status::kOk);
  // Residual/input energy: RK4 truncation only (h = 25 us vs L/R = 2.1 ms),
  // observed ~1e-12; 1e-7 bound.
  EXPECT_LT(relative_energy_residual(m), 1e-7);

  PaperAsPrinted typo;
  ASSERT_EQ(typo.base.configure(p), Status::kOk);
  // The printed sign makes phase b's back-EMF do work the torque does not
  // account for. At this slow microstep speed (back-EMF ~0.1 V against 30 V)
  // the residual is still ~5e-4 of the input, over 1000 times the bound
  // above: the test tells the two signs apart.
  EXPECT_GT(relative_energy_residual(typo), 1e-4);
}

TEST(SimStepper, HoldsPositionAgainstLoadAtClosedFormAngle) {
  // Phase A at constant voltage: at rest i_a = v_a / R and the rotor settles
  // where -K_m i_a sin(N_r th) = tau_load, i.e. th = -asin(tau/(K_m i_a)) / N_r.
  Stepper2PhParams p;
  p.load = mcsim::load_constant(0.2);  // the paper's load
  Stepper2Ph m;
  ASSERT_EQ(m.configure(p), Status::kOk);
  // 3 A: holding torque 0.40 N m, twice the load, so the undamped swing from
  // th = 0 does not reach the unstable point (2 A would let the rotor slip a
  // tooth and run away under the load).
  const double i_a = 3.0;
  const Stepper2Ph::Input u(p.R_ohm * i_a, 0.0);
  Stepper2Ph::State x(i_a, 0.0, 0.0, 0.0);  // phase current already settled
  const double period_s = 1.0e-4;
  for (int k = 0; k < 80000; ++k) {  // 8 s; slowest (mechanical) mode tau ~0.36 s
    ASSERT_EQ(mcsim::advance_zoh(m, u, k * period_s, period_s, 2, &x), Status::kOk);
  }
  const double th_eq = -std::asin(0.2 / (p.Km_nm_a * i_a)) / 50.0;
  // ~22 time constants of the slowest mode (damping B + K_m^2/R over 2J):
  // the transient is below 1e-9 of the 10 mrad initial error; 1e-7 rad bound.
  EXPECT_NEAR(x(3), th_eq, 1e-7);
  EXPECT_NEAR(x(0), i_a, 1e-6);  // 1e-6 A: back-EMF gone at rest
  EXPECT_NEAR(x(1), 0.0, 1e-6);
}

TEST(SimStepper, InvalidParametersKeepOldOnes) {
  Stepper2Ph m;
  Stepper2PhParams p;
  p.rotor_teeth = 0;
  EXPECT_EQ(m.configure(p), Status::kBadTeeth);
  p = Stepper2PhParams{};
  p.Km_nm_a = 0.0;
  EXPECT_EQ(m.configure(p), Status::kNonPositiveTorqueConstant);
  p = Stepper2PhParams{};
  p.L_h = 0.0;
  EXPECT_EQ(m.configure(p), Status::kNonPositiveInductance);
  p = Stepper2PhParams{};
  p.R_ohm = INFINITY;
  EXPECT_EQ(m.configure(p), Status::kNotFinite);
  EXPECT_EQ(m.params().rotor_teeth, 50);
  EXPECT_EQ(m.params().Km_nm_a, 0.1349);
}

}  // namespace
