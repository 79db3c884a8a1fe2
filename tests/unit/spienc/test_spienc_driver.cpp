// The AS5047P and MA732 drivers' fast-loop read against a scripted SPI that
// plays the chip's part: which command each frame sends, how each answer
// is checked, the hold rule (one bad read holds the last angle, N in a row
// clear VALID), the error and diagnostic commands, the probe.
#include <gtest/gtest.h>

#include "mc_as5047p.h"
#include "mc_ma732.h"
#include "spi_script.h"

namespace
{

// The chip's read-data frame (test side: parity by popcount, not the
// driver's code): PARD, EF, 14 data bits.
uint16_t resp(uint32_t data, bool ef = false)
{
    uint32_t w = (data & 0x3FFFu) | (ef ? 0x4000u : 0u);
    if (__builtin_popcount(w) % 2 != 0) {
        w |= 0x8000u;
    }
    return static_cast<uint16_t>(w);
}

constexpr uint16_t kReadAngleCom = 0xFFFFu; // see As5047pFrames.Commands
constexpr uint16_t kReadAngleUnc = 0x7FFEu;
constexpr uint16_t kReadDiaagc = 0xFFFCu;
constexpr uint16_t kReadErrfl = 0x4001u;
constexpr uint32_t kValid = MC_HAL_ENCODER_FLAG_VALID | MC_HAL_ENCODER_FLAG_INDEX;

struct As5047pTest : public ::testing::Test {
    SpiScript spi;
    mc_as5047p_t enc{};
    mc_hal_encoder_sample_t s{};

    void init(uint32_t n_bad = 3u, uint32_t diag = 0u, bool daec = true)
    {
        mc_as5047p_config_t c{};
        c.p_spi = &spi.dev;
        c.daec = daec;
        c.bad_reads_max = n_bad;
        c.diag_period = diag;
        ASSERT_EQ(mc_as5047p_init(&enc, &c), 0);
    }
    void read()
    {
        ASSERT_EQ(mc_hal_encoder_read(&enc.dev, &s), 0);
    }
};

} // namespace

TEST_F(As5047pTest, InitRefusesBadConfigsAndWritesNothing)
{
    mc_as5047p_config_t c{};
    c.p_spi = &spi.dev;
    c.bad_reads_max = 3u;
    enc.hold.n_reads = 77u;
    mc_as5047p_config_t bad = c;
    bad.p_spi = nullptr;
    EXPECT_EQ(mc_as5047p_init(&enc, &bad), -EINVAL);
    bad = c;
    bad.bad_reads_max = 0u;
    EXPECT_EQ(mc_as5047p_init(&enc, &bad), -EINVAL);
    bad.bad_reads_max = MC_SPIENC_BAD_READS_MAX + 1u;
    EXPECT_EQ(mc_as5047p_init(&enc, &bad), -EINVAL);
    bad = c;
    bad.diag_period = 1u; // every read a DIAAGC read: no angle ever
    EXPECT_EQ(mc_as5047p_init(&enc, &bad), -EINVAL);
    EXPECT_EQ(mc_as5047p_init(nullptr, &c), -EINVAL);
    EXPECT_EQ(enc.hold.n_reads, 77u);
    EXPECT_TRUE(spi.mosi.empty()); // init talks to nobody
}

// Pipelined: each frame sends READ ANGLECOM and receives the answer to the
// previous one. Before the first angle the sample is not VALID.
TEST_F(As5047pTest, AngleEveryFrame)
{
    init();
    spi.push(resp(0u)); // the answer to nothing (after init): not an angle
    spi.push(resp(1000u));
    spi.push(resp(16383u));
    read();
    EXPECT_EQ(s.flags, 0u);
    read();
    EXPECT_EQ(s.count, 1000u);
    EXPECT_EQ(s.counts_per_rev, 16384u);
    EXPECT_EQ(s.flags, kValid);
    read();
    EXPECT_EQ(s.count, 16383u);
    ASSERT_EQ(spi.mosi.size(), 3u);
    for (uint32_t m : spi.mosi) {
        EXPECT_EQ(m, kReadAngleCom);
    }
    mc_as5047p_t unc{};
    mc_as5047p_config_t c = enc.cfg;
    c.daec = false;
    ASSERT_EQ(mc_as5047p_init(&unc, &c), 0);
    ASSERT_EQ(mc_hal_encoder_read(&unc.dev, &s), 0);
    EXPECT_EQ(spi.mosi.back(), kReadAngleUnc);
}

// One bad read holds the last angle (VALID); the N-th in a row clears
// VALID; a good angle restores it.
TEST_F(As5047pTest, ParityErrorsHoldThenInvalidateAtTheNth)
{
    init(3u);
    spi.push(resp(0u));
    spi.push(resp(500u));
    read();
    read();
    ASSERT_EQ(s.count, 500u);
    const uint16_t flipped = static_cast<uint16_t>(resp(600u) ^ 0x0004u);
    spi.push(flipped);
    read();
    EXPECT_EQ(s.count, 500u);
    EXPECT_EQ(s.flags, kValid);
    EXPECT_EQ(enc.hold.err_last, MC_SPIENC_ERR_PARITY);
    spi.push(flipped);
    read();
    EXPECT_EQ(s.flags, kValid);
    spi.push(flipped); // the third in a row: N = 3
    read();
    EXPECT_EQ(s.count, 500u);
    EXPECT_EQ(s.flags, 0u);
    EXPECT_EQ(enc.hold.run, 3u);
    spi.push(resp(700u));
    read();
    EXPECT_EQ(s.count, 700u);
    EXPECT_EQ(s.flags, kValid);
    EXPECT_EQ(enc.hold.n_bad, 3u);
    // the commands never changed: a MISO error is not the chip's
    for (uint32_t m : spi.mosi) {
        EXPECT_EQ(m, kReadAngleCom);
    }
}

// EF in an answer: bad read; the driver reads ERRFL once (its answer,
// which carries EF for what it clears, names the error), then angles.
TEST_F(As5047pTest, ErrorFlagReadsErrflAndNamesTheError)
{
    init(3u);
    spi.push(resp(0u));
    spi.push(resp(100u));
    read();
    read();
    spi.push(resp(0u, true)); // EF: the chip refused a command (parity)
    read();
    EXPECT_EQ(enc.hold.err_last, MC_SPIENC_ERR_CHIP);
    EXPECT_EQ(s.count, 100u);
    EXPECT_EQ(s.flags, kValid);
    spi.push(resp(0u, true)); // the angle command sent meanwhile: EF again
    read();
    EXPECT_EQ(spi.mosi.back(), kReadErrfl);
    spi.push(resp(0x4u, true)); // ERRFL: PARERR (its own answer has EF)
    read();
    EXPECT_EQ(spi.mosi.back(), kReadAngleCom); // not a second ERRFL
    EXPECT_EQ(enc.hold.err_last, MC_SPIENC_ERR_NONE);
    EXPECT_NE(enc.hold.err_seen & MC_SPIENC_ERR_CHIP_PARERR, 0u);
    EXPECT_EQ(s.flags, kValid); // two bad reads and a held one: N = 3 rides through
    EXPECT_EQ(s.count, 100u);
    spi.push(resp(120u));
    read();
    EXPECT_EQ(s.count, 120u);
    EXPECT_EQ(enc.hold.n_bad, 2u);
    EXPECT_EQ(enc.hold.n_held, 2u); // the answer to nothing after init, ERRFL
}

// DIAAGC every diag_period reads: its answer occupies one frame (held
// angle); a field error latches: every read is a DIAAGC read and bad,
// until a clean one.
TEST_F(As5047pTest, DiagnosticPeriodAndMagnetLatch)
{
    init(3u, 4u);
    spi.push(resp(0u));
    for (int k = 0; k < 3; ++k) {
        spi.push(resp(200u + static_cast<uint32_t>(k)));
    }
    for (int k = 0; k < 4; ++k) {
        read();
    }
    ASSERT_EQ(spi.mosi.size(), 4u);
    EXPECT_EQ(spi.mosi[3], kReadDiaagc); // the 4th read asks for DIAAGC
    EXPECT_EQ(s.count, 202u);            // its frame brings read 3's angle
    spi.push(resp(0x0180u));             // DIAAGC: LF, AGC 0x80: healthy
    read();
    EXPECT_EQ(enc.hold.err_last, MC_SPIENC_ERR_NONE);
    EXPECT_EQ(enc.hold.n_held, 2u); // after init, and this one
    EXPECT_EQ(s.count, 202u);
    EXPECT_EQ(s.flags, kValid);
    for (uint32_t a : {203u, 204u, 205u}) {
        spi.push(resp(a));
        read();
    }
    EXPECT_EQ(spi.mosi.back(), kReadDiaagc); // 4 reads later
    EXPECT_EQ(s.count, 205u);
    spi.push(resp(0x0980u)); // DIAAGC: MAGL (magnet lost)
    read();
    EXPECT_EQ(enc.hold.err_last, MC_SPIENC_ERR_MAGNET);
    EXPECT_TRUE(enc.diag_latched);
    EXPECT_EQ(spi.mosi.back(), kReadAngleCom); // decided before the answer
    spi.push(resp(9999u));                     // an angle from a chip without field: not used
    read();
    EXPECT_EQ(spi.mosi.back(), kReadDiaagc);
    EXPECT_EQ(s.count, 205u);
    EXPECT_EQ(s.flags, kValid);
    spi.push(resp(0x0980u));
    read();
    EXPECT_EQ(s.flags, 0u);  // three bad in a row
    spi.push(resp(0x0180u)); // field back
    read();
    EXPECT_FALSE(enc.diag_latched);
    EXPECT_EQ(s.flags, 0u);
    spi.push(resp(0x0180u)); // the DIAAGC command sent while it was latched
    read();
    EXPECT_EQ(s.flags, 0u); // no angle yet
    spi.push(resp(250u));
    read();
    EXPECT_EQ(s.count, 250u);
    EXPECT_EQ(s.flags, kValid);
}

// MISO stuck low: every word 0x0000 (parity fine, no EF): the angle would
// read 0 for ever; the DIAAGC read shows LF clear: MC_SPIENC_ERR_DIAG,
// latched like a field error (every read a bad DIAAGC read from then on).
TEST_F(As5047pTest, MisoStuckLowIsCaughtByTheDiagnostic)
{
    init(2u, 4u);
    for (int k = 0; k < 5; ++k) {
        read(); // reads 2..4 report angle 0; read 4 asks for DIAAGC
    }
    EXPECT_EQ(enc.hold.err_last, MC_SPIENC_ERR_DIAG);
    EXPECT_EQ(s.flags, kValid); // one bad read
    read();
    EXPECT_EQ(spi.mosi.back(), kReadDiaagc); // latched
    EXPECT_EQ(s.flags, 0u);
    for (int k = 0; k < 10; ++k) {
        read();
        EXPECT_EQ(s.flags, 0u);
    }
}

// A failed transfer (-EIO) is a bad read like any other; the driver
// returns 0 with the hold rule's sample (the HAL contract's -EIO would
// fault the drive at once).
TEST_F(As5047pTest, SpiFailureIsABadRead)
{
    init(2u);
    spi.push(resp(0u));
    spi.push(resp(42u));
    read();
    read();
    spi.push(0u, true);
    read();
    EXPECT_EQ(enc.hold.err_last, MC_SPIENC_ERR_SPI);
    EXPECT_EQ(s.flags, kValid);
    EXPECT_EQ(s.count, 42u);
    spi.push(0u, true);
    read();
    EXPECT_EQ(s.flags, 0u);
}

TEST_F(As5047pTest, ProbeHealthyChipAbsentChipAndMagnet)
{
    init();
    // ERRFL cmd -> (anything), DIAAGC cmd -> ERRFL answer, SETTINGS1 cmd ->
    // DIAAGC answer, angle cmd -> SETTINGS1 answer.
    spi.push(0x1234u);
    spi.push(resp(0x0u, false));
    spi.push(resp(0x0180u));
    spi.push(resp(0x0001u));
    EXPECT_EQ(mc_as5047p_probe(&enc), 0);
    ASSERT_EQ(spi.mosi.size(), 4u);
    EXPECT_EQ(spi.mosi[0], kReadErrfl);
    EXPECT_EQ(spi.mosi[1], kReadDiaagc);
    EXPECT_EQ(spi.mosi[2], 0xC018u);
    EXPECT_EQ(spi.mosi[3], kReadAngleCom);
    spi.push(resp(321u)); // the pipeline holds an angle command
    read();
    EXPECT_EQ(s.count, 321u);
    EXPECT_EQ(s.flags, kValid);

    // MISO pulled up (no chip): 0xFFFF everywhere: the DIAAGC answer (the
    // third frame) has EF -> -EPROTO, the probe stops there.
    for (int k = 0; k < 3; ++k) {
        spi.push(0xFFFFu);
    }
    EXPECT_EQ(mc_as5047p_probe(&enc), -EPROTO);
    EXPECT_TRUE(spi.script.empty());
    // MISO pulled down: DIAAGC 0 (LF clear) -> -EPROTO.
    for (int k = 0; k < 4; ++k) {
        spi.push(0x0000u);
    }
    EXPECT_EQ(mc_as5047p_probe(&enc), -EPROTO);
    // A chip with its magnet too far: MAGL -> -ERANGE.
    spi.push(0u);
    spi.push(resp(0u));
    spi.push(resp(0x0980u));
    spi.push(resp(0x0001u));
    EXPECT_EQ(mc_as5047p_probe(&enc), -ERANGE);
    // The bus fails: -EIO.
    spi.push(0u, true);
    EXPECT_EQ(mc_as5047p_probe(&enc), -EIO);
}

namespace
{

uint32_t frame32(uint16_t word, bool good_parity = true)
{
    uint32_t par = static_cast<uint32_t>(__builtin_popcount(word) % 2);
    if (!good_parity) {
        par ^= 1u;
    }
    return (static_cast<uint32_t>(word) << 16) | (par << 15);
}

struct Ma732Test : public ::testing::Test {
    SpiScript spi;
    mc_ma732_t enc{};
    mc_hal_encoder_sample_t s{};

    void init(bool parity, uint32_t n_bad = 3u, uint32_t diag = 0u)
    {
        mc_ma732_config_t c{};
        c.p_spi = &spi.dev;
        c.parity = parity;
        c.bad_reads_max = n_bad;
        c.diag_period = diag;
        ASSERT_EQ(mc_ma732_init(&enc, &c), 0);
    }
    void read()
    {
        ASSERT_EQ(mc_hal_encoder_read(&enc.dev, &s), 0);
    }
};

} // namespace

// 16-bit frames: MOSI 0x0000, MISO the angle of this very frame.
TEST_F(Ma732Test, SixteenBitAngleOfThisFrame)
{
    init(false);
    spi.push(0xABCDu);
    read();
    EXPECT_EQ(s.count, 0xABCDu);
    EXPECT_EQ(s.counts_per_rev, 65536u);
    EXPECT_EQ(s.flags, kValid);
    EXPECT_EQ(spi.mosi[0], 0u);
    EXPECT_EQ(spi.bits[0], 16);
}

// 32-clock frames with parity: a wrong parity bit is a bad read (held);
// N in a row clear VALID.
TEST_F(Ma732Test, ParityFramesHoldAndInvalidate)
{
    init(true, 2u);
    spi.push(frame32(0x8C63u));
    read();
    EXPECT_EQ(s.count, 0x8C63u);
    EXPECT_EQ(spi.bits[0], 32);
    EXPECT_EQ(spi.mosi[0], 0u);
    spi.push(frame32(0x8C64u, false));
    read();
    EXPECT_EQ(enc.hold.err_last, MC_SPIENC_ERR_PARITY);
    EXPECT_EQ(s.count, 0x8C63u);
    EXPECT_EQ(s.flags, kValid);
    spi.push(frame32(0x8C65u, false));
    read();
    EXPECT_EQ(s.flags, 0u);
    spi.push(frame32(0x0001u));
    read();
    EXPECT_EQ(s.count, 1u);
    EXPECT_EQ(s.flags, kValid);
}

// Register 0x1B every diag_period reads: the command's own frame still
// carries an angle; the next carries the register (held angle); MGL
// latches the field error (every read a 0x1B read, bad) until it clears.
TEST_F(Ma732Test, StatusRegisterPeriodAndMagnetLatch)
{
    init(true, 3u, 3u);
    spi.push(frame32(100u));
    spi.push(frame32(101u));
    spi.push(frame32(102u)); // read 3 sends 0x5B00; its MISO is this angle
    read();
    read();
    read();
    EXPECT_EQ(spi.mosi[2], 0x5B00u << 16);
    EXPECT_EQ(s.count, 102u);
    spi.push(frame32(0x4000u)); // 0x1B = 0x40 in bits 15:8: MGL
    read();
    EXPECT_TRUE(enc.diag_latched);
    EXPECT_EQ(enc.hold.err_last, MC_SPIENC_ERR_MAGNET);
    EXPECT_EQ(s.count, 102u);
    EXPECT_EQ(spi.mosi.back(), 0u); // decided before the answer
    spi.push(frame32(5555u));       // an angle without a field: not used
    read();
    EXPECT_EQ(spi.mosi.back(), 0x5B00u << 16); // latched: status every read
    EXPECT_EQ(s.count, 102u);
    spi.push(frame32(0x4000u));
    read();
    EXPECT_EQ(s.flags, 0u);
    spi.push(frame32(0x0000u)); // clear
    read();
    EXPECT_FALSE(enc.diag_latched);
    spi.push(frame32(0x0000u)); // the status asked for while latched
    read();
    EXPECT_EQ(s.flags, 0u);
    spi.push(frame32(300u));
    read();
    EXPECT_EQ(s.count, 300u);
    EXPECT_EQ(s.flags, kValid);
}

TEST_F(Ma732Test, ProbeChecksStatusAndTheSpiCanDoParity)
{
    init(true);
    spi.push(frame32(1234u)); // the angle, while 0x1B is asked for
    spi.push(frame32(0x0000u));
    EXPECT_EQ(mc_ma732_probe(&enc), 0);
    EXPECT_EQ(spi.mosi[0], 0x5B00u << 16);
    EXPECT_EQ(spi.mosi[1], 0u);
    spi.push(frame32(0xFFFFu));
    spi.push(frame32(0xFFFFu)); // MISO high: MGH and MGL together
    EXPECT_EQ(mc_ma732_probe(&enc), -EPROTO);
    spi.push(frame32(0u));
    spi.push(frame32(0x8000u)); // MGH
    EXPECT_EQ(mc_ma732_probe(&enc), -ERANGE);
    spi.push(frame32(0u));
    spi.push(frame32(0u, false));
    EXPECT_EQ(mc_ma732_probe(&enc), -EPROTO);
    spi.push(0u, true);
    EXPECT_EQ(mc_ma732_probe(&enc), -EIO);

    SpiScript spi16;
    spi16.only16();
    mc_ma732_t e16{};
    mc_ma732_config_t c{};
    c.p_spi = &spi16.dev;
    c.parity = true;
    c.bad_reads_max = 3u;
    ASSERT_EQ(mc_ma732_init(&e16, &c), 0);
    EXPECT_EQ(mc_ma732_probe(&e16), -ENODEV);
    EXPECT_TRUE(spi16.mosi.empty());
}

TEST_F(Ma732Test, InitRefusesBadConfigs)
{
    mc_ma732_config_t c{};
    c.p_spi = &spi.dev;
    c.bad_reads_max = 0u;
    EXPECT_EQ(mc_ma732_init(&enc, &c), -EINVAL);
    c.bad_reads_max = 3u;
    c.diag_period = 1u;
    EXPECT_EQ(mc_ma732_init(&enc, &c), -EINVAL);
    c.diag_period = 0u;
    c.p_spi = nullptr;
    EXPECT_EQ(mc_ma732_init(&enc, &c), -EINVAL);
}
