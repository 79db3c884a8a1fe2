// The drive for any motor: controller gains derived from the motor and board
// files (sim/cli/motor_file.hpp), and the one place where the firmware's
// configurations (mc_drive_cfg_t, the sensorless and PI^2D plug-ins, the
// sensored speed PI) and the simulated board are built from them.
//
// The gains: Gains below holds the C derivation's results
// (firmware/app/config/mc_gains.h documents every formula and refusal);
// derive_gains keeps the scenarios that still build the drive here (not the
// generic ones: they run the application on its parameter table,
// app_params.hpp).
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
/// Every motor and board value into the summary (motor.*, board.*).
void record_files(const MotorFiles& f, Summary& s);

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
