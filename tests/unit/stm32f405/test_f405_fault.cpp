// fault on TIM1/TIM8 break + GPIO against register files in RAM: gate kill
// (EGR.BG, MOE, gate-enable pin), hardware break propagation, release.
#include <gtest/gtest.h>

#include "f405_test_util.h"

namespace
{

// Board: nFAULT on PB12 (active low, also wired to TIM1_BKIN), gate-driver
// enable on PB5 (active high), no over-current comparator pin.
struct FaultBoard : public ::testing::Test {
    mc_f405_tim_regs_t tim1{};
    mc_f405_tim_regs_t tim8{};
    mc_f405_gpio_regs_t gpiob{};
    mc_f405_fault_t fault{};
    mc_f405_pwm3_t pwm3{};
    mc_f405_pwm2_t pwm2{};

    mc_f405_fault_config_t fault_cfg()
    {
        mc_f405_fault_config_t c{};
        c.p_tim1 = &tim1;
        c.p_tim8 = &tim8;
        c.gate_driver_fault = {&gpiob, 12u, true};
        c.overcurrent = {nullptr, 0u, false};
        c.gate_enable = {&gpiob, 5u, false};
        c.bkin_mask = MC_HAL_FAULT_GATE_DRIVER;
        return c;
    }

    void SetUp() override
    {
        gpiob.IDR = 1u << 12; // nFAULT high: no fault
        const mc_f405_fault_config_t fc = fault_cfg();
        ASSERT_EQ(mc_f405_fault_init(&fault, &fc), 0);

        mc_f405_pwm3_config_t c3{};
        c3.p_tim = &tim1;
        c3.tim_clk_hz = 168000000u;
        c3.pwm_freq_hz = 20000u;
        c3.deadtime_ns = 500u;
        c3.adc_trigger_lead_ticks = 8u;
        c3.adc_trigger = MC_F405_ADC_TRIG_TIM1_TRGO;
        c3.break_enable = true;
        c3.p_fault = &fault;
        ASSERT_EQ(mc_f405_pwm3_init(&pwm3, &c3), 0);

        mc_f405_pwm2_config_t c2{};
        c2.p_tim = &tim8;
        c2.tim_clk_hz = 168000000u;
        c2.pwm_freq_hz = 20000u;
        c2.p_fault = &fault;
        ASSERT_EQ(mc_f405_pwm2_init(&pwm2, &c2), 0);
    }

    mc_hal_fault_status_t read()
    {
        mc_hal_fault_status_t st{};
        EXPECT_EQ(mc_hal_fault_read(&fault.dev, &st), 0);
        return st;
    }
};

} // namespace

// Init: PB5 driven high through BSRR set bit 5 and made an output (MODER5 =
// 01), PB12 an input (MODER12 = 00).
TEST_F(FaultBoard, InitConfiguresPins)
{
    EXPECT_EQ(gpiob.BSRR, 1u << 5);
    EXPECT_EQ(gpiob.MODER, 1u << 10);
    const mc_hal_fault_status_t st = read();
    EXPECT_EQ(st.active_mask, 0u);
    EXPECT_EQ(st.latched_mask, 0u);
    EXPECT_FALSE(st.gate_killed);
}

TEST_F(FaultBoard, InvalidConfig)
{
    mc_f405_fault_t f2;
    poison(f2);
    const auto drv0 = snapshot(f2);
    mc_f405_fault_config_t c = fault_cfg();
    c.gate_enable.pin = 16u;
    EXPECT_EQ(mc_f405_fault_init(&f2, &c), -EINVAL);
    c = fault_cfg();
    c.p_tim1 = nullptr;
    c.p_tim8 = nullptr;
    EXPECT_EQ(mc_f405_fault_init(&f2, &c), -EINVAL);
    c = fault_cfg();
    c.bkin_mask = 1u << 5;
    EXPECT_EQ(mc_f405_fault_init(&f2, &c), -EINVAL);
    EXPECT_EQ(snapshot(f2), drv0);
}

// Gate kill: BG on both timers (RM0090 §17.4.6 EGR bit 7), MOE cleared on
// both, gate enable low (BSRR reset half: bit 16 + 5), latched; both PWM
// enables refused even before the hardware has set BIF.
TEST_F(FaultBoard, GateKillForcesEverythingOff)
{
    ASSERT_EQ(mc_hal_pwm3_enable(&pwm3.dev), 0);
    ASSERT_EQ(mc_hal_pwm2_enable(&pwm2.dev), 0);

    ASSERT_EQ(mc_hal_fault_gate_kill(&fault.dev), 0);
    EXPECT_EQ(tim1.EGR, MC_F405_TIM_EGR_BG);
    EXPECT_EQ(tim8.EGR, MC_F405_TIM_EGR_BG);
    EXPECT_EQ(tim1.BDTR & MC_F405_TIM_BDTR_MOE, 0u);
    EXPECT_EQ(tim8.BDTR & MC_F405_TIM_BDTR_MOE, 0u);
    EXPECT_EQ(gpiob.BSRR, 1u << (16u + 5u));
    EXPECT_TRUE(read().gate_killed);

    EXPECT_EQ(mc_hal_pwm3_enable(&pwm3.dev), -EBUSY);
    EXPECT_EQ(mc_hal_pwm2_enable(&pwm2.dev), -EBUSY);
    EXPECT_EQ(tim1.BDTR & MC_F405_TIM_BDTR_MOE, 0u);
    EXPECT_EQ(tim8.BDTR & MC_F405_TIM_BDTR_MOE, 0u);

    ASSERT_EQ(mc_hal_fault_gate_kill(&fault.dev), 0); // idempotent
    EXPECT_TRUE(read().gate_killed);
}

// nFAULT pulls BKIN low: the hardware clears TIM1's MOE and sets BIF (the
// test does both). The next read latches the kill for every bridge (TIM8
// gets BG too), names the gate-driver input, and release is refused while
// nFAULT is still low.
TEST_F(FaultBoard, HardwareBreakLatchesAndPropagates)
{
    ASSERT_EQ(mc_hal_pwm3_enable(&pwm3.dev), 0);
    gpiob.IDR = 0u;                                // nFAULT asserted
    tim1.BDTR = tim1.BDTR & ~MC_F405_TIM_BDTR_MOE; // hardware
    tim1.SR = MC_F405_TIM_SR_BIF;                  // hardware

    const mc_hal_fault_status_t st = read();
    EXPECT_EQ(st.active_mask, MC_HAL_FAULT_GATE_DRIVER);
    EXPECT_EQ(st.latched_mask, MC_HAL_FAULT_GATE_DRIVER);
    EXPECT_TRUE(st.gate_killed);
    EXPECT_EQ(tim8.EGR, MC_F405_TIM_EGR_BG); // propagated
    EXPECT_EQ(gpiob.BSRR, 1u << (16u + 5u)); // gate driver disabled

    const auto tim1_0 = snapshot(tim1);
    EXPECT_EQ(mc_hal_fault_gate_release(&fault.dev), -EBUSY);
    EXPECT_EQ(snapshot(tim1), tim1_0); // nothing changed
    EXPECT_TRUE(read().gate_killed);
}

// A break pulse that is over by the time of the read is still attributed
// to the inputs wired to BKIN.
TEST_F(FaultBoard, ShortBreakPulseAttributedToBkinInputs)
{
    tim1.SR = MC_F405_TIM_SR_BIF;
    const mc_hal_fault_status_t st = read();
    EXPECT_EQ(st.active_mask, 0u);
    EXPECT_EQ(st.latched_mask, MC_HAL_FAULT_GATE_DRIVER);
    EXPECT_TRUE(st.gate_killed);
}

// Release: BIF cleared with a rc_w0 write of ~BIF on both timers, MOE
// stays off, gate enable back high, latches cleared; enable works again.
TEST_F(FaultBoard, ReleaseClearsLatches)
{
    ASSERT_EQ(mc_hal_fault_gate_kill(&fault.dev), 0);
    tim1.SR = MC_F405_TIM_SR_BIF; // hardware response to BG
    tim8.SR = MC_F405_TIM_SR_BIF;

    ASSERT_EQ(mc_hal_fault_gate_release(&fault.dev), 0);
    EXPECT_EQ(tim1.SR, ~MC_F405_TIM_SR_BIF);
    EXPECT_EQ(tim8.SR, ~MC_F405_TIM_SR_BIF);
    EXPECT_EQ(tim1.BDTR & MC_F405_TIM_BDTR_MOE, 0u);
    EXPECT_EQ(gpiob.BSRR, 1u << 5);
    const mc_hal_fault_status_t st = read();
    EXPECT_FALSE(st.gate_killed);
    EXPECT_EQ(st.latched_mask, 0u);

    tim1.SR = 0u; // what the hardware shows after the rc_w0 write
    tim8.SR = 0u;
    EXPECT_EQ(mc_hal_pwm3_enable(&pwm3.dev), 0);
    EXPECT_EQ(mc_hal_pwm2_enable(&pwm2.dev), 0);
}
