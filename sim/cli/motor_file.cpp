#include "motor_file.hpp"

#include "board_hall.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>
#include <system_error>
#include <utility>
#include <toml++/toml.h>

#include "board_desc.hpp"
#include "scenario.hpp"
#include "config/mc_params.h"

namespace mcsim {
namespace {

// The firmware's range of one parameter (tools/config/params.toml, through
// its generated table), as doubles.
struct FwRange {
  double lo, hi;
};
FwRange fw_range(uint32_t id) {
  const mc_param_info_t* p = mc_param_find(id, nullptr);
  if (p == nullptr) throw std::logic_error("parameter " + std::to_string(id) + " not in the table");
  if (p->type == MC_PARAM_TYPE_F32) return {p->min.f, p->max.f};
  return {static_cast<double>(p->min.u), static_cast<double>(p->max.u)};
}
const char* const kFwTable = " (the drive's parameter table, tools/config/params.toml)";

// "FILE:LINE: reason"; for a value given on the command line (its source is
// the --set, see apply_overrides) "--set KEY=VALUE: reason".
[[noreturn]] void fail(const std::string& file, long line, const std::string& reason) {
  if (file.rfind("--set ", 0) == 0) throw UsageError(file + ": " + reason);
  throw UsageError(file + ":" + std::to_string(line < 1 ? 1 : line) + ": " + reason);
}

long line_of(const toml::node& n) {
  return static_cast<long>(n.source().begin.line);
}

// Keys of one table replaced on the command line -> that --set.
using SetSources = std::map<std::string, std::string>;

// One table of a file: reads keys, remembers which were read, and rejects
// the rest as unknown.
class TableReader {
 public:
  TableReader(std::string file, std::string table_name, const toml::table& t,
              const SetSources& sets)
      : file_(std::move(file)), name_(std::move(table_name)), t_(t), sets_(sets) {}

  // Where key's value came from: the file, or the --set that replaced it.
  std::string src(const std::string& key) const {
    const auto it = sets_.find(key);
    return it == sets_.end() ? file_ : it->second;
  }

  const toml::node* need(const std::string& key) {
    const toml::node* n = maybe(key);
    if (n == nullptr) {
      fail(file_, line_of(t_), "[" + name_ + "] is missing the required key '" + key + "'");
    }
    return n;
  }
  const toml::node* maybe(const std::string& key) {
    seen_.insert(key);
    const toml::node* n = t_.get(key);
    if (n != nullptr) {
      const auto it = sets_.find(key);
      at_[key] = it == sets_.end() ? file_ + ":" + std::to_string(line_of(*n)) : it->second;
    }
    return n;
  }
  // "FILE:LINE" or "--set ..." of each key read.
  const KeySources& sources() const { return at_; }

  std::string text(const std::string& key, bool required) {
    const toml::node* n = required ? need(key) : maybe(key);
    if (n == nullptr) return std::string();
    if (!n->is_string()) fail(src(key), line_of(*n), "'" + key + "' must be a string");
    return n->value<std::string>().value_or("");
  }

  // A finite number in [lo, hi] (integers accepted). lo_open: lo excluded.
  // why: said after the range (where it comes from).
  double number(const toml::node* n, const std::string& key, double lo, double hi, bool lo_open,
                const std::string& unit, const std::string& why = "") const {
    if (!n->is_number())
      fail(src(key), line_of(*n), "'" + key + "' must be a number (" + unit + ")");
    const double v = n->value<double>().value_or(std::nan(""));
    if (!std::isfinite(v) || v > hi || (lo_open ? v <= lo : v < lo)) {
      std::ostringstream os;
      os << "'" << key << "' = " << v << " " << unit << " is out of range " << (lo_open ? "(" : "[")
         << lo << ", " << hi << "]" << why;
      fail(src(key), line_of(*n), os.str());
    }
    return v;
  }
  // A key the firmware's table holds too: [lo, hi] narrowed to its range.
  // dflt: the value when the key is absent (NaN: required).
  double fw_num(const std::string& key, uint32_t id, double dflt, double lo, double hi,
                bool lo_open, const std::string& unit) {
    const FwRange fw = fw_range(id);
    if (fw.lo > lo || (fw.lo == lo && !lo_open)) {
      lo = fw.lo;
      lo_open = false;
    }
    hi = std::min(hi, fw.hi);
    const toml::node* n = std::isnan(dflt) ? need(key) : maybe(key);
    return n == nullptr ? dflt : number(n, key, lo, hi, lo_open, unit, kFwTable);
  }
  long fw_int(const std::string& key, uint32_t id) {
    const FwRange fw = fw_range(id);
    return integer(need(key), key, static_cast<long>(fw.lo), static_cast<long>(fw.hi), kFwTable);
  }
  double num(const std::string& key, double lo, double hi, bool lo_open, const std::string& unit) {
    return number(need(key), key, lo, hi, lo_open, unit);
  }
  double num_or(const std::string& key, double dflt, double lo, double hi, bool lo_open,
                const std::string& unit) {
    const toml::node* n = maybe(key);
    return n == nullptr ? dflt : number(n, key, lo, hi, lo_open, unit);
  }
  long integer(const toml::node* n, const std::string& key, long lo, long hi,
               const std::string& why = "") const {
    if (!n->is_integer()) fail(src(key), line_of(*n), "'" + key + "' must be an integer");
    const long v = static_cast<long>(n->value<int64_t>().value_or(0));
    if (v < lo || v > hi) {
      fail(src(key), line_of(*n),
           "'" + key + "' = " + std::to_string(v) + " is out of range [" + std::to_string(lo) +
               ", " + std::to_string(hi) + "]" + why);
    }
    return v;
  }
  long int_req(const std::string& key, long lo, long hi) { return integer(need(key), key, lo, hi); }
  long int_or(const std::string& key, long dflt, long lo, long hi) {
    const toml::node* n = maybe(key);
    return n == nullptr ? dflt : integer(n, key, lo, hi);
  }
  bool boolean_or(const std::string& key, bool dflt) {
    const toml::node* n = maybe(key);
    if (n == nullptr) return dflt;
    if (!n->is_boolean()) fail(src(key), line_of(*n), "'" + key + "' must be true or false");
    return n->value<bool>().value_or(dflt);
  }
  long line(const std::string& key) {
    const toml::node* n = t_.get(key);
    return n ? line_of(*n) : line_of(t_);
  }
  void reject_unknown() {
    for (const auto& kv : t_) {
      const std::string k(kv.first.str());
      if (seen_.count(k) == 0u) {
        std::ostringstream msg;
        msg << "unknown key '" << k << "' in [" << name_ << "] (known: ";
        const char* sep = "";
        for (const auto& s : seen_) {
          msg << sep << s;
          sep = ", ";
        }
        msg << ")";
        fail(src(k), line_of(kv.second), msg.str());
      }
    }
  }

 private:
  std::string file_, name_;
  const toml::table& t_;
  const SetSources& sets_;
  std::set<std::string> seen_;
  KeySources at_;
};

// Top-level keys other than the known tables are refused too.
void check_top(const std::string& path, const toml::table& root) {
  for (const auto& kv : root) {
    const std::string k(kv.first.str());
    if (k != "motor" && k != "board" && k != "stepper") {
      fail(path, line_of(kv.second),
           "unknown top-level key or table '" + k +
               "' (expected [motor] or [stepper], and/or [board])");
    }
    if (!kv.second.is_table()) fail(path, line_of(kv.second), "'" + k + "' must be a table");
  }
}

// The cogging keys of [motor] (see motor_file.hpp); a torque without slots
// is refused (its order would be unknown).
void read_cogging(TableReader& r, MotorSpec* m) {
  m->slots = static_cast<int>(r.int_or("slots", 0, 0, 1000));
  m->cogging_nm = r.num_or("cogging_nm", 0.0, 0.0, 1.0e3, false, "N m");
  m->cogging_phase_rad = r.num_or("cogging_phase_rad", 0.0, -10.0, 10.0, false, "rad");
  // the first amplitude given (named in the refusal below)
  std::string key = m->cogging_nm > 0.0 ? "cogging_nm" : "";
  for (int k = 0; k < 3; ++k) {
    const std::string h = "cogging_h" + std::to_string(k + 2);
    m->cogging_h_nm[k] = r.num_or(h + "_nm", 0.0, 0.0, 1.0e3, false, "N m");
    m->cogging_h_phase_rad[k] = r.num_or(h + "_phase_rad", 0.0, -10.0, 10.0, false, "rad");
    if (key.empty() && m->cogging_h_nm[k] > 0.0) key = h + "_nm";
  }
  if (!key.empty() && m->slots == 0) {
    fail(r.src(key), r.line(key),
         "a cogging torque needs 'slots' (its order is lcm(slots, poles))");
  }
}

MotorSpec read_motor(const std::string& path, const toml::table& t, const SetSources& sets) {
  TableReader r(path, "motor", t, sets);
  MotorSpec m;
  m.file = path;
  m.name = r.text("name", true);
  m.source = r.text("source", false);
  const double req = std::nan("");  // fw_num: a required key
  m.r_ohm = r.fw_num("r_ohm", MC_PARAM_ID_R_OHM, req, 1.0e-4, 1.0e3, false, "ohm");
  m.ld_h = r.fw_num("ld_h", MC_PARAM_ID_LD_H, req, 1.0e-7, 10.0, false, "H");
  m.lq_h = r.fw_num("lq_h", MC_PARAM_ID_LQ_H, req, 1.0e-7, 10.0, false, "H");
  m.flux_wb = r.fw_num("flux_wb", MC_PARAM_ID_FLUX_WB, req, 1.0e-5, 10.0, false, "Wb");
  m.pole_pairs = static_cast<int>(r.fw_int("pole_pairs", MC_PARAM_ID_POLE_PAIRS));
  m.j_kgm2 = r.fw_num("j_kgm2", MC_PARAM_ID_J_KGM2, req, 1.0e-9, 1.0e3, false, "kg m^2");
  m.b_nm_s_rad =
      r.fw_num("b_nm_s_rad", MC_PARAM_ID_B_NM_S_RAD, req, 0.0, 1.0e3, false, "N m s/rad");
  m.i_max_a = r.fw_num("i_max_a", MC_PARAM_ID_I_MAX_A, req, 0.0, 1.0e4, true, "A");
  m.speed_max_rad_s =
      r.fw_num("speed_max_rad_s", MC_PARAM_ID_SPEED_MAX_RAD_S, req, 0.0, 1.0e5, true, "rad/s");
  m.i_rated_a = r.fw_num("i_rated_a", MC_PARAM_ID_I_RATED_A, 0.5 * m.i_max_a, 0.0, m.i_max_a, true,
                         "A (at most i_max_a)");
  m.speed_rated_rad_s =
      r.fw_num("speed_rated_rad_s", MC_PARAM_ID_SPEED_RATED_RAD_S, 0.8 * m.speed_max_rad_s, 0.0,
               m.speed_max_rad_s, true, "rad/s (at most speed_max_rad_s)");
  read_cogging(r, &m);
  if (m.ld_h > 1.05 * m.lq_h) {
    fail(r.src("ld_h"), r.line("ld_h"),
         "ld_h exceeds lq_h by more than 5 %: only surface (Ld = Lq) and interior "
         "(Ld < Lq) magnet machines are modelled");
  }
  r.reject_unknown();
  m.at = r.sources();
  return m;
}

// The torque constant of a [stepper] (motor_file.hpp): km_nm_a, or the
// datasheet's holding torque at the rated current with its excitation.
void read_stepper_km(TableReader& r, StepperSpec* m) {
  const toml::node* km = r.maybe("km_nm_a");
  const toml::node* th = r.maybe("holding_torque_nm");
  const toml::node* ex = r.maybe("holding_excitation");
  if ((km == nullptr) == (th == nullptr)) {
    fail(r.src(km != nullptr ? "km_nm_a" : "holding_torque_nm"), r.line("km_nm_a"),
         "[stepper] needs exactly one of 'km_nm_a' and 'holding_torque_nm' (with "
         "'holding_excitation')");
  }
  if (km != nullptr) {
    if (ex != nullptr) {
      fail(r.src("holding_excitation"), line_of(*ex),
           "'holding_excitation' belongs to 'holding_torque_nm', not to 'km_nm_a'");
    }
    m->km_nm_a = r.number(km, "km_nm_a", 0.0, 100.0, true, "N m/A");
    return;
  }
  m->holding_torque_nm = r.number(th, "holding_torque_nm", 0.0, 1.0e3, true, "N m");
  m->holding_excitation = r.text("holding_excitation", false);
  if (ex == nullptr) {
    fail(r.src("holding_torque_nm"), line_of(*th),
         "'holding_torque_nm' needs 'holding_excitation': \"two_phase_on\" (T = sqrt(2) Km "
         "i_rated_a) or \"one_phase_on\" (T = Km i_rated_a)");
  }
  double k = 0.0;
  if (m->holding_excitation == "two_phase_on") {
    k = std::sqrt(2.0);
  } else if (m->holding_excitation == "one_phase_on") {
    k = 1.0;
  } else {
    fail(r.src("holding_excitation"), line_of(*ex),
         "'holding_excitation' = \"" + m->holding_excitation +
             R"(" is not "two_phase_on" or "one_phase_on")");
  }
  m->km_nm_a = m->holding_torque_nm / (k * m->i_rated_a);
}

StepperSpec read_stepper(const std::string& path, const toml::table& t, const SetSources& sets) {
  TableReader r(path, "stepper", t, sets);
  StepperSpec m;
  m.file = path;
  m.name = r.text("name", true);
  m.source = r.text("source", false);
  m.r_ohm = r.num("r_ohm", 0.0, 1.0e3, true, "ohm");
  m.l_h = r.num("l_h", 0.0, 10.0, true, "H");
  m.i_rated_a = r.num("i_rated_a", 0.0, 1.0e3, true, "A");
  m.rotor_teeth = static_cast<int>(r.int_req("rotor_teeth", 1, 1000));
  m.j_kgm2 = r.num("j_kgm2", 0.0, 1.0e3, true, "kg m^2");
  m.detent_nm = r.num("detent_nm", 0.0, 1.0e3, false, "N m");
  m.b_nm_s_rad = r.num_or("b_nm_s_rad", 0.0, 0.0, 1.0e3, false, "N m s/rad");
  read_stepper_km(r, &m);
  if (const toml::node* sa = r.maybe("step_angle_deg"); sa != nullptr) {
    const double deg = r.number(sa, "step_angle_deg", 0.0, 90.0, true, "deg");
    const double want = 90.0 / m.rotor_teeth;
    if (std::abs(deg - want) > 1.0e-3 * want) {
      std::ostringstream os;
      os << "'step_angle_deg' = " << deg << " does not match rotor_teeth = " << m.rotor_teeth
         << " (a full step of a two-phase hybrid stepper is 90 / rotor_teeth = " << want << " deg)";
      fail(r.src("step_angle_deg"), line_of(*sa), os.str());
    }
  }
  r.reject_unknown();
  m.at = r.sources();
  return m;
}

// An absolute SPI encoder (as5047p, ma732): its counts are the chip's (an
// encoder_cpr --set beside it is refused, a file's replaced), its line's
// error rate and the magnet's angle on the shaft.
void read_abs_encoder(TableReader& r, BoardSpec* b, long line) {
  const long cpr = b->encoder == kEncoderAs5047p ? 16384 : 65536;
  if (r.src("encoder_cpr").rfind("--set", 0) == 0 && b->encoder_cpr != cpr) {
    fail(r.src("encoder_cpr"), line,
         "'encoder_cpr' does not apply to an absolute encoder: the '" + b->encoder + "' reads " +
             std::to_string(cpr) + " counts per turn (remove the --set)");
  }
  if (b->encoder_cpr == 0) {
    fail(r.src("encoder"), line,
         "encoder '" + b->encoder + "' on a board without an encoder (encoder_cpr 0)");
  }
  b->encoder_cpr = cpr;
  b->encoder_err_rate =
      r.num_or("encoder_err_rate", 0.0, 0.0, 1.0, false, "per frame (a bit flipped on MISO)");
  b->encoder_mount_rad = r.num_or("encoder_mount_rad", 0.0, -6.283185307179586, 6.283185307179586,
                                  false, "rad (the mechanical angle the chip adds to the shaft's)");
}

// The position sensor (motor_file.hpp, [board] encoder): the types the
// plant and the firmware run today, the others refused by name.
void read_encoder_type(TableReader& r, BoardSpec* b) {
  const std::string type = r.text("encoder", false);
  b->encoder = type.empty() ? kEncoderAbi : type;
  const toml::node* n = r.maybe("encoder");
  const long line = n != nullptr ? line_of(*n) : 1;
  const bool absolute = b->encoder == kEncoderAs5047p || b->encoder == kEncoderMa732;
  if (b->encoder != kEncoderAbi && b->encoder != kEncoderAbiIndex && b->encoder != kEncoderHall &&
      !absolute) {
    fail(r.src("encoder"), line,
         "encoder '" + b->encoder +
             "' is not a sensor type: 'abi' (A/B, no index), 'abi_index' (A/B with an index "
             "mark at encoder_index_rad), 'as5047p', 'ma732' (absolute on SPI), 'hall' (three "
             "Hall sensors)");
  }
  if (b->encoder == kEncoderAbiIndex && b->encoder_cpr == 0) {
    fail(r.src("encoder"), line, "encoder 'abi_index' needs an encoder: encoder_cpr is 0");
  }
  b->encoder_index_rad = r.num_or("encoder_index_rad", 0.0, -6.283185307179586, 6.283185307179586,
                                  false, "rad (mechanical angle of the index mark)");
  if (b->encoder != kEncoderAbiIndex && r.maybe("encoder_index_rad") != nullptr) {
    fail(r.src("encoder_index_rad"), line_of(*r.maybe("encoder_index_rad")),
         "encoder_index_rad: only an 'abi_index' encoder has an index mark");
  }
  for (const char* k : {"encoder_err_rate", "encoder_mount_rad"}) {
    if (const toml::node* x = r.maybe(k); x != nullptr && !absolute) {
      fail(r.src(k), line_of(*x),
           std::string(k) + ": only an absolute encoder ('as5047p', 'ma732') has it");
    }
  }
  // The Hall model's keys (board_hall.hpp checks them together).
  for (const char* k : {"hall_offset_e_rad", "hall_hysteresis_e_rad", "hall_edge_error_e_rad",
                        "hall_fault", "hall_fault_at_s"}) {
    if (b->encoder != kEncoderHall && r.maybe(k) != nullptr) {
      fail(r.src(k), line_of(*r.maybe(k)), std::string(k) + ": only a 'hall' encoder has it");
    }
  }
  if (absolute) {
    read_abs_encoder(r, b, line);
    return;
  }
  b->hall_offset_e_rad = r.num_or("hall_offset_e_rad", 0.0, -6.283185307179586, 6.283185307179586,
                                  false, "rad el. (sensor A's angle)");
  b->hall_hysteresis_e_rad =
      r.num_or("hall_hysteresis_e_rad", 0.0, 0.0, 0.5, false, "rad el. (the full band)");
  b->hall_edge_error_e_rad = r.num_or("hall_edge_error_e_rad", 0.0, -0.4, 0.4, false,
                                      "rad el. (rising edges +e, falling -e)");
  if (r.maybe("hall_fault") != nullptr) b->hall_fault = r.text("hall_fault", false);
  b->hall_fault_at_s = r.num_or("hall_fault_at_s", 0.0, 0.0, 1.0e4, false, "s");
}

BoardSpec read_board(const std::string& path, const toml::table& t, const SetSources& sets) {
  TableReader r(path, "board", t, sets);
  BoardSpec b;
  b.file = path;
  b.name = r.text("name", true);
  b.source = r.text("source", false);
  const double req = std::nan("");  // fw_num: a required key
  b.vbus_v = r.fw_num("vbus_v", MC_PARAM_ID_VBUS_V, req, 0.0, 2000.0, true, "V");
  b.pwm_hz = r.fw_num("pwm_hz", MC_PARAM_ID_PWM_HZ, req, 1000.0, 200000.0, false, "Hz");
  b.dead_time_s = r.fw_num("dead_time_s", MC_PARAM_ID_DEAD_TIME_S, req, 0.0, 0.1 / b.pwm_hz, false,
                           "s (at most 10 % of a period)");
  b.current_sensors = static_cast<int>(r.fw_int("current_sensors", MC_PARAM_ID_CURRENT_SENSORS));
  b.i_sense_max_a =
      r.fw_num("i_sense_max_a", MC_PARAM_ID_I_SENSE_MAX_A, req, 0.0, 1.0e5, true, "A");
  b.adc_bits = static_cast<int>(r.fw_int("adc_bits", MC_PARAM_ID_ADC_BITS));
  // 0: no encoder (mcsim's); else the firmware's range
  const FwRange cpr = fw_range(MC_PARAM_ID_ENCODER_CPR);
  b.encoder_cpr = r.int_req("encoder_cpr", 0, static_cast<long>(cpr.hi));
  if (b.encoder_cpr != 0 && b.encoder_cpr < static_cast<long>(cpr.lo)) {
    fail(r.src("encoder_cpr"), r.line("encoder_cpr"),
         "'encoder_cpr' = " + std::to_string(b.encoder_cpr) +
             " is out of range: 0 (no encoder) or [" + std::to_string(static_cast<long>(cpr.lo)) +
             ", " + std::to_string(static_cast<long>(cpr.hi)) + "]" + kFwTable);
  }
  read_encoder_type(r, &b);
  // 0 when absent: the ranges follow i_sense_max_a and vbus_v (BoardSpec),
  // also when a scenario changes those after the files are read
  b.i_adc_full_scale_a = r.num_or("i_adc_full_scale_a", 0.0, b.i_sense_max_a, 1.0e5, false,
                                  "A (at least i_sense_max_a)");
  b.vbus_sense_max_v = r.num_or("vbus_sense_max_v", 0.0, b.vbus_v, 1.0e4, true, "V (above vbus_v)");
  // above vbus_v: the drive's check (app_params.cpp names both values)
  b.vbus_board_max_v = r.num_or("vbus_board_max_v", 0.0, 0.0, b.vbus_full_scale_v(), true,
                                "V (at most what the bus sensor reads)");
  b.delay_periods = static_cast<int>(r.int_or("delay_periods", 1, 0, 4));
  b.dc_link_c_f = r.num_or("dc_link_c_f", 0.0, 0.0, 10.0, false, "F");
  b.source_r_ohm = r.num_or("source_r_ohm", 0.05, 1.0e-4, 1.0e3, false, "ohm");
  b.source_sink = r.boolean_or("source_sink", false);
  b.brake_r_ohm = r.num_or("brake_r_ohm", 0.0, 0.0, 1.0e4, false, "ohm");
  r.reject_unknown();
  b.at = r.sources();
  return b;
}

// --set motor.KEY=VALUE / board.KEY=VALUE: the value is parsed as TOML and
// replaces (or adds) KEY in that table before the table is read, so it is
// checked by exactly the rules of the file; a refusal names the --set.
SetSources apply_overrides(toml::table& t, const std::string& table, const Overrides& ov) {
  SetSources srcs;
  for (const auto& kv : ov) {
    const std::string prefix = table + ".";
    if (kv.first.compare(0, prefix.size(), prefix) != 0) continue;
    const std::string key = kv.first.substr(prefix.size());
    const std::string where = "--set " + kv.first + "=" + kv.second;
    toml::table one;
    // A name (board.encoder=abi_index, board.hall_fault=all_high) may be
    // given as a bare word.
    const bool bare_name =
        (key == "encoder" || key == "hall_fault") && !kv.second.empty() &&
        kv.second.find_first_not_of(
            "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_") == std::string::npos;
    try {
      one = toml::parse(key + " = " + (bare_name ? "\"" + kv.second + "\"" : kv.second), where);
    } catch (const toml::parse_error& e) {
      throw UsageError(where + ": not a TOML value: " + std::string(e.description()));
    }
    const toml::node* v = one.get(key);
    if (v == nullptr || one.size() != 1u) throw UsageError(where + ": malformed key");
    t.insert_or_assign(key, *v);
    srcs[key] = where;
  }
  return srcs;
}

// A [board] table that names a board description (`description = "odrive36"`
// or a path, relative to the file): nothing else in it, the values are the
// description's.
bool names_description(const std::string& file, const toml::table& bt, std::string* arg) {
  const toml::node* n = bt.get("description");
  if (n == nullptr) return false;
  if (!n->is_string()) fail(file, line_of(*n), "'description' must be a board name or path");
  for (const auto& kv : bt) {
    if (kv.first.str() != "description") {
      fail(file, line_of(kv.second),
           "'" + std::string(kv.first.str()) +
               "' beside 'description': the board's values are its description's "
               "(change one run with --set board.KEY=VALUE)");
    }
  }
  *arg = n->value<std::string>().value_or("");
  if (arg->find('/') != std::string::npos) {
    *arg = (std::filesystem::path(file).parent_path() / *arg).string();
  }
  return true;
}

BoardSpec read_board_table(const std::string& file, toml::table& bt, const Overrides& ov) {
  std::string desc;
  if (names_description(file, bt, &desc)) return load_board_desc(desc, ov);
  const SetSources bsets = apply_overrides(bt, "board", ov);
  return read_board(file, bt, bsets);
}

}  // namespace

toml::table parse_toml_file(const std::string& path) {
  try {
    return toml::parse_file(path);
  } catch (const toml::parse_error& e) {
    const std::string d(e.description());
    if (e.source().begin.line == 0 || d.find("File could not be opened") != std::string::npos) {
      fail(path, 1, "cannot read the file: " + d);
    }
    fail(path, static_cast<long>(e.source().begin.line), "malformed TOML: " + d);
  }
}

BoardSpec load_board_desc(const std::string& arg, const Overrides& overrides) {
  BoardDescTable d = board_desc_table(arg);
  const SetSources sets = apply_overrides(d.board, "board", overrides);
  BoardSpec b = read_board(d.path, d.board, sets);
  for (const auto& kv : d.at) {
    if (sets.count(kv.first) == 0u) b.at[kv.first] = kv.second;
  }
  return b;
}

MotorFiles load_motor_files(const std::string& motor_path, const std::string& board_path,
                            const Overrides& overrides) {
  for (const auto& kv : overrides) {
    if (kv.first.rfind("motor.", 0) != 0 && kv.first.rfind("board.", 0) != 0) {
      throw UsageError("--set " + kv.first + ": file overrides are motor.KEY or board.KEY");
    }
  }
  MotorFiles f;
  toml::table mroot = parse_toml_file(motor_path);
  check_top(motor_path, mroot);
  toml::table* mt = mroot["motor"].as_table();
  toml::table* st = mroot["stepper"].as_table();
  if (mt != nullptr && st != nullptr) {
    fail(motor_path, line_of(*mroot.get("stepper")),
         "both [motor] and [stepper]: a file describes one motor (a PMSM in [motor] or a "
         "two-phase stepper in [stepper])");
  }
  if (mt == nullptr && st == nullptr) fail(motor_path, 1, "no [motor] or [stepper] table");
  if (st != nullptr) {
    f.is_stepper = true;
    const SetSources ssets = apply_overrides(*st, "motor", overrides);
    f.stepper = read_stepper(motor_path, *st, ssets);
  } else {
    const SetSources msets = apply_overrides(*mt, "motor", overrides);
    f.motor = read_motor(motor_path, *mt, msets);
  }
  if (board_path.empty()) {
    toml::table* bt = mroot["board"].as_table();
    if (bt == nullptr) {
      fail(motor_path, 1, "no [board] table here and no --board FILE given");
    }
    f.board = read_board_table(motor_path, *bt, overrides);
  } else if (is_board_description(board_path)) {
    if (const toml::node* other = mroot.get("board"); other != nullptr) {
      fail(motor_path, line_of(*other),
           "a [board] table here and --board " + board_path +
               ": one of them would be ignored (remove this one, or the --board)");
    }
    f.board = load_board_desc(board_path, overrides);
  } else {
    std::error_code ec;  // the same file named twice holds both, as one
    const bool same = std::filesystem::equivalent(motor_path, board_path, ec);
    if (const toml::node* other = mroot.get("board"); other != nullptr && !same) {
      fail(motor_path, line_of(*other),
           "a [board] table here and --board " + board_path +
               ": one of them would be ignored (remove this one, or the --board)");
    }
    toml::table broot = parse_toml_file(board_path);
    check_top(board_path, broot);
    if (const toml::node* other = broot.get("stepper"); other != nullptr && !same) {
      fail(board_path, line_of(*other),
           "a [stepper] table in the --board file would be ignored (the motor is --motor " +
               motor_path + "'s): remove it");
    }
    if (const toml::node* other = broot.get("motor"); other != nullptr && !same) {
      fail(board_path, line_of(*other),
           "a [motor] table in the --board file would be ignored (the motor is --motor " +
               motor_path + "'s): remove it");
    }
    toml::table* bt = broot["board"].as_table();
    if (bt == nullptr) fail(board_path, 1, "no [board] table");
    f.board = read_board_table(board_path, *bt, overrides);
  }
  if (f.is_stepper && f.board.encoder != kEncoderAbi && f.board.encoder != kEncoderAbiIndex) {
    throw UsageError(motor_path +
                     ": a stepper runs with an A/B encoder in the simulator; the "
                     "board's encoder '" +
                     f.board.encoder + "' is not modelled for it");
  }
  check_hall(f);
  return f;
}

}  // namespace mcsim
