#include "app_params.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>
#include <vector>

#include "drive_setup.hpp"
extern "C" {
#include "config/mc_law_cfg.h"
}

namespace mcsim {
namespace {

struct GainParam {
  const char* key;  // the scenario's --set key (gain_params)
  float mc_params_t::*field;
};

const GainParam kGainParams[] = {
    {"cur_bw_rad_s", &mc_params_t::current_bw_rad_s},
    {"i_limit_a", &mc_params_t::i_max_a},
    {"enc_pll_bw_rad_s", &mc_params_t::speed_pll_bw_rad_s},
    {"speed_wc_rad_s", &mc_params_t::speed_bw_rad_s},
    {"speed_accel_rad_s2", &mc_params_t::speed_ramp_rad_s2},
    {"obs_crit_rad_s", &mc_params_t::obs_omega_crit_m_rad_s},
    {"pll_bw_rad_s", &mc_params_t::obs_pll_bw_rad_s},
    {"sls_wc_rad_s", &mc_params_t::sls_speed_bw_rad_s},
    {"handover_rad_s", &mc_params_t::sls_handover_rad_s},
    {"if_current_a", &mc_params_t::sls_if_current_a},
    {"if_accel_rad_s2", &mc_params_t::sls_if_accel_rad_s2},
    {"align_time_s", &mc_params_t::sls_align_time_s},
    {"pi2d_wn_rad_s", &mc_params_t::pi2d_wn_rad_s},
    {"pi2d_a_per_s", &mc_params_t::pi2d_a_per_s},
    {"pos_kp_per_s", &mc_params_t::pos_kp_per_s},
    {"pos_v_max_rad_s", &mc_params_t::traj_v_max_rad_s},
    {"pos_a_max_rad_s2", &mc_params_t::traj_a_max_rad_s2},
    {"pos_d_max_rad_s2", &mc_params_t::traj_d_max_rad_s2},
    {"pos_filter_bw_rad_s", &mc_params_t::traj_filter_bw_rad_s},
    {"stop_decel_rad_s2", &mc_params_t::stop_decel_rad_s2},
};

std::string join_names(uint32_t bits, const std::vector<std::pair<uint32_t, const char*>>& names) {
  std::string s;
  uint32_t known = 0;
  for (const auto& [bit, name] : names) {
    known |= bit;
    if ((bits & bit) != 0u) s += (s.empty() ? "" : "|") + std::string(name);
  }
  if ((bits & ~known) != 0u) {
    s += (s.empty() ? "" : "|") + std::string("0x") + [](uint32_t v) {
      char b[16];
      std::snprintf(b, sizeof b, "%x", v);
      return std::string(b);
    }(bits & ~known);
  }
  return s.empty() ? "none" : s;
}

// The sensorless and PI2D laws need what the board gives them.
void refuse_law(const MotorFiles& f, const mc_params_t& p, uint32_t err) {
  const uint32_t law = mc_law_speed_check(&p);
  std::string what = "the drive application refuses the parameter table built from " +
                     f.motor.file + " and " + f.board.file + ": MC_PARAMS_ERR " +
                     params_err_names(err);
  if ((err & MC_PARAMS_ERR_LAW) != 0u) {
    const char* name = p.speed_law == MC_LAW_SPEED_PI2D         ? "PI2D"
                       : p.speed_law == MC_LAW_SPEED_SENSORLESS ? "the sensorless law"
                                                                : "the sensored speed law";
    what = std::string(name) + " refuses this motor (" + law_err_names(law) + "; " + what + ")";
  }
  throw UsageError(what);
}

}  // namespace

std::string params_err_names(uint32_t bits) {
  return join_names(bits, {{MC_PARAMS_ERR_NULL, "NULL"},
                           {MC_PARAMS_ERR_RANGE, "RANGE"},
                           {MC_PARAMS_ERR_SENSE, "SENSE"},
                           {MC_PARAMS_ERR_BANDWIDTH, "BANDWIDTH"},
                           {MC_PARAMS_ERR_DEAD_TIME, "DEAD_TIME"},
                           {MC_PARAMS_ERR_BITRATE, "BITRATE"},
                           {MC_PARAMS_ERR_DRIVE, "DRIVE"},
                           {MC_PARAMS_ERR_LAW, "LAW"},
                           {MC_PARAMS_ERR_GAINS, "GAINS"},
                           {MC_PARAMS_ERR_ENCODER, "ENCODER"},
                           {MC_PARAMS_ERR_BOARD, "BOARD"}});
}

std::string law_err_names(uint32_t bits) {
  return join_names(bits, {{MC_GAINS_ERR_VALUE, "VALUE"},
                           {MC_GAINS_ERR_LR_SHORT, "LR_SHORT"},
                           {MC_GAINS_ERR_RIPPLE, "RIPPLE"},
                           {MC_GAINS_ERR_I_LIMIT, "I_LIMIT"},
                           {MC_GAINS_ERR_SENSE, "SENSE"},
                           {MC_GAINS_ERR_SPEED_LIMIT, "SPEED_LIMIT"},
                           {MC_GAINS_ERR_PI2D_FILTER,
                            "PI2D_FILTER: the filter pole a < 3 wn, slower than the loop"},
                           {MC_GAINS_ERR_PI2D_COUPLING,
                            "PI2D_COUPLING: kt ke / (J L k2) > 300 rad/s, the back-EMF couples "
                            "the speed error into the q current"},
                           {MC_GAINS_ERR_SALIENT,
                            "SALIENT: ld_h and lq_h differ by more than 5 %, the law assumes "
                            "surface magnets"},
                           {MC_LAW_ERR_SLS_INIT, "SLS_INIT"},
                           {MC_LAW_ERR_PI2D_INIT, "PI2D_INIT"},
                           {MC_LAW_ERR_POS_INIT, "POS_INIT"},
                           {MC_LAW_ERR_RUNNING, "RUNNING"},
                           {MC_LAW_ERR_ENCODER, "ENCODER: the law needs an encoder"},
                           {MC_LAW_ERR_SPD_INIT, "SPD_INIT"}});
}

mc_params_t params_from_files(const MotorFiles& f, const Params& overrides, uint32_t speed_law) {
  // The refusals that name the files' values (mc_gains_derive's errors,
  // with the file and line of the value to change).
  const Gains g = derive_gains(f, &overrides);
  const MotorSpec& m = f.motor;
  const BoardSpec& b = f.board;
  mc_params_t p = mc_params_default;
  p.r_ohm = static_cast<float>(m.r_ohm * g.model_r_scale);
  p.ld_h = static_cast<float>(m.ld_h * g.model_l_scale);
  p.lq_h = static_cast<float>(m.lq_h * g.model_l_scale);
  p.flux_wb = static_cast<float>(m.flux_wb * g.model_flux_scale);
  p.pole_pairs = static_cast<uint32_t>(m.pole_pairs);
  p.j_kgm2 = static_cast<float>(m.j_kgm2);
  p.b_nm_s_rad = static_cast<float>(m.b_nm_s_rad);
  p.i_max_a = static_cast<float>(m.i_max_a);
  p.speed_max_rad_s = static_cast<float>(m.speed_max_rad_s);
  p.i_rated_a = static_cast<float>(m.i_rated_a);
  p.speed_rated_rad_s = static_cast<float>(m.speed_rated_rad_s);
  p.vbus_v = static_cast<float>(b.vbus_v);
  p.pwm_hz = static_cast<uint32_t>(std::lround(b.pwm_hz));
  p.dead_time_s = static_cast<float>(b.dead_time_s);
  p.current_sensors = static_cast<uint32_t>(b.current_sensors);
  p.i_sense_max_a = static_cast<float>(b.i_sense_max_a);
  p.adc_bits = static_cast<uint32_t>(b.adc_bits);
  p.encoder_cpr = static_cast<uint32_t>(b.encoder_cpr);
  p.slow_loop_div = static_cast<uint32_t>(std::max(1.0, std::round(b.pwm_hz / 1000.0)));
  // The gains the user set (a value other than the derived default).
  const std::vector<ParamSpec> specs = gain_params(f);
  for (const GainParam& gp : kGainParams) {
    const auto it = std::find_if(specs.begin(), specs.end(),
                                 [&](const ParamSpec& s) { return s.key == gp.key; });
    const double v = overrides.get(gp.key);
    if (it != specs.end() && v != it->default_value) p.*(gp.field) = static_cast<float>(v);
  }
  p.speed_law = speed_law;
  const uint32_t err = mc_params_validate(&p);
  if (err != MC_PARAMS_OK) refuse_law(f, p, err);
  return p;
}

mc_params_eff_t resolve_params(const mc_params_t& p) {
  mc_params_eff_t e{};
  (void)mc_params_resolve(&p, &e);
  return e;
}

void record_app_setup(const MotorFiles& f, const mc_params_t& p, Summary& s) {
  Gains g;
  const mc_params_eff_t e = resolve_params(p);
  const mc_gains_t& c = e.g;
  g.cur_bw_rad_s = c.cur_bw_rad_s;
  g.i_limit_a = c.i_limit_a;
  g.enc_pll_bw_rad_s = c.enc_pll_bw_rad_s;
  g.speed_wc_rad_s = c.speed_wc_rad_s;
  g.speed_accel_rad_s2 = c.speed_accel_rad_s2;
  g.obs_crit_rad_s = c.obs_crit_rad_s;
  g.pll_bw_rad_s = c.pll_bw_rad_s;
  g.sls_wc_rad_s = c.sls_wc_rad_s;
  g.handover_rad_s = c.handover_rad_s;
  g.if_current_a = c.if_current_a;
  g.if_accel_rad_s2 = c.if_accel_rad_s2;
  g.align_time_s = c.align_time_s;
  g.pi2d_wn_rad_s = c.pi2d_wn_rad_s;
  g.pi2d_a_per_s = c.pi2d_a_per_s;
  g.pos_kp_per_s = c.pos_kp_per_s;
  g.pos_v_max_rad_s = c.pos_v_max_rad_s;
  g.pos_a_max_rad_s2 = c.pos_a_max_rad_s2;
  g.pos_d_max_rad_s2 = c.pos_d_max_rad_s2;
  g.pos_filter_bw_rad_s = c.pos_filter_bw_rad_s;
  g.stop_decel_rad_s2 = c.stop_decel_rad_s2;
  g.kt_nm_a = c.kt_nm_a;
  g.v_max_v = c.v_max_v;
  g.i_rated_eff_a = c.i_rated_eff_a;
  g.torque_rated_nm = c.torque_rated_nm;
  g.speed_limit_rad_s = c.speed_limit_rad_s;
  g.speed_rated_eff_rad_s = c.speed_rated_eff_rad_s;
  g.model_r_scale = p.r_ohm / f.motor.r_ohm;
  g.model_l_scale = p.ld_h / f.motor.ld_h;
  g.model_flux_scale = f.motor.flux_wb > 0 ? p.flux_wb / f.motor.flux_wb : 1.0;
  record_setup(f, g, s);
  s.set("param.speed_law", p.speed_law);
  s.set("param.speed_kp_a_s_rad", e.p.speed_kp_a_s_rad);
  s.set("param.speed_ki_a_rad", e.p.speed_ki_a_rad);
  s.set("param.speed_ramp_rad_s2", e.p.speed_ramp_rad_s2);
  s.set("param.slow_loop_div", p.slow_loop_div);
}

}  // namespace mcsim
