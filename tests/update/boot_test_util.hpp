// Helpers of the bootloader's host tests: a fake NOR flash with the
// STM32F405's sector map (or a small one), images built and sealed as
// tools/boot/mc_image.py seals them, and a host side that speaks the update
// protocol (BOOT_REQ, BOOT_DATA, BOOT_REPLY) to mc_boot_update frame by
// frame, with hooks to drop, repeat, reorder or corrupt frames.
#ifndef BOOT_TEST_UTIL_HPP
#define BOOT_TEST_UTIL_HPP

#include <cstdint>
#include <cstring>
#include <functional>
#include <optional>
#include <random>
#include <vector>

extern "C" {
#include "mc_boot_image.h"
#include "mc_boot_layout.h"
#include "mc_boot_proto.h"
#include "mc_boot_start.h"
#include "mc_boot_update.h"
#include "mc_can_proto.h"
#include "mc_cfg_store.h"
#include "mc_crc32.h"
#include "mc_fake_flash.h"
#include "mc_params.h"
}

namespace boot_test
{

// RM0090 table 5: 4 x 16 KiB, 64 KiB, 7 x 128 KiB.
inline std::vector<uint32_t> F405Sectors()
{
    std::vector<uint32_t> s = {0x4000u, 0x4000u, 0x4000u, 0x4000u, 0x10000u};
    for (int i = 0; i < 7; ++i) {
        s.push_back(0x20000u);
    }
    return s;
}

// A small device of the same shape (bootloader sector, a slot of three
// 1 KiB sectors, two configuration sectors): every word of an update is
// affordable as a power-cut point.
inline std::vector<uint32_t> SmallSectors()
{
    return {0x400u, 0x400u, 0x400u, 0x400u, 0x1000u, 0x1000u};
}

struct Device {
    std::vector<uint32_t> sizes;
    std::vector<uint8_t> mem;
    mc_fake_flash_t flash{};
    uint32_t slot_first = MC_BOOT_APP_FIRST_SECTOR;
    uint32_t slot_n = 0u;
    uint32_t cfg_a = 0u;
    uint32_t cfg_b = 0u;
    mc_boot_crc_table_t crc{};

    explicit Device(std::vector<uint32_t> s) : sizes(std::move(s))
    {
        uint32_t total = 0u;
        for (uint32_t b : sizes) {
            total += b;
        }
        mem.assign(total, 0xFFu);
        cfg_a = static_cast<uint32_t>(sizes.size()) - 2u;
        cfg_b = cfg_a + 1u;
        slot_n = cfg_a - slot_first;
        mc_boot_crc_table_init(&crc);
        PowerOn();
    }
    // "Power on": bind the fake to the memory as it is (cuts cleared).
    void PowerOn()
    {
        mc_fake_flash_init(&flash, mem.data(), sizes.data(), static_cast<uint32_t>(sizes.size()));
    }
    uint32_t SectorStart(uint32_t sector) const
    {
        uint32_t off = 0u;
        for (uint32_t i = 0u; i < sector; ++i) {
            off += sizes[i];
        }
        return off;
    }
    uint32_t SlotStart() const
    {
        return SectorStart(slot_first);
    }
    uint32_t SlotBytes() const
    {
        return SectorStart(cfg_a) - SlotStart();
    }
    mc_boot_slot_t Slot(uint32_t board = MC_BOOT_BOARD_EXAMPLE) const
    {
        mc_boot_slot_t s = mc_boot_slot_layout1(&flash.dev, board, &crc);
        s.n_sectors = slot_n; // the small map's slot is shorter
        return s;
    }
    mc_cfg_store_cfg_t Store() const
    {
        mc_cfg_store_cfg_t c{};
        c.flash = &flash.dev;
        c.sector[0] = cfg_a;
        c.sector[1] = cfg_b;
        return c;
    }
    std::vector<uint8_t> SlotContents(uint32_t n) const
    {
        return std::vector<uint8_t>(mem.begin() + SlotStart(), mem.begin() + SlotStart() + n);
    }
    std::vector<uint8_t> CfgContents() const
    {
        return std::vector<uint8_t>(mem.begin() + SectorStart(cfg_a), mem.end());
    }
    void Install(const std::vector<uint8_t> &img)
    {
        std::memcpy(mem.data() + SlotStart(), img.data(), img.size());
    }
};

inline uint32_t Le32(const uint8_t *p)
{
    return static_cast<uint32_t>(p[0]) | (static_cast<uint32_t>(p[1]) << 8) |
           (static_cast<uint32_t>(p[2]) << 16) | (static_cast<uint32_t>(p[3]) << 24);
}

inline void Put32(uint8_t *p, uint32_t v)
{
    for (int i = 0; i < 4; ++i) {
        p[i] = static_cast<uint8_t>(v >> (8 * i));
    }
}

// The image CRC as the seal computes it (crc32 and commit words left out).
inline uint32_t ImageCrc(const std::vector<uint8_t> &img)
{
    uint32_t c = mc_crc32_update(MC_CRC32_INIT, img.data(), MC_BOOT_CRC_WORD_OFFSET);
    c = mc_crc32_update(c, img.data() + MC_BOOT_IMAGE_MIN_BYTES,
                        img.size() - MC_BOOT_IMAGE_MIN_BYTES);
    return mc_crc32_final(c);
}

// Recompute crc32 (and set commit) after a field was changed.
inline void Seal(std::vector<uint8_t> &img, bool committed = true)
{
    Put32(&img[MC_BOOT_HDR_OFFSET + 20u], static_cast<uint32_t>(img.size()));
    Put32(&img[MC_BOOT_CRC_WORD_OFFSET], ImageCrc(img));
    Put32(&img[MC_BOOT_COMMIT_WORD_OFFSET], committed ? MC_BOOT_COMMIT_MAGIC : 0xFFFFFFFFu);
}

// An image of `bytes` (a multiple of 4): vectors (SP at the top of RAM, the
// reset handler inside the image), the header, pseudo-random code.
inline std::vector<uint8_t> MakeImage(uint32_t bytes, uint32_t version, uint32_t seed,
                                      uint32_t board = MC_BOOT_BOARD_EXAMPLE,
                                      uint32_t layout = MC_BOOT_LAYOUT_ID)
{
    std::vector<uint8_t> img(bytes);
    std::mt19937 rng(seed);
    for (auto &b : img) {
        b = static_cast<uint8_t>(rng());
    }
    Put32(&img[0], MC_BOOT_RAM_END);
    Put32(&img[4], (MC_BOOT_APP_ADDR + MC_BOOT_IMAGE_MIN_BYTES) | 1u);
    const uint32_t hdr[6] = {
        MC_BOOT_IMAGE_MAGIC, MC_BOOT_HDR_VERSION, board, layout, version, bytes};
    for (uint32_t i = 0u; i < 6u; ++i) {
        Put32(&img[MC_BOOT_HDR_OFFSET + 4u * i], hdr[i]);
    }
    Seal(img);
    return img;
}

// A valid configuration record with this node id (and bit rate).
inline void SaveConfig(Device &d, uint32_t node_id, uint32_t bitrate_bps = 500000u)
{
    mc_params_t p = mc_params_default;
    p.can_node_id = node_id;
    p.can_bitrate_bps = bitrate_bps;
    static mc_cfg_store_t s; // large: keep it off the stack
    const mc_cfg_store_cfg_t c = d.Store();
    mc_cfg_store_init(&s, &c);
    mc_cfg_store_save(&s, &p);
}

struct Reply {
    uint32_t op, status, state, reason, value;
};

inline Reply Decode(const mc_hal_can_frame_t &f)
{
    return {f.data[0], f.data[1], f.data[2], f.data[3], Le32(&f.data[4])};
}

inline mc_hal_can_frame_t ReqFrame(uint32_t node, uint32_t op, uint32_t arg, uint32_t value)
{
    mc_hal_can_frame_t f{};
    f.id = mc_can_id(node, MC_CAN_CMD_BOOT_REQ);
    f.len = 8u;
    f.data[0] = static_cast<uint8_t>(op);
    f.data[1] = static_cast<uint8_t>(arg);
    f.data[2] = static_cast<uint8_t>(arg >> 8);
    f.data[3] = static_cast<uint8_t>(arg >> 16);
    Put32(&f.data[4], value);
    return f;
}

// BOOT_DATA frames of block k of img.
inline std::vector<mc_hal_can_frame_t> DataFrames(uint32_t node, const std::vector<uint8_t> &img,
                                                  uint32_t k)
{
    std::vector<mc_hal_can_frame_t> out;
    const uint32_t start = k * MC_BOOT_BLOCK_BYTES;
    const uint32_t len =
        std::min<uint32_t>(MC_BOOT_BLOCK_BYTES, static_cast<uint32_t>(img.size()) - start);
    for (uint32_t c = 0u; c * MC_BOOT_CHUNK_BYTES < len; ++c) {
        mc_hal_can_frame_t f{};
        f.id = mc_can_id(node, MC_CAN_CMD_BOOT_DATA);
        f.len = 8u;
        f.data[0] = static_cast<uint8_t>(c);
        for (uint32_t i = 0u; i < MC_BOOT_CHUNK_BYTES; ++i) {
            const uint32_t at = c * MC_BOOT_CHUNK_BYTES + i;
            f.data[1u + i] = (at < len) ? img[start + at] : 0u;
        }
        out.push_back(f);
    }
    return out;
}

inline uint32_t BlockCrc(const std::vector<uint8_t> &img, uint32_t k)
{
    const uint32_t start = k * MC_BOOT_BLOCK_BYTES;
    const uint32_t len =
        std::min<uint32_t>(MC_BOOT_BLOCK_BYTES, static_cast<uint32_t>(img.size()) - start);
    return mc_crc32(img.data() + start, len);
}

inline uint32_t BeginArg(uint32_t board, uint32_t layout = MC_BOOT_LAYOUT_ID,
                         uint32_t hdr_version = MC_BOOT_HDR_VERSION)
{
    return board | (layout << 8) | (hdr_version << 16);
}

// The host end: frames into the bootloader, replies out. `channel` may
// rewrite the frames of a block before they are delivered (drop, repeat,
// reorder, corrupt); the clock advances 1 ms per request so the reply
// budget refills as on a real bus.
struct Host {
    mc_boot_update_t *u;
    uint32_t node;
    uint32_t now_ms = 0u;
    std::function<void(uint32_t k, std::vector<mc_hal_can_frame_t> &)> channel;

    Host(mc_boot_update_t *p_u, uint32_t node_id) : u(p_u), node(node_id)
    {
    }

    std::optional<Reply> Deliver(const mc_hal_can_frame_t &f)
    {
        mc_hal_can_frame_t r{}, a{};
        now_ms += 1u;
        (void)mc_boot_update_poll(u, now_ms, &a);
        if (mc_boot_update_rx(u, &f, &r) == 1u) {
            return Decode(r);
        }
        return std::nullopt;
    }
    // A request and its answer: a round trip of a few ms on a real bus.
    std::optional<Reply> Req(uint32_t op, uint32_t arg = 0u, uint32_t value = 0u)
    {
        now_ms += 9u;
        return Deliver(ReqFrame(node, op, arg, value));
    }
    // WRITE k and its data; the reply (if any) of the last frame that gave one.
    std::optional<Reply> Block(const std::vector<uint8_t> &img, uint32_t k)
    {
        std::optional<Reply> last = Req(MC_CAN_VAL_BOOT_OP_WRITE, k, BlockCrc(img, k));
        auto frames = DataFrames(node, img, k);
        if (channel) {
            channel(k, frames);
        }
        for (const auto &f : frames) {
            auto r = Deliver(f);
            if (r) {
                last = r;
            }
        }
        return last;
    }
    // The whole update with up to `retries` resends per block. Returns the
    // last reply (COMMIT's OK when it went through).
    std::optional<Reply> Update(const std::vector<uint8_t> &img, uint32_t board, int retries = 0)
    {
        auto r = Req(MC_CAN_VAL_BOOT_OP_BEGIN, BeginArg(board), static_cast<uint32_t>(img.size()));
        if (!r || r->status != MC_CAN_VAL_BOOT_STATUS_OK) {
            return r;
        }
        const uint32_t n = (static_cast<uint32_t>(img.size()) + 255u) / 256u;
        uint32_t k = 0u;
        int tries = 0;
        while (k < n) {
            r = Block(img, k);
            if (r && r->status == MC_CAN_VAL_BOOT_STATUS_OK && r->value == k + 1u) {
                k++;
                tries = 0;
                continue;
            }
            if (++tries > retries) {
                return r;
            }
            if (r && r->op == MC_CAN_VAL_BOOT_OP_WRITE && r->value <= k) {
                k = r->value; // the block the bootloader expects
            }
        }
        r = Req(MC_CAN_VAL_BOOT_OP_VERIFY, 0u, ImageCrc(img));
        if (!r || r->status != MC_CAN_VAL_BOOT_STATUS_OK) {
            return r;
        }
        return Req(MC_CAN_VAL_BOOT_OP_COMMIT);
    }
};

} // namespace boot_test

#endif // BOOT_TEST_UTIL_HPP
