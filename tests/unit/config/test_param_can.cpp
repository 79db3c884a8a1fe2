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
        const mc_cfg_store_cfg_t sc = {&flash.dev, {0u, 1u}, 0u};
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
        if (top_up) {
            c.reply.tokens = MC_TM_REPLY_BURST; // time counted by the test alone
        }
        EXPECT_EQ(MC_CAN_ERR_NONE, mc_can_cmd_handle(&c, &f, fake.board.can));
        // as a host does: wait for the reply (the reply limiter may hold it
        // for a few supervision steps: one token per 25 ms)
        mc_hal_can_frame_t r{};
        int waited = 0;
        while (mc_hal_fake_can_tx_pop(&fake, &r) != 0 && waited < 100) {
            mc_can_cmd_step(&c);
            ++waited;
        }
        EXPECT_LE(waited, 25) << "a reply held longer than one token's refill";
        mc_hal_can_frame_t more{};
        EXPECT_NE(0, mc_hal_fake_can_tx_pop(&fake, &more)) << "one PARAM_REPLY per request";
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
    bool top_up = false; // Req tops the reply limiter up (tested apart)
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
    // gains vs PWM rate: 3000 rad/s at 5 kHz is bw dt = 0.6 > 0.3
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
    EXPECT_EQ(MC_PARAM_ERR_NEEDS_CONFIRM,
              Req(MC_PARAM_OP_WRITE, MC_PARAM_ID_CAN_NODE_ID, 5u).status);
    EXPECT_EQ(MC_PARAM_OK, Req(MC_PARAM_OP_CONFIRM, MC_PARAM_ID_CAN_NODE_ID, 5u).status);
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
    // defaults: staged, applied, saved, and after a reset every value is the
    // default but the node id and bit rate, which LOAD_DEFAULTS keeps (it
    // cannot move the node: that takes a WRITE and its CONFIRM)
    EXPECT_EQ(MC_PARAM_OK, Req(MC_PARAM_OP_LOAD_DEFAULTS, 0).status);
    EXPECT_EQ(MC_PARAM_OK, Req(MC_PARAM_OP_APPLY, 0).status);
    EXPECT_EQ(MC_PARAM_OK, Req(MC_PARAM_OP_SAVE, 0).status);
    Boot();
    mc_params_t want = mc_params_default;
    want.can_node_id = 5u;
    EXPECT_EQ(0, std::memcmp(&p, &want, sizeof p));
    EXPECT_EQ(5u, c.cfg.node_id);
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

// ---- issue 28: the access classes protect, the flash is a budget ----------

// Protections could be switched off while the motor ran (omega_max 0,
// temp_max 0, stall detection 0, can_timeout_s 60: WRITE + APPLY answered
// OK with the bridge on). Every trip, supervision limit, the command
// timeout and the stop ramps are `stopped` now: refused RUNNING, nothing
// staged; the same writes go through once the bridge is off.
TEST_F(ParamCan, ProtectionsCannotBeSwitchedOffWhileRunning)
{
    struct W {
        uint32_t id;
        uint32_t raw;
    } writes[] = {
        {MC_PARAM_ID_OMEGA_MAX_RAD_S, Bits(0.0f)},   {MC_PARAM_ID_TEMP_MAX_C, Bits(0.0f)},
        {MC_PARAM_ID_STALL_TIME_S, Bits(0.0f)},      {MC_PARAM_ID_STALL_CURRENT_FRAC, Bits(0.0f)},
        {MC_PARAM_ID_STALL_SPEED_RAD_S, Bits(0.0f)}, {MC_PARAM_ID_I_UNBALANCE_MAX_A, Bits(0.0f)},
        {MC_PARAM_ID_CAN_TIMEOUT_S, Bits(60.0f)},    {MC_PARAM_ID_I_TRIP_A, Bits(59.0f)},
        {MC_PARAM_ID_VBUS_MAX_V, Bits(1000.0f)},     {MC_PARAM_ID_VBUS_MIN_V, Bits(0.5f)},
        {MC_PARAM_ID_STOP_DECEL_RAD_S2, Bits(0.1f)}, {MC_PARAM_ID_STOP_RAMP_A_PER_S, Bits(0.1f)},
    };
    Run();
    const mc_params_t staged = srv.staged;
    const float w_trip = d.cfg.omega_max_rad_s; // derived: 1.5 speed_max_rad_s
    ASSERT_GT(w_trip, 0.0f);
    for (const W &w : writes) {
        const mc_param_info_t *info = mc_param_find(w.id, nullptr);
        ASSERT_NE(nullptr, info);
        EXPECT_EQ(MC_PARAM_ACCESS_STOPPED, info->access) << "id " << w.id;
        EXPECT_EQ(MC_PARAM_ERR_RUNNING, Req(MC_PARAM_OP_WRITE, w.id, w.raw).status)
            << "id " << w.id;
    }
    EXPECT_EQ(0, std::memcmp(&staged, &srv.staged, sizeof staged)) << "nothing staged";
    EXPECT_FALSE(srv.pending);
    EXPECT_EQ(w_trip, d.cfg.omega_max_rad_s);
    EXPECT_EQ(500u, c.timeout_ticks);
    // bridge off: allowed (the operator's decision, with the motor at rest;
    // 0 is the derived trip, so another value)
    ASSERT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_IDLE));
    EXPECT_EQ(MC_PARAM_OK,
              Req(MC_PARAM_OP_WRITE, MC_PARAM_ID_OMEGA_MAX_RAD_S, Bits(2.0f * w_trip)).status);
    EXPECT_EQ(MC_PARAM_OK, Req(MC_PARAM_OP_WRITE, MC_PARAM_ID_CAN_TIMEOUT_S, Bits(2.0f)).status);
    EXPECT_EQ(MC_PARAM_OK, Req(MC_PARAM_OP_APPLY, 0).status);
    EXPECT_EQ(2.0f * w_trip, d.cfg.omega_max_rad_s);
    EXPECT_EQ(2000u, c.timeout_ticks);
}

// Three frames (WRITE node id, APPLY, SAVE) used to move the drive off its
// bus at the next boot. A node id or bit rate now needs a CONFIRM, the
// very next request, same id and value, within 2 s; every other way
// stages nothing.
TEST_F(ParamCan, NodeIdAndBitRateNeedTheirConfirmRightAfterTheWrite)
{
    top_up = true;
    // the three frames: refused, the store keeps node 1
    EXPECT_EQ(MC_PARAM_ERR_NEEDS_CONFIRM,
              Req(MC_PARAM_OP_WRITE, MC_PARAM_ID_CAN_NODE_ID, 5u).status);
    EXPECT_EQ(1u, srv.staged.can_node_id) << "nothing staged by the WRITE";
    EXPECT_EQ(MC_PARAM_OK, Req(MC_PARAM_OP_APPLY, 0).status);
    EXPECT_EQ(MC_PARAM_OK, Req(MC_PARAM_OP_SAVE, 0).status);
    Boot();
    EXPECT_EQ(1u, c.cfg.node_id);
    // CONFIRM without its WRITE, of another value or id, after another request
    const mc_params_t staged = srv.staged;
    EXPECT_EQ(MC_PARAM_ERR_NOT_CONFIRMED,
              Req(MC_PARAM_OP_CONFIRM, MC_PARAM_ID_CAN_NODE_ID, 5u).status);
    EXPECT_EQ(MC_PARAM_ERR_NEEDS_CONFIRM,
              Req(MC_PARAM_OP_WRITE, MC_PARAM_ID_CAN_NODE_ID, 5u).status);
    EXPECT_EQ(MC_PARAM_ERR_NOT_CONFIRMED,
              Req(MC_PARAM_OP_CONFIRM, MC_PARAM_ID_CAN_NODE_ID, 6u).status);
    EXPECT_EQ(MC_PARAM_ERR_NOT_CONFIRMED,
              Req(MC_PARAM_OP_CONFIRM, MC_PARAM_ID_CAN_NODE_ID, 5u).status)
        << "a failed CONFIRM disarms";
    EXPECT_EQ(MC_PARAM_ERR_NEEDS_CONFIRM,
              Req(MC_PARAM_OP_WRITE, MC_PARAM_ID_CAN_BITRATE_BPS, 250000u).status);
    EXPECT_EQ(MC_PARAM_ERR_NOT_CONFIRMED,
              Req(MC_PARAM_OP_CONFIRM, MC_PARAM_ID_CAN_NODE_ID, 250000u).status);
    EXPECT_EQ(MC_PARAM_ERR_NEEDS_CONFIRM,
              Req(MC_PARAM_OP_WRITE, MC_PARAM_ID_CAN_BITRATE_BPS, 250000u).status);
    EXPECT_EQ(MC_PARAM_OK, Req(MC_PARAM_OP_READ, MC_PARAM_ID_CAN_BITRATE_BPS).status);
    EXPECT_EQ(MC_PARAM_ERR_NOT_CONFIRMED,
              Req(MC_PARAM_OP_CONFIRM, MC_PARAM_ID_CAN_BITRATE_BPS, 250000u).status)
        << "not the very next request";
    EXPECT_EQ(0, std::memcmp(&staged, &srv.staged, sizeof staged));
    // the window: 2 s at the 1 kHz supervision step (2000 steps), exact
    EXPECT_EQ(MC_PARAM_ERR_NEEDS_CONFIRM,
              Req(MC_PARAM_OP_WRITE, MC_PARAM_ID_CAN_NODE_ID, 5u).status);
    for (int k = 0; k < 2001; ++k) {
        mc_can_cmd_step(&c);
    }
    EXPECT_EQ(MC_PARAM_ERR_NOT_CONFIRMED,
              Req(MC_PARAM_OP_CONFIRM, MC_PARAM_ID_CAN_NODE_ID, 5u).status)
        << "late";
    EXPECT_EQ(MC_PARAM_ERR_NEEDS_CONFIRM,
              Req(MC_PARAM_OP_WRITE, MC_PARAM_ID_CAN_NODE_ID, 5u).status);
    for (int k = 0; k < 1990; ++k) {
        mc_can_cmd_step(&c);
    }
    EXPECT_EQ(MC_PARAM_OK, Req(MC_PARAM_OP_CONFIRM, MC_PARAM_ID_CAN_NODE_ID, 5u).status);
    EXPECT_EQ(5u, srv.staged.can_node_id);
    // writing the value already staged needs no confirmation
    EXPECT_EQ(MC_PARAM_OK, Req(MC_PARAM_OP_WRITE, MC_PARAM_ID_CAN_NODE_ID, 5u).status);
    // LOAD_DEFAULTS keeps the staged node id and bit rate
    EXPECT_EQ(MC_PARAM_OK, Req(MC_PARAM_OP_LOAD_DEFAULTS, 0).status);
    EXPECT_EQ(5u, srv.staged.can_node_id);
    EXPECT_EQ(500000u, srv.staged.can_bitrate_bps);
    // and it takes effect after APPLY, SAVE and a reset only
    EXPECT_EQ(MC_PARAM_OK, Req(MC_PARAM_OP_APPLY, 0).status);
    EXPECT_EQ(MC_PARAM_OK, Req(MC_PARAM_OP_SAVE, 0).status);
    EXPECT_EQ(1u, c.cfg.node_id);
    Boot();
    EXPECT_EQ(5u, c.cfg.node_id);
}

// 2000 SAVEs in 2 s were all written (55 erases on the SIL flash).
// Now an unchanged set is not written at all, and changed sets go through
// the bucket: 4, then one per 120 s; RATE_LIMIT says how long to wait.
TEST_F(ParamCan, SaveSkipsAnUnchangedSetAndIsRateLimited)
{
    top_up = true;
    Reply r = Req(MC_PARAM_OP_SAVE, 0);
    ASSERT_EQ(MC_PARAM_OK, r.status);
    EXPECT_EQ(1u, r.value);
    const uint32_t steps = flash.steps;
    for (int k = 0; k < 2000; ++k) {
        r = Req(MC_PARAM_OP_SAVE, 0);
        ASSERT_EQ(MC_PARAM_OK, r.status) << k;
        ASSERT_EQ(1u, r.value) << "the record that holds the set";
        mc_can_cmd_step(&c); // 1 ms
    }
    EXPECT_EQ(steps, flash.steps) << "no erase, no program for an unchanged set";
    EXPECT_EQ(2000u, srv.saves_skipped);
    EXPECT_EQ(1u, store.saves);
    // changed sets: 3 more tokens in the bucket (4 at boot, one used)
    float i_max = 5.0f;
    auto change = [&]() {
        i_max += 0.5f;
        ASSERT_EQ(MC_PARAM_OK, Req(MC_PARAM_OP_WRITE, MC_PARAM_ID_I_MAX_A, Bits(i_max)).status);
        ASSERT_EQ(MC_PARAM_OK, Req(MC_PARAM_OP_APPLY, 0).status);
    };
    for (uint32_t k = 0; k < 3; ++k) {
        change();
        EXPECT_EQ(MC_PARAM_OK, Req(MC_PARAM_OP_SAVE, 0).status);
    }
    EXPECT_EQ(4u, store.saves);
    change();
    r = Req(MC_PARAM_OP_SAVE, 0);
    EXPECT_EQ(MC_PARAM_ERR_RATE_LIMIT, r.status);
    // the bucket refills one per 120 s; 2 s of steps have passed since it
    // began refilling (the first SAVE used its first token): 118 s to wait
    EXPECT_EQ(118u, r.value) << "seconds until the next SAVE";
    const uint32_t steps2 = flash.steps;
    for (uint32_t k = 0; k < 117999u; ++k) {
        mc_can_cmd_step(&c);
    }
    EXPECT_EQ(MC_PARAM_ERR_RATE_LIMIT, Req(MC_PARAM_OP_SAVE, 0).status) << "1 ms early";
    EXPECT_EQ(steps2, flash.steps) << "a refused SAVE touches no flash";
    mc_can_cmd_step(&c);
    r = Req(MC_PARAM_OP_SAVE, 0);
    EXPECT_EQ(MC_PARAM_OK, r.status);
    EXPECT_EQ(5u, r.value);
    EXPECT_EQ(2u, srv.saves_limited);
    // a reboot boots the newest
    Boot();
    EXPECT_EQ(i_max, p.i_max_a);
}

// The bucket refilled at a reset, and a CAN node can reset the drive: ENTER
// the bootloader, then its RUN. 4 SAVEs, a reset, 4 more, ... would have
// written as fast as the bootloader cycles. The application's side of the
// update now sees "busy" (ENTER refused BUSY) until the bucket is full
// again, so a reset gives no SAVE the limiter had not allowed. Exact: the
// refill is counted in the 1 kHz supervision steps.
TEST_F(ParamCan, NoResetIntoTheBootloaderBeforeTheSaveBucketIsFull)
{
    struct Seen {
        int calls = 0;
        bool busy = false;
    } seen;
    mc_can_cmd_attach_boot(
        &c,
        [](void *ctx, const mc_hal_can_frame_t *, bool busy, const mc_hal_can_t *) {
            auto *k = static_cast<Seen *>(ctx);
            k->calls++;
            k->busy = busy;
        },
        &seen);
    mc_hal_can_frame_t enter{};
    enter.id = mc_can_id(c.cfg.node_id, MC_CAN_CMD_BOOT_REQ);
    enter.len = 8;
    auto boot_busy = [&]() {
        c.reply.tokens = MC_TM_REPLY_BURST;
        EXPECT_EQ(MC_CAN_ERR_NONE, mc_can_cmd_handle(&c, &enter, fake.board.can));
        return seen.busy;
    };
    top_up = true;
    EXPECT_FALSE(boot_busy()) << "a full bucket (boot): the update may reset";
    EXPECT_EQ(MC_PARAM_OK, Req(MC_PARAM_OP_SAVE, 0).status);
    EXPECT_EQ(MC_PARAM_OK, Req(MC_PARAM_OP_SAVE, 0).status) << "unchanged: no token";
    EXPECT_TRUE(boot_busy()) << "one token spent";
    for (uint32_t k = 0; k + 1u < MC_PARAM_SAVE_PERIOD_S * 1000u; ++k) {
        mc_can_cmd_step(&c);
    }
    EXPECT_TRUE(boot_busy()) << "1 ms before the refill";
    mc_can_cmd_step(&c);
    EXPECT_FALSE(boot_busy()) << "full again";
    EXPECT_EQ(4, seen.calls);
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
    // a SAVE of the unchanged set writes nothing and the set is stored
    EXPECT_EQ(MC_PARAM_OK, Req(MC_PARAM_OP_SAVE, 0).status);
    ASSERT_TRUE(mc_telemetry_values(MC_TM_HEARTBEAT, &src, v));
    EXPECT_EQ(static_cast<float>(MC_CAN_VAL_CFG_STATUS_STORED), v[MC_CAN_HEARTBEAT_CFG_STATUS]);
    EXPECT_EQ(1u, srv.saves_skipped);
    // a SAVE of a changed set the flash refuses: the heartbeat says so
    EXPECT_EQ(MC_PARAM_OK, Req(MC_PARAM_OP_WRITE, MC_PARAM_ID_I_MAX_A, Bits(7.5f)).status);
    EXPECT_EQ(MC_PARAM_OK, Req(MC_PARAM_OP_APPLY, 0).status);
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
