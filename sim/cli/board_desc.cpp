#include "board_desc.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <utility>

#include "scenario.hpp"

#ifndef MCSIM_BOARDS_DIR
#error "MCSIM_BOARDS_DIR: the build names firmware/targets/stm32f405/boards"
#endif

namespace mcsim {
namespace fs = std::filesystem;
namespace {

constexpr double kAdcCounts = 4096.0;  // the STM32F405's 12-bit ADC
constexpr int kAdcBits = 12;
// The drive's pwm_hz range (tools/config/params.toml; mc_boards.py PWM_HZ_MIN/MAX).
constexpr long kPwmHzMin = 5000, kPwmHzMax = 60000;

[[noreturn]] void fail(const std::string& file, long line, const std::string& reason) {
  throw UsageError(file + ":" + std::to_string(line < 1 ? 1 : line) + ": " + reason);
}

long line_of(const toml::node& n) {
  return static_cast<long>(n.source().begin.line);
}

// A board.toml and, for a variant, its base: a key is the variant's when it
// sets it, else the base's (mc_boards.py merge()).
class Desc {
 public:
  struct Layer {
    std::string file;
    toml::table root;
  };
  struct Hit {
    const toml::node* n;
    std::string file;
  };

  explicit Desc(std::vector<Layer> layers) : layers_(std::move(layers)) {}

  const std::string& file() const { return layers_.front().file; }

  Hit find(const std::string& table, const std::string& key) const {
    for (const auto& l : layers_) {
      const toml::table* t = table.empty() ? &l.root : l.root[table].as_table();
      if (t == nullptr) continue;
      if (const toml::node* n = t->get(key)) return {n, l.file};
    }
    return {nullptr, file()};
  }
  static std::string name(const std::string& table, const std::string& key) {
    return table.empty() ? key : "[" + table + "] " + key;
  }
  long table_line(const std::string& table) const {
    for (const auto& l : layers_) {
      if (const toml::node* n = l.root.get(table)) return line_of(*n);
    }
    return 1;
  }
  Hit need(const std::string& table, const std::string& key) const {
    Hit h = find(table, key);
    if (h.n == nullptr) fail(file(), table_line(table), name(table, key) + ": missing");
    return h;
  }
  std::string at(const Hit& h) const { return h.file + ":" + std::to_string(line_of(*h.n)); }

  // A finite number in [lo, hi] (lo excluded when lo_open).
  double number(const std::string& table, const std::string& key, double lo, double hi,
                bool lo_open, const std::string& unit, std::string* where = nullptr) const {
    const Hit h = need(table, key);
    if (!h.n->is_number() || h.n->is_boolean()) {
      fail(h.file, line_of(*h.n), name(table, key) + ": must be a number (" + unit + ")");
    }
    const double v = h.n->value<double>().value_or(std::nan(""));
    if (!std::isfinite(v) || v > hi || (lo_open ? v <= lo : v < lo)) {
      std::ostringstream os;
      os << name(table, key) << ": " << v << " " << unit << " is out of range "
         << (lo_open ? "(" : "[") << lo << ", " << hi << "]";
      fail(h.file, line_of(*h.n), os.str());
    }
    if (where != nullptr) *where = at(h);
    return v;
  }
  long integer(const std::string& table, const std::string& key, long lo, long hi,
               std::string* where = nullptr) const {
    const Hit h = need(table, key);
    if (!h.n->is_integer()) fail(h.file, line_of(*h.n), name(table, key) + ": must be an integer");
    const long v = static_cast<long>(h.n->value<int64_t>().value_or(0));
    if (v < lo || v > hi) {
      fail(h.file, line_of(*h.n),
           name(table, key) + ": " + std::to_string(v) + " is out of range [" + std::to_string(lo) +
               ", " + std::to_string(hi) + "]");
    }
    if (where != nullptr) *where = at(h);
    return v;
  }
  std::string text(const std::string& table, const std::string& key, const std::string& dflt,
                   bool required) const {
    const Hit h = required ? need(table, key) : find(table, key);
    if (h.n == nullptr) return dflt;
    if (!h.n->is_string()) fail(h.file, line_of(*h.n), name(table, key) + ": must be a string");
    return h.n->value<std::string>().value_or(dflt);
  }
  bool boolean(const std::string& table, const std::string& key) const {
    const Hit h = need(table, key);
    if (!h.n->is_boolean()) {
      fail(h.file, line_of(*h.n), name(table, key) + ": must be true or false");
    }
    return h.n->value<bool>().value_or(false);
  }

 private:
  std::vector<Layer> layers_;
};

// The description's layers (variant first) and the folder of its pins.csv.
Desc read_layers(const std::string& path, std::string* pins_dir) {
  std::vector<Desc::Layer> layers;
  layers.push_back({path, parse_toml_file(path)});
  const fs::path dir = fs::path(path).parent_path();
  *pins_dir = dir.string();
  if (const toml::node* base = layers.front().root.get("base")) {
    if (!base->is_string()) fail(path, line_of(*base), "base: must be a board folder name");
    const std::string bname = base->value<std::string>().value_or("");
    const fs::path bdir = dir.parent_path() / bname;
    const std::string bpath = (bdir / "board.toml").string();
    if (!fs::is_regular_file(bpath)) {
      fail(path, line_of(*base), "base: '" + bname + "' is not a board folder beside this one");
    }
    layers.push_back({bpath, parse_toml_file(bpath)});
    if (layers.back().root.get("base") != nullptr) {
      fail(path, line_of(*base), "base: '" + bname + "' is a variant itself");
    }
    if (!fs::is_regular_file(dir / "pins.csv")) *pins_dir = bdir.string();
  }
  return Desc(std::move(layers));
}

// The phases pins.csv measures (rows adc_ia, adc_ib, adc_ic).
int current_sensors(const std::string& pins_dir) {
  const std::string p = (fs::path(pins_dir) / "pins.csv").string();
  std::ifstream in(p);
  if (!in) fail(p, 1, "cannot read the board's pins.csv");
  int n = 0;
  std::string line;
  while (std::getline(in, line)) {
    const std::string sig = line.substr(0, line.find(','));
    n += (sig == "adc_ia" || sig == "adc_ib" || sig == "adc_ic") ? 1 : 0;
  }
  if (n < 2) fail(p, 1, "fewer than two measured phases (adc_ia/adc_ib/adc_ic)");
  return n;
}

// [sense]: the current range, the converter's range and the bus sensor's.
struct Sense {
  double i_sense_max_a, i_adc_full_scale_a, vbus_sense_max_v, vbus_min_v, vbus_max_v;
  std::string at_i, at_vbus, at_vmax;
};

Sense read_sense(const Desc& d) {
  Sense s{};
  const double vref = d.number("sense", "vref_v", 0.0, 3.6, true, "V", &s.at_i);
  const double shunt = d.number("sense", "shunt_ohm", 0.0, 1.0, true, "ohm");
  const double gain = std::fabs(d.number("sense", "amp_gain_v_per_v", -1e4, 1e4, false, "V/V"));
  if (gain == 0.0) {
    fail(d.need("sense", "amp_gain_v_per_v").file, line_of(*d.need("sense", "amp_gain_v_per_v").n),
         "[sense] amp_gain_v_per_v: must be non-zero");
  }
  const double offset =
      d.number("sense", "amp_offset_v", 0.0, vref, true, "V (inside 0 .. vref_v)");
  const long margin = d.integer("sense", "rail_margin_counts", 0, 2047);
  double divider = 0.0;
  if (d.find("sense", "vbus_divider").n != nullptr) {
    divider = d.number("sense", "vbus_divider", 1.0, 1e4, false, "", &s.at_vbus);
  } else {  // a resistor pair: Vbus / Vpin = (top + bottom) / bottom
    const double top = d.number("sense", "vbus_r_top_ohm", 0.0, 1e9, true, "ohm", &s.at_vbus);
    divider = (top + d.number("sense", "vbus_r_bottom_ohm", 0.0, 1e9, true, "ohm")) /
              d.number("sense", "vbus_r_bottom_ohm", 0.0, 1e9, true, "ohm");
  }
  s.vbus_min_v = d.number("sense", "vbus_min_v", 0.0, 1e4, true, "V");
  s.vbus_max_v =
      d.number("sense", "vbus_max_v", s.vbus_min_v, 1e4, true, "V (above vbus_min_v)", &s.at_vmax);
  const double half_v = std::min(offset, vref - offset);
  s.i_sense_max_a = (half_v - static_cast<double>(margin) * vref / kAdcCounts) / (gain * shunt);
  if (!(s.i_sense_max_a > 0.0)) {
    fail(d.file(), d.table_line("sense"), "[sense] rail_margin_counts: leaves no current range");
  }
  s.i_adc_full_scale_a = vref / (2.0 * gain * shunt);
  s.vbus_sense_max_v = vref * divider;
  if (!(s.vbus_max_v < s.vbus_sense_max_v)) {  // the drive trips on what it reads
    const Desc::Hit h = d.need("sense", "vbus_max_v");
    fail(h.file, line_of(*h.n),
         "[sense] vbus_max_v: not below what the bus divider reads (vref_v divider = " +
             std::to_string(s.vbus_sense_max_v) + " V)");
  }
  return s;
}

}  // namespace

std::string boards_dir() {
  return MCSIM_BOARDS_DIR;
}

std::vector<std::string> board_names() {
  std::vector<std::string> out;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(boards_dir(), ec)) {
    if (e.is_directory() && fs::is_regular_file(e.path() / "board.toml")) {
      out.push_back(e.path().filename().string());
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

bool is_board_description(const std::string& arg) {
  const bool has_sep = arg.find('/') != std::string::npos;
  const bool toml_ext = arg.size() >= 5 && arg.compare(arg.size() - 5, 5, ".toml") == 0;
  return (!has_sep && !toml_ext && !arg.empty()) || fs::path(arg).filename() == "board.toml";
}

std::string board_desc_path(const std::string& arg) {
  if (arg.find('/') != std::string::npos || fs::path(arg).filename() == "board.toml") return arg;
  const fs::path p = fs::path(boards_dir()) / arg / "board.toml";
  if (!fs::is_regular_file(p)) {
    std::string names;
    for (const auto& n : board_names()) names += (names.empty() ? "" : ", ") + n;
    throw UsageError("--board " + arg + ": no board of that name (boards: " + names +
                     "; or a path to a board.toml or to a file with a [board] table)");
  }
  return p.string();
}

BoardDescTable board_desc_table(const std::string& arg) {
  BoardDescTable out;
  out.path = board_desc_path(arg);
  std::string pins_dir;
  const Desc d = read_layers(out.path, &pins_dir);
  const std::string name = d.text("", "name", "", true);
  std::string at_pwm, at_dead, at_nominal, at_cpr;
  const long pwm_hz = d.integer("pwm", "frequency_hz", kPwmHzMin, kPwmHzMax, &at_pwm);
  const long dead_ns = d.integer("pwm", "deadtime_ns", 1, 6000, &at_dead);
  if (static_cast<double>(dead_ns) * 1e-9 > 0.1 / static_cast<double>(pwm_hz)) {
    const Desc::Hit h = d.need("pwm", "deadtime_ns");
    fail(h.file, line_of(*h.n), "[pwm] deadtime_ns: above 10 % of a PWM period");
  }
  const Sense s = read_sense(d);
  const double nominal = d.number("supply", "nominal_v", s.vbus_min_v, s.vbus_max_v, false,
                                  "V (inside [sense] vbus_min_v .. vbus_max_v)", &at_nominal);
  // The fitted sensor: the board's encoder key (motor_file.cpp checks it
  // after any --set board.encoder: the types the simulator runs today).
  std::string at_enc = d.file();
  const std::string enc_type = d.text("encoder", "type", "abi", false);
  if (d.find("encoder", "type").n != nullptr) {
    const Desc::Hit h = d.need("encoder", "type");
    at_enc = h.file + ":" + std::to_string(line_of(*h.n));
    if (enc_type != "abi" && enc_type != "as5047p" && enc_type != "ma732" && enc_type != "hall") {
      fail(h.file, line_of(*h.n),
           "[encoder] type: '" + enc_type +
               "' is not available in the simulator yet (the drive and the simulated board "
               "do not read it); the simulator runs 'abi', 'abi_index', 'as5047p', 'ma732' "
               "and 'hall' (--set board.encoder)");
    }
  }
  const long cpr = d.integer("encoder", "counts_per_rev", 1, 65536, &at_cpr);
  const long chip_cpr = enc_type == "as5047p" ? 16384 : (enc_type == "ma732" ? 65536 : cpr);
  if (cpr != chip_cpr) {  // the image's generator refuses it too (tools/boards)
    const Desc::Hit h = d.need("encoder", "counts_per_rev");
    fail(h.file, line_of(*h.n),
         "[encoder] counts_per_rev must be the " + enc_type + "'s " + std::to_string(chip_cpr));
  }
  double brake_r = 0.0;
  std::string at_brake = d.file() + ":" + std::to_string(d.table_line("brake"));
  if (d.boolean("brake", "present")) {
    brake_r = d.number("brake", "r_ohm", 0.0, 1e4, true, "ohm", &at_brake);
  } else if (d.find("brake", "r_ohm").n != nullptr) {
    const Desc::Hit h = d.need("brake", "r_ohm");
    fail(h.file, line_of(*h.n), "[brake] r_ohm: a resistor without a chopper (present = false)");
  }
  toml::table& b = out.board;
  b.insert("name", name);
  b.insert("source", "board description " + out.path);
  b.insert("vbus_v", nominal);
  b.insert("pwm_hz", static_cast<double>(pwm_hz));
  b.insert("dead_time_s", static_cast<double>(dead_ns) * 1e-9);
  b.insert("current_sensors", static_cast<int64_t>(current_sensors(pins_dir)));
  b.insert("i_sense_max_a", s.i_sense_max_a);
  b.insert("i_adc_full_scale_a", s.i_adc_full_scale_a);
  b.insert("adc_bits", static_cast<int64_t>(kAdcBits));
  b.insert("vbus_sense_max_v", s.vbus_sense_max_v);
  b.insert("vbus_board_max_v", s.vbus_max_v);
  b.insert("encoder_cpr", static_cast<int64_t>(cpr));
  b.insert("encoder", enc_type);
  b.insert("brake_r_ohm", brake_r);
  const std::string pins = (fs::path(pins_dir) / "pins.csv").string();
  out.at = {{"name", out.path},
            {"vbus_v", at_nominal},
            {"pwm_hz", at_pwm},
            {"dead_time_s", at_dead},
            {"current_sensors", pins},
            {"i_sense_max_a", s.at_i},
            {"i_adc_full_scale_a", s.at_i},
            {"adc_bits", out.path},
            {"vbus_sense_max_v", s.at_vbus},
            {"vbus_board_max_v", s.at_vmax},
            {"encoder_cpr", at_cpr},
            {"encoder", at_enc},
            {"brake_r_ohm", at_brake}};
  return out;
}

}  // namespace mcsim
