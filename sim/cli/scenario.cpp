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
    set_.insert(kv.first);
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

void CsvWriter::commit_as(const std::string& path) {
  if (std::fflush(f_) != 0 || std::ferror(f_)) {
    throw UsageError("write error on '" + tmp_path_ + "'");
  }
  std::fclose(f_);
  f_ = nullptr;
  if (std::rename(tmp_path_.c_str(), path.c_str()) != 0) {
    throw UsageError("cannot rename to '" + path + "': " + std::strerror(errno));
  }
  committed_ = true;
}

double run_duration(RunContext& ctx, double own_s) {
  const double d = ctx.duration_s > 0.0 ? ctx.duration_s : own_s;
  if (!(d > 0.0) || d > kMaxDurationS) {
    std::ostringstream os;
    os << "the run this scenario derives (" << d << " s) is outside (0, " << kMaxDurationS
       << "] s; give a shorter --duration";
    throw UsageError(os.str());
  }
  ctx.summary.set("duration_s", d);
  return d;
}

long step_count(double duration_s, double period_s) {
  const double n = duration_s / period_s;
  if (!std::isfinite(n) || !(duration_s >= 0.0) || !(period_s > 0.0) || n > kMaxSteps) {
    std::ostringstream os;
    os << "a run of " << duration_s << " s in periods of " << period_s << " s needs " << n
       << " periods, more than the " << kMaxSteps << " a run may take";
    throw UsageError(os.str());
  }
  return std::lround(n);
}

static std::string json_number(double v) {
  if (!std::isfinite(v)) return "null";
  std::ostringstream os;
  os.precision(10);
  os << v;
  return os.str();
}

namespace {

// Length of the valid UTF-8 sequence at s[i], or 0 (RFC 3629: no overlong
// forms, no surrogates, at most U+10FFFF).
size_t utf8_len(const std::string& s, size_t i) {
  const auto b = [&](size_t k) { return static_cast<unsigned char>(s[k]); };
  const unsigned char c = b(i);
  size_t n = 0;
  unsigned char lo = 0x80, hi = 0xBF;  // bounds of the second byte
  if (c < 0x80) return 1;
  if (c >= 0xC2 && c <= 0xDF) {
    n = 2;
  } else if (c >= 0xE0 && c <= 0xEF) {
    n = 3;
    if (c == 0xE0) lo = 0xA0;
    if (c == 0xED) hi = 0x9F;
  } else if (c >= 0xF0 && c <= 0xF4) {
    n = 4;
    if (c == 0xF0) lo = 0x90;
    if (c == 0xF4) hi = 0x8F;
  } else {
    return 0;
  }
  if (i + n > s.size() || b(i + 1) < lo || b(i + 1) > hi) return 0;
  for (size_t k = 2; k < n; ++k) {
    if (b(i + k) < 0x80 || b(i + k) > 0xBF) return 0;
  }
  return n;
}

}  // namespace

std::string json_string(const std::string& s) {
  std::string out = "\"";
  for (size_t i = 0; i < s.size();) {
    const unsigned char c = static_cast<unsigned char>(s[i]);
    const size_t n = utf8_len(s, i);
    if (n == 0) {
      out += "\\ufffd";
      ++i;
      continue;
    }
    if (n > 1) {
      out.append(s, i, n);
      i += n;
      continue;
    }
    switch (c) {
      case '"':
        out += "\\\"";
        break;
      case '\\':
        out += "\\\\";
        break;
      case '\b':
        out += "\\b";
        break;
      case '\f':
        out += "\\f";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\r':
        out += "\\r";
        break;
      case '\t':
        out += "\\t";
        break;
      default:
        if (c < 0x20) {
          char buf[8];
          std::snprintf(buf, sizeof buf, "\\u%04x", c);
          out += buf;
        } else {
          out += static_cast<char>(c);
        }
    }
    ++i;
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
