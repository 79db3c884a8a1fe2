// A scenario's side of the CAN bus (issue 29 item 3): the DBC's command
// messages (tools/can/motordrive.dbc), packed by the firmware's generated
// codec (mc_can_proto_pack, the tables mc_can_cmd decodes), and a runner
// that gives them to an AppTarget one period at a time with the host
// keep-alive a user's tool sends. A scenario commands the application only
// through these frames, so the `--pil` twin replays the same run.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "app_target.hpp"
extern "C" {
#include "mc_can_cmd.h"
#include "mc_can_proto.h"
}

namespace mcsim {

/// The command frames for one node.
class AppCommands {
 public:
  explicit AppCommands(uint32_t node_id) : node_(node_id) {}
  mc_hal_can_frame_t enable(bool on) const;
  /// mode: MC_CAN_CTRL_CURRENT, _SPEED or _POSITION.
  mc_hal_can_frame_t mode(uint32_t mode) const;
  mc_hal_can_frame_t current_ref(double id_a, double iq_a) const;
  mc_hal_can_frame_t speed_ref(double omega_m_rad_s) const;
  mc_hal_can_frame_t position_ref(double theta_m_rad) const;
  /// COMMISSION_CMD: action MC_COMM_CAN_START, _ABORT or _REPORT with its
  /// options (0: the drive's default).
  mc_hal_can_frame_t commission(uint32_t action, double i_test_a, double v_test_max_v,
                                double speed_max_m_rad_s) const;
  /// PARAM_REQ with an opcode that takes no id or value (MC_PARAM_OP_APPLY,
  /// MC_PARAM_OP_SAVE).
  mc_hal_can_frame_t param_op(uint32_t opcode) const;
  /// PARAM_REQ opcode for parameter id with the value's raw 32 bits given
  /// as a number (a u32 parameter's value; up to 2^24 exactly).
  mc_hal_can_frame_t param_req(uint32_t opcode, uint32_t id, double raw) const;
  /// HOST_HEARTBEAT, its counter advanced by one at each call.
  mc_hal_can_frame_t host_heartbeat();

 private:
  mc_hal_can_frame_t pack(uint32_t msg, const std::vector<float>& values) const;
  uint32_t node_;
  uint8_t hb_counter_ = 0;
};

/// Runs an AppTarget period by period: the frames queued since the last
/// period go to the next one, a HOST_HEARTBEAT every keepalive_s of
/// simulated time (a tenth of the command timeout), and every CMD_ERROR the
/// application answers is a refused command: step() throws UsageError
/// naming the command and the error (a scenario never commands what the
/// drive refuses without saying so).
class AppRunner {
 public:
  explicit AppRunner(AppTarget& target);
  void send(const mc_hal_can_frame_t& f) { pending_.push_back(f); }
  /// Enable the drive in mode (MC_CAN_CTRL_*): mode, then enable. When the
  /// booted table makes the drive find the rotor's angle at this enable
  /// (angle_ref index or align, angle_find_at_enable 1, the angle unknown
  /// since power-up) the scenario must wait for it: with waits_for_find
  /// it then calls finish_angle_find(); without, start refuses the run
  /// (UsageError: the scenario's timing does not allow for it).
  void start(uint32_t mode, bool waits_for_find = false);
  /// After start(): the periods of the power-up find, until the drive runs
  /// the commanded mode (at most max_s of simulated time). Returns the time
  /// it took (0: no find ran, nothing stepped). A find that fails faults
  /// the drive (the scenario's AppWatch names it, with the finder's reason);
  /// one still running after max_s is a UsageError.
  double finish_angle_find(double max_s = 30.0);
  /// Whether the booted table makes the drive find the angle at an enable
  /// in mode (see start()).
  bool find_at_enable(uint32_t mode) const;
  /// The keep-alive from now on without an enable (a commissioning run,
  /// which the application times out as an enabled drive).
  void keep_host_alive();
  AppTargetPeriod step();
  /// Stop (false) or resume the HOST_HEARTBEAT keep-alive: a host that
  /// went silent (the application's command timeout then stops the drive).
  void keepalive(bool on) { keepalive_on_ = on; }
  AppCommands& cmd() { return cmd_; }
  const mc_app_probe_t& probe() const { return t_.probe(); }
  hal_host::PmsmBoard& board() { return t_.board(); }
  AppTarget& target() { return t_; }
  uint64_t frames_sent() const { return frames_tx_; }
  /// The frames the application sent in the last step.
  const std::vector<mc_hal_can_frame_t>& sent() const { return tx_; }

 private:
  AppTarget& t_;
  AppCommands cmd_;
  std::vector<mc_hal_can_frame_t> pending_, tx_;
  double keepalive_s_ = 0, next_hb_s_ = 0;
  uint64_t frames_tx_ = 0;
  bool started_ = false;
  bool keepalive_on_ = true;
  bool find_pending_ = false;  // start() enabled a mode that finds the angle first
};

}  // namespace mcsim
