// Issue 21 items 2 and 3 through the scenarios for any motor: regen-stop
// (DC link, regen current limit, brake chopper) and field-weakening (MTPA,
// voltage-feedback field weakening).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "motor_library.hpp"

namespace mcsim {
namespace {

using testlib::Case;
using testlib::files;

std::map<std::string, double> run(const std::string& scen, const MotorFiles& f,
                                  const testlib::Sets& sets, const std::string& tag) {
  return testlib::run_scenario(scen, f, sets, tag);
}

class RegenStop : public ::testing::TestWithParam<Case> {};

// A full-speed stop at the configured deceleration never trips on
// over-voltage, with and without the brake resistor; the energy balance
// over the stop (source + kinetic + magnetic = resistor + source R +
// windings and friction + capacitor) closes within 1 % of the kinetic
// energy; the resistor takes energy only when fitted.
TEST_P(RegenStop, FullSpeedStopBelowTripEnergyBalanced) {
  const MotorFiles f = files(GetParam());
  for (const char* brake : {"on", "off"}) {
    SCOPED_TRACE(std::string("brake=") + brake);
    const auto r = run("regen-stop", f, {{"brake", brake}}, brake);
    EXPECT_EQ(r.at("faults"), 0.0);
    EXPECT_LT(r.at("vbus_peak_v"), r.at("vbus_trip_v"));
    EXPECT_LT(std::abs(r.at("energy_balance_rel_err")), 0.01);
    EXPECT_TRUE(std::isfinite(r.at("stop_time_s")));
    if (std::string(brake) == "on") {
      EXPECT_GE(r.at("brake_energy_j"), 0.0);
    } else {
      EXPECT_EQ(r.at("brake_energy_j"), 0.0);
    }
  }
}

// With the resistor the stop follows the reference ramp (within 10 %),
// and the resistor takes most of the kinetic energy on the motors whose
// braking power lifts the bus above the chopper's threshold.
TEST(RegenStopBrake, ResistorTakesTheEnergyAndTheRampHolds) {
  const auto r =
      run("regen-stop", files({"odrive-d5065", "odrive-v36-24v"}), {{"brake", "on"}}, "");
  EXPECT_NEAR(r.at("stop_time_s"), r.at("stop_time_ramp_s"), 0.1 * r.at("stop_time_ramp_s"));
  EXPECT_GT(r.at("brake_energy_j"), 0.5 * r.at("kinetic_j"));
}

// Field weakening on the salient (IPM, Lq/Ld = 2) motor: MTPA torque per
// ampere within 1 % of the analytic optimum at 25..100 % rated current (and
// above the id = 0 torque constant), then a speed ramp to 2.5x base speed
// that holds without fault, the current inside its limit, the d current
// above the demagnetisation bound.
TEST(FieldWeakening, SalientMtpaAndRampTo2p5xBase) {
  const auto r = run("field-weakening", files({"ipm-representative-48v", ""}), {}, "");
  EXPECT_EQ(r.at("faults"), 0.0);
  EXPECT_LT(r.at("mtpa_rel_err_max"), 0.01);
  EXPECT_GT(r.at("mtpa_t_per_a_over_kt_max"), 1.05);
  EXPECT_NEAR(r.at("target_over_base"), 2.5, 1e-9);
  EXPECT_NEAR(r.at("omega_final_rad_s"), r.at("target_speed_rad_s"),
              0.02 * r.at("target_speed_rad_s"));
  EXPECT_LE(r.at("i_peak_a"), 1.05 * r.at("i_limit_a"));
  EXPECT_GE(r.at("id_min_a"), r.at("id_demag_bound_a") - 0.05 * r.at("i_limit_a"));
  // Past the point where the rectifier would conduct on a loss of control.
  EXPECT_GT(r.at("target_speed_rad_s"), r.at("omega_uncontrolled_gen_rad_s"));
}

// Non-salient motors: the MTPA d current is zero (what the loop leaves is
// current-loop noise, below 1 % of rated), the torque per ampere is kt.
TEST(FieldWeakening, NonSalientUnaffected) {
  const MotorFiles f = files({"odrive-d5065", "odrive-v36-24v"});
  const auto r = run("field-weakening", f, {}, "");
  EXPECT_EQ(r.at("faults"), 0.0);
  EXPECT_LT(r.at("mtpa_id_abs_max_a"), 0.01 * f.motor.i_rated_a);
  EXPECT_LT(r.at("mtpa_rel_err_max"), 0.01);
  EXPECT_NEAR(r.at("omega_final_rad_s"), r.at("target_speed_rad_s"),
              0.02 * r.at("target_speed_rad_s"));
}

INSTANTIATE_TEST_SUITE_P(Library, RegenStop, ::testing::ValuesIn(testlib::library()),
                         testlib::case_name);

}  // namespace
}  // namespace mcsim
