// mcsim/stepper_2ph.hpp: two-phase permanent-magnet stepper motor, model of
// Seshagiri and Khalil ("Position control of a PMSM using conditional
// integrators"), eq. (1), re-derived from the phase flux linkages
//   lambda_a = L i_a + (K_m/N_r) cos(N_r th),  lambda_b = L i_b + (K_m/N_r) sin(N_r th)
// (co-energy torque tau = i_a dlambda_a/dth + i_b dlambda_b/dth):
//
//   L di_a/dt = v_a - R i_a + K_m w sin(N_r th)
//   L di_b/dt = v_b - R i_b - K_m w cos(N_r th)
//   J dw/dt   = -K_m i_a sin(N_r th) + K_m i_b cos(N_r th) - B w - load(t, th, w)
//   dth/dt    = w
//
// The paper prints "+ K_m w cos(N_r th)" in the phase-b equation; that sign
// breaks energy conservation (back-EMF must equal dlambda/dt, the torque of the
// same equation fixes lambda_b) and disagrees with its own dq form (2)
// (x2' = ... - k2 x3, i.e. -K_m w/L on the q axis). The minus sign is used here.
// The paper's "tau_L = 0.2 kg" is a torque in N m. Neglected as in the paper:
// mutual inductance, detent torque, saturation, inductance variation.
//
// State x (index, name, unit):
//   0 i_a_a           phase-A current           [A]
//   1 i_b_a           phase-B current           [A]
//   2 omega_m_rad_s   shaft speed               [rad/s]
//   3 theta_m_rad     shaft angle               [rad] (not wrapped)
// Input u:
//   0 v_a_v           phase-A winding voltage   [V]
//   1 v_b_v           phase-B winding voltage   [V]
#ifndef MCSIM_STEPPER_2PH_HPP
#define MCSIM_STEPPER_2PH_HPP

#include <Eigen/Core>

#include "mcsim/load_torque.hpp"
#include "mcsim/status.hpp"

namespace mcsim {

struct Stepper2PhParams {
  // Defaults: the paper's simulation values (R and L the "actual" ones).
  double R_ohm = 19.0;
  double L_h = 0.040;
  double Km_nm_a = 0.1349;  // torque constant = back-EMF constant [V s/rad]
  int rotor_teeth = 50;     // N_r
  double J_kgm2 = 4.1295e-4;
  double B_nms_rad = 0.0013;
  LoadTorque load{};

  // kOk, kNotFinite, kNonPositiveResistance, kNonPositiveInductance,
  // kNonPositiveTorqueConstant, kBadTeeth, kNonPositiveInertia,
  // kNegativeFriction, kBadLoad.
  Status validate() const;
};

class Stepper2Ph {
 public:
  using State = Eigen::Matrix<double, 4, 1>;
  using Input = Eigen::Matrix<double, 2, 1>;
  enum : int { kIa = 0, kIb = 1, kOmegaM = 2, kThetaM = 3 };
  enum : int { kVa = 0, kVb = 1 };

  Stepper2Ph() = default;
  // Validates p; on error returns the code and keeps the previous parameters.
  Status configure(const Stepper2PhParams& p);
  const Stepper2PhParams& params() const { return p_; }

  State deriv(double t_s, const State& x, const Input& u) const;

  double torque_nm(const State& x) const;  // electromagnetic
  double load_nm(double t_s, const State& x) const;
  double input_power_w(const State& x, const Input& u) const;  // v_a i_a + v_b i_b
  double copper_loss_w(const State& x) const;                  // R (i_a^2 + i_b^2)
  double magnetic_energy_j(const State& x) const;              // L/2 (i_a^2 + i_b^2)
  double kinetic_energy_j(const State& x) const;               // J/2 w^2

 private:
  Stepper2PhParams p_{};
};

}  // namespace mcsim

#endif  // MCSIM_STEPPER_2PH_HPP
