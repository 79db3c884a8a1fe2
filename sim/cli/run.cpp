#include "run.hpp"

#include <sstream>

namespace mcsim {

const Scenario& need_scenario(const std::string& name) {
  const Scenario* s = find_scenario(name);
  if (s == nullptr) {
    throw UsageError("unknown scenario '" + name + "' (see 'mcsim list')");
  }
  return *s;
}

namespace {

// The scenarios that take a [stepper] file, comma separated.
std::string stepper_scenarios() {
  std::string with;
  for (const auto& sc : registry()) {
    if (sc.takes_stepper) with += (with.empty() ? "" : ", ") + sc.name;
  }
  return with.empty() ? "no scenario" : with;
}

}  // namespace

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
  auto f = std::make_unique<MotorFiles>(load_motor_files(motor, board, overrides));
  if (f->is_stepper && !s.takes_stepper) {
    throw UsageError(motor + ": a [stepper] file (a two-phase stepper): scenario '" + s.name +
                     "' runs a PMSM ([motor] table); the stepper runs in " + stepper_scenarios());
  }
  if (!f->is_stepper && s.takes_stepper) {
    throw UsageError(motor + ": a [motor] file (a PMSM): scenario '" + s.name +
                     "' runs a two-phase stepper, a file with a [stepper] table (see sim/motors/)");
  }
  return f;
}

PreparedRun prepare_run(const std::string& scenario, const std::string& motor_path,
                        const std::string& board_path,
                        const std::vector<std::pair<std::string, std::string>>& sets,
                        const std::string& flash_path, double duration_s) {
  PreparedRun r;
  r.scenario = &need_scenario(scenario);
  if (duration_s != 0.0) {
    if (!r.scenario->takes_duration) {
      throw UsageError("scenario '" + r.scenario->name +
                       "' takes no --duration: its length is set by what it does (see 'mcsim "
                       "describe " +
                       r.scenario->name + "')");
    }
    if (!(duration_s > 0.0) || duration_s > kMaxDurationS) {
      std::ostringstream os;
      os << "duration " << duration_s << " s is out of range (0, " << kMaxDurationS
         << "] s (one simulated hour: the longest run mcsim takes)";
      throw UsageError(os.str());
    }
  }
  r.duration_s = duration_s > 0.0 ? duration_s : r.scenario->default_duration_s;
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

RunOutcome execute_run(const PreparedRun& run, RowSink& sink, Summary& summary, Progress& progress,
                       const std::string& out_dir) {
  const Scenario& scen = *run.scenario;
  RunContext ctx{run.duration_s,  run.params,      sink,    summary,      progress,
                 run.files.get(), run.flash.get(), out_dir, run.pil.get()};
  summary.set_text("scenario", scen.name);
  summary.set("duration_s", run.duration_s);
  for (const auto& kv : run.params.values()) summary.set("param." + kv.first, kv.second);
  RunOutcome out;
  try {
    scen.run(ctx);
  } catch (const UsageError& e) {
    out.kind = RunOutcome::Kind::kRefused;
    out.message = e.what();
  } catch (const std::exception& e) {
    out.kind = RunOutcome::Kind::kFailed;
    out.stopped = true;
    out.message = std::string("run failed: ") + e.what();
    summary.set_text("verdict", std::string("failed: ") + e.what());
    summary.set_text("verdict_detail", "the run stopped on its way");
    summary.set("stopped", 1.0);
  }
  progress.done();
  summary.set("rows", static_cast<double>(sink.rows()));
  if (out.kind != RunOutcome::Kind::kPass) return out;
  const auto v = summary.texts().find("verdict");
  if (v == summary.texts().end()) {
    throw std::logic_error("scenario '" + scen.name + "' returned without a verdict");
  }
  if (v->second == "pass" || v->second == "none") return out;
  out.kind = RunOutcome::Kind::kFailed;
  const auto st = summary.numbers().find("stopped");
  out.stopped = st != summary.numbers().end() && st->second != 0.0;
  const auto d = summary.texts().find("verdict_detail");
  out.message = "run failed: " + v->second +
                (d != summary.texts().end() && !d->second.empty() ? " (" + d->second + ")" : "");
  return out;
}

}  // namespace mcsim
