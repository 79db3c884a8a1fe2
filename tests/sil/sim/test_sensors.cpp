// Sensor models: quantisation, offset, gain, saturation, noise statistics,
// determinism per seed; encoder quantisation and index.
#include <cmath>
#include <cstdint>
#include <random>
#include <set>
#include <vector>

#include <gtest/gtest.h>

#include "mcsim/sensors.hpp"
#include "sim_test_util.hpp"

namespace {

using mcsim::CurrentSensor;
using mcsim::CurrentSensorParams;
using mcsim::Encoder;
using mcsim::EncoderParams;
using mcsim::Status;
using mcsim::VbusSensor;
using mcsim::VbusSensorParams;
using mcsim_test::kPi;

TEST(SimSensors, EngineSequenceIsTheStandardOne) {
  // The C++ standard fixes the 10000th output of a default-seeded
  // mt19937_64 (seed 5489): guards the determinism claim across toolchains.
  mcsim::GaussianRng rng(5489U);
  double u = 0.0;
  for (int k = 0; k < 10000; ++k) {
    u = rng.uniform_open01();
  }
  const double expected =
      (static_cast<double>(9981545732273789042ULL >> 11U) + 1.0) / 9007199254740992.0;
  EXPECT_EQ(u, expected);  // exact: same integer, same conversion
}

TEST(SimSensors, CurrentQuantisationStepIsOneLsb) {
  CurrentSensorParams p;
  p.full_scale_a = 25.0;
  p.bits = 10;
  CurrentSensor s;
  ASSERT_EQ(s.configure(p), Status::kOk);
  const double lsb = 50.0 / 1024.0;
  EXPECT_DOUBLE_EQ(s.lsb_a(), lsb);
  std::set<std::int32_t> codes;
  double prev = s.sample_a(-3.0);
  for (int k = 1; k <= 3000; ++k) {
    const double i = -3.0 + 0.002 * k;  // sweep -3..+3 A in 2 mA steps
    const double y = s.sample_a(i);
    const double jump = y - prev;
    // Output moves in whole LSBs: 0 or exactly one step (1e-12 round-off).
    EXPECT_TRUE(std::fabs(jump) < 1e-12 || std::fabs(jump - lsb) < 1e-12) << "i=" << i;
    // Quantisation error at most half an LSB (+ round-off).
    EXPECT_LE(std::fabs(y - i), 0.5 * lsb + 1e-12);
    codes.insert(s.sample_code(i));
    prev = y;
  }
  // 6 A span / 48.8 mA = 123 levels (+-1 for the ends).
  EXPECT_GE(codes.size(), 122U);
  EXPECT_LE(codes.size(), 124U);
}

TEST(SimSensors, CurrentOffsetGainAndSaturation) {
  CurrentSensorParams p;
  p.full_scale_a = 20.0;
  p.bits = 12;
  p.offset_a = 0.37;
  p.gain_error = 0.02;
  CurrentSensor s;
  ASSERT_EQ(s.configure(p), Status::kOk);
  const double lsb = s.lsb_a();
  // Zero input reads the offset, within half an LSB.
  EXPECT_NEAR(s.sample_a(0.0), 0.37, 0.5 * lsb);
  // 10 A reads 1.02 * 10 + 0.37, within half an LSB.
  EXPECT_NEAR(s.sample_a(10.0), 10.57, 0.5 * lsb);
  // Saturation at the converter range: codes -2048 .. 2047 (exact).
  EXPECT_EQ(s.sample_code(1.0e3), 2047);
  EXPECT_EQ(s.sample_code(-1.0e3), -2048);
  EXPECT_EQ(s.sample_code(NAN), 0);
}

TEST(SimSensors, NoiseHasTheRequestedStatistics) {
  CurrentSensorParams p;
  p.full_scale_a = 100.0;
  p.bits = 24;  // LSB 12 uA: quantisation negligible against 0.2 A noise
  p.noise_rms_a = 0.2;
  p.seed = 42U;
  CurrentSensor s;
  ASSERT_EQ(s.configure(p), Status::kOk);
  const int n = 20000;
  double sum = 0.0;
  double sum2 = 0.0;
  double lag1 = 0.0;
  double prev = 0.0;
  for (int k = 0; k < n; ++k) {
    const double y = s.sample_a(1.0) - 1.0;
    sum += y;
    sum2 += y * y;
    lag1 += y * prev;
    prev = y;
  }
  const double mean = sum / n;
  const double rms = std::sqrt(sum2 / n - mean * mean);
  // Standard error of the mean: 0.2/sqrt(20000) = 1.4 mA -> 5 sigma = 7 mA.
  EXPECT_NEAR(mean, 0.0, 7.0e-3);
  // Standard error of the rms estimate: 0.2/sqrt(2 n) = 1 mA -> 5 sigma = 5 mA.
  EXPECT_NEAR(rms, 0.2, 5.0e-3);
  // Successive samples are independent (both Box-Muller outputs are used):
  // lag-1 correlation has standard error 1/sqrt(n) = 0.007 -> 5 sigma bound.
  EXPECT_NEAR(lag1 / sum2, 0.0, 0.035);
}

TEST(SimSensors, DeterministicForASeed) {
  CurrentSensorParams p;
  p.noise_rms_a = 0.5;
  p.seed = 7U;
  CurrentSensor a;
  CurrentSensor b;
  ASSERT_EQ(a.configure(p), Status::kOk);
  ASSERT_EQ(b.configure(p), Status::kOk);
  std::vector<std::int32_t> first;
  int differ = 0;
  for (int k = 0; k < 500; ++k) {
    const std::int32_t ca = a.sample_code(0.1 * k);
    EXPECT_EQ(ca, b.sample_code(0.1 * k));  // same seed: identical sequence
    first.push_back(ca);
  }
  // Re-configuring restarts the sequence.
  ASSERT_EQ(a.configure(p), Status::kOk);
  for (int k = 0; k < 500; ++k) {
    EXPECT_EQ(a.sample_code(0.1 * k), first[static_cast<std::size_t>(k)]);
  }
  // Another seed gives another sequence (0.5 A noise vs 24 mA LSB: nearly
  // every sample differs; require more than half).
  p.seed = 8U;
  ASSERT_EQ(b.configure(p), Status::kOk);
  for (int k = 0; k < 500; ++k) {
    if (b.sample_code(0.1 * k) != first[static_cast<std::size_t>(k)]) {
      ++differ;
    }
  }
  EXPECT_GT(differ, 250);
}

TEST(SimSensors, InvalidAdcConfigKeepsOldOne) {
  CurrentSensor s;
  CurrentSensorParams p;
  p.bits = 0;
  EXPECT_EQ(s.configure(p), Status::kBadBits);
  p = CurrentSensorParams{};
  p.bits = 31;
  EXPECT_EQ(s.configure(p), Status::kBadBits);
  p = CurrentSensorParams{};
  p.full_scale_a = 0.0;
  EXPECT_EQ(s.configure(p), Status::kBadFullScale);
  p = CurrentSensorParams{};
  p.gain_error = -1.0;
  EXPECT_EQ(s.configure(p), Status::kBadGain);
  p = CurrentSensorParams{};
  p.noise_rms_a = -0.1;
  EXPECT_EQ(s.configure(p), Status::kNegativeNoise);
  p = CurrentSensorParams{};
  p.offset_a = INFINITY;
  EXPECT_EQ(s.configure(p), Status::kNotFinite);
  EXPECT_DOUBLE_EQ(s.lsb_a(), 100.0 / 4096.0);  // defaults kept
}

TEST(SimSensors, VbusIsUnipolar) {
  VbusSensorParams p;
  p.full_scale_v = 64.0;
  p.bits = 12;
  p.offset_v = -0.1;
  VbusSensor s;
  ASSERT_EQ(s.configure(p), Status::kOk);
  EXPECT_DOUBLE_EQ(s.lsb_v(), 64.0 / 4096.0);
  EXPECT_NEAR(s.sample_v(48.0), 47.9, 0.5 * s.lsb_v());  // offset, half-LSB bound
  EXPECT_EQ(s.sample_code(-5.0), 0);                     // exact: bottom rail
  EXPECT_EQ(s.sample_code(100.0), 4095);                 // exact: top rail
}

// The codes are defined as round(y / lsb) and floor(theta cpr / 2 pi); the
// models compute them with a reciprocal and fall back to the division near
// an integer. Checked bit for bit against the definitions on random values
// and on exact ties and their neighbours (where a product and a quotient
// can round to different sides).
TEST(SimSensors, CodesEqualTheDefinitionsExactly) {
  CurrentSensorParams p;
  p.full_scale_a = 20.0;  // lsb 40/4096: not a power of two
  p.bits = 12;
  CurrentSensor s;
  ASSERT_EQ(s.configure(p), Status::kOk);
  const double lsb = s.lsb_a();
  auto expect_code = [&](double y) {
    double q = std::floor(y / lsb + 0.5);
    q = std::fmin(std::fmax(q, -2048.0), 2047.0);
    ASSERT_EQ(s.sample_code(y), static_cast<std::int32_t>(q)) << "y=" << y;
  };
  std::uint64_t r = 12345U;
  for (int k = 0; k < 200000; ++k) {
    r = r * 6364136223846793005ULL + 1442695040888963407ULL;
    expect_code((static_cast<double>(r >> 11) * 0x1p-53 - 0.5) * 50.0);
  }
  for (int c = -2100; c < 2100; ++c) {
    const double tie = (c + 0.5) * lsb;
    expect_code(tie);
    expect_code(std::nextafter(tie, 1e9));
    expect_code(std::nextafter(tie, -1e9));
  }
  for (const std::int32_t cpr : {4096, 8192, 2000, 1000}) {
    EncoderParams ep;
    ep.counts_per_rev = cpr;
    Encoder e;
    ASSERT_EQ(e.configure(ep), Status::kOk);
    const double step = 2.0 * kPi / cpr;
    for (int c = -3 * cpr; c < 3 * cpr; c += 7) {
      for (const double th : {c * step, std::nextafter(c * step, 1e9),
                              std::nextafter(c * step, -1e9), (c + 0.5) * step}) {
        const std::int64_t want = static_cast<std::int64_t>(std::floor(th * cpr / (2.0 * kPi)));
        const mcsim::EncoderReading rd = e.sample(th);
        ASSERT_EQ(rd.count, want) << "cpr " << cpr << " th " << th;
        const std::int64_t in_rev = ((want % cpr) + cpr) % cpr;
        ASSERT_EQ(rd.count_in_rev, in_rev) << "cpr " << cpr << " th " << th;
      }
    }
  }
}

TEST(SimEncoder, QuantisesTheMechanicalAngle) {
  EncoderParams p;
  p.counts_per_rev = 2000;
  Encoder e;
  ASSERT_EQ(e.configure(p), Status::kOk);
  const double step = 2.0 * kPi / 2000.0;
  EXPECT_DOUBLE_EQ(e.step_rad(), step);
  std::int64_t prev = e.sample(0.0).count;
  EXPECT_EQ(prev, 0);
  for (int k = 1; k <= 5000; ++k) {
    const double th = 1.3e-3 * k;  // 6.5 rad: more than one turn
    const mcsim::EncoderReading r = e.sample(th);
    // The count never skips (steps 1.3 mrad < 3.1 mrad) and never goes back.
    EXPECT_GE(r.count - prev, 0);
    EXPECT_LE(r.count - prev, 1);
    prev = r.count;
    // Reported angle is the true angle truncated to the step, modulo a turn.
    const double wrapped = th - 2.0 * kPi * std::floor(th / (2.0 * kPi));
    const double err = wrapped - r.angle_rad;
    // err in [0, step) except right at the wrap; 1e-9 rad round-off margin.
    const bool at_wrap = std::fabs(std::fabs(err) - 2.0 * kPi) < step;
    EXPECT_TRUE((err > -1e-9 && err < step + 1e-9) || at_wrap) << "th=" << th;
  }
  EXPECT_EQ(prev, static_cast<std::int64_t>(std::floor(6.5 / step)));
  // Negative direction counts down.
  EXPECT_EQ(e.sample(-0.5 * step).count, -1);
}

TEST(SimEncoder, IndexMakesTheCountAbsolute) {
  EncoderParams p;
  p.counts_per_rev = 1000;
  p.has_index = true;
  p.index_angle_rad = 1.0;
  Encoder e;
  ASSERT_EQ(e.configure(p), Status::kOk);
  e.reset(0.3);  // powered up at 0.3 rad: counts relative to that
  const mcsim::EncoderReading r0 = e.sample(0.5);
  EXPECT_FALSE(r0.index_seen);
  EXPECT_EQ(r0.count_in_rev, static_cast<std::int32_t>(std::floor(0.5 * 1000 / (2 * kPi))) -
                                 static_cast<std::int32_t>(std::floor(0.3 * 1000 / (2 * kPi))));
  const mcsim::EncoderReading r1 = e.sample(1.2);  // crossed 1.0 rad
  EXPECT_TRUE(r1.index_seen);
  const std::int32_t expected = static_cast<std::int32_t>(std::floor(0.2 * 1000 / (2 * kPi)));
  EXPECT_EQ(r1.count_in_rev, expected);  // absolute: 0 at the index mark
  // 1e-12 rad: one multiplication of an exact count by the step.
  EXPECT_NEAR(r1.angle_rad, expected * 2.0 * kPi / 1000.0, 1e-12);
  // Going back below the mark keeps the absolute reference.
  const mcsim::EncoderReading r2 = e.sample(0.9);
  EXPECT_TRUE(r2.index_seen);
  EXPECT_EQ(r2.count_in_rev,
            static_cast<std::int32_t>(std::floor((0.9 - 1.0 + 2 * kPi) * 1000 / (2 * kPi))));
  EncoderParams bad;
  bad.counts_per_rev = 0;
  EXPECT_EQ(e.configure(bad), Status::kBadCounts);
  EXPECT_TRUE(e.sample(1.3).index_seen);  // unchanged by the failed configure
}

TEST(SimEncoder, LinesAreQuadratureWithOneIndexPulsePerTurn) {
  // A and B: a Gray sequence (one line changes per count, A leading B
  // counting up), cpr edges per turn; Z: high over one count per turn, at
  // the index mark, the first crossing flagged.
  EncoderParams p;
  p.counts_per_rev = 400;
  p.has_index = true;
  p.index_angle_rad = 2.0;
  Encoder e;
  ASSERT_EQ(e.configure(p), Status::kOk);
  const double th0 = 0.7;
  e.reset(th0);
  mcsim::EncoderReading prev = e.sample(th0);
  EXPECT_EQ(prev.count, 0);  // counts from 0 at the power-up angle
  int edges = 0, z_samples = 0, crossings = 0;
  const double step = 2.0 * kPi / 400.0 / 16.0;  // 16 samples per count
  for (int k = 1; k <= 2 * 400 * 16; ++k) {      // two turns up
    const double th = th0 + k * step;
    const mcsim::EncoderReading r = e.sample(th);
    const int da = (r.a != prev.a) ? 1 : 0, db = (r.b != prev.b) ? 1 : 0;
    ASSERT_LE(da + db, 1) << "k=" << k;  // never both lines at once
    if (da + db == 1) {
      ++edges;
      // Counting up: the state advances (0,0) -> (1,0) -> (1,1) -> (0,1).
      const int q0 = prev.a ? (prev.b ? 2 : 1) : (prev.b ? 3 : 0);
      const int q1 = r.a ? (r.b ? 2 : 1) : (r.b ? 3 : 0);
      ASSERT_EQ(q1, (q0 + 1) % 4) << "k=" << k;
      ASSERT_EQ(r.count, prev.count + 1);
    }
    if (r.z) ++z_samples;
    if (r.index_crossed) {
      ++crossings;
      // Z rises at the mark: th just past 2.0 (mod 2 pi).
      const double past = std::fmod(th - 2.0 + 4.0 * kPi, 2.0 * kPi);
      EXPECT_LT(past, step + 1e-12);
      EXPECT_TRUE(r.z);
    }
    prev = r;
  }
  EXPECT_EQ(edges, 800);
  EXPECT_EQ(crossings, 2);
  EXPECT_NEAR(z_samples, 2 * 16, 2);  // one count wide, twice
}

TEST(SimEncoder, PowerUpAtAnyAngleCountsFromZeroThenIndexGivesTheAbsoluteAngle) {
  // Eight power-ups at random rotor angles: the count is 0 at power-up
  // whatever the angle; after the index the count in the turn is the
  // angle from the mark, the same at every power-up.
  EncoderParams p;
  p.counts_per_rev = 8192;
  p.has_index = true;
  p.index_angle_rad = 0.9;
  Encoder e;
  ASSERT_EQ(e.configure(p), Status::kOk);
  std::mt19937_64 rng(2024);
  std::uniform_real_distribution<double> u(0.0, 2.0 * kPi);
  for (int n = 0; n < 8; ++n) {
    const double th0 = u(rng);
    e.reset(th0);
    EXPECT_EQ(e.sample(th0).count, 0);
    EXPECT_FALSE(e.sample(th0).index_seen);
    // One turn forward in small steps passes the mark once.
    mcsim::EncoderReading r;
    for (int k = 1; k <= 1000; ++k) r = e.sample(th0 + 2.0 * kPi * k / 1000.0);
    EXPECT_TRUE(r.index_seen);
    const double from_mark = std::fmod(th0 - 0.9 + 2.0 * kPi, 2.0 * kPi);
    // The absolute count is floor(from_mark / step) (the same turn position).
    EXPECT_EQ(r.count_in_rev, static_cast<std::int32_t>(std::floor(from_mark * 8192 / (2 * kPi))))
        << "power-up " << n;
  }
}

}  // namespace
