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
  load_is_const_ =
      p.load.kind == LoadKind::kConstant && !(p.load.coulomb_nm > 0.0) && !dq_.cogging().active();
  const_load_nm_ = p.load.tau0_nm;
  plan_period_s_ = 0.0;  // step constants depend on the parameters: re-plan
  plan_n_sub_ = 0;
  return Status::kOk;
}

Status PmsmRotorFrame::set_electrical(double r_ohm, double flux_wb) {
  const Status st = dq_.set_electrical(r_ohm, flux_wb);
  if (st == Status::kOk) plan_period_s_ = 0.0;  // the step constants depend on R, flux
  return st;
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

void PmsmRotorFrame::plan_steps(double period_s, int n_sub) {
  const PmsmParams& p = dq_.params();
  const double h = period_s / static_cast<double>(n_sub);
  const double sigmas[3] = {0.5 * h, h, h / 6.0};
  for (int k = 0; k < 3; ++k) {
    StageConsts& c = stage_[k];
    const double sg = sigmas[k];
    c.sigma = sg;
    c.v_d = sg * inv_ld_;
    c.v_q = sg * inv_lq_;
    c.r_d = c.v_d * p.R_ohm;
    c.x_d = c.v_d * pp_ * p.Lq_h;
    c.r_q = c.v_q * p.R_ohm;
    c.x_q = c.v_q * pp_ * p.Ld_h;
    c.f_q = c.v_q * pp_ * p.flux_wb;
    c.inv_j = sg * inv_j_;
    c.t_1 = c.inv_j * kt_ * p.flux_wb;
    c.t_2 = c.inv_j * kt_ * (p.Ld_h - p.Lq_h);
    c.b = c.inv_j * p.B_nms_rad;
    c.l = c.inv_j * const_load_nm_;
    c.w_e = sg * pp_;
  }
  plan_period_s_ = period_s;
  plan_n_sub_ = n_sub;
}

template <bool kConstLoad>
PmsmRotorFrame::Y6 PmsmRotorFrame::rk4_substeps(const Y6& y0, const Input& u, double t0_s,
                                                int n_sub) const {
  using Y = Y6;
  const auto add = [](const Y& a, const Y& b) -> Y {
    return {a.id + b.id, a.iq + b.iq, a.wm + b.wm, a.th + b.th, a.c + b.c, a.s + b.s};
  };
  // (a + 2 b + c) / 3, the part of the RK4 weights known before stage 4.
  const auto weigh3 = [](const Y& a, const Y& b, const Y& c) -> Y {
    constexpr double k3 = 1.0 / 3.0;
    return {((a.id + (b.id + b.id)) + c.id) * k3, ((a.iq + (b.iq + b.iq)) + c.iq) * k3,
            ((a.wm + (b.wm + b.wm)) + c.wm) * k3, ((a.th + (b.th + b.th)) + c.th) * k3,
            ((a.c + (b.c + b.c)) + c.c) * k3,     ((a.s + (b.s + b.s)) + c.s) * k3};
  };
  const PmsmParams& p = dq_.params();
  const CoggingTorque& cog = dq_.cogging();
  const double h = stage_[1].sigma;
  const double half = stage_[0].sigma;
  // The input terms, constant over the period (ZOH): sigma/L times v.
  double ad[3], bd[3], aq[3], bq[3];
  for (int k = 0; k < 3; ++k) {
    ad[k] = stage_[k].v_d * u(0);
    bd[k] = stage_[k].v_d * u(1);
    aq[k] = stage_[k].v_q * u(0);
    bq[k] = stage_[k].v_q * u(1);
  }
  // g = sigma_k f(t, y): deriv() times the stage's step factor, with
  //   v_d = c v_alpha + s v_beta,  v_q = c v_beta - s v_alpha.
  const auto stage = [&](const Y& y, int k, double t_s) -> Y {
    const StageConsts& c = stage_[k];
    double l = kConstLoad ? c.l : c.inv_j * p.load.eval_nm(t_s, y.th, y.wm);
    if (!kConstLoad && cog.active()) l -= c.inv_j * cog.torque_nm(y.th);
    const double w = c.w_e * y.wm;
    Y g;
    g.id = (y.c * ad[k] + y.s * bd[k]) + (c.x_d * (y.wm * y.iq) - c.r_d * y.id);
    g.iq = (y.c * bq[k] - y.s * aq[k]) - (c.r_q * y.iq + y.wm * (c.x_q * y.id + c.f_q));
    g.wm = y.iq * (c.t_1 + c.t_2 * y.id) - (c.b * y.wm + l);
    g.th = c.sigma * y.wm;
    g.c = -(w * y.s);
    g.s = w * y.c;
    return g;
  };
  Y y = y0;
  for (int j = 0; j < n_sub; ++j) {
    // t from the step index (no accumulated round-off in time).
    const double t_s = t0_s + static_cast<double>(j) * h;
    const Y g1 = stage(y, 0, t_s);                  // (h/2) k1
    const Y g2 = stage(add(y, g1), 0, t_s + half);  // (h/2) k2
    const Y g3 = stage(add(y, g2), 1, t_s + half);  // h k3
    const Y part = add(y, weigh3(g1, g2, g3));      // x + (h/6)(k1 + 2 k2 + 2 k3)
    const Y g4 = stage(add(y, g3), 2, t_s + h);     // (h/6) k4
    y = add(part, g4);
  }
  return y;
}

Status PmsmRotorFrame::advance_zoh(const Input& u, double t0_s, double period_s, int n_sub,
                                   State* x) {
  if (n_sub < 1) {
    return Status::kBadStepCount;
  }
  if (!std::isfinite(period_s) || !(period_s > 0.0)) {
    return Status::kBadPeriod;
  }
  if (!std::isfinite(t0_s) || x == nullptr) {
    return Status::kNotFinite;
  }
  if (period_s != plan_period_s_ || n_sub != plan_n_sub_) {
    plan_steps(period_s, n_sub);
  }
  const Y6 y0{(*x)(kId), (*x)(kIq), (*x)(kOmegaM), (*x)(kThetaM), (*x)(kCos), (*x)(kSin)};
  // Two instantiations so that the constant-load loop carries no load call
  // and no branch per stage.
  const Y6 y = load_is_const_ ? rk4_substeps<true>(y0, u, t0_s, n_sub)
                              : rk4_substeps<false>(y0, u, t0_s, n_sub);
  *x << y.id, y.iq, y.wm, y.th, y.c, y.s;
  return Status::kOk;
}

}  // namespace mcsim
