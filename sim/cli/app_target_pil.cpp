// The PIL AppTarget (app_target.hpp): the board's whole image on the
// emulated Cortex-M4F, the plant on the host, one period at a time over the
// PIL link (foc_pil.hpp's PilSession; protocol firmware/targets/pil/
// mc_pil_frame.h, version 6: the application's probe comes back as PROBE
// and PROBE2 after each period; with --flash the board's flash file's bytes
// go to the image's RAM store (FLASH frames) before it boots; a board with a brake chopper gets one in the image's
// HAL, whose duty comes back in OUT and drives the plant's brake; a board
// with Hall sensors gets Hall inputs there, the host's Hall model read at
// each period's sample and its code sent in MEAS).
//
// What the image runs is the flashed image's code (main.c's interrupt and
// PendSV sequence, firmware/app: the application, the drive, the laws, CAN,
// parameter service and store); what differs is only the HAL (hal/pil
// instead of the board's hal/stm32f405 drivers): the ADC, encoder, Hall,
// fault, tick and temperature answers are the host board's, CAN frames travel over
// the link, the configuration store is two RAM sectors (erased, or the
// --flash file's content: never written back), no watchdog.
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "app_target.hpp"
#include "foc_pil.hpp"
#include "hal_host/hall_input.hpp"
#include "scenario.hpp"
extern "C" {
#include "config/mc_cfg_store.h"
}

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
  const uint32_t err = mc_params_validate(&s.defaults);
  if (err != MC_PARAMS_OK) {
    char bits[16];
    std::snprintf(bits, sizeof bits, "0x%X", static_cast<unsigned>(err));
    throw UsageError(std::string("PIL: the parameter table is invalid (MC_PARAMS_ERR bits ") +
                     bits + "): the image would refuse it");
  }
  return s;
}

// The image's RAM store as a flash for the host's store code (the FLASH
// frames' content): two sectors of FileFlash's geometry, NOR semantics
// (program clears bits only).
class RamFlash {
 public:
  static constexpr std::size_t kSectorBytes = std::size_t{16} * 1024u;  // FileFlash's
  explicit RamFlash(std::vector<uint8_t> bytes) : mem_(std::move(bytes)) {}
  const mc_hal_flash_t* hal() const { return &dev_; }
  const std::vector<uint8_t>& bytes() const { return mem_; }

 private:
  static RamFlash& self(void* c) { return *static_cast<RamFlash*>(c); }
  static std::size_t at(uint32_t sector, uint32_t off) {
    return static_cast<std::size_t>(sector) * kSectorBytes + off;
  }
  static bool in(uint32_t sector, uint32_t off, std::size_t len) {
    return sector < 2u && off <= kSectorBytes && len <= kSectorBytes - off;
  }
  static int size(void* /*ctx*/, uint32_t sector, uint32_t* b) {
    if (sector >= 2u) return -EINVAL;
    *b = static_cast<uint32_t>(kSectorBytes);
    return 0;
  }
  static int erase(void* c, uint32_t sector) {
    if (sector >= 2u) return -EINVAL;
    std::fill_n(self(c).mem_.begin() + static_cast<std::ptrdiff_t>(at(sector, 0u)), kSectorBytes,
                uint8_t{0xFF});
    return 0;
  }
  static int program(void* c, uint32_t sector, uint32_t off, const uint32_t* w, uint32_t n) {
    const std::size_t len = static_cast<std::size_t>(n) * 4u;
    if (!in(sector, off, len) || (off % 4u) != 0u) return -EINVAL;
    std::vector<uint8_t> b(len);
    std::memcpy(b.data(), w, len);
    for (std::size_t i = 0; i < len; ++i) self(c).mem_[at(sector, off) + i] &= b[i];
    return 0;
  }
  static int read(void* c, uint32_t sector, uint32_t off, void* p, uint32_t len) {
    if (!in(sector, off, len)) return -EINVAL;
    std::memcpy(p, self(c).mem_.data() + at(sector, off), len);
    return 0;
  }
  static constexpr mc_hal_flash_ops_t kOps = {size, erase, program, read};
  std::vector<uint8_t> mem_;
  mc_hal_flash_t dev_{&kOps, this};
};

// Whether two sets differ in a parameter of the table.
bool sets_differ(const mc_params_t& a, const mc_params_t& b) {
  for (const mc_param_info_t& info : mc_param_table) {
    if (info.offset == MC_PARAM_NO_FIELD) continue;
    if (mc_param_get_raw(&a, &info) != mc_param_get_raw(&b, &info)) return true;
  }
  return false;
}

// --flash: what the image's store receives (FLASH frames) and the set it
// boots. The board's file read through its HAL (never written); a stored
// set gets what the scenario chose written over it (AppSetup::over_stored,
// as the SIL target writes it over the set it booted), here as a newer
// record of the copy, which the image then boots. *booted: the set the
// image boots (s.defaults when the store holds none it boots).
std::vector<uint8_t> flash_for_image(const AppSetup& s, mc_params_t* booted) {
  std::vector<uint8_t> bytes(2u * RamFlash::kSectorBytes);
  for (uint32_t k = 0; k < 2u; ++k) {
    uint32_t n = 0;
    if (mc_hal_flash_sector_size(s.flash, k, &n) != 0 || n != RamFlash::kSectorBytes ||
        mc_hal_flash_read(s.flash, k, 0u, bytes.data() + static_cast<std::size_t>(k) * n, n) != 0) {
      throw UsageError("PIL: the flash file cannot be read as the image's two 16 KiB sectors");
    }
  }
  RamFlash ram(std::move(bytes));
  mc_cfg_store_t st{};
  mc_cfg_store_cfg_t sc{};
  sc.flash = ram.hal();
  sc.sector[0] = 0u;
  sc.sector[1] = 1u;
  mc_params_t q{};
  *booted = s.defaults;
  if (mc_cfg_store_init(&st, &sc) != 0) throw UsageError("PIL: no store on the flash file");
  const mc_cfg_boot_t b = mc_cfg_store_load(&st, &q);
  if (b != MC_CFG_BOOT_STORED && b != MC_CFG_BOOT_MIGRATED) return ram.bytes();
  const mc_params_t stored = q;
  for (uint32_t id : s.over_stored) {
    const mc_param_info_t* info = mc_param_find(id, nullptr);
    if (info != nullptr) mc_param_set_raw(&q, info, mc_param_get_raw(&s.defaults, info));
  }
  if (q.anticogging == 2u) q.anticogging = 0u;  // as the image boots a stored 2 (mc_app_boot)
  if (sets_differ(q, stored)) {
    if (mc_params_validate(&q) != MC_PARAMS_OK) {
      throw UsageError(
          "PIL: the stored configuration with the scenario's settings over it is invalid");
    }
    if (mc_cfg_store_save(&st, &q) != 0) {
      throw UsageError("PIL: the scenario's settings do not fit the flash copy's store");
    }
  }
  *booted = q;
  return ram.bytes();
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
    if (s.flash != nullptr) ps.flash = flash_for_image(s, &params_);
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
