// STM32F405 independent watchdog and reset flags (hal/stm32f405/mc_f405_iwdg.c)
// against register files in RAM. Expected values from RM0090: section 19.4
// (IWDG_KR keys 0xCCCC start, 0x5555 unlock, 0xAAAA reload; PR 0..6 = /4 ..
// /256; RLR 12 bits; SR.PVU/RVU), table 107 (timeouts at 32 kHz: /4 reaches
// 512 ms, /256 32768 ms) and section 7.3.21 (RCC_CSR: RMVF bit 24, BORRSTF
// 25, PINRSTF 26, PORRSTF 27, SFTRSTF 28, IWDGRSTF 29, WWDGRSTF 30, LPWRRSTF
// 31; reset value 0x0E000000 after a power-on). Register values are exact:
// they are bit fields and integers.
#include <gtest/gtest.h>

#include <vector>

#include "mc_f405_iwdg.h"

namespace
{

struct Model {
    mc_f405_iwdg_regs_t regs{};
    uint32_t csr = 0;
    std::vector<uint32_t> kr_seen; // KR as seen at each SR poll
    uint32_t busy_polls = 0;       // polls for which SR stays busy
    bool stuck = false;            // SR never clears
};

void HwPoll(void *ctx)
{
    auto *m = static_cast<Model *>(ctx);
    m->kr_seen.push_back(static_cast<uint32_t>(m->regs.KR));
    if (m->stuck) {
        m->regs.SR = MC_F405_IWDG_SR_PVU | MC_F405_IWDG_SR_RVU;
    } else if (m->busy_polls > 0u) {
        m->busy_polls--;
        m->regs.SR = MC_F405_IWDG_SR_RVU;
    } else {
        m->regs.SR = 0u;
    }
}

mc_f405_iwdg_config_t Cfg(Model &m)
{
    return mc_f405_iwdg_config_t{&m.regs, &m.csr, HwPoll, &m};
}

TEST(F405Iwdg, DividerAgainstRm0090Table107)
{
    struct Row {
        uint32_t ms, pr, rlr;
    };
    // counts = ceil(ms * 32 / (4 * 2^PR)), RLR = counts - 1, smallest PR
    const Row rows[] = {
        {1, 0, 7},        // 8 counts of 0.125 ms
        {100, 0, 799},    // 800 counts of 0.125 ms
        {512, 0, 4095},   // the /4 maximum of table 107
        {513, 1, 2051},   // one ms more needs /8: 2052 counts of 0.25 ms
        {1000, 1, 3999},  // 4000 counts of 0.25 ms
        {2049, 3, 2048},  // /16 ends at 2048 ms: /32, 2049 counts of 1 ms
        {30000, 6, 3749}, // 3750 counts of 8 ms
    };
    for (const Row &r : rows) {
        uint32_t pr = 99, rlr = 99;
        ASSERT_EQ(0, mc_f405_iwdg_divider(r.ms, &pr, &rlr)) << r.ms;
        EXPECT_EQ(r.pr, pr) << r.ms << " ms";
        EXPECT_EQ(r.rlr, rlr) << r.ms << " ms";
    }
    uint32_t pr = 0, rlr = 0;
    EXPECT_EQ(-EINVAL, mc_f405_iwdg_divider(0u, &pr, &rlr));
    EXPECT_EQ(-EINVAL, mc_f405_iwdg_divider(MC_HAL_WDG_TIMEOUT_MAX_MS + 1u, &pr, &rlr));
}

TEST(F405Iwdg, StartWritesKeysPrescalerReloadThenFeeds)
{
    Model m;
    mc_f405_iwdg_t w{};
    const mc_f405_iwdg_config_t c = Cfg(m);
    ASSERT_EQ(0, mc_f405_iwdg_init(&w, &c));
    EXPECT_EQ(-EBUSY, mc_hal_wdg_feed(&w.dev)) << "feed before start";
    m.busy_polls = 3; // the update takes a few LSI periods
    ASSERT_EQ(0, mc_hal_wdg_start(&w.dev, 50u));
    EXPECT_EQ(0u, m.regs.PR);
    EXPECT_EQ(399u, m.regs.RLR); // 50 ms / 0.125 ms = 400 counts
    // at the poll after PR/RLR were written the last key was the unlock
    // key; the last write of all is the reload
    ASSERT_FALSE(m.kr_seen.empty());
    EXPECT_EQ(MC_F405_IWDG_KEY_UNLOCK, m.kr_seen.back());
    EXPECT_EQ(MC_F405_IWDG_KEY_RELOAD, m.regs.KR);
    m.regs.KR = 0u;
    EXPECT_EQ(0, mc_hal_wdg_feed(&w.dev));
    EXPECT_EQ(MC_F405_IWDG_KEY_RELOAD, m.regs.KR);
    EXPECT_EQ(50u, w.timeout_ms);
}

TEST(F405Iwdg, RefusesBadTimeoutAndReportsAStuckUpdate)
{
    Model m;
    mc_f405_iwdg_t w{};
    const mc_f405_iwdg_config_t c = Cfg(m);
    ASSERT_EQ(0, mc_f405_iwdg_init(&w, &c));
    EXPECT_EQ(-EINVAL, mc_hal_wdg_start(&w.dev, 0u));
    EXPECT_EQ(0u, m.regs.KR) << "a refused start writes nothing";
    m.stuck = true;
    EXPECT_EQ(-EIO, mc_hal_wdg_start(&w.dev, 100u));
    EXPECT_EQ(0u, w.timeout_ms);
}

TEST(F405Iwdg, ResetCauseFromRccCsrLatchedAndCleared)
{
    struct Row {
        uint32_t csr, cause;
    };
    const Row rows[] = {
        {0x0E000000u, MC_HAL_WDG_RESET_POWER_ON}, // RM0090 reset value after POR
        {MC_F405_RCC_CSR_BORRSTF | MC_F405_RCC_CSR_PINRSTF, MC_HAL_WDG_RESET_BROWNOUT},
        {MC_F405_RCC_CSR_PINRSTF, MC_HAL_WDG_RESET_PIN},
        {MC_F405_RCC_CSR_IWDGRSTF | MC_F405_RCC_CSR_PINRSTF, MC_HAL_WDG_RESET_WATCHDOG},
        {MC_F405_RCC_CSR_SFTRSTF | MC_F405_RCC_CSR_PINRSTF, MC_HAL_WDG_RESET_SOFTWARE},
        {MC_F405_RCC_CSR_WWDGRSTF | MC_F405_RCC_CSR_PINRSTF, MC_HAL_WDG_RESET_WINDOW},
        {MC_F405_RCC_CSR_LPWRRSTF | MC_F405_RCC_CSR_PINRSTF, MC_HAL_WDG_RESET_LOW_POWER},
        {0u, MC_HAL_WDG_RESET_NONE}, // emulation: RCC not mapped
        // a watchdog reset after a power-on whose flags nobody cleared
        {0x0E000000u | MC_F405_RCC_CSR_IWDGRSTF,
         MC_HAL_WDG_RESET_WATCHDOG | MC_HAL_WDG_RESET_POWER_ON},
    };
    for (const Row &r : rows) {
        Model m;
        m.csr = r.csr | 0x3u; // LSION, LSIRDY: kept as they were
        mc_f405_iwdg_t w{};
        const mc_f405_iwdg_config_t c = Cfg(m);
        ASSERT_EQ(0, mc_f405_iwdg_init(&w, &c));
        uint32_t cause = 0xFFu;
        ASSERT_EQ(0, mc_hal_wdg_reset_cause(&w.dev, &cause));
        EXPECT_EQ(r.cause, cause) << std::hex << r.csr;
        EXPECT_EQ(r.csr | 0x3u, w.csr_at_boot);
        EXPECT_EQ(r.csr | 0x3u | MC_F405_RCC_CSR_RMVF, m.csr) << "RMVF written, other bits kept";
    }
}

} // namespace
