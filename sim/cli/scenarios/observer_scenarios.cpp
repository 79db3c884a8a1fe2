// Paper 002 scenarios through the firmware path (drive + sensorless plug-in
// on the simulated board): observer-table1 (Figs. 5-7), observer-test-motor
// (Figs. 8-9), observer-lowspeed-sweep, ii-observer.
#include <algorithm>
#include <cmath>
#include <deque>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "observer_sil.hpp"
#include "scenario.hpp"
#include "scenarios/q31_loops.hpp"
#include "verdict.hpp"
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

// One sample of a profile run (after the period's step).
struct ProfileSample {
  double t, w, wref, what, err, iq, tau_e;
};

// A run of the sensorless drive with a speed reference profile and a load
// profile; writes the standard CSV (about 6000 rows) and hands every
// period's sample to each(): the metrics are computed on the fly, so the
// run keeps no trajectory in memory.
struct RunResult {
  double first_handover_s = std::nan("");
  uint32_t faults = 0;
  double w_last = 0.0;
};

RunResult run_profile(RunContext& ctx, Sil& sil, const std::function<double(double)>& ref,
                      const std::function<void(const ProfileSample&, const RunResult&)>& each) {
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
  const long n = step_count(ctx.duration_s, T);
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
    if (tm.handovers != handovers && std::isnan(r.first_handover_s)) r.first_handover_s = tt;
    handovers = tm.handovers;
    r.w_last = x(2);
    each(ProfileSample{tt, x(2), ref(t), tm.omega_hat_m_rad_s, sil.angle_error(), iq,
                       sil.board().torque_nm()},
         r);
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

// max |y| over t in [a, b), fed in time order.
class WinMax {
 public:
  WinMax(double a, double b) : a_(a), b_(b) {}
  void add(double t, double y) {
    if (t >= a_ && t < b_) m_ = std::max(m_, std::abs(y));
  }
  double value() const { return m_; }

 private:
  double a_, b_, m_ = 0.0;
};

// mean of y over t in [a, b) (NaN if empty), summed in time order.
class WinMean {
 public:
  WinMean(double a, double b) : a_(a), b_(b) {}
  void add(double t, double y) {
    if (t >= a_ && t < b_) {
      s_ += y;
      ++n_;
    }
  }
  double value() const { return n_ ? s_ / static_cast<double>(n_) : std::nan(""); }

 private:
  double a_, b_, s_ = 0.0;
  long n_ = 0;
};

// Values over a window [a, b) kept for a two-pass statistic: memory set by
// the window's length, not the run's.
class WinValues {
 public:
  WinValues(double a, double b) : a_(a), b_(b) {}
  void add(double t, double y) {
    if (t >= a_ && t < b_) v_.push_back(y);
  }
  double mean() const {
    double s = 0;
    for (double y : v_) s += y;
    return v_.empty() ? std::nan("") : s / static_cast<double>(v_.size());
  }
  double stddev() const {
    const double m = mean();
    double s = 0;
    for (double y : v_) s += (y - m) * (y - m);
    return v_.empty() ? std::nan("") : std::sqrt(s / static_cast<double>(v_.size()));
  }

 private:
  double a_, b_;
  std::vector<double> v_;
};

// Transient at the first hand-over (IF -> CLOSED): the largest change of
// the electromagnetic torque and of the true q current over one PWM period
// within 3 periods either side of the switch, against the largest
// per-period change in the 20 ms of I-f before it; and the torque change
// over the following 5 ms (set by the speed loop taking over, not by the
// switch). Fed every sample; keeps the last 20 ms (and a few periods) until
// the hand-over and then the 5 ms after it.
class HandoverAcc {
 public:
  explicit HandoverAcc(double period_s)
      : keep_(static_cast<size_t>(std::ceil(0.02 / period_s)) + 8) {}
  void add(const ProfileSample& s, double t_handover) {
    if (n_ == 1) T_ = s.t - first_t_;
    if (n_ == 0) first_t_ = s.t;
    ++n_;
    if (std::isnan(t_handover)) {  // before: remember the recent past
      buf_.push_back(s);
      if (buf_.size() > keep_) buf_.pop_front();
      return;
    }
    if (std::isnan(t0_)) {  // the hand-over: the past first, then this sample
      t0_ = t_handover;
      have_prev_ = false;
      for (const ProfileSample& p : buf_) feed(p);
      buf_.clear();
    }
    if (s.t <= t0_ + std::max(0.005, 3.5 * T_) + T_) feed(s);
  }
  void write(Summary& sm) const {
    sm.set("handover_time_s", t0_);
    if (std::isnan(t0_)) return;
    sm.set("handover_torque_step_per_period_nm", jump_);
    sm.set("handover_iq_step_per_period_a", jump_iq_);
    sm.set("if_torque_step_per_period_nm", before_);
    sm.set("handover_torque_change_5ms_nm", dtau5_);
  }

 private:
  void feed(const ProfileSample& s) {
    if (have_prev_) {
      const double d = std::abs(s.tau_e - prev_.tau_e);
      if (std::abs(s.t - t0_) <= 3.5 * T_) {
        jump_ = std::max(jump_, d);
        jump_iq_ = std::max(jump_iq_, std::abs(s.iq - prev_.iq));
        if (std::isnan(tau0_)) tau0_ = prev_.tau_e;
      }
      if (s.t >= t0_ - 0.02 && s.t < t0_ - 3.5 * T_) before_ = std::max(before_, d);
      if (!std::isnan(tau0_) && s.t > t0_ && s.t <= t0_ + 0.005) {
        dtau5_ = std::max(dtau5_, std::abs(s.tau_e - tau0_));
      }
    }
    prev_ = s;
    have_prev_ = true;
  }
  size_t keep_;
  std::deque<ProfileSample> buf_;
  ProfileSample prev_{};
  bool have_prev_ = false;
  long n_ = 0;
  double first_t_ = 0.0, T_ = 1.0, t0_ = std::nan(""), tau0_ = std::nan("");
  double jump_ = 0, jump_iq_ = 0, before_ = 0, dtau5_ = 0;
};

// ------------------------------------------------------- observer-table1
// Paper 002 Figs. 5-7 on the 40 kW machine: the verdict holds the drive to
// what the figures show: no fault, the I-f start handed over to the
// observer, the angle error after 1 s within 0.1 rad electrical (measured
// 0.002: the estimate follows the rotor) and the rated load step at
// 1500 r/min rejected: 0.3 s after it the mean speed error is within 1 % of
// the reference (measured 0.02 %; the dip itself, 9 %, is reported).
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
  HandoverAcc ho(sil.board().period_s());
  WinMax ang(1.0, 1e9), dip(1.2, 1.6);
  WinMean rec(1.5, 1.6);
  const RunResult r = run_profile(ctx, sil, ref, [&](const ProfileSample& p, const RunResult& rr) {
    ho.add(p, rr.first_handover_s);
    ang.add(p.t, p.err);
    dip.add(p.t, p.wref - p.w);
    rec.add(p.t, p.wref - p.w);
  });
  ctx.summary.set("fault_bits", r.faults);
  ctx.summary.set_text("fault_names", drive_fault_names(r.faults));
  ho.write(ctx.summary);
  ctx.summary.set("angle_err_max_after_1s_rad", ang.value());
  ctx.summary.set("speed_dip_load_step_rad_s", dip.value());
  if (r.faults) return write_verdict(ctx.summary, faulted(r.faults));
  Judge j;
  j.at_least("too short to judge", "duration [s]", ctx.duration_s, 1.6,
             "the first load step's window ends at 1.6 s");
  j.require("not locked", !std::isnan(r.first_handover_s),
            "the I-f start handed over to the observer");
  j.at_most("angle error too large", "max |theta_e error| after 1 s [rad]", ang.value(), 0.1);
  j.at_most("load not rejected", "|mean speed error| 0.3 s after the load step [rad/s]",
            std::abs(rec.value()), 0.01 * 1500 * kRpm, "1 % of the reference");
  write_verdict(ctx.summary, j.verdict());
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
// Paper 002 Figs. 8-9 on the 0.3 kW motor: no fault and the hand-over, in
// every profile. Profiles 0 and 1 (Fig. 8, the load step): the speed dip
// within 60 r/min (tests/sil/observer: a full-load step at 200 r/min, 23
// measured; the figure's dip is of that order) and the speed back on the
// reference, the mean error over the last 0.3 s of the load within
// 2 r/min (the speed loop's integral action; the dead-time cases of
// sim/README leave a ripple, not an offset). Profile 3 (start-stop): the
// law falls back to I-f on the way down and the rotor ends within 0.05
// rad/s of standstill (tests/sil/observer StopsAndHoldsLoadAtStandstill).
// Profile 2 (the ramp of Fig. 9) claims no more than the fault and the
// hand-over.
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
  HandoverAcc ho(sil.board().period_s());
  WinMax e_max(t_step, t_step + 1.0);
  WinMean e_mean(t_step + 0.7, t_step + 1.0), a_no(t_step - 0.3, t_step),
      a_full(t_step + 0.7, t_step + 1.0);
  double ang_after = 0.0;
  const RunResult r = run_profile(ctx, sil, ref, [&](const ProfileSample& p, const RunResult& rr) {
    ho.add(p, rr.first_handover_s);
    const double e = p.wref - p.w;
    e_max.add(p.t, e);
    e_mean.add(p.t, e);
    a_no.add(p.t, p.err);
    a_full.add(p.t, p.err);
    if (p.t >= rr.first_handover_s + 0.3) ang_after = std::max(ang_after, std::abs(p.err));
  });
  ctx.summary.set("fault_bits", r.faults);
  ctx.summary.set_text("fault_names", drive_fault_names(r.faults));
  ho.write(ctx.summary);
  if (profile <= 1) {
    ctx.summary.set("speed_err_max_load_step_rad_s", e_max.value());
    ctx.summary.set("speed_err_max_load_step_rpm", e_max.value() / kRpm);
    ctx.summary.set("speed_err_mean_last_0.3s_of_load_rad_s", e_mean.value());
    ctx.summary.set("angle_err_mean_no_load_rad", a_no.value());
    ctx.summary.set("angle_err_mean_full_load_rad", a_full.value());
    ctx.summary.set("angle_err_max_after_handover_rad", ang_after);
  }
  if (profile == 3) {
    ctx.summary.set("fallbacks", sil.tm().fallbacks);
    ctx.summary.set("speed_final_rad_s", r.w_last);
  }
  if (r.faults) return write_verdict(ctx.summary, faulted(r.faults));
  Judge j;
  j.require("not locked", !std::isnan(r.first_handover_s),
            "the I-f start handed over to the observer");
  if (profile <= 1) {
    j.at_least("too short to judge", "duration [s]", ctx.duration_s, t_step + 1.0,
               "the load step's second");
    j.at_most("load not held", "speed dip at the load step [r/min]", e_max.value() / kRpm, 60.0);
    j.at_most("not settled", "|mean speed error| over the last 0.3 s of the load [r/min]",
              std::abs(e_mean.value()) / kRpm, 2.0);
  } else if (profile == 3) {
    j.at_least("too short to judge", "duration [s]", ctx.duration_s, t_step + 1.0,
               "the stop's second");
    j.at_least("no fallback", "fallbacks to I-f", sil.tm().fallbacks, 1.0);
    j.at_most("not stopped", "|speed| at the end [rad/s]", std::abs(r.w_last), 0.05);
  }
  write_verdict(ctx.summary, j.verdict());
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
    const long n = step_count(t3, T);
    // mean speed and angle error, speed ripple (rms about the mean, from
    // sums about the first sample) and the largest angle error over the
    // last half of the hold, on the fly
    long cnt = 0;
    double sw = 0, se = 0, c0 = 0, s1 = 0, s2 = 0, emax = 0;
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
        const double w = sil.board().state()(2), e = sil.angle_error();
        if (cnt == 0) c0 = w;
        sw += w;
        se += e;
        s1 += w - c0;
        s2 += (w - c0) * (w - c0);
        emax = std::max(emax, std::abs(e));
        ++cnt;
      }
    }
    double wm = 0, wr = 0, em = 0;
    if (cnt > 0) {
      const double nn = static_cast<double>(cnt);
      wm = sw / nn;
      em = se / nn;
      wr = std::sqrt(std::max(0.0, s2 / nn - (s1 / nn) * (s1 / nn)));
    }
    // Works: no fault, mean speed within max(3 r/min, 10 %) of the
    // reference, angle error below 0.35 rad (20 deg: torque still 94 %).
    const bool empty = cnt == 0;
    const bool works = faults == 0 && !empty &&
                       std::abs(wm / kRpm - rpm) <= std::max(3.0, 0.1 * rpm) && emax < 0.35;
    ctx.csv.row({rpm, works ? 1.0 : 0.0, empty ? std::nan("") : wm / kRpm,
                 empty ? std::nan("") : wr / kRpm, empty ? std::nan("") : em,
                 empty ? std::nan("") : emax, static_cast<double>(faults),
                 static_cast<double>(sil.drive().tm.ctrl_err), t_fault});
    ctx.progress.update(++idx, static_cast<double>(speeds.size()));
  }
  write_no_claim(ctx.summary,
                 "a map of where the sensorless loop stops working (one row per speed, with "
                 "whether it works and its drive fault): its rows are the result");
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
                           0.0,
                           sweep_params(),
                           run_sweep,
                           {},
                           /*takes_flash=*/false,
                           /*motor_optional=*/false,
                           /*takes_duration=*/false});

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
  const long n = step_count(ctx.duration_s, dt);
  const long every = std::max(1L, n / 6000);
  // The statistics' windows, fed on the fly (the two-pass ones keep their
  // window's values: memory set by the 0.3 s and 0.2 s windows).
  WinValues ii_ss(t_step - 0.3, t_step), pll_ss(t_step - 0.3, t_step), dd_ss(t_step - 0.3, t_step);
  WinMax ii_ls(t_step, t_step + 0.3), pll_ls(t_step, t_step + 0.3), dd_ls(t_step, t_step + 0.3);
  WinValues load_end(ctx.duration_s - 0.2, 1e9);
  for (long k = 0; k <= n; ++k) {
    mc_ctrl_sls_set_speed_ref(&sil.ctrl(), static_cast<float>(w0));
    sil.step();
    if (sil.drive().faults) {
      ctx.summary.set("fault_bits", sil.drive().faults);
      ctx.summary.set_text("fault_names", drive_fault_names(sil.drive().faults));
      return write_verdict(ctx.summary, faulted(sil.drive().faults));
    }
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
    ii_ss.add(t, wi - w);
    pll_ss.add(t, wp - w);
    dd_ss.add(t, dd - w);
    ii_ls.add(t, wi - w);
    pll_ls.add(t, wp - w);
    dd_ls.add(t, dd - w);
    load_end.add(t, li - sil.load_nm(t));
    if (k % every == 0 || k == n) {
      ctx.csv.row({t, w, wi, wp, dd, sil.load_nm(t), li, tau_now, th, ii.r});
      ctx.progress.update(t, ctx.duration_s);
    }
  }
  // steady noise (rms of the error) before the load step, and the largest
  // error after it
  ctx.summary.set("ii_speed_err_rms_steady_rad_s", ii_ss.stddev());
  ctx.summary.set("pll_speed_err_rms_steady_rad_s", pll_ss.stddev());
  ctx.summary.set("dd_speed_err_rms_steady_rad_s", dd_ss.stddev());
  ctx.summary.set("ii_speed_err_max_load_step_rad_s", ii_ls.value());
  ctx.summary.set("pll_speed_err_max_load_step_rad_s", pll_ls.value());
  ctx.summary.set("dd_speed_err_max_load_step_rad_s", dd_ls.value());
  ctx.summary.set("ii_load_err_mean_final_nm", load_end.mean());
  ctx.summary.set("ii_load_err_rms_final_nm", load_end.stddev());
  // Paper 002 Sec. IV (tests/sil/observer IiObserverEstimatesLoadFromEncoder):
  // the I&I observer finds the load, which the PLL and the derivative do
  // not estimate: its mean error over the last 0.2 s within 1 % of the
  // rated torque (measured 1e-4 N m of 3). That needs the run to reach
  // 0.4 s past the step (24 time constants of k1 at the default bandwidth).
  // The speed estimates' noise is compared, not judged (the I&I's is the
  // largest at this bandwidth).
  Judge j;
  j.at_least("too short to judge", "duration [s]", ctx.duration_s, t_step + 0.4,
             "the load step + 0.4 s");
  j.at_most("load not estimated", "|mean load error| at the end [N m]", std::abs(load_end.mean()),
            0.01 * m.rated_torque_nm, "1 % of rated torque");
  write_verdict(ctx.summary, j.verdict());
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
