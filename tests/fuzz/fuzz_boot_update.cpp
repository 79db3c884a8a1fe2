// libFuzzer target: the bootloader's update protocol (firmware/boot/
// mc_boot_update.h) on a fake flash, driven by arbitrary frames. The input
// is a sequence of records (kind byte + 9 bytes): raw frames of any id,
// length and flags; BOOT_REQ with any op, arg and value; BOOT_DATA chunks;
// and, so the fuzzer reaches the deep states, the right BEGIN, blocks,
// VERIFY and COMMIT of a valid image with a frame dropped, repeated,
// swapped or corrupted where the record says. Checked after every record,
// whatever the input (the flash is wrapped):
//  - nothing outside the application slot is ever erased or programmed
//    (the bootloader's sector and the configuration sectors keep their
//    bytes);
//  - a program only clears erased words of the slot, in increasing address
//    order after the erases of a BEGIN, one block (<= 256 bytes) at the
//    block's own offset, with the bytes whose CRC-32 the WRITE announced
//    (the header's commit word excepted, written erased);
//  - the commit word is written only as MC_BOOT_COMMIT_MAGIC, and only
//    over an image that then passes the whole boot check;
//  - at most one reply per frame, a BOOT_REPLY of this node, 8 bytes.
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <vector>

extern "C" {
#include "mc_boot_image.h"
#include "mc_boot_layout.h"
#include "mc_boot_update.h"
#include "mc_can_proto.h"
#include "mc_crc32.h"
#include "mc_fake_flash.h"
}

namespace {

constexpr uint32_t kNode = 9u;
constexpr uint32_t kSectors[] = {0x400u, 0x400u, 0x400u, 0x400u, 0x1000u, 0x1000u};
constexpr uint32_t kNSectors = 6u;
constexpr uint32_t kSlotFirst = 1u, kSlotN = 3u;
constexpr uint32_t kImageBytes = 2500u;
constexpr size_t kRecord = 10u;

void die(const char* why) {
  (void)why;
  std::abort();
}

uint32_t le32(const uint8_t* p) {
  return uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24;
}

struct Rig {
  std::vector<uint8_t> mem, before;
  std::vector<uint8_t> img;
  mc_fake_flash_t fake{};
  mc_hal_flash_t checked{};
  mc_boot_crc_table_t crc{};
  mc_boot_update_t u{};
  uint32_t slot_start = 0u, slot_end = 0u;
  uint32_t next_off = 0u;  // lowest slot offset a program may write next
  uint32_t write_block = 0u, write_crc = 0u;
  bool write_seen = false;
  uint8_t shadow[MC_BOOT_BLOCK_CHUNKS * MC_BOOT_CHUNK_BYTES] = {};  // the chunks since the WRITE
  bool committed = false;
  uint32_t now_ms = 0u;

  uint32_t start(uint32_t s) const {
    uint32_t o = 0u;
    for (uint32_t i = 0u; i < s; ++i) o += kSectors[i];
    return o;
  }
  mc_boot_slot_t slot() {
    mc_boot_slot_t s = mc_boot_slot_layout1(&checked, MC_BOOT_BOARD_PIL, &crc);
    s.n_sectors = kSlotN;  // this small map's slot
    return s;
  }
};

Rig* g;

int w_size(void*, uint32_t s, uint32_t* b) {
  return mc_hal_flash_sector_size(&g->fake.dev, s, b);
}

int w_erase(void*, uint32_t s) {
  if (s < kSlotFirst || s >= kSlotFirst + kSlotN) die("erase outside the slot");
  if (s == kSlotFirst) g->next_off = 0u;  // a BEGIN starts over
  return mc_hal_flash_erase(&g->fake.dev, s);
}

int w_program(void*, uint32_t s, uint32_t off, const uint32_t* w, uint32_t n) {
  if (s < kSlotFirst || s >= kSlotFirst + kSlotN) die("program outside the slot");
  const uint32_t at = g->start(s) + off;
  const uint32_t rel = at - g->slot_start;
  for (uint32_t i = 0u; i < n; ++i) {
    uint32_t cur;
    std::memcpy(&cur, &g->mem[at + 4u * i], 4u);
    if (cur != 0xFFFFFFFFu) die("program over a word that is not erased");
  }
  if (rel == MC_BOOT_COMMIT_WORD_OFFSET && n == 1u) {
    if (w[0] != MC_BOOT_COMMIT_MAGIC) die("the commit word with another value");
    g->committed = true;
  } else {
    if (rel < g->next_off) die("a program behind the last one");
    if (n * 4u > MC_BOOT_BLOCK_BYTES || rel % MC_BOOT_BLOCK_BYTES != 0u) die("not one block");
    if (!g->write_seen || rel / MC_BOOT_BLOCK_BYTES != g->write_block)
      die("a block no WRITE announced");
    std::vector<uint8_t> b(n * 4u);
    std::memcpy(b.data(), w, b.size());
    // the bytes the chunks carried: their CRC-32 is the WRITE's, and the
    // block is written as they were (the header's commit word erased)
    std::vector<uint8_t> sent(g->shadow, g->shadow + b.size());
    if (mc_crc32(sent.data(), sent.size()) != g->write_crc)
      die("a block that does not match its WRITE");
    if (rel / MC_BOOT_BLOCK_BYTES == MC_BOOT_HDR_OFFSET / MC_BOOT_BLOCK_BYTES) {
      const uint32_t c = MC_BOOT_COMMIT_WORD_OFFSET % MC_BOOT_BLOCK_BYTES;
      if (le32(&b[c]) != 0xFFFFFFFFu) die("the header's block with its commit word set");
      std::memset(&sent[c], 0xFF, 4u);
    }
    if (b != sent) die("a block written with other bytes than its chunks carried");
    g->next_off = rel + n * 4u;
  }
  return mc_hal_flash_program(&g->fake.dev, s, off, w, n);
}

int w_read(void*, uint32_t s, uint32_t off, void* p, uint32_t len) {
  return mc_hal_flash_read(&g->fake.dev, s, off, p, len);
}

const mc_hal_flash_ops_t kChecked = {w_size, w_erase, w_program, w_read};

// A valid image for this slot: vectors, header, bytes, sealed.
std::vector<uint8_t> make_image() {
  std::vector<uint8_t> img(kImageBytes);
  for (size_t i = 0; i < img.size(); ++i) img[i] = uint8_t(i * 131u + 7u);
  auto put = [&](uint32_t at, uint32_t v) { std::memcpy(&img[at], &v, 4u); };
  put(0u, MC_BOOT_RAM_END);
  put(4u, (MC_BOOT_APP_ADDR + MC_BOOT_IMAGE_MIN_BYTES) | 1u);
  const uint32_t h[6] = {MC_BOOT_IMAGE_MAGIC, MC_BOOT_HDR_VERSION, MC_BOOT_BOARD_PIL,
                         MC_BOOT_LAYOUT_ID,   0x010203u,           kImageBytes};
  for (uint32_t i = 0u; i < 6u; ++i) put(MC_BOOT_HDR_OFFSET + 4u * i, h[i]);
  uint32_t c = mc_crc32_update(MC_CRC32_INIT, img.data(), MC_BOOT_CRC_WORD_OFFSET);
  c = mc_crc32_final(
      mc_crc32_update(c, &img[MC_BOOT_IMAGE_MIN_BYTES], kImageBytes - MC_BOOT_IMAGE_MIN_BYTES));
  put(MC_BOOT_CRC_WORD_OFFSET, c);
  put(MC_BOOT_COMMIT_WORD_OFFSET, MC_BOOT_COMMIT_MAGIC);
  return img;
}

mc_hal_can_frame_t frame(uint32_t cmd, const uint8_t* d8) {
  mc_hal_can_frame_t f{};
  f.id = mc_can_id(kNode, cmd);
  f.len = 8u;
  std::memcpy(f.data, d8, 8u);
  return f;
}

mc_hal_can_frame_t req(uint32_t op, uint32_t arg, uint32_t value) {
  uint8_t d[8] = {uint8_t(op), uint8_t(arg), uint8_t(arg >> 8), uint8_t(arg >> 16)};
  std::memcpy(&d[4], &value, 4u);
  return frame(MC_CAN_CMD_BOOT_REQ, d);
}

void deliver(const mc_hal_can_frame_t& f) {
  if (f.id == mc_can_id(kNode, MC_CAN_CMD_BOOT_REQ) && f.len == 8u &&
      f.data[0] == MC_CAN_VAL_BOOT_OP_WRITE &&
      (f.flags & (MC_HAL_CAN_FLAG_EXT | MC_HAL_CAN_FLAG_RTR | MC_HAL_CAN_FLAG_FD)) == 0u) {
    g->write_seen = true;  // what the bootloader will hold the block to
    g->write_block = uint32_t(f.data[1]) | uint32_t(f.data[2]) << 8 | uint32_t(f.data[3]) << 16;
    g->write_crc = le32(&f.data[4]);
    std::memset(g->shadow, 0, sizeof g->shadow);
  }
  if (f.id == mc_can_id(kNode, MC_CAN_CMD_BOOT_DATA) && f.len == 8u &&
      f.data[0] < MC_BOOT_BLOCK_CHUNKS &&
      (f.flags & (MC_HAL_CAN_FLAG_EXT | MC_HAL_CAN_FLAG_RTR | MC_HAL_CAN_FLAG_FD)) == 0u) {
    std::memcpy(&g->shadow[f.data[0] * MC_BOOT_CHUNK_BYTES], &f.data[1], MC_BOOT_CHUNK_BYTES);
  }
  mc_hal_can_frame_t r{};
  r.len = 0xEEu;
  const uint32_t n = mc_boot_update_rx(&g->u, &f, &r);
  if (n > 1u) die("more than one reply");
  if (n == 1u &&
      (r.id != mc_can_id(kNode, MC_CAN_CMD_BOOT_REPLY) || r.len != 8u || r.flags != 0u ||
       r.data[2] < MC_CAN_VAL_BOOT_STATE_IDLE || r.data[2] > MC_CAN_VAL_BOOT_STATE_COMMITTED))
    die("a malformed reply");
  if (g->committed) {
    mc_boot_slot_t s = g->slot();
    if (mc_boot_image_check(&s, nullptr) != MC_BOOT_IMG_OK)
      die("committed an image that fails the check");
  }
}

// The right block k, with one fault at chunk i: 0 none, 1 drop, 2 repeat, 3 swap, 4 flip.
void good_block(uint32_t k, uint32_t fault, uint32_t i, uint8_t x) {
  const uint32_t start = k * MC_BOOT_BLOCK_BYTES;
  if (start >= kImageBytes) return;
  const uint32_t len = std::min<uint32_t>(MC_BOOT_BLOCK_BYTES, kImageBytes - start);
  deliver(req(MC_CAN_VAL_BOOT_OP_WRITE, k, mc_crc32(&g->img[start], len)));
  std::vector<mc_hal_can_frame_t> fr;
  for (uint32_t c = 0u; c * MC_BOOT_CHUNK_BYTES < len; ++c) {
    uint8_t d[8] = {uint8_t(c)};
    for (uint32_t j = 0u; j < MC_BOOT_CHUNK_BYTES; ++j) {
      const uint32_t at = c * MC_BOOT_CHUNK_BYTES + j;
      d[1u + j] = at < len ? g->img[start + at] : 0u;
    }
    fr.push_back(frame(MC_CAN_CMD_BOOT_DATA, d));
  }
  i %= uint32_t(fr.size());
  if (fault == 1u) fr.erase(fr.begin() + i);
  if (fault == 2u) fr.insert(fr.begin() + i, fr[i]);
  if (fault == 3u && i + 1u < fr.size()) std::swap(fr[i], fr[i + 1u]);
  if (fault == 4u) fr[i].data[1u + x % 7u] ^= uint8_t(1u + x);
  for (const auto& f : fr) deliver(f);
}

void record(const uint8_t* r) {
  const uint8_t kind = r[0] % 9u;
  mc_hal_can_frame_t f{};
  mc_hal_can_frame_t a{};
  switch (kind) {
    case 0:  // a raw frame: any id, length, flags, data
      f.id = le32(&r[1]) & 0x7FFu;
      f.len = r[5] % 10u;
      f.flags = r[6] & MC_HAL_CAN_FLAG_ALL;
      std::memcpy(f.data, &r[1], 9u);
      deliver(f);
      break;
    case 1:  // BOOT_REQ: any op, arg, value
      deliver(req(r[1], uint32_t(r[2]) | uint32_t(r[3]) << 8, le32(&r[4]) ^ r[8]));
      break;
    case 2:  // BOOT_DATA: any chunk and bytes
      deliver(frame(MC_CAN_CMD_BOOT_DATA, &r[1]));
      break;
    case 3:  // the right BEGIN (or one field off)
      deliver(req(
          MC_CAN_VAL_BOOT_OP_BEGIN,
          (MC_BOOT_BOARD_PIL | MC_BOOT_LAYOUT_ID << 8 | MC_BOOT_HDR_VERSION << 16) ^ (r[1] & r[2]),
          kImageBytes ^ (r[3] & r[4])));
      break;
    case 4:  // the right block, perhaps with one fault
    case 5:
      good_block(r[1] % 12u, r[2] % 5u, r[3], r[4]);
      break;
    case 6: {  // VERIFY with the image's CRC (or another)
      uint32_t c;
      std::memcpy(&c, &g->img[MC_BOOT_CRC_WORD_OFFSET], 4u);
      deliver(req(MC_CAN_VAL_BOOT_OP_VERIFY, 0u, c ^ (r[1] & r[2])));
      break;
    }
    case 7:
      deliver(req(MC_CAN_VAL_BOOT_OP_COMMIT, 0u, 0u));
      break;
    default:  // time passes
      g->now_ms += uint32_t(r[1]) * 4u;
      (void)mc_boot_update_poll(&g->u, g->now_ms, &a);
      break;
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  Rig rig;
  g = &rig;
  uint32_t total = 0u;
  for (uint32_t b : kSectors) total += b;
  rig.mem.assign(total, 0xFFu);
  for (uint32_t i = 0u; i < rig.start(kSlotFirst); ++i)
    rig.mem[i] = uint8_t(i);  // "the bootloader"
  for (uint32_t i = rig.start(4u); i < total; ++i) rig.mem[i] = uint8_t(i * 7u);  // "configuration"
  rig.img = make_image();
  std::memcpy(&rig.mem[rig.start(kSlotFirst)], rig.img.data(), rig.img.size());  // an old image
  rig.before = rig.mem;
  rig.slot_start = rig.start(kSlotFirst);
  rig.slot_end = rig.start(4u);
  if (mc_fake_flash_init(&rig.fake, rig.mem.data(), kSectors, kNSectors) != 0) return 0;
  rig.checked.ops = &kChecked;
  rig.checked.ctx = nullptr;
  mc_boot_crc_table_init(&rig.crc);
  mc_boot_update_cfg_t c{};
  c.slot = rig.slot();
  c.node_id = kNode;
  c.reason = MC_BOOT_IMG_REQUESTED;
  if (mc_boot_update_init(&rig.u, &c, 0u) != MC_BOOT_CFG_OK) die("init");
  for (size_t at = 0u; at + kRecord <= size && at < 4000u * kRecord; at += kRecord) {
    record(&data[at]);
  }
  if (std::memcmp(rig.mem.data(), rig.before.data(), rig.slot_start) != 0 ||
      std::memcmp(&rig.mem[rig.slot_end], &rig.before[rig.slot_end], total - rig.slot_end) != 0)
    die("a byte outside the slot changed");
  g = nullptr;
  return 0;
}
