// position-move for any motor (`--motor FILE [--board FILE]`): the position
// cascade plug-in (firmware/app/mc_ctrl_position.c) on the unmodified drive,
// gains from drive_setup (pos_* keys). A trapezoidal move of `turns` turns
// from standstill; optionally a re-plan to `replan_turns` at `replan_frac` of
// the predicted move time, or (stream=1) the same move streamed as setpoints
// at stream_hz through the input filter. Every metric is computed on the fly
// (constant memory).
//
// Summary:
//   move_time_pred_s      the trapezoid's duration (the last plan's end, from
//                         the start of the move)
//   reach_time_s          first entry into |count error| <= 1 count
//   move_time_s           last entry into |count error| <= 1 count (encoder
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
#include <stdexcept>

#include "drive_setup.hpp"
#include "scenario.hpp"
#include "verdict.hpp"

namespace mcsim {
namespace {

constexpr double kTwoPi = 6.283185307179586476925;

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

void run_position(RunContext& ctx) {
  const MotorFiles& f = *ctx.files;
  Gains g = derive_gains(f, &ctx.params);
  if (ctx.params.get("v_max") > 0) g.pos_v_max_rad_s = ctx.params.get("v_max");
  if (ctx.params.get("a_max") > 0) g.pos_a_max_rad_s2 = ctx.params.get("a_max");
  if (ctx.params.get("d_max") > 0) g.pos_d_max_rad_s2 = ctx.params.get("d_max");
  const double turns = ctx.params.get("turns");
  const double replan_frac = ctx.params.get("replan_frac");
  const bool stream = ctx.params.get("stream") > 0.5;
  const double tau_l = ctx.params.get("load_frac") * g.torque_rated_nm;
  RigOptions o;
  o.law = Law::kPosition;
  if (tau_l != 0.0) o.load_nm = [tau_l](double) { return tau_l; };
  MotorRig rig(f, g, o);
  mc_ctrl_pos_t& pc = rig.pos();
  const double T = rig.period_s();
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
  // Streamed: a smooth (1 - cos) profile of the trapezoid's length.
  const double t_stream = t_pred0;
  const double settle = 20.0 / g.pos_kp_per_s;
  const double dur = run_duration(ctx, t0 + t_move_total + settle);
  const long n = step_count(dur, T);
  const long every = std::lround(ctx.params.get("csv_every")) > 0
                         ? std::lround(ctx.params.get("csv_every"))
                         : std::max(1L, n / 20000);
  ctx.csv.columns({"t", "i_d_a", "i_q_a", "i_d_ref_a", "i_q_ref_a", "omega_m_rad_s",
                   "omega_ref_rad_s", "theta_e_rad", "v_d_v", "v_q_v", "fault_1", "theta_m_rad",
                   "theta_ref_rad"});

  double target_rad = 0, start_rad = 0, sgn = turns >= 0 ? 1.0 : -1.0;
  bool started = false, replanned = false, replan_seen = false;
  double t_pred = 0, t_last_out = 0, overshoot = 0, track_max = 0, dv_max = 0;
  double prev_v = 0;
  bool have_prev_v = false;
  long stream_div = std::max(1L, std::lround(1.0 / (ctx.params.get("stream_hz") * T)));
  double t_reach = std::nan("");
  double err_counts = 0, err_true = 0, id = 0, iq = 0;
  int32_t start_turns = 0;
  float start_frac = 0;
  for (long k = 0; k <= n; ++k) {
    const double t = rig.board().t_s();
    if (!started && t >= t0) {
      // The rotor's measured multi-turn position: turn + count.
      start_turns = pc.tm.turns;
      start_frac = static_cast<float>(pc.tm.count * rad_per_count);
      start_rad = pc.tm.turns * kTwoPi + pc.tm.count * rad_per_count;
      target_rad = start_rad + turns * kTwoPi;
      if (stream) {
        if (mc_ctrl_pos_set_input_mode(&pc, MC_TRAJ_MODE_FILTER) != 0u) {
          throw UsageError("input filter refused");
        }
      } else {
        if (mc_ctrl_pos_set_target(
                &pc, start_turns + static_cast<int32_t>(std::lround(turns)),
                start_frac + static_cast<float>((turns - std::round(turns)) * kTwoPi)) != 0u) {
          throw UsageError("target refused");
        }
      }
      started = true;
    }
    if (started && stream && (k % stream_div) == 0) {
      const double ts = std::min(t - t0, t_stream);
      const double x = 0.5 * (1 - std::cos(M_PI * ts / t_stream)) * turns * kTwoPi;
      const double xw = std::floor(x / kTwoPi);
      if (mc_ctrl_pos_set_target(&pc, start_turns + static_cast<int32_t>(xw),
                                 start_frac + static_cast<float>(x - xw * kTwoPi)) != 0u) {
        throw UsageError("setpoint refused");
      }
    }
    if (started && !stream && !replanned && replan_frac > 0 && t >= t0 + replan_frac * t_pred0) {
      const double rt = ctx.params.get("replan_turns");
      target_rad = start_rad + rt * kTwoPi;
      sgn = (rt * kTwoPi + start_rad) >= pc.tm.theta_ref_rad ? 1.0 : -1.0;
      if (mc_ctrl_pos_set_target(&pc, start_turns + static_cast<int32_t>(std::lround(rt)),
                                 start_frac + static_cast<float>((rt - std::round(rt)) * kTwoPi)) !=
          0u) {
        throw UsageError("re-plan target refused");
      }
      replanned = true;
    }
    // The plant at t (sampled by this period's fast step), then the step:
    // the law's reference and measurement below are those of the sample at t.
    rig.board().true_dq_a(&id, &iq);
    const double th_true = rig.board().state()(3);
    const double w_true = rig.board().state()(2);
    const double th_e_true = rig.theta_e_true();
    double vd, vq;
    rig.dq_volts(&vd, &vq);
    if (k == n) break;
    rig.step();
    if (started && t_pred == 0 && !stream) t_pred = mc_traj_f32_get_duration_s(&pc.traj);
    if (replanned && t_pred > 0 && pc.traj.k == 1 && !replan_seen) {
      // the re-plan took effect this step: its end, from the move's start
      t_pred = (t - t0) + mc_traj_f32_get_duration_s(&pc.traj);
      replan_seen = true;
    }
    // the plug-in's multi-turn measurement (exact: turns and count)
    const double th_meas = pc.tm.turns * kTwoPi + pc.tm.count * rad_per_count;
    const double th_ref = pc.tm.theta_ref_rad;
    if (started) {
      err_counts = std::abs(target_rad - th_meas) / rad_per_count;
      err_true = std::abs(target_rad - th_true) / rad_per_count;
      if (err_counts > 1.0 + 1e-6) t_last_out = t;
      if (err_counts <= 1.0 + 1e-6 && std::isnan(t_reach)) t_reach = t;
      overshoot = std::max(overshoot, sgn * (th_true - target_rad));
      if (k > 0) track_max = std::max(track_max, std::abs(th_ref - th_true));
      const double vr = pc.tm.omega_ref_rad_s;
      if (have_prev_v) dv_max = std::max(dv_max, std::abs(vr - prev_v));
      prev_v = vr;
      have_prev_v = true;
    }
    if (k % every == 0) {
      double idr, iqr;
      rig.dq_refs(&idr, &iqr);
      const double row[] = {t,
                            id,
                            iq,
                            idr,
                            iqr,
                            w_true,
                            rig.omega_ref_rad_s(),
                            th_e_true,
                            vd,
                            vq,
                            static_cast<double>(rig.drive().faults),
                            th_true,
                            started ? th_ref : th_true};
      ctx.csv.row(row, 13);
    }
    if (rig.drive().faults != 0u) break;
    if ((k & 1023) == 0) ctx.progress.update(t, dur);
  }
  record_setup(f, g, ctx.summary);
  mc_drive_t& dr = rig.drive();
  ctx.summary.set("faults", dr.faults);
  if (dr.faults != 0u) {
    const std::string names = drive_fault_names(dr.faults);
    ctx.summary.set_text("fault_names", names);
    return write_verdict(ctx.summary, faulted(dr.faults, names + " (law error bits " +
                                                             std::to_string(dr.tm.ctrl_err) + ")"));
  }
  if (stream) t_pred = t_stream;
  ctx.summary.set_text("mode", stream ? "stream" : (replanned ? "replan" : "trapezoid"));
  ctx.summary.set("turns", turns);
  ctx.summary.set("target_rad", target_rad);
  ctx.summary.set("encoder_cpr", cpr);
  ctx.summary.set("move_time_pred_s", t_pred);
  ctx.summary.set("reach_time_s", t_reach - t0);
  ctx.summary.set("reach_time_ratio", (t_reach - t0) / t_pred);
  ctx.summary.set("move_time_s", t_last_out - t0);
  ctx.summary.set("move_time_ratio", (t_last_out - t0) / t_pred);
  ctx.summary.set("final_err_counts", err_counts);
  ctx.summary.set("final_err_true_counts", err_true);
  ctx.summary.set("overshoot_rad", std::max(0.0, overshoot));
  ctx.summary.set("overshoot_counts", std::max(0.0, overshoot) / rad_per_count);
  ctx.summary.set("track_err_max_rad", track_max);
  ctx.summary.set("dv_ref_max_rad_s", dv_max);
  ctx.summary.set("dv_ref_bound_rad_s", std::max(a, d) * T);
  ctx.summary.set("v_max_rad_s", v);
  ctx.summary.set("a_max_rad_s2", a);
  ctx.summary.set("d_max_rad_s2", d);
  PositionFigures fig;
  fig.stream = stream;
  fig.final_err_counts = err_counts;
  fig.overshoot_rad = std::max(0.0, overshoot);
  fig.move_time_s = t_last_out - t0;
  fig.move_time_pred_s = t_pred;
  fig.dv_ref_max_rad_s = dv_max;
  fig.a_max_rad_s2 = a;
  fig.d_max_rad_s2 = d;
  fig.pos_kp_per_s = g.pos_kp_per_s;
  fig.enc_bw_rad_s = g.enc_pll_bw_rad_s;
  fig.period_s = T;
  fig.duration_s = dur;
  fig.track_err_max_rad = track_max;
  write_verdict(ctx.summary, judge_position(fig));
}

const Registrar reg_position(
    {"position-move",
     "any motor with an encoder: a trapezoidal move of `turns` turns through the position "
     "cascade (trajectory -> P -> velocity PI -> FOC); re-plan mid-move (replan_frac) or "
     "streamed setpoints through the input filter (stream=1); summary: final error in counts, "
     "overshoot, move time against the trapezoid's",
     0.0,
     {},
     run_position,
     position_params});

}  // namespace
}  // namespace mcsim
