// libFuzzer target: the CAN command handler and the frame unpackers under
// arbitrary frames (ids, flags, lengths up to 64, payloads) interleaved with
// supervision ticks and telemetry. Each 12-byte record of the input:
//   [0]     op: bits 0-1: 0/1 frame to the handler, 2 tick(s), 3 telemetry
//               bits 2-7: ticks to run for op 2
//   [1..2]  id (little-endian, 11 bits; bit 15 = extended, bit 14 = RTR,
//               bit 13 = FD)
//   [3]     length (taken mod 65)
//   [4..11] first data bytes (the rest of an FD payload repeats them)
// Invariants checked after every record:
//   - unpack accepts a frame only with the DBC's exact length, and every
//     decoded value lies within its signal's range (half a step of slack);
//     repacking the values gives back the same frame data;
//   - the handler's result is NONE, IGNORED or a code the DBC defines, and
//     a rejected frame (not IGNORED) produced exactly one CMD_ERROR unless
//     the reply limiter took it (counted);
//   - a PARAM_REQ for this node that the handler accepted got exactly one
//     PARAM_REPLY with its opcode and id and a status the DBC defines, at
//     once or (held by the reply limiter) at a later tick, and nothing
//     else is ever sent; one refused LIMITED came while a reply was held;
//   - the keep-alive: only an accepted HOST_HEARTBEAT or the enable of a
//     run resets the command timeout, and after a tick a run that is
//     neither stopping nor ended has had one within timeout_s;
//   - the reply limiter's bucket never holds more than its depth;
//   - enabled only while the drive runs (CURRENT/CTRL), stopping implies
//     enabled; |references| within the drive's i_max (the one in force:
//     an APPLY may change it).
// The parameter service is attached as on the MCU, with the configuration
// store on a fake flash of two 1 KiB sectors (two records each, so a few
// SAVEs go through append, erase and switch); the drive runs the stored
// configuration (the table's defaults: the flash starts erased each input).
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>

extern "C" {
#include "mc_can_cmd.h"
#include "mc_can_proto.h"
#include "mc_cfg_store.h"
#include "mc_drive.h"
#include "mc_fake_flash.h"
#include "mc_hal_fake.h"
#include "mc_param_srv.h"
#include "mc_params.h"
#include "mc_telemetry.h"
}

namespace {

void require(bool ok) {
  if (!ok) std::abort();
}

int speed_hook(void*, float w) {
  return std::fabs(w) > 150.0f ? -1 : 0;
}

void check_unpack(const mc_hal_can_frame_t& f) {
  float v[MC_CAN_NSIG_MAX];
  uint32_t m = MC_CAN_MSG_COUNT;
  const mc_can_err_t e = mc_can_proto_unpack(&f, &m, v, MC_CAN_NSIG_MAX);
  if (e != MC_CAN_ERR_NONE) {
    require(e == MC_CAN_ERR_FORMAT || e == MC_CAN_ERR_UNKNOWN_CMD || e == MC_CAN_ERR_LENGTH ||
            e == MC_CAN_ERR_RANGE);
    return;
  }
  const mc_can_message_t& g = mc_can_messages[m];
  require(f.len == g.dlc && f.flags == 0u);
  for (uint32_t i = 0; i < g.n_signals; ++i) {
    const mc_can_signal_t& s = g.signals[i];
    require(std::isfinite(v[i]) && v[i] >= s.min - 0.5f * s.scale &&
            v[i] <= s.max + 0.5f * s.scale);
  }
  // A raw integer signal wider than a float's 24-bit mantissa (PARAM_REQ.value:
  // 32 raw bits, which the handler reads from the frame, not from the
  // float) does not survive the float round trip: no repack check then.
  for (uint32_t i = 0; i < g.n_signals; ++i) {
    if (g.signals[i].length > 24u && g.signals[i].scale == 1.0f) return;
  }
  // node 63 (broadcast) decodes but is never packed: repack as node 1
  const uint32_t node = mc_can_id_node(f.id) <= MC_CAN_NODE_ID_MAX ? mc_can_id_node(f.id) : 1u;
  mc_hal_can_frame_t r{};
  require(mc_can_proto_pack(m, node, v, MC_CAN_NSIG_MAX, &r) == MC_CAN_ERR_NONE);
  require(r.id == mc_can_id(node, mc_can_id_cmd(f.id)) && r.len == f.len);
  // bits outside every signal are not carried: compare signal by signal
  float w[MC_CAN_NSIG_MAX];
  uint32_t m2;
  require(mc_can_proto_unpack(&r, &m2, w, MC_CAN_NSIG_MAX) == MC_CAN_ERR_NONE && m2 == m);
  // Values travel as floats: v = raw * scale rounded to a float, and pack
  // rounds v / scale back to the raw grid. Both w and v lie on the raw grid
  // (up to float rounding), so they must agree to half a step plus two float
  // roundings (pack divides, unpack multiplies; each below 2^-24 |v|, so
  // below one float spacing at |v|). Where the float's spacing at |v| is well
  // below the step this allows no other raw value: the round trip is exact.
  // Where it is not (SPEED.omega_m_rad_s, 24 bits of 1 mrad/s, near 8388
  // rad/s: spacing 0.98 mrad/s; SET_POSITION_REF's 32 bits of 0.1 mrad
  // beyond about 800 rad), the float itself cannot tell the neighbouring raw
  // values apart, and the bound allows exactly that.
  for (uint32_t i = 0; i < g.n_signals; ++i) {
    const float a = std::fabs(v[i]);
    const float ulp = std::nextafter(a, INFINITY) - a;
    require(std::fabs(w[i] - v[i]) <= 0.5f * g.signals[i].scale + 2.0f * ulp);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static mc_hal_fake_t fake;
  mc_hal_fake_config_t fcfg;
  require(mc_hal_fake_config_default(&fcfg) == 0);
  require(mc_hal_fake_init(&fake, &fcfg) == 0);
  // Boot as on the MCU: the store on the (erased) flash, the drive from it.
  static uint8_t flash_mem[2u * 1024u];
  std::memset(flash_mem, 0xFF, sizeof flash_mem);
  static mc_fake_flash_t flash;
  const uint32_t sectors[2] = {1024u, 1024u};
  require(mc_fake_flash_init(&flash, flash_mem, sectors, 2u) == 0);
  static mc_cfg_store_t store;
  const mc_cfg_store_cfg_t scfg{&flash.dev, {0u, 1u}, 0u};
  require(mc_cfg_store_init(&store, &scfg) == 0);
  mc_params_t p;
  const mc_cfg_boot_t boot = mc_cfg_store_load(&store, &p);
  require(boot == MC_CFG_BOOT_EMPTY);
  mc_drive_t d;
  mc_drive_cfg_t dc;
  require(mc_params_to_drive_cfg(&p, &dc) == MC_PARAMS_OK);
  require(mc_drive_init(&d, &dc, &fake.board) == MC_DRIVE_CFG_OK);
  require(mc_hal_fake_encoder_set(&fake, 0u, MC_HAL_ENCODER_FLAG_VALID) == 0);
  mc_telemetry_cfg_t tc{};
  tc.node_id = 1;
  tc.bitrate_bps = 250000;
  tc.bus_budget_frac = 0.5f;
  tc.tick_hz = 1000;
  tc.rate_hz[MC_TM_HEARTBEAT] = 10;
  tc.rate_hz[MC_TM_CURRENTS] = 100;
  mc_telemetry_t tm;
  require(mc_telemetry_init(&tm, &tc) == MC_TM_CFG_OK);
  mc_can_cmd_cfg_t cc{};
  cc.node_id = 1;
  cc.tick_hz = 1000;
  cc.timeout_s = 0.02f;
  cc.stop_ramp_a_per_s = 500.0f;
  cc.stop_decel_rad_s2 = 2000.0f;
  cc.speed_max_rad_s = 200.0f;
  cc.set_speed_ref = speed_hook;
  cc.speed_drive_mode = MC_DRIVE_MODE_CURRENT;
  cc.position_drive_mode = MC_DRIVE_MODE_IDLE;
  mc_can_cmd_t c;
  require(mc_can_cmd_init(&c, &cc, &d, &tm) == MC_CAN_CMD_CFG_OK);
  static mc_param_srv_t srv;
  require(mc_param_srv_init(&srv, &p, &d, &fake.board, &store, static_cast<uint8_t>(boot)) == 0);
  mc_can_cmd_attach_params(&c, &srv);
  const mc_telemetry_src_t src{&d, &c, nullptr, nullptr};

  for (size_t k = 0; k + 12 <= size; k += 12) {
    const uint8_t* r = data + k;
    const unsigned op = r[0] & 3u;
    if (op <= 1u) {
      mc_hal_can_frame_t f{};
      const uint16_t raw = static_cast<uint16_t>(r[1] | (r[2] << 8));
      f.id = raw & 0x7FFu;
      if (raw & 0x8000u) f.flags |= MC_HAL_CAN_FLAG_EXT;
      if (raw & 0x4000u) f.flags |= MC_HAL_CAN_FLAG_RTR;
      if (raw & 0x2000u) f.flags |= MC_HAL_CAN_FLAG_FD;
      f.len = static_cast<uint8_t>(r[3] % 65u);
      for (unsigned i = 0; i < MC_HAL_CAN_FD_MAX_LEN; ++i) f.data[i] = r[4 + (i % 8u)];
      check_unpack(f);
      const uint32_t rejected = c.rx_rejected;
      const uint32_t limited = c.reply_limited;
      const bool held_before = c.held_have;
      const uint32_t alive_before = c.ticks_since_alive;
      const bool enabled_before = c.enabled;
      const mc_can_err_t e = mc_can_cmd_handle(&c, &f, &fake.can_dev);
      require(e == MC_CAN_ERR_NONE || e == MC_CAN_ERR_IGNORED ||
              (e >= MC_CAN_ERR_UNKNOWN_CMD && e <= MC_CAN_ERR_LIMITED));
      require(e != MC_CAN_ERR_LIMITED || held_before || mc_can_id_cmd(f.id) == MC_CAN_CMD_BOOT_REQ);
      // only a fresh HOST_HEARTBEAT or the start of a run is a keep-alive
      if (c.ticks_since_alive != alive_before) {
        require(c.ticks_since_alive == 0u && e == MC_CAN_ERR_NONE &&
                (mc_can_id_cmd(f.id) == MC_CAN_CMD_HOST_HEARTBEAT ||
                 (mc_can_id_cmd(f.id) == MC_CAN_CMD_SET_ENABLE && !enabled_before && c.enabled)));
      }
      // a rejection is answered unless the reply rate limit took it
      const bool limited_now = c.reply_limited != limited;
      const bool rej = (e != MC_CAN_ERR_NONE && e != MC_CAN_ERR_IGNORED);
      require(c.rx_rejected == rejected + (rej ? 1u : 0u));
      const bool param_req = e == MC_CAN_ERR_NONE && mc_can_id_cmd(f.id) == MC_CAN_CMD_PARAM_REQ;
      mc_hal_can_frame_t out;
      uint32_t replies = 0, param_replies = 0;
      while (mc_hal_fake_can_tx_pop(&fake, &out) == 0) {
        float v[MC_CAN_NSIG_MAX];
        uint32_t m;
        require(mc_can_proto_unpack(&out, &m, v, MC_CAN_NSIG_MAX) == MC_CAN_ERR_NONE);
        if (m == MC_CAN_MSG_PARAM_REPLY) {
          require(param_req && out.data[0] == f.data[0] && out.data[1] == f.data[1] &&
                  out.data[2] == f.data[2] && out.data[3] <= MC_PARAM_ERR_RATE_LIMIT);
          ++param_replies;
          continue;
        }
        require(m == MC_CAN_MSG_CMD_ERROR && v[MC_CAN_CMD_ERROR_ERROR] == static_cast<float>(e));
        ++replies;
      }
      require(replies == ((rej && !limited_now) ? 1u : 0u));
      require(!limited_now || rej);
      // answered now, or held for a later tick (then the slot was free)
      const bool held_now = param_req && !held_before && c.held_have;
      require(param_replies == ((param_req && !held_now) ? 1u : 0u));
      if (held_now) {
        require(c.held.data[0] == f.data[0] && c.held.data[1] == f.data[1] &&
                c.held.data[2] == f.data[2] && c.held.data[3] <= MC_PARAM_ERR_RATE_LIMIT);
      }
    } else if (op == 2u) {
      const unsigned n = 1u + (r[0] >> 2);
      for (unsigned i = 0; i < n; ++i) {
        (void)mc_hal_fake_adc_set_sample(
            &fake, 0.0f, 0.0f, 0.0f, 24.0f,
            MC_HAL_ADC_VALID_IA | MC_HAL_ADC_VALID_IB | MC_HAL_ADC_VALID_VBUS);
        for (unsigned j = 0; j < d.cfg.slow_loop_div; ++j) {
          if (mc_drive_fast_step(&d)) mc_drive_slow_step(&d);
        }
        const bool held = c.held_have;
        const mc_hal_can_frame_t held_f = c.held;
        mc_can_cmd_step(&c);
        require(!c.enabled || c.stopping || c.ticks_since_alive < c.timeout_ticks);
        // a tick sends nothing but the held PARAM_REPLY
        mc_hal_can_frame_t out;
        uint32_t n_out = 0;
        while (mc_hal_fake_can_tx_pop(&fake, &out) == 0) {
          require(held && !c.held_have && out.id == held_f.id && out.len == held_f.len &&
                  std::memcmp(out.data, held_f.data, out.len) == 0);
          ++n_out;
        }
        require(n_out <= 1u);
      }
    } else {
      (void)mc_telemetry_step(&tm, &fake.can_dev, &src);
      mc_hal_can_frame_t out;
      while (mc_hal_fake_can_tx_pop(&fake, &out) == 0) {
        float v[MC_CAN_NSIG_MAX];
        uint32_t m;
        require(mc_can_proto_unpack(&out, &m, v, MC_CAN_NSIG_MAX) == MC_CAN_ERR_NONE);
      }
    }
    require(!c.stopping || c.enabled);
    require(c.reply.tokens <= MC_TM_REPLY_BURST);
    require(!c.enabled || d.mode == MC_DRIVE_MODE_CURRENT || d.mode == MC_DRIVE_MODE_CTRL);
    require(std::fabs(d.id_ref_a) <= d.cfg.i_max_a && std::fabs(d.iq_ref_a) <= d.cfg.i_max_a);
  }
  return 0;
}
