// bus-limits: any motor, an acceleration and a regenerative stop on a DC
// link whose supply has an internal resistance (source_r_ohm) and sinks
// current (source_sink=1: the regenerated current flows back into it), with
// the drive's DC-bus current limits (firmware/app/drive/mc_drive_bus.h: the
// parameters i_bus_max_a, i_bus_regen_max_a) set. The drive application's
// sensored speed law (SET_SPEED_REF frames) accelerates the rotor to
// speed_rad_s at the derived slew, holds it, then the reference ramps to 0.
//
// Columns: i_bus_a is the plant's supply current (mcsim::DcLink
// source_avg_a, the mean over the period; positive: drawn from the supply),
// i_bus_est_a the drive's estimate, i_bus_max_a / i_bus_regen_max_a the
// limits the drive has in force (its probe; 0: off).
//
// Verdict: no fault; the supply current after the first period never above
// i_bus_max_a nor below -i_bus_regen_max_a by more than 2 % of them; the
// rotor reached 95 % of speed_rad_s and came back below 2 % of it. With
// limits=off the drive runs without them and the run is judged against the
// same figures: it shows what the limits hold back (and fails where the
// unlimited drive draws more).
//
// Default limits: fractions of the power the speed ramp asks at the top
// speed, P = speed_rad_s min(kt i_limit, J ramp): motoring half of it,
// regenerating a third, over the nominal bus, so that the unlimited run
// exceeds both on any motor.
#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>

#include "app_params.hpp"
#include "app_scenario.hpp"
#include "scenario.hpp"
#include "verdict.hpp"

namespace mcsim {
namespace {

constexpr double kTolFrac = 0.02;  // issue 33 item 5: 2 % of the limits

double demand_w(const MotorFiles& f, const mc_params_eff_t& e) {
  const mc_gains_t& g = e.g;
  const double tau = std::min(g.kt_nm_a * g.i_limit_a, f.motor.j_kgm2 * e.p.speed_ramp_rad_s2);
  return 0.5 * g.speed_limit_rad_s * tau;  // at the default speed (half the limit)
}

std::vector<ParamSpec> bus_params(const MotorFiles& f) {
  const mc_params_eff_t e = files_params_eff(f);
  const BoardSpec& b = f.board;
  const double p_w = demand_w(f, e), vbus = e.p.vbus_v;
  std::vector<ParamSpec> p = {
      {"limits",
       1.0,
       "1",
       "the drive's DC-bus limits on (off: the same run unlimited)",
       0.0,
       1.0,
       {{"off", 0.0}, {"on", 1.0}}},
      {"i_bus_max_a", 0.5 * p_w / vbus, "A",
       "motoring bus current limit (default: half the power the speed ramp asks at speed_rad_s "
       "over the nominal bus)",
       1.0e-3, 1000.0},
      {"i_bus_regen_max_a", p_w / (3.0 * vbus), "A",
       "regenerative bus current limit (default: a third of that power over the nominal bus)",
       1.0e-3, 1000.0},
      {"speed_rad_s", 0.5 * e.g.speed_limit_rad_s, "rad/s",
       "running speed before the stop (mechanical; default half the speed limit)", 0.0,
       e.g.speed_limit_rad_s},
      {"source_r_ohm", b.source_r_ohm, "ohm", "supply internal resistance", 1.0e-4, 1.0e3},
      {"dc_link_c_f", b.dc_link_c_f > 0 ? b.dc_link_c_f : 1.0e-3, "F",
       "bus capacitance (the board file's, else 1 mF)", 1.0e-7, 10.0},
      {"csv_every", 0.0, "1", "write every n-th PWM period (0: all up to 20000 rows)", 0.0, 1.0e9}};
  for (auto& s : app_gain_params(f)) p.push_back(s);
  return p;
}

// The table's range for a limit given with --set (a value the drive's
// parameter store would refuse is refused here too).
void set_limit(mc_params_t* p, const char* name, double v) {
  const int32_t i = mc_param_find_name(name);
  if (i < 0) throw std::logic_error(std::string("bus-limits: no parameter ") + name);
  const mc_param_info_t& info = mc_param_table[i];
  mc_param_value_t raw;
  raw.f = static_cast<float>(v);
  if (mc_param_check_value(&info, raw.u) != MC_PARAM_OK) {
    throw UsageError(std::string("--set ") + name + "=" + std::to_string(v) +
                     ": outside the parameter table's range");
  }
  mc_param_set_raw(p, &info, raw.u);
}

struct BusTrace {
  double i_max = -1e300, i_min = 1e300, w_max = 0;
};

void run_bus(RunContext& ctx) {
  MotorFiles f = *ctx.files;
  const Params& P = ctx.params;
  f.board.dc_link_c_f = P.get("dc_link_c_f");
  f.board.source_r_ohm = P.get("source_r_ohm");
  f.board.source_sink = true;
  f.board.brake_r_ohm = 0.0;
  const bool on = P.get("limits") > 0.5;
  const double i_m = P.get("i_bus_max_a"), i_r = P.get("i_bus_regen_max_a");
  mc_params_t p = params_from_files(f, P);
  p.brake_enable = 0u;
  if (on) {
    set_limit(&p, "i_bus_max_a", i_m);
    set_limit(&p, "i_bus_regen_max_a", i_r);
  }
  const mc_params_eff_t e0 = resolve_params(p);
  const double w_t = P.get("speed_rad_s");
  const double acc = e0.p.speed_ramp_rad_s2;
  const double t_acc = w_t / acc, t_set = 40.0 / e0.g.speed_wc_rad_s;
  // The limited run is slower than the ramp: the kinetic energy at the
  // limits' power, with margin.
  const double ke_j = 0.5 * f.motor.j_kgm2 * w_t * w_t;
  const double vb = e0.p.vbus_v;
  const double t0 = 0.01, t_up = 2.0 * (t_acc + ke_j / (i_m * vb)) + t_set;
  const double t_stop = t0 + t_up;
  const double dur = run_duration(ctx, t_stop + 2.0 * (t_acc + ke_j / (i_r * vb)) + t_set);
  const std::unique_ptr<AppTarget> target = make_file_target(ctx, f, p, nullptr);
  AppRunner run(*target);
  run.start(MC_CAN_CTRL_SPEED);
  auto& board = run.board();
  const mcsim::DcLink* link = board.dc_link();
  if (link == nullptr) throw std::logic_error("bus-limits: the board has no DC link");
  const double T = board.period_s();
  const long n = step_count(dur, T);
  const long every =
      P.get("csv_every") > 0 ? std::lround(P.get("csv_every")) : std::max(1L, n / 20000);
  ctx.csv.columns({"t", "omega_m_rad_s", "omega_ref_rad_s", "i_q_a", "i_q_ref_a", "vbus_v",
                   "i_bus_a", "i_bus_est_a", "i_bus_max_a", "i_bus_regen_max_a", "fault_1"});
  double w_cmd = 0.0, w = 0.0;
  std::string stopped;
  AppWatch watch;
  BusTrace tr;
  for (long k = 0; k <= n; ++k) {
    const double t = board.t_s();
    const double w_want = t >= t_stop ? 0.0 : (t >= t0 ? w_t : 0.0);
    if (w_want != w_cmd) {
      run.send(run.cmd().speed_ref(w_want));
      w_cmd = w_want;
    }
    double id = 0, iq = 0;
    board.true_dq_a(&id, &iq);
    w = board.state()(2);
    tr.w_max = std::max(tr.w_max, w);
    const double ib = link->source_avg_a();  // over the period that ended at t
    if (k >= 2) {                            // after the first period
      tr.i_max = std::max(tr.i_max, ib);
      tr.i_min = std::min(tr.i_min, ib);
    }
    const mc_app_probe_t& pr = run.probe();
    if (k % every == 0) {
      const double row[] = {t,
                            w,
                            pr.omega_ref_rad_s,
                            iq,
                            pr.iq_ref_a,
                            board.vbus_v(),
                            ib,
                            pr.i_bus_est_a,
                            pr.i_bus_mot_lim_a,
                            pr.i_bus_regen_lim_a,
                            static_cast<double>(pr.faults)};
      ctx.csv.row(row, sizeof row / sizeof row[0]);
    }
    stopped = watch(pr);
    if (!stopped.empty()) break;
    if (k < n) run.step();
    if ((k & 1023) == 0) ctx.progress.update(t, dur);
  }
  record_app_setup(f, p, ctx.summary);
  const mc_app_probe_t& d = run.probe();
  ctx.summary.set("faults", d.faults);
  ctx.summary.set_text("limits", on ? "on" : "off");
  ctx.summary.set("i_bus_max_a", i_m);
  ctx.summary.set("i_bus_regen_max_a", i_r);
  ctx.summary.set("source_r_ohm", f.board.source_r_ohm);
  if (!stopped.empty()) {
    ctx.summary.set_text("fault_names", stopped);
    return write_verdict(ctx.summary,
                         d.faults != 0u ? faulted(d.faults) : Verdict{"stopped", stopped, true});
  }
  ctx.summary.set("i_bus_peak_a", tr.i_max);
  ctx.summary.set("i_bus_min_a", tr.i_min);
  ctx.summary.set("i_bus_excess_frac", tr.i_max / i_m - 1.0);
  ctx.summary.set("i_bus_regen_excess_frac", -tr.i_min / i_r - 1.0);
  ctx.summary.set("omega_start_rad_s", w_t);
  ctx.summary.set("omega_peak_rad_s", tr.w_max);
  ctx.summary.set("omega_end_rad_s", w);
  Judge j;
  j.at_most("bus current above its limit", "supply current peak after the first period [A]",
            tr.i_max, (1.0 + kTolFrac) * i_m, "i_bus_max_a + 2 %");
  j.at_least("regenerative bus current above its limit",
             "supply current minimum after the first period [A]", tr.i_min, -(1.0 + kTolFrac) * i_r,
             "-(i_bus_regen_max_a + 2 %)");
  j.at_least("target not reached", "peak speed [rad/s]", tr.w_max, 0.95 * w_t,
             "95 % of speed_rad_s");
  j.at_most("not stopped", "|speed| at the end [rad/s]", std::abs(w), 0.02 * w_t,
            "2 % of speed_rad_s");
  write_verdict(ctx.summary, j.verdict());
}

const Registrar reg_bus(on_app_target(
    {"bus-limits",
     "any motor: acceleration and regenerative stop on a supply with internal resistance that "
     "sinks current, the drive's DC-bus current limits set (limits=off: the same run without); "
     "summary: the supply current's peak and minimum against i_bus_max_a and i_bus_regen_max_a",
     0.0,
     {},
     run_bus,
     bus_params}));

}  // namespace
}  // namespace mcsim
