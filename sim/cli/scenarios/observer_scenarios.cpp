// Paper 002 scenarios through the firmware path (drive + sensorless plug-in
// on the simulated board): observer-table1 (Figs. 5-7), observer-test-motor
// (Figs. 8-9), observer-lowspeed-sweep, ii-observer.
#include <algorithm>
#include <cmath>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "observer_sil.hpp"
#include "scenario.hpp"
#include "scenarios/q31_loops.hpp"
extern "C" {
#include "math/mc_math.h"
#include "observer/mc_iiobs.h"
#include "observer/mc_spdpll.h"
}

namespace mcsim {
namespace observer {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kRpm = 2 * kPi / 60.0;

SilOptions options_from(const Params& p) {
  SilOptions o;
  o.dead_time_s = p.get("dead_time_s");
  o.dead_comp_frac = p.get("dead_comp_frac");
  o.dead_comp_duty = p.get("dead_comp_duty") != 0.0;
  o.noise_rms_a = p.get("noise_rms_a");
  o.r_error = p.get("r_error");
  o.flux_error = p.get("flux_error");
  o.crit_frac = p.get("crit_frac");
  return o;
}

std::vector<ParamSpec> common_params() {
  return {
      {"dead_time_s", 0.0, "s", "inverter dead time (paper's bench: 2e-6)", 0.0, 1e-5},
      {"dead_comp_frac", 1.0, "1", "fraction of the dead time the observer's voltage compensates",
       0.0, 1.5},
      {"dead_comp_duty",
       0.0,
       "-",
       "also compensate that dead time in the duties (f32 kernels only; off = 0, on = 1)",
       0.0,
       1.0,
       {{"off", 0.0}, {"on", 1.0}}},
      {"noise_rms_a", 0.0, "A", "current-sensor noise (rms)", 0.0, 5.0},
      {"r_error", 0.0, "1", "relative error of R in the controller", -0.9, 2.0},
      {"flux_error", 0.0, "1", "relative error of the flux in the controller", -0.5, 0.5},
      {"crit_frac", 0.02, "1", "observer critical speed as a fraction of rated speed (sets gamma)",
       0.002, 0.2},
  };
}

// A run of the sensorless drive with a speed reference profile and a load
// profile; writes the standard CSV and collects metrics.
struct RunResult {
  std::vector<double> t, w, wref, what, err, iq, tau_e;
  double first_handover_s = std::nan("");
  uint32_t faults = 0;
};

RunResult run_profile(RunContext& ctx, Sil& sil, const std::function<double(double)>& ref) {
  ctx.csv.columns({"t",
                   "omega_m_rad_s",
                   "omega_ref_rad_s",
                   "omega_hat_rad_s",
                   "theta_e_rad",
                   "theta_e_hat_rad",
                   "angle_err_rad",
                   "tau_load_nm",
                   "tau_e_nm",
                   "id_a",
                   "iq_a",
                   "id_ref_a",
                   "iq_ref_a",
                   "i_alpha_a",
                   "i_beta_a",
                   "v_alpha_v",
                   "v_beta_v",
                   "x_hat_alpha_wb",
                   "x_hat_beta_wb",
                   "phase_1",
                   "fault_1"});
  const double T = sil.board().period_s();
  const long n = std::lround(ctx.duration_s / T);
  const long every = std::max(1L, n / 6000);
  RunResult r;
  uint32_t handovers = 0;
  for (long k = 0; k <= n; ++k) {
    const double t = sil.t_s();
    if (sil.set_speed_ref(static_cast<float>(ref(t))) != 0u) {
      throw UsageError("speed reference beyond the controller's limit");
    }
    if (k < n) sil.step();
    const double tt = sil.t_s();
    const auto x = sil.board().state();
    double id, iq;
    sil.board().true_dq_a(&id, &iq);
    const auto& tm = sil.tm();
    r.t.push_back(tt);
    r.w.push_back(x(2));
    r.wref.push_back(ref(t));
    r.what.push_back(tm.omega_hat_m_rad_s);
    r.err.push_back(sil.angle_error());
    r.iq.push_back(iq);
    r.tau_e.push_back(sil.board().torque_nm());
    if (tm.handovers != handovers && std::isnan(r.first_handover_s)) r.first_handover_s = tt;
    handovers = tm.handovers;
    if (k % every == 0 || k == n) {
      double xa = 0, xb = 0;
      sil.flux_hat_wb(&xa, &xb);
      ctx.csv.row({tt,
                   x(2),
                   ref(t),
                   tm.omega_hat_m_rad_s,
                   sil.theta_e_true(),
                   tm.theta_hat_e_rad,
                   sil.angle_error(),
                   sil.load_nm(tt),
                   sil.board().torque_nm(),
                   id,
                   iq,
                   tm.id_ref_a,
                   tm.iq_ref_a,
                   tm.i_alpha_a,
                   tm.i_beta_a,
                   tm.v_alpha_obs_v,
                   tm.v_beta_obs_v,
                   xa,
                   xb,
                   static_cast<double>(tm.phase),
                   static_cast<double>(sil.drive().faults)});
      ctx.progress.update(tt, ctx.duration_s);
    }
    if (sil.drive().faults != 0u) {
      r.faults = sil.drive().faults;
      break;
    }
  }
  return r;
}

// max |y| over t in [a, b)
double max_abs(const RunResult& r, const std::vector<double>& y, double a, double b) {
  double m = 0;
  for (size_t k = 0; k < r.t.size(); ++k)
    if (r.t[k] >= a && r.t[k] < b) m = std::max(m, std::abs(y[k]));
  return m;
}
double mean(const RunResult& r, const std::vector<double>& y, double a, double b) {
  double s = 0;
  long n = 0;
  for (size_t k = 0; k < r.t.size(); ++k)
    if (r.t[k] >= a && r.t[k] < b) {
      s += y[k];
      ++n;
    }
  return n ? s / static_cast<double>(n) : std::nan("");
}
double stddev(const RunResult& r, const std::vector<double>& y, double a, double b) {
  const double m = mean(r, y, a, b);
  double s = 0;
  long n = 0;
  for (size_t k = 0; k < r.t.size(); ++k)
    if (r.t[k] >= a && r.t[k] < b) {
      s += (y[k] - m) * (y[k] - m);
      ++n;
    }
  return n ? std::sqrt(s / static_cast<double>(n)) : std::nan("");
}

// Transient at the first hand-over (IF -> CLOSED): the largest change of
// the electromagnetic torque and of the true q current over one PWM period
// within 3 periods either side of the switch, against the largest
// per-period change in the 20 ms of I-f before it; and the torque change
// over the following 5 ms (set by the speed loop taking over, not by the
// switch).
void handover_metrics(const RunResult& r, Summary& s) {
  s.set("handover_time_s", r.first_handover_s);
  if (std::isnan(r.first_handover_s)) return;
  const double t0 = r.first_handover_s;
  const double T = r.t.size() > 1 ? r.t[1] - r.t[0] : 1.0;
  double jump = 0, jump_iq = 0, before = 0, tau0 = std::nan(""), dtau5 = 0;
  for (size_t k = 1; k < r.t.size(); ++k) {
    const double d = std::abs(r.tau_e[k] - r.tau_e[k - 1]);
    if (std::abs(r.t[k] - t0) <= 3.5 * T) {
      jump = std::max(jump, d);
      jump_iq = std::max(jump_iq, std::abs(r.iq[k] - r.iq[k - 1]));
      if (std::isnan(tau0)) tau0 = r.tau_e[k - 1];
    }
    if (r.t[k] >= t0 - 0.02 && r.t[k] < t0 - 3.5 * T) before = std::max(before, d);
    if (!std::isnan(tau0) && r.t[k] > t0 && r.t[k] <= t0 + 0.005) {
      dtau5 = std::max(dtau5, std::abs(r.tau_e[k] - tau0));
    }
  }
  s.set("handover_torque_step_per_period_nm", jump);
  s.set("handover_iq_step_per_period_a", jump_iq);
  s.set("if_torque_step_per_period_nm", before);
  s.set("handover_torque_change_5ms_nm", dtau5);
}

// ------------------------------------------------------- observer-table1
void run_table1(RunContext& ctx) {
  const Machine m = table1_40kw();
  const SilOptions o = options_from(ctx.params);
  const double tl = ctx.params.get("load_nm");
  LoadSteps load{{{1.2, tl}, {2.0, 0.0}, {2.6, tl}}};
  Sil sil(m, o, default_ctrl_cfg(m, o), load);
  sil.record(ctx.summary);
  // Reference steps (slewed by the controller at speed_slew): 500 r/min,
  // 1500 r/min at 0.6 s, 1000 r/min at 1.6 s, 1500 r/min at 2.2 s.
  auto ref = [](double t) {
    if (t < 0.6) return 500 * kRpm;
    if (t < 1.6) return 1500 * kRpm;
    if (t < 2.2) return 1000 * kRpm;
    return 1500 * kRpm;
  };
  const RunResult r = run_profile(ctx, sil, ref);
  ctx.summary.set("fault_bits", r.faults);
  handover_metrics(r, ctx.summary);
  ctx.summary.set("angle_err_max_after_1s_rad", max_abs(r, r.err, 1.0, 1e9));
  ctx.summary.set("speed_dip_load_step_rad_s", max_abs(
                                                   r,
                                                   [&] {
                                                     std::vector<double> e(r.w.size());
                                                     for (size_t k = 0; k < e.size(); ++k)
                                                       e[k] = r.wref[k] - r.w[k];
                                                     return e;
                                                   }(),
                                                   1.2, 1.6));
  if (r.faults) throw std::runtime_error("drive faulted: bits " + std::to_string(r.faults));
}

auto table1_params() {
  auto p = common_params();
  p.push_back({"load_nm", 180.0, "N m", "load-torque steps (rated 180 N m)", -400.0, 400.0});
  return p;
}

const Registrar reg_table1({"observer-table1",
                            "Paper 002 Figs. 5-7: the 40 kW machine of Table I, sensorless "
                            "speed control through the drive (8 kHz, 1.25 ms speed loop), "
                            "I-f start, speed steps, rated load-torque steps",
                            3.0, table1_params(), run_table1});

// --------------------------------------------------- observer-test-motor
void run_test_motor(RunContext& ctx) {
  const Machine m = test_motor_300w();
  SilOptions o = options_from(ctx.params);
  o.q31 = ctx.params.get("kernels") != 0.0;
  const int profile = static_cast<int>(ctx.params.get("profile"));
  const double tl = ctx.params.get("load_frac") * m.rated_torque_nm;
  const double t_step = ctx.params.get("t_load_s");
  LoadSteps load;
  std::function<double(double)> ref;
  double w0 = 200 * kRpm;
  if (profile == 0 || profile == 1) {
    w0 = (profile == 0 ? 200.0 : 800.0) * kRpm;
    load.steps = {{t_step, tl}, {t_step + 1.0, 0.0}};
    ref = [w0](double) { return w0; };
  } else if (profile == 2) {
    const double a = ctx.params.get("ramp_rad_s2");
    load.steps = {{0.0, 0.3 * m.rated_torque_nm}};
    ref = [a, t_step](double t) {
      return std::min(1000 * kRpm, 200 * kRpm + std::max(0.0, t - t_step) * a);
    };
  } else {
    // start-stop: to 300 r/min, hold, back to 0 (hand-over both ways)
    load.steps = {{0.0, 0.3 * m.rated_torque_nm}};
    ref = [t_step](double t) { return (t < t_step) ? 300 * kRpm : 0.0; };
  }
  const auto cfg = default_ctrl_cfg(m, o);
  Sil sil(m, o, cfg, load);
  sil.record(ctx.summary);
  ctx.summary.set("profile", profile);
  ctx.summary.set("load_step_nm", tl);
  const RunResult r = run_profile(ctx, sil, ref);
  ctx.summary.set("fault_bits", r.faults);
  handover_metrics(r, ctx.summary);
  std::vector<double> e(r.w.size());
  for (size_t k = 0; k < e.size(); ++k) e[k] = r.wref[k] - r.w[k];
  if (profile <= 1) {
    ctx.summary.set("speed_err_max_load_step_rad_s", max_abs(r, e, t_step, t_step + 1.0));
    ctx.summary.set("speed_err_max_load_step_rpm", max_abs(r, e, t_step, t_step + 1.0) / kRpm);
    ctx.summary.set("speed_err_mean_last_0.3s_of_load_rad_s",
                    mean(r, e, t_step + 0.7, t_step + 1.0));
    ctx.summary.set("angle_err_mean_no_load_rad", mean(r, r.err, t_step - 0.3, t_step));
    ctx.summary.set("angle_err_mean_full_load_rad", mean(r, r.err, t_step + 0.7, t_step + 1.0));
    ctx.summary.set("angle_err_max_after_handover_rad",
                    max_abs(r, r.err, r.first_handover_s + 0.3, 1e9));
  }
  if (profile == 3) {
    double t_fb = std::nan("");
    ctx.summary.set("fallbacks", sil.tm().fallbacks);
    (void)t_fb;
    ctx.summary.set("speed_final_rad_s", r.w.back());
  }
  if (r.faults) throw std::runtime_error("drive faulted: bits " + std::to_string(r.faults));
}

auto test_motor_params() {
  auto p = common_params();
  p.push_back({"profile", 0.0, "1",
               "0: 200 r/min with a load step (Fig. 8a), 1: 800 r/min (Fig. 8b), 2: ramp "
               "200 -> 1000 r/min (Fig. 9), 3: start-stop 0 -> 300 -> 0 r/min",
               0.0, 3.0});
  p.push_back({"load_frac", 1.0, "1", "load step as a fraction of rated torque (3 N m)", 0.0, 1.5});
  p.push_back(
      {"t_load_s", 1.0, "s", "time of the load step / ramp start / stop command", 0.2, 100.0});
  p.push_back({"ramp_rad_s2", 100.0, "rad/s^2", "profile 2: reference ramp", 1.0, 1000.0});
  p.push_back(q31loop::kernels_param());
  return p;
}

const Registrar reg_test_motor({"observer-test-motor",
                                "Paper 002 Figs. 8-9: the 0.3 kW test motor of Table I, sensorless "
                                "speed control through the drive: full-load step at 200 or "
                                "800 r/min, ramp 200 -> 1000 r/min, or start-stop",
                                2.5, test_motor_params(), run_test_motor});

// ----------------------------------------------- observer-lowspeed-sweep
void run_sweep(RunContext& ctx) {
  const Machine m = test_motor_300w();
  SilOptions o = options_from(ctx.params);
  o.lowspeed_fallback = false;  // on purpose: find where the loop stops working
  const double tl = ctx.params.get("load_frac") * m.rated_torque_nm;
  const double hold = ctx.params.get("hold_s");
  ctx.csv.columns({"speed_ref_rpm", "works_1", "speed_mean_rpm", "speed_ripple_rms_rpm",
                   "angle_err_mean_rad", "angle_err_max_rad", "fault_1", "ctrl_err_1",
                   "fault_time_s"});
  const std::vector<double> speeds = {400, 200, 100, 60, 40, 30, 20, 10, 5, 0};
  int idx = 0;
  for (double rpm : speeds) {
    // the load is applied once the loop runs (0.6 s, after the I-f start:
    // an I-f start against half the rated torque plus the acceleration
    // torque would need more than the 60 % I-f current)
    LoadSteps load{{{0.6, tl}}};
    Sil sil(m, o, default_ctrl_cfg(m, o), load);
    if (idx == 0) sil.record(ctx.summary);
    // start at 200 r/min (I-f, hand-over), settle, ramp to the target in
    // 0.5 s, hold, measure over the last half of the hold
    const double t1 = 0.8, t2 = 1.3, t3 = t2 + hold;
    auto ref = [&](double t) {
      if (t < t1) return 200 * kRpm;
      if (t < t2) return (200 + (rpm - 200) * (t - t1) / (t2 - t1)) * kRpm;
      return rpm * kRpm;
    };
    const double T = sil.board().period_s();
    const long n = std::lround(t3 / T);
    std::vector<double> w, e;
    uint32_t faults = 0;
    double t_fault = std::nan("");
    for (long k = 0; k < n; ++k) {
      const double t = sil.t_s();
      mc_ctrl_sls_set_speed_ref(&sil.ctrl(), static_cast<float>(ref(t)));
      sil.step();
      if (sil.drive().faults) {
        faults = sil.drive().faults;
        t_fault = sil.t_s();
        break;
      }
      if (sil.t_s() >= t2 + 0.5 * hold) {
        w.push_back(sil.board().state()(2));
        e.push_back(sil.angle_error());
      }
    }
    double wm = 0, wr = 0, em = 0, emax = 0;
    for (double v : w) wm += v;
    for (double v : e) em += v;
    if (!w.empty()) {
      wm /= static_cast<double>(w.size());
      em /= static_cast<double>(e.size());
      for (double v : w) wr += (v - wm) * (v - wm);
      wr = std::sqrt(wr / static_cast<double>(w.size()));
      for (double v : e) emax = std::max(emax, std::abs(v));
    }
    // Works: no fault, mean speed within max(3 r/min, 10 %) of the
    // reference, angle error below 0.35 rad (20 deg: torque still 94 %).
    const bool works = faults == 0 && !w.empty() &&
                       std::abs(wm / kRpm - rpm) <= std::max(3.0, 0.1 * rpm) && emax < 0.35;
    ctx.csv.row({rpm, works ? 1.0 : 0.0, w.empty() ? std::nan("") : wm / kRpm,
                 w.empty() ? std::nan("") : wr / kRpm, w.empty() ? std::nan("") : em,
                 w.empty() ? std::nan("") : emax, static_cast<double>(faults),
                 static_cast<double>(sil.drive().tm.ctrl_err), t_fault});
    ctx.progress.update(++idx, static_cast<double>(speeds.size()));
  }
}

auto sweep_params() {
  auto p = common_params();
  // realistic defaults for the sweep: the paper's 2 us dead time of which
  // the controller knows 80 %, sensor noise and a 10 % resistance error
  for (auto& s : p) {
    if (s.key == "dead_time_s") s.default_value = 2e-6;
    if (s.key == "dead_comp_frac") s.default_value = 0.8;
    if (s.key == "noise_rms_a") s.default_value = 0.02;
    if (s.key == "r_error") s.default_value = 0.1;
  }
  p.push_back({"load_frac", 0.5, "1", "constant load as a fraction of rated torque", 0.0, 1.5});
  p.push_back({"hold_s", 1.5, "s", "time at each speed (the last half is measured)", 0.2, 20.0});
  return p;
}

const Registrar reg_sweep({"observer-lowspeed-sweep",
                           "Sensorless loop on the 0.3 kW test motor from 400 r/min down to "
                           "standstill (low-speed fallback off): one row per speed with the "
                           "steady angle error, speed ripple and whether the loop works",
                           0.0, sweep_params(), run_sweep});

// ----------------------------------------------------------- ii-observer
void run_ii(RunContext& ctx) {
  const Machine m = test_motor_300w();
  SilOptions o = options_from(ctx.params);
  o.encoder_cpr = static_cast<int>(ctx.params.get("encoder_cpr"));
  const double tl = ctx.params.get("load_frac") * m.rated_torque_nm;
  const double t_step = ctx.params.get("t_load_s");
  LoadSteps load{{{t_step, tl}}};
  Sil sil(m, o, default_ctrl_cfg(m, o), load);
  sil.record(ctx.summary);
  const double w0 = ctx.params.get("speed_rpm") * kRpm;
  const double bw = ctx.params.get("bw_rad_s");
  const double dt = sil.board().period_s();
  const double pp = m.motor.pole_pairs, kt = 1.5 * pp * m.motor.flux_wb;

  // I&I: a1 = 6, a2 = 8.5 (k1 = 2.29); t_unit so that k1 / t_unit = bw.
  mc_iiobs_f32_cfg_t ic{};
  ic.j_kgm2 = static_cast<float>(m.motor.J_kgm2);
  ic.f_nms_rad = static_cast<float>(m.motor.B_nms_rad);
  ic.a1 = 6.0f;
  ic.a2 = 8.5f;
  ic.k4 = 1.0f;
  ic.t_unit_s = static_cast<float>(2.2929 / bw);
  ic.dt_s = static_cast<float>(dt);
  ic.r_max = 1000.0f;
  mc_iiobs_f32_t ii{};
  if (mc_iiobs_f32_init(&ii, &ic) != 0u) throw UsageError("I&I observer rejected its config");
  // PLL on the encoder angle, same bandwidth
  mc_spdpll_f32_cfg_t pc{static_cast<float>(bw), static_cast<float>(dt), 1000.0f};
  mc_spdpll_f32_t pll{};
  if (mc_spdpll_f32_init(&pll, &pc) != 0u) throw UsageError("PLL rejected its config");
  // dirty derivative: first-order filtered difference of the unwrapped
  // encoder angle, bandwidth bw
  double dd = 0, th_prev = 0, tau_prev = 0;
  bool first = true;

  ctx.summary.set("ii_a1", ic.a1);
  ctx.summary.set("ii_a2", ic.a2);
  ctx.summary.set("ii_k4", ic.k4);
  ctx.summary.set("ii_t_unit_s", ic.t_unit_s);
  ctx.summary.set("ii_k1", ii.k.k1);
  ctx.summary.set("ii_k2", ii.k.k2);
  ctx.summary.set("ii_k3", ii.k.k3);
  ctx.summary.set("ii_k5", ii.k.k5);
  ctx.summary.set("estimator_bw_rad_s", bw);

  ctx.csv.columns({"t", "omega_m_rad_s", "omega_ii_rad_s", "omega_pll_rad_s", "omega_dd_rad_s",
                   "tau_load_nm", "tau_load_ii_nm", "tau_e_est_nm", "theta_m_enc_rad", "r_1"});
  const long n = std::lround(ctx.duration_s / dt);
  const long every = std::max(1L, n / 6000);
  std::vector<double> tv, ew_ii, ew_pll, ew_dd, el;
  for (long k = 0; k <= n; ++k) {
    mc_ctrl_sls_set_speed_ref(&sil.ctrl(), static_cast<float>(w0));
    sil.step();
    if (sil.drive().faults) throw std::runtime_error("drive faulted");
    const double t = sil.t_s();
    const auto& tmd = sil.drive().tm;
    const double th = tmd.theta_m_rad;  // encoder, quantised
    // electrical torque from the measured currents at the encoder angle
    float s, c, al, be, d, q;
    mc_sincos_f32(static_cast<float>(tmd.theta_e_rad), &s, &c);
    al = tmd.ia_a;
    be = static_cast<float>((tmd.ia_a + 2.0 * tmd.ib_a) / std::sqrt(3.0));
    d = c * al + s * be;
    q = -s * al + c * be;
    (void)d;
    const double tau_now = kt * q;
    const double tau_avg = first ? tau_now : 0.5 * (tau_now + tau_prev);
    tau_prev = tau_now;
    mc_iiobs_f32_step(&ii, static_cast<float>(th), static_cast<float>(tau_avg));
    float wp_f = 0.0f;
    (void)mc_spdpll_f32_step(&pll, static_cast<float>(th), &wp_f);
    const double wp = wp_f;
    if (first) {
      th_prev = th;
      first = false;
      mc_iiobs_f32_reset(&ii, static_cast<float>(th), 0.0f, 0.0f);
    }
    const double dth = std::remainder(th - th_prev, 2 * kPi);
    th_prev = th;
    dd += bw * dt * (dth / dt - dd);
    const double w = sil.board().state()(2);
    const double wi = mc_iiobs_f32_get_omega_m_rad_s(&ii), li = mc_iiobs_f32_get_tau_load_nm(&ii);
    tv.push_back(t);
    ew_ii.push_back(wi - w);
    ew_pll.push_back(wp - w);
    ew_dd.push_back(dd - w);
    el.push_back(li - sil.load_nm(t));
    if (k % every == 0 || k == n) {
      ctx.csv.row({t, w, wi, wp, dd, sil.load_nm(t), li, tau_now, th, ii.r});
      ctx.progress.update(t, ctx.duration_s);
    }
  }
  RunResult r;
  r.t = tv;
  // steady noise (rms of the error) before the load step, and the largest
  // error after it
  ctx.summary.set("ii_speed_err_rms_steady_rad_s", stddev(r, ew_ii, t_step - 0.3, t_step));
  ctx.summary.set("pll_speed_err_rms_steady_rad_s", stddev(r, ew_pll, t_step - 0.3, t_step));
  ctx.summary.set("dd_speed_err_rms_steady_rad_s", stddev(r, ew_dd, t_step - 0.3, t_step));
  ctx.summary.set("ii_speed_err_max_load_step_rad_s", max_abs(r, ew_ii, t_step, t_step + 0.3));
  ctx.summary.set("pll_speed_err_max_load_step_rad_s", max_abs(r, ew_pll, t_step, t_step + 0.3));
  ctx.summary.set("dd_speed_err_max_load_step_rad_s", max_abs(r, ew_dd, t_step, t_step + 0.3));
  ctx.summary.set("ii_load_err_mean_final_nm", mean(r, el, ctx.duration_s - 0.2, 1e9));
  ctx.summary.set("ii_load_err_rms_final_nm", stddev(r, el, ctx.duration_s - 0.2, 1e9));
}

auto ii_params() {
  auto p = common_params();
  p.push_back({"speed_rpm", 400.0, "r/min", "speed reference", 150.0, 1200.0});
  p.push_back({"load_frac", 1.0, "1", "load step as a fraction of rated torque", 0.0, 1.5});
  p.push_back({"t_load_s", 1.0, "s", "time of the load step", 0.5, 100.0});
  p.push_back({"encoder_cpr", 2048.0, "1", "encoder counts per revolution", 16.0, 1e6});
  p.push_back({"bw_rad_s", 60.0, "rad/s",
               "bandwidth of the three estimators (I&I: k1 / t_unit; PLL double pole; "
               "dirty derivative pole)",
               5.0, 700.0});
  return p;
}

const Registrar reg_ii({"ii-observer",
                        "Paper 002 Sec. IV: I&I speed and load-torque observer on the test "
                        "motor's quantised encoder angle and electrical torque, with a load "
                        "step; compared with a PLL and a dirty derivative of the same angle",
                        2.0, ii_params(), run_ii});

}  // namespace
}  // namespace observer
}  // namespace mcsim
