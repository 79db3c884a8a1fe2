// ADC capability through the fake: samples, missed samples, injected faults.
#include <cerrno>

#include "hal_test_fixture.h"

namespace
{

// A sentinel sample: a read that must not write its output leaves it as is.
mc_hal_adc_sample_t Sentinel()
{
    mc_hal_adc_sample_t s{};
    s.ia_a = -123.0f;
    s.ib_a = -123.0f;
    s.ic_a = -123.0f;
    s.vbus_v = -123.0f;
    s.valid_mask = 0xDEADu;
    s.timestamp_ticks = 0xDEADu;
    s.seq = 0xDEADu;
    return s;
}

void ExpectSentinel(const mc_hal_adc_sample_t &s)
{
    const mc_hal_adc_sample_t ref = Sentinel();
    EXPECT_NEAR(ref.ia_a, s.ia_a, kExact);
    EXPECT_NEAR(ref.vbus_v, s.vbus_v, kExact);
    EXPECT_EQ(ref.valid_mask, s.valid_mask);
    EXPECT_EQ(ref.seq, s.seq);
}

TEST_F(HalFake, AdcReadReturnsTheSampleWithTimestampAndSequence)
{
    ASSERT_EQ(0, mc_hal_fake_tick_set(&fake, 1000u));
    ASSERT_EQ(0,
              mc_hal_fake_adc_set_sample(&fake, 1.5f, -0.75f, -0.75f, 48.0f, MC_HAL_ADC_VALID_ALL));
    ASSERT_EQ(0, mc_hal_fake_tick_advance(&fake, 7u)); // read happens later

    mc_hal_adc_sample_t s = Sentinel();
    ASSERT_EQ(0, mc_hal_adc_read(hal->adc, &s));
    EXPECT_NEAR(1.5f, s.ia_a, kExact);
    EXPECT_NEAR(-0.75f, s.ib_a, kExact);
    EXPECT_NEAR(-0.75f, s.ic_a, kExact);
    EXPECT_NEAR(48.0f, s.vbus_v, kExact);
    EXPECT_EQ(MC_HAL_ADC_VALID_ALL, s.valid_mask);
    EXPECT_EQ(1000u, s.timestamp_ticks); // the trigger time, not the read time
    EXPECT_EQ(1u, s.seq);

    ASSERT_EQ(0, mc_hal_fake_adc_set_sample(&fake, 0.0f, 0.0f, 0.0f, 47.0f, MC_HAL_ADC_VALID_ALL));
    ASSERT_EQ(0, mc_hal_adc_read(hal->adc, &s));
    EXPECT_EQ(2u, s.seq);
    EXPECT_EQ(1007u, s.timestamp_ticks);
    EXPECT_NEAR(47.0f, s.vbus_v, kExact);
}

TEST_F(HalFake, AdcSecondReadOfTheSameConversionIsEAGAIN)
{
    mc_hal_adc_sample_t s = Sentinel();
    EXPECT_EQ(-EAGAIN, mc_hal_adc_read(hal->adc, &s)); // nothing converted yet
    ExpectSentinel(s);

    ASSERT_EQ(0, mc_hal_fake_adc_set_sample(&fake, 1.0f, 2.0f, 3.0f, 24.0f, MC_HAL_ADC_VALID_ALL));
    ASSERT_EQ(0, mc_hal_adc_read(hal->adc, &s));
    s = Sentinel();
    EXPECT_EQ(-EAGAIN, mc_hal_adc_read(hal->adc, &s));
    ExpectSentinel(s);
}

TEST_F(HalFake, AdcMissedConversionsShowAsSequenceGap)
{
    mc_hal_adc_sample_t s{};
    for (int i = 0; i < 3; ++i) {
        ASSERT_EQ(0,
                  mc_hal_fake_adc_set_sample(&fake, 0.0f, 0.0f, 0.0f, 24.0f, MC_HAL_ADC_VALID_ALL));
    }
    ASSERT_EQ(0, mc_hal_adc_read(hal->adc, &s));
    EXPECT_EQ(3u, s.seq); // two samples overwritten before the read
}

TEST_F(HalFake, AdcSequenceWraps)
{
    fake.adc_sample.seq = 0xFFFFFFFFu;
    ASSERT_EQ(0, mc_hal_fake_adc_set_sample(&fake, 0.0f, 0.0f, 0.0f, 24.0f, MC_HAL_ADC_VALID_ALL));
    mc_hal_adc_sample_t s{};
    ASSERT_EQ(0, mc_hal_adc_read(hal->adc, &s));
    EXPECT_EQ(0u, s.seq);
}

TEST_F(HalFake, AdcPartialValidMaskIsPassedThrough)
{
    // Two-shunt board: phase c is not measured.
    const uint32_t mask = MC_HAL_ADC_VALID_IA | MC_HAL_ADC_VALID_IB | MC_HAL_ADC_VALID_VBUS;
    ASSERT_EQ(0, mc_hal_fake_adc_set_sample(&fake, 1.0f, -1.0f, 0.0f, 24.0f, mask));
    mc_hal_adc_sample_t s{};
    ASSERT_EQ(0, mc_hal_adc_read(hal->adc, &s));
    EXPECT_EQ(mask, s.valid_mask);
    EXPECT_EQ(0u, s.valid_mask & MC_HAL_ADC_VALID_IC);
}

TEST_F(HalFake, AdcSetSampleRejectsUnknownValidBits)
{
    EXPECT_EQ(-EINVAL, mc_hal_fake_adc_set_sample(&fake, 1.0f, 1.0f, 1.0f, 24.0f, 1u << 4));
    EXPECT_FALSE(fake.adc_pending);
    EXPECT_EQ(0u, fake.adc_sample.seq);
    EXPECT_NEAR(0.0f, fake.adc_sample.ia_a, kExact);
}

TEST_F(HalFake, AdcInjectedEIOLeavesOutputAndKeepsSamplePending)
{
    ASSERT_EQ(0,
              mc_hal_fake_adc_set_sample(&fake, 2.0f, -1.0f, -1.0f, 24.0f, MC_HAL_ADC_VALID_ALL));
    ASSERT_EQ(0, mc_hal_fake_inject_error(&fake, MC_HAL_FAKE_ADC_READ, -EIO, 1u));
    mc_hal_adc_sample_t s = Sentinel();
    EXPECT_EQ(-EIO, mc_hal_adc_read(hal->adc, &s));
    ExpectSentinel(s);
    ASSERT_EQ(0, mc_hal_adc_read(hal->adc, &s)); // injection was one-shot
    EXPECT_NEAR(2.0f, s.ia_a, kExact);
    EXPECT_EQ(2u, fake.call_count[MC_HAL_FAKE_ADC_READ]);
}

TEST_F(HalFake, AdcTemperatures)
{
    mc_hal_adc_temp_t t{};
    // Power-up: no valid channel.
    ASSERT_EQ(0, mc_hal_adc_read_temp(hal->adc, &t));
    EXPECT_EQ(0u, t.valid_mask);

    ASSERT_EQ(0, mc_hal_fake_adc_set_temp(&fake, 45.5f, 80.25f, MC_HAL_ADC_TEMP_VALID_ALL));
    ASSERT_EQ(0, mc_hal_adc_read_temp(hal->adc, &t));
    EXPECT_NEAR(45.5f, t.power_stage_temp_c, kExact);
    EXPECT_NEAR(80.25f, t.motor_temp_c, kExact);
    EXPECT_EQ(MC_HAL_ADC_TEMP_VALID_ALL, t.valid_mask);

    EXPECT_EQ(-EINVAL, mc_hal_fake_adc_set_temp(&fake, 1.0f, 1.0f, 1u << 2));
    EXPECT_NEAR(45.5f, fake.adc_temp.power_stage_temp_c, kExact);

    ASSERT_EQ(0, mc_hal_fake_inject_error(&fake, MC_HAL_FAKE_ADC_READ_TEMP, -EIO, 1u));
    mc_hal_adc_temp_t u{};
    u.motor_temp_c = -999.0f;
    EXPECT_EQ(-EIO, mc_hal_adc_read_temp(hal->adc, &u));
    EXPECT_NEAR(-999.0f, u.motor_temp_c, kExact);
}

} // namespace
