#include "scenario.hpp"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <sstream>
#include <unistd.h>

namespace mcsim {

std::vector<Scenario>& registry() {
  static std::vector<Scenario> r;
  return r;
}

const Scenario* find_scenario(const std::string& name) {
  for (const auto& s : registry()) {
    if (s.name == name) return &s;
  }
  return nullptr;
}

Params::Params(const std::vector<ParamSpec>& specs,
               const std::vector<std::pair<std::string, std::string>>& sets) {
  for (const auto& p : specs) values_[p.key] = p.default_value;
  for (const auto& kv : sets) {
    const ParamSpec* spec = nullptr;
    for (const auto& p : specs) {
      if (p.key == kv.first) spec = &p;
    }
    if (spec == nullptr) {
      std::string known;
      for (const auto& p : specs) known += (known.empty() ? "" : ", ") + p.key;
      throw UsageError("unknown key '" + kv.first +
                       "' (this scenario takes: " + (known.empty() ? "none" : known) + ")");
    }
    bool named = false;
    double v = 0.0;
    for (const auto& c : spec->choices) {
      if (c.first == kv.second) {
        v = c.second;
        named = true;
      }
    }
    if (!named) {
      const char* s = kv.second.c_str();
      char* end = nullptr;
      errno = 0;
      v = std::strtod(s, &end);
      if (kv.second.empty() || end == s || *end != '\0' || errno == ERANGE || !std::isfinite(v)) {
        std::string names;
        for (const auto& c : spec->choices) names += (names.empty() ? "" : ", ") + c.first;
        throw UsageError("malformed value '" + kv.second + "' for " + kv.first +
                         (names.empty() ? " (a finite number is expected)"
                                        : " (a finite number or one of: " + names + ")"));
      }
    }
    if (v < spec->min_value || v > spec->max_value) {
      std::ostringstream os;
      os << "value " << v << " for " << kv.first << " is out of range [" << spec->min_value << ", "
         << spec->max_value << "] " << spec->unit;
      throw UsageError(os.str());
    }
    values_[kv.first] = v;
  }
}

double Params::get(const std::string& key) const {
  auto it = values_.find(key);
  if (it == values_.end()) throw std::logic_error("scenario read undeclared key " + key);
  return it->second;
}

CsvWriter::CsvWriter(const std::string& final_path)
    : final_path_(final_path), tmp_path_(final_path + ".part") {
  f_ = std::fopen(tmp_path_.c_str(), "w");
  if (f_ == nullptr) {
    throw UsageError("cannot write '" + tmp_path_ + "': " + std::strerror(errno));
  }
}

CsvWriter::~CsvWriter() {
  if (f_ != nullptr) std::fclose(f_);
  if (!committed_) std::remove(tmp_path_.c_str());
}

void CsvWriter::columns(const std::vector<std::string>& names) {
  if (ncols_ != 0) throw std::logic_error("CSV header written twice");
  ncols_ = names.size();
  for (size_t i = 0; i < names.size(); ++i) {
    std::fprintf(f_, "%s%s", i ? "," : "", names[i].c_str());
  }
  std::fputc('\n', f_);
}

void CsvWriter::row(const double* values, size_t n) {
  if (n != ncols_) throw std::logic_error("CSV row width does not match header");
  for (size_t i = 0; i < n; ++i) {
    std::fprintf(f_, "%s%.9g", i ? "," : "", values[i]);
  }
  std::fputc('\n', f_);
  ++rows_;
}

void ColumnSink::columns(const std::vector<std::string>& names) {
  if (have_header_) throw std::logic_error("CSV header written twice");
  have_header_ = true;
  names_ = names;
}

void ColumnSink::row(const double* values, size_t n) {
  if (n != names_.size()) throw std::logic_error("CSV row width does not match header");
  data_.insert(data_.end(), values, values + n);
  ++rows_;
}

void CsvWriter::commit() {
  if (std::fflush(f_) != 0 || std::ferror(f_)) {
    throw UsageError("write error on '" + tmp_path_ + "'");
  }
  std::fclose(f_);
  f_ = nullptr;
  if (std::rename(tmp_path_.c_str(), final_path_.c_str()) != 0) {
    throw UsageError("cannot rename to '" + final_path_ + "': " + std::strerror(errno));
  }
  committed_ = true;
}

static std::string json_number(double v) {
  if (!std::isfinite(v)) return "null";
  std::ostringstream os;
  os.precision(10);
  os << v;
  return os.str();
}

static std::string json_string(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

std::string Summary::to_json() const {
  std::ostringstream os;
  os << "{";
  bool first = true;
  for (const auto& kv : txt_) {
    os << (first ? "\n  " : ",\n  ") << json_string(kv.first) << ": " << json_string(kv.second);
    first = false;
  }
  for (const auto& kv : num_) {
    os << (first ? "\n  " : ",\n  ") << json_string(kv.first) << ": " << json_number(kv.second);
    first = false;
  }
  for (const auto& o : obj_) {
    os << (first ? "\n  " : ",\n  ") << json_string(o.first) << ": {";
    bool f2 = true;
    for (const auto& kv : o.second) {
      os << (f2 ? "" : ", ") << json_string(kv.first) << ": " << json_number(kv.second);
      f2 = false;
    }
    os << "}";
    first = false;
  }
  os << "\n}\n";
  return os.str();
}

void Progress::update(double t_s, double duration_s) {
  if (!enabled_ || duration_s <= 0.0) return;
  int pct = static_cast<int>(100.0 * t_s / duration_s);
  if (pct == last_pct_) return;
  last_pct_ = pct;
  std::fprintf(stderr, "\r  %3d%%  t = %.3f s", pct, t_s);
  std::fflush(stderr);
}

void Progress::done() const {
  if (enabled_ && last_pct_ >= 0) std::fprintf(stderr, "\r\033[K");
}

}  // namespace mcsim
