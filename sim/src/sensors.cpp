#include "mcsim/sensors.hpp"

#include <cfloat>
#include <cmath>

#include "util.hpp"

namespace mcsim {

namespace {

constexpr double kTwoPi = 6.283185307179586476925286766559;
constexpr double kInvTwoPi = 1.0 / kTwoPi;

// x rounded to the nearest integer (ties to even), for |x| < 2^51: adding
// and removing 1.5 * 2^52 leaves no fraction bits (double arithmetic in the
// default rounding mode, which FLT_EVAL_METHOD == 0 guarantees is not done
// in a wider format). Two additions instead of a floor() call or its
// inlined integer round trip.
static_assert(FLT_EVAL_METHOD == 0, "the codes need double arithmetic evaluated in double");
double nearest_int(double x) {
  constexpr double kShift = 0x1.8p52;
  return (x + kShift) - kShift;
}

// The codes below are computed with a reciprocal instead of a division (a
// long latency at the head of every SIL period), bit for bit equal to the
// definitions: num * inv_den (inv_den = 1 / den rounded) differs from the
// rounded quotient by at most 2^-50 (|q| + 1); when it is farther than
// tol = 2^-44 (|q| + 1) from every integer (floor) or from every half
// integer (rounding), the quotient rounds the same way. Otherwise (about one
// call in 10^12 for noisy inputs; NaN, infinity, |q| >= 2^50) the division
// is done.
double tolerance(double q) {
  return 0x1p-44 * (std::fabs(q) + 1.0);
}

// std::floor(num / den).
double floor_of_quotient(double num, double den, double inv_den) {
  const double q = num * inv_den;
  const double r = nearest_int(q);
  if (std::fabs(q) < 0x1p50 && std::fabs(q - r) > tolerance(q)) {
    return (r > q) ? r - 1.0 : r;
  }
  return std::floor(num / den);
}

// std::floor(num / den + 0.5): the nearest integer, ties up.
double round_of_quotient(double num, double den, double inv_den) {
  const double q = num * inv_den;
  const double r = nearest_int(q);
  if (std::fabs(q) < 0x1p50 && std::fabs(q - r) < 0.5 - tolerance(q)) {
    return r;
  }
  return std::floor(num / den + 0.5);
}

// Rounds y / lsb to the nearest code (ties up) and clamps it to [lo, hi]
// (integers); a NaN reading gives code 0. The code as a double (exact).
double quantise(double y, double lsb, double inv_lsb, double lo, double hi) {
  const double q = round_of_quotient(y, lsb, inv_lsb);
  if (std::isnan(q)) {
    return 0.0;
  }
  return detail::clamp(q, lo, hi);
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
  return to_i64(floor_of_quotient(num, kTwoPi, kInvTwoPi));
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
  const double u1 = uniform_open01();  // (0, 1]: log is finite
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
    code_hi_ = std::ldexp(1.0, p.bits - 1) - 1.0;
    rng_.reseed(p.seed);
  }
  return s;
}

double CurrentSensor::code(double i_true_a) {
  // No draw for a noiseless sensor (the Gaussian draw is a third of a
  // noiseless SIL step); a noisy one draws every sample.
  const double noise = (p_.noise_rms_a > 0.0) ? p_.noise_rms_a * rng_.normal() : 0.0;
  const double y = (1.0 + p_.gain_error) * i_true_a + p_.offset_a + noise;
  return quantise(y, lsb_, inv_lsb_, -code_hi_ - 1.0, code_hi_);
}

std::int32_t CurrentSensor::sample_code(double i_true_a) {
  return static_cast<std::int32_t>(code(i_true_a));
}

double CurrentSensor::sample_a(double i_true_a) {
  return code(i_true_a) * lsb_;
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
    code_hi_ = std::ldexp(1.0, p.bits) - 1.0;
    rng_.reseed(p.seed);
  }
  return s;
}

double VbusSensor::code(double vbus_true_v) {
  const double noise = (p_.noise_rms_v > 0.0) ? p_.noise_rms_v * rng_.normal() : 0.0;
  const double y = (1.0 + p_.gain_error) * vbus_true_v + p_.offset_v + noise;
  return quantise(y, lsb_, inv_lsb_, 0.0, code_hi_);
}

std::int32_t VbusSensor::sample_code(double vbus_true_v) {
  return static_cast<std::int32_t>(code(vbus_true_v));
}

double VbusSensor::sample_v(double vbus_true_v) {
  return code(vbus_true_v) * lsb_;
}

// -------------------------------------------------------------------- Encoder

Status EncoderParams::validate() const {
  if (!std::isfinite(index_angle_rad)) {
    return Status::kNotFinite;
  }
  if (counts_per_rev < 1 || (direction != 1 && direction != -1)) {
    return Status::kBadCounts;
  }
  return Status::kOk;
}

Status Encoder::configure(const EncoderParams& p) {
  const Status s = p.validate();
  if (s == Status::kOk) {
    p_ = p;
    const std::int32_t cpr = p.counts_per_rev;
    in_rev_mask_ = ((cpr & (cpr - 1)) == 0) ? cpr - 1 : -1;
    reset(0.0);
  }
  return s;
}

void Encoder::reset(double theta_m_rad) {
  theta_m_rad *= static_cast<double>(p_.direction);
  const double cpr = static_cast<double>(p_.counts_per_rev);
  edge0_ = floor_turns(theta_m_rad * cpr);
  rev_idx_ = floor_turns(theta_m_rad - p_.index_angle_rad);
  index_seen_ = false;
}

double Encoder::step_rad() const {
  return kTwoPi / static_cast<double>(p_.counts_per_rev);
}

EncoderReading Encoder::sample(double theta_m_rad) {
  theta_m_rad *= static_cast<double>(p_.direction);
  const double cpr = static_cast<double>(p_.counts_per_rev);
  const std::int64_t cpr_i = p_.counts_per_rev;
  EncoderReading r;
  const std::int64_t edge = floor_turns(theta_m_rad * cpr);
  r.count = edge - edge0_;
  // Quadrature state of the absolute edge number: 0 -> (0,0), 1 -> (1,0),
  // 2 -> (1,1), 3 -> (0,1).
  const std::int64_t q = edge & 3;
  r.a = (q == 1) || (q == 2);
  r.b = (q >= 2);
  std::int64_t in_rev = r.count;
  if (p_.has_index) {
    const std::int64_t rev = floor_turns(theta_m_rad - p_.index_angle_rad);
    if (rev != rev_idx_) {
      index_seen_ = true;  // the index mark was crossed since the last sample
      r.index_crossed = true;
    }
    rev_idx_ = rev;
    const std::int64_t abs_edge = floor_turns((theta_m_rad - p_.index_angle_rad) * cpr);
    const std::int64_t abs_in_rev = ((abs_edge % cpr_i) + cpr_i) % cpr_i;
    r.z = (abs_in_rev == 0);
    if (index_seen_) {
      in_rev = abs_edge;
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
