// make_app_target_sil (app_target.hpp): the drive application compiled for
// the host on the simulated board, one PWM period = hal_host::app_period
// (the image's interrupt/PendSV sequence), booted from the setup's
// parameter table (or the setup's flash: the stored set, with the
// scenario's choices over it), the laws from the parameters, commissioning
// over CAN bound as the images bind it, and a CAN bus
// in memory: the frames a period is given are what the controller holds
// when the receive interrupt runs at the period start; the frames the
// application sends in the period are handed back.
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <deque>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "app_params.hpp"
#include "app_target.hpp"
#include "hal_host/app_rig.hpp"
#include "hal_host/can_ops.hpp"
#include "hal_host/hall_input.hpp"
#include "scenario.hpp"
extern "C" {
#include "commission/mc_comm_can.h"
#include "config/mc_law_cfg.h"
#include "mc_telemetry.h"
}

namespace mcsim {
namespace {

// The in-memory CAN controller: never full, never in error.
class MemCan {
 public:
  MemCan() {
    dev_.ops = hal_host::can_ops<MemCan>();
    dev_.ctx = this;
  }
  int send(const mc_hal_can_frame_t* f) {
    tx_.push_back(*f);
    return 0;
  }
  int receive(mc_hal_can_frame_t* f) {
    if (rx_.empty()) return -EAGAIN;
    *f = rx_.front();
    rx_.pop_front();
    return 0;
  }
  int get_status(mc_hal_can_status_t* s) const {
    *s = mc_hal_can_status_t{};
    s->state = MC_HAL_CAN_STATE_ERROR_ACTIVE;
    return 0;
  }
  const mc_hal_can_t* hal() const { return &dev_; }
  std::deque<mc_hal_can_frame_t> rx_;
  std::vector<mc_hal_can_frame_t> tx_;

 private:
  mc_hal_can_t dev_{};
};

std::string hex(uint32_t v) {
  char b[16];
  std::snprintf(b, sizeof b, "0x%x", v);
  return b;
}

class AppTargetSil final : public AppTarget {
 public:
  explicit AppTargetSil(const AppSetup& s)
      : params_(s.defaults),
        board_(std::make_unique<hal_host::PmsmBoard>(s.board)),
        app_(std::make_unique<mc_app_t>()),
        drive_(std::make_unique<mc_drive_t>()) {
    const uint32_t verr = mc_params_validate(&params_);
    if (verr != MC_PARAMS_OK) {
      throw UsageError("the application's parameter table is invalid: MC_PARAMS_ERR " +
                       params_err_names(verr) + " (law_error " +
                       law_err_names(mc_law_speed_check(&params_)) + ")");
    }
    mc_app_cfg_t c{};
    c.defaults = &params_;
    c.flash = s.flash;  // null: no store, the table boots as the board's defaults
    c.flash_sectors[0] = 0u;
    c.flash_sectors[1] = 1u;
    app_target_binding(s, &c);  // the images' binding, as the PIL target's
    if (s.hall) {               // the board's Hall inputs on the plant's model
      hall_ = std::make_unique<hal_host::HallInput>(*board_, s.hall_params, s.board.theta_m0_rad);
      hall_->set_fault(s.hall_fault, s.hall_fault_sensor, s.hall_fault_at_s);
      c.hall = hall_->hal();
    }
    const uint32_t berr = mc_app_boot(app_.get(), &c);
    if ((berr & MC_APP_CFG_ERR_STORE) != 0u) {
      throw UsageError("the configuration store refused the flash's sectors (MC_APP_CFG bits " +
                       hex(berr) + ")");
    }
    if (berr != MC_APP_CFG_OK) {
      throw UsageError("the application refused to boot: MC_APP_CFG bits " + hex(berr));
    }
    over_stored(s);
    const uint32_t aerr = mc_app_start(app_.get(), drive_.get(), board_->hal(), can_.hal(), true);
    if ((aerr & MC_APP_CFG_ERR_TM) != 0u) {
      char load[96];
      std::snprintf(load, sizeof load, "bus load %.1f %% of %u bit/s, budget %.1f %%",
                    100.0 * mc_telemetry_bus_load(&app_->tm_cfg),
                    static_cast<unsigned>(app_->tm_cfg.bitrate_bps), 100.0 * s.tm_budget_frac);
      throw UsageError(
          "the application refused to start: telemetry configuration refused (MC_TM_CFG "
          "bits " +
          hex(app_->tm_err) + "), " + load);
    }
    if (aerr != MC_APP_CFG_OK) {
      throw UsageError("the application refused to start: MC_APP_CFG bits " + hex(aerr) +
                       " (drive MC_DRIVE_CFG " + hex(app_->drive_err) + ", telemetry " +
                       hex(app_->tm_err) + ", commands " + hex(app_->cmd_err) + ", laws " +
                       law_err_names(app_->laws.error) + ")");
    }
    // Commissioning over CAN, as the images bind it (main.c,
    // mc_board_comm_cfg; the PIL board's rule: hal/pil/mc_hal_pil.c).
    mc_comm_can_cfg_t cc{};
    mc_comm_can_cfg_for_board(&app_->params, app_->params.i_sense_max_a, app_->params.vbus_v,
                              app_->params.current_sensors == 3u, &cc);
    if (mc_comm_can_init(comm_can_.get(), &cc, comm_.get(), drive_.get(),
                         app_->params_valid ? &app_->srv : nullptr) == MC_COMM_CAN_CFG_OK) {
      mc_app_attach_commission(app_.get(), comm_can_.get());
    }
    mc_app_probe(app_.get(), &probe_);
  }

  // A stored set booted: what the scenario chose (AppSetup::over_stored)
  // written over it, as a host's WRITE and APPLY would before the enable.
  void over_stored(const AppSetup& s) {
    const uint32_t b = app_->boot_status;
    if (s.over_stored.empty() || (b != MC_CFG_BOOT_STORED && b != MC_CFG_BOOT_MIGRATED)) return;
    mc_params_t q = app_->params;
    for (uint32_t id : s.over_stored) {
      const mc_param_info_t* info = mc_param_find(id, nullptr);
      if (info == nullptr) continue;
      mc_param_set_raw(&q, info, mc_param_get_raw(&s.defaults, info));
    }
    const uint32_t err = mc_params_validate(&q);
    if (err != MC_PARAMS_OK) {
      throw UsageError(
          "the stored configuration with the scenario's settings over it is invalid: "
          "MC_PARAMS_ERR " +
          params_err_names(err) + " (law_error " + law_err_names(mc_law_speed_check(&q)) + ")");
    }
    app_->params = q;
  }

  AppTargetPeriod period(const std::vector<mc_hal_can_frame_t>& rx,
                         std::vector<mc_hal_can_frame_t>* tx) override {
    can_.rx_.insert(can_.rx_.end(), rx.begin(), rx.end());
    const hal_host::AppPeriod ap = hal_host::app_period(*board_, *app_);
    mc_app_probe(app_.get(), &probe_);
    if (tx != nullptr) tx->insert(tx->end(), can_.tx_.begin(), can_.tx_.end());
    can_.tx_.clear();
    AppTargetPeriod r;
    r.slow_ran = ap.slow_ran;
    return r;
  }
  const mc_app_probe_t& probe() const override { return probe_; }
  const mc_params_t& params() const override { return app_->params; }
  const mc_params_t* staged() const override {
    return app_->params_valid ? &app_->srv.staged : nullptr;
  }
  hal_host::PmsmBoard& board() override { return *board_; }
  std::string name() const override { return "sil"; }
  const mc_comm_t* commissioning() const override { return comm_.get(); }

 private:
  mc_params_t params_;
  std::unique_ptr<hal_host::PmsmBoard> board_;
  std::unique_ptr<hal_host::HallInput> hall_;
  std::unique_ptr<mc_app_t> app_;
  std::unique_ptr<mc_drive_t> drive_;
  std::unique_ptr<mc_comm_t> comm_ = std::make_unique<mc_comm_t>();  // large
  std::unique_ptr<mc_comm_can_t> comm_can_ = std::make_unique<mc_comm_can_t>();
  MemCan can_;
  mc_app_probe_t probe_{};
};

}  // namespace

std::unique_ptr<AppTarget> make_app_target_sil(const AppSetup& s) {
  return std::make_unique<AppTargetSil>(s);
}

}  // namespace mcsim
