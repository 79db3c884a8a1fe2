// The rotor angle at enable in the application (firmware/app/app/mc_app,
// angle_ref / angle_find_at_enable of the parameter table) on the simulated
// board (hal_host::PmsmBoard: the table's default motor, 4 pole pairs, an
// incremental encoder of 8192 counts that counts from 0 at the rotor's
// power-up angle theta_m0, an index mark where asked), driven over CAN as
// a host drives it (SET_CONTROL_MODE, SET_ENABLE, SET_SPEED_REF, the
// keep-alive) through hal_host::app_period, the image's interrupt sequence.
// The stored encoder_offset_rad is the table's 0: after a power-up at
// theta_m0 the true offset is p theta_m0, so the stored one is stale.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <deque>
#include <memory>
#include <random>
#include <vector>

#include "hal_host/app_rig.hpp"
#include "hal_host/pmsm_board.hpp"
extern "C" {
#include "mc_app.h"
#include "mc_can_dbc.h"
#include "mc_can_proto.h"
}

namespace
{

constexpr double kPi = 3.14159265358979323846;

// A CAN bus of one host: frames the host sends wait in rx, the drive's in tx.
struct Bus {
    std::deque<mc_hal_can_frame_t> rx;
    std::vector<mc_hal_can_frame_t> tx;
    mc_hal_can_t can{};
};

int bus_send(void *ctx, const mc_hal_can_frame_t *f)
{
    static_cast<Bus *>(ctx)->tx.push_back(*f);
    return 0;
}

int bus_receive(void *ctx, mc_hal_can_frame_t *f)
{
    auto *b = static_cast<Bus *>(ctx);
    if (b->rx.empty()) {
        return -EAGAIN;
    }
    *f = b->rx.front();
    b->rx.pop_front();
    return 0;
}

int bus_status(void *, mc_hal_can_status_t *s)
{
    *s = mc_hal_can_status_t{};
    return 0;
}

const mc_hal_can_ops_t kBusOps = {bus_send, bus_receive, bus_status};

struct Boot {
    double theta_m0_rad = 0.0;
    uint32_t angle_ref = MC_DRIVE_ANGLE_REF_STORED;
    uint32_t find_at_enable = 0u;
    double load_nm = 0.0;
    bool index = false;
    double index_at_rad = 1.0;
    double offset_rad = 0.0; // the stored encoder_offset_rad
};

class AngleFind : public ::testing::Test
{
  protected:
    void Start(const Boot &b)
    {
        p = mc_params_default;
        p.angle_ref = b.angle_ref;
        p.angle_find_at_enable = b.find_at_enable;
        p.encoder_offset_rad = static_cast<float>(b.offset_rad);
        p.tm_currents_hz = 0u; // the heartbeat is what the tests read
        p.tm_voltages_hz = 0u;
        p.tm_speed_hz = 0u;
        ASSERT_EQ(MC_PARAMS_OK, mc_params_validate(&p));
        hal_host::PmsmBoardConfig bc;
        bc.motor.R_ohm = p.r_ohm;
        bc.motor.Ld_h = p.ld_h;
        bc.motor.Lq_h = p.lq_h;
        bc.motor.flux_wb = p.flux_wb;
        bc.motor.pole_pairs = static_cast<int>(p.pole_pairs);
        bc.motor.J_kgm2 = p.j_kgm2;
        bc.motor.B_nms_rad = 1.0e-4; // a little friction the table does not know
        bc.motor.load = mcsim::load_constant(b.load_nm);
        bc.inverter.t_pwm_s = 1.0 / p.pwm_hz;
        bc.vbus_v = p.vbus_v;
        bc.current_sensor.full_scale_a = p.i_sense_max_a;
        bc.vbus_sensor.full_scale_v = 100.0;
        bc.encoder.counts_per_rev = static_cast<int32_t>(p.encoder_cpr);
        bc.encoder.has_index = b.index;
        bc.encoder.index_angle_rad = b.index_at_rad;
        bc.theta_m0_rad = b.theta_m0_rad;
        board = std::make_unique<hal_host::PmsmBoard>(bc);
        bus.can.ops = &kBusOps;
        bus.can.ctx = &bus;
        mc_app_cfg_t acfg{};
        acfg.defaults = &p;
        acfg.tm_budget_frac = 0.5f;
        acfg.laws_from_params = true;
        app = std::make_unique<mc_app_t>();
        ASSERT_EQ(MC_APP_CFG_OK, mc_app_boot(app.get(), &acfg));
        ASSERT_EQ(MC_APP_CFG_OK, mc_app_start(app.get(), &drive, board->hal(), &bus.can, true));
        ASSERT_EQ(app->laws.error, 0u);
    }

    void Send(uint32_t msg, std::vector<float> v)
    {
        mc_hal_can_frame_t f{};
        v.resize(8u, 0.0f);
        ASSERT_EQ(MC_CAN_ERR_NONE, mc_can_proto_pack(msg, p.can_node_id, v.data(), 8u, &f));
        bus.rx.push_back(f);
    }

    // Run for t_s with the host's keep-alive every 50 ms (timeout 0.5 s).
    void Run(double t_s)
    {
        const long n = std::lround(t_s * p.pwm_hz);
        const long hb_every = std::lround(0.05 * p.pwm_hz);
        for (long k = 0; k < n; ++k) {
            if ((k % hb_every) == 0) {
                Send(MC_CAN_MSG_HOST_HEARTBEAT, {static_cast<float>(hb++ & 0xFFu)});
            }
            (void)hal_host::app_period(*board, *app);
        }
    }

    // The last HEARTBEAT the drive sent, decoded.
    std::vector<float> LastHeartbeat() const
    {
        std::vector<float> v(MC_CAN_HEARTBEAT_NSIG, -1.0f);
        for (auto it = bus.tx.rbegin(); it != bus.tx.rend(); ++it) {
            uint32_t msg = 0u;
            if (mc_can_proto_unpack(&*it, &msg, v.data(), MC_CAN_HEARTBEAT_NSIG) ==
                    MC_CAN_ERR_NONE &&
                msg == MC_CAN_MSG_HEARTBEAT) {
                return v;
            }
        }
        ADD_FAILURE() << "no HEARTBEAT";
        return v;
    }

    // The error code of the last CMD_ERROR the drive sent (0: none).
    float LastCmdError() const
    {
        for (auto it = bus.tx.rbegin(); it != bus.tx.rend(); ++it) {
            float v[8] = {};
            uint32_t msg = 0u;
            if (mc_can_proto_unpack(&*it, &msg, v, 8u) == MC_CAN_ERR_NONE &&
                msg == MC_CAN_MSG_CMD_ERROR) {
                return v[MC_CAN_CMD_ERROR_ERROR];
            }
        }
        return 0.0f;
    }

    // The angle parameter the host reads (PARAM_REQ READ through the service).
    uint32_t ReadParam(uint32_t id)
    {
        uint32_t v = 0u;
        EXPECT_EQ(MC_PARAM_OK, mc_param_srv_request(&app->srv, MC_PARAM_OP_READ, id, &v));
        return v;
    }

    double OmegaM() const
    {
        return board->state()(2);
    }
    double ThetaM() const
    {
        return board->state()(3);
    }

    mc_params_t p{};
    std::unique_ptr<hal_host::PmsmBoard> board;
    std::unique_ptr<mc_app_t> app;
    mc_drive_t drive{};
    Bus bus;
    uint32_t hb = 0u;
};

// (a) angle_ref align, find at enable: from 8 power-up angles (fixed seed)
// an enable in SPEED with +30 rad/s (then -30 rad/s at the 4 odd ones)
// aligns, and the sensored speed law then turns the rotor the commanded
// way: after 1.5 s the plant's speed is within 5 % of the reference (the
// speed loop settles within about 0.3 s at the derived 50 rad/s crossover;
// 5 % covers the ripple of the encoder's 8192 counts through the tracking
// loop), with no fault. Without the alignment the stale offset (p theta_m0
// wrong) turns it the wrong way or not at all: the speed check fails.
TEST_F(AngleFind, AlignThenSpeedFromEightPowerUpAngles)
{
    std::mt19937_64 rng(20261129u);
    std::uniform_real_distribution<double> angle(0.3, 2.0 * kPi - 0.3);
    for (int k = 0; k < 8; ++k) {
        const double th0 = angle(rng);
        const float w = (k % 2 == 0) ? 30.0f : -30.0f;
        SCOPED_TRACE(testing::Message() << "power-up " << k << " theta_m0 " << th0);
        Boot b;
        b.theta_m0_rad = th0;
        b.angle_ref = MC_DRIVE_ANGLE_REF_ALIGN;
        b.find_at_enable = 1u;
        Start(b);
        ASSERT_EQ(mc_drive_angle_state(&drive), MC_DRIVE_ANGLE_NEED_ALIGN);
        Send(MC_CAN_MSG_SET_CONTROL_MODE, {static_cast<float>(MC_CAN_CTRL_SPEED)});
        Send(MC_CAN_MSG_SET_ENABLE, {1.0f});
        Send(MC_CAN_MSG_SET_SPEED_REF, {w}); // during the find: kept
        Run(0.01);
        EXPECT_TRUE(app->cmd.enabled);
        EXPECT_TRUE(app->cmd.angle_finding);
        EXPECT_EQ(drive.ctrl, mc_ctrl_align_ops(&app->laws.align));
        Run(4.0);
        ASSERT_EQ(mc_drive_angle_state(&drive), MC_DRIVE_ANGLE_KNOWN);
        // the offset the alignment measured: p theta_m0 within 0.02 rad el.
        // (test_align_sil's tolerance: 4 counts of rest band and the count)
        const double want = std::fmod(p.pole_pairs * th0, 2.0 * kPi);
        double err = drive.cfg.encoder_offset_rad - want;
        err -= 2.0 * kPi * std::round(err / (2.0 * kPi));
        EXPECT_LE(std::fabs(err), 0.02);
        EXPECT_FALSE(app->cmd.angle_finding);
        EXPECT_EQ(drive.ctrl, mc_ctrl_speed_ops(&app->laws.spd));
        EXPECT_EQ(drive.mode, MC_DRIVE_MODE_CTRL);
        EXPECT_EQ(drive.faults, 0u);
        Run(1.5);
        EXPECT_EQ(drive.faults, 0u);
        EXPECT_NEAR(OmegaM(), w, 0.05 * std::fabs(w));
        EXPECT_EQ(app->angle_error, 0u);
    }
}

// (b) align without find at enable: SET_ENABLE in SPEED is refused
// ANGLE_UNKNOWN (CMD_ERROR, HEARTBEAT.last_error), the bridge stays off and
// the rotor where it was; CURRENT the same.
TEST_F(AngleFind, WithoutFindAtEnableRefusedWithItsReason)
{
    Boot b;
    b.theta_m0_rad = 2.0;
    b.angle_ref = MC_DRIVE_ANGLE_REF_ALIGN;
    Start(b);
    for (const uint32_t mode : {MC_CAN_CTRL_SPEED, MC_CAN_CTRL_CURRENT}) {
        SCOPED_TRACE(mode);
        bus.tx.clear();
        Send(MC_CAN_MSG_SET_CONTROL_MODE, {static_cast<float>(mode)});
        Send(MC_CAN_MSG_SET_ENABLE, {1.0f});
        Run(0.2);
        EXPECT_FALSE(app->cmd.enabled);
        EXPECT_FALSE(board->pwm_enabled());
        EXPECT_EQ(drive.mode, MC_DRIVE_MODE_IDLE);
        EXPECT_EQ(LastCmdError(), static_cast<float>(MC_CAN_ERR_ANGLE_UNKNOWN));
        const std::vector<float> hbv = LastHeartbeat();
        EXPECT_EQ(hbv[MC_CAN_HEARTBEAT_LAST_ERROR], static_cast<float>(MC_CAN_ERR_ANGLE_UNKNOWN));
        EXPECT_EQ(hbv[MC_CAN_HEARTBEAT_ENABLED], 0.0f);
        EXPECT_EQ(ThetaM(), 2.0); // nothing moved it (exact: no torque, at rest)
    }
}

// (c) a load the alignment cannot hold (1.5 x the vector's k_t i = 0.99 N m
// at the derived 1.5 A): the rotor slips, the drive faults in that step
// (bridge off), the run ends with stop_reason ANGLE_FIND in the HEARTBEAT
// and the readonly parameter angle_error names SLIP; nothing left enabled.
TEST_F(AngleFind, AlignmentUnderALoadItCannotHoldNamesWhy)
{
    Boot b;
    b.theta_m0_rad = 1.3;
    b.angle_ref = MC_DRIVE_ANGLE_REF_ALIGN;
    b.find_at_enable = 1u;
    b.load_nm = 1.5 * 1.5 * 0.66;
    Start(b);
    Send(MC_CAN_MSG_SET_CONTROL_MODE, {static_cast<float>(MC_CAN_CTRL_SPEED)});
    Send(MC_CAN_MSG_SET_ENABLE, {1.0f});
    Run(3.0);
    EXPECT_FALSE(app->cmd.enabled);
    EXPECT_FALSE(board->pwm_enabled());
    EXPECT_EQ(drive.mode, MC_DRIVE_MODE_FAULT);
    EXPECT_NE(drive.faults & MC_DRIVE_FAULT_CONTROL, 0u);
    EXPECT_EQ(mc_drive_angle_state(&drive), MC_DRIVE_ANGLE_NEED_ALIGN);
    EXPECT_EQ(app->cmd.stop_reason, MC_CAN_STOP_ANGLE_FIND);
    EXPECT_EQ(LastHeartbeat()[MC_CAN_HEARTBEAT_STOP_REASON],
              static_cast<float>(MC_CAN_STOP_ANGLE_FIND));
    EXPECT_EQ(ReadParam(MC_PARAM_ID_ANGLE_ERROR), MC_CTRL_ALIGN_ERR_SLIP);
    // the speed law is back in its slot for the next run
    EXPECT_EQ(drive.ctrl, mc_ctrl_speed_ops(&app->laws.spd));
}

// (d) angle_ref index with the plant's index mark at 1.0 rad: the search
// runs at the enable, the index makes the angle known, then the speed law
// turns the rotor at +30 rad/s within 5 % (as in (a)) from three power-up
// angles.
TEST_F(AngleFind, IndexSearchThenSpeed)
{
    for (const double th0 : {0.2, 2.5, 4.4}) {
        SCOPED_TRACE(th0);
        Boot b;
        b.theta_m0_rad = th0;
        b.angle_ref = MC_DRIVE_ANGLE_REF_INDEX;
        b.find_at_enable = 1u;
        b.index = true;
        b.index_at_rad = 1.0;
        // the offset stored relative to the index (as commissioning after an
        // index search stores it): p times the mark's angle, the electrical
        // angle of the d axis at the index's count 0
        b.offset_rad = std::fmod(4.0 * b.index_at_rad, 2.0 * kPi);
        Start(b);
        ASSERT_EQ(mc_drive_angle_state(&drive), MC_DRIVE_ANGLE_NEED_INDEX);
        Send(MC_CAN_MSG_SET_CONTROL_MODE, {static_cast<float>(MC_CAN_CTRL_SPEED)});
        Send(MC_CAN_MSG_SET_ENABLE, {1.0f});
        Run(0.01);
        EXPECT_EQ(drive.ctrl, mc_ctrl_idx_ops(&app->laws.idx));
        Run(3.0);
        ASSERT_EQ(mc_drive_angle_state(&drive), MC_DRIVE_ANGLE_KNOWN);
        EXPECT_EQ(drive.ctrl, mc_ctrl_speed_ops(&app->laws.spd));
        Send(MC_CAN_MSG_SET_SPEED_REF, {30.0f});
        Run(1.5);
        EXPECT_EQ(drive.faults, 0u);
        EXPECT_NEAR(OmegaM(), 30.0, 0.05 * 30.0);
    }
}

// (e) angle_ref index on an encoder whose index never comes (no mark, or
// its EXTI line broken): the search at the enable turns travel_max (the
// table's 1.25 turn) one way, then the other, and fails by name: the
// bridge off, stop_reason ANGLE_FIND in the HEARTBEAT, the readonly
// angle_error NOT_FOUND, the angle still unknown (the stored offset never
// used). The motion under the bridge stays within the bound plus the
// rotor's coasting past it when the vector turns back (0.05 rad: at the
// search's 10 rad/s with the vector's damped spring, as
// CtrlIdx.NotFoundAfterBothDirections); sampled every 10 ms while the
// bridge is on (the search ends with the bridge off at 10 rad/s, and
// the frictionless rotor then coasts, which is not the search's travel),
// so the far end of each leg within 0.1 rad (10 ms at 10 rad/s).
// Timing: 2 x 7.85 rad at 10 rad/s and the ramps: under 2 s; Run(4.0).
TEST_F(AngleFind, IndexSearchWithoutTheIndexFailsByName)
{
    Boot b;
    b.theta_m0_rad = 0.9;
    b.angle_ref = MC_DRIVE_ANGLE_REF_INDEX;
    b.find_at_enable = 1u;
    b.index = false;
    Start(b);
    ASSERT_EQ(mc_drive_angle_state(&drive), MC_DRIVE_ANGLE_NEED_INDEX);
    Send(MC_CAN_MSG_SET_CONTROL_MODE, {static_cast<float>(MC_CAN_CTRL_SPEED)});
    Send(MC_CAN_MSG_SET_ENABLE, {1.0f});
    Run(0.01);
    ASSERT_EQ(drive.ctrl, mc_ctrl_idx_ops(&app->laws.idx));
    const double travel_max = 1.25 * 2.0 * kPi;
    double th_lo = ThetaM(), th_hi = ThetaM();
    const long n = std::lround(4.0 / 0.01);
    for (long k = 0; k < n; ++k) {
        Run(0.01);
        if (board->pwm_enabled()) { // the search's motion, not the coasting after it
            th_lo = std::min(th_lo, ThetaM());
            th_hi = std::max(th_hi, ThetaM());
        }
    }
    EXPECT_FALSE(app->cmd.enabled);
    EXPECT_FALSE(board->pwm_enabled());
    EXPECT_EQ(drive.mode, MC_DRIVE_MODE_FAULT);
    EXPECT_NE(drive.faults & MC_DRIVE_FAULT_CONTROL, 0u);
    EXPECT_EQ(mc_drive_angle_state(&drive), MC_DRIVE_ANGLE_NEED_INDEX);
    EXPECT_EQ(app->cmd.stop_reason, MC_CAN_STOP_ANGLE_FIND);
    EXPECT_EQ(LastHeartbeat()[MC_CAN_HEARTBEAT_STOP_REASON],
              static_cast<float>(MC_CAN_STOP_ANGLE_FIND));
    EXPECT_EQ(ReadParam(MC_PARAM_ID_ANGLE_ERROR), MC_CTRL_ALIGN_ERR_NOT_FOUND);
    // both directions, each within its bound
    EXPECT_LE(th_hi - b.theta_m0_rad, travel_max + 0.05);
    EXPECT_GE(th_hi - b.theta_m0_rad, travel_max - 0.1);
    EXPECT_LE(b.theta_m0_rad - th_lo, travel_max + 0.05);
    EXPECT_GE(b.theta_m0_rad - th_lo, travel_max - 0.1);
    EXPECT_EQ(drive.ctrl, mc_ctrl_speed_ops(&app->laws.spd)); // back in its slot
}

// POSITION after an alignment: a SET_POSITION_REF during the find is
// refused MODE (its frame is set at the hand-over); after it the position
// law holds the rotor where the find left it and moves it by the 3 rad the
// host asks, in the telemetry's multi-turn frame: within 0.05 rad (65
// encoder counts; the cascade settles to a few counts on the frictionless
// load, the margin is for the trajectory's last millisecond).
TEST_F(AngleFind, AlignThenPosition)
{
    Boot b;
    b.theta_m0_rad = 4.1;
    b.angle_ref = MC_DRIVE_ANGLE_REF_ALIGN;
    b.find_at_enable = 1u;
    Start(b);
    Send(MC_CAN_MSG_SET_CONTROL_MODE, {static_cast<float>(MC_CAN_CTRL_POSITION)});
    Send(MC_CAN_MSG_SET_ENABLE, {1.0f});
    Run(0.01);
    ASSERT_TRUE(app->cmd.angle_finding);
    Send(MC_CAN_MSG_SET_POSITION_REF, {1.0f});
    Run(0.01);
    EXPECT_EQ(LastCmdError(), static_cast<float>(MC_CAN_ERR_MODE));
    Run(4.0);
    ASSERT_EQ(mc_drive_angle_state(&drive), MC_DRIVE_ANGLE_KNOWN);
    ASSERT_EQ(drive.ctrl, mc_ctrl_pos_ops(&app->laws.pos));
    const double th_plant0 = ThetaM();
    const float th_tm0 = mc_telemetry_theta_multi_rad(&app->tm, &drive);
    Send(MC_CAN_MSG_SET_POSITION_REF, {th_tm0 + 3.0f});
    Run(3.0);
    EXPECT_EQ(drive.faults, 0u);
    EXPECT_TRUE(app->cmd.enabled);
    EXPECT_NEAR(ThetaM() - th_plant0, 3.0, 0.05);
}

// The host falls silent during a find: the run ends at once with
// CMD_TIMEOUT (the find's bounded current needs no controlled stop), the
// bridge off, the angle still unknown.
TEST_F(AngleFind, KeepAliveLostDuringTheFind)
{
    Boot b;
    b.theta_m0_rad = 0.7;
    b.angle_ref = MC_DRIVE_ANGLE_REF_ALIGN;
    b.find_at_enable = 1u;
    Start(b);
    Send(MC_CAN_MSG_SET_CONTROL_MODE, {static_cast<float>(MC_CAN_CTRL_SPEED)});
    Send(MC_CAN_MSG_SET_ENABLE, {1.0f});
    const long n = std::lround(0.7 * p.pwm_hz); // past the 0.5 s timeout, no keep-alive
    for (long k = 0; k < n; ++k) {
        (void)hal_host::app_period(*board, *app);
    }
    EXPECT_FALSE(app->cmd.enabled);
    EXPECT_FALSE(app->cmd.angle_finding);
    EXPECT_FALSE(board->pwm_enabled());
    EXPECT_EQ(app->cmd.stop_reason, MC_CAN_STOP_CMD_TIMEOUT);
    EXPECT_EQ(mc_drive_angle_state(&drive), MC_DRIVE_ANGLE_NEED_ALIGN);
    EXPECT_EQ(drive.ctrl, mc_ctrl_speed_ops(&app->laws.spd)); // back in its slot
}

// The parameters: a reference to find without an encoder is refused by
// name; out-of-range values by the table.
TEST(AngleParams, RefusedWithoutAnEncoder)
{
    mc_params_t p = mc_params_default;
    p.encoder_cpr = 0u;
    p.angle_ref = MC_DRIVE_ANGLE_REF_ALIGN;
    EXPECT_EQ(mc_params_validate(&p) & MC_PARAMS_ERR_ANGLE_REF, MC_PARAMS_ERR_ANGLE_REF);
    p.angle_ref = MC_DRIVE_ANGLE_REF_STORED;
    p.angle_find_at_enable = 1u;
    EXPECT_EQ(mc_params_validate(&p) & MC_PARAMS_ERR_ANGLE_REF, MC_PARAMS_ERR_ANGLE_REF);
    p = mc_params_default;
    p.angle_ref = 3u;
    EXPECT_EQ(mc_params_validate(&p), MC_PARAMS_ERR_RANGE);
    p = mc_params_default;
    p.angle_ref = MC_DRIVE_ANGLE_REF_INDEX;
    mc_drive_cfg_t dc{};
    ASSERT_EQ(mc_params_to_drive_cfg(&p, &dc), MC_PARAMS_OK);
    EXPECT_EQ(dc.angle_ref, MC_DRIVE_ANGLE_REF_INDEX);
}

} // namespace
