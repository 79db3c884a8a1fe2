// cogging for any motor with cogging (`--motor FILE [--board FILE]`, issue
// 35 item 4): what the plant's cogging torque (mcsim/cogging.hpp) does to
// the drive application, measured in two phases on the same files.
//
//  1. Speed: the sensored speed PI (SPEED mode) at speed_frac times the
//     rated speed; after the ramp and 40 / speed_wc of settling, a window of
//     at least window_periods (default 20) cogging periods and 10 /
//     speed_wc. A longer window (e.g. 400) separates a lasting ripple at
//     orders of the turn from a transient of the speed loop. The cogging torque is a
//     disturbance at N_c w (N_c = lcm(slots, 2 p) per turn) that the loop
//     rejects: speed ripple ~ A / |J s + B + kt C(s)| at s = j N_c w.
//  2. Hold: POSITION mode holding where it started (no move); after
//     20 / pos_kp_per_s, a step load of hold_load_frac rated torque; the
//     rotor's excursion from the held angle over the following 20 /
//     pos_kp_per_s.
//
// The speed is the plant's (the rotor's true speed): the physical ripple,
// not the drive's encoder tracking loop's estimate (filtered at its
// bandwidth and quantised to counts), which the summary gives besides.
//
// Summary:
//   cogging_order            N_c = lcm(slots, 2 pole_pairs) per turn
//   cogging_freq_rad_s       N_c w_t: the disturbance's frequency
//   speed_target_rad_s       speed_frac speed_rated_eff
//   speed_ripple_pp_rad_s    peak-to-peak of the true speed in the window
//   speed_mean_rad_s         its mean
//   speed_ripple_cog_amp_rad_s  the amplitude of its line at the cogging
//                            order (locked to N_c theta): the ripple the
//                            cogging makes, apart from what is not locked
//                            to the angle (the current ADC's counts, the
//                            encoder's through the loop)
//   speed_est_ripple_pp_rad_s  peak-to-peak of the drive's speed estimate
//   iq_ref_pp_a              peak-to-peak of the current reference
//   hold_err_pp_rad          peak-to-peak of the true angle after the load
//                            step (the held angle included)
//   hold_err_max_rad         largest |angle - held angle| after the step
//   hold_load_nm             the step
//   speed_phase_s, hold_phase_s  the phases' simulated times (--duration
//                            caps their sum; a window it cuts is not measured)
//   cog_status, cog_status_name  the drive's cog_status (MC_COG_ST_*) as the
//                            speed phase starts: OK the map is attached;
//                            EMPTY none, ENCODER made with another encoder or
//                            offset (the drive then runs without it)
//   cog_ff_pp_a              peak-to-peak of the drive's anticogging
//                            feed-forward in the window (0: no map applied)
//   cog_ff_max_abs_a         its largest magnitude over the speed phase
//                            (a run cut before the window has it too)
//   cog_saved, cog_save_seq  with --flash and a calibration: 1 once the map
//                            and the set are SAVEd, and the store's sequence
// The CSV's cog_ff_a column is that feed-forward, every row.
//
// --flash FILE with --set anticogging=1 (cog_cal 1): after the speed
// window the drive is disabled and SAVEs (the map with the set in force,
// anticogging 1, as `mdtool calibrate --cogging --save` does); a run with
// --set cog_cal=0 then boots from FILE: a simulated power cycle onto the
// stored map (--set theta_m0_rad=X: at another rotor angle).
// With the table parameter `anticogging` (when the firmware has it) set by
// --set like any other; the drive's `cog_slots` is the motor file's slots
// (--set cog_slots=N overrides it; 0: unknown, the calibration finds the
// order in its currents, mc_cog_find_order, or keeps every order).
//
// Verdict: refused (exit 2, named) on a motor without cogging; a fault or
// stop is the failure; otherwise pass once both figures are measured
// (finite): the scenario measures, the tests hold it to the analytic
// estimate (tests/sil/motors/test_cogging_scenario_sil.cpp).
#include <algorithm>
#include <complex>
#include <cmath>
#include <functional>
#include <limits>
#include <memory>
#include <string>

#include "app_params.hpp"
#include "app_scenario.hpp"
#include "scenario.hpp"
#include "verdict.hpp"
#include "mcsim/cogging.hpp"
extern "C" {
#include "commission/mc_comm_cog.h"
#include "mc_can_proto.h"
#include "mc_param_srv.h"
}

namespace mcsim {
namespace {

constexpr double kTwoPi = 6.283185307179586476925;
constexpr const char* kAnticogging = "anticogging";

// The table's anticogging parameter when the firmware has one (-1: none).
int32_t anticogging_index() {
  return mc_param_find_name(kAnticogging);
}

double table_value(const mc_param_info_t& info, mc_param_value_t v) {
  return info.type == MC_PARAM_TYPE_U32 ? static_cast<double>(v.u) : static_cast<double>(v.f);
}

// Whether the keys every drive scenario shares (the gains, the power-up
// keys) already hold anticogging: then params_from_files sets it.
bool shared_key(const MotorFiles& f) {
  for (const auto& s : app_gain_params(f)) {
    if (s.key == kAnticogging) return true;
  }
  for (const auto& s : app_powerup_params(f)) {
    if (s.key == kAnticogging) return true;
  }
  return false;
}

std::vector<ParamSpec> cogging_params(const MotorFiles& f) {
  std::vector<ParamSpec> p = {
      {"speed_frac", 0.10, "1", "speed of the ripple measurement, fraction of rated speed", 1e-3,
       1.0},
      {"hold_load_frac", 0.05, "1", "step load in the position hold, fraction of rated torque",
       -1.0, 1.0},
      {"window_periods", 20.0, "1",
       "the speed window's length in cogging periods (at least 10 / speed_wc)", 1.0, 1.0e5},
      {"csv_every", 0.0, "1", "write every n-th PWM period (0: all up to 20000 rows)", 0.0, 1.0e9},
      {"cog_cal", 1.0, "1",
       "with anticogging=1: 1 the drive calibrates its map first (anticogging 2), 0 it runs on "
       "the map it booted (--flash)",
       0.0, 1.0},
      {"cog_slots", -1.0, "1",
       "the drive's cog_slots parameter: the map's kept orders (-1: the motor file's slots, 0: "
       "unknown: the calibration finds the order, or keeps every order)",
       -1.0, 1000.0}};
  for (auto& s : app_gain_params(f)) p.push_back(s);
  if (anticogging_index() >= 0 && !shared_key(f)) {
    const int32_t i = anticogging_index();
    const mc_param_info_t& info = mc_param_table[i];
    p.push_back({kAnticogging, table_value(info, info.def), mc_param_units[i],
                 "the table's parameter: the drive's cogging compensation",
                 table_value(info, info.min), table_value(info, info.max)});
  }
  return p;
}

// The --set anticogging value onto the table (when it has the parameter and
// the shared keys do not already carry it).
void set_anticogging(const MotorFiles& f, const Params& P, mc_params_t* p) {
  const int32_t i = anticogging_index();
  if (i < 0 || shared_key(f) || !P.was_set(kAnticogging)) return;
  const mc_param_info_t& info = mc_param_table[i];
  const double v = P.get(kAnticogging);
  mc_param_value_t raw;
  if (info.type == MC_PARAM_TYPE_U32) {
    raw.u = static_cast<uint32_t>(std::lround(v));
  } else {
    raw.f = static_cast<float>(v);
  }
  if (mc_param_check_value(&info, raw.u) != MC_PARAM_OK) {
    throw UsageError("--set anticogging: outside the parameter table's range");
  }
  mc_param_set_raw(p, &info, raw.u);
}

struct Span {  // running min / max / sum of a signal
  double lo = std::numeric_limits<double>::infinity(), hi = -lo, sum = 0;
  long n = 0;
  void add(double v) {
    lo = std::min(lo, v);
    hi = std::max(hi, v);
    sum += v;
    ++n;
  }
  double pp() const { return n ? hi - lo : std::nan(""); }
  double mean() const { return n ? sum / static_cast<double>(n) : std::nan(""); }
};

struct Phase {  // what a phase hands back: "" or the fault / stop that ended it
  std::string stopped;
  uint32_t faults = 0;
};

Phase end_of(AppRunner& run, const std::string& stopped) {
  return {stopped, run.probe().faults};
}

// With --set anticogging=1: the drive calibrates its map first, as a host
// runs it (mc_app.h, anticogging 2): enabled in SPEED at rest, PARAM_REQ
// WRITE anticogging 2 and APPLY; the drive's turns until cog_cal_status
// (read every 50 ms) reads DONE (the drive then runs with anticogging 1) or
// FAILED. Returns "" or the reason; *t_s the time it took.
std::string calibrate(RunContext& ctx, AppRunner& run, double* t_s) {
  hal_host::PmsmBoard& board = run.board();
  const double t0 = board.t_s();
  const double w = static_cast<double>(MC_APP_COG_CAL_SPEED_RAD_S);
  // two ramps each way, two settles, two turns at w, and their 2x limits
  const double t_max =
      static_cast<double>(MC_APP_COG_CAL_PASSES) *
          (3.0 * static_cast<double>(MC_APP_COG_CAL_RAMP_S) +
           2.0 * static_cast<double>(MC_APP_COG_CAL_SETTLE_S) +
           2.0 * static_cast<double>(MC_COMM_COG_TIME_FACTOR) * 1.01 * kTwoPi / w) +
      1.0;
  run.send(run.cmd().param_req(MC_PARAM_OP_WRITE, MC_PARAM_ID_ANTICOGGING, 2.0));
  run.send(run.cmd().param_op(MC_PARAM_OP_APPLY));
  const uint32_t node = run.target().params().can_node_id;
  double next_read = 0.05;
  AppWatch watch;
  for (;;) {
    const double t = board.t_s() - t0;
    if (t > t_max) return "the anticogging calibration did not end in time";
    if (t >= next_read) {
      run.send(run.cmd().param_req(MC_PARAM_OP_READ, MC_PARAM_ID_COG_CAL_STATUS, 0.0));
      next_read += 0.05;
    }
    std::string stopped = watch(run.probe());
    if (!stopped.empty()) return stopped;
    run.step();
    if ((std::lround(t / board.period_s()) & 1023) == 0) ctx.progress.update(t, t_max);
    for (const mc_hal_can_frame_t& f : run.sent()) {
      uint32_t msg = 0;
      float v[MC_CAN_NSIG_MAX];
      if (mc_can_id_node(f.id) != node || mc_can_proto_unpack(&f, &msg, v, MC_CAN_NSIG_MAX) != 0 ||
          msg != MC_CAN_MSG_PARAM_REPLY) {
        continue;
      }
      if (static_cast<uint32_t>(v[MC_CAN_PARAM_REPLY_OPCODE]) == MC_PARAM_OP_APPLY &&
          static_cast<uint32_t>(v[MC_CAN_PARAM_REPLY_STATUS]) != MC_PARAM_OK) {
        return "anticogging 2 refused: MC_PARAMS_ERR_* " +
               std::to_string(static_cast<uint32_t>(v[MC_CAN_PARAM_REPLY_VALUE]));
      }
      if (static_cast<uint32_t>(v[MC_CAN_PARAM_REPLY_PARAM_ID]) != MC_PARAM_ID_COG_CAL_STATUS) {
        continue;
      }
      const uint32_t st = static_cast<uint32_t>(v[MC_CAN_PARAM_REPLY_VALUE]);
      ctx.summary.set("cog_cal_status", st);
      if ((st & 0xFFu) == MC_COMM_COG_DONE) {
        *t_s = board.t_s() - t0;
        return "";
      }
      if ((st & 0xFFu) == MC_COMM_COG_FAILED) {
        return "anticogging calibration failed: cog_cal_status " + std::to_string(st);
      }
    }
  }
}

// The reply to a PARAM_REQ of opcode op among the frames the application
// sent in the last step: true with its status and value, false when none.
bool param_reply(AppRunner& run, uint32_t op, uint32_t* status, uint32_t* value) {
  const uint32_t node = run.target().params().can_node_id;
  for (const mc_hal_can_frame_t& f : run.sent()) {
    uint32_t msg = 0;
    float v[MC_CAN_NSIG_MAX];
    if (mc_can_id_node(f.id) != node || mc_can_proto_unpack(&f, &msg, v, MC_CAN_NSIG_MAX) != 0 ||
        msg != MC_CAN_MSG_PARAM_REPLY ||
        static_cast<uint32_t>(v[MC_CAN_PARAM_REPLY_OPCODE]) != op) {
      continue;
    }
    *status = static_cast<uint32_t>(v[MC_CAN_PARAM_REPLY_STATUS]);
    *value = static_cast<uint32_t>(v[MC_CAN_PARAM_REPLY_VALUE]);
    return true;
  }
  return false;
}

// With --flash, after a calibration and the speed window: the map and the
// set in force (anticogging 1) stored as a host stores them (mdtool
// calibrate --cogging --save): DISABLE, then once the drive is idle (the
// application stores a map only then: mc_app_cog_save) PARAM SAVE, which
// stores the configuration and the map behind it. The board's flash then
// holds what its next power-up boots (--set cog_cal=0). Returns "" or why
// not (cog_saved 1 in the summary when stored).
std::string save_calibration(RunContext& ctx, AppRunner& run) {
  hal_host::PmsmBoard& board = run.board();
  const double t0 = board.t_s();
  constexpr double kStopMaxS = 5.0, kReplyMaxS = 1.0;  // a ramp to rest; a reply within periods
  run.send(run.cmd().enable(false));
  while (run.probe().mode != MC_DRIVE_MODE_IDLE) {
    if (run.probe().faults != 0u)
      return "a fault before the SAVE: " + drive_fault_names(run.probe().faults);
    if (board.t_s() - t0 > kStopMaxS) return "the drive did not stop for the SAVE";
    run.step();
  }
  const double t1 = board.t_s();
  run.send(run.cmd().param_op(MC_PARAM_OP_SAVE));
  uint32_t status = 0, value = 0;
  for (;;) {
    if (board.t_s() - t1 > kReplyMaxS) return "no reply to the SAVE";
    run.step();
    if (!param_reply(run, MC_PARAM_OP_SAVE, &status, &value)) continue;
    if (status != MC_PARAM_OK) {
      return "the SAVE refused: MC_PARAM status " + std::to_string(status) + " (value " +
             std::to_string(value) + ")";
    }
    ctx.summary.set("cog_saved", 1.0);
    ctx.summary.set("cog_save_seq", value);
    return "";
  }
}

const char* cog_status_name(uint32_t st) {
  static const char* const names[] = {"OK",        "EMPTY",     "LAYOUT", "CRC",  "ENCODER",
                                      "NONFINITE", "AMPLITUDE", "ARG",    "FLASH"};
  return st < 9u ? names[st] : "?";
}

bool calibrates(const RunContext& ctx) {
  return anticogging_index() >= 0 && ctx.params.was_set(kAnticogging) &&
         std::lround(ctx.params.get(kAnticogging)) == 1 &&
         std::lround(ctx.params.get("cog_cal")) == 1;
}

// The true speed's line at the cogging order over the window: the
// amplitude of its component locked to N_c theta (the ripple the cogging
// torque makes, apart from what is not locked to the angle).
struct CogLine {
  double n_c = 0.0;
  std::complex<double> we{}, e{};
  double sw = 0.0;
  long n = 0;
  void add(double w, double theta) {
    const std::complex<double> r = std::polar(1.0, -n_c * theta);
    we += w * r;
    e += r;
    sw += w;
    ++n;
  }
  // 2 |mean((w - mean w) e^{-j N_c theta})|
  double amp() const {
    return n > 0 ? 2.0 * std::abs(we - (sw / static_cast<double>(n)) * e) / static_cast<double>(n)
                 : std::nan("");
  }
};

// The speed phase's measurements over its window.
struct SpeedSpans {
  Span w_true, w_est, iq_ref, cog_ff;
  CogLine line;
};

// Phase 1: the speed loop at w_t; the window's spans.
Phase speed_phase(RunContext& ctx, const mc_params_t& p, double w_t, double n_c, double cap_s,
                  SpeedSpans* sp) {
  const MotorFiles& f = *ctx.files;
  const mc_params_eff_t e = resolve_params(p);
  const double wc = e.g.speed_wc_rad_s;
  const double t0 = 0.01;
  const double t_acc = std::abs(w_t) / static_cast<double>(e.p.speed_ramp_rad_s2);
  const double t_win0 = t0 + t_acc + 40.0 / wc;
  const double win =
      std::max(ctx.params.get("window_periods") * kTwoPi / (n_c * std::abs(w_t)), 10.0 / wc);
  const double dur = std::min(t_win0 + win, cap_s);
  const std::unique_ptr<AppTarget> target = make_file_target(ctx, f, p, nullptr);
  AppRunner run(*target);
  run.start(MC_CAN_CTRL_SPEED, true);
  hal_host::PmsmBoard& board = run.board();
  ctx.summary.set("angle_find_s", run.finish_angle_find());
  if (calibrates(ctx)) {
    double t_cal = 0.0;
    const std::string why = calibrate(ctx, run, &t_cal);
    if (!why.empty()) {
      ctx.summary.set("speed_phase_s", 0.0);
      return end_of(run, why);
    }
    ctx.summary.set("cog_cal_s", t_cal);
  }
  const double t_origin = board.t_s();
  const long n = step_count(dur, board.period_s());
  const long every = std::lround(ctx.params.get("csv_every")) > 0
                         ? std::lround(ctx.params.get("csv_every"))
                         : std::max(1L, n / 10000);
  bool sent = false;
  std::string stopped;
  AppWatch watch;
  double id = 0, iq = 0, ff_max = 0;
  for (long k = 0; k <= n; ++k) {
    const double t = board.t_s() - t_origin;
    if (!sent && t >= t0) {
      run.send(run.cmd().speed_ref(w_t));
      sent = true;
    }
    const double w = board.state()(2);
    const mc_app_probe_t& q = run.probe();
    if (k == 0) {  // the map's status as the phase starts (after a calibration)
      ctx.summary.set("cog_status", q.cog_status);
      ctx.summary.set_text("cog_status_name", cog_status_name(q.cog_status));
    }
    ff_max = std::max(ff_max, std::abs(static_cast<double>(q.cog_ff_a)));
    if (t >= t_win0) {
      sp->w_true.add(w);
      sp->line.add(w, board.state()(3));
      sp->w_est.add(q.omega_m_rad_s);
      sp->iq_ref.add(q.iq_ref_a);
      sp->cog_ff.add(q.cog_ff_a);
    }
    if (k % every == 0) {
      board.true_dq_a(&id, &iq);
      const double row[] = {0.0,       t, w, q.omega_m_rad_s, q.iq_ref_a, iq, board.state()(3),
                            q.cog_ff_a};
      ctx.csv.row(row, 8);
    }
    stopped = watch(q);
    if (!stopped.empty() || k == n) break;
    run.step();
    if ((k & 1023) == 0) ctx.progress.update(t, dur);
  }
  ctx.summary.set("cog_ff_max_abs_a", ff_max);
  ctx.summary.set("speed_phase_s", dur);
  ctx.summary.set("speed_window_s", win);
  ctx.summary.set("speed_window_start_s", t_win0);
  if (stopped.empty() && calibrates(ctx) && ctx.flash != nullptr && sp->w_true.n > 0) {
    stopped = save_calibration(ctx, run);
  }
  return end_of(run, stopped);
}

// Phase 2: position hold, a step load; the angle's excursion after it.
Phase hold_phase(RunContext& ctx, const mc_params_t& p, double tau_step, double cap_s,
                 Span* th_after, double* th_hold, double* err_max) {
  const MotorFiles& f = *ctx.files;
  const mc_params_eff_t e = resolve_params(p);
  const double settle = 20.0 / e.g.pos_kp_per_s;
  const double t_step = 0.01 + settle;
  const double dur = std::min(t_step + settle, cap_s);
  double t_origin = 0.0;
  const std::function<double(double)> load = [tau_step, t_step, &t_origin](double t) {
    return t - t_origin >= t_step ? tau_step : 0.0;
  };
  const std::unique_ptr<AppTarget> target = make_file_target(ctx, f, p, &load);
  AppRunner run(*target);
  hal_host::PmsmBoard& board = run.board();
  if (calibrates(ctx)) {  // in SPEED, then POSITION from where it stopped
    run.start(MC_CAN_CTRL_SPEED, true);
    (void)run.finish_angle_find();
    double t_cal = 0.0;
    const std::string why = calibrate(ctx, run, &t_cal);
    if (!why.empty()) return end_of(run, why);
    run.send(run.cmd().enable(false));
    run.send(run.cmd().mode(MC_CAN_CTRL_POSITION));
    run.send(run.cmd().enable(true));
  } else {  // a power-up find (index, align) runs first, where the table asks for it
    run.start(MC_CAN_CTRL_POSITION, true);
    (void)run.finish_angle_find();
  }
  t_origin = board.t_s();
  const long n = step_count(dur, board.period_s());
  const long every = std::max(1L, n / 10000);
  std::string stopped;
  AppWatch watch;
  double id = 0, iq = 0;
  bool held = false;
  for (long k = 0; k <= n; ++k) {
    const double t = board.t_s() - t_origin;
    const double th = board.state()(3);
    if (!held && t >= t_step) {
      *th_hold = th;  // the angle held when the load steps on
      held = true;
    }
    if (held) {
      th_after->add(th);
      *err_max = std::max(*err_max, std::abs(th - *th_hold));
    }
    const mc_app_probe_t& q = run.probe();
    if (k % every == 0) {
      board.true_dq_a(&id, &iq);
      const double row[] = {1.0, t,  board.state()(2), q.omega_m_rad_s, q.iq_ref_a,
                            iq,  th, q.cog_ff_a};
      ctx.csv.row(row, 8);
    }
    stopped = watch(q);
    if (!stopped.empty() || k == n) break;
    run.step();
    if ((k & 1023) == 0) ctx.progress.update(t, dur);
  }
  ctx.summary.set("hold_phase_s", dur);
  ctx.summary.set("hold_step_time_s", t_step);
  return end_of(run, stopped);
}

void run_cogging(RunContext& ctx) {
  const MotorFiles& f = *ctx.files;
  if (!(f.motor.slots > 0 && f.motor.cogging_nm > 0.0)) {
    throw UsageError(f.motor.file + ": cogging needs a motor with cogging_nm > 0 (and slots)");
  }
  if (f.board.encoder_cpr == 0) {
    throw UsageError(f.board.file + ": cogging needs an encoder (encoder_cpr = 0 here)");
  }
  mc_params_t p = params_from_files(f, ctx.params, MC_LAW_SPEED_PI);
  set_anticogging(f, ctx.params, &p);
  const long slots = std::lround(ctx.params.get("cog_slots"));
  p.cog_slots = static_cast<uint32_t>(slots < 0 ? f.motor.slots : slots);
  const mc_params_eff_t e = resolve_params(p);
  const double n_c = cogging_order(f.motor.slots, f.motor.pole_pairs);
  const double w_t = ctx.params.get("speed_frac") * e.g.speed_rated_eff_rad_s;
  const double tau_step = ctx.params.get("hold_load_frac") * e.g.torque_rated_nm;
  ctx.csv.columns({"phase", "t", "omega_m_rad_s", "omega_est_rad_s", "iq_ref_a", "iq_a",
                   "theta_m_rad", "cog_ff_a"});
  SpeedSpans sp;
  sp.line.n_c = n_c;
  Span th_after;
  double th_hold = 0.0, err_max = 0.0;
  // --duration caps the two phases' total (the speed phase first): a run
  // cut before a window leaves its figure unmeasured (the verdict says so).
  const double cap = ctx.duration_s > 0.0 ? run_duration(ctx, ctx.duration_s) : kMaxDurationS;
  Phase ph = speed_phase(ctx, p, w_t, n_c, cap, &sp);
  const Span& w_true = sp.w_true;
  const double used = ctx.summary.numbers().at("speed_phase_s");
  if (ph.stopped.empty() && cap - used > 0.0) {
    ph = hold_phase(ctx, p, tau_step, cap - used, &th_after, &th_hold, &err_max);
  }
  ctx.progress.done();
  const auto& nums = ctx.summary.numbers();
  ctx.summary.set("duration_s",
                  used + (nums.count("hold_phase_s") ? nums.at("hold_phase_s") : 0.0));
  record_app_setup(f, p, ctx.summary);
  ctx.summary.set("faults", ph.faults);
  ctx.summary.set("cogging_order", n_c);
  ctx.summary.set("cogging_nm", f.motor.cogging_nm);
  ctx.summary.set("cogging_freq_rad_s", n_c * std::abs(w_t));
  ctx.summary.set("speed_target_rad_s", w_t);
  ctx.summary.set("speed_frac", ctx.params.get("speed_frac"));
  if (anticogging_index() >= 0) {
    ctx.summary.set("anticogging", ctx.params.get(kAnticogging));
  }
  if (!ph.stopped.empty()) {
    ctx.summary.set_text("fault_names", ph.stopped);
    return write_verdict(ctx.summary, ph.faults != 0u ? faulted(ph.faults, ph.stopped)
                                                      : Verdict{"stopped", ph.stopped, true});
  }
  ctx.summary.set("speed_ripple_pp_rad_s", w_true.pp());
  ctx.summary.set("speed_mean_rad_s", w_true.mean());
  ctx.summary.set("speed_ripple_cog_amp_rad_s", sp.line.amp());
  ctx.summary.set("speed_est_ripple_pp_rad_s", sp.w_est.pp());
  ctx.summary.set("iq_ref_pp_a", sp.iq_ref.pp());
  ctx.summary.set("cog_ff_pp_a", sp.cog_ff.pp());
  ctx.summary.set("hold_load_nm", tau_step);
  ctx.summary.set("hold_theta_rad", th_hold);
  ctx.summary.set("hold_err_pp_rad", th_after.pp());
  ctx.summary.set("hold_err_max_rad", err_max);
  Judge j;
  j.require("ripple not measured", std::isfinite(w_true.pp()) && w_true.n > 1,
            "speed ripple measured over the window");
  j.require("hold error not measured", std::isfinite(th_after.pp()) && th_after.n > 1,
            "hold error measured after the load step");
  j.note("measured, not bounded here: the tests hold the ripple to the loop's analytic estimate");
  write_verdict(ctx.summary, j.verdict());
}

const Registrar reg_cogging(on_app_target(
    {"cogging",
     "any motor with cogging (slots, cogging_nm): speed ripple of the speed PI at speed_frac of "
     "rated speed (speed_ripple_pp_rad_s) and the position error in hold under a step load "
     "(hold_err_pp_rad); --set anticogging=0|1 when the firmware has that parameter",
     0.0,
     {},
     run_cogging,
     cogging_params}));

}  // namespace
}  // namespace mcsim
