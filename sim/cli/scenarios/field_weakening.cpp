// field-weakening: any motor, the drive's MTPA + field-weakening kernel
// (firmware/kernels/fw/mc_fw.h) in the drive application (issue 29 item
// 3): the parameter table of the files (app_params.hpp) with fw_enable = 1
// (fw_v_margin and fw_ki_a_per_vs the table's: 0.9 and derived), commanded
// by CAN frames (app_cmd.hpp), on the SIL or with --pil the board's whole
// image (app_target.hpp), the same CSV and summary on both.
//
// Part 1, MTPA (rotor on a dyno flywheel: j_load_factor motor inertias, so
// it stays near standstill): CURRENT mode, SET_CURRENT_REF (0, I) for I =
// 25, 50, 75 and 100 % of the rated current (the drive's MTPA turns |i|
// into its d and q parts), each held 12 design rise times + 2 ms (the
// command waits up to one slow-loop period); at the end of each hold the
// plant's torque per ampere |T| / |i| (true currents) is compared with the
// analytic optimum for that current magnitude,
//   max over beta of 3/2 p I cos(beta) (flux + (Lq - Ld) I sin(beta)) / I,
// found here by golden-section search in double (independent of the
// kernel's closed form). mtpa_rel_err_max is the largest |ratio - 1|.
//
// Part 2, speed ramp: SPEED mode on the sensored speed law (speed_law 0),
// SET_SPEED_REF from standstill to min(2.5 base speed, speed_max_rad_s),
// the drive slewing the reference at speed_ramp_rad_s2 (the table's),
// held for hold_s. Base speed: where MTPA at the rated current needs
// v_max = 0.9 vbus / sqrt 3 in steady state (R included). Summary: faults,
// |i| peak against the table's current limit, final speed, v_mag - v_max
// in the hold (the probe's field-weakening signals).
//
// CSV (parts 2 and 3): t, the true dq currents, the drive's references
// (probe), the true speed, the speed reference (probe), the true
// electrical angle, the applied dq voltage in the true frame, v_mag_v (|v|
// the current loop applied) and v_max_v (the field-weakening target) from
// the probe, the faults, the plant's bus voltage vbus_v.
//
// Part 3 (--set fault=1): a loss of control at the top speed. The supply
// is a bench supply behind a diode (it cannot sink current), the bus
// capacitor the board file's or 1 mF. At the end of the hold the encoder's
// cable comes off (the plant's encoder reads not valid): the drive faults
// ENCODER, one of the faults that may short the phases
// (MC_DRIVE_ASC_FAULTS), and the run goes on for fault_s. With asc=off
// (the asc_enable parameter) the drive opens the bridge: above
// omega_uncontrolled_gen the back-EMF drives current through the diodes
// into the bus. With asc=on it shorts the phases through the low-side
// switches (without a valid encoder the short holds until CLEAR_FAULTS).
// Summary: fault_vbus_peak_v against fault_vbus_trip_v (vbus_max_v), the
// peak phase current against i_trip_a and the braking torque. The short's
// current settles towards flux / Ld, but its transient from the operating
// point overshoots that by up to |v_dq| / (omega_e Ld) (the flux deviation
// rotating at omega_e); fault_i_sense_max_a gives the board the sensing
// (the table's i_sense_max_a, and i_trip_a at 98 % of it) that the
// transient needs.
#include <algorithm>
#include <cmath>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>

#include "app_scenario.hpp"
#include "scenario.hpp"
#include "verdict.hpp"
extern "C" {
#include "config/mc_law_cfg.h"
}

namespace mcsim {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Torque per ampere at the MTPA point for |i| = I (golden section on beta).
double mtpa_t_per_a(const MotorSpec& m, double I) {
  const double dl = m.lq_h - m.ld_h;
  auto t = [&](double b) {
    return 1.5 * m.pole_pairs * I * std::cos(b) * (m.flux_wb + dl * I * std::sin(b));
  };
  double lo = -0.5 * kPi, hi = 0.5 * kPi;
  const double g = 0.5 * (std::sqrt(5.0) - 1.0);
  for (int k = 0; k < 200; ++k) {
    const double a = hi - g * (hi - lo), b = lo + g * (hi - lo);
    if (t(a) > t(b))
      hi = b;
    else
      lo = a;
  }
  return t(0.5 * (lo + hi)) / I;
}

// Mechanical speed at which MTPA at current I needs v (steady state).
double base_speed(const MotorSpec& m, double I, double v) {
  const double dl = m.lq_h - m.ld_h;
  const double id =
      (std::abs(dl) > 1e-3 * std::max(m.ld_h, m.lq_h))
          ? (m.flux_wb - std::sqrt(m.flux_wb * m.flux_wb + 8 * dl * dl * I * I)) / (4 * dl)
          : 0.0;
  const double iq = std::sqrt(std::max(0.0, I * I - id * id));
  auto vmag = [&](double wm) {
    const double we = m.pole_pairs * wm;
    const double vd = m.r_ohm * id - we * m.lq_h * iq;
    const double vq = m.r_ohm * iq + we * (m.flux_wb + m.ld_h * id);
    return std::hypot(vd, vq);
  };
  double lo = 0, hi = 1.0e5;
  if (vmag(lo) >= v) return 0.0;
  for (int k = 0; k < 200; ++k) {
    const double mid = 0.5 * (lo + hi);
    if (vmag(mid) > v)
      hi = mid;
    else
      lo = mid;
  }
  return lo;
}

std::vector<ParamSpec> fw_params(const MotorFiles& f) {
  std::vector<ParamSpec> p = {
      {"speed_factor", 2.5, "1", "ramp target in base speeds (capped at speed_max_rad_s)", 0.1,
       10.0},
      {"hold_s", 0.3, "s", "hold at the target", 0.0, 100.0},
      {"j_load_factor", 1.0e4, "1", "MTPA part: dyno inertia in motor inertias", 0.0, 1.0e9},
      {"csv_every", 0.0, "1", "write every n-th PWM period (0: all up to 20000 rows)", 0.0, 1.0e9},
      {"fault", 0.0, "1",
       "part 3: the encoder lost at the end of the hold, one-way supply (a loss of control at the "
       "top speed)",
       0.0, 1.0},
      {"asc",
       0.0,
       "1",
       "the drive's active short circuit (the asc_enable parameter)",
       0.0,
       1.0,
       {{"off", 0.0}, {"on", 1.0}}},
      {"fault_s", 0.05, "s", "part 3: run time after the fault", 1.0e-4, 10.0},
      {"fault_i_sense_max_a", 0.0, "A",
       "part 3: current-sensing range of the board (0: the board file's); the drive's "
       "over-current trip i_trip_a at 98 % of it",
       0.0, 1.0e5}};
  for (auto& s : app_gain_params(f)) p.push_back(s);
  return p;
}

// One CSV row (parts 2 and 3): the plant's true dq currents, speed, angle,
// applied voltage and bus; the application's references and field-weakening
// signals (its probe).
class FwRecorder {
 public:
  FwRecorder(RunContext& ctx, AppRunner& run, int pole_pairs, long every)
      : ctx_(ctx), run_(run), p_(pole_pairs), every_(every) {}
  void header() {
    ctx_.csv.columns({"t", "i_d_a", "i_q_a", "i_d_ref_a", "i_q_ref_a", "omega_m_rad_s",
                      "omega_ref_rad_s", "theta_e_rad", "v_d_v", "v_q_v", "v_mag_v", "v_max_v",
                      "fault_1", "vbus_v"});
  }
  void row() {
    if (k_++ % every_ != 0) return;
    hal_host::PmsmBoard& b = run_.board();
    const mc_app_probe_t& pr = run_.probe();
    double id = 0, iq = 0;
    b.true_dq_a(&id, &iq);
    const double th = std::remainder(p_ * b.rotor_frame_state()(3), 2 * kPi);
    const Eigen::Vector2d& v = b.v_alpha_beta_applied();
    const double c = std::cos(th), s = std::sin(th);
    const double r[] = {b.t_s(),
                        id,
                        iq,
                        pr.id_ref_a,
                        pr.iq_ref_a,
                        b.state()(2),
                        pr.omega_ref_rad_s,
                        th,
                        c * v(0) + s * v(1),
                        -s * v(0) + c * v(1),
                        pr.fw_v_mag_v,
                        pr.fw_v_max_v,
                        static_cast<double>(pr.faults),
                        b.vbus_v()};
    ctx_.csv.row(r, sizeof r / sizeof r[0]);
  }

 private:
  RunContext& ctx_;
  AppRunner& run_;
  int p_;
  long every_;
  long k_ = 0;
};

// The application's drive configuration (its fw kernel's bounds, trips).
mc_drive_cfg_t drive_cfg_of(const mc_params_t& p) {
  const mc_params_eff_t e = resolve_params(p);
  mc_drive_cfg_t c{};
  (void)mc_params_eff_to_drive_cfg(&e, &c);
  return c;
}

// The verdict of a part that stopped (a fault or the application's stop).
void stopped_verdict(RunContext& ctx, const mc_app_probe_t& d, const std::string& why,
                     const char* part) {
  ctx.summary.set("faults", d.faults);
  ctx.summary.set_text("fault_names", why);
  write_verdict(ctx.summary, d.faults != 0u ? faulted(d.faults, why + " " + part)
                                            : Verdict{"stopped", why + " " + part, true});
}

struct MtpaResult {
  double err_max = 0, kt_gain = 0, id_abs_max = 0;
  bool ok = false;
};

// Part 1: MTPA on the dyno (see the file comment).
MtpaResult run_mtpa(RunContext& ctx, const MotorFiles& f, const mc_params_t& p) {
  const mc_params_eff_t e = resolve_params(p);
  MotorFiles fd = f;
  fd.motor.j_kgm2 *= 1.0 + ctx.params.get("j_load_factor");
  const std::unique_ptr<AppTarget> target = make_file_target(ctx, fd, p, nullptr);
  AppRunner run(*target);
  run.start(MC_CAN_CTRL_CURRENT);
  hal_host::PmsmBoard& board = run.board();
  const double hold = 12.0 * std::log(9.0) / e.g.cur_bw_rad_s + 2e-3;
  const long nh = std::lround(hold / board.period_s());
  MtpaResult r;
  AppWatch watch;
  for (int lvl = 1; lvl <= 4; ++lvl) {
    const double icmd = 0.25 * lvl * e.g.i_rated_eff_a;
    run.send(run.cmd().current_ref(0.0, icmd));
    for (long k = 0; k < nh; ++k) {
      run.step();
      const std::string why = watch(run.probe());
      if (!why.empty()) {
        stopped_verdict(ctx, run.probe(), why, "in part 1 (MTPA on the dyno)");
        return r;
      }
    }
    double id, iq;
    board.true_dq_a(&id, &iq);
    const double I = std::hypot(id, iq);
    const double tpa = std::abs(board.torque_nm()) / I;
    const double opt = mtpa_t_per_a(f.motor, I);
    const double err = tpa / opt - 1.0;
    ctx.summary.set("mtpa_i" + std::to_string(25 * lvl) + "_rel_err", err);
    ctx.summary.set("mtpa_i" + std::to_string(25 * lvl) + "_gain_over_id0", opt / e.g.kt_nm_a);
    r.err_max = std::max(r.err_max, std::abs(err));
    r.kt_gain = std::max(r.kt_gain, tpa / e.g.kt_nm_a);
    r.id_abs_max = std::max(r.id_abs_max, std::abs(id));
  }
  r.ok = true;
  return r;
}

// Part 3: the encoder lost at speed and what follows (see the file comment).
void run_fault(RunContext& ctx, AppRunner& run, FwRecorder& rec, const mc_drive_cfg_t& dc) {
  const MotorSpec& m = ctx.files->motor;
  hal_host::PmsmBoard& board = run.board();
  const double w0 = board.state()(2);
  const double vbus0 = board.vbus_v();
  hal_host::PmsmBoard::Injection inj;
  inj.encoder_dead = true;
  board.inject(inj);
  const long nf = step_count(ctx.params.get("fault_s"), board.period_s());
  double vpk = vbus0, ipk = 0, tq_min = 0;
  long asc_steps = 0;
  for (long k = 0; k < nf; ++k) {
    run.step();
    const Eigen::Vector3d i = board.phase_currents_true_a();
    ipk = std::max(ipk, i.cwiseAbs().maxCoeff());
    vpk = std::max(vpk, board.vbus_v());
    tq_min = std::min(tq_min, board.torque_nm());
    asc_steps += run.probe().asc_active != 0u ? 1 : 0;
    rec.row();
  }
  const mc_app_probe_t& d = run.probe();
  ctx.summary.set_text("asc", dc.asc_enable ? "on" : "off");
  ctx.summary.set_text("fault_cause", "encoder lost (the plant's encoder reads not valid)");
  ctx.summary.set("fault_omega_m_rad_s", w0);
  ctx.summary.set("fault_emf_over_vbus",
                  std::sqrt(3.0) * m.pole_pairs * m.flux_wb * std::abs(w0) / vbus0);
  ctx.summary.set("fault_vbus_before_v", vbus0);
  ctx.summary.set("fault_vbus_peak_v", vpk);
  ctx.summary.set("fault_vbus_trip_v", dc.vbus_max_v);
  ctx.summary.set("fault_i_phase_peak_a", ipk);
  ctx.summary.set("fault_i_trip_a", dc.i_trip_a);
  ctx.summary.set("fault_torque_min_nm", tq_min);
  ctx.summary.set("fault_asc_time_s", static_cast<double>(asc_steps) * board.period_s());
  ctx.summary.set("fault_omega_end_rad_s", board.state()(2));
  ctx.summary.set("fault_first", d.first_fault);
  ctx.summary.set("fault_bits", d.faults);
  ctx.summary.set_text("fault_first_name", drive_fault_names(d.first_fault));
  ctx.summary.set_text("fault_names", drive_fault_names(d.faults));
}

void run_fw(RunContext& ctx) {
  MotorFiles f = *ctx.files;
  const Params& P = ctx.params;
  const bool fault = P.get("fault") > 0.5;
  const double isense = fault ? P.get("fault_i_sense_max_a") : 0.0;
  if (fault) {  // part 3 on a supply that cannot sink current
    f.board.dc_link_c_f = f.board.dc_link_c_f > 0.0 ? f.board.dc_link_c_f : 1.0e-3;
    f.board.source_sink = false;
    if (isense > 0.0) f.board.i_sense_max_a = isense;
  }
  if (f.board.encoder_cpr == 0) {
    throw UsageError(f.board.file + ": field-weakening needs an encoder (encoder_cpr = 0 here)");
  }
  const MotorSpec& m = f.motor;
  // The application's table: the sensored speed law, MTPA and field
  // weakening on, the active short circuit as asked; a board with its own
  // sensing for part 3 trips where that sensing ends (the switches rated
  // for it), not at 1.6x the current limit.
  mc_params_t p = params_from_files(f, P, MC_LAW_SPEED_PI);
  p.fw_enable = 1u;
  p.asc_enable = P.get("asc") > 0.5 ? 1u : 0u;
  if (isense > 0.0) p.i_trip_a = static_cast<float>(0.98 * isense);
  const mc_params_eff_t e = resolve_params(p);
  const mc_gains_t& g = e.g;
  const mc_drive_cfg_t dc = drive_cfg_of(p);
  if (p.asc_enable != 0u && !(p.flux_wb / p.ld_h < dc.i_trip_a)) {
    throw UsageError(
        "asc=on: the drive refuses the active short circuit for this motor: its "
        "short-circuit current flux / Ld = " +
        std::to_string(p.flux_wb / p.ld_h) +
        " A is not below the over-current trip "
        "i_trip_a = " +
        std::to_string(dc.i_trip_a) + " A (more sensing: --set fault_i_sense_max_a=...)");
  }

  // ---- part 1: MTPA on the dyno
  const MtpaResult mt = run_mtpa(ctx, f, p);
  if (!mt.ok) return;
  ctx.summary.set("mtpa_rel_err_max", mt.err_max);
  ctx.summary.set("mtpa_id_abs_max_a", mt.id_abs_max);
  ctx.summary.set("mtpa_t_per_a_over_kt_max", mt.kt_gain);

  // ---- part 2: speed ramp into field weakening
  const double vbus = f.board.vbus_v;
  const double v_fw = 0.9 * vbus / std::sqrt(3.0);
  const double w_base = base_speed(m, g.i_rated_eff_a, v_fw);
  const double w_t = std::min(P.get("speed_factor") * w_base, m.speed_max_rad_s);
  const double t0 = 0.01, t_acc = w_t / static_cast<double>(e.p.speed_ramp_rad_s2);
  const double dur = run_duration(ctx, t0 + t_acc + 40.0 / g.speed_wc_rad_s + P.get("hold_s"));
  const double t_hold = dur - P.get("hold_s");
  const std::unique_ptr<AppTarget> target = make_file_target(ctx, f, p, nullptr);
  AppRunner run(*target);
  run.start(MC_CAN_CTRL_SPEED);
  hal_host::PmsmBoard& board = run.board();
  const long n = step_count(dur, board.period_s());
  const long every =
      P.get("csv_every") > 0 ? std::lround(P.get("csv_every")) : std::max(1L, n / 20000);
  FwRecorder rec(ctx, run, m.pole_pairs, every);
  rec.header();
  double i_pk = 0, w = 0, id = 0, iq = 0, v_over = -1e9, id_min = 0, werr_hold = 0;
  bool ref_sent = false;
  std::string stopped;
  AppWatch watch;
  for (long k = 0; k <= n; ++k) {
    const double t = board.t_s();
    if (!ref_sent && t >= t0) {
      run.send(run.cmd().speed_ref(w_t));
      ref_sent = true;
    }
    board.true_dq_a(&id, &iq);
    w = board.state()(2);
    i_pk = std::max(i_pk, std::hypot(id, iq));
    id_min = std::min(id_min, id);
    const mc_app_probe_t& pr = run.probe();
    if (t >= t_hold) {
      v_over = std::max(v_over, static_cast<double>(pr.fw_v_mag_v - pr.fw_v_max_v));
      werr_hold = std::max(werr_hold, std::abs(w - w_t));
    }
    rec.row();
    stopped = watch(pr);
    if (!stopped.empty()) break;
    if (k < n) run.step();
    if ((k & 1023) == 0) ctx.progress.update(t, dur);
  }
  record_app_setup(f, p, ctx.summary);
  if (!stopped.empty()) {
    return stopped_verdict(ctx, run.probe(), stopped, "in part 2 (the speed ramp)");
  }
  ctx.summary.set("faults", run.probe().faults);
  // The demagnetisation / circle bound the application's fw kernel derives.
  mc_fw_f32_t fw{};
  (void)mc_fw_f32_init(&fw, &dc.fw);
  ctx.summary.set("base_speed_rad_s", w_base);
  ctx.summary.set("target_speed_rad_s", w_t);
  ctx.summary.set("target_over_base", w_t / w_base);
  ctx.summary.set("omega_final_rad_s", w);
  ctx.summary.set("omega_err_max_hold_rad_s", werr_hold);
  ctx.summary.set("i_peak_a", i_pk);
  ctx.summary.set("i_limit_a", g.i_limit_a);
  ctx.summary.set("id_min_a", id_min);
  ctx.summary.set("id_demag_bound_a", static_cast<double>(fw.id_min_a));
  ctx.summary.set("v_mag_minus_v_max_hold_max_v", v_over);
  ctx.summary.set("v_fw_max_v", v_fw);
  // the frames the application sent (its telemetry)
  ctx.summary.set("app_tx_frames", static_cast<double>(run.frames_sent()));
  // Loss of control: the rectifier conducts above this speed (mc_fw.h).
  ctx.summary.set("omega_uncontrolled_gen_rad_s",
                  vbus / (std::sqrt(3.0) * m.pole_pairs * m.flux_wb));
  ctx.summary.set("short_circuit_current_a", m.flux_wb / m.ld_h);
  if (fault) run_fault(ctx, run, rec, dc);
  FieldWeakeningFigures fig;
  fig.mtpa_rel_err_max = mt.err_max;
  fig.omega_final_rad_s = w;
  fig.target_rad_s = w_t;
  fig.i_peak_a = i_pk;
  fig.i_limit_a = g.i_limit_a;
  fig.id_min_a = id_min;
  fig.id_demag_bound_a = fw.id_min_a;
  fig.fault_part = fault;
  write_verdict(ctx.summary, judge_field_weakening(fig));
}

const Registrar reg_fw(on_app_target(
    {"field-weakening",
     "any motor: the drive application with MTPA and field weakening on (fw_enable): MTPA torque "
     "per ampere on a dyno against the analytic optimum, then a sensored speed ramp to 2.5x base "
     "speed (capped at speed_max) with voltage-feedback field weakening; CSV adds v_mag_v, "
     "v_max_v and vbus_v; fault=1: the encoder lost at the top speed on a supply that cannot "
     "sink current, asc=on|off (the asc_enable parameter)",
     0.0,
     {},
     run_fw,
     fw_params}));

}  // namespace
}  // namespace mcsim
