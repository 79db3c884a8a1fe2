// mcsim/pmsm_params.hpp: physical parameters of a 3-phase PMSM, shared by the
// dq model (PmsmDq) and the alpha-beta model (PmsmAb).
//
// Conventions used by both models:
// - amplitude-invariant Clarke, so electrical power and torque carry 3/2:
//     P_in  = 3/2 (v_d i_d + v_q i_q)
//     tau_e = 3/2 p (flux i_q + (Ld - Lq) i_d i_q)
// - flux_wb is the peak PM flux linkage per phase (= ke in V s/rad_e);
// - theta_e = pole_pairs * theta_m, omega_e = pole_pairs * omega_m;
// - the load torque opposes positive rotation (see load_torque.hpp).
#ifndef MCSIM_PMSM_PARAMS_HPP
#define MCSIM_PMSM_PARAMS_HPP

#include "mcsim/cogging.hpp"
#include "mcsim/load_torque.hpp"
#include "mcsim/status.hpp"

namespace mcsim {

struct PmsmParams {
  double R_ohm = 0.1;     // stator resistance per phase
  double Ld_h = 1.0e-4;   // d-axis inductance
  double Lq_h = 1.0e-4;   // q-axis inductance (Ld != Lq: reluctance torque)
  double flux_wb = 0.01;  // PM flux linkage (peak, per phase); 0 allowed
  int pole_pairs = 4;
  double J_kgm2 = 1.0e-5;   // rotor + load inertia
  double B_nms_rad = 0.0;   // viscous friction
  LoadTorque load{};        // load torque model (plus optional Coulomb)
  CoggingParams cogging{};  // cogging torque (cogging.hpp); default none

  // kOk or the first failing check: kNotFinite, kNonPositiveResistance,
  // kNonPositiveInductance, kNegativeFlux, kBadPolePairs, kNonPositiveInertia,
  // kNegativeFriction, kBadLoad, kBadCogging.
  Status validate() const;
};

}  // namespace mcsim

#endif  // MCSIM_PMSM_PARAMS_HPP
