// mcsim/sensors.hpp: measurement models. Every sensor is deterministic for a
// given seed: noise comes from std::mt19937_64 (whose output sequence the C++
// standard fixes) and this library's own Box-Muller transform (no
// std::normal_distribution, whose algorithm is implementation-defined).
//
// ADC channel (CurrentSensor, VbusSensor):
//   y    = (1 + gain_error) x + offset + noise          (noise ~ N(0, rms^2))
//   code = round(y / lsb), clamped to the converter range
//   out  = code * lsb
// CurrentSensor is bipolar: lsb = 2 full_scale_a / 2^bits, codes in
//   [-2^(bits-1), 2^(bits-1) - 1].
// VbusSensor is unipolar: lsb = full_scale_v / 2^bits, codes in [0, 2^bits - 1].
//
// Encoder: incremental, counts_per_rev edges per mechanical turn (after
// quadrature decoding). The counter value is floor(dir theta_m * cpr / 2 pi)
// relative to the angle at reset(); with an index, once the shaft has crossed
// index_angle_rad (mod 2 pi) the reported count becomes absolute, i.e.
// floor((theta_m - index_angle_rad) cpr / 2 pi) mod cpr.
// Power-up: reset(theta_m0) is the board's power-up with the rotor at
// theta_m0 (an incremental encoder counts from 0 there). The lines as a
// receiver sees them: with E = floor(dir theta_m cpr / 2 pi) (the absolute
// edge number, which the shaft fixes, not the power-up), the quadrature
// state E mod 4 = 0, 1, 2, 3 gives (A, B) = (0, 0), (1, 0), (1, 1), (0, 1)
// (A leads B counting up, one edge per count), and Z is high over the
// first count after the index mark (floor((dir theta_m - index) cpr / 2 pi)
// mod cpr == 0), the pulse an EXTI line sees; index_crossed reports that
// the mark was passed since the previous sample.
#ifndef MCSIM_SENSORS_HPP
#define MCSIM_SENSORS_HPP

#include <cstdint>
#include <random>

#include "mcsim/status.hpp"

namespace mcsim {

// Standard normal samples: mt19937_64 + Box-Muller, deterministic per seed.
class GaussianRng {
 public:
  explicit GaussianRng(std::uint64_t seed = 1U) : eng_(seed) {}
  void reseed(std::uint64_t seed);
  double uniform_open01();  // in (0, 1], 53-bit resolution
  double normal();          // N(0, 1)

 private:
  std::mt19937_64 eng_;
  double spare_ = 0.0;
  bool has_spare_ = false;
};

struct CurrentSensorParams {
  double gain_error = 0.0;  // relative, gain = 1 + gain_error (> 0)
  double offset_a = 0.0;
  double full_scale_a = 50.0;  // bipolar range +-full_scale_a
  int bits = 12;               // 1..30
  double noise_rms_a = 0.0;
  std::uint64_t seed = 1U;
  // kOk, kNotFinite, kBadGain, kBadFullScale, kBadBits, kNegativeNoise.
  Status validate() const;
};

class CurrentSensor {
 public:
  CurrentSensor() = default;
  // Validates p and reseeds the noise; on error keeps everything unchanged.
  Status configure(const CurrentSensorParams& p);
  double lsb_a() const { return lsb_; }
  std::int32_t sample_code(double i_true_a);  // advances the noise generator
  double sample_a(double i_true_a);           // sample_code() * lsb_a()

 private:
  double code(double i_true_a);  // the code, as an (integral) double
  CurrentSensorParams p_{};
  double lsb_ = 2.0 * 50.0 / 4096.0;  // of the default params; set by configure()
  double inv_lsb_ = 4096.0 / (2.0 * 50.0);
  double code_hi_ = 2047.0;  // codes in [-code_hi_ - 1, code_hi_]
  GaussianRng rng_{1U};
};

struct VbusSensorParams {
  double gain_error = 0.0;
  double offset_v = 0.0;
  double full_scale_v = 60.0;  // unipolar range [0, full_scale_v)
  int bits = 12;
  double noise_rms_v = 0.0;
  std::uint64_t seed = 2U;
  Status validate() const;
};

class VbusSensor {
 public:
  VbusSensor() = default;
  Status configure(const VbusSensorParams& p);
  double lsb_v() const { return lsb_; }
  std::int32_t sample_code(double vbus_true_v);
  double sample_v(double vbus_true_v);  // sample_code() * lsb_v()

 private:
  double code(double vbus_true_v);
  VbusSensorParams p_{};
  double lsb_ = 60.0 / 4096.0;  // of the default params; set by configure()
  double inv_lsb_ = 4096.0 / 60.0;
  double code_hi_ = 4095.0;
  GaussianRng rng_{2U};
};

struct EncoderParams {
  std::int32_t counts_per_rev = 4096;  // >= 1
  bool has_index = false;
  double index_angle_rad = 0.0;  // mechanical angle of the index mark
  // +1: counts up when the shaft turns positive; -1: mounted (or wired) the
  // other way, counts down. The offset of an incremental encoder is the
  // shaft angle at reset() (the board's power-up angle).
  int direction = 1;
  // kOk, kNotFinite, kBadCounts (also for a direction other than +-1).
  Status validate() const;
};

struct EncoderReading {
  std::int64_t count = 0;         // unwrapped counter since reset (edges)
  std::int32_t count_in_rev = 0;  // [0, cpr): relative, or absolute once index seen
  bool index_seen = false;
  double angle_rad = 0.0;                // count_in_rev * 2 pi / cpr
  bool a = false, b = false, z = false;  // line levels (z always low without an index)
  bool index_crossed = false;            // the mark was passed since the last sample
};

class Encoder {
 public:
  Encoder() = default;
  // Validates p and resets at angle 0; on error keeps everything unchanged.
  Status configure(const EncoderParams& p);
  // Power-up / counter reset at the true mechanical angle theta_m_rad.
  void reset(double theta_m_rad);
  double step_rad() const;
  EncoderReading sample(double theta_m_rad);

 private:
  EncoderParams p_{};
  std::int64_t edge0_ = 0;           // floor(theta_reset * cpr / 2pi)
  std::int64_t rev_idx_ = 0;         // floor((theta - index) / 2pi) at the last sample
  std::int32_t in_rev_mask_ = 4095;  // cpr - 1 for a power-of-two cpr, else -1
  bool index_seen_ = false;
};

}  // namespace mcsim

#endif  // MCSIM_SENSORS_HPP
