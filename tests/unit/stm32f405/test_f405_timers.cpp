// encoder (TIMx encoder mode) and tick (TIM2 free running) against register
// files in RAM. Register facts: RM0090 §18.4 (TIM2..TIM5).
#include <gtest/gtest.h>

#include "f405_test_util.h"

namespace
{

mc_f405_encoder_config_t enc_cfg(mc_f405_tim_regs_t *tim, const mc_hal_tick_t *tick)
{
    mc_f405_encoder_config_t c{};
    c.p_tim = tim;
    c.counts_per_rev = 4096u; // 1024-line encoder, x4
    c.counter_32bit = false;
    c.input_filter = 6u;
    c.invert = false;
    c.p_tick = tick;
    return c;
}

} // namespace

TEST(F405Tick, Tim2At1MHz)
{
    mc_f405_tim_regs_t tim2{};
    mc_f405_tick_t tick;
    // APB1 timer clock 84 MHz, PSC = 83 -> 1 MHz.
    const mc_f405_tick_config_t c{&tim2, 84000000u, 83u};
    ASSERT_EQ(mc_f405_tick_init(&tick, &c), 0);
    EXPECT_EQ(tim2.PSC, 83u);
    EXPECT_EQ(tim2.ARR, 0xFFFFFFFFu);
    EXPECT_EQ(tim2.CR1, MC_F405_TIM_CR1_CEN); // up-counting, no other mode
    EXPECT_EQ(tim2.SMCR, 0u);
    EXPECT_EQ(tim2.EGR, MC_F405_TIM_EGR_UG);

    uint32_t hz = 0u;
    ASSERT_EQ(mc_hal_tick_get_freq_hz(&tick.dev, &hz), 0);
    EXPECT_EQ(hz, 1000000u);
    tim2.CNT = 0xFFFFFFF0u; // the hardware counts
    uint32_t t = 0u;
    ASSERT_EQ(mc_hal_tick_read(&tick.dev, &t), 0);
    EXPECT_EQ(t, 0xFFFFFFF0u);
}

TEST(F405Tick, InvalidConfig)
{
    mc_f405_tim_regs_t tim2{};
    mc_f405_tick_t tick;
    poison(tick);
    const auto drv0 = snapshot(tick);
    const mc_f405_tick_config_t c1{&tim2, 0u, 0u};
    EXPECT_EQ(mc_f405_tick_init(&tick, &c1), -EINVAL);
    const mc_f405_tick_config_t c2{&tim2, 84000000u, 0x10000u};
    EXPECT_EQ(mc_f405_tick_init(&tick, &c2), -EINVAL);
    const mc_f405_tick_config_t c3{nullptr, 84000000u, 0u};
    EXPECT_EQ(mc_f405_tick_init(&tick, &c3), -EINVAL);
    EXPECT_EQ(snapshot(tick), drv0);
    EXPECT_EQ(tim2.CR1, 0u);
}

// Encoder mode 3 (SMS = 011: count on both edges of TI1 and TI2 = x4),
// CC1S = CC2S = 01 (IC1 <- TI1, IC2 <- TI2), filter ICxF in bits 7:4 and
// 15:12, ARR = counts_per_rev - 1.
TEST(F405Encoder, InitRegisterWrites)
{
    mc_f405_tim_regs_t tim3{};
    mc_f405_encoder_t enc;
    const mc_f405_encoder_config_t c = enc_cfg(&tim3, nullptr);
    ASSERT_EQ(mc_f405_encoder_init(&enc, &c), 0);
    EXPECT_EQ(tim3.SMCR, 3u);
    EXPECT_EQ(tim3.CCMR1, 0x01u | (6u << 4) | 0x100u | (6u << 12));
    EXPECT_EQ(tim3.CCER, 0u);
    EXPECT_EQ(tim3.PSC, 0u);
    EXPECT_EQ(tim3.ARR, 4095u);
    EXPECT_EQ(tim3.CNT, 0u);
    EXPECT_EQ(tim3.CR1, MC_F405_TIM_CR1_CEN);

    mc_f405_encoder_t enc2;
    mc_f405_encoder_config_t c2 = enc_cfg(&tim3, nullptr);
    c2.invert = true;
    ASSERT_EQ(mc_f405_encoder_init(&enc2, &c2), 0);
    EXPECT_EQ(tim3.CCER, 1u << 1); // CC1P: TI1 inverted, direction flips
}

TEST(F405Encoder, ReadCountIndexAndTimestamp)
{
    mc_f405_tim_regs_t tim3{};
    mc_f405_tim_regs_t tim2{};
    mc_f405_tick_t tick;
    const mc_f405_tick_config_t tc{&tim2, 84000000u, 0u};
    ASSERT_EQ(mc_f405_tick_init(&tick, &tc), 0);
    mc_f405_encoder_t enc;
    const mc_f405_encoder_config_t c = enc_cfg(&tim3, &tick.dev);
    ASSERT_EQ(mc_f405_encoder_init(&enc, &c), 0);

    tim3.CNT = 1234u;
    tim2.CNT = 999u;
    mc_hal_encoder_sample_t s{};
    ASSERT_EQ(mc_hal_encoder_read(&enc.dev, &s), 0);
    EXPECT_EQ(s.count, 1234u);
    EXPECT_EQ(s.counts_per_rev, 4096u);
    EXPECT_EQ(s.flags, MC_HAL_ENCODER_FLAG_VALID);
    EXPECT_EQ(s.timestamp_ticks, 999u);

    mc_f405_encoder_index_isr(&enc);
    EXPECT_EQ(tim3.CNT, 0u);
    tim3.CNT = 7u;
    ASSERT_EQ(mc_hal_encoder_read(&enc.dev, &s), 0);
    EXPECT_EQ(s.count, 7u);
    EXPECT_EQ(s.flags, MC_HAL_ENCODER_FLAG_VALID | MC_HAL_ENCODER_FLAG_INDEX);

    tim3.CNT = 5000u; // beyond ARR: impossible for a working timer
    ASSERT_EQ(mc_hal_encoder_read(&enc.dev, &s), 0);
    EXPECT_EQ(s.flags & MC_HAL_ENCODER_FLAG_VALID, 0u);

    tim3.CR1 = 0u; // counter stopped
    s.count = 42u;
    EXPECT_EQ(mc_hal_encoder_read(&enc.dev, &s), -EIO);
    EXPECT_EQ(s.count, 42u);
}

TEST(F405Encoder, CountsPerRevLimits)
{
    mc_f405_tim_regs_t tim{};
    mc_f405_encoder_t enc;
    poison(enc);
    const auto drv0 = snapshot(enc);
    mc_f405_encoder_config_t c = enc_cfg(&tim, nullptr);
    c.counts_per_rev = 65537u; // ARR would need 17 bits on TIM3/TIM4
    EXPECT_EQ(mc_f405_encoder_init(&enc, &c), -EINVAL);
    c.counts_per_rev = 0u;
    EXPECT_EQ(mc_f405_encoder_init(&enc, &c), -EINVAL);
    c = enc_cfg(&tim, nullptr);
    c.input_filter = 16u;
    EXPECT_EQ(mc_f405_encoder_init(&enc, &c), -EINVAL);
    EXPECT_EQ(snapshot(enc), drv0);
    EXPECT_EQ(tim.CR1, 0u);

    c = enc_cfg(&tim, nullptr);
    c.counts_per_rev = 65536u; // ARR = 0xFFFF: still fits
    EXPECT_EQ(mc_f405_encoder_init(&enc, &c), 0);
    EXPECT_EQ(tim.ARR, 0xFFFFu);
    c.counts_per_rev = 100000u; // TIM2/TIM5 32-bit counter
    c.counter_32bit = true;
    EXPECT_EQ(mc_f405_encoder_init(&enc, &c), 0);
    EXPECT_EQ(tim.ARR, 99999u);
}
