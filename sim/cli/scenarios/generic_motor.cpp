// Scenarios for any motor (`--motor FILE [--board FILE]`): the unmodified
// drive application on the simulated board, its parameter table built from
// the files and the gains derived from it by the firmware's C
// (app_params.hpp, firmware/app/config/mc_gains.h). Every metric is computed on the fly: a run keeps
// constant memory whatever its length. The CSV keeps every PWM period up to
// 20000 rows and is decimated beyond (csv_every).
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>

#include "app_scenario.hpp"
#include "board_hall.hpp"
#include "app_params.hpp"
#include "rise_timer.hpp"
#include "scenario.hpp"
#include "verdict.hpp"
extern "C" {
#include "config/mc_law_cfg.h"
}

namespace mcsim {
namespace {

constexpr double kPi = 3.14159265358979323846;

// The sensorless law's error bits, named (the reasons a start can fail).
std::string sls_reason(uint32_t e) {
  if (e & MC_CTRL_SLS_ERR_NO_LOCK) {
    return "sensorless start-up did not lock: the observer's speed never agreed with the I-f "
           "frame at the hand-over speed (the observer's low-speed limit, or the I-f current "
           "too small for the load)";
  }
  if (e & MC_CTRL_SLS_ERR_FOC) return "the sensorless law's current loop refused a step";
  if (e & MC_CTRL_SLS_ERR_MEAS) return "non-finite measurement";
  return "sensorless law error bits " + std::to_string(e) + " (observer divergence)";
}

long csv_every(const RunContext& ctx, long n) {
  const long e = std::lround(ctx.params.get("csv_every"));
  return e > 0 ? e : std::max(1L, n / 20000);
}

// The run's duration: --duration, or the scenario's own from the motor.
double duration(RunContext& ctx, double auto_s) {
  return run_duration(ctx, auto_s);
}

ParamSpec csv_every_spec() {
  return {"csv_every", 0.0,  "1", "write every n-th PWM period (0: all up to 20000 rows)",
          0.0,         1.0e9};
}

// ------------------------------------------------------------ current step
// A hot winding (issue 33 item 2: the drive's R following the winding
// estimate, measured): the plant's temperatures and the drive's winding
// model, sim/README.md.
std::vector<ParamSpec> hot_params() {
  return {
      {"plant_thermal",
       0.0,
       "1",
       "plant: winding and housing temperatures with R(T) and flux(T) from the motor's rating "
       "(the table's winding_* values), started at t_winding0_c and read by a motor thermistor; "
       "the drive runs its winding model from there (winding_model 1)",
       0.0,
       1.0,
       {{"off", 0.0}, {"on", 1.0}}},
      {"t_winding0_c", 25.0, "degC",
       "plant_thermal=on: the winding's temperature at power-up (after an overload: the "
       "housing and the magnet still at the ambient), the drive's estimate starting from its "
       "thermistor",
       -20.0, 150.0},
      {"r_follow",
       1.0,
       "1",
       "the table's winding_r_follow (plant_thermal=on): the observer's R follows the winding "
       "estimate (1) or stays r_ohm (0)",
       0.0,
       1.0,
       {{"off", 0.0}, {"on", 1.0}}},
  };
}

// plant_thermal=on (hot_params: current-step, sensorless-speed-step): the drive's winding model and the
// plant's network from the same rating (the table's winding_* values and
// r_ohm as the plant's own), both starting at t_winding0_c: the plant's
// winding read by a motor thermistor, whose first reading starts the
// drive's estimate. The trip moves to temp_max_c 180 C (a hot start must
// not trip at the default 100 C: that trip is not what is measured).
constexpr float kHotTripC = 180.0f;

void hot_table(const Params& P, mc_params_t* p) {
  if (P.get("plant_thermal") < 0.5) {
    if (P.was_set("t_winding0_c") || P.was_set("r_follow")) {
      throw UsageError("t_winding0_c and r_follow need --set plant_thermal=on");
    }
    return;
  }
  p->winding_model = 1u;
  p->winding_r_follow = P.get("r_follow") > 0.5 ? 1u : 0u;
  p->temp_max_c = kHotTripC;
  if (mc_params_validate(p) != MC_PARAMS_OK) {
    throw UsageError("plant_thermal: the drive refuses the winding model's parameters");
  }
}

ThermalParams hot_plant_thermal(const MotorFiles& f, const mc_params_t& p, double t0_c) {
  ThermalRating r;
  r.r_ohm = f.motor.r_ohm;
  r.i_rated_a = f.motor.i_rated_a;
  r.rise_k = p.winding_rise_k;
  r.ambient_c = r.t_ref_c = p.ambient_c;
  r.winding_share = p.winding_share;
  r.tau_winding_s = p.winding_tau_s;
  r.tau_housing_s = p.housing_tau_s;
  ThermalParams t;
  if (thermal_from_rating(r, &t) != Status::kOk) {
    throw UsageError("plant_thermal: the plant refuses the thermal rating");
  }
  t.t_w0_c = t0_c;  // the housing (and the magnet with it) at the ambient
  return t;
}

// The board of a plant_thermal run (make_file_target's adjust).
std::function<void(AppSetup&)> hot_board(const MotorFiles& f, const mc_params_t& p,
                                         const Params& P) {
  if (P.get("plant_thermal") < 0.5) return {};
  const ThermalParams t = hot_plant_thermal(f, p, P.get("t_winding0_c"));
  return [t](AppSetup& s) {
    s.board.thermal_enabled = true;
    s.board.thermal = t;
    s.board.motor_thermistor = true;
  };
}

// The summary of a plant_thermal run: the plant's winding and the drive's
// estimate at the end.
void hot_summary(const Params& P, AppRunner& run, Summary& sum) {
  if (P.get("plant_thermal") < 0.5) return;
  sum.set("t_winding_c", run.board().power_stage().thermal()->winding_c());
  sum.set("t_winding_est_c", static_cast<double>(run.probe().t_winding_est_c));
  sum.set("r_follow", P.get("r_follow"));
}

std::vector<ParamSpec> current_step_params(const MotorFiles& f) {
  const mc_gains_t g = files_params_eff(f).g;  // the C derivation's, for the files
  const double L = std::max(f.motor.ld_h, f.motor.lq_h);
  // Default step: half the rated current, at most what needs half the
  // voltage limit at the first instant (kp + R) di <= v_max / 2.
  const double di =
      std::min(0.5 * g.i_rated_eff_a, 0.5 * g.v_max_v / (L * g.cur_bw_rad_s + f.motor.r_ohm));
  std::vector<ParamSpec> p = {
      {"iq_step_a", di, "A", "q-axis current step", -g.i_limit_a, g.i_limit_a},
      {"id_step_a", -0.5 * di, "A", "d-axis current step (after the q step)", -g.i_limit_a,
       g.i_limit_a},
      {"j_load_factor", 100.0, "1",
       "inertia coupled to the rotor, in motor inertias (a dyno flywheel: the rotor stays near "
       "standstill, as on a test bench)",
       0.0, 1.0e6},
      csv_every_spec()};
  for (auto& s : hot_params()) p.push_back(s);
  for (auto& s : app_gain_params(f)) p.push_back(s);
  return p;
}

void run_current_step(RunContext& ctx) {
  const MotorFiles& f = *ctx.files;
  // The drive's table from the files; the plant with the dyno's flywheel.
  mc_params_t p = params_from_files(f, ctx.params);
  hot_table(ctx.params, &p);
  const mc_params_eff_t e = resolve_params(p);
  mc_drive_cfg_t dcfg{};
  (void)mc_params_eff_to_drive_cfg(&e, &dcfg);
  MotorFiles plant = f;
  plant.motor.j_kgm2 *= 1.0 + ctx.params.get("j_load_factor");
  const std::unique_ptr<AppTarget> target =
      make_file_target(ctx, plant, p, nullptr, hot_board(f, p, ctx.params));
  AppRunner run(*target);
  run.start(MC_CAN_CTRL_CURRENT, true);
  hal_host::PmsmBoard& board = run.board();
  // The power-up find at enable (the index search or the alignment, when the
  // table asks for it): the step's time starts after it.
  const double t_find = run.finish_angle_find();
  const double t_origin = board.t_s();
  ctx.summary.set("angle_find_s", t_find);
  const double T = board.period_s();
  const double design = std::log(9.0) / e.g.cur_bw_rad_s;
  // Each step gets 12 design rise times (settled to 0.5 %) plus 2 ms (the
  // command waits up to one slow-loop period for the application's slow step).
  const double t_iq = 10 * T, t_id = t_iq + 12 * design + 2e-3;
  const double dur = duration(ctx, t_id + 12 * design + 2e-3);
  const double iq_s = ctx.params.get("iq_step_a"), id_s = ctx.params.get("id_step_a");
  const long n = step_count(dur, T);
  AppRecorder rec{ctx, run, f.motor.pole_pairs, false, csv_every(ctx, n)};
  rec.header();
  // settled: within 2 % of the step, at least 5 ADC steps (the verdict's band)
  const double lsb = 2.0 * f.board.i_sense_max_a / std::ldexp(1.0, f.board.adc_bits);
  const double band_q = std::max(0.02 * std::abs(iq_s), 5.0 * lsb),
               band_d = std::max(0.02 * std::abs(id_s), 5.0 * lsb);
  // q over its own window (the d step moves i_q a little through the
  // decoupling), d to the end
  StepResponse rq(t_iq, t_id, 0.0, iq_s, band_q), rd(t_id, 1e300, 0.0, id_s, band_d);
  double id = 0, iq = 0;
  bool sent_q = false, sent_d = false;
  std::string stopped;
  AppWatch watch;
  for (long k = 0; k <= n; ++k) {
    const double t = board.t_s() - t_origin;
    if (!sent_q && t >= t_iq) {
      run.send(run.cmd().current_ref(0.0, iq_s));
      sent_q = true;
    }
    if (!sent_d && t >= t_id) {
      run.send(run.cmd().current_ref(id_s, iq_s));
      sent_d = true;
    }
    board.true_dq_a(&id, &iq);
    rq.add(t, iq);
    rd.add(t, id);
    rec.row(t, id, iq, board.state()(2));
    stopped = watch(run.probe());
    if (!stopped.empty()) break;  // as the speed scenarios: a faulted run ends at its fault
    if (k < n) run.step();
    if ((k & 1023) == 0) ctx.progress.update(t, dur);
  }
  record_app_setup(f, p, ctx.summary);
  const mc_app_probe_t& d = run.probe();
  ctx.summary.set("faults", d.faults);
  if (!stopped.empty()) {
    ctx.summary.set_text("fault_names", stopped);
    return write_verdict(ctx.summary, d.faults != 0u ? faulted(d.faults, stopped)
                                                     : Verdict{"stopped", stopped, true});
  }
  ctx.summary.set("rise_time_designed_s", design);
  ctx.summary.set("iq_rise_time_s", rq.rise_s());
  ctx.summary.set("id_rise_time_s", rd.rise_s());
  ctx.summary.set("iq_rise_time_ratio", rq.rise_s() / design);
  ctx.summary.set("id_rise_time_ratio", rd.rise_s() / design);
  ctx.summary.set("iq_overshoot_pct", 100.0 * rq.overshoot_frac());
  ctx.summary.set("id_overshoot_pct", 100.0 * rd.overshoot_frac());
  ctx.summary.set("iq_settle_time_s", rq.settle_s());
  ctx.summary.set("id_settle_time_s", rd.settle_s());
  ctx.summary.set("kp_q_v_per_a", dcfg.foc.kp_q_v_per_a);
  ctx.summary.set("ki_q_v_per_as", dcfg.foc.ki_q_v_per_as);
  ctx.summary.set("iq_final_a", iq);
  ctx.summary.set("id_final_a", id);
  hot_summary(ctx.params, run, ctx.summary);
  CurrentStepFigures fig;
  // The references the drive runs: the commands as SET_CURRENT_REF carries
  // them (1 mA resolution).
  fig.iq_step_a = d.iq_ref_a;
  fig.id_step_a = d.id_ref_a;
  fig.iq_rise_ratio = rq.rise_s() / design;
  fig.id_rise_ratio = rd.rise_s() / design;
  fig.iq_final_a = iq;
  fig.id_final_a = id;
  fig.lsb_a = lsb;
  fig.iq_overshoot = rq.overshoot_frac();
  fig.id_overshoot = rd.overshoot_frac();
  fig.t_id_step_s = t_id;
  fig.duration_s = dur;
  fig.bw_t = e.g.cur_bw_rad_s * T;
  write_verdict(ctx.summary, judge_current_step(fig));
}

const Registrar reg_current(on_app_target(
    {"current-step",
     "any motor (--motor FILE [--board FILE]): FOC current loop through the firmware, a q then "
     "a d current step; summary: 10-90% rise times against the design ln 9 / cur_bw",
     0.0,
     {},
     run_current_step,
     current_step_params}));

// --------------------------------------------------- speed step / load step
std::vector<ParamSpec> speed_params(const MotorFiles& f, bool load_step) {
  const mc_gains_t g = files_params_eff(f).g;
  std::vector<ParamSpec> p = {
      {"law", 0.0, "1", "speed law", 0.0, 1.0, {{"pi", 0.0}, {"pi2d", 1.0}}},
      {"speed_rad_s", 0.5 * g.speed_rated_eff_rad_s, "rad/s",
       load_step ? "running speed (mechanical)" : "speed step target (mechanical)",
       -g.speed_limit_rad_s, g.speed_limit_rad_s},
      {"load_frac", load_step ? 0.5 : 0.0, "1",
       load_step ? "load step, fraction of rated torque"
                 : "constant load, fraction of rated torque",
       -1.0, 1.0},
      csv_every_spec()};
  for (auto& s : app_gain_params(f)) p.push_back(s);
  return p;
}

void run_speed(RunContext& ctx, bool load_step) {
  const MotorFiles& f = *ctx.files;
  if (f.board.encoder_cpr == 0) {
    throw UsageError(f.board.file +
                     ": this scenario needs an encoder (encoder_cpr = 0 here); "
                     "use sensorless-speed-step");
  }
  const bool pi2d = ctx.params.get("law") > 0.5;
  // The application's table: SPEED runs the speed_law it names.
  const mc_params_t p =
      params_from_files(f, ctx.params, pi2d ? MC_LAW_SPEED_PI2D : MC_LAW_SPEED_PI);
  const mc_params_eff_t e = resolve_params(p);  // the gains the application derives
  const mc_gains_t& g = e.g;
  const double w_t = ctx.params.get("speed_rad_s");
  const double tau_l = ctx.params.get("load_frac") * g.torque_rated_nm;
  const double wc = pi2d ? 3.0 * g.pi2d_wn_rad_s : g.speed_wc_rad_s;
  // The drive slews the reference at speed_ramp_rad_s2 (the table's).
  const double t_acc = std::abs(w_t) / static_cast<double>(e.p.speed_ramp_rad_s2);
  const double t0 = 0.01;
  // Settling: the PI's zero at wc/4 leaves a tail of a few 4/wc.
  const double t_set = 40.0 / wc;
  // load-step: the speed step first, the load once it has settled.
  const double t_load = load_step ? t0 + t_acc + 0.5 * t_set : 0.0;
  const double dur = duration(ctx, load_step ? t_load + t_set : t0 + t_acc + t_set);
  double t_origin = 0.0;  // the end of the power-up find: the step's time 0
  const std::function<double(double)> load = [tau_l, t_load, &t_origin](double t) {
    return t - t_origin >= t_load ? tau_l : 0.0;
  };
  const std::unique_ptr<AppTarget> target = make_file_target(ctx, f, p, &load);
  AppRunner run(*target);
  run.start(MC_CAN_CTRL_SPEED, true);
  hal_host::PmsmBoard& board = run.board();
  // The power-up find at enable (the index search or the alignment, when the
  // table asks for it): the step's time starts after it.
  ctx.summary.set("angle_find_s", run.finish_angle_find());
  t_origin = board.t_s();
  const double T = board.period_s();
  const long n = step_count(dur, T);
  AppRecorder rec{ctx, run, f.motor.pole_pairs, false, csv_every(ctx, n)};
  rec.used = f.board.encoder == kEncoderHall;
  rec.header();
  const double band = 0.02 * std::abs(w_t);
  double last_out = t0, id_max_ss = 0, iq_max = 0, w = 0, id = 0, iq = 0, werr_max_ss = 0;
  double last_out_load = t_load, dip = 0, w_max = 0, t_half = std::nan("");
  // the steady window's speed: its mean error (the steady error) and its
  // peak to peak (a residual oscillation the 2 % band alone would pass)
  double w_ss_min = std::numeric_limits<double>::infinity(), w_ss_max = -w_ss_min, werr_ss_sum = 0;
  long n_ss = 0;
  bool ref_sent = false;
  const double t_ss = dur - 0.2 * (dur - (load_step ? t_load : t0 + t_acc));
  std::string stopped;
  AppWatch watch;
  for (long k = 0; k <= n; ++k) {
    const double t = board.t_s() - t_origin;
    if (!ref_sent && t >= t0) {
      run.send(run.cmd().speed_ref(w_t));
      ref_sent = true;
    }
    board.true_dq_a(&id, &iq);
    w = board.state()(2);
    w_max = std::max(w_max, w_t >= 0 ? w : -w);
    if (t >= t0 && std::isnan(t_half) && std::abs(w) >= 0.5 * std::abs(w_t)) t_half = t - t0;
    if (t >= t0 && std::abs(w - w_t) > band) last_out = t;
    if (load_step && t >= t_load) {
      dip = std::max(dip, std::abs(w - w_t));
      if (std::abs(w - w_t) > band) last_out_load = t;
    }
    if (t >= t_ss) {
      id_max_ss = std::max(id_max_ss, std::abs(id));
      werr_max_ss = std::max(werr_max_ss, std::abs(w - w_t));
      w_ss_min = std::min(w_ss_min, w);
      w_ss_max = std::max(w_ss_max, w);
      werr_ss_sum += w - w_t;
      ++n_ss;
    }
    iq_max = std::max(iq_max, std::abs(iq));
    rec.row(t, id, iq, w);
    stopped = watch(run.probe());
    if (!stopped.empty()) break;
    if (k < n) run.step();
    if ((k & 1023) == 0) ctx.progress.update(t, dur);
  }
  record_app_setup(f, p, ctx.summary);
  record_spi_encoder(board, ctx.summary);
  const mc_app_probe_t& d = run.probe();
  ctx.summary.set_text("law", pi2d ? "pi2d" : "pi");
  ctx.summary.set("faults", d.faults);
  if (f.board.encoder == kEncoderHall) {
    // the Hall's reasons and the hand-over's fallback (the parameter hall_error)
    ctx.summary.set("hall_error", d.hall_error);
    ctx.summary.set_text("hall_error_names", hall_err_names(d.hall_error));
  }
  if (!stopped.empty()) {
    ctx.summary.set_text("fault_names", stopped);
    return write_verdict(ctx.summary, d.faults != 0u ? faulted(d.faults, stopped)
                                                     : Verdict{"stopped", stopped, true});
  }
  if (load_step) {
    ctx.summary.set("t_load_step_s", t_load);
    ctx.summary.set("load_dip_rad_s", dip);
    ctx.summary.set("recover_2pct_s", last_out_load - t_load);
  } else {
    ctx.summary.set("settle_2pct_s", last_out - t0);
    // the largest speed past the target, of the target (the step's overshoot)
    ctx.summary.set("overshoot_frac",
                    w_t != 0.0 ? std::max(0.0, w_max / std::abs(w_t) - 1.0) : 0.0);
  }
  ctx.summary.set("settled", std::abs(w - w_t) <= band ? 1.0 : 0.0);
  ctx.summary.set("omega_final_rad_s", w);
  ctx.summary.set("accel_time_s", t_acc);
  // when the rotor passed half the target, from the command (the
  // application's ramp: about t_acc / 2)
  ctx.summary.set("half_speed_time_s", t_half);
  // the frames the application sent (its telemetry; none from a C++ loop)
  ctx.summary.set("app_tx_frames", static_cast<double>(run.frames_sent()));
  ctx.summary.set("id_abs_max_steady_a", id_max_ss);
  ctx.summary.set("id_abs_max_steady_frac_rated", id_max_ss / g.i_rated_eff_a);
  ctx.summary.set("omega_err_max_steady_rad_s", werr_max_ss);
  ctx.summary.set("omega_err_mean_steady_rad_s",
                  n_ss ? werr_ss_sum / static_cast<double>(n_ss) : std::nan(""));
  ctx.summary.set("omega_pp_steady_rad_s", n_ss ? w_ss_max - w_ss_min : std::nan(""));
  ctx.summary.set("iq_abs_max_a", iq_max);
  ctx.summary.set("load_nm", tau_l);
  SpeedStepFigures fig;
  fig.load_step = load_step;
  fig.target_rad_s = w_t;
  fig.speed_limit_rad_s = g.speed_limit_rad_s;
  fig.werr_max_steady_rad_s = werr_max_ss;
  fig.id_max_steady_frac_rated = id_max_ss / g.i_rated_eff_a;
  fig.t_steady_from_s = t_ss;
  fig.t_event_s = load_step ? t_load : t0 + t_acc;
  fig.duration_s = dur;
  write_verdict(ctx.summary, judge_speed_step(fig));
}

const Registrar reg_speed(on_app_target(
    {"speed-step",
     "any motor: sensored speed step from standstill through the firmware (law=pi: speed PI "
     "on the drive's encoder speed; law=pi2d: the PI^2D plug-in); summary: 2% settling time, "
     "steady |i_d|",
     0.0,
     {},
     [](RunContext& ctx) { run_speed(ctx, false); },
     [](const MotorFiles& f) { return speed_params(f, false); }}));

const Registrar reg_load(on_app_target(
    {"load-step",
     "any motor: sensored speed step to speed_rad_s, then a load step of load_frac rated torque "
     "(law=pi or pi2d); summary: speed dip and 2% recovery time",
     0.0,
     {},
     [](RunContext& ctx) { run_speed(ctx, true); },
     [](const MotorFiles& f) { return speed_params(f, true); }}));

// -------------------------------------------------- sensorless speed step
std::vector<ParamSpec> sls_params(const MotorFiles& f) {
  const mc_gains_t g = files_params_eff(f).g;
  std::vector<ParamSpec> p = {
      {"speed_rad_s", 0.5 * g.speed_rated_eff_rad_s, "rad/s", "speed target (mechanical)",
       -g.speed_limit_rad_s, g.speed_limit_rad_s},
      {"load_frac", 0.3, "1", "load from standstill on, fraction of rated torque", -1.0, 1.0},
      {"load_step_frac", 0.3, "1", "load step added later, fraction of rated torque", -1.0, 1.0},
      csv_every_spec()};
  for (auto& s : hot_params()) p.push_back(s);
  for (auto& s : app_gain_params(f)) p.push_back(s);
  return p;
}

// The observer's gain the application's sensorless law runs with (its
// init computes it from the configuration mc_law_sls_cfg builds).
double sls_gamma(const mc_params_eff_t& e) {
  mc_ctrl_sls_cfg_t sc{};
  mc_law_sls_cfg(&e.m, &e.g, &sc);
  const auto law = std::make_unique<mc_ctrl_sls_t>();
  return mc_ctrl_sls_init(law.get(), &sc) == 0u ? static_cast<double>(law->gamma) : std::nan("");
}

void run_sensorless(RunContext& ctx) {
  const MotorFiles& f = *ctx.files;
  mc_params_t p = params_from_files(f, ctx.params, MC_LAW_SPEED_SENSORLESS);
  hot_table(ctx.params, &p);
  const mc_params_eff_t e = resolve_params(p);
  const mc_gains_t& g = e.g;
  const double w_t = ctx.params.get("speed_rad_s");
  if (std::abs(w_t) < g.handover_rad_s / (1.0 - 0.3) * 1.2) {
    throw UsageError("speed_rad_s must be well above the hand-over speed " +
                     std::to_string(g.handover_rad_s) +
                     " rad/s: below it the observer cannot see the angle (its low-speed limit)");
  }
  const double tau0 = ctx.params.get("load_frac") * g.torque_rated_nm;
  const double tau1 = tau0 + ctx.params.get("load_step_frac") * g.torque_rated_nm;
  const double wc = g.sls_wc_rad_s;
  const double t_start = g.align_time_s + g.handover_rad_s / g.if_accel_rad_s2 + 0.1;
  const double slew = 0.5 * g.torque_rated_nm / f.motor.j_kgm2;
  const double t_run = std::abs(w_t) / slew + 40.0 / wc;
  const double t_load = t_start + t_run;
  const double dur = duration(ctx, t_load + 40.0 / wc);
  // The load opposes the direction of the run (an active load: it turns a
  // rotor at standstill backwards).
  const double sgn = w_t >= 0 ? 1.0 : -1.0;
  const double tau0s = sgn * tau0, tau1s = sgn * tau1;
  const std::function<double(double)> load = [tau0s, tau1s, t_load](double t) {
    return t >= t_load ? tau1s : tau0s;
  };
  const std::unique_ptr<AppTarget> target =
      make_file_target(ctx, f, p, &load, hot_board(f, p, ctx.params));
  AppRunner run(*target);
  run.start(MC_CAN_CTRL_SPEED);
  run.send(run.cmd().speed_ref(w_t));
  hal_host::PmsmBoard& board = run.board();
  const double T = board.period_s();
  const long n = step_count(dur, T);
  AppRecorder rec{ctx, run, f.motor.pole_pairs, true, csv_every(ctx, n)};
  rec.header();
  const double band = 0.05 * std::abs(w_t);
  double t_lock = std::nan(""), ang_max = 0, ang_sq = 0, werr_end = 0, w = 0, id = 0, iq = 0;
  long ang_n = 0, k = 0;
  // the end window (the last tenth after the load step, as werr_end): the
  // observer's own angle error and the true dq currents' means (MTPA on a
  // salient machine: i_d and the current per torque)
  double ang_end_max = 0, id_end_sum = 0, iq_end_sum = 0;
  long n_end = 0;
  double min_w_align = 0;
  double t_enable = std::nan("");  // the application enabled the drive (the load ran before)
  // The true angle at the previous period's start: the sample the probe's
  // estimate (the fast step run at the end of the previous iteration) was
  // computed from. Compared with the angle after the plant advanced, the
  // error was omega_e T on every motor (issue 31: the observer's own is
  // tens of times smaller).
  double th_sampled = std::nan("");
  std::string stopped;
  AppWatch watch;
  for (k = 0; k <= n; ++k) {
    const double t = board.t_s();
    board.true_dq_a(&id, &iq);
    w = board.state()(2);
    const mc_app_probe_t& pr = run.probe();
    const bool running = pr.cmd_enabled != 0u;
    if (running && std::isnan(t_enable)) t_enable = t;
    if (running && pr.sls_phase == MC_CTRL_SLS_ALIGN) min_w_align = std::min(min_w_align, sgn * w);
    if (running && pr.sls_phase == MC_CTRL_SLS_CLOSED && std::isnan(t_lock)) t_lock = t;
    if (!std::isnan(t_lock) && t > t_lock + 0.05) {
      const double hat = static_cast<double>(pr.sls_theta_hat_e_rad);
      const double err = std::abs(std::remainder(hat - th_sampled, 2 * kPi));
      ang_max = std::max(ang_max, err);
      ang_sq += err * err;
      ++ang_n;
      if (t >= dur - 0.1 * (dur - t_load)) ang_end_max = std::max(ang_end_max, err);
    }
    if (t >= dur - 0.1 * (dur - t_load)) {
      werr_end = std::max(werr_end, std::abs(w - w_t));
      id_end_sum += id;
      iq_end_sum += iq;
      ++n_end;
    }
    rec.row(t, id, iq, w);
    stopped = watch(pr);
    if (!stopped.empty()) break;
    th_sampled = rec.theta_e_true();
    if (k < n) run.step();
    if ((k & 1023) == 0) ctx.progress.update(t, dur);
  }
  record_app_setup(f, p, ctx.summary);
  const mc_app_probe_t& d = run.probe();
  ctx.summary.set("faults", d.faults);
  ctx.summary.set("handovers", d.sls_handovers);
  ctx.summary.set("fallbacks", d.sls_fallbacks);
  ctx.summary.set("t_lock_s", t_lock);
  ctx.summary.set("t_load_step_s", t_load);
  ctx.summary.set("t_enable_s", t_enable);
  ctx.summary.set("align_backwards_rad_s", -min_w_align);
  ctx.summary.set("obs_gamma_per_wb2_s", sls_gamma(e));
  if (!stopped.empty()) {
    const std::string why = (d.faults & MC_DRIVE_FAULT_CONTROL) ? sls_reason(d.ctrl_err) : stopped;
    ctx.summary.set_text("fault_names", why);
    const bool no_lock =
        (d.faults & MC_DRIVE_FAULT_CONTROL) != 0u && (d.ctrl_err & MC_CTRL_SLS_ERR_NO_LOCK) != 0u;
    return write_verdict(ctx.summary, no_lock          ? Verdict{"not locked", why, true}
                                      : d.faults != 0u ? faulted(d.faults, why)
                                                       : Verdict{"stopped", why, true});
  }
  const bool locked = d.sls_phase == MC_CTRL_SLS_CLOSED;
  ctx.summary.set("locked", locked ? 1.0 : 0.0);
  ctx.summary.set("angle_err_max_rad", ang_max);
  ctx.summary.set("angle_err_rms_rad",
                  ang_n ? std::sqrt(ang_sq / static_cast<double>(ang_n)) : std::nan(""));
  ctx.summary.set("omega_final_rad_s", w);
  ctx.summary.set("omega_err_max_end_rad_s", werr_end);
  ctx.summary.set("angle_err_max_end_rad", ang_end_max);
  ctx.summary.set("id_mean_end_a", n_end ? id_end_sum / static_cast<double>(n_end) : std::nan(""));
  ctx.summary.set("iq_mean_end_a", n_end ? iq_end_sum / static_cast<double>(n_end) : std::nan(""));
  ctx.summary.set("tracks", werr_end <= band ? 1.0 : 0.0);
  ctx.summary.set("load0_nm", tau0);
  ctx.summary.set("load1_nm", tau1);
  hot_summary(ctx.params, run, ctx.summary);
  SensorlessFigures fig;
  fig.target_rad_s = w_t;
  fig.locked = locked;
  fig.werr_max_end_rad_s = werr_end;
  fig.angle_err_max_rad = ang_max;
  fig.t_load_step_s = t_load;
  fig.duration_s = dur;
  write_verdict(ctx.summary, judge_sensorless(fig));
}

const Registrar reg_sls(on_app_target(
    {"sensorless-speed-step",
     "any motor: sensorless start from standstill under load (I-f, hand-over to the flux "
     "observer), speed step, then a load step; summary: lock, angle error, tracking",
     0.0,
     {},
     run_sensorless,
     sls_params}));

}  // namespace
}  // namespace mcsim
