// The A/B configuration store (firmware/app/config/mc_cfg_store.h) on the
// fake flash (hal/fake/mc_fake_flash.h). Configurations are compared bit
// for bit (memcmp): a store either returns exactly what was saved or
// exactly the defaults / the previous record, never a mixture.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <vector>

#include "mc_cfg_store.h"
#include "mc_crc32.h"
#include "mc_fake_flash.h"

namespace
{

constexpr uint32_t kRecBytes = MC_CFG_REC_WORDS * 4u;
constexpr uint32_t kCodeBytes = 256u; // sector 0: stands for the code, never touched

struct Rig {
    std::vector<uint8_t> mem;
    uint32_t sizes[3];
    mc_fake_flash_t flash{};
    mc_cfg_store_t store{};

    explicit Rig(uint32_t sector_bytes) : mem(kCodeBytes + 2u * sector_bytes, 0xFF)
    {
        sizes[0] = kCodeBytes;
        sizes[1] = sector_bytes;
        sizes[2] = sector_bytes;
        for (uint32_t i = 0; i < kCodeBytes; ++i) {
            mem[i] = static_cast<uint8_t>(i * 7u + 1u);
        }
    }
    // Power on: a fresh fake and store over the same memory.
    mc_cfg_boot_t Boot(mc_params_t *p)
    {
        EXPECT_EQ(mc_fake_flash_init(&flash, mem.data(), sizes, 3), 0);
        const mc_cfg_store_cfg_t c = {&flash.dev, {1u, 2u}, 0u};
        EXPECT_EQ(mc_cfg_store_init(&store, &c), 0);
        return mc_cfg_store_load(&store, p);
    }
    uint8_t *Sector(uint32_t i)
    {
        return mem.data() + kCodeBytes + (i - 1u) * sizes[1];
    }
};

bool Same(const mc_params_t &a, const mc_params_t &b)
{
    return std::memcmp(&a, &b, sizeof a) == 0;
}

// A valid configuration that differs from the defaults and from the others.
mc_params_t Variant(uint32_t i)
{
    mc_params_t p = mc_params_default;
    p.i_max_a = 1.0f + static_cast<float>(i % 12u);
    p.r_ohm = 0.1f * static_cast<float>(i + 1u);
    p.pole_pairs = 1u + i % 60u;
    p.can_node_id = i % 62u;
    EXPECT_EQ(mc_params_validate(&p), MC_PARAMS_OK);
    return p;
}

// Hand-made record (for layouts and migrations this firmware never writes).
std::vector<uint32_t> Record(uint32_t layout, uint32_t seq,
                             const std::vector<std::pair<uint32_t, uint32_t>> &entries,
                             uint32_t format = MC_CFG_FORMAT)
{
    std::vector<uint32_t> w = {MC_CFG_MAGIC, format | (layout << 16), seq,
                               static_cast<uint32_t>(entries.size()) | 0xFFFF0000u};
    for (const auto &e : entries) {
        w.push_back(e.first);
        w.push_back(e.second);
    }
    w.push_back(mc_crc32(w.data(), w.size() * 4u));
    return w;
}

std::vector<std::pair<uint32_t, uint32_t>> Entries(const mc_params_t &p)
{
    std::vector<std::pair<uint32_t, uint32_t>> e;
    for (uint32_t i = 0; i < MC_PARAM_COUNT; ++i) {
        if (mc_param_table[i].offset != MC_PARAM_NO_FIELD) {
            e.emplace_back(mc_param_table[i].id, mc_param_get_raw(&p, &mc_param_table[i]));
        }
    }
    return e;
}

TEST(Crc32, CheckValue)
{
    // The catalogued check value of CRC-32/ISO-HDLC (zlib's crc32).
    EXPECT_EQ(mc_crc32("123456789", 9), 0xCBF43926u);
    EXPECT_EQ(mc_crc32("", 0), 0x00000000u);
}

TEST(CfgStore, EmptyBootsWithDefaultsThenRoundTrip)
{
    Rig r(4096);
    mc_params_t p{};
    EXPECT_EQ(r.Boot(&p), MC_CFG_BOOT_EMPTY);
    EXPECT_TRUE(Same(p, mc_params_default));
    const mc_params_t v = Variant(3);
    ASSERT_EQ(mc_cfg_store_save(&r.store, &v), 0);
    EXPECT_EQ(r.flash.erases, 0u) << "an erased sector is used without erasing it again";
    EXPECT_EQ(r.Boot(&p), MC_CFG_BOOT_STORED);
    EXPECT_TRUE(Same(p, v));
    EXPECT_EQ(r.store.seq, 1u);
}

TEST(CfgStore, NewestWinsAndCodeSectorUntouched)
{
    Rig r(kRecBytes * 3u + 64u); // three records per sector: appends and switches
    const std::vector<uint8_t> code(r.mem.begin(), r.mem.begin() + kCodeBytes);
    mc_params_t p{};
    r.Boot(&p);
    for (uint32_t i = 0; i < 20; ++i) {
        const mc_params_t v = Variant(i);
        ASSERT_EQ(mc_cfg_store_save(&r.store, &v), 0) << i;
        ASSERT_EQ(r.Boot(&p), MC_CFG_BOOT_STORED) << i;
        ASSERT_TRUE(Same(p, v)) << i;
        EXPECT_EQ(r.store.seq, i + 1u);
    }
    EXPECT_TRUE(std::equal(code.begin(), code.end(), r.mem.begin()));
}

TEST(CfgStore, CorruptNewestFallsBackToPrevious)
{
    Rig r(kRecBytes * 3u + 64u);
    mc_params_t p{};
    r.Boot(&p);
    const mc_params_t a = Variant(1), b = Variant(2);
    ASSERT_EQ(mc_cfg_store_save(&r.store, &a), 0);
    ASSERT_EQ(mc_cfg_store_save(&r.store, &b), 0);
    r.Sector(1)[kRecBytes + 40] ^= 0x04; // one bit of the second record's payload
    EXPECT_EQ(r.Boot(&p), MC_CFG_BOOT_STORED);
    EXPECT_TRUE(Same(p, a));
    // the next save does not append behind the damaged record: it starts B
    const mc_params_t c = Variant(3);
    ASSERT_EQ(mc_cfg_store_save(&r.store, &c), 0);
    EXPECT_EQ(r.store.active, 1);
    EXPECT_EQ(r.Boot(&p), MC_CFG_BOOT_STORED);
    EXPECT_TRUE(Same(p, c));
}

TEST(CfgStore, GarbageIsCorruptAndRecoverable)
{
    Rig r(4096);
    std::memset(r.Sector(1), 0x5A, 64);
    mc_params_t p{};
    EXPECT_EQ(r.Boot(&p), MC_CFG_BOOT_CORRUPT);
    EXPECT_TRUE(Same(p, mc_params_default));
    const mc_params_t v = Variant(5);
    ASSERT_EQ(mc_cfg_store_save(&r.store, &v), 0);
    EXPECT_EQ(r.Boot(&p), MC_CFG_BOOT_STORED);
    EXPECT_TRUE(Same(p, v));
}

TEST(CfgStore, OtherLayoutOrFormatRefusedWithDefaults)
{
    for (const auto &rec : {Record(MC_PARAMS_LAYOUT_VERSION + 1u, 7, Entries(Variant(1))),
                            Record(MC_PARAMS_LAYOUT_VERSION - 1u, 7, Entries(Variant(1))),
                            Record(MC_PARAMS_LAYOUT_VERSION, 7, Entries(Variant(1)), 2u)}) {
        Rig r(4096);
        std::memcpy(r.Sector(1), rec.data(), rec.size() * 4u);
        mc_params_t p{};
        EXPECT_EQ(r.Boot(&p), MC_CFG_BOOT_LAYOUT);
        EXPECT_TRUE(Same(p, mc_params_default));
        // a save supersedes the refused record (larger sequence number)
        const mc_params_t v = Variant(2);
        ASSERT_EQ(mc_cfg_store_save(&r.store, &v), 0);
        EXPECT_EQ(r.store.seq, 8u);
        EXPECT_EQ(r.Boot(&p), MC_CFG_BOOT_STORED);
        EXPECT_TRUE(Same(p, v));
    }
}

TEST(CfgStore, MissingAndUnknownIdsMigrate)
{
    Rig r(4096);
    const float r_ohm = 0.25f, i_max = 7.0f;
    uint32_t rb, ib;
    std::memcpy(&rb, &r_ohm, 4);
    std::memcpy(&ib, &i_max, 4);
    // a record of a table that lacked every other parameter and had id 9999
    const auto rec = Record(MC_PARAMS_LAYOUT_VERSION, 3,
                            {{MC_PARAM_ID_R_OHM, rb}, {9999u, 42u}, {MC_PARAM_ID_I_MAX_A, ib}});
    std::memcpy(r.Sector(2), rec.data(), rec.size() * 4u);
    mc_params_t p{};
    EXPECT_EQ(r.Boot(&p), MC_CFG_BOOT_MIGRATED);
    mc_params_t want = mc_params_default;
    want.r_ohm = r_ohm;
    want.i_max_a = i_max;
    EXPECT_TRUE(Same(p, want));
    EXPECT_EQ(r.store.boot_dropped, 1u);
    EXPECT_EQ(r.store.boot_missing, MC_PARAM_STORED_COUNT - 2u);
}

TEST(CfgStore, InvalidRecordRefusedWithDefaults)
{
    Rig r(4096);
    mc_params_t bad = mc_params_default;
    bad.i_sense_max_a = 5.0f; // each value in range, the whole refused (sensor
    bad.i_trip_a = 6.0f;      // scale below the trip)
    ASSERT_NE(mc_params_validate(&bad), MC_PARAMS_OK);
    const auto rec = Record(MC_PARAMS_LAYOUT_VERSION, 1, Entries(bad));
    std::memcpy(r.Sector(1), rec.data(), rec.size() * 4u);
    mc_params_t p{};
    EXPECT_EQ(r.Boot(&p), MC_CFG_BOOT_INVALID);
    EXPECT_TRUE(Same(p, mc_params_default));
    // and the store itself refuses to write it
    const uint32_t steps = r.flash.steps;
    EXPECT_EQ(mc_cfg_store_save(&r.store, &bad), -EINVAL);
    EXPECT_EQ(r.flash.steps, steps);
}

TEST(CfgStore, FlashErrorKeepsPrevious)
{
    Rig r(kRecBytes + 16u); // one record per sector: every save erases
    mc_params_t p{};
    r.Boot(&p);
    const mc_params_t a = Variant(1), b = Variant(2);
    ASSERT_EQ(mc_cfg_store_save(&r.store, &a), 0);
    r.flash.fail_next = -EIO; // the erase of B fails
    EXPECT_EQ(mc_cfg_store_save(&r.store, &b), -EIO);
    EXPECT_EQ(r.Boot(&p), MC_CFG_BOOT_STORED);
    EXPECT_TRUE(Same(p, a));
}

// The save cut at every step k of its n (not done, half done), each time
// from the flash image before: the cut save must fail with -EIO;
// after_cut(k, tear) checks the reboot, the same save then completes, and
// after_redo(k) checks that.
template <typename Save, typename AfterCut, typename AfterRedo>
void CutAtEveryStep(Rig &r, mc_params_t *p, const std::vector<uint8_t> &before, uint32_t n,
                    Save save, AfterCut after_cut, AfterRedo after_redo)
{
    for (uint32_t k = 1; k <= n; ++k) {
        for (const mc_fake_flash_tear_t tear : {MC_FAKE_FLASH_TEAR_NONE, MC_FAKE_FLASH_TEAR_HALF}) {
            r.mem = before;
            r.Boot(p);
            mc_fake_flash_cut_at(&r.flash, k, tear);
            ASSERT_EQ(save(), -EIO) << "step " << k << " tear " << tear;
            after_cut(k, tear);
            ASSERT_EQ(save(), 0) << "step " << k << " tear " << tear;
            after_redo(k);
        }
    }
}

// The power-cut guarantee: for every save of a sequence, cut the power at
// every erase and every word-program step (the step not done, and the step
// half done), reboot, and require exactly the previous configuration; the
// store must then save and load normally. A cut after the last step (no
// cut) must give the new one.
// first_seq != 0: the store starts with one record of that sequence number
// (written by hand), and every save's number is checked.
void PowerCutSweep(uint32_t sector_bytes, uint32_t saves, uint32_t *p_cases, uint32_t *p_erase_cuts,
                   uint32_t first_seq = 0u)
{
    Rig r(sector_bytes);
    mc_params_t p{};
    mc_params_t old = mc_params_default;
    if (first_seq != 0u) {
        old = Variant(100);
        const auto rec = Record(MC_PARAMS_LAYOUT_VERSION, first_seq, Entries(old));
        std::memcpy(r.Sector(1), rec.data(), rec.size() * 4u);
    }
    r.Boot(&p);
    ASSERT_TRUE(Same(p, old));
    uint32_t seq = first_seq;
    for (uint32_t i = 0; i < saves; ++i) {
        const mc_params_t next = Variant(i);
        const std::vector<uint8_t> before = r.mem;
        // steps of an uncut save from this state
        r.Boot(&p);
        const uint32_t s0 = r.flash.steps, e0 = r.flash.erases;
        ASSERT_EQ(mc_cfg_store_save(&r.store, &next), 0);
        const uint32_t n = r.flash.steps - s0;
        const bool erased = r.flash.erases > e0;
        ASSERT_GE(n, MC_CFG_REC_WORDS);
        const std::vector<uint8_t> after = r.mem;
        CutAtEveryStep(
            r, &p, before, n, [&]() { return mc_cfg_store_save(&r.store, &next); },
            [&](uint32_t k, mc_fake_flash_tear_t tear) {
                const mc_cfg_boot_t st = r.Boot(&p);
                ASSERT_TRUE(Same(p, old)) << "save " << i << " cut at step " << k << " of " << n
                                          << " tear " << tear << " boot " << st;
                if (i > 0) {
                    ASSERT_EQ(st, MC_CFG_BOOT_STORED);
                }
                ++*p_cases;
                if (erased && k == 1) {
                    ++*p_erase_cuts;
                }
            },
            [&](uint32_t k) {
                // the store recovers: the same save completed
                ASSERT_EQ(r.Boot(&p), MC_CFG_BOOT_STORED) << "save " << i << " step " << k;
                ASSERT_TRUE(Same(p, next));
            });
        ASSERT_FALSE(::testing::Test::HasFatalFailure());
        r.mem = after;
        ASSERT_EQ(r.Boot(&p), MC_CFG_BOOT_STORED);
        ASSERT_TRUE(Same(p, next)) << "save " << i;
        seq = (seq == 0xFFFFFFFFu) ? 1u : seq + 1u; // 0 means "none": skipped
        ASSERT_EQ(r.store.seq, seq) << "save " << i;
        old = next;
    }
}

TEST(CfgStore, PowerCutAtEveryStepOneRecordPerSector)
{
    uint32_t cases = 0, erase_cuts = 0;
    PowerCutSweep(kRecBytes + 16u, 5, &cases, &erase_cuts);
    // 5 saves x (1 erase + MC_CFG_REC_WORDS words), except the first save
    // (sector A starts erased: no erase) x 2 tear modes
    EXPECT_EQ(cases, 2u * (5u * MC_CFG_REC_WORDS + 4u));
    EXPECT_EQ(erase_cuts, 2u * 4u);
}

TEST(CfgStore, PowerCutAtEveryStepAppendAndSwitch)
{
    uint32_t cases = 0, erase_cuts = 0;
    PowerCutSweep(kRecBytes * 2u + 32u, 7, &cases, &erase_cuts);
    // 2 records per sector: saves 3, 5, 7 start a sector (erase)
    EXPECT_EQ(cases, 2u * (7u * MC_CFG_REC_WORDS + 3u));
    EXPECT_EQ(erase_cuts, 2u * 3u);
}

// The sequence number's wrap (issue 28: at 0xFFFFFFFF the next save wrote
// 0, was answered OK, and the next boot took the old record). From
// 0xFFFFFFFE on, through 0xFFFFFFFF, 1, 2, ...: every save boots as the
// newest, with a power cut at every step of every save leaving the old
// set, in both sector layouts (appends, and a switch at every save).
TEST(CfgStore, SequenceNumberWrapsAndTheNewestStillWins)
{
    uint32_t cases = 0, erase_cuts = 0;
    PowerCutSweep(kRecBytes * 2u + 32u, 5, &cases, &erase_cuts, 0xFFFFFFFEu);
    // the hand-made record fills half of A: saves 2 and 4 start a sector
    EXPECT_EQ(cases, 2u * (5u * MC_CFG_REC_WORDS + 2u));
    EXPECT_EQ(erase_cuts, 2u * 2u);
    cases = erase_cuts = 0;
    PowerCutSweep(kRecBytes + 16u, 4, &cases, &erase_cuts, 0xFFFFFFFEu);
    EXPECT_EQ(erase_cuts, 2u * 4u) << "every save erases";
    // the comparison itself: serial-number arithmetic
    EXPECT_TRUE(mc_cfg_store_seq_newer(1u, 0xFFFFFFFFu));
    EXPECT_TRUE(mc_cfg_store_seq_newer(0xFFFFFFFFu, 0xFFFFFFFEu));
    EXPECT_FALSE(mc_cfg_store_seq_newer(0xFFFFFFFFu, 1u));
    EXPECT_EQ(1u, mc_cfg_store_seq_next(0xFFFFFFFFu));
    EXPECT_EQ(0xFFFFFFFFu, mc_cfg_store_seq_next(0xFFFFFFFEu));
}

// mc_cfg_store_holds: the newest record is exactly what a save would write
// (the parameter service skips such a SAVE); a changed value, an older
// record, or no record at all is not.
TEST(CfgStore, HoldsTellsAnUnchangedSet)
{
    Rig r(kRecBytes * 3u + 64u);
    mc_params_t p{};
    r.Boot(&p);
    const mc_params_t a = Variant(1), b = Variant(2);
    EXPECT_FALSE(mc_cfg_store_holds(&r.store, &a)) << "empty store";
    ASSERT_EQ(mc_cfg_store_save(&r.store, &a), 0);
    EXPECT_TRUE(mc_cfg_store_holds(&r.store, &a));
    EXPECT_FALSE(mc_cfg_store_holds(&r.store, &b));
    mc_params_t a1 = a;
    a1.i_max_a = std::nextafter(a.i_max_a, 100.0f); // one ulp
    EXPECT_FALSE(mc_cfg_store_holds(&r.store, &a1));
    ASSERT_EQ(mc_cfg_store_save(&r.store, &b), 0);
    EXPECT_FALSE(mc_cfg_store_holds(&r.store, &a)) << "a is only in the older record";
    r.Boot(&p);
    EXPECT_TRUE(mc_cfg_store_holds(&r.store, &b)) << "after a reboot too";
    // a record of another layout holding the same values is not ours
    Rig r2(4096);
    const auto rec = Record(MC_PARAMS_LAYOUT_VERSION + 1u, 3, Entries(a));
    std::memcpy(r2.Sector(1), rec.data(), rec.size() * 4u);
    r2.Boot(&p);
    EXPECT_FALSE(mc_cfg_store_holds(&r2.store, &a));
}

} // namespace

// ------------------------------------------------- the anticogging map kind

namespace
{

constexpr uint32_t kMapBytes = 2088u; // sizeof(mc_cog_map_t): the store takes any multiple of 8
constexpr uint32_t kMapRecBytes = kMapBytes + 5u * 4u;

std::vector<uint8_t> MapBlob(uint32_t i)
{
    std::vector<uint8_t> m(kMapBytes);
    for (uint32_t k = 0; k < kMapBytes; ++k) {
        m[k] = static_cast<uint8_t>(k * 13u + i * 101u + 7u);
    }
    return m;
}

// The stored map is exactly want (empty: none stored).
void ExpectMap(Rig &r, const std::vector<uint8_t> &want, const char *what)
{
    std::vector<uint8_t> got(kMapBytes, 0u);
    const int rc = mc_cfg_store_load_map(&r.store, got.data(), kMapBytes);
    if (want.empty()) {
        EXPECT_EQ(rc, -ENOENT) << what;
    } else {
        ASSERT_EQ(rc, 0) << what;
        EXPECT_EQ(got, want) << what;
    }
}

// Configuration (C) and map (M) saves in the order ops, the power cut at
// every step of each (not done, half done): after the reboot each kind is
// exactly its previous newest (bit for bit; a map never saved: none),
// and the save then completes. Returns the cases and the switches (saves
// that erased).
void MixedPowerCutSweep(uint32_t sector_bytes, const char *ops, uint32_t *p_cases,
                        uint32_t *p_switches)
{
    Rig r(sector_bytes);
    mc_params_t p{};
    mc_params_t old_cfg = mc_params_default;
    std::vector<uint8_t> old_map;
    r.Boot(&p);
    for (uint32_t i = 0; ops[i] != '\0'; ++i) {
        const bool map = ops[i] == 'M';
        const mc_params_t next_cfg = Variant(i);
        const std::vector<uint8_t> next_map = MapBlob(i);
        const auto save = [&]() {
            return map ? mc_cfg_store_save_map(&r.store, next_map.data(), kMapBytes)
                       : mc_cfg_store_save(&r.store, &next_cfg);
        };
        const std::vector<uint8_t> before = r.mem;
        r.Boot(&p);
        const uint32_t s0 = r.flash.steps, e0 = r.flash.erases;
        ASSERT_EQ(save(), 0) << "op " << i;
        const uint32_t n = r.flash.steps - s0;
        *p_switches += (r.flash.erases > e0) ? 1u : 0u;
        const std::vector<uint8_t> after = r.mem;
        CutAtEveryStep(
            r, &p, before, n, save,
            [&](uint32_t k, mc_fake_flash_tear_t /*tear*/) {
                r.Boot(&p);
                ASSERT_TRUE(Same(p, old_cfg)) << "op " << i << " cut at " << k << " of " << n;
                ExpectMap(r, old_map, "after the cut");
                ++*p_cases;
            },
            [&](uint32_t /*k*/) {
                r.Boot(&p);
                ASSERT_TRUE(Same(p, map ? old_cfg : next_cfg));
                ExpectMap(r, map ? next_map : old_map, "after the recovery");
            });
        ASSERT_FALSE(::testing::Test::HasFatalFailure());
        r.mem = after;
        r.Boot(&p);
        if (map) {
            old_map = next_map;
        } else {
            old_cfg = next_cfg;
        }
        ASSERT_TRUE(Same(p, old_cfg)) << "op " << i;
        ExpectMap(r, old_map, "after the save");
    }
}

} // namespace

// One configuration record and one map per sector: every save switches
// and copies the other kind's newest record first. The cases: every step
// of every save, both tear modes.
TEST(CfgStoreMap, PowerCutAtEveryStepOfMixedSavesEachKindKeepsOldOrNew)
{
    uint32_t cases = 0, switches = 0;
    MixedPowerCutSweep(kRecBytes + kMapRecBytes + 16u, "CMCCMMC", &cases, &switches);
    // the first two fill sector A (a configuration, then the map behind
    // it); each later save switches
    EXPECT_EQ(switches, 5u);
    // every save writes its record; each switch also copies the other kind
    EXPECT_GT(cases, 2u * (4u * MC_CFG_REC_WORDS + 3u * (kMapRecBytes / 4u)));
}

// Two of each per sector: appends, switches with a copy.
TEST(CfgStoreMap, PowerCutAtEveryStepAppendAndSwitch)
{
    uint32_t cases = 0, switches = 0;
    MixedPowerCutSweep(2u * (kRecBytes + kMapRecBytes) + 32u, "MCMCCMMCCM", &cases, &switches);
    EXPECT_GE(switches, 2u);
    EXPECT_GT(cases, 2u * (5u * MC_CFG_REC_WORDS + 5u * (kMapRecBytes / 4u)));
}

// A map record of another size (another layout) is refused -EBADMSG and
// the buffer not changed; a map saved does not disturb the configuration
// (the configuration's sequence number stays, the counter moves on); a
// sector that cannot hold both is refused -ENOSPC with nothing written.
TEST(CfgStoreMap, OtherSizeRefusedAndTheConfigurationUntouched)
{
    Rig r(kRecBytes + kMapRecBytes + 16u);
    mc_params_t p{};
    r.Boot(&p);
    const mc_params_t c = Variant(3);
    ASSERT_EQ(mc_cfg_store_save(&r.store, &c), 0);
    const std::vector<uint8_t> m = MapBlob(1);
    ASSERT_EQ(mc_cfg_store_save_map(&r.store, m.data(), kMapBytes), 0);
    EXPECT_EQ(r.Boot(&p), MC_CFG_BOOT_STORED);
    EXPECT_TRUE(Same(p, c));
    EXPECT_EQ(r.store.seq, 1u);
    EXPECT_EQ(r.store.seq_top, 2u);
    std::vector<uint8_t> small(kMapBytes - 8u, 0xA5u);
    const std::vector<uint8_t> small0 = small;
    EXPECT_EQ(mc_cfg_store_load_map(&r.store, small.data(), kMapBytes - 8u), -EBADMSG);
    EXPECT_EQ(small, small0);
    EXPECT_EQ(mc_cfg_store_save_map(&r.store, m.data(), kMapBytes - 4u), -EINVAL);
    EXPECT_EQ(mc_cfg_store_save_map(&r.store, nullptr, kMapBytes), -EINVAL);

    Rig tiny(kRecBytes + 16u);
    tiny.Boot(&p);
    ASSERT_EQ(mc_cfg_store_save(&tiny.store, &c), 0);
    const std::vector<uint8_t> before = tiny.mem;
    EXPECT_EQ(mc_cfg_store_save_map(&tiny.store, m.data(), kMapBytes), -ENOSPC);
    EXPECT_EQ(tiny.mem, before);
}

// A record of a kind this image does not know (a later image's: another
// magic in the same envelope, valid length and CRC) is skipped by its
// length: the configuration written after it boots, and the next save
// appends behind it. The same bytes with a wrong CRC are a cut record (the
// rest of the sector unusable): the configuration before it boots.
TEST(CfgStore, UnknownRecordKindIsSkipped)
{
    Rig r(4096);
    const mc_params_t v1 = Variant(1);
    const mc_params_t v2 = Variant(2);
    std::vector<uint32_t> unknown = {
        0x584D434Du /* "MCMX" */, 1u, 5u, 3u | 0xFFFF0000u, 11u, 12u, 21u, 22u, 31u, 32u};
    unknown.push_back(mc_crc32(unknown.data(), unknown.size() * 4u));
    const std::vector<uint32_t> rec1 = Record(MC_PARAMS_LAYOUT_VERSION, 4u, Entries(v1));
    const std::vector<uint32_t> rec2 = Record(MC_PARAMS_LAYOUT_VERSION, 6u, Entries(v2));
    std::vector<uint32_t> sector = rec1;
    sector.insert(sector.end(), unknown.begin(), unknown.end());
    sector.insert(sector.end(), rec2.begin(), rec2.end());
    std::memcpy(r.Sector(1), sector.data(), sector.size() * 4u);

    mc_params_t p{};
    ASSERT_EQ(r.Boot(&p), MC_CFG_BOOT_STORED);
    EXPECT_TRUE(Same(p, v2)) << "the configuration behind the unknown record";
    EXPECT_EQ(r.store.seq, 6u);
    const mc_params_t v3 = Variant(3);
    ASSERT_EQ(mc_cfg_store_save(&r.store, &v3), 0);
    EXPECT_EQ(r.flash.erases, 0u) << "appended behind the records, no sector switch";
    ASSERT_EQ(r.Boot(&p), MC_CFG_BOOT_STORED);
    EXPECT_TRUE(Same(p, v3));
    EXPECT_EQ(0, std::memcmp(r.Sector(1) + rec1.size() * 4u, unknown.data(), unknown.size() * 4u))
        << "the unknown record is left as it was";

    // its CRC broken: a cut record, the sector ends there (v1 boots)
    Rig c(4096);
    std::vector<uint32_t> cut = sector;
    cut[rec1.size() + unknown.size() - 1u] ^= 1u;
    std::memcpy(c.Sector(1), cut.data(), cut.size() * 4u);
    ASSERT_EQ(c.Boot(&p), MC_CFG_BOOT_STORED);
    EXPECT_TRUE(Same(p, v1));
}

// ---- Two axes on the one store (mc_cfg_store.h, "Axes") ----------------------

namespace
{

// A small map: the store takes any multiple of 8 bytes, and the sweeps cut
// at every word of every record (a 2 KB map makes them minutes long).
constexpr uint32_t kAxMapBytes = 64u;
constexpr uint32_t kAxMapRecBytes = kAxMapBytes + 5u * 4u;

std::vector<uint8_t> AxMap(uint32_t i)
{
    std::vector<uint8_t> m(kAxMapBytes);
    for (uint32_t k = 0; k < kAxMapBytes; ++k) {
        m[k] = static_cast<uint8_t>(k * 13u + i * 101u + 7u);
    }
    return m;
}

// Both axes' stores over the same flash, as a two-axis image has them.
struct Rig2 {
    Rig r;
    mc_cfg_store_t s1{};

    explicit Rig2(uint32_t sector_bytes) : r(sector_bytes)
    {
    }
    // Power on: a fresh fake and both stores over the same memory.
    void Boot(mc_params_t p[2], mc_cfg_boot_t st[2])
    {
        st[0] = r.Boot(&p[0]);
        const mc_cfg_store_cfg_t c = {&r.flash.dev, {1u, 2u}, 1u};
        EXPECT_EQ(mc_cfg_store_init(&s1, &c), 0);
        st[1] = mc_cfg_store_load(&s1, &p[1]);
    }
    mc_cfg_store_t *Store(uint32_t axis)
    {
        return (axis == 0u) ? &r.store : &s1;
    }
};

std::vector<uint8_t> LoadMap(mc_cfg_store_t *s)
{
    std::vector<uint8_t> got(kAxMapBytes, 0u);
    return (mc_cfg_store_load_map(s, got.data(), kAxMapBytes) == 0) ? got : std::vector<uint8_t>{};
}

// What the flash must hold for both axes: each kind's newest.
struct Held {
    mc_params_t cfg[2] = {mc_params_default, mc_params_default};
    std::vector<uint8_t> map[2];
};

void ExpectHeld(Rig2 &r, const Held &h, const std::string &what)
{
    mc_params_t p[2];
    mc_cfg_boot_t st[2];
    r.Boot(p, st);
    for (uint32_t a = 0; a < 2u; ++a) {
        ASSERT_TRUE(Same(p[a], h.cfg[a])) << what << ": axis " << a << " boot " << st[a];
        ASSERT_EQ(LoadMap(r.Store(a)), h.map[a]) << what << ": axis " << a << "'s map";
    }
}

// ops: pairs "<axis><C|M>", e.g. "0C1M". Every save cut at every step (not
// done, half done): after the reboot every kind of both axes is exactly its
// previous newest; the save then completes and only its kind changed.
void TwoAxisPowerCutSweep(uint32_t sector_bytes, const char *ops, uint32_t *p_cases,
                          uint32_t *p_switches)
{
    Rig2 r(sector_bytes);
    Held held;
    mc_params_t p[2];
    mc_cfg_boot_t st[2];
    r.Boot(p, st);
    for (uint32_t i = 0; ops[2u * i] != '\0'; ++i) {
        const uint32_t axis = (ops[2u * i] == '1') ? 1u : 0u;
        const bool map = ops[2u * i + 1u] == 'M';
        Held next = held;
        if (map) {
            next.map[axis] = AxMap(10u * i + axis);
        } else {
            next.cfg[axis] = Variant(10u * i + axis);
        }
        const auto save = [&]() {
            return map ? mc_cfg_store_save_map(r.Store(axis), next.map[axis].data(), kAxMapBytes)
                       : mc_cfg_store_save(r.Store(axis), &next.cfg[axis]);
        };
        const std::vector<uint8_t> before = r.r.mem;
        r.Boot(p, st);
        const uint32_t s0 = r.r.flash.steps, e0 = r.r.flash.erases;
        ASSERT_EQ(save(), 0) << "op " << i;
        const uint32_t n = r.r.flash.steps - s0;
        *p_switches += (r.r.flash.erases > e0) ? 1u : 0u;
        const std::vector<uint8_t> after = r.r.mem;
        for (uint32_t k = 1; k <= n; ++k) {
            for (const mc_fake_flash_tear_t tear :
                 {MC_FAKE_FLASH_TEAR_NONE, MC_FAKE_FLASH_TEAR_HALF}) {
                const std::string what = "op " + std::to_string(i) + " cut at " +
                                         std::to_string(k) + " of " + std::to_string(n) + " tear " +
                                         std::to_string(tear);
                r.r.mem = before;
                r.Boot(p, st);
                mc_fake_flash_cut_at(&r.r.flash, k, tear);
                ASSERT_EQ(save(), -EIO) << what;
                ExpectHeld(r, held, what);
                ASSERT_EQ(save(), 0) << what;
                ExpectHeld(r, next, what + ", redone");
                ++*p_cases;
            }
        }
        r.r.mem = after;
        ExpectHeld(r, next, "op " + std::to_string(i));
        held = next;
    }
}

} // namespace

// One record of each of the four kinds per sector: from the fifth save on
// every save switches and copies the three other kinds' newest first.
TEST(CfgStoreAxes, PowerCutAtEveryStepEachKindOfBothAxesKeepsOldOrNew)
{
    uint32_t cases = 0, switches = 0;
    TwoAxisPowerCutSweep(2u * (kRecBytes + kAxMapRecBytes) + 16u, "0C1C0M1M1C0C1M0M1C", &cases,
                         &switches);
    EXPECT_EQ(switches, 5u); // the first four fill sector A
    // every save writes its record; each switch also copies three records
    EXPECT_GT(cases, 2u * (5u * MC_CFG_REC_WORDS + 4u * (kAxMapRecBytes / 4u)));
}

// Two of each per sector: appends, and switches with copies.
TEST(CfgStoreAxes, PowerCutAtEveryStepAppendAndSwitch)
{
    uint32_t cases = 0, switches = 0;
    TwoAxisPowerCutSweep(4u * (kRecBytes + kAxMapRecBytes) + 32u, "1C0C1M0M1C1C0C1M0M0C1C0C",
                         &cases, &switches);
    EXPECT_GE(switches, 2u);
    EXPECT_GT(cases, 2u * (10u * MC_CFG_REC_WORDS));
}

// The two stores run side by side without a reboot between them, as on the
// board: one's sector switch erases the sector the other last saw its
// records in, and the other's next save and SAVE check (holds) still see
// the flash as it is. A one-axis image's store is axis 0's; axis 1 then
// boots EMPTY (nothing of its own stored), not CORRUPT; axis 2 is refused.
TEST(CfgStoreAxes, EachAxisSeesTheOthersSavesWithoutARebootAndBootsItsOwn)
{
    Rig2 r(kRecBytes * 2u + kAxMapRecBytes + 32u);
    mc_params_t p[2];
    mc_cfg_boot_t st[2];
    r.Boot(p, st);
    EXPECT_EQ(st[0], MC_CFG_BOOT_EMPTY);
    EXPECT_EQ(st[1], MC_CFG_BOOT_EMPTY);
    // A one-axis image saved (axis 0's record only).
    const mc_params_t a0 = Variant(1);
    ASSERT_EQ(mc_cfg_store_save(r.Store(0), &a0), 0);
    r.Boot(p, st);
    EXPECT_EQ(st[0], MC_CFG_BOOT_STORED);
    EXPECT_TRUE(Same(p[0], a0));
    EXPECT_EQ(st[1], MC_CFG_BOOT_EMPTY);
    EXPECT_TRUE(Same(p[1], mc_params_default));
    // Both live: axis 1 saves until it has switched sectors twice, then axis
    // 0 (its view from before) saves and checks.
    const uint32_t e0 = r.r.flash.erases;
    mc_params_t a1 = Variant(2);
    for (uint32_t i = 0; i < 9u; ++i) {
        a1 = Variant(20u + i);
        ASSERT_EQ(mc_cfg_store_save(r.Store(1), &a1), 0) << i;
    }
    ASSERT_GE(r.r.flash.erases - e0, 2u);
    // axis 0 saves with the view it had before axis 1's switches
    const mc_params_t a0b = Variant(3);
    ASSERT_EQ(mc_cfg_store_save(r.Store(0), &a0b), 0);
    EXPECT_TRUE(mc_cfg_store_holds(r.Store(0), &a0b));
    EXPECT_FALSE(mc_cfg_store_holds(r.Store(0), &a0));
    const std::vector<uint8_t> m1 = AxMap(7);
    ASSERT_EQ(mc_cfg_store_save_map(r.Store(1), m1.data(), kAxMapBytes), 0);
    r.Boot(p, st);
    EXPECT_EQ(st[0], MC_CFG_BOOT_STORED);
    EXPECT_EQ(st[1], MC_CFG_BOOT_STORED);
    EXPECT_TRUE(Same(p[0], a0b));
    EXPECT_TRUE(Same(p[1], a1));
    EXPECT_EQ(LoadMap(r.Store(0)), std::vector<uint8_t>{}) << "no map of axis 0";
    EXPECT_EQ(LoadMap(r.Store(1)), m1);
    // The sequence counter is shared: axis 0's last save took the number
    // after axis 1's saves.
    EXPECT_EQ(r.Store(0)->seq, 11u); // 1, then axis 1's 2..10, then 11
    EXPECT_EQ(r.Store(1)->seq, 10u);
    EXPECT_EQ(r.Store(1)->seq_top, 12u); // its map
    mc_cfg_store_t bad{};
    const mc_cfg_store_cfg_t c2 = {&r.r.flash.dev, {1u, 2u}, 2u};
    EXPECT_EQ(mc_cfg_store_init(&bad, &c2), -EINVAL);
}
