// libFuzzer target: the `mcsim run --set key=value` parser (mcsim::Params).
// Input: newline-separated key=value pairs. Any input must either parse into
// values inside the declared ranges or throw mcsim::UsageError; anything else
// (a crash, a sanitizer report, another exception, an out-of-range value
// accepted) is a bug. The same bytes, as a name or a path in a summary
// (mcsim::json_string), must give a valid JSON string: no raw control
// character, valid UTF-8, only JSON's escapes.
#include <cctype>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <vector>

#include "scenario.hpp"

namespace {

// A JSON string literal (RFC 8259) in valid UTF-8, or abort.
void check_json_string(const std::string& j) {
  if (j.size() < 2 || j.front() != '"' || j.back() != '"') std::abort();
  for (size_t i = 1; i + 1 < j.size(); ++i) {
    const unsigned char c = static_cast<unsigned char>(j[i]);
    if (c < 0x20 || c == '"') std::abort();
    if (c == '\\') {
      const char e = j[++i];
      if (e == 'u') {
        for (int k = 1; k <= 4; ++k) {
          if (i + k + 1 >= j.size() || std::isxdigit(static_cast<unsigned char>(j[i + k])) == 0) {
            std::abort();
          }
        }
        i += 4;
      } else if (std::string("\"\\/bfnrt").find(e) == std::string::npos) {
        std::abort();
      }
      continue;
    }
    if (c < 0x80) continue;
    size_t n = c >= 0xF0 ? 4 : c >= 0xE0 ? 3 : c >= 0xC2 ? 2 : 0;
    if (n == 0 || c > 0xF4 || i + n > j.size() - 1) std::abort();
    for (size_t k = 1; k < n; ++k) {
      if ((static_cast<unsigned char>(j[i + k]) & 0xC0) != 0x80) std::abort();
    }
    i += n - 1;
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::vector<mcsim::ParamSpec> specs = {
      {"iq_step_a", 2.0, "A", "", -10.0, 10.0},
      {"bw_hz", 200.0, "Hz", "", 1.0, 5000.0},
      {"substeps", 4.0, "1", "", 1.0, 64.0},
  };
  std::vector<std::pair<std::string, std::string>> sets;
  std::string text(reinterpret_cast<const char*>(data), size);
  check_json_string(mcsim::json_string(text));
  size_t pos = 0;
  while (pos <= text.size()) {
    size_t nl = text.find('\n', pos);
    if (nl == std::string::npos) nl = text.size();
    const std::string line = text.substr(pos, nl - pos);
    const size_t eq = line.find('=');
    if (eq != std::string::npos) sets.emplace_back(line.substr(0, eq), line.substr(eq + 1));
    pos = nl + 1;
  }
  try {
    mcsim::Params p(specs, sets);
    for (const auto& s : specs) {
      const double v = p.get(s.key);
      if (!std::isfinite(v) || v < s.min_value || v > s.max_value) std::abort();
    }
  } catch (const mcsim::UsageError&) {
    // refused with a message: the expected outcome for bad input
  }
  return 0;
}
