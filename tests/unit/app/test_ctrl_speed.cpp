// The sensored speed law (firmware/app/ctrl/mc_ctrl_speed.h) stepped
// directly with hand-built measurements: the PI on the drive's speed plus
// the feed-forward of the drive's reference, the limit in force with
// clamping anti-windup, the tracking of the regenerative limit, and the
// refusals. Exact comparisons recompute the law's float expressions in the
// same order.
#include <gtest/gtest.h>

#include <cmath>

extern "C" {
#include "mc_ctrl_speed.h"
}

namespace
{

constexpr float kDt = 50e-6f;

mc_ctrl_speed_cfg_t Cfg()
{
    mc_ctrl_speed_cfg_t c{};
    c.kp_a_s_rad = 0.2f;
    c.ki_a_rad = 5.0f;
    c.dt_s = kDt;
    c.iq_max_a = 20.0f;
    c.kt_nm_a = 0.1f;
    c.j_kgm2 = 1e-3f;
    c.b_nm_s_rad = 1e-4f;
    c.pole_pairs = 7u;
    return c;
}

mc_drive_meas_t Meas(float w_ref, float a_ref, float w)
{
    mc_drive_meas_t m{};
    m.have_encoder = true;
    m.have_speed_ref = true;
    m.omega_ref_rad_s = w_ref;
    m.alpha_ref_rad_s2 = a_ref;
    m.omega_m_rad_s = w;
    m.theta_e_rad = 1.25f;
    m.i_max_a = 20.0f;
    m.regen_scale = 1.0f;
    m.dt_s = kDt;
    return m;
}

TEST(CtrlSpeed, PiPlusTheReferencesFeedForwardInTheRotorFrame)
{
    mc_ctrl_speed_t c{};
    const mc_ctrl_speed_cfg_t cfg = Cfg();
    ASSERT_EQ(0u, mc_ctrl_speed_init(&c, &cfg));
    const mc_drive_ctrl_t *ops = mc_ctrl_speed_ops(&c);
    EXPECT_EQ(MC_DRIVE_OUT_CURRENT, ops->outputs);
    EXPECT_TRUE(ops->needs_encoder);
    EXPECT_TRUE(ops->uses_speed_ref);
    mc_drive_out_t out{};
    const mc_drive_meas_t m = Meas(100.0f, 500.0f, 98.0f);
    ASSERT_EQ(0u, mc_ctrl_speed_fast(&c, &m, &out));
    const float e = 100.0f - 98.0f;
    const float ff = ((1e-3f * 500.0f) + (1e-4f * 100.0f)) / 0.1f;
    // the kernel's order (mc_pi.h): p + I + ff, I = ki dt e on the first step
    const float want = ((0.2f * e) + (5.0f * kDt * e)) + ff;
    EXPECT_NEAR(want, out.iq_ref_a, 1e-6f); // float rounding of a 5 A value
    EXPECT_EQ(ff, c.tm.iq_ff_a);
    EXPECT_EQ(0.0f, out.id_ref_a);
    EXPECT_EQ(1.25f, out.theta_e_rad);
    EXPECT_EQ(98.0f * 7.0f, out.omega_e_rad_s);
    EXPECT_TRUE(out.rotor_frame);
    EXPECT_FALSE(out.reframe);
}

// The drive's limit in force (lower than the configured one, as after a
// run-time APPLY of i_max_a): the output saturates there, the integrator
// stops there (clamping), so the output leaves saturation in the step the
// error reverses: the reference is never dropped, never wound up.
TEST(CtrlSpeed, SaturatesAtTheLimitInForceWithoutWindingUp)
{
    mc_ctrl_speed_t c{};
    const mc_ctrl_speed_cfg_t cfg = Cfg();
    ASSERT_EQ(0u, mc_ctrl_speed_init(&c, &cfg));
    mc_drive_out_t out{};
    mc_drive_meas_t m = Meas(300.0f, 0.0f, 0.0f);
    m.i_max_a = 6.0f;
    for (int k = 0; k < 20000; ++k) { // 1 s at the limit
        ASSERT_EQ(0u, mc_ctrl_speed_fast(&c, &m, &out));
        ASSERT_EQ(6.0f, out.iq_ref_a) << k;
    }
    EXPECT_EQ(20000u, c.tm.saturated);
    EXPECT_LE(c.pi.integ, 6.0f);
    // the rotor overshoots the reference by 1 rad/s: the output leaves the
    // limit at once (the integrator holds only what the output could use:
    // here p alone saturated, so nothing)
    m.omega_m_rad_s = 301.0f;
    ASSERT_EQ(0u, mc_ctrl_speed_fast(&c, &m, &out));
    EXPECT_LT(out.iq_ref_a, 1.0f);
    EXPECT_GT(out.iq_ref_a, -1.0f);
}

// The drive's regenerative limit scaled the last braking reference
// (regen_scale < 1): before each step the integrator undoes the increment
// that pushed against what was applied (mc_pi_f32_track), so it holds
// where it was while the bus cannot take more, instead of winding towards
// the current limit; braking resumes from there.
TEST(CtrlSpeed, TracksTheRegenerativeLimit)
{
    mc_ctrl_speed_t c{};
    const mc_ctrl_speed_cfg_t cfg = Cfg();
    ASSERT_EQ(0u, mc_ctrl_speed_init(&c, &cfg));
    mc_drive_out_t out{};
    mc_drive_meas_t m = Meas(0.0f, 0.0f, 10.0f); // braking: p = -2 A, the integrator winds
    for (int k = 0; k < 2000; ++k) {
        ASSERT_EQ(0u, mc_ctrl_speed_fast(&c, &m, &out));
    }
    const float i0 = c.pi.integ; // -5 A after 0.1 s at ki e = -50 A/s
    ASSERT_LT(i0, -4.0f);
    m.regen_scale = 0.25f;
    for (int k = 0; k < 2000; ++k) {
        m.iq_applied_a = 0.25f * out.iq_ref_a; // what the drive let through
        ASSERT_EQ(0u, mc_ctrl_speed_fast(&c, &m, &out));
    }
    EXPECT_EQ(2000u, c.tm.tracked);
    // held within one step's increment (ki dt e = 2.5 mA), where it would
    // have wound another 5 A
    EXPECT_NEAR(i0, c.pi.integ, 5.0f * kDt * 10.0f + 1e-6f);
}

TEST(CtrlSpeed, RefusalsAreNamed)
{
    mc_ctrl_speed_t c{};
    mc_ctrl_speed_cfg_t cfg = Cfg();
    EXPECT_EQ(MC_CTRL_SPEED_ERR_NULL, mc_ctrl_speed_init(nullptr, &cfg));
    cfg.kp_a_s_rad = -1.0f;
    EXPECT_EQ(MC_CTRL_SPEED_ERR_GAIN, mc_ctrl_speed_init(&c, &cfg));
    cfg = Cfg();
    cfg.ki_a_rad = NAN;
    EXPECT_EQ(MC_CTRL_SPEED_ERR_GAIN, mc_ctrl_speed_init(&c, &cfg));
    cfg = Cfg();
    cfg.kt_nm_a = 0.0f;
    EXPECT_EQ(MC_CTRL_SPEED_ERR_MODEL, mc_ctrl_speed_init(&c, &cfg));
    cfg = Cfg();
    cfg.iq_max_a = 0.0f;
    EXPECT_EQ(MC_CTRL_SPEED_ERR_MODEL, mc_ctrl_speed_init(&c, &cfg));
    cfg = Cfg();
    ASSERT_EQ(0u, mc_ctrl_speed_init(&c, &cfg));
    mc_drive_out_t out{};
    mc_drive_meas_t m = Meas(10.0f, 0.0f, 0.0f);
    m.have_encoder = false;
    EXPECT_EQ(MC_CTRL_SPEED_ERR_MEAS, mc_ctrl_speed_fast(&c, &m, &out));
    m = Meas(10.0f, 0.0f, 0.0f);
    m.have_speed_ref = false;
    EXPECT_EQ(MC_CTRL_SPEED_ERR_MEAS, mc_ctrl_speed_fast(&c, &m, &out));
    m = Meas(10.0f, 0.0f, NAN);
    EXPECT_EQ(MC_CTRL_SPEED_ERR_STEP, mc_ctrl_speed_fast(&c, &m, &out));
    // a NaN leaves no trace: the next good step is the law's first
    m = Meas(10.0f, 0.0f, 0.0f);
    EXPECT_EQ(0u, mc_ctrl_speed_fast(&c, &m, &out));
    EXPECT_TRUE(std::isfinite(out.iq_ref_a));
    for (const float bad : {-1e-3f, NAN, INFINITY}) {
        cfg = Cfg();
        cfg.ref_lag_s = bad;
        EXPECT_EQ(MC_CTRL_SPEED_ERR_GAIN, mc_ctrl_speed_init(&c, &cfg)) << bad;
    }
}

// The reference lag (cfg.ref_lag_s): the PI compares the measured speed
// with the reference through a first-order lag of ref_lag_s, started at
// the rotor's speed. A rotor that is where the lagged reference is, step
// by step along a ramp, leaves the PI nothing: the output is the
// feed-forward alone (1e-5 A: float rounding of the same lag recomputed
// here). Without the lag the same rotor leaves the PI the ramp's tracking
// error, a_ref * ref_lag_s = 1 rad/s at the end, and its integral: the
// output exceeds the feed-forward by more than kp times that error.
TEST(CtrlSpeed, ReferenceLagLeavesTheFeedForwardAloneOnARamp)
{
    const float a_ref = 1000.0f; // feed-forward J a / kt = 10 A, half the limit
    const float lag_s = 1e-3f;
    const float alpha = kDt / (lag_s + kDt);
    for (const float cfg_lag : {lag_s, 0.0f}) {
        mc_ctrl_speed_t c{};
        mc_ctrl_speed_cfg_t cfg = Cfg();
        cfg.ref_lag_s = cfg_lag;
        ASSERT_EQ(0u, mc_ctrl_speed_init(&c, &cfg));
        float lag = 0.0f;
        float ff = 0.0f;
        float err = 0.0f;
        mc_drive_out_t out{};
        for (int k = 0; k <= 400; ++k) { // from rest: the lag starts at 0
            const float w_ref = a_ref * kDt * static_cast<float>(k);
            lag += alpha * (w_ref - lag);
            const mc_drive_meas_t m = Meas(w_ref, a_ref, lag);
            ASSERT_EQ(0u, mc_ctrl_speed_fast(&c, &m, &out));
            ff = ((cfg.j_kgm2 * a_ref) + (cfg.b_nm_s_rad * w_ref)) / cfg.kt_nm_a;
            err = w_ref - lag;
            if (cfg_lag > 0.0f) {
                ASSERT_NEAR(ff, out.iq_ref_a, 1e-5f) << k;
            }
        }
        if (cfg_lag == 0.0f) {
            EXPECT_NEAR(a_ref * lag_s, err, 0.02f * a_ref * lag_s); // the ramp's settled lag
            EXPECT_GT(out.iq_ref_a - ff, cfg.kp_a_s_rad * err);
        }
    }
}

} // namespace
