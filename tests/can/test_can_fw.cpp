// CAN protocol codec, telemetry scheduler and command handler
// (firmware/app/mc_can_proto, mc_telemetry, mc_can_cmd) on the fake HAL
// board, with the drive application of tests/unit/app's fixture.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <deque>
#include <random>

#include "app_test_fixture.h"
extern "C" {
#include "mc_can_cmd.h"
#include "mc_can_proto.h"
#include "mc_telemetry.h"
}

namespace {

using apptest::AppDrive;

// Rounding to the nearest raw value: at most half a step, plus float32
// arithmetic in (v - offset) / scale and raw * scale (a few ulp of v).
float QuantTol(const mc_can_signal_t& s, float v) {
  return 0.5f * s.scale + 4.0f * 1.2e-7f * std::fmax(1.0f, std::fabs(v));
}

mc_hal_can_frame_t Frame(uint32_t id, std::initializer_list<uint8_t> bytes, uint8_t flags = 0) {
  mc_hal_can_frame_t f{};
  f.id = id;
  f.flags = flags;
  f.len = static_cast<uint8_t>(bytes.size());
  size_t i = 0;
  for (uint8_t b : bytes) f.data[i++] = b;
  return f;
}

// ------------------------------------------------------------- codec
TEST(CanProto, IdentifierLayout) {
  EXPECT_EQ(0x032u, mc_can_id(1u, MC_CAN_CMD_SET_CURRENT_REF));
  EXPECT_EQ(0x7FFu, mc_can_id(63u, 31u));
  EXPECT_EQ(5u, mc_can_id_node(mc_can_id(5u, 0x17u)));
  EXPECT_EQ(0x17u, mc_can_id_cmd(mc_can_id(5u, 0x17u)));
  EXPECT_EQ(MC_CAN_MSG_HEARTBEAT, mc_can_proto_find(MC_CAN_CMD_HEARTBEAT));
  EXPECT_EQ(MC_CAN_MSG_COUNT, mc_can_proto_find(0x0Du));  // unused id
}

// The same values cantools encodes to e8030030f8ff0005 (checked by hand
// with cantools when the DBC was written; tests/can/test_dbc_c.py checks
// every message against cantools at run time).
TEST(CanProto, KnownFrameBytes) {
  const float v[] = {1.0f, -2.0f, 0.0f, 5.0f};
  mc_hal_can_frame_t f{};
  ASSERT_EQ(MC_CAN_ERR_NONE, mc_can_proto_pack(MC_CAN_MSG_CURRENTS, 1u, v, 4u, &f));
  const uint8_t want[8] = {0xe8, 0x03, 0x00, 0x30, 0xf8, 0xff, 0x00, 0x05};
  EXPECT_EQ(0x022u, f.id);
  EXPECT_EQ(8u, f.len);
  EXPECT_EQ(0u, f.flags);
  EXPECT_EQ(0, std::memcmp(want, f.data, 8));
}

TEST(CanProto, RoundTripEveryMessageWithinHalfAStep) {
  std::mt19937 rng(7);
  for (uint32_t m = 0; m < MC_CAN_MSG_COUNT; ++m) {
    const mc_can_message_t& msg = mc_can_messages[m];
    for (int trial = 0; trial < 200; ++trial) {
      float v[MC_CAN_NSIG_MAX] = {0};
      for (uint32_t i = 0; i < msg.n_signals; ++i) {
        std::uniform_real_distribution<float> u(msg.signals[i].min, msg.signals[i].max);
        v[i] = u(rng);
        if (msg.signals[i].scale == 1.0f) v[i] = std::round(v[i]);  // enumerations, counters
      }
      mc_hal_can_frame_t f{};
      ASSERT_EQ(MC_CAN_ERR_NONE, mc_can_proto_pack(m, 3u, v, MC_CAN_NSIG_MAX, &f));
      EXPECT_EQ(mc_can_id(3u, msg.cmd), f.id);
      EXPECT_EQ(msg.dlc, f.len);
      float back[MC_CAN_NSIG_MAX] = {0};
      uint32_t got = 99;
      ASSERT_EQ(MC_CAN_ERR_NONE, mc_can_proto_unpack(&f, &got, back, MC_CAN_NSIG_MAX))
          << "message " << m;
      ASSERT_EQ(m, got);
      for (uint32_t i = 0; i < msg.n_signals; ++i) {
        EXPECT_NEAR(v[i], back[i], QuantTol(msg.signals[i], v[i]))
            << "message " << m << " signal " << i;
      }
    }
  }
}

TEST(CanProto, PackSaturatesAndMapsNaNToZero) {
  const mc_can_signal_t& s = mc_can_messages[MC_CAN_MSG_CURRENTS].signals[MC_CAN_CURRENTS_I_Q_A];
  const float big[] = {1e5f, -1e5f, 0.0f, 0.0f};
  const float odd[] = {NAN, INFINITY, 0.0f, 0.0f};
  mc_hal_can_frame_t f{};
  float v[4];
  uint32_t m;
  ASSERT_EQ(MC_CAN_ERR_NONE, mc_can_proto_pack(MC_CAN_MSG_CURRENTS, 1u, big, 4u, &f));
  ASSERT_EQ(MC_CAN_ERR_NONE, mc_can_proto_unpack(&f, &m, v, 4u));
  EXPECT_NEAR(s.max, v[0], QuantTol(s, s.max));
  EXPECT_NEAR(s.min, v[1], QuantTol(s, s.min));
  ASSERT_EQ(MC_CAN_ERR_NONE, mc_can_proto_pack(MC_CAN_MSG_CURRENTS, 1u, odd, 4u, &f));
  ASSERT_EQ(MC_CAN_ERR_NONE, mc_can_proto_unpack(&f, &m, v, 4u));
  EXPECT_EQ(0.0f, v[0]);
  EXPECT_NEAR(s.max, v[1], QuantTol(s, s.max));
}

TEST(CanProto, PackRejectsMisuseAndLeavesFrame) {
  const float v[MC_CAN_NSIG_MAX] = {0};
  mc_hal_can_frame_t f{};
  f.id = 0x123;
  EXPECT_EQ(MC_CAN_ERR_ARG, mc_can_proto_pack(MC_CAN_MSG_COUNT, 1u, v, MC_CAN_NSIG_MAX, &f));
  EXPECT_EQ(MC_CAN_ERR_ARG, mc_can_proto_pack(MC_CAN_MSG_HEARTBEAT, 63u, v, MC_CAN_NSIG_MAX, &f));
  EXPECT_EQ(MC_CAN_ERR_ARG, mc_can_proto_pack(MC_CAN_MSG_HEARTBEAT, 1u, v, 3u, &f));
  EXPECT_EQ(MC_CAN_ERR_ARG, mc_can_proto_pack(MC_CAN_MSG_HEARTBEAT, 1u, nullptr, 9u, &f));
  EXPECT_EQ(MC_CAN_ERR_ARG, mc_can_proto_pack(MC_CAN_MSG_HEARTBEAT, 1u, v, 9u, nullptr));
  EXPECT_EQ(0x123u, f.id);
}

TEST(CanProto, UnpackRejectsFormatLengthIdAndRange) {
  float v[MC_CAN_NSIG_MAX];
  uint32_t m = 77;
  auto un = [&](const mc_hal_can_frame_t& f) {
    return mc_can_proto_unpack(&f, &m, v, MC_CAN_NSIG_MAX);
  };
  EXPECT_EQ(MC_CAN_ERR_FORMAT, un(Frame(0x031, {1}, MC_HAL_CAN_FLAG_RTR)));
  EXPECT_EQ(MC_CAN_ERR_FORMAT, un(Frame(0x031, {1}, MC_HAL_CAN_FLAG_FD)));
  EXPECT_EQ(MC_CAN_ERR_FORMAT, un(Frame(0x031, {1}, MC_HAL_CAN_FLAG_EXT)));
  EXPECT_EQ(MC_CAN_ERR_UNKNOWN_CMD, un(Frame(0x02D, {1})));
  EXPECT_EQ(MC_CAN_ERR_LENGTH, un(Frame(0x032, {0, 0, 0xE8})));
  EXPECT_EQ(MC_CAN_ERR_LENGTH, un(Frame(0x031, {})));
  EXPECT_EQ(MC_CAN_ERR_RANGE, un(Frame(0x031, {0})));  // control_mode 1..3
  EXPECT_EQ(MC_CAN_ERR_RANGE, un(Frame(0x031, {4})));
  EXPECT_EQ(MC_CAN_ERR_RANGE, un(Frame(0x030, {2})));              // enable 0..1
  EXPECT_EQ(MC_CAN_ERR_RANGE, un(Frame(0x036, {13, 10, 0})));      // tm_cmd 1..12
  EXPECT_EQ(MC_CAN_ERR_RANGE, un(Frame(0x036, {1, 0xE9, 0x03})));  // 1001 Hz
  // 10000.001 rad/s: one raw step above the DBC maximum
  EXPECT_EQ(MC_CAN_ERR_RANGE, un(Frame(0x033, {0x81, 0x96, 0x98, 0x00})));
  EXPECT_EQ(MC_CAN_ERR_NONE, un(Frame(0x033, {0x80, 0x96, 0x98, 0x00})));
  // raw 10000000 * 0.001f: float rounding of the scale, and float's spacing
  // at 1e4 (0.98e-3)
  EXPECT_NEAR(10000.0f, v[0], 2e-3f);
  EXPECT_EQ(MC_CAN_MSG_SET_SPEED_REF, m);
  EXPECT_EQ(MC_CAN_ERR_NONE, un(Frame(0x035, {})));  // CLEAR_FAULTS: no data
}

TEST(CanProto, WorstCaseFrameBits) {
  EXPECT_EQ(135u, mc_can_frame_bits_worst(8u));
  EXPECT_EQ(55u, mc_can_frame_bits_worst(0u));
}

// --------------------------------------------------------- telemetry
mc_telemetry_cfg_t TmCfg() {
  mc_telemetry_cfg_t c{};
  c.node_id = 1;
  c.bitrate_bps = 1000000;
  c.bus_budget_frac = 0.5f;
  c.tick_hz = 1000;
  const uint16_t r[MC_TM_COUNT] = {10, 200, 100, 100, 50, 0, 0, 0};
  std::memcpy(c.rate_hz, r, sizeof r);
  return c;
}

TEST(Telemetry, BusLoadFormula) {
  mc_telemetry_cfg_t c = TmCfg();
  // 460 frames/s of 8 bytes, 135 bits each, plus the CMD_ERROR replies at
  // their limit (50/s, 135 bits), on 1 Mbit/s; float sum exact to a few ulp.
  EXPECT_NEAR(510.0 * 135.0 / 1e6, mc_telemetry_bus_load(&c), 1e-7);
  c.bitrate_bps = 125000;
  EXPECT_NEAR(510.0 * 135.0 / 125e3, mc_telemetry_bus_load(&c), 1e-6);
  EXPECT_EQ(0.0f, mc_telemetry_bus_load(nullptr));
}

TEST(Telemetry, InitValidatesEachFieldAndLeavesStateOnError) {
  mc_telemetry_t t;
  std::memset(&t, 0xA5, sizeof t);
  mc_telemetry_t before = t;
  auto bad = [&](void (*edit)(mc_telemetry_cfg_t*), uint32_t want) {
    mc_telemetry_cfg_t c = TmCfg();
    edit(&c);
    EXPECT_EQ(want, mc_telemetry_init(&t, &c));
    EXPECT_EQ(0, std::memcmp(&before, &t, sizeof t));
  };
  bad([](mc_telemetry_cfg_t* c) { c->node_id = 63; }, MC_TM_CFG_ERR_NODE);
  bad([](mc_telemetry_cfg_t* c) { c->bitrate_bps = 9999; }, MC_TM_CFG_ERR_BITRATE);
  bad([](mc_telemetry_cfg_t* c) { c->bitrate_bps = 1000001; }, MC_TM_CFG_ERR_BITRATE);
  bad([](mc_telemetry_cfg_t* c) { c->tick_hz = 0; }, MC_TM_CFG_ERR_TICK);
  bad([](mc_telemetry_cfg_t* c) { c->bus_budget_frac = 0.0f; }, MC_TM_CFG_ERR_BUDGET);
  bad([](mc_telemetry_cfg_t* c) { c->bus_budget_frac = 0.71f; }, MC_TM_CFG_ERR_BUDGET);
  bad([](mc_telemetry_cfg_t* c) { c->bus_budget_frac = NAN; }, MC_TM_CFG_ERR_BUDGET);
  bad([](mc_telemetry_cfg_t* c) { c->rate_hz[1] = 1001; }, MC_TM_CFG_ERR_RATE);
  bad([](mc_telemetry_cfg_t* c) { c->rate_hz[MC_TM_HEARTBEAT] = 0; }, MC_TM_CFG_ERR_HEARTBEAT);
  // 125 kbit/s: (460 + 50 replies) frames/s x 135 bits = 55.1 % > 40 %
  bad(
      [](mc_telemetry_cfg_t* c) {
        c->bitrate_bps = 125000;
        c->bus_budget_frac = 0.4f;
      },
      MC_TM_CFG_ERR_LOAD);
  EXPECT_EQ(MC_TM_CFG_ERR_NULL, mc_telemetry_init(nullptr, nullptr));
  mc_telemetry_cfg_t ok = TmCfg();
  ok.bitrate_bps = 125000;
  ok.bus_budget_frac = 0.6f;  // 55.1 % fits
  EXPECT_EQ(MC_TM_CFG_OK, mc_telemetry_init(&t, &ok));
}

class TelemetryOnDrive : public AppDrive {
 protected:
  void SetUp() override {
    AppDrive::SetUp();
    InitDrive();
    GoodSample();
    (void)mc_drive_fast_step(&d);
  }
  // Run n ticks, popping every frame; counts frames per command id.
  void Run(mc_telemetry_t* t, int n, const mc_telemetry_src_t* src, uint32_t counts[32],
           std::vector<mc_hal_can_frame_t>* out = nullptr) {
    for (int k = 0; k < n; ++k) {
      (void)mc_telemetry_step(t, &fake.can_dev, src);
      mc_hal_can_frame_t f;
      while (mc_hal_fake_can_tx_pop(&fake, &f) == 0) {
        counts[mc_can_id_cmd(f.id)]++;
        if (out) out->push_back(f);
      }
    }
  }
};

TEST_F(TelemetryOnDrive, RatesAreExactPerSecond) {
  mc_telemetry_cfg_t c = TmCfg();
  c.rate_hz[MC_TM_POSITION] = 3;  // does not divide the tick rate
  c.rate_hz[MC_TM_SPEED] = 1000;  // every tick
  mc_telemetry_t t;
  ASSERT_EQ(MC_TM_CFG_OK, mc_telemetry_init(&t, &c));
  const mc_telemetry_src_t src{&d, nullptr, nullptr, nullptr};
  uint32_t counts[32] = {0};
  Run(&t, 1000, &src, counts);
  // a phase accumulator is exact over whole seconds: no tolerance
  EXPECT_EQ(10u, counts[MC_CAN_CMD_HEARTBEAT]);
  EXPECT_EQ(200u, counts[MC_CAN_CMD_CURRENTS]);
  EXPECT_EQ(100u, counts[MC_CAN_CMD_VOLTAGES]);
  EXPECT_EQ(1000u, counts[MC_CAN_CMD_SPEED]);
  EXPECT_EQ(3u, counts[MC_CAN_CMD_POSITION]);
  EXPECT_EQ(0u, counts[MC_CAN_CMD_OBSERVER]);
  EXPECT_EQ(1313u, t.tx_frames);
}

TEST_F(TelemetryOnDrive, SequenceCountsEveryFrameEvenWhenTheHalRefuses) {
  mc_telemetry_cfg_t c = TmCfg();
  for (auto& r : c.rate_hz) r = 0;
  c.rate_hz[MC_TM_HEARTBEAT] = 1;  // its minimum; first frame after 1 s
  c.rate_hz[MC_TM_CURRENTS] = 1000;
  mc_telemetry_t t;
  ASSERT_EQ(MC_TM_CFG_OK, mc_telemetry_init(&t, &c));
  const mc_telemetry_src_t src{&d, nullptr, nullptr, nullptr};
  uint32_t counts[32] = {0};
  std::vector<mc_hal_can_frame_t> fr;
  Run(&t, 300, &src, counts, &fr);
  ASSERT_EQ(300u, fr.size());
  for (size_t k = 0; k < fr.size(); ++k) EXPECT_EQ(k % 256u, fr[k].data[7]) << k;
  // the HAL refuses two frames: the counter skips them (a gap the logger sees)
  ASSERT_EQ(0, mc_hal_fake_inject_error(&fake, MC_HAL_FAKE_CAN_SEND, -ENOBUFS, 2));
  fr.clear();
  Run(&t, 3, &src, counts, &fr);
  ASSERT_EQ(1u, fr.size());
  EXPECT_EQ((300u + 2u) % 256u, fr[0].data[7]);
  EXPECT_EQ(2u, t.tx_nobufs);
  EXPECT_EQ(2u, t.tx_dropped);
  EXPECT_EQ(0u, t.last_fail_mask);
}

TEST_F(TelemetryOnDrive, ControlLawMessagesOnlyWithData) {
  mc_telemetry_cfg_t c = TmCfg();
  for (auto& r : c.rate_hz) r = 0;
  c.rate_hz[MC_TM_HEARTBEAT] = 1;  // its minimum; first frame after 1 s
  c.rate_hz[MC_TM_OBSERVER] = 100;
  c.rate_hz[MC_TM_STEPPER] = 100;
  mc_telemetry_t t;
  ASSERT_EQ(MC_TM_CFG_OK, mc_telemetry_init(&t, &c));
  uint32_t counts[32] = {0};
  const mc_telemetry_src_t none{&d, nullptr, nullptr, nullptr};
  Run(&t, 100, &none, counts);
  EXPECT_EQ(0u, counts[MC_CAN_CMD_OBSERVER] + counts[MC_CAN_CMD_STEPPER]);
  mc_telemetry_ext_t x{};
  x.have_observer = true;
  x.tau_l_hat_nm = 0.25f;
  x.omega_hat_rad_s = -12.5f;
  x.theta_hat_rad = 3.0f;
  const mc_telemetry_src_t with{&d, nullptr, &x, nullptr};
  std::vector<mc_hal_can_frame_t> fr;
  Run(&t, 100, &with, counts, &fr);
  EXPECT_EQ(10u, counts[MC_CAN_CMD_OBSERVER]);
  EXPECT_EQ(0u, counts[MC_CAN_CMD_STEPPER]);  // have_stepper false
  float v[MC_CAN_NSIG_MAX];
  uint32_t m;
  ASSERT_EQ(MC_CAN_ERR_NONE, mc_can_proto_unpack(&fr.front(), &m, v, MC_CAN_NSIG_MAX));
  EXPECT_NEAR(0.25f, v[0], 0.0005f);  // half of 0.001 N m
  EXPECT_NEAR(-12.5f, v[1], 0.005f);  // half of 0.01 rad/s
  EXPECT_NEAR(3.0f, v[2], 0.0001f);   // half of 0.0002 rad
  EXPECT_EQ(0.0f, v[MC_CAN_OBSERVER_SAT]);
  EXPECT_EQ(0.0f, v[MC_CAN_OBSERVER_SEQ]);  // its first frame: sequence 0
  ASSERT_EQ(MC_CAN_ERR_NONE, mc_can_proto_unpack(&fr.back(), &m, v, MC_CAN_NSIG_MAX));
  EXPECT_EQ(9.0f, v[MC_CAN_OBSERVER_SEQ]);  // the tenth
}

TEST_F(TelemetryOnDrive, CurrentsAreTheParkTransformOfThePhaseCurrents) {
  d.tm.ia_a = 2.0f;
  d.tm.ib_a = -1.0f;
  d.tm.theta_e_rad = 0.7f;
  const mc_telemetry_src_t src{&d, nullptr, nullptr, nullptr};
  float v[MC_CAN_NSIG_MAX];
  ASSERT_TRUE(mc_telemetry_values(MC_TM_CURRENTS, &src, v));
  const double al = 2.0, be = (2.0 + 2.0 * -1.0) / std::sqrt(3.0);
  const double id = al * std::cos(0.7) + be * std::sin(0.7);
  const double iq = -al * std::sin(0.7) + be * std::cos(0.7);
  // own float sin/cos: a few 1e-7 relative
  EXPECT_NEAR(id, v[MC_CAN_CURRENTS_I_D_A], 1e-5);
  EXPECT_NEAR(iq, v[MC_CAN_CURRENTS_I_Q_A], 1e-5);
}

// BUS_CURRENT (BO_ 44) carries the drive's bus estimate and the limits in
// force (mc_drive_bus.h) as they are, within half a step of 0.01 A.
TEST_F(TelemetryOnDrive, BusCurrentCarriesTheEstimateAndTheLimits) {
  // -3.25 A pushed back: 3/2 (vd id + vq iq) / vbus = 1.5 (-1.3 * 40) / 24
  d.tm.foc.vd_v = 0.0f;
  d.tm.foc.id_a = 0.0f;
  d.tm.foc.vq_v = -1.3f;
  d.tm.foc.iq_a = 40.0f;
  d.tm.vbus_v = 24.0f;
  d.bus.i_mot_lim_a = 12.5f;
  d.bus.i_regen_lim_a = 4.0f;
  const mc_telemetry_src_t src{&d, nullptr, nullptr, nullptr};
  float v[MC_CAN_NSIG_MAX];
  ASSERT_TRUE(mc_telemetry_values(MC_TM_BUS_CURRENT, &src, v));
  mc_hal_can_frame_t f;
  ASSERT_EQ(MC_CAN_ERR_NONE, mc_can_proto_pack(MC_CAN_MSG_BUS_CURRENT, 1u, v, MC_CAN_NSIG_MAX, &f));
  EXPECT_EQ((1u << 5) | 12u, f.id);  // node 1, BO_ 44
  uint32_t m = 0;
  float u[MC_CAN_NSIG_MAX];
  ASSERT_EQ(MC_CAN_ERR_NONE, mc_can_proto_unpack(&f, &m, u, MC_CAN_NSIG_MAX));
  EXPECT_EQ(MC_CAN_MSG_BUS_CURRENT, m);
  EXPECT_NEAR(-3.25f, u[MC_CAN_BUS_CURRENT_I_BUS_EST_A], 0.005f);
  EXPECT_NEAR(12.5f, u[MC_CAN_BUS_CURRENT_I_BUS_MAX_A], 0.005f);
  EXPECT_NEAR(4.0f, u[MC_CAN_BUS_CURRENT_I_BUS_REGEN_MAX_A], 0.005f);
  EXPECT_EQ(0.0f, u[MC_CAN_BUS_CURRENT_SAT]);
  EXPECT_EQ(static_cast<uint32_t>(MC_TM_BUS_CURRENT),
            mc_telemetry_slot_of_cmd(MC_CAN_CMD_BUS_CURRENT));
  EXPECT_EQ(static_cast<uint32_t>(MC_TM_COUNT), mc_telemetry_slot_of_cmd(0x0Du));  // not telemetry
}

TEST_F(TelemetryOnDrive, SetRateRefusesAboveBudget) {
  mc_telemetry_cfg_t c = TmCfg();
  c.bitrate_bps = 125000;
  c.bus_budget_frac = 0.6f;
  mc_telemetry_t t;
  ASSERT_EQ(MC_TM_CFG_OK, mc_telemetry_init(&t, &c));
  // +300 Hz of 135-bit frames at 125 kbit/s: 55.1 % + 32.4 % > 60 %
  EXPECT_EQ(MC_TM_CFG_ERR_LOAD, mc_telemetry_set_rate(&t, MC_TM_SPEED, 400));
  EXPECT_EQ(100u, t.cfg.rate_hz[MC_TM_SPEED]);
  EXPECT_EQ(MC_TM_CFG_ERR_RATE, mc_telemetry_set_rate(&t, MC_TM_COUNT, 1));
  // the drive's own heartbeat cannot be switched off
  EXPECT_EQ(MC_TM_CFG_ERR_HEARTBEAT, mc_telemetry_set_rate(&t, MC_TM_HEARTBEAT, 0));
  EXPECT_EQ(10u, t.cfg.rate_hz[MC_TM_HEARTBEAT]);
  EXPECT_EQ(MC_TM_CFG_OK, mc_telemetry_set_rate(&t, MC_TM_SPEED, 0));
  EXPECT_NEAR((360.0 + 50.0) * 135.0 / 125e3, t.load_frac, 1e-6);
}

// --------------------------------------------------- command handler
int g_speed_calls = 0;
float g_speed_ref = 0.0f;
int SpeedHook(void*, float w) {
  ++g_speed_calls;
  g_speed_ref = w;
  return 0;
}

class CanCmd : public TelemetryOnDrive {
 protected:
  void SetUp() override {
    TelemetryOnDrive::SetUp();
    ASSERT_EQ(MC_TM_CFG_OK, mc_telemetry_init(&tm, &(tcfg = TmCfg())));
    cc.node_id = 1;
    cc.tick_hz = 1000;
    cc.timeout_s = 0.1f;
    cc.stop_ramp_a_per_s = 100.0f;
    cc.stop_decel_rad_s2 = 1000.0f;
    cc.speed_max_rad_s = 200.0f;
    cc.speed_drive_mode = MC_DRIVE_MODE_CURRENT;
    cc.position_drive_mode = MC_DRIVE_MODE_IDLE;
    g_speed_calls = 0;
    g_speed_ref = 0.0f;
  }
  void Init() { ASSERT_EQ(MC_CAN_CMD_CFG_OK, mc_can_cmd_init(&c, &cc, &d, &tm)); }
  mc_can_err_t Send(const mc_hal_can_frame_t& f) {
    return mc_can_cmd_handle(&c, &f, &fake.can_dev);
  }
  // Pop the one CMD_ERROR reply and check its fields.
  void ExpectReply(uint32_t cmd, mc_can_err_t e, uint32_t len) {
    mc_hal_can_frame_t f;
    ASSERT_EQ(0, mc_hal_fake_can_tx_pop(&fake, &f));
    float v[MC_CAN_NSIG_MAX];
    uint32_t m;
    ASSERT_EQ(MC_CAN_ERR_NONE, mc_can_proto_unpack(&f, &m, v, MC_CAN_NSIG_MAX));
    ASSERT_EQ(MC_CAN_MSG_CMD_ERROR, m);
    EXPECT_EQ(0x03Fu, f.id);
    EXPECT_EQ(static_cast<float>(cmd), v[MC_CAN_CMD_ERROR_REJECTED_CMD]);
    EXPECT_EQ(static_cast<float>(e), v[MC_CAN_CMD_ERROR_ERROR]);
    EXPECT_EQ(static_cast<float>(len), v[MC_CAN_CMD_ERROR_RX_LEN]);
    EXPECT_NE(0, mc_hal_fake_can_tx_pop(&fake, &f)) << "one reply only";
    EXPECT_EQ(static_cast<uint8_t>(e), c.last_error);
    EXPECT_EQ(cmd, c.last_error_cmd);
  }
  // f disables the drive at once: bridge open, stop reason DISABLE_CMD.
  void ExpectDisables(const mc_hal_can_frame_t& f) {
    ASSERT_EQ(MC_CAN_ERR_NONE, Send(f));
    EXPECT_EQ(MC_DRIVE_MODE_IDLE, d.mode);
    EXPECT_FALSE(c.enabled);
    EXPECT_EQ(MC_CAN_STOP_DISABLE_CMD, c.stop_reason);
  }
  void EnableCurrent() {
    ASSERT_EQ(MC_CAN_ERR_NONE, Send(Frame(0x031, {1})));
    ASSERT_EQ(MC_CAN_ERR_NONE, Send(Frame(0x030, {1})));
    ASSERT_EQ(MC_DRIVE_MODE_CURRENT, d.mode);
  }
  mc_telemetry_cfg_t tcfg{};
  mc_telemetry_t tm{};
  mc_can_cmd_cfg_t cc{};
  mc_can_cmd_t c{};
};

TEST_F(CanCmd, InitValidatesAndLeavesStateOnError) {
  mc_can_cmd_t z;
  std::memset(&z, 0x5A, sizeof z);
  const mc_can_cmd_t before = z;
  auto bad = [&](void (*edit)(mc_can_cmd_cfg_t*), uint32_t want) {
    mc_can_cmd_cfg_t x = cc;
    edit(&x);
    EXPECT_EQ(want, mc_can_cmd_init(&z, &x, &d, &tm));
    EXPECT_EQ(0, std::memcmp(&before, &z, sizeof z));
  };
  bad([](mc_can_cmd_cfg_t* x) { x->node_id = 63; }, MC_CAN_CMD_CFG_ERR_NODE);
  bad([](mc_can_cmd_cfg_t* x) { x->tick_hz = 0; }, MC_CAN_CMD_CFG_ERR_TICK);
  bad([](mc_can_cmd_cfg_t* x) { x->timeout_s = 0.0005f; }, MC_CAN_CMD_CFG_ERR_TIMEOUT);  // < 1 tick
  bad([](mc_can_cmd_cfg_t* x) { x->timeout_s = NAN; }, MC_CAN_CMD_CFG_ERR_TIMEOUT);
  bad([](mc_can_cmd_cfg_t* x) { x->timeout_s = 61.0f; }, MC_CAN_CMD_CFG_ERR_TIMEOUT);
  bad([](mc_can_cmd_cfg_t* x) { x->stop_ramp_a_per_s = -1.0f; }, MC_CAN_CMD_CFG_ERR_RAMP);
  bad([](mc_can_cmd_cfg_t* x) { x->stop_decel_rad_s2 = INFINITY; }, MC_CAN_CMD_CFG_ERR_RAMP);
  bad([](mc_can_cmd_cfg_t* x) { x->speed_max_rad_s = 0.0f; }, MC_CAN_CMD_CFG_ERR_SPEED);
  bad(
      [](mc_can_cmd_cfg_t* x) {
        x->set_speed_ref = SpeedHook;
        x->speed_drive_mode = MC_DRIVE_MODE_IDLE;
      },
      MC_CAN_CMD_CFG_ERR_MODE);
  EXPECT_EQ(MC_CAN_CMD_CFG_ERR_NULL, mc_can_cmd_init(&z, &cc, nullptr, &tm));
  Init();
  EXPECT_EQ(100u, c.timeout_ticks);
}

TEST_F(CanCmd, EnableAndSetCurrentReference) {
  Init();
  EnableCurrent();
  EXPECT_TRUE(c.enabled);
  // i_d = -0.5 A, i_q = 1.25 A (24-bit mA each)
  ASSERT_EQ(MC_CAN_ERR_NONE, Send(Frame(0x032, {0x0C, 0xFE, 0xFF, 0xE2, 0x04, 0x00})));
  EXPECT_FLOAT_EQ(-0.5f, d.id_ref_a);
  EXPECT_FLOAT_EQ(1.25f, d.iq_ref_a);
  mc_hal_can_frame_t f;
  EXPECT_NE(0, mc_hal_fake_can_tx_pop(&fake, &f)) << "no reply to an accepted command";
  ExpectDisables(Frame(0x030, {0}));
}

// Every rejected command: error reply, and neither the handler's state
// (apart from the error record) nor the drive changed.
TEST_F(CanCmd, RejectedCommandsReplyAndChangeNothing) {
  Init();
  EnableCurrent();
  ASSERT_EQ(MC_CAN_ERR_NONE, Send(Frame(0x032, {0, 0, 0, 0xE8, 0x03, 0})));  // i_q 1 A
  struct Case {
    mc_hal_can_frame_t f;
    mc_can_err_t e;
  } cases[] = {
      {Frame(0x032, {0, 0, 0xE8}), MC_CAN_ERR_LENGTH},
      {Frame(0x032, {0, 0, 0, 0xA8, 0x61, 0}), MC_CAN_ERR_RANGE},  // 25 A > the drive's i_max 20 A
      {Frame(0x031, {2}), MC_CAN_ERR_MODE},                        // mode change while enabled
      {Frame(0x033, {0, 0, 0, 0}), MC_CAN_ERR_MODE},               // speed ref in CURRENT mode
      {Frame(0x035, {}), MC_CAN_ERR_MODE},                         // clear faults while enabled
      {Frame(0x022, {0, 0, 0, 0, 0, 0, 0, 0}), MC_CAN_ERR_UNKNOWN_CMD},  // a telemetry id
      {Frame(0x02D, {}), MC_CAN_ERR_UNKNOWN_CMD},
      {Frame(0x032, {0, 0, 0, 0xE8, 0x03, 0}, MC_HAL_CAN_FLAG_RTR), MC_CAN_ERR_FORMAT},
      {Frame(0x036, {2, 0xE8, 0x03}), MC_CAN_ERR_BUDGET},   // CURRENTS at 1000 Hz (see below)
      {Frame(0x036, {13, 1, 0}), MC_CAN_ERR_RANGE},         // 13: no telemetry message
      {Frame(0x036, {1, 0, 0}), MC_CAN_ERR_HEARTBEAT_MIN},  // HEARTBEAT off
      {Frame(0x037, {7}), MC_CAN_ERR_STALE},                // the counter of the last one
  };
  ASSERT_EQ(MC_CAN_ERR_NONE, Send(Frame(0x037, {7})));
  // a 125 kbit/s bus: the present rates load it 55.1 %; CURRENTS at
  // 1000 Hz would add 800 x 135 / 125e3 = 86 % > the 50 % budget
  tm.cfg.bitrate_bps = 125000;
  for (const auto& k : cases) {
    c.reply.tokens = MC_TM_REPLY_BURST;  // the rate limit is tested apart
    mc_drive_t d0 = d;
    mc_can_cmd_t c0 = c;
    mc_telemetry_t tm0 = tm;
    EXPECT_EQ(k.e, Send(k.f)) << "id 0x" << std::hex << k.f.id;
    ExpectReply(mc_can_id_cmd(k.f.id), k.e, k.f.len);
    EXPECT_EQ(0, std::memcmp(&d0, &d, sizeof d)) << "drive changed";
    EXPECT_EQ(0, std::memcmp(&tm0, &tm, sizeof tm)) << "telemetry changed";
    mc_can_cmd_t c1 = c;
    c1.last_error = c0.last_error;
    c1.last_error_cmd = c0.last_error_cmd;
    c1.err_seq = c0.err_seq;
    c1.rx_rejected = c0.rx_rejected;
    c1.reply = c0.reply;
    EXPECT_EQ(0, std::memcmp(&c0, &c1, sizeof c)) << "handler changed";
    EXPECT_EQ(c0.rx_rejected + 1u, c.rx_rejected);
  }
  EXPECT_EQ(12u, c.err_seq);
}

TEST_F(CanCmd, OtherNodesAndExtendedFramesAreIgnoredSilently) {
  Init();
  EXPECT_EQ(MC_CAN_ERR_IGNORED, Send(Frame(0x051, {1})));  // node 2
  EXPECT_EQ(MC_CAN_ERR_IGNORED, Send(Frame(0x031, {1}, MC_HAL_CAN_FLAG_EXT)));
  mc_hal_can_frame_t f;
  EXPECT_NE(0, mc_hal_fake_can_tx_pop(&fake, &f));
  EXPECT_EQ(MC_CAN_CTRL_NONE, c.control_mode);
}

TEST_F(CanCmd, SpeedAndPositionNeedTheirHooks) {
  Init();
  EXPECT_EQ(MC_CAN_ERR_UNSUPPORTED, Send(Frame(0x031, {2})));
  ExpectReply(0x11, MC_CAN_ERR_UNSUPPORTED, 1);
  EXPECT_EQ(MC_CAN_ERR_UNSUPPORTED, Send(Frame(0x031, {3})));
  ExpectReply(0x11, MC_CAN_ERR_UNSUPPORTED, 1);
  EXPECT_EQ(MC_CAN_ERR_MODE, Send(Frame(0x030, {1})));  // no control mode selected
  ExpectReply(0x10, MC_CAN_ERR_MODE, 1);
}

TEST_F(CanCmd, TimeoutRampsTheCurrentToZeroThenIdles) {
  Init();
  EnableCurrent();
  ASSERT_EQ(MC_CAN_ERR_NONE, Send(Frame(0x032, {0, 0, 0, 0xD0, 0x07, 0})));  // i_q 2 A
  // a heartbeat (counter advancing) every 99 ticks keeps it running
  uint8_t n = 0;
  for (int k = 0; k < 500; ++k) {
    if (k % 99 == 0) {
      ASSERT_EQ(MC_CAN_ERR_NONE, Send(Frame(0x037, {n++})));
    }
    mc_can_cmd_step(&c);
  }
  ASSERT_TRUE(c.enabled);
  ASSERT_FALSE(c.stopping);
  // silence: the stop starts at the 100th tick after the last command
  ASSERT_EQ(MC_CAN_ERR_NONE, Send(Frame(0x037, {n++})));
  for (int k = 0; k < 99; ++k) mc_can_cmd_step(&c);
  EXPECT_FALSE(c.stopping);
  EXPECT_FLOAT_EQ(2.0f, d.iq_ref_a);
  mc_can_cmd_step(&c);
  EXPECT_TRUE(c.stopping);
  // 100 A/s at 1 kHz: 0.1 A per tick (float steps: 1e-5 A)
  EXPECT_NEAR(1.9f, d.iq_ref_a, 1e-5f);
  EXPECT_EQ(MC_CAN_ERR_MODE, Send(Frame(0x032, {0, 0, 0, 0xD0, 0x07, 0})));
  ExpectReply(0x12, MC_CAN_ERR_MODE, 6);
  int ticks = 1;
  while (c.enabled && ticks < 100) {
    mc_can_cmd_step(&c);
    ++ticks;
  }
  EXPECT_EQ(20, ticks);  // 2 A / 0.1 A per tick
  EXPECT_EQ(MC_DRIVE_MODE_IDLE, d.mode);
  EXPECT_EQ(0.0f, d.iq_ref_a);
  EXPECT_EQ(MC_CAN_STOP_CMD_TIMEOUT, c.stop_reason);
  // the heartbeat telemetry reports it
  const mc_telemetry_src_t src{&d, &c, nullptr, nullptr};
  float v[MC_CAN_NSIG_MAX];
  ASSERT_TRUE(mc_telemetry_values(MC_TM_HEARTBEAT, &src, v));
  EXPECT_EQ(static_cast<float>(MC_CAN_STOP_CMD_TIMEOUT), v[MC_CAN_HEARTBEAT_STOP_REASON]);
  EXPECT_EQ(0.0f, v[MC_CAN_HEARTBEAT_ENABLED]);
  EXPECT_EQ(0.0f, v[MC_CAN_HEARTBEAT_MODE]);
}

TEST_F(CanCmd, SpeedModeRampsTheSpeedReferenceOnTimeout) {
  cc.set_speed_ref = SpeedHook;
  Init();
  ASSERT_EQ(MC_CAN_ERR_NONE, Send(Frame(0x031, {2})));
  ASSERT_EQ(MC_CAN_ERR_NONE, Send(Frame(0x030, {1})));
  // 50 rad/s = raw 50000
  ASSERT_EQ(MC_CAN_ERR_NONE, Send(Frame(0x033, {0x50, 0xC3, 0x00, 0x00})));
  EXPECT_FLOAT_EQ(50.0f, g_speed_ref);
  EXPECT_EQ(MC_CAN_ERR_NONE, Send(Frame(0x033, {0x40, 0x0D, 0x03, 0x00})));  // 200 rad/s: the limit
  EXPECT_EQ(MC_CAN_ERR_RANGE, Send(Frame(0x033, {0x41, 0x0D, 0x03, 0x00})));  // 200.001 rad/s
  ASSERT_EQ(MC_CAN_ERR_NONE, Send(Frame(0x033, {0x50, 0xC3, 0x00, 0x00})));
  ExpectReply(0x13, MC_CAN_ERR_RANGE, 4);
  for (int k = 0; k < 100; ++k) mc_can_cmd_step(&c);
  EXPECT_TRUE(c.stopping);
  // 1000 rad/s^2 at 1 kHz: 1 rad/s per tick, 50 ticks to zero
  EXPECT_NEAR(49.0f, g_speed_ref, 1e-4f);  // float steps
  int ticks = 1;
  while (c.enabled && ticks < 1000) {
    mc_can_cmd_step(&c);
    ++ticks;
  }
  // 50 steps of 1 rad/s; 1000 * (1/1000) in float may leave a sliver for one more
  EXPECT_GE(ticks, 50);
  EXPECT_LE(ticks, 51);
  EXPECT_EQ(0.0f, g_speed_ref);
  EXPECT_EQ(MC_CAN_STOP_CMD_TIMEOUT, c.stop_reason);
}

TEST_F(CanCmd, DriveFaultEndsTheRun) {
  Init();
  EnableCurrent();
  ASSERT_EQ(0, mc_hal_fake_adc_set_sample(&fake, 0.0f, 0.0f, 0.0f, 100.0f, apptest::kMask3));
  (void)mc_drive_fast_step(&d);  // over-voltage
  ASSERT_EQ(MC_DRIVE_MODE_FAULT, d.mode);
  mc_can_cmd_step(&c);
  EXPECT_FALSE(c.enabled);
  EXPECT_EQ(MC_CAN_STOP_FAULT, c.stop_reason);
  EXPECT_EQ(MC_CAN_ERR_REFUSED, Send(Frame(0x035, {})));  // bus still too high
  ExpectReply(0x15, MC_CAN_ERR_REFUSED, 0);
  GoodSample();
  (void)mc_drive_fast_step(&d);
  EXPECT_EQ(MC_CAN_ERR_NONE, Send(Frame(0x035, {})));
  EXPECT_EQ(MC_DRIVE_MODE_IDLE, d.mode);
}

TEST_F(CanCmd, TelemetryRateCommand) {
  Init();
  ASSERT_EQ(MC_CAN_ERR_NONE, Send(Frame(0x036, {4, 0x2C, 0x01})));  // SPEED 300 Hz
  EXPECT_EQ(300u, tm.cfg.rate_hz[MC_TM_SPEED]);
  // BUS_CURRENT by its command id 12 (slots past POSITION_REF are not id - 1)
  ASSERT_EQ(MC_CAN_ERR_NONE, Send(Frame(0x036, {12, 20, 0})));
  EXPECT_EQ(20u, tm.cfg.rate_hz[MC_TM_BUS_CURRENT]);
  // THERMAL by its command id 11 (slot 11, after BUS_CURRENT)
  ASSERT_EQ(MC_CAN_ERR_NONE, Send(Frame(0x036, {11, 10, 0})));
  EXPECT_EQ(10u, tm.cfg.rate_hz[MC_TM_THERMAL]);
  // 13 names no telemetry message: refused, nothing changes
  const mc_telemetry_cfg_t before = tm.cfg;
  EXPECT_NE(MC_CAN_ERR_NONE, Send(Frame(0x036, {13, 20, 0})));
  EXPECT_EQ(0, std::memcmp(&before, &tm.cfg, sizeof before));
  mc_can_cmd_t z{};
  ASSERT_EQ(MC_CAN_CMD_CFG_OK, mc_can_cmd_init(&z, &cc, &d, nullptr));
  const mc_hal_can_frame_t f = Frame(0x036, {4, 1, 0});
  EXPECT_EQ(MC_CAN_ERR_UNSUPPORTED, mc_can_cmd_handle(&z, &f, nullptr));
}

TEST_F(CanCmd, PollHandlesQueuedFramesAndBoundsTheWork) {
  Init();
  for (uint8_t i = 0; i < 5; ++i) {
    const mc_hal_can_frame_t hb = Frame(0x037, {i});
    ASSERT_EQ(0, mc_hal_fake_can_rx_push(&fake, &hb));
  }
  EXPECT_EQ(3u, mc_can_cmd_poll(&c, &fake.can_dev, 3u));
  EXPECT_EQ(2u, mc_can_cmd_poll(&c, &fake.can_dev, 16u));
  EXPECT_EQ(5u, c.rx_accepted);
}

// ------------------------------------------- telemetry for any motor
// The library's 60 A-class motor: 40 A and 1290 rad/s arrive as such
// (protocol 1 clipped them to 16.382 A and 655.34 rad/s), sat stays 0; a
// value beyond the range is sent saturated with sat = 1.
TEST_F(TelemetryOnDrive, SixtyAmpMotorValuesArriveUnclipped) {
  // i_q = 40 A at theta_e = 0: i_alpha = 0, i_beta = 40 A -> ia = 0, ib = 40 sqrt(3)/2
  d.tm.theta_e_rad = 0.0f;
  d.tm.ia_a = 0.0f;
  d.tm.ib_a = 40.0f * std::sqrt(3.0f) / 2.0f;
  d.tm.iq_ref_a = 40.0f;
  d.tm.omega_m_rad_s = 1290.0f;
  mc_telemetry_cfg_t c = TmCfg();
  for (auto& r : c.rate_hz) r = 0;
  c.rate_hz[MC_TM_HEARTBEAT] = 1;
  c.rate_hz[MC_TM_CURRENTS] = 1000;
  c.rate_hz[MC_TM_SPEED] = 1000;
  c.rate_hz[MC_TM_CURRENT_REFS] = 1000;
  mc_telemetry_t t;
  ASSERT_EQ(MC_TM_CFG_OK, mc_telemetry_init(&t, &c));
  const mc_telemetry_src_t src{&d, nullptr, nullptr, &t};
  uint32_t counts[32] = {0};
  std::vector<mc_hal_can_frame_t> fr;
  Run(&t, 1, &src, counts, &fr);
  ASSERT_EQ(3u, fr.size());
  for (const auto& f : fr) {
    float v[MC_CAN_NSIG_MAX];
    uint32_t m;
    ASSERT_EQ(MC_CAN_ERR_NONE, mc_can_proto_unpack(&f, &m, v, MC_CAN_NSIG_MAX));
    if (m == MC_CAN_MSG_CURRENTS) {
      // Park in float (1e-5 relative) plus half of the 1 mA step
      EXPECT_NEAR(40.0f, v[MC_CAN_CURRENTS_I_Q_A], 0.0005f + 4e-4f);
      EXPECT_NEAR(0.0f, v[MC_CAN_CURRENTS_I_D_A], 0.0005f + 4e-4f);
      EXPECT_EQ(0.0f, v[MC_CAN_CURRENTS_SAT]);
    } else if (m == MC_CAN_MSG_SPEED) {
      EXPECT_NEAR(1290.0f, v[MC_CAN_SPEED_OMEGA_M_RAD_S], 0.0005f + 1e-4f);  // half a step + float
      EXPECT_EQ(0.0f, v[MC_CAN_SPEED_SAT]);
    } else {
      ASSERT_EQ(MC_CAN_MSG_CURRENT_REFS, m);
      EXPECT_NEAR(40.0f, v[MC_CAN_CURRENT_REFS_I_Q_REF_A], 0.0005f + 1e-5f);
      EXPECT_EQ(0.0f, v[MC_CAN_CURRENT_REFS_SAT]);
    }
  }
  EXPECT_EQ(0u, t.saturated);
  // beyond the range (and NaN): saturated, and flagged
  d.tm.omega_m_rad_s = 9000.0f;
  d.tm.iq_ref_a = NAN;
  fr.clear();
  Run(&t, 1, &src, counts, &fr);
  ASSERT_EQ(3u, fr.size());
  float v[MC_CAN_NSIG_MAX];
  uint32_t m;
  ASSERT_EQ(MC_CAN_ERR_NONE, mc_can_proto_unpack(&fr[1], &m, v, MC_CAN_NSIG_MAX));
  ASSERT_EQ(MC_CAN_MSG_SPEED, m);
  EXPECT_NEAR(8388.607f, v[MC_CAN_SPEED_OMEGA_M_RAD_S], 1e-3f);  // the range's end, float
  EXPECT_EQ(1.0f, v[MC_CAN_SPEED_SAT]);
  ASSERT_EQ(MC_CAN_ERR_NONE, mc_can_proto_unpack(&fr[2], &m, v, MC_CAN_NSIG_MAX));
  ASSERT_EQ(MC_CAN_MSG_CURRENT_REFS, m);
  EXPECT_EQ(0.0f, v[MC_CAN_CURRENT_REFS_I_Q_REF_A]);  // NaN packs as 0 ...
  EXPECT_EQ(1.0f, v[MC_CAN_CURRENT_REFS_SAT]);        // ... and says so
  EXPECT_EQ(2u, t.saturated);
}

// THERMAL (issue 33): the winding estimate, the current limit in force and
// its factor as the drive holds them (mc_drive_thermal.h), within half a
// step of each signal plus float rounding.
TEST_F(TelemetryOnDrive, ThermalCarriesTheEstimateAndTheDeratedLimit) {
  d.cfg.i_max_a = 40.0f;
  d.thermal.t_w_c = 121.37f;
  d.thermal.k = 0.25f;
  d.thermal.derating = true;
  mc_telemetry_cfg_t c = TmCfg();
  for (auto& r : c.rate_hz) r = 0;
  c.rate_hz[MC_TM_HEARTBEAT] = 1;
  c.rate_hz[MC_TM_THERMAL] = 1000;
  mc_telemetry_t t;
  ASSERT_EQ(MC_TM_CFG_OK, mc_telemetry_init(&t, &c));
  const mc_telemetry_src_t src{&d, nullptr, nullptr, &t};
  uint32_t counts[32] = {0};
  std::vector<mc_hal_can_frame_t> fr;
  Run(&t, 1, &src, counts, &fr);
  ASSERT_EQ(1u, fr.size());
  EXPECT_EQ((1u << 5) | MC_CAN_CMD_THERMAL, fr[0].id);  // node 1, BO_ 43
  float v[MC_CAN_NSIG_MAX];
  uint32_t m;
  ASSERT_EQ(MC_CAN_ERR_NONE, mc_can_proto_unpack(&fr[0], &m, v, MC_CAN_NSIG_MAX));
  ASSERT_EQ(MC_CAN_MSG_THERMAL, m);
  EXPECT_NEAR(121.37f, v[MC_CAN_THERMAL_T_WINDING_EST_C], 0.005f + 1e-4f);
  EXPECT_NEAR(10.0f, v[MC_CAN_THERMAL_I_LIMIT_A], 0.0005f + 1e-5f);
  EXPECT_NEAR(0.25f, v[MC_CAN_THERMAL_DERATE_FACTOR], 0.0005f + 1e-6f);
  EXPECT_EQ(1.0f, v[MC_CAN_THERMAL_DERATING]);
  EXPECT_EQ(0.0f, v[MC_CAN_THERMAL_SAT]);
}

// Multi-turn position at 1290 rad/s (205 turns/s, 1.29 rad per 1 kHz tick)
// and backwards: the unwrapped angle follows w t.
TEST_F(TelemetryOnDrive, PositionIsMultiTurnAtAnySpeed) {
  mc_telemetry_cfg_t c = TmCfg();
  mc_telemetry_t t;
  ASSERT_EQ(MC_TM_CFG_OK, mc_telemetry_init(&t, &c));
  const mc_telemetry_src_t src{&d, nullptr, nullptr, &t};
  const double two_pi = 6.283185307179586;
  for (double w : {1290.0, -1290.0, 4000.0}) {
    mc_telemetry_t tt;
    ASSERT_EQ(MC_TM_CFG_OK, mc_telemetry_init(&tt, &c));
    const mc_telemetry_src_t s{&d, nullptr, nullptr, &tt};
    d.tm.omega_m_rad_s = static_cast<float>(w);
    for (int k = 0; k <= 1000; ++k) {
      const double th = w * k * 1e-3;
      d.tm.theta_m_rad = static_cast<float>(th - two_pi * std::floor(th / two_pi));
      (void)mc_telemetry_step(&tt, &fake.can_dev, &s);
      mc_hal_can_frame_t f;
      while (mc_hal_fake_can_tx_pop(&fake, &f) == 0) {
      }
    }
    float v[MC_CAN_NSIG_MAX];
    ASSERT_TRUE(mc_telemetry_values(MC_TM_POSITION, &s, v));
    // w * 1 s, from 0; float of the in-turn angle and of turns * 2 pi:
    // a few ulp of 4000 rad (5e-4 rad)
    EXPECT_NEAR(w, v[MC_CAN_POSITION_THETA_M_RAD], 2e-3) << w;
    EXPECT_EQ(0.0f, v[MC_CAN_POSITION_SAT]);
  }
  (void)src;
}

// ------------------------------------------------ protocol hardening
TEST_F(CanCmd, DisableHasTheLowestIdOfTheNodeAndOpensTheBridge) {
  Init();
  for (uint32_t m = 0; m < MC_CAN_MSG_COUNT; ++m) {
    if (m != MC_CAN_MSG_DISABLE) {
      EXPECT_LT(mc_can_id(1u, MC_CAN_CMD_DISABLE), mc_can_id(1u, mc_can_messages[m].cmd));
    }
  }
  EnableCurrent();
  ExpectDisables(Frame(0x020, {}));
}

// Protocol 1 kept the drive enabled on one stale heartbeat repeated.
TEST_F(CanCmd, AStaleHostHeartbeatIsNoKeepAlive) {
  Init();
  EnableCurrent();
  ASSERT_EQ(MC_CAN_ERR_NONE, Send(Frame(0x037, {42})));
  int ticks = 0;
  while (c.enabled && !c.stopping && ticks < 1000) {
    if (ticks % 10 == 9) {
      EXPECT_EQ(MC_CAN_ERR_STALE, Send(Frame(0x037, {42})));  // the same frame again
    }
    mc_can_cmd_step(&c);
    ++ticks;
  }
  EXPECT_EQ(100, ticks);  // the timeout (100 ticks) counts from the last fresh one
  // stopping, or already stopped (a rotor at rest: the bridge opens at once)
  EXPECT_TRUE(c.stopping || (!c.enabled && c.stop_reason == MC_CAN_STOP_CMD_TIMEOUT));
  EXPECT_EQ(static_cast<uint8_t>(MC_CAN_ERR_STALE), c.last_error);
}

// Issue 28, finding 1: any accepted frame was a keep-alive. Measured then
// (current mode, host heartbeats stop at 0.3 s, timeout 0.5 s): the same
// SET_CURRENT_REF every 100 ms, a PARAM_REQ READ every 100 ms (even of an
// unknown id), a no-op SET_TM_RATE, or a HOST_HEARTBEAT alternating
// 0,1,0,1 kept the drive enabled to the end of the run. Here, at the
// fixture's 1 kHz step and 0.1 s timeout: heartbeats every 50 ms up to
// tick 300, then one of those frames every 20 ms. Each time the stop
// begins exactly timeout_ticks after the last fresh heartbeat (integers:
// exact).
TEST_F(CanCmd, OnlyAnAdvancingHostHeartbeatKeepsTheDriveAlive) {
  struct Case {
    const char* what;
    mc_hal_can_frame_t f;
  } cases[] = {
      {"the same SET_CURRENT_REF", Frame(0x032, {0, 0, 0, 0xE8, 0x03, 0})},
      {"PARAM_REQ READ of an unknown id", Frame(0x038, {0, 0x13, 0, 0, 0, 0, 0, 0})},
      {"a no-op SET_TM_RATE", Frame(0x036, {4, 50, 0})},
      {"SET_ENABLE 1 again", Frame(0x030, {1})},
      {"a repeated HOST_HEARTBEAT", Frame(0x037, {5})},
  };
  for (const auto& k : cases) {
    SetUp();
    Init();
    EnableCurrent();
    int last_fresh = -1, stop_at = -1;
    uint8_t n = 0;
    for (int t = 0; t < 1000 && stop_at < 0; ++t) {
      if (t <= 300 && t % 50 == 0) {
        ASSERT_EQ(MC_CAN_ERR_NONE, Send(Frame(0x037, {n++}))) << k.what;
        last_fresh = t;
      } else if (t > 300 && t % 20 == 0) {
        (void)Send(k.f);
      }
      mc_can_cmd_step(&c);
      if (c.stopping || !c.enabled) stop_at = t;
    }
    EXPECT_EQ(last_fresh + static_cast<int>(c.timeout_ticks) - 1, stop_at) << k.what;
    EXPECT_TRUE(c.stopping || c.stop_reason == MC_CAN_STOP_CMD_TIMEOUT) << k.what;
  }
}

// The alternating 0,1,0,1 of the issue, from the start of a run: 0 sets the
// reference, 1 advances, then every frame is a step of 255 or 0: STALE.
TEST_F(CanCmd, AnAlternatingHeartbeatIsNoKeepAlive) {
  Init();
  EnableCurrent();
  int stop_at = -1, last_ok = -1;
  for (int t = 0; t < 1000 && stop_at < 0; ++t) {
    if (t % 10 == 0) {
      const mc_can_err_t e = Send(Frame(0x037, {static_cast<uint8_t>((t / 10) % 2)}));
      if (e == MC_CAN_ERR_NONE) {
        last_ok = t;
      } else {
        EXPECT_EQ(MC_CAN_ERR_STALE, e);
      }
    }
    mc_can_cmd_step(&c);
    if (c.stopping || !c.enabled) stop_at = t;
  }
  EXPECT_EQ(10, last_ok) << "0 then 1 accepted, nothing after";
  EXPECT_EQ(10 + 99, stop_at);
}

// The counter advances modulo 256 by 1..MC_CAN_HB_STEP_MAX: across the
// wrap, with up to 7 frames lost; a larger jump, a step back and a repeat
// are STALE and change nothing (the reference stays).
TEST_F(CanCmd, HeartbeatCounterAdvancesModuloWrapByABoundedStep) {
  Init();
  EnableCurrent();
  const struct {
    uint8_t n;
    mc_can_err_t e;
  } seq[] = {
      {250, MC_CAN_ERR_NONE},   // the run's first: the reference
      {251, MC_CAN_ERR_NONE},   // +1
      {255, MC_CAN_ERR_NONE},   // +4
      {3, MC_CAN_ERR_NONE},     // +4 across the wrap
      {11, MC_CAN_ERR_NONE},    // +8: the largest step
      {20, MC_CAN_ERR_STALE},   // +9
      {10, MC_CAN_ERR_STALE},   // -1
      {11, MC_CAN_ERR_STALE},   // a repeat
      {139, MC_CAN_ERR_STALE},  // +128
      {12, MC_CAN_ERR_NONE},    // +1 from 11: the reference did not move
  };
  for (const auto& k : seq) {
    c.reply.tokens = MC_TM_REPLY_BURST;  // the replies are tested apart
    c.ticks_since_alive = 7u;
    EXPECT_EQ(k.e, Send(Frame(0x037, {k.n}))) << int(k.n);
    EXPECT_EQ(k.e == MC_CAN_ERR_NONE ? 0u : 7u, c.ticks_since_alive) << int(k.n);
    mc_hal_can_frame_t f;
    while (mc_hal_fake_can_tx_pop(&fake, &f) == 0) {
    }
  }
  EXPECT_EQ(12u, c.hb_last);
}

// A new run (enable) takes its first HOST_HEARTBEAT as the reference: a
// host that restarts its counter (a new mdtool process) is not STALE, and
// the timeout counts from the enable itself.
TEST_F(CanCmd, EnableStartsTheTimeoutAndANewReference) {
  Init();
  ASSERT_EQ(MC_CAN_ERR_NONE, Send(Frame(0x037, {200})));
  for (int t = 0; t < 500; ++t) mc_can_cmd_step(&c);  // disabled: no timeout
  EXPECT_FALSE(c.stopping);
  EnableCurrent();
  EXPECT_EQ(0u, c.ticks_since_alive);
  EXPECT_EQ(MC_CAN_ERR_NONE, Send(Frame(0x037, {0})));  // 200 -> 0 would be STALE in a run
  for (int t = 0; t < 99; ++t) mc_can_cmd_step(&c);
  EXPECT_TRUE(c.enabled && !c.stopping);
  ASSERT_EQ(MC_CAN_ERR_NONE, Send(Frame(0x037, {1})));
  for (int t = 0; t < 99; ++t) mc_can_cmd_step(&c);
  EXPECT_TRUE(c.enabled && !c.stopping);
  mc_can_cmd_step(&c);
  EXPECT_TRUE(c.stopping || !c.enabled) << "100 ticks after the last heartbeat";
}

TEST_F(CanCmd, ErrorRepliesAreRateLimitedAndCounted) {
  Init();
  // 16 bad frames per 1 kHz tick for 1 s (the poll's bound): protocol 1
  // answered every one (16000/s); now the reply limiter's burst of 10,
  // then 40 per second.
  uint32_t replies = 0;
  for (int k = 0; k < 1000; ++k) {
    for (int i = 0; i < 16; ++i) {
      (void)Send(Frame(0x02D, {}));
      mc_hal_can_frame_t f;  // the bus takes each (the fake's queue holds 8)
      while (mc_hal_fake_can_tx_pop(&fake, &f) == 0) ++replies;
    }
    mc_can_cmd_step(&c);
  }
  // token bucket: burst + rate x 1 s, the last refill may fall after the end
  EXPECT_GE(replies, MC_TM_REPLY_BURST + MC_TM_REPLY_MAX_HZ - 1u);
  EXPECT_LE(replies, MC_TM_REPLY_BURST + MC_TM_REPLY_MAX_HZ);
  EXPECT_EQ(16000u, c.rx_rejected);
  EXPECT_EQ(16000u - replies, c.reply_limited);
  EXPECT_EQ(static_cast<uint8_t>(MC_CAN_ERR_UNKNOWN_CMD), c.last_error);  // still reported
}

// A CAN HAL whose receive queue is a deque (the fake's holds 8 frames).
struct QueueCan {
  std::deque<mc_hal_can_frame_t> q;
  static int Send(void*, const mc_hal_can_frame_t*) { return 0; }
  static int Recv(void* ctx, mc_hal_can_frame_t* f) {
    auto* self = static_cast<QueueCan*>(ctx);
    if (self->q.empty()) return -EAGAIN;
    *f = self->q.front();
    self->q.pop_front();
    return 0;
  }
  mc_hal_can_ops_t ops{Send, Recv, nullptr};
  mc_hal_can_t dev{&ops, this};
};

// 100 % bus load from another node: at 1 Mbit/s the shortest frames (47
// bits) come 21277 per second, 22 per 1 ms tick; the node's keep-alive
// (every 50 ms) is still handled within its tick and the drive never times
// out; the receive queue does not grow. Without the filter the foreign
// frames used the poll's 16 frames per tick and the queue grew without end.
TEST_F(CanCmd, AForeignFloodCostsNoKeepAlive) {
  Init();
  EnableCurrent();
  QueueCan bus;
  uint8_t n = 0;
  size_t q_max = 0;
  for (int k = 0; k < 2000; ++k) {
    for (int i = 0; i < 22; ++i) bus.q.push_back(Frame(0x041, {}));  // node 2, 0 bytes
    if (k % 50 == 0) bus.q.push_back(Frame(0x037, {n++}));
    q_max = std::max(q_max, bus.q.size());
    (void)mc_can_cmd_poll(&c, &bus.dev, 16u);
    mc_can_cmd_step(&c);
    ASSERT_TRUE(c.enabled && !c.stopping) << "tick " << k;
    ASSERT_LT(c.ticks_since_alive, 51u) << "keep-alive handled late, tick " << k;
  }
  EXPECT_EQ(0u, bus.q.size());
  EXPECT_LE(q_max, 23u);  // one tick's frames
  EXPECT_EQ(2000u * 22u, c.rx_foreign);
  EXPECT_EQ(0u, c.rx_rejected);
}

// A reference set while disabled is refused: enable starts from the
// present state (protocol 1 applied it as a step on enable).
TEST_F(CanCmd, ReferencesWhileDisabledAreRefusedAndEnableStartsFromThePresent) {
  Init();
  ASSERT_EQ(MC_CAN_ERR_NONE, Send(Frame(0x031, {1})));
  EXPECT_EQ(MC_CAN_ERR_MODE, Send(Frame(0x032, {0, 0, 0, 0x40, 0x1F, 0})));  // i_q 8 A
  ExpectReply(0x12, MC_CAN_ERR_MODE, 6);
  ASSERT_EQ(0, mc_drive_set_current_ref(&d, 0.0f, 8.0f));  // left by an earlier run
  ASSERT_EQ(MC_CAN_ERR_NONE, Send(Frame(0x030, {1})));
  EXPECT_EQ(0.0f, d.iq_ref_a);
  EXPECT_EQ(0.0f, d.id_ref_a);
}

TEST_F(CanCmd, SpeedEnableStartsAtTheMeasuredSpeed) {
  cc.set_speed_ref = SpeedHook;
  Init();
  ASSERT_EQ(MC_CAN_ERR_NONE, Send(Frame(0x031, {2})));
  EXPECT_EQ(MC_CAN_ERR_MODE, Send(Frame(0x033, {0x50, 0xC3, 0x00, 0x00})));
  ExpectReply(0x13, MC_CAN_ERR_MODE, 4);
  EXPECT_EQ(0, g_speed_calls);
  d.tm.omega_m_rad_s = 30.0f;  // still coasting
  ASSERT_EQ(MC_CAN_ERR_NONE, Send(Frame(0x030, {1})));
  EXPECT_EQ(1, g_speed_calls);
  EXPECT_EQ(30.0f, g_speed_ref);
  EXPECT_EQ(30.0f, c.omega_ref_rad_s);
}

int g_pos_calls = 0;
float g_pos_ref = 0.0f;
int PosHook(void*, float th) {
  ++g_pos_calls;
  g_pos_ref = th;
  return 0;
}

// Position mode with a multi-turn target: 1000.5 rad (159 turns) and
// -3.25 rad arrive as such (in the telemetry's frame; the hook gets them
// relative to the angle at enable); beyond +-200000 rad is refused RANGE.
TEST_F(CanCmd, PositionTargetIsMultiTurnAndRangeChecked) {
  cc.set_position_ref = PosHook;
  cc.position_drive_mode = MC_DRIVE_MODE_CURRENT;
  g_pos_calls = 0;
  Init();
  ASSERT_EQ(MC_CAN_ERR_NONE, Send(Frame(0x031, {3})));
  EXPECT_EQ(MC_CAN_ERR_MODE, Send(Frame(0x034, {0x08, 0xAA, 0x98, 0x00})));  // while disabled
  ExpectReply(0x14, MC_CAN_ERR_MODE, 4);
  ASSERT_EQ(MC_CAN_ERR_NONE, Send(Frame(0x030, {1})));
  EXPECT_EQ(1, g_pos_calls);  // enable: hold the position at enable (relative 0)
  EXPECT_EQ(0.0f, g_pos_ref);
  const float th0 = d.tm.theta_m_rad;  // no telemetry step yet: the single-turn angle
  EXPECT_EQ(th0, c.theta_enable_rad);
  EXPECT_EQ(th0, c.theta_ref_rad);
  ASSERT_EQ(MC_CAN_ERR_NONE, Send(Frame(0x034, {0x08, 0xAA, 0x98, 0x00})));  // cantools: 1000.5
  EXPECT_NEAR(1000.5f - th0, g_pos_ref, 2e-4f);  // raw 10005000 * 0.0001f: float rounding
  ASSERT_EQ(MC_CAN_ERR_NONE, Send(Frame(0x034, {0x0C, 0x81, 0xFF, 0xFF})));  // -3.25
  EXPECT_NEAR(-3.25f - th0, g_pos_ref, 1e-6f);
  EXPECT_NEAR(-3.25f, c.theta_ref_rad, 1e-6f);
  // raw 2000010000 = 200001 rad (the check is in float: 200000.0001 would
  // round to the limit itself)
  EXPECT_EQ(MC_CAN_ERR_RANGE, Send(Frame(0x034, {0x10, 0xBB, 0x35, 0x77})));
  ExpectReply(0x14, MC_CAN_ERR_RANGE, 4);
  EXPECT_NEAR(-3.25f - th0, g_pos_ref, 1e-6f);
}

}  // namespace
