// Processor-in-the-loop twin of FocSil: the same plant and board
// (hal_host::PmsmBoard with the paper-002 test motor) on the host, the drive
// application on the emulated STM32F405 (QEMU netduinoplus2, image
// mc_stm32f405_pil: firmware/targets/stm32f405 with hal/pil/mc_hal_pil.c), the two
// exchanging one frame each way per PWM period over USART1.
//
// Per period, as FocSil::step() does it in one process:
//   board.sample()  -> MEAS (the board's adc/encoder/fault/tick/Hall HAL answers,
//                      plus this period's commands) -> target: fast step in
//                      the ADC interrupt, slow step in PendSV when due
//   OUT             -> the duties, enable and gate kills the drive asked for,
//                      applied to the board -> board.advance()
// The drive configuration is FocSil's (sent as CFG at start-up), so the SIL
// and PIL runs of one FocSilOptions are the same experiment.
//
// Whole-image mode (the second constructor): the image binds the drive
// application (firmware/app/app/mc_app) on the default parameters and the
// binding sent at start-up (PARAMS, APP), and CAN frames travel with the
// periods: step() delivers the given frames to the drive before the period
// (CAN_RX) and returns those it sent (CAN_TX). Both loops run within the
// period, as in the SIL's one period (hal_host::app_period).
#pragma once

#include <functional>
#include <memory>
#include <vector>

#include "foc_sil.hpp"
#include "hal_host/pil_link.hpp"
extern "C" {
#include "hal/hall.h"
#include "mc_params.h"
#include "mc_pil_frame.h"
#include "mc_pil_probe.h"
}

namespace mcsim {

// What the scenario asks of the drive in one period.
struct PilCommand {
  bool set_mode = false;
  mc_drive_mode_t mode = MC_DRIVE_MODE_IDLE;
  bool set_refs = false;
  float id_ref_a = 0.0f;
  float iq_ref_a = 0.0f;
};

// The whole image's start-up: the board's default parameters and the rest
// of the application's binding (mc_pil_frame.h).
struct PilAppSetup {
  mc_params_t defaults{};
  mc_pil_app_t app{};  // caps: the session's (the board's brake, hall below)
  // The board's Hall inputs (hal_host::HallInput on the session's board;
  // null: none): read once per period at the sample into MEAS, the image's
  // HAL exposing them to the application (MC_PIL_CAP_HALL). Outlives the
  // session.
  const mc_hal_hall_t* hall = nullptr;
  // The board's flash content for the image's RAM configuration store
  // (FLASH frames before APP; link version 6): its two sectors' bytes, or
  // empty for an erased store.
  std::vector<uint8_t> flash;
};

// A frame the image sent, and the period (MEAS seq) it left in.
struct PilCanTx {
  uint32_t seq = 0;
  mc_hal_can_frame_t frame{};
};

// The host end of one PIL session on any simulated board (FocPil's two
// modes; the PIL AppTarget, app_target_pil.cpp): the link to the image and
// one period at a time on the caller's board. The board outlives the
// session.
class PilSession {
 public:
  // Starts QEMU (PilLink) and waits for HELLO. Throws std::runtime_error.
  PilSession(hal_host::PmsmBoard& board, const hal_host::PilLinkOptions& link);

  // Drive alone: the drive configuration (CFG), READY checked.
  void boot_drive(const mc_drive_cfg_t& cfg);
  // Whole image: the application on setup.defaults (PARAMS, APP), READY and
  // the application's probe after boot (PROBE) checked.
  void boot_app(const PilAppSetup& setup);

  // One PWM period (FocPil::step); in the whole-image mode the probe the
  // image sent before OUT is probe().
  const mc_pil_out_t& step(const PilCommand& cmd, const std::vector<mc_hal_can_frame_t>& can_rx,
                           std::vector<PilCanTx>* can_tx);

  const mc_pil_ready_t& ready() const { return ready_; }
  const mc_app_probe_t& probe() const { return probe_; }
  int finish() { return link_.finish(0); }

 private:
  void expect_ready();
  void expect_probe();
  void expect_probe2();  // PROBE2, right after PROBE

  hal_host::PmsmBoard& board_;
  hal_host::PilLink link_;
  mc_pil_ready_t ready_{};
  mc_pil_out_t out_{};
  mc_app_probe_t probe_{};
  bool app_mode_ = false;
  const mc_hal_hall_t* hall_ = nullptr;  // the board's Hall inputs (PilAppSetup::hall)
  uint32_t seq_ = 0;
};

class FocPil {
 public:
  // tweak_cfg (optional) edits the drive configuration before it is sent
  // (tests use it to show that a one-ulp change is detected). Throws
  // std::runtime_error if QEMU fails or the target refuses the config.
  FocPil(const FocSilOptions& o, const hal_host::PilLinkOptions& link,
         const std::function<void(mc_drive_cfg_t&)>& tweak_cfg = nullptr);

  // Whole image: the application on setup.defaults (see the file comment).
  // Throws std::runtime_error if QEMU fails or the application refuses.
  FocPil(const FocSilOptions& o, const hal_host::PilLinkOptions& link, const PilAppSetup& setup);

  // One PWM period (see the file comment): can_rx are delivered to the
  // drive's CAN before it, the frames it sends are appended to can_tx.
  // Throws std::runtime_error on a link error or a frame out of sequence.
  const mc_pil_out_t& step(const PilCommand& cmd,
                           const std::vector<mc_hal_can_frame_t>& can_rx = {},
                           std::vector<PilCanTx>* can_tx = nullptr) {
    return pil_.step(cmd, can_rx, can_tx);
  }

  hal_host::PmsmBoard& board() { return sil_.board(); }
  const mc_pil_ready_t& ready() const { return pil_.ready(); }
  // Whole image: the application's probe after the last period.
  const mc_app_probe_t& probe() const { return pil_.probe(); }
  // Stop the target; returns its exit status (0 = clean END).
  int finish() { return pil_.finish(); }

 private:
  FocSil sil_;  // owns the board; its own drive instance stays idle
  PilSession pil_;
};

}  // namespace mcsim
