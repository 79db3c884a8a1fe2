// Commissioning in the loop: the drive application's commissioning
// (firmware/app/commission: mc_comm_can, bound as the images bind it, its
// configuration from mc_comm_can_cfg_for_board) run over CAN on a target
// built from the motor and board files, as a user's tool runs it: START,
// the keep-alive, COMMISSION_STATUS followed, every COMMISSION_RESULT read.
// The application boots the files' parameter table (app_params.hpp:
// params_from_files -> mc_params_to_drive_cfg, the image's path); the
// sequence reads none of its motor values, only the drive's limits.
//
// One implementation for the `commission` scenario (commission.cpp: its
// CSV rows, --pil) and the SIL tests (tests/sil/commission: the same run on
// the SIL, the plant's fault injections through the hooks below).
// verify_speed_step reboots the application on the table commissioning
// staged (staged_params: the image's staging, mc_comm_can.c stage()) and
// runs a speed step on the application's speed law; the plant keeps the
// files' true motor.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "app_cmd.hpp"
#include "app_target.hpp"
#include "hal_host/pmsm_board.hpp"
#include "motor_file.hpp"
extern "C" {
#include "commission/mc_commission.h"
#include "mc_params.h"
}

namespace mcsim {

struct CommissionSetup {
  double encoder_offset_rad = 1.0;  // plant: electrical angle of the d axis at count 0
  int encoder_direction = 1;        // plant: +1 counts up with positive rotation
  double adc_offset_a = 0.0;        // plant: offsets (x, -0.7 x, 0.4 x) on a, b, c [A]
  double noise_rms_a = 0.0;         // plant: current noise per channel [A]
  double i_test_a = 0.0;            // COMMISSION_CMD i_test_a; 0: the drive's default
                                    // (a quarter of the sense range within i_max_a)
  double t_max_s = 12.0;            // give up after this much simulated time
  std::uint64_t seed = 1;           // plant: current-noise generator
  // verify_speed_step, sensorless: the rotor's electrical angle at the
  // start (the I-f start resets its observer at angle 0; see the .cpp).
  double sensorless_start_theta_e_rad = 0.0;
  // Test hooks: the plant's configuration before it is built (a plant the
  // drive's table cannot describe, e.g. a locked rotor), injections once the
  // board is built (before START), and a call after every period with the
  // step COMMISSION_STATUS last reported (mc_comm_step_t; e.g. a load that
  // appears in the flux step).
  std::function<void(hal_host::PmsmBoardConfig&)> plant;
  std::function<void(hal_host::PmsmBoard&)> inject;
  // the application's setup before it is built (the Hall inputs' faults)
  std::function<void(AppSetup&)> setup;
  std::function<void(hal_host::PmsmBoard&, uint32_t step)> each_period;
};

struct CommissionRun {
  // What COMMISSION_RESULT reported (the sensor offsets: the ones in use
  // plus the measured, as staged; valid from COMMISSION_STATUS): all zero
  // unless done.
  mc_comm_result_t res{};
  mc_params_t staged{};  // the booted table with the results staged (done)
  uint32_t err = 0;      // MC_COMM_ERR_* of the status frame (0: done)
  uint32_t detail = 0;   // COMMISSION_STATUS.detail (MC_COMM_DETAIL_*)
  // The flux step's checks (mc_comm_check.h) as the sequence left them
  // (have_checks: the target shows them, the SIL; all zero before the coast)
  bool have_checks = false;
  mc_comm_flux_chk_t flux_chk{};
  mc_comm_mech_chk_t mech_chk{};
  uint32_t drive_faults = 0;  // the drive's fault bits at the end
  bool done = false;
  bool bridge_off = false;    // PWM disabled at the end (after a failure)
  double duration_s = 0;      // when the last result (or FAILED) arrived, from START
  double index_search_s = 0;  // angle_ref index: the search before START (0: none)
  uint64_t tx_frames = 0;     // frames the application sent
  // the plant's true values in the result's terms
  double true_encoder_offset_rad = 0;
  int true_encoder_direction = 1;
  double true_adc_offset_a[3] = {0, 0, 0};
};

/// The target a run is made on: the files' target (make_file_target)
/// booted from p, `adjust` completing the setup (the plant's imperfections).
using CommissionTargetFactory = std::function<std::unique_ptr<AppTarget>(
    const mc_params_t& p, const std::function<void(AppSetup&)>& adjust)>;
/// Called before each period of the run (k = 0 .. the last; the CSV rows).
using CommissionObserver = std::function<void(AppRunner& run, long k)>;

/// Default plant imperfections for the board: offset 1 % and noise 0.1 %
/// of the sensor range (about 20 and 2 LSB at 12 bits).
CommissionSetup default_commission_setup(const MotorFiles& f);

/// The table the application boots before commissioning: the files' table
/// (params_from_files, the sensored speed law). Throws UsageError when the
/// table is refused.
mc_params_t commission_booted_params(const MotorFiles& f);

/// The sequence over CAN on make's target booted from p (see the file
/// comment); with p.angle_ref index the drive's index search first (an
/// enable at 0 A, the image's mc_ctrl_idx), so the offset is relative to
/// the index. Throws UsageError for files the run refuses (no encoder;
/// angle_ref index without angle_find_at_enable), runtime_error naming the
/// reason when the index search fails.
CommissionRun run_commission(const MotorFiles& f, const CommissionSetup& s, const mc_params_t& p,
                             const CommissionTargetFactory& make,
                             const CommissionObserver& observe = CommissionObserver());
/// The same on the SIL, booted from commission_booted_params(f).
CommissionRun run_commission(const MotorFiles& f, const CommissionSetup& s);

/// The plant's imperfections of s: current noise and its seed, the
/// encoder's direction, the shaft angle at power-up (encoder_offset_rad).
void configure_plant(const MotorFiles& f, const CommissionSetup& s, hal_host::PmsmBoardConfig& bc);
/// The current-sensor offsets of s on phases a, b, c (x, -0.7 x, 0.4 x).
void set_adc_offsets(const CommissionSetup& s, double out[3]);
/// The electrical encoder offset the firmware's formula should find on
/// the plant bc (the count's quantisation included), relative to the
/// power-up count.
double true_offset(const MotorFiles& f, const CommissionSetup& s,
                   const hal_host::PmsmBoardConfig& bc);
/// The same relative to the index (angle_ref index: the count from the
/// mark on).
double true_index_offset(const MotorFiles& f, const CommissionSetup& s,
                         const hal_host::PmsmBoardConfig& bc);

/// Names of MC_COMM_ERR_* bits, "|"-separated.
std::string commission_error_names(uint32_t err);
/// COMMISSION_STATUS.detail by name (MC_COMM_DETAIL_*).
std::string commission_detail_name(uint32_t detail);

/// The booted table with what commissioning stages (mc_comm_can.c,
/// stage(): r, ld, lq, flux, pole pairs, encoder offset and direction, the
/// sensor offsets as r reports them; J and B with the speed PI gains reset
/// to 0, derived from them, when the mechanics were measured), as the host
/// APPLYs and SAVEs it.
mc_params_t staged_params(mc_params_t booted, const mc_comm_result_t& r);
/// The Hall table held in the parameters 166-173 of p.
mc_comm_hall_table_t hall_table_of(const mc_params_t& p);

/// A speed step to half the rated speed on make's target rebooted on the
/// staged table with speed_law law (MC_LAW_SPEED_PI or _SENSORLESS), the
/// plant as in s (the files' true motor). Returns the final speed error as
/// a fraction of the target, NaN if the drive faulted or stopped. Throws
/// UsageError when the table refuses the law for this motor.
double verify_speed_step(const MotorFiles& f, const CommissionSetup& s, mc_params_t staged,
                         uint32_t law, double* p_target_rad_s, const CommissionTargetFactory& make);
/// The same on the SIL.
double verify_speed_step(const MotorFiles& f, const CommissionSetup& s, const mc_params_t& staged,
                         uint32_t law, double* p_target_rad_s);

}  // namespace mcsim
