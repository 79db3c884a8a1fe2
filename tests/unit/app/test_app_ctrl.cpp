// The control-law plug-in interface of the drive (MC_DRIVE_MODE_CTRL):
// attach rules, what the law is given and where its duties go, and how its
// errors are handled. The law here is a recording stub defined in the test.
#include <cerrno>
#include <cmath>

#include <gtest/gtest.h>

#include "app_test_fixture.h"

namespace apptest
{
namespace
{

struct StubLaw {
    uint32_t resets = 0, fasts = 0, slows = 0;
    uint32_t reset_ret = 0, fast_ret = 0, slow_ret = 0;
    mc_drive_meas_t last{};
    mc_drive_out_t out{0.2f, 0.5f, 0.8f, 0.25f, -0.75f};
};

uint32_t stub_reset(void *ctx)
{
    auto *s = static_cast<StubLaw *>(ctx);
    s->resets++;
    return s->reset_ret;
}
uint32_t stub_fast(void *ctx, const mc_drive_meas_t *m, mc_drive_out_t *out)
{
    auto *s = static_cast<StubLaw *>(ctx);
    s->fasts++;
    s->last = *m;
    *out = s->out;
    return s->fast_ret;
}
uint32_t stub_slow(void *ctx)
{
    auto *s = static_cast<StubLaw *>(ctx);
    s->slows++;
    return s->slow_ret;
}

class AppDriveCtrl : public AppDrive
{
  protected:
    mc_drive_ctrl_t Law(uint32_t outputs, bool needs_encoder = true)
    {
        return mc_drive_ctrl_t{outputs,   needs_encoder, stub_reset, stub_fast,
                               stub_slow, &law,          nullptr,    false};
    }
    StubLaw law;
};

TEST_F(AppDriveCtrl, AttachRules)
{
    InitDrive();
    mc_drive_ctrl_t c = Law(MC_DRIVE_OUT_PWM3);
    c.fast = nullptr;
    EXPECT_EQ(-EINVAL, mc_drive_attach_ctrl(&d, &c));
    c = Law(5u);
    EXPECT_EQ(-EINVAL, mc_drive_attach_ctrl(&d, &c));
    EXPECT_EQ(nullptr, d.ctrl);
    // CTRL without a law attached.
    EXPECT_EQ(-ENODEV, mc_drive_set_mode(&d, MC_DRIVE_MODE_CTRL));
    // A board without the law's bridge or its encoder.
    mc_hal_t h = fake.board;
    h.pwm2 = nullptr;
    h.encoder = nullptr;
    ASSERT_EQ(MC_DRIVE_CFG_OK, mc_drive_init(&d, &cfg, &h));
    c = Law(MC_DRIVE_OUT_PWM2);
    EXPECT_EQ(-ENODEV, mc_drive_attach_ctrl(&d, &c));
    c = Law(MC_DRIVE_OUT_PWM3, true);
    EXPECT_EQ(-ENODEV, mc_drive_attach_ctrl(&d, &c));
    c = Law(MC_DRIVE_OUT_PWM3, false); // a sensorless law needs no encoder
    EXPECT_EQ(0, mc_drive_attach_ctrl(&d, &c));
    // CURRENT mode needs the encoder.
    EXPECT_EQ(-ENODEV, mc_drive_set_mode(&d, MC_DRIVE_MODE_CURRENT));
}

TEST_F(AppDriveCtrl, NotWhileRunning)
{
    InitDrive();
    const mc_drive_ctrl_t c = Law(MC_DRIVE_OUT_PWM3);
    ASSERT_EQ(0, mc_drive_attach_ctrl(&d, &c));
    ASSERT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_CTRL));
    EXPECT_EQ(-EBUSY, mc_drive_attach_ctrl(&d, nullptr));
    EXPECT_EQ(&c, d.ctrl);
    EXPECT_EQ(-EBUSY, mc_drive_set_mode(&d, MC_DRIVE_MODE_CURRENT));
}

TEST_F(AppDriveCtrl, RunsTheLawAndWritesItsThreePhaseDuties)
{
    InitDrive();
    const mc_drive_ctrl_t c = Law(MC_DRIVE_OUT_PWM3);
    ASSERT_EQ(0, mc_drive_attach_ctrl(&d, &c));
    ASSERT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_CTRL));
    EXPECT_EQ(1u, law.resets);
    EXPECT_TRUE(fake.pwm3.enabled);
    ASSERT_EQ(0, mc_hal_fake_encoder_set(&fake, 1024u, MC_HAL_ENCODER_FLAG_VALID));
    ASSERT_EQ(0, mc_hal_fake_adc_set_sample(&fake, 1.5f, -0.5f, 0.0f, kVbus, kMask3));
    (void)mc_drive_fast_step(&d);
    EXPECT_EQ(MC_DRIVE_MODE_CTRL, d.mode);
    EXPECT_EQ(1u, law.fasts);
    // Measurements passed through unchanged (copies: exact).
    EXPECT_EQ(1.5f, law.last.ia_a);
    EXPECT_EQ(-0.5f, law.last.ib_a);
    EXPECT_EQ(kVbus, law.last.vbus_v);
    EXPECT_TRUE(law.last.have_encoder);
    EXPECT_EQ(1024u, law.last.enc_count);
    EXPECT_EQ(d.tm.theta_e_rad, law.last.theta_e_rad);
    EXPECT_EQ(kDt, law.last.dt_s);
    // Its duties reached the 3-phase bridge.
    EXPECT_EQ(0.2f, fake.pwm3.duty_a);
    EXPECT_EQ(0.5f, fake.pwm3.duty_b);
    EXPECT_EQ(0.8f, fake.pwm3.duty_c);
    // The slow loop reaches the law too.
    for (uint32_t k = 0; k < cfg.slow_loop_div; ++k) {
        GoodSample();
        if (mc_drive_fast_step(&d)) {
            mc_drive_slow_step(&d);
        }
    }
    EXPECT_EQ(1u, law.slows);
}

TEST_F(AppDriveCtrl, StepperLawDrivesTheDualHBridgeWithoutAThirdPhase)
{
    InitDrive();
    const mc_drive_ctrl_t c = Law(MC_DRIVE_OUT_PWM2);
    ASSERT_EQ(0, mc_drive_attach_ctrl(&d, &c));
    ASSERT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_CTRL));
    EXPECT_TRUE(fake.pwm2.enabled);
    EXPECT_FALSE(fake.pwm3.enabled);
    // Two winding currents of 0.6 trip each: a derived third phase would be
    // 1.2 trip and trip; a stepper has no third phase.
    const uint32_t mask2 = MC_HAL_ADC_VALID_IA | MC_HAL_ADC_VALID_IB | MC_HAL_ADC_VALID_VBUS;
    ASSERT_EQ(0,
              mc_hal_fake_adc_set_sample(&fake, 0.6f * kITrip, 0.6f * kITrip, 0.0f, kVbus, mask2));
    (void)mc_drive_fast_step(&d);
    EXPECT_EQ(MC_DRIVE_FAULT_NONE, d.faults);
    EXPECT_EQ(0.0f, law.last.ic_a);
    EXPECT_EQ(0.25f, fake.pwm2.duty_a);
    EXPECT_EQ(-0.75f, fake.pwm2.duty_b);
}

TEST_F(AppDriveCtrl, LawErrorsAreControlFaults)
{
    InitDrive();
    const mc_drive_ctrl_t c = Law(MC_DRIVE_OUT_PWM3);
    ASSERT_EQ(0, mc_drive_attach_ctrl(&d, &c));
    law.reset_ret = 3u;
    EXPECT_EQ(-EINVAL, mc_drive_set_mode(&d, MC_DRIVE_MODE_CTRL));
    EXPECT_FALSE(fake.pwm3.enabled);
    law.reset_ret = 0u;
    ASSERT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_CTRL));
    law.fast_ret = 0x40u;
    GoodSample();
    (void)mc_drive_fast_step(&d);
    EXPECT_EQ(MC_DRIVE_MODE_FAULT, d.mode);
    EXPECT_EQ(MC_DRIVE_FAULT_CONTROL, d.faults);
    EXPECT_EQ(0x40u, d.tm.ctrl_err);
    EXPECT_FALSE(fake.pwm3.enabled);
}

TEST_F(AppDriveCtrl, SlowErrorIsAControlFault)
{
    InitDrive();
    const mc_drive_ctrl_t c = Law(MC_DRIVE_OUT_PWM3);
    ASSERT_EQ(0, mc_drive_attach_ctrl(&d, &c));
    ASSERT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_CTRL));
    law.slow_ret = 9u;
    mc_drive_slow_step(&d);
    EXPECT_EQ(MC_DRIVE_FAULT_CONTROL, d.faults);
    EXPECT_FALSE(fake.pwm3.enabled);
}

TEST_F(AppDriveCtrl, InvalidLawDutiesArePwmFaults)
{
    // The HAL refuses a NaN duty; the drive treats the refusal as a fault.
    InitDrive();
    const mc_drive_ctrl_t c = Law(MC_DRIVE_OUT_PWM3);
    ASSERT_EQ(0, mc_drive_attach_ctrl(&d, &c));
    ASSERT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_CTRL));
    law.out.duty_b = std::nanf("");
    GoodSample();
    (void)mc_drive_fast_step(&d);
    EXPECT_EQ(MC_DRIVE_FAULT_PWM, d.faults);
    EXPECT_FALSE(fake.pwm3.enabled);
}

} // namespace
} // namespace apptest
