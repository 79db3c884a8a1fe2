#include "app_params.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "plant_from_files.hpp"
extern "C" {
#include "config/mc_law_cfg.h"
#include "mc_drive.h"
}

namespace mcsim {
namespace {

// The gain parameters of the table (tools/config/params.toml), by name: the
// values mc_law_gains_from_params hands mc_gains_derive as given when not 0.
// Each is a --set key of the generic scenarios, its default the value the C
// derivation resolves for the files (mc_params_resolve).
const char* const kGainNames[] = {
    "current_bw_rad_s",   "speed_pll_bw_rad_s", "speed_bw_rad_s",         "speed_kp_a_s_rad",
    "speed_ki_a_rad",     "speed_ramp_rad_s2",  "obs_omega_crit_m_rad_s", "obs_pll_bw_rad_s",
    "sls_speed_bw_rad_s", "sls_handover_rad_s", "sls_if_current_a",       "sls_if_accel_rad_s2",
    "sls_align_time_s",   "pi2d_wn_rad_s",      "pi2d_a_per_s",           "pos_kp_per_s",
    "traj_v_max_rad_s",   "traj_a_max_rad_s2",  "traj_d_max_rad_s2",      "traj_filter_bw_rad_s",
    "stop_decel_rad_s2",
};

// Model errors: the motor values the drive is given, the files' scaled.
struct ModelScale {
  const char* key;
  const char* help;
};
const ModelScale kScales[] = {
    {"model_r_scale", "the drive's R / the motor's (model error)"},
    {"model_l_scale", "the drive's Ld, Lq / the motor's (model error)"},
    {"model_flux_scale", "the drive's flux / the motor's (model error)"},
};

// The derived limits of mc_gains_t the summary records (gain.NAME), besides
// the gain parameters' own values.
struct GainField {
  const char* name;
  double mc_gains_t::*field;
};
const GainField kGainFields[] = {
    {"cur_bw_rad_s", &mc_gains_t::cur_bw_rad_s},
    {"i_limit_a", &mc_gains_t::i_limit_a},
    {"enc_pll_bw_rad_s", &mc_gains_t::enc_pll_bw_rad_s},
    {"speed_wc_rad_s", &mc_gains_t::speed_wc_rad_s},
    {"speed_accel_rad_s2", &mc_gains_t::speed_accel_rad_s2},
    {"speed_kp_a_s_rad", &mc_gains_t::speed_kp_a_s_rad},
    {"speed_ki_a_rad", &mc_gains_t::speed_ki_a_rad},
    {"obs_crit_rad_s", &mc_gains_t::obs_crit_rad_s},
    {"pll_bw_rad_s", &mc_gains_t::pll_bw_rad_s},
    {"sls_wc_rad_s", &mc_gains_t::sls_wc_rad_s},
    {"handover_rad_s", &mc_gains_t::handover_rad_s},
    {"if_current_a", &mc_gains_t::if_current_a},
    {"if_accel_rad_s2", &mc_gains_t::if_accel_rad_s2},
    {"align_time_s", &mc_gains_t::align_time_s},
    {"pi2d_wn_rad_s", &mc_gains_t::pi2d_wn_rad_s},
    {"pi2d_a_per_s", &mc_gains_t::pi2d_a_per_s},
    {"pos_kp_per_s", &mc_gains_t::pos_kp_per_s},
    {"pos_v_max_rad_s", &mc_gains_t::pos_v_max_rad_s},
    {"pos_a_max_rad_s2", &mc_gains_t::pos_a_max_rad_s2},
    {"pos_d_max_rad_s2", &mc_gains_t::pos_d_max_rad_s2},
    {"pos_filter_bw_rad_s", &mc_gains_t::pos_filter_bw_rad_s},
    {"stop_decel_rad_s2", &mc_gains_t::stop_decel_rad_s2},
    {"kt_nm_a", &mc_gains_t::kt_nm_a},
    {"v_max_v", &mc_gains_t::v_max_v},
    {"i_rated_eff_a", &mc_gains_t::i_rated_eff_a},
    {"torque_rated_nm", &mc_gains_t::torque_rated_nm},
    {"speed_limit_rad_s", &mc_gains_t::speed_limit_rad_s},
    {"speed_rated_eff_rad_s", &mc_gains_t::speed_rated_eff_rad_s},
    {"pi2d_coupling", &mc_gains_t::pi2d_coupling},
    {"speed_voltage_rad_s", &mc_gains_t::speed_voltage_rad_s},
    {"speed_delay_rad_s", &mc_gains_t::speed_delay_rad_s},
};

// The table row of a gain parameter (kGainNames holds only table names: a
// unit test checks each is found).
const mc_param_info_t& row_of(const char* name) {
  const int32_t i = mc_param_find_name(name);
  if (i < 0) throw std::logic_error(std::string("no parameter named ") + name);
  return mc_param_table[i];
}

double get_f32(const mc_params_t& p, const mc_param_info_t& info) {
  mc_param_value_t v;
  v.u = mc_param_get_raw(&p, &info);
  return static_cast<double>(v.f);
}

std::string num(double v) {
  std::ostringstream os;
  os.precision(4);
  os << v;
  return os.str();
}

// Where a file key's value came from ("FILE:LINE", or the --set that
// replaced it); the file itself for a key left at its default.
std::string where(const KeySources& at, const std::string& key, const std::string& file) {
  const auto it = at.find(key);
  return it != at.end() ? it->second : file;
}

// The refusals of mc_gains_derive's errors (mc_params_resolve): no gains
// make these safe. Each names the value its remedy changes (file and line,
// or its --set) and the values the C derivation weighed it against (e.m:
// what the drive is given, the model scales applied).
void refuse_unsafe(const MotorFiles& f, uint32_t err, const mc_params_eff_t& e) {
  const MotorSpec& m = f.motor;
  const BoardSpec& b = f.board;
  const mc_gains_motor_t& gm = e.m;
  const double T = 1.0 / gm.pwm_hz;
  const double l_min = std::min(gm.ld_h, gm.lq_h);
  const std::string l_at = where(m.at, m.ld_h <= m.lq_h ? "ld_h" : "lq_h", m.file);
  if ((err & MC_GAINS_ERR_VALUE) != 0u) {
    throw UsageError(m.file + ", " + b.file + ": no gains: a motor or board value is not positive");
  }
  if ((err & MC_GAINS_ERR_LR_SHORT) != 0u) {
    throw UsageError(where(b.at, "pwm_hz", b.file) +
                     ": no safe gains: the electrical time constant L/R = " +
                     num(l_min / gm.r_ohm) + " s (L at " + l_at + ", r_ohm at " +
                     where(m.at, "r_ohm", m.file) + ") is shorter than two PWM periods (" +
                     num(2 * T) + " s at " + num(gm.pwm_hz) + " Hz): raise pwm_hz");
  }
  if ((err & MC_GAINS_ERR_RIPPLE) != 0u) {
    throw UsageError(where(b.at, "pwm_hz", b.file) +
                     ": no safe gains: the PWM current ripple vbus T / (4 L) = " +
                     num(gm.vbus_v * T / (4.0 * l_min)) + " A (peak to peak; L at " + l_at +
                     ") exceeds i_max_a (" + num(gm.i_max_a) + " A at " +
                     where(m.at, "i_max_a", m.file) + "): raise pwm_hz or lower vbus_v (at " +
                     where(b.at, "vbus_v", b.file) + ")");
  }
  if ((err & MC_GAINS_ERR_I_LIMIT) != 0u) {
    throw UsageError(where(b.at, "i_sense_max_a", b.file) + ": no safe gains: the usable current " +
                     num(e.g.i_limit_a) +
                     " A (sensor range / 1.25, bus through R) is below 10 % of i_max_a (" +
                     num(gm.i_max_a) + " A at " + where(m.at, "i_max_a", m.file) + ")");
  }
  if ((err & MC_GAINS_ERR_SENSE) != 0u) {
    throw UsageError(where(b.at, "i_sense_max_a", b.file) + ": i_limit_a " + num(e.g.i_limit_a) +
                     " A leaves no margin to the current sensor's full scale " +
                     num(gm.i_sense_max_a) + " A");
  }
  if ((err & MC_GAINS_ERR_SPEED_LIMIT) != 0u) {
    throw UsageError(where(b.at, "vbus_v", b.file) + ": no safe gains: the bus (" + num(gm.vbus_v) +
                     " V) cannot drive rated current (" + num(gm.i_rated_a) +
                     " A, the motor's R and flux: " + m.file + ") at any speed");
  }
  if (err != 0u) {
    throw UsageError(m.file + ", " + b.file + ": no safe gains: MC_GAINS_ERR " +
                     law_err_names(err));
  }
}

// The files' motor and board into the table (the drive's motor values
// scaled by the model errors); every gain and derived limit left 0.
mc_params_t table_of(const MotorFiles& f, double r_scale, double l_scale, double flux_scale) {
  const MotorSpec& m = f.motor;
  const BoardSpec& b = f.board;
  mc_params_t p = mc_params_default;
  p.r_ohm = static_cast<float>(m.r_ohm * r_scale);
  p.ld_h = static_cast<float>(m.ld_h * l_scale);
  p.lq_h = static_cast<float>(m.lq_h * l_scale);
  p.flux_wb = static_cast<float>(m.flux_wb * flux_scale);
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
  p.vbus_board_max_v = static_cast<float>(b.bus_limit_v());
  p.slow_loop_div = static_cast<uint32_t>(std::max(1.0, std::round(b.pwm_hz / 1000.0)));
  // an absolute SPI encoder's latency (the image's board sets the same:
  // board_stm32f405.c): the AS5047P's angle is latched at the end of the
  // previous period's frame (DAEC covers the chip's own delay), the MA732's
  // at its frame's start less its 3 us
  if (b.encoder == kEncoderAs5047p) p.encoder_latency_s = static_cast<float>(1.0 / b.pwm_hz);
  if (b.encoder == kEncoderMa732) p.encoder_latency_s = 3e-6f;
  if (b.encoder == kEncoderHall) {
    // the Hall kernel on the board's Hall inputs, referenced at power-up
    p.encoder_type = MC_PARAMS_ENCODER_HALL;
    p.angle_ref = MC_DRIVE_ANGLE_REF_STORED;
  }
  if (b.encoder == kEncoderAbiIndex) {
    // the offset is relative to the index: an index search at the first enable
    p.angle_ref = MC_DRIVE_ANGLE_REF_INDEX;
    p.angle_find_at_enable = 1u;
  }
  return p;
}

// angle_ref, angle_find_at_enable from the run's keys (when it has them).
void set_angle_params(const Params& P, mc_params_t* p) {
  const auto& v = P.values();
  if (const auto it = v.find("angle_ref"); it != v.end()) {
    p->angle_ref = static_cast<uint32_t>(it->second);
  }
  if (const auto it = v.find("angle_find_at_enable"); it != v.end()) {
    p->angle_find_at_enable = static_cast<uint32_t>(it->second);
  }
  if (const auto it = v.find("encoder_latency_s"); it != v.end()) {
    p->encoder_latency_s = static_cast<float>(it->second);
  }
  // the Hall + observer hand-over (firmware/app/drive/mc_drive_hallobs.h)
  if (const auto it = v.find("hall_obs_start_e_rad_s"); it != v.end()) {
    p->hall_obs_start_e_rad_s = static_cast<float>(it->second);
  }
  if (const auto it = v.find("hall_obs_end_e_rad_s"); it != v.end()) {
    p->hall_obs_end_e_rad_s = static_cast<float>(it->second);
  }
  if (const auto it = v.find("hall_obs_disagree_e_rad"); it != v.end()) {
    p->hall_obs_disagree_e_rad = static_cast<float>(it->second);
  }
}

// The table resolved by the C derivation, refused with the reason named.
mc_params_eff_t resolve_or_refuse(const MotorFiles& f, const mc_params_t& p) {
  mc_params_eff_t e{};
  const uint32_t err = mc_params_resolve(&p, &e);
  if (err != MC_GAINS_OK) refuse_unsafe(f, err, e);
  return e;
}

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
  if ((err & MC_PARAMS_ERR_HALL_OBS) != 0u) {
    mc_drive_hallobs_cfg_t hc{};
    what = "the Hall + observer hand-over refuses this table (MC_DRIVE_HALLOBS_ERR " +
           hallobs_err_names(mc_law_hallobs_cfg(&p, &hc)) + "; " + what + ")";
  }
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
                           {MC_PARAMS_ERR_BOARD, "BOARD"},
                           {MC_PARAMS_ERR_HALL_OBS, "HALL_OBS"}});
}

std::string hallobs_err_names(uint32_t bits) {
  return join_names(
      bits,
      {{MC_DRIVE_HALLOBS_ERR_NULL, "NULL"},
       {MC_DRIVE_HALLOBS_ERR_BLEND,
        "BLEND: not 0 < hall_obs_start < hall_obs_end, or hall_obs_disagree not in (0, pi/2]"},
       {MC_DRIVE_HALLOBS_ERR_OBSERVER, "OBSERVER: the flux observer refuses its gain"},
       {MC_DRIVE_HALLOBS_ERR_PLL, "PLL"},
       {MC_DRIVE_HALLOBS_ERR_TIMING, "TIMING"},
       {MC_DRIVE_HALLOBS_ERR_NOT_HALL, "NOT_HALL: encoder_type is not the Hall sensors"},
       {MC_DRIVE_HALLOBS_ERR_MOTOR,
        "MOTOR: the observer needs R, L and flux (and a non-salient machine) as the sensorless "
        "law"}});
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
                            "SALIENT: ld_h and lq_h differ by more than 5 %, the PI2D law "
                            "assumes surface magnets"},
                           {MC_LAW_ERR_SLS_INIT, "SLS_INIT"},
                           {MC_LAW_ERR_PI2D_INIT, "PI2D_INIT"},
                           {MC_LAW_ERR_POS_INIT, "POS_INIT"},
                           {MC_LAW_ERR_RUNNING, "RUNNING"},
                           {MC_LAW_ERR_ENCODER, "ENCODER: the law needs an encoder"},
                           {MC_LAW_ERR_SPD_INIT, "SPD_INIT"}});
}

std::vector<ParamSpec> app_gain_params(const MotorFiles& f) {
  const mc_params_eff_t e = files_params_eff(f);
  std::vector<ParamSpec> v;
  for (const char* name : kGainNames) {
    const mc_param_info_t& info = row_of(name);
    const int32_t i = mc_param_find_name(name);
    const double d = get_f32(e.p, info);
    mc_param_value_t lo, hi;
    lo = info.min;
    hi = info.max;
    v.push_back({name, d, mc_param_units[i],
                 "the table's parameter; default derived from the motor and board "
                 "(firmware/app/config/mc_gains.h)",
                 std::min(static_cast<double>(lo.f), d), std::max(static_cast<double>(hi.f), d)});
  }
  for (const ModelScale& s : kScales) v.push_back({s.key, 1.0, "1", s.help, 1e-3, 1e3});
  return v;
}

std::vector<ParamSpec> app_powerup_params(const MotorFiles& f) {
  const mc_params_t d = table_of(f, 1.0, 1.0, 1.0);
  return {
      {"theta_m0_rad", 0.0, "rad",
       "plant: the rotor's mechanical angle at power-up (an incremental encoder counts from 0 "
       "there)",
       -100.0, 100.0},
      {"angle_ref",
       static_cast<double>(d.angle_ref),
       "1",
       "the table's parameter: what makes the stored encoder offset true after a power-up "
       "(stored, index, align; default from board.encoder)",
       0.0,
       2.0,
       {{"stored", 0.0}, {"index", 1.0}, {"align", 2.0}}},
      {"angle_find_at_enable", static_cast<double>(d.angle_find_at_enable), "1",
       "the table's parameter: 1 = the first enable runs the index search or the alignment, "
       "0 = it is refused (ANGLE_UNKNOWN) until the angle is known",
       0.0, 1.0},
      {"encoder_latency_s", static_cast<double>(d.encoder_latency_s), "s",
       "the table's parameter: the encoder's latency the drive advances the angle by "
       "(default from board.encoder: as5047p one PWM period, ma732 3 us, A/B 0)",
       0.0, 1e-3},
      {"hall_obs_start_e_rad_s", static_cast<double>(d.hall_obs_start_e_rad_s), "rad/s",
       "the table's parameter: the Hall + observer hand-over's start, |speed| el. (board.encoder "
       "hall)",
       0.0, 1e5},
      {"hall_obs_end_e_rad_s", static_cast<double>(d.hall_obs_end_e_rad_s), "rad/s",
       "the table's parameter: the hand-over's end, |speed| el.; 0 = off", 0.0, 1e5},
      {"hall_obs_disagree_e_rad", static_cast<double>(d.hall_obs_disagree_e_rad), "rad",
       "the table's parameter: the largest |observer - Hall| angle while the observer is used", 0.0,
       1.5707964},
  };
}

mc_params_eff_t files_params_eff(const MotorFiles& f) {
  return resolve_or_refuse(f, table_of(f, 1.0, 1.0, 1.0));
}

mc_params_t params_from_files(const MotorFiles& f, const Params& overrides, uint32_t speed_law) {
  mc_params_t p = table_of(f, overrides.get("model_r_scale"), overrides.get("model_l_scale"),
                           overrides.get("model_flux_scale"));
  // The gains the user set (a value other than the derived default): given
  // to the drive, the others derived from them by the C.
  const mc_params_eff_t d = files_params_eff(f);
  for (const char* name : kGainNames) {
    const mc_param_info_t& info = row_of(name);
    const double v = overrides.get(name);
    if (v == get_f32(d.p, info)) continue;
    mc_param_value_t raw;
    raw.f = static_cast<float>(v);
    if (mc_param_check_value(&info, raw.u) != MC_PARAM_OK) {
      throw UsageError(std::string("--set ") + name + "=" + num(v) +
                       ": outside the parameter table's range");
    }
    mc_param_set_raw(&p, &info, raw.u);
  }
  p.speed_law = speed_law;
  set_angle_params(overrides, &p);
  (void)resolve_or_refuse(f, p);
  if (!(p.vbus_v < p.vbus_board_max_v)) {  // else MC_PARAMS_ERR_BOARD, unnamed
    const BoardSpec& b = f.board;
    throw UsageError(where(b.at, "vbus_v", b.file) + ": vbus_v " + num(p.vbus_v) +
                     " V is not below the board's bus limit vbus_board_max_v " +
                     num(p.vbus_board_max_v) + " V (at " + where(b.at, "vbus_board_max_v", b.file) +
                     "): the drive's trip and braking thresholds lie between the two");
  }
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
  const mc_params_eff_t e = resolve_params(p);
  record_files(f, s);
  for (const GainField& g : kGainFields) s.set(std::string("gain.") + g.name, e.g.*(g.field));
  s.set("gain.model_r_scale", p.r_ohm / f.motor.r_ohm);
  s.set("gain.model_l_scale", p.ld_h / f.motor.ld_h);
  s.set("gain.model_flux_scale", f.motor.flux_wb > 0 ? p.flux_wb / f.motor.flux_wb : 1.0);
  for (const char* name : kGainNames) {
    s.set(std::string("param.") + name, get_f32(e.p, row_of(name)));
  }
  s.set("param.speed_law", p.speed_law);
  s.set("param.slow_loop_div", p.slow_loop_div);
}

}  // namespace mcsim
