// mc_drive_init: every configuration rule is rejected with its own
// MC_DRIVE_CFG_ERR_* bit and leaves the drive untouched; a good init starts
// IDLE with the PWM outputs off.
#include <cmath>
#include <cstring>

#include "app_test_fixture.h"

namespace apptest
{
namespace
{

class AppDriveInit : public AppDrive
{
  protected:
    // Init with `c` (and `h`) into a drive filled with a byte pattern; expect
    // exactly `want`, the drive bytes unchanged and the PWM not touched.
    void ExpectRejected(const mc_drive_cfg_t &c, uint32_t want, const mc_hal_t *h = nullptr)
    {
        mc_drive_t probe;
        std::memset(&probe, 0xA5, sizeof probe);
        mc_drive_t copy;
        std::memcpy(&copy, &probe, sizeof probe);
        const uint32_t disables = Calls(MC_HAL_FAKE_PWM3_DISABLE);
        EXPECT_EQ(want, mc_drive_init(&probe, &c, h != nullptr ? h : hal));
        // Byte comparison on purpose: padding included, every byte of the
        // pattern must survive a rejected init.
        EXPECT_EQ(
            0,
            std::memcmp(
                &probe, &copy,
                sizeof probe)) // NOLINT(bugprone-suspicious-memory-comparison,cert-exp42-c,cert-flp37-c)
            << "drive written on error";
        EXPECT_EQ(disables, Calls(MC_HAL_FAKE_PWM3_DISABLE));
    }
};

TEST_F(AppDriveInit, NullPointers)
{
    EXPECT_EQ(MC_DRIVE_CFG_ERR_NULL, mc_drive_init(nullptr, &cfg, hal));
    mc_drive_t probe;
    std::memset(&probe, 0x5A, sizeof probe);
    mc_drive_t copy;
    std::memcpy(&copy, &probe, sizeof probe);
    EXPECT_EQ(MC_DRIVE_CFG_ERR_NULL, mc_drive_init(&probe, nullptr, hal));
    EXPECT_EQ(MC_DRIVE_CFG_ERR_NULL, mc_drive_init(&probe, &cfg, nullptr));
    // Byte comparison on purpose: the pattern must survive, padding included.
    EXPECT_EQ(
        0,
        std::memcmp(
            &probe, &copy,
            sizeof probe)); // NOLINT(bugprone-suspicious-memory-comparison,cert-exp42-c,cert-flp37-c)
}

TEST_F(AppDriveInit, HalMissingCapability)
{
    // Required: the ADC, and at least one bridge (pwm3 for a 3-phase drive,
    // pwm2 for a stepper).
    mc_hal_t h = fake.board;
    h.adc = nullptr;
    ExpectRejected(cfg, MC_DRIVE_CFG_ERR_HAL, &h);
    h = fake.board;
    h.pwm3 = nullptr;
    h.pwm2 = nullptr;
    ExpectRejected(cfg, MC_DRIVE_CFG_ERR_HAL, &h);
    // Optional: either bridge alone, the encoder (sensorless laws), tick,
    // fault, can.
    h = fake.board;
    h.pwm3 = nullptr;
    EXPECT_EQ(MC_DRIVE_CFG_OK, mc_drive_init(&d, &cfg, &h));
    h = fake.board;
    h.encoder = nullptr;
    h.tick = nullptr;
    h.fault = nullptr;
    h.can = nullptr;
    h.pwm2 = nullptr;
    EXPECT_EQ(MC_DRIVE_CFG_OK, mc_drive_init(&d, &cfg, &h));
}

TEST_F(AppDriveInit, FocConfigRejected)
{
    mc_drive_cfg_t c = cfg;
    c.foc.r_ohm = -0.1f; // MC_FOC_ERR_MOTOR
    ExpectRejected(c, MC_DRIVE_CFG_ERR_FOC);
    c = cfg;
    c.foc.v_limit_ratio = 1.5f; // MC_FOC_ERR_V_LIMIT
    ExpectRejected(c, MC_DRIVE_CFG_ERR_FOC);
    c = cfg;
    c.foc.dt_s = 0.0f; // MC_FOC_ERR_DT (3 bw dt = 0 passes the PLL rule)
    ExpectRejected(c, MC_DRIVE_CFG_ERR_FOC);
}

TEST_F(AppDriveInit, PolePairsZero)
{
    mc_drive_cfg_t c = cfg;
    c.pole_pairs = 0u;
    ExpectRejected(c, MC_DRIVE_CFG_ERR_POLES);
    c.pole_pairs = 1u;
    EXPECT_EQ(MC_DRIVE_CFG_OK, mc_drive_init(&d, &c, hal));
}

TEST_F(AppDriveInit, SlowLoopDivZero)
{
    mc_drive_cfg_t c = cfg;
    c.slow_loop_div = 0u;
    ExpectRejected(c, MC_DRIVE_CFG_ERR_DIV);
    c.slow_loop_div = 1u;
    EXPECT_EQ(MC_DRIVE_CFG_OK, mc_drive_init(&d, &c, hal));
}

TEST_F(AppDriveInit, CurrentLimits)
{
    const float bad_imax[] = {0.0f, -1.0f, kNaN, kInf};
    for (float v : bad_imax) {
        mc_drive_cfg_t c = cfg;
        c.i_max_a = v;
        if (std::isinf(v)) {
            c.i_trip_a = kInf; // keep i_trip >= i_max: only finiteness is broken
        }
        SCOPED_TRACE(v);
        ExpectRejected(c, MC_DRIVE_CFG_ERR_CURRENT);
    }
    mc_drive_cfg_t c = cfg;
    c.i_trip_a = std::nextafter(cfg.i_max_a, 0.0f); // trip just below i_max
    ExpectRejected(c, MC_DRIVE_CFG_ERR_CURRENT);
    c.i_trip_a = kNaN;
    ExpectRejected(c, MC_DRIVE_CFG_ERR_CURRENT);
    c.i_trip_a = kInf;
    ExpectRejected(c, MC_DRIVE_CFG_ERR_CURRENT);
    c.i_trip_a = cfg.i_max_a; // equal is allowed
    EXPECT_EQ(MC_DRIVE_CFG_OK, mc_drive_init(&d, &c, hal));
}

TEST_F(AppDriveInit, VbusWindow)
{
    struct Case {
        float lo, hi;
    };
    const Case bad[] = {
        {30.0f, 30.0f}, // empty window
        {40.0f, 30.0f}, // reversed
        {kNaN, 60.0f},  {10.0f, kNaN},  {10.0f, kInf},
        {-kInf, 60.0f}, {-1.0f, 60.0f}, // an under-voltage trip must be a positive voltage
    };
    for (const Case &k : bad) {
        mc_drive_cfg_t c = cfg;
        c.vbus_min_v = k.lo;
        c.vbus_max_v = k.hi;
        SCOPED_TRACE(k.lo);
        SCOPED_TRACE(k.hi);
        ExpectRejected(c, MC_DRIVE_CFG_ERR_VBUS);
    }
    mc_drive_cfg_t c = cfg;
    c.vbus_max_v = std::nextafter(c.vbus_min_v, kInf); // narrowest non-empty window
    EXPECT_EQ(MC_DRIVE_CFG_OK, mc_drive_init(&d, &c, hal));
}

TEST_F(AppDriveInit, SpeedPllBandwidth)
{
    const float bad[] = {0.0f, -100.0f, kNaN, kInf};
    for (float bw : bad) {
        mc_drive_cfg_t c = cfg;
        c.speed_pll_bw_rad_s = bw;
        SCOPED_TRACE(bw);
        ExpectRejected(c, MC_DRIVE_CFG_ERR_SPEED_PLL);
    }
    // 3 bw dt <= 1 at dt = 50 us: bw <= 6666.7 rad/s.
    mc_drive_cfg_t c = cfg;
    c.speed_pll_bw_rad_s = 6700.0f; // 3 bw dt = 1.005
    ExpectRejected(c, MC_DRIVE_CFG_ERR_SPEED_PLL);
    c.speed_pll_bw_rad_s = 6660.0f; // 3 bw dt = 0.999
    EXPECT_EQ(MC_DRIVE_CFG_OK, mc_drive_init(&d, &c, hal));
    // The rule scales with dt: the same bw at twice the period is refused.
    c.foc.dt_s = 2.0f * kDt;
    ExpectRejected(c, MC_DRIVE_CFG_ERR_SPEED_PLL);
}

TEST_F(AppDriveInit, EncoderOffsetNotFinite)
{
    mc_drive_cfg_t c = cfg;
    c.encoder_offset_rad = kNaN;
    ExpectRejected(c, MC_DRIVE_CFG_ERR_OFFSET);
    c.encoder_offset_rad = -kInf;
    ExpectRejected(c, MC_DRIVE_CFG_ERR_OFFSET);
    c.encoder_offset_rad = -100.0f; // any finite offset is fine (wrapped)
    EXPECT_EQ(MC_DRIVE_CFG_OK, mc_drive_init(&d, &c, hal));
}

TEST_F(AppDriveInit, SeveralRulesBrokenReportsAllBits)
{
    mc_drive_cfg_t c = cfg;
    c.pole_pairs = 0u;
    c.slow_loop_div = 0u;
    c.encoder_offset_rad = kNaN;
    c.vbus_min_v = kNaN;
    mc_hal_t h = fake.board;
    h.adc = nullptr;
    ExpectRejected(c,
                   MC_DRIVE_CFG_ERR_POLES | MC_DRIVE_CFG_ERR_DIV | MC_DRIVE_CFG_ERR_OFFSET |
                       MC_DRIVE_CFG_ERR_VBUS | MC_DRIVE_CFG_ERR_HAL,
                   &h);
}

TEST_F(AppDriveInit, GoodInitIsIdleWithPwmOff)
{
    fake.pwm3.enabled = true; // outputs left on by whoever ran before
    ASSERT_EQ(MC_DRIVE_CFG_OK, mc_drive_init(&d, &cfg, hal));
    EXPECT_FALSE(fake.pwm3.enabled);
    EXPECT_EQ(1u, Calls(MC_HAL_FAKE_PWM3_DISABLE));
    EXPECT_EQ(MC_DRIVE_MODE_IDLE, d.mode);
    EXPECT_EQ(hal, d.hal);
    // Config copied (members: padding is not guaranteed to be copied).
    EXPECT_EQ(cfg.pole_pairs, d.cfg.pole_pairs);
    EXPECT_EQ(cfg.slow_loop_div, d.cfg.slow_loop_div);
    EXPECT_EQ(cfg.encoder_offset_rad, d.cfg.encoder_offset_rad);
    EXPECT_EQ(cfg.i_trip_a, d.cfg.i_trip_a);
    EXPECT_EQ(cfg.vbus_max_v, d.cfg.vbus_max_v);
    EXPECT_EQ(cfg.foc.dt_s, d.cfg.foc.dt_s);
    EXPECT_EQ(MC_DRIVE_FAULT_NONE, d.faults);
    EXPECT_EQ(0u, d.first_fault);
    EXPECT_EQ(0.0f, d.id_ref_a);
    EXPECT_EQ(0.0f, d.iq_ref_a);
    EXPECT_FALSE(d.enc_trk.primed);
    // Tracking-loop gains (s + bw)^3: one or two float products each,
    // relative error below 2 * 2^-24 (tolerance 3e-7 relative).
    const double bw = kPllBw;
    const double dt = kDt;
    EXPECT_NEAR(d.enc_trk.k1_dt, 3.0 * bw * dt, 3e-7 * 3.0 * bw * dt);
    EXPECT_NEAR(d.enc_trk.k2_dt, 3.0 * bw * bw * dt, 3e-7 * 3.0 * bw * bw * dt);
    EXPECT_NEAR(d.enc_trk.k3_dt, bw * bw * bw * dt, 3e-7 * bw * bw * bw * dt);
}

TEST_F(AppDriveInit, ReinitOfARunningDriveResetsIt)
{
    InitRunning();
    ASSERT_EQ(MC_DRIVE_CFG_OK, mc_drive_init(&d, &cfg, hal));
    EXPECT_FALSE(fake.pwm3.enabled);
    EXPECT_EQ(MC_DRIVE_MODE_IDLE, d.mode);
    EXPECT_EQ(0.0f, d.iq_ref_a);
    EXPECT_EQ(0u, d.fast_count);
}

} // namespace
} // namespace apptest
