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
#include "motor_file.hpp"

namespace mcsim {
namespace csmc {

struct DriveOptions {
  PlantOptions plant{};    // default: Fig. 3 plant (set in the .cpp)
  double pwm_hz = 10.0e3;  // fast-loop rate (paper's sampled case: 10 kHz)
  double vbus_v = 60.0;
  double current_fs_a = 5.0;  // ADC full scale (12 bits)
  double speed_pll_bw_rad_s = 1000.0;
  double duration_s = 0.4;
  double step_rad = kPaperStepRad;  // phi_d = phi0 + step from t = 0
  double eps_s = 1.0e-3;
  // Boundary layers. The paper's mu = (0.1 A, 50 rad/s^2) give a discrete
  // loop gain (T/L)(M/mu) of 1.7 (d) and 1.1 (q) per period at 10 kHz:
  // stable without computation delay (the paper's sampled case), a limit
  // cycle with the one-period delay of a real drive (needs < ~1). Wider
  // layers (0.5 A, 200 rad/s^2: gains 0.33, 0.27) keep the exact regulation
  // (the conditional integrators work inside any layer).
  double mu1_a = 0.5;
  double mu2_rad_s2 = 200.0;
  // A motor and board from files (stepper_drive_options); the defaults are
  // the paper's plant on the dual H-bridge, as above.
  double dead_time_s = 0.0;  // common_leg: the legs' dead time
  double detent_nm = 0.0;    // plant: detent torque, 4 N_r periods a turn
  double i_max_a = 3.0;      // the drive's current limit and trip
  double i_trip_a = 4.5;
  double v_limit_v = 0.0;         // the law's clamp of each of u_d, u_q; 0: vbus
  double m1_v = 0.0, m2_v = 0.0;  // the law's M_i; 0: the paper's 50 V
  int encoder_cpr = 1 << 18;      // counts per mechanical revolution
  int delay_periods = 1;
  int adc_bits = 12;              // current converter
  bool hgo = false;               // output feedback (else state feedback)
  bool model_law = false;         // law (5) instead of -M sat
  bool common_leg = false;        // the three-leg board (hal_host StepperBoard)
  bool model_from_plant = false;  // the law's model (state feedback's e2'') from plant
};

/// The motor and board of `mcsim run csmc-drive --motor STEPPER --board B`
/// and the CSMC settings derived for them (sim/README.md, csmc-drive):
///   topology: the board's three legs with a common one (winding a between
///     legs 1 and 3, b between 2 and 3): |v_ab| <= vbus / sqrt(2) at every
///     angle, so the law clamps each of u_d, u_q to vbus / 2 and
///     M1 = M2 = vbus / 2 (u = -M sat(s / mu) never asks beyond it);
///   k1, k2, k0: the paper's (the sliding surfaces' dynamics do not depend
///     on the motor);
///   mu_i: the discrete gain per period of the layer, T g_i M_i / mu_i with
///     g_1 = 1 / L (s1' = u1 / L + ...) and g_2 = K_m / (J L) (s2' = e2''' =
///     K_m u2 / (J L) + ...), set to kLayerGain (the paper's plant on its
///     board runs at 0.33 and 0.27; it must stay below about 1 with the
///     one-period delay, csmc_drive.hpp DriveOptions);
///   load: kLoadFrac of the rated torque K_m i_rated (the model knows it, as
///     the paper's knows its 0.2 N m; the detent torque it does not);
///   current: limit 1.5 i_rated, trip 2 i_rated;
///   the step: the paper's phi_d step (one full step of a 1.8 deg motor).
/// Refused (UsageError naming the reason): the paper's step asks
/// J k1 step + load + detent beyond the rated torque; the topology's M
/// below 2 R i_rated (no margin over the rated current's drop); one count of
/// the current converter coarser than kMaxCountRatio of the step's e2''
/// (current resolution); the trip beyond the board's current range; no
/// encoder. At run time (the scenario's detent parameter) a detent torque
/// the state feedback cannot hold within the settling band.
constexpr double kLayerGain = 0.3;
constexpr double kLoadFrac = 0.25;
// The current converter's count against the step: (K_m / J) i_count at
// most this fraction of k1 step (csmc_drive.cpp; measured: 0.19 to 0.53 on
// the library's NEMA files on odrive36 and vesc6 settle, 0.75 to 1.05 in
// the cases tried limit-cycle or rest off the target).
constexpr double kMaxCountRatio = 0.6;
DriveOptions stepper_drive_options(const MotorFiles& f);

struct DriveSample {
  double t, phi_d, phi, e2, i_d, i_q, w, v_d, v_q, duty_a, duty_b, fault;
  double e2_meas, de2_meas, dde2_meas, s1, s2;  // what the plug-in used
};

struct DriveResult {
  std::vector<DriveSample> trace;  ///< run_drive(o) only
  unsigned faults = 0;
  long samples = 0;            ///< one per PWM period
  long clipped_periods = 0;    ///< common_leg: requests outside the hexagon
  double max_request_v = 0.0;  ///< common_leg: largest |(v_a, v_b)| asked
};

/// The loop for duration_s: the first form keeps every period's sample in
/// trace; the second hands each to on_sample and keeps none.
DriveResult run_drive(const DriveOptions& o);
DriveResult run_drive(const DriveOptions& o,
                      const std::function<void(const DriveSample&)>& on_sample);

}  // namespace csmc
}  // namespace mcsim
