#include "drive_setup.hpp"

#include "hal_host/sil_rig.hpp"
extern "C" {
#include "config/mc_gains.h"
#include "config/mc_law_cfg.h"
}

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace mcsim {
namespace {

constexpr double kPi = 3.14159265358979323846;

// The speed PI of every scenario: kp = J wc / kt, zero at wc / 4 (the
// formula lives in firmware/app/config/mc_gains.c, shared with the drive).
void speed_pi(double j_kgm2, double kt_nm_a, double wc_rad_s, float* p_kp, float* p_ki) {
  if (mc_gains_speed_pi(j_kgm2, kt_nm_a, wc_rad_s, p_kp, p_ki) != MC_GAINS_OK) {
    throw UsageError("no speed PI gains: J, kt and the crossover must be positive");
  }
}

std::string num(double v) {
  std::ostringstream os;
  os.precision(4);
  os << v;
  return os.str();
}

// One gain: the derived value, unless the user set another one.
double pick(const Params* p, const char* key, double derived, double dflt) {
  if (p == nullptr) return derived;
  const double v = p->get(key);
  return (v != dflt) ? v : derived;
}

struct Key {
  const char* key;
  double Gains::*field;
  const char* unit;
  const char* help;
};

const Key kKeys[] = {
    {"cur_bw_rad_s", &Gains::cur_bw_rad_s, "rad/s",
     "current-loop bandwidth (kp = L bw, ki = R bw)"},
    {"i_limit_a", &Gains::i_limit_a, "A", "current limit of the drive"},
    {"enc_pll_bw_rad_s", &Gains::enc_pll_bw_rad_s, "rad/s", "encoder tracking-loop bandwidth"},
    {"speed_wc_rad_s", &Gains::speed_wc_rad_s, "rad/s", "sensored speed PI crossover"},
    {"speed_accel_rad_s2", &Gains::speed_accel_rad_s2, "rad/s^2", "speed reference slew rate"},
    {"obs_crit_rad_s", &Gains::obs_crit_rad_s, "rad/s",
     "flux observer critical speed (sets gamma)"},
    {"pll_bw_rad_s", &Gains::pll_bw_rad_s, "rad/s", "observer PLL bandwidth"},
    {"sls_wc_rad_s", &Gains::sls_wc_rad_s, "rad/s", "sensorless speed PI crossover"},
    {"handover_rad_s", &Gains::handover_rad_s, "rad/s", "I-f -> closed-loop hand-over speed"},
    {"if_current_a", &Gains::if_current_a, "A", "I-f start current"},
    {"if_accel_rad_s2", &Gains::if_accel_rad_s2, "rad/s^2", "I-f frequency ramp (mechanical)"},
    {"align_time_s", &Gains::align_time_s, "s", "alignment current ramp"},
    {"pi2d_wn_rad_s", &Gains::pi2d_wn_rad_s, "rad/s", "PI2D triple pole"},
    {"pi2d_a_per_s", &Gains::pi2d_a_per_s, "1/s", "PI2D dirty-derivative pole"},
    {"pos_kp_per_s", &Gains::pos_kp_per_s, "1/s", "position P gain"},
    {"pos_v_max_rad_s", &Gains::pos_v_max_rad_s, "rad/s", "trajectory cruise speed"},
    {"pos_a_max_rad_s2", &Gains::pos_a_max_rad_s2, "rad/s^2", "trajectory acceleration"},
    {"pos_d_max_rad_s2", &Gains::pos_d_max_rad_s2, "rad/s^2", "trajectory deceleration"},
    {"pos_filter_bw_rad_s", &Gains::pos_filter_bw_rad_s, "rad/s", "input filter bandwidth"},
    {"stop_decel_rad_s2", &Gains::stop_decel_rad_s2, "rad/s^2", "controlled-stop deceleration"},
    {"model_r_scale", &Gains::model_r_scale, "1", "the drive's R / the motor's (model error)"},
    {"model_l_scale", &Gains::model_l_scale, "1", "the drive's Ld, Lq / the motor's (model error)"},
    {"model_flux_scale", &Gains::model_flux_scale, "1",
     "the drive's flux / the motor's (model error)"},
};

// The motor and board values the firmware's gain formulas take.
mc_gains_motor_t gains_motor(const MotorFiles& f) {
  const MotorSpec& m = f.motor;
  const BoardSpec& b = f.board;
  mc_gains_motor_t gm{};
  gm.r_ohm = m.r_ohm;
  gm.ld_h = m.ld_h;
  gm.lq_h = m.lq_h;
  gm.flux_wb = m.flux_wb;
  gm.pole_pairs = m.pole_pairs;
  gm.j_kgm2 = m.j_kgm2;
  gm.b_nm_s_rad = m.b_nm_s_rad;
  gm.i_max_a = m.i_max_a;
  gm.i_rated_a = m.i_rated_a;
  gm.speed_max_rad_s = m.speed_max_rad_s;
  gm.speed_rated_rad_s = m.speed_rated_rad_s;
  gm.vbus_v = b.vbus_v;
  gm.pwm_hz = b.pwm_hz;
  gm.dead_time_s = b.dead_time_s;
  gm.i_sense_max_a = b.i_sense_max_a;
  gm.delay_periods = b.delay_periods;
  return gm;
}

// Where a file key's value came from ("FILE:LINE", or the --set that
// replaced it); the file itself for a key left at its default.
std::string where(const KeySources& at, const std::string& key, const std::string& file) {
  const auto it = at.find(key);
  return it != at.end() ? it->second : file;
}

// The refusals of mc_gains_derive's errors: no gains make these safe. Each
// names the value its remedy changes (file and line, or its --set) and the
// other side's values it was weighed against.
void refuse_unsafe(const MotorFiles& f, uint32_t err, double i_limit_a) {
  const MotorSpec& m = f.motor;
  const BoardSpec& b = f.board;
  const double T = 1.0 / b.pwm_hz;
  const double l_min = std::min(m.ld_h, m.lq_h);
  const std::string l_at = where(m.at, m.ld_h <= m.lq_h ? "ld_h" : "lq_h", m.file);
  if ((err & MC_GAINS_ERR_VALUE) != 0u) {
    throw UsageError(m.file + ", " + b.file + ": no gains: a motor or board value is not positive");
  }
  if ((err & MC_GAINS_ERR_LR_SHORT) != 0u) {
    throw UsageError(where(b.at, "pwm_hz", b.file) +
                     ": no safe gains: the electrical time constant L/R = " + num(l_min / m.r_ohm) +
                     " s (L at " + l_at + ", r_ohm at " + where(m.at, "r_ohm", m.file) +
                     ") is shorter than two PWM periods (" + num(2 * T) + " s at " + num(b.pwm_hz) +
                     " Hz): raise pwm_hz");
  }
  if ((err & MC_GAINS_ERR_RIPPLE) != 0u) {
    throw UsageError(where(b.at, "pwm_hz", b.file) +
                     ": no safe gains: the PWM current ripple vbus T / (4 L) = " +
                     num(b.vbus_v * T / (4.0 * l_min)) + " A (peak to peak; L at " + l_at +
                     ") exceeds i_max_a (" + num(m.i_max_a) + " A at " +
                     where(m.at, "i_max_a", m.file) + "): raise pwm_hz or lower vbus_v (at " +
                     where(b.at, "vbus_v", b.file) + ")");
  }
  if ((err & MC_GAINS_ERR_I_LIMIT) != 0u) {
    throw UsageError(where(b.at, "i_sense_max_a", b.file) + ": no safe gains: the usable current " +
                     num(i_limit_a) +
                     " A (sensor range / 1.25, bus through R) is below 10 % of i_max_a (" +
                     num(m.i_max_a) + " A at " + where(m.at, "i_max_a", m.file) + ")");
  }
  if ((err & MC_GAINS_ERR_SENSE) != 0u) {
    throw UsageError(where(b.at, "i_sense_max_a", b.file) + ": i_limit_a " + num(i_limit_a) +
                     " A leaves no margin to the current sensor's full scale " +
                     num(b.i_sense_max_a) + " A");
  }
  if ((err & MC_GAINS_ERR_SPEED_LIMIT) != 0u) {
    throw UsageError(where(b.at, "vbus_v", b.file) + ": no safe gains: the bus (" + num(b.vbus_v) +
                     " V) cannot drive rated current (" + num(m.i_rated_a) +
                     " A, the motor's R and flux: " + m.file + ") at any speed");
  }
}

// The settable gains, in the firmware's struct and in Gains (one table).
struct Pair {
  double mc_gains_t::*c;
  double Gains::*g;
};
const Pair kPairs[] = {
    {&mc_gains_t::cur_bw_rad_s, &Gains::cur_bw_rad_s},
    {&mc_gains_t::i_limit_a, &Gains::i_limit_a},
    {&mc_gains_t::enc_pll_bw_rad_s, &Gains::enc_pll_bw_rad_s},
    {&mc_gains_t::speed_wc_rad_s, &Gains::speed_wc_rad_s},
    {&mc_gains_t::speed_accel_rad_s2, &Gains::speed_accel_rad_s2},
    {&mc_gains_t::obs_crit_rad_s, &Gains::obs_crit_rad_s},
    {&mc_gains_t::pll_bw_rad_s, &Gains::pll_bw_rad_s},
    {&mc_gains_t::sls_wc_rad_s, &Gains::sls_wc_rad_s},
    {&mc_gains_t::handover_rad_s, &Gains::handover_rad_s},
    {&mc_gains_t::if_current_a, &Gains::if_current_a},
    {&mc_gains_t::if_accel_rad_s2, &Gains::if_accel_rad_s2},
    {&mc_gains_t::align_time_s, &Gains::align_time_s},
    {&mc_gains_t::pi2d_wn_rad_s, &Gains::pi2d_wn_rad_s},
    {&mc_gains_t::pi2d_a_per_s, &Gains::pi2d_a_per_s},
    {&mc_gains_t::pos_kp_per_s, &Gains::pos_kp_per_s},
    {&mc_gains_t::pos_v_max_rad_s, &Gains::pos_v_max_rad_s},
    {&mc_gains_t::pos_a_max_rad_s2, &Gains::pos_a_max_rad_s2},
    {&mc_gains_t::pos_d_max_rad_s2, &Gains::pos_d_max_rad_s2},
    {&mc_gains_t::pos_filter_bw_rad_s, &Gains::pos_filter_bw_rad_s},
    {&mc_gains_t::stop_decel_rad_s2, &Gains::stop_decel_rad_s2},
    {&mc_gains_t::kt_nm_a, &Gains::kt_nm_a},
    {&mc_gains_t::v_max_v, &Gains::v_max_v},
    {&mc_gains_t::i_rated_eff_a, &Gains::i_rated_eff_a},
    {&mc_gains_t::torque_rated_nm, &Gains::torque_rated_nm},
    {&mc_gains_t::speed_limit_rad_s, &Gains::speed_limit_rad_s},
    {&mc_gains_t::speed_rated_eff_rad_s, &Gains::speed_rated_eff_rad_s},
    {&mc_gains_t::pi2d_coupling, &Gains::pi2d_coupling},
    {&mc_gains_t::speed_kp_a_s_rad, &Gains::speed_kp_a_s_rad},
    {&mc_gains_t::speed_ki_a_rad, &Gains::speed_ki_a_rad},
};

// The gains from the firmware's formulas (firmware/app/config/mc_gains.c,
// the same the drive derives from its parameter table); a --set value that
// differs from its derived default is taken as given.
Gains derive(const MotorFiles& f, const Params* p, const Gains* dflt) {
  mc_gains_t fix{};
  mc_gains_fix_none(&fix);
  if (p != nullptr && dflt != nullptr) {
    for (const auto& k : kKeys) {
      const double v = p->get(k.key);
      if (v == dflt->*(k.field)) continue;
      for (const auto& q : kPairs) {
        if (q.g == k.field) fix.*(q.c) = v;
      }
    }
  }
  const mc_gains_motor_t gm = gains_motor(f);
  mc_gains_t c{};
  const uint32_t err = mc_gains_derive(&gm, &fix, &c);
  // Refusals first: no gains make these safe.
  refuse_unsafe(f, err, c.i_limit_a);
  Gains g;
  for (const auto& q : kPairs) g.*(q.g) = c.*(q.c);
  g.pi2d_ok = g.pi2d_a_per_s >= 3.0 * g.pi2d_wn_rad_s;
  // Model errors: what the drive believes is the files' motor scaled by
  // these (the plant stays the files'); the gains above are not re-derived,
  // so a run shows the designed loops on a wrong model (MotorRig applies them).
  auto get = [&](const char* key, double derived, double Gains::*field) {
    return pick(p, key, derived, dflt ? dflt->*field : derived);
  };
  g.model_r_scale = get("model_r_scale", 1.0, &Gains::model_r_scale);
  g.model_l_scale = get("model_l_scale", 1.0, &Gains::model_l_scale);
  g.model_flux_scale = get("model_flux_scale", 1.0, &Gains::model_flux_scale);
  return g;
}

}  // namespace

std::vector<ParamSpec> gain_params(const MotorFiles& f) {
  const Gains g = derive(f, nullptr, nullptr);
  std::vector<ParamSpec> v;
  for (const auto& k : kKeys) {
    const double d = g.*(k.field);
    v.push_back({k.key, d, k.unit, std::string(k.help) + " (derived from the motor and board)",
                 d > 0 ? d * 1e-3 : 0.0, d > 0 ? d * 1e3 : 1.0});
  }
  return v;
}

Gains derive_gains(const MotorFiles& f, const Params* p) {
  const Gains d = derive(f, nullptr, nullptr);
  return p ? derive(f, p, &d) : d;
}

void record_setup(const MotorFiles& f, const Gains& g, Summary& s) {
  record_files(f, s);
  for (const auto& k : kKeys) s.set(std::string("gain.") + k.key, g.*(k.field));
  s.set("gain.i_rated_eff_a", g.i_rated_eff_a);
  s.set("gain.torque_rated_nm", g.torque_rated_nm);
  s.set("gain.speed_limit_rad_s", g.speed_limit_rad_s);
  s.set("gain.speed_rated_eff_rad_s", g.speed_rated_eff_rad_s);
  s.set("gain.kt_nm_a", g.kt_nm_a);
  s.set("gain.v_max_v", g.v_max_v);
}

void record_files(const MotorFiles& f, Summary& s) {
  const MotorSpec& m = f.motor;
  const BoardSpec& b = f.board;
  s.set_text("motor", m.name);
  s.set_text("motor_file", m.file);
  s.set_text("board", b.name);
  s.set_text("board_file", b.file);
  s.set("motor.r_ohm", m.r_ohm);
  s.set("motor.ld_h", m.ld_h);
  s.set("motor.lq_h", m.lq_h);
  s.set("motor.flux_wb", m.flux_wb);
  s.set("motor.pole_pairs", m.pole_pairs);
  s.set("motor.j_kgm2", m.j_kgm2);
  s.set("motor.b_nm_s_rad", m.b_nm_s_rad);
  s.set("motor.i_max_a", m.i_max_a);
  s.set("motor.i_rated_a", m.i_rated_a);
  s.set("motor.speed_max_rad_s", m.speed_max_rad_s);
  s.set("motor.speed_rated_rad_s", m.speed_rated_rad_s);
  s.set("board.vbus_v", b.vbus_v);
  s.set("board.pwm_hz", b.pwm_hz);
  s.set("board.dead_time_s", b.dead_time_s);
  s.set("board.current_sensors", b.current_sensors);
  s.set("board.i_sense_max_a", b.i_sense_max_a);
  s.set("board.adc_bits", b.adc_bits);
  s.set("board.encoder_cpr", static_cast<double>(b.encoder_cpr));
  s.set("board.delay_periods", b.delay_periods);
  if (b.dc_link_c_f > 0.0) {
    s.set("board.dc_link_c_f", b.dc_link_c_f);
    s.set("board.source_r_ohm", b.source_r_ohm);
    s.set("board.source_sink", b.source_sink ? 1.0 : 0.0);
    s.set("board.brake_r_ohm", b.brake_r_ohm);
  }
}

hal_host::PmsmBoardConfig build_board_cfg(const MotorFiles& f) {
  const MotorSpec& m = f.motor;
  const BoardSpec& b = f.board;
  hal_host::PmsmBoardConfig bc;
  bc.motor.R_ohm = m.r_ohm;
  bc.motor.Ld_h = m.ld_h;
  bc.motor.Lq_h = m.lq_h;
  bc.motor.flux_wb = m.flux_wb;
  bc.motor.pole_pairs = m.pole_pairs;
  bc.motor.J_kgm2 = m.j_kgm2;
  bc.motor.B_nms_rad = m.b_nm_s_rad;
  bc.motor.cogging.slots = m.slots;  // the plant's cogging (none by default)
  bc.motor.cogging.amplitude_nm = m.cogging_nm;
  bc.motor.cogging.phase_rad = m.cogging_phase_rad;
  for (int k = 0; k < mcsim::CoggingParams::kMaxHarmonics; ++k) {
    bc.motor.cogging.harmonic_nm[k] = m.cogging_h_nm[k];
    bc.motor.cogging.harmonic_phase_rad[k] = m.cogging_h_phase_rad[k];
  }
  bc.inverter.t_pwm_s = 1.0 / b.pwm_hz;
  bc.inverter.t_dead_s = b.dead_time_s;
  bc.inverter.i_dead_band_a = std::max(1e-3, 0.01 * m.i_rated_a);
  bc.vbus_v = b.vbus_v;
  bc.current_sensor.full_scale_a = b.adc_full_scale_a();
  bc.current_sensor.bits = b.adc_bits;
  bc.vbus_sensor.full_scale_v = b.vbus_full_scale_v();
  bc.vbus_sensor.bits = b.adc_bits;
  // No encoder (encoder_cpr = 0): the board model still has one, which no
  // scenario reads (the sensored scenarios refuse such a board).
  bc.encoder.counts_per_rev = b.encoder_cpr > 0 ? static_cast<int>(b.encoder_cpr) : 4096;
  bc.substeps = 4;
  bc.three_shunts = (b.current_sensors == 3);
  bc.delay_periods = b.delay_periods;
  if (b.dc_link_c_f > 0.0) {
    bc.dc_link_enabled = true;
    bc.dc_link.source_v = b.vbus_v;
    bc.dc_link.source_r_ohm = b.source_r_ohm;
    bc.dc_link.source_sink = b.source_sink;
    bc.dc_link.c_f = b.dc_link_c_f;
    bc.dc_link.brake_r_ohm = b.brake_r_ohm;
  }
  return bc;
}

mc_drive_cfg_t build_drive_cfg(const MotorFiles& f, const Gains& g) {
  const MotorSpec& m = f.motor;
  const BoardSpec& b = f.board;
  mc_drive_cfg_t dc{};
  float kp = 0, ki = 0;
  if (mc_foc_f32_gains_from_bandwidth(static_cast<float>(m.r_ohm), static_cast<float>(m.ld_h),
                                      static_cast<float>(g.cur_bw_rad_s), &kp, &ki) != 0u) {
    throw UsageError("current-loop bandwidth rejected by the firmware");
  }
  dc.foc.kp_d_v_per_a = kp;
  dc.foc.ki_d_v_per_as = ki;
  if (mc_foc_f32_gains_from_bandwidth(static_cast<float>(m.r_ohm), static_cast<float>(m.lq_h),
                                      static_cast<float>(g.cur_bw_rad_s), &kp, &ki) != 0u) {
    throw UsageError("current-loop bandwidth rejected by the firmware");
  }
  dc.foc.kp_q_v_per_a = kp;
  dc.foc.ki_q_v_per_as = ki;
  dc.foc.r_ohm = static_cast<float>(m.r_ohm);
  dc.foc.ld_h = static_cast<float>(m.ld_h);
  dc.foc.lq_h = static_cast<float>(m.lq_h);
  dc.foc.flux_wb = static_cast<float>(m.flux_wb);
  dc.foc.dt_s = static_cast<float>(1.0 / b.pwm_hz);
  dc.foc.aw = MC_PI_AW_CLAMP;
  dc.foc.limit_mode = MC_SVPWM_LIMIT_CIRCLE;
  dc.foc.v_limit_ratio = 0.95f;
  dc.foc.v_abs_max_v = static_cast<float>(1.5 * b.vbus_v);
  dc.foc.decouple = true;
  dc.pole_pairs = static_cast<uint32_t>(m.pole_pairs);
  dc.speed_pll_bw_rad_s = static_cast<float>(g.enc_pll_bw_rad_s);
  // Slow loop (supervision) at about 1 kHz.
  dc.slow_loop_div = static_cast<uint32_t>(std::max(1.0, std::round(b.pwm_hz / 1000.0)));
  // References up to the limit (the sensorless law's I-f vector may reach
  // 1.25 iq: 1.5x), the trip at 1.6x the limit inside the sensor's range.
  dc.i_max_a = static_cast<float>(g.i_limit_a);
  dc.i_trip_a = static_cast<float>(std::min(1.6 * g.i_limit_a, 0.98 * b.i_sense_max_a));
  dc.vbus_min_v = static_cast<float>(0.5 * b.vbus_v);
  dc.vbus_max_v = static_cast<float>(1.5 * b.vbus_v);
  // Braking (mc_drive.h): the chopper from 1.1 to 1.2 vbus, then the regen
  // current limit from 1.25 to 1.4 vbus, below the 1.5 vbus trip. On a
  // stiff bus neither is ever reached.
  dc.brake_on_v = static_cast<float>(1.1 * b.vbus_v);
  dc.brake_full_v = static_cast<float>(1.2 * b.vbus_v);
  dc.vbus_regen_start_v = static_cast<float>(1.25 * b.vbus_v);
  dc.vbus_regen_end_v = static_cast<float>(1.4 * b.vbus_v);
  // Braking in the windings when the bus is full: up to the current limit,
  // at most half the current that would cancel the magnet flux.
  dc.regen_id_a = static_cast<float>(std::min(g.i_limit_a, 0.5 * m.flux_wb / m.ld_h));
  dc.omega_max_rad_s = static_cast<float>(1.5 * m.speed_max_rad_s);
  dc.temp_max_c = 100.0f;
  dc.stall_current_frac = 0.0f;  // stall check off: a locked rotor is a test case here
  dc.stall_speed_rad_s = 0.0f;
  dc.stall_time_s = 0.0f;
  // Three shunts: sum within 3 % of the sensor range (a few LSB of rounding).
  dc.i_unbalance_max_a = b.current_sensors == 3 ? static_cast<float>(0.03 * b.i_sense_max_a) : 0.0f;
  // Controlled stop: the speed PI's kp, the feed-forward J decel / kt;
  // rest below 0.2 % of the rated speed. Warnings off (no thermal model).
  dc.stop_decel_rad_s2 = static_cast<float>(g.stop_decel_rad_s2);
  dc.speed_accel_rad_s2 = static_cast<float>(g.speed_accel_rad_s2);
  dc.stop_rest_rad_s = static_cast<float>(0.002 * g.speed_rated_eff_rad_s);
  {
    float stop_ki_unused = 0.0f;
    speed_pi(m.j_kgm2, g.kt_nm_a, g.speed_wc_rad_s, &dc.stop_kp_a_s_rad, &stop_ki_unused);
  }
  dc.stop_iq_ff_a =
      static_cast<float>(std::min(g.i_limit_a, m.j_kgm2 * g.stop_decel_rad_s2 / g.kt_nm_a));
  return dc;
}

mc_fw_f32_cfg_t build_fw_cfg(const MotorFiles& f, const Gains& g) {
  const MotorSpec& m = f.motor;
  mc_fw_f32_cfg_t c{};
  c.ld_h = static_cast<float>(m.ld_h);
  c.lq_h = static_cast<float>(m.lq_h);
  c.flux_wb = static_cast<float>(m.flux_wb);
  c.i_max_a = static_cast<float>(g.i_limit_a);
  c.v_margin = 0.9f;
  c.k_demag = 0.9f;
  c.ki_fw_a_per_vs =
      static_cast<float>(g.cur_bw_rad_s / (10.0 * m.pole_pairs * m.speed_max_rad_s * m.ld_h));
  c.dt_s = static_cast<float>(1.0 / f.board.pwm_hz);
  return c;
}

namespace {
mc_gains_t to_c(const Gains& g) {
  mc_gains_t c{};
  for (const auto& q : kPairs) c.*(q.c) = g.*(q.g);
  return c;
}
}  // namespace

// The laws' configurations: firmware/app/config/mc_law_cfg.c, the same the
// drive builds from its parameter table.
mc_ctrl_sls_cfg_t build_sensorless_cfg(const MotorFiles& f, const Gains& g) {
  const mc_gains_motor_t gm = gains_motor(f);
  const mc_gains_t c = to_c(g);
  mc_ctrl_sls_cfg_t sc{};
  mc_law_sls_cfg(&gm, &c, &sc);
  return sc;
}

mc_ctrl_pi2d_cfg_t build_pi2d_cfg(const MotorFiles& f, const Gains& g) {
  const mc_gains_motor_t gm = gains_motor(f);
  const mc_gains_t c = to_c(g);
  mc_ctrl_pi2d_cfg_t cc{};
  (void)mc_law_pi2d_cfg(&gm, &c, &cc);  // its refusals: MotorRig's messages
  return cc;
}

mc_ctrl_pos_cfg_t build_position_cfg(const MotorFiles& f, const Gains& g) {
  const mc_gains_motor_t gm = gains_motor(f);
  const mc_gains_t c = to_c(g);
  mc_ctrl_pos_cfg_t pc{};
  mc_law_pos_cfg(&gm, &c, &pc);
  return pc;
}

// ------------------------------------------------------------------ rig
MotorRig::MotorRig(const MotorFiles& f, const Gains& g, RigOptions o)
    : f_(f), fd_(f), g_(g), o_(std::move(o)) {
  if (o_.drive_motor != nullptr) fd_.motor = *o_.drive_motor;
  fd_.motor.r_ohm *= g.model_r_scale;
  fd_.motor.ld_h *= g.model_l_scale;
  fd_.motor.lq_h *= g.model_l_scale;
  fd_.motor.flux_wb *= g.model_flux_scale;
  T_ = 1.0 / f.board.pwm_hz;
  if (o_.law != Law::kSensorless && f.board.encoder_cpr == 0) {
    throw UsageError(f.board.file +
                     ": this scenario needs an encoder (encoder_cpr = 0 here); "
                     "use sensorless-speed-step");
  }
  hal_host::PmsmBoardConfig bc = build_board_cfg(f);
  if (o_.load_nm) {
    bc.motor.load.kind = LoadKind::kFunction;
    bc.motor.load.fn = [](double t, double, double, const void* ctx) {
      return (*static_cast<const std::function<double(double)>*>(ctx))(t);
    };
    bc.motor.load.fn_ctx = &o_.load_nm;
  }
  if (o_.board_hook) o_.board_hook(bc);
  board_ = std::make_unique<hal_host::PmsmBoard>(bc);
  if ((o_.law == Law::kSensorless || o_.law == Law::kPi2d) &&
      std::abs(f.motor.ld_h - f.motor.lq_h) > 0.05 * std::max(f.motor.ld_h, f.motor.lq_h)) {
    throw UsageError(f.motor.file +
                     ": ld_h and lq_h differ by more than 5 %: the sensorless "
                     "and PI^2D laws assume a non-salient machine (surface magnets)");
  }
  if (o_.board_built_hook) o_.board_built_hook(*board_);
  dcfg_ = build_drive_cfg(fd_, g);
  if (o_.fw) {
    dcfg_.fw_enable = true;
    dcfg_.fw = build_fw_cfg(fd_, g);
  }
  if (o_.drive_hook) o_.drive_hook(dcfg_);
  if (o_.law == Law::kSensorless) {
    dcfg_.stall_current_frac = 0.0f;
    // the law's duty-side dead-time correction is the drive's current loop's
    const mc_ctrl_sls_cfg_t sc = build_sensorless_cfg(fd_, g);
    dcfg_.dead_time_comp = sc.dead_comp_duty && sc.dead_time_s > 0.0f;
    dcfg_.dead_time_s = sc.dead_time_s;
    dcfg_.dead_band_a = sc.dead_band_a;
  }
  const uint32_t derr = mc_drive_init(&drive_, &dcfg_, board_->hal());
  if (derr != MC_DRIVE_CFG_OK) {
    throw UsageError(
        "the drive refused the configuration built from the files: MC_DRIVE_CFG "
        "bits " +
        std::to_string(derr));
  }
  switch (o_.law) {
    case Law::kCurrent:
      break;
    case Law::kSpeedPi: {
      mc_pi_f32_cfg_t pc{};
      const double wc = g.speed_wc_rad_s;
      speed_pi(fd_.motor.j_kgm2, g.kt_nm_a, wc, &pc.kp, &pc.ki_per_s);
      pc.dt_s = static_cast<float>(T_);
      pc.out_min = static_cast<float>(-g.i_limit_a);
      pc.out_max = static_cast<float>(g.i_limit_a);
      pc.aw = MC_PI_AW_CLAMP;
      if (mc_pi_f32_init(&spi_, &pc) != 0u) throw UsageError("speed PI gains rejected");
      break;
    }
    case Law::kPi2d: {
      if (!g.pi2d_ok) {
        throw UsageError("PI2D refuses this motor: its current loop (cur_bw " +
                         num(g.cur_bw_rad_s) +
                         " rad/s) is too slow for kt/J = " + num(g.kt_nm_a / fd_.motor.j_kgm2) +
                         ": the position filter would have "
                         "to be slower than the speed loop (use law=pi)");
      }
      if (g.pi2d_coupling > 300.0) {
        throw UsageError(
            "PI2D refuses this motor: the back-EMF couples the speed error into "
            "the q current faster than the law's proportional current loop "
            "separates them: kt ke / (J L k2) = " +
            num(g.pi2d_coupling) +
            " rad/s > 300 (an empirical bound: the gimbal-class motor "
            "limit-cycles to over-current above it; use law=pi)");
      }
      const mc_ctrl_pi2d_cfg_t cc = build_pi2d_cfg(fd_, g);
      const uint32_t e = mc_ctrl_pi2d_init(&pi2d_, &cc);
      if (e != 0u) {
        mc_pi2d_f32_t probe{};
        const uint32_t le = mc_pi2d_f32_init(&probe, &cc.law);
        throw UsageError(std::string("PI2D refuses this motor: ") +
                         ((le & MC_PI2D_ERR_KI_EPS)     ? "the proof's ki (L/R)^2 < eps fails"
                          : (le & MC_PI2D_ERR_KP_PRIME) ? "kp' = kp - ki/eps <= 0"
                                                        : "its configuration is invalid") +
                         " (MC_CTRL_PI2D bits " + std::to_string(e) + ", MC_PI2D bits " +
                         std::to_string(le) + ")");
      }
      if (mc_drive_attach_ctrl(&drive_, mc_ctrl_pi2d_ops(&pi2d_)) != 0) {
        throw std::runtime_error("drive refused the PI2D plug-in");
      }
      break;
    }
    case Law::kPosition: {
      const mc_ctrl_pos_cfg_t pc = build_position_cfg(f, g);
      const uint32_t e = mc_ctrl_pos_init(&pos_, &pc);
      if (e != 0u) {
        throw UsageError(
            "the position law refuses this motor's configuration: MC_CTRL_POS "
            "bits " +
            std::to_string(e));
      }
      if (mc_drive_attach_ctrl(&drive_, mc_ctrl_pos_ops(&pos_)) != 0) {
        throw std::runtime_error("drive refused the position plug-in");
      }
      break;
    }
    case Law::kSensorless: {
      const mc_ctrl_sls_cfg_t sc = build_sensorless_cfg(fd_, g);
      const uint32_t e = mc_ctrl_sls_init(&sls_, &sc);
      if (e != 0u) {
        throw UsageError(
            "the sensorless law refuses this motor's configuration: MC_CTRL_SLS "
            "bits " +
            std::to_string(e));
      }
      if (mc_drive_attach_ctrl(&drive_, mc_ctrl_sls_ops(&sls_)) != 0) {
        throw std::runtime_error("drive refused the sensorless plug-in");
      }
      break;
    }
  }
  const mc_drive_mode_t mode = (o_.law == Law::kCurrent || o_.law == Law::kSpeedPi)
                                   ? MC_DRIVE_MODE_CURRENT
                                   : MC_DRIVE_MODE_CTRL;
  if (mc_drive_set_mode(&drive_, mode) != 0) throw std::runtime_error("drive refused its mode");
}

void MotorRig::set_speed_ref(double omega_m_rad_s) {
  w_cmd_ = omega_m_rad_s;
  if (o_.law == Law::kSensorless || o_.law == Law::kPi2d) {
    // the drive shapes these laws' reference
    if (mc_drive_set_speed_ref(&drive_, static_cast<float>(omega_m_rad_s)) != 0) {
      throw UsageError("speed reference rejected by the drive");
    }
  }
}

double MotorRig::omega_ref_rad_s() const {
  if (o_.law == Law::kPosition) return pos_.tm.omega_ref_rad_s;
  if (o_.law == Law::kSensorless || o_.law == Law::kPi2d) return drive_.speed_ref_rad_s;
  return w_ref_;
}

void MotorRig::step() {
  hal_host::sil_period(*board_, drive_, [this] { set_references(); });
}

// Runs after the period's sample, before the interrupt (sil_period's
// on_sampled hook): the slewed speed reference and the speed loop.
void MotorRig::set_references() {
  // The drive cut the last braking reference (regen limit): the speed PI's
  // anti-windup works against what was applied.
  if (o_.law == Law::kSpeedPi && drive_.tm.regen_scale < 1.0f) {
    (void)mc_pi_f32_track(&spi_, drive_.tm.iq_ref_a);
  }
  if (o_.law == Law::kSpeedPi) {
    // Reference slewed at speed_accel_rad_s2 (exact: constant acceleration
    // over the period, then clamp at the target).
    const double amax = g_.speed_accel_rad_s2;
    const double err = w_cmd_ - w_ref_;
    a_ref_ = std::abs(err) <= amax * T_ ? err / T_ : std::copysign(amax, err);
    {
      // The drive's encoder PLL speed of the previous step (a speed loop in
      // a lower-priority task sees it one period late).
      float iq = 0.0f;
      (void)mc_pi_f32_step_ff(
          &spi_, static_cast<float>(w_ref_ - drive_.tm.omega_m_rad_s),
          static_cast<float>((fd_.motor.j_kgm2 * a_ref_ + fd_.motor.b_nm_s_rad * w_ref_) /
                             g_.kt_nm_a),
          &iq);
      if (mc_drive_set_current_ref(&drive_, 0.0f, iq) != 0) {
        throw std::runtime_error("iq reference rejected by the drive");
      }
    }
    w_ref_ += a_ref_ * T_;
  }
}

double MotorRig::theta_e_true() const {
  return std::remainder(f_.motor.pole_pairs * board_->rotor_frame_state()(3), 2 * kPi);
}

double MotorRig::theta_e_hat() const {
  return o_.law == Law::kSensorless ? std::remainder(sls_.tm.theta_hat_e_rad, 2 * kPi)
                                    : std::nan("");
}

void MotorRig::dq_refs(double* id, double* iq) const {
  switch (o_.law) {
    case Law::kPi2d:
      *id = pi2d_.tm.id_ref_a;
      *iq = pi2d_.tm.iq_ref_a;
      return;
    case Law::kPosition:
    case Law::kSensorless:
      *id = drive_.tm.id_ref_a;
      *iq = drive_.tm.iq_ref_a;
      return;
    default:
      *id = drive_.id_ref_a;
      *iq = drive_.iq_ref_a;
  }
}

void MotorRig::dq_volts(double* vd, double* vq) const {
  const Eigen::Vector2d& v = board_->v_alpha_beta_applied();
  const double th = theta_e_true(), c = std::cos(th), s = std::sin(th);
  *vd = c * v(0) + s * v(1);
  *vq = -s * v(0) + c * v(1);
}

}  // namespace mcsim
