// The CSMC loop through the drive application on the simulated stepper
// board (see csmc_drive.hpp), and the csmc-drive scenario.
#include "csmc_drive.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <sstream>
#include <string>

#include "hal_host/sil_rig.hpp"
#include "hal_host/stepper_board.hpp"
#include "mc_ctrl_csmc.h"
#include "mc_drive.h"
#include "scenario.hpp"
#include "verdict.hpp"

namespace mcsim {
namespace csmc {

namespace {

// The law's model of the motor (state feedback's e2'' and the model law's
// terms): the plant's values, R and L known within +-10 % (the paper's
// +-5 % and +-14 % about its nominal), q_i by the paper's rule.
void set_model(const DriveOptions& o, mc_csmc_f32_cfg_t* law) {
  mc_csmc_f32_model_t& m = law->model;
  m.km_nm_a = static_cast<float>(o.plant.Km_nm_a);
  m.j_kgm2 = static_cast<float>(o.plant.J_kgm2);
  m.b_nms_rad = static_cast<float>(o.plant.B_nms_rad);
  m.rotor_teeth = static_cast<uint32_t>(o.plant.rotor_teeth);
  m.tau_load_nm = static_cast<float>(o.plant.tau_load_nm);
  m.r_nom_ohm = static_cast<float>(o.plant.R_ohm);
  m.r_min_ohm = static_cast<float>(0.9 * o.plant.R_ohm);
  m.r_max_ohm = static_cast<float>(1.1 * o.plant.R_ohm);
  m.l_nom_h = static_cast<float>(o.plant.L_h);
  m.l_min_h = static_cast<float>(0.9 * o.plant.L_h);
  m.l_max_h = static_cast<float>(1.1 * o.plant.L_h);
  // q_i = 2.1 k0^i mu_i L^M (paper Sec. III; k0 = 20, 100 as paper_ctrl)
  m.q1_v = static_cast<float>(2.1 * 20.0 * o.mu1_a * 1.1 * o.plant.L_h);
  m.q2_radh_s3 = static_cast<float>(2.1 * 100.0 * o.mu2_rad_s2 * 1.1 * o.plant.L_h);
}

}  // namespace

DriveResult run_drive(const DriveOptions& o) {
  std::vector<DriveSample> trace;
  DriveResult r = run_drive(o, [&trace](const DriveSample& s) { trace.push_back(s); });
  r.trace = std::move(trace);
  return r;
}

DriveResult run_drive(const DriveOptions& o,
                      const std::function<void(const DriveSample&)>& on_sample) {
  hal_host::StepperBoardConfig bc;
  bc.motor.R_ohm = o.plant.R_ohm;
  bc.motor.L_h = o.plant.L_h;
  bc.motor.Km_nm_a = o.plant.Km_nm_a;
  bc.motor.J_kgm2 = o.plant.J_kgm2;
  bc.motor.B_nms_rad = o.plant.B_nms_rad;
  bc.motor.rotor_teeth = o.plant.rotor_teeth;
  bc.motor.load = load_constant(o.plant.tau_load_nm);
  if (o.detent_nm > 0.0) {  // the detent torque: a full step's period, 4 N_r a turn
    bc.motor.load.kind = LoadKind::kAngleSpeed;
    bc.motor.load.ripple_nm = o.detent_nm;
    bc.motor.load.ripple_per_rev = 4.0 * o.plant.rotor_teeth;
  }
  bc.t_pwm_s = 1.0 / o.pwm_hz;
  bc.vbus_v = o.vbus_v;
  bc.current_sensor.full_scale_a = o.current_fs_a;
  bc.current_sensor.bits = o.adc_bits;
  bc.encoder.counts_per_rev = o.encoder_cpr;
  bc.delay_periods = o.delay_periods;
  bc.substeps = 4;
  bc.common_leg = o.common_leg;
  bc.dead_time_s = o.dead_time_s;
  hal_host::StepperBoard board(bc);

  const float dt = static_cast<float>(1.0 / o.pwm_hz);
  mc_drive_cfg_t dc{};
  // The FOC part of the drive is not used in CTRL mode, but the drive
  // validates it: a consistent current loop for this motor.
  dc.foc.r_ohm = static_cast<float>(o.plant.R_ohm);
  dc.foc.ld_h = static_cast<float>(o.plant.L_h);
  dc.foc.lq_h = static_cast<float>(o.plant.L_h);
  dc.foc.flux_wb = static_cast<float>(o.plant.Km_nm_a / o.plant.rotor_teeth);
  dc.foc.kp_d_v_per_a = 10.0f;
  dc.foc.ki_d_v_per_as = 5000.0f;
  dc.foc.kp_q_v_per_a = 10.0f;
  dc.foc.ki_q_v_per_as = 5000.0f;
  dc.foc.dt_s = dt;
  dc.foc.aw = MC_PI_AW_CLAMP;
  dc.foc.limit_mode = MC_SVPWM_LIMIT_CIRCLE;
  dc.foc.v_limit_ratio = 0.95f;
  dc.foc.v_abs_max_v = static_cast<float>(o.vbus_v);
  dc.foc.decouple = true;
  dc.pole_pairs = static_cast<uint32_t>(o.plant.rotor_teeth);  // theta_e = N_r phi
  dc.encoder_offset_rad = 0.0f;  // d axis on winding A at phi = 0 (sim model)
  dc.speed_pll_bw_rad_s = static_cast<float>(o.speed_pll_bw_rad_s);
  dc.slow_loop_div = 10u;
  dc.i_max_a = static_cast<float>(o.i_max_a);
  dc.i_trip_a = static_cast<float>(o.i_trip_a);
  dc.vbus_min_v = static_cast<float>(0.5 * o.vbus_v);
  dc.vbus_max_v = static_cast<float>(1.5 * o.vbus_v);
  dc.omega_max_rad_s = 100.0f;
  dc.temp_max_c = 100.0f;
  dc.stall_current_frac = 0.0f;  // a position loop holds torque at standstill
  dc.i_unbalance_max_a = 0.0f;
  mc_drive_t d;
  const uint32_t de = mc_drive_init(&d, &dc, board.hal());
  if (de != MC_DRIVE_CFG_OK)
    throw std::runtime_error("drive config rejected: " + std::to_string(de));

  mc_ctrl_csmc_cfg_t cc{};
  cc.law = paper_ctrl(o.model_law, true, false);
  cc.law.mu1_a = static_cast<float>(o.mu1_a);
  cc.law.mu2_rad_s2 = static_cast<float>(o.mu2_rad_s2);
  cc.law.dt_s = dt;
  cc.law.v_limit_v = static_cast<float>(o.v_limit_v > 0.0 ? o.v_limit_v : o.vbus_v);
  if (o.m1_v > 0.0) cc.law.m1_v = static_cast<float>(o.m1_v);
  if (o.m2_v > 0.0) cc.law.m2_v = static_cast<float>(o.m2_v);
  if (o.model_from_plant) set_model(o, &cc.law);
  cc.feedback = o.hgo ? MC_CTRL_CSMC_FB_HGO : MC_CTRL_CSMC_FB_STATE;
  cc.hgo = paper_hgo(o.eps_s);
  cc.hgo.dt_s = dt;
  cc.duty_max = 1.0f;
  static mc_ctrl_csmc_t ctrl;  // plug-in state outlives the drive's use of it
  const uint32_t ce = mc_ctrl_csmc_init(&ctrl, &cc);
  if (ce != MC_CTRL_CSMC_ERR_NONE) {
    throw std::runtime_error("csmc plug-in config rejected: " + std::to_string(ce));
  }
  if (mc_drive_attach_ctrl(&d, mc_ctrl_csmc_ops(&ctrl)) != 0) {
    throw std::runtime_error("drive refused the csmc plug-in");
  }
  // First fast step in IDLE to read the encoder, then CTRL.
  (void)hal_host::sil_period(board, d);
  if (mc_drive_set_mode(&d, MC_DRIVE_MODE_CTRL) != 0) {
    throw std::runtime_error("drive refused CTRL mode");
  }
  const double phi0 = board.state()(Stepper2Ph::kThetaM);
  if (mc_ctrl_csmc_set_ref(&ctrl, static_cast<float>(phi0 + o.step_rad), 0.0f, 0.0f, 0.0f, 0.0f,
                           0.0f) != MC_CTRL_CSMC_ERR_NONE) {
    throw std::runtime_error("reference rejected");
  }
  DriveResult r;
  const long n = step_count(o.duration_s, 1.0 / o.pwm_hz);
  const auto record = [&] {
    const auto& x = board.state();
    const auto& tm = ctrl.tm;
    on_sample(DriveSample{board.t_s() - bc.t_pwm_s, phi0 + o.step_rad, x(Stepper2Ph::kThetaM),
                          x(Stepper2Ph::kThetaM) - phi0 - o.step_rad, tm.i_d_a, tm.i_q_a,
                          x(Stepper2Ph::kOmegaM), tm.out.v_d_v, tm.out.v_q_v, d.tm.ctrl_out.duty2_a,
                          d.tm.ctrl_out.duty2_b, static_cast<double>(d.faults), tm.in.e2_rad,
                          tm.in.de2_rad_s, tm.in.dde2_rad_s2, tm.out.s1_a, tm.out.s2_rad_s2});
    ++r.samples;
  };
  for (long k = 0; k <= n; ++k) (void)hal_host::sil_period(board, d, hal_host::NoHook{}, record);
  r.faults = d.faults;
  r.clipped_periods = board.clipped_periods();
  r.max_request_v = board.max_request_amplitude_v();
  return r;
}

DriveOptions stepper_drive_options(const MotorFiles& f) {
  if (!f.is_stepper) throw UsageError(f.motor.file + ": csmc-drive runs a [stepper] file");
  const StepperSpec& m = f.stepper;
  const BoardSpec& b = f.board;
  DriveOptions o;
  o.plant.R_ohm = m.r_ohm;
  o.plant.L_h = m.l_h;
  o.plant.Km_nm_a = m.km_nm_a;
  o.plant.J_kgm2 = m.j_kgm2;
  o.plant.B_nms_rad = m.b_nm_s_rad;
  o.plant.rotor_teeth = m.rotor_teeth;
  o.plant.tau_load_nm = kLoadFrac * m.rated_torque_nm();
  o.detent_nm = m.detent_nm;
  o.pwm_hz = b.pwm_hz;
  o.vbus_v = b.vbus_v;
  o.dead_time_s = b.dead_time_s;
  o.encoder_cpr = static_cast<int>(b.encoder_cpr);
  o.current_fs_a = b.adc_full_scale_a();
  o.adc_bits = b.adc_bits;
  o.delay_periods = b.delay_periods;
  o.common_leg = true;
  o.model_from_plant = true;
  o.i_max_a = 1.5 * m.i_rated_a;
  o.i_trip_a = 2.0 * m.i_rated_a;
  o.v_limit_v = 0.5 * b.vbus_v;  // per axis: |(u_d, u_q)| <= vbus / sqrt(2)
  o.m1_v = o.v_limit_v;
  o.m2_v = o.v_limit_v;
  const double t = 1.0 / b.pwm_hz;
  o.mu1_a = o.m1_v * t / (m.l_h * kLayerGain);
  o.mu2_rad_s2 = o.m2_v * t * m.km_nm_a / (m.j_kgm2 * m.l_h * kLayerGain);
  const std::string who = "csmc-drive: " + m.file + " on " + b.name + ": ";
  std::ostringstream os;
  if (b.encoder_cpr == 0) throw UsageError(who + "the board has no encoder (encoder_cpr 0)");
  const mc_csmc_f32_cfg_t paper = paper_ctrl(false, true, false);
  const double need = m.j_kgm2 * paper.k1_per_s2 * o.step_rad + o.plant.tau_load_nm + m.detent_nm;
  if (need > m.rated_torque_nm()) {
    os << who << "the paper's step with its k1 = " << paper.k1_per_s2 << " 1/s^2 needs J k1 step"
       << " + load + detent = " << need
       << " N m, above the rated torque Km i_rated = " << m.rated_torque_nm()
       << " N m: refused (the surfaces' gains are the paper's)";
    throw UsageError(os.str());
  }
  if (o.m1_v < 2.0 * m.r_ohm * m.i_rated_a) {
    os << who << "M = vbus / 2 = " << o.m1_v << " V (the common leg's limit per axis) is below "
       << "2 R i_rated = " << 2.0 * m.r_ohm * m.i_rated_a
       << " V: no margin over the rated current's drop, refused";
    throw UsageError(os.str());
  }
  // One count of the current converter moves the state feedback's e2''
  // (K_m i_q / J) by (K_m / J) i_count; against the k1 step the surface
  // asks at the step's start, more than kMaxCountRatio of it limit-cycles.
  const double i_count = 2.0 * b.adc_full_scale_a() / std::pow(2.0, b.adc_bits);
  const double ratio = m.km_nm_a / m.j_kgm2 * i_count / (paper.k1_per_s2 * o.step_rad);
  if (ratio > kMaxCountRatio) {
    os << who << "current resolution: one count (" << i_count
       << " A) is (K_m / J) i_count = " << m.km_nm_a / m.j_kgm2 * i_count
       << " rad/s^2 of the state feedback's e2'', " << ratio << " times k1 step (at most "
       << kMaxCountRatio << "): refused";
    throw UsageError(os.str());
  }
  if (o.i_trip_a > b.i_sense_max_a) {
    os << who << "the trip at 2 i_rated = " << o.i_trip_a << " A is beyond the board's current "
       << "range " << b.i_sense_max_a << " A: refused";
    throw UsageError(os.str());
  }
  return o;
}

namespace {

constexpr double kPi = 3.14159265358979323846;
// csmc-drive with a motor: the run's length, and the verdict's bounds
// (measured figures and reasons in tests/sil/csmc, sim/README.md).
constexpr double kMotorRunS = 0.3;
constexpr double kMotorSettleS = 0.1;

// What a run of the loop measured (the CSV written as it runs).
struct Figures {
  DriveResult r;
  double over = 0.0;      // largest e2 (past the target) [rad]
  double last_out = 0.0;  // last time |e2| > band [s]
  double emax = 0.0;      // max |e2| in the last win [s]
  long changes = 0;       // v_q sign changes in the last win
};

// Runs o, writing the CSV (about 5000 rows and the last); band: the
// settling band [rad]; win: the steady-state window at the end [s].
Figures run_figures(RunContext& ctx, const DriveOptions& o, double band, double win) {
  ctx.csv.columns({"t", "phi_d_rad", "x4_rad", "e2_rad", "x1_a", "x2_a", "x3_rad_s", "u1_v", "u2_v",
                   "duty2_a_1", "duty2_b_1", "fault_1", "e2_meas_rad", "de2_meas_rad_s",
                   "dde2_meas_rad_s2", "s1_a", "s2_rad_s2"});
  // One sample per period from the fast step before the loop's first
  // period to the last: n + 1 of them; about 5000 rows and the last.
  const long n_samples = step_count(o.duration_s, 1.0 / o.pwm_hz) + 1;
  const long every = std::max(1L, n_samples / 5000);
  // The last window (plus a period) kept for the steady-state figures,
  // whose start is known only at the end (the last sample's time).
  const size_t keep = static_cast<size_t>(std::ceil(win * o.pwm_hz)) + 2;
  std::vector<DriveSample> tail(keep);
  long k = 0;
  Figures f;
  f.r = run_drive(o, [&](const DriveSample& s) {
    if (k % every == 0 || k + 1 == n_samples) {
      ctx.csv.row({s.t, s.phi_d, s.phi, s.e2, s.i_d, s.i_q, s.w, s.v_d, s.v_q, s.duty_a, s.duty_b,
                   s.fault, s.e2_meas, s.de2_meas, s.dde2_meas, s.s1, s.s2});
    }
    f.over = std::max(f.over, s.e2);
    if (std::abs(s.e2) > band) f.last_out = s.t;
    tail[static_cast<size_t>(k) % keep] = s;
    ++k;
  });
  double prev = 0.0;
  const long first = std::max(0L, k - static_cast<long>(keep));
  const double t_end = tail[static_cast<size_t>(k - 1) % keep].t;
  for (long i = first; i < k; ++i) {
    const DriveSample& s = tail[static_cast<size_t>(i) % keep];
    if (s.t >= t_end - win) {
      f.emax = std::max(f.emax, std::abs(s.e2));
      if ((s.v_q > 0.0 && prev < 0.0) || (s.v_q < 0.0 && prev > 0.0)) ++f.changes;
      if (s.v_q != 0.0) prev = s.v_q;
    }
  }
  ctx.summary.set("faults", static_cast<double>(f.r.faults));
  ctx.summary.set_text("fault_names", drive_fault_names(f.r.faults));
  ctx.summary.set("overshoot_pct", 100.0 * f.over / o.step_rad);
  ctx.summary.set("settling_2pct_s", f.last_out);
  ctx.summary.set("e2_ss_max_abs_rad", f.emax);
  ctx.summary.set("vq_sign_changes_per_s", static_cast<double>(f.changes) / win);
  return f;
}

// csmc-drive (tests/sil/csmc DrivePluginRegulatesTheStepperOnTheSimulated-
// Board): no fault; in the last 0.1 s the position error stays within 2
// encoder counts (the measurement's resolution) without v_q sign changes
// (no chattering); the step overshoots by less than 2 % and settles (2 %)
// within 0.06 s. The window needs 0.1 s after that: a run of 0.16 s.
void run_paper_scenario(RunContext& ctx) {
  DriveOptions o;
  o.duration_s = ctx.duration_s;
  o.plant.R_ohm = 19.5;
  o.plant.L_h = 0.030;
  o.pwm_hz = ctx.params.get("pwm_hz");
  o.hgo = ctx.params.get("hgo") != 0.0;
  o.eps_s = ctx.params.get("eps_s");
  o.encoder_cpr = static_cast<int>(ctx.params.get("encoder_cpr"));
  o.delay_periods = static_cast<int>(ctx.params.get("delay_periods"));
  o.mu1_a = ctx.params.get("mu1_a");
  o.mu2_rad_s2 = ctx.params.get("mu2_rad_s2");
  const double win = 0.1;
  const Figures f = run_figures(ctx, o, 0.02 * o.step_rad, win);
  if (f.r.faults != 0u) return write_verdict(ctx.summary, faulted(f.r.faults));
  Judge j;
  j.at_least("too short to judge", "duration [s]", o.duration_s, 0.16,
             "0.06 s to settle + the 0.1 s window");
  j.at_most("steady-state error", "|e2| in the last 0.1 s [rad]", f.emax,
            2.0 * 2.0 * kPi / o.encoder_cpr, "2 encoder counts");
  j.at_most("chattering", "v_q sign changes in the last 0.1 s [1/s]",
            static_cast<double>(f.changes) / win, 0.0);
  j.at_most("overshoot", "overshoot / step", f.over / o.step_rad, 0.02);
  j.at_most("not settled", "2 % settling time [s]", f.last_out, 0.06);
  write_verdict(ctx.summary, j.verdict());
}

// The paper's state feedback takes e2'' from the currents through its
// model, which has no detent torque: at rest it sees e2'' = tau_det / J and
// its conditional integrator zeroes k1 e2 + e2'' (e2' = 0), so the rotor can
// rest where J k1 e2 = -tau_det(phi), up to detent / (J k1) from the target.
// Beyond the settling band the run is refused (named); --set detent=0 runs
// the plant without it (the paper's eq. (1) has none).
void check_detent(const MotorFiles& f, const DriveOptions& o, double band) {
  if (o.hgo || o.detent_nm <= 0.0) return;
  const mc_csmc_f32_cfg_t paper = paper_ctrl(false, true, false);
  const double e_rest = o.detent_nm / (o.plant.J_kgm2 * paper.k1_per_s2);
  if (e_rest <= band) return;
  std::ostringstream os;
  os << "csmc-drive: " << f.stepper.file << ": detent: the state feedback's model has no "
     << "detent torque; the rotor may rest up to detent / (J k1) = " << e_rest
     << " rad from the target, beyond the settling band " << band
     << " rad (refused; --set detent=0 runs the plant without the detent torque, as the "
     << "paper's eq. (1))";
  throw UsageError(os.str());
}

// csmc-drive --motor STEPPER --board B: the derived settings
// (stepper_drive_options), the verdict's bounds in sim/README.md.
void run_motor_scenario(RunContext& ctx) {
  DriveOptions o = stepper_drive_options(*ctx.files);
  o.duration_s = run_duration(ctx, kMotorRunS);
  o.hgo = ctx.params.get("hgo") != 0.0;
  o.eps_s = ctx.params.get("eps_s");
  o.mu1_a = ctx.params.get("mu1_a");
  o.mu2_rad_s2 = ctx.params.get("mu2_rad_s2");
  const double count = 2.0 * kPi / o.encoder_cpr;
  // The settling band: 2 % of the step, but not below 2 counts (the loop
  // regulates the counted angle: the true one may sit a count off).
  const double band = std::max(0.02 * o.step_rad, 2.0 * count);
  if (ctx.params.get("detent") == 0.0) o.detent_nm = 0.0;
  check_detent(*ctx.files, o, band);
  const double win = 0.1;
  const Figures f = run_figures(ctx, o, band, win);
  const double v_lim = o.vbus_v / std::sqrt(2.0);
  ctx.summary.set("settling_band_rad", band);
  ctx.summary.set("v_request_max_v", f.r.max_request_v);
  ctx.summary.set("v_common_leg_limit_v", v_lim);
  ctx.summary.set("clipped_periods", static_cast<double>(f.r.clipped_periods));
  ctx.summary.set("m_v", o.m1_v);
  ctx.summary.set("tau_load_nm", o.plant.tau_load_nm);
  if (f.r.faults != 0u) return write_verdict(ctx.summary, faulted(f.r.faults));
  Judge j;
  j.at_least("too short to judge", "duration [s]", o.duration_s, kMotorSettleS + win,
             "the settling bound + the 0.1 s window");
  j.at_most("chattering", "v_q sign changes in the last 0.1 s [1/s]",
            static_cast<double>(f.changes) / win, 0.05 * o.pwm_hz,
            "5 % of the PWM rate: the ideal SMC switches about every period, the counts' dither "
            "far less");
  j.at_most("steady-state error", "|e2| in the last 0.1 s [rad]", f.emax, 2.0 * count,
            "2 encoder counts");
  j.at_most("overshoot", "overshoot / step", f.over / o.step_rad, band / o.step_rad + 0.02,
            "the settling band + 2 %: the loop regulates the counted angle");
  j.at_most("not settled", "settling time into the band [s]", f.last_out, kMotorSettleS);
  j.at_most("beyond the common leg's limit", "largest |(v_a, v_b)| asked [V]", f.r.max_request_v,
            v_lim, "vbus / sqrt(2), every angle");
  j.at_most("clipped", "periods asking outside the hexagon",
            static_cast<double>(f.r.clipped_periods), 0.0);
  write_verdict(ctx.summary, j.verdict());
}

void run_drive_scenario(RunContext& ctx) {
  if (ctx.files != nullptr) return run_motor_scenario(ctx);
  run_paper_scenario(ctx);
}

// The scenario's parameters for a stepper file: the layers derived for it.
std::vector<ParamSpec> motor_params(const MotorFiles& files) {
  const DriveOptions o = stepper_drive_options(files);
  return {
      {"hgo", 0.0, "-", "1: output feedback (high-gain observer), 0: state feedback", 0.0, 1.0},
      {"detent", 1.0, "-", "1: the file's detent torque in the plant, 0: none (the paper's plant)",
       0.0, 1.0},
      {"eps_s", 1.0e-3, "s", "observer eps (hgo = 1)", 1.0e-5, 1.0e-1},
      {"mu1_a", o.mu1_a, "A", "boundary layer of s1 (derived: gain 0.3 a period)", 1.0e-3, 100.0},
      {"mu2_rad_s2", o.mu2_rad_s2, "rad/s^2", "boundary layer of s2 (derived: gain 0.3 a period)",
       1.0, 1.0e8}};
}

const Registrar reg_drive(
    {"csmc-drive",
     "The CSMC stepper position loop through the firmware path: drive application in CTRL mode "
     "with the mc_ctrl_csmc plug-in on the simulated dual-H-bridge board (12-bit currents, "
     "encoder, one-period delay); phi_d step of 0.03142 rad, 0.2 N m load. --motor STEPPER "
     "--board B: a [stepper] file on the board's three legs with a common one, the settings "
     "derived for it (sim/README.md)",
     0.4,
     {{"pwm_hz", 10.0e3, "Hz", "fast-loop rate", 5.0e3, 100.0e3},
      {"hgo", 0.0, "-", "1: output feedback (high-gain observer), 0: state feedback", 0.0, 1.0},
      {"eps_s", 1.0e-3, "s", "observer eps (hgo = 1)", 1.0e-5, 1.0e-1},
      {"encoder_cpr", 262144.0, "counts", "encoder counts per revolution", 1000.0, 16777216.0},
      {"delay_periods", 1.0, "-", "computation delay", 0.0, 4.0},
      {"mu1_a", 0.5, "A", "boundary layer of s1 (paper 0.1; see csmc_drive.hpp)", 1.0e-3, 10.0},
      {"mu2_rad_s2", 200.0, "rad/s^2", "boundary layer of s2 (paper 50)", 1.0, 1.0e4}},
     run_drive_scenario,
     motor_params,
     /*takes_flash=*/false,
     /*motor_optional=*/true,
     /*takes_duration=*/true,
     /*takes_pil=*/false,
     /*takes_stepper=*/true});

}  // namespace
}  // namespace csmc
}  // namespace mcsim
