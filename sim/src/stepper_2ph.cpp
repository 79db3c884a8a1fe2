#include "mcsim/stepper_2ph.hpp"

#include <cmath>

#include "util.hpp"

namespace mcsim {

Status Stepper2PhParams::validate() const {
  if (!detail::all_finite({R_ohm, L_h, Km_nm_a, J_kgm2, B_nms_rad})) {
    return Status::kNotFinite;
  }
  if (!(R_ohm > 0.0)) {
    return Status::kNonPositiveResistance;
  }
  if (!(L_h > 0.0)) {
    return Status::kNonPositiveInductance;
  }
  if (!(Km_nm_a > 0.0)) {
    return Status::kNonPositiveTorqueConstant;
  }
  if (rotor_teeth < 1) {
    return Status::kBadTeeth;
  }
  if (!(J_kgm2 > 0.0)) {
    return Status::kNonPositiveInertia;
  }
  if (B_nms_rad < 0.0) {
    return Status::kNegativeFriction;
  }
  return load.validate();
}

Status Stepper2Ph::configure(const Stepper2PhParams& p) {
  const Status s = p.validate();
  if (s == Status::kOk) {
    p_ = p;
  }
  return s;
}

Stepper2Ph::State Stepper2Ph::deriv(double t_s, const State& x, const Input& u) const {
  const double nth = static_cast<double>(p_.rotor_teeth) * x(kThetaM);
  const double s = std::sin(nth);
  const double c = std::cos(nth);
  const double w = x(kOmegaM);
  State dx;
  dx(kIa) = (u(kVa) - p_.R_ohm * x(kIa) + p_.Km_nm_a * w * s) / p_.L_h;
  dx(kIb) = (u(kVb) - p_.R_ohm * x(kIb) - p_.Km_nm_a * w * c) / p_.L_h;
  dx(kOmegaM) = (torque_nm(x) - p_.B_nms_rad * w - load_nm(t_s, x)) / p_.J_kgm2;
  dx(kThetaM) = w;
  return dx;
}

double Stepper2Ph::torque_nm(const State& x) const {
  const double nth = static_cast<double>(p_.rotor_teeth) * x(kThetaM);
  return p_.Km_nm_a * (-x(kIa) * std::sin(nth) + x(kIb) * std::cos(nth));
}

double Stepper2Ph::load_nm(double t_s, const State& x) const {
  return p_.load.eval_nm(t_s, x(kThetaM), x(kOmegaM));
}

double Stepper2Ph::input_power_w(const State& x, const Input& u) const {
  return u(kVa) * x(kIa) + u(kVb) * x(kIb);
}

double Stepper2Ph::copper_loss_w(const State& x) const {
  return p_.R_ohm * (x(kIa) * x(kIa) + x(kIb) * x(kIb));
}

double Stepper2Ph::magnetic_energy_j(const State& x) const {
  return 0.5 * p_.L_h * (x(kIa) * x(kIa) + x(kIb) * x(kIb));
}

double Stepper2Ph::kinetic_energy_j(const State& x) const {
  return 0.5 * p_.J_kgm2 * x(kOmegaM) * x(kOmegaM);
}

}  // namespace mcsim
