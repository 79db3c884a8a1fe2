// The board's absolute SPI encoder (board.encoder = as5047p | ma732) on
// the simulated board: hal_host::SpiEncoder, the image's driver on the
// plant's chip model (app_scenario.hpp set_board_spi_encoder).
#include "app_scenario.hpp"

#include <string>

namespace mcsim {

void set_board_spi_encoder(const MotorFiles& f, hal_host::PmsmBoardConfig& bc) {
  hal_host::SpiEncoderConfig& c = bc.spi_encoder;
  c = hal_host::SpiEncoderConfig{};
  if (f.board.encoder == kEncoderAs5047p) {
    c.type = hal_host::SpiEncoderType::kAs5047p;
  } else if (f.board.encoder == kEncoderMa732) {
    c.type = hal_host::SpiEncoderType::kMa732;
  } else {
    return;
  }
  c.err_rate = f.board.encoder_err_rate;
  c.mount_offset_rad = f.board.encoder_mount_rad;
}

void record_spi_encoder(hal_host::PmsmBoard& board, Summary& s) {
  const hal_host::SpiEncoder* e = board.spi_encoder();
  if (e == nullptr) return;
  const mc_spienc_hold_t& h = e->hold();
  s.set("encoder_reads", h.n_reads);
  s.set("encoder_bad_reads", h.n_bad);
  s.set("encoder_line_flips", static_cast<double>(e->miso_flips()));
  std::string seen;
  for (uint32_t b = 0; b < 32u; ++b) {
    const char* n = mc_spienc_err_name(h.err_seen & (1u << b));
    if (n != nullptr) seen += (seen.empty() ? "" : "|") + std::string(n);
  }
  s.set_text("encoder_errors_seen", seen.empty() ? "none" : seen);
}

}  // namespace mcsim
