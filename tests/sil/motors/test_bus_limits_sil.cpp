// Issue 33 items 4 and 5 (bus-limits): the drive's DC-bus current limits
// (firmware/app/drive/mc_drive_bus.h) on the ODrive v3.6 (24 V and 56 V)
// and VESC 6 boards with their library motors, through the scenario bus-limits (sim/cli/scenarios):
// an acceleration and a regenerative stop on a supply with internal
// resistance.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <string>

#include "app_params.hpp"
#include "motor_library.hpp"

namespace mcsim {
namespace {

using testlib::Case;
using testlib::files;

class BusLimits : public ::testing::TestWithParam<Case> {};

// With the limits the supply current after the first period stays within
// 2 % of them (the bound: the steady-state model leaves the
// current loop's lag behind a falling reference, about 1.3 % measured)
// while the rotor still reaches 95 % of its speed and stops; the same run
// without them draws and returns more than 1.25 times each (measured 1.36
// on the hub motor's braking, whose 0.5 ohm winding burns much of the
// energy, 2.2 to 3.0 times elsewhere): the limits are what holds the
// current.
TEST_P(BusLimits, SupplyCurrentWithinItsLimitsAndNotWithout) {
  const MotorFiles f = files(GetParam());
  const auto on = testlib::run_scenario("bus-limits", f, {{"limits", "on"}}, "on");
  EXPECT_EQ(on.at("faults"), 0.0);
  EXPECT_EQ(on.at("stopped"), 0.0);
  EXPECT_LE(on.at("i_bus_excess_frac"), 0.02);
  EXPECT_LE(on.at("i_bus_regen_excess_frac"), 0.02);
  EXPECT_GT(on.at("i_bus_peak_a"), 0.9 * on.at("i_bus_max_a")) << "the limit was reached";
  EXPECT_LT(on.at("i_bus_min_a"), -0.9 * on.at("i_bus_regen_max_a")) << "braking reached it";
  EXPECT_GE(on.at("omega_peak_rad_s"), 0.95 * on.at("omega_start_rad_s"));
  EXPECT_LE(std::abs(on.at("omega_end_rad_s")), 0.02 * on.at("omega_start_rad_s"));
  const auto off = testlib::run_scenario("bus-limits", f, {{"limits", "off"}}, "off");
  EXPECT_EQ(off.at("faults"), 0.0);
  EXPECT_GT(off.at("i_bus_excess_frac"), 0.25);
  EXPECT_GT(off.at("i_bus_regen_excess_frac"), 0.25);
}

INSTANTIATE_TEST_SUITE_P(Boards, BusLimits,
                         ::testing::Values(Case{"odrive-d5065", "odrive-v36-24v"},
                                           Case{"turnigy-sk3-6374-149kv", "vesc6-48v"},
                                           Case{"hub-6p5in-15pp", "odrive-v36-56v"},
                                           Case{"u8-class-kv100", "odrive-v36-56v"}),
                         testlib::case_name);

// The supply's resistance is the scenario's (--set source_r_ohm): ten
// times the board's still holds the limits, and the bus sags and rises by
// the resistance times the current (the summary records the one used).
TEST(BusLimitsSupply, HigherSupplyResistanceStillWithinLimits) {
  const MotorFiles f = files({"odrive-d5065", "odrive-v36-24v"});
  const double r = 10.0 * f.board.source_r_ohm;
  const auto s = testlib::run_scenario("bus-limits", f, {{"source_r_ohm", std::to_string(r)}}, "");
  EXPECT_NEAR(s.at("source_r_ohm"), r, 1e-9 * r);
  EXPECT_EQ(s.at("faults"), 0.0);
  EXPECT_LE(s.at("i_bus_excess_frac"), 0.02);
  EXPECT_LE(s.at("i_bus_regen_excess_frac"), 0.02);
}

}  // namespace
}  // namespace mcsim
