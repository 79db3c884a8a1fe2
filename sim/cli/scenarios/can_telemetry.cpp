// Scenario can-telemetry: the FOC drive on the simulated board with the
// drive application of the MCU image (firmware/app/app/mc_app: CAN receive
// ring, command handler, telemetry, command timeout, parameter service and
// flash configuration, sensored speed loop) bound to it; this file only binds
// the application to the simulated board, its CAN and its flash file.
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
// The motor and board: the paper-002 test motor on FocSil's 200 V board
// (no --motor), or any motor and board of sim/motors/ (--motor FILE
// [--board FILE], MotorRig of drive_setup.hpp: the plant, sensors and the
// drive's limits from the files, the gains of drive_setup.hpp and every one
// of them settable with --set; the speed PI's defaults are the derived
// speed_wc_rad_s and i_limit_a, speed_max_rad_s the derived speed limit).
//
// With --set realtime=1 the loop is paced to the wall clock (needed when
// people or scripts send commands on a live interface).
//
// The CSV has one row per slow-loop step: the values every telemetry
// message carried (or would carry) at that step, as "<MESSAGE>.<signal>",
// with the mask of the frames generated (tm_sent_mask, bit = slot) and of
// those the HAL refused (tm_fail_mask), so a logger's decoded frames can be
// matched one for one.
//
// The control laws are the application's, built from the parameters as on
// the MCU (mc_app_cfg_t.laws_from_params, firmware/app/config/mc_law_cfg.h):
// SPEED runs the law of the speed_law parameter (--set speed_law=N, or the
// stored value with --flash): 0 the application's sensored speed PI (at the
// slow rate, writing the current references in the drive's CURRENT mode,
// gains below), 1 the sensorless law (flux observer + PLL, I-f start from
// standstill), 2 PI2D; POSITION the position cascade
// (firmware/app/ctrl/mc_ctrl_position: trapezoid to the multi-turn target
// of SET_POSITION_REF, at speed_max_rad_s and stop_decel_rad_s2). Their
// gains come from the motor values (mc_gains.c).
//
// Parameters (PARAM_REQ/PARAM_REPLY) are served as on the MCU: the
// parameter service (firmware/app/config/mc_param_srv) on the drive, with
// the configuration store on the board's flash when mcsim runs with
// --flash FILE (hal_host::FileFlash). The scenario's settings, as a
// parameter set (scenario_params below), are this board's defaults (what
// mc_params_default is on the MCU: the table's defaults describe a 48 V
// board, not this 200 V one). Boot, with --flash: mc_cfg_store_load; with a
// STORED or MIGRATED record the stored set replaces the scenario's settings
// for everything the firmware configures (gains from current_bw_rad_s,
// pwm_hz, slow_loop_div, limits, trips, CAN node id, bit rate, timeout,
// ramps, speed limit, telemetry rates: the stored value wins over --set,
// as a flashed drive ignores how it was shipped); any other status boots
// the scenario's settings and says so. The plant and the board's hardware
// (motor, inertia, load, bus voltage, sensors) stay the scenario's: the
// flash configures the drive, not the motor it is wired to. A SAVE writes
// the file. On this board pwm_hz and slow_loop_div cannot change by APPLY
// during a run (the simulated PWM period and CAN tick are fixed at start):
// such an APPLY is refused INVALID (MC_PARAMS_ERR_DRIVE). Without --flash
// the service runs without a store (SAVE answers STORE), and with settings
// outside the parameter table (e.g. rate_heartbeat_hz=500, a 10 kbit/s bus)
// without the service (PARAM_REQ: UNSUPPORTED).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "app_binding.hpp"
#include "can_bus.hpp"
#include "drive_setup.hpp"
#include "foc_sil.hpp"
#include "hal_host/app_rig.hpp"
#include "hal_host/file_flash.hpp"
#include "scenario.hpp"
#include "verdict.hpp"
extern "C" {
#include "commission/mc_comm_can.h"
#include "mc_app.h"
#include "mc_can_proto.h"
#include "mc_params.h"
}

namespace mcsim {
namespace {

const char* const kSlotParam[MC_TM_COUNT] = {
    "rate_heartbeat_hz",    "rate_currents_hz",    "rate_voltages_hz",   "rate_speed_hz",
    "rate_position_hz",     "rate_observer_hz",    "rate_controller_hz", "rate_stepper_hz",
    "rate_current_refs_hz", "rate_position_ref_hz"};
const char* const kSlotName[MC_TM_COUNT] = {"HEARTBEAT",    "CURRENTS",    "VOLTAGES",   "SPEED",
                                            "POSITION",     "OBSERVER",    "CONTROLLER", "STEPPER",
                                            "CURRENT_REFS", "POSITION_REF"};
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
    {"theta_ref_rad", "sat", "seq"}};

std::string env_or(const char* name, const std::string& fallback) {
  const char* v = std::getenv(name);
  return (v != nullptr && *v != '\0') ? std::string(v) : fallback;
}

const char* const kBootName[] = {"STORED", "MIGRATED", "EMPTY", "CORRUPT",
                                 "LAYOUT", "INVALID",  "FLASH"};

// The simulated motor, board and drive: FocSil (paper-002 test motor) or
// MotorRig (the --motor/--board files). o holds the rates, inertia, bus and
// bandwidths the rest of the scenario reads, for both.
struct CanBoard {
  FocSilOptions o;
  double kt_nm_a = 0, b_nm_s_rad = 0, i_sense_max_a = 0, dead_time_s = 0;
  double i_rated_a = 0, speed_rated_rad_s = 0;  // the laws' gains scale with them
  uint32_t adc_bits = 12, encoder_cpr = 0;
  std::unique_ptr<FocSil> sil;
  std::unique_ptr<MotorRig> rig;
  void step() const { sil ? sil->step() : rig->step(); }
  hal_host::PmsmBoard& board() const { return sil ? sil->board() : rig->board(); }
  mc_drive_t& drive() const { return sil ? sil->drive() : rig->drive(); }
};

// (Re)build the board for o (pwm_hz, slow_loop_div, bandwidths may come
// from the flash).
void build_board(CanBoard& cb, const RunContext& ctx) {
  if (ctx.files == nullptr) {
    const PmsmParams m = paper002_test_motor();
    cb.kt_nm_a = 1.5 * m.pole_pairs * m.flux_wb;
    cb.b_nm_s_rad = m.B_nms_rad;
    cb.i_rated_a = 4.24;            // paper 002 Table I: 3 A rms
    cb.speed_rated_rad_s = 104.72;  // 1000 r/min
    cb.i_sense_max_a = 20.0;        // FocSil's board: 12-bit, 20 A, 8192 counts
    cb.adc_bits = 12u;
    cb.encoder_cpr = 8192u;
    cb.dead_time_s = 0.0;  // the average-value inverter has none here
    cb.sil = std::make_unique<FocSil>(cb.o);
    return;
  }
  MotorFiles f = *ctx.files;
  f.board.pwm_hz = cb.o.pwm_hz;
  Gains g = derive_gains(f, &ctx.params);
  g.cur_bw_rad_s = cb.o.bw_rad_s;
  g.enc_pll_bw_rad_s = cb.o.speed_pll_bw_rad_s;
  cb.kt_nm_a = g.kt_nm_a;
  cb.b_nm_s_rad = f.motor.b_nm_s_rad;
  cb.i_rated_a = f.motor.i_rated_a;
  cb.speed_rated_rad_s = f.motor.speed_rated_rad_s;
  cb.i_sense_max_a = f.board.i_sense_max_a;
  cb.adc_bits = static_cast<uint32_t>(f.board.adc_bits);
  cb.encoder_cpr = static_cast<uint32_t>(f.board.encoder_cpr);
  cb.dead_time_s = f.board.dead_time_s;
  RigOptions ro;
  ro.law = Law::kCurrent;
  const double load = ctx.params.get("load_nm");
  ro.load_nm = [load](double) { return load; };
  const int substeps = static_cast<int>(ctx.params.get("substeps"));
  ro.board_hook = [substeps](hal_host::PmsmBoardConfig& bc) { bc.substeps = substeps; };
  const unsigned div = cb.o.slow_loop_div;
  ro.drive_hook = [div](mc_drive_cfg_t& dc) { dc.slow_loop_div = div; };
  cb.rig = std::make_unique<MotorRig>(f, g, ro);
}

CanBoard make_board(const RunContext& ctx) {
  const auto& P = ctx.params;
  CanBoard cb;
  FocSilOptions& o = cb.o;
  o.substeps = static_cast<int>(P.get("substeps"));
  o.slow_loop_div = static_cast<unsigned>(P.get("slow_loop_div"));
  o.load_nm = P.get("load_nm");
  if (ctx.files == nullptr) {
    o.pwm_hz = P.get("pwm_hz");
    o.J_kgm2 = P.get("J_kgm2");
    o.bw_rad_s = 2.0 * 3.14159265358979 * P.get("bw_hz");
    o.speed_pll_bw_rad_s = P.get("speed_pll_bw_rad_s");
  } else {
    const MotorFiles& f = *ctx.files;
    o.pwm_hz = f.board.pwm_hz;
    o.J_kgm2 = f.motor.j_kgm2;
    o.vbus_v = f.board.vbus_v;
    o.three_shunts = f.board.current_sensors == 3;
    o.delay_periods = f.board.delay_periods;
    o.bw_rad_s = P.get("cur_bw_rad_s");
    o.speed_pll_bw_rad_s = P.get("enc_pll_bw_rad_s");
  }
  build_board(cb, ctx);
  return cb;
}

// The scenario's settings and the drive configuration FocSil or MotorRig
// built from them, as a parameter set (the board's defaults; see the header).
mc_params_t scenario_params(const Params& P, const CanBoard& cb, const mc_drive_cfg_t& c) {
  mc_params_t p = mc_params_default;
  const FocSilOptions& o = cb.o;
  p.r_ohm = c.foc.r_ohm;
  p.ld_h = c.foc.ld_h;
  p.lq_h = c.foc.lq_h;
  p.flux_wb = c.foc.flux_wb;
  p.pole_pairs = c.pole_pairs;
  p.j_kgm2 = static_cast<float>(o.J_kgm2);
  p.b_nm_s_rad = static_cast<float>(cb.b_nm_s_rad);
  p.i_rated_a = static_cast<float>(cb.i_rated_a);
  p.speed_rated_rad_s = static_cast<float>(cb.speed_rated_rad_s);
  p.speed_law = static_cast<uint32_t>(P.get("speed_law"));
  p.i_max_a = c.i_max_a;
  p.speed_max_rad_s = static_cast<float>(P.get("speed_max_rad_s"));
  p.vbus_v = static_cast<float>(o.vbus_v);
  p.pwm_hz = static_cast<uint32_t>(std::lround(o.pwm_hz));
  p.dead_time_s = static_cast<float>(cb.dead_time_s);
  p.current_sensors = o.three_shunts ? 3u : 2u;
  p.i_sense_max_a = static_cast<float>(cb.i_sense_max_a);
  p.adc_bits = cb.adc_bits;
  p.encoder_cpr = cb.encoder_cpr;
  p.current_bw_rad_s = static_cast<float>(o.bw_rad_s);
  p.v_limit_ratio = c.foc.v_limit_ratio;
  p.slow_loop_div = c.slow_loop_div;
  p.speed_pll_bw_rad_s = c.speed_pll_bw_rad_s;
  p.encoder_offset_rad = c.encoder_offset_rad;
  p.encoder_reversed = c.encoder_reversed ? 1u : 0u;
  p.i_offset_a_a = c.i_offset_a[0];
  p.i_offset_b_a = c.i_offset_a[1];
  p.i_offset_c_a = c.i_offset_a[2];
  p.i_trip_a = c.i_trip_a;
  p.vbus_min_v = c.vbus_min_v;
  p.vbus_max_v = c.vbus_max_v;
  p.omega_max_rad_s = c.omega_max_rad_s;
  p.temp_max_c = c.temp_max_c;
  p.stall_current_frac = c.stall_current_frac;
  p.stall_speed_rad_s = c.stall_speed_rad_s;
  p.stall_time_s = c.stall_time_s;
  p.i_unbalance_max_a = c.i_unbalance_max_a;
  p.open_phase_i_min_a = c.open_phase_i_min_a;
  p.open_phase_time_s = c.open_phase_time_s;
  p.can_node_id = static_cast<uint32_t>(P.get("node_id"));
  p.can_bitrate_bps = static_cast<uint32_t>(P.get("bitrate_kbps") * 1000.0);
  p.can_timeout_s = static_cast<float>(P.get("timeout_s"));
  p.stop_ramp_a_per_s = static_cast<float>(P.get("stop_ramp_a_per_s"));
  p.stop_decel_rad_s2 = static_cast<float>(P.get("stop_decel_rad_s2"));
  // the speed law's crossover (its gains derive from it and J) and the
  // speed reference's ramp
  p.speed_bw_rad_s = static_cast<float>(P.get("speed_bw_rad_s"));
  p.speed_ramp_rad_s2 = static_cast<float>(P.get("speed_ramp_rad_s2"));
  // the position move as this scenario always ran it: cruise at the speed
  // limit, accelerate and decelerate at the stop's rate
  p.traj_v_max_rad_s = p.speed_max_rad_s;
  p.traj_a_max_rad_s2 = p.stop_decel_rad_s2;
  p.traj_d_max_rad_s2 = p.stop_decel_rad_s2;
  p.tm_heartbeat_hz = static_cast<uint32_t>(P.get("rate_heartbeat_hz"));
  p.tm_currents_hz = static_cast<uint32_t>(P.get("rate_currents_hz"));
  p.tm_voltages_hz = static_cast<uint32_t>(P.get("rate_voltages_hz"));
  p.tm_speed_hz = static_cast<uint32_t>(P.get("rate_speed_hz"));
  p.tm_position_hz = static_cast<uint32_t>(P.get("rate_position_hz"));
  return p;
}

void run_can_telemetry(RunContext& ctx) {
  const auto& P = ctx.params;
  CanBoard cb = make_board(ctx);
  FocSilOptions& o = cb.o;
  // Boot: the configuration (see the header).
  const mc_params_t p_scn = scenario_params(P, cb, cb.drive().cfg);
  const uint32_t scn_err = mc_params_validate(&p_scn);
  if (ctx.flash != nullptr && scn_err != MC_PARAMS_OK) {
    throw UsageError(
        "with --flash the scenario's settings are the board's defaults and must "
        "form a valid parameter set (firmware/app/config/PARAMS.md); "
        "mc_params_validate refuses them: MC_PARAMS_ERR bits 0x" +
        std::to_string(scn_err));
  }
  auto app_ptr = std::make_unique<mc_app_t>();
  mc_app_t& app = *app_ptr;
  mc_app_cfg_t acfg{};
  acfg.flash = ctx.flash != nullptr ? ctx.flash->hal() : nullptr;
  acfg.flash_sectors[0] = 0u;
  acfg.flash_sectors[1] = 1u;
  acfg.defaults = &p_scn;
  acfg.tm_budget_frac = static_cast<float>(P.get("budget_pct") / 100.0);
  for (int i = 0; i < MC_TM_COUNT - MC_TM_OBSERVER; ++i) {
    acfg.tm_ext_rate_hz[i] = static_cast<uint16_t>(P.get(kSlotParam[MC_TM_OBSERVER + i]));
  }
  if ((mc_app_boot(&app, &acfg) & MC_APP_CFG_ERR_STORE) != 0u) {
    throw std::logic_error("configuration store refused the flash file's sectors");
  }
  const mc_params_t& p = app.params;
  const auto boot = static_cast<mc_cfg_boot_t>(app.boot_status);
  if (ctx.flash != nullptr) {
    if (boot != MC_CFG_BOOT_STORED && boot != MC_CFG_BOOT_MIGRATED && boot != MC_CFG_BOOT_EMPTY) {
      std::fprintf(stderr,
                   "mcsim: %s: no usable configuration (boot status %s): the "
                   "scenario's settings\n",
                   ctx.flash->path().c_str(), kBootName[boot]);
    }
    if (p.pwm_hz != p_scn.pwm_hz || p.slow_loop_div != p_scn.slow_loop_div) {
      o.pwm_hz = static_cast<double>(p.pwm_hz);
      o.slow_loop_div = p.slow_loop_div;
      o.bw_rad_s = static_cast<double>(p.current_bw_rad_s);
      o.speed_pll_bw_rad_s = static_cast<double>(p.speed_pll_bw_rad_s);
      build_board(cb, ctx);
    }
  }
  mc_drive_t& d = cb.drive();
  // The parameter service needs the drive to run exactly its parameters
  // (the application initialises it from them).
  const bool serve_params = scn_err == MC_PARAMS_OK;
  const double tick_hz_d = o.pwm_hz / o.slow_loop_div;
  if (std::fabs(tick_hz_d - std::round(tick_hz_d)) > 1e-9) {
    throw UsageError("pwm_hz / slow_loop_div must be a whole number of hertz");
  }
  const uint32_t tick_hz = static_cast<uint32_t>(std::lround(tick_hz_d));

  // CAN: a candump log, SocketCAN or a socketcand server (sim/cli/can_bus.hpp).
  hal_host::PmsmBoard& board = cb.board();
  const std::unique_ptr<hal_host::CanTransport> can_bus =
      open_can_bus(board, P.get("realtime") != 0.0, ctx.out_dir);
  const mc_hal_can_t* can = can_bus->hal();

  // The laws of SPEED (speed_law) and POSITION from the parameters.
  app.cfg.laws_from_params = true;
  const uint32_t aerr = mc_app_start(&app, &d, board.hal(), can, serve_params);
  if ((aerr & MC_APP_CFG_ERR_TM) != 0u) {
    throw UsageError("telemetry configuration refused (MC_TM_CFG bits 0x" +
                     std::to_string(app.tm_err) + "), bus load " +
                     std::to_string(100.0 * mc_telemetry_bus_load(&app.tm_cfg)) + " % of " +
                     std::to_string(app.tm_cfg.bitrate_bps) + " bit/s, budget " +
                     std::to_string(P.get("budget_pct")) + " %");
  }
  if ((aerr & MC_APP_CFG_ERR_CMD) != 0u) {
    throw UsageError("command handler configuration refused (MC_CAN_CMD_CFG bits 0x" +
                     std::to_string(app.cmd_err) + ")");
  }
  if (aerr != MC_APP_CFG_OK) {
    throw std::logic_error("the application refused a validated configuration (MC_APP_CFG 0x" +
                           std::to_string(aerr) + ")");
  }
  mc_telemetry_t& tm = app.tm;
  const mc_can_cmd_t& cmd = app.cmd;
  const mc_telemetry_src_t& src = app.tm_src;
  // Commissioning over CAN (COMMISSION_CMD, firmware/app/commission/
  // mc_comm_can.h): the board's test limits as in the commission scenario,
  // the results staged in the parameter service (when it is served).
  static mc_comm_t comm;  // large; one run at a time
  mc_comm_can_t comm_can{};
  {
    const double T = 1.0 / o.pwm_hz;
    mc_comm_can_cfg_t k{};
    k.base.dt_s = static_cast<float>(T);
    k.base.i_test_a = static_cast<float>(0.25 * p.i_sense_max_a);
    k.base.v_test_max_v = static_cast<float>(0.9 * o.vbus_v / std::sqrt(3.0));
    k.base.offset_max_a = static_cast<float>(0.1 * p.i_sense_max_a);
    k.base.dead_time_s = p.dead_time_s;
    k.base.cur_bw_rad_s = static_cast<float>(0.08 / T);
    k.base.speed_max_m_rad_s = p.speed_max_rad_s;
    k.base.bemf_frac = 0.5f;
    k.base.pole_pairs_max = 32;
    k.base.three_shunts = o.three_shunts;
    k.node_id = static_cast<uint8_t>(p.can_node_id);
    k.status_div = std::max<uint32_t>(1u, tick_hz / 10u);
    k.enc_pll_bw_rad_s = p.speed_pll_bw_rad_s;
    if (mc_comm_can_init(&comm_can, &k, &comm, &d, serve_params ? &app.srv : nullptr) !=
        MC_COMM_CAN_CFG_OK) {
      throw UsageError("commissioning refused its configuration for this board");
    }
    mc_app_attach_commission(&app, &comm_can);
  }

  // MCSIM_APP_BINDING_OUT=FILE: this binding, for the processor-in-the-loop
  // twin (sim/cli/app_binding.hpp, tests/target/pil/test_pil_can.cpp).
  if (const std::string out = env_or("MCSIM_APP_BINDING_OUT", ""); !out.empty()) {
    AppBinding ab;
    ab.plant = o;
    ab.defaults = p_scn;
    ab.tm_budget_frac = app.cfg.tm_budget_frac;
    std::copy(std::begin(app.cfg.tm_ext_rate_hz), std::end(app.cfg.tm_ext_rate_hz),
              std::begin(ab.tm_ext_rate_hz));
    ab.pwm_hz_fixed = app.cfg.pwm_hz_fixed;
    ab.slow_loop_div_fixed = app.cfg.slow_loop_div_fixed;
    ab.serve_params = serve_params;
    ab.position_law = app.cfg.position_law.ctrl != nullptr;
    ab.commissioning = app.comm != nullptr;
    write_app_binding(out, ab);
  }

  std::vector<std::string> cols{
      "t", "tm_sent_mask", "tm_fail_mask", "omega_m_true_rad_s", "i_q_true_a", "theta_m_true_rad"};
  for (int i = 0; i < MC_TM_COUNT; ++i) {
    const uint32_t msg = mc_telemetry_msg(static_cast<uint32_t>(i));
    if (kSlotSignals[i].size() != mc_can_messages[msg].n_signals) {
      throw std::logic_error(std::string("signal list of ") + kSlotName[i] + " out of date");
    }
    for (const auto& s : kSlotSignals[i]) cols.push_back(std::string(kSlotName[i]) + "." + s);
  }
  ctx.csv.columns(cols);

  const bool realtime = P.get("realtime") != 0.0;
  // end_after_stop_s > 0: end the run that long after a CAN-commanded run
  // stopped (timeout, disable or fault), for scripted tests whose command
  // timing depends on a slow machine.
  const double end_after_stop_s = P.get("end_after_stop_s");
  bool was_enabled = false;
  double t_end_early = -1.0;
  const double T = board.period_s();
  const long n = step_count(ctx.duration_s, T);
  const auto wall0 = std::chrono::steady_clock::now();
  uint64_t frames = 0, slow_steps = 0;
  uint32_t rx_read_max = 0;  // frames taken from the HAL by one receive call
  std::vector<double> row(cols.size());
  for (long k = 1; k <= n; ++k) {
    // One period as the image's interrupts run it (hal_host::app_period):
    // the CAN receive interrupt, the fast step, the slow step when due.
    const hal_host::AppPeriod ap = hal_host::app_period(board, app);
    rx_read_max = std::max(rx_read_max, ap.rx_frames);
    if (!ap.slow_ran) continue;
    const uint32_t sent = app.tm_sent;
    ++slow_steps;
    frames += static_cast<uint64_t>(__builtin_popcount(sent));

    size_t c = 0;
    double id_true, iq_true;
    board.true_dq_a(&id_true, &iq_true);
    row[c++] = board.t_s();
    row[c++] = sent;
    row[c++] = tm.last_fail_mask;
    row[c++] = board.state()(2);
    row[c++] = iq_true;
    row[c++] = board.state()(3);  // multi-turn, from the start angle (0)
    for (uint32_t i = 0; i < MC_TM_COUNT; ++i) {
      float v[MC_CAN_NSIG_MAX] = {0};
      const bool have = mc_telemetry_values(i, &src, v);
      const uint32_t ns = mc_can_messages[mc_telemetry_msg(i)].n_signals;
      const bool was_sent = (sent >> i) & 1u;
      v[ns - 1] = static_cast<float>(was_sent ? static_cast<uint8_t>(tm.seq[i] - 1u) : tm.seq[i]);
      for (uint32_t j = 0; j < ns; ++j) row[c++] = have ? static_cast<double>(v[j]) : std::nan("");
    }
    ctx.csv.row(row);
    if (realtime) {
      std::this_thread::sleep_until(wall0 + std::chrono::duration<double>(board.t_s()));
    }
    if ((slow_steps & 255u) == 0) ctx.progress.update(board.t_s(), ctx.duration_s);
    if (end_after_stop_s > 0.0) {
      if (was_enabled && !cmd.enabled && t_end_early < 0.0)
        t_end_early = board.t_s() + end_after_stop_s;
      was_enabled = cmd.enabled;
      if (t_end_early >= 0.0 && board.t_s() >= t_end_early) break;
    }
  }
  ctx.summary.set("t_end_s", board.t_s());
  close_can_bus(*can_bus, ctx.summary);

  ctx.summary.set("tick_hz", tick_hz);
  ctx.summary.set("bus_load_frac", tm.load_frac);
  ctx.summary.set("tm_frames_generated", static_cast<double>(frames));
  ctx.summary.set("tm_frames_queued", tm.tx_frames);
  ctx.summary.set("tm_frames_dropped", tm.tx_dropped);
  ctx.summary.set("tm_tx_nobufs", tm.tx_nobufs);
  ctx.summary.set("tm_tx_busoff", tm.tx_busoff);
  ctx.summary.set("cmd_accepted", cmd.rx_accepted);
  ctx.summary.set("cmd_rejected", cmd.rx_rejected);
  ctx.summary.set("cmd_reply_dropped", cmd.reply_dropped);
  ctx.summary.set("cmd_reply_limited", cmd.reply_limited);
  // foreign frames: dropped by the application's receive path (before the
  // ring) or by the command handler's own filter
  ctx.summary.set("cmd_rx_foreign", app.rx_foreign + cmd.rx_foreign);
  ctx.summary.set("cmd_poll_frames_max", std::max(rx_read_max, cmd.poll_max));
  // the receive interrupt's part: foreign frames dropped there (before the
  // ring and the command handler), own frames lost to a full ring, and the
  // most frames one call took from the HAL
  ctx.summary.set("app_rx_foreign", app.rx_foreign);
  ctx.summary.set("app_rx_overflows", app.rx_overflows);
  ctx.summary.set("app_rx_read_max", rx_read_max);
  ctx.summary.set("tm_frames_saturated", tm.saturated);
  ctx.summary.set("final_mode", static_cast<double>(d.mode));
  ctx.summary.set("final_enabled", cmd.enabled ? 1.0 : 0.0);
  ctx.summary.set("final_stop_reason", cmd.stop_reason);
  ctx.summary.set("final_faults", d.faults);
  ctx.summary.set_text("final_fault_names", drive_fault_names(d.faults));
  // The laws (firmware/app/config/mc_law_cfg.h): which one SPEED ran, and
  // why one is not available (the law_error parameter).
  ctx.summary.set("speed_law", app.laws.speed_law);
  ctx.summary.set("law_error", app.laws.error);
  ctx.summary.set("sls_handovers", app.laws.sls.tm.handovers);
  if (ctx.flash != nullptr) {
    // What the drive booted from (cfg_from_store: ids of the parameters whose
    // stored value replaced the scenario's), and what the run did to the store.
    std::string from_store;
    for (const mc_param_info_t& entry : mc_param_table) {
      const mc_param_info_t* info = &entry;
      if (info->offset == MC_PARAM_NO_FIELD) continue;
      if (mc_param_get_raw(&p, info) != mc_param_get_raw(&p_scn, info)) {
        from_store += (from_store.empty() ? "" : ",") + std::to_string(info->id);
      }
    }
    ctx.summary.set_text("flash_file", ctx.flash->path());
    ctx.summary.set_text("cfg_boot_status", kBootName[boot]);
    ctx.summary.set("cfg_boot_code", static_cast<double>(boot));
    ctx.summary.set_text("cfg_from_store", from_store);
    ctx.summary.set("cfg_store_seq", app.store.seq);
    ctx.summary.set("cfg_saves", app.store.saves);
    ctx.summary.set("cfg_applied", app.srv.applied);
    ctx.summary.set("flash_persist_errors", ctx.flash->persist_errors());
  }
  CanTelemetryFigures fig;
  fig.tm_frames_dropped = tm.tx_dropped;
  fig.rx_overflows = app.rx_overflows;
  fig.flash_persist_errors = ctx.flash != nullptr ? ctx.flash->persist_errors() : 0.0;
  fig.final_faults = d.faults;
  write_verdict(ctx.summary, judge_can_telemetry(fig));
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

// Without --motor: the paper-002 test motor on FocSil's board.
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

// With --motor/--board: the gains of drive_setup.hpp (cur_bw_rad_s,
// enc_pll_bw_rad_s, stop_decel_rad_s2, ...), the speed PI and the limits
// from them; pwm_hz and J from the files (--set board.pwm_hz=,
// motor.j_kgm2=).
std::vector<ParamSpec> file_params(const MotorFiles& f) {
  const Gains g = derive_gains(f, nullptr);
  std::vector<ParamSpec> v = can_params();
  const double torque_max_nm = g.kt_nm_a * g.i_limit_a;
  const std::vector<ParamSpec> own = {
      {"speed_max_rad_s", g.speed_limit_rad_s, "rad/s",
       "largest speed reference accepted (derived: speed_limit_rad_s)", 0.1, 10000.0},
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
  const std::vector<ParamSpec> gains = gain_params(f);
  v.insert(v.end(), gains.begin(), gains.end());
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
  return s;
}

const Registrar reg_can(make_scenario());

}  // namespace
}  // namespace mcsim
