// field-weakening: any motor, the drive's MTPA + field-weakening kernel
// (firmware/kernels/fw/mc_fw.h) with the firmware in the loop.
//
// Part 1, MTPA (rotor on a dyno flywheel: j_load_factor motor inertias, so
// it stays near standstill): current commands of 25, 50, 75 and 100 % of
// the rated current, each held 12 design rise times + 2 ms; at the end of
// each hold the plant's torque per ampere |T| / |i| (true currents) is
// compared with the analytic optimum for that current magnitude,
//   max over beta of 3/2 p I cos(beta) (flux + (Lq - Ld) I sin(beta)) / I,
// found here by golden-section search in double (independent of the
// kernel's closed form). mtpa_rel_err_max is the largest |ratio - 1|.
//
// Part 2, speed ramp: the sensored speed PI (its output is the signed
// current command) from standstill to min(2.5 base speed, speed_max_rad_s),
// slewed at speed_accel_rad_s2, held for hold_s. Base speed: where MTPA at
// the rated current needs v_max = 0.9 vbus / sqrt 3 in steady state (R
// included). Summary: faults, |i| peak against i_limit, final speed,
// v_mag - v_max in the hold.
//
// CSV (part 2): the generic scenarios' columns plus v_mag_v (|v_dq| the
// current loop applied) and v_max_v (the field-weakening target), and
// vbus_v.
//
// Part 3 (--set fault=1): a loss of control at the top speed. The supply
// is a bench supply behind a diode (it cannot sink current), the bus
// capacitor the board file's or 1 mF. At the end of the hold the
// application raises a fault (mc_drive_raise_fault, EXTERNAL) and the run
// goes on for fault_s. With asc=off the drive opens the bridge: above
// omega_uncontrolled_gen the back-EMF drives current through the diodes
// into the bus. With asc=on (mc_drive_cfg_t.asc_enable) it shorts the
// phases through the low-side switches. Summary: fault_vbus_peak_v against
// fault_vbus_trip_v, the peak phase current and the braking torque. The
// short's current settles towards flux / Ld, but its transient from the
// operating point overshoots that by up to |v_dq| / (omega_e Ld) (the flux
// deviation rotating at omega_e); fault_i_sense_max_a gives the board the
// sensing (and the drive a trip at 98 % of it) that the transient needs.
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "drive_setup.hpp"
#include "scenario.hpp"
#include "verdict.hpp"

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
      {"fault", 0.0, "1", "part 3: a fault at the end of the hold, one-way supply", 0.0, 1.0},
      {"asc",
       0.0,
       "1",
       "the drive's active short circuit (asc_enable)",
       0.0,
       1.0,
       {{"off", 0.0}, {"on", 1.0}}},
      {"fault_s", 0.05, "s", "part 3: run time after the fault", 1.0e-4, 10.0},
      {"fault_i_sense_max_a", 0.0, "A",
       "part 3: current-sensing range of the board (0: the board file's); the drive's "
       "over-current trip at 98 % of it",
       0.0, 1.0e5}};
  for (auto& s : gain_params(f)) p.push_back(s);
  return p;
}

// One CSV row (part 2 and part 3): the true dq currents, the drive's
// references and voltages, the bus.
void write_row(RunContext& ctx, MotorRig& rig) {
  double id, iq, vd, vq;
  rig.board().true_dq_a(&id, &iq);
  rig.dq_volts(&vd, &vq);
  const auto& tm = rig.drive().tm;
  const double row[] = {rig.board().t_s(),
                        id,
                        iq,
                        tm.id_ref_a,
                        tm.iq_ref_a,
                        rig.board().state()(2),
                        rig.omega_ref_rad_s(),
                        rig.theta_e_true(),
                        vd,
                        vq,
                        tm.fw.v_mag_v,
                        tm.fw.v_max_v,
                        static_cast<double>(rig.drive().faults),
                        rig.board().vbus_v()};
  ctx.csv.row(row, sizeof row / sizeof row[0]);
}

// Part 3: the fault at speed and what follows (see the file's comment).
void run_fault(RunContext& ctx, MotorRig& rig, long every) {
  const MotorSpec& m = ctx.files->motor;
  auto& board = rig.board();
  const double w0 = board.state()(2);
  const double vbus0 = board.vbus_v();
  mc_drive_raise_fault(&rig.drive(), MC_DRIVE_FAULT_EXTERNAL);
  const long nf = step_count(ctx.params.get("fault_s"), rig.period_s());
  double vpk = vbus0, ipk = 0, tq_min = 0;
  long asc_steps = 0;
  for (long k = 0; k < nf; ++k) {
    rig.step();
    const Eigen::Vector3d i = board.phase_currents_true_a();
    ipk = std::max(ipk, i.cwiseAbs().maxCoeff());
    vpk = std::max(vpk, board.vbus_v());
    tq_min = std::min(tq_min, board.torque_nm());
    asc_steps += rig.drive().asc_active ? 1 : 0;
    if (k % every == 0) write_row(ctx, rig);
  }
  ctx.summary.set_text("asc", rig.drive_cfg().asc_enable ? "on" : "off");
  ctx.summary.set("fault_omega_m_rad_s", w0);
  ctx.summary.set("fault_emf_over_vbus",
                  std::sqrt(3.0) * m.pole_pairs * m.flux_wb * std::abs(w0) / vbus0);
  ctx.summary.set("fault_vbus_before_v", vbus0);
  ctx.summary.set("fault_vbus_peak_v", vpk);
  ctx.summary.set("fault_vbus_trip_v", rig.drive_cfg().vbus_max_v);
  ctx.summary.set("fault_i_phase_peak_a", ipk);
  ctx.summary.set("fault_i_trip_a", rig.drive_cfg().i_trip_a);
  ctx.summary.set("fault_torque_min_nm", tq_min);
  ctx.summary.set("fault_asc_time_s", static_cast<double>(asc_steps) * rig.period_s());
  ctx.summary.set("fault_omega_end_rad_s", board.state()(2));
  ctx.summary.set("fault_first", rig.drive().first_fault);
  ctx.summary.set("fault_bits", rig.drive().faults);
  ctx.summary.set_text("fault_first_name", drive_fault_names(rig.drive().first_fault));
  ctx.summary.set_text("fault_names", drive_fault_names(rig.drive().faults));
}

void run_fw(RunContext& ctx) {
  MotorFiles f = *ctx.files;
  const bool fault = ctx.params.get("fault") > 0.5;
  if (fault) {  // part 3 on a supply that cannot sink current
    f.board.dc_link_c_f = f.board.dc_link_c_f > 0.0 ? f.board.dc_link_c_f : 1.0e-3;
    f.board.source_sink = false;
    const double isense = ctx.params.get("fault_i_sense_max_a");
    if (isense > 0.0) f.board.i_sense_max_a = isense;
  }
  const MotorSpec& m = f.motor;
  const Params& P = ctx.params;
  const Gains g = derive_gains(f, &P);
  const double T = 1.0 / f.board.pwm_hz;

  // ---- part 1: MTPA on the dyno
  double mtpa_err = 0, kt_gain = 0, id_abs_max_mtpa = 0;
  {
    MotorFiles fd = f;
    fd.motor.j_kgm2 *= 1.0 + P.get("j_load_factor");
    RigOptions o;
    o.law = Law::kCurrent;
    o.fw = true;
    MotorRig rig(fd, g, o);
    const double hold = 12.0 * std::log(9.0) / g.cur_bw_rad_s + 2e-3;
    const long nh = std::lround(hold / T);
    for (int lvl = 1; lvl <= 4; ++lvl) {
      const double icmd = 0.25 * lvl * g.i_rated_eff_a;
      if (mc_drive_set_current_ref(&rig.drive(), 0.0f, static_cast<float>(icmd)) != 0) {
        throw UsageError("current command rejected by the drive");
      }
      for (long k = 0; k < nh; ++k) rig.step();
      if (rig.drive().faults != 0u) {
        ctx.summary.set("faults", rig.drive().faults);
        ctx.summary.set_text("fault_names", drive_fault_names(rig.drive().faults));
        return write_verdict(ctx.summary,
                             faulted(rig.drive().faults, "in part 1 (MTPA on the dyno)"));
      }
      double id, iq;
      rig.board().true_dq_a(&id, &iq);
      const double I = std::hypot(id, iq);
      const double tpa = std::abs(rig.board().torque_nm()) / I;
      const double opt = mtpa_t_per_a(m, I);
      const double e = tpa / opt - 1.0;
      ctx.summary.set("mtpa_i" + std::to_string(25 * lvl) + "_rel_err", e);
      ctx.summary.set("mtpa_i" + std::to_string(25 * lvl) + "_gain_over_id0", opt / g.kt_nm_a);
      mtpa_err = std::max(mtpa_err, std::abs(e));
      kt_gain = std::max(kt_gain, tpa / g.kt_nm_a);
      id_abs_max_mtpa = std::max(id_abs_max_mtpa, std::abs(id));
    }
  }
  ctx.summary.set("mtpa_rel_err_max", mtpa_err);
  ctx.summary.set("mtpa_id_abs_max_a", id_abs_max_mtpa);
  ctx.summary.set("mtpa_t_per_a_over_kt_max", kt_gain);

  // ---- part 2: speed ramp into field weakening
  const double vbus = f.board.vbus_v;
  const double v_fw = 0.9 * vbus / std::sqrt(3.0);
  const double w_base = base_speed(m, g.i_rated_eff_a, v_fw);
  const double w_t = std::min(P.get("speed_factor") * w_base, m.speed_max_rad_s);
  const double t0 = 0.01, t_acc = w_t / g.speed_accel_rad_s2;
  const double dur = run_duration(ctx, t0 + t_acc + 40.0 / g.speed_wc_rad_s + P.get("hold_s"));
  const double t_hold = dur - P.get("hold_s");
  RigOptions o;
  o.law = Law::kSpeedPi;
  o.fw = true;
  const bool asc = P.get("asc") > 0.5;
  // A board with its own sensing for part 3 trips where that sensing ends
  // (the switches rated for it), not at 1.6x the current limit.
  const double isense = fault ? P.get("fault_i_sense_max_a") : 0.0;
  o.drive_hook = [asc, isense](mc_drive_cfg_t& c) {
    c.asc_enable = asc;
    if (isense > 0.0) c.i_trip_a = static_cast<float>(0.98 * isense);
  };
  MotorRig rig(f, g, o);
  const long n = step_count(dur, T);
  const long every =
      P.get("csv_every") > 0 ? std::lround(P.get("csv_every")) : std::max(1L, n / 20000);
  ctx.csv.columns({"t", "i_d_a", "i_q_a", "i_d_ref_a", "i_q_ref_a", "omega_m_rad_s",
                   "omega_ref_rad_s", "theta_e_rad", "v_d_v", "v_q_v", "v_mag_v", "v_max_v",
                   "fault_1", "vbus_v"});
  double i_pk = 0, w = 0, id = 0, iq = 0, v_over = -1e9, id_min = 0, werr_hold = 0;
  for (long k = 0; k <= n; ++k) {
    const double t = rig.board().t_s();
    rig.set_speed_ref(t >= t0 ? w_t : 0.0);
    rig.board().true_dq_a(&id, &iq);
    w = rig.board().state()(2);
    i_pk = std::max(i_pk, std::hypot(id, iq));
    id_min = std::min(id_min, id);
    const auto& tm = rig.drive().tm;
    if (t >= t_hold) {
      v_over = std::max(v_over, static_cast<double>(tm.fw.v_mag_v - tm.fw.v_max_v));
      werr_hold = std::max(werr_hold, std::abs(w - w_t));
    }
    if (k % every == 0) write_row(ctx, rig);
    if (rig.drive().faults != 0u) break;
    if (k < n) rig.step();
    if ((k & 1023) == 0) ctx.progress.update(t, dur);
  }
  record_setup(f, g, ctx.summary);
  const mc_drive_t& d = rig.drive();
  ctx.summary.set("faults", d.faults);
  if (d.faults != 0u) {
    ctx.summary.set_text("fault_names", drive_fault_names(d.faults));
    return write_verdict(ctx.summary, faulted(d.faults, "in part 2 (the speed ramp)"));
  }
  ctx.summary.set("base_speed_rad_s", w_base);
  ctx.summary.set("target_speed_rad_s", w_t);
  ctx.summary.set("target_over_base", w_t / w_base);
  ctx.summary.set("omega_final_rad_s", w);
  ctx.summary.set("omega_err_max_hold_rad_s", werr_hold);
  ctx.summary.set("i_peak_a", i_pk);
  ctx.summary.set("i_limit_a", g.i_limit_a);
  ctx.summary.set("id_min_a", id_min);
  ctx.summary.set("id_demag_bound_a", static_cast<double>(d.fw.id_min_a));
  ctx.summary.set("v_mag_minus_v_max_hold_max_v", v_over);
  ctx.summary.set("v_fw_max_v", v_fw);
  // Loss of control: the rectifier conducts above this speed (mc_fw.h).
  ctx.summary.set("omega_uncontrolled_gen_rad_s",
                  vbus / (std::sqrt(3.0) * m.pole_pairs * m.flux_wb));
  ctx.summary.set("short_circuit_current_a", m.flux_wb / m.ld_h);
  if (fault) run_fault(ctx, rig, every);
  FieldWeakeningFigures fig;
  fig.mtpa_rel_err_max = mtpa_err;
  fig.omega_final_rad_s = w;
  fig.target_rad_s = w_t;
  fig.i_peak_a = i_pk;
  fig.i_limit_a = g.i_limit_a;
  fig.id_min_a = id_min;
  fig.id_demag_bound_a = d.fw.id_min_a;
  fig.fault_part = fault;
  write_verdict(ctx.summary, judge_field_weakening(fig));
}

const Registrar reg_fw(
    {"field-weakening",
     "any motor: MTPA torque per ampere on a dyno against the analytic optimum, then a sensored "
     "speed ramp to 2.5x base speed (capped at speed_max) with voltage-feedback field weakening; "
     "CSV adds v_mag_v, v_max_v and vbus_v; fault=1: a fault at the top speed on a supply that "
     "cannot sink current, asc=on|off (the drive's active short circuit)",
     0.0,
     {},
     run_fw,
     fw_params});

}  // namespace
}  // namespace mcsim
