// position-move through the drive application (mc_app's position law,
// mc_ctrl_position on mc_drive, commanded by SET_POSITION_REF frames) on the
// D5065 and the paper-002 test motor: a 10-turn trapezoid, a re-plan
// mid-move; a move streamed as setpoints through the input filter.
//
// Bounds (measured values in sim/cli/README or the commit; 8192 counts/turn):
//   final error        <= count_band: 1 encoder count (the law's own
//                      measurement) plus how far SET_POSITION_REF's 1e-4 rad
//                      resolution puts the target off the count grid (at
//                      most 0.07 count at 8192 counts/turn): the loop rests
//                      on a count, its +-1 count dither around a target
//                      between two counts reaches 1 + that offset
//   reach time         first entry within count_band: within 2 % of the
//                      trapezoid's predicted duration
//   overshoot          <= 32 counts (1/256 turn). Measured 24 (D5065) and
//                      7 (paper motor): the drive's encoder tracking loop
//                      (bw 1000 rad/s) answers the step of acceleration at
//                      the end of the deceleration with a speed transient of
//                      about d/bw, which the velocity PI turns into torque.
//   settle time        last entry within count_band: within 1.4x the predicted
//                      duration (the same transient decays at the position
//                      loop's pace)
//   re-plan            the velocity reference changes by at most max(a, d) T
//                      per period (continuous; only the acceleration steps)
#include <gtest/gtest.h>

#include <cctype>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "motor_library.hpp"

namespace mcsim {
namespace {

using testlib::Case;

const Case kCases[] = {{"odrive-d5065", "odrive-v36-24v"},
                       {"paper002-test-motor", "paper002-200v"}};

std::map<std::string, double> run(const Case& c, const testlib::Sets& sets) {
  return testlib::run_scenario("position-move", testlib::files(c), sets);
}

class PositionSil : public ::testing::TestWithParam<Case> {};

TEST_P(PositionSil, TenTurnMoveReachesWithinOneCountOnTime) {
  const auto r = run(GetParam(), {{"turns", "10"}});
  EXPECT_EQ(r.at("faults"), 0.0);
  EXPECT_LE(r.at("final_err_counts"), r.at("count_band"));
  EXPECT_LE(r.at("final_err_true_counts"), r.at("count_band"));
  EXPECT_NEAR(r.at("reach_time_ratio"), 1.0, 0.02);
  EXPECT_LT(r.at("move_time_ratio"), 1.4);
  EXPECT_LE(r.at("overshoot_counts"), 32.0);
  EXPECT_LE(r.at("dv_ref_max_rad_s"), r.at("dv_ref_bound_rad_s") * 1.001);
}

TEST_P(PositionSil, NegativeShortTriangleMove) {
  const auto r = run(GetParam(), {{"turns", "-0.25"}});
  EXPECT_EQ(r.at("faults"), 0.0);
  EXPECT_LE(r.at("final_err_counts"), r.at("count_band"));
  // A 31 ms triangle on the D5065: the end transient (above) is a
  // larger part of it; within 10 ms of the prediction (measured 9 ms).
  EXPECT_LE(r.at("reach_time_s"), r.at("move_time_pred_s") + 0.010);
  EXPECT_GE(r.at("reach_time_s"), r.at("move_time_pred_s") * 0.98);
  EXPECT_LE(r.at("overshoot_counts"), 32.0);
}

// A new target (back to 3 turns) half-way through a 10-turn move: the
// velocity reference stays continuous, the new target is reached.
TEST_P(PositionSil, ReplanMidMoveIsSmooth) {
  const auto r = run(GetParam(), {{"turns", "10"}, {"replan_frac", "0.5"}, {"replan_turns", "3"}});
  EXPECT_EQ(r.at("faults"), 0.0);
  EXPECT_LE(r.at("dv_ref_max_rad_s"), r.at("dv_ref_bound_rad_s") * 1.001);
  EXPECT_LE(r.at("final_err_counts"), r.at("count_band"));
  EXPECT_NEAR(r.at("reach_time_ratio"), 1.0, 0.02);
  EXPECT_LE(r.at("overshoot_counts"), 32.0);
}

// Setpoints streamed through the input filter (stream=1: the scenario sets
// pos_input_mode = 1 and sends a (1 - cos) ramp of 10 turns as
// SET_POSITION_REF frames at 200 Hz): the target is reached within
// count_band, the rotor follows the filter's reference within 0.01 rad
// (the scenario's verdict: the velocity PI's lag behind a reference that is
// smooth to the second derivative), with no fault.
TEST_P(PositionSil, StreamedSetpointsThroughTheInputFilter) {
  const auto r = run(GetParam(), {{"turns", "10"}, {"stream", "1"}});
  EXPECT_EQ(r.at("pos_input_mode"), 1.0);  // the application's table, as booted
  EXPECT_EQ(r.at("faults"), 0.0);
  EXPECT_LE(r.at("final_err_counts"), r.at("count_band"));
  EXPECT_LE(r.at("track_err_max_rad"), 0.01);
}

INSTANTIATE_TEST_SUITE_P(Motors, PositionSil, ::testing::ValuesIn(kCases), testlib::case_name);

}  // namespace
}  // namespace mcsim
