#include "foc_pil.hpp"

#include <stdexcept>
#include <string>
#include <vector>

namespace mcsim {

namespace {

std::vector<uint8_t> frame_buf() {
  return std::vector<uint8_t>(MC_PIL_MAX_FRAME);
}

}  // namespace

FocPil::FocPil(const FocSilOptions& o, const hal_host::PilLinkOptions& link,
               const std::function<void(mc_drive_cfg_t&)>& tweak_cfg)
    : sil_(o), link_(link) {
  const std::vector<uint8_t> hello = link_.receive_frame();
  if (mc_pil_check_hello(hello.data(), hello.size()) != MC_PIL_OK) {
    throw std::runtime_error("FocPil: expected HELLO from the target");
  }
  mc_drive_cfg_t cfg = sil_.drive().cfg;
  if (tweak_cfg) tweak_cfg(cfg);
  std::vector<uint8_t> buf = frame_buf();
  const std::size_t n = mc_pil_encode_cfg(&cfg, buf.data(), buf.size());
  link_.send(buf.data(), n);
  const std::vector<uint8_t> r = link_.receive_frame();
  if (mc_pil_decode_ready(r.data(), r.size(), &ready_) != MC_PIL_OK) {
    throw std::runtime_error("FocPil: expected READY from the target");
  }
  if (ready_.drive_cfg_err != MC_DRIVE_CFG_OK) {
    throw std::runtime_error("FocPil: the target's drive refused the configuration, bits " +
                             std::to_string(ready_.drive_cfg_err));
  }
}

const mc_pil_out_t& FocPil::step(const PilCommand& cmd) {
  hal_host::PmsmBoard& b = sil_.board();
  b.sample();

  mc_pil_meas_t m{};
  m.seq = seq_;
  m.adc_rc = b.adc_read(&m.adc);
  m.enc_rc = b.encoder_read(&m.enc);
  m.fault_rc = b.fault_read(&m.fault);
  (void)b.tick_read(&m.tick_ticks);
  (void)b.tick_freq(&m.tick_hz);
  m.cmd_flags =
      (cmd.set_mode ? MC_PIL_CMD_SET_MODE : 0u) | (cmd.set_refs ? MC_PIL_CMD_SET_REFS : 0u);
  m.mode = static_cast<uint32_t>(cmd.mode);
  m.id_ref_a = cmd.id_ref_a;
  m.iq_ref_a = cmd.iq_ref_a;

  std::vector<uint8_t> buf = frame_buf();
  const std::size_t n = mc_pil_encode_meas(&m, buf.data(), buf.size());
  link_.send(buf.data(), n);
  const std::vector<uint8_t> r = link_.receive_frame();
  if (mc_pil_decode_out(r.data(), r.size(), &out_) != MC_PIL_OK || out_.seq != seq_) {
    throw std::runtime_error("FocPil: bad or out-of-sequence OUT frame at period " +
                             std::to_string(seq_));
  }

  // What the drive did to the bridge this period, in the board's terms.
  if (out_.duty_set_count > 0u && b.pwm_set_duty(out_.duty_a, out_.duty_b, out_.duty_c) != 0) {
    throw std::runtime_error("FocPil: the board refused duties the target accepted");
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

}  // namespace mcsim
