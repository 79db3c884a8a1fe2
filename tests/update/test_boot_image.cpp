// The application image and the bootloader's start decision
// (firmware/boot/mc_boot_image.h, mc_boot_start.h) on a fake flash with the
// STM32F405's sector map: every failure of the boot check has its name,
// the table CRC equals the bitwise one, and the node id and bit rate come
// from the configuration store only when valid. Exact comparisons
// throughout (bytes, codes, CRCs): nothing here is a measurement.
#include <gtest/gtest.h>

#include "boot_test_util.hpp"

using namespace boot_test;

namespace
{

constexpr uint32_t kImageBytes = 20000u; // spans slot sectors 1 and 2

class BootImage : public ::testing::Test
{
  protected:
    Device dev{F405Sectors()};
    std::vector<uint8_t> img = MakeImage(kImageBytes, 0x010203u, 7u);

    mc_boot_img_t Check(const std::vector<uint8_t> &i)
    {
        std::fill(dev.mem.begin() + dev.SlotStart(),
                  dev.mem.begin() + dev.SlotStart() + dev.SlotBytes(), 0xFFu);
        dev.Install(i);
        const mc_boot_slot_t s = dev.Slot();
        return mc_boot_image_check(&s, nullptr);
    }
};

TEST_F(BootImage, TableCrcEqualsBitwiseCrc)
{
    mc_boot_crc_table_t t;
    mc_boot_crc_table_init(&t);
    std::mt19937 rng(3);
    for (int n = 0; n < 200; ++n) {
        std::vector<uint8_t> b(rng() % 700u);
        for (auto &x : b) {
            x = static_cast<uint8_t>(rng());
        }
        const uint32_t s0 = static_cast<uint32_t>(rng());
        ASSERT_EQ(mc_crc32_update(s0, b.data(), b.size()),
                  mc_boot_crc32_update(&t, s0, b.data(), b.size()));
    }
    const char *check = "123456789";
    EXPECT_EQ(0xCBF43926u, mc_crc32_final(mc_boot_crc32_update(&t, MC_CRC32_INIT, check, 9u)));
}

TEST_F(BootImage, ValidImagePasses)
{
    EXPECT_EQ(MC_BOOT_IMG_OK, Check(img));
    mc_boot_image_hdr_t h{};
    const mc_boot_slot_t s = dev.Slot();
    ASSERT_EQ(MC_BOOT_IMG_OK, mc_boot_image_check(&s, &h));
    EXPECT_EQ(kImageBytes, h.image_bytes);
    EXPECT_EQ(0x010203u, h.app_version);
    EXPECT_EQ(ImageCrc(img), h.crc32);
}

TEST_F(BootImage, EveryFailureIsNamed)
{
    auto field = [&](uint32_t word, uint32_t v, bool reseal) {
        auto i = img;
        Put32(&i[MC_BOOT_HDR_OFFSET + 4u * word], v);
        if (reseal) {
            Seal(i);
        }
        return i;
    };
    EXPECT_EQ(MC_BOOT_IMG_EMPTY, Check(std::vector<uint8_t>(kImageBytes, 0xFFu)));
    EXPECT_EQ(MC_BOOT_IMG_MAGIC, Check(field(0u, 0x12345678u, true)));
    EXPECT_EQ(MC_BOOT_IMG_HDR_VERSION, Check(field(1u, 2u, true)));
    EXPECT_EQ(MC_BOOT_IMG_BOARD, Check(field(2u, MC_BOOT_BOARD_VESC6, true)));
    EXPECT_EQ(MC_BOOT_IMG_LAYOUT, Check(field(3u, 2u, true)));
    // image_bytes: not a multiple of 4, smaller than the header, beyond the slot
    EXPECT_EQ(MC_BOOT_IMG_SIZE, Check(field(5u, kImageBytes - 2u, false)));
    EXPECT_EQ(MC_BOOT_IMG_SIZE, Check(field(5u, MC_BOOT_IMAGE_MIN_BYTES - 4u, false)));
    EXPECT_EQ(MC_BOOT_IMG_SIZE, Check(field(5u, dev.SlotBytes() + 4u, false)));
    // one bit anywhere in the CRC's range: vectors, header, code, last byte
    for (uint32_t at : {0u, 5u, MC_BOOT_HDR_OFFSET + 16u, 1000u, kImageBytes - 1u}) {
        auto i = img;
        i[at] ^= 0x10u;
        EXPECT_EQ(MC_BOOT_IMG_CRC, Check(i)) << "byte " << at;
    }
    auto uncommitted = img;
    Seal(uncommitted, false);
    EXPECT_EQ(MC_BOOT_IMG_UNCOMMITTED, Check(uncommitted));
    // vectors: SP outside RAM, SP unaligned, reset handler ARM state or outside
    for (auto [word, v] :
         std::vector<std::pair<uint32_t, uint32_t>>{{0u, 0x10010000u},
                                                    {0u, MC_BOOT_RAM_END - 2u},
                                                    {1u, MC_BOOT_APP_ADDR + 0x400u},
                                                    {1u, (MC_BOOT_APP_ADDR + kImageBytes) | 1u},
                                                    {1u, 0x08000101u}}) {
        auto i = img;
        Put32(&i[4u * word], v);
        Seal(i);
        EXPECT_EQ(MC_BOOT_IMG_VECTORS, Check(i)) << "vector " << word << " = " << v;
    }
}

TEST_F(BootImage, UnreadableFlashIsFlash)
{
    dev.Install(img);
    dev.flash.dead = true; // every read now fails -EIO
    const mc_boot_slot_t s = dev.Slot();
    EXPECT_EQ(MC_BOOT_IMG_FLASH, mc_boot_image_check(&s, nullptr));
}

TEST_F(BootImage, StartDecision)
{
    mc_cfg_store_t store;
    mc_boot_start_cfg_t c{};
    c.slot = dev.Slot();
    c.store = dev.Store();
    mc_boot_start_t o{};

    // a valid image, no request, nothing stored: start it; node 1, 500k
    dev.Install(img);
    mc_boot_start_decide(&c, &store, &o);
    EXPECT_EQ(MC_BOOT_IMG_OK, o.reason);
    EXPECT_EQ(1u, o.node_id);
    EXPECT_FALSE(o.node_stored);
    EXPECT_EQ(500000u, o.bitrate_bps);

    // the application asked: stay, REQUESTED; node and rate from the store
    SaveConfig(dev, 5u, 250000u);
    const auto cfg_before = dev.CfgContents();
    c.requested = true;
    mc_boot_start_decide(&c, &store, &o);
    EXPECT_EQ(MC_BOOT_IMG_OK, o.image);
    EXPECT_EQ(MC_BOOT_IMG_REQUESTED, o.reason);
    EXPECT_EQ(5u, o.node_id);
    EXPECT_TRUE(o.node_stored);
    EXPECT_EQ(250000u, o.bitrate_bps);
    EXPECT_EQ(cfg_before, dev.CfgContents()) << "the decision wrote to the configuration store";

    // an invalid image stays whatever the mailbox says
    c.requested = false;
    Seal(img, false);
    dev.Install(img);
    mc_boot_start_decide(&c, &store, &o);
    EXPECT_EQ(MC_BOOT_IMG_UNCOMMITTED, o.reason);
}

TEST_F(BootImage, StoredValuesOutOfRangeTakeTheDefaults)
{
    // A record written by other firmware: node 63, 300 kbit/s (out of the
    // table's ranges), CRC valid.
    std::vector<uint32_t> rec = {MC_CFG_MAGIC,
                                 MC_CFG_FORMAT | (99u << 16),
                                 1u,
                                 2u | 0xFFFF0000u,
                                 MC_PARAM_ID_CAN_NODE_ID,
                                 63u,
                                 MC_PARAM_ID_CAN_BITRATE_BPS,
                                 300000u};
    rec.push_back(mc_crc32(rec.data(), rec.size() * 4u));
    std::memcpy(dev.mem.data() + dev.SectorStart(dev.cfg_a), rec.data(), rec.size() * 4u);
    mc_cfg_store_t store;
    mc_boot_start_cfg_t c{};
    c.slot = dev.Slot();
    c.store = dev.Store();
    mc_boot_start_t o{};
    mc_boot_start_decide(&c, &store, &o);
    EXPECT_EQ(1u, o.node_id);
    EXPECT_FALSE(o.node_stored);
    EXPECT_EQ(500000u, o.bitrate_bps);
    // the same record with node 7 and 1 Mbit/s: taken, whatever its layout
    rec[5] = 7u;
    rec[7] = 1000000u;
    rec.back() = mc_crc32(rec.data(), (rec.size() - 1u) * 4u);
    std::memcpy(dev.mem.data() + dev.SectorStart(dev.cfg_a), rec.data(), rec.size() * 4u);
    mc_boot_start_decide(&c, &store, &o);
    EXPECT_EQ(7u, o.node_id);
    EXPECT_EQ(1000000u, o.bitrate_bps);
}

} // namespace
