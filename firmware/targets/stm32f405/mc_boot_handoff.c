/**
 * @file mc_boot_handoff.c
 * @brief Bootloader and application hand-offs: see mc_boot_handoff.h.
 */
#include "mc_boot_handoff.h"

#include "mc_boot_layout.h"
#include "mc_cortexm.h"

#define MAILBOX0 MC_REG32(MC_BOOT_MAILBOX_ADDR)
#define MAILBOX1 MC_REG32(MC_BOOT_MAILBOX_ADDR + 4u)
/* AIRCR: the write key and SYSRESETREQ (ARMv7-M B3.2.6). */
#define AIRCR_RESET (0x05FA0000u | (1u << 2))

void mc_boot_system_reset(void)
{
    mc_irq_disable();
    mc_dsb();
    MC_SCB_AIRCR = AIRCR_RESET;
    mc_dsb();
    for (;;) {
        mc_wfi(); /* the reset takes a few cycles */
    }
}

void mc_boot_mailbox_enter(void *ctx)
{
    (void)ctx;
    mc_irq_disable();
    MAILBOX0 = MC_BOOT_REQ_MAGIC0;
    MAILBOX1 = MC_BOOT_REQ_MAGIC1;
    mc_boot_system_reset();
}

bool mc_boot_mailbox_take(void)
{
    const bool asked = (MAILBOX0 == MC_BOOT_REQ_MAGIC0) && (MAILBOX1 == MC_BOOT_REQ_MAGIC1);
    MAILBOX0 = 0u;
    MAILBOX1 = 0u;
    return asked;
}

void mc_boot_start_image(uint32_t addr)
{
    const uint32_t sp = MC_REG32(addr);
    const uint32_t pc = MC_REG32(addr + 4u);
    MC_SCB_VTOR = addr;
    mc_dsb();
    mc_isb();
#if defined(__arm__)
    __asm__ volatile("msr msp, %0\n\tbx %1" : : "r"(sp), "r"(pc) : "memory");
#else
    (void)sp;
    (void)pc;
#endif
    for (;;) {
        mc_wfi(); /* not reached on the MCU */
    }
}
