// One scenario run, the same for the mcsim CLI and the Python binding
// (tools/mdtool, mdtool._sil): validate everything first, then run into a
// RowSink (a CSV file, or columns in memory) and a Summary.
#pragma once

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "hal_host/file_flash.hpp"
#include "motor_file.hpp"
#include "scenario.hpp"

namespace mcsim {

/// The scenario, or UsageError("unknown scenario ...").
const Scenario& need_scenario(const std::string& name);

/// --motor/--board for scenario s: the parsed files, or null for a scenario
/// with its own motor (which refuses them). UsageError on any problem.
std::unique_ptr<MotorFiles> motor_files(const Scenario& s, const std::string& motor_path,
                                        const std::string& board_path,
                                        const Overrides& overrides = {});

/// A run whose inputs were all checked: nothing has been written yet.
struct PreparedRun {
  const Scenario* scenario = nullptr;
  std::unique_ptr<MotorFiles> files;  ///< null for scenarios with their own motor
  Params params;
  std::unique_ptr<hal_host::FileFlash> flash;  ///< --flash FILE, opened; else null
};

/// Scenario name, motor and board files and every key=value checked (the
/// messages of `mcsim run`, as UsageError). flash_path ("" = none): the
/// board's flash file (hal_host::FileFlash), opened and checked here
/// ("<file>: <reason>" as UsageError; nothing is written until the run
/// erases or programs it); only for scenarios with takes_flash.
PreparedRun prepare_run(const std::string& scenario, const std::string& motor_path,
                        const std::string& board_path,
                        const std::vector<std::pair<std::string, std::string>>& sets,
                        const std::string& flash_path = "");

/// Run it: summary keys scenario, duration_s and param.*, the scenario's own,
/// then rows. duration_s <= 0: the scenario's own (from the motor for the
/// generic scenarios). Whatever the scenario throws propagates (a UsageError
/// for refused settings, std::exception for a failed run such as a drive
/// fault); the summary then holds what was set before the throw and the sink
/// the rows written so far.
void execute_run(const PreparedRun& run, double duration_s, RowSink& sink, Summary& summary,
                 Progress& progress);

}  // namespace mcsim
