// spi on SPI1..3 against register files in RAM: CR1 for a configuration
// (RM0090 §28.5.1, values worked out here from the bit positions), the
// chip-select pin, and a transfer. A register file in RAM behaves as a
// loopback: the word written to DR is the word read back (MISO tied to
// MOSI); the status flags are what the test writes into SR.
#include <gtest/gtest.h>

#include "f405_test_util.h"

namespace
{

// RM0090 §28.5.1 SPI_CR1 bit positions, typed from the manual.
constexpr uint32_t kCpha = 1u << 0;
constexpr uint32_t kCpol = 1u << 1;
constexpr uint32_t kMstr = 1u << 2;
constexpr uint32_t kSpe = 1u << 6;
constexpr uint32_t kSsi = 1u << 8;
constexpr uint32_t kSsm = 1u << 9;
constexpr uint32_t kDff = 1u << 11;
// SPI_SR
constexpr uint32_t kRxne = 1u << 0;
constexpr uint32_t kTxe = 1u << 1;

// The DRV8301 on the ODrive v3.6: SPI3 on APB1 (42 MHz), chip select PC13
// active low, mode 1 (CPOL 0, CPHA 1), at most 5 MHz.
struct SpiBoard : public ::testing::Test {
    mc_f405_spi_regs_t spi{};
    mc_f405_gpio_regs_t gpioc{};
    mc_f405_spi_t drv{};

    mc_f405_spi_config_t cfg()
    {
        mc_f405_spi_config_t c{};
        c.p_spi = &spi;
        c.pclk_hz = 42000000u;
        c.max_sck_hz = 5000000u;
        c.mode = 1u;
        c.cs = {&gpioc, 13u, true};
        return c;
    }
};

} // namespace

// 42 MHz / 8 = 5.25 MHz is above 5 MHz, so BR = 011 (/16): 2.625 MHz, the
// divider the ODrive firmware uses for its DRV8301 (spi.c, prescaler 16).
TEST_F(SpiBoard, InitMode1SixteenBitMaster)
{
    const mc_f405_spi_config_t c = cfg();
    ASSERT_EQ(mc_f405_spi_init(&drv, &c), 0);
    EXPECT_EQ(drv.sck_hz, 2625000u);
    EXPECT_EQ(spi.CR1, kCpha | kMstr | (3u << 3) | kSpe | kSsi | kSsm | kDff);
    EXPECT_EQ(spi.CR2, 0u);
    // CS released: BSRR set half, bit 13 (active low: released = high);
    // MODER13 = 01 output.
    EXPECT_EQ(gpioc.BSRR, 1u << 13);
    EXPECT_EQ(gpioc.MODER, 1u << 26);
}

// Mode 3 on SPI1 (84 MHz APB2) at no more than 84 MHz: the smallest
// divider /2 (BR = 000), 42 MHz; CPOL and CPHA both set.
TEST_F(SpiBoard, InitMode3FastestDivider)
{
    mc_f405_spi_config_t c = cfg();
    c.pclk_hz = 84000000u;
    c.max_sck_hz = 84000000u;
    c.mode = 3u;
    ASSERT_EQ(mc_f405_spi_init(&drv, &c), 0);
    EXPECT_EQ(drv.sck_hz, 42000000u);
    EXPECT_EQ(spi.CR1, kCpha | kCpol | kMstr | kSpe | kSsi | kSsm | kDff);
}

TEST_F(SpiBoard, InvalidConfigWritesNothing)
{
    poison(drv);
    const auto drv0 = snapshot(drv);
    const auto spi0 = snapshot(spi);
    const auto gpio0 = snapshot(gpioc);

    mc_f405_spi_config_t c = cfg();
    c.mode = 4u;
    EXPECT_EQ(mc_f405_spi_init(&drv, &c), -EINVAL);
    c = cfg();
    c.cs.p_port = nullptr;
    EXPECT_EQ(mc_f405_spi_init(&drv, &c), -EINVAL);
    c = cfg();
    c.cs.pin = 16u;
    EXPECT_EQ(mc_f405_spi_init(&drv, &c), -EINVAL);
    c = cfg();
    c.max_sck_hz = 42000000u / 256u - 1u; // below the largest divider
    EXPECT_EQ(mc_f405_spi_init(&drv, &c), -EINVAL);
    c = cfg();
    c.pclk_hz = 0u;
    EXPECT_EQ(mc_f405_spi_init(&drv, &c), -EINVAL);

    EXPECT_EQ(snapshot(drv), drv0);
    EXPECT_EQ(snapshot(spi), spi0);
    EXPECT_EQ(snapshot(gpioc), gpio0);
}

// Flags ready (TXE, RXNE set, BSY clear): the word goes to DR, the received
// word (loopback) comes back, and the chip select ends released.
TEST_F(SpiBoard, TransferLoopback)
{
    const mc_f405_spi_config_t c = cfg();
    ASSERT_EQ(mc_f405_spi_init(&drv, &c), 0);
    spi.SR = kTxe | kRxne;
    gpioc.BSRR = 0u;
    uint16_t rx = 0u;
    ASSERT_EQ(mc_hal_spi_transfer16(&drv.dev, 0x9000u, &rx), 0);
    EXPECT_EQ(spi.DR, 0x9000u);
    EXPECT_EQ(rx, 0x9000u);
    EXPECT_EQ(gpioc.BSRR, 1u << 13); // last write: released (high)

    // The received word may be discarded.
    ASSERT_EQ(mc_hal_spi_transfer16(&drv.dev, 0x1550u, nullptr), 0);
    EXPECT_EQ(spi.DR, 0x1550u);
}

// TXE never set (peripheral stuck or clock off): -EIO after the poll
// limit, nothing written to DR, chip select released, rx untouched.
TEST_F(SpiBoard, TransferTimesOutWhenTxeNeverSets)
{
    const mc_f405_spi_config_t c = cfg();
    ASSERT_EQ(mc_f405_spi_init(&drv, &c), 0);
    spi.SR = 0u;
    spi.DR = 0xA5A5u;
    gpioc.BSRR = 0u;
    uint16_t rx = 0x1234u;
    EXPECT_EQ(mc_hal_spi_transfer16(&drv.dev, 0x9000u, &rx), -EIO);
    EXPECT_EQ(spi.DR, 0xA5A5u);
    EXPECT_EQ(rx, 0x1234u);
    EXPECT_EQ(gpioc.BSRR, 1u << 13);
}

// RXNE never set: the word was written but no answer: -EIO, CS released.
TEST_F(SpiBoard, TransferTimesOutWhenRxneNeverSets)
{
    const mc_f405_spi_config_t c = cfg();
    ASSERT_EQ(mc_f405_spi_init(&drv, &c), 0);
    spi.SR = kTxe;
    uint16_t rx = 0x1234u;
    EXPECT_EQ(mc_hal_spi_transfer16(&drv.dev, 0x9000u, &rx), -EIO);
    EXPECT_EQ(rx, 0x1234u);
    EXPECT_EQ(gpioc.BSRR, 1u << 13);
}

// SPE cleared (peripheral reset): -EIO without touching the chip select.
TEST_F(SpiBoard, DisabledPeripheralIsIoError)
{
    const mc_f405_spi_config_t c = cfg();
    ASSERT_EQ(mc_f405_spi_init(&drv, &c), 0);
    spi.CR1 = 0u;
    gpioc.BSRR = 0u;
    EXPECT_EQ(mc_hal_spi_transfer16(&drv.dev, 0x9000u, nullptr), -EIO);
    EXPECT_EQ(gpioc.BSRR, 0u);
}

// Two devices on one SPI (the ODrive v3.6's SPI3: the DRV8301 in mode 1 at
// 2.625 MHz on PC13, an MA732 in mode 3 at 21 MHz on PA0): each transfer
// finds CR1 set for the other device and restores its own (RM0090
// §28.3.3: BR/CPOL/CPHA are changed with SPE = 0, then SPE set again).
TEST_F(SpiBoard, SharedBusRestoresEachDevicesSettings)
{
    mc_f405_gpio_regs_t gpioa{};
    const mc_f405_spi_config_t c = cfg();
    ASSERT_EQ(mc_f405_spi_init(&drv, &c), 0);
    const uint32_t cr1_drv = spi.CR1;
    mc_f405_spi_t enc{};
    mc_f405_spi_config_t ce = cfg();
    ce.max_sck_hz = 25000000u; // 42 MHz / 2 = 21 MHz: BR = 000
    ce.mode = 3u;
    ce.cs = {&gpioa, 0u, true};
    ce.cs_gap_reads = 16u;
    ASSERT_EQ(mc_f405_spi_init(&enc, &ce), 0);
    const uint32_t cr1_enc = kCpha | kCpol | kMstr | kSpe | kSsi | kSsm | kDff;
    EXPECT_EQ(spi.CR1, cr1_enc);
    EXPECT_EQ(enc.sck_hz, 21000000u);

    spi.SR = kTxe | kRxne;
    ASSERT_EQ(mc_hal_spi_transfer16(&drv.dev, 0x9000u, nullptr), 0);
    EXPECT_EQ(spi.CR1, cr1_drv);
    EXPECT_EQ(gpioc.BSRR, 1u << 13); // the DRV8301's chip select
    gpioa.BSRR = 0u;
    ASSERT_EQ(mc_hal_spi_transfer16(&enc.dev, 0x0000u, nullptr), 0);
    EXPECT_EQ(spi.CR1, cr1_enc);
    EXPECT_EQ(gpioa.BSRR, 1u << 0); // the encoder's, released last
}

// 32 clocks under one chip select: the high word first (MSB first), the
// received words assembled the same way (loopback: rx = tx).
TEST_F(SpiBoard, Transfer32TwoWordsOneFrame)
{
    const mc_f405_spi_config_t c = cfg();
    ASSERT_EQ(mc_f405_spi_init(&drv, &c), 0);
    spi.SR = kTxe | kRxne;
    uint32_t rx = 0u;
    ASSERT_EQ(mc_hal_spi_transfer32(&drv.dev, 0x12345678u, &rx), 0);
    EXPECT_EQ(spi.DR, 0x5678u); // the last word written
    EXPECT_EQ(rx, 0x12345678u);
    EXPECT_EQ(gpioc.BSRR, 1u << 13);

    spi.SR = 0u; // TXE never set: -EIO, rx untouched, chip select released
    rx = 7u;
    EXPECT_EQ(mc_hal_spi_transfer32(&drv.dev, 1u, &rx), -EIO);
    EXPECT_EQ(rx, 7u);
}
