// The normalised PMSM of paper 000, eqs. (1)-(4), against the physical dq
// model: with unit parameters and through the documented general scaling.
#include <cmath>

#include <Eigen/Core>
#include <gtest/gtest.h>

#include "mcsim/integrator.hpp"
#include "mcsim/load_torque.hpp"
#include "mcsim/pmsm_dq.hpp"
#include "mcsim/pmsm_normalised.hpp"

namespace {

using mcsim::PmsmDq;
using mcsim::PmsmNormalised;
using mcsim::PmsmNormalisedParams;
using mcsim::PmsmParams;
using mcsim::Status;

PmsmParams unit_machine(double flux_wb, double tau_load_nm) {
  PmsmParams p;
  p.R_ohm = 1.0;
  p.Ld_h = 1.0;
  p.Lq_h = 1.0;
  p.flux_wb = flux_wb;
  p.pole_pairs = 1;
  p.J_kgm2 = 1.0;
  p.B_nms_rad = 0.0;
  p.load = mcsim::load_constant(tau_load_nm);
  return p;
}

// Smooth, varying input in the paper's variables u1 = v_d, u2 = v_q.
Eigen::Vector2d u_profile(double t) {
  return Eigen::Vector2d(0.3 * std::sin(1.7 * t), 1.2 + 0.5 * std::cos(0.9 * t));
}

TEST(SimNormalised, DerivEqualsUnitPhysicalModel) {
  const double flux = 0.8;
  const double tau = 0.25;
  PmsmDq phys;
  ASSERT_EQ(phys.configure(unit_machine(flux, tau)), Status::kOk);
  PmsmNormalised norm;
  PmsmNormalisedParams np;
  np.gamma = flux;        // back-EMF gain = flux
  np.sigma = 1.5 * flux;  // torque gain = 3/2 p flux / J (amplitude-invariant)
  np.tau_l = tau;         // tau_load / J
  ASSERT_EQ(norm.configure(np), Status::kOk);
  for (int k = 0; k < 50; ++k) {
    const double s = 0.1 * k;
    const Eigen::Matrix<double, 4, 1> x(std::sin(3.0 * s), 2.0 * std::cos(s), 5.0 * std::sin(s), s);
    const Eigen::Vector2d u(std::cos(2.0 * s), -std::sin(s));
    const Eigen::Matrix<double, 4, 1> dn = norm.deriv(0.0, x, u);
    const Eigen::Matrix<double, 4, 1> dp = phys.deriv(0.0, x, u);
    // Same expressions up to the order of operations: a few ulps of the
    // largest term (~20) -> 1e-13 absolute.
    EXPECT_LT((dn - dp).cwiseAbs().maxCoeff(), 1e-13) << "k=" << k;
  }
}

// Wrappers that apply u_profile(t) so both runs see the same continuous input.
struct NormDriven {
  using State = Eigen::Matrix<double, 4, 1>;
  using Input = Eigen::Vector2d;
  const PmsmNormalised* m = nullptr;
  double v_scale = 1.0;  // u = u_profile(t_phys) / v_base
  double t_scale = 1.0;  // t_phys = t_n * t_base
  State deriv(double t_n, const State& x, const Input& /*u*/) const {
    return m->deriv(t_n, x, u_profile(t_n * t_scale) * v_scale);
  }
};

struct PhysDriven {
  using State = PmsmDq::State;
  using Input = PmsmDq::Input;
  const PmsmDq* m = nullptr;
  double v_gain = 1.0;  // physical voltage = v_gain * u_profile(t)
  State deriv(double t_s, const State& x, const Input& /*u*/) const {
    return m->deriv(t_s, x, Input(u_profile(t_s) * v_gain));
  }
};

TEST(SimNormalised, TrajectoryEqualsUnitPhysicalModel) {
  PmsmDq phys;
  ASSERT_EQ(phys.configure(unit_machine(0.8, 0.25)), Status::kOk);
  PmsmNormalised norm;
  PmsmNormalisedParams np;
  np.gamma = 0.8;
  np.sigma = 1.2;
  np.tau_l = 0.25;
  ASSERT_EQ(norm.configure(np), Status::kOk);
  PhysDriven fp;
  fp.m = &phys;
  NormDriven fn;
  fn.m = &norm;
  Eigen::Matrix<double, 4, 1> xp(0.1, -0.2, 0.3, 0.0);
  Eigen::Matrix<double, 4, 1> xn = xp;
  const Eigen::Vector2d u0 = Eigen::Vector2d::Zero();
  for (int k = 0; k < 200; ++k) {  // t = 0..20
    ASSERT_EQ(mcsim::advance_zoh(fp, u0, 0.1 * k, 0.1, 10, &xp), Status::kOk);
    ASSERT_EQ(mcsim::advance_zoh(fn, u0, 0.1 * k, 0.1, 10, &xn), Status::kOk);
  }
  // Same ODE, same integrator: only round-off differs, 1e-10 on O(1) states.
  EXPECT_LT((xp - xn).cwiseAbs().maxCoeff(), 1e-10);
  EXPECT_GT(std::fabs(xp(2)), 0.1);  // it moved
}

TEST(SimNormalised, GeneralScalingMapsAPhysicalMachine) {
  PmsmParams p;
  p.R_ohm = 0.3;
  p.Ld_h = 4.0e-4;
  p.Lq_h = 4.0e-4;
  p.flux_wb = 0.02;
  p.pole_pairs = 5;
  p.J_kgm2 = 3.0e-5;
  p.B_nms_rad = 0.0;
  const double tau_load = 0.04;
  p.load = mcsim::load_constant(tau_load);
  PmsmDq phys;
  ASSERT_EQ(phys.configure(p), Status::kOk);
  mcsim::PmsmNormalisedScaling sc;
  ASSERT_EQ(mcsim::make_normalised_scaling(p, 10.0, tau_load, &sc), Status::kOk);
  PmsmNormalised norm;
  ASSERT_EQ(norm.configure(sc.params), Status::kOk);

  PhysDriven fp;
  fp.m = &phys;
  fp.v_gain = 3.0;  // volts
  NormDriven fn;
  fn.m = &norm;
  fn.v_scale = 3.0 / sc.v_base_v;
  fn.t_scale = sc.t_base_s;
  const double pp = 5.0;
  Eigen::Matrix<double, 4, 1> xp(1.0, -2.0, 10.0, 0.05);
  Eigen::Matrix<double, 4, 1> xn(1.0 / sc.i_base_a, -2.0 / sc.i_base_a, pp * 10.0 * sc.t_base_s,
                                 pp * 0.05);
  const Eigen::Vector2d u0 = Eigen::Vector2d::Zero();
  const double period_s = 2.0e-5;
  const double period_n = period_s / sc.t_base_s;
  for (int k = 0; k < 2000; ++k) {  // 40 ms = 30 electrical time constants
    ASSERT_EQ(mcsim::advance_zoh(fp, u0, k * period_s, period_s, 2, &xp), Status::kOk);
    ASSERT_EQ(mcsim::advance_zoh(fn, u0, k * period_n, period_n, 2, &xn), Status::kOk);
  }
  const Eigen::Matrix<double, 4, 1> xp_from_n(xn(0) * sc.i_base_a, xn(1) * sc.i_base_a,
                                              xn(2) / (pp * sc.t_base_s), xn(3) / pp);
  // The two runs take the same steps of the same ODE in scaled variables:
  // only round-off through the scale factors differs (observed 5e-14);
  // bound 1e-10 relative per component. A wrong sigma, gamma or tau_l
  // mapping gives errors of percents.
  for (int i = 0; i < 4; ++i) {
    EXPECT_NEAR(xp_from_n(i), xp(i), 1e-10 * (1.0 + std::fabs(xp(i)))) << "i=" << i;
  }
  EXPECT_GT(std::fabs(xp(2) - 10.0), 1.0);  // the speed changed
}

TEST(SimNormalised, ScalingAndConfigErrors) {
  PmsmParams p = unit_machine(1.0, 0.0);
  p.Lq_h = 2.0;
  mcsim::PmsmNormalisedScaling sc;
  sc.t_base_s = -7.0;
  EXPECT_EQ(mcsim::make_normalised_scaling(p, 1.0, 0.0, &sc), Status::kNonSalientRequired);
  p = unit_machine(1.0, 0.0);
  p.B_nms_rad = 0.1;
  EXPECT_EQ(mcsim::make_normalised_scaling(p, 1.0, 0.0, &sc), Status::kNonSalientRequired);
  p = unit_machine(1.0, 0.0);
  EXPECT_EQ(mcsim::make_normalised_scaling(p, 0.0, 0.0, &sc), Status::kBadBase);
  EXPECT_EQ(sc.t_base_s, -7.0);  // untouched on error
  EXPECT_EQ(mcsim::make_normalised_scaling(p, 1.0, 0.0, &sc), Status::kOk);
  EXPECT_EQ(sc.t_base_s, 1.0);
  EXPECT_EQ(sc.params.gamma, 1.0);
  EXPECT_EQ(sc.params.sigma, 1.5);

  PmsmNormalised n;
  PmsmNormalisedParams bad;
  bad.sigma = 0.0;
  EXPECT_EQ(n.configure(bad), Status::kNonPositiveTorqueConstant);
  bad.sigma = 1.0;
  bad.gamma = -1.0;
  EXPECT_EQ(n.configure(bad), Status::kNegativeFlux);
  bad.gamma = NAN;
  EXPECT_EQ(n.configure(bad), Status::kNotFinite);
  EXPECT_EQ(n.params().gamma, 1.0);  // default kept
}

}  // namespace
