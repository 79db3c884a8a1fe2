// The CSMC loop around the simulated stepper (see csmc_loop.hpp).
#include "csmc_loop.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "csmc/mc_csvc.h"
#include "csmc/mc_stepper_dq.h"
#include "mc_ctrl_csmc.h"
#include "mcsim/integrator.hpp"
#include "mcsim/stepper_2ph.hpp"
#include "scenario.hpp"

namespace mcsim {
namespace csmc {

mc_csmc_f32_cfg_t paper_ctrl(bool model_law, bool integrators, bool ideal) {
  mc_csmc_f32_cfg_t c{};
  c.law = model_law ? MC_CSMC_LAW_MODEL : MC_CSMC_LAW_CONST;
  c.sw = ideal ? MC_CSMC_SW_SGN : MC_CSMC_SW_SAT;
  c.k1_per_s2 = 7.5e4f;
  c.k2_per_s = 550.0f;
  c.mu1_a = 0.1f;
  c.mu2_rad_s2 = 50.0f;
  const float k01 = 20.0f, k02 = 100.0f;
  if (integrators) {
    if (mc_csvc_f32_integrator(k01, &c.sigma1) != MC_CSVC_ERR_NONE ||
        mc_csvc_f32_integrator(k02, &c.sigma2) != MC_CSVC_ERR_NONE) {
      throw std::runtime_error("conditional integrator rejected");
    }
  }
  c.m1_v = 50.0f;
  c.m2_v = 50.0f;
  mc_csmc_f32_model_t& m = c.model;
  m.km_nm_a = 0.1349f;
  m.j_kgm2 = 4.1295e-4f;
  m.b_nms_rad = 0.0013f;
  m.rotor_teeth = 50u;
  m.tau_load_nm = 0.2f;
  m.r_nom_ohm = 20.0f;
  m.r_min_ohm = 19.0f;
  m.r_max_ohm = 21.0f;
  m.l_nom_h = 0.035f;
  m.l_min_h = 0.030f;
  m.l_max_h = 0.040f;
  // q_i = 2.1 k0^i mu_i L^M (paper Sec. III)
  m.q1_v = 2.1f * k01 * c.mu1_a * m.l_max_h;
  m.q2_radh_s3 = 2.1f * k02 * c.mu2_rad_s2 * m.l_max_h;
  c.v_limit_v = 1.0e4f;  // the paper's laws have no voltage limit
  c.dt_s = 1.0e-5f;
  return c;
}

mc_hgo_f32_cfg_t paper_hgo(double eps_s) {
  mc_hgo_f32_cfg_t h{};
  h.alpha1 = 17.0f;
  h.alpha2 = 80.0f;
  h.alpha3 = 100.0f;
  h.eps_s = static_cast<float>(eps_s);
  h.dt_s = 1.0e-5f;
  h.input_order = 2u;  // parabolic input model between samples (mc_hgo.h)
  return h;
}

void paper_servo(double w0_rad_s, mc_csmc_f32_cfg_t* cfg) {
  const float w0 = static_cast<float>(w0_rad_s);
  const float w02 = w0 * w0;
  // S1 last row (0, -4 w0^4, 0, -5 w0^2, 0), S2 last row (0, -w0^2, 0).
  const float c1[5] = {0.0f, -4.0f * w02 * w02, 0.0f, -5.0f * w02, 0.0f};
  const float re1[5] = {-1.0f, -2.0f, -2.0f, -3.0f, -3.0f};
  const float im1[5] = {0.0f, 1.0f, -1.0f, 1.0f, -1.0f};
  const float c2[3] = {0.0f, -w02, 0.0f};
  const float re2[3] = {-1.0f, -2.0f, -2.0f};
  const float im2[3] = {0.0f, 1.0f, -1.0f};
  if (mc_csvc_f32_place(5u, c1, re1, im1, &cfg->sigma1) != MC_CSVC_ERR_NONE ||
      mc_csvc_f32_place(3u, c2, re2, im2, &cfg->sigma2) != MC_CSVC_ERR_NONE) {
    throw std::runtime_error("servocompensator pole placement rejected");
  }
}

namespace {

struct Ref {
  double phi, dphi, ddphi, dddphi;
};

Ref reference(const LoopOptions& o, double t) {
  Ref r{0.0, 0.0, 0.0, 0.0};
  if (o.ref == RefKind::kSteps) {
    // Steps: derivatives are impulses at the jumps, taken as zero (the
    // paper's phi_d is piecewise constant).
    r.phi = (t >= 0.0 ? o.step_rad : 0.0) +
            ((o.step2_t_s >= 0.0 && t >= o.step2_t_s) ? o.step_rad : 0.0);
  } else {
    const double w = o.w0_rad_s, a = o.r0_rad;
    const double c = std::cos(w * t), s = std::sin(w * t);
    r.phi = a * c;
    r.dphi = -a * w * s;
    r.ddphi = -a * w * w * c;
    r.dddphi = a * w * w * w * s;
  }
  return r;
}

}  // namespace

LoopResult run_loop(const LoopOptions& o) {
  std::vector<Sample> trace;
  const long n = step_count(o.duration_s, o.dt_s);
  trace.reserve(static_cast<size_t>(n) / std::max<size_t>(1, o.record_every) + 2);
  LoopResult r = run_loop(o, [&trace](const Sample& s) { trace.push_back(s); });
  r.trace = std::move(trace);
  return r;
}

LoopResult run_loop(const LoopOptions& o, const SampleFn& on_sample) {
  Stepper2PhParams p;
  p.R_ohm = o.plant.R_ohm;
  p.L_h = o.plant.L_h;
  p.Km_nm_a = o.plant.Km_nm_a;
  p.J_kgm2 = o.plant.J_kgm2;
  p.B_nms_rad = o.plant.B_nms_rad;
  p.rotor_teeth = o.plant.rotor_teeth;
  p.load = load_constant(o.plant.tau_load_nm);
  Stepper2Ph plant;
  if (plant.configure(p) != Status::kOk) throw std::runtime_error("stepper parameters rejected");
  if (!(o.dt_s > 0.0) || o.substeps < 1 || !(o.duration_s > 0.0)) {
    throw std::runtime_error("bad loop timing");
  }

  // The loop is the drive's plug-in (firmware/app/ctrl/mc_ctrl_csmc), its
  // step called on the plant's measurements (the drive and its encoder
  // are left out: the paper's loop measures exactly).
  mc_ctrl_csmc_cfg_t cc{};
  cc.law = o.ctrl;
  cc.law.dt_s = static_cast<float>(o.dt_s);
  cc.feedback = (o.fb == Feedback::kHgo) ? MC_CTRL_CSMC_FB_HGO : MC_CTRL_CSMC_FB_STATE;
  cc.hgo = o.hgo;
  cc.hgo.dt_s = cc.law.dt_s;
  cc.duty_max = 1.0f;  // unused: no bridge here
  mc_ctrl_csmc_t ctrl{};
  const uint32_t ce = mc_ctrl_csmc_init(&ctrl, &cc);
  if (ce != MC_CTRL_CSMC_ERR_NONE) {
    throw std::runtime_error("csmc config rejected, error bits " + std::to_string(ce));
  }
  const uint32_t nr = static_cast<uint32_t>(o.plant.rotor_teeth);

  LoopResult res;
  const long n = step_count(o.duration_s, o.dt_s);
  const size_t every = std::max<size_t>(1, o.record_every);
  Stepper2Ph::State x = Stepper2Ph::State::Zero();
  const mc_ctrl_csmc_tm_t& tm = ctrl.tm;
  for (long k = 0; k <= n; ++k) {
    const double t = static_cast<double>(k) * o.dt_s;
    const Ref r = reference(o, t);
    if (mc_ctrl_csmc_set_ref(&ctrl, static_cast<float>(r.phi), static_cast<float>(r.dphi),
                             static_cast<float>(r.ddphi), static_cast<float>(r.dddphi), 0.0f,
                             0.0f) != MC_CTRL_CSMC_ERR_NONE) {
      throw std::runtime_error("reference refused");
    }
    // Measurements at t_k (float, as the firmware sees them); e2 formed in
    // double and rounded once (a small number, full precision).
    mc_ctrl_csmc_meas_t m{};
    m.ia_a = static_cast<float>(x(Stepper2Ph::kIa));
    m.ib_a = static_cast<float>(x(Stepper2Ph::kIb));
    m.omega_m_rad_s = static_cast<float>(x(Stepper2Ph::kOmegaM));
    m.phi_rad = static_cast<float>(x(Stepper2Ph::kThetaM));
    m.theta_e_rad = mc_stepper_theta_e_f32(m.phi_rad, nr);
    m.e2_rad = static_cast<float>(x(Stepper2Ph::kThetaM) - r.phi);
    if (mc_ctrl_csmc_step(&ctrl, &m) != MC_CTRL_CSMC_ERR_NONE) {
      throw std::runtime_error("csmc step refused an input");
    }

    if (k % static_cast<long>(every) == 0 || k == n) {
      res.last = Sample{t,
                        tm.in.e1_a,
                        tm.in.e2_rad,
                        tm.i_d_a,
                        tm.i_q_a,
                        m.omega_m_rad_s,
                        x(Stepper2Ph::kThetaM),
                        tm.out.v_d_v,
                        tm.out.v_q_v,
                        tm.est.z1,
                        tm.est.z2,
                        tm.est.z3,
                        tm.out.s1_a,
                        tm.out.s2_rad_s2,
                        r.phi};
      on_sample(res.last);
    }
    if (k == n) {
      res.t_end = t;
      res.e2_end = x(Stepper2Ph::kThetaM) - r.phi;
      break;
    }
    const Stepper2Ph::Input u(static_cast<double>(tm.v_a_v), static_cast<double>(tm.v_b_v));
    if (advance_zoh(plant, u, t, o.dt_s, o.substeps, &x) != Status::kOk) {
      throw std::runtime_error("integration failed");
    }
    if (!x.allFinite()) throw std::runtime_error("plant state diverged");
  }
  return res;
}

StepAcc::StepAcc(double t_from, double t_to, double phi_final_rad, double step_rad)
    : t_from_(t_from),
      t_to_(t_to),
      phi_final_(phi_final_rad),
      step_(step_rad),
      sgn_(step_rad >= 0.0 ? 1.0 : -1.0),
      band_(0.02 * std::abs(step_rad)),
      last_out_(t_from) {}

void StepAcc::add(const Sample& s) {
  if (s.t < t_from_ || s.t > t_to_) return;
  const double d = s.x4 - phi_final_;
  over_ = std::max(over_, sgn_ * d);
  if (std::abs(d) > band_) last_out_ = s.t;
}

StepMetrics StepAcc::result() const {
  StepMetrics m;
  m.overshoot_frac = over_ / std::abs(step_);
  m.settling_s = last_out_ - t_from_;
  return m;
}

StepMetrics step_metrics(const std::vector<Sample>& tr, double t_from, double t_to,
                         double phi_final_rad, double step_rad) {
  StepAcc a(t_from, t_to, phi_final_rad, step_rad);
  for (const Sample& s : tr) a.add(s);
  return a.result();
}

void WindowAcc::add(const Sample& s) {
  if (s.t < t_from_ || s.t > t_to_) return;
  const double v = s.*field_;
  if (n_ == 0) {
    lo_ = hi_ = v;
    t0_ = s.t;
  } else if ((v > 0.0 && prev_ < 0.0) || (v < 0.0 && prev_ > 0.0)) {
    ++changes_;
  }
  if (v != 0.0) prev_ = v;
  lo_ = std::min(lo_, v);
  hi_ = std::max(hi_, v);
  w_.max_abs = std::max(w_.max_abs, std::abs(v));
  sum_ += v;
  sum2_ += v * v;
  t1_ = s.t;
  ++n_;
}

WindowStats WindowAcc::result() const {
  WindowStats w = w_;
  if (n_ > 0) {
    w.mean = sum_ / static_cast<double>(n_);
    w.rms = std::sqrt(sum2_ / static_cast<double>(n_));
    w.peak_to_peak = hi_ - lo_;
    if (t1_ > t0_) w.sign_changes_per_s = static_cast<double>(changes_) / (t1_ - t0_);
  }
  return w;
}

WindowStats window_stats(const std::vector<Sample>& tr, double Sample::*field, double t_from,
                         double t_to) {
  WindowAcc a(field, t_from, t_to);
  for (const Sample& s : tr) a.add(s);
  return a.result();
}

}  // namespace csmc
}  // namespace mcsim
