// mcsim/pmsm_rotor_frame.hpp: the PMSM of PmsmDq driven by stationary-frame
// (alpha-beta) voltages, for fast closed-loop simulation.
//
// An inverter holds v_alpha, v_beta constant over a PWM period; in the rotor
// frame that input rotates. Rather than calling sin/cos at every RK4 stage
// (what dominates the cost of PmsmAb), the rotation is carried as two extra
// states c = cos(theta_e), s = sin(theta_e) with
//   dc/dt = -omega_e s,   ds/dt = omega_e c,
// so the derivative is polynomial. The electrical and mechanical equations
// are PmsmDq's own (its deriv() is called), with
//   v_d =  c v_alpha + s v_beta,   v_q = -s v_alpha + c v_beta.
// resync() recomputes (c, s) from theta_m once per period, so the two
// representations of the angle never drift apart.
//
// State x (index, name, unit):
//   0 i_d_a, 1 i_q_a, 2 omega_m_rad_s, 3 theta_m_rad (as PmsmDq),
//   4 cos_theta_e_1, 5 sin_theta_e_1
// Input u: 0 v_alpha_v, 1 v_beta_v
#ifndef MCSIM_PMSM_ROTOR_FRAME_HPP
#define MCSIM_PMSM_ROTOR_FRAME_HPP

#include <Eigen/Core>

#include "mcsim/pmsm_dq.hpp"

namespace mcsim {

class PmsmRotorFrame {
 public:
  using State = Eigen::Matrix<double, 6, 1>;
  using Input = Eigen::Matrix<double, 2, 1>;
  enum : int { kId = 0, kIq = 1, kOmegaM = 2, kThetaM = 3, kCos = 4, kSin = 5 };

  Status configure(const PmsmParams& p) { return dq_.configure(p); }
  const PmsmParams& params() const { return dq_.params(); }
  const PmsmDq& dq() const { return dq_; }

  State deriv(double t_s, const State& x, const Input& u) const {
    const double c = x(kCos), s = x(kSin);
    const PmsmDq::Input vdq(c * u(0) + s * u(1), -s * u(0) + c * u(1));
    const PmsmDq::State d4 = dq_.deriv(t_s, x.head<4>(), vdq);
    const double we = dq_.params().pole_pairs * x(kOmegaM);
    State dx;
    dx << d4, -we * s, we * c;
    return dx;
  }

  // Full state from dq currents, speed and angle.
  State make_state(double id_a, double iq_a, double omega_m, double theta_m) const;
  // Recompute (c, s) from theta_m (one sin/cos).
  void resync(State* x) const;
  // Stationary-frame currents (alpha, beta).
  static Eigen::Vector2d i_alpha_beta_a(const State& x) {
    const double c = x(kCos), s = x(kSin);
    return {c * x(kId) - s * x(kIq), s * x(kId) + c * x(kIq)};
  }
  double torque_nm(const State& x) const { return dq_.torque_nm(x.head<4>()); }

 private:
  PmsmDq dq_;
};

}  // namespace mcsim

#endif  // MCSIM_PMSM_ROTOR_FRAME_HPP
