#include "mcsim/inverter.hpp"

#include <cmath>

#include "mcsim/frames.hpp"
#include "util.hpp"

namespace mcsim {

Status InverterParams::validate() const {
  if (!detail::all_finite({t_pwm_s, t_dead_s, i_dead_band_a})) {
    return Status::kNotFinite;
  }
  if (!(t_pwm_s > 0.0)) {
    return Status::kBadPwmPeriod;
  }
  if (t_dead_s < 0.0 || !(t_dead_s < 0.5 * t_pwm_s)) {
    return Status::kBadDeadTime;
  }
  if (!(i_dead_band_a > 0.0)) {
    return Status::kBadDeadBand;
  }
  return Status::kOk;
}

Status Inverter3Ph::configure(const InverterParams& p) {
  const Status s = p.validate();
  if (s == Status::kOk) {
    p_ = p;
  }
  return s;
}

Eigen::Vector3d Inverter3Ph::pole_voltages_v(const Eigen::Vector3d& duty_abc, double vbus_v,
                                             const Eigen::Vector3d& i_abc_a) const {
  const double dead_frac = p_.t_dead_s / p_.t_pwm_s;
  const double vdc_v = (vbus_v > 0.0) ? vbus_v : 0.0;  // a bridge cannot invert the bus
  Eigen::Vector3d v;
  for (int k = 0; k < 3; ++k) {
    const double d = detail::clamp(duty_abc(k), 0.0, 1.0);
    // No dead time: skip the division (this runs once per SIL period). A leg
    // held at 0 or 1 does not switch in the period (one switch on
    // throughout: the active short circuit is all three at 0), so it has
    // no dead-time interval either.
    const bool switches = d > 0.0 && d < 1.0;
    const double err = (dead_frac > 0.0 && switches)
                           ? detail::sat1(i_abc_a(k) / p_.i_dead_band_a) * dead_frac
                           : 0.0;
    v(k) = detail::clamp((d - err) * vdc_v, 0.0, vdc_v);
  }
  return v;
}

Eigen::Vector3d Inverter3Ph::phase_voltages_v(const Eigen::Vector3d& duty_abc, double vbus_v,
                                              const Eigen::Vector3d& i_abc_a) const {
  const Eigen::Vector3d pole = pole_voltages_v(duty_abc, vbus_v, i_abc_a);
  const double v_cm = (pole(0) + pole(1) + pole(2)) * (1.0 / 3.0);
  return pole - Eigen::Vector3d::Constant(v_cm);
}

Eigen::Vector2d Inverter3Ph::alpha_beta_v(const Eigen::Vector3d& duty_abc, double vbus_v,
                                          const Eigen::Vector3d& i_abc_a) const {
  // Clarke of the pole voltages: the common mode that separates them from
  // the phase voltages cancels in both components, so it is not formed, and
  // 1/3, 1/sqrt(3) are products. Same value as clarke(phase_voltages_v())
  // to a few roundings (tests/sil/sim), with a third of its latency: a SIL
  // period computes this right before integrating the plant with it.
  const Eigen::Vector3d p = pole_voltages_v(duty_abc, vbus_v, i_abc_a);
  constexpr double kThird = 1.0 / 3.0;
  constexpr double kInvSqrt3 = 0.57735026918962576451;
  return Eigen::Vector2d(((p(0) + p(0)) - p(1) - p(2)) * kThird, (p(1) - p(2)) * kInvSqrt3);
}

double Inverter3Ph::dc_current_a(const Eigen::Vector3d& duty_abc, const Eigen::Vector3d& i_abc_a) {
  double i_dc = 0.0;
  for (int k = 0; k < 3; ++k) {
    i_dc += detail::clamp(duty_abc(k), 0.0, 1.0) * i_abc_a(k);
  }
  return i_dc;
}

Status InverterCommonLeg::configure(const InverterParams& p) {
  return legs_.configure(p);
}

Eigen::Vector3d InverterCommonLeg::pole_voltages_v(const Eigen::Vector3d& duty, double vbus_v,
                                                   const Eigen::Vector2d& i_ab_a) const {
  return legs_.pole_voltages_v(duty, vbus_v, leg_currents_a(i_ab_a));
}

Eigen::Vector2d InverterCommonLeg::voltages_v(const Eigen::Vector3d& duty, double vbus_v,
                                              const Eigen::Vector2d& i_ab_a) const {
  const Eigen::Vector3d v = pole_voltages_v(duty, vbus_v, i_ab_a);
  return {v(0) - v(2), v(1) - v(2)};
}

double InverterCommonLeg::dc_current_a(const Eigen::Vector3d& duty, const Eigen::Vector2d& i_ab_a) {
  return Inverter3Ph::dc_current_a(duty, leg_currents_a(i_ab_a));
}

bool InverterCommonLeg::reachable(const Eigen::Vector2d& v_ab, double vbus_v) {
  const double lim = vbus_v * (1.0 + 1e-12);
  return std::fabs(v_ab(0)) <= lim && std::fabs(v_ab(1)) <= lim &&
         std::fabs(v_ab(0) - v_ab(1)) <= lim;
}

double InverterCommonLeg::max_quadrature_amplitude_v(double vbus_v) {
  return vbus_v * 0.70710678118654752440;  // 1 / sqrt(2)
}

Status InverterHBridge2::configure(const InverterParams& p) {
  const Status s = p.validate();
  if (s == Status::kOk) {
    p_ = p;
  }
  return s;
}

Eigen::Vector2d InverterHBridge2::voltages_v(const Eigen::Vector2d& duty_ab, double vbus_v,
                                             const Eigen::Vector2d& i_ab_a) const {
  const double dead_frac = p_.t_dead_s / p_.t_pwm_s;
  const double vdc_v = (vbus_v > 0.0) ? vbus_v : 0.0;  // a bridge cannot invert the bus
  Eigen::Vector2d v;
  for (int k = 0; k < 2; ++k) {
    const double d = detail::clamp(duty_ab(k), -1.0, 1.0);
    const double err = 2.0 * detail::sat1(i_ab_a(k) / p_.i_dead_band_a) * dead_frac;
    v(k) = detail::clamp((d - err) * vdc_v, -vdc_v, vdc_v);
  }
  return v;
}

}  // namespace mcsim
