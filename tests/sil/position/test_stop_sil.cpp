// Controlled stop (mc_drive MODE_STOPPING) through the drive application
// (mc_app on the simulated board, booted from the motor and board files'
// parameter table, commanded by CAN frames): the host stops sending its
// HOST_HEARTBEAT keep-alive, the application's command timeout
// (can_timeout_s) stops the drive; in speed mode it decelerates to
// standstill at stop_decel_rad_s2 before the bridge opens, in position mode
// the law's stop op does the same.
//
// Bounds: the bridge opens with |omega| <= stop_rest_rad_s + 1 % of the
// starting speed; the stop takes between 0.95 and 1.2 omega_0 / decel
// (the drive's P loop may reach the rest speed about 1/wc after its ramp
// ends); the rotor never turns backwards by more than 2 decel T (speed
// mode: plus stop_rest_rad_s, below).
// Measured figures: firmware/app/README.md (drive-stop).
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>

#include "app_scenario.hpp"
#include "mc_record.hpp"
#include "motor_file.hpp"

namespace mcsim {
namespace {

const std::string kDir = MCSIM_MOTORS_DIR;
constexpr double kTwoPi = 6.283185307179586;

struct StopResult {
  double t_stop_s, w0, w_at_open, decel, rest;
  double w_back;  // largest speed against w0's direction during the stop [rad/s]
  double period_s;
  uint32_t faults, stop_reason;
  bool speed_mode;
};

StopResult RunStop(const char* motor, const char* board, bool position) {
  const MotorFiles f = load_motor_files(kDir + "/" + motor + ".toml", kDir + "/" + board + ".toml");
  const mc_params_t p = params_from_files(f, Params(app_gain_params(f), {}));
  const mc_params_eff_t e = resolve_params(p);
  mc_drive_cfg_t dc{};
  mc_params_eff_to_drive_cfg(&e, &dc);
  const std::unique_ptr<AppTarget> target = make_file_target(f, p, nullptr);
  AppRunner run(*target);
  hal_host::PmsmBoard& b = run.board();
  StopResult r{};
  r.speed_mode = !position;
  const double w_t = 0.5 * e.g.speed_rated_eff_rad_s;
  const double T = b.period_s();
  r.period_s = T;
  // Run up: speed loop to w_t, or a long position move cruising at pos_v_max.
  run.start(position ? MC_CAN_CTRL_POSITION : MC_CAN_CTRL_SPEED);
  run.send(position ? run.cmd().position_ref(1000.0 * kTwoPi) : run.cmd().speed_ref(w_t));
  const double t_run =
      2.0 * std::max(w_t, e.g.pos_v_max_rad_s) / e.p.speed_ramp_rad_s2 + 40.0 / e.g.speed_wc_rad_s;
  for (long k = 0; k < std::lround(t_run / T); ++k) run.step();
  // The host goes silent: the application stops the drive after its timeout.
  run.keepalive(false);
  const double t_silent = b.t_s();
  while (run.probe().mode != MC_DRIVE_MODE_STOPPING && b.t_s() < t_silent + 2.0 * p.can_timeout_s) {
    run.step();
  }
  EXPECT_EQ(MC_DRIVE_MODE_STOPPING, run.probe().mode);
  EXPECT_NEAR(b.t_s() - t_silent, p.can_timeout_s, 0.1 * p.can_timeout_s + 2e-3);
  r.w0 = b.state()(2);
  r.decel = dc.stop_decel_rad_s2;
  r.rest = dc.stop_rest_rad_s;
  const double t0 = b.t_s();
  const double dir = (r.w0 < 0.0) ? -1.0 : 1.0;
  r.w_back = 0.0;
  while (run.probe().mode == MC_DRIVE_MODE_STOPPING && b.t_s() < t0 + 5.0) {
    run.step();
    r.w_back = std::max(r.w_back, -dir * b.state()(2));
  }
  r.t_stop_s = b.t_s() - t0;
  r.w_at_open = b.state()(2);
  // the application's slow step sees the end of the stop
  for (long k = 0; k < static_cast<long>(2 * p.slow_loop_div); ++k) run.step();
  r.faults = run.probe().faults;
  r.stop_reason = run.probe().cmd_stop_reason;
  EXPECT_EQ(MC_DRIVE_MODE_IDLE, run.probe().mode);
  return r;
}

void Check(const StopResult& r) {
  EXPECT_EQ(0u, r.faults);
  EXPECT_EQ(MC_CAN_STOP_CMD_TIMEOUT, r.stop_reason);
  EXPECT_GT(std::abs(r.w0), 10.0);
  EXPECT_LE(std::abs(r.w_at_open), r.rest + 0.01 * std::abs(r.w0));
  const double t_pred = std::abs(r.w0) / r.decel;
  EXPECT_GE(r.t_stop_s / t_pred, 0.95);
  EXPECT_LE(r.t_stop_s / t_pred, 1.20) << "t_stop " << r.t_stop_s << " pred " << t_pred;
  mc_record("stop_time_ratio", r.t_stop_s / t_pred, 1.20);
  // A stop never drives the rotor backwards: the drive opens the bridge in
  // the fast step whose encoder speed has crossed zero. What is left: the
  // period in which the crossing happens and the period in which that
  // step's current still acts, each at most decel * T.
  // Speed mode runs the application's sensored speed law, which follows the
  // drive's shaped reference down its ramp: measured 0.20 rad/s backwards on
  // the paper-002 motor (0 with the former C++ speed PI in CURRENT mode),
  // inside the drive's rest band stop_rest_rad_s (0.21 rad/s there), where
  // the slow loop ends the stop. Bound for speed mode: 2 decel T plus that
  // band (an open question for the law's stop, see the commit).
  const double back_max = 2.0 * r.decel * r.period_s + (r.speed_mode ? r.rest : 0.0);
  EXPECT_LE(r.w_back, back_max) << "the stop reversed the rotor";
  mc_record("reverse_speed_rad_s", r.w_back, back_max);
  std::printf(
      "stop: w0 %.2f rad/s, decel %.1f rad/s^2, t %.5f s (pred %.5f, ratio %.4f), "
      "w at bridge off %.4f rad/s\n",
      r.w0, r.decel, r.t_stop_s, t_pred, r.t_stop_s / t_pred, r.w_at_open);
  std::printf("stop: largest speed against the start direction %.4f rad/s\n", r.w_back);
}

TEST(StopSil, SpeedModeTimeoutStopD5065) {
  Check(RunStop("odrive-d5065", "odrive-v36-24v", false));
}
TEST(StopSil, SpeedModeTimeoutStopPaperMotor) {
  Check(RunStop("paper002-test-motor", "paper002-200v", false));
}
TEST(StopSil, PositionModeStopD5065) {
  Check(RunStop("odrive-d5065", "odrive-v36-24v", true));
}
TEST(StopSil, PositionModeStopPaperMotor) {
  Check(RunStop("paper002-test-motor", "paper002-200v", true));
}

}  // namespace
}  // namespace mcsim
