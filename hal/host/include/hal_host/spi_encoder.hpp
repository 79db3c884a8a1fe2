// hal_host::SpiEncoder: an absolute SPI encoder on the simulated board
// (issue 32 item 5). The image's driver (hal/spienc: mc_as5047p or
// mc_ma732, configured as the F405 board configures it: AS5047P with DAEC,
// MA732 in 32-clock frames with parity, N = MC_SPIENC_BAD_READS_DEFAULT
// bad reads in a row, one diagnostic read per 1000) talks through a host
// SPI device (hal/spi.h) to the plant's chip model (mcsim::As5047p,
// mcsim::Ma732: their resolution, latency, noise), so the drive's encoder
// device is the driver itself, as on the board.
//
// Timing: observe() at the period's sample (t_k, the plant's shaft); the
// fast loop's read makes its one frame at t_k: the AS5047P's frame ends
// (CSn rising, the latch) kFrameAs5047pS later (16 clocks at 5.25 MHz),
// the MA732's starts (CS falling) at t_k.
//
// Protocol errors: err_rate is the probability that a frame has one bit
// flipped on MISO between the chip and the MCU (uniform over the bits the
// reader reads: 16 for the AS5047P, the 16 angle bits and the parity bit
// for the MA732), a parity failure the driver must catch: one bad read.
// The line is clean during the set-up's probe (it runs once, at boot; a
// probe that fails stops the set-up: the constructor throws, as the
// image's set-up stops with MC_BOARD_F405_ERR_SPIENC) and has err_rate
// from the first fast-loop read on.
#ifndef HAL_HOST_SPI_ENCODER_HPP
#define HAL_HOST_SPI_ENCODER_HPP

#include <cstdint>
#include <memory>

#include "hal/encoder.h"
#include "hal/spi.h"
#include "mc_as5047p.h"
#include "mc_ma732.h"
#include "mcsim/spi_encoders.hpp"

namespace hal_host {

enum class SpiEncoderType : int { kNone = 0, kAs5047p, kMa732 };

struct SpiEncoderConfig {
  SpiEncoderType type = SpiEncoderType::kNone;
  double err_rate = 0.0;          // [0, 1]: MISO bit errors per frame from the first read
  double mount_offset_rad = 0.0;  // the magnet on the shaft: the chip reads dir theta_m + this
  int direction = 1;              // +-1: the chip's angle grows with the shaft's (or against)
  std::uint64_t seed = 7U;        // the chip's noise and line errors
};

class SpiEncoder {
 public:
  static constexpr double kFrameAs5047pS = 16.0 / 5.25e6;

  // Throws std::invalid_argument naming the reason (a rate outside [0, 1],
  // no type, the chip model's refusal, the probe's failure).
  SpiEncoder(const SpiEncoderConfig& cfg, double theta_m0_rad, double omega_m0_rad_s);
  SpiEncoder(const SpiEncoder&) = delete;
  SpiEncoder& operator=(const SpiEncoder&) = delete;

  // The shaft at the period's sample t_k (times non-decreasing).
  void observe(double t_s, double theta_m_rad, double omega_m_rad_s);
  // The drive's encoder device: the driver's.
  const mc_hal_encoder_t* encoder() const;
  // The driver's read rule (runs, counts, errors: mc_spienc.h).
  const mc_spienc_hold_t& hold() const;
  // The line's bit errors so far.
  std::uint64_t miso_flips() const { return flips_; }
  std::uint32_t counts_per_rev() const;
  // Test hook: the line's error rate from the next frame on ([0, 1]).
  void set_err_rate(double rate);

  // The host SPI device's frames (public for the C ops table).
  int transfer16(std::uint16_t tx, std::uint16_t* p_rx) noexcept;
  int transfer32(std::uint32_t tx, std::uint32_t* p_rx) noexcept;

 private:
  SpiEncoderConfig cfg_;
  mcsim::As5047p as_;
  mcsim::Ma732 ma_;
  // One bit of the low `bits` flipped with probability rate_.
  std::uint32_t line(std::uint32_t w, int bits);
  double t_frame_s_ = 0.0;
  double rate_ = 0.0;  // the line's, 0 until the probe has run
  std::uint64_t flips_ = 0;
  mcsim::GaussianRng line_rng_{7U};
  mc_hal_spi_t spi_{};
  mc_as5047p_t as_drv_{};
  mc_ma732_t ma_drv_{};
};

}  // namespace hal_host

#endif  // HAL_HOST_SPI_ENCODER_HPP
