// mcsim/pmsm_dq.hpp: PMSM in the rotor (dq) frame, physical units.
//
// State x (index, name, unit):
//   0 i_d_a           d-axis current            [A]
//   1 i_q_a           q-axis current            [A]
//   2 omega_m_rad_s   mechanical speed          [rad/s]
//   3 theta_m_rad     mechanical angle          [rad] (not wrapped)
// Input u:
//   0 v_d_v           d-axis voltage            [V]
//   1 v_q_v           q-axis voltage            [V]
//
// Equations (omega_e = p omega_m, amplitude-invariant dq):
//   Ld di_d/dt = v_d - R i_d + omega_e Lq i_q
//   Lq di_q/dt = v_q - R i_q - omega_e (Ld i_d + flux)
//   J dw_m/dt  = 3/2 p (flux i_q + (Ld - Lq) i_d i_q) + cog(th_m) - B w_m
//                - load(t, th_m, w_m)     (cog: cogging.hpp, 0 by default)
//   dth_m/dt   = w_m
#ifndef MCSIM_PMSM_DQ_HPP
#define MCSIM_PMSM_DQ_HPP

#include <Eigen/Core>

#include "mcsim/pmsm_params.hpp"
#include "mcsim/status.hpp"

namespace mcsim {

class PmsmDq {
 public:
  using State = Eigen::Matrix<double, 4, 1>;
  using Input = Eigen::Matrix<double, 2, 1>;
  enum : int { kId = 0, kIq = 1, kOmegaM = 2, kThetaM = 3 };
  enum : int { kVd = 0, kVq = 1 };

  PmsmDq() = default;  // default PmsmParams (valid)
  // Validates p; on error returns the code and keeps the previous parameters.
  Status configure(const PmsmParams& p);
  const PmsmParams& params() const { return p_; }
  // Resistance and PM flux only (e.g. from a thermal model); the same
  // checks as configure() (kNonPositiveResistance, kNegativeFlux,
  // kNotFinite), nothing changed on error.
  Status set_electrical(double r_ohm, double flux_wb);
  const CoggingTorque& cogging() const { return cog_; }

  State deriv(double t_s, const State& x, const Input& u) const;

  double torque_nm(const State& x) const;            // electromagnetic
  double load_nm(double t_s, const State& x) const;  // load model incl. Coulomb
  double cogging_nm(const State& x) const { return cog_.torque_nm(x(kThetaM)); }
  double cogging_energy_j(const State& x) const { return cog_.energy_j(x(kThetaM)); }
  double input_power_w(const State& x, const Input& u) const;  // 3/2 v.i
  double copper_loss_w(const State& x) const;                  // 3/2 R |i|^2
  double magnetic_energy_j(const State& x) const;              // 3/4 (Ld id^2 + Lq iq^2)
  double kinetic_energy_j(const State& x) const;               // 1/2 J w^2

 private:
  PmsmParams p_{};
  CoggingTorque cog_{};
};

}  // namespace mcsim

#endif  // MCSIM_PMSM_DQ_HPP
