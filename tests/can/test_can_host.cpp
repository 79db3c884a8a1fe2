// Host CAN HAL (hal/host): candump log writer / command-script reader and
// the SocketCAN error-frame handling (testable without a kernel CAN stack;
// the SocketCAN data path itself is exercised by can.vcan_e2e).
#include <gtest/gtest.h>

#include <cerrno>
#include <fstream>
#include <linux/can.h>
#include <linux/can/error.h>
#include <sstream>
#include <cstring>
#include <system_error>

#include "can_test_frame.hpp"
#include "hal_host/candump_log.hpp"
#include "hal_host/socketcan.hpp"
extern "C" {
#include "mc_app.h"
#include "mc_hal_fake.h"
}

namespace {

std::string Slurp(const std::string& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

TEST(Candump, FormatMatchesCandumpL) {
  EXPECT_EQ("(0000000001.250000) can0 021#0A00FF",
            hal_host::candump_format(1.25, "can0", Fr(0x21, {0x0A, 0, 0xFF})));
  EXPECT_EQ("(0000000000.000001) vcan0 12345678#",
            hal_host::candump_format(1e-6, "vcan0", Fr(0x12345678, {}, MC_HAL_CAN_FLAG_EXT)));
  mc_hal_can_frame_t r = Fr(0x7FF, {});
  r.flags = MC_HAL_CAN_FLAG_RTR;
  r.len = 4;
  EXPECT_EQ("(0000000002.000000) can0 7FF#R4", hal_host::candump_format(2.0, "can0", r));
  EXPECT_EQ("(0000000000.500000) can0 123##1AABB",
            hal_host::candump_format(
                0.5, "can0", Fr(0x123, {0xAA, 0xBB}, MC_HAL_CAN_FLAG_FD | MC_HAL_CAN_FLAG_BRS)));
}

TEST(Candump, ParseInvertsFormatAndRejectsGarbage) {
  const mc_hal_can_frame_t in[] = {Fr(0x21, {1, 2, 3, 4, 5, 6, 7, 8}),
                                   Fr(0x1ABCDEF0, {9}, MC_HAL_CAN_FLAG_EXT), Fr(0x35, {}),
                                   Fr(0x123, {1, 2, 3}, MC_HAL_CAN_FLAG_FD)};
  for (const auto& f : in) {
    double t = 0;
    mc_hal_can_frame_t g{};
    ASSERT_TRUE(hal_host::candump_parse(hal_host::candump_format(3.5, "can0", f), &t, &g));
    EXPECT_EQ(3.5, t);
    EXPECT_EQ(f.id, g.id);
    EXPECT_EQ(f.flags, g.flags);
    ASSERT_EQ(f.len, g.len);
    EXPECT_EQ(0, std::memcmp(f.data, g.data, f.len));
  }
  double t;
  mc_hal_can_frame_t g;
  EXPECT_FALSE(hal_host::candump_parse("", &t, &g));
  EXPECT_FALSE(hal_host::candump_parse("(1.0) can0 21#00", &t, &g));  // 2-digit id
  EXPECT_FALSE(hal_host::candump_parse("(1.0) can0 021#0", &t, &g));  // odd digits
  EXPECT_FALSE(hal_host::candump_parse("(x) can0 021#00", &t, &g));
  EXPECT_FALSE(
      hal_host::candump_parse("(1.0) can0 20000004#0000000000000000", &t, &g));  // error frame
}

TEST(CandumpLogCan, WritesFramesAtTheCallersClockAndReplaysAScript) {
  const std::string dir = ::testing::TempDir();
  const std::string out = dir + "/mc_can_out.log", script = dir + "/mc_can_script.log";
  {
    std::ofstream s(script);
    s << "# comment\n(0000000000.100000) can0 031#01\n\n(0000000000.200000) can0 030#01\n";
  }
  double now = 0.0;
  {
    hal_host::CandumpLogCan c(
        out, "can0", [&now] { return now; }, script, [] { return 42u; });
    mc_hal_can_frame_t f;
    EXPECT_EQ(-EAGAIN, mc_hal_can_receive(c.hal(), &f));
    now = 0.15;
    ASSERT_EQ(0, mc_hal_can_receive(c.hal(), &f));
    EXPECT_EQ(0x31u, f.id);
    EXPECT_EQ(42u, f.timestamp_ticks);
    EXPECT_EQ(-EAGAIN, mc_hal_can_receive(c.hal(), &f));
    now = 0.25;
    ASSERT_EQ(0, mc_hal_can_receive(c.hal(), &f));
    EXPECT_EQ(0x30u, f.id);
    EXPECT_EQ(-EAGAIN, mc_hal_can_receive(c.hal(), &f));
    const mc_hal_can_frame_t a = Fr(0x22, {1, 2});
    ASSERT_EQ(0, mc_hal_can_send(c.hal(), &a));
    mc_hal_can_frame_t bad = Fr(0x800, {});  // 12-bit id without EXT
    EXPECT_EQ(-EINVAL, mc_hal_can_send(c.hal(), &bad));
    EXPECT_EQ(1u, c.stats().tx_frames);
    EXPECT_EQ(1u, c.stats().tx_rejected);
    EXPECT_EQ(2u, c.stats().rx_frames);
    EXPECT_TRUE(c.flush());
  }
  EXPECT_EQ("(0000000000.250000) can0 022#0102\n", Slurp(out));
}

TEST(CandumpLogCan, BadScriptNamesTheLine) {
  const std::string script = ::testing::TempDir() + "/mc_can_bad.log";
  {
    std::ofstream s(script);
    s << "(0.1) can0 031#01\nnot a frame\n";
  }
  try {
    hal_host::CandumpLogCan c(
        "", "can0", [] { return 0.0; }, script);
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string::npos, std::string(e.what()).find(":2:")) << e.what();
  }
}

TEST(SocketCan, ErrorFramesDriveTheBusState) {
  mc_hal_can_status_t st{};
  hal_host::SocketCanStats s;
  uint8_t d[8] = {0};
  d[1] = CAN_ERR_CRTL_TX_WARNING;
  hal_host::socketcan_apply_error(CAN_ERR_FLAG | CAN_ERR_CRTL, d, &st, &s);
  EXPECT_EQ(MC_HAL_CAN_STATE_ERROR_WARNING, st.state);
  d[1] = CAN_ERR_CRTL_RX_PASSIVE | CAN_ERR_CRTL_RX_OVERFLOW;
  hal_host::socketcan_apply_error(CAN_ERR_FLAG | CAN_ERR_CRTL, d, &st, &s);
  EXPECT_EQ(MC_HAL_CAN_STATE_ERROR_PASSIVE, st.state);
  EXPECT_EQ(1u, st.rx_overrun_count);
  hal_host::socketcan_apply_error(CAN_ERR_FLAG | CAN_ERR_BUSOFF, d, &st, &s);
  hal_host::socketcan_apply_error(CAN_ERR_FLAG | CAN_ERR_BUSOFF, d, &st, &s);
  EXPECT_EQ(MC_HAL_CAN_STATE_BUS_OFF, st.state);
  EXPECT_EQ(1u, s.bus_off_events);  // one event, two frames
  hal_host::socketcan_apply_error(CAN_ERR_FLAG | CAN_ERR_RESTARTED, d, &st, &s);
  EXPECT_EQ(MC_HAL_CAN_STATE_ERROR_ACTIVE, st.state);
  EXPECT_EQ(5u, s.rx_error_frames);
#ifdef CAN_ERR_CNT
  d[6] = 130;
  d[7] = 7;
  hal_host::socketcan_apply_error(CAN_ERR_FLAG | CAN_ERR_CNT, d, &st, &s);
  EXPECT_EQ(130u, st.tx_err_count);
  EXPECT_EQ(7u, st.rx_err_count);
#endif
}

// The application on the host HAL's bus-state path: the controller state
// comes from SocketCAN error frames (socketcan_apply_error, what SocketCan
// does with each error frame it reads); frames go through the fake board.
struct ErrorFrameCan {
  mc_hal_can_status_t st{};
  hal_host::SocketCanStats stats;
  const mc_hal_can_t* inner = nullptr;
  mc_hal_can_t dev{};
  static int send(void* c, const mc_hal_can_frame_t* f) {
    return mc_hal_can_send(static_cast<ErrorFrameCan*>(c)->inner, f);
  }
  static int receive(void* c, mc_hal_can_frame_t* f) {
    return mc_hal_can_receive(static_cast<ErrorFrameCan*>(c)->inner, f);
  }
  static int status(void* c, mc_hal_can_status_t* s) {
    *s = static_cast<ErrorFrameCan*>(c)->st;
    return 0;
  }
  void error_frame(uint32_t id, uint8_t ctrl) {
    uint8_t d[8] = {0};
    d[1] = ctrl;
    hal_host::socketcan_apply_error(CAN_ERR_FLAG | id, d, &st, &stats);
  }
};

TEST(SocketCan, AppStopsTheDriveOnBusOffFromErrorFrames) {
  static const mc_hal_can_ops_t ops{ErrorFrameCan::send, ErrorFrameCan::receive,
                                    ErrorFrameCan::status};
  mc_hal_fake_config_t fc{};
  ASSERT_EQ(0, mc_hal_fake_config_default(&fc));
  static mc_hal_fake_t fake{};
  ASSERT_EQ(0, mc_hal_fake_init(&fake, &fc));
  fake.adc_temp = mc_hal_adc_temp_t{25.0f, 25.0f, MC_HAL_ADC_TEMP_VALID_ALL, 0u};
  ErrorFrameCan can;
  can.inner = fake.board.can;
  can.dev = mc_hal_can_t{&ops, &can};
  const mc_params_t defaults = mc_params_default;
  mc_app_cfg_t cfg{};
  cfg.defaults = &defaults;
  cfg.tm_budget_frac = 0.5f;
  static mc_app_t app{};
  static mc_drive_t drive{};
  ASSERT_EQ(MC_APP_CFG_OK, mc_app_boot(&app, &cfg));
  ASSERT_EQ(MC_APP_CFG_OK, mc_app_start(&app, &drive, &fake.board, &can.dev, true));
  ASSERT_EQ(0, mc_hal_fake_encoder_set(&fake, 0u, MC_HAL_ENCODER_FLAG_VALID));
  auto period = [&]() {
    ASSERT_EQ(0, mc_hal_fake_adc_set_sample(
                     &fake, 0.0f, 0.0f, 0.0f, defaults.vbus_v,
                     MC_HAL_ADC_VALID_IA | MC_HAL_ADC_VALID_IB | MC_HAL_ADC_VALID_VBUS));
    if (mc_app_fast_step(&app)) {
      mc_app_can_rx_isr(&app);
      mc_app_slow_step(&app);
    }
  };
  auto slow_steps = [&](uint32_t n) {
    for (uint32_t i = 0; i < n * defaults.slow_loop_div; ++i) period();
  };
  auto send = [&](uint32_t cmd, uint8_t b) {
    mc_hal_can_frame_t f{};
    f.id = defaults.can_node_id << 5 | cmd;
    f.len = 1;
    f.data[0] = b;
    ASSERT_EQ(0, mc_hal_fake_can_rx_push(&fake, &f));
  };
  send(0x11u, 1);  // SET_CONTROL_MODE CURRENT
  send(0x10u, 1);  // SET_ENABLE 1
  slow_steps(2);
  ASSERT_EQ(MC_DRIVE_MODE_CURRENT, drive.mode);
  can.error_frame(CAN_ERR_CRTL, CAN_ERR_CRTL_TX_WARNING);
  slow_steps(1);
  EXPECT_EQ(1u, mc_app_can_state(&app));
  EXPECT_EQ(MC_DRIVE_MODE_CURRENT, drive.mode) << "a warning level alone keeps running";
  can.error_frame(CAN_ERR_BUSOFF, 0u);
  slow_steps(1);
  EXPECT_EQ(3u, mc_app_can_state(&app));
  EXPECT_EQ(MC_APP_FAULT_CAN_BUS_OFF, app.faults);
  EXPECT_NE(MC_DRIVE_MODE_CURRENT, drive.mode) << "controlled stop";
  slow_steps(400);
  EXPECT_EQ(MC_DRIVE_MODE_IDLE, drive.mode);
  EXPECT_FALSE(app.cmd.enabled);
  // the kernel restarts the controller: error-active, then CLEAR_FAULTS works
  can.error_frame(CAN_ERR_RESTARTED, 0u);
  slow_steps(1);
  EXPECT_EQ(0u, mc_app_can_state(&app));
  mc_hal_can_frame_t f{};
  f.id = defaults.can_node_id << 5 | 0x15u;  // CLEAR_FAULTS, no data
  ASSERT_EQ(0, mc_hal_fake_can_rx_push(&fake, &f));
  slow_steps(1);
  EXPECT_EQ(0u, drive.warnings);
  EXPECT_EQ(MC_APP_FAULT_NONE, app.faults);
}

TEST(SocketCan, MissingInterfaceOrStackIsAnErrorNamingIt) {
  try {
    hal_host::SocketCan s("mcnosuch0");
    FAIL() << "opened a nonexistent interface";
  } catch (const std::system_error& e) {
    // EAFNOSUPPORT on a kernel without CAN, ENODEV where CAN exists
    EXPECT_TRUE(e.code().value() == EAFNOSUPPORT || e.code().value() == ENODEV) << e.what();
    EXPECT_NE(std::string::npos, std::string(e.what()).find("mcnosuch0"));
  }
}

}  // namespace
