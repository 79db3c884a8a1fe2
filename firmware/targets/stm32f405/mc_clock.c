/**
 * @file mc_clock.c
 * @brief STM32F405 clock tree to 168 MHz: see mc_clock.h.
 */
#include "mc_clock.h"

#include <stdbool.h>
#include <stddef.h>

#include "mc_cortexm.h"
#include "mc_stm32f405.h"

mc_clock_regs_t mc_clock_regs_stm32f405(void)
{
    const mc_clock_regs_t r = {
        .rcc_cr = mc_reg32(MC_RCC_BASE + MC_RCC_CR_OFS),
        .rcc_pllcfgr = mc_reg32(MC_RCC_BASE + MC_RCC_PLLCFGR_OFS),
        .rcc_cfgr = mc_reg32(MC_RCC_BASE + MC_RCC_CFGR_OFS),
        .rcc_apb1enr = mc_reg32(MC_RCC_BASE + MC_RCC_APB1ENR_OFS),
        .flash_acr = mc_reg32(MC_FLASH_BASE),
        .pwr_cr = mc_reg32(MC_PWR_BASE),
    };
    return r;
}

/* PLLP field for a division by 2, 4, 6 or 8: 0, 1, 2, 3. */
static uint32_t pllp_field(uint32_t div)
{
    return ((div / 2u) - 1u) & 3u;
}

uint32_t mc_clock_pllcfgr_168mhz(uint32_t pllcfgr_reset)
{
    uint32_t v = pllcfgr_reset & MC_RCC_PLLCFGR_RESERVED_MASK;
    v |= MC_CLOCK_PLL_M << MC_RCC_PLLCFGR_M_POS;
    v |= MC_CLOCK_PLL_N << MC_RCC_PLLCFGR_N_POS;
    v |= pllp_field(MC_CLOCK_PLL_P_DIV) << MC_RCC_PLLCFGR_P_POS;
    v |= MC_RCC_PLLCFGR_SRC_HSE;
    v |= MC_CLOCK_PLL_Q << MC_RCC_PLLCFGR_Q_POS;
    return v;
}

/* Poll until (*reg & mask) == want, at most `loops` times. */
static bool wait_bits(const volatile uint32_t *reg, uint32_t mask, uint32_t want, uint32_t loops)
{
    for (uint32_t i = 0u; i < loops; ++i) {
        if ((*reg & mask) == want) {
            return true;
        }
    }
    return (*reg & mask) == want;
}

static bool regs_complete(const mc_clock_regs_t *r)
{
    return r->rcc_cr != NULL && r->rcc_pllcfgr != NULL && r->rcc_cfgr != NULL &&
           r->rcc_apb1enr != NULL && r->flash_acr != NULL && r->pwr_cr != NULL;
}

mc_clock_status_t mc_clock_init_168mhz(const mc_clock_regs_t *regs, uint32_t timeout_loops,
                                       uint32_t *p_sysclk_hz)
{
    uint32_t sysclk_hz = MC_CLOCK_HSI_HZ;
    mc_clock_status_t st = MC_CLOCK_OK_168MHZ;

    if (regs == NULL || !regs_complete(regs)) {
        return MC_CLOCK_ERR_NULL;
    }
    if ((*regs->rcc_cr & MC_RCC_CR_HSIRDY) == 0u) {
        /* Silicon always runs from a ready HSI out of reset: no RCC here. */
        if (p_sysclk_hz != NULL) {
            *p_sysclk_hz = 0u;
        }
        return MC_CLOCK_NO_RCC;
    }

    /* Regulator scale 1 (its register needs the PWR clock). */
    *regs->rcc_apb1enr |= MC_RCC_APB1ENR_PWREN;
    *regs->pwr_cr |= MC_PWR_CR_VOS;

    *regs->rcc_cr |= MC_RCC_CR_HSEON;
    if (!wait_bits(regs->rcc_cr, MC_RCC_CR_HSERDY, MC_RCC_CR_HSERDY, timeout_loops)) {
        *regs->rcc_cr &= ~MC_RCC_CR_HSEON;
        st = MC_CLOCK_ERR_HSE;
    }

    if (st == MC_CLOCK_OK_168MHZ) {
        /* The PLL can only be configured while it is off. */
        *regs->rcc_cr &= ~MC_RCC_CR_PLLON;
        (void)wait_bits(regs->rcc_cr, MC_RCC_CR_PLLRDY, 0u, timeout_loops);
        *regs->rcc_pllcfgr = mc_clock_pllcfgr_168mhz(*regs->rcc_pllcfgr);
        *regs->rcc_cr |= MC_RCC_CR_PLLON;
        if (!wait_bits(regs->rcc_cr, MC_RCC_CR_PLLRDY, MC_RCC_CR_PLLRDY, timeout_loops)) {
            *regs->rcc_cr &= ~(MC_RCC_CR_PLLON | MC_RCC_CR_HSEON);
            st = MC_CLOCK_ERR_PLL;
        }
    }

    if (st == MC_CLOCK_OK_168MHZ) {
        /* Wait states before the faster clock; bus dividers before the
         * switch so APB1/APB2 never exceed 42/84 MHz. */
        *regs->flash_acr = (*regs->flash_acr & ~MC_FLASH_ACR_LATENCY_MASK) |
                           MC_FLASH_ACR_LATENCY_5WS | MC_FLASH_ACR_PRFTEN | MC_FLASH_ACR_ICEN |
                           MC_FLASH_ACR_DCEN;
        *regs->rcc_cfgr = (*regs->rcc_cfgr & ~(MC_RCC_CFGR_HPRE_MASK | MC_RCC_CFGR_PPRE1_MASK |
                                               MC_RCC_CFGR_PPRE2_MASK)) |
                          MC_RCC_CFGR_PPRE1_DIV4 | MC_RCC_CFGR_PPRE2_DIV2;
        *regs->rcc_cfgr = (*regs->rcc_cfgr & ~MC_RCC_CFGR_SW_MASK) | MC_RCC_CFGR_SW_PLL;
        if (wait_bits(regs->rcc_cfgr, MC_RCC_CFGR_SWS_MASK, MC_RCC_CFGR_SWS_PLL, timeout_loops)) {
            sysclk_hz = MC_CLOCK_SYSCLK_HZ;
        } else {
            /* Back to the HSI (SW = 0); the wait states stay (safe, slower). */
            *regs->rcc_cfgr &= ~MC_RCC_CFGR_SW_MASK;
            st = MC_CLOCK_ERR_SWITCH;
        }
    }

    if (p_sysclk_hz != NULL) {
        *p_sysclk_hz = sysclk_hz;
    }
    return st;
}
