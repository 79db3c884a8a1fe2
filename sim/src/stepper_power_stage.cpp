// See stepper_power_stage.hpp.
#include "mcsim/stepper_power_stage.hpp"

#include <cmath>

#include "mcsim/integrator.hpp"
#include "util.hpp"

namespace mcsim {

Status StepperPowerStageParams::validate() const {
  const Status sm = motor.validate();
  if (sm != Status::kOk) return sm;
  if (!(t_pwm_s > 0.0) || !std::isfinite(t_pwm_s)) return Status::kBadPwmPeriod;
  if (substeps < 1) return Status::kBadStepCount;
  if (!(vbus_v > 0.0) || !detail::all_finite({vbus_v, theta_m0_rad})) return Status::kNotFinite;
  return Status::kOk;
}

Status StepperPowerStage::configure(const StepperPowerStageParams& p) {
  const Status s = p.validate();
  if (s != Status::kOk) return s;
  p_ = p;
  (void)plant_.configure(p.motor);  // validated above
  x_ = State::Zero();
  x_(Stepper2Ph::kThetaM) = p.theta_m0_rad;
  t_s_ = 0.0;
  period_count_ = 0;
  v_applied_ = Eigen::Vector2d::Zero();
  open_[0] = open_[1] = true;
  return Status::kOk;
}

void StepperPowerStage::freewheel(double h_s, int n) {
  // Each winding on its own: while it carries current the diodes clamp it to
  // -vbus sign(i); once the current would reverse it is zero and open.
  for (int k = 0; k < n; ++k) {
    const double t = t_s_ + k * h_s;
    Stepper2Ph::Input u = Stepper2Ph::Input::Zero();
    for (int j = 0; j < 2; ++j) {
      const double i = x_(j);
      if (i != 0.0) open_[j] = false;
      u(j) = open_[j] ? 0.0 : (i > 0.0 ? -p_.vbus_v : p_.vbus_v);
    }
    const State before = x_;
    State x1 = rk4_step(plant_, t, x_, u, h_s);
    for (int j = 0; j < 2; ++j) {
      if (open_[j] || x1(j) * before(j) <= 0.0) {
        x1(j) = 0.0;  // open winding (or the current reached zero): no current
        open_[j] = true;
      }
    }
    x_ = x1;
    v_applied_ = u;
  }
}

Status StepperPowerStage::advance(const Eigen::Vector2d& duty_ab, bool switching) {
  const double T = p_.t_pwm_s;
  const int n = p_.substeps;
  if (!switching) {
    if (!std::isfinite(t_s_)) return Status::kNotFinite;
    freewheel(T / n, n);
  } else {
    open_[0] = open_[1] = false;
    v_applied_ = duty_ab * p_.vbus_v;
    const Status s = advance_zoh(plant_, v_applied_, t_s_, T, n, &x_);
    if (s != Status::kOk) return s;
  }
  ++period_count_;
  t_s_ = static_cast<double>(period_count_) * T;
  return Status::kOk;
}

}  // namespace mcsim
