// mcsim/pmsm_rotor_frame.hpp: the PMSM of PmsmDq driven by stationary-frame
// (alpha-beta) voltages, for fast closed-loop simulation.
//
// An inverter holds v_alpha, v_beta constant over a PWM period; in the rotor
// frame that input rotates. Rather than calling sin/cos at every RK4 stage
// (what dominates the cost of PmsmAb), the rotation is carried as two extra
// states c = cos(theta_e), s = sin(theta_e) with
//   dc/dt = -omega_e s,   ds/dt = omega_e c,
// so the derivative is polynomial. The electrical and mechanical equations
// are PmsmDq's, with
//   v_d =  c v_alpha + s v_beta,   v_q = -s v_alpha + c v_beta,
// written out here with the divisions replaced by reciprocals computed at
// configure() (this derivative runs 80 000 times per simulated second at
// 20 kHz and 4 RK4 sub-steps); tests/sil/host checks it against
// PmsmDq::deriv. resync() recomputes (c, s) from theta_m, so the two
// representations of the angle never drift apart (RK4 integrates both to
// O(h^4) per step; the caller re-syncs every few periods).
//
// advance_zoh() is mcsim::advance_zoh() (classical RK4, n equal sub-steps,
// input held) written out for this model, because it is most of the cost of
// a SIL period. Same stages, same weights; what differs is only where the
// roundings fall:
//   - every stage computes g = sigma f(x_stage) with the step factor sigma
//     (h/2 for stages 1 and 2, h for stage 3, h/6 for stage 4) folded into
//     the model's constants, and the ZOH input folded in once per period
//     (sigma/L * v_alpha, ...), so a stage is a few products and sums;
//   - x + (h/6)(k1 + 2 k2 + 2 k3 + k4) is formed as
//     (x + (g1 + 2 g2 + g3) / 3) + g4, the first part while stage 4 runs.
// The step constants are recomputed when (period, sub-steps) change and at
// configure(). tests/sil/sim checks it against rk4_step() on deriv() to
// 1e-13 relative per period, so RK4's order and stability carry over.
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

  // Validates p; on error returns the code and keeps the previous parameters.
  Status configure(const PmsmParams& p);
  // Resistance and PM flux only (PmsmDq::set_electrical; the step
  // constants are re-planned at the next advance_zoh()).
  Status set_electrical(double r_ohm, double flux_wb);
  const PmsmParams& params() const { return dq_.params(); }
  const PmsmDq& dq() const { return dq_; }

  State deriv(double t_s, const State& x, const Input& u) const {
    const PmsmParams& p = dq_.params();
    const double c = x(kCos), s = x(kSin);
    const double vd = c * u(0) + s * u(1);
    const double vq = -s * u(0) + c * u(1);
    const double id = x(kId), iq = x(kIq), wm = x(kOmegaM);
    const double we = pp_ * wm;
    const double tau_e = kt_ * iq * (p.flux_wb + (p.Ld_h - p.Lq_h) * id);
    State dx;
    dx(kId) = (vd - p.R_ohm * id + we * p.Lq_h * iq) * inv_ld_;
    dx(kIq) = (vq - p.R_ohm * iq - we * (p.Ld_h * id + p.flux_wb)) * inv_lq_;
    double tau_l = load_is_const_ ? const_load_nm_ : p.load.eval_nm(t_s, x(kThetaM), wm);
    if (dq_.cogging().active()) tau_l -= dq_.cogging().torque_nm(x(kThetaM));
    dx(kOmegaM) = (tau_e - p.B_nms_rad * wm - tau_l) * inv_j_;
    dx(kThetaM) = wm;
    dx(kCos) = -we * s;
    dx(kSin) = we * c;
    return dx;
  }

  // Advances *x from t0_s over period_s with n_sub RK4 sub-steps, u held
  // (what advance_zoh(*this, u, t0_s, period_s, n_sub, x) computes, to a few
  // roundings). Errors as advance_zoh() (state unchanged): kBadStepCount,
  // kBadPeriod, kNotFinite.
  Status advance_zoh(const Input& u, double t0_s, double period_s, int n_sub, State* x);

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
  // Model constants times one stage's step factor sigma; see advance_zoh().
  struct StageConsts {
    double sigma = 0.0;  // h/2, h or h/6
    double v_d = 0.0;    // sigma / Ld   (times v: the input term of i_d)
    double v_q = 0.0;    // sigma / Lq
    double r_d = 0.0;    // sigma R / Ld
    double x_d = 0.0;    // sigma p Lq / Ld   (times omega_m i_q)
    double r_q = 0.0;    // sigma R / Lq
    double x_q = 0.0;    // sigma p Ld / Lq   (times omega_m i_d)
    double f_q = 0.0;    // sigma p flux / Lq (times omega_m)
    double t_1 = 0.0;    // sigma 3/2 p flux / J          (times i_q)
    double t_2 = 0.0;    // sigma 3/2 p (Ld - Lq) / J     (times i_d i_q)
    double b = 0.0;      // sigma B / J
    double l = 0.0;      // sigma tau_load / J (constant load)
    double inv_j = 0.0;  // sigma / J (any other load)
    double w_e = 0.0;    // sigma p   (times omega_m: rotation of (c, s))
  };
  void plan_steps(double period_s, int n_sub);
  // The six states as plain scalars, as the stages are written out.
  struct Y6 {
    double id, iq, wm, th, c, s;
  };
  template <bool kConstLoad>
  Y6 rk4_substeps(const Y6& y0, const Input& u, double t0_s, int n_sub) const;

  PmsmDq dq_;
  double pp_ = 1.0, kt_ = 1.5, inv_ld_ = 0.0, inv_lq_ = 0.0, inv_j_ = 0.0;
  bool load_is_const_ = true;  // constant load, no Coulomb, no cogging: skip the call
  double const_load_nm_ = 0.0;
  // advance_zoh() step constants for (plan_period_s_, plan_n_sub_); a period
  // of 0 means not planned.
  double plan_period_s_ = 0.0;
  int plan_n_sub_ = 0;
  StageConsts stage_[3];  // sigma = h/2, h, h/6
};

}  // namespace mcsim

#endif  // MCSIM_PMSM_ROTOR_FRAME_HPP
