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
/// With ctx.flash (mcsim --flash FILE, the SIL): the application boots
/// from the file's configuration store (mc_app_boot, as main.c): an absent
/// or erased file boots p; a stored record replaces p, except for what the
/// scenario or the user chose over the files' plain table (its speed law,
/// fw_enable, a --set gain: written over the stored set, as a host's
/// PARAM_REQ WRITE and APPLY before the enable). A file the drive cannot
/// boot (CORRUPT, LAYOUT, INVALID, FLASH) or a stored set of another board
/// (pwm_hz, dead_time_s, vbus_v, current_sensors, i_sense_max_a,
/// adc_bits, encoder_cpr differ from p's) is refused (UsageError naming it; nothing has been written).
/// theta_m0_rad (the run's key, when it has one): the plant's rotor angle
/// at power-up. The board's encoder type (set_board_sensor) on the plant.
///
/// The same on the SIL (tests that build their own run).
std::unique_ptr<AppTarget> make_file_target(
    const MotorFiles& plant, const mc_params_t& p, const std::function<double(double)>* load_nm,
    const std::function<void(AppSetup&)>& adjust = std::function<void(AppSetup&)>());

/// The board's position sensor on the plant: "abi_index" an index mark at
/// encoder_index_rad (BoardSpec::encoder); "as5047p", "ma732" the image's
/// driver on the chip model (set_board_spi_encoder, app_spi_encoder.cpp).
void set_board_sensor(const MotorFiles& f, hal_host::PmsmBoardConfig& bc);
void set_board_spi_encoder(const MotorFiles& f, hal_host::PmsmBoardConfig& bc);
/// The absolute encoder's reads into the summary: encoder_reads,
/// encoder_bad_reads, encoder_line_flips, encoder_errors_seen (nothing
/// with the A/B encoder).
void record_spi_encoder(hal_host::PmsmBoard& board, Summary& s);

/// The refusals of a --flash boot (make_file_target): throws UsageError.
void check_flash_boot(const AppTarget& t, const std::string& file, const mc_params_t& board);
/// MC_CTRL_ALIGN_ERR_* bits by name ("LOAD|SLIP"; "none").
std::string align_err_names(uint32_t bits);
/// "STORED", "EMPTY", ... (mc_cfg_boot_t).
std::string flash_boot_name(uint32_t boot_status);

/// The scenarios' CSV: t, the true dq currents, the references (the
/// application's probe), the true speed and electrical angle, the observer's
/// angle and the I-f frame's mechanical speed omega_if_rad_s (sensorless: 0
/// in ALIGN, the I-f ramp in IF, NaN once CLOSED; omega_ref_rad_s is the
/// speed command's ramp, which the I-f frame follows only up to the
/// hand-over speed), the applied dq voltage in the true frame, the faults.
struct AppRecorder {
  RunContext& ctx;
  AppRunner& run;
  int pole_pairs = 1;
  bool hat = false;
  long every = 1;
  long k = 0;
  /// a column theta_e_used_rad: the angle the drive's current loop used
  /// (the Hall + observer hand-over's blend, or the encoder's)
  bool used = false;
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
