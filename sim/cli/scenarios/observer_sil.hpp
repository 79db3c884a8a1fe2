// Sensorless FOC (paper 002) on the simulated board: the unmodified drive
// application (firmware/app/mc_drive) in CTRL mode with the sensorless
// plug-in (firmware/app/mc_ctrl_sensorless), on hal_host::PmsmBoard. Shared
// by the observer-* scenarios of mcsim and the SIL tests.
#pragma once

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "hal_host/pmsm_board.hpp"
#include "scenario.hpp"
extern "C" {
#include "mc_ctrl_sensorless.h"
#include "mc_ctrl_sensorless_q31.h"
#include "mc_drive.h"
}

namespace mcsim {
namespace observer {

// Piecewise-constant load torque (N m, opposing positive rotation): value
// of the last step with t >= t_s, 0 before the first. Pure, as the plant's
// RK4 requires.
struct LoadSteps {
  std::vector<std::pair<double, double>> steps;  // (t_s, tau_nm), sorted by t
  double eval(double t_s) const;
};

struct Machine {
  std::string name;
  PmsmParams motor;  // R, L, flux, pole pairs, J, B
  double vbus_v = 0.0;
  double rated_torque_nm = 0.0, rated_speed_rpm = 0.0, rated_current_a = 0.0;
  double i_full_scale_a = 0.0;  // current-sensor range
};

// Paper 002, Table I. J and friction are not in the paper: our choice,
// documented in the scenario JSON and the README.
Machine table1_40kw();      // 40 kW simulation machine
Machine test_motor_300w();  // 0.3 kW test motor on its dynamometer

struct SilOptions {
  double pwm_hz = 8000.0;       // paper: 8 kHz PWM, 125 us current loop
  unsigned speed_div = 10;      // paper: 1.25 ms speed loop
  int substeps = 4;             // RK4 sub-steps per PWM period
  int delay_periods = 1;        // computation delay of the board
  double dead_time_s = 0.0;     // inverter dead time
  double dead_comp_frac = 1.0;  // fraction of it the controller compensates
  bool dead_comp_duty = false;  // compensate in the duties too (else the observer only)
  double noise_rms_a = 0.0;     // current-sensor noise
  double r_error = 0.0;         // relative error of R in the controller
  double flux_error = 0.0;      // relative error of flux in the controller
  bool lowspeed_fallback = true;
  bool if_damping = true;
  int encoder_cpr = 8192;         // board encoder (unused by the sensorless law)
  double crit_frac = 0.02;        // observer critical speed / rated speed
  double speed_wc_rad_s = 100.0;  // speed-loop crossover (J / kt plant)
  bool q31 = false;               // run the q31 plug-in (mc_ctrl_sensorless_q31)
};

// Controller configuration for a machine (the paper's structure, our gains;
// every value is written to the scenario JSON by record()).
mc_ctrl_sls_cfg_t default_ctrl_cfg(const Machine& m, const SilOptions& o);

// The q31 plug-in's config: the f32 config plus bases from the machine
// (current: the sensor range; voltage: twice the bus; electrical speed:
// the next power of two above 1.2x the PLL limit 2 speed_max pole_pairs;
// flux: the power of two at or above 1.5 (flux + L i_base), mc_fluxobs_q31.h).
mc_ctrl_sls_q31_cfg_t q31_ctrl_cfg(const Machine& m, const mc_ctrl_sls_cfg_t& f);

class Sil {
 public:
  Sil(const Machine& m, const SilOptions& o, const mc_ctrl_sls_cfg_t& cfg, LoadSteps load);
  // One PWM period: sample, drive fast (and slow) step, plant.
  void step();
  hal_host::PmsmBoard& board() { return *board_; }
  mc_drive_t& drive() { return drive_; }
  // The f32 plug-in (initialised in both cases; attached unless q31).
  mc_ctrl_sls_t& ctrl() { return ctrl_; }
  // The q31 plug-in (attached with SilOptions::q31).
  mc_ctrl_sls_q31_t& ctrl_q31() { return ctrl_q31_; }
  bool q31() const { return o_.q31; }
  // Telemetry of the attached plug-in's last fast step (the q31 one's
  // converted to engineering units after each step).
  const mc_ctrl_sls_tm_t& tm() const { return o_.q31 ? tm_q31_ : ctrl_.tm; }
  // Speed reference to the attached plug-in (MC_CTRL_SLS_ERR_* bits).
  uint32_t set_speed_ref(float omega_m_rad_s);
  // Observer flux estimate [Wb] of the attached plug-in.
  void flux_hat_wb(double* p_alpha, double* p_beta) const;
  const Machine& machine() const { return m_; }
  double load_nm(double t_s) const { return load_.eval(t_s); }
  double t_s() const { return board_->t_s(); }
  // True electrical angle at the last sampling instant (the one the
  // firmware's last fast step saw), wrapped to [-pi, pi).
  double theta_e_true() const { return theta_e_sampled_; }
  // Observer angle error (wrapped) against it, rad.
  double angle_error() const;
  // Every motor, inverter and controller parameter into the summary.
  void record(Summary& s) const;

 private:
  Machine m_;
  SilOptions o_;
  LoadSteps load_;
  std::unique_ptr<hal_host::PmsmBoard> board_;
  mc_drive_t drive_{};
  mc_ctrl_sls_t ctrl_{};
  mc_ctrl_sls_q31_t ctrl_q31_{};
  mc_ctrl_sls_tm_t tm_q31_{};
  double theta_e_sampled_ = 0.0;
};

}  // namespace observer
}  // namespace mcsim
