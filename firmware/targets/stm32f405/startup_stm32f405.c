/**
 * @file startup_stm32f405.c
 * @brief Reset handler and vector table of the STM32F405 (Cortex-M4F).
 *
 * Reset: point VTOR at this image's vector table (an application linked
 * into the slot behind the bootloader, firmware/boot/mc_boot_layout.h, takes
 * its interrupts from its own table; the bootloader at 0x08000000 sets the
 * reset value), enable the FPU (CP10/CP11 full access, before any
 * floating-point instruction; lazy FP context stacking is the reset default
 * and is set explicitly), copy .data from flash, zero .bss and .ccmbss, then
 * main().
 * The clock tree is set by main (mc_clock.h), not here, so that its result
 * can be reported.
 *
 * Vector table: the 16 Cortex-M4 system exceptions and the 82 STM32F405
 * interrupts, IRQ 0 (WWDG) up to IRQ 81 (FPU), named as in RM0090 table 61.
 * Positions 61, 62 (Ethernet) and 78..80 (DCMI, CRYP, HASH/RNG) exist only on
 * the F407/F415/F417; they stay in the table so the layout is the family's.
 * Every handler is a weak alias of mc_default_handler: an application or
 * board file defines the ones it uses (the drive's main defines
 * ADC_IRQHandler and PendSV_Handler).
 */
#include <stddef.h>
#include <stdint.h>

#include "mc_cortexm.h"
#include "mc_stm32f405.h"

/* Linker-script symbols (stm32f405.ld). */
extern uint32_t _estack;
extern uint32_t _sidata[], _sdata[], _edata[], _sbss[], _ebss[], _sccmbss[], _eccmbss[];

int main(void);
void Reset_Handler(void);
void mc_default_handler(void);

/** An exception nobody handles: stop here (a debugger shows IPSR). */
void mc_default_handler(void)
{
    for (;;) {
        mc_wfi();
    }
}

#define MC_WEAK_ALIAS __attribute__((weak, alias("mc_default_handler")))

void NMI_Handler(void) MC_WEAK_ALIAS;
void HardFault_Handler(void) MC_WEAK_ALIAS;
void MemManage_Handler(void) MC_WEAK_ALIAS;
void BusFault_Handler(void) MC_WEAK_ALIAS;
void UsageFault_Handler(void) MC_WEAK_ALIAS;
void SVC_Handler(void) MC_WEAK_ALIAS;
void DebugMon_Handler(void) MC_WEAK_ALIAS;
void PendSV_Handler(void) MC_WEAK_ALIAS;
void SysTick_Handler(void) MC_WEAK_ALIAS;

void WWDG_IRQHandler(void) MC_WEAK_ALIAS;
void PVD_IRQHandler(void) MC_WEAK_ALIAS;
void TAMP_STAMP_IRQHandler(void) MC_WEAK_ALIAS;
void RTC_WKUP_IRQHandler(void) MC_WEAK_ALIAS;
void FLASH_IRQHandler(void) MC_WEAK_ALIAS;
void RCC_IRQHandler(void) MC_WEAK_ALIAS;
void EXTI0_IRQHandler(void) MC_WEAK_ALIAS;
void EXTI1_IRQHandler(void) MC_WEAK_ALIAS;
void EXTI2_IRQHandler(void) MC_WEAK_ALIAS;
void EXTI3_IRQHandler(void) MC_WEAK_ALIAS;
void EXTI4_IRQHandler(void) MC_WEAK_ALIAS;
void DMA1_Stream0_IRQHandler(void) MC_WEAK_ALIAS;
void DMA1_Stream1_IRQHandler(void) MC_WEAK_ALIAS;
void DMA1_Stream2_IRQHandler(void) MC_WEAK_ALIAS;
void DMA1_Stream3_IRQHandler(void) MC_WEAK_ALIAS;
void DMA1_Stream4_IRQHandler(void) MC_WEAK_ALIAS;
void DMA1_Stream5_IRQHandler(void) MC_WEAK_ALIAS;
void DMA1_Stream6_IRQHandler(void) MC_WEAK_ALIAS;
void ADC_IRQHandler(void) MC_WEAK_ALIAS;
void CAN1_TX_IRQHandler(void) MC_WEAK_ALIAS;
void CAN1_RX0_IRQHandler(void) MC_WEAK_ALIAS;
void CAN1_RX1_IRQHandler(void) MC_WEAK_ALIAS;
void CAN1_SCE_IRQHandler(void) MC_WEAK_ALIAS;
void EXTI9_5_IRQHandler(void) MC_WEAK_ALIAS;
void TIM1_BRK_TIM9_IRQHandler(void) MC_WEAK_ALIAS;
void TIM1_UP_TIM10_IRQHandler(void) MC_WEAK_ALIAS;
void TIM1_TRG_COM_TIM11_IRQHandler(void) MC_WEAK_ALIAS;
void TIM1_CC_IRQHandler(void) MC_WEAK_ALIAS;
void TIM2_IRQHandler(void) MC_WEAK_ALIAS;
void TIM3_IRQHandler(void) MC_WEAK_ALIAS;
void TIM4_IRQHandler(void) MC_WEAK_ALIAS;
void I2C1_EV_IRQHandler(void) MC_WEAK_ALIAS;
void I2C1_ER_IRQHandler(void) MC_WEAK_ALIAS;
void I2C2_EV_IRQHandler(void) MC_WEAK_ALIAS;
void I2C2_ER_IRQHandler(void) MC_WEAK_ALIAS;
void SPI1_IRQHandler(void) MC_WEAK_ALIAS;
void SPI2_IRQHandler(void) MC_WEAK_ALIAS;
void USART1_IRQHandler(void) MC_WEAK_ALIAS;
void USART2_IRQHandler(void) MC_WEAK_ALIAS;
void USART3_IRQHandler(void) MC_WEAK_ALIAS;
void EXTI15_10_IRQHandler(void) MC_WEAK_ALIAS;
void RTC_Alarm_IRQHandler(void) MC_WEAK_ALIAS;
void OTG_FS_WKUP_IRQHandler(void) MC_WEAK_ALIAS;
void TIM8_BRK_TIM12_IRQHandler(void) MC_WEAK_ALIAS;
void TIM8_UP_TIM13_IRQHandler(void) MC_WEAK_ALIAS;
void TIM8_TRG_COM_TIM14_IRQHandler(void) MC_WEAK_ALIAS;
void TIM8_CC_IRQHandler(void) MC_WEAK_ALIAS;
void DMA1_Stream7_IRQHandler(void) MC_WEAK_ALIAS;
void FSMC_IRQHandler(void) MC_WEAK_ALIAS;
void SDIO_IRQHandler(void) MC_WEAK_ALIAS;
void TIM5_IRQHandler(void) MC_WEAK_ALIAS;
void SPI3_IRQHandler(void) MC_WEAK_ALIAS;
void UART4_IRQHandler(void) MC_WEAK_ALIAS;
void UART5_IRQHandler(void) MC_WEAK_ALIAS;
void TIM6_DAC_IRQHandler(void) MC_WEAK_ALIAS;
void TIM7_IRQHandler(void) MC_WEAK_ALIAS;
void DMA2_Stream0_IRQHandler(void) MC_WEAK_ALIAS;
void DMA2_Stream1_IRQHandler(void) MC_WEAK_ALIAS;
void DMA2_Stream2_IRQHandler(void) MC_WEAK_ALIAS;
void DMA2_Stream3_IRQHandler(void) MC_WEAK_ALIAS;
void DMA2_Stream4_IRQHandler(void) MC_WEAK_ALIAS;
void ETH_IRQHandler(void) MC_WEAK_ALIAS;
void ETH_WKUP_IRQHandler(void) MC_WEAK_ALIAS;
void CAN2_TX_IRQHandler(void) MC_WEAK_ALIAS;
void CAN2_RX0_IRQHandler(void) MC_WEAK_ALIAS;
void CAN2_RX1_IRQHandler(void) MC_WEAK_ALIAS;
void CAN2_SCE_IRQHandler(void) MC_WEAK_ALIAS;
void OTG_FS_IRQHandler(void) MC_WEAK_ALIAS;
void DMA2_Stream5_IRQHandler(void) MC_WEAK_ALIAS;
void DMA2_Stream6_IRQHandler(void) MC_WEAK_ALIAS;
void DMA2_Stream7_IRQHandler(void) MC_WEAK_ALIAS;
void USART6_IRQHandler(void) MC_WEAK_ALIAS;
void I2C3_EV_IRQHandler(void) MC_WEAK_ALIAS;
void I2C3_ER_IRQHandler(void) MC_WEAK_ALIAS;
void OTG_HS_EP1_OUT_IRQHandler(void) MC_WEAK_ALIAS;
void OTG_HS_EP1_IN_IRQHandler(void) MC_WEAK_ALIAS;
void OTG_HS_WKUP_IRQHandler(void) MC_WEAK_ALIAS;
void OTG_HS_IRQHandler(void) MC_WEAK_ALIAS;
void DCMI_IRQHandler(void) MC_WEAK_ALIAS;
void CRYP_IRQHandler(void) MC_WEAK_ALIAS;
void HASH_RNG_IRQHandler(void) MC_WEAK_ALIAS;
void FPU_IRQHandler(void) MC_WEAK_ALIAS;

static size_t words_between(const uint32_t *start, const uint32_t *end)
{
    return (size_t)(((uintptr_t)end - (uintptr_t)start) / sizeof(uint32_t));
}

static void vtor_set(void);

void Reset_Handler(void)
{
    vtor_set();
    /* FPU first: the C code below may already use FP registers. */
    MC_SCB_CPACR |= MC_SCB_CPACR_FPU_FULL;
    mc_dsb();
    mc_isb();
    MC_FPU_FPCCR |= MC_FPU_FPCCR_ASPEN | MC_FPU_FPCCR_LSPEN;

    /* Section sizes from the linker symbols' addresses (word aligned). */
    const size_t n_data = words_between(_sdata, _edata);
    for (size_t i = 0u; i < n_data; ++i) {
        _sdata[i] = _sidata[i];
    }
    const size_t n_bss = words_between(_sbss, _ebss);
    for (size_t i = 0u; i < n_bss; ++i) {
        _sbss[i] = 0u;
    }
    /* Empty unless something is placed in CCM (.ccmbss): the emulated
     * images never do, since QEMU does not map the CCM. */
    const size_t n_ccm = words_between(_sccmbss, _eccmbss);
    for (size_t i = 0u; i < n_ccm; ++i) {
        _sccmbss[i] = 0u;
    }
    (void)main();
    mc_default_handler();
}

typedef void (*mc_vector_t)(void);

/* Entry 0 is the initial stack pointer, not a function; the table is an
 * array of words as far as the core is concerned. */
__attribute__((section(".isr_vector"),
               used)) static const mc_vector_t mc_vectors[16 + MC_STM32F405_IRQ_COUNT] = {
    (mc_vector_t)(uintptr_t)&_estack, /* NOLINT(performance-no-int-to-ptr): initial SP */
    Reset_Handler, NMI_Handler, HardFault_Handler, MemManage_Handler, BusFault_Handler,
    UsageFault_Handler, 0, 0, 0, 0, SVC_Handler, DebugMon_Handler, 0, PendSV_Handler,
    SysTick_Handler,
    /* IRQ 0 .. 81 */
    WWDG_IRQHandler, PVD_IRQHandler, TAMP_STAMP_IRQHandler, RTC_WKUP_IRQHandler, FLASH_IRQHandler,
    RCC_IRQHandler, EXTI0_IRQHandler, EXTI1_IRQHandler, EXTI2_IRQHandler, EXTI3_IRQHandler,
    EXTI4_IRQHandler, DMA1_Stream0_IRQHandler, DMA1_Stream1_IRQHandler, DMA1_Stream2_IRQHandler,
    DMA1_Stream3_IRQHandler, DMA1_Stream4_IRQHandler, DMA1_Stream5_IRQHandler,
    DMA1_Stream6_IRQHandler, ADC_IRQHandler, /* 18 */
    CAN1_TX_IRQHandler, CAN1_RX0_IRQHandler, CAN1_RX1_IRQHandler, CAN1_SCE_IRQHandler,
    EXTI9_5_IRQHandler, TIM1_BRK_TIM9_IRQHandler, /* 24 */
    TIM1_UP_TIM10_IRQHandler, TIM1_TRG_COM_TIM11_IRQHandler, TIM1_CC_IRQHandler,
    TIM2_IRQHandler, /* 28 */
    TIM3_IRQHandler, TIM4_IRQHandler, I2C1_EV_IRQHandler, I2C1_ER_IRQHandler, I2C2_EV_IRQHandler,
    I2C2_ER_IRQHandler, SPI1_IRQHandler, SPI2_IRQHandler, USART1_IRQHandler, /* 37 */
    USART2_IRQHandler, USART3_IRQHandler, EXTI15_10_IRQHandler,              /* 40 */
    RTC_Alarm_IRQHandler, OTG_FS_WKUP_IRQHandler, TIM8_BRK_TIM12_IRQHandler,
    TIM8_UP_TIM13_IRQHandler, TIM8_TRG_COM_TIM14_IRQHandler, TIM8_CC_IRQHandler,
    DMA1_Stream7_IRQHandler, FSMC_IRQHandler, SDIO_IRQHandler, TIM5_IRQHandler, /* 50 */
    SPI3_IRQHandler, UART4_IRQHandler, UART5_IRQHandler, TIM6_DAC_IRQHandler, TIM7_IRQHandler,
    DMA2_Stream0_IRQHandler, DMA2_Stream1_IRQHandler, DMA2_Stream2_IRQHandler,
    DMA2_Stream3_IRQHandler, DMA2_Stream4_IRQHandler, /* 60 */
    ETH_IRQHandler, ETH_WKUP_IRQHandler, CAN2_TX_IRQHandler, CAN2_RX0_IRQHandler,
    CAN2_RX1_IRQHandler, CAN2_SCE_IRQHandler, OTG_FS_IRQHandler, DMA2_Stream5_IRQHandler,
    DMA2_Stream6_IRQHandler, DMA2_Stream7_IRQHandler, /* 70 */
    USART6_IRQHandler, I2C3_EV_IRQHandler, I2C3_ER_IRQHandler, OTG_HS_EP1_OUT_IRQHandler,
    OTG_HS_EP1_IN_IRQHandler, OTG_HS_WKUP_IRQHandler, OTG_HS_IRQHandler, DCMI_IRQHandler,
    CRYP_IRQHandler, HASH_RNG_IRQHandler, /* 80 */
    FPU_IRQHandler,                       /* 81 */
};

static void vtor_set(void)
{
    /* NOLINTNEXTLINE(performance-no-int-to-ptr): the table's address as the register wants it */
    MC_SCB_VTOR = (uint32_t)(uintptr_t)mc_vectors;
    mc_dsb();
}
