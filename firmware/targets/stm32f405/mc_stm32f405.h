/**
 * @file mc_stm32f405.h
 * @brief STM32F405 facts the port needs: interrupt numbers (RM0090 table 61)
 *        and the addresses of the RCC, FLASH and PWR registers the clock
 *        set-up writes (RM0090 sections 3.9, 5.4, 7.3). The peripheral
 *        drivers (TIM1, ADC, encoder timer, bxCAN) live in hal/stm32f405.
 */
#ifndef MC_STM32F405_H
#define MC_STM32F405_H

#include <stdint.h>

/** Interrupts of the STM32F405 vector table: IRQ 0 (WWDG) .. 81 (FPU). */
#define MC_STM32F405_IRQ_COUNT 82u

#define MC_IRQ_ADC           18u /**< ADC1/2/3 global: end of injected conversion */
#define MC_IRQ_CAN1_RX0      20u
#define MC_IRQ_TIM1_BRK_TIM9 24u
#define MC_IRQ_TIM1_UP_TIM10 25u
#define MC_IRQ_TIM2          28u
#define MC_IRQ_USART1        37u
#define MC_IRQ_FPU           81u

/* Exception numbers as IPSR reports them. */
#define MC_EXC_PENDSV 14u
#define MC_EXC_IRQ(n) (16u + (n))

/* Base addresses (RM0090 table 1). */
#define MC_RCC_BASE    0x40023800u
#define MC_FLASH_BASE  0x40023C00u /**< flash interface registers */
#define MC_PWR_BASE    0x40007000u
#define MC_TIM2_BASE   0x40000000u
#define MC_USART1_BASE 0x40011000u

/* RCC register offsets. */
#define MC_RCC_CR_OFS      0x00u
#define MC_RCC_PLLCFGR_OFS 0x04u
#define MC_RCC_CFGR_OFS    0x08u
#define MC_RCC_AHB1ENR_OFS 0x30u
#define MC_RCC_APB1ENR_OFS 0x40u
#define MC_RCC_APB2ENR_OFS 0x44u

/* RCC_CR */
#define MC_RCC_CR_HSION  (1u << 0)
#define MC_RCC_CR_HSIRDY (1u << 1)
#define MC_RCC_CR_HSEON  (1u << 16)
#define MC_RCC_CR_HSERDY (1u << 17)
#define MC_RCC_CR_HSEBYP (1u << 18)
#define MC_RCC_CR_PLLON  (1u << 24)
#define MC_RCC_CR_PLLRDY (1u << 25)

/* RCC_PLLCFGR: f_vco = f_in * N / M, f_sys = f_vco / P, f_usb = f_vco / Q. */
#define MC_RCC_PLLCFGR_M_POS         0u  /**< 6 bits, 2..63 */
#define MC_RCC_PLLCFGR_N_POS         6u  /**< 9 bits, 50..432 */
#define MC_RCC_PLLCFGR_P_POS         16u /**< 2 bits: 0 -> /2, 1 -> /4, 2 -> /6, 3 -> /8 */
#define MC_RCC_PLLCFGR_SRC_HSE       (1u << 22)
#define MC_RCC_PLLCFGR_Q_POS         24u         /**< 4 bits, 2..15 */
#define MC_RCC_PLLCFGR_RESERVED_MASK 0xF0BC8000u /**< bits to keep at their reset value */

/* RCC_CFGR */
#define MC_RCC_CFGR_SW_MASK    (3u << 0)
#define MC_RCC_CFGR_SW_PLL     (2u << 0)
#define MC_RCC_CFGR_SWS_MASK   (3u << 2)
#define MC_RCC_CFGR_SWS_PLL    (2u << 2)
#define MC_RCC_CFGR_HPRE_MASK  (0xFu << 4) /**< 0: AHB = SYSCLK */
#define MC_RCC_CFGR_PPRE1_MASK (7u << 10)
#define MC_RCC_CFGR_PPRE1_DIV4 (5u << 10) /**< APB1 = AHB / 4 (<= 42 MHz) */
#define MC_RCC_CFGR_PPRE2_MASK (7u << 13)
#define MC_RCC_CFGR_PPRE2_DIV2 (4u << 13) /**< APB2 = AHB / 2 (<= 84 MHz) */

#define MC_RCC_APB1ENR_PWREN (1u << 28)

/* FLASH_ACR (offset 0) */
#define MC_FLASH_ACR_LATENCY_MASK (7u << 0)
#define MC_FLASH_ACR_LATENCY_5WS  (5u << 0) /**< 150 < HCLK <= 168 MHz at 2.7..3.6 V */
#define MC_FLASH_ACR_PRFTEN       (1u << 8)
#define MC_FLASH_ACR_ICEN         (1u << 9)
#define MC_FLASH_ACR_DCEN         (1u << 10)

/* PWR_CR (offset 0) */
#define MC_PWR_CR_VOS (1u << 14) /**< regulator scale 1: needed above 144 MHz */

#endif /* MC_STM32F405_H */
