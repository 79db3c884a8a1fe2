// Shared by the SIL tests that run the scenarios for any motor (tests/sil/
// motors, position, commission): the library's motor/board pairs, loading
// them, and running a registered scenario in-process as `mcsim run` does
// (its summary returned). The test target defines MCSIM_MOTORS_DIR.
#pragma once

#include <gtest/gtest.h>

#include <cctype>
#include <filesystem>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "plant_from_files.hpp"
#include "motor_file.hpp"
#include "scenario.hpp"

namespace mcsim {
namespace testlib {

struct Case {
  const char* motor;
  const char* board;  // "" = the motor file holds [board]
};

// Every motor of sim/motors with the board it is run on (sim/motors/README.md).
inline const std::vector<Case>& library() {
  static const std::vector<Case> cases = {
      {"paper002-test-motor", "paper002-200v"}, {"paper002-40kw", ""},
      {"odrive-d5065", "odrive-v36-24v"},       {"gimbal-gm4108", "gimbal-24v"},
      {"low-l-8uh", "low-l-48khz-24v"},         {"turnigy-sk3-6374-149kv", "vesc6-48v"},
      {"hub-6p5in-15pp", "odrive-v36-56v"},     {"u8-class-kv100", "odrive-v36-56v"},
  };
  return cases;
}

inline MotorFiles files(const Case& c) {
  const std::string dir = MCSIM_MOTORS_DIR;
  return load_motor_files(dir + "/" + c.motor + ".toml",
                          c.board[0] ? dir + "/" + c.board + ".toml" : "");
}

// The hub motor (its Hall sensors read as an encoder) on the 56 V ODrive
// v3.6 with `cpr` counts a turn: the coarse-sensor cases (issue 31 item 3).
inline MotorFiles hub_on_odrive(int cpr) {
  const std::string dir = MCSIM_MOTORS_DIR;
  MotorFiles f = load_motor_files(dir + "/hub-6p5in-15pp.toml", dir + "/odrive-v36-56v.toml");
  f.board.encoder_cpr = cpr;
  return f;
}

// A name usable as a gtest parameter name or a folder name.
inline std::string identifier(std::string s) {
  for (auto& ch : s) {
    if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
  }
  return s;
}

inline std::string case_name(const ::testing::TestParamInfo<Case>& i) {
  return identifier(i.param.motor);
}

using Sets = std::vector<std::pair<std::string, std::string>>;

// Runs scenario `scen` for the files as `mcsim run` does, writing its CSV in
// a folder of its own per test (ctest runs tests in parallel; `tag` tells
// apart several runs of one test) and returns the summary's numbers.
inline std::map<std::string, double> run_scenario(
    const std::string& scen, const MotorFiles& f, const Sets& sets, const std::string& tag = "",
    std::map<std::string, std::string>* texts = nullptr) {
  const Scenario* s = find_scenario(scen);
  if (s == nullptr) throw std::logic_error("scenario " + scen + " not registered");
  const Params p(s->motor_params(f), sets);
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const std::string dir =
      ::testing::TempDir() + "/" +
      identifier(std::string(info->test_suite_name()) + "_" + info->name() + tag);
  std::filesystem::create_directories(dir);
  CsvWriter csv(dir + "/" + scen + ".csv");
  Summary sum;
  Progress prog(false);
  RunContext ctx{0.0, p, csv, sum, prog, &f};
  s->run(ctx);
  csv.commit();
  if (texts != nullptr) *texts = sum.texts();
  return sum.numbers();
}

}  // namespace testlib
}  // namespace mcsim
