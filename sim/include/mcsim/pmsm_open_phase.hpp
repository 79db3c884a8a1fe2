// mcsim/pmsm_open_phase.hpp: the PMSM of PmsmDq with one phase conductor
// broken (open-phase fault). Star connection, isolated star point.
//
// Phase x = open_phase (0 = a, 1 = b, 2 = c) carries no current; the other
// two, y = x + 1 and z = x + 2 (mod 3), form one series circuit through the
// star point: i_y = i, i_z = -i, i_x = 0. One electrical state i remains.
//
// Derivation (amplitude-invariant Clarke, as PmsmDq; theta = theta_e):
//   The currents i_abc = (0, i, -i) (rotated to phase x) map to
//   i_alphabeta = i u, with u = |u| (cos phi, sin phi), |u| = 2/sqrt(3),
//   phi = pi/2 + x 2pi/3 (the direction of e_y - e_z; orthogonal to phase
//   x's axis, whose alpha-beta direction is x 2pi/3).
//   Power: v_y i_y + v_z i_z = (v_y - v_z) i = 3/2 v_alphabeta . i_alphabeta,
//   so the line voltage is v_yz = 3/2 u . v_alphabeta (the star-point
//   voltage cancels in v_y - v_z: v_yz is the difference of the two pole
//   voltages of the inverter). With the stationary-frame machine
//     v_ab = R i_ab + d/dt psi_ab,
//     psi_ab = L(theta) i_ab + psi_f (cos theta, sin theta),
//     L(theta) = (Ld + Lq)/2 I + (Ld - Lq)/2 [cos 2th, sin 2th; sin 2th, -cos 2th]
//   (PmsmDq's dq equations written in alpha-beta) and u constant:
//     v_yz = 2 R i + d/dt (L_yz(theta) i) + e_yz
//   with
//     L_yz(theta)   = 3/2 u' L(theta) u = (Ld + Lq) + (Ld - Lq) cos 2(theta - phi)
//     psi_yz(theta) = 3/2 u' psi_f (cos, sin) = sqrt(3) psi_f cos(theta - phi)
//     e_yz          = omega_e dpsi_yz/dtheta = -sqrt(3) psi_f omega_e sin(theta - phi)
//   so, for the state,
//     L_yz di/dt = v_yz - 2 R i - e_yz - omega_e (dL_yz/dtheta) i.
//   With Ld = Lq = L (no saliency) L_yz = 2 L: the series circuit is 2R, 2L
//   (the synchronous inductance L = L_self - L_mutual appears once per
//   phase), time constant L/R. Saliency is supported: L_yz depends on the
//   angle, between 2 min(Ld, Lq) and 2 max(Ld, Lq), never 0.
//   Torque from the co-energy W' = 1/2 L_yz i^2 + psi_yz i:
//     tau_e = p (1/2 i^2 dL_yz/dtheta + i dpsi_yz/dtheta),
//   which equals PmsmDq's 3/2 p (psi_f i_q + (Ld - Lq) i_d i_q) at the dq
//   currents of i u (tests/sil/sim check both and the energy balance).
//   Mechanics as PmsmDq.
// As PmsmRotorFrame, cos/sin of theta_e are carried as states, so the
// derivative evaluates no trigonometric function.
//
// Entering the fault from a healthy state (from_rotor_frame): the break
// forces i_x to zero at once (the energy of an arc at the break is not
// modelled); the series current starts at (i_y - i_z)/2, the projection of
// the current vector on u.
//
// State x (index, name, unit):
//   0 i_a (= i_y = -i_z), 1 omega_m_rad_s, 2 theta_m_rad, 3 cos_theta_e_1,
//   4 sin_theta_e_1
// Input u: 0 v_yz_v (pole voltage of y minus pole voltage of z)
#ifndef MCSIM_PMSM_OPEN_PHASE_HPP
#define MCSIM_PMSM_OPEN_PHASE_HPP

#include <Eigen/Core>

#include "mcsim/pmsm_params.hpp"
#include "mcsim/pmsm_rotor_frame.hpp"
#include "mcsim/status.hpp"

namespace mcsim {

class PmsmOpenPhase {
 public:
  using State = Eigen::Matrix<double, 5, 1>;
  using Input = Eigen::Matrix<double, 1, 1>;
  enum : int { kI = 0, kOmegaM = 1, kThetaM = 2, kCos = 3, kSin = 4 };

  // Validates p and open_phase (0..2: kBadPhase otherwise); on error keeps
  // the previous configuration (default: phase a open, default PmsmParams).
  Status configure(const PmsmParams& p, int open_phase);
  const PmsmParams& params() const { return p_; }
  int open_phase() const { return x_; }
  int phase_y() const { return (x_ + 1) % 3; }  // carries +i
  int phase_z() const { return (x_ + 2) % 3; }  // carries -i

  State deriv(double t_s, const State& x, const Input& u) const {
    const double c = x(kCos), s = x(kSin);
    const double cr = c * cphi_ + s * sphi_;  // cos(theta_e - phi)
    const double sr = s * cphi_ - c * sphi_;  // sin(theta_e - phi)
    const double i = x(kI), wm = x(kOmegaM);
    const double we = pp_ * wm;
    const double l = lsum_ + ldiff_ * (cr * cr - sr * sr);
    const double dl = -4.0 * ldiff_ * sr * cr;      // dL_yz/dtheta_e
    const double dpsi = -kSqrt3 * p_.flux_wb * sr;  // dpsi_yz/dtheta_e
    const double tau_e = pp_ * (0.5 * i * i * dl + i * dpsi);
    State dx;
    dx(kI) = (u(0) - 2.0 * p_.R_ohm * i - we * dpsi - we * dl * i) / l;
    double net_nm = tau_e - p_.B_nms_rad * wm - p_.load.eval_nm(t_s, x(kThetaM), wm);
    if (cog_.active()) net_nm += cog_.torque_nm(x(kThetaM));
    dx(kOmegaM) = net_nm / p_.J_kgm2;
    dx(kThetaM) = wm;
    dx(kCos) = -we * s;
    dx(kSin) = we * c;
    return dx;
  }

  // L_yz(theta_e) [H], e_yz [V], electromagnetic torque [N m] at state x.
  double line_inductance_h(const State& x) const;
  double line_emf_v(const State& x) const;
  double torque_nm(const State& x) const;
  // Magnetic co-energy of the circuit, 1/2 L_yz i^2 [J] (for energy checks).
  double magnetic_energy_j(const State& x) const;
  // Phase currents (a, b, c): exactly 0 in the open phase, +i and -i in y, z.
  Eigen::Vector3d phase_currents_a(const State& x) const;
  // The state at the break: mechanics and (cos, sin) copied, the series
  // current projected (i_y - i_z)/2 = sqrt(3)/2 (i_d cos(th - phi) - i_q sin(th - phi)).
  State from_rotor_frame(const PmsmRotorFrame::State& xr) const;
  // The same machine state in PmsmRotorFrame's representation (dq currents
  // of i u at the state's angle).
  PmsmRotorFrame::State to_rotor_frame(const State& x) const;

  static constexpr double kSqrt3 = 1.7320508075688772;

 private:
  PmsmParams p_{};
  CoggingTorque cog_{};
  int x_ = 0;
  double pp_ = 4.0;
  double lsum_ = 2.0e-4, ldiff_ = 0.0;  // Ld + Lq, Ld - Lq
  double cphi_ = 0.0, sphi_ = 1.0;      // direction of u
};

}  // namespace mcsim

#endif  // MCSIM_PMSM_OPEN_PHASE_HPP
