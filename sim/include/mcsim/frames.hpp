// mcsim/frames.hpp: reference-frame transforms of the simulator (its own,
// independent of firmware/kernels/transforms). Double precision, <cmath>.
//
// Clarke is amplitude-invariant: a balanced set of phase quantities of
// amplitude A maps to an alpha-beta vector of length A; power is then
// P = (3/2) (v_alpha i_alpha + v_beta i_beta) = (3/2) (v_d i_d + v_q i_q).
// Park rotates by the electrical angle theta_e_rad (d axis on the PM flux).
#ifndef MCSIM_FRAMES_HPP
#define MCSIM_FRAMES_HPP

#include <cmath>

#include <Eigen/Core>

namespace mcsim {

// (a, b, c) -> (alpha, beta); the zero-sequence part is discarded.
inline Eigen::Vector2d clarke(const Eigen::Vector3d& abc) {
  const double k_sqrt3 = std::sqrt(3.0);
  return Eigen::Vector2d((2.0 * abc(0) - abc(1) - abc(2)) / 3.0, (abc(1) - abc(2)) / k_sqrt3);
}

// (alpha, beta) -> (a, b, c) with zero common mode.
inline Eigen::Vector3d inverse_clarke(const Eigen::Vector2d& ab) {
  const double h = 0.5 * std::sqrt(3.0);
  return Eigen::Vector3d(ab(0), -0.5 * ab(0) + h * ab(1), -0.5 * ab(0) - h * ab(1));
}

// (alpha, beta) -> (d, q) at electrical angle theta_e_rad.
inline Eigen::Vector2d park(const Eigen::Vector2d& ab, double theta_e_rad) {
  const double c = std::cos(theta_e_rad);
  const double s = std::sin(theta_e_rad);
  return Eigen::Vector2d(c * ab(0) + s * ab(1), -s * ab(0) + c * ab(1));
}

// (d, q) -> (alpha, beta) at electrical angle theta_e_rad.
inline Eigen::Vector2d inverse_park(const Eigen::Vector2d& dq, double theta_e_rad) {
  const double c = std::cos(theta_e_rad);
  const double s = std::sin(theta_e_rad);
  return Eigen::Vector2d(c * dq(0) - s * dq(1), s * dq(0) + c * dq(1));
}

}  // namespace mcsim

#endif  // MCSIM_FRAMES_HPP
