// Each board's GPIO set-up (the generated table, applied by
// mc_board_gpio_apply) against its pins.csv, read here independently of the
// generator: on ports filled with a pattern, every listed pin has the
// MODER, OTYPER, OSPEEDR, PUPDR and AFR fields pins.csv gives and outputs
// their start level in BSRR; every other pin keeps the pattern. Also from
// pins.csv alone: no pin is used twice, every signal the drive needs exists
// on a pin that can carry it, and the current-sense channels are the
// boards' (ODrive v3.6 M0: phase B PC0 = IN10, phase C PC1 = IN11).
#include <gtest/gtest.h>

#include <set>
#include <string>

#include "board_files.h"

extern "C" {
#include "mc_board_example_gen.h"
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

constexpr uint32_t kPattern = 0xA5A5A5A5u;

class BoardPins : public ::testing::TestWithParam<Case>
{
};

uint32_t field(uint32_t reg, int pos, int width)
{
    return (reg >> pos) & ((1u << width) - 1u);
}

} // namespace

TEST_P(BoardPins, GpioRegistersMatchPinsCsv)
{
    const Case &c = GetParam();
    const auto pins = boards::read_pins(c.name);
    ASSERT_FALSE(pins.empty());

    mc_f405_gpio_regs_t ports[MC_F405_GPIO_PORTS];
    mc_f405_gpio_regs_t *ptr[MC_F405_GPIO_PORTS];
    for (unsigned k = 0; k < MC_F405_GPIO_PORTS; ++k) {
        ports[k].MODER = kPattern;
        ports[k].OTYPER = kPattern;
        ports[k].OSPEEDR = kPattern;
        ports[k].PUPDR = kPattern;
        ports[k].IDR = 0u;
        ports[k].ODR = 0u;
        ports[k].BSRR = 0u;
        ports[k].LCKR = 0u;
        ports[k].AFR[0] = kPattern;
        ports[k].AFR[1] = kPattern;
        ptr[k] = &ports[k];
    }
    mc_board_gpio_apply(c.desc->p_gpio, c.desc->n_gpio, ptr);

    std::set<std::pair<int, int>> listed;
    for (const auto &p : pins) {
        if (boards::is_hall(p.signal)) {
            continue; // an alternate of an encoder pin: the Hall table's (below)
        }
        SCOPED_TRACE(p.signal + " " + p.name);
        listed.insert({p.port, p.pin});
        const mc_f405_gpio_regs_t &g = ports[p.port];
        EXPECT_EQ(field(g.MODER, 2 * p.pin, 2), boards::moder_code(p.mode));
        EXPECT_EQ(field(g.OTYPER, p.pin, 1), boards::otyper_code(p.otype));
        EXPECT_EQ(field(g.OSPEEDR, 2 * p.pin, 2), boards::ospeedr_code(p.speed));
        EXPECT_EQ(field(g.PUPDR, 2 * p.pin, 2), boards::pupdr_code(p.pull));
        const uint32_t afr = g.AFR[p.pin / 8];
        EXPECT_EQ(field(afr, 4 * (p.pin % 8), 4), p.mode == "af" ? uint32_t(p.af) : 0u);
        if (p.mode == "output") {
            // BSRR: bit n sets the pin, bit n + 16 resets it.
            EXPECT_EQ(field(g.BSRR, p.pin, 1), p.init == 1 ? 1u : 0u);
            EXPECT_EQ(field(g.BSRR, p.pin + 16, 1), p.init == 0 ? 1u : 0u);
        } else {
            EXPECT_EQ(field(g.BSRR, p.pin, 1), 0u);
            EXPECT_EQ(field(g.BSRR, p.pin + 16, 1), 0u);
        }
    }
    // Pins not in pins.csv: untouched.
    for (int port = 0; port < int(MC_F405_GPIO_PORTS); ++port) {
        for (int pin = 0; pin < 16; ++pin) {
            if (listed.count({port, pin}) != 0u) {
                continue;
            }
            SCOPED_TRACE(std::string("P") + char('A' + port) + std::to_string(pin));
            const mc_f405_gpio_regs_t &g = ports[port];
            EXPECT_EQ(field(g.MODER, 2 * pin, 2), field(kPattern, 2 * pin, 2));
            EXPECT_EQ(field(g.OTYPER, pin, 1), field(kPattern, pin, 1));
            EXPECT_EQ(field(g.OSPEEDR, 2 * pin, 2), field(kPattern, 2 * pin, 2));
            EXPECT_EQ(field(g.PUPDR, 2 * pin, 2), field(kPattern, 2 * pin, 2));
            EXPECT_EQ(field(g.AFR[pin / 8], 4 * (pin % 8), 4), field(kPattern, 4 * (pin % 8), 4));
            EXPECT_EQ(field(g.BSRR, pin, 1), 0u);
            EXPECT_EQ(field(g.BSRR, pin + 16, 1), 0u);
        }
    }
    // The ports whose clocks the set-up enables are exactly those used.
    uint32_t mask = 0u;
    for (const auto &p : pins) {
        mask |= 1u << p.port;
    }
    EXPECT_EQ(c.desc->gpio_port_mask, mask);
}

// The Hall inputs' table (applied instead of the encoder's pins when the
// sensor is Hall): each hall_* row of pins.csv on its pin, nothing else
// touched; and each sits on one of enc_a, enc_b, enc_z's pins.
TEST_P(BoardPins, HallTableMatchesPinsCsv)
{
    const Case &c = GetParam();
    const auto pins = boards::read_pins(c.name);
    std::set<std::pair<int, int>> hall;
    std::set<std::string> enc_pins;
    for (const char *e : {"enc_a", "enc_b", "enc_z"}) {
        if (boards::find(pins, e) != nullptr) {
            enc_pins.insert(boards::find(pins, e)->name);
        }
    }
    mc_f405_gpio_regs_t ports[MC_F405_GPIO_PORTS];
    mc_f405_gpio_regs_t *ptr[MC_F405_GPIO_PORTS];
    for (unsigned k = 0; k < MC_F405_GPIO_PORTS; ++k) {
        ports[k] = mc_f405_gpio_regs_t{};
        ports[k].MODER = kPattern;
        ports[k].PUPDR = kPattern;
        ports[k].AFR[0] = kPattern;
        ports[k].AFR[1] = kPattern;
        ptr[k] = &ports[k];
    }
    if (c.desc->p_gpio_hall == nullptr) {
        for (const auto &p : pins) {
            EXPECT_FALSE(boards::is_hall(p.signal)) << p.signal;
        }
        return;
    }
    mc_board_gpio_apply(c.desc->p_gpio_hall, c.desc->n_gpio_hall, ptr);
    int n = 0;
    for (const auto &p : pins) {
        if (!boards::is_hall(p.signal)) {
            continue;
        }
        ++n;
        SCOPED_TRACE(p.signal + " " + p.name);
        hall.insert({p.port, p.pin});
        EXPECT_EQ(enc_pins.count(p.name), 1u);
        EXPECT_EQ(p.mode, "input");
        const mc_f405_gpio_regs_t &g = ports[p.port];
        EXPECT_EQ(field(g.MODER, 2 * p.pin, 2), 0u); // input
        EXPECT_EQ(field(g.PUPDR, 2 * p.pin, 2), boards::pupdr_code(p.pull));
        EXPECT_EQ(field(g.AFR[p.pin / 8], 4 * (p.pin % 8), 4), 0u);
        const auto &hp = c.desc->hall[(p.signal == "hall_a") ? 0 : (p.signal == "hall_b") ? 1 : 2];
        EXPECT_EQ(hp.port, p.port);
        EXPECT_EQ(hp.pin, p.pin);
    }
    EXPECT_EQ(n, 3);
    for (int port = 0; port < int(MC_F405_GPIO_PORTS); ++port) {
        for (int pin = 0; pin < 16; ++pin) {
            if (hall.count({port, pin}) == 0u) {
                EXPECT_EQ(field(ports[port].MODER, 2 * pin, 2), field(kPattern, 2 * pin, 2));
            }
        }
    }
}

TEST_P(BoardPins, NoPinTwiceAndNeededSignalsPresent)
{
    const Case &c = GetParam();
    const auto pins = boards::read_pins(c.name);
    std::set<std::string> names, signals;
    for (const auto &p : pins) {
        if (boards::is_hall(p.signal)) {
            EXPECT_TRUE(signals.insert(p.signal).second) << p.signal << " listed twice";
            continue; // shares an encoder pin (HallTableMatchesPinsCsv)
        }
        EXPECT_TRUE(names.insert(p.name).second) << p.name << " used twice";
        EXPECT_TRUE(signals.insert(p.signal).second) << p.signal << " listed twice";
        EXPECT_NE(p.name, "PA13") << "SWDIO taken";
        EXPECT_NE(p.name, "PA14") << "SWCLK taken";
    }
    // What the drive and the board binding need: TIM1 PWM (AF1), two or three
    // phase currents and the bus voltage on ADC pins, the TIM3 encoder
    // (AF2), CAN1 (AF9), the gate driver's enable and fault pins.
    for (const char *s : {"pwm_ah", "pwm_al", "pwm_bh", "pwm_bl", "pwm_ch", "pwm_cl"}) {
        const auto *p = boards::find(pins, s);
        ASSERT_NE(p, nullptr) << s;
        EXPECT_EQ(p->mode, "af") << s;
        EXPECT_EQ(p->af, 1) << s;
    }
    for (const char *s : {"enc_a", "enc_b"}) {
        const auto *p = boards::find(pins, s);
        ASSERT_NE(p, nullptr) << s;
        EXPECT_EQ(p->af, 2) << s;
    }
    for (const char *s : {"can_rx", "can_tx"}) {
        const auto *p = boards::find(pins, s);
        ASSERT_NE(p, nullptr) << s;
        EXPECT_EQ(p->af, 9) << s;
    }
    int phases = 0;
    for (const char *s : {"adc_ia", "adc_ib", "adc_ic"}) {
        const auto *p = boards::find(pins, s);
        if (p != nullptr) {
            ++phases;
            EXPECT_TRUE(boards::adc_channel(p->name).has_value()) << s;
        }
    }
    EXPECT_GE(phases, 2);
    ASSERT_NE(boards::find(pins, "adc_ib"), nullptr);
    ASSERT_NE(boards::find(pins, "adc_vbus"), nullptr);
    ASSERT_NE(boards::find(pins, "gate_enable"), nullptr);
    EXPECT_EQ(boards::find(pins, "gate_enable")->mode, "output");
    EXPECT_EQ(boards::find(pins, "gate_enable")->init, 0); // starts disabled (active high)
    ASSERT_NE(boards::find(pins, "gate_fault"), nullptr);
    EXPECT_EQ(boards::find(pins, "gate_fault")->mode, "input");
    if (c.desc->has_drv8301) {
        for (const char *s : {"drv_spi_sck", "drv_spi_miso", "drv_spi_mosi"}) {
            const auto *p = boards::find(pins, s);
            ASSERT_NE(p, nullptr) << s;
            EXPECT_EQ(p->af, 6) << s; // SPI3
        }
        const auto *cs = boards::find(pins, "drv_spi_cs");
        ASSERT_NE(cs, nullptr);
        EXPECT_EQ(cs->init, 1); // released
    }
}

// The description's ADC channels are the pins.csv pins' channels.
TEST_P(BoardPins, AdcChannelsFollowPins)
{
    const Case &c = GetParam();
    const auto pins = boards::read_pins(c.name);
    auto ch = [&](const char *s) -> unsigned {
        const auto *p = boards::find(pins, s);
        return p == nullptr ? MC_F405_ADC_CH_NONE : *boards::adc_channel(p->name);
    };
    EXPECT_EQ(c.desc->adc_ch_ia, ch("adc_ia"));
    EXPECT_EQ(c.desc->adc_ch_ib, ch("adc_ib"));
    EXPECT_EQ(c.desc->adc_ch_ic, ch("adc_ic"));
    EXPECT_EQ(c.desc->adc_ch_vbus, ch("adc_vbus"));
    EXPECT_EQ(c.desc->temp_power_stage.channel, ch("adc_temp_fet"));
    EXPECT_EQ(c.desc->temp_motor.channel, ch("adc_temp_motor"));
}

INSTANTIATE_TEST_SUITE_P(Boards, BoardPins, ::testing::ValuesIn(kBoards),
                         [](const ::testing::TestParamInfo<Case> &i) {
                             return std::string(i.param.name);
                         });

// The facts the issue names, from the sources (ODrive main.h/adc.c, VESC
// hw_60_core.h): on the ODrive v3.6 M0 phase B is PC0 (IN10) and phase C is
// PC1 (IN11), phase A is not measured, PA6 is the bus sense (IN6) and not a
// break input; on the VESC 6 PB5 is the gate enable, PC0..PC2 are phases
// A..C.
TEST(BoardFacts, OdriveM0SensesPhasesBAndC)
{
    const auto pins = boards::read_pins("odrive36");
    ASSERT_NE(boards::find(pins, "adc_ib"), nullptr);
    ASSERT_NE(boards::find(pins, "adc_ic"), nullptr);
    EXPECT_EQ(boards::find(pins, "adc_ib")->name, "PC0");
    EXPECT_EQ(boards::find(pins, "adc_ic")->name, "PC1");
    EXPECT_EQ(boards::find(pins, "adc_ia"), nullptr);
    EXPECT_EQ(boards::find(pins, "adc_vbus")->name, "PA6");
    EXPECT_EQ(mc_board_odrive36_desc.adc_ch_ia, MC_F405_ADC_CH_NONE);
    EXPECT_EQ(mc_board_odrive36_desc.adc_ch_ib, 10u);
    EXPECT_EQ(mc_board_odrive36_desc.adc_ch_ic, 11u);
    EXPECT_EQ(mc_board_odrive36_desc.adc_ch_vbus, 6u);
    EXPECT_FALSE(mc_board_odrive36_desc.break_enable);
}

TEST(BoardFacts, Vesc6GateEnableAndThreeShunts)
{
    const auto pins = boards::read_pins("vesc6");
    EXPECT_EQ(boards::find(pins, "gate_enable")->name, "PB5");
    EXPECT_EQ(boards::find(pins, "gate_fault")->name, "PB7");
    EXPECT_EQ(boards::find(pins, "adc_ia")->name, "PC0");
    EXPECT_EQ(boards::find(pins, "adc_ib")->name, "PC1");
    EXPECT_EQ(boards::find(pins, "adc_ic")->name, "PC2");
    EXPECT_EQ(boards::find(pins, "enc_a")->name, "PC6");
    EXPECT_EQ(boards::find(pins, "enc_b")->name, "PC7");
    EXPECT_EQ(mc_board_vesc6_desc.adc_ch_ia, 10u);
    EXPECT_EQ(mc_board_vesc6_desc.adc_ch_ib, 11u);
    EXPECT_EQ(mc_board_vesc6_desc.adc_ch_ic, 12u);
    EXPECT_EQ(mc_board_vesc6_desc.adc_ch_vbus, 13u);
}

// The index and Hall pins of the two real boards, from their sources
// (ODrive board.cpp M0_ENC_Z PC9 and hallA/B/C on ENC0_A/B/Z; VESC
// hw_60_core.h HW_HALL_ENC_GPIO1..3 PC6..PC8, HW_ENC_EXTI_LINE 8), and the
// ODrive's SPI encoder chip select GPIO1 = PA0 (encoder.hpp
// abs_spi_cs_gpio_pin 1).
TEST(BoardFacts, IndexHallAndSpiEncoderPins)
{
    const auto od = boards::read_pins("odrive36");
    EXPECT_EQ(boards::find(od, "enc_z")->name, "PC9");
    EXPECT_EQ(boards::find(od, "hall_a")->name, "PB4");
    EXPECT_EQ(boards::find(od, "hall_b")->name, "PB5");
    EXPECT_EQ(boards::find(od, "hall_c")->name, "PC9");
    EXPECT_EQ(boards::find(od, "enc_spi_cs")->name, "PA0");
    EXPECT_EQ(boards::find(od, "enc_spi_cs")->init, 1);
    EXPECT_EQ(mc_board_odrive36_desc.enc_index.port, 2u);
    EXPECT_EQ(mc_board_odrive36_desc.enc_index.pin, 9u);
    EXPECT_EQ(mc_board_odrive36_desc.enc_spi_cs.port, 0u);
    EXPECT_EQ(mc_board_odrive36_desc.enc_spi_cs.pin, 0u);
    EXPECT_TRUE(mc_board_odrive36_desc.enc_spi_cs.active_low);
    const auto ve = boards::read_pins("vesc6");
    EXPECT_EQ(boards::find(ve, "enc_z")->name, "PC8");
    EXPECT_EQ(boards::find(ve, "hall_a")->name, "PC6");
    EXPECT_EQ(boards::find(ve, "hall_b")->name, "PC7");
    EXPECT_EQ(boards::find(ve, "hall_c")->name, "PC8");
    EXPECT_EQ(boards::find(ve, "enc_spi_cs"), nullptr);
    EXPECT_EQ(mc_board_vesc6_desc.enc_index.pin, 8u);
    EXPECT_EQ(mc_board_example_desc.enc_index.port, MC_BOARD_PORT_NONE);
    EXPECT_EQ(mc_board_example_desc.p_gpio_hall, nullptr);
}

// The ODrive v3.6's second axis (M1) from its sources (main.h, tim.c,
// adc.c, board.cpp at the commit pins.csv names): phase B on PC3 (IN13),
// phase C on PC2 (IN12), FET thermistor PA4 (IN4), encoder TIM4 on PB6/PB7
// (AF2) with the index on PC15 pulled down, the DRV8301 chip select PC14
// released. Its gate inputs are TIM8's pins (PC6..PC8, PA7, PB0, PB1),
// held low as outputs until the image drives M1: a bridge that cannot
// switch. Its DRV8301 shares the gate enable with M0's.
TEST(BoardFacts, OdriveM1PinsAreTheSecondAxisAndItsGatesAreHeldLow)
{
    const auto pins = boards::read_pins("odrive36");
    struct Want {
        const char *sig, *name, *mode;
        int af;
    };
    const Want want[] = {
        {"m1_adc_ib", "PC3", "analog", 0},
        {"m1_adc_ic", "PC2", "analog", 0},
        {"m1_adc_temp_fet", "PA4", "analog", 0},
        {"m1_enc_a", "PB6", "af", 2},
        {"m1_enc_b", "PB7", "af", 2},
        {"m1_enc_z", "PC15", "input", 0},
        {"m1_drv_spi_cs", "PC14", "output", 0},
        {"m1_pwm_ah", "PC6", "output", 0},
        {"m1_pwm_bh", "PC7", "output", 0},
        {"m1_pwm_ch", "PC8", "output", 0},
        {"m1_pwm_al", "PA7", "output", 0},
        {"m1_pwm_bl", "PB0", "output", 0},
        {"m1_pwm_cl", "PB1", "output", 0},
    };
    for (const Want &w : want) {
        const auto *p = boards::find(pins, w.sig);
        ASSERT_NE(p, nullptr) << w.sig;
        EXPECT_EQ(p->name, w.name) << w.sig;
        EXPECT_EQ(p->mode, w.mode) << w.sig;
        EXPECT_EQ(p->af, w.af) << w.sig;
        if (std::string(w.sig).rfind("m1_pwm_", 0) == 0) {
            EXPECT_EQ(p->init, 0) << w.sig << ": held low, the gate off";
        }
    }
    EXPECT_EQ(boards::find(pins, "m1_drv_spi_cs")->init, 1);
    EXPECT_EQ(boards::find(pins, "m1_enc_z")->pull, "down");
    EXPECT_EQ(boards::find(pins, "m1_adc_ia"), nullptr);
}
