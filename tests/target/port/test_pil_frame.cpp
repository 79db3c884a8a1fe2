// PIL link frames (firmware/targets/pil/mc_pil_frame.c): round trips keep
// every bit (NaN payloads, -0, extremes), and corrupt or foreign frames are
// refused with their specific error, output untouched.
#include <gtest/gtest.h>

#include <array>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

extern "C" {
#include "mc_pil_frame.h"
#include "mc_pil_probe.h"
}

namespace {

template <class T>
bool same_bits(const T& a, const T& b) {
  return std::memcmp(&a, &b, sizeof a) == 0;
}

float nan_with_payload() {
  const uint32_t b = 0xFFA12345u;  // negative NaN with a payload
  float f;
  std::memcpy(&f, &b, sizeof f);
  return f;
}

TEST(PilFrame, Crc16IsCcittFalse) {
  const char* s = "123456789";
  EXPECT_EQ(mc_pil_crc16(reinterpret_cast<const uint8_t*>(s), 9),
            0x29B1u);  // catalogue check value
}

TEST(PilFrame, MeasRoundTripKeepsEveryBit) {
  mc_pil_meas_t m{};
  m.seq = 0xDEADBEEFu;
  m.adc_rc = -EAGAIN;
  m.adc = {nan_with_payload(),
           -0.0f,
           std::numeric_limits<float>::denorm_min(),
           200.0f,
           MC_HAL_ADC_VALID_ALL,
           123u,
           456u};
  m.enc_rc = 0;
  m.enc = {8191u, 8192u, MC_HAL_ENCODER_FLAG_ALL, 99u};
  m.fault_rc = -EIO;
  m.fault = {1u, 3u, true};
  m.tick_ticks = 0xFFFFFFFFu;
  m.tick_hz = 10000000u;
  m.cmd_flags = MC_PIL_CMD_SET_MODE | MC_PIL_CMD_SET_REFS;
  m.mode = MC_DRIVE_MODE_CURRENT;
  m.id_ref_a = -1.0f;
  m.iq_ref_a = std::numeric_limits<float>::infinity();
  m.temp_rc = -ENOSYS;
  m.temp = {25.0f, nan_with_payload(), 1u, 2u};
  m.hall_rc = -ENODEV;
  m.hall_code = 0xFFFFFFFAu;  // every bit travels: the image checks the range
  uint8_t buf[MC_PIL_MAX_FRAME];
  const size_t n = mc_pil_encode_meas(&m, buf, sizeof buf);
  ASSERT_EQ(n, 3u + 4u * 31u + 2u);  // version 5: the Hall read, two words
  EXPECT_EQ(mc_pil_frame_len(buf, 3), n);
  EXPECT_EQ(mc_pil_frame_type(buf, n), MC_PIL_TYPE_MEAS);
  mc_pil_meas_t d{};
  ASSERT_EQ(mc_pil_decode_meas(buf, n, &d), MC_PIL_OK);
  EXPECT_EQ(d.seq, m.seq);
  EXPECT_EQ(d.adc_rc, m.adc_rc);
  EXPECT_TRUE(same_bits(d.adc.ia_a, m.adc.ia_a));
  EXPECT_TRUE(same_bits(d.adc.ib_a, m.adc.ib_a));
  EXPECT_TRUE(same_bits(d.adc.ic_a, m.adc.ic_a));
  EXPECT_EQ(d.adc.seq, 456u);
  EXPECT_EQ(d.enc.count, 8191u);
  EXPECT_EQ(d.fault_rc, -EIO);
  EXPECT_TRUE(d.fault.gate_killed);
  EXPECT_EQ(d.tick_ticks, 0xFFFFFFFFu);
  EXPECT_EQ(d.tick_hz, 10000000u);
  EXPECT_EQ(d.cmd_flags, m.cmd_flags);
  EXPECT_TRUE(same_bits(d.iq_ref_a, m.iq_ref_a));
  EXPECT_EQ(d.temp_rc, -ENOSYS);
  EXPECT_TRUE(same_bits(d.temp.motor_temp_c, m.temp.motor_temp_c));
  EXPECT_EQ(d.temp.valid_mask, 1u);
  EXPECT_EQ(d.temp.absent_mask, 2u);
  EXPECT_EQ(d.hall_rc, -ENODEV);
  EXPECT_EQ(d.hall_code, 0xFFFFFFFAu);
  m.hall_rc = 0;
  m.hall_code = 5u;
  ASSERT_EQ(mc_pil_encode_meas(&m, buf, sizeof buf), n);
  ASSERT_EQ(mc_pil_decode_meas(buf, n, &d), MC_PIL_OK);
  EXPECT_EQ(d.hall_rc, 0);
  EXPECT_EQ(d.hall_code, 5u);
}

TEST(PilFrame, OutAndCfgRoundTrip) {
  mc_pil_out_t o{};
  o.seq = 7u;
  o.duty_a = 0.25f;
  o.duty_b = nan_with_payload();
  o.cmd_rc = -EBUSY;
  o.ipsr_fast = 34u;
  o.brake_set_count = 1u;
  o.brake_duty = std::nextafter(0.375f, 1.0f);
  uint8_t buf[MC_PIL_MAX_FRAME];
  size_t n = mc_pil_encode_out(&o, buf, sizeof buf);
  mc_pil_out_t od{};
  ASSERT_EQ(mc_pil_decode_out(buf, n, &od), MC_PIL_OK);
  EXPECT_TRUE(same_bits(od, o));

  mc_drive_cfg_t c{};
  c.foc.r_ohm = 0.675f;
  c.foc.kp_q_v_per_a = std::nextafter(1.4326f, 2.0f);
  c.foc.aw = MC_PI_AW_BACK_CALC;
  c.foc.limit_mode = MC_SVPWM_LIMIT_HEXAGON;
  c.foc.decouple = true;
  c.pole_pairs = 4u;
  c.slow_loop_div = 20u;
  c.vbus_max_v = 300.0f;
  n = mc_pil_encode_cfg(&c, buf, sizeof buf);
  mc_drive_cfg_t cd{};
  ASSERT_EQ(mc_pil_decode_cfg(buf, n, &cd), MC_PIL_OK);
  EXPECT_TRUE(same_bits(cd.foc.kp_q_v_per_a, c.foc.kp_q_v_per_a));
  EXPECT_EQ(cd.foc.aw, MC_PI_AW_BACK_CALC);
  EXPECT_EQ(cd.foc.limit_mode, MC_SVPWM_LIMIT_HEXAGON);
  EXPECT_TRUE(cd.foc.decouple);
  EXPECT_EQ(cd.pole_pairs, 4u);
  EXPECT_EQ(cd.slow_loop_div, 20u);
  EXPECT_EQ(cd.vbus_max_v, 300.0f);
}

TEST(PilFrame, CorruptOrForeignFramesAreRefusedAndOutputUntouched) {
  mc_pil_out_t o{};
  o.seq = 1u;
  uint8_t buf[MC_PIL_MAX_FRAME];
  const size_t n = mc_pil_encode_out(&o, buf, sizeof buf);
  mc_pil_out_t d{};
  d.seq = 42u;

  std::vector<uint8_t> bad(buf, buf + n);
  bad[10] ^= 0x01u;  // one bit of the payload
  EXPECT_EQ(mc_pil_decode_out(bad.data(), bad.size(), &d), MC_PIL_ERR_CRC);
  bad.assign(buf, buf + n);
  bad[0] = 0x5A;
  EXPECT_EQ(mc_pil_decode_out(bad.data(), bad.size(), &d), MC_PIL_ERR_SYNC);
  EXPECT_EQ(mc_pil_decode_out(buf, n - 1, &d), MC_PIL_ERR_LEN);
  mc_pil_meas_t m{};
  EXPECT_EQ(mc_pil_decode_meas(buf, n, &m), MC_PIL_ERR_TYPE);
  EXPECT_EQ(mc_pil_decode_out(buf, n, nullptr), MC_PIL_ERR_ARG);
  EXPECT_EQ(d.seq, 42u) << "output written on error";

  EXPECT_EQ(mc_pil_encode_out(&o, buf, n - 1), 0u) << "buffer one byte short";
  EXPECT_EQ(mc_pil_encode_out(&o, nullptr, 0), 0u);
  uint8_t hello[5];
  ASSERT_EQ(mc_pil_encode_hello(hello, sizeof hello), 5u);
  EXPECT_EQ(mc_pil_check_hello(hello, 5), MC_PIL_OK);
  EXPECT_EQ(mc_pil_check_hello(buf, n), MC_PIL_ERR_TYPE);
}

}  // namespace

namespace {

// 0xF0 ^ i at byte i: a CAN payload pattern whose bytes all differ.
constexpr std::array<uint8_t, MC_HAL_CAN_FD_MAX_LEN> kPattern = [] {
  std::array<uint8_t, MC_HAL_CAN_FD_MAX_LEN> p{};
  for (size_t i = 0; i < p.size(); ++i) p[i] = static_cast<uint8_t>(0xF0u ^ i);
  return p;
}();

TEST(PilFrame, WholeImageFramesRoundTrip) {
  uint8_t buf[MC_PIL_MAX_FRAME];
  // PARAMS: up to MC_PIL_PARAMS_MAX pairs per frame, none or more refused.
  uint32_t ids[MC_PIL_PARAMS_MAX + 1], raws[MC_PIL_PARAMS_MAX + 1];
  for (uint32_t i = 0; i <= MC_PIL_PARAMS_MAX; ++i) {
    ids[i] = 100u + i;
    raws[i] = 0xA5000000u ^ i;
  }
  EXPECT_EQ(mc_pil_encode_params(ids, raws, 0u, buf, sizeof buf), 0u);
  EXPECT_EQ(mc_pil_encode_params(ids, raws, MC_PIL_PARAMS_MAX + 1u, buf, sizeof buf), 0u);
  size_t n = mc_pil_encode_params(ids, raws, MC_PIL_PARAMS_MAX, buf, sizeof buf);
  ASSERT_GT(n, 0u);
  uint32_t ids_d[MC_PIL_PARAMS_MAX] = {}, raws_d[MC_PIL_PARAMS_MAX] = {}, k = 0;
  ASSERT_EQ(mc_pil_decode_params(buf, n, ids_d, raws_d, &k), MC_PIL_OK);
  ASSERT_EQ(k, MC_PIL_PARAMS_MAX);
  for (uint32_t i = 0; i < k; ++i) {
    EXPECT_EQ(ids_d[i], ids[i]);
    EXPECT_EQ(raws_d[i], raws[i]);
  }

  mc_pil_app_t a{};
  a.tm_budget_frac = 0.5f;
  a.tm_ext_rate_hz[4] = 50u;
  a.tm_budget_frac = std::nextafter(0.378f, 1.0f);
  a.tick_hz = 0xFFFFFFFFu;
  a.slow_loop_div_fixed = 10u;
  a.caps = MC_PIL_CAP_BRAKE | MC_PIL_CAP_HALL;
  n = mc_pil_encode_app(&a, buf, sizeof buf);
  ASSERT_EQ(n, 3u + 4u * 12u + 2u);  // version 5 keeps version 3's size: caps
  mc_pil_app_t ad{};
  ASSERT_EQ(mc_pil_decode_app(buf, n, &ad), MC_PIL_OK);
  EXPECT_TRUE(same_bits(ad, a));

  // CAN frames of every data length keep their bytes; the TX seq travels.
  for (uint8_t len : {0, 1, 3, 4, 5, 8, 12, 64}) {
    mc_hal_can_frame_t f{};
    f.id = 0x7FFu;
    f.timestamp_ticks = 0x12345678u;
    f.len = len;
    f.flags = (len > 8u) ? MC_HAL_CAN_FLAG_FD : 0u;
    // The first len bytes of a fixed pattern (bytes past len stay 0, as the
    // decoder leaves them). Copied, not written byte by byte in a loop over
    // len: GCC 12 at -O2/-O3 unrolls that loop for every len of the list and
    // warns (stringop-overflow) about writes it has proved unreachable.
    std::memcpy(f.data, kPattern.data(), len);
    n = mc_pil_encode_can_rx(&f, buf, sizeof buf);
    mc_hal_can_frame_t fd{};
    ASSERT_EQ(mc_pil_decode_can_rx(buf, n, &fd), MC_PIL_OK) << int(len);
    EXPECT_TRUE(same_bits(fd, f)) << int(len);
    n = mc_pil_encode_can_tx(42u, &f, buf, sizeof buf);
    uint32_t seq = 0;
    mc_hal_can_frame_t ft{};
    ASSERT_EQ(mc_pil_decode_can_tx(buf, n, &seq, &ft), MC_PIL_OK) << int(len);
    EXPECT_EQ(seq, 42u);
    EXPECT_TRUE(same_bits(ft, f)) << int(len);
    // The wrong decoder refuses it.
    EXPECT_EQ(mc_pil_decode_can_rx(buf, n, &fd), MC_PIL_ERR_TYPE);
  }
}

TEST(PilFrame, CanFrameWithALengthThatIsNoCanLengthIsRefused) {
  mc_hal_can_frame_t f{};
  f.id = 0x21u;
  f.len = 8u;
  uint8_t buf[MC_PIL_MAX_FRAME];
  size_t n = mc_pil_encode_can_rx(&f, buf, sizeof buf);
  // Claim 12 bytes in the length word (an FD length, but the payload holds
  // two data words, not three), then 9 (no CAN FD length). Re-seal the CRC
  // each time so only the length check can refuse it.
  for (uint8_t bad : {12, 9}) {
    buf[MC_PIL_HEADER_LEN + 8u] = bad;
    const uint16_t crc = mc_pil_crc16(&buf[1], n - 1u - MC_PIL_CRC_LEN);
    buf[n - 2u] = static_cast<uint8_t>(crc & 0xFFu);
    buf[n - 1u] = static_cast<uint8_t>(crc >> 8);
    mc_hal_can_frame_t fd{};
    fd.id = 0x555u;
    EXPECT_EQ(mc_pil_decode_can_rx(buf, n, &fd), MC_PIL_ERR_LEN) << int(bad);
    EXPECT_EQ(fd.id, 0x555u) << "output untouched";
  }
}

// Version 3 (the brake chopper in APP and OUT): READY carries the protocol version; a version-1 READY (two
// words) is refused by length, so a stale image stops the host at READY.
TEST(PilFrame, ReadyCarriesTheProtocolVersion) {
  uint8_t buf[MC_PIL_MAX_FRAME];
  const mc_pil_ready_t r = {7u, 168000000u, MC_PIL_VERSION};
  size_t n = mc_pil_encode_ready(&r, buf, sizeof buf);
  mc_pil_ready_t d{};
  ASSERT_EQ(mc_pil_decode_ready(buf, n, &d), MC_PIL_OK);
  EXPECT_TRUE(same_bits(d, r));
  EXPECT_EQ(d.version, 6u);  // 6: PROBE2 (the probe past a frame), FLASH (the board's flash)
  const uint32_t v1[2] = {0u, 0u};
  n = mc_pil_encode_words(MC_PIL_TYPE_READY, v1, 2u, buf, sizeof buf);
  ASSERT_GT(n, 0u);
  mc_pil_ready_t untouched = r;
  EXPECT_EQ(mc_pil_decode_ready(buf, n, &untouched), MC_PIL_ERR_LEN);
  EXPECT_TRUE(same_bits(untouched, r));
}

// PROBE: every field of mc_app_probe_t keeps its bits (NaN payload, -0,
// the last field); a short, foreign or corrupt frame is refused, output
// untouched.
TEST(PilFrame, ProbeRoundTripKeepsEveryBit) {
  uint8_t buf[MC_PIL_MAX_FRAME];
  mc_app_probe_t p{};
  p.mode = 3u;
  p.first_fault = 0xFFFFFFFFu;
  p.id_ref_a = -0.0f;
  p.iq_a = nan_with_payload();
  p.omega_m_rad_s = std::numeric_limits<float>::denorm_min();
  p.pos_turns = -123456;
  p.pos_traj_k = 0xDEADBEEFu;
  p.sls_omega_if_rad_s = -0.0f;
  p.i_limit_a = nan_with_payload();
  p.hall_error = 0xA5A5A5A5u;       // the last field of PROBE
  p.cog_status = 4u;                // the first of PROBE2
  p.cog_ff_a = nan_with_payload();  // the last field
  const size_t n2 = mc_pil_encode_probe2(&p, buf, sizeof buf);
  ASSERT_EQ(n2, MC_PIL_HEADER_LEN + 4u * MC_PIL_PROBE2_WORDS + MC_PIL_CRC_LEN);
  EXPECT_EQ(mc_pil_frame_type(buf, n2), MC_PIL_TYPE_PROBE2);
  mc_app_probe_t d{};
  ASSERT_EQ(mc_pil_decode_probe2(buf, n2, &d), MC_PIL_OK);
  EXPECT_EQ(mc_pil_decode_probe(buf, n2, &d), MC_PIL_ERR_TYPE);  // a PROBE2 is not a PROBE
  const size_t n = mc_pil_encode_probe(&p, buf, sizeof buf);
  ASSERT_EQ(n, MC_PIL_HEADER_LEN + 4u * MC_PIL_PROBE1_WORDS + MC_PIL_CRC_LEN);
  EXPECT_EQ(MC_PIL_PROBE1_WORDS + MC_PIL_PROBE2_WORDS, sizeof(mc_app_probe_t) / 4u);
  ASSERT_EQ(mc_pil_decode_probe(buf, n, &d), MC_PIL_OK);
  EXPECT_TRUE(same_bits(d, p));  // the two parts make the whole probe
  EXPECT_EQ(mc_pil_frame_type(buf, n), MC_PIL_TYPE_PROBE);
  EXPECT_EQ(mc_pil_encode_probe(&p, buf, n - 1u), 0u);  // does not fit
  EXPECT_EQ(mc_pil_encode_probe(nullptr, buf, sizeof buf), 0u);

  mc_app_probe_t untouched{};
  untouched.mode = 9u;
  const mc_app_probe_t before = untouched;
  buf[10] ^= 0x01u;  // one bit of the payload
  EXPECT_EQ(mc_pil_decode_probe(buf, n, &untouched), MC_PIL_ERR_CRC);
  EXPECT_TRUE(same_bits(untouched, before));
  const size_t k = mc_pil_encode_hello(buf, sizeof buf);
  EXPECT_EQ(mc_pil_decode_probe(buf, k, &untouched), MC_PIL_ERR_TYPE);
  uint32_t words[MC_PIL_PROBE_WORDS] = {};
  const size_t m =
      mc_pil_encode_words(MC_PIL_TYPE_PROBE, words, MC_PIL_PROBE1_WORDS - 1u, buf, sizeof buf);
  EXPECT_EQ(mc_pil_decode_probe(buf, m, &untouched), MC_PIL_ERR_LEN);
  EXPECT_TRUE(same_bits(untouched, before));
  EXPECT_EQ(
      mc_pil_encode_words(MC_PIL_TYPE_PROBE, words, MC_PIL_MAX_PAYLOAD / 4u + 1u, buf, sizeof buf),
      0u);
}

}  // namespace

namespace {

// Version 3: OUT carries the brake chopper's duty (23 words), APP whether
// the board has one (10 words); a version-2 OUT (21 words) or APP (9 words)
// is refused by length and leaves the output as it was.
TEST(PilFrame, Version2OutAndAppAreRefused) {
  uint8_t buf[MC_PIL_MAX_FRAME];
  const uint32_t v2_out[21] = {};
  size_t n = mc_pil_encode_words(MC_PIL_TYPE_OUT, v2_out, 21u, buf, sizeof buf);
  ASSERT_GT(n, 0u);
  mc_pil_out_t o{};
  o.brake_duty = 0.5f;
  EXPECT_EQ(mc_pil_decode_out(buf, n, &o), MC_PIL_ERR_LEN);
  EXPECT_EQ(o.brake_duty, 0.5f);
  const uint32_t v2_app[9] = {};
  n = mc_pil_encode_words(MC_PIL_TYPE_APP, v2_app, 9u, buf, sizeof buf);
  ASSERT_GT(n, 0u);
  mc_pil_app_t a{};
  a.caps = 7u;
  EXPECT_EQ(mc_pil_decode_app(buf, n, &a), MC_PIL_ERR_LEN);
  EXPECT_EQ(a.caps, 7u);
}

// Version 5: MEAS carries the Hall read (31 words); a version-4 MEAS (29
// words) is refused by length and leaves the output as it was. The brake
// keeps its bit value of version 3 and 4 (has_brake 1), so APP's layout is
// the same and a host and an image of different versions meet at READY,
// where the host refuses the image by its version (foc_pil.cpp).
TEST(PilFrame, Version4MeasIsRefusedAndTheBrakeKeepsItsBit) {
  uint8_t buf[MC_PIL_MAX_FRAME];
  const uint32_t v4_meas[29] = {};
  const size_t n = mc_pil_encode_words(MC_PIL_TYPE_MEAS, v4_meas, 29u, buf, sizeof buf);
  ASSERT_GT(n, 0u);
  mc_pil_meas_t m{};
  m.hall_code = 3u;
  EXPECT_EQ(mc_pil_decode_meas(buf, n, &m), MC_PIL_ERR_LEN);
  EXPECT_EQ(m.hall_code, 3u);
  EXPECT_EQ(MC_PIL_CAP_BRAKE, 1u);
  EXPECT_EQ(MC_PIL_CAP_ALL & MC_PIL_CAP_HALL, MC_PIL_CAP_HALL);
  EXPECT_EQ(MC_PIL_VERSION, 6u);
}

// FLASH (version 6): an offset and whole words of the board's flash, the
// bytes decoded in place; a partial word, an empty or oversize chunk refused.
TEST(PilFrame, FlashRoundTripAndRefusals) {
  uint8_t buf[MC_PIL_MAX_FRAME];
  std::vector<uint8_t> data(MC_PIL_FLASH_CHUNK);
  for (std::size_t i = 0; i < data.size(); ++i) data[i] = static_cast<uint8_t>(i * 7u + 1u);
  const size_t n = mc_pil_encode_flash(0x7F00u, data.data(), MC_PIL_FLASH_CHUNK, buf, sizeof buf);
  ASSERT_EQ(n, MC_PIL_MAX_FRAME);  // the largest chunk fills a frame
  uint32_t off = 0, len = 0;
  const uint8_t* p = nullptr;
  ASSERT_EQ(mc_pil_decode_flash(buf, n, &off, &p, &len), MC_PIL_OK);
  EXPECT_EQ(off, 0x7F00u);
  ASSERT_EQ(len, MC_PIL_FLASH_CHUNK);
  EXPECT_EQ(std::memcmp(p, data.data(), len), 0);
  EXPECT_EQ(mc_pil_encode_flash(0u, data.data(), 6u, buf, sizeof buf), 0u);  // not whole words
  EXPECT_EQ(mc_pil_encode_flash(0u, data.data(), 0u, buf, sizeof buf), 0u);
  EXPECT_EQ(mc_pil_encode_flash(0u, data.data(), MC_PIL_FLASH_CHUNK + 4u, buf, sizeof buf), 0u);
  const uint32_t one[1] = {5u};  // an offset without bytes
  const size_t m = mc_pil_encode_words(MC_PIL_TYPE_FLASH, one, 1u, buf, sizeof buf);
  EXPECT_EQ(mc_pil_decode_flash(buf, m, &off, &p, &len), MC_PIL_ERR_LEN);
  const size_t k = mc_pil_encode_hello(buf, sizeof buf);
  EXPECT_EQ(mc_pil_decode_flash(buf, k, &off, &p, &len), MC_PIL_ERR_TYPE);
}

}  // namespace
