#include "mcsim/load_torque.hpp"

#include <cmath>

#include "util.hpp"

namespace mcsim {

double LoadTorque::eval_nm(double t_s, double theta_m_rad, double omega_m_rad_s) const {
  double tau_nm = 0.0;
  switch (kind) {
    case LoadKind::kConstant:
      tau_nm = tau0_nm;
      break;
    case LoadKind::kStep:
      tau_nm = (t_s >= step_time_s) ? (tau0_nm + tau_step_nm) : tau0_nm;
      break;
    case LoadKind::kAngleSpeed:
      tau_nm = tau0_nm + k_omega_nms_rad * omega_m_rad_s +
               k_omega2_nms2_rad2 * omega_m_rad_s * std::fabs(omega_m_rad_s) +
               ripple_nm * std::sin(ripple_per_rev * theta_m_rad + ripple_phase_rad);
      break;
    case LoadKind::kFunction:
      tau_nm = (fn != nullptr) ? fn(t_s, theta_m_rad, omega_m_rad_s, fn_ctx) : 0.0;
      break;
  }
  if (coulomb_nm > 0.0) {
    tau_nm += coulomb_nm * detail::sat1(omega_m_rad_s / coulomb_band_rad_s);
  }
  return tau_nm;
}

Status LoadTorque::validate() const {
  if (!detail::all_finite({tau0_nm, step_time_s, tau_step_nm, k_omega_nms_rad, k_omega2_nms2_rad2,
                           ripple_nm, ripple_per_rev, ripple_phase_rad, coulomb_nm,
                           coulomb_band_rad_s})) {
    return Status::kNotFinite;
  }
  if (coulomb_nm < 0.0) {
    return Status::kNegativeFriction;
  }
  if (!(coulomb_band_rad_s > 0.0)) {
    return Status::kBadLoad;
  }
  switch (kind) {
    case LoadKind::kConstant:
    case LoadKind::kStep:
    case LoadKind::kAngleSpeed:
      return Status::kOk;
    case LoadKind::kFunction:
      return (fn != nullptr) ? Status::kOk : Status::kBadLoad;
  }
  return Status::kBadLoad;  // kind outside the enum
}

LoadTorque load_constant(double tau_nm) {
  LoadTorque l{};
  l.kind = LoadKind::kConstant;
  l.tau0_nm = tau_nm;
  return l;
}

LoadTorque load_step(double tau_before_nm, double step_time_s, double tau_after_nm) {
  LoadTorque l{};
  l.kind = LoadKind::kStep;
  l.tau0_nm = tau_before_nm;
  l.step_time_s = step_time_s;
  l.tau_step_nm = tau_after_nm - tau_before_nm;
  return l;
}

}  // namespace mcsim
