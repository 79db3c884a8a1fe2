// adc on ADC1 against a register file in RAM: configuration (RM0090 §13.13)
// and conversion of the injected data registers to amperes and volts.
#include <gtest/gtest.h>

#include <cmath>

#include "f405_test_util.h"

namespace
{

// Board: 3 shunts on ADC channels 10, 11, 12, bus divider on 13, power-stage
// sensor on 14, motor thermistor network on 15. 0.5 mOhm shunts, x20
// amplifiers biased at 1.65 V, Vref 3.3 V, bus divider 20:1.
struct AdcBoard : public ::testing::Test {
    mc_f405_adc_regs_t adc{};
    mc_f405_adc_common_regs_t common{};
    mc_f405_tim_regs_t tim2{};
    mc_f405_tick_t tick{};
    mc_f405_adc_t drv{};

    mc_f405_adc_config_t cfg()
    {
        mc_f405_adc_config_t c{};
        c.p_adc = &adc;
        c.p_common = &common;
        c.p_tick = &tick.dev;
        c.ch_ia = 10u;
        c.ch_ib = 11u;
        c.ch_ic = 12u;
        c.ch_vbus = 13u;
        c.smp_current = MC_F405_ADC_SMP_15;
        c.smp_vbus = MC_F405_ADC_SMP_28;
        c.smp_temp = MC_F405_ADC_SMP_480;
        c.trigger = MC_F405_ADC_TRIG_TIM1_TRGO;
        c.clk_div = 4u;
        c.jeoc_irq = true;
        c.vref_v = 3.3f;
        c.shunt_ohm = 0.0005f;
        c.amp_gain_v_per_v = 20.0f;
        c.ia_offset_v = 1.65f;
        c.ib_offset_v = 1.65f;
        c.ic_offset_v = 1.65f;
        c.vbus_divider = 20.0f;
        c.rail_margin_counts = 16u;
        // Linear sensor, 10 mV/degC with 0.5 V at 0 degC: T = -50 + 100 v.
        c.temp_power_stage = {14u, -50.0f, 100.0f, 0.1f, 2.0f, 0.0f, 0.0f, nullptr, 0u};
        c.temp_motor = {15u, -50.0f, 100.0f, 0.1f, 2.0f, 0.0f, 0.0f, nullptr, 0u};
        return c;
    }

    void SetUp() override
    {
        mc_f405_tick_config_t tc{&tim2, 84000000u, 0u};
        ASSERT_EQ(mc_f405_tick_init(&tick, &tc), 0);
    }

    // One completed injected conversion, as the hardware leaves it.
    void convert(uint32_t ia, uint32_t ib, uint32_t ic, uint32_t vbus)
    {
        adc.JDR[0] = ia;
        adc.JDR[1] = ib;
        adc.JDR[2] = ic;
        adc.JDR[3] = vbus;
        adc.SR = MC_F405_ADC_SR_JEOC;
    }
};

// Independent model of the board's analog front end, in double.
double amps(uint32_t raw)
{
    const double v = raw * 3.3 / 4096.0;
    return (v - 1.65) / (20.0 * 0.0005);
}

double bus_volts(uint32_t raw)
{
    return raw * 3.3 / 4096.0 * 20.0;
}

} // namespace

TEST_F(AdcBoard, InitRegisterWritesFourInjected)
{
    const mc_f405_adc_config_t c = cfg();
    ASSERT_EQ(mc_f405_adc_init(&drv, &c), 0);

    // JSQR: JL = 3 (4 conversions) at bits 21:20; JSQ1..JSQ4 = 10, 11, 12, 13
    // at bits 4:0, 9:5, 14:10, 19:15.
    EXPECT_EQ(adc.JSQR, (3u << 20) | 10u | (11u << 5) | (12u << 10) | (13u << 15));
    // CR2: ADON, JEXTSEL = 0001 (TIM1 TRGO) at 19:16, JEXTEN = 01 rising at
    // 21:20.
    EXPECT_EQ(adc.CR2, 1u | (1u << 16) | (1u << 20));
    // CR1: SCAN (bit 8) for the sequence, JEOCIE (bit 7), RES = 00 12 bit.
    EXPECT_EQ(adc.CR1, (1u << 8) | (1u << 7));
    // SMPR1 (channels 10..18, 3 bits each from bit 0): ch10..12 15 cycles
    // (001), ch13 28 cycles (010), ch14, ch15 480 cycles (111).
    EXPECT_EQ(adc.SMPR1, 1u | (1u << 3) | (1u << 6) | (2u << 9) | (7u << 12) | (7u << 15));
    EXPECT_EQ(adc.SMPR2, 0u);
    // ADC_CCR.ADCPRE = 01: PCLK2 / 4 = 21 MHz (< 36 MHz max).
    EXPECT_EQ(common.CCR, 1u << 16);
    for (int k = 0; k < 4; ++k) {
        EXPECT_EQ(adc.JOFR[k], 0u);
    }
    EXPECT_EQ(adc.SQR1, 0u);  // one regular conversion per start
    EXPECT_EQ(adc.SQR3, 14u); // first temperature channel
}

// Two shunts and the CC4 trigger: JL = 2 and the sequence sits in JSQ2..JSQ4
// (RM0090 JSQR: a shorter sequence uses the last fields), JEXTSEL = 0000.
TEST_F(AdcBoard, InitTwoShuntsCc4Trigger)
{
    mc_f405_adc_config_t c = cfg();
    c.ch_ic = MC_F405_ADC_CH_NONE;
    c.trigger = MC_F405_ADC_TRIG_TIM1_CC4;
    c.clk_div = 8u;
    ASSERT_EQ(mc_f405_adc_init(&drv, &c), 0);
    EXPECT_EQ(adc.JSQR, (2u << 20) | (10u << 5) | (11u << 10) | (13u << 15));
    EXPECT_EQ(adc.CR2, 1u | (0u << 16) | (1u << 20));
    EXPECT_EQ(common.CCR, 3u << 16); // ADCPRE = 11: / 8

    // vbus is the third conversion now: JDR3.
    adc.JDR[0] = 2148u;
    adc.JDR[1] = 1948u;
    adc.JDR[2] = 1000u;
    adc.SR = MC_F405_ADC_SR_JEOC;
    mc_hal_adc_sample_t s{};
    ASSERT_EQ(mc_hal_adc_read(&drv.dev, &s), 0);
    EXPECT_EQ(s.valid_mask, MC_HAL_ADC_VALID_IA | MC_HAL_ADC_VALID_IB | MC_HAL_ADC_VALID_VBUS);
    EXPECT_NEAR(s.vbus_v, bus_volts(1000u), rel_tol(bus_volts(1000u)));
    EXPECT_EQ(s.ic_a, 0.0f);
}

// A second axis' ADC (ADC2 on the ODrive v3.6) on TIM8's CC4 event:
// JEXTSEL = 1110 (RM0090 §13.6, external trigger for injected channels;
// the ST HAL's ADC_EXTERNALTRIGINJECCONV_T8_CC4 is JEXTSEL_3|2|1), JEXTEN =
// 01 (rising edge), ADON. Everything else as on ADC1.
TEST_F(AdcBoard, Tim8Cc4TriggerJextsel)
{
    mc_f405_adc_config_t c = cfg();
    c.trigger = MC_F405_ADC_TRIG_TIM8_CC4;
    ASSERT_EQ(mc_f405_adc_init(&drv, &c), 0);
    EXPECT_EQ((adc.CR2 >> 16) & 0xFu, 0xEu); // JEXTSEL[19:16] = 1110
    EXPECT_EQ((adc.CR2 >> 20) & 0x3u, 1u);   // JEXTEN[21:20] = 01, rising
    EXPECT_EQ(adc.CR2, 1u | (14u << 16) | (1u << 20));

    // A trigger value past the last one is refused, nothing written.
    mc_f405_adc_regs_t adc_b{};
    mc_f405_adc_t drv_b{};
    const auto r0 = snapshot(adc_b);
    c.p_adc = &adc_b;
    c.trigger = static_cast<mc_f405_adc_trigger_t>(3);
    EXPECT_EQ(mc_f405_adc_init(&drv_b, &c), -EINVAL);
    EXPECT_EQ(snapshot(adc_b), r0);
}

// ADC1 (M0) and ADC2 (M1) share the ADC interrupt: each driver reports its
// own end of injected sequence (JEOC with JEOCIE), not the other's; the
// flag stays set until that driver's read clears it.
TEST_F(AdcBoard, JeocPendingTellsTheAdcsApart)
{
    mc_f405_adc_regs_t adc2{};
    mc_f405_adc_t drv2{};
    const mc_f405_adc_config_t c1 = cfg();
    mc_f405_adc_config_t c2 = cfg();
    c2.p_adc = &adc2;
    c2.trigger = MC_F405_ADC_TRIG_TIM8_CC4;
    ASSERT_EQ(mc_f405_adc_init(&drv, &c1), 0);
    ASSERT_EQ(mc_f405_adc_init(&drv2, &c2), 0);
    EXPECT_FALSE(mc_f405_adc_jeoc_pending(&drv)); // init cleared SR
    EXPECT_FALSE(mc_f405_adc_jeoc_pending(&drv2));

    adc2.SR = MC_F405_ADC_SR_JEOC | MC_F405_ADC_SR_EOC; // M1's sequence ended
    EXPECT_FALSE(mc_f405_adc_jeoc_pending(&drv));
    EXPECT_TRUE(mc_f405_adc_jeoc_pending(&drv2));
    adc.SR = MC_F405_ADC_SR_EOC; // a temperature conversion is not the fast loop
    EXPECT_FALSE(mc_f405_adc_jeoc_pending(&drv));
    convert(2048u, 2048u, 2048u, 1000u); // M0's too
    EXPECT_TRUE(mc_f405_adc_jeoc_pending(&drv));
    EXPECT_TRUE(mc_f405_adc_jeoc_pending(&drv2));

    // The read of M1 writes ~JEOC to ADC2's SR (rc_w0: the hardware clears
    // JEOC alone, EOC stays) and nothing to ADC1's.
    mc_hal_adc_sample_t s{};
    ASSERT_EQ(mc_hal_adc_read(&drv2.dev, &s), 0);
    EXPECT_EQ(adc2.SR, ~MC_F405_ADC_SR_JEOC);
    adc2.SR = MC_F405_ADC_SR_EOC; // what the hardware leaves after that write
    EXPECT_FALSE(mc_f405_adc_jeoc_pending(&drv2));
    EXPECT_TRUE(mc_f405_adc_jeoc_pending(&drv));

    // JEOC set with JEOCIE off (a polled ADC) raises no interrupt: not
    // pending for the shared ISR.
    adc.CR1 &= ~MC_F405_ADC_CR1_JEOCIE;
    EXPECT_FALSE(mc_f405_adc_jeoc_pending(&drv));
    EXPECT_FALSE(mc_f405_adc_jeoc_pending(nullptr));
}

TEST_F(AdcBoard, InvalidConfigWritesNothing)
{
    poison(drv);
    const auto drv0 = snapshot(drv);
    const auto regs0 = snapshot(adc);
    const auto common0 = snapshot(common);

    mc_f405_adc_config_t c = cfg();
    c.clk_div = 3u;
    EXPECT_EQ(mc_f405_adc_init(&drv, &c), -EINVAL);
    c = cfg();
    c.shunt_ohm = std::nanf("");
    EXPECT_EQ(mc_f405_adc_init(&drv, &c), -EINVAL);
    c = cfg();
    c.amp_gain_v_per_v = 0.0f;
    EXPECT_EQ(mc_f405_adc_init(&drv, &c), -EINVAL);
    c = cfg();
    c.ch_ia = MC_F405_ADC_CH_NONE; // only phase b: nothing to derive from
    c.ch_ic = MC_F405_ADC_CH_NONE;
    EXPECT_EQ(mc_f405_adc_init(&drv, &c), -EINVAL);
    c = cfg();
    c.ch_ib = MC_F405_ADC_CH_NONE; // phase b is always measured
    EXPECT_EQ(mc_f405_adc_init(&drv, &c), -EINVAL);
    c = cfg();
    c.temp_power_stage.c3_c_per_v3 = std::nanf("");
    EXPECT_EQ(mc_f405_adc_init(&drv, &c), -EINVAL);
    c = cfg();
    c.ch_vbus = 19u;
    EXPECT_EQ(mc_f405_adc_init(&drv, &c), -EINVAL);
    c = cfg();
    c.vref_v = 5.0f;
    EXPECT_EQ(mc_f405_adc_init(&drv, &c), -EINVAL);
    c = cfg();
    c.vbus_divider = 0.5f;
    EXPECT_EQ(mc_f405_adc_init(&drv, &c), -EINVAL);
    c = cfg();
    c.smp_vbus = static_cast<mc_f405_adc_smp_t>(8);
    EXPECT_EQ(mc_f405_adc_init(&drv, &c), -EINVAL);
    c = cfg();
    c.temp_motor.v_min_v = 3.0f; // window inverted
    EXPECT_EQ(mc_f405_adc_init(&drv, &c), -EINVAL);

    EXPECT_EQ(snapshot(drv), drv0);
    EXPECT_EQ(snapshot(adc), regs0);
    EXPECT_EQ(snapshot(common), common0);
}

// Conversion: i = (raw * Vref / 4096 - offset) / (gain * R): 100 counts
// above the 1.65 V bias (2048 counts) is 8.0566 A.
TEST_F(AdcBoard, ReadConvertsToPhysicalUnits)
{
    const mc_f405_adc_config_t c = cfg();
    ASSERT_EQ(mc_f405_adc_init(&drv, &c), 0);
    tim2.CNT = 123456u; // tick counter now

    convert(2148u, 1948u, 2048u, 1000u);
    mc_hal_adc_sample_t s{};
    ASSERT_EQ(mc_hal_adc_read(&drv.dev, &s), 0);
    EXPECT_NEAR(s.ia_a, amps(2148u), rel_tol(amps(2148u)));
    EXPECT_NEAR(s.ib_a, amps(1948u), rel_tol(amps(1948u)));
    // At the bias: only the float rounding of the 2048-count offset is left
    // (well below 1 uA).
    EXPECT_NEAR(s.ic_a, 0.0, 1e-6);
    EXPECT_NEAR(s.vbus_v, bus_volts(1000u), rel_tol(bus_volts(1000u)));
    EXPECT_EQ(s.valid_mask, MC_HAL_ADC_VALID_ALL);
    EXPECT_EQ(s.timestamp_ticks, 123456u);
    EXPECT_EQ(s.seq, 1u);
    // JEOC cleared by a rc_w0 write that leaves every other flag alone.
    EXPECT_EQ(adc.SR, ~MC_F405_ADC_SR_JEOC);

    // No new conversion: -EAGAIN, sample untouched.
    mc_hal_adc_sample_t s2 = s;
    EXPECT_EQ(mc_hal_adc_read(&drv.dev, &s2), -EAGAIN);
    EXPECT_EQ(s2.seq, 1u);

    convert(4000u, 100u, 2048u, 3000u);
    ASSERT_EQ(mc_hal_adc_read(&drv.dev, &s), 0);
    EXPECT_EQ(s.seq, 2u);
    EXPECT_NEAR(s.ia_a, amps(4000u), rel_tol(amps(4000u)));
    EXPECT_NEAR(s.ib_a, amps(100u), rel_tol(amps(100u)));
}

// Negative gain (inverting amplifier): the sign flips.
TEST_F(AdcBoard, NegativeGainFlipsSign)
{
    mc_f405_adc_config_t c = cfg();
    c.amp_gain_v_per_v = -20.0f;
    ASSERT_EQ(mc_f405_adc_init(&drv, &c), 0);
    convert(2148u, 2048u, 2048u, 1000u);
    mc_hal_adc_sample_t s{};
    ASSERT_EQ(mc_hal_adc_read(&drv.dev, &s), 0);
    EXPECT_NEAR(s.ia_a, -amps(2148u), rel_tol(amps(2148u)));
}

// Within rail_margin_counts (16) of either rail the amplifier or the ADC
// saturates: the channel is flagged invalid and reads 0.
TEST_F(AdcBoard, RailsInvalidateChannel)
{
    const mc_f405_adc_config_t c = cfg();
    ASSERT_EQ(mc_f405_adc_init(&drv, &c), 0);
    convert(16u, 4079u, 17u, 4095u);
    mc_hal_adc_sample_t s{};
    ASSERT_EQ(mc_hal_adc_read(&drv.dev, &s), 0);
    EXPECT_EQ(s.valid_mask, MC_HAL_ADC_VALID_IC); // 17 is just inside
    EXPECT_EQ(s.ia_a, 0.0f);
    EXPECT_EQ(s.ib_a, 0.0f);
    EXPECT_EQ(s.vbus_v, 0.0f);
    EXPECT_NEAR(s.ic_a, amps(17u), rel_tol(amps(17u)));
}

TEST_F(AdcBoard, AdcOffIsIoError)
{
    const mc_f405_adc_config_t c = cfg();
    ASSERT_EQ(mc_f405_adc_init(&drv, &c), 0);
    convert(2048u, 2048u, 2048u, 1000u);
    adc.CR2 = 0u; // ADON lost (peripheral reset)
    mc_hal_adc_sample_t s{};
    s.seq = 77u;
    EXPECT_EQ(mc_hal_adc_read(&drv.dev, &s), -EIO);
    EXPECT_EQ(s.seq, 77u);
    EXPECT_EQ(adc.SR, MC_F405_ADC_SR_JEOC); // flag not consumed
}

// Temperatures: read_temp starts a regular conversion (SQ1 = channel,
// SWSTART), the next call after EOC converts DR and starts the other one.
TEST_F(AdcBoard, TemperaturesAlternate)
{
    const mc_f405_adc_config_t c = cfg();
    ASSERT_EQ(mc_f405_adc_init(&drv, &c), 0);

    mc_hal_adc_temp_t t{};
    ASSERT_EQ(mc_hal_adc_read_temp(&drv.dev, &t), 0);
    EXPECT_EQ(t.valid_mask, 0u);  // nothing converted yet
    EXPECT_EQ(t.absent_mask, 0u); // both sensors fitted
    EXPECT_EQ(adc.SQR3, 14u);
    EXPECT_NE(adc.CR2 & MC_F405_ADC_CR2_SWSTART, 0u);

    // Hardware: conversion done, 1241 counts = 0.99983 V -> 49.98 degC.
    adc.CR2 = adc.CR2 & ~MC_F405_ADC_CR2_SWSTART;
    adc.DR = 1241u;
    adc.SR = MC_F405_ADC_SR_EOC;
    ASSERT_EQ(mc_hal_adc_read_temp(&drv.dev, &t), 0);
    const double expect_c = -50.0 + 100.0 * (1241.0 * 3.3 / 4096.0);
    EXPECT_EQ(t.valid_mask, MC_HAL_ADC_TEMP_VALID_POWER_STAGE);
    EXPECT_NEAR(t.power_stage_temp_c, expect_c, rel_tol(expect_c));
    EXPECT_EQ(adc.SQR3, 15u); // now the motor channel
    EXPECT_NE(adc.CR2 & MC_F405_ADC_CR2_SWSTART, 0u);

    // Motor sensor open: 4095 counts = 3.299 V > 2.0 V window.
    adc.DR = 4095u;
    adc.SR = MC_F405_ADC_SR_EOC;
    ASSERT_EQ(mc_hal_adc_read_temp(&drv.dev, &t), 0);
    EXPECT_EQ(t.valid_mask, MC_HAL_ADC_TEMP_VALID_POWER_STAGE);
    EXPECT_EQ(adc.SQR3, 14u);
}

TEST_F(AdcBoard, NoTemperatureChannelsMeansNoOp)
{
    mc_f405_adc_config_t c = cfg();
    c.temp_power_stage.channel = MC_F405_ADC_CH_NONE;
    c.temp_motor.channel = MC_F405_ADC_CH_NONE;
    ASSERT_EQ(mc_f405_adc_init(&drv, &c), 0);
    mc_hal_adc_temp_t t{};
    EXPECT_EQ(mc_hal_adc_read_temp(&drv.dev, &t), -ENODEV);
}

// Phases b and c measured (the ODrive v3.6 M0 layout: ib on channel 10 =
// PC0, ic on channel 11 = PC1, bus on channel 6 = PA6): JL = 2 and the
// sequence ib, ic, vbus fills JSQ2..JSQ4. JDR1 is phase b, JDR2 phase c;
// ia is reported as -(ib + ic) and is valid only when both are.
TEST_F(AdcBoard, PhasesBAndCDeriveA)
{
    mc_f405_adc_config_t c = cfg();
    c.ch_ia = MC_F405_ADC_CH_NONE;
    c.ch_ib = 10u;
    c.ch_ic = 11u;
    c.ch_vbus = 6u;
    ASSERT_EQ(mc_f405_adc_init(&drv, &c), 0);
    EXPECT_EQ(adc.JSQR, (2u << 20) | (10u << 5) | (11u << 10) | (6u << 15));

    adc.JDR[0] = 2148u; // phase b: +100 counts
    adc.JDR[1] = 1998u; // phase c: -50 counts
    adc.JDR[2] = 1000u;
    adc.SR = MC_F405_ADC_SR_JEOC;
    mc_hal_adc_sample_t s{};
    ASSERT_EQ(mc_hal_adc_read(&drv.dev, &s), 0);
    EXPECT_EQ(s.valid_mask, MC_HAL_ADC_VALID_ALL);
    EXPECT_NEAR(s.ib_a, amps(2148u), rel_tol(amps(2148u)));
    EXPECT_NEAR(s.ic_a, amps(1998u), rel_tol(amps(1998u)));
    const double ia = -(amps(2148u) + amps(1998u));
    EXPECT_NEAR(s.ia_a, ia, rel_tol(ia));
    EXPECT_NEAR(s.vbus_v, bus_volts(1000u), rel_tol(bus_volts(1000u)));

    // Phase c saturated: ic and the derived ia are invalid, ib stays.
    adc.JDR[0] = 2148u;
    adc.JDR[1] = 4095u;
    adc.JDR[2] = 1000u;
    adc.SR = MC_F405_ADC_SR_JEOC;
    ASSERT_EQ(mc_hal_adc_read(&drv.dev, &s), 0);
    EXPECT_EQ(s.valid_mask, MC_HAL_ADC_VALID_IB | MC_HAL_ADC_VALID_VBUS);
    EXPECT_EQ(s.ia_a, 0.0f);
}

// Cubic sensor: T = 10 + 20 v - 3 v^2 + 0.5 v^3 at 1241 counts.
TEST_F(AdcBoard, CubicTemperatureSensor)
{
    mc_f405_adc_config_t c = cfg();
    c.temp_power_stage = {14u, 10.0f, 20.0f, 0.1f, 3.2f, -3.0f, 0.5f, nullptr, 0u};
    c.temp_motor.channel = MC_F405_ADC_CH_NONE;
    ASSERT_EQ(mc_f405_adc_init(&drv, &c), 0);
    mc_hal_adc_temp_t t{};
    ASSERT_EQ(mc_hal_adc_read_temp(&drv.dev, &t), 0);
    adc.DR = 1241u;
    adc.SR = MC_F405_ADC_SR_EOC;
    ASSERT_EQ(mc_hal_adc_read_temp(&drv.dev, &t), 0);
    const double v = 1241.0 * 3.3 / 4096.0;
    const double expect_c = 10.0 + 20.0 * v - 3.0 * v * v + 0.5 * v * v * v;
    EXPECT_EQ(t.valid_mask, MC_HAL_ADC_TEMP_VALID_POWER_STAGE);
    EXPECT_NEAR(t.power_stage_temp_c, expect_c, rel_tol(expect_c));
    // no motor channel configured: reported absent (not fitted), which the
    // drive does not require, unlike a fitted sensor without a reading
    EXPECT_EQ(t.absent_mask, MC_HAL_ADC_TEMP_VALID_MOTOR);
}

// Table sensor: three points (0.5 V, 100 degC), (1.0 V, 60 degC), (2.0 V,
// 20 degC) interpolated linearly; outside 0.5..2.0 V invalid. 1241 counts =
// 0.99983 V lies in the first segment: 100 - 40 (0.99983 - 0.5) / 0.5.
TEST_F(AdcBoard, TableTemperatureSensor)
{
    static const mc_f405_adc_temp_point_t table[] = {{0.5f, 100.0f}, {1.0f, 60.0f}, {2.0f, 20.0f}};
    mc_f405_adc_config_t c = cfg();
    c.temp_power_stage = {14u, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, table, 3u};
    c.temp_motor.channel = MC_F405_ADC_CH_NONE;
    ASSERT_EQ(mc_f405_adc_init(&drv, &c), 0);
    mc_hal_adc_temp_t t{};
    ASSERT_EQ(mc_hal_adc_read_temp(&drv.dev, &t), 0);
    const double v1 = 1241.0 * 3.3 / 4096.0;
    adc.DR = 1241u;
    adc.SR = MC_F405_ADC_SR_EOC;
    ASSERT_EQ(mc_hal_adc_read_temp(&drv.dev, &t), 0);
    const double e1 = 100.0 - 40.0 * (v1 - 0.5) / 0.5;
    EXPECT_EQ(t.valid_mask, MC_HAL_ADC_TEMP_VALID_POWER_STAGE);
    EXPECT_NEAR(t.power_stage_temp_c, e1, rel_tol(e1));
    // 1862 counts = 1.5002 V: second segment, 60 - 40 (1.5002 - 1.0).
    adc.DR = 1862u;
    adc.SR = MC_F405_ADC_SR_EOC;
    ASSERT_EQ(mc_hal_adc_read_temp(&drv.dev, &t), 0);
    const double e2 = 60.0 - 40.0 * (1862.0 * 3.3 / 4096.0 - 1.0);
    EXPECT_NEAR(t.power_stage_temp_c, e2, rel_tol(e2));
    // 2600 counts = 2.095 V: beyond the last point, open circuit.
    adc.DR = 2600u;
    adc.SR = MC_F405_ADC_SR_EOC;
    ASSERT_EQ(mc_hal_adc_read_temp(&drv.dev, &t), 0);
    EXPECT_EQ(t.valid_mask, 0u);
}

// A table must have increasing voltages and finite values.
TEST_F(AdcBoard, BadTemperatureTableRefused)
{
    static const mc_f405_adc_temp_point_t falling[] = {{1.0f, 20.0f}, {0.5f, 60.0f}};
    mc_f405_adc_config_t c = cfg();
    c.temp_power_stage = {14u, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, falling, 2u};
    EXPECT_EQ(mc_f405_adc_init(&drv, &c), -EINVAL);
    c.temp_power_stage = {14u, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, nullptr, 2u};
    EXPECT_EQ(mc_f405_adc_init(&drv, &c), -EINVAL);
    c.temp_power_stage = {14u, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, falling, 1u};
    EXPECT_EQ(mc_f405_adc_init(&drv, &c), -EINVAL);
}
