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

    // No index configured: the EXTI handler has nothing to do, the count
    // stays relative to power-up.
    EXPECT_FALSE(mc_f405_encoder_index_isr(&enc));
    EXPECT_EQ(tim3.CNT, 1234u);
    ASSERT_EQ(mc_hal_encoder_read(&enc.dev, &s), 0);
    EXPECT_EQ(s.flags, MC_HAL_ENCODER_FLAG_VALID);

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

namespace
{

// The ODrive v3.6's index: ENC0_Z on PC9 (port C = 2), rising edge.
struct IndexBoard : public ::testing::Test {
    mc_f405_tim_regs_t tim3{};
    mc_f405_exti_regs_t exti{};
    mc_f405_syscfg_regs_t syscfg{};
    mc_f405_encoder_t enc{};

    mc_f405_encoder_config_t cfg(uint8_t port, uint8_t pin, bool falling)
    {
        mc_f405_encoder_config_t c = enc_cfg(&tim3, nullptr);
        c.counts_per_rev = 8192u;
        c.index.p_exti = &exti;
        c.index.p_syscfg = &syscfg;
        c.index.port = port;
        c.index.pin = pin;
        c.index.falling_edge = falling;
        return c;
    }
};

} // namespace

// RM0090 §9.2.5 SYSCFG_EXTICR3 holds lines 8..11, EXTI9[7:4]; port C is
// 0010: EXTICR[2] = 0x20. §12.3: RTSR bit 9 (rising), FTSR bit 9 clear, PR
// bit 9 written 1 (clears a stale pending edge), IMR bit 9 set.
TEST_F(IndexBoard, OdriveIndexPc9RisingRegisterWrites)
{
    syscfg.EXTICR[2] = 0xF00Fu; // lines 8 and 11 belong to others: kept
    exti.FTSR = 1u << 9;        // a stale falling trigger: cleared
    exti.IMR = 1u << 3;         // another line's mask: kept
    const mc_f405_encoder_config_t c = cfg(2u, 9u, false);
    ASSERT_EQ(mc_f405_encoder_init(&enc, &c), 0);
    EXPECT_EQ(syscfg.EXTICR[2], 0xF02Fu);
    EXPECT_EQ(syscfg.EXTICR[0], 0u);
    EXPECT_EQ(exti.RTSR, 1u << 9);
    EXPECT_EQ(exti.FTSR, 0u);
    EXPECT_EQ(exti.PR, 1u << 9);
    EXPECT_EQ(exti.IMR, (1u << 9) | (1u << 3));
    EXPECT_EQ(exti.EMR, 0u);
}

// The VESC 6's index: PC8 (HW_ENC_EXTI_LINE 8): EXTICR3 bits 3:0 = 0010.
// A falling edge, on line 15 of port I (8): EXTICR4 bits 15:12 = 1000.
TEST_F(IndexBoard, LineAndPortFields)
{
    mc_f405_encoder_config_t c = cfg(2u, 8u, false);
    ASSERT_EQ(mc_f405_encoder_init(&enc, &c), 0);
    EXPECT_EQ(syscfg.EXTICR[2], 0x2u);
    EXPECT_EQ(exti.IMR, 1u << 8);

    mc_f405_exti_regs_t exti2{};
    mc_f405_syscfg_regs_t sys2{};
    c = cfg(8u, 15u, true);
    c.index.p_exti = &exti2;
    c.index.p_syscfg = &sys2;
    ASSERT_EQ(mc_f405_encoder_init(&enc, &c), 0);
    EXPECT_EQ(sys2.EXTICR[3], 0x8000u);
    EXPECT_EQ(exti2.FTSR, 1u << 15);
    EXPECT_EQ(exti2.RTSR, 0u);
}

TEST_F(IndexBoard, BadIndexConfigWritesNothing)
{
    poison(enc);
    const auto drv0 = snapshot(enc);
    mc_f405_encoder_config_t c = cfg(9u, 9u, false); // no port J on the F405
    EXPECT_EQ(mc_f405_encoder_init(&enc, &c), -EINVAL);
    c = cfg(2u, 16u, false); // EXTI lines 0..15 are the pins
    EXPECT_EQ(mc_f405_encoder_init(&enc, &c), -EINVAL);
    c = cfg(2u, 9u, false);
    c.index.p_syscfg = nullptr;
    EXPECT_EQ(mc_f405_encoder_init(&enc, &c), -EINVAL);
    EXPECT_EQ(snapshot(enc), drv0);
    EXPECT_EQ(tim3.CR1, 0u);
    EXPECT_EQ(exti.IMR, 0u);
    EXPECT_EQ(syscfg.EXTICR[2], 0u);
}

// The ISR latches CNT at the first index, masks the line and from then on
// the count is reported relative to it with the INDEX flag; the counter
// itself is never written (no edge lost).
TEST_F(IndexBoard, LatchAtTheIndexAndCountRelativeToIt)
{
    const mc_f405_encoder_config_t c = cfg(2u, 9u, false);
    ASSERT_EQ(mc_f405_encoder_init(&enc, &c), 0);
    mc_hal_encoder_sample_t s{};
    tim3.CNT = 5000u;
    ASSERT_EQ(mc_hal_encoder_read(&enc.dev, &s), 0);
    EXPECT_EQ(s.count, 5000u);
    EXPECT_EQ(s.flags, MC_HAL_ENCODER_FLAG_VALID); // not referenced yet

    // Another line of EXTI9_5 pending: not ours.
    exti.PR = 1u << 7;
    EXPECT_FALSE(mc_f405_encoder_index_isr(&enc));
    EXPECT_FALSE(enc.index_seen);

    tim3.CNT = 6000u;
    exti.PR = 1u << 9; // the hardware sets PR at the rising edge
    EXPECT_TRUE(mc_f405_encoder_index_isr(&enc));
    EXPECT_EQ(exti.PR, 1u << 9); // written 1 to clear (rc_w1)
    EXPECT_EQ(enc.index_count, 6000u);
    EXPECT_TRUE(enc.index_seen);
    EXPECT_EQ(exti.IMR & (1u << 9), 0u); // masked: found
    EXPECT_EQ(tim3.CNT, 6000u);          // never written

    tim3.CNT = 6010u;
    ASSERT_EQ(mc_hal_encoder_read(&enc.dev, &s), 0);
    EXPECT_EQ(s.count, 10u);
    EXPECT_EQ(s.flags, MC_HAL_ENCODER_FLAG_VALID | MC_HAL_ENCODER_FLAG_INDEX);
    tim3.CNT = 100u; // wrapped past 8191: 100 - 6000 + 8192
    ASSERT_EQ(mc_hal_encoder_read(&enc.dev, &s), 0);
    EXPECT_EQ(s.count, 2292u);
    tim3.CNT = 5999u; // one count before the index
    ASSERT_EQ(mc_hal_encoder_read(&enc.dev, &s), 0);
    EXPECT_EQ(s.count, 8191u);

    // A later edge with the line masked: PR set by the hardware, no
    // interrupt was raised for it, the latch stays.
    exti.PR = 1u << 9;
    tim3.CNT = 7000u;
    EXPECT_FALSE(mc_f405_encoder_index_isr(&enc));
    EXPECT_EQ(enc.index_count, 6000u);
    EXPECT_EQ(enc.index_events, 1u);

    // Re-arm for a new search: relative to power-up until the next index.
    exti.PR = 0u;
    ASSERT_EQ(mc_f405_encoder_index_rearm(&enc), 0);
    EXPECT_EQ(exti.PR, 1u << 9); // the stale edge cleared
    EXPECT_NE(exti.IMR & (1u << 9), 0u);
    ASSERT_EQ(mc_hal_encoder_read(&enc.dev, &s), 0);
    EXPECT_EQ(s.count, 7000u);
    EXPECT_EQ(s.flags, MC_HAL_ENCODER_FLAG_VALID);
    exti.PR = 1u << 9;
    tim3.CNT = 42u;
    EXPECT_TRUE(mc_f405_encoder_index_isr(&enc));
    ASSERT_EQ(mc_hal_encoder_read(&enc.dev, &s), 0);
    EXPECT_EQ(s.count, 0u);
    EXPECT_EQ(s.flags, MC_HAL_ENCODER_FLAG_VALID | MC_HAL_ENCODER_FLAG_INDEX);
    EXPECT_EQ(mc_f405_encoder_index_rearm(nullptr), -EINVAL);
}

// RM0090 table 61 (vector table): EXTI0..4 are IRQs 6..10, EXTI9_5 23,
// EXTI15_10 40.
TEST(F405Exti, IrqOfEachLine)
{
    const uint32_t want[16] = {6, 7, 8, 9, 10, 23, 23, 23, 23, 23, 40, 40, 40, 40, 40, 40};
    for (uint32_t line = 0u; line < 16u; ++line) {
        EXPECT_EQ(mc_f405_exti_irq(line), want[line]) << line;
    }
    EXPECT_EQ(mc_f405_exti_irq(16u), 0xFFFFFFFFu);
}

// Hall inputs: three IDR bits (RM0090 §8.4.5) as code bits 0..2; an
// active-low pin inverts.
TEST(F405Hall, CodeFromThreePins)
{
    mc_f405_gpio_regs_t gpioc{};
    mc_f405_gpio_regs_t gpiob{};
    mc_f405_hall_t hall{};
    mc_f405_hall_config_t c{};
    c.pin[0] = {&gpioc, 6u, false};
    c.pin[1] = {&gpioc, 7u, false};
    c.pin[2] = {&gpiob, 8u, false};
    ASSERT_EQ(mc_f405_hall_init(&hall, &c), 0);
    uint32_t code = 99u;
    gpioc.IDR = (1u << 6);
    gpiob.IDR = (1u << 8) | (1u << 7); // PB7 is not a Hall pin
    ASSERT_EQ(mc_hal_hall_read(&hall.dev, &code), 0);
    EXPECT_EQ(code, 5u); // A and C
    gpioc.IDR = (1u << 7);
    gpiob.IDR = 0u;
    ASSERT_EQ(mc_hal_hall_read(&hall.dev, &code), 0);
    EXPECT_EQ(code, 2u);
    c.pin[1].active_low = true;
    ASSERT_EQ(mc_f405_hall_init(&hall, &c), 0);
    ASSERT_EQ(mc_hal_hall_read(&hall.dev, &code), 0);
    EXPECT_EQ(code, 0u);
    EXPECT_EQ(mc_hal_hall_read(&hall.dev, nullptr), -EINVAL);
    c.pin[2].p_port = nullptr;
    EXPECT_EQ(mc_f405_hall_init(&hall, &c), -EINVAL);
    c.pin[2] = {&gpiob, 16u, false};
    EXPECT_EQ(mc_f405_hall_init(&hall, &c), -EINVAL);
}
