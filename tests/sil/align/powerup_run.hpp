// What the power-up tests share (test_powerup_sil.cpp,
// test_powerup_spienc_sil.cpp): a run through the path of `mcsim run`
// (prepare_run, execute_run: the files, the --set keys, the flash file)
// with its summary and its columns, a folder per test for the flash files,
// and the power-up angles drawn from a stated seed.
#ifndef MC_TESTS_POWERUP_RUN_HPP
#define MC_TESTS_POWERUP_RUN_HPP

#include <gtest/gtest.h>

#include <cstddef>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "run.hpp"
#include "scenario.hpp"

namespace mcsim::powerup {

constexpr double kPi = 3.14159265358979323846;
constexpr int kPowerUps = 8;

using Sets = std::vector<std::pair<std::string, std::string>>;

struct RunResult {
  RunOutcome out;
  std::map<std::string, double> num;
  std::map<std::string, std::string> txt;
  std::vector<std::string> cols;
  std::vector<double> data;  // row-major, cols.size() per row
  // the mean of column c over the rows with t at or after t0 (NaN: none)
  double mean_after(const std::string& c, double t0) const {
    std::size_t j = 0;
    while (j < cols.size() && cols[j] != c) ++j;
    double sum = 0;
    long n = 0;
    for (std::size_t k = 0; j < cols.size() && k + cols.size() <= data.size(); k += cols.size()) {
      if (data[k] < t0) continue;
      sum += data[k + j];
      ++n;
    }
    return n > 0 ? sum / static_cast<double>(n) : std::nan("");
  }
};

// A run as `mcsim run SCENARIO --motor .. --board .. --set .. [--flash F]`;
// prepare_run's refusals (mcsim's exit 2) come back as kRefused.
inline RunResult run(const std::string& scen, const std::string& motor, const std::string& board,
                     const Sets& sets, const std::string& flash) {
  RunResult r;
  try {
    const PreparedRun p = prepare_run(scen, motor, board, sets, flash);
    ColumnSink sink;
    Summary sum;
    Progress prog(false);
    r.out = execute_run(p, sink, sum, prog);
    r.num = sum.numbers();
    r.txt = sum.texts();
    r.cols = sink.names();
    r.data = sink.data();
  } catch (const UsageError& e) {
    r.out.kind = RunOutcome::Kind::kRefused;
    r.out.message = e.what();
  }
  return r;
}

// A file `name` in a folder of the running test's own.
inline std::string tmp(const std::string& prefix, const std::string& name) {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const std::string dir = ::testing::TempDir() + "/" + prefix + info->name();
  std::filesystem::create_directories(dir);
  return dir + "/" + name;
}

inline std::string bytes(const std::string& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// kPowerUps mechanical angles at power-up, anywhere in the turn.
inline std::vector<double> power_up_angles(unsigned seed) {
  std::mt19937 gen(seed);
  std::uniform_real_distribution<double> u(-kPi, kPi);
  std::vector<double> v;
  for (int k = 0; k < kPowerUps; ++k) v.push_back(u(gen));
  return v;
}

}  // namespace mcsim::powerup

#endif  // MC_TESTS_POWERUP_RUN_HPP
