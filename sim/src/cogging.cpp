// See cogging.hpp.
#include "mcsim/cogging.hpp"

#include <numeric>

#include "util.hpp"

namespace mcsim {

Status CoggingParams::validate() const {
  if (!detail::all_finite({amplitude_nm, phase_rad})) return Status::kNotFinite;
  for (int k = 0; k < kMaxHarmonics; ++k) {
    if (!detail::all_finite({harmonic_nm[k], harmonic_phase_rad[k]})) return Status::kNotFinite;
    if (harmonic_nm[k] < 0.0) return Status::kBadCogging;
  }
  if (slots < 0 || slots > 1000 || amplitude_nm < 0.0) return Status::kBadCogging;
  return Status::kOk;
}

bool CoggingParams::active() const {
  bool any = amplitude_nm > 0.0;
  for (const double a : harmonic_nm) any = any || a > 0.0;
  return slots > 0 && any;
}

int cogging_order(int slots, int pole_pairs) {
  if (slots <= 0 || pole_pairs <= 0) return 0;
  return std::lcm(slots, 2 * pole_pairs);
}

Status CoggingTorque::configure(const CoggingParams& c, int pole_pairs) {
  const Status s = c.validate();
  if (s != Status::kOk) return s;
  if (pole_pairs < 1) return Status::kBadPolePairs;
  order_ = cogging_order(c.slots, pole_pairs);
  active_ = c.active();
  for (int k = 0; k < kOrders; ++k) {
    const double a = (k == 0) ? c.amplitude_nm : c.harmonic_nm[k - 1];
    const double ph = (k == 0) ? c.phase_rad : c.harmonic_phase_rad[k - 1];
    a_[k] = a;
    ac_[k] = a * std::cos(ph);
    as_[k] = a * std::sin(ph);
  }
  return Status::kOk;
}

double CoggingTorque::eval(double theta_m_rad, bool potential) const {
  // One sin/cos of N th; the harmonics by the angle-addition recursion
  // (sin, cos of (k+1)x from those of kx and x).
  const double x = static_cast<double>(order_) * theta_m_rad;
  const double s1 = std::sin(x), c1 = std::cos(x);
  double sk = s1, ck = c1, sum = 0.0;
  for (int k = 0; k < kOrders; ++k) {
    if (a_[k] > 0.0) {
      // A sin(kx + phi) = (A cos phi) sin kx + (A sin phi) cos kx;
      // A cos(kx + phi) / (kN) for the potential.
      sum += potential ? (ac_[k] * ck - as_[k] * sk) / (static_cast<double>((k + 1) * order_))
                       : ac_[k] * sk + as_[k] * ck;
    }
    const double s_next = sk * c1 + ck * s1;
    ck = ck * c1 - sk * s1;
    sk = s_next;
  }
  return sum;
}

}  // namespace mcsim
