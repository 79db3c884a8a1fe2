// Internal helpers of mc_sim (not installed, not part of the API).
#ifndef MCSIM_SRC_UTIL_HPP
#define MCSIM_SRC_UTIL_HPP

#include <cmath>
#include <initializer_list>

namespace mcsim {
namespace detail {

inline bool all_finite(std::initializer_list<double> values) {
  for (const double v : values) {
    if (!std::isfinite(v)) {
      return false;
    }
  }
  return true;
}

inline double clamp(double v, double lo, double hi) {
  if (v < lo) {
    return lo;
  }
  if (v > hi) {
    return hi;
  }
  return v;
}

// Unit saturation: v for |v| < 1, sign(v) outside.
inline double sat1(double v) {
  return clamp(v, -1.0, 1.0);
}

}  // namespace detail
}  // namespace mcsim

#endif  // MCSIM_SRC_UTIL_HPP
