// The SPI encoder drivers (hal/spienc) on the plant's chip models
// (mcsim::As5047p, mcsim::Ma732: written from the same datasheets by
// another hand): each PWM period the shaft moves, the driver makes its one
// frame and reports a count; the count must be the shaft's angle at the
// instant its latency names, within the chip's resolution; injected line
// errors must be caught (never reported as an angle).
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "mc_as5047p.h"
#include "mc_ma732.h"
#include "mcsim/spi_encoders.hpp"

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kT = 50e-6;       // PWM period (20 kHz)
constexpr double kFrame = 3.2e-6;  // the frame after the period's start (16 clocks at 5.25 MHz)

// The shaft: theta0 + w0 t + a t^2 / 2.
struct Shaft {
  double th0 = 0.7, w0 = 0.0, a = 0.0;
  double th(double t) const { return th0 + w0 * t + 0.5 * a * t * t; }
  double w(double t) const { return w0 + a * t; }
};

double wrap_pi(double x) {
  double w = std::fmod(x + kPi, 2.0 * kPi);
  if (w < 0.0) {
    w += 2.0 * kPi;
  }
  return w - kPi;
}

// The chips on the SPI capability: a frame at the adapter's present time.
struct As5047pBus {
  mcsim::As5047p chip;
  double t_end = 0.0;  // CSn rising of the next frame
  mc_hal_spi_t dev{&ops, this};
  static int t16(void* ctx, uint16_t tx, uint16_t* p_rx) {
    auto* b = static_cast<As5047pBus*>(ctx);
    const uint16_t rx = b->chip.transfer(tx, b->t_end, 16);
    if (p_rx != nullptr) {
      *p_rx = rx;
    }
    return 0;
  }
  static inline const mc_hal_spi_ops_t ops = {&As5047pBus::t16, nullptr};
};

struct Ma732Bus {
  mcsim::Ma732 chip;
  double t_start = 0.0;  // CS falling of the next frame
  mc_hal_spi_t dev{&ops, this};
  static int t16(void* ctx, uint16_t tx, uint16_t* p_rx) {
    auto* b = static_cast<Ma732Bus*>(ctx);
    const uint32_t rx = b->chip.transfer(tx, b->t_start, 16);
    if (p_rx != nullptr) {
      *p_rx = static_cast<uint16_t>(rx);
    }
    return 0;
  }
  // 32 clocks: the model knows 16 + the parity clock (17); the clocks
  // after the 17th carry nothing the driver reads (MPS: ignored).
  static int t32(void* ctx, uint32_t tx, uint32_t* p_rx) {
    auto* b = static_cast<Ma732Bus*>(ctx);
    const uint32_t w17 = b->chip.transfer(static_cast<uint16_t>(tx >> 16), b->t_start, 17);
    if (p_rx != nullptr) {
      *p_rx = w17 << 15;
    }
    return 0;
  }
  static inline const mc_hal_spi_ops_t ops = {&Ma732Bus::t16, &Ma732Bus::t32};
};

struct Trace {
  std::vector<mc_hal_encoder_sample_t> s;
  std::vector<double> truth;  // the shaft at the latency's instant
};

// n periods: observe the shaft at t_k, one read; truth[k] = the shaft at
// t_k + lag (lag < 0: in the past).
template <typename Bus, typename Drv>
Trace run(Bus& bus, Drv& drv, const Shaft& sh, int n, double lag, double frame_offset,
          double* p_t_field) {
  Trace r;
  for (int k = 0; k < n; ++k) {
    const double t = k * kT;
    EXPECT_EQ(bus.chip.observe(t, sh.th(t), sh.w(t)), mcsim::Status::kOk);
    *p_t_field = t + frame_offset;
    mc_hal_encoder_sample_t s{};
    EXPECT_EQ(mc_hal_encoder_read(&drv.dev, &s), 0);
    r.s.push_back(s);
    r.truth.push_back(sh.th(t + lag));
  }
  return r;
}

double count_rad(const mc_hal_encoder_sample_t& s) {
  return 2.0 * kPi * s.count / s.counts_per_rev;
}

mc_as5047p_t as5047p_on(As5047pBus& bus, bool daec, uint32_t diag) {
  mc_as5047p_t d{};
  mc_as5047p_config_t c{};
  c.p_spi = &bus.dev;
  c.daec = daec;
  c.bad_reads_max = MC_SPIENC_BAD_READS_DEFAULT;
  c.diag_period = diag;
  EXPECT_EQ(mc_as5047p_init(&d, &c), 0);
  return d;
}

}  // namespace

// DAEC on: the count is the shaft one period (plus the frame offset)
// before the read, within half a 14-bit LSB, at a constant speed and under
// acceleration (DAEC extrapolates over the chip's 110 us with the speed:
// a (110 us)^2 / 2 off under an acceleration a). DAEC off: the chip's
// 110 us more.
TEST(SpiEncoderSil, As5047pAngleWithinResolutionAndLatency) {
  for (const bool daec : {true, false}) {
    for (const double acc : {0.0, 2000.0}) {
      As5047pBus bus;
      mcsim::As5047pParams p;
      ASSERT_EQ(bus.chip.configure(p), mcsim::Status::kOk);
      Shaft sh;
      sh.w0 = 150.0;  // 1430 rpm
      sh.a = acc;
      bus.chip.power_up(0.0, sh.th(0.0), sh.w(0.0));
      auto d = as5047p_on(bus, daec, MC_AS5047P_DIAG_PERIOD_DEFAULT);
      ASSERT_EQ(mc_as5047p_probe(&d), 0);
      // latency: the previous frame's end, minus the chip's delay without DAEC
      const double lag = -kT + kFrame - (daec ? 0.0 : p.latency_s);
      const Trace r = run(bus, d, sh, 4000, lag, kFrame, &bus.t_end);
      const double lsb = 2.0 * kPi / 16384.0;
      // 0.5 LSB rounding, DAEC's a L^2 / 2, float of the reference: 1e-9
      const double tol = 0.5 * lsb + 0.5 * acc * p.latency_s * p.latency_s + 1e-9;
      double emax = 0.0;
      int valid = 0;
      // read 0 returns the angle the probe's last frame latched (at 0)
      for (size_t k = 1; k < r.s.size(); ++k) {
        ASSERT_NE(r.s[k].flags & MC_HAL_ENCODER_FLAG_VALID, 0u) << k;
        ++valid;
        // a held read (the periodic DIAAGC) repeats the previous count
        const bool held = (k > 1) && (r.s[k].count == r.s[k - 1].count);
        const double want = held ? r.truth[k - 1] : r.truth[k];
        emax = std::fmax(emax, std::fabs(wrap_pi(count_rad(r.s[k]) - want)));
      }
      EXPECT_GT(valid, 3990);
      EXPECT_LE(emax, tol) << "daec " << daec << " acc " << acc;
      EXPECT_EQ(d.hold.n_bad, 0u);
      EXPECT_EQ(d.hold.err_seen, 0u);
    }
  }
}

// Bits flipped on MISO (2 % of the frames): every one is a parity error,
// held; no count a flipped frame carried is ever reported.
TEST(SpiEncoderSil, As5047pMisoParityErrorsAreAllCaught) {
  As5047pBus bus;
  mcsim::As5047pParams p;
  p.line.miso_error_rate = 0.02;
  p.line.seed = 11u;
  ASSERT_EQ(bus.chip.configure(p), mcsim::Status::kOk);
  Shaft sh;
  sh.w0 = -80.0;
  bus.chip.power_up(0.0, sh.th(0.0), sh.w(0.0));
  auto d = as5047p_on(bus, true, 0u);
  ASSERT_EQ(mc_as5047p_probe(&d), 0);
  const uint64_t flips0 = bus.chip.counters().miso_flips;
  const Trace r = run(bus, d, sh, 20000, -kT + kFrame, kFrame, &bus.t_end);
  const uint64_t flips = bus.chip.counters().miso_flips - flips0;
  ASSERT_GT(flips, 300u);  // 2 % of 20000
  EXPECT_EQ(d.hold.n_bad, flips);
  EXPECT_EQ(d.hold.err_seen, MC_SPIENC_ERR_PARITY);
  const double tol = 0.5 * 2.0 * kPi / 16384.0 + 1e-9;
  uint32_t run_bad = 0u;
  for (size_t k = 2; k < r.s.size(); ++k) {
    const double fresh = std::fabs(wrap_pi(count_rad(r.s[k]) - r.truth[k]));
    if (fresh <= tol) {
      run_bad = 0u;
      ASSERT_NE(r.s[k].flags, 0u);
      continue;
    }
    // not fresh: held, and the hold rule's VALID
    ASSERT_EQ(r.s[k].count, r.s[k - 1].count) << k;
    ++run_bad;
    const bool valid = (r.s[k].flags & MC_HAL_ENCODER_FLAG_VALID) != 0u;
    EXPECT_EQ(valid, run_bad < MC_SPIENC_BAD_READS_DEFAULT) << k;
  }
}

// Bits flipped on MOSI (1 %): the chip sees a command with a parity
// error, answers with EF until ERRFL is read; the driver reads ERRFL and
// names the chip's PARERR; no wrong angle is reported.
TEST(SpiEncoderSil, As5047pMosiErrorsAreNamedByErrfl) {
  As5047pBus bus;
  mcsim::As5047pParams p;
  p.line.mosi_error_rate = 0.01;
  p.line.seed = 5u;
  ASSERT_EQ(bus.chip.configure(p), mcsim::Status::kOk);
  Shaft sh;
  sh.w0 = 40.0;
  bus.chip.power_up(0.0, sh.th(0.0), sh.w(0.0));
  auto d = as5047p_on(bus, true, 0u);
  ASSERT_EQ(mc_as5047p_probe(&d), 0);
  const Trace r = run(bus, d, sh, 20000, -kT + kFrame, kFrame, &bus.t_end);
  ASSERT_GT(bus.chip.counters().mosi_flips, 100u);
  EXPECT_NE(d.hold.err_seen & MC_SPIENC_ERR_CHIP, 0u);
  EXPECT_NE(d.hold.err_seen & MC_SPIENC_ERR_CHIP_PARERR, 0u);
  EXPECT_EQ(d.hold.err_seen & MC_SPIENC_ERR_PARITY, 0u);  // MISO is clean
  const double tol = 0.5 * 2.0 * kPi / 16384.0 + 1e-9;
  for (size_t k = 2; k < r.s.size(); ++k) {
    const double fresh = std::fabs(wrap_pi(count_rad(r.s[k]) - r.truth[k]));
    if (fresh > tol) {
      ASSERT_EQ(r.s[k].count, r.s[k - 1].count) << k;  // held, never wrong
    }
  }
}

// The line dies at read k0 (every MISO bit error): the last angle is held
// and VALID through read k0 + N - 2; read k0 + N - 1 is not VALID: the
// drive's ENCODER fault (N - 1) periods after the first bad read.
TEST(SpiEncoderSil, As5047pNBadReadsInARowInvalidateWithinTheStatedLatency) {
  As5047pBus bus;
  mcsim::As5047pParams p;
  ASSERT_EQ(bus.chip.configure(p), mcsim::Status::kOk);
  Shaft sh;
  sh.w0 = 100.0;
  bus.chip.power_up(0.0, sh.th(0.0), sh.w(0.0));
  auto d = as5047p_on(bus, true, 0u);
  ASSERT_EQ(mc_as5047p_probe(&d), 0);
  (void)run(bus, d, sh, 100, -kT + kFrame, kFrame, &bus.t_end);
  const uint32_t held = d.hold.code;
  p.line.miso_error_rate = 1.0;
  ASSERT_EQ(bus.chip.configure(p), mcsim::Status::kOk);  // same chip, a bad line
  bus.chip.power_up(100 * kT, sh.th(100 * kT), sh.w(100 * kT));
  for (uint32_t k = 0; k < MC_SPIENC_BAD_READS_DEFAULT; ++k) {
    const double t = (100 + k) * kT;
    ASSERT_EQ(bus.chip.observe(t, sh.th(t), sh.w(t)), mcsim::Status::kOk);
    bus.t_end = t + kFrame;
    mc_hal_encoder_sample_t s{};
    ASSERT_EQ(mc_hal_encoder_read(&d.dev, &s), 0);
    EXPECT_EQ(s.count, held);
    const bool valid = (s.flags & MC_HAL_ENCODER_FLAG_VALID) != 0u;
    EXPECT_EQ(valid, k + 1u < MC_SPIENC_BAD_READS_DEFAULT) << k;
  }
}

// The magnet falls off: the chip's angles are noise with a valid parity;
// the periodic DIAAGC read (every 50 reads) shows MAGL; from then on
// every read is bad until the field is back: not VALID within 50 + N
// reads.
TEST(SpiEncoderSil, As5047pMagnetLossIsFoundByTheDiagnostic) {
  As5047pBus bus;
  mcsim::As5047pParams p;
  ASSERT_EQ(bus.chip.configure(p), mcsim::Status::kOk);
  Shaft sh;
  sh.w0 = 30.0;
  bus.chip.power_up(0.0, sh.th(0.0), sh.w(0.0));
  auto d = as5047p_on(bus, true, 50u);
  ASSERT_EQ(mc_as5047p_probe(&d), 0);
  (void)run(bus, d, sh, 200, -kT + kFrame, kFrame, &bus.t_end);
  bus.chip.set_magnet_fault(mcsim::MagnetFault::kTooWeak);
  int first_invalid = -1;
  for (int k = 0; k < 200 && first_invalid < 0; ++k) {
    const double t = (200 + k) * kT;
    ASSERT_EQ(bus.chip.observe(t, sh.th(t), sh.w(t)), mcsim::Status::kOk);
    bus.t_end = t + kFrame;
    mc_hal_encoder_sample_t s{};
    ASSERT_EQ(mc_hal_encoder_read(&d.dev, &s), 0);
    if ((s.flags & MC_HAL_ENCODER_FLAG_VALID) == 0u) {
      first_invalid = k;
    }
  }
  ASSERT_GE(first_invalid, 0);
  // a DIAAGC command within 50 reads, its answer one read later, then N
  // bad reads (the answer's own read counts)
  EXPECT_LE(first_invalid, 50 + 1 + static_cast<int>(MC_SPIENC_BAD_READS_DEFAULT));
  EXPECT_NE(d.hold.err_seen & MC_SPIENC_ERR_MAGNET, 0u);
}

namespace {

mc_ma732_t ma732_on(Ma732Bus& bus, bool parity) {
  mc_ma732_t d{};
  mc_ma732_config_t c{};
  c.p_spi = &bus.dev;
  c.parity = parity;
  c.bad_reads_max = MC_SPIENC_BAD_READS_DEFAULT;
  c.diag_period = 0u;
  EXPECT_EQ(mc_ma732_init(&d, &c), 0);
  return d;
}

}  // namespace

// MA732, 32-clock frames with parity: the angle at the frame's start less
// the chip's 3 us; at a constant speed within half a 16-bit LSB (the
// filter tracks a ramp without lag); under an acceleration a its type-2
// filter lags by a tau^2 (tau 1.024 ms at FW 119).
TEST(SpiEncoderSil, Ma732AngleWithinResolutionAndLatency) {
  for (const double acc : {0.0, 500.0}) {
    Ma732Bus bus;
    mcsim::Ma732Params p;
    p.noise_from_filter = false;  // resolution: the code, not the noise
    ASSERT_EQ(bus.chip.configure(p), mcsim::Status::kOk);
    Shaft sh;
    sh.w0 = -120.0;
    sh.a = acc;
    bus.chip.power_up(0.0, sh.th(0.0), sh.w(0.0));
    auto d = ma732_on(bus, true);
    ASSERT_EQ(mc_ma732_probe(&d), 0);
    const Trace r = run(bus, d, sh, 4000, -p.latency_s, 0.0, &bus.t_start);
    const double tau = mcsim::Ma732::filter_tau_s(119u);
    // 0.5 LSB of 2^16, the lag a tau^2 (its transient decays from 0
    // up to it), the RK4 filter's error 1e-9
    const double tol = 0.5 * 2.0 * kPi / 65536.0 + acc * tau * tau + 1e-9;
    double emax = 0.0;
    for (size_t k = 0; k < r.s.size(); ++k) {
      ASSERT_NE(r.s[k].flags & MC_HAL_ENCODER_FLAG_VALID, 0u) << k;
      emax = std::fmax(emax, std::fabs(wrap_pi(count_rad(r.s[k]) - r.truth[k])));
    }
    EXPECT_LE(emax, tol) << acc;
    EXPECT_EQ(d.hold.n_bad, 0u);
  }
}

// MISO flips in 17-bit frames: every one a parity error (held). In 16-bit
// frames (no parity) the same flips pass unseen: the reason the board uses
// 32-clock frames for the MA732.
TEST(SpiEncoderSil, Ma732ParityCatchesWhat16BitFramesCannot) {
  for (const bool parity : {true, false}) {
    Ma732Bus bus;
    mcsim::Ma732Params p;
    p.noise_from_filter = false;
    p.line.miso_error_rate = 0.02;
    p.line.seed = 3u;
    ASSERT_EQ(bus.chip.configure(p), mcsim::Status::kOk);
    Shaft sh;
    sh.w0 = 60.0;
    bus.chip.power_up(0.0, sh.th(0.0), sh.w(0.0));
    auto d = ma732_on(bus, parity);
    const Trace r = run(bus, d, sh, 10000, -p.latency_s, 0.0, &bus.t_start);
    const uint64_t flips = bus.chip.counters().miso_flips;
    ASSERT_GT(flips, 150u);
    const double tol = 0.5 * 2.0 * kPi / 65536.0 + 1e-9;
    uint64_t wrong = 0u;
    for (size_t k = 1; k < r.s.size(); ++k) {
      const double e = std::fabs(wrap_pi(count_rad(r.s[k]) - r.truth[k]));
      if (e > tol && r.s[k].count != r.s[k - 1].count) {
        ++wrong;  // a fresh count that is not the shaft's
      }
    }
    if (parity) {
      EXPECT_EQ(d.hold.n_bad, flips);
      EXPECT_EQ(wrong, 0u);
    } else {
      EXPECT_EQ(d.hold.n_bad, 0u);
      EXPECT_GT(wrong, flips / 2u);  // most flips reach the drive as angles
    }
  }
}
