// The `commission` scenario: the drive, knowing only the board, measures
// the motor of a file (firmware/app/commission/README.md), then (verify=1)
// runs a sensored and a sensorless speed step on the identified values.
#include "generic_commission.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "hal_host/sil_rig.hpp"
#include "scenario.hpp"
#include "verdict.hpp"

namespace mcsim {
namespace {

constexpr double kPi = 3.14159265358979323846;

double wrap2pi(double x) {
  x = std::fmod(x, 2 * kPi);
  return x < 0 ? x + 2 * kPi : x;
}

void set_adc_offsets(const CommissionSetup& s, double out[3]) {
  out[0] = s.adc_offset_a;
  out[1] = -0.7 * s.adc_offset_a;
  out[2] = 0.4 * s.adc_offset_a;
}

void configure_plant(const MotorFiles& f, const CommissionSetup& s, hal_host::PmsmBoardConfig& bc) {
  bc.current_sensor.noise_rms_a = s.noise_rms_a;
  bc.current_sensor.seed = s.seed;
  bc.encoder.direction = s.encoder_direction;
  // An incremental encoder's offset is the shaft angle at power-up.
  bc.theta_m0_rad = s.encoder_offset_rad / f.motor.pole_pairs;
}

// The electrical offset the firmware's formula needs for this plant: the
// counter is floor(x) - floor(x0), x = dir theta cpr / 2 pi, so on average
// the count lags x - x0 by 1/2 - frac(x0) counts.
double true_offset(const MotorFiles& f, const CommissionSetup& s,
                   const hal_host::PmsmBoardConfig& bc) {
  const double cpr = bc.encoder.counts_per_rev, step = 2 * kPi / cpr, p = f.motor.pole_pairs;
  const double th0 = bc.theta_m0_rad, dir = s.encoder_direction;
  const double x0 = dir * th0 * cpr / (2 * kPi);
  return wrap2pi(p * (th0 - dir * (x0 - std::floor(x0) - 0.5) * step));
}

// The drive with placeholder motor values (what an image knows before
// commissioning): only the board's limits are real.
mc_drive_cfg_t board_only_drive_cfg(const MotorFiles& f) {
  const BoardSpec& b = f.board;
  mc_drive_cfg_t dc{};
  const double T = 1.0 / b.pwm_hz, bw = 0.08 / T;
  float kp = 0, ki = 0;
  (void)mc_foc_f32_gains_from_bandwidth(0.1f, 1e-4f, static_cast<float>(bw), &kp, &ki);
  dc.foc.kp_d_v_per_a = dc.foc.kp_q_v_per_a = kp;
  dc.foc.ki_d_v_per_as = dc.foc.ki_q_v_per_as = ki;
  dc.foc.r_ohm = 0.1f;
  dc.foc.ld_h = dc.foc.lq_h = 1e-4f;
  dc.foc.flux_wb = 0.01f;
  dc.foc.dt_s = static_cast<float>(T);
  dc.foc.aw = MC_PI_AW_CLAMP;
  dc.foc.limit_mode = MC_SVPWM_LIMIT_CIRCLE;
  dc.foc.v_limit_ratio = 0.95f;
  dc.foc.v_abs_max_v = static_cast<float>(1.5 * b.vbus_v);
  dc.foc.decouple = true;
  dc.pole_pairs = 1;
  dc.speed_pll_bw_rad_s = static_cast<float>(std::min(1000.0, 0.1 / T));
  dc.slow_loop_div = static_cast<uint32_t>(std::max(1.0, std::round(b.pwm_hz / 1000.0)));
  dc.i_max_a = static_cast<float>(b.i_sense_max_a / 1.25);
  dc.i_trip_a = static_cast<float>(0.98 * b.i_sense_max_a);
  dc.vbus_min_v = static_cast<float>(0.5 * b.vbus_v);
  dc.vbus_max_v = static_cast<float>(1.5 * b.vbus_v);
  dc.omega_max_rad_s = 0.0f;  // unknown motor: commissioning caps its own speed
  dc.temp_max_c = 100.0f;
  dc.i_unbalance_max_a = b.current_sensors == 3 ? static_cast<float>(0.03 * b.i_sense_max_a) : 0.0f;
  return dc;
}

}  // namespace

CommissionSetup default_commission_setup(const MotorFiles& f) {
  CommissionSetup s;
  s.adc_offset_a = 0.01 * f.board.i_sense_max_a;
  s.noise_rms_a = 0.001 * f.board.i_sense_max_a;
  return s;
}

std::string commission_error_names(uint32_t e) {
  static const char* const names[] = {
      "OFFSET",        "NO_MOTOR",        "OPEN_PHASE",  "ENCODER_NO_MOTION",
      "ROTOR_BLOCKED", "WRONG_DIRECTION", "ENCODER_BAD", "OVERCURRENT",
      "VOLTAGE",       "RANGE",           "MEAS",        "ABORTED"};
  std::string s;
  for (int i = 0; i < 12; ++i) {
    if (e & (1u << i)) s += (s.empty() ? "" : "|") + std::string(names[i]);
  }
  return s;
}

CommissionRun run_commission(const MotorFiles& f, const CommissionSetup& s) {
  if (f.board.encoder_cpr == 0) {
    throw UsageError(f.board.file + ": commissioning needs an encoder (encoder_cpr = 0)");
  }
  const BoardSpec& b = f.board;
  hal_host::PmsmBoardConfig bc = build_board_cfg(f);
  configure_plant(f, s, bc);
  hal_host::PmsmBoard board(bc);
  hal_host::PmsmBoard::Injection inj;
  set_adc_offsets(s, inj.offset_a);
  board.inject(inj);
  if (s.inject) s.inject(board);

  CommissionRun run;
  run.true_encoder_offset_rad = true_offset(f, s, bc);
  run.true_encoder_direction = s.encoder_direction;
  set_adc_offsets(s, run.true_adc_offset_a);
  if (b.current_sensors != 3) run.true_adc_offset_a[2] = 0.0;

  mc_drive_cfg_t dc = board_only_drive_cfg(f);
  mc_drive_t drive{};
  if (mc_drive_init(&drive, &dc, board.hal()) != MC_DRIVE_CFG_OK) {
    throw std::runtime_error("the board-only drive configuration was refused");
  }
  const double T = 1.0 / b.pwm_hz;
  mc_comm_cfg_t cc{};
  cc.dt_s = static_cast<float>(T);
  cc.i_test_a = static_cast<float>(s.i_test_a > 0 ? s.i_test_a : 0.25 * b.i_sense_max_a);
  cc.v_test_max_v = static_cast<float>(0.9 * b.vbus_v / std::sqrt(3.0));
  cc.offset_max_a = static_cast<float>(0.1 * b.i_sense_max_a);
  cc.dead_time_s = static_cast<float>(b.dead_time_s);
  cc.cur_bw_rad_s = static_cast<float>(0.08 / T);  // drive_setup's cur_bw_rad_s
  cc.speed_max_m_rad_s = 1.0e4f;
  cc.bemf_frac = 0.5f;
  cc.pole_pairs_max = 32;
  cc.three_shunts = (b.current_sensors == 3);
  static mc_comm_t comm;  // large; one run at a time
  if (mc_comm_init(&comm, &cc) != MC_COMM_CFG_OK) {
    throw UsageError("commissioning refused its configuration for this board");
  }
  if (mc_drive_attach_ctrl(&drive, mc_comm_ops(&comm)) != 0 ||
      mc_drive_set_mode(&drive, MC_DRIVE_MODE_CTRL) != 0) {
    throw std::runtime_error("the drive refused the commissioning plug-in");
  }
  const long n_max = std::lround(s.t_max_s / T);
  long k = 0;
  for (; k < n_max; ++k) {
    hal_host::sil_period(board, drive);
    if (s.each_period) s.each_period(board, comm);
    if (drive.mode == MC_DRIVE_MODE_FAULT || mc_comm_done(&comm)) break;
  }
  run.duration_s = static_cast<double>(k + 1) * T;
  run.done = mc_comm_done(&comm);
  run.err = comm.err;
  if (!run.done && run.err == 0u) run.err = MC_COMM_ERR_ABORTED;  // timed out
  run.drive_faults = drive.faults;
  if (run.done) {
    mc_drive_set_mode(&drive, MC_DRIVE_MODE_IDLE);
    run.res = comm.res;
  }
  run.bridge_off = !board.pwm_enabled();
  return run;
}

MotorSpec identified_motor(const MotorSpec& truth, const mc_comm_result_t& r) {
  MotorSpec m = truth;
  m.r_ohm = r.r_ohm;
  m.ld_h = r.ld_h;
  m.lq_h = r.lq_h;
  m.flux_wb = r.flux_wb;
  m.pole_pairs = static_cast<int>(r.pole_pairs);
  if (r.valid & MC_COMM_HAVE_MECH) {
    m.j_kgm2 = r.j_kgm2;
    m.b_nm_s_rad = r.b_nm_s_rad;
  }
  return m;
}

double verify_speed_step(const MotorFiles& f, const CommissionSetup& s, const CommissionRun& run,
                         Law law, double* p_target) {
  MotorFiles fi = f;
  fi.motor = identified_motor(f.motor, run.res);
  const Gains g = derive_gains(fi, nullptr);  // the same formulas, identified values
  RigOptions o;
  o.law = law;
  o.drive_motor = &fi.motor;
  o.board_hook = [&](hal_host::PmsmBoardConfig& bc) {
    configure_plant(f, s, bc);
    // The sensorless run starts the rotor at sensorless_start_theta_e_rad
    // (default 0): the I-f start holds the current at two angles and
    // restarts its observer from the flux path's circle fit
    // (mc_ctrl_sls_cfg_t.align_any_angle), so any start angle works
    // (tests/sil/commission SensorlessStartAngle); the encoder is not used.
    if (law == Law::kSensorless) {
      bc.theta_m0_rad = s.sensorless_start_theta_e_rad / f.motor.pole_pairs;
    }
  };
  o.board_built_hook = [&](hal_host::PmsmBoard& bd) {
    hal_host::PmsmBoard::Injection inj;
    set_adc_offsets(s, inj.offset_a);
    bd.inject(inj);
  };
  const mc_comm_result_t res = run.res;
  const float bw = static_cast<float>(g.cur_bw_rad_s);
  o.drive_hook = [res, bw](mc_drive_cfg_t& dc) {
    if (mc_comm_apply(&res, bw, &dc) != 0u) throw std::runtime_error("result refused by apply");
  };
  MotorRig rig(f, g, o);
  const double w_t = 0.5 * g.speed_rated_eff_rad_s;
  *p_target = w_t;
  rig.set_speed_ref(w_t);
  const double wc = law == Law::kSensorless ? g.sls_wc_rad_s : g.speed_wc_rad_s;
  double t_end = std::abs(w_t) / (0.5 * g.torque_rated_nm / f.motor.j_kgm2) + 40.0 / wc + 0.1;
  if (law == Law::kSensorless) t_end += g.align_time_s + g.handover_rad_s / g.if_accel_rad_s2 + 0.1;
  const long n = std::lround(t_end / rig.period_s());
  for (long k = 0; k < n; ++k) {
    rig.step();
    if (rig.drive().faults != 0u) return std::nan("");
  }
  return std::abs(rig.board().state()(2) - w_t) / std::abs(w_t);
}

namespace {

std::vector<ParamSpec> commission_params(const MotorFiles& f) {
  const CommissionSetup d = default_commission_setup(f);
  return {
      {"encoder_offset_rad", d.encoder_offset_rad, "rad",
       "plant: electrical angle of the d axis at encoder count 0", -100.0, 100.0},
      {"encoder_direction", 1.0, "1", "plant: encoder counting direction (+1 or -1)", -1.0, 1.0},
      {"adc_offset_a", d.adc_offset_a, "A",
       "plant: current-sensor offsets (x, -0.7 x, 0.4 x) on phases a, b, c", -1e4, 1e4},
      {"noise_rms_a", d.noise_rms_a, "A", "plant: current-sensor noise per channel", 0.0, 1e4},
      {"i_test_a", 0.25 * f.board.i_sense_max_a, "A", "commissioning test current", 1e-6, 1e6},
      {"verify", 0.0, "1",
       "1: then run sensored and sensorless speed steps on the identified "
       "values",
       0.0, 1.0},
      {"verify_sensorless_theta_e_rad", 0.0, "rad",
       "verify=1: the rotor's electrical angle when the sensorless run starts", -100.0, 100.0},
      {"seed", 1.0, "1", "plant: current-noise generator seed", 0.0, 4294967295.0},
  };
}

void run_commission_scenario(RunContext& ctx) {
  const MotorFiles& f = *ctx.files;
  CommissionSetup s = default_commission_setup(f);
  s.encoder_offset_rad = ctx.params.get("encoder_offset_rad");
  s.encoder_direction = ctx.params.get("encoder_direction") < 0 ? -1 : 1;
  s.adc_offset_a = ctx.params.get("adc_offset_a");
  s.noise_rms_a = ctx.params.get("noise_rms_a");
  s.i_test_a = ctx.params.get("i_test_a");
  s.seed = static_cast<std::uint64_t>(ctx.params.get("seed"));
  s.sensorless_start_theta_e_rad = ctx.params.get("verify_sensorless_theta_e_rad");
  const CommissionRun run = run_commission(f, s);
  const mc_comm_result_t& r = run.res;
  ctx.summary.set("duration_s", run.duration_s);
  ctx.summary.set("error_bits", run.err);
  ctx.summary.set_text("fault", run.err ? commission_error_names(run.err) : "");
  ctx.summary.set_text("motor", f.motor.name);
  ctx.summary.set_text("board", f.board.name);
  ctx.csv.columns({"t", "done"});
  const double row[2] = {run.duration_s, run.done ? 1.0 : 0.0};
  ctx.csv.row(row, 2);
  ctx.summary.set_object("true", {{"r_ohm", f.motor.r_ohm},
                                  {"ld_h", f.motor.ld_h},
                                  {"lq_h", f.motor.lq_h},
                                  {"flux_wb", f.motor.flux_wb},
                                  {"pole_pairs", f.motor.pole_pairs},
                                  {"encoder_offset_rad", run.true_encoder_offset_rad},
                                  {"encoder_direction", run.true_encoder_direction},
                                  {"adc_offset_a_a", run.true_adc_offset_a[0]},
                                  {"adc_offset_b_a", run.true_adc_offset_a[1]},
                                  {"adc_offset_c_a", run.true_adc_offset_a[2]},
                                  {"j_kgm2", f.motor.j_kgm2},
                                  {"b_nm_s_rad", f.motor.b_nm_s_rad}});
  CommissionFigures fig;
  fig.duration_s = run.duration_s;
  fig.error_names = commission_error_names(run.err);
  if (!run.done) return write_verdict(ctx.summary, judge_commission(fig));
  std::map<std::string, double> id = {{"r_ohm", r.r_ohm},
                                      {"ld_h", r.ld_h},
                                      {"lq_h", r.lq_h},
                                      {"flux_wb", r.flux_wb},
                                      {"pole_pairs", r.pole_pairs},
                                      {"encoder_offset_rad", r.encoder_offset_rad},
                                      {"encoder_direction", r.encoder_direction},
                                      {"adc_offset_a_a", r.adc_offset_a[0]},
                                      {"adc_offset_b_a", r.adc_offset_a[1]},
                                      {"adc_offset_c_a", r.adc_offset_a[2]},
                                      {"dead_time_v", r.dead_time_v},
                                      {"saliency", r.lq_h / r.ld_h}};
  if (r.valid & MC_COMM_HAVE_MECH) {
    id["j_kgm2"] = r.j_kgm2;
    id["b_nm_s_rad"] = r.b_nm_s_rad;
  }
  ctx.summary.set_object("identified", id);
  const double e_off = std::remainder(r.encoder_offset_rad - run.true_encoder_offset_rad, 2 * kPi);
  double e_adc = 0;  // the largest current-sensor offset error
  for (int k = 0; k < 3; ++k) {
    e_adc = std::max(e_adc, std::abs(r.adc_offset_a[k] - run.true_adc_offset_a[k]));
  }
  ctx.summary.set_object(
      "error", {{"r_frac", r.r_ohm / f.motor.r_ohm - 1},
                {"ld_frac", r.ld_h / f.motor.ld_h - 1},
                {"lq_frac", r.lq_h / f.motor.lq_h - 1},
                {"flux_frac", r.flux_wb / f.motor.flux_wb - 1},
                {"encoder_offset_deg", e_off * 180 / kPi},
                {"pole_pairs_diff", static_cast<double>(r.pole_pairs) - f.motor.pole_pairs},
                {"direction_wrong", r.encoder_direction == run.true_encoder_direction ? 0.0 : 1.0},
                {"adc_offset_max_a", e_adc},
                {"adc_offset_max_frac", e_adc / f.board.i_sense_max_a}});
  if (ctx.params.get("verify") > 0.5) {
    // verify.LAW_faulted: 1 if the drive faulted on the way (the error is
    // then NaN), 0 if not. A law that refuses this motor (the sensorless
    // law takes no salient machine; either law a pair without safe gains)
    // leaves its error NaN, no _faulted, and
    // says why; commissioning itself succeeded, so the run does not fail.
    double w = 0;
    const auto verify = [&](Law law, const char* name) {
      try {
        const double e = verify_speed_step(f, s, run, law, &w);
        ctx.summary.set(std::string("verify.") + name + "_speed_err_frac", e);
        ctx.summary.set(std::string("verify.") + name + "_faulted", std::isnan(e) ? 1.0 : 0.0);
      } catch (const UsageError& e) {
        ctx.summary.set(std::string("verify.") + name + "_speed_err_frac", std::nan(""));
        ctx.summary.set_text(std::string("verify.") + name + "_refused", e.what());
        if (law == Law::kSensorless) {
          fig.sensorless_refused = true;
        } else {
          fig.sensored_refused = true;  // no safe gains for this motor and board
        }
      }
    };
    verify(Law::kSpeedPi, "sensored");
    verify(Law::kSensorless, "sensorless");
    ctx.summary.set("verify.speed_target_rad_s", w);
  }
  const auto& n = ctx.summary.numbers();
  fig.done = true;
  fig.r_frac = r.r_ohm / f.motor.r_ohm - 1;
  fig.ld_frac = r.ld_h / f.motor.ld_h - 1;
  fig.lq_frac = r.lq_h / f.motor.lq_h - 1;
  fig.flux_frac = r.flux_wb / f.motor.flux_wb - 1;
  fig.pole_pairs_diff = static_cast<double>(r.pole_pairs) - f.motor.pole_pairs;
  fig.encoder_offset_deg = e_off * 180 / kPi;
  fig.adc_offset_max_frac = e_adc / f.board.i_sense_max_a;
  fig.direction_right = r.encoder_direction == run.true_encoder_direction;
  fig.verify = ctx.params.get("verify") > 0.5;
  if (fig.verify) {
    fig.verify_sensored_err_frac = n.at("verify.sensored_speed_err_frac");
    fig.verify_sensorless_err_frac = n.at("verify.sensorless_speed_err_frac");
  }
  write_verdict(ctx.summary, judge_commission(fig));
}

const Registrar reg_commission(
    {"commission",
     "any motor: the drive, knowing only the board, measures current-sensor offsets, R, Ld, "
     "Lq, pole pairs, encoder direction and offset, flux (and J, B); JSON with 'identified' and "
     "'true'; verify=1 then runs speed steps on the identified values",
     0.0,
     {},
     run_commission_scenario,
     commission_params,
     /*takes_flash=*/false,
     /*motor_optional=*/false,
     /*takes_duration=*/false});

}  // namespace
}  // namespace mcsim
