// libFuzzer target: the `mcsim run --set key=value` parser (mcsim::Params).
// Input: newline-separated key=value pairs. Any input must either parse into
// values inside the declared ranges or throw mcsim::UsageError; anything else
// (a crash, a sanitizer report, another exception, an out-of-range value
// accepted) is a bug.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <vector>

#include "scenario.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::vector<mcsim::ParamSpec> specs = {
      {"iq_step_a", 2.0, "A", "", -10.0, 10.0},
      {"bw_hz", 200.0, "Hz", "", 1.0, 5000.0},
      {"substeps", 4.0, "1", "", 1.0, 64.0},
  };
  std::vector<std::pair<std::string, std::string>> sets;
  std::string text(reinterpret_cast<const char*>(data), size);
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
