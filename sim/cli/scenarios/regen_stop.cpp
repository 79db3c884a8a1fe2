// regen-stop: any motor, a full-speed stop on a DC link (mcsim::DcLink) so
// braking shows on the bus voltage; with and without the brake resistor
// (--set brake=on|off: the brake_enable parameter). The drive application's
// sensored speed law (speed_law 0, commanded by SET_SPEED_REF frames)
// accelerates the rotor to speed_rad_s (default: the speed limit), holds
// it, then the reference ramps to zero at decel_rad_s2 (the drive's slew,
// the speed_ramp_rad_s2 parameter). The drive limits the regenerative current by the bus voltage, injects d
// current to burn energy in the windings when the bus is full, and drives
// the chopper (mc_drive.h, "Regenerative braking").
//
// Summary: vbus peak (and its margin to the trip), energy to the resistor,
// stop time (reference at zero -> |omega| below 2 % of the start speed for
// good), and the energy balance over the stop
//   E_source + E_kinetic + E_magnetic (released) =
//     E_brake + E_source_r + E_copper + E_friction + dE_capacitor
// with the plant's own quantities (the copper and friction losses from the
// true currents and speed, trapezoidal per period): its residual relative
// to the kinetic energy is energy_balance_rel_err.
#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>

#include "app_scenario.hpp"
#include "app_params.hpp"
#include "scenario.hpp"
#include "verdict.hpp"

namespace mcsim {
namespace {

// Representative bus capacitance when the board file gives none: 0.25 mF
// per kW of peak shaft power, at least 1 mF (the 40 kW machine of paper 002
// trips on over-voltage with 1 mF: its current loop, 640 rad/s, cannot cut
// 40 kW before a 1 mF bus has risen through the 36 V regen band).
double default_c_f(const mc_gains_t& g) {
  const double p_w = g.kt_nm_a * g.i_limit_a * g.speed_limit_rad_s;
  return std::max(1.0e-3, 0.25e-3 * p_w / 1000.0);
}

std::vector<ParamSpec> regen_params(const MotorFiles& f) {
  const mc_gains_t g = files_params_eff(f).g;  // the C derivation's, for the files
  const BoardSpec& b = f.board;
  std::vector<ParamSpec> p = {
      {"brake", 1.0, "1", "brake resistor on the chopper", 0.0, 1.0, {{"off", 0.0}, {"on", 1.0}}},
      {"speed_rad_s", g.speed_limit_rad_s, "rad/s", "running speed before the stop (mechanical)",
       0.0, g.speed_limit_rad_s},
      {"dc_link_c_f", b.dc_link_c_f > 0 ? b.dc_link_c_f : default_c_f(g), "F",
       "bus capacitance (the board file's, else a representative 0.25 mF per kW of the "
       "drive's peak shaft power kt i_limit speed_limit, at least 1 mF)",
       1.0e-7, 10.0},
      {"source_r_ohm", b.source_r_ohm, "ohm", "supply internal resistance", 1.0e-4, 1.0e3},
      {"source_sink", b.source_sink ? 1.0 : 0.0, "1",
       "the supply can sink current (0: a bench supply behind a diode)", 0.0, 1.0},
      {"brake_r_ohm", b.brake_r_ohm > 0 ? b.brake_r_ohm : 2.0, "ohm",
       "brake resistor when brake=on (the board file's, else 2 ohm as ODrive's default)", 1.0e-3,
       1.0e4},
      {"csv_every", 0.0, "1", "write every n-th PWM period (0: all up to 20000 rows)", 0.0, 1.0e9}};
  for (auto& s : app_gain_params(f)) p.push_back(s);
  return p;
}

void run_regen(RunContext& ctx) {
  MotorFiles f = *ctx.files;
  const Params& P = ctx.params;
  f.board.dc_link_c_f = P.get("dc_link_c_f");
  f.board.source_r_ohm = P.get("source_r_ohm");
  f.board.source_sink = P.get("source_sink") > 0.5;
  const bool brake = P.get("brake") > 0.5;
  f.board.brake_r_ohm = brake ? P.get("brake_r_ohm") : 0.0;
  // The application's table (app_params.hpp); the chopper where the board
  // has a brake resistor (brake_enable: a board without one refuses it).
  mc_params_t p = params_from_files(f, P);
  p.brake_enable = brake ? 1u : 0u;
  const mc_params_eff_t e0 = resolve_params(p);
  const mc_gains_t& g = e0.g;
  const double w_t = P.get("speed_rad_s");
  const double acc = e0.p.speed_ramp_rad_s2;
  const double t0 = 0.01, t_acc = w_t / acc, t_set = 40.0 / g.speed_wc_rad_s;
  const double t_stop = t0 + t_acc + t_set;
  // The stop may take longer than the ramp when the bus cannot take the
  // energy: allow the kinetic energy over a tenth of the copper loss at the
  // d-current limit, and at least 20 ramps.
  const MotorSpec& m = f.motor;
  const double ke_j = 0.5 * m.j_kgm2 * w_t * w_t;
  const double p_cu = std::max(1e-9, 1.5 * m.r_ohm * g.i_limit_a * g.i_limit_a);
  const double dur = run_duration(ctx, t_stop + std::max(20.0 * t_acc, 10.0 * ke_j / p_cu) + t_set);
  const std::unique_ptr<AppTarget> target = make_file_target(ctx, f, p, nullptr);
  AppRunner run(*target);
  run.start(MC_CAN_CTRL_SPEED);
  auto& board = run.board();
  const mcsim::DcLink* link = board.dc_link();
  if (link == nullptr) throw std::logic_error("regen-stop: the board has no DC link");
  const double T = board.period_s();
  const long n = step_count(dur, T);
  const long every =
      P.get("csv_every") > 0 ? std::lround(P.get("csv_every")) : std::max(1L, n / 20000);
  ctx.csv.columns({"t", "omega_m_rad_s", "omega_ref_rad_s", "i_d_a", "i_q_a", "i_d_ref_a",
                   "i_q_ref_a", "vbus_v", "brake_duty", "regen_scale", "fault_1"});
  const double trip = e0.p.vbus_max_v;
  double w_cmd = 0.0;  // the last SET_SPEED_REF sent
  std::string stopped;
  AppWatch watch;
  double vpk = 0, t_still = std::nan(""), w = 0, id = 0, iq = 0, w_min = 0;
  // Energy bookkeeping over the stop (from t_stop).
  double e_cu = 0, p_prev = 0;
  double ke0 = 0, em0 = 0, src0 = 0, srcr0 = 0, brk0 = 0, cap0 = 0;
  bool in_stop = false;
  auto loss_w = [&](double idd, double iqq, double ww) {
    return 1.5 * m.r_ohm * (idd * idd + iqq * iqq) + m.b_nm_s_rad * ww * ww;
  };
  auto emag = [&](double idd, double iqq) {
    return 0.75 * (m.ld_h * idd * idd + m.lq_h * iqq * iqq);
  };
  for (long k = 0; k <= n; ++k) {
    const double t = board.t_s();
    const double w_want = t >= t_stop ? 0.0 : (t >= t0 ? w_t : 0.0);
    if (w_want != w_cmd) {
      run.send(run.cmd().speed_ref(w_want));
      w_cmd = w_want;
    }
    board.true_dq_a(&id, &iq);
    w = board.state()(2);
    const double v = board.vbus_v();
    if (t >= t_stop) {
      vpk = std::max(vpk, v);
      w_min = std::min(w_min, w);
      if (std::abs(w) > 0.02 * w_t)
        t_still = std::nan("");
      else if (std::isnan(t_still))
        t_still = t;
      const double pl = loss_w(id, iq, w);
      if (!in_stop) {
        in_stop = true;
        ke0 = 0.5 * m.j_kgm2 * w * w;
        em0 = emag(id, iq);
        src0 = link->energy().source_j;
        srcr0 = link->energy().source_r_j;
        brk0 = link->energy().brake_j;
        cap0 = link->cap_delta_j();
      } else {
        e_cu += 0.5 * T * (p_prev + pl);  // copper + friction, trapezoid
      }
      p_prev = pl;
    }
    const mc_app_probe_t& pr = run.probe();
    if (k % every == 0) {
      const double row[] = {t,
                            w,
                            pr.omega_ref_rad_s,
                            id,
                            iq,
                            pr.id_ref_a,
                            pr.iq_ref_a,
                            v,
                            board.brake_duty(),
                            pr.regen_scale,
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
  ctx.summary.set_text("brake", brake ? "on" : "off");
  ctx.summary.set("vbus_trip_v", trip);  // the thresholds, also for a run a fault stopped
  ctx.summary.set("vbus_regen_start_v", e0.p.vbus_regen_start_v);
  if (!stopped.empty()) {
    ctx.summary.set_text("fault_names", stopped);
    return write_verdict(ctx.summary,
                         d.faults != 0u ? faulted(d.faults) : Verdict{"stopped", stopped, true});
  }
  const auto& e = link->energy();
  const double ke1 = 0.5 * m.j_kgm2 * w * w, em1 = emag(id, iq);
  const double lhs = (e.source_j - src0) + (ke0 - ke1) + (em0 - em1);
  const double rhs =
      (e.brake_j - brk0) + (e.source_r_j - srcr0) + e_cu + (link->cap_delta_j() - cap0);
  ctx.summary.set("vbus_peak_v", vpk);
  ctx.summary.set("vbus_margin_v", trip - vpk);
  ctx.summary.set("brake_on_v", brake ? e0.p.brake_on_v : 0.0f);
  ctx.summary.set("decel_rad_s2", acc);
  ctx.summary.set("stop_time_s", t_still - t_stop);
  ctx.summary.set("stop_time_ramp_s", w_t / acc);
  ctx.summary.set("omega_start_rad_s", w_t);
  ctx.summary.set("omega_min_rad_s", w_min);
  ctx.summary.set("kinetic_j", ke0);
  ctx.summary.set("brake_energy_j", e.brake_j - brk0);
  ctx.summary.set("source_energy_j", e.source_j - src0);
  ctx.summary.set("source_r_energy_j", e.source_r_j - srcr0);
  ctx.summary.set("winding_friction_loss_j", e_cu);
  ctx.summary.set("cap_delta_j", link->cap_delta_j() - cap0);
  ctx.summary.set("energy_balance_residual_j", lhs - rhs);
  ctx.summary.set("energy_balance_rel_err", (lhs - rhs) / std::max(1e-12, ke0));
  RegenFigures fig;
  fig.stop_time_s = t_still - t_stop;
  fig.vbus_peak_v = vpk;
  fig.vbus_trip_v = trip;
  fig.energy_balance_rel_err = (lhs - rhs) / std::max(1e-12, ke0);
  write_verdict(ctx.summary, judge_regen_stop(fig));
}

const Registrar reg_regen(on_app_target(
    {"regen-stop",
     "any motor: full-speed stop on a DC link (supply with internal resistance that cannot sink "
     "by default, bus capacitor, brake resistor with brake=on): regen current limit by the bus "
     "voltage, chopper; summary: vbus peak, energy to the resistor, stop time, energy balance",
     0.0,
     {},
     run_regen,
     regen_params}));

}  // namespace
}  // namespace mcsim
