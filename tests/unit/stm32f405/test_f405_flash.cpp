// STM32F405 flash driver (hal/stm32f405/mc_f405_flash.c) against a register
// file in RAM plus a small model of the RM0090 controller (section 3.5-3.7):
// KEY1 then KEY2 in KEYR clears CR.LOCK (a wrong key keeps it locked); STRT
// with SER erases sector SNB of the array; a word write with PG programs it
// (bitwise AND, as NOR flash) and sets EOP; an injected SR error flag makes
// the operation fail; each operation replaces SR (the RAM register file
// cannot model rc_w1). Register values are exact: they are bit fields.
#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "mc_f405_flash.h"

namespace
{

struct Model {
    mc_f405_flash_regs_t regs{};
    std::vector<uint8_t> mem = std::vector<uint8_t>(1u << 20, 0xFF);
    std::vector<uint32_t> keys;     // KEYR writes seen
    std::vector<uint32_t> cr_start; // CR at each STRT
    uint32_t inject_sr = 0;         // error flag raised by the next operation
    uint32_t programmed = 0;
    std::vector<uint8_t> shadow = mem; // last known array (to see word writes)
};

void HwPoll(void *ctx)
{
    auto *m = static_cast<Model *>(ctx);
    mc_f405_flash_regs_t &r = m->regs;
    if (r.KEYR != 0u) {
        m->keys.push_back(static_cast<uint32_t>(r.KEYR));
        const size_t n = m->keys.size();
        if (n >= 2 && m->keys[n - 2] == MC_F405_FLASH_KEY1 &&
            m->keys[n - 1] == MC_F405_FLASH_KEY2) {
            r.CR &= ~MC_F405_FLASH_CR_LOCK;
        }
        r.KEYR = 0u;
    }
    if ((r.CR & MC_F405_FLASH_CR_STRT) != 0u) {
        m->cr_start.push_back(static_cast<uint32_t>(r.CR));
        const uint32_t snb = (r.CR & MC_F405_FLASH_CR_SNB_MASK) >> MC_F405_FLASH_CR_SNB_SHIFT;
        uint32_t off = 0, bytes = 0;
        ASSERT_EQ(0, mc_f405_flash_sector_geometry(snb, &off, &bytes));
        if (m->inject_sr == 0u) {
            std::memset(m->mem.data() + off, 0xFF, bytes);
        }
        r.CR &= ~MC_F405_FLASH_CR_STRT;
        r.SR = m->inject_sr != 0u ? m->inject_sr : MC_F405_FLASH_SR_EOP;
        m->inject_sr = 0u;
        m->shadow = m->mem;
    }
    if ((r.CR & MC_F405_FLASH_CR_PG) != 0u && m->mem != m->shadow) {
        // one word was written: NOR programming only clears bits
        for (size_t i = 0; i < m->mem.size(); ++i) {
            if (m->mem[i] != m->shadow[i]) {
                EXPECT_EQ(r.CR & 0x300u, MC_F405_FLASH_CR_PSIZE_X32)
                    << "word program needs PSIZE x32";
                m->mem[i] = m->inject_sr != 0u ? m->shadow[i] : (m->mem[i] & m->shadow[i]);
            }
        }
        ++m->programmed;
        r.SR = m->inject_sr != 0u ? m->inject_sr : MC_F405_FLASH_SR_EOP;
        m->inject_sr = 0u;
        m->shadow = m->mem;
    }
}

class F405Flash : public ::testing::Test
{
  protected:
    void SetUp() override
    {
        m.regs.CR = MC_F405_FLASH_CR_LOCK; // reset value 0x80000000 (RM0090 3.9.7)
        const mc_f405_flash_config_t c = {&m.regs, m.mem.data(), 0x1u /* sector 0: code */,
                                          100u,    HwPoll,       &m};
        ASSERT_EQ(0, mc_f405_flash_init(&f, &c));
    }
    Model m;
    mc_f405_flash_t f{};
};

TEST(F405FlashMap, SectorGeometryRm0090Table5)
{
    const uint32_t want_off[12] = {0x00000, 0x04000, 0x08000, 0x0C000, 0x10000, 0x20000,
                                   0x40000, 0x60000, 0x80000, 0xA0000, 0xC0000, 0xE0000};
    const uint32_t want_size[12] = {16384,  16384,  16384,  16384,  65536,  131072,
                                    131072, 131072, 131072, 131072, 131072, 131072};
    for (uint32_t s = 0; s < 12; ++s) {
        uint32_t off = 0, bytes = 0;
        ASSERT_EQ(0, mc_f405_flash_sector_geometry(s, &off, &bytes));
        EXPECT_EQ(want_off[s], off) << s;
        EXPECT_EQ(want_size[s], bytes) << s;
    }
    uint32_t off = 0, bytes = 0;
    EXPECT_EQ(-EINVAL, mc_f405_flash_sector_geometry(12, &off, &bytes));
}

TEST_F(F405Flash, EraseSequenceRegisters)
{
    std::memset(m.mem.data() + 0xE0000, 0x00, 0x20000);
    m.mem[0xDFFFF] = 0x00; // last byte of sector 10
    m.shadow = m.mem;
    ASSERT_EQ(0, mc_hal_flash_erase(&f.dev, 11));
    ASSERT_EQ(2u, m.keys.size());
    EXPECT_EQ(0x45670123u, m.keys[0]);
    EXPECT_EQ(0xCDEF89ABu, m.keys[1]);
    ASSERT_EQ(1u, m.cr_start.size());
    // PSIZE x32 (0x200) | SNB 11 << 3 (0x58) | SER (0x2) | STRT (0x10000)
    EXPECT_EQ(0x0001025Au, m.cr_start[0]);
    EXPECT_EQ(0x80000000u, m.regs.CR) << "locked again, SER/SNB cleared";
    for (uint32_t i = 0; i < 0x20000; ++i) {
        ASSERT_EQ(0xFF, m.mem[0xE0000 + i]);
    }
    EXPECT_EQ(0x00, m.mem[0xDFFFF]) << "sector 10 untouched";
}

TEST_F(F405Flash, ProgramWordsAndReadBack)
{
    const uint32_t w[3] = {0x4746434Du, 0x00010001u, 0x12345678u};
    ASSERT_EQ(0, mc_hal_flash_program(&f.dev, 10, 8, w, 3));
    EXPECT_EQ(3u, m.programmed);
    EXPECT_EQ(0x80000000u, m.regs.CR);
    uint32_t back[3] = {};
    ASSERT_EQ(0, mc_hal_flash_read(&f.dev, 10, 8, back, sizeof back));
    EXPECT_EQ(0, std::memcmp(w, back, sizeof w));
    uint32_t sz = 0;
    ASSERT_EQ(0, mc_hal_flash_sector_size(&f.dev, 10, &sz));
    EXPECT_EQ(131072u, sz);
}

TEST_F(F405Flash, ErrorsAndRefusals)
{
    EXPECT_EQ(-EINVAL, mc_hal_flash_erase(&f.dev, 0)) << "the code sector is protected";
    EXPECT_EQ(-EINVAL, mc_hal_flash_erase(&f.dev, 12));
    const uint32_t w = 0;
    EXPECT_EQ(-EINVAL, mc_hal_flash_program(&f.dev, 10, 2, &w, 1)) << "misaligned";
    EXPECT_EQ(-EINVAL, mc_hal_flash_program(&f.dev, 1, 16384, &w, 1)) << "past the sector";
    EXPECT_TRUE(m.keys.empty()) << "refused before touching the controller";
    for (uint32_t err : {MC_F405_FLASH_SR_WRPERR, MC_F405_FLASH_SR_PGAERR, MC_F405_FLASH_SR_PGPERR,
                         MC_F405_FLASH_SR_PGSERR}) {
        m.inject_sr = err;
        EXPECT_EQ(-EIO, mc_hal_flash_program(&f.dev, 10, 0, &w, 1)) << err;
        // (SR is rc_w1 on silicon; RAM keeps the value, so the model
        // replaces SR at each operation instead)
        EXPECT_EQ(0x80000000u, m.regs.CR);
    }
    m.inject_sr = MC_F405_FLASH_SR_WRPERR;
    EXPECT_EQ(-EIO, mc_hal_flash_erase(&f.dev, 5));
    // stuck busy: bounded wait, -EIO
    m.regs.SR = MC_F405_FLASH_SR_BSY;
    EXPECT_EQ(-EIO, mc_hal_flash_erase(&f.dev, 5));
}

} // namespace
