#include "app_cmd.hpp"

#include <cstdio>
#include <stdexcept>

#include "scenario.hpp"
extern "C" {
#include "config/mc_law_cfg.h"
}

namespace mcsim {

mc_hal_can_frame_t AppCommands::pack(uint32_t msg, const std::vector<float>& values) const {
  mc_hal_can_frame_t f{};
  const float none = 0.0f;
  const float* v = values.empty() ? &none : values.data();
  const uint32_t n = values.empty() ? 1u : static_cast<uint32_t>(values.size());
  if (mc_can_proto_pack(msg, node_, v, n, &f) != MC_CAN_ERR_NONE) {
    throw std::logic_error("mc_can_proto_pack refused a command (message " + std::to_string(msg) +
                           ")");
  }
  return f;
}

mc_hal_can_frame_t AppCommands::enable(bool on) const {
  return pack(MC_CAN_MSG_SET_ENABLE, {on ? 1.0f : 0.0f});
}

mc_hal_can_frame_t AppCommands::mode(uint32_t mode) const {
  return pack(MC_CAN_MSG_SET_CONTROL_MODE, {static_cast<float>(mode)});
}

mc_hal_can_frame_t AppCommands::current_ref(double id_a, double iq_a) const {
  return pack(MC_CAN_MSG_SET_CURRENT_REF, {static_cast<float>(id_a), static_cast<float>(iq_a)});
}

mc_hal_can_frame_t AppCommands::speed_ref(double omega_m_rad_s) const {
  return pack(MC_CAN_MSG_SET_SPEED_REF, {static_cast<float>(omega_m_rad_s)});
}

mc_hal_can_frame_t AppCommands::position_ref(double theta_m_rad) const {
  return pack(MC_CAN_MSG_SET_POSITION_REF, {static_cast<float>(theta_m_rad)});
}

mc_hal_can_frame_t AppCommands::commission(uint32_t action, double i_test_a, double v_test_max_v,
                                           double speed_max_m_rad_s) const {
  return pack(MC_CAN_MSG_COMMISSION_CMD,
              {static_cast<float>(action), static_cast<float>(i_test_a),
               static_cast<float>(v_test_max_v), static_cast<float>(speed_max_m_rad_s)});
}

mc_hal_can_frame_t AppCommands::param_op(uint32_t opcode) const {
  return pack(MC_CAN_MSG_PARAM_REQ, {static_cast<float>(opcode), 0.0f, 0.0f});
}

mc_hal_can_frame_t AppCommands::param_req(uint32_t opcode, uint32_t id, double raw) const {
  return pack(MC_CAN_MSG_PARAM_REQ,
              {static_cast<float>(opcode), static_cast<float>(id), static_cast<float>(raw)});
}

mc_hal_can_frame_t AppCommands::host_heartbeat() {
  ++hb_counter_;
  return pack(MC_CAN_MSG_HOST_HEARTBEAT, {static_cast<float>(hb_counter_)});
}

AppRunner::AppRunner(AppTarget& target) : t_(target), cmd_(target.params().can_node_id) {
  keepalive_s_ = 0.1 * static_cast<double>(target.params().can_timeout_s);
}

bool AppRunner::find_at_enable(uint32_t mode) const {
  const mc_params_t& p = t_.params();
  const bool needs_encoder = mode == MC_CAN_CTRL_CURRENT || mode == MC_CAN_CTRL_POSITION ||
                             (mode == MC_CAN_CTRL_SPEED && p.speed_law != MC_LAW_SPEED_SENSORLESS);
  return needs_encoder && p.angle_ref != MC_DRIVE_ANGLE_REF_STORED &&
         p.angle_find_at_enable != 0u && t_.probe().angle_state != MC_DRIVE_ANGLE_KNOWN;
}

void AppRunner::start(uint32_t mode, bool waits_for_find) {
  if (!waits_for_find && find_at_enable(mode)) {
    throw UsageError(
        "the drive finds the rotor's angle at this enable (angle_ref " +
        std::string(t_.params().angle_ref == MC_DRIVE_ANGLE_REF_INDEX ? "index" : "align") +
        ", angle_find_at_enable 1) and this scenario does not wait for it yet (speed-step, "
        "load-step and current-step do)");
  }
  find_pending_ = find_at_enable(mode);
  send(cmd_.mode(mode));
  send(cmd_.enable(true));
  keep_host_alive();  // the first keep-alive with the enable
}

double AppRunner::finish_angle_find(double max_s) {
  if (!find_pending_) return 0.0;
  find_pending_ = false;
  const double t0 = t_.board().t_s();
  bool began = false;
  while (t_.board().t_s() - t0 < max_s) {
    step();
    const mc_app_probe_t& p = t_.probe();
    // the find failed: the scenario's watch names it once the next slow
    // step has ended the run (the fault comes from the fast step first)
    if (p.faults != 0u && p.angle_finding == 0u) break;
    if (p.angle_finding != 0u) began = true;
    if (began && p.angle_finding == 0u) break;
    if (!began && p.cmd_enabled != 0u && p.angle_state == MC_DRIVE_ANGLE_KNOWN) break;
  }
  if (t_.probe().angle_finding != 0u) {
    throw UsageError("the drive's power-up angle find did not end within " + std::to_string(max_s) +
                     " s");
  }
  return t_.board().t_s() - t0;
}

void AppRunner::keep_host_alive() {
  started_ = true;
  next_hb_s_ = t_.board().t_s();
}

AppTargetPeriod AppRunner::step() {
  const double t = t_.board().t_s();
  if (started_ && keepalive_on_ && t >= next_hb_s_) {
    pending_.push_back(cmd_.host_heartbeat());
    next_hb_s_ = t + keepalive_s_;
  }
  tx_.clear();
  const AppTargetPeriod r = t_.period(pending_, &tx_);
  pending_.clear();
  for (const mc_hal_can_frame_t& f : tx_) {
    ++frames_tx_;
    if (mc_can_id_cmd(f.id) != MC_CAN_CMD_CMD_ERROR) continue;
    uint32_t msg = 0;
    float v[MC_CAN_NSIG_MAX] = {0};
    if (mc_can_proto_unpack(&f, &msg, v, MC_CAN_NSIG_MAX) != MC_CAN_ERR_NONE) continue;
    const auto code = static_cast<uint32_t>(v[MC_CAN_CMD_ERROR_ERROR]);
    if (code == MC_CAN_ERR_ANGLE_UNKNOWN) {
      throw UsageError(
          "the drive application refused the enable: CMD_ERROR ANGLE_UNKNOWN (the mode needs "
          "the rotor's angle, unknown since power-up: angle_ref " +
          std::string(t_.params().angle_ref == MC_DRIVE_ANGLE_REF_INDEX ? "index" : "align") +
          " without angle_find_at_enable; the stored encoder offset is not used before the " +
          std::string(t_.params().angle_ref == MC_DRIVE_ANGLE_REF_INDEX ? "index is seen"
                                                                        : "alignment") +
          ")");
    }
    throw UsageError("the drive application refused command 0x" +
                     [](uint32_t c) {
                       char b[8];
                       std::snprintf(b, sizeof b, "%02x", c);
                       return std::string(b);
                     }(static_cast<uint32_t>(v[MC_CAN_CMD_ERROR_REJECTED_CMD])) +
                     " (CMD_ERROR error " +
                     std::to_string(static_cast<int>(v[MC_CAN_CMD_ERROR_ERROR])) +
                     ") at t = " + std::to_string(t) + " s");
  }
  return r;
}

}  // namespace mcsim
