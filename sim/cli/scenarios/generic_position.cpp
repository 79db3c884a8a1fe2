// position-move for any motor (`--motor FILE [--board FILE]`): the drive
// application's POSITION mode (its position law, firmware/app/ctrl/
// mc_ctrl_position, built from the parameter table: app_params.hpp, pos_*
// keys onto the traj_* parameters), commanded by SET_POSITION_REF frames. A
// trapezoidal move of `turns` turns from standstill; optionally a re-plan to
// `replan_turns` at `replan_frac` of the predicted move time; or (stream=1)
// the same move streamed as SET_POSITION_REF setpoints at stream_hz, a
// (1 - cos) ramp over the trapezoid's time, through the law's input filter
// (parameter pos_input_mode = 1). Every metric is computed on
// the fly (constant memory).
//
// Summary:
//   move_time_pred_s      the trapezoid's duration (the last plan's end, from
//                         the start of the move)
//   count_band            1 count plus the target's offset from the count grid
//                         (SET_POSITION_REF carries 1e-4 rad)
//   reach_time_s          first entry into |count error| <= count_band
//   move_time_s           last entry into |count error| <= count_band (encoder
//                         count against the target, multi-turn), from the start
//   move_time_ratio       move_time_s / move_time_pred_s
//   final_err_counts      |target - measured| at the end [counts]
//   final_err_true_counts |target - true angle| at the end [counts]
//   overshoot_rad/_counts largest excursion of the true angle beyond the
//                         target in the move's direction
//   track_err_max_rad     largest |theta_ref - theta_m (true)| during the move
//   dv_ref_max_rad_s      largest change of the velocity reference in one
//                         period; dv_ref_bound_rad_s = max(a, d) T
#include <algorithm>
#include <cmath>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>

#include "app_scenario.hpp"
#include "drive_setup.hpp"
#include "scenario.hpp"
#include "verdict.hpp"

namespace mcsim {
namespace {

constexpr double kTwoPi = 6.283185307179586476925;
constexpr double kPi = 3.141592653589793238463;

std::vector<ParamSpec> position_params(const MotorFiles& f) {
  std::vector<ParamSpec> p = {
      {"turns", 10.0, "1", "move length in turns (sign: direction)", -1000.0, 1000.0},
      {"v_max", 0.0, "rad/s", "trajectory cruise speed (0: pos_v_max_rad_s)", 0.0, 1.0e5},
      {"a_max", 0.0, "rad/s^2", "trajectory acceleration (0: pos_a_max_rad_s2)", 0.0, 1.0e9},
      {"d_max", 0.0, "rad/s^2", "trajectory deceleration (0: pos_d_max_rad_s2)", 0.0, 1.0e9},
      {"replan_frac", 0.0, "1",
       "re-plan to replan_turns at this fraction of the predicted move time (0: off)", 0.0, 1.0},
      {"replan_turns", 5.0, "1", "target of the re-plan [turns from the start]", -1000.0, 1000.0},
      {"stream", 0.0, "1", "1: stream the move as setpoints through the input filter", 0.0, 1.0},
      {"stream_hz", 200.0, "Hz", "setpoint rate of the streamed move", 1.0, 1.0e5},
      {"load_frac", 0.0, "1", "constant load, fraction of rated torque", -1.0, 1.0},
      {"csv_every", 0.0, "1", "write every n-th PWM period (0: all up to 20000 rows)", 0.0, 1.0e9}};
  for (auto& s : gain_params(f)) p.push_back(s);
  return p;
}

// The angle the application receives for theta (SET_POSITION_REF's
// resolution): the frame packed and decoded by the firmware's codec.
double as_sent(const mc_hal_can_frame_t& f) {
  uint32_t msg = 0;
  float v[MC_CAN_NSIG_MAX] = {0};
  (void)mc_can_proto_unpack(&f, &msg, v, MC_CAN_NSIG_MAX);
  return static_cast<double>(v[MC_CAN_SET_POSITION_REF_THETA_REF_RAD]);
}

struct PosRun {
  double target_rad = 0, start_rad = 0, sgn = 1;
  bool started = false, replanned = false, replan_seen = false;
  double t_pred = 0, t_last_out = 0, overshoot = 0, track_max = 0, dv_max = 0;
  double prev_v = 0;
  bool have_prev_v = false;
  double t_reach = std::nan("");
  double err_counts = 0, err_true = 0;
  // 1 count, plus how far SET_POSITION_REF's 1e-4 rad resolution puts the
  // target off the encoder's count grid (the loop rests on a count: with
  // the target between two, its +-1 count dither reaches 1 + that).
  double band_counts = 1.0;
  void set_target(double rad, double rad_per_count) {
    target_rad = rad;
    const double c = rad / rad_per_count;
    band_counts = std::max(band_counts, 1.0 + std::abs(c - std::round(c)));
  }
};

void run_position(RunContext& ctx) {
  const MotorFiles& f = *ctx.files;
  if (f.board.encoder_cpr == 0) {
    throw UsageError(f.board.file + ": position-move needs an encoder (encoder_cpr = 0 here)");
  }
  const bool stream = ctx.params.get("stream") > 0.5;
  mc_params_t p0 = params_from_files(f, ctx.params);
  p0.pos_input_mode = stream ? 1u : 0u;
  // the move's limits: the trajectory parameters
  if (ctx.params.get("v_max") > 0)
    p0.traj_v_max_rad_s = static_cast<float>(ctx.params.get("v_max"));
  if (ctx.params.get("a_max") > 0)
    p0.traj_a_max_rad_s2 = static_cast<float>(ctx.params.get("a_max"));
  if (ctx.params.get("d_max") > 0)
    p0.traj_d_max_rad_s2 = static_cast<float>(ctx.params.get("d_max"));
  const mc_params_t p = p0;
  const mc_params_eff_t e = resolve_params(p);
  const mc_gains_t& g = e.g;
  const double turns = ctx.params.get("turns");
  const double replan_frac = ctx.params.get("replan_frac");
  const double tau_l = ctx.params.get("load_frac") * g.torque_rated_nm;
  const std::function<double(double)> load = [tau_l](double) { return tau_l; };
  const std::unique_ptr<AppTarget> target =
      make_file_target(ctx, f, p, tau_l != 0.0 ? &load : nullptr);
  AppRunner run(*target);
  run.start(MC_CAN_CTRL_POSITION);
  hal_host::PmsmBoard& board = run.board();
  const double T = board.period_s();
  const double cpr = static_cast<double>(f.board.encoder_cpr);
  const double rad_per_count = kTwoPi / cpr;

  // Settle the loop at standstill first, then move from where the rotor is.
  const double t0 = 0.01;
  const double a = g.pos_a_max_rad_s2, d = g.pos_d_max_rad_s2, v = g.pos_v_max_rad_s;
  const double D = std::abs(turns) * kTwoPi;
  // Trapezoid or triangle from rest (mc_traj.h) for the run's length.
  const double vp = std::min(v, std::sqrt(2 * a * d * D / (a + d)));
  const double t_pred0 = (vp < v) ? vp / a + vp / d : D / v + v / (2 * a) + v / (2 * d);
  double t_move_total = t_pred0;
  if (replan_frac > 0)
    t_move_total +=
        std::abs(ctx.params.get("replan_turns") - turns) * kTwoPi / v + 2 * v / std::min(a, d);
  const double t_stream = t_pred0;  // the streamed ramp takes the trapezoid's time
  const long stream_div =
      std::max(1L, std::lround(1.0 / (ctx.params.get("stream_hz") * board.period_s())));
  const double settle = 20.0 / g.pos_kp_per_s;
  const double dur = run_duration(ctx, t0 + t_move_total + settle);
  const long n = step_count(dur, T);
  const long every = std::lround(ctx.params.get("csv_every")) > 0
                         ? std::lround(ctx.params.get("csv_every"))
                         : std::max(1L, n / 20000);
  ctx.csv.columns({"t", "i_d_a", "i_q_a", "i_d_ref_a", "i_q_ref_a", "omega_m_rad_s",
                   "omega_ref_rad_s", "theta_e_rad", "v_d_v", "v_q_v", "fault_1", "theta_m_rad",
                   "theta_ref_rad"});
  AppRecorder rec{ctx, run, f.motor.pole_pairs, false, 1};
  PosRun r;
  r.sgn = turns >= 0 ? 1.0 : -1.0;
  double t_cmd = t0;  // when the application took the last target
  double id = 0, iq = 0;
  std::string stopped;
  AppWatch watch;
  for (long k = 0; k <= n; ++k) {
    const double t = board.t_s();
    const mc_app_probe_t& pr = run.probe();
    if (!r.started && t >= t0) {
      // The rotor's measured multi-turn position (the law's turns + count).
      r.start_rad = pr.pos_turns * kTwoPi + pr.pos_count * rad_per_count;
      const mc_hal_can_frame_t fr = run.cmd().position_ref(r.start_rad + turns * kTwoPi);
      r.set_target(as_sent(fr), rad_per_count);
      if (!stream) run.send(fr);
      r.started = true;
    }
    if (r.started && stream && (k % stream_div) == 0) {
      const double ts = std::min(t - t0, t_stream);
      const double x = 0.5 * (1.0 - std::cos(kPi * ts / t_stream)) * turns * kTwoPi;
      run.send(run.cmd().position_ref(r.start_rad + x));
    }
    if (r.started && !stream && !r.replanned && replan_frac > 0 &&
        t >= t0 + replan_frac * t_pred0) {
      const double rt = ctx.params.get("replan_turns");
      const mc_hal_can_frame_t fr = run.cmd().position_ref(r.start_rad + rt * kTwoPi);
      r.set_target(as_sent(fr), rad_per_count);
      r.sgn = r.target_rad >= pr.pos_theta_ref_rad ? 1.0 : -1.0;
      run.send(fr);
      r.replanned = true;
    }
    // The plant at t (sampled by this period's fast step), then the step:
    // the law's reference and measurement below are those of the sample at t.
    board.true_dq_a(&id, &iq);
    const double th_true = board.state()(3);
    const double w_true = board.state()(2);
    const double th_e_true = rec.theta_e_true();
    const Eigen::Vector2d& vab = board.v_alpha_beta_applied();
    const double vd = std::cos(th_e_true) * vab(0) + std::sin(th_e_true) * vab(1);
    const double vq = -std::sin(th_e_true) * vab(0) + std::cos(th_e_true) * vab(1);
    if (k == n) break;
    run.step();
    const mc_app_probe_t& q = run.probe();
    if (r.started && !stream && r.t_pred == 0 && q.pos_traj_k > 0) {
      // the move took effect (the application's slow step): its end, from t0
      t_cmd = t;
      r.t_pred = (t - t0) + static_cast<double>(q.pos_traj_duration_s);
    }
    if (r.replanned && r.t_pred > 0 && q.pos_traj_k == 1 && !r.replan_seen) {
      // the re-plan took effect this step: its end, from the move's start
      r.t_pred = (t - t0) + static_cast<double>(q.pos_traj_duration_s);
      r.replan_seen = true;
    }
    // the law's multi-turn measurement (exact: turns and count)
    const double th_meas = q.pos_turns * kTwoPi + q.pos_count * rad_per_count;
    const double th_ref = q.pos_theta_ref_rad;
    if (r.started) {
      r.err_counts = std::abs(r.target_rad - th_meas) / rad_per_count;
      r.err_true = std::abs(r.target_rad - th_true) / rad_per_count;
      if (r.err_counts > r.band_counts + 1e-6) r.t_last_out = t;
      if (r.err_counts <= r.band_counts + 1e-6 && std::isnan(r.t_reach)) r.t_reach = t;
      r.overshoot = std::max(r.overshoot, r.sgn * (th_true - r.target_rad));
      if (k > 0 && t > t_cmd) r.track_max = std::max(r.track_max, std::abs(th_ref - th_true));
      const double vr = q.omega_ref_rad_s;
      if (r.have_prev_v) r.dv_max = std::max(r.dv_max, std::abs(vr - r.prev_v));
      r.prev_v = vr;
      r.have_prev_v = true;
    }
    if (k % every == 0) {
      const double row[] = {t,
                            id,
                            iq,
                            q.id_ref_a,
                            q.iq_ref_a,
                            w_true,
                            q.omega_ref_rad_s,
                            th_e_true,
                            vd,
                            vq,
                            static_cast<double>(q.faults),
                            th_true,
                            r.started ? th_ref : th_true};
      ctx.csv.row(row, 13);
    }
    stopped = watch(q);
    if (!stopped.empty()) break;
    if ((k & 1023) == 0) ctx.progress.update(t, dur);
  }
  record_app_setup(f, p, ctx.summary);
  const mc_app_probe_t& dr = run.probe();
  ctx.summary.set("faults", dr.faults);
  if (!stopped.empty()) {
    ctx.summary.set_text("fault_names", stopped);
    return write_verdict(ctx.summary, dr.faults != 0u ? faulted(dr.faults, stopped)
                                                      : Verdict{"stopped", stopped, true});
  }
  if (stream) r.t_pred = t_stream;
  ctx.summary.set_text("mode", stream ? "stream" : (r.replanned ? "replan" : "trapezoid"));
  ctx.summary.set("pos_input_mode", run.target().params().pos_input_mode);
  ctx.summary.set("turns", turns);
  ctx.summary.set("target_rad", r.target_rad);
  ctx.summary.set("encoder_cpr", cpr);
  ctx.summary.set("move_time_pred_s", r.t_pred);
  ctx.summary.set("reach_time_s", r.t_reach - t0);
  ctx.summary.set("reach_time_ratio", (r.t_reach - t0) / r.t_pred);
  ctx.summary.set("move_time_s", r.t_last_out - t0);
  ctx.summary.set("move_time_ratio", (r.t_last_out - t0) / r.t_pred);
  ctx.summary.set("count_band", r.band_counts);
  ctx.summary.set("final_err_counts", r.err_counts);
  ctx.summary.set("final_err_true_counts", r.err_true);
  ctx.summary.set("overshoot_rad", std::max(0.0, r.overshoot));
  ctx.summary.set("overshoot_counts", std::max(0.0, r.overshoot) / rad_per_count);
  ctx.summary.set("track_err_max_rad", r.track_max);
  ctx.summary.set("dv_ref_max_rad_s", r.dv_max);
  ctx.summary.set("dv_ref_bound_rad_s", std::max(a, d) * T);
  ctx.summary.set("v_max_rad_s", v);
  ctx.summary.set("a_max_rad_s2", a);
  ctx.summary.set("d_max_rad_s2", d);
  PositionFigures fig;
  fig.stream = stream;
  // judged against 1 count: the target's offset from the grid taken off
  fig.final_err_counts = std::max(0.0, r.err_counts - (r.band_counts - 1.0));
  fig.overshoot_rad = std::max(0.0, r.overshoot);
  fig.move_time_s = r.t_last_out - t0;
  fig.move_time_pred_s = r.t_pred;
  fig.dv_ref_max_rad_s = r.dv_max;
  fig.a_max_rad_s2 = a;
  fig.d_max_rad_s2 = d;
  fig.pos_kp_per_s = g.pos_kp_per_s;
  fig.enc_bw_rad_s = g.enc_pll_bw_rad_s;
  fig.period_s = T;
  fig.duration_s = dur;
  fig.track_err_max_rad = r.track_max;
  write_verdict(ctx.summary, judge_position(fig));
}

const Registrar reg_position(on_app_target(
    {"position-move",
     "any motor with an encoder: a trapezoidal move of `turns` turns through the position "
     "cascade (trajectory -> P -> velocity PI -> FOC); re-plan mid-move (replan_frac) or "
     "streamed setpoints through the input filter (stream=1); summary: final error in counts, "
     "overshoot, move time against the trapezoid's",
     0.0,
     {},
     run_position,
     position_params}));

}  // namespace
}  // namespace mcsim
