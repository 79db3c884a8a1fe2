// hal/drv8301 against the datasheet's register map (TI SLOS719F) and a model
// of the chip (drv8301_model.h). Bit layout asserted here, typed from the
// datasheet: 16-bit frame, bit 15 R/W (1 = read), bits 14:11 address,
// bits 10:0 data; Control 1 = OC_ADJ_SET[10:6] OCP_MODE[5:4] PWM_MODE[3]
// GATE_RESET[2] GATE_CURRENT[1:0]; Control 2 = OC_TOFF[6] DC_CAL[5:4]
// GAIN[3:2] OCTW_MODE[1:0]; Status 1 = FAULT[10] GVDD_UV[9] PVDD_UV[8]
// OTSD[7] OTW[6] FETHA_OC[5] FETLA_OC[4] FETHB_OC[3] FETLB_OC[2]
// FETHC_OC[1] FETLC_OC[0]; Status 2 = GVDD_OV[7] device ID[3:0].
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "drv8301_model.h"

extern "C" {
#include "mc_drv8301.h"
}

namespace
{

// The ODrive v3.6 set-up (Firmware/Drivers/DRV8301/drv8301.cpp at
// odriverobotics/ODrive f9b5419c): OC_ADJ_SET 21, OC latch shut down, six
// PWM inputs, 1.7 A gate current; cycle-by-cycle OC_TOFF, report OT and OC
// on nOCTW, gain 40 V/V (the default requested current range of 60 A snaps
// to 40 V/V on 0.5 mOhm, motor.cpp).
mc_drv8301_config_t odrive_cfg()
{
    mc_drv8301_config_t c{};
    c.gain = MC_DRV8301_GAIN_40;
    c.oc_adj_set = 21u;
    c.ocp_mode = MC_DRV8301_OCP_LATCH;
    c.pwm_mode = MC_DRV8301_PWM_6;
    c.gate_current = MC_DRV8301_GATE_1A7;
    c.octw_mode = MC_DRV8301_OCTW_OT_AND_OC;
    c.oc_toff = MC_DRV8301_OC_TOFF_CYCLE;
    return c;
}

// Frames, typed as hex from the layout above.
constexpr uint16_t kWriteCtrl1Odrive = 0x1550u; // 0 | 0010 << 11 | 10101 01 0 0 00
constexpr uint16_t kWriteCtrl2Odrive = 0x1808u; // 0 | 0011 << 11 | 0 00 10 00
constexpr uint16_t kReadStatus1 = 0x8000u;
constexpr uint16_t kReadStatus2 = 0x8800u;
constexpr uint16_t kReadCtrl1 = 0x9000u;
constexpr uint16_t kReadCtrl2 = 0x9800u;

} // namespace

TEST(Drv8301Frames, CommandLayout)
{
    EXPECT_EQ(mc_drv8301_frame_read(MC_DRV8301_REG_STATUS1), kReadStatus1);
    EXPECT_EQ(mc_drv8301_frame_read(MC_DRV8301_REG_STATUS2), kReadStatus2);
    EXPECT_EQ(mc_drv8301_frame_read(MC_DRV8301_REG_CTRL1), kReadCtrl1);
    EXPECT_EQ(mc_drv8301_frame_read(MC_DRV8301_REG_CTRL2), kReadCtrl2);
    EXPECT_EQ(mc_drv8301_frame_write(MC_DRV8301_REG_CTRL1, 0x550u), kWriteCtrl1Odrive);
    EXPECT_EQ(mc_drv8301_frame_write(MC_DRV8301_REG_CTRL2, 0x008u), kWriteCtrl2Odrive);
    // Data keeps 11 bits: it cannot spill into the address or R/W bit.
    EXPECT_EQ(mc_drv8301_frame_write(MC_DRV8301_REG_CTRL1, 0xFFFFu), 0x17FFu);
}

// ODrive: Control 1 = 21 << 6 | 01 << 4 = 0x550, Control 2 = 10 << 2 = 0x008.
TEST(Drv8301Encode, OdriveSetup)
{
    const mc_drv8301_config_t c = odrive_cfg();
    uint16_t c1 = 0u;
    uint16_t c2 = 0u;
    ASSERT_EQ(mc_drv8301_ctrl_encode(&c, &c1, &c2), 0);
    EXPECT_EQ(c1, 0x550u);
    EXPECT_EQ(c2, 0x008u);
}

// VESC 6 (hwconf/drv8301.c, motor/mcconf_default.h and mc_interface.c at
// vedderb/bldc b9d287b3): OC_ADJ 16, OCP current limit, gain 20 V/V:
// Control 1 = 16 << 6 = 0x400, Control 2 = 01 << 2 = 0x004.
TEST(Drv8301Encode, Vesc6Setup)
{
    mc_drv8301_config_t c = odrive_cfg();
    c.gain = MC_DRV8301_GAIN_20;
    c.oc_adj_set = 16u;
    c.ocp_mode = MC_DRV8301_OCP_CURRENT_LIMIT;
    uint16_t c1 = 0u;
    uint16_t c2 = 0u;
    ASSERT_EQ(mc_drv8301_ctrl_encode(&c, &c1, &c2), 0);
    EXPECT_EQ(c1, 0x400u);
    EXPECT_EQ(c2, 0x004u);
}

// Every other field at a non-zero value lands at its own bits.
TEST(Drv8301Encode, FieldPositions)
{
    mc_drv8301_config_t c{};
    c.gain = MC_DRV8301_GAIN_80;             // 11 at 3:2
    c.oc_adj_set = 31u;                      // 11111 at 10:6
    c.ocp_mode = MC_DRV8301_OCP_DISABLED;    // 11 at 5:4
    c.pwm_mode = MC_DRV8301_PWM_3;           // 1 at 3
    c.gate_current = MC_DRV8301_GATE_0A25;   // 10 at 1:0
    c.octw_mode = MC_DRV8301_OCTW_OC_ONLY;   // 10 at 1:0
    c.oc_toff = MC_DRV8301_OC_TOFF_OFF_TIME; // 1 at 6
    uint16_t c1 = 0u;
    uint16_t c2 = 0u;
    ASSERT_EQ(mc_drv8301_ctrl_encode(&c, &c1, &c2), 0);
    EXPECT_EQ(c1, (31u << 6) | (3u << 4) | (1u << 3) | 2u);
    EXPECT_EQ(c2, (1u << 6) | (3u << 2) | 2u);
}

// Codes outside the field and the reserved encodings are refused and the
// outputs keep their values.
TEST(Drv8301Encode, RefusesReservedAndOutOfRange)
{
    uint16_t c1 = 0xAAAAu;
    uint16_t c2 = 0x5555u;
    mc_drv8301_config_t c = odrive_cfg();
    c.oc_adj_set = 32u;
    EXPECT_EQ(mc_drv8301_ctrl_encode(&c, &c1, &c2), -EINVAL);
    c = odrive_cfg();
    c.gate_current = static_cast<mc_drv8301_gate_current_t>(3); // reserved
    EXPECT_EQ(mc_drv8301_ctrl_encode(&c, &c1, &c2), -EINVAL);
    c = odrive_cfg();
    c.octw_mode = static_cast<mc_drv8301_octw_mode_t>(3); // reserved
    EXPECT_EQ(mc_drv8301_ctrl_encode(&c, &c1, &c2), -EINVAL);
    c = odrive_cfg();
    c.gain = static_cast<mc_drv8301_gain_t>(4);
    EXPECT_EQ(mc_drv8301_ctrl_encode(&c, &c1, &c2), -EINVAL);
    EXPECT_EQ(mc_drv8301_ctrl_encode(nullptr, &c1, &c2), -EINVAL);
    EXPECT_EQ(c1, 0xAAAAu);
    EXPECT_EQ(c2, 0x5555u);
}

// OC_ADJ_SET table (SLOS719F): a few codes typed from the datasheet, and
// the table strictly increasing.
TEST(Drv8301OcAdj, TableValues)
{
    EXPECT_EQ(mc_drv8301_oc_adj_vds_mv(0u), 60u);
    EXPECT_EQ(mc_drv8301_oc_adj_vds_mv(15u), 358u);
    EXPECT_EQ(mc_drv8301_oc_adj_vds_mv(16u), 403u);
    EXPECT_EQ(mc_drv8301_oc_adj_vds_mv(21u), 730u);
    EXPECT_EQ(mc_drv8301_oc_adj_vds_mv(31u), 2400u);
    EXPECT_EQ(mc_drv8301_oc_adj_vds_mv(32u), 0u);
    for (uint32_t k = 1u; k < 32u; ++k) {
        EXPECT_GT(mc_drv8301_oc_adj_vds_mv(k), mc_drv8301_oc_adj_vds_mv(k - 1u)) << k;
    }
}

// 100 A through 5 mOhm is 500 mV: code 17 (454 mV) is the largest at or
// below it (code 18 is 511 mV). 1 mV either side of code 21's 730 mV picks
// 21 and 20 (float rounding of the product is below 1e-4 mV).
TEST(Drv8301OcAdj, CodeForTripCurrent)
{
    uint8_t code = 99u;
    ASSERT_EQ(mc_drv8301_oc_adj_for_trip(100.0f, 0.005f, &code), 0);
    EXPECT_EQ(code, 17u);
    ASSERT_EQ(mc_drv8301_oc_adj_for_trip(731.0f, 0.001f, &code), 0); // 731 mV
    EXPECT_EQ(code, 21u);
    ASSERT_EQ(mc_drv8301_oc_adj_for_trip(729.0f, 0.001f, &code), 0); // 729 mV
    EXPECT_EQ(code, 20u);
    ASSERT_EQ(mc_drv8301_oc_adj_for_trip(1000.0f, 0.005f, &code), 0); // 5 V
    EXPECT_EQ(code, 31u);
    code = 99u;
    EXPECT_EQ(mc_drv8301_oc_adj_for_trip(10.0f, 0.005f, &code), -EINVAL); // 50 mV
    EXPECT_EQ(mc_drv8301_oc_adj_for_trip(std::nanf(""), 0.005f, &code), -EINVAL);
    EXPECT_EQ(mc_drv8301_oc_adj_for_trip(100.0f, -0.005f, &code), -EINVAL);
    EXPECT_EQ(code, 99u);
}

TEST(Drv8301Faults, NamesAndStatusMapping)
{
    const char *names[12] = {"FETLC_OC", "FETHC_OC", "FETLB_OC", "FETHB_OC", "FETLA_OC", "FETHA_OC",
                             "OTW",      "OTSD",     "PVDD_UV",  "GVDD_UV",  "FAULT",    "GVDD_OV"};
    for (uint32_t k = 0u; k < 12u; ++k) {
        const char *n = mc_drv8301_fault_name(1u << k);
        ASSERT_NE(n, nullptr) << k;
        EXPECT_STREQ(n, names[k]);
    }
    EXPECT_EQ(mc_drv8301_fault_name(0u), nullptr);
    EXPECT_EQ(mc_drv8301_fault_name(3u), nullptr);       // two bits
    EXPECT_EQ(mc_drv8301_fault_name(1u << 12), nullptr); // not a fault
    // Status 1 D5 + D10, Status 2 D7 + device ID 1.
    EXPECT_EQ(mc_drv8301_faults_from_status(0x0420u, 0x0081u),
              MC_DRV8301_FAULT_FETHA_OC | MC_DRV8301_FAULT_FAULT | MC_DRV8301_FAULT_GVDD_OV);
    // Only the low 11 bits of Status 1 are register data.
    EXPECT_EQ(mc_drv8301_faults_from_status(0xF800u, 0x0000u), 0u);
}

// Set-up on a healthy chip: the frames on the wire, in order, and the
// registers the chip ends with.
TEST(Drv8301Init, OdriveFramesAndRegisters)
{
    Drv8301Model chip;
    const mc_hal_spi_t spi = chip.spi();
    const mc_drv8301_config_t c = odrive_cfg();
    mc_drv8301_t drv{};
    ASSERT_EQ(mc_drv8301_init(&drv, &spi, &c), 0);
    EXPECT_EQ(drv.status, MC_DRV8301_STATUS_OK);
    EXPECT_EQ(chip.reg[2], 0x550u);
    EXPECT_EQ(chip.reg[3], 0x008u);
    const std::vector<uint16_t> want = {
        kWriteCtrl1Odrive, kWriteCtrl2Odrive,
        kReadCtrl1,        kReadCtrl1, // read Control 1, clock the answer out
        kReadCtrl2,        kReadCtrl1, // read Control 2
        kReadStatus1,      kReadCtrl1, // faults
        kReadStatus2,      kReadCtrl1,
    };
    EXPECT_EQ(chip.frames, want);
    EXPECT_EQ(drv.faults, 0u);
    EXPECT_EQ(drv.device_id, 1u);
}

// A fault read back is named: the chip latched a high-side over-current on
// phase A (Status 1 D5, with FAULT D10) and GVDD over-voltage (Status 2 D7).
// The read clears the latches in the chip; the next read finds none.
TEST(Drv8301Init, FaultReadBackIsNamed)
{
    Drv8301Model chip;
    const mc_hal_spi_t spi = chip.spi();
    const mc_drv8301_config_t c = odrive_cfg();
    mc_drv8301_t drv{};
    ASSERT_EQ(mc_drv8301_init(&drv, &spi, &c), 0);

    chip.reg[0] = (1u << 5) | (1u << 10);
    chip.reg[1] = static_cast<uint16_t>((1u << 7) | 1u);
    uint32_t faults = 0u;
    ASSERT_EQ(mc_drv8301_read_faults(&drv, &faults), 0);
    EXPECT_EQ(faults,
              MC_DRV8301_FAULT_FETHA_OC | MC_DRV8301_FAULT_FAULT | MC_DRV8301_FAULT_GVDD_OV);
    std::string named;
    for (uint32_t k = 0u; k < 12u; ++k) {
        if ((faults & (1u << k)) != 0u) {
            named += std::string(mc_drv8301_fault_name(1u << k)) + " ";
        }
    }
    EXPECT_EQ(named, "FETHA_OC FAULT GVDD_OV ");
    EXPECT_EQ(chip.reg[0], 0u);
    EXPECT_EQ(chip.reg[1], 1u);
    ASSERT_EQ(mc_drv8301_read_faults(&drv, &faults), 0);
    EXPECT_EQ(faults, 0u);
}

// A fault present at set-up refuses the set-up (-EBUSY) and names it;
// an over-temperature warning alone does not.
TEST(Drv8301Init, FaultAtSetupRefuses)
{
    Drv8301Model chip;
    chip.reg[0] = (1u << 9) | (1u << 10); // GVDD_UV
    const mc_hal_spi_t spi = chip.spi();
    const mc_drv8301_config_t c = odrive_cfg();
    mc_drv8301_t drv{};
    EXPECT_EQ(mc_drv8301_init(&drv, &spi, &c), -EBUSY);
    EXPECT_EQ(drv.status, MC_DRV8301_STATUS_FAULT);
    EXPECT_EQ(drv.faults, MC_DRV8301_FAULT_GVDD_UV | MC_DRV8301_FAULT_FAULT);
    EXPECT_STREQ(mc_drv8301_status_name(drv.status), "chip reports a fault");

    Drv8301Model warm;
    warm.reg[0] = 1u << 6; // OTW only
    const mc_hal_spi_t spi2 = warm.spi();
    mc_drv8301_t drv2{};
    EXPECT_EQ(mc_drv8301_init(&drv2, &spi2, &c), 0);
    EXPECT_EQ(drv2.faults, MC_DRV8301_FAULT_OTW);
}

// A write the chip ignores once is caught by the read-back and repeated;
// one it always ignores fails the set-up.
TEST(Drv8301Init, IgnoredWriteIsRetriedThenRefused)
{
    const mc_drv8301_config_t c = odrive_cfg();
    Drv8301Model once;
    once.ignore_ctrl1_writes = 1;
    const mc_hal_spi_t spi = once.spi();
    mc_drv8301_t drv{};
    ASSERT_EQ(mc_drv8301_init(&drv, &spi, &c), 0);
    EXPECT_EQ(once.reg[2], 0x550u);
    EXPECT_EQ(once.frames.size(), 16u); // two write-and-verify rounds + status

    Drv8301Model never;
    never.ignore_ctrl1_writes = 1000;
    const mc_hal_spi_t spi2 = never.spi();
    mc_drv8301_t drv2{};
    EXPECT_EQ(mc_drv8301_init(&drv2, &spi2, &c), -EIO);
    EXPECT_EQ(drv2.status, MC_DRV8301_STATUS_READBACK);
    EXPECT_EQ(never.frames.size(), 6u * MC_DRV8301_INIT_ATTEMPTS);
}

// No chip: MISO pulled high reads 0xFFFF (frame-fault bit set), MISO low
// reads 0x0000 (address 0, not the Control 1 asked for). Both: no response.
TEST(Drv8301Init, NoChipIsNoResponse)
{
    const mc_drv8301_config_t c = odrive_cfg();
    for (const bool high : {true, false}) {
        Drv8301Model chip;
        chip.miso_stuck_high = high;
        chip.miso_stuck_low = !high;
        const mc_hal_spi_t spi = chip.spi();
        mc_drv8301_t drv{};
        EXPECT_EQ(mc_drv8301_init(&drv, &spi, &c), -EIO) << high;
        EXPECT_EQ(drv.status, MC_DRV8301_STATUS_NO_RESPONSE) << high;
    }
}

// A failing SPI transfer stops the set-up at once; a bad configuration is
// refused before any frame.
TEST(Drv8301Init, SpiFailureAndBadConfig)
{
    mc_drv8301_config_t c = odrive_cfg();
    Drv8301Model chip;
    chip.fail_at_frame = 1; // the Control 2 write
    const mc_hal_spi_t spi = chip.spi();
    mc_drv8301_t drv{};
    EXPECT_EQ(mc_drv8301_init(&drv, &spi, &c), -EIO);
    EXPECT_EQ(drv.status, MC_DRV8301_STATUS_SPI);
    EXPECT_EQ(chip.frames.size(), 2u);

    Drv8301Model idle;
    const mc_hal_spi_t spi2 = idle.spi();
    c.oc_adj_set = 40u;
    mc_drv8301_t drv2{};
    EXPECT_EQ(mc_drv8301_init(&drv2, &spi2, &c), -EINVAL);
    EXPECT_EQ(drv2.status, MC_DRV8301_STATUS_CONFIG);
    EXPECT_TRUE(idle.frames.empty());
}

// Register access refuses addresses beyond Control 2 and data beyond 11
// bits, without a frame.
TEST(Drv8301Access, RefusesBadArguments)
{
    Drv8301Model chip;
    const mc_hal_spi_t spi = chip.spi();
    mc_drv8301_t drv{};
    drv.p_spi = &spi;
    uint16_t v = 0x1234u;
    EXPECT_EQ(mc_drv8301_read_reg(&drv, 4u, &v), -EINVAL);
    EXPECT_EQ(mc_drv8301_write_reg(&drv, 2u, 0x800u), -EINVAL);
    EXPECT_EQ(mc_drv8301_write_reg(&drv, 1u << 4, 0u), -EINVAL);
    EXPECT_TRUE(chip.frames.empty());
    EXPECT_EQ(v, 0x1234u);
    ASSERT_EQ(mc_drv8301_write_reg(&drv, MC_DRV8301_REG_CTRL2, 0x004u), 0);
    ASSERT_EQ(mc_drv8301_read_reg(&drv, MC_DRV8301_REG_CTRL2, &v), 0);
    EXPECT_EQ(v, 0x004u);
}

// GATE_RESET: one write of Control 1 with D2 set (0x1554 for the ODrive
// set-up), the latched over-current cleared in the chip, Control 1 read back
// as configured (D2 back to 0).
TEST(Drv8301Reset, GateResetClearsLatchedFaults)
{
    Drv8301Model chip;
    const mc_hal_spi_t spi = chip.spi();
    const mc_drv8301_config_t c = odrive_cfg();
    mc_drv8301_t drv{};
    ASSERT_EQ(mc_drv8301_init(&drv, &spi, &c), 0);
    chip.reg[0] = (1u << 4) | (1u << 10); // FETLA_OC latched
    chip.frames.clear();
    ASSERT_EQ(mc_drv8301_reset_faults(&drv), 0);
    const std::vector<uint16_t> want = {0x1554u, kReadCtrl1, kReadCtrl1};
    EXPECT_EQ(chip.frames, want);
    EXPECT_EQ(chip.gate_resets, 1);
    EXPECT_EQ(chip.reg[0], 0u);
    EXPECT_EQ(chip.reg[2], 0x550u);

    // A chip that lost its configuration (EN_GATE reset) and drops the
    // write fails the read-back check.
    chip.power_reset();
    chip.ignore_ctrl1_writes = 1;
    EXPECT_EQ(mc_drv8301_reset_faults(&drv), -EIO);
    mc_drv8301_t none{};
    EXPECT_EQ(mc_drv8301_reset_faults(&none), -EINVAL);
}
