// What the generic motor scenarios share once they run the drive
// application (issue 29 item 3): the target built from the files (the
// board from the board file, the load a function of time, the parameter
// table of app_params.hpp), the CSV row every one of them writes, and the
// end-of-run check that the application still ran (no fault, not stopped).
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "app_cmd.hpp"
#include "app_params.hpp"
#include "app_target.hpp"
#include "plant_from_files.hpp"
#include "scenario.hpp"

namespace mcsim {

/// The target for the files: the plant from the board and motor files
/// (plant_motor: the motor the plant simulates, e.g. with a flywheel),
/// load_nm(t) opposing positive rotation (kept alive by the caller), the
/// application booted from p: the SIL, or with ctx.pil (mcsim run --pil)
/// the board's whole image on QEMU (the target's name then on stderr: the
/// CSV and summary are the same on both targets, bit for bit). adjust, if
/// set, completes the setup before the target is built (the CAN scenario's
/// telemetry binding, store, commissioning, the plant's sub-steps).
std::unique_ptr<AppTarget> make_file_target(
    const RunContext& ctx, const MotorFiles& plant, const mc_params_t& p,
    const std::function<double(double)>* load_nm,
    const std::function<void(AppSetup&)>& adjust = std::function<void(AppSetup&)>());
/// The same on the SIL (tests that build their own run).
std::unique_ptr<AppTarget> make_file_target(
    const MotorFiles& plant, const mc_params_t& p, const std::function<double(double)>* load_nm,
    const std::function<void(AppSetup&)>& adjust = std::function<void(AppSetup&)>());

/// The scenarios' CSV: t, the true dq currents, the references (the
/// application's probe), the true speed and electrical angle, the observer's
/// angle (sensorless), the applied dq voltage in the true frame, the faults.
struct AppRecorder {
  RunContext& ctx;
  AppRunner& run;
  int pole_pairs = 1;
  bool hat = false;
  long every = 1;
  long k = 0;
  void header();
  void row(double t, double id, double iq, double w);
  double theta_e_true();
};

/// The drive's faults and the application's stop, named; "" while it runs
/// (and before the command handler enabled the drive the first time).
class AppWatch {
 public:
  std::string operator()(const mc_app_probe_t& p);

 private:
  bool was_enabled_ = false;
};

}  // namespace mcsim
