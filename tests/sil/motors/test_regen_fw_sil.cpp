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

#include "drive_setup.hpp"
#include "motor_file.hpp"
#include "scenario.hpp"

namespace mcsim {
namespace {

const std::string kDir = MCSIM_MOTORS_DIR;

struct Case {
  const char* motor;
  const char* board;  // "" = the motor file holds [board]
};

MotorFiles files(const Case& c) {
  return load_motor_files(kDir + "/" + c.motor + ".toml",
                          c.board[0] ? kDir + "/" + c.board + ".toml" : "");
}

std::map<std::string, double> run(const std::string& scen, const MotorFiles& f,
                                  const std::vector<std::pair<std::string, std::string>>& sets,
                                  const std::string& tag) {
  const Scenario* s = find_scenario(scen);
  if (s == nullptr) throw std::logic_error("scenario " + scen + " not registered");
  const Params p(s->motor_params(f), sets);
  std::string name = ::testing::UnitTest::GetInstance()->current_test_info()->name() + tag;
  for (auto& ch : name) {
    if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
  }
  const std::string dir = ::testing::TempDir() + "/regen_fw_sil_" + name;
  std::filesystem::create_directories(dir);
  CsvWriter csv(dir + "/" + scen + ".csv");
  Summary sum;
  Progress prog(false);
  RunContext ctx{0.0, p, csv, sum, prog, &f};
  s->run(ctx);
  csv.commit();
  return sum.numbers();
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
  const auto r = run("regen-stop", files({"odrive-d5065", "odrive-v36-24v"}), {{"brake", "on"}},
                     "");
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

INSTANTIATE_TEST_SUITE_P(
    Library, RegenStop,
    ::testing::Values(Case{"paper002-test-motor", "paper002-200v"}, Case{"paper002-40kw", ""},
                      Case{"odrive-d5065", "odrive-v36-24v"},
                      Case{"gimbal-gm4108", "gimbal-24v"}, Case{"low-l-8uh", "low-l-48khz-24v"},
                      Case{"turnigy-sk3-6374-149kv", "vesc6-48v"}),
    [](const ::testing::TestParamInfo<Case>& i) {
      std::string n = i.param.motor;
      for (auto& ch : n) {
        if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
      }
      return n;
    });

}  // namespace
}  // namespace mcsim
