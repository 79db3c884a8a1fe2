// See hall.hpp.
#include "mcsim/hall.hpp"

#include <cmath>
#include <cstddef>

#include "util.hpp"

namespace mcsim {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kTwoPi = 2.0 * kPi;

double wrap_2pi(double x) {
  const double w = std::fmod(x, kTwoPi);
  return (w < 0.0) ? w + kTwoPi : w;
}

}  // namespace

Status HallParams::validate() const {
  if (!detail::all_finite({offset_e_rad, hysteresis_e_rad})) return Status::kNotFinite;
  for (const double e : edge_error_e_rad) {
    if (!std::isfinite(e)) return Status::kNotFinite;
  }
  if (pole_pairs < 1) return Status::kBadPolePairs;
  if (spacing != HallSpacing::k120 && spacing != HallSpacing::k60) return Status::kBadSensor;
  if (hysteresis_e_rad < 0.0) return Status::kBadSensor;
  for (const double e : edge_error_e_rad) {
    if (!(std::fabs(e) + 0.5 * hysteresis_e_rad < kPi / 6.0)) return Status::kBadSensor;
  }
  return Status::kOk;
}

Status HallSensors::configure(const HallParams& p) {
  const Status s = p.validate();
  if (s != Status::kOk) return s;
  p_ = p;
  reset(0.0);
  return Status::kOk;
}

double HallSensors::edge_e_rad(int sensor, bool rising) const {
  const int k = (sensor < 0) ? 0 : (sensor > 2 ? 2 : sensor);
  const double spacing = (p_.spacing == HallSpacing::k60) ? kPi / 3.0 : 2.0 * kPi / 3.0;
  const double phi = p_.offset_e_rad + k * spacing;
  const std::size_t edge = 2U * static_cast<std::size_t>(k) + (rising ? 0U : 1U);
  return wrap_2pi(phi + (rising ? 0.0 : kPi) + p_.edge_error_e_rad[edge]);
}

bool HallSensors::inside(int k, double th_e, bool high, double margin) const {
  const double rise = edge_e_rad(k, true), fall = edge_e_rad(k, false);
  // The region as [start, start + len) with its distance from start.
  const double start = high ? rise : fall;
  const double len = high ? wrap_2pi(fall - rise) : wrap_2pi(rise - fall);
  const double d = wrap_2pi(th_e - start);
  return d >= margin && d < len - margin;
}

void HallSensors::reset(double theta_m_rad) {
  const double th_e = static_cast<double>(p_.pole_pairs) * theta_m_rad;
  for (int k = 0; k < 3; ++k) state_[k] = inside(k, th_e, true, 0.0);
  fault_ = HallFault::kNone;
}

std::uint8_t HallSensors::sample(double theta_m_rad) {
  const double th_e = static_cast<double>(p_.pole_pairs) * theta_m_rad;
  const double m = 0.5 * p_.hysteresis_e_rad;
  std::uint8_t out = 0U;
  for (int k = 0; k < 3; ++k) {
    // Switch only once inside the other region by half the band.
    if (inside(k, th_e, !state_[k], m)) state_[k] = !state_[k];
    bool level = state_[k];
    if (fault_ == HallFault::kAllLow) level = false;
    if (fault_ == HallFault::kAllHigh) level = true;
    if (k == fault_sensor_ && fault_ == HallFault::kStuckLow) level = false;
    if (k == fault_sensor_ && fault_ == HallFault::kStuckHigh) level = true;
    if (level) out = static_cast<std::uint8_t>(out | (1U << static_cast<unsigned>(k)));
  }
  return out;
}

Status HallSensors::set_fault(HallFault f, int sensor) {
  const bool stuck = (f == HallFault::kStuckLow || f == HallFault::kStuckHigh);
  if (stuck && (sensor < 0 || sensor > 2)) return Status::kBadSensor;
  fault_ = f;
  fault_sensor_ = stuck ? sensor : 0;
  return Status::kOk;
}

}  // namespace mcsim
