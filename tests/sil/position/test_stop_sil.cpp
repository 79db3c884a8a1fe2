// Controlled stop (mc_drive MODE_STOPPING) in the SIL rig: a command-timeout
// stop (mc_drive_stop, what mc_can_cmd does on a timeout) in speed mode at
// speed decelerates to standstill at stop_decel_rad_s2 before the bridge
// opens; in position mode the law's stop op does the same.
//
// Bounds: the bridge opens with |omega| <= stop_rest_rad_s + 1 % of the
// starting speed; the stop takes between 0.95 and 1.2 omega_0 / decel
// (the drive's P loop may reach the rest speed about 1/wc after its ramp
// ends); the rotor never turns backwards by more than 2 decel T (below).
// Measured figures: firmware/app/README.md (drive-stop).
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "drive_setup.hpp"
#include "motor_file.hpp"
#include "mc_record.hpp"

namespace mcsim {
namespace {

const std::string kDir = MCSIM_MOTORS_DIR;

struct StopResult {
  double t_stop_s, w0, w_at_open, decel, rest;
  double w_back;  // largest speed against w0's direction during the stop [rad/s]
  double period_s;
  uint32_t faults;
};

StopResult RunStop(const char* motor, const char* board, Law law) {
  const MotorFiles f = load_motor_files(kDir + "/" + motor + ".toml", kDir + "/" + board + ".toml");
  const Gains g = derive_gains(f, nullptr);
  RigOptions ro;
  ro.law = law;
  MotorRig rig(f, g, ro);
  StopResult r{};
  const double w_t = 0.5 * g.speed_rated_eff_rad_s;
  const double T = rig.period_s();
  r.period_s = T;
  // Run up: speed loop to w_t, or a long position move cruising at pos_v_max.
  if (law == Law::kPosition) {
    EXPECT_EQ(0u, mc_ctrl_pos_set_target(&rig.pos(), 1000, 0.0f));
  } else {
    rig.set_speed_ref(w_t);
  }
  const double t_run =
      2.0 * std::max(w_t, g.pos_v_max_rad_s) / g.speed_accel_rad_s2 + 40.0 / g.speed_wc_rad_s;
  for (long k = 0; k < std::lround(t_run / T); ++k) rig.step();
  r.w0 = rig.board().state()(2);
  r.decel = rig.drive_cfg().stop_decel_rad_s2;
  r.rest = rig.drive_cfg().stop_rest_rad_s;
  EXPECT_EQ(0, mc_drive_stop(&rig.drive()));
  EXPECT_EQ(MC_DRIVE_MODE_STOPPING, rig.drive().mode);
  const double t0 = rig.board().t_s();
  const double dir = (r.w0 < 0.0) ? -1.0 : 1.0;
  r.w_back = 0.0;
  while (rig.drive().mode == MC_DRIVE_MODE_STOPPING && rig.board().t_s() < t0 + 5.0) {
    rig.step();
    r.w_back = std::max(r.w_back, -dir * rig.board().state()(2));
  }
  r.t_stop_s = rig.board().t_s() - t0;
  r.w_at_open = rig.board().state()(2);
  r.faults = rig.drive().faults;
  EXPECT_EQ(MC_DRIVE_MODE_IDLE, rig.drive().mode);
  return r;
}

void Check(const StopResult& r) {
  EXPECT_EQ(0u, r.faults);
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
  const double back_max = 2.0 * r.decel * r.period_s;
  EXPECT_LE(r.w_back, back_max) << "the stop reversed the rotor";
  mc_record("reverse_speed_rad_s", r.w_back, back_max);
  std::printf(
      "stop: w0 %.2f rad/s, decel %.1f rad/s^2, t %.5f s (pred %.5f, ratio %.4f), "
      "w at bridge off %.4f rad/s\n",
      r.w0, r.decel, r.t_stop_s, t_pred, r.t_stop_s / t_pred, r.w_at_open);
  std::printf("stop: largest speed against the start direction %.4f rad/s\n", r.w_back);
}

TEST(StopSil, SpeedModeTimeoutStopD5065) {
  Check(RunStop("odrive-d5065", "odrive-v36-24v", Law::kSpeedPi));
}
TEST(StopSil, SpeedModeTimeoutStopPaperMotor) {
  Check(RunStop("paper002-test-motor", "paper002-200v", Law::kSpeedPi));
}
TEST(StopSil, PositionModeStopD5065) {
  Check(RunStop("odrive-d5065", "odrive-v36-24v", Law::kPosition));
}
TEST(StopSil, PositionModeStopPaperMotor) {
  Check(RunStop("paper002-test-motor", "paper002-200v", Law::kPosition));
}

}  // namespace
}  // namespace mcsim
