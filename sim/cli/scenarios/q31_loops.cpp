// Closed loops with the q31 kernels; see q31_loops.hpp.
#include "scenarios/q31_loops.hpp"

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "hal_host/pmsm_board.hpp"
#include "hal_host/sil_rig.hpp"
#include "mcsim/integrator.hpp"
#include "mcsim/pmsm_normalised.hpp"
#include "mcsim/stepper_2ph.hpp"
#include "scenario.hpp"
#include "spill.hpp"
#include "verdict.hpp"

extern "C" {
#include "csmc/mc_stepper_dq.h"
#include "math/mc_math.h"
#include "mc_ctrl_csmc_q31.h"
#include "mc_ctrl_pi2d_q31.h"
#include "mc_drive.h"
#include "mc_pu.h"
#include "transforms/mc_svpwm.h"
}

namespace mcsim {
namespace q31loop {

namespace {
constexpr double kPi = 3.14159265358979323846;
}  // namespace

// ------------------------------------------------------------ pi2d paper
mc_pi2d_q31_bases_t paper_pi2d_bases() {
  mc_pi2d_q31_bases_t b{};
  b.i_base_a = 32.0f;
  b.v_base_v = 2048.0f;
  b.theta_base_rad = 8.0f;  // theta_m, theta_ref in [0, 2 pi) + e4
  b.thetaf_base_rad = 1.0f;
  b.omega_base_rad_s = 16.0f;
  b.alpha_base_rad_s2 = 8.0f;
  b.jerk_base_rad_s3 = 1.0f;
  b.did_base_a_s = 1.0f;
  b.nu_base_nm = 1.0f;
  return b;
}

long run_paper_q31(const pi2d::PaperOptions& o,
                   const std::function<void(const pi2d::PaperSample&)>& row) {
  const double T = 1.0 / o.rate_hz;
  PmsmNormalised plant;
  PmsmNormalisedParams pp;
  pp.sigma = 0.51;
  pp.gamma = 0.17;
  pp.tau_l = o.tau_l;
  if (plant.configure(pp) != Status::kOk) throw std::invalid_argument("normalised plant");
  mc_pi2d_q31_cfg_t cfg{};
  cfg.f = pi2d::paper_cfg(T);
  cfg.base = paper_pi2d_bases();
  const mc_pi2d_q31_bases_t& b = cfg.base;
  mc_pi2d_q31_t law{};
  const uint32_t err = mc_pi2d_q31_init(&law, &cfg);
  if (err != 0u) throw std::invalid_argument("q31 paper gains rejected: " + std::to_string(err));
  InputDelay<PmsmNormalised::Input, 4> delay;
  delay.configure(static_cast<size_t>(o.delay_periods), PmsmNormalised::Input::Zero());
  PmsmNormalised::State x = PmsmNormalised::State::Zero();
  const long n = step_count(o.duration, T);
  for (long k = 0; k <= n; ++k) {
    const double t = static_cast<double>(k) / o.rate_hz;
    const pi2d::SpeedRef r = pi2d::paper_profile(t);
    const double off = 2.0 * kPi * std::floor(r.th / (2.0 * kPi));
    mc_pi2d_q31_in_t in{};
    in.id = mc_pu_to_q31(x(0), b.i_base_a);
    in.iq = mc_pu_to_q31(x(1), b.i_base_a);
    in.theta_m = mc_pu_to_q31(x(3) - off, b.theta_base_rad);
    in.theta_ref = mc_pu_to_q31(r.th - off, b.theta_base_rad);
    in.omega_ref = mc_pu_to_q31(r.w, b.omega_base_rad_s);
    in.alpha_ref = mc_pu_to_q31(r.a, b.alpha_base_rad_s2);
    in.jerk_ref = mc_pu_to_q31(r.j, b.jerk_base_rad_s3);
    mc_pi2d_q31_out_t out{};
    mc_pi2d_q31_step(&law, &in, &out);
    const double u1 = mc_pu_from_q31(out.vd, b.v_base_v), u2 = mc_pu_from_q31(out.vq, b.v_base_v);
    row(pi2d::PaperSample{
        t, x(0), x(1), x(2), x(3), r.w, r.th, mc_pu_from_q31(out.iq_ref, b.i_base_a), u1, u2,
        mc_pu_from_q31(out.nu, b.nu_base_nm), mc_pu_from_q31(out.theta_f, b.thetaf_base_rad)});
    if (k == n) break;
    const PmsmNormalised::Input u = delay.push(PmsmNormalised::Input(u1, u2));
    advance_zoh(plant, u, t, T, o.substeps, &x);
  }
  return n;
}

// ------------------------------------------------------------ pi2d motor
mc_pi2d_q31_bases_t motor_pi2d_bases(const pi2d::MotorOptions& o) {
  mc_pi2d_q31_bases_t b{};
  b.i_base_a = 20.0f;  // the board's current-sensor range
  b.v_base_v = static_cast<float>(2.0 * o.vbus_v);
  b.theta_base_rad = 8.0f;  // positions kept in [0, 2 pi) (+ e4) by the plug-in
  b.thetaf_base_rad = 1.0f;
  b.omega_base_rad_s = 256.0f;    // 1000 r/min = 105 rad/s
  b.alpha_base_rad_s2 = 1024.0f;  // ramp 262 rad/s^2
  b.jerk_base_rad_s3 = 1.0f;
  b.did_base_a_s = 1.0f;
  b.nu_base_nm = 8.0f;  // nu_max = 2 load + 1 = 7 N m
  return b;
}

namespace {

constexpr double kRpm = 2.0 * kPi / 60.0;

pi2d::SpeedRef motor_profile(const pi2d::MotorOptions& o, double t) {
  const double w_r = o.speed_rpm * kRpm, acc = w_r / o.ramp_s;
  pi2d::SpeedRef r;
  if (t < o.t_up_s) return r;
  if (t < o.t_up_s + o.ramp_s) {
    r.a = acc;
    r.w = acc * (t - o.t_up_s);
  } else if (t < o.t_down_s) {
    r.w = w_r;
  } else if (t < o.t_down_s + o.ramp_s) {
    r.a = -acc;
    r.w = w_r - acc * (t - o.t_down_s);
  }
  return r;
}

}  // namespace

pi2d::MotorMetrics run_motor_q31(const pi2d::MotorOptions& o, double duration_s,
                                 const std::function<void(const pi2d::MotorSample&)>& row) {
  // The rig of pi2d::run_motor (same board, drive and limits).
  hal_host::PmsmBoard bd(pi2d::motor_board_cfg(o));
  const mc_drive_cfg_t dc = pi2d::motor_drive_cfg(o);
  mc_drive_t d{};
  if (mc_drive_init(&d, &dc, bd.hal()) != MC_DRIVE_CFG_OK) {
    throw std::invalid_argument("drive configuration rejected");
  }
  // The q31 PI^2D plug-in (firmware/app/ctrl/mc_ctrl_pi2d_q31), attached
  // as the f32 one is in pi2d::run_motor.
  mc_ctrl_pi2d_q31_t ctrl{};
  mc_ctrl_pi2d_q31_cfg_t cc{};
  cc.law.f = pi2d::motor_pi2d_cfg(o);
  cc.law.base = motor_pi2d_bases(o);
  cc.limit_mode = MC_SVPWM_LIMIT_CIRCLE;
  cc.dt_s = 1.0 / o.pwm_hz;
  const uint32_t lerr = mc_ctrl_pi2d_q31_init(&ctrl, &cc);
  if (lerr != 0u) throw std::invalid_argument("q31 PI2D rejected: " + std::to_string(lerr));
  const mc_pi2d_q31_bases_t& b = cc.law.base;
  if (mc_drive_attach_ctrl(&d, mc_ctrl_pi2d_q31_ops(&ctrl)) != 0) {
    throw std::runtime_error("plug-in refused");
  }
  if (mc_drive_set_mode(&d, MC_DRIVE_MODE_CTRL) != 0) throw std::runtime_error("CTRL mode");

  const double T = 1.0 / o.pwm_hz;
  const long n = step_count(duration_s, T);
  const double w_r = o.speed_rpm * kRpm;
  pi2d::MotorMetrics mm;
  double sum_e2 = 0.0, last_out_of_band = o.t_load_s;
  for (long k = 0; k <= n; ++k) {
    const double t = bd.t_s();
    const pi2d::SpeedRef r = motor_profile(o, t);
    // The last row is recorded before the plant moves; the period the
    // rig then integrates is not recorded.
    (void)hal_host::sil_period(
        bd, d,
        [&] {
          // float references, as the f32 plug-in's
          (void)mc_ctrl_pi2d_q31_set_ref(&ctrl, static_cast<float>(r.w), static_cast<float>(r.a),
                                         0.0f, 0.0f);
        },
        [&] {
          double id, iq;
          bd.true_dq_a(&id, &iq);
          const auto x = bd.state();
          const double e = x(2) - r.w;
          sum_e2 += e * e;
          mm.peak_err_rad_s = std::max(mm.peak_err_rad_s, std::abs(e));
          mm.peak_current_a = std::max(mm.peak_current_a, std::hypot(id, iq));
          if (t >= o.t_load_s && t < o.t_down_s) {
            mm.load_dip_rad_s = std::max(mm.load_dip_rad_s, std::abs(e));
            if (std::abs(e) > 0.01 * w_r) last_out_of_band = t;
          }
          pi2d::MotorSample s{};
          s.t = t;
          s.omega_m = x(2);
          s.omega_ref = r.w;
          s.id = id;
          s.iq = iq;
          s.iq_ref = mc_pu_from_q31(ctrl.tm.iq_ref, b.i_base_a);
          s.vd = mc_pu_from_q31(ctrl.tm.vd, b.v_base_v);
          s.vq = mc_pu_from_q31(ctrl.tm.vq, b.v_base_v);
          s.nu = mc_pu_from_q31(ctrl.tm.nu, b.nu_base_nm);
          s.theta_f = mc_pu_from_q31(ctrl.tm.theta_f, b.thetaf_base_rad);
          s.load = (t >= o.t_load_s) ? o.load_nm : 0.0;
          row(s);
        });
  }
  mm.rms_err_rad_s = std::sqrt(sum_e2 / static_cast<double>(n + 1));
  mm.settle_after_load_s = last_out_of_band - o.t_load_s;
  mm.faults = d.faults;
  return mm;
}

// ----------------------------------------------------------------- csmc
mc_csmc_q31_bases_t paper_csmc_bases() {
  mc_csmc_q31_bases_t b{};
  b.i_base_a = 20.0f;
  b.theta_base_rad = 0.5f;
  b.omega_base_rad_s = 200.0f;
  b.alpha_base_rad_s2 = 1.0e5f;
  b.did_base_a_s = 1.0e5f;
  b.jerk_base_rad_s3 = 1.0e7f;
  b.g_base_rad_s3 = 1.0e9f;
  b.v_base_v = 2.0e4f;
  return b;
}

csmc::LoopResult run_csmc_q31(const csmc::LoopOptions& o) {
  std::vector<csmc::Sample> trace;
  csmc::LoopResult r = run_csmc_q31(o, [&trace](const csmc::Sample& s) { trace.push_back(s); });
  r.trace = std::move(trace);
  return r;
}

csmc::LoopResult run_csmc_q31(const csmc::LoopOptions& o, const csmc::SampleFn& on_sample) {
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
  if (o.fb != csmc::Feedback::kState || o.ref != csmc::RefKind::kSteps) {
    throw std::runtime_error("run_csmc_q31: state feedback with step references only");
  }
  // The q31 plug-in (firmware/app/ctrl/mc_ctrl_csmc_q31), its step called
  // on the plant's measurements as csmc::run_loop calls the f32 one.
  mc_ctrl_csmc_q31_cfg_t cc{};
  cc.law.f = o.ctrl;
  cc.law.f.dt_s = static_cast<float>(o.dt_s);
  cc.law.base = paper_csmc_bases();
  cc.feedback = MC_CTRL_CSMC_FB_STATE;
  cc.duty_max = 1.0f;  // unused: no bridge here
  const mc_csmc_q31_bases_t& b = cc.law.base;
  mc_ctrl_csmc_q31_t ctrl{};
  const uint32_t ce = mc_ctrl_csmc_q31_init(&ctrl, &cc);
  if (ce != MC_CTRL_CSMC_ERR_NONE) {
    throw std::runtime_error("q31 csmc rejected: " + std::to_string(ce));
  }
  const mc_ctrl_csmc_q31_tm_t& tm = ctrl.tm;
  const uint32_t nr = static_cast<uint32_t>(o.plant.rotor_teeth);
  csmc::LoopResult res;
  const long n = step_count(o.duration_s, o.dt_s);
  const size_t every = std::max<size_t>(1, o.record_every);
  Stepper2Ph::State x = Stepper2Ph::State::Zero();
  for (long k = 0; k <= n; ++k) {
    const double t = static_cast<double>(k) * o.dt_s;
    const double phi = (t >= 0.0 ? o.step_rad : 0.0) +
                       ((o.step2_t_s >= 0.0 && t >= o.step2_t_s) ? o.step_rad : 0.0);
    if (mc_ctrl_csmc_q31_set_ref(&ctrl, static_cast<float>(phi), 0.0f, 0.0f, 0.0f, 0.0f, 0.0f) !=
        MC_CTRL_CSMC_ERR_NONE) {
      throw std::runtime_error("reference refused");
    }
    // e2 per unit from the exact angle, rounded once
    const double e2 = x(Stepper2Ph::kThetaM) - phi;
    mc_ctrl_csmc_q31_meas_t m{};
    m.ia_a = static_cast<float>(x(Stepper2Ph::kIa));
    m.ib_a = static_cast<float>(x(Stepper2Ph::kIb));
    m.omega_m_rad_s = static_cast<float>(x(Stepper2Ph::kOmegaM));
    m.phi_rad = static_cast<float>(x(Stepper2Ph::kThetaM));
    m.theta_e_rad = mc_stepper_theta_e_f32(m.phi_rad, nr);
    m.e2 = mc_pu_to_q31(e2, b.theta_base_rad);
    if (mc_ctrl_csmc_q31_step(&ctrl, &m) != MC_CTRL_CSMC_ERR_NONE) {
      throw std::runtime_error("q31 csmc step refused an input");
    }
    if (k % static_cast<long>(every) == 0 || k == n) {
      res.last = csmc::Sample{t,
                              tm.fin.e1_a,
                              e2,
                              tm.i_d_a,
                              tm.i_q_a,
                              m.omega_m_rad_s,
                              x(Stepper2Ph::kThetaM),
                              tm.v_d_v,
                              tm.v_q_v,
                              0.0,
                              0.0,
                              0.0,
                              mc_pu_from_q31(tm.out.s1, b.i_base_a),
                              mc_pu_from_q31(tm.out.s2, b.alpha_base_rad_s2),
                              phi};
      on_sample(res.last);
    }
    if (k == n) {
      res.t_end = t;
      res.e2_end = e2;
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

// -------------------------------------------------------------- scenarios
namespace {

// pi2d-paper-q31 (tests/sil/q31 Pi2dPaperTracksTheF32Loop): the q31 loop
// stays within 1e-5 of the f32 loop in speed and position and 0.1 V in u2
// (the kernels' rounding through an exponentially stable loop), and tracks
// as the f32 loop does (pi2d-paper's bound on the speed error after t = 10).
void run_paper_cmp(RunContext& ctx) {
  pi2d::PaperOptions o;
  o.rate_hz = ctx.params.get("rate_hz");
  o.tau_l = ctx.params.get("tau_l");
  o.duration = ctx.duration_s;
  // The f32 run's samples wait in a temporary file for the q31 run's.
  Spill a(7);
  double f32_x3_final = 0.0;
  pi2d::run_paper(o, [&](const pi2d::PaperSample& s) {
    const double v[7] = {s.t, s.x3_ref, s.x3, s.x4, s.x2, s.u2, s.nu};
    a.put(v);
    f32_x3_final = s.x3;
  });
  ctx.progress.update(0.5 * ctx.duration_s, ctx.duration_s);
  ctx.csv.columns({"t", "x3_ref", "f32_x3", "q31_x3", "f32_x4", "q31_x4", "f32_x2", "q31_x2",
                   "f32_u2", "q31_u2", "f32_nu", "q31_nu", "dx3", "dx4"});
  const long every = std::max(1L, std::lround(o.rate_hz / 1000.0));
  double dx3 = 0, dx4 = 0, dx2 = 0, du2 = 0, dnu = 0, e3_late = 0, q31_x3_final = 0;
  long k = 0;
  a.rewind();
  double f[7];
  run_paper_q31(o, [&](const pi2d::PaperSample& r) {
    if (!a.get(f)) return;
    dx3 = std::max(dx3, std::abs(f[2] - r.x3));
    dx4 = std::max(dx4, std::abs(f[3] - r.x4));
    dx2 = std::max(dx2, std::abs(f[4] - r.x2));
    du2 = std::max(du2, std::abs(f[5] - r.u2));
    dnu = std::max(dnu, std::abs(f[6] - r.nu));
    if (r.t > 10.0) e3_late = std::max(e3_late, std::abs(r.x3 - r.x3_ref));
    if (k++ % every == 0) {
      ctx.csv.row({f[0], f[1], f[2], r.x3, f[3], r.x4, f[4], r.x2, f[5], r.u2, f[6], r.nu,
                   r.x3 - f[2], r.x4 - f[3]});
    }
    q31_x3_final = r.x3;
  });
  ctx.summary.set("max_abs_dx3", dx3);
  ctx.summary.set("max_abs_dx4", dx4);
  ctx.summary.set("max_abs_dx2", dx2);
  ctx.summary.set("max_abs_du2", du2);
  ctx.summary.set("max_abs_dnu", dnu);
  ctx.summary.set("q31_x3_final", q31_x3_final);
  ctx.summary.set("f32_x3_final", f32_x3_final);
  ctx.summary.set("q31_max_abs_e3_after_10", e3_late);
  Judge j;
  j.at_most("q31 off the f32 loop", "max |speed q31 - f32|", dx3, 1e-5);
  j.at_most("q31 off the f32 loop", "max |position q31 - f32|", dx4, 1e-5);
  j.at_most("q31 off the f32 loop", "max |u2 q31 - f32|", du2, 0.1);
  pi2d::check_paper(j, ctx.duration_s, e3_late);
  write_verdict(ctx.summary, j.verdict());
}

const Registrar reg_paper_q31(
    {"pi2d-paper-q31",
     "pi2d-paper with the q31 PI^2D kernel (mc_pi2d_q31) next to the f32 run: both trajectories "
     "and their difference (tests/sil/q31 bounds it)",
     14.0,
     {{"rate_hz", 10000.0, "1/t_n", "controller rate (normalised time)", 100.0, 1.0e6},
      {"tau_l", 1.0, "1", "normalised load torque", -10.0, 10.0}},
     run_paper_cmp});

// pi2d-motor-q31 (tests/sil/q31 Pi2dMotorTracksTheF32Loop): no fault; the
// speed within 0.5 rad/s of the f32 plug-in's (the quantised ADC and
// encoder make the loops' inputs differ by an LSB now and then), the rms
// speed error and the load-step dip within 2 % of the f32 run's.
void run_motor_cmp(RunContext& ctx) {
  pi2d::MotorOptions o;
  o.load_nm = ctx.params.get("load_nm");
  o.noise_rms_a = ctx.params.get("noise_rms_a");
  // The f32 run's samples wait in a temporary file for the q31 run's.
  Spill sp(5);
  const auto ma = pi2d::run_motor(o, true, ctx.duration_s, [&](const pi2d::MotorSample& s) {
    const double v[5] = {s.t, s.omega_ref, s.omega_m, s.iq, s.nu};
    sp.put(v);
  });
  ctx.progress.update(0.5 * ctx.duration_s, ctx.duration_s);
  ctx.csv.columns({"t", "omega_ref_rad_s", "f32_omega_m_rad_s", "q31_omega_m_rad_s", "f32_i_q_a",
                   "q31_i_q_a", "f32_nu_nm", "q31_nu_nm", "d_omega_rad_s"});
  double dw = 0, diq = 0, dnu = 0;
  long k = 0;
  sp.rewind();
  double a[5];
  const auto mq = run_motor_q31(o, ctx.duration_s, [&](const pi2d::MotorSample& q) {
    if (!sp.get(a)) return;
    dw = std::max(dw, std::abs(a[2] - q.omega_m));
    diq = std::max(diq, std::abs(a[3] - q.iq));
    dnu = std::max(dnu, std::abs(a[4] - q.nu));
    if (k++ % 4 == 0) {
      ctx.csv.row({a[0], a[1], a[2], q.omega_m, a[3], q.iq, a[4], q.nu, q.omega_m - a[2]});
    }
  });
  ctx.summary.set("max_abs_domega_rad_s", dw);
  ctx.summary.set("max_abs_diq_a", diq);
  ctx.summary.set("max_abs_dnu_nm", dnu);
  ctx.summary.set("f32.rms_speed_error_rad_s", ma.rms_err_rad_s);
  ctx.summary.set("q31.rms_speed_error_rad_s", mq.rms_err_rad_s);
  ctx.summary.set("f32.load_step_dip_rad_s", ma.load_dip_rad_s);
  ctx.summary.set("q31.load_step_dip_rad_s", mq.load_dip_rad_s);
  ctx.summary.set("q31.faults", mq.faults);
  ctx.summary.set("f32.faults", ma.faults);
  if (ma.faults != 0u || mq.faults != 0u) {
    return write_verdict(
        ctx.summary, faulted(ma.faults | mq.faults, "f32: " + drive_fault_names(ma.faults) +
                                                        ", q31: " + drive_fault_names(mq.faults)));
  }
  Judge j;
  j.at_most("q31 off the f32 loop", "max |speed q31 - f32| [rad/s]", dw, 0.5);
  j.at_most("q31 off the f32 loop", "|rms speed error q31 - f32| [rad/s]",
            std::abs(mq.rms_err_rad_s - ma.rms_err_rad_s), 0.02 * ma.rms_err_rad_s,
            "2 % of the f32 run's");
  j.at_most("q31 off the f32 loop", "|load-step dip q31 - f32| [rad/s]",
            std::abs(mq.load_dip_rad_s - ma.load_dip_rad_s), 0.02 * ma.load_dip_rad_s);
  write_verdict(ctx.summary, j.verdict());
}

const Registrar reg_motor_q31(
    {"pi2d-motor-q31",
     "pi2d-motor (PI^2D part) with a q31 plug-in: mc_pi2d_q31 and Clarke/Park/SVPWM q31 through "
     "the drive's CTRL mode, next to the f32 plug-in run",
     2.2,
     {{"load_nm", 3.0, "N m", "load step at t = 1 s", -10.0, 10.0},
      {"noise_rms_a", 0.0, "A", "current-sensor noise (rms)", 0.0, 1.0}},
     run_motor_cmp});

// csmc-state-feedback-q31 (tests/sil/q31 CsmcStateFeedbackTracksTheF32Loop):
// positions within 1e-6 rad of the f32 loop, currents within 1e-4 A; with
// the integrators, no steady error (|e2| <= 1e-6 rad at the end) and the
// second step settled (2 %) within 0.1 s. The second step is at 0.5 s: the
// run needs 0.6 s.
void run_csmc_cmp(RunContext& ctx) {
  csmc::LoopOptions o;
  o.duration_s = ctx.duration_s;
  o.dt_s = ctx.params.get("dt_s");
  o.step2_t_s = 0.5;
  const bool integ = ctx.params.get("integrators") != 0.0;
  o.ctrl = csmc::paper_ctrl(true, integ, false);
  o.record_every =
      std::max<size_t>(1, static_cast<size_t>(std::floor(o.duration_s / o.dt_s / 5000.0)));
  // The f32 run's samples wait in a temporary file for the q31 run's.
  Spill sp(5);
  const csmc::LoopResult a = csmc::run_loop(o, [&](const csmc::Sample& s) {
    const double v[5] = {s.t, s.phi_d, s.x4, s.u2, s.x1};
    sp.put(v);
  });
  ctx.progress.update(0.5 * ctx.duration_s, ctx.duration_s);
  ctx.csv.columns({"t", "phi_d_rad", "f32_x4_rad", "q31_x4_rad", "f32_u2_v", "q31_u2_v", "f32_x1_a",
                   "q31_x1_a", "dx4_rad"});
  double dx4 = 0, dx1 = 0;
  const double step = csmc::kPaperStepRad;
  csmc::StepAcc step2(0.5, o.duration_s, 2.0 * step, step);
  sp.rewind();
  double f[5];
  const csmc::LoopResult q = run_csmc_q31(o, [&](const csmc::Sample& r) {
    step2.add(r);
    if (!sp.get(f)) return;
    dx4 = std::max(dx4, std::abs(f[2] - r.x4));
    dx1 = std::max(dx1, std::abs(f[4] - r.x1));
    ctx.csv.row({f[0], f[1], f[2], r.x4, f[3], r.u2, f[4], r.x1, r.x4 - f[2]});
  });
  ctx.summary.set("max_abs_dx4_rad", dx4);
  ctx.summary.set("max_abs_dx1_a", dx1);
  ctx.summary.set("f32_e2_final_rad", a.e2_end);
  ctx.summary.set("q31_e2_final_rad", q.e2_end);
  ctx.summary.set("q31_step2_settling_2pct_s", step2.result().settling_s);
  Judge j;
  j.at_least("too short to judge", "duration [s]", o.duration_s, 0.6, "the second step + 0.1 s");
  j.at_most("q31 off the f32 loop", "max |position q31 - f32| [rad]", dx4, 1e-6);
  j.at_most("q31 off the f32 loop", "max |current q31 - f32| [A]", dx1, 1e-4);
  if (integ) {
    j.at_most("steady-state error", "|e2| at the end (q31) [rad]", std::abs(q.e2_end), 1e-6,
              "integral action");
    j.at_most("not settled", "second step's 2 % settling (q31) [s]", step2.result().settling_s,
              0.1);
  } else {
    j.note("without the integrators a steady error remains: not judged");
  }
  write_verdict(ctx.summary, j.verdict());
}

const Registrar reg_csmc_q31(
    {"csmc-state-feedback-q31",
     "csmc-state-feedback (paper 001 Fig. 2) with the q31 CSMC kernel (mc_csmc_q31 with q31 "
     "conditional integrators) next to the f32 run",
     1.0,
     {{"dt_s", 1.0e-5, "s", "control period", 1.0e-6, 1.0e-3},
      {"integrators", 1.0, "-", "1: conditional integrators k0 = (20, 100); 0: none", 0.0, 1.0}},
     run_csmc_cmp});

}  // namespace
}  // namespace q31loop
}  // namespace mcsim
