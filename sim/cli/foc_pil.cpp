#include "foc_pil.hpp"

#include <algorithm>
#include <cerrno>
#include <stdexcept>
#include <string>
#include <vector>

namespace mcsim {

namespace {

std::vector<uint8_t> frame_buf() {
  return std::vector<uint8_t>(MC_PIL_MAX_FRAME);
}

}  // namespace

PilSession::PilSession(hal_host::PmsmBoard& board, const hal_host::PilLinkOptions& link)
    : board_(board), link_(link) {
  const std::vector<uint8_t> hello = link_.receive_frame();
  if (mc_pil_check_hello(hello.data(), hello.size()) != MC_PIL_OK) {
    throw std::runtime_error("PIL: expected HELLO from the target");
  }
}

void PilSession::boot_drive(const mc_drive_cfg_t& cfg) {
  std::vector<uint8_t> buf = frame_buf();
  const std::size_t n = mc_pil_encode_cfg(&cfg, buf.data(), buf.size());
  link_.send(buf.data(), n);
  expect_ready();
}

void PilSession::boot_app(const PilAppSetup& setup) {
  // Every parameter with a field, MC_PIL_PARAMS_MAX per frame.
  std::vector<uint32_t> ids, raws;
  for (const mc_param_info_t& info : mc_param_table) {
    if (info.offset == MC_PARAM_NO_FIELD) continue;
    ids.push_back(info.id);
    raws.push_back(mc_param_get_raw(&setup.defaults, &info));
  }
  std::vector<uint8_t> buf = frame_buf();
  for (std::size_t at = 0; at < ids.size(); at += MC_PIL_PARAMS_MAX) {
    const auto k = static_cast<uint32_t>(std::min<std::size_t>(MC_PIL_PARAMS_MAX, ids.size() - at));
    const std::size_t n =
        mc_pil_encode_params(ids.data() + at, raws.data() + at, k, buf.data(), buf.size());
    link_.send(buf.data(), n);
  }
  // The flash content, MC_PIL_FLASH_CHUNK bytes a frame; erased chunks are
  // left out (the image's store starts erased).
  const std::vector<uint8_t>& fl = setup.flash;
  for (std::size_t at = 0; at < fl.size(); at += MC_PIL_FLASH_CHUNK) {
    const auto k = static_cast<uint32_t>(std::min<std::size_t>(MC_PIL_FLASH_CHUNK, fl.size() - at));
    if (std::all_of(fl.begin() + static_cast<std::ptrdiff_t>(at),
                    fl.begin() + static_cast<std::ptrdiff_t>(at + k),
                    [](uint8_t b) { return b == 0xFFu; })) {
      continue;
    }
    const std::size_t n =
        mc_pil_encode_flash(static_cast<uint32_t>(at), fl.data() + at, k, buf.data(), buf.size());
    if (n == 0u) throw std::runtime_error("PIL: the flash content is not whole words");
    link_.send(buf.data(), n);
  }
  mc_pil_app_t app = setup.app;
  (void)board_.tick_freq(&app.tick_hz);  // this board's, whatever the caller gave
  // The image's HAL exposes a brake chopper when this board has one, Hall
  // inputs when it has them (the image binds them as the application's).
  app.caps = ((board_.hal()->brake != nullptr) ? MC_PIL_CAP_BRAKE : 0u) |
             ((setup.hall != nullptr) ? MC_PIL_CAP_HALL : 0u);
  hall_ = setup.hall;
  const std::size_t n = mc_pil_encode_app(&app, buf.data(), buf.size());
  link_.send(buf.data(), n);
  expect_ready();
  app_mode_ = true;
  expect_probe();  // the application after boot
}

void PilSession::expect_ready() {
  const std::vector<uint8_t> r = link_.receive_frame();
  if (mc_pil_decode_ready(r.data(), r.size(), &ready_) != MC_PIL_OK) {
    throw std::runtime_error("PIL: expected READY (link protocol version " +
                             std::to_string(MC_PIL_VERSION) +
                             ") from the target: is the image built from this tree?");
  }
  if (ready_.version != MC_PIL_VERSION) {
    throw std::runtime_error("PIL: the image speaks link protocol version " +
                             std::to_string(ready_.version) + ", this host " +
                             std::to_string(MC_PIL_VERSION) + ": rebuild the image");
  }
  if (ready_.drive_cfg_err == MC_PIL_READY_ERR_CAPS) {
    throw std::runtime_error(
        "PIL: the image refused the board's capabilities (APP caps): it has no HAL for one of "
        "them");
  }
  if (ready_.drive_cfg_err != MC_DRIVE_CFG_OK) {
    throw std::runtime_error("PIL: the target's drive refused the configuration, bits " +
                             std::to_string(ready_.drive_cfg_err));
  }
}

void PilSession::expect_probe() {
  const std::vector<uint8_t> r = link_.receive_frame();
  if (mc_pil_decode_probe(r.data(), r.size(), &probe_) != MC_PIL_OK) {
    throw std::runtime_error("PIL: expected the application's PROBE at period " +
                             std::to_string(seq_));
  }
  expect_probe2();
}

void PilSession::expect_probe2() {
  const std::vector<uint8_t> r = link_.receive_frame();
  if (mc_pil_decode_probe2(r.data(), r.size(), &probe_) != MC_PIL_OK) {
    throw std::runtime_error("PIL: expected PROBE2 after PROBE at period " + std::to_string(seq_));
  }
}

const mc_pil_out_t& PilSession::step(const PilCommand& cmd,
                                     const std::vector<mc_hal_can_frame_t>& can_rx,
                                     std::vector<PilCanTx>* can_tx) {
  hal_host::PmsmBoard& b = board_;
  b.sample();

  mc_pil_meas_t m{};
  m.seq = seq_;
  m.adc_rc = b.adc_read(&m.adc);
  m.enc_rc = b.encoder_read(&m.enc);
  m.fault_rc = b.fault_read(&m.fault);
  m.temp_rc = b.adc_read_temp(&m.temp);
  // The Hall inputs at the same sample, once per period: what the SIL's
  // drive reads in its fast step (hal_host::HallInput after sample()).
  m.hall_rc = (hall_ != nullptr) ? mc_hal_hall_read(hall_, &m.hall_code) : -ENODEV;
  (void)b.tick_read(&m.tick_ticks);
  (void)b.tick_freq(&m.tick_hz);
  m.cmd_flags =
      (cmd.set_mode ? MC_PIL_CMD_SET_MODE : 0u) | (cmd.set_refs ? MC_PIL_CMD_SET_REFS : 0u);
  m.mode = static_cast<uint32_t>(cmd.mode);
  m.id_ref_a = cmd.id_ref_a;
  m.iq_ref_a = cmd.iq_ref_a;

  std::vector<uint8_t> buf = frame_buf();
  for (const mc_hal_can_frame_t& f : can_rx) {
    const std::size_t k = mc_pil_encode_can_rx(&f, buf.data(), buf.size());
    if (k == 0) throw std::runtime_error("PIL: CAN frame does not fit a link frame");
    link_.send(buf.data(), k);
  }
  const std::size_t n = mc_pil_encode_meas(&m, buf.data(), buf.size());
  link_.send(buf.data(), n);
  bool probed = false;
  for (;;) {
    const std::vector<uint8_t> r = link_.receive_frame();
    const int type = mc_pil_frame_type(r.data(), r.size());
    if (type == MC_PIL_TYPE_CAN_TX) {
      PilCanTx t;
      if (mc_pil_decode_can_tx(r.data(), r.size(), &t.seq, &t.frame) != MC_PIL_OK ||
          t.seq != seq_) {
        throw std::runtime_error("PIL: bad or out-of-sequence CAN_TX frame at period " +
                                 std::to_string(seq_));
      }
      if (can_tx != nullptr) can_tx->push_back(t);
      continue;
    }
    if (type == MC_PIL_TYPE_PROBE && app_mode_ && !probed) {
      if (mc_pil_decode_probe(r.data(), r.size(), &probe_) != MC_PIL_OK) {
        throw std::runtime_error("PIL: bad PROBE frame at period " + std::to_string(seq_));
      }
      expect_probe2();
      probed = true;
      continue;
    }
    if (mc_pil_decode_out(r.data(), r.size(), &out_) != MC_PIL_OK || out_.seq != seq_) {
      throw std::runtime_error("PIL: bad or out-of-sequence OUT frame at period " +
                               std::to_string(seq_));
    }
    break;
  }
  if (app_mode_ && !probed) {
    throw std::runtime_error("PIL: no PROBE before OUT at period " + std::to_string(seq_));
  }

  // What the drive did to the bridge this period, in the board's terms.
  if (out_.duty_set_count > 0u && b.pwm_set_duty(out_.duty_a, out_.duty_b, out_.duty_c) != 0) {
    throw std::runtime_error("PIL: the board refused duties the target accepted");
  }
  if (out_.brake_set_count > 0u && b.brake_set_duty(out_.brake_duty) != 0) {
    throw std::runtime_error("PIL: the board refused a brake duty the target accepted");
  }
  if (out_.gate_kill_count > 0u) b.fault_gate_kill();
  if (out_.pwm_enabled != 0u) {
    (void)b.pwm_enable();
  } else {
    (void)b.pwm_disable();
  }
  b.advance();
  ++seq_;
  return out_;
}

FocPil::FocPil(const FocSilOptions& o, const hal_host::PilLinkOptions& link,
               const std::function<void(mc_drive_cfg_t&)>& tweak_cfg)
    : sil_(o), pil_(sil_.board(), link) {
  mc_drive_cfg_t cfg = sil_.drive().cfg;
  if (tweak_cfg) tweak_cfg(cfg);
  pil_.boot_drive(cfg);
}

FocPil::FocPil(const FocSilOptions& o, const hal_host::PilLinkOptions& link,
               const PilAppSetup& setup)
    : sil_(o), pil_(sil_.board(), link) {
  pil_.boot_app(setup);
}

}  // namespace mcsim
