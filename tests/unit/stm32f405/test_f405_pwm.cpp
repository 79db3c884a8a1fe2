// pwm3 on TIM1 and pwm2 on TIM8 against register files in RAM. Expected
// register values are worked out from RM0090 §17.4 in the comments.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "f405_test_util.h"

namespace
{

constexpr uint32_t kTimClkHz = 168000000u; // APB2 timer clock at 168 MHz SYSCLK

mc_f405_pwm3_config_t pwm3_cfg(mc_f405_tim_regs_t *tim)
{
    mc_f405_pwm3_config_t c{};
    c.p_tim = tim;
    c.tim_clk_hz = kTimClkHz;
    c.pwm_freq_hz = 20000u;
    c.deadtime_ns = 500u;
    c.adc_trigger_lead_ticks = 8u;
    c.adc_trigger = MC_F405_ADC_TRIG_TIM1_TRGO;
    c.break_enable = true;
    c.break_active_high = false; // nFAULT-style, active low
    c.high_side_active_low = false;
    c.low_side_active_low = false;
    c.p_fault = nullptr;
    return c;
}

// DTG decoding straight from the RM0090 §17.4.18 table, in tDTS units.
uint32_t dtg_ticks(uint32_t dtg)
{
    if ((dtg & 0x80u) == 0u) {
        return dtg & 0x7Fu;
    }
    if ((dtg & 0xC0u) == 0x80u) {
        return (64u + (dtg & 0x3Fu)) * 2u;
    }
    if ((dtg & 0xE0u) == 0xC0u) {
        return (32u + (dtg & 0x1Fu)) * 8u;
    }
    return (32u + (dtg & 0x1Fu)) * 16u;
}

} // namespace

// ---- dead time ----------------------------------------------------------

// Hand-worked values at 168 MHz (tDTS = 5.952 ns):
//  500 ns = 84 tDTS        -> DTG = 84 = 0x54 (first range, exact)
// 1000 ns = 168 tDTS       -> 2 x (64 + 20): DTG = 0x80 | 20 = 0x94
// 2000 ns = 336 tDTS       -> 8 x (32 + 10): DTG = 0xC0 | 10 = 0xCA
// 4000 ns = 672 tDTS       -> 16 x (32 + 10): DTG = 0xE0 | 10 = 0xEA
//  100 ns = 16.8 -> 17 tDTS (rounded up) -> 0x11, 101.19 ns -> 101
TEST(F405Deadtime, HandWorkedValuesAt168MHz)
{
    struct Case {
        uint32_t ns, dtg, actual_ns;
    };
    const Case cases[] = {
        {500u, 0x54u, 500u},   {1000u, 0x94u, 1000u}, {2000u, 0xCAu, 2000u},
        {4000u, 0xEAu, 4000u}, {100u, 0x11u, 101u},   {6000u, 0xFFu, 6000u},
    };
    for (const Case &c : cases) {
        uint32_t dtg = 0u;
        uint32_t actual = 0u;
        ASSERT_EQ(mc_f405_deadtime_encode(c.ns, kTimClkHz, &dtg, &actual), 0) << c.ns;
        EXPECT_EQ(dtg, c.dtg) << c.ns;
        EXPECT_EQ(actual, c.actual_ns) << c.ns;
    }
}

// For every dead time 1..6000 ns the encoding is the shortest DTG value
// that is not shorter than asked (brute force over all 256 codes).
TEST(F405Deadtime, ShortestCodeNotBelowRequestExhaustive)
{
    for (uint32_t ns = 1u; ns <= 6000u; ++ns) {
        const uint64_t need = (static_cast<uint64_t>(ns) * kTimClkHz + 999999999u) / 1000000000u;
        uint32_t best = 0xFFFFFFFFu;
        for (uint32_t code = 0u; code < 256u; ++code) {
            const uint32_t t = dtg_ticks(code);
            if (t >= need && t < best) {
                best = t;
            }
        }
        uint32_t dtg = 0u;
        ASSERT_EQ(mc_f405_deadtime_encode(ns, kTimClkHz, &dtg, nullptr), 0) << ns;
        ASSERT_EQ(dtg_ticks(dtg), best) << ns;
    }
}

TEST(F405Deadtime, RejectsZeroAndTooLong)
{
    uint32_t dtg = 7u;
    EXPECT_EQ(mc_f405_deadtime_encode(0u, kTimClkHz, &dtg, nullptr), -EINVAL);
    EXPECT_EQ(mc_f405_deadtime_encode(6001u, kTimClkHz, &dtg, nullptr), -EINVAL); // > 1008 tDTS
    EXPECT_EQ(mc_f405_deadtime_encode(500u, 0u, &dtg, nullptr), -EINVAL);
    EXPECT_EQ(mc_f405_deadtime_encode(500u, kTimClkHz, nullptr, nullptr), -EINVAL);
    EXPECT_EQ(dtg, 7u);
}

// ---- pwm3 configuration ---------------------------------------------------

// 20 kHz centre-aligned at 168 MHz: period = 2 ARR / 168e6 -> ARR = 4200,
// PSC = 0. Registers per RM0090 §17.4.
TEST(F405Pwm3, InitRegisterWrites20kHz)
{
    mc_f405_tim_regs_t tim{};
    mc_f405_pwm3_t pwm;
    const mc_f405_pwm3_config_t cfg = pwm3_cfg(&tim);

    ASSERT_EQ(mc_f405_pwm3_init(&pwm, &cfg), 0);

    EXPECT_EQ(tim.PSC, 0u);
    EXPECT_EQ(tim.ARR, 4200u);
    EXPECT_EQ(tim.RCR, 1u); // one update event per PWM period
    // CR1: CMS = 01 (centre-aligned mode 1, bits 6:5), ARPE (bit 7), CEN.
    EXPECT_EQ(tim.CR1, (1u << 5) | (1u << 7) | 1u);
    EXPECT_EQ(tim.CR1 & MC_F405_TIM_CR1_CMS_MASK, 1u << 5);
    // CCMR1: OC1M = OC2M = 110 (PWM mode 1) with OCxPE: 0x68 per channel.
    EXPECT_EQ(tim.CCMR1, 0x6868u);
    // CCMR2: OC3 PWM mode 1 + PE (0x68), OC4M = 111 (PWM mode 2) + PE (0x78).
    EXPECT_EQ(tim.CCMR2, 0x7868u);
    // CCER: CC1E|CC1NE, CC2E|CC2NE, CC3E|CC3NE (bits 0,2,4,6,8,10), no
    // polarity inversion, CC4 output off (TRGO trigger needs no CC4E).
    EXPECT_EQ(tim.CCER, 0x0555u);
    // CR2: MMS = 111, TRGO = OC4REF; idle states OISx = 0.
    EXPECT_EQ(tim.CR2, 7u << 4);
    // BDTR: DTG = 0x54 (500 ns), OSSI (bit 10), OSSR (bit 11), BKE (12),
    // BKP = 0 (break active low), AOE = 0, MOE = 0: outputs off.
    EXPECT_EQ(tim.BDTR, 0x54u | (1u << 10) | (1u << 11) | (1u << 12));
    EXPECT_EQ(tim.BDTR & MC_F405_TIM_BDTR_MOE, 0u);
    // Zero vector, ADC trigger 8 ticks before the counter peak.
    EXPECT_EQ(tim.CCR1, 2100u);
    EXPECT_EQ(tim.CCR2, 2100u);
    EXPECT_EQ(tim.CCR3, 2100u);
    EXPECT_EQ(tim.CCR4, 4192u);
    EXPECT_EQ(tim.EGR, MC_F405_TIM_EGR_UG);

    mc_hal_pwm3_state_t st{};
    ASSERT_EQ(mc_hal_pwm3_get_state(&pwm.dev, &st), 0);
    EXPECT_FALSE(st.enabled);
    EXPECT_EQ(st.duty_a, MC_HAL_PWM3_DUTY_INIT);
    // 50 us; float of 8400/168e6, tolerance: one float rounding of 5e-5.
    EXPECT_NEAR(st.period_s, 50e-6, 1e-11);
}

TEST(F405Pwm3, PolarityBreakHighAndCc4Trigger)
{
    mc_f405_tim_regs_t tim{};
    mc_f405_pwm3_t pwm;
    mc_f405_pwm3_config_t cfg = pwm3_cfg(&tim);
    cfg.break_active_high = true;
    cfg.high_side_active_low = true;
    cfg.low_side_active_low = true;
    cfg.adc_trigger = MC_F405_ADC_TRIG_TIM1_CC4;
    cfg.deadtime_ns = 1000u;

    ASSERT_EQ(mc_f405_pwm3_init(&pwm, &cfg), 0);
    // Every CCxP and CCxNP of channels 1..3 (0xFFF) plus CC4E (bit 12).
    EXPECT_EQ(tim.CCER, 0x0FFFu | (1u << 12));
    // DTG 0x94 (1 us), BKP (bit 13) set for an active-high break.
    EXPECT_EQ(tim.BDTR, 0x94u | (1u << 10) | (1u << 11) | (1u << 12) | (1u << 13));
}

// 1 kHz needs half a period of 84000 ticks > 65535: PSC = 1 (divide by 2),
// ARR = 42000.
TEST(F405Pwm3, LowFrequencyUsesPrescaler)
{
    mc_f405_tim_regs_t tim{};
    mc_f405_pwm3_t pwm;
    mc_f405_pwm3_config_t cfg = pwm3_cfg(&tim);
    cfg.pwm_freq_hz = 1000u;

    ASSERT_EQ(mc_f405_pwm3_init(&pwm, &cfg), 0);
    EXPECT_EQ(tim.PSC, 1u);
    EXPECT_EQ(tim.ARR, 42000u);
    mc_hal_pwm3_state_t st{};
    ASSERT_EQ(mc_hal_pwm3_get_state(&pwm.dev, &st), 0);
    EXPECT_NEAR(st.period_s, 1e-3, 1e-9); // float rounding of 1e-3
}

TEST(F405Pwm3, InvalidConfigWritesNothing)
{
    mc_f405_tim_regs_t tim{};
    mc_f405_pwm3_t pwm;
    poison(pwm);
    const auto regs0 = snapshot(tim);
    const auto drv0 = snapshot(pwm);

    mc_f405_pwm3_config_t cfg = pwm3_cfg(&tim);
    cfg.pwm_freq_hz = 1000000u; // ARR = 84 < 100: too coarse
    EXPECT_EQ(mc_f405_pwm3_init(&pwm, &cfg), -EINVAL);
    cfg = pwm3_cfg(&tim);
    cfg.deadtime_ns = 7000u; // > 1008 tDTS
    EXPECT_EQ(mc_f405_pwm3_init(&pwm, &cfg), -EINVAL);
    cfg = pwm3_cfg(&tim);
    cfg.deadtime_ns = 0u;
    EXPECT_EQ(mc_f405_pwm3_init(&pwm, &cfg), -EINVAL);
    cfg = pwm3_cfg(&tim);
    cfg.adc_trigger_lead_ticks = 4200u; // must be < ARR
    EXPECT_EQ(mc_f405_pwm3_init(&pwm, &cfg), -EINVAL);
    cfg = pwm3_cfg(&tim);
    cfg.adc_trigger_lead_ticks = 0u;
    EXPECT_EQ(mc_f405_pwm3_init(&pwm, &cfg), -EINVAL);
    cfg = pwm3_cfg(&tim);
    cfg.pwm_freq_hz = 0u;
    EXPECT_EQ(mc_f405_pwm3_init(&pwm, &cfg), -EINVAL);
    cfg = pwm3_cfg(nullptr);
    EXPECT_EQ(mc_f405_pwm3_init(&pwm, &cfg), -EINVAL);

    EXPECT_EQ(snapshot(tim), regs0);
    EXPECT_EQ(snapshot(pwm), drv0);
}

// ---- pwm3 on TIM8 (a second axis) -------------------------------------------

// The ODrive v3.6's M1: TIM8, 24 kHz (ARR = 168e6 / (2 x 24000) = 3500),
// 119 ns dead time = 19.99 -> 20 tDTS (DTG 0x14, rounded up), no break
// input, ADC trigger = TIM8 CC4 168 ticks (1 us) before the peak. TIM8 has
// TIM1's register layout (RM0090 §17), so the values are TIM1's but for
// CC4E: the CC4 event reaches the ADC only with the channel enabled.
TEST(F405Pwm3, Tim8Cc4TriggerRegisterWrites)
{
    mc_f405_tim_regs_t tim8{};
    mc_f405_pwm3_t pwm;
    mc_f405_pwm3_config_t cfg = pwm3_cfg(&tim8);
    cfg.tim = MC_F405_ADV_TIM8;
    cfg.pwm_freq_hz = 24000u;
    cfg.deadtime_ns = 119u;
    cfg.adc_trigger_lead_ticks = 168u;
    cfg.adc_trigger = MC_F405_ADC_TRIG_TIM8_CC4;
    cfg.break_enable = false;

    ASSERT_EQ(mc_f405_pwm3_init(&pwm, &cfg), 0);
    EXPECT_EQ(tim8.PSC, 0u);    // 3500 fits 16 bits: no prescaler
    EXPECT_EQ(tim8.ARR, 3500u); // 168e6 / (2 x 24e3), exact
    EXPECT_EQ(tim8.RCR, 1u);    // one update (duty load) per period
    // CR1: CMS = 01 (centre-aligned 1), ARPE, CEN: 0xA1, as on TIM1.
    EXPECT_EQ(tim8.CR1, (1u << 5) | (1u << 7) | 1u);
    EXPECT_EQ(tim8.CCMR1, 0x6868u); // OC1/OC2 PWM mode 1 + preload
    EXPECT_EQ(tim8.CCMR2, 0x7868u); // OC3 PWM mode 1, OC4 PWM mode 2 (rises at CCR4 up-counting)
    // CCER: the three complementary pairs (0x555) and CC4E (bit 12): the
    // CC4 event is the ADC2 trigger.
    EXPECT_EQ(tim8.CCER, 0x0555u | (1u << 12));
    // BDTR: DTG 0x14, OSSI, OSSR; BKE clear (TIM8_BKIN would be PA6, the
    // bus-voltage pin); MOE clear: outputs off.
    EXPECT_EQ(tim8.BDTR, 0x14u | (1u << 10) | (1u << 11));
    EXPECT_EQ(tim8.CCR4, 3500u - 168u); // trigger 168 ticks = 1 us before the peak
    EXPECT_EQ(tim8.CCR1, 1750u);        // zero vector: 50 %
    EXPECT_EQ(pwm.dev.ctx, &pwm);
}

// An ADC trigger is one of the pwm's own timer's events: a TIM1 trigger on
// TIM8 or TIM8's on TIM1 would start the conversions at the other axis'
// instant. Refused, nothing written. An enum value past the last is refused
// on either timer.
TEST(F405Pwm3, TriggerOfTheOtherTimerRefused)
{
    mc_f405_tim_regs_t tim{};
    mc_f405_pwm3_t pwm;
    poison(pwm);
    const auto regs0 = snapshot(tim);
    const auto drv0 = snapshot(pwm);

    mc_f405_pwm3_config_t cfg = pwm3_cfg(&tim);
    cfg.tim = MC_F405_ADV_TIM8;
    cfg.adc_trigger = MC_F405_ADC_TRIG_TIM1_TRGO;
    EXPECT_EQ(mc_f405_pwm3_init(&pwm, &cfg), -EINVAL);
    cfg.adc_trigger = MC_F405_ADC_TRIG_TIM1_CC4;
    EXPECT_EQ(mc_f405_pwm3_init(&pwm, &cfg), -EINVAL);
    cfg = pwm3_cfg(&tim);
    cfg.adc_trigger = MC_F405_ADC_TRIG_TIM8_CC4; // on TIM1
    EXPECT_EQ(mc_f405_pwm3_init(&pwm, &cfg), -EINVAL);
    cfg.adc_trigger = static_cast<mc_f405_adc_trigger_t>(3);
    EXPECT_EQ(mc_f405_pwm3_init(&pwm, &cfg), -EINVAL);
    cfg.tim = MC_F405_ADV_TIM8;
    EXPECT_EQ(mc_f405_pwm3_init(&pwm, &cfg), -EINVAL);
    cfg.tim = static_cast<mc_f405_adv_tim_t>(2);
    cfg.adc_trigger = MC_F405_ADC_TRIG_TIM1_TRGO;
    EXPECT_EQ(mc_f405_pwm3_init(&pwm, &cfg), -EINVAL);

    EXPECT_EQ(snapshot(tim), regs0);
    EXPECT_EQ(snapshot(pwm), drv0);
}

namespace
{

// M0 on TIM1 and M1 on TIM8 at 24 kHz (ARR 3500), the triggers 168 ticks
// before each peak.
struct TwoAxes : public ::testing::Test {
    mc_f405_tim_regs_t tim1{};
    mc_f405_tim_regs_t tim8{};
    mc_f405_pwm3_t m0{};
    mc_f405_pwm3_t m1{};

    void SetUp() override
    {
        mc_f405_pwm3_config_t c0 = pwm3_cfg(&tim1);
        c0.pwm_freq_hz = 24000u;
        c0.adc_trigger_lead_ticks = 168u;
        ASSERT_EQ(mc_f405_pwm3_init(&m0, &c0), 0);
        mc_f405_pwm3_config_t c1 = c0;
        c1.p_tim = &tim8;
        c1.tim = MC_F405_ADV_TIM8;
        c1.adc_trigger = MC_F405_ADC_TRIG_TIM8_CC4;
        ASSERT_EQ(mc_f405_pwm3_init(&m1, &c1), 0);
        tim1.CNT = 1234u; // running since init
        tim8.CNT = 77u;
        tim1.EGR = 0u;
        tim8.EGR = 0u;
    }
};

// Ticks until a centre-aligned counter that starts at `cnt` counting up
// next reaches `v` while counting up (RM0090 §17.3.2: up to ARR, down to
// 0, up again).
uint32_t ticks_to_up_crossing(uint32_t cnt, uint32_t v, uint32_t arr)
{
    return (v >= cnt) ? (v - cnt) : ((arr - cnt) + arr + v);
}

} // namespace

// The board's phase: lag = ARR - 1 = 3499. Both counters restarted by an
// update event (EGR = UG on each), the leader loaded with 3499, the lagger
// with 0, both running again with their CR1 modes kept.
TEST_F(TwoAxes, StartPhasedLoadsTheCounters)
{
    const uint32_t cr1 = tim1.CR1;
    ASSERT_EQ(mc_f405_pwm3_start_phased(&m0, &m1, m0.arr - 1u), 0);
    EXPECT_EQ(tim1.CNT, 3499u);
    EXPECT_EQ(tim8.CNT, 0u);
    EXPECT_EQ(tim1.EGR, MC_F405_TIM_EGR_UG); // prescaler, repetition counter reset
    EXPECT_EQ(tim8.EGR, MC_F405_TIM_EGR_UG);
    EXPECT_EQ(tim1.CR1, cr1); // centre-aligned 1, ARPE, CEN: running again
    EXPECT_EQ(tim8.CR1, cr1);
    EXPECT_EQ(tim1.BDTR & MC_F405_TIM_BDTR_MOE, 0u); // outputs untouched (off)
    EXPECT_EQ(tim8.BDTR & MC_F405_TIM_BDTR_MOE, 0u);

    // Where the triggers fall (counter model, exact integers): M0's CC4
    // (CCR4 = 3332, counting up) 3332 - 3499 -> after the peak, so the next
    // one is (3500 - 3499) + 3500 + 3332 = 6833 ticks on; M1's 3332 ticks
    // on. M1 samples 3499 ticks after M0's previous trigger (M0's period is
    // 7000): half a period less one tick, the lag loaded.
    const uint32_t t0 = ticks_to_up_crossing(tim1.CNT, tim1.CCR4, m0.arr);
    const uint32_t t1 = ticks_to_up_crossing(tim8.CNT, tim8.CCR4, m1.arr);
    EXPECT_EQ(t0, 6833u);
    EXPECT_EQ(t1, 3332u);
    EXPECT_EQ(t1 + 2u * m0.arr - t0, 3499u);
    // At M1's trigger M0's counter is counting down at lead + 1 = 169 ticks
    // above its valley: M0 switches there only at duties below 169 / 3500
    // = 4.8 %, the other axis' sample sees no edge of M0 above that.
    const uint32_t m0_at_t1 = m0.arr - (t1 - (m0.arr - tim1.CNT));
    EXPECT_EQ(m0_at_t1, 169u);
}

// Refusals write nothing: the same timer twice, lag >= ARR (the counters
// start counting up, so ARR - 1 is the largest loadable lag), NULL, and two
// timers at different rates (the phase would drift).
TEST_F(TwoAxes, StartPhasedRefusals)
{
    const auto r1 = snapshot(tim1);
    const auto r8 = snapshot(tim8);
    EXPECT_EQ(mc_f405_pwm3_start_phased(&m0, &m0, 10u), -EINVAL);
    EXPECT_EQ(mc_f405_pwm3_start_phased(&m0, &m1, m0.arr), -EINVAL);
    EXPECT_EQ(mc_f405_pwm3_start_phased(nullptr, &m1, 10u), -EINVAL);
    EXPECT_EQ(mc_f405_pwm3_start_phased(&m0, nullptr, 10u), -EINVAL);
    mc_f405_tim_regs_t tim8b{};
    mc_f405_pwm3_t m1b{};
    mc_f405_pwm3_config_t c = m1.cfg;
    c.p_tim = &tim8b;
    c.pwm_freq_hz = 20000u; // ARR 4200
    ASSERT_EQ(mc_f405_pwm3_init(&m1b, &c), 0);
    EXPECT_EQ(mc_f405_pwm3_start_phased(&m0, &m1b, 10u), -EINVAL);
    EXPECT_EQ(snapshot(tim1), r1);
    EXPECT_EQ(snapshot(tim8), r8);
    EXPECT_EQ(tim8b.CNT, 0u);
}

// ---- pwm3 behaviour ----------------------------------------------------------

TEST(F405Pwm3, DutyToCompareRegisters)
{
    mc_f405_tim_regs_t tim{};
    mc_f405_pwm3_t pwm;
    const mc_f405_pwm3_config_t cfg = pwm3_cfg(&tim);
    ASSERT_EQ(mc_f405_pwm3_init(&pwm, &cfg), 0);

    // CCR = round(d * ARR): 0.25 * 4200 = 1050, 0.1 * 4200 = 420 (float
    // 0.1 * 4200 = 420.00000x rounds to 420), 1 -> 4200.
    ASSERT_EQ(mc_hal_pwm3_set_duty(&pwm.dev, 0.25f, 0.1f, 1.0f), 0);
    EXPECT_EQ(tim.CCR1, 1050u);
    EXPECT_EQ(tim.CCR2, 420u);
    EXPECT_EQ(tim.CCR3, 4200u);
    ASSERT_EQ(mc_hal_pwm3_set_duty(&pwm.dev, 0.0f, 0.5f, 0.75f), 0);
    EXPECT_EQ(tim.CCR1, 0u);
    EXPECT_EQ(tim.CCR2, 2100u);
    EXPECT_EQ(tim.CCR3, 3150u);
    EXPECT_EQ(tim.CCR4, 4192u); // the ADC trigger never moves

    mc_hal_pwm3_state_t st{};
    ASSERT_EQ(mc_hal_pwm3_get_state(&pwm.dev, &st), 0);
    EXPECT_EQ(st.duty_a, 0.0f);
    EXPECT_EQ(st.duty_b, 0.5f);
    EXPECT_EQ(st.duty_c, 0.75f);
}

TEST(F405Pwm3, InvalidDutyChangesNoRegister)
{
    mc_f405_tim_regs_t tim{};
    mc_f405_pwm3_t pwm;
    const mc_f405_pwm3_config_t cfg = pwm3_cfg(&tim);
    ASSERT_EQ(mc_f405_pwm3_init(&pwm, &cfg), 0);
    ASSERT_EQ(mc_hal_pwm3_set_duty(&pwm.dev, 0.2f, 0.3f, 0.4f), 0);
    const auto regs0 = snapshot(tim);

    const float nan = std::numeric_limits<float>::quiet_NaN();
    const float inf = std::numeric_limits<float>::infinity();
    EXPECT_EQ(mc_hal_pwm3_set_duty(&pwm.dev, 0.5f, 0.5f, 1.0001f), -EINVAL);
    EXPECT_EQ(mc_hal_pwm3_set_duty(&pwm.dev, -0.001f, 0.5f, 0.5f), -EINVAL);
    EXPECT_EQ(mc_hal_pwm3_set_duty(&pwm.dev, 0.5f, nan, 0.5f), -EINVAL);
    EXPECT_EQ(mc_hal_pwm3_set_duty(&pwm.dev, 0.5f, 0.5f, inf), -EINVAL);
    EXPECT_EQ(snapshot(tim), regs0); // all three checked before any write

    mc_hal_pwm3_state_t st{};
    ASSERT_EQ(mc_hal_pwm3_get_state(&pwm.dev, &st), 0);
    EXPECT_EQ(st.duty_a, 0.2f);
    EXPECT_EQ(st.duty_b, 0.3f);
    EXPECT_EQ(st.duty_c, 0.4f);
}

TEST(F405Pwm3, EnableSetsMoeDisableClearsIt)
{
    mc_f405_tim_regs_t tim{};
    mc_f405_pwm3_t pwm;
    const mc_f405_pwm3_config_t cfg = pwm3_cfg(&tim);
    ASSERT_EQ(mc_f405_pwm3_init(&pwm, &cfg), 0);
    const uint32_t bdtr_off = tim.BDTR;

    ASSERT_EQ(mc_hal_pwm3_enable(&pwm.dev), 0);
    EXPECT_EQ(tim.BDTR, bdtr_off | MC_F405_TIM_BDTR_MOE); // only MOE changes
    mc_hal_pwm3_state_t st{};
    ASSERT_EQ(mc_hal_pwm3_get_state(&pwm.dev, &st), 0);
    EXPECT_TRUE(st.enabled);
    ASSERT_EQ(mc_hal_pwm3_enable(&pwm.dev), 0); // idempotent

    ASSERT_EQ(mc_hal_pwm3_disable(&pwm.dev), 0);
    EXPECT_EQ(tim.BDTR, bdtr_off);
    EXPECT_EQ(tim.BDTR & MC_F405_TIM_BDTR_MOE, 0u);
    ASSERT_EQ(mc_hal_pwm3_get_state(&pwm.dev, &st), 0);
    EXPECT_FALSE(st.enabled);
    EXPECT_EQ(mc_hal_pwm3_disable(&pwm.dev), 0); // idempotent
}

// A hardware break clears MOE and sets BIF (the test plays the hardware):
// the state reads disabled and enable is refused while BIF is latched.
TEST(F405Pwm3, HardwareBreakBlocksEnable)
{
    mc_f405_tim_regs_t tim{};
    mc_f405_pwm3_t pwm;
    const mc_f405_pwm3_config_t cfg = pwm3_cfg(&tim);
    ASSERT_EQ(mc_f405_pwm3_init(&pwm, &cfg), 0);
    ASSERT_EQ(mc_hal_pwm3_enable(&pwm.dev), 0);

    tim.BDTR = tim.BDTR & ~MC_F405_TIM_BDTR_MOE; // hardware: break clears MOE
    tim.SR = MC_F405_TIM_SR_BIF;                 // hardware: break flag
    mc_hal_pwm3_state_t st{};
    ASSERT_EQ(mc_hal_pwm3_get_state(&pwm.dev, &st), 0);
    EXPECT_FALSE(st.enabled);
    EXPECT_EQ(mc_hal_pwm3_enable(&pwm.dev), -EBUSY);
    EXPECT_EQ(tim.BDTR & MC_F405_TIM_BDTR_MOE, 0u);

    tim.SR = 0u; // flag cleared (by the fault driver's release)
    EXPECT_EQ(mc_hal_pwm3_enable(&pwm.dev), 0);
}

// disable confirms the outputs are off by reading MOE back. A register file
// cannot hold a stuck bit, so make the written value itself keep MOE (a
// corrupted driver image): disable must report -EIO, not 0.
TEST(F405Pwm3, DisableReportsMoeStillSet)
{
    mc_f405_tim_regs_t tim{};
    mc_f405_pwm3_t pwm;
    const mc_f405_pwm3_config_t cfg = pwm3_cfg(&tim);
    ASSERT_EQ(mc_f405_pwm3_init(&pwm, &cfg), 0);
    pwm.bdtr_off |= MC_F405_TIM_BDTR_MOE;
    EXPECT_EQ(mc_hal_pwm3_disable(&pwm.dev), -EIO);
}

// ---- pwm2 on TIM8 -------------------------------------------------------------

TEST(F405Pwm2, InitAndBipolarDuties)
{
    mc_f405_tim_regs_t tim8{};
    mc_f405_pwm2_t pwm;
    mc_f405_pwm2_config_t cfg{};
    cfg.p_tim = &tim8;
    cfg.tim_clk_hz = kTimClkHz;
    cfg.pwm_freq_hz = 20000u;
    cfg.break_enable = true;
    cfg.break_active_high = false;
    cfg.outputs_active_low = false;

    ASSERT_EQ(mc_f405_pwm2_init(&pwm, &cfg), 0);
    EXPECT_EQ(tim8.PSC, 0u);
    EXPECT_EQ(tim8.ARR, 4200u);
    EXPECT_EQ(tim8.CR1, (1u << 5) | (1u << 7) | 1u);
    EXPECT_EQ(tim8.CCMR1, 0x6868u); // CH1, CH2 PWM mode 1 + preload
    EXPECT_EQ(tim8.CCMR2, 0x6868u); // CH3, CH4 PWM mode 1 + preload
    EXPECT_EQ(tim8.CCER, 0x1111u);  // CC1E..CC4E, no CCxNE
    // No dead time (no complementary outputs), OSSI, OSSR, BKE, MOE off.
    EXPECT_EQ(tim8.BDTR, (1u << 10) | (1u << 11) | (1u << 12));
    // Duty 0 on both bridges: every leg at 50 %.
    EXPECT_EQ(tim8.CCR1, 2100u);
    EXPECT_EQ(tim8.CCR2, 2100u);
    EXPECT_EQ(tim8.CCR3, 2100u);
    EXPECT_EQ(tim8.CCR4, 2100u);

    // d = 0.5: legs at 75 % / 25 % -> 3150 / 1050; d = -1: 0 / 4200.
    ASSERT_EQ(mc_hal_pwm2_set_duty(&pwm.dev, 0.5f, -1.0f), 0);
    EXPECT_EQ(tim8.CCR1, 3150u);
    EXPECT_EQ(tim8.CCR2, 1050u);
    EXPECT_EQ(tim8.CCR3, 0u);
    EXPECT_EQ(tim8.CCR4, 4200u);

    const auto regs0 = snapshot(tim8);
    EXPECT_EQ(mc_hal_pwm2_set_duty(&pwm.dev, 1.5f, 0.0f), -EINVAL);
    EXPECT_EQ(mc_hal_pwm2_set_duty(&pwm.dev, 0.0f, std::nanf("")), -EINVAL);
    EXPECT_EQ(snapshot(tim8), regs0);

    ASSERT_EQ(mc_hal_pwm2_enable(&pwm.dev), 0);
    EXPECT_NE(tim8.BDTR & MC_F405_TIM_BDTR_MOE, 0u);
    ASSERT_EQ(mc_hal_pwm2_disable(&pwm.dev), 0);
    EXPECT_EQ(tim8.BDTR & MC_F405_TIM_BDTR_MOE, 0u);
    mc_hal_pwm2_state_t st{};
    ASSERT_EQ(mc_hal_pwm2_get_state(&pwm.dev, &st), 0);
    EXPECT_FALSE(st.enabled);
    EXPECT_EQ(st.duty_a, 0.5f);
    EXPECT_EQ(st.duty_b, -1.0f);
}
