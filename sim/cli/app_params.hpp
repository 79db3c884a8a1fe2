// The parameter table the drive application boots in the generic scenarios
// (issue 29 items 1 and 3): the motor and board files -> mc_params_t
// (tools/config/params.toml, firmware/app/config/mc_params.h), every gain
// and derived limit left 0 so that the firmware's C derivation
// (mc_params_resolve: mc_gains_derive, mc_law_gains_from_params,
// mc_params_to_drive_cfg) computes it, exactly as on the board.
//
// The scenarios' gain keys (--set KEY=VALUE, gain_params in drive_setup.hpp)
// are written onto the parameter of the same meaning when the user changed
// them (a value equal to the derived default stays derived):
//
//   cur_bw_rad_s -> current_bw_rad_s       enc_pll_bw_rad_s -> speed_pll_bw_rad_s
//   i_limit_a    -> i_max_a (the drive limits to min(it, the sensor's and
//                   the bus's bounds): mc_gains.c)
//   speed_wc_rad_s -> speed_bw_rad_s       speed_accel_rad_s2 -> speed_ramp_rad_s2
//   obs_crit_rad_s -> obs_omega_crit_m_rad_s  pll_bw_rad_s -> obs_pll_bw_rad_s
//   sls_wc_rad_s -> sls_speed_bw_rad_s     handover_rad_s -> sls_handover_rad_s
//   if_current_a -> sls_if_current_a       if_accel_rad_s2 -> sls_if_accel_rad_s2
//   align_time_s -> sls_align_time_s       pi2d_wn_rad_s, pi2d_a_per_s, pos_kp_per_s
//   pos_v_max_rad_s -> traj_v_max_rad_s    pos_a_max_rad_s2 -> traj_a_max_rad_s2
//   pos_d_max_rad_s2 -> traj_d_max_rad_s2  pos_filter_bw_rad_s -> traj_filter_bw_rad_s
//   stop_decel_rad_s2 -> stop_decel_rad_s2
//   model_r_scale, model_l_scale, model_flux_scale: the motor values the
//                   drive is given (r_ohm, ld_h/lq_h, flux_wb) scaled
//
// The board's part: vbus_v, pwm_hz, dead_time_s, current_sensors,
// i_sense_max_a, adc_bits, encoder_cpr from the board file, slow_loop_div
// for a slow loop at about 1 kHz; everything else the table's default
// (supervision, stall check, telemetry rates, CAN node 1, timeout).
#pragma once

#include <cstdint>
#include <string>

#include "motor_file.hpp"
#include "scenario.hpp"
extern "C" {
#include "mc_params.h"
}

namespace mcsim {

/// The parameter table for the files and the scenario's --set values
/// (see the file comment), SPEED running speed_law (MC_LAW_SPEED_*). Throws UsageError when no safe gains exist
/// (naming the file values, as derive_gains does) or when
/// mc_params_validate refuses the set (its MC_PARAMS_ERR bits named; a
/// refused speed law with its law_error reasons).
mc_params_t params_from_files(const MotorFiles& f, const Params& overrides,
                              uint32_t speed_law = 0u);

/// The names of MC_PARAMS_ERR_* bits ("DRIVE|LAW"), of the law errors
/// (MC_GAINS_ERR_* | MC_LAW_ERR_*: "PI2D_COUPLING").
std::string params_err_names(uint32_t bits);
std::string law_err_names(uint32_t bits);

/// The motor, board and every gain of the booted table (mc_params_resolve:
/// the C derivation) into the summary, under the keys record_setup writes.
void record_app_setup(const MotorFiles& f, const mc_params_t& p, Summary& s);

/// The resolved table (its gains and limits), for a scenario's timing.
mc_params_eff_t resolve_params(const mc_params_t& p);

}  // namespace mcsim
