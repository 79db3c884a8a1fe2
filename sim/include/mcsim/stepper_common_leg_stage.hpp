// mcsim/stepper_common_leg_stage.hpp: a two-phase stepper (Stepper2Ph) on a
// three-leg bridge with a common leg (InverterCommonLeg: winding a between
// legs 1 and 3, winding b between legs 2 and 3), the topology that drives a
// stepper from a three-phase board (issue 34 item 3). Next to
// StepperPowerStage (two full H-bridges).
//
// One call of advance() is one PWM period T = inverter.t_pwm_s, the duties
// and the switching state held over it, `substeps` RK4 sub-steps.
//
// Bridge switching: average-value, winding voltages (v_1 - v_3, v_2 - v_3)
// of InverterCommonLeg, dead time evaluated with the leg currents at the
// period's start, held over it. The windings' voltages are limited to the
// hexagon |v_a|, |v_b|, |v_a - v_b| <= vbus (quadrature amplitude at most
// vbus / sqrt(2): inverter.hpp derives it); duties outside [0, 1] are
// clamped, so a command beyond the limit gives what the bridge can.
//
// Bridge off (all switches open): each leg carrying current conducts
// through a diode, its pole at 0 V for current out of the leg and at vbus
// for current into it (leg currents i_a, i_b, -(i_a + i_b)). Per sub-step:
//   - all three legs conduct: v_a = v_1 - v_3, v_b = v_2 - v_3 from the
//     clamps (e.g. i_a, i_b > 0: both windings at -vbus);
//   - one winding at zero current: the other alone across its two legs
//     (-vbus sign(i)), the idle one's free pole floating (its current held
//     at zero);
//   - the common leg at zero current (i_a = -i_b): the windings in series
//     between legs 1 and 2, v_1 - v_2 from the clamps, the common node
//     floating so that i_a + i_b stays zero:
//       2 L di_a/dt = (v_1 - v_2) - 2 R i_a + (e_a - e_b);
//   - no current: open, the mechanics alone.
// A current whose sign changes within a sub-step stopped at zero in it: a
// winding current that reversed is set to zero; when the common leg's
// current reversed, the state is projected onto i_a = -i_b (series). As in
// StepperPowerStage, a winding that reached zero stays open: a back-EMF
// above the bus (diodes conducting again) and a floating node driven out of
// [0, vbus] are not modelled.
//
// Nothing here allocates.
#ifndef MCSIM_STEPPER_COMMON_LEG_STAGE_HPP
#define MCSIM_STEPPER_COMMON_LEG_STAGE_HPP

#include <cstdint>

#include <Eigen/Core>

#include "mcsim/inverter.hpp"
#include "mcsim/status.hpp"
#include "mcsim/stepper_2ph.hpp"

namespace mcsim {

struct StepperCommonLegStageParams {
  Stepper2PhParams motor{};
  InverterParams inverter{};  // t_pwm_s is the period of advance()
  double vbus_v = 24.0;       // DC-bus voltage, > 0
  int substeps = 4;           // RK4 sub-steps per period, >= 1
  double theta_m0_rad = 0.0;  // initial shaft angle

  // kOk or the first failing check: motor.validate(), inverter.validate(),
  // kBadStepCount, kNotFinite (vbus_v not > 0 or not finite, theta_m0_rad
  // not finite).
  Status validate() const;
};

class StepperCommonLegStage {
 public:
  using State = Stepper2Ph::State;  // (i_a, i_b, w, theta)

  // Validates p and starts at its initial condition (zero current, bridge
  // off, t = 0). On error returns the code and keeps everything.
  Status configure(const StepperCommonLegStageParams& p);
  const StepperCommonLegStageParams& params() const { return p_; }

  // One period with the bridge switching at duty (each in [0, 1], legs 1,
  // 2, 3) when switching is true, all switches open otherwise. Errors of the
  // integrator (kNotFinite when the time is not finite).
  Status advance(const Eigen::Vector3d& duty, bool switching);

  // DC-bus voltage from the next advance() on (a DC link may drive it).
  void set_vbus_v(double v) { p_.vbus_v = v; }
  double t_s() const { return t_s_; }
  double period_s() const { return p_.inverter.t_pwm_s; }
  const State& state() const { return x_; }
  const Stepper2Ph& plant() const { return plant_; }
  // Winding voltages over the last period (the last sub-step's with the
  // bridge off).
  const Eigen::Vector2d& v_applied() const { return v_applied_; }
  // Mean electrical power into the windings over the last period (trapezoid
  // of v . i per sub-step) [W]; what the bridge draws from the bus.
  double last_input_power_w() const { return p_in_w_; }

 private:
  void freewheel(double h_s, int n);

  StepperCommonLegStageParams p_{};
  Stepper2Ph plant_;
  InverterCommonLeg inverter_;
  State x_ = State::Zero();
  double t_s_ = 0.0;
  uint64_t period_count_ = 0;
  Eigen::Vector2d v_applied_ = Eigen::Vector2d::Zero();
  double p_in_w_ = 0.0;
};

}  // namespace mcsim

#endif  // MCSIM_STEPPER_COMMON_LEG_STAGE_HPP
