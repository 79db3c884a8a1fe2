// mcsim: run named simulation scenarios (plants alone, or the firmware in
// closed loop through the host HAL) and write CSV + JSON summaries.
//
//   mcsim list
//   mcsim describe <scenario>
//   mcsim run <scenario> --out DIR [--duration S] [--set key=value ...]
//             [--motor FILE [--board FILE]]   (scenarios for any motor)
//             [--flash FILE]   (the scenarios on the drive application, the
//                              SIL: the board's flash; the drive boots from
//                              the configuration stored there, commission and
//                              can-telemetry save to it; sim/README.md,
//                              "Power-up")
//             [--pil]   (the scenarios on the drive application: the board's
//                       whole image on QEMU's emulated Cortex-M4F instead of
//                       the SIL; pil_options below)
//   mcsim bench [--duration S]
//
// Exit codes (sim/README.md, "Verdicts"):
//   0  the run passed its verdict (or has no claim to check): DIR/<scenario>.csv
//      and DIR/<scenario>.json;
//   1  the run failed: its verdict is not a pass (not settled, faulted: ...),
//      or it stopped on its way; DIR/<scenario>.partial.csv (the rows it
//      wrote) and DIR/<scenario>.json (with the verdict);
//   2  a usage error or a setting the scenario refused, before or during
//      the run: nothing written (a directory --out created is removed).
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <memory>
#include <string>
#include <unistd.h>
#include <vector>

#include "app_params.hpp"
#include "app_target.hpp"
#include "bench.hpp"
#include "motor_file.hpp"
#include "run.hpp"
#include "scenario.hpp"

namespace {

void usage(std::FILE* f) {
  std::fprintf(
      f,
      "usage: mcsim list\n"
      "       mcsim describe <scenario> [--motor FILE [--board FILE]]\n"
      "       mcsim run <scenario> --out DIR [--duration S] [--set key=value ...]\n"
      "                 [--motor FILE [--board FILE]] [--flash FILE] [--pil]\n"
      "       mcsim bench [--duration S]\n"
      "\n"
      "--pil (the scenarios `describe` marks \"--pil: yes\"): the drive application runs\n"
      "as the board's whole image (mc_stm32f405_pil: the image's main, both interrupts,\n"
      "the application, CAN, parameter service) on QEMU's emulated Cortex-M4F, the\n"
      "plant on the host, one PWM period at a time; the CSV and summary are the same as\n"
      "without --pil, bit for bit. What differs from the flashed image is the HAL only\n"
      "(hal/pil: ADC, encoder, faults and CAN over the link, the configuration store in\n"
      "RAM, no watchdog). Slow: hundreds of wall seconds per simulated second.\n"
      "--flash FILE (the same scenarios): the board's flash; the drive boots from its\n"
      "stored configuration (absent: erased), commission saves what it identified,\n"
      "cogging --set anticogging=1 saves its calibrated map (--set cog_cal=0 boots\n"
      "it); a file it cannot boot or another board's is refused. With --pil the\n"
      "image's RAM store gets the file's bytes before it boots (the file is not\n"
      "written). A power-up elsewhere: --set theta_m0_rad=X; the encoder: --set\n"
      "board.encoder=TYPE (abi, abi_index, hall).\n"
      "Files:\n"
      "  MCSIM_QEMU          qemu-system-arm         (default: the one the build found)\n"
      "  MCSIM_PIL_ELF       the PIL image            (default: the build's, target mc_pil_m4f)\n"
      "  MCSIM_PIL_BOOT_ELF  its emulated bootloader  (default: the build's, mc_boot_pil_m4f)\n"
      "  MCSIM_PIL_LOG       the image's semihosting text (default: none)\n");
}

#ifndef MCSIM_QEMU_ARM
#define MCSIM_QEMU_ARM ""
#endif
#ifndef MCSIM_PIL_ELF
#define MCSIM_PIL_ELF ""
#endif
#ifndef MCSIM_BOOT_PIL_ELF
#define MCSIM_BOOT_PIL_ELF ""
#endif

// --pil: QEMU, the image and its bootloader from the environment, else the
// build's (tests/target/CMakeLists.txt defines them where the ARM toolchain
// and QEMU were found); UsageError naming what is missing.
std::shared_ptr<const mcsim::AppTargetPilOptions> pil_options(const mcsim::Scenario& scen,
                                                              const std::string& board) {
  if (!scen.takes_pil) {
    std::string on;
    for (const auto& s : mcsim::registry()) {
      if (s.takes_pil) on += (on.empty() ? "" : ", ") + s.name;
    }
    throw mcsim::UsageError("--pil: " + scen.name +
                            " does not run the drive application (--pil runs " + on + ")");
  }
  auto o = std::make_shared<mcsim::AppTargetPilOptions>();
  struct File {
    const char* env;
    const char* built;
    const char* what;
    std::string* to;
  };
  const File files[] = {
      {"MCSIM_QEMU", MCSIM_QEMU_ARM, "QEMU (qemu-system-arm)", &o->link.qemu},
      {"MCSIM_PIL_ELF", MCSIM_PIL_ELF, "the PIL image (build target mc_pil_m4f)", &o->link.elf},
      {"MCSIM_PIL_BOOT_ELF", MCSIM_BOOT_PIL_ELF,
       "the PIL bootloader (build target mc_boot_pil_m4f)", &o->link.boot_elf}};
  for (const File& f : files) {
    const char* env = std::getenv(f.env);
    *f.to = env != nullptr && *env != '\0' ? env : f.built;
    if (f.to->empty()) {
      throw mcsim::UsageError(std::string("--pil: no ") + f.what + ": this build found none " +
                              "(no ARM toolchain or QEMU at configure time); set " + f.env);
    }
    if (access(f.to->c_str(), R_OK) != 0) {
      throw mcsim::UsageError(std::string("--pil: ") + f.what + " '" + *f.to +
                              "' cannot be read (" + std::strerror(errno) + "; set " + f.env +
                              " or build it)");
    }
  }
  if (const char* log = std::getenv("MCSIM_PIL_LOG"); log != nullptr) o->link.semihost_log = log;
  o->board = board;
  return o;
}

double parse_positive(const std::string& what, const std::string& s) {
  char* end = nullptr;
  errno = 0;
  double v = std::strtod(s.c_str(), &end);
  if (s.empty() || *end != '\0' || errno == ERANGE || !std::isfinite(v) || v <= 0.0) {
    throw mcsim::UsageError("malformed " + what + " '" + s + "' (a positive number is expected)");
  }
  return v;
}

int cmd_list() {
  for (const auto& s : mcsim::registry()) {
    if (s.takes_duration) {
      std::printf("%-28s %s (default %.3g s)\n", s.name.c_str(), s.description.c_str(),
                  s.default_duration_s);
    } else {
      std::printf("%-28s %s (no --duration)\n", s.name.c_str(), s.description.c_str());
    }
  }
  return 0;
}

// The drive's derived speed limit and what sets it (mc_gains.h,
// speed_limit_rad_s): the motor's own maximum, the bus voltage, or the
// current loop's electrical angle per period.
void print_speed_limit(const mcsim::MotorFiles& f) {
  const mc_gains_t& g = mcsim::files_params_eff(f).g;
  const double w = g.speed_limit_rad_s, w_v = 0.9 * g.speed_voltage_rad_s,
               w_d = 0.9 * g.speed_delay_rad_s;
  char why[200];
  if (w == w_d && w_d <= w_v) {
    std::snprintf(why, sizeof why,
                  "the current loop: 0.9 x %g rad of electrical angle per PWM period (p = %d, "
                  "%g Hz; a faster PWM raises it)",
                  MC_GAINS_WE_T_MAX, f.motor.pole_pairs, f.board.pwm_hz);
  } else if (w == w_v) {
    std::snprintf(why, sizeof why,
                  "the bus voltage: 0.9 x the speed at which rated current needs "
                  "0.95 vbus / sqrt 3 (vbus %g V)",
                  f.board.vbus_v);
  } else {
    std::snprintf(why, sizeof why, "the motor's speed_max_rad_s");
  }
  std::printf("speed limit: %g rad/s (mechanical), set by %s\n", w, why);
  std::printf("  its bounds: motor %g, bus voltage %g, current loop %g rad/s\n",
              f.motor.speed_max_rad_s, w_v, w_d);
}

int cmd_describe(const std::vector<std::string>& args) {
  if (args.empty()) throw mcsim::UsageError("describe takes one scenario name");
  const auto& s = mcsim::need_scenario(args[0]);
  std::string motor, board;
  for (size_t i = 1; i < args.size(); ++i) {
    if ((args[i] == "--motor" || args[i] == "--board") && i + 1 < args.size()) {
      (args[i] == "--motor" ? motor : board) = args[i + 1];
      ++i;
    } else {
      throw mcsim::UsageError("describe: unexpected '" + args[i] + "'");
    }
  }
  std::printf("%s: %s\n", s.name.c_str(), s.description.c_str());
  if (!s.takes_duration) {
    std::printf("duration: set by what the scenario does (no --duration)\n");
  } else if (s.default_duration_s > 0.0) {
    std::printf("default duration: %g s (at most %g s)\n", s.default_duration_s,
                mcsim::kMaxDurationS);
  } else {
    std::printf("default duration: derived from the motor (at most %g s)\n", mcsim::kMaxDurationS);
  }
  std::printf("--pil: %s\n", s.takes_pil ? "yes (the board's whole image on QEMU: mcsim --help)"
                                         : "no (the scenario does not run the drive application)");
  if (s.motor_params && motor.empty() && !s.motor_optional) {
    std::printf("parameters (--set key=value):\n");
    std::printf(
        "  (ranges and defaults depend on the motor: describe %s --motor FILE "
        "[--board FILE])\n",
        s.name.c_str());
    return 0;
  }
  const auto files = mcsim::motor_files(s, motor, board);
  if (files && !files->is_stepper) print_speed_limit(*files);  // a PMSM's
  std::printf("parameters (--set key=value):\n");
  const std::vector<mcsim::ParamSpec> specs = files ? s.motor_params(*files) : s.params;
  for (const auto& p : specs) {
    std::printf("  %-22s default %-10g [%g, %g] %-8s %s", p.key.c_str(), p.default_value,
                p.min_value, p.max_value, p.unit.c_str(), p.help.c_str());
    for (size_t i = 0; i < p.choices.size(); ++i) {
      std::printf("%s%s = %g", i ? ", " : " (", p.choices[i].first.c_str(), p.choices[i].second);
    }
    std::printf("%s\n", p.choices.empty() ? "" : ")");
  }
  return 0;
}

// The directories of path that do not exist yet, outermost first.
std::vector<std::filesystem::path> missing_dirs(const std::string& path) {
  std::vector<std::filesystem::path> v;
  std::error_code ec;
  for (std::filesystem::path p = std::filesystem::absolute(path, ec).lexically_normal();
       !p.empty() && !std::filesystem::exists(p, ec); p = p.parent_path()) {
    v.insert(v.begin(), p);
    if (p == p.parent_path()) break;
  }
  return v;
}

// The entries of dir whose names start with prefix.
std::vector<std::string> entries(const std::string& dir, const std::string& prefix) {
  std::vector<std::string> v;
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(dir, ec)) {
    const std::string n = e.path().filename().string();
    if (n.rfind(prefix, 0) == 0) v.push_back(n);
  }
  return v;
}

// A refused run leaves nothing: the files it created in out_dir (named
// after the scenario: its CSV and JSON parts, a scenario's own files such as
// can-telemetry's default CAN log), then the directories mcsim created.
void remove_traces(const std::string& out_dir, const std::string& prefix,
                   const std::vector<std::string>& before,
                   const std::vector<std::filesystem::path>& created) {
  std::error_code ec;
  for (const auto& n : entries(out_dir, prefix)) {
    if (std::find(before.begin(), before.end(), n) == before.end()) {
      std::filesystem::remove(std::filesystem::path(out_dir) / n, ec);
    }
  }
  for (auto it = created.rbegin(); it != created.rend(); ++it) {
    std::filesystem::remove(*it, ec);  // only if empty
  }
}

void write_json(const std::string& path, const mcsim::Summary& summary) {
  const std::string tmp = path + ".part";
  std::FILE* jf = std::fopen(tmp.c_str(), "w");
  if (jf == nullptr) throw mcsim::UsageError("cannot write '" + tmp + "'");
  const std::string js = summary.to_json();
  const bool ok = std::fputs(js.c_str(), jf) >= 0;
  if (std::fclose(jf) != 0 || !ok) {
    std::remove(tmp.c_str());
    throw mcsim::UsageError("write error on '" + tmp + "'");
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    std::remove(tmp.c_str());
    throw mcsim::UsageError("cannot write '" + path + "'");
  }
}

int cmd_run(const std::vector<std::string>& args) {
  if (args.empty()) throw mcsim::UsageError("run: missing scenario name");
  if (args[0] == "-h" || args[0] == "--help") {
    usage(stdout);
    return 0;
  }
  const auto& scen = mcsim::need_scenario(args[0]);
  std::string out_dir;
  double duration = 0.0;  // the scenario's own
  std::vector<std::pair<std::string, std::string>> sets;
  std::string motor_path, board_path, flash_path;
  bool pil = false;
  for (size_t i = 1; i < args.size(); ++i) {
    const std::string& a = args[i];
    auto value = [&](const char* opt) -> const std::string& {
      if (i + 1 >= args.size()) throw mcsim::UsageError(std::string(opt) + " needs a value");
      return args[++i];
    };
    if (a == "--out") {
      out_dir = value("--out");
    } else if (a == "--duration") {
      duration = parse_positive("duration", value("--duration"));
    } else if (a == "--motor") {
      motor_path = value("--motor");
    } else if (a == "--board") {
      board_path = value("--board");
    } else if (a == "--flash") {
      flash_path = value("--flash");
      if (flash_path.empty()) throw mcsim::UsageError("--flash needs a file name");
    } else if (a == "--pil") {
      pil = true;
    } else if (a == "--set") {
      const std::string& kv = value("--set");
      auto eq = kv.find('=');
      if (eq == std::string::npos || eq == 0) {
        throw mcsim::UsageError("--set expects key=value, got '" + kv + "'");
      }
      sets.emplace_back(kv.substr(0, eq), kv.substr(eq + 1));
    } else {
      throw mcsim::UsageError("unknown option '" + a + "'");
    }
  }
  if (out_dir.empty()) throw mcsim::UsageError("run: --out DIR is required");
  // Scenario, motor and board files, the duration and every --set before
  // anything is written: a bad input changes nothing.
  mcsim::PreparedRun run =
      mcsim::prepare_run(scen.name, motor_path, board_path, sets, flash_path, duration);
  if (pil) run.pil = pil_options(scen, board_path);

  const std::vector<std::filesystem::path> created = missing_dirs(out_dir);
  std::error_code ec;
  std::filesystem::create_directories(out_dir, ec);
  if (ec || !std::filesystem::is_directory(out_dir) || access(out_dir.c_str(), W_OK) != 0) {
    throw mcsim::UsageError("output directory '" + out_dir + "' cannot be created or written");
  }
  const std::string prefix = scen.name + ".";
  const std::vector<std::string> before = entries(out_dir, prefix);
  const std::string base = out_dir + "/" + scen.name;
  mcsim::RunOutcome outcome;
  mcsim::Summary summary;
  {
    mcsim::CsvWriter csv(base + ".csv");
    mcsim::Progress progress(isatty(STDERR_FILENO) != 0);
    outcome = mcsim::execute_run(run, csv, summary, progress, out_dir);
    if (outcome.kind != mcsim::RunOutcome::Kind::kRefused) {
      const bool pass = outcome.kind == mcsim::RunOutcome::Kind::kPass;
      const std::string csv_path = base + (pass ? ".csv" : ".partial.csv");
      write_json(base + ".json", summary);
      csv.commit_as(csv_path);
      // no stale trajectory of an earlier run beside this run's summary
      std::remove((base + (pass ? ".partial.csv" : ".csv")).c_str());
      std::printf("%s (%zu rows)\n%s.json\n", csv_path.c_str(), csv.rows(), base.c_str());
    }
  }
  switch (outcome.kind) {
    case mcsim::RunOutcome::Kind::kPass:
      return 0;
    case mcsim::RunOutcome::Kind::kFailed:
      std::fprintf(stderr, "mcsim: %s\n", outcome.message.c_str());
      return 1;
    case mcsim::RunOutcome::Kind::kRefused:
      break;
  }
  remove_traces(out_dir, prefix, before, created);
  std::fprintf(stderr, "mcsim: %s\n", outcome.message.c_str());
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  try {
    if (args.empty() || args[0] == "-h" || args[0] == "--help" || args[0] == "help") {
      usage(args.empty() ? stderr : stdout);
      return args.empty() ? 2 : 0;
    }
    const std::string cmd = args[0];
    args.erase(args.begin());
    if (cmd == "list") return cmd_list();
    if (cmd == "describe") return cmd_describe(args);
    if (cmd == "run") return cmd_run(args);
    if (cmd == "bench") return mcsim::cmd_bench(args);
    throw mcsim::UsageError("unknown command '" + cmd + "'");
  } catch (const mcsim::UsageError& e) {
    std::fprintf(stderr, "mcsim: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mcsim: run failed: %s\n", e.what());
    return 1;
  }
}
