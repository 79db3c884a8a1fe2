// See thermal.hpp.
#include "mcsim/thermal.hpp"

#include <cmath>

#include <Eigen/Core>

#include "mcsim/integrator.hpp"
#include "util.hpp"

namespace mcsim {

namespace {

constexpr double kTwoPi = 6.283185307179586476925286766559;
constexpr double kAbsoluteZeroC = -273.15;

// The network with the energies as states: (T_w, T_h, E_cu, E_fe, E_amb),
// input (|i|^2, omega_e, R_ref).
struct Network {
  using State = Eigen::Matrix<double, 5, 1>;
  using Input = Eigen::Matrix<double, 3, 1>;
  const ThermalModel* m;
  State deriv(double /*t_s*/, const State& x, const Input& u) const {
    const ThermalParams& p = m->params();
    const double p_cu = 1.5 * u(0) * u(2) * m->resistance_factor_at(x(0));
    const double p_fe = m->iron_loss_w(u(1));
    const double q_wh = (x(0) - x(1)) / p.r_wh_k_w;
    const double q_ha = (x(1) - p.ambient_c) / p.r_ha_k_w;
    State d;
    d << (p_cu - q_wh) / p.c_w_j_k, (q_wh + p_fe - q_ha) / p.c_h_j_k, p_cu, p_fe, q_ha;
    return d;
  }
};

}  // namespace

Status ThermalParams::validate() const {
  if (!detail::all_finite({ambient_c, r_wh_k_w, r_ha_k_w, c_w_j_k, c_h_j_k, t_ref_c, alpha_cu_1_k,
                           beta_magnet_1_k, magnet_winding_weight, iron_k_h_w_hz, iron_k_e_w_hz2,
                           t_w0_c, t_h0_c})) {
    return Status::kNotFinite;
  }
  const bool ok = r_wh_k_w > 0.0 && r_ha_k_w > 0.0 && c_w_j_k > 0.0 && c_h_j_k > 0.0 &&
                  alpha_cu_1_k >= 0.0 && alpha_cu_1_k <= 0.01 && beta_magnet_1_k >= -0.01 &&
                  beta_magnet_1_k <= 0.0 && magnet_winding_weight >= 0.0 &&
                  magnet_winding_weight <= 1.0 && iron_k_h_w_hz >= 0.0 && iron_k_e_w_hz2 >= 0.0 &&
                  ambient_c > kAbsoluteZeroC && t_ref_c > kAbsoluteZeroC &&
                  t_w0_c > kAbsoluteZeroC && t_h0_c > kAbsoluteZeroC;
  return ok ? Status::kOk : Status::kBadThermal;
}

Status thermal_from_rating(const ThermalRating& r, ThermalParams* out) {
  if (!detail::all_finite({r.r_ohm, r.i_rated_a, r.rise_k, r.ambient_c, r.t_ref_c, r.winding_share,
                           r.tau_winding_s, r.tau_housing_s})) {
    return Status::kNotFinite;
  }
  if (!(r.r_ohm > 0.0) || !(r.i_rated_a > 0.0) || !(r.rise_k > 0.0) ||
      !(r.winding_share > 0.0 && r.winding_share < 1.0) || !(r.tau_winding_s > 0.0) ||
      !(r.tau_housing_s > 0.0) || out == nullptr) {
    return Status::kBadThermal;
  }
  ThermalParams p;
  p.ambient_c = r.ambient_c;
  p.t_ref_c = r.t_ref_c;
  p.t_w0_c = p.t_h0_c = r.ambient_c;
  ThermalModel m;
  if (m.configure(p) != Status::kOk) return Status::kBadThermal;
  // The copper loss at the rated current and the rated hot winding: then
  // the steady state of T_w = T_a + P_cu(T_w) R_total is exactly the rise.
  const double p_hot =
      1.5 * r.i_rated_a * r.i_rated_a * r.r_ohm * m.resistance_factor_at(r.ambient_c + r.rise_k);
  const double r_total = r.rise_k / p_hot;
  p.r_wh_k_w = r.winding_share * r_total;
  p.r_ha_k_w = r_total - p.r_wh_k_w;
  p.c_w_j_k = r.tau_winding_s / p.r_wh_k_w;
  p.c_h_j_k = r.tau_housing_s / p.r_ha_k_w;
  const Status s = p.validate();
  if (s == Status::kOk) *out = p;
  return s;
}

double heat_capacity_j_k(double copper_kg, double iron_kg, double aluminium_kg) {
  return kSpecificHeatCopperJKgK * copper_kg + kSpecificHeatIronJKgK * iron_kg +
         kSpecificHeatAluminiumJKgK * aluminium_kg;
}

Status ThermalModel::configure(const ThermalParams& p) {
  const Status s = p.validate();
  if (s != Status::kOk) return s;
  p_ = p;
  t_w_ = p.t_w0_c;
  t_h_ = p.t_h0_c;
  e_ = ThermalEnergy{};
  return Status::kOk;
}

double ThermalModel::resistance_factor_at(double t_winding_c) const {
  // Copper's coefficient is referred to 20 C: R(T) = R20 (1 + a (T - 20)).
  const double a = p_.alpha_cu_1_k;
  return (1.0 + a * (t_winding_c - 20.0)) / (1.0 + a * (p_.t_ref_c - 20.0));
}

double ThermalModel::flux_factor() const {
  return 1.0 + p_.beta_magnet_1_k * (magnet_c() - p_.t_ref_c);
}

double ThermalModel::copper_loss_w(double i_sq_a2, double r_ref_ohm) const {
  return 1.5 * i_sq_a2 * r_ref_ohm * resistance_factor();
}

double ThermalModel::iron_loss_w(double omega_e_rad_s) const {
  const double f = std::fabs(omega_e_rad_s) / kTwoPi;
  return (p_.iron_k_h_w_hz + p_.iron_k_e_w_hz2 * f) * f;
}

double ThermalModel::stored_j() const {
  return p_.c_w_j_k * (t_w_ - p_.t_w0_c) + p_.c_h_j_k * (t_h_ - p_.t_h0_c);
}

double ThermalModel::steady_winding_c(double p_cu_w, double p_fe_w) const {
  const double t_h = p_.ambient_c + (p_cu_w + p_fe_w) * p_.r_ha_k_w;
  return t_h + p_cu_w * p_.r_wh_k_w;
}

void ThermalModel::iron_loss_friction(int pole_pairs, double* b_nms_rad, double* coulomb_nm) const {
  // P = k_h f + k_e f^2 with f = p |w| / 2 pi: torque P / |w| =
  // k_h p / 2 pi (Coulomb) + k_e (p / 2 pi)^2 |w| (viscous).
  const double g = static_cast<double>(pole_pairs) / kTwoPi;
  if (b_nms_rad != nullptr) *b_nms_rad = p_.iron_k_e_w_hz2 * g * g;
  if (coulomb_nm != nullptr) *coulomb_nm = p_.iron_k_h_w_hz * g;
}

void ThermalModel::advance(double h_s, int n, double i_sq_a2, double omega_e_rad_s,
                           double r_ref_ohm) {
  if (!(h_s > 0.0) || n < 1 || !detail::all_finite({h_s, i_sq_a2, omega_e_rad_s, r_ref_ohm})) {
    return;
  }
  const Network net{this};
  Network::State x;
  x << t_w_, t_h_, 0.0, 0.0, 0.0;
  const Network::Input u(i_sq_a2, omega_e_rad_s, r_ref_ohm);
  if (advance_zoh(net, u, 0.0, h_s, n, &x) != Status::kOk) return;
  t_w_ = x(0);
  t_h_ = x(1);
  e_.copper_j += x(2);
  e_.iron_j += x(3);
  e_.ambient_j += x(4);
}

}  // namespace mcsim
