// A whole board set-up (boards/mc_board_f405.c with the generated
// description) on register files in RAM and, for the DRV8301, a model of
// the chip (tests/unit/drv8301/drv8301_model.h). Expected values come from
// the board's own files read here (pins.csv, board.toml with toml++) and
// from RM0090 / the DRV8301 datasheet (TI SLOS719F) field positions typed
// in this file, not from the generator.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "board_files.h"
#include "drv8301_model.h"

extern "C" {
#include "mc_board_example_gen.h"
#include "mc_board_f405.h"
#include "mc_board_odrive36_24v_gen.h"
#include "mc_board_odrive36_gen.h"
#include "mc_board_vesc6_gen.h"
}

namespace
{

struct Case {
    const char *name;
    const mc_board_desc_t *desc;
};

// Test names and messages show the board's name.
[[maybe_unused]] void PrintTo(const Case &c, std::ostream *os)
{
    *os << c.name;
}

const Case kBoards[] = {
    {"example", &mc_board_example_desc},
    {"odrive36", &mc_board_odrive36_desc},
    {"odrive36_24v", &mc_board_odrive36_24v_desc},
    {"vesc6", &mc_board_vesc6_desc},
};

constexpr uint32_t kSysclkHz = 168000000u;
constexpr uint32_t kPwmHz = 20000u;
constexpr double kVref = 3.3;

// RM0090 bit positions.
constexpr uint32_t kApb1Tim2 = 1u << 0, kApb1Tim3 = 1u << 1, kApb1Tim5 = 1u << 3,
                   kApb1Spi3 = 1u << 15, kApb1Can1 = 1u << 25;
constexpr uint32_t kApb2Tim1 = 1u << 0, kApb2Adc1 = 1u << 8, kApb2Syscfg = 1u << 14;
constexpr uint32_t kBdtrBke = 1u << 12, kBdtrBkp = 1u << 13, kBdtrMoe = 1u << 15;
constexpr uint32_t kEgrBg = 1u << 7;
constexpr uint32_t kCanMsrInak = 1u << 0;

struct Rig {
    mc_f405_gpio_regs_t gpio[MC_F405_GPIO_PORTS]{};
    volatile uint32_t ahb1 = 0u, apb1 = 0u, apb2 = 0u;
    mc_f405_tim_regs_t tim1{}, tim2{}, tim3{}, tim5{};
    mc_f405_adc_regs_t adc{};
    mc_f405_adc_common_regs_t adc_common{};
    mc_f405_can_regs_t can{};
    mc_f405_spi_regs_t spi3{};
    mc_f405_syscfg_regs_t syscfg{};
    mc_f405_exti_regs_t exti{};
    std::vector<uint32_t> delays;
    mc_board_f405_t board{};

    static void delay(void *ctx, uint32_t us)
    {
        static_cast<Rig *>(ctx)->delays.push_back(us);
    }

    mc_board_f405_periph_t periph()
    {
        mc_board_f405_periph_t p{};
        for (unsigned k = 0; k < MC_F405_GPIO_PORTS; ++k) {
            p.p_gpio[k] = &gpio[k];
        }
        p.p_rcc_ahb1enr = &ahb1;
        p.p_rcc_apb1enr = &apb1;
        p.p_rcc_apb2enr = &apb2;
        p.p_tim1 = &tim1;
        p.p_tim2 = &tim2;
        p.p_tim3 = &tim3;
        p.p_tim5 = &tim5;
        p.p_adc1 = &adc;
        p.p_adc_common = &adc_common;
        p.p_can1 = &can;
        p.p_spi3 = &spi3;
        p.p_syscfg = &syscfg;
        p.p_exti = &exti;
        p.delay_us = &Rig::delay;
        p.delay_ctx = this;
        return p;
    }

    mc_board_f405_err_t setup(const mc_board_desc_t *d)
    {
        can.MSR = kCanMsrInak; // the CAN controller acknowledges init mode
        const mc_board_f405_periph_t p = periph();
        return mc_board_f405_setup(&board, d, &p, kSysclkHz, kPwmHz);
    }
};

const Case kDrvBoards[] = {
    {"odrive36", &mc_board_odrive36_desc},
    {"odrive36_24v", &mc_board_odrive36_24v_desc},
    {"vesc6", &mc_board_vesc6_desc},
};

class BoardSetup : public ::testing::TestWithParam<Case>
{
};
class GateDriverBoard : public ::testing::TestWithParam<Case>
{
};

double divider(const toml::table &t)
{
    if (t.at_path("sense.vbus_divider").is_number()) {
        return boards::num(t, "sense.vbus_divider");
    }
    const double top = boards::num(t, "sense.vbus_r_top_ohm");
    const double bottom = boards::num(t, "sense.vbus_r_bottom_ohm");
    return (top + bottom) / bottom;
}

double amps(const toml::table &t, uint32_t raw)
{
    const double v = raw * kVref / 4096.0;
    return (v - boards::num(t, "sense.amp_offset_v")) /
           (boards::num(t, "sense.amp_gain_v_per_v") * boards::num(t, "sense.shunt_ohm"));
}

// Beta model of a thermistor network from board.toml, v(T) and T(v).
double ntc_v(const toml::table &t, const std::string &slot, double t_c)
{
    const std::string s = "thermistor." + slot + ".";
    const double r = boards::num(t, s + "r25_ohm") *
                     std::exp(boards::num(t, s + "beta_k") * (1.0 / (t_c + 273.15) - 1.0 / 298.15));
    const double rf = boards::num(t, s + "r_fixed_ohm");
    const bool low = *t.at_path(s + "side").value<std::string>() == "low";
    return kVref * (low ? r / (r + rf) : rf / (r + rf));
}

double ntc_t(const toml::table &t, const std::string &slot, double v)
{
    const std::string s = "thermistor." + slot + ".";
    const double rf = boards::num(t, s + "r_fixed_ohm");
    const bool low = *t.at_path(s + "side").value<std::string>() == "low";
    const double r = low ? rf * v / (kVref - v) : rf * (kVref - v) / v;
    return 1.0 / (std::log(r / boards::num(t, s + "r25_ohm")) / boards::num(t, s + "beta_k") +
                  1.0 / 298.15) -
           273.15;
}

} // namespace

TEST_P(BoardSetup, ClocksPinsTimersAndAdc)
{
    const Case &c = GetParam();
    const auto pins = boards::read_pins(c.name);
    const toml::table t = boards::read_toml(c.name);
    Rig rig;
    ASSERT_EQ(rig.setup(c.desc), MC_BOARD_F405_OK) << mc_board_f405_err_name(rig.board.err);
    ASSERT_NE(rig.board.hal.adc, nullptr);
    ASSERT_NE(rig.board.hal.pwm3, nullptr);
    ASSERT_NE(rig.board.hal.encoder, nullptr);
    ASSERT_NE(rig.board.hal.fault, nullptr);
    EXPECT_NE(rig.board.hal.can, nullptr);

    // Clocks: the used GPIO ports, TIM3/TIM5/CAN1 (+SPI3 with a DRV8301),
    // TIM1/ADC1.
    uint32_t ports = 0u;
    for (const auto &p : pins) {
        ports |= 1u << p.port;
    }
    EXPECT_EQ(rig.ahb1, ports);
    EXPECT_EQ(rig.apb1, kApb1Tim3 | kApb1Tim5 | kApb1Can1 | (c.desc->has_drv8301 ? kApb1Spi3 : 0u) |
                            (c.desc->has_brake ? kApb1Tim2 : 0u));
    const auto *z = boards::find(pins, "enc_z");
    EXPECT_EQ(rig.apb2, kApb2Tim1 | kApb2Adc1 | (z != nullptr ? kApb2Syscfg : 0u));

    // The index (enc_z) on its EXTI line (RM0090 §9.2.3..6: EXTICRn holds
    // lines 4(n-1)..4n-1, 4 bits each, the port's number; §12.3: rising
    // edge, unmasked), the TIM3 encoder as the drive's encoder.
    if (z != nullptr) {
        EXPECT_EQ((rig.syscfg.EXTICR[z->pin / 4] >> (4 * (z->pin % 4))) & 0xFu, unsigned(z->port));
        EXPECT_EQ(rig.exti.RTSR, 1u << z->pin);
        EXPECT_EQ(rig.exti.FTSR, 0u);
        EXPECT_EQ(rig.exti.IMR, 1u << z->pin);
        EXPECT_EQ(mc_board_f405_exti_irq(c.desc),
                  z->pin <= 4 ? 6u + z->pin : (z->pin <= 9 ? 23u : 40u));
    } else {
        EXPECT_EQ(rig.exti.IMR, 0u);
        EXPECT_EQ(mc_board_f405_exti_irq(c.desc), 0xFFFFFFFFu);
    }
    EXPECT_EQ(rig.board.hal.encoder, &rig.board.enc.dev);

    // No driver undid a pin's mode (a BKIN left in its alternate function,
    // the chip select and gate enable outputs, nFAULT an input).
    for (const auto &p : pins) {
        if (boards::is_hall(p.signal)) {
            continue; // the Hall table is not applied with the encoder fitted
        }
        EXPECT_EQ((rig.gpio[p.port].MODER >> (2 * p.pin)) & 3u, boards::moder_code(p.mode))
            << p.signal;
    }
    // Gate enable raised last by the fault driver (active high: BSRR set),
    // after the reset pulse, and on DRV8301 boards followed by the 20 ms
    // start-up wait.
    const auto *en = boards::find(pins, "gate_enable");
    EXPECT_EQ(rig.gpio[en->port].BSRR, 1u << en->pin);
    const std::vector<uint32_t> want_delays =
        c.desc->has_drv8301 ? std::vector<uint32_t>{40u, 20000u} : std::vector<uint32_t>{40u};
    EXPECT_EQ(rig.delays, want_delays);

    // TIM1: outputs off, break input only where the board has one (active
    // low), dead time = ceil(ns * 168 MHz) ticks (all below 128: DTG[7] = 0).
    EXPECT_EQ(rig.tim1.BDTR & kBdtrMoe, 0u);
    const bool brk = *t.at_path("pwm.break_input").value<std::string>() == "overcurrent";
    EXPECT_EQ((rig.tim1.BDTR & kBdtrBke) != 0u, brk);
    EXPECT_EQ(rig.tim1.BDTR & kBdtrBkp, 0u);
    const double dt_ticks = boards::num(t, "pwm.deadtime_ns") * 1e-9 * kSysclkHz;
    ASSERT_LT(dt_ticks, 128.0);
    EXPECT_EQ(rig.tim1.BDTR & 0xFFu, uint32_t(std::ceil(dt_ticks - 1e-9)));

    // TIM3 encoder: ARR = counts per revolution - 1.
    EXPECT_EQ(rig.tim3.ARR, uint32_t(boards::num(t, "encoder.counts_per_rev")) - 1u);

    // ADC1 injected sequence: the measured phases in phase order, then the
    // bus, from the pins' channels; JL = length - 1, sequence in the last
    // JSQ fields (RM0090 §13.13.12).
    std::vector<unsigned> seq;
    std::vector<int> phase;
    const char *names[3] = {"adc_ia", "adc_ib", "adc_ic"};
    for (int k = 0; k < 3; ++k) {
        if (const auto *p = boards::find(pins, names[k])) {
            seq.push_back(*boards::adc_channel(p->name));
            phase.push_back(k);
        }
    }
    seq.push_back(*boards::adc_channel(boards::find(pins, "adc_vbus")->name));
    const unsigned n = unsigned(seq.size());
    uint32_t jsqr = (n - 1u) << 20;
    for (unsigned k = 0; k < n; ++k) {
        jsqr |= seq[k] << (5u * (4u - n + k));
    }
    EXPECT_EQ(rig.adc.JSQR, jsqr);

    // A conversion through the board's scaling: +150 counts on the first
    // measured phase, -60 on the second, +25 on a third, bus at 2500.
    const uint32_t raws[3] = {2048u + 150u, 2048u - 60u, 2048u + 25u};
    for (unsigned k = 0; k + 1 < n; ++k) {
        rig.adc.JDR[k] = raws[k];
    }
    rig.adc.JDR[n - 1] = 2500u;
    rig.adc.SR = MC_F405_ADC_SR_JEOC;
    mc_hal_adc_sample_t s{};
    ASSERT_EQ(mc_hal_adc_read(rig.board.hal.adc, &s), 0);
    double want[3] = {0.0, 0.0, 0.0};
    double sum_abs = 0.0;
    for (unsigned k = 0; k + 1 < n; ++k) {
        want[phase[k]] = amps(t, raws[k]);
        sum_abs += std::fabs(want[phase[k]]);
    }
    if (boards::find(pins, "adc_ia") == nullptr) {
        want[0] = -(want[1] + want[2]); // ODrive: phase A from B and C
    }
    // Float: a few roundings of 2^-24 on values below 200 A; 1e-5 relative
    // to the inputs' size covers them with margin and catches any wrong
    // constant (one count is 1e-3 of the 150-count signal).
    const double tol = 1e-5 * (sum_abs + 1.0);
    EXPECT_NEAR(s.ia_a, want[0], tol);
    EXPECT_NEAR(s.ib_a, want[1], tol);
    if (boards::find(pins, "adc_ic") != nullptr) {
        EXPECT_NEAR(s.ic_a, want[2], tol);
        EXPECT_EQ(s.valid_mask, MC_HAL_ADC_VALID_ALL);
    } else {
        EXPECT_EQ(s.valid_mask, MC_HAL_ADC_VALID_IA | MC_HAL_ADC_VALID_IB | MC_HAL_ADC_VALID_VBUS);
    }
    const double vbus = 2500.0 * kVref / 4096.0 * divider(t);
    EXPECT_NEAR(s.vbus_v, vbus, 1e-5 * vbus);
}

// The ODrive v3.6 variants (issue 29): each image reads its own board's bus.
// A 24 V bus on the 24 V board (divider 11) gives the pin 24 / 11 V; the
// 24 V image reads it back within one count (3.3 V * 11 / 4096 = 8.9 mV, the
// rounding of the code), while the 56 V image (divider 19) would read it
// 19 / 11 = 1.73 times high, the error the board owner had to fix by hand.
// Likewise 48 V on the 56 V board through its own image.
TEST(BoardBus, OdriveVariantsReadTheirOwnBus)
{
    struct V {
        const mc_board_desc_t *desc;
        double vbus_v, divider;
    };
    for (const V &v :
         {V{&mc_board_odrive36_24v_desc, 24.0, 11.0}, V{&mc_board_odrive36_desc, 48.0, 19.0}}) {
        SCOPED_TRACE(v.desc->name);
        Rig rig;
        ASSERT_EQ(rig.setup(v.desc), MC_BOARD_F405_OK) << mc_board_f405_err_name(rig.board.err);
        const double lsb_v = kVref * v.divider / 4096.0;
        const auto code = uint32_t(std::lround(v.vbus_v / lsb_v));
        rig.adc.JDR[0] = 2048u; /* phases b, c at 0 A, then the bus */
        rig.adc.JDR[1] = 2048u;
        rig.adc.JDR[2] = code;
        rig.adc.SR = MC_F405_ADC_SR_JEOC;
        mc_hal_adc_sample_t s{};
        ASSERT_EQ(mc_hal_adc_read(rig.board.hal.adc, &s), 0);
        EXPECT_NEAR(s.vbus_v, v.vbus_v, lsb_v);
    }
    EXPECT_NEAR(double(mc_board_odrive36_desc.vbus_divider) /
                    double(mc_board_odrive36_24v_desc.vbus_divider),
                19.0 / 11.0, 1e-6);
}

// Thermistors through the ADC driver against the board.toml models: the
// ODrive's cubic in v / 3.3 V exactly (float evaluation: 5e-3 degC), an
// NTC's Beta curve within 0.5 degC (linear interpolation between table
// points at most 10 degC apart; the generator reports the largest error,
// 0.35 degC, in boards/README.md).
TEST_P(BoardSetup, ThermistorsFollowTheirModels)
{
    const Case &c = GetParam();
    const toml::table t = boards::read_toml(c.name);
    Rig rig;
    ASSERT_EQ(rig.setup(c.desc), MC_BOARD_F405_OK);
    const char *slots[2] = {"power_stage", "motor"};
    const mc_f405_adc_temp_sensor_t *sensors[2] = {&c.desc->temp_power_stage, &c.desc->temp_motor};
    int checked = 0;
    for (int k = 0; k < 2; ++k) {
        const std::string slot = slots[k];
        if (!t.at_path("thermistor." + slot).is_table()) {
            EXPECT_EQ(sensors[k]->channel, MC_F405_ADC_CH_NONE) << slot;
            continue;
        }
        const std::string model = *t.at_path("thermistor." + slot + ".model").value<std::string>();
        for (double t_c : {0.0, 25.0, 60.0, 95.0, 110.0}) {
            SCOPED_TRACE(slot + " at " + std::to_string(t_c));
            uint32_t raw = 0u;
            double want = 0.0;
            double tol = 0.0;
            if (model == "ntc") {
                raw = uint32_t(std::lround(ntc_v(t, slot, t_c) / kVref * 4096.0));
                want = ntc_t(t, slot, raw * kVref / 4096.0);
                tol = 0.5;
            } else {
                // ODrive: T = cubic in x = v / 3.3 V, coefficients highest first.
                const auto *arr = t.at_path("thermistor." + slot + ".coeffs_high_first").as_array();
                ASSERT_NE(arr, nullptr);
                // Invert by search: the raw count whose temperature is nearest t_c.
                double best = 1e9;
                for (uint32_t r = 1u; r < 4095u; ++r) {
                    double y = 0.0;
                    for (const auto &e : *arr) {
                        y = y * (r / 4096.0) + *e.value<double>();
                    }
                    if (std::fabs(y - t_c) < best) {
                        best = std::fabs(y - t_c);
                        raw = r;
                        want = y;
                    }
                }
                tol = 5e-3;
            }
            // Start conversions until this slot's is running, then deliver
            // its result (EOC set; reading DR clears it in the hardware).
            mc_hal_adc_temp_t temp{};
            auto deliver = [&](uint32_t value) {
                rig.adc.DR = value;
                rig.adc.SR = MC_F405_ADC_SR_EOC;
                const int rc = mc_hal_adc_read_temp(rig.board.hal.adc, &temp);
                rig.adc.SR = 0u;
                return rc;
            };
            ASSERT_EQ(mc_hal_adc_read_temp(rig.board.hal.adc, &temp), 0);
            while (rig.adc.SQR3 != sensors[k]->channel) {
                ASSERT_EQ(deliver(2048u), 0);
            }
            ASSERT_EQ(deliver(raw), 0);
            const uint32_t bit =
                k == 0 ? MC_HAL_ADC_TEMP_VALID_POWER_STAGE : MC_HAL_ADC_TEMP_VALID_MOTOR;
            ASSERT_NE(temp.valid_mask & bit, 0u);
            EXPECT_NEAR(k == 0 ? temp.power_stage_temp_c : temp.motor_temp_c, want, tol);
            ++checked;
        }
    }
    if (std::string(c.name) == "example") {
        EXPECT_EQ(checked, 0);
    } else {
        EXPECT_GT(checked, 0);
    }
}

// The DRV8301 set-up a board's description asks for, on a model of the chip:
// Control 1 = OC_ADJ_SET[10:6] OCP_MODE[5:4] PWM_MODE[3] GATE_CURRENT[1:0],
// Control 2 = OC_TOFF[6] GAIN[3:2] OCTW_MODE[1:0], from board.toml.
TEST_P(BoardSetup, GateDriverRegistersFromBoardToml)
{
    const Case &c = GetParam();
    const toml::table t = boards::read_toml(c.name);
    Rig rig;
    ASSERT_EQ(rig.setup(c.desc), MC_BOARD_F405_OK);
    Drv8301Model chip;
    const mc_hal_spi_t spi = chip.spi();
    ASSERT_EQ(mc_board_f405_gate_driver_setup(&rig.board, c.desc, &spi), MC_BOARD_F405_OK);
    if (!t.at_path("drv8301").is_table()) {
        EXPECT_FALSE(c.desc->has_drv8301);
        EXPECT_TRUE(chip.frames.empty());
        return;
    }
    const std::map<std::string, uint32_t> ocp = {
        {"current_limit", 0u}, {"latch", 1u}, {"report_only", 2u}, {"disabled", 3u}};
    const std::map<std::string, uint32_t> octw = {
        {"ot_and_oc", 0u}, {"ot_only", 1u}, {"oc_only", 2u}};
    const std::map<double, uint32_t> gate = {{1.7, 0u}, {0.7, 1u}, {0.25, 2u}};
    const std::map<int64_t, uint32_t> gain = {{10, 0u}, {20, 1u}, {40, 2u}, {80, 3u}};
    const uint32_t ctrl1 = (uint32_t(boards::num(t, "drv8301.oc_adj_set")) << 6) |
                           (ocp.at(*t.at_path("drv8301.ocp_mode").value<std::string>()) << 4) |
                           ((*t.at_path("drv8301.pwm_mode").value<int64_t>() == 3 ? 1u : 0u) << 3) |
                           gate.at(boards::num(t, "drv8301.gate_current_a"));
    const uint32_t ctrl2 =
        ((*t.at_path("drv8301.oc_toff").value<std::string>() == "off_time" ? 1u : 0u) << 6) |
        (gain.at(*t.at_path("drv8301.gain_v_per_v").value<int64_t>()) << 2) |
        octw.at(*t.at_path("drv8301.octw_mode").value<std::string>());
    EXPECT_EQ(chip.reg[2], ctrl1);
    EXPECT_EQ(chip.reg[3], ctrl2);
    // The first two frames are the writes: bit 15 = 0, address in 14:11.
    ASSERT_GE(chip.frames.size(), 2u);
    EXPECT_EQ(chip.frames[0], (2u << 11) | ctrl1);
    EXPECT_EQ(chip.frames[1], (3u << 11) | ctrl2);
    EXPECT_EQ(rig.board.drv.status, MC_DRV8301_STATUS_OK);
    // Where the DRV8301 amplifies the shunts, its gain is the scaling's.
    if (*t.at_path("sense.amplifier").value<std::string>() == "drv8301") {
        EXPECT_EQ(double(*t.at_path("drv8301.gain_v_per_v").value<int64_t>()),
                  boards::num(t, "sense.amp_gain_v_per_v"));
    }
}

// A DRV8301 that does not answer stops the set-up with the gates killed:
// TIM1 break generated (EGR.BG) and EN_GATE driven low (BSRR reset half).
TEST_P(GateDriverBoard, SilentGateDriverKillsTheGates)
{
    const Case &c = GetParam();
    ASSERT_TRUE(c.desc->has_drv8301);
    const auto pins = boards::read_pins(c.name);
    Rig rig;
    ASSERT_EQ(rig.setup(c.desc), MC_BOARD_F405_OK);
    Drv8301Model chip;
    chip.miso_stuck_high = true;
    const mc_hal_spi_t spi = chip.spi();
    EXPECT_EQ(mc_board_f405_gate_driver_setup(&rig.board, c.desc, &spi),
              MC_BOARD_F405_ERR_GATE_DRIVER);
    EXPECT_EQ(rig.board.err, MC_BOARD_F405_ERR_GATE_DRIVER);
    EXPECT_EQ(rig.board.drv.status, MC_DRV8301_STATUS_NO_RESPONSE);
    EXPECT_EQ(rig.tim1.EGR & kEgrBg, kEgrBg);
    const auto *en = boards::find(pins, "gate_enable");
    EXPECT_EQ(rig.gpio[en->port].BSRR, 1u << (en->pin + 16));
}

// After a gate kill (EN_GATE low resets the chip: its settings are lost) the
// board is not ready; after the release it waits the 20 ms start-up time in
// slow-loop periods, then writes and verifies the set-up again.
TEST_P(GateDriverBoard, SetupWrittenAgainAfterKillAndRelease)
{
    const Case &c = GetParam();
    const auto pins = boards::read_pins(c.name);
    Rig rig;
    ASSERT_EQ(rig.setup(c.desc), MC_BOARD_F405_OK);
    Drv8301Model chip;
    const mc_hal_spi_t spi = chip.spi();
    ASSERT_EQ(mc_board_f405_gate_driver_setup(&rig.board, c.desc, &spi), MC_BOARD_F405_OK);
    const uint16_t ctrl1 = chip.reg[2];
    const uint16_t ctrl2 = chip.reg[3];
    const auto *nf = boards::find(pins, "gate_fault");
    rig.gpio[nf->port].IDR = 1u << nf->pin; // nFAULT high: no fault
    EXPECT_TRUE(mc_board_f405_gate_driver_supervise(&rig.board, c.desc, &spi, 1000u, false));

    ASSERT_EQ(mc_hal_fault_gate_kill(rig.board.hal.fault), 0);
    chip.power_reset();
    EXPECT_FALSE(mc_board_f405_gate_driver_supervise(&rig.board, c.desc, &spi, 1000u, false));
    ASSERT_EQ(mc_hal_fault_gate_release(rig.board.hal.fault), 0);
    chip.frames.clear();
    for (int k = 0; k < 19; ++k) { // 19 ms: still inside the start-up time
        EXPECT_FALSE(mc_board_f405_gate_driver_supervise(&rig.board, c.desc, &spi, 1000u, false));
    }
    EXPECT_TRUE(chip.frames.empty());
    EXPECT_TRUE(mc_board_f405_gate_driver_supervise(&rig.board, c.desc, &spi, 1000u, false));
    EXPECT_EQ(chip.reg[2], ctrl1);
    EXPECT_EQ(chip.reg[3], ctrl2);
    EXPECT_TRUE(rig.board.drv_ready);
}

// If the set-up fails after a release, the gates are killed again.
TEST_P(GateDriverBoard, FailedRearmKillsAgain)
{
    const Case &c = GetParam();
    Rig rig;
    ASSERT_EQ(rig.setup(c.desc), MC_BOARD_F405_OK);
    Drv8301Model chip;
    const mc_hal_spi_t spi = chip.spi();
    ASSERT_EQ(mc_board_f405_gate_driver_setup(&rig.board, c.desc, &spi), MC_BOARD_F405_OK);
    ASSERT_EQ(mc_hal_fault_gate_kill(rig.board.hal.fault), 0);
    EXPECT_FALSE(mc_board_f405_gate_driver_supervise(&rig.board, c.desc, &spi, 1000u, false));
    const auto pins = boards::read_pins(c.name); // kept: find() points into it
    const auto *nf = boards::find(pins, "gate_fault");
    rig.gpio[nf->port].IDR = 1u << nf->pin;
    ASSERT_EQ(mc_hal_fault_gate_release(rig.board.hal.fault), 0);
    ASSERT_FALSE(rig.board.fault.killed);
    chip.miso_stuck_high = true; // the chip does not come back
    for (int k = 0; k < 20; ++k) {
        EXPECT_FALSE(mc_board_f405_gate_driver_supervise(&rig.board, c.desc, &spi, 1000u, false));
    }
    EXPECT_TRUE(rig.board.fault.killed);
    EXPECT_EQ(rig.board.drv.status, MC_DRV8301_STATUS_NO_RESPONSE);
}

// nFAULT asserts with a latched over-current in the chip: the status
// registers are read at once (named faults); the chip's latch is reset
// (GATE_RESET) only after the drive has recorded its hardware fault, and
// only once per assertion.
TEST_P(GateDriverBoard, NfaultReadsFaultsThenResetsLatchOnce)
{
    const Case &c = GetParam();
    const auto pins = boards::read_pins(c.name);
    Rig rig;
    ASSERT_EQ(rig.setup(c.desc), MC_BOARD_F405_OK);
    Drv8301Model chip;
    const mc_hal_spi_t spi = chip.spi();
    ASSERT_EQ(mc_board_f405_gate_driver_setup(&rig.board, c.desc, &spi), MC_BOARD_F405_OK);
    const auto *nf = boards::find(pins, "gate_fault");
    rig.gpio[nf->port].IDR = 0u;          // nFAULT low (active)
    chip.reg[0] = (1u << 3) | (1u << 10); // FETHB_OC, FAULT
    EXPECT_TRUE(mc_board_f405_gate_driver_supervise(&rig.board, c.desc, &spi, 1000u, false));
    EXPECT_EQ(rig.board.drv.faults, MC_DRV8301_FAULT_FETHB_OC | MC_DRV8301_FAULT_FAULT);
    EXPECT_STREQ(mc_drv8301_fault_name(MC_DRV8301_FAULT_FETHB_OC), "FETHB_OC");
    EXPECT_EQ(chip.gate_resets, 0);
    chip.reg[0] = (1u << 3) | (1u << 10); // still latched
    EXPECT_TRUE(mc_board_f405_gate_driver_supervise(&rig.board, c.desc, &spi, 1000u, true));
    EXPECT_EQ(chip.gate_resets, 1);
    EXPECT_EQ(chip.reg[0], 0u);
    EXPECT_TRUE(mc_board_f405_gate_driver_supervise(&rig.board, c.desc, &spi, 1000u, true));
    EXPECT_EQ(chip.gate_resets, 1);         // once per assertion
    rig.gpio[nf->port].IDR = 1u << nf->pin; // released
    EXPECT_TRUE(mc_board_f405_gate_driver_supervise(&rig.board, c.desc, &spi, 1000u, false));
    EXPECT_EQ(chip.gate_resets, 1);
}

// A missing peripheral or description is refused before any register is
// written.
TEST(BoardSetupArgs, Refused)
{
    Rig rig;
    mc_board_f405_periph_t p = rig.periph();
    p.p_spi3 = nullptr; // the ODrive needs SPI3
    EXPECT_EQ(mc_board_f405_setup(&rig.board, &mc_board_odrive36_desc, &p, kSysclkHz, kPwmHz),
              MC_BOARD_F405_ERR_ARG);
    p = rig.periph();
    EXPECT_EQ(mc_board_f405_setup(&rig.board, nullptr, &p, kSysclkHz, kPwmHz),
              MC_BOARD_F405_ERR_ARG);
    EXPECT_EQ(mc_board_f405_setup(&rig.board, &mc_board_odrive36_desc, &p, 0u, kPwmHz),
              MC_BOARD_F405_ERR_ARG);
    EXPECT_EQ(rig.ahb1, 0u);
    EXPECT_EQ(rig.apb1, 0u);
    EXPECT_EQ(rig.gpio[1].MODER, 0u);
    EXPECT_STREQ(mc_board_f405_err_name(MC_BOARD_F405_ERR_GATE_DRIVER), "gate driver");
}

INSTANTIATE_TEST_SUITE_P(Boards, BoardSetup, ::testing::ValuesIn(kBoards),
                         [](const ::testing::TestParamInfo<Case> &i) {
                             return std::string(i.param.name);
                         });
INSTANTIATE_TEST_SUITE_P(Boards, GateDriverBoard, ::testing::ValuesIn(kDrvBoards),
                         [](const ::testing::TestParamInfo<Case> &i) {
                             return std::string(i.param.name);
                         });

// The ODrive v3.6 with an absolute encoder on SPI3 (board.toml type
// as5047p or ma732): its own device on the shared SPI3 (RM0090 §28.5.1
// CR1: the AS5047P in mode 1 at 42 MHz / 8 = 5.25 MHz <= 10 MHz, BR = 010;
// the MA732 in mode 3 at 42 / 2 = 21 MHz <= 25 MHz, BR = 000), chip
// select PA0 (GPIO1) released high, the chip driver as the drive's
// encoder, probed at set-up. A register file answers every frame with the
// word sent (loopback): no chip answers so, and the set-up says so.
TEST(BoardSpiEncoder, OdriveAbsoluteEncoderOnSpi3)
{
    constexpr uint32_t kCpha = 1u << 0, kCpol = 1u << 1, kMstr = 1u << 2, kSpe = 1u << 6,
                       kSsi = 1u << 8, kSsm = 1u << 9, kDff = 1u << 11;
    for (const auto type : {MC_BOARD_ENC_AS5047P, MC_BOARD_ENC_MA732}) {
        mc_board_desc_t d = mc_board_odrive36_desc;
        d.enc_type = type;
        Rig rig;
        rig.spi3.SR = (1u << 0) | (1u << 1); // RXNE, TXE: frames complete
        EXPECT_EQ(rig.setup(&d), MC_BOARD_F405_ERR_SPIENC);
        EXPECT_EQ(rig.board.enc_probe_rc, -EPROTO);
        const bool as = (type == MC_BOARD_ENC_AS5047P);
        EXPECT_EQ(rig.board.enc_spi.cr1,
                  kMstr | kSpe | kSsi | kSsm | kDff | kCpha | (as ? (2u << 3) : kCpol));
        EXPECT_EQ(rig.board.enc_spi.sck_hz, as ? 5250000u : 21000000u);
        EXPECT_EQ(rig.board.enc_spi.cfg.cs.p_port, &rig.gpio[0]);
        EXPECT_EQ(rig.board.enc_spi.cfg.cs.pin, 0u);
        EXPECT_TRUE(rig.board.enc_spi.cfg.cs.active_low);
        EXPECT_EQ((rig.gpio[0].MODER >> 0) & 3u, 1u); // PA0 output
        EXPECT_EQ(rig.gpio[0].BSRR & 1u, 1u);         // released (high) last
        EXPECT_EQ(rig.board.hal.encoder, as ? &rig.board.as5047p.dev : &rig.board.ma732.dev);
        EXPECT_NE(rig.apb1 & kApb1Spi3, 0u);
    }
    // A board without a chip select for it refuses the type.
    mc_board_desc_t d = mc_board_vesc6_desc;
    d.enc_type = MC_BOARD_ENC_AS5047P;
    Rig rig;
    EXPECT_EQ(rig.setup(&d), MC_BOARD_F405_ERR_ARG);
    EXPECT_STREQ(mc_board_f405_err_name(MC_BOARD_F405_ERR_SPIENC), "absolute encoder");
}

// Hall sensors fitted (board.toml type hall): the Hall table over the
// encoder's pins (inputs with pull-ups), the inputs read as one code, no
// encoder for the drive until the Hall kernel is bound to it.
TEST(BoardHall, HallInputsOnTheEncoderPins)
{
    for (const Case &c : kDrvBoards) {
        SCOPED_TRACE(c.name);
        mc_board_desc_t d = *c.desc;
        d.enc_type = MC_BOARD_ENC_HALL;
        Rig rig;
        ASSERT_EQ(rig.setup(&d), MC_BOARD_F405_OK) << mc_board_f405_err_name(rig.board.err);
        EXPECT_EQ(rig.board.hal.encoder, nullptr);
        const auto pins = boards::read_pins(c.name);
        uint32_t want = 0u;
        for (int k = 0; k < 3; ++k) {
            const char *sig[3] = {"hall_a", "hall_b", "hall_c"};
            const auto *p = boards::find(pins, sig[k]);
            ASSERT_NE(p, nullptr);
            EXPECT_EQ((rig.gpio[p->port].MODER >> (2 * p->pin)) & 3u, 0u) << sig[k]; // input
            EXPECT_EQ((rig.gpio[p->port].PUPDR >> (2 * p->pin)) & 3u, 1u) << sig[k]; // pull-up
            if (k != 1) {
                rig.gpio[p->port].IDR |= 1u << p->pin; // A and C high: code 5
                want |= 1u << k;
            }
        }
        uint32_t code = 0u;
        ASSERT_EQ(mc_hal_hall_read(&rig.board.hall.dev, &code), 0);
        EXPECT_EQ(code, want);
    }
}

// SPI3 scheduled on the gate-driver boards: the slow side's handle (the
// one the binding hands to the DRV8301 calls) runs frames directly until
// the fast loop starts (mc_spisched_defer).
TEST(BoardSpiSchedule, GateDriverHandleDirectUntilDeferred)
{
    Rig rig;
    ASSERT_EQ(rig.setup(&mc_board_odrive36_desc), MC_BOARD_F405_OK);
    rig.spi3.SR = (1u << 0) | (1u << 1);
    uint16_t rx = 0u;
    ASSERT_EQ(mc_hal_spi_transfer16(&rig.board.sched.dev, 0x9000u, &rx), 0);
    EXPECT_EQ(rig.spi3.DR, 0x9000u);                   // on the bus at once
    EXPECT_FALSE(mc_board_f405_fast_slot(&rig.board)); // nothing waits
}

// The configuration's CAN bit rate on the controller (issue 19): BTR from
// the APB1 clock (sysclk / 4 = 42 MHz) at the 87.5 % sample point, by the
// formula of RM0090 §32.7.7, bit = (1 + BS1 + BS2) tq, tq = (BRP + 1) / pclk;
// BTR = BRP | (BS1 - 1) << 16 | (BS2 - 1) << 20 | (SJW - 1) << 24. Values
// worked by hand: the exact splits with the sample point nearest 87.5 %,
// the one with more tq on a tie.
//   125 kbit/s: 336 clocks: 16 tq of 21 clocks, sample at 14/16 = 87.5 %:
//               BRP 20, BS1 13, BS2 2 -> 0x001C0014;
//   250 kbit/s: 168 clocks: 8 tq of 21, sample at 7/8: BRP 20, BS1 6,
//               BS2 1 -> 0x00050014 (no 16-tq split: 168 / 16 is not whole);
//   500 kbit/s: 84 clocks: 14 tq of 6, sample at 12/14: -> 0x001A0005;
//   1 Mbit/s:   42 clocks: 14 tq of 3 -> 0x001A0002.
TEST_P(BoardSetup, CanBitRateFromTheParameter)
{
    const Case &c = GetParam();
    Rig rig;
    ASSERT_EQ(rig.setup(c.desc), MC_BOARD_F405_OK) << mc_board_f405_err_name(rig.board.err);
    ASSERT_TRUE(rig.board.can_ok);
    EXPECT_EQ(rig.can.BTR, 0x001A0005u); // the set-up's 500 kbit/s
    const struct {
        uint32_t bps, btr;
    } kRates[] = {{125000u, 0x001C0014u},
                  {250000u, 0x00050014u},
                  {1000000u, 0x001A0002u},
                  {500000u, 0x001A0005u}};
    for (const auto &r : kRates) {
        EXPECT_EQ(mc_board_f405_can_set_bitrate(&rig.board, r.bps), MC_BOARD_F405_OK) << r.bps;
        EXPECT_EQ(rig.can.BTR, r.btr) << r.bps;
        EXPECT_EQ(rig.board.can.cfg.bitrate_bps, r.bps);
        EXPECT_EQ(rig.board.hal.can, &rig.board.can.dev) << r.bps;
    }
    // Unsupported rates: refused by name, the controller keeps its timing.
    for (const uint32_t bps : {0u, 100000u, 800000u, 333333u, 2000000u}) {
        EXPECT_EQ(mc_board_f405_can_set_bitrate(&rig.board, bps), MC_BOARD_F405_ERR_CAN_BITRATE)
            << bps;
        EXPECT_EQ(rig.can.BTR, 0x001A0005u) << bps;
    }
    EXPECT_STREQ(mc_board_f405_err_name(MC_BOARD_F405_ERR_CAN_BITRATE), "CAN bit rate");
}

// On the HSI fallback (16 MHz, APB1 4 MHz) 1 Mbit/s has 4 tq per bit, below
// bxCAN's 8: refused although the parameter allows it; 125 kbit/s is timed
// (32 clocks: 16 tq of 2, BRP 1, BS1 13, BS2 2 -> 0x001C0001).
TEST(BoardCanBitRate, RateTheClockCannotTimeIsRefused)
{
    Rig rig;
    rig.can.MSR = kCanMsrInak;
    const mc_board_f405_periph_t p = rig.periph();
    ASSERT_EQ(mc_board_f405_setup(&rig.board, &mc_board_odrive36_desc, &p, 16000000u, kPwmHz),
              MC_BOARD_F405_OK);
    const uint32_t btr0 = rig.can.BTR;
    EXPECT_EQ(mc_board_f405_can_set_bitrate(&rig.board, 1000000u), MC_BOARD_F405_ERR_CAN_BITRATE);
    EXPECT_EQ(rig.can.BTR, btr0);
    EXPECT_EQ(mc_board_f405_can_set_bitrate(&rig.board, 125000u), MC_BOARD_F405_OK);
    EXPECT_EQ(rig.can.BTR, 0x001C0001u);
}

// The brake chopper (board.toml [brake], pins.csv brake_l/brake_h): on a
// board with one, TIM2 on the description's channels, centre-aligned
// (RM0090 §18.4.1 CMS = 11), both channels PWM mode 2 (OCxM = 111) with
// preload (OCxPE), the low switch's polarity inverted (CCxP: on while
// CNT < CCRl) and both outputs enabled, ARR the period, both switches off
// at boot; without one no handle, TIM2 untouched and its clock off.
TEST_P(BoardSetup, BrakeChopperFromBoardToml)
{
    const Case &c = GetParam();
    const toml::table t = boards::read_toml(c.name);
    const bool present = t.at_path("brake.present").value<bool>().value();
    Rig rig;
    ASSERT_EQ(rig.setup(c.desc), MC_BOARD_F405_OK) << mc_board_f405_err_name(rig.board.err);
    ASSERT_EQ(c.desc->has_brake, present);
    if (!present) {
        EXPECT_EQ(rig.board.hal.brake, nullptr);
        EXPECT_EQ(rig.apb1 & kApb1Tim2, 0u);
        EXPECT_EQ(rig.tim2.CR1 | rig.tim2.CCER | rig.tim2.CCMR1 | rig.tim2.CCMR2 | rig.tim2.ARR |
                      rig.tim2.CCR1 | rig.tim2.CCR2 | rig.tim2.CCR3 | rig.tim2.CCR4,
                  0u);
        return;
    }
    ASSERT_EQ(rig.board.hal.brake, &rig.board.brake.dev);
    EXPECT_EQ(t.at_path("brake.timer").value<std::string>().value(), "tim2");
    const auto lo = unsigned(boards::num(t, "brake.ch_low"));
    const auto hi = unsigned(boards::num(t, "brake.ch_high"));
    const auto arr = uint32_t(boards::num(t, "brake.period_clocks"));
    const auto dead = uint32_t(boards::num(t, "brake.deadtime_clocks"));
    const double duty_max = boards::num(t, "brake.duty_max");
    // Both pins in their alternate function AF1 (TIM2), as pins.csv says.
    const auto pins = boards::read_pins(c.name);
    for (const char *sig : {"brake_l", "brake_h"}) {
        const auto *pin = boards::find(pins, sig);
        ASSERT_NE(pin, nullptr) << sig;
        EXPECT_EQ(pin->mode, "af") << sig;
        EXPECT_EQ((rig.gpio[pin->port].MODER >> (2 * pin->pin)) & 3u, 2u) << sig;
        EXPECT_EQ((rig.gpio[pin->port].AFR[pin->pin / 8] >> (4 * (pin->pin % 8))) & 0xFu, 1u)
            << sig;
    }
    EXPECT_EQ(rig.tim2.PSC, 0u);
    EXPECT_EQ(rig.tim2.ARR, arr);
    EXPECT_EQ(rig.tim2.CR1 & (3u << 5), 3u << 5);               // CMS centre-aligned 3
    EXPECT_EQ(rig.tim2.CR1 & ((1u << 7) | 1u), (1u << 7) | 1u); // ARPE, CEN
    volatile uint32_t *ccr[] = {&rig.tim2.CCR1, &rig.tim2.CCR2, &rig.tim2.CCR3, &rig.tim2.CCR4};
    for (const unsigned ch : {lo, hi}) {
        const uint32_t ccmr = (ch <= 2) ? rig.tim2.CCMR1 : rig.tim2.CCMR2;
        EXPECT_EQ((ccmr >> (8 * ((ch - 1) % 2))) & 0x78u, (7u << 4) | (1u << 3)) << ch;
        EXPECT_NE(rig.tim2.CCER & (1u << (4 * (ch - 1))), 0u) << ch; // CCxE
    }
    EXPECT_NE(rig.tim2.CCER & (1u << (4 * (lo - 1) + 1)), 0u); // low: active low
    EXPECT_EQ(rig.tim2.CCER & (1u << (4 * (hi - 1) + 1)), 0u); // high: active high
    // Boot: both off (low never: CNT < 0; high never: CNT >= ARR + 1).
    EXPECT_EQ(*ccr[lo - 1], 0u);
    EXPECT_EQ(*ccr[hi - 1], arr + 1u);

    // A duty the drive asks for (mc_drive's brake step calls this handle)
    // lands in the compares: the high switch on for round(d ARR) of the ARR
    // ticks of each half period, the low switch off dead-time ticks before.
    for (const float d : {0.0f, 0.25f, 0.5f, 0.9f, 1.0f}) {
        ASSERT_EQ(mc_hal_brake_set_duty(rig.board.hal.brake, d), 0) << d;
        const double dc = std::min(double(d), duty_max);
        const auto on = uint32_t(std::lround(float(dc) * float(arr)));
        EXPECT_EQ(*ccr[hi - 1], arr + 1u - on) << d;
        EXPECT_EQ(*ccr[lo - 1], arr + 1u - on - dead) << d;
        // Never on together: the low switch goes off dead-time ticks before
        // the high one comes on.
        EXPECT_EQ(*ccr[hi - 1] - *ccr[lo - 1], dead) << d;
    }
    // A duty outside [0, 1] or NaN is refused and changes nothing.
    ASSERT_EQ(mc_hal_brake_set_duty(rig.board.hal.brake, 0.5f), 0);
    const uint32_t h = *ccr[hi - 1], l = *ccr[lo - 1];
    for (const float bad : {-0.1f, 1.5f, std::nanf("")}) {
        EXPECT_EQ(mc_hal_brake_set_duty(rig.board.hal.brake, bad), -EINVAL) << bad;
        EXPECT_EQ(*ccr[hi - 1], h);
        EXPECT_EQ(*ccr[lo - 1], l);
    }
    // The gate kill (fault path) turns both switches off, and they stay
    // off while the kill is latched whatever duty is asked.
    (void)mc_hal_fault_gate_kill(rig.board.hal.fault);
    EXPECT_EQ(*ccr[lo - 1], 0u);
    EXPECT_EQ(*ccr[hi - 1], arr + 1u);
    EXPECT_EQ(mc_hal_brake_set_duty(rig.board.hal.brake, 0.5f), 0);
    EXPECT_EQ(*ccr[lo - 1], 0u);
    EXPECT_EQ(*ccr[hi - 1], arr + 1u);
}

// A description whose brake timer is out of range stops the set-up by name.
TEST(BoardBrake, BadTimerDescriptionIsRefused)
{
    mc_board_desc_t d = mc_board_odrive36_desc;
    d.brake_ch_high = d.brake_ch_low;
    Rig rig;
    EXPECT_EQ(rig.setup(&d), MC_BOARD_F405_ERR_BRAKE);
    EXPECT_STREQ(mc_board_f405_err_name(MC_BOARD_F405_ERR_BRAKE), "brake chopper timer");
    d = mc_board_odrive36_desc;
    d.brake_duty_max = 1.0f; // no room for the dead time
    Rig rig2;
    EXPECT_EQ(rig2.setup(&d), MC_BOARD_F405_ERR_BRAKE);
}
