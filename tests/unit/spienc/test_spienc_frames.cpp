// AS5047P and MA732 frames against their datasheets. Every expected word is
// worked out by hand in the comment beside it from the frame definitions
// (mc_as5047p.h, mc_ma732.h): no value is computed by the code under test.
#include <gtest/gtest.h>

#include "mc_as5047p.h"
#include "mc_ma732.h"

// AS5047P command: bit 15 PARC (even parity over bits 14:0), bit 14 R/W.
TEST(As5047pFrames, Commands)
{
    // READ ANGLECOM 0x3FFF: bits 14:0 = 1 + 14 ones = 15 ones, odd -> PARC
    // = 1: 0xFFFF (the "read the angle" word of every public driver).
    EXPECT_EQ(mc_as5047p_cmd_read(0x3FFFu), 0xFFFFu);
    // READ ANGLEUNC 0x3FFE: 1 + 13 ones = 14, even -> 0x7FFE.
    EXPECT_EQ(mc_as5047p_cmd_read(0x3FFEu), 0x7FFEu);
    // READ DIAAGC 0x3FFC: 1 + 12 ones = 13, odd -> 0xFFFC.
    EXPECT_EQ(mc_as5047p_cmd_read(0x3FFCu), 0xFFFCu);
    // READ ERRFL 0x0001: 1 + 1 = 2, even -> 0x4001.
    EXPECT_EQ(mc_as5047p_cmd_read(0x0001u), 0x4001u);
    // READ SETTINGS1 0x0018: 1 + 2 = 3, odd -> 0xC018.
    EXPECT_EQ(mc_as5047p_cmd_read(0x0018u), 0xC018u);
    // WRITE SETTINGS1 0x0018 (R/W 0): 2 ones, even -> 0x0018.
    EXPECT_EQ(mc_as5047p_cmd_write(0x0018u), 0x0018u);
    // WRITE ZPOSM 0x0016: 3 ones, odd -> 0x8016.
    EXPECT_EQ(mc_as5047p_cmd_write(0x0016u), 0x8016u);
    // Data 0x0005 (DIR | factory bit): 2 ones -> 0x0005; data 0x0007 -> 0x8007.
    EXPECT_EQ(mc_as5047p_data_write(0x0005u), 0x0005u);
    EXPECT_EQ(mc_as5047p_data_write(0x0007u), 0x8007u);
    // The NOP frame 0x0000 (write to address 0): no ones, no parity bit.
    EXPECT_EQ(mc_as5047p_cmd_write(0x0000u), 0x0000u);
    // Address bits above 13 are not part of the address.
    EXPECT_EQ(mc_as5047p_cmd_read(0xFFFFu), 0xFFFFu);
}

// Read data: bit 15 PARD (even over bits 14:0), bit 14 EF, 13:0 data.
TEST(As5047pFrames, ReadDataChecks)
{
    uint16_t d = 0u;
    // Angle 0x1234 (0001 0010 0011 0100: 5 ones) -> PARD 1: 0x9234.
    EXPECT_EQ(mc_as5047p_frame_check(0x9234u, &d), MC_SPIENC_ERR_NONE);
    EXPECT_EQ(d, 0x1234u);
    // The same with PARD clear: 5 ones in 16 bits, odd: parity error, data
    // untouched.
    d = 0xAAAAu;
    EXPECT_EQ(mc_as5047p_frame_check(0x1234u, &d), MC_SPIENC_ERR_PARITY);
    EXPECT_EQ(d, 0xAAAAu);
    // Any single flipped bit is caught (odd number of ones).
    for (int bit = 0; bit < 16; ++bit) {
        EXPECT_EQ(mc_as5047p_frame_check(static_cast<uint16_t>(0x9234u ^ (1u << bit)), &d),
                  MC_SPIENC_ERR_PARITY)
            << bit;
    }
    // EF with data 0 (the chip's answer after a command it refused):
    // 0x4000 has one one -> PARD 1: 0xC000.
    EXPECT_EQ(mc_as5047p_frame_check(0xC000u, &d), MC_SPIENC_ERR_CHIP);
    EXPECT_EQ(d, 0u);
    // MISO pulled up, no chip: 0xFFFF (16 ones, even) passes parity but EF is set.
    EXPECT_EQ(mc_as5047p_frame_check(0xFFFFu, &d), MC_SPIENC_ERR_CHIP);
}

TEST(As5047pFrames, RegisterContents)
{
    // ERRFL bit 0 FRERR, 1 INVCOMM, 2 PARERR.
    EXPECT_EQ(mc_as5047p_errfl_errs(0x0u), 0u);
    EXPECT_EQ(mc_as5047p_errfl_errs(0x1u), MC_SPIENC_ERR_CHIP_FRERR);
    EXPECT_EQ(mc_as5047p_errfl_errs(0x2u), MC_SPIENC_ERR_CHIP_INVCOMM);
    EXPECT_EQ(mc_as5047p_errfl_errs(0x4u), MC_SPIENC_ERR_CHIP_PARERR);
    // DIAAGC: LF (bit 8) set with AGC 0x80 is a healthy chip: 0x0180.
    EXPECT_EQ(mc_as5047p_diaagc_errs(0x0180u), 0u);
    EXPECT_EQ(mc_as5047p_diaagc_errs(0x0980u), MC_SPIENC_ERR_MAGNET); // MAGL bit 11
    EXPECT_EQ(mc_as5047p_diaagc_errs(0x0580u), MC_SPIENC_ERR_MAGNET); // MAGH bit 10
    EXPECT_EQ(mc_as5047p_diaagc_errs(0x0380u), MC_SPIENC_ERR_CORDIC); // COF bit 9
    // LF clear: the offset loop has not finished, or MISO is stuck low (0).
    EXPECT_EQ(mc_as5047p_diaagc_errs(0x0000u), MC_SPIENC_ERR_DIAG);
}

// MA732: the parity bit at the 17th clock, MPS AN137 table 1.
TEST(Ma732Frames, ParityBitOfAn137Table1)
{
    EXPECT_EQ(mc_ma732_parity_bit(0x0000u), 0u); // 0 ones
    EXPECT_EQ(mc_ma732_parity_bit(0x8C62u), 0u); // 1000110001100010: 6 ones
    EXPECT_EQ(mc_ma732_parity_bit(0x8C63u), 1u); // 1000110001100011: 7 ones
    EXPECT_EQ(mc_ma732_parity_bit(0x5D00u), 1u); // 0101110100000000: 5 ones
}

// A 32-clock frame: bits 31:16 the word, bit 15 the parity, 14:0 ignored.
TEST(Ma732Frames, ThirtyTwoClockFrame)
{
    uint16_t w = 0u;
    // 0x8C63 with parity 1: 0x8C63 << 16 | 1 << 15 = 0x8C638000.
    EXPECT_EQ(mc_ma732_frame32_check(0x8C638000u, &w), MC_SPIENC_ERR_NONE);
    EXPECT_EQ(w, 0x8C63u);
    // Bits after the parity are not the chip's: ignored.
    EXPECT_EQ(mc_ma732_frame32_check(0x8C637FFFu | 0x8000u, &w), MC_SPIENC_ERR_NONE);
    // Parity 0 for 0x8C63: wrong.
    w = 1u;
    EXPECT_EQ(mc_ma732_frame32_check(0x8C630000u, &w), MC_SPIENC_ERR_PARITY);
    EXPECT_EQ(w, 1u);
    // Every single flipped bit among the 17 is caught.
    for (int bit = 15; bit < 32; ++bit) {
        EXPECT_EQ(mc_ma732_frame32_check(0x8C638000u ^ (1u << bit), &w), MC_SPIENC_ERR_PARITY)
            << bit;
    }
}

TEST(Ma732Frames, CommandsAndStatus)
{
    // Read register: 010 aaaaa 00000000. 0x1B = 11011: 0100 0000 0000 0000
    // | 0001 1011 << 8 = 0x5B00. FW 0x0E: 0x4E00.
    EXPECT_EQ(mc_ma732_cmd_read(0x1Bu), 0x5B00u);
    EXPECT_EQ(mc_ma732_cmd_read(0x0Eu), 0x4E00u);
    EXPECT_EQ(mc_ma732_cmd_read(0x3Fu), 0x5F00u); // 5-bit address
    // 0x1B: MGH bit 7, MGL bit 6.
    EXPECT_EQ(mc_ma732_status_errs(0x00u), 0u);
    EXPECT_EQ(mc_ma732_status_errs(0x80u), MC_SPIENC_ERR_MAGNET);
    EXPECT_EQ(mc_ma732_status_errs(0x40u), MC_SPIENC_ERR_MAGNET);
    EXPECT_EQ(mc_ma732_status_errs(0xC0u), MC_SPIENC_ERR_DIAG); // never both: MISO high
    EXPECT_EQ(mc_ma732_status_errs(0x3Fu), 0u);                 // other bits: not status
}

TEST(SpiencNames, EveryErrorHasAName)
{
    for (uint32_t bit :
         {MC_SPIENC_ERR_SPI, MC_SPIENC_ERR_PARITY, MC_SPIENC_ERR_CHIP, MC_SPIENC_ERR_MAGNET,
          MC_SPIENC_ERR_CORDIC, MC_SPIENC_ERR_DIAG, MC_SPIENC_ERR_CHIP_FRERR,
          MC_SPIENC_ERR_CHIP_INVCOMM, MC_SPIENC_ERR_CHIP_PARERR}) {
        EXPECT_NE(mc_spienc_err_name(bit), nullptr) << bit;
    }
    EXPECT_EQ(mc_spienc_err_name(0u), nullptr);
    EXPECT_EQ(mc_spienc_err_name(MC_SPIENC_ERR_SPI | MC_SPIENC_ERR_PARITY), nullptr);
}
