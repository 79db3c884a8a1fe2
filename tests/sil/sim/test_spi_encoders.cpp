// SPI absolute encoders at the protocol level (mcsim/spi_encoders.hpp):
// the AS5047P's and the MA732's frames (parity of every frame, the
// pipelined responses, register reads and writes, error flags), their
// angles against the true shaft angle (resolution, latency, DAEC, the
// MagAlpha filter's response to a speed step in closed form), and the
// injected line errors (every one caught by parity, at the set rate,
// deterministic per seed).
#include <cmath>
#include <cstdint>
#include <vector>

#include <gtest/gtest.h>

#include "mcsim/spi_encoders.hpp"
#include "sim_test_util.hpp"

namespace {

using mcsim::As5047p;
using mcsim::As5047pParams;
using mcsim::Ma732;
using mcsim::Ma732Params;
using mcsim::Status;
using mcsim_test::kPi;

constexpr double kLsb14 = 2.0 * kPi / 16384.0;
constexpr double kLsb16 = 2.0 * kPi / 65536.0;

// Distance between two angles on the circle.
double ang_dist(double a, double b) {
  double d = std::fmod(a - b, 2.0 * kPi);
  if (d < 0.0) d += 2.0 * kPi;
  return std::min(d, 2.0 * kPi - d);
}

TEST(SimAs5047p, CommandFramesCarryEvenParity) {
  EXPECT_EQ(As5047p::read_command(0x3FFF), 0xFFFF);  // ANGLECOM: the usual 0xFFFF
  EXPECT_EQ(As5047p::read_command(0x0001), 0x4001);  // ERRFL: two ones, PARC 0
  EXPECT_EQ(As5047p::read_command(0x3FFC), 0xFFFC);  // DIAAGC: 13 ones, PARC 1
  EXPECT_EQ(As5047p::read_command(0x0000), 0xC000);
  EXPECT_EQ(As5047p::write_command(0x0018), 0x0018);
  EXPECT_EQ(As5047p::write_command(0x0016), 0x8016);
  EXPECT_TRUE(mcsim::spi_even_parity(0xFFFF, 16));
  EXPECT_FALSE(mcsim::spi_even_parity(0x7FFF, 16));
}

TEST(SimAs5047p, EveryFrameItSendsHasEvenParity) {
  // A mix of every readable register, writes and an invalid address over
  // a moving shaft: no frame the chip sends has odd parity.
  As5047p c;
  As5047pParams p;
  p.noise_rms_rad = 1.0e-3;
  ASSERT_EQ(c.configure(p), Status::kOk);
  const std::uint16_t regs[] = {0x0000, 0x0001, 0x0003, 0x0016, 0x0017, 0x0018,
                                0x0019, 0x3FFC, 0x3FFD, 0x3FFE, 0x3FFF, 0x0100};
  const double T = 50.0e-6;
  for (int k = 0; k < 20000; ++k) {
    const double t = k * T;
    ASSERT_EQ(c.observe(t, 100.0 * t, 100.0), Status::kOk);
    std::uint16_t mosi = As5047p::read_command(regs[k % 12]);
    if (k % 97 == 0) mosi = As5047p::write_command(As5047p::kSettings2);
    if (k % 97 == 1) mosi = As5047p::write_data(static_cast<std::uint16_t>(k & 0xFF));
    const std::uint16_t miso = c.transfer(mosi, t);
    ASSERT_TRUE(mcsim::spi_even_parity(miso, 16)) << "frame " << k;
  }
}

TEST(SimAs5047p, AngleAgainstTheTrueAngleWithLatencyAndDaec) {
  As5047pParams p;
  p.latency_s = 110.0e-6;
  p.mount_offset_rad = 0.3;
  p.direction = -1;
  As5047p c;
  ASSERT_EQ(c.configure(p), Status::kOk);
  const double T = 50.0e-6, w = 300.0;
  c.power_up(0.0, 1.0, w);
  // 0xFFFF every frame: frame k returns ANGLECOM latched at frame k-1.
  EXPECT_EQ(c.transfer(0xFFFF, 0.0), 0x0000);  // nothing latched before power-up
  for (int k = 1; k < 400; ++k) {
    const double t = k * T;
    ASSERT_EQ(c.observe(t, 1.0 + w * t, w), Status::kOk);
    const std::uint16_t miso = c.transfer(0xFFFF, t);
    ASSERT_EQ(miso & 0x4000, 0);  // no error flag
    const double got = (miso & 0x3FFF) * kLsb14;
    const double truth = -(1.0 + w * (t - T)) + 0.3;  // at the previous latch
    // DAEC: no lag at a constant speed; half an LSB of quantisation plus
    // rounding (1e-9 rad).
    ASSERT_LE(ang_dist(got, truth), 0.5 * kLsb14 + 1e-9) << "k=" << k;
  }
  // ANGLEUNC lags by w * latency = 0.033 rad (87 LSB).
  const double t1 = 400 * T;
  ASSERT_EQ(c.observe(t1, 1.0 + w * t1, w), Status::kOk);
  (void)c.transfer(As5047p::read_command(As5047p::kAngleUnc), t1);
  const double t2 = 401 * T;
  ASSERT_EQ(c.observe(t2, 1.0 + w * t2, w), Status::kOk);
  const double got = (c.transfer(0xFFFF, t2) & 0x3FFF) * kLsb14;
  EXPECT_LE(ang_dist(got, -(1.0 + w * (t1 - 110.0e-6)) + 0.3), 0.5 * kLsb14 + 1e-9);
}

TEST(SimAs5047p, DaecLeavesHalfAlphaLatencySquaredUnderAcceleration) {
  // theta = alpha t^2 / 2: extrapolating theta(t - L) with its speed gives
  // theta(t) - alpha L^2 / 2 = 1.2e-3 rad (3.2 LSB) at alpha = 2e5 rad/s^2.
  As5047pParams p;
  p.latency_s = 110.0e-6;
  As5047p c;
  ASSERT_EQ(c.configure(p), Status::kOk);
  const double a = 2.0e5, T = 25.0e-6, lat = p.latency_s;
  for (int k = 0; k <= 200; ++k) {
    const double t = k * T;
    ASSERT_EQ(c.observe(t, 0.5 * a * t * t, a * t), Status::kOk);
    if (k < 10) continue;  // the history reaches back past the latency
    const double want = 0.5 * a * t * t - 0.5 * a * lat * lat;
    // The Hermite history is exact for a parabola: half an LSB.
    ASSERT_LE(ang_dist(c.angle_code(t, true) * kLsb14, want), 0.5 * kLsb14 + 1e-9);
    ASSERT_LE(ang_dist(c.angle_code(t, false) * kLsb14, 0.5 * a * (t - lat) * (t - lat)),
              0.5 * kLsb14 + 1e-9);
  }
}

// Runs a write (command frame, data frame) and returns the two MISO words.
std::pair<std::uint16_t, std::uint16_t> write_reg(As5047p* c, std::uint16_t addr,
                                                  std::uint16_t value, double t) {
  const std::uint16_t a = c->transfer(As5047p::write_command(addr), t);
  const std::uint16_t b = c->transfer(As5047p::write_data(value), t);
  return {a, b};
}

TEST(SimAs5047p, ZeroPositionDirectionAndPowerUpRestoreTheOtp) {
  As5047pParams p;
  p.zposm = 0x12;  // OTP zero 0x12 << 6 = 1152
  As5047p c;
  ASSERT_EQ(c.configure(p), Status::kOk);
  const double th = 2.0;  // at rest
  c.power_up(0.0, th, 0.0);
  const auto raw = static_cast<std::uint16_t>(std::lround(th / kLsb14) & 0x3FFF);
  EXPECT_EQ(c.angle_code(0.0, true), (raw - 1152 + 16384) % 16384);
  // Write ZPOSM = 0x20, ZPOSL = 0x05: zero 0x20 << 6 | 5 = 2053. The write
  // answers with the old content in its data frame, the new in the next.
  const auto w1 = write_reg(&c, As5047p::kZposm, 0x20, 0.0);
  EXPECT_EQ(w1.second & 0x3FFF, 0x12);
  const auto w2 = write_reg(&c, As5047p::kZposl, 0x05, 0.0);
  EXPECT_EQ(w2.first & 0x3FFF, 0x20);  // the ZPOSM write's new content
  EXPECT_EQ(c.transfer(0xFFFF, 0.0) & 0x3FFF, 0x05);
  EXPECT_EQ(c.transfer(0xFFFF, 0.0) & 0x3FFF, (raw - 2053 + 16384) % 16384);
  // DIR negates the raw angle before the zero.
  (void)write_reg(&c, As5047p::kSettings1, As5047p::kDir, 0.0);
  EXPECT_EQ(c.angle_code(0.0, true), ((16384 - raw) % 16384 - 2053 + 16384) % 16384);
  // Power-up: the volatile registers from the OTP again.
  c.power_up(0.0, th, 0.0);
  EXPECT_EQ(c.angle_code(0.0, true), (raw - 1152 + 16384) % 16384);
}

TEST(SimAs5047p, ErrorFlagsParityInvalidCommandAndFraming) {
  As5047p c;
  ASSERT_EQ(c.configure(As5047pParams{}), Status::kOk);
  // A command with a wrong parity bit: not executed, PARERR, EF set in the
  // following frames until ERRFL is read.
  (void)c.transfer(0xFFFE, 0.0);  // read 0x3FFE with PARC wrong
  EXPECT_EQ(c.errfl(), As5047p::kParerr);
  std::uint16_t m = c.transfer(As5047p::read_command(As5047p::kErrfl), 0.0);
  EXPECT_EQ(m & 0x3FFF, 0);     // the bad command's (non-)answer
  EXPECT_NE(m & 0x4000, 0);     // EF
  m = c.transfer(0xFFFF, 0.0);  // ERRFL's content; reading cleared it
  EXPECT_EQ(m & 0x3FFF, As5047p::kParerr);
  EXPECT_EQ(c.errfl(), 0);
  m = c.transfer(0xFFFF, 0.0);
  EXPECT_EQ(m & 0x4000, 0);
  // Invalid address, write to a read-only register, a 15-clock frame.
  (void)c.transfer(As5047p::read_command(0x0100), 0.0);
  EXPECT_EQ(c.errfl(), As5047p::kInvcomm);
  (void)c.transfer(As5047p::write_command(As5047p::kAngleCom), 0.0);
  (void)c.transfer(0xFFFF, 0.0, 15);
  EXPECT_EQ(c.errfl(), As5047p::kInvcomm | As5047p::kFrerr);
  // Magnet diagnostics in DIAAGC: LF (bit 8) always, MAGL / MAGH on a fault.
  (void)c.transfer(As5047p::read_command(As5047p::kDiaagc), 0.0);
  EXPECT_EQ(c.transfer(0xFFFF, 0.0) & 0x0F00, 0x0100);
  c.set_magnet_fault(mcsim::MagnetFault::kTooWeak);
  (void)c.transfer(As5047p::read_command(As5047p::kDiaagc), 0.0);
  EXPECT_EQ(c.transfer(0xFFFF, 0.0) & 0x0F00, 0x0900);
  c.set_magnet_fault(mcsim::MagnetFault::kTooStrong);
  (void)c.transfer(As5047p::read_command(As5047p::kDiaagc), 0.0);
  EXPECT_EQ(c.transfer(0xFFFF, 0.0) & 0x0F00, 0x0500);
}

TEST(SimAs5047p, LineErrorsAreCaughtByParityAtTheSetRateAndRepeatPerSeed) {
  As5047pParams p;
  p.line.miso_error_rate = 0.02;
  p.line.seed = 42;
  As5047p a, b, d;
  ASSERT_EQ(a.configure(p), Status::kOk);
  ASSERT_EQ(b.configure(p), Status::kOk);
  p.line.seed = 43;
  ASSERT_EQ(d.configure(p), Status::kOk);
  const int n = 50000;
  int odd = 0, differ = 0;
  for (int k = 0; k < n; ++k) {
    const double t = k * 50.0e-6;
    for (As5047p* c : {&a, &b, &d}) ASSERT_EQ(c->observe(t, 50.0 * t, 50.0), Status::kOk);
    const std::uint16_t ma = a.transfer(0xFFFF, t);
    ASSERT_EQ(b.transfer(0xFFFF, t), ma);  // same seed: the same frames
    if (d.transfer(0xFFFF, t) != ma) ++differ;
    if (!mcsim::spi_even_parity(ma, 16)) ++odd;
  }
  // Every single-bit flip shows as odd parity.
  EXPECT_EQ(static_cast<std::uint64_t>(odd), a.counters().miso_flips);
  // At the rate: 0.02 +- 5 sigma of the binomial (sigma = 6.3e-4).
  EXPECT_NEAR(static_cast<double>(odd) / n, 0.02, 5.0 * std::sqrt(0.02 * 0.98 / n));
  EXPECT_GT(differ, 0);  // another seed, other errors
  // Received-side errors: every corrupted command is a PARERR.
  As5047pParams q;
  q.line.mosi_error_rate = 1.0;
  As5047p e;
  ASSERT_EQ(e.configure(q), Status::kOk);
  (void)e.transfer(0xFFFF, 0.0);
  EXPECT_EQ(e.errfl(), As5047p::kParerr);
  EXPECT_EQ(e.counters().mosi_flips, 1U);
}

// ------------------------------------------------------------------ MA732

Ma732Params quiet_ma732() {
  Ma732Params p;
  p.noise_from_filter = false;
  p.noise_rms_rad = 0.0;
  return p;
}

TEST(SimMa732, FilterTableAndCommandFrames) {
  EXPECT_DOUBLE_EQ(Ma732::filter_tau_s(51), 64.0e-6);
  EXPECT_DOUBLE_EQ(Ma732::filter_tau_s(119), 1024.0e-6);
  EXPECT_DOUBLE_EQ(Ma732::filter_tau_s(187), 16384.0e-6);
  EXPECT_DOUBLE_EQ(Ma732::resolution_bits(51), 9.0);
  EXPECT_DOUBLE_EQ(Ma732::resolution_bits(119), 11.0);
  EXPECT_DOUBLE_EQ(Ma732::resolution_bits(187), 13.0);
  EXPECT_EQ(Ma732::read_command(0x0E), 0x4E00);
  EXPECT_EQ(Ma732::write_command(0x00, 0x12), 0x8012);
}

TEST(SimMa732, NoLagAtConstantSpeedBeyondItsLatency) {
  Ma732Params p = quiet_ma732();
  p.latency_s = 3.0e-6;
  p.mount_offset_rad = -0.4;
  Ma732 c;
  ASSERT_EQ(c.configure(p), Status::kOk);
  const double w = 250.0, T = 50.0e-6;
  c.power_up(0.0, 0.2, w);  // converged on the motion at power-up
  for (int k = 1; k < 2000; ++k) {
    const double t = k * T;
    ASSERT_EQ(c.observe(t, 0.2 + w * t, w), Status::kOk);
    const std::uint32_t code = c.transfer(0x0000, t);
    // A ramp is the type-2 loop's exact steady state (RK4 is exact on it):
    // half an LSB plus rounding.
    ASSERT_LE(ang_dist(code * kLsb16, 0.2 + w * (t - 3.0e-6) - 0.4), 0.5 * kLsb16 + 1e-9)
        << "k=" << k;
  }
}

TEST(SimMa732, SpeedStepErrorDecaysAsTheFilterTimeConstantSays) {
  // A speed step dw at t0: the double-pole tracking loop's error is
  // e(t) = dw (t - t0) e^(-(t - t0) / tau), peak dw tau / e at tau.
  for (const std::uint8_t fw : {std::uint8_t{119}, std::uint8_t{68}}) {
    Ma732Params p = quiet_ma732();
    p.latency_s = 0.0;
    p.regs[Ma732::kFw] = fw;
    Ma732 c;
    ASSERT_EQ(c.configure(p), Status::kOk);
    const double tau = Ma732::filter_tau_s(fw), dw = 100.0, t0 = 1.0e-3, h = 5.0e-6;
    c.power_up(0.0, 0.0, 0.0);
    double worst = 0.0, peak = 0.0;
    for (int k = 1; k <= static_cast<int>((t0 + 8.0 * tau) / h); ++k) {
      const double t = k * h;
      const double th = (t > t0) ? dw * (t - t0) : 0.0;
      // The sample at the step carries the new speed (exact for t > t0).
      ASSERT_EQ(c.observe(t, th, (t >= t0) ? dw : 0.0), Status::kOk);
      const double e = (t > t0) ? dw * (t - t0) * std::exp(-(t - t0) / tau) : 0.0;
      const double got = c.transfer(0x0000, t) * kLsb16;
      worst = std::max(worst, ang_dist(got, th - e));
      peak = std::max(peak, e);
    }
    // Half an LSB, RK4 at tau / 8 (~1e-6 of the peak), and the step's
    // instant falling between samples (the Hermite segment straddling t0
    // bends the input over 5 us: dw h^2 / tau ~ 2.5e-6 rad at tau = 1 ms,
    // 2e-5 rad at 128 us): bound 0.5 LSB + 3e-5 rad.
    EXPECT_LE(worst, 0.5 * kLsb16 + 3.0e-5) << "FW " << int{fw};
    EXPECT_NEAR(peak, dw * tau / std::exp(1.0), 1e-3 * dw * tau) << "FW " << int{fw};
  }
}

TEST(SimMa732, RegisterReadWriteZeroDirectionAndFrameLengths) {
  Ma732 c;
  ASSERT_EQ(c.configure(quiet_ma732()), Status::kOk);
  const double th = 1.0;
  c.power_up(0.0, th, 0.0);
  const auto raw = static_cast<std::uint32_t>(std::lround(th / kLsb16));
  // Read FW: this frame the angle, the next the register << 8.
  EXPECT_EQ(c.transfer(Ma732::read_command(Ma732::kFw), 0.0), raw);
  EXPECT_EQ(c.transfer(0x0000, 0.0), 119U << 8U);
  EXPECT_EQ(c.transfer(0x0000, 0.0), raw);
  // Write the zero 0x1234: each write echoes the new value next frame.
  (void)c.transfer(Ma732::write_command(Ma732::kZLow, 0x34), 0.0);
  EXPECT_EQ(c.transfer(Ma732::write_command(Ma732::kZHigh, 0x12), 0.0), 0x3400U);
  EXPECT_EQ(c.transfer(0x0000, 0.0), 0x1200U);
  EXPECT_EQ(c.transfer(0x0000, 0.0), (raw - 0x1234U) & 0xFFFFU);
  // RD negates the direction.
  (void)c.transfer(Ma732::write_command(Ma732::kRd, 0x80), 0.0);
  (void)c.transfer(0x0000, 0.0);
  EXPECT_EQ(c.transfer(0x0000, 0.0), ((0x10000U - raw) - 0x1234U) & 0xFFFFU);
  // 8 clocks: the top byte, no command executed (the read is ignored).
  const std::uint32_t full = c.transfer(0x0000, 0.0);
  EXPECT_EQ(c.transfer(Ma732::read_command(Ma732::kFw), 0.0, 8), full >> 8U);
  EXPECT_EQ(c.transfer(0x0000, 0.0), full);
  // 17 clocks: the word and its even-parity bit.
  const std::uint32_t w17 = c.transfer(0x0000, 0.0, 17);
  EXPECT_EQ(w17 >> 1U, full);
  EXPECT_TRUE(mcsim::spi_even_parity(w17, 17));
  // Another length: nothing.
  EXPECT_EQ(c.transfer(0x0000, 0.0, 12), 0U);
  // Magnet diagnostics in 0x1B.
  c.set_magnet_fault(mcsim::MagnetFault::kTooStrong);
  (void)c.transfer(Ma732::read_command(Ma732::kStatus), 0.0);
  EXPECT_EQ(c.transfer(0x0000, 0.0), static_cast<std::uint32_t>(Ma732::kMgh) << 8U);
  // Power-up restores the NVM contents (zero, direction).
  c.power_up(0.0, th, 0.0);
  EXPECT_EQ(c.transfer(0x0000, 0.0), raw);
}

TEST(SimMa732, NoiseFollowsTheFilterAndParityCatchesLineErrors) {
  Ma732Params p;  // noise from FW = 119: 11 bits at 3 sigma
  p.line.miso_error_rate = 0.05;
  p.line.seed = 9;
  Ma732 c;
  ASSERT_EQ(c.configure(p), Status::kOk);
  c.power_up(0.0, 3.0, 0.0);
  const double sigma = 2.0 * kPi / 2048.0 / 3.0;
  EXPECT_NEAR(c.noise_rms_rad(), sigma, 1e-15);
  const int n = 20000;
  double s1 = 0.0, s2 = 0.0;
  int odd = 0;
  for (int k = 0; k < n; ++k) {
    const std::uint32_t w = c.transfer(0x0000, 0.0, 17);
    if (!mcsim::spi_even_parity(w, 17)) {
      ++odd;
      continue;
    }
    const double d = std::remainder((w >> 1U) * kLsb16 - 3.0, 2.0 * kPi);
    s1 += d;
    s2 += d * d;
  }
  EXPECT_EQ(static_cast<std::uint64_t>(odd), c.counters().miso_flips);
  EXPECT_NEAR(static_cast<double>(odd) / n, 0.05, 5.0 * std::sqrt(0.05 * 0.95 / n));
  const int m = n - odd;
  const double sd = std::sqrt(s2 / m - (s1 / m) * (s1 / m));
  // The sample's spread: 1/sqrt(2m) = 0.5 % per sigma; quantisation adds
  // LSB^2 / 12 (0.07 %). Bound 3 %.
  EXPECT_NEAR(sd / sigma, 1.0, 0.03);
  EXPECT_NEAR(s1 / m, 0.0, 5.0 * sigma / std::sqrt(m) + 0.5 * kLsb16);
}

TEST(SimSpiEncoders, InvalidParametersAreRefused) {
  As5047p a;
  As5047pParams p;
  p.line.miso_error_rate = 1.5;
  EXPECT_EQ(a.configure(p), Status::kBadSensor);
  p.line.miso_error_rate = 0.0;
  p.direction = 0;
  EXPECT_EQ(a.configure(p), Status::kBadSensor);
  p.direction = 1;
  p.zposm = 0x100;
  EXPECT_EQ(a.configure(p), Status::kBadSensor);
  p.zposm = 0;
  p.latency_s = NAN;
  EXPECT_EQ(a.configure(p), Status::kNotFinite);
  Ma732 m;
  Ma732Params q;
  q.latency_s = 2.0e-3;
  EXPECT_EQ(m.configure(q), Status::kBadSensor);
  q.latency_s = 0.0;
  q.noise_rms_rad = -1.0;
  EXPECT_EQ(m.configure(q), Status::kBadSensor);
  // Time going backwards is refused.
  ASSERT_EQ(m.configure(Ma732Params{}), Status::kOk);
  ASSERT_EQ(m.observe(1.0e-3, 0.0, 0.0), Status::kOk);
  EXPECT_EQ(m.observe(0.5e-3, 0.0, 0.0), Status::kBadPeriod);
}

}  // namespace
