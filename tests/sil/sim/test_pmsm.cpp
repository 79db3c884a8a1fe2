// PMSM plants in dq and alpha-beta: parameter validation, load models, energy
// balance, frame equivalence and the closed-form steady state.
#include <cmath>

#include <Eigen/Core>
#include <gtest/gtest.h>

#include "mcsim/frames.hpp"
#include "mcsim/integrator.hpp"
#include "mcsim/load_torque.hpp"
#include "mcsim/pmsm_ab.hpp"
#include "mcsim/pmsm_dq.hpp"
#include "sim_test_util.hpp"

namespace {

using mcsim::PmsmAb;
using mcsim::PmsmDq;
using mcsim::PmsmParams;
using mcsim::Status;
using mcsim_test::kPi;

// A small salient drone/servo-class machine: Ld != Lq so the reluctance
// torque and the angle-dependent alpha-beta inductance are exercised.
PmsmParams salient_machine() {
  PmsmParams p;
  p.R_ohm = 0.2;
  p.Ld_h = 2.0e-4;
  p.Lq_h = 3.5e-4;
  p.flux_wb = 0.015;
  p.pole_pairs = 4;
  p.J_kgm2 = 2.0e-5;
  p.B_nms_rad = 1.0e-5;
  return p;
}

// ------------------------------------------------------------- configuration

TEST(SimPmsmConfig, InvalidParametersGiveSpecificCodesAndKeepOldOnes) {
  PmsmDq m;
  ASSERT_EQ(m.configure(salient_machine()), Status::kOk);
  PmsmParams bad = salient_machine();
  bad.R_ohm = 0.0;
  EXPECT_EQ(m.configure(bad), Status::kNonPositiveResistance);
  bad = salient_machine();
  bad.Lq_h = -1e-4;
  EXPECT_EQ(m.configure(bad), Status::kNonPositiveInductance);
  bad = salient_machine();
  bad.flux_wb = -0.1;
  EXPECT_EQ(m.configure(bad), Status::kNegativeFlux);
  bad = salient_machine();
  bad.pole_pairs = 0;
  EXPECT_EQ(m.configure(bad), Status::kBadPolePairs);
  bad = salient_machine();
  bad.J_kgm2 = 0.0;
  EXPECT_EQ(m.configure(bad), Status::kNonPositiveInertia);
  bad = salient_machine();
  bad.B_nms_rad = -1e-6;
  EXPECT_EQ(m.configure(bad), Status::kNegativeFriction);
  bad = salient_machine();
  bad.Ld_h = NAN;
  EXPECT_EQ(m.configure(bad), Status::kNotFinite);
  bad = salient_machine();
  bad.load.kind = mcsim::LoadKind::kFunction;  // no function given
  EXPECT_EQ(m.configure(bad), Status::kBadLoad);
  // Exact: the stored parameters are the last valid ones.
  EXPECT_EQ(m.params().R_ohm, 0.2);
  EXPECT_EQ(m.params().Lq_h, 3.5e-4);
  EXPECT_EQ(m.params().pole_pairs, 4);

  PmsmAb a;
  EXPECT_EQ(a.configure(bad), Status::kBadLoad);
  EXPECT_EQ(a.params().R_ohm, PmsmParams{}.R_ohm);
}

// --------------------------------------------------------------- load models

double quadratic_load(double t_s, double theta_m_rad, double omega_m_rad_s, const void* ctx) {
  const double k = *static_cast<const double*>(ctx);
  return k * (t_s + theta_m_rad + omega_m_rad_s);
}

TEST(SimLoad, KindsEvaluateAsDocumented) {
  // All exact or 1e-15-relative comparisons: each value is one or two
  // floating-point operations on exactly representable inputs.
  const mcsim::LoadTorque c = mcsim::load_constant(0.3);
  EXPECT_EQ(c.eval_nm(5.0, 1.0, -3.0), 0.3);

  const mcsim::LoadTorque s = mcsim::load_step(0.1, 0.5, 0.4);
  EXPECT_EQ(s.validate(), Status::kOk);
  EXPECT_EQ(s.eval_nm(0.499, 0.0, 0.0), 0.1);
  EXPECT_DOUBLE_EQ(s.eval_nm(0.5, 0.0, 0.0), 0.4);

  mcsim::LoadTorque a;
  a.kind = mcsim::LoadKind::kAngleSpeed;
  a.tau0_nm = 0.1;
  a.k_omega_nms_rad = 0.01;
  a.k_omega2_nms2_rad2 = 0.001;
  a.ripple_nm = 0.05;
  a.ripple_per_rev = 6.0;
  const double th = 0.2;
  const double w = -10.0;
  EXPECT_NEAR(a.eval_nm(0.0, th, w), 0.1 + 0.01 * w - 0.001 * w * w + 0.05 * std::sin(6.0 * th),
              1e-15);

  double k = 2.0;
  mcsim::LoadTorque f;
  f.kind = mcsim::LoadKind::kFunction;
  f.fn = &quadratic_load;
  f.fn_ctx = &k;
  EXPECT_EQ(f.validate(), Status::kOk);
  EXPECT_EQ(f.eval_nm(1.0, 2.0, 3.0), 12.0);
}

TEST(SimLoad, CoulombOpposesMotionAndIsLinearNearZero) {
  mcsim::LoadTorque l = mcsim::load_constant(0.0);
  l.coulomb_nm = 0.02;
  l.coulomb_band_rad_s = 0.1;
  EXPECT_EQ(l.eval_nm(0.0, 0.0, 5.0), 0.02);    // brakes forward motion
  EXPECT_EQ(l.eval_nm(0.0, 0.0, -5.0), -0.02);  // brakes reverse motion
  EXPECT_EQ(l.eval_nm(0.0, 0.0, 0.0), 0.0);
  EXPECT_NEAR(l.eval_nm(0.0, 0.0, 0.05), 0.01, 1e-15);  // half the band
  l.coulomb_nm = -0.01;
  EXPECT_EQ(l.validate(), Status::kNegativeFriction);
  l.coulomb_nm = 0.01;
  l.coulomb_band_rad_s = 0.0;
  EXPECT_EQ(l.validate(), Status::kBadLoad);
}

TEST(SimPmsmDq, LoadBrakesPositiveSpeed) {
  PmsmParams p = salient_machine();
  p.B_nms_rad = 0.0;
  p.load = mcsim::load_constant(0.1);
  PmsmDq m;
  ASSERT_EQ(m.configure(p), Status::kOk);
  const PmsmDq::State x(0.0, 0.0, 10.0, 0.0);
  const PmsmDq::State dx = m.deriv(0.0, x, PmsmDq::Input::Zero());
  // Zero current: no torque, only the load: dw/dt = -0.1 / J exactly
  // (up to one rounding).
  EXPECT_NEAR(dx(PmsmDq::kOmegaM), -0.1 / p.J_kgm2, 1e-9);
  EXPECT_EQ(dx(PmsmDq::kThetaM), 10.0);
}

// ------------------------------------------------------------ energy balance

// Piecewise-constant (per control period) voltages that vary strongly.
Eigen::Vector2d vdq_profile(double t_s) {
  return Eigen::Vector2d(-1.0 + 0.8 * std::sin(2.0 * kPi * 40.0 * t_s),
                         4.0 + 2.0 * std::sin(2.0 * kPi * 13.0 * t_s));
}

mcsim::LoadTorque varied_load() {
  mcsim::LoadTorque l;
  l.kind = mcsim::LoadKind::kAngleSpeed;
  l.tau0_nm = 0.01;
  l.k_omega_nms_rad = 1.0e-5;
  l.ripple_nm = 0.005;
  l.ripple_per_rev = 6.0;
  l.coulomb_nm = 0.003;
  l.coulomb_band_rad_s = 0.5;
  return l;
}

template <class Plant, class VoltageFn>
void check_energy_balance(const Plant& plant, VoltageFn volts) {
  mcsim_test::EnergyAudit<Plant> audit;
  audit.plant = &plant;
  typename mcsim_test::EnergyAudit<Plant>::State xa = mcsim_test::EnergyAudit<Plant>::State::Zero();
  const auto xa0 = xa;
  const double period_s = 50.0e-6;
  double e_in_abs_j = 0.0;
  for (int k = 0; k < 4000; ++k) {  // 0.2 s
    const double t_s = k * period_s;
    const typename Plant::Input u = volts(t_s, xa);
    const auto before = xa;
    ASSERT_EQ(mcsim::advance_zoh(audit, u, t_s, period_s, 4, &xa), Status::kOk);
    e_in_abs_j += std::fabs(xa(4) - before(4));
  }
  // The run must actually move energy around (else the test proves nothing).
  ASSERT_GT(e_in_abs_j, 0.5);
  ASSERT_GT(plant.kinetic_energy_j(xa.template head<4>()), 1e-3);
  ASSERT_GT(xa(5), 0.05);  // copper loss
  ASSERT_GT(xa(7), 1e-3);  // load work
  // Relative residual 1e-7 of the input energy: the balance is exact for the
  // true solution; what remains is RK4 truncation (h = 12.5 us against time
  // constants >= 0.7 ms; observed 2e-11 in dq, 1e-9 in alpha-beta). A missing 3/2 in the
  // torque, a wrong back-EMF sign or a wrong inductance derivative leaves a
  // residual of order 10% or more.
  EXPECT_LT(std::fabs(audit.residual_j(xa0, xa)), 1e-7 * e_in_abs_j);
}

TEST(SimPmsmDq, EnergyBalanceOverVaryingVoltages) {
  PmsmParams p = salient_machine();
  p.load = varied_load();
  PmsmDq m;
  ASSERT_EQ(m.configure(p), Status::kOk);
  check_energy_balance(m, [](double t_s, const Eigen::Matrix<double, 8, 1>& /*xa*/) {
    return PmsmDq::Input(vdq_profile(t_s));
  });
}

TEST(SimPmsmAb, EnergyBalanceOverVaryingVoltages) {
  PmsmParams p = salient_machine();
  p.load = varied_load();
  PmsmAb m;
  ASSERT_EQ(m.configure(p), Status::kOk);
  const double pp = static_cast<double>(p.pole_pairs);
  // Voltages rotated with the rotor angle at the start of each period.
  check_energy_balance(m, [pp](double t_s, const Eigen::Matrix<double, 8, 1>& xa) {
    return PmsmAb::Input(mcsim::inverse_park(vdq_profile(t_s), pp * xa(3)));
  });
}

// ----------------------------------------------------------- dq == alpha-beta

// Both wrappers apply the same continuous dq voltage profile; the alpha-beta
// one rotates it with its own (true) rotor angle, so both integrate the same
// ODE in two coordinate systems.
struct DqDriven {
  using State = PmsmDq::State;
  using Input = PmsmDq::Input;
  const PmsmDq* m = nullptr;
  State deriv(double t_s, const State& x, const Input& /*u*/) const {
    return m->deriv(t_s, x, Input(vdq_profile(t_s)));
  }
};

struct AbDriven {
  using State = PmsmAb::State;
  using Input = PmsmAb::Input;
  const PmsmAb* m = nullptr;
  State deriv(double t_s, const State& x, const Input& /*u*/) const {
    const double th_e = static_cast<double>(m->params().pole_pairs) * x(3);
    return m->deriv(t_s, x, Input(mcsim::inverse_park(vdq_profile(t_s), th_e)));
  }
};

TEST(SimPmsmFrames, DqAndAlphaBetaModelsAgree) {
  PmsmParams p = salient_machine();
  p.load = varied_load();
  PmsmDq dq;
  PmsmAb ab;
  ASSERT_EQ(dq.configure(p), Status::kOk);
  ASSERT_EQ(ab.configure(p), Status::kOk);
  DqDriven fdq;
  fdq.m = &dq;
  AbDriven fab;
  fab.m = &ab;
  PmsmDq::State xdq(0.5, -0.3, 0.0, 0.1);
  const double th_e0 = 4.0 * 0.1;
  const Eigen::Vector2d iab0 = mcsim::inverse_park(Eigen::Vector2d(0.5, -0.3), th_e0);
  PmsmAb::State xab(iab0(0), iab0(1), 0.0, 0.1);
  const Eigen::Vector2d u0 = Eigen::Vector2d::Zero();
  const double period_s = 50.0e-6;
  double max_di_a = 0.0;
  double max_dw_rad_s = 0.0;
  double max_dth_rad = 0.0;
  for (int k = 0; k < 4000; ++k) {  // 0.2 s, speed up to ~70 rad/s mech
    const double t_s = k * period_s;
    ASSERT_EQ(mcsim::advance_zoh(fdq, u0, t_s, period_s, 4, &xdq), Status::kOk);
    ASSERT_EQ(mcsim::advance_zoh(fab, u0, t_s, period_s, 4, &xab), Status::kOk);
    const Eigen::Vector2d idq_from_ab = mcsim::park(Eigen::Vector2d(xab(0), xab(1)), 4.0 * xab(3));
    max_di_a = std::fmax(max_di_a, (idq_from_ab - xdq.head<2>()).cwiseAbs().maxCoeff());
    max_dw_rad_s = std::fmax(max_dw_rad_s, std::fabs(xab(2) - xdq(2)));
    max_dth_rad = std::fmax(max_dth_rad, std::fabs(xab(3) - xdq(3)));
  }
  ASSERT_GT(xdq(2), 20.0);  // the machine really spun up
  // Same ODE, two coordinates: they differ only by RK4 truncation, which is
  // larger in alpha-beta (sinusoidal states, w_e h <= 0.003): observed
  // 5e-10 A, 1.4e-9 rad/s, 1.2e-11 rad; bounds 1e-6 A / 1e-6 rad/s / 1e-8 rad.
  // A sign error in either frame's cross-coupling gives errors of amperes.
  EXPECT_LT(max_di_a, 1e-6);
  EXPECT_LT(max_dw_rad_s, 1e-6);
  EXPECT_LT(max_dth_rad, 1e-8);
}

TEST(SimPmsmFrames, TorqueAndEnergyAgreeAtAnyAngle) {
  PmsmDq dq;
  PmsmAb ab;
  ASSERT_EQ(dq.configure(salient_machine()), Status::kOk);
  ASSERT_EQ(ab.configure(salient_machine()), Status::kOk);
  for (int k = 0; k < 24; ++k) {
    const double th_m = 0.37 * k;
    const PmsmDq::State xdq(-3.0 + 0.2 * k, 5.0 - 0.4 * k, 12.0, th_m);
    const Eigen::Vector2d iab = mcsim::inverse_park(xdq.head<2>(), 4.0 * th_m);
    const PmsmAb::State xab(iab(0), iab(1), 12.0, th_m);
    // 1e-12 relative: identical physics, different round-off paths.
    EXPECT_NEAR(ab.torque_nm(xab), dq.torque_nm(xdq), 1e-12 * 1.0);
    EXPECT_NEAR(ab.magnetic_energy_j(xab), dq.magnetic_energy_j(xdq), 1e-15);
  }
}

// -------------------------------------------------------- closed-form steady

TEST(SimPmsmDq, SteadyStateMatchesClosedForm) {
  // Pick the operating point, solve the steady-state equations for the
  // voltages, apply them from standstill and check the plant settles there:
  //   0 = v_d - R i_d + w_e Lq i_q
  //   0 = v_q - R i_q - w_e (Ld i_d + flux)
  //   0 = 3/2 p i_q (flux + (Ld - Lq) i_d) - B w_m - tau_load
  PmsmParams p = salient_machine();
  p.B_nms_rad = 2.0e-4;
  p.load = mcsim::load_constant(0.05);
  PmsmDq m;
  ASSERT_EQ(m.configure(p), Status::kOk);
  const double w_m = 150.0;
  const double i_d = -2.0;
  const double pp = static_cast<double>(p.pole_pairs);
  const double w_e = pp * w_m;
  const double i_q =
      (p.B_nms_rad * w_m + 0.05) / (1.5 * pp * (p.flux_wb + (p.Ld_h - p.Lq_h) * i_d));
  const PmsmDq::Input u(p.R_ohm * i_d - w_e * p.Lq_h * i_q,
                        p.R_ohm * i_q + w_e * (p.Ld_h * i_d + p.flux_wb));
  // The solved point is an equilibrium of the model (residual at round-off).
  const PmsmDq::State xs(i_d, i_q, w_m, 0.0);
  const PmsmDq::State dxs = m.deriv(0.0, xs, u);
  EXPECT_NEAR(dxs(0), 0.0, 1e-9);  // A/s; terms are ~1e4 A/s
  EXPECT_NEAR(dxs(1), 0.0, 1e-9);
  EXPECT_NEAR(dxs(2), 0.0, 1e-9);  // rad/s^2; terms ~1e4

  PmsmDq::State x = PmsmDq::State::Zero();
  const double period_s = 50.0e-6;
  for (int k = 0; k < 10000; ++k) {  // 0.5 s, > 100 electrical/mechanical time constants
    ASSERT_EQ(mcsim::advance_zoh(m, u, k * period_s, period_s, 4, &x), Status::kOk);
  }
  // After > 100 time constants the transient is below 1e-40 of its size;
  // what is left is round-off (observed ~1e-13): 1e-7 A and 1e-6 rad/s bounds.
  EXPECT_NEAR(x(PmsmDq::kId), i_d, 1e-7);
  EXPECT_NEAR(x(PmsmDq::kIq), i_q, 1e-7);
  EXPECT_NEAR(x(PmsmDq::kOmegaM), w_m, 1e-6);
}

}  // namespace
