// mcsim/pmsm_power_stage.hpp: a three-phase bridge (average-value inverter,
// Inverter3Ph) feeding a PMSM, with the physics of the switches that a
// controller cannot see: diode freewheeling with the bridge off and a broken
// phase conductor. The plant side of a simulated PMSM drive board: the board
// (hal/host) only binds the HAL's duties, enable and sensors to it.
//
// One call of advance() is one PWM period T = inverter.t_pwm_s, the duties
// and the switching state held over it (zero-order hold), integrated with
// `substeps` RK4 sub-steps. The duties are those in force for the period:
// the caller applies any computation delay.
//
// Bridge switching: the pole voltages follow the duties (Inverter3Ph, dead
// time evaluated with the phase currents at the period's start); the plant
// is PmsmRotorFrame (the dq model driven by the alpha-beta voltage,
// trig-free), its (cos, sin) states re-derived from theta_m every 32 periods.
//
// Bridge off (all six switches open): a phase still carrying current
// freewheels through a diode: its pole is at 0 V for current into the motor
// and at vbus for current out of it. The pole voltages are re-evaluated at
// every sub-step; when the current vector would reverse within one sub-step,
// it is set to zero and the machine is open-circuit from then on (as long as
// its line-to-line back-EMF stays below vbus, which is checked: above it the
// diode rectifier conducts again).
//
// Open phase (set_open_phase): one phase conductor broken between the bridge
// and the star point. The plant is then PmsmOpenPhase (one series current
// through the other two phases, driven by the difference of their pole
// voltages); the rotor-frame state keeps the same machine state (rounded),
// so rotor_frame_state() and phase_currents_a() see it. With the switches
// open the series current freewheels through the diodes of its two legs
// (-vbus or +vbus across the pair) until it reaches zero.
//
// Nothing here allocates; advance() costs no trigonometric function.
#ifndef MCSIM_PMSM_POWER_STAGE_HPP
#define MCSIM_PMSM_POWER_STAGE_HPP

#include <cmath>
#include <cstdint>

#include <Eigen/Core>

#include "mcsim/inverter.hpp"
#include "mcsim/load_torque.hpp"
#include "mcsim/pmsm_open_phase.hpp"
#include "mcsim/pmsm_params.hpp"
#include "mcsim/pmsm_rotor_frame.hpp"
#include "mcsim/status.hpp"
#include "mcsim/thermal.hpp"

namespace mcsim {

struct PmsmPowerStageParams {
  PmsmParams motor{};
  InverterParams inverter{};    // t_pwm_s is the period of advance()
  double vbus_v = 24.0;         // DC-bus voltage (stiff source), > 0
  int substeps = 4;             // RK4 sub-steps per period, >= 1
  double theta_m0_rad = 0.0;    // initial rotor angle
  double omega_m0_rad_s = 0.0;  // initial speed
  // Temperatures (thermal.hpp): off by default (R and flux constant, bit
  // for bit the stage without it). On: the thermal model advances once per
  // period with the period's mean |i_dq|^2 (trapezoid of its ends) and the
  // speed at its end, and the plant's R and flux follow R(T_w), flux(T_m)
  // from the next period on; motor.R_ohm and motor.flux_wb are their values
  // at thermal.t_ref_c.
  bool thermal_enabled = false;
  ThermalParams thermal{};

  // kOk or the first failing check: motor.validate(), inverter.validate(),
  // kBadStepCount (substeps < 1), kNotFinite (vbus_v not > 0 or not finite,
  // an initial condition not finite), thermal.validate() when enabled.
  Status validate() const;
};

class PmsmPowerStage {
 public:
  // (i_d, i_q, omega_m, theta_m, cos, sin): PmsmRotorFrame's state.
  using State = PmsmRotorFrame::State;

  // Validates p and starts at its initial condition (zero current, bridge
  // off, all phases connected, t = 0). On error returns the code and keeps
  // the previous configuration and state.
  Status configure(const PmsmPowerStageParams& p);
  const PmsmPowerStageParams& params() const { return p_; }

  // One period with the bridge switching at duty_abc (each in [0, 1]) when
  // switching is true, all switches open otherwise. Errors of the
  // integrator (kNotFinite when the time is not finite). The healthy
  // switching path, once per SIL period, is inline: it costs no more than
  // the two calls (inverter, integrator) it makes.
  Status advance(const Eigen::Vector3d& duty_abc, bool switching) {
    if (disconnected_ || open_phase_ >= 0 || !switching) {
      return advance_special(duty_abc, switching && !disconnected_);
    }
    open_circuit_ = false;
    const double isq0 = thermal_on_ ? current_sq_a2() : 0.0;
    duty_applied_ = duty_abc;
    // The inverter uses the phase currents only for the dead-time error.
    const Eigen::Vector3d i =
        (p_.inverter.t_dead_s > 0.0) ? phase_currents_a() : Eigen::Vector3d::Zero();
    const Eigen::Vector2d v = inverter_.alpha_beta_v(duty_abc, p_.vbus_v, i);
    v_ab_applied_ = v;
    const Status s = plant_.advance_zoh(v, t_s_, p_.inverter.t_pwm_s, p_.substeps, &x_);
    if (s != Status::kOk) return s;
    end_period(isq0);
    return Status::kOk;
  }

  // -1: all three phases connected; 0..2: that phase conductor is broken
  // from the next advance() on. kBadPhase (nothing changed) outside -1..2.
  Status set_open_phase(int phase);
  int open_phase() const { return open_phase_; }
  // true: no motor on the terminals (all three conductors off): the bridge's
  // switching reaches no winding; the machine behaves as with the switches
  // open (no current unless its back-EMF exceeds the bus).
  void set_disconnected(bool d) { disconnected_ = d; }
  bool disconnected() const { return disconnected_; }
  // Load torque model (kBadLoad and friends of PmsmParams::validate(),
  // nothing changed, on error).
  Status set_load(const LoadTorque& load);
  // DC-bus voltage from the next advance() on; the inverter treats a
  // negative value as 0 (a test may collapse the bus).
  void set_vbus_v(double v) { p_.vbus_v = v; }
  double vbus_v() const { return p_.vbus_v; }

  double t_s() const { return t_s_; }
  double period_s() const { return p_.inverter.t_pwm_s; }
  const State& rotor_frame_state() const { return x_; }
  const PmsmRotorFrame& plant() const { return plant_; }
  double torque_nm() const { return plant_.torque_nm(x_); }
  // Phase currents (a, b, c) [A] of the rotor-frame state (what a current
  // sensor measures; with an open phase the rounded dq image of the exact
  // series current).
  Eigen::Vector3d phase_currents_a() const {
    // Amplitude-invariant inverse Clarke.
    const Eigen::Vector2d iab = PmsmRotorFrame::i_alpha_beta_a(x_);
    const double a = iab(0), b = iab(1);
    const double s3 = std::sqrt(3.0) / 2.0;
    return {a, -0.5 * a + s3 * b, -0.5 * a - s3 * b};
  }
  // Exact phase currents [A]: with an open phase exactly 0 in it and exactly
  // opposite in the other two.
  Eigen::Vector3d phase_currents_true_a() const;
  // Duties and alpha-beta voltage in force over the last period (0.5 and 0
  // with the bridge off; the alpha-beta voltage of the last freewheeling
  // sub-step while a diode conducts).
  const Eigen::Vector3d& duties_applied() const { return duty_applied_; }
  const Eigen::Vector2d& v_alpha_beta_applied() const { return v_ab_applied_; }
  // True while no current flows with the bridge off (the diodes block).
  bool open_circuit() const { return open_circuit_; }
  // The thermal model, nullptr when thermal_enabled is false. The plant's
  // present R and flux: plant().params().R_ohm, .flux_wb.
  const ThermalModel* thermal() const { return thermal_on_ ? &thermal_ : nullptr; }

 private:
  // The bridge off, or a phase open.
  Status advance_special(const Eigen::Vector3d& duty, bool switching);
  // (cos, sin) of the electrical angle are integrated as states; re-derive
  // them from theta_m every 32 periods (drift per period is O(h^5)).
  // isq0: |i_dq|^2 at the period's start (for the thermal model).
  void end_period(double isq0) {
    if (thermal_on_) thermal_period(isq0);
    if ((++period_count_ & 31U) == 0U) plant_.resync(&x_);
    t_s_ += p_.inverter.t_pwm_s;
  }
  double current_sq_a2() const { return x_(0) * x_(0) + x_(1) * x_(1); }
  void thermal_period(double isq0);
  void apply_temperatures();
  void freewheel(double h_s, int n);
  void advance_open_phase(const Eigen::Vector3d& duty, bool switching);

  PmsmPowerStageParams p_{};
  PmsmRotorFrame plant_;
  Inverter3Ph inverter_;
  PmsmOpenPhase open_plant_;
  State x_ = State::Zero();
  Eigen::Vector3d duty_applied_{0.5, 0.5, 0.5};
  Eigen::Vector2d v_ab_applied_ = Eigen::Vector2d::Zero();
  double t_s_ = 0.0;
  uint64_t period_count_ = 0;
  // Open phase: the series current it carries (exact; x_ holds the same
  // state in dq, rounded). open_fresh_: the break has just happened (or
  // healed), the next period projects the series current from x_.
  double open_i_a_ = 0.0;
  int open_phase_ = -1;
  bool disconnected_ = false;
  bool open_fresh_ = true;
  bool open_circuit_ = true;
  ThermalModel thermal_;
  bool thermal_on_ = false;
};

}  // namespace mcsim

#endif  // MCSIM_PMSM_POWER_STAGE_HPP
