// STM32F405 clock set-up (firmware/targets/stm32f405/mc_clock.c) against a
// register file in RAM. The "hardware" is the initial register contents:
// a ready flag preset to 1 stands for a clock that starts, one left at 0 for
// one that never does. Expected register values are computed here from
// RM0090's field positions, independently of the driver's macros.
#include <gtest/gtest.h>

#include <cstdint>

extern "C" {
#include "mc_clock.h"
}

namespace {

struct Regs {
  volatile uint32_t cr = 0, pllcfgr = 0, cfgr = 0, apb1enr = 0, acr = 0, pwr = 0;
  mc_clock_regs_t map() { return mc_clock_regs_t{&cr, &pllcfgr, &cfgr, &apb1enr, &acr, &pwr}; }
};

constexpr uint32_t kHsiOnRdy = (1u << 0) | (1u << 1);
constexpr uint32_t kHseRdy = 1u << 17;
constexpr uint32_t kPllRdy = 1u << 25;
constexpr uint32_t kPllcfgrReset = 0x24003010u;  // RM0090 7.3.2
constexpr uint32_t kSwsPll = 2u << 2;
constexpr uint32_t kLoops = 100u;  // small: the fake's flags never change

TEST(TargetClock, EmulatorWithoutRccIsDetectedAndLeftAlone) {
  Regs r;  // QEMU: every RCC register reads 0
  mc_clock_regs_t m = r.map();
  uint32_t hz = 123u;
  EXPECT_EQ(mc_clock_init_168mhz(&m, kLoops, &hz), MC_CLOCK_NO_RCC);
  EXPECT_EQ(hz, 0u);
  EXPECT_EQ(r.cr, 0u);
  EXPECT_EQ(r.pllcfgr, 0u);
  EXPECT_EQ(r.cfgr, 0u);
  EXPECT_EQ(r.acr, 0u);
  EXPECT_EQ(r.apb1enr, 0u);
  EXPECT_EQ(r.pwr, 0u);
}

TEST(TargetClock, HseAndPllGive168MHzWithBusDividersAndWaitStates) {
  Regs r;
  r.cr = kHsiOnRdy | kHseRdy | kPllRdy;
  r.pllcfgr = kPllcfgrReset;
  r.cfgr = kSwsPll;
  mc_clock_regs_t m = r.map();
  uint32_t hz = 0u;
  ASSERT_EQ(mc_clock_init_168mhz(&m, kLoops, &hz), MC_CLOCK_OK_168MHZ);
  EXPECT_EQ(hz, 168000000u);

  // PLL: M = 8, N = 336, P = /2 (field 0), source HSE, Q = 7, reserved bits
  // of the reset value kept.
  const uint32_t p = r.pllcfgr;
  EXPECT_EQ(p, 0x27405408u);
  const uint32_t M = p & 0x3Fu, N = (p >> 6) & 0x1FFu, P = 2u * (((p >> 16) & 3u) + 1u),
                 Q = (p >> 24) & 0xFu;
  EXPECT_NE(p & (1u << 22), 0u) << "PLL source must be the HSE";
  EXPECT_EQ(8000000u / M * N / P, 168000000u) << "SYSCLK from the register fields";
  EXPECT_EQ(8000000u / M * N / Q, 48000000u) << "USB/SDIO clock from the register fields";
  EXPECT_GE(8000000u / M, 1000000u);  // VCO input 1..2 MHz (RM0090 6.3.2)
  EXPECT_LE(8000000u / M, 2000000u);
  EXPECT_GE(8000000u / M * N, 100000000u);  // VCO 100..432 MHz
  EXPECT_LE(8000000u / M * N, 432000000u);

  EXPECT_EQ(r.cr & ((1u << 16) | (1u << 24)), (1u << 16) | (1u << 24)) << "HSEON, PLLON";
  // CFGR: AHB /1, APB1 /4 (PPRE1 = 101), APB2 /2 (PPRE2 = 100), SW = PLL.
  EXPECT_EQ(r.cfgr & 0xFCF3u, (5u << 10) | (4u << 13) | 2u);
  // Flash: 5 wait states, prefetch, instruction and data caches.
  EXPECT_EQ(r.acr, 5u | (1u << 8) | (1u << 9) | (1u << 10));
  EXPECT_EQ(r.pwr, 1u << 14) << "regulator scale 1";
  EXPECT_EQ(r.apb1enr, 1u << 28) << "PWR clock";
}

TEST(TargetClock, HseThatNeverStartsLeavesHsiAndHseOff) {
  Regs r;
  r.cr = kHsiOnRdy;
  r.pllcfgr = kPllcfgrReset;
  mc_clock_regs_t m = r.map();
  uint32_t hz = 0u;
  EXPECT_EQ(mc_clock_init_168mhz(&m, kLoops, &hz), MC_CLOCK_ERR_HSE);
  EXPECT_EQ(hz, 16000000u);
  EXPECT_EQ(r.cr & (1u << 16), 0u) << "HSEON cleared again";
  EXPECT_EQ(r.pllcfgr, kPllcfgrReset) << "PLL untouched";
  EXPECT_EQ(r.cfgr & 3u, 0u) << "SYSCLK stays on the HSI";
  EXPECT_EQ(r.acr, 0u);
}

TEST(TargetClock, PllThatNeverLocksIsSwitchedOff) {
  Regs r;
  r.cr = kHsiOnRdy | kHseRdy;
  r.pllcfgr = kPllcfgrReset;
  mc_clock_regs_t m = r.map();
  uint32_t hz = 0u;
  EXPECT_EQ(mc_clock_init_168mhz(&m, kLoops, &hz), MC_CLOCK_ERR_PLL);
  EXPECT_EQ(hz, 16000000u);
  EXPECT_EQ(r.cr & ((1u << 16) | (1u << 24)), 0u) << "PLLON and HSEON cleared";
  EXPECT_EQ(r.cfgr & 3u, 0u);
}

TEST(TargetClock, SwitchNotConfirmedFallsBackToHsi) {
  Regs r;
  r.cr = kHsiOnRdy | kHseRdy | kPllRdy;
  r.pllcfgr = kPllcfgrReset;  // SWS never reports the PLL
  mc_clock_regs_t m = r.map();
  uint32_t hz = 0u;
  EXPECT_EQ(mc_clock_init_168mhz(&m, kLoops, &hz), MC_CLOCK_ERR_SWITCH);
  EXPECT_EQ(hz, 16000000u);
  EXPECT_EQ(r.cfgr & 3u, 0u) << "SW back to the HSI";
}

TEST(TargetClock, MissingRegisterIsRefused) {
  Regs r;
  mc_clock_regs_t m = r.map();
  m.flash_acr = nullptr;
  uint32_t hz = 7u;
  EXPECT_EQ(mc_clock_init_168mhz(&m, kLoops, &hz), MC_CLOCK_ERR_NULL);
  EXPECT_EQ(mc_clock_init_168mhz(nullptr, kLoops, &hz), MC_CLOCK_ERR_NULL);
  EXPECT_EQ(hz, 7u);
}

}  // namespace
