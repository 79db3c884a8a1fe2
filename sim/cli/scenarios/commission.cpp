// commission: any motor, the drive application's commissioning
// (firmware/app/commission: mc_comm_can, bound as the images bind it) run
// through the AppTarget (issue 29 item 3): on the SIL or with --pil the
// board's whole image on QEMU, the same CSV and summary on both.
//
// The application boots the table of the files (app_params.hpp). The
// sequence reads none of its motor values (it starts from the board: PWM
// period, dead time, shunts; mc_comm_can_cfg_for_board), only the drive's
// limits: i_max_a bounds the test current, speed_max_rad_s and the
// over-speed trip the spin-up; what it identifies replaces the motor
// values. (A table with placeholder motor values instead refused to boot
// many of the campaign's random boards: its derived current limit and PWM
// ripple checks then judge the board against a motor it does not drive.)
// The plant has the sensor offsets, noise, encoder direction and start
// angle of the parameters.
// The scenario sends COMMISSION_CMD START (i_test_a; 0: the drive's
// default, a quarter of the sense range within i_max_a), keeps the host
// alive (HOST_HEARTBEAT: the application times a run out as an enabled
// drive), follows COMMISSION_STATUS and reads what the drive identified
// from its COMMISSION_RESULT frames (every item, IEEE 754 bits), as a
// user's tool does (mdtool calibrate). The run ends when every result has
// arrived, when the status says FAILED, or after t_max_s.
//
// verify=1: the drive reboots on the identified values, as after the
// host's APPLY and SAVE (the booted table with the values commissioning
// stages: r, ld, lq, flux, pole pairs, encoder offset and direction, the
// sensor offsets, J and B with the speed gains derived from them), and runs
// a speed step to half the rated speed on the sensored speed law
// (speed_law 0) and on the sensorless law (speed_law 2, its I-f start from
// verify_sensorless_theta_e_rad), each on a fresh plant with the same
// imperfections. A law the table refuses for this motor (the sensorless law
// a salient machine) is reported, not run.
//
// CSV: the commissioning run, the generic scenarios' columns
// (app_scenario.hpp), one row every max(1, t_max_s / T / 20000) periods.
// Summary: "true", "identified", "error" as before the move, duration_s
// (when the last result arrived), verify.* (the final speed error of each
// step as a fraction of its target).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <functional>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "app_scenario.hpp"
#include "generic_commission.hpp"
#include "scenario.hpp"
#include "verdict.hpp"
extern "C" {
#include "config/mc_law_cfg.h"
#include "config/mc_param_srv.h"
}

namespace mcsim {
namespace {

constexpr double kPi = 3.14159265358979323846;

// What the host learns from the application's commissioning frames.
struct CommissionFrames {
  bool ended = false;  // DONE with every result, or FAILED
  bool done = false;
  uint32_t err = 0, valid = 0, step = 0;
  double t_end_s = 0;
  std::array<float, MC_COMM_CAN_ITEM_COUNT> value{};
  uint32_t have = 0;    // bit per item received
  bool staged = false;  // COMMISSION_STATUS: the results are staged in the table
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
      valid = static_cast<uint32_t>(v[MC_CAN_COMMISSION_STATUS_VALID]);
      staged = v[MC_CAN_COMMISSION_STATUS_STAGED] > 0.5f;
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

std::vector<ParamSpec> commission_params(const MotorFiles& f) {
  const CommissionSetup d = default_commission_setup(f);
  return {
      {"encoder_offset_rad", d.encoder_offset_rad, "rad",
       "plant: electrical angle of the d axis at encoder count 0", -100.0, 100.0},
      {"theta_m0_rad", d.encoder_offset_rad / f.motor.pole_pairs, "rad",
       "plant: the rotor's mechanical angle at power-up (the same as encoder_offset_rad / "
       "pole_pairs: set one)",
       -100.0, 100.0},
      {"encoder_direction", 1.0, "1", "plant: encoder counting direction (+1 or -1)", -1.0, 1.0},
      {"adc_offset_a", d.adc_offset_a, "A",
       "plant: current-sensor offsets (x, -0.7 x, 0.4 x) on phases a, b, c", -1e4, 1e4},
      {"noise_rms_a", d.noise_rms_a, "A", "plant: current-sensor noise per channel", 0.0, 1e4},
      {"i_test_a", 0.0, "A",
       "commissioning test current (COMMISSION_CMD; 0: the drive's default, a quarter of the "
       "current-sense range within i_max_a)",
       0.0, 65.535},
      {"t_max_s", d.t_max_s, "s", "give up after this much simulated time", 1e-3, 100.0},
      {"verify", 0.0, "1",
       "1: then run sensored and sensorless speed steps on the identified values (the drive "
       "rebooted on them)",
       0.0, 1.0},
      {"verify_sensorless_theta_e_rad", 0.0, "rad",
       "verify=1: the rotor's electrical angle when the sensorless run starts", -100.0, 100.0},
      {"seed", 1.0, "1", "plant: current-noise generator seed", 0.0, 4294967295.0},
  };
}

// The table the application boots (see the file comment), with the run's
// power-up keys (angle_ref, angle_find_at_enable).
mc_params_t booted_params(const MotorFiles& f, const Params& P) {
  mc_params_t p = params_from_files(f, Params(app_gain_params(f), {}), MC_LAW_SPEED_PI);
  p.angle_ref = static_cast<uint32_t>(P.get("angle_ref"));
  p.angle_find_at_enable = static_cast<uint32_t>(P.get("angle_find_at_enable"));
  const uint32_t err = mc_params_validate(&p);
  if (err != MC_PARAMS_OK) {
    throw UsageError("angle_ref " + std::to_string(p.angle_ref) +
                     " refused by the parameter table: MC_PARAMS_ERR " + params_err_names(err));
  }
  return p;
}

// The booted table with what commissioning stages (mc_comm_can.c, stage()).
mc_params_t identified_params(mc_params_t p, const CommissionFrames& c) {
  const auto& v = c.value;
  p.r_ohm = v[MC_COMM_CAN_ITEM_R_OHM];
  p.ld_h = v[MC_COMM_CAN_ITEM_LD_H];
  p.lq_h = v[MC_COMM_CAN_ITEM_LQ_H];
  p.flux_wb = v[MC_COMM_CAN_ITEM_FLUX_WB];
  p.pole_pairs = static_cast<uint32_t>(std::lround(v[MC_COMM_CAN_ITEM_POLE_PAIRS]));
  p.encoder_offset_rad = v[MC_COMM_CAN_ITEM_ENCODER_OFFSET_RAD];
  p.encoder_reversed = v[MC_COMM_CAN_ITEM_ENCODER_DIRECTION] < 0.0f ? 1u : 0u;
  p.i_offset_a_a = v[MC_COMM_CAN_ITEM_ADC_OFFSET_A_A];
  p.i_offset_b_a = v[MC_COMM_CAN_ITEM_ADC_OFFSET_B_A];
  p.i_offset_c_a = v[MC_COMM_CAN_ITEM_ADC_OFFSET_C_A];
  if ((c.valid & MC_COMM_HAVE_MECH) != 0u) {
    p.j_kgm2 = v[MC_COMM_CAN_ITEM_J_KGM2];
    p.b_nm_s_rad = v[MC_COMM_CAN_ITEM_B_NM_S_RAD];
    p.speed_kp_a_s_rad = 0.0f;  // derived from the identified inertia
    p.speed_ki_a_rad = 0.0f;
  }
  return p;
}

// The electrical offset relative to the index (the count 0 from the mark
// on, and on average half a count behind the shaft): the angle of the
// middle of count 0, dir (index + step / 2), times the pole pairs.
double true_index_offset(const MotorFiles& f, const CommissionSetup& s,
                         const hal_host::PmsmBoardConfig& bc) {
  const double step = 2 * kPi / bc.encoder.counts_per_rev;
  const double th = s.encoder_direction * (bc.encoder.index_angle_rad + 0.5 * step);
  return std::remainder(f.motor.pole_pairs * th, 2 * kPi);
}

// The plant's side of the setup, and its sensor offsets once built.
CommissionSetup plant_setup(const RunContext& ctx) {
  CommissionSetup s = default_commission_setup(*ctx.files);
  s.encoder_offset_rad = ctx.params.get("encoder_offset_rad");
  // theta_m0_rad is the same power-up angle, mechanical (configure_plant)
  const double pp = ctx.files->motor.pole_pairs;
  const double off_dflt = default_commission_setup(*ctx.files).encoder_offset_rad;
  const double th = ctx.params.get("theta_m0_rad");
  if (th != off_dflt / pp) {
    if (s.encoder_offset_rad != off_dflt) {
      throw UsageError(
          "theta_m0_rad and encoder_offset_rad both set the rotor's angle at "
          "power-up: set one");
    }
    s.encoder_offset_rad = th * pp;
  }
  s.encoder_direction = ctx.params.get("encoder_direction") < 0 ? -1 : 1;
  s.adc_offset_a = ctx.params.get("adc_offset_a");
  s.noise_rms_a = ctx.params.get("noise_rms_a");
  s.i_test_a = ctx.params.get("i_test_a");
  s.t_max_s = ctx.params.get("t_max_s");
  s.seed = static_cast<std::uint64_t>(ctx.params.get("seed"));
  s.sensorless_start_theta_e_rad = ctx.params.get("verify_sensorless_theta_e_rad");
  return s;
}

void inject_offsets(const CommissionSetup& s, hal_host::PmsmBoard& b) {
  hal_host::PmsmBoard::Injection inj;
  set_adc_offsets(s, inj.offset_a);
  b.inject(inj);
}

// angle_ref index: the offset commissioning measures must be relative to
// the index, so the drive finds it first, as a user enables the drive once
// (its index search at the enable) before `mdtool calibrate`: an enable in
// CURRENT mode at 0 A, the search, the disable. Returns the search's time.
double find_index_first(RunContext& ctx, AppRunner& run) {
  if (run.target().params().angle_ref != MC_DRIVE_ANGLE_REF_INDEX ||
      run.probe().angle_state == MC_DRIVE_ANGLE_KNOWN) {
    return 0.0;
  }
  if (!run.find_at_enable(MC_CAN_CTRL_CURRENT)) {
    throw UsageError(
        "angle_ref index: the encoder offset must be measured relative to the index, and the "
        "drive searches it only at an enable with angle_find_at_enable 1 (0 here)");
  }
  const double t0 = run.board().t_s();
  run.start(MC_CAN_CTRL_CURRENT, true);
  (void)run.finish_angle_find();
  if (run.probe().faults != 0u) {
    AppWatch watch;
    throw std::runtime_error("the index search before commissioning failed: " + watch(run.probe()));
  }
  run.send(run.cmd().enable(false));
  const double t1 = run.board().t_s();
  while (run.probe().mode != MC_DRIVE_MODE_IDLE && run.board().t_s() - t1 < 1.0) run.step();
  ctx.summary.set("index_search_s", run.board().t_s() - t0);
  return run.board().t_s() - t0;
}

// The PARAM_REPLY to opcode op among the frames of a period: its status
// (and its value's raw bits), or -1 when none.
int param_reply(const std::vector<mc_hal_can_frame_t>& frames, uint32_t op, uint32_t* p_value) {
  for (const mc_hal_can_frame_t& f : frames) {
    if (mc_can_id_cmd(f.id) != MC_CAN_CMD_PARAM_REPLY || f.len < 8u || f.data[0] != op) continue;
    *p_value = static_cast<uint32_t>(f.data[4]) | (static_cast<uint32_t>(f.data[5]) << 8) |
               (static_cast<uint32_t>(f.data[6]) << 16) | (static_cast<uint32_t>(f.data[7]) << 24);
    return f.data[3];
  }
  return -1;
}

// --flash: what commissioning staged applied and saved, as `mdtool
// calibrate --save` does (PARAM_REQ APPLY, then SAVE; each answered by
// PARAM_REPLY). A refusal stops the run (exit 1) naming the status.
void save_to_flash(RunContext& ctx, AppRunner& run, const CommissionFrames& c) {
  if (!c.staged) {
    throw std::runtime_error(
        "--flash: the drive did not stage the results (no parameter "
        "service): nothing to save");
  }
  static const char* const kStatus[] = {"OK",      "UNKNOWN_ID",    "READONLY",      "RANGE",
                                        "RUNNING", "FAULT",         "INVALID",       "STORE",
                                        "OPCODE",  "NEEDS_CONFIRM", "NOT_CONFIRMED", "RATE_LIMIT"};
  for (const uint32_t op : {MC_PARAM_OP_APPLY, MC_PARAM_OP_SAVE}) {
    const char* name = op == MC_PARAM_OP_APPLY ? "APPLY" : "SAVE";
    run.send(run.cmd().param_op(op));
    int st = -1;
    uint32_t value = 0;
    const double t0 = run.board().t_s();
    while (st < 0 && run.board().t_s() - t0 < 1.0) {
      run.step();
      st = param_reply(run.sent(), op, &value);
    }
    if (st != 0) {
      throw std::runtime_error(std::string("--flash: PARAM_REQ ") + name +
                               (st < 0 ? " not answered within 1 s"
                                       : std::string(" answered ") + kStatus[std::min(st, 11)] +
                                             " (value " + std::to_string(value) + ")"));
    }
    if (op == MC_PARAM_OP_SAVE) ctx.summary.set("cfg_saved_seq", value);
  }
  ctx.summary.set("cfg_saves", run.probe().store_saves);
}

// The commissioning run on the application (see the file comment).
CommissionFrames run_app_commission(RunContext& ctx, const CommissionSetup& s,
                                    const mc_params_t& p) {
  const MotorFiles& f = *ctx.files;
  const std::unique_ptr<AppTarget> target =
      make_file_target(ctx, f, p, nullptr, [&](AppSetup& su) { configure_plant(f, s, su.board); });
  AppRunner run(*target);
  hal_host::PmsmBoard& board = run.board();
  inject_offsets(s, board);
  const double t_start = find_index_first(ctx, run);  // the commissioning's time 0
  run.keep_host_alive();
  run.send(run.cmd().commission(MC_COMM_CAN_START, s.i_test_a, 0.0, 0.0));
  const long n = step_count(s.t_max_s, board.period_s());
  AppRecorder rec{ctx, run, f.motor.pole_pairs, false, std::max(1L, n / 20000)};
  rec.header();
  CommissionFrames c;
  double id = 0, iq = 0;
  for (long k = 0; k <= n && !c.ended; ++k) {
    const double t = board.t_s() - t_start;
    board.true_dq_a(&id, &iq);
    rec.row(t, id, iq, board.state()(2));
    if (k < n) {
      run.step();
      c.take(run.sent(), board.t_s() - t_start);
    }
    if ((k & 1023) == 0) ctx.progress.update(t, s.t_max_s);
  }
  if (c.done && c.ended && ctx.flash != nullptr) save_to_flash(ctx, run, c);
  if (!c.ended) {
    c.t_end_s = board.t_s() - t_start;
    if (c.err == 0u) c.err = MC_COMM_ERR_ABORTED;  // timed out
    c.done = false;
  }
  ctx.summary.set("commission_faults", run.probe().faults);
  ctx.summary.set("app_tx_frames", static_cast<double>(run.frames_sent()));
  return c;
}

// A speed step on the rebooted drive (see the file comment): the final
// speed error as a fraction of the target, NaN when the drive stopped.
double verify_step(RunContext& ctx, const CommissionSetup& s, mc_params_t p, uint32_t law,
                   double* p_target) {
  const MotorFiles& f = *ctx.files;
  p.speed_law = law;
  const mc_params_eff_t e = resolve_params(p);
  const mc_gains_t& g = e.g;
  const bool sls = law == MC_LAW_SPEED_SENSORLESS;
  const std::unique_ptr<AppTarget> target = make_file_target(ctx, f, p, nullptr, [&](AppSetup& su) {
    su.flash = nullptr;  // the identified values, not the flash (see the file comment)
    su.flash_must_boot = false;
    configure_plant(f, s, su.board);
    if (sls) su.board.theta_m0_rad = s.sensorless_start_theta_e_rad / f.motor.pole_pairs;
  });
  AppRunner run(*target);
  inject_offsets(s, run.board());
  const double w_t = 0.5 * g.speed_rated_eff_rad_s;
  *p_target = w_t;
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

// verify=1: both laws on the identified values (see the file comment).
void run_verify(RunContext& ctx, const CommissionSetup& s, const mc_params_t& p,
                CommissionFigures& fig) {
  double w = 0;
  const auto verify = [&](uint32_t law, const char* name) {
    const std::string key = std::string("verify.") + name;
    try {
      const double e = verify_step(ctx, s, p, law, &w);
      ctx.summary.set(key + "_speed_err_frac", e);
      ctx.summary.set(key + "_faulted", std::isnan(e) ? 1.0 : 0.0);
    } catch (const UsageError& e) {
      // the table refuses this law for the identified motor
      ctx.summary.set(key + "_speed_err_frac", std::nan(""));
      ctx.summary.set_text(key + "_refused", e.what());
      if (law == MC_LAW_SPEED_SENSORLESS) {
        fig.sensorless_refused = true;
      } else {
        fig.sensored_refused = true;
      }
    }
  };
  verify(MC_LAW_SPEED_PI, "sensored");
  verify(MC_LAW_SPEED_SENSORLESS, "sensorless");
  ctx.summary.set("verify.speed_target_rad_s", w);
  const auto& n = ctx.summary.numbers();
  fig.verify = true;
  fig.verify_sensored_err_frac = n.at("verify.sensored_speed_err_frac");
  fig.verify_sensorless_err_frac = n.at("verify.sensorless_speed_err_frac");
}

void record_truth(RunContext& ctx, const CommissionSetup& s, double true_off, const double adc[3]) {
  const MotorSpec& m = ctx.files->motor;
  ctx.summary.set_object("true", {{"r_ohm", m.r_ohm},
                                  {"ld_h", m.ld_h},
                                  {"lq_h", m.lq_h},
                                  {"flux_wb", m.flux_wb},
                                  {"pole_pairs", m.pole_pairs},
                                  {"encoder_offset_rad", true_off},
                                  {"encoder_direction", s.encoder_direction},
                                  {"adc_offset_a_a", adc[0]},
                                  {"adc_offset_b_a", adc[1]},
                                  {"adc_offset_c_a", adc[2]},
                                  {"j_kgm2", m.j_kgm2},
                                  {"b_nm_s_rad", m.b_nm_s_rad}});
}

void run_commission_scenario(RunContext& ctx) {
  const MotorFiles& f = *ctx.files;
  if (f.board.encoder_cpr == 0) {
    throw UsageError(f.board.file + ": commissioning needs an encoder (encoder_cpr = 0)");
  }
  const CommissionSetup s = plant_setup(ctx);
  const mc_params_t p = booted_params(f, ctx.params);
  hal_host::PmsmBoardConfig bc = build_board_cfg(f);
  set_board_sensor(f, bc);
  configure_plant(f, s, bc);
  const double true_off = p.angle_ref == MC_DRIVE_ANGLE_REF_INDEX && bc.encoder.has_index
                              ? true_index_offset(f, s, bc)
                              : true_offset(f, s, bc);
  double adc[3];
  set_adc_offsets(s, adc);
  if (f.board.current_sensors != 3) adc[2] = 0.0;

  const CommissionFrames c = run_app_commission(ctx, s, p);
  const auto& v = c.value;
  ctx.summary.set("duration_s", c.t_end_s);
  ctx.summary.set("error_bits", c.err);
  ctx.summary.set_text("fault", c.err ? commission_error_names(c.err) : "");
  ctx.summary.set_text("motor", f.motor.name);
  ctx.summary.set_text("board", f.board.name);
  record_truth(ctx, s, true_off, adc);
  CommissionFigures fig;
  fig.duration_s = c.t_end_s;
  fig.error_names = commission_error_names(c.err);
  if (!c.done) return write_verdict(ctx.summary, judge_commission(fig));
  const double r = v[MC_COMM_CAN_ITEM_R_OHM], ld = v[MC_COMM_CAN_ITEM_LD_H];
  const double lq = v[MC_COMM_CAN_ITEM_LQ_H], flux = v[MC_COMM_CAN_ITEM_FLUX_WB];
  const double pp = v[MC_COMM_CAN_ITEM_POLE_PAIRS];
  const double off = v[MC_COMM_CAN_ITEM_ENCODER_OFFSET_RAD];
  const double dir = v[MC_COMM_CAN_ITEM_ENCODER_DIRECTION];
  const double adc_id[3] = {v[MC_COMM_CAN_ITEM_ADC_OFFSET_A_A], v[MC_COMM_CAN_ITEM_ADC_OFFSET_B_A],
                            v[MC_COMM_CAN_ITEM_ADC_OFFSET_C_A]};
  std::map<std::string, double> id = {{"r_ohm", r},
                                      {"ld_h", ld},
                                      {"lq_h", lq},
                                      {"flux_wb", flux},
                                      {"pole_pairs", pp},
                                      {"encoder_offset_rad", off},
                                      {"encoder_direction", dir},
                                      {"adc_offset_a_a", adc_id[0]},
                                      {"adc_offset_b_a", adc_id[1]},
                                      {"adc_offset_c_a", adc_id[2]},
                                      {"saliency", lq / ld}};
  if ((c.valid & MC_COMM_HAVE_MECH) != 0u) {
    id["j_kgm2"] = v[MC_COMM_CAN_ITEM_J_KGM2];
    id["b_nm_s_rad"] = v[MC_COMM_CAN_ITEM_B_NM_S_RAD];
  }
  ctx.summary.set_object("identified", id);
  const double e_off = std::remainder(off - true_off, 2 * kPi);
  double e_adc = 0;  // the largest current-sensor offset error
  for (int k = 0; k < 3; ++k) e_adc = std::max(e_adc, std::abs(adc_id[k] - adc[k]));
  const bool dir_right = (dir < 0) == (s.encoder_direction < 0);
  ctx.summary.set_object("error", {{"r_frac", r / f.motor.r_ohm - 1},
                                   {"ld_frac", ld / f.motor.ld_h - 1},
                                   {"lq_frac", lq / f.motor.lq_h - 1},
                                   {"flux_frac", flux / f.motor.flux_wb - 1},
                                   {"encoder_offset_deg", e_off * 180 / kPi},
                                   {"pole_pairs_diff", pp - f.motor.pole_pairs},
                                   {"direction_wrong", dir_right ? 0.0 : 1.0},
                                   {"adc_offset_max_a", e_adc},
                                   {"adc_offset_max_frac", e_adc / f.board.i_sense_max_a}});
  if (ctx.params.get("verify") > 0.5) run_verify(ctx, s, identified_params(p, c), fig);
  fig.done = true;
  fig.r_frac = r / f.motor.r_ohm - 1;
  fig.ld_frac = ld / f.motor.ld_h - 1;
  fig.lq_frac = lq / f.motor.lq_h - 1;
  fig.flux_frac = flux / f.motor.flux_wb - 1;
  fig.pole_pairs_diff = pp - f.motor.pole_pairs;
  fig.encoder_offset_deg = e_off * 180 / kPi;
  fig.adc_offset_max_frac = e_adc / f.board.i_sense_max_a;
  fig.direction_right = dir_right;
  write_verdict(ctx.summary, judge_commission(fig));
}

const Registrar reg_commission(on_app_target(
    {"commission",
     "any motor: the drive application's commissioning over CAN (COMMISSION_CMD), from the "
     "board alone: current-sensor offsets, R, Ld, Lq, pole pairs, encoder direction and offset, "
     "flux (and J, B) read back from its COMMISSION_RESULT frames; JSON with 'identified' and "
     "'true'; verify=1 then reboots the drive on the identified values and runs speed steps",
     0.0,
     {},
     run_commission_scenario,
     commission_params,
     /*takes_flash=*/true,
     /*motor_optional=*/false,
     /*takes_duration=*/false}));

}  // namespace
}  // namespace mcsim
