// Mode machine (IDLE / CURRENT / FAULT), current references, loop
// scheduling and the CURRENT-mode fast step on the fake board.
#include <cmath>
#include <cstring>

#include "app_test_fixture.h"

extern "C" int mc_test_set_mode_raw(mc_drive_t *d, int mode);

namespace apptest
{
namespace
{

using AppDriveMode = AppDrive;

TEST_F(AppDriveMode, IdleToCurrentWritesZeroVoltageThenEnables)
{
    InitDrive();
    // Duties left anywhere by someone else: the drive must centre them.
    fake.pwm3.duty_a = 0.1f;
    fake.pwm3.duty_b = 0.9f;
    fake.pwm3.duty_c = 0.3f;
    ASSERT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_CURRENT));
    EXPECT_EQ(MC_DRIVE_MODE_CURRENT, d.mode);
    EXPECT_TRUE(fake.pwm3.enabled);
    // 0.5 exactly: a constant copied through, no arithmetic.
    EXPECT_EQ(0.5f, fake.pwm3.duty_a);
    EXPECT_EQ(0.5f, fake.pwm3.duty_b);
    EXPECT_EQ(0.5f, fake.pwm3.duty_c);
    EXPECT_EQ(1u, Calls(MC_HAL_FAKE_PWM3_ENABLE));
    // Already in CURRENT: accepted, nothing re-done.
    EXPECT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_CURRENT));
    EXPECT_EQ(1u, Calls(MC_HAL_FAKE_PWM3_ENABLE));
}

TEST_F(AppDriveMode, DutiesAreSetBeforeTheEnable)
{
    InitDrive();
    // If the zero-voltage duties are refused the switches must never close:
    // enable not even called.
    ASSERT_EQ(0, mc_hal_fake_inject_error(&fake, MC_HAL_FAKE_PWM3_SET_DUTY, -EIO, 1u));
    EXPECT_EQ(-EBUSY, mc_drive_set_mode(&d, MC_DRIVE_MODE_CURRENT));
    EXPECT_EQ(0u, Calls(MC_HAL_FAKE_PWM3_ENABLE));
    EXPECT_FALSE(fake.pwm3.enabled);
    EXPECT_EQ(MC_DRIVE_MODE_IDLE, d.mode);
}

TEST_F(AppDriveMode, EnableFailureIsBusyAndPwmStaysOff)
{
    InitDrive();
    ASSERT_EQ(0, mc_hal_fake_inject_error(&fake, MC_HAL_FAKE_PWM3_ENABLE, -EIO, 1u));
    const uint32_t disables = Calls(MC_HAL_FAKE_PWM3_DISABLE);
    EXPECT_EQ(-EBUSY, mc_drive_set_mode(&d, MC_DRIVE_MODE_CURRENT));
    EXPECT_FALSE(fake.pwm3.enabled);
    EXPECT_EQ(MC_DRIVE_MODE_IDLE, d.mode);
    EXPECT_EQ(disables + 1u, Calls(MC_HAL_FAKE_PWM3_DISABLE)); // put back to safe
    EXPECT_EQ(MC_DRIVE_FAULT_NONE, d.faults);
    // The injection is consumed: the next request works.
    EXPECT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_CURRENT));
    EXPECT_TRUE(fake.pwm3.enabled);
}

TEST_F(AppDriveMode, EnableRefusedWhileGateKilled)
{
    fcfg.fault_input_kills = true;
    InitDrive();
    // A glitch on the gate-driver input latches the kill and goes away.
    ASSERT_EQ(0, mc_hal_fake_fault_set_inputs(&fake, MC_HAL_FAULT_GATE_DRIVER));
    ASSERT_EQ(0, mc_hal_fake_fault_set_inputs(&fake, 0u));
    ASSERT_TRUE(fake.fault.gate_killed);
    EXPECT_EQ(-EBUSY, mc_drive_set_mode(&d, MC_DRIVE_MODE_CURRENT));
    EXPECT_FALSE(fake.pwm3.enabled);
    EXPECT_EQ(MC_DRIVE_MODE_IDLE, d.mode);
}

TEST_F(AppDriveMode, CurrentRefusedInFault)
{
    InitRunning();
    // Trip (stale ADC sample) -> FAULT.
    (void)mc_drive_fast_step(&d);
    ASSERT_EQ(MC_DRIVE_MODE_FAULT, d.mode);
    const uint32_t enables = Calls(MC_HAL_FAKE_PWM3_ENABLE);
    const uint32_t duties = Calls(MC_HAL_FAKE_PWM3_SET_DUTY);
    EXPECT_EQ(-EBUSY, mc_drive_set_mode(&d, MC_DRIVE_MODE_CURRENT));
    EXPECT_EQ(MC_DRIVE_MODE_FAULT, d.mode);
    EXPECT_FALSE(fake.pwm3.enabled);
    EXPECT_EQ(enables, Calls(MC_HAL_FAKE_PWM3_ENABLE));
    EXPECT_EQ(duties, Calls(MC_HAL_FAKE_PWM3_SET_DUTY));
    // IDLE is accepted (outputs off) but does not leave FAULT: only
    // mc_drive_clear_faults does.
    EXPECT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_IDLE));
    EXPECT_EQ(MC_DRIVE_MODE_FAULT, d.mode);
    EXPECT_NE(0u, d.faults);
}

TEST_F(AppDriveMode, InvalidModeIsEinvalAndChangesNothing)
{
    InitRunning();
    const uint32_t disables = Calls(MC_HAL_FAKE_PWM3_DISABLE);
    // 7: not an enumerator; made in C (invalid_mode.c), where that is defined.
    EXPECT_EQ(-EINVAL, mc_test_set_mode_raw(&d, 7));
    // FAULT is entered by the drive, never requested.
    EXPECT_EQ(-EINVAL, mc_drive_set_mode(&d, MC_DRIVE_MODE_FAULT));
    EXPECT_EQ(MC_DRIVE_MODE_CURRENT, d.mode);
    EXPECT_TRUE(fake.pwm3.enabled);
    EXPECT_EQ(disables, Calls(MC_HAL_FAKE_PWM3_DISABLE));
    EXPECT_EQ(MC_DRIVE_FAULT_NONE, d.faults);
}

TEST_F(AppDriveMode, IdleDisablesPwm)
{
    InitRunning();
    ASSERT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_IDLE));
    EXPECT_EQ(MC_DRIVE_MODE_IDLE, d.mode);
    EXPECT_FALSE(fake.pwm3.enabled);
    // In IDLE the fast step measures but never writes duties.
    const uint32_t duties = Calls(MC_HAL_FAKE_PWM3_SET_DUTY);
    for (int i = 0; i < 5; ++i) {
        GoodSample();
        (void)mc_drive_fast_step(&d);
    }
    EXPECT_EQ(duties, Calls(MC_HAL_FAKE_PWM3_SET_DUTY));
    EXPECT_FALSE(fake.pwm3.enabled);
    EXPECT_EQ(MC_DRIVE_MODE_IDLE, d.mode);
    EXPECT_EQ(MC_DRIVE_FAULT_NONE, d.faults);
}

TEST_F(AppDriveMode, CurrentRefValidation)
{
    InitDrive();
    ASSERT_EQ(0, mc_drive_set_current_ref(&d, -2.0f, 3.0f));
    const float bad[] = {
        kNaN, kInf, -kInf, std::nextafter(kIMax, kInf), -std::nextafter(kIMax, kInf), 1e30f};
    for (float v : bad) {
        SCOPED_TRACE(v);
        EXPECT_EQ(-EINVAL, mc_drive_set_current_ref(&d, v, 1.0f));
        EXPECT_EQ(-EINVAL, mc_drive_set_current_ref(&d, 1.0f, v));
        // previous references kept, bit for bit
        EXPECT_EQ(-2.0f, d.id_ref_a);
        EXPECT_EQ(3.0f, d.iq_ref_a);
    }
    // |ref| == i_max is inside the limit.
    EXPECT_EQ(0, mc_drive_set_current_ref(&d, -kIMax, kIMax));
    EXPECT_EQ(-kIMax, d.id_ref_a);
    EXPECT_EQ(kIMax, d.iq_ref_a);
}

TEST_F(AppDriveMode, SlowLoopDueEverySlowLoopDivCalls)
{
    const uint32_t divs[] = {1u, 3u, kSlowDiv};
    for (uint32_t div : divs) {
        SCOPED_TRACE(div);
        cfg.slow_loop_div = div;
        InitDrive();
        for (uint32_t n = 1u; n <= 5u * div + 2u; ++n) {
            GoodSample();
            const bool due = mc_drive_fast_step(&d);
            EXPECT_EQ(n % div == 0u, due) << "call " << n;
        }
        EXPECT_EQ(5u * div + 2u, d.fast_count);
    }
}

TEST_F(AppDriveMode, SlowLoopScheduleKeepsRunningInFault)
{
    InitDrive();
    for (uint32_t n = 1u; n <= 3u * kSlowDiv; ++n) {
        // no sample: every step is a stale-ADC fault, the schedule still runs
        EXPECT_EQ(n % kSlowDiv == 0u, mc_drive_fast_step(&d)) << "call " << n;
    }
    EXPECT_EQ(MC_DRIVE_MODE_FAULT, d.mode);
}

TEST_F(AppDriveMode, CurrentModeStepWritesFocDuties)
{
    InitDrive();
    ASSERT_EQ(0, mc_hal_fake_encoder_set(&fake, 1234u, MC_HAL_ENCODER_FLAG_VALID));
    ASSERT_EQ(0, mc_drive_set_current_ref(&d, -1.0f, 8.0f));
    ASSERT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_CURRENT));

    // Reference: the FOC kernel alone, same config, same inputs.
    mc_foc_f32_t foc;
    ASSERT_EQ(MC_FOC_ERR_NONE, mc_foc_f32_init(&foc, &cfg.foc));

    for (int k = 0; k < 20; ++k) {
        GoodSample();
        const uint32_t duties = Calls(MC_HAL_FAKE_PWM3_SET_DUTY);
        (void)mc_drive_fast_step(&d);
        ASSERT_EQ(MC_DRIVE_FAULT_NONE, d.faults);
        ASSERT_EQ(duties + 1u, Calls(MC_HAL_FAKE_PWM3_SET_DUTY));

        mc_foc_f32_in_t in{};
        in.ia_a = 0.0f;
        in.ib_a = 0.0f;
        in.ic_a = 0.0f;
        in.three_phase = false;
        in.theta_e_rad = d.tm.theta_e_rad;
        in.omega_e_rad_s = 0.0f; // encoder still: the speed estimate stays 0
        in.vbus_v = kVbus;
        in.id_ref_a = -1.0f;
        in.iq_ref_a = 8.0f;
        mc_foc_f32_out_t want{};
        ASSERT_EQ(MC_FOC_ERR_NONE, mc_foc_f32_step(&foc, &in, &want));

        // Same C code on the same inputs, -ffp-contract=off: bit-identical
        // (tolerance 0).
        EXPECT_EQ(0.0f, d.tm.omega_m_rad_s);
        EXPECT_EQ(want.duty_a, d.tm.foc.duty_a);
        EXPECT_EQ(want.duty_b, d.tm.foc.duty_b);
        EXPECT_EQ(want.duty_c, d.tm.foc.duty_c);
        EXPECT_EQ(want.vd_v, d.tm.foc.vd_v);
        EXPECT_EQ(want.vq_v, d.tm.foc.vq_v);
        EXPECT_EQ(want.v_alpha_v, d.tm.foc.v_alpha_v);
        EXPECT_EQ(want.v_beta_v, d.tm.foc.v_beta_v);
        EXPECT_EQ(want.id_a, d.tm.foc.id_a);
        EXPECT_EQ(want.iq_a, d.tm.foc.iq_a);
        // What reached the bridge is what the FOC computed.
        EXPECT_EQ(d.tm.foc.duty_a, fake.pwm3.duty_a);
        EXPECT_EQ(d.tm.foc.duty_b, fake.pwm3.duty_b);
        EXPECT_EQ(d.tm.foc.duty_c, fake.pwm3.duty_c);
        const float duty[] = {fake.pwm3.duty_a, fake.pwm3.duty_b, fake.pwm3.duty_c};
        for (float x : duty) {
            EXPECT_GE(x, 0.0f);
            EXPECT_LE(x, 1.0f);
        }
        // Error in q positive, in d negative: the PIs push vq up, vd down.
        EXPECT_GT(d.tm.foc.vq_v, 0.0f);
        EXPECT_LT(d.tm.foc.vd_v, 0.0f);
        // Telemetry of the inputs, copied without arithmetic.
        EXPECT_EQ(-1.0f, d.tm.id_ref_a);
        EXPECT_EQ(8.0f, d.tm.iq_ref_a);
        EXPECT_EQ(kVbus, d.tm.vbus_v);
        EXPECT_EQ(0.0f, d.tm.ia_a);
        EXPECT_EQ(0.0f, d.tm.ic_a);
    }
    // The duties moved away from zero voltage (the PIs integrate the error).
    EXPECT_GT(std::fabs(fake.pwm3.duty_a - 0.5f) + std::fabs(fake.pwm3.duty_b - 0.5f) +
                  std::fabs(fake.pwm3.duty_c - 0.5f),
              0.01f);
    EXPECT_TRUE(fake.pwm3.enabled);
}

TEST_F(AppDriveMode, ReenteringCurrentStartsTheFocFromRest)
{
    InitDrive();
    ASSERT_EQ(0, mc_drive_set_current_ref(&d, 2.0f, -6.0f));
    ASSERT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_CURRENT));
    for (int k = 0; k < 50; ++k) { // wind the PI integrators up
        GoodSample();
        (void)mc_drive_fast_step(&d);
    }
    ASSERT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_IDLE));
    ASSERT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_CURRENT));
    ASSERT_EQ(0, mc_drive_set_current_ref(&d, 2.0f, -6.0f));
    GoodSample();
    (void)mc_drive_fast_step(&d);
    ASSERT_EQ(MC_DRIVE_FAULT_NONE, d.faults);

    // First step of a fresh controller on the same inputs: bit-identical
    // (tolerance 0, same code), i.e. no integrator state carried over.
    mc_foc_f32_t foc;
    ASSERT_EQ(MC_FOC_ERR_NONE, mc_foc_f32_init(&foc, &cfg.foc));
    mc_foc_f32_in_t in{};
    in.theta_e_rad = d.tm.theta_e_rad;
    in.vbus_v = kVbus;
    in.id_ref_a = 2.0f;
    in.iq_ref_a = -6.0f;
    mc_foc_f32_out_t want{};
    ASSERT_EQ(MC_FOC_ERR_NONE, mc_foc_f32_step(&foc, &in, &want));
    EXPECT_EQ(want.vd_v, d.tm.foc.vd_v);
    EXPECT_EQ(want.vq_v, d.tm.foc.vq_v);
}

TEST_F(AppDriveMode, ThreeValidCurrentsAreUsedForIc)
{
    InitDrive();
    ASSERT_EQ(0, mc_hal_fake_adc_set_sample(&fake, 1.0f, 2.0f, -2.5f, kVbus, MC_HAL_ADC_VALID_ALL));
    (void)mc_drive_fast_step(&d);
    EXPECT_EQ(-2.5f, d.tm.ic_a); // measured ic, copied
    ASSERT_EQ(0, mc_hal_fake_adc_set_sample(&fake, 1.0f, 2.0f, -2.5f, kVbus, kMask3));
    (void)mc_drive_fast_step(&d);
    EXPECT_EQ(-3.0f, d.tm.ic_a); // derived -(ia + ib): exact in float
    EXPECT_EQ(MC_DRIVE_FAULT_NONE, d.faults);
}

} // namespace
} // namespace apptest
