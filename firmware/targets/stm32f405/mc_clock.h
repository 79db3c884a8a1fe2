/**
 * @file mc_clock.h
 * @brief STM32F405 clock tree: SYSCLK = HCLK = 168 MHz from an 8 MHz HSE
 *        crystal through the main PLL (RM0090 section 6).
 *
 *   HSE 8 MHz / M 8 = 1 MHz -> x N 336 = VCO 336 MHz -> / P 2 = 168 MHz SYSCLK
 *                                                     -> / Q 7 = 48 MHz (USB)
 *   AHB /1 = 168 MHz, APB1 /4 = 42 MHz (timers x2 = 84 MHz),
 *   APB2 /2 = 84 MHz (TIM1 clock x2 = 168 MHz)
 *   Flash: 5 wait states, prefetch and both caches on (RM0090 table 10).
 *   Regulator: voltage scale 1 (PWR_CR.VOS), required above 144 MHz.
 *
 * Emulation: QEMU's netduinoplus2 has no RCC model; its registers read 0.
 * On silicon RCC_CR always reads HSION = HSIRDY = 1 after reset (the chip
 * runs from the HSI). mc_clock_init_168mhz() therefore detects the emulator
 * at run time (HSIRDY reads 0), returns MC_CLOCK_NO_RCC and writes nothing;
 * no build switch is needed, and the same image runs in both places.
 *
 * Every wait on a ready flag is bounded (timeout_loops polls): a crystal
 * that does not start leaves the chip on the 16 MHz HSI with the HSE off and
 * an error code, never a hang.
 *
 * The registers are reached through mc_clock_regs_t, so the host tests run
 * the same code against a register file in RAM.
 */
#ifndef MC_CLOCK_H
#define MC_CLOCK_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define MC_CLOCK_HSE_HZ    8000000u
#define MC_CLOCK_HSI_HZ    16000000u
#define MC_CLOCK_SYSCLK_HZ 168000000u
#define MC_CLOCK_APB1_HZ   42000000u
#define MC_CLOCK_APB2_HZ   84000000u

#define MC_CLOCK_PLL_M     8u
#define MC_CLOCK_PLL_N     336u
#define MC_CLOCK_PLL_P_DIV 2u
#define MC_CLOCK_PLL_Q     7u

/** Polls per ready flag by default: >= 20 ms at 16 MHz (HSE start-up is
 *  specified at 2 ms typical). */
#define MC_CLOCK_TIMEOUT_LOOPS 100000u

typedef enum {
    MC_CLOCK_OK_168MHZ = 0,  /**< SYSCLK = 168 MHz from the PLL on HSE */
    MC_CLOCK_NO_RCC = 1,     /**< no RCC (emulator): nothing written */
    MC_CLOCK_ERR_HSE = 2,    /**< HSE did not become ready: HSE off, HSI 16 MHz */
    MC_CLOCK_ERR_PLL = 3,    /**< PLL did not lock: PLL and HSE off, HSI 16 MHz */
    MC_CLOCK_ERR_SWITCH = 4, /**< SYSCLK did not switch to the PLL: HSI 16 MHz */
    MC_CLOCK_ERR_NULL = 5,   /**< a register pointer is NULL */
} mc_clock_status_t;

/** The registers the clock set-up touches. */
typedef struct {
    volatile uint32_t *rcc_cr;
    volatile uint32_t *rcc_pllcfgr;
    volatile uint32_t *rcc_cfgr;
    volatile uint32_t *rcc_apb1enr;
    volatile uint32_t *flash_acr;
    volatile uint32_t *pwr_cr;
} mc_clock_regs_t;

/** The STM32F405's own registers. */
mc_clock_regs_t mc_clock_regs_stm32f405(void);

/** RCC_PLLCFGR value for the 168 MHz tree, given its reset value. */
uint32_t mc_clock_pllcfgr_168mhz(uint32_t pllcfgr_reset);

/**
 * Set the clock tree to 168 MHz (see file comment). Order: regulator scale
 * 1, HSE on and ready, PLL configured and locked, flash wait states and bus
 * dividers, then SYSCLK switched to the PLL and confirmed. Returns the status;
 * *p_sysclk_hz (if not NULL) receives the resulting core clock (0 if unknown,
 * i.e. MC_CLOCK_NO_RCC).
 */
mc_clock_status_t mc_clock_init_168mhz(const mc_clock_regs_t *regs, uint32_t timeout_loops,
                                       uint32_t *p_sysclk_hz);

#ifdef __cplusplus
}
#endif

#endif /* MC_CLOCK_H */
