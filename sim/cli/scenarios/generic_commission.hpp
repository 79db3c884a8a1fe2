// Commissioning in the loop: the drive, knowing only the board, measures a
// motor from a file (firmware/app/commission). run_commission and
// verify_speed_step are the kernel-level rig of the tests
// (tests/sil/commission: the drive alone with the commissioning plug-in, a
// C++ rig for the runs on the identified values); the `commission`
// scenario (commission.cpp) runs the drive application's commissioning
// over CAN instead and shares only the plant's side (the helpers below).
#pragma once

#include <cstdint>
#include <functional>
#include <string>

#include "drive_setup.hpp"
#include "hal_host/pmsm_board.hpp"
#include "motor_file.hpp"
extern "C" {
#include "commission/mc_commission.h"
}

namespace mcsim {

struct CommissionSetup {
  double encoder_offset_rad = 1.0;  // plant: electrical angle of the d axis at count 0
  int encoder_direction = 1;        // plant: +1 counts up with positive rotation
  double adc_offset_a = 0.0;        // plant: offsets (x, -0.7 x, 0.4 x) on a, b, c [A]
  double noise_rms_a = 0.0;         // plant: current noise per channel [A]
  double i_test_a = 0.0;            // 0: 0.25 i_sense_max_a (the board's range)
  double t_max_s = 12.0;            // give up after this much simulated time
  std::uint64_t seed = 1;           // plant: current-noise generator
  // verify_speed_step, sensorless: the rotor's electrical angle at the
  // start (the I-f start resets its observer at angle 0; see the .cpp).
  double sensorless_start_theta_e_rad = 0.0;
  // Test hooks: injections once the board is built, and a call every period
  // (e.g. a load that appears in the flux step).
  std::function<void(hal_host::PmsmBoard&)> inject;
  std::function<void(hal_host::PmsmBoard&, const mc_comm_t&)> each_period;
};

struct CommissionRun {
  mc_comm_result_t res{};
  uint32_t err = 0;           // MC_COMM_ERR_* (0: done)
  uint32_t drive_faults = 0;  // the drive's fault bits at the end
  bool done = false;
  bool bridge_off = false;  // PWM disabled at the end (after a failure)
  double duration_s = 0;
  // the plant's true values in the result's terms
  double true_encoder_offset_rad = 0;
  int true_encoder_direction = 1;
  double true_adc_offset_a[3] = {0, 0, 0};
};

/// Default plant imperfections for the board: offset 1 % and noise 0.1 %
/// of the sensor range (about 20 and 2 LSB at 12 bits).
CommissionSetup default_commission_setup(const MotorFiles& f);

/// Run the sequence; throws UsageError for files the rig refuses.
CommissionRun run_commission(const MotorFiles& f, const CommissionSetup& s);

/// The plant's imperfections of s: current noise and its seed, the
/// encoder's direction, the shaft angle at power-up (encoder_offset_rad).
void configure_plant(const MotorFiles& f, const CommissionSetup& s, hal_host::PmsmBoardConfig& bc);
/// The current-sensor offsets of s on phases a, b, c (x, -0.7 x, 0.4 x).
void set_adc_offsets(const CommissionSetup& s, double out[3]);
/// The electrical encoder offset the firmware's formula should find on
/// the plant bc (the count's quantisation included).
double true_offset(const MotorFiles& f, const CommissionSetup& s,
                   const hal_host::PmsmBoardConfig& bc);

/// Names of MC_COMM_ERR_* bits, "|"-separated.
std::string commission_error_names(uint32_t err);

/// The motor as commissioning identified it (the file's other values kept:
/// limits, ratings; J and B replaced when identified).
MotorSpec identified_motor(const MotorSpec& truth, const mc_comm_result_t& r);

/// Speed step on the identified values: law kSpeedPi or kSensorless; the
/// plant as in s. Returns the final speed error as a fraction of the target
/// (NaN if the drive faulted).
double verify_speed_step(const MotorFiles& f, const CommissionSetup& s, const CommissionRun& run,
                         Law law, double* p_target_rad_s);

}  // namespace mcsim
