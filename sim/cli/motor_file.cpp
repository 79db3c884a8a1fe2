#include "motor_file.hpp"

#include <cmath>
#include <map>
#include <set>
#include <sstream>
#include <utility>
#include <toml++/toml.h>

#include "scenario.hpp"

namespace mcsim {
namespace {

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
    seen_.insert(key);
    const toml::node* n = t_.get(key);
    if (n == nullptr) {
      fail(file_, line_of(t_), "[" + name_ + "] is missing the required key '" + key + "'");
    }
    return n;
  }
  const toml::node* maybe(const std::string& key) {
    seen_.insert(key);
    return t_.get(key);
  }

  std::string text(const std::string& key, bool required) {
    const toml::node* n = required ? need(key) : maybe(key);
    if (n == nullptr) return std::string();
    if (!n->is_string()) fail(src(key), line_of(*n), "'" + key + "' must be a string");
    return n->value<std::string>().value_or("");
  }

  // A finite number in [lo, hi] (integers accepted). lo_open: lo excluded.
  double number(const toml::node* n, const std::string& key, double lo, double hi, bool lo_open,
                const std::string& unit) const {
    if (!n->is_number())
      fail(src(key), line_of(*n), "'" + key + "' must be a number (" + unit + ")");
    const double v = n->value<double>().value_or(std::nan(""));
    if (!std::isfinite(v) || v > hi || (lo_open ? v <= lo : v < lo)) {
      std::ostringstream os;
      os << "'" << key << "' = " << v << " " << unit << " is out of range " << (lo_open ? "(" : "[")
         << lo << ", " << hi << "]";
      fail(src(key), line_of(*n), os.str());
    }
    return v;
  }
  double num(const std::string& key, double lo, double hi, bool lo_open, const std::string& unit) {
    return number(need(key), key, lo, hi, lo_open, unit);
  }
  double num_or(const std::string& key, double dflt, double lo, double hi, bool lo_open,
                const std::string& unit) {
    const toml::node* n = maybe(key);
    return n == nullptr ? dflt : number(n, key, lo, hi, lo_open, unit);
  }
  long integer(const toml::node* n, const std::string& key, long lo, long hi) const {
    if (!n->is_integer()) fail(src(key), line_of(*n), "'" + key + "' must be an integer");
    const long v = static_cast<long>(n->value<int64_t>().value_or(0));
    if (v < lo || v > hi) {
      fail(src(key), line_of(*n),
           "'" + key + "' = " + std::to_string(v) + " is out of range [" + std::to_string(lo) +
               ", " + std::to_string(hi) + "]");
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
};

toml::table parse(const std::string& path) {
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

// Top-level keys other than the known tables are refused too.
void check_top(const std::string& path, const toml::table& root) {
  for (const auto& kv : root) {
    const std::string k(kv.first.str());
    if (k != "motor" && k != "board") {
      fail(path, line_of(kv.second),
           "unknown top-level key or table '" + k + "' (expected [motor] and/or [board])");
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
  bool any = m->cogging_nm > 0.0;
  for (int k = 0; k < 3; ++k) {
    const std::string h = "cogging_h" + std::to_string(k + 2);
    m->cogging_h_nm[k] = r.num_or(h + "_nm", 0.0, 0.0, 1.0e3, false, "N m");
    m->cogging_h_phase_rad[k] = r.num_or(h + "_phase_rad", 0.0, -10.0, 10.0, false, "rad");
    any = any || m->cogging_h_nm[k] > 0.0;
  }
  if (any && m->slots == 0) {
    const std::string key = m->cogging_nm > 0.0 ? "cogging_nm" : "cogging_h2_nm";
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
  m.r_ohm = r.num("r_ohm", 1.0e-4, 1.0e3, false, "ohm");
  m.ld_h = r.num("ld_h", 1.0e-7, 10.0, false, "H");
  m.lq_h = r.num("lq_h", 1.0e-7, 10.0, false, "H");
  m.flux_wb = r.num("flux_wb", 1.0e-5, 10.0, false, "Wb");
  m.pole_pairs = static_cast<int>(r.int_req("pole_pairs", 1, 100));
  m.j_kgm2 = r.num("j_kgm2", 1.0e-9, 1.0e3, false, "kg m^2");
  m.b_nm_s_rad = r.num("b_nm_s_rad", 0.0, 1.0e3, false, "N m s/rad");
  m.i_max_a = r.num("i_max_a", 0.0, 1.0e4, true, "A");
  m.speed_max_rad_s = r.num("speed_max_rad_s", 0.0, 1.0e5, true, "rad/s");
  m.i_rated_a = r.num_or("i_rated_a", 0.5 * m.i_max_a, 0.0, m.i_max_a, true, "A (at most i_max_a)");
  m.speed_rated_rad_s = r.num_or("speed_rated_rad_s", 0.8 * m.speed_max_rad_s, 0.0,
                                 m.speed_max_rad_s, true, "rad/s (at most speed_max_rad_s)");
  read_cogging(r, &m);
  if (m.ld_h > 1.05 * m.lq_h) {
    fail(r.src("ld_h"), r.line("ld_h"),
         "ld_h exceeds lq_h by more than 5 %: only surface (Ld = Lq) and interior "
         "(Ld < Lq) magnet machines are modelled");
  }
  r.reject_unknown();
  return m;
}

BoardSpec read_board(const std::string& path, const toml::table& t, const SetSources& sets) {
  TableReader r(path, "board", t, sets);
  BoardSpec b;
  b.file = path;
  b.name = r.text("name", true);
  b.source = r.text("source", false);
  b.vbus_v = r.num("vbus_v", 0.0, 2000.0, true, "V");
  b.pwm_hz = r.num("pwm_hz", 1000.0, 200000.0, false, "Hz");
  b.dead_time_s = r.num("dead_time_s", 0.0, 0.1 / b.pwm_hz, false, "s (at most 10 % of a period)");
  b.current_sensors = static_cast<int>(r.int_req("current_sensors", 2, 3));
  b.i_sense_max_a = r.num("i_sense_max_a", 0.0, 1.0e5, true, "A");
  b.adc_bits = static_cast<int>(r.int_req("adc_bits", 8, 24));
  b.encoder_cpr = r.int_req("encoder_cpr", 0, 1L << 24);
  b.delay_periods = static_cast<int>(r.int_or("delay_periods", 1, 0, 4));
  b.dc_link_c_f = r.num_or("dc_link_c_f", 0.0, 0.0, 10.0, false, "F");
  b.source_r_ohm = r.num_or("source_r_ohm", 0.05, 1.0e-4, 1.0e3, false, "ohm");
  b.source_sink = r.boolean_or("source_sink", false);
  b.brake_r_ohm = r.num_or("brake_r_ohm", 0.0, 0.0, 1.0e4, false, "ohm");
  r.reject_unknown();
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
    try {
      one = toml::parse(key + " = " + kv.second, where);
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

}  // namespace

MotorFiles load_motor_files(const std::string& motor_path, const std::string& board_path,
                            const Overrides& overrides) {
  for (const auto& kv : overrides) {
    if (kv.first.rfind("motor.", 0) != 0 && kv.first.rfind("board.", 0) != 0) {
      throw UsageError("--set " + kv.first + ": file overrides are motor.KEY or board.KEY");
    }
  }
  MotorFiles f;
  toml::table mroot = parse(motor_path);
  check_top(motor_path, mroot);
  toml::table* mt = mroot["motor"].as_table();
  if (mt == nullptr) fail(motor_path, 1, "no [motor] table");
  const SetSources msets = apply_overrides(*mt, "motor", overrides);
  f.motor = read_motor(motor_path, *mt, msets);
  if (board_path.empty()) {
    toml::table* bt = mroot["board"].as_table();
    if (bt == nullptr) {
      fail(motor_path, 1, "no [board] table here and no --board FILE given");
    }
    const SetSources bsets = apply_overrides(*bt, "board", overrides);
    f.board = read_board(motor_path, *bt, bsets);
  } else {
    toml::table broot = parse(board_path);
    check_top(board_path, broot);
    toml::table* bt = broot["board"].as_table();
    if (bt == nullptr) fail(board_path, 1, "no [board] table");
    const SetSources bsets = apply_overrides(*bt, "board", overrides);
    f.board = read_board(board_path, *bt, bsets);
  }
  return f;
}

}  // namespace mcsim
