#include "run.hpp"

namespace mcsim {

const Scenario& need_scenario(const std::string& name) {
  const Scenario* s = find_scenario(name);
  if (s == nullptr) {
    throw UsageError("unknown scenario '" + name + "' (see 'mcsim list')");
  }
  return *s;
}

std::unique_ptr<MotorFiles> motor_files(const Scenario& s, const std::string& motor,
                                        const std::string& board, const Overrides& overrides) {
  if (!s.motor_params) {
    if (!motor.empty() || !board.empty()) {
      throw UsageError("scenario '" + s.name +
                       "' runs its own motor and takes no --motor "
                       "or --board (the scenarios for any motor: current-step, "
                       "speed-step, sensorless-speed-step, load-step)");
    }
    return nullptr;
  }
  if (motor.empty()) {
    if (s.motor_optional && board.empty() && overrides.empty()) return nullptr;  // its own motor
    throw UsageError("scenario '" + s.name +
                     "' needs --motor FILE (and --board FILE "
                     "unless the motor file has a [board] table); see sim/motors/");
  }
  return std::make_unique<MotorFiles>(load_motor_files(motor, board, overrides));
}

PreparedRun prepare_run(const std::string& scenario, const std::string& motor_path,
                        const std::string& board_path,
                        const std::vector<std::pair<std::string, std::string>>& sets,
                        const std::string& flash_path) {
  PreparedRun r;
  r.scenario = &need_scenario(scenario);
  // motor.KEY= and board.KEY= edit the files (scenarios for any motor);
  // every other key is a scenario parameter.
  Overrides file_sets;
  std::vector<std::pair<std::string, std::string>> params;
  for (const auto& kv : sets) {
    const bool file_key = kv.first.rfind("motor.", 0) == 0 || kv.first.rfind("board.", 0) == 0;
    (file_key && r.scenario->motor_params ? file_sets : params).push_back(kv);
  }
  r.files = motor_files(*r.scenario, motor_path, board_path, file_sets);
  r.params = Params(r.files ? r.scenario->motor_params(*r.files) : r.scenario->params,
                    params);  // validates keys and values
  if (!flash_path.empty()) {
    if (!r.scenario->takes_flash) {
      std::string with;
      for (const auto& s : registry()) {
        if (s.takes_flash) with += (with.empty() ? "" : ", ") + s.name;
      }
      throw UsageError("scenario '" + r.scenario->name + "' has no flash: --flash FILE is for " +
                       with);
    }
    try {
      r.flash = std::make_unique<hal_host::FileFlash>(flash_path);
    } catch (const hal_host::FileFlashError& e) {
      throw UsageError(e.what());
    }
  }
  return r;
}

void execute_run(const PreparedRun& run, double duration_s, RowSink& sink, Summary& summary,
                 Progress& progress) {
  const Scenario& scen = *run.scenario;
  RunContext ctx{duration_s, run.params, sink, summary, progress, run.files.get(), run.flash.get()};
  summary.set_text("scenario", scen.name);
  summary.set("duration_s", duration_s);
  for (const auto& kv : run.params.values()) summary.set("param." + kv.first, kv.second);
  scen.run(ctx);
  progress.done();
  summary.set("rows", static_cast<double>(sink.rows()));
}

}  // namespace mcsim
