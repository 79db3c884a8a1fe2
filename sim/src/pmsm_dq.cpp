#include "mcsim/pmsm_dq.hpp"

#include "util.hpp"

namespace mcsim {

Status PmsmParams::validate() const {
  if (!detail::all_finite({R_ohm, Ld_h, Lq_h, flux_wb, J_kgm2, B_nms_rad})) {
    return Status::kNotFinite;
  }
  if (!(R_ohm > 0.0)) {
    return Status::kNonPositiveResistance;
  }
  if (!(Ld_h > 0.0) || !(Lq_h > 0.0)) {
    return Status::kNonPositiveInductance;
  }
  if (flux_wb < 0.0) {
    return Status::kNegativeFlux;
  }
  if (pole_pairs < 1) {
    return Status::kBadPolePairs;
  }
  if (!(J_kgm2 > 0.0)) {
    return Status::kNonPositiveInertia;
  }
  if (B_nms_rad < 0.0) {
    return Status::kNegativeFriction;
  }
  const Status sl = load.validate();
  if (sl != Status::kOk) return sl;
  return cogging.validate();
}

Status PmsmDq::configure(const PmsmParams& p) {
  const Status s = p.validate();
  if (s == Status::kOk) {
    p_ = p;
    (void)cog_.configure(p.cogging, p.pole_pairs);  // validated above
  }
  return s;
}

Status PmsmDq::set_electrical(double r_ohm, double flux_wb) {
  PmsmParams p = p_;
  p.R_ohm = r_ohm;
  p.flux_wb = flux_wb;
  const Status s = p.validate();
  if (s == Status::kOk) {
    p_.R_ohm = r_ohm;
    p_.flux_wb = flux_wb;
  }
  return s;
}

PmsmDq::State PmsmDq::deriv(double t_s, const State& x, const Input& u) const {
  const double pp = static_cast<double>(p_.pole_pairs);
  const double i_d = x(kId);
  const double i_q = x(kIq);
  const double w_m = x(kOmegaM);
  const double w_e = pp * w_m;
  State dx;
  dx(kId) = (u(kVd) - p_.R_ohm * i_d + w_e * p_.Lq_h * i_q) / p_.Ld_h;
  dx(kIq) = (u(kVq) - p_.R_ohm * i_q - w_e * (p_.Ld_h * i_d + p_.flux_wb)) / p_.Lq_h;
  double net_nm = torque_nm(x) - p_.B_nms_rad * w_m - load_nm(t_s, x);
  if (cog_.active()) net_nm += cog_.torque_nm(x(kThetaM));
  dx(kOmegaM) = net_nm / p_.J_kgm2;
  dx(kThetaM) = w_m;
  return dx;
}

double PmsmDq::torque_nm(const State& x) const {
  const double pp = static_cast<double>(p_.pole_pairs);
  return 1.5 * pp * (p_.flux_wb * x(kIq) + (p_.Ld_h - p_.Lq_h) * x(kId) * x(kIq));
}

double PmsmDq::load_nm(double t_s, const State& x) const {
  return p_.load.eval_nm(t_s, x(kThetaM), x(kOmegaM));
}

double PmsmDq::input_power_w(const State& x, const Input& u) const {
  return 1.5 * (u(kVd) * x(kId) + u(kVq) * x(kIq));
}

double PmsmDq::copper_loss_w(const State& x) const {
  return 1.5 * p_.R_ohm * (x(kId) * x(kId) + x(kIq) * x(kIq));
}

double PmsmDq::magnetic_energy_j(const State& x) const {
  return 0.75 * (p_.Ld_h * x(kId) * x(kId) + p_.Lq_h * x(kIq) * x(kIq));
}

double PmsmDq::kinetic_energy_j(const State& x) const {
  return 0.5 * p_.J_kgm2 * x(kOmegaM) * x(kOmegaM);
}

}  // namespace mcsim
