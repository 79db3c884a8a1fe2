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
