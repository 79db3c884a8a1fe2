// mcsim/inverter.hpp: average-value (switching-cycle averaged) inverters.
//
// Inverter3Ph: three half-bridge legs feeding a star-connected machine with
// an isolated neutral.
//   duty_abc  (3, each clamped to [0, 1])  fraction of T_pwm the high switch is on
//   vbus_v    DC-bus voltage [V] (negative values are treated as 0)
//   i_abc_a   phase currents [A], positive INTO the machine (for dead time)
// Pole voltage (leg output to the negative rail), with optional dead time:
//   v_xN = clamp(d_x vbus - sat(i_x / i_dead_band_a) (t_dead/T_pwm) vbus, 0, vbus)
// sat() is linear for |i_x| < i_dead_band_a (smooth near zero current) and
// +-1 outside: a current flowing out of the leg loses the dead-time interval.
// A leg at d_x = 0 or 1 does not switch and has no dead-time term (the
// active short circuit: all three low sides on, d = 0).
// The clamp to [0, vbus] is the DC-bus limit: no leg can produce more.
// Phase-to-neutral voltage removes the common mode:
//   v_x = v_xN - (v_aN + v_bN + v_cN)/3,  so v_a + v_b + v_c = 0,
// and the alpha-beta voltage is the amplitude-invariant Clarke of v_abc.
//
// InverterHBridge2: two full H-bridges (one per stepper phase).
//   duty_ab (2, signed, clamped to [-1, 1]), vbus_v, i_ab_a (winding currents)
//   v_x = clamp(d_x vbus - 2 sat(i_x / i_dead_band_a) (t_dead/T_pwm) vbus, -vbus, vbus)
// (both legs of a bridge lose the dead time with the same sign relative to the
// winding current, hence the factor 2).
#ifndef MCSIM_INVERTER_HPP
#define MCSIM_INVERTER_HPP

#include <Eigen/Core>

#include "mcsim/status.hpp"

namespace mcsim {

struct InverterParams {
  double t_pwm_s = 50.0e-6;     // PWM period, > 0
  double t_dead_s = 0.0;        // dead time, 0 <= t_dead < t_pwm/2
  double i_dead_band_a = 0.05;  // linear region of the dead-time error, > 0

  // kOk, kNotFinite, kBadPwmPeriod, kBadDeadTime, kBadDeadBand.
  Status validate() const;
};

class Inverter3Ph {
 public:
  Inverter3Ph() = default;
  // Validates p; on error returns the code and keeps the previous parameters.
  Status configure(const InverterParams& p);
  const InverterParams& params() const { return p_; }

  // Leg voltages to the negative DC rail [V].
  Eigen::Vector3d pole_voltages_v(const Eigen::Vector3d& duty_abc, double vbus_v,
                                  const Eigen::Vector3d& i_abc_a) const;
  // Phase-to-neutral voltages [V] (sum is zero).
  Eigen::Vector3d phase_voltages_v(const Eigen::Vector3d& duty_abc, double vbus_v,
                                   const Eigen::Vector3d& i_abc_a) const;
  // (v_alpha, v_beta) [V], amplitude-invariant Clarke of the phase voltages.
  Eigen::Vector2d alpha_beta_v(const Eigen::Vector3d& duty_abc, double vbus_v,
                               const Eigen::Vector3d& i_abc_a) const;
  // Average DC-bus current drawn by the bridge [A]: sum d_x i_x.
  static double dc_current_a(const Eigen::Vector3d& duty_abc, const Eigen::Vector3d& i_abc_a);

 private:
  InverterParams p_{};
};

class InverterHBridge2 {
 public:
  InverterHBridge2() = default;
  // Validates p; on error returns the code and keeps the previous parameters.
  Status configure(const InverterParams& p);
  const InverterParams& params() const { return p_; }

  // Winding voltages (v_a, v_b) [V].
  Eigen::Vector2d voltages_v(const Eigen::Vector2d& duty_ab, double vbus_v,
                             const Eigen::Vector2d& i_ab_a) const;

 private:
  InverterParams p_{};
};

}  // namespace mcsim

#endif  // MCSIM_INVERTER_HPP
