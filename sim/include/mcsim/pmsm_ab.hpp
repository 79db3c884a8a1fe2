// mcsim/pmsm_ab.hpp: the same PMSM as PmsmDq, in the stationary (alpha-beta)
// frame. Ld != Lq is supported: the stator inductance matrix depends on the
// electrical angle theta_e = p theta_m.
//
// State x (index, name, unit):
//   0 i_alpha_a       alpha current             [A]
//   1 i_beta_a        beta current              [A]
//   2 omega_m_rad_s   mechanical speed          [rad/s]
//   3 theta_m_rad     mechanical angle          [rad] (not wrapped)
// Input u:
//   0 v_alpha_v       alpha voltage             [V]
//   1 v_beta_v        beta voltage              [V]
//
// Flux linkage: lambda = L(theta_e) i + flux [cos theta_e, sin theta_e]^T with
//   L(theta_e) = L0 I + L2 [[cos 2th, sin 2th], [sin 2th, -cos 2th]],
//   L0 = (Ld + Lq)/2, L2 = (Ld - Lq)/2   (det L = Ld Lq > 0).
// Voltage equation d(lambda)/dt = v - R i gives
//   L(th) di/dt = v - R i - omega_e dL/dth i - omega_e flux [-sin th, cos th]^T
// Torque: tau_e = 3/2 p (lambda_alpha i_beta - lambda_beta i_alpha).
// Mechanics and load as in PmsmDq.
#ifndef MCSIM_PMSM_AB_HPP
#define MCSIM_PMSM_AB_HPP

#include <Eigen/Core>

#include "mcsim/pmsm_params.hpp"
#include "mcsim/status.hpp"

namespace mcsim {

class PmsmAb {
 public:
  using State = Eigen::Matrix<double, 4, 1>;
  using Input = Eigen::Matrix<double, 2, 1>;
  enum : int { kIalpha = 0, kIbeta = 1, kOmegaM = 2, kThetaM = 3 };
  enum : int { kValpha = 0, kVbeta = 1 };

  PmsmAb() = default;
  // Validates p; on error returns the code and keeps the previous parameters.
  Status configure(const PmsmParams& p);
  const PmsmParams& params() const { return p_; }

  State deriv(double t_s, const State& x, const Input& u) const;

  // Stator inductance matrix L(theta_e) [H].
  Eigen::Matrix2d inductance_h(double theta_e_rad) const;
  // Total stator flux linkage (alpha, beta) [Wb].
  Eigen::Vector2d flux_linkage_wb(const State& x) const;
  double torque_nm(const State& x) const;
  double load_nm(double t_s, const State& x) const;
  double input_power_w(const State& x, const Input& u) const;  // 3/2 v.i
  double copper_loss_w(const State& x) const;                  // 3/2 R |i|^2
  double magnetic_energy_j(const State& x) const;              // 3/4 i^T L i
  double kinetic_energy_j(const State& x) const;               // 1/2 J w^2

 private:
  PmsmParams p_{};
  CoggingTorque cog_{};
};

}  // namespace mcsim

#endif  // MCSIM_PMSM_AB_HPP
