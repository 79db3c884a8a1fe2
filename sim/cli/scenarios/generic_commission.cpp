// Commissioning in the loop over CAN (see generic_commission.hpp): one run
// for the `commission` scenario (commission.cpp) and the SIL tests
// (tests/sil/commission).
#include "generic_commission.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include "app_params.hpp"
#include "app_scenario.hpp"
#include "board_hall.hpp"
#include "plant_from_files.hpp"
#include "scenario.hpp"
extern "C" {
#include "commission/mc_comm_can.h"
#include "config/mc_law_cfg.h"
}

namespace mcsim {
namespace {

constexpr double kPi = 3.14159265358979323846;

double wrap2pi(double x) {
  x = std::fmod(x, 2 * kPi);
  return x < 0 ? x + 2 * kPi : x;
}

// What the host learns from the application's commissioning frames.
struct CommissionFrames {
  bool ended = false;  // DONE with every result, or FAILED
  bool done = false;
  uint32_t err = 0, valid = 0, step = 0, detail = 0;
  double t_end_s = 0;
  std::array<float, MC_COMM_CAN_ITEM_COUNT> value{};
  uint32_t have = 0;  // bit per item received
  // COMMISSION_STATUS and COMMISSION_RESULT among the frames of a period.
  void take(const std::vector<mc_hal_can_frame_t>& frames, double t);
};

void CommissionFrames::take(const std::vector<mc_hal_can_frame_t>& frames, double t) {
  for (const mc_hal_can_frame_t& f : frames) {
    const uint32_t cmd = mc_can_id_cmd(f.id);
    if (cmd == MC_CAN_CMD_COMMISSION_RESULT && f.len >= 8u) {
      // the value is the float's bits, little-endian (DBC: 32|32@1+)
      const uint32_t bits =
          static_cast<uint32_t>(f.data[4]) | (static_cast<uint32_t>(f.data[5]) << 8) |
          (static_cast<uint32_t>(f.data[6]) << 16) | (static_cast<uint32_t>(f.data[7]) << 24);
      const uint32_t item = f.data[0];
      if (item < MC_COMM_CAN_ITEM_COUNT) {
        std::memcpy(&value[item], &bits, sizeof bits);
        have |= 1u << item;
      }
    } else if (cmd == MC_CAN_CMD_COMMISSION_STATUS) {
      uint32_t msg = 0;
      float v[MC_CAN_NSIG_MAX] = {0};
      if (mc_can_proto_unpack(&f, &msg, v, MC_CAN_NSIG_MAX) != MC_CAN_ERR_NONE) continue;
      step = static_cast<uint32_t>(v[MC_CAN_COMMISSION_STATUS_STEP]);
      err = static_cast<uint32_t>(v[MC_CAN_COMMISSION_STATUS_ERROR]);
      detail = static_cast<uint32_t>(v[MC_CAN_COMMISSION_STATUS_DETAIL]);
      valid = static_cast<uint32_t>(v[MC_CAN_COMMISSION_STATUS_VALID]);
      done = step == MC_COMM_STEP_DONE;
      if (step == MC_COMM_STEP_FAILED) {
        ended = true;
        t_end_s = t;
      }
    }
  }
  constexpr uint32_t kAll = (1u << MC_COMM_CAN_ITEM_COUNT) - 1u;
  if (done && have == kAll && !ended) {
    ended = true;
    t_end_s = t;
  }
}

// The result as the frames carry it (COMMISSION_RESULT items, the status's
// valid bits).
mc_comm_result_t result_of(const CommissionFrames& c) {
  const auto& v = c.value;
  mc_comm_result_t r{};
  r.r_ohm = v[MC_COMM_CAN_ITEM_R_OHM];
  r.ld_h = v[MC_COMM_CAN_ITEM_LD_H];
  r.lq_h = v[MC_COMM_CAN_ITEM_LQ_H];
  r.flux_wb = v[MC_COMM_CAN_ITEM_FLUX_WB];
  r.pole_pairs = static_cast<uint32_t>(std::lround(v[MC_COMM_CAN_ITEM_POLE_PAIRS]));
  r.encoder_offset_rad = v[MC_COMM_CAN_ITEM_ENCODER_OFFSET_RAD];
  r.encoder_direction = v[MC_COMM_CAN_ITEM_ENCODER_DIRECTION] < 0.0f ? -1 : 1;
  for (uint32_t k = 0; k < 3u; ++k) r.adc_offset_a[k] = v[MC_COMM_CAN_ITEM_ADC_OFFSET_A_A + k];
  r.j_kgm2 = v[MC_COMM_CAN_ITEM_J_KGM2];
  r.b_nm_s_rad = v[MC_COMM_CAN_ITEM_B_NM_S_RAD];
  r.valid = c.valid;
  return r;
}

void inject_offsets(const CommissionSetup& s, hal_host::PmsmBoard& b) {
  hal_host::PmsmBoard::Injection inj;
  set_adc_offsets(s, inj.offset_a);
  b.inject(inj);
}

// angle_ref index: the offset commissioning measures must be relative to
// the index (the drive refuses START until it has been seen: mc_comm_can.c),
// so the drive searches it first, as a user enables the drive once before
// `mdtool calibrate`: an enable in CURRENT mode at 0 A runs the image's
// search (mc_ctrl_idx, bounded current and travel, both directions), then
// the disable. Returns the time it took (0: no search needed). A search
// that fails stops the run naming the finder's reason.
double find_index_first(AppRunner& run) {
  if (run.target().params().angle_ref != MC_DRIVE_ANGLE_REF_INDEX ||
      run.probe().angle_state == MC_DRIVE_ANGLE_KNOWN) {
    return 0.0;
  }
  if (!run.find_at_enable(MC_CAN_CTRL_CURRENT)) {
    throw UsageError(
        "angle_ref index: the encoder offset is measured relative to the index, and the drive "
        "searches it only at an enable with angle_find_at_enable 1 (0 here)");
  }
  const double t0 = run.board().t_s();
  run.start(MC_CAN_CTRL_CURRENT, true);
  (void)run.finish_angle_find();
  if (run.probe().faults != 0u || run.probe().angle_state != MC_DRIVE_ANGLE_KNOWN) {
    AppWatch watch;
    throw std::runtime_error("the index search before commissioning failed: " + watch(run.probe()));
  }
  run.send(run.cmd().enable(false));
  const double t1 = run.board().t_s();
  while (run.probe().mode != MC_DRIVE_MODE_IDLE && run.board().t_s() - t1 < 1.0) run.step();
  return run.board().t_s() - t0;
}

// The target for the SIL runs: the files' plant.
CommissionTargetFactory sil_factory(const MotorFiles& f) {
  return [&f](const mc_params_t& p, const std::function<void(AppSetup&)>& adjust) {
    return make_file_target(f, p, nullptr, adjust);
  };
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
  bc.spi_encoder.direction = s.encoder_direction;
  // An incremental encoder's offset is the shaft angle at power-up.
  bc.theta_m0_rad = s.encoder_offset_rad / f.motor.pole_pairs;
}

// Relative to the index (the count 0 from the mark on, on average half a
// count behind the shaft): the angle of the middle of count 0, dir (index +
// step / 2), times the pole pairs.
double true_index_offset(const MotorFiles& f, const CommissionSetup& s,
                         const hal_host::PmsmBoardConfig& bc) {
  const double step = 2 * kPi / bc.encoder.counts_per_rev;
  const double th = s.encoder_direction * (bc.encoder.index_angle_rad + 0.5 * step);
  return wrap2pi(f.motor.pole_pairs * th);
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

CommissionSetup default_commission_setup(const MotorFiles& f) {
  CommissionSetup s;
  s.adc_offset_a = 0.01 * f.board.i_sense_max_a;
  s.noise_rms_a = 0.001 * f.board.i_sense_max_a;
  return s;
}

std::string commission_error_names(uint32_t e) {
  static const char* const names[] = {"OFFSET",
                                      "NO_MOTOR",
                                      "OPEN_PHASE",
                                      "ENCODER_NO_MOTION",
                                      "ROTOR_BLOCKED",
                                      "WRONG_DIRECTION",
                                      "ENCODER_BAD",
                                      "OVERCURRENT",
                                      "VOLTAGE",
                                      "RANGE",
                                      "MEAS",
                                      "ABORTED",
                                      "HOST_LOST",
                                      "ENCODER_COARSE",
                                      "HALL_CODES",
                                      "HALL_ORDER",
                                      "FLUX_SPEEDS",
                                      "MECH_FIT",
                                      "MECH_SPIN_COAST",
                                      "IF_SYNC"};
  std::string s;
  for (int i = 0; i < 20; ++i) {
    if (e & (1u << i)) s += (s.empty() ? "" : "|") + std::string(names[i]);
  }
  return s;
}

std::string commission_detail_name(uint32_t d) {
  static const char* const names[] = {"NONE", "FLUX_SPEEDS", "MECH_FIT", "MECH_SPIN_COAST",
                                      "IF_SYNC"};
  return d < 5u ? names[d] : "UNKNOWN";
}

mc_params_t commission_booted_params(const MotorFiles& f) {
  return params_from_files(f, Params(app_gain_params(f), {}), MC_LAW_SPEED_PI);
}

CommissionRun run_commission(const MotorFiles& f, const CommissionSetup& s, const mc_params_t& p,
                             const CommissionTargetFactory& make,
                             const CommissionObserver& observe) {
  // encoder_cpr 0: the drive commissions without an encoder (R, L, flux
  // from an I-f spin on the table's pole pairs; README "Without an encoder")
  CommissionRun out;
  hal_host::PmsmBoardConfig bc = build_board_cfg(f);
  set_board_sensor(f, bc);
  configure_plant(f, s, bc);
  const bool by_index = p.angle_ref == MC_DRIVE_ANGLE_REF_INDEX;
  out.true_encoder_offset_rad = by_index                          ? true_index_offset(f, s, bc)
                                : f.board.encoder == kEncoderHall ? hall_true_offset(f)
                                                                  : true_offset(f, s, bc);
  if (bc.spi_encoder.type != hal_host::SpiEncoderType::kNone) {
    // absolute: the chip reads dir theta_m + mount (rounded: no mean lag)
    out.true_encoder_offset_rad =
        wrap2pi(-s.encoder_direction * f.motor.pole_pairs * bc.spi_encoder.mount_offset_rad);
  }
  out.true_encoder_direction = s.encoder_direction;
  set_adc_offsets(s, out.true_adc_offset_a);
  if (f.board.current_sensors != 3) out.true_adc_offset_a[2] = 0.0;

  const std::unique_ptr<AppTarget> target = make(p, [&](AppSetup& su) {
    configure_plant(f, s, su.board);
    if (s.plant) s.plant(su.board);
    if (s.setup) s.setup(su);
  });
  AppRunner run(*target);
  hal_host::PmsmBoard& board = run.board();
  inject_offsets(s, board);
  if (s.inject) s.inject(board);
  out.index_search_s = find_index_first(run);
  const double t_start = board.t_s();  // the commissioning's time 0
  run.keep_host_alive();
  run.send(run.cmd().commission(MC_COMM_CAN_START, s.i_test_a, 0.0, 0.0));
  // the Hall table's step comes on top of the other steps' time
  const double t_max_s = s.t_max_s + (f.board.encoder == kEncoderHall ? MC_COMM_HALL_STEP_S : 0.0);
  const long n = step_count(t_max_s, board.period_s());
  CommissionFrames c;
  for (long k = 0; k <= n && !c.ended; ++k) {
    if (observe) observe(run, k);
    if (k < n) {
      run.step();
      c.take(run.sent(), board.t_s() - t_start);
      if (s.each_period) s.each_period(board, c.step);
    }
  }
  if (!c.ended) {
    c.t_end_s = board.t_s() - t_start;
    if (c.err == 0u) c.err = MC_COMM_ERR_ABORTED;  // timed out
    c.done = false;
  }
  out.err = c.err;
  out.detail = c.detail;
  if (const mc_comm_t* cm = target->commissioning()) {
    out.have_checks = true;
    out.flux_chk = cm->flux_chk;
    out.mech_chk = cm->mech_chk;
  }
  out.done = c.done;
  out.duration_s = c.t_end_s;
  out.drive_faults = run.probe().faults;
  out.bridge_off = !board.pwm_enabled();
  out.tx_frames = run.frames_sent();
  if (out.done) {
    out.res = result_of(c);
    // The Hall table has no COMMISSION_RESULT item: the SIL reads it from
    // the parameter service's staged set, as a host reads parameters 166-173
    const mc_params_t* st = target->staged();
    if (st != nullptr && p.encoder_type == MC_PARAMS_ENCODER_HALL) {
      out.res.have_hall = true;
      out.res.hall = hall_table_of(*st);
    }
    out.staged = staged_params(p, out.res);
  }
  return out;
}

CommissionRun run_commission(const MotorFiles& f, const CommissionSetup& s) {
  return run_commission(f, s, commission_booted_params(f), sil_factory(f));
}

mc_comm_hall_table_t hall_table_of(const mc_params_t& p) {
  mc_comm_hall_table_t t{};
  for (unsigned k = 0u; k < MC_HALL_SECTORS; ++k) {
    t.code_of_sector[k] = static_cast<uint8_t>((p.hall_codes >> (3u * k)) & 7u);
  }
  t.edge_e_rad[0] = p.hall_edge0_e_rad;
  t.edge_e_rad[1] = p.hall_edge1_e_rad;
  t.edge_e_rad[2] = p.hall_edge2_e_rad;
  t.edge_e_rad[3] = p.hall_edge3_e_rad;
  t.edge_e_rad[4] = p.hall_edge4_e_rad;
  t.edge_e_rad[5] = p.hall_edge5_e_rad;
  t.hysteresis_e_rad = p.hall_hysteresis_e_rad;
  return t;
}

mc_params_t staged_params(mc_params_t booted, const mc_comm_result_t& r) {
  booted.r_ohm = r.r_ohm;
  booted.ld_h = r.ld_h;
  booted.lq_h = r.lq_h;
  booted.flux_wb = r.flux_wb;
  booted.pole_pairs = r.pole_pairs;
  if ((r.valid & MC_COMM_HAVE_ENCODER) != 0u) {  // none without an encoder
    booted.encoder_offset_rad = r.encoder_offset_rad;
    booted.encoder_reversed = r.encoder_direction < 0 ? 1u : 0u;
  }
  booted.i_offset_a_a = r.adc_offset_a[0];
  booted.i_offset_b_a = r.adc_offset_a[1];
  booted.i_offset_c_a = r.adc_offset_a[2];
  if ((r.valid & MC_COMM_HAVE_MECH) != 0u) {
    booted.j_kgm2 = r.j_kgm2;
    booted.b_nm_s_rad = r.b_nm_s_rad;
    booted.speed_kp_a_s_rad = 0.0f;  // derived from the identified inertia
    booted.speed_ki_a_rad = 0.0f;
  }
  if (r.have_hall) {  // the measured Hall table, against the d axis (mc_comm_can.c stage_hall)
    booted.hall_codes = 0u;
    for (unsigned k = 0u; k < MC_HALL_SECTORS; ++k) {
      booted.hall_codes |= (static_cast<uint32_t>(r.hall.code_of_sector[k]) & 7u) << (3u * k);
    }
    booted.hall_edge0_e_rad = r.hall.edge_e_rad[0];
    booted.hall_edge1_e_rad = r.hall.edge_e_rad[1];
    booted.hall_edge2_e_rad = r.hall.edge_e_rad[2];
    booted.hall_edge3_e_rad = r.hall.edge_e_rad[3];
    booted.hall_edge4_e_rad = r.hall.edge_e_rad[4];
    booted.hall_edge5_e_rad = r.hall.edge_e_rad[5];
    booted.hall_hysteresis_e_rad = r.hall.hysteresis_e_rad;
    booted.encoder_offset_rad = 0.0f;
    booted.encoder_reversed = 0u;
  }
  return booted;
}

// The sensorless run starts the rotor at sensorless_start_theta_e_rad
// (default 0): the I-f start holds the current at two angles and restarts
// its observer from the flux path's circle fit
// (mc_ctrl_sls_cfg_t.align_any_angle), so any start angle works
// (tests/sil/commission SensorlessStartAngle); the encoder is not used.
double verify_speed_step(const MotorFiles& f, const CommissionSetup& s, mc_params_t staged,
                         uint32_t law, double* p_target_rad_s,
                         const CommissionTargetFactory& make) {
  staged.speed_law = law;
  const mc_params_eff_t e = resolve_params(staged);
  const mc_gains_t& g = e.g;
  const bool sls = law == MC_LAW_SPEED_SENSORLESS;
  const std::unique_ptr<AppTarget> target = make(staged, [&](AppSetup& su) {
    configure_plant(f, s, su.board);
    if (sls) su.board.theta_m0_rad = s.sensorless_start_theta_e_rad / f.motor.pole_pairs;
  });
  AppRunner run(*target);
  inject_offsets(s, run.board());
  const double w_t = 0.5 * g.speed_rated_eff_rad_s;
  *p_target_rad_s = w_t;
  run.start(MC_CAN_CTRL_SPEED, true);
  (void)run.finish_angle_find();  // angle_ref index: the search first
  run.send(run.cmd().speed_ref(w_t));
  const double wc = sls ? g.sls_wc_rad_s : g.speed_wc_rad_s;
  double t_end = std::abs(w_t) / static_cast<double>(e.p.speed_ramp_rad_s2) + 40.0 / wc + 0.1;
  if (sls) t_end += g.align_time_s + g.handover_rad_s / g.if_accel_rad_s2 + 0.1;
  const long n = step_count(t_end, run.board().period_s());
  AppWatch watch;
  for (long k = 0; k < n; ++k) {
    run.step();
    if (!watch(run.probe()).empty()) return std::nan("");
  }
  return std::abs(run.board().state()(2) - w_t) / std::abs(w_t);
}

double verify_speed_step(const MotorFiles& f, const CommissionSetup& s, const mc_params_t& staged,
                         uint32_t law, double* p_target_rad_s) {
  return verify_speed_step(f, s, staged, law, p_target_rad_s, sil_factory(f));
}

}  // namespace mcsim
