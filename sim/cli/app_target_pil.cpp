// The PIL AppTarget (app_target.hpp): the board's whole image on the
// emulated Cortex-M4F, the plant on the host, one period at a time over the
// PIL link (foc_pil.hpp's PilSession; protocol firmware/targets/pil/
// mc_pil_frame.h, version 5: the application's probe comes back as PROBE
// after each period; a board with a brake chopper gets one in the image's
// HAL, whose duty comes back in OUT and drives the plant's brake; a board
// with Hall sensors gets Hall inputs there, the host's Hall model read at
// each period's sample and its code sent in MEAS).
//
// What the image runs is the flashed image's code (main.c's interrupt and
// PendSV sequence, firmware/app: the application, the drive, the laws, CAN,
// parameter service and store); what differs is only the HAL (hal/pil
// instead of the board's hal/stm32f405 drivers): the ADC, encoder, Hall,
// fault, tick and temperature answers are the host board's, CAN frames travel over
// the link, the configuration store is two RAM sectors, no watchdog.
#include <unistd.h>

#include <cstdio>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "app_target.hpp"
#include "foc_pil.hpp"
#include "hal_host/hall_input.hpp"
#include "scenario.hpp"

namespace mcsim {

namespace {

const AppSetup& checked(const AppSetup& s, const AppTargetPilOptions& o) {
  const std::pair<const char*, const std::string*> files[] = {
      {"QEMU", &o.link.qemu}, {"PIL image", &o.link.elf}, {"PIL bootloader", &o.link.boot_elf}};
  for (const auto& [what, path] : files) {
    if (path == &o.link.boot_elf && path->empty()) continue;  // an image linked at the reset vector
    if (path->empty() || ::access(path->c_str(), R_OK) != 0) {
      throw UsageError(std::string("PIL: ") + what + " '" + *path +
                       "' cannot be read (build the image: target mc_pil_m4f)");
    }
  }
  if (s.flash != nullptr) {
    throw UsageError(
        "PIL: the image's configuration store is its own (an erased RAM store): --flash is "
        "for the SIL");
  }
  const uint32_t err = mc_params_validate(&s.defaults);
  if (err != MC_PARAMS_OK) {
    char bits[16];
    std::snprintf(bits, sizeof bits, "0x%X", static_cast<unsigned>(err));
    throw UsageError(std::string("PIL: the parameter table is invalid (MC_PARAMS_ERR bits ") +
                     bits + "): the image would refuse it");
  }
  return s;
}

// The board's Hall inputs on the plant's model, as the SIL target makes
// them (app_target_sil.cpp): the host reads them at each period's sample
// and sends the code in MEAS; null without Hall sensors.
std::unique_ptr<hal_host::HallInput> hall_of(const AppSetup& s, const hal_host::PmsmBoard& b) {
  if (!s.hall) return nullptr;
  auto h = std::make_unique<hal_host::HallInput>(b, s.hall_params, s.board.theta_m0_rad);
  h->set_fault(s.hall_fault, 0, s.hall_fault_at_s);
  return h;
}

std::string image_name(const AppTargetPilOptions& o) {
  const std::string& elf = o.link.elf;
  const std::size_t slash = elf.find_last_of('/');
  std::string n = slash == std::string::npos ? elf : elf.substr(slash + 1);
  if (const std::size_t dot = n.rfind(".elf"); dot != std::string::npos) n.resize(dot);
  return "pil:" + n + (o.board.empty() ? "" : ":" + o.board);
}

class PilAppTarget final : public AppTarget {
 public:
  PilAppTarget(const AppSetup& s, const AppTargetPilOptions& o)
      : params_(checked(s, o).defaults),
        board_(std::make_unique<hal_host::PmsmBoard>(s.board)),
        hall_(hall_of(s, *board_)),
        pil_(*board_, o.link),
        name_(image_name(o)) {
    PilAppSetup ps;
    ps.defaults = s.defaults;
    mc_app_cfg_t c{};
    app_target_binding(s, &c);
    ps.app.tm_budget_frac = c.tm_budget_frac;
    for (uint32_t i = 0; i < MC_PIL_TM_EXT_RATES; ++i)
      ps.app.tm_ext_rate_hz[i] = c.tm_ext_rate_hz[i];
    ps.app.pwm_hz_fixed = c.pwm_hz_fixed;
    ps.app.slow_loop_div_fixed = c.slow_loop_div_fixed;
    ps.hall = hall_ ? hall_->hal() : nullptr;
    pil_.boot_app(ps);
  }
  ~PilAppTarget() override {
    try {
      (void)pil_.finish();
    } catch (...) {  // NOLINT(bugprone-empty-catch): QEMU is stopped by the link either way
    }
  }
  PilAppTarget(const PilAppTarget&) = delete;
  PilAppTarget& operator=(const PilAppTarget&) = delete;

  AppTargetPeriod period(const std::vector<mc_hal_can_frame_t>& rx,
                         std::vector<mc_hal_can_frame_t>* tx) override {
    tx_.clear();
    const mc_pil_out_t& o = pil_.step(PilCommand{}, rx, &tx_);
    if (tx != nullptr) {
      for (const PilCanTx& t : tx_) tx->push_back(t.frame);
    }
    AppTargetPeriod r;
    r.slow_ran = o.slow_ran != 0u;
    return r;
  }
  const mc_app_probe_t& probe() const override { return pil_.probe(); }
  const mc_params_t& params() const override { return params_; }
  hal_host::PmsmBoard& board() override { return *board_; }
  std::string name() const override { return name_; }

 private:
  mc_params_t params_;
  std::unique_ptr<hal_host::PmsmBoard> board_;
  std::unique_ptr<hal_host::HallInput> hall_;
  PilSession pil_;
  std::string name_;
  std::vector<PilCanTx> tx_;
};

}  // namespace

std::unique_ptr<AppTarget> make_app_target_pil(const AppSetup& s, const AppTargetPilOptions& o) {
  return std::make_unique<PilAppTarget>(s, o);
}

}  // namespace mcsim
