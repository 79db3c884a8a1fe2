#include "mcsim/pmsm_ab.hpp"

#include <cmath>

#include <Eigen/LU>

namespace mcsim {

Status PmsmAb::configure(const PmsmParams& p) {
  const Status s = p.validate();
  if (s == Status::kOk) {
    p_ = p;
    (void)cog_.configure(p.cogging, p.pole_pairs);  // validated above
  }
  return s;
}

Eigen::Matrix2d PmsmAb::inductance_h(double theta_e_rad) const {
  const double l0 = 0.5 * (p_.Ld_h + p_.Lq_h);
  const double l2 = 0.5 * (p_.Ld_h - p_.Lq_h);
  const double c2 = std::cos(2.0 * theta_e_rad);
  const double s2 = std::sin(2.0 * theta_e_rad);
  Eigen::Matrix2d l;
  l << l0 + l2 * c2, l2 * s2, l2 * s2, l0 - l2 * c2;
  return l;
}

Eigen::Vector2d PmsmAb::flux_linkage_wb(const State& x) const {
  const double th_e = static_cast<double>(p_.pole_pairs) * x(kThetaM);
  const Eigen::Vector2d i(x(kIalpha), x(kIbeta));
  const Eigen::Vector2d pm(p_.flux_wb * std::cos(th_e), p_.flux_wb * std::sin(th_e));
  return inductance_h(th_e) * i + pm;
}

PmsmAb::State PmsmAb::deriv(double t_s, const State& x, const Input& u) const {
  const double pp = static_cast<double>(p_.pole_pairs);
  const double th_e = pp * x(kThetaM);
  const double w_m = x(kOmegaM);
  const double w_e = pp * w_m;
  const double l2 = 0.5 * (p_.Ld_h - p_.Lq_h);
  const double c2 = std::cos(2.0 * th_e);
  const double s2 = std::sin(2.0 * th_e);
  const Eigen::Vector2d i(x(kIalpha), x(kIbeta));
  const Eigen::Vector2d v(u(kValpha), u(kVbeta));

  // dL/dtheta_e = 2 L2 [[-sin 2th, cos 2th], [cos 2th, sin 2th]]
  Eigen::Matrix2d dl;
  dl << -2.0 * l2 * s2, 2.0 * l2 * c2, 2.0 * l2 * c2, 2.0 * l2 * s2;
  // Back-EMF of the magnet: d/dt (flux [cos, sin]) = w_e flux [-sin, cos]
  const Eigen::Vector2d emf_pm(-w_e * p_.flux_wb * std::sin(th_e),
                               w_e * p_.flux_wb * std::cos(th_e));
  const Eigen::Vector2d rhs = v - p_.R_ohm * i - w_e * (dl * i) - emf_pm;
  const Eigen::Vector2d di = inductance_h(th_e).inverse() * rhs;

  State dx;
  dx(kIalpha) = di(0);
  dx(kIbeta) = di(1);
  double net_nm = torque_nm(x) - p_.B_nms_rad * w_m - load_nm(t_s, x);
  if (cog_.active()) net_nm += cog_.torque_nm(x(kThetaM));
  dx(kOmegaM) = net_nm / p_.J_kgm2;
  dx(kThetaM) = w_m;
  return dx;
}

double PmsmAb::torque_nm(const State& x) const {
  const Eigen::Vector2d lam = flux_linkage_wb(x);
  return 1.5 * static_cast<double>(p_.pole_pairs) * (lam(0) * x(kIbeta) - lam(1) * x(kIalpha));
}

double PmsmAb::load_nm(double t_s, const State& x) const {
  return p_.load.eval_nm(t_s, x(kThetaM), x(kOmegaM));
}

double PmsmAb::input_power_w(const State& x, const Input& u) const {
  return 1.5 * (u(kValpha) * x(kIalpha) + u(kVbeta) * x(kIbeta));
}

double PmsmAb::copper_loss_w(const State& x) const {
  return 1.5 * p_.R_ohm * (x(kIalpha) * x(kIalpha) + x(kIbeta) * x(kIbeta));
}

double PmsmAb::magnetic_energy_j(const State& x) const {
  const double th_e = static_cast<double>(p_.pole_pairs) * x(kThetaM);
  const Eigen::Vector2d i(x(kIalpha), x(kIbeta));
  return 0.75 * i.dot(inductance_h(th_e) * i);
}

double PmsmAb::kinetic_energy_j(const State& x) const {
  return 0.5 * p_.J_kgm2 * x(kOmegaM) * x(kOmegaM);
}

}  // namespace mcsim
