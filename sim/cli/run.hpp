// One scenario run, the same for the mcsim CLI and the Python binding
// (tools/mdtool, mdtool._sil): validate everything first, then run into a
// RowSink (a CSV file, or columns in memory) and a Summary, and judge it by
// the verdict the scenario wrote (sim/cli/verdict.hpp).
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
  double duration_s = 0.0;  ///< the run's: --duration, else the scenario's default
  /// --pil: the PIL target's QEMU, image and bootloader (takes_pil
  /// scenarios only); null: the SIL.
  std::shared_ptr<const AppTargetPilOptions> pil;
};

/// Scenario name, motor and board files and every key=value checked (the
/// messages of `mcsim run`, as UsageError). flash_path ("" = none): the
/// board's flash file (hal_host::FileFlash), opened and checked here
/// ("<file>: <reason>" as UsageError; nothing is written until the run
/// erases or programs it); only for scenarios with takes_flash.
/// duration_s: 0 for the scenario's own; else in (0, kMaxDurationS], and
/// only for scenarios that take a duration (UsageError otherwise).
PreparedRun prepare_run(const std::string& scenario, const std::string& motor_path,
                        const std::string& board_path,
                        const std::vector<std::pair<std::string, std::string>>& sets,
                        const std::string& flash_path = "", double duration_s = 0.0);

/// How a run ended; mcsim's exit code and mdtool.sil's error_kind.
struct RunOutcome {
  enum class Kind {
    kPass,     ///< verdict "pass" (or "none": the scenario has no claim to check); exit 0
    kFailed,   ///< verdict not a pass, or the run stopped on its way; exit 1
    kRefused,  ///< a setting refused inside the run (UsageError); exit 2
  };
  Kind kind = Kind::kPass;
  /// kFailed: the run stopped on its way (an exception, a drive fault, a
  /// sequence that stopped: the summary's stopped = 1) rather than ran to
  /// its end and judged itself.
  bool stopped = false;
  /// kFailed, kRefused: what mcsim prints after "mcsim: ".
  std::string message;
};

/// Run it: summary keys scenario, duration_s and param.*, the scenario's own,
/// its verdict, then rows. Never throws for what the scenario does: a
/// UsageError inside the run is kRefused; any other exception is kFailed
/// with the summary's verdict "failed: <what>"; a run that returns is judged
/// by the verdict it wrote ("pass", "none", else kFailed). A scenario that
/// returns without a verdict is a programming error (std::logic_error).
/// The summary holds what was set up to the end and the sink the rows.
/// out_dir: mcsim's --out (RunContext::out_dir), "" in memory.
RunOutcome execute_run(const PreparedRun& run, RowSink& sink, Summary& summary, Progress& progress,
                       const std::string& out_dir = "");

}  // namespace mcsim
