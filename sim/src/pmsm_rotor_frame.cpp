#include "mcsim/pmsm_rotor_frame.hpp"

#include <cmath>

namespace mcsim {

PmsmRotorFrame::State PmsmRotorFrame::make_state(double id_a, double iq_a, double omega_m,
                                                 double theta_m) const {
  State x;
  x << id_a, iq_a, omega_m, theta_m, 0.0, 0.0;
  resync(&x);
  return x;
}

void PmsmRotorFrame::resync(State* x) const {
  const double th_e = dq_.params().pole_pairs * (*x)(kThetaM);
  (*x)(kCos) = std::cos(th_e);
  (*x)(kSin) = std::sin(th_e);
}

}  // namespace mcsim
