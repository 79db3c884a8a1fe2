#include "mcsim/pmsm_open_phase.hpp"

namespace mcsim {

Status PmsmOpenPhase::configure(const PmsmParams& p, int open_phase) {
  const Status st = p.validate();
  if (st != Status::kOk) return st;
  if (open_phase < 0 || open_phase > 2) return Status::kBadPhase;
  p_ = p;
  (void)cog_.configure(p.cogging, p.pole_pairs);  // validated above
  x_ = open_phase;
  pp_ = static_cast<double>(p.pole_pairs);
  lsum_ = p.Ld_h + p.Lq_h;
  ldiff_ = p.Ld_h - p.Lq_h;
  // phi = pi/2 + x 2pi/3: 90, 210, 330 degrees.
  static const double kC[3] = {0.0, -0.5 * kSqrt3, 0.5 * kSqrt3};
  static const double kS[3] = {1.0, -0.5, -0.5};
  cphi_ = kC[open_phase];
  sphi_ = kS[open_phase];
  return Status::kOk;
}

double PmsmOpenPhase::line_inductance_h(const State& x) const {
  const double cr = x(kCos) * cphi_ + x(kSin) * sphi_;
  const double sr = x(kSin) * cphi_ - x(kCos) * sphi_;
  return lsum_ + ldiff_ * (cr * cr - sr * sr);
}

double PmsmOpenPhase::line_emf_v(const State& x) const {
  const double sr = x(kSin) * cphi_ - x(kCos) * sphi_;
  return -kSqrt3 * p_.flux_wb * pp_ * x(kOmegaM) * sr;
}

double PmsmOpenPhase::torque_nm(const State& x) const {
  const double cr = x(kCos) * cphi_ + x(kSin) * sphi_;
  const double sr = x(kSin) * cphi_ - x(kCos) * sphi_;
  const double i = x(kI);
  return pp_ * (-2.0 * ldiff_ * sr * cr * i * i - kSqrt3 * p_.flux_wb * sr * i);
}

double PmsmOpenPhase::magnetic_energy_j(const State& x) const {
  return 0.5 * line_inductance_h(x) * x(kI) * x(kI);
}

Eigen::Vector3d PmsmOpenPhase::phase_currents_a(const State& x) const {
  Eigen::Vector3d i = Eigen::Vector3d::Zero();
  i(phase_y()) = x(kI);
  i(phase_z()) = -x(kI);
  return i;
}

PmsmOpenPhase::State PmsmOpenPhase::from_rotor_frame(const PmsmRotorFrame::State& xr) const {
  const double c = xr(PmsmRotorFrame::kCos), s = xr(PmsmRotorFrame::kSin);
  const double cr = c * cphi_ + s * sphi_;
  const double sr = s * cphi_ - c * sphi_;
  State x;
  x(kI) = 0.5 * kSqrt3 * (xr(PmsmRotorFrame::kId) * cr - xr(PmsmRotorFrame::kIq) * sr);
  x(kOmegaM) = xr(PmsmRotorFrame::kOmegaM);
  x(kThetaM) = xr(PmsmRotorFrame::kThetaM);
  x(kCos) = c;
  x(kSin) = s;
  return x;
}

PmsmRotorFrame::State PmsmOpenPhase::to_rotor_frame(const State& x) const {
  const double c = x(kCos), s = x(kSin);
  const double cr = c * cphi_ + s * sphi_;
  const double sr = s * cphi_ - c * sphi_;
  const double k = 2.0 / kSqrt3 * x(kI);
  PmsmRotorFrame::State xr;
  xr(PmsmRotorFrame::kId) = k * cr;
  xr(PmsmRotorFrame::kIq) = -k * sr;
  xr(PmsmRotorFrame::kOmegaM) = x(kOmegaM);
  xr(PmsmRotorFrame::kThetaM) = x(kThetaM);
  xr(PmsmRotorFrame::kCos) = c;
  xr(PmsmRotorFrame::kSin) = s;
  return xr;
}

}  // namespace mcsim
