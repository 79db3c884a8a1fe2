// mcsim scenario framework: a registry of named scenarios, each declaring its
// parameters (name, default, unit, description), a run function that writes
// rows to a CSV and metrics to a summary.
#pragma once

#include <cstdio>
#include <functional>
#include <map>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace hal_host {
class FileFlash;  // hal_host/file_flash.hpp
}

namespace mcsim {

struct MotorFiles;           // motor_file.hpp
struct AppTargetPilOptions;  // app_target.hpp

/// A user-visible error: printed as "mcsim: <what>", exit code 2.
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// The longest run mcsim accepts (--duration, a campaign's duration_s, a
/// scenario's own duration): one simulated hour. The longest default run is
/// 14 s; an hour of the 20 kHz drive is 7.2e7 PWM periods, about 5 minutes
/// at the release build's 250x real time (sim/README.md), and a typo such as
/// 1e300 is refused instead of running zero steps.
constexpr double kMaxDurationS = 3600.0;
/// The most periods (control or integration steps) one run may take: a
/// count every scenario's loop counter holds, and above what an hour of a
/// 100 kHz board needs (3.6e8).
constexpr double kMaxSteps = 1.0e9;

/// The number of periods of period_s in duration_s (rounded to nearest), or
/// UsageError naming both when it is not finite, negative or above
/// kMaxSteps: a count that does not fit is refused, never wrapped.
long step_count(double duration_s, double period_s);

/// One declared parameter of a scenario, settable with --set key=value.
struct ParamSpec {
  std::string key;
  double default_value;
  std::string unit;
  std::string help;
  double min_value;  ///< inclusive bounds; a value outside is a usage error
  double max_value;
  /// Named values accepted besides numbers (e.g. {"f32", 0}, {"q31", 1}).
  std::vector<std::pair<std::string, double>> choices = {};
};

/// Parameter values of one run: declared defaults overridden by --set.
class Params {
 public:
  Params() = default;
  Params(const std::vector<ParamSpec>& specs,
         const std::vector<std::pair<std::string, std::string>>& sets);
  double get(const std::string& key) const;
  const std::map<std::string, double>& values() const { return values_; }
  /// Whether key was given with --set (even at its default).
  bool was_set(const std::string& key) const { return set_.count(key) != 0u; }

 private:
  std::map<std::string, double> values_;
  std::set<std::string> set_;
};

/// Where a scenario's trajectory goes: a header fixed by the first call to
/// columns(), then rows of exactly that many values. The CLI writes a CSV
/// (CsvWriter); the Python binding keeps the numbers in memory (ColumnSink).
class RowSink {
 public:
  virtual ~RowSink() = default;
  virtual void columns(const std::vector<std::string>& names) = 0;
  virtual void row(const double* values, size_t n) = 0;
  void row(const std::vector<double>& values) { row(values.data(), values.size()); }
  size_t rows() const { return rows_; }

 protected:
  size_t rows_ = 0;
};

/// Column-oriented CSV: the header is fixed by the first call to columns(),
/// each row must have exactly that many values. Written to a temporary file
/// (final_path + ".part") and renamed into place by commit() or commit_as();
/// without either the destructor removes it.
class CsvWriter : public RowSink {
 public:
  CsvWriter(const std::string& final_path);
  ~CsvWriter() override;
  CsvWriter(const CsvWriter&) = delete;
  CsvWriter& operator=(const CsvWriter&) = delete;
  using RowSink::row;
  void columns(const std::vector<std::string>& names) override;
  void row(const double* values, size_t n) override;
  void commit() { commit_as(final_path_); }
  /// Renamed to path instead (mcsim: <scenario>.partial.csv for a failed run).
  void commit_as(const std::string& path);

 private:
  std::string final_path_, tmp_path_;
  std::FILE* f_ = nullptr;
  size_t ncols_ = 0;
  bool committed_ = false;
};

/// The trajectory in memory, row-major, full double precision (the CSV
/// prints the same values with %.9g).
class ColumnSink : public RowSink {
 public:
  using RowSink::row;
  void columns(const std::vector<std::string>& names) override;
  void row(const double* values, size_t n) override;
  const std::vector<std::string>& names() const { return names_; }
  const std::vector<double>& data() const { return data_; }

 private:
  std::vector<std::string> names_;
  std::vector<double> data_;
  bool have_header_ = false;
};

/// s as a JSON string literal (quotes included): `"` and `\` escaped, every
/// control character (U+0000..U+001F) as \b \f \n \r \t or \u00XX, and each
/// byte that is not part of valid UTF-8 (a file name's raw bytes) as \ufffd,
/// so any name or path gives valid JSON (RFC 8259).
std::string json_string(const std::string& s);

/// Summary metrics written as a flat JSON object next to the CSV.
class Summary {
 public:
  void set(const std::string& key, double value) { num_[key] = value; }
  void set_text(const std::string& key, const std::string& value) { txt_[key] = value; }
  /// A nested object of numbers, written as "key": {"k": v, ...}.
  void set_object(const std::string& key, const std::map<std::string, double>& v) { obj_[key] = v; }
  std::string to_json() const;
  const std::map<std::string, double>& numbers() const { return num_; }
  const std::map<std::string, std::string>& texts() const { return txt_; }
  const std::map<std::string, std::map<std::string, double>>& objects() const { return obj_; }

 private:
  std::map<std::string, double> num_;
  std::map<std::string, std::string> txt_;
  std::map<std::string, std::map<std::string, double>> obj_;
};

/// Progress bar on a terminal (stderr), silent otherwise.
class Progress {
 public:
  explicit Progress(bool enabled) : enabled_(enabled) {}
  void update(double t_s, double duration_s);
  void done() const;

 private:
  bool enabled_;
  int last_pct_ = -1;
};

struct RunContext {
  /// The run's duration: --duration, else the scenario's default; 0 for the
  /// scenarios for any motor without --duration (they derive their own).
  double duration_s = 0.0;
  const Params& params;
  RowSink& csv;  ///< the trajectory (a CSV file for the CLI)
  Summary& summary;
  Progress& progress;
  /// --motor/--board files (scenarios with motor_params only; else null).
  const MotorFiles* files = nullptr;
  /// --flash FILE: the simulated board's flash (scenarios with takes_flash
  /// only; else null).
  hal_host::FileFlash* flash = nullptr;
  /// The run's output directory (mcsim run --out), where a scenario puts
  /// any file of its own; empty when the rows stay in memory (mdtool.sil).
  std::string out_dir = {};
  /// --pil: the board's whole image on QEMU (app_target.hpp) instead of the
  /// SIL (scenarios with takes_pil only; else null).
  const AppTargetPilOptions* pil = nullptr;
};

/// The run's duration: ctx.duration_s when given (prepare_run checked it),
/// else own_s, the length the scenario derives for itself (from the motor),
/// refused with UsageError above kMaxDurationS. Written to the summary's
/// duration_s.
double run_duration(RunContext& ctx, double own_s);

struct Scenario {
  std::string name;
  std::string description;
  double default_duration_s;
  std::vector<ParamSpec> params;
  std::function<void(RunContext&)> run;
  /// Set for scenarios that run any motor (--motor FILE [--board FILE],
  /// required): their parameters, with ranges and defaults from the files.
  /// Null: the scenario has its own motor and refuses --motor.
  std::function<std::vector<ParamSpec>(const MotorFiles&)> motor_params = {};
  /// The scenario's drive boots from the board's flash (mcsim --flash FILE):
  /// the configuration store of firmware/app/config on hal_host::FileFlash.
  bool takes_flash = false;
  /// With motor_params: --motor is optional; without it the scenario runs
  /// its own motor with `params` (RunContext::files null).
  bool motor_optional = false;
  /// False: the run's length is set by what it does (a commissioning
  /// sequence, a list of speeds, no time at all), and --duration is refused.
  bool takes_duration = true;
  /// The scenario runs the drive application through make_file_target
  /// (app_scenario.hpp) and so also on the PIL target (mcsim run --pil).
  bool takes_pil = false;
  /// With motor_params: the scenario runs a two-phase stepper (a --motor
  /// file with a [stepper] table; csmc-drive); the others take a [motor]
  /// (PMSM) file. The other kind is refused by name (run.cpp).
  bool takes_stepper = false;
};

/// s for the registrations of the scenarios on the drive application
/// (app_scenario.cpp): takes_pil and takes_flash set, and with
/// motor_params the power-up keys (app_params.hpp app_powerup_params)
/// added to its parameters.
Scenario on_app_target(Scenario s);

/// Global registry; scenario files register themselves with a static
/// Registrar at start-up.
std::vector<Scenario>& registry();
struct Registrar {
  explicit Registrar(Scenario s) { registry().push_back(std::move(s)); }
};
const Scenario* find_scenario(const std::string& name);

}  // namespace mcsim
