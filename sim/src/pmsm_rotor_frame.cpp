#include "mcsim/pmsm_rotor_frame.hpp"

#include <cmath>

namespace mcsim {

Status PmsmRotorFrame::configure(const PmsmParams& p) {
  const Status st = dq_.configure(p);
  if (st != Status::kOk) return st;
  pp_ = static_cast<double>(p.pole_pairs);
  kt_ = 1.5 * pp_;
  inv_ld_ = 1.0 / p.Ld_h;
  inv_lq_ = 1.0 / p.Lq_h;
  inv_j_ = 1.0 / p.J_kgm2;
  load_is_const_ = p.load.kind == LoadKind::kConstant && !(p.load.coulomb_nm > 0.0);
  const_load_nm_ = p.load.tau0_nm;
  return Status::kOk;
}

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
