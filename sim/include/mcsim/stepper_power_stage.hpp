// mcsim/stepper_power_stage.hpp: two full H-bridges (one per winding) feeding
// the two-phase stepper (Stepper2Ph), with the diode physics of the bridges
// switched off. The plant side of a simulated stepper drive board: the
// board (hal/host) only binds the HAL's duties, enable and sensors to it.
//
// One call of advance() is one PWM period T = t_pwm_s, the duties and the
// switching state held over it (zero-order hold), `substeps` RK4 sub-steps.
// The duties are those in force for the period: the caller applies any
// computation delay.
//
// Bridges switching: average-value, winding voltage = duty * vbus (bipolar,
// duty in [-1, 1], no dead time).
// Bridges off (all switches open): a winding with current freewheels through
// the diodes against the bus (-vbus sign(i)) until its current reaches zero,
// then stays open (zero current), each winding on its own.
//
// Nothing here allocates.
#ifndef MCSIM_STEPPER_POWER_STAGE_HPP
#define MCSIM_STEPPER_POWER_STAGE_HPP

#include <cstdint>

#include <Eigen/Core>

#include "mcsim/status.hpp"
#include "mcsim/stepper_2ph.hpp"

namespace mcsim {

struct StepperPowerStageParams {
  Stepper2PhParams motor{};
  double t_pwm_s = 1.0e-4;    // period of advance(), > 0
  double vbus_v = 60.0;       // DC-bus voltage (stiff source), > 0
  int substeps = 4;           // RK4 sub-steps per period, >= 1
  double theta_m0_rad = 0.0;  // initial shaft angle

  // kOk or the first failing check: motor.validate(), kBadPwmPeriod,
  // kBadStepCount, kNotFinite (vbus_v not > 0 or not finite, theta_m0_rad
  // not finite).
  Status validate() const;
};

class StepperPowerStage {
 public:
  using State = Stepper2Ph::State;  // (i_a, i_b, w, phi)

  // Validates p and starts at its initial condition (zero current, bridges
  // off, t = 0). On error returns the code and keeps everything.
  Status configure(const StepperPowerStageParams& p);
  const StepperPowerStageParams& params() const { return p_; }

  // One period with the bridges switching at duty_ab (each in [-1, 1]) when
  // switching is true, all switches open otherwise. Errors of the
  // integrator (kNotFinite when the time is not finite).
  Status advance(const Eigen::Vector2d& duty_ab, bool switching);

  double t_s() const { return t_s_; }
  double period_s() const { return p_.t_pwm_s; }
  const State& state() const { return x_; }
  // Winding voltages over the last period (the last sub-step's while a
  // diode conducts).
  const Eigen::Vector2d& v_applied() const { return v_applied_; }

 private:
  void freewheel(double h_s, int n);

  StepperPowerStageParams p_{};
  Stepper2Ph plant_;
  State x_ = State::Zero();
  double t_s_ = 0.0;
  uint64_t period_count_ = 0;
  Eigen::Vector2d v_applied_ = Eigen::Vector2d::Zero();
  bool open_[2] = {true, true};
};

}  // namespace mcsim

#endif  // MCSIM_STEPPER_POWER_STAGE_HPP
