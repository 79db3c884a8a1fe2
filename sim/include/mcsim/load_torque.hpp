// mcsim/load_torque.hpp: load torque models shared by every plant.
//
// A small value type (no heap, no std::function): a kind enum plus the
// parameters of each kind, and an optional plain function pointer with a
// context pointer for anything else. Coulomb friction can be added to any
// kind.
//
// Sign convention: the load torque OPPOSES positive rotation. Every plant uses
//   J * d(omega_m)/dt = tau_e - B * omega_m - load.eval_nm(t, theta_m, omega_m)
// so a positive constant load brakes a motor that spins forward.
#ifndef MCSIM_LOAD_TORQUE_HPP
#define MCSIM_LOAD_TORQUE_HPP

#include "mcsim/status.hpp"

namespace mcsim {

enum class LoadKind : int {
  kConstant = 0,  // tau = tau0_nm
  kStep,          // tau = tau0_nm, plus tau_step_nm from t >= step_time_s
  kAngleSpeed,    // tau = tau0_nm + k_omega*w + k_omega2*w*|w|
                  //       + ripple_nm*sin(ripple_per_rev*theta + ripple_phase_rad)
  kFunction,      // tau = fn(t, theta, omega, fn_ctx)
};

// User load: must be pure (same inputs, same result) so RK4 stages agree.
using LoadFn = double (*)(double t_s, double theta_m_rad, double omega_m_rad_s, const void* ctx);

struct LoadTorque {
  LoadKind kind = LoadKind::kConstant;
  double tau0_nm = 0.0;
  double step_time_s = 0.0;         // kStep
  double tau_step_nm = 0.0;         // kStep: added at t >= step_time_s
  double k_omega_nms_rad = 0.0;     // kAngleSpeed: linear in speed
  double k_omega2_nms2_rad2 = 0.0;  // kAngleSpeed: fan/pump law w*|w|
  double ripple_nm = 0.0;           // kAngleSpeed: angle-periodic amplitude
  double ripple_per_rev = 0.0;      // kAngleSpeed: periods per mech. turn
  double ripple_phase_rad = 0.0;    // kAngleSpeed
  LoadFn fn = nullptr;              // kFunction
  const void* fn_ctx = nullptr;     // kFunction: passed to fn
  // Coulomb friction (any kind): coulomb_nm * sat(omega / coulomb_band_rad_s),
  // linear inside the band so the ODE stays continuous at omega = 0.
  double coulomb_nm = 0.0;
  double coulomb_band_rad_s = 1.0e-3;

  // Total load torque [N m] (model plus Coulomb friction).
  double eval_nm(double t_s, double theta_m_rad, double omega_m_rad_s) const;
  // kOk, kNotFinite, kNegativeFriction or kBadLoad.
  Status validate() const;
};

// Convenience constructors.
LoadTorque load_constant(double tau_nm);
LoadTorque load_step(double tau_before_nm, double step_time_s, double tau_after_nm);

}  // namespace mcsim

#endif  // MCSIM_LOAD_TORQUE_HPP
