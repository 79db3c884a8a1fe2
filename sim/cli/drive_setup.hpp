// The drive for any motor: controller gains derived from the motor and board
// files (sim/cli/motor_file.hpp), and the one place where the firmware's
// configurations (mc_drive_cfg_t, the sensorless and PI^2D plug-ins, the
// sensored speed PI) and the simulated board are built from them.
//
// Gains (every one overridable with --set KEY=VALUE; the others are then
// derived from the overridden values). T = 1/pwm_hz, kt = 3/2 p flux,
// ke = p flux, v_max = 0.95 vbus / sqrt 3 (the SVPWM circle).
//
//   cur_bw_rad_s       = 0.08 / T. The current PI kp = L bw, ki = R bw
//                        cancels the winding's pole: the loop is first order
//                        with bandwidth bw; with the one-period computation
//                        delay it stays first-order-like (10-90 % rise
//                        ln 9 / bw within 25 %) while bw T <= 0.08.
//   i_limit_a          = min(i_max_a, i_sense_max_a / 1.25, 0.8 v_max / R):
//                        inside the sensor's range with margin, and a
//                        current the bus can push through R at standstill.
//   i_rated_eff_a      = min(i_rated_a, i_limit_a); torque_rated = kt i_rated_eff.
//   speed_limit_rad_s  = min(speed_max_rad_s, 0.9 w_v), w_v the speed at
//                        which rated current needs v_max (R, L, ke).
//   speed_rated_eff    = min(speed_rated_rad_s, speed_limit_rad_s).
//   enc_pll_bw_rad_s   = min(1000, 0.1 / T): the drive's encoder tracking loop.
//   speed_wc_rad_s     = min(cur_bw / 10, enc_pll_bw / 4): crossover of the
//                        sensored speed PI on the plant kt / (J s):
//                        kp = J wc / kt, ki = kp wc / 4 (zero at wc / 4).
//   speed_accel_rad_s2 = 0.5 kt i_limit / J: the reference slews so that
//                        half the current limit accelerates the rotor.
//   obs_crit_rad_s     = 0.02 speed_rated_eff: flux observer critical speed,
//                        gamma = 4 p w_crit / flux^2 (in the firmware).
//   pll_bw_rad_s       = min(300, 0.04 / T): observer PLL (paper 002).
//   sls_wc_rad_s       = min(pll_bw / 3, cur_bw / 10): sensorless speed PI
//                        crossover, same formula as the sensored one.
//   handover_rad_s     = 0.1 speed_rated_eff (5x the critical speed).
//   if_current_a       = min(i_limit, 0.8 i_rated_eff): holds 30 % rated load
//                        at a load angle of about 22 deg plus the ramp.
//   if_accel_rad_s2    = 0.15 torque_rated / J.
//   align_time_s       = clamp(2 sqrt(0.2 J / (p 0.3 torque_rated)),
//                        10 / cur_bw, 0.05): short enough that a 30 %
//                        rated load cannot turn the rotor 0.2 rad (electrical)
//                        while the current ramps up, long enough for the
//                        current loop.
//   pos_kp_per_s       = speed_wc / 6: position P gain (the position pole
//                        below the velocity PI's zero at speed_wc / 4, so the
//                        cascade does not overshoot); the velocity PI of the
//                        position cascade is the sensored speed PI above.
//   pos_v_max_rad_s    = 0.5 speed_rated_eff: trapezoid cruise speed.
//   pos_a_max_rad_s2   = speed_accel_rad_s2 (half the current limit
//                        accelerates the rotor; the other half is the loop's).
//   pos_d_max_rad_s2   = speed_accel_rad_s2.
//   pos_filter_bw_rad_s = pos_kp: input filter of streamed setpoints.
//   stop_decel_rad_s2  = speed_accel_rad_s2: the drive's controlled stop.
//   pi2d_wn_rad_s      = min(speed_wc / 3, 0.5 R / L): the PI^2D triple pole;
//                        the R/L bound keeps the proof's ki (L/R)^2 < eps
//                        with eps = 2 ki / kp (kp' = kp / 2).
//   pi2d_a_per_s       = min(enc_pll_bw, 0.1 / T, 2 cur_bw sigma / (3 wn)),
//                        sigma = kt / J: dirty-derivative pole (b = 1); the
//                        last bound keeps the law's coupling of the speed
//                        error into the q-current error (Delta ~ 3 wn a / sigma)
//                        below 2 k2. PI^2D is refused when this leaves
//                        a < 3 wn (the filter would be slower than the loop),
//                        and when kt ke / (J L k2) > 300 rad/s: an empirical
//                        bound (the library's gimbal motor, 453, limit-cycles
//                        to over-current with any wn, a tried; the others are
//                        at 7 to 186 and settle).
//
// Refused (UsageError naming the reason): L/R shorter than two PWM periods;
// a PWM ripple vbus T / (4 L) (peak to peak, half-bridge at 50 % duty: an
// upper bound) above i_max_a; an i_limit below 10 % of
// i_max_a (sensor or bus too small for the motor).
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "hal_host/pmsm_board.hpp"
#include "motor_file.hpp"
#include "scenario.hpp"
extern "C" {
#include "mc_ctrl_pi2d.h"
#include "mc_ctrl_position.h"
#include "mc_ctrl_sensorless.h"
#include "mc_drive.h"
#include "pi/mc_pi.h"
}

namespace mcsim {

struct Gains {
  double cur_bw_rad_s = 0, i_limit_a = 0, i_rated_eff_a = 0, torque_rated_nm = 0;
  double speed_limit_rad_s = 0, speed_rated_eff_rad_s = 0;
  double enc_pll_bw_rad_s = 0, speed_wc_rad_s = 0, speed_accel_rad_s2 = 0;
  double obs_crit_rad_s = 0, pll_bw_rad_s = 0, sls_wc_rad_s = 0, handover_rad_s = 0;
  double if_current_a = 0, if_accel_rad_s2 = 0, align_time_s = 0;
  double pi2d_wn_rad_s = 0, pi2d_a_per_s = 0;
  double pos_kp_per_s = 0, pos_v_max_rad_s = 0, pos_a_max_rad_s2 = 0, pos_d_max_rad_s2 = 0;
  double pos_filter_bw_rad_s = 0, stop_decel_rad_s2 = 0;
  double model_r_scale = 1, model_l_scale = 1, model_flux_scale = 1;  // drive's / motor's
  // derived, not settable
  double kt_nm_a = 0, v_max_v = 0;
  double speed_kp_a_s_rad = 0, speed_ki_a_rad = 0;  // the speed PI at speed_wc
  bool pi2d_ok = true;       // the PI^2D filter pole could be placed (see above)
  double pi2d_coupling = 0;  // kt ke / (J L k2) [rad/s]; PI^2D refused above 300
};

/// The --set keys of the gains, their defaults derived from the files.
std::vector<ParamSpec> gain_params(const MotorFiles& f);

/// Gains for the files; with p, every gain whose value differs from its
/// derived default is taken from p and the later ones derived from it.
/// Throws UsageError when no safe gains exist.
Gains derive_gains(const MotorFiles& f, const Params* p);

/// Every motor, board and gain value into the summary.
void record_setup(const MotorFiles& f, const Gains& g, Summary& s);

enum class Law { kCurrent, kSpeedPi, kPi2d, kSensorless, kPosition };

struct RigOptions {
  Law law = Law::kCurrent;
  // Load torque [N m] opposing positive rotation, a pure function of t.
  std::function<double(double)> load_nm;
  // MTPA + field weakening in the drive (build_fw_cfg); the speed PI's
  // output is then the signed current command.
  bool fw = false;
  // Optional: the motor values the drive believes (e.g. identified by
  // commissioning); the plant stays the files' motor. Unset: the same.
  const MotorSpec* drive_motor = nullptr;
  // Optional hooks: the plant's board configuration before it is built
  // (sensor offsets, encoder), the board once built (injections), and the
  // drive configuration before init (identified offsets and encoder).
  std::function<void(hal_host::PmsmBoardConfig&)> board_hook;
  std::function<void(hal_host::PmsmBoard&)> board_built_hook;
  std::function<void(mc_drive_cfg_t&)> drive_hook;
};

/// The simulated board + the unmodified drive + the law's plug-in, built
/// from the files and the gains. Step = one PWM period.
class MotorRig {
 public:
  MotorRig(const MotorFiles& f, const Gains& g, RigOptions o);
  MotorRig(const MotorRig&) = delete;
  MotorRig& operator=(const MotorRig&) = delete;
  ~MotorRig() = default;

  void step();
  /// Speed reference (mechanical) for the speed laws; the sensored PI and
  /// PI^2D get it slewed at speed_accel_rad_s2 here.
  void set_speed_ref(double omega_m_rad_s);
  hal_host::PmsmBoard& board() { return *board_; }
  mc_drive_t& drive() { return drive_; }
  const mc_ctrl_sls_t& sls() const { return sls_; }
  const mc_ctrl_pi2d_t& pi2d() const { return pi2d_; }
  mc_ctrl_pos_t& pos() { return pos_; }
  double omega_ref_rad_s() const;
  double period_s() const { return T_; }
  double theta_e_true() const;
  void dq_refs(double* id_ref, double* iq_ref) const;
  void dq_volts(double* vd, double* vq) const;
  double theta_e_hat() const;  // NaN unless an observer runs
  const mc_drive_cfg_t& drive_cfg() const { return dcfg_; }

 private:
  void set_references();
  MotorFiles f_;
  MotorFiles fd_;  // the drive's view of the motor (RigOptions::drive_motor)
  Gains g_;
  RigOptions o_;
  double T_ = 0;
  std::unique_ptr<hal_host::PmsmBoard> board_;
  mc_drive_t drive_{};
  mc_drive_cfg_t dcfg_{};
  mc_ctrl_sls_t sls_{};
  mc_ctrl_pi2d_t pi2d_{};
  mc_ctrl_pos_t pos_{};
  mc_pi_f32_t spi_{};
  double w_cmd_ = 0, w_ref_ = 0, a_ref_ = 0;
};

/// Build the drive configuration (current loop, limits, supervision).
mc_drive_cfg_t build_drive_cfg(const MotorFiles& f, const Gains& g);
mc_ctrl_sls_cfg_t build_sensorless_cfg(const MotorFiles& f, const Gains& g);
mc_ctrl_pi2d_cfg_t build_pi2d_cfg(const MotorFiles& f, const Gains& g);
mc_ctrl_pos_cfg_t build_position_cfg(const MotorFiles& f, const Gains& g);
hal_host::PmsmBoardConfig build_board_cfg(const MotorFiles& f);
/// MTPA / field weakening (kernels/fw/mc_fw.h): v_margin 0.9 (the current
/// loop limits at 0.95 of the circle), k_demag 0.9, i_max = i_limit, and
/// ki_fw = cur_bw / (10 p speed_max Ld): the loop d|v|/d id ~ omega_e Ld
/// closes at a tenth of the current loop's bandwidth at the top speed
/// (slower below it).
mc_fw_f32_cfg_t build_fw_cfg(const MotorFiles& f, const Gains& g);

}  // namespace mcsim
