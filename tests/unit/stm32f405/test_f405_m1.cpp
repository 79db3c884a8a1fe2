// The ODrive v3.6's second axis (M1, boards/mc_board_f405_m1.h): its driver
// configurations built from the board's description and run through the
// hal/stm32f405 drivers on register files in RAM. Expected register values
// are worked out from RM0090 in the comments; the pins and channels from
// the ODrive source (pins.csv m1_*, commit f9b5419c).
#include <gtest/gtest.h>

#include <cmath>

#include "drv8301_model.h"
#include "f405_test_util.h"
#include "mc_board_f405_m1.h"
#include "mc_board_odrive36_gen.h"

namespace
{

constexpr uint32_t kSysclkHz = 168000000u;
constexpr uint32_t kPwmHz = 24000u; // board.toml [pwm] of the ODrive v3.6

struct M1Board : public ::testing::Test {
    mc_f405_tim_regs_t tim8{};
    mc_f405_tim_regs_t tim4{};
    mc_f405_tim_regs_t tim1{};
    mc_f405_tim_regs_t tim5{};
    mc_f405_adc_regs_t adc2{};
    mc_f405_adc_common_regs_t common{};
    mc_f405_spi_regs_t spi3{};
    mc_f405_gpio_regs_t gpioc{};
    mc_f405_syscfg_regs_t syscfg{};
    mc_f405_exti_regs_t exti{};
    mc_f405_tick_t tick{};
    mc_f405_fault_t fault{};
    mc_board_f405_m1_periph_t periph{};
    mc_board_f405_m1_cfg_t m1{};

    void SetUp() override
    {
        const mc_f405_tick_config_t tc{&tim5, 84000000u, 0u};
        ASSERT_EQ(mc_f405_tick_init(&tick, &tc), 0);
        mc_f405_fault_config_t fc{};
        fc.p_tim1 = &tim1;
        fc.p_tim8 = &tim8;
        ASSERT_EQ(mc_f405_fault_init(&fault, &fc), 0);
        periph = {&tim8, &tim4, &adc2, &common, &spi3, &gpioc, &syscfg, &exti, &tick.dev, &fault};
        ASSERT_EQ(mc_board_f405_m1_config(&mc_board_odrive36_desc, &periph, kSysclkHz, kPwmHz, &m1),
                  0);
    }
};

} // namespace

// pwm3 on TIM8 at 24 kHz: ARR = 168e6 / (2 x 24e3) = 3500, PSC 0; M0's
// 119 ns dead time = 19.99 tDTS -> 20 (DTG 0x14); CC4E for the TIM8 CC4
// ADC trigger 168 ticks (1 us) before the peak; no break (BKE clear: PA6,
// TIM8_BKIN's pin, is the bus-voltage input); M0's fault latch honoured.
TEST_F(M1Board, PwmOnTim8)
{
    mc_f405_pwm3_t pwm{};
    ASSERT_EQ(mc_f405_pwm3_init(&pwm, &m1.pwm3), 0);
    EXPECT_EQ(tim8.ARR, 3500u);
    EXPECT_EQ(tim8.PSC, 0u);
    EXPECT_EQ(tim8.CR1, (1u << 5) | (1u << 7) | 1u);       // CMS 01, ARPE, CEN
    EXPECT_EQ(tim8.CCMR1, 0x6868u);                        // PWM mode 1 + preload, CH1/CH2
    EXPECT_EQ(tim8.CCMR2, 0x7868u);                        // CH3 PWM 1, CH4 PWM 2 (the trigger)
    EXPECT_EQ(tim8.CCER, 0x0555u | (1u << 12));            // 3 complementary pairs + CC4E
    EXPECT_EQ(tim8.BDTR, 0x14u | (1u << 10) | (1u << 11)); // DTG, OSSI, OSSR; MOE, BKE clear
    EXPECT_EQ(tim8.CCR4, 3500u - 168u);
    EXPECT_EQ(m1.pwm3.adc_trigger, MC_F405_ADC_TRIG_TIM8_CC4);
    EXPECT_EQ(pwm.cfg.p_fault, &fault);

    // A gate kill of the shared fault driver stops M1's bridge too.
    ASSERT_EQ(mc_hal_pwm3_enable(&pwm.dev), 0);
    EXPECT_NE(tim8.BDTR & MC_F405_TIM_BDTR_MOE, 0u);
    mc_hal_fault_gate_kill(&fault.dev);
    EXPECT_EQ(tim8.BDTR & MC_F405_TIM_BDTR_MOE, 0u);
    EXPECT_EQ(mc_hal_pwm3_enable(&pwm.dev), -EBUSY);
}

// ADC2 injected on TIM8 CC4: ib (13, PC3), ic (12, PC2), vbus (6, PA6).
// JSQR: JL = 2 (three conversions) in bits 21:20, the sequence in the last
// three fields JSQ2..JSQ4 (RM0090 §13.13.12): 13 << 5 | 12 << 10 | 6 << 15.
// CR2: ADON, JEXTSEL 1110 (TIM8 CC4), JEXTEN 01. CR1: SCAN, JEOCIE.
// SMPR1: ch 12, 13 at 15 cycles (001) in bits 8:6 and 11:9; SMPR2: ch 6 at
// 15 cycles (bits 20:18), the thermistor's ch 4 at 144 (110, bits 14:12).
// CCR: ADCPRE 01 (PCLK2 / 4), what M0's set-up writes (the field is common).
// SQR3 = 4: the regular conversion is M1's FET thermistor on PA4.
TEST_F(M1Board, AdcOnAdc2)
{
    mc_f405_adc_t adc{};
    ASSERT_EQ(mc_f405_adc_init(&adc, &m1.adc), 0);
    EXPECT_EQ(adc2.JSQR, (2u << 20) | (13u << 5) | (12u << 10) | (6u << 15));
    EXPECT_EQ(adc2.CR2, 1u | (14u << 16) | (1u << 20));
    EXPECT_EQ(adc2.CR1, (1u << 8) | (1u << 7));
    EXPECT_EQ(adc2.SMPR1, (1u << 6) | (1u << 9));
    EXPECT_EQ(adc2.SMPR2, (1u << 18) | (6u << 12));
    EXPECT_EQ(common.CCR, 1u << 16);
    EXPECT_EQ(adc2.SQR3, 4u);

    // A sample: ib and ic as converted, ia = -(ib + ic), vbus through the
    // board's divider. Independent model in double from the description.
    const mc_board_desc_t &d = mc_board_odrive36_desc;
    const double v_per_count = d.adc_vref_v / 4096.0;
    auto amps = [&](uint32_t raw) {
        return (raw * v_per_count - d.amp_offset_v) / (d.amp_gain_v_per_v * d.shunt_ohm);
    };
    adc2.JDR[0] = 2148u; // ib
    adc2.JDR[1] = 1948u; // ic
    adc2.JDR[2] = 2000u; // vbus
    adc2.SR = MC_F405_ADC_SR_JEOC;
    mc_hal_adc_sample_t s{};
    ASSERT_EQ(mc_hal_adc_read(&adc.dev, &s), 0);
    EXPECT_EQ(s.valid_mask, MC_HAL_ADC_VALID_IA | MC_HAL_ADC_VALID_IB | MC_HAL_ADC_VALID_IC |
                                MC_HAL_ADC_VALID_VBUS);
    // Tolerance: f405_test_util rel_tol (float rounding of a few operations).
    EXPECT_NEAR(s.ib_a, amps(2148u), rel_tol(amps(2148u)));
    EXPECT_NEAR(s.ic_a, amps(1948u), rel_tol(amps(1948u)));
    EXPECT_NEAR(s.ia_a, -(amps(2148u) + amps(1948u)), rel_tol(amps(2148u)) + rel_tol(amps(1948u)));
    const double vbus = 2000u * v_per_count * d.vbus_divider;
    EXPECT_NEAR(s.vbus_v, vbus, rel_tol(vbus));
}

// M1's FET thermistor on PA4 (channel 4), M0's curve: the cubic of the
// description at the converted pin voltage.
TEST_F(M1Board, FetThermistorOnPa4)
{
    mc_f405_adc_t adc{};
    ASSERT_EQ(mc_f405_adc_init(&adc, &m1.adc), 0);
    ASSERT_NE(adc.dev.ops->read_temp, nullptr);
    mc_hal_adc_temp_t t{};
    ASSERT_EQ(mc_hal_adc_read_temp(&adc.dev, &t), 0); // starts channel 4
    EXPECT_EQ(adc2.SQR3, 4u);
    EXPECT_NE(adc2.CR2 & MC_F405_ADC_CR2_SWSTART, 0u);
    adc2.DR = 1500u;
    adc2.SR = MC_F405_ADC_SR_EOC;
    ASSERT_EQ(mc_hal_adc_read_temp(&adc.dev, &t), 0);
    const mc_f405_adc_temp_sensor_t &s = mc_board_odrive36_desc.temp_power_stage;
    const double v = 1500.0 * mc_board_odrive36_desc.adc_vref_v / 4096.0;
    const double t_c =
        s.offset_c + s.slope_c_per_v * v + s.c2_c_per_v2 * v * v + s.c3_c_per_v3 * v * v * v;
    EXPECT_NE(t.valid_mask & MC_HAL_ADC_TEMP_VALID_POWER_STAGE, 0u);
    // Tolerance 1e-3 degC: float evaluation of a cubic of terms up to ~100 degC.
    EXPECT_NEAR(t.power_stage_temp_c, t_c, 1e-3);
    EXPECT_GT(t_c, 0.0); // a plausible board temperature: the channel and curve agree
    EXPECT_LT(t_c, 100.0);
    EXPECT_EQ(t.absent_mask, MC_HAL_ADC_TEMP_VALID_MOTOR); // no motor sensor on M1
}

// TIM4 in encoder mode 3 (SMS = 011, x4), CC1S = CC2S = 01 (TI1, TI2),
// filter ICxF = 4 (M0's) in bits 7:4 and 15:12, ARR = 8192 - 1. Index PC15:
// EXTI line 15 lives in SYSCFG_EXTICR4 bits 15:12 (RM0090 §9.2.6), port C
// = 0010; RTSR bit 15 (rising), IMR bit 15; the EXTI15_10 interrupt (40).
TEST_F(M1Board, EncoderOnTim4IndexOnPc15)
{
    syscfg.EXTICR[3] = 0x0FFFu; // lines 12..14 belong to others: kept
    mc_f405_encoder_t enc{};
    ASSERT_EQ(mc_f405_encoder_init(&enc, &m1.enc), 0);
    EXPECT_EQ(tim4.SMCR, 3u);
    EXPECT_EQ(tim4.CCMR1, 0x01u | (4u << 4) | 0x100u | (4u << 12));
    EXPECT_EQ(tim4.ARR, 8191u);
    EXPECT_EQ(tim4.CCER, 0u); // not inverted
    EXPECT_EQ(tim4.CR1, MC_F405_TIM_CR1_CEN);
    EXPECT_EQ(syscfg.EXTICR[3], 0x2FFFu);
    EXPECT_EQ(exti.RTSR, 1u << 15);
    EXPECT_EQ(exti.FTSR, 0u);
    EXPECT_EQ(exti.IMR, 1u << 15);
    EXPECT_EQ(mc_f405_exti_irq(15u), 40u);

    // The index latches TIM4's count: 16-bit counter at 8191 + 1 wraps.
    tim4.CNT = 5000u;
    exti.PR = 1u << 15;
    EXPECT_TRUE(mc_f405_encoder_index_isr(&enc));
    EXPECT_TRUE(enc.index_seen);
    EXPECT_EQ(enc.index_count, 5000u);
}

// Two DRV8301 on SPI3: M0's on PC13 and M1's on PC14, same mode and rate,
// so one CR1 serves both (no rewrite between their frames); each transfer
// drives its own chip select, both pins outputs, released high.
TEST_F(M1Board, TwoGateDriversShareSpi3)
{
    mc_f405_spi_config_t c0 = m1.drv_spi;
    c0.cs.pin = 13u; // M0's (desc drv_spi_cs)
    mc_f405_spi_t spi_m0{};
    mc_f405_spi_t spi_m1{};
    ASSERT_EQ(mc_f405_spi_init(&spi_m0, &c0), 0);
    ASSERT_EQ(mc_f405_spi_init(&spi_m1, &m1.drv_spi), 0);
    EXPECT_EQ(spi_m1.cfg.cs.pin, 14u);
    EXPECT_TRUE(spi_m1.cfg.cs.active_low);
    EXPECT_EQ(spi_m0.cr1, spi_m1.cr1);
    EXPECT_EQ(spi_m1.sck_hz, 2625000u);              // 42 MHz / 16: at most 2.625 MHz (desc)
    EXPECT_EQ(gpioc.MODER, (1u << 26) | (1u << 28)); // PC13, PC14 outputs (01)

    spi3.SR = (1u << 1) | (1u << 0); // TXE, RXNE: the frame completes
    gpioc.BSRR = 0u;
    ASSERT_EQ(mc_hal_spi_transfer16(&spi_m1.dev, 0x9000u, nullptr), 0);
    EXPECT_EQ(gpioc.BSRR, 1u << 14); // M1's chip select released last
    const uint32_t cr1 = spi3.CR1;
    ASSERT_EQ(mc_hal_spi_transfer16(&spi_m0.dev, 0x9000u, nullptr), 0);
    EXPECT_EQ(gpioc.BSRR, 1u << 13);
    EXPECT_EQ(spi3.CR1, cr1);

    // The DRV8301 driver keeps no globals: two instances, one per chip
    // (each chip's frames through its own chip select), set up in turn,
    // each chip holding the configuration with the other's untouched.
    Drv8301Model chip0;
    Drv8301Model chip1;
    const mc_hal_spi_t bus0 = chip0.spi();
    const mc_hal_spi_t bus1 = chip1.spi();
    mc_drv8301_t drv0{};
    mc_drv8301_t drv1{};
    ASSERT_EQ(mc_drv8301_init(&drv0, &bus0, &mc_board_odrive36_desc.drv8301), 0);
    const size_t frames0 = chip0.frames.size();
    ASSERT_EQ(mc_drv8301_init(&drv1, &bus1, &mc_board_odrive36_desc.drv8301), 0);
    EXPECT_EQ(chip0.frames.size(), frames0); // M1's set-up sent nothing to M0's chip
    EXPECT_EQ(chip0.reg[2], drv0.ctrl1);
    EXPECT_EQ(chip0.reg[3], drv0.ctrl2);
    EXPECT_EQ(chip1.reg[2], drv1.ctrl1);
    EXPECT_EQ(chip1.reg[3], drv1.ctrl2);
    EXPECT_EQ(drv1.status, MC_DRV8301_STATUS_OK);
}

// Refusals: nothing written to the output.
TEST_F(M1Board, ConfigRefusals)
{
    mc_board_f405_m1_cfg_t out{};
    poison(out);
    const auto out0 = snapshot(out);
    const mc_board_desc_t *d = &mc_board_odrive36_desc;
    EXPECT_EQ(mc_board_f405_m1_config(nullptr, &periph, kSysclkHz, kPwmHz, &out), -EINVAL);
    EXPECT_EQ(mc_board_f405_m1_config(d, nullptr, kSysclkHz, kPwmHz, &out), -EINVAL);
    EXPECT_EQ(mc_board_f405_m1_config(d, &periph, 0u, kPwmHz, &out), -EINVAL);
    EXPECT_EQ(mc_board_f405_m1_config(d, &periph, kSysclkHz, 0u, &out), -EINVAL);
    EXPECT_EQ(mc_board_f405_m1_config(d, &periph, kSysclkHz, kPwmHz, nullptr), -EINVAL);
    mc_board_f405_m1_periph_t p = periph;
    p.p_adc2 = nullptr;
    EXPECT_EQ(mc_board_f405_m1_config(d, &p, kSysclkHz, kPwmHz, &out), -EINVAL);
    mc_board_desc_t no_drv = *d;
    no_drv.has_drv8301 = false; // not an ODrive v3.6
    EXPECT_EQ(mc_board_f405_m1_config(&no_drv, &periph, kSysclkHz, kPwmHz, &out), -EINVAL);
    mc_board_desc_t three = *d;
    three.adc_ch_ia = 5u; // phases a, b, c: not the ODrive's b and c
    EXPECT_EQ(mc_board_f405_m1_config(&three, &periph, kSysclkHz, kPwmHz, &out), -EINVAL);
    EXPECT_EQ(snapshot(out), out0);
}
