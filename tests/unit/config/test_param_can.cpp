// The parameter exchange over CAN (PARAM_REQ / PARAM_REPLY of
// tools/can/motordrive.dbc) end to end on the fake HAL: the command handler,
// the parameter service, the drive, the telemetry and the A/B store on the
// fake flash. Values are compared bit for bit (they travel as raw 32 bits).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include "mc_can_cmd.h"
#include "mc_can_proto.h"
#include "mc_cfg_store.h"
#include "mc_fake_flash.h"
#include "mc_hal_fake.h"
#include "mc_param_srv.h"
#include "mc_telemetry.h"

namespace
{

constexpr uint32_t kSector = 4096;

uint32_t Bits(float f)
{
    uint32_t u;
    std::memcpy(&u, &f, sizeof u);
    return u;
}

struct Reply {
    uint32_t op, id, status, value;
};

class ParamCan : public ::testing::Test
{
  protected:
    void SetUp() override
    {
        Boot();
    }

    // Power on: flash, store, configuration, drive, telemetry, commands.
    void Boot()
    {
        mc_hal_fake_config_t fc;
        ASSERT_EQ(0, mc_hal_fake_config_default(&fc));
        ASSERT_EQ(0, mc_hal_fake_init(&fake, &fc));
        ASSERT_EQ(0, mc_fake_flash_init(&flash, mem.data(), sizes, 2));
        const mc_cfg_store_cfg_t sc = {&flash.dev, {0u, 1u}};
        ASSERT_EQ(0, mc_cfg_store_init(&store, &sc));
        boot = mc_cfg_store_load(&store, &p);
        mc_drive_cfg_t dc;
        ASSERT_EQ(MC_PARAMS_OK, mc_params_to_drive_cfg(&p, &dc));
        ASSERT_EQ(MC_DRIVE_CFG_OK, mc_drive_init(&d, &dc, &fake.board));
        mc_telemetry_cfg_t tc{};
        tc.node_id = static_cast<uint8_t>(p.can_node_id);
        tc.bitrate_bps = p.can_bitrate_bps;
        tc.bus_budget_frac = 0.5f;
        tc.tick_hz = 1000;
        tc.rate_hz[MC_TM_HEARTBEAT] = static_cast<uint16_t>(p.tm_heartbeat_hz);
        tc.rate_hz[MC_TM_CURRENTS] = static_cast<uint16_t>(p.tm_currents_hz);
        ASSERT_EQ(MC_TM_CFG_OK, mc_telemetry_init(&tm, &tc));
        mc_can_cmd_cfg_t cc{};
        cc.node_id = static_cast<uint8_t>(p.can_node_id);
        cc.tick_hz = 1000;
        cc.timeout_s = p.can_timeout_s;
        cc.stop_ramp_a_per_s = p.stop_ramp_a_per_s;
        mc_params_eff_t e;
        ASSERT_EQ(MC_GAINS_OK, mc_params_resolve(&p, &e));
        cc.stop_decel_rad_s2 = e.p.stop_decel_rad_s2;
        cc.speed_max_rad_s = p.speed_max_rad_s;
        ASSERT_EQ(MC_CAN_CMD_CFG_OK, mc_can_cmd_init(&c, &cc, &d, &tm));
        ASSERT_EQ(0,
                  mc_param_srv_init(&srv, &p, &d, &fake.board, &store, static_cast<uint8_t>(boot)));
        mc_can_cmd_attach_params(&c, &srv);
    }

    Reply Req(uint32_t op, uint32_t id, uint32_t value = 0)
    {
        mc_hal_can_frame_t f{};
        f.id = mc_can_id(c.cfg.node_id, MC_CAN_CMD_PARAM_REQ);
        f.len = 8;
        f.data[0] = static_cast<uint8_t>(op);
        f.data[1] = static_cast<uint8_t>(id);
        f.data[2] = static_cast<uint8_t>(id >> 8);
        for (int i = 0; i < 4; ++i)
            f.data[4 + i] = static_cast<uint8_t>(value >> (8 * i));
        EXPECT_EQ(MC_CAN_ERR_NONE, mc_can_cmd_handle(&c, &f, fake.board.can));
        mc_hal_can_frame_t r{};
        EXPECT_EQ(0, mc_hal_fake_can_tx_pop(&fake, &r)) << "one PARAM_REPLY per request";
        EXPECT_EQ(mc_can_id(c.cfg.node_id, MC_CAN_CMD_PARAM_REPLY), r.id);
        EXPECT_EQ(8u, r.len);
        Reply out{r.data[0], static_cast<uint32_t>(r.data[1] | (r.data[2] << 8)), r.data[3], 0};
        for (int i = 0; i < 4; ++i)
            out.value |= static_cast<uint32_t>(r.data[4 + i]) << (8 * i);
        EXPECT_EQ(op, out.op);
        EXPECT_EQ(id, out.id);
        return out;
    }

    void Run()
    {
        ASSERT_EQ(0, mc_hal_fake_encoder_set(&fake, 0u, MC_HAL_ENCODER_FLAG_VALID));
        ASSERT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_CURRENT));
        ASSERT_TRUE(fake.pwm3.enabled);
    }

    std::vector<uint8_t> mem = std::vector<uint8_t>(2 * kSector, 0xFF);
    uint32_t sizes[2] = {kSector, kSector};
    mc_hal_fake_t fake{};
    mc_fake_flash_t flash{};
    mc_cfg_store_t store{};
    mc_cfg_boot_t boot{};
    mc_params_t p{};
    mc_drive_t d{};
    mc_telemetry_t tm{};
    mc_can_cmd_t c{};
    mc_param_srv_t srv{};
};

TEST_F(ParamCan, ReadValuesAndStatus)
{
    EXPECT_EQ(MC_CFG_BOOT_EMPTY, boot);
    Reply r = Req(MC_PARAM_OP_READ, MC_PARAM_ID_R_OHM);
    EXPECT_EQ(MC_PARAM_OK, r.status);
    EXPECT_EQ(Bits(0.675f), r.value);
    EXPECT_EQ(500000u, Req(MC_PARAM_OP_READ, MC_PARAM_ID_CAN_BITRATE_BPS).value);
    EXPECT_EQ(MC_PARAMS_LAYOUT_VERSION,
              Req(MC_PARAM_OP_READ, MC_PARAM_ID_CFG_LAYOUT_VERSION).value);
    EXPECT_EQ(static_cast<uint32_t>(MC_CFG_BOOT_EMPTY),
              Req(MC_PARAM_OP_READ, MC_PARAM_ID_CFG_STORE_STATUS).value);
    EXPECT_EQ(MC_PARAM_ERR_UNKNOWN_ID, Req(MC_PARAM_OP_READ, 19u).status);
}

TEST_F(ParamCan, BadWritesRefusedWithReasonNothingChanged)
{
    const mc_param_srv_t before = srv;
    EXPECT_EQ(MC_PARAM_ERR_UNKNOWN_ID, Req(MC_PARAM_OP_WRITE, 19u, 1u).status);
    EXPECT_EQ(MC_PARAM_ERR_READONLY, Req(MC_PARAM_OP_WRITE, MC_PARAM_ID_CFG_STORE_SEQ, 5u).status);
    EXPECT_EQ(MC_PARAM_ERR_RANGE, Req(MC_PARAM_OP_WRITE, MC_PARAM_ID_R_OHM, Bits(-0.5f)).status);
    EXPECT_EQ(MC_PARAM_ERR_RANGE, Req(MC_PARAM_OP_WRITE, MC_PARAM_ID_R_OHM,
                                      Bits(std::numeric_limits<float>::quiet_NaN()))
                                      .status);
    EXPECT_EQ(MC_PARAM_ERR_RANGE, Req(MC_PARAM_OP_WRITE, MC_PARAM_ID_POLE_PAIRS, 0u).status);
    EXPECT_EQ(MC_PARAM_ERR_RANGE, Req(MC_PARAM_OP_WRITE, MC_PARAM_ID_CAN_NODE_ID, 63u).status);
    EXPECT_EQ(0, std::memcmp(&before, &srv, sizeof srv));
    // an opcode outside the DBC range is a malformed command: CMD_ERROR
    mc_hal_can_frame_t f{};
    f.id = mc_can_id(1u, MC_CAN_CMD_PARAM_REQ);
    f.len = 8;
    f.data[0] = 9;
    EXPECT_EQ(MC_CAN_ERR_RANGE, mc_can_cmd_handle(&c, &f, fake.board.can));
    EXPECT_EQ(0, std::memcmp(&before, &srv, sizeof srv));
}

TEST_F(ParamCan, WriteTakesEffectOnApply)
{
    EXPECT_EQ(MC_PARAM_OK, Req(MC_PARAM_OP_WRITE, MC_PARAM_ID_I_MAX_A, Bits(5.0f)).status);
    EXPECT_EQ(Bits(5.0f), Req(MC_PARAM_OP_READ, MC_PARAM_ID_I_MAX_A).value); // staged
    EXPECT_EQ(1u, Req(MC_PARAM_OP_READ, MC_PARAM_ID_CFG_PENDING).value);
    EXPECT_EQ(10.0f, d.cfg.i_max_a) << "not in effect before APPLY";
    EXPECT_EQ(MC_PARAM_OK, Req(MC_PARAM_OP_APPLY, 0).status);
    EXPECT_EQ(5.0f, d.cfg.i_max_a);
    EXPECT_EQ(-EINVAL, mc_drive_set_current_ref(&d, 0.0f, 5.5f));
    EXPECT_EQ(0u, Req(MC_PARAM_OP_READ, MC_PARAM_ID_CFG_PENDING).value);
    // a stopped parameter applied while stopped re-initialises the drive
    EXPECT_EQ(MC_PARAM_OK, Req(MC_PARAM_OP_WRITE, MC_PARAM_ID_PWM_HZ, 10000u).status);
    EXPECT_EQ(MC_PARAM_OK, Req(MC_PARAM_OP_APPLY, 0).status);
    EXPECT_EQ(1.0f / 10000.0f, d.cfg.foc.dt_s);
    // CAN-side runtime parameters
    EXPECT_EQ(MC_PARAM_OK, Req(MC_PARAM_OP_WRITE, MC_PARAM_ID_CAN_TIMEOUT_S, Bits(0.25f)).status);
    EXPECT_EQ(MC_PARAM_OK, Req(MC_PARAM_OP_WRITE, MC_PARAM_ID_TM_CURRENTS_HZ, 250u).status);
    EXPECT_EQ(MC_PARAM_OK, Req(MC_PARAM_OP_APPLY, 0).status);
    EXPECT_EQ(250u, c.timeout_ticks); // 0.25 s at 1 kHz
    EXPECT_EQ(250u, tm.cfg.rate_hz[MC_TM_CURRENTS]);
}

TEST_F(ParamCan, InconsistentSetRefusedAsAWhole)
{
    const mc_drive_cfg_t dc = d.cfg;
    // each value in range; together the trip (15 A) exceeds the sensor (12 A)
    EXPECT_EQ(MC_PARAM_OK, Req(MC_PARAM_OP_WRITE, MC_PARAM_ID_I_SENSE_MAX_A, Bits(12.0f)).status);
    EXPECT_EQ(MC_PARAM_OK, Req(MC_PARAM_OP_WRITE, MC_PARAM_ID_I_MAX_A, Bits(8.0f)).status);
    EXPECT_EQ(MC_PARAM_OK, Req(MC_PARAM_OP_WRITE, MC_PARAM_ID_I_TRIP_A, Bits(15.0f)).status);
    Reply r = Req(MC_PARAM_OP_APPLY, 0);
    EXPECT_EQ(MC_PARAM_ERR_INVALID, r.status);
    EXPECT_EQ(MC_PARAMS_ERR_SENSE, r.value);
    EXPECT_EQ(0, std::memcmp(&dc, &d.cfg, sizeof dc)) << "never half applied";
    EXPECT_EQ(10.0f, srv.active.i_max_a);
    // gains vs PWM rate: 1257 rad/s at 2 kHz is bw dt = 0.63 > 0.5
    EXPECT_EQ(MC_PARAM_OK, Req(MC_PARAM_OP_WRITE, MC_PARAM_ID_I_SENSE_MAX_A, Bits(60.0f)).status);
    EXPECT_EQ(MC_PARAM_OK, Req(MC_PARAM_OP_WRITE, MC_PARAM_ID_PWM_HZ, 5000u).status);
    EXPECT_EQ(MC_PARAM_OK,
              Req(MC_PARAM_OP_WRITE, MC_PARAM_ID_CURRENT_BW_RAD_S, Bits(3000.0f)).status);
    r = Req(MC_PARAM_OP_APPLY, 0);
    EXPECT_EQ(MC_PARAM_ERR_INVALID, r.status);
    EXPECT_EQ(MC_PARAMS_ERR_BANDWIDTH, r.value);
    // telemetry above the bus budget (4 x 1000 frames/s of 135 bits on
    // 500 kbit/s is 108 %): refused, rates unchanged
    EXPECT_EQ(MC_PARAM_OK, Req(MC_PARAM_OP_LOAD_DEFAULTS, 0).status);
    for (uint32_t id : {MC_PARAM_ID_TM_CURRENTS_HZ, MC_PARAM_ID_TM_VOLTAGES_HZ,
                        MC_PARAM_ID_TM_SPEED_HZ, MC_PARAM_ID_TM_POSITION_HZ}) {
        EXPECT_EQ(MC_PARAM_OK, Req(MC_PARAM_OP_WRITE, id, 1000u).status);
    }
    EXPECT_EQ(MC_PARAM_ERR_INVALID, Req(MC_PARAM_OP_APPLY, 0).status);
    EXPECT_EQ(100u, tm.cfg.rate_hz[MC_TM_CURRENTS]);
    EXPECT_EQ(0, std::memcmp(&dc, &d.cfg, sizeof dc));
}

TEST_F(ParamCan, WhileRunningOnlyRuntimeParameters)
{
    Run();
    EXPECT_EQ(MC_PARAM_ERR_RUNNING, Req(MC_PARAM_OP_WRITE, MC_PARAM_ID_R_OHM, Bits(0.5f)).status);
    EXPECT_EQ(MC_PARAM_ERR_RUNNING, Req(MC_PARAM_OP_WRITE, MC_PARAM_ID_CAN_NODE_ID, 3u).status);
    EXPECT_EQ(MC_PARAM_OK, Req(MC_PARAM_OP_WRITE, MC_PARAM_ID_I_MAX_A, Bits(6.0f)).status);
    EXPECT_EQ(MC_PARAM_OK, Req(MC_PARAM_OP_APPLY, 0).status);
    EXPECT_EQ(6.0f, d.cfg.i_max_a);
    EXPECT_EQ(MC_DRIVE_MODE_CURRENT, d.mode) << "a runtime apply does not stop the drive";
    // A lower limit takes effect at once on the reference in force (found by
    // can.fuzz_cmd: 4 A kept running after i_max_a became 2.77 A). Exact
    // values: the clamp copies the limit, the sign is kept.
    ASSERT_EQ(0, mc_drive_set_current_ref(&d, -1.0f, -5.5f));
    EXPECT_EQ(MC_PARAM_OK, Req(MC_PARAM_OP_WRITE, MC_PARAM_ID_I_MAX_A, Bits(2.5f)).status);
    EXPECT_EQ(MC_PARAM_OK, Req(MC_PARAM_OP_APPLY, 0).status);
    EXPECT_EQ(-1.0f, d.id_ref_a) << "inside the new limit: unchanged";
    EXPECT_EQ(-2.5f, d.iq_ref_a) << "clamped to the new i_max_a";
    EXPECT_EQ(MC_PARAM_OK, Req(MC_PARAM_OP_WRITE, MC_PARAM_ID_I_MAX_A, Bits(6.0f)).status);
    EXPECT_EQ(MC_PARAM_OK, Req(MC_PARAM_OP_APPLY, 0).status);
    EXPECT_TRUE(fake.pwm3.enabled);
    EXPECT_EQ(MC_PARAM_ERR_RUNNING, Req(MC_PARAM_OP_SAVE, 0).status);
    EXPECT_EQ(MC_PARAM_ERR_RUNNING, Req(MC_PARAM_OP_LOAD_DEFAULTS, 0).status);
    EXPECT_EQ(0u, flash.steps) << "no flash operation while the bridge is on";
    // a stopped parameter staged while stopped cannot be applied once running
    ASSERT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_IDLE));
    EXPECT_EQ(MC_PARAM_OK, Req(MC_PARAM_OP_WRITE, MC_PARAM_ID_POLE_PAIRS, 7u).status);
    EXPECT_EQ(MC_PARAM_OK, Req(MC_PARAM_OP_WRITE, MC_PARAM_ID_I_MAX_A, Bits(4.0f)).status);
    Run();
    EXPECT_EQ(MC_PARAM_ERR_RUNNING, Req(MC_PARAM_OP_APPLY, 0).status);
    EXPECT_EQ(6.0f, d.cfg.i_max_a) << "nothing of the set applied";
    EXPECT_EQ(4u, d.cfg.pole_pairs);
}

TEST_F(ParamCan, FaultLatchedOnlyReadsAndTheClearPath)
{
    mc_drive_raise_fault(&d, MC_DRIVE_FAULT_EXTERNAL);
    ASSERT_EQ(MC_DRIVE_MODE_FAULT, d.mode);
    EXPECT_EQ(MC_PARAM_ERR_FAULT, Req(MC_PARAM_OP_WRITE, MC_PARAM_ID_I_MAX_A, Bits(5.0f)).status);
    EXPECT_EQ(MC_PARAM_ERR_FAULT, Req(MC_PARAM_OP_APPLY, 0).status);
    EXPECT_EQ(MC_PARAM_ERR_FAULT, Req(MC_PARAM_OP_SAVE, 0).status);
    EXPECT_EQ(MC_PARAM_ERR_FAULT, Req(MC_PARAM_OP_LOAD_DEFAULTS, 0).status);
    EXPECT_EQ(MC_PARAM_OK, Req(MC_PARAM_OP_READ, MC_PARAM_ID_I_MAX_A).status);
    EXPECT_EQ(10.0f, d.cfg.i_max_a);
    // the clear path (the fake's bus is inside the window: the cause is gone)
    ASSERT_EQ(0, mc_hal_fake_adc_set_sample(&fake, 0.0f, 0.0f, 0.0f, 24.0f,
                                            MC_HAL_ADC_VALID_IA | MC_HAL_ADC_VALID_IB |
                                                MC_HAL_ADC_VALID_VBUS));
    (void)mc_drive_fast_step(&d); // the drive sees the bus back in its window
    mc_hal_can_frame_t f{};
    f.id = mc_can_id(1u, MC_CAN_CMD_CLEAR_FAULTS);
    ASSERT_EQ(MC_CAN_ERR_NONE, mc_can_cmd_handle(&c, &f, fake.board.can));
    EXPECT_EQ(MC_PARAM_OK, Req(MC_PARAM_OP_WRITE, MC_PARAM_ID_I_MAX_A, Bits(5.0f)).status);
}

TEST_F(ParamCan, SaveSurvivesRebootNodeIdOnlyAfterReset)
{
    EXPECT_EQ(MC_PARAM_OK, Req(MC_PARAM_OP_WRITE, MC_PARAM_ID_I_MAX_A, Bits(7.0f)).status);
    EXPECT_EQ(MC_PARAM_OK, Req(MC_PARAM_OP_WRITE, MC_PARAM_ID_CAN_NODE_ID, 5u).status);
    EXPECT_EQ(MC_PARAM_OK, Req(MC_PARAM_OP_APPLY, 0).status);
    EXPECT_EQ(1u, c.cfg.node_id) << "the node id changes only after save + reset";
    Reply r = Req(MC_PARAM_OP_SAVE, 0);
    EXPECT_EQ(MC_PARAM_OK, r.status);
    EXPECT_EQ(1u, r.value); // first record
    Boot();
    EXPECT_EQ(MC_CFG_BOOT_STORED, boot);
    EXPECT_EQ(5u, c.cfg.node_id);
    EXPECT_EQ(7.0f, d.cfg.i_max_a);
    EXPECT_EQ(Bits(7.0f), Req(MC_PARAM_OP_READ, MC_PARAM_ID_I_MAX_A).value); // node 5 now
    // defaults: staged, applied, saved, and after a reset the node is 1 again
    EXPECT_EQ(MC_PARAM_OK, Req(MC_PARAM_OP_LOAD_DEFAULTS, 0).status);
    EXPECT_EQ(MC_PARAM_OK, Req(MC_PARAM_OP_APPLY, 0).status);
    EXPECT_EQ(MC_PARAM_OK, Req(MC_PARAM_OP_SAVE, 0).status);
    Boot();
    EXPECT_EQ(0, std::memcmp(&p, &mc_params_default, sizeof p));
    EXPECT_EQ(1u, c.cfg.node_id);
}

TEST_F(ParamCan, HeartbeatSaysWhenDefaultsWereLoaded)
{
    float v[MC_CAN_NSIG_MAX] = {0};
    const mc_telemetry_src_t src = {&d, &c, nullptr, nullptr};
    ASSERT_TRUE(mc_telemetry_values(MC_TM_HEARTBEAT, &src, v));
    EXPECT_EQ(static_cast<float>(MC_CAN_VAL_CFG_STATUS_EMPTY), v[MC_CAN_HEARTBEAT_CFG_STATUS]);
    std::memset(mem.data(), 0x00, 64); // garbage where a record would start
    Boot();
    EXPECT_EQ(MC_CFG_BOOT_CORRUPT, boot);
    ASSERT_TRUE(mc_telemetry_values(MC_TM_HEARTBEAT, &src, v));
    EXPECT_EQ(static_cast<float>(MC_CAN_VAL_CFG_STATUS_CORRUPT), v[MC_CAN_HEARTBEAT_CFG_STATUS]);
    EXPECT_EQ(0, std::memcmp(&p, &mc_params_default, sizeof p));
}

TEST_F(ParamCan, HeartbeatReportsTheStoreAfterASave)
{
    // the heartbeat said the boot status (EMPTY) after a SAVE until the
    // next boot: it reports what the store holds now
    float v[MC_CAN_NSIG_MAX] = {0};
    const mc_telemetry_src_t src = {&d, &c, nullptr, nullptr};
    ASSERT_EQ(MC_CFG_BOOT_EMPTY, boot);
    EXPECT_EQ(MC_PARAM_OK, Req(MC_PARAM_OP_WRITE, MC_PARAM_ID_I_MAX_A, Bits(7.0f)).status);
    EXPECT_EQ(MC_PARAM_OK, Req(MC_PARAM_OP_APPLY, 0).status);
    ASSERT_TRUE(mc_telemetry_values(MC_TM_HEARTBEAT, &src, v));
    EXPECT_EQ(static_cast<float>(MC_CAN_VAL_CFG_STATUS_EMPTY), v[MC_CAN_HEARTBEAT_CFG_STATUS])
        << "applied, not saved: the store is still empty";
    EXPECT_EQ(MC_PARAM_OK, Req(MC_PARAM_OP_SAVE, 0).status);
    ASSERT_TRUE(mc_telemetry_values(MC_TM_HEARTBEAT, &src, v));
    EXPECT_EQ(static_cast<float>(MC_CAN_VAL_CFG_STATUS_STORED), v[MC_CAN_HEARTBEAT_CFG_STATUS]);
    EXPECT_EQ(static_cast<uint32_t>(MC_CFG_BOOT_STORED),
              Req(MC_PARAM_OP_READ, MC_PARAM_ID_CFG_STORE_STATUS).value);
    EXPECT_EQ(static_cast<uint8_t>(MC_CFG_BOOT_EMPTY), srv.boot_status) << "the boot's, kept";
    // a SAVE the flash refuses: the heartbeat says so
    flash.fail_next = -EIO;
    EXPECT_EQ(MC_PARAM_ERR_STORE, Req(MC_PARAM_OP_SAVE, 0).status);
    ASSERT_TRUE(mc_telemetry_values(MC_TM_HEARTBEAT, &src, v));
    EXPECT_EQ(static_cast<float>(MC_CAN_VAL_CFG_STATUS_FLASH), v[MC_CAN_HEARTBEAT_CFG_STATUS]);
    EXPECT_EQ(MC_PARAM_OK, Req(MC_PARAM_OP_SAVE, 0).status);
    ASSERT_TRUE(mc_telemetry_values(MC_TM_HEARTBEAT, &src, v));
    EXPECT_EQ(static_cast<float>(MC_CAN_VAL_CFG_STATUS_STORED), v[MC_CAN_HEARTBEAT_CFG_STATUS]);
    // and the next boot agrees
    Boot();
    EXPECT_EQ(MC_CFG_BOOT_STORED, boot);
    ASSERT_TRUE(mc_telemetry_values(MC_TM_HEARTBEAT, &src, v));
    EXPECT_EQ(static_cast<float>(MC_CAN_VAL_CFG_STATUS_STORED), v[MC_CAN_HEARTBEAT_CFG_STATUS]);
}

} // namespace
