// hal_host::FileFlash, the SIL board's file-backed flash: the hal/flash.h
// contract (erase, NOR program, read, argument checks), persistence across
// instances (a "reboot"), refusal of a file that is not a flash image, and
// the configuration store (mc_cfg_store) on it across two boots.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "hal_host/file_flash.hpp"
extern "C" {
#include "mc_cfg_store.h"
#include "mc_drive_cog.h"
#include "mc_params.h"
}

namespace
{

using hal_host::FileFlash;

// One boot of the configuration store on the file flash: the flash opened
// on the file and the store initialised on its two sectors (a simulated
// power cycle is a second StoreBoot on the same file).
struct StoreBoot {
    FileFlash f;
    mc_cfg_store_t s{};
    explicit StoreBoot(const std::string &path) : f(path)
    {
        const mc_cfg_store_cfg_t sc{f.hal(), {0u, 1u}, 0u};
        EXPECT_EQ(mc_cfg_store_init(&s, &sc), 0);
    }
};

class FileFlashTest : public ::testing::Test
{
  protected:
    void SetUp() override
    {
        char tmpl[] = "/tmp/mc_file_flash_XXXXXX";
        ASSERT_NE(mkdtemp(tmpl), nullptr);
        dir_ = tmpl;
        path_ = dir_ + "/flash.bin";
    }
    void TearDown() override
    {
        std::remove(path_.c_str());
        std::remove((path_ + ".tmp").c_str());
        std::remove(dir_.c_str());
    }
    std::vector<uint8_t> file_bytes() const
    {
        std::ifstream f(path_, std::ios::binary);
        return std::vector<uint8_t>((std::istreambuf_iterator<char>(f)),
                                    std::istreambuf_iterator<char>());
    }
    void write_file(const std::vector<uint8_t> &b) const
    {
        std::ofstream f(path_, std::ios::binary);
        f.write(reinterpret_cast<const char *>(b.data()), static_cast<std::streamsize>(b.size()));
    }
    std::string dir_, path_;
};

TEST_F(FileFlashTest, NewFileIsErasedAndNotCreatedUntilWritten)
{
    FileFlash f(path_);
    EXPECT_FALSE(f.existed());
    uint32_t bytes = 0;
    ASSERT_EQ(mc_hal_flash_sector_size(f.hal(), 0, &bytes), 0);
    EXPECT_EQ(bytes, 16384u);
    ASSERT_EQ(mc_hal_flash_sector_size(f.hal(), 1, &bytes), 0);
    EXPECT_EQ(bytes, 16384u);
    EXPECT_EQ(mc_hal_flash_sector_size(f.hal(), 2, &bytes), -EINVAL);
    uint32_t w[4] = {0, 0, 0, 0};
    ASSERT_EQ(mc_hal_flash_read(f.hal(), 1, 16368, w, sizeof w), 0);
    for (uint32_t v : w)
        EXPECT_EQ(v, MC_HAL_FLASH_ERASED_WORD);
    EXPECT_FALSE(std::ifstream(path_).good()); // reading writes nothing
}

TEST_F(FileFlashTest, ProgramIsNorAndEraseRestores)
{
    FileFlash f(path_);
    const uint32_t a[2] = {0x12345678u, 0xF0F0F0F0u};
    ASSERT_EQ(mc_hal_flash_program(f.hal(), 0, 8, a, 2), 0);
    uint32_t r[2];
    ASSERT_EQ(mc_hal_flash_read(f.hal(), 0, 8, r, sizeof r), 0);
    EXPECT_EQ(r[0], 0x12345678u);
    EXPECT_EQ(r[1], 0xF0F0F0F0u);
    // A second program of the same word: bits only clear (AND).
    const uint32_t b = 0x0FF00FF0u;
    ASSERT_EQ(mc_hal_flash_program(f.hal(), 0, 12, &b, 1), 0);
    ASSERT_EQ(mc_hal_flash_read(f.hal(), 0, 12, r, 4), 0);
    EXPECT_EQ(r[0], 0xF0F0F0F0u & 0x0FF00FF0u);
    // The other sector is untouched; erase restores 0xFF.
    ASSERT_EQ(mc_hal_flash_read(f.hal(), 1, 8, r, sizeof r), 0);
    EXPECT_EQ(r[0], MC_HAL_FLASH_ERASED_WORD);
    ASSERT_EQ(mc_hal_flash_erase(f.hal(), 0), 0);
    ASSERT_EQ(mc_hal_flash_read(f.hal(), 0, 8, r, sizeof r), 0);
    EXPECT_EQ(r[0], MC_HAL_FLASH_ERASED_WORD);
    EXPECT_EQ(r[1], MC_HAL_FLASH_ERASED_WORD);
    EXPECT_EQ(f.erases(), 1u);
    EXPECT_EQ(f.programs(), 2u);
}

TEST_F(FileFlashTest, RefusesBadArgumentsAndChangesNothing)
{
    FileFlash f(path_);
    const uint32_t w[2] = {0, 0};
    uint8_t buf[8];
    EXPECT_EQ(mc_hal_flash_erase(f.hal(), 2), -EINVAL);
    EXPECT_EQ(mc_hal_flash_program(f.hal(), 2, 0, w, 1), -EINVAL);
    EXPECT_EQ(mc_hal_flash_program(f.hal(), 0, 2, w, 1), -EINVAL);     // misaligned
    EXPECT_EQ(mc_hal_flash_program(f.hal(), 0, 16380, w, 2), -EINVAL); // past the end
    EXPECT_EQ(mc_hal_flash_program(f.hal(), 0, 0, nullptr, 1), -EINVAL);
    EXPECT_EQ(mc_hal_flash_read(f.hal(), 0, 16380, buf, 8), -EINVAL);
    EXPECT_EQ(mc_hal_flash_read(f.hal(), 0, 0, nullptr, 8), -EINVAL);
    EXPECT_EQ(f.erases() + f.programs(), 0u);
    EXPECT_FALSE(std::ifstream(path_).good());
    ASSERT_EQ(mc_hal_flash_program(f.hal(), 0, 16380, w, 1), 0); // the last word
}

TEST_F(FileFlashTest, EveryCompletedOperationIsInTheFile)
{
    const uint32_t a[3] = {0xAABBCCDDu, 0x11223344u, 0x00000000u};
    {
        FileFlash f(path_);
        ASSERT_EQ(mc_hal_flash_program(f.hal(), 1, 100, a, 3), 0);
        // In the file already, while the instance lives (a kill now keeps it).
        const auto b = file_bytes();
        ASSERT_EQ(b.size(), FileFlash::kFileBytes);
        uint32_t w;
        std::memcpy(&w, b.data() + 16384 + 100, 4);
        EXPECT_EQ(w, 0xAABBCCDDu);
        EXPECT_EQ(b[0], 0xFFu);
        EXPECT_FALSE(std::ifstream(path_ + ".tmp").good());
    }
    FileFlash g(path_); // "reboot"
    EXPECT_TRUE(g.existed());
    uint32_t r[3];
    ASSERT_EQ(mc_hal_flash_read(g.hal(), 1, 100, r, sizeof r), 0);
    EXPECT_EQ(std::memcmp(r, a, sizeof a), 0);
    ASSERT_EQ(mc_hal_flash_erase(g.hal(), 1), 0);
    FileFlash h(path_);
    ASSERT_EQ(mc_hal_flash_read(h.hal(), 1, 100, r, 4), 0);
    EXPECT_EQ(r[0], MC_HAL_FLASH_ERASED_WORD);
}

TEST_F(FileFlashTest, WrongSizeFileIsRefusedByNameAndLeftAlone)
{
    const std::vector<uint8_t> small(1000, 0x5Au);
    write_file(small);
    try {
        FileFlash f(path_);
        FAIL() << "accepted a 1000-byte file";
    } catch (const hal_host::FileFlashError &e) {
        const std::string m = e.what();
        EXPECT_EQ(m.rfind(path_ + ": ", 0), 0u) << m;
        EXPECT_NE(m.find("1000"), std::string::npos) << m;
    }
    EXPECT_EQ(file_bytes(), small);
}

TEST_F(FileFlashTest, FolderAndMissingFolderAreRefused)
{
    EXPECT_THROW(FileFlash f(dir_), hal_host::FileFlashError); // a folder
    EXPECT_THROW(FileFlash f(dir_ + "/no/such/flash.bin"), hal_host::FileFlashError);
    EXPECT_THROW(FileFlash f(""), hal_host::FileFlashError);
}

// The configuration store on the file flash, across two "boots" (two
// processes would do the same: all state is in the file).
TEST_F(FileFlashTest, ConfigStoreKeepsItsRecordAcrossBoots)
{
    mc_params_t p = mc_params_default;
    {
        StoreBoot boot(path_);
        mc_cfg_store_t &s = boot.s;
        mc_params_t got;
        EXPECT_EQ(mc_cfg_store_load(&s, &got), MC_CFG_BOOT_EMPTY);
        p.speed_max_rad_s = 123.5f;
        p.tm_currents_hz = 50u;
        ASSERT_EQ(mc_params_validate(&p), MC_PARAMS_OK);
        ASSERT_EQ(mc_cfg_store_save(&s, &p), 0);
        ASSERT_EQ(mc_cfg_store_save(&s, &p), 0); // appends a second record
        EXPECT_EQ(s.seq, 2u);
    }
    {
        StoreBoot boot(path_);
        mc_cfg_store_t &s = boot.s;
        mc_params_t got;
        EXPECT_EQ(mc_cfg_store_load(&s, &got), MC_CFG_BOOT_STORED);
        EXPECT_EQ(std::memcmp(&got, &p, sizeof p), 0);
        EXPECT_EQ(s.seq, 2u);
    }
    // A flipped byte inside both records: no valid record left -> CORRUPT.
    auto b = file_bytes();
    ASSERT_EQ(b.size(), FileFlash::kFileBytes);
    b[4 * 6] ^= 0x01u;                      // an entry of record 1
    b[4 * (MC_CFG_REC_WORDS + 6)] ^= 0x01u; // the same in record 2
    write_file(b);
    StoreBoot boot(path_);
    mc_cfg_store_t &s = boot.s;
    mc_params_t got;
    EXPECT_EQ(mc_cfg_store_load(&s, &got), MC_CFG_BOOT_CORRUPT);
    EXPECT_EQ(std::memcmp(&got, &mc_params_default, sizeof got), 0);
}

// The anticogging map on the SIL board's flash: saved once, then enough
// configuration SAVEs to switch sectors several times (each switch copies
// the map), and a simulated power cycle (a new FileFlash on the file): the
// map reads back bit for bit and validates against the same encoder.
TEST_F(FileFlashTest, AnticoggingMapSurvivesSectorSwitchesAndAPowerCycle)
{
    std::vector<float> iq(MC_COG_N);
    for (uint32_t k = 0; k < MC_COG_N; ++k) {
        iq[k] = 0.3f * static_cast<float>((k * 29u) % 11u) - 1.5f;
    }
    const mc_cog_ident_t id{0u, 8192u, 0u, 7u, 0.5f};
    mc_cog_map_t map{};
    ASSERT_EQ(mc_cog_build(&map, iq.data(), MC_COG_N, &id, 5.0f, 0u), MC_COG_ST_OK);
    mc_params_t p = mc_params_default;
    uint32_t erases = 0u;
    {
        StoreBoot boot(path_);
        mc_cfg_store_t &s = boot.s;
        mc_params_t got;
        EXPECT_EQ(mc_cfg_store_load(&s, &got), MC_CFG_BOOT_EMPTY);
        ASSERT_EQ(mc_cfg_store_save_map(&s, &map, sizeof map), 0);
        int32_t home = s.home;
        for (uint32_t i = 0; i < 40u; ++i) {
            p.speed_max_rad_s = 100.0f + static_cast<float>(i);
            ASSERT_EQ(mc_cfg_store_save(&s, &p), 0);
            erases += (s.home != home) ? 1u : 0u;
            home = s.home;
        }
    }
    // 16 KiB sectors: 15 configuration records beside the map, 17 alone
    EXPECT_GE(erases, 2u);
    StoreBoot boot(path_);
    mc_cfg_store_t &s = boot.s;
    mc_params_t got;
    EXPECT_EQ(mc_cfg_store_load(&s, &got), MC_CFG_BOOT_STORED);
    EXPECT_EQ(got.speed_max_rad_s, 139.0f);
    mc_cog_map_t back{};
    ASSERT_EQ(mc_cfg_store_load_map(&s, &back, sizeof back), 0);
    EXPECT_EQ(std::memcmp(&back, &map, sizeof map), 0);
    EXPECT_EQ(mc_cog_check(&back, &id), MC_COG_ST_OK);
}

} // namespace
