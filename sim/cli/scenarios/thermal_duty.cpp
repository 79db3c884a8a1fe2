// thermal-duty (issue 33 item 5): any motor, an overload cycle that would
// overheat the winding, with the drive's thermal derating on (derate=1) or
// off (derate=0). The plant's two-node thermal model (mcsim/thermal.hpp,
// R(T) and the magnet's flux(T)) from the motor's rating; the drive's own
// winding estimate (firmware/app/drive/mc_drive_thermal.h, written
// independently) from the same rating and the drive's R (the table's
// r_ohm: model_r_scale makes it off, e.g. 1.1 for "10 % off at the start
// temperature", the commissioning error the estimate must live with).
//
// The cycle: CURRENT mode, a current of overload * i_rated_a on the d axis
// for on_s, then 0 for off_s, repeated for the run. On the d axis the
// current makes no torque (for an interior magnet machine, none with
// iq = 0), so the rotor stays at rest without a brake and the winding sees
// the same copper loss 3/2 R(T) |i_dq|^2 as a torque current of that size.
// The default duty, 1.75 x rated for 60 s in 90 s, has a mean |i|^2 of
// about 2 i_rated^2: its steady rise is twice the rated rise, past the
// limit (t_winding_limit_c = derate_end_c, the drive's derate_motor_end_c,
// where its current limit reaches 0). Where the drive's current limit is
// below 1.75 x rated, 95 % of it for a longer on-phase (default_duty).
//
// Time: 10 simulated minutes with the catalogue's time constants (tau_w
// 30 s, tau_h 900 s) by default. Everything thermal scales with one time
// (tau_w, tau_h, on_s, off_s, the duration): a test may run the same
// physics faster by dividing them all by one factor while the electrical
// dynamics (milliseconds) stay far faster than the thermal ones.
//
// CSV: t, t_winding_c (the plant's winding), t_winding_est_c (the drive's
// estimate, the probe's), t_housing_c (the plant's), i_limit_a (the current
// limit in force), i_d_a (the plant's), i_d_ref_a.
// Summary: t_winding_limit_c, t_winding_max_c, t_est_err_max_k (the largest
// |estimate - plant|), i_limit_min_a, derate. Verdict: the estimate within
// 5 K throughout; with derate=1 the winding at most 2 K above its limit;
// with derate=0 the winding above its limit (the duty overheats it: the
// comparison the derating is judged by).
#include <algorithm>
#include <cmath>
#include <memory>
#include <string>

#include "app_params.hpp"
#include "app_scenario.hpp"
#include "scenario.hpp"
#include "verdict.hpp"

extern "C" {
#include "mc_params.h"
}

namespace mcsim {
namespace {

constexpr double kEstTolK = 5.0;    // issue 33: estimate within 5 K of the plant
constexpr double kLimitTolK = 2.0;  // issue 33: at most 2 K above the limit with derating

// The default duty: 1.75 x rated for 60 s in 90 s, where the drive's
// current limit allows it. A motor whose limit is closer to its rating
// (paper002-40kw: 400 A on a 274 A rating) gets 95 % of its limit for an
// on-phase long enough to keep the duty's mean |i|^2 (on_s / 90 s of
// overload^2, up to all of the 90 s) and a longer run, so the duty still
// overheats it.
constexpr double kOverload = 1.75, kOnS = 60.0, kPeriodS = 90.0, kDurationS = 600.0;

struct Duty {
  double overload, on_s, duration_s;
};

Duty default_duty(const MotorFiles& f) {
  const double i_lim = files_params_eff(f).g.i_limit_a;
  if (kOverload * f.motor.i_rated_a <= i_lim) return {kOverload, kOnS, kDurationS};
  const double k = 0.95 * i_lim / f.motor.i_rated_a;
  // the smaller current's quicker winding rise is made up by the housing's:
  // the run lasts longer in the same ratio (up to an hour)
  const double r = (kOverload / k) * (kOverload / k);
  return {k, std::min(kPeriodS, kOnS * r), std::min(3600.0, kDurationS * r)};
}

std::vector<ParamSpec> thermal_params(const MotorFiles& f) {
  const Duty d = default_duty(f);
  std::vector<ParamSpec> p = {
      {"derate",
       1.0,
       "1",
       "the drive's derating by the winding estimate (0: off, the estimate runs)",
       0.0,
       1.0,
       {{"off", 0.0}, {"on", 1.0}}},
      {"overload", d.overload, "1",
       "current of the on-phase in units of the motor's i_rated_a (default 1.75, or 95 % of "
       "the drive's current limit where 1.75 x rated is above it)",
       0.1, 3.0},
      {"on_s", d.on_s, "s",
       "on-phase of the cycle (default 60 s, longer with a smaller overload: the same mean "
       "|i|^2)",
       1e-3, 3600.0},
      {"off_s", kPeriodS - d.on_s, "s", "off-phase of the cycle (zero current, the bridge on)", 0.0,
       3600.0},
      {"duration_s", d.duration_s, "s",
       "the run (at least 10 min of the cycle at catalogue time constants; longer with a "
       "smaller overload)",
       1e-2, 3600.0},
      {"tau_w_s", 30.0, "s", "winding time constant, plant and drive (C_w R_wh)", 1e-2, 1e4},
      {"tau_h_s", 900.0, "s", "housing time constant, plant and drive (C_h R_ha)", 1e-2, 1e5},
      {"rise_k", 80.0, "K", "steady winding rise at i_rated_a (the rating both models come from)",
       1.0, 200.0},
      {"share", 0.3, "1", "R_wh / (R_wh + R_ha)", 0.01, 0.99},
      {"ambient_c", 25.0, "degC", "ambient and start temperature", -20.0, 60.0},
      {"derate_start_c", 110.0, "degC", "the drive's derate_motor_start_c", 1.0, 250.0},
      {"derate_end_c", 130.0, "degC",
       "the drive's derate_motor_end_c: the winding's limit (130 C: insulation class B)", 2.0,
       250.0},
      {"csv_every", 0.0, "1", "write every n-th PWM period (0: about 20000 rows)", 0.0, 1.0e9}};
  for (auto& s : app_gain_params(f)) p.push_back(s);
  return p;
}

// The drive's table: the files' with the winding model and its derating.
mc_params_t thermal_table(const MotorFiles& f, const Params& P) {
  mc_params_t p = params_from_files(f, P);
  p.winding_model = 1u;
  p.winding_rise_k = static_cast<float>(P.get("rise_k"));
  p.winding_tau_s = static_cast<float>(P.get("tau_w_s"));
  p.housing_tau_s = static_cast<float>(P.get("tau_h_s"));
  p.winding_share = static_cast<float>(P.get("share"));
  p.ambient_c = static_cast<float>(P.get("ambient_c"));
  if (P.get("derate") > 0.5) {
    p.derate_motor_start_c = static_cast<float>(P.get("derate_start_c"));
    p.derate_motor_end_c = static_cast<float>(P.get("derate_end_c"));
  }
  if (mc_params_validate(&p) != MC_PARAMS_OK) {
    throw UsageError(
        "thermal-duty: the drive refuses the thermal parameters (derate_end_c must "
        "be above derate_start_c, each inside the table's range)");
  }
  return p;
}

// The plant's thermal network from the same rating, with the motor's own R.
ThermalParams plant_thermal(const MotorFiles& f, const Params& P) {
  ThermalRating r;
  r.r_ohm = f.motor.r_ohm;
  r.i_rated_a = f.motor.i_rated_a;
  r.rise_k = P.get("rise_k");
  r.ambient_c = r.t_ref_c = P.get("ambient_c");
  r.winding_share = P.get("share");
  r.tau_winding_s = P.get("tau_w_s");
  r.tau_housing_s = P.get("tau_h_s");
  ThermalParams t;
  if (thermal_from_rating(r, &t) != Status::kOk) {
    throw UsageError("thermal-duty: the plant refuses the thermal rating");
  }
  return t;
}

void run_thermal(RunContext& ctx) {
  const MotorFiles& f = *ctx.files;
  const Params& P = ctx.params;
  const mc_params_t p = thermal_table(f, P);
  const ThermalParams tp = plant_thermal(f, P);
  const double i_on = P.get("overload") * f.motor.i_rated_a;
  const double i_lim = resolve_params(p).g.i_limit_a;
  if (i_on > i_lim) {
    throw UsageError("thermal-duty: overload x i_rated_a = " + std::to_string(i_on) +
                     " A is above the drive's current limit " + std::to_string(i_lim) + " A");
  }
  const auto adjust = [&](AppSetup& s) {
    s.board.thermal_enabled = true;
    s.board.thermal = tp;
  };
  const std::unique_ptr<AppTarget> target = make_file_target(ctx, f, p, nullptr, adjust);
  AppRunner run(*target);
  run.start(MC_CAN_CTRL_CURRENT, true);
  (void)run.finish_angle_find();
  hal_host::PmsmBoard& board = run.board();
  const ThermalModel* th = board.power_stage().thermal();
  const double on_s = P.get("on_s"), period_s = on_s + P.get("off_s");
  const double dur = run_duration(ctx, P.get("duration_s"));
  const double T = board.period_s(), t0 = board.t_s();
  const long n = step_count(dur, T);
  const long every =
      P.get("csv_every") > 0 ? std::lround(P.get("csv_every")) : std::max(1L, n / 20000);
  ctx.csv.columns(
      {"t", "t_winding_c", "t_winding_est_c", "t_housing_c", "i_limit_a", "i_d_a", "i_d_ref_a"});
  const double limit_c = P.get("derate_end_c");
  double cmd = -1.0, tw_max = -1e9, err_max = 0.0, ilim_min = 1e9, id = 0, iq = 0;
  double t_err_max = 0.0;
  std::string stopped;
  AppWatch watch;
  // the estimate is compared once the drive has stepped its model (the
  // first slow step after the enable)
  bool est_live = false;
  for (long k = 0; k <= n; ++k) {
    const double t = board.t_s() - t0;
    const double want = std::fmod(t, period_s) < on_s ? i_on : 0.0;
    if (want != cmd) {
      run.send(run.cmd().current_ref(want, 0.0));
      cmd = want;
    }
    const mc_app_probe_t& pr = run.probe();
    board.true_dq_a(&id, &iq);
    const double tw = th->winding_c();
    est_live = est_live || pr.i_limit_a > 0.0f;
    tw_max = std::max(tw_max, tw);
    ilim_min = std::min(ilim_min, static_cast<double>(pr.i_limit_a));
    const double e = std::abs(static_cast<double>(pr.t_winding_est_c) - tw);
    if (est_live && e > err_max) {
      err_max = e;
      t_err_max = t;
    }
    if (k % every == 0) {
      const double row[] = {t,  tw,         pr.t_winding_est_c, th->housing_c(), pr.i_limit_a,
                            id, pr.id_ref_a};
      ctx.csv.row(row, sizeof row / sizeof row[0]);
    }
    stopped = watch(pr);
    if (!stopped.empty()) break;
    if (k < n) run.step();
    if ((k & 4095) == 0) ctx.progress.update(t, dur);
  }
  record_app_setup(f, p, ctx.summary);
  const mc_app_probe_t& d = run.probe();
  const bool derate = P.get("derate") > 0.5;
  ctx.summary.set("faults", d.faults);
  ctx.summary.set_text("derate", derate ? "on" : "off");
  ctx.summary.set("t_winding_limit_c", limit_c);
  ctx.summary.set("t_winding_max_c", tw_max);
  ctx.summary.set("t_est_err_max_k", err_max);
  ctx.summary.set("t_est_err_max_at_s", t_err_max);
  ctx.summary.set("i_limit_min_a", ilim_min);
  ctx.summary.set("i_on_a", i_on);
  ctx.summary.set("model_r_scale", P.get("model_r_scale"));
  if (!stopped.empty()) {
    ctx.summary.set_text("fault_names", stopped);
    return write_verdict(ctx.summary,
                         d.faults != 0u ? faulted(d.faults) : Verdict{"stopped", stopped, true});
  }
  Judge j;
  j.at_most("estimate off", "max |t_winding_est_c - t_winding_c| [K]", err_max, kEstTolK,
            "issue 33: the drive's estimate within 5 K of the plant's winding throughout");
  if (derate) {
    j.at_most("winding over its limit", "t_winding_max_c", tw_max, limit_c + kLimitTolK,
              "issue 33: with derating the winding at most 2 K above its limit");
  } else {
    j.at_least("duty does not overheat", "t_winding_max_c", tw_max, limit_c + kLimitTolK,
               "without derating the duty must take the winding past its limit, or the "
               "comparison shows nothing");
  }
  write_verdict(ctx.summary, j.verdict());
}

const Registrar reg_thermal(on_app_target(
    {"thermal-duty",
     "any motor: an overload cycle (overload x i_rated on the d axis, on_s of on_s + off_s) "
     "on a plant with winding and housing temperatures; the drive's winding estimate and its "
     "derating (derate=0: off); summary: winding max against its limit, estimate error",
     0.0,
     {},
     run_thermal,
     thermal_params}));

}  // namespace
}  // namespace mcsim
