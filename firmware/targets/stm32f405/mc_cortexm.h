/**
 * @file mc_cortexm.h
 * @brief Cortex-M4F core registers (SCB, NVIC) and the few instructions the
 *        STM32F405 port needs (WFI, barriers, IPSR), from the ARMv7-M
 *        Architecture Reference Manual.
 *
 * The instructions are wrapped in static inline functions so the port's C
 * files also compile on the host (the lint and warning checks of the host
 * build see them): there the wrappers are empty and IPSR reads 0. Nothing
 * compiled for the host ever runs these files.
 */
#ifndef MC_CORTEXM_H
#define MC_CORTEXM_H

#include <stdint.h>

/** The register at a fixed peripheral address. */
static inline volatile uint32_t *mc_reg32(uintptr_t addr)
{
    /* NOLINTNEXTLINE(performance-no-int-to-ptr): memory-mapped register */
    return (volatile uint32_t *)addr;
}

static inline volatile uint8_t *mc_reg8(uintptr_t addr)
{
    return (volatile uint8_t *)addr; /* NOLINT(performance-no-int-to-ptr): memory-mapped register */
}

#define MC_REG32(addr) (*mc_reg32((uintptr_t)(addr)))

/* System control block. */
#define MC_SCB_ICSR  MC_REG32(0xE000ED04u) /**< interrupt control and state */
#define MC_SCB_VTOR  MC_REG32(0xE000ED08u) /**< vector table offset */
#define MC_SCB_AIRCR MC_REG32(0xE000ED0Cu) /**< priority grouping (write key 0x05FA) */
#define MC_SCB_SHPR3 MC_REG32(0xE000ED20u) /**< PendSV (bits 23:16), SysTick (31:24) */
#define MC_SCB_CPACR MC_REG32(0xE000ED88u) /**< coprocessor access (CP10, CP11: FPU) */
#define MC_FPU_FPCCR MC_REG32(0xE000EF34u) /**< FP context control (lazy stacking) */

#define MC_SCB_ICSR_PENDSVSET (1u << 28)
#define MC_SCB_CPACR_FPU_FULL (0xFu << 20) /**< CP10 and CP11 full access */
#define MC_FPU_FPCCR_ASPEN    (1u << 31)   /**< FP context saved on exception entry */
#define MC_FPU_FPCCR_LSPEN    (1u << 30)   /**< ... lazily (space reserved, saved on first use) */

/* NVIC: 32 interrupts per enable/pending word, 8-bit priority fields of
 * which the STM32F405 implements the top 4 bits (16 levels, 0 = highest). */
#define MC_NVIC_ISER(n)       MC_REG32(0xE000E100u + 4u * (uint32_t)(n))
#define MC_NVIC_ICER(n)       MC_REG32(0xE000E180u + 4u * (uint32_t)(n))
#define MC_NVIC_ISPR(n)       MC_REG32(0xE000E200u + 4u * (uint32_t)(n))
#define MC_NVIC_ICPR(n)       MC_REG32(0xE000E280u + 4u * (uint32_t)(n))
#define MC_NVIC_IPR_BYTE(irq) (*mc_reg8((uintptr_t)0xE000E400u + (uintptr_t)(irq)))
#define MC_NVIC_PRIO_BITS     4u

static inline void mc_nvic_set_priority(uint32_t irq, uint32_t prio)
{
    MC_NVIC_IPR_BYTE(irq) = (uint8_t)((prio << (8u - MC_NVIC_PRIO_BITS)) & 0xFFu);
}

static inline void mc_nvic_enable(uint32_t irq)
{
    MC_NVIC_ISER(irq >> 5) = 1u << (irq & 31u);
}

static inline void mc_nvic_disable(uint32_t irq)
{
    MC_NVIC_ICER(irq >> 5) = 1u << (irq & 31u);
}

/** Make an interrupt pending by software (as if its peripheral raised it). */
static inline void mc_nvic_set_pending(uint32_t irq)
{
    MC_NVIC_ISPR(irq >> 5) = 1u << (irq & 31u);
}

/** PendSV priority (lowest = 15 on the STM32F405). */
static inline void mc_scb_set_pendsv_priority(uint32_t prio)
{
    const uint32_t field = (prio << (8u - MC_NVIC_PRIO_BITS)) & 0xFFu;
    MC_SCB_SHPR3 = (MC_SCB_SHPR3 & ~(0xFFu << 16)) | (field << 16);
}

static inline void mc_scb_pend_pendsv(void)
{
    MC_SCB_ICSR = MC_SCB_ICSR_PENDSVSET;
}

#if defined(__arm__)
static inline void mc_dsb(void)
{
    __asm__ volatile("dsb" ::: "memory");
}
static inline void mc_isb(void)
{
    __asm__ volatile("isb" ::: "memory");
}
static inline void mc_wfi(void)
{
    __asm__ volatile("wfi" ::: "memory");
}
static inline void mc_irq_disable(void)
{
    __asm__ volatile("cpsid i" ::: "memory");
}
static inline void mc_irq_enable(void)
{
    __asm__ volatile("cpsie i" ::: "memory");
}
/** Exception number being handled (0 = thread mode, 14 = PendSV, 16 + n = IRQ n). */
static inline uint32_t mc_ipsr(void)
{
    uint32_t v;
    __asm__ volatile("mrs %0, ipsr" : "=r"(v));
    return v;
}
#else
static inline void mc_dsb(void)
{
}
static inline void mc_isb(void)
{
}
static inline void mc_wfi(void)
{
}
static inline void mc_irq_disable(void)
{
}
static inline void mc_irq_enable(void)
{
}
static inline uint32_t mc_ipsr(void)
{
    return 0u;
}
#endif

#endif /* MC_CORTEXM_H */
