// mcsim/spi_encoders.hpp: absolute magnetic angle encoders read over SPI,
// modelled at the protocol level as the chips answer, so that a firmware
// driver written against the same datasheets can be run against them
// (issue 32 item 2): ams AS5047P and MPS MagAlpha MA732. Independent of
// the firmware; every random draw deterministic per seed (GaussianRng).
//
// Time: the caller tells the chip how the shaft moves (observe(t, theta_m,
// omega_m), at least once per PWM period, times non-decreasing) and runs
// SPI frames (transfer(mosi, t)). The chip keeps the recent motion (a ring
// of kHistory samples, cubic Hermite between them, exact for a constant
// acceleration) and evaluates it at the instants its signal path sees.
// The magnet's angle is dir theta_m + mount_offset_rad.
//
// Noise and protocol errors: angle noise N(0, noise_rms_rad^2) per latched
// reading; with probability miso_error_rate a frame the chip sends has one
// bit flipped on the line (uniform bit), with mosi_error_rate the chip
// receives the command with one bit flipped. Parity (AS5047P always, MA732
// with a 17-bit frame) detects every such single-bit error.
//
// ---------------------------------------------------------------- AS5047P
// Frames (ams AS5047P datasheet, "SPI Interface"; the same command / read
// data / write data scheme as the family's AS5055A datasheet v2-06 Figures
// 15-19 and AS5050's, which carry it with other bit positions; the
// positions and register map below are the AS5047P's as public drivers use
// them: moteus' fw/as5047.h (commit 1f4a195, 0xFFFF reads ANGLECOM, 14
// data bits), SimpleFOC's Arduino-FOC-drivers AS5047 register layout):
//   command    bit 15 PARC (even parity of bits 14:0), bit 14 R/W (1 read),
//              bits 13:0 address
//   read data  bit 15 PARD (even parity of bits 14:0), bit 14 EF (error
//              flag), bits 13:0 data
//   write data bit 15 PARD, bit 14 0, bits 13:0 data
// 16-bit frames, SPI mode 1, MSB first. Pipelined: the register addressed
// by a read command is latched at the end of that frame (CSn rising: the
// t of transfer()) and shifted out in the next frame; a write command
// answers with the register's old content in the next frame (which carries
// the data) and with the new content in the one after. So 0xFFFF (read
// ANGLECOM, parity set) sent every frame returns the angle latched one
// frame earlier.
// Registers: NOP 0x0000, ERRFL 0x0001 (bit 0 FRERR framing, bit 1 INVCOMM
// invalid command, bit 2 PARERR parity; cleared by reading it), PROG
// 0x0003, ZPOSM 0x0016 (zero position bits 13:6), ZPOSL 0x0017 (bits 5:0
// zero bits 5:0, bits 6, 7 error enables), SETTINGS1 0x0018 (bit 0 factory
// 1, bit 2 DIR, bit 4 DAECDIS, bit 6 Dataselect), SETTINGS2 0x0019, DIAAGC
// 0x3FFC (bit 11 MAGL, 10 MAGH, 9 COF, 8 LF, 7:0 AGC), MAG 0x3FFD, ANGLEUNC
// 0x3FFE (no compensation), ANGLECOM 0x3FFF (with DAEC; without it when
// DAECDIS or Dataselect is set). The writable registers are volatile
// copies of the OTP: power_up() restores the OTP values of the parameters.
// Angle: 14 bits, code = round(2^14 a / 2 pi) mod 2^14 of the magnet angle
// a seen latency_s before the latch, DIR negating it, the zero position
// subtracted. DAEC (dynamic angle error compensation) extrapolates over
// the latency with the speed at that instant: a + w latency, exact at a
// constant speed, 1/2 alpha latency^2 off under an acceleration alpha.
// Modelling choices where the datasheet is not explicit to us: EF is set
// while ERRFL holds an error (until ERRFL is read); a command with a
// parity error is not executed and answered with data 0; a read of an
// unknown address or a write to a read-only one is INVCOMM with data 0; a
// frame of other than 16 bits is FRERR; a write command to NOP (the 0x0000
// frame) is a no-operation without a data frame.
// latency_s default 110 us: the datasheet's system propagation delay of the
// absolute interface without DAEC, as we read it; noise default 0 (the
// datasheet's figure is for the user to set). Verify both against the
// datasheet revision at hand.
//
// ------------------------------------------------------------------ MA732
// Frames (MPS MA732 datasheet, "SPI"; the command format as public drivers
// use it: moteus' fw/ma732.h, commit 1f4a195, and unhuman's motorlib MA732
// driver (3-bit command, 5-bit address, 8-bit value; 20 ms after a write)):
//   angle read   MOSI 0x0000; MISO the 16-bit angle (its most significant
//                bits first; an 8-bit frame returns the top byte only and
//                executes no command)
//   read reg     MOSI 010 aaaaa 00000000: this frame's MISO is the angle,
//                the next frame's MISO is the register's value << 8
//   write reg    MOSI 100 aaaaa vvvvvvvv: the register is written (the
//                datasheet allows 20 ms for the NVM; the model writes at
//                once), the next frame's MISO is the new value << 8
//   17-bit frame the 16 bits and an even-parity bit (MPS application note
//                AN137, "Parity bit (SPI and SSI)": the 17th clock edge)
// SPI mode 0 or 3; the angle leaves the output buffer as it was at CS
// falling (the t of transfer()). Registers (8 bits, 0x00..0x1F): Z 0x00
// (7:0) and 0x01 (15:8) the zero, BCT 0x02, 0x09 bit 7 RD (direction), FW
// 0x0E (filter window, default 119), 0x1B bit 7 MGH / bit 6 MGL (field above
// / below its thresholds; read-only).
// Angle: 16 bits, code = round(2^16 a / 2 pi) mod 2^16, RD negating it, Z
// subtracted. The MagAlpha's digital filter (MPS, "Understanding the
// MagAlpha digital filter") trades bandwidth for resolution, the output
// resolution being the 3-sigma spread of the readings; it follows speed
// changes with its time constant tau. Modelled as a type-2 tracking loop
// (no lag at a constant speed, the error of a speed step decaying with tau):
//   e = a - a_f,  da_f/dt = w_f + 2 e / tau,  dw_f/dt = e / tau^2
// (double pole at -1/tau), plus a fixed latency_s and the noise.
// FW -> tau: 64 us at FW = 51 doubling every 17 up to 16384 us at 187
// (moteus' fw/ma732.h maps filter_us onto FW so, 1024 us at the default
// 119); FW -> resolution 9 bits at 51 plus half a bit per 17 (13 bits at
// 187), the half bit per doubling of tau that averaging gives: noise
// sigma = 2 pi / 2^bits / 3 when noise_from_filter. latency_s default 3 us.
// These are our reading of the datasheet's filter table and timing:
// verify against it.
#ifndef MCSIM_SPI_ENCODERS_HPP
#define MCSIM_SPI_ENCODERS_HPP

#include <cstdint>

#include "mcsim/sensors.hpp"
#include "mcsim/status.hpp"

namespace mcsim {

// The shaft's recent motion: (t, theta, dtheta/dt) samples, times
// non-decreasing (a sample at the last time replaces it), the oldest
// dropped beyond kHistory. theta_at/omega_at: cubic Hermite between the
// samples around t, linear from the nearest end outside them.
class MotionHistory {
 public:
  static constexpr int kHistory = 64;
  void clear() { n_ = 0; }
  bool empty() const { return n_ == 0; }
  // kNotFinite, kBadPeriod (t before the last sample; nothing stored).
  Status push(double t_s, double theta_rad, double omega_rad_s);
  double theta_at(double t_s) const;
  double omega_at(double t_s) const;
  double last_t_s() const;

 private:
  struct Sample {
    double t, th, w;
  };
  const Sample& at(int k) const { return s_[(head_ + k) % kHistory]; }  // k = 0: oldest
  // Index k of the last sample at or before t (-1: before all).
  int find(double t_s) const;
  Sample s_[kHistory] = {};
  int head_ = 0, n_ = 0;
};

enum class MagnetFault : int { kNone = 0, kTooWeak, kTooStrong };

// Frame-level error injection and counters, shared by both chips.
struct SpiLineParams {
  double miso_error_rate = 0.0;  // [0, 1]
  double mosi_error_rate = 0.0;  // [0, 1]
  std::uint64_t seed = 7U;
};
struct SpiCounters {
  std::uint64_t frames = 0, miso_flips = 0, mosi_flips = 0;
};

// Even parity over the low `bits` bits of w: true when they hold an even
// number of ones.
bool spi_even_parity(std::uint32_t w, int bits);

// ---------------------------------------------------------------- AS5047P

struct As5047pParams {
  double latency_s = 110.0e-6;  // signal path delay (uncompensated), [0, 1 ms]
  double noise_rms_rad = 0.0;   // >= 0
  double mount_offset_rad = 0.0;
  int direction = 1;  // +-1
  // OTP contents (the volatile registers after power-up).
  std::uint16_t zposm = 0, zposl = 0, settings1 = 0x0001, settings2 = 0;
  std::uint8_t agc = 128;          // DIAAGC AGC value with a normal field
  std::uint16_t magnitude = 4000;  // MAG (CORDIC magnitude) with a normal field
  SpiLineParams line{};
  // kOk, kNotFinite, kBadSensor (a rate outside [0, 1], latency outside
  // [0, 1 ms], noise < 0, direction not +-1, a register wider than its field).
  Status validate() const;
};

class As5047p {
 public:
  enum : std::uint16_t {
    kNop = 0x0000,
    kErrfl = 0x0001,
    kProg = 0x0003,
    kZposm = 0x0016,
    kZposl = 0x0017,
    kSettings1 = 0x0018,
    kSettings2 = 0x0019,
    kDiaagc = 0x3FFC,
    kMag = 0x3FFD,
    kAngleUnc = 0x3FFE,
    kAngleCom = 0x3FFF,
  };
  enum : std::uint16_t { kFrerr = 1U, kInvcomm = 2U, kParerr = 4U };
  enum : std::uint16_t { kDir = 1U << 2, kDaecdis = 1U << 4, kDataselect = 1U << 6 };

  // Validates p and powers up at t = 0, theta_m = 0, at rest; on error
  // keeps everything.
  Status configure(const As5047pParams& p);
  // Power-up: history restarted at (t, theta_m, omega_m), registers from
  // the OTP, no error, no pending response (the first frame returns 0).
  void power_up(double t_s, double theta_m_rad, double omega_m_rad_s);
  Status observe(double t_s, double theta_m_rad, double omega_m_rad_s) {
    return motion_.push(t_s, theta_m_rad, omega_m_rad_s);
  }
  // One frame of `bits` clocks ending (CSn rising) at t_s: returns what the
  // chip drove on MISO, then executes the command it received.
  std::uint16_t transfer(std::uint16_t mosi, double t_s, int bits = 16);
  void set_magnet_fault(MagnetFault f) { fault_ = f; }

  // Frames with their parity bit set.
  static std::uint16_t read_command(std::uint16_t address);
  static std::uint16_t write_command(std::uint16_t address);
  static std::uint16_t write_data(std::uint16_t data14);
  // The angle code (14 bits, zero and DIR applied, no noise) the chip would
  // latch at t_s, with or without DAEC.
  std::uint16_t angle_code(double t_s, bool compensated) const;
  std::uint16_t errfl() const { return errfl_; }
  const SpiCounters& counters() const { return n_; }

 private:
  std::uint16_t reg(std::uint16_t address, double t_s, bool* ok);
  // The code of the magnet angle (plus noise_rad) the signal path gives at t_s.
  std::uint16_t code_of(double t_s, bool compensated, double noise_rad) const;
  std::uint16_t latch_angle(double t_s, bool compensated);
  std::uint16_t make_response(std::uint16_t data) const;
  As5047pParams p_{};
  MotionHistory motion_;
  GaussianRng rng_{7U};
  MagnetFault fault_ = MagnetFault::kNone;
  std::uint16_t zposm_ = 0, zposl_ = 0, settings1_ = 1, settings2_ = 0, prog_ = 0;
  std::uint16_t errfl_ = 0, response_ = 0;
  bool write_pending_ = false;
  std::uint16_t write_address_ = 0;
  SpiCounters n_{};
};

// ------------------------------------------------------------------ MA732

struct Ma732Params {
  double latency_s = 3.0e-6;      // [0, 1 ms]
  bool noise_from_filter = true;  // noise from FW (see above), else noise_rms_rad
  double noise_rms_rad = 0.0;     // >= 0
  double mount_offset_rad = 0.0;
  int direction = 1;  // +-1
  // NVM contents (the registers after power-up); FW (0x0E) 119 by default.
  std::uint8_t regs[32] = {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 119, 0,
                           0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0,   0};
  SpiLineParams line{};
  // kOk, kNotFinite, kBadSensor (a rate outside [0, 1], latency outside
  // [0, 1 ms], noise < 0, direction not +-1).
  Status validate() const;
};

class Ma732 {
 public:
  enum : std::uint8_t { kZLow = 0x00, kZHigh = 0x01, kBct = 0x02, kRd = 0x09, kFw = 0x0E };
  enum : std::uint8_t { kStatus = 0x1B };
  enum : std::uint8_t { kRdBit = 0x80, kMgh = 0x80, kMgl = 0x40 };

  // Validates p and powers up at t = 0, theta_m = 0, at rest; on error
  // keeps everything.
  Status configure(const Ma732Params& p);
  // Power-up: filter converged on (theta_m, omega_m), registers from NVM.
  void power_up(double t_s, double theta_m_rad, double omega_m_rad_s);
  // The shaft at t_s (non-decreasing); advances the filter.
  Status observe(double t_s, double theta_m_rad, double omega_m_rad_s);
  // One frame of 8, 16 or 17 clocks starting (CS falling) at t_s (other
  // lengths: nothing executed, MISO 0). 17: the 16 bits << 1 | parity.
  std::uint32_t transfer(std::uint16_t mosi, double t_s, int bits = 16);
  void set_magnet_fault(MagnetFault f) { fault_ = f; }

  static std::uint16_t read_command(std::uint8_t address) {
    return static_cast<std::uint16_t>(0x4000U | ((address & 0x1FU) << 8U));
  }
  static std::uint16_t write_command(std::uint8_t address, std::uint8_t value) {
    return static_cast<std::uint16_t>(0x8000U | ((address & 0x1FU) << 8U) | value);
  }
  // Filter time constant [s] and output resolution [bits, 3 sigma] of FW.
  static double filter_tau_s(std::uint8_t fw);
  static double resolution_bits(std::uint8_t fw);
  // The angle code (16 bits, Z and RD applied, no noise) the chip would
  // shift out for a frame starting at t_s.
  std::uint16_t angle_code(double t_s) const;
  std::uint8_t reg(std::uint8_t address) const { return regs_[address & 0x1FU]; }
  const SpiCounters& counters() const { return n_; }
  double noise_rms_rad() const;

 private:
  void filter_to(double t1_s);
  std::uint16_t code_of(double t_s, double noise_rad) const;
  std::uint16_t latch_angle(double t_s);
  Ma732Params p_{};
  MotionHistory motion_;                   // the shaft
  MotionHistory filtered_;                 // the filter's output (angle, its rate)
  double af_ = 0.0, wf_ = 0.0, tf_ = 0.0;  // filter state at tf_
  GaussianRng rng_{7U};
  MagnetFault fault_ = MagnetFault::kNone;
  std::uint8_t regs_[32] = {};
  bool reg_pending_ = false;
  std::uint8_t reg_value_ = 0;
  SpiCounters n_{};
};

}  // namespace mcsim

#endif  // MCSIM_SPI_ENCODERS_HPP
