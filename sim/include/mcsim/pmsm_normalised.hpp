// mcsim/pmsm_normalised.hpp: the normalised, non-salient PMSM used by Loria,
// Espinosa-Perez and Avila-Becerril ("A simple PI^2D output feedback
// controller for the PMSM"), eqs. (1)-(4):
//
//   x1' = -x1 + x2 x3 + u1
//   x2' = -x2 - x1 x3 - gamma x3 + u2
//   x3' = sigma x2 - tau_l
//   x4' = x3
//
// State x = (x1, x2, x3, x4), input u = (u1, u2), all dimensionless; time is
// the normalised time t_n. Parameters: sigma (torque gain), gamma (back-EMF
// gain), tau_l (normalised load, constant).
//
// Mapping to the physical dq model (re-derived from the paper's vector model
// L di/dt = -R i - w_e flux J rho - w_e J L i + V with J = [[0,-1],[1,0]],
// rho = [1,0]^T, which expands to the PmsmDq equations with Ld = Lq = L; the
// paper's speed in the electrical equations is the ELECTRICAL speed):
// choose a current base I_b [A] and let T = L/R [s] (time base). Then
//   t_n   = t / T
//   x1    = i_d / I_b,   x2 = i_q / I_b
//   x3    = omega_e T = p omega_m L/R
//   x4    = theta_e  = p theta_m
//   u1,u2 = v_d/(R I_b), v_q/(R I_b)
//   gamma = flux / (L I_b)
//   sigma = (3/2) p^2 flux I_b T^2 / J   (3/2: amplitude-invariant torque)
//   tau_l = p T^2 tau_load / J
// which requires Ld = Lq and B = 0 (the paper neglects viscous friction).
// With R = L = p = J = 1 and I_b = 1: x = (i_d, i_q, omega_m, theta_m),
// u = (v_d, v_q), gamma = flux, sigma = 1.5 flux, tau_l = tau_load.
// (The paper's own sigma = n_p flux / J has no 3/2: it uses a power-invariant
// or per-phase torque; sigma and gamma are free parameters of the model.)
#ifndef MCSIM_PMSM_NORMALISED_HPP
#define MCSIM_PMSM_NORMALISED_HPP

#include <Eigen/Core>

#include "mcsim/pmsm_params.hpp"
#include "mcsim/status.hpp"

namespace mcsim {

struct PmsmNormalisedParams {
  double sigma = 1.0;  // > 0
  double gamma = 1.0;  // >= 0
  double tau_l = 0.0;  // any finite value

  // kOk, kNotFinite, kNonPositiveTorqueConstant (sigma <= 0), kNegativeFlux
  // (gamma < 0).
  Status validate() const;
};

class PmsmNormalised {
 public:
  using State = Eigen::Matrix<double, 4, 1>;
  using Input = Eigen::Matrix<double, 2, 1>;

  PmsmNormalised() = default;
  // Validates p; on error returns the code and keeps the previous parameters.
  Status configure(const PmsmNormalisedParams& p);
  const PmsmNormalisedParams& params() const { return p_; }

  // t_n is the normalised time (unused: the model is autonomous).
  State deriv(double t_n, const State& x, const Input& u) const;

 private:
  PmsmNormalisedParams p_{};
};

// Base values of the mapping above and the resulting normalised parameters.
struct PmsmNormalisedScaling {
  double t_base_s = 1.0;            // T = L/R
  double i_base_a = 1.0;            // I_b
  double v_base_v = 1.0;            // R I_b
  double omega_e_base_rad_s = 1.0;  // 1/T
  PmsmNormalisedParams params{};
};

// Builds the scaling of a physical machine with Ld == Lq and B == 0 for a
// constant load tau_load_nm. Errors: the PmsmParams::validate() codes,
// kNonSalientRequired (Ld != Lq or B != 0), kBadBase (i_base_a <= 0 or not
// finite, or out == nullptr), kNonPositiveTorqueConstant (flux == 0 gives sigma = 0).
// *out is written only on kOk.
Status make_normalised_scaling(const PmsmParams& phys, double i_base_a, double tau_load_nm,
                               PmsmNormalisedScaling* out);

}  // namespace mcsim

#endif  // MCSIM_PMSM_NORMALISED_HPP
