// The application's side of the firmware update: BOOT_REQ INFO, VERSION
// and the confirmed ENTER (firmware/app/can/mc_boot_enter.h) alone, then
// inside the drive application (mc_app on the fake HAL board) through the
// command handler: the board's enter hook runs only after ENTER and its
// confirmation, one slow step after the OK went out, with the bridge off,
// and never while the drive runs. Exact comparisons (codes, counts).
#include <gtest/gtest.h>

#include <vector>

#include "boot_test_util.hpp"

extern "C" {
#include "mc_app.h"
#include "mc_boot_enter.h"
#include "mc_hal_fake.h"
}

using namespace boot_test;

namespace
{

constexpr uint32_t kNode = 1u;
const mc_boot_enter_cfg_t kImage = {MC_BOOT_BOARD_VESC6, MC_BOOT_LAYOUT_ID, 0x000301u};

struct Enter : public ::testing::Test {
    mc_boot_enter_t e{};
    bool busy = false;

    void SetUp() override
    {
        mc_boot_enter_init(&e, &kImage, kNode, 1000u, 1234u);
    }
    std::optional<Reply> Req(uint32_t op, uint32_t arg = 0u, uint32_t value = 0u)
    {
        mc_hal_can_frame_t r{};
        const mc_hal_can_frame_t f = ReqFrame(kNode, op, arg, value);
        for (int i = 0; i < 10; ++i) {
            mc_boot_enter_step(&e); // 10 ms between requests
        }
        if (mc_boot_enter_handle(&e, &f, busy, &r) != 1u) {
            return std::nullopt;
        }
        EXPECT_EQ(mc_can_id(kNode, MC_CAN_CMD_BOOT_REPLY), r.id);
        const Reply d = Decode(r);
        EXPECT_EQ(op, d.op);
        EXPECT_EQ(uint32_t{MC_CAN_VAL_BOOT_STATE_APP}, d.state);
        return d;
    }
};

TEST_F(Enter, InfoAndVersion)
{
    auto r = Req(MC_CAN_VAL_BOOT_OP_INFO);
    EXPECT_EQ(uint32_t{MC_CAN_VAL_BOOT_STATUS_OK}, r->status);
    EXPECT_EQ(MC_BOOT_BOARD_VESC6 | (MC_BOOT_LAYOUT_ID << 8) | (MC_BOOT_PROTO_VERSION << 16),
              r->value);
    r = Req(MC_CAN_VAL_BOOT_OP_VERSION);
    EXPECT_EQ(0x000301u, r->value);
    EXPECT_FALSE(mc_boot_enter_due(&e));
}

TEST_F(Enter, OnlyTheConfirmedEnterCounts)
{
    // a wrong key, a confirmation with no ENTER before it
    EXPECT_EQ(uint32_t{MC_CAN_VAL_BOOT_STATUS_KEY}, Req(MC_CAN_VAL_BOOT_OP_ENTER, 0u, 1u)->status);
    EXPECT_EQ(uint32_t{MC_CAN_VAL_BOOT_STATUS_KEY},
              Req(MC_CAN_VAL_BOOT_OP_ENTER_CONFIRM, 0u, 0u)->status);
    // ENTER: CONFIRM with a token; a wrong token spends it
    auto r = Req(MC_CAN_VAL_BOOT_OP_ENTER, 0u, MC_BOOT_ENTER_KEY);
    ASSERT_EQ(uint32_t{MC_CAN_VAL_BOOT_STATUS_CONFIRM}, r->status);
    const uint32_t token = r->value;
    EXPECT_NE(0u, token);
    EXPECT_EQ(uint32_t{MC_CAN_VAL_BOOT_STATUS_KEY},
              Req(MC_CAN_VAL_BOOT_OP_ENTER_CONFIRM, 0u, token ^ 1u)->status);
    EXPECT_EQ(uint32_t{MC_CAN_VAL_BOOT_STATUS_KEY},
              Req(MC_CAN_VAL_BOOT_OP_ENTER_CONFIRM, 0u, token)->status);
    // a token expires after MC_BOOT_CONFIRM_MS (1 s: 101 requests of 10 ms)
    r = Req(MC_CAN_VAL_BOOT_OP_ENTER, 0u, MC_BOOT_ENTER_KEY);
    for (int i = 0; i < 100; ++i) {
        ASSERT_TRUE(Req(MC_CAN_VAL_BOOT_OP_INFO));
    }
    EXPECT_EQ(uint32_t{MC_CAN_VAL_BOOT_STATUS_KEY},
              Req(MC_CAN_VAL_BOOT_OP_ENTER_CONFIRM, 0u, r->value)->status);
    // busy: neither ENTER nor its confirmation
    busy = true;
    EXPECT_EQ(uint32_t{MC_CAN_VAL_BOOT_STATUS_BUSY},
              Req(MC_CAN_VAL_BOOT_OP_ENTER, 0u, MC_BOOT_ENTER_KEY)->status);
    busy = false;
    r = Req(MC_CAN_VAL_BOOT_OP_ENTER, 0u, MC_BOOT_ENTER_KEY);
    busy = true;
    EXPECT_EQ(uint32_t{MC_CAN_VAL_BOOT_STATUS_BUSY},
              Req(MC_CAN_VAL_BOOT_OP_ENTER_CONFIRM, 0u, r->value)->status);
    busy = false;
    EXPECT_FALSE(mc_boot_enter_due(&e));
    // and the good path: two different tokens in a row, the second confirmed
    const uint32_t t1 = Req(MC_CAN_VAL_BOOT_OP_ENTER, 0u, MC_BOOT_ENTER_KEY)->value;
    const uint32_t t2 = Req(MC_CAN_VAL_BOOT_OP_ENTER, 0u, MC_BOOT_ENTER_KEY)->value;
    EXPECT_NE(t1, t2);
    EXPECT_EQ(uint32_t{MC_CAN_VAL_BOOT_STATUS_OK},
              Req(MC_CAN_VAL_BOOT_OP_ENTER_CONFIRM, 0u, t2)->status);
    EXPECT_TRUE(mc_boot_enter_due(&e));
}

TEST_F(Enter, TheBootloadersRequestsAndMalformedOnesAreRefusedByName)
{
    for (uint32_t op :
         {MC_CAN_VAL_BOOT_OP_BEGIN, MC_CAN_VAL_BOOT_OP_WRITE, MC_CAN_VAL_BOOT_OP_VERIFY,
          MC_CAN_VAL_BOOT_OP_COMMIT, MC_CAN_VAL_BOOT_OP_ABORT, MC_CAN_VAL_BOOT_OP_RUN}) {
        EXPECT_EQ(uint32_t{MC_CAN_VAL_BOOT_STATUS_STATE}, Req(op, 1u, 1u)->status) << op;
    }
    EXPECT_EQ(uint32_t{MC_CAN_VAL_BOOT_STATUS_OPCODE}, Req(0x40u)->status);
    EXPECT_EQ(uint32_t{MC_CAN_VAL_BOOT_STATUS_FORMAT},
              Req(MC_CAN_VAL_BOOT_OP_INFO, 0u, 5u)->status);
    EXPECT_EQ(uint32_t{MC_CAN_VAL_BOOT_STATUS_FORMAT},
              Req(MC_CAN_VAL_BOOT_OP_ENTER, 3u, MC_BOOT_ENTER_KEY)->status);
    mc_hal_can_frame_t f = ReqFrame(kNode, MC_CAN_VAL_BOOT_OP_INFO, 0u, 0u), r{};
    f.len = 4u;
    ASSERT_EQ(1u, mc_boot_enter_handle(&e, &f, false, &r));
    EXPECT_EQ(uint32_t{MC_CAN_VAL_BOOT_STATUS_FORMAT}, Decode(r).status);
}

TEST_F(Enter, RepliesWithinTheBudget)
{
    // 100 requests with no time passing: the burst only; the rest counted
    mc_hal_can_frame_t r{};
    const mc_hal_can_frame_t f = ReqFrame(kNode, MC_CAN_VAL_BOOT_OP_INFO, 0u, 0u);
    uint32_t sent = 0u;
    for (int i = 0; i < 100; ++i) {
        sent += mc_boot_enter_handle(&e, &f, false, &r);
    }
    EXPECT_EQ(MC_BOOT_REPLY_BURST, sent);
    EXPECT_EQ(100u - MC_BOOT_REPLY_BURST, e.replies_limited);
    // one second later: the burst again (250/s refills more than 8)
    for (int i = 0; i < 1000; ++i) {
        mc_boot_enter_step(&e);
    }
    sent = 0u;
    for (int i = 0; i < 100; ++i) {
        sent += mc_boot_enter_handle(&e, &f, false, &r);
    }
    EXPECT_EQ(MC_BOOT_REPLY_BURST, sent);
}

// ------------------------------------------------ inside the application

class AppBoot : public ::testing::Test
{
  protected:
    void SetUp() override
    {
        mc_hal_fake_config_t fc{};
        ASSERT_EQ(0, mc_hal_fake_config_default(&fc));
        ASSERT_EQ(0, mc_hal_fake_init(&fake, &fc));
        fake.adc_temp.power_stage_temp_c = 25.0f;
        fake.adc_temp.motor_temp_c = 25.0f;
        fake.adc_temp.valid_mask = MC_HAL_ADC_TEMP_VALID_ALL;
        defaults = mc_params_default;
        cfg.defaults = &defaults;
        cfg.tm_budget_frac = 0.5f;
        cfg.boot = &kImage;
        cfg.enter_boot = [](void *ctx) { static_cast<AppBoot *>(ctx)->entered++; };
        cfg.boot_ctx = this;
        ASSERT_EQ(MC_APP_CFG_OK, mc_app_boot(&app, &cfg));
        ASSERT_EQ(MC_APP_CFG_OK, mc_app_start(&app, &drive, &fake.board, fake.board.can, true));
        ASSERT_EQ(0, mc_hal_fake_encoder_set(&fake, 0u, MC_HAL_ENCODER_FLAG_VALID));
    }
    void Slow(uint32_t n = 1u)
    {
        for (uint32_t i = 0; i < n * defaults.slow_loop_div; ++i) {
            ASSERT_EQ(0, mc_hal_fake_adc_set_sample(&fake, 0.0f, 0.0f, 0.0f, defaults.vbus_v,
                                                    MC_HAL_ADC_VALID_IA | MC_HAL_ADC_VALID_IB |
                                                        MC_HAL_ADC_VALID_VBUS));
            if (mc_app_fast_step(&app)) {
                mc_app_can_rx_isr(&app);
                mc_app_slow_step(&app);
            }
        }
    }
    // Send one frame, run a slow step, return the BOOT_REPLY (or CMD_ERROR).
    std::optional<mc_hal_can_frame_t> Send(const mc_hal_can_frame_t &f, uint32_t cmd)
    {
        EXPECT_EQ(0, mc_hal_fake_can_rx_push(&fake, &f));
        Slow();
        std::optional<mc_hal_can_frame_t> got;
        mc_hal_can_frame_t t;
        while (mc_hal_fake_can_tx_pop(&fake, &t) == 0) {
            if (t.id == mc_can_id(kNode, cmd)) {
                got = t;
            }
        }
        return got;
    }
    uint32_t Enter()
    {
        auto r = Send(ReqFrame(kNode, MC_CAN_VAL_BOOT_OP_ENTER, 0u, MC_BOOT_ENTER_KEY),
                      MC_CAN_CMD_BOOT_REPLY);
        return r ? Decode(*r).status : 0xFFu;
    }

    mc_hal_fake_t fake{};
    mc_params_t defaults{};
    mc_app_cfg_t cfg{};
    mc_app_t app{};
    mc_drive_t drive{};
    int entered = 0;
};

TEST_F(AppBoot, EnterConfirmedResetsIntoTheBootloaderWithTheBridgeOff)
{
    auto r = Send(ReqFrame(kNode, MC_CAN_VAL_BOOT_OP_ENTER, 0u, MC_BOOT_ENTER_KEY),
                  MC_CAN_CMD_BOOT_REPLY);
    ASSERT_TRUE(r);
    ASSERT_EQ(uint32_t{MC_CAN_VAL_BOOT_STATUS_CONFIRM}, Decode(*r).status);
    EXPECT_EQ(0, entered);
    r = Send(ReqFrame(kNode, MC_CAN_VAL_BOOT_OP_ENTER_CONFIRM, 0u, Decode(*r).value),
             MC_CAN_CMD_BOOT_REPLY);
    ASSERT_TRUE(r);
    EXPECT_EQ(uint32_t{MC_CAN_VAL_BOOT_STATUS_OK}, Decode(*r).status);
    EXPECT_EQ(0, entered) << "not in the step that queued the OK";
    Slow();
    EXPECT_EQ(1, entered);
    EXPECT_EQ(MC_DRIVE_MODE_IDLE, drive.mode);
    EXPECT_FALSE(fake.pwm3.enabled);
}

TEST_F(AppBoot, NotWhileTheDriveRuns)
{
    mc_hal_can_frame_t f{};
    f.id = mc_can_id(kNode, MC_CAN_CMD_SET_CONTROL_MODE);
    f.len = 1u;
    f.data[0] = MC_CAN_CTRL_CURRENT;
    (void)Send(f, MC_CAN_CMD_CMD_ERROR);
    f.id = mc_can_id(kNode, MC_CAN_CMD_SET_ENABLE);
    f.data[0] = 1u;
    (void)Send(f, MC_CAN_CMD_CMD_ERROR);
    ASSERT_TRUE(app.cmd.enabled);
    EXPECT_EQ(uint32_t{MC_CAN_VAL_BOOT_STATUS_BUSY}, Enter());
    Slow(10);
    EXPECT_EQ(0, entered);
    EXPECT_TRUE(app.cmd.enabled);
}

TEST_F(AppBoot, BootDataAndAnUnboundBoardAreRefused)
{
    // BOOT_DATA is the bootloader's: CMD_ERROR MODE
    auto e = Send(DataFrames(kNode, std::vector<uint8_t>(256u, 0u), 0u)[0], MC_CAN_CMD_CMD_ERROR);
    ASSERT_TRUE(e);
    EXPECT_EQ(uint8_t{MC_CAN_CMD_BOOT_DATA}, e->data[0]);
    EXPECT_EQ(uint8_t{MC_CAN_ERR_MODE}, e->data[1]);
    // without the board's binding BOOT_REQ is UNSUPPORTED
    mc_can_cmd_attach_boot(&app.cmd, nullptr, nullptr);
    e = Send(ReqFrame(kNode, MC_CAN_VAL_BOOT_OP_INFO, 0u, 0u), MC_CAN_CMD_CMD_ERROR);
    ASSERT_TRUE(e);
    EXPECT_EQ(uint8_t{MC_CAN_CMD_BOOT_REQ}, e->data[0]);
    EXPECT_EQ(uint8_t{MC_CAN_ERR_UNSUPPORTED}, e->data[1]);
}

// Issue 28: every reply of the application passes the one limiter of the
// CAN handler (mc_telemetry.h), BOOT_REPLY too: a BOOT_REQ INFO every 1 ms
// slow step for 1 s gets the bucket's 10 and 39 of the 40 refills (the
// 40th falls after the last request), the rest not served and counted.
// Exact: frame counts.
TEST_F(AppBoot, BootRepliesPassTheApplicationsReplyLimiter)
{
    const mc_hal_can_frame_t f = ReqFrame(kNode, MC_CAN_VAL_BOOT_OP_INFO, 0u, 0u);
    uint32_t replies = 0u;
    for (uint32_t k = 0u; k < app.tick_hz; ++k) {
        if (Send(f, MC_CAN_CMD_BOOT_REPLY)) {
            ++replies;
        }
    }
    EXPECT_EQ(MC_TM_REPLY_BURST + MC_TM_REPLY_MAX_HZ - 1u, replies);
    EXPECT_LE(replies, MC_TM_REPLY_RESERVE_HZ) << "the bus budget's reserve for one second";
    EXPECT_EQ(app.tick_hz - replies, app.cmd.reply_limited);
    EXPECT_EQ(uint8_t{MC_CAN_ERR_LIMITED}, app.cmd.last_error);
}

TEST(BootProto, ByteLayoutEqualsTheDbcCodec)
{
    // mc_boot_reply_frame / mc_boot_req_decode against the table-driven
    // codec generated from the DBC (itself checked against cantools by
    // can.dbc_c_tables): the same bytes.
    std::mt19937 gen(5);
    auto rng = [&gen] { return static_cast<uint32_t>(gen()); };
    for (int n = 0; n < 500; ++n) {
        const uint32_t v[5] = {rng() & 0xFFu, rng() & 0xFFu, rng() & 0xFFu, rng() & 0xFFu,
                               static_cast<uint32_t>(rng())};
        mc_hal_can_frame_t a{}, b{};
        mc_boot_reply_frame(7u, v[0], v[1], v[2], v[3], v[4], &a);
        const float fv[5] = {float(v[0]), float(v[1]), float(v[2]), float(v[3]), 0.0f};
        ASSERT_EQ(MC_CAN_ERR_NONE, mc_can_proto_pack(MC_CAN_MSG_BOOT_REPLY, 7u, fv, 5u, &b));
        ASSERT_EQ(a.id, b.id);
        ASSERT_EQ(a.len, b.len);
        // the 32-bit value: as raw bits (a float32 would round it)
        for (int i = 0; i < 4; ++i) {
            ASSERT_EQ(a.data[i], b.data[i]);
        }
        EXPECT_EQ(v[4], Le32(&a.data[4]));

        const mc_hal_can_frame_t q = ReqFrame(3u, v[0], v[4] & 0xFFFFFFu, v[4] ^ 0x5A5A5A5Au);
        uint32_t msg = 0u;
        float out[MC_CAN_NSIG_MAX];
        ASSERT_EQ(MC_CAN_ERR_NONE, mc_can_proto_unpack(&q, &msg, out, MC_CAN_NSIG_MAX));
        ASSERT_EQ(uint32_t{MC_CAN_MSG_BOOT_REQ}, msg);
        mc_boot_msg_t m{};
        mc_boot_req_decode(q.data, &m);
        EXPECT_EQ(static_cast<uint32_t>(out[MC_CAN_BOOT_REQ_BOOT_OP]), m.op);
        EXPECT_EQ(static_cast<uint32_t>(out[MC_CAN_BOOT_REQ_ARG]), m.arg)
            << "24 bits: exact in f32";
        EXPECT_EQ(v[4] ^ 0x5A5A5A5Au, m.value);
    }
}

} // namespace
