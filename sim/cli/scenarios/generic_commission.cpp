// Commissioning on the kernel-level rig (the drive alone with the
// commissioning plug-in, the tests of tests/sil/commission) and the plant's
// side shared with the `commission` scenario (commission.cpp, which runs the
// drive application's commissioning over CAN).
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

}  // namespace

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

namespace {

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

}  // namespace mcsim
