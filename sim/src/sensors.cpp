#include "mcsim/sensors.hpp"

#include <cmath>

#include "util.hpp"

namespace mcsim {

namespace {

constexpr double kTwoPi = 6.283185307179586476925286766559;
constexpr double kInvTwoPi = 1.0 / kTwoPi;

// std::floor(num / den + add), bit for bit, without the division (a long
// latency at the head of every SIL period) unless it could matter: the
// product num * inv_den (inv_den = 1 / den rounded) differs from the
// quotient by a few units in the last place, at most 2^-50 (|q| + 1) after
// the addition; when q is farther than tol = 2^-44 (|q| + 1) from every
// integer, both lie strictly between the same two integers. Otherwise (one
// call in ~10^12 for noisy inputs, and NaN or infinity) the division is done.
double floor_of_quotient(double num, double den, double inv_den, double add) {
  const double q = num * inv_den + add;
  const double f = std::floor(q);
  const double tol = 0x1p-44 * (std::fabs(q) + 1.0);
  if (q - f > tol && (f + 1.0) - q > tol) {
    return f;
  }
  return std::floor(num / den + add);
}

// Rounds y / lsb to the nearest code (ties up) and clamps it to [lo, hi];
// a NaN reading gives code 0.
std::int32_t quantise(double y, double lsb, double inv_lsb, std::int32_t lo, std::int32_t hi) {
  const double q = floor_of_quotient(y, lsb, inv_lsb, 0.5);
  if (std::isnan(q)) {
    return 0;
  }
  const double c = detail::clamp(q, static_cast<double>(lo), static_cast<double>(hi));
  return static_cast<std::int32_t>(c);
}

Status validate_adc(double gain_error, double offset, double full_scale, int bits,
                    double noise_rms) {
  if (!detail::all_finite({gain_error, offset, full_scale, noise_rms})) {
    return Status::kNotFinite;
  }
  if (!(1.0 + gain_error > 0.0)) {
    return Status::kBadGain;
  }
  if (!(full_scale > 0.0)) {
    return Status::kBadFullScale;
  }
  if (bits < 1 || bits > 30) {
    return Status::kBadBits;
  }
  if (noise_rms < 0.0) {
    return Status::kNegativeNoise;
  }
  return Status::kOk;
}

// floor(v) as an integer, v already integral (0 if not finite).
std::int64_t to_i64(double v) {
  return std::isfinite(v) ? static_cast<std::int64_t>(v) : 0;
}

// floor(num / 2 pi) as an integer (0 if not finite).
std::int64_t floor_turns(double num) {
  return to_i64(floor_of_quotient(num, kTwoPi, kInvTwoPi, 0.0));
}

}  // namespace

// ---------------------------------------------------------------- GaussianRng

void GaussianRng::reseed(std::uint64_t seed) {
  eng_.seed(seed);
  has_spare_ = false;
  spare_ = 0.0;
}

double GaussianRng::uniform_open01() {
  // Top 53 bits of the 64-bit draw, shifted by one so that 0 is excluded.
  const std::uint64_t r = eng_() >> 11U;
  return (static_cast<double>(r) + 1.0) * (1.0 / 9007199254740992.0);  // 2^-53
}

double GaussianRng::normal() {
  if (has_spare_) {
    has_spare_ = false;
    return spare_;
  }
  // Box-Muller: two independent uniforms -> two independent N(0,1).
  const double u1 = uniform_open01();              // (0, 1]: log is finite
  const double u2 = uniform_open01();
  const double r = std::sqrt(-2.0 * std::log(u1));
  const double a = kTwoPi * u2;
  spare_ = r * std::sin(a);
  has_spare_ = true;
  return r * std::cos(a);
}

// -------------------------------------------------------------- CurrentSensor

Status CurrentSensorParams::validate() const {
  return validate_adc(gain_error, offset_a, full_scale_a, bits, noise_rms_a);
}

Status CurrentSensor::configure(const CurrentSensorParams& p) {
  const Status s = p.validate();
  if (s == Status::kOk) {
    p_ = p;
    lsb_ = 2.0 * p.full_scale_a / std::ldexp(1.0, p.bits);
    inv_lsb_ = 1.0 / lsb_;
    rng_.reseed(p.seed);
  }
  return s;
}

std::int32_t CurrentSensor::sample_code(double i_true_a) {
  // No draw for a noiseless sensor (the Gaussian draw is a third of a
  // noiseless SIL step); a noisy one draws every sample.
  const double noise = (p_.noise_rms_a > 0.0) ? p_.noise_rms_a * rng_.normal() : 0.0;
  const double y = (1.0 + p_.gain_error) * i_true_a + p_.offset_a + noise;
  const std::int32_t half = static_cast<std::int32_t>(1) << (p_.bits - 1);
  return quantise(y, lsb_, inv_lsb_, -half, half - 1);
}

// ----------------------------------------------------------------- VbusSensor

Status VbusSensorParams::validate() const {
  return validate_adc(gain_error, offset_v, full_scale_v, bits, noise_rms_v);
}

Status VbusSensor::configure(const VbusSensorParams& p) {
  const Status s = p.validate();
  if (s == Status::kOk) {
    p_ = p;
    lsb_ = p.full_scale_v / std::ldexp(1.0, p.bits);
    inv_lsb_ = 1.0 / lsb_;
    rng_.reseed(p.seed);
  }
  return s;
}

std::int32_t VbusSensor::sample_code(double vbus_true_v) {
  const double noise = (p_.noise_rms_v > 0.0) ? p_.noise_rms_v * rng_.normal() : 0.0;
  const double y = (1.0 + p_.gain_error) * vbus_true_v + p_.offset_v + noise;
  const std::int32_t full = static_cast<std::int32_t>(
      (static_cast<std::int64_t>(1) << p_.bits) - 1);
  return quantise(y, lsb_, inv_lsb_, 0, full);
}

// -------------------------------------------------------------------- Encoder

Status EncoderParams::validate() const {
  if (!std::isfinite(index_angle_rad)) {
    return Status::kNotFinite;
  }
  if (counts_per_rev < 1) {
    return Status::kBadCounts;
  }
  return Status::kOk;
}

Status Encoder::configure(const EncoderParams& p) {
  const Status s = p.validate();
  if (s == Status::kOk) {
    p_ = p;
    const std::int64_t cpr = p.counts_per_rev;
    in_rev_mask_ = ((cpr & (cpr - 1)) == 0) ? cpr - 1 : -1;
    reset(0.0);
  }
  return s;
}

void Encoder::reset(double theta_m_rad) {
  const double cpr = static_cast<double>(p_.counts_per_rev);
  edge0_ = floor_turns(theta_m_rad * cpr);
  rev_idx_ = floor_turns(theta_m_rad - p_.index_angle_rad);
  index_seen_ = false;
}

double Encoder::step_rad() const { return kTwoPi / static_cast<double>(p_.counts_per_rev); }

EncoderReading Encoder::sample(double theta_m_rad) {
  const double cpr = static_cast<double>(p_.counts_per_rev);
  const std::int64_t cpr_i = p_.counts_per_rev;
  EncoderReading r;
  r.count = floor_turns(theta_m_rad * cpr) - edge0_;
  std::int64_t in_rev = r.count;
  if (p_.has_index) {
    const std::int64_t rev = floor_turns(theta_m_rad - p_.index_angle_rad);
    if (rev != rev_idx_) {
      index_seen_ = true;  // the index mark was crossed since the last sample
    }
    rev_idx_ = rev;
    if (index_seen_) {
      in_rev = floor_turns((theta_m_rad - p_.index_angle_rad) * cpr);
    }
  }
  if (in_rev_mask_ >= 0) {
    in_rev &= in_rev_mask_;  // power-of-two cpr: the non-negative remainder
  } else {
    in_rev %= cpr_i;
    if (in_rev < 0) {
      in_rev += cpr_i;
    }
  }
  r.count_in_rev = static_cast<std::int32_t>(in_rev);
  r.index_seen = index_seen_;
  r.angle_rad = static_cast<double>(r.count_in_rev) * step_rad();
  return r;
}

}  // namespace mcsim
