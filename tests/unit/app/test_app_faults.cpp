// Fault reaction of the fast and slow steps, and mc_drive_clear_faults.
// Every fast-step trip must, in that same step: disable the PWM through the
// HAL, enter FAULT, set exactly its sticky bit, record it as the first fault
// and stamp the fake's tick.
#include <cmath>

#include "app_test_fixture.h"

namespace apptest
{
namespace
{

constexpr uint32_t kTripTick = 0xC0FFEE01u; // the fake's tick at the trip

class AppDriveFault : public AppDrive
{
  protected:
    // One fast step at tick kTripTick; expect exactly `bit` raised by it.
    void StepExpectTrip(uint32_t bit)
    {
        ASSERT_EQ(0, mc_hal_fake_tick_set(&fake, kTripTick));
        // The conversion happened at the trip tick too: the step runs within
        // its deadline, so only the injected cause trips.
        fake.adc_sample.timestamp_ticks = kTripTick;
        const uint32_t disables = Calls(MC_HAL_FAKE_PWM3_DISABLE);
        (void)mc_drive_fast_step(&d);
        EXPECT_EQ(disables + 1u, Calls(MC_HAL_FAKE_PWM3_DISABLE)) << "no disable in this step";
        EXPECT_FALSE(fake.pwm3.enabled);
        EXPECT_EQ(MC_DRIVE_MODE_FAULT, d.mode);
        EXPECT_EQ(bit, d.faults);
        EXPECT_EQ(bit, d.first_fault);
        EXPECT_EQ(kTripTick, d.fault_tick);
    }

    // A clean step: no fault, no disable.
    void StepExpectClean()
    {
        const uint32_t disables = Calls(MC_HAL_FAKE_PWM3_DISABLE);
        (void)mc_drive_fast_step(&d);
        EXPECT_EQ(MC_DRIVE_FAULT_NONE, d.faults);
        EXPECT_EQ(disables, Calls(MC_HAL_FAKE_PWM3_DISABLE));
    }

    void Sample(float ia, float ib, float ic, float vbus, uint32_t mask = kMask3)
    {
        ASSERT_EQ(0, mc_hal_fake_adc_set_sample(&fake, ia, ib, ic, vbus, mask));
    }
};

// ---- fast step: ADC ---------------------------------------------------------

TEST_F(AppDriveFault, AdcReadError)
{
    InitRunning();
    Sample(0.0f, 0.0f, 0.0f, kVbus);
    ASSERT_EQ(0, mc_hal_fake_inject_error(&fake, MC_HAL_FAKE_ADC_READ, -EIO, 1u));
    StepExpectTrip(MC_DRIVE_FAULT_ADC);
}

TEST_F(AppDriveFault, AdcStaleSample)
{
    InitRunning();
    // No new conversion since the last read: the fake returns -EAGAIN.
    StepExpectTrip(MC_DRIVE_FAULT_ADC);
}

TEST_F(AppDriveFault, AdcMissingIa)
{
    InitRunning();
    Sample(0.0f, 0.0f, 0.0f, kVbus,
           MC_HAL_ADC_VALID_IB | MC_HAL_ADC_VALID_IC | MC_HAL_ADC_VALID_VBUS);
    StepExpectTrip(MC_DRIVE_FAULT_ADC);
}

TEST_F(AppDriveFault, AdcMissingIb)
{
    InitRunning();
    Sample(0.0f, 0.0f, 0.0f, kVbus,
           MC_HAL_ADC_VALID_IA | MC_HAL_ADC_VALID_IC | MC_HAL_ADC_VALID_VBUS);
    StepExpectTrip(MC_DRIVE_FAULT_ADC);
}

TEST_F(AppDriveFault, AdcMissingVbus)
{
    InitRunning();
    Sample(0.0f, 0.0f, 0.0f, kVbus,
           MC_HAL_ADC_VALID_IA | MC_HAL_ADC_VALID_IB | MC_HAL_ADC_VALID_IC);
    StepExpectTrip(MC_DRIVE_FAULT_ADC);
}

TEST_F(AppDriveFault, AdcFaultDetectedInIdleToo)
{
    InitDrive();
    StepExpectTrip(MC_DRIVE_FAULT_ADC); // never sampled: stale
}

// ---- fast step: measurement values -------------------------------------------

TEST_F(AppDriveFault, NanOrInfMeasurement)
{
    struct Case {
        float ia, ib, ic, vbus;
        uint32_t mask;
    };
    const Case cases[] = {
        {kNaN, 0.0f, 0.0f, kVbus, kMask3},
        {0.0f, kNaN, 0.0f, kVbus, kMask3},
        {0.0f, 0.0f, 0.0f, kNaN, kMask3},
        {kInf, 0.0f, 0.0f, kVbus, kMask3},
        {0.0f, -kInf, 0.0f, kVbus, kMask3},
        {0.0f, 0.0f, 0.0f, kInf, kMask3},
        {0.0f, 0.0f, kNaN, kVbus, MC_HAL_ADC_VALID_ALL}, // measured ic
        // derived ic = -(ia + ib) overflows to -inf
        {3e38f, 3e38f, 0.0f, kVbus, kMask3},
    };
    for (const Case &k : cases) {
        SCOPED_TRACE(&k - cases);
        InitRunning();
        Sample(k.ia, k.ib, k.ic, k.vbus, k.mask);
        StepExpectTrip(MC_DRIVE_FAULT_MEAS_NAN);
    }
}

TEST_F(AppDriveFault, NanInIcIgnoredWhenIcNotValid)
{
    InitRunning();
    Sample(1.0f, 2.0f, kNaN, kVbus, kMask3); // ic channel not valid: derived
    StepExpectClean();
    EXPECT_EQ(-3.0f, d.tm.ic_a);
}

TEST_F(AppDriveFault, OverCurrentOnEachPhase)
{
    const float above = std::nextafter(kITrip, kInf);
    struct Case {
        float ia, ib, ic;
        uint32_t mask;
    };
    const Case cases[] = {
        {above, 0.0f, 0.0f, kMask3},
        {-above, 0.0f, 0.0f, kMask3},
        {0.0f, above, 0.0f, kMask3},
        {0.0f, -above, 0.0f, kMask3},
        {0.0f, 0.0f, above, MC_HAL_ADC_VALID_ALL}, // measured ic
        {0.0f, 0.0f, -above, MC_HAL_ADC_VALID_ALL},
        // derived ic = -(ia + ib) = -36 A while |ia|, |ib| = 18 A are fine
        {0.6f * kITrip, 0.6f * kITrip, 0.0f, kMask3},
        {-0.6f * kITrip, -0.6f * kITrip, 0.0f, kMask3},
    };
    for (const Case &k : cases) {
        SCOPED_TRACE(&k - cases);
        InitRunning();
        Sample(k.ia, k.ib, k.ic, kVbus, k.mask);
        StepExpectTrip(MC_DRIVE_FAULT_OVERCURRENT);
    }
}

TEST_F(AppDriveFault, CurrentsAtTripLevelDoNotTrip)
{
    InitRunning();
    // |i| == i_trip is not above it.
    Sample(kITrip, -kITrip, 0.0f, kVbus, kMask3); // derived ic = 0
    StepExpectClean();
    Sample(0.0f, 0.0f, -kITrip, kVbus, MC_HAL_ADC_VALID_ALL);
    StepExpectClean();
    // The measured ic, when valid, replaces the derived one: ia = ib = 18 A
    // with a measured ic of 5 A is no trip although -(ia + ib) = -36 A.
    Sample(0.6f * kITrip, 0.6f * kITrip, 5.0f, kVbus, MC_HAL_ADC_VALID_ALL);
    StepExpectClean();
    EXPECT_EQ(MC_DRIVE_MODE_CURRENT, d.mode);
}

TEST_F(AppDriveFault, VbusBelowMin)
{
    InitRunning();
    Sample(0.0f, 0.0f, 0.0f, std::nextafter(kVbusMin, 0.0f));
    StepExpectTrip(MC_DRIVE_FAULT_VBUS_LOW);
}

TEST_F(AppDriveFault, VbusAboveMax)
{
    InitRunning();
    Sample(0.0f, 0.0f, 0.0f, std::nextafter(kVbusMax, kInf));
    StepExpectTrip(MC_DRIVE_FAULT_VBUS_HIGH);
}

TEST_F(AppDriveFault, VbusAtWindowEdgesIsFine)
{
    InitRunning();
    Sample(0.0f, 0.0f, 0.0f, kVbusMin);
    StepExpectClean();
    Sample(0.0f, 0.0f, 0.0f, kVbusMax);
    StepExpectClean();
}

// ---- fast step: encoder, PWM --------------------------------------------------

TEST_F(AppDriveFault, EncoderReadError)
{
    InitRunning();
    Sample(0.0f, 0.0f, 0.0f, kVbus);
    ASSERT_EQ(0, mc_hal_fake_inject_error(&fake, MC_HAL_FAKE_ENCODER_READ, -EIO, 1u));
    StepExpectTrip(MC_DRIVE_FAULT_ENCODER);
}

TEST_F(AppDriveFault, EncoderNotValid)
{
    const uint32_t flags[] = {0u, MC_HAL_ENCODER_FLAG_INDEX};
    for (uint32_t f : flags) {
        SCOPED_TRACE(f);
        InitRunning();
        ASSERT_EQ(0, mc_hal_fake_encoder_set(&fake, 100u, f));
        Sample(0.0f, 0.0f, 0.0f, kVbus);
        StepExpectTrip(MC_DRIVE_FAULT_ENCODER);
    }
}

TEST_F(AppDriveFault, PwmSetDutyRefused)
{
    InitRunning();
    Sample(0.0f, 0.0f, 0.0f, kVbus);
    ASSERT_EQ(0, mc_hal_fake_inject_error(&fake, MC_HAL_FAKE_PWM3_SET_DUTY, -EIO, 1u));
    StepExpectTrip(MC_DRIVE_FAULT_PWM);
}

// ---- fault bookkeeping ----------------------------------------------------------

TEST_F(AppDriveFault, SimultaneousFaultsFirstIsLowestBit)
{
    InitRunning();
    ASSERT_EQ(0, mc_hal_fake_tick_set(&fake, 77u));
    Sample(2.0f * kITrip, 0.0f, 0.0f, 2.0f * kVbusMax);
    (void)mc_drive_fast_step(&d);
    EXPECT_EQ(MC_DRIVE_FAULT_OVERCURRENT | MC_DRIVE_FAULT_VBUS_HIGH, d.faults);
    EXPECT_EQ(MC_DRIVE_FAULT_OVERCURRENT, d.first_fault);
    EXPECT_EQ(77u, d.fault_tick);
}

TEST_F(AppDriveFault, LaterFaultsAreStickyButDoNotReplaceTheFirst)
{
    InitRunning();
    Sample(0.0f, 0.0f, 0.0f, 1.0f);
    StepExpectTrip(MC_DRIVE_FAULT_VBUS_LOW);
    ASSERT_EQ(0, mc_hal_fake_tick_advance(&fake, 1000u));
    ASSERT_EQ(0, mc_hal_fake_inject_error(&fake, MC_HAL_FAKE_ENCODER_READ, -EIO, 1u));
    Sample(0.0f, 0.0f, 0.0f, kVbus);
    (void)mc_drive_fast_step(&d);
    EXPECT_EQ(MC_DRIVE_FAULT_VBUS_LOW | MC_DRIVE_FAULT_ENCODER, d.faults);
    EXPECT_EQ(MC_DRIVE_FAULT_VBUS_LOW, d.first_fault);
    EXPECT_EQ(kTripTick, d.fault_tick);
    // A clean step in FAULT clears nothing.
    Sample(0.0f, 0.0f, 0.0f, kVbus);
    (void)mc_drive_fast_step(&d);
    EXPECT_EQ(MC_DRIVE_FAULT_VBUS_LOW | MC_DRIVE_FAULT_ENCODER, d.faults);
    EXPECT_EQ(MC_DRIVE_MODE_FAULT, d.mode);
    EXPECT_FALSE(fake.pwm3.enabled);
}

TEST_F(AppDriveFault, NoTickCapabilityStampsZero)
{
    mc_hal_t h = fake.board;
    h.tick = nullptr;
    ASSERT_EQ(MC_DRIVE_CFG_OK, mc_drive_init(&d, &cfg, &h));
    ASSERT_EQ(0, mc_hal_fake_encoder_set(&fake, 0u, MC_HAL_ENCODER_FLAG_VALID));
    ASSERT_EQ(0, mc_hal_fake_tick_set(&fake, 5u));
    (void)mc_drive_fast_step(&d); // stale ADC
    EXPECT_EQ(MC_DRIVE_FAULT_ADC, d.faults);
    EXPECT_EQ(0u, d.fault_tick);
}

// ---- slow step: hardware fault input ------------------------------------------------

TEST_F(AppDriveFault, SlowStepQuietWithoutFaultInput)
{
    InitRunning();
    mc_drive_slow_step(&d);
    EXPECT_EQ(MC_DRIVE_FAULT_NONE, d.faults);
    EXPECT_EQ(MC_DRIVE_MODE_CURRENT, d.mode);
    EXPECT_TRUE(fake.pwm3.enabled);
}

TEST_F(AppDriveFault, SlowStepRaisesHwInputWhenInputActive)
{
    InitRunning();
    ASSERT_EQ(0, mc_hal_fake_tick_set(&fake, kTripTick));
    ASSERT_EQ(0, mc_hal_fake_fault_set_inputs(&fake, MC_HAL_FAULT_OVERCURRENT));
    const uint32_t disables = Calls(MC_HAL_FAKE_PWM3_DISABLE);
    mc_drive_slow_step(&d);
    EXPECT_EQ(disables + 1u, Calls(MC_HAL_FAKE_PWM3_DISABLE));
    EXPECT_FALSE(fake.pwm3.enabled);
    EXPECT_EQ(MC_DRIVE_MODE_FAULT, d.mode);
    EXPECT_EQ(MC_DRIVE_FAULT_HW_INPUT, d.faults);
    EXPECT_EQ(MC_DRIVE_FAULT_HW_INPUT, d.first_fault);
    EXPECT_EQ(kTripTick, d.fault_tick);
}

TEST_F(AppDriveFault, SlowStepRaisesHwInputWhenGateKilledOnly)
{
    InitRunning();
    ASSERT_EQ(0, mc_hal_fake_fault_set_inputs(&fake, MC_HAL_FAULT_GATE_DRIVER));
    ASSERT_EQ(0, mc_hal_fake_fault_set_inputs(&fake, 0u)); // glitch gone, kill latched
    ASSERT_TRUE(fake.fault.gate_killed);
    mc_drive_slow_step(&d);
    EXPECT_EQ(MC_DRIVE_MODE_FAULT, d.mode);
    EXPECT_EQ(MC_DRIVE_FAULT_HW_INPUT, d.faults);
}

TEST_F(AppDriveFault, SlowStepDisablesPwmWhenTheInputDoesNotKill)
{
    // Fault input not wired to the break input: only the drive stops the PWM.
    fcfg.fault_input_kills = false;
    ASSERT_EQ(0, mc_hal_fake_init(&fake, &fcfg));
    InitRunning();
    ASSERT_EQ(0, mc_hal_fake_fault_set_inputs(&fake, MC_HAL_FAULT_GATE_DRIVER));
    ASSERT_TRUE(fake.pwm3.enabled);
    ASSERT_FALSE(fake.fault.gate_killed);
    mc_drive_slow_step(&d);
    EXPECT_FALSE(fake.pwm3.enabled);
    EXPECT_EQ(MC_DRIVE_FAULT_HW_INPUT, d.faults);
}

TEST_F(AppDriveFault, SlowStepWithoutFaultCapability)
{
    mc_hal_t h = fake.board;
    h.fault = nullptr;
    ASSERT_EQ(MC_DRIVE_CFG_OK, mc_drive_init(&d, &cfg, &h));
    ASSERT_EQ(0, mc_hal_fake_fault_set_inputs(&fake, MC_HAL_FAULT_GATE_DRIVER));
    mc_drive_slow_step(&d); // nothing to read: no fault from the slow step
    EXPECT_EQ(MC_DRIVE_FAULT_NONE, d.faults);
    EXPECT_EQ(0u, Calls(MC_HAL_FAKE_FAULT_READ));
}

// ---- clear_faults -----------------------------------------------------------------------

TEST_F(AppDriveFault, ClearRefusedWhileHwInputActive)
{
    InitRunning();
    ASSERT_EQ(0, mc_hal_fake_fault_set_inputs(&fake, MC_HAL_FAULT_OVERCURRENT));
    mc_drive_slow_step(&d);
    ASSERT_EQ(MC_DRIVE_FAULT_HW_INPUT, d.faults);
    EXPECT_EQ(-EBUSY, mc_drive_clear_faults(&d));
    EXPECT_EQ(MC_DRIVE_MODE_FAULT, d.mode);
    EXPECT_EQ(MC_DRIVE_FAULT_HW_INPUT, d.faults);
    EXPECT_EQ(MC_DRIVE_FAULT_HW_INPUT, d.first_fault);
    EXPECT_TRUE(fake.fault.gate_killed);
}

TEST_F(AppDriveFault, ClearReleasesTheGateOnceTheInputIsGone)
{
    InitRunning();
    ASSERT_EQ(0, mc_hal_fake_fault_set_inputs(&fake, MC_HAL_FAULT_OVERCURRENT));
    mc_drive_slow_step(&d);
    ASSERT_EQ(0, mc_hal_fake_fault_set_inputs(&fake, 0u));
    // Gate release refused once: still busy, still in FAULT.
    ASSERT_EQ(0, mc_hal_fake_inject_error(&fake, MC_HAL_FAKE_FAULT_GATE_RELEASE, -EIO, 1u));
    EXPECT_EQ(-EBUSY, mc_drive_clear_faults(&d));
    EXPECT_EQ(MC_DRIVE_MODE_FAULT, d.mode);
    EXPECT_TRUE(fake.fault.gate_killed);
    // Fault status unreadable: busy.
    ASSERT_EQ(0, mc_hal_fake_inject_error(&fake, MC_HAL_FAKE_FAULT_READ, -EIO, 1u));
    EXPECT_EQ(-EBUSY, mc_drive_clear_faults(&d));
    EXPECT_EQ(MC_DRIVE_MODE_FAULT, d.mode);

    EXPECT_EQ(0, mc_drive_clear_faults(&d));
    EXPECT_FALSE(fake.fault.gate_killed);
    EXPECT_EQ(MC_DRIVE_MODE_IDLE, d.mode);
    EXPECT_EQ(MC_DRIVE_FAULT_NONE, d.faults);
    EXPECT_EQ(0u, d.first_fault);
    EXPECT_FALSE(fake.pwm3.enabled); // clearing does not restart the bridge
    // And the drive can run again.
    EXPECT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_CURRENT));
    EXPECT_TRUE(fake.pwm3.enabled);
}

TEST_F(AppDriveFault, ClearRefusedWhileVbusOutsideWindow)
{
    const float bad_vbus[] = {0.5f * kVbusMin, 2.0f * kVbusMax};
    for (float v : bad_vbus) {
        SCOPED_TRACE(v);
        InitRunning();
        Sample(0.0f, 0.0f, 0.0f, v);
        (void)mc_drive_fast_step(&d);
        ASSERT_EQ(MC_DRIVE_MODE_FAULT, d.mode);
        const uint32_t faults = d.faults;
        EXPECT_EQ(-EBUSY, mc_drive_clear_faults(&d));
        EXPECT_EQ(MC_DRIVE_MODE_FAULT, d.mode);
        EXPECT_EQ(faults, d.faults);
        // The bus comes back: the fast step keeps measuring in FAULT.
        Sample(0.0f, 0.0f, 0.0f, kVbus);
        (void)mc_drive_fast_step(&d);
        EXPECT_EQ(0, mc_drive_clear_faults(&d));
        EXPECT_EQ(MC_DRIVE_MODE_IDLE, d.mode);
        EXPECT_EQ(MC_DRIVE_FAULT_NONE, d.faults);
        EXPECT_EQ(0u, d.first_fault);
        EXPECT_FALSE(fake.pwm3.enabled);
    }
}

TEST_F(AppDriveFault, ClearRefusedBeforeAnyBusMeasurement)
{
    InitDrive();
    (void)mc_drive_fast_step(&d); // stale ADC: no vbus ever measured
    ASSERT_EQ(MC_DRIVE_FAULT_ADC, d.faults);
    EXPECT_EQ(-EBUSY, mc_drive_clear_faults(&d));
    EXPECT_EQ(MC_DRIVE_MODE_FAULT, d.mode);
}

TEST_F(AppDriveFault, ClearAcceptedAfterAFastStepFault)
{
    InitRunning();
    Sample(0.0f, 0.0f, 0.0f, kVbus);
    ASSERT_EQ(0, mc_hal_fake_inject_error(&fake, MC_HAL_FAKE_ENCODER_READ, -EIO, 1u));
    StepExpectTrip(MC_DRIVE_FAULT_ENCODER);
    EXPECT_EQ(0, mc_drive_clear_faults(&d));
    EXPECT_EQ(MC_DRIVE_MODE_IDLE, d.mode);
    EXPECT_EQ(MC_DRIVE_FAULT_NONE, d.faults);
    EXPECT_EQ(MC_FOC_ERR_NONE, d.foc_err);
    EXPECT_FALSE(fake.pwm3.enabled);
}

// hal/pwm3.h: when disable cannot confirm the outputs are off (-EIO), the
// caller must fire the gate kill. Found by this suite; fixed in mc_drive.c.
TEST_F(AppDrive, FaultFallsBackToGateKillWhenDisableFails)
{
    InitRunning();
    ASSERT_EQ(0, mc_hal_fake_adc_set_sample(&fake, 2.0f * kITrip, 0.0f, 0.0f, kVbus, kMask3));
    mc_hal_fake_inject_error(&fake, MC_HAL_FAKE_PWM3_DISABLE, -EIO, 1u);
    (void)mc_drive_fast_step(&d);
    EXPECT_EQ(MC_DRIVE_MODE_FAULT, d.mode);
    EXPECT_EQ(1u, fake.gate_kill_count);
    EXPECT_FALSE(fake.pwm3.enabled);
}

// Going to IDLE (or FAULT) zeroes the references, so the next CURRENT starts
// at no torque instead of re-applying the old one.
TEST_F(AppDrive, ReferencesZeroedOnIdleAndFault)
{
    InitRunning();
    ASSERT_NE(0.0f, d.iq_ref_a);
    EXPECT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_IDLE));
    EXPECT_EQ(0.0f, d.id_ref_a);
    EXPECT_EQ(0.0f, d.iq_ref_a);
    EXPECT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_CURRENT));
    GoodSample();
    (void)mc_drive_fast_step(&d);
    EXPECT_EQ(0.0f, d.tm.iq_ref_a);

    EXPECT_EQ(0, mc_drive_set_current_ref(&d, 1.0f, 2.0f));
    ASSERT_EQ(0, mc_hal_fake_adc_set_sample(&fake, 2.0f * kITrip, 0.0f, 0.0f, kVbus, kMask3));
    (void)mc_drive_fast_step(&d);
    ASSERT_EQ(MC_DRIVE_MODE_FAULT, d.mode);
    EXPECT_EQ(0.0f, d.id_ref_a);
    EXPECT_EQ(0.0f, d.iq_ref_a);
}

// Supervision that cannot read the fault status fails safe.
TEST_F(AppDrive, UnreadableFaultStatusIsAFault)
{
    InitRunning();
    mc_hal_fake_inject_error(&fake, MC_HAL_FAKE_FAULT_READ, -EIO, 1u);
    mc_drive_slow_step(&d);
    EXPECT_EQ(MC_DRIVE_MODE_FAULT, d.mode);
    EXPECT_EQ(MC_DRIVE_FAULT_HW_INPUT, d.faults);
    EXPECT_FALSE(fake.pwm3.enabled);
}

} // namespace
} // namespace apptest
