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

#include "hal_host/pil_link.hpp"
#include "hal_host/pmsm_board.hpp"
#include "mcsim/hall.hpp"
extern "C" {
#include "hal/can.h"
#include "commission/mc_commission.h"
#include "hal/flash.h"
#include "mc_app.h"
#include "mc_params.h"
}

namespace mcsim {

struct AppSetup {
  hal_host::PmsmBoardConfig board;  // plant + board (its load function included)
  mc_params_t defaults{};           // the configuration the application boots
  // Telemetry beyond the parameter table: the share of the bus it may use
  // and the rates of the messages past POSITION (mc_app_cfg_t; the images'
  // binding by default). Both targets bind them (the PIL's APP frame).
  float tm_budget_frac = 0.5f;
  uint16_t tm_ext_rate_hz[MC_TM_COUNT - MC_TM_OBSERVER] = {};
  // The board's configuration store (the SIL only: the PIL image has its
  // own, an erased RAM store, and make_app_target_pil refuses one here).
  // Null: no store (a SAVE answers STORE; the PIL image's RAM store answers
  // it OK: a run that saves is not compared with --pil).
  const mc_hal_flash_t* flash = nullptr;
  // make_file_target with --flash: refuse a flash the drive cannot boot
  // (app_scenario.hpp; can-telemetry boots the defaults and says so), and
  // the parameters written over a stored set before the start (ids).
  bool flash_must_boot = false;
  std::vector<uint32_t> over_stored;
  // Hall sensors (board_hall.hpp): the board's Hall inputs read the
  // plant's model (hal_host::HallInput), powered up at board.theta_m0_rad,
  // with hall_fault from hall_fault_at_s. Both targets: the SIL's drive
  // reads them, the PIL host reads them at each sample for the image's.
  bool hall = false;
  mcsim::HallParams hall_params{};
  mcsim::HallFault hall_fault = mcsim::HallFault::kNone;
  double hall_fault_at_s = 0.0;
  int hall_fault_sensor = 0;  // the sensor of kStuckLow / kStuckHigh (0..2)
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
  // The parameter service's staged set (what commissioning staged for the
  // host's APPLY and SAVE); nullptr where the target cannot show it (PIL:
  // the image's memory is the board's).
  virtual const mc_params_t* staged() const { return nullptr; }
  // The commissioning sequence's state (its checks' figures: flux_chk,
  // mech_chk); nullptr where the target cannot show it (PIL).
  virtual const mc_comm_t* commissioning() const { return nullptr; }
  virtual hal_host::PmsmBoard& board() = 0;
  // "sil" or "pil:<image>" for the summary.
  virtual std::string name() const = 0;
};

// The application's binding besides the parameter table, as the boards'
// images make it (firmware/targets/stm32f405/board_stm32f405.c,
// mc_board_app_cfg): the PWM rate and the slow divider fixed to the
// table's (APPLY cannot change them on a board), telemetry up to half of
// the bus, the rates of the messages past POSITION 0 (the image's; a
// scenario may ask for others: AppSetup), the laws of SPEED and POSITION
// from the parameters. Both targets bind it (the
// PIL image receives it in its APP frame), so their applications are the
// same; flash, watchdog and boot hooks are each target's own.
inline void app_target_binding(const AppSetup& s, mc_app_cfg_t* c) {
  c->pwm_hz_fixed = s.defaults.pwm_hz;
  c->slow_loop_div_fixed = s.defaults.slow_loop_div;
  c->tm_budget_frac = s.tm_budget_frac;  // the images': 0.5
  for (size_t i = 0; i < sizeof c->tm_ext_rate_hz / sizeof c->tm_ext_rate_hz[0]; ++i) {
    c->tm_ext_rate_hz[i] = s.tm_ext_rate_hz[i];  // the images': 0
  }
  c->laws_from_params = true;
}

// Throws UsageError naming the reason when the application refuses the
// setup (its parameter table invalid, a law refused).
std::unique_ptr<AppTarget> make_app_target_sil(const AppSetup& s);

// The PIL target: the board's whole image (mc_stm32f405_pil: the image's
// main, both interrupts, the application, CAN and a RAM configuration store
// behind hal/pil's HAL; firmware/targets/pil) on QEMU's emulated M4F, booted
// on s.defaults with app_target_binding, the plant built from s.board on
// the host (app_target_pil.cpp).
struct AppTargetPilOptions {
  hal_host::PilLinkOptions link;  // QEMU, the PIL image and its bootloader, logs
  std::string board;              // the board s describes, for name() (may be "")
};
// Throws UsageError when the setup cannot run on the link (QEMU, the image
// or its bootloader unreadable, the parameter table invalid, --flash: the
// image's store is its own), std::runtime_error when QEMU or the image
// fails. The brake chopper and the Hall inputs travel on the link (APP's
// caps).
std::unique_ptr<AppTarget> make_app_target_pil(const AppSetup& s, const AppTargetPilOptions& o);

}  // namespace mcsim
