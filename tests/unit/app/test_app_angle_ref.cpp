// The angle reference after a power-up (mc_drive.h, MC_DRIVE_ANGLE_REF_*):
// CURRENT mode and the sensored laws refused with -EACCES and a named state
// until the index is seen (INDEX) or an alignment set the offset (ALIGN);
// the laws that find the angle themselves run before; STORED as before.
#include <cerrno>
#include <cmath>

#include "app_test_fixture.h"

namespace apptest
{
namespace
{

uint32_t stub_fast(void *, const mc_drive_meas_t *, mc_drive_out_t *out)
{
    out->duty_a = out->duty_b = out->duty_c = 0.5f;
    return 0u;
}

class AngleRef : public AppDrive
{
  protected:
    mc_drive_ctrl_t Law(bool finds_angle)
    {
        mc_drive_ctrl_t c{};
        c.outputs = MC_DRIVE_OUT_PWM3;
        c.needs_encoder = true;
        c.fast = stub_fast;
        c.finds_angle = finds_angle;
        return c;
    }
};

TEST_F(AngleRef, StoredRunsAtOnce)
{
    InitDrive(); // GoodCfg: angle_ref 0, STORED
    EXPECT_EQ(mc_drive_angle_state(&d), MC_DRIVE_ANGLE_KNOWN);
    EXPECT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_CURRENT));
}

TEST_F(AngleRef, OutOfRangeRefusedAtInit)
{
    cfg.angle_ref = 3u;
    EXPECT_EQ(mc_drive_init(&d, &cfg, hal), MC_DRIVE_CFG_ERR_ANGLE_REF);
    EXPECT_EQ(mc_drive_check_cfg(&cfg), MC_DRIVE_CFG_ERR_ANGLE_REF);
}

// ALIGN: refused (CURRENT, a sensored law) with NEED_ALIGN and the bridge
// off; a law that finds the angle runs; a measured offset makes the angle
// known and is the one the FOC uses; a re-init (an APPLY) loses it.
TEST_F(AngleRef, AlignRefusesUntilAnOffsetIsMeasured)
{
    cfg.angle_ref = MC_DRIVE_ANGLE_REF_ALIGN;
    InitDrive();
    EXPECT_EQ(mc_drive_angle_state(&d), MC_DRIVE_ANGLE_NEED_ALIGN);
    EXPECT_EQ(-EACCES, mc_drive_set_mode(&d, MC_DRIVE_MODE_CURRENT));
    EXPECT_EQ(d.mode, MC_DRIVE_MODE_IDLE);
    EXPECT_FALSE(fake.pwm3.enabled);
    const mc_drive_ctrl_t sensored = Law(false);
    ASSERT_EQ(0, mc_drive_attach_ctrl(&d, &sensored));
    EXPECT_EQ(-EACCES, mc_drive_set_mode(&d, MC_DRIVE_MODE_CTRL));
    EXPECT_FALSE(fake.pwm3.enabled);
    const mc_drive_ctrl_t finder = Law(true);
    ASSERT_EQ(0, mc_drive_attach_ctrl(&d, &finder));
    EXPECT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_CTRL));
    EXPECT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_IDLE));

    // bad offsets change nothing
    EXPECT_EQ(-EINVAL, mc_drive_set_encoder_offset(&d, kNaN));
    EXPECT_EQ(-EINVAL, mc_drive_set_encoder_offset(&d, -0.1f));
    EXPECT_EQ(-EINVAL, mc_drive_set_encoder_offset(&d, 6.3f));
    EXPECT_EQ(mc_drive_angle_state(&d), MC_DRIVE_ANGLE_NEED_ALIGN);
    EXPECT_EQ(0, mc_drive_set_encoder_offset(&d, 1.25f));
    EXPECT_EQ(mc_drive_angle_state(&d), MC_DRIVE_ANGLE_KNOWN);
    EXPECT_EQ(d.cfg.encoder_offset_rad, 1.25f);
    // at count 0 the electrical angle is the offset (exact: 0 + 1.25)
    GoodSample();
    (void)mc_drive_fast_step(&d);
    EXPECT_EQ(d.tm.theta_e_rad, 1.25f);
    ASSERT_EQ(0, mc_drive_attach_ctrl(&d, &sensored));
    EXPECT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_CTRL));
    EXPECT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_IDLE));
    EXPECT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_CURRENT));
    // not while CURRENT runs on it
    EXPECT_EQ(-EBUSY, mc_drive_set_encoder_offset(&d, 2.0f));
    EXPECT_EQ(d.cfg.encoder_offset_rad, 1.25f);
    EXPECT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_IDLE));
    // a re-init starts from the stored (stale) offset: refused again
    InitDrive();
    EXPECT_EQ(mc_drive_angle_state(&d), MC_DRIVE_ANGLE_NEED_ALIGN);
    EXPECT_EQ(-EACCES, mc_drive_set_mode(&d, MC_DRIVE_MODE_CURRENT));
}

// INDEX: refused with NEED_INDEX until a sample carries the index flag;
// the count's jump there (the HAL re-references it) is no encoder fault
// even with the jump check on, and the tracking loop starts over (speed 0
// after the jump, not the jump over one period).
TEST_F(AngleRef, IndexKnownFromTheFirstSampleWithTheFlag)
{
    cfg.angle_ref = MC_DRIVE_ANGLE_REF_INDEX;
    cfg.omega_max_rad_s = 100.0f; // jump threshold: 2 x 100 x 50e-6 x 16384 / 2 pi + 2 = 28 counts
    InitDrive();
    GoodSample();
    for (uint32_t k = 0; k < 20u; ++k) {
        ASSERT_EQ(0, mc_hal_fake_encoder_set(&fake, 1000u + k, MC_HAL_ENCODER_FLAG_VALID));
        GoodSample();
        (void)mc_drive_fast_step(&d);
    }
    EXPECT_EQ(mc_drive_angle_state(&d), MC_DRIVE_ANGLE_NEED_INDEX);
    EXPECT_EQ(-EACCES, mc_drive_set_mode(&d, MC_DRIVE_MODE_CURRENT));
    const mc_drive_ctrl_t finder = Law(true);
    ASSERT_EQ(0, mc_drive_attach_ctrl(&d, &finder));
    ASSERT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_CTRL));
    // the index: the count jumps from 1019 to 7 (relative to the mark)
    ASSERT_EQ(0, mc_hal_fake_encoder_set(&fake, 7u,
                                         MC_HAL_ENCODER_FLAG_VALID | MC_HAL_ENCODER_FLAG_INDEX));
    GoodSample();
    (void)mc_drive_fast_step(&d);
    EXPECT_EQ(d.faults, 0u);
    EXPECT_EQ(mc_drive_angle_state(&d), MC_DRIVE_ANGLE_KNOWN);
    ASSERT_EQ(0, mc_hal_fake_encoder_set(&fake, 8u,
                                         MC_HAL_ENCODER_FLAG_VALID | MC_HAL_ENCODER_FLAG_INDEX));
    GoodSample();
    (void)mc_drive_fast_step(&d);
    EXPECT_EQ(d.faults, 0u);
    // the tracking loop restarted at the jump: at most the one count per
    // period it then saw (2 pi / 16384 / 50e-6 = 7.67 rad/s), not the
    // 1012 counts back (-7760 rad/s over one period)
    EXPECT_LE(std::fabs(d.tm.omega_m_rad_s), 7.67f);
    EXPECT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_IDLE));
    EXPECT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_CURRENT));
}

// Without the re-base the same jump in a STORED drive is an encoder fault
// (the check the INDEX re-base must not defeat elsewhere).
TEST_F(AngleRef, JumpWithoutIndexStillFaults)
{
    cfg.omega_max_rad_s = 100.0f;
    InitDrive();
    for (uint32_t k = 0; k < 20u; ++k) {
        ASSERT_EQ(0, mc_hal_fake_encoder_set(&fake, 1000u + k, MC_HAL_ENCODER_FLAG_VALID));
        GoodSample();
        (void)mc_drive_fast_step(&d);
    }
    ASSERT_EQ(0, mc_hal_fake_encoder_set(&fake, 7u,
                                         MC_HAL_ENCODER_FLAG_VALID | MC_HAL_ENCODER_FLAG_INDEX));
    GoodSample();
    (void)mc_drive_fast_step(&d);
    EXPECT_NE(d.faults & MC_DRIVE_FAULT_ENCODER, 0u);
}

} // namespace
} // namespace apptest
