// The anticogging feed-forward in the drive (mc_drive_attach_cog,
// mc_drive_cfg_t.anticogging, mc_drive_ctrl_t.cogging_ff): added once, to
// the q reference of a speed or position law giving current references, at
// the encoder's mechanical angle, before the current limit; nowhere else.
// The law is a stub answering fixed references.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "app_test_fixture.h"

namespace apptest
{
namespace
{

constexpr double kPi = 3.14159265358979323846;

struct FixedLaw {
    mc_drive_out_t out{};
};

uint32_t fixed_fast(void *ctx, const mc_drive_meas_t *, mc_drive_out_t *out)
{
    *out = static_cast<FixedLaw *>(ctx)->out;
    return 0u;
}

class DriveCogFf : public AppDrive
{
  protected:
    void SetUp() override
    {
        AppDrive::SetUp();
        // 0.5 cos(theta) + 0.25 sin(3 theta) [A] at the map's bins
        std::vector<float> v(MC_COG_N);
        for (uint32_t k = 0; k < MC_COG_N; ++k) {
            const double th = 2.0 * kPi * k / MC_COG_N;
            v[k] = static_cast<float>(0.5 * std::cos(th) + 0.25 * std::sin(3.0 * th));
        }
        mc_cog_ident_t id{};
        id.enc_cpr = fcfg.encoder_counts_per_rev;
        id.pole_pairs = kPolePairs;
        id.enc_offset_rad = kOffset;
        ASSERT_EQ(MC_COG_ST_OK, mc_cog_build(&map, v.data(), MC_COG_N, &id, 10.0f, 0u));
        ASSERT_EQ(MC_COG_ST_OK, mc_cog_build(&map1, v.data(), MC_COG_N, &id, 10.0f, 1u));
        law.out.iq_ref_a = 5.0f;
        law.out.theta_e_rad = kOffset;
        law.out.rotor_frame = true;
        ctrl = mc_drive_ctrl_t{};
        ctrl.outputs = MC_DRIVE_OUT_CURRENT;
        ctrl.needs_encoder = true;
        ctrl.fast = fixed_fast;
        ctrl.ctx = &law;
        ctrl.cogging_ff = true;
        cfg.anticogging = true;
    }

    // Init, the law (and the map) attached, CTRL, the rotor at count, one
    // fast step.
    void RunAt(uint32_t count, bool attach_map = true)
    {
        InitDrive();
        ASSERT_EQ(0, mc_drive_attach_ctrl(&d, &ctrl));
        ASSERT_EQ(0, mc_drive_attach_cog(&d, attach_map ? &map : nullptr));
        ASSERT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_CTRL));
        Step(count);
    }

    void Step(uint32_t count)
    {
        ASSERT_EQ(0, mc_hal_fake_encoder_set(&fake, count, MC_HAL_ENCODER_FLAG_VALID));
        GoodSample();
        (void)mc_drive_fast_step(&d);
        ASSERT_EQ(MC_DRIVE_FAULT_NONE, d.faults);
    }

    mc_cog_map_t map{};  /**< every order kept (0): the bins */
    mc_cog_map_t map1{}; /**< order 1, its eight multiples kept: the series */
    FixedLaw law;
    mc_drive_ctrl_t ctrl{};
};

} // namespace

// At count 0 (theta_m 0) the map gives 0.5 A, so the q reference is 5.5 A;
// one count on, the advanced lookup at that angle (exact). The
// analytic value within q15's half LSB (0.75 A full scale / 65534) and
// the interpolation bound (2 pi 3 / 1024)^2 / 8 0.25 A + (2 pi / 1024)^2 /
// 8 0.5 A (1.1e-5 A): 3e-5 A.
TEST_F(DriveCogFf, AddedToTheLawsQReferenceAtTheMechanicalAngle)
{
    RunAt(0u);
    EXPECT_EQ(MC_DRIVE_MODE_CTRL, d.mode);
    EXPECT_NEAR(d.tm.cog_ff_a, 0.5f, 3e-5f);
    EXPECT_EQ(d.tm.iq_ref_a, 5.0f + d.tm.cog_ff_a);
    EXPECT_EQ(d.tm.id_ref_a, 0.0f); // d untouched
    Step(1u);
    // One count on, the tracking loop's speed is not 0: the drive asks for
    // the map one period ahead plus 1 / bandwidth times its rate of change
    // 1.5 periods ahead (mc_cog_loop_t; mc_cog_ff_adv_a: the same call,
    // exact: this map keeps every order, so the bins); the current it asks
    // to flow is the map there, within the bound above.
    const float w = d.tm.omega_m_rad_s;
    const mc_cog_loop_t lp = {d.cfg.foc.dt_s, 1.5f * d.cfg.foc.dt_s,
                              d.cfg.foc.lq_h / d.foc.pi_q.kp};
    float i_a = 0.0f;
    EXPECT_EQ(d.tm.cog_ff_a, mc_cog_ff_adv_a(&map, d.tm.theta_m_rad, w, &lp, &i_a));
    const double th =
        2.0 * kPi / fcfg.encoder_counts_per_rev + static_cast<double>(w * lp.lead_i_s);
    EXPECT_NEAR(i_a, 0.5 * std::cos(th) + 0.25 * std::sin(3.0 * th), 3e-5);
    EXPECT_EQ(d.tm.iq_ref_a, 5.0f + d.tm.cog_ff_a);
}

// A map with an order goes through its series (mc_cog_series_ff_adv_a),
// derived when it is attached: the same call on a series derived here,
// bit for bit; orders 1 and 3 are kept, so the current at theta_m 0 is the
// map's 0.5 A within the projection's 1e-4 A (test_drive_cog.cpp). The
// series follows the map attached: a rebuilt map (another CRC) attached at
// the same address gets its own series; re-attaching the same one leaves
// it as it was.
TEST_F(DriveCogFf, AMapWithAnOrderGoesThroughItsSeries)
{
    InitDrive();
    ASSERT_EQ(0, mc_drive_attach_ctrl(&d, &ctrl));
    ASSERT_EQ(0, mc_drive_attach_cog(&d, &map1));
    EXPECT_EQ(d.cog_ser.order, 1u);
    EXPECT_EQ(d.cog_ser.count, MC_COG_KEEP_MAX);
    ASSERT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_CTRL));
    Step(0u);
    EXPECT_NEAR(d.tm.cog_ff_a, 0.5f, 1e-4f);
    Step(1u);
    mc_cog_series_t ser{};
    mc_cog_series_init(&ser, &map1);
    const mc_cog_loop_t lp = {d.cfg.foc.dt_s, 1.5f * d.cfg.foc.dt_s,
                              d.cfg.foc.lq_h / d.foc.pi_q.kp};
    float i_a = 0.0f;
    EXPECT_EQ(d.tm.cog_ff_a,
              mc_cog_series_ff_adv_a(&ser, d.tm.theta_m_rad, d.tm.omega_m_rad_s, &lp, &i_a));
    // the same map again: nothing derived (the series' words untouched)
    d.cog_ser.a[0] = 123.0f;
    ASSERT_EQ(0, mc_drive_attach_cog(&d, &map1));
    EXPECT_EQ(d.cog_ser.a[0], 123.0f);
    // rebuilt in place with order 0: another CRC, no series (the bins)
    map1 = map;
    ASSERT_EQ(0, mc_drive_attach_cog(&d, &map1));
    EXPECT_EQ(d.cog_ser.count, 0u);
}

// Nothing added: anticogging off (and switched on at run time through the
// runtime limits), no map, a law without cogging_ff (commissioning, the
// angle finders), CURRENT mode: the q reference is the law's / the set one,
// bit for bit.
TEST_F(DriveCogFf, OnlyWithTheFlagAMapAndASpeedOrPositionLaw)
{
    cfg.anticogging = false;
    RunAt(0u);
    EXPECT_EQ(d.tm.cog_ff_a, 0.0f);
    EXPECT_EQ(d.tm.iq_ref_a, 5.0f);
    mc_drive_cfg_t on = d.cfg;
    on.anticogging = true;
    mc_drive_set_runtime_limits(&d, &on);
    Step(0u);
    EXPECT_NEAR(d.tm.iq_ref_a, 5.5f, 3e-5f);
    on.anticogging = false;
    mc_drive_set_runtime_limits(&d, &on);
    Step(0u);
    EXPECT_EQ(d.tm.iq_ref_a, 5.0f);

    cfg.anticogging = true;
    RunAt(0u, false);
    EXPECT_EQ(d.tm.iq_ref_a, 5.0f);

    ctrl.cogging_ff = false;
    RunAt(0u);
    EXPECT_EQ(d.tm.cog_ff_a, 0.0f);
    EXPECT_EQ(d.tm.iq_ref_a, 5.0f);

    InitDrive();
    ASSERT_EQ(0, mc_drive_attach_cog(&d, &map));
    ASSERT_EQ(0, mc_drive_set_current_ref(&d, 0.0f, 5.0f));
    ASSERT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_CURRENT));
    Step(0u);
    EXPECT_EQ(MC_DRIVE_MODE_CURRENT, d.mode);
    EXPECT_EQ(d.tm.iq_ref_a, 5.0f);
}

// The sum is clamped to the current limit in force, as every reference:
// the law at the limit less 0.1 A plus 0.5 A is the limit; at minus the
// limit the feed-forward pulls it inside (-20 + 0.5 A).
TEST_F(DriveCogFf, TheSumStaysWithinTheCurrentLimit)
{
    law.out.iq_ref_a = kIMax - 0.1f;
    RunAt(0u);
    EXPECT_EQ(d.tm.iq_ref_a, kIMax);
    law.out.iq_ref_a = -kIMax;
    Step(0u);
    EXPECT_NEAR(d.tm.iq_ref_a, -kIMax + 0.5f, 3e-5f);
}

// A map needs the encoder its angle comes from.
TEST_F(DriveCogFf, NoMapWithoutAnEncoder)
{
    InitDrive();
    mc_hal_t no_enc = *hal;
    no_enc.encoder = nullptr;
    d.hal = &no_enc;
    EXPECT_EQ(-ENODEV, mc_drive_attach_cog(&d, &map));
    EXPECT_EQ(nullptr, d.cog);
    EXPECT_EQ(0, mc_drive_attach_cog(&d, nullptr));
}

} // namespace apptest

namespace apptest
{

// A map of every order (the bins: no series) fades as a whole at its RMS
// order (mc_cog_map_order_rms, derived when attached): the drive turning
// at the speed where that order is 6 times the current loop's bandwidth
// adds half the bins' feed-forward, at 9 times none (the rotor's counts
// fed at a constant speed until the tracking loop holds it; each compared
// with the same lookup and gain on the step's own angle and speed: equal
// to float rounding, 1e-6 A).
TEST_F(DriveCogFf, AMapOfEveryOrderFadesAtItsRmsOrder)
{
    std::vector<float> v(MC_COG_N);
    for (uint32_t k = 0; k < MC_COG_N; ++k) {
        v[k] = static_cast<float>(0.3 * std::sin(300.0 * 2.0 * kPi * k / MC_COG_N));
    }
    mc_cog_ident_t id{};
    id.enc_cpr = fcfg.encoder_counts_per_rev;
    id.pole_pairs = kPolePairs;
    id.enc_offset_rad = kOffset;
    mc_cog_map_t high{};
    ASSERT_EQ(MC_COG_ST_OK, mc_cog_build(&high, v.data(), MC_COG_N, &id, 10.0f, 0u));
    for (const double x_want : {6.0, 9.0}) {
        InitDrive();
        ASSERT_EQ(0, mc_drive_attach_ctrl(&d, &ctrl));
        ASSERT_EQ(0, mc_drive_attach_cog(&d, &high));
        EXPECT_EQ(d.cog_ser.count, 0u);
        EXPECT_EQ(d.cog_ord_rms, mc_cog_map_order_rms(&high));
        ASSERT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_CTRL));
        const mc_cog_loop_t lp = {d.cfg.foc.dt_s, 1.5f * d.cfg.foc.dt_s,
                                  d.cfg.foc.lq_h / d.foc.pi_q.kp};
        const double w = x_want / (static_cast<double>(lp.tau_s) * d.cog_ord_rms);
        const double cpr = fcfg.encoder_counts_per_rev;
        for (uint32_t k = 0; k < 4000u; ++k) {
            const double turns = w * kDt * k / (2.0 * kPi);
            Step(static_cast<uint32_t>(std::floor((turns - std::floor(turns)) * cpr)));
        }
        const float x = std::fabs(d.tm.omega_m_rad_s) * lp.tau_s * d.cog_ord_rms;
        EXPECT_NEAR(x, x_want, 0.05 * x_want); // the tracking loop's count ripple
        const float g = mc_cog_fade_gain(x);
        float i_a = 0.0f;
        const float want =
            g * mc_cog_ff_adv_a(&high, d.tm.theta_m_rad, d.tm.omega_m_rad_s, &lp, &i_a);
        EXPECT_NEAR(d.tm.cog_ff_a, want, 1e-6f) << x_want;
        if (x_want > MC_COG_FADE_END) {
            EXPECT_EQ(d.tm.cog_ff_a, 0.0f);
        } else {
            EXPECT_GT(g, 0.3f);
            EXPECT_LT(g, 0.7f);
        }
    }
}

} // namespace apptest
