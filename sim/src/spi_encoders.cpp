// See spi_encoders.hpp.
#include "mcsim/spi_encoders.hpp"

#include <cmath>

#include "util.hpp"

namespace mcsim {

namespace {

constexpr double kTwoPi = 6.283185307179586476925286766559;

// Nearest code of angle a [rad] with 2^bits codes per turn, mod 2^bits.
std::uint32_t angle_to_code(double a, int bits) {
  const double scale = std::ldexp(1.0, bits) / kTwoPi;
  const double c = std::floor(a * scale + 0.5);
  const auto i = static_cast<std::int64_t>(c);
  return static_cast<std::uint32_t>(static_cast<std::uint64_t>(i) & ((1ULL << bits) - 1ULL));
}

// With probability rate, flips one uniformly chosen bit of the low `bits`
// bits of *w; true when it did.
bool maybe_flip(GaussianRng* rng, double rate, int bits, std::uint32_t* w) {
  if (!(rate > 0.0) || rng->uniform_open01() > rate) return false;
  int bit = static_cast<int>(rng->uniform_open01() * bits);  // (0, bits]
  if (bit >= bits) bit = bits - 1;
  *w ^= (1U << static_cast<unsigned>(bit));
  return true;
}

Status validate_line(const SpiLineParams& l) {
  if (!detail::all_finite({l.miso_error_rate, l.mosi_error_rate})) return Status::kNotFinite;
  const bool ok = l.miso_error_rate >= 0.0 && l.miso_error_rate <= 1.0 &&
                  l.mosi_error_rate >= 0.0 && l.mosi_error_rate <= 1.0;
  return ok ? Status::kOk : Status::kBadSensor;
}

Status validate_chip(double latency_s, double noise_rms_rad, double mount_offset_rad,
                     int direction) {
  if (!detail::all_finite({latency_s, noise_rms_rad, mount_offset_rad})) {
    return Status::kNotFinite;
  }
  const bool ok = latency_s >= 0.0 && latency_s <= 1.0e-3 && noise_rms_rad >= 0.0 &&
                  (direction == 1 || direction == -1);
  return ok ? Status::kOk : Status::kBadSensor;
}

}  // namespace

bool spi_even_parity(std::uint32_t w, int bits) {
  unsigned ones = 0U;
  for (int k = 0; k < bits; ++k) ones += (w >> static_cast<unsigned>(k)) & 1U;
  return (ones & 1U) == 0U;
}

// -------------------------------------------------------------- MotionHistory

Status MotionHistory::push(double t_s, double theta_rad, double omega_rad_s) {
  if (!detail::all_finite({t_s, theta_rad, omega_rad_s})) return Status::kNotFinite;
  if (n_ > 0) {
    Sample& last = s_[(head_ + n_ - 1) % kHistory];
    if (t_s < last.t) return Status::kBadPeriod;
    if (t_s == last.t) {
      last = Sample{t_s, theta_rad, omega_rad_s};
      return Status::kOk;
    }
  }
  if (n_ == kHistory) {
    head_ = (head_ + 1) % kHistory;
    --n_;
  }
  s_[(head_ + n_) % kHistory] = Sample{t_s, theta_rad, omega_rad_s};
  ++n_;
  return Status::kOk;
}

double MotionHistory::last_t_s() const {
  return (n_ > 0) ? at(n_ - 1).t : 0.0;
}

int MotionHistory::find(double t_s) const {
  for (int k = n_ - 1; k >= 0; --k) {
    if (at(k).t <= t_s) return k;
  }
  return -1;
}

double MotionHistory::theta_at(double t_s) const {
  if (n_ == 0) return 0.0;
  const int k = find(t_s);
  if (k < 0 || k == n_ - 1) {
    const Sample& e = at(k < 0 ? 0 : n_ - 1);
    return e.th + e.w * (t_s - e.t);
  }
  // Cubic Hermite on [t0, t1] with the end slopes.
  const Sample& a = at(k);
  const Sample& b = at(k + 1);
  const double h = b.t - a.t;
  const double s = (t_s - a.t) / h;
  const double s2 = s * s, s3 = s2 * s;
  return (2.0 * s3 - 3.0 * s2 + 1.0) * a.th + (s3 - 2.0 * s2 + s) * h * a.w +
         (3.0 * s2 - 2.0 * s3) * b.th + (s3 - s2) * h * b.w;
}

double MotionHistory::omega_at(double t_s) const {
  if (n_ == 0) return 0.0;
  const int k = find(t_s);
  if (k < 0 || k == n_ - 1) return at(k < 0 ? 0 : n_ - 1).w;
  const Sample& a = at(k);
  const Sample& b = at(k + 1);
  const double h = b.t - a.t;
  const double s = (t_s - a.t) / h;
  const double s2 = s * s;
  return ((6.0 * s2 - 6.0 * s) * (a.th - b.th)) / h + (3.0 * s2 - 4.0 * s + 1.0) * a.w +
         (3.0 * s2 - 2.0 * s) * b.w;
}

// -------------------------------------------------------------------- AS5047P

Status As5047pParams::validate() const {
  const Status sc = validate_chip(latency_s, noise_rms_rad, mount_offset_rad, direction);
  if (sc != Status::kOk) return sc;
  const Status sl = validate_line(line);
  if (sl != Status::kOk) return sl;
  const bool ok = zposm <= 0xFFU && zposl <= 0xFFU && settings1 <= 0xFFU && settings2 <= 0xFFU &&
                  magnitude <= 0x3FFFU;
  return ok ? Status::kOk : Status::kBadSensor;
}

Status As5047p::configure(const As5047pParams& p) {
  const Status s = p.validate();
  if (s != Status::kOk) return s;
  p_ = p;
  rng_.reseed(p.line.seed);
  n_ = SpiCounters{};
  fault_ = MagnetFault::kNone;
  power_up(0.0, 0.0, 0.0);
  return Status::kOk;
}

void As5047p::power_up(double t_s, double theta_m_rad, double omega_m_rad_s) {
  motion_.clear();
  (void)motion_.push(t_s, theta_m_rad, omega_m_rad_s);  // a bad value leaves it empty: angle 0
  zposm_ = p_.zposm;
  zposl_ = p_.zposl;
  settings1_ = static_cast<std::uint16_t>(p_.settings1 | 1U);  // factory bit reads 1
  settings2_ = p_.settings2;
  prog_ = 0;
  errfl_ = 0;
  response_ = 0;
  write_pending_ = false;
}

std::uint16_t As5047p::read_command(std::uint16_t address) {
  auto w = static_cast<std::uint16_t>(0x4000U | (address & 0x3FFFU));
  if (!spi_even_parity(w, 16)) w = static_cast<std::uint16_t>(w | 0x8000U);
  return w;
}

std::uint16_t As5047p::write_command(std::uint16_t address) {
  auto w = static_cast<std::uint16_t>(address & 0x3FFFU);
  if (!spi_even_parity(w, 16)) w = static_cast<std::uint16_t>(w | 0x8000U);
  return w;
}

std::uint16_t As5047p::write_data(std::uint16_t data14) {
  return write_command(data14);  // the same layout: parity, 0, 14 bits
}

std::uint16_t As5047p::code_of(double t_s, bool compensated, double noise_rad) const {
  const double td = t_s - p_.latency_s;
  double th = motion_.theta_at(td);
  if (compensated) th += motion_.omega_at(td) * p_.latency_s;
  const double a = static_cast<double>(p_.direction) * th + p_.mount_offset_rad + noise_rad;
  std::uint32_t code = angle_to_code(a, 14);
  if ((settings1_ & kDir) != 0U) code = (0x4000U - code) & 0x3FFFU;
  const std::uint32_t zero = ((zposm_ & 0xFFU) << 6U) | (zposl_ & 0x3FU);
  return static_cast<std::uint16_t>((code + 0x4000U - zero) & 0x3FFFU);
}

std::uint16_t As5047p::angle_code(double t_s, bool compensated) const {
  return code_of(t_s, compensated, 0.0);
}

std::uint16_t As5047p::latch_angle(double t_s, bool compensated) {
  if (fault_ == MagnetFault::kTooWeak) {
    // No usable field: the CORDIC angle is noise.
    return static_cast<std::uint16_t>(angle_to_code(kTwoPi * rng_.uniform_open01(), 14));
  }
  // Noise on the magnet's angle (no draw for a noiseless chip).
  const double noise = (p_.noise_rms_rad > 0.0) ? p_.noise_rms_rad * rng_.normal() : 0.0;
  return code_of(t_s, compensated, noise);
}

std::uint16_t As5047p::reg(std::uint16_t address, double t_s, bool* ok) {
  *ok = true;
  switch (address) {
    case kNop:
      return 0;
    case kErrfl:
      return errfl_;
    case kProg:
      return prog_;
    case kZposm:
      return zposm_;
    case kZposl:
      return zposl_;
    case kSettings1:
      return settings1_;
    case kSettings2:
      return settings2_;
    case kDiaagc: {
      // LF (bit 8): the offset loop has settled; MAGL / MAGH with the AGC
      // at its end when the field is too weak / too strong.
      std::uint16_t d = 1U << 8U;
      if (fault_ == MagnetFault::kTooWeak)
        return static_cast<std::uint16_t>(d | (1U << 11U) | 0xFFU);
      if (fault_ == MagnetFault::kTooStrong) return static_cast<std::uint16_t>(d | (1U << 10U));
      return static_cast<std::uint16_t>(d | p_.agc);
    }
    case kMag:
      return p_.magnitude;
    case kAngleUnc:
      return latch_angle(t_s, false);
    case kAngleCom:
      return latch_angle(t_s, (settings1_ & (kDaecdis | kDataselect)) == 0U);
    default:
      *ok = false;
      return 0;
  }
}

std::uint16_t As5047p::make_response(std::uint16_t data) const {
  auto w = static_cast<std::uint16_t>((data & 0x3FFFU) | (errfl_ != 0U ? 0x4000U : 0U));
  if (!spi_even_parity(w, 16)) w = static_cast<std::uint16_t>(w | 0x8000U);
  return w;
}

std::uint16_t As5047p::transfer(std::uint16_t mosi, double t_s, int bits) {
  ++n_.frames;
  std::uint32_t miso = response_;
  if (maybe_flip(&rng_, p_.line.miso_error_rate, 16, &miso)) ++n_.miso_flips;
  std::uint32_t rx = mosi;
  if (maybe_flip(&rng_, p_.line.mosi_error_rate, 16, &rx)) ++n_.mosi_flips;
  const auto out = static_cast<std::uint16_t>(miso);
  if (bits != 16 || !spi_even_parity(rx, 16)) {
    errfl_ = static_cast<std::uint16_t>(errfl_ | (bits != 16 ? kFrerr : kParerr));
    write_pending_ = false;
    response_ = make_response(0);
    return out;
  }
  bool ok = true;
  if (write_pending_) {
    // The data frame of a write: the register takes the 14 data bits (its
    // own width), the next frame returns the new content.
    write_pending_ = false;
    const std::uint16_t d = rx & 0xFFU;
    switch (write_address_) {
      case kProg:
        prog_ = d;
        break;
      case kZposm:
        zposm_ = d;
        break;
      case kZposl:
        zposl_ = d;
        break;
      case kSettings1:
        settings1_ = static_cast<std::uint16_t>(d | 1U);
        break;
      default:  // kSettings2 (the only other writable address)
        settings2_ = d;
        break;
    }
    response_ = make_response(reg(write_address_, t_s, &ok));
    return out;
  }
  const auto address = static_cast<std::uint16_t>(rx & 0x3FFFU);
  if ((rx & 0x4000U) != 0U) {
    std::uint16_t v = reg(address, t_s, &ok);
    if (!ok) {
      errfl_ = static_cast<std::uint16_t>(errfl_ | kInvcomm);
      v = 0;
    }
    response_ = make_response(v);
    if (ok && address == kErrfl) errfl_ = 0;  // cleared by the read
    return out;
  }
  const bool writable = address == kProg || address == kZposm || address == kZposl ||
                        address == kSettings1 || address == kSettings2;
  if (address == kNop) {
    response_ = make_response(0);
  } else if (writable) {
    write_pending_ = true;
    write_address_ = address;
    response_ = make_response(reg(address, t_s, &ok));  // the old content
  } else {
    errfl_ = static_cast<std::uint16_t>(errfl_ | kInvcomm);
    response_ = make_response(0);
  }
  return out;
}

// ---------------------------------------------------------------------- MA732

Status Ma732Params::validate() const {
  const Status sc = validate_chip(latency_s, noise_rms_rad, mount_offset_rad, direction);
  if (sc != Status::kOk) return sc;
  return validate_line(line);
}

double Ma732::filter_tau_s(std::uint8_t fw) {
  const double f = detail::clamp(static_cast<double>(fw), 51.0, 187.0);
  return 64.0e-6 * std::exp2((f - 51.0) / 17.0);
}

double Ma732::resolution_bits(std::uint8_t fw) {
  const double f = detail::clamp(static_cast<double>(fw), 51.0, 187.0);
  return 9.0 + (f - 51.0) / 34.0;
}

double Ma732::noise_rms_rad() const {
  if (!p_.noise_from_filter) return p_.noise_rms_rad;
  // Resolution as the 3-sigma spread of the readings.
  return kTwoPi / std::exp2(resolution_bits(regs_[kFw])) / 3.0;
}

Status Ma732::configure(const Ma732Params& p) {
  const Status s = p.validate();
  if (s != Status::kOk) return s;
  p_ = p;
  rng_.reseed(p.line.seed);
  n_ = SpiCounters{};
  fault_ = MagnetFault::kNone;
  power_up(0.0, 0.0, 0.0);
  return Status::kOk;
}

void Ma732::power_up(double t_s, double theta_m_rad, double omega_m_rad_s) {
  motion_.clear();
  filtered_.clear();
  const bool ok = motion_.push(t_s, theta_m_rad, omega_m_rad_s) == Status::kOk;
  af_ = ok ? theta_m_rad : 0.0;
  wf_ = ok ? omega_m_rad_s : 0.0;
  tf_ = ok ? t_s : 0.0;
  (void)filtered_.push(tf_, af_, wf_);
  for (int k = 0; k < 32; ++k) regs_[k] = p_.regs[k];
  reg_pending_ = false;
  reg_value_ = 0;
}

Status Ma732::observe(double t_s, double theta_m_rad, double omega_m_rad_s) {
  const Status s = motion_.push(t_s, theta_m_rad, omega_m_rad_s);
  if (s == Status::kOk) filter_to(t_s);
  return s;
}

void Ma732::filter_to(double t1_s) {
  if (!(t1_s > tf_)) return;
  const double tau = filter_tau_s(regs_[kFw]);
  // Long gaps: the filter has converged on the input long before t1 (40
  // tau: e^-40); restart it there.
  if (t1_s - tf_ > 40.0 * tau) {
    tf_ = t1_s - 40.0 * tau;
    af_ = motion_.theta_at(tf_);
    wf_ = motion_.omega_at(tf_);
  }
  const double dt = t1_s - tf_;
  const int m = static_cast<int>(std::ceil(dt / (0.125 * tau)));
  const double h = dt / m;
  const double k1 = 2.0 / tau, k2 = 1.0 / (tau * tau);
  // (da_f, dw_f) at (a_f, w_f) with the input at time t.
  const auto f = [&](double t, double a, double w, double* da, double* dw) {
    const double e = motion_.theta_at(t) - a;
    *da = w + k1 * e;
    *dw = k2 * e;
  };
  for (int j = 0; j < m; ++j) {
    const double t = tf_ + j * h;
    double a1, w1, a2, w2, a3, w3, a4, w4;
    f(t, af_, wf_, &a1, &w1);
    f(t + 0.5 * h, af_ + 0.5 * h * a1, wf_ + 0.5 * h * w1, &a2, &w2);
    f(t + 0.5 * h, af_ + 0.5 * h * a2, wf_ + 0.5 * h * w2, &a3, &w3);
    f(t + h, af_ + h * a3, wf_ + h * w3, &a4, &w4);
    af_ += h / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4);
    wf_ += h / 6.0 * (w1 + 2.0 * w2 + 2.0 * w3 + w4);
  }
  tf_ = t1_s;
  double da, dw;
  f(tf_, af_, wf_, &da, &dw);
  (void)filtered_.push(tf_, af_, da);
}

std::uint16_t Ma732::code_of(double t_s, double noise_rad) const {
  const double th = filtered_.theta_at(t_s - p_.latency_s);
  const double a = static_cast<double>(p_.direction) * th + p_.mount_offset_rad + noise_rad;
  std::uint32_t code = angle_to_code(a, 16);
  if ((regs_[kRd] & kRdBit) != 0U) code = (0x10000U - code) & 0xFFFFU;
  const std::uint32_t zero = regs_[kZLow] | (static_cast<std::uint32_t>(regs_[kZHigh]) << 8U);
  return static_cast<std::uint16_t>((code + 0x10000U - zero) & 0xFFFFU);
}

std::uint16_t Ma732::angle_code(double t_s) const {
  return code_of(t_s, 0.0);
}

std::uint16_t Ma732::latch_angle(double t_s) {
  if (fault_ == MagnetFault::kTooWeak) {
    return static_cast<std::uint16_t>(angle_to_code(kTwoPi * rng_.uniform_open01(), 16));
  }
  const double sigma = noise_rms_rad();
  return code_of(t_s, (sigma > 0.0) ? sigma * rng_.normal() : 0.0);
}

std::uint32_t Ma732::transfer(std::uint16_t mosi, double t_s, int bits) {
  ++n_.frames;
  if (bits != 8 && bits != 16 && bits != 17) return 0U;
  const std::uint16_t word =
      reg_pending_ ? static_cast<std::uint16_t>(reg_value_ << 8U) : latch_angle(t_s);
  reg_pending_ = false;
  std::uint32_t out = word;
  if (bits == 8) out = word >> 8U;
  if (bits == 17)
    out = (static_cast<std::uint32_t>(word) << 1U) | (spi_even_parity(word, 16) ? 0U : 1U);
  if (maybe_flip(&rng_, p_.line.miso_error_rate, bits, &out)) ++n_.miso_flips;
  if (bits == 8) return out;  // a partial frame: no command
  std::uint32_t rx = mosi;
  if (maybe_flip(&rng_, p_.line.mosi_error_rate, 16, &rx)) ++n_.mosi_flips;
  const std::uint32_t cmd = rx >> 13U;
  const auto address = static_cast<std::uint8_t>((rx >> 8U) & 0x1FU);
  if (cmd == 0x2U || cmd == 0x4U) {
    if (cmd == 0x4U && address != kStatus) regs_[address] = static_cast<std::uint8_t>(rx & 0xFFU);
    std::uint8_t v = regs_[address];
    if (address == kStatus) {
      const unsigned mgh = kMgh, mgl = kMgl;
      v = static_cast<std::uint8_t>((fault_ == MagnetFault::kTooStrong ? mgh : 0U) |
                                    (fault_ == MagnetFault::kTooWeak ? mgl : 0U));
    }
    reg_pending_ = true;
    reg_value_ = v;
  }
  return out;
}

}  // namespace mcsim
