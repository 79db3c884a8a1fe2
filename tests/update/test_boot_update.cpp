// The bootloader's update protocol (firmware/boot/mc_boot_update.h) on a
// fake flash: a whole update, every refusal with its name, dropped,
// repeated, reordered and corrupted frames that never write a wrong byte,
// the reply budget, and a power cut at every erase and every programmed
// word of an update (both "the step did not happen" and "the step was cut
// half way"), each followed by a reboot that must start the old image,
// the new one, or stay in the bootloader with a named reason, and by an
// update that must then complete. Exact comparisons throughout.
#include <gtest/gtest.h>

#include <set>

#include "boot_test_util.hpp"

using namespace boot_test;

namespace
{

constexpr uint32_t kNode = 5u;
constexpr uint32_t kBoard = MC_BOOT_BOARD_EXAMPLE;

class BootUpdate : public ::testing::Test
{
  protected:
    Device dev{F405Sectors()};
    std::vector<uint8_t> old_img = MakeImage(9000u, 0x010000u, 1u);
    std::vector<uint8_t> new_img = MakeImage(20000u, 0x020000u, 2u);
    mc_boot_update_t u{};
    Host host{&u, kNode};
    std::vector<uint8_t> cfg_before;

    void SetUp() override
    {
        dev.Install(old_img);
        SaveConfig(dev, kNode);
        cfg_before = dev.CfgContents();
        Start();
    }
    void Start()
    {
        mc_boot_update_cfg_t c{};
        c.slot = dev.Slot();
        c.node_id = kNode;
        c.reason = MC_BOOT_IMG_REQUESTED;
        ASSERT_EQ(MC_BOOT_CFG_OK, mc_boot_update_init(&u, &c, host.now_ms));
    }
    mc_boot_img_t Boot(mc_boot_image_hdr_t *h = nullptr)
    {
        const mc_boot_slot_t s = dev.Slot();
        return mc_boot_image_check(&s, h);
    }
    // The slot holds new_img's first `blocks` blocks (commit word erased)
    // and is erased beyond them: no wrong byte anywhere.
    ::testing::AssertionResult SlotIsPrefix(uint32_t blocks)
    {
        auto want = new_img;
        Put32(&want[MC_BOOT_COMMIT_WORD_OFFSET], 0xFFFFFFFFu);
        const auto got = dev.SlotContents(static_cast<uint32_t>(want.size()));
        for (uint32_t i = 0u; i < want.size(); ++i) {
            const uint8_t w = (i < blocks * MC_BOOT_BLOCK_BYTES) ? want[i] : 0xFFu;
            if (got[i] != w) {
                return ::testing::AssertionFailure()
                       << "slot byte " << i << " is " << int(got[i]) << ", expected " << int(w);
            }
        }
        return ::testing::AssertionSuccess();
    }
    void ExpectNewImageBoots()
    {
        mc_boot_image_hdr_t h{};
        ASSERT_EQ(MC_BOOT_IMG_OK, Boot(&h));
        EXPECT_EQ(0x020000u, h.app_version);
        EXPECT_EQ(new_img, dev.SlotContents(static_cast<uint32_t>(new_img.size())));
        EXPECT_EQ(cfg_before, dev.CfgContents()) << "the configuration store changed";
    }
};

TEST_F(BootUpdate, WholeUpdateThenTheNewImageBoots)
{
    const auto r = host.Update(new_img, kBoard);
    ASSERT_TRUE(r.has_value());
    EXPECT_EQ(uint32_t{MC_CAN_VAL_BOOT_OP_COMMIT}, r->op);
    EXPECT_EQ(uint32_t{MC_CAN_VAL_BOOT_STATUS_OK}, r->status);
    EXPECT_EQ(uint32_t{MC_CAN_VAL_BOOT_STATE_COMMITTED}, r->state);
    EXPECT_EQ(MC_BOOT_ACT_RESET, mc_boot_update_action(&u));
    // 20000 bytes: 79 blocks; slot sectors 1 and 2 (16 KiB each) erased
    EXPECT_EQ(79u, u.blocks_written);
    EXPECT_EQ(2u, u.sectors_erased);
    EXPECT_EQ(0u, u.replies_limited);
    ExpectNewImageBoots();
}

TEST_F(BootUpdate, TheApplicationsConfigurationLoadsAsBeforeTheUpdate)
{
    // the store as the new image's mc_app_boot reads it: the same record,
    // STORED, every parameter the same (node 5 included)
    static mc_cfg_store_t store;
    const mc_cfg_store_cfg_t sc = dev.Store();
    mc_params_t before{}, after{};
    ASSERT_EQ(0, mc_cfg_store_init(&store, &sc));
    ASSERT_EQ(MC_CFG_BOOT_STORED, mc_cfg_store_load(&store, &before));
    const auto r = host.Update(new_img, kBoard);
    ASSERT_TRUE(r && r->status == MC_CAN_VAL_BOOT_STATUS_OK);
    ASSERT_EQ(0, mc_cfg_store_init(&store, &sc));
    EXPECT_EQ(MC_CFG_BOOT_STORED, mc_cfg_store_load(&store, &after));
    EXPECT_EQ(0, std::memcmp(&before, &after, sizeof before));
    EXPECT_EQ(kNode, after.can_node_id);
}

TEST_F(BootUpdate, InfoVersionAndAnnounce)
{
    auto r = host.Req(MC_CAN_VAL_BOOT_OP_INFO);
    ASSERT_TRUE(r);
    EXPECT_EQ(kBoard | (MC_BOOT_LAYOUT_ID << 8) | (MC_BOOT_PROTO_VERSION << 16), r->value);
    EXPECT_EQ(uint32_t{MC_CAN_VAL_BOOT_STATE_IDLE}, r->state);
    EXPECT_EQ(uint32_t{MC_CAN_VAL_BOOT_REASON_REQUESTED}, r->reason);
    r = host.Req(MC_CAN_VAL_BOOT_OP_VERSION);
    ASSERT_TRUE(r);
    EXPECT_EQ(0x010000u, r->value); // the image in the slot
    // ANNOUNCE at once, then once per MC_BOOT_ANNOUNCE_MS
    host.now_ms = 0u;
    Start();
    mc_hal_can_frame_t f{};
    std::vector<uint32_t> at;
    for (uint32_t t = 0u; t <= 3000u; ++t) {
        if (mc_boot_update_poll(&u, t, &f) == 1u) {
            at.push_back(t);
            EXPECT_EQ(mc_can_id(kNode, MC_CAN_CMD_BOOT_REPLY), f.id);
            EXPECT_EQ(uint32_t{MC_CAN_VAL_BOOT_OP_ANNOUNCE}, Decode(f).op);
        }
    }
    EXPECT_EQ((std::vector<uint32_t>{0u, 1000u, 2000u, 3000u}), at);
}

TEST_F(BootUpdate, AnImageForAnotherBoardOrLayoutIsRefusedBeforeAnythingIsErased)
{
    const uint32_t n = static_cast<uint32_t>(new_img.size());
    struct Case {
        uint32_t arg, value, status;
    };
    for (const Case &c :
         {Case{BeginArg(MC_BOOT_BOARD_VESC6), n, MC_CAN_VAL_BOOT_STATUS_BOARD},
          Case{BeginArg(kBoard, 2u), n, MC_CAN_VAL_BOOT_STATUS_LAYOUT},
          Case{BeginArg(kBoard, MC_BOOT_LAYOUT_ID, 2u), n, MC_CAN_VAL_BOOT_STATUS_HEADER},
          Case{BeginArg(kBoard), n + 2u, MC_CAN_VAL_BOOT_STATUS_SIZE},
          Case{BeginArg(kBoard), dev.SlotBytes() + 4u, MC_CAN_VAL_BOOT_STATUS_SIZE},
          Case{BeginArg(kBoard), 64u, MC_CAN_VAL_BOOT_STATUS_SIZE}}) {
        const auto r = host.Req(MC_CAN_VAL_BOOT_OP_BEGIN, c.arg, c.value);
        ASSERT_TRUE(r);
        EXPECT_EQ(c.status, r->status) << "BEGIN arg 0x" << std::hex << c.arg;
        EXPECT_EQ(0u, u.sectors_erased);
        EXPECT_EQ(MC_BOOT_IMG_OK, Boot()) << "the old image was touched";
    }
    // BEGIN agrees, but the image's own header names another board: the
    // header's block is refused, and VERIFY never passes
    auto other =
        MakeImage(static_cast<uint32_t>(new_img.size()), 0x020000u, 2u, MC_BOOT_BOARD_ODRIVE36);
    ASSERT_EQ(uint32_t{MC_CAN_VAL_BOOT_STATUS_OK},
              host.Req(MC_CAN_VAL_BOOT_OP_BEGIN, BeginArg(kBoard), n)->status);
    EXPECT_EQ(uint32_t{MC_CAN_VAL_BOOT_STATUS_OK}, host.Block(other, 0u)->status);
    const auto r = host.Block(other, 1u);
    EXPECT_EQ(uint32_t{MC_CAN_VAL_BOOT_STATUS_HEADER}, r->status);
    EXPECT_EQ(1u, r->value) << "block 1 must be sent again";
    EXPECT_NE(MC_BOOT_IMG_OK, Boot());
}

TEST_F(BootUpdate, ACorruptImageNeverVerifiesNorBoots)
{
    auto bad = new_img;
    bad[15000] ^= 1u; // the file changed after sealing: block CRCs fine, image CRC not
    auto r = host.Update(bad, kBoard);
    ASSERT_TRUE(r);
    EXPECT_EQ(uint32_t{MC_CAN_VAL_BOOT_OP_VERIFY}, r->op);
    EXPECT_EQ(uint32_t{MC_CAN_VAL_BOOT_STATUS_IMAGE_CRC}, r->status);
    EXPECT_EQ(uint32_t{MC_CAN_VAL_BOOT_STATE_IDLE}, r->state);
    EXPECT_EQ(MC_BOOT_IMG_CRC, Boot()) << "the slot holds the corrupt image, uncommitted";
    // COMMIT without VERIFY: refused
    EXPECT_EQ(uint32_t{MC_CAN_VAL_BOOT_STATUS_STATE}, host.Req(MC_CAN_VAL_BOOT_OP_COMMIT)->status);
    EXPECT_NE(MC_BOOT_IMG_OK, Boot());
    // and the right image afterwards
    r = host.Update(new_img, kBoard);
    EXPECT_EQ(uint32_t{MC_CAN_VAL_BOOT_STATUS_OK}, r->status);
    ExpectNewImageBoots();
}

// Block k's frames through a faulty channel: each fault must fail the block
// with its name and leave the slot exactly as before it.
TEST_F(BootUpdate, DroppedRepeatedReorderedOrCorruptFramesNeverWriteAWrongByte)
{
    const uint32_t n = static_cast<uint32_t>(new_img.size());
    ASSERT_EQ(uint32_t{MC_CAN_VAL_BOOT_STATUS_OK},
              host.Req(MC_CAN_VAL_BOOT_OP_BEGIN, BeginArg(kBoard), n)->status);
    using Frames = std::vector<mc_hal_can_frame_t>;
    struct Fault {
        const char *what;
        std::function<void(Frames &, uint32_t i)> apply;
        uint32_t status; // expected reply; UINT32_MAX: no reply (block incomplete)
    };
    const std::vector<Fault> faults = {
        {"drop", [](Frames &f, uint32_t i) { f.erase(f.begin() + i); },
         MC_CAN_VAL_BOOT_STATUS_SEQUENCE},
        {"repeat", [](Frames &f, uint32_t i) { f.insert(f.begin() + i, f[i]); },
         MC_CAN_VAL_BOOT_STATUS_SEQUENCE},
        {"swap", [](Frames &f, uint32_t i) { std::swap(f[i], f[i + 1u]); },
         MC_CAN_VAL_BOOT_STATUS_SEQUENCE},
        {"corrupt", [](Frames &f, uint32_t i) { f[i].data[3] ^= 0x40u; },
         MC_CAN_VAL_BOOT_STATUS_BLOCK_CRC},
        {"short", [](Frames &f, uint32_t i) { f[i].len = 7u; }, MC_CAN_VAL_BOOT_STATUS_FORMAT},
        {"padding", [](Frames &f, uint32_t) { f.back().data[7] = 1u; },
         MC_CAN_VAL_BOOT_STATUS_FORMAT},
    };
    uint32_t k = 0u;
    for (const auto &fault : faults) {
        for (uint32_t i : {0u, 17u, 35u}) { // first, middle, next to last chunk
            host.channel = [&](uint32_t, Frames &f) { fault.apply(f, i); };
            const auto r = host.Block(new_img, k);
            ASSERT_TRUE(r) << fault.what << " at chunk " << i;
            EXPECT_EQ(fault.status, r->status) << fault.what << " at chunk " << i;
            EXPECT_EQ(k, r->value) << "the block to send again";
            EXPECT_TRUE(SlotIsPrefix(k)) << fault.what << " at chunk " << i;
            host.channel = nullptr;
            ASSERT_EQ(k + 1u, host.Block(new_img, k)->value);
            EXPECT_TRUE(SlotIsPrefix(++k));
        }
    }
    // the last chunk lost: no reply (the host times out and sends it again)
    host.channel = [](uint32_t, Frames &f) { f.pop_back(); };
    const auto r = host.Block(new_img, k);
    EXPECT_FALSE(r.has_value() && r->op == MC_CAN_VAL_BOOT_OP_WRITE && r->status == 0u);
    EXPECT_TRUE(SlotIsPrefix(k));
    host.channel = nullptr;
    // a block out of order, and a WRITE repeated after its OK was lost
    auto s = host.Req(MC_CAN_VAL_BOOT_OP_WRITE, k + 1u, BlockCrc(new_img, k + 1u));
    EXPECT_EQ(uint32_t{MC_CAN_VAL_BOOT_STATUS_SEQUENCE}, s->status);
    EXPECT_EQ(k, s->value);
    ASSERT_EQ(k + 1u, host.Block(new_img, k)->value);
    const uint32_t words = dev.flash.words;
    s = host.Block(new_img, k); // again: answered, not written
    EXPECT_EQ(uint32_t{MC_CAN_VAL_BOOT_STATUS_OK}, s->status);
    EXPECT_EQ(k + 1u, s->value);
    EXPECT_EQ(words, dev.flash.words);
    EXPECT_TRUE(SlotIsPrefix(k + 1u));
    // a repeat with another CRC is a different block: refused
    s = host.Req(MC_CAN_VAL_BOOT_OP_WRITE, k, BlockCrc(new_img, k) ^ 1u);
    EXPECT_EQ(uint32_t{MC_CAN_VAL_BOOT_STATUS_SEQUENCE}, s->status);
}

TEST_F(BootUpdate, RequestsAreCheckedAndAnsweredByName)
{
    // wrong length, reserved fields set, unknown op, out of session
    mc_hal_can_frame_t f = ReqFrame(kNode, MC_CAN_VAL_BOOT_OP_INFO, 0u, 0u);
    f.len = 7u;
    EXPECT_EQ(uint32_t{MC_CAN_VAL_BOOT_STATUS_FORMAT}, host.Deliver(f)->status);
    EXPECT_EQ(uint32_t{MC_CAN_VAL_BOOT_STATUS_FORMAT},
              host.Req(MC_CAN_VAL_BOOT_OP_INFO, 1u, 0u)->status);
    EXPECT_EQ(uint32_t{MC_CAN_VAL_BOOT_STATUS_FORMAT},
              host.Req(MC_CAN_VAL_BOOT_OP_COMMIT, 0u, 9u)->status);
    EXPECT_EQ(uint32_t{MC_CAN_VAL_BOOT_STATUS_OPCODE}, host.Req(0x77u)->status);
    EXPECT_EQ(uint32_t{MC_CAN_VAL_BOOT_STATUS_STATE},
              host.Req(MC_CAN_VAL_BOOT_OP_WRITE, 0u, 0u)->status);
    EXPECT_EQ(uint32_t{MC_CAN_VAL_BOOT_STATUS_STATE},
              host.Req(MC_CAN_VAL_BOOT_OP_VERIFY, 0u, 0u)->status);
    EXPECT_EQ(uint32_t{MC_CAN_VAL_BOOT_STATUS_KEY},
              host.Req(MC_CAN_VAL_BOOT_OP_ENTER, 0u, 1u)->status);
    EXPECT_EQ(uint32_t{MC_CAN_VAL_BOOT_STATUS_OK},
              host.Req(MC_CAN_VAL_BOOT_OP_ENTER, 0u, MC_BOOT_ENTER_KEY)->status);
    // remote and extended frames, other nodes, data frames without a block
    f = ReqFrame(kNode, MC_CAN_VAL_BOOT_OP_INFO, 0u, 0u);
    f.flags = MC_HAL_CAN_FLAG_RTR;
    EXPECT_EQ(uint32_t{MC_CAN_VAL_BOOT_STATUS_FORMAT}, host.Deliver(f)->status);
    f.flags = MC_HAL_CAN_FLAG_EXT;
    EXPECT_FALSE(host.Deliver(f).has_value());
    EXPECT_FALSE(host.Deliver(ReqFrame(kNode + 1u, MC_CAN_VAL_BOOT_OP_INFO, 0u, 0u)).has_value());
    EXPECT_FALSE(host.Deliver(DataFrames(kNode, new_img, 0u)[0]).has_value());
    EXPECT_EQ(0u, u.sectors_erased + u.blocks_written);
    // ABORT ends a session; RUN asks for the reset
    ASSERT_EQ(uint32_t{MC_CAN_VAL_BOOT_STATUS_OK},
              host.Req(MC_CAN_VAL_BOOT_OP_BEGIN, BeginArg(kBoard), 1024u)->status);
    EXPECT_EQ(uint32_t{MC_CAN_VAL_BOOT_STATE_RECEIVING}, host.Req(MC_CAN_VAL_BOOT_OP_INFO)->state);
    EXPECT_EQ(uint32_t{MC_CAN_VAL_BOOT_STATE_IDLE}, host.Req(MC_CAN_VAL_BOOT_OP_ABORT)->state);
    EXPECT_EQ(MC_BOOT_ACT_NONE, mc_boot_update_action(&u));
    EXPECT_EQ(uint32_t{MC_CAN_VAL_BOOT_STATUS_OK}, host.Req(MC_CAN_VAL_BOOT_OP_RUN)->status);
    EXPECT_EQ(MC_BOOT_ACT_RESET, mc_boot_update_action(&u));
}

TEST_F(BootUpdate, RepliesStayWithinTheirBudget)
{
    // 1000 INFO requests within 100 ms of bus time: the burst, then
    // MC_BOOT_REPLY_MAX_HZ per second (250/s x 0.1 s = 25 more), the rest
    // counted. The poll before each request refills (Host::Deliver).
    uint32_t got = 0u;
    for (int i = 0; i < 1000; ++i) {
        mc_hal_can_frame_t r{}, a{};
        host.now_ms = static_cast<uint32_t>(i / 10);
        (void)mc_boot_update_poll(&u, host.now_ms, &a);
        const mc_hal_can_frame_t f = ReqFrame(kNode, MC_CAN_VAL_BOOT_OP_INFO, 0u, 0u);
        got += mc_boot_update_rx(&u, &f, &r);
    }
    // bound: burst 8, + 250/s x 99 ms = 24.75 (the announce at t = 0 took one)
    EXPECT_GE(got, 30u);
    EXPECT_LE(got, 8u + 25u);
    EXPECT_EQ(1000u, got + u.replies_limited);
}

TEST_F(BootUpdate, LossyChannelStillWritesExactlyTheImage)
{
    // Random faults on 5 % of the blocks, the host resending as told.
    std::mt19937 rng(99);
    host.channel = [&](uint32_t, std::vector<mc_hal_can_frame_t> &f) {
        if (rng() % 20u != 0u) {
            return;
        }
        const uint32_t i = rng() % (f.size() - 1u);
        switch (rng() % 4u) {
        case 0:
            f.erase(f.begin() + i);
            break;
        case 1:
            f.insert(f.begin() + i, f[i]);
            break;
        case 2:
            std::swap(f[i], f[i + 1u]);
            break;
        default:
            f[i].data[1u + rng() % 7u] ^= static_cast<uint8_t>(1u + rng() % 255u);
            break;
        }
    };
    const auto r = host.Update(new_img, kBoard, 5);
    ASSERT_TRUE(r);
    EXPECT_EQ(uint32_t{MC_CAN_VAL_BOOT_STATUS_OK}, r->status);
    EXPECT_GT(u.blocks_failed, 0u) << "the channel never faulted: the test proves nothing";
    ExpectNewImageBoots();
}

// ------------------------------------------------------------- power cuts

enum class Outcome {
    kOld,
    kNew,
    kBootloader
};

struct CutResult {
    Outcome outcome;
    mc_boot_img_t reason;
};

// Run an update cut at step k (tear or not), reboot, classify; then check
// the update completes from there. Returns the classification.
CutResult CutAndRecover(Device &dev, const std::vector<uint8_t> &old_img,
                        const std::vector<uint8_t> &new_img, uint32_t k, mc_fake_flash_tear_t tear,
                        const std::vector<uint8_t> &cfg_before)
{
    mc_boot_update_t u{};
    Host host{&u, kNode};
    mc_boot_update_cfg_t c{};
    c.slot = dev.Slot();
    c.node_id = kNode;
    c.reason = MC_BOOT_IMG_REQUESTED;
    EXPECT_EQ(MC_BOOT_CFG_OK, mc_boot_update_init(&u, &c, 0u));
    mc_fake_flash_cut_at(&dev.flash, k, tear);
    (void)host.Update(new_img, kBoard);
    EXPECT_TRUE(dev.flash.dead) << "step " << k << " was never reached";

    dev.PowerOn(); // reboot: the flash as the cut left it
    mc_cfg_store_t store;
    mc_boot_start_cfg_t sc{};
    sc.slot = dev.Slot();
    sc.store = dev.Store();
    mc_boot_start_t st{};
    mc_boot_start_decide(&sc, &store, &st);
    CutResult res{Outcome::kBootloader, st.reason};
    const auto slot_old = dev.SlotContents(static_cast<uint32_t>(old_img.size()));
    const auto slot_new = dev.SlotContents(static_cast<uint32_t>(new_img.size()));
    if (st.reason == MC_BOOT_IMG_OK) {
        // it starts an image: exactly the old one or exactly the new one
        if (slot_old == old_img && st.hdr.app_version == 0x010000u) {
            res.outcome = Outcome::kOld;
        } else if (slot_new == new_img && st.hdr.app_version == 0x020000u) {
            res.outcome = Outcome::kNew;
        } else {
            ADD_FAILURE() << "step " << k << ": a valid image that is neither old nor new";
        }
    }
    EXPECT_EQ(kNode, st.node_id) << "step " << k;
    EXPECT_EQ(cfg_before, dev.CfgContents()) << "step " << k << ": the configuration changed";

    // the update then completes (a new session, as after a real reboot)
    mc_boot_update_t u2{};
    Host h2{&u2, kNode};
    c.reason = st.reason;
    EXPECT_EQ(MC_BOOT_CFG_OK, mc_boot_update_init(&u2, &c, 0u));
    const auto r = h2.Update(new_img, kBoard);
    EXPECT_TRUE(r && r->status == MC_CAN_VAL_BOOT_STATUS_OK) << "step " << k;
    mc_boot_image_hdr_t h{};
    const mc_boot_slot_t s = dev.Slot();
    EXPECT_EQ(MC_BOOT_IMG_OK, mc_boot_image_check(&s, &h)) << "step " << k;
    EXPECT_EQ(new_img, dev.SlotContents(static_cast<uint32_t>(new_img.size()))) << "step " << k;
    return res;
}

// Steps of one whole update on a fresh device: erases + programmed words.
uint32_t CountSteps(const std::vector<uint32_t> &sizes, const std::vector<uint8_t> &old_img,
                    const std::vector<uint8_t> &new_img)
{
    Device d{sizes};
    d.Install(old_img);
    SaveConfig(d, kNode);
    d.PowerOn();
    mc_boot_update_t u{};
    Host host{&u, kNode};
    mc_boot_update_cfg_t c{};
    c.slot = d.Slot();
    c.node_id = kNode;
    mc_boot_update_init(&u, &c, 0u);
    const auto r = host.Update(new_img, kBoard);
    EXPECT_TRUE(r && r->status == MC_CAN_VAL_BOOT_STATUS_OK);
    return d.flash.steps;
}

// Cut at every step k that `at` selects (1 .. the update's steps), each
// time before the step happens and half way through it.
void PowerCutAt(const std::vector<uint32_t> &sizes, const std::vector<uint8_t> &old_img,
                const std::vector<uint8_t> &new_img,
                const std::function<bool(uint32_t k, uint32_t steps)> &at)
{
    const uint32_t steps = CountSteps(sizes, old_img, new_img);
    std::set<int> reasons;
    uint32_t n_old = 0u, n_boot = 0u, runs = 0u;
    for (uint32_t k = 1u; k <= steps; ++k) {
        if (!at(k, steps)) {
            continue;
        }
        for (mc_fake_flash_tear_t tear : {MC_FAKE_FLASH_TEAR_NONE, MC_FAKE_FLASH_TEAR_HALF}) {
            Device d{sizes};
            d.Install(old_img);
            SaveConfig(d, kNode);
            const auto cfg = d.CfgContents();
            d.PowerOn();
            const CutResult r = CutAndRecover(d, old_img, new_img, k, tear, cfg);
            runs++;
            // The old image survives only a cut before the first erase took
            // effect; the new one needs the commit word, the last step, so no
            // cut inside the update can start it; everything else is the
            // bootloader with a reason it names.
            if (r.outcome == Outcome::kOld) {
                n_old++;
                EXPECT_TRUE(k == 1u && tear == MC_FAKE_FLASH_TEAR_NONE) << "step " << k;
            } else {
                EXPECT_EQ(Outcome::kBootloader, r.outcome) << "step " << k;
                n_boot++;
                reasons.insert(static_cast<int>(r.reason));
                EXPECT_NE(MC_BOOT_IMG_FLASH, r.reason) << "step " << k;
                EXPECT_NE(MC_BOOT_IMG_OK, r.reason) << "step " << k;
            }
            if (::testing::Test::HasFailure()) {
                return;
            }
        }
    }
    EXPECT_EQ(1u, n_old);
    EXPECT_EQ(runs - 1u, n_boot);
    std::printf("[power-cut] %u steps, %u cuts: old image %u, bootloader %u (reasons", steps, runs,
                n_old, n_boot);
    for (int r : reasons) {
        std::printf(" %d", r);
    }
    std::printf(")\n");
}

TEST(BootPowerCut, EveryEraseAndEveryWordOnASmallDevice)
{
    // slot of 3 x 1 KiB; a 2.5 KiB update over an 1.5 KiB image: every one
    // of its erases and programmed words, each cut before it happens and
    // half way through it
    const auto sizes = SmallSectors();
    const auto old_img = MakeImage(1500u, 0x010000u, 11u);
    const auto new_img = MakeImage(2500u, 0x020000u, 12u);
    EXPECT_EQ(3u + 625u + 1u, CountSteps(sizes, old_img, new_img));
    PowerCutAt(sizes, old_img, new_img, [](uint32_t, uint32_t) { return true; });
}

TEST(BootPowerCut, EveryEraseAndBlockOnTheF405Map)
{
    // the real sector map, a 20 KB image over a 9 KB one: both erases, the
    // first and the last word of every block (the block boundaries), the
    // commit word
    const auto sizes = F405Sectors();
    const auto old_img = MakeImage(9000u, 0x010000u, 1u);
    const auto new_img = MakeImage(20000u, 0x020000u, 2u);
    EXPECT_EQ(2u + 5000u + 1u, CountSteps(sizes, old_img, new_img));
    PowerCutAt(sizes, old_img, new_img, [](uint32_t k, uint32_t steps) {
        const uint32_t w = k - 3u; // word index from the first program
        return k <= 2u || k == steps || (w % 64u) == 0u || (w % 64u) == 63u;
    });
}

} // namespace
