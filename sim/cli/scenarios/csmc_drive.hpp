// The CSMC stepper position loop through the firmware path: the drive
// application (firmware/app/mc_drive) in CTRL mode with the CSMC plug-in
// (firmware/app/mc_ctrl_csmc) on the simulated dual-H-bridge board
// (hal/host StepperBoard), as the MCU would run it: sampled currents
// (12-bit ADC), encoder counts, the drive's speed tracking loop, one-period
// computation delay, duties on the HAL's pwm2.
#pragma once

#include <functional>
#include <vector>

#include "csmc_loop.hpp"

namespace mcsim {
namespace csmc {

struct DriveOptions {
  PlantOptions plant{};    // default: Fig. 3 plant (set in the .cpp)
  double pwm_hz = 10.0e3;  // fast-loop rate (paper's sampled case: 10 kHz)
  double vbus_v = 60.0;
  int encoder_cpr = 1 << 18;  // counts per mechanical revolution
  double current_fs_a = 5.0;  // ADC full scale (12 bits)
  int delay_periods = 1;
  double speed_pll_bw_rad_s = 1000.0;
  double duration_s = 0.4;
  double step_rad = kPaperStepRad;  // phi_d = phi0 + step from t = 0
  bool hgo = false;                 // output feedback (else state feedback)
  double eps_s = 1.0e-3;
  bool model_law = false;  // law (5) instead of -M sat
  // Boundary layers. The paper's mu = (0.1 A, 50 rad/s^2) give a discrete
  // loop gain (T/L)(M/mu) of 1.7 (d) and 1.1 (q) per period at 10 kHz:
  // stable without computation delay (the paper's sampled case), a limit
  // cycle with the one-period delay of a real drive (needs < ~1). Wider
  // layers (0.5 A, 200 rad/s^2: gains 0.33, 0.27) keep the exact regulation
  // (the conditional integrators work inside any layer).
  double mu1_a = 0.5;
  double mu2_rad_s2 = 200.0;
};

struct DriveSample {
  double t, phi_d, phi, e2, i_d, i_q, w, v_d, v_q, duty_a, duty_b, fault;
  double e2_meas, de2_meas, dde2_meas, s1, s2;  // what the plug-in used
};

struct DriveResult {
  std::vector<DriveSample> trace;  ///< run_drive(o) only
  unsigned faults = 0;
  long samples = 0;  ///< one per PWM period
};

/// The loop for duration_s: the first form keeps every period's sample in
/// trace; the second hands each to on_sample and keeps none.
DriveResult run_drive(const DriveOptions& o);
DriveResult run_drive(const DriveOptions& o,
                      const std::function<void(const DriveSample&)>& on_sample);

}  // namespace csmc
}  // namespace mcsim
