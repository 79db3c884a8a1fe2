// The drive application as a scenario sees it (issue 29 items 3 and 5): the
// MCU image's application (firmware/app/app/mc_app) on the simulated board,
// booted from a parameter table, either compiled for the host (the SIL:
// hal_host::app_period, the image's interrupt/PendSV sequence) or, with
// `--pil`, the board's whole image on the emulated Cortex-M4F exchanging one
// period at a time with the same plant.
//
// A scenario talks to the application only through CAN frames (the DBC's
// command messages, as a user's tool would) and reads it only through the
// probe (mc_app_probe_t) and the plant: so the same scenario code gives the
// same CSV and summary, bit for bit, on either target.
//
//   AppSetup       what both targets are built from: the plant and board
//                  (hal_host::PmsmBoardConfig, from the motor and board
//                  files) and the parameter table the application boots
//                  (the board's defaults: mc_params_t, every quantity of the
//                  drive, its laws chosen by speed_law).
//   period(rx,tx)  one PWM period: the frames in rx received by the
//                  application's CAN receive interrupt before the fast step
//                  (app_period's step 2), the frames it sent appended to tx.
//   probe()        the application's state after the last period.
//   board()        the plant (host side in both targets).
//
// make_app_target_sil lives in app_target_sil.cpp, make_app_target_pil in
// app_target_pil.cpp.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "hal_host/pmsm_board.hpp"
extern "C" {
#include "hal/can.h"
#include "mc_app.h"
#include "mc_params.h"
}

namespace mcsim {

struct AppSetup {
  hal_host::PmsmBoardConfig board;  // plant + board (its load function included)
  mc_params_t defaults{};           // the configuration the application boots
};

// What one period did (both targets report the same).
struct AppTargetPeriod {
  bool slow_ran = false;  // the slow step (PendSV's body) ran in this period
};

class AppTarget {
 public:
  virtual ~AppTarget() = default;
  AppTarget() = default;
  AppTarget(const AppTarget&) = delete;
  AppTarget& operator=(const AppTarget&) = delete;

  // One PWM period (see the file comment). Throws std::runtime_error when
  // the target fails (PIL: link error, frame out of sequence).
  virtual AppTargetPeriod period(const std::vector<mc_hal_can_frame_t>& rx,
                                 std::vector<mc_hal_can_frame_t>* tx) = 0;
  // The application after the last period (after construction: after boot).
  virtual const mc_app_probe_t& probe() const = 0;
  // The parameter table the application booted (validated).
  virtual const mc_params_t& params() const = 0;
  virtual hal_host::PmsmBoard& board() = 0;
  // "sil" or "pil:<image>" for the summary.
  virtual std::string name() const = 0;
};

// Throws UsageError naming the reason when the application refuses the
// setup (its parameter table invalid, a law refused).
std::unique_ptr<AppTarget> make_app_target_sil(const AppSetup& s);

}  // namespace mcsim
