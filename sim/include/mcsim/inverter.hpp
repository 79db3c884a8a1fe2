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
//
// InverterCommonLeg: a three-leg bridge driving a two-phase stepper with a
// common leg (issue 34 item 3; SimpleFOC's hybrid-stepper driver wires it
// so): winding a between legs 1 and 3, winding b between legs 2 and 3.
//   duty (3, each clamped to [0, 1]), vbus_v, i_ab_a (winding currents,
//   positive from leg 1 (2) through the winding into the common leg 3)
//   leg currents (positive out of the leg): i_1 = i_a, i_2 = i_b,
//   i_3 = -(i_a + i_b)
//   pole voltages v_k as Inverter3Ph's (same dead-time term with i_k)
//   winding voltages v_a = v_1 - v_3, v_b = v_2 - v_3
// Voltage limit. With every pole in [0, V] the reachable (v_a, v_b) are
// the differences of two poles each against the same third: |v_a| <= V,
// |v_b| <= V and |v_a - v_b| = |v_1 - v_2| <= V, a hexagon with vertices
// (V, 0), (V, V), (0, V), (-V, 0), (-V, -V), (0, -V); and every point of it
// is reachable (v_3 = max(0, -v_a, -v_b) puts all three poles in [0, V]).
// A stepper is driven by quadrature voltages (U cos p, U sin p): the
// binding edge is |v_a - v_b| = sqrt(2) U |cos(p + pi/4)| <= V, so the
// amplitude reachable at every angle is
//   U_max = V / sqrt(2)  (0.707 V),
// against V for two full H-bridges (the square |v_a|, |v_b| <= V). The
// common-mode choice (the firmware's) does not change the windings'
// voltages; the DC current is sum_k d_k i_k as for the three-phase bridge.
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

class InverterCommonLeg {
 public:
  InverterCommonLeg() = default;
  // Validates p; on error returns the code and keeps the previous parameters.
  Status configure(const InverterParams& p);
  const InverterParams& params() const { return legs_.params(); }

  // Leg (pole) voltages to the negative rail [V].
  Eigen::Vector3d pole_voltages_v(const Eigen::Vector3d& duty, double vbus_v,
                                  const Eigen::Vector2d& i_ab_a) const;
  // Winding voltages (v_a, v_b) = (v_1 - v_3, v_2 - v_3) [V].
  Eigen::Vector2d voltages_v(const Eigen::Vector3d& duty, double vbus_v,
                             const Eigen::Vector2d& i_ab_a) const;
  // The leg currents (i_a, i_b, -(i_a + i_b)), positive out of the leg [A].
  static Eigen::Vector3d leg_currents_a(const Eigen::Vector2d& i_ab_a) {
    return {i_ab_a(0), i_ab_a(1), -(i_ab_a(0) + i_ab_a(1))};
  }
  // Average DC-bus current drawn by the bridge [A]: sum d_k i_k.
  static double dc_current_a(const Eigen::Vector3d& duty, const Eigen::Vector2d& i_ab_a);
  // The hexagon: |v_a|, |v_b|, |v_a - v_b| all <= vbus (to rel. 1e-12).
  static bool reachable(const Eigen::Vector2d& v_ab, double vbus_v);
  // The quadrature amplitude reachable at every angle: vbus / sqrt(2).
  static double max_quadrature_amplitude_v(double vbus_v);

 private:
  Inverter3Ph legs_;
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
