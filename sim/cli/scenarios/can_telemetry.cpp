// Scenario can-telemetry: the drive application of the MCU image
// (firmware/app/app/mc_app: CAN receive ring, command handler, telemetry,
// command timeout, parameter service and flash configuration, the laws
// chosen by the parameters) on the AppTarget the generic scenarios use
// (app_scenario.hpp make_file_target: the SIL, hal_host::app_period, or with
// --pil the board's whole image on QEMU), its CAN frames carried to and from
// a bus. This file only connects the target's CAN boundary to the bus and
// records what crosses it.
//
// Where the frames go (environment, since scenario parameters are numbers;
// sim/cli/can_bus.hpp):
//   MCSIM_CAN_IF=vcan0     a SocketCAN interface (hal_host::SocketCan):
//                          telemetry out, commands in (cansend, mc_can.py);
//   MCSIM_CAN_IF=socketcand:127.0.0.1:29536
//                          a socketcand server (hal_host::SocketcandCan) for
//                          python-can's socketcand interface (mdtool);
//   otherwise              the candump log MCSIM_CAN_LOG (default
//                          DIR/can-telemetry.candump.log, DIR the run's
//                          --out; in memory, mdtool.sil, MCSIM_CAN_LOG must
//                          be set), time-stamped with the simulated time;
// commands from the candump-format script MCSIM_CAN_CMDS if set (any of them).
// The frames a period's receive interrupt gets are those the bus delivered
// by the start of the period; the frames the application sent in a period
// go to the bus at its end (stamped with the period's end).
//
// The motor and board: the paper-002 test motor on a 200 V, 10 kHz board
// with a 12-bit, +-20 A current sense and an 8192-count encoder (no
// --motor), or any motor and board (--motor FILE [--board FILE]). The
// application boots the parameter table built from them (app_params.hpp
// params_from_files: every gain and derived limit by the firmware's C
// derivation, as on the board), with the CAN settings below; the plant is
// built from the same files.
//
// With --set realtime=1 the loop is paced to the wall clock (needed when
// people or scripts send commands on a live interface).
//
// The CSV has one row per slow-loop step: the true speed, q current and
// angle of the plant, and for every telemetry message the signals of the
// last frame of it the application sent (decoded with the DBC's generated
// codec; empty before the first), as "<MESSAGE>.<signal>", with the mask
// of the messages sent in that step (tm_sent_mask, bit = slot) and of those
// the bus refused (tm_fail_mask), so a logger's decoded frames can be
// matched one for one. The summary's counters are the application's probe
// (mc_app_probe_t: telemetry, commands, receive interrupt, store) and what
// the bus saw: nothing of the application is read but its frames and its
// probe, so the run with --pil writes the same CSV, summary and CAN log.
//
// Parameters (PARAM_REQ/PARAM_REPLY) are served as on the MCU: the
// parameter service (firmware/app/config/mc_param_srv) on the drive, with
// the configuration store on the board's flash when mcsim runs with
// --flash FILE (hal_host::FileFlash; the SIL only: the PIL image has its own
// erased RAM store). The scenario's settings are this board's defaults
// (what mc_params_default is on the MCU). Boot, with --flash:
// mc_cfg_store_load; with a STORED or MIGRATED record the stored set
// replaces the scenario's settings for everything the firmware configures
// (the stored value wins over --set, as a flashed drive ignores how it was
// shipped); a stored set whose pwm_hz or slow_loop_div differ from the
// board's is refused (boot status INVALID: the simulated PWM period and CAN
// tick are fixed at start, as a board's are) and the scenario's settings
// run; any other status boots the scenario's settings and says so. The
// plant (motor, inertia, load, bus voltage, sensors) stays the scenario's:
// the flash configures the drive, not the motor it is wired to. A SAVE
// writes the file. Without --flash the service runs without a store (SAVE
// answers STORE). Settings outside the parameter table are refused.
//
// Commissioning over CAN (COMMISSION_CMD) is bound as the boards' main.c
// binds it (the SIL; the PIL image binds none: app_target.hpp).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "app_params.hpp"
#include "app_scenario.hpp"
#include "can_bus.hpp"
#include "foc_sil.hpp"
#include "hal_host/file_flash.hpp"
#include "scenario.hpp"
#include "verdict.hpp"
extern "C" {
#include "mc_can_proto.h"
#include "mc_params.h"
#include "mc_telemetry.h"
}

namespace mcsim {
namespace {

const char* const kSlotParam[MC_TM_COUNT] = {
    "rate_heartbeat_hz",    "rate_currents_hz",     "rate_voltages_hz",    "rate_speed_hz",
    "rate_position_hz",     "rate_observer_hz",     "rate_controller_hz",  "rate_stepper_hz",
    "rate_current_refs_hz", "rate_position_ref_hz", "rate_bus_current_hz", "rate_thermal_hz"};
const char* const kSlotName[MC_TM_COUNT] = {
    "HEARTBEAT",  "CURRENTS", "VOLTAGES",     "SPEED",        "POSITION",    "OBSERVER",
    "CONTROLLER", "STEPPER",  "CURRENT_REFS", "POSITION_REF", "BUS_CURRENT", "THERMAL"};
// Signal names per slot, in DBC order (checked against the generated
// signal counts below; tests/can compares the CSV header with the DBC).
const std::vector<std::vector<std::string>> kSlotSignals = {
    {"mode", "control_mode", "enabled", "stopping", "can_state", "stop_reason", "cfg_status",
     "faults", "last_error", "last_error_cmd", "seq"},
    {"i_d_a", "i_q_a", "sat", "seq"},
    {"v_d_v", "v_q_v", "v_bus_v", "sat", "seq"},
    {"omega_m_rad_s", "omega_ref_rad_s", "sat", "seq"},
    {"theta_m_rad", "theta_e_rad", "sat", "seq"},
    {"tau_l_hat_nm", "omega_hat_rad_s", "theta_hat_rad", "sat", "seq"},
    {"nu_pu", "vartheta_pu", "sat", "seq"},
    {"e1_rad", "e2_rad_s", "s1", "s2", "seq"},
    {"i_d_ref_a", "i_q_ref_a", "sat", "seq"},
    {"theta_ref_rad", "sat", "seq"},
    {"i_bus_est_a", "i_bus_max_a", "i_bus_regen_max_a", "sat", "seq"},
    {"t_winding_est_c", "i_limit_a", "derate_factor", "derating", "sat", "seq"}};

const char* const kBootName[] = {"STORED", "MIGRATED", "EMPTY", "CORRUPT",
                                 "LAYOUT", "INVALID",  "FLASH"};

// Without --motor: the paper-002 test motor (Table I; J the scenario's
// flywheel) on a 200 V board: 10 kHz (pwm_hz), no dead time, two shunts,
// 12-bit +-20 A current sense, 400 V bus sense, an 8192-count encoder.
MotorFiles paper002_files(const Params& P) {
  const PmsmParams m = paper002_test_motor();
  MotorFiles f;
  f.motor.name = "paper002-test-motor";
  f.motor.file = "(paper 002 test motor)";
  f.motor.r_ohm = m.R_ohm;
  f.motor.ld_h = m.Ld_h;
  f.motor.lq_h = m.Lq_h;
  f.motor.flux_wb = m.flux_wb;
  f.motor.pole_pairs = m.pole_pairs;
  f.motor.j_kgm2 = P.get("J_kgm2");
  f.motor.b_nm_s_rad = m.B_nms_rad;
  f.motor.i_max_a = 10.0;
  f.motor.i_rated_a = 4.24;            // 3 A rms
  f.motor.speed_rated_rad_s = 104.72;  // 1000 r/min
  f.motor.speed_max_rad_s = 157.08;    // 1.5x rated
  f.board.name = "paper002-200v";
  f.board.file = "(200 V board)";
  f.board.vbus_v = 200.0;
  f.board.pwm_hz = P.get("pwm_hz");
  f.board.dead_time_s = 0.0;
  f.board.current_sensors = 2;
  f.board.i_sense_max_a = 20.0;
  f.board.adc_bits = 12;
  f.board.vbus_sense_max_v = 400.0;
  f.board.encoder_cpr = 8192;
  return f;
}

// The parameter table without --motor: the files' motor and board values,
// the limits of the paper-002 bench (10 A, trip 15 A, bus 100..300 V,
// 1.5x rated speed, 100 degC, stall 90 % of i_max below 1 rad/s for 0.5 s),
// the current loop at bw_hz, every gain derived by the firmware.
mc_params_t paper002_params(const MotorFiles& f, const Params& P) {
  mc_params_t p = mc_params_default;
  p.r_ohm = static_cast<float>(f.motor.r_ohm);
  p.ld_h = static_cast<float>(f.motor.ld_h);
  p.lq_h = static_cast<float>(f.motor.lq_h);
  p.flux_wb = static_cast<float>(f.motor.flux_wb);
  p.pole_pairs = static_cast<uint32_t>(f.motor.pole_pairs);
  p.j_kgm2 = static_cast<float>(f.motor.j_kgm2);
  p.b_nm_s_rad = static_cast<float>(f.motor.b_nm_s_rad);
  p.i_rated_a = static_cast<float>(f.motor.i_rated_a);
  p.speed_rated_rad_s = static_cast<float>(f.motor.speed_rated_rad_s);
  p.i_max_a = static_cast<float>(f.motor.i_max_a);
  p.vbus_v = static_cast<float>(f.board.vbus_v);
  p.vbus_board_max_v = static_cast<float>(f.board.bus_limit_v());
  p.pwm_hz = static_cast<uint32_t>(std::lround(f.board.pwm_hz));
  p.dead_time_s = static_cast<float>(f.board.dead_time_s);
  p.current_sensors = static_cast<uint32_t>(f.board.current_sensors);
  p.i_sense_max_a = static_cast<float>(f.board.i_sense_max_a);
  p.adc_bits = static_cast<uint32_t>(f.board.adc_bits);
  p.encoder_cpr = static_cast<uint32_t>(f.board.encoder_cpr);
  p.current_bw_rad_s = static_cast<float>(2.0 * 3.14159265358979 * P.get("bw_hz"));
  p.speed_pll_bw_rad_s = static_cast<float>(P.get("speed_pll_bw_rad_s"));
  p.i_trip_a = 15.0f;
  p.vbus_min_v = static_cast<float>(0.5 * f.board.vbus_v);
  p.vbus_max_v = static_cast<float>(1.5 * f.board.vbus_v);
  p.omega_max_rad_s = static_cast<float>(f.motor.speed_max_rad_s);
  p.temp_max_c = 100.0f;
  p.stall_current_frac = 0.9f;
  p.stall_speed_rad_s = 1.0f;
  p.stall_time_s = 0.5f;
  p.stop_decel_rad_s2 = static_cast<float>(P.get("stop_decel_rad_s2"));
  return p;
}

// The CAN side's settings on top of the motor's table (the board's defaults).
void can_settings(const Params& P, mc_params_t* p) {
  p->speed_law = static_cast<uint32_t>(P.get("speed_law"));
  p->speed_max_rad_s = static_cast<float>(P.get("speed_max_rad_s"));
  p->slow_loop_div = static_cast<uint32_t>(P.get("slow_loop_div"));
  p->can_node_id = static_cast<uint32_t>(P.get("node_id"));
  p->can_bitrate_bps = static_cast<uint32_t>(P.get("bitrate_kbps") * 1000.0);
  p->can_timeout_s = static_cast<float>(P.get("timeout_s"));
  p->stop_ramp_a_per_s = static_cast<float>(P.get("stop_ramp_a_per_s"));
  // the speed law's crossover (0: derived) and the speed reference's ramp
  if (P.get("speed_bw_rad_s") > 0.0)
    p->speed_bw_rad_s = static_cast<float>(P.get("speed_bw_rad_s"));
  if (P.get("speed_ramp_rad_s2") > 0.0) {
    p->speed_ramp_rad_s2 = static_cast<float>(P.get("speed_ramp_rad_s2"));
  }
  // the position move as this scenario always ran it: cruise at the speed
  // limit, accelerate and decelerate at the stop's rate (0: derived)
  p->traj_v_max_rad_s = p->speed_max_rad_s;
  p->traj_a_max_rad_s2 = p->stop_decel_rad_s2;
  p->traj_d_max_rad_s2 = p->stop_decel_rad_s2;
  p->tm_heartbeat_hz = static_cast<uint32_t>(P.get("rate_heartbeat_hz"));
  p->tm_currents_hz = static_cast<uint32_t>(P.get("rate_currents_hz"));
  p->tm_voltages_hz = static_cast<uint32_t>(P.get("rate_voltages_hz"));
  p->tm_speed_hz = static_cast<uint32_t>(P.get("rate_speed_hz"));
  p->tm_position_hz = static_cast<uint32_t>(P.get("rate_position_hz"));
}

// What crosses the boundary, recorded: the last decoded frame of every
// telemetry message, the masks of one slow step.
struct TmRecord {
  uint32_t node = 0;
  std::vector<std::vector<double>> held;  // per slot, NaN before the first frame
  uint32_t sent_mask = 0, fail_mask = 0;
  uint64_t frames = 0, refused = 0;
  explicit TmRecord(uint32_t node_id) : node(node_id) {
    for (int i = 0; i < MC_TM_COUNT; ++i) {
      const uint32_t msg = mc_telemetry_msg(static_cast<uint32_t>(i));
      if (kSlotSignals[i].size() != mc_can_messages[msg].n_signals) {
        throw std::logic_error(std::string("signal list of ") + kSlotName[i] + " out of date");
      }
      held.emplace_back(kSlotSignals[i].size(), std::nan(""));
    }
  }
  // A frame the application sent; refused: the bus did not take it.
  void frame(const mc_hal_can_frame_t& f, bool refused_by_bus) {
    uint32_t msg = 0;
    float v[MC_CAN_NSIG_MAX] = {0};
    if (mc_can_id_node(f.id) != node || mc_can_proto_unpack(&f, &msg, v, MC_CAN_NSIG_MAX) != 0) {
      return;
    }
    for (uint32_t i = 0; i < MC_TM_COUNT; ++i) {
      if (mc_telemetry_msg(i) != msg) continue;
      sent_mask |= 1u << i;
      ++frames;
      if (refused_by_bus) {
        fail_mask |= 1u << i;
        ++refused;
      }
      for (size_t j = 0; j < held[i].size(); ++j) held[i][j] = static_cast<double>(v[j]);
    }
  }
};

std::vector<std::string> csv_columns() {
  std::vector<std::string> cols{
      "t", "tm_sent_mask", "tm_fail_mask", "omega_m_true_rad_s", "i_q_true_a", "theta_m_true_rad"};
  for (int i = 0; i < MC_TM_COUNT; ++i) {
    for (const auto& s : kSlotSignals[i]) cols.push_back(std::string(kSlotName[i]) + "." + s);
  }
  return cols;
}

// The summary: the application's probe and what the bus saw.
void write_summary(RunContext& ctx, AppTarget& t, const mc_params_t& p_scn, const TmRecord& rec,
                   uint32_t rx_read_max) {
  const mc_app_probe_t& q = t.probe();
  Summary& s = ctx.summary;
  s.set("tick_hz", q.tick_hz);
  s.set("bus_load_frac", q.tm_load_frac);
  s.set("tm_frames_generated", static_cast<double>(rec.frames));
  s.set("tm_frames_queued", q.tm_tx_frames);
  // refused by the application's controller or by the bus
  s.set("tm_frames_dropped", static_cast<double>(q.tm_tx_dropped + rec.refused));
  s.set("tm_tx_nobufs", q.tm_tx_nobufs);
  s.set("tm_tx_busoff", q.tm_tx_busoff);
  s.set("tm_bus_refused", static_cast<double>(rec.refused));
  s.set("cmd_accepted", q.cmd_rx_accepted);
  s.set("cmd_rejected", q.cmd_rx_rejected);
  s.set("cmd_reply_dropped", q.cmd_reply_dropped);
  s.set("cmd_reply_limited", q.cmd_reply_limited);
  // foreign frames: dropped by the application's receive path (before the
  // ring) or by the command handler's own filter
  s.set("cmd_rx_foreign", q.app_rx_foreign + q.cmd_rx_foreign);
  s.set("cmd_poll_frames_max", std::max(rx_read_max, q.cmd_poll_max));
  // the receive interrupt's part: foreign frames dropped there, own frames
  // lost to a full ring, and the most frames the bus delivered to one period
  s.set("app_rx_foreign", q.app_rx_foreign);
  s.set("app_rx_overflows", q.app_rx_overflows);
  s.set("app_rx_read_max", rx_read_max);
  s.set("tm_frames_saturated", q.tm_saturated);
  s.set("final_mode", q.mode);
  s.set("final_enabled", q.cmd_enabled != 0u ? 1.0 : 0.0);
  s.set("final_stop_reason", q.cmd_stop_reason);
  s.set("final_faults", q.faults);
  s.set_text("final_fault_names", drive_fault_names(q.faults));
  // The laws (firmware/app/config/mc_law_cfg.h): which one SPEED ran, and
  // why one is not available (the law_error parameter).
  s.set("speed_law", q.speed_law);
  s.set("law_error", q.law_error);
  s.set("sls_handovers", q.sls_handovers);
  if (ctx.flash != nullptr) {
    // What the drive booted from (cfg_from_store: ids of the parameters whose
    // stored value replaced the scenario's), and what the run did to the store.
    std::string from_store;
    for (const mc_param_info_t& info : mc_param_table) {
      if (info.offset == MC_PARAM_NO_FIELD) continue;
      if (mc_param_get_raw(&t.params(), &info) != mc_param_get_raw(&p_scn, &info)) {
        from_store += (from_store.empty() ? "" : ",") + std::to_string(info.id);
      }
    }
    const uint32_t boot = std::min<uint32_t>(q.boot_status, 6u);
    s.set_text("flash_file", ctx.flash->path());
    s.set_text("cfg_boot_status", kBootName[boot]);
    s.set("cfg_boot_code", static_cast<double>(boot));
    s.set_text("cfg_from_store", from_store);
    s.set("cfg_store_seq", q.store_seq);
    s.set("cfg_saves", q.store_saves);
    s.set("cfg_applied", q.srv_applied);
    s.set("flash_persist_errors", ctx.flash->persist_errors());
  }
  CanTelemetryFigures fig;
  fig.tm_frames_dropped = static_cast<double>(q.tm_tx_dropped + rec.refused);
  fig.rx_overflows = q.app_rx_overflows;
  fig.flash_persist_errors = ctx.flash != nullptr ? ctx.flash->persist_errors() : 0.0;
  fig.final_faults = q.faults;
  write_verdict(s, judge_can_telemetry(fig));
}

void run_can_telemetry(RunContext& ctx) {
  const auto& P = ctx.params;
  const MotorFiles f = ctx.files != nullptr ? *ctx.files : paper002_files(P);
  const auto speed_law = static_cast<uint32_t>(P.get("speed_law"));
  mc_params_t p_scn =
      ctx.files != nullptr ? params_from_files(f, P, speed_law) : paper002_params(f, P);
  can_settings(P, &p_scn);
  const uint32_t scn_err = mc_params_validate(&p_scn);
  if (scn_err != MC_PARAMS_OK) {
    throw UsageError(
        "the scenario's settings are the board's defaults and must form a valid parameter set "
        "(firmware/app/config/PARAMS.md); mc_params_validate refuses them: MC_PARAMS_ERR " +
        params_err_names(scn_err) + " (law_error " + law_err_names(mc_law_speed_check(&p_scn)) +
        ")");
  }
  const double tick_hz_d = static_cast<double>(p_scn.pwm_hz) / p_scn.slow_loop_div;
  if (std::fabs(tick_hz_d - std::round(tick_hz_d)) > 1e-9) {
    throw UsageError("pwm_hz / slow_loop_div must be a whole number of hertz");
  }
  const double load = P.get("load_nm");
  const std::function<double(double)> load_fn = [load](double) { return load; };
  const auto substeps = static_cast<int>(P.get("substeps"));
  const std::unique_ptr<AppTarget> target =
      make_file_target(ctx, f, p_scn, load != 0.0 ? &load_fn : nullptr, [&](AppSetup& s) {
        s.board.substeps = substeps;
        s.tm_budget_frac = static_cast<float>(P.get("budget_pct") / 100.0);
        for (int i = 0; i < MC_TM_COUNT - MC_TM_OBSERVER; ++i) {
          s.tm_ext_rate_hz[i] = static_cast<uint16_t>(P.get(kSlotParam[MC_TM_OBSERVER + i]));
        }
        s.flash = ctx.flash != nullptr ? ctx.flash->hal() : nullptr;
        // its own rule (the file comment): a store it cannot boot boots the
        // scenario's settings, and the stored values win over --set
        s.flash_must_boot = false;
        s.over_stored.clear();
      });
  AppTarget& t = *target;
  const uint32_t boot = t.probe().boot_status;
  if (ctx.flash != nullptr && boot != MC_CFG_BOOT_STORED && boot != MC_CFG_BOOT_MIGRATED &&
      boot != MC_CFG_BOOT_EMPTY) {
    std::fprintf(stderr,
                 "mcsim: %s: no usable configuration (boot status %s): the "
                 "scenario's settings\n",
                 ctx.flash->path().c_str(), kBootName[std::min<uint32_t>(boot, 6u)]);
  }

  // CAN: a candump log, SocketCAN or a socketcand server (sim/cli/can_bus.hpp).
  hal_host::PmsmBoard& board = t.board();
  const bool realtime = P.get("realtime") != 0.0;
  const std::unique_ptr<hal_host::CanTransport> can_bus =
      open_can_bus(board, realtime, ctx.out_dir);
  const mc_hal_can_t* bus = can_bus->hal();

  const std::vector<std::string> cols = csv_columns();
  ctx.csv.columns(cols);
  TmRecord rec(t.params().can_node_id);
  // end_after_stop_s > 0: end the run that long after a CAN-commanded run
  // stopped (timeout, disable or fault), for scripted tests whose command
  // timing depends on a slow machine.
  const double end_after_stop_s = P.get("end_after_stop_s");
  bool was_enabled = false;
  double t_end_early = -1.0;
  const long n = step_count(ctx.duration_s, board.period_s());
  const auto wall0 = std::chrono::steady_clock::now();
  uint64_t slow_steps = 0;
  uint32_t rx_read_max = 0;  // the most frames the bus delivered to one period
  std::vector<mc_hal_can_frame_t> rx, tx;
  std::vector<double> row(cols.size());
  for (long k = 1; k <= n; ++k) {
    // The frames the bus delivered by the start of the period, one period
    // of the target, its frames to the bus (stamped with the period's end).
    rx.clear();
    tx.clear();
    mc_hal_can_frame_t fr;
    while (mc_hal_can_receive(bus, &fr) == 0) rx.push_back(fr);
    rx_read_max = std::max(rx_read_max, static_cast<uint32_t>(rx.size()));
    const AppTargetPeriod ap = t.period(rx, &tx);
    for (const mc_hal_can_frame_t& x : tx) rec.frame(x, mc_hal_can_send(bus, &x) != 0);
    if (!ap.slow_ran) continue;
    ++slow_steps;
    size_t c = 0;
    double id_true, iq_true;
    board.true_dq_a(&id_true, &iq_true);
    row[c++] = board.t_s();
    row[c++] = rec.sent_mask;
    row[c++] = rec.fail_mask;
    row[c++] = board.state()(2);
    row[c++] = iq_true;
    row[c++] = board.state()(3);  // multi-turn, from the start angle (0)
    for (const auto& v : rec.held) {
      for (double x : v) row[c++] = x;
    }
    rec.sent_mask = rec.fail_mask = 0;
    ctx.csv.row(row);
    if (realtime) {
      std::this_thread::sleep_until(wall0 + std::chrono::duration<double>(board.t_s()));
    }
    if ((slow_steps & 255u) == 0) ctx.progress.update(board.t_s(), ctx.duration_s);
    if (end_after_stop_s > 0.0) {
      const bool enabled = t.probe().cmd_enabled != 0u;
      if (was_enabled && !enabled && t_end_early < 0.0)
        t_end_early = board.t_s() + end_after_stop_s;
      was_enabled = enabled;
      if (t_end_early >= 0.0 && board.t_s() >= t_end_early) break;
    }
  }
  ctx.summary.set("t_end_s", board.t_s());
  close_can_bus(*can_bus, ctx.summary);
  write_summary(ctx, t, p_scn, rec, rx_read_max);
}

// The CAN side's parameters, the same for every motor.
std::vector<ParamSpec> can_params() {
  return {{"node_id", 1.0, "1", "CAN node id (id = node << 5 | cmd)", 0.0, 62.0},
          {"bitrate_kbps", 1000.0, "kbit/s", "bus bit rate for the budget check", 10.0, 1000.0},
          {"budget_pct", 50.0, "%", "share of the bus the telemetry may use", 1.0, 70.0},
          {"rate_heartbeat_hz", 10.0, "Hz", "HEARTBEAT rate (at least 1 Hz)", 1.0, 1000.0},
          {"rate_currents_hz", 200.0, "Hz", "CURRENTS rate", 0.0, 1000.0},
          {"rate_voltages_hz", 100.0, "Hz", "VOLTAGES rate", 0.0, 1000.0},
          {"rate_speed_hz", 100.0, "Hz", "SPEED rate", 0.0, 1000.0},
          {"rate_position_hz", 50.0, "Hz", "POSITION rate", 0.0, 1000.0},
          {"rate_observer_hz", 0.0, "Hz", "OBSERVER rate (sent while the sensorless law runs)", 0.0,
           1000.0},
          {"rate_controller_hz", 0.0, "Hz", "CONTROLLER rate (nothing sent here)", 0.0, 1000.0},
          {"rate_stepper_hz", 0.0, "Hz", "STEPPER rate (nothing sent here)", 0.0, 1000.0},
          {"rate_current_refs_hz", 100.0, "Hz", "CURRENT_REFS rate", 0.0, 1000.0},
          {"rate_position_ref_hz", 50.0, "Hz", "POSITION_REF rate", 0.0, 1000.0},
          {"rate_bus_current_hz", 0.0, "Hz", "BUS_CURRENT rate", 0.0, 1000.0},
          {"rate_thermal_hz", 0.0, "Hz", "THERMAL rate", 0.0, 1000.0},
          {"timeout_s", 0.5, "s", "command timeout while enabled", 0.001, 60.0},
          {"stop_ramp_a_per_s", 20.0, "A/s", "current ramp of a safe stop", 0.01, 1e6},
          {"speed_law", 0.0, "1",
           "law of SPEED mode (parameter speed_law): 0 sensored PI, 1 sensorless (I-f start), "
           "2 PI2D",
           0.0, 2.0},
          {"realtime", 0.0, "1", "1: pace the simulation to the wall clock", 0.0, 1.0},
          {"end_after_stop_s", 0.0, "s",
           "if > 0, end the run this long after a CAN-enabled run stopped (timeout, disable, "
           "fault)",
           0.0, 100.0},
          {"substeps", 2.0, "1", "RK4 sub-steps per PWM period", 1.0, 64.0}};
}

// Without --motor: the paper-002 test motor on its 200 V board.
std::vector<ParamSpec> own_params() {
  std::vector<ParamSpec> v = can_params();
  const std::vector<ParamSpec> own = {
      {"stop_decel_rad_s2", 200.0, "rad/s^2", "speed ramp of a safe stop", 0.01, 1e6},
      {"speed_max_rad_s", 150.0, "rad/s", "largest speed reference accepted", 0.1, 1000.0},
      {"speed_bw_rad_s", 0.0, "rad/s",
       "crossover of the speed loops (parameter speed_bw_rad_s; 0: derived, min(current_bw / 10, "
       "speed_pll_bw / 4))",
       0.0, 500.0},
      {"speed_ramp_rad_s2", 0.0, "rad/s^2",
       "speed reference ramp (parameter speed_ramp_rad_s2; 0: derived, half the current limit's "
       "acceleration)",
       0.0, 1.0e6},
      {"pwm_hz", 10000.0, "Hz", "PWM and current-loop rate", 1000.0, 100000.0},
      {"slow_loop_div", 10.0, "1", "slow loop (CAN) every this many PWM periods", 1.0, 1000.0},
      {"bw_hz", 200.0, "Hz", "designed current-loop bandwidth", 1.0, 2000.0},
      {"speed_pll_bw_rad_s", 1000.0, "rad/s",
       "encoder tracking loop bandwidth (3 bw / pwm_hz <= 1)", 1.0, 6000.0},
      {"J_kgm2", 0.05, "kg m^2",
       "rotor + load inertia (a flywheel: 1 A accelerates it at 13 rad/s^2)", 1.0e-7, 100.0},
      {"load_nm", 0.0, "N m", "constant load torque", -10.0, 10.0}};
  v.insert(v.end(), own.begin(), own.end());
  return v;
}

// With --motor/--board: the gain keys of the generic scenarios (the table's
// parameters: app_gain_params, current_bw_rad_s, speed_pll_bw_rad_s,
// stop_decel_rad_s2, ...), the speed limit from the motor
// file; pwm_hz and J from the files (--set board.pwm_hz=, motor.j_kgm2=).
std::vector<ParamSpec> file_params(const MotorFiles& f) {
  std::vector<ParamSpec> v = can_params();
  const double torque_max_nm = 1.5 * f.motor.pole_pairs * f.motor.flux_wb * f.motor.i_max_a;
  const std::vector<ParamSpec> own = {
      {"speed_max_rad_s", f.motor.speed_max_rad_s, "rad/s",
       "largest speed reference accepted (the motor file's speed_max_rad_s)", 0.1, 10000.0},
      {"speed_bw_rad_s", 0.0, "rad/s",
       "crossover of the speed loops (parameter speed_bw_rad_s; 0: derived, min(current_bw / 10, "
       "speed_pll_bw / 4))",
       0.0, 1.0e4},
      {"speed_ramp_rad_s2", 0.0, "rad/s^2",
       "speed reference ramp (parameter speed_ramp_rad_s2; 0: derived, half the current limit's "
       "acceleration)",
       0.0, 1.0e6},
      {"slow_loop_div", std::max(1.0, std::round(f.board.pwm_hz / 1000.0)), "1",
       "slow loop (CAN) every this many PWM periods (about 1 kHz)", 1.0, 1000.0},
      {"load_nm", 0.0, "N m", "constant load torque (at most the current limit's torque)",
       -torque_max_nm, torque_max_nm}};
  v.insert(v.end(), own.begin(), own.end());
  // the table's gain keys, those above kept (their 0 is the table's "derived")
  for (const ParamSpec& g : app_gain_params(f)) {
    if (std::none_of(v.begin(), v.end(), [&](const ParamSpec& k) { return k.key == g.key; })) {
      v.push_back(g);
    }
  }
  return v;
}

Scenario make_scenario() {
  Scenario s{"can-telemetry",
             "FOC drive (paper-002 test motor, or --motor FILE [--board FILE]) with CAN "
             "telemetry and commands: frames to SocketCAN (MCSIM_CAN_IF=vcan0), a socketcand "
             "server (MCSIM_CAN_IF=socketcand:127.0.0.1:29536) or a candump log "
             "(MCSIM_CAN_LOG; commands from MCSIM_CAN_CMDS)",
             2.0,
             own_params(),
             run_can_telemetry,
             file_params,
             true};
  s.motor_optional = true;
  return on_app_target(s);
}

const Registrar reg_can(make_scenario());

}  // namespace
}  // namespace mcsim
