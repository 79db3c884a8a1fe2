// See spi_encoder.hpp.
#include "hal_host/spi_encoder.hpp"

#include <cerrno>
#include <cmath>
#include <stdexcept>
#include <string>

namespace hal_host {

namespace {

int t16(void* ctx, uint16_t tx, uint16_t* p_rx) {
  return static_cast<SpiEncoder*>(ctx)->transfer16(tx, p_rx);
}
int t32(void* ctx, uint32_t tx, uint32_t* p_rx) {
  return static_cast<SpiEncoder*>(ctx)->transfer32(tx, p_rx);
}
const mc_hal_spi_ops_t kSpiOps = {&t16, &t32};

std::string probe_why(int rc) {
  switch (rc) {
    case -EIO:
      return "EIO: an SPI transfer failed";
    case -EPROTO:
      return "EPROTO: a parity error or a word no chip sends";
    case -ERANGE:
      return "ERANGE: the magnet's field out of range";
    case -ENODEV:
      return "ENODEV: no 32-clock frames";
    default:
      return std::to_string(rc);
  }
}

}  // namespace

SpiEncoder::SpiEncoder(const SpiEncoderConfig& cfg, double theta_m0_rad, double omega_m0_rad_s)
    : cfg_(cfg) {
  if (!(cfg.err_rate >= 0.0 && cfg.err_rate <= 1.0)) {
    throw std::invalid_argument("spi_encoder: err_rate must lie in [0, 1]");
  }
  if (!std::isfinite(cfg.mount_offset_rad)) {
    throw std::invalid_argument("spi_encoder: mount_offset_rad must be finite");
  }
  line_rng_.reseed(cfg.seed + 0x5A5AU);
  spi_ = {&kSpiOps, this};
  int rc = 0;
  if (cfg.type == SpiEncoderType::kAs5047p) {
    mcsim::As5047pParams p;
    p.mount_offset_rad = cfg.mount_offset_rad;
    p.direction = cfg.direction;
    p.line.seed = cfg.seed;
    if (as_.configure(p) != mcsim::Status::kOk) {
      throw std::invalid_argument("spi_encoder: the AS5047P model refused its parameters");
    }
    as_.power_up(0.0, theta_m0_rad, omega_m0_rad_s);
    mc_as5047p_config_t c{};
    c.p_spi = &spi_;
    c.p_tick = nullptr;
    c.daec = true;  // the F405 board's set-up (mc_board_f405.c)
    c.bad_reads_max = MC_SPIENC_BAD_READS_DEFAULT;
    c.diag_period = MC_AS5047P_DIAG_PERIOD_DEFAULT;
    if (mc_as5047p_init(&as_drv_, &c) != 0) {
      throw std::invalid_argument("spi_encoder: mc_as5047p_init refused the configuration");
    }
    t_frame_s_ = kFrameAs5047pS;
    rc = mc_as5047p_probe(&as_drv_);
  } else if (cfg.type == SpiEncoderType::kMa732) {
    mcsim::Ma732Params p;
    p.mount_offset_rad = cfg.mount_offset_rad;
    p.direction = cfg.direction;
    p.line.seed = cfg.seed;
    if (ma_.configure(p) != mcsim::Status::kOk) {
      throw std::invalid_argument("spi_encoder: the MA732 model refused its parameters");
    }
    ma_.power_up(0.0, theta_m0_rad, omega_m0_rad_s);
    mc_ma732_config_t c{};
    c.p_spi = &spi_;
    c.p_tick = nullptr;
    c.parity = true;  // 32-clock frames, as the F405 board reads it
    c.bad_reads_max = MC_SPIENC_BAD_READS_DEFAULT;
    c.diag_period = MC_MA732_DIAG_PERIOD_DEFAULT;
    if (mc_ma732_init(&ma_drv_, &c) != 0) {
      throw std::invalid_argument("spi_encoder: mc_ma732_init refused the configuration");
    }
    t_frame_s_ = 0.0;
    rc = mc_ma732_probe(&ma_drv_);
  } else {
    throw std::invalid_argument("spi_encoder: no chip type");
  }
  if (rc != 0) {
    throw std::invalid_argument("spi_encoder: the chip's probe failed (" + probe_why(rc) +
                                "): the board's set-up stops");
  }
  rate_ = cfg.err_rate;
}

void SpiEncoder::observe(double t_s, double theta_m_rad, double omega_m_rad_s) {
  const mcsim::Status st = cfg_.type == SpiEncoderType::kAs5047p
                               ? as_.observe(t_s, theta_m_rad, omega_m_rad_s)
                               : ma_.observe(t_s, theta_m_rad, omega_m_rad_s);
  if (st != mcsim::Status::kOk) {
    throw std::runtime_error("spi_encoder: the shaft's motion refused (time backwards or NaN)");
  }
  t_frame_s_ = t_s + (cfg_.type == SpiEncoderType::kAs5047p ? kFrameAs5047pS : 0.0);
}

const mc_hal_encoder_t* SpiEncoder::encoder() const {
  return cfg_.type == SpiEncoderType::kAs5047p ? &as_drv_.dev : &ma_drv_.dev;
}

const mc_spienc_hold_t& SpiEncoder::hold() const {
  return cfg_.type == SpiEncoderType::kAs5047p ? as_drv_.hold : ma_drv_.hold;
}

std::uint32_t SpiEncoder::counts_per_rev() const {
  return cfg_.type == SpiEncoderType::kAs5047p ? MC_AS5047P_CPR : MC_MA732_CPR;
}

void SpiEncoder::set_err_rate(double rate) {
  if (!(rate >= 0.0 && rate <= 1.0)) {
    throw std::invalid_argument("spi_encoder: err_rate must lie in [0, 1]");
  }
  rate_ = rate;
}

std::uint32_t SpiEncoder::line(std::uint32_t w, int bits) {
  if (rate_ <= 0.0 || line_rng_.uniform_open01() > rate_) return w;
  const double u = line_rng_.uniform_open01();  // (0, 1]
  int bit = static_cast<int>(std::ceil(u * bits)) - 1;
  bit = bit < 0 ? 0 : (bit >= bits ? bits - 1 : bit);
  ++flips_;
  return w ^ (1U << static_cast<unsigned>(bit));
}

int SpiEncoder::transfer16(std::uint16_t tx, std::uint16_t* p_rx) noexcept {
  std::uint32_t rx = 0;
  if (cfg_.type == SpiEncoderType::kAs5047p) {
    rx = line(as_.transfer(tx, t_frame_s_, 16), 16);
  } else {
    rx = line(ma_.transfer(tx, t_frame_s_, 16), 16);
  }
  if (p_rx != nullptr) *p_rx = static_cast<std::uint16_t>(rx);
  return 0;
}

// 32 clocks: the MA732's 16 bits and its parity bit (the 17th clock); the
// clocks after it carry nothing the reader reads.
int SpiEncoder::transfer32(std::uint32_t tx, std::uint32_t* p_rx) noexcept {
  if (cfg_.type != SpiEncoderType::kMa732) return -ENODEV;
  const std::uint32_t w17 =
      line(ma_.transfer(static_cast<std::uint16_t>(tx >> 16U), t_frame_s_, 17), 17);
  if (p_rx != nullptr) *p_rx = w17 << 15U;
  return 0;
}

}  // namespace hal_host
