// The parameter table the drive application boots in the generic scenarios
// (issue 29 items 1 and 3): the motor and board files -> mc_params_t
// (tools/config/params.toml, firmware/app/config/mc_params.h), every gain
// and derived limit left 0 so that the firmware's C derivation
// (mc_params_resolve: mc_gains_derive, mc_law_gains_from_params,
// mc_params_to_drive_cfg) computes it, exactly as on the board.
//
// The scenarios' gain keys (--set KEY=VALUE, app_gain_params) are the
// table's gain parameters, by name: current_bw_rad_s, speed_pll_bw_rad_s,
// speed_bw_rad_s, speed_kp_a_s_rad, speed_ki_a_rad, speed_ramp_rad_s2,
// obs_omega_crit_m_rad_s, obs_pll_bw_rad_s, sls_*, pi2d_wn_rad_s,
// pi2d_a_per_s, pos_kp_per_s, traj_*, stop_decel_rad_s2 (the ones
// mc_law_gains_from_params takes as given when not 0). Their defaults are
// what the C derivation resolves for the files; a value the user changed is
// written onto the parameter (one equal to the default stays derived). The
// current limit is the motor's: --set motor.i_max_a. Besides them:
//   model_r_scale, model_l_scale, model_flux_scale: the motor values the
//                   drive is given (r_ohm, ld_h/lq_h, flux_wb) scaled
//   angle_ref, angle_find_at_enable (app_powerup_params): the table's, their
//                   defaults from the board's encoder type
// The summary records every field of the resolved mc_gains_t as gain.NAME
// (its C names: gain.cur_bw_rad_s, gain.i_limit_a, ...) and each gain
// parameter's resolved value as param.NAME.
//
// The board's part: vbus_v, pwm_hz, dead_time_s, current_sensors,
// i_sense_max_a, adc_bits, encoder_cpr from the board file, slow_loop_div
// for a slow loop at about 1 kHz; everything else the table's default
// (supervision, stall check, telemetry rates, CAN node 1, timeout).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "motor_file.hpp"
#include "scenario.hpp"
extern "C" {
#include "mc_params.h"
}

namespace mcsim {

/// The --set keys of the gains (see the file comment).
std::vector<ParamSpec> app_gain_params(const MotorFiles& f);

/// The power-up keys of every scenario on the drive application (issue 32
/// item 1; app_scenario.hpp on_app_target adds them): theta_m0_rad (the
/// plant: the rotor's mechanical angle at power-up, where an incremental
/// encoder counts from 0), and the table's angle_ref and
/// angle_find_at_enable (defaults from the board's encoder: "abi_index"
/// index and 1, "abi" the table's, stored and 0), encoder_latency_s
/// (as5047p one PWM period, ma732 3 us, A/B 0).
std::vector<ParamSpec> app_powerup_params(const MotorFiles& f);

/// The files' table resolved by the C derivation (no --set): the derived
/// gains and limits the scenarios' defaults come from. Throws UsageError
/// (the reason and the file values named) when no safe gains exist.
mc_params_eff_t files_params_eff(const MotorFiles& f);

/// The parameter table for the files and the scenario's --set values
/// (see the file comment), SPEED running speed_law (MC_LAW_SPEED_*). Throws
/// UsageError when no safe gains exist (naming the file values), when a
/// gain is outside the table's range, or when
/// mc_params_validate refuses the set (its MC_PARAMS_ERR bits named; a
/// refused speed law with its law_error reasons).
mc_params_t params_from_files(const MotorFiles& f, const Params& overrides,
                              uint32_t speed_law = 0u);

/// The names of MC_PARAMS_ERR_* bits ("DRIVE|LAW"), of the law errors
/// (MC_GAINS_ERR_* | MC_LAW_ERR_*: "PI2D_COUPLING").
std::string params_err_names(uint32_t bits);
std::string law_err_names(uint32_t bits);
/// The names of the Hall + observer hand-over's refusals (MC_DRIVE_HALLOBS_ERR_*).
std::string hallobs_err_names(uint32_t bits);

/// The motor, board and every gain of the booted table (mc_params_resolve:
/// the C derivation) into the summary (motor.*, board.*, gain.*, param.*).
void record_app_setup(const MotorFiles& f, const mc_params_t& p, Summary& s);

/// The resolved table (its gains and limits), for a scenario's timing.
mc_params_eff_t resolve_params(const mc_params_t& p);

}  // namespace mcsim
