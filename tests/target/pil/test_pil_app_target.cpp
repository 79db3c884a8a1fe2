// The PIL AppTarget (sim/cli/app_target_pil.cpp) against the SIL, for any
// motor and board: the same drive application, booted from the same
// parameter table on the same plant (hal_host::PmsmBoardConfig from the
// motor file and the board's description, sim/cli/plant_from_files.hpp
// build_board_cfg), commanded by the same CAN frames (packed with the
// project's DBC encoders, mc_can_proto_pack), once compiled for the host and
// run through hal_host::app_period, once as the board's whole image on the
// emulated Cortex-M4F (mc_stm32f405_pil, QEMU netduinoplus2).
//
// The SIL side is the scenarios' (mcsim::make_app_target_sil,
// sim/cli/app_target_sil.cpp): app_period on the board, the application
// bound by app_target_binding as the PIL image binds it.
//
// Boards: the ODrive v3.6 (24 V variant) and the VESC 6, with the ODrive
// D5065 motor file (sim/motors/odrive-d5065.toml); the sensored speed law on
// both, the sensorless one on the VESC 6 too.
// The experiment (0.1 s simulated per board): enable in CURRENT at 5 ms, a
// q-current step of 20 % of the motor's rated current at 10 ms, disable and
// switch to SPEED at 40 ms, enable, a speed reference of 10 % of the rated
// speed at 42 ms. Every period, the application's probe (mc_app_probe_t)
// and the plant's state (currents, speed, angle; time) must be equal bit
// for bit (memcmp; tolerance 0: both sides run the same IEEE single
// precision code with -ffp-contract=off and the kernels' own math, the link
// carries floats as bit patterns, the plant is the same host code), and so
// must every CAN frame the application sent (id, length, payload, period).
//
// Also printed per board, as one JSON line each ("[pil-cost] {...}"), the
// PIL cost: wall seconds per simulated second of the lock-step run, with the
// SIL's for scale (a benchmark: machine and load dependent, never asserted,
// in no document; tools/docs/README.md).
#include <gtest/gtest.h>

#include <sys/stat.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "app_target.hpp"
#include "plant_from_files.hpp"
#include "mc_record.hpp"
#include "motor_file.hpp"
#include "pil_test_link.hpp"
#include "scenario.hpp"
extern "C" {
#include "mc_can_cmd.h"
#include "mc_can_dbc.h"
#include "mc_can_proto.h"
#include "mc_ctrl_sensorless.h"
#include "mc_pil_frame.h"
#include "mc_board_odrive36_gen.h"
#include "mc_board_vesc6_gen.h"
}

namespace {

constexpr double kDuration_s = 0.1;
const char* const kMotor = "odrive-d5065.toml";

// ---- the parameter table from the motor and board files ------------------
// (the boot configuration of both targets: the board's defaults with the
// motor's and board's values; every gain derived by the image's C builders)
mc_params_t params_from_files(const mcsim::MotorFiles& f) {
  const mcsim::MotorSpec& m = f.motor;
  const mcsim::BoardSpec& b = f.board;
  mc_params_t p = mc_params_default;
  p.r_ohm = static_cast<float>(m.r_ohm);
  p.ld_h = static_cast<float>(m.ld_h);
  p.lq_h = static_cast<float>(m.lq_h);
  p.flux_wb = static_cast<float>(m.flux_wb);
  p.pole_pairs = static_cast<uint32_t>(m.pole_pairs);
  p.j_kgm2 = static_cast<float>(m.j_kgm2);
  p.b_nm_s_rad = static_cast<float>(m.b_nm_s_rad);
  p.i_max_a = static_cast<float>(std::min(m.i_max_a, b.i_sense_max_a / 1.25));
  p.speed_max_rad_s = static_cast<float>(m.speed_max_rad_s);
  p.i_rated_a = static_cast<float>(std::min(m.i_rated_a, static_cast<double>(p.i_max_a)));
  p.speed_rated_rad_s = static_cast<float>(m.speed_rated_rad_s);
  p.vbus_v = static_cast<float>(b.vbus_v);
  p.pwm_hz = static_cast<uint32_t>(std::lround(b.pwm_hz));
  p.slow_loop_div = (p.pwm_hz + 500u) / 1000u;  // about 1 kHz, as the board images
  p.dead_time_s = static_cast<float>(b.dead_time_s);
  p.current_sensors = static_cast<uint32_t>(b.current_sensors);
  p.i_sense_max_a = static_cast<float>(b.i_sense_max_a);
  p.adc_bits = static_cast<uint32_t>(b.adc_bits);
  p.encoder_cpr = static_cast<uint32_t>(b.encoder_cpr);
  p.vbus_board_max_v = static_cast<float>(b.bus_limit_v());
  return p;
}

// ---- the experiment -----------------------------------------------------

mc_hal_can_frame_t pack(uint32_t msg, uint32_t node, std::vector<float> v) {
  mc_hal_can_frame_t f{};
  v.resize(MC_CAN_NSIG_MAX, 0.0f);
  if (mc_can_proto_pack(msg, node, v.data(), static_cast<uint32_t>(v.size()), &f) !=
      MC_CAN_ERR_NONE) {
    throw std::runtime_error("DBC encoder refused message " + std::to_string(msg));
  }
  return f;
}

struct Script {
  std::vector<std::pair<long, mc_hal_can_frame_t>> at;  // (period, frame), in order
  float iq_step_a = 0.0f;
  float speed_ref_rad_s = 0.0f;
};

Script script(const mc_params_t& p, double T) {
  Script s;
  const uint32_t node = p.can_node_id;
  s.iq_step_a = std::round(0.2f * p.i_rated_a);
  s.speed_ref_rad_s = std::round(0.1f * p.speed_rated_rad_s);
  auto k = [T](double t_s) { return std::lround(t_s / T); };
  s.at = {
      {k(0.005), pack(MC_CAN_MSG_SET_CONTROL_MODE, node, {float(MC_CAN_CTRL_CURRENT)})},
      {k(0.005), pack(MC_CAN_MSG_SET_ENABLE, node, {1.0f})},
      {k(0.010), pack(MC_CAN_MSG_SET_CURRENT_REF, node, {0.0f, s.iq_step_a})},
      {k(0.040), pack(MC_CAN_MSG_SET_ENABLE, node, {0.0f})},
      {k(0.040), pack(MC_CAN_MSG_SET_CONTROL_MODE, node, {float(MC_CAN_CTRL_SPEED)})},
      {k(0.040), pack(MC_CAN_MSG_SET_ENABLE, node, {1.0f})},
      {k(0.042), pack(MC_CAN_MSG_SET_SPEED_REF, node, {s.speed_ref_rad_s})},
  };
  return s;
}

// Everything a scenario can read of one period (the probe, the plant and
// the frames sent), compared with memcmp.
struct Snapshot {
  mc_app_probe_t probe{};
  double plant[7] = {};  // i_alpha, i_beta, omega_m, theta_m, t, bus voltage, brake duty
  std::vector<mc_hal_can_frame_t> tx;
  bool slow_ran = false;
};

Snapshot snap(mcsim::AppTarget& t, const mcsim::AppTargetPeriod& r,
              std::vector<mc_hal_can_frame_t> tx) {
  Snapshot s;
  s.probe = t.probe();
  const hal_host::PmsmBoard::State x = t.board().state();
  static_assert(hal_host::PmsmBoard::State::RowsAtCompileTime == 4, "plant state size");
  for (int i = 0; i < 4; ++i) s.plant[i] = x[i];
  s.plant[4] = t.board().t_s();
  s.plant[5] = t.board().vbus_v();
  s.plant[6] = t.board().brake_duty();
  s.tx = std::move(tx);
  s.slow_ran = r.slow_ran;
  return s;
}

// "" when equal bit for bit, else what differs.
std::string difference(const Snapshot& a, const Snapshot& b) {
  if (std::memcmp(&a.probe, &b.probe, sizeof a.probe) != 0) return "probe";
  if (std::memcmp(a.plant, b.plant, sizeof a.plant) != 0) return "plant";
  if (a.slow_ran != b.slow_ran) return "slow step";
  if (a.tx.size() != b.tx.size()) return "number of CAN frames sent";
  for (size_t i = 0; i < a.tx.size(); ++i) {
    const mc_hal_can_frame_t &x = a.tx[i], &y = b.tx[i];
    if (x.id != y.id || x.len != y.len || x.flags != y.flags ||
        std::memcmp(x.data, y.data, x.len) != 0) {
      return "CAN frame " + std::to_string(i);
    }
  }
  return "";
}

struct RunLog {
  std::vector<Snapshot> periods;
  Snapshot boot;
  double wall_s = 0.0;
};

RunLog run(mcsim::AppTarget& t, const Script& sc, long n) {
  RunLog r;
  r.boot.probe = t.probe();
  size_t next = 0;
  const auto t0 = std::chrono::steady_clock::now();
  for (long k = 0; k < n; ++k) {
    std::vector<mc_hal_can_frame_t> rx, tx;
    while (next < sc.at.size() && sc.at[next].first == k) rx.push_back(sc.at[next++].second);
    const mcsim::AppTargetPeriod p = t.period(rx, &tx);
    r.periods.push_back(snap(t, p, std::move(tx)));
  }
  r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

// The board's generated description, the one the flashed image is built
// with (firmware/targets/stm32f405/boards/<name>/, board_stm32f405.c).
const mc_board_desc_t& board_desc(const std::string& board) {
  if (board == "odrive36") return mc_board_odrive36_desc;
  if (board == "vesc6") return mc_board_vesc6_desc;
  throw std::invalid_argument("no description linked for board " + board);
}

mcsim::AppSetup setup_for(const std::string& board) {
  const mcsim::MotorFiles f =
      mcsim::load_motor_files(std::string(MC_MOTORS_DIR) + "/" + kMotor, board);
  mcsim::AppSetup s;
  s.board = mcsim::build_board_cfg(f);
  s.defaults = params_from_files(f);
  // The bus limits as the board image's defaults take them (board_defaults
  // in board_stm32f405.c: from the description; the trip derived from the
  // board's limit, vbus_board_max_v, which the simulator's table already
  // holds from the same description).
  const mc_board_desc_t& d = board_desc(board);
  s.defaults.vbus_min_v = d.vbus_min_v;
  s.defaults.vbus_max_v = 0.0f;
  return s;
}

// The table the PIL image boots is the board image's: its board quantities
// are the generated description's (the simulator read the same board.toml;
// the generator rounds to float, the simulator keeps doubles: 1e-6
// relative), its PWM rate and slow divider the image's (board_stm32f405.c
// PWM_HZ, slow_loop_div()).
void expect_board_image_table(const mc_params_t& p, const std::string& board) {
  const mc_board_desc_t& d = board_desc(board);
  EXPECT_EQ(p.pwm_hz, d.pwm_hz);
  EXPECT_EQ(p.slow_loop_div, (d.pwm_hz + 500u) / 1000u);
  EXPECT_EQ(p.encoder_cpr, d.enc_counts_per_rev);
  EXPECT_NEAR(p.i_sense_max_a, d.i_sense_max_a, 1e-6f * d.i_sense_max_a);
  EXPECT_NEAR(p.dead_time_s, static_cast<float>(d.deadtime_ns) * 1e-9f, 1e-12f);
  EXPECT_EQ(p.vbus_board_max_v, d.vbus_max_v);
  EXPECT_EQ(p.vbus_v, d.vbus_nominal_v);
}

// speed_law: the law of SPEED (params.toml speed_law: 0 sensored PI, 1
// sensorless). Returns the SIL run (equal to the PIL's when the test passes).
RunLog same_experiment(const std::string& board, uint32_t speed_law = 0u) {
  mcsim::AppSetup s = setup_for(board);
  s.defaults.speed_law = speed_law;
  const std::string tag = board + (speed_law == 0u ? "" : ".law" + std::to_string(speed_law));
  EXPECT_EQ(mc_params_validate(&s.defaults), MC_PARAMS_OK);
  expect_board_image_table(s.defaults, board);
  const std::unique_ptr<mcsim::AppTarget> sil_t = mcsim::make_app_target_sil(s);
  mcsim::AppTarget& sil = *sil_t;
  mcsim::AppTargetPilOptions po;
  po.link = pil_test_link("pil_app_target_" + tag + ".log", 60.0);
  po.board = board;
  std::unique_ptr<mcsim::AppTarget> pil = mcsim::make_app_target_pil(s, po);
  EXPECT_EQ(pil->name(), "pil:mc_stm32f405_pil:" + board);

  const double T = sil.board().period_s();
  const long n = std::lround(kDuration_s / T);
  const Script sc = script(s.defaults, T);
  // After boot, before any period.
  EXPECT_EQ(std::memcmp(&sil.probe(), &pil->probe(), sizeof(mc_app_probe_t)), 0);
  const RunLog a = run(sil, sc, n);
  const RunLog b = run(*pil, sc, n);

  long first = -1;
  std::string what;
  for (long k = 0; k < n && first < 0; ++k) {
    what = difference(a.periods[static_cast<size_t>(k)], b.periods[static_cast<size_t>(k)]);
    if (!what.empty()) first = k;
  }
  EXPECT_EQ(first, -1) << tag << ": first differing period " << first << " (" << what << ")";
  long frames = 0;
  for (const Snapshot& p : a.periods) frames += static_cast<long>(p.tx.size());
  std::printf("[pil-app] %s: %ld periods, %ld CAN frames compared\n", tag.c_str(), n, frames);
  mc_record(tag + ".periods_compared", static_cast<double>(n));
  mc_record(tag + ".periods_differing", first < 0 ? 0.0 : 1.0, 0.0);
  const double sim_s = static_cast<double>(n) * T;
  std::printf(
      "[pil-cost] {\"benchmark\": \"pil_app_target\", \"board\": \"%s\", \"motor\": \"%s\", "
      "\"speed_law\": %u, \"pwm_hz\": %u, \"periods\": %ld, \"sim_s\": %.6g, "
      "\"pil_wall_s\": %.6g, \"pil_wall_s_per_sim_s\": %.4g, \"sil_wall_s_per_sim_s\": %.4g}\n",
      board.c_str(), kMotor, speed_law, s.defaults.pwm_hz, n, sim_s, b.wall_s, b.wall_s / sim_s,
      a.wall_s / sim_s);
  return a;
}

// The q-current step in CURRENT (both laws run the same CURRENT mode).
void expect_current_step(const RunLog& a, const Script& sc, double T) {
  const mc_app_probe_t& c = a.periods[static_cast<size_t>(std::lround(0.035 / T) - 1)].probe;

  // CURRENT, enabled, the q current at its reference 25 ms after the step
  // (the current loop's bandwidth is hundreds of rad/s or more: 25 ms is
  // many time constants; 5 % of the step bounds ripple and quantisation).
  EXPECT_EQ(c.mode, static_cast<uint32_t>(MC_DRIVE_MODE_CURRENT));
  EXPECT_NEAR(c.iq_ref_a, sc.iq_step_a, 1e-3f);  // the DBC's 1 mA step
  EXPECT_NEAR(c.iq_a, sc.iq_step_a, 0.05 * sc.iq_step_a);
  EXPECT_EQ(c.faults, 0u);
}

// The experiment did what it says (on the SIL run, which the PIL equals).
void sensored_experiment(const std::string& board) {
  const RunLog a = same_experiment(board);
  const mcsim::AppSetup s = setup_for(board);
  const double T = 1.0 / s.defaults.pwm_hz;
  const Script sc = script(s.defaults, T);
  expect_current_step(a, sc, T);
  // SPEED (the application's CTRL mode): the law's reference has reached
  // the command and the rotor follows it; no fault.
  const mc_app_probe_t& e = a.periods.back().probe;
  EXPECT_EQ(e.mode, static_cast<uint32_t>(MC_DRIVE_MODE_CTRL));
  EXPECT_EQ(e.faults, 0u);
  EXPECT_EQ(e.cmd_enabled, 1u);
  EXPECT_NEAR(e.omega_ref_rad_s, sc.speed_ref_rad_s, 1e-3f);  // the DBC's step
  // the rotor at the reference 58 ms after it (a light rotor: the speed law
  // settles in a few ms; 10 % bounds its overshoot and the encoder's ripple)
  EXPECT_NEAR(e.omega_m_rad_s, sc.speed_ref_rad_s, 0.1f * sc.speed_ref_rad_s);
  std::printf("[pil-app] %s: at %.3g s speed %.4g rad/s, ref %.4g\n", board.c_str(), kDuration_s,
              static_cast<double>(e.omega_m_rad_s), static_cast<double>(e.omega_ref_rad_s));
}

// The ODrive v3.6 56 V board (the stm32f405-odrive36 image), on its 48 V
// nominal supply (board.toml: a nominal bus equal to the 56 V limit left no
// margin for the brake and regen thresholds, MC_PARAMS_ERR_DRIVE).
TEST(PilAppTarget, OdriveV36ImageEqualsSilBitForBit) {
  sensored_experiment("odrive36");
}

TEST(PilAppTarget, Vesc6ImageEqualsSilBitForBit) {
  sensored_experiment("vesc6");
}

// The sensorless law (speed_law 1: flux observer, PLL, I-f start) on the
// VESC 6: the law's own probe fields (start-up phase, handovers, the
// observer's angle) travel in PROBE too.
TEST(PilAppTarget, Vesc6SensorlessImageEqualsSilBitForBit) {
  const RunLog a = same_experiment("vesc6", 1u);
  const mc_app_probe_t& e = a.periods.back().probe;
  // 58 ms into SPEED the law has aligned and runs its I-f start (the
  // observer's hand-over comes later on this rotor), turning the rotor
  // forward; no fault.
  EXPECT_EQ(e.mode, static_cast<uint32_t>(MC_DRIVE_MODE_CTRL));
  EXPECT_EQ(e.faults, 0u);
  EXPECT_EQ(e.law_error, 0u);
  EXPECT_EQ(e.sls_phase, static_cast<uint32_t>(MC_CTRL_SLS_IF));
  EXPECT_GT(e.omega_m_rad_s, 0.0f);
  std::printf("[pil-app] vesc6.law1: phase %u handovers %u speed %.4g rad/s mode %u faults %u\n",
              e.sls_phase, e.sls_handovers, static_cast<double>(e.omega_m_rad_s), e.mode, e.faults);
}

// The comparison finds one ulp: in any probe field, in the plant's state.
TEST(PilAppTarget, OneUlpInTheProbeOrThePlantIsADifference) {
  Snapshot a;
  a.probe.iq_a = 1.5f;
  a.plant[2] = 100.0;
  Snapshot b = a;
  EXPECT_EQ(difference(a, b), "");
  b.probe.iq_a = std::nextafter(a.probe.iq_a, 2.0f);
  EXPECT_EQ(difference(a, b), "probe");
  b = a;
  b.probe.pos_traj_k = 1u;  // the last field
  EXPECT_EQ(difference(a, b), "probe");
  b = a;
  b.plant[2] = std::nextafter(a.plant[2], 200.0);
  EXPECT_EQ(difference(a, b), "plant");
}

// The whole chain sees one ulp: the parameter table with r_ohm one ulp
// higher on the PIL side only (the image derives its current-loop gains
// from it) gives another trajectory within the short current step.
TEST(PilAppTarget, OneUlpInAParameterChangesThePilRun) {
  const std::string board = "vesc6";
  const mcsim::AppSetup s = setup_for(board);
  mcsim::AppSetup s_ulp = s;
  s_ulp.defaults.r_ohm = std::nextafter(s.defaults.r_ohm, 1.0f);
  const std::unique_ptr<mcsim::AppTarget> sil_t = mcsim::make_app_target_sil(s);
  mcsim::AppTarget& sil = *sil_t;
  mcsim::AppTargetPilOptions po;
  po.link = pil_test_link("pil_app_target_ulp.log", 60.0);
  std::unique_ptr<mcsim::AppTarget> pil = mcsim::make_app_target_pil(s_ulp, po);
  const double T = sil.board().period_s();
  const long n = std::lround(0.02 / T);  // the current step starts at 10 ms
  const Script sc = script(s.defaults, T);
  const RunLog a = run(sil, sc, n);
  const RunLog b = run(*pil, sc, n);
  long first = -1;
  for (long k = 0; k < n && first < 0; ++k) {
    if (!difference(a.periods[static_cast<size_t>(k)], b.periods[static_cast<size_t>(k)]).empty()) {
      first = k;
    }
  }
  EXPECT_GE(first, 0) << "a one-ulp change of r_ohm went unseen";
}

// Bad input: a parameter table the image would refuse is refused before
// QEMU starts, with the reason.
TEST(PilAppTarget, InvalidTableIsRefusedWithAReason) {
  mcsim::AppSetup s = setup_for("vesc6");
  s.defaults.pwm_hz = 1u;  // below the table's 5 kHz
  mcsim::AppTargetPilOptions po;
  po.link = pil_test_link("pil_app_target_refused.log");
  try {
    (void)mcsim::make_app_target_pil(s, po);
    FAIL() << "accepted an invalid table";
  } catch (const mcsim::UsageError& e) {
    EXPECT_NE(std::string(e.what()).find("MC_PARAMS_ERR"), std::string::npos) << e.what();
  }
}

// A missing image is refused with its path before QEMU starts.
TEST(PilAppTarget, MissingImageIsRefusedWithAReason) {
  const mcsim::AppSetup s = setup_for("vesc6");
  mcsim::AppTargetPilOptions po;
  po.link = pil_test_link("pil_app_target_refused.log");
  po.link.elf = std::string(MC_PIL_LOG_DIR) + "/no_such_image.elf";
  try {
    (void)mcsim::make_app_target_pil(s, po);
    FAIL() << "accepted a missing image";
  } catch (const mcsim::UsageError& e) {
    EXPECT_NE(std::string(e.what()).find("no_such_image.elf"), std::string::npos) << e.what();
  }
}

// A host of a later link version names a capability this image has no HAL
// for (APP caps, a bit outside MC_PIL_CAP_ALL): the image answers READY
// with MC_PIL_READY_ERR_CAPS and its own version, so the host can name the
// mismatch (foc_pil.cpp), says why in its semihosting text and stops
// (exit status 3, PIL_EXIT_FRAME_ERROR: nothing booted).
TEST(PilAppTarget, UnknownCapabilityIsRefusedByTheImageWithItsVersion) {
  const std::string log = "pil_app_target_caps.log";
  hal_host::PilLink link(pil_test_link(log));
  const std::vector<uint8_t> hello = link.receive_frame();
  ASSERT_EQ(mc_pil_check_hello(hello.data(), hello.size()), MC_PIL_OK);
  mc_pil_app_t a{};
  a.tick_hz = 168000000u;
  a.caps = MC_PIL_CAP_HALL | (1u << 7);  // bit 7: no version has it
  std::vector<uint8_t> buf(MC_PIL_MAX_FRAME);
  link.send(buf.data(), mc_pil_encode_app(&a, buf.data(), buf.size()));
  const std::vector<uint8_t> r = link.receive_frame();
  mc_pil_ready_t rd{};
  ASSERT_EQ(mc_pil_decode_ready(r.data(), r.size(), &rd), MC_PIL_OK);
  EXPECT_EQ(rd.drive_cfg_err, MC_PIL_READY_ERR_CAPS);
  EXPECT_EQ(rd.version, MC_PIL_VERSION);
  try {
    (void)link.receive_frame();
    FAIL() << "the image went on after refusing APP";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("exit status 3"), std::string::npos) << e.what();
  }
  std::FILE* f = std::fopen((std::string(MC_PIL_LOG_DIR) + "/" + log).c_str(), "r");
  ASSERT_NE(f, nullptr);
  char text[256] = {};
  const std::size_t n = std::fread(text, 1, sizeof text - 1, f);
  std::fclose(f);
  EXPECT_NE(std::string(text, n).find("capability"), std::string::npos) << text;
}

// ---- braking: a regenerative stop on the ODrive v3.6 ----------------------
//
// The plant's DC link: the board's 48 V nominal supply through 50 mOhm that
// cannot sink current (a diode: the braking energy stays on the bus), 1 mF
// of bus capacitance (a test value: the ODrive's board files give none) and
// the board's brake resistor (board.toml [brake] r_ohm, 2 ohm). The table
// enables the chopper (brake_enable 1; brake_on_v / brake_full_v derived:
// 49.6 V / 51.6 V on the 48 V bus with its 56 V limit). The experiment:
// SPEED, enable at 5 ms, 200 rad/s at 6 ms, 0 rad/s at 60 ms (the speed law
// brakes the rotor at its current limit: the rotor's 3 J go to the bus),
// 0.12 s simulated.
constexpr double kRegenDuration_s = 0.12;
constexpr float kRegenSpeed_rad_s = 200.0f;

mcsim::AppSetup regen_setup() {
  mcsim::AppSetup s = setup_for("odrive36");
  s.defaults.brake_enable = 1u;
  s.board.dc_link_enabled = true;
  s.board.dc_link.source_v = s.board.vbus_v;
  s.board.dc_link.source_r_ohm = 0.05;
  s.board.dc_link.source_sink = false;
  s.board.dc_link.c_f = 1e-3;
  s.board.dc_link.brake_r_ohm = static_cast<double>(mc_board_odrive36_desc.brake_r_ohm);
  return s;
}

Script regen_script(const mc_params_t& p, double T) {
  Script s;
  const uint32_t node = p.can_node_id;
  s.speed_ref_rad_s = kRegenSpeed_rad_s;
  auto k = [T](double t_s) { return std::lround(t_s / T); };
  s.at = {
      {k(0.005), pack(MC_CAN_MSG_SET_CONTROL_MODE, node, {float(MC_CAN_CTRL_SPEED)})},
      {k(0.005), pack(MC_CAN_MSG_SET_ENABLE, node, {1.0f})},
      {k(0.006), pack(MC_CAN_MSG_SET_SPEED_REF, node, {kRegenSpeed_rad_s})},
      {k(0.060), pack(MC_CAN_MSG_SET_SPEED_REF, node, {0.0f})},
  };
  return s;
}

// Bit for bit equal SIL and PIL (probe, plant with the bus voltage and the
// brake duty in force, CAN frames), and the brake did the work: it
// conducted, and the bus peak stays below the board's limit.
TEST(PilAppTarget, OdriveV36RegenerativeStopBrakesAsTheSil) {
  const mcsim::AppSetup s = regen_setup();
  ASSERT_EQ(mc_params_validate(&s.defaults), MC_PARAMS_OK);
  expect_board_image_table(s.defaults, "odrive36");
  const std::unique_ptr<mcsim::AppTarget> sil_t = mcsim::make_app_target_sil(s);
  mcsim::AppTarget& sil = *sil_t;
  mcsim::AppTargetPilOptions po;
  po.link = pil_test_link("pil_app_target_odrive36.brake.log", 60.0);
  po.board = "odrive36";
  std::unique_ptr<mcsim::AppTarget> pil = mcsim::make_app_target_pil(s, po);
  const double T = sil.board().period_s();
  const long n = std::lround(kRegenDuration_s / T);
  const Script sc = regen_script(s.defaults, T);
  ASSERT_EQ(std::memcmp(&sil.probe(), &pil->probe(), sizeof(mc_app_probe_t)), 0);
  const RunLog a = run(sil, sc, n);
  const RunLog b = run(*pil, sc, n);

  long first = -1;
  std::string what;
  for (long k = 0; k < n && first < 0; ++k) {
    what = difference(a.periods[static_cast<size_t>(k)], b.periods[static_cast<size_t>(k)]);
    if (!what.empty()) first = k;
  }
  EXPECT_EQ(first, -1) << "first differing period " << first << " (" << what << ")";

  double peak_a = 0.0, peak_b = 0.0, duty_a = 0.0, duty_b = 0.0, speed_top = 0.0;
  long braking = 0;
  for (long k = 0; k < n; ++k) {
    const Snapshot &x = a.periods[static_cast<size_t>(k)], &y = b.periods[static_cast<size_t>(k)];
    peak_a = std::max(peak_a, x.plant[5]);
    peak_b = std::max(peak_b, y.plant[5]);
    duty_a = std::max(duty_a, x.plant[6]);
    duty_b = std::max(duty_b, y.plant[6]);
    speed_top = std::max(speed_top, x.plant[2]);
    braking += (y.plant[6] > 0.0) ? 1 : 0;
  }
  // The same bus peak and brake duty, to the bit.
  EXPECT_EQ(std::memcmp(&peak_a, &peak_b, sizeof peak_a), 0) << peak_a << " vs " << peak_b;
  EXPECT_EQ(std::memcmp(&duty_a, &duty_b, sizeof duty_a), 0) << duty_a << " vs " << duty_b;
  // The rotor reached the reference (within 10 %: the speed law's
  // overshoot), the image's chopper conducted (a run without the brake
  // cannot pass), the bus rose past the chopper's on threshold and stayed
  // below the board's 56 V limit; no fault at the end, the rotor stopped
  // (within 5 % of the reference it had).
  const mc_app_probe_t& e = b.periods.back().probe;
  EXPECT_NEAR(speed_top, kRegenSpeed_rad_s, 0.1 * kRegenSpeed_rad_s);
  EXPECT_GT(duty_b, 0.0);
  EXPECT_GT(braking, 0);
  // brake_on_v derived (params.toml): vbus_v + 0.2 (vbus_max_v - vbus_v),
  // the trip derived from the board's limit (min(1.5 vbus_v, 56 V))
  mc_params_eff_t eff{};
  ASSERT_EQ(mc_params_resolve(&s.defaults, &eff), MC_GAINS_OK);
  const double trip_v = eff.p.vbus_max_v;
  EXPECT_EQ(trip_v, static_cast<double>(mc_board_odrive36_desc.vbus_max_v));
  const double on_v = s.defaults.vbus_v + 0.2 * (trip_v - s.defaults.vbus_v);
  EXPECT_GT(peak_b, on_v);
  EXPECT_LT(peak_b, trip_v);
  EXPECT_EQ(e.faults, 0u);
  EXPECT_NEAR(e.omega_m_rad_s, 0.0f, 0.05f * kRegenSpeed_rad_s);
  std::printf(
      "[pil-app] odrive36.brake: %ld periods, bus peak %.6g V, brake duty peak %.4g, "
      "%ld braking periods, top speed %.4g rad/s\n",
      n, peak_b, duty_b, braking, speed_top);
  mc_record("odrive36.brake.vbus_peak_v", peak_b);
  mc_record("odrive36.brake.duty_peak", duty_b);
}

}  // namespace
