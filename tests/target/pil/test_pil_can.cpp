// Processor-in-the-loop, the whole image: the STM32F405 image's main, both
// loops in their interrupts and the drive application with CAN
// (firmware/app/app/mc_app: receive ring, command handler, telemetry,
// command timeout, parameter service and flash store, speed loop) on the
// emulated M4F (QEMU netduinoplus2, image mc_stm32f405_pil in its
// whole-image mode), the plant on the host, CAN frames over the PIL link;
// against the software-in-the-loop run of the same CAN demo
// (mcsim run can-telemetry, the same application compiled for the host).
//
// The SIL run writes the application's binding it made (plant options,
// the board's default parameters, telemetry budget and speed-loop gains:
// MCSIM_APP_BINDING_OUT, sim/cli/app_binding.hpp); the PIL run builds the
// same plant from it and boots the image's application on the same
// defaults. Both get the frames of demo_pil_commands.log in the same
// period (those whose time stamp the simulated clock has reached at the
// start of that period: the CAN receive interrupt before the fast step, as
// hal_host::app_period runs it), and both logs are candump files stamped
// with the simulated time at the end of the period the frame left in.
//
// Expected: the same frames, bit for bit (ids, lengths, payloads, periods),
// in the same order: tolerance 0. The drive's and the application's
// arithmetic is IEEE single precision with -ffp-contract=off and the
// kernels' own math (no libm), bit-identical on x86-64 and the M4F
// (tests/target bitexact, kv); the link carries floats as bit patterns; the
// plant is the same host code in both runs. A lock-step run: no wall clock
// anywhere in the criteria.
#include <gtest/gtest.h>

#include <sys/stat.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "app_binding.hpp"
#include "foc_pil.hpp"
#include "hal_host/candump_log.hpp"
#include "mc_record.hpp"
#include "pil_test_link.hpp"
extern "C" {
#include "mc_can_dbc.h"
#include "mc_can_proto.h"
}

namespace {

// Simulated duration of both runs: the demo's last accepted frame is at
// 100 ms, the command timeout (timeout_s below) starts the safe stop 100 ms
// later, the stop ramp from about 22 rad/s at 200 rad/s^2 ends near 320 ms,
// so 500 ms leaves the drive idle for the last heartbeat. 5000 periods at
// 10 kHz.
constexpr double kDuration_s = 0.5;
// Shortened from the SIL demo's defaults so the PIL run stays short: the
// command timeout 0.5 s -> 0.1 s; a lighter flywheel (J 0.05 -> 0.005
// kg m^2) so the speed step settles within the run.
const char* const kSets[] = {"timeout_s=0.1", "J_kgm2=0.005"};

std::string work_dir() {
  return std::string(MC_PIL_LOG_DIR) + "/pil_can";
}

std::vector<std::string> read_lines(const std::string& path) {
  std::ifstream f(path);
  std::vector<std::string> out;
  std::string line;
  while (std::getline(f, line)) {
    if (!line.empty()) out.push_back(line);
  }
  return out;
}

// The SIL run: mcsim can-telemetry with the demo script, a new flash file,
// its candump log and the application binding. Returns mcsim's status.
int run_sil(const std::string& dir) {
  (void)std::remove((dir + "/sil.flash").c_str());
  std::string cmd = "env -u MCSIM_CAN_IF MCSIM_CAN_LOG='" + dir + "/sil.candump.log'" +
                    " MCSIM_CAN_CMDS='" + MC_PIL_DEMO + "'" + " MCSIM_APP_BINDING_OUT='" + dir +
                    "/binding.txt' '" + MC_MCSIM + "' run can-telemetry --out '" + dir +
                    "/sil' --duration " + std::to_string(kDuration_s) + " --flash '" + dir +
                    "/sil.flash'";
  for (const char* s : kSets) cmd += std::string(" --set ") + s;
  cmd += " > '" + dir + "/sil.stdout' 2>&1";
  return std::system(cmd.c_str());
}

struct PilRun {
  long periods = 0;
  long rx_delivered = 0;
  long slow_periods = 0;
  int exit_status = -1;
};

// The PIL run of the same binding and script; its frames into pil.candump.log.
PilRun run_pil(const mcsim::AppBinding& ab, const std::string& dir) {
  PilRun r;
  mcsim::PilAppSetup setup;
  setup.defaults = ab.defaults;
  setup.app.tm_budget_frac = ab.tm_budget_frac;
  for (uint32_t i = 0; i < MC_PIL_TM_EXT_RATES; ++i) {
    setup.app.tm_ext_rate_hz[i] = ab.tm_ext_rate_hz[i];
  }
  setup.app.pwm_hz_fixed = ab.pwm_hz_fixed;
  setup.app.slow_loop_div_fixed = ab.slow_loop_div_fixed;

  mcsim::FocPil pil(ab.plant, pil_test_link("pil_can/pil_semihost.log", 60.0), setup);
  hal_host::PmsmBoard& b = pil.board();
  double now_s = 0.0;
  hal_host::CandumpLogCan can(
      dir + "/pil.candump.log", "can0", [&now_s]() { return now_s; }, MC_PIL_DEMO);
  const double T = b.period_s();
  r.periods = std::lround(kDuration_s / T);  // as the scenario: lround(duration / T)
  std::vector<mc_hal_can_frame_t> rx;
  std::vector<mcsim::PilCanTx> tx;
  for (long k = 0; k < r.periods; ++k) {
    rx.clear();
    tx.clear();
    {
      // The SIL's receive interrupt runs at the period's start (the script
      // frames whose stamp that time has reached)
      now_s = b.t_s();
      mc_hal_can_frame_t f{};
      while (can.receive(&f) == 0) rx.push_back(f);
    }
    const mc_pil_out_t& o = pil.step(mcsim::PilCommand{}, rx, &tx);
    r.rx_delivered += static_cast<long>(rx.size());
    r.slow_periods += o.slow_ran != 0u ? 1 : 0;
    now_s = b.t_s();
    for (const mcsim::PilCanTx& t : tx) {
      if (can.send(&t.frame) != 0) throw std::runtime_error("PIL: candump log write failed");
    }
  }
  if (!can.flush()) throw std::runtime_error("PIL: candump log write failed");
  r.exit_status = pil.finish();
  return r;
}

// Index of the first line that differs, or -1 when both are equal.
long first_difference(const std::vector<std::string>& a, const std::vector<std::string>& b) {
  for (size_t k = 0; k < a.size() && k < b.size(); ++k) {
    if (a[k] != b[k]) return static_cast<long>(k);
  }
  return (a.size() == b.size()) ? -1 : static_cast<long>(std::min(a.size(), b.size()));
}

struct Decoded {
  double t_s;
  uint32_t msg;
  std::vector<float> v;
};

std::vector<Decoded> decode(const std::vector<std::string>& lines) {
  std::vector<Decoded> out;
  for (const std::string& line : lines) {
    Decoded d{};
    mc_hal_can_frame_t f{};
    if (!hal_host::candump_parse(line, &d.t_s, &f)) continue;
    d.v.assign(MC_CAN_NSIG_MAX, 0.0f);
    if (mc_can_proto_unpack(&f, &d.msg, d.v.data(), MC_CAN_NSIG_MAX) != MC_CAN_ERR_NONE) continue;
    out.push_back(d);
  }
  return out;
}

TEST(PilCanDemo, WholeImageTelemetryIsBitIdenticalToSil) {
  const std::string dir = work_dir();
  (void)::mkdir(dir.c_str(), 0755);
  ASSERT_EQ(run_sil(dir), 0) << "mcsim failed: see " << dir << "/sil.stdout";
  const mcsim::AppBinding ab = mcsim::read_app_binding(dir + "/binding.txt");
  // The image always boots its application from the parameters; the SIL
  // must have done the same (laws from the parameters on both sides;
  // commissioning, which the PIL board leaves out, is not in the demo).
  ASSERT_TRUE(ab.serve_params);

  const PilRun pil = run_pil(ab, dir);
  ASSERT_EQ(pil.exit_status, 0) << "target did not exit cleanly on END";

  const std::vector<std::string> sil_lines = read_lines(dir + "/sil.candump.log");
  const std::vector<std::string> pil_lines = read_lines(dir + "/pil.candump.log");
  // Every script frame was delivered (the ring holds them for the slow step).
  EXPECT_EQ(pil.rx_delivered, 11);
  EXPECT_EQ(pil.slow_periods, pil.periods / static_cast<long>(ab.plant.slow_loop_div));

  // The comparison: every frame, time stamp (the period), id and payload.
  const long diff = first_difference(sil_lines, pil_lines);
  EXPECT_EQ(diff, -1) << "first differing frame: SIL '"
                      << (diff >= 0 && static_cast<size_t>(diff) < sil_lines.size()
                              ? sil_lines[static_cast<size_t>(diff)]
                              : "(none)")
                      << "' PIL '"
                      << (diff >= 0 && static_cast<size_t>(diff) < pil_lines.size()
                              ? pil_lines[static_cast<size_t>(diff)]
                              : "(none)")
                      << "'";
  ASSERT_EQ(sil_lines.size(), pil_lines.size());

  // Frame counts compared, per message.
  const std::vector<Decoded> sil = decode(sil_lines);
  ASSERT_EQ(sil.size(), sil_lines.size()) << "a frame of the SIL log does not decode";
  std::map<uint32_t, long> per_msg;
  for (const Decoded& d : sil) per_msg[d.msg]++;
  std::printf("[pil-can] %zu frames compared over %ld periods:", sil_lines.size(), pil.periods);
  for (const auto& [msg, count] : per_msg) {
    char key[32];  // by command id (tools/can/motordrive.dbc: 0x01 HEARTBEAT, ...)
    std::snprintf(key, sizeof key, "frames.cmd_0x%02X", mc_can_messages[msg].cmd);
    std::printf(" %s=%ld", key + 7, count);
    mc_record(key, static_cast<double>(count));
  }
  std::printf("\n");
  mc_record("frames_compared", static_cast<double>(sil_lines.size()));
  mc_record("periods", static_cast<double>(pil.periods));
  mc_record("frames_differing", diff == -1 ? 0.0 : 1.0, 0.0);

  // The demo did what it says (checked on the SIL log, which the PIL log
  // equals): WRITE, APPLY and SAVE answered OK (SAVE: record 1 in the new
  // store); the malformed speed reference refused LENGTH, the one above the
  // written limit RANGE; the drive ran in SPEED mode and its speed followed
  // the 20 rad/s reference (it passes 19 rad/s, 95 %, and stays below 24:
  // the speed PI's overshoot on this flywheel is about 13 %), then stopped
  // on the command timeout and was idle at the end.
  std::vector<std::pair<int, int>> replies;  // (opcode, status)
  std::vector<std::pair<int, int>> errors;   // (rejected cmd, error)
  bool ran_speed = false, stopping = false;
  float omega_max = 0.0f;
  std::vector<float> last_hb;
  for (const Decoded& d : sil) {
    if (d.msg == MC_CAN_MSG_PARAM_REPLY) {
      replies.emplace_back(static_cast<int>(d.v[MC_CAN_PARAM_REPLY_OPCODE]),
                           static_cast<int>(d.v[MC_CAN_PARAM_REPLY_STATUS]));
    } else if (d.msg == MC_CAN_MSG_CMD_ERROR) {
      errors.emplace_back(static_cast<int>(d.v[MC_CAN_CMD_ERROR_REJECTED_CMD]),
                          static_cast<int>(d.v[MC_CAN_CMD_ERROR_ERROR]));
    } else if (d.msg == MC_CAN_MSG_HEARTBEAT) {
      ran_speed |=
          d.v[MC_CAN_HEARTBEAT_ENABLED] == 1.0f && d.v[MC_CAN_HEARTBEAT_CONTROL_MODE] == 2.0f;
      stopping |= d.v[MC_CAN_HEARTBEAT_STOPPING] == 1.0f;
      last_hb = d.v;
    } else if (d.msg == MC_CAN_MSG_SPEED) {
      omega_max = std::max(omega_max, d.v[MC_CAN_SPEED_OMEGA_M_RAD_S]);
    }
  }
  const std::vector<std::pair<int, int>> want_replies = {{1, 0}, {2, 0}, {3, 0}};
  EXPECT_EQ(replies, want_replies);
  const std::vector<std::pair<int, int>> want_errors = {{0x13, 2}, {0x13, 3}};
  EXPECT_EQ(errors, want_errors);
  EXPECT_TRUE(ran_speed);
  EXPECT_TRUE(stopping);
  ASSERT_FALSE(last_hb.empty());
  EXPECT_EQ(last_hb[MC_CAN_HEARTBEAT_STOP_REASON], 1.0f);  // CMD_TIMEOUT
  EXPECT_EQ(last_hb[MC_CAN_HEARTBEAT_ENABLED], 0.0f);
  EXPECT_EQ(last_hb[MC_CAN_HEARTBEAT_MODE], 0.0f);  // IDLE
  // the store's status: STORED since the SAVE wrote record 1 (EMPTY before)
  EXPECT_EQ(last_hb[MC_CAN_HEARTBEAT_CFG_STATUS], 0.0f);
  EXPECT_GE(omega_max, 19.0f);
  EXPECT_LE(omega_max, 24.0f);

  // The comparison can fail: one bit of one payload changed is found.
  std::vector<std::string> tampered = pil_lines;
  ASSERT_FALSE(tampered.empty());
  std::string& last = tampered[tampered.size() / 2];
  last.back() = (last.back() == '0') ? '1' : '0';
  EXPECT_EQ(first_difference(sil_lines, tampered), static_cast<long>(tampered.size() / 2));
}

}  // namespace
