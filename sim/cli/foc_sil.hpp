// The FOC software-in-the-loop set-up shared by the scenarios, the benchmark
// and the SIL tests: the paper-002 "test motor" on a simulated board, driven
// by the unmodified firmware drive application (firmware/app).
#pragma once

#include <memory>

#include "hal_host/pmsm_board.hpp"
extern "C" {
#include "mc_drive.h"
}

namespace mcsim {

struct FocSilOptions {
  double pwm_hz = 20000.0;                           // PWM and current-loop rate
  int substeps = 4;                                  // RK4 sub-steps per PWM period
  int delay_periods = 1;                             // computation delay
  double bw_rad_s = 2.0 * 3.14159265358979 * 500.0;  // designed current-loop bandwidth
  double vbus_v = 200.0;
  double J_kgm2 = 1.0e-3;  // rotor + load inertia
  double load_nm = 0.0;
  double noise_rms_a = 0.0;            // current-sensor noise
  double speed_pll_bw_rad_s = 1000.0;  // encoder tracking loop (speed for the feed-forward)
  unsigned slow_loop_div = 20;         // slow loop at pwm_hz / 20 (1 kHz at 20 kHz)
  bool three_shunts = false;           // measure ic too (enables the unbalance check)
  double omega_m0_rad_s = 0.0;         // initial rotor speed (mechanical)
  double theta_m0_rad = 0.0;           // initial rotor angle (mechanical)
};

// Paper 002, Table I, test motor: 0.3 kW, n_p = 4, Phi = 0.11 Wb,
// L = 1.14 mH, R_s = 0.675 ohm, 200 V bus, 3 A rated.
mcsim::PmsmParams paper002_test_motor();

class FocSil {
 public:
  explicit FocSil(const FocSilOptions& o);
  // One PWM period: ADC trigger, firmware fast step (and slow step when
  // due), plant integration (hal_host::sil_period).
  void step();
  hal_host::PmsmBoard& board() { return *board_; }
  mc_drive_t& drive() { return drive_; }
  const FocSilOptions& options() const { return opt_; }
  double designed_kp() const { return kp_; }
  double designed_ki() const { return ki_; }

 private:
  FocSilOptions opt_;
  std::unique_ptr<hal_host::PmsmBoard> board_;
  mc_drive_t drive_{};
  double kp_ = 0, ki_ = 0;
};

}  // namespace mcsim
