#include "mcsim/pmsm_normalised.hpp"

#include <cmath>

#include "util.hpp"

namespace mcsim {

Status PmsmNormalisedParams::validate() const {
  if (!detail::all_finite({sigma, gamma, tau_l})) {
    return Status::kNotFinite;
  }
  if (!(sigma > 0.0)) {
    return Status::kNonPositiveTorqueConstant;
  }
  if (gamma < 0.0) {
    return Status::kNegativeFlux;
  }
  return Status::kOk;
}

Status PmsmNormalised::configure(const PmsmNormalisedParams& p) {
  const Status s = p.validate();
  if (s == Status::kOk) {
    p_ = p;
  }
  return s;
}

PmsmNormalised::State PmsmNormalised::deriv(double t_n, const State& x, const Input& u) const {
  (void)t_n;
  State dx;
  dx(0) = -x(0) + x(1) * x(2) + u(0);
  dx(1) = -x(1) - x(0) * x(2) - p_.gamma * x(2) + u(1);
  dx(2) = p_.sigma * x(1) - p_.tau_l;
  dx(3) = x(2);
  return dx;
}

Status make_normalised_scaling(const PmsmParams& phys, double i_base_a, double tau_load_nm,
                               PmsmNormalisedScaling* out) {
  const Status s = phys.validate();
  if (s != Status::kOk) {
    return s;
  }
  if (!detail::all_finite({i_base_a, tau_load_nm})) {
    return Status::kNotFinite;
  }
  if (!(i_base_a > 0.0)) {
    return Status::kBadBase;
  }
  if (phys.Ld_h != phys.Lq_h || phys.B_nms_rad != 0.0) {
    return Status::kNonSalientRequired;
  }
  if (!(phys.flux_wb > 0.0)) {
    return Status::kNonPositiveTorqueConstant;
  }
  if (out == nullptr) {
    return Status::kBadBase;
  }
  const double pp = static_cast<double>(phys.pole_pairs);
  const double t_base_s = phys.Ld_h / phys.R_ohm;
  PmsmNormalisedScaling sc;
  sc.t_base_s = t_base_s;
  sc.i_base_a = i_base_a;
  sc.v_base_v = phys.R_ohm * i_base_a;
  sc.omega_e_base_rad_s = 1.0 / t_base_s;
  sc.params.gamma = phys.flux_wb / (phys.Ld_h * i_base_a);
  sc.params.sigma = 1.5 * pp * pp * phys.flux_wb * i_base_a * t_base_s * t_base_s / phys.J_kgm2;
  sc.params.tau_l = pp * t_base_s * t_base_s * tau_load_nm / phys.J_kgm2;
  *out = sc;
  return Status::kOk;
}

}  // namespace mcsim
