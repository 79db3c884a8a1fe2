// Encoder and tick capabilities through the fake, and the tick helpers.
#include <cerrno>

#include "hal_test_fixture.h"

namespace
{

TEST_F(HalFake, EncoderReadReturnsCountCprFlagsTimestamp)
{
    mc_hal_encoder_sample_t e{};
    ASSERT_EQ(0, mc_hal_encoder_read(hal->encoder, &e));
    EXPECT_EQ(0u, e.count);
    EXPECT_EQ(16384u, e.counts_per_rev);
    EXPECT_EQ(0u, e.flags); // power-up: not valid, no index yet

    ASSERT_EQ(0, mc_hal_fake_tick_set(&fake, 555u));
    ASSERT_EQ(0, mc_hal_fake_encoder_set(&fake, 16383u,
                                         MC_HAL_ENCODER_FLAG_VALID | MC_HAL_ENCODER_FLAG_INDEX));
    ASSERT_EQ(0, mc_hal_encoder_read(hal->encoder, &e));
    EXPECT_EQ(16383u, e.count); // the last count of a turn is legal
    EXPECT_EQ(16384u, e.counts_per_rev);
    EXPECT_EQ(MC_HAL_ENCODER_FLAG_VALID | MC_HAL_ENCODER_FLAG_INDEX, e.flags);
    EXPECT_EQ(555u, e.timestamp_ticks);
}

TEST_F(HalFake, EncoderSetRejectsOutOfRangeAndUnknownFlags)
{
    ASSERT_EQ(0, mc_hal_fake_encoder_set(&fake, 100u, MC_HAL_ENCODER_FLAG_VALID));
    EXPECT_EQ(-EINVAL, mc_hal_fake_encoder_set(&fake, 16384u, MC_HAL_ENCODER_FLAG_VALID));
    EXPECT_EQ(-EINVAL, mc_hal_fake_encoder_set(&fake, 5u, 1u << 2));
    EXPECT_EQ(100u, fake.encoder.count);
    EXPECT_EQ(MC_HAL_ENCODER_FLAG_VALID, fake.encoder.flags);
}

TEST_F(HalFake, EncoderInjectedEIOLeavesOutput)
{
    ASSERT_EQ(0, mc_hal_fake_inject_error(&fake, MC_HAL_FAKE_ENCODER_READ, -EIO, 1u));
    mc_hal_encoder_sample_t e{};
    e.count = 0xBEEFu;
    EXPECT_EQ(-EIO, mc_hal_encoder_read(hal->encoder, &e));
    EXPECT_EQ(0xBEEFu, e.count);
}

TEST_F(HalFake, TickReadFrequencyAndAdvance)
{
    uint32_t hz = 0;
    ASSERT_EQ(0, mc_hal_tick_get_freq_hz(hal->tick, &hz));
    EXPECT_EQ(168000000u, hz);

    uint32_t t0 = 1;
    ASSERT_EQ(0, mc_hal_tick_read(hal->tick, &t0));
    EXPECT_EQ(0u, t0);
    ASSERT_EQ(0, mc_hal_fake_tick_advance(&fake, 8400u)); // 50 us at 168 MHz
    uint32_t t1 = 0;
    ASSERT_EQ(0, mc_hal_tick_read(hal->tick, &t1));
    EXPECT_EQ(8400u, t1);
    EXPECT_EQ(50u, mc_hal_tick_to_us(mc_hal_tick_elapsed(t1, t0), hz));
}

TEST_F(HalFake, TickWrapsAndElapsedIsCorrectAcrossTheWrap)
{
    ASSERT_EQ(0, mc_hal_fake_tick_set(&fake, 0xFFFFFFF0u));
    uint32_t t0 = 0;
    ASSERT_EQ(0, mc_hal_tick_read(hal->tick, &t0));
    ASSERT_EQ(0, mc_hal_fake_tick_advance(&fake, 0x20u));
    uint32_t t1 = 0;
    ASSERT_EQ(0, mc_hal_tick_read(hal->tick, &t1));
    EXPECT_EQ(0x10u, t1); // wrapped
    EXPECT_EQ(0x20u, mc_hal_tick_elapsed(t1, t0));
}

TEST(HalTick, ElapsedHelper)
{
    EXPECT_EQ(0x20u, mc_hal_tick_elapsed(0x10u, 0xFFFFFFF0u));
    EXPECT_EQ(0u, mc_hal_tick_elapsed(5u, 5u));
    EXPECT_EQ(1u, mc_hal_tick_elapsed(0u, 0xFFFFFFFFu));
    EXPECT_EQ(0xFFFFFFFFu, mc_hal_tick_elapsed(0u, 1u)); // longest interval
    EXPECT_EQ(300u, mc_hal_tick_elapsed(1300u, 1000u));
}

TEST(HalTick, ToMicrosecondsIsExactIntegerArithmetic)
{
    // Exact: integer arithmetic, rounded down; values computed by hand.
    EXPECT_EQ(1u, mc_hal_tick_to_us(168u, 168000000u));
    EXPECT_EQ(0u, mc_hal_tick_to_us(167u, 168000000u)); // rounds down
    // Full DWT wrap at 168 MHz: 4294967295 / 168 = 25565281.5 -> 25565281 us.
    EXPECT_EQ(25565281u, mc_hal_tick_to_us(0xFFFFFFFFu, 168000000u));
    // 2^32 - 1 ticks at 1 Hz: needs 64 bits, must not overflow.
    EXPECT_EQ(4294967295000000ull, mc_hal_tick_to_us(0xFFFFFFFFu, 1u));
    EXPECT_EQ(0u, mc_hal_tick_to_us(1000u, 0u)); // no frequency, no time
}

} // namespace
