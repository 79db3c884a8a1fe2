// PI^2D (paper 000) scenarios shared by mcsim and the SIL tests:
// - the paper's Section V on its normalised PMSM (mcsim::PmsmNormalised),
//   the firmware kernel sampled at 10 kHz with zero-order hold;
// - the paper-002 0.3 kW test motor on the simulated board (hal/host) with
//   the unmodified drive and the PI^2D plug-in (firmware/app/mc_ctrl_pi2d),
//   against a conventional cascade (speed PI on the encoder's differentiated
//   position, the drive's FOC current loops) in the same scenario.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "hal_host/pmsm_board.hpp"
#include "verdict.hpp"

extern "C" {
#include "mc_drive.h"
#include "pi2d/mc_pi2d.h"
}

namespace mcsim {
namespace pi2d {

// Reference speed and its derivatives; th is its integral (from 0 at t = 0).
struct SpeedRef {
  double w = 0, a = 0, j = 0, th = 0;
};

// Section V profile: 5.25 rad/s^2 to 5.25 rad/s at t = 1 s, hold to 3 s,
// 3.675 rad/s^2 to 12.6 rad/s (t = 5 s), hold 2 s, -6.3 rad/s^2 to 0
// (t = 9 s), hold. The jerk is zero between the corners (the impulses at
// the corners are not applied: a sampled law cannot apply them).
SpeedRef paper_profile(double t_s);

// The paper's gains (closed-loop k1 = 4, k2 = 75) on the normalised model
// (R = L = p = J = 1, ke = gamma = 0.17, kt = sigma = 0.51), limits that
// never act, sample period dt_s.
mc_pi2d_f32_cfg_t paper_cfg(double dt_s);

struct PaperOptions {
  double rate_hz = 10000.0;  // controller rate (normalised time)
  int substeps = 2;          // RK4 sub-steps per control period
  int delay_periods = 0;     // computation delay (0: as the continuous law)
  double tau_l = 1.0;        // load
  double duration = 14.0;
};

struct PaperSample {
  double t, x1, x2, x3, x4, x3_ref, x4_ref, x2_ref, u1, u2, nu, theta_f;
};

// Runs the closed loop from the zero state; calls row() at every control
// period (before the plant advances). Returns the number of periods.
long run_paper(const PaperOptions& o, const std::function<void(const PaperSample&)>& row);

// ------------------------------------------------------------- motor
struct MotorOptions {
  double pwm_hz = 20000.0;
  int substeps = 4;
  int delay_periods = 1;
  double vbus_v = 200.0;
  double J_kgm2 = 1.0e-3;     // rotor + coupled load (documented choice)
  double B_nms_rad = 1.0e-4;  // viscous friction
  double speed_rpm = 1000.0;  // rated speed
  double ramp_s = 0.4;        // 0 -> rated speed and back
  double t_up_s = 0.05;       // start of the ramp up
  double t_load_s = 1.0;      // rated-load step
  double load_nm = 3.0;       // rated torque (Table I)
  double t_down_s = 1.6;      // start of the ramp down
  double i_limit_a = 9.0;     // current limit (both controllers)
  double bw_current_rad_s = 2.0 * 3.14159265358979 * 500.0;  // current loops
  double wn_rad_s = 60.0;                                    // mechanical loop: triple pole at -wn
  double filter_rad_s = 1000.0;                              // speed filter / dirty-derivative pole
  double noise_rms_a = 0.0;
};

struct MotorSample {
  double t, omega_m, omega_ref, id, iq, iq_ref, vd, vq, nu, theta_f, load;
};

struct MotorMetrics {
  double rms_err_rad_s = 0, peak_err_rad_s = 0, peak_current_a = 0;
  double settle_after_load_s = 0;  // |e| within 1 % of rated speed for good
  double load_dip_rad_s = 0;       // largest |e| after the load step
  unsigned faults = 0;
};

// Builds the gains of the PI^2D law for the motor options (documented in
// the scenario help) and runs it (pi2d = true) or the cascade.
mc_pi2d_f32_cfg_t motor_pi2d_cfg(const MotorOptions& o);
// The pi2d-motor rig: the paper-002 test motor on the simulated board, and
// the drive configuration (FOC current loops, limits, supervision) used by
// both the f32 and the q31 PI2D runs and the PI cascade.
hal_host::PmsmBoardConfig motor_board_cfg(const MotorOptions& o);
mc_drive_cfg_t motor_drive_cfg(const MotorOptions& o);
MotorMetrics run_motor(const MotorOptions& o, bool pi2d, double duration_s,
                       const std::function<void(const MotorSample&)>& row);

// The verdicts of pi2d-paper (the speed error after t = 10, checked into j)
// and pi2d-motor (both loops; the thresholds and their reasons in pi2d.cpp).
void check_paper(Judge& j, double duration, double max_e3_after_10);
Verdict judge_motor(const MotorOptions& o, double duration, const MotorMetrics& pi2d,
                    const MotorMetrics& cascade);

}  // namespace pi2d
}  // namespace mcsim
