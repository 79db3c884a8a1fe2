// Supervision added for the fail-safe drive: over-speed, implausible encoder
// step, control-deadline overrun, over-temperature, stall, external faults,
// and the validation of their parameters.
#include <cerrno>
#include <cmath>

#include <gtest/gtest.h>

#include "app_test_fixture.h"
#include "mc_record.hpp"

namespace apptest
{
namespace
{

class AppDriveSupervision : public AppDrive
{
  protected:
    void SetUp() override
    {
        AppDrive::SetUp();
        cpr = fcfg.encoder_counts_per_rev;
        cfg.omega_max_rad_s = 200.0f;
        cfg.temp_max_c = 90.0f;
        cfg.stall_current_frac = 0.8f;
        cfg.stall_speed_rad_s = 1.0f;
        cfg.stall_time_s = 0.01f;
        // Healthy temperatures unless a test says otherwise.
        ASSERT_EQ(0, mc_hal_fake_adc_set_temp(&fake, 40.0f, 40.0f, MC_HAL_ADC_TEMP_VALID_ALL));
    }
    // One step with a fresh zero-current sample stamped now.
    bool Step()
    {
        GoodSample();
        return mc_drive_fast_step(&d);
    }
    uint32_t cpr = 0;
};

TEST_F(AppDriveSupervision, ConfigRulesEachRejected)
{
    // Rejected with the one flag, and the drive left as it was.
    auto ExpectRejected = [&](const mc_drive_cfg_t &c, uint32_t want) {
        mc_drive_t probe{};
        probe.fast_count = 1234u;
        EXPECT_EQ(want, mc_drive_init(&probe, &c, hal));
        EXPECT_EQ(1234u, probe.fast_count) << "drive written on error";
    };
    const float bad[] = {-1.0f, kNaN, kInf};
    for (float v : bad) {
        for (int field = 0; field < 6; ++field) {
            mc_drive_cfg_t c = cfg;
            float *p[6] = {&c.omega_max_rad_s,   &c.temp_max_c,   &c.stall_current_frac,
                           &c.stall_speed_rad_s, &c.stall_time_s, &c.i_unbalance_max_a};
            *p[field] = v;
            ExpectRejected(c, MC_DRIVE_CFG_ERR_SUPERVISION);
        }
    }
    mc_drive_cfg_t c = cfg;
    c.stall_current_frac = 1.01f;
    ExpectRejected(c, MC_DRIVE_CFG_ERR_SUPERVISION);
    // 0 disables a check and is valid.
    c = cfg;
    c.omega_max_rad_s = c.temp_max_c = c.stall_time_s = 0.0f;
    EXPECT_EQ(MC_DRIVE_CFG_OK, mc_drive_init(&d, &c, hal));
}

TEST_F(AppDriveSupervision, OverSpeedTripsOnTheSpeedEstimate)
{
    // Turning at a constant count rate whose speed is 1.5 omega_max: the
    // tracking loop (bw 500 rad/s) passes omega_max within a few ms; each
    // step (30 counts at cpr 8192? see below) stays inside the plausible
    // encoder step, so OVERSPEED is the only fault.
    InitDrive();
    const float w = 1.5f * cfg.omega_max_rad_s;
    const double counts_per_step = w * kDt * cpr / (2.0 * M_PI);
    double pos = 0.0;
    int steps = 0;
    while (d.faults == 0u && steps < 2000) {
        pos += counts_per_step;
        const uint32_t count = static_cast<uint32_t>(std::llround(pos)) % cpr;
        ASSERT_EQ(0, mc_hal_fake_encoder_set(&fake, count, MC_HAL_ENCODER_FLAG_VALID));
        Step();
        ++steps;
    }
    EXPECT_EQ(MC_DRIVE_FAULT_OVERSPEED, d.faults);
    // Latency: a critically damped third-order loop at bw = 500 rad/s
    // reaches omega_max = w/1.5 in about 3/bw (6 ms, 120 steps); 400 steps
    // (20 ms) is a loose bound that still fails a loop that never trips.
    EXPECT_LT(steps, 400);
    mc_record("fault_bits", d.faults);
    mc_record("period_s", kDt);
    mc_record("latency_s", steps * kDt, 400 * kDt);
}

TEST_F(AppDriveSupervision, ImplausibleEncoderStepIsAnEncoderFault)
{
    InitDrive();
    Step();
    // omega_max = 200 rad/s allows 2 * 200 * 50e-6 * cpr / 2pi + 2 counts
    // per step; a quarter turn in one period is not a motion.
    ASSERT_EQ(0, mc_hal_fake_encoder_set(&fake, cpr / 4u, MC_HAL_ENCODER_FLAG_VALID));
    Step();
    EXPECT_EQ(MC_DRIVE_FAULT_ENCODER, d.faults);
}

TEST_F(AppDriveSupervision, EncoderStepsAcrossTheWrapArePlausible)
{
    InitDrive();
    ASSERT_EQ(0, mc_hal_fake_encoder_set(&fake, cpr - 2u, MC_HAL_ENCODER_FLAG_VALID));
    Step();
    ASSERT_EQ(0, mc_hal_fake_encoder_set(&fake, 3u, MC_HAL_ENCODER_FLAG_VALID));
    Step();
    EXPECT_EQ(MC_DRIVE_FAULT_NONE, d.faults);
}

TEST_F(AppDriveSupervision, DeadlineOverrun)
{
    InitDrive();
    ASSERT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_CURRENT));
    const uint32_t period_ticks = static_cast<uint32_t>(fcfg.tick_freq_hz * kDt);
    // Finishing within the period is fine...
    GoodSample();
    ASSERT_EQ(0, mc_hal_fake_tick_advance(&fake, period_ticks - 1u));
    (void)mc_drive_fast_step(&d);
    EXPECT_EQ(MC_DRIVE_FAULT_NONE, d.faults);
    // ...a step that ends more than one period after its conversion is not.
    GoodSample();
    ASSERT_EQ(0, mc_hal_fake_tick_advance(&fake, period_ticks + 1u));
    (void)mc_drive_fast_step(&d);
    EXPECT_EQ(MC_DRIVE_FAULT_OVERRUN, d.faults);
    EXPECT_FALSE(fake.pwm3.enabled);
}

TEST_F(AppDriveSupervision, OverTemperatureAndInvalidSensor)
{
    InitDrive();
    ASSERT_EQ(0, mc_hal_fake_adc_set_temp(&fake, 89.0f, 60.0f, MC_HAL_ADC_TEMP_VALID_ALL));
    mc_drive_slow_step(&d);
    EXPECT_EQ(MC_DRIVE_FAULT_NONE, d.faults);
    ASSERT_EQ(0, mc_hal_fake_adc_set_temp(&fake, 91.0f, 60.0f, MC_HAL_ADC_TEMP_VALID_ALL));
    mc_drive_slow_step(&d);
    EXPECT_EQ(MC_DRIVE_FAULT_OVERTEMP, d.faults);

    InitDrive();
    ASSERT_EQ(0, mc_hal_fake_adc_set_temp(&fake, 20.0f, 95.0f, MC_HAL_ADC_TEMP_VALID_ALL));
    mc_drive_slow_step(&d);
    EXPECT_EQ(MC_DRIVE_FAULT_OVERTEMP, d.faults) << "motor winding too hot";

    // A fitted sensor without a reading: tolerated for the grace (a board
    // converts one thermistor per slow step, so right after boot one has
    // none yet), then it trips: the limit cannot be enforced without it.
    InitDrive();
    ASSERT_EQ(0, mc_hal_fake_adc_set_temp(&fake, 20.0f, 20.0f, MC_HAL_ADC_TEMP_VALID_POWER_STAGE));
    for (uint32_t k = 0; k < MC_DRIVE_TEMP_INVALID_STEPS; ++k)
        mc_drive_slow_step(&d);
    EXPECT_EQ(MC_DRIVE_FAULT_NONE, d.faults) << "within the grace";
    mc_drive_slow_step(&d);
    EXPECT_EQ(MC_DRIVE_FAULT_OVERTEMP, d.faults) << "a missing reading cannot be trusted";

    // A reading that comes back within the grace restarts it.
    InitDrive();
    ASSERT_EQ(0, mc_hal_fake_adc_set_temp(&fake, 20.0f, 20.0f, 0u));
    for (uint32_t k = 0; k < MC_DRIVE_TEMP_INVALID_STEPS; ++k)
        mc_drive_slow_step(&d);
    ASSERT_EQ(0, mc_hal_fake_adc_set_temp(&fake, 20.0f, 20.0f, MC_HAL_ADC_TEMP_VALID_ALL));
    mc_drive_slow_step(&d);
    ASSERT_EQ(0, mc_hal_fake_adc_set_temp(&fake, 20.0f, 20.0f, 0u));
    for (uint32_t k = 0; k < MC_DRIVE_TEMP_INVALID_STEPS; ++k)
        mc_drive_slow_step(&d);
    EXPECT_EQ(MC_DRIVE_FAULT_NONE, d.faults) << "the grace counts consecutive steps";
}

TEST_F(AppDriveSupervision, TemperatureSensorTheBoardDoesNotHave)
{
    // ODrive v3.6: a power-stage thermistor, none on the motor. The motor
    // channel is absent, not invalid: the drive runs and enforces the
    // power stage's limit only (it used to trip OVERTEMP at the first slow
    // step, so that board's image could never be enabled).
    InitDrive();
    fake.adc_temp.absent_mask = MC_HAL_ADC_TEMP_VALID_MOTOR;
    ASSERT_EQ(0, mc_hal_fake_adc_set_temp(&fake, 40.0f, 0.0f, MC_HAL_ADC_TEMP_VALID_POWER_STAGE));
    for (uint32_t k = 0; k < 10u * MC_DRIVE_TEMP_INVALID_STEPS; ++k)
        mc_drive_slow_step(&d);
    EXPECT_EQ(MC_DRIVE_FAULT_NONE, d.faults);
    // an absent channel's value is ignored, whatever the HAL leaves in it
    ASSERT_EQ(0, mc_hal_fake_adc_set_temp(&fake, 40.0f, 500.0f, MC_HAL_ADC_TEMP_VALID_POWER_STAGE));
    mc_drive_slow_step(&d);
    EXPECT_EQ(MC_DRIVE_FAULT_NONE, d.faults);
    ASSERT_EQ(0, mc_hal_fake_adc_set_temp(&fake, 91.0f, 0.0f, MC_HAL_ADC_TEMP_VALID_POWER_STAGE));
    mc_drive_slow_step(&d);
    EXPECT_EQ(MC_DRIVE_FAULT_OVERTEMP, d.faults) << "the fitted sensor still trips at once";

    // A board with no temperature sensor at all cannot enforce temp_max_c:
    // it trips after the grace, as an unreadable sensor does.
    InitDrive();
    fake.adc_temp.absent_mask = MC_HAL_ADC_TEMP_VALID_ALL;
    ASSERT_EQ(0, mc_hal_fake_adc_set_temp(&fake, 0.0f, 0.0f, 0u));
    for (uint32_t k = 0; k < MC_DRIVE_TEMP_INVALID_STEPS; ++k)
        mc_drive_slow_step(&d);
    EXPECT_EQ(MC_DRIVE_FAULT_NONE, d.faults);
    mc_drive_slow_step(&d);
    EXPECT_EQ(MC_DRIVE_FAULT_OVERTEMP, d.faults);
}

TEST_F(AppDriveSupervision, StallAfterItsTime)
{
    // iq at the stall fraction of i_max with the rotor still: at theta_e =
    // offset the q axis is at offset + pi/2; currents that put 0.9 i_max on
    // it, held, trip after stall_time_s (10 ms = 20 slow steps of 0.5 ms).
    InitDrive();
    ASSERT_EQ(0, mc_drive_set_current_ref(&d, 0.0f, 0.9f * kIMax));
    ASSERT_EQ(0, mc_drive_set_mode(&d, MC_DRIVE_MODE_CURRENT));
    const float th = kOffset + 0.5f * static_cast<float>(M_PI);
    const float amp = 0.9f * kIMax;
    const float ia = amp * std::cos(th);
    const float ib = amp * std::cos(th - 2.0f * static_cast<float>(M_PI) / 3.0f);
    int slow_steps = 0;
    for (int k = 0; k < 4000 && d.faults == 0u; ++k) {
        ASSERT_EQ(0, mc_hal_fake_adc_set_sample(&fake, ia, ib, -ia - ib, kVbus, kMask3));
        if (mc_drive_fast_step(&d)) {
            mc_drive_slow_step(&d);
            ++slow_steps;
        }
    }
    EXPECT_EQ(MC_DRIVE_FAULT_STALL, d.faults);
    // Trips when the time in the condition exceeds 10 ms: after 20 slow
    // steps of 0.5 ms if the float sum of twenty 5e-4 lands above 0.01 (it
    // does, by one ulp), else after 21. Earlier means the timer is wrong.
    EXPECT_GE(slow_steps, 20);
    EXPECT_LE(slow_steps, 21);
}

TEST_F(AppDriveSupervision, UnbalancedThreePhaseCurrents)
{
    cfg.i_unbalance_max_a = 1.0f;
    InitDrive();
    ASSERT_EQ(0,
              mc_hal_fake_adc_set_sample(&fake, 5.0f, -2.0f, -2.1f, kVbus, MC_HAL_ADC_VALID_ALL));
    (void)mc_drive_fast_step(&d);
    EXPECT_EQ(MC_DRIVE_FAULT_NONE, d.faults) << "0.9 A of imbalance is inside the limit";
    ASSERT_EQ(0,
              mc_hal_fake_adc_set_sample(&fake, 5.0f, -2.0f, -1.9f, kVbus, MC_HAL_ADC_VALID_ALL));
    (void)mc_drive_fast_step(&d);
    EXPECT_EQ(MC_DRIVE_FAULT_UNBALANCED, d.faults);
}

TEST_F(AppDriveSupervision, ExternalFaultFromTheApplication)
{
    InitRunning();
    mc_drive_raise_fault(&d, MC_DRIVE_FAULT_EXTERNAL | MC_DRIVE_FAULT_ADC);
    EXPECT_EQ(MC_DRIVE_FAULT_EXTERNAL, d.faults) << "only the external bit may be raised";
    EXPECT_FALSE(fake.pwm3.enabled);
}

} // namespace
} // namespace apptest
